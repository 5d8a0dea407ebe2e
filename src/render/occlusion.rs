//! Coarse occlusion culling: the farthest depth of each 8 × 8 tile of a depth buffer.
//!
//! A triangle whose nearest vertex is at least as far as the farthest pixel of every tile its bounding
//! box touches cannot pass the depth test anywhere (perspective-correct depth stays between the vertex
//! depths), so the renderer skips it without walking its pixels. That removes most of the garment's
//! back faces (behind the front cloth or the body) and the body capsules hidden inside the garment,
//! which would otherwise cost as much as the visible cloth. [`TileDepth::occludes`] answers for one
//! triangle; the renderer rebuilds the tiles from its [`DepthBuffer`] between passes.

use crate::raster::{DepthBuffer, ScreenVertex};

/// Tile edge in pixels.
pub const TILE: u32 = 8;

/// Farthest depth per tile (`f32::INFINITY` where any pixel is still empty).
#[derive(Clone, Debug, Default)]
pub struct TileDepth {
    tiles_x: u32,
    tiles_y: u32,
    width: u32,
    height: u32,
    max: Vec<f32>,
}

impl TileDepth {
    /// Recomputes the tiles of `depth`, reusing the allocation.
    pub fn build(&mut self, depth: &DepthBuffer) {
        let (width, height) = (depth.width(), depth.height());
        self.width = width;
        self.height = height;
        self.tiles_x = width.div_ceil(TILE);
        self.tiles_y = height.div_ceil(TILE);
        self.max.clear();
        self.max.resize(
            self.tiles_x as usize * self.tiles_y as usize,
            f32::NEG_INFINITY,
        );
        let pixels = depth.as_slice();
        if width == 0 {
            return;
        }
        for (y, row) in pixels.chunks_exact(width as usize).enumerate() {
            let tiles = &mut self.max[(y / TILE as usize) * self.tiles_x as usize..]
                [..self.tiles_x as usize];
            for (m, run) in tiles.iter_mut().zip(row.chunks(TILE as usize)) {
                *m = run.iter().fold(*m, |a, &d| if d > a { d } else { a });
            }
        }
    }

    /// True if no pixel of the triangle's bounding box could pass the depth test.
    pub fn occludes(&self, v: &[ScreenVertex; 3]) -> bool {
        self.occludes_box(
            v[0].x.min(v[1].x).min(v[2].x),
            v[0].y.min(v[1].y).min(v[2].y),
            v[0].x.max(v[1].x).max(v[2].x),
            v[0].y.max(v[1].y).max(v[2].y),
            v[0].depth.min(v[1].depth).min(v[2].depth),
        )
    }

    /// True if every pixel of the box `[x0, x1] × [y0, y1]` (pixel coordinates) holds a depth no
    /// farther than `near`, so nothing at depth ≥ `near` inside the box can be drawn. NaN anywhere
    /// (an undrawable vertex) gives false.
    pub fn occludes_box(&self, x0: f32, y0: f32, x1: f32, y1: f32, near: f32) -> bool {
        let min_x = x0.floor().max(0.0);
        let min_y = y0.floor().max(0.0);
        let max_x = x1.ceil().min(self.width as f32);
        let max_y = y1.ceil().min(self.height as f32);
        if !(min_x < max_x && min_y < max_y && near.is_finite()) {
            return false;
        }
        let (tx0, ty0) = (min_x as u32 / TILE, min_y as u32 / TILE);
        let (tx1, ty1) = ((max_x as u32 - 1) / TILE, (max_y as u32 - 1) / TILE);
        (ty0..=ty1).all(|ty| {
            let row = &self.max[(ty * self.tiles_x) as usize..][..self.tiles_x as usize];
            row[tx0 as usize..=tx1 as usize].iter().all(|&m| near >= m)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::{draw_triangle, Cull};

    fn sv(x: f32, y: f32, depth: f32) -> ScreenVertex {
        ScreenVertex { x, y, depth }
    }

    #[test]
    fn a_triangle_behind_a_full_wall_is_occluded_and_one_in_front_is_not() {
        let mut depth = DepthBuffer::new(20, 12);
        let wall = |d| [sv(-1.0, -1.0, d), sv(60.0, -1.0, d), sv(-1.0, 60.0, d)];
        draw_triangle(&mut depth, wall(5.0), Cull::None, 0.1, |_| {});
        let mut tiles = TileDepth::default();
        tiles.build(&depth);
        let small = |d| [sv(3.0, 3.0, d), sv(15.0, 4.0, d), sv(5.0, 10.0, d)];
        assert!(tiles.occludes(&small(6.0)));
        assert!(!tiles.occludes(&small(4.0)));
        // An empty pixel anywhere in a tile keeps it open.
        let mut partial = DepthBuffer::new(20, 12);
        draw_triangle(
            &mut partial,
            [sv(0.0, 0.0, 5.0), sv(20.0, 0.0, 5.0), sv(0.0, 12.0, 5.0)],
            Cull::None,
            0.1,
            |_| {},
        );
        tiles.build(&partial);
        assert!(!tiles.occludes(&small(6.0)));
        assert!(!tiles.occludes(&[sv(f32::NAN, 0.0, 6.0), sv(1.0, 1.0, 6.0), sv(2.0, 0.0, 6.0)]));
    }
}
