//! The mocap-aligned dataset format: what the synthetic generator writes and `suitcap-train` reads.
//!
//! ```text
//! DATASET/
//!   frames/000000.png …   RGB frames, numbered from 0
//!   masks/000000.png …    ground-truth person masks (8-bit grey, 255 = person, 0 = not)
//!   motion.bvh            ground-truth pose, one BVH frame per image frame, at the video's rate
//!   camera.toml           intrinsics and extrinsics in the mocap's world frame (see `camera`)
//!   markers.csv           per frame, every visible suit marker: id, colour, projected centre, visible
//!                         fraction and visible pixels
//!   manifest.toml         everything needed to reproduce the dataset; written last
//! ```
//!
//! `manifest.toml` is written after everything else, so a directory without it is an incomplete
//! dataset and [`Dataset::open`] refuses it. A recorded (real) dataset has the same layout; its
//! `markers.csv` may be absent and its masks may cover only the frames that were labelled by hand.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::bvh::{BvhError, Motion};
use crate::camera::{Camera, CameraError};

/// Version of the dataset layout this build reads and writes.
pub const DATASET_FORMAT: u32 = 1;

/// `manifest.toml`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    pub format: u32,
    /// Program and version that wrote the dataset.
    pub generator: String,
    /// The command line that reproduces it.
    pub command: String,
    pub frames: usize,
    pub fps: f64,
    pub width: u32,
    pub height: u32,
    pub seed: u64,
    pub clip: ClipInfo,
    pub subject: SubjectInfo,
    pub suit: SuitInfo,
    pub scene: SceneInfo,
}

/// Where the ground-truth motion came from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClipInfo {
    /// File name of the source BVH.
    pub name: String,
    pub source_fps: f64,
    pub start_frame: usize,
    /// For each dataset frame, the source clip frame it shows.
    pub source_frames: Vec<usize>,
}

/// The person's proportions.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SubjectInfo {
    pub name: String,
    pub height_cm: f32,
    pub girth: f32,
    pub arm_ratio: f32,
    pub leg_ratio: f32,
}

/// The suit the person wears.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SuitInfo {
    pub name: String,
    pub layout_seed: u64,
    pub marker_size_cm: f32,
    pub marker_gap_cm: f32,
}

/// The rendering conditions drawn from the seed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneInfo {
    /// Background photographs or video frames used, in order.
    pub backgrounds: Vec<String>,
    /// Whether the background is a video (moves every frame) or a still photograph.
    pub background_is_video: bool,
    pub horizontal_fov_deg: f32,
    /// Unit vector towards the light, world frame.
    pub light_direction: [f32; 3],
    pub ambient: f32,
    pub exposure: f32,
    /// Relative amplitude and period (s) of the slow exposure drift.
    pub exposure_drift: f32,
    pub exposure_period_s: f32,
    /// Sensor noise: read noise σ (of 255) and shot-noise gain.
    pub read_noise: f32,
    pub shot_noise: f32,
    /// Gaussian blur σ in pixels.
    pub blur_sigma: f32,
    /// Moving clutter objects drawn behind the person.
    pub clutter_objects: usize,
}

/// One visible marker in one frame (a row of `markers.csv`).
#[derive(Clone, Debug, PartialEq)]
pub struct MarkerRecord {
    pub frame: usize,
    pub marker_id: u32,
    /// Colour name from the suit (e.g. "cyan").
    pub colour: String,
    /// Projected centre, pixels (pixel centres at +0.5).
    pub x: f32,
    pub y: f32,
    /// Fraction of the marker's projected area that is visible, in [0, 1].
    pub visible_fraction: f32,
    /// Visible area in pixels (a marker seen edge-on can be wholly visible and one pixel large).
    pub visible_px: u32,
}

/// The header line of `markers.csv`.
pub const MARKERS_HEADER: &str = "frame,marker_id,colour,x,y,visible_fraction,visible_px";

/// A dataset that cannot be used; names the file and what is wrong.
#[derive(Debug, thiserror::Error)]
pub enum DatasetError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(
        "{path}: missing; the dataset is incomplete (the generator writes manifest.toml last)"
    )]
    Incomplete { path: PathBuf },
    #[error("{path}: {message}")]
    Manifest { path: PathBuf, message: String },
    #[error(transparent)]
    Motion(#[from] BvhError),
    #[error(transparent)]
    Camera(#[from] CameraError),
    #[error("{path}: line {line}: {message}")]
    Markers {
        path: PathBuf,
        line: usize,
        message: String,
    },
    #[error("{path}: {message}")]
    Mismatch { path: PathBuf, message: String },
}

/// Path of frame `index` under `frames/`.
pub fn frame_path(root: &Path, index: usize) -> PathBuf {
    root.join("frames").join(format!("{index:06}.png"))
}

/// Path of mask `index` under `masks/`.
pub fn mask_path(root: &Path, index: usize) -> PathBuf {
    root.join("masks").join(format!("{index:06}.png"))
}

impl Manifest {
    pub fn to_toml(&self) -> String {
        let body = toml::to_string(self).unwrap_or_default();
        format!("# suitcap dataset manifest (format {DATASET_FORMAT}); see the `dataset` module docs.\n{body}")
    }

    pub fn load(path: &Path) -> Result<Manifest, DatasetError> {
        let text = std::fs::read_to_string(path).map_err(|source| {
            if source.kind() == std::io::ErrorKind::NotFound {
                DatasetError::Incomplete {
                    path: path.to_owned(),
                }
            } else {
                DatasetError::Io {
                    path: path.to_owned(),
                    source,
                }
            }
        })?;
        let manifest: Manifest = toml::from_str(&text).map_err(|e| DatasetError::Manifest {
            path: path.to_owned(),
            message: e.to_string(),
        })?;
        if manifest.format != DATASET_FORMAT {
            return Err(DatasetError::Manifest {
                path: path.to_owned(),
                message: format!("field format: {} is not the dataset format this build reads ({DATASET_FORMAT})", manifest.format),
            });
        }
        if manifest.clip.source_frames.len() != manifest.frames {
            return Err(DatasetError::Manifest {
                path: path.to_owned(),
                message: format!(
                    "field clip.source_frames: {} entries for {} frames",
                    manifest.clip.source_frames.len(),
                    manifest.frames
                ),
            });
        }
        Ok(manifest)
    }
}

/// Writes `markers.csv` text.
pub fn markers_to_csv(records: &[MarkerRecord]) -> String {
    let mut out = String::with_capacity(32 * records.len() + 64);
    out.push_str(MARKERS_HEADER);
    out.push('\n');
    for r in records {
        out.push_str(&format!(
            "{},{},{},{:.3},{:.3},{:.3},{}\n",
            r.frame, r.marker_id, r.colour, r.x, r.y, r.visible_fraction, r.visible_px
        ));
    }
    out
}

/// Parses `markers.csv` text; errors name the line and the field.
pub fn markers_from_csv(text: &str, path: &Path) -> Result<Vec<MarkerRecord>, DatasetError> {
    let error = |line: usize, message: String| DatasetError::Markers {
        path: path.to_owned(),
        line,
        message,
    };
    let mut lines = text.lines().enumerate();
    match lines.next() {
        Some((_, header)) if header.trim() == MARKERS_HEADER => {}
        Some((_, header)) => {
            return Err(error(
                1,
                format!("header is '{header}', expected '{MARKERS_HEADER}'"),
            ))
        }
        None => return Err(error(1, "empty file".into())),
    }
    let mut records = Vec::new();
    for (i, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split(',').collect();
        if fields.len() != 7 {
            return Err(error(i + 1, format!("{} fields, expected 7", fields.len())));
        }
        fn field<T: std::str::FromStr>(value: &str, name: &str) -> Result<T, String> {
            value
                .trim()
                .parse()
                .map_err(|_| format!("field {name}: '{value}' is not a valid number"))
        }
        let parsed = (|| -> Result<MarkerRecord, String> {
            let record = MarkerRecord {
                frame: field(fields[0], "frame")?,
                marker_id: field(fields[1], "marker_id")?,
                colour: fields[2].trim().to_owned(),
                x: field(fields[3], "x")?,
                y: field(fields[4], "y")?,
                visible_fraction: field(fields[5], "visible_fraction")?,
                visible_px: field(fields[6], "visible_px")?,
            };
            if !(record.x.is_finite() && record.y.is_finite()) {
                return Err("field x/y: not finite".into());
            }
            if !(0.0..=1.0).contains(&record.visible_fraction) {
                return Err(format!(
                    "field visible_fraction: {} is not in [0, 1]",
                    record.visible_fraction
                ));
            }
            Ok(record)
        })();
        records.push(parsed.map_err(|m| error(i + 1, m))?);
    }
    Ok(records)
}

/// An opened, checked dataset.
#[derive(Clone, Debug)]
pub struct Dataset {
    pub root: PathBuf,
    pub manifest: Manifest,
    pub camera: Camera,
    pub motion: Motion,
}

impl Dataset {
    /// Opens a dataset directory: the manifest must exist and match the motion, camera and frames.
    pub fn open(root: &Path) -> Result<Dataset, DatasetError> {
        let manifest = Manifest::load(&root.join("manifest.toml"))?;
        let motion = Motion::load(&root.join("motion.bvh"))?;
        let camera = Camera::load(&root.join("camera.toml"))?;
        let mismatch = |path: PathBuf, message: String| DatasetError::Mismatch { path, message };
        if motion.frame_count() != manifest.frames {
            return Err(mismatch(
                root.join("motion.bvh"),
                format!(
                    "{} frames, the manifest says {}",
                    motion.frame_count(),
                    manifest.frames
                ),
            ));
        }
        if (camera.intrinsics.width, camera.intrinsics.height) != (manifest.width, manifest.height)
        {
            return Err(mismatch(
                root.join("camera.toml"),
                format!(
                    "image size {}x{}, the manifest says {}x{}",
                    camera.intrinsics.width,
                    camera.intrinsics.height,
                    manifest.width,
                    manifest.height
                ),
            ));
        }
        for index in [0, manifest.frames.saturating_sub(1)] {
            let frame = frame_path(root, index);
            if manifest.frames > 0 && !frame.is_file() {
                return Err(mismatch(frame, "missing frame".into()));
            }
        }
        Ok(Dataset {
            root: root.to_owned(),
            manifest,
            camera,
            motion,
        })
    }

    pub fn frame_count(&self) -> usize {
        self.manifest.frames
    }

    pub fn frame_path(&self, index: usize) -> PathBuf {
        frame_path(&self.root, index)
    }

    pub fn mask_path(&self, index: usize) -> PathBuf {
        mask_path(&self.root, index)
    }

    /// Reads `markers.csv`.
    pub fn markers(&self) -> Result<Vec<MarkerRecord>, DatasetError> {
        let path = self.root.join("markers.csv");
        let text = std::fs::read_to_string(&path).map_err(|source| DatasetError::Io {
            path: path.clone(),
            source,
        })?;
        markers_from_csv(&text, &path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markers_csv_round_trip() {
        let records = vec![
            MarkerRecord {
                frame: 0,
                marker_id: 20_102,
                colour: "cyan".into(),
                x: 12.5,
                y: 7.25,
                visible_fraction: 1.0,
                visible_px: 52,
            },
            MarkerRecord {
                frame: 3,
                marker_id: 5,
                colour: "red".into(),
                x: 0.0,
                y: 479.5,
                visible_fraction: 0.375,
                visible_px: 3,
            },
        ];
        let text = markers_to_csv(&records);
        assert!(text.starts_with(MARKERS_HEADER));
        assert_eq!(
            markers_from_csv(&text, Path::new("m.csv")).expect("parses"),
            records
        );
    }

    #[test]
    fn bad_markers_csv_names_line_and_field() {
        let text = format!("{MARKERS_HEADER}\n0,1,red,1,2,0.5,9\n1,2,cyan,abc,2,0.5,9\n");
        let err = markers_from_csv(&text, Path::new("m.csv"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("m.csv") && err.contains("line 3") && err.contains("field x"),
            "{err}"
        );
        let err = markers_from_csv("a,b\n", Path::new("m.csv"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("header"), "{err}");
        let text = format!("{MARKERS_HEADER}\n0,1,red,1,2,1.5,9\n");
        assert!(markers_from_csv(&text, Path::new("m.csv")).is_err());
    }

    #[test]
    fn a_directory_without_manifest_is_incomplete() {
        let dir = tempfile::tempdir().expect("tempdir");
        let err = Dataset::open(dir.path()).unwrap_err();
        assert!(matches!(err, DatasetError::Incomplete { .. }), "{err}");
        assert!(err.to_string().contains("manifest.toml"));
    }
}
