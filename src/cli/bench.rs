//! `suitcap bench`: how fast the pipeline runs on this machine, stage by stage.
//!
//! Frames are decoded into memory first (file decoding is not part of the pipeline). Two
//! measurements:
//!
//! 1. *Sequential*: every stage on one frame after another on one thread, timed per frame; medians
//!    per stage, and frames/s of the pose alone (segment → descriptor → regression → root) and of the
//!    whole chain (+ cloth, render, composite). This is the latency of one frame.
//! 2. *Pipelined*: the threaded runner (capture, pose, cloth, render + composite on their own
//!    threads, bounded queues) over the same frames as recorded input, so none are dropped: frames/s
//!    of the whole pipeline, which overlaps the stages across the cores.
//!
//! Then the peak resident set of the process (`VmHWM`). Timing belongs here, never in tests.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use anyhow::bail;
use clap::Args;

use suitcap::body_size::Silhouette;
use suitcap::cloth::garment::{GarmentKind, GarmentMesh};
use suitcap::source::memory::MemorySource;
use suitcap::tryon::runner::{self, Controls, InputKind, PoseStage};
use suitcap::tryon::{ClothOptions, ClothStage, GarmentChoice, Overlays, SimulationMode};

#[derive(Args, Clone, Debug)]
pub struct BenchArgs {
    /// Frame size of the bundled footage: 640x480 or 1440x1080.
    #[arg(long, default_value = "640x480")]
    size: String,
    #[arg(long, default_value_os_t = suitcap::suit::default_suit_dir())]
    suit: PathBuf,
    /// Frames to process in each measurement (the footage is replayed cyclically).
    #[arg(long, default_value_t = 120)]
    frames: u64,
    /// Garment and the vertex count to cut it to.
    #[arg(long, default_value = "tshirt")]
    garment: String,
    #[arg(long, default_value_t = 4000)]
    vertices: usize,
    /// Other footage instead of the bundled: a directory of frames (needs --camera).
    #[arg(long, requires = "camera")]
    input: Option<PathBuf>,
    #[arg(long)]
    camera: Option<PathBuf>,
}

#[derive(Default)]
struct Samples {
    segment: Vec<f64>,
    describe: Vec<f64>,
    regress: Vec<f64>,
    cloth: Vec<f64>,
    render: Vec<f64>,
    composite: Vec<f64>,
    pose_total: Vec<f64>,
    total: Vec<f64>,
}

use super::median;

fn peak_rss_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

pub fn bench(args: &BenchArgs) -> anyhow::Result<()> {
    let (dir, camera_path) = match (&args.input, &args.camera) {
        (Some(dir), Some(camera)) => (dir.clone(), camera.clone()),
        _ => {
            let footage = args.suit.join("demo").join(&args.size);
            (footage.join("frames"), footage.join("camera.toml"))
        }
    };
    if !dir.is_dir() {
        bail!(
            "no footage at {} (bundled sizes: 640x480, 1440x1080; or pass --input and --camera)",
            dir.display()
        );
    }
    let camera = suitcap::camera::Camera::load(&camera_path)?;
    let (width, height) = (camera.intrinsics.width, camera.intrinsics.height);
    let frame_count = suitcap::source::directory::list_frame_files(&dir)?.len();
    let kind: GarmentKind = args.garment.parse()?;
    let pose_stage = || -> anyhow::Result<PoseStage> {
        Ok(PoseStage {
            pipeline: suitcap::pipeline::PosePipeline::load(&args.suit)?,
            filter: None,
            segmenter: Some(suitcap::pipeline::PosePipeline::load_segmenter(&args.suit)?),
            root_glitch_window_s: None,
        })
    };
    let mut pose = pose_stage()?;
    let template = pose.pipeline.regressor.skeleton.skeleton.clone();
    // The garment cut to the asked vertex count on the template body (the live mode's solver).
    let edge = {
        let size = suitcap::body_size::BodySize::TEMPLATE;
        let (subject, skeleton) = size.subject(&template);
        let body = suitcap::body::Body::new(&subject, &skeleton)?;
        let rig = suitcap::cloth::proxies::BodyRig::new(
            skeleton,
            body,
            suitcap::cloth::proxies::DEFAULT_MARGIN_CM,
        );
        GarmentMesh::with_vertex_count(kind, &rig, args.vertices, 2.5)?.1
    };
    let cloth_options = || {
        let mut o = ClothOptions::new(GarmentChoice::Procedural(kind), SimulationMode::Live);
        o.edge_cm = Some(edge);
        // As `live` runs it on the poses it estimates.
        o.inertia = suitcap::tryon::ESTIMATED_POSE_INERTIA;
        // The template's size, so the garment has the asked vertex count (timing, not fit).
        o.known_size = Some(suitcap::body_size::BodySize::TEMPLATE);
        o
    };
    let mut cloth = ClothStage::new(&template, cloth_options())?;
    let mut render = suitcap::tryon::RenderStage::new(Default::default(), Vec::new());
    println!(
        "{} frames of {}x{} from {} replayed for {} frames; garment {} cut to ~{} vertices ({edge:.2} cm edges); {} threads",
        frame_count,
        width,
        height,
        dir.display(),
        args.frames,
        kind.name(),
        args.vertices,
        rayon::current_num_threads()
    );

    // 1. Pipelined. First from the encoded files (decoded at delivery like a webcam's MJPEG), so
    //    the peak memory is the pipeline's and not a store of decoded frames; then from frames
    //    decoded beforehand (the pipeline's own speed), with and without the garment.
    let files = suitcap::source::directory::list_frame_files(&dir)?
        .into_iter()
        .map(|p| Ok((p.display().to_string(), std::fs::read(&p)?)))
        .collect::<std::io::Result<Vec<_>>>()?;
    let mut decoded = Vec::new();
    // (garment, frames decoded beforehand)
    for (garment, predecoded) in [(true, false), (true, true), (false, true)] {
        if predecoded && decoded.is_empty() {
            decoded = super::tryon::load_frames(&dir)?;
        }
        let source = if predecoded {
            MemorySource::new(decoded.clone(), 30.0, args.frames)
                .ok_or_else(|| anyhow::anyhow!("{}: frames differ in size", dir.display()))?
        } else {
            MemorySource::from_encoded(files.clone(), 30.0, args.frames)
                .map_err(anyhow::Error::msg)?
        };
        let controls = Controls::new(Overlays::default());
        let mut first_done: Option<Instant> = None;
        let mut count = 0u64;
        let cloth = if garment {
            Some(ClothStage::new(&template, cloth_options())?)
        } else {
            None
        };
        let summary = runner::run(
            move || Ok(Box::new(source) as Box<dyn suitcap::source::FrameSource>),
            InputKind::Recorded,
            camera,
            pose_stage()?,
            cloth,
            suitcap::tryon::RenderStage::new(Default::default(), Vec::new()),
            Arc::clone(&controls),
            Vec::new,
            |_| {
                count += 1;
                if count == 5 {
                    first_done = Some(Instant::now());
                }
                true
            },
        );
        if let Some(e) = summary.source_error {
            bail!("the benchmark's source failed: {e}");
        }
        let seconds = first_done.map_or(summary.seconds, |t| t.elapsed().as_secs_f64());
        let steady_frames = count.saturating_sub(5).max(1);
        println!(
            "pipelined (stages on threads), {}, {}: {:.1} frames/s over {} frames after the first 5",
            if garment { "whole pipeline" } else { "pose only" },
            if predecoded { "frames decoded beforehand" } else { "JPEG decoded in the capture stage" },
            steady_frames as f64 / seconds.max(1e-9),
            steady_frames
        );
        if !predecoded {
            match peak_rss_mb() {
                Some(mb) => println!("peak resident set of the pipeline: {mb:.0} MB"),
                None => println!("peak resident set: unknown (no /proc/self/status)"),
            }
        }
    }

    // 2. Sequential, on decoded frames.
    let frames = decoded;
    let mut s = Samples::default();
    let mut vertices = 0;
    let overlay = suitcap::tryon::PoseOverlay::default();
    for k in 0..args.frames {
        let frame = &frames[(k % frames.len() as u64) as usize];
        let started = Instant::now();
        let result = pose.pipeline.process(frame, &camera, None);
        let pose_ms = started.elapsed().as_secs_f64() * 1e3;
        let c = cloth.advance(
            &result.frame,
            k as f64 / 30.0,
            result.person,
            Silhouette::from(&result),
            &camera,
        )?;
        vertices = vertices.max(c.positions.len());
        let mut image = frame.clone();
        let (r, comp) = render.draw(
            &mut image,
            &camera,
            &c,
            result.person.then_some(&result.mask),
            &overlay,
            Overlays::default(),
            &[],
            &[],
        )?;
        s.segment.push(result.times.segment);
        s.describe.push(result.times.describe);
        s.regress.push(result.times.regress);
        s.cloth.push(c.milliseconds);
        s.render.push(r);
        s.composite.push(comp);
        s.pose_total.push(pose_ms);
        s.total.push(started.elapsed().as_secs_f64() * 1e3);
    }
    // Skip the frames before the garment was on (sizing and dressing are not steady state).
    let steady = |v: &[f64]| median(&v[v.len().min(5)..]);
    println!("sequential, median ms per frame (steady state):");
    for (name, v) in [
        ("segment", &s.segment),
        ("describe", &s.describe),
        ("regress + root", &s.regress),
        ("cloth", &s.cloth),
        ("render", &s.render),
        ("composite", &s.composite),
    ] {
        println!("  {name:<16} {:>8.2}", steady(v));
    }
    let pose_ms = steady(&s.pose_total);
    let total_ms = steady(&s.total);
    println!(
        "  pose only        {:>8.2}  → {:.1} frames/s\n  whole chain      {:>8.2}  → {:.1} frames/s  ({} garment vertices)",
        pose_ms,
        1e3 / pose_ms,
        total_ms,
        1e3 / total_ms,
        vertices
    );

    Ok(())
}
