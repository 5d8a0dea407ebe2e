//! `suitcap-train`: learns a suit's models from mocap-aligned video.
//!
//! Subcommands so far: `segment` learns the segmenter's lookup tables and term weights from consecutive
//! frames with masks of a dataset (the generator's format, `suitcap::dataset`); `codebooks` learns the
//! Feature Context, HOG and silhouette codebooks by k-means over the datasets' local histograms.

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
    /// Learn the FC (200), HOG (100) and silhouette (100) codebooks by k-means over the local
    /// histograms of every frame of the datasets (ground-truth masks); writes SUIT/codebook_*.bin.
    Codebooks {
        #[arg(long)]
        suit: PathBuf,
        /// Dataset directories (repeatable).
        #[arg(long, required = true)]
        data: Vec<PathBuf>,
        /// Training vectors per codebook, subsampled with the seed.
        #[arg(long, default_value_t = 20_000)]
        max_vectors: usize,
        #[arg(long, default_value_t = 1)]
        seed: u64,
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
        let (image, mask) = frame_and_mask(&dataset, index)?;
        training.push(TrainingFrame { image, mask });
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

/// Reads frame `index` and its mask from a dataset, naming the file on error.
fn frame_and_mask(dataset: &Dataset, index: usize) -> anyhow::Result<(image::RgbImage, Mask)> {
    let (frame_path, mask_path) = (dataset.frame_path(index), dataset.mask_path(index));
    let image = image::open(&frame_path)
        .with_context(|| format!("cannot read frame {index}: {}", frame_path.display()))?
        .to_rgb8();
    let mask = image::open(&mask_path)
        .with_context(|| format!("cannot read mask {index}: {}", mask_path.display()))?
        .to_luma8();
    Ok((image, Mask::from_gray(&mask)))
}

fn codebooks(
    suit_dir: &PathBuf,
    data: &[PathBuf],
    max_vectors: usize,
    seed: u64,
) -> anyhow::Result<()> {
    use rayon::prelude::*;
    use suitcap::descriptor::{codebook::Codebook, Codebooks, Describer, LocalHistograms};
    let suit = SuitDefinition::load_dir(suit_dir)?;
    let started = std::time::Instant::now();
    let mut locals: Vec<LocalHistograms> = Vec::new();
    for dir in data {
        let dataset = Dataset::open(dir)?;
        let bar = indicatif::ProgressBar::new(dataset.frame_count() as u64);
        let part = (0..dataset.frame_count())
            .into_par_iter()
            .map_init(
                || Describer::new(&suit),
                |describer, index| -> anyhow::Result<LocalHistograms> {
                    let (image, mask) = frame_and_mask(&dataset, index)?;
                    bar.inc(1);
                    Ok(describer.local_histograms(&image, &mask, None))
                },
            )
            .collect::<anyhow::Result<Vec<_>>>()?;
        bar.finish_and_clear();
        locals.extend(part);
    }
    let frames = locals.len();
    let described = started.elapsed().as_secs_f64();
    let gather = |f: &dyn Fn(&LocalHistograms) -> &Vec<f32>| {
        locals
            .iter()
            .flat_map(|l| f(l).iter().copied())
            .collect::<Vec<f32>>()
    };
    let fc = gather(&|l| &l.feature_contexts);
    let hog = gather(&|l| &l.hog_blocks);
    let sc = gather(&|l| &l.shape_contexts);
    use suitcap::descriptor::{
        feature_context::FC_LEN, hog::HOG_BINS, silhouette, FC_CENTRES, HOG_CENTRES,
        SILHOUETTE_CENTRES,
    };
    let sc_len = silhouette::SC_RADIAL * silhouette::SC_ANGULAR;
    let kmeans_started = std::time::Instant::now();
    let (fc_book, fc_inertia) = Codebook::train(
        "Feature Context",
        &fc,
        FC_LEN,
        FC_CENTRES,
        max_vectors,
        seed,
    )?;
    let (hog_book, hog_inertia) =
        Codebook::train("HOG", &hog, HOG_BINS, HOG_CENTRES, max_vectors, seed)?;
    let (sc_book, sc_inertia) = Codebook::train(
        "silhouette",
        &sc,
        sc_len,
        SILHOUETTE_CENTRES,
        max_vectors,
        seed,
    )?;
    Codebooks {
        fc: fc_book,
        hog: hog_book,
        silhouette: sc_book,
    }
    .save(suit_dir)?;
    println!(
        "codebooks from {frames} frames ({described:.1} s to describe, {:.1} s of k-means, seed {seed}, at most {max_vectors} vectors each):\n  \
         FC: {} marker histograms → {FC_CENTRES} centres, inertia {fc_inertia:.3e}\n  \
         HOG: {} blocks → {HOG_CENTRES} centres, inertia {hog_inertia:.3e}\n  \
         silhouette: {} contour points → {SILHOUETTE_CENTRES} centres, inertia {sc_inertia:.3e}\n\
         written to {}",
        kmeans_started.elapsed().as_secs_f64(),
        fc.len() / FC_LEN,
        hog.len() / HOG_BINS,
        sc.len() / sc_len,
        suit_dir.display()
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
        Command::Codebooks {
            suit,
            data,
            max_vectors,
            seed,
        } => codebooks(suit, data, *max_vectors, *seed),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
