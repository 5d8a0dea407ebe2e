//! Background plates for synthetic frames: real photographs and real video, plus moving clutter.
//!
//! [`discover`] walks the folders given on the command line: a folder whose images are all named by
//! numbers (`000000.jpg`, `000002.jpg`, …) is a video, played in order so the background really moves;
//! every other image is a still photograph. Plates are cropped to the camera's aspect ratio (with a
//! seed-chosen zoom and pan) and resampled bilinearly to its size. [`Clutter`] objects — textured or
//! flat rectangles and ellipses, some in the suit's own hues — slide across or flicker in front of the
//! plate and behind the person, so a segmenter cannot rely on a static background. The renderer
//! composites the person over the result.

use std::path::{Path, PathBuf};

use image::RgbImage;
use rand::Rng;

/// Frame rate of a folder of numbered video frames (the shipped `vtest` frames are 5 per second).
pub const VIDEO_FPS: f64 = 5.0;

/// One usable background.
#[derive(Clone, Debug, PartialEq)]
pub enum BackgroundSource {
    Photo(PathBuf),
    Video { dir: PathBuf, frames: Vec<PathBuf> },
}

impl BackgroundSource {
    pub fn describe(&self) -> String {
        match self {
            BackgroundSource::Photo(p) => p.display().to_string(),
            BackgroundSource::Video { dir, frames } => {
                format!("{} ({} video frames)", dir.display(), frames.len())
            }
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum BackgroundError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: cannot decode image: {source}")]
    Decode {
        path: PathBuf,
        source: image::ImageError,
    },
    #[error("no PNG or JPEG backgrounds found in {0}")]
    Empty(String),
}

fn is_image(path: &Path) -> bool {
    matches!(
        path.extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .as_deref(),
        Some("png" | "jpg" | "jpeg")
    )
}

fn numeric_stem(path: &Path) -> Option<u64> {
    path.file_stem()?.to_str()?.parse().ok()
}

/// Finds photographs and numbered video folders under `dirs` (recursively, three levels deep).
pub fn discover(dirs: &[PathBuf]) -> Result<Vec<BackgroundSource>, BackgroundError> {
    fn walk(
        dir: &Path,
        depth: usize,
        out: &mut Vec<BackgroundSource>,
    ) -> Result<(), BackgroundError> {
        let read = std::fs::read_dir(dir).map_err(|source| BackgroundError::Io {
            path: dir.to_owned(),
            source,
        })?;
        let mut images = Vec::new();
        let mut subdirs = Vec::new();
        for entry in read {
            let path = entry
                .map_err(|source| BackgroundError::Io {
                    path: dir.to_owned(),
                    source,
                })?
                .path();
            if path.is_dir() {
                subdirs.push(path);
            } else if is_image(&path) {
                images.push(path);
            }
        }
        images.sort();
        subdirs.sort();
        if images.len() >= 2 && images.iter().all(|p| numeric_stem(p).is_some()) {
            images.sort_by_key(|p| numeric_stem(p));
            out.push(BackgroundSource::Video {
                dir: dir.to_owned(),
                frames: images,
            });
        } else {
            out.extend(images.into_iter().map(BackgroundSource::Photo));
        }
        if depth < 3 {
            for sub in subdirs {
                walk(&sub, depth + 1, out)?;
            }
        }
        Ok(())
    }
    let mut out = Vec::new();
    for dir in dirs {
        if dir.is_file() && is_image(dir) {
            out.push(BackgroundSource::Photo(dir.clone()));
        } else {
            walk(dir, 0, &mut out)?;
        }
    }
    if out.is_empty() {
        let names: Vec<String> = dirs.iter().map(|d| d.display().to_string()).collect();
        return Err(BackgroundError::Empty(names.join(", ")));
    }
    Ok(out)
}

/// Which part of a plate is shown: a crop of the target aspect ratio, `zoom` ≥ 1 times smaller than
/// the largest such crop, its centre placed at (`pan_x`, `pan_y`) ∈ [0, 1]² of the free range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crop {
    pub zoom: f32,
    pub pan_x: f32,
    pub pan_y: f32,
}

/// Loads an image and returns the `crop` of it resampled to `width × height`.
pub fn load_plate(
    path: &Path,
    width: u32,
    height: u32,
    crop: Crop,
) -> Result<RgbImage, BackgroundError> {
    let image = image::open(path)
        .map_err(|source| BackgroundError::Decode {
            path: path.to_owned(),
            source,
        })?
        .to_rgb8();
    Ok(crop_resize(&image, width, height, crop))
}

/// Bilinear resampling of a crop of `src` (see [`Crop`]) to `width × height`.
pub fn crop_resize(src: &RgbImage, width: u32, height: u32, crop: Crop) -> RgbImage {
    let (sw, sh) = (src.width() as f32, src.height() as f32);
    let aspect = width as f32 / height as f32;
    let (mut cw, mut ch) = if sw / sh > aspect {
        (sh * aspect, sh)
    } else {
        (sw, sw / aspect)
    };
    cw /= crop.zoom.max(1.0);
    ch /= crop.zoom.max(1.0);
    let x0 = (sw - cw) * crop.pan_x.clamp(0.0, 1.0);
    let y0 = (sh - ch) * crop.pan_y.clamp(0.0, 1.0);
    let (sx, sy) = (cw / width as f32, ch / height as f32);
    let mut out = RgbImage::new(width, height);
    let raw = src.as_raw();
    let stride = src.width() as usize * 3;
    let (max_x, max_y) = (src.width() as usize - 1, src.height() as usize - 1);
    for (y, row) in out.rows_mut().enumerate() {
        let fy = (y0 + (y as f32 + 0.5) * sy - 0.5).max(0.0);
        let (iy, ty) = ((fy as usize).min(max_y), fy.fract());
        let iy1 = (iy + 1).min(max_y);
        for (x, pixel) in row.enumerate() {
            let fx = (x0 + (x as f32 + 0.5) * sx - 0.5).max(0.0);
            let (ix, tx) = ((fx as usize).min(max_x), fx.fract());
            let ix1 = (ix + 1).min(max_x);
            for c in 0..3 {
                let p = |xx: usize, yy: usize| raw[yy * stride + xx * 3 + c] as f32;
                let top = p(ix, iy) * (1.0 - tx) + p(ix1, iy) * tx;
                let bottom = p(ix, iy1) * (1.0 - tx) + p(ix1, iy1) * tx;
                pixel.0[c] = (top * (1.0 - ty) + bottom * ty + 0.5) as u8;
            }
        }
    }
    out
}

/// Shape of a clutter object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    Rectangle,
    Ellipse,
}

/// An object moving or flickering behind the person.
#[derive(Clone, Debug)]
pub struct Clutter {
    pub shape: Shape,
    /// Half extents, pixels.
    pub half_width: f32,
    pub half_height: f32,
    /// Centre at t = 0 and velocity (pixels/s); positions wrap around the image.
    pub start: (f32, f32),
    pub velocity: (f32, f32),
    /// Flicker: visible while `sin(2π t / period + phase) > 0`; `None` = always visible.
    pub flicker: Option<(f32, f32)>,
    /// Flat colour (RGB 0–255) or a texture the size of the object's bounding box.
    pub colour: [f32; 3],
    pub texture: Option<RgbImage>,
}

impl Clutter {
    /// A random object for a `width × height` image; `texture_from` optionally lends a photo patch.
    pub fn random(
        rng: &mut impl Rng,
        width: u32,
        height: u32,
        texture_from: Option<&RgbImage>,
    ) -> Clutter {
        let (w, h) = (width as f32, height as f32);
        let half_width = rng.gen_range(0.04..0.14) * w;
        let half_height = rng.gen_range(0.04..0.2) * h;
        let speed = rng.gen_range(0.03..0.3) * w;
        let angle: f32 = rng.gen_range(0.0..std::f32::consts::TAU);
        let moving = rng.gen_bool(0.75);
        let flicker = (!moving || rng.gen_bool(0.3))
            .then(|| (rng.gen_range(0.4..2.5), rng.gen_range(0.0..6.3)));
        // Hues anywhere on the circle, the suit's own included: a segmenter must use more than colour.
        let hsv = suitcap::colour::Hsv {
            hue: rng.gen_range(0.0..360.0),
            saturation: rng.gen_range(0.2..0.9),
            value: rng.gen_range(0.25..0.95),
        };
        let colour = hsv.to_rgb().map(|c| c * 255.0);
        let texture = texture_from.filter(|_| rng.gen_bool(0.5)).map(|src| {
            let crop = Crop {
                zoom: rng.gen_range(2.0..5.0),
                pan_x: rng.gen(),
                pan_y: rng.gen(),
            };
            crop_resize(
                src,
                (2.0 * half_width).ceil().max(1.0) as u32,
                (2.0 * half_height).ceil().max(1.0) as u32,
                crop,
            )
        });
        Clutter {
            shape: if rng.gen_bool(0.5) {
                Shape::Rectangle
            } else {
                Shape::Ellipse
            },
            half_width,
            half_height,
            start: (rng.gen_range(0.0..w), rng.gen_range(0.0..h)),
            velocity: if moving {
                (speed * angle.cos(), speed * angle.sin() * 0.4)
            } else {
                (0.0, 0.0)
            },
            flicker,
            colour,
            texture,
        }
    }

    /// Draws the object at time `t` seconds into an RGB f32 image of `width × height`.
    pub fn draw(&self, t: f32, rgb: &mut [[f32; 3]], width: u32, height: u32) {
        if let Some((period, phase)) = self.flicker {
            if (std::f32::consts::TAU * t / period + phase).sin() <= 0.0 {
                return;
            }
        }
        let (w, h) = (width as f32, height as f32);
        let span_x = w + 2.0 * self.half_width;
        let span_y = h + 2.0 * self.half_height;
        let cx = (self.start.0 + self.velocity.0 * t + self.half_width).rem_euclid(span_x)
            - self.half_width;
        let cy = (self.start.1 + self.velocity.1 * t + self.half_height).rem_euclid(span_y)
            - self.half_height;
        let x0 = (cx - self.half_width).floor().max(0.0) as u32;
        let x1 = ((cx + self.half_width).ceil().max(0.0) as u32).min(width);
        let y0 = (cy - self.half_height).floor().max(0.0) as u32;
        let y1 = ((cy + self.half_height).ceil().max(0.0) as u32).min(height);
        for y in y0..y1 {
            for x in x0..x1 {
                let dx = (x as f32 + 0.5 - cx) / self.half_width;
                let dy = (y as f32 + 0.5 - cy) / self.half_height;
                let inside = match self.shape {
                    Shape::Rectangle => dx.abs() <= 1.0 && dy.abs() <= 1.0,
                    Shape::Ellipse => dx * dx + dy * dy <= 1.0,
                };
                if !inside {
                    continue;
                }
                let colour = match &self.texture {
                    Some(tex) => {
                        let tx =
                            (((dx + 1.0) * 0.5 * tex.width() as f32) as u32).min(tex.width() - 1);
                        let ty =
                            (((dy + 1.0) * 0.5 * tex.height() as f32) as u32).min(tex.height() - 1);
                        tex.get_pixel(tx, ty).0.map(f32::from)
                    }
                    None => self.colour,
                };
                rgb[(y * width + x) as usize] = colour;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbered_folders_are_videos_and_other_images_photos() {
        let dir = tempfile::tempdir().expect("tempdir");
        let video = dir.path().join("walk");
        std::fs::create_dir(&video).expect("mkdir");
        let img = RgbImage::new(4, 3);
        for name in ["000004.jpg", "000000.jpg", "000002.jpg"] {
            img.save(video.join(name)).expect("save");
        }
        img.save(dir.path().join("room.png")).expect("save");
        std::fs::write(dir.path().join("notes.txt"), "x").expect("write");
        let found = discover(&[dir.path().to_owned()]).expect("found");
        assert_eq!(found.len(), 2);
        assert_eq!(
            found[0],
            BackgroundSource::Photo(dir.path().join("room.png"))
        );
        match &found[1] {
            BackgroundSource::Video { frames, .. } => {
                let names: Vec<_> = frames
                    .iter()
                    .map(|f| f.file_name().map(|n| n.to_owned()))
                    .collect();
                assert_eq!(
                    names,
                    ["000000.jpg", "000002.jpg", "000004.jpg"].map(|n| Some(n.into()))
                );
            }
            other => panic!("expected a video, got {other:?}"),
        }
        assert!(discover(&[video.join("000000.jpg").with_file_name("none")]).is_err());
    }

    #[test]
    fn crop_resize_of_a_flat_image_is_flat_and_keeps_gradients_in_order() {
        let mut src = RgbImage::new(8, 6);
        for (x, _, p) in src.enumerate_pixels_mut() {
            p.0 = [x as u8 * 30, 100, 7];
        }
        let out = crop_resize(
            &src,
            4,
            3,
            Crop {
                zoom: 1.0,
                pan_x: 0.5,
                pan_y: 0.5,
            },
        );
        assert_eq!(out.dimensions(), (4, 3));
        for y in 0..3 {
            assert_eq!(out.get_pixel(0, y).0[1], 100);
            let reds: Vec<u8> = (0..4).map(|x| out.get_pixel(x, y).0[0]).collect();
            assert!(reds.windows(2).all(|w| w[0] < w[1]), "{reds:?}");
        }
    }

    #[test]
    fn clutter_moves_with_time() {
        let clutter = Clutter {
            shape: Shape::Rectangle,
            half_width: 2.0,
            half_height: 2.0,
            start: (5.0, 5.0),
            velocity: (10.0, 0.0),
            flicker: None,
            colour: [255.0, 0.0, 0.0],
            texture: None,
        };
        let mut a = vec![[0.0; 3]; 40 * 10];
        clutter.draw(0.0, &mut a, 40, 10);
        assert_eq!(a[5 * 40 + 5], [255.0, 0.0, 0.0]);
        let mut b = vec![[0.0; 3]; 40 * 10];
        clutter.draw(1.0, &mut b, 40, 10);
        assert_eq!(b[5 * 40 + 5], [0.0; 3]);
        assert_eq!(b[5 * 40 + 15], [255.0, 0.0, 0.0]);
    }
}
