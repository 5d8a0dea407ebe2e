//! Per-pixel features of the segmenter: colour bins, hue/saturation for neighbour contrasts, gradients.
//!
//! A frame is first box-downscaled by the cut's factor; each pixel then gets, through a 6-bit-per-channel
//! RGB lookup table ([`ColourLut`]):
//! - a colour bin of (hue, saturation, value) for chromatic pixels, or of value alone for pixels whose
//!   saturation or value is too low for hue to mean anything ([`MIN_SATURATION`], [`MIN_VALUE`]);
//! - its hue and saturation, quantised to bytes, for the neighbourhood contrast bins;
//!
//! It also gets, from the value channel, its horizontal and vertical central-difference gradients.
//! The tables of `tables` are indexed by these bins.

use image::RgbImage;

use crate::colour::Hsv;

/// Below this saturation a pixel is achromatic.
pub const MIN_SATURATION: f32 = 0.12;
/// Below this value a pixel is achromatic.
pub const MIN_VALUE: f32 = 0.08;

pub const HUE_BINS: usize = 36;
pub const SAT_BINS: usize = 6;
pub const VAL_BINS: usize = 4;
pub const GREY_BINS: usize = 16;
/// Number of colour bins: chromatic (hue × saturation × value) then achromatic (value).
pub const COLOUR_BINS: usize = HUE_BINS * SAT_BINS * VAL_BINS + GREY_BINS;

/// Neighbour contrast bins: 12 hue-difference bins (6° wide up to 60°, one beyond, one for pairs with an
/// achromatic pixel, which use the value difference instead) × 6 saturation-difference bins.
pub const DHUE_BINS: usize = 12;
pub const DSAT_BINS: usize = 6;
pub const CONTRAST_BINS: usize = DHUE_BINS * DSAT_BINS;

/// Gradient bins per axis (0, 2, 4, 8, 16, 32, 64, 128 on the 0–255 value scale).
pub const GRADIENT_BINS: usize = 8;
/// Temporal difference bins (0, 3, 6, 12, 24, 48, 96).
pub const TEMPORAL_BINS: usize = 7;
/// Pattern classes: how much of the other half of the suit's pattern surrounds a pixel, and whether
/// it is the suit's mix of marker hues. For a marker-coloured pixel, the share of cloth-coloured
/// pixels in the window around it, mixed when a marker of another hue is in the window too; for any
/// other pixel, the share of marker-coloured pixels, mixed when markers of at least two hues are.
/// Classes 0–4: no other half, mixed with up to 6 %, up to 14 %, up to 25 %, more; 5 and 6: one hue
/// only, up to 14 % and more. The suit's markers take their hues at random from the suit's colours,
/// so a window of the suit almost always sees two of them; an orange, a tabby cat or a red poster
/// next to something yellow sees only one.
pub const PATTERN_CLASSES: usize = 7;

/// The pattern class of a share class (0–4 from [`pattern_class`]) and whether the hues are mixed.
#[inline]
pub fn mixed_pattern_class(share: u8, mixed: bool) -> u8 {
    match (share, mixed) {
        (0, _) => 0,
        (s, true) => s,
        (1 | 2, false) => 5,
        (_, false) => 6,
    }
}

/// Is this pattern class the suit's own interleaving of cloth and mixed markers with at least
/// `share` (a class 1–4)?
#[inline]
pub fn is_suit_pattern(class: u8, share: u8) -> bool {
    (share..=4).contains(&class)
}
/// Half-width of the pattern window: a 60th of the cut's height, at least 4 pixels (a 9 × 9 window at
/// 320 × 240). The person fills a similar share of the picture at any resolution, so the window
/// spans a similar number of marker pitches.
/// At most 127, so that a window's counts fit the 16-bit lanes of the pattern's summed-area table.
pub fn pattern_radius(height: usize) -> usize {
    ((height as f32 / 60.0).round() as usize).clamp(4, 127)
}

/// Pattern class of `count` pixels of the other half of the pattern in a window of `area` pixels:
/// a share of 0, up to 6 %, up to 14 %, up to 25 %, more. Compared in integers (6 % is 3/50, 14 %
/// 7/50), which for windows of up to 65,535 pixels classes every count as the share's `f32`
/// quotient did: a count off a bound is at least 1/(50 · area) away from it, far more than an
/// `f32`'s rounding there.
#[inline]
pub fn pattern_class(count: u32, area: u32) -> u8 {
    let fiftieths = count * 50;
    if count == 0 {
        0
    } else if fiftieths <= 3 * area {
        1
    } else if fiftieths <= 7 * area {
        2
    } else if count * 4 <= area {
        3
    } else {
        4
    }
}

/// Index into the joint colour × pattern table.
#[inline]
pub fn colour_index(colour: PixelColour, pattern: u8) -> usize {
    pattern as usize * COLOUR_BINS + colour.bin as usize
}

/// Which pixels have one of the suit's marker colours (hue within the suit's tolerance of a marker
/// hue, saturation and value above its gates).
#[derive(Clone, Debug)]
pub struct MarkerGate {
    /// Index + 1 of the marker colour a hue belongs to: the nearest marker hue within the suit's
    /// tolerance (0: none).
    marker_of: [u8; 256],
    markers: usize,
    /// Hues of the suit's cloth (its background colour).
    cloth_hue: [bool; 256],
    min_saturation: u8,
    min_value: u8,
}

impl MarkerGate {
    pub fn new(suit: &crate::suit::SuitDefinition) -> MarkerGate {
        let gates = suit.detection;
        MarkerGate {
            marker_of: std::array::from_fn(|q| {
                let hue = (q as f32 + 0.5) * 360.0 / 256.0;
                suit.markers
                    .iter()
                    .enumerate()
                    .filter(|(_, m)| {
                        crate::colour::hue_distance(hue, m.hsv.hue) <= gates.hue_tolerance_deg
                    })
                    .min_by(|a, b| {
                        crate::colour::hue_distance(hue, a.1.hsv.hue)
                            .total_cmp(&crate::colour::hue_distance(hue, b.1.hsv.hue))
                    })
                    .map_or(0, |(k, _)| (k + 1).min(255) as u8)
            }),
            markers: suit.markers.len().min(254),
            cloth_hue: std::array::from_fn(|q| {
                let hue = (q as f32 + 0.5) * 360.0 / 256.0;
                crate::colour::hue_distance(hue, suit.background.hsv.hue) <= gates.hue_tolerance_deg
            }),
            min_saturation: (gates.min_saturation * 255.0) as u8,
            min_value: (gates.min_value * 255.0) as u8,
        }
    }

    #[inline]
    pub fn is_marker(&self, c: PixelColour) -> bool {
        c.chromatic
            && c.sat >= self.min_saturation
            && c.val >= self.min_value
            && self.marker_of[c.hue as usize] != 0
    }

    /// Which of the suit's marker colours the pixel has, if any.
    #[inline]
    pub fn marker_index(&self, c: PixelColour) -> Option<usize> {
        if self.is_marker(c) {
            (self.marker_of[c.hue as usize] as usize).checked_sub(1)
        } else {
            None
        }
    }

    /// Number of marker colours of the suit.
    pub fn markers(&self) -> usize {
        self.markers
    }

    /// Does the pixel have the suit cloth's hue?
    #[inline]
    pub fn is_cloth(&self, c: PixelColour) -> bool {
        c.chromatic
            && c.sat >= self.min_saturation
            && c.val >= self.min_value
            && self.cloth_hue[c.hue as usize]
    }
}

/// Quantised colour of one pixel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PixelColour {
    pub bin: u16,
    /// Hue on 0–255 for the full circle.
    pub hue: u8,
    /// Saturation on 0–255.
    pub sat: u8,
    /// Value on 0–255.
    pub val: u8,
    pub chromatic: bool,
    /// The chroma (saturation × value) as a vector at the hue's angle, halved to fit: what
    /// [`temporal_difference`] compares besides the value.
    pub chroma: [i8; 2],
}

/// Colour bin of an RGB pixel (exact, without the lookup table).
pub fn classify(r: u8, g: u8, b: u8) -> PixelColour {
    let hsv = Hsv::from_rgb([r as f32 / 255.0, g as f32 / 255.0, b as f32 / 255.0]);
    let chromatic = hsv.saturation >= MIN_SATURATION && hsv.value >= MIN_VALUE;
    let bin = if chromatic {
        let h = ((hsv.hue / 360.0 * HUE_BINS as f32) as usize).min(HUE_BINS - 1);
        let s = (((hsv.saturation - MIN_SATURATION) / (1.0 - MIN_SATURATION) * SAT_BINS as f32)
            as usize)
            .min(SAT_BINS - 1);
        let v = ((hsv.value * VAL_BINS as f32) as usize).min(VAL_BINS - 1);
        (h * SAT_BINS + s) * VAL_BINS + v
    } else {
        HUE_BINS * SAT_BINS * VAL_BINS
            + ((hsv.value * GREY_BINS as f32) as usize).min(GREY_BINS - 1)
    };
    let chroma = 0.5 * 255.0 * hsv.saturation * hsv.value;
    let (sin, cos) = hsv.hue.to_radians().sin_cos();
    PixelColour {
        bin: bin as u16,
        hue: ((hsv.hue / 360.0 * 256.0) as u32).min(255) as u8,
        sat: (hsv.saturation * 255.0).round() as u8,
        val: (hsv.value * 255.0).round() as u8,
        chromatic,
        chroma: [(chroma * cos).round() as i8, (chroma * sin).round() as i8],
    }
}

/// How much a pixel's colour changed from one frame to the next, on the value's 0–255 scale: the
/// larger of the change in value and the change of the chroma vector along either axis. The value
/// alone (as the bilayer segmenter's intensity difference) misses the suit's yellowish green
/// leaving a blue or red background of the same brightness, so the motion term took such a pixel
/// for an unchanged one and kept the person's label on it: on `scripts/eval_segmenter.sh`'s
/// sequences 28–85 % of the pixels wrongly called person had been person in one of the three
/// frames before. With the chroma counted, that script's mean IoU rose by 0.013 with the
/// coordinate search's weights and stayed as it was with the pair search's, which turn the
/// temporal terms down.
#[inline]
pub fn temporal_difference(a: PixelColour, b: PixelColour) -> u32 {
    let da = (a.chroma[0] as i32 - b.chroma[0] as i32).unsigned_abs();
    let db = (a.chroma[1] as i32 - b.chroma[1] as i32).unsigned_abs();
    (a.val.abs_diff(b.val) as u32).max(2 * da.max(db))
}

/// RGB (6 bits per channel) → [`PixelColour`], 262,144 entries, built once per segmenter.
#[derive(Clone, Debug)]
pub struct ColourLut {
    table: Vec<PixelColour>,
}

impl Default for ColourLut {
    fn default() -> Self {
        ColourLut::new()
    }
}

impl ColourLut {
    pub fn new() -> ColourLut {
        let mut table = Vec::with_capacity(1 << 18);
        for r in 0..64u32 {
            for g in 0..64u32 {
                for b in 0..64u32 {
                    let up = |c: u32| ((c << 2) | (c >> 4)) as u8;
                    table.push(classify(up(r), up(g), up(b)));
                }
            }
        }
        ColourLut { table }
    }

    #[inline]
    pub fn get(&self, [r, g, b]: [u8; 3]) -> PixelColour {
        self.table[((r as usize >> 2) << 12) | ((g as usize >> 2) << 6) | (b as usize >> 2)]
    }
}

/// Contrast bin of two neighbouring pixels.
#[inline]
pub fn contrast_bin(a: PixelColour, b: PixelColour) -> usize {
    let dh = if a.chromatic && b.chromatic {
        let d = a.hue.wrapping_sub(b.hue).min(b.hue.wrapping_sub(a.hue)) as u32; // 0..128 = 0..180°
                                                                                 // 6° is 4.27 units on the 256-unit circle.
        ((d * 15 / 64) as usize).min(DHUE_BINS - 2)
    } else {
        DHUE_BINS - 1
    };
    let ds = if a.chromatic && b.chromatic {
        a.sat.abs_diff(b.sat)
    } else {
        a.val.abs_diff(b.val)
    } as usize;
    let ds = (ds / 13).min(DSAT_BINS - 1); // 13/255 ≈ 0.05 per bin, the last ≥ 0.25
    dh * DSAT_BINS + ds
}

/// Bin of a gradient magnitude on the 0–255 scale: 0, [2,4), [4,8), … [128, ∞).
#[inline]
pub fn gradient_bin(g: u32) -> usize {
    if g < 2 {
        0
    } else {
        ((32 - g.leading_zeros()) as usize - 1).min(GRADIENT_BINS - 1)
    }
}

/// [`gradient_bin`] of every difference of two bytes, for the per-pixel loop.
const GRADIENT_BIN_OF: [u8; 256] = {
    let mut table = [0u8; 256];
    let mut g = 2;
    while g < 256 {
        let bin = (31 - (g as u32).leading_zeros()) as usize;
        table[g] = if bin < GRADIENT_BINS {
            bin
        } else {
            GRADIENT_BINS - 1
        } as u8;
        g += 1;
    }
    table
};

/// Bin of a temporal difference: [0,3), [3,6), [6,12), [12,24), [24,48), [48,96), [96, ∞).
#[inline]
pub fn temporal_bin(d: u32) -> usize {
    match d {
        0..=2 => 0,
        3..=5 => 1,
        6..=11 => 2,
        12..=23 => 3,
        24..=47 => 4,
        48..=95 => 5,
        _ => 6,
    }
}

/// The features of one downscaled frame.
#[derive(Clone, Debug, Default)]
pub struct FrameFeatures {
    pub width: usize,
    pub height: usize,
    pub colour: Vec<PixelColour>,
    /// Joint bin of the horizontal and vertical gradient of the value channel.
    pub gradient: Vec<u8>,
    /// Gradient magnitude bin (max of the two axes), for the motion term.
    pub gradient_magnitude: Vec<u8>,
    /// Pattern class (see [`PATTERN_CLASSES`]), joint with the colour in the colour table.
    pub pattern: Vec<u8>,
    /// Summed-area table of the pattern's halves, one 16-bit lane each (see `compute_pattern`).
    pattern_sum: Vec<u64>,
    /// Which half of the pattern each pixel has (see `compute_pattern`).
    half: Vec<u8>,
}

/// Lanes of [`FrameFeatures`]' packed summed-area table: the cloth's colour, then one per marker
/// colour (a suit has at most [`MAX_MARKER_COLOURS`](crate::suit::MAX_MARKER_COLOURS)).
const PATTERN_LANES: usize = 4;
const LANE_BITS: u32 = 16;

/// "No seed pixel" in a chamfer distance map.
pub const FAR: u16 = u16::MAX / 2;

/// Two-pass 3-4 chamfer distance transform in place: seeds hold 0, other pixels [`FAR`]; the result
/// is 3 × the distance in pixels (4 per diagonal step): for a seed `a` columns and `b` rows away,
/// 3·max(a, b) + min(a, b). Each pass takes a row's steps from the row before it (straight and
/// diagonal) over the whole row at once, which vectorises, then its steps along the row, the one
/// part that runs pixel after pixel.
pub fn chamfer(d: &mut [u16], w: usize, h: usize) {
    if w == 0 || h == 0 {
        return;
    }
    // Forward: the row above and its two diagonals, then from the left.
    for y in 0..h {
        if y > 0 {
            let (above, row) = d[(y - 1) * w..(y + 1) * w].split_at_mut(w);
            from_row(row, above);
        }
        let row = &mut d[y * w..(y + 1) * w];
        for x in 1..w {
            row[x] = row[x].min(row[x - 1] + 3);
        }
    }
    // Backward: the row below and its two diagonals, then from the right.
    for y in (0..h).rev() {
        if y + 1 < h {
            let (row, below) = d[y * w..(y + 2) * w].split_at_mut(w);
            from_row(row, below);
        }
        let row = &mut d[y * w..(y + 1) * w];
        for x in (0..w - 1).rev() {
            row[x] = row[x].min(row[x + 1] + 3);
        }
    }
}

/// One chamfer step from the neighbouring row `next` into `row`: straight (3) and diagonal (4).
fn from_row(row: &mut [u16], next: &[u16]) {
    for (v, &n) in row.iter_mut().zip(next) {
        *v = (*v).min(n + 3);
    }
    for (v, &n) in row[1..].iter_mut().zip(next) {
        *v = (*v).min(n + 4);
    }
    for (v, &n) in row.iter_mut().zip(&next[1..]) {
        *v = (*v).min(n + 4);
    }
}

/// Pixels this close (at the cut's resolution) to a pixel of the suit's pattern can be the suit.
pub const SUIT_RADIUS: u16 = 2;

/// Is pixel `i` of `features` a pixel of the suit's pattern: of the cloth's or a marker's colour, and
/// seeing the suit's mixed pattern around it (the seeds of [`suit_support`])?
#[inline]
pub fn is_pattern_seed(features: &FrameFeatures, gate: &MarkerGate, i: usize) -> bool {
    shows_suit_pattern(features, gate, i, 1)
}

/// Is pixel `i` of `features` of the cloth's or a marker's colour within the suit's interleaving
/// of the two with at least `share` (a pattern class 1–4, see [`is_suit_pattern`])?
#[inline]
pub fn shows_suit_pattern(
    features: &FrameFeatures,
    gate: &MarkerGate,
    i: usize,
    share: u8,
) -> bool {
    let c = features.colour[i];
    is_suit_pattern(features.pattern[i], share) && (gate.is_cloth(c) || gate.is_marker(c))
}

/// Is pixel `i` of `features` of the cloth's or a marker's colour with the other half of the
/// pattern around it, mixed hues or not (any pattern class but 0)? The looser seed of the
/// segmenter's run-time check that a cut pixel is near the suit's pattern. The mixed-hue seed of
/// [`is_pattern_seed`] needs two marker hues in the window, which a person far from the camera
/// (a marker pitch of 6 pixels in a 9-pixel window at 320 × 240) or a stretch of cloth without
/// markers (the seams where the suit's parts meet) often does not show: on the bundled demo clip
/// the mixed seeds cut off the torso of a side view and gave a mean IoU of 0.826 (worst frame
/// 0.215), these seeds 0.962 (worst 0.932), and every other test sequence the same or better.
#[inline]
pub fn is_near_pattern(features: &FrameFeatures, gate: &MarkerGate, i: usize) -> bool {
    let c = features.colour[i];
    features.pattern[i] != 0 && (gate.is_cloth(c) || gate.is_marker(c))
}

/// Where the suit can be: pixels within [`SUIT_RADIUS`] of a pixel of the cloth's or a marker's
/// colour that sees the suit's mixed pattern around it (see [`PATTERN_CLASSES`]; skin has a red
/// marker's hue, but no mixed markers around it). With `within`, only its set pixels are seeds.
pub fn suit_support(
    features: &FrameFeatures,
    gate: &MarkerGate,
    within: Option<&[bool]>,
    distance: &mut Vec<u16>,
    out: &mut Vec<bool>,
) {
    distance.clear();
    distance.extend((0..features.colour.len()).map(|i| {
        if within.is_none_or(|m| m[i]) && is_pattern_seed(features, gate, i) {
            0
        } else {
            FAR
        }
    }));
    chamfer(distance, features.width, features.height);
    out.clear();
    out.extend(distance.iter().map(|&d| d <= 3 * SUIT_RADIUS));
}

/// Box-downscales `image` by `factor` (1 = copy) into `out` (RGB, row-major): each output pixel is
/// the rounded mean of its `factor × factor` block; a last partial column or row is dropped.
///
/// The `factor` rows of a block are first added byte by byte into one row of 16-bit column sums
/// (a loop the compiler vectorises), then each block's columns are added from that row, with the
/// common factors as constants so that the division by the area becomes a multiplication: on the
/// bundled demo clips 0.33 against 0.53 ms at factor 2 (640×480) and 1.2 against 1.9 ms at
/// factor 3 (1440×1080) for the pixel-by-pixel loops before, with the same output.
pub fn downscale(image: &RgbImage, factor: u32, out: &mut Vec<[u8; 3]>) -> (usize, usize) {
    let f = factor.max(1) as usize;
    let (w, h) = (image.width() as usize / f, image.height() as usize / f);
    out.clear();
    out.reserve(w * h);
    let raw = image.as_raw();
    let stride = image.width() as usize * 3;
    // A constant block size lets the compiler turn the division by the area into a multiply.
    match f {
        2 => block_means::<2, u16>(2, raw, stride, w, h, out),
        3 => block_means::<3, u16>(3, raw, stride, w, h, out),
        4 => block_means::<4, u16>(4, raw, stride, w, h, out),
        // Column sums of up to 257 rows of bytes fit 16 bits.
        ..=257 => block_means::<0, u16>(f, raw, stride, w, h, out),
        _ => block_means::<0, u32>(f, raw, stride, w, h, out),
    }
    (w, h)
}

/// The block means of [`downscale`] for blocks of `F` (a constant) or, with `F` = 0, `f` pixels,
/// with column sums of `f` rows in `S`.
fn block_means<const F: usize, S>(
    f: usize,
    raw: &[u8],
    stride: usize,
    w: usize,
    h: usize,
    out: &mut Vec<[u8; 3]>,
) where
    S: Copy + Default + std::ops::AddAssign + From<u8> + Into<u32>,
{
    let f = if F > 0 { F } else { f };
    let span = w * f * 3;
    let area = (f * f) as u32;
    let mut sums = vec![S::default(); span];
    for y in 0..h {
        sums.fill(S::default());
        for row in raw[y * f * stride..(y + 1) * f * stride].chunks_exact(stride) {
            for (s, &v) in sums.iter_mut().zip(&row[..span]) {
                *s += S::from(v);
            }
        }
        for block in sums.chunks_exact(f * 3) {
            let mut sum = [0u32; 3];
            for p in block.chunks_exact(3) {
                sum[0] += p[0].into();
                sum[1] += p[1].into();
                sum[2] += p[2].into();
            }
            out.push(sum.map(|s| ((s + area / 2) / area) as u8));
        }
    }
}

impl FrameFeatures {
    /// Computes the features of a downscaled frame `rgb` of `width × height` into `self`.
    pub fn compute(
        &mut self,
        rgb: &[[u8; 3]],
        width: usize,
        height: usize,
        lut: &ColourLut,
        gate: &MarkerGate,
    ) {
        self.width = width;
        self.height = height;
        self.colour.clear();
        self.colour.extend(rgb.iter().map(|&p| lut.get(p)));
        self.gradient.clear();
        self.gradient_magnitude.clear();
        self.gradient.resize(width * height, 0);
        self.gradient_magnitude.resize(width * height, 0);
        if width == 0 || height == 0 {
            self.pattern.clear();
            return;
        }
        for y in 0..height {
            let line = |y: usize| &self.colour[y * width..(y + 1) * width];
            let (above, row, below) = (
                line(y.saturating_sub(1)),
                line(y),
                line((y + 1).min(height - 1)),
            );
            let gradient = &mut self.gradient[y * width..(y + 1) * width];
            let magnitude = &mut self.gradient_magnitude[y * width..(y + 1) * width];
            for x in 0..width {
                let gh = row[(x + 1).min(width - 1)]
                    .val
                    .abs_diff(row[x.saturating_sub(1)].val);
                let gv = below[x].val.abs_diff(above[x].val);
                let (bh, bv) = (GRADIENT_BIN_OF[gh as usize], GRADIENT_BIN_OF[gv as usize]);
                gradient[x] = bh * GRADIENT_BINS as u8 + bv;
                magnitude[x] = bh.max(bv);
            }
        }
        self.compute_pattern(gate);
    }

    /// The pattern class of every pixel from box sums (integral images) of the marker and cloth
    /// indicators over a [`pattern_radius`] window. On the suit every pixel sees both halves of the
    /// pattern; inside a red poster or a lawn, or a few pixels off the person, it does not.
    ///
    /// The four indicators (cloth, and each marker colour) share one summed-area table, a 16-bit
    /// lane each of a `u64`: sums of the whole image overflow a lane, but in wrapping arithmetic a
    /// box sum `a + d − b − c` is exact lane by lane as long as each lane's count in the box fits
    /// 16 bits, which a window of at most 65,535 pixels guarantees.
    fn compute_pattern(&mut self, gate: &MarkerGate) {
        let (w, h) = (self.width, self.height);
        let r = pattern_radius(h);
        debug_assert!((2 * r + 1).pow(2) < 1 << LANE_BITS);
        debug_assert!(gate.markers() < PATTERN_LANES);
        // Per pixel, the half of the pattern it has: 0 none, 1 the cloth, 2 + k marker colour k.
        self.half.clear();
        self.half
            .extend(self.colour.iter().map(|&c| match gate.marker_index(c) {
                Some(k) => (k + 2).min(u8::MAX as usize) as u8,
                None => gate.is_cloth(c) as u8,
            }));
        // Its lane in the summed-area table (a marker colour past the lanes counts in none).
        let lane_of: [u64; 256] = std::array::from_fn(|half| match half {
            0 => 0,
            n if n - 1 < PATTERN_LANES => 1 << (LANE_BITS as usize * (n - 1)),
            _ => 0,
        });
        let stride = w + 1;
        self.pattern_sum.clear();
        self.pattern_sum.resize(stride * (h + 1), 0);
        for (y, halves) in self.half.chunks_exact(w).enumerate() {
            let (above, below) = self.pattern_sum.split_at_mut((y + 1) * stride);
            let above = &above[y * stride..];
            let mut row = 0u64;
            for x in 0..w {
                row = row.wrapping_add(lane_of[halves[x] as usize]);
                below[x + 1] = above[x + 1].wrapping_add(row);
            }
        }
        let lane = |sums: u64, k: usize| ((sums >> (LANE_BITS as usize * k)) & 0xffff) as u32;
        // A marker pixel's own lane among the marker lanes, as a bit (none for the others).
        let own_bit: [u8; 256] = std::array::from_fn(|half| match half {
            n if n >= 2 && n - 1 < PATTERN_LANES => 1 << (n - 2),
            _ => 0,
        });
        let sum = &self.pattern_sum;
        self.pattern.clear();
        for (y, halves) in self.half.chunks_exact(w).enumerate() {
            let (y0, y1) = (y.saturating_sub(r), (y + r + 1).min(h));
            let (top, bottom) = (&sum[y0 * stride..][..stride], &sum[y1 * stride..][..stride]);
            let rows = (y1 - y0) as u32;
            for (x, &half) in halves.iter().enumerate() {
                let (x0, x1) = (x.saturating_sub(r), (x + r + 1).min(w));
                let boxed = bottom[x1]
                    .wrapping_add(top[x0])
                    .wrapping_sub(top[x1])
                    .wrapping_sub(bottom[x0]);
                let area = rows * (x1 - x0) as u32;
                // The marker lanes past the suit's colours hold no counts.
                let (mut markers_seen, mut seen) = (0u32, 0u8);
                for k in 1..PATTERN_LANES {
                    let n = lane(boxed, k);
                    markers_seen += n;
                    seen |= ((n > 0) as u8) << (k - 1);
                }
                // Marker colours present in the window other than the pixel's own.
                let present = (seen & !own_bit[half as usize]).count_ones();
                let (other, mixed) = if half >= 2 {
                    (lane(boxed, 0), present >= 1)
                } else {
                    (markers_seen, present >= 2)
                };
                self.pattern
                    .push(mixed_pattern_class(pattern_class(other, area), mixed));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    proptest::proptest! {
        #[test]
        fn the_chamfer_transform_is_the_nearest_seeds_3_4_distance(
            cells in proptest::collection::vec(proptest::bool::weighted(0.08), 1..300),
            width in 1usize..24,
        ) {
            let height = cells.len() / width;
            proptest::prop_assume!(height > 0);
            let seeds = &cells[..width * height];
            let mut d: Vec<u16> = seeds.iter().map(|&s| if s { 0 } else { FAR }).collect();
            chamfer(&mut d, width, height);
            for (i, &got) in d.iter().enumerate() {
                let (x, y) = (i % width, i / width);
                // 3 per step, 4 per diagonal: a seed a columns and b rows away is 3·max + min.
                let nearest = (0..seeds.len())
                    .filter(|&j| seeds[j])
                    .map(|j| {
                        let (a, b) = ((j % width).abs_diff(x), (j / width).abs_diff(y));
                        (3 * a.max(b) + a.min(b)) as u16
                    })
                    .min()
                    .unwrap_or(FAR);
                proptest::prop_assert_eq!(got, nearest, "pixel ({}, {})", x, y);
            }
        }
    }

    #[test]
    fn grey_and_dark_pixels_are_achromatic() {
        let grey = classify(128, 128, 128);
        assert!(!grey.chromatic);
        assert!(grey.bin as usize >= HUE_BINS * SAT_BINS * VAL_BINS);
        assert!(!classify(10, 0, 0).chromatic); // value 0.04
        let green = classify(120, 180, 60);
        assert!(green.chromatic && (green.bin as usize) < HUE_BINS * SAT_BINS * VAL_BINS);
    }

    #[test]
    fn suit_hues_fall_in_different_bins() {
        let bins: Vec<u16> = [
            [204, 31, 31],
            [38, 191, 191],
            [100, 55, 158],
            [123, 184, 64],
        ]
        .iter()
        .map(|&[r, g, b]| classify(r, g, b).bin)
        .collect();
        for i in 0..4 {
            for j in i + 1..4 {
                assert_ne!(
                    bins[i] as usize / (SAT_BINS * VAL_BINS),
                    bins[j] as usize / (SAT_BINS * VAL_BINS)
                );
            }
        }
    }

    #[test]
    fn lut_agrees_with_direct_classification_on_6_bit_colours() {
        let lut = ColourLut::new();
        for &(r, g, b) in &[
            (0u8, 0u8, 0u8),
            (255, 255, 255),
            (252, 4, 128),
            (100, 200, 40),
        ] {
            let up = |c: u8| (c & !3) | (c >> 6);
            assert_eq!(lut.get([r, g, b]), classify(up(r), up(g), up(b)));
        }
    }

    #[test]
    fn contrast_bins() {
        let a = classify(120, 180, 60);
        assert_eq!(contrast_bin(a, a), 0);
        let red = classify(204, 31, 31);
        assert_eq!(contrast_bin(a, red) / DSAT_BINS, DHUE_BINS - 2); // far apart in hue
        let grey = classify(128, 128, 128);
        assert_eq!(contrast_bin(a, grey) / DSAT_BINS, DHUE_BINS - 1);
    }

    #[test]
    fn a_change_of_hue_at_the_same_brightness_is_a_temporal_difference() {
        let (yellow, blue) = (classify(200, 200, 0), classify(0, 0, 200));
        assert_eq!(yellow.val, blue.val);
        // Chroma ½·255·1·0.784 = 100 at 60° and at 240°: the vectors are opposite, (±50, ±86.6),
        // so the larger component changes by 173, doubled back to the value's scale.
        assert!((340..=350).contains(&temporal_difference(yellow, blue)));
        assert_eq!(temporal_difference(yellow, yellow), 0);
        // Greys have no chroma: only the value counts.
        assert_eq!(
            temporal_difference(classify(40, 40, 40), classify(90, 90, 90)),
            50
        );
    }

    #[test]
    fn gradient_and_temporal_bins() {
        assert_eq!(
            [0, 1, 2, 3, 4, 8, 127, 128, 255].map(gradient_bin),
            [0, 0, 1, 1, 2, 3, 6, 7, 7]
        );
        for g in 0..=255u32 {
            assert_eq!(GRADIENT_BIN_OF[g as usize] as usize, gradient_bin(g), "{g}");
        }
        assert_eq!(
            [0, 2, 3, 6, 12, 24, 48, 96, 255].map(temporal_bin),
            [0, 0, 1, 2, 3, 4, 5, 6, 6]
        );
    }

    #[test]
    fn pattern_class_counts_the_other_half_of_the_pattern() {
        let suit = crate::suit::SuitDefinition::load_dir(
            &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("suits/default"),
        )
        .expect("suit");
        let gate = MarkerGate::new(&suit);
        let (red, green, grey) = ([204u8, 31, 31], [123u8, 184, 64], [128u8, 128, 128]);
        // A 12×1 row: green, one red marker at x = 1, green to x = 5, grey after.
        let mut rgb = vec![green; 12];
        rgb[1] = red;
        for p in rgb.iter_mut().skip(6) {
            *p = grey;
        }
        let mut f = FrameFeatures::default();
        f.compute(&rgb, 12, 1, &ColourLut::new(), &gate);
        // Window x−4..=x+4 clipped to the row. x = 0: 1 marker in 5 pixels (20 %), share class 3,
        // but one hue only → class 6. The marker (x = 1) sees 5 cloth pixels of 6 (class 4) and no
        // marker of another hue → 6. x = 5: 1 of 9 (11 %), share class 2, one hue → 5.
        // x = 6 (grey) no longer sees the marker (its window starts at 2) → class 0.
        assert_eq!(f.pattern, vec![6, 6, 6, 5, 5, 5, 0, 0, 0, 0, 0, 0]);
        // A cyan marker at x = 3 mixes the hues. Cloth x = 0: 2 markers of 5 pixels (40 %) → 4;
        // x = 2: 2 of 7 (29 %) → 4; x = 4 and 5: 2 of 9 (22 %) → 3. Each marker sees the other, and
        // its cloth share (x = 1: 4 of 6; x = 3: 4 of 8) is class 4 → 4. The grey x = 6 and 7 see the
        // cyan marker only (1 of 9, 11 %) → 5; x = 8 (window 4..=11) sees none → 0.
        rgb[3] = [38, 191, 191];
        f.compute(&rgb, 12, 1, &ColourLut::new(), &gate);
        assert_eq!(f.pattern, vec![4, 4, 4, 4, 3, 3, 5, 5, 0, 0, 0, 0]);
        assert!(!gate.is_marker(classify(123, 184, 64)) && gate.is_cloth(classify(123, 184, 64)));
        assert!(gate.is_marker(classify(38, 191, 191)));
    }

    #[test]
    fn the_suit_is_supported_near_its_mixed_pattern() {
        let suit = crate::suit::SuitDefinition::load_dir(
            &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("suits/default"),
        )
        .expect("suit");
        let gate = MarkerGate::new(&suit);
        // The mixed row of the pattern test: classes 4, 4, 4, 4, 3, 3 on the suit-coloured x = 0..=5,
        // then grey 5, 5, 0, 0, 0, 0.
        let (red, cyan, green, grey) = (
            [204u8, 31, 31],
            [38u8, 191, 191],
            [123u8, 184, 64],
            [128u8, 128, 128],
        );
        let mut rgb = vec![green; 6];
        rgb[1] = red;
        rgb[3] = cyan;
        rgb.extend([grey; 6]);
        let mut f = FrameFeatures::default();
        f.compute(&rgb, 12, 1, &ColourLut::new(), &gate);
        let (mut distance, mut support) = (Vec::new(), Vec::new());
        // Seeds x = 0..=5; SUIT_RADIUS = 2 reaches x = 7.
        suit_support(&f, &gate, None, &mut distance, &mut support);
        let expect = |n: usize| (0..12).map(|x| x < n).collect::<Vec<bool>>();
        assert_eq!(support, expect(8));
        // Seeds only inside a mask of x = 0..=2: support to x = 4.
        let within = expect(3);
        suit_support(&f, &gate, Some(&within), &mut distance, &mut support);
        assert_eq!(support, expect(5));
        // A lone red marker on the cloth is not the suit's mix: no support at all.
        rgb[3] = green;
        f.compute(&rgb, 12, 1, &ColourLut::new(), &gate);
        suit_support(&f, &gate, None, &mut distance, &mut support);
        assert_eq!(support, expect(0));
        // It is near the pattern, though: the suit-coloured x = 0..=5 (classes 6, 6, 6, 5, 5, 5),
        // not the grey beyond, nor cloth with no marker in its window (the row from x = 6 green).
        let near: Vec<bool> = (0..12).map(|i| is_near_pattern(&f, &gate, i)).collect();
        assert_eq!(near, expect(6));
        for p in rgb.iter_mut().skip(6) {
            *p = green;
        }
        f.compute(&rgb, 12, 1, &ColourLut::new(), &gate);
        let near: Vec<bool> = (0..12).map(|i| is_near_pattern(&f, &gate, i)).collect();
        assert_eq!(
            near,
            expect(6),
            "x = 6..=11 see the marker at x = 1 up to x = 5 only"
        );
    }

    #[test]
    fn downscale_averages_blocks() {
        let mut img = RgbImage::new(4, 2);
        img.put_pixel(0, 0, image::Rgb([100, 0, 0]));
        img.put_pixel(1, 1, image::Rgb([200, 0, 0]));
        let mut out = Vec::new();
        assert_eq!(downscale(&img, 2, &mut out), (2, 1));
        assert_eq!(out, vec![[75, 0, 0], [0, 0, 0]]);
    }

    #[test]
    fn halving_matches_the_block_mean_of_any_factor() {
        // An odd-sized image (the last column and row are dropped) with every value different:
        // factors 2, 3 and 4 (constant block sizes) and 5 (any size) against the rounded mean of
        // each block.
        let img = RgbImage::from_fn(9, 7, |x, y| {
            image::Rgb([
                (x * 29 + y * 7) as u8,
                (x * 3 + y * 41) as u8,
                (x * y * 13 + 5) as u8,
            ])
        });
        for f in [2u32, 3, 4, 5] {
            let mut out = Vec::new();
            let (w, h) = downscale(&img, f, &mut out);
            assert_eq!((w, h), (9 / f as usize, 7 / f as usize));
            for (k, p) in out.iter().enumerate() {
                let (x, y) = ((k % w) as u32 * f, (k / w) as u32 * f);
                for (c, &value) in p.iter().enumerate() {
                    let sum: u32 = (0..f * f)
                        .map(|i| img.get_pixel(x + i % f, y + i / f)[c] as u32)
                        .sum();
                    assert_eq!(
                        value as u32,
                        (sum + f * f / 2) / (f * f),
                        "factor {f} pixel {k}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_block_taller_than_sixteen_bit_column_sums_hold_is_still_its_mean() {
        // 258 rows of 255 overflow a 16-bit column sum; factor 258 takes the 32-bit path.
        let img = RgbImage::from_fn(259, 258, |x, y| {
            image::Rgb([
                255,
                (x % 7) as u8 * 30,
                if (x + y) % 2 == 0 { 200 } else { 0 },
            ])
        });
        let mut out = Vec::new();
        assert_eq!(downscale(&img, 258, &mut out), (1, 1));
        assert_eq!(out, vec![[255, 90, 100]]);
    }

    #[test]
    fn pattern_classes_in_integers_are_the_classes_of_the_share() {
        // The rule as a share (an f32 quotient, as the classes were first defined) against the
        // integer comparisons, for every count of every window up to 21 × 21 pixels and around
        // each bound in the largest windows the 16-bit lanes allow.
        let of_share = |share: f32| -> u8 {
            if share <= 0.0 {
                0
            } else if share <= 0.06 {
                1
            } else if share <= 0.14 {
                2
            } else if share <= 0.25 {
                3
            } else {
                4
            }
        };
        let check = |count: u32, area: u32| {
            assert_eq!(
                pattern_class(count, area),
                of_share(count as f32 / area as f32),
                "{count} of {area}"
            );
        };
        for area in 1..=441 {
            (0..=area).for_each(|count| check(count, area));
        }
        for area in [255 * 255, 65_000, 65_535u32] {
            for bound in [area * 3 / 50, area * 7 / 50, area / 4] {
                (bound.saturating_sub(2)..=bound + 2).for_each(|count| check(count, area));
            }
        }
        assert_eq!(pattern_class(3, 50), 1, "6 % is in class 1");
        assert_eq!(pattern_class(4, 50), 2);
        assert_eq!(pattern_class(7, 50), 2, "14 % is in class 2");
        assert_eq!(pattern_class(1, 4), 3, "25 % is in class 3");
        assert_eq!(pattern_class(26, 100), 4);
    }
}
