//! `suitcap`: the runtime command line.
//!
//! Subcommands so far: `capture` records any frame source (webcam, frame directory, Y4M) into a
//! directory of numbered PNG frames — the first step of recording a new suit's training video — and
//! `check` validates a suit definition and a dataset.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{bail, Context};
use clap::{Parser, Subcommand};

use suitcap::source::{open_source, SourceOptions};

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
enum Command {
    /// Record frames from a camera (/dev/videoN or an index), a frame directory or a Y4M file into
    /// numbered PNG frames. Corrupt input frames are skipped, counted and named.
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
    },
    /// Validate a suit directory (suit.toml) and, optionally, a dataset against it.
    Check {
        #[arg(long, default_value = "suits/default")]
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
) -> anyhow::Result<()> {
    let options = SourceOptions {
        size,
        fps,
        ..SourceOptions::default()
    };
    let mut source = open_source(input, &options)?;
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    eprintln!("capturing from {}", source.describe());
    let started = Instant::now();
    let (mut written, mut skipped) = (0u64, Vec::new());
    loop {
        if frames.is_some_and(|n| written >= n) {
            break;
        }
        match source.next_frame() {
            Ok(Some(frame)) => {
                let path = out.join(format!("{written:06}.png"));
                frame
                    .image
                    .save(&path)
                    .with_context(|| format!("cannot write {}", path.display()))?;
                written += 1;
            }
            Ok(None) => break,
            Err(
                e @ (suitcap::source::SourceError::CorruptFrame { .. }
                | suitcap::source::SourceError::SizeMismatch { .. }),
            ) => {
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
        "{written} frames written to {} in {seconds:.1} s; {} corrupt frames skipped",
        out.display(),
        skipped.len()
    );
    for s in &skipped {
        println!("  skipped: {s}");
    }
    Ok(())
}

fn check(suit: &PathBuf, data: Option<&PathBuf>) -> anyhow::Result<()> {
    let definition = suitcap::suit::SuitDefinition::load_dir(suit)?;
    println!(
        "suit '{}': {} marker colours, {} cm markers every {} cm, {} estimated joints",
        definition.name,
        definition.markers.len(),
        definition.marker_size_cm,
        definition.pitch_cm(),
        definition.skeleton.joints.len()
    );
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
            "dataset {}: {} frames {}x{} at {} fps, subject '{}', clip {}",
            data.display(),
            dataset.frame_count(),
            dataset.manifest.width,
            dataset.manifest.height,
            dataset.manifest.fps,
            dataset.manifest.subject.name,
            dataset.manifest.clip.name
        );
    }
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
        } => capture(input, out, *frames, *size, *fps),
        Command::Check { suit, data } => check(suit, data.as_ref()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
