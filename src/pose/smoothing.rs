//! Temporal smoothing and joint limits for the pose output, applied to each BVH frame the regressor
//! decodes, before it is written or drives the body.
//!
//! * [`OneEuro`]: the One-Euro filter of Casiez, Roussel and Vogel 2012 ("1€ Filter: A Simple
//!   Speed-based Low-pass Filter for Noisy Input in Interactive Systems"): an exponential low-pass whose
//!   cutoff rises with the signal's speed (`min_cutoff + beta · |speed|`, the speed itself low-passed at
//!   `d_cutoff`), so slow motion is smoothed hard and fast motion is followed with little lag. The
//!   smoothing factor comes from the time between samples, so it works at any and at varying frame rates.
//! * Angles are filtered in unwrapped space: each new value is moved by whole turns to lie within 180°
//!   of the previous one, so a rotation crossing ±180° (179° → −179°) is a 2° step and never swept
//!   through 0; the output is wrapped back into (−180°, 180°].
//! * [`JointLimits`]: per rotation channel of each non-root joint, the range of values seen in training
//!   motions (the shortest arc holding all of them, so a range may straddle ±180°) widened by a margin.
//!   Stored as `joint_limits.toml` (with a format version) and applied as clamps in the unwrapped space
//!   around the range's centre. The root's rotation (the person's heading in the room) and every
//!   position channel are never limited.
//! * [`repair_root_glitches`], for a recorded take before it is written: frames in which the
//!   whole body turns faster than a person can (the regressor flipping the heading for a frame or
//!   a few) are filled in between the frames around them, which a causal filter cannot do.
//!   [`RootGlitchRepair`] does the same to a stream by holding the frames of a glitch back until it
//!   is over: the try-on runner puts recorded input through it on its way to the cloth, so the
//!   garment is not flung about by a heading the take's file does not have.
//! * [`PoseFilter`]: both, per BVH channel of one skeleton, each switchable (`Option`) and resettable
//!   ([`PoseFilter::reset`], e.g. on tracking loss, so the filter does not glide from a stale pose).
//!   Each frame is clamped, smoothed, and clamped again; it hands the frame back in place.
//! * [`smooth_backwards`], for a recorded take before it is written: the frames, smoothed forwards
//!   as they were estimated, smoothed once more from the last to the first, which undoes the
//!   forward pass's lag (a zero-phase, forward–backward filter, which only a recording can have).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::bvh::Motion;
use crate::skeleton::{interpolate_frames, Channel, Skeleton};

/// Version of the `joint_limits.toml` format.
pub const JOINT_LIMITS_VERSION: u32 = 1;
/// File name of the limits inside a suit directory.
pub const JOINT_LIMITS_FILE: &str = "joint_limits.toml";
/// Default widening of each learned range, each side.
pub const DEFAULT_MARGIN_DEG: f32 = 5.0;
/// Time step assumed when a timestamp does not advance.
pub const FALLBACK_DT: f64 = 1.0 / 30.0;

/// Wraps an angle in degrees into (−180, 180].
pub fn wrap_degrees(a: f64) -> f64 {
    let w = (a + 180.0).rem_euclid(360.0) - 180.0;
    if w == -180.0 {
        180.0
    } else {
        w
    }
}

/// Fills in the frames of `values` (frames of `skeleton`'s channels, one after another) in which
/// the root turned faster than `max_turn_deg` a frame: a tracking glitch, as no person turns that
/// fast (see [`crate::skeleton::MAX_ROOT_TURN_DEG_PER_S`]). A frame that turns more than that from
/// the frame before starts a glitch; it ends at the first frame within `window` frames after it
/// that the frame before the glitch reaches at that speed (at most `max_turn_deg` times the frames
/// between them), and the frames between are filled in between those two, every channel
/// (rotations the short way). So a glitch that comes back is taken out, and a turn that stays is
/// spread over as many frames as a person would need; one that no frame within the window
/// reaches at that speed is left as it is. Returns the frame ranges filled in.
///
/// This is [`RootGlitchRepair`] run over a whole take, with time counted in frames.
pub fn repair_root_glitches(
    skeleton: &Skeleton,
    values: &mut [f32],
    max_turn_deg: f32,
    window: usize,
) -> Vec<std::ops::Range<usize>> {
    let n = skeleton.channel_count();
    if n == 0 || max_turn_deg.is_nan() || max_turn_deg <= 0.0 {
        return Vec::new();
    }
    let mut repair = RootGlitchRepair::new(skeleton, max_turn_deg, window as f64);
    let mut released = Vec::new();
    for (k, frame) in values.chunks_exact(n).enumerate() {
        released.extend(repair.push(frame.to_vec(), k as f64, k));
    }
    released.extend(repair.finish());
    let filled = released.into_iter().filter(|r| r.filled).map(|r| {
        values[r.item * n..(r.item + 1) * n].copy_from_slice(&r.frame);
        r.item
    });
    index_ranges(filled)
}

/// Ascending frame indices as ranges of consecutive ones: `[1, 2, 3, 5]` → `[1..4, 5..6]`.
pub fn index_ranges(indices: impl IntoIterator<Item = usize>) -> Vec<std::ops::Range<usize>> {
    let mut spans: Vec<std::ops::Range<usize>> = Vec::new();
    for k in indices {
        match spans.last_mut() {
            Some(span) if span.end == k => span.end += 1,
            _ => spans.push(k..k + 1),
        }
    }
    spans
}

/// A frame [`RootGlitchRepair`] let go of: its pose (filled in between the frames around a glitch
/// when `filled`), its time, and what came with it.
#[derive(Clone, Debug, PartialEq)]
pub struct Released<T> {
    pub frame: Vec<f32>,
    pub time: f64,
    pub item: T,
    pub filled: bool,
}

/// [`repair_root_glitches`] as a stream, for the frames of a recording on their way from the pose
/// stage to the cloth: each pose is let go of as soon as it is known not to be part of a root
/// glitch, and the frames of a glitch are held until the pose comes back within reach (then they
/// are filled in between the poses around them) or until `window` has passed since the glitch
/// began (then its first frame is let go of as it is and the rest judged again). A stream without
/// glitches passes through without delay; a glitch delays the frames after it by at most the
/// window. Times are in any unit (seconds for a stream, frame indices for a take) with
/// `max_turn_deg` the fastest turn per unit and `window` in that unit. Frames come out in the
/// order they went in, each once.
#[derive(Clone, Debug)]
pub struct RootGlitchRepair<T> {
    skeleton: Skeleton,
    rotation: Vec<bool>,
    max_turn_deg: f32,
    window: f64,
    /// The last frame let go of, and its time: what a held frame is judged against.
    good: Option<(Vec<f32>, f64)>,
    held: std::collections::VecDeque<Released<T>>,
}

impl<T> RootGlitchRepair<T> {
    pub fn new(skeleton: &Skeleton, max_turn_deg: f32, window: f64) -> RootGlitchRepair<T> {
        RootGlitchRepair {
            skeleton: skeleton.clone(),
            rotation: skeleton.rotation_channels(),
            max_turn_deg,
            window,
            good: None,
            held: std::collections::VecDeque::new(),
        }
    }

    /// Frames held back, waiting to see whether a glitch comes back.
    pub fn held(&self) -> usize {
        self.held.len()
    }

    /// Takes the pose `frame` at `time` with `item`; gives back the frames that can go on now, in
    /// order (none while a glitch may be under way).
    pub fn push(&mut self, frame: Vec<f32>, time: f64, item: T) -> Vec<Released<T>> {
        self.held.push_back(Released {
            frame,
            time,
            item,
            filled: false,
        });
        self.settle(false)
    }

    /// Lets go of every frame still held, at the end of the stream (a glitch that has not come
    /// back by then is left as it is).
    pub fn finish(&mut self) -> Vec<Released<T>> {
        self.settle(true)
    }

    fn reachable(&self, (good, good_time): (&[f32], f64), frame: &Released<T>) -> bool {
        let turn = self.skeleton.root_turn_degrees(good, &frame.frame);
        turn <= self.max_turn_deg * (frame.time - good_time) as f32
    }

    fn release(&mut self, count: usize, out: &mut Vec<Released<T>>) {
        for r in self.held.drain(..count) {
            self.good = Some((r.frame.clone(), r.time));
            out.push(r);
        }
    }

    fn settle(&mut self, end: bool) -> Vec<Released<T>> {
        let mut out = Vec::new();
        while let Some(first) = self.held.front() {
            let Some((good, good_time)) = self.good.take() else {
                self.release(1, &mut out);
                continue;
            };
            let from = (good.as_slice(), good_time);
            let start = first.time;
            let back = if self.reachable(from, first) {
                Some(0)
            } else {
                self.held
                    .iter()
                    .enumerate()
                    .skip(1)
                    .take_while(|(_, h)| h.time - start <= self.window)
                    .find(|(_, h)| self.reachable(from, h))
                    .map(|(j, _)| j)
            };
            let waiting = !end
                && self
                    .held
                    .back()
                    .is_some_and(|last| last.time - start <= self.window);
            match back {
                Some(j) => {
                    let span = self.held[j].time - good_time;
                    let mut filled = Vec::with_capacity(good.len());
                    for k in 0..j {
                        let t = ((self.held[k].time - good_time) / span) as f32;
                        interpolate_frames(
                            &self.rotation,
                            &good,
                            &self.held[j].frame,
                            t,
                            &mut filled,
                        );
                        let h = &mut self.held[k];
                        std::mem::swap(&mut h.frame, &mut filled);
                        h.filled = true;
                    }
                    self.release(j + 1, &mut out);
                }
                None if waiting => {
                    self.good = Some((good, good_time));
                    break;
                }
                None => self.release(1, &mut out),
            }
        }
        out
    }
}

/// Parameters of one One-Euro filter (cutoffs in Hz; `beta` in 1 / (signal unit)).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct OneEuroParams {
    /// Cutoff at rest: lower = smoother, more lag when slow.
    pub min_cutoff: f64,
    /// How fast the cutoff rises with speed: higher = less lag when fast, more jitter.
    pub beta: f64,
    /// Cutoff of the speed estimate.
    pub d_cutoff: f64,
}

/// Smoothing settings for the two kinds of BVH channel. The defaults are starting values (angles in
/// degrees, positions in cm), not tuned on captured data.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SmoothingParams {
    pub angles: OneEuroParams,
    pub positions: OneEuroParams,
}

impl Default for SmoothingParams {
    fn default() -> Self {
        SmoothingParams {
            angles: OneEuroParams {
                min_cutoff: 1.0,
                beta: 0.05,
                d_cutoff: 1.0,
            },
            positions: OneEuroParams {
                min_cutoff: 1.0,
                beta: 0.02,
                d_cutoff: 1.0,
            },
        }
    }
}

/// Smoothing factor of an exponential low-pass with `cutoff` Hz for a step of `dt` seconds.
fn alpha(cutoff: f64, dt: f64) -> f64 {
    let tau = 1.0 / (std::f64::consts::TAU * cutoff.max(1e-9));
    1.0 / (1.0 + tau / dt)
}

/// One One-Euro filter over a scalar signal, optionally an angle in degrees.
#[derive(Clone, Debug, PartialEq)]
pub struct OneEuro {
    pub params: OneEuroParams,
    /// Filter on the circle (degrees) rather than the line.
    pub angle: bool,
    /// (last unwrapped raw value, last filtered value, last filtered speed), `None` before the first
    /// sample.
    state: Option<(f64, f64, f64)>,
}

impl OneEuro {
    pub fn new(params: OneEuroParams, angle: bool) -> OneEuro {
        OneEuro {
            params,
            angle,
            state: None,
        }
    }

    /// Forgets the history: the next sample passes unchanged.
    pub fn reset(&mut self) {
        self.state = None;
    }

    /// Filters `x` arriving `dt` seconds after the previous sample (a non-positive or non-finite
    /// `dt` counts as [`FALLBACK_DT`]); a non-finite `x` is passed through and resets the filter.
    pub fn filter(&mut self, x: f64, dt: f64) -> f64 {
        if !x.is_finite() {
            self.state = None;
            return x;
        }
        let dt = if dt.is_finite() && dt > 0.0 {
            dt
        } else {
            FALLBACK_DT
        };
        let Some((raw_prev, prev, speed_prev)) = self.state else {
            let x = if self.angle { wrap_degrees(x) } else { x };
            self.state = Some((x, x, 0.0));
            return x;
        };
        let raw = if self.angle {
            raw_prev + wrap_degrees(x - raw_prev)
        } else {
            x
        };
        let speed = (raw - prev) / dt;
        let speed = speed_prev + alpha(self.params.d_cutoff, dt) * (speed - speed_prev);
        let cutoff = self.params.min_cutoff + self.params.beta * speed.abs();
        let mut filtered = prev + alpha(cutoff, dt) * (raw - prev);
        let mut raw = raw;
        if self.angle {
            // Keep the unwrapped state near zero so it never loses precision over many turns.
            let shift = 360.0 * (filtered / 360.0).round();
            filtered -= shift;
            raw -= shift;
        }
        self.state = Some((raw, filtered, speed));
        if self.angle {
            wrap_degrees(filtered)
        } else {
            filtered
        }
    }
}

/// The allowed range of one rotation channel, in degrees: `min ≤ max ≤ min + 360`, `min` in
/// (−180, 180]; `max` may exceed 180 for a range straddling ±180°.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AngleRange {
    pub min: f32,
    pub max: f32,
}

impl AngleRange {
    /// A range covering the whole circle does not limit anything.
    pub fn is_full(&self) -> bool {
        self.max - self.min >= 360.0
    }

    /// `angle` clamped into the range, wrapped into (−180, 180]. The angle is first moved by whole
    /// turns to lie within 180° of the range's centre.
    pub fn clamp(&self, angle: f32) -> f32 {
        if self.is_full() || !angle.is_finite() {
            return angle;
        }
        let (min, max) = (f64::from(self.min), f64::from(self.max));
        let centre = 0.5 * (min + max);
        let unwrapped = centre + wrap_degrees(f64::from(angle) - centre);
        if unwrapped >= min && unwrapped <= max {
            return angle;
        }
        wrap_degrees(unwrapped.clamp(min, max)) as f32
    }

    /// The shortest arc holding every angle, widened by `margin` each side (the whole circle if that
    /// leaves no gap). `None` for no finite angle.
    pub fn covering(angles: &[f32], margin: f32) -> Option<AngleRange> {
        let mut a: Vec<f64> = angles
            .iter()
            .filter(|v| v.is_finite())
            .map(|&v| wrap_degrees(f64::from(v)))
            .collect();
        if a.is_empty() {
            return None;
        }
        a.sort_by(f64::total_cmp);
        // The largest gap between circularly consecutive angles is what the range leaves out.
        let (mut gap, mut start) = (a[0] + 360.0 - a[a.len() - 1], a[0]);
        for w in a.windows(2) {
            if w[1] - w[0] > gap {
                gap = w[1] - w[0];
                start = w[1];
            }
        }
        let width = 360.0 - gap;
        let margin = f64::from(margin.max(0.0));
        if width + 2.0 * margin >= 360.0 {
            return Some(AngleRange {
                min: -180.0,
                max: 180.0,
            });
        }
        // Rounded outwards to 0.01° so the file holds exactly the learned range.
        let low = start - margin;
        let shift = wrap_degrees(low) - low;
        let mut min = ((low + shift) * 100.0).floor() / 100.0;
        let mut max = ((low + width + 2.0 * margin + shift) * 100.0).ceil() / 100.0;
        if min <= -180.0 {
            min += 360.0;
            max += 360.0;
        }
        Some(AngleRange {
            min: min as f32,
            max: max as f32,
        })
    }
}

/// Learned ranges per (joint name, rotation channel).
#[derive(Clone, Debug, PartialEq)]
pub struct JointLimits {
    /// Degrees each learned range was widened by on each side.
    pub margin_deg: f32,
    /// Frames the ranges were learned from.
    pub frames: usize,
    /// Sorted by joint (file order of the first motion) then channel order.
    pub limits: Vec<ChannelLimit>,
}

/// The range of one rotation channel of one joint.
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelLimit {
    pub joint: String,
    pub channel: Channel,
    pub range: AngleRange,
}

/// A joint limits file that cannot be read or written; names the file and the field.
#[derive(Debug, thiserror::Error)]
pub enum LimitsError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: cannot write: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Format { path: PathBuf, message: String },
    #[error("{path}: field {field}: {message}")]
    Field {
        path: PathBuf,
        field: String,
        message: String,
    },
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct LimitsFile {
    version: u32,
    margin_deg: f64,
    frames: usize,
    #[serde(default)]
    limit: Vec<LimitEntry>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct LimitEntry {
    joint: String,
    channel: String,
    min: f64,
    max: f64,
}

/// `v` rounded to `places` decimals, as the f64 that prints shortest (files stay readable).
fn decimal(v: f32, places: i32) -> f64 {
    let scale = 10f64.powi(places);
    (f64::from(v) * scale).round() / scale
}

impl JointLimits {
    /// Learns the range of every rotation channel of every non-root joint over all frames of
    /// `motions` (joints matched by name), widened by `margin_deg` each side.
    pub fn learn(motions: &[Motion], margin_deg: f32) -> JointLimits {
        let mut order: Vec<(String, Channel)> = Vec::new();
        let mut values: HashMap<(String, Channel), Vec<f32>> = HashMap::new();
        let mut frames = 0;
        for motion in motions {
            frames += motion.frame_count();
            for joint in motion.skeleton.joints().iter().skip(1) {
                for (k, &channel) in joint.channels.iter().enumerate() {
                    if !channel.is_rotation() {
                        continue;
                    }
                    let key = (joint.name.clone(), channel);
                    let list = values.entry(key.clone()).or_insert_with(|| {
                        order.push(key);
                        Vec::new()
                    });
                    list.extend(motion.frames().map(|f| f[joint.first_channel + k]));
                }
            }
        }
        let limits = order
            .into_iter()
            .filter_map(|key| {
                let range = AngleRange::covering(values.get(&key)?, margin_deg)?;
                Some(ChannelLimit {
                    joint: key.0,
                    channel: key.1,
                    range,
                })
            })
            .collect();
        JointLimits {
            margin_deg,
            frames,
            limits,
        }
    }

    /// The range of `joint`'s `channel`, if limited.
    pub fn get(&self, joint: &str, channel: Channel) -> Option<AngleRange> {
        self.limits
            .iter()
            .find(|l| l.joint == joint && l.channel == channel)
            .map(|l| l.range)
    }

    /// Per channel of `skeleton`'s frames, the range that applies (root and positions: none).
    pub fn bind(&self, skeleton: &Skeleton) -> Vec<Option<AngleRange>> {
        let mut out = vec![None; skeleton.channel_count()];
        for joint in skeleton.joints().iter().skip(1) {
            for (k, &channel) in joint.channels.iter().enumerate() {
                if channel.is_rotation() {
                    out[joint.first_channel + k] =
                        self.get(&joint.name, channel).filter(|r| !r.is_full());
                }
            }
        }
        out
    }

    /// The file's text.
    pub fn to_toml(&self) -> Result<String, toml::ser::Error> {
        let file = LimitsFile {
            version: JOINT_LIMITS_VERSION,
            margin_deg: decimal(self.margin_deg, 3),
            frames: self.frames,
            limit: self
                .limits
                .iter()
                .map(|l| LimitEntry {
                    joint: l.joint.clone(),
                    channel: l.channel.name().to_owned(),
                    min: decimal(l.range.min, 2),
                    max: decimal(l.range.max, 2),
                })
                .collect(),
        };
        let body = toml::to_string(&file)?;
        Ok(format!(
            "# Joint limits learned from training motions: per rotation channel (degrees) the shortest\n\
             # arc holding every training value, widened by margin_deg each side; max may exceed 180\n\
             # for a range across ±180. Written by suitcap; see src/pose/smoothing.rs.\n{body}"
        ))
    }

    /// Parses and validates the file's text; `path` names the source in errors.
    pub fn parse(text: &str, path: &Path) -> Result<JointLimits, LimitsError> {
        let file: LimitsFile = toml::from_str(text).map_err(|e| LimitsError::Format {
            path: path.to_owned(),
            message: e.to_string(),
        })?;
        let field = |field: String, message: String| LimitsError::Field {
            path: path.to_owned(),
            field,
            message,
        };
        if file.version != JOINT_LIMITS_VERSION {
            return Err(field(
                "version".into(),
                format!(
                    "{} is not the version this build reads ({JOINT_LIMITS_VERSION})",
                    file.version
                ),
            ));
        }
        if !(file.margin_deg >= 0.0 && file.margin_deg <= 180.0) {
            return Err(field(
                "margin_deg".into(),
                format!("{} is not in [0, 180]", file.margin_deg),
            ));
        }
        let mut limits: Vec<ChannelLimit> = Vec::with_capacity(file.limit.len());
        for (i, entry) in file.limit.into_iter().enumerate() {
            let at = |name: &str| format!("limit[{i}].{name}");
            let channel = Channel::from_name(&entry.channel)
                .filter(|c| c.is_rotation())
                .ok_or_else(|| {
                    field(
                        at("channel"),
                        format!(
                            "'{}' is not a rotation channel (Xrotation, Yrotation, Zrotation)",
                            entry.channel
                        ),
                    )
                })?;
            if !(entry.min.is_finite() && entry.min >= -180.0 && entry.min <= 180.0) {
                return Err(field(
                    at("min"),
                    format!("{} is not in [-180, 180]", entry.min),
                ));
            }
            if !(entry.max.is_finite() && entry.max >= entry.min && entry.max - entry.min <= 360.0)
            {
                return Err(field(
                    at("max"),
                    format!(
                        "{} is not in [min, min + 360] = [{}, {}]",
                        entry.max,
                        entry.min,
                        entry.min + 360.0
                    ),
                ));
            }
            if limits
                .iter()
                .any(|l| l.joint == entry.joint && l.channel == channel)
            {
                return Err(field(
                    at("joint"),
                    format!("'{}' {} appears twice", entry.joint, channel.name()),
                ));
            }
            limits.push(ChannelLimit {
                joint: entry.joint,
                channel,
                range: AngleRange {
                    min: entry.min as f32,
                    max: entry.max as f32,
                },
            });
        }
        Ok(JointLimits {
            margin_deg: file.margin_deg as f32,
            frames: file.frames,
            limits,
        })
    }

    /// Reads a limits file.
    pub fn load(path: &Path) -> Result<JointLimits, LimitsError> {
        let text = std::fs::read_to_string(path).map_err(|source| LimitsError::Io {
            path: path.to_owned(),
            source,
        })?;
        JointLimits::parse(&text, path)
    }

    /// Writes the file atomically.
    pub fn save(&self, path: &Path) -> Result<(), LimitsError> {
        let text = self.to_toml().map_err(|e| LimitsError::Format {
            path: path.to_owned(),
            message: e.to_string(),
        })?;
        crate::io::write_atomic(path, text.as_bytes()).map_err(|source| LimitsError::Write {
            path: path.to_owned(),
            source,
        })
    }
}

/// Smoothing and limits for the frames of one skeleton, one stream.
#[derive(Clone, Debug)]
pub struct PoseFilter {
    /// Per channel filter; `None` when smoothing is off.
    smoothing: Option<Vec<OneEuro>>,
    /// Per channel range; `None` when limits are off.
    limits: Option<Vec<Option<AngleRange>>>,
    channels: usize,
    last_time: Option<f64>,
}

impl PoseFilter {
    /// A filter for frames of `skeleton`, smoothing with `smoothing` and clamping to `limits` (either
    /// may be `None` to switch it off).
    pub fn new(
        skeleton: &Skeleton,
        smoothing: Option<SmoothingParams>,
        limits: Option<&JointLimits>,
    ) -> PoseFilter {
        let kinds: Vec<bool> = skeleton
            .joints()
            .iter()
            .flat_map(|j| j.channels.iter().map(|c| c.is_rotation()))
            .collect();
        PoseFilter {
            smoothing: smoothing.map(|p| {
                kinds
                    .iter()
                    .map(|&angle| OneEuro::new(if angle { p.angles } else { p.positions }, angle))
                    .collect()
            }),
            limits: limits.map(|l| l.bind(skeleton)),
            channels: kinds.len(),
            last_time: None,
        }
    }

    pub fn smoothing_enabled(&self) -> bool {
        self.smoothing.is_some()
    }

    pub fn limits_enabled(&self) -> bool {
        self.limits.is_some()
    }

    /// Forgets the history (call on tracking loss); limits stay.
    pub fn reset(&mut self) {
        self.last_time = None;
        if let Some(filters) = &mut self.smoothing {
            filters.iter_mut().for_each(OneEuro::reset);
        }
    }

    fn clamp(&self, frame: &mut [f32]) {
        if let Some(limits) = &self.limits {
            for (v, range) in frame.iter_mut().zip(limits) {
                if let Some(r) = range {
                    *v = r.clamp(*v);
                }
            }
        }
    }

    /// Clamps, smooths and clamps `frame` (taken at `time_s` seconds on the stream's clock) in place.
    /// A frame of the wrong length is left unchanged.
    pub fn apply(&mut self, time_s: f64, frame: &mut [f32]) {
        if frame.len() != self.channels {
            return;
        }
        self.clamp(frame);
        let dt = self.last_time.map_or(FALLBACK_DT, |t| time_s - t);
        if time_s.is_finite() {
            self.last_time = Some(time_s);
        }
        if let Some(filters) = &mut self.smoothing {
            for (v, f) in frame.iter_mut().zip(filters.iter_mut()) {
                *v = f.filter(f64::from(*v), dt) as f32;
            }
            self.clamp(frame);
        }
    }
}

/// Smooths a recorded take once more, backwards in time, with `filter`: the filter the frames were
/// smoothed with forwards as they were estimated (it is reset first, and clamps to its limits as
/// it goes). The forward pass lags behind a moving joint; the backward pass lags the other way,
/// so together they follow it without lag, as a zero-phase (forward–backward) filter does.
/// `values` holds the frames one after the other, `frame_time_s` apart. The frames listed in
/// `breaks` (nobody in view, where the forward filter started again) are left as they are and
/// start the filter again; those listed in `skipped` (frames filled in between poses, to be
/// filled in again from the smoothed ones) are left as they are, the filter's clock running on
/// over them. Does nothing when the filter does not smooth or the frames are not of its length.
pub fn smooth_backwards(
    filter: &mut PoseFilter,
    values: &mut [f32],
    frame_time_s: f64,
    (breaks, skipped): (&[usize], &[usize]),
) {
    if !filter.smoothing_enabled()
        || filter.channels == 0
        || !values.len().is_multiple_of(filter.channels)
    {
        return;
    }
    filter.reset();
    let frames = values.len() / filter.channels;
    // Per frame: 0 smoothed, 1 skipped, 2 a break (a long take may have many of either).
    let mut kind = vec![0u8; frames];
    for (&k, mark) in skipped
        .iter()
        .map(|k| (k, 1))
        .chain(breaks.iter().map(|k| (k, 2)))
    {
        if let Some(slot) = kind.get_mut(k) {
            *slot = (*slot).max(mark);
        }
    }
    for (k, frame) in values.chunks_exact_mut(filter.channels).enumerate().rev() {
        match kind[k] {
            0 => filter.apply((frames - 1 - k) as f64 * frame_time_s, frame),
            1 => {}
            _ => filter.reset(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skeleton::tests::two_joint_arm;

    #[test]
    fn smoothing_back_undoes_the_forward_lag_of_a_steady_turn() {
        // The elbow turning at 3° a frame (90°/s) for two seconds, the root still.
        let mut filter = PoseFilter::new(&two_joint_arm(), Some(SmoothingParams::default()), None);
        let mut values = turning(&[0.0; 60]);
        for (k, frame) in values.chunks_exact_mut(9).enumerate() {
            for v in &mut frame[6..] {
                *v *= 3.0;
            }
            filter.apply(k as f64 * DT, frame);
        }
        let forward = values.clone();
        smooth_backwards(&mut filter, &mut values, DT, (&[], &[]));
        // Frame 30, well inside: the forward pass lags behind the turn; forward and back do not.
        let at = |v: &[f32]| v[30 * 9 + 6];
        let lag_forward = 90.0 - at(&forward);
        let lag_both = (90.0 - at(&values)).abs();
        assert!(lag_forward > 0.5, "the forward pass lags: {lag_forward}");
        assert!(
            lag_both < lag_forward / 4.0,
            "{lag_both} against {lag_forward}"
        );
    }

    #[test]
    fn smoothing_back_leaves_breaks_and_constant_frames_alone() {
        let mut filter = PoseFilter::new(&two_joint_arm(), Some(SmoothingParams::default()), None);
        // Ten frames of the root turned 20° and the elbow bent 5°; frames 3 and 4 are breaks
        // with elbows of their own.
        let mut values = turning(&[20.0; 10]);
        for frame in values.chunks_exact_mut(9) {
            frame[6] = 5.0;
        }
        values[3 * 9 + 6] = -40.0;
        values[4 * 9 + 6] = 77.0;
        let before = values.clone();
        smooth_backwards(&mut filter, &mut values, DT, (&[3, 4], &[]));
        for (a, b) in values.iter().zip(&before) {
            assert!((a - b).abs() < 1e-4, "{a} against {b}");
        }
        // A skipped frame is left alone too, and the filter goes on over it.
        let mut turn = turning(&[0.0; 12]);
        turn[5 * 9 + 6] = 500.0;
        let mut filter = PoseFilter::new(&two_joint_arm(), Some(SmoothingParams::default()), None);
        smooth_backwards(&mut filter, &mut turn, DT, (&[], &[5]));
        assert_eq!(turn[5 * 9 + 6], 500.0);
        assert!(turn[4 * 9 + 6] < 6.0, "{}", turn[4 * 9 + 6]);
        // Without smoothing nothing is done at all.
        let mut limits_only = PoseFilter::new(&two_joint_arm(), None, None);
        let mut ramp = turning(&[0.0, 10.0, 20.0]);
        let unchanged = ramp.clone();
        smooth_backwards(&mut limits_only, &mut ramp, DT, (&[], &[]));
        assert_eq!(ramp, unchanged);
    }

    const DT: f64 = 1.0 / 30.0;

    /// Frames of the two-joint arm turning its root about the vertical by `yaw` degrees, the
    /// elbow bent by the frame's index.
    fn turning(yaw: &[f32]) -> Vec<f32> {
        yaw.iter()
            .enumerate()
            .flat_map(|(k, &y)| [0.0, 0.0, 0.0, 0.0, y, 0.0, k as f32, 0.0, 0.0])
            .collect()
    }

    #[test]
    fn consecutive_indices_make_one_range() {
        assert_eq!(index_ranges([1, 2, 3, 5, 7, 8]), vec![1..4, 5..6, 7..9]);
        assert_eq!(index_ranges([0]), vec![0..1]);
        assert!(index_ranges(std::iter::empty()).is_empty());
    }

    #[test]
    fn a_turn_faster_than_a_person_is_filled_in_between_the_frames_around_it() {
        let arm = two_joint_arm();
        let yaw_of = |values: &[f32]| values.chunks(9).map(|f| f[4]).collect::<Vec<_>>();
        // A glitch that comes back: frame 2 is filled in halfway between frames 1 and 3, the
        // elbow too.
        let mut glitch = turning(&[0.0, 0.0, 90.0, 5.0, 10.0]);
        glitch[2 * 9 + 6] = 40.0;
        assert_eq!(
            repair_root_glitches(&arm, &mut glitch, 35.0, 15),
            vec![2..3]
        );
        assert_eq!(yaw_of(&glitch), [0.0, 0.0, 2.5, 5.0, 10.0]);
        assert_eq!(glitch[2 * 9 + 6], 2.0);
        // A turn that stays is spread over three frames, 30° each.
        let mut step = turning(&[0.0, 0.0, 90.0, 90.0, 90.0]);
        assert_eq!(repair_root_glitches(&arm, &mut step, 35.0, 15), vec![2..4]);
        let yaw = yaw_of(&step);
        assert!(
            (yaw[2] - 30.0).abs() < 1e-4 && (yaw[3] - 60.0).abs() < 1e-4,
            "{yaw:?}"
        );
        // ... unless the window is too short to reach it; turns a person can make stay.
        let mut short = turning(&[0.0, 0.0, 90.0, 90.0]);
        assert!(repair_root_glitches(&arm, &mut short, 35.0, 1).is_empty());
        assert_eq!(yaw_of(&short), [0.0, 0.0, 90.0, 90.0]);
        let mut fast = turning(&[0.0, 30.0, 60.0, 30.0]);
        assert!(repair_root_glitches(&arm, &mut fast, 35.0, 15).is_empty());
        // The short way round: 170° to −170° is a 20° turn.
        let mut across = turning(&[150.0, 170.0, -170.0]);
        assert!(repair_root_glitches(&arm, &mut across, 35.0, 15).is_empty());
    }

    /// The yaw of each released frame and whether it was filled in, with the items' order.
    fn yaws(released: &[Released<usize>]) -> Vec<(usize, f32, bool)> {
        released
            .iter()
            .map(|r| (r.item, r.frame[4], r.filled))
            .collect()
    }

    #[test]
    fn a_stream_is_held_back_only_while_a_glitch_may_be_under_way() {
        let arm = two_joint_arm();
        let frames = turning(&[0.0, 10.0, 90.0, 15.0, 20.0]);
        // 30 frames/s, the fastest turn 1050°/s (35° a frame), half a second's window.
        let mut repair = RootGlitchRepair::new(&arm, 1050.0, 0.5);
        let mut out = Vec::new();
        for (k, frame) in frames.chunks(9).enumerate() {
            let released = repair.push(frame.to_vec(), k as f64 / 30.0, k);
            out.push(yaws(&released));
        }
        assert_eq!(out[0], [(0, 0.0, false)]);
        assert_eq!(out[1], [(1, 10.0, false)]);
        // Frame 2 turns 80° in a frame: held until frame 3 comes back within reach.
        assert!(out[2].is_empty() && out.len() == 5);
        assert_eq!(out[3].len(), 2);
        assert_eq!((out[3][0].0, out[3][0].2), (2, true));
        assert!((out[3][0].1 - 12.5).abs() < 1e-4, "{:?}", out[3]);
        assert_eq!(out[3][1], (3, 15.0, false));
        assert_eq!(out[4], [(4, 20.0, false)]);
        assert!(repair.finish().is_empty() && repair.held() == 0);
    }

    #[test]
    fn a_turn_that_no_frame_within_the_window_undoes_goes_on_as_it_is() {
        let arm = two_joint_arm();
        // Window of one frame: 90° cannot be reached from 0° at 35° a frame within it.
        let mut repair = RootGlitchRepair::new(&arm, 35.0, 1.0);
        let frames = turning(&[0.0, 90.0, 90.0, 90.0]);
        let mut pushed = frames.chunks(9).enumerate();
        let mut push = |repair: &mut RootGlitchRepair<usize>| {
            let (k, frame) = pushed.next().expect("a frame");
            yaws(&repair.push(frame.to_vec(), k as f64, k))
        };
        assert_eq!(push(&mut repair), [(0, 0.0, false)]);
        assert!(push(&mut repair).is_empty());
        assert!(push(&mut repair).is_empty());
        assert_eq!(
            push(&mut repair),
            [(1, 90.0, false), (2, 90.0, false), (3, 90.0, false)]
        );
        // At the end of a stream whatever is held goes as it is.
        let mut ended = RootGlitchRepair::new(&arm, 35.0, 15.0);
        assert_eq!(ended.push(frames[..9].to_vec(), 0.0, 0).len(), 1);
        assert!(ended.push(frames[9..18].to_vec(), 1.0, 1).is_empty());
        assert_eq!(yaws(&ended.finish()), [(1, 90.0, false)]);
    }

    /// The whole-take repair as it was written before the stream existed, frame index by frame
    /// index, kept as the stream's reference.
    fn repaired_frame_by_frame(skeleton: &Skeleton, values: &mut [f32], max: f32, window: usize) {
        let n = skeleton.channel_count();
        let frames = values.len() / n;
        let rotation = skeleton.rotation_channels();
        let turn = |values: &[f32], i: usize, j: usize| {
            skeleton.root_turn_degrees(&values[i * n..(i + 1) * n], &values[j * n..(j + 1) * n])
        };
        let mut filled = Vec::new();
        let mut k = 1;
        while k < frames {
            let good = k - 1;
            if turn(values, good, k) <= max {
                k += 1;
                continue;
            }
            let back = (k + 1..frames.min(k + 1 + window))
                .find(|&j| turn(values, good, j) <= max * (j - good) as f32);
            let Some(end) = back else {
                k += 1;
                continue;
            };
            let (a, b) = (
                values[good * n..(good + 1) * n].to_vec(),
                values[end * n..(end + 1) * n].to_vec(),
            );
            for m in k..end {
                let t = (m - good) as f32 / (end - good) as f32;
                interpolate_frames(&rotation, &a, &b, t, &mut filled);
                values[m * n..(m + 1) * n].copy_from_slice(&filled);
            }
            k = end;
        }
    }

    proptest::proptest! {
        /// Streamed, every frame comes out once, in order, as the frame-by-frame repair of the
        /// whole take has it.
        #[test]
        fn streaming_matches_the_whole_take(yaw in proptest::collection::vec(-180.0f32..180.0, 1..40)) {
            let arm = two_joint_arm();
            let frames = turning(&yaw);
            let mut whole = frames.clone();
            repaired_frame_by_frame(&arm, &mut whole, 35.0, 3);
            let mut repair = RootGlitchRepair::new(&arm, 35.0, 3.0);
            let mut streamed = Vec::new();
            for (k, frame) in frames.chunks(9).enumerate() {
                streamed.extend(repair.push(frame.to_vec(), k as f64, k));
            }
            streamed.extend(repair.finish());
            let order: Vec<usize> = streamed.iter().map(|r| r.item).collect();
            proptest::prop_assert_eq!(order, (0..yaw.len()).collect::<Vec<_>>());
            // Equal but for rounding: the stream interpolates at times in f64, the reference at
            // frame fractions in f32.
            let values: Vec<f32> = streamed.into_iter().flat_map(|r| r.frame).collect();
            proptest::prop_assert_eq!(values.len(), whole.len());
            for (k, (v, w)) in values.iter().zip(&whole).enumerate() {
                proptest::prop_assert!((v - w).abs() <= 1e-3, "value {}: {} against {}", k, v, w);
            }
        }
    }

    #[test]
    fn real_motion_has_no_root_glitches() {
        for clip in [
            "cmu_02_01_walk.bvh",
            "cmu_10_03_kick_ball.bvh",
            "cmu_13_39_jump.bvh",
        ] {
            let path = Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("tests/data/mocap")
                .join(clip);
            let motion = Motion::load(&path).expect("clip");
            let (motion, _) = motion
                .resample(crate::bvh::CMU_CALIBRATION_FRAMES, None, 30.0)
                .expect("resample");
            let mut values = motion.values().to_vec();
            let spans = repair_root_glitches(
                &motion.skeleton,
                &mut values,
                crate::skeleton::MAX_ROOT_TURN_DEG_PER_S / 30.0,
                15,
            );
            assert!(spans.is_empty(), "{clip}: {spans:?}");
        }
    }

    fn run(filter: &mut OneEuro, xs: &[f64]) -> Vec<f64> {
        xs.iter().map(|&x| filter.filter(x, DT)).collect()
    }

    fn angles() -> OneEuroParams {
        SmoothingParams::default().angles
    }

    #[test]
    fn constant_signal_passes_unchanged() {
        for angle in [false, true] {
            let mut f = OneEuro::new(angles(), angle);
            for y in run(&mut f, &[42.0; 100]) {
                assert!((y - 42.0).abs() < 1e-9, "{y}");
            }
        }
    }

    #[test]
    fn step_converges_without_overshoot() {
        let mut f = OneEuro::new(angles(), false);
        let mut xs = vec![0.0; 10];
        xs.extend([10.0; 60]);
        let ys = run(&mut f, &xs);
        assert!(
            ys[10] > 0.0 && ys[10] < 10.0,
            "the step is smoothed: {}",
            ys[10]
        );
        assert!(ys.windows(2).all(|w| w[1] >= w[0] - 1e-12), "monotone");
        assert!(ys.iter().all(|&y| y <= 10.0 + 1e-9), "no overshoot");
        assert!(
            (ys[69] - 10.0).abs() < 0.01,
            "converged after 2 s: {}",
            ys[69]
        );
    }

    #[test]
    fn noise_on_a_sine_is_reduced() {
        // 0.25 Hz, ±30° sine at 30 frames/s with ±10° uniform noise from a fixed LCG.
        let mut seed = 12345u64;
        let mut noise = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 33) as f64 / (1u64 << 31) as f64 - 0.5) * 20.0
        };
        let truth: Vec<f64> = (0..300)
            .map(|i| 30.0 * (std::f64::consts::TAU * 0.25 * i as f64 * DT).sin())
            .collect();
        let noisy: Vec<f64> = truth.iter().map(|t| t + noise()).collect();
        let mut f = OneEuro::new(angles(), true);
        let smooth = run(&mut f, &noisy);
        let rms = |a: &[f64]| {
            (a.iter()
                .zip(&truth)
                .skip(30)
                .map(|(x, t)| (x - t).powi(2))
                .sum::<f64>()
                / (a.len() - 30) as f64)
                .sqrt()
        };
        let (before, after) = (rms(&noisy), rms(&smooth));
        assert!(after < 0.7 * before, "rms {before:.3} → {after:.3}");
    }

    #[test]
    fn angles_cross_180_without_sweeping_through_0() {
        let mut f = OneEuro::new(angles(), true);
        let ys = run(
            &mut f,
            &[170.0, 175.0, 179.0, -179.0, -175.0, -170.0, -170.0],
        );
        for y in &ys {
            assert!(y.abs() > 160.0, "{ys:?}");
        }
        assert!(ys[6] < 0.0, "follows to the negative side: {ys:?}");
        assert_eq!(wrap_degrees(180.0), 180.0);
        assert_eq!(wrap_degrees(-180.0), 180.0);
        assert_eq!(wrap_degrees(190.0), -170.0);
        assert_eq!(wrap_degrees(-540.0), 180.0);
    }

    #[test]
    fn filter_follows_timestamps() {
        // A plain 1.5 Hz low-pass (beta = 0): one 1/30 s step moves about as far as two 1/60 s steps,
        // α = 1 / (1 + τ/dt) with τ = 1 / (2π · 1.5): 0.239 vs 1 − (1 − 0.136)² = 0.254.
        let params = OneEuroParams {
            min_cutoff: 1.5,
            beta: 0.0,
            d_cutoff: 1.0,
        };
        let mut a = OneEuro::new(params, false);
        let mut b = OneEuro::new(params, false);
        a.filter(0.0, DT);
        b.filter(0.0, DT / 2.0);
        let ya = a.filter(10.0, DT);
        let yb1 = b.filter(10.0, DT / 2.0);
        let yb = b.filter(10.0, DT / 2.0);
        assert!(
            (ya - 2.39).abs() < 0.01 && (yb - 2.54).abs() < 0.01,
            "{ya} {yb}"
        );
        assert!(
            (yb1 - 1.36).abs() < 0.01,
            "half the time, less movement: {yb1}"
        );
        assert!(a.filter(10.0, DT) > ya);
        a.reset();
        assert_eq!(a.filter(-3.0, DT), -3.0);
    }

    #[test]
    fn ranges_clamp_outside_and_keep_inside() {
        let r = AngleRange {
            min: -30.0,
            max: 60.0,
        };
        assert_eq!(r.clamp(10.0), 10.0);
        assert_eq!(r.clamp(90.0), 60.0);
        assert_eq!(r.clamp(-100.0), -30.0);
        // Outside values go to the nearer end: 160° is 100° past 60° but 170° before −30°.
        assert_eq!(r.clamp(160.0), 60.0);
        // −170° is 130° past 60° and 140° before −30°; −160° is nearer to −30°.
        assert_eq!(r.clamp(-170.0), 60.0);
        assert_eq!(r.clamp(-160.0), -30.0);
        // A range across ±180: [170, 190] = 170° … −170°.
        let r = AngleRange {
            min: 170.0,
            max: 190.0,
        };
        assert_eq!(r.clamp(-175.0), -175.0);
        assert_eq!(r.clamp(175.0), 175.0);
        assert_eq!(r.clamp(150.0), 170.0);
        assert_eq!(r.clamp(-150.0), -170.0);
        let full = AngleRange {
            min: -180.0,
            max: 180.0,
        };
        assert_eq!(full.clamp(123.0), 123.0);
    }

    #[test]
    fn covering_ranges_take_the_shortest_arc() {
        let r = AngleRange::covering(&[10.0, -20.0, 40.0], 5.0).expect("range");
        assert_eq!((r.min, r.max), (-25.0, 45.0));
        let r = AngleRange::covering(&[175.0, -175.0, 179.0], 5.0).expect("range");
        assert_eq!((r.min, r.max), (170.0, 190.0));
        let r = AngleRange::covering(&[0.0, 120.0, -120.0], 5.0).expect("range");
        assert_eq!((r.min, r.max), (-120.0 - 5.0, 120.0 + 5.0));
        let r = AngleRange::covering(&[0.0, 90.0, 180.0, -90.0], 50.0).expect("range");
        assert!(r.is_full());
        assert!(AngleRange::covering(&[], 5.0).is_none());
    }

    fn arm_motion(elbow_z: &[f32]) -> Motion {
        let skeleton = two_joint_arm();
        let values = elbow_z
            .iter()
            .flat_map(|&z| [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, z, 1.0, -1.0])
            .collect();
        Motion::new(skeleton, DT, values).expect("motion")
    }

    #[test]
    fn limits_are_learned_per_channel_and_applied() {
        let limits =
            JointLimits::learn(&[arm_motion(&[0.0, 30.0]), arm_motion(&[-10.0, 90.0])], 5.0);
        assert_eq!(limits.frames, 4);
        // The root is not limited; the elbow's three rotations are.
        assert_eq!(limits.limits.len(), 3);
        assert_eq!(
            limits.get("elbow", Channel::Zrotation),
            Some(AngleRange {
                min: -15.0,
                max: 95.0
            })
        );
        assert_eq!(
            limits.get("elbow", Channel::Xrotation),
            Some(AngleRange {
                min: -4.0,
                max: 6.0
            })
        );
        let mut filter = PoseFilter::new(&two_joint_arm(), None, Some(&limits));
        let mut frame = [200.0, 5.0, 0.0, 170.0, 0.0, 0.0, 120.0, 3.0, -1.0];
        filter.apply(0.0, &mut frame);
        assert_eq!(frame, [200.0, 5.0, 0.0, 170.0, 0.0, 0.0, 95.0, 3.0, -1.0]);
    }

    #[test]
    fn pose_filter_smooths_switches_and_resets() {
        let skeleton = two_joint_arm();
        let mut off = PoseFilter::new(&skeleton, None, None);
        assert!(!off.smoothing_enabled() && !off.limits_enabled());
        let mut frame = [1.0, 2.0, 3.0, 179.0, 0.0, 0.0, 10.0, 0.0, 0.0];
        let copy = frame;
        off.apply(0.0, &mut frame);
        assert_eq!(frame, copy);

        let mut on = PoseFilter::new(&skeleton, Some(SmoothingParams::default()), None);
        let mut first = [0.0, 0.0, 0.0, 179.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        on.apply(0.0, &mut first);
        let mut second = [10.0, 0.0, 0.0, -179.0, 0.0, 0.0, 10.0, 0.0, 0.0];
        on.apply(1.0 / 30.0, &mut second);
        assert!(second[0] > 0.0 && second[0] < 10.0, "{}", second[0]);
        assert!(second[3].abs() > 178.0, "crosses ±180: {}", second[3]);
        on.reset();
        let mut third = [5.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        on.apply(2.0, &mut third);
        assert_eq!(third[0], 5.0, "after a reset the first frame passes");
    }

    #[test]
    fn limits_survive_a_toml_round_trip() {
        let limits = JointLimits::learn(&[arm_motion(&[175.0, -170.0, 179.5])], 2.5);
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join(JOINT_LIMITS_FILE);
        limits.save(&path).expect("save");
        let back = JointLimits::load(&path).expect("load");
        assert_eq!(back, limits);
        let r = back.get("elbow", Channel::Zrotation).expect("range");
        assert_eq!((r.min, r.max), (172.5, 192.5));
    }

    #[test]
    fn limits_of_real_mocap_keep_its_frames_and_round_trip() {
        let clip = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mocap/cmu_09_01_run.bvh");
        let motion = Motion::load(&clip).expect("clip");
        let limits = JointLimits::learn(std::slice::from_ref(&motion), DEFAULT_MARGIN_DEG);
        let text = limits.to_toml().expect("serialises");
        let back = JointLimits::parse(&text, Path::new("joint_limits.toml")).expect("parses");
        assert_eq!(back, limits);
        let mut filter = PoseFilter::new(&motion.skeleton, None, Some(&back));
        for frame in motion.frames() {
            let mut clamped = frame.to_vec();
            filter.apply(0.0, &mut clamped);
            assert_eq!(clamped, frame, "a training frame is inside its own limits");
        }
    }

    #[test]
    fn malformed_files_name_the_field() {
        let p = Path::new("joint_limits.toml");
        let good = JointLimits::learn(&[arm_motion(&[0.0, 30.0])], 5.0)
            .to_toml()
            .expect("serialises");
        JointLimits::parse(&good, p).expect("valid");
        let cases = [
            (good.replacen("version = 1", "version = 9", 1), "version"),
            (good.replacen("min = -5.0", "min = \"low\"", 1), "min"),
            (
                good.replacen("max = 35.0", "max = -50.0", 1),
                "limit[0].max",
            ),
            (
                good.replacen("channel = \"Zrotation\"", "channel = \"Xposition\"", 1),
                "limit[0].channel",
            ),
            (good.replacen("version = 1\n", "", 1), "version"),
            (format!("{good}\nextra = 1\n"), "extra"),
        ];
        for (text, field) in cases {
            assert_ne!(text, good, "{field}: the fixture did not change");
            let err = JointLimits::parse(&text, p).expect_err(field).to_string();
            assert!(
                err.contains(field) && err.contains("joint_limits.toml"),
                "{field}: {err}"
            );
        }
        let err = JointLimits::load(Path::new("/nonexistent/joint_limits.toml")).unwrap_err();
        assert!(err.to_string().contains("/nonexistent/joint_limits.toml"));
    }
}
