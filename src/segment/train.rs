//! Learning the segmenter from consecutive frames with masks (`suitcap-train segment`).
//!
//! The tables are counted on the first frames; the last `held_back` frames are kept aside to choose the
//! weights σ_C, σ_N, σ_G, σ_M, σ_T, σ_P: starting from all ones, a coordinate search tries each weight at
//! ×¼, ×½, ×2 and ×4 of its current value and keeps a change when the mean IoU of the segmenter run on the
//! held-back frames (with its own history, warmed up on the two frames before them) goes up; two passes.
//! The held-back frames are scored as recorded and with their background (outside the mask) turned
//! by 90°, 180° and 270° of hue: the suit will be used in rooms the 20 frames never showed, so the
//! weights must not lean on the training room's colours (a turned background holds the cloth's and
//! the markers' hues where the room had none). The final tables are counted on all frames with the
//! chosen weights.

use image::RgbImage;

use super::cleanup::{part_band, PART_REACH};
use super::features::{downscale, suit_support, ColourLut, FrameFeatures, MarkerGate};
use super::segmenter::{Segmenter, SegmenterOptions};
use super::tables::{SegmenterTables, TableCounts, Weights, WEIGHTS};
use crate::mask::Mask;
use crate::suit::SuitDefinition;

/// One training frame: the picture and its person mask, consecutive with the next.
#[derive(Clone, Debug)]
pub struct TrainingFrame {
    pub image: RgbImage,
    pub mask: Mask,
}

/// How training went.
#[derive(Clone, Debug, PartialEq)]
pub struct TrainReport {
    pub frames: usize,
    pub held_back: usize,
    /// Mean IoU on the held-back frames (as recorded and with turned background hues) with all
    /// weights 1 and with the chosen weights.
    pub default_iou: f64,
    pub chosen_iou: f64,
    pub weights: Weights,
    /// Segmenter runs the search made.
    pub evaluations: usize,
}

/// Why training cannot run.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum TrainError {
    #[error("need at least {needed} frames ({held_back} held back for the weights + 3 to count), got {got}")]
    TooFewFrames {
        needed: usize,
        held_back: usize,
        got: usize,
    },
    #[error("frame {index}: image is {image:?} but its mask is {mask:?}")]
    SizeMismatch {
        index: usize,
        image: (u32, u32),
        mask: (u32, u32),
    },
    #[error("downscale factor {0} is not in 1..=8")]
    BadDownscale(u32),
}

/// The mask at the cut's resolution: a block is person when at least half its pixels are.
pub fn downscale_mask(mask: &Mask, factor: u32) -> (Vec<bool>, usize, usize) {
    let f = factor.max(1) as usize;
    let (w, h) = (mask.width() as usize / f, mask.height() as usize / f);
    let src = mask.pixels();
    let stride = mask.width() as usize;
    let mut out = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            let count: usize = (0..f)
                .map(|dy| {
                    (0..f)
                        .filter(|&dx| src[(y * f + dy) * stride + x * f + dx])
                        .count()
                })
                .sum();
            out.push(2 * count >= f * f);
        }
    }
    (out, w, h)
}

/// The suit part of a person mask at the features' size: person pixels within
/// [`SUIT_RADIUS`](super::features::SUIT_RADIUS) of a person pixel of the cloth's or a marker's
/// colour in the suit's pattern (see [`suit_support`]).
pub fn suit_pixels(
    features: &FrameFeatures,
    person: &[bool],
    gate: &MarkerGate,
    distance: &mut Vec<u16>,
) -> Vec<bool> {
    let mut support = Vec::new();
    suit_support(features, gate, Some(person), distance, &mut support);
    person.iter().zip(&support).map(|(&p, &s)| p && s).collect()
}

/// Counts the tables: the cut's tables on the suit part of the masks (the cut finds the suit), the
/// part table and band prior on the rest of the person.
fn count(frames: &[TrainingFrame], factor: u32, lut: &ColourLut, gate: &MarkerGate) -> TableCounts {
    let mut counts = TableCounts::default();
    let (mut distance, mut band) = (Vec::new(), Vec::new());
    let mut history: Vec<(FrameFeatures, Vec<bool>)> = Vec::new();
    let mut small = Vec::new();
    for frame in frames {
        let (w, h) = downscale(&frame.image, factor, &mut small);
        let mut features = FrameFeatures::default();
        features.compute(&small, w, h, lut, gate);
        let (person, _, _) = downscale_mask(&frame.mask, factor);
        let mask = suit_pixels(&features, &person, gate, &mut distance);
        part_band(&mask, w, h, PART_REACH, &mut distance, &mut band);
        counts.add_parts(&features, &person, &mask, &band);
        let parts: Vec<bool> = person.iter().zip(&mask).map(|(&p, &s)| p && !s).collect();
        let previous = history.last().map(|(f, m)| (f, m.as_slice()));
        let before = if history.len() >= 2 {
            Some(history[history.len() - 2].1.as_slice())
        } else {
            None
        };
        counts.add_frame(&features, &mask, Some(&parts), previous, before);
        history.push((features, mask));
        if history.len() > 2 {
            history.remove(0);
        }
    }
    counts
}

/// The frame with the hue of every background pixel turned by `degrees`.
pub fn turn_background_hue(frame: &TrainingFrame, degrees: f32) -> TrainingFrame {
    let mut image = frame.image.clone();
    for (pixel, &person) in image.pixels_mut().zip(frame.mask.pixels()) {
        if !person {
            let mut hsv = crate::colour::Hsv::from_rgb(pixel.0.map(|c| c as f32 / 255.0));
            hsv.hue = (hsv.hue + degrees).rem_euclid(360.0);
            pixel.0 = hsv
                .to_rgb()
                .map(|c| (c * 255.0).round().clamp(0.0, 255.0) as u8);
        }
    }
    TrainingFrame {
        image,
        mask: frame.mask.clone(),
    }
}

/// Mean IoU of a segmenter with `tables` over `frames[start..]`, warmed up on the two frames before.
pub fn held_back_iou(
    tables: &SegmenterTables,
    suit: &SuitDefinition,
    frames: &[TrainingFrame],
    start: usize,
) -> f64 {
    let mut segmenter = Segmenter::new(tables.clone(), suit, SegmenterOptions::default());
    for frame in &frames[start.saturating_sub(2)..start] {
        segmenter.segment(&frame.image);
    }
    let scored = &frames[start..];
    let total: f64 = scored
        .iter()
        .map(|f| segmenter.segment(&f.image).mask.iou(&f.mask))
        .sum();
    total / scored.len().max(1) as f64
}

/// Learns the tables and weights from consecutive `frames`.
pub fn train_segmenter(
    frames: &[TrainingFrame],
    suit: &SuitDefinition,
    factor: u32,
    held_back: usize,
) -> Result<(SegmenterTables, TrainReport), TrainError> {
    if !(1..=8).contains(&factor) {
        return Err(TrainError::BadDownscale(factor));
    }
    if frames.len() < held_back + 3 {
        return Err(TrainError::TooFewFrames {
            needed: held_back + 3,
            held_back,
            got: frames.len(),
        });
    }
    for (index, f) in frames.iter().enumerate() {
        if f.image.dimensions() != (f.mask.width(), f.mask.height()) {
            return Err(TrainError::SizeMismatch {
                index,
                image: f.image.dimensions(),
                mask: (f.mask.width(), f.mask.height()),
            });
        }
    }
    let lut = ColourLut::new();
    let gate = MarkerGate::new(suit);
    // The grid the tables are counted on (`downscale` rounds a frame's height down the same way).
    let trained_rows = frames[0].image.height() / factor;
    let split = frames.len() - held_back;
    let counts = count(&frames[..split], factor, &lut, &gate);
    let warm_up = split.saturating_sub(2);
    let variants: Vec<Vec<TrainingFrame>> = [0.0f32, 90.0, 180.0, 270.0]
        .iter()
        .map(|&turn| {
            frames[warm_up..]
                .iter()
                .map(|f| {
                    if turn == 0.0 {
                        f.clone()
                    } else {
                        turn_background_hue(f, turn)
                    }
                })
                .collect()
        })
        .collect();
    let mut evaluations = 0;
    let mut evaluate = |weights: Weights| {
        evaluations += 1;
        if held_back == 0 {
            return 0.0;
        }
        let tables = counts.finish(factor, trained_rows, weights);
        let start = split - warm_up;
        variants
            .iter()
            .map(|v| held_back_iou(&tables, suit, v, start))
            .sum::<f64>()
            / variants.len() as f64
    };
    let mut weights = Weights::default();
    let default_iou = evaluate(weights);
    let mut best = default_iou;
    if held_back > 0 {
        for _pass in 0..2 {
            for k in 0..WEIGHTS {
                let base = weights.to_array();
                for factor_k in [0.25f32, 0.5, 2.0, 4.0] {
                    let mut trial = base;
                    trial[k] = base[k] * factor_k;
                    let iou = evaluate(Weights::from_array(trial));
                    if iou > best + 1e-4 {
                        best = iou;
                        weights = Weights::from_array(trial);
                    }
                }
            }
        }
    }
    let tables = count(frames, factor, &lut, &gate).finish(factor, trained_rows, weights);
    let report = TrainReport {
        frames: frames.len(),
        held_back,
        default_iou,
        chosen_iou: best,
        weights,
        evaluations,
    };
    Ok((tables, report))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn downscaled_mask_takes_the_majority_of_each_block() {
        // 4×2 mask, factor 2: left block 2 of 4 set → person; right block 1 of 4 → background.
        let m = Mask::from_pixels(
            4,
            2,
            vec![true, true, false, true, false, false, false, false],
        )
        .expect("size");
        assert_eq!(downscale_mask(&m, 2), (vec![true, false], 2, 1));
    }

    /// Frames of a green square with red and cyan marker dots moving over a textured, partly green background.
    fn synthetic_frames(n: usize) -> Vec<TrainingFrame> {
        (0..n)
            .map(|t| {
                let (w, h) = (64u32, 48u32);
                let mut image = RgbImage::new(w, h);
                let mut mask = vec![false; (w * h) as usize];
                for y in 0..h {
                    for x in 0..w {
                        let bg = if (x / 8 + y / 8) % 2 == 0 {
                            [90, 90, 200]
                        } else {
                            [200, 190, 170]
                        };
                        let inside =
                            x >= 20 + t as u32 && x < 40 + t as u32 && (10..40).contains(&y);
                        let px = if inside {
                            mask[(y * w + x) as usize] = true;
                            if x % 7 < 3 && y % 7 < 3 {
                                // Red and cyan dots: the suit's mix of marker hues.
                                if (x / 7 + y / 7) % 2 == 0 {
                                    [200, 30, 30]
                                } else {
                                    [38, 191, 191]
                                }
                            } else {
                                [120, 180, 60]
                            }
                        } else {
                            bg
                        };
                        image.put_pixel(x, y, image::Rgb(px));
                    }
                }
                TrainingFrame {
                    image,
                    mask: Mask::from_pixels(w, h, mask).expect("size"),
                }
            })
            .collect()
    }

    fn suit() -> SuitDefinition {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("suits/default");
        SuitDefinition::load_dir(&dir).expect("suit")
    }

    #[test]
    fn learns_a_person_that_moves_over_a_checkerboard() {
        let frames = synthetic_frames(12);
        let (tables, report) = train_segmenter(&frames[..10], &suit(), 1, 4).expect("trains");
        assert!(report.chosen_iou >= report.default_iou);
        assert!(report.chosen_iou > 0.95, "{report:?}");
        let mut seg = Segmenter::new(tables, &suit(), SegmenterOptions::default());
        for f in &frames[10..] {
            let out = seg.segment(&f.image);
            assert!(
                out.mask.iou(&f.mask) > 0.95,
                "iou {}",
                out.mask.iou(&f.mask)
            );
        }
        // Nobody in the frame: an empty mask.
        let empty = RgbImage::from_pixel(64, 48, image::Rgb([90, 90, 200]));
        seg.reset();
        assert!(seg.segment(&empty).mask.is_empty());
    }

    #[test]
    fn the_flow_is_the_cost_of_the_cut_it_returns() {
        let frames = synthetic_frames(6);
        let (tables, _) = train_segmenter(&frames, &suit(), 2, 0).expect("trains");
        let mut seg = Segmenter::new(tables, &suit(), SegmenterOptions::default());
        seg.build_graph(&frames[3].image);
        let graph = seg.graph().clone();
        let result = super::super::maxflow::GridMaxFlow::new().solve(&graph);
        let cost = graph.cut_cost(&result.labels);
        assert!(
            (cost - result.flow).abs() <= 1e-4 * cost.max(1.0),
            "{cost} vs {}",
            result.flow
        );
    }

    #[test]
    fn too_few_frames_or_mismatched_masks_are_errors() {
        let frames = synthetic_frames(4);
        assert!(matches!(
            train_segmenter(&frames, &suit(), 2, 4),
            Err(TrainError::TooFewFrames { .. })
        ));
        let mut bad = synthetic_frames(5);
        bad[2].mask = Mask::empty(10, 10);
        assert!(matches!(
            train_segmenter(&bad, &suit(), 2, 0),
            Err(TrainError::SizeMismatch { index: 2, .. })
        ));
    }
}
