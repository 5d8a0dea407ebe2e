//! The trained pose regressor of a suit: the RVM, which descriptor it reads, and the skeleton it
//! writes.
//!
//! Stored in the suit directory as `regressor.bin` (the relevance vectors, the weight matrix, the
//! kernel width, the noise estimate, the descriptor kind and the pose vector's rotation encoding)
//! and `skeleton.bvh` (the training mocap's hierarchy with one template frame whose values fill the
//! joints the suit does not estimate). The runtime loads both, predicts a pose vector per frame and
//! decodes it into a BVH frame.

use std::path::{Path, PathBuf};

use super::exemplars::{Exemplars, ExemplarsError, EXEMPLARS_FILE};
use super::rvm::Rvm;
use super::{LayoutError, PoseLayout, RotationEncoding};
use crate::bvh::{BvhError, Motion};
use crate::descriptor::DescriptorKind;
use crate::model::{ModelError, ModelFile};
use crate::suit::SuitDefinition;

pub const REGRESSOR_KIND: &str = "regressor";
/// Version 2: the pose vector's depth is in metres (`pose::DEPTH_SCALE`). Version 3: the full
/// descriptor's box values are weighted by [`crate::descriptor::BOX_WEIGHT`]. Version 4: the
/// rotation encoding of the pose vector is stored ([`RotationEncoding`]).
pub const REGRESSOR_VERSION: u32 = 4;
pub const REGRESSOR_FILE: &str = "regressor.bin";
pub const SKELETON_FILE: &str = "skeleton.bvh";

/// A loaded regressor.
#[derive(Clone, Debug)]
pub struct Regressor {
    pub rvm: Rvm,
    pub descriptor: DescriptorKind,
    /// The hierarchy written to BVH, with the template frame.
    pub skeleton: Motion,
    pub layout: PoseLayout,
    /// Training frames whose nearest ones pull the RVM's estimate towards poses seen with such
    /// a picture ([`Exemplars`]); `None` for a suit trained before them.
    pub exemplars: Option<Exemplars>,
}

/// A regressor that cannot be loaded.
#[derive(Debug, thiserror::Error)]
pub enum RegressorError {
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error(transparent)]
    Bvh(#[from] BvhError),
    #[error("{path}: {source}")]
    Layout { path: PathBuf, source: LayoutError },
    #[error("{path}: {message}")]
    Mismatch { path: PathBuf, message: String },
    #[error(transparent)]
    Exemplars(#[from] ExemplarsError),
}

fn kind_code(kind: DescriptorKind) -> f32 {
    match kind {
        DescriptorKind::Fc => 0.0,
        DescriptorKind::Hog => 1.0,
        DescriptorKind::FcHog => 2.0,
        DescriptorKind::Full => 3.0,
        DescriptorKind::Silhouette => 4.0,
    }
}

fn kind_from_code(code: f32) -> Option<DescriptorKind> {
    DescriptorKind::ALL
        .into_iter()
        .find(|&k| kind_code(k) == code)
}

impl Regressor {
    /// Writes `regressor.bin` and `skeleton.bvh` into `suit_dir`.
    pub fn save(&self, suit_dir: &Path) -> Result<(), RegressorError> {
        let r = &self.rvm;
        let mut m = ModelFile::new(REGRESSOR_KIND, REGRESSOR_VERSION);
        m.push("descriptor", &[1], vec![kind_code(self.descriptor)]);
        m.push("rotations", &[1], vec![self.layout.rotations.code()]);
        m.push("width", &[1], vec![r.width]);
        m.push("noise", &[1], vec![r.noise]);
        m.push(
            "relevance_vectors",
            &[r.relevance_vectors.len() / r.dim.max(1), r.dim],
            r.relevance_vectors.clone(),
        );
        m.push(
            "weights",
            &[r.weights.len() / r.outputs.max(1), r.outputs],
            r.weights.clone(),
        );
        m.write(&suit_dir.join(REGRESSOR_FILE))?;
        self.skeleton.write(&suit_dir.join(SKELETON_FILE))?;
        match &self.exemplars {
            Some(exemplars) => exemplars.save(suit_dir)?,
            // Another regressor's exemplars must not be blended into this one's poses.
            None => match std::fs::remove_file(suit_dir.join(EXEMPLARS_FILE)) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                    return Err(ModelError::Write {
                        path: suit_dir.join(EXEMPLARS_FILE),
                        source: e,
                    }
                    .into())
                }
                _ => {}
            },
        }
        Ok(())
    }

    /// The pose vector of a frame's `descriptor`: the RVM's, moved towards the nearest
    /// exemplars' where the suit has them.
    pub fn predict_into(&self, descriptor: &[f32], pose: &mut [f32]) {
        self.rvm.predict_into(descriptor, pose);
        if let Some(exemplars) = &self.exemplars {
            exemplars.blend(descriptor, pose);
        }
    }

    /// Reads a suit's regressor, checking it against the suit's skeleton and its own shapes.
    pub fn load(suit_dir: &Path, suit: &SuitDefinition) -> Result<Regressor, RegressorError> {
        let mut regressor = Regressor::load_without_exemplars(suit_dir, suit)?;
        regressor.exemplars = Exemplars::load(suit_dir, regressor.rvm.dim, regressor.layout.len())?;
        Ok(regressor)
    }

    /// [`Regressor::load`] without reading the exemplars (`exemplars` is `None`): for writing
    /// them anew, whatever state the old file is in.
    pub fn load_without_exemplars(
        suit_dir: &Path,
        suit: &SuitDefinition,
    ) -> Result<Regressor, RegressorError> {
        let path = suit_dir.join(REGRESSOR_FILE);
        let m = ModelFile::read(&path, REGRESSOR_KIND, REGRESSOR_VERSION)?;
        let skeleton = Motion::load(&suit_dir.join(SKELETON_FILE))?;
        let layout = PoseLayout::new(&suit.skeleton, &skeleton.skeleton).map_err(|source| {
            RegressorError::Layout {
                path: suit_dir.join(SKELETON_FILE),
                source,
            }
        })?;
        let get = |name: &str| {
            m.arrays
                .iter()
                .find(|a| a.name == name)
                .ok_or_else(|| ModelError::Array {
                    path: path.clone(),
                    name: name.into(),
                    message: "is missing".into(),
                })
        };
        let descriptor =
            kind_from_code(m.array(&path, "descriptor", &[1])?[0]).ok_or_else(|| {
                RegressorError::Mismatch {
                    path: path.clone(),
                    message: "unknown descriptor kind".into(),
                }
            })?;
        let rotations = RotationEncoding::from_code(m.array(&path, "rotations", &[1])?[0])
            .ok_or_else(|| RegressorError::Mismatch {
                path: path.clone(),
                message: "unknown rotation encoding".into(),
            })?;
        let layout = layout.with_rotations(rotations);
        let width = m.array(&path, "width", &[1])?[0];
        let noise = m.array(&path, "noise", &[1])?[0];
        let rv = get("relevance_vectors")?;
        let weights = get("weights")?;
        let (count, dim) = match rv.dims[..] {
            [count, dim] => (count, dim),
            _ => {
                return Err(RegressorError::Mismatch {
                    path,
                    message: "relevance_vectors is not a matrix".into(),
                })
            }
        };
        if dim != descriptor.len() {
            return Err(RegressorError::Mismatch {
                path,
                message: format!(
                    "relevance vectors have {dim} values, the {} descriptor has {}",
                    descriptor.name(),
                    descriptor.len()
                ),
            });
        }
        if weights.dims != [count + 1, layout.len()] {
            return Err(RegressorError::Mismatch {
                path,
                message: format!(
                    "weights are {:?}, expected [{}, {}]",
                    weights.dims,
                    count + 1,
                    layout.len()
                ),
            });
        }
        if skeleton.frame_count() == 0 {
            return Err(RegressorError::Mismatch {
                path: suit_dir.join(SKELETON_FILE),
                message: "no template frame".into(),
            });
        }
        let rvm = Rvm {
            dim,
            outputs: layout.len(),
            width,
            relevance_vectors: rv.data.clone(),
            weights: weights.data.clone(),
            noise,
        };
        Ok(Regressor {
            rvm,
            descriptor,
            skeleton,
            layout,
            exemplars: None,
        })
    }

    /// The template frame (values of the joints the suit does not estimate).
    pub fn template(&self) -> &[f32] {
        self.skeleton.frame(0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shipped() -> Regressor {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("suits/default");
        let suit = SuitDefinition::load_dir(&dir).expect("the default suit");
        Regressor::load(&dir, &suit).expect("the default regressor")
    }

    #[test]
    fn the_exemplars_move_the_rvms_pose_by_their_share() {
        let mut regressor = shipped();
        let (dim, outputs) = (regressor.rvm.dim, regressor.rvm.outputs);
        let descriptor: Vec<f32> = (0..dim).map(|i| (i % 7) as f32 / 70.0).collect();
        let mut alone = vec![0.0; outputs];
        regressor.rvm.predict_into(&descriptor, &mut alone);
        // One exemplar, all of whose pose values are 1: the pose moves half-way to it.
        let mut exemplars =
            Exemplars::new(vec![0.0; dim], dim, vec![1.0; outputs], outputs).expect("valid");
        exemplars.share = 0.5;
        regressor.exemplars = Some(exemplars);
        let mut blended = vec![0.0; outputs];
        regressor.predict_into(&descriptor, &mut blended);
        for (b, a) in blended.iter().zip(&alone) {
            assert!((b - (a + 1.0) / 2.0).abs() < 1e-5, "{b} from {a}");
        }
        // Without exemplars the RVM's pose is the regressor's.
        regressor.exemplars = None;
        regressor.predict_into(&descriptor, &mut blended);
        assert_eq!(blended, alone);
    }

    #[test]
    fn saving_without_exemplars_removes_the_file_an_earlier_save_left() {
        let mut regressor = shipped();
        let dir = tempfile::tempdir().expect("tempdir");
        regressor.save(dir.path()).expect("save");
        assert!(dir.path().join(EXEMPLARS_FILE).exists());
        regressor.exemplars = None;
        regressor.save(dir.path()).expect("save");
        assert!(!dir.path().join(EXEMPLARS_FILE).exists());
    }
}
