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
//! Modules present so far: [`source`] (frames in), [`suit`] (the suit definition), [`skeleton`] and
//! [`bvh`] (hierarchy, forward kinematics, BVH files), [`camera`] (pinhole model, `camera.toml`),
//! [`body`] (subjects and capsule bodies carrying the suit pattern), [`raster`] (z-buffered triangles),
//! [`colour`] (HSV), [`dataset`] (the generator's mocap-aligned dataset format) and [`io`].

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
pub mod tryon;
pub mod suit;
