//! suitcap: monocular motion capture and virtual try-on from a printed marker suit.
//!
//! The pipeline, one module per stage (after Rogge, Neumann, Wacker, Magnor 2011, "Monocular Pose
//! Reconstruction for an Augmented Reality Clothing System"):
//!
//! ```text
//! source (camera, frame directory, Y4M) → segmenter (mask) → marker detection → descriptors
//!   → RVM regression (pose vector) → joint angles + root (camera) → BVH / forward kinematics
//!   → body proxies → cloth → render + composite
//! ```
//!
//! Frames come from [`source`]; [`segment`] gives the person [`mask`]; [`descriptor`] the 304-D
//! descriptor; [`pose`] the regressed pose, its smoothing, limits and root registration, and
//! [`pipeline`] joins those per stream. [`body_size`], [`cloth`], [`render`] and [`composite`] put a
//! garment on the estimated body and into the frame; [`tryon`] runs every stage on threads joined by
//! [`queue`]s. Around them: [`suit`], [`skeleton`] and [`bvh`], [`camera`], [`body`], [`raster`],
//! [`colour`], [`dataset`], [`model`] and the suit's [`manifest`], [`pattern`], [`preview`],
//! [`stats`] and [`io`].

pub mod body;
pub mod body_size;
pub mod bvh;
pub mod camera;
pub mod cloth;
pub mod colour;
pub mod composite;
pub mod dataset;
pub mod descriptor;
pub mod io;
pub mod manifest;
pub mod mask;
pub mod model;
pub mod pattern;
pub mod pipeline;
pub mod pose;
pub mod preview;
pub mod queue;
pub mod raster;
pub mod render;
pub mod segment;
pub mod skeleton;
pub mod source;
pub mod stats;
pub mod suit;
pub mod tryon;
