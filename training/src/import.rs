//! `suitcap-train import`: a training dataset from a real recording.
//!
//! A suit is trained on video recorded alongside motion capture. The recording arrives as a video
//! (a frame directory, e.g. from `suitcap capture`, whose `timestamps.csv` gives each frame's
//! capture time, or a `.y4m` file), the BVH the mocap system wrote, the camera's calibration in
//! the mocap's world frame (`camera.toml`) and, for the segmenter's training, hand-made masks of
//! some frames. [`import`] pairs every video frame with
//! the mocap frame nearest its time (the two clocks joined by one offset, the mocap time of the
//! video's first frame: [`suitcap::dataset::mocap_frame_at`]), leaves out the video taken before
//! the mocap started or after it ended, and writes the dataset layout of [`suitcap::dataset`]:
//! `frames/`, the masks that exist (renumbered with their frames), `motion.bvh` with one BVH frame
//! per image at the video's rate, `camera.toml`, and `manifest.toml` last, with a `[recording]`
//! table saying where it all came from. The other training commands then read it like a generated
//! dataset.
//!
//! A wrong clock offset or calibration would silently teach the regressor poses the frames do not
//! show, so the import then checks the pairing when the suit has a segmenter: over the first
//! frames, the share of the suit's joints (the mocap's, projected through the calibration) that
//! land on the person the segmenter finds, at the given offset and at every offset within a
//! second of it ([`scan_offsets`]); a much better one elsewhere is reported as a warning. The
//! check is coarse: joints lie inside the body, so on a slow motion an offset a frame or two off
//! still puts them all on the person; it catches offsets wrong by a few frames or more (on a
//! generated walk, 0.2 s off: 49.6 % against 100 %) and calibrations that miss the person.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use glam::Vec2;

use suitcap::bvh::Motion;
use suitcap::camera::Camera;
use suitcap::dataset::{
    self, mocap_frame_at, ClipInfo, Manifest, MocapTime, RecordingInfo, SuitInfo, DATASET_FORMAT,
};
use suitcap::mask::Mask;
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
    /// Video frames within the mocap that could not be read (corrupt, or of another size), each
    /// named: left out, the frames after them keep their own mocap frames.
    pub unreadable: Vec<String>,
    /// Whether the video went on after the mocap (or past `max_frames`).
    pub cut_at_end: bool,
    pub masks: usize,
    pub fps: f64,
    pub source_frames: (usize, usize),
    /// How well the mocap lands on the video (`None` without a segmenter in the suit).
    pub alignment: Option<AlignmentCheck>,
}

/// The pairing check: the share of the suit's joints, projected through the calibration, that
/// land on the segmented person.
#[derive(Clone, Debug, PartialEq)]
pub struct AlignmentCheck {
    pub frames: usize,
    /// At the given offset.
    pub given: f64,
    /// The offset within a second of the given one with the highest share, and that share.
    pub best_offset_s: f64,
    pub best: f64,
}

/// Frames of the start of the recording the pairing is checked on.
const CHECK_FRAMES: usize = 150;

/// How far (pixels) a projected joint may lie from the segmented person and still count.
const CHECK_RADIUS: i32 = 4;

/// Whether a set pixel of `mask` lies within `radius` pixels (chessboard) of `point`.
pub fn lands_on(mask: &Mask, point: Vec2, radius: i32) -> bool {
    let (w, h) = (mask.width() as i32, mask.height() as i32);
    let (cx, cy) = (point.x.floor() as i32, point.y.floor() as i32);
    (cy - radius..=cy + radius).any(|y| {
        (cx - radius..=cx + radius)
            .any(|x| x >= 0 && y >= 0 && x < w && y < h && mask.get(x as u32, y as u32))
    })
}

/// For each candidate offset, the share of projected joints that land on the person of their
/// frame: frame `k` (taken at `video_times[k]`, person `masks[k]`) is paired with the mocap frame
/// nearest its time plus the offset, whose joints are `joints_px(mocap frame)` (`None` behind the
/// camera). Frames outside the take do not count; an offset that leaves fewer than half of them
/// gets no share.
pub fn scan_offsets(
    video_times: &[f64],
    masks: &[Mask],
    frame_time: f64,
    frame_count: usize,
    candidates: &[f64],
    joints_px: impl Fn(usize) -> Vec<Option<Vec2>>,
) -> Vec<(f64, Option<f64>)> {
    candidates
        .iter()
        .map(|&offset| {
            let (mut inside, mut total, mut frames) = (0usize, 0usize, 0usize);
            for (&t, mask) in video_times.iter().zip(masks) {
                let MocapTime::At(s) = mocap_frame_at(t, frame_time, frame_count, offset) else {
                    continue;
                };
                frames += 1;
                for p in joints_px(s) {
                    total += 1;
                    inside += p.is_some_and(|p| lands_on(mask, p, CHECK_RADIUS)) as usize;
                }
            }
            let share = (2 * frames >= video_times.len() && total > 0)
                .then(|| inside as f64 / total as f64);
            (offset, share)
        })
        .collect()
}

/// Segments the first frames of the imported dataset with the suit's segmenter and scans the clock
/// offsets within a second of `o.offset_s`; `None` when the suit has no segmenter yet (a damaged
/// one is an error).
fn check_alignment(
    o: &ImportOptions,
    suit: &SuitDefinition,
    motion: &Motion,
    camera: &Camera,
    video_times: &[f64],
) -> anyhow::Result<Option<AlignmentCheck>> {
    if !o
        .suit
        .join(suitcap::segment::tables::SEGMENTER_FILE)
        .exists()
    {
        return Ok(None);
    }
    let tables = suitcap::segment::SegmenterTables::load(o.suit)?;
    let joints = suit.skeleton.bind(&motion.skeleton)?;
    let frames = video_times.len().min(CHECK_FRAMES);
    let masks = super::segmenter_masks(&dataset::Dataset::open(o.out)?, suit, tables, frames)?;
    let joints_px = |s: usize| {
        let positions = motion.skeleton.joint_positions(motion.frame(s));
        joints
            .iter()
            .map(|&j| camera.project(positions[j]).map(|p| p.pixel))
            .collect()
    };
    let step = motion.frame_time.max(1.0 / 240.0);
    let reach = (1.0 / step).round() as i64;
    let candidates: Vec<f64> = (-reach..=reach)
        .map(|k| o.offset_s + k as f64 * step)
        .collect();
    let scanned = scan_offsets(
        &video_times[..frames],
        &masks,
        motion.frame_time,
        motion.frame_count(),
        &candidates,
        joints_px,
    );
    let given = scanned[reach as usize].1.unwrap_or(0.0);
    let (best_offset_s, best) = scanned
        .iter()
        .filter_map(|&(offset, share)| share.map(|s| (offset, s)))
        .fold(
            (o.offset_s, given),
            |best, c| if c.1 > best.1 { c } else { best },
        );
    Ok(Some(AlignmentCheck {
        frames,
        given,
        best_offset_s,
        best,
    }))
}

/// The name a mask of each video frame has: the frame file's stem + `.png` for a directory (as
/// `suitcap segment` writes them), the frame's index for a `.y4m` file.
fn mask_names(spec: &SourceSpec) -> anyhow::Result<Option<Vec<String>>> {
    Ok(match spec {
        SourceSpec::Directory(dir) => Some(png_names_of_frames(dir)?),
        _ => None,
    })
}

/// Copies a hand-made mask into the dataset as 8-bit grey PNG, checking its size.
fn copy_mask(from: &Path, to: &Path, size: (u32, u32)) -> anyhow::Result<()> {
    let mask = image::open(from)
        .with_context(|| format!("cannot read mask {}", from.display()))?
        .to_luma8();
    if mask.dimensions() != size {
        bail!(
            "{}: {}x{} mask for {}x{} frames",
            from.display(),
            mask.width(),
            mask.height(),
            size.0,
            size.1
        );
    }
    mask.save(to)
        .with_context(|| format!("cannot write {}", to.display()))
}

/// Imports a recording as a dataset (see the module documentation); nothing is a dataset in
/// `o.out` until its manifest, written last, is there.
pub fn import(o: &ImportOptions) -> anyhow::Result<ImportReport> {
    let suit = SuitDefinition::load_dir(o.suit)?;
    let motion = Motion::load(o.bvh)?;
    suit.skeleton.bind(&motion.skeleton).with_context(|| {
        format!(
            "{}: does not carry the suit's joints ({})",
            o.bvh.display(),
            o.suit.join(suitcap::suit::SUIT_FILE).display()
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

    // The output's frames/ and masks/ are replaced: the inputs must not be in them.
    if let Ok(out) = std::fs::canonicalize(o.out) {
        let inputs = [("--video", Some(Path::new(o.video))), ("--masks", o.masks)];
        for (flag, input) in inputs {
            let Some(input) = input.and_then(|p| std::fs::canonicalize(p).ok()) else {
                continue;
            };
            if ["frames", "masks"]
                .iter()
                .any(|sub| input.starts_with(out.join(sub)))
            {
                bail!(
                    "{flag} {}: inside {}'s frames/ or masks/, which the import replaces; give another --out",
                    input.display(),
                    o.out.display()
                );
            }
        }
    }
    dataset::prepare_dataset_dir(o.out, o.overwrite)?;
    let manifest_path = o.out.join("manifest.toml");

    let mut source_frames = Vec::new();
    let mut video_times = Vec::new();
    let mut first_video_frame = 0usize;
    let mut cut_at_end = false;
    let mut masks = 0usize;
    // Video frames that could not be read: (index, why); and the last one imported.
    let mut unreadable: Vec<(usize, String)> = Vec::new();
    let mut last_video_frame = 0usize;
    loop {
        let frame = match video.next_frame() {
            Ok(Some(frame)) => frame,
            Ok(None) => break,
            Err(e) => match e.skipped_frame() {
                // One bad frame leaves a gap in time, as a frame the camera dropped does.
                Some(index) => {
                    unreadable.push((index as usize, e.to_string()));
                    continue;
                }
                None => {
                    return Err(e).with_context(|| {
                        format!(
                            "{}: the video failed after {} imported frames",
                            o.video,
                            source_frames.len()
                        )
                    })
                }
            },
        };
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
                copy_mask(&from, &dataset::mask_path(o.out, k), (width, height))?;
                masks += 1;
            }
        }
        source_frames.push(mocap_frame);
        video_times.push(time);
        last_video_frame = index;
    }
    // Those before the mocap's start would have been left out anyway; those after the last
    // imported frame are named but leave no gap in the dataset.
    unreadable.retain(|&(index, _)| index >= first_video_frame);
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
            skipped_video_frames: unreadable
                .iter()
                .map(|&(index, _)| index)
                .filter(|&index| index < last_video_frame)
                .collect(),
            mocap_offset_s: o.offset_s,
            masks,
        }),
    };
    suitcap::io::write_atomic(&manifest_path, manifest.to_toml().as_bytes())
        .with_context(|| format!("cannot write {}", manifest_path.display()))?;
    let alignment = check_alignment(o, &suit, &motion, &camera, &video_times)?;
    Ok(ImportReport {
        alignment,
        frames: source_frames.len(),
        skipped_before: first_video_frame,
        unreadable: unreadable.into_iter().map(|(_, why)| why).collect(),
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

/// `seconds` rounded to the millisecond, without a negative zero: the scanned offsets are sums of
/// steps, so the one that is 0 may come out as −1e-17, printed "-0.000".
fn to_millisecond(seconds: f64) -> f64 {
    (seconds * 1000.0).round() / 1000.0 + 0.0
}

/// The command's output line.
pub fn summary(o: &ImportOptions, r: &ImportReport) -> String {
    let out: PathBuf = o.out.to_owned();
    format!(
        "imported {} frames of {} at {:.3} frames/s with mocap frames {}..={} of {} (offset {} s){}{}{}; {}; dataset written to {}",
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
        match r.unreadable.len() {
            0 => String::new(),
            n => format!(
                ", {n} video frames that could not be read left out (the others keep their mocap frames; below)"
            ),
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
    ) + &r
        .unreadable
        .iter()
        .map(|why| format!("\n  left out: {why}"))
        .collect::<String>()
        + &match &r.alignment {
        None => "\nthe suit has no segmenter yet: the pairing of video and mocap was not checked".to_owned(),
        Some(a) => {
            let mut line = format!(
                "\npairing check on the first {} frames: {:.1} % of the suit's joints land on the segmented person at --offset {} s; the best offset within ±1 s is {:.3} s ({:.1} %)",
                a.frames,
                100.0 * a.given,
                o.offset_s,
                to_millisecond(a.best_offset_s),
                100.0 * a.best
            );
            if a.best < 0.5 {
                line += "\nwarning: the mocap does not land on the segmented person at any offset within ±1 s: check camera.toml and --offset, and that the suit's segmenter finds the person (suitcap segment)";
            } else if a.best > a.given + 0.05 {
                line += &format!(
                    "\nwarning: the mocap fits the video clearly better at another offset: check --offset (e.g. import again with --offset {:.3} --overwrite) and camera.toml",
                    to_millisecond(a.best_offset_s)
                );
            }
            line
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use suitcap::dataset::Dataset;

    fn repo(path: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(path)
    }

    /// A 6-frame 320 × 240 generated dataset standing in for a recording: its frames are the video, its
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
                width: 320,
                height: 240,
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
    fn offsets_print_without_a_negative_zero() {
        let scanned = -0.1 + 3.0 * (1.0 / 30.0);
        assert_eq!(format!("{:.3}", to_millisecond(scanned)), "0.000");
        assert_eq!(to_millisecond(-0.2504), -0.25);
    }

    #[test]
    fn a_joint_lands_within_the_radius() {
        let mask = Mask::from_fn(20, 20, |x, y| (x, y) == (10, 10));
        assert!(lands_on(&mask, Vec2::new(10.5, 10.5), 0));
        assert!(lands_on(&mask, Vec2::new(14.9, 6.0), CHECK_RADIUS));
        assert!(!lands_on(&mask, Vec2::new(15.0, 10.5), CHECK_RADIUS));
        assert!(!lands_on(&mask, Vec2::new(-30.0, 10.5), CHECK_RADIUS));
    }

    #[test]
    fn the_scan_finds_the_offset_at_which_the_joints_follow_the_person() {
        // Five frames 0.1 s apart; in frame k the person is the column x = 10k (64 × 8 masks). The
        // mocap (0.1 s frames, 8 of them) has its one joint at x = 10(s − 2) + 0.5 in frame s, so
        // video frame k shows mocap frame k + 2: the clocks are 0.2 s apart.
        let times: Vec<f64> = (0..5).map(|k| k as f64 * 0.1).collect();
        let masks: Vec<Mask> = (0..5)
            .map(|k| Mask::from_fn(64, 8, |x, _| x == 10 * k))
            .collect();
        let joint = |s: usize| vec![Some(Vec2::new(10.0 * (s as f32 - 2.0) + 0.5, 4.0))];
        let candidates = [-0.3, 0.1, 0.2, 0.3];
        let scanned = scan_offsets(&times, &masks, 0.1, 8, &candidates, joint);
        let shares: Vec<Option<f64>> = scanned.iter().map(|&(_, s)| s).collect();
        // At −0.3 s only two of the five frames are within the take: no share.
        assert_eq!(shares, vec![None, Some(0.0), Some(1.0), Some(0.0)]);
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
        // The pairing check: one frame off still puts the slow walk's joints on the person.
        let check = report
            .alignment
            .as_ref()
            .expect("the default suit has a segmenter");
        assert!(check.given > 0.9 && check.best >= check.given, "{check:?}");
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
        let mut writer = Y4mWriter::create(&video, 320, 240, 15.0, Y4mChroma::C444).expect("y4m");
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
    fn an_unreadable_video_frame_is_left_out_and_the_others_keep_their_mocap_frames() {
        let r = Recording::new();
        let video = r.tmp.path().join("video");
        std::fs::create_dir_all(&video).expect("dir");
        for k in 0..6 {
            let name = format!("{k:06}.png");
            std::fs::copy(r.rec.frame_path(k), video.join(&name)).expect("copy");
        }
        // Frame 2 cut short, as a copy interrupted or a camera that lost the frame's end.
        let bytes = std::fs::read(video.join("000002.png")).expect("read");
        std::fs::write(video.join("000002.png"), &bytes[..bytes.len() / 2]).expect("cut");
        let video_name = video.to_string_lossy().into_owned();
        let out = r.tmp.path().join("out");
        let mut o = r.options(&out);
        o.video = &video_name;
        let report = import(&o).expect("imports the others");
        assert_eq!((report.frames, report.skipped_before), (5, 0));
        assert_eq!(report.unreadable.len(), 1);
        assert!(
            report.unreadable[0].contains("000002.png"),
            "{:?}",
            report.unreadable
        );
        assert!(summary(&o, &report).contains("1 video frames that could not be read left out"));
        let imported = Dataset::open(&out).expect("a dataset");
        assert_eq!(imported.manifest.clip.source_frames, vec![0, 1, 3, 4, 5]);
        let recording = imported.manifest.recording.as_ref().expect("recorded");
        assert_eq!(recording.skipped_video_frames, vec![2]);
        assert_eq!(imported.motion.frame(2), r.rec.motion.frame(3));
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
            err.contains("camera.toml") && err.contains("640x480") && err.contains("320x240"),
            "{err}"
        );
        // A hand-made mask of another size.
        let masks = tmp.path().join("labelled");
        std::fs::create_dir_all(&masks).expect("dir");
        image::GrayImage::new(10, 10)
            .save(masks.join("000000.png"))
            .expect("mask");
        let mut o = r.options(&out);
        o.masks = Some(&masks);
        let err = format!("{:#}", import(&o).unwrap_err());
        assert!(
            err.contains("000000.png") && err.contains("10x10 mask"),
            "{err}"
        );
        // An output that holds the video.
        let mut o = r.options(&r.rec.root);
        o.overwrite = true;
        let err = format!("{:#}", import(&o).unwrap_err());
        assert!(
            err.contains("--video") && err.contains("another --out"),
            "{err}"
        );
        assert!(r.rec.frame_path(0).is_file(), "the video is untouched");
        // A camera is not a recording.
        let mut o = r.options(&out);
        o.video = "/dev/video0";
        let err = format!("{:#}", import(&o).unwrap_err());
        assert!(err.contains("suitcap capture"), "{err}");
        // Nothing was written for any of them.
        assert!(!out.join("manifest.toml").exists());
    }
}
