//! `suitcap-train`: learns a suit's models from mocap-aligned video.
//!
//! Subcommands so far: `segment` learns the segmenter's lookup tables and term weights from consecutive
//! frames with masks of a dataset (the generator's format, `suitcap::dataset`).

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context};
use clap::{Parser, Subcommand};

use suitcap::dataset::Dataset;
use suitcap::mask::Mask;
use suitcap::segment::{train_segmenter, TrainingFrame};
use suitcap::suit::SuitDefinition;

#[derive(Parser)]
#[command(
    name = "suitcap-train",
    version,
    about = "Train a suitcap suit from mocap-aligned video"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Learn the segmenter (colour, neighbourhood, gradient, motion and temporal tables and their
    /// weights) from consecutive frames with masks; writes SUIT/segmenter.bin.
    Segment {
        #[arg(long)]
        suit: PathBuf,
        #[arg(long)]
        data: PathBuf,
        /// Number of consecutive frames used.
        #[arg(long, default_value_t = 20)]
        frames: usize,
        /// First frame used.
        #[arg(long, default_value_t = 0)]
        start: usize,
        /// Of those, the last N are held back to choose the term weights.
        #[arg(long, default_value_t = 6)]
        held_back: usize,
        /// The cut runs on frames box-downscaled by this factor.
        #[arg(long, default_value_t = 2)]
        downscale: u32,
    },
}

fn segment(
    suit_dir: &PathBuf,
    data: &PathBuf,
    frames: usize,
    start: usize,
    held_back: usize,
    downscale: u32,
) -> anyhow::Result<()> {
    let suit = SuitDefinition::load_dir(suit_dir)?;
    let dataset = Dataset::open(data)?;
    if start + frames > dataset.frame_count() {
        bail!(
            "{}: has {} frames; frames {start}..{} were asked for",
            data.display(),
            dataset.frame_count(),
            start + frames
        );
    }
    let mut training = Vec::with_capacity(frames);
    for index in start..start + frames {
        let (frame_path, mask_path) = (dataset.frame_path(index), dataset.mask_path(index));
        let image = image::open(&frame_path)
            .with_context(|| format!("cannot read frame {index}: {}", frame_path.display()))?
            .to_rgb8();
        let mask = image::open(&mask_path)
            .with_context(|| format!("cannot read mask {index}: {}", mask_path.display()))?
            .to_luma8();
        training.push(TrainingFrame {
            image,
            mask: Mask::from_gray(&mask),
        });
    }
    let started = std::time::Instant::now();
    let (tables, report) = train_segmenter(&training, &suit, downscale, held_back)?;
    tables.save(suit_dir)?;
    let w = report.weights;
    println!(
        "segmenter trained on frames {start}..{} of {} in {:.1} s: tables counted on the first {} frames, weights chosen on the last {} (coordinate search, {} runs): \
         σ_C {:.3}, σ_N {:.3}, σ_G {:.3}, σ_M {:.3}, σ_T {:.3}; held-back mean IoU {:.4} (all weights 1: {:.4}); final tables counted on all {} frames; written to {}",
        start + frames,
        data.display(),
        started.elapsed().as_secs_f64(),
        report.frames - report.held_back,
        report.held_back,
        report.evaluations,
        w.colour,
        w.neighbourhood,
        w.gradient,
        w.motion,
        w.temporal,
        report.chosen_iou,
        report.default_iou,
        report.frames,
        suit_dir.join(suitcap::segment::tables::SEGMENTER_FILE).display()
    );
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Segment {
            suit,
            data,
            frames,
            start,
            held_back,
            downscale,
        } => segment(suit, data, *frames, *start, *held_back, *downscale),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
