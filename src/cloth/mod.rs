//! Cloth: garments simulated on the posed body's collision capsules.
//!
//! The stage between the pose (BVH channels per frame) and the renderer:
//!
//! ```text
//! Body (elliptic capsules) ── proxies ──▶ round tapered capsules per joint, BodyRig
//! BodyRig + rest pose ── garment / obj ──▶ GarmentMesh (rest positions, triangles, anchors)
//! GarmentMesh + Material ── solver ──▶ Cloth: dress, then step_frame(prev, next) per frame
//!                                       └─▶ positions, normals, triangles, posed capsules
//! ```
//!
//! - [`capsule`]: tapered capsules, exact signed distance, closest point, bounds.
//! - [`proxies`]: the body's parts as round capsules; [`proxies::BodyRig`] interpolates skeleton
//!   frames and poses the capsules every substep.
//! - [`material`]: fabric presets and their mapping to solver parameters.
//! - [`garment`]: procedural T-shirt, skirt and dress sized from the body, with anchors.
//! - [`obj`]: garments from OBJ files.
//! - [`topology`]: edges, hinges, boundary loops of triangle meshes.
//! - [`solver`]: the XPBD solver, quality figures, a whole-motion run for the command line.
//! - `stretch` (private): the solver's stretch sweep, eight vertex-disjoint edges at a time.
//!
//! Units: centimetres, grams, seconds; world Y up; gravity −981 cm/s².

pub mod capsule;
pub mod garment;
pub mod material;
pub mod obj;
pub mod proxies;
pub mod solver;
mod stretch;
pub mod topology;

pub use capsule::Capsule;
pub use garment::{Anchor, Cuff, GarmentKind, GarmentMesh, GarmentParams};
pub use material::Material;
pub use proxies::{BodyPose, BodyRig};
pub use solver::{Cloth, FrameQuality, QualitySummary, SolverSettings};
