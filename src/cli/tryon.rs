//! `suitcap run`, `drape`, `demo` and `live`: the try-on pipeline behind the command line.
//!
//! `run` and `live` drive [`suitcap::tryon::runner`] (stages on threads), recording the pose as BVH;
//! `drape` simulates a garment on a given motion (ground truth from the generator) and composites it
//! into the given frames; `demo` is `run` on the footage bundled with the default suit, compared with
//! its ground truth. Everything written goes to a temporary name first and is renamed, and the BVH
//! take is written whatever ends the run (end of input, a failing camera, Ctrl-C, SIGTERM).

use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::sync::Arc;

use anyhow::{bail, Context};
use clap::Args;
use image::RgbImage;

use super::counted;
use suitcap::bvh::Motion;
use suitcap::camera::Camera;
use suitcap::cloth::material::Material;
use suitcap::pipeline::PosePipeline;
use suitcap::pose::smoothing::{
    index_ranges, repair_root_glitches, smooth_backwards, JointLimits, PoseFilter, SmoothingParams,
    JOINT_LIMITS_FILE,
};
use suitcap::preview::{GifPreview, PreviewSettings};
use suitcap::render::RenderSettings;
use suitcap::skeleton::{interpolate_frames, MAX_ROOT_TURN_DEG_PER_S};
use suitcap::source::{open_source, FrameSource, SourceOptions};
use suitcap::tryon::runner::{
    self, Controls, FrameTimes, InputKind, Output, PoseStage, RunSummary,
};
use suitcap::tryon::{
    ClothOptions, ClothStage, ClothStatus, GarmentChoice, Overlays, RenderStage, SimulationMode,
    ESTIMATED_POSE_INERTIA,
};

/// Options shared by the commands that put a garment on.
#[derive(Args, Clone, Debug)]
pub struct GarmentArgs {
    /// tshirt, skirt, dress, a garment .obj (rest-pose world cm), or none.
    #[arg(long, default_value = "tshirt")]
    pub garment: String,
    /// Fabric preset: light, medium, stiff, chiffon, silk, cotton_poplin, cotton_jersey, wool, denim.
    #[arg(long, default_value = "medium")]
    pub material: String,
    /// Simulate as the live app does (2 cm garment, 40 substeps) instead of the quality mode
    /// (1 cm garment, 80 substeps) that recorded input gets by default.
    #[arg(long)]
    pub live_cloth: bool,
    /// Debug overlays drawn into the frames: any of mask, markers, skeleton, timings (comma-separated).
    #[arg(long, value_delimiter = ',')]
    pub overlays: Vec<String>,
}

/// Options of the pose stage.
#[derive(Args, Clone, Debug)]
pub struct PoseArgs {
    /// Switch off the One-Euro smoothing of the pose (and the take's second pass backwards on
    /// writing), and the filling in of the frames in which the whole body turns
    /// faster than a person can (in the written take; with `run`, also in the poses the garment
    /// and the overlays follow).
    #[arg(long)]
    pub no_smoothing: bool,
    /// Switch off the joint limits (SUIT/joint_limits.toml).
    #[arg(long)]
    pub no_limits: bool,
}

pub fn parse_overlays(names: &[String]) -> anyhow::Result<Overlays> {
    let mut o = Overlays::default();
    for name in names.iter().filter(|n| !n.is_empty()) {
        match name.as_str() {
            "mask" => o.mask = true,
            "markers" => o.markers = true,
            "skeleton" => o.skeleton = true,
            "timings" => o.timings = true,
            other => {
                bail!("--overlays: unknown overlay '{other}' (mask, markers, skeleton, timings)")
            }
        }
    }
    Ok(o)
}

fn material(name: &str) -> anyhow::Result<Material> {
    Material::preset(name).with_context(|| {
        format!("--material: unknown fabric '{name}' (light, medium, stiff, chiffon, silk, cotton_poplin, cotton_jersey, wool, denim)")
    })
}

/// The garment `--garment` names (a built-in one or an OBJ file that exists).
fn garment_choice(name: &str) -> anyhow::Result<GarmentChoice> {
    let garment = GarmentChoice::parse(name).context("--garment")?;
    if let GarmentChoice::Obj(path) = &garment {
        if !path.is_file() {
            bail!("--garment: {} does not exist", path.display());
        }
    }
    Ok(garment)
}

/// The cloth stage asked for, or `None` for `--garment none`. On recorded input the garment is
/// worn from the first frame with a person (the frames held while the person is measured).
fn cloth_stage(
    args: &GarmentArgs,
    template: &suitcap::skeleton::Skeleton,
    mode: SimulationMode,
    input: InputKind,
) -> anyhow::Result<Option<ClothStage>> {
    if args.garment.eq_ignore_ascii_case("none") {
        return Ok(None);
    }
    let mut options = ClothOptions::new(garment_choice(&args.garment)?, mode);
    options.material = material(&args.material)?;
    options.inertia = ESTIMATED_POSE_INERTIA;
    options.dress_from_first_frame = input == InputKind::Recorded;
    Ok(Some(ClothStage::new(template, options)?))
}

fn render_stage(pipeline: &PosePipeline) -> RenderStage {
    let colours = pipeline
        .suit
        .markers
        .iter()
        .map(|c| {
            c.hsv
                .to_rgb()
                .map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
        })
        .collect();
    RenderStage::new(RenderSettings::default(), colours)
}

/// The pose stage of `run` (`glitch_window_s`: recorded input, [`GLITCH_WINDOW_S`] unless the
/// smoothing is off) or of `live` (`None`: a live picture is not held back).
fn pose_stage(
    suit_dir: &Path,
    args: &PoseArgs,
    glitch_window_s: Option<f64>,
) -> anyhow::Result<PoseStage> {
    let pipeline = PosePipeline::load(suit_dir)?;
    let limits_path = suit_dir.join(JOINT_LIMITS_FILE);
    let limits = if args.no_limits || !limits_path.exists() {
        None
    } else {
        Some(JointLimits::load(&limits_path)?)
    };
    let smoothing = (!args.no_smoothing).then(SmoothingParams::default);
    let filter = (smoothing.is_some() || limits.is_some()).then(|| {
        PoseFilter::new(
            &pipeline.regressor.skeleton.skeleton,
            smoothing,
            limits.as_ref(),
        )
    });
    let segmenter = Some(PosePipeline::load_segmenter(suit_dir)?);
    Ok(PoseStage {
        pipeline,
        filter,
        segmenter,
        root_glitch_window_s: glitch_window_s.filter(|_| !args.no_smoothing),
    })
}

/// The camera calibration of an input: `--camera`, else camera.toml beside the input, else in
/// the suit; `None` when there is none. A calibration file that is there but cannot be read is
/// an error naming it, never passed over for an assumed camera.
pub fn find_camera(
    input: &str,
    suit_dir: &Path,
    camera: Option<&PathBuf>,
) -> anyhow::Result<Option<Camera>> {
    let path = match camera {
        Some(path) => Some(path.clone()),
        None => {
            let input = Path::new(input);
            [
                input.join("camera.toml"),
                input.with_file_name("camera.toml"),
                suit_dir.join("camera.toml"),
            ]
            .into_iter()
            .find(|p| p.is_file())
        }
    };
    Ok(path.map(|path| Camera::load(&path)).transpose()?)
}

/// The input's calibration ([`find_camera`]), else a typical webcam at the input's `size`
/// ([`default_webcam`]), saying so: the joint angles do not need the camera, only the root's
/// place in the room does.
fn camera_or_webcam(
    input: &str,
    suit_dir: &Path,
    camera: Option<Camera>,
    size: (u32, u32),
) -> Camera {
    camera.unwrap_or_else(|| {
        println!(
            "no camera calibration for {input} (--camera, or camera.toml beside it or in {}): assuming a webcam with a 60° horizontal field of view, level, 1.2 m above the floor, the person about 3.5 m away; the joint angles do not depend on it, the root's position does",
            suit_dir.display()
        );
        default_webcam(size)
    })
}

/// Lets Ctrl-C and SIGTERM stop the capture so the take is finalised.
pub fn stop_on_signals(controls: &Arc<Controls>) {
    let controls = Arc::clone(controls);
    if let Err(e) = ctrlc::set_handler(move || {
        eprintln!("\nstopping: finishing the frames in flight and writing the take…");
        controls.stop.store(true, Ordering::Relaxed);
    }) {
        eprintln!("warning: Ctrl-C will not finalise the take: {e}");
    }
}

/// Per-stage milliseconds of every frame, for medians.
#[derive(Default)]
pub struct TimingLog {
    frames: Vec<FrameTimes>,
}

/// Picks one stage's milliseconds out of a frame's timings.
type StageTime = fn(&FrameTimes) -> f64;

impl TimingLog {
    pub fn push(&mut self, t: FrameTimes) {
        self.frames.push(t);
    }

    fn median(&self, f: impl Fn(&FrameTimes) -> f64) -> f64 {
        super::median(&self.frames.iter().map(f).collect::<Vec<_>>())
    }

    /// "stage median ms" lines.
    pub fn summary(&self) -> String {
        let stages: [(&str, StageTime); 7] = [
            ("segment", |t| t.segment),
            ("describe", |t| t.describe),
            ("regress + root", |t| t.regress),
            ("cloth", |t| t.cloth),
            ("render", |t| t.render),
            ("composite", |t| t.composite),
            ("latency", |t| t.latency),
        ];
        let mut out = format!("per-stage median over {} frames:\n", self.frames.len());
        for (name, f) in stages {
            out.push_str(&format!("  {name:<16} {:>8.2} ms\n", self.median(f)));
        }
        out
    }
}

/// A BVH take being recorded, one BVH frame per frame of its [`TakeClock`]. Frames of the clock
/// without a pose (input frames that were corrupt or that a live pipeline dropped because it was
/// behind; on the camera's clock also frames the camera itself dropped, which show only as a gap in
/// its timestamps) are filled in between the poses before and after them (rotations the short way,
/// as the cloth's substeps are), or hold the last pose at the end of a recording; without them
/// every later BVH frame would be early against the video.
pub struct Take {
    motion: Motion,
    path: PathBuf,
    /// Which channels are rotations, for the filling in.
    rotation: Vec<bool>,
    fps: f64,
    clock: TakeClock,
    /// The input frame BVH frame 0 stands for: 0 for a recording; for a live take, which starts
    /// at whichever frame is shown when recording starts, `None` until the first pose.
    first_index: Option<u64>,
    /// The first pose pushed, to which the camera's clock measures every later frame's time.
    first: Option<Placed>,
    /// The last pose pushed.
    last: Option<Placed>,
    /// Whether [`Take::write`] fills in root glitches.
    repair_glitches: bool,
    /// BVH frames whose poses came already filled in over a root glitch (the runner's
    /// [`RootGlitchRepair`](suitcap::pose::smoothing::RootGlitchRepair) on recorded input).
    filled_before: Vec<usize>,
    /// The frames filled in over root glitches, before and by the last [`Take::write`].
    glitches: Vec<std::ops::Range<usize>>,
    /// The pose filter the poses were smoothed with forwards, to smooth a recording's take
    /// backwards on writing ([`smooth_backwards`]); `None`: written as pushed.
    backward: Option<PoseFilter>,
    /// BVH frames with nobody in view (the forward filter started again after them).
    nobody: Vec<usize>,
    /// BVH frames filled in for frames of the clock without a pose (filled in again from the
    /// smoothed poses around them when the take is smoothed back).
    held_slots: Vec<usize>,
}

/// The `count` frames between `before` and `next` at even steps, one after the other into `out`
/// (cleared): what [`Take`] fills in for frames of the clock without a pose, rotations the short
/// way ([`interpolate_frames`]).
fn frames_between(
    rotation: &[bool],
    before: &[f32],
    next: &[f32],
    count: usize,
    out: &mut Vec<f32>,
) {
    out.clear();
    let mut frame = Vec::with_capacity(before.len());
    for k in 1..=count {
        let t = k as f32 / (count + 1) as f32;
        interpolate_frames(rotation, before, next, t, &mut frame);
        out.extend_from_slice(&frame);
    }
}

/// How long a root glitch may last before the pose it comes back to, seconds
/// ([`repair_root_glitches`]): the quick start's lasts three frames.
pub const GLITCH_WINDOW_S: f64 = 0.5;

/// What a take's BVH frames count.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TakeClock {
    /// One BVH frame per input frame (`run`: BVH frame k is the recording's k-th frame, so the
    /// take lines up with the frame files and the composited frames).
    InputFrames,
    /// One BVH frame per 1/fps of the frames' timestamps (`live`: the take keeps the camera's
    /// time also over frames the camera dropped).
    CaptureTime,
}

/// Where a pushed pose went: its input frame, its time in the stream, its BVH frame.
#[derive(Clone, Copy, Debug)]
struct Placed {
    index: u64,
    time_s: f64,
    slot: u64,
}

impl Take {
    /// A take at `fps` on `skeleton` counting `clock`'s frames, written to `path`; its first BVH
    /// frame stands for input frame `first_index` (0 for a recording) or, with `None`, for the
    /// first frame pushed.
    pub fn new(
        skeleton: &suitcap::skeleton::Skeleton,
        fps: f64,
        clock: TakeClock,
        path: PathBuf,
        first_index: Option<u64>,
    ) -> anyhow::Result<Take> {
        Ok(Take {
            motion: Motion::new(skeleton.clone(), 1.0 / fps, Vec::new())?,
            path,
            rotation: skeleton.rotation_channels(),
            fps,
            clock,
            first_index,
            first: None,
            last: None,
            repair_glitches: true,
            filled_before: Vec::new(),
            glitches: Vec::new(),
            backward: None,
            nobody: Vec::new(),
            held_slots: Vec::new(),
        })
    }

    /// The take smoothed backwards on writing with `filter`, the one its poses were smoothed
    /// with forwards ([`smooth_backwards`]: a recording's take then follows the motion without
    /// the forward filter's lag); `None`, or a filter that does not smooth: written as pushed.
    pub fn smoothing_backwards(mut self, filter: Option<PoseFilter>) -> Take {
        self.backward = filter.filter(PoseFilter::smoothing_enabled);
        self
    }

    /// Notes that BVH frame `slot` had nobody in view, so the backward smoothing starts again
    /// there as the forward one did.
    pub fn note_nobody(&mut self, slot: u64) {
        self.nobody.push(slot as usize);
    }

    /// The take with the filling in of root glitches on write switched on or off (on by default).
    pub fn repairing_glitches(mut self, on: bool) -> Take {
        self.repair_glitches = on;
        self
    }

    /// The BVH frame for input frame `index` shown at `time_s` into the stream. The first pose
    /// goes to its input frame's place (input frames before it were lost). On the input frames'
    /// clock every later one does too; on the camera's it goes to its time's place after the
    /// first pose, and at least one after the pose before it (a camera running a little faster
    /// than its rate must not overwrite poses).
    fn slot_for(&self, index: u64, time_s: f64) -> u64 {
        match (self.clock, self.first, self.last) {
            (TakeClock::CaptureTime, Some(first), Some(last)) => {
                let elapsed = ((time_s - first.time_s) * self.fps).round().max(0.0);
                (first.slot + elapsed as u64).max(last.slot + 1)
            }
            _ => index.saturating_sub(self.first_index.unwrap_or(index)),
        }
    }

    /// Records the pose of input frame `index`, shown at `time_s` into the stream, first filling
    /// in the clock's frames between the last pose pushed and it (between the two poses; before the
    /// first pose, with this one).
    /// Returns the BVH frame it went to.
    pub fn push(&mut self, index: u64, time_s: f64, frame: &[f32]) -> anyhow::Result<u64> {
        let slot = self.slot_for(index, time_s);
        self.fill_until(slot, frame)?;
        self.motion.push_frame(frame)?;
        let placed = Placed {
            index,
            time_s,
            slot,
        };
        self.first.get_or_insert(placed);
        self.first_index.get_or_insert(index);
        self.last = Some(placed);
        Ok(slot)
    }

    /// Holds the last pose over the input frames after the last one pushed, up to the stream's
    /// `input_frames` (the frames a recording ended with that never reached the pose stage).
    /// Nothing to hold before the first pose.
    pub fn hold_to_end(&mut self, input_frames: u64) -> anyhow::Result<()> {
        let Some(last) = self.last else {
            return Ok(());
        };
        let after = input_frames.saturating_sub(last.index + 1);
        let pose = self.motion.frame(self.motion.frame_count() - 1).to_vec();
        self.fill_until(last.slot + 1 + after, &pose)
    }

    /// Fills the BVH frames from the next one up to `slot` (exclusive): from the last pose
    /// towards `next`, the pose of BVH frame `slot` (the last pose throughout when `next` is that
    /// pose; `next` throughout before the first pose).
    fn fill_until(&mut self, slot: u64, next: &[f32]) -> anyhow::Result<()> {
        let filled_to = self.motion.frame_count() as u64;
        let missing = slot.saturating_sub(filled_to);
        if missing == 0 {
            return Ok(());
        }
        let before = match self.motion.frame_count() {
            0 => next.to_vec(),
            n => self.motion.frame(n - 1).to_vec(),
        };
        let mut filled = Vec::new();
        frames_between(&self.rotation, &before, next, missing as usize, &mut filled);
        for frame in filled.chunks_exact(before.len().max(1)) {
            self.motion.push_frame(frame)?;
        }
        self.held_slots
            .extend(filled_to as usize..(filled_to + missing) as usize);
        Ok(())
    }

    pub fn frames(&self) -> usize {
        self.motion.frame_count()
    }

    /// BVH frames filled in for frames of the clock without a pose.
    pub fn held(&self) -> usize {
        self.held_slots.len()
    }

    /// "recorded N frames → PATH", with the frames held over input that never reached the pose
    /// stage.
    fn recorded_line(&self, path: &Path) -> String {
        format!(
            "recorded {} frames → {} ({} of them filled in between the poses around them, for frames that were corrupt or that the pipeline or the camera dropped, so the take keeps the camera's time{})",
            self.frames(),
            path.display(),
            self.held(),
            self.glitches_clause()
        )
    }

    /// Notes that the pose pushed to BVH frame `slot` came filled in over a root glitch, for the
    /// report ([`Take::glitches_clause`]).
    pub fn note_glitch_filled(&mut self, slot: u64) {
        self.filled_before.push(slot as usize);
    }

    /// Fills the held frames of `values` (the take's frames one after the other) in again between
    /// the poses around them, as [`Take::fill_until`] did when they were pushed: half-way between
    /// two poses, the last pose after the end, the first before the start.
    fn fill_in_again(&self, values: &mut [f32]) {
        let channels = self.rotation.len();
        let frames = values.len() / channels.max(1);
        let mut filled = Vec::with_capacity(channels);
        for run in index_ranges(self.held_slots.iter().copied()) {
            let frame = |k: usize| values[k * channels..(k + 1) * channels].to_vec();
            let (before, next) = match (
                run.start.checked_sub(1).map(frame),
                (run.end < frames).then(|| frame(run.end)),
            ) {
                (Some(before), Some(next)) => (before, next),
                (Some(pose), None) | (None, Some(pose)) => (pose.clone(), pose),
                (None, None) => continue,
            };
            frames_between(&self.rotation, &before, &next, run.len(), &mut filled);
            values[run.start * channels..run.end * channels].copy_from_slice(&filled);
        }
    }

    /// Writes the take (atomically) and returns its path. The file gets the frames in which the
    /// whole body turned faster than a person can filled in between the frames around them
    /// ([`repair_root_glitches`], within [`GLITCH_WINDOW_S`]): a live take's poses come on as
    /// they were estimated, a `run`'s came filled in already ([`Take::note_glitch_filled`]).
    /// A take [`Take::smoothing_backwards`] is then smoothed backwards. The take in memory keeps
    /// what was pushed.
    pub fn write(&mut self) -> anyhow::Result<PathBuf> {
        let mut values = self.motion.values().to_vec();
        let window = (GLITCH_WINDOW_S * self.fps).round().max(1.0) as usize;
        let repaired = if self.repair_glitches {
            repair_root_glitches(
                &self.motion.skeleton,
                &mut values,
                MAX_ROOT_TURN_DEG_PER_S / self.fps as f32,
                window,
            )
        } else {
            Vec::new()
        };
        if let Some(filter) = &mut self.backward {
            smooth_backwards(
                filter,
                &mut values,
                1.0 / self.fps,
                (&self.nobody, &self.held_slots),
            );
            self.fill_in_again(&mut values);
        }
        let mut filled = vec![false; self.motion.frame_count()];
        for k in repaired
            .into_iter()
            .flatten()
            .chain(self.filled_before.iter().copied())
        {
            if let Some(f) = filled.get_mut(k) {
                *f = true;
            }
        }
        self.glitches = index_ranges(
            filled
                .iter()
                .enumerate()
                .filter(|(_, &f)| f)
                .map(|(k, _)| k),
        );
        Motion::new(self.motion.skeleton.clone(), 1.0 / self.fps, values)?.write(&self.path)?;
        Ok(self.path.clone())
    }

    /// "; N BVH frames of M root glitches filled in" after a write that filled any, else "".
    fn glitches_clause(&self) -> String {
        match self.glitches.iter().map(|g| g.len()).sum::<usize>() {
            0 => String::new(),
            frames => format!(
                "; {} of {} (the whole body turning faster than a person can) filled in between the frames around them",
                counted(frames, "BVH frame", "BVH frames"),
                counted(self.glitches.len(), "root glitch", "root glitches")
            ),
        }
    }
}

/// What `run` writes besides the take.
struct RunOutputs {
    frames_dir: PathBuf,
    preview: Option<GifPreview>,
    rows: String,
    /// The input frame the next row is for.
    next_index: u64,
}

impl RunOutputs {
    fn new(out: &Path, fps: f64) -> anyhow::Result<RunOutputs> {
        let frames_dir = out.join("frames");
        std::fs::create_dir_all(&frames_dir)
            .with_context(|| format!("cannot create {}", frames_dir.display()))?;
        let settings = PreviewSettings {
            fps: fps as f32,
            ..PreviewSettings::default()
        };
        Ok(RunOutputs {
            frames_dir,
            preview: Some(GifPreview::create(&out.join("preview.gif"), settings)?),
            rows: String::from(
                "frame,person,markers,garment,strain_p95,penetration_cm,segment_ms,describe_ms,regress_ms,cloth_ms,render_ms,composite_ms,time_s,bvh_frame,root_glitch\n",
            ),
            next_index: 0,
        })
    }

    /// Rows for the input frames before `index` that never reached the pipeline (corrupt): their
    /// garment column says `skipped` and the rest is empty.
    fn skipped_until(&mut self, index: u64) {
        for k in self.next_index..index {
            self.rows.push_str(&format!("{k},,,skipped,,,,,,,,,,,\n"));
        }
        self.next_index = self.next_index.max(index);
    }

    /// The row and composited frame of `out`, whose pose went to BVH frame `bvh_frame`.
    fn add(&mut self, out: &Output, bvh_frame: u64) -> anyhow::Result<()> {
        self.skipped_until(out.index);
        self.next_index = out.index + 1;
        let path = self.frames_dir.join(format!("{:06}.png", out.index));
        write_png(&out.image, &path)?;
        if let Some(preview) = &mut self.preview {
            preview.push(&out.image)?;
        }
        let t = out.times;
        let (strain, depth) = out
            .cloth
            .quality
            .map_or((String::new(), String::new()), |q| {
                (
                    format!("{:.5}", q.strain_p95),
                    format!("{:.3}", q.penetration_cm),
                )
            });
        self.rows.push_str(&format!(
            "{},{},{},{},{strain},{depth},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.6},{bvh_frame},{}\n",
            out.index,
            out.pose.person as u8,
            out.pose.markers.len(),
            status_name(&out.cloth.status),
            t.segment,
            t.describe,
            t.regress,
            t.cloth,
            t.render,
            t.composite,
            out.timestamp_s,
            out.pose.root_glitch_filled as u8
        ));
        Ok(())
    }

    fn finish(mut self, out: &Path) -> anyhow::Result<()> {
        if let Some(preview) = self.preview.take() {
            preview.finish()?;
        }
        let path = out.join("frames.csv");
        suitcap::io::write_atomic(&path, self.rows.as_bytes())
            .with_context(|| format!("cannot write {}", path.display()))
    }
}

/// The frames whose garment could not be simulated: each distinct message is printed once (a
/// failure repeats every frame), the frames are counted.
#[derive(Default)]
struct GarmentFailures {
    last: String,
    frames: usize,
}

impl GarmentFailures {
    /// Counts frame `index`'s failure; the line to print when its message is not the last one's.
    fn note(&mut self, index: u64, error: &str) -> Option<String> {
        self.frames += 1;
        (error != self.last).then(|| {
            self.last = error.to_owned();
            format!("frame {index}: garment: {error}")
        })
    }
}

fn status_name(status: &ClothStatus) -> &'static str {
    match status {
        ClothStatus::Worn { .. } => "worn",
        ClothStatus::Sizing { .. } => "measuring",
        ClothStatus::NoPerson => "hidden",
        ClothStatus::Off => "off",
    }
}

/// Writes a PNG to a temporary name and renames it.
pub fn write_png(image: &RgbImage, path: &Path) -> anyhow::Result<()> {
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new_with_quality(
        &mut bytes,
        image::codecs::png::CompressionType::Fast,
        image::codecs::png::FilterType::Sub,
    )
    .write_image(
        image.as_raw(),
        image.width(),
        image.height(),
        image::ExtendedColorType::Rgb8,
    )
    .with_context(|| format!("cannot encode {}", path.display()))?;
    suitcap::io::write_atomic(path, &bytes)
        .with_context(|| format!("cannot write {}", path.display()))
}

use image::ImageEncoder;

/// `suitcap run`: the whole pipeline on a recorded input, its take on `clock`.
pub fn run(
    input: &str,
    suit_dir: &Path,
    out: &Path,
    camera: Option<&PathBuf>,
    clock: TakeClock,
    garment: &GarmentArgs,
    pose: &PoseArgs,
) -> anyhow::Result<()> {
    if !Path::new(input).exists() {
        anyhow::bail!("{input}: no such frame directory or .y4m file");
    }
    let calibrated = find_camera(input, suit_dir, camera)?;
    let pose_stage = pose_stage(suit_dir, pose, Some(GLITCH_WINDOW_S))?;
    let mode = if garment.live_cloth {
        SimulationMode::Live
    } else {
        SimulationMode::Quality
    };
    let cloth = cloth_stage(
        garment,
        &pose_stage.pipeline.regressor.skeleton.skeleton,
        mode,
        InputKind::Recorded,
    )?;
    let render = render_stage(&pose_stage.pipeline);
    // Open once here to check the size and learn the rate; the capture thread opens its own.
    let probe = open_source(input, &SourceOptions::default())?;
    let size = probe.size();
    let camera = camera_or_webcam(input, suit_dir, calibrated, size);
    if size != (camera.intrinsics.width, camera.intrinsics.height) {
        bail!(
            "{input} is {}x{}, but the camera is calibrated for {}x{}",
            size.0,
            size.1,
            camera.intrinsics.width,
            camera.intrinsics.height
        );
    }
    let fps = probe.frame_rate().unwrap_or(30.0);
    let total = count_frames(input);
    drop(probe);
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let template = pose_stage.pipeline.regressor.skeleton.skeleton.clone();
    let mut take = Take::new(&template, fps, clock, out.join("take.bvh"), Some(0))?
        .repairing_glitches(!pose.no_smoothing)
        .smoothing_backwards(pose_stage.filter.clone());
    let mut outputs = RunOutputs::new(out, fps)?;
    let controls = Controls::new(parse_overlays(&garment.overlays)?);
    stop_on_signals(&controls);
    let bar = match total {
        Some(n) => indicatif::ProgressBar::new(n),
        None => indicatif::ProgressBar::new_spinner(),
    };
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} frames {per_sec} {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let mut timings = TimingLog::default();
    let (mut nobody, mut failure) = (0usize, None::<anyhow::Error>);
    let mut body_size = None;
    let mut garment_failures = GarmentFailures::default();
    let input_owned = input.to_owned();
    let summary = runner::run(
        move || {
            open_source(&input_owned, &SourceOptions::default()).map(|s| s as Box<dyn FrameSource>)
        },
        InputKind::Recorded,
        camera,
        pose_stage,
        cloth,
        render,
        Arc::clone(&controls),
        Vec::new,
        |output| {
            nobody += (!output.pose.person) as usize;
            timings.push(output.times);
            if let ClothStatus::Worn { size } = output.cloth.status {
                body_size.get_or_insert(size);
            }
            if let Some(line) = output
                .cloth_error
                .as_deref()
                .and_then(|e| garment_failures.note(output.index, e))
            {
                // To stderr around the bar: `ProgressBar::println` prints nothing when the bar
                // is hidden (output not a terminal), and the error would be lost.
                bar.suspend(|| eprintln!("{line}"));
            }
            let result = take
                .push(output.index, output.timestamp_s, &output.pose.frame)
                .and_then(|bvh_frame| {
                    if output.pose.root_glitch_filled {
                        take.note_glitch_filled(bvh_frame);
                    }
                    if !output.pose.person {
                        take.note_nobody(bvh_frame);
                    }
                    outputs.add(&output, bvh_frame)
                });
            bar.inc(1);
            match result {
                Ok(()) => true,
                Err(e) => {
                    failure = Some(e.context(format!("frame {}", output.index)));
                    false
                }
            }
        },
    );
    bar.finish_and_clear();
    // Corrupt frames at the end of a recording read to its end hold the last pose too.
    if failure.is_none() && summary.source_error.is_none() && !summary.stopped_by_user {
        take.hold_to_end(summary.input_frames)?;
        outputs.skipped_until(summary.input_frames);
    }
    let bvh = take.write()?;
    outputs.finish(out)?;
    report(&summary, &take, nobody, &timings);
    if let Some(size) = body_size {
        println!(
            "body size measured on the silhouettes of {} frames: {:.0} cm tall ({:.3} × the suit's skeleton), girth {:.2} (1 = the base figure's build); the garment is cut for it",
            size.frames,
            size.height_cm(&template),
            size.height_scale,
            size.girth
        );
        if let Some(truth) = Path::new(input)
            .is_dir()
            .then(|| generator_truth(Path::new(input), None))
            .flatten()
        {
            println!("  {truth}");
        }
    }
    if garment_failures.frames > 0 {
        eprintln!(
            "no garment on {} frames: it could not be simulated (the messages above; frames.csv marks them \"off\")",
            garment_failures.frames
        );
    }
    println!(
        "composited frames: {}/frames/  preview: {}/preview.gif  per-frame table: {}/frames.csv",
        out.display(),
        out.display(),
        out.display()
    );
    finish(summary, failure, &bvh)
}

fn count_frames(input: &str) -> Option<u64> {
    let path = Path::new(input);
    path.is_dir()
        .then(|| suitcap::source::directory::list_frame_files(path).ok())
        .flatten()
        .map(|files| files.len() as u64)
}

fn report(summary: &RunSummary, take: &Take, nobody: usize, timings: &TimingLog) {
    let filled = match take.held() {
        0 => String::new(),
        n => format!(
            "; {} filled in between the poses around them",
            counted(n, "BVH frame", "BVH frames")
        ),
    };
    println!(
        "{} → {} ({} with nobody: previous pose kept, garment hidden, flagged in frames.csv); {} skipped; {} dropped{filled}{}; {:.1} s ({:.1} frames/s)",
        counted(take.frames(), "frame", "frames"),
        take.path.display(),
        counted(nobody, "frame", "frames"),
        counted(summary.skipped.len(), "corrupt frame", "corrupt frames"),
        counted(summary.dropped as usize, "camera frame", "camera frames"),
        take.glitches_clause(),
        summary.seconds,
        summary.frames as f64 / summary.seconds.max(1e-9)
    );
    for s in &summary.skipped {
        println!("  skipped: {s}");
    }
    print!("{}", timings.summary());
}

/// The exit status: an error for a failed source or output, after everything recorded was written.
fn finish(summary: RunSummary, failure: Option<anyhow::Error>, bvh: &Path) -> anyhow::Result<()> {
    if let Some(e) = failure {
        return Err(e.context(format!(
            "stopped early; the frames before were written ({})",
            bvh.display()
        )));
    }
    if let Some(e) = summary.source_error {
        bail!(
            "the input failed: {e}; the {} frames before it are in {}",
            summary.frames,
            bvh.display()
        );
    }
    if summary.stopped_by_user {
        println!("stopped by signal; the take is complete up to the last processed frame");
    }
    Ok(())
}

/// `suitcap demo`: the bundled footage through the whole pipeline, compared with its ground truth.
pub fn demo(suit_dir: &Path, out: &Path) -> anyhow::Result<()> {
    let footage = suit_dir.join("demo/640x480");
    let frames = footage.join("frames");
    if !frames.is_dir() {
        bail!(
            "{} has no bundled demo footage ({} is missing)",
            suit_dir.display(),
            frames.display()
        );
    }
    let garment = GarmentArgs {
        garment: "tshirt".to_owned(),
        material: "medium".to_owned(),
        live_cloth: false,
        overlays: Vec::new(),
    };
    let pose = PoseArgs {
        no_smoothing: false,
        no_limits: false,
    };
    let input = frames.to_string_lossy().into_owned();
    let camera = footage.join("camera.toml");
    run(
        &input,
        suit_dir,
        out,
        Some(&camera),
        TakeClock::InputFrames,
        &garment,
        &pose,
    )?;
    let truth = Motion::load(&footage.join("motion.bvh"))?;
    let take = Motion::load(&out.join("take.bvh"))?;
    let suit = suitcap::suit::SuitDefinition::load_dir(suit_dir)?;
    let layout = suitcap::pose::PoseLayout::new(&suit.skeleton, &truth.skeleton)?;
    let mut errors = suitcap::pose::eval::JointErrors::new(suit.skeleton.joint_names());
    for k in 0..truth.frame_count().min(take.frame_count()) {
        errors.add(&layout, truth.frame(k), take.frame(k));
    }
    println!(
        "against the ground truth of the bundled clip (a motion the suit was not trained on): mean joint angle error {:.1}° (Euler), {:.1}° (geodesic) over {} frames",
        errors.mean_euler(),
        errors.mean_geodesic(),
        errors.frames
    );
    Ok(())
}

/// The generator's subject, when `frames_dir` is the `frames/` of a generated dataset (its
/// `manifest.toml` beside it): the nominal height, the standing height of the rendered figure
/// with its limb ratios (from the dataset's `motion.bvh`, or `motion` when given) and the girth,
/// which body-size measurements are checked against.
fn generator_truth(frames_dir: &Path, motion: Option<&Motion>) -> Option<String> {
    let dataset = frames_dir.parent()?;
    let subject = suitcap::dataset::Manifest::load(&dataset.join("manifest.toml"))
        .ok()?
        .subject?;
    let loaded;
    let motion = match motion {
        Some(motion) => motion,
        None => {
            loaded = Motion::load(&dataset.join("motion.bvh")).ok()?;
            &loaded
        }
    };
    Some(format!(
        "ground truth (generator's subject {}, nominal height {:.1} cm): standing {:.1} cm with its limb ratios (the motion's own skeleton, scale 1.000), girth {:.2}",
        subject.name,
        subject.height_cm,
        suitcap::body_size::skeleton_height_cm(&motion.skeleton),
        subject.girth
    ))
}

/// `suitcap drape`: a garment simulated on a given motion, composited into the given frames.
#[allow(clippy::too_many_arguments)]
pub fn drape(
    motion_path: &Path,
    camera_path: &Path,
    frames_dir: &Path,
    masks: Option<&PathBuf>,
    out: &Path,
    garment: &GarmentArgs,
) -> anyhow::Result<()> {
    use suitcap::body_size::{BodySize, BodySizeEstimator, Silhouette};
    use suitcap::mask::Mask;
    super::ensure_mask_dir("--masks", masks)?;
    // The options first, so a mistyped garment, fabric or overlay is named before any work.
    if garment.garment.eq_ignore_ascii_case("none") {
        bail!("--garment none: drape needs a garment");
    }
    let choice = garment_choice(&garment.garment)?;
    let fabric = material(&garment.material)?;
    let overlays = parse_overlays(&garment.overlays)?;
    let motion = Motion::load(motion_path)?;
    let camera = Camera::load(camera_path)?;
    let mut source = suitcap::source::directory::DirectorySource::open(frames_dir, 30.0)?;
    let template = motion.skeleton.clone();
    let mode = if garment.live_cloth {
        SimulationMode::Live
    } else {
        SimulationMode::Quality
    };
    // Body size from the silhouettes: the given masks, else the masks/ beside the frames.
    let masks_dir = masks.cloned().or_else(|| {
        let beside = frames_dir.parent()?.join("masks");
        beside.is_dir().then_some(beside)
    });
    let size = match &masks_dir {
        Some(dir) => {
            let body = suitcap::body_size::template_body(&template)?;
            let mut estimator = BodySizeEstimator::new();
            let count = motion.frame_count();
            for k in (0..count).step_by((count / 40).max(1)) {
                let path = dir.join(format!("{k:06}.png"));
                let Ok(grey) = image::open(&path).map(|i| i.to_luma8()) else {
                    continue;
                };
                let calibrated = (camera.intrinsics.width, camera.intrinsics.height);
                super::ensure_mask_size(&path, grey.dimensions(), calibrated, "mask")?;
                estimator.add_frame(
                    Silhouette::whole(&Mask::from_gray(&grey)),
                    &body,
                    &template,
                    motion.frame(k),
                    &camera,
                );
            }
            let size = estimator.estimate();
            if size.frames == 0 {
                eprintln!(
                    "warning: no mask in {} is named like a frame of the motion (000000.png, …): the garment is sized for the motion's skeleton at girth 1",
                    dir.display()
                );
            }
            println!(
                "body size from {} silhouettes in {}: height {:.1} cm (×{:.3} the motion's skeleton), girth {:.2}",
                size.frames,
                dir.display(),
                size.height_cm(&template),
                size.height_scale,
                size.girth
            );
            size
        }
        None => {
            println!("no masks: the garment is sized for the motion's skeleton at girth 1");
            BodySize::TEMPLATE
        }
    };
    if let Some(truth) = generator_truth(frames_dir, Some(&motion)) {
        println!("  {truth}");
    }
    let mut options = ClothOptions::new(choice, mode);
    options.material = fabric;
    options.known_size = Some(size);
    options.check_tunnelling = true;
    let mut stage = ClothStage::new(&template, options)?;
    let mut render = RenderStage::new(RenderSettings::default(), Vec::new());
    let out_frames = out.join("frames");
    std::fs::create_dir_all(&out_frames)
        .with_context(|| format!("cannot create {}", out_frames.display()))?;
    let fps = motion.frame_rate();
    let mut preview = GifPreview::create(
        &out.join("preview.gif"),
        PreviewSettings {
            fps: fps as f32,
            ..PreviewSettings::default()
        },
    )?;
    let empty = Mask::empty(camera.intrinsics.width, camera.intrinsics.height);
    let mut quality = Vec::new();
    let (mut cloth_ms, mut render_ms, mut skipped) = (Vec::new(), Vec::new(), Vec::new());
    let mut vertices = 0;
    let bar = indicatif::ProgressBar::new(motion.frame_count() as u64);
    for k in 0..motion.frame_count() {
        let mut image = match source.next_frame() {
            Ok(Some(frame)) => frame.image,
            Ok(None) => break,
            Err(e) => {
                skipped.push(e.to_string());
                continue;
            }
        };
        let silhouette = Silhouette::whole(&empty);
        let cloth = stage.advance(motion.frame(k), k as f64 / fps, true, silhouette, &camera)?;
        vertices = cloth.positions.len();
        if let Some(q) = cloth.quality {
            quality.push((k, q));
        }
        cloth_ms.push(cloth.milliseconds);
        let pose =
            suitcap::tryon::PoseOverlay::new(None, Vec::new(), &template, motion.frame(k), &camera);
        // The true body: it hides the garment wherever it is in front.
        let (r, c) = render.draw(&mut image, &camera, &cloth, None, &pose, overlays, &[], &[])?;
        render_ms.push(r + c);
        write_png(&image, &out_frames.join(format!("{k:06}.png")))?;
        preview.push(&image)?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    preview.finish()?;
    // The largest value of a quality figure over the frames, and the frame it was in.
    let worst = |f: fn(&suitcap::cloth::solver::FrameQuality) -> f32| {
        quality
            .iter()
            .map(|(k, q)| (f(q), *k))
            .fold((0.0f32, 0), |a, b| if b.0 > a.0 { b } else { a })
    };
    let mut p95s: Vec<f32> = quality.iter().map(|(_, q)| q.strain_p95).collect();
    p95s.sort_by(f32::total_cmp);
    let (p95_worst, p95_frame) = worst(|q| q.strain_p95);
    let (strain_max, strain_frame) = worst(|q| q.strain_max);
    let (depth_max, depth_frame) = worst(|q| q.penetration_cm);
    // Vertices that tunnelled through the body: while the garment was put on (in the first
    // frame's figure), and in the frames after it.
    let tunnelled = |frames: &[(usize, suitcap::cloth::solver::FrameQuality)]| {
        frames
            .iter()
            .filter_map(|(k, q)| Some((*k, q.tunnelled? as usize)))
            .filter(|&(_, n)| n > 0)
            .collect::<Vec<_>>()
    };
    let (dressing, moving) = quality.split_at(quality.len().min(1));
    let (dressing, moving) = (tunnelled(dressing), tunnelled(moving));
    println!(
        "{} of {} ({} vertices, {:?} mode, {}) → {}/frames/ and {}/preview.gif; {} skipped",
        counted(quality.len(), "frame", "frames"),
        stage.garment().name(),
        vertices,
        mode,
        garment.material,
        out.display(),
        out.display(),
        counted(skipped.len(), "unreadable frame", "unreadable frames")
    );
    for s in &skipped {
        println!("  skipped: {s}");
    }
    println!(
        "quality: edge strain 95th percentile median {:.2} % (worst frame {:.2} %, frame {}), maximum {:.2} % (frame {}); deepest vertex inside a capsule at a frame's end {:.2} mm (frame {})",
        p95s.get(p95s.len() / 2).copied().unwrap_or(0.0) * 100.0,
        p95_worst * 100.0,
        p95_frame,
        strain_max * 100.0,
        strain_frame,
        depth_max * 10.0,
        depth_frame
    );
    println!(
        "tunnelling: {} vertices passed through the body in {} frames{}; {} while the garment was put on",
        moving.iter().map(|&(_, n)| n).sum::<usize>(),
        moving.len(),
        match moving.iter().max_by_key(|&&(_, n)| n) {
            Some((k, n)) => format!(" (most in frame {k}: {n})"),
            None => String::new(),
        },
        dressing.iter().map(|&(_, n)| n).sum::<usize>()
    );
    println!(
        "time: cloth {:.2} ms, render + composite {:.2} ms per frame (medians)",
        super::median(&cloth_ms),
        super::median(&render_ms)
    );
    Ok(())
}

/// `suitcap live`: the camera with the garment, in a window.
#[allow(clippy::too_many_arguments)]
pub fn live(
    device: &str,
    suit_dir: &Path,
    camera: Option<&PathBuf>,
    size: Option<(u32, u32)>,
    fps: Option<f64>,
    record: Option<&PathBuf>,
    garment: &GarmentArgs,
    pose: &PoseArgs,
) -> anyhow::Result<()> {
    use minifb::{Key, KeyRepeat, Window, WindowOptions};
    // A calibration given, beside a recorded input, or in the suit; else a typical webcam.
    let calibrated = find_camera(device, suit_dir, camera)?;
    let options = SourceOptions {
        size: size.or(calibrated.map(|c| (c.intrinsics.width, c.intrinsics.height))),
        fps,
        ..SourceOptions::default()
    };
    let probe = open_source(device, &options)?;
    let actual = probe.size();
    let rate = probe.frame_rate().unwrap_or(30.0);
    let described = probe.describe();
    drop(probe);
    let camera = camera_or_webcam(device, suit_dir, calibrated, actual);
    if actual != (camera.intrinsics.width, camera.intrinsics.height) {
        bail!(
            "{device} gives {}x{} frames, but the camera calibration is for {}x{}: pass --camera with a calibration at the camera's size",
            actual.0,
            actual.1,
            camera.intrinsics.width,
            camera.intrinsics.height
        );
    }
    let pose_stage = pose_stage(suit_dir, pose, None)?;
    let cloth = cloth_stage(
        garment,
        &pose_stage.pipeline.regressor.skeleton.skeleton,
        SimulationMode::Live,
        InputKind::Live,
    )?;
    let render = render_stage(&pose_stage.pipeline);
    let mut window = Window::new(
        &format!("suitcap live — {described}"),
        actual.0 as usize,
        actual.1 as usize,
        WindowOptions::default(),
    )
    .map_err(|e| {
        anyhow::anyhow!(
            "cannot open a preview window ({e}); `live` needs a desktop session (DISPLAY), `suitcap run` works without one"
        )
    })?;
    let overlays = parse_overlays(&garment.overlays)?;
    let controls = Controls::new(overlays);
    stop_on_signals(&controls);
    // Recording: --record starts at once; R starts and stops; every stop writes its take.
    let base = record.cloned().unwrap_or_else(|| PathBuf::from("take.bvh"));
    let mut takes_written: Vec<(PathBuf, usize)> = Vec::new();
    let template_pipeline_skeleton = pose_stage.pipeline.regressor.skeleton.skeleton.clone();
    // Each take is smoothed back on writing with the filter its poses were smoothed with.
    let take_filter = pose_stage.filter.clone();
    let mut recording: Option<Take> = match record {
        Some(path) => Some(
            Take::new(
                &template_pipeline_skeleton,
                rate,
                TakeClock::CaptureTime,
                path.clone(),
                Some(0),
            )?
            .repairing_glitches(!pose.no_smoothing)
            .smoothing_backwards(take_filter.clone()),
        ),
        None => None,
    };
    let recording_flag = Arc::new(std::sync::atomic::AtomicBool::new(recording.is_some()));
    let banner_flag = Arc::clone(&recording_flag);
    let mut timings = TimingLog::default();
    let mut buffer: Vec<u32> = Vec::new();
    let mut garment_choice = GarmentChoice::parse(&garment.garment).unwrap_or(
        GarmentChoice::Procedural(suitcap::cloth::garment::GarmentKind::TShirt),
    );
    let mut failure: Option<anyhow::Error> = None;
    let mut garment_failures = GarmentFailures::default();
    let device_owned = device.to_owned();
    println!("keys: G garment · M mask · K markers · S skeleton · T timings · R record on/off · Esc/Q quit");
    let summary = runner::run(
        move || {
            // A recorded file stands in for a camera: deliver it at its own rate.
            let recorded = Path::new(&device_owned).exists() && !device_owned.starts_with("/dev/");
            open_source(&device_owned, &options).map(|s| {
                if recorded {
                    Box::new(suitcap::source::memory::Paced::new(s)) as Box<dyn FrameSource>
                } else {
                    s as Box<dyn FrameSource>
                }
            })
        },
        InputKind::Live,
        camera,
        pose_stage,
        cloth,
        render,
        Arc::clone(&controls),
        move || {
            if banner_flag.load(Ordering::Relaxed) {
                vec!["REC".to_owned()]
            } else {
                Vec::new()
            }
        },
        |output| {
            timings.push(output.times);
            if let Some(line) = output
                .cloth_error
                .as_deref()
                .and_then(|e| garment_failures.note(output.index, e))
            {
                eprintln!("{line}");
            }
            if let Some(take) = &mut recording {
                match take.push(output.index, output.timestamp_s, &output.pose.frame) {
                    Ok(slot) if !output.pose.person => take.note_nobody(slot),
                    Ok(_) => {}
                    Err(e) => {
                        failure = Some(e);
                        return false;
                    }
                }
            }
            buffer.clear();
            buffer.extend(output.image.pixels().map(|p| {
                let [r, g, b] = p.0;
                (r as u32) << 16 | (g as u32) << 8 | b as u32
            }));
            let (w, h) = output.image.dimensions();
            if window
                .update_with_buffer(&buffer, w as usize, h as usize)
                .is_err()
                || !window.is_open()
            {
                return false;
            }
            for key in window.get_keys_pressed(KeyRepeat::No) {
                let mut o = controls.overlays();
                match key {
                    Key::Escape | Key::Q => return false,
                    Key::M => o.mask = !o.mask,
                    Key::K => o.markers = !o.markers,
                    Key::S => o.skeleton = !o.skeleton,
                    Key::T => o.timings = !o.timings,
                    Key::G => {
                        garment_choice = garment_choice.next();
                        controls.switch_garment(garment_choice.clone());
                    }
                    Key::R => match recording.take() {
                        Some(mut take) => match take.write() {
                            Ok(path) => {
                                println!("{}", take.recorded_line(&path));
                                takes_written.push((path, take.frames()));
                            }
                            Err(e) => {
                                failure = Some(e);
                                return false;
                            }
                        },
                        None => {
                            let path = numbered(&base, takes_written.len());
                            match Take::new(
                                &template_pipeline_skeleton,
                                rate,
                                TakeClock::CaptureTime,
                                path,
                                None,
                            ) {
                                Ok(take) => {
                                    recording = Some(
                                        take.repairing_glitches(!pose.no_smoothing)
                                            .smoothing_backwards(take_filter.clone()),
                                    )
                                }
                                Err(e) => eprintln!(
                                    "cannot start recording: {}",
                                    suitcap::io::error_line(e.as_ref())
                                ),
                            }
                        }
                    },
                    _ => {}
                }
                recording_flag.store(recording.is_some(), Ordering::Relaxed);
                controls.set_overlays(o);
            }
            true
        },
    );
    if let Some(mut take) = recording.take() {
        // Frames at the end of a recorded input that the pipeline dropped hold the last pose too.
        if summary.source_error.is_none() && !summary.stopped_by_user {
            take.hold_to_end(summary.input_frames)?;
        }
        let path = take.write()?;
        println!("{}", take.recorded_line(&path));
    }
    println!(
        "{} shown, {} dropped (the pipeline was behind), {} skipped",
        counted(summary.frames as usize, "frame", "frames"),
        counted(summary.dropped as usize, "camera frame", "camera frames"),
        counted(summary.skipped.len(), "corrupt frame", "corrupt frames")
    );
    print!("{}", timings.summary());
    if let Some(e) = failure {
        return Err(e);
    }
    if let Some(e) = summary.source_error {
        bail!("the camera failed: {e}; everything recorded before it was written");
    }
    Ok(())
}

/// An uncalibrated webcam: 60° across, level, 120 cm above the mocap floor, 350 cm from the origin.
fn default_webcam((width, height): (u32, u32)) -> Camera {
    use glam::Vec3;
    Camera::look_at(
        suitcap::camera::Intrinsics::from_fov(width, height, 60.0),
        Vec3::new(0.0, 120.0, 350.0),
        Vec3::new(0.0, 120.0, 0.0),
        Vec3::Y,
    )
}

/// `take.bvh`, then `take-2.bvh`, `take-3.bvh`, …
fn numbered(base: &Path, index: usize) -> PathBuf {
    if index == 0 {
        return base.to_owned();
    }
    let stem = base
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    base.with_file_name(format!("{stem}-{}.bvh", index + 1))
}

/// Frames of a directory decoded into memory (for the benchmark).
pub fn load_frames(dir: &Path) -> anyhow::Result<Vec<RgbImage>> {
    let mut source = suitcap::source::directory::DirectorySource::open(dir, 30.0)?;
    let mut frames = Vec::new();
    while let Some(frame) = source.next_frame()? {
        frames.push(frame.image);
    }
    Ok(frames)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_repeated_garment_failure_is_printed_once_and_every_frame_counted() {
        let mut failures = GarmentFailures::default();
        let a = "garment 'tshirt': no armhole found on the rShldr side";
        assert_eq!(
            failures.note(9, a).as_deref(),
            Some("frame 9: garment: garment 'tshirt': no armhole found on the rShldr side")
        );
        assert_eq!(failures.note(10, a), None);
        assert!(failures.note(11, "other").is_some());
        assert!(failures.note(12, a).is_some());
        assert_eq!(failures.frames, 4);
    }

    #[test]
    fn a_calibration_is_found_beside_the_input_and_a_broken_one_is_an_error() {
        let tmp = tempfile::tempdir().unwrap();
        let (input, suit) = (tmp.path().join("frames"), tmp.path().join("suit"));
        std::fs::create_dir_all(&input).unwrap();
        std::fs::create_dir_all(&suit).unwrap();
        let name = input.to_str().unwrap();
        // None anywhere: no calibration, so `run` and `live` assume a webcam.
        assert!(find_camera(name, &suit, None).unwrap().is_none());
        let demo =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("suits/default/demo/640x480/camera.toml");
        std::fs::copy(&demo, input.join("camera.toml")).unwrap();
        let found = find_camera(name, &suit, None).unwrap().unwrap();
        assert_eq!(
            (found.intrinsics.width, found.intrinsics.height),
            (640, 480)
        );
        assert_eq!(
            camera_or_webcam(name, &suit, None, (320, 240))
                .intrinsics
                .width,
            320
        );
        // A broken file beside the input is not passed over for the suit's or a webcam.
        std::fs::write(input.join("camera.toml"), "garbage").unwrap();
        std::fs::copy(&demo, suit.join("camera.toml")).unwrap();
        let error = find_camera(name, &suit, None).unwrap_err().to_string();
        assert!(error.contains("camera.toml"), "{error}");
    }

    /// The take's frames as their first channel (each test frame is `[k; 6]`).
    fn firsts(take: &Take) -> Vec<f32> {
        take.motion.frames().map(|f| f[0]).collect()
    }

    /// One joint, the hip, with three position and three rotation channels.
    fn hip() -> suitcap::skeleton::Skeleton {
        use suitcap::skeleton::{Channel, Joint, Skeleton};
        Skeleton::new(vec![Joint {
            name: "hip".into(),
            parent: None,
            offset: glam::Vec3::ZERO,
            channels: vec![
                Channel::Xposition,
                Channel::Yposition,
                Channel::Zposition,
                Channel::Zrotation,
                Channel::Xrotation,
                Channel::Yrotation,
            ],
            first_channel: 0,
            end_site: Some(glam::Vec3::Y),
        }])
        .unwrap()
    }

    #[test]
    fn a_recordings_take_is_smoothed_back_and_its_filled_frames_filled_in_again() {
        // The hip turning steadily at 3° a frame (its Z rotation, channel 3), smoothed forwards
        // as `run` smooths its poses; input frame 20 never arrived.
        let skeleton = hip();
        let mut forward = PoseFilter::new(&skeleton, Some(SmoothingParams::default()), None);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("take.bvh");
        let mut take = Take::new(&skeleton, 30.0, TakeClock::InputFrames, path, Some(0))
            .unwrap()
            .smoothing_backwards(Some(forward.clone()));
        let mut pushed = Vec::new();
        for k in (0..40u64).filter(|&k| k != 20) {
            let mut frame = [0.0, 0.0, 0.0, 3.0 * k as f32, 0.0, 0.0];
            forward.apply(k as f64 / 30.0, &mut frame);
            pushed.push(frame[3]);
            take.push(k, k as f64 / 30.0, &frame).unwrap();
        }
        let written: Vec<f32> = Motion::load(&take.write().unwrap())
            .unwrap()
            .frames()
            .map(|f| f[3])
            .collect();
        // Frame 10: the forward pass lags behind the turn, the written take does not.
        let lag_forward = 30.0 - pushed[10];
        assert!(lag_forward > 0.5, "{lag_forward}");
        assert!(
            (written[10] - 30.0).abs() < lag_forward / 4.0,
            "{}",
            written[10]
        );
        // Frame 20 lies half-way between the smoothed frames around it (six decimals in the file).
        assert!((written[20] - (written[19] + written[21]) / 2.0).abs() < 1e-3);
    }

    #[test]
    fn a_take_fills_in_frame_times_without_a_pose() {
        let skeleton = hip();
        let frame = |k: u64| [k as f32; 6];
        let take_on = |clock, first_index| {
            Take::new(
                &skeleton,
                30.0,
                clock,
                PathBuf::from("take.bvh"),
                first_index,
            )
            .unwrap()
        };
        // A recording: input frames 0 and 3 never arrived, nor 6 and 7 at the end.
        let mut take = take_on(TakeClock::InputFrames, Some(0));
        let at_rate = |k: u64| k as f64 / 30.0;
        for k in [1, 2, 4, 5] {
            take.push(k, at_rate(k), &frame(k)).unwrap();
        }
        take.hold_to_end(8).unwrap();
        // Frame 0 takes the first pose; 3 lies between 2 and 4; 6 and 7 hold the last.
        assert_eq!(firsts(&take), [1.0, 1.0, 2.0, 3.0, 4.0, 5.0, 5.0, 5.0]);
        assert_eq!((take.frames(), take.held()), (8, 4));
        // A live take starts at the first frame pushed; frames 12 and 13 were dropped. The root's
        // Z rotation (channel 3) goes from 11 to 14 the short way; so it does from 170° to −170°.
        let mut live = take_on(TakeClock::CaptureTime, None);
        for k in [10, 11, 14] {
            live.push(k, at_rate(k), &frame(k)).unwrap();
        }
        assert_eq!(firsts(&live), [10.0, 11.0, 12.0, 13.0, 14.0]);
        assert_eq!(live.held(), 2);
        let mut turn = take_on(TakeClock::InputFrames, Some(0));
        turn.push(0, 0.0, &[0.0, 0.0, 0.0, 170.0, 0.0, 0.0])
            .unwrap();
        turn.push(2, at_rate(2), &[0.0, 0.0, 0.0, -170.0, 0.0, 0.0])
            .unwrap();
        let middle = turn.motion.frame(1)[3];
        assert!((middle.abs() - 180.0).abs() < 1e-4, "{middle}");
        // A camera that dropped the frame at 100 ms: the frames after it are numbered densely,
        // their timestamps are not. On the camera's clock the frame after the gap goes to its
        // time's place, and the hold over a trailing corrupt frame 4 follows it; on the input
        // frames' clock (`run`) each input frame has its BVH frame.
        let times = [(0, 0.0), (1, 34.0), (2, 66.0), (3, 134.0)];
        let mut camera = take_on(TakeClock::CaptureTime, Some(0));
        let mut files = take_on(TakeClock::InputFrames, Some(0));
        for (k, ms) in times {
            camera.push(k, ms / 1000.0, &frame(k)).unwrap();
            files.push(k, ms / 1000.0, &frame(k)).unwrap();
        }
        camera.hold_to_end(5).unwrap();
        files.hold_to_end(5).unwrap();
        assert_eq!(firsts(&camera), [0.0, 1.0, 2.0, 2.5, 3.0, 3.0]);
        assert_eq!(camera.held(), 2);
        assert_eq!(firsts(&files), [0.0, 1.0, 2.0, 3.0, 3.0]);
        assert_eq!(files.held(), 1);
        // A camera a little faster than its rate: no pose overwrites another, none is doubled.
        let mut fast = take_on(TakeClock::CaptureTime, None);
        for k in 0..4 {
            fast.push(k, k as f64 * 0.031, &frame(k)).unwrap();
        }
        assert_eq!((firsts(&fast), fast.held()), (vec![0.0, 1.0, 2.0, 3.0], 0));
        // Nothing to hold before a first pose.
        let mut empty = take_on(TakeClock::InputFrames, Some(0));
        empty.hold_to_end(5).unwrap();
        assert_eq!(empty.frames(), 0);
        // The whole body spun 90° for one frame (the hip's Z rotation is channel 3): the file
        // gets that frame filled in between its neighbours, the take keeps what was estimated.
        let dir = tempfile::tempdir().unwrap();
        let recording_to = |name: &str| {
            Take::new(
                &skeleton,
                30.0,
                TakeClock::InputFrames,
                dir.path().join(name),
                Some(0),
            )
            .unwrap()
        };
        // The hip's Z rotation (channel 3) of every frame of a written take.
        let written_z = |path: PathBuf| -> Vec<f32> {
            Motion::load(&path)
                .unwrap()
                .frames()
                .map(|f| f[3])
                .collect()
        };
        let mut spun = recording_to("take.bvh");
        for (k, z) in [0.0, 2.0, 92.0, 6.0].into_iter().enumerate() {
            spun.push(k as u64, at_rate(k as u64), &[0.0, 0.0, 0.0, z, 0.0, 0.0])
                .unwrap();
        }
        assert_eq!(spun.glitches_clause(), "");
        let z = written_z(spun.write().unwrap());
        assert_eq!(z, [0.0, 2.0, 4.0, 6.0]);
        assert_eq!(spun.motion.frame(2)[3], 92.0);
        assert!(
            spun.glitches_clause()
                .contains("1 BVH frame of 1 root glitch"),
            "{}",
            spun.glitches_clause()
        );
        // Switched off (--no-smoothing), the file keeps the spin.
        let mut raw = spun.repairing_glitches(false);
        let z = written_z(raw.write().unwrap());
        assert_eq!(
            (z, raw.glitches_clause()),
            (vec![0.0, 2.0, 92.0, 6.0], String::new())
        );
        // Poses that came filled in already (the runner's repair of recorded input) count with
        // the frames the write fills in: two glitches, three frames.
        let mut before = recording_to("before.bvh");
        for (k, z) in [0.0, 1.0, 2.0, 3.0, 93.0, 5.0].into_iter().enumerate() {
            let slot = before
                .push(k as u64, at_rate(k as u64), &[0.0, 0.0, 0.0, z, 0.0, 0.0])
                .unwrap();
            if (1..3).contains(&k) {
                before.note_glitch_filled(slot);
            }
        }
        let z = written_z(before.write().unwrap());
        assert_eq!(z, [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]);
        assert_eq!(before.glitches, vec![1..3, 4..5]);
        assert!(before
            .glitches_clause()
            .contains("3 BVH frames of 2 root glitches"));
    }
}
