//! `suitcap-train import`: a training dataset from a real recording.
//!
//! A suit is trained on video recorded alongside motion capture. The recording arrives as a video
//! (a frame directory, e.g. from `suitcap capture`, whose `timestamps.csv` gives each frame's
//! capture time, or a `.y4m` file), the BVH the mocap system
//! wrote, the camera's calibration in the mocap's world frame (`camera.toml`) and, for the
//! segmenter's training, hand-made masks of some frames. [`import`] pairs every video frame with
//! the mocap frame nearest its time (the two clocks joined by one offset, the mocap time of the
//! video's first frame: [`suitcap::dataset::mocap_frame_at`]), leaves out the video taken before
//! the mocap started or after it ended, and writes the dataset layout of [`suitcap::dataset`]:
//! `frames/`, the masks that exist (renumbered with their frames), `motion.bvh` with one BVH frame
//! per image at the video's rate, `camera.toml`, and `manifest.toml` last, with a `[recording]`
//! table saying where it all came from. The other training commands then read it like a generated
//! dataset.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context};

use suitcap::bvh::Motion;
use suitcap::camera::Camera;
use suitcap::dataset::{
    self, mocap_frame_at, ClipInfo, Manifest, MocapTime, RecordingInfo, SuitInfo, DATASET_FORMAT,
};
use suitcap::source::{self, directory::png_names_of_frames, SourceOptions, SourceSpec};
use suitcap::suit::SuitDefinition;

/// What to import.
pub struct ImportOptions<'a> {
    /// A frame directory or a `.y4m` file.
    pub video: &'a str,
    pub bvh: &'a Path,
    pub camera: &'a Path,
    pub suit: &'a Path,
    pub out: &'a Path,
    /// Mocap time (s) of the video's first frame.
    pub offset_s: f64,
    /// The video's frame rate, for a frame directory without `timestamps.csv` (its frames are
    /// then taken to be evenly spaced) or a `.y4m` file without a rate in its header.
    pub fps: Option<f64>,
    /// Hand-made masks, named like the video's frames (`NNNNNN.png` for a `.y4m` file).
    pub masks: Option<&'a Path>,
    pub performer: &'a str,
    pub max_frames: Option<usize>,
    pub overwrite: bool,
    /// The command line, kept in the manifest.
    pub command: String,
}

/// What an import did.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportReport {
    pub frames: usize,
    /// Video frames taken before the mocap started.
    pub skipped_before: usize,
    /// Whether the video went on after the mocap (or past `max_frames`).
    pub cut_at_end: bool,
    pub masks: usize,
    pub fps: f64,
    pub source_frames: (usize, usize),
}

/// The name a mask of each video frame has: the frame file's stem + `.png` for a directory (as
/// `suitcap segment` writes them), the frame's index for a `.y4m` file.
fn mask_names(spec: &SourceSpec) -> anyhow::Result<Option<Vec<String>>> {
    Ok(match spec {
        SourceSpec::Directory(dir) => Some(png_names_of_frames(dir)?),
        _ => None,
    })
}

pub fn import(o: &ImportOptions) -> anyhow::Result<ImportReport> {
    let suit = SuitDefinition::load_dir(o.suit)?;
    let motion = Motion::load(o.bvh)?;
    suit.skeleton.bind(&motion.skeleton).with_context(|| {
        format!(
            "{}: does not carry the suit's joints ({})",
            o.bvh.display(),
            o.suit.join("suit.toml").display()
        )
    })?;
    if motion.frame_count() == 0 {
        bail!("{}: no frames", o.bvh.display());
    }
    let camera = Camera::load(o.camera)?;
    if !o.offset_s.is_finite() {
        bail!("--offset {}: not a number of seconds", o.offset_s);
    }
    let spec = source::parse_spec(o.video)?;
    if let SourceSpec::Device(path) = &spec {
        bail!(
            "{}: a camera; import reads a recording (record one with `suitcap capture`)",
            path.display()
        );
    }
    let fps_given = match o.fps {
        Some(f) if !(f.is_finite() && f > 0.0) => bail!("--fps {f}: not a frame rate"),
        f => f,
    };
    let names = mask_names(&spec)?;
    let options = SourceOptions {
        fps: fps_given,
        // No rate is assumed: a directory without timestamps.csv has none unless given.
        fps_for_directory: fps_given.unwrap_or(f64::NAN),
        ..SourceOptions::default()
    };
    let mut video = source::open_source(o.video, &options)?;
    let fps = video.frame_rate().with_context(|| {
        format!(
            "{}: no frame rate (a frame directory without {}, or a .y4m file without one in its header); give --fps",
            o.video,
            source::directory::TIMESTAMPS_FILE
        )
    })?;
    let (width, height) = video.size();
    let (cw, ch) = (camera.intrinsics.width, camera.intrinsics.height);
    if (cw, ch) != (width, height) {
        bail!(
            "{}: calibrated for {cw}x{ch} images, but {} has {width}x{height} frames",
            o.camera.display(),
            o.video
        );
    }

    dataset::prepare_dataset_dir(o.out, o.overwrite)?;
    let manifest_path = o.out.join("manifest.toml");

    let mut source_frames = Vec::new();
    let mut first_video_frame = 0usize;
    let mut cut_at_end = false;
    let mut masks = 0usize;
    while let Some(frame) = video.next_frame().with_context(|| {
        format!(
            "{}: video frame {} (a dataset needs every frame; cut the recording before it with --max-frames)",
            o.video,
            first_video_frame + source_frames.len()
        )
    })? {
        let index = frame.index as usize;
        let time = frame.timestamp.as_secs_f64();
        let mocap_frame =
            match mocap_frame_at(time, motion.frame_time, motion.frame_count(), o.offset_s) {
                MocapTime::Before => {
                    first_video_frame = index + 1;
                    continue;
                }
                MocapTime::After => {
                    cut_at_end = true;
                    break;
                }
                MocapTime::At(s) => s,
            };
        if o.max_frames.is_some_and(|m| source_frames.len() >= m) {
            cut_at_end = true;
            break;
        }
        let k = source_frames.len();
        let path = dataset::frame_path(o.out, k);
        frame
            .image
            .save(&path)
            .with_context(|| format!("cannot write {}", path.display()))?;
        if let Some(dir) = o.masks {
            let name = match &names {
                Some(names) => names.get(index).cloned().unwrap_or_default(),
                None => format!("{index:06}.png"),
            };
            let from = dir.join(&name);
            if from.is_file() {
                let mask = image::open(&from)
                    .with_context(|| format!("cannot read mask {}", from.display()))?
                    .to_luma8();
                if mask.dimensions() != (width, height) {
                    bail!(
                        "{}: {}x{} mask for {width}x{height} frames",
                        from.display(),
                        mask.width(),
                        mask.height()
                    );
                }
                let to = dataset::mask_path(o.out, k);
                mask.save(&to)
                    .with_context(|| format!("cannot write {}", to.display()))?;
                masks += 1;
            }
        }
        source_frames.push(mocap_frame);
    }
    let (Some(&first), Some(&last)) = (source_frames.first(), source_frames.last()) else {
        bail!(
            "no frame of {} falls within the mocap ({} frames, {:.2} s) at --offset {} s: the offset is the mocap time of the video's first frame",
            o.video,
            motion.frame_count(),
            motion.frame_count() as f64 * motion.frame_time,
            o.offset_s
        );
    };
    if let Some(dir) = o.masks {
        if masks == 0 {
            bail!(
                "{}: no mask named like an imported frame (e.g. {})",
                dir.display(),
                match &names {
                    Some(names) => names.get(first_video_frame).cloned().unwrap_or_default(),
                    None => format!("{first_video_frame:06}.png"),
                }
            );
        }
    }
    let mut values = Vec::with_capacity(source_frames.len() * motion.skeleton.channel_count());
    for &s in &source_frames {
        values.extend_from_slice(motion.frame(s));
    }
    Motion::new(motion.skeleton.clone(), 1.0 / fps, values)?.write(&o.out.join("motion.bvh"))?;
    let camera_out = o.out.join("camera.toml");
    std::fs::copy(o.camera, &camera_out).with_context(|| {
        format!(
            "cannot copy {} to {}",
            o.camera.display(),
            camera_out.display()
        )
    })?;
    let manifest = Manifest {
        format: DATASET_FORMAT,
        generator: format!("suitcap-train import {}", env!("CARGO_PKG_VERSION")),
        command: o.command.clone(),
        frames: source_frames.len(),
        fps,
        width,
        height,
        seed: None,
        clip: ClipInfo {
            name: file_name(o.bvh),
            source_fps: motion.frame_rate(),
            start_frame: first,
            source_frames: source_frames.clone(),
        },
        subject: None,
        suit: SuitInfo {
            name: suit.name.clone(),
            layout_seed: suit.layout_seed,
            marker_size_cm: suit.marker_size_cm,
            marker_gap_cm: suit.marker_gap_cm,
        },
        scene: None,
        recording: Some(RecordingInfo {
            video: o.video.to_owned(),
            performer: o.performer.to_owned(),
            first_video_frame,
            mocap_offset_s: o.offset_s,
            masks,
        }),
    };
    suitcap::io::write_atomic(&manifest_path, manifest.to_toml().as_bytes())
        .with_context(|| format!("cannot write {}", manifest_path.display()))?;
    Ok(ImportReport {
        frames: source_frames.len(),
        skipped_before: first_video_frame,
        cut_at_end,
        masks,
        fps,
        source_frames: (first, last),
    })
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// The command's output line.
pub fn summary(o: &ImportOptions, r: &ImportReport) -> String {
    let out: PathBuf = o.out.to_owned();
    format!(
        "imported {} frames of {} at {:.3} frames/s with mocap frames {}..={} of {} (offset {} s){}{}; {}; dataset written to {}",
        r.frames,
        o.video,
        r.fps,
        r.source_frames.0,
        r.source_frames.1,
        o.bvh.display(),
        o.offset_s,
        match r.skipped_before {
            0 => String::new(),
            n => format!(", the first {n} video frames before the mocap left out"),
        },
        if r.cut_at_end {
            ", the video after the mocap's end (or --max-frames) left out"
        } else {
            ""
        },
        match (o.masks, r.masks) {
            (None, _) => "no masks given".to_owned(),
            (Some(_), n) => format!("{n} with masks"),
        },
        out.display()
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use suitcap::dataset::Dataset;

    fn repo(path: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(path)
    }

    /// A 6-frame generated dataset standing in for a recording: its frames are the video, its
    /// `motion.bvh` (30 frames/s) the mocap.
    struct Recording {
        tmp: tempfile::TempDir,
        rec: Dataset,
        bvh: PathBuf,
        video: String,
        camera: PathBuf,
        suit: PathBuf,
    }

    impl Recording {
        fn new() -> Recording {
            use suitcap_tools::synth::{generate, SynthOptions};
            let tmp = tempfile::tempdir().expect("tempdir");
            let dir = tmp.path().join("rec");
            let options = SynthOptions {
                start_frame: 20,
                frames: Some(6),
                width: 160,
                height: 120,
                seed: 3,
                ..SynthOptions::new(
                    repo("tests/data/mocap/cmu_02_01_walk.bvh"),
                    dir.clone(),
                    repo("suits/default"),
                    vec![repo("tests/data/backgrounds")],
                )
            };
            generate(&options, &|| {}).expect("dataset");
            let rec = Dataset::open(&dir).expect("reopens");
            Recording {
                bvh: dir.join("motion.bvh"),
                video: dir.join("frames").display().to_string(),
                camera: dir.join("camera.toml"),
                suit: repo("suits/default"),
                rec,
                tmp,
            }
        }

        fn options<'a>(&'a self, out: &'a Path) -> ImportOptions<'a> {
            ImportOptions {
                video: &self.video,
                bvh: &self.bvh,
                camera: &self.camera,
                suit: &self.suit,
                out,
                offset_s: 0.0,
                fps: Some(30.0),
                masks: None,
                performer: "ana",
                max_frames: None,
                overwrite: false,
                command: "test".into(),
            }
        }
    }

    #[test]
    fn a_recording_becomes_a_dataset_with_each_frame_on_its_mocap_frame() {
        let r = Recording::new();
        let (rec, tmp) = (&r.rec, &r.tmp);
        // Hand-made masks of video frames 2 and 3 only.
        let masks = tmp.path().join("labelled");
        std::fs::create_dir_all(&masks).expect("dir");
        for k in [2, 3] {
            std::fs::copy(rec.mask_path(k), masks.join(format!("{k:06}.png"))).expect("copy");
        }

        // The video's first frame was taken one mocap frame into the take: video frame k shows
        // mocap frame k + 1, and the last video frame is past the take's end.
        let out = tmp.path().join("late");
        let mut o = r.options(&out);
        o.offset_s = 1.0 / 30.0;
        o.masks = Some(&masks);
        let report = import(&o).expect("imports");
        assert_eq!(
            (
                report.frames,
                report.skipped_before,
                report.cut_at_end,
                report.masks
            ),
            (5, 0, true, 2)
        );
        let imported = Dataset::open(&out).expect("a dataset");
        assert_eq!(imported.manifest.clip.source_frames, vec![1, 2, 3, 4, 5]);
        assert_eq!(imported.manifest.performer(), "ana");
        for k in 0..5 {
            assert_eq!(
                imported.motion.frame(k),
                rec.motion.frame(k + 1),
                "frame {k}"
            );
            let a = image::open(imported.frame_path(k))
                .expect("frame")
                .to_rgb8();
            let b = image::open(rec.frame_path(k)).expect("frame").to_rgb8();
            assert_eq!(a, b, "frame {k} is the video's frame {k}");
            assert_eq!(
                imported.mask_path(k).is_file(),
                k == 2 || k == 3,
                "mask {k}"
            );
        }
        // Importing again over it needs --overwrite.
        let err = import(&o).unwrap_err().to_string();
        assert!(err.contains("--overwrite"), "{err}");

        // The mocap started one frame after the video: video frame 0 has none and is left out.
        let out = tmp.path().join("early");
        let mut o = r.options(&out);
        o.offset_s = -1.0 / 30.0;
        let report = import(&o).expect("imports");
        assert_eq!(
            (report.frames, report.skipped_before, report.masks),
            (5, 1, 0)
        );
        let imported = Dataset::open(&out).expect("a dataset");
        assert_eq!(imported.manifest.clip.source_frames, vec![0, 1, 2, 3, 4]);
        assert_eq!(imported.motion.frame(0), rec.motion.frame(0));
        let first = image::open(imported.frame_path(0))
            .expect("frame")
            .to_rgb8();
        assert_eq!(
            first,
            image::open(rec.frame_path(1)).expect("frame").to_rgb8()
        );

        // The camera dropped a frame after the second: with the capture times in timestamps.csv
        // (as `suitcap capture` writes them), the frames after the gap keep their mocap frames.
        use suitcap::source::directory::{timestamps_line, TIMESTAMPS_FILE, TIMESTAMPS_HEADER};
        let mut times = format!("{TIMESTAMPS_HEADER}\n");
        for (k, slot) in [0, 1, 3, 4, 5, 6].into_iter().enumerate() {
            times += &timestamps_line(&format!("{k:06}.png"), slot as f64 / 30.0);
        }
        std::fs::write(rec.root.join("frames").join(TIMESTAMPS_FILE), times).expect("write");
        let out = tmp.path().join("dropped");
        let mut o = r.options(&out);
        o.fps = None;
        let report = import(&o).expect("imports");
        assert_eq!((report.frames, report.cut_at_end), (5, true));
        assert!(
            (report.fps - 30.0).abs() < 0.01,
            "the median interval's rate"
        );
        let imported = Dataset::open(&out).expect("a dataset");
        assert_eq!(imported.manifest.clip.source_frames, vec![0, 1, 3, 4, 5]);
    }

    #[test]
    fn a_y4m_recording_gives_its_own_rate_and_masks_by_frame_index() {
        use suitcap::source::y4m::{Y4mChroma, Y4mWriter};
        let r = Recording::new();
        let tmp = &r.tmp;
        // The video at 15 frames/s (444, so the frames come back nearly as rendered): video
        // frame k is at k/15 s, i.e. mocap frame 2k of the 30 frames/s take.
        let video = tmp.path().join("take.y4m");
        let mut writer = Y4mWriter::create(&video, 160, 120, 15.0, Y4mChroma::C444).expect("y4m");
        for k in 0..6 {
            let frame = image::open(r.rec.frame_path(k)).expect("frame").to_rgb8();
            writer.write_frame(&frame).expect("write");
        }
        writer.finish().expect("flush");
        let masks = tmp.path().join("labelled");
        std::fs::create_dir_all(&masks).expect("dir");
        std::fs::copy(r.rec.mask_path(1), masks.join("000001.png")).expect("copy");
        let out = tmp.path().join("y4m");
        let video_name = video.display().to_string();
        let mut o = r.options(&out);
        o.video = &video_name;
        o.fps = None;
        o.masks = Some(&masks);
        let report = import(&o).expect("imports");
        // Video frames 0–2 are mocap frames 0, 2, 4; frame 3 (mocap 6) is past the take's end.
        assert_eq!((report.frames, report.masks, report.fps), (3, 1, 15.0));
        let imported = Dataset::open(&out).expect("a dataset");
        assert_eq!(imported.manifest.clip.source_frames, vec![0, 2, 4]);
        assert_eq!(imported.motion.frame(2), r.rec.motion.frame(4));
        // BVH keeps the frame time to eight decimals.
        assert!((imported.motion.frame_time - 1.0 / 15.0).abs() < 1e-7);
        assert!(imported.mask_path(1).is_file() && !imported.mask_path(0).is_file());
    }

    #[test]
    fn what_cannot_be_imported_is_named() {
        let r = Recording::new();
        let tmp = &r.tmp;
        let out = tmp.path().join("out");
        // No overlap between the video and the take.
        let mut o = r.options(&out);
        o.offset_s = 10.0;
        let err = format!("{:#}", import(&o).unwrap_err());
        assert!(
            err.contains("falls within the mocap") && err.contains("--offset 10"),
            "{err}"
        );
        // A frame directory without a rate.
        let mut o = r.options(&out);
        o.fps = None;
        let err = format!("{:#}", import(&o).unwrap_err());
        assert!(err.contains("--fps"), "{err}");
        // A calibration of another image size.
        let camera = repo("suits/default/demo/640x480/camera.toml");
        let mut o = r.options(&out);
        o.camera = &camera;
        let err = format!("{:#}", import(&o).unwrap_err());
        assert!(
            err.contains("camera.toml") && err.contains("640x480") && err.contains("160x120"),
            "{err}"
        );
        // A camera is not a recording.
        let mut o = r.options(&out);
        o.video = "/dev/video0";
        let err = format!("{:#}", import(&o).unwrap_err());
        assert!(err.contains("suitcap capture"), "{err}");
        // Nothing was written for any of them.
        assert!(!out.join("manifest.toml").exists());
    }
}
