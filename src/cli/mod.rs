//! The runtime command line's larger subcommands, one file per group.

pub mod bench;
pub mod tryon;
