//! The whole pipeline on threads: capture → segment → pose → cloth → render + composite → the
//! caller's sink.
//!
//! Each stage runs on its own thread, joined to the next by a bounded [`StageQueue`]. Camera frames
//! enter a [`Full::DropOldest`] queue when the input is live, so a machine that falls behind drops
//! old frames (counted, and shown) instead of delaying the picture; recorded input waits instead and
//! loses nothing. Every later queue waits, so every pose that was estimated reaches the sink, which
//! records it. With [`PoseStage::root_glitch_window_s`] (recorded input) the pose thread holds the
//! frames of a root glitch back until it is over and passes them on filled in, in order; with
//! [`ClothOptions::dress_from_first_frame`](super::ClothOptions) (recorded input) the cloth thread
//! holds the frames from the first person on until the person is measured, so the garment is
//! worn from that first frame: the quality mode's 20 measuring frames when each one measures,
//! about 25 MB at 640×480 and 125 MB at 1440×1080, and at most [`ClothStage::sizing_hold`]
//! (twice that). The sink (on the calling thread, where a window must live) gets one [`Output`]
//! per processed frame, in order.
//!
//! Stopping: the sink returning `false`, or [`Controls::stop`] (set by Ctrl-C/SIGTERM), stops the
//! capture; the frames already in flight still drain through every stage, so the take ends cleanly.
//! A source that fails mid-stream (a camera unplugged) ends the stream the same way, and the error is
//! in the [`RunSummary`] for the caller to report after it has written what was recorded.

use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use std::sync::{Arc, Mutex};
use std::thread;
use std::time::Instant;

use image::RgbImage;

use crate::body_size::Silhouette;
use crate::camera::Camera;
use crate::pipeline::{PoseFrame, PosePipeline};
use crate::pose::smoothing::{PoseFilter, Released, RootGlitchRepair};
use crate::queue::{Full, StageQueue};
use crate::segment::{Segmentation, Segmenter};
use crate::skeleton::MAX_ROOT_TURN_DEG_PER_S;
use crate::source::{FrameSource, SourceError};

use super::{
    ClothFrame, ClothStage, ClothStatus, GarmentChoice, Overlays, PoseOverlay, RenderStage,
};

/// Settings the user changes while the pipeline runs (the live window's keys, signals).
#[derive(Debug, Default)]
pub struct Controls {
    /// Stop capturing; what is in flight still finishes.
    pub stop: AtomicBool,
    overlays: AtomicU8,
    garment: Mutex<Option<GarmentChoice>>,
}

impl Controls {
    pub fn new(overlays: Overlays) -> Arc<Controls> {
        let controls = Controls::default();
        controls.set_overlays(overlays);
        Arc::new(controls)
    }

    pub fn overlays(&self) -> Overlays {
        let bits = self.overlays.load(Ordering::Relaxed);
        Overlays {
            mask: bits & 1 != 0,
            markers: bits & 2 != 0,
            skeleton: bits & 4 != 0,
            timings: bits & 8 != 0,
        }
    }

    pub fn set_overlays(&self, o: Overlays) {
        let bits = o.mask as u8
            | (o.markers as u8) << 1
            | (o.skeleton as u8) << 2
            | (o.timings as u8) << 3;
        self.overlays.store(bits, Ordering::Relaxed);
    }

    /// Asks the cloth stage to switch garments at its next frame.
    pub fn switch_garment(&self, garment: GarmentChoice) {
        if let Ok(mut slot) = self.garment.lock() {
            *slot = Some(garment);
        }
    }

    fn take_garment(&self) -> Option<GarmentChoice> {
        self.garment.lock().ok().and_then(|mut slot| slot.take())
    }

    pub fn stopped(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

/// Milliseconds each stage spent on one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameTimes {
    pub segment: f64,
    pub describe: f64,
    pub regress: f64,
    pub cloth: f64,
    pub render: f64,
    pub composite: f64,
    /// From the frame leaving the source to the composited picture reaching the sink.
    pub latency: f64,
}

/// One finished frame.
pub struct Output {
    pub index: u64,
    pub timestamp_s: f64,
    /// The frame with the garment and overlays composited in.
    pub image: RgbImage,
    /// The pose, smoothed and limited as configured: BVH channels of the pose stage's skeleton.
    pub pose: PoseFrame,
    pub cloth: ClothFrame,
    pub times: FrameTimes,
    /// Camera frames dropped so far because the pipeline was behind.
    pub dropped: u64,
    /// The cloth stage's error for this frame (garment hidden), if any.
    pub cloth_error: Option<String>,
}

/// What a run did besides the frames.
#[derive(Clone, Debug, Default)]
pub struct RunSummary {
    pub frames: u64,
    pub dropped: u64,
    /// Corrupt input frames, each named.
    pub skipped: Vec<String>,
    /// Why the source stopped early (a camera unplugged, an unreadable file), if it did.
    pub source_error: Option<String>,
    /// Input frames the source went through: one past the last index it delivered or named in
    /// an error (delivered, dropped and skipped frames alike).
    pub input_frames: u64,
    pub stopped_by_user: bool,
    pub seconds: f64,
}

/// The pose stage: the suit's pose pipeline plus temporal smoothing and joint limits, and
/// optionally a segmenter of its own that [`run`] puts on a separate thread.
pub struct PoseStage {
    pub pipeline: PosePipeline,
    pub filter: Option<PoseFilter>,
    pub segmenter: Option<Segmenter>,
    /// With `Some(window)` (seconds), the poses go on through a [`RootGlitchRepair`] (the root
    /// turning faster than [`MAX_ROOT_TURN_DEG_PER_S`], coming back within the window): the frames
    /// of a glitch are held back until it is over and go on filled in between the poses around
    /// it, to the cloth, the overlays and the sink alike. It delays the frames after a glitch by up
    /// to the window, so it is for recorded input; `None` passes every pose on as it comes.
    pub root_glitch_window_s: Option<f64>,
}

impl PoseStage {
    fn process(
        &mut self,
        image: &RgbImage,
        given: Option<Silhouette>,
        camera: &Camera,
        time_s: f64,
    ) -> PoseFrame {
        let mut pose = self.pipeline.process(image, camera, given);
        if let Some(filter) = &mut self.filter {
            if pose.person {
                filter.apply(time_s, &mut pose.frame);
            } else {
                filter.reset();
            }
        }
        pose
    }
}

/// Whether the input is a live camera (drop old frames) or recorded (never drop).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InputKind {
    Live,
    Recorded,
}

struct Captured {
    index: u64,
    timestamp_s: f64,
    image: RgbImage,
    started: Instant,
}

struct Segmented {
    captured: Captured,
    /// `None` when the pose stage segments for itself.
    segmentation: Option<Segmentation>,
    segment_ms: f64,
}

struct Posed {
    captured: Captured,
    pose: PoseFrame,
}

struct Dressed {
    posed: Posed,
    cloth: ClothFrame,
    cloth_error: Option<String>,
}

/// Items a queue holds besides the one each stage is working on.
const QUEUE_FRAMES: usize = 1;

/// Runs the pipeline until the source ends, fails, or is stopped. `open_source` runs on the capture
/// thread (camera handles need not be `Send`); `banner` gives the sink-independent lines drawn on
/// every frame (e.g. "REC"); `sink` gets every output in order and returns `false` to stop.
#[allow(clippy::too_many_arguments)]
pub fn run(
    open_source: impl FnOnce() -> Result<Box<dyn FrameSource>, SourceError> + Send,
    input: InputKind,
    camera: Camera,
    mut pose_stage: PoseStage,
    mut cloth_stage: Option<ClothStage>,
    mut render_stage: RenderStage,
    controls: Arc<Controls>,
    banner: impl Fn() -> Vec<String> + Send,
    mut sink: impl FnMut(Output) -> bool,
) -> RunSummary {
    let policy = match input {
        InputKind::Live => Full::DropOldest,
        InputKind::Recorded => Full::Wait,
    };
    let captured: StageQueue<Captured> = StageQueue::new(QUEUE_FRAMES, policy);
    let segmented: StageQueue<Segmented> = StageQueue::new(QUEUE_FRAMES, Full::Wait);
    let posed: StageQueue<Posed> = StageQueue::new(QUEUE_FRAMES, Full::Wait);
    let dressed: StageQueue<Dressed> = StageQueue::new(QUEUE_FRAMES, Full::Wait);
    let finished: StageQueue<Output> = StageQueue::new(QUEUE_FRAMES, Full::Wait);
    let started = Instant::now();
    let mut summary = RunSummary::default();
    let skeleton = pose_stage.pipeline.regressor.skeleton.skeleton.clone();

    thread::scope(|scope| {
        let capture = {
            let (queue, controls) = (captured.clone(), Arc::clone(&controls));
            scope.spawn(move || capture_frames(open_source, &queue, &controls))
        };
        {
            // Segmentation on its own thread when the pose stage brought a segmenter.
            let (input, output) = (captured.clone(), segmented.clone());
            let mut segmenter = pose_stage.segmenter.take();
            scope.spawn(move || {
                while let Some(captured) = input.pop() {
                    let started = Instant::now();
                    let segmentation = segmenter.as_mut().map(|s| s.segment(&captured.image));
                    let segment_ms = started.elapsed().as_secs_f64() * 1e3;
                    let item = Segmented {
                        captured,
                        segmentation,
                        segment_ms,
                    };
                    if output.push(item).is_err() {
                        break;
                    }
                }
                input.close();
                output.close();
            });
        }
        {
            let (input, output) = (segmented.clone(), posed.clone());
            let mut repair = pose_stage
                .root_glitch_window_s
                .map(|window| RootGlitchRepair::new(&skeleton, MAX_ROOT_TURN_DEG_PER_S, window));
            scope.spawn(move || {
                while let Some(Segmented {
                    captured,
                    segmentation,
                    segment_ms,
                }) = input.pop()
                {
                    let time = captured.timestamp_s;
                    let given = segmentation.as_ref().map(Silhouette::from);
                    let mut pose = pose_stage.process(&captured.image, given, &camera, time);
                    if segmentation.is_some() {
                        pose.times.segment = segment_ms;
                    }
                    let posed = Posed { captured, pose };
                    let sent = match repair.as_mut() {
                        Some(repair) => {
                            let frame = posed.pose.frame.clone();
                            pass_on(&output, repair.push(frame, time, posed))
                        }
                        None => output.push(posed).is_ok(),
                    };
                    if !sent {
                        break;
                    }
                }
                if let Some(repair) = repair.as_mut() {
                    pass_on(&output, repair.finish());
                }
                input.close();
                output.close();
            });
        }
        {
            let (input, output, controls) = (posed.clone(), dressed.clone(), Arc::clone(&controls));
            scope.spawn(move || {
                let mut hold = cloth_stage
                    .as_ref()
                    .and_then(ClothStage::sizing_hold)
                    .map(SizingHold::new);
                let camera = &camera;
                let dress_all = |stage: &mut Option<ClothStage>, frames: Vec<Posed>| {
                    frames.into_iter().all(|posed| {
                        let dressed = dress(stage.as_mut(), &controls, posed, camera);
                        output.push(dressed).is_ok()
                    })
                };
                while let Some(posed) = input.pop() {
                    let frames = match (hold.as_mut(), cloth_stage.as_mut()) {
                        (Some(hold), Some(stage)) => hold.push(stage, posed, camera),
                        _ => vec![posed],
                    };
                    if !dress_all(&mut cloth_stage, frames) {
                        break;
                    }
                }
                if let (Some(hold), Some(stage)) = (hold.as_mut(), cloth_stage.as_mut()) {
                    let frames = hold.finish(stage);
                    dress_all(&mut cloth_stage, frames);
                }
                input.close();
                output.close();
            });
        }
        {
            let (input, output, controls) =
                (dressed.clone(), finished.clone(), Arc::clone(&controls));
            let dropped_from = captured.clone();
            scope.spawn(move || {
                let mut last_times = FrameTimes::default();
                while let Some(Dressed {
                    posed,
                    cloth,
                    cloth_error,
                }) = input.pop()
                {
                    let Posed { captured, pose } = posed;
                    let overlays = controls.overlays();
                    let overlay = PoseOverlay::new(
                        overlays.mask.then(|| pose.mask.clone()),
                        if overlays.markers {
                            pose.markers.clone()
                        } else {
                            Vec::new()
                        },
                        &skeleton,
                        &pose.frame,
                        &camera,
                    );
                    let dropped = dropped_from.dropped();
                    let mut lines = banner();
                    if dropped > 0 {
                        lines.push(format!("DROPPED {dropped}"));
                    }
                    if !pose.person {
                        lines.push("NO PERSON".to_owned());
                    }
                    if let ClothStatus::Sizing { seen, needed } = &cloth.status {
                        lines.push(format!("MEASURING {seen}/{needed}"));
                    }
                    let text = timing_lines(&last_times);
                    let mut image = captured.image;
                    let (render, composite) = render_stage
                        .draw(
                            &mut image,
                            &camera,
                            &cloth,
                            pose.person.then_some(&pose.mask),
                            &overlay,
                            overlays,
                            &text,
                            &lines,
                        )
                        .unwrap_or((0.0, 0.0));
                    let times = FrameTimes {
                        segment: pose.times.segment,
                        describe: pose.times.describe,
                        regress: pose.times.regress,
                        cloth: cloth.milliseconds,
                        render,
                        composite,
                        latency: captured.started.elapsed().as_secs_f64() * 1e3,
                    };
                    last_times = times;
                    let out = Output {
                        index: captured.index,
                        timestamp_s: captured.timestamp_s,
                        image,
                        pose,
                        cloth,
                        times,
                        dropped,
                        cloth_error,
                    };
                    if output.push(out).is_err() {
                        break;
                    }
                }
                input.close();
                output.close();
            });
        }
        while let Some(out) = finished.pop() {
            summary.frames += 1;
            if !sink(out) {
                controls.stop.store(true, Ordering::Relaxed);
            }
        }
        let end = capture.join().unwrap_or_else(|_| CaptureEnd {
            error: Some("the capture thread panicked".to_owned()),
            ..CaptureEnd::default()
        });
        summary.skipped = end.skipped;
        summary.source_error = end.error;
        summary.input_frames = end.input_frames;
    });
    summary.dropped = captured.dropped();
    summary.stopped_by_user = controls.stopped();
    summary.seconds = started.elapsed().as_secs_f64();
    summary
}

/// The cloth stage's work on one frame: the garment the user switched to, then the cloth advanced
/// to the frame's pose (hidden, with the error, where it cannot be simulated).
fn dress(
    stage: Option<&mut ClothStage>,
    controls: &Controls,
    posed: Posed,
    camera: &Camera,
) -> Dressed {
    let p = &posed.pose;
    let (cloth, cloth_error) = match stage {
        None => (ClothFrame::hidden(ClothStatus::Off, 0.0), None),
        Some(stage) => {
            if let Some(garment) = controls.take_garment() {
                stage.set_garment(garment);
            }
            let time = posed.captured.timestamp_s;
            let silhouette = Silhouette::from(p);
            match stage.advance(&p.frame, time, p.person, silhouette, camera) {
                Ok(cloth) => (cloth, None),
                Err(e) => (
                    ClothFrame::hidden(ClothStatus::Off, 0.0),
                    Some(e.to_string()),
                ),
            }
        }
    };
    Dressed {
        posed,
        cloth,
        cloth_error,
    }
}

/// Recorded frames held back from the first one with a person until the cloth stage has
/// measured the person ([`ClothOptions::dress_from_first_frame`](super::ClothOptions)), so that
/// the garment is put on at the first of them.
struct SizingHold {
    held: Vec<Posed>,
    /// Frames held at most ([`ClothStage::sizing_hold`]).
    limit: usize,
}

impl SizingHold {
    fn new(limit: usize) -> SizingHold {
        SizingHold {
            held: Vec::new(),
            limit,
        }
    }

    /// Takes the next frame; returns the frames that go on to the cloth now, in order. Frames
    /// before the first person pass at once; from then on they are held (and measured) until the
    /// size is known or `limit` frames are held, when the size comes from those measured.
    fn push(&mut self, stage: &mut ClothStage, posed: Posed, camera: &Camera) -> Vec<Posed> {
        if self.held.is_empty() && (stage.size().is_some() || !posed.pose.person) {
            return vec![posed];
        }
        let p = &posed.pose;
        let sized = stage.measure(&p.frame, p.person, Silhouette::from(p), camera);
        self.held.push(posed);
        if sized || self.held.len() >= self.limit {
            stage.settle_size();
            return std::mem::take(&mut self.held);
        }
        Vec::new()
    }

    /// The end of the stream: the frames still held, the size from those measured.
    fn finish(&mut self, stage: &mut ClothStage) -> Vec<Posed> {
        if !self.held.is_empty() {
            stage.settle_size();
        }
        std::mem::take(&mut self.held)
    }
}

/// Passes the frames a [`RootGlitchRepair`] let go of on to the next stage, each with its pose
/// filled in where the repair did; `false` once the next stage is gone.
fn pass_on(output: &StageQueue<Posed>, released: Vec<Released<Posed>>) -> bool {
    released.into_iter().all(|r| {
        let mut posed = r.item;
        if r.filled {
            posed.pose.frame = r.frame;
            posed.pose.root_glitch_filled = true;
        }
        output.push(posed).is_ok()
    })
}

/// How the capture thread ended.
#[derive(Debug, Default)]
struct CaptureEnd {
    /// The skipped corrupt frames, each named.
    skipped: Vec<String>,
    /// The error that ended the stream, if any.
    error: Option<String>,
    /// [`RunSummary::input_frames`].
    input_frames: u64,
}

/// The capture thread: reads frames into `queue` until the end, a failure or a stop.
fn capture_frames(
    open_source: impl FnOnce() -> Result<Box<dyn FrameSource>, SourceError>,
    queue: &StageQueue<Captured>,
    controls: &Controls,
) -> CaptureEnd {
    let mut end = CaptureEnd::default();
    let mut source = match open_source() {
        Ok(source) => source,
        Err(e) => {
            queue.close();
            end.error = Some(e.to_string());
            return end;
        }
    };
    let mut seen = |index: u64| end.input_frames = end.input_frames.max(index + 1);
    while !controls.stopped() {
        match source.next_frame() {
            Ok(Some(frame)) => {
                seen(frame.index);
                let item = Captured {
                    index: frame.index,
                    timestamp_s: frame.timestamp.as_secs_f64(),
                    image: frame.image,
                    started: Instant::now(),
                };
                if queue.push(item).is_err() {
                    break;
                }
            }
            Ok(None) => break,
            Err(e) => match e.skipped_frame() {
                Some(index) => {
                    seen(index);
                    end.skipped.push(e.to_string());
                }
                None => {
                    end.error = Some(e.to_string());
                    break;
                }
            },
        }
    }
    queue.close();
    end
}

fn timing_lines(t: &FrameTimes) -> Vec<String> {
    vec![
        format!(
            "SEG {:.1} DESC {:.1} RVM {:.1} MS",
            t.segment, t.describe, t.regress
        ),
        format!(
            "CLOTH {:.1} RENDER {:.1} COMP {:.1} MS",
            t.cloth, t.render, t.composite
        ),
        format!("LATENCY {:.0} MS", t.latency),
    ]
}
