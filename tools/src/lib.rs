//! Tools around suitcap: the synthetic mocap-aligned video generator (`suitcap-synth`).
//!
//! Real suit footage does not exist yet, so training and evaluation run on frames rendered here: a
//! suited body driven by real CMU motion capture ([`synth`]), drawn by [`render`] over real
//! photographs and video with moving clutter ([`backgrounds`]).

pub mod backgrounds;
pub mod render;
pub mod synth;
