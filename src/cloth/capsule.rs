//! Tapered capsules (sphere-swept cones): the body's collision proxies, in world centimetres.
//!
//! A [`Capsule`] is the convex hull of two spheres. This module answers the questions the cloth
//! solver and the renderer ask about one: the exact signed distance of a point to its surface
//! (negative inside), the closest surface point and the outward normal there ([`Capsule::closest`]),
//! and an axis-aligned bounding box ([`Capsule::aabb`]) for broad phases. The distance is exact for
//! any radii, including a taper and the case where one sphere contains the other (the capsule is
//! then that sphere).
//!
//! Geometry: in the half-plane through the axis, with `x` along the axis from `a` and `y` the
//! distance from it, the hull's side is the line tangent to both circles. Its outward normal is
//! `(s, c)` with `s = (radius_a − radius_b) / |b − a|` and `c = √(1 − s²)`; it touches the circles at
//! parameters `0` and `|b − a|·c` along the tangent direction `(c, −s)`. A point whose tangent
//! coordinate `x·c − y·s` is below 0 is nearest to sphere `a`, above `|b − a|·c` to sphere `b`, and
//! otherwise to the side, at signed distance `x·s + y·c − radius_a`. Hands to the solver:
//! [`PreparedCapsule`] (the same query with the per-capsule constants precomputed, in SIMD
//! vectors); to the renderer: the [`Capsule`] fields themselves.

use glam::{Vec3, Vec3A};

/// The convex hull of a sphere of `radius_a` at `a` and one of `radius_b` at `b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Capsule {
    pub a: Vec3,
    pub b: Vec3,
    pub radius_a: f32,
    pub radius_b: f32,
}

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    /// The empty box (union identity).
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// The box grown by `margin` on every side.
    pub fn expanded(&self, margin: f32) -> Aabb {
        Aabb {
            min: self.min - Vec3::splat(margin),
            max: self.max + Vec3::splat(margin),
        }
    }

    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    pub fn overlaps(&self, other: &Aabb) -> bool {
        self.min.cmple(other.max).all() && other.min.cmple(self.max).all()
    }
}

/// The point of a capsule's surface nearest to a query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Signed distance from the query point to the surface (negative inside).
    pub distance: f32,
    /// The surface point.
    pub point: Vec3,
    /// Unit outward normal at `point`; the query point is `point + normal · distance`.
    pub normal: Vec3,
}

impl Capsule {
    pub fn new(a: Vec3, b: Vec3, radius_a: f32, radius_b: f32) -> Capsule {
        Capsule {
            a,
            b,
            radius_a,
            radius_b,
        }
    }

    /// The centre and radius of the sphere a fraction `t` of the way from `a` to `b`: the capsule
    /// is the union of these spheres for `t` in [0, 1].
    pub fn sphere_at(&self, t: f32) -> (Vec3, f32) {
        (
            self.a.lerp(self.b, t),
            self.radius_a + (self.radius_b - self.radius_a) * t,
        )
    }

    /// Exact signed distance from `p` to the surface, negative inside.
    pub fn signed_distance(&self, p: Vec3) -> f32 {
        self.prepared().distance(p.into())
    }

    /// Closest surface point, outward normal and signed distance.
    pub fn closest(&self, p: Vec3) -> SurfacePoint {
        let (distance, normal) = self.prepared().query(p.into());
        let normal = Vec3::from(normal);
        SurfacePoint {
            distance,
            point: p - normal * distance,
            normal,
        }
    }

    /// Tight axis-aligned bounds (the union of both spheres' boxes bounds the hull exactly).
    pub fn aabb(&self) -> Aabb {
        Aabb {
            min: (self.a - Vec3::splat(self.radius_a)).min(self.b - Vec3::splat(self.radius_b)),
            max: (self.a + Vec3::splat(self.radius_a)).max(self.b + Vec3::splat(self.radius_b)),
        }
    }

    /// The capsule with its constants precomputed for repeated queries.
    pub fn prepared(&self) -> PreparedCapsule {
        PreparedCapsule::new(self)
    }
}

/// A [`Capsule`] ready for fast distance queries.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PreparedCapsule {
    a: Vec3A,
    b: Vec3A,
    /// Unit axis from `a` to `b` (any unit vector when the capsule is a sphere).
    axis: Vec3A,
    radius_a: f32,
    radius_b: f32,
    /// `|b − a| · cos`: tangent coordinate where the side meets sphere `b`.
    side_end: f32,
    sin: f32,
    cos: f32,
    /// One sphere contains the other (or the axis is degenerate): the capsule is a single sphere.
    sphere: Option<(Vec3A, f32)>,
}

impl PreparedCapsule {
    pub fn new(capsule: &Capsule) -> PreparedCapsule {
        let a = Vec3A::from(capsule.a);
        let b = Vec3A::from(capsule.b);
        let (ra, rb) = (capsule.radius_a, capsule.radius_b);
        let length = (b - a).length();
        let sphere = if length.is_nan() || length <= 1e-6 || (ra - rb).abs() >= length {
            Some(if ra >= rb { (a, ra) } else { (b, rb) })
        } else {
            None
        };
        let axis = if length > 1e-6 {
            (b - a) / length
        } else {
            Vec3A::Y
        };
        let sin = if sphere.is_none() {
            (ra - rb) / length
        } else {
            0.0
        };
        let cos = (1.0 - sin * sin).max(0.0).sqrt();
        PreparedCapsule {
            a,
            b,
            axis,
            radius_a: ra,
            radius_b: rb,
            side_end: length * cos,
            sin,
            cos,
            sphere,
        }
    }

    /// Signed distance and unit outward normal at the nearest surface point.
    #[inline]
    pub fn query(&self, p: Vec3A) -> (f32, Vec3A) {
        if let Some((centre, radius)) = self.sphere {
            return sphere_query(p, centre, radius, self.axis);
        }
        let ap = p - self.a;
        let x = ap.dot(self.axis);
        let radial = ap - self.axis * x;
        let y = radial.length();
        let t = x * self.cos - y * self.sin;
        if t < 0.0 {
            sphere_query(p, self.a, self.radius_a, self.axis)
        } else if t > self.side_end {
            sphere_query(p, self.b, self.radius_b, self.axis)
        } else {
            let radial_dir = if y > 1e-6 {
                radial / y
            } else {
                self.axis.any_orthonormal_vector()
            };
            (
                x * self.sin + y * self.cos - self.radius_a,
                self.axis * self.sin + radial_dir * self.cos,
            )
        }
    }

    /// Signed distance only.
    #[inline]
    pub fn distance(&self, p: Vec3A) -> f32 {
        if let Some((centre, radius)) = self.sphere {
            return (p - centre).length() - radius;
        }
        let ap = p - self.a;
        let x = ap.dot(self.axis);
        let y = (ap - self.axis * x).length();
        let t = x * self.cos - y * self.sin;
        if t < 0.0 {
            ap.length() - self.radius_a
        } else if t > self.side_end {
            (p - self.b).length() - self.radius_b
        } else {
            x * self.sin + y * self.cos - self.radius_a
        }
    }

    /// Whether the straight path from `from` to `to` goes through the capsule while both ends lie
    /// outside it. The signed distance to a convex body is convex along a line, so its minimum on
    /// the path is found by golden-section search; since the distance changes by at most the
    /// distance moved, the search is skipped when the ends are too far out for the path to reach
    /// the surface (`d(from) + d(to) ≥ |to − from|`), which is almost always, and usually already
    /// when `d(to)` alone is that far.
    #[inline]
    pub fn path_passes_through(&self, from: Vec3A, to: Vec3A) -> bool {
        let d_to = self.distance(to);
        let length2 = (to - from).length_squared();
        if d_to <= 0.0 || d_to * d_to >= length2 {
            return false;
        }
        let d_from = self.distance(from);
        if d_from <= 0.0 || d_from + d_to >= length2.sqrt() {
            return false;
        }
        let at = |s: f32| self.distance(from + (to - from) * s);
        let ratio = 0.5 * (5f32.sqrt() - 1.0);
        let (mut lo, mut hi) = (0.0f32, 1.0f32);
        let (mut s1, mut s2) = (hi - ratio * (hi - lo), lo + ratio * (hi - lo));
        let (mut d1, mut d2) = (at(s1), at(s2));
        for _ in 0..40 {
            if d1.min(d2) < 0.0 {
                return true;
            }
            if d1 < d2 {
                hi = s2;
                (s2, d2) = (s1, d1);
                s1 = hi - ratio * (hi - lo);
                d1 = at(s1);
            } else {
                lo = s1;
                (s1, d1) = (s2, d2);
                s2 = lo + ratio * (hi - lo);
                d2 = at(s2);
            }
        }
        d1.min(d2) < 0.0
    }
}

#[inline]
fn sphere_query(p: Vec3A, centre: Vec3A, radius: f32, axis: Vec3A) -> (f32, Vec3A) {
    let d = p - centre;
    let length = d.length();
    let normal = if length > 1e-6 {
        d / length
    } else {
        axis.any_orthonormal_vector()
    };
    (length - radius, normal)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f32, b: f32) -> bool {
        (a - b).abs() < 1e-4
    }

    /// Axis 10 cm along X, radius 3 at the origin tapering to 1: sin = (3 − 1)/10 = 0.2,
    /// cos = √0.96 = 0.979796.
    fn cone() -> Capsule {
        Capsule::new(Vec3::ZERO, Vec3::new(10.0, 0.0, 0.0), 3.0, 1.0)
    }

    #[test]
    fn tapered_side_distance_is_the_tangent_line_distance() {
        let c = cone();
        // (5, 5): tangent coordinate 5·0.9798 − 5·0.2 = 3.90 ∈ [0, 9.80] → side:
        // 5·0.2 + 5·0.9798 − 3 = 2.898979.
        let s = c.closest(Vec3::new(5.0, 5.0, 0.0));
        assert!(close(s.distance, 2.898979), "{s:?}");
        assert!((s.normal - Vec3::new(0.2, 0.979796, 0.0)).length() < 1e-5);
        // The surface point is on the surface and p = point + normal·distance.
        assert!(c.signed_distance(s.point).abs() < 1e-4);
        // The same by symmetry in any direction around the axis.
        assert!(close(
            c.signed_distance(Vec3::new(5.0, 0.0, -5.0)),
            2.898979
        ));
        // On the axis at x = 5: 5·0.2 − 3 = −2 (inside).
        assert!(close(c.signed_distance(Vec3::new(5.0, 0.0, 0.0)), -2.0));
    }

    #[test]
    fn ends_are_spheres() {
        let c = cone();
        assert!(close(c.signed_distance(Vec3::new(-5.0, 0.0, 0.0)), 2.0));
        assert!(close(c.signed_distance(Vec3::new(15.0, 0.0, 0.0)), 4.0));
        // Behind sphere a, off axis: (−3, 4) is 5 from a → 2.
        let s = c.closest(Vec3::new(-3.0, 4.0, 0.0));
        assert!(close(s.distance, 2.0));
        assert!((s.point - Vec3::new(-1.8, 2.4, 0.0)).length() < 1e-5);
        // Just past sphere b's tangent circle the distance is to b: (12, 1) → √5 − 1.
        assert!(close(
            c.signed_distance(Vec3::new(12.0, 1.0, 0.0)),
            5f32.sqrt() - 1.0
        ));
    }

    #[test]
    fn taper_in_the_other_direction_is_the_mirror_image() {
        let c = Capsule::new(Vec3::ZERO, Vec3::new(10.0, 0.0, 0.0), 1.0, 3.0);
        assert!(close(c.signed_distance(Vec3::new(5.0, 5.0, 0.0)), 2.898979));
        assert!(close(c.signed_distance(Vec3::new(-5.0, 0.0, 0.0)), 4.0));
    }

    #[test]
    fn a_sphere_containing_the_other_is_the_whole_capsule() {
        // |ra − rb| = 4 ≥ |b − a| = 1: the capsule is the big sphere.
        let c = Capsule::new(Vec3::ZERO, Vec3::new(1.0, 0.0, 0.0), 5.0, 1.0);
        assert!(close(c.signed_distance(Vec3::new(0.0, 7.0, 0.0)), 2.0));
        assert!(close(c.signed_distance(Vec3::new(3.0, 0.0, 0.0)), -2.0));
        assert!(close(c.signed_distance(Vec3::new(-3.0, 0.0, 0.0)), -2.0));
        let c = Capsule::new(Vec3::ZERO, Vec3::new(0.0, 1.0, 0.0), 1.0, 5.0);
        assert!(close(c.signed_distance(Vec3::new(0.0, 9.0, 0.0)), 3.0));
        // A point sphere at one end (degenerate axis).
        let c = Capsule::new(Vec3::ONE, Vec3::ONE, 2.0, 2.0);
        assert!(close(c.signed_distance(Vec3::new(1.0, 1.0, 4.0)), 1.0));
    }

    #[test]
    fn cylinder_matches_the_segment_distance() {
        let c = Capsule::new(Vec3::ZERO, Vec3::new(0.0, 20.0, 0.0), 4.0, 4.0);
        assert!(close(c.signed_distance(Vec3::new(6.0, 10.0, 0.0)), 2.0));
        assert!(close(c.signed_distance(Vec3::new(0.0, 25.0, 0.0)), 1.0));
        assert!(close(c.signed_distance(Vec3::new(1.0, 10.0, 0.0)), -3.0));
        let s = c.closest(Vec3::new(0.0, 10.0, 0.0));
        assert!(close(s.distance, -4.0));
        assert!(close(s.normal.length(), 1.0));
    }

    /// A tapered capsule at a slant to every axis.
    fn slanted() -> Capsule {
        Capsule::new(
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(-4.0, 9.0, 1.0),
            2.5,
            1.2,
        )
    }

    /// A linear congruential generator of coordinates in [−12, 12).
    fn uniform_in_24_cm(seed: u32) -> impl FnMut() -> f32 {
        let mut state = seed;
        move || {
            state = state.wrapping_mul(1664525).wrapping_add(1013904223);
            (state >> 8) as f32 / (1u32 << 24) as f32 * 24.0 - 12.0
        }
    }

    #[test]
    fn a_path_through_the_capsule_passes_and_one_beside_or_into_it_does_not() {
        // A cylinder of radius 4 along Y from 0 to 20.
        let c = Capsule::new(Vec3::ZERO, Vec3::new(0.0, 20.0, 0.0), 4.0, 4.0).prepared();
        let path = |from: [f32; 3], to: [f32; 3]| {
            c.path_passes_through(Vec3A::from_array(from), Vec3A::from_array(to))
        };
        // Through the axis: both ends 2 outside.
        assert!(path([-6.0, 10.0, 0.0], [6.0, 10.0, 0.0]));
        // 5 from the axis at the closest: 1 outside all the way.
        assert!(!path([-6.0, 10.0, 5.0], [6.0, 10.0, 5.0]));
        // 3.9 from the axis at the closest: grazes 0.1 deep.
        assert!(path([-6.0, 10.0, 3.9], [6.0, 10.0, 3.9]));
        // Over the end sphere (the top at y = 24) and through it.
        assert!(!path([-6.0, 24.5, 0.0], [6.0, 24.5, 0.0]));
        assert!(path([-6.0, 23.0, 0.0], [6.0, 23.0, 0.0]));
        // Ending inside, or starting there, is penetration, not a passage.
        assert!(!path([-6.0, 10.0, 0.0], [0.0, 10.0, 0.0]));
        assert!(!path([0.0, 10.0, 0.0], [6.0, 10.0, 0.0]));
        // A short step outside, and no step at all.
        assert!(!path([-6.0, 10.0, 0.0], [-5.0, 10.0, 0.0]));
        assert!(!path([-6.0, 10.0, 0.0], [-6.0, 10.0, 0.0]));
    }

    #[test]
    fn path_passes_through_agrees_with_a_dense_sampling() {
        let c = slanted().prepared();
        let mut rnd = uniform_in_24_cm(777);
        let (mut passes, mut checked) = (0, 0);
        for _ in 0..2000 {
            let from = Vec3A::new(rnd(), rnd(), rnd());
            let to = Vec3A::new(rnd(), rnd(), rnd());
            let samples: Vec<f32> = (0..=4000)
                .map(|k| c.distance(from + (to - from) * (k as f32 / 4000.0)))
                .collect();
            let deepest = samples.iter().copied().fold(f32::INFINITY, f32::min);
            let ends_out = samples[0] > 0.0 && samples[4000] > 0.0;
            // Leave out paths that only graze the surface, where sampling and search may differ.
            if deepest.abs() < 1e-3 {
                continue;
            }
            checked += 1;
            let expected = ends_out && deepest < 0.0;
            passes += expected as usize;
            assert_eq!(c.path_passes_through(from, to), expected, "{from} → {to}");
        }
        assert!(checked > 1900 && passes > 100, "{checked} {passes}");
    }

    #[test]
    fn distance_is_consistent_with_closest_and_brute_force() {
        // Against a brute-force minimum over the union of spheres along the axis (which is the hull).
        let c = slanted();
        let mut rnd = uniform_in_24_cm(12345);
        for _ in 0..200 {
            let p = Vec3::new(rnd(), rnd() + 5.0, rnd());
            let exact = c.signed_distance(p);
            if exact < 0.0 {
                continue; // the union-of-spheres bound below is exact only outside
            }
            let brute = (0..=4000)
                .map(|k| {
                    let t = k as f32 / 4000.0;
                    p.distance(c.a.lerp(c.b, t)) - (c.radius_a + (c.radius_b - c.radius_a) * t)
                })
                .fold(f32::INFINITY, f32::min);
            assert!((exact - brute).abs() < 2e-3, "{p} {exact} {brute}");
            let s = c.closest(p);
            assert!((s.point + s.normal * s.distance - p).length() < 1e-4);
        }
    }

    #[test]
    fn aabb_bounds_both_spheres() {
        let b = cone().aabb();
        assert_eq!(b.min, Vec3::new(-3.0, -3.0, -3.0));
        assert_eq!(b.max, Vec3::new(11.0, 3.0, 3.0));
        assert!(b.contains(Vec3::new(10.5, 0.0, 0.0)));
        assert!(!b.contains(Vec3::new(11.5, 0.0, 0.0)));
        assert!(b.overlaps(&b.expanded(1.0)));
    }
}
