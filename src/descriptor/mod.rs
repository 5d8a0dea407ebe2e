//! The frame descriptor: what the pose regressor reads (source paper sec. 3.1.2–3.1.4).
//!
//! From a frame and the person's mask: [`markers`] finds the suit's markers, [`feature_context`]
//! describes each marker's neighbourhood and the FC codebook quantises them (200 values); [`hog`]
//! histograms gradient orientations in a 16 × 16 grid over the silhouette's box and the HOG codebook
//! quantises the blocks (100 values); the box's position and size relative to the frame add 4 values:
//! 304 in all. [`silhouette`] is the baseline of Agarwal & Triggs (shape contexts along the outer
//! contour, 100-centre codebook) that the paper measures itself against. [`codebook`] holds the k-means
//! codebooks. A frame with nobody in it gives an all-zero descriptor flagged "no person".

pub mod codebook;
pub mod feature_context;
pub mod hog;
pub mod markers;
pub mod silhouette;

use std::path::Path;

use image::RgbImage;

use crate::mask::Mask;
use crate::model::ModelError;
use crate::suit::SuitDefinition;
use codebook::{codebook_path, Codebook, CODEBOOK_VERSION};
use feature_context::{feature_contexts, FC_LEN};
use markers::{DetectedMarker, MarkerDetector};

/// Codebook sizes.
pub const FC_CENTRES: usize = 200;
pub const HOG_CENTRES: usize = 100;
pub const SILHOUETTE_CENTRES: usize = 100;
/// Weight of the silhouette box's four values (shares of the frame's width and height) in the full
/// descriptor. The RVM's Gaussian kernel reads the Euclidean distance between two descriptors, and
/// unweighted the box set most of it (median distance between training descriptors 0.23, against
/// 0.12 for FC alone and 0.08 for HOG alone): where the person stood in the frame counted for more
/// than their pose. Weighted by ½ and by ¼, the error on the held-back training motions fell from
/// 7.39° to 7.17° and 7.11° (docs/measurements.md, fourth session of 2026-12-04); a regressor
/// trained with another weight reads other descriptors, hence regressor version 3 (see
/// [`crate::pose::regressor::REGRESSOR_VERSION`]).
pub const BOX_WEIGHT: f32 = 0.25;
/// Model kinds (and file stems) of the codebooks in a suit directory.
pub const FC_CODEBOOK: &str = "codebook_fc";
pub const HOG_CODEBOOK: &str = "codebook_hog";
pub const SILHOUETTE_CODEBOOK: &str = "codebook_silhouette";
/// Version of the HOG codebook file: 2 since its block histograms count the person's gradients only
/// ([`hog::person_block_histograms`]); a suit trained before must be retrained.
pub const HOG_CODEBOOK_VERSION: u32 = 2;

/// Which descriptor to compute, for the experiments of the paper.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DescriptorKind {
    /// Feature Context only (200).
    Fc,
    /// HOG only (100).
    Hog,
    /// FC + HOG (300).
    FcHog,
    /// FC + HOG + silhouette box (304): the paper's descriptor.
    Full,
    /// The Agarwal & Triggs silhouette shape-context descriptor (100).
    Silhouette,
}

impl DescriptorKind {
    /// Every kind.
    pub const ALL: [DescriptorKind; 5] = [
        DescriptorKind::Fc,
        DescriptorKind::Hog,
        DescriptorKind::FcHog,
        DescriptorKind::Full,
        DescriptorKind::Silhouette,
    ];

    pub fn len(self) -> usize {
        match self {
            DescriptorKind::Fc => FC_CENTRES,
            DescriptorKind::Hog => HOG_CENTRES,
            DescriptorKind::FcHog => FC_CENTRES + HOG_CENTRES,
            DescriptorKind::Full => FC_CENTRES + HOG_CENTRES + 4,
            DescriptorKind::Silhouette => SILHOUETTE_CENTRES,
        }
    }

    pub fn is_empty(self) -> bool {
        false
    }

    /// Parses `fc`, `hog`, `fc+hog`, `full` (= `fc+hog+box`) or `silhouette`.
    pub fn parse(text: &str) -> Option<DescriptorKind> {
        match text.to_ascii_lowercase().as_str() {
            "fc" => Some(DescriptorKind::Fc),
            "hog" => Some(DescriptorKind::Hog),
            "fc+hog" => Some(DescriptorKind::FcHog),
            "full" | "fc+hog+box" => Some(DescriptorKind::Full),
            "silhouette" => Some(DescriptorKind::Silhouette),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            DescriptorKind::Fc => "fc",
            DescriptorKind::Hog => "hog",
            DescriptorKind::FcHog => "fc+hog",
            DescriptorKind::Full => "fc+hog+box",
            DescriptorKind::Silhouette => "silhouette",
        }
    }
}

/// One frame's descriptor.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameDescriptor {
    pub kind: DescriptorKind,
    pub values: Vec<f32>,
    /// False when the mask was empty: `values` are then all zero.
    pub person: bool,
}

/// The three codebooks of a suit.
#[derive(Clone, Debug, PartialEq)]
pub struct Codebooks {
    pub fc: Codebook,
    pub hog: Codebook,
    pub silhouette: Codebook,
}

impl Codebooks {
    /// Reads the codebooks from a suit directory; errors name the missing or bad file.
    pub fn load(suit_dir: &Path) -> Result<Codebooks, ModelError> {
        Ok(Codebooks {
            fc: Codebook::load(
                &codebook_path(suit_dir, FC_CODEBOOK),
                FC_CODEBOOK,
                CODEBOOK_VERSION,
                FC_CENTRES,
                FC_LEN,
            )?,
            hog: Codebook::load(
                &codebook_path(suit_dir, HOG_CODEBOOK),
                HOG_CODEBOOK,
                HOG_CODEBOOK_VERSION,
                HOG_CENTRES,
                hog::HOG_BINS,
            )?,
            silhouette: Codebook::load(
                &codebook_path(suit_dir, SILHOUETTE_CODEBOOK),
                SILHOUETTE_CODEBOOK,
                CODEBOOK_VERSION,
                SILHOUETTE_CENTRES,
                silhouette::SC_RADIAL * silhouette::SC_ANGULAR,
            )?,
        })
    }

    pub fn save(&self, suit_dir: &Path) -> Result<(), ModelError> {
        self.fc.save(
            &codebook_path(suit_dir, FC_CODEBOOK),
            FC_CODEBOOK,
            CODEBOOK_VERSION,
        )?;
        self.hog.save(
            &codebook_path(suit_dir, HOG_CODEBOOK),
            HOG_CODEBOOK,
            HOG_CODEBOOK_VERSION,
        )?;
        self.silhouette.save(
            &codebook_path(suit_dir, SILHOUETTE_CODEBOOK),
            SILHOUETTE_CODEBOOK,
            CODEBOOK_VERSION,
        )
    }
}

/// The local histograms of one frame, before quantisation (also what codebook training collects).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LocalHistograms {
    pub markers: Vec<DetectedMarker>,
    /// `markers.len() × FC_LEN`.
    pub feature_contexts: Vec<f32>,
    /// Non-empty HOG blocks, `blocks × HOG_BINS`.
    pub hog_blocks: Vec<f32>,
    /// Contour shape contexts, `points × 60`.
    pub shape_contexts: Vec<f32>,
    /// Silhouette box (x0, y0, x1, y1), if there is a person.
    pub bbox: Option<(u32, u32, u32, u32)>,
}

/// Computes local histograms and descriptors for a suit.
pub struct Describer {
    detector: MarkerDetector,
}

impl Describer {
    pub fn new(suit: &SuitDefinition) -> Describer {
        Describer {
            detector: MarkerDetector::new(suit),
        }
    }

    /// The local histograms a descriptor of `kind` needs (all of them when `kind` is `None`).
    pub fn local_histograms(
        &mut self,
        frame: &RgbImage,
        mask: &Mask,
        kind: Option<DescriptorKind>,
    ) -> LocalHistograms {
        let Some(bbox) = mask.bounding_box() else {
            return LocalHistograms::default();
        };
        let height = (bbox.3 - bbox.1) as f32;
        let wants = |k: &[DescriptorKind]| kind.is_none_or(|kind| k.contains(&kind));
        use DescriptorKind::*;
        let markers = if wants(&[Fc, FcHog, Full]) {
            self.detector.detect(frame, mask)
        } else {
            Vec::new()
        };
        let feature_contexts = feature_contexts(&markers, height);
        let hog_blocks = if wants(&[Hog, FcHog, Full]) {
            let blocks = hog::person_block_histograms(frame, mask, bbox);
            blocks
                .values
                .chunks_exact(blocks.bins)
                .filter(|b| b.iter().any(|&v| v != 0.0))
                .flatten()
                .copied()
                .collect()
        } else {
            Vec::new()
        };
        let shape_contexts = if wants(&[Silhouette]) {
            silhouette::silhouette_shape_contexts(mask)
                .into_iter()
                .flatten()
                .collect()
        } else {
            Vec::new()
        };
        LocalHistograms {
            markers,
            feature_contexts,
            hog_blocks,
            shape_contexts,
            bbox: Some(bbox),
        }
    }

    /// The descriptor of `kind` for one frame, and the markers found.
    pub fn describe(
        &mut self,
        frame: &RgbImage,
        mask: &Mask,
        kind: DescriptorKind,
        codebooks: &Codebooks,
    ) -> (FrameDescriptor, Vec<DetectedMarker>) {
        let local = self.local_histograms(frame, mask, Some(kind));
        let descriptor = quantise(&local, kind, codebooks, frame.dimensions());
        (descriptor, local.markers)
    }
}

/// Quantises local histograms into the descriptor of `kind` for a frame of `size`.
pub fn quantise(
    local: &LocalHistograms,
    kind: DescriptorKind,
    codebooks: &Codebooks,
    size: (u32, u32),
) -> FrameDescriptor {
    let mut values = vec![0.0f32; kind.len()];
    let Some((x0, y0, x1, y1)) = local.bbox else {
        return FrameDescriptor {
            kind,
            values,
            person: false,
        };
    };
    use DescriptorKind::*;
    match kind {
        Fc => codebooks.fc.quantise(&local.feature_contexts, &mut values),
        Hog => codebooks.hog.quantise(&local.hog_blocks, &mut values),
        FcHog | Full => {
            let (fc, rest) = values.split_at_mut(FC_CENTRES);
            codebooks.fc.quantise(&local.feature_contexts, fc);
            codebooks
                .hog
                .quantise(&local.hog_blocks, &mut rest[..HOG_CENTRES]);
            if kind == Full {
                let (w, h) = (size.0 as f32, size.1 as f32);
                rest[HOG_CENTRES..].copy_from_slice(&[
                    BOX_WEIGHT * x0 as f32 / w,
                    BOX_WEIGHT * y0 as f32 / h,
                    BOX_WEIGHT * (x1 - x0) as f32 / w,
                    BOX_WEIGHT * (y1 - y0) as f32 / h,
                ]);
            }
        }
        Silhouette => codebooks
            .silhouette
            .quantise(&local.shape_contexts, &mut values),
    }
    FrameDescriptor {
        kind,
        values,
        person: true,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::suit::shipped_default as suit;

    fn codebooks() -> Codebooks {
        let book = |k: usize, dim: usize| {
            let centres = (0..k * dim)
                .map(|i| ((i * 7919) % 101) as f32 / 101.0 / dim as f32)
                .collect();
            Codebook::from_centres(dim, centres).expect("valid")
        };
        Codebooks {
            fc: book(FC_CENTRES, FC_LEN),
            hog: book(HOG_CENTRES, hog::HOG_BINS),
            silhouette: book(
                SILHOUETTE_CENTRES,
                silhouette::SC_RADIAL * silhouette::SC_ANGULAR,
            ),
        }
    }

    /// A green 40 × 120 person with a 4 × 4 marker every 7 pixels, cycling through the three colours.
    fn person() -> (RgbImage, Mask) {
        let (w, h) = (100u32, 160u32);
        let mut frame = RgbImage::from_pixel(w, h, image::Rgb([80, 80, 90]));
        let mut mask = vec![false; (w * h) as usize];
        let colours = [[204, 31, 31], [38, 191, 191], [100, 55, 158]];
        for y in 20..140 {
            for x in 30..70 {
                mask[(y * w + x) as usize] = true;
                let (cx, cy) = ((x - 30) % 7, (y - 20) % 7);
                let k = (((x - 30) / 7 + (y - 20) / 7) % 3) as usize;
                let rgb = if (1..5).contains(&cx) && (1..5).contains(&cy) {
                    colours[k]
                } else {
                    [123, 184, 64]
                };
                frame.put_pixel(x, y, image::Rgb(rgb));
            }
        }
        (frame, Mask::from_pixels(w, h, mask).expect("size"))
    }

    #[test]
    fn an_empty_mask_gives_a_zero_descriptor_flagged_no_person() {
        let (frame, _) = person();
        let mut describer = Describer::new(&suit());
        for kind in DescriptorKind::ALL {
            let (d, markers) =
                describer.describe(&frame, &Mask::empty(100, 160), kind, &codebooks());
            assert!(!d.person);
            assert_eq!(d.values.len(), kind.len());
            assert!(d.values.iter().all(|&v| v == 0.0));
            assert!(markers.is_empty());
        }
    }

    #[test]
    fn the_full_descriptor_has_304_values_each_block_summing_to_one() {
        let (frame, mask) = person();
        let mut describer = Describer::new(&suit());
        let (d, markers) = describer.describe(&frame, &mask, DescriptorKind::Full, &codebooks());
        assert!(d.person);
        assert_eq!(d.values.len(), 304);
        assert!(markers.len() > 50, "{} markers", markers.len());
        assert!(d.values.iter().all(|v| v.is_finite() && *v >= 0.0));
        let fc: f32 = d.values[..200].iter().sum();
        let hog: f32 = d.values[200..300].iter().sum();
        assert!(
            (fc - 1.0).abs() < 1e-4 && (hog - 1.0).abs() < 1e-4,
            "{fc} {hog}"
        );
        // The box: x0 = 30/100, y0 = 20/160, width 40/100, height 120/160, each × BOX_WEIGHT.
        let expected = [0.3f32, 0.125, 0.4, 0.75].map(|v| BOX_WEIGHT * v);
        assert_eq!(&d.values[300..], &expected);
        let (s, _) = describer.describe(&frame, &mask, DescriptorKind::Silhouette, &codebooks());
        assert!((s.values.iter().sum::<f32>() - 1.0).abs() < 1e-4);
    }

    #[test]
    fn kinds_parse_by_name() {
        for kind in DescriptorKind::ALL {
            assert_eq!(DescriptorKind::parse(kind.name()), Some(kind));
        }
        assert_eq!(DescriptorKind::parse("full"), Some(DescriptorKind::Full));
        assert_eq!(DescriptorKind::parse("sift"), None);
    }
}
