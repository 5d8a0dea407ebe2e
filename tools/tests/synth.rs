//! End-to-end checks of the generator: determinism, the dataset it writes, and clear errors.

use std::path::{Path, PathBuf};

use suitcap::dataset::Dataset;
use suitcap_tools::synth::{generate, SynthOptions};

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(path)
}

fn options(out: &Path, seed: u64) -> SynthOptions {
    SynthOptions {
        frames: Some(6),
        width: 160,
        height: 120,
        seed,
        ..SynthOptions::new(
            repo("tests/data/mocap/cmu_02_01_walk.bvh"),
            out.to_owned(),
            repo("suits/default"),
            vec![repo("tests/data/backgrounds")],
        )
    }
}

fn files(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    for sub in ["frames", "masks"] {
        let mut entries: Vec<PathBuf> = std::fs::read_dir(dir.join(sub))
            .expect("dir")
            .map(|e| e.expect("entry").path())
            .collect();
        entries.sort();
        for path in entries {
            let bytes = std::fs::read(&path).expect("read");
            out.push((path.strip_prefix(dir).expect("prefix").to_owned(), bytes));
        }
    }
    for name in ["motion.bvh", "camera.toml", "markers.csv", "manifest.toml"] {
        out.push((
            PathBuf::from(name),
            std::fs::read(dir.join(name)).expect("read"),
        ));
    }
    out
}

#[test]
fn the_same_seed_gives_byte_identical_output() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let (a, b, c) = (
        tmp.path().join("a"),
        tmp.path().join("b"),
        tmp.path().join("c"),
    );
    generate(&options(&a, 7), &|| {}).expect("first run");
    generate(&options(&b, 7), &|| {}).expect("second run");
    generate(&options(&c, 8), &|| {}).expect("other seed");
    let (fa, fb, fc) = (files(&a), files(&b), files(&c));
    assert_eq!(fa.len(), 6 + 6 + 4);
    assert_eq!(fa, fb, "same seed, different bytes");
    let frame_differs = fa
        .iter()
        .zip(&fc)
        .any(|(x, y)| x.0.starts_with("frames") && x.1 != y.1);
    assert!(frame_differs, "another seed should render different frames");
}

#[test]
fn the_dataset_reopens_and_is_aligned_with_the_clip() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().join("d");
    generate(&options(&out, 3), &|| {}).expect("generate");
    let dataset = Dataset::open(&out).expect("dataset opens");
    assert_eq!(dataset.frame_count(), 6);
    assert_eq!(dataset.motion.frame_count(), 6);
    // 120 frames/s → 30 frames/s: every fourth source frame from the start frame.
    assert_eq!(
        dataset.manifest.clip.source_frames,
        vec![12, 16, 20, 24, 28, 32]
    );
    let clip =
        suitcap::bvh::Motion::load(&repo("tests/data/mocap/cmu_02_01_walk.bvh")).expect("clip");
    // Joint angles are the clip's (only the root translation and the offsets are scaled).
    let k = 3;
    let source = clip.frame(dataset.manifest.clip.source_frames[k]);
    for (channel, (a, b)) in dataset
        .motion
        .frame(k)
        .iter()
        .zip(source)
        .enumerate()
        .skip(3)
    {
        assert!((a - b).abs() < 1e-4, "channel {channel}: {a} vs {b}");
    }
    let markers = dataset.markers().expect("markers.csv");
    assert!(!markers.is_empty());
    assert!(markers
        .iter()
        .all(|m| m.frame < 6 && (0.0..=1.0).contains(&m.visible_fraction)));
    let mask = image::open(dataset.mask_path(0)).expect("mask").to_luma8();
    assert_eq!(mask.dimensions(), (160, 120));
    assert!(mask.pixels().all(|p| p.0[0] == 0 || p.0[0] == 255));
    assert!(mask.pixels().filter(|p| p.0[0] == 255).count() > 200);
    // A second run into the same folder must be asked for.
    let err = generate(&options(&out, 3), &|| {}).expect_err("refuses to overwrite");
    assert!(err.to_string().contains("--overwrite"), "{err}");
}

#[test]
fn absent_frames_show_the_room_alone() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let (with, without) = (tmp.path().join("with"), tmp.path().join("without"));
    generate(&options(&with, 4), &|| {}).expect("person throughout");
    let absent = SynthOptions {
        absent: vec![0..2, 4..5],
        ..options(&without, 4)
    };
    generate(&absent, &|| {}).expect("person absent in frames 0, 1 and 4");
    let (a, b) = (
        Dataset::open(&with).expect("opens"),
        Dataset::open(&without).expect("opens"),
    );
    let person = |d: &Dataset, k: usize| {
        let mask = image::open(d.mask_path(k)).expect("mask").to_luma8();
        mask.pixels().filter(|p| p.0[0] == 255).count()
    };
    let marked: Vec<usize> = b
        .markers()
        .expect("markers")
        .iter()
        .map(|m| m.frame)
        .collect();
    for k in 0..6 {
        let gone = [0, 1, 4].contains(&k);
        assert_eq!(person(&b, k) == 0, gone, "frame {k}");
        assert_eq!(marked.contains(&k), !gone, "frame {k}");
        assert_eq!(
            person(&b, k),
            if gone { 0 } else { person(&a, k) },
            "frame {k}"
        );
        // Where the person is, the frame is the one rendered with them throughout.
        let frame = |d: &Dataset| std::fs::read(d.frame_path(k)).expect("frame");
        assert_eq!(frame(&a) == frame(&b), !gone, "frame {k}");
    }
    let late = SynthOptions {
        absent: vec![std::ops::Range { start: 6, end: 9 }],
        ..options(&tmp.path().join("late"), 4)
    };
    let err = format!("{:#}", generate(&late, &|| {}).expect_err("past the end"));
    assert!(
        err.contains("--absent 6..9") && err.contains("6 frames"),
        "{err}"
    );
}

#[test]
fn bad_clips_are_clear_errors() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let text = std::fs::read_to_string(repo("tests/data/mocap/cmu_09_01_run.bvh")).expect("clip");

    let renamed = tmp.path().join("renamed.bvh");
    std::fs::write(&renamed, text.replace("JOINT rShin", "JOINT rKnee")).expect("write");
    let mut o = options(&tmp.path().join("x"), 1);
    o.bvh = renamed;
    let err = format!("{:#}", generate(&o, &|| {}).expect_err("unknown joint"));
    assert!(
        err.contains("rShin") && err.contains("renamed.bvh"),
        "{err}"
    );

    let truncated = tmp.path().join("truncated.bvh");
    std::fs::write(&truncated, &text[..text.len() / 2]).expect("write");
    o.bvh = truncated;
    let err = format!("{:#}", generate(&o, &|| {}).expect_err("truncated"));
    assert!(err.contains("truncated.bvh"), "{err}");

    o.bvh = repo("tests/data/mocap/cmu_09_01_run.bvh");
    o.frames = Some(500);
    let err = format!("{:#}", generate(&o, &|| {}).expect_err("too long"));
    assert!(err.contains("at most"), "{err}");

    o.frames = Some(2);
    o.subject = Some("nobody".into());
    let err = format!("{:#}", generate(&o, &|| {}).expect_err("unknown subject"));
    assert!(err.contains("nobody") && err.contains("ana"), "{err}");
    assert!(!tmp.path().join("x").join("manifest.toml").exists());
}
