//! Marker detection: the suit's coloured squares inside the person's mask.
//!
//! Every pixel inside the mask is classified to one of the suit's marker colours by hue (within the
//! suit's `hue_tolerance_deg` of the colour's hue, with saturation and value above the suit's gates,
//! so the yellowish-green cloth and dark or washed-out pixels are not markers), through one
//! 256 KB table from the pixel's 6-bit-per-channel RGB to its label. Pixels of one colour are
//! grouped into 4-connected components; a component is a marker when
//!
//! - its area fits a 4 × 4 cm square at the person's apparent size (estimated from the silhouette
//!   height for a 170 cm person): from a sliver of one to about four such squares, so that a marker
//!   cut by an arm or a fold, or seen at a slant, still counts;
//! - at least 40 % of its in-mask border is cloth, where a border pixel that is neither cloth nor a
//!   marker colour (the grey a blurred purple edge makes with the complementary green cloth) is judged
//!   by the pixel one step further out;
//! - its most saturated pixel reaches half its colour's printed saturation, and for red, whose hue
//!   gate takes in skin, more than skin's 0.5 (hands next to red markers).
//!
//! Each marker's centroid, colour and area go to the Feature Context descriptor.
//!
//! Measured (2026-12-01) with `suitcap describe --masks … --truth-markers …` on five 640×480
//! sequences (`suitcap-synth --frames 60 --threads 1 --backgrounds ../shared/backgrounds/photos`,
//! seeds 201–205: walk 08_01 ana, kick 10_03 ben, jump 13_39 chidi, dance 05_12 dana, kick 11_01
//! emil), recall / precision with ground-truth masks, before → after the grey-rim, saturation and
//! 40 % border rules: walk 0.973 / 0.990 → 0.972 / 0.991, kick 10 0.932 / 0.994 → 0.938 / 0.993,
//! jump 0.979 / 0.991 → 0.979 / 0.991, dance 0.931 / 0.994 → 0.933 / 0.994, kick 11 0.894 / 0.998 →
//! 0.963 / 0.9995 (the old rule lost purple markers whose whole rim is grey). With the segmenter's
//! masks the precision rises 0.964 → 0.970, 0.927 → 0.955, 0.964 → 0.963, 0.978 → 0.981, 0.997 →
//! 0.999. The constants were chosen on these same sequences. What is still missed is mostly markers
//! seen nearly edge-on: markers with no rendered pixel whose four neighbours are the same marker
//! (at most 2 px thick) are 16 % and 17 % of the counted truth of kick 10 and dance 05 and are found
//! 0.73 and 0.67 of the time; the rest 0.976 and 0.987. Tried and dropped: splitting large components into
//! their saturated cores (recall +0.1–0.3 points, precision −1 point), taking the cloth's colour out
//! of grey and brownish pixels before the hue test (precision with segmenter masks 0.82–0.97),
//! one-pixel markers and a 15 % border share (precision down, recall unchanged).

use glam::Vec2;
use image::RgbImage;

use crate::mask::Mask;
use crate::segment::features::{ColourLut, MarkerGate, PixelColour};
use crate::suit::SuitDefinition;

/// Height assumed for the person when converting the silhouette's height to centimetres.
pub const ASSUMED_HEIGHT_CM: f32 = 170.0;

/// One detected marker.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DetectedMarker {
    /// Centroid in pixels (pixel centres at +0.5).
    pub centre: Vec2,
    /// Index into the suit's marker colours.
    pub colour: usize,
    /// Pixels.
    pub area: u32,
}

/// Classifies pixels to marker colours and finds the markers of a frame.
#[derive(Clone, Debug)]
pub struct MarkerDetector {
    lut: ColourLut,
    /// The label of every 6-bit-per-channel RGB (indexed like [`ColourLut`]): a marker colour index,
    /// `CLOTH` or `NONE`; one lookup per pixel in the labelling pass.
    pixel_label: Vec<u8>,
    /// The suit's saturation/value gates and marker/cloth hue tests.
    gate: MarkerGate,
    marker_size_cm: f32,
    /// Per marker colour: the saturation (0–255) a component's most saturated pixel must reach.
    min_peak_sat: Vec<u8>,
    labels: Vec<u8>,
    stack: Vec<usize>,
}

const NONE: u8 = u8::MAX;
const SEEN: u8 = u8::MAX - 1;
const CLOTH: u8 = u8::MAX - 2;
const OUTSIDE: u8 = u8::MAX - 3;
/// Share of a marker's in-mask border that must be cloth.
const MIN_CLOTH_BORDER: f32 = 0.4;
/// Share of its colour's printed saturation that a marker's most saturated pixel must reach.
const PEAK_SATURATION_SHARE: f32 = 0.5;
/// Hue of skin (degrees): skin tones lie at about 15–30°, inside the red marker's hue gate.
const SKIN_HUE_DEG: f32 = 20.0;
/// Skin is at most this saturated (the six subjects' albedos: 0.27–0.50; a red marker's core 0.85).
const SKIN_MAX_SATURATION: f32 = 0.5;

/// The saturation (0–255) a component's most saturated pixel must reach to be a marker of colour
/// `hsv`: half the printed saturation, so a marker blurred into the cloth still passes, and for a
/// colour whose hue gate takes in skin, more than skin reaches (hands next to red markers).
fn min_peak_saturation(hsv: crate::colour::Hsv, hue_tolerance_deg: f32) -> u8 {
    let mut min = PEAK_SATURATION_SHARE * hsv.saturation;
    if crate::colour::hue_distance(hsv.hue, SKIN_HUE_DEG) <= hue_tolerance_deg {
        min = min.max(SKIN_MAX_SATURATION);
    }
    (min * 255.0).round() as u8
}

impl MarkerDetector {
    pub fn new(suit: &SuitDefinition) -> MarkerDetector {
        let gates = suit.detection;
        let lut = ColourLut::new();
        let gate = MarkerGate::new(suit);
        let pixel_label = (0..1usize << 18)
            .map(|i| {
                let rgb = [(i >> 12) as u8, (i >> 6) as u8 & 63, i as u8 & 63].map(|c| c << 2);
                let c = lut.get(rgb);
                match gate.marker_index(c) {
                    Some(k) => k as u8,
                    None if gate.is_cloth(c) => CLOTH,
                    None => NONE,
                }
            })
            .collect();
        MarkerDetector {
            lut,
            pixel_label,
            gate,
            marker_size_cm: suit.marker_size_cm,
            min_peak_sat: suit
                .markers
                .iter()
                .map(|m| min_peak_saturation(m.hsv, gates.hue_tolerance_deg))
                .collect(),
            labels: Vec::new(),
            stack: Vec::new(),
        }
    }

    /// The marker colour of a pixel, if it has one.
    #[inline]
    pub fn classify(&self, c: PixelColour) -> Option<u8> {
        self.gate.marker_index(c).map(|k| k as u8)
    }

    /// Area bounds (pixels) of a marker for a silhouette `height` pixels tall.
    pub fn area_bounds(&self, height: f32) -> (u32, u32) {
        let side = self.marker_size_cm * height / ASSUMED_HEIGHT_CM;
        let square = side * side;
        (
            (0.08 * square).max(2.0) as u32,
            (4.0 * square).max(6.0) as u32,
        )
    }

    /// The markers inside `mask` (same size as `frame`). An empty mask gives no markers.
    pub fn detect(&mut self, frame: &RgbImage, mask: &Mask) -> Vec<DetectedMarker> {
        let Some((x0, y0, x1, y1)) = mask.bounding_box() else {
            return Vec::new();
        };
        if frame.dimensions() != (mask.width(), mask.height()) {
            return Vec::new();
        }
        let (bw, bh) = ((x1 - x0) as usize, (y1 - y0) as usize);
        let width = frame.width() as usize;
        let raw = frame.as_raw();
        let inside = mask.pixels();
        self.labels.clear();
        self.labels.resize(bw * bh, NONE);
        for y in 0..bh {
            let row = (y + y0 as usize) * width + x0 as usize;
            for x in 0..bw {
                let i = row + x;
                self.labels[y * bw + x] = if inside[i] {
                    let p = i * 3;
                    let (r, g, b) = (raw[p] as usize, raw[p + 1] as usize, raw[p + 2] as usize);
                    self.pixel_label[((r >> 2) << 12) | ((g >> 2) << 6) | (b >> 2)]
                } else {
                    OUTSIDE
                };
            }
        }
        let (min_area, max_area) = self.area_bounds(bh as f32);
        let mut markers = Vec::new();
        for start in 0..self.labels.len() {
            let colour = self.labels[start];
            if colour >= OUTSIDE {
                continue;
            }
            let (mut area, mut sum) = (0u32, Vec2::ZERO);
            let (mut border, mut cloth_border) = (0u32, 0u32);
            let mut peak_sat = 0u8;
            self.labels[start] = SEEN;
            self.stack.push(start);
            while let Some(i) = self.stack.pop() {
                let (x, y) = (i % bw, i / bw);
                area += 1;
                sum += Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let p = ((y + y0 as usize) * width + x + x0 as usize) * 3;
                peak_sat = peak_sat.max(self.lut.get([raw[p], raw[p + 1], raw[p + 2]]).sat);
                for (dx, dy) in [(-1, 0), (1, 0), (0, -1), (0, 1)] {
                    let Some(j) = step(x, y, bw, bh, dx, dy) else {
                        continue;
                    };
                    let label = self.labels[j];
                    if label == colour {
                        self.labels[j] = SEEN;
                        self.stack.push(j);
                    } else if label != SEEN && label != OUTSIDE {
                        border += 1;
                        let beyond = if label == NONE {
                            step(x, y, bw, bh, 2 * dx, 2 * dy).map(|k| self.labels[k])
                        } else {
                            None
                        };
                        cloth_border += (label == CLOTH || beyond == Some(CLOTH)) as u32;
                    }
                }
            }
            let on_cloth = border == 0 || cloth_border as f32 >= MIN_CLOTH_BORDER * border as f32;
            let saturated = peak_sat >= self.min_peak_sat[colour as usize];
            if on_cloth && saturated && (min_area..=max_area).contains(&area) {
                markers.push(DetectedMarker {
                    centre: sum / area as f32 + Vec2::new(x0 as f32, y0 as f32),
                    colour: colour as usize,
                    area,
                });
            }
        }
        markers
    }
}

/// The index of pixel (`x` + `dx`, `y` + `dy`) in a `bw` × `bh` grid, if inside it.
#[inline]
fn step(x: usize, y: usize, bw: usize, bh: usize, dx: isize, dy: isize) -> Option<usize> {
    let (x, y) = (x.checked_add_signed(dx)?, y.checked_add_signed(dy)?);
    (x < bw && y < bh).then(|| y * bw + x)
}

/// A marker the generator says is visible, for scoring detections.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TruthMarker {
    pub centre: Vec2,
    pub colour: usize,
    pub visible_fraction: f32,
    pub visible_px: u32,
}

/// Detections scored against the truth of one or more frames.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MarkerScore {
    /// Truth markers that count for recall, and how many of them were found.
    pub truth: usize,
    pub found: usize,
    /// Detections, and how many lie on a truth marker of their colour.
    pub detections: usize,
    pub correct: usize,
}

impl MarkerScore {
    pub fn recall(&self) -> f64 {
        if self.truth == 0 {
            1.0
        } else {
            self.found as f64 / self.truth as f64
        }
    }

    pub fn precision(&self) -> f64 {
        if self.detections == 0 {
            1.0
        } else {
            self.correct as f64 / self.detections as f64
        }
    }

    pub fn add(&mut self, other: MarkerScore) {
        self.truth += other.truth;
        self.found += other.found;
        self.detections += other.detections;
        self.correct += other.correct;
    }
}

/// Scores one frame's detections. A truth marker counts for recall when at least `min_fraction` of
/// it and at least `min_px` pixels are visible; it is found when a detection of its colour lies within
/// `tolerance` pixels of its projected centre. A detection is correct when it lies within `tolerance`
/// of any visible truth marker of its colour. Each detection matches at most one truth marker.
pub fn score_markers(
    detected: &[DetectedMarker],
    truth: &[TruthMarker],
    min_fraction: f32,
    min_px: u32,
    tolerance: f32,
) -> MarkerScore {
    let mut used = vec![false; detected.len()];
    let mut score = MarkerScore {
        detections: detected.len(),
        ..MarkerScore::default()
    };
    // Greedy matching, nearest pairs first.
    let mut pairs: Vec<(f32, usize, usize)> = Vec::new();
    for (t, tm) in truth.iter().enumerate() {
        for (d, dm) in detected.iter().enumerate() {
            let distance = dm.centre.distance(tm.centre);
            if dm.colour == tm.colour && distance <= tolerance {
                pairs.push((distance, t, d));
            }
        }
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut truth_matched = vec![false; truth.len()];
    for (_, t, d) in pairs {
        if !truth_matched[t] && !used[d] {
            truth_matched[t] = true;
            used[d] = true;
        }
    }
    for (t, tm) in truth.iter().enumerate() {
        if tm.visible_fraction >= min_fraction && tm.visible_px >= min_px {
            score.truth += 1;
            score.found += truth_matched[t] as usize;
        }
    }
    score.correct = used.iter().filter(|&&u| u).count();
    score
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn suit() -> SuitDefinition {
        SuitDefinition::load_dir(&Path::new(env!("CARGO_MANIFEST_DIR")).join("suits/default"))
            .expect("suit")
    }

    /// A 170-pixel-tall green person (so a 4 cm marker is 4 px wide) with three markers.
    fn fixture() -> (RgbImage, Mask) {
        let (w, h) = (60u32, 180u32);
        let mut frame = RgbImage::from_pixel(w, h, image::Rgb([90, 90, 90]));
        let mut mask = vec![false; (w * h) as usize];
        for y in 5..175 {
            for x in 10..50 {
                frame.put_pixel(x, y, image::Rgb([123, 184, 64]));
                mask[(y * w + x) as usize] = true;
            }
        }
        let square = |frame: &mut RgbImage, x0: u32, y0: u32, rgb: [u8; 3]| {
            for y in y0..y0 + 4 {
                for x in x0..x0 + 4 {
                    frame.put_pixel(x, y, image::Rgb(rgb));
                }
            }
        };
        square(&mut frame, 12, 20, [204, 31, 31]); // red, centre (14, 22)
        square(&mut frame, 30, 40, [38, 191, 191]); // cyan, centre (32, 42)
        square(&mut frame, 20, 100, [100, 55, 158]); // purple, centre (22, 102)
                                                     // A red square outside the mask is not on the person.
        square(&mut frame, 52, 60, [204, 31, 31]);
        (frame, Mask::from_pixels(w, h, mask).expect("size"))
    }

    #[test]
    fn three_markers_at_known_places() {
        let (frame, mask) = fixture();
        let mut detector = MarkerDetector::new(&suit());
        let mut found = detector.detect(&frame, &mask);
        found.sort_by_key(|m| m.colour);
        assert_eq!(found.len(), 3, "{found:?}");
        let expected = [
            (0, Vec2::new(14.0, 22.0)),
            (1, Vec2::new(32.0, 42.0)),
            (2, Vec2::new(22.0, 102.0)),
        ];
        for (m, (colour, centre)) in found.iter().zip(expected) {
            assert_eq!(m.colour, colour);
            assert_eq!(m.area, 16);
            assert!(m.centre.distance(centre) < 1e-4, "{m:?}");
        }
    }

    #[test]
    fn the_cloth_and_an_empty_mask_give_no_markers() {
        let (frame, _) = fixture();
        let mut detector = MarkerDetector::new(&suit());
        assert!(detector.detect(&frame, &Mask::empty(60, 180)).is_empty());
        let plain = RgbImage::from_pixel(60, 180, image::Rgb([123, 184, 64]));
        let full = Mask::from_pixels(60, 180, vec![true; 60 * 180]).expect("size");
        assert!(detector.detect(&plain, &full).is_empty());
    }

    #[test]
    fn scoring_matches_by_colour_and_distance() {
        let d = |x: f32, c: usize| DetectedMarker {
            centre: Vec2::new(x, 0.0),
            colour: c,
            area: 9,
        };
        let t = |x: f32, c: usize, f: f32| TruthMarker {
            centre: Vec2::new(x, 0.0),
            colour: c,
            visible_fraction: f,
            visible_px: 9,
        };
        // Truth: red at 0 (whole), cyan at 10 (whole), red at 20 (30 % visible).
        // Detected: red at 0.5 (right), red at 10 (wrong colour for the cyan), red at 20.4 (the partial one).
        let truth = [t(0.0, 0, 1.0), t(10.0, 1, 1.0), t(20.0, 0, 0.3)];
        let detected = [d(0.5, 0), d(10.0, 0), d(20.4, 0)];
        let score = score_markers(&detected, &truth, 0.6, 4, 2.0);
        assert_eq!(
            score,
            MarkerScore {
                truth: 2,
                found: 1,
                detections: 3,
                correct: 2
            }
        );
        assert_eq!(score.recall(), 0.5);
        assert!((score.precision() - 2.0 / 3.0).abs() < 1e-12);
    }

    /// Paints the `size` × `size` square at (`x0`, `y0`).
    fn paint(frame: &mut RgbImage, x0: u32, y0: u32, size: u32, rgb: [u8; 3]) {
        for y in y0..y0 + size {
            for x in x0..x0 + size {
                frame.put_pixel(x, y, image::Rgb(rgb));
            }
        }
    }

    #[test]
    fn a_marker_with_a_grey_rim_is_still_on_the_cloth() {
        // Purple and the cloth's green are complementary: their blur is a grey ring around the marker,
        // so the marker's direct neighbours are not cloth; the cloth one pixel further out counts.
        let (mut frame, mask) = fixture();
        paint(&mut frame, 19, 59, 6, [100, 100, 100]);
        paint(&mut frame, 20, 60, 4, [100, 55, 158]);
        let mut detector = MarkerDetector::new(&suit());
        let found = detector.detect(&frame, &mask);
        assert_eq!(found.len(), 4, "{found:?}");
        assert!(found
            .iter()
            .any(|m| m.colour == 2 && m.centre.distance(Vec2::new(22.0, 62.0)) < 1e-4));
        // A blob inside a wide grey field is not on the cloth.
        paint(&mut frame, 10, 130, 20, [100, 100, 100]);
        paint(&mut frame, 18, 138, 4, [100, 55, 158]);
        assert_eq!(detector.detect(&frame, &mask).len(), 4);
    }

    #[test]
    fn skin_and_washed_out_blobs_are_not_markers() {
        let (mut frame, mask) = fixture();
        // Skin (hue 20°, saturation 0.45) is inside the red hue gate but below the skin bound.
        paint(&mut frame, 20, 60, 4, [200, 140, 110]);
        // A cyan blob at a quarter of the printed saturation (0.2 < half of 0.80).
        paint(&mut frame, 30, 80, 4, [150, 191, 191]);
        let mut detector = MarkerDetector::new(&suit());
        assert_eq!(detector.detect(&frame, &mask).len(), 3);
        assert_eq!(min_peak_saturation(suit().markers[0].hsv, 35.0), 128);
        assert_eq!(min_peak_saturation(suit().markers[1].hsv, 35.0), 102);
    }

    #[test]
    fn blobs_too_big_for_a_marker_are_rejected() {
        let (mut frame, mask) = fixture();
        for y in 120..160 {
            for x in 12..48 {
                frame.put_pixel(x, y, image::Rgb([204, 31, 31]));
            }
        }
        let mut detector = MarkerDetector::new(&suit());
        assert_eq!(detector.detect(&frame, &mask).len(), 3);
    }
}
