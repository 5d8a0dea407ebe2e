//! Z-buffered triangle rasterizer.
//!
//! Triangles arrive already projected (pixel coordinates plus camera depth). [`draw_triangle`] walks the
//! pixels whose centres the triangle covers (top-left fill rule, so two triangles sharing an edge never
//! both draw a pixel and never both miss one), interpolates depth and barycentric weights with
//! perspective correction, keeps the fragment if it is nearer than what the [`DepthBuffer`] holds, and
//! hands it to a shading closure. The synthetic generator shades the suited body with it; the garment
//! renderer draws the body proxies depth-only and then the garment.

use crate::camera::Projected;

/// A projected vertex: pixel position and depth along the optical axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenVertex {
    pub x: f32,
    pub y: f32,
    pub depth: f32,
}

impl From<Projected> for ScreenVertex {
    fn from(p: Projected) -> Self {
        ScreenVertex {
            x: p.pixel.x,
            y: p.pixel.y,
            depth: p.depth,
        }
    }
}

/// Which triangles to skip by their winding.
///
/// Meshes are wound so that `(b − a) × (c − a)` points out of the surface. Seen by the camera, a front
/// face then has negative signed area in pixel coordinates (x right, y down).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cull {
    /// Draw both sides.
    None,
    /// Skip triangles facing away from the camera.
    Back,
}

/// One covered pixel of a triangle that passed the depth test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fragment {
    pub x: u32,
    pub y: u32,
    /// `y · width + x`.
    pub index: usize,
    pub depth: f32,
    /// Perspective-correct barycentric weights of the triangle's three vertices (sum 1).
    pub weights: [f32; 3],
    /// True when the triangle faces the camera.
    pub front_facing: bool,
}

/// Per-pixel depth; `f32::INFINITY` where nothing is drawn.
#[derive(Clone, Debug, PartialEq)]
pub struct DepthBuffer {
    width: u32,
    height: u32,
    depth: Vec<f32>,
}

impl DepthBuffer {
    pub fn new(width: u32, height: u32) -> DepthBuffer {
        DepthBuffer {
            width,
            height,
            depth: vec![f32::INFINITY; width as usize * height as usize],
        }
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    /// Resets every pixel to empty, reallocating only if the size changed.
    pub fn clear(&mut self, width: u32, height: u32) {
        self.width = width;
        self.height = height;
        self.depth.clear();
        self.depth
            .resize(width as usize * height as usize, f32::INFINITY);
    }

    pub fn get(&self, x: u32, y: u32) -> f32 {
        self.depth[y as usize * self.width as usize + x as usize]
    }

    pub fn as_slice(&self) -> &[f32] {
        &self.depth
    }
}

#[inline]
fn edge(ax: f32, ay: f32, bx: f32, by: f32, px: f32, py: f32) -> f32 {
    (bx - ax) * (py - ay) - (by - ay) * (px - ax)
}

/// Is edge a→b a top or left edge of a triangle with positive signed area (pixel coordinates)?
#[inline]
fn is_top_left(ax: f32, ay: f32, bx: f32, by: f32) -> bool {
    (ay == by && bx > ax) || by < ay
}

/// Rasterizes one triangle. Triangles with a vertex nearer than `near` (or not finite) are skipped.
/// `shade` is called for every covered pixel nearer than the depth buffer, which is then updated.
pub fn draw_triangle(
    buffer: &mut DepthBuffer,
    vertices: [ScreenVertex; 3],
    cull: Cull,
    near: f32,
    mut shade: impl FnMut(Fragment),
) {
    let [a, b, c] = vertices;
    if [a, b, c]
        .iter()
        .any(|v| !(v.depth >= near) || !v.x.is_finite() || !v.y.is_finite())
    {
        return;
    }
    let area = edge(a.x, a.y, b.x, b.y, c.x, c.y);
    if area == 0.0 || !area.is_finite() {
        return;
    }
    let front_facing = area < 0.0;
    if cull == Cull::Back && !front_facing {
        return;
    }
    // Order the vertices so the signed area is positive; `order` maps back to the caller's vertices.
    let (v, order) = if area > 0.0 {
        ([a, b, c], [0, 1, 2])
    } else {
        ([a, c, b], [0, 2, 1])
    };
    let area = area.abs();

    let (w, h) = (buffer.width as f32, buffer.height as f32);
    let min_x = v
        .iter()
        .map(|p| p.x)
        .fold(f32::INFINITY, f32::min)
        .floor()
        .max(0.0);
    let max_x = v
        .iter()
        .map(|p| p.x)
        .fold(f32::NEG_INFINITY, f32::max)
        .ceil()
        .min(w);
    let min_y = v
        .iter()
        .map(|p| p.y)
        .fold(f32::INFINITY, f32::min)
        .floor()
        .max(0.0);
    let max_y = v
        .iter()
        .map(|p| p.y)
        .fold(f32::NEG_INFINITY, f32::max)
        .ceil()
        .min(h);
    if min_x >= max_x || min_y >= max_y {
        return;
    }
    let edges = [(1, 2), (2, 0), (0, 1)]; // weight i belongs to the edge opposite vertex i
    let top_left = edges.map(|(i, j)| is_top_left(v[i].x, v[i].y, v[j].x, v[j].y));
    let inv_depth = v.map(|p| 1.0 / p.depth);
    let width = buffer.width as usize;

    for py in min_y as u32..max_y as u32 {
        let cy = py as f32 + 0.5;
        for px in min_x as u32..max_x as u32 {
            let cx = px as f32 + 0.5;
            let mut lambda = [0.0f32; 3];
            let mut inside = true;
            for (k, &(i, j)) in edges.iter().enumerate() {
                let e = edge(v[i].x, v[i].y, v[j].x, v[j].y, cx, cy);
                if e < 0.0 || (e == 0.0 && !top_left[k]) {
                    inside = false;
                    break;
                }
                lambda[k] = e / area;
            }
            if !inside {
                continue;
            }
            let inv_z =
                lambda[0] * inv_depth[0] + lambda[1] * inv_depth[1] + lambda[2] * inv_depth[2];
            let depth = 1.0 / inv_z;
            let index = py as usize * width + px as usize;
            if depth >= buffer.depth[index] {
                continue;
            }
            buffer.depth[index] = depth;
            let mut weights = [0.0f32; 3];
            for k in 0..3 {
                weights[order[k]] = lambda[k] * inv_depth[k] * depth;
            }
            shade(Fragment {
                x: px,
                y: py,
                index,
                depth,
                weights,
                front_facing,
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sv(x: f32, y: f32, depth: f32) -> ScreenVertex {
        ScreenVertex { x, y, depth }
    }

    fn covered(buffer: &DepthBuffer) -> Vec<(u32, u32)> {
        let mut out = Vec::new();
        for y in 0..buffer.height() {
            for x in 0..buffer.width() {
                if buffer.get(x, y).is_finite() {
                    out.push((x, y));
                }
            }
        }
        out
    }

    #[test]
    fn a_right_triangle_covers_the_pixels_whose_centres_it_contains() {
        // Triangle (0,0) (4,0) (0,4): centres (x+.5, y+.5) with x + y + 1 < 4 lie inside;
        // centres exactly on the hypotenuse (x + y + 1 = 4) are on a right edge and are not drawn.
        let mut buffer = DepthBuffer::new(4, 4);
        draw_triangle(
            &mut buffer,
            [sv(0.0, 0.0, 1.0), sv(4.0, 0.0, 1.0), sv(0.0, 4.0, 1.0)],
            Cull::None,
            0.1,
            |_| {},
        );
        let expected: Vec<(u32, u32)> = (0..4)
            .flat_map(|y| (0..4).map(move |x| (x, y)))
            .filter(|(x, y)| x + y + 1 < 4)
            .collect();
        assert_eq!(covered(&buffer), expected);
    }

    #[test]
    fn two_triangles_sharing_an_edge_cover_each_pixel_once() {
        // A 4×4 square split along its diagonal: every pixel drawn exactly once.
        let mut buffer = DepthBuffer::new(4, 4);
        let mut count = vec![0; 16];
        let (p0, p1, p2, p3) = (
            sv(0.0, 0.0, 1.0),
            sv(4.0, 0.0, 1.0),
            sv(4.0, 4.0, 1.0),
            sv(0.0, 4.0, 1.0),
        );
        draw_triangle(&mut buffer, [p0, p1, p2], Cull::None, 0.1, |f| {
            count[f.index] += 1
        });
        buffer.clear(4, 4);
        draw_triangle(&mut buffer, [p0, p2, p3], Cull::None, 0.1, |f| {
            count[f.index] += 1
        });
        assert_eq!(count, vec![1; 16]);
    }

    #[test]
    fn nearer_triangle_wins_whatever_the_order() {
        for near_first in [true, false] {
            let mut buffer = DepthBuffer::new(4, 4);
            let mut colour = vec![0u8; 16];
            let big = |d: f32| [sv(-1.0, -1.0, d), sv(9.0, -1.0, d), sv(-1.0, 9.0, d)];
            let order = if near_first {
                [(1, 2.0), (2, 5.0)]
            } else {
                [(2, 5.0), (1, 2.0)]
            };
            for (id, depth) in order {
                draw_triangle(&mut buffer, big(depth), Cull::None, 0.1, |f| {
                    colour[f.index] = id
                });
            }
            assert!(colour.iter().all(|&c| c == 1));
            assert_eq!(buffer.get(0, 0), 2.0);
        }
    }

    #[test]
    fn back_faces_are_culled_and_front_faces_drawn() {
        let mut buffer = DepthBuffer::new(4, 4);
        // Negative signed area in pixel coordinates = front facing.
        let front = [sv(0.0, 0.0, 1.0), sv(0.0, 4.0, 1.0), sv(4.0, 0.0, 1.0)];
        let back = [sv(0.0, 0.0, 1.0), sv(4.0, 0.0, 1.0), sv(0.0, 4.0, 1.0)];
        let mut drawn = 0;
        draw_triangle(&mut buffer, back, Cull::Back, 0.1, |_| drawn += 1);
        assert_eq!(drawn, 0);
        draw_triangle(&mut buffer, front, Cull::Back, 0.1, |f| {
            drawn += 1;
            assert!(f.front_facing)
        });
        assert_eq!(drawn, 6);
    }

    #[test]
    fn weights_are_perspective_correct() {
        // An edge from depth 1 to depth 3: the pixel halfway across on screen is a quarter of the
        // way along in 3-D (1/z interpolates linearly: 1/z = (1 + 1/3)/2 = 2/3 → z = 1.5).
        let mut buffer = DepthBuffer::new(8, 8);
        let tri = [sv(0.0, 0.0, 1.0), sv(8.0, 0.0, 3.0), sv(0.0, 8.0, 1.0)];
        let mut probe = None;
        draw_triangle(&mut buffer, tri, Cull::None, 0.1, |f| {
            if f.x == 3 && f.y == 0 {
                probe = Some(f)
            }
        });
        let f = probe.expect("pixel (3,0) covered");
        // Screen position x = 3.5 of 8 → λ₁ = 3.5/8 − (0.5/8)·0 … check via depth and weight sum instead.
        let sum: f32 = f.weights.iter().sum();
        assert!((sum - 1.0).abs() < 1e-5);
        let depth_from_weights = f.weights[0] * 1.0 + f.weights[1] * 3.0 + f.weights[2] * 1.0;
        assert!((depth_from_weights - f.depth).abs() < 1e-4, "{f:?}");
        // 1/z at λ = (1 − 3.5/8 − 0.5/8, 3.5/8, 0.5/8): 1/z = 1 − λ₁ + λ₁/3.
        let l1 = 3.5 / 8.0;
        let expected_depth = 1.0 / (1.0 - l1 + l1 / 3.0);
        assert!((f.depth - expected_depth).abs() < 1e-4);
    }

    #[test]
    fn triangles_behind_the_near_plane_or_off_screen_draw_nothing() {
        let mut buffer = DepthBuffer::new(4, 4);
        let mut drawn = 0;
        draw_triangle(
            &mut buffer,
            [sv(0.0, 0.0, 0.01), sv(4.0, 0.0, 1.0), sv(0.0, 4.0, 1.0)],
            Cull::None,
            0.1,
            |_| drawn += 1,
        );
        draw_triangle(
            &mut buffer,
            [
                sv(10.0, 10.0, 1.0),
                sv(14.0, 10.0, 1.0),
                sv(10.0, 14.0, 1.0),
            ],
            Cull::None,
            0.1,
            |_| drawn += 1,
        );
        draw_triangle(
            &mut buffer,
            [sv(f32::NAN, 0.0, 1.0), sv(4.0, 0.0, 1.0), sv(0.0, 4.0, 1.0)],
            Cull::None,
            0.1,
            |_| drawn += 1,
        );
        assert_eq!(drawn, 0);
    }
}
