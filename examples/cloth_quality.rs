//! Cloth quality on the bench's eight cases without the criterion timing:
//! `cargo run --release --example cloth_quality [filter] [-v]`.
//!
//! Prints `run_motion`'s summary for walk 02_01 and kick 10_03, T-shirt and dress at about 2,000
//! and 4,000 vertices (the same cases as `cargo bench --bench cloth`), and how far the T-shirt's
//! sleeve ends (its cuffs) got from the arm. The dressed first frame counts like the others. With
//! `-v`, also where the worst frame's top 5 % of edges lie: stretched or compressed, rest length,
//! nearest body part, height band; how many frames have a largest strain above 5 / 10 / 20 %;
//! and, in the frame with the largest strain, the edges above 10 % with the two capsules nearest
//! each end (signed distance, cm). The filter keeps the cases whose name (`kick/dress/4000`, …) contains it.
//!
//! Environment overrides of the live settings, for experiments: `CLOTH_SUBSTEPS`, `CLOTH_SWEEPS`,
//! `CLOTH_RHO` (Chebyshev ρ, 0 = plain sweeps), `CLOTH_LIMIT` (strain limit, 0 = off),
//! `CLOTH_COMPRESSION`, `CLOTH_TETHER_SLACK`, `CLOTH_CUFF_SLIDE` (cm a sleeve end may slide up the
//! arm before it is held), `CLOTH_CUFF_TAU` (its hold's time constant, s),
//! `CLOTH_TAU` (loose-anchor time constant, s), `CLOTH_BEND_SCALE` (× the bending compliance),
//! `CLOTH_COUNTS` (vertex counts, e.g. `2500,3300`), `CLOTH_MATERIAL` (a preset name, default
//! medium). `CLOTH_MODE=quality`: the quality mode of `suitcap run` / `drape` instead (its
//! substeps, and the garment at its 1 cm edges instead of the vertex counts). `CLOTH_CLIP`: another
//! BVH file instead of the two clips, from the end of its calibration lead-in (the first six
//! frames of a raw CMU capture at 120 frames/s, none of a 30 frames/s clip; `CLOTH_FIRST_FRAME`
//! to choose); `CLOTH_SUBJECT`: another built-in
//! subject than chidi, or `motion` for the clip's own skeleton at girth 1 (what `suitcap drape`
//! wears without masks; `CLOTH_HEIGHT_SCALE` and `CLOTH_GIRTH` size it as `drape --masks` prints,
//! e.g. 1.017 and 1.19 for the demo clip on the segmenter's masks). `CLOTH_GARMENTS`: other
//! garments than the T-shirt and the dress, e.g. `skirt`. Each case counts the vertices that tunnel through a capsule in any substep
//! (`Cloth::check_tunnelling`, "tunnelled N (M frames; D dressing)": in the motion's frames after
//! the first, and while the garment was put on); `CLOTH_NO_TUNNEL_CHECK=1` leaves the count out
//! ("tunnelled -"), which the frames/s need. The frames/s printed are from `run_motion`'s
//! stepping time: one run, noisy; use `cargo bench --bench cloth` for speed.

use std::path::Path;

use glam::Vec3A;
use suitcap::body::Body;
use suitcap::body::Subject;
use suitcap::body_size::BodySize;
use suitcap::bvh::{Motion, CMU_CALIBRATION_FRAMES};
use suitcap::cloth::capsule::Capsule;
use suitcap::cloth::garment::{GarmentKind, GarmentMesh, GarmentParams};
use suitcap::cloth::material::Material;
use suitcap::cloth::proxies::{BodyRig, DEFAULT_MARGIN_CM};
use suitcap::cloth::solver::{run_motion, Cloth, SolverSettings};
use suitcap::cloth::topology::unique_edges;

/// Frames to skip at the start of `motion`: the calibration lead-in of a raw capture at more than
/// 60 frames/s ([`CMU_CALIBRATION_FRAMES`]), none otherwise (the generator's and the demo's clips,
/// at 30 frames/s, start in the take; `CLOTH_FIRST_FRAME` overrides it).
fn calibration_frames(motion: &Motion) -> usize {
    if motion.frame_time < 1.0 / 60.0 {
        CMU_CALIBRATION_FRAMES
    } else {
        0
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let verbose = args.iter().any(|a| a == "-v");
    let check_tunnelling = std::env::var("CLOTH_NO_TUNNEL_CHECK").map_or(true, |v| v != "1");
    let only = args
        .iter()
        .find(|a| *a != "-v")
        .cloned()
        .unwrap_or_default();
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let subject_name = std::env::var("CLOTH_SUBJECT").unwrap_or_else(|_| "chidi".into());
    let quality_mode = std::env::var("CLOTH_MODE").is_ok_and(|m| m == "quality");
    // Vertex counts (default the bench's 2,000 and 4,000), e.g. CLOTH_COUNTS=2400,3400.
    let counts: Vec<usize> = std::env::var("CLOTH_COUNTS")
        .ok()
        .map(|s| s.split(',').filter_map(|c| c.trim().parse().ok()).collect())
        .unwrap_or_else(|| vec![2000, 4000]);
    let mut settings = if quality_mode {
        SolverSettings::quality()
    } else {
        SolverSettings::live()
    };
    let env = |name: &str| std::env::var(name).ok().and_then(|s| s.parse::<f32>().ok());
    if let Some(v) = env("CLOTH_SUBSTEPS") {
        settings.substeps = v as u32;
    }
    if let Some(v) = env("CLOTH_SWEEPS") {
        settings.stretch_sweeps = v as u32;
    }
    if let Some(v) = env("CLOTH_TETHER_SLACK") {
        settings.tether_slack = v;
    }
    if let Some(v) = env("CLOTH_TAU") {
        settings.loose_anchor_seconds = v;
    }
    if let Some(v) = env("CLOTH_RHO") {
        settings.chebyshev_rho = v;
    }
    if let Some(v) = env("CLOTH_LIMIT") {
        settings.strain_limit = v;
    }
    if let Some(v) = env("CLOTH_CUFF_SLIDE") {
        settings.cuff_slide_cm = v;
    }
    if let Some(v) = env("CLOTH_CUFF_TAU") {
        settings.cuff_hold_seconds = v;
    }
    if let Some(v) = env("CLOTH_COMPRESSION") {
        settings.compression = v;
    }
    let mut material = match std::env::var("CLOTH_MATERIAL") {
        Ok(name) => Material::preset(&name).ok_or(format!("no material preset {name}"))?,
        Err(_) => Material::medium(),
    };
    if let Some(v) = env("CLOTH_BEND_SCALE") {
        material.bend_compliance *= v;
    }
    let extra_clip = std::env::var("CLOTH_CLIP").ok();
    let clips = match &extra_clip {
        Some(clip) => vec![("clip", clip.as_str())],
        None => vec![
            ("walk", "tests/data/mocap/cmu_02_01_walk.bvh"),
            ("kick", "tests/data/mocap/cmu_10_03_kick_ball.bvh"),
        ],
    };
    // Garments: the bench's T-shirt and dress, or those named in CLOTH_GARMENTS (e.g. `skirt`).
    let kinds: Vec<GarmentKind> = match std::env::var("CLOTH_GARMENTS") {
        Ok(names) => names
            .split(',')
            .map(|n| n.trim().parse())
            .collect::<Result<_, _>>()?,
        Err(_) => vec![GarmentKind::TShirt, GarmentKind::Dress],
    };
    // The quality mode's garment has one size (its edge length), not a vertex count.
    let counts = if quality_mode { vec![0] } else { counts };
    for (clip_name, clip) in clips {
        let motion = Motion::load(&repo.join(clip))?;
        let rig = if subject_name == "motion" {
            let size = BodySize {
                height_scale: env("CLOTH_HEIGHT_SCALE").unwrap_or(1.0),
                girth: env("CLOTH_GIRTH").unwrap_or(1.0),
                ..BodySize::TEMPLATE
            };
            let (subject, skeleton) = size.subject(&motion.skeleton);
            let body = Body::new(&subject, &skeleton)?;
            BodyRig::new(skeleton, body, DEFAULT_MARGIN_CM)
        } else {
            let subject =
                Subject::find(&subject_name).ok_or(format!("no subject {subject_name}"))?;
            BodyRig::for_subject(subject, &motion.skeleton, DEFAULT_MARGIN_CM)?
        };
        let first_frame = match env("CLOTH_FIRST_FRAME") {
            Some(frame) => frame as usize,
            None => calibration_frames(&motion),
        };
        let (frames, _) =
            rig.scale_motion(&motion)
                .resample(first_frame, None, settings.fps as f64)?;
        // The limbs' speed, for the "no tunnelling at 3 m/s hand speed" of issue 6.
        let (hands, feet) = suitcap::cloth::solver::peak_limb_speeds(&frames);
        println!(
            "{clip_name}: hands up to {hands:.1} m/s, feet up to {feet:.1} m/s between frames"
        );
        for &kind in &kinds {
            for &target in &counts {
                let size = if quality_mode {
                    "quality".to_string()
                } else {
                    target.to_string()
                };
                let case = format!("{clip_name}/{}/{size}", kind.name());
                if !only.is_empty() && !case.contains(&only) {
                    continue;
                }
                let mesh = if quality_mode {
                    GarmentMesh::generate(kind, &rig, &GarmentParams::quality())?
                } else {
                    GarmentMesh::with_vertex_count(kind, &rig, target, 2.5)?.0
                };
                let mut cloth = Cloth::new(&mesh, &material, &settings, &rig)?;
                cloth.check_tunnelling(check_tunnelling);
                let (mut worst, mut peak) = (Snapshot::default(), Snapshot::default());
                let mut maxima = Vec::new();
                let summary = run_motion(&rig, &mut cloth, &frames, |k, c, q| {
                    maxima.push(q.strain_max);
                    peak.keep_if_above(q.strain_max, k, c);
                    worst.keep_if_above(q.strain_p95, k, c);
                })?;
                let sleeves = if mesh.cuffs.is_empty() {
                    format!(
                        "no sleeves, waist {:.1} cm from its place (mean; most {:.1})",
                        summary.belt_offset_mean_cm, summary.belt_offset_max_cm
                    )
                } else {
                    format!(
                        "sleeve ends ≤ {:.1} cm off the arm, {:.1} cm up it (mean; most {:.1})",
                        summary.cuff_gap_max_cm,
                        summary.cuff_slide_mean_cm,
                        summary.cuff_slide_max_cm
                    )
                };
                println!(
                    "{case:22} {:5} v  p95 {:.2} / {:.2} %  max {:5.2} %  stretch p95 {:.2} max {:5.1} %  pen {:.2} mm  tunnelled {}  {sleeves}  {:.0} fps",
                    summary.vertices,
                    100.0 * summary.strain_p95_worst,
                    100.0 * summary.strain_p95_mean,
                    100.0 * summary.strain_max,
                    100.0 * summary.stretch_p95_worst,
                    100.0 * summary.stretch_max,
                    10.0 * summary.penetration_max_cm,
                    match (summary.tunnelled, summary.tunnelled_dressing) {
                        (Some(n), Some(d)) => {
                            format!("{n} ({} frames; {d} dressing)", summary.tunnelled_frames)
                        }
                        _ => "-".to_string(),
                    },
                    summary.frames_per_second()
                );
                if verbose {
                    describe_top(&rig, &cloth, &mesh, &worst);
                    let over = |t: f32| maxima.iter().filter(|&&m| m > t).count();
                    println!(
                        "   frames with max > 5 / 10 / 20 %: {} / {} / {} of {}",
                        over(0.05),
                        over(0.10),
                        over(0.20),
                        maxima.len()
                    );
                    describe_peak(&rig, &cloth, &mesh, &peak);
                }
            }
        }
    }
    Ok(())
}

/// A frame kept for the verbose report: the figure it was kept for, its index, the cloth's
/// positions and the posed capsules.
#[derive(Default)]
struct Snapshot {
    value: f32,
    frame: usize,
    x: Vec<Vec3A>,
    capsules: Vec<Capsule>,
}

impl Snapshot {
    fn keep_if_above(&mut self, value: f32, frame: usize, cloth: &Cloth) {
        if value > self.value {
            *self = Snapshot {
                value,
                frame,
                x: cloth.positions().to_vec(),
                capsules: cloth.pose().capsules.clone(),
            };
        }
    }
}

/// Where the top 5 % of edges of one frame lie.
fn describe_top(rig: &BodyRig, cloth: &Cloth, mesh: &GarmentMesh, at: &Snapshot) {
    let (frame, x, capsules) = (at.frame, &at.x, &at.capsules);
    let rest = cloth.rest_positions();
    let edges = unique_edges(&mesh.triangles);
    let mut strains: Vec<(f32, usize)> = edges
        .iter()
        .enumerate()
        .map(|(e, &[i, j])| {
            let l0 = rest[i as usize].distance(rest[j as usize]);
            ((x[i as usize].distance(x[j as usize]) - l0) / l0, e)
        })
        .collect();
    strains.sort_by(|a, b| b.0.abs().total_cmp(&a.0.abs()));
    let top = &strains[..strains.len() / 20];
    let mean_rest: f32 = edges
        .iter()
        .map(|&[i, j]| rest[i as usize].distance(rest[j as usize]))
        .sum::<f32>()
        / edges.len() as f32;
    let stretched = top.iter().filter(|s| s.0 > 0.0).count();
    println!(
        "   worst frame {frame}: top {} edges, {} stretched / {} compressed; mean rest {:.2} cm",
        top.len(),
        stretched,
        top.len() - stretched,
        mean_rest
    );
    // Per nearest body part (at rest), how many of the top edges and their mean rest length.
    let mut parts: Vec<(String, usize, usize, f32, f32)> = Vec::new();
    for &(s, e) in top {
        let [i, j] = edges[e];
        let mid = (x[i as usize] + x[j as usize]) * 0.5;
        let mut best = (f32::INFINITY, "?");
        for (pc, cap) in rig.proxies().iter().zip(capsules) {
            let d = cap.signed_distance(mid.into());
            if d < best.0 {
                best = (d, rig.body().parts[pc.part].name);
            }
        }
        let l0 = rest[i as usize].distance(rest[j as usize]);
        let name = best.1.to_string();
        match parts.iter_mut().find(|p| p.0 == name) {
            Some(p) => {
                p.1 += 1;
                p.2 += (s > 0.0) as usize;
                p.3 += l0;
                p.4 += best.0;
            }
            None => parts.push((name, 1, (s > 0.0) as usize, l0, best.0)),
        }
    }
    parts.sort_by_key(|p| std::cmp::Reverse(p.1));
    for (name, n, st, l0, d) in parts {
        println!(
            "     {name:16} {n:4} edges ({st} stretched), mean rest {:.2} cm, mean distance {:+.2} cm",
            l0 / n as f32,
            d / n as f32
        );
    }
    // By rest height band (10 cm) and side (front z > 0 / back).
    let mut bands: std::collections::BTreeMap<(i32, bool), (usize, usize, usize)> =
        Default::default();
    for (k, &(s, e)) in strains.iter().enumerate() {
        let [i, j] = edges[e];
        let p = (rest[i as usize] + rest[j as usize]) * 0.5;
        let b = bands
            .entry(((p.y / 10.0).floor() as i32, p.z > 0.0))
            .or_default();
        b.0 += 1;
        if k < top.len() {
            b.1 += 1;
            b.2 += (s > 0.0) as usize;
        }
    }
    for ((y, front), (n, t, st)) in bands.iter().rev() {
        println!(
            "     y {:4}..{:4} {:5} {n:5} edges, {t:4} in top ({st} stretched)",
            y * 10,
            y * 10 + 10,
            if *front { "front" } else { "back" }
        );
    }
    for &(s, e) in strains.iter().take(5) {
        let [i, j] = edges[e];
        let p = (rest[i as usize] + rest[j as usize]) * 0.5;
        println!(
            "     {:+.1} % edge {i}-{j} rest {:.2} cm at rest ({:.0}, {:.0}, {:.0})",
            100.0 * s,
            rest[i as usize].distance(rest[j as usize]),
            p.x,
            p.y,
            p.z
        );
    }
}

/// The edges above 10 % strain in the frame of the largest strain, with the capsules their ends
/// are nearest to and how deep.
fn describe_peak(rig: &BodyRig, cloth: &Cloth, mesh: &GarmentMesh, at: &Snapshot) {
    let (frame, x, capsules) = (at.frame, &at.x, &at.capsules);
    let rest = cloth.rest_positions();
    let edges = unique_edges(&mesh.triangles);
    let nearest = |p: Vec3A| {
        let mut d: Vec<(f32, &str)> = rig
            .proxies()
            .iter()
            .zip(capsules)
            .map(|(pc, cap)| {
                (
                    cap.signed_distance(p.into()),
                    rig.body().parts[pc.part].name,
                )
            })
            .collect();
        d.sort_by(|a, b| a.0.total_cmp(&b.0));
        format!("{} {:+.2} / {} {:+.2}", d[0].1, d[0].0, d[1].1, d[1].0)
    };
    let mut over: Vec<(f32, usize, usize)> = edges
        .iter()
        .filter_map(|&[i, j]| {
            let (i, j) = (i as usize, j as usize);
            let l0 = rest[i].distance(rest[j]);
            let s = (x[i].distance(x[j]) - l0) / l0;
            (s.abs() > 0.10).then_some((s, i, j))
        })
        .collect();
    over.sort_by(|a, b| b.0.abs().total_cmp(&a.0.abs()));
    println!("   peak frame {frame}: {} edges over 10 %", over.len());
    for &(s, i, j) in over.iter().take(12) {
        let p = (rest[i] + rest[j]) * 0.5;
        println!(
            "     {:+.1} % {i}-{j} rest {:.2} cm at ({:.0}, {:.0}, {:.0}); ends: {} | {}",
            100.0 * s,
            rest[i].distance(rest[j]),
            p.x,
            p.y,
            p.z,
            nearest(x[i]),
            nearest(x[j])
        );
    }
}
