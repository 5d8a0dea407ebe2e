//! Tessellation of tapered capsules into small closed triangle meshes for the renderer's depth-only
//! body pass.
//!
//! A tapered capsule is the convex hull of two spheres (`a`, `radius_a`) and (`b`, `radius_b`). Its
//! surface is a spherical cap on each sphere joined by the cone tangent to both: with axis
//! `u = (b − a)/L` and `sin φ = (radius_a − radius_b)/L`, the surface normal at elevation `α` (measured
//! from the equator towards `u`) is `cos α·radial + sin α·u`; sphere A carries `α ∈ [−90°, φ]`, sphere B
//! `α ∈ [φ, 90°]`, and the cone is the band between the two rings at `α = φ`, cut along the axis
//! into as many bands as keep its triangles about as long as wide. [`CapsuleMesh`] keeps the triangle
//! lists (fixed for a given resolution and number of cone bands) and writes the world-space vertices
//! of one capsule, shrunk by an inset, into a caller's buffer. Every vertex lies on the (inset) surface, so the mesh is
//! inscribed and never pokes out of it. Triangles are wound so `(b − a) × (c − a)` points outward, the
//! convention [`crate::raster::Cull`] expects; the renderer draws them with back faces culled.

use std::f32::consts::FRAC_PI_2;

use glam::Vec3;

use crate::cloth::Capsule;

/// Most bands the cone between the two spheres is cut into along the axis.
pub const MAX_CONE_SEGMENTS: u32 = 16;

/// The triangle lists of a capsule tessellation (one per number of cone segments) and the ring
/// directions they are built from.
#[derive(Clone, Debug)]
pub struct CapsuleMesh {
    segments: u32,
    rings_per_cap: u32,
    /// (cos θ, sin θ) around the axis, one per segment.
    around: Vec<(f32, f32)>,
    /// `triangles[n − 1]`: the mesh with the cone cut into `n` bands.
    triangles: Vec<Vec<[u32; 3]>>,
}

impl CapsuleMesh {
    /// `segments` around the axis (at least 3) and `rings_per_cap` rings on each sphere (at least 1).
    pub fn new(segments: u32, rings_per_cap: u32) -> CapsuleMesh {
        let segments = segments.max(3);
        let rings_per_cap = rings_per_cap.max(1);
        let around = (0..segments)
            .map(|s| {
                let theta = std::f32::consts::TAU * s as f32 / segments as f32;
                (theta.cos(), theta.sin())
            })
            .collect();
        let triangles = (1..=MAX_CONE_SEGMENTS)
            .map(|n| capsule_triangles(segments, 2 * rings_per_cap + n - 1))
            .collect();
        CapsuleMesh {
            segments,
            rings_per_cap,
            around,
            triangles,
        }
    }

    /// The triangles of the mesh whose cone has `cone_segments` bands (clamped to
    /// 1..=[`MAX_CONE_SEGMENTS`]).
    pub fn triangles(&self, cone_segments: u32) -> &[[u32; 3]] {
        let n = cone_segments.clamp(1, MAX_CONE_SEGMENTS);
        &self.triangles[n as usize - 1]
    }

    /// Two poles plus `2 · rings_per_cap + cone_segments − 1` rings of `segments` vertices.
    pub fn vertex_count(&self, cone_segments: u32) -> usize {
        let n = cone_segments.clamp(1, MAX_CONE_SEGMENTS);
        2 + (2 * self.rings_per_cap + n - 1) as usize * self.segments as usize
    }

    /// Writes the vertices of `capsule` with both radii reduced by `inset` (world units) into `out`
    /// (cleared first) and returns the number of bands the cone was cut into — enough to keep its
    /// triangles about as long as they are wide, so none is a long sliver, whose bounding box the
    /// rasterizer would walk in vain. `None`, leaving `out` empty, when nothing is left to draw (both
    /// radii used up by the inset, or a non-finite capsule).
    pub fn vertices(&self, capsule: &Capsule, inset: f32, out: &mut Vec<Vec3>) -> Option<u32> {
        out.clear();
        let shape = Profile::of(capsule, inset)?;
        let k = self.rings_per_cap;
        let cone_length = shape.a.distance(shape.b) * shape.phi.cos();
        let width =
            std::f32::consts::TAU * shape.radius_a.max(shape.radius_b) / self.segments as f32;
        let n = ((cone_length / (1.5 * width.max(1e-3))).ceil() as u32).clamp(1, MAX_CONE_SEGMENTS);
        out.push(shape.a - shape.axis * shape.radius_a);
        // Sphere A: α from just above the south pole up to φ (inclusive).
        for i in 1..=k {
            let alpha = -FRAC_PI_2 + (shape.phi + FRAC_PI_2) * i as f32 / k as f32;
            self.push_ring(out, &shape, shape.a, shape.radius_a, alpha);
        }
        // The cone: rings between the two tangent rings, on the straight lines joining them.
        let (sin_phi, cos_phi) = shape.phi.sin_cos();
        for j in 1..n {
            let t = j as f32 / n as f32;
            out.extend(self.around.iter().map(|&(c, s)| {
                let normal = (shape.e1 * c + shape.e2 * s) * cos_phi + shape.axis * sin_phi;
                let on_a = shape.a + normal * shape.radius_a;
                let on_b = shape.b + normal * shape.radius_b;
                on_a.lerp(on_b, t)
            }));
        }
        // Sphere B: α from φ (inclusive) up to just below the north pole.
        for j in 0..k {
            let alpha = shape.phi + (FRAC_PI_2 - shape.phi) * j as f32 / k as f32;
            self.push_ring(out, &shape, shape.b, shape.radius_b, alpha);
        }
        out.push(shape.b + shape.axis * shape.radius_b);
        Some(n)
    }

    fn push_ring(
        &self,
        out: &mut Vec<Vec3>,
        shape: &Profile,
        centre: Vec3,
        radius: f32,
        alpha: f32,
    ) {
        let (sin_a, cos_a) = alpha.sin_cos();
        let along = centre + shape.axis * (radius * sin_a);
        let spread = radius * cos_a;
        out.extend(
            self.around
                .iter()
                .map(|&(c, s)| along + (shape.e1 * c + shape.e2 * s) * spread),
        );
    }
}

/// A capsule reduced to what the tessellation needs.
struct Profile {
    a: Vec3,
    b: Vec3,
    radius_a: f32,
    radius_b: f32,
    /// Unit axis from `a` to `b`, and two unit vectors with `e1 × e2 = axis`.
    axis: Vec3,
    e1: Vec3,
    e2: Vec3,
    /// Elevation of the tangent cone's normal.
    phi: f32,
}

impl Profile {
    fn of(capsule: &Capsule, inset: f32) -> Option<Profile> {
        let (mut a, mut b) = (capsule.a, capsule.b);
        let mut radius_a = (capsule.radius_a - inset).max(0.0);
        let mut radius_b = (capsule.radius_b - inset).max(0.0);
        if !(a.is_finite() && b.is_finite() && radius_a.is_finite() && radius_b.is_finite())
            || radius_a.max(radius_b) <= 0.0
        {
            return None;
        }
        let length = a.distance(b);
        // One sphere inside the other (or both at one point): the hull is the bigger sphere.
        if length <= (radius_a - radius_b).abs() || length < 1e-4 {
            let (c, r) = if radius_a >= radius_b {
                (a, radius_a)
            } else {
                (b, radius_b)
            };
            (a, b, radius_a, radius_b) = (c, c, r, r);
        }
        let axis = if a == b { Vec3::X } else { (b - a).normalize() };
        let e1 = axis.any_orthonormal_vector();
        let e2 = axis.cross(e1);
        let phi = if a == b {
            0.0
        } else {
            ((radius_a - radius_b) / a.distance(b))
                .clamp(-1.0, 1.0)
                .asin()
        };
        Some(Profile {
            a,
            b,
            radius_a,
            radius_b,
            axis,
            e1,
            e2,
            phi,
        })
    }
}

/// Outward-wound triangles of a pole–rings–pole mesh: vertex 0 is the pole at `a`'s end, ring `r`'s
/// vertex `s` is `1 + r·segments + s`, the last vertex is the pole at `b`'s end.
fn capsule_triangles(segments: u32, rings: u32) -> Vec<[u32; 3]> {
    let ring = |r: u32, s: u32| 1 + r * segments + s % segments;
    let north = 1 + rings * segments;
    let mut out = Vec::with_capacity(2 * segments as usize * rings as usize);
    for s in 0..segments {
        out.push([0, ring(0, s + 1), ring(0, s)]);
    }
    for r in 0..rings - 1 {
        for s in 0..segments {
            out.push([ring(r, s), ring(r, s + 1), ring(r + 1, s + 1)]);
            out.push([ring(r, s), ring(r + 1, s + 1), ring(r + 1, s)]);
        }
    }
    for s in 0..segments {
        out.push([north, ring(rings - 1, s), ring(rings - 1, s + 1)]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn capsule() -> Capsule {
        Capsule {
            a: Vec3::new(0.0, 0.0, 0.0),
            b: Vec3::new(0.0, 30.0, 0.0),
            radius_a: 8.0,
            radius_b: 5.0,
        }
    }

    /// Distance from `p` to the segment a–b.
    fn axis_distance(p: Vec3, a: Vec3, b: Vec3) -> (f32, Vec3) {
        let ab = b - a;
        let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
        let q = a + ab * t;
        (p.distance(q), q)
    }

    #[test]
    fn triangles_are_wound_outward_and_the_mesh_is_closed() {
        let mesh = CapsuleMesh::new(12, 3);
        let mut v = Vec::new();
        let n = mesh.vertices(&capsule(), 0.0, &mut v).expect("drawable");
        assert!(n > 1, "a 30 cm capsule of radius 8 is cut along the cone");
        assert_eq!(v.len(), mesh.vertex_count(n));
        let c = capsule();
        for t in mesh.triangles(n) {
            let [p, q, r] = t.map(|i| v[i as usize]);
            let n = (q - p).cross(r - p);
            let centroid = (p + q + r) / 3.0;
            let (_, on_axis) = axis_distance(centroid, c.a, c.b);
            assert!(n.dot(centroid - on_axis) > 0.0, "{t:?} wound inward");
        }
        // Closed: every undirected edge is shared by exactly two triangles.
        let mut edges = std::collections::HashMap::new();
        for t in mesh.triangles(n) {
            for k in 0..3 {
                let (i, j) = (t[k], t[(k + 1) % 3]);
                *edges.entry((i.min(j), i.max(j))).or_insert(0) += 1;
            }
        }
        assert!(edges.values().all(|&n| n == 2));
    }

    #[test]
    fn vertices_lie_on_the_inset_surface() {
        // Every vertex lies on one of the two inset spheres or on the cone tangent to both: at axial
        // position t its distance from the axis is the cone's radius there.
        let mesh = CapsuleMesh::new(10, 2);
        let mut v = Vec::new();
        let c = capsule();
        let (ra, rb, length) = (7.0f32, 4.0f32, 30.0f32);
        let sin_phi = (ra - rb) / length;
        let cos_phi = (1.0 - sin_phi * sin_phi).sqrt();
        let (ta, tb) = (ra * sin_phi, length + rb * sin_phi);
        let n = mesh.vertices(&c, 1.0, &mut v).expect("drawable");
        let mut on_cone = 0;
        for p in &v {
            let on_a = (p.distance(c.a) - ra).abs() < 1e-3;
            let on_b = (p.distance(c.b) - rb).abs() < 1e-3;
            let t = p.y; // the axis is world Y from the origin
            let rho = (p.x * p.x + p.z * p.z).sqrt();
            let cone = ra * cos_phi + (rb - ra) * cos_phi * (t - ta) / (tb - ta);
            let on_side = (ta..=tb).contains(&t) && (rho - cone).abs() < 1e-3;
            on_cone += usize::from(on_side && !on_a && !on_b);
            assert!(on_a || on_b || on_side, "{p}");
        }
        assert_eq!(on_cone, (n as usize - 1) * 10);
        assert!(mesh.vertices(&c, 9.0, &mut v).is_none());
        assert!(v.is_empty());
    }

    #[test]
    fn a_sphere_swallowing_the_other_becomes_a_sphere() {
        let mesh = CapsuleMesh::new(8, 2);
        let mut v = Vec::new();
        let c = Capsule {
            a: Vec3::ZERO,
            b: Vec3::new(1.0, 0.0, 0.0),
            radius_a: 10.0,
            radius_b: 2.0,
        };
        assert_eq!(mesh.vertices(&c, 0.0, &mut v), Some(1));
        assert!(v.iter().all(|p| (p.length() - 10.0).abs() < 1e-3));
    }
}
