//! Fuzz-style property tests: the readers of user and model files never panic, whatever the bytes.
//!
//! Covered, through the public API only: the BVH reader ([`Motion::parse`], and what the runtime does
//! with a motion it accepted), the model container ([`ModelFile::decode`]) and the loaders built on
//! it ([`Regressor::load`], [`Codebook::load`] / [`Codebooks::load`], [`SegmenterTables::load`]), the
//! Y4M reader ([`Y4mReader`], [`Y4mSource`]) and the joint limits file ([`JointLimits::parse`]).
//! Inputs are fully random bytes, every truncation of a small valid file, byte flips, insertions and
//! deletions in valid files, random token soups for the text formats, and for model files flips that
//! keep the checksum valid and edits of the decoded arrays (shapes, names, missing arrays) re-encoded,
//! so the loaders' shape checks are reached and not only the checksum. Each check only asks that the
//! call returns (Ok or Err) instead of panicking; proptest reports the smallest failing input.
//!
//! Run: `cargo test --release --test fuzz` (about 10–20 s on two cores).

use std::io::Cursor;
use std::path::{Path, PathBuf};

use proptest::prelude::*;
use proptest::test_runner::Config;

use suitcap::bvh::Motion;
use suitcap::descriptor::codebook::{codebook_path, Codebook};
use suitcap::descriptor::{Codebooks, HOG_CENTRES, HOG_CODEBOOK, HOG_CODEBOOK_VERSION};
use suitcap::model::ModelFile;
use suitcap::pose::regressor::{
    Regressor, REGRESSOR_FILE, REGRESSOR_KIND, REGRESSOR_VERSION, SKELETON_FILE,
};
use suitcap::pose::smoothing::JointLimits;
use suitcap::segment::tables::{
    SegmenterTables, SEGMENTER_FILE, SEGMENTER_KIND, SEGMENTER_VERSION,
};
use suitcap::source::y4m::{Y4mChroma, Y4mReader, Y4mSource, Y4mWriter};
use suitcap::suit::SuitDefinition;

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn fixture(path: &str) -> Vec<u8> {
    std::fs::read(repo(path)).unwrap_or_else(|e| panic!("test fixture {path}: {e}"))
}

fn suit() -> SuitDefinition {
    SuitDefinition::load_dir(&repo("suits/default")).expect("the default suit")
}

fn config(cases: u32) -> Config {
    Config {
        cases,
        // Failures are reported with the minimal input; no regression files in the source tree.
        failure_persistence: None,
        ..Config::default()
    }
}

/// One edit of a byte string.
#[derive(Clone, Debug)]
enum Edit {
    Flip { at: usize, mask: u8 },
    Set { at: usize, value: u8 },
    Insert { at: usize, bytes: Vec<u8> },
    Delete { at: usize, len: usize },
    Truncate { at: usize },
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        4 => (any::<usize>(), 1u8..=255).prop_map(|(at, mask)| Edit::Flip { at, mask }),
        2 => (any::<usize>(), any::<u8>()).prop_map(|(at, value)| Edit::Set { at, value }),
        2 => (any::<usize>(), proptest::collection::vec(any::<u8>(), 1..16))
            .prop_map(|(at, bytes)| Edit::Insert { at, bytes }),
        2 => (any::<usize>(), 1usize..64).prop_map(|(at, len)| Edit::Delete { at, len }),
        1 => any::<usize>().prop_map(|at| Edit::Truncate { at }),
    ]
}

/// Applies `edits` to a copy of `bytes` (positions taken modulo the current length).
fn mutate(bytes: &[u8], edits: &[Edit]) -> Vec<u8> {
    let mut out = bytes.to_vec();
    for e in edits {
        let n = out.len();
        match e {
            Edit::Flip { at, mask } if n > 0 => out[at % n] ^= mask,
            Edit::Set { at, value } if n > 0 => out[at % n] = *value,
            Edit::Insert { at, bytes } => {
                let at = at % (n + 1);
                out.splice(at..at, bytes.iter().copied());
            }
            Edit::Delete { at, len } if n > 0 => {
                let at = at % n;
                out.drain(at..(at + len).min(n));
            }
            Edit::Truncate { at } => out.truncate(at % (n + 1)),
            _ => {}
        }
    }
    out
}

// ---------------------------------------------------------------------------------------------
// BVH

/// Parses; if the file is accepted, also does what the runtime does with a motion.
fn bvh(bytes: &[u8]) {
    if let Ok(motion) = Motion::parse(bytes, Path::new("fuzz.bvh")) {
        let count = motion.frame_count();
        assert!(count > 0, "an accepted BVH has frames");
        let _ = motion.skeleton.joint_positions(motion.frame(0));
        let _ = motion.skeleton.joint_positions(motion.frame(count - 1));
        // Writing it back must not panic either. (It need not read back: a leaf joint whose End
        // Site was unreadable is written without one, and bvh_anim then drops that joint.)
        let text = motion.to_bvh_string();
        let _ = Motion::parse(text.as_bytes(), Path::new("again.bvh"));
    }
}

/// A small valid BVH: the suit's skeleton with its one template frame (7 KB).
fn small_bvh() -> Vec<u8> {
    fixture("suits/default/skeleton.bvh")
}

/// A tiny two-joint BVH with three frames.
const TINY_BVH: &str = "HIERARCHY\nROOT hip\n{\n\tOFFSET 0 0 0\n\tCHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\n\tJOINT knee\n\t{\n\t\tOFFSET 0 -40 0\n\t\tCHANNELS 3 Zrotation Xrotation Yrotation\n\t\tEnd Site\n\t\t{\n\t\t\tOFFSET 0 -40 0\n\t\t}\n\t}\n}\nMOTION\nFrames: 3\nFrame Time: 0.033333\n0 90 0 0 0 0 10 0 0\n1 90 0 0 5 0 20 0 0\n2 90 0 0 10 0 30 0 0\n";

#[test]
fn bvh_fixtures_are_valid() {
    assert!(Motion::parse(&small_bvh(), Path::new("skeleton.bvh")).is_ok());
    assert_eq!(
        Motion::parse(TINY_BVH.as_bytes(), Path::new("tiny.bvh"))
            .expect("tiny")
            .frame_count(),
        3
    );
}

#[test]
fn bvh_malformed_hierarchies_and_huge_counts_are_errors() {
    // bvh_anim 0.4 panics on the first two and would reserve terabytes for the last two.
    let cases = [
        TINY_BVH.replacen("ROOT hip", "ROOT", 1),
        TINY_BVH.replacen("JOINT knee", "HIERARCHY", 1),
        TINY_BVH.replacen("CHANNELS 3", "CHANNELS 99999999999", 1),
        TINY_BVH.replacen("Frames: 3", "Frames: 99999999999", 1),
    ];
    for text in cases {
        let err = Motion::parse(text.as_bytes(), Path::new("bad.bvh"));
        assert!(
            matches!(&err, Err(e) if e.to_string().contains("bad.bvh")),
            "{err:?}"
        );
    }
}

#[test]
fn bvh_every_truncation() {
    let tiny = TINY_BVH.as_bytes();
    for n in 0..=tiny.len() {
        bvh(&tiny[..n]);
    }
    let small = small_bvh();
    for n in 0..=small.len() {
        bvh(&small[..n]);
    }
}

/// Words and numbers BVH files are made of, for token soups that reach deep into the parser.
fn bvh_token() -> impl Strategy<Value = String> {
    prop_oneof![
        8 => prop::sample::select(vec![
            "HIERARCHY", "ROOT", "JOINT", "End", "Site", "{", "}", "OFFSET", "CHANNELS",
            "Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation", "Zrotation", "MOTION",
            "Frames:", "Frame", "Time:", "hip", "knee", "\n", "\r\n", "\t", " ",
        ])
        .prop_map(str::to_owned),
        4 => prop::sample::select(vec![
            "0", "1", "3", "6", "-1", "0.0333", "1e309", "-1e309", "nan", "inf", "-0", "1e-45",
            "4294967296", "18446744073709551616", "99999999", "3.", ".5", "--1", "1e", "",
        ])
        .prop_map(str::to_owned),
        1 => "[ -~]{0,8}",
    ]
}

proptest! {
    #![proptest_config(config(2048))]

    #[test]
    fn bvh_random_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..2048)) {
        bvh(&bytes);
    }

    #[test]
    fn bvh_token_soup(tokens in proptest::collection::vec(bvh_token(), 0..120)) {
        bvh(tokens.join(" ").as_bytes());
    }

    #[test]
    fn bvh_edits_of_a_valid_file(edits in proptest::collection::vec(edit(), 1..6), which in 0usize..2) {
        let base = if which == 0 { TINY_BVH.as_bytes().to_vec() } else { small_bvh() };
        bvh(&mutate(&base, &edits));
    }

    #[test]
    fn bvh_token_replaced_in_a_valid_file(at in any::<usize>(), token in bvh_token(), count in 1usize..4) {
        // Replace `count` whitespace-separated tokens of the tiny file, starting at one.
        let words: Vec<&str> = TINY_BVH.split_inclusive(char::is_whitespace).collect();
        let at = at % words.len();
        let mut text = String::new();
        for (i, w) in words.iter().enumerate() {
            if i >= at && i < at + count {
                text.push_str(&token);
                text.push(' ');
            } else {
                text.push_str(w);
            }
        }
        bvh(text.as_bytes());
    }
}

// ---------------------------------------------------------------------------------------------
// Model files and their loaders

/// FNV-1a, the container's checksum (documented in `src/model.rs`).
fn fnv1a(bytes: &[u8]) -> u64 {
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    for &b in bytes {
        hash ^= u64::from(b);
        hash = hash.wrapping_mul(0x0100_0000_01b3);
    }
    hash
}

/// Replaces the trailing checksum so that corrupt content gets past it.
fn rechecksum(bytes: &mut [u8]) {
    if bytes.len() >= 8 {
        let body = bytes.len() - 8;
        let sum = fnv1a(&bytes[..body]);
        bytes[body..].copy_from_slice(&sum.to_le_bytes());
    }
}

/// A small valid regressor file for the default suit: 2 relevance vectors over the HOG descriptor
/// (code 1), the matrix rotation encoding (code 1), weights for the 105 pose values.
fn small_regressor() -> Vec<u8> {
    let mut m = ModelFile::new(REGRESSOR_KIND, REGRESSOR_VERSION);
    m.push("descriptor", &[1], vec![1.0]);
    m.push("rotations", &[1], vec![1.0]);
    m.push("width", &[1], vec![3.0]);
    m.push("noise", &[1], vec![0.1]);
    m.push(
        "relevance_vectors",
        &[2, HOG_CENTRES],
        (0..2 * HOG_CENTRES).map(|i| i as f32 * 0.01).collect(),
    );
    m.push(
        "weights",
        &[3, 105],
        (0..3 * 105).map(|i| (i % 7) as f32 * 0.1).collect(),
    );
    m.encode()
}

/// A loader run on one model file's bytes.
type Loader = dyn Fn(&ModelDir, &[u8]);

/// Directory with a suit's model files, rewritten per case.
struct ModelDir {
    dir: tempfile::TempDir,
    suit: SuitDefinition,
}

impl ModelDir {
    fn new() -> ModelDir {
        let dir = tempfile::tempdir().expect("tempdir");
        for name in [
            SKELETON_FILE,
            "codebook_fc.bin",
            "codebook_hog.bin",
            "codebook_silhouette.bin",
            SEGMENTER_FILE,
        ] {
            std::fs::copy(
                repo(&format!("suits/default/{name}")),
                dir.path().join(name),
            )
            .expect("copy fixture");
        }
        std::fs::write(dir.path().join(REGRESSOR_FILE), small_regressor()).expect("write");
        ModelDir { dir, suit: suit() }
    }

    fn path(&self) -> &Path {
        self.dir.path()
    }

    fn regressor(&self, bytes: &[u8]) {
        std::fs::write(self.path().join(REGRESSOR_FILE), bytes).expect("write");
        let _ = Regressor::load(self.path(), &self.suit);
    }

    fn skeleton(&self, bytes: &[u8]) {
        std::fs::write(self.path().join(SKELETON_FILE), bytes).expect("write");
        if let Ok(r) = Regressor::load(self.path(), &self.suit) {
            assert!(!r.template().is_empty());
        }
    }

    /// The HOG codebook alone (the loader of each codebook file).
    fn codebook(&self, bytes: &[u8]) {
        let path = codebook_path(self.path(), HOG_CODEBOOK);
        std::fs::write(&path, bytes).expect("write");
        let _ = Codebook::load(&path, HOG_CODEBOOK, HOG_CODEBOOK_VERSION, HOG_CENTRES, 36);
    }

    /// All three codebooks of the suit, the HOG one replaced.
    fn codebooks(&self, bytes: &[u8]) {
        self.codebook(bytes);
        let _ = Codebooks::load(self.path());
    }

    fn segmenter(&self, bytes: &[u8]) {
        std::fs::write(self.path().join(SEGMENTER_FILE), bytes).expect("write");
        let _ = SegmenterTables::load(self.path());
    }
}

fn decode_any(bytes: &[u8]) {
    for (kind, version) in [
        (REGRESSOR_KIND, REGRESSOR_VERSION),
        (SEGMENTER_KIND, SEGMENTER_VERSION),
        (HOG_CODEBOOK, HOG_CODEBOOK_VERSION),
    ] {
        let _ = ModelFile::decode(bytes, Path::new("fuzz.bin"), kind, version);
    }
}

#[test]
fn model_fixtures_are_valid() {
    let d = ModelDir::new();
    let regressor = Regressor::load(d.path(), &d.suit).expect("small regressor");
    assert_eq!(
        regressor.layout.rotations,
        suitcap::pose::RotationEncoding::MatrixColumns
    );
    Codebooks::load(d.path()).expect("codebooks");
    SegmenterTables::load(d.path()).expect("segmenter");
}

#[test]
fn an_unknown_rotation_encoding_is_an_error_naming_the_file() {
    let d = ModelDir::new();
    let mut m = ModelFile::decode(
        &small_regressor(),
        Path::new("r.bin"),
        REGRESSOR_KIND,
        REGRESSOR_VERSION,
    )
    .expect("fixture");
    for array in &mut m.arrays {
        if array.name == "rotations" {
            array.data = vec![7.0];
        }
    }
    std::fs::write(d.path().join(REGRESSOR_FILE), m.encode()).expect("write");
    let error = Regressor::load(d.path(), &d.suit)
        .expect_err("code 7")
        .to_string();
    assert!(
        error.contains(REGRESSOR_FILE) && error.contains("rotation encoding"),
        "{error}"
    );
}

#[test]
fn model_every_truncation() {
    let d = ModelDir::new();
    let regressor = small_regressor();
    for n in 0..=regressor.len() {
        decode_any(&regressor[..n]);
        d.regressor(&regressor[..n]);
    }
    let hog = fixture("suits/default/codebook_hog.bin");
    for n in 0..=hog.len() {
        d.codebook(&hog[..n]);
    }
    let segmenter = fixture("suits/default/segmenter.bin");
    for n in 0..=segmenter.len() {
        let _ = ModelFile::decode(
            &segmenter[..n],
            Path::new("segmenter.bin"),
            SEGMENTER_KIND,
            SEGMENTER_VERSION,
        );
    }
    for n in (0..=segmenter.len()).step_by(97) {
        d.segmenter(&segmenter[..n]);
    }
    // Truncated and re-checksummed: the content itself ends early.
    for n in (8..=regressor.len()).step_by(3) {
        let mut cut = regressor[..n].to_vec();
        rechecksum(&mut cut);
        d.regressor(&cut);
    }
}

/// An edit of a decoded model file.
#[derive(Clone, Debug)]
enum ArrayEdit {
    Drop(usize),
    Rename(usize, String),
    Dims(usize, Vec<usize>),
    /// New dims without changing the data: the encoded lengths disagree.
    DimsOnly(usize, Vec<usize>),
    Data(usize, Vec<f32>),
    Duplicate(usize),
}

fn array_edit() -> impl Strategy<Value = ArrayEdit> {
    let dims = proptest::collection::vec(
        prop_oneof![0usize..4, Just(100), Just(105), Just(36), 0usize..400],
        0..4,
    );
    let names = prop::sample::select(vec![
        "descriptor",
        "rotations",
        "width",
        "noise",
        "relevance_vectors",
        "weights",
        "centres",
        "downscale",
        "colour",
        "prior",
        "neighbourhood",
        "gradient",
        "motion",
        "temporal",
        "pair_prior",
        "x",
    ]);
    prop_oneof![
        (any::<usize>()).prop_map(ArrayEdit::Drop),
        (any::<usize>(), names).prop_map(|(i, n)| ArrayEdit::Rename(i, n.to_owned())),
        (any::<usize>(), dims.clone()).prop_map(|(i, d)| ArrayEdit::Dims(i, d)),
        (any::<usize>(), dims).prop_map(|(i, d)| ArrayEdit::DimsOnly(i, d)),
        (
            any::<usize>(),
            proptest::collection::vec(
                prop_oneof![
                    Just(0.0f32),
                    Just(-1.0),
                    Just(1.0),
                    Just(0.5),
                    Just(2.0),
                    Just(4.0),
                    Just(8.0),
                    Just(9.0),
                    Just(1e30),
                    Just(-1e30),
                    Just(f32::MIN_POSITIVE),
                    any::<f32>()
                ],
                0..8
            )
        )
            .prop_map(|(i, v)| ArrayEdit::Data(i, v)),
        any::<usize>().prop_map(ArrayEdit::Duplicate),
    ]
}

/// Applies the edits to the decoded file and re-encodes it (valid checksum).
fn edit_model(model: &ModelFile, edits: &[ArrayEdit]) -> Vec<u8> {
    let mut m = model.clone();
    for e in edits {
        let n = m.arrays.len();
        if n == 0 {
            break;
        }
        match e {
            ArrayEdit::Drop(i) => {
                m.arrays.remove(i % n);
            }
            ArrayEdit::Rename(i, name) => m.arrays[i % n].name = name.clone(),
            ArrayEdit::Dims(i, dims) => {
                let a = &mut m.arrays[i % n];
                let len: usize = dims.iter().product();
                a.dims = dims.clone();
                // Too big to build: keep the dims, the encoded data is then short.
                a.data.resize(len.min(1 << 16), 0.5);
            }
            ArrayEdit::DimsOnly(i, dims) => m.arrays[i % n].dims = dims.clone(),
            ArrayEdit::Data(i, values) => {
                let a = &mut m.arrays[i % n];
                for (k, v) in values.iter().enumerate() {
                    if let Some(slot) = a.data.get_mut(k) {
                        *slot = *v;
                    }
                }
            }
            ArrayEdit::Duplicate(i) => {
                let a = m.arrays[i % n].clone();
                m.arrays.push(a);
            }
        }
    }
    m.encode()
}

proptest! {
    #![proptest_config(config(2048))]

    #[test]
    fn model_random_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..512), header in any::<bool>()) {
        let mut input = bytes;
        if header {
            // A valid magic, container version and kind, then noise, with a valid checksum.
            let mut head = b"SUITCAP\0".to_vec();
            head.extend_from_slice(&1u32.to_le_bytes());
            head.extend_from_slice(&(REGRESSOR_KIND.len() as u32).to_le_bytes());
            head.extend_from_slice(REGRESSOR_KIND.as_bytes());
            head.extend_from_slice(&REGRESSOR_VERSION.to_le_bytes());
            head.extend_from_slice(&input);
            head.extend_from_slice(&[0; 8]);
            rechecksum(&mut head);
            input = head;
        }
        decode_any(&input);
    }
}

proptest! {
    #![proptest_config(config(512))]

    #[test]
    fn model_flips_with_a_valid_checksum(edits in proptest::collection::vec(edit(), 1..4), which in 0usize..3) {
        thread_local!(static DIR: ModelDir = ModelDir::new());
        DIR.with(|d| {
            let (base, load): (Vec<u8>, &Loader) = match which {
                0 => (small_regressor(), &ModelDir::regressor),
                1 => (fixture("suits/default/codebook_hog.bin"), &ModelDir::codebooks),
                _ => (fixture("suits/default/segmenter.bin"), &ModelDir::segmenter),
            };
            let mut bytes = mutate(&base, &edits);
            load(d, &bytes);
            rechecksum(&mut bytes);
            decode_any(&bytes);
            load(d, &bytes);
        });
    }

    #[test]
    fn model_array_edits(edits in proptest::collection::vec(array_edit(), 1..4), which in 0usize..3) {
        thread_local!(static DIR: ModelDir = ModelDir::new());
        DIR.with(|d| {
            let (base, kind, version, load): (Vec<u8>, &str, u32, &Loader) = match which {
                0 => (small_regressor(), REGRESSOR_KIND, REGRESSOR_VERSION, &ModelDir::regressor),
                1 => (fixture("suits/default/codebook_hog.bin"), HOG_CODEBOOK, HOG_CODEBOOK_VERSION, &ModelDir::codebooks),
                _ => (fixture("suits/default/segmenter.bin"), SEGMENTER_KIND, SEGMENTER_VERSION, &ModelDir::segmenter),
            };
            let model = ModelFile::decode(&base, Path::new("fixture.bin"), kind, version).expect("valid fixture");
            load(d, &edit_model(&model, &edits));
        });
    }

    #[test]
    fn regressor_with_an_edited_skeleton(edits in proptest::collection::vec(edit(), 1..6), tokens in proptest::collection::vec(bvh_token(), 0..6), at in any::<usize>()) {
        thread_local!(static DIR: ModelDir = ModelDir::new());
        DIR.with(|d| {
            d.skeleton(&mutate(&small_bvh(), &edits));
            // A token soup spliced into the hierarchy: joints with odd channels, missing joints.
            let text = String::from_utf8_lossy(&small_bvh()).into_owned();
            let mut cut = at % text.len();
            while !text.is_char_boundary(cut) {
                cut -= 1;
            }
            let spliced = format!("{} {} {}", &text[..cut], tokens.join(" "), &text[cut..]);
            d.skeleton(spliced.as_bytes());
        });
    }
}

// ---------------------------------------------------------------------------------------------
// Y4M

/// Reads every frame the reader gives, asking again after errors as the source contract allows.
fn y4m(bytes: &[u8]) {
    let Ok(mut reader) = Y4mReader::new(Cursor::new(bytes), "fuzz.y4m") else {
        return;
    };
    let (w, h) = (reader.header().width, reader.header().height);
    for _ in 0..64 {
        match reader.read_frame() {
            Ok(None) => return,
            Ok(Some((_, image))) => assert_eq!(image.dimensions(), (w, h)),
            Err(_) => {}
        }
    }
}

/// Three 6×4 frames written by the crate's own writer.
fn small_y4m(chroma: Y4mChroma) -> Vec<u8> {
    let mut writer = Y4mWriter::new(Vec::new(), 6, 4, 30.0, chroma).expect("writer");
    for f in 0..3u8 {
        let image = image::RgbImage::from_fn(6, 4, |x, y| {
            image::Rgb([x as u8 * 40, y as u8 * 60, f * 100])
        });
        writer.write_frame(&image).expect("frame");
    }
    writer.finish().expect("finish")
}

fn mono_y4m() -> Vec<u8> {
    let mut bytes = b"YUV4MPEG2 W5 H3 F25:1 Ip A0:0 Cmono XCOLORRANGE=LIMITED\n".to_vec();
    for f in 0..2u8 {
        bytes.extend_from_slice(b"FRAME Ixyz\n");
        bytes.extend((0..15u8).map(|i| i * 16 + f));
    }
    bytes
}

fn y4m_fixtures() -> Vec<Vec<u8>> {
    vec![
        small_y4m(Y4mChroma::C420),
        small_y4m(Y4mChroma::C444),
        mono_y4m(),
    ]
}

#[test]
fn y4m_fixtures_are_valid() {
    for bytes in y4m_fixtures() {
        let mut reader = Y4mReader::new(Cursor::new(&bytes[..]), "fixture.y4m").expect("header");
        let mut frames = 0;
        while reader.read_frame().expect("frame").is_some() {
            frames += 1;
        }
        assert!(frames >= 2);
    }
}

#[test]
fn y4m_every_truncation() {
    for bytes in y4m_fixtures() {
        for n in 0..=bytes.len() {
            y4m(&bytes[..n]);
        }
    }
    // The same through the file source.
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("cut.y4m");
    let bytes = small_y4m(Y4mChroma::C420);
    for n in (0..=bytes.len()).step_by(7) {
        std::fs::write(&path, &bytes[..n]).expect("write");
        if let Ok(mut source) = Y4mSource::open(&path, None) {
            use suitcap::source::FrameSource;
            for _ in 0..8 {
                if let Ok(None) = source.next_frame() {
                    break;
                }
            }
        }
    }
}

/// Header tokens, valid and not.
fn y4m_header_token() -> impl Strategy<Value = String> {
    prop_oneof![
        prop::sample::select(vec![
            "W1",
            "W6",
            "W0",
            "W16384",
            "W16385",
            "W4294967295",
            "W-1",
            "W",
            "H1",
            "H4",
            "H0",
            "H16384",
            "H99999999999",
            "F30:1",
            "F0:0",
            "F30:0",
            "F0:1",
            "F:",
            "F30",
            "F1:1:1",
            "Ip",
            "It",
            "I?",
            "Ix",
            "I",
            "C420",
            "C420jpeg",
            "C420paldv",
            "C420mpeg2",
            "C444",
            "Cmono",
            "Cmono16",
            "C420p10",
            "C422",
            "C",
            "A1:1",
            "A0:0",
            "XCOLORRANGE=FULL",
            "XCOLORRANGE=LIMITED",
            "X",
            "\r",
            "",
            "Z",
            "\u{0}",
        ])
        .prop_map(str::to_owned),
        "[ -~]{0,6}",
    ]
}

proptest! {
    #![proptest_config(config(2048))]

    #[test]
    fn y4m_random_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..1024)) {
        y4m(&bytes);
    }

    #[test]
    fn y4m_random_header_and_data(tokens in proptest::collection::vec(y4m_header_token(), 0..8), data in proptest::collection::vec(any::<u8>(), 0..400), frame_lines in 0usize..4) {
        let mut bytes = format!("YUV4MPEG2 {}\n", tokens.join(" ")).into_bytes();
        let chunk = data.len() / (frame_lines + 1);
        for (i, part) in data.chunks(chunk.max(1)).enumerate() {
            if i <= frame_lines {
                bytes.extend_from_slice(b"FRAME\n");
            }
            bytes.extend_from_slice(part);
        }
        y4m(&bytes);
    }

    #[test]
    fn y4m_edits_of_valid_files(edits in proptest::collection::vec(edit(), 1..6), which in 0usize..3) {
        let base = &y4m_fixtures()[which];
        y4m(&mutate(base, &edits));
    }
}

// ---------------------------------------------------------------------------------------------
// Joint limits file

fn limits_text() -> String {
    let motion = Motion::parse(TINY_BVH.as_bytes(), Path::new("tiny.bvh")).expect("tiny");
    JointLimits::learn(&[motion], 5.0)
        .to_toml()
        .expect("serialises")
}

proptest! {
    #![proptest_config(config(1024))]

    #[test]
    fn joint_limits_edits_and_noise(edits in proptest::collection::vec(edit(), 1..6), noise in "\\PC{0,200}") {
        let path = Path::new("joint_limits.toml");
        let _ = JointLimits::parse(&String::from_utf8_lossy(&mutate(limits_text().as_bytes(), &edits)), path);
        let _ = JointLimits::parse(&noise, path);
    }
}
