//! A live V4L2 webcam as a frame source (Linux, through the `v4l` crate).
//!
//! Opening a camera lists what it offers (pixel format × size × frame rate),
//! picks the closest match to the request with the pure function
//! [`choose_format`] (MJPG preferred above 640x480, YUYV otherwise, only these
//! two are decoded), sets it, and streams through four mmap buffers.
//!
//! The segmenter receives RGB frames converted from YUYV or MJPEG (see
//! [`super::convert`]), stamped with the driver's buffer timestamp relative to
//! the first frame (falling back to a monotonic clock when the driver gives
//! none). A frame that fails to decode gives `CorruptFrame` and the next call
//! reads the next frame. Missing (`ENOENT`/`ENODEV`) and busy (`EBUSY`)
//! devices, and devices with no usable format, give their own errors.

use std::fmt;
use std::io;
use std::path::Path;
use std::time::{Duration, Instant};

use v4l::buffer::{Flags, Type};
use v4l::frameinterval::FrameIntervalEnum;
use v4l::framesize::FrameSizeEnum;
use v4l::io::mmap::Stream;
use v4l::io::traits::CaptureStream;
use v4l::video::capture::Parameters;
use v4l::video::Capture;
use v4l::{Device, Format, FourCC, Fraction};

use super::convert::{mjpeg_to_rgb, yuyv_to_rgb_strided};
use super::y4m::fps_to_ratio;
use super::{Frame, FrameSource, SourceError, SourceOptions};

/// Size used when the caller does not ask for one.
pub const DEFAULT_SIZE: (u32, u32) = (640, 480);
/// Frame rate aimed for when the caller does not ask for one.
pub const DEFAULT_FPS: f64 = 30.0;
/// Above this many pixels MJPG is preferred over YUYV (USB 2 bandwidth).
pub const HIGH_RES_PIXELS: u64 = 640 * 480;
/// How long to wait for a frame before reporting the camera as stalled.
pub const FRAME_TIMEOUT: Duration = Duration::from_secs(5);
/// Number of mmap buffers requested from the driver.
pub const BUFFER_COUNT: u32 = 4;

// errno values (Linux) for errors std has no stable ErrorKind for.
const ENODEV: i32 = 19;

/// A pixel format this module can decode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PixelFormat {
    /// Packed YUV 4:2:2.
    Yuyv,
    /// Motion JPEG (also accepted under the fourcc `JPEG`).
    Mjpeg,
}

impl PixelFormat {
    /// The usable format for a fourcc, if any.
    pub fn from_fourcc(fourcc: [u8; 4]) -> Option<Self> {
        match &fourcc {
            b"YUYV" => Some(PixelFormat::Yuyv),
            b"MJPG" | b"JPEG" => Some(PixelFormat::Mjpeg),
            _ => None,
        }
    }

    /// The canonical fourcc.
    pub fn fourcc(self) -> [u8; 4] {
        match self {
            PixelFormat::Yuyv => *b"YUYV",
            PixelFormat::Mjpeg => *b"MJPG",
        }
    }

    /// The fourcc as text, e.g. "YUYV".
    pub fn name(self) -> &'static str {
        match self {
            PixelFormat::Yuyv => "YUYV",
            PixelFormat::Mjpeg => "MJPG",
        }
    }
}

/// One format × size a device offers, with its frame rates.
#[derive(Debug, Clone, PartialEq)]
pub struct OfferedFormat {
    pub fourcc: [u8; 4],
    /// 0 when the driver did not list sizes for this format.
    pub width: u32,
    /// 0 when the driver did not list sizes for this format.
    pub height: u32,
    /// Frames per second offered at this size; empty if not listed.
    pub frame_rates: Vec<f64>,
}

fn fourcc_text(fourcc: [u8; 4]) -> String {
    fourcc
        .iter()
        .map(|&b| if b.is_ascii_graphic() { b as char } else { '?' })
        .collect()
}

fn fmt_rate(fps: f64) -> String {
    format!("{}", (fps * 100.0).round() / 100.0)
}

impl fmt::Display for OfferedFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", fourcc_text(self.fourcc))?;
        if self.width == 0 || self.height == 0 {
            write!(f, " (sizes not listed)")?;
        } else {
            write!(f, " {}x{}", self.width, self.height)?;
        }
        if !self.frame_rates.is_empty() {
            let rates: Vec<String> = self.frame_rates.iter().map(|&r| fmt_rate(r)).collect();
            write!(f, " @{}fps", rates.join("/"))?;
        }
        Ok(())
    }
}

/// The format to ask the driver for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChosenFormat {
    pub pixel_format: PixelFormat,
    pub width: u32,
    pub height: u32,
    /// Frame rate to request, `None` if the device lists none.
    pub fps: Option<f64>,
}

/// No offered format can be decoded.
#[derive(thiserror::Error, Debug, Clone, PartialEq)]
#[error("no usable format (need YUYV or MJPG); offered: {}", offered.join(", "))]
pub struct NoUsableFormat {
    /// Every offered format, as "FOURCC WxH @rates".
    pub offered: Vec<String>,
}

/// |ln(a / b)|: symmetric relative distance between two positive numbers.
fn log_distance(a: f64, b: f64) -> f64 {
    if a > 0.0 && b > 0.0 {
        (a / b).ln().abs()
    } else {
        f64::INFINITY
    }
}

/// Picks, among the usable offered formats, the size closest to `want`
/// (default 640x480; unlisted sizes rank last), then the rate closest to
/// `fps` (default 30), then MJPG above [`HIGH_RES_PIXELS`] and YUYV at or
/// below it, then the larger size.
pub fn choose_format(
    offered: &[OfferedFormat],
    want: Option<(u32, u32)>,
    fps: Option<f64>,
) -> Result<ChosenFormat, NoUsableFormat> {
    let (want_w, want_h) = want.unwrap_or(DEFAULT_SIZE);
    let target_fps = fps
        .filter(|f| f.is_finite() && *f > 0.0)
        .unwrap_or(DEFAULT_FPS);

    let candidates = offered.iter().filter_map(|o| {
        let pixel_format = PixelFormat::from_fourcc(o.fourcc)?;
        let listed = o.width > 0 && o.height > 0;
        let (width, height, size_cost) = if listed {
            let cost = log_distance(f64::from(o.width), f64::from(want_w))
                + log_distance(f64::from(o.height), f64::from(want_h));
            (o.width, o.height, cost)
        } else {
            (want_w, want_h, f64::MAX)
        };
        let best_rate = o
            .frame_rates
            .iter()
            .copied()
            .filter(|r| r.is_finite() && *r > 0.0)
            .min_by(|a, b| {
                log_distance(*a, target_fps)
                    .total_cmp(&log_distance(*b, target_fps))
                    .then(b.total_cmp(a))
            });
        let rate_cost = best_rate.map_or(0.5, |r| log_distance(r, target_fps));
        let pixels = u64::from(width) * u64::from(height);
        let preferred = if pixels > HIGH_RES_PIXELS {
            PixelFormat::Mjpeg
        } else {
            PixelFormat::Yuyv
        };
        let format_penalty = u8::from(pixel_format != preferred);
        let chosen = ChosenFormat {
            pixel_format,
            width,
            height,
            fps: best_rate,
        };
        Some((size_cost, rate_cost, format_penalty, pixels, chosen))
    });

    candidates
        .min_by(|a, b| {
            a.0.total_cmp(&b.0)
                .then(a.1.total_cmp(&b.1))
                .then(a.2.cmp(&b.2))
                .then(b.3.cmp(&a.3))
        })
        .map(|c| c.4)
        .ok_or_else(|| NoUsableFormat {
            offered: offered.iter().map(|o| o.to_string()).collect(),
        })
}

/// Representative sizes inside a stepwise/continuous size range: common
/// webcam sizes, the wanted size and the maximum, each snapped to the grid.
pub fn stepwise_sizes(
    min: (u32, u32),
    max: (u32, u32),
    step: (u32, u32),
    want: Option<(u32, u32)>,
) -> Vec<(u32, u32)> {
    let snap = |v: u32, lo: u32, hi: u32, st: u32| {
        let v = v.clamp(lo, hi.max(lo));
        let st = st.max(1);
        lo + (v - lo) / st * st
    };
    let mut sizes: Vec<(u32, u32)> = [
        (320, 240),
        (640, 480),
        (800, 600),
        (1280, 720),
        (1920, 1080),
    ]
    .into_iter()
    .chain(want)
    .chain(std::iter::once(max))
    .map(|(w, h)| (snap(w, min.0, max.0, step.0), snap(h, min.1, max.1, step.1)))
    .filter(|&(w, h)| w > 0 && h > 0)
    .collect();
    sizes.sort_unstable();
    sizes.dedup();
    sizes
}

/// Frame rates from a list of frame intervals (seconds per frame).
fn interval_rates(intervals: &[FrameIntervalEnum], target_fps: f64) -> Vec<f64> {
    let rate = |f: &Fraction| {
        (f.numerator > 0 && f.denominator > 0)
            .then(|| f64::from(f.denominator) / f64::from(f.numerator))
    };
    let mut rates = Vec::new();
    for interval in intervals {
        match interval {
            FrameIntervalEnum::Discrete(f) => rates.extend(rate(f)),
            FrameIntervalEnum::Stepwise(s) => {
                // The shortest interval is the highest rate.
                if let (Some(hi), Some(lo)) = (rate(&s.min), rate(&s.max)) {
                    rates.extend([hi, lo, target_fps.clamp(lo.min(hi), hi.max(lo))]);
                }
            }
        }
    }
    rates.sort_by(|a, b| b.total_cmp(a));
    rates.dedup();
    rates
}

/// Everything the device offers, as far as the driver lists it.
fn enumerate_formats(dev: &Device, options: &SourceOptions) -> Vec<OfferedFormat> {
    let target_fps = options.fps.unwrap_or(DEFAULT_FPS);
    let mut offered = Vec::new();
    for desc in dev.enum_formats().unwrap_or_default() {
        let fourcc = desc.fourcc;
        let mut sizes = Vec::new();
        for size in dev.enum_framesizes(fourcc).unwrap_or_default() {
            match size.size {
                FrameSizeEnum::Discrete(d) => sizes.push((d.width, d.height)),
                FrameSizeEnum::Stepwise(s) => sizes.extend(stepwise_sizes(
                    (s.min_width, s.min_height),
                    (s.max_width, s.max_height),
                    (s.step_width, s.step_height),
                    options.size,
                )),
            }
        }
        if sizes.is_empty() {
            offered.push(OfferedFormat {
                fourcc: fourcc.repr,
                width: 0,
                height: 0,
                frame_rates: Vec::new(),
            });
        }
        for (width, height) in sizes {
            let intervals: Vec<FrameIntervalEnum> = dev
                .enum_frameintervals(fourcc, width, height)
                .unwrap_or_default()
                .into_iter()
                .map(|i| i.interval)
                .collect();
            offered.push(OfferedFormat {
                fourcc: fourcc.repr,
                width,
                height,
                frame_rates: interval_rates(&intervals, target_fps),
            });
        }
    }
    offered
}

/// Maps an I/O error from the device to the matching [`SourceError`].
pub fn device_error(device: &str, action: &'static str, err: io::Error) -> SourceError {
    let device = device.to_string();
    match err.kind() {
        io::ErrorKind::NotFound => SourceError::DeviceMissing { device },
        io::ErrorKind::ResourceBusy => SourceError::DeviceBusy { device },
        _ if err.raw_os_error() == Some(ENODEV) => SourceError::DeviceMissing { device },
        _ => SourceError::Device {
            device,
            action,
            source: err,
        },
    }
}

/// A driver timestamp (seconds, microseconds) as a duration; `None` when the
/// driver left it zero or it is out of range.
pub fn device_timestamp(sec: i64, usec: i64) -> Option<Duration> {
    if sec < 0 || !(0..1_000_000).contains(&usec) || (sec == 0 && usec == 0) {
        return None;
    }
    Some(Duration::new(sec as u64, (usec * 1000) as u32))
}

/// Where frame timestamps are measured from: fixed by the first frame.
#[derive(Debug, Clone, Copy)]
enum ClockBase {
    Device(Duration),
    Monotonic(Instant),
}

/// Timestamp of a frame relative to the stream start.
fn relative_timestamp(
    base: &mut Option<ClockBase>,
    device: Option<Duration>,
    now: Instant,
    stream_start: Instant,
) -> Duration {
    let b = *base.get_or_insert(match device {
        Some(d) => ClockBase::Device(d),
        None => ClockBase::Monotonic(now),
    });
    match (b, device) {
        (ClockBase::Device(first), Some(d)) => d.saturating_sub(first),
        (ClockBase::Monotonic(first), _) => now.saturating_duration_since(first),
        // Device clock vanished mid-stream: fall back to wall time since start.
        (ClockBase::Device(_), None) => now.saturating_duration_since(stream_start),
    }
}

/// A streaming V4L2 camera.
pub struct V4l2Source {
    device_name: String,
    // The stream keeps its own handle on the device; fields drop in order.
    stream: Stream<'static>,
    _device: Device,
    pixel_format: PixelFormat,
    width: u32,
    height: u32,
    stride: usize,
    fps: Option<f64>,
    next_index: u64,
    clock_base: Option<ClockBase>,
    opened_at: Instant,
}

impl fmt::Debug for V4l2Source {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("V4l2Source")
            .field("device", &self.device_name)
            .field("format", &self.pixel_format)
            .field("size", &(self.width, self.height))
            .field("fps", &self.fps)
            .finish()
    }
}

impl V4l2Source {
    /// Opens the camera at `path` (e.g. "/dev/video0"), chooses and sets a
    /// format per [`choose_format`] and prepares mmap streaming.
    pub fn open(path: &Path, options: &SourceOptions) -> Result<Self, SourceError> {
        let name = path.display().to_string();
        let dev = Device::with_path(path).map_err(|e| device_error(&name, "open", e))?;

        let offered = enumerate_formats(&dev, options);
        let chosen = choose_format(&offered, options.size, options.fps).map_err(|e| {
            SourceError::NoUsableFormat {
                device: name.clone(),
                offered: e.offered,
            }
        })?;

        let request = Format::new(
            chosen.width,
            chosen.height,
            FourCC::new(&chosen.pixel_format.fourcc()),
        );
        let actual = dev
            .set_format(&request)
            .map_err(|e| device_error(&name, "setting the format", e))?;
        let pixel_format = PixelFormat::from_fourcc(actual.fourcc.repr).ok_or_else(|| {
            SourceError::NoUsableFormat {
                device: name.clone(),
                offered: offered.iter().map(|o| o.to_string()).collect(),
            }
        })?;
        let row_bytes = actual.width as usize * 2;
        let stride = match pixel_format {
            PixelFormat::Yuyv => (actual.stride as usize).max(row_bytes),
            PixelFormat::Mjpeg => 0,
        };

        // Frame rate: best effort; many drivers ignore or refuse it.
        if let Some((num, den)) = chosen.fps.or(options.fps).and_then(fps_to_ratio) {
            let _ = dev.set_params(&Parameters::new(Fraction::new(den, num)));
        }
        let fps = dev
            .params()
            .ok()
            .map(|p| p.interval)
            .filter(|i| i.numerator > 0 && i.denominator > 0)
            .map(|i| f64::from(i.denominator) / f64::from(i.numerator))
            .or(chosen.fps);

        let mut stream = Stream::with_buffers(&dev, Type::VideoCapture, BUFFER_COUNT)
            .map_err(|e| device_error(&name, "allocating buffers", e))?;
        stream.set_timeout(FRAME_TIMEOUT);

        Ok(V4l2Source {
            device_name: name,
            stream,
            _device: dev,
            pixel_format,
            width: actual.width,
            height: actual.height,
            stride,
            fps,
            next_index: 0,
            clock_base: None,
            opened_at: Instant::now(),
        })
    }

    /// Opens `/dev/video{index}`.
    pub fn open_index(index: u32, options: &SourceOptions) -> Result<Self, SourceError> {
        Self::open(Path::new(&format!("/dev/video{index}")), options)
    }

    /// The pixel format being streamed.
    pub fn pixel_format(&self) -> PixelFormat {
        self.pixel_format
    }
}

impl FrameSource for V4l2Source {
    fn next_frame(&mut self) -> Result<Option<Frame>, SourceError> {
        let (buf, meta) = CaptureStream::next(&mut self.stream)
            .map_err(|e| device_error(&self.device_name, "reading a frame", e))?;
        let index = self.next_index;
        self.next_index += 1;
        let now = Instant::now();
        // time_t is i32 on some 32-bit targets, hence the conversions.
        #[allow(clippy::useless_conversion)]
        let device_time = device_timestamp(
            i64::from(meta.timestamp.sec),
            i64::from(meta.timestamp.usec),
        );
        let timestamp = relative_timestamp(&mut self.clock_base, device_time, now, self.opened_at);

        let corrupt = |reason: String| SourceError::CorruptFrame {
            source_name: self.device_name.clone(),
            index,
            reason,
        };
        if meta.flags.contains(Flags::ERROR) {
            return Err(corrupt("driver flagged the buffer as damaged".to_string()));
        }
        let used = (meta.bytesused as usize).min(buf.len());
        if used == 0 {
            return Err(corrupt("empty buffer".to_string()));
        }
        let data = &buf[..used];
        let image = match self.pixel_format {
            PixelFormat::Yuyv => yuyv_to_rgb_strided(data, self.width, self.height, self.stride),
            PixelFormat::Mjpeg => mjpeg_to_rgb(data),
        }
        .map_err(|e| corrupt(e.to_string()))?;
        if image.dimensions() != (self.width, self.height) {
            return Err(corrupt(format!(
                "decoded {}x{}, expected {}x{}",
                image.width(),
                image.height(),
                self.width,
                self.height
            )));
        }
        Ok(Some(Frame {
            index,
            timestamp,
            image,
        }))
    }

    fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    fn frame_rate(&self) -> Option<f64> {
        self.fps
    }

    fn describe(&self) -> String {
        let rate = self
            .fps
            .map(|f| format!(" @{}fps", fmt_rate(f)))
            .unwrap_or_default();
        format!(
            "{} {}x{} {}{}",
            self.device_name,
            self.width,
            self.height,
            self.pixel_format.name(),
            rate
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn offer(fourcc: &[u8; 4], width: u32, height: u32, rates: &[f64]) -> OfferedFormat {
        OfferedFormat {
            fourcc: *fourcc,
            width,
            height,
            frame_rates: rates.to_vec(),
        }
    }

    /// A typical UVC webcam: YUYV is slow above 640x480, MJPG is fast everywhere.
    fn webcam() -> Vec<OfferedFormat> {
        vec![
            offer(b"YUYV", 640, 480, &[30.0, 15.0]),
            offer(b"YUYV", 320, 240, &[30.0]),
            offer(b"YUYV", 1280, 720, &[10.0, 5.0]),
            offer(b"YUYV", 1920, 1080, &[5.0]),
            offer(b"MJPG", 640, 480, &[30.0]),
            offer(b"MJPG", 1280, 720, &[30.0, 60.0]),
            offer(b"MJPG", 1920, 1080, &[30.0]),
        ]
    }

    fn chosen(pixel_format: PixelFormat, width: u32, height: u32, fps: f64) -> ChosenFormat {
        ChosenFormat {
            pixel_format,
            width,
            height,
            fps: Some(fps),
        }
    }

    #[test]
    fn default_is_yuyv_vga_at_30() {
        assert_eq!(
            choose_format(&webcam(), None, None).unwrap(),
            chosen(PixelFormat::Yuyv, 640, 480, 30.0)
        );
    }

    #[test]
    fn high_resolution_prefers_mjpg() {
        assert_eq!(
            choose_format(&webcam(), Some((1920, 1080)), Some(30.0)).unwrap(),
            chosen(PixelFormat::Mjpeg, 1920, 1080, 30.0)
        );
        assert_eq!(
            choose_format(&webcam(), Some((1280, 720)), Some(60.0)).unwrap(),
            chosen(PixelFormat::Mjpeg, 1280, 720, 60.0)
        );
    }

    #[test]
    fn mjpg_at_high_res_even_when_rates_tie() {
        let offers = vec![
            offer(b"YUYV", 1280, 720, &[30.0]),
            offer(b"MJPG", 1280, 720, &[30.0]),
        ];
        assert_eq!(
            choose_format(&offers, Some((1280, 720)), None)
                .unwrap()
                .pixel_format,
            PixelFormat::Mjpeg
        );
    }

    #[test]
    fn yuyv_wins_at_low_res_unless_too_slow() {
        let offers = vec![
            offer(b"MJPG", 640, 480, &[30.0]),
            offer(b"YUYV", 640, 480, &[15.0]),
        ];
        assert_eq!(
            choose_format(&offers, Some((640, 480)), Some(30.0)).unwrap(),
            chosen(PixelFormat::Mjpeg, 640, 480, 30.0)
        );
        assert_eq!(
            choose_format(&offers, Some((640, 480)), Some(15.0)).unwrap(),
            chosen(PixelFormat::Yuyv, 640, 480, 15.0)
        );
    }

    #[test]
    fn closest_size_and_rate() {
        // 800x600 is asked; 640x480 is closer than 1280x720.
        let c = choose_format(&webcam(), Some((800, 600)), Some(25.0)).unwrap();
        assert_eq!((c.width, c.height, c.fps), (640, 480, Some(30.0)));
        // 12 fps: of YUYV 640x480's {30, 15}, 15 is closer.
        let c = choose_format(&webcam(), Some((640, 480)), Some(12.0)).unwrap();
        assert_eq!((c.pixel_format, c.fps), (PixelFormat::Yuyv, Some(15.0)));
    }

    #[test]
    fn only_yuyv_is_used_even_if_slow() {
        let offers = vec![offer(b"YUYV", 1280, 720, &[10.0])];
        assert_eq!(
            choose_format(&offers, Some((1920, 1080)), Some(30.0)).unwrap(),
            chosen(PixelFormat::Yuyv, 1280, 720, 10.0)
        );
    }

    #[test]
    fn jpeg_fourcc_counts_as_mjpeg_and_unlisted_sizes_work() {
        let offers = vec![offer(b"JPEG", 0, 0, &[])];
        let c = choose_format(&offers, Some((1024, 768)), None).unwrap();
        assert_eq!(
            c,
            ChosenFormat {
                pixel_format: PixelFormat::Mjpeg,
                width: 1024,
                height: 768,
                fps: None
            }
        );
    }

    #[test]
    fn no_usable_format_lists_offers() {
        let offers = vec![
            offer(b"H264", 1920, 1080, &[30.0, 15.0]),
            offer(b"GREY", 0, 0, &[]),
        ];
        let err = choose_format(&offers, None, None).unwrap_err();
        assert_eq!(
            err.offered,
            vec![
                "H264 1920x1080 @30/15fps".to_string(),
                "GREY (sizes not listed)".to_string()
            ]
        );
        assert!(choose_format(&[], None, None)
            .unwrap_err()
            .offered
            .is_empty());
    }

    #[test]
    fn stepwise_sizes_are_snapped_and_bounded() {
        let sizes = stepwise_sizes((16, 16), (1280, 720), (16, 8), Some((1000, 700)));
        assert!(sizes.contains(&(640, 480)));
        assert!(sizes.contains(&(1280, 720)));
        assert!(sizes.contains(&(992, 696))); // 1000,700 snapped down to the grid
        assert!(sizes
            .iter()
            .all(|&(w, h)| w <= 1280 && h <= 720 && w >= 16 && h >= 16));
        assert!(sizes
            .iter()
            .all(|&(w, h)| (w - 16) % 16 == 0 && (h - 16) % 8 == 0));
        // Degenerate step and range must not panic.
        assert_eq!(stepwise_sizes((8, 8), (8, 8), (0, 0), None), vec![(8, 8)]);
    }

    #[test]
    fn interval_rates_from_fractions() {
        use v4l::frameinterval::Stepwise;
        let rates = interval_rates(
            &[
                FrameIntervalEnum::Discrete(Fraction::new(1, 30)),
                FrameIntervalEnum::Discrete(Fraction::new(1001, 30000)),
                FrameIntervalEnum::Discrete(Fraction::new(0, 0)),
            ],
            30.0,
        );
        assert_eq!(rates.len(), 2);
        assert!((rates[1] - 29.97).abs() < 0.01);
        let rates = interval_rates(
            &[FrameIntervalEnum::Stepwise(Stepwise {
                min: Fraction::new(1, 60),
                max: Fraction::new(1, 5),
                step: Fraction::new(1, 1),
            })],
            24.0,
        );
        assert_eq!(rates, vec![60.0, 24.0, 5.0]);
    }

    #[test]
    fn timestamps_from_driver_or_clock() {
        assert_eq!(device_timestamp(0, 0), None);
        assert_eq!(device_timestamp(-1, 5), None);
        assert_eq!(device_timestamp(1, 1_000_000), None);
        assert_eq!(
            device_timestamp(2, 500_000),
            Some(Duration::from_millis(2500))
        );

        let start = Instant::now();
        let mut base = None;
        let t0 = relative_timestamp(&mut base, device_timestamp(100, 0), start, start);
        let t1 = relative_timestamp(&mut base, device_timestamp(100, 33_000), start, start);
        assert_eq!((t0, t1), (Duration::ZERO, Duration::from_millis(33)));

        let mut base = None;
        let later = start + Duration::from_millis(40);
        assert_eq!(
            relative_timestamp(&mut base, None, start, start),
            Duration::ZERO
        );
        assert_eq!(
            relative_timestamp(&mut base, None, later, start),
            Duration::from_millis(40)
        );
    }

    #[test]
    fn errors_map_to_missing_and_busy() {
        let e = device_error(
            "/dev/video7",
            "open",
            io::Error::from(io::ErrorKind::NotFound),
        );
        assert!(matches!(e, SourceError::DeviceMissing { .. }));
        let e = device_error("/dev/video7", "open", io::Error::from_raw_os_error(16)); // EBUSY
        assert!(matches!(e, SourceError::DeviceBusy { .. }));
        let e = device_error("/dev/video7", "open", io::Error::from_raw_os_error(ENODEV));
        assert!(matches!(e, SourceError::DeviceMissing { .. }));
        let e = device_error("/dev/video7", "open", io::Error::from_raw_os_error(13)); // EACCES
        assert!(e.to_string().contains("/dev/video7"));
    }

    #[test]
    fn missing_device_is_reported() {
        match V4l2Source::open(Path::new("/dev/video99"), &SourceOptions::default()) {
            Err(SourceError::DeviceMissing { device }) => assert_eq!(device, "/dev/video99"),
            other => panic!("expected DeviceMissing, got {other:?}"),
        }
        assert!(matches!(
            V4l2Source::open_index(99, &SourceOptions::default()),
            Err(SourceError::DeviceMissing { .. })
        ));
    }
}
