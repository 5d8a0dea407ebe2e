//! YUV4MPEG2 (`.y4m`) files: a hand-written reader used as a frame source,
//! and a writer the project uses for preview output.
//!
//! A Y4M file is one header line (`YUV4MPEG2 W640 H480 F30:1 Ip A1:1 C420jpeg`)
//! followed by frames, each a `FRAME` line (optional parameters, ignored) and
//! the raw planes Y, then Cb, then Cr. Supported colour tags: `420`, `420jpeg`,
//! `420paldv`, `420mpeg2` (all read as 4:2:0 with nearest chroma upsampling),
//! `444` and `mono`; `420jpeg` is assumed when `C` is absent. Interlaced
//! files, other subsamplings and high bit depths are rejected with a clear
//! error. Samples are BT.601 limited range (`mono`: full range) unless the
//! ffmpeg extension `XCOLORRANGE=FULL|LIMITED` says otherwise.
//!
//! The segmenter receives RGB frames stamped `index / F`. A truncated final
//! frame gives [`SourceError::TruncatedFrame`] naming its index, and the stream
//! ends. A frame that does not start with `FRAME` (a damaged file) gives
//! [`SourceError::CorruptFrame`]; the reader then looks for the next `FRAME`
//! line further on (six bytes that planar pixel data all but never holds) and
//! goes on from there, numbering the frames after it by the bytes passed over,
//! so that their timestamps stay right; without one the stream ends.

use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

use image::RgbImage;

use super::convert::{
    chroma_420_size, mono_to_rgb, rgb_to_yuv420p, rgb_to_yuv444p, yuv420p_to_rgb, yuv444p_to_rgb,
    YuvPlanes, YuvRange,
};
use super::{timestamp_at, timestamp_at_fps, Frame, FrameSource, SourceError};

/// Longest header or `FRAME` line accepted, in bytes.
pub const MAX_LINE: usize = 4096;
/// Largest width or height accepted.
pub const MAX_DIMENSION: u32 = 16384;

const MAGIC: &[u8] = b"YUV4MPEG2";
const FRAME_MARKER: &[u8] = b"FRAME";

/// Chroma layout of the 8-bit planes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Y4mColour {
    /// 4:2:0, chroma planes ceil(w/2) x ceil(h/2) (any siting).
    Yuv420,
    /// 4:4:4, three full planes.
    Yuv444,
    /// Luma only.
    Mono,
}

impl Y4mColour {
    /// Bytes of one frame's planes, `None` on overflow.
    pub fn frame_bytes(self, width: u32, height: u32) -> Option<usize> {
        let luma = (width as usize).checked_mul(height as usize)?;
        match self {
            Y4mColour::Yuv420 => {
                let (cw, ch) = chroma_420_size(width, height);
                let chroma = (cw as usize).checked_mul(ch as usize)?;
                luma.checked_add(chroma.checked_mul(2)?)
            }
            Y4mColour::Yuv444 => luma.checked_mul(3),
            Y4mColour::Mono => Some(luma),
        }
    }
}

/// The parsed stream header.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Y4mHeader {
    pub width: u32,
    pub height: u32,
    /// `F` as (numerator, denominator) frames per second; `None` if absent or `F0:0`.
    pub frame_rate: Option<(u32, u32)>,
    pub colour: Y4mColour,
    pub range: YuvRange,
}

/// Why a header line was refused.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum HeaderProblem {
    /// Not a valid Y4M header.
    Malformed(String),
    /// Valid, but a kind of video this reader does not handle.
    Unsupported(String),
}

fn malformed(reason: impl Into<String>) -> HeaderProblem {
    HeaderProblem::Malformed(reason.into())
}

fn parse_u32(text: &[u8]) -> Option<u32> {
    std::str::from_utf8(text).ok()?.parse().ok()
}

fn parse_ratio(text: &[u8]) -> Option<(u32, u32)> {
    let colon = text.iter().position(|&b| b == b':')?;
    Some((parse_u32(&text[..colon])?, parse_u32(&text[colon + 1..])?))
}

/// Parses a header line (without its trailing newline).
pub fn parse_header(line: &[u8]) -> Result<Y4mHeader, HeaderProblem> {
    let mut tokens = line
        .split(|&b| b == b' ')
        .map(|t| t.strip_suffix(b"\r").unwrap_or(t))
        .filter(|t| !t.is_empty());
    if tokens.next() != Some(MAGIC) {
        return Err(malformed("does not start with YUV4MPEG2"));
    }
    let (mut width, mut height, mut frame_rate, mut colour, mut range) =
        (None, None, None, Y4mColour::Yuv420, None);
    for token in tokens {
        let (tag, value) = (token[0], &token[1..]);
        let shown = String::from_utf8_lossy(token);
        match tag {
            b'W' => width = Some(parse_u32(value).ok_or_else(|| malformed(format!("bad width {shown}")))?),
            b'H' => height = Some(parse_u32(value).ok_or_else(|| malformed(format!("bad height {shown}")))?),
            b'F' => {
                let rate = parse_ratio(value)
                    .ok_or_else(|| malformed(format!("bad frame rate {shown}")))?;
                frame_rate = match rate {
                    (0, 0) => None,
                    (n, d) if n > 0 && d > 0 => Some((n, d)),
                    _ => return Err(malformed(format!("bad frame rate {shown}"))),
                };
            }
            b'I' => match value {
                b"p" | b"?" => {}
                b"t" | b"b" | b"m" => {
                    return Err(HeaderProblem::Unsupported(format!(
                        "interlaced video ({shown}); only progressive (Ip) is supported"
                    )))
                }
                _ => return Err(malformed(format!("bad interlacing tag {shown}"))),
            },
            b'C' => {
                colour = match value {
                    b"420" | b"420jpeg" | b"420paldv" | b"420mpeg2" => Y4mColour::Yuv420,
                    b"444" => Y4mColour::Yuv444,
                    b"mono" => Y4mColour::Mono,
                    v if v.windows(2).any(|p| p[0] == b'p' && p[1].is_ascii_digit())
                        || (v.starts_with(b"mono") && v.len() > 4) =>
                    {
                        return Err(HeaderProblem::Unsupported(format!(
                            "high bit depth colour space {shown}; only 8-bit is supported"
                        )))
                    }
                    _ => {
                        return Err(HeaderProblem::Unsupported(format!(
                            "colour space {shown}; supported: C420, C420jpeg, C420paldv, C420mpeg2, C444, Cmono"
                        )))
                    }
                }
            }
            b'X' => match value {
                b"COLORRANGE=FULL" => range = Some(YuvRange::Full),
                b"COLORRANGE=LIMITED" => range = Some(YuvRange::Limited),
                _ => {}
            },
            _ => {} // A (aspect) and unknown tags are ignored
        }
    }
    let width = width.ok_or_else(|| malformed("missing W (width)"))?;
    let height = height.ok_or_else(|| malformed("missing H (height)"))?;
    if width == 0 || height == 0 || width > MAX_DIMENSION || height > MAX_DIMENSION {
        return Err(malformed(format!(
            "size {width}x{height} outside 1..={MAX_DIMENSION}"
        )));
    }
    let default_range = match colour {
        Y4mColour::Mono => YuvRange::Full,
        _ => YuvRange::Limited,
    };
    Ok(Y4mHeader {
        width,
        height,
        frame_rate,
        colour,
        range: range.unwrap_or(default_range),
    })
}

/// A line read with a length limit.
#[derive(Debug, PartialEq, Eq)]
struct Line {
    bytes: Vec<u8>,
    /// Ended with `\n` (false at end of file or when the limit was hit).
    terminated: bool,
}

/// Reads up to and including `\n`, at most `limit + 1` bytes.
fn read_line<R: BufRead>(reader: &mut R, limit: usize) -> std::io::Result<Line> {
    let mut bytes = Vec::new();
    reader
        .take(limit as u64 + 1)
        .read_until(b'\n', &mut bytes)?;
    let terminated = bytes.last() == Some(&b'\n');
    if terminated {
        bytes.pop();
    }
    Ok(Line { bytes, terminated })
}

/// Splits a frame buffer into its planes and converts it to RGB.
pub fn frame_to_rgb(header: &Y4mHeader, data: &[u8]) -> Result<RgbImage, String> {
    let (w, h) = (header.width, header.height);
    let luma = w as usize * h as usize;
    let result = match header.colour {
        Y4mColour::Yuv420 => {
            let (cw, ch) = chroma_420_size(w, h);
            let chroma = cw as usize * ch as usize;
            let (y, rest) = data.split_at(luma.min(data.len()));
            let (u, v) = rest.split_at(chroma.min(rest.len()));
            yuv420p_to_rgb(y, u, v, w, h, header.range)
        }
        Y4mColour::Yuv444 => {
            let (y, rest) = data.split_at(luma.min(data.len()));
            let (u, v) = rest.split_at(luma.min(rest.len()));
            yuv444p_to_rgb(y, u, v, w, h, header.range)
        }
        Y4mColour::Mono => mono_to_rgb(data, w, h, header.range),
    };
    result.map_err(|e| e.to_string())
}

/// Reads frames from any buffered Y4M byte stream.
#[derive(Debug)]
pub struct Y4mReader<R> {
    reader: R,
    name: String,
    header: Y4mHeader,
    frame_bytes: usize,
    next_index: u64,
    ended: bool,
    /// The next frame's `FRAME` line was read while looking for it after a damaged frame.
    marker_read: bool,
    buffer: Vec<u8>,
}

impl<R: BufRead> Y4mReader<R> {
    /// Reads and checks the header. `name` (usually the path) is used in errors.
    pub fn new(mut reader: R, name: &str) -> Result<Self, SourceError> {
        let path = PathBuf::from(name);
        let line = read_line(&mut reader, MAX_LINE).map_err(|source| SourceError::Io {
            path: path.clone(),
            source,
        })?;
        if !line.terminated {
            let reason = if line.bytes.len() > MAX_LINE {
                format!("header line longer than {MAX_LINE} bytes")
            } else {
                "header line not terminated (empty or truncated file)".to_string()
            };
            return Err(SourceError::BadHeader { path, reason });
        }
        let header = parse_header(&line.bytes).map_err(|problem| match problem {
            HeaderProblem::Malformed(reason) => SourceError::BadHeader {
                path: path.clone(),
                reason,
            },
            HeaderProblem::Unsupported(reason) => SourceError::Unsupported {
                path: path.clone(),
                reason,
            },
        })?;
        let frame_bytes = header
            .colour
            .frame_bytes(header.width, header.height)
            .ok_or_else(|| SourceError::BadHeader {
                path: path.clone(),
                reason: "frame size overflows".to_string(),
            })?;
        Ok(Y4mReader {
            reader,
            name: name.to_string(),
            header,
            frame_bytes,
            next_index: 0,
            ended: false,
            marker_read: false,
            buffer: Vec::new(),
        })
    }

    /// The stream header.
    pub fn header(&self) -> &Y4mHeader {
        &self.header
    }

    fn corrupt(&mut self, index: u64, reason: String) -> SourceError {
        SourceError::CorruptFrame {
            source_name: self.name.clone(),
            index,
            reason,
        }
    }

    fn io_error(&mut self, source: std::io::Error) -> SourceError {
        self.ended = true;
        SourceError::Io {
            path: PathBuf::from(&self.name),
            source,
        }
    }

    fn truncated(&mut self, index: u64, got: usize) -> SourceError {
        self.ended = true;
        SourceError::TruncatedFrame {
            source_name: self.name.clone(),
            index,
            expected: self.frame_bytes,
            got,
        }
    }

    /// After frame `index` did not start with a FRAME line (`read` bytes of it consumed), reads
    /// on to the next FRAME line and through it, numbers the next frame by the bytes passed over
    /// (at least one frame on) and says how many frames on that is; `None` when the data ends
    /// first.
    fn find_next_marker(&mut self, index: u64, read: usize) -> std::io::Result<Option<u64>> {
        // Bytes of the marker matched so far, and bytes passed over before it.
        let (mut matched, mut passed) = (0usize, read);
        let delimiter = loop {
            let buf = self.reader.fill_buf()?;
            if buf.is_empty() {
                return Ok(None);
            }
            let (mut used, mut found) = (0, None);
            for &b in buf {
                used += 1;
                if matched == FRAME_MARKER.len() {
                    if matches!(b, b'\n' | b' ' | b'\r') {
                        found = Some(b);
                        break;
                    }
                    passed += matched;
                    matched = 0;
                }
                if b == FRAME_MARKER[matched] {
                    matched += 1;
                } else {
                    // "FRAME" has no repeated letter, so a mismatch restarts at this byte.
                    passed += matched;
                    matched = usize::from(b == FRAME_MARKER[0]);
                    passed += 1 - matched;
                }
            }
            self.reader.consume(used);
            if let Some(d) = found {
                break d;
            }
        };
        if delimiter != b'\n' {
            // The marker's parameters, up to its line's end.
            let rest = read_line(&mut self.reader, MAX_LINE)?;
            if !rest.terminated {
                return Ok(None);
            }
        }
        let frame = (self.frame_bytes + FRAME_MARKER.len() + 1) as f64;
        let lost = ((passed as f64 / frame).round() as u64).max(1);
        self.next_index = index + lost;
        self.marker_read = true;
        Ok(Some(lost))
    }

    /// Next frame as (index, image); `Ok(None)` at the end of the data or
    /// after an error that leaves the stream unreadable.
    pub fn read_frame(&mut self) -> Result<Option<(u64, RgbImage)>, SourceError> {
        if self.ended {
            return Ok(None);
        }
        let index = self.next_index;
        self.next_index += 1;
        if !std::mem::take(&mut self.marker_read) {
            let line = match read_line(&mut self.reader, MAX_LINE) {
                Ok(line) => line,
                Err(source) => return Err(self.io_error(source)),
            };
            if line.bytes.is_empty() && !line.terminated {
                self.ended = true;
                return Ok(None);
            }
            let has_marker = line.bytes.starts_with(FRAME_MARKER)
                && matches!(
                    line.bytes.get(FRAME_MARKER.len()),
                    None | Some(b' ') | Some(b'\r')
                );
            if !line.terminated && (has_marker || FRAME_MARKER.starts_with(&line.bytes)) {
                return Err(self.truncated(index, 0));
            }
            if !has_marker {
                let shown: String = String::from_utf8_lossy(&line.bytes)
                    .chars()
                    .take(20)
                    .collect();
                let read = line.bytes.len() + usize::from(line.terminated);
                let reason = match self.find_next_marker(index, read) {
                    Ok(Some(lost)) => format!(
                        "expected a FRAME line, found {shown:?}; going on at the next FRAME line, {lost} frame(s) on"
                    ),
                    Ok(None) => {
                        self.ended = true;
                        format!("expected a FRAME line, found {shown:?}; no FRAME line follows")
                    }
                    Err(source) => return Err(self.io_error(source)),
                };
                return Err(self.corrupt(index, reason));
            }
        }
        self.buffer.clear();
        let got = match (&mut self.reader)
            .take(self.frame_bytes as u64)
            .read_to_end(&mut self.buffer)
        {
            Ok(got) => got,
            Err(source) => return Err(self.io_error(source)),
        };
        if got < self.frame_bytes {
            return Err(self.truncated(index, got));
        }
        match frame_to_rgb(&self.header, &self.buffer) {
            Ok(image) => Ok(Some((index, image))),
            Err(reason) => Err(self.corrupt(index, reason)),
        }
    }
}

/// A `.y4m` file as a frame source.
#[derive(Debug)]
pub struct Y4mSource {
    path: PathBuf,
    reader: Y4mReader<BufReader<File>>,
    /// Used when the header has no `F` tag.
    fallback_fps: Option<f64>,
}

/// Rate assumed for timestamps when neither the file nor the caller gives one.
pub const DEFAULT_FPS: f64 = 30.0;

impl Y4mSource {
    /// Opens `path` and reads its header. `fallback_fps` is the rate reported
    /// and used for timestamps if the header has no `F` tag (else 30).
    pub fn open(path: &Path, fallback_fps: Option<f64>) -> Result<Self, SourceError> {
        let file = File::open(path).map_err(|source| SourceError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let name = path.display().to_string();
        let reader = Y4mReader::new(BufReader::with_capacity(1 << 20, file), &name)?;
        Ok(Y4mSource {
            path: path.to_path_buf(),
            reader,
            fallback_fps: fallback_fps.filter(|f| f.is_finite() && *f > 0.0),
        })
    }

    /// The file's header.
    pub fn header(&self) -> &Y4mHeader {
        self.reader.header()
    }

    fn timestamp(&self, index: u64) -> Duration {
        match self.reader.header.frame_rate {
            Some((n, d)) => timestamp_at(index, n, d),
            None => timestamp_at_fps(index, self.fallback_fps.unwrap_or(DEFAULT_FPS)),
        }
    }
}

impl FrameSource for Y4mSource {
    fn next_frame(&mut self) -> Result<Option<Frame>, SourceError> {
        Ok(self.reader.read_frame()?.map(|(index, image)| Frame {
            index,
            timestamp: self.timestamp(index),
            image,
        }))
    }

    fn size(&self) -> (u32, u32) {
        (self.reader.header.width, self.reader.header.height)
    }

    fn frame_rate(&self) -> Option<f64> {
        match self.reader.header.frame_rate {
            Some((n, d)) => Some(f64::from(n) / f64::from(d)),
            None => self.fallback_fps,
        }
    }

    fn describe(&self) -> String {
        let h = &self.reader.header;
        let rate = match self.frame_rate() {
            Some(fps) => format!(" @{}fps", (fps * 100.0).round() / 100.0),
            None => String::new(),
        };
        format!(
            "y4m {} {}x{} {:?}{}",
            self.path.display(),
            h.width,
            h.height,
            h.colour,
            rate
        )
    }
}

/// Chroma layout written by [`Y4mWriter`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Y4mChroma {
    /// `C420jpeg`: chroma averaged over 2x2 blocks (smaller files).
    C420,
    /// `C444`: full-resolution chroma (exact colours up to rounding).
    C444,
}

/// Why a Y4M file could not be written.
#[derive(thiserror::Error, Debug)]
pub enum Y4mWriteError {
    #[error("cannot create {}: {source}", path.display())]
    Create {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("write failed: {0}")]
    Io(#[from] std::io::Error),
    #[error("frame is {}x{}, but the stream is {}x{}", got.0, got.1, expected.0, expected.1)]
    SizeMismatch {
        expected: (u32, u32),
        got: (u32, u32),
    },
    #[error("invalid stream size {width}x{height}")]
    BadSize { width: u32, height: u32 },
    #[error("invalid frame rate {fps}")]
    BadFrameRate { fps: f64 },
}

/// A frame rate as a Y4M `F` ratio: whole rates as n:1, NTSC-style rates
/// (e.g. 29.97) as n*1000:1001, others in thousandths. `None` if not positive.
pub fn fps_to_ratio(fps: f64) -> Option<(u32, u32)> {
    if !fps.is_finite() || fps <= 0.0 || fps > 1_000_000.0 {
        return None;
    }
    if (fps - fps.round()).abs() < 1e-6 && fps.round() >= 1.0 {
        return Some((fps.round() as u32, 1));
    }
    let ntsc = fps * 1.001;
    if (ntsc - ntsc.round()).abs() < 1e-3 && ntsc.round() >= 1.0 {
        return Some((ntsc.round() as u32 * 1000, 1001));
    }
    let milli = (fps * 1000.0).round() as u32;
    if milli == 0 {
        return None;
    }
    let g = gcd(milli, 1000);
    Some((milli / g, 1000 / g))
}

fn gcd(a: u32, b: u32) -> u32 {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

/// Writes RGB frames as BT.601 limited-range YUV4MPEG2.
#[derive(Debug)]
pub struct Y4mWriter<W: Write> {
    out: W,
    width: u32,
    height: u32,
    chroma: Y4mChroma,
    frames_written: u64,
}

impl<W: Write> Y4mWriter<W> {
    /// Writes the stream header for `width`x`height` frames at `fps`.
    pub fn new(
        mut out: W,
        width: u32,
        height: u32,
        fps: f64,
        chroma: Y4mChroma,
    ) -> Result<Self, Y4mWriteError> {
        if width == 0 || height == 0 || width > MAX_DIMENSION || height > MAX_DIMENSION {
            return Err(Y4mWriteError::BadSize { width, height });
        }
        let (n, d) = fps_to_ratio(fps).ok_or(Y4mWriteError::BadFrameRate { fps })?;
        let tag = match chroma {
            Y4mChroma::C420 => "420jpeg",
            Y4mChroma::C444 => "444",
        };
        writeln!(out, "YUV4MPEG2 W{width} H{height} F{n}:{d} Ip A1:1 C{tag}")?;
        Ok(Y4mWriter {
            out,
            width,
            height,
            chroma,
            frames_written: 0,
        })
    }

    /// Converts and appends one frame, which must have the stream's size.
    pub fn write_frame(&mut self, image: &RgbImage) -> Result<(), Y4mWriteError> {
        if image.dimensions() != (self.width, self.height) {
            return Err(Y4mWriteError::SizeMismatch {
                expected: (self.width, self.height),
                got: image.dimensions(),
            });
        }
        let YuvPlanes { y, u, v } = match self.chroma {
            Y4mChroma::C420 => rgb_to_yuv420p(image),
            Y4mChroma::C444 => rgb_to_yuv444p(image),
        };
        self.out.write_all(b"FRAME\n")?;
        self.out.write_all(&y)?;
        self.out.write_all(&u)?;
        self.out.write_all(&v)?;
        self.frames_written += 1;
        Ok(())
    }

    /// Frames written so far.
    pub fn frames_written(&self) -> u64 {
        self.frames_written
    }

    /// Flushes and returns the underlying writer.
    pub fn finish(mut self) -> Result<W, Y4mWriteError> {
        self.out.flush()?;
        Ok(self.out)
    }
}

impl Y4mWriter<BufWriter<File>> {
    /// Creates (or truncates) a `.y4m` file at `path`.
    pub fn create(
        path: &Path,
        width: u32,
        height: u32,
        fps: f64,
        chroma: Y4mChroma,
    ) -> Result<Self, Y4mWriteError> {
        let file = File::create(path).map_err(|source| Y4mWriteError::Create {
            path: path.to_path_buf(),
            source,
        })?;
        Y4mWriter::new(BufWriter::new(file), width, height, fps, chroma)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::Rgb;
    use proptest::prelude::*;
    use std::io::Cursor;

    fn reader(bytes: &[u8]) -> Result<Y4mReader<Cursor<&[u8]>>, SourceError> {
        Y4mReader::new(Cursor::new(bytes), "test.y4m")
    }

    fn test_image(w: u32, h: u32) -> RgbImage {
        RgbImage::from_fn(w, h, |x, y| {
            let colours = [
                [255, 0, 0],
                [0, 255, 0],
                [0, 0, 255],
                [250, 250, 250],
                [40, 90, 160],
            ];
            // Constant colour over 2x2 blocks so 4:2:0 chroma is exact per block.
            Rgb(colours[((x / 2 + y / 2) % 5) as usize])
        })
    }

    #[test]
    fn header_parsing() {
        let h = parse_header(b"YUV4MPEG2 W640 H480 F30:1 Ip A1:1 C420jpeg").unwrap();
        assert_eq!(
            h,
            Y4mHeader {
                width: 640,
                height: 480,
                frame_rate: Some((30, 1)),
                colour: Y4mColour::Yuv420,
                range: YuvRange::Limited
            }
        );
        let h =
            parse_header(b"YUV4MPEG2 W3 H5 F30000:1001 C444 XCOLORRANGE=FULL XYSCSS=444").unwrap();
        assert_eq!(
            (h.colour, h.range, h.frame_rate),
            (Y4mColour::Yuv444, YuvRange::Full, Some((30000, 1001)))
        );
        // No C tag: 420jpeg; no F tag: unknown rate.
        let h = parse_header(b"YUV4MPEG2 W2 H2").unwrap();
        assert_eq!((h.colour, h.frame_rate), (Y4mColour::Yuv420, None));
        assert_eq!(
            parse_header(b"YUV4MPEG2 W2 H2 Cmono").unwrap().colour,
            Y4mColour::Mono
        );
        for tag in ["C420", "C420paldv", "C420mpeg2"] {
            let line = format!("YUV4MPEG2 W2 H2 {tag}");
            assert_eq!(
                parse_header(line.as_bytes()).unwrap().colour,
                Y4mColour::Yuv420
            );
        }
    }

    #[test]
    fn header_rejections() {
        let unsupported = |line: &str| {
            matches!(
                parse_header(line.as_bytes()),
                Err(HeaderProblem::Unsupported(_))
            )
        };
        let malformed = |line: &str| {
            matches!(
                parse_header(line.as_bytes()),
                Err(HeaderProblem::Malformed(_))
            )
        };
        assert!(unsupported("YUV4MPEG2 W2 H2 It"));
        assert!(unsupported("YUV4MPEG2 W2 H2 Ib"));
        assert!(unsupported("YUV4MPEG2 W2 H2 C420p10"));
        assert!(unsupported("YUV4MPEG2 W2 H2 C444p16"));
        assert!(unsupported("YUV4MPEG2 W2 H2 Cmono16"));
        assert!(unsupported("YUV4MPEG2 W2 H2 C422"));
        assert!(malformed("YUV4MPEG W2 H2"));
        assert!(malformed("YUV4MPEG2 H2"));
        assert!(malformed("YUV4MPEG2 W0 H2"));
        assert!(malformed("YUV4MPEG2 W2 H99999"));
        assert!(malformed("YUV4MPEG2 W2 H2 Fx:1"));
        assert!(malformed("YUV4MPEG2 W2 H2 F30:0"));
    }

    #[test]
    fn reads_frames_with_params() {
        // 2x2 4:2:0: 4 luma + 1 + 1 chroma bytes per frame.
        let mut data = b"YUV4MPEG2 W2 H2 F25:1 Ip C420jpeg\n".to_vec();
        data.extend_from_slice(b"FRAME\n");
        data.extend_from_slice(&[235, 235, 235, 235, 128, 128]);
        data.extend_from_slice(b"FRAME Ixyz\n");
        data.extend_from_slice(&[81, 81, 81, 81, 90, 240]);
        let mut r = reader(&data).unwrap();
        let (i0, white) = r.read_frame().unwrap().unwrap();
        assert_eq!((i0, white.get_pixel(1, 1).0), (0, [255, 255, 255]));
        let (i1, red) = r.read_frame().unwrap().unwrap();
        assert_eq!((i1, red.get_pixel(0, 1).0), (1, [255, 0, 0]));
        assert!(r.read_frame().unwrap().is_none());
        assert!(r.read_frame().unwrap().is_none());
    }

    #[test]
    fn truncated_final_frame() {
        let mut data = Vec::new();
        let mut w = Y4mWriter::new(&mut data, 4, 4, 30.0, Y4mChroma::C420).unwrap();
        for _ in 0..3 {
            w.write_frame(&test_image(4, 4)).unwrap();
        }
        w.finish().unwrap();
        let full_len = data.len();
        data.truncate(full_len - 5);
        let mut r = reader(&data).unwrap();
        assert!(r.read_frame().unwrap().is_some());
        assert!(r.read_frame().unwrap().is_some());
        match r.read_frame() {
            Err(SourceError::TruncatedFrame {
                source_name,
                index,
                expected,
                got,
            }) => {
                assert_eq!(
                    (source_name.as_str(), index, expected, got),
                    ("test.y4m", 2, 24, 19)
                );
            }
            other => panic!("expected TruncatedFrame, got {other:?}"),
        }
        assert!(r.read_frame().unwrap().is_none());

        // Cut inside the FRAME marker itself.
        let cut = data.len() - 19 - 3;
        let mut r = reader(&data[..cut]).unwrap();
        r.read_frame().unwrap();
        r.read_frame().unwrap();
        assert!(matches!(
            r.read_frame(),
            Err(SourceError::TruncatedFrame {
                index: 2,
                got: 0,
                ..
            })
        ));
    }

    #[test]
    fn garbage_instead_of_frame_is_corrupt() {
        let data = b"YUV4MPEG2 W2 H2 C444\nGARBAGE\n0123456789AB";
        let mut r = reader(data).unwrap();
        match r.read_frame() {
            Err(SourceError::CorruptFrame {
                index: 0, reason, ..
            }) => assert!(reason.contains("no FRAME line follows"), "{reason}"),
            other => panic!("expected CorruptFrame, got {other:?}"),
        }
        assert!(r.read_frame().unwrap().is_none());
    }

    #[test]
    fn after_a_damaged_frame_the_next_frame_line_is_found() {
        // Four 2x2 4:4:4 frames of 12 bytes each; each frame's samples are its number.
        let mut data = b"YUV4MPEG2 W2 H2 F30:1 C444\n".to_vec();
        for k in 0..4u8 {
            data.extend_from_slice(b"FRAME\n");
            data.extend_from_slice(&[100 + k; 12]);
        }
        let frame_len = 6 + 12;
        let header_len = data.len() - 4 * frame_len;
        // Frame 1's marker damaged; frame 2's marker written with a parameter.
        data[header_len + frame_len + 3] = b'X';
        let mut with_parameter = data[..header_len + 2 * frame_len].to_vec();
        with_parameter.extend_from_slice(b"FRAME Ixyz\n");
        with_parameter.extend_from_slice(&data[header_len + 2 * frame_len + 6..]);
        let mut r = reader(&with_parameter).unwrap();
        let (i0, first) = r.read_frame().unwrap().unwrap();
        assert_eq!(i0, 0);
        match r.read_frame() {
            Err(SourceError::CorruptFrame {
                index: 1, reason, ..
            }) => assert!(reason.contains("1 frame(s) on"), "{reason}"),
            other => panic!("expected CorruptFrame, got {other:?}"),
        }
        let (i2, third) = r.read_frame().unwrap().unwrap();
        let (i3, _) = r.read_frame().unwrap().unwrap();
        assert_eq!((i2, i3), (2, 3));
        assert_ne!(first, third);
        assert!(r.read_frame().unwrap().is_none());
        // Frames 1 and 2 damaged at once (two markers gone): the next one is frame 3.
        let mut two = data.clone();
        two[header_len + 2 * frame_len + 1] = b'x';
        let mut r = reader(&two).unwrap();
        assert_eq!(r.read_frame().unwrap().unwrap().0, 0);
        match r.read_frame() {
            Err(SourceError::CorruptFrame {
                index: 1, reason, ..
            }) => assert!(reason.contains("2 frame(s) on"), "{reason}"),
            other => panic!("expected CorruptFrame, got {other:?}"),
        }
        assert_eq!(r.read_frame().unwrap().unwrap().0, 3);
        assert!(r.read_frame().unwrap().is_none());
    }

    #[test]
    fn bad_files() {
        assert!(matches!(reader(b""), Err(SourceError::BadHeader { .. })));
        assert!(matches!(
            reader(b"YUV4MPEG2 W2 H2"),
            Err(SourceError::BadHeader { .. })
        ));
        assert!(matches!(
            reader(b"YUV4MPEG2 W2 H2 It\n"),
            Err(SourceError::Unsupported { .. })
        ));
        let long = [b'A'; MAX_LINE * 2];
        assert!(matches!(reader(&long), Err(SourceError::BadHeader { .. })));
    }

    fn max_channel_error(a: &RgbImage, b: &RgbImage) -> u8 {
        a.as_raw()
            .iter()
            .zip(b.as_raw())
            .map(|(p, q)| p.abs_diff(*q))
            .max()
            .unwrap_or(0)
    }

    #[test]
    fn writer_reader_round_trip_through_a_file() {
        let dir = tempfile::tempdir().unwrap();
        for (chroma, w, h) in [
            (Y4mChroma::C444, 5, 3),
            (Y4mChroma::C420, 6, 4),
            (Y4mChroma::C420, 7, 5),
        ] {
            let path = dir.path().join("clip.y4m");
            let mut writer = Y4mWriter::create(&path, w, h, 29.97, chroma).unwrap();
            let frames: Vec<RgbImage> = (0..3)
                .map(|i| {
                    let mut img = test_image(w, h);
                    for (x, y) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                        img.put_pixel(x, y, Rgb([i * 50, i * 50 + 10, i * 50 + 20]));
                    }
                    img
                })
                .collect();
            for f in &frames {
                writer.write_frame(f).unwrap();
            }
            assert_eq!(writer.frames_written(), 3);
            writer.finish().unwrap();

            let mut src = Y4mSource::open(&path, None).unwrap();
            assert_eq!(src.size(), (w, h));
            assert_eq!(src.header().frame_rate, Some((30000, 1001)));
            assert!((src.frame_rate().unwrap() - 29.97).abs() < 0.001);
            assert!(src.describe().contains("clip.y4m"));
            for (i, original) in frames.iter().enumerate() {
                let frame = src.next_frame().unwrap().unwrap();
                assert_eq!(frame.index, i as u64);
                assert_eq!(frame.timestamp, timestamp_at(i as u64, 30000, 1001));
                let err = max_channel_error(&frame.image, original);
                assert!(err <= 4, "{chroma:?} {w}x{h} frame {i}: error {err}");
            }
            assert!(src.next_frame().unwrap().is_none());
        }
    }

    #[test]
    fn writer_rejects_bad_input() {
        let mut sink = Vec::new();
        assert!(matches!(
            Y4mWriter::new(&mut sink, 4, 4, 0.0, Y4mChroma::C444),
            Err(Y4mWriteError::BadFrameRate { .. })
        ));
        let mut w = Y4mWriter::new(&mut sink, 4, 4, 30.0, Y4mChroma::C444).unwrap();
        assert!(matches!(
            w.write_frame(&test_image(2, 2)),
            Err(Y4mWriteError::SizeMismatch { .. })
        ));
    }

    #[test]
    fn frame_rate_ratios() {
        assert_eq!(fps_to_ratio(30.0), Some((30, 1)));
        assert_eq!(fps_to_ratio(29.97), Some((30000, 1001)));
        assert_eq!(fps_to_ratio(59.94), Some((60000, 1001)));
        assert_eq!(fps_to_ratio(12.5), Some((25, 2)));
        assert_eq!(fps_to_ratio(-1.0), None);
        assert_eq!(fps_to_ratio(f64::NAN), None);
    }

    #[test]
    fn missing_frame_rate_uses_fallback() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("norate.y4m");
        let mut data = b"YUV4MPEG2 W2 H2 Cmono\n".to_vec();
        for _ in 0..2 {
            data.extend_from_slice(b"FRAME\n\x00\x40\x80\xff");
        }
        std::fs::write(&path, data).unwrap();
        let mut src = Y4mSource::open(&path, Some(10.0)).unwrap();
        assert_eq!(src.frame_rate(), Some(10.0));
        let f0 = src.next_frame().unwrap().unwrap();
        assert_eq!(f0.image.get_pixel(1, 1).0, [255, 255, 255]);
        assert_eq!(f0.image.get_pixel(1, 0).0, [64, 64, 64]);
        let f1 = src.next_frame().unwrap().unwrap();
        assert_eq!(f1.timestamp, Duration::from_millis(100));
    }

    fn exercise(bytes: &[u8]) {
        if let Ok(mut r) = reader(bytes) {
            for _ in 0..8 {
                match r.read_frame() {
                    Ok(Some(_)) | Err(_) => {}
                    Ok(None) => break,
                }
            }
        }
    }

    proptest! {
        #[test]
        fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
            let _ = parse_header(&bytes);
            exercise(&bytes);
        }

        #[test]
        fn arbitrary_frames_after_valid_header_never_panic(
            w in 1u32..9, h in 1u32..9, c in 0usize..3,
            body in proptest::collection::vec(any::<u8>(), 0..600),
            marker in proptest::bool::ANY,
        ) {
            let tag = ["C420jpeg", "C444", "Cmono"][c];
            let mut data = format!("YUV4MPEG2 W{w} H{h} F30:1 {tag}\n").into_bytes();
            if marker {
                data.extend_from_slice(b"FRAME\n");
            }
            data.extend_from_slice(&body);
            exercise(&data);
        }

        #[test]
        fn arbitrary_header_tokens_never_panic(tokens in proptest::collection::vec("[WHFICAX][ -~]{0,12}", 0..8)) {
            let line = format!("YUV4MPEG2 {}", tokens.join(" "));
            let _ = parse_header(line.as_bytes());
            exercise(format!("{line}\nFRAME\n").as_bytes());
        }
    }
}
