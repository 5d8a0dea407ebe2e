//! The mocap-aligned dataset format: what the synthetic generator writes and `suitcap-train` reads.
//!
//! ```text
//! DATASET/
//!   frames/000000.png …   RGB frames, numbered from 0 (or all .jpg: the bundled demo's are)
//!   masks/000000.png …    ground-truth person masks (8-bit grey, 255 = person, 0 = not)
//!   motion.bvh            ground-truth pose, one BVH frame per image frame, at the video's rate
//!   camera.toml           intrinsics and extrinsics in the mocap's world frame (see `camera`)
//!   markers.csv           per frame, every visible suit marker: id, colour, projected centre, visible
//!                         fraction and visible pixels
//!   manifest.toml         everything needed to reproduce the dataset; written last
//! ```
//!
//! `manifest.toml` is written after everything else, so a directory without it is an incomplete
//! dataset and [`Dataset::open`] refuses it. A recorded (real) dataset has the same layout
//! (`suitcap-train import` makes one from a video, the BVH captured with it and the camera's
//! calibration): its manifest has a `[recording]` table instead of the generator's `seed`,
//! `[subject]` and `[scene]`, its `markers.csv` is absent and its masks may cover only the frames
//! that were labelled by hand. [`mocap_frame_at`] pairs a video frame with its mocap frame.

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
    /// The generator's seed (generated datasets only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    pub clip: ClipInfo,
    /// The generated person's proportions (generated datasets only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub subject: Option<SubjectInfo>,
    pub suit: SuitInfo,
    /// The rendering conditions (generated datasets only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene: Option<SceneInfo>,
    /// Where a recorded dataset's video came from and how the mocap was aligned to it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub recording: Option<RecordingInfo>,
}

/// A recorded dataset's video and its alignment with the motion capture.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecordingInfo {
    /// The video (frame directory or `.y4m`) as given to the import.
    pub video: String,
    /// Who wore the suit.
    pub performer: String,
    /// The video frame that became dataset frame 0 (earlier ones had no mocap).
    pub first_video_frame: usize,
    /// Video frames between the first and the last imported one that were left out because they
    /// could not be read (corrupt, or of another size): dataset frame k is the k-th of the
    /// others, with its own mocap frame.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub skipped_video_frames: Vec<usize>,
    /// Mocap time (seconds from the BVH's first frame) at which the video's frame 0 was taken.
    pub mocap_offset_s: f64,
    /// How many dataset frames have a hand-made mask in `masks/`.
    pub masks: usize,
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
    /// Share of the marker's printed square that faces the camera unoccluded, in [0, 1] (the
    /// generator samples its surface; before the eleventh session of 2026-12-05 it divided the
    /// visible pixels by the flat square's projected area, capped at 1, which counted a marker
    /// wrapped round a limb's outline as wholly visible; before the first session of 2026-12-06
    /// it counted the part of a square inside another part, where two parts' capsules cross,
    /// as seen).
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
    #[error(
        "{dir}: not a dataset (no manifest.toml, no frames/): make one from a recording and its mocap with `suitcap-train import`, or render one with `suitcap-synth`"
    )]
    NotADataset { dir: PathBuf },
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
    #[error("{path} already holds a dataset; pass --overwrite to replace it")]
    Exists { path: PathBuf },
    #[error("{path} already holds files but no dataset (an interrupted run, or another program's); pass --overwrite to replace them")]
    Leftovers { path: PathBuf },
    #[error("{path}: cannot write: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// Makes `out` ready for a new dataset: refuses a dataset already there, or files in its
/// `frames/` or `masks/` without one (an interrupted writer's, whose masks would pair with the new
/// frames), unless `overwrite` (they then go); creates `frames/` and `masks/`, and removes an old
/// manifest first, so that a writer interrupted from here on leaves an incomplete dataset.
pub fn prepare_dataset_dir(out: &Path, overwrite: bool) -> Result<(), DatasetError> {
    let write_error = |path: &Path| {
        let path = path.to_owned();
        move |source| DatasetError::Write { path, source }
    };
    let manifest = out.join("manifest.toml");
    if !overwrite {
        if manifest.exists() {
            return Err(DatasetError::Exists {
                path: out.to_owned(),
            });
        }
        for sub in ["frames", "masks"] {
            let dir = out.join(sub);
            if std::fs::read_dir(&dir).is_ok_and(|mut entries| entries.next().is_some()) {
                return Err(DatasetError::Leftovers { path: dir });
            }
        }
    }
    for sub in ["frames", "masks"] {
        let dir = out.join(sub);
        if dir.exists() && overwrite {
            std::fs::remove_dir_all(&dir).map_err(write_error(&dir))?;
        }
        std::fs::create_dir_all(&dir).map_err(write_error(&dir))?;
    }
    if manifest.exists() {
        std::fs::remove_file(&manifest).map_err(write_error(&manifest))?;
    }
    Ok(())
}

/// The frame file extensions a dataset may use, the written one first.
const FRAME_EXTENSIONS: [&str; 2] = ["png", "jpg"];

/// Path of frame `index` under `frames/` (as written: PNG; [`Dataset::frame_path`] also finds JPEG).
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

    /// Who is in the frames: the generated subject's name or the recording's performer.
    pub fn performer(&self) -> &str {
        match (&self.subject, &self.recording) {
            (Some(subject), _) => &subject.name,
            (None, Some(recording)) => &recording.performer,
            (None, None) => "unknown",
        }
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
        if manifest.recording.is_none() {
            for (field, present) in [
                ("seed", manifest.seed.is_some()),
                ("subject", manifest.subject.is_some()),
                ("scene", manifest.scene.is_some()),
            ] {
                if !present {
                    return Err(DatasetError::Manifest {
                        path: path.to_owned(),
                        message: format!("field {field}: missing (a generated dataset has seed, [subject] and [scene]; a recorded one has [recording])"),
                    });
                }
            }
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

/// Where a video frame's time falls in a mocap take (see [`mocap_frame_at`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MocapTime {
    /// Taken before the mocap's first frame.
    Before,
    /// The nearest mocap frame.
    At(usize),
    /// Taken after the mocap's last frame.
    After,
}

/// The mocap frame shown by a video frame taken `video_time` seconds after the video's start, for
/// a take of `frame_count` frames `frame_time` seconds apart whose time `offset_s` is the video's
/// time 0: the nearest frame (not an interpolation, so the ground truth stays a recorded pose);
/// more than half a frame before the first or after the last is outside the take.
pub fn mocap_frame_at(
    video_time: f64,
    frame_time: f64,
    frame_count: usize,
    offset_s: f64,
) -> MocapTime {
    let s = ((video_time + offset_s) / frame_time).round();
    if frame_count == 0 || s.is_nan() || s > (frame_count - 1) as f64 {
        MocapTime::After
    } else if s < 0.0 {
        MocapTime::Before
    } else {
        MocapTime::At(s as usize)
    }
}

/// An opened, checked dataset.
#[derive(Clone, Debug)]
pub struct Dataset {
    pub root: PathBuf,
    pub manifest: Manifest,
    pub camera: Camera,
    pub motion: Motion,
    /// The frames' file extension: `png` (what the generator and the importer write) or `jpg`
    /// (a dataset shipped compressed, like the bundled demo), as frame 0 has it.
    pub frame_extension: &'static str,
}

impl Dataset {
    /// Opens a dataset directory: the manifest must exist and match the motion, camera and frames.
    pub fn open(root: &Path) -> Result<Dataset, DatasetError> {
        if !root.join("manifest.toml").exists() && !root.join("frames").is_dir() {
            return Err(DatasetError::NotADataset {
                dir: root.to_path_buf(),
            });
        }
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
        let frame_extension = FRAME_EXTENSIONS
            .into_iter()
            .find(|ext| frame_path(root, 0).with_extension(ext).is_file())
            .unwrap_or(FRAME_EXTENSIONS[0]);
        for index in [0, manifest.frames.saturating_sub(1)] {
            let frame = frame_path(root, index).with_extension(frame_extension);
            if manifest.frames > 0 && !frame.is_file() {
                return Err(mismatch(frame, "missing frame".into()));
            }
        }
        Ok(Dataset {
            root: root.to_owned(),
            manifest,
            camera,
            motion,
            frame_extension,
        })
    }

    pub fn frame_count(&self) -> usize {
        self.manifest.frames
    }

    pub fn frame_path(&self, index: usize) -> PathBuf {
        frame_path(&self.root, index).with_extension(self.frame_extension)
    }

    pub fn mask_path(&self, index: usize) -> PathBuf {
        mask_path(&self.root, index)
    }

    /// Whether frame `index` has a mask (a recording may have masks for some frames only).
    pub fn has_mask(&self, index: usize) -> bool {
        self.mask_path(index).is_file()
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
    fn the_bundled_demo_is_a_dataset_of_jpeg_frames() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("suits/default/demo/640x480");
        let dataset = Dataset::open(&root).expect("the demo opens");
        assert_eq!(dataset.frame_extension, "jpg");
        let last = dataset.frame_path(dataset.frame_count() - 1);
        assert!(last.ends_with("frames/000059.jpg"), "{}", last.display());
        assert!(last.is_file());
        // Writers still name PNG files.
        assert!(frame_path(&root, 0).ends_with("frames/000000.png"));
    }

    #[test]
    fn a_directory_without_manifest_is_incomplete() {
        let dir = tempfile::tempdir().expect("tempdir");
        // Neither manifest.toml nor frames/ (an empty directory, or a capture's frames): not a dataset.
        let err = Dataset::open(dir.path()).unwrap_err();
        assert!(matches!(err, DatasetError::NotADataset { .. }), "{err}");
        assert!(err.to_string().contains("suitcap-train import"), "{err}");
        // With frames/ but no manifest it is one the generator did not finish.
        std::fs::create_dir(dir.path().join("frames")).expect("mkdir");
        let err = Dataset::open(dir.path()).unwrap_err();
        assert!(matches!(err, DatasetError::Incomplete { .. }), "{err}");
        assert!(err.to_string().contains("manifest.toml"));
    }

    #[test]
    fn an_output_directory_is_replaced_only_when_asked() {
        let dir = tempfile::tempdir().expect("tempdir");
        let out = dir.path().join("take");
        prepare_dataset_dir(&out, false).expect("a new directory");
        assert!(out.join("frames").is_dir() && out.join("masks").is_dir());
        // An interrupted writer's mask: refused, then cleared with overwrite.
        std::fs::write(out.join("masks").join("000000.png"), b"old").expect("write");
        let err = prepare_dataset_dir(&out, false).unwrap_err();
        assert!(matches!(err, DatasetError::Leftovers { .. }), "{err}");
        assert!(err.to_string().contains("masks") && err.to_string().contains("--overwrite"));
        prepare_dataset_dir(&out, true).expect("overwrite");
        assert_eq!(
            std::fs::read_dir(out.join("masks")).expect("dir").count(),
            0
        );
        // A finished dataset: refused; with overwrite its manifest goes first.
        std::fs::write(out.join("manifest.toml"), "format = 1").expect("write");
        let err = prepare_dataset_dir(&out, false).unwrap_err();
        assert!(matches!(err, DatasetError::Exists { .. }), "{err}");
        prepare_dataset_dir(&out, true).expect("overwrite");
        assert!(!out.join("manifest.toml").exists());
    }

    #[test]
    fn video_frames_get_the_nearest_mocap_frame() {
        // Mocap at 100 Hz for 20 frames (0–0.19 s), video at 30 frames/s for 8 frames.
        let at = |offset: f64| -> Vec<MocapTime> {
            (0..8)
                .map(|k| mocap_frame_at(k as f64 / 30.0, 0.01, 20, offset))
                .collect()
        };
        use MocapTime::{After, At, Before};
        // Video time 0 is mocap time 0.02 s: 0.02, 0.053, 0.087, 0.12, 0.153, 0.187 s → frames
        // 2, 5, 9, 12, 15, 19; 0.22 and 0.253 s are past the take's end.
        assert_eq!(
            at(0.02),
            [At(2), At(5), At(9), At(12), At(15), At(19), After, After]
        );
        // The mocap started 0.05 s after the video: video frames 0 (−0.05 s) and 1 (−0.017 s)
        // have none; frame 2 (0.017 s) is mocap frame 2.
        assert_eq!(
            at(-0.05),
            [Before, Before, At(2), At(5), At(8), At(12), At(15), At(18)]
        );
        // Within half a mocap frame of the start still counts.
        assert_eq!(mocap_frame_at(0.0, 0.01, 20, -0.004), At(0));
        assert_eq!(mocap_frame_at(0.0, 0.01, 0, 0.0), After);
    }

    #[test]
    fn a_manifest_is_generated_or_recorded() {
        let recorded = Manifest {
            format: DATASET_FORMAT,
            generator: "suitcap-train import".into(),
            command: "suitcap-train import …".into(),
            frames: 2,
            fps: 30.0,
            width: 64,
            height: 48,
            seed: None,
            clip: ClipInfo {
                name: "take.bvh".into(),
                source_fps: 120.0,
                start_frame: 3,
                source_frames: vec![3, 7],
            },
            subject: None,
            suit: SuitInfo {
                name: "default".into(),
                layout_seed: 7,
                marker_size_cm: 4.0,
                marker_gap_cm: 3.0,
            },
            scene: None,
            recording: Some(RecordingInfo {
                video: "rec/".into(),
                performer: "ana".into(),
                first_video_frame: 1,
                skipped_video_frames: vec![5],
                mocap_offset_s: -0.01,
                masks: 0,
            }),
        };
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("manifest.toml");
        std::fs::write(&path, recorded.to_toml()).expect("write");
        let loaded = Manifest::load(&path).expect("a recorded manifest loads");
        assert_eq!(loaded, recorded);
        assert_eq!(loaded.performer(), "ana");
        // A manifest from before the skipped frames were recorded reads as none skipped.
        let text = recorded.to_toml();
        assert!(text.contains("skipped_video_frames = [5]"), "{text}");
        std::fs::write(&path, text.replace("skipped_video_frames = [5]\n", "")).expect("write");
        let older = Manifest::load(&path).expect("loads");
        assert!(older
            .recording
            .is_some_and(|r| r.skipped_video_frames.is_empty()));
        // Without [recording] it must be a generated one, with seed, subject and scene.
        let text = recorded.to_toml();
        let cut = text.find("[recording]").expect("table");
        std::fs::write(&path, &text[..cut]).expect("write");
        let err = Manifest::load(&path).unwrap_err().to_string();
        assert!(
            err.contains("manifest.toml") && err.contains("field seed"),
            "{err}"
        );
    }
}
