//! Edge snapping: the full-resolution mask's outline moved onto the frame's colour edge, then
//! decided pixel by pixel by how much of the person's colour each holds.
//!
//! The cut decides the person at half resolution and the refinement
//! ([`Segmenter`](super::Segmenter), step 5) decides the pixels of the boundary band at full
//! resolution from each one's own colour against the learned tables, which say how suit-like a
//! colour is, not where between the suit's colour and the room's a blurred edge pixel lies: about
//! half of the wrong pixels were within 3 px of the true edge, a third within one. Here every
//! *outline* pixel (one with a 4-neighbour of the other label) takes the label of the pixel
//! nearest to it in colour (squared RGB distance) among the pixels within `radius` (chessboard
//! distance) that are not on the outline: one-nearest-neighbour classification against the
//! colours on both sides of this stretch of the edge. A camera's blur mixes the two sides; a pixel
//! more than half person is nearer the person's colour beside it than the background's, so the
//! outline settles where the mix is half and half, which is where the covered pixels end. A tie
//! keeps the label, and so does a person pixel of a colour the caller keeps (the segmenter keeps
//! the suit's marker colours, since a marker on the outline is a sliver that the blur has already
//! thinned and that the marker detector needs) — unless at least `room_share` of the background
//! samples around it have the same kept colour: then the room beside the person is of this
//! marker's hue (dark red coffee beside a red marker, a purple cushion beside a purple one), the
//! colour says nothing about which side the pixel is on, and it is decided like any other; a room
//! of another marker's hue (sky blue under the cyan gate beside a purple marker) leaves it kept. A
//! marker on the outline blurs into a pixel or two of the room, a few of the samples; a room of its
//! hue fills most of them. Each pass decides all outline pixels from the same labels, then the next
//! pass looks at the new outline; a pass that changes nothing ends it.
//!
//! Chosen on the default suit's *training* datasets (punch 02_05, dance 05_04, jumping jacks 13_30,
//! drink 14_37; every eighth frame, the shipped tables, without the kept colours): the mean IoU
//! rose by 0.026–0.029 with radius 3 and two passes; radius 2 and 4 and a third pass gave within
//! 0.004 of that, and deciding a band two pixels wide (samples beyond it) only 0.012–0.015. The
//! figures on the test sequences are in `docs/measurements.md` (*Seventh session*). It costs about
//! 0.6 ms per 640×480 frame and 1.5 ms per 1440×1080 frame.
//!
//! The room test and four passes (tenth session of 2026-12-05): before it, every marker-coloured
//! outline pixel stayed person, and where the room has a marker's hue the mask kept a rim of it a
//! pixel or two wide along the suit (walk 10_04 over coffee: 2.1 % of the person's area in the ring
//! just outside the true outline, 0.2 % missed just inside). Chosen on the nine selection
//! renderings (`docs/measurements.md`), two passes: mean IoU 0.9487 with every marker colour kept,
//! 0.9583 with none kept, 0.9578 / 0.9575 / **0.9571** / 0.9566 with the room test at shares 0.15 /
//! 0.3 / 0.5 / 0.7, where the markers' recall over the nine was 0.9171 kept, 0.9126 none, 0.9140 /
//! 0.9144 / **0.9147** / 0.9150 (precision 0.9745, 0.9861, 0.9858 / 0.9855 / **0.9849** / 0.9836).
//! Then, at 0.5, passes 3 / **4** / 6 gave 0.9585 / **0.9589** / 0.9592 (recall 0.9143 / **0.9138**
//! / 0.9135, precision 0.9857 / **0.9863** / 0.9866) and radius 2 / 4 at two passes 0.9568 / 0.9571:
//! with the rim gone, the outline has more than two pixels to travel in places. The two more
//! passes cost about a quarter of a millisecond per frame at 640×480 and at 1440×1080. Since the
//! eleventh session only room samples of the pixel's own marker colour count (before, any marker
//! colour did): the selection's IoU the same, the markers' recall over the nine 0.9137 → 0.9140; a
//! drink over a sky-blue photograph 0.9624 → 0.9667.
//!
//! Then [`unmix_outline`] decides each outline pixel once more by linear unmixing: where the
//! pixel's colour lies between the colours sampled a pixel and a half inside and outside along the
//! outline's normal, it is person when it holds more than half of the inside's colour. The
//! nearest-colour test above compares the pixel with each side's nearest sample, and a blur of the
//! green cloth with a blue room reads as cyan, with a red one as red: a marker's colour, which it
//! keeps; the masks added up to 8 times as many pixels one pixel outside the true outline as they
//! missed one pixel inside (tenth session of 2026-12-06, docs/measurements.md).
//!
//! The snapped and unmixed [`Mask`] goes on to marker detection like the refined one.

use image::RgbImage;

use super::cleanup::PixelBox;
use crate::mask::Mask;

/// How [`snap_to_colour_edges`] snaps an outline.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Snapping {
    /// How far (pixels, chessboard) the colours of both sides are sampled.
    pub radius: u32,
    /// Passes; each moves the outline by a pixel at most (0: none).
    pub passes: u32,
    /// Person pixels of a kept colour stay person unless at least this share of the background
    /// samples around them have the same kept colour (above 1: they always stay).
    pub keep_room_share: f32,
}

/// Snaps `mask`'s outline to the colour edges of `frame` (see the module documentation) as
/// `snapping` says; person pixels of a colour the caller keeps (`kept_colour` gives its class, the
/// segmenter's a marker colour's index) stay person unless the room around them has the same kept
/// colour ([`Snapping::keep_room_share`]). Returns how many pixels changed label, or `None` (and
/// leaves the mask alone) when the frame and the mask differ in size.
pub fn snap_to_colour_edges(
    frame: &RgbImage,
    mask: &mut Mask,
    snapping: Snapping,
    kept_colour: impl Fn([u8; 3]) -> Option<usize>,
) -> Option<usize> {
    let Snapping {
        radius,
        passes,
        keep_room_share: room_share,
    } = snapping;
    let (w, h) = (mask.width() as usize, mask.height() as usize);
    if (frame.width() as usize, frame.height() as usize) != (w, h) {
        return None;
    }
    // Each pass moves the outline by a pixel at most, so every outline pixel and every sample
    // it reads lie within the person's box grown by `passes + radius`; the work is done on a
    // copy of that region's labels, written back at the end.
    let grow = (radius + passes) as usize;
    let Some(region) = PixelBox::around(mask.pixels(), w, h, grow) else {
        return Some(0);
    };
    let PixelBox {
        x0: rx0,
        y0: ry0,
        x1: rx1,
        y1: ry1,
    } = region;
    let (rw, rh) = (rx1 - rx0, ry1 - ry0);
    // The region's labels as 0 or 1; colours are read from the frame, four lanes per pixel (the
    // fourth zero) so that a distance is one vector subtraction, product and sum.
    let rgb = frame.as_raw();
    let colour = |x: usize, y: usize| {
        let i = 3 * ((ry0 + y) * w + rx0 + x);
        [rgb[i] as i32, rgb[i + 1] as i32, rgb[i + 2] as i32, 0]
    };
    let mut label = labels_in(mask, region);
    let r = radius as usize;
    let mut class = vec![OUTLINE; rw * rh];
    // After the first pass only the pixels within `radius + 1` of a change can decide
    // differently: a sample's class changes only next to a pixel that changed label.
    let mut near_change: Option<Vec<bool>> = None;
    let mut decided = Vec::new();
    let mut changed = 0;
    for _ in 0..passes {
        mark_classes(&label, rw, &mut class);
        decided.clear();
        for k in outline_pixels(&class) {
            if near_change.as_ref().is_some_and(|near| !near[k]) {
                continue;
            }
            let (x, y) = (k % rw, k / rw);
            let c = colour(x, y);
            // The nearest colour among the samples of each label in the window.
            let (mut person, mut background) = (u32::MAX, u32::MAX);
            let (from, to) = (x.saturating_sub(r), (x + r + 1).min(rw));
            for qy in y.saturating_sub(r)..(y + r + 1).min(rh) {
                for (qx, &kind) in (from..to).zip(&class[qy * rw + from..qy * rw + to]) {
                    let d = colour_distance(c, colour(qx, qy));
                    person = person.min(if kind == PERSON { d } else { u32::MAX });
                    background = background.min(if kind == BACKGROUND { d } else { u32::MAX });
                }
            }
            let flips = if label[k] == 1 {
                background < person
                    && !kept_colour(rgb_of(c)).is_some_and(|own| {
                        // Counted only here: few outline pixels are of a kept colour and would
                        // flip.
                        let (mut samples, mut alike) = (0u32, 0u32);
                        for qy in y.saturating_sub(r)..(y + r + 1).min(rh) {
                            for qx in from..to {
                                if class[qy * rw + qx] == BACKGROUND {
                                    samples += 1;
                                    alike +=
                                        (kept_colour(rgb_of(colour(qx, qy))) == Some(own)) as u32;
                                }
                            }
                        }
                        (alike as f32) < room_share * samples as f32
                    })
            } else {
                person < background
            };
            if flips {
                decided.push(k);
            }
        }
        if decided.is_empty() {
            break;
        }
        changed += decided.len();
        let near = near_change.get_or_insert_with(|| vec![false; rw * rh]);
        near.fill(false);
        let reach = r + 1;
        for &k in &decided {
            label[k] ^= 1;
            let (x, y) = (k % rw, k / rw);
            for qy in y.saturating_sub(reach)..(y + reach + 1).min(rh) {
                let row = qy * rw;
                near[row + x.saturating_sub(reach)..row + (x + reach + 1).min(rw)].fill(true);
            }
        }
    }
    let pixels = mask.pixels_mut();
    for (y, row) in (ry0..ry1).zip(label.chunks_exact(rw)) {
        for (p, &l) in pixels[y * w + rx0..y * w + rx1].iter_mut().zip(row) {
            *p = l == 1;
        }
    }
    Some(changed)
}

/// A pixel with a 4-neighbour of the other label: decided, not a sample.
const OUTLINE: u8 = 0;
/// A background pixel off the outline: a background sample.
const BACKGROUND: u8 = 1;
/// A person pixel off the outline: a person sample.
const PERSON: u8 = 2;

/// How [`unmix_outline`] decides the outline's pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Unmixing {
    /// How far inside and outside along the outline's normal the two sides are sampled, pixels.
    pub distance: f32,
    /// The least RGB distance between the two samples (0–255 a channel) for a pixel to be decided.
    pub min_contrast: f32,
    /// The largest distance of the pixel's colour from the line between the two samples, as a
    /// share of their distance, for a pixel to be decided.
    pub max_residual: f32,
}

/// Decides each outline pixel of `mask` (one with a 4-neighbour of the other label) by linear
/// unmixing: its colour `c` taken as `α·f + (1 − α)·b` between the colours `f` and `b` sampled
/// (bilinearly) [`Unmixing::distance`] pixels inside and outside along the outline's normal,
/// person where `α ≥ ½`. The camera's blur mixes the two sides, and a pixel covered more than
/// half by the person is more than half the person's colour, whatever the two colours are; the
/// nearest-colour snapping above only compares the pixel with each side's nearest sample, which
/// a mix of the cloth's green and a blue room (cyan) or the room's red (a red marker) can be
/// nearer to. A pixel whose two sides differ by less than [`Unmixing::min_contrast`], or whose
/// colour lies off the line between them by more than [`Unmixing::max_residual`] of their
/// distance (a marker on the outline, a third colour), keeps its label. All pixels are decided
/// from the labels before the pass. Returns how many changed, or `None` (and leaves the mask
/// alone) when the frame and the mask differ in size.
pub fn unmix_outline(frame: &RgbImage, mask: &mut Mask, unmixing: Unmixing) -> Option<usize> {
    let (w, h) = (mask.width() as usize, mask.height() as usize);
    if (frame.width() as usize, frame.height() as usize) != (w, h) {
        return None;
    }
    // The person's box grown by a pixel holds every outline pixel; outside it is background.
    let Some(b) = PixelBox::around(mask.pixels(), w, h, 1) else {
        return Some(0);
    };
    let (bw, bh) = (b.width(), b.height());
    let label = labels_in(mask, b);
    let mut class = vec![OUTLINE; label.len()];
    mark_classes(&label, bw, &mut class);
    let rgb = frame.as_raw();
    let at = |x: usize, y: usize| {
        let i = 3 * (y * w + x);
        [rgb[i] as f32, rgb[i + 1] as f32, rgb[i + 2] as f32]
    };
    // Bilinear colour at (fx, fy) in frame pixels, clamped to the frame.
    let sample = |fx: f32, fy: f32| {
        let (fx, fy) = (fx.clamp(0.0, (w - 1) as f32), fy.clamp(0.0, (h - 1) as f32));
        let (x0, y0) = (fx as usize, fy as usize);
        let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
        let (tx, ty) = (fx - x0 as f32, fy - y0 as f32);
        let (a, b, c, d) = (at(x0, y0), at(x1, y0), at(x0, y1), at(x1, y1));
        std::array::from_fn::<f32, 3, _>(|k| {
            (a[k] * (1.0 - tx) + b[k] * tx) * (1.0 - ty) + (c[k] * (1.0 - tx) + d[k] * tx) * ty
        })
    };
    let min_contrast2 = unmixing.min_contrast * unmixing.min_contrast;
    let max_residual2 = unmixing.max_residual * unmixing.max_residual;
    let mut flips = Vec::new();
    for k in outline_pixels(&class) {
        let (bx, by) = (k % bw, k / bw);
        let (x, y) = (b.x0 + bx, b.y0 + by);
        // The normal into the person: the summed offsets of the person's pixels in the 5×5
        // window minus those of the background's (beyond the frame's edge, the edge's labels:
        // a window cut by the edge would tilt the normal).
        let person_at = |dx: isize, dy: isize| {
            let gx = (x as isize + dx).clamp(0, w as isize - 1) as usize;
            let gy = (y as isize + dy).clamp(0, h as isize - 1) as usize;
            b.contains(gx, gy) && label[(gy - b.y0) * bw + gx - b.x0] == 1
        };
        let (mut nx, mut ny) = (0i32, 0i32);
        let inner = bx >= 2 && by >= 2 && bx + 2 < bw && by + 2 < bh;
        for dy in -2..=2isize {
            for dx in -2..=2isize {
                let person = if inner {
                    // The window within the box: no clamping needed.
                    let (qx, qy) = ((bx as isize + dx) as usize, (by as isize + dy) as usize);
                    label[qy * bw + qx] == 1
                } else {
                    person_at(dx, dy)
                };
                let side = if person { 1 } else { -1 };
                nx += side * dx as i32;
                ny += side * dy as i32;
            }
        }
        let (nx, ny) = (nx as f32, ny as f32);
        let norm = (nx * nx + ny * ny).sqrt();
        if norm < 1e-3 {
            continue;
        }
        let step = unmixing.distance / norm;
        let inside = sample(x as f32 + step * nx, y as f32 + step * ny);
        let outside = sample(x as f32 - step * nx, y as f32 - step * ny);
        let c = at(x, y);
        let across: [f32; 3] = std::array::from_fn(|k| inside[k] - outside[k]);
        let contrast2: f32 = across.iter().map(|v| v * v).sum();
        if contrast2 < min_contrast2 || contrast2 == 0.0 {
            continue;
        }
        let from_outside: [f32; 3] = std::array::from_fn(|k| c[k] - outside[k]);
        let alpha = (0..3).map(|k| from_outside[k] * across[k]).sum::<f32>() / contrast2;
        let residual2: f32 = (0..3)
            .map(|k| (from_outside[k] - alpha * across[k]).powi(2))
            .sum();
        if residual2 <= max_residual2 * contrast2 && (alpha >= 0.5) != (label[k] == 1) {
            flips.push(y * w + x);
        }
    }
    let pixels = mask.pixels_mut();
    for &i in &flips {
        pixels[i] = !pixels[i];
    }
    Some(flips.len())
}

/// The labels of `mask` within the box `b` as 0 or 1, row-major.
fn labels_in(mask: &Mask, b: PixelBox) -> Vec<u8> {
    let w = mask.width() as usize;
    let mut label = Vec::with_capacity(b.width() * b.height());
    for y in b.y0..b.y1 {
        label.extend(
            mask.pixels()[y * w + b.x0..y * w + b.x1]
                .iter()
                .map(|&p| p as u8),
        );
    }
    label
}

/// The class of every pixel of a region of labels (0 or 1) `rw` wide. The pixels around the
/// region are not looked at (the caller's region has background all round it, or ends at the
/// image's edge). Written as whole-row operations without branches, so that it runs in vector
/// lanes: the region is the person's whole box.
fn mark_classes(label: &[u8], rw: usize, class: &mut [u8]) {
    let rows: Vec<&[u8]> = label.chunks_exact(rw).collect();
    for (y, (row, out)) in rows.iter().zip(class.chunks_exact_mut(rw)).enumerate() {
        let up = if y > 0 { rows[y - 1] } else { row };
        let down = rows.get(y + 1).copied().unwrap_or(row);
        // Vertical differences, then the horizontal ones with the left and right neighbours.
        for (((o, &l), &u), &d) in out
            .iter_mut()
            .zip(row.iter())
            .zip(up.iter())
            .zip(down.iter())
        {
            *o = (l ^ u) | (l ^ d);
        }
        for ((o, &l), &right) in out.iter_mut().zip(row.iter()).zip(&row[1..]) {
            *o |= l ^ right;
        }
        for ((o, &l), &left) in out[1..].iter_mut().zip(&row[1..]).zip(row.iter()) {
            *o |= l ^ left;
        }
        // OUTLINE (0) where a neighbour differs, else BACKGROUND (1) or PERSON (2).
        for (o, &l) in out.iter_mut().zip(row.iter()) {
            *o = (1 + l) * (1 - *o);
        }
    }
}

/// The indices of the OUTLINE pixels in `class`, skipping runs of 32 without one at a time (the
/// outline is a few thousandths of the person's box).
fn outline_pixels(class: &[u8]) -> impl Iterator<Item = usize> + '_ {
    const RUN: usize = 32;
    class
        .chunks(RUN)
        .enumerate()
        // The least class of the run, without an early exit, so that it runs in vector lanes.
        .filter(|(_, run)| run.iter().fold(u8::MAX, |least, &c| least.min(c)) == OUTLINE)
        .flat_map(|(n, run)| {
            run.iter()
                .enumerate()
                .filter(|&(_, &c)| c == OUTLINE)
                .map(move |(k, _)| n * RUN + k)
        })
}

/// The colour of a four-lane sample.
fn rgb_of(c: [i32; 4]) -> [u8; 3] {
    [c[0] as u8, c[1] as u8, c[2] as u8]
}

/// Squared RGB distance (the fourth lanes are zero).
fn colour_distance(a: [i32; 4], b: [i32; 4]) -> u32 {
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2], a[3] - b[3]];
    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] + d[3] * d[3]) as u32
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::Rgb;
    use proptest::prelude::*;

    const SUIT: [u8; 3] = [200, 200, 0];
    const ROOM_COLOUR: [u8; 3] = [0, 0, 200];
    const TWO_PASSES: Snapping = Snapping {
        radius: 3,
        passes: 2,
        keep_room_share: 0.5,
    };
    /// Kept colours stay whatever the room (the rule before the room test).
    const ALWAYS_KEPT: Snapping = Snapping {
        keep_room_share: 1.5,
        ..TWO_PASSES
    };

    /// An 8 × 3 frame: columns 0–3 the person, 4–7 the room, blurred across the edge so that
    /// column 3 is 0.7 person + 0.3 room and column 4 the other way round.
    fn blurred_edge() -> RgbImage {
        let mix = |a: f32| {
            Rgb([0, 1, 2].map(|k| (a * SUIT[k] as f32 + (1.0 - a) * ROOM_COLOUR[k] as f32) as u8))
        };
        RgbImage::from_fn(8, 3, |x, _| match x {
            0..=2 => Rgb(SUIT),
            3 => mix(0.7),
            4 => mix(0.3),
            _ => Rgb(ROOM_COLOUR),
        })
    }

    fn columns(upto: u32) -> Mask {
        let pixels = (0..3).flat_map(|_| (0..8).map(move |x| x < upto)).collect();
        Mask::from_pixels(8, 3, pixels).expect("8 × 3")
    }

    #[test]
    fn a_mask_one_pixel_too_wide_or_too_narrow_snaps_to_the_half_mix() {
        let frame = blurred_edge();
        // Too wide: column 4 (0.3 person) is nearer the room of column 6 than the 0.7 mix of
        // column 3; column 5 is the room itself.
        let mut wide = columns(5);
        assert_eq!(
            snap_to_colour_edges(&frame, &mut wide, TWO_PASSES, |_| None),
            Some(3)
        );
        assert_eq!(wide, columns(4));
        // Too narrow: column 3 (0.7 person) is nearer the person of column 1 than column 4's
        // 0.3 mix; column 2 is the person itself.
        let mut narrow = columns(3);
        assert_eq!(
            snap_to_colour_edges(&frame, &mut narrow, TWO_PASSES, |_| None),
            Some(3)
        );
        assert_eq!(narrow, columns(4));
        // Right already: nothing moves.
        let mut right = columns(4);
        assert_eq!(
            snap_to_colour_edges(&frame, &mut right, TWO_PASSES, |_| None),
            Some(0)
        );
        assert_eq!(right, columns(4));
    }

    const UNMIXING: Unmixing = Unmixing {
        distance: 1.5,
        min_contrast: 30.0,
        max_residual: 0.15,
    };

    #[test]
    fn unmixing_puts_the_outline_where_the_blur_is_half_person() {
        let frame = blurred_edge();
        // Too wide: column 4 (0.3 person) between the samples at x 2.5 (0.85) and 5.5 (the room)
        // is α = 0.3 / 0.85 ≈ 0.35: background. Column 5 (the room) stays.
        let mut wide = columns(5);
        assert_eq!(unmix_outline(&frame, &mut wide, UNMIXING), Some(3));
        assert_eq!(wide, columns(4));
        // Too narrow: column 3 (0.7) between the person at x 1.5 and 4.5 (0.15) is α ≈ 0.65:
        // person. Column 2 (the person) stays.
        let mut narrow = columns(3);
        assert_eq!(unmix_outline(&frame, &mut narrow, UNMIXING), Some(3));
        assert_eq!(narrow, columns(4));
        let mut right = columns(4);
        assert_eq!(unmix_outline(&frame, &mut right, UNMIXING), Some(0));
    }

    #[test]
    fn unmixing_leaves_a_third_colour_and_a_flat_frame_alone() {
        // A sharp edge after column 3 and a red pixel at (4, 1): its colour lies 0.47 of the
        // two sides' distance off the line between them, so it keeps its label; the room's
        // pixels of column 4 go.
        let mut frame = RgbImage::from_fn(8, 3, |x, _| Rgb(if x < 4 { SUIT } else { ROOM_COLOUR }));
        frame.put_pixel(4, 1, Rgb([200, 0, 0]));
        let mut mask = columns(5);
        assert_eq!(unmix_outline(&frame, &mut mask, UNMIXING), Some(2));
        let mut expected = columns(4);
        expected.pixels_mut()[8 + 4] = true;
        assert_eq!(mask, expected);
        // One colour everywhere: no contrast, nothing decided; no person; another size.
        let flat = RgbImage::from_pixel(8, 3, Rgb(SUIT));
        let mut mask = columns(5);
        assert_eq!(unmix_outline(&flat, &mut mask, UNMIXING), Some(0));
        assert_eq!(unmix_outline(&flat, &mut columns(0), UNMIXING), Some(0));
        let small = RgbImage::from_pixel(4, 3, Rgb(SUIT));
        assert_eq!(unmix_outline(&small, &mut columns(5), UNMIXING), None);
    }

    #[test]
    fn person_pixels_of_a_kept_colour_stay() {
        // As the too-wide mask above, but column 4's colour (the 0.3 mix) is one to keep.
        let frame = blurred_edge();
        let kept = *frame.get_pixel(4, 0);
        let mut wide = columns(5);
        let changed = snap_to_colour_edges(&frame, &mut wide, TWO_PASSES, |rgb| {
            (rgb == kept.0).then_some(0)
        });
        assert_eq!(changed, Some(0));
        assert_eq!(wide, columns(5));
    }

    #[test]
    fn a_kept_colour_beside_a_room_of_kept_colours_is_decided_like_any_other() {
        // As above, but the room (columns 5–7) has a kept colour too: column 4 goes back to it.
        let frame = blurred_edge();
        let kept = *frame.get_pixel(4, 0);
        let keep = |rgb: [u8; 3]| (rgb == kept.0 || rgb == ROOM_COLOUR).then_some(0);
        let mut wide = columns(5);
        assert_eq!(
            snap_to_colour_edges(&frame, &mut wide, TWO_PASSES, keep),
            Some(3)
        );
        assert_eq!(wide, columns(4));
        // A room of another kept colour (another marker's hue) leaves the pixel kept.
        let other = |rgb: [u8; 3]| match rgb {
            rgb if rgb == kept.0 => Some(0),
            ROOM_COLOUR => Some(1),
            _ => None,
        };
        let mut wide = columns(5);
        assert_eq!(
            snap_to_colour_edges(&frame, &mut wide, TWO_PASSES, other),
            Some(0)
        );
        assert_eq!(wide, columns(5));
        // Above 1 a kept colour always stays, whatever the room (the rule before the room test).
        let mut wide = columns(5);
        assert_eq!(
            snap_to_colour_edges(&frame, &mut wide, ALWAYS_KEPT, keep),
            Some(0)
        );
        assert_eq!(wide, columns(5));
    }

    #[test]
    fn without_a_colour_edge_or_a_person_nothing_changes() {
        let flat = RgbImage::from_pixel(8, 3, Rgb(SUIT));
        let mut mask = columns(5);
        assert_eq!(
            snap_to_colour_edges(&flat, &mut mask, TWO_PASSES, |_| None),
            Some(0)
        );
        assert_eq!(mask, columns(5));
        let mut empty = Mask::empty(8, 3);
        assert_eq!(
            snap_to_colour_edges(&blurred_edge(), &mut empty, TWO_PASSES, |_| None),
            Some(0)
        );
        assert!(empty.is_empty());
    }

    #[test]
    fn a_frame_of_another_size_leaves_the_mask_alone() {
        let mut mask = columns(5);
        let small = RgbImage::new(4, 3);
        assert_eq!(
            snap_to_colour_edges(&small, &mut mask, TWO_PASSES, |_| None),
            None
        );
        assert_eq!(mask, columns(5));
    }

    #[test]
    fn zero_passes_change_nothing() {
        let mut mask = columns(5);
        assert_eq!(
            snap_to_colour_edges(
                &blurred_edge(),
                &mut mask,
                Snapping {
                    passes: 0,
                    ..TWO_PASSES
                },
                |_| None
            ),
            Some(0)
        );
        assert_eq!(mask, columns(5));
    }

    /// Every outline pixel decided in every pass over the whole image, straight from the
    /// module's description: what the region and the restricted later passes must reproduce.
    fn snap_everywhere(frame: &RgbImage, mask: &mut Mask, radius: usize, passes: u32) -> usize {
        let (w, h) = (mask.width() as usize, mask.height() as usize);
        let colour = |i: usize| {
            let p = frame.as_raw();
            [p[3 * i] as i32, p[3 * i + 1] as i32, p[3 * i + 2] as i32, 0]
        };
        let mut changed = 0;
        for _ in 0..passes {
            let labels = mask.pixels().to_vec();
            let mut class = vec![0; w * h];
            let bytes: Vec<u8> = labels.iter().map(|&l| l as u8).collect();
            mark_classes(&bytes, w, &mut class);
            let mut flips = Vec::new();
            for y in 0..h {
                for x in 0..w {
                    let i = y * w + x;
                    if class[i] != OUTLINE {
                        continue;
                    }
                    let (mut person, mut background) = (u32::MAX, u32::MAX);
                    for qy in y.saturating_sub(radius)..(y + radius + 1).min(h) {
                        for qx in x.saturating_sub(radius)..(x + radius + 1).min(w) {
                            let q = qy * w + qx;
                            let d = colour_distance(colour(i), colour(q));
                            match class[q] {
                                PERSON => person = person.min(d),
                                BACKGROUND => background = background.min(d),
                                _ => {}
                            }
                        }
                    }
                    if (labels[i] && background < person) || (!labels[i] && person < background) {
                        flips.push(i);
                    }
                }
            }
            changed += flips.len();
            for i in flips {
                mask.pixels_mut()[i] = !labels[i];
            }
        }
        changed
    }

    proptest! {
        #[test]
        fn the_region_and_the_later_passes_near_changes_decide_as_everywhere(
            seed in proptest::collection::vec(any::<u8>(), 12 * 10 * 4),
            radius in 1u32..4,
            passes in 1u32..4,
        ) {
            // A blob in a 12 × 10 frame of few colours, so that ties and flips both happen.
            let (w, h) = (12u32, 10u32);
            let frame = RgbImage::from_fn(w, h, |x, y| {
                let v = seed[((y * w + x) * 4) as usize] % 4 * 60;
                Rgb([v, 255 - v, v / 2])
            });
            let pixels = (0..w * h)
                .map(|i| {
                    let (x, y) = (i % w, i / w);
                    (2..9).contains(&x) && (2..8).contains(&y) && seed[(i * 4 + 1) as usize] > 40
                })
                .collect();
            let mask = Mask::from_pixels(w, h, pixels).expect("12 × 10");
            let (mut fast, mut slow) = (mask.clone(), mask);
            let changed = snap_to_colour_edges(
                &frame,
                &mut fast,
                Snapping { radius, passes, ..TWO_PASSES },
                |_| None,
            );
            let expected = snap_everywhere(&frame, &mut slow, radius as usize, passes);
            prop_assert_eq!(fast, slow);
            prop_assert_eq!(changed, Some(expected));
        }
    }
}
