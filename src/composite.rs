//! Compositing and debug overlays: the rendered garment blended into the video frame, and the
//! mask, markers, skeleton and status text drawn over it with tiny-skia.
//!
//! - [`Compositor::composite`] is the fast path for a frame with only the garment: it blends the
//!   [`GarmentLayer`] source-over (premultiplied) straight into the frame's RGB rows under the
//!   layer's rectangle ([`blend_over`]), optionally in parallel bands with rayon. This one blend is
//!   written here, not left to tiny-skia: tiny-skia 0.11 draws a pixmap only through its
//!   floating-point pipeline (its 8-bit pipeline has no gather stage), where three quarters of the
//!   1.6–1.7 ms this step took at 1280×720 went, while over an opaque frame source-over is one
//!   multiply-add per channel: 0.16 ms (`cargo bench --bench render`, docs/measurements.md, seventh
//!   session of 2026-12-07), the same pixels on the quick start.
//! - [`Compositor::canvas`] converts the whole frame into a [`Canvas`] for the garment plus debug
//!   overlays — the person mask tinted, markers as small circles, the skeleton as antialiased lines,
//!   and text lines (timings, "no person", drops, "REC") in a hand-coded 5×7 bitmap font drawn as
//!   filled rectangles on a dark backdrop — and [`Canvas::finish`] writes it back into an RGB frame.
//!   tiny-skia draws on premultiplied RGBA; the frame is opaque, so the conversion is just adding
//!   (and later dropping) an alpha of 255, into a buffer the [`Compositor`] keeps. The canvas blends
//!   the garment with [`blend_over`] too, so that both paths give the same pixels.
//!
//! The result is the frame's RGB pixels, ready for the preview window, PNG frames or the GIF preview
//! ([`crate::preview`]).

use glam::Vec2;
use image::RgbImage;
use rayon::prelude::*;
use tiny_skia::{
    FillRule, LineCap, LineJoin, Paint, PathBuilder, PixmapMut, Rect, Stroke, Transform,
};

use crate::mask::Mask;
use crate::render::GarmentLayer;

/// Rows per parallel band at least, so tiny frames are not split into slivers.
const MIN_BAND_ROWS: usize = 16;

/// Something that cannot be composited.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum CompositeError {
    #[error("{what} is {width}×{height} but the frame is {frame_width}×{frame_height}")]
    SizeMismatch {
        what: &'static str,
        width: u32,
        height: u32,
        frame_width: u32,
        frame_height: u32,
    },
    #[error("a {width}×{height} frame has no pixels to draw on")]
    EmptyFrame { width: u32, height: u32 },
}

fn same_size(
    what: &'static str,
    (width, height): (u32, u32),
    frame: (u32, u32),
) -> Result<(), CompositeError> {
    if (width, height) == frame {
        Ok(())
    } else {
        Err(CompositeError::SizeMismatch {
            what,
            width,
            height,
            frame_width: frame.0,
            frame_height: frame.1,
        })
    }
}

/// Opaque RGB pixels → RGBA with alpha 255 (premultiplied and straight alike). Converts
/// `min(rgb.len()/3, rgba.len()/4)` pixels.
pub fn rgb_to_rgba(rgb: &[u8], rgba: &mut [u8]) {
    for (s, d) in rgb.chunks_exact(3).zip(rgba.chunks_exact_mut(4)) {
        d.copy_from_slice(&[s[0], s[1], s[2], 255]);
    }
}

/// RGBA → RGB, dropping alpha (the canvas over an opaque frame stays opaque).
pub fn rgba_to_rgb(rgba: &[u8], rgb: &mut [u8]) {
    for (s, d) in rgba.chunks_exact(4).zip(rgb.chunks_exact_mut(3)) {
        d.copy_from_slice(&s[..3]);
    }
}

/// `x / 255` rounded to nearest, exact for `x ≤ 255 · 255`.
#[inline]
fn div255(x: u32) -> u32 {
    let x = x + 128;
    (x + (x >> 8)) >> 8
}

/// Blends the premultiplied RGBA pixels of `layer` source-over onto the opaque pixels of `dst`,
/// whose colour channels are the first three of every `dst_channels` bytes (3 for RGB, 4 for
/// RGBA, whose alpha stays 255): `dst = src + dst · (255 − α) / 255`, rounded. Blends
/// `min(layer.len() / 4, dst.len() / dst_channels)` pixels.
pub fn blend_over(dst: &mut [u8], dst_channels: usize, layer: &[u8]) {
    for (d, s) in dst
        .chunks_exact_mut(dst_channels)
        .zip(layer.chunks_exact(4))
    {
        match s[3] {
            0 => {}
            255 => d[..3].copy_from_slice(&s[..3]),
            alpha => {
                let keep = 255 - alpha as u32;
                for (d, &s) in d[..3].iter_mut().zip(&s[..3]) {
                    // A premultiplied channel is at most its alpha, so this stays within 255.
                    *d = (s as u32 + div255(*d as u32 * keep)).min(255) as u8;
                }
            }
        }
    }
}

/// Rows per band when `rows` are split over the rayon pool (all of them when not parallel).
fn band_rows(rows: usize, parallel: bool) -> usize {
    if parallel {
        rows.div_ceil(rayon::current_num_threads().max(1))
            .max(MIN_BAND_ROWS)
    } else {
        rows.max(1)
    }
}

/// A small coloured circle, e.g. a detected marker's centroid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MarkerDot {
    /// Pixel position (pixel centres at +0.5).
    pub centre: Vec2,
    pub colour: [u8; 3],
}

/// How [`Canvas::text`] draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TextStyle {
    pub colour: [u8; 3],
    /// Pixels per font cell (1 = 5×7 pixel glyphs on a 6×8 pitch).
    pub scale: u32,
    /// RGBA (straight alpha) of the box behind the text; alpha 0 for none.
    pub backdrop: [u8; 4],
}

impl Default for TextStyle {
    fn default() -> TextStyle {
        TextStyle {
            colour: [255, 255, 255],
            scale: 2,
            backdrop: [0, 0, 0, 170],
        }
    }
}

/// Blends garment layers and overlays into frames, reusing its buffers.
#[derive(Clone, Debug, Default)]
pub struct Compositor {
    parallel: bool,
    /// RGBA of the whole frame, for [`Compositor::canvas`].
    canvas: Vec<u8>,
    mask: Option<tiny_skia::Mask>,
}

impl Compositor {
    /// `parallel`: split the pixel work into row bands over the rayon pool.
    pub fn new(parallel: bool) -> Compositor {
        Compositor {
            parallel,
            ..Compositor::default()
        }
    }

    /// Blends `layer` source-over into `frame`, touching only the layer's rectangle.
    pub fn composite(
        &mut self,
        frame: &mut RgbImage,
        layer: &GarmentLayer,
    ) -> Result<(), CompositeError> {
        same_size("the garment layer", layer.frame_size(), frame.dimensions())?;
        let Some(rect) = layer.bounds() else {
            return Ok(());
        };
        let stride = frame.width() as usize * 3;
        let (x0, y0) = (rect.x as usize, rect.y as usize);
        let (width, height) = (rect.width as usize, rect.height as usize);
        let pixels: &mut [u8] = frame;
        let rows = &mut pixels[y0 * stride..(y0 + height) * stride];
        let band = band_rows(height, self.parallel);
        let blend_rows = |rows: &mut [u8], layer: &[u8]| {
            for (row, layer_row) in rows.chunks_mut(stride).zip(layer.chunks(width * 4)) {
                blend_over(&mut row[x0 * 3..][..width * 3], 3, layer_row);
            }
        };
        if band >= height {
            blend_rows(rows, layer.data());
        } else {
            rows.par_chunks_mut(band * stride)
                .zip(layer.data().par_chunks(band * width * 4))
                .for_each(|(rows, layer)| blend_rows(rows, layer));
        }
        Ok(())
    }

    /// The whole of `frame` as a canvas for the garment and debug overlays.
    pub fn canvas(&mut self, frame: &RgbImage) -> Result<Canvas<'_>, CompositeError> {
        let (width, height) = frame.dimensions();
        if width == 0 || height == 0 {
            return Err(CompositeError::EmptyFrame { width, height });
        }
        self.canvas.resize(width as usize * height as usize * 4, 0);
        let band = band_rows(height as usize, self.parallel) * width as usize;
        let src: &[u8] = frame;
        if self.parallel {
            self.canvas
                .par_chunks_mut(band * 4)
                .zip(src.par_chunks(band * 3))
                .for_each(|(rgba, rgb)| rgb_to_rgba(rgb, rgba));
        } else {
            rgb_to_rgba(src, &mut self.canvas);
        }
        let pixmap = PixmapMut::from_bytes(&mut self.canvas, width, height)
            .ok_or(CompositeError::EmptyFrame { width, height })?;
        Ok(Canvas {
            pixmap,
            mask: &mut self.mask,
            parallel: self.parallel,
        })
    }
}

/// A frame as premultiplied RGBA, to draw the garment and overlays on; [`Canvas::finish`] writes it
/// back.
pub struct Canvas<'a> {
    pixmap: PixmapMut<'a>,
    mask: &'a mut Option<tiny_skia::Mask>,
    parallel: bool,
}

fn solid(rgb: [u8; 3], alpha: u8) -> Paint<'static> {
    let mut paint = Paint::default();
    paint.set_color_rgba8(rgb[0], rgb[1], rgb[2], alpha);
    paint.anti_alias = true;
    paint
}

impl<'a> Canvas<'a> {
    pub fn width(&self) -> u32 {
        self.pixmap.width()
    }

    pub fn height(&self) -> u32 {
        self.pixmap.height()
    }

    /// The pixels, for drawing anything else with tiny-skia.
    pub fn pixmap_mut(&mut self) -> &mut PixmapMut<'a> {
        &mut self.pixmap
    }

    /// Blends the garment layer source-over ([`blend_over`]).
    pub fn garment(&mut self, layer: &GarmentLayer) -> Result<(), CompositeError> {
        same_size("the garment layer", layer.frame_size(), self.size())?;
        let Some(rect) = layer.bounds() else {
            return Ok(());
        };
        let stride = self.pixmap.width() as usize * 4;
        let (x0, y0, width) = (rect.x as usize, rect.y as usize, rect.width as usize);
        let rows = self.pixmap.data_mut()[y0 * stride..].chunks_mut(stride);
        for (row, layer_row) in rows.zip(layer.data().chunks(width * 4)) {
            blend_over(&mut row[x0 * 4..][..width * 4], 4, layer_row);
        }
        Ok(())
    }

    /// Tints the person pixels with `tint` (RGBA, straight alpha: how strongly).
    pub fn mask(&mut self, mask: &Mask, tint: [u8; 4]) -> Result<(), CompositeError> {
        same_size("the mask", (mask.width(), mask.height()), self.size())?;
        let (width, height) = self.size();
        let fits = self
            .mask
            .as_ref()
            .is_some_and(|m| (m.width(), m.height()) == (width, height));
        if !fits {
            *self.mask = tiny_skia::Mask::new(width, height);
        }
        let Some(alpha) = self.mask.as_mut() else {
            return Err(CompositeError::EmptyFrame { width, height });
        };
        for (a, &p) in alpha.data_mut().iter_mut().zip(mask.pixels()) {
            *a = if p { 255 } else { 0 };
        }
        let paint = solid([tint[0], tint[1], tint[2]], tint[3]);
        if let Some(rect) = Rect::from_xywh(0.0, 0.0, width as f32, height as f32) {
            self.pixmap
                .fill_rect(rect, &paint, Transform::identity(), Some(alpha));
        }
        Ok(())
    }

    /// Markers as filled circles of `radius` pixels with a thin dark outline.
    pub fn markers(&mut self, markers: &[MarkerDot], radius: f32) {
        let outline = Stroke {
            width: 1.0,
            ..Stroke::default()
        };
        let dark = solid([0, 0, 0], 200);
        for m in markers {
            let Some(circle) = PathBuilder::from_circle(m.centre.x, m.centre.y, radius) else {
                continue;
            };
            self.pixmap.fill_path(
                &circle,
                &solid(m.colour, 255),
                FillRule::Winding,
                Transform::identity(),
                None,
            );
            self.pixmap
                .stroke_path(&circle, &dark, &outline, Transform::identity(), None);
        }
    }

    /// The skeleton: an antialiased line of `width` pixels per (parent, child) pixel pair, over a
    /// slightly wider dark line for contrast.
    pub fn skeleton(&mut self, bones: &[(Vec2, Vec2)], colour: [u8; 3], width: f32) {
        let mut pb = PathBuilder::new();
        for (a, b) in bones {
            if a.is_finite() && b.is_finite() {
                pb.move_to(a.x, a.y);
                pb.line_to(b.x, b.y);
            }
        }
        let Some(path) = pb.finish() else {
            return;
        };
        let stroke = |width: f32| Stroke {
            width,
            line_cap: LineCap::Round,
            line_join: LineJoin::Round,
            ..Stroke::default()
        };
        self.pixmap.stroke_path(
            &path,
            &solid([0, 0, 0], 140),
            &stroke(width + 2.0),
            Transform::identity(),
            None,
        );
        self.pixmap.stroke_path(
            &path,
            &solid(colour, 255),
            &stroke(width),
            Transform::identity(),
            None,
        );
    }

    /// Text lines with their top-left corner (of the backdrop) at pixel (x, y). Characters outside
    /// printable ASCII but '°' draw as '?'.
    pub fn text<S: AsRef<str>>(&mut self, x: f32, y: f32, lines: &[S], style: &TextStyle) {
        let s = style.scale.max(1) as f32;
        let pad = 2.0 * s;
        let columns = lines
            .iter()
            .map(|l| l.as_ref().chars().count())
            .max()
            .unwrap_or(0);
        if columns == 0 {
            return;
        }
        let box_w = columns as f32 * font::PITCH_X as f32 * s - s + 2.0 * pad;
        let box_h = lines.len() as f32 * font::PITCH_Y as f32 * s - s + 2.0 * pad;
        if style.backdrop[3] > 0 {
            if let Some(rect) = Rect::from_xywh(x, y, box_w, box_h) {
                let backdrop = style.backdrop;
                let mut paint = solid([backdrop[0], backdrop[1], backdrop[2]], backdrop[3]);
                paint.anti_alias = false;
                self.pixmap
                    .fill_rect(rect, &paint, Transform::identity(), None);
            }
        }
        let mut pb = PathBuilder::new();
        for (row, line) in lines.iter().enumerate() {
            let top = y + pad + (row * font::PITCH_Y as usize) as f32 * s;
            for (col, c) in line.as_ref().chars().enumerate() {
                let left = x + pad + (col * font::PITCH_X as usize) as f32 * s;
                for (gy, x0, x1) in font::runs(c) {
                    let rect = Rect::from_ltrb(
                        left + x0 as f32 * s,
                        top + gy as f32 * s,
                        left + x1 as f32 * s,
                        top + (gy + 1) as f32 * s,
                    );
                    if let Some(rect) = rect {
                        pb.push_rect(rect);
                    }
                }
            }
        }
        if let Some(path) = pb.finish() {
            let mut paint = solid(style.colour, 255);
            paint.anti_alias = false;
            self.pixmap.fill_path(
                &path,
                &paint,
                FillRule::Winding,
                Transform::identity(),
                None,
            );
        }
    }

    /// Writes the canvas into `frame` (same size) as RGB.
    pub fn finish(self, frame: &mut RgbImage) -> Result<(), CompositeError> {
        same_size("the canvas", self.size(), frame.dimensions())?;
        let band =
            band_rows(self.pixmap.height() as usize, self.parallel) * self.pixmap.width() as usize;
        let rgba: &[u8] = self.pixmap.as_ref().data();
        let rgb: &mut [u8] = frame;
        if self.parallel {
            rgb.par_chunks_mut(band * 3)
                .zip(rgba.par_chunks(band * 4))
                .for_each(|(rgb, rgba)| rgba_to_rgb(rgba, rgb));
        } else {
            rgba_to_rgb(rgba, rgb);
        }
        Ok(())
    }

    fn size(&self) -> (u32, u32) {
        (self.pixmap.width(), self.pixmap.height())
    }
}

/// A 5×7 bitmap font for printable ASCII (after the classic HD44780 character ROM).
pub mod font {
    /// Glyph cell pitch in font pixels: 5 + 1 columns, 7 + 1 rows.
    pub const PITCH_X: u32 = 6;
    pub const PITCH_Y: u32 = 8;

    /// The degree sign, the one character beyond printable ASCII (angle errors are in degrees).
    const DEGREE: [u8; 7] = [0x0C, 0x12, 0x12, 0x0C, 0x00, 0x00, 0x00];

    /// Rows top to bottom; bit 4 is the leftmost column.
    pub fn glyph(c: char) -> [u8; 7] {
        if c == '°' {
            return DEGREE;
        }
        let code = c as u32;
        let index = if (32..=126).contains(&code) {
            code - 32
        } else {
            '?' as u32 - 32
        };
        GLYPHS[index as usize]
    }

    /// Horizontal runs of set pixels of `c`'s glyph: (row, first column, end column exclusive).
    pub fn runs(c: char) -> impl Iterator<Item = (u32, u32, u32)> {
        let rows = glyph(c);
        (0..7u32).flat_map(move |y| {
            let bits = rows[y as usize];
            let mut out = [(0u32, 0u32, 0u32); 3];
            let mut n = 0;
            let mut x = 0;
            while x < 5 {
                if bits & (0x10 >> x) != 0 {
                    let start = x;
                    while x < 5 && bits & (0x10 >> x) != 0 {
                        x += 1;
                    }
                    out[n] = (y, start, x);
                    n += 1;
                } else {
                    x += 1;
                }
            }
            out.into_iter().take(n)
        })
    }

    #[rustfmt::skip]
    const GLYPHS: [[u8; 7]; 95] = [
        [0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00], // ' '
        [0x04, 0x04, 0x04, 0x04, 0x00, 0x00, 0x04], // !
        [0x0A, 0x0A, 0x0A, 0x00, 0x00, 0x00, 0x00], // "
        [0x0A, 0x0A, 0x1F, 0x0A, 0x1F, 0x0A, 0x0A], // #
        [0x04, 0x0F, 0x14, 0x0E, 0x05, 0x1E, 0x04], // $
        [0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03], // %
        [0x0C, 0x12, 0x14, 0x08, 0x15, 0x12, 0x0D], // &
        [0x0C, 0x04, 0x08, 0x00, 0x00, 0x00, 0x00], // '
        [0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02], // (
        [0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08], // )
        [0x00, 0x04, 0x15, 0x0E, 0x15, 0x04, 0x00], // *
        [0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00], // +
        [0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08], // ,
        [0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00], // -
        [0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C], // .
        [0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00], // /
        [0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E], // 0
        [0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E], // 1
        [0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F], // 2
        [0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E], // 3
        [0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02], // 4
        [0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E], // 5
        [0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E], // 6
        [0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08], // 7
        [0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E], // 8
        [0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C], // 9
        [0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00], // :
        [0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x04, 0x08], // ;
        [0x02, 0x04, 0x08, 0x10, 0x08, 0x04, 0x02], // <
        [0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00], // =
        [0x08, 0x04, 0x02, 0x01, 0x02, 0x04, 0x08], // >
        [0x0E, 0x11, 0x01, 0x02, 0x04, 0x00, 0x04], // ?
        [0x0E, 0x11, 0x01, 0x0D, 0x15, 0x15, 0x0E], // @
        [0x0E, 0x11, 0x11, 0x11, 0x1F, 0x11, 0x11], // A
        [0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E], // B
        [0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E], // C
        [0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C], // D
        [0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F], // E
        [0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10], // F
        [0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F], // G
        [0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11], // H
        [0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E], // I
        [0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C], // J
        [0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11], // K
        [0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F], // L
        [0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11], // M
        [0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11], // N
        [0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E], // O
        [0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10], // P
        [0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D], // Q
        [0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11], // R
        [0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E], // S
        [0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04], // T
        [0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E], // U
        [0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04], // V
        [0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A], // W
        [0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11], // X
        [0x11, 0x11, 0x11, 0x0A, 0x04, 0x04, 0x04], // Y
        [0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F], // Z
        [0x0E, 0x08, 0x08, 0x08, 0x08, 0x08, 0x0E], // [
        [0x00, 0x10, 0x08, 0x04, 0x02, 0x01, 0x00], // backslash
        [0x0E, 0x02, 0x02, 0x02, 0x02, 0x02, 0x0E], // ]
        [0x04, 0x0A, 0x11, 0x00, 0x00, 0x00, 0x00], // ^
        [0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F], // _
        [0x08, 0x04, 0x02, 0x00, 0x00, 0x00, 0x00], // `
        [0x00, 0x00, 0x0E, 0x01, 0x0F, 0x11, 0x0F], // a
        [0x10, 0x10, 0x16, 0x19, 0x11, 0x11, 0x1E], // b
        [0x00, 0x00, 0x0E, 0x10, 0x10, 0x11, 0x0E], // c
        [0x01, 0x01, 0x0D, 0x13, 0x11, 0x11, 0x0F], // d
        [0x00, 0x00, 0x0E, 0x11, 0x1F, 0x10, 0x0E], // e
        [0x06, 0x09, 0x08, 0x1C, 0x08, 0x08, 0x08], // f
        [0x00, 0x0F, 0x11, 0x11, 0x0F, 0x01, 0x0E], // g
        [0x10, 0x10, 0x16, 0x19, 0x11, 0x11, 0x11], // h
        [0x04, 0x00, 0x0C, 0x04, 0x04, 0x04, 0x0E], // i
        [0x02, 0x00, 0x06, 0x02, 0x02, 0x12, 0x0C], // j
        [0x10, 0x10, 0x12, 0x14, 0x18, 0x14, 0x12], // k
        [0x0C, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E], // l
        [0x00, 0x00, 0x1A, 0x15, 0x15, 0x11, 0x11], // m
        [0x00, 0x00, 0x16, 0x19, 0x11, 0x11, 0x11], // n
        [0x00, 0x00, 0x0E, 0x11, 0x11, 0x11, 0x0E], // o
        [0x00, 0x00, 0x1E, 0x11, 0x1E, 0x10, 0x10], // p
        [0x00, 0x00, 0x0D, 0x13, 0x0F, 0x01, 0x01], // q
        [0x00, 0x00, 0x16, 0x19, 0x10, 0x10, 0x10], // r
        [0x00, 0x00, 0x0E, 0x10, 0x0E, 0x01, 0x1E], // s
        [0x08, 0x08, 0x1C, 0x08, 0x08, 0x09, 0x06], // t
        [0x00, 0x00, 0x11, 0x11, 0x11, 0x13, 0x0D], // u
        [0x00, 0x00, 0x11, 0x11, 0x11, 0x0A, 0x04], // v
        [0x00, 0x00, 0x11, 0x11, 0x15, 0x15, 0x0A], // w
        [0x00, 0x00, 0x11, 0x0A, 0x04, 0x0A, 0x11], // x
        [0x00, 0x00, 0x11, 0x11, 0x0F, 0x01, 0x0E], // y
        [0x00, 0x00, 0x1F, 0x02, 0x04, 0x08, 0x1F], // z
        [0x02, 0x04, 0x04, 0x08, 0x04, 0x04, 0x02], // {
        [0x04, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04], // |
        [0x08, 0x04, 0x04, 0x02, 0x04, 0x04, 0x08], // }
        [0x00, 0x00, 0x00, 0x0D, 0x12, 0x00, 0x00], // ~
    ];
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::PixelRect;

    fn frame(width: u32, height: u32, rgb: [u8; 3]) -> RgbImage {
        RgbImage::from_pixel(width, height, image::Rgb(rgb))
    }

    /// A one-pixel layer at (x, y) of a `w × h` frame.
    fn dot_layer(w: u32, h: u32, x: u32, y: u32, rgba: [u8; 4]) -> GarmentLayer {
        let rect = PixelRect {
            x,
            y,
            width: 1,
            height: 1,
        };
        GarmentLayer::from_premultiplied(w, h, rect, rgba.to_vec()).expect("fits")
    }

    #[test]
    fn conversions_round_trip() {
        let rgb = [1, 2, 3, 4, 5, 6];
        let mut rgba = [0; 8];
        rgb_to_rgba(&rgb, &mut rgba);
        assert_eq!(rgba, [1, 2, 3, 255, 4, 5, 6, 255]);
        let mut back = [0; 6];
        rgba_to_rgb(&rgba, &mut back);
        assert_eq!(back, rgb);
    }

    #[test]
    fn the_blend_is_source_over_rounded_for_every_alpha_and_background() {
        for alpha in 0..=255u32 {
            for background in 0..=255u32 {
                // A premultiplied channel at most its alpha: the largest, the smallest, between.
                for src in [0, alpha / 3, alpha] {
                    let layer = [src as u8, 0, 0, alpha as u8];
                    let mut rgb = [background as u8, background as u8, 0];
                    let mut rgba = [background as u8, background as u8, 0, 255];
                    blend_over(&mut rgb, 3, &layer);
                    blend_over(&mut rgba, 4, &layer);
                    let keep = background as f64 * (255 - alpha) as f64 / 255.0;
                    let expected = (src as f64 + keep).round() as u8;
                    assert_eq!(rgb[0], expected, "α {alpha}, src {src}, dst {background}");
                    assert_eq!(rgb[1], keep.round() as u8);
                    assert_eq!(rgba[..3], rgb);
                    assert_eq!(rgba[3], 255);
                }
            }
        }
    }

    #[test]
    fn bands_one_pass_and_the_canvas_give_the_same_pixels() {
        // A 7 × 64 layer with every alpha over a 9 × 70 frame: on two or more threads the
        // parallel compositor splits its rows into bands.
        let (w, h) = (9, 70);
        let rect = PixelRect {
            x: 1,
            y: 3,
            width: 7,
            height: 64,
        };
        let rgba: Vec<u8> = (0..7 * 64)
            .flat_map(|i| {
                let a = (i * 37 % 256) as u8;
                [a / 2, a, a / 3, a]
            })
            .collect();
        let layer = GarmentLayer::from_premultiplied(w, h, rect, rgba).expect("fits");
        let background =
            RgbImage::from_fn(w, h, |x, y| image::Rgb([(x * 20) as u8, (y * 3) as u8, 77]));
        let mut results = Vec::new();
        for parallel in [false, true] {
            let mut f = background.clone();
            let mut c = Compositor::new(parallel);
            c.composite(&mut f, &layer).expect("same size");
            results.push(f);
            let mut f = background.clone();
            let mut canvas = c.canvas(&background).expect("canvas");
            canvas.garment(&layer).expect("same size");
            canvas.finish(&mut f).expect("same size");
            results.push(f);
        }
        assert!(results.iter().all(|r| r == &results[0]));
        // Outside the layer's rectangle nothing changed; a pixel of alpha 255 is the layer's.
        assert_eq!(results[0].get_pixel(0, 10), background.get_pixel(0, 10));
        assert_eq!(results[0].get_pixel(4, 68), background.get_pixel(4, 68));
        let opaque = (0..7 * 64)
            .find(|i| i * 37 % 256 == 255)
            .expect("an opaque pixel");
        let (x, y) = (1 + opaque % 7, 3 + opaque / 7);
        assert_eq!(results[0].get_pixel(x, y).0, [127, 255, 85]);
    }

    #[test]
    fn a_half_transparent_pixel_blends_source_over() {
        // Premultiplied (64, 0, 0, 128) over opaque (0, 0, 200):
        // r = 64 + 0·(1 − 128/255) = 64, b = 200·(127/255) = 99.6.
        for parallel in [false, true] {
            let mut f = frame(4, 3, [0, 0, 200]);
            let layer = dot_layer(4, 3, 2, 1, [64, 0, 0, 128]);
            Compositor::new(parallel)
                .composite(&mut f, &layer)
                .expect("same size");
            let p = f.get_pixel(2, 1).0;
            assert_eq!(p[0], 64);
            assert_eq!(p[1], 0);
            assert!((99..=100).contains(&p[2]), "{p:?}");
            // Everything else untouched.
            assert_eq!(f.get_pixel(1, 1).0, [0, 0, 200]);
            assert_eq!(f.get_pixel(2, 0).0, [0, 0, 200]);
        }
    }

    #[test]
    fn composite_and_canvas_agree_and_sizes_are_checked() {
        let layer = dot_layer(5, 40, 3, 33, [10, 20, 30, 255]);
        let mut a = frame(5, 40, [90, 90, 90]);
        let mut c = Compositor::new(true);
        c.composite(&mut a, &layer).expect("same size");
        let mut b = frame(5, 40, [90, 90, 90]);
        let src = b.clone();
        let mut canvas = c.canvas(&src).expect("canvas");
        canvas.garment(&layer).expect("same size");
        canvas.finish(&mut b).expect("same size");
        assert_eq!(a, b);
        assert_eq!(a.get_pixel(3, 33).0, [10, 20, 30]);
        let mut small = frame(4, 40, [0, 0, 0]);
        let err = c.composite(&mut small, &layer).unwrap_err();
        assert!(err.to_string().contains("5×40"), "{err}");
    }

    #[test]
    fn the_font_draws_a_known_glyph_in_the_right_cells() {
        // 'L' at scale 1, backdrop off, text origin (0, 0): glyph cells start at the padding (2, 2).
        let f = frame(12, 12, [0, 0, 0]);
        let mut c = Compositor::new(false);
        let mut canvas = c.canvas(&f).expect("canvas");
        let style = TextStyle {
            colour: [255, 255, 255],
            scale: 1,
            backdrop: [0, 0, 0, 0],
        };
        canvas.text(0.0, 0.0, &["L"], &style);
        let mut out = f.clone();
        canvas.finish(&mut out).expect("size");
        for y in 0..12 {
            for x in 0..12 {
                let inside = (2..7).contains(&x) && (2..9).contains(&y);
                let lit = inside && (x == 2 || y == 8);
                let p = out.get_pixel(x, y).0;
                assert_eq!(p, if lit { [255; 3] } else { [0; 3] }, "({x}, {y})");
            }
        }
    }

    #[test]
    fn text_gets_a_dark_backdrop_scaled_with_the_font() {
        let f = frame(40, 30, [200, 200, 200]);
        let mut c = Compositor::new(false);
        let mut canvas = c.canvas(&f).expect("canvas");
        let style = TextStyle {
            colour: [255, 0, 0],
            scale: 2,
            backdrop: [0, 0, 0, 255],
        };
        canvas.text(1.0, 1.0, &["REC", "é"], &style);
        let mut out = f.clone();
        canvas.finish(&mut out).expect("size");
        // Backdrop: 3 columns · 6 · 2 − 2 + 2·4 = 42 → clipped at 40; 2 rows · 8 · 2 − 2 + 8 = 38 → 30.
        assert_eq!(out.get_pixel(1, 1).0, [0, 0, 0]);
        assert_eq!(out.get_pixel(0, 0).0, [200, 200, 200]);
        // 'R' top-left cell at (1 + 4, 1 + 4), 2×2 pixels.
        assert_eq!(out.get_pixel(5, 5).0, [255, 0, 0]);
        assert_eq!(out.get_pixel(6, 6).0, [255, 0, 0]);
        // Unknown characters draw as '?'; the degree sign is a small ring at the top.
        assert_eq!(font::glyph('é'), font::glyph('?'));
        assert_eq!(font::glyph('°'), [0x0C, 0x12, 0x12, 0x0C, 0, 0, 0]);
    }

    #[test]
    fn overlays_draw_where_expected() {
        let f = frame(32, 32, [0, 0, 0]);
        let mut c = Compositor::new(false);
        let mut canvas = c.canvas(&f).expect("canvas");
        let person =
            Mask::from_pixels(32, 32, (0..32 * 32).map(|i| i % 32 < 8).collect()).expect("size");
        canvas.mask(&person, [0, 255, 0, 128]).expect("size");
        canvas.markers(
            &[MarkerDot {
                centre: Vec2::new(20.0, 20.0),
                colour: [255, 0, 0],
            }],
            3.0,
        );
        canvas.skeleton(
            &[(Vec2::new(10.5, 28.5), Vec2::new(30.5, 28.5))],
            [0, 0, 255],
            2.0,
        );
        let mut out = f.clone();
        canvas.finish(&mut out).expect("size");
        assert_eq!(out.get_pixel(2, 2).0, [0, 128, 0]);
        assert_eq!(out.get_pixel(12, 2).0, [0, 0, 0]);
        assert_eq!(out.get_pixel(20, 20).0, [255, 0, 0]);
        assert_eq!(out.get_pixel(20, 28).0, [0, 0, 255]);
        let wrong = Mask::empty(8, 8);
        let mut canvas = c.canvas(&f).expect("canvas");
        assert!(canvas.mask(&wrong, [0, 0, 0, 255]).is_err());
    }
}
