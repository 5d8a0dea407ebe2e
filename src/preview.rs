//! Preview GIF writer: composited frames, downsized and thinned, streamed into an animated GIF that
//! loops forever, so a person can glance at a run without a video player.
//!
//! [`GifPreview::push`] takes every `every`-th frame, scales it (triangle filter) to at most
//! `max_width` pixels wide keeping the aspect ratio of the first frame, and encodes it right away with
//! the image crate's GIF encoder (per-frame palette by NeuQuant, `Repeat::Infinite`). Frames go to a
//! temporary name beside the target ([`crate::io::temporary_path`]); [`GifPreview::finish`] writes
//! the trailer, flushes to disk and renames the file into place. A crash therefore never leaves a
//! truncated GIF under the final name, and a writer dropped without `finish` deletes its temporary
//! file. Every error names the file. What comes out is the finished `.gif` for the user.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Duration;

use image::codecs::gif::{GifEncoder, Repeat};
use image::imageops::FilterType;
use image::{Delay, Frame, RgbImage, RgbaImage};

/// How the preview is sampled and encoded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PreviewSettings {
    /// Frames wider than this are scaled down to it (0: keep the size).
    pub max_width: u32,
    /// Keep every n-th frame (the first, the (n+1)-th, …); 0 counts as 1.
    pub every: u32,
    /// Frame rate of the input, for the GIF's frame delay (`every / fps` seconds per kept frame).
    pub fps: f32,
    /// GIF quantizer speed, 1 (best) ..= 30 (fastest).
    pub speed: i32,
}

impl Default for PreviewSettings {
    fn default() -> PreviewSettings {
        PreviewSettings {
            max_width: 480,
            every: 1,
            fps: 30.0,
            speed: 10,
        }
    }
}

/// A preview that could not be written; every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum PreviewError {
    #[error("{path}: cannot create: {source}")]
    Create { path: PathBuf, source: io::Error },
    #[error("{path}: cannot write frame {frame}: {message}")]
    Write {
        path: PathBuf,
        frame: u64,
        message: String,
    },
    #[error("{path}: no frames were written")]
    Empty { path: PathBuf },
    #[error("{path}: cannot finish: {source}")]
    Finish { path: PathBuf, source: io::Error },
}

/// The file both the encoder (through [`Sink`]) and the preview hold, and the first write error,
/// which the encoder would otherwise swallow when it writes the trailer on drop.
struct Shared {
    writer: Option<BufWriter<File>>,
    error: Option<io::Error>,
}

fn lock(shared: &Mutex<Shared>) -> std::sync::MutexGuard<'_, Shared> {
    shared.lock().unwrap_or_else(PoisonError::into_inner)
}

/// The encoder's writer.
struct Sink(Arc<Mutex<Shared>>);

impl Sink {
    fn with<T>(&mut self, f: impl FnOnce(&mut BufWriter<File>) -> io::Result<T>) -> io::Result<T> {
        let mut shared = lock(&self.0);
        let result = match shared.writer.as_mut() {
            Some(w) => f(w),
            None => Err(io::Error::other("the preview file is closed")),
        };
        if let Err(e) = &result {
            if shared.error.is_none() {
                shared.error = Some(io::Error::new(e.kind(), e.to_string()));
            }
        }
        result
    }
}

impl Write for Sink {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.with(|w| w.write(buf))
    }

    fn flush(&mut self) -> io::Result<()> {
        self.with(|w| w.flush())
    }
}

/// An animated GIF being written.
pub struct GifPreview {
    path: PathBuf,
    tmp: PathBuf,
    settings: PreviewSettings,
    encoder: Option<GifEncoder<Sink>>,
    shared: Arc<Mutex<Shared>>,
    /// Output size, fixed by the first frame.
    size: Option<(u32, u32)>,
    seen: u64,
    written: u64,
}

impl GifPreview {
    /// Starts a preview that [`GifPreview::finish`] will leave at `path`.
    pub fn create(path: &Path, settings: PreviewSettings) -> Result<GifPreview, PreviewError> {
        let tmp = crate::io::temporary_path(path);
        let file = File::create(&tmp).map_err(|source| PreviewError::Create {
            path: path.to_owned(),
            source,
        })?;
        let shared = Arc::new(Mutex::new(Shared {
            writer: Some(BufWriter::new(file)),
            error: None,
        }));
        let mut encoder =
            GifEncoder::new_with_speed(Sink(Arc::clone(&shared)), settings.speed.clamp(1, 30));
        let mut preview = GifPreview {
            path: path.to_owned(),
            tmp,
            settings,
            encoder: None,
            shared,
            size: None,
            seen: 0,
            written: 0,
        };
        encoder
            .set_repeat(Repeat::Infinite)
            .map_err(|e| preview.write_error(e.to_string()))?;
        preview.encoder = Some(encoder);
        Ok(preview)
    }

    /// The final file name.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Frames encoded so far.
    pub fn frames_written(&self) -> u64 {
        self.written
    }

    /// Offers the next frame; returns whether it was kept and encoded.
    pub fn push(&mut self, frame: &RgbImage) -> Result<bool, PreviewError> {
        let index = self.seen;
        self.seen += 1;
        if !index.is_multiple_of(u64::from(self.settings.every.max(1))) || frame.width() == 0 {
            return Ok(false);
        }
        let (width, height) = *self
            .size
            .get_or_insert_with(|| preview_size(frame.dimensions(), self.settings.max_width));
        let rgba = downsized_rgba(frame, width, height);
        let delay = frame_delay(self.settings.every, self.settings.fps);
        let result = match self.encoder.as_mut() {
            Some(encoder) => encoder.encode_frame(Frame::from_parts(rgba, 0, 0, delay)),
            None => return Err(self.write_error("the preview is closed".into())),
        };
        result.map_err(|e| self.write_error(e.to_string()))?;
        self.written += 1;
        Ok(true)
    }

    /// Writes the GIF's trailer, flushes it to disk and renames it to its final name. Returns the
    /// number of frames written.
    pub fn finish(mut self) -> Result<u64, PreviewError> {
        let result = self.close();
        if result.is_err() {
            let _ = std::fs::remove_file(&self.tmp);
        }
        result
    }

    fn close(&mut self) -> Result<u64, PreviewError> {
        // Dropping the encoder writes the trailer through the sink.
        drop(self.encoder.take());
        if self.written == 0 {
            return Err(PreviewError::Empty {
                path: self.path.clone(),
            });
        }
        let finish = |source| PreviewError::Finish {
            path: self.path.clone(),
            source,
        };
        let (writer, error) = {
            let mut shared = lock(&self.shared);
            (shared.writer.take(), shared.error.take())
        };
        if let Some(e) = error {
            return Err(finish(e));
        }
        let writer = writer.ok_or_else(|| finish(io::Error::other("the file is closed")))?;
        let file = writer.into_inner().map_err(|e| finish(e.into_error()))?;
        file.sync_all().map_err(finish)?;
        drop(file);
        std::fs::rename(&self.tmp, &self.path).map_err(finish)?;
        Ok(self.written)
    }

    fn write_error(&self, message: String) -> PreviewError {
        PreviewError::Write {
            path: self.path.clone(),
            frame: self.seen.saturating_sub(1),
            message,
        }
    }
}

impl Drop for GifPreview {
    /// Not finished: the temporary file goes, nothing appears under the final name.
    fn drop(&mut self) {
        if self.encoder.is_some() {
            drop(self.encoder.take());
            drop(lock(&self.shared).writer.take());
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// Output size for a `(width, height)` frame: at most `max_width` wide (0 = unlimited), aspect kept,
/// at least 1 × 1, and within GIF's 65,535-pixel limit.
pub fn preview_size((width, height): (u32, u32), max_width: u32) -> (u32, u32) {
    let limit = if max_width == 0 { u32::MAX } else { max_width };
    let out_w = width.min(limit).clamp(1, u16::MAX as u32);
    let out_h = ((height as f64 * out_w as f64 / width.max(1) as f64).round() as u32)
        .clamp(1, u16::MAX as u32);
    (out_w, out_h)
}

/// `frame` scaled to `width × height` (triangle filter) as RGBA.
fn downsized_rgba(frame: &RgbImage, width: u32, height: u32) -> RgbaImage {
    let small;
    let src = if frame.dimensions() == (width, height) {
        frame
    } else {
        small = image::imageops::resize(frame, width, height, FilterType::Triangle);
        &small
    };
    let mut out = RgbaImage::new(width, height);
    for (d, s) in out.pixels_mut().zip(src.pixels()) {
        *d = image::Rgba([s[0], s[1], s[2], 255]);
    }
    out
}

/// Display time of one kept frame: `every / fps` seconds (30 fps if `fps` is not positive).
pub fn frame_delay(every: u32, fps: f32) -> Delay {
    let fps = if fps > 0.0 && fps.is_finite() {
        fps
    } else {
        30.0
    };
    Delay::from_saturating_duration(Duration::from_secs_f64(
        f64::from(every.max(1)) / f64::from(fps),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::AnimationDecoder;

    fn frame(shade: u8) -> RgbImage {
        RgbImage::from_fn(16, 8, |x, _| image::Rgb([shade, (x * 16) as u8, 0]))
    }

    #[test]
    fn writes_a_decodable_looping_gif_of_every_second_frame() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("preview.gif");
        let settings = PreviewSettings {
            max_width: 8,
            every: 2,
            fps: 25.0,
            speed: 30,
        };
        let mut gif = GifPreview::create(&path, settings).expect("create");
        let kept: Vec<bool> = (0..5)
            .map(|i| gif.push(&frame(i * 50)).expect("push"))
            .collect();
        assert_eq!(kept, [true, false, true, false, true]);
        assert!(!path.exists(), "nothing under the final name before finish");
        assert_eq!(gif.finish().expect("finish"), 3);
        let file = std::io::BufReader::new(File::open(&path).expect("open"));
        let decoder = image::codecs::gif::GifDecoder::new(file).expect("a GIF");
        let frames = decoder.into_frames().collect_frames().expect("frames");
        assert_eq!(frames.len(), 3);
        assert_eq!(frames[0].buffer().dimensions(), (8, 4));
        // 2 frames at 25 fps = 80 ms.
        assert_eq!(frames[0].delay().numer_denom_ms(), (80, 1));
        let names: Vec<_> = std::fs::read_dir(dir.path()).expect("dir").collect();
        assert_eq!(names.len(), 1, "no temporary file left");
    }

    #[test]
    fn an_unfinished_preview_leaves_no_file() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("preview.gif");
        let mut gif = GifPreview::create(&path, PreviewSettings::default()).expect("create");
        gif.push(&frame(10)).expect("push");
        drop(gif);
        assert!(!path.exists());
        assert_eq!(std::fs::read_dir(dir.path()).expect("dir").count(), 0);
    }

    #[test]
    fn errors_name_the_file() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("missing").join("preview.gif");
        let err = GifPreview::create(&path, PreviewSettings::default())
            .err()
            .expect("no directory");
        assert!(err.to_string().contains("preview.gif"), "{err}");
        let path = dir.path().join("empty.gif");
        let gif = GifPreview::create(&path, PreviewSettings::default()).expect("create");
        let err = gif.finish().unwrap_err();
        assert!(err.to_string().contains("empty.gif"), "{err}");
        assert_eq!(std::fs::read_dir(dir.path()).expect("dir").count(), 0);
    }

    #[test]
    fn sizes_keep_the_aspect_ratio() {
        assert_eq!(preview_size((1280, 720), 480), (480, 270));
        assert_eq!(preview_size((320, 240), 480), (320, 240));
        assert_eq!(preview_size((1280, 720), 0), (1280, 720));
    }
}
