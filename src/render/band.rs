//! One horizontal band of the garment layer, rendered on its own: the depth buffer and occlusion
//! tiles of the band, and the passes that fill its rows of the layer.
//!
//! The layer is cut into bands of whole rows so that the bands can render in parallel (rayon) with no
//! shared mutable state; with one band it is the plain single-threaded renderer. Each band walks every
//! triangle (those entirely above or below it cost a comparison) in four passes:
//!
//! 1. the garment's front faces, shaded into the layer;
//! 2. the body capsules, depth-only: a capsule fragment nearer than the cloth erases the cloth's pixel
//!    back to transparent (the real arm shows there) — the same result as drawing the capsules first,
//!    but capsules hidden inside the garment are now culled by the occlusion tiles. With the
//!    person's mask ([`Scene::person`]) only where the camera sees the person: an estimated arm
//!    that strays off the real one over the room would cut a hole showing the room;
//! 3. the garment's back faces (the inside), culled by the tiles where the front cloth or the body
//!    covers them, which is almost everywhere except openings;
//! 4. the antialiasing fins along silhouette edges ([`super::silhouette`]).
//!
//! Between passes the occlusion tiles ([`super::occlusion`]) are rebuilt from the depth buffer. The
//! band hands its finished rows of premultiplied RGBA back to the renderer's layer.

use crate::mask::Mask;
use crate::raster::{draw_triangle, Cull, DepthBuffer, Fragment, ScreenVertex};

use super::capsule_mesh::CapsuleMesh;
use super::occlusion::TileDepth;
use super::silhouette::{
    edge_coverage, facing, fin, silhouette_owner, Facing, MeshEdge, FIN_WIDTH,
};
use super::{blend_opaque_over, shade};

/// Everything a band reads, in layer pixel coordinates.
pub struct Scene<'a> {
    /// Garment vertices (NaN where undrawable).
    pub screen: &'a [ScreenVertex],
    pub triangles: &'a [[u32; 3]],
    pub facing: &'a [Facing],
    /// Per vertex: outside and inside intensity.
    pub intensity: &'a [[f32; 2]],
    /// Outside and inside colour.
    pub colours: [[f32; 3]; 2],
    /// The tessellation the capsules were made with, their projected vertices one after the other,
    /// and where each capsule's vertices start.
    pub capsule_mesh: &'a CapsuleMesh,
    pub capsule_screen: &'a [ScreenVertex],
    pub capsule_spans: &'a [CapsuleSpan],
    /// Mesh edges for the fins (empty: no antialiasing).
    pub edges: &'a [MeshEdge],
    pub near: f32,
    /// Where the camera sees the person; `None`: everywhere.
    pub person: Option<PersonPixels<'a>>,
}

/// The person's mask of the frame and where the layer's first pixel lies in it.
#[derive(Clone, Copy, Debug)]
pub struct PersonPixels<'a> {
    pub mask: &'a Mask,
    pub origin: (u32, u32),
}

impl PersonPixels<'_> {
    /// Whether layer pixel (`x`, `y`) shows the person (outside the mask: no).
    pub fn contains(&self, x: u32, y: u32) -> bool {
        let (fx, fy) = (self.origin.0 + x, self.origin.1 + y);
        fx < self.mask.width() && fy < self.mask.height() && self.mask.get(fx, fy)
    }
}

/// One capsule's vertices in [`Scene::capsule_screen`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CapsuleSpan {
    pub start: usize,
    pub cone_segments: u32,
}

/// The per-band buffers, kept between frames.
#[derive(Clone, Debug)]
pub struct Band {
    depth: DepthBuffer,
    tiles: TileDepth,
}

impl Default for Band {
    fn default() -> Band {
        Band {
            depth: DepthBuffer::new(0, 0),
            tiles: TileDepth::default(),
        }
    }
}

/// The triangle's vertices moved up by `shift` rows.
#[inline]
fn fetch(tri: &[u32; 3], vertices: &[ScreenVertex], shift: f32) -> [ScreenVertex; 3] {
    tri.map(|i| {
        let v = vertices[i as usize];
        ScreenVertex {
            x: v.x,
            y: v.y - shift,
            depth: v.depth,
        }
    })
}

/// True when every vertex is above the band's top or below its bottom (NaN: false).
#[inline]
fn misses(v: &[ScreenVertex; 3], height: f32) -> bool {
    v.iter().all(|p| p.y < 0.0) || v.iter().all(|p| p.y > height)
}

#[inline]
fn shade_fragment(pixels: &mut [u8], f: &Fragment, lit: &[[f32; 2]; 3], colours: &[[f32; 3]; 2]) {
    let side = usize::from(!f.front_facing);
    let i = f.weights[0] * lit[0][side] + f.weights[1] * lit[1][side] + f.weights[2] * lit[2][side];
    let rgb = shade(colours[side], i);
    pixels[4 * f.index..4 * f.index + 4].copy_from_slice(&[rgb[0], rgb[1], rgb[2], 255]);
}

impl Band {
    /// Renders rows `y0 .. y0 + pixels.len() / (4 · width)` of the layer into `pixels` (cleared by
    /// the caller).
    pub fn render(&mut self, scene: &Scene, y0: u32, width: u32, pixels: &mut [u8]) {
        let height = (pixels.len() / (4 * width.max(1) as usize)) as u32;
        self.depth.clear(width, height);
        let shift = y0 as f32;
        let h = height as f32;
        let near = scene.near;

        // 1. Front faces.
        for (tri, _) in scene
            .triangles
            .iter()
            .zip(scene.facing)
            .filter(|(_, &f)| f == Facing::Front)
        {
            let v = fetch(tri, scene.screen, shift);
            if misses(&v, h) {
                continue;
            }
            let lit = tri.map(|i| scene.intensity[i as usize]);
            draw_triangle(&mut self.depth, v, Cull::None, near, |f| {
                shade_fragment(pixels, &f, &lit, &scene.colours)
            });
        }
        self.tiles.build(&self.depth);

        // 2. Capsules, depth-only; where they are in front of the cloth they erase it.
        let mut drew_capsule = false;
        for span in scene.capsule_spans {
            let count = scene.capsule_mesh.vertex_count(span.cone_segments);
            let Some(verts) = scene.capsule_screen.get(span.start..span.start + count) else {
                continue;
            };
            if self.capsule_hidden(verts, shift) {
                continue;
            }
            for tri in scene.capsule_mesh.triangles(span.cone_segments) {
                let v = fetch(tri, verts, shift);
                if misses(&v, h) || facing(v, near) != Facing::Front || self.tiles.occludes(&v) {
                    continue;
                }
                drew_capsule = true;
                // Two closures, so that without a mask the pixel loop is the plain one.
                let erase = |pixels: &mut [u8], f: &Fragment| pixels[4 * f.index..][..4].fill(0);
                match scene.person {
                    None => {
                        draw_triangle(&mut self.depth, v, Cull::Back, near, |f| erase(pixels, &f))
                    }
                    Some(person) => draw_triangle(&mut self.depth, v, Cull::Back, near, |f| {
                        if person.contains(f.x, y0 + f.y) {
                            erase(pixels, &f)
                        }
                    }),
                }
            }
        }
        if drew_capsule {
            self.tiles.build(&self.depth);
        }

        // 3. Back faces: the inside of the garment, where nothing nearer covers it.
        for (tri, _) in scene
            .triangles
            .iter()
            .zip(scene.facing)
            .filter(|(_, &f)| f == Facing::Back)
        {
            let v = fetch(tri, scene.screen, shift);
            if misses(&v, h) || self.tiles.occludes(&v) {
                continue;
            }
            let lit = tri.map(|i| scene.intensity[i as usize]);
            draw_triangle(&mut self.depth, v, Cull::None, near, |f| {
                shade_fragment(pixels, &f, &lit, &scene.colours)
            });
        }

        // 4. Antialiasing fins outside the silhouette edges.
        for edge in scene.edges {
            self.draw_fin(scene, edge, shift, pixels);
        }
    }

    /// True if the whole capsule lies outside the band or behind everything drawn so far (its
    /// nearest vertex no nearer than the farthest pixel under its bounding box).
    fn capsule_hidden(&self, verts: &[ScreenVertex], shift: f32) -> bool {
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        for v in verts {
            for (k, c) in [v.x, v.y - shift, v.depth].into_iter().enumerate() {
                lo[k] = lo[k].min(c);
                hi[k] = hi[k].max(c);
            }
        }
        if verts.iter().any(|v| v.depth.is_nan()) {
            return false; // partly undrawable: leave it to the triangles
        }
        let height = self.depth.height() as f32;
        hi[1] < 0.0 || lo[1] > height || self.tiles.occludes_box(lo[0], lo[1], hi[0], hi[1], lo[2])
    }

    fn draw_fin(&mut self, scene: &Scene, edge: &MeshEdge, shift: f32, pixels: &mut [u8]) {
        let Some(owner) = silhouette_owner(edge, scene.facing) else {
            return;
        };
        let tri = scene.triangles[owner as usize];
        let [i, j] = edge.vertices;
        let Some(&k) = tri.iter().find(|&&v| v != i && v != j) else {
            return;
        };
        let [p0, p1, opposite] = fetch(&[i, j, k], scene.screen, shift);
        let h = self.depth.height() as f32;
        if (p0.y < -1.0 && p1.y < -1.0) || (p0.y > h + 1.0 && p1.y > h + 1.0) {
            return;
        }
        let Some(fin) = fin(p0, p1, opposite, FIN_WIDTH) else {
            return;
        };
        let side = usize::from(scene.facing[owner as usize] != Facing::Front);
        let (li, lj) = (
            scene.intensity[i as usize][side],
            scene.intensity[j as usize][side],
        );
        let colour = scene.colours[side];
        for (corners, lit) in [([0, 1, 2], [li, lj, lj]), ([0, 2, 3], [li, lj, li])] {
            let v = corners.map(|c| fin.quad[c]);
            draw_triangle(&mut self.depth, v, Cull::None, scene.near, |f| {
                let centre = glam::Vec2::new(f.x as f32 + 0.5, f.y as f32 + 0.5);
                let coverage = edge_coverage(&fin, centre);
                if coverage <= 0.0 {
                    return;
                }
                let i = f.weights[0] * lit[0] + f.weights[1] * lit[1] + f.weights[2] * lit[2];
                blend_opaque_over(
                    &mut pixels[4 * f.index..4 * f.index + 4],
                    shade(colour, i),
                    coverage,
                );
            });
        }
    }
}
