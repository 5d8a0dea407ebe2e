//! The runtime command line's larger subcommands, one file per group.

pub mod bench;
pub mod tryon;

/// The median of `values` for a report; 0 when empty.
pub fn median(values: &[f64]) -> f64 {
    suitcap::stats::median(values).unwrap_or(0.0)
}
