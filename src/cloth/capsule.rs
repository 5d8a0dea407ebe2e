//! Tapered capsules (sphere-swept cones): the body's collision proxies, in world centimetres.

use glam::Vec3;

/// The convex hull of a sphere of `radius_a` at `a` and one of `radius_b` at `b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Capsule {
    pub a: Vec3,
    pub b: Vec3,
    pub radius_a: f32,
    pub radius_b: f32,
}
