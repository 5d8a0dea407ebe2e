//! `suitcap`: the runtime command line.
//!
//! `live` (camera → garment in a window, BVH recording), `run` (the same on recorded input, writing
//! the take, the composited frames and a preview), `drape` (a garment on a given motion), `demo` (the
//! quick start) and `bench` live in [`cli`]; here are the smaller tools: `capture` records any frame
//! source into numbered PNG or JPEG frames (the first step of recording a new suit's training video),
//! `segment` and `describe` run single stages over a sequence, `check` validates a suit and a dataset,
//! and `suit pattern` prints the suit's sewing panels.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{bail, Context};
use clap::{Parser, Subcommand};

use suitcap::mask::Mask;
use suitcap::segment::{Segmenter, SegmenterOptions, SegmenterTables, StageTimes};
use suitcap::source::directory::{
    png_names_of_frames, timestamps_line, TIMESTAMPS_FILE, TIMESTAMPS_HEADER,
};
use suitcap::source::{open_source, SourceOptions};
use suitcap::suit::SuitDefinition;

mod cli;

#[derive(Parser)]
#[command(
    name = "suitcap",
    version,
    about = "Monocular motion capture and virtual try-on from a marker suit"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum SuitCommand {
    /// Printable sewing panels of the suit's marker layout at true size: PNG (at --dpi) and SVG per
    /// panel, made to measure for a built-in subject or a height and girth.
    Pattern {
        #[arg(long, default_value_os_t = suitcap::suit::default_suit_dir())]
        suit: PathBuf,
        #[arg(long)]
        out: PathBuf,
        /// Built-in subject whose proportions the suit is cut for (default chidi).
        #[arg(long)]
        subject: Option<String>,
        /// Body height in cm (overrides the subject's).
        #[arg(long)]
        height: Option<f32>,
        /// Girth factor, 1 = the base figure's build (overrides the subject's).
        #[arg(long)]
        girth: Option<f32>,
        #[arg(long, default_value_t = 150.0)]
        dpi: f32,
        /// Print each marker's id on it.
        #[arg(long)]
        marker_ids: bool,
    },
}

#[derive(Subcommand)]
enum Command {
    /// Record frames from a camera (/dev/videoN or an index), a frame directory or a Y4M file into
    /// numbered PNG frames, with each frame's time in timestamps.csv. Corrupt input frames are
    /// skipped, counted and named.
    Capture {
        /// /dev/videoN, a camera index, a directory of numbered frames, or a .y4m file.
        input: String,
        /// Output directory for 000000.png, 000001.png, …
        #[arg(long)]
        out: PathBuf,
        /// Stop after this many frames (a camera runs until Ctrl-C otherwise).
        #[arg(long)]
        frames: Option<u64>,
        /// Wanted camera size, e.g. 640x480.
        #[arg(long, value_parser = parse_size)]
        size: Option<(u32, u32)>,
        /// Wanted camera frame rate.
        #[arg(long)]
        fps: Option<f64>,
        /// Write JPEG frames of this quality (1–100) instead of PNG.
        #[arg(long, value_parser = clap::value_parser!(u8).range(1..=100))]
        jpeg: Option<u8>,
    },
    /// Segment every frame of INPUT with the suit's trained segmenter: one PNG mask per frame
    /// (same names as a frame directory's files, else NNNNNN.png).
    Segment {
        #[arg(long, default_value_os_t = suitcap::suit::default_suit_dir())]
        suit: PathBuf,
        /// A directory of frames or a .y4m file.
        #[arg(long)]
        input: String,
        #[arg(long)]
        out: PathBuf,
        /// Ground-truth masks (same names) to report IoU against.
        #[arg(long)]
        truth: Option<PathBuf>,
        /// Override the trained term weights σ_C,σ_N,σ_G,σ_M,σ_T (for experiments), e.g. 2,1,1,0,1.
        #[arg(long, value_delimiter = ',')]
        weights: Option<Vec<f32>>,
        /// How many nats the part test leans towards the part where the previous frame attached
        /// a head or shoes (default 1.5; 0 switches the memory off, as before the eighth session
        /// of 2026-12-05).
        #[arg(long)]
        part_memory: Option<f32>,
        /// How many nats the last look for a head and shoes, in frames where less than their
        /// area was found above or below the suit, leans towards the part within the ellipses
        /// where they are expected (default 6; 0 switches that look off, as before the ninth
        /// session of 2026-12-06).
        #[arg(long)]
        part_look: Option<f32>,
        /// How many nats the last look for a hand leans towards the part within the ellipse
        /// where it is expected beyond the end of a suit's arm, in frames where less than a
        /// quarter of that ellipse was found (default 3; 0 switches that look off, as before the
        /// ninth session of 2026-12-07).
        #[arg(long)]
        hand_look: Option<f32>,
        /// Share of the person's own head and shoe colours, learned from the frames before, in the
        /// part test (default 0.3; 0 uses the trained part table alone, as before the ninth session
        /// of 2026-12-05).
        #[arg(long)]
        part_colours: Option<f32>,
        /// The edge snapping keeps an outline pixel of a marker's colour on the person unless at
        /// least this share of the room around it has a marker's colour too (default 0.5; above 1
        /// keeps it always, as before the tenth session of 2026-12-05).
        #[arg(long)]
        keep_room_share: Option<f32>,
        /// How far from the nearest marker the suit's cloth can be, in cm (default 24; 0: no
        /// limit, as before the tenth session of 2026-12-06); farther cloth is a cloth-coloured
        /// object touching the person.
        #[arg(long)]
        cloth_reach: Option<f32>,
        /// How often a stream's first frame is segmented at most, each pass learning from the one
        /// before (default 8; 2, as before the third session of 2026-12-07).
        #[arg(long)]
        first_frame_passes: Option<u32>,
        /// The weight of the label prior, relative to the temporal term's, in a stream's first two
        /// frames, which have no second-order history (default 1; a first frame that leaves most
        /// of what looks like the suit out is segmented again without it)
        #[arg(long)]
        label_prior_share: Option<f32>,
        /// Fill holes in the final mask up to this many markers' areas that are mostly of the
        /// suit's colours (default 4; 0 switches it off, as before the fourth session of
        /// 2026-12-07).
        #[arg(long)]
        suit_holes: Option<f32>,
        /// Without the outline's pixels decided by unmixing the colours beside them (as before
        /// the tenth session of 2026-12-06; for comparisons).
        #[arg(long)]
        no_unmix: bool,
        /// Without the room learned pixel by pixel (as before the second session of 2026-12-06;
        /// for comparisons).
        #[arg(long)]
        no_room: bool,
        /// Without a second look, free of the history, at a frame whose mask came out empty
        /// while much of it looks like the suit (as before the tenth session of 2026-12-07; for
        /// comparisons).
        #[arg(long)]
        no_lost_retry: bool,
        /// A pixel of the band around the suit where heads, hands and shoes are looked for is
        /// kept out of the room's learning if its colour is likelier a part's than the room's by
        /// more than this many nats (default 1; `--room-band-odds=-inf` keeps the whole band
        /// out, as before the tenth session of 2026-12-07).
        #[arg(long)]
        room_band_odds: Option<f32>,
        /// Also write the graph of this frame index as GCG1 (to compare solvers).
        #[arg(long, requires = "graph_out")]
        dump_graph: Option<u64>,
        #[arg(long)]
        graph_out: Option<PathBuf>,
    },
    /// Compute the frame descriptor (Feature Context + HOG + box, or a variant) of every frame:
    /// one CSV row per frame; optionally the detected markers, and their recall and precision
    /// against a generated dataset's markers.csv.
    Describe {
        #[arg(long, default_value_os_t = suitcap::suit::default_suit_dir())]
        suit: PathBuf,
        /// A directory of frames or a .y4m file.
        #[arg(long)]
        input: String,
        /// Person masks (same names as the frames); without it the suit's segmenter runs.
        #[arg(long)]
        masks: Option<PathBuf>,
        #[arg(long)]
        out: PathBuf,
        #[arg(long)]
        markers_out: Option<PathBuf>,
        /// fc, hog, fc+hog, full (= fc+hog+box, 304 values) or silhouette.
        #[arg(long, default_value = "full")]
        descriptor: String,
        /// A generator's markers.csv to score the detected markers against.
        #[arg(long)]
        truth_markers: Option<PathBuf>,
    },
    /// The whole pipeline on a recording (frame directory or Y4M): pose, garment, compositing.
    /// Writes OUT/take.bvh (on the suit's skeleton; one BVH frame per input frame, or with
    /// --camera-time per 1/fps of the input's timestamps), the composited frames OUT/frames/,
    /// OUT/preview.gif and OUT/frames.csv (per input frame: person seen, markers, milliseconds, its
    /// time and the BVH frame its pose went to).
    Run {
        /// A directory of frames or a .y4m file.
        input: String,
        #[arg(long, default_value_os_t = suitcap::suit::default_suit_dir())]
        suit: PathBuf,
        #[arg(long)]
        out: PathBuf,
        /// The camera's calibration; default: camera.toml beside the input (a dataset), else in the suit,
        /// else a level 60° webcam 1.2 m high is assumed (the joint angles do not depend on it).
        #[arg(long)]
        camera: Option<PathBuf>,
        /// Place the take's frames by the input's timestamps (a capture's timestamps.csv) instead
        /// of one BVH frame per input frame: frames the camera dropped are filled in, so the take
        /// keeps the capture's time (as `live` does) and no longer lines up file by file.
        #[arg(long)]
        camera_time: bool,
        #[command(flatten)]
        garment: cli::tryon::GarmentArgs,
        #[command(flatten)]
        pose: cli::tryon::PoseArgs,
    },
    /// The camera with the simulated garment in a window, at the camera's rate; records BVH.
    Live {
        /// /dev/videoN or a camera index (a frame directory or .y4m file also works, for testing).
        #[arg(long, default_value = "/dev/video0")]
        device: String,
        #[arg(long, default_value_os_t = suitcap::suit::default_suit_dir())]
        suit: PathBuf,
        /// The camera's calibration (default: camera.toml beside a recorded input or in the suit, else a
        /// level 60° webcam 1.2 m high).
        #[arg(long)]
        camera: Option<PathBuf>,
        /// Wanted camera size, e.g. 640x480 (default: the calibration's).
        #[arg(long, value_parser = parse_size)]
        size: Option<(u32, u32)>,
        #[arg(long)]
        fps: Option<f64>,
        /// Record from the start into this BVH file (R starts and stops recording).
        #[arg(long)]
        record: Option<PathBuf>,
        #[command(flatten)]
        garment: cli::tryon::GarmentArgs,
        #[command(flatten)]
        pose: cli::tryon::PoseArgs,
    },
    /// Simulate a garment on a given motion (e.g. a generated dataset's motion.bvh) and composite it
    /// into the given frames: PNG frames and a preview GIF in OUT, and the cloth quality figures.
    Drape {
        #[arg(long)]
        motion: PathBuf,
        #[arg(long)]
        camera: PathBuf,
        /// Directory of frames, one per motion frame.
        #[arg(long)]
        frames: PathBuf,
        /// Person masks for the body-size estimate (default: masks/ beside the frames, if present).
        #[arg(long)]
        masks: Option<PathBuf>,
        #[arg(long)]
        out: PathBuf,
        #[command(flatten)]
        garment: cli::tryon::GarmentArgs,
    },
    /// The quick start: the footage bundled with the default suit through the whole pipeline
    /// (no camera, no network, nothing to train); results in OUT.
    Demo {
        #[arg(long, default_value_os_t = suitcap::suit::default_suit_dir())]
        suit: PathBuf,
        #[arg(long, default_value = "out/demo")]
        out: PathBuf,
    },
    /// Per-stage median milliseconds and frames/s of the pose and try-on pipeline on the suit's
    /// bundled footage (or --input), sequential and on threads, and the peak resident memory.
    Bench(cli::bench::BenchArgs),
    /// Suit tools.
    Suit {
        #[command(subcommand)]
        command: SuitCommand,
    },
    /// Validate a suit directory (suit.toml, and that its trained models, if any, load with this
    /// build) and, optionally, a dataset against it.
    Check {
        #[arg(long, default_value_os_t = suitcap::suit::default_suit_dir())]
        suit: PathBuf,
        #[arg(long)]
        data: Option<PathBuf>,
    },
}

fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let (w, h) = text
        .split_once('x')
        .ok_or_else(|| format!("'{text}' is not WIDTHxHEIGHT"))?;
    let parse = |v: &str| {
        v.parse::<u32>()
            .map_err(|_| format!("'{text}' is not WIDTHxHEIGHT"))
    };
    let (w, h) = (parse(w)?, parse(h)?);
    if w == 0 || h == 0 {
        return Err(format!("'{text}': width and height must be positive"));
    }
    Ok((w, h))
}

fn capture(
    input: &str,
    out: &PathBuf,
    frames: Option<u64>,
    size: Option<(u32, u32)>,
    fps: Option<f64>,
    jpeg: Option<u8>,
) -> anyhow::Result<()> {
    let options = SourceOptions {
        size,
        fps,
        ..SourceOptions::default()
    };
    let mut source = open_source(input, &options)?;
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    // Each frame's time from the source's clock, a line per frame as it is written (unbuffered:
    // a camera is stopped with Ctrl-C), so that a dropped frame leaves a gap in time that the
    // frame directory's reader and `suitcap-train import` see.
    let times_path = out.join(TIMESTAMPS_FILE);
    let mut times = std::fs::File::create(&times_path)
        .and_then(|mut f| writeln!(f, "{TIMESTAMPS_HEADER}").map(|()| f))
        .with_context(|| format!("cannot write {}", times_path.display()))?;
    eprintln!("capturing from {}", source.describe());
    let started = Instant::now();
    let (mut written, mut skipped) = (0u64, Vec::new());
    loop {
        if frames.is_some_and(|n| written >= n) {
            break;
        }
        match source.next_frame() {
            Ok(Some(frame)) => {
                let extension = if jpeg.is_some() { "jpg" } else { "png" };
                let name = format!("{written:06}.{extension}");
                let path = out.join(&name);
                save_frame(&frame.image, &path, jpeg)
                    .with_context(|| format!("cannot write {}", path.display()))?;
                times
                    .write_all(timestamps_line(&name, frame.timestamp.as_secs_f64()).as_bytes())
                    .with_context(|| format!("cannot write {}", times_path.display()))?;
                written += 1;
            }
            Ok(None) => break,
            Err(e) if e.skipped_frame().is_some() => {
                eprintln!("skipped: {e}");
                skipped.push(e.to_string());
            }
            Err(e) => {
                eprintln!("stopped after {written} frames: {e}");
                if written == 0 {
                    return Err(e.into());
                }
                break;
            }
        }
    }
    let seconds = started.elapsed().as_secs_f64();
    println!(
        "{} written to {} in {seconds:.1} s; {} skipped",
        cli::counted(written as usize, "frame", "frames"),
        out.display(),
        cli::counted(skipped.len(), "corrupt frame", "corrupt frames")
    );
    for s in &skipped {
        println!("  skipped: {s}");
    }
    Ok(())
}

/// Writes a frame as PNG, or as JPEG of the given quality.
fn save_frame(image: &image::RgbImage, path: &Path, jpeg: Option<u8>) -> anyhow::Result<()> {
    match jpeg {
        None => image.save(path)?,
        Some(quality) => {
            let file = std::io::BufWriter::new(std::fs::File::create(path)?);
            image::codecs::jpeg::JpegEncoder::new_with_quality(file, quality)
                .encode_image(image)?;
        }
    }
    Ok(())
}

/// Loads each trained model a suit has as `run` would, so a stale or damaged file (a model from
/// another version, a truncated download) is named here rather than at the first frame; the ones
/// not trained yet are listed (a suit part-way through training is not an error).
fn check_trained_models(suit: &Path, definition: &SuitDefinition) -> anyhow::Result<()> {
    use suitcap::descriptor::codebook::codebook_path;
    use suitcap::descriptor::{Codebooks, FC_CODEBOOK, HOG_CODEBOOK, SILHOUETTE_CODEBOOK};
    use suitcap::pose::regressor::{Regressor, REGRESSOR_FILE};
    use suitcap::pose::smoothing::{JointLimits, JOINT_LIMITS_FILE};
    use suitcap::segment::tables::SEGMENTER_FILE;
    let (mut loaded, mut missing) = (Vec::new(), Vec::new());
    if suit.join(SEGMENTER_FILE).exists() {
        let tables = SegmenterTables::load(suit)?;
        let w = tables.weights;
        loaded.push(format!(
            "segmenter tables (trained on frames {} rows high, cut at 1/{}; σ_C {}, σ_N {}, σ_G {}, σ_M {}, σ_T {})",
            tables.trained_rows * tables.downscale,
            tables.downscale,
            w.colour,
            w.neighbourhood,
            w.gradient,
            w.motion,
            w.temporal
        ));
    } else {
        missing.push(SEGMENTER_FILE);
    }
    let codebooks = [FC_CODEBOOK, HOG_CODEBOOK, SILHOUETTE_CODEBOOK];
    if codebooks
        .iter()
        .any(|kind| codebook_path(suit, kind).exists())
    {
        Codebooks::load(suit)?;
        loaded.push("codebooks".to_string());
    } else {
        missing.push("codebook_*.bin");
    }
    if suit.join(REGRESSOR_FILE).exists() {
        let regressor = Regressor::load(suit, definition)?;
        loaded.push(format!(
            "regressor ({} descriptor, {} relevance vectors, {})",
            regressor.descriptor.name(),
            regressor.rvm.len(),
            regressor
                .exemplars
                .as_ref()
                .map_or("no exemplars".to_string(), |e| format!(
                    "{} exemplars",
                    e.len()
                ))
        ));
    } else {
        missing.push(REGRESSOR_FILE);
    }
    let limits = suit.join(JOINT_LIMITS_FILE);
    if limits.exists() {
        JointLimits::load(&limits)?;
        loaded.push("joint limits".to_string());
    } else {
        missing.push(JOINT_LIMITS_FILE);
    }
    if !loaded.is_empty() {
        println!("trained models load: {}", loaded.join(", "));
    }
    match suitcap::manifest::verify(suit)? {
        Some(files) => println!(
            "the model files are those {} records ({files} checksums match)",
            suit.join(suitcap::manifest::MANIFEST_FILE).display()
        ),
        None if !loaded.is_empty() => println!(
            "no checksums to compare the model files with ({} absent or from before them)",
            suit.join(suitcap::manifest::MANIFEST_FILE).display()
        ),
        None => {}
    }
    if !missing.is_empty() {
        println!(
            "not trained yet: {} (`suitcap-train suit --suit {} --data DATASET …` trains the models, `suitcap-train limits` the joint limits)",
            missing.join(", "),
            suit.display()
        );
    }
    Ok(())
}

fn check(suit: &Path, data: Option<&Path>) -> anyhow::Result<()> {
    let definition = SuitDefinition::load_dir(suit)?;
    println!(
        "suit '{}': {} marker colours, {} cm markers every {} cm, {} estimated joints",
        definition.name,
        definition.markers.len(),
        definition.marker_size_cm,
        definition.pitch_cm(),
        definition.skeleton.joints.len()
    );
    check_trained_models(suit, &definition)?;
    if let Some(data) = data {
        let dataset = suitcap::dataset::Dataset::open(data)?;
        definition
            .skeleton
            .bind(&dataset.motion.skeleton)
            .with_context(|| {
                format!(
                    "{}: motion.bvh does not carry the suit's joints",
                    data.display()
                )
            })?;
        if dataset.manifest.suit.layout_seed != definition.layout_seed {
            bail!(
                "{}: rendered with suit layout seed {}, but {} has {}",
                data.display(),
                dataset.manifest.suit.layout_seed,
                suit.display(),
                definition.layout_seed
            );
        }
        println!(
            "dataset {}: {} frames {}x{} at {:.3} fps, subject '{}', clip {}",
            data.display(),
            dataset.frame_count(),
            dataset.manifest.width,
            dataset.manifest.height,
            dataset.manifest.fps,
            dataset.manifest.performer(),
            dataset.manifest.clip.name
        );
        if let Some(r) = &dataset.manifest.recording {
            let masked = (0..dataset.frame_count())
                .filter(|&k| dataset.has_mask(k))
                .count();
            let skipped = match r.skipped_video_frames.as_slice() {
                [] => String::new(),
                frames => format!(
                    ", its unreadable frames {} left out",
                    frames
                        .iter()
                        .map(usize::to_string)
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            };
            println!(
                "  recorded: video {} from its frame {}{skipped}, mocap offset {} s; {masked} frames with masks",
                r.video, r.first_video_frame, r.mocap_offset_s
            );
        }
    }
    Ok(())
}

/// The next frame that decodes. A corrupt or mis-sized frame is reported, recorded in `skipped` and
/// passed over; the end of the stream or any other error (reported, with the `done` frames so far)
/// gives `None`.
fn next_good_frame(
    source: &mut (dyn suitcap::source::FrameSource + Send),
    skipped: &mut Vec<String>,
    done: usize,
) -> Option<suitcap::source::Frame> {
    loop {
        match source.next_frame() {
            Ok(frame) => return frame,
            Err(e) if e.skipped_frame().is_some() => {
                eprintln!("skipped: {e}");
                skipped.push(e.to_string());
            }
            Err(e) => {
                eprintln!("stopped after {done} frames: {e}");
                return None;
            }
        }
    }
}

/// For a frame directory, the PNG name each input frame's output gets (its file stem); `None` for
/// other inputs, whose outputs are numbered.
fn output_names(input: &str) -> anyhow::Result<Option<Vec<String>>> {
    if !Path::new(input).is_dir() {
        return Ok(None);
    }
    Ok(Some(png_names_of_frames(Path::new(input))?))
}

/// The segmenter's options with `suitcap segment`'s overrides of the part memory and the last
/// looks for a head and shoes and for hands (nats), the share of the person's own part colours,
/// the edge snapping's room share for marker colours, the cloth's reach from the markers (cm),
/// the passes over a stream's first frame and the label prior's share in its first two frames,
/// the room model (`no_room`: off) and the part odds above which its band is kept out of it, the
/// outline's unmixing (`no_unmix`: off), the second look at a frame found empty (`no_lost_retry`:
/// off) and the largest hole of the suit's colours filled (markers' areas).
fn segmenter_options(
    (part_memory, part_look, hand_look): (Option<f32>, Option<f32>, Option<f32>),
    part_colours: Option<f32>,
    (keep_room_share, suit_holes, room_band_odds): (Option<f32>, Option<f32>, Option<f32>),
    (cloth_reach, first_frame_passes, label_prior_share): (Option<f32>, Option<u32>, Option<f32>),
    (no_room, no_unmix, no_lost_retry): (bool, bool, bool),
) -> anyhow::Result<SegmenterOptions> {
    let mut options = SegmenterOptions::default();
    if let Some(passes) = first_frame_passes {
        if passes == 0 {
            bail!("--first-frame-passes: 0 is not a number of passes (1 or more)");
        }
        options.first_frame_passes = passes;
    }
    if let Some(odds) = room_band_odds {
        if odds.is_nan() {
            bail!("--room-band-odds: NaN is not a number of nats");
        }
        if let Some(room) = &mut options.room {
            room.band_part_odds = odds;
        }
    }
    if no_room {
        options.room = None;
    }
    if no_unmix {
        options.unmix = None;
    }
    options.lost_person_retry = !no_lost_retry;
    // `flag`'s value if it is finite and not negative, else an error naming the flag.
    let at_least_zero = |flag: &str, value: f32, what: &str| {
        if value.is_finite() && value >= 0.0 {
            Ok(value)
        } else {
            Err(anyhow::anyhow!(
                "{flag}: {value} is not a finite {what} >= 0"
            ))
        }
    };
    if let Some(nats) = part_memory {
        options.part_memory = at_least_zero("--part-memory", nats, "number")?;
    }
    if let Some(nats) = part_look {
        options.part_look = at_least_zero("--part-look", nats, "number")?;
    }
    if let Some(nats) = hand_look {
        options.hand_look = at_least_zero("--hand-look", nats, "number")?;
    }
    if let Some(share) = part_colours {
        if !(0.0..=1.0).contains(&share) {
            bail!("--part-colours: {share} is not a share between 0 and 1");
        }
        options.part_colour_share = share;
    }
    if let Some(share) = keep_room_share {
        options.snap.keep_room_share = at_least_zero("--keep-room-share", share, "share")?;
    }
    if let Some(share) = label_prior_share {
        options.label_prior_share = at_least_zero("--label-prior-share", share, "share")?;
    }
    if let Some(cm) = cloth_reach {
        options.cloth_reach_cm = at_least_zero("--cloth-reach", cm, "number of cm")?;
    }
    if let Some(markers) = suit_holes {
        options.suit_hole_markers = at_least_zero("--suit-holes", markers, "number of markers")?;
    }
    Ok(options)
}

fn segment(
    suit_dir: &Path,
    input: &str,
    out: &Path,
    truth: Option<&PathBuf>,
    weights: Option<&[f32]>,
    options: SegmenterOptions,
    dump: Option<(u64, &PathBuf)>,
) -> anyhow::Result<()> {
    let suit = SuitDefinition::load_dir(suit_dir)?;
    let mut tables = SegmenterTables::load(suit_dir)?;
    if let Some(w) = weights {
        let array: [f32; 5] = w.try_into().map_err(|_| {
            anyhow::anyhow!(
                "--weights takes 5 numbers (σ_C,σ_N,σ_G,σ_M,σ_T), got {}",
                w.len()
            )
        })?;
        if array.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
            bail!("--weights: every weight must be a finite number >= 0");
        }
        tables.weights = suitcap::segment::Weights::from_array(array);
    }
    cli::ensure_mask_dir("--truth", truth)?;
    let mut segmenter = Segmenter::new(tables, &suit, options);
    let names = output_names(input)?;
    let mut source = open_source(input, &SourceOptions::default())?;
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let (mut frames, mut skipped) = (0usize, Vec::new());
    let mut times = Vec::new();
    // Per frame scored against the truth: how the mask agrees with it, and the frame's name.
    let mut scored: Vec<(suitcap::mask::Agreement, String)> = Vec::new();
    let mut unscored = 0usize;
    let (mut cleaned_frames, mut removed_px, mut filled_px, mut empty_frames) =
        (0usize, 0usize, 0usize, 0usize);
    let (mut off_cloth_px, mut far_px, mut suit_hole_px) = (0usize, 0usize, 0usize);
    let mut looked_again = 0usize;
    // The last frame's height, for the cut's factor in the summary.
    let mut last_height = None;
    loop {
        let before = skipped.len();
        let Some(frame) = next_good_frame(source.as_mut(), &mut skipped, frames) else {
            break;
        };
        if skipped.len() > before {
            segmenter.reset(); // the history no longer matches the picture
        }
        let name = names
            .as_ref()
            .and_then(|n| n.get(frame.index as usize).cloned())
            .unwrap_or_else(|| format!("{:06}.png", frame.index));
        if let Some((index, path)) = dump {
            if index == frame.index {
                segmenter.build_graph(&frame.image);
                suitcap::segment::gcg::write_gcg(path, segmenter.graph())?;
                println!("frame {index}: graph written to {}", path.display());
            }
        }
        let result = segmenter.segment(&frame.image);
        last_height = Some(frame.image.height());
        times.push(result.times);
        let c = result.cleanup;
        if c.components_removed
            + c.holes_filled
            + c.off_cloth_pieces
            + c.far_from_markers_pixels
            + c.suit_holes_filled
            > 0
        {
            cleaned_frames += 1;
        }
        removed_px += c.pixels_removed;
        off_cloth_px += c.off_cloth_pixels;
        far_px += c.far_from_markers_pixels;
        suit_hole_px += c.suit_hole_pixels;
        filled_px += c.pixels_filled;
        empty_frames += result.mask.is_empty() as usize;
        looked_again += result.looked_again as usize;
        let path = out.join(&name);
        result
            .mask
            .to_gray()
            .save(&path)
            .with_context(|| format!("cannot write {}", path.display()))?;
        if let Some(truth) = truth {
            // Only the frames with a truth mask are scored (a few may have been labelled).
            let truth_path = truth.join(&name);
            if truth_path.is_file() {
                let gt = read_mask_for(&truth_path, &frame.image, "truth mask")?;
                scored.push((result.mask.agreement(&gt), name.clone()));
            } else {
                unscored += 1;
            }
        }
        frames += 1;
    }
    println!(
        "{} written to {}; {} skipped; {} with nobody; {} found empty with much of the suit in view, looked at again without the history",
        cli::counted(frames, "mask", "masks"),
        out.display(),
        cli::counted(skipped.len(), "corrupt frame", "corrupt frames"),
        cli::counted(empty_frames, "frame", "frames"),
        cli::counted(looked_again, "frame", "frames")
    );
    let grid = match last_height {
        Some(height) => format!(
            "the cut's {}×{} grid, factor {}",
            segmenter.graph().width(),
            segmenter.graph().height(),
            segmenter.tables().cut_factor(height)
        ),
        None => "the cut's resolution".to_owned(),
    };
    println!(
        "clean-up (largest marker-carrying region kept, small holes filled, pieces not cloth and larger than a \
         few markers removed, cloth far from every marker removed) changed {cleaned_frames} frames: \
         {removed_px} stray person pixels removed, {filled_px} hole pixels filled, {off_cloth_px} pixels of \
         large pieces not cloth removed, {far_px} pixels of cloth far from the markers removed (on {grid}); \
         {suit_hole_px} frame pixels of holes of the suit's colours filled"
    );
    if !times.is_empty() {
        let stage_median =
            |f: &dyn Fn(&StageTimes) -> f64| cli::median(&times.iter().map(f).collect::<Vec<_>>());
        println!(
            "median ms per frame: features {:.2}, graph {:.2}, cut {:.2}, clean-up {:.2}, refine {:.2}, history {:.2}, total {:.2}",
            stage_median(&|t| t.features),
            stage_median(&|t| t.graph),
            stage_median(&|t| t.cut),
            stage_median(&|t| t.cleanup),
            stage_median(&|t| t.refine),
            stage_median(&|t| t.history),
            stage_median(&|t| t.total())
        );
    }
    // Frames whose truth has nobody are reported apart: their IoU is 1 or 0, and would hide the
    // person frames' figures.
    let (scored, nobody): (Vec<_>, Vec<_>) =
        scored.into_iter().partition(|(a, _)| a.both + a.missed > 0);
    if !scored.is_empty() {
        let n = scored.len() as f64;
        let mean = scored.iter().map(|(a, _)| a.iou()).sum::<f64>() / n;
        let worst = scored
            .iter()
            .map(|(a, name)| (a.iou(), name.clone()))
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .unwrap_or_default();
        let (missed, extra) = scored.iter().fold((0.0, 0.0), |(m, e), (a, _)| {
            let (am, ae) = a.missed_and_extra();
            (m + am, e + ae)
        });
        println!(
            "IoU against {}: mean {mean:.4}, worst {:.4} ({}); per frame on average {:.1} % of the person missed, {:.1} % of its area added",
            truth.map(|t| t.display().to_string()).unwrap_or_default(),
            worst.0,
            worst.1,
            100.0 * missed / n,
            100.0 * extra / n,
        );
    }
    if !nobody.is_empty() {
        let empty = nobody.iter().filter(|(a, _)| a.extra == 0).count();
        let most = nobody
            .iter()
            .max_by_key(|(a, _)| a.extra)
            .map(|(a, name)| format!("; at most {} ({name})", a.extra))
            .filter(|_| empty < nobody.len())
            .unwrap_or_default();
        println!(
            "{} with nobody in the truth (not in the IoU): {empty} given an empty mask, {} person pixels{most}",
            cli::counted(nobody.len(), "frame", "frames"),
            nobody.iter().map(|(a, _)| a.extra).sum::<usize>(),
        );
    }
    if let Some(truth) = truth.filter(|_| unscored > 0) {
        println!(
            "{unscored} frames not scored: no mask of their name in {}",
            truth.display()
        );
    }
    Ok(())
}

/// The mask (8-bit grey, 255 = person) at `path` for `frame`, whose size it must have; `what`
/// names it in errors ("mask", "truth mask").
fn read_mask_for(path: &Path, frame: &image::RgbImage, what: &str) -> anyhow::Result<Mask> {
    let grey = image::open(path)
        .with_context(|| format!("cannot read {what} {}", path.display()))?
        .to_luma8();
    cli::ensure_mask_size(path, grey.dimensions(), frame.dimensions(), what)?;
    Ok(Mask::from_gray(&grey))
}

fn describe(
    suit_dir: &Path,
    input: &str,
    masks: Option<&PathBuf>,
    out: &Path,
    markers_out: Option<&PathBuf>,
    descriptor: &str,
    truth_markers: Option<&PathBuf>,
) -> anyhow::Result<()> {
    use suitcap::descriptor::markers::{
        match_markers, match_tolerance, score_matching, MarkerScore, TruthMarker,
        COUNTED_VISIBLE_FRACTION, COUNTED_VISIBLE_PX,
    };
    use suitcap::descriptor::{Codebooks, Describer, DescriptorKind};
    let kind = DescriptorKind::parse(descriptor).with_context(|| {
        format!("--descriptor '{descriptor}': expected fc, hog, fc+hog, full or silhouette")
    })?;
    cli::ensure_mask_dir("--masks", masks)?;
    let suit = SuitDefinition::load_dir(suit_dir)?;
    let codebooks = Codebooks::load(suit_dir)?;
    let mut segmenter = match masks {
        Some(_) => None,
        None => Some(Segmenter::new(
            SegmenterTables::load(suit_dir)?,
            &suit,
            SegmenterOptions::default(),
        )),
    };
    let truth = match truth_markers {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("cannot read {}", path.display()))?;
            Some(suitcap::dataset::markers_from_csv(&text, path)?)
        }
        None => None,
    };
    let names = output_names(input)?;
    let mut source = open_source(input, &SourceOptions::default())?;
    let mut describer = Describer::new(&suit);
    let mut rows = String::new();
    rows.push_str("frame,person");
    for k in 0..kind.len() {
        rows.push_str(&format!(",d{k}"));
    }
    rows.push('\n');
    let mut marker_rows = String::from("frame,colour,x,y,area\n");
    let mut skipped = Vec::new();
    let (mut frames, mut times, mut counts) = (0usize, Vec::new(), Vec::new());
    // The count (every marker with 60 % of its square visible) and a stricter one.
    let (mut score, mut score_px) = (MarkerScore::default(), MarkerScore::default());
    while let Some(frame) = next_good_frame(source.as_mut(), &mut skipped, frames) {
        let name = names
            .as_ref()
            .and_then(|n| n.get(frame.index as usize).cloned())
            .unwrap_or_else(|| format!("{:06}.png", frame.index));
        let mask = match (masks, segmenter.as_mut()) {
            (Some(dir), _) => read_mask_for(&dir.join(&name), &frame.image, "mask")?,
            (None, Some(segmenter)) => segmenter.segment(&frame.image).mask,
            (None, None) => bail!("no masks and no segmenter"),
        };
        let started = std::time::Instant::now();
        let (d, markers) = describer.describe(&frame.image, &mask, kind, &codebooks);
        times.push(started.elapsed().as_secs_f64() * 1e3);
        counts.push(markers.len());
        rows.push_str(&format!("{},{}", frame.index, d.person as u8));
        for v in &d.values {
            rows.push_str(&format!(",{v:.6}"));
        }
        rows.push('\n');
        for m in &markers {
            let colour = suit
                .markers
                .get(m.colour)
                .map(|c| c.name.as_str())
                .unwrap_or("?");
            marker_rows.push_str(&format!(
                "{},{colour},{:.3},{:.3},{}\n",
                frame.index, m.centre.x, m.centre.y, m.area
            ));
        }
        if let Some(truth) = &truth {
            let expected = TruthMarker::of_frame(truth, frame.index as usize, &suit);
            // One matching, scored under both counts.
            let (matched, used) = match_markers(&markers, &expected, match_tolerance(&expected));
            score.add(score_matching(
                &matched,
                &used,
                &expected,
                COUNTED_VISIBLE_FRACTION,
                0,
            ));
            score_px.add(score_matching(
                &matched,
                &used,
                &expected,
                COUNTED_VISIBLE_FRACTION,
                COUNTED_VISIBLE_PX,
            ));
        }
        frames += 1;
    }
    suitcap::io::write_atomic(out, rows.as_bytes())
        .with_context(|| format!("cannot write {}", out.display()))?;
    if let Some(path) = markers_out {
        suitcap::io::write_atomic(path, marker_rows.as_bytes())
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    let median = cli::median(&times);
    let mean_markers = counts.iter().sum::<usize>() as f64 / counts.len().max(1) as f64;
    println!("{frames} {} descriptors ({} values) written to {}; median {median:.2} ms per frame, {mean_markers:.0} markers per frame; {}", kind.name(), kind.len(), out.display(), cli::counted(skipped.len(), "corrupt frame skipped", "corrupt frames skipped"));
    if truth.is_some() {
        println!(
            "markers vs truth (those with ≥ 60 % of their square visible): recall {:.4} ({} of {}), precision {:.4} ({} of {} detections); of those with ≥ {COUNTED_VISIBLE_PX} px visible too: recall {:.4} ({} of {})",
            score.recall(), score.found, score.truth, score.precision(), score.correct, score.detections,
            score_px.recall(), score_px.found, score_px.truth
        );
    }
    Ok(())
}

fn suit_pattern(
    suit: &Path,
    out: &Path,
    subject: Option<&str>,
    height: Option<f32>,
    girth: Option<f32>,
    dpi: f32,
    marker_ids: bool,
) -> anyhow::Result<()> {
    use suitcap::pattern::{pattern_subject, subject_note, write_suit_pattern, PatternOptions};
    let subject = pattern_subject(subject, height, girth)?;
    let options = PatternOptions { dpi, marker_ids };
    let files = write_suit_pattern(suit, &subject, out, &options)?;
    println!(
        "{} files in {} ({}; PNG at {dpi} dpi, SVG at true size in mm): print at 100 % and check the 10 cm bar",
        files.len(),
        out.display(),
        subject_note(&subject)
    );
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Capture {
            input,
            out,
            frames,
            size,
            fps,
            jpeg,
        } => capture(input, out, *frames, *size, *fps, *jpeg),
        Command::Check { suit, data } => check(suit, data.as_deref()),
        Command::Run {
            input,
            suit,
            out,
            camera,
            camera_time,
            garment,
            pose,
        } => {
            let clock = if *camera_time {
                cli::tryon::TakeClock::CaptureTime
            } else {
                cli::tryon::TakeClock::InputFrames
            };
            cli::tryon::run(input, suit, out, camera.as_ref(), clock, garment, pose)
        }
        Command::Live {
            device,
            suit,
            camera,
            size,
            fps,
            record,
            garment,
            pose,
        } => cli::tryon::live(
            device,
            suit,
            camera.as_ref(),
            *size,
            *fps,
            record.as_ref(),
            garment,
            pose,
        ),
        Command::Drape {
            motion,
            camera,
            frames,
            masks,
            out,
            garment,
        } => cli::tryon::drape(motion, camera, frames, masks.as_ref(), out, garment),
        Command::Demo { suit, out } => cli::tryon::demo(suit, out),
        Command::Bench(args) => cli::bench::bench(args),
        Command::Suit {
            command:
                SuitCommand::Pattern {
                    suit,
                    out,
                    subject,
                    height,
                    girth,
                    dpi,
                    marker_ids,
                },
        } => suit_pattern(
            suit,
            out,
            subject.as_deref(),
            *height,
            *girth,
            *dpi,
            *marker_ids,
        ),
        Command::Describe {
            suit,
            input,
            masks,
            out,
            markers_out,
            descriptor,
            truth_markers,
        } => describe(
            suit,
            input,
            masks.as_ref(),
            out,
            markers_out.as_ref(),
            descriptor,
            truth_markers.as_ref(),
        ),
        Command::Segment {
            suit,
            input,
            out,
            truth,
            weights,
            part_memory,
            part_look,
            hand_look,
            part_colours,
            keep_room_share,
            cloth_reach,
            first_frame_passes,
            label_prior_share,
            suit_holes,
            no_unmix,
            no_room,
            no_lost_retry,
            room_band_odds,
            dump_graph,
            graph_out,
        } => segmenter_options(
            (*part_memory, *part_look, *hand_look),
            *part_colours,
            (*keep_room_share, *suit_holes, *room_band_odds),
            (*cloth_reach, *first_frame_passes, *label_prior_share),
            (*no_room, *no_unmix, *no_lost_retry),
        )
        .and_then(|options| {
            segment(
                suit,
                input,
                out,
                truth.as_ref(),
                weights.as_deref(),
                options,
                dump_graph.zip(graph_out.as_ref()),
            )
        }),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", suitcap::io::error_line(e.as_ref()));
            ExitCode::FAILURE
        }
    }
}
