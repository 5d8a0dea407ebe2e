//! Silhouette edges of the garment mesh and the antialiasing fins drawn along them.
//!
//! The garment is rasterized at pixel centres, which leaves its outline stair-stepped. Where the outline
//! comes from the mesh itself, it runs along *silhouette edges*: edges between a triangle facing the
//! camera and one facing away (the contour of the surface), and boundary edges (neckline, hem, cuffs).
//! Both triangles of a contour edge project to the same side of it, so the other side of the edge is
//! outside the garment's projection there. [`fin`] builds a thin screen-space quad on that outer side,
//! [`FIN_WIDTH`] pixels wide, at the depth of the edge; the renderer rasterizes it with the same depth
//! buffer (so the body or nearer cloth still hides it) and blends the edge's colour over what the layer
//! holds with the pixel's coverage by the half-plane inside the edge, [`edge_coverage`]. Pixels whose
//! centres lie inside keep full alpha, so the edge ends up about ⅛ px fatter on average than the exact
//! box-filtered coverage — invisible, and it never lets the background leak through the garment.
//! Where an arm (a capsule) hides the garment the boundary stays aliased: the capsule is only a proxy
//! for the real arm whose pixels show there anyway.
//!
//! The edge table depends only on the triangle list, so [`EdgeTable`] rebuilds it only when the list
//! changes.

use glam::Vec2;

use crate::raster::ScreenVertex;

/// Marks the missing second triangle of a boundary edge.
pub const NO_TRIANGLE: u32 = u32::MAX;

/// How far a fin reaches out of the silhouette, in pixels: far enough for every pixel centre whose
/// square the edge crosses (at most √2/2 px away, for a diagonal edge).
pub const FIN_WIDTH: f32 = 0.75;

/// An undirected mesh edge and the one or two triangles that share it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MeshEdge {
    pub vertices: [u32; 2],
    /// Triangle indices; the second is [`NO_TRIANGLE`] on the mesh boundary.
    pub triangles: [u32; 2],
}

/// The edges of a triangle list, rebuilt only when the list changes. Edges shared by more than two
/// triangles (non-manifold) are left out: they get no fins.
#[derive(Clone, Debug, Default)]
pub struct EdgeTable {
    source: Vec<[u32; 3]>,
    edges: Vec<MeshEdge>,
    scratch: Vec<(u32, u32, u32)>,
}

impl EdgeTable {
    /// Makes the table describe `triangles`, rebuilding only if they differ from the last call's.
    pub fn update(&mut self, triangles: &[[u32; 3]]) {
        if self.source.as_slice() == triangles {
            return;
        }
        self.source.clear();
        self.source.extend_from_slice(triangles);
        build_edges(triangles, &mut self.scratch, &mut self.edges);
    }

    pub fn edges(&self) -> &[MeshEdge] {
        &self.edges
    }
}

/// The manifold and boundary edges of `triangles` into `out`; `scratch` is reused working space.
pub fn build_edges(
    triangles: &[[u32; 3]],
    scratch: &mut Vec<(u32, u32, u32)>,
    out: &mut Vec<MeshEdge>,
) {
    scratch.clear();
    out.clear();
    for (t, tri) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (i, j) = (tri[k], tri[(k + 1) % 3]);
            if i != j {
                scratch.push((i.min(j), i.max(j), t as u32));
            }
        }
    }
    scratch.sort_unstable();
    let mut start = 0;
    while start < scratch.len() {
        let (i, j, first) = scratch[start];
        let mut end = start + 1;
        while end < scratch.len() && (scratch[end].0, scratch[end].1) == (i, j) {
            end += 1;
        }
        let triangles = match end - start {
            1 => Some([first, NO_TRIANGLE]),
            2 => Some([first, scratch[start + 1].2]),
            _ => None,
        };
        if let Some(triangles) = triangles {
            out.push(MeshEdge {
                vertices: [i, j],
                triangles,
            });
        }
        start = end;
    }
}

/// How a projected triangle faces the camera.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Facing {
    Front,
    Back,
    /// Not drawn: a vertex behind the near plane or not finite, or zero area on screen.
    Hidden,
}

/// Facing of a projected triangle, by the sign of its area in pixel coordinates (negative = front,
/// the rasterizer's convention). Vertices nearer than `near` make it hidden.
pub fn facing(v: [ScreenVertex; 3], near: f32) -> Facing {
    if v.iter()
        .any(|p| p.depth.is_nan() || p.depth < near || !p.x.is_finite() || !p.y.is_finite())
    {
        return Facing::Hidden;
    }
    let area = (v[1].x - v[0].x) * (v[2].y - v[0].y) - (v[1].y - v[0].y) * (v[2].x - v[0].x);
    if area < 0.0 {
        Facing::Front
    } else if area > 0.0 {
        Facing::Back
    } else {
        Facing::Hidden
    }
}

/// The triangle whose side of `edge` is drawn when the edge is on the silhouette: the drawn one of a
/// boundary edge (or of an edge whose neighbour is hidden), the front-facing one of a contour edge.
/// `None` for interior edges between two triangles facing the same way.
pub fn silhouette_owner(edge: &MeshEdge, facing_of: &[Facing]) -> Option<u32> {
    let state = |t: u32| facing_of.get(t as usize).copied().unwrap_or(Facing::Hidden);
    let [t0, t1] = edge.triangles;
    match (state(t0), state(t1)) {
        (Facing::Hidden, Facing::Hidden) => None,
        (_, Facing::Hidden) => Some(t0),
        (Facing::Hidden, _) => Some(t1),
        (a, b) if a == b => None,
        (Facing::Front, _) => Some(t0),
        _ => Some(t1),
    }
}

/// A fin: the quad `p0, p1, p1 + n·w, p0 + n·w` outside the edge `p0 → p1`, with the edge's line.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fin {
    /// Two triangles: `[quad[0], quad[1], quad[2]]` and `[quad[0], quad[2], quad[3]]`.
    pub quad: [ScreenVertex; 4],
    /// A point on the edge.
    pub origin: Vec2,
    /// Unit normal of the edge pointing out of the silhouette.
    pub normal: Vec2,
}

/// The fin on the side of edge `p0 → p1` away from `opposite` (the owner triangle's third vertex), or
/// `None` for a degenerate edge.
pub fn fin(p0: ScreenVertex, p1: ScreenVertex, opposite: ScreenVertex, width: f32) -> Option<Fin> {
    let (a, b, c) = (
        Vec2::new(p0.x, p0.y),
        Vec2::new(p1.x, p1.y),
        Vec2::new(opposite.x, opposite.y),
    );
    let along = b - a;
    let mut normal = Vec2::new(along.y, -along.x).try_normalize()?;
    if normal.dot(c - a) > 0.0 {
        normal = -normal;
    }
    let out = normal * width;
    let shifted = |p: ScreenVertex| ScreenVertex {
        x: p.x + out.x,
        y: p.y + out.y,
        depth: p.depth,
    };
    Some(Fin {
        quad: [p0, p1, shifted(p1), shifted(p0)],
        origin: a,
        normal,
    })
}

/// Fraction of the pixel with centre `centre` covered by the half-plane inside the fin's edge: a linear
/// ramp over the pixel square's extent along the normal (`|nx| + |ny|`), exact for axis-aligned edges.
pub fn edge_coverage(fin: &Fin, centre: Vec2) -> f32 {
    let distance = (centre - fin.origin).dot(fin.normal);
    let extent = fin.normal.x.abs() + fin.normal.y.abs();
    (0.5 - distance / extent).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sv(x: f32, y: f32) -> ScreenVertex {
        ScreenVertex { x, y, depth: 1.0 }
    }

    #[test]
    fn edges_of_two_triangles_sharing_a_diagonal() {
        let mut table = EdgeTable::default();
        table.update(&[[0, 1, 2], [0, 2, 3]]);
        let edges = table.edges();
        assert_eq!(edges.len(), 5);
        let diagonal = edges
            .iter()
            .find(|e| e.vertices == [0, 2])
            .expect("diagonal");
        assert_eq!(diagonal.triangles, [0, 1]);
        assert_eq!(
            edges
                .iter()
                .filter(|e| e.triangles[1] == NO_TRIANGLE)
                .count(),
            4
        );
    }

    #[test]
    fn contour_edges_belong_to_the_front_face() {
        let e = MeshEdge {
            vertices: [0, 1],
            triangles: [0, 1],
        };
        use Facing::*;
        assert_eq!(silhouette_owner(&e, &[Back, Front]), Some(1));
        assert_eq!(silhouette_owner(&e, &[Front, Back]), Some(0));
        assert_eq!(silhouette_owner(&e, &[Front, Front]), None);
        assert_eq!(silhouette_owner(&e, &[Back, Hidden]), Some(0));
        let boundary = MeshEdge {
            vertices: [0, 1],
            triangles: [0, NO_TRIANGLE],
        };
        assert_eq!(silhouette_owner(&boundary, &[Back]), Some(0));
    }

    #[test]
    fn fins_point_away_from_the_triangle_and_coverage_ramps_down() {
        // Edge along y = 4 from x = 0 to 8; triangle above it (y < 4): the fin goes down.
        let f = fin(sv(0.0, 4.0), sv(8.0, 4.0), sv(4.0, 0.0), FIN_WIDTH).expect("edge");
        assert!((f.normal - Vec2::Y).length() < 1e-6);
        assert_eq!(f.quad[2].y, 4.0 + FIN_WIDTH);
        assert!((edge_coverage(&f, Vec2::new(2.0, 4.0)) - 0.5).abs() < 1e-6);
        assert!((edge_coverage(&f, Vec2::new(2.0, 4.25)) - 0.25).abs() < 1e-6);
        assert_eq!(edge_coverage(&f, Vec2::new(2.0, 4.6)), 0.0);
        assert!(fin(sv(1.0, 1.0), sv(1.0, 1.0), sv(0.0, 0.0), 1.0).is_none());
    }
}
