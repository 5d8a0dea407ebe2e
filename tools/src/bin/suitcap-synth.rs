//! `suitcap-synth`: renders a person in the marker suit, driven by a BVH clip, over real backgrounds,
//! and writes a mocap-aligned dataset (frames, masks, motion.bvh, camera.toml, markers.csv, manifest.toml).

use std::ops::Range;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use indicatif::{ProgressBar, ProgressStyle};

use suitcap_tools::synth::{generate, SynthOptions};

/// Folder of the backgrounds shipped in the repository, used when --backgrounds is not given.
const BUNDLED_BACKGROUNDS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/data/backgrounds");
const DEFAULT_SUIT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../suits/default");

#[derive(Parser)]
#[command(
    name = "suitcap-synth",
    version,
    about = "Render a synthetic, mocap-aligned marker-suit dataset"
)]
struct Args {
    /// BVH clip that drives the body (CMU/Daz joint names, e.g. tests/data/mocap/*.bvh).
    #[arg(long)]
    bvh: PathBuf,
    /// Output dataset directory.
    #[arg(long)]
    out: PathBuf,
    /// First clip frame used (the shipped clips start with a T-pose and a blend: skip ~10 frames).
    #[arg(long, default_value_t = 12)]
    start_frame: usize,
    /// Number of frames to render (default: as many as the clip holds).
    #[arg(long)]
    frames: Option<usize>,
    /// Camera frame rate; the clip is resampled to it.
    #[arg(long, default_value_t = 30.0)]
    fps: f64,
    /// Image size: 640x480 (default), 1280x720, 1440x1080 or any WIDTHxHEIGHT.
    #[arg(long, default_value = "640x480")]
    size: String,
    /// Built-in subject by name or index (ana, ben, chidi, dana, emil, fumiko = 0..5); default: from the seed.
    #[arg(long)]
    subject: Option<String>,
    /// Folder(s) of photographs and/or numbered video frames (repeatable). Default: the bundled set.
    #[arg(long)]
    backgrounds: Vec<PathBuf>,
    /// Suit directory (suit.toml).
    #[arg(long, default_value = DEFAULT_SUIT)]
    suit: PathBuf,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Replace a dataset that already exists in --out.
    #[arg(long)]
    overwrite: bool,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Frames rendered without the person, as FIRST..END (END not included; repeatable): the room
    /// alone, an empty mask. E.g. `--absent 0..20` for someone who steps into view at frame 20.
    #[arg(long, value_parser = parse_range)]
    absent: Vec<Range<usize>>,
}

/// `text` as two numbers on either side of `separator`; errors name `flag`, the `form` it takes
/// and which number was bad.
fn parse_pair<T: std::str::FromStr>(
    text: &str,
    separator: &str,
    flag: &str,
    (form, first, second): (&str, &str, &str),
) -> Result<(T, T), String> {
    let (a, b) = text
        .split_once(separator)
        .ok_or_else(|| format!("{flag} '{text}' is not {form}"))?;
    let a = a
        .parse::<T>()
        .map_err(|_| format!("{flag} '{text}': bad {first}"))?;
    let b = b
        .parse::<T>()
        .map_err(|_| format!("{flag} '{text}': bad {second}"))?;
    Ok((a, b))
}

fn parse_range(text: &str) -> Result<Range<usize>, String> {
    let names = ("FIRST..END", "first frame", "end frame");
    let (first, end) = parse_pair::<usize>(text, "..", "--absent", names)?;
    if end <= first {
        return Err(format!("--absent '{text}': END must be after FIRST"));
    }
    Ok(first..end)
}

fn parse_size(text: &str) -> Result<(u32, u32), String> {
    parse_pair(text, "x", "--size", ("WIDTHxHEIGHT", "width", "height"))
}

fn run(args: Args) -> anyhow::Result<()> {
    let (width, height) = parse_size(&args.size).map_err(anyhow::Error::msg)?;
    if let Some(threads) = args.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build_global()?;
    }
    let backgrounds = if args.backgrounds.is_empty() {
        vec![PathBuf::from(BUNDLED_BACKGROUNDS)]
    } else {
        args.backgrounds
    };
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    let options = SynthOptions {
        bvh: args.bvh,
        out: args.out,
        start_frame: args.start_frame,
        frames: args.frames,
        fps: args.fps,
        width,
        height,
        subject: args.subject,
        backgrounds,
        suit_dir: args.suit,
        seed: args.seed,
        overwrite: args.overwrite,
        command,
        absent: args.absent,
    };
    let bar = ProgressBar::new(args.frames.unwrap_or(0) as u64);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} frames {per_sec} {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    if args.frames.is_none() {
        bar.set_length(0);
    }
    let summary = generate(&options, &|| bar.inc(1))?;
    bar.finish_and_clear();
    println!(
        "{} frames of subject '{}' over {} written to {} in {:.2} s ({:.1} frames/s rendering and writing); {:.0} visible markers per frame",
        summary.frames,
        summary.subject,
        summary.background,
        options.out.display(),
        summary.seconds_total,
        summary.frames as f64 / summary.seconds_rendering,
        summary.mean_visible_markers
    );
    Ok(())
}

fn main() -> ExitCode {
    match run(Args::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", suitcap::io::error_line(e.as_ref()));
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{parse_range, parse_size};

    #[test]
    fn ranges_and_sizes_parse_and_bad_ones_name_what_is_wrong() {
        assert_eq!(parse_range("0..20"), Ok(0..20));
        assert_eq!(parse_size("640x480"), Ok((640, 480)));
        for (text, wrong) in [
            ("5..2", "END must be after FIRST"),
            ("3..3", "END must be after FIRST"),
            ("5-9", "is not FIRST..END"),
            ("a..9", "bad first frame"),
            ("1..-9", "bad end frame"),
        ] {
            let err = parse_range(text).expect_err(text);
            assert!(err.contains("--absent") && err.contains(wrong), "{err}");
        }
        let err = parse_size("64xq").expect_err("bad height");
        assert!(err.contains("--size '64xq': bad height"), "{err}");
    }
}
