//! The runtime binary end to end with the shipped default suit: a generated clip in, a BVH take out,
//! one BVH frame per input frame, readable again; `segment` with and without the part memory and the
//! person's part colours; `describe`'s rows; and clear errors for a broken model, setting or
//! directory.

use std::path::{Path, PathBuf};
use std::process::Command;

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn suitcap() -> Command {
    Command::new(env!("CARGO_BIN_EXE_suitcap"))
}

/// `suitcap SUBCOMMAND --suit suits/default --input DATA/frames`, for the options that follow.
fn on_the_frames_of(subcommand: &str, data: &Path) -> Command {
    let mut command = suitcap();
    command
        .args([subcommand, "--suit"])
        .arg(repo("suits/default"))
        .arg("--input")
        .arg(data.join("frames"));
    command
}

/// The command's stdout, after checking that it succeeded (its stderr is the failure message).
fn succeeded(output: std::process::Output) -> String {
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// Renders a 12-frame dataset with the workspace's `suitcap-synth` binary (the tools crate depends on
/// this one, so its library is not reachable from here; the test command builds the workspace first).
fn generated_clip(dir: &Path) -> PathBuf {
    let synth = Path::new(env!("CARGO_BIN_EXE_suitcap")).with_file_name("suitcap-synth");
    let status = Command::new(&synth)
        .args([
            "--bvh",
            repo("tests/data/mocap/cmu_13_39_jump.bvh")
                .to_str()
                .expect("utf-8 path"),
        ])
        .args(["--frames", "12", "--seed", "3", "--out"])
        .arg(dir)
        .status();
    match status {
        Ok(s) if s.success() => dir.to_owned(),
        _ => panic!(
            "cannot run {} (build the workspace: cargo test --workspace)",
            synth.display()
        ),
    }
}

#[test]
fn run_writes_one_bvh_frame_per_input_frame() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let data = generated_clip(&tmp.path().join("clip"));
    let out = tmp.path().join("out");
    succeeded(
        suitcap()
            .args(["run"])
            .arg(data.join("frames"))
            .args([
                "--suit",
                repo("suits/default").to_str().expect("utf-8 path"),
                "--out",
            ])
            .arg(&out)
            .output()
            .expect("runs"),
    );
    let take = suitcap::bvh::Motion::load(&out.join("take.bvh")).expect("a valid BVH");
    assert_eq!(take.frame_count(), 12);
    assert!((take.frame_rate() - 30.0).abs() < 1e-3);
    let rows = std::fs::read_to_string(out.join("frames.csv")).expect("frames.csv");
    assert_eq!(rows.lines().count(), 13);
    // The estimated angles are close to the truth on this clip (a loose bound: the regressor's
    // measured error is in the README).
    let truth = suitcap::bvh::Motion::load(&data.join("motion.bvh")).expect("truth");
    let suit = suitcap::suit::SuitDefinition::load_dir(&repo("suits/default")).expect("suit");
    let layout = suitcap::pose::PoseLayout::new(&suit.skeleton, &truth.skeleton).expect("layout");
    let mut errors = suitcap::pose::eval::JointErrors::new(
        suit.skeleton
            .joints
            .iter()
            .map(|j| j.name.clone())
            .collect(),
    );
    for k in 0..12 {
        errors.add(&layout, truth.frame(k), take.frame(k));
    }
    assert!(
        errors.mean_euler() < 30.0,
        "mean error {:.1}°",
        errors.mean_euler()
    );

    // The same clip as `suitcap capture` writes it when the camera dropped frame 5: the files
    // numbered densely, the gap only in `timestamps.csv`. By default the take has one BVH frame
    // per input frame (11); on the capture's time (`--camera-time`) one per 1/30 s, frame 5
    // filled in (12).
    let captured = tmp.path().join("captured");
    std::fs::create_dir_all(&captured).expect("mkdir");
    let mut times = String::from("file,seconds\n");
    for (written, k) in (0..12).filter(|&k| k != 5).enumerate() {
        let name = format!("{written:06}.png");
        std::fs::copy(
            data.join(format!("frames/{k:06}.png")),
            captured.join(&name),
        )
        .expect("copy");
        times += &format!("{name},{:.6}\n", k as f64 / 30.0);
    }
    std::fs::write(captured.join("timestamps.csv"), times).expect("timestamps");
    for (extra, frames) in [(None, 11), (Some("--camera-time"), 12)] {
        let out = tmp.path().join(format!("out_captured_{frames}"));
        let printed = succeeded(
            suitcap()
                .args(["run"])
                .arg(&captured)
                .args([
                    "--suit",
                    repo("suits/default").to_str().expect("utf-8 path"),
                    "--camera",
                ])
                .arg(data.join("camera.toml"))
                .arg("--out")
                .arg(&out)
                .args(extra)
                .output()
                .expect("runs"),
        );
        let take = suitcap::bvh::Motion::load(&out.join("take.bvh")).expect("a valid BVH");
        assert_eq!(take.frame_count(), frames, "{printed}");
        assert_eq!(
            printed.contains("; 1 BVH frame filled in"),
            frames == 12,
            "{printed}"
        );
        // frames.csv names each input frame's time and BVH frame: the file after the gap
        // (input frame 5, taken at 6/30 s) is BVH frame 6 on the capture's time.
        let rows = std::fs::read_to_string(out.join("frames.csv")).expect("frames.csv");
        let row = rows.lines().find(|l| l.starts_with("5,")).expect("row 5");
        let bvh_frame = if frames == 12 {
            ",0.200000,6,0"
        } else {
            ",0.200000,5,0"
        };
        assert!(row.ends_with(bvh_frame), "{row}");
    }
}

#[test]
fn eval_writes_the_per_joint_table_and_its_bar_chart() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let data = generated_clip(&tmp.path().join("clip"));
    let train = Path::new(env!("CARGO_BIN_EXE_suitcap")).with_file_name("suitcap-train");
    let (csv, chart, json) = (
        tmp.path().join("joints.csv"),
        tmp.path().join("joints.png"),
        tmp.path().join("eval.json"),
    );
    let table = succeeded(
        Command::new(&train)
            .args([
                "eval",
                "--suit",
                repo("suits/default").to_str().expect("utf-8 path"),
                "--data",
            ])
            .arg(&data)
            .arg("--csv")
            .arg(&csv)
            .arg("--chart")
            .arg(&chart)
            .arg("--json")
            .arg(&json)
            .output()
            .expect("runs (the test command builds the workspace first)"),
    );
    assert!(table.contains("(12 frames, masks: segmenter;"), "{table}");
    // A header, a row per joint of the printed table, and the mean; the root has no position
    // error (it is aligned), every other joint one in centimetres.
    let rows = std::fs::read_to_string(&csv).expect("the CSV");
    let lines: Vec<&str> = rows.lines().collect();
    assert_eq!(lines[0], "joint,euler_deg,geodesic_deg,position_cm");
    assert!(lines[1].ends_with(','), "{rows}");
    for row in &lines[2..] {
        let cm: f64 = row
            .rsplit(',')
            .next()
            .unwrap_or_default()
            .parse()
            .expect("cm");
        assert!((0.0..100.0).contains(&cm), "{row}");
    }
    assert!(
        lines.last().is_some_and(|l| l.starts_with("mean,")),
        "{rows}"
    );
    let printed: Vec<&str> = table
        .lines()
        .skip_while(|l| !l.starts_with("joint "))
        .skip(1)
        .collect();
    assert_eq!(lines.len() - 1, printed.len(), "{table}");
    for (row, line) in lines[1..].iter().zip(&printed) {
        let name = row.split(',').next().unwrap_or_default();
        assert!(line.starts_with(&format!("{name} ")), "{row} / {line}");
    }
    let image = image::open(&chart).expect("a PNG").to_rgb8();
    assert!(image.width() > 600 && image.height() > 400);
    // The Euler series' blue is drawn somewhere.
    assert!(image.pixels().any(|p| p.0 == [0x1f, 0x77, 0xb4]));
    // The JSON holds the figures the console printed: the means, a row per joint, and the take
    // as `run` writes it (the shipped suit has joint limits, so `run`'s filter is among those
    // evaluated).
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).expect("the JSON")).expect("JSON");
    assert_eq!(report["masks"], "segmenter");
    assert_eq!(report["frames"], 12);
    let degrees = |value: &serde_json::Value| format!("{:.2}°", value.as_f64().expect("a number"));
    let mean = printed.last().expect("the mean row");
    assert!(
        mean.contains(&degrees(&report["mean_euler_deg"]).replace('°', "")),
        "{mean} / {report}"
    );
    assert_eq!(
        report["joints"].as_array().map(Vec::len),
        Some(printed.len() - 1)
    );
    assert!(report["joints"][0]["position_cm"].is_null(), "{report}");
    let take = &report["recorded_take"];
    let line = table
        .lines()
        .find(|l| l.contains("then smoothed back as `run` writes"))
        .expect("the take's line");
    assert!(
        line.contains(&format!("{} (Euler)", degrees(&take["mean_euler_deg"]))),
        "{line} / {take}"
    );
    let filtered = report["filtered"].as_array().expect("the filters");
    assert!(!filtered.is_empty(), "{report}");
    for variant in filtered {
        let label = variant["variant"].as_str().expect("a name");
        assert!(
            table.contains(&format!(
                "  with {label}: {} (Euler)",
                degrees(&variant["mean_euler_deg"])
            )),
            "{label} / {table}"
        );
    }
}

/// A suit directory `dir/suit` holding the shipped suit's definition and `models` (no manifest).
fn copied_suit(dir: &Path, models: &[&str]) -> PathBuf {
    let suit = dir.join("suit");
    std::fs::create_dir(&suit).expect("mkdir");
    for name in std::iter::once(&"suit.toml").chain(models) {
        std::fs::copy(repo("suits/default").join(name), suit.join(name)).expect("copy");
    }
    suit
}

#[test]
fn exemplars_are_written_for_a_trained_suit_and_recorded_in_its_manifest() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let mut models = MODEL_FILES_BUT_THE_REGRESSOR.to_vec();
    models.extend(["regressor.bin", "model.toml"]);
    // The shipped suit without its exemplars, as a suit trained before them.
    let suit = copied_suit(tmp.path(), &models);
    let manifest = std::fs::read_to_string(suit.join("model.toml")).expect("the manifest");
    let without: String = manifest
        .lines()
        .filter(|l| !l.contains("exemplars.bin"))
        .map(|l| format!("{l}\n"))
        .collect();
    assert_ne!(
        without, manifest,
        "the shipped manifest records the exemplars"
    );
    std::fs::write(suit.join("model.toml"), without).expect("write");
    let check = || {
        succeeded(
            suitcap()
                .args(["check", "--suit"])
                .arg(&suit)
                .output()
                .expect("runs"),
        )
    };
    let before = check();
    assert!(
        before.contains("no exemplars") && before.contains("(6 checksums match)"),
        "{before}"
    );
    let data = generated_clip(&tmp.path().join("clip"));
    let train = Path::new(env!("CARGO_BIN_EXE_suitcap")).with_file_name("suitcap-train");
    let write_exemplars = || {
        succeeded(
            Command::new(&train)
                .args(["exemplars", "--suit"])
                .arg(&suit)
                .arg("--data")
                .arg(&data)
                .output()
                .expect("runs"),
        )
    };
    let printed = write_exemplars();
    // Twelve frames with the person: every 8th, frames 0 and 8.
    assert!(
        printed.starts_with("2 exemplars (every 8th of 12 training frames"),
        "{printed}"
    );
    let after = check();
    assert!(
        after.contains("2 exemplars") && after.contains("(7 checksums match)"),
        "{after}"
    );
    // A broken exemplars file is named, and writing the exemplars again mends it.
    let file = suit.join("exemplars.bin");
    let bytes = std::fs::read(&file).expect("read");
    std::fs::write(&file, &bytes[..bytes.len() / 2]).expect("write");
    let broken = suitcap()
        .args(["check", "--suit"])
        .arg(&suit)
        .output()
        .expect("runs");
    assert!(!broken.status.success());
    let stderr = String::from_utf8_lossy(&broken.stderr);
    assert!(stderr.contains("exemplars.bin"), "{stderr}");
    write_exemplars();
    assert_eq!(check(), after);
}

const MODEL_FILES_BUT_THE_REGRESSOR: [&str; 5] = [
    "segmenter.bin",
    "codebook_fc.bin",
    "codebook_hog.bin",
    "codebook_silhouette.bin",
    "skeleton.bvh",
];

#[test]
fn a_truncated_model_file_is_a_clear_error() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let suit = copied_suit(tmp.path(), &MODEL_FILES_BUT_THE_REGRESSOR);
    let bytes = std::fs::read(repo("suits/default/regressor.bin")).expect("read");
    std::fs::write(suit.join("regressor.bin"), &bytes[..bytes.len() / 3]).expect("write");
    let data = generated_clip(&tmp.path().join("clip"));
    let names_the_regressor = |output: std::process::Output| {
        assert!(!output.status.success());
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(
            stderr.contains("regressor.bin") && stderr.contains("truncated"),
            "{stderr}"
        );
    };
    names_the_regressor(
        suitcap()
            .args(["run"])
            .arg(data.join("frames"))
            .arg("--suit")
            .arg(&suit)
            .arg("--out")
            .arg(tmp.path().join("out"))
            .output()
            .expect("runs"),
    );
    // `check` finds it before any frame is read.
    names_the_regressor(
        suitcap()
            .args(["check", "--suit"])
            .arg(&suit)
            .output()
            .expect("runs"),
    );
}

#[test]
fn a_model_file_that_is_not_the_one_the_manifest_records_is_refused_by_name() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let suit = copied_suit(tmp.path(), &MODEL_FILES_BUT_THE_REGRESSOR);
    std::fs::copy(
        repo("suits/default/regressor.bin"),
        suit.join("regressor.bin"),
    )
    .expect("copy");
    // A manifest whose regressor is another one than the suit's (a stage re-run after it).
    let mut files = suitcap::manifest::record_files(&suit).expect("checksums");
    files.insert("regressor.bin".into(), "0123456789abcdef".into());
    let manifest = suitcap::manifest::Manifest {
        format: suitcap::manifest::MANIFEST_FORMAT,
        tool: "test".into(),
        descriptor: "fc+hog+box".into(),
        rotations: "matrix".into(),
        basis_candidates: 1,
        relevance_vectors: 1,
        kernel_width: 1.0,
        noise: 1.0,
        training_frames: 1,
        dataset_paths: Vec::new(),
        datasets: Vec::new(),
        files,
    };
    std::fs::write(suit.join("model.toml"), manifest.to_toml().expect("toml")).expect("write");
    let output = suitcap()
        .args(["check", "--suit"])
        .arg(&suit)
        .output()
        .expect("runs");
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("regressor.bin: not the file") && stderr.contains("model.toml"),
        "{stderr}"
    );
    // With the right checksum the same suit passes.
    std::fs::write(
        suit.join("model.toml"),
        suitcap::manifest::Manifest {
            files: suitcap::manifest::record_files(&suit).expect("checksums"),
            ..manifest
        }
        .to_toml()
        .expect("toml"),
    )
    .expect("write");
    let passed = succeeded(
        suitcap()
            .args(["check", "--suit"])
            .arg(&suit)
            .output()
            .expect("runs"),
    );
    assert!(passed.contains("6 checksums match"), "{passed}");
}

#[test]
fn check_loads_the_trained_models() {
    let check = |suit: &Path| {
        succeeded(
            suitcap()
                .args(["check", "--suit"])
                .arg(suit)
                .output()
                .expect("runs"),
        )
    };
    let shipped = check(&repo("suits/default"));
    assert!(
        shipped.contains("trained models load") && shipped.contains("relevance vectors"),
        "{shipped}"
    );
    // Its files are the ones `train.sh` left (the exemplars written by `suitcap-train exemplars`
    // since), as its manifest records them.
    assert!(shipped.contains("(7 checksums match)"), "{shipped}");
    assert!(shipped.contains(" exemplars)"), "{shipped}");
    // A suit defined but not trained yet is fine, and says what to do; so is one part-way through
    // training (the segmenter only).
    let tmp = tempfile::tempdir().expect("tempdir");
    let add = |file: &str| {
        std::fs::copy(repo("suits/default").join(file), tmp.path().join(file)).expect("copy");
        check(tmp.path())
    };
    let untrained = add("suit.toml");
    assert!(
        untrained.contains("not trained yet: segmenter.bin, codebook_*.bin, regressor.bin"),
        "{untrained}"
    );
    let part = add("segmenter.bin");
    assert!(
        part.contains("trained models load: segmenter tables (trained on frames 480 rows high, cut at 1/2; σ_C 1, σ_N 0.03125, σ_G 1, σ_M 1, σ_T 1)\n")
            && part.contains("not trained yet: codebook_*.bin, regressor.bin"),
        "{part}"
    );
    assert!(!shipped.contains("not trained yet"), "{shipped}");
}

#[test]
fn segment_masks_every_frame_with_or_without_the_part_memory_and_colours_and_rejects_bad_settings()
{
    let tmp = tempfile::tempdir().expect("tempdir");
    let data = generated_clip(&tmp.path().join("clip"));
    let all_masks = data.join("masks");
    let segment = |out: &Path, truth: &Path, extra: &[&str]| {
        on_the_frames_of("segment", &data)
            .arg("--truth")
            .arg(truth)
            .arg("--out")
            .arg(out)
            .args(extra)
            .output()
            .expect("runs")
    };
    for (name, extra) in [
        ("remembering", &[][..]),
        ("plain", &["--part-memory", "0"][..]),
        ("no last look", &["--part-look", "0"][..]),
        ("trained colours", &["--part-colours", "0"][..]),
        ("marker colours kept", &["--keep-room-share", "2"][..]),
        ("cloth anywhere", &["--cloth-reach", "0"][..]),
        ("outline not unmixed", &["--no-unmix"][..]),
        ("first frame once", &["--first-frame-passes", "1"][..]),
        ("no suit holes filled", &["--suit-holes", "0"][..]),
        ("band kept out of the room", &["--room-band-odds=-inf"][..]),
        ("no second look when empty", &["--no-lost-retry"][..]),
    ] {
        let out = tmp.path().join(name);
        let report = succeeded(segment(&out, &all_masks, extra));
        assert!(report.contains("IoU against"), "{report}");
        assert!(
            report.contains("0 frames found empty with much of the suit in view"),
            "{report}"
        );
        let masks = std::fs::read_dir(&out).expect("masks written").count();
        assert_eq!(masks, 12, "{name}");
    }
    let out = tmp.path().join("bad");
    for (bad, flag) in [
        (&["--part-memory=-1"][..], "--part-memory"),
        (&["--part-look", "inf"][..], "--part-look"),
        (&["--part-colours", "1.5"][..], "--part-colours"),
        (&["--keep-room-share", "NaN"][..], "--keep-room-share"),
        (&["--cloth-reach=-24"][..], "--cloth-reach"),
        (&["--first-frame-passes", "0"][..], "--first-frame-passes"),
        (&["--suit-holes=-2"][..], "--suit-holes"),
        (&["--room-band-odds", "NaN"][..], "--room-band-odds"),
    ] {
        let output = segment(&out, &all_masks, bad);
        assert!(!output.status.success(), "{bad:?}");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(stderr.contains(flag), "{stderr}");
        assert!(!out.exists(), "nothing written for a bad setting");
    }
    // A truth directory that is not there (a typo) is an error, not 12 frames "not scored".
    let output = segment(&out, &tmp.path().join("no_such_masks"), &[]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        !output.status.success() && stderr.contains("--truth"),
        "{stderr}"
    );
    assert!(
        !out.exists(),
        "nothing written for a missing truth directory"
    );
    // Truth masks of a few frames only (as hand-labelled ones are): those frames are scored.
    let few = tmp.path().join("labelled");
    std::fs::create_dir_all(&few).expect("dir");
    for k in 0..5 {
        let name = format!("{k:06}.png");
        std::fs::copy(data.join("masks").join(&name), few.join(&name)).expect("copy");
    }
    // One of them labelled as nobody: reported apart from the IoU, with what the segmenter found.
    let labelled = image::open(few.join("000003.png"))
        .expect("mask")
        .to_luma8();
    image::GrayImage::new(labelled.width(), labelled.height())
        .save(few.join("000003.png"))
        .expect("empty mask");
    let report = succeeded(segment(&tmp.path().join("few"), &few, &[]));
    assert!(
        report.contains("IoU against") && report.contains("7 frames not scored"),
        "{report}"
    );
    assert!(
        report.contains("1 frame with nobody in the truth (not in the IoU): 0 given an empty mask")
            && report.contains("(000003.png)"),
        "{report}"
    );
    // A truth mask of another size is named, not scored as if it fitted.
    image::GrayImage::new(10, 10)
        .save(few.join("000002.png"))
        .expect("mask");
    let output = segment(&tmp.path().join("wrong"), &few, &[]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success(), "{stderr}");
    assert!(
        stderr.contains("000002.png") && stderr.contains("10x10 truth mask"),
        "{stderr}"
    );
}

#[test]
fn describe_writes_a_row_per_frame_and_names_a_missing_mask_directory() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let data = generated_clip(&tmp.path().join("clip"));
    let describe = |masks: &Path, out: &Path| {
        on_the_frames_of("describe", &data)
            .arg("--masks")
            .arg(masks)
            .arg("--out")
            .arg(out)
            .output()
            .expect("runs")
    };
    let out = tmp.path().join("descriptors.csv");
    succeeded(describe(&data.join("masks"), &out));
    let csv = std::fs::read_to_string(&out).expect("descriptors written");
    // A header and one row per frame, each with the frame's name and 304 values after the flag.
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 13, "{csv}");
    assert!(lines[1..].iter().all(|l| l.split(',').count() == 2 + 304));
    // A mask directory that is not there (a typo) is named, before anything is written; it was
    // reported as frame 0's missing mask.
    let missing = tmp.path().join("no_such_masks");
    let out = tmp.path().join("none.csv");
    let output = describe(&missing, &out);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        !output.status.success() && stderr.contains("--masks") && stderr.contains("no_such_masks"),
        "{stderr}"
    );
    assert!(
        !out.exists(),
        "nothing written for a missing mask directory"
    );
}
