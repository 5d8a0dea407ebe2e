//! The runtime command line's larger subcommands, one file per group.

pub mod bench;
pub mod tryon;

/// `n` and the noun in the number `n` asks for, for a report: `counted(1, "frame", "frames")` is
/// "1 frame", `counted(0, "frame", "frames")` "0 frames".
pub fn counted(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

/// The median of `values` for a report; 0 when empty.
pub fn median(values: &[f64]) -> f64 {
    suitcap::stats::median(values).unwrap_or(0.0)
}

/// Errors unless a mask read from `path` (`size`, width × height) has the frames' `frame_size`;
/// `what` names it ("mask", "truth mask").
pub fn ensure_mask_size(
    path: &std::path::Path,
    size: (u32, u32),
    frame_size: (u32, u32),
    what: &str,
) -> anyhow::Result<()> {
    anyhow::ensure!(
        size == frame_size,
        "{}: a {}x{} {what} for {}x{} frames",
        path.display(),
        size.0,
        size.1,
        frame_size.0,
        frame_size.1
    );
    Ok(())
}

/// Errors unless `dir`, given with option `option` ("--truth", "--masks"), is a directory: a
/// mistyped path is named before anything is written, not taken for masks that are all missing.
pub fn ensure_mask_dir(option: &str, dir: Option<&std::path::PathBuf>) -> anyhow::Result<()> {
    match dir {
        Some(dir) if !dir.is_dir() => {
            anyhow::bail!("{option} {}: no such directory of masks", dir.display())
        }
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::counted;

    #[test]
    fn a_count_of_one_takes_the_singular_and_any_other_the_plural() {
        assert_eq!(counted(1, "frame", "frames"), "1 frame");
        assert_eq!(counted(0, "frame", "frames"), "0 frames");
        assert_eq!(
            counted(2, "root glitch", "root glitches"),
            "2 root glitches"
        );
    }
}
