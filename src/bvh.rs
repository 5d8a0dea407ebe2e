//! BVH motion: reading, writing and resampling.
//!
//! A [`Motion`] is a [`Skeleton`] plus frames of channel values and a frame time. Files are parsed with
//! the `bvh_anim` crate (which accepts the shipped CMU clips' mixed CRLF/LF line endings, tabs,
//! exponents and negative zeros) and converted to plain data here, with every value checked finite.
//! Writing is done in this module: `bvh_anim` 0.4's `builder` does not yet build joints and its `Bvh`
//! has no way to change offsets or the frame count, so a scaled or regressed motion cannot be expressed
//! through it. Every file written here is read back by `bvh_anim` in the tests. Files are written to a
//! temporary name and renamed, so a crash never leaves a truncated BVH.
//!
//! The generator resamples a clip (often 120 frames/s) to the camera's rate with
//! [`Motion::resample`]; training and evaluation read the result as ground truth; the runtime writes
//! its estimated pose through [`Motion::write`].

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use glam::Vec3;

use crate::skeleton::{Channel, Joint, Skeleton, SkeletonError};

/// Frames at the start of a raw CMU capture (120 frames/s) that blend in from the calibration
/// T-pose (50 ms, the limbs swinging 15–40° a frame back into the take): the cloth bench and its
/// quality example start after them.
pub const CMU_CALIBRATION_FRAMES: usize = 6;

/// A skeleton with frames of channel values.
#[derive(Clone, Debug, PartialEq)]
pub struct Motion {
    pub skeleton: Skeleton,
    /// Seconds between frames.
    pub frame_time: f64,
    /// `frame_count × channel_count` values, frame-major.
    values: Vec<f32>,
}

/// The largest channel value taken as data: a million degrees is 2,778 turns, a million
/// centimetres 10 km, beyond any take (and there an `f32` keeps only a sixteenth of a unit).
/// Larger values are a damaged file, which forward kinematics would turn into noise.
pub const MAX_CHANNEL_VALUE: f32 = 1.0e6;

/// A BVH file that could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum BvhError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: not a valid BVH file{}: {message}", line.map(|l| format!(" (line {l})")).unwrap_or_default())]
    Parse {
        path: PathBuf,
        line: Option<usize>,
        message: String,
    },
    #[error(
        "{path}: frame {frame}, channel {channel} ({joint} {channel_name}) is not a finite number, or beyond ±{MAX_CHANNEL_VALUE} (degrees or centimetres)"
    )]
    NotFinite {
        path: PathBuf,
        frame: usize,
        channel: usize,
        joint: String,
        channel_name: &'static str,
    },
    #[error("{path}: frame time {frame_time} s is not a positive number")]
    FrameTime { path: PathBuf, frame_time: f64 },
    #[error("{path}: the file holds no frames")]
    NoFrames { path: PathBuf },
    #[error("{path}: invalid hierarchy: {source}")]
    Hierarchy {
        path: PathBuf,
        source: SkeletonError,
    },
    #[error("frame {frame} has {got} values, the skeleton has {expected} channels")]
    FrameLength {
        frame: usize,
        got: usize,
        expected: usize,
    },
    #[error("{path}: cannot write: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// Why a clip cannot be resampled as asked.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ResampleError {
    #[error("the target frame rate {0} is not a positive number")]
    BadRate(f64),
    #[error("start frame {start} is past the clip's last frame {last}")]
    StartPastEnd { start: usize, last: usize },
    #[error("{wanted} frames at {fps} frames/s from frame {start} need source frame {needed}, the clip ends at {last}: at most {available} frames fit")]
    TooLong {
        wanted: usize,
        fps: f64,
        start: usize,
        needed: usize,
        last: usize,
        available: usize,
    },
}

impl Motion {
    /// A motion from plain parts. `values` must hold whole frames of `skeleton.channel_count()` values.
    pub fn new(skeleton: Skeleton, frame_time: f64, values: Vec<f32>) -> Result<Motion, BvhError> {
        let channels = skeleton.channel_count();
        if channels > 0 && !values.len().is_multiple_of(channels) {
            return Err(BvhError::FrameLength {
                frame: values.len() / channels,
                got: values.len() % channels,
                expected: channels,
            });
        }
        Ok(Motion {
            skeleton,
            frame_time,
            values,
        })
    }

    /// Reads a BVH file; errors name the file and, where the parser knows it, the line.
    pub fn load(path: &Path) -> Result<Motion, BvhError> {
        let bytes = std::fs::read(path).map_err(|source| BvhError::Io {
            path: path.to_owned(),
            source,
        })?;
        Motion::parse(&bytes, path)
    }

    /// Parses BVH bytes; `path` is only used to name the source in errors.
    pub fn parse(bytes: &[u8], path: &Path) -> Result<Motion, BvhError> {
        let parse_error = |line: Option<usize>, message: String| BvhError::Parse {
            path: path.to_owned(),
            line,
            message,
        };
        check_counts(bytes).map_err(|(line, message)| parse_error(Some(line), message))?;
        let bvh = parse_without_panic(bytes)
            .map_err(|message| parse_error(None, message))?
            .map_err(|e| parse_error(e.line(), e.to_string()))?;

        let mut joints = Vec::new();
        let mut first_channel = 0;
        for joint in bvh.joints() {
            let data = joint.data();
            let mut channels = Vec::with_capacity(data.channels().len());
            for channel in data.channels() {
                if channel.motion_index() != first_channel + channels.len() {
                    return Err(parse_error(
                        None,
                        format!("joint '{}': channels are not in file order", data.name()),
                    ));
                }
                channels.push(convert_channel(channel.channel_type()));
            }
            let offset = data.offset();
            joints.push(Joint {
                name: data.name().to_string(),
                parent: data.parent_index(),
                offset: Vec3::new(offset.x, offset.y, offset.z),
                first_channel,
                channels,
                end_site: data.end_site().map(|e| Vec3::new(e.x, e.y, e.z)),
            });
            first_channel += data.channels().len();
        }
        let skeleton = Skeleton::new(joints).map_err(|source| BvhError::Hierarchy {
            path: path.to_owned(),
            source,
        })?;

        let frame_time = bvh.frame_time().as_secs_f64();
        if !(frame_time > 0.0 && frame_time.is_finite()) {
            return Err(BvhError::FrameTime {
                path: path.to_owned(),
                frame_time,
            });
        }
        let channel_count = skeleton.channel_count();
        let mut values = Vec::with_capacity(bvh.frames().len() * channel_count);
        for (frame, data) in bvh.frames().enumerate() {
            let slice = data.as_slice();
            if slice.len() != channel_count {
                return Err(parse_error(
                    None,
                    format!(
                        "frame {frame} has {} values, expected {channel_count}",
                        slice.len()
                    ),
                ));
            }
            if let Some(channel) = slice
                .iter()
                .position(|v| !v.is_finite() || v.abs() > MAX_CHANNEL_VALUE)
            {
                let (joint, channel_name) = channel_owner(&skeleton, channel);
                return Err(BvhError::NotFinite {
                    path: path.to_owned(),
                    frame,
                    channel,
                    joint,
                    channel_name,
                });
            }
            values.extend_from_slice(slice);
        }
        if values.is_empty() {
            return Err(BvhError::NoFrames {
                path: path.to_owned(),
            });
        }
        Ok(Motion {
            skeleton,
            frame_time,
            values,
        })
    }

    pub fn frame_count(&self) -> usize {
        match self.skeleton.channel_count() {
            0 => 0,
            n => self.values.len() / n,
        }
    }

    /// Frames per second (1 / frame time).
    pub fn frame_rate(&self) -> f64 {
        1.0 / self.frame_time
    }

    /// The channel values of frame `index`. Panics if `index >= frame_count()`.
    pub fn frame(&self, index: usize) -> &[f32] {
        let n = self.skeleton.channel_count();
        &self.values[index * n..(index + 1) * n]
    }

    /// The fastest joint `name` moves between two consecutive frames, in the file's units per
    /// second (centimetres for the shipped clips); `None` if the skeleton has no such joint or the
    /// motion fewer than two frames. For the cloth benchmark's "hand speed" (a fast limb that a
    /// garment must not let through).
    pub fn peak_joint_speed(&self, name: &str) -> Option<f32> {
        let joint = self.skeleton.find(name)?;
        let positions: Vec<_> = self
            .frames()
            .map(|f| self.skeleton.joint_positions(f)[joint])
            .collect();
        positions
            .windows(2)
            .map(|w| w[0].distance(w[1]) * self.frame_rate() as f32)
            .reduce(f32::max)
    }

    pub fn frames(&self) -> impl ExactSizeIterator<Item = &[f32]> + '_ {
        self.values
            .chunks_exact(self.skeleton.channel_count().max(1))
    }

    /// All values, frame-major.
    pub fn values(&self) -> &[f32] {
        &self.values
    }

    /// Appends one frame; its length must equal the channel count.
    pub fn push_frame(&mut self, frame: &[f32]) -> Result<(), BvhError> {
        let expected = self.skeleton.channel_count();
        if frame.len() != expected {
            return Err(BvhError::FrameLength {
                frame: self.frame_count(),
                got: frame.len(),
                expected,
            });
        }
        self.values.extend_from_slice(frame);
        Ok(())
    }

    /// The source frame that output frame `k` at `fps` starting at source frame `start` shows:
    /// the nearest source frame to time `k / fps` after `start`. Nearest (not interpolated) keeps the
    /// ground truth an exact recorded pose.
    pub fn source_frame_for(&self, start: usize, k: usize, fps: f64) -> usize {
        start + ((k as f64 / fps) / self.frame_time).round() as usize
    }

    /// Resamples `count` frames (or as many as fit, if `None`) at `fps` starting at source frame `start`.
    /// Returns the resampled motion and, for each output frame, the source frame it was taken from.
    pub fn resample(
        &self,
        start: usize,
        count: Option<usize>,
        fps: f64,
    ) -> Result<(Motion, Vec<usize>), ResampleError> {
        if !(fps > 0.0 && fps.is_finite()) {
            return Err(ResampleError::BadRate(fps));
        }
        let last = self.frame_count().saturating_sub(1);
        if start > last {
            return Err(ResampleError::StartPastEnd { start, last });
        }
        let available = (0..)
            .take_while(|&k| self.source_frame_for(start, k, fps) <= last)
            .count();
        let count = match count {
            Some(wanted) if wanted > available => {
                return Err(ResampleError::TooLong {
                    wanted,
                    fps,
                    start,
                    needed: self.source_frame_for(start, wanted - 1, fps),
                    last,
                    available,
                })
            }
            Some(wanted) => wanted,
            None => available,
        };
        let sources: Vec<usize> = (0..count)
            .map(|k| self.source_frame_for(start, k, fps))
            .collect();
        let mut values = Vec::with_capacity(count * self.skeleton.channel_count());
        for &s in &sources {
            values.extend_from_slice(self.frame(s));
        }
        let motion = Motion {
            skeleton: self.skeleton.clone(),
            frame_time: 1.0 / fps,
            values,
        };
        Ok((motion, sources))
    }

    /// The same motion on a different skeleton of the same layout (e.g. one scaled to a subject), with
    /// each frame's values passed through `f(frame values)` (e.g. to scale root translation).
    pub fn with_skeleton(&self, skeleton: Skeleton, mut f: impl FnMut(&mut [f32])) -> Motion {
        let mut values = self.values.clone();
        for frame in values.chunks_exact_mut(self.skeleton.channel_count().max(1)) {
            f(frame);
        }
        Motion {
            skeleton,
            frame_time: self.frame_time,
            values,
        }
    }

    /// The BVH text of this motion.
    pub fn to_bvh_string(&self) -> String {
        let mut out = String::with_capacity(256 + self.values.len() * 10);
        out.push_str("HIERARCHY\n");
        let joints = self.skeleton.joints();
        let depth_of = |mut index: usize| {
            let mut depth = 0;
            while let Some(parent) = joints[index].parent {
                depth += 1;
                index = parent;
            }
            depth
        };
        let mut open: Vec<usize> = Vec::new(); // stack of joints whose braces are open
        for (index, joint) in joints.iter().enumerate() {
            while let Some(&top) = open.last() {
                if Some(top) == joint.parent {
                    break;
                }
                close_joint(&mut out, joints, top, depth_of(top));
                open.pop();
            }
            let depth = depth_of(index);
            let pad = "\t".repeat(depth);
            let keyword = if joint.parent.is_none() {
                "ROOT"
            } else {
                "JOINT"
            };
            let _ = writeln!(out, "{pad}{keyword} {}", joint.name);
            let _ = writeln!(out, "{pad}{{");
            let _ = writeln!(out, "{pad}\tOFFSET {}", format_vec(joint.offset));
            let names: Vec<&str> = joint.channels.iter().map(|c| c.name()).collect();
            let _ = writeln!(out, "{pad}\tCHANNELS {} {}", names.len(), names.join(" "));
            open.push(index);
        }
        while let Some(top) = open.pop() {
            close_joint(&mut out, joints, top, depth_of(top));
        }
        let _ = writeln!(out, "MOTION");
        let _ = writeln!(out, "Frames: {}", self.frame_count());
        let _ = writeln!(out, "Frame Time: {:.8}", self.frame_time);
        for frame in self.frames() {
            let line: Vec<String> = frame.iter().map(|&v| format_number(v)).collect();
            out.push_str(&line.join(" "));
            out.push('\n');
        }
        out
    }

    /// Writes the motion as BVH to `path` through a temporary file and a rename, so that an
    /// interrupted write never leaves a truncated file behind.
    pub fn write(&self, path: &Path) -> Result<(), BvhError> {
        crate::io::write_atomic(path, self.to_bvh_string().as_bytes()).map_err(|source| {
            BvhError::Write {
                path: path.to_owned(),
                source,
            }
        })
    }
}

/// Most channels a BVH joint can have (three positions, three rotations).
const MAX_JOINT_CHANNELS: u64 = 6;

/// Rejects counts that would make `bvh_anim` 0.4 reserve memory before reading the data it counts
/// (a joint's declared `CHANNELS` count, and channels × `Frames` values): a failed allocation aborts
/// the process, which no error handling can catch. Every value takes at least one byte, so the
/// declared frames must fit in the file. Errors carry the 1-based line.
fn check_counts(bytes: &[u8]) -> Result<(), (usize, String)> {
    let number = |t: Option<&[u8]>| std::str::from_utf8(t?).ok()?.parse::<u64>().ok();
    let mut channels = 0u64;
    for (n, line) in bytes.split(|&b| b == b'\n').enumerate() {
        let mut tokens = line
            .split(|&b| b.is_ascii_whitespace() || b == b':')
            .filter(|t| !t.is_empty());
        match tokens.next() {
            Some(b"CHANNELS") => {
                if let Some(declared) = number(tokens.next()).filter(|&d| d > MAX_JOINT_CHANNELS) {
                    return Err((
                        n + 1,
                        format!("CHANNELS {declared}: a joint has at most {MAX_JOINT_CHANNELS} channels"),
                    ));
                }
                channels += tokens.count() as u64;
            }
            Some(b"Frames") => {
                if let Some(frames) = number(tokens.next()) {
                    if u128::from(frames) * u128::from(channels.max(1)) > bytes.len() as u128 {
                        return Err((
                            n + 1,
                            format!(
                                "Frames: {frames} frames of {channels} channels are more values than the file holds"
                            ),
                        ));
                    }
                }
            }
            _ => {}
        }
    }
    Ok(())
}

thread_local! {
    /// Set while `bvh_anim` runs on this thread, so its panics are not printed.
    static QUIET_PANICS: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// `bvh_anim::from_bytes`, with its panics on malformed input (0.4 panics on e.g. a `ROOT` without
/// a name or an unexpected `JOINT`) turned into an error message. The panic hook is wrapped once so
/// that those panics print nothing; every other panic goes to the previous hook as before.
fn parse_without_panic(
    bytes: &[u8],
) -> Result<Result<bvh_anim::Bvh, bvh_anim::errors::LoadError>, String> {
    static HOOK: std::sync::Once = std::sync::Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !QUIET_PANICS.with(std::cell::Cell::get) {
                previous(info);
            }
        }));
    });
    QUIET_PANICS.with(|q| q.set(true));
    let result = std::panic::catch_unwind(|| bvh_anim::from_bytes(bytes));
    QUIET_PANICS.with(|q| q.set(false));
    result.map_err(|payload| {
        let reason = payload
            .downcast_ref::<&str>()
            .map(|s| (*s).to_owned())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "the parser gave up".to_owned());
        format!("malformed hierarchy: {reason}")
    })
}

fn close_joint(out: &mut String, joints: &[Joint], index: usize, depth: usize) {
    let pad = "\t".repeat(depth);
    // A leaf needs an End Site to be read back as a joint (bvh_anim drops a childless joint
    // without one), so write a zero-length one when the source had none.
    let leaf = !joints.iter().any(|j| j.parent == Some(index));
    let end_site = joints[index].end_site.or(leaf.then_some(Vec3::ZERO));
    if let Some(end) = end_site {
        let _ = writeln!(out, "{pad}\tEnd Site");
        let _ = writeln!(out, "{pad}\t{{");
        let _ = writeln!(out, "{pad}\t\tOFFSET {}", format_vec(end));
        let _ = writeln!(out, "{pad}\t}}");
    }
    let _ = writeln!(out, "{pad}}}");
}

fn format_vec(v: Vec3) -> String {
    format!(
        "{} {} {}",
        format_number(v.x),
        format_number(v.y),
        format_number(v.z)
    )
}

/// Six decimals, trailing zeros trimmed: exact to 5e-7 and short for the many zeros of a mocap file.
fn format_number(v: f32) -> String {
    let mut s = format!("{v:.6}");
    if s.contains('.') {
        while s.ends_with('0') {
            s.pop();
        }
        if s.ends_with('.') {
            s.pop();
        }
    }
    if s == "-0" {
        s = "0".into();
    }
    s
}

fn convert_channel(channel: bvh_anim::ChannelType) -> Channel {
    use bvh_anim::ChannelType as C;
    match channel {
        C::PositionX => Channel::Xposition,
        C::PositionY => Channel::Yposition,
        C::PositionZ => Channel::Zposition,
        C::RotationX => Channel::Xrotation,
        C::RotationY => Channel::Yrotation,
        C::RotationZ => Channel::Zrotation,
    }
}

/// The joint and channel name that own value `channel` of a frame.
fn channel_owner(skeleton: &Skeleton, channel: usize) -> (String, &'static str) {
    for joint in skeleton.joints() {
        if channel >= joint.first_channel && channel < joint.first_channel + joint.channels.len() {
            return (
                joint.name.clone(),
                joint.channels[channel - joint.first_channel].name(),
            );
        }
    }
    (String::from("?"), "?")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skeleton::tests::two_joint_arm;
    use proptest::prelude::*;

    const TINY: &str = "HIERARCHY\r\nROOT hip\r\n{\r\n\tOFFSET 0 0 0\r\n\tCHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\r\n\tJOINT knee\r\n\t{\r\n\t\tOFFSET 0 -40 0\r\n\t\tCHANNELS 3 Zrotation Xrotation Yrotation\r\n\t\tEnd Site\r\n\t\t{\r\n\t\t\tOFFSET 0 -45 0\r\n\t\t}\r\n\t}\r\n}\r\nMOTION\r\nFrames:\t3\r\nFrame Time:\t0.00833333\r\n0 90 0 0 0 0 10 -0.0 0\n0 90 1 0 0 0 20 2.5e-1 0\n0 90 2 0 0 0 30 0 0\n";

    fn tiny() -> Motion {
        Motion::parse(TINY.as_bytes(), Path::new("tiny.bvh")).expect("tiny parses")
    }

    #[test]
    fn peak_joint_speed_is_the_fastest_step_times_the_frame_rate() {
        // The hip moves 1 unit along Z a frame at 120 frames/s, unrotated, so the knee below it
        // moves with it; the knee's own turn moves only what hangs from it.
        let m = tiny();
        let hip = m.peak_joint_speed("hip").expect("hip");
        assert!((hip - 120.0).abs() < 0.01, "{hip}");
        let knee = m.peak_joint_speed("knee").expect("knee");
        assert!((knee - 120.0).abs() < 0.01, "{knee}");
        assert_eq!(m.peak_joint_speed("nose"), None);
    }

    #[test]
    fn parses_crlf_tabs_exponents_and_negative_zero() {
        let m = tiny();
        assert_eq!(m.frame_count(), 3);
        assert_eq!(m.skeleton.len(), 2);
        assert_eq!(
            m.skeleton.joint(1).end_site,
            Some(Vec3::new(0.0, -45.0, 0.0))
        );
        assert_eq!(m.frame(1)[7], 0.25);
        assert!((m.frame_rate() - 120.0).abs() < 0.01);
    }

    #[test]
    fn write_then_read_gives_the_same_motion() {
        let m = tiny();
        let text = m.to_bvh_string();
        let back = Motion::parse(text.as_bytes(), Path::new("back.bvh")).expect("reads back");
        assert_eq!(back.skeleton, m.skeleton);
        assert_eq!(back.values(), m.values());
        assert!((back.frame_time - m.frame_time).abs() < 1e-8);
    }

    #[test]
    fn shipped_clip_survives_a_round_trip() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mocap/cmu_09_01_run.bvh");
        let m = Motion::load(&path).expect("shipped clip loads");
        assert_eq!(m.skeleton.len(), 43);
        assert_eq!(m.skeleton.channel_count(), 132);
        let back =
            Motion::parse(m.to_bvh_string().as_bytes(), Path::new("back.bvh")).expect("back");
        assert_eq!(back.frame_count(), m.frame_count());
        let worst = back
            .values()
            .iter()
            .zip(m.values())
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f32::max);
        assert!(worst < 1e-5, "worst difference {worst}");
    }

    #[test]
    fn malformed_files_are_errors_naming_the_file() {
        let truncated = &TINY[..TINY.len() - 20];
        let err = Motion::parse(truncated.as_bytes(), Path::new("cut.bvh")).unwrap_err();
        assert!(err.to_string().starts_with("cut.bvh"), "{err}");
        let garbage = TINY.replace("20 2.5e-1", "20 abc");
        let err = Motion::parse(garbage.as_bytes(), Path::new("bad.bvh")).unwrap_err();
        assert!(err.to_string().contains("bad.bvh"), "{err}");
        let nan = TINY.replace("20 2.5e-1", "20 nan");
        let err = Motion::parse(nan.as_bytes(), Path::new("nan.bvh")).unwrap_err();
        assert!(err.to_string().contains("nan.bvh"), "{err}");
        // A damaged value too large for any angle or position is named like a NaN; a spinning
        // joint's unwrapped angle is not.
        for (value, ok) in [("1e30", false), ("-2e6", false), ("3600", true)] {
            let text = TINY.replace("20 2.5e-1", &format!("20 {value}"));
            let result = Motion::parse(text.as_bytes(), Path::new("big.bvh"));
            assert_eq!(result.is_ok(), ok, "{value}");
            if let Err(err) = result {
                assert!(matches!(err, BvhError::NotFinite { .. }), "{err}");
            }
        }
        let err = Motion::parse(b"not a bvh", Path::new("x.bvh")).unwrap_err();
        assert!(err.to_string().contains("x.bvh"), "{err}");
        let err = Motion::load(Path::new("/nonexistent/clip.bvh")).unwrap_err();
        assert!(err.to_string().contains("/nonexistent/clip.bvh"), "{err}");
    }

    #[test]
    fn resampling_120_to_30_takes_every_fourth_frame() {
        let skeleton = two_joint_arm();
        let values: Vec<f32> = (0..100)
            .flat_map(|f| std::iter::repeat_n(f as f32, 9))
            .collect();
        let m = Motion::new(skeleton, 1.0 / 120.0, values).expect("motion");
        let (r, sources) = m.resample(10, Some(5), 30.0).expect("fits");
        assert_eq!(sources, vec![10, 14, 18, 22, 26]);
        assert_eq!(r.frame(3)[0], 22.0);
        assert!((r.frame_rate() - 30.0).abs() < 1e-9);
    }

    #[test]
    fn resampling_120_to_25_lands_on_the_nearest_frames() {
        let skeleton = two_joint_arm();
        let m = Motion::new(skeleton, 1.0 / 120.0, vec![0.0; 9 * 60]).expect("motion");
        let (_, sources) = m.resample(0, None, 25.0).expect("fits");
        // k/25 s × 120 = 4.8 k → 0, 4.8, 9.6, 14.4, 19.2, 24, 28.8, … rounded.
        assert_eq!(&sources[..8], &[0, 5, 10, 14, 19, 24, 29, 34]);
        assert_eq!(*sources.last().expect("some"), 58);
        assert!(matches!(
            m.resample(0, Some(20), 25.0),
            Err(ResampleError::TooLong { available: 13, .. })
        ));
        assert!(matches!(
            m.resample(60, None, 25.0),
            Err(ResampleError::StartPastEnd { .. })
        ));
    }

    proptest! {
        #[test]
        fn any_frames_survive_a_write_read_round_trip(
            values in proptest::collection::vec(-360.0f32..360.0, 9..90)
        ) {
            let n = values.len() / 9 * 9;
            let m = Motion::new(two_joint_arm(), 1.0 / 30.0, values[..n].to_vec()).expect("whole frames");
            let back = Motion::parse(m.to_bvh_string().as_bytes(), Path::new("p.bvh")).expect("reads back");
            prop_assert_eq!(back.frame_count(), m.frame_count());
            for (a, b) in back.values().iter().zip(m.values()) {
                prop_assert!((a - b).abs() <= 1e-4, "{} vs {}", a, b);
            }
        }
    }
}
