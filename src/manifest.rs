//! The suit model's manifest, `model.toml`: how `suitcap-train suit` trained the regressor, on
//! which datasets, and a checksum of every model file of the suit as it stood when training
//! ended.
//!
//! The trainer writes each model file atomically, but a suit is several files from three stages
//! (segmenter tables, codebooks, regressor), and the stages also run on their own: a run stopped
//! after the codebooks, or a stage re-run later, leaves a regressor beside codebooks it was not
//! trained with, which would load and give wrong poses without a word. The manifest is written
//! last, so [`verify`] tells such a suit from a whole one: every file it lists must still have its
//! checksum (FNV-1a 64 of the bytes, as the model files' own trailer). The pose pipeline and
//! `suitcap check` call it after loading the models (so a truncated file is named as such first);
//! a suit without a manifest (hand-assembled, or part-way through its first training) or with one
//! from before the checksums (format 1) is not checked.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

/// The manifest's file name in a suit directory.
pub const MANIFEST_FILE: &str = "model.toml";
/// The format this build writes; format 1 (before the checksums) is read but not checked.
pub const MANIFEST_FORMAT: u32 = 2;
/// The model files a manifest records, where the suit has them: the segmenter tables, the three
/// codebooks, the regressor, its skeleton and its exemplars.
pub fn model_files() -> [String; 7] {
    use crate::descriptor::{FC_CODEBOOK, HOG_CODEBOOK, SILHOUETTE_CODEBOOK};
    [
        crate::segment::tables::SEGMENTER_FILE.to_string(),
        format!("{FC_CODEBOOK}.bin"),
        format!("{HOG_CODEBOOK}.bin"),
        format!("{SILHOUETTE_CODEBOOK}.bin"),
        crate::pose::regressor::REGRESSOR_FILE.to_string(),
        crate::pose::regressor::SKELETON_FILE.to_string(),
        crate::pose::exemplars::EXEMPLARS_FILE.to_string(),
    ]
}

/// One training dataset as the manifest records it: its directory's name and, for a generated
/// one, what its own manifest says it was made from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DatasetRecord {
    pub name: String,
    pub frames: usize,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clip: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub subject: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
}

/// `model.toml`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    pub format: u32,
    /// The program and version that wrote it.
    #[serde(default)]
    pub tool: String,
    pub descriptor: String,
    pub rotations: String,
    pub basis_candidates: usize,
    pub relevance_vectors: usize,
    pub kernel_width: f32,
    pub noise: f64,
    pub training_frames: usize,
    /// Format 1 kept the datasets' paths only; they are not read back.
    #[serde(default, skip_serializing)]
    pub dataset_paths: Vec<String>,
    #[serde(default, rename = "dataset")]
    pub datasets: Vec<DatasetRecord>,
    /// Model file name → checksum (16 hex digits).
    #[serde(default)]
    pub files: BTreeMap<String, String>,
}

/// A manifest that cannot be read, or a suit whose files no longer match it.
#[derive(Debug, thiserror::Error)]
pub enum ManifestError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: not a suit manifest: {message}")]
    Format { path: PathBuf, message: String },
    #[error("{file}: not the file {manifest} records (a training stage ran again after it was written, or a training stopped part-way), so the suit's models may not fit together; run `suitcap-train suit` on this suit again")]
    Changed { file: PathBuf, manifest: PathBuf },
    #[error("{file}: missing, but {manifest} records it; restore it or run `suitcap-train suit` on this suit again")]
    Missing { file: PathBuf, manifest: PathBuf },
}

/// The checksum of a file's bytes as the manifest writes it.
pub fn checksum(bytes: &[u8]) -> String {
    format!("{:016x}", crate::model::fnv1a(bytes))
}

/// The checksums of the suit's model files that exist ([`model_files`]).
pub fn record_files(suit_dir: &Path) -> Result<BTreeMap<String, String>, ManifestError> {
    let mut files = BTreeMap::new();
    for name in model_files() {
        let path = suit_dir.join(&name);
        match std::fs::read(&path) {
            Ok(bytes) => {
                files.insert(name, checksum(&bytes));
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(source) => return Err(ManifestError::Io { path, source }),
        }
    }
    Ok(files)
}

impl Manifest {
    /// The manifest as TOML, with a comment naming what wrote it.
    pub fn to_toml(&self) -> Result<String, toml::ser::Error> {
        Ok(format!(
            "# suitcap suit model: how the regressor was trained, and a checksum of every model\n\
             # file as training left it (see src/manifest.rs). Written by {}.\n{}",
            self.tool,
            toml::to_string(self)?
        ))
    }

    /// Parses `model.toml` text; `path` names it in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Manifest, ManifestError> {
        let format_error = |e: toml::de::Error| ManifestError::Format {
            path: path.to_owned(),
            message: e.to_string(),
        };
        // Format 1 wrote `datasets` as a list of paths; read it under its own name.
        let mut value: toml::Table = toml::from_str(text).map_err(format_error)?;
        if let Some(paths @ toml::Value::Array(_)) = value.remove("datasets") {
            value.insert("dataset_paths".into(), paths);
        }
        toml::Value::Table(value).try_into().map_err(format_error)
    }

    /// The suit's manifest, `None` when it has none.
    pub fn load(suit_dir: &Path) -> Result<Option<Manifest>, ManifestError> {
        let path = suit_dir.join(MANIFEST_FILE);
        match std::fs::read_to_string(&path) {
            Ok(text) => Manifest::parse(&text, &path).map(Some),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
            Err(source) => Err(ManifestError::Io { path, source }),
        }
    }
}

/// Checks that every model file the suit's manifest records still has its checksum. `Ok(None)`:
/// there is nothing to check (no manifest, or one of format 1); `Ok(Some(n))`: `n` files match.
pub fn verify(suit_dir: &Path) -> Result<Option<usize>, ManifestError> {
    let Some(manifest) = Manifest::load(suit_dir)? else {
        return Ok(None);
    };
    if manifest.files.is_empty() {
        return Ok(None);
    }
    let manifest_path = suit_dir.join(MANIFEST_FILE);
    for (name, expected) in &manifest.files {
        let file = suit_dir.join(name);
        let bytes = match std::fs::read(&file) {
            Ok(bytes) => bytes,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                return Err(ManifestError::Missing {
                    file,
                    manifest: manifest_path,
                })
            }
            Err(source) => return Err(ManifestError::Io { path: file, source }),
        };
        if &checksum(&bytes) != expected {
            return Err(ManifestError::Changed {
                file,
                manifest: manifest_path,
            });
        }
    }
    Ok(Some(manifest.files.len()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn manifest(files: BTreeMap<String, String>) -> Manifest {
        Manifest {
            format: MANIFEST_FORMAT,
            tool: "suitcap-train test".into(),
            descriptor: "fc+hog+box".into(),
            rotations: "matrix".into(),
            basis_candidates: 12,
            relevance_vectors: 5,
            kernel_width: 0.5,
            noise: 0.01,
            training_frames: 40,
            dataset_paths: Vec::new(),
            datasets: vec![DatasetRecord {
                name: "walk".into(),
                frames: 40,
                clip: Some("cmu_02_01_walk.bvh".into()),
                subject: Some("ana".into()),
                seed: Some(7),
            }],
            files,
        }
    }

    #[test]
    fn the_model_files_are_the_ones_the_loaders_read() {
        let suit = Path::new("suit");
        let files = model_files();
        assert_eq!(files[0], crate::segment::tables::SEGMENTER_FILE);
        assert_eq!(
            suit.join(&files[1]),
            crate::descriptor::codebook::codebook_path(suit, crate::descriptor::FC_CODEBOOK)
        );
        assert_eq!(files[2], "codebook_hog.bin");
        assert_eq!(files[3], "codebook_silhouette.bin");
    }

    #[test]
    fn the_checksum_is_fnv1a_in_hex() {
        // FNV-1a 64 of no bytes is its offset basis; of "a" the published test vector.
        assert_eq!(checksum(b""), "cbf29ce484222325");
        assert_eq!(checksum(b"a"), "af63dc4c8601ec8c");
    }

    #[test]
    fn a_written_manifest_reads_back() {
        let m = manifest(BTreeMap::from([("regressor.bin".into(), checksum(b"r"))]));
        let text = m.to_toml().expect("serialises");
        assert_eq!(
            Manifest::parse(&text, Path::new("model.toml")).expect("parses"),
            m
        );
    }

    #[test]
    fn a_format_1_manifest_reads_with_nothing_to_check() {
        let dir = tempfile::tempdir().expect("tempdir");
        std::fs::write(
            dir.path().join(MANIFEST_FILE),
            "format = 1\ndescriptor = \"fc+hog+box\"\nrotations = \"matrix\"\nbasis_candidates = 3\n\
             relevance_vectors = 2\nkernel_width = 0.1\nnoise = 0.01\ntraining_frames = 9\n\
             datasets = [\"/tmp/a\", \"/tmp/b\"]\n",
        )
        .expect("write");
        let m = Manifest::load(dir.path()).expect("reads").expect("present");
        assert_eq!(m.dataset_paths, ["/tmp/a", "/tmp/b"]);
        assert!(m.files.is_empty());
        assert_eq!(verify(dir.path()).expect("nothing to check"), None);
    }

    #[test]
    fn a_file_changed_or_missing_since_the_manifest_is_named() {
        let dir = tempfile::tempdir().expect("tempdir");
        let suit = dir.path();
        assert_eq!(verify(suit).expect("no manifest"), None);
        std::fs::write(suit.join("codebook_fc.bin"), b"old codebook").expect("write");
        std::fs::write(suit.join("regressor.bin"), b"regressor").expect("write");
        let m = manifest(record_files(suit).expect("checksums"));
        assert_eq!(m.files.len(), 2);
        std::fs::write(suit.join(MANIFEST_FILE), m.to_toml().expect("toml")).expect("write");
        assert_eq!(verify(suit).expect("whole"), Some(2));
        // The codebooks trained again, the regressor not: named.
        std::fs::write(suit.join("codebook_fc.bin"), b"new codebook").expect("write");
        let err = verify(suit).expect_err("changed").to_string();
        assert!(
            err.contains("codebook_fc.bin") && err.contains("suitcap-train suit"),
            "{err}"
        );
        std::fs::remove_file(suit.join("codebook_fc.bin")).expect("rm");
        let err = verify(suit).expect_err("missing").to_string();
        assert!(err.contains("codebook_fc.bin: missing"), "{err}");
    }

    #[test]
    fn a_broken_manifest_is_a_clear_error() {
        let dir = tempfile::tempdir().expect("tempdir");
        std::fs::write(dir.path().join(MANIFEST_FILE), "format = \"two\"\n").expect("write");
        let err = verify(dir.path()).expect_err("broken").to_string();
        assert!(err.contains("model.toml: not a suit manifest"), "{err}");
    }
}
