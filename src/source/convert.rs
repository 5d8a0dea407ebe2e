//! Pixel-format conversion: camera and file encodings (YUYV 4:2:2, MJPEG,
//! planar YUV 4:2:0 / 4:4:4 / mono) to packed 8-bit RGB, plus the reverse
//! RGB → planar YUV used by the Y4M writer.
//!
//! Everything here is a pure function over byte slices. The frame sources call
//! these and hand the resulting [`RgbImage`] to the next stage (the segmenter),
//! which therefore only ever sees 8-bit sRGB-ish RGB, whatever the camera sent.
//!
//! YUV is BT.601. Camera YUYV and Y4M data are limited range (Y 16..235,
//! chroma 16..240) unless told otherwise ([`YuvRange::Full`]).

use image::{ImageFormat, RgbImage};

/// Why a buffer could not be converted to RGB.
#[derive(thiserror::Error, Debug, Clone, PartialEq, Eq)]
pub enum ConvertError {
    /// The buffer is shorter than the frame needs.
    #[error("buffer too short for {width}x{height}: {expected} bytes needed, {got} given")]
    ShortBuffer {
        width: u32,
        height: u32,
        expected: usize,
        got: usize,
    },
    /// A YUYV buffer of odd length, or an odd width (half a macropixel).
    #[error("YUYV data must hold whole macropixels: width {width}, buffer length {len}")]
    PartialMacropixel { width: u32, len: usize },
    /// The row stride is smaller than a row.
    #[error("row stride {stride} is smaller than a row of {row_bytes} bytes")]
    BadStride { stride: usize, row_bytes: usize },
    /// Zero width or height, or a size whose byte count overflows.
    #[error("invalid image size {width}x{height}")]
    BadSize { width: u32, height: u32 },
    /// The JPEG decoder rejected the data.
    #[error("JPEG decode failed: {reason}")]
    Jpeg { reason: String },
    /// The JPEG data stops before its end-of-image marker: the file or the camera's buffer was cut
    /// short. The decoder would fill the missing rows with grey and report nothing.
    #[error("JPEG data is truncated: {len} bytes without the end-of-image marker")]
    TruncatedJpeg { len: usize },
    /// An image file (PNG, JPEG, GIF) that does not decode.
    #[error("{reason}")]
    Image { reason: String },
}

/// Quantisation range of YUV samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum YuvRange {
    /// "TV" range: Y in 16..=235, Cb/Cr in 16..=240 (the usual case).
    #[default]
    Limited,
    /// "PC"/JPEG range: all of 0..=255.
    Full,
}

/// Fixed-point (×256) BT.601 YUV → RGB coefficients for one range.
#[derive(Debug, Clone, Copy)]
struct YuvCoefficients {
    y_offset: i32,
    y_mul: i32,
    r_from_v: i32,
    g_from_u: i32,
    g_from_v: i32,
    b_from_u: i32,
}

impl YuvRange {
    fn coefficients(self) -> YuvCoefficients {
        match self {
            // 255/219 * 256 = 298; 1.596 * 256 = 409; 0.392 → 100; 0.813 → 208; 2.017 → 516
            YuvRange::Limited => YuvCoefficients {
                y_offset: 16,
                y_mul: 298,
                r_from_v: 409,
                g_from_u: 100,
                g_from_v: 208,
                b_from_u: 516,
            },
            // 1.402 → 359; 0.344 → 88; 0.714 → 183; 1.772 → 454
            YuvRange::Full => YuvCoefficients {
                y_offset: 0,
                y_mul: 256,
                r_from_v: 359,
                g_from_u: 88,
                g_from_v: 183,
                b_from_u: 454,
            },
        }
    }
}

fn clamp_u8(v: i32) -> u8 {
    v.clamp(0, 255) as u8
}

/// One BT.601 YUV sample triple to RGB.
#[inline]
fn yuv_to_rgb_pixel(y: u8, u: u8, v: u8, k: YuvCoefficients) -> [u8; 3] {
    let c = k.y_mul * (i32::from(y) - k.y_offset);
    let d = i32::from(u) - 128;
    let e = i32::from(v) - 128;
    [
        clamp_u8((c + k.r_from_v * e + 128) >> 8),
        clamp_u8((c - k.g_from_u * d - k.g_from_v * e + 128) >> 8),
        clamp_u8((c + k.b_from_u * d + 128) >> 8),
    ]
}

/// One RGB pixel to limited-range BT.601 (Y, Cb, Cr).
#[inline]
pub fn rgb_to_yuv601(rgb: [u8; 3]) -> [u8; 3] {
    let [r, g, b] = rgb.map(i32::from);
    let y = ((66 * r + 129 * g + 25 * b + 128) >> 8) + 16;
    let u = ((-38 * r - 74 * g + 112 * b + 128) >> 8) + 128;
    let v = ((112 * r - 94 * g - 18 * b + 128) >> 8) + 128;
    [clamp_u8(y), clamp_u8(u), clamp_u8(v)]
}

/// Number of pixels, or `BadSize` for zero or overflowing sizes.
fn pixel_count(width: u32, height: u32) -> Result<usize, ConvertError> {
    let bad = ConvertError::BadSize { width, height };
    if width == 0 || height == 0 {
        return Err(bad);
    }
    (width as usize).checked_mul(height as usize).ok_or(bad)
}

/// Size of a chroma plane for 4:2:0 subsampling: ceil(w/2) x ceil(h/2).
pub fn chroma_420_size(width: u32, height: u32) -> (u32, u32) {
    (width.div_ceil(2), height.div_ceil(2))
}

fn check_len(width: u32, height: u32, expected: usize, got: usize) -> Result<(), ConvertError> {
    if got < expected {
        Err(ConvertError::ShortBuffer {
            width,
            height,
            expected,
            got,
        })
    } else {
        Ok(())
    }
}

/// Packed YUYV 4:2:2 (`Y0 U Y1 V` per two pixels, rows packed without padding),
/// limited-range BT.601, to RGB.
///
/// Errors on an odd width, an odd buffer length or a buffer shorter than
/// `width * height * 2`. Bytes past the frame are ignored.
pub fn yuyv_to_rgb(data: &[u8], width: u32, height: u32) -> Result<RgbImage, ConvertError> {
    let stride = (width as usize).saturating_mul(2);
    yuyv_to_rgb_strided(data, width, height, stride)
}

/// As [`yuyv_to_rgb`] but rows start every `stride` bytes (V4L2 `bytesperline`).
pub fn yuyv_to_rgb_strided(
    data: &[u8],
    width: u32,
    height: u32,
    stride: usize,
) -> Result<RgbImage, ConvertError> {
    pixel_count(width, height)?;
    if !width.is_multiple_of(2) || !data.len().is_multiple_of(2) {
        return Err(ConvertError::PartialMacropixel {
            width,
            len: data.len(),
        });
    }
    let row_bytes = width as usize * 2;
    if stride < row_bytes {
        return Err(ConvertError::BadStride { stride, row_bytes });
    }
    let expected = stride
        .checked_mul(height as usize - 1)
        .and_then(|n| n.checked_add(row_bytes))
        .ok_or(ConvertError::BadSize { width, height })?;
    check_len(width, height, expected, data.len())?;

    let k = YuvRange::Limited.coefficients();
    let mut out = RgbImage::new(width, height);
    for (y, out_row) in out.chunks_exact_mut(width as usize * 3).enumerate() {
        let row = &data[y * stride..y * stride + row_bytes];
        for (mp, px) in row.chunks_exact(4).zip(out_row.chunks_exact_mut(6)) {
            let (y0, u, y1, v) = (mp[0], mp[1], mp[2], mp[3]);
            px[0..3].copy_from_slice(&yuv_to_rgb_pixel(y0, u, v, k));
            px[3..6].copy_from_slice(&yuv_to_rgb_pixel(y1, u, v, k));
        }
    }
    Ok(out)
}

/// Planar YUV 4:2:0 to RGB. Chroma planes are `ceil(w/2) x ceil(h/2)`;
/// upsampling is nearest-neighbour (each chroma sample covers a 2x2 block).
pub fn yuv420p_to_rgb(
    y_plane: &[u8],
    u_plane: &[u8],
    v_plane: &[u8],
    width: u32,
    height: u32,
    range: YuvRange,
) -> Result<RgbImage, ConvertError> {
    let n = pixel_count(width, height)?;
    let (cw, ch) = chroma_420_size(width, height);
    let cn = cw as usize * ch as usize;
    check_len(width, height, n, y_plane.len())?;
    check_len(cw, ch, cn, u_plane.len())?;
    check_len(cw, ch, cn, v_plane.len())?;

    let k = range.coefficients();
    let (w, cw) = (width as usize, cw as usize);
    let mut out = RgbImage::new(width, height);
    for (y, out_row) in out.chunks_exact_mut(w * 3).enumerate() {
        let luma = &y_plane[y * w..(y + 1) * w];
        let crow = (y / 2) * cw;
        let (us, vs) = (&u_plane[crow..crow + cw], &v_plane[crow..crow + cw]);
        for (x, px) in out_row.chunks_exact_mut(3).enumerate() {
            px.copy_from_slice(&yuv_to_rgb_pixel(luma[x], us[x / 2], vs[x / 2], k));
        }
    }
    Ok(out)
}

/// Planar YUV 4:4:4 (three full-size planes) to RGB.
pub fn yuv444p_to_rgb(
    y_plane: &[u8],
    u_plane: &[u8],
    v_plane: &[u8],
    width: u32,
    height: u32,
    range: YuvRange,
) -> Result<RgbImage, ConvertError> {
    let n = pixel_count(width, height)?;
    check_len(width, height, n, y_plane.len())?;
    check_len(width, height, n, u_plane.len())?;
    check_len(width, height, n, v_plane.len())?;
    let k = range.coefficients();
    let mut out = RgbImage::new(width, height);
    for (i, px) in out.chunks_exact_mut(3).enumerate() {
        px.copy_from_slice(&yuv_to_rgb_pixel(y_plane[i], u_plane[i], v_plane[i], k));
    }
    Ok(out)
}

/// A single luma plane (Y4M `Cmono`) to grey RGB.
pub fn mono_to_rgb(
    y_plane: &[u8],
    width: u32,
    height: u32,
    range: YuvRange,
) -> Result<RgbImage, ConvertError> {
    let n = pixel_count(width, height)?;
    check_len(width, height, n, y_plane.len())?;
    let k = range.coefficients();
    let mut out = RgbImage::new(width, height);
    for (px, &y) in out.chunks_exact_mut(3).zip(y_plane) {
        px.copy_from_slice(&yuv_to_rgb_pixel(y, 128, 128, k));
    }
    Ok(out)
}

/// Planar YUV planes (Y, U, V) in the order a Y4M frame stores them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct YuvPlanes {
    pub y: Vec<u8>,
    pub u: Vec<u8>,
    pub v: Vec<u8>,
}

/// RGB to limited-range BT.601 planar 4:4:4.
pub fn rgb_to_yuv444p(image: &RgbImage) -> YuvPlanes {
    let n = image.width() as usize * image.height() as usize;
    let mut planes = YuvPlanes {
        y: Vec::with_capacity(n),
        u: Vec::with_capacity(n),
        v: Vec::with_capacity(n),
    };
    for px in image.pixels() {
        let [y, u, v] = rgb_to_yuv601(px.0);
        planes.y.push(y);
        planes.u.push(u);
        planes.v.push(v);
    }
    planes
}

/// RGB to limited-range BT.601 planar 4:2:0; each chroma sample is the mean
/// over its (up to) 2x2 block, so odd sizes give `ceil(w/2) x ceil(h/2)` planes.
pub fn rgb_to_yuv420p(image: &RgbImage) -> YuvPlanes {
    let full = rgb_to_yuv444p(image);
    let (w, h) = (image.width() as usize, image.height() as usize);
    let (cw, ch) = (w.div_ceil(2), h.div_ceil(2));
    let mut u = Vec::with_capacity(cw * ch);
    let mut v = Vec::with_capacity(cw * ch);
    for cy in 0..ch {
        for cx in 0..cw {
            let (mut su, mut sv, mut count) = (0u32, 0u32, 0u32);
            for y in (2 * cy)..(2 * cy + 2).min(h) {
                for x in (2 * cx)..(2 * cx + 2).min(w) {
                    su += u32::from(full.u[y * w + x]);
                    sv += u32::from(full.v[y * w + x]);
                    count += 1;
                }
            }
            u.push(((su + count / 2) / count) as u8);
            v.push(((sv + count / 2) / count) as u8);
        }
    }
    YuvPlanes { y: full.y, u, v }
}

/// The standard Huffman tables of JPEG (ITU T.81 Annex K.3) as one DHT
/// segment, marker included: luminance DC, chrominance DC, luminance AC,
/// chrominance AC. MJPEG webcams commonly omit these from every frame.
#[rustfmt::skip]
pub const DEFAULT_DHT_SEGMENT: [u8; 420] = [
    0xFF, 0xC4, 0x01, 0xA2,
    // DC luminance: class 0, id 0
    0x00,
    0x00, 0x01, 0x05, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
    0x00, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08, 0x09, 0x0A, 0x0B,
    // DC chrominance: class 0, id 1
    0x01,
    0x00, 0x03, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00,
    0x00, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08, 0x09, 0x0A, 0x0B,
    // AC luminance: class 1, id 0
    0x10,
    0x00, 0x02, 0x01, 0x03, 0x03, 0x02, 0x04, 0x03, 0x05, 0x05, 0x04, 0x04, 0x00, 0x00, 0x01, 0x7D,
    0x01, 0x02, 0x03, 0x00, 0x04, 0x11, 0x05, 0x12, 0x21, 0x31, 0x41, 0x06, 0x13, 0x51, 0x61, 0x07,
    0x22, 0x71, 0x14, 0x32, 0x81, 0x91, 0xA1, 0x08, 0x23, 0x42, 0xB1, 0xC1, 0x15, 0x52, 0xD1, 0xF0,
    0x24, 0x33, 0x62, 0x72, 0x82, 0x09, 0x0A, 0x16, 0x17, 0x18, 0x19, 0x1A, 0x25, 0x26, 0x27, 0x28,
    0x29, 0x2A, 0x34, 0x35, 0x36, 0x37, 0x38, 0x39, 0x3A, 0x43, 0x44, 0x45, 0x46, 0x47, 0x48, 0x49,
    0x4A, 0x53, 0x54, 0x55, 0x56, 0x57, 0x58, 0x59, 0x5A, 0x63, 0x64, 0x65, 0x66, 0x67, 0x68, 0x69,
    0x6A, 0x73, 0x74, 0x75, 0x76, 0x77, 0x78, 0x79, 0x7A, 0x83, 0x84, 0x85, 0x86, 0x87, 0x88, 0x89,
    0x8A, 0x92, 0x93, 0x94, 0x95, 0x96, 0x97, 0x98, 0x99, 0x9A, 0xA2, 0xA3, 0xA4, 0xA5, 0xA6, 0xA7,
    0xA8, 0xA9, 0xAA, 0xB2, 0xB3, 0xB4, 0xB5, 0xB6, 0xB7, 0xB8, 0xB9, 0xBA, 0xC2, 0xC3, 0xC4, 0xC5,
    0xC6, 0xC7, 0xC8, 0xC9, 0xCA, 0xD2, 0xD3, 0xD4, 0xD5, 0xD6, 0xD7, 0xD8, 0xD9, 0xDA, 0xE1, 0xE2,
    0xE3, 0xE4, 0xE5, 0xE6, 0xE7, 0xE8, 0xE9, 0xEA, 0xF1, 0xF2, 0xF3, 0xF4, 0xF5, 0xF6, 0xF7, 0xF8,
    0xF9, 0xFA,
    // AC chrominance: class 1, id 1
    0x11,
    0x00, 0x02, 0x01, 0x02, 0x04, 0x04, 0x03, 0x04, 0x07, 0x05, 0x04, 0x04, 0x00, 0x01, 0x02, 0x77,
    0x00, 0x01, 0x02, 0x03, 0x11, 0x04, 0x05, 0x21, 0x31, 0x06, 0x12, 0x41, 0x51, 0x07, 0x61, 0x71,
    0x13, 0x22, 0x32, 0x81, 0x08, 0x14, 0x42, 0x91, 0xA1, 0xB1, 0xC1, 0x09, 0x23, 0x33, 0x52, 0xF0,
    0x15, 0x62, 0x72, 0xD1, 0x0A, 0x16, 0x24, 0x34, 0xE1, 0x25, 0xF1, 0x17, 0x18, 0x19, 0x1A, 0x26,
    0x27, 0x28, 0x29, 0x2A, 0x35, 0x36, 0x37, 0x38, 0x39, 0x3A, 0x43, 0x44, 0x45, 0x46, 0x47, 0x48,
    0x49, 0x4A, 0x53, 0x54, 0x55, 0x56, 0x57, 0x58, 0x59, 0x5A, 0x63, 0x64, 0x65, 0x66, 0x67, 0x68,
    0x69, 0x6A, 0x73, 0x74, 0x75, 0x76, 0x77, 0x78, 0x79, 0x7A, 0x82, 0x83, 0x84, 0x85, 0x86, 0x87,
    0x88, 0x89, 0x8A, 0x92, 0x93, 0x94, 0x95, 0x96, 0x97, 0x98, 0x99, 0x9A, 0xA2, 0xA3, 0xA4, 0xA5,
    0xA6, 0xA7, 0xA8, 0xA9, 0xAA, 0xB2, 0xB3, 0xB4, 0xB5, 0xB6, 0xB7, 0xB8, 0xB9, 0xBA, 0xC2, 0xC3,
    0xC4, 0xC5, 0xC6, 0xC7, 0xC8, 0xC9, 0xCA, 0xD2, 0xD3, 0xD4, 0xD5, 0xD6, 0xD7, 0xD8, 0xD9, 0xDA,
    0xE2, 0xE3, 0xE4, 0xE5, 0xE6, 0xE7, 0xE8, 0xE9, 0xEA, 0xF2, 0xF3, 0xF4, 0xF5, 0xF6, 0xF7, 0xF8,
    0xF9, 0xFA,
];

/// What a scan of the JPEG header segments found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct JpegHeaderScan {
    /// A DHT (0xFFC4) segment occurs before the first scan.
    pub has_dht: bool,
    /// Byte offset of the first SOS (0xFFDA) marker, if the headers reach one.
    pub sos_offset: Option<usize>,
}

/// Walks the marker segments of a JPEG up to its first SOS, without decoding.
/// Stops quietly at anything malformed (the decoder will report it).
pub fn scan_jpeg_headers(data: &[u8]) -> JpegHeaderScan {
    let mut scan = JpegHeaderScan {
        has_dht: false,
        sos_offset: None,
    };
    if data.len() < 4 || data[0] != 0xFF || data[1] != 0xD8 {
        return scan;
    }
    let mut pos = 2;
    while pos + 1 < data.len() {
        if data[pos] != 0xFF {
            return scan;
        }
        let marker = data[pos + 1];
        match marker {
            0xFF => pos += 1, // fill byte
            0xDA => {
                scan.sos_offset = Some(pos);
                return scan;
            }
            0xD9 => return scan,
            0x01 | 0xD0..=0xD7 => pos += 2,
            _ => {
                if marker == 0xC4 {
                    scan.has_dht = true;
                }
                let Some(len) = data.get(pos + 2..pos + 4) else {
                    return scan;
                };
                let len = usize::from(u16::from_be_bytes([len[0], len[1]]));
                if len < 2 {
                    return scan;
                }
                pos += 2 + len;
            }
        }
    }
    scan
}

/// The JPEG with the Annex K default Huffman tables inserted before its first
/// scan if it has no DHT segment of its own; `None` when nothing needs adding.
pub fn with_default_dht(data: &[u8]) -> Option<Vec<u8>> {
    let scan = scan_jpeg_headers(data);
    match scan {
        JpegHeaderScan {
            has_dht: false,
            sos_offset: Some(sos),
        } => {
            let mut out = Vec::with_capacity(data.len() + DEFAULT_DHT_SEGMENT.len());
            out.extend_from_slice(&data[..sos]);
            out.extend_from_slice(&DEFAULT_DHT_SEGMENT);
            out.extend_from_slice(&data[sos..]);
            Some(out)
        }
        _ => None,
    }
}

/// Whether `data` starts like a JPEG stream (the start-of-image marker FF D8).
pub fn is_jpeg(data: &[u8]) -> bool {
    data.starts_with(&[0xFF, 0xD8])
}

/// Checks that JPEG data is whole: the end-of-image marker FF D9 follows its first scan. Inside
/// the compressed data an FF byte is always followed by 00 or a restart marker, so FF D9 there is
/// the end; what comes after it (a camera's zero padding, a phone's trailer) does not matter, and
/// an EXIF thumbnail's own FF D9 lies before the first scan. A JPEG cut short (a file copied in
/// part, a USB camera that lost the end of a frame) decodes without an error, the missing rows
/// grey: the segmenter would see a frame with nobody in it, and training a grey picture with a
/// pose. Data whose headers do not reach a scan is left to the decoder, which rejects it.
pub fn check_jpeg_whole(data: &[u8]) -> Result<(), ConvertError> {
    let Some(sos) = scan_jpeg_headers(data).sos_offset else {
        return Ok(());
    };
    if data[sos..].windows(2).rev().any(|w| w == [0xFF, 0xD9]) {
        Ok(())
    } else {
        Err(ConvertError::TruncatedJpeg { len: data.len() })
    }
}

/// An encoded frame (PNG, JPEG or GIF, told from its first bytes) to RGB. A JPEG is checked to be
/// whole first ([`check_jpeg_whole`]); a truncated PNG is an error of its decoder.
pub fn decode_frame(data: &[u8]) -> Result<RgbImage, ConvertError> {
    if is_jpeg(data) {
        check_jpeg_whole(data)?;
    }
    image::load_from_memory(data)
        .map(|img| img.into_rgb8())
        .map_err(|e| ConvertError::Image {
            reason: e.to_string(),
        })
}

/// One MJPEG frame (a JPEG image, possibly without Huffman tables) to RGB; a frame cut short is an
/// error ([`check_jpeg_whole`]).
pub fn mjpeg_to_rgb(data: &[u8]) -> Result<RgbImage, ConvertError> {
    check_jpeg_whole(data)?;
    let patched = with_default_dht(data);
    let bytes = patched.as_deref().unwrap_or(data);
    image::load_from_memory_with_format(bytes, ImageFormat::Jpeg)
        .map(|img| img.into_rgb8())
        .map_err(|e| ConvertError::Jpeg {
            reason: e.to_string(),
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::codecs::jpeg::JpegEncoder;
    use image::Rgb;

    fn px(img: &RgbImage, x: u32, y: u32) -> [u8; 3] {
        img.get_pixel(x, y).0
    }

    fn close(a: [u8; 3], b: [u8; 3], tol: i32) -> bool {
        a.iter()
            .zip(b.iter())
            .all(|(&p, &q)| (i32::from(p) - i32::from(q)).abs() <= tol)
    }

    #[test]
    fn yuyv_white_black_red() {
        let white = yuyv_to_rgb(&[235, 128, 235, 128], 2, 1).unwrap();
        assert_eq!(px(&white, 0, 0), [255, 255, 255]);
        assert_eq!(px(&white, 1, 0), [255, 255, 255]);
        let black = yuyv_to_rgb(&[16, 128, 16, 128], 2, 1).unwrap();
        assert_eq!(px(&black, 0, 0), [0, 0, 0]);
        assert_eq!(px(&black, 1, 0), [0, 0, 0]);
        // BT.601 limited-range red is (Y, Cb, Cr) = (81, 90, 240).
        let red = yuyv_to_rgb(&[81, 90, 81, 240], 2, 1).unwrap();
        assert_eq!(px(&red, 0, 0), [255, 0, 0]);
    }

    #[test]
    fn yuyv_two_pixels_share_chroma_but_not_luma() {
        // Y0 = black, Y1 = white, neutral chroma.
        let img = yuyv_to_rgb(&[16, 128, 235, 128], 2, 1).unwrap();
        assert_eq!(px(&img, 0, 0), [0, 0, 0]);
        assert_eq!(px(&img, 1, 0), [255, 255, 255]);
    }

    #[test]
    fn yuyv_rows_and_stride() {
        // 2x2, stride 6 (2 padding bytes per row); row 0 black, row 1 white.
        let data = [16, 128, 16, 128, 9, 9, 235, 128, 235, 128, 9, 9];
        let img = yuyv_to_rgb_strided(&data, 2, 2, 6).unwrap();
        assert_eq!(px(&img, 1, 0), [0, 0, 0]);
        assert_eq!(px(&img, 0, 1), [255, 255, 255]);
    }

    #[test]
    fn yuyv_rejects_bad_buffers() {
        assert!(matches!(
            yuyv_to_rgb(&[16, 128, 16, 128], 2, 2),
            Err(ConvertError::ShortBuffer {
                expected: 8,
                got: 4,
                ..
            })
        ));
        assert!(matches!(
            yuyv_to_rgb(&[16, 128, 16], 2, 1),
            Err(ConvertError::PartialMacropixel { .. })
        ));
        assert!(matches!(
            yuyv_to_rgb(&[16, 128, 16, 128, 16, 128], 3, 1),
            Err(ConvertError::PartialMacropixel { .. })
        ));
        assert!(matches!(
            yuyv_to_rgb(&[], 0, 0),
            Err(ConvertError::BadSize { .. })
        ));
    }

    #[test]
    fn planar_420_odd_size_uses_ceil_chroma() {
        // 3x3 image: chroma planes are 2x2. Top-left 2x2 block red chroma,
        // everything else neutral.
        let y = [81, 81, 235, 81, 81, 235, 235, 235, 235];
        let u = [90, 128, 128, 128];
        let v = [240, 128, 128, 128];
        let img = yuv420p_to_rgb(&y, &u, &v, 3, 3, YuvRange::Limited).unwrap();
        assert_eq!(px(&img, 0, 0), [255, 0, 0]);
        assert_eq!(px(&img, 1, 1), [255, 0, 0]);
        assert_eq!(px(&img, 2, 0), [255, 255, 255]);
        assert_eq!(px(&img, 2, 2), [255, 255, 255]);
        assert!(yuv420p_to_rgb(&y, &u[..3], &v, 3, 3, YuvRange::Limited).is_err());
    }

    #[test]
    fn planar_444_and_mono() {
        let img =
            yuv444p_to_rgb(&[81, 16], &[90, 128], &[240, 128], 2, 1, YuvRange::Limited).unwrap();
        assert_eq!(px(&img, 0, 0), [255, 0, 0]);
        assert_eq!(px(&img, 1, 0), [0, 0, 0]);
        let full = mono_to_rgb(&[0, 200], 2, 1, YuvRange::Full).unwrap();
        assert_eq!(px(&full, 1, 0), [200, 200, 200]);
        let limited = mono_to_rgb(&[16, 235], 2, 1, YuvRange::Limited).unwrap();
        assert_eq!(px(&limited, 0, 0), [0, 0, 0]);
        assert_eq!(px(&limited, 1, 0), [255, 255, 255]);
    }

    #[test]
    fn rgb_yuv_round_trip_is_close() {
        for rgb in [
            [0, 0, 0],
            [255, 255, 255],
            [255, 0, 0],
            [0, 255, 0],
            [0, 0, 255],
            [12, 200, 77],
            [128, 128, 128],
        ] {
            let [y, u, v] = rgb_to_yuv601(rgb);
            let back = yuv_to_rgb_pixel(y, u, v, YuvRange::Limited.coefficients());
            assert!(close(rgb, back, 3), "{rgb:?} -> {back:?}");
        }
        assert_eq!(rgb_to_yuv601([255, 255, 255]), [235, 128, 128]);
        assert_eq!(rgb_to_yuv601([0, 0, 0]), [16, 128, 128]);
    }

    #[test]
    fn rgb_to_420_averages_blocks() {
        let mut img = RgbImage::from_pixel(3, 1, Rgb([0, 0, 0]));
        img.put_pixel(2, 0, Rgb([255, 255, 255]));
        let planes = rgb_to_yuv420p(&img);
        assert_eq!(planes.y, vec![16, 16, 235]);
        assert_eq!(planes.u.len(), 2);
        assert_eq!(planes.v.len(), 2);
    }

    /// A 16x16 image of four flat colour quadrants, JPEG-encoded.
    fn quadrant_jpeg() -> (RgbImage, Vec<u8>) {
        let colours = [[220, 30, 30], [30, 200, 40], [30, 40, 210], [240, 240, 240]];
        let img = RgbImage::from_fn(16, 16, |x, y| {
            Rgb(colours[(usize::from(y >= 8) << 1) | usize::from(x >= 8)])
        });
        let mut bytes = Vec::new();
        JpegEncoder::new_with_quality(&mut bytes, 95)
            .encode_image(&img)
            .unwrap();
        (img, bytes)
    }

    /// Removes every DHT segment before the first scan.
    fn strip_dht(jpeg: &[u8]) -> Vec<u8> {
        let mut out = jpeg[..2].to_vec();
        let mut pos = 2;
        loop {
            assert_eq!(jpeg[pos], 0xFF);
            let marker = jpeg[pos + 1];
            if marker == 0xDA {
                out.extend_from_slice(&jpeg[pos..]);
                return out;
            }
            let len = usize::from(u16::from_be_bytes([jpeg[pos + 2], jpeg[pos + 3]]));
            if marker != 0xC4 {
                out.extend_from_slice(&jpeg[pos..pos + 2 + len]);
            }
            pos += 2 + len;
        }
    }

    #[test]
    fn mjpeg_decodes_close_to_original() {
        let (img, bytes) = quadrant_jpeg();
        assert!(scan_jpeg_headers(&bytes).has_dht);
        let decoded = mjpeg_to_rgb(&bytes).unwrap();
        assert_eq!(decoded.dimensions(), (16, 16));
        for (x, y) in [(2, 2), (13, 2), (2, 13), (13, 13)] {
            assert!(
                close(px(&decoded, x, y), px(&img, x, y), 12),
                "({x},{y}): {:?} vs {:?}",
                px(&decoded, x, y),
                px(&img, x, y)
            );
        }
    }

    #[test]
    fn mjpeg_without_dht_gets_default_tables() {
        let (_, bytes) = quadrant_jpeg();
        let stripped = strip_dht(&bytes);
        let scan = scan_jpeg_headers(&stripped);
        assert!(!scan.has_dht);
        assert!(scan.sos_offset.is_some());
        // The encoder uses the Annex K tables, so re-inserting them must give
        // back exactly the same pixels.
        let patched = with_default_dht(&stripped).unwrap();
        assert!(scan_jpeg_headers(&patched).has_dht);
        let reference = mjpeg_to_rgb(&bytes).unwrap();
        let decoded = mjpeg_to_rgb(&stripped).unwrap();
        assert_eq!(decoded, reference);
        assert!(with_default_dht(&bytes).is_none());
    }

    #[test]
    fn default_dht_segment_is_well_formed() {
        let len = usize::from(u16::from_be_bytes([
            DEFAULT_DHT_SEGMENT[2],
            DEFAULT_DHT_SEGMENT[3],
        ]));
        assert_eq!(len + 2, DEFAULT_DHT_SEGMENT.len());
        // Walk the four tables: class/id byte, 16 counts, then that many symbols.
        let mut pos = 4;
        let mut tables = 0;
        while pos < DEFAULT_DHT_SEGMENT.len() {
            let counts = &DEFAULT_DHT_SEGMENT[pos + 1..pos + 17];
            let n: usize = counts.iter().map(|&c| usize::from(c)).sum();
            pos += 17 + n;
            tables += 1;
        }
        assert_eq!(pos, DEFAULT_DHT_SEGMENT.len());
        assert_eq!(tables, 4);
    }

    proptest::proptest! {
        #[test]
        fn arbitrary_buffers_never_panic(
            data in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..200),
            w in 0u32..12, h in 0u32..12, stride in 0usize..40,
        ) {
            let _ = yuyv_to_rgb(&data, w, h);
            let _ = yuyv_to_rgb_strided(&data, w, h, stride);
            let third = data.len() / 3;
            let (y, rest) = data.split_at(third);
            let (u, v) = rest.split_at(third);
            let _ = yuv420p_to_rgb(y, u, v, w, h, YuvRange::Limited);
            let _ = yuv444p_to_rgb(y, u, v, w, h, YuvRange::Full);
            let _ = mono_to_rgb(&data, w, h, YuvRange::Full);
            let mut jpeg = vec![0xFF, 0xD8];
            jpeg.extend_from_slice(&data);
            let _ = scan_jpeg_headers(&jpeg);
            let _ = mjpeg_to_rgb(&jpeg);
        }
    }

    #[test]
    fn mjpeg_garbage_is_an_error() {
        assert!(matches!(mjpeg_to_rgb(&[]), Err(ConvertError::Jpeg { .. })));
        assert!(matches!(
            mjpeg_to_rgb(&[0xFF, 0xD8, 0xFF, 0xDA, 0, 2, 1, 2, 3, 0xFF, 0xD9]),
            Err(ConvertError::Jpeg { .. })
        ));
    }

    #[test]
    fn a_truncated_jpeg_is_an_error_not_a_grey_frame() {
        let img = RgbImage::from_fn(64, 64, |x, y| Rgb([(4 * x) as u8, (4 * y) as u8, 90]));
        let mut bytes = Vec::new();
        JpegEncoder::new_with_quality(&mut bytes, 95)
            .encode_image(&img)
            .expect("encodes");
        // The decoder alone takes the first two thirds and fills the rest (what the check is for).
        let two_thirds = 2 * bytes.len() / 3;
        assert!(image::load_from_memory(&bytes[..two_thirds]).is_ok());
        for cut in [two_thirds, bytes.len() - 1] {
            let short = &bytes[..cut];
            assert_eq!(
                mjpeg_to_rgb(short),
                Err(ConvertError::TruncatedJpeg { len: cut })
            );
            assert_eq!(
                decode_frame(short),
                Err(ConvertError::TruncatedJpeg { len: cut })
            );
        }
        // A camera's buffer padded with zeros after the end-of-image marker is whole, and so is
        // a file with a trailer after it.
        for tail in [&[0u8; 64][..], b"SEFT trailer"] {
            let mut longer = bytes.clone();
            longer.extend_from_slice(tail);
            assert_eq!(check_jpeg_whole(&longer), Ok(()));
            assert_eq!(mjpeg_to_rgb(&longer), mjpeg_to_rgb(&bytes));
        }
        assert_eq!(decode_frame(&bytes), mjpeg_to_rgb(&bytes));
        // An APP1 segment before the scan that holds an end-of-image marker of its own (as an
        // EXIF thumbnail does) does not make a cut scan whole.
        let mut with_app1 = vec![0xFF, 0xD8, 0xFF, 0xE1, 0x00, 0x06, 0xFF, 0xD9, 0x00, 0x00];
        with_app1.extend_from_slice(&bytes[2..]);
        assert_eq!(check_jpeg_whole(&with_app1), Ok(()));
        let cut = with_app1.len() - 40;
        assert_eq!(
            check_jpeg_whole(&with_app1[..cut]),
            Err(ConvertError::TruncatedJpeg { len: cut })
        );
    }

    #[test]
    fn decode_frame_reads_png_and_reports_a_truncated_one() {
        let mut img = RgbImage::new(3, 2);
        img.put_pixel(2, 1, image::Rgb([10, 200, 30]));
        let mut png = Vec::new();
        img.write_to(&mut std::io::Cursor::new(&mut png), ImageFormat::Png)
            .expect("encodes");
        assert_eq!(decode_frame(&png), Ok(img));
        assert!(matches!(
            decode_frame(&png[..png.len() / 2]),
            Err(ConvertError::Image { .. })
        ));
        assert!(matches!(
            decode_frame(b"not an image"),
            Err(ConvertError::Image { .. })
        ));
    }
}
