//! Frames held in memory, replayed as a stream: the benchmark's input and a source that fails on cue
//! for tests of what the pipeline keeps when a camera dies mid-take. Frames are kept either decoded
//! or as the encoded bytes of their files (JPEG, PNG), decoded at every delivery like the MJPEG
//! stream of a webcam, which keeps a high-resolution clip small in memory.

use std::time::Duration;

use super::convert::decode_frame;
use super::{Frame, FrameSource, SourceError};

/// Replays `frames` cyclically for `length` frames at `fps`, optionally failing like an unplugged
/// camera at frame `fail_at`.
#[derive(Clone, Debug)]
pub struct MemorySource {
    frames: Vec<Stored>,
    size: (u32, u32),
    fps: f64,
    length: u64,
    next: u64,
    fail_at: Option<u64>,
}

#[derive(Clone, Debug)]
enum Stored {
    Decoded(image::RgbImage),
    Encoded(Vec<u8>),
}

impl MemorySource {
    /// `None` when `frames` is empty or the frames differ in size.
    pub fn new(frames: Vec<image::RgbImage>, fps: f64, length: u64) -> Option<MemorySource> {
        let size = frames.first()?.dimensions();
        if frames.iter().any(|f| f.dimensions() != size) {
            return None;
        }
        MemorySource::from_stored(
            frames.into_iter().map(Stored::Decoded).collect(),
            size,
            fps,
            length,
        )
    }

    /// Frames kept as encoded image files, decoded when delivered. `Err` names the first file that
    /// does not decode or differs in size from the first.
    pub fn from_encoded(
        files: Vec<(String, Vec<u8>)>,
        fps: f64,
        length: u64,
    ) -> Result<MemorySource, String> {
        let mut size = None;
        for (name, bytes) in &files {
            let dims = decode_frame(bytes)
                .map_err(|e| format!("{name}: {e}"))?
                .dimensions();
            if *size.get_or_insert(dims) != dims {
                return Err(format!(
                    "{name}: {}x{} differs from the first frame",
                    dims.0, dims.1
                ));
            }
        }
        let size = size.ok_or("no frames")?;
        let stored = files.into_iter().map(|(_, b)| Stored::Encoded(b)).collect();
        MemorySource::from_stored(stored, size, fps, length).ok_or_else(|| "no frames".to_owned())
    }

    fn from_stored(
        frames: Vec<Stored>,
        size: (u32, u32),
        fps: f64,
        length: u64,
    ) -> Option<MemorySource> {
        (!frames.is_empty()).then_some(MemorySource {
            frames,
            size,
            fps,
            length,
            next: 0,
            fail_at: None,
        })
    }

    /// Frame `index` fails with a device error that ends the stream.
    pub fn failing_at(mut self, index: u64) -> MemorySource {
        self.fail_at = Some(index);
        self
    }
}

impl FrameSource for MemorySource {
    fn next_frame(&mut self) -> Result<Option<Frame>, SourceError> {
        if self.next >= self.length || self.fail_at.is_some_and(|f| self.next > f) {
            return Ok(None);
        }
        let index = self.next;
        self.next += 1;
        if self.fail_at == Some(index) {
            return Err(SourceError::Device {
                device: "memory".to_owned(),
                action: "dequeue a frame",
                source: std::io::Error::from_raw_os_error(19), // ENODEV: the device went away
            });
        }
        let image = match &self.frames[(index % self.frames.len() as u64) as usize] {
            Stored::Decoded(image) => image.clone(),
            Stored::Encoded(bytes) => {
                decode_frame(bytes).map_err(|e| SourceError::CorruptFrame {
                    source_name: "memory".to_owned(),
                    index,
                    reason: e.to_string(),
                })?
            }
        };
        Ok(Some(Frame {
            index,
            timestamp: Duration::from_secs_f64(index as f64 / self.fps),
            image,
        }))
    }

    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn frame_rate(&self) -> Option<f64> {
        Some(self.fps)
    }

    fn describe(&self) -> String {
        format!(
            "{} frames in memory, {}x{} @{}fps, replayed for {}",
            self.frames.len(),
            self.size.0,
            self.size.1,
            self.fps,
            self.length
        )
    }
}

/// Delivers another source's frames no faster than their timestamps, as a camera would: for running
/// the live app on a recorded file.
pub struct Paced<S> {
    inner: S,
    started: Option<std::time::Instant>,
}

impl<S: FrameSource> Paced<S> {
    pub fn new(inner: S) -> Paced<S> {
        Paced {
            inner,
            started: None,
        }
    }
}

impl<S: FrameSource> FrameSource for Paced<S> {
    fn next_frame(&mut self) -> Result<Option<Frame>, SourceError> {
        let frame = self.inner.next_frame()?;
        if let Some(f) = &frame {
            let started = *self.started.get_or_insert_with(std::time::Instant::now);
            let due = started + f.timestamp;
            let now = std::time::Instant::now();
            if due > now {
                std::thread::sleep(due - now);
            }
        }
        Ok(frame)
    }

    fn size(&self) -> (u32, u32) {
        self.inner.size()
    }

    fn frame_rate(&self) -> Option<f64> {
        self.inner.frame_rate()
    }

    fn describe(&self) -> String {
        format!("{} (paced)", self.inner.describe())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replays_cyclically_and_fails_on_cue() {
        let frames = vec![
            image::RgbImage::new(2, 2),
            image::RgbImage::from_pixel(2, 2, image::Rgb([9, 9, 9])),
        ];
        let mut source = MemorySource::new(frames, 10.0, 5)
            .expect("frames")
            .failing_at(3);
        let mut seen = Vec::new();
        let error = loop {
            match source.next_frame() {
                Ok(Some(f)) => seen.push((f.index, f.image.get_pixel(0, 0).0[0], f.timestamp)),
                Ok(None) => break None,
                Err(e) => break Some(e),
            }
        };
        assert_eq!(
            seen.iter().map(|s| (s.0, s.1)).collect::<Vec<_>>(),
            [(0, 0), (1, 9), (2, 0)]
        );
        assert_eq!(seen[2].2, Duration::from_millis(200));
        assert!(error.is_some_and(|e| e.to_string().contains("dequeue")));
        assert!(matches!(source.next_frame(), Ok(None)));
        assert!(MemorySource::new(Vec::new(), 30.0, 1).is_none());
    }
}
