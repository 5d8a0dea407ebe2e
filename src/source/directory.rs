//! A directory of numbered PNG/JPEG frames as a frame source.
//!
//! Files are ordered by natural sort of their names (`frame_2.png` before
//! `frame_10.png`, `000001.png` before `000002.png`); files that are not
//! `.png`, `.jpg` or `.jpeg` are ignored. Frame `i` is the `i`-th file in that
//! order, stamped `i / fps` — or, when the directory holds a `timestamps.csv`
//! ([`TIMESTAMPS_FILE`], which `suitcap capture` writes as it records: one
//! `file,seconds` line per frame, the camera's own clock from the stream's
//! start), stamped with its time, so a frame the camera dropped leaves a gap
//! instead of shifting every later frame; the stream's rate is then the median
//! interval's.
//!
//! The segmenter receives RGB frames that all have the first frame's size. A
//! frame that cannot be read, is corrupt, or has another size gives an error
//! naming the file and index; the next call moves on to the following file,
//! so the caller can skip bad frames and count them.

use std::cmp::Ordering;
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::time::Duration;

use super::convert::decode_frame;
use super::{timestamp_at_fps, Frame, FrameSource, SourceError};

/// Reads numbered image files from a directory, in natural order.
#[derive(Debug)]
pub struct DirectorySource {
    dir: PathBuf,
    files: Vec<PathBuf>,
    next: usize,
    size: (u32, u32),
    fps: f64,
    /// Each file's time from `timestamps.csv`, in `files`' order.
    times: Option<Vec<f64>>,
}

/// The capture times of a frame directory's files, beside them.
pub const TIMESTAMPS_FILE: &str = "timestamps.csv";

/// The header line of [`TIMESTAMPS_FILE`].
pub const TIMESTAMPS_HEADER: &str = "file,seconds";

/// One line of [`TIMESTAMPS_FILE`].
pub fn timestamps_line(file_name: &str, seconds: f64) -> String {
    format!("{file_name},{seconds:.6}\n")
}

/// Parses [`TIMESTAMPS_FILE`] text into (file name, seconds) pairs; errors name the line.
pub fn parse_timestamps(text: &str, path: &Path) -> Result<Vec<(String, f64)>, SourceError> {
    let error = |line: usize, reason: String| SourceError::Timestamps {
        path: path.to_path_buf(),
        line: Some(line),
        reason,
    };
    let mut lines = text.lines().enumerate();
    match lines.next() {
        Some((_, header)) if header.trim() == TIMESTAMPS_HEADER => {}
        _ => {
            return Err(error(
                1,
                format!("expected the header '{TIMESTAMPS_HEADER}'"),
            ))
        }
    }
    let mut times = Vec::new();
    for (i, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let Some((file, seconds)) = line.rsplit_once(',') else {
            return Err(error(i + 1, "expected 'file,seconds'".into()));
        };
        let seconds: f64 = seconds
            .trim()
            .parse()
            .ok()
            .filter(|s: &f64| s.is_finite())
            .ok_or_else(|| error(i + 1, format!("field seconds: '{seconds}' is not a time")))?;
        times.push((file.trim().to_owned(), seconds));
    }
    Ok(times)
}

/// Each of `files`' time from the directory's [`TIMESTAMPS_FILE`]; `None` without one. Every
/// frame file must be listed, and the times must increase in the files' order.
fn read_times(dir: &Path, files: &[PathBuf]) -> Result<Option<Vec<f64>>, SourceError> {
    let path = dir.join(TIMESTAMPS_FILE);
    let text = match std::fs::read_to_string(&path) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(source) => return Err(SourceError::Io { path, source }),
    };
    let mut listed = parse_timestamps(&text, &path)?;
    listed.sort_by(|a, b| a.0.cmp(&b.0));
    let mut times: Vec<f64> = Vec::with_capacity(files.len());
    for file in files {
        let name = file_name(file);
        let Ok(k) = listed.binary_search_by(|(n, _)| n.as_str().cmp(&name)) else {
            return Err(SourceError::Timestamps {
                path,
                line: None,
                reason: format!("no time for frame file {name}"),
            });
        };
        let t = listed[k].1;
        if times.last().is_some_and(|&last| t <= last) {
            return Err(SourceError::Timestamps {
                path,
                line: None,
                reason: format!("{name}'s time {t} s is not after the frame before it"),
            });
        }
        times.push(t);
    }
    Ok(Some(times))
}

/// The median interval's rate of increasing `times`; `None` for fewer than two.
fn median_rate(times: &[f64]) -> Option<f64> {
    let mut intervals: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
    if intervals.is_empty() {
        return None;
    }
    let middle = intervals.len() / 2;
    let (_, median, _) = intervals.select_nth_unstable_by(middle, f64::total_cmp);
    Some(1.0 / *median)
}

/// Whether the file name has a PNG or JPEG extension (case-insensitive).
pub fn is_frame_file(path: &Path) -> bool {
    path.extension().and_then(OsStr::to_str).is_some_and(|e| {
        ["png", "jpg", "jpeg"]
            .iter()
            .any(|x| e.eq_ignore_ascii_case(x))
    })
}

/// Splits a name into runs of digits and runs of non-digits.
fn chunks(name: &str) -> impl Iterator<Item = &str> {
    let mut rest = name;
    std::iter::from_fn(move || {
        let first = rest.chars().next()?;
        let digit = first.is_ascii_digit();
        let end = rest
            .find(|c: char| c.is_ascii_digit() != digit)
            .unwrap_or(rest.len());
        let (chunk, tail) = rest.split_at(end);
        rest = tail;
        Some(chunk)
    })
}

/// Compares two digit runs by numeric value, without overflow.
fn cmp_digits(a: &str, b: &str) -> Ordering {
    let a_trim = a.trim_start_matches('0');
    let b_trim = b.trim_start_matches('0');
    a_trim
        .len()
        .cmp(&b_trim.len())
        .then_with(|| a_trim.cmp(b_trim))
}

/// Natural ("human") order: digit runs compare by value, other text by bytes;
/// exact ties (e.g. `1.png` vs `01.png`) fall back to plain byte order.
pub fn natural_cmp(a: &str, b: &str) -> Ordering {
    let mut ca = chunks(a);
    let mut cb = chunks(b);
    loop {
        match (ca.next(), cb.next()) {
            (None, None) => return a.cmp(b),
            (None, Some(_)) => return Ordering::Less,
            (Some(_), None) => return Ordering::Greater,
            (Some(x), Some(y)) => {
                let both_digits = x.starts_with(|c: char| c.is_ascii_digit())
                    && y.starts_with(|c: char| c.is_ascii_digit());
                let ord = if both_digits {
                    cmp_digits(x, y)
                } else {
                    x.cmp(y)
                };
                if ord != Ordering::Equal {
                    return ord;
                }
            }
        }
    }
}

/// The frame files of `dir` (PNG/JPEG only), naturally sorted by file name.
pub fn list_frame_files(dir: &Path) -> Result<Vec<PathBuf>, SourceError> {
    let io_err = |source| SourceError::Io {
        path: dir.to_path_buf(),
        source,
    };
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(io_err)? {
        let path = entry.map_err(io_err)?.path();
        if is_frame_file(&path) && path.is_file() {
            files.push(path);
        }
    }
    files.sort_by(|a, b| natural_cmp(&file_name(a), &file_name(b)));
    Ok(files)
}

/// The name of a PNG written for each frame file of `dir` (a mask, say): the frame's file stem
/// with `.png`, in the frames' order.
pub fn png_names_of_frames(dir: &Path) -> Result<Vec<String>, SourceError> {
    Ok(list_frame_files(dir)?
        .iter()
        .map(|f| {
            format!(
                "{}.png",
                f.file_stem()
                    .map(|s| s.to_string_lossy())
                    .unwrap_or_default()
            )
        })
        .collect())
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Width and height from an image file's header, without decoding pixels.
fn read_dimensions(path: &Path) -> Result<(u32, u32), String> {
    image::ImageReader::open(path)
        .map_err(|e| e.to_string())?
        .with_guessed_format()
        .map_err(|e| e.to_string())?
        .into_dimensions()
        .map_err(|e| e.to_string())
}

impl DirectorySource {
    /// Lists the frames of `dir`; the stream's size is that of the first frame
    /// whose header can be read. The timestamps come from the directory's
    /// `timestamps.csv` if it has one, else from `fps` (index / fps).
    pub fn open(dir: &Path, fps: f64) -> Result<Self, SourceError> {
        let files = list_frame_files(dir)?;
        let times = read_times(dir, &files)?;
        let fps = times.as_deref().and_then(median_rate).unwrap_or(fps);
        if files.is_empty() {
            return Err(SourceError::EmptyDirectory {
                path: dir.to_path_buf(),
            });
        }
        let mut first_error = None;
        let mut size = None;
        for (index, file) in files.iter().enumerate() {
            match read_dimensions(file) {
                Ok(dims) => {
                    size = Some(dims);
                    break;
                }
                Err(reason) => {
                    first_error.get_or_insert(SourceError::CorruptFrame {
                        source_name: file.display().to_string(),
                        index: index as u64,
                        reason,
                    });
                }
            }
        }
        let size = match (size, first_error) {
            (Some(size), _) => size,
            (None, Some(err)) => return Err(err),
            (None, None) => {
                return Err(SourceError::EmptyDirectory {
                    path: dir.to_path_buf(),
                })
            }
        };
        Ok(DirectorySource {
            dir: dir.to_path_buf(),
            files,
            next: 0,
            size,
            fps,
            times,
        })
    }

    /// Number of frame files found.
    pub fn len(&self) -> usize {
        self.files.len()
    }

    /// Whether there are no frame files (never true for an opened source).
    pub fn is_empty(&self) -> bool {
        self.files.is_empty()
    }

    /// The frame files, in stream order.
    pub fn files(&self) -> &[PathBuf] {
        &self.files
    }

    fn load(&self, index: usize) -> Result<image::RgbImage, SourceError> {
        let path = &self.files[index];
        let bytes = std::fs::read(path).map_err(|source| SourceError::Io {
            path: path.clone(),
            source,
        })?;
        let image = decode_frame(&bytes).map_err(|e| SourceError::CorruptFrame {
            source_name: path.display().to_string(),
            index: index as u64,
            reason: e.to_string(),
        })?;
        let got = image.dimensions();
        if got != self.size {
            return Err(SourceError::SizeMismatch {
                path: path.clone(),
                index: index as u64,
                expected: self.size,
                got,
            });
        }
        Ok(image)
    }
}

impl FrameSource for DirectorySource {
    fn next_frame(&mut self) -> Result<Option<Frame>, SourceError> {
        let index = self.next;
        if index >= self.files.len() {
            return Ok(None);
        }
        self.next += 1; // move on even if this frame fails
        let image = self.load(index)?;
        Ok(Some(Frame {
            index: index as u64,
            timestamp: match &self.times {
                Some(times) => Duration::from_secs_f64(times[index].max(0.0)),
                None => timestamp_at_fps(index as u64, self.fps),
            },
            image,
        }))
    }

    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn frame_rate(&self) -> Option<f64> {
        (self.fps.is_finite() && self.fps > 0.0).then_some(self.fps)
    }

    fn describe(&self) -> String {
        format!(
            "frames dir {} ({} frames, {}x{})",
            self.dir.display(),
            self.files.len(),
            self.size.0,
            self.size.1
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::{ImageFormat, Rgb, RgbImage};
    use std::time::Duration;

    fn write_png(dir: &Path, name: &str, w: u32, h: u32, colour: [u8; 3]) {
        RgbImage::from_pixel(w, h, Rgb(colour))
            .save_with_format(dir.join(name), ImageFormat::Png)
            .unwrap();
    }

    #[test]
    fn natural_order() {
        let mut names = vec![
            "frame_10.jpg",
            "frame_2.jpg",
            "frame_1.jpg",
            "a.png",
            "frame_02b.png",
        ];
        names.sort_by(|a, b| natural_cmp(a, b));
        assert_eq!(
            names,
            vec![
                "a.png",
                "frame_1.jpg",
                "frame_2.jpg",
                "frame_02b.png",
                "frame_10.jpg"
            ]
        );
        assert_eq!(natural_cmp("000009.png", "000010.png"), Ordering::Less);
        assert_eq!(
            natural_cmp(
                "99999999999999999999999.png",
                "100000000000000000000000.png"
            ),
            Ordering::Less
        );
        assert_ne!(natural_cmp("1.png", "01.png"), Ordering::Equal);
    }

    #[test]
    fn reads_frames_in_order_and_ignores_other_files() {
        let dir = tempfile::tempdir().unwrap();
        write_png(dir.path(), "frame_10.png", 4, 3, [0, 0, 255]);
        write_png(dir.path(), "frame_2.png", 4, 3, [0, 255, 0]);
        write_png(dir.path(), "frame_1.png", 4, 3, [255, 0, 0]);
        std::fs::write(dir.path().join("notes.txt"), "hello").unwrap();
        let mut src = DirectorySource::open(dir.path(), 10.0).unwrap();
        assert_eq!(src.size(), (4, 3));
        assert_eq!(src.frame_rate(), Some(10.0));
        assert!(src.describe().contains("(3 frames"));
        let colours: Vec<_> = std::iter::from_fn(|| src.next_frame().unwrap())
            .map(|f| (f.index, f.timestamp, f.image.get_pixel(0, 0).0))
            .collect();
        assert_eq!(
            colours,
            vec![
                (0, Duration::ZERO, [255, 0, 0]),
                (1, Duration::from_millis(100), [0, 255, 0]),
                (2, Duration::from_millis(200), [0, 0, 255]),
            ]
        );
        assert!(src.next_frame().unwrap().is_none());
    }

    #[test]
    fn timestamps_csv_gives_each_frame_its_capture_time() {
        let dir = tempfile::tempdir().unwrap();
        for name in ["000000.png", "000001.png", "000002.png", "000003.png"] {
            write_png(dir.path(), name, 4, 3, [9, 9, 9]);
        }
        // The camera dropped a frame between the second and the third.
        let mut text = format!("{TIMESTAMPS_HEADER}\n");
        for (name, t) in [
            ("000000.png", 0.0),
            ("000001.png", 0.04),
            ("000002.png", 0.12),
            ("000003.png", 0.16),
        ] {
            text += &timestamps_line(name, t);
        }
        std::fs::write(dir.path().join(TIMESTAMPS_FILE), &text).unwrap();
        let mut src = DirectorySource::open(dir.path(), 30.0).unwrap();
        // The median interval, 40 ms, not the 30 frames/s assumed without the file.
        assert!((src.frame_rate().unwrap() - 25.0).abs() < 1e-9);
        let times: Vec<u128> = std::iter::from_fn(|| src.next_frame().unwrap())
            .map(|f| f.timestamp.as_millis())
            .collect();
        assert_eq!(times, vec![0, 40, 120, 160]);

        // A frame file the file does not list, a time going back, a bad field: named errors.
        let short = text.lines().take(4).collect::<Vec<_>>().join("\n");
        let back = text.replace("000002.png,0.120000", "000002.png,0.010000");
        let bad = text.replace("0.040000", "soon");
        for (broken, named) in [
            (short, ["timestamps.csv", "000003.png"]),
            (back, ["000002.png", "not after"]),
            (bad, ["line 3", "seconds"]),
        ] {
            std::fs::write(dir.path().join(TIMESTAMPS_FILE), broken).unwrap();
            let err = DirectorySource::open(dir.path(), 30.0)
                .unwrap_err()
                .to_string();
            assert!(named.iter().all(|n| err.contains(n)), "{err}");
        }
    }

    #[test]
    fn jpeg_frames_work() {
        let dir = tempfile::tempdir().unwrap();
        RgbImage::from_pixel(8, 8, Rgb([200, 100, 50]))
            .save_with_format(dir.path().join("000000.jpg"), ImageFormat::Jpeg)
            .unwrap();
        let mut src = DirectorySource::open(dir.path(), 30.0).unwrap();
        let frame = src.next_frame().unwrap().unwrap();
        let [r, g, b] = frame.image.get_pixel(4, 4).0;
        assert!(r.abs_diff(200) < 8 && g.abs_diff(100) < 8 && b.abs_diff(50) < 8);
    }

    #[test]
    fn empty_directory_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("readme.md"), "x").unwrap();
        assert!(matches!(
            DirectorySource::open(dir.path(), 30.0),
            Err(SourceError::EmptyDirectory { .. })
        ));
    }

    #[test]
    fn corrupt_and_mismatched_frames_are_reported_and_skipped() {
        let dir = tempfile::tempdir().unwrap();
        write_png(dir.path(), "000000.png", 4, 4, [1, 2, 3]);
        // Truncated PNG: the first half of a valid file.
        write_png(dir.path(), "000001.png", 4, 4, [1, 2, 3]);
        let full = std::fs::read(dir.path().join("000001.png")).unwrap();
        std::fs::write(dir.path().join("000001.png"), &full[..full.len() / 2]).unwrap();
        // Not an image at all.
        std::fs::write(dir.path().join("000002.jpg"), b"not a jpeg").unwrap();
        write_png(dir.path(), "000003.png", 5, 4, [1, 2, 3]);
        // A JPEG cut short, which the decoder alone would fill with grey.
        let cut = dir.path().join("000004.jpg");
        RgbImage::from_fn(4, 4, |x, y| Rgb([60 * x as u8, 60 * y as u8, 9]))
            .save_with_format(&cut, ImageFormat::Jpeg)
            .unwrap();
        let full = std::fs::read(&cut).unwrap();
        std::fs::write(&cut, &full[..full.len() - 20]).unwrap();
        write_png(dir.path(), "000005.png", 4, 4, [9, 9, 9]);

        let mut src = DirectorySource::open(dir.path(), 30.0).unwrap();
        assert_eq!(src.next_frame().unwrap().unwrap().index, 0);
        match src.next_frame() {
            Err(SourceError::CorruptFrame {
                source_name, index, ..
            }) => {
                assert_eq!(index, 1);
                assert!(source_name.ends_with("000001.png"));
            }
            other => panic!("expected CorruptFrame, got {other:?}"),
        }
        match src.next_frame() {
            Err(SourceError::CorruptFrame {
                source_name, index, ..
            }) => {
                assert_eq!(index, 2);
                assert!(source_name.ends_with("000002.jpg"));
            }
            other => panic!("expected CorruptFrame, got {other:?}"),
        }
        match src.next_frame() {
            Err(SourceError::SizeMismatch {
                path,
                index,
                expected,
                got,
            }) => {
                assert_eq!((index, expected, got), (3, (4, 4), (5, 4)));
                assert!(path.ends_with("000003.png"));
            }
            other => panic!("expected SizeMismatch, got {other:?}"),
        }
        match src.next_frame() {
            Err(e @ SourceError::CorruptFrame { index: 4, .. }) => {
                let text = e.to_string();
                assert!(
                    text.contains("000004.jpg") && text.contains("truncated"),
                    "{text}"
                );
            }
            other => panic!("expected CorruptFrame, got {other:?}"),
        }
        let last = src.next_frame().unwrap().unwrap();
        assert_eq!((last.index, last.image.get_pixel(0, 0).0), (5, [9, 9, 9]));
        assert!(src.next_frame().unwrap().is_none());
    }

    #[test]
    fn corrupt_first_frame_does_not_stop_opening() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("0.png"), b"garbage").unwrap();
        write_png(dir.path(), "1.png", 2, 2, [0, 0, 0]);
        let mut src = DirectorySource::open(dir.path(), 30.0).unwrap();
        assert_eq!(src.size(), (2, 2));
        assert!(matches!(
            src.next_frame(),
            Err(SourceError::CorruptFrame { index: 0, .. })
        ));
        assert_eq!(src.next_frame().unwrap().unwrap().index, 1);
    }
}
