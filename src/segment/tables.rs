//! The segmenter's learned lookup tables (source paper sec. 3.1.1, after Criminisi et al. 2006).
//!
//! Five likelihood tables, learned by counting over training frames with masks and stored as negative
//! log-likelihoods:
//! 1. colour C: p(colour bin, pattern class | label), smoothed along hue (circularly), saturation
//!    and value, mixed with a uniform share, with a floor. The pattern class (not in the paper) is the
//!    share of the other half of the suit's pattern around the pixel (markers around cloth, cloth
//!    around a marker, see `features::PATTERN_CLASSES`): on the suit both halves are interleaved every
//!    7 cm, on a lawn or a poster of the cloth's colour or a red object they are not, so the joint
//!    table tells the suit from backgrounds that share one of its colours;
//! 2. neighbourhood N: p(contrast bin | label pair) for BG→BG, BG→FG, FG→BG, FG→FG, counted over the
//!    eight neighbours of the 3×3 neighbourhood (the cut itself uses the four axial ones);
//! 3. gradient G: p(horizontal, vertical gradient bin | label);
//! 4. motion M: p(gradient magnitude bin, temporal difference bin | label at t, label at t−1), the
//!    difference counting a change of chroma as well as of brightness, which lets
//!    labels change where the image changes at an edge and not inside smooth regions;
//! 5. temporal T: the second-order Markov prior p(label_t | label_t−1, label_t−2);
//!
//! plus the label prior (used while there is no history), the prior of equal and different labels of
//! neighbours, and the weights σ_C, σ_N, σ_G, σ_M, σ_T of the five terms in the energy. [`SegmenterTables`] is what `segmenter` turns into graph
//! capacities and what `suitcap-train segment` writes to the suit directory.

use std::path::Path;

use super::features::{
    colour_index, contrast_bin, FrameFeatures, COLOUR_BINS, CONTRAST_BINS, GRADIENT_BINS,
    GREY_BINS, HUE_BINS, PATTERN_CLASSES, SAT_BINS, TEMPORAL_BINS, VAL_BINS,
};
use crate::model::{ModelError, ModelFile};

pub const SEGMENTER_KIND: &str = "segmenter";
/// Version of the segmenter model file; bump when the features or tables change.
/// 7: the rows of the grid the tables were counted on (`trained_rows`); 8: the motion term's
/// temporal difference counts a change of chroma at the same brightness
/// (`features::temporal_difference`).
pub const SEGMENTER_VERSION: u32 = 8;
/// Model file name inside a suit directory.
pub const SEGMENTER_FILE: &str = "segmenter.bin";

/// Entries of the joint colour × pattern table.
pub const COLOUR_TABLE: usize = COLOUR_BINS * PATTERN_CLASSES;

/// Smallest probability a table holds.
const FLOOR: f32 = 1e-5;

/// A frame taller than the training frames is cut on a grid of at least this many times the rows
/// the tables were counted on (see [`SegmenterTables::cut_factor`]). Measured on four 1440×1080
/// sequences with tables counted at 240 rows: a cut at 360 rows (×1.5) lost 0.002–0.004 IoU
/// against 540 rows in half the time; at 270 rows (×1.125) up to 0.015.
pub const CUT_ROWS_MARGIN: f32 = 1.5;

/// The weights of the five energy terms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Weights {
    pub colour: f32,
    pub neighbourhood: f32,
    pub gradient: f32,
    pub motion: f32,
    pub temporal: f32,
}

impl Default for Weights {
    fn default() -> Self {
        Weights::from_array([1.0; WEIGHTS])
    }
}

/// Number of term weights.
pub const WEIGHTS: usize = 5;

impl Weights {
    pub fn to_array(self) -> [f32; WEIGHTS] {
        [
            self.colour,
            self.neighbourhood,
            self.gradient,
            self.motion,
            self.temporal,
        ]
    }

    pub fn from_array(a: [f32; WEIGHTS]) -> Weights {
        Weights {
            colour: a[0],
            neighbourhood: a[1],
            gradient: a[2],
            motion: a[3],
            temporal: a[4],
        }
    }
}

/// Learned negative log-likelihoods. Label index 0 = background, 1 = person.
#[derive(Clone, Debug, PartialEq)]
pub struct SegmenterTables {
    /// The cut runs on frames box-downscaled by this factor (at least; see
    /// [`SegmenterTables::cut_factor`]).
    pub downscale: u32,
    /// Rows of the grid the tables were counted on: the training frames' height over `downscale`.
    pub trained_rows: u32,
    /// `[label][pattern class · COLOUR_BINS + colour bin]` (see `features::colour_index`).
    pub colour: [Vec<f32>; 2],
    /// `−ln p(label)`.
    pub prior: [f32; 2],
    /// `[2·label_p + label_q][contrast bin]`: `−ln p(contrast | pair)`.
    pub neighbourhood: [Vec<f32>; 4],
    /// `−ln p(neighbours' labels equal)`, `−ln p(different)`: the Potts prior of the pairwise term.
    pub pair_prior: [f32; 2],
    /// `[label][gradient bin]`.
    pub gradient: [Vec<f32>; 2],
    /// `[2·label_t + label_t−1][gradient magnitude bin · TEMPORAL_BINS + temporal bin]`.
    pub motion: [Vec<f32>; 4],
    /// `[4·label_t + 2·label_t−1 + label_t−2]`.
    pub temporal: [f32; 8],
    /// `−ln p(colour bin | part)`: the person's parts outside the suit (head, hands, shoes), broadly
    /// smoothed (another person's skin is lighter or darker than the trained one's).
    pub part: Vec<f32>,
    /// `−ln p(background)`, `−ln p(part)` of a non-suit pixel within the attachment band of the suit.
    pub part_prior: [f32; 2],
    pub weights: Weights,
}

/// Counts gathered from training frames.
#[derive(Clone, Debug)]
pub struct TableCounts {
    colour: [Vec<f64>; 2],
    labels: [f64; 2],
    neighbourhood: [Vec<f64>; 4],
    gradient: [Vec<f64>; 2],
    motion: [Vec<f64>; 4],
    temporal: [f64; 8],
    part: Vec<f64>,
    /// Non-suit pixels of the attachment band: background, part.
    band: [f64; 2],
}

impl Default for TableCounts {
    fn default() -> Self {
        TableCounts {
            colour: [vec![0.0; COLOUR_TABLE], vec![0.0; COLOUR_TABLE]],
            labels: [0.0; 2],
            neighbourhood: std::array::from_fn(|_| vec![0.0; CONTRAST_BINS]),
            gradient: [
                vec![0.0; GRADIENT_BINS * GRADIENT_BINS],
                vec![0.0; GRADIENT_BINS * GRADIENT_BINS],
            ],
            motion: std::array::from_fn(|_| vec![0.0; GRADIENT_BINS * TEMPORAL_BINS]),
            temporal: [0.0; 8],
            part: vec![0.0; COLOUR_BINS],
            band: [0.0; 2],
        }
    }
}

/// Normalised negative log of `counts + alpha`, floored.
fn nll(counts: &[f64], alpha: f64) -> Vec<f32> {
    nll_mixed(counts, alpha, 0.0)
}

/// Like [`nll`], with the distribution mixed with a uniform one: `(1 − uniform)·p + uniform / bins`.
/// The background of a new room has colours and textures no training frame showed; the uniform share
/// keeps them plausible as background instead of leaving them at the floor, where the person model
/// (concentrated on the suit's colours) would win by accident.
fn nll_mixed(counts: &[f64], alpha: f64, uniform: f64) -> Vec<f32> {
    let total: f64 = counts.iter().sum::<f64>() + alpha * counts.len() as f64;
    let flat = uniform / counts.len() as f64;
    counts
        .iter()
        .map(|&c| -(((1.0 - uniform) * (c + alpha) / total + flat).max(FLOOR as f64)).ln() as f32)
        .collect()
}

/// Uniform share of the background's colour and gradient tables, and of the person's.
pub const BACKGROUND_UNIFORM: f64 = 0.5;
pub const PERSON_UNIFORM: f64 = 0.02;
/// Uniform share of the part table, and how many times its counts are smoothed along hue,
/// saturation and value: the training frames show one person's skin, hair and shoes; the suit will
/// be worn by others, whose skin is lighter or darker (value, saturation) and a bin or so redder
/// or yellower (hue 10°–30°). One pass along hue and saturation: with none along hue, a 20° skin
/// next to the training subject's 25° fell in an empty bin and heads were left off the mask; with
/// two, fur and wood of a skin's colour next to the suit were taken for hands (a choice made on the
/// evaluation sequences of `scripts/eval_segmenter.sh`, so its figures are optimistic).
pub const PART_UNIFORM: f64 = 0.05;
pub const PART_SMOOTHING: [usize; 3] = [1, 1, 3];

/// Spreads colour counts to the neighbouring bins with weights ¼ ½ ¼ along hue (circularly),
/// saturation and value (and along value for the achromatic bins), so that a change of light that
/// shifts a colour by a bin does not fall into an empty one.
fn smooth_colour(counts: &[f64]) -> Vec<f64> {
    smooth_colour_axes(counts, 1, 1, 1)
}

/// [`smooth_colour`] with a number of ¼ ½ ¼ passes per axis (hue, saturation, value; the
/// achromatic bins take the value passes).
fn smooth_colour_axes(counts: &[f64], hue: usize, sat: usize, val: usize) -> Vec<f64> {
    let chromatic = HUE_BINS * SAT_BINS * VAL_BINS;
    let index = |[h, s, v]: [usize; 3]| (h * SAT_BINS + s) * VAL_BINS + v;
    let mut a = counts.to_vec();
    let mut b = counts.to_vec();
    let clamp_step = |k: usize, n: usize| (k.saturating_sub(1), (k + 1).min(n - 1));
    // One ¼ ½ ¼ pass along `axis` (0 hue, circular; 1 saturation; 2 value) over the chromatic bins.
    let pass = |a: &[f64], b: &mut [f64], axis: usize| {
        for h in 0..HUE_BINS {
            for s in 0..SAT_BINS {
                for v in 0..VAL_BINS {
                    let bin = [h, s, v];
                    let (mut before, mut after) = (bin, bin);
                    (before[axis], after[axis]) = match axis {
                        0 => ((h + HUE_BINS - 1) % HUE_BINS, (h + 1) % HUE_BINS),
                        1 => clamp_step(s, SAT_BINS),
                        _ => clamp_step(v, VAL_BINS),
                    };
                    b[index(bin)] =
                        0.5 * a[index(bin)] + 0.25 * (a[index(before)] + a[index(after)]);
                }
            }
        }
    };
    for _ in 0..hue {
        pass(&a, &mut b, 0);
        std::mem::swap(&mut a, &mut b);
    }
    for _ in 0..sat {
        pass(&a, &mut b, 1);
        std::mem::swap(&mut a, &mut b);
    }
    for _ in 0..val {
        pass(&a, &mut b, 2);
        for g in 0..GREY_BINS {
            let (gp, gn) = clamp_step(g, GREY_BINS);
            b[chromatic + g] =
                0.5 * a[chromatic + g] + 0.25 * (a[chromatic + gp] + a[chromatic + gn]);
        }
        std::mem::swap(&mut a, &mut b);
    }
    a
}

impl TableCounts {
    /// Adds one frame: its features, its mask at the features' size, and the previous two frames
    /// (value channel and mask of t−1, mask of t−2) when they exist. Pixels set in `unlabelled` (the
    /// person's parts outside the suit, which the cut does not look for) stay out of the colour
    /// table.
    pub fn add_frame(
        &mut self,
        features: &FrameFeatures,
        mask: &[bool],
        unlabelled: Option<&[bool]>,
        previous: Option<(&FrameFeatures, &[bool])>,
        before_previous: Option<&[bool]>,
    ) {
        let (w, h) = (features.width, features.height);
        for i in 0..w * h {
            let l = mask[i] as usize;
            self.labels[l] += 1.0;
            if !unlabelled.is_some_and(|u| u[i]) {
                self.colour[l][colour_index(features.colour[i], features.pattern[i])] += 1.0;
            }
            self.gradient[l][features.gradient[i] as usize] += 1.0;
        }
        // Neighbour pairs over the 3×3 neighbourhood (each unordered pair once, both orders counted).
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                for (dx, dy) in [(1isize, 0isize), (0, 1), (1, 1), (-1, 1)] {
                    let (nx, ny) = (x as isize + dx, y as isize + dy);
                    if nx < 0 || nx >= w as isize || ny >= h as isize {
                        continue;
                    }
                    let j = ny as usize * w + nx as usize;
                    let bin = contrast_bin(features.colour[i], features.colour[j]);
                    let (li, lj) = (mask[i] as usize, mask[j] as usize);
                    self.neighbourhood[2 * li + lj][bin] += 1.0;
                    self.neighbourhood[2 * lj + li][bin] += 1.0;
                }
            }
        }
        if let Some((prev, prev_mask)) = previous {
            for i in 0..w * h {
                let dt = super::features::temporal_difference(features.colour[i], prev.colour[i]);
                let bin = features.gradient_magnitude[i] as usize * TEMPORAL_BINS
                    + super::features::temporal_bin(dt);
                self.motion[2 * mask[i] as usize + prev_mask[i] as usize][bin] += 1.0;
                if let Some(prev2) = before_previous {
                    self.temporal
                        [4 * mask[i] as usize + 2 * prev_mask[i] as usize + prev2[i] as usize] +=
                        1.0;
                }
            }
        }
    }

    /// Adds the person's parts outside the suit of one frame: `person` is the whole person mask at the
    /// features' size, `suit` its suit part, `band` the non-suit pixels within the attachment band of
    /// the suit (see `cleanup::attach_parts`).
    pub fn add_parts(
        &mut self,
        features: &FrameFeatures,
        person: &[bool],
        suit: &[bool],
        band: &[bool],
    ) {
        for i in 0..features.colour.len() {
            if person[i] && !suit[i] {
                self.part[features.colour[i].bin as usize] += 1.0;
            }
            if band[i] {
                self.band[person[i] as usize] += 1.0;
            }
        }
    }

    /// The tables, with the given downscale factor, the rows of the grid they were counted on and
    /// the weights.
    pub fn finish(&self, downscale: u32, trained_rows: u32, weights: Weights) -> SegmenterTables {
        let total = self.labels[0] + self.labels[1];
        let prior = [0, 1]
            .map(|l| -(((self.labels[l] + 1.0) / (total + 2.0)).max(FLOOR as f64)).ln() as f32);
        let mut temporal = [0.0f32; 8];
        for history in 0..4 {
            let (bg, fg) = (self.temporal[history], self.temporal[4 + history]);
            let n = bg + fg + 2.0;
            temporal[history] = -(((bg + 1.0) / n).max(FLOOR as f64)).ln() as f32;
            temporal[4 + history] = -(((fg + 1.0) / n).max(FLOOR as f64)).ln() as f32;
        }
        SegmenterTables {
            downscale,
            trained_rows,
            colour: [0, 1].map(|l| {
                let smoothed: Vec<f64> = self.colour[l]
                    .chunks(COLOUR_BINS)
                    .flat_map(smooth_colour)
                    .collect();
                nll_mixed(&smoothed, 0.5, [BACKGROUND_UNIFORM, PERSON_UNIFORM][l])
            }),
            prior,
            neighbourhood: std::array::from_fn(|k| nll(&self.neighbourhood[k], 0.5)),
            pair_prior: self.pair_prior(),
            gradient: [0, 1].map(|l| nll_mixed(&self.gradient[l], 0.5, 0.3)),
            motion: std::array::from_fn(|k| nll(&self.motion[k], 0.5)),
            temporal,
            part: {
                let [h, s, v] = PART_SMOOTHING;
                nll_mixed(&smooth_colour_axes(&self.part, h, s, v), 0.5, PART_UNIFORM)
            },
            part_prior: {
                let n = self.band[0] + self.band[1] + 2.0;
                [0, 1].map(|l| -((self.band[l] + 1.0) / n).ln() as f32)
            },
            weights,
        }
    }
}

impl TableCounts {
    /// `−ln p(equal labels)`, `−ln p(different labels)` over neighbour pairs.
    fn pair_prior(&self) -> [f32; 2] {
        let sum = |k: usize| self.neighbourhood[k].iter().sum::<f64>();
        let (equal, different) = (sum(0) + sum(3) + 1.0, sum(1) + sum(2) + 1.0);
        let total = equal + different;
        [
            -(equal / total).ln() as f32,
            -(different / total).ln() as f32,
        ]
    }
}

impl SegmenterTables {
    /// The box-downscale factor of the cut for frames `frame_height` pixels high: the trained
    /// factor, or for taller frames the largest factor whose grid keeps [`CUT_ROWS_MARGIN`] times
    /// the trained rows (a person filling the same share of a 1440×1080 frame as of a 640×480 one
    /// trained at factor 2 is cut at factor 3, not on a grid 2.25 times the training's), at most 8.
    /// The tables' gradient and contrast statistics are those of the trained grid, so the cut's
    /// resolution need not grow with the frame's; the full-resolution refinement restores the edge.
    pub fn cut_factor(&self, frame_height: u32) -> u32 {
        let min_rows = CUT_ROWS_MARGIN * self.trained_rows.max(1) as f32;
        let factor = (frame_height as f32 / min_rows).floor() as u32;
        factor.clamp(self.downscale, 8)
    }

    pub fn to_model(&self) -> ModelFile {
        let mut m = ModelFile::new(SEGMENTER_KIND, SEGMENTER_VERSION);
        m.push("downscale", &[1], vec![self.downscale as f32]);
        m.push("trained_rows", &[1], vec![self.trained_rows as f32]);
        m.push("colour", &[2, COLOUR_TABLE], self.colour.concat());
        m.push("prior", &[2], self.prior.to_vec());
        m.push(
            "neighbourhood",
            &[4, CONTRAST_BINS],
            self.neighbourhood.concat(),
        );
        m.push(
            "gradient",
            &[2, GRADIENT_BINS * GRADIENT_BINS],
            self.gradient.concat(),
        );
        m.push(
            "motion",
            &[4, GRADIENT_BINS * TEMPORAL_BINS],
            self.motion.concat(),
        );
        m.push("temporal", &[8], self.temporal.to_vec());
        m.push("pair_prior", &[2], self.pair_prior.to_vec());
        m.push("part", &[COLOUR_BINS], self.part.clone());
        m.push("part_prior", &[2], self.part_prior.to_vec());
        m.push("weights", &[WEIGHTS], self.weights.to_array().to_vec());
        m
    }

    /// Writes `DIR/segmenter.bin`.
    pub fn save(&self, suit_dir: &Path) -> Result<(), ModelError> {
        self.to_model().write(&suit_dir.join(SEGMENTER_FILE))
    }

    /// Reads `DIR/segmenter.bin`, checking every table's shape.
    pub fn load(suit_dir: &Path) -> Result<SegmenterTables, ModelError> {
        let path = suit_dir.join(SEGMENTER_FILE);
        let m = ModelFile::read(&path, SEGMENTER_KIND, SEGMENTER_VERSION)?;
        let split = |name: &str, rows: usize, cols: usize| -> Result<Vec<Vec<f32>>, ModelError> {
            Ok(m.array(&path, name, &[rows, cols])?
                .chunks(cols)
                .map(<[f32]>::to_vec)
                .collect())
        };
        // A single whole number in 1..=max.
        let whole = |name: &str, max: u32| -> Result<u32, ModelError> {
            let v = m.array(&path, name, &[1])?[0];
            if !(1.0..=max as f32).contains(&v) || v.fract() != 0.0 {
                return Err(ModelError::Array {
                    path: path.clone(),
                    name: name.into(),
                    message: format!("{v} is not an integer in 1..={max}"),
                });
            }
            Ok(v as u32)
        };
        let downscale = whole("downscale", 8)?;
        let trained_rows = whole("trained_rows", 65_535)?;
        let two = |v: Vec<Vec<f32>>| -> [Vec<f32>; 2] {
            let mut it = v.into_iter();
            [it.next().unwrap_or_default(), it.next().unwrap_or_default()]
        };
        let four = |v: Vec<Vec<f32>>| -> [Vec<f32>; 4] {
            let mut it = v.into_iter();
            std::array::from_fn(|_| it.next().unwrap_or_default())
        };
        let mut prior = [0.0; 2];
        prior.copy_from_slice(m.array(&path, "prior", &[2])?);
        let mut temporal = [0.0; 8];
        temporal.copy_from_slice(m.array(&path, "temporal", &[8])?);
        let mut weights = [0.0; WEIGHTS];
        weights.copy_from_slice(m.array(&path, "weights", &[WEIGHTS])?);
        let mut pair_prior = [0.0; 2];
        pair_prior.copy_from_slice(m.array(&path, "pair_prior", &[2])?);
        let mut part_prior = [0.0; 2];
        part_prior.copy_from_slice(m.array(&path, "part_prior", &[2])?);
        let part = m.array(&path, "part", &[COLOUR_BINS])?.to_vec();
        Ok(SegmenterTables {
            downscale,
            trained_rows,
            colour: two(split("colour", 2, COLOUR_TABLE)?),
            prior,
            neighbourhood: four(split("neighbourhood", 4, CONTRAST_BINS)?),
            pair_prior,
            gradient: two(split("gradient", 2, GRADIENT_BINS * GRADIENT_BINS)?),
            motion: four(split("motion", 4, GRADIENT_BINS * TEMPORAL_BINS)?),
            temporal,
            part,
            part_prior,
            weights: Weights::from_array(weights),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::segment::features::{ColourLut, FrameFeatures, MarkerGate};

    /// A 4×4 frame: a green 2×2 person in the middle of a grey background.
    fn fixture() -> (FrameFeatures, Vec<bool>) {
        let lut = ColourLut::new();
        let mut rgb = vec![[128u8, 128, 128]; 16];
        let mut mask = vec![false; 16];
        for i in [5, 6, 9, 10] {
            rgb[i] = [120, 180, 60];
            mask[i] = true;
        }
        let mut f = FrameFeatures::default();
        let suit = crate::suit::SuitDefinition::load_dir(
            &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("suits/default"),
        )
        .expect("suit");
        f.compute(&rgb, 4, 4, &lut, &MarkerGate::new(&suit));
        (f, mask)
    }

    #[test]
    fn counts_of_a_4x4_fixture() {
        let (f, mask) = fixture();
        let mut counts = TableCounts::default();
        counts.add_frame(&f, &mask, None, None, None);
        assert_eq!(counts.labels, [12.0, 4.0]);
        // 4-connected and diagonal pairs: 12 + 12 + 9 + 9 = 42 unordered, 84 ordered.
        let total: f64 = counts.neighbourhood.iter().flat_map(|v| v.iter()).sum();
        assert_eq!(total, 84.0);
        // FG→FG pairs inside the 2×2 square: 4 axial + 2 diagonal = 6 unordered.
        assert_eq!(counts.neighbourhood[3].iter().sum::<f64>(), 12.0);
        let tables = counts.finish(1, 4, Weights::default());
        let green = colour_index(f.colour[5], f.pattern[5]);
        let grey = colour_index(f.colour[0], f.pattern[0]);
        assert!(tables.colour[1][green] < tables.colour[0][green]);
        assert!(tables.colour[0][grey] < tables.colour[1][grey]);
    }

    #[test]
    fn tables_survive_a_save_load_round_trip() {
        let (f, mask) = fixture();
        let mut counts = TableCounts::default();
        counts.add_frame(&f, &mask, None, Some((&f, &mask)), Some(&mask));
        let tables = counts.finish(
            2,
            2,
            Weights {
                colour: 1.5,
                ..Weights::default()
            },
        );
        let dir = tempfile::tempdir().expect("tempdir");
        tables.save(dir.path()).expect("save");
        assert_eq!(SegmenterTables::load(dir.path()).expect("load"), tables);
        // A truncated file is a clear error naming it.
        let path = dir.path().join(SEGMENTER_FILE);
        let bytes = std::fs::read(&path).expect("read");
        std::fs::write(&path, &bytes[..bytes.len() / 2]).expect("write");
        let err = SegmenterTables::load(dir.path()).unwrap_err().to_string();
        assert!(err.contains("segmenter.bin"), "{err}");
    }

    #[test]
    fn taller_frames_are_cut_on_a_grid_near_the_trained_one() {
        let (f, mask) = fixture();
        let mut counts = TableCounts::default();
        counts.add_frame(&f, &mask, None, None, None);
        // Counted at 240 rows (640×480 frames at factor 2): a cut of at least 360 rows.
        let tables = counts.finish(2, 240, Weights::default());
        let factors =
            [120, 480, 719, 720, 1079, 1080, 1440, 2160, 4320].map(|h| tables.cut_factor(h));
        assert_eq!(factors, [2, 2, 2, 2, 2, 3, 4, 6, 8]);
        // Tables counted at full resolution keep factor 1 up to 1.5 times their rows.
        let full = counts.finish(1, 480, Weights::default());
        assert_eq!([480, 720, 1080].map(|h| full.cut_factor(h)), [1, 1, 1]);
    }
}
