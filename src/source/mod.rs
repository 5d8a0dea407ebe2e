//! Frame sources: where the pictures of the marker suit come from.
//!
//! A [`FrameSource`] is a stream of RGB frames with timestamps. Three kinds
//! exist: a live V4L2 webcam ([`v4l2`]), a directory of numbered PNG/JPEG
//! frames ([`directory`]) and a YUV4MPEG2 file ([`y4m`]). [`open_source`]
//! picks one from a command-line style spec.
//!
//! The next stage, the segmenter, receives [`Frame`]s: an index counting from
//! 0, a timestamp measured from the start of the stream, and an 8-bit
//! [`image::RgbImage`] that always has the size reported by
//! [`FrameSource::size`]. Errors ([`SourceError`]) name the file or device and,
//! for per-frame errors, the frame index; a frame error does not end the
//! stream, so the caller may count it and ask for the next frame.

pub mod convert;
pub mod directory;
pub mod memory;
pub mod v4l2;
pub mod y4m;

use std::path::{Path, PathBuf};
use std::time::Duration;

/// One picture from a source.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Position in the stream, from 0; frames that failed still use up an index.
    pub index: u64,
    /// Time since the start of the stream (device clock, or index / fps for files).
    pub timestamp: Duration,
    /// The picture, always of the source's [`FrameSource::size`].
    pub image: image::RgbImage,
}

/// A stream of RGB frames with timestamps.
pub trait FrameSource {
    /// Next frame, Ok(None) at the end of the stream.
    ///
    /// After an `Err` for one frame the stream can be asked again: it moves on
    /// to the next frame, or returns `Ok(None)` if it cannot continue.
    fn next_frame(&mut self) -> Result<Option<Frame>, SourceError>;
    /// Width and height of every frame.
    fn size(&self) -> (u32, u32);
    /// Frames per second, if known.
    fn frame_rate(&self) -> Option<f64>;
    /// One line for logs, e.g. "/dev/video0 640x480 MJPG @30fps".
    fn describe(&self) -> String;
}

impl<S: FrameSource + ?Sized> FrameSource for Box<S> {
    fn next_frame(&mut self) -> Result<Option<Frame>, SourceError> {
        (**self).next_frame()
    }
    fn size(&self) -> (u32, u32) {
        (**self).size()
    }
    fn frame_rate(&self) -> Option<f64> {
        (**self).frame_rate()
    }
    fn describe(&self) -> String {
        (**self).describe()
    }
}

/// What the user asked for when opening a source.
#[derive(Debug, Clone, PartialEq)]
pub struct SourceOptions {
    /// Wanted frame size (cameras: the closest offered size is used; files ignore it).
    pub size: Option<(u32, u32)>,
    /// Wanted frame rate (cameras: the closest offered rate is used; Y4M files
    /// without an `F` tag use it as their rate).
    pub fps: Option<f64>,
    /// Frame rate assumed for a directory of frames, giving timestamps index / fps.
    pub fps_for_directory: f64,
}

impl Default for SourceOptions {
    fn default() -> Self {
        SourceOptions {
            size: None,
            fps: None,
            fps_for_directory: 30.0,
        }
    }
}

/// Everything that can go wrong while opening or reading a source.
#[derive(thiserror::Error, Debug)]
pub enum SourceError {
    #[error("camera {device} does not exist")]
    DeviceMissing { device: String },
    #[error("camera {device} is busy (another program is using it)")]
    DeviceBusy { device: String },
    #[error("camera {device} offers no usable format (need YUYV or MJPG); it offers: {}",
        if offered.is_empty() { "nothing (is it a metadata node?)".to_string() } else { offered.join(", ") })]
    NoUsableFormat {
        device: String,
        offered: Vec<String>,
    },
    #[error("camera {device}: {action} failed: {source}")]
    Device {
        device: String,
        action: &'static str,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot read {}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{source_name}: frame {index} is corrupt: {reason}")]
    CorruptFrame {
        source_name: String,
        index: u64,
        reason: String,
    },
    #[error("{source_name}: frame {index} is truncated: {expected} bytes expected, {got} found")]
    TruncatedFrame {
        source_name: String,
        index: u64,
        expected: usize,
        got: usize,
    },
    #[error("{}: bad header: {reason}", path.display())]
    BadHeader { path: PathBuf, reason: String },
    #[error("{}: unsupported: {reason}", path.display())]
    Unsupported { path: PathBuf, reason: String },
    #[error("{}: no PNG or JPEG frames in directory", path.display())]
    EmptyDirectory { path: PathBuf },
    #[error("{}: {}{reason}", path.display(), line.map(|l| format!("line {l}: ")).unwrap_or_default())]
    Timestamps {
        path: PathBuf,
        line: Option<usize>,
        reason: String,
    },
    #[error("{}: frame {index} is {}x{}, but the stream is {}x{}",
        path.display(), got.0, got.1, expected.0, expected.1)]
    SizeMismatch {
        path: PathBuf,
        index: u64,
        expected: (u32, u32),
        got: (u32, u32),
    },
    #[error("cannot open {spec:?} as a frame source: {reason}")]
    UnknownSpec { spec: String, reason: String },
}

impl SourceError {
    /// The frame this error is about when the stream can go on past it (a corrupt frame, or one
    /// of another size): callers skip and name it. `None` for an error that ends the stream.
    pub fn skipped_frame(&self) -> Option<u64> {
        match self {
            SourceError::CorruptFrame { index, .. } | SourceError::SizeMismatch { index, .. } => {
                Some(*index)
            }
            _ => None,
        }
    }
}

/// What a source spec names.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SourceSpec {
    /// A V4L2 device node, e.g. "/dev/video0" (also from a bare index "0").
    Device(PathBuf),
    /// A directory of numbered image frames.
    Directory(PathBuf),
    /// A YUV4MPEG2 file.
    Y4m(PathBuf),
}

/// Classifies a spec: a device index or `/dev/video*` path, an existing
/// directory, or a `*.y4m` file. Only looks at the file system for `is_dir`.
pub fn parse_spec(spec: &str) -> Result<SourceSpec, SourceError> {
    let trimmed = spec.trim();
    if !trimmed.is_empty() && trimmed.bytes().all(|b| b.is_ascii_digit()) {
        return match trimmed.parse::<u32>() {
            Ok(n) => Ok(SourceSpec::Device(PathBuf::from(format!("/dev/video{n}")))),
            Err(_) => Err(SourceError::UnknownSpec {
                spec: spec.to_string(),
                reason: "device index out of range".to_string(),
            }),
        };
    }
    let path = Path::new(trimmed);
    if trimmed.starts_with("/dev/video") || trimmed.starts_with("/dev/v4l/") {
        return Ok(SourceSpec::Device(path.to_path_buf()));
    }
    if path.is_dir() {
        return Ok(SourceSpec::Directory(path.to_path_buf()));
    }
    let is_y4m = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("y4m"));
    if is_y4m {
        return Ok(SourceSpec::Y4m(path.to_path_buf()));
    }
    let reason = if !path.exists() {
        "no such file or directory".to_string()
    } else if is_compressed_video(path) {
        // A phone's or a camera app's recording: no decoder for these is built in.
        format!(
            "a compressed video file, which suitcap does not decode; convert it to Y4M first, e.g. \
             `ffmpeg -i {trimmed:?} -pix_fmt yuv420p {:?}`",
            path.with_extension("y4m").display().to_string()
        )
    } else {
        "expected a camera (/dev/videoN or an index), a directory of frames or a .y4m file"
            .to_string()
    };
    Err(SourceError::UnknownSpec {
        spec: spec.to_string(),
        reason,
    })
}

/// Whether `path` names a compressed video container by its extension (MP4, QuickTime,
/// Matroska, WebM, AVI, MPEG transport streams).
fn is_compressed_video(path: &Path) -> bool {
    const VIDEO: [&str; 9] = [
        "mp4", "m4v", "mov", "mkv", "webm", "avi", "ts", "mts", "mpg",
    ];
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| VIDEO.iter().any(|v| e.eq_ignore_ascii_case(v)))
}

/// Opens the source named by `spec`: "/dev/videoN" or a device index like "0"
/// → V4L2 camera; a directory → numbered frames; a `*.y4m` file → Y4M.
pub fn open_source(
    spec: &str,
    options: &SourceOptions,
) -> Result<Box<dyn FrameSource + Send>, SourceError> {
    Ok(match parse_spec(spec)? {
        SourceSpec::Device(path) => Box::new(v4l2::V4l2Source::open(&path, options)?),
        SourceSpec::Directory(path) => Box::new(directory::DirectorySource::open(
            &path,
            options.fps_for_directory,
        )?),
        SourceSpec::Y4m(path) => Box::new(y4m::Y4mSource::open(&path, options.fps)?),
    })
}

/// Timestamp of frame `index` at a constant rate of `num/den` frames per second.
pub fn timestamp_at(index: u64, rate_num: u32, rate_den: u32) -> Duration {
    if rate_num == 0 {
        return Duration::ZERO;
    }
    let nanos = u128::from(index) * u128::from(rate_den) * 1_000_000_000 / u128::from(rate_num);
    Duration::from_nanos(u64::try_from(nanos).unwrap_or(u64::MAX))
}

/// Timestamp of frame `index` at `fps` frames per second (zero for a bad rate).
pub fn timestamp_at_fps(index: u64, fps: f64) -> Duration {
    if fps.is_finite() && fps > 0.0 {
        Duration::try_from_secs_f64(index as f64 / fps).unwrap_or(Duration::MAX)
    } else {
        Duration::ZERO
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_per_frame_errors_are_skipped_frames() {
        let corrupt = SourceError::CorruptFrame {
            source_name: "x".into(),
            index: 4,
            reason: "bad".into(),
        };
        let size = SourceError::SizeMismatch {
            path: PathBuf::from("x/000005.png"),
            index: 5,
            expected: (4, 4),
            got: (5, 4),
        };
        let truncated = SourceError::TruncatedFrame {
            source_name: "x".into(),
            index: 6,
            expected: 12,
            got: 3,
        };
        assert_eq!(corrupt.skipped_frame(), Some(4));
        assert_eq!(size.skipped_frame(), Some(5));
        assert_eq!(truncated.skipped_frame(), None);
    }

    #[test]
    fn specs_are_classified() {
        assert_eq!(
            parse_spec("0").unwrap(),
            SourceSpec::Device(PathBuf::from("/dev/video0"))
        );
        assert_eq!(
            parse_spec("/dev/video3").unwrap(),
            SourceSpec::Device(PathBuf::from("/dev/video3"))
        );
        let dir = tempfile::tempdir().unwrap();
        assert_eq!(
            parse_spec(dir.path().to_str().unwrap()).unwrap(),
            SourceSpec::Directory(dir.path().to_path_buf())
        );
        assert_eq!(
            parse_spec("clip.Y4M").unwrap(),
            SourceSpec::Y4m(PathBuf::from("clip.Y4M"))
        );
        assert!(matches!(
            parse_spec("nothing-here.mp4"),
            Err(SourceError::UnknownSpec { .. })
        ));
        assert!(matches!(
            parse_spec("99999999999999"),
            Err(SourceError::UnknownSpec { .. })
        ));
    }

    #[test]
    fn a_compressed_video_is_named_with_how_to_convert_it() {
        let dir = tempfile::tempdir().unwrap();
        let clip = dir.path().join("take.MOV");
        std::fs::write(&clip, b"not decoded").unwrap();
        let error = parse_spec(clip.to_str().unwrap()).unwrap_err().to_string();
        assert!(error.contains("compressed video"), "{error}");
        assert!(
            error.contains(&format!(
                "{:?}",
                dir.path().join("take.y4m").display().to_string()
            )),
            "{error}"
        );
        // Any other file is still told what is expected.
        let notes = dir.path().join("notes.txt");
        std::fs::write(&notes, b"").unwrap();
        let error = parse_spec(notes.to_str().unwrap()).unwrap_err().to_string();
        assert!(error.contains("a .y4m file"), "{error}");
    }

    #[test]
    fn open_missing_device_and_file() {
        let opts = SourceOptions::default();
        match open_source("/dev/video99", &opts) {
            Err(SourceError::DeviceMissing { device }) => assert_eq!(device, "/dev/video99"),
            Err(e) => panic!("wrong error {e}"),
            Ok(_) => panic!("opened a missing device"),
        }
        assert!(matches!(
            open_source("/no/such/clip.y4m", &opts),
            Err(SourceError::Io { .. })
        ));
    }

    #[test]
    fn open_source_dispatches_to_files() {
        let dir = tempfile::tempdir().unwrap();
        let frames = dir.path().join("frames");
        std::fs::create_dir(&frames).unwrap();
        image::RgbImage::new(4, 2)
            .save(frames.join("000000.png"))
            .unwrap();
        let opts = SourceOptions {
            fps_for_directory: 5.0,
            ..SourceOptions::default()
        };
        let src = open_source(frames.to_str().unwrap(), &opts).unwrap();
        assert_eq!((src.size(), src.frame_rate()), ((4, 2), Some(5.0)));
        assert!(src.describe().starts_with("frames dir"));

        let clip = dir.path().join("clip.y4m");
        std::fs::write(&clip, b"YUV4MPEG2 W2 H2 F25:1 C444\nFRAME\n000000000000").unwrap();
        let mut src = open_source(clip.to_str().unwrap(), &opts).unwrap();
        assert_eq!((src.size(), src.frame_rate()), ((2, 2), Some(25.0)));
        assert_eq!(src.next_frame().unwrap().unwrap().index, 0);
        assert!(src.next_frame().unwrap().is_none());
    }

    #[test]
    fn timestamps() {
        assert_eq!(timestamp_at(30, 30, 1), Duration::from_secs(1));
        assert_eq!(timestamp_at(30, 30000, 1001), Duration::from_millis(1001));
        assert_eq!(timestamp_at(5, 0, 1), Duration::ZERO);
        assert_eq!(timestamp_at_fps(15, 30.0), Duration::from_millis(500));
        assert_eq!(timestamp_at_fps(15, 0.0), Duration::ZERO);
    }

    #[test]
    fn errors_name_their_subject() {
        let e = SourceError::NoUsableFormat {
            device: "/dev/video0".into(),
            offered: vec!["H264 1920x1080 @30".into()],
        };
        assert!(e.to_string().contains("/dev/video0"));
        assert!(e.to_string().contains("H264 1920x1080"));
        let e = SourceError::SizeMismatch {
            path: "d/000003.png".into(),
            index: 3,
            expected: (4, 4),
            got: (5, 4),
        };
        assert!(e.to_string().contains("d/000003.png"));
        assert!(e.to_string().contains("frame 3"));
    }
}
