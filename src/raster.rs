//! Z-buffered triangle rasterizer.
//!
//! Triangles arrive already projected (pixel coordinates plus camera depth). [`draw_triangle`] walks the
//! pixels whose centres the triangle covers (top-left fill rule, so two triangles sharing an edge never
//! both draw a pixel and never both miss one), interpolates depth and barycentric weights with
//! perspective correction, keeps the fragment if it is nearer than what the [`DepthBuffer`] holds, and
//! hands it to a shading closure. The synthetic generator shades the suited body with it; the garment
//! renderer draws the body proxies depth-only and then the garment.
//!
//! # Method
//!
//! Coverage is defined by the f32 edge function `edge` of each of the three edges at the pixel
//! centre `(x + 0.5, y + 0.5)`: a pixel is covered when all three are positive, or zero on a top or
//! left edge. The rasterizer draws exactly those pixels, but does not test them one by one. Per row
//! of the bounding box:
//!
//! 1. **Span.** Along a row each rounded edge function is monotone in x (every operation in it rounds
//!    a monotone function of x), so each edge admits a half-line of pixels and the three together an
//!    interval `[start, end)`. Each edge's end of it is computed analytically, `⌊ax + 0.5 + row /
//!    dy⌋` where the edge function crosses zero, and used as is when a rounding-error bound shows the
//!    nearest pixel centres are safely on their sides (`Edge::boundary`). Otherwise (a vertex or
//!    edge through a pixel centre, horizontal edges, the fill-rule ties) the boundary is found by
//!    stepping from the estimate with the exact per-pixel test (`Edge::walk`). Either way the span
//!    is exactly the pixel set the per-pixel test accepts; pixels outside it cost nothing.
//! 2. **Depth.** `1/z = Σ λᵢ/zᵢ` (`λᵢ = eᵢ / area`) is linear in screen space. At the span's first
//!    pixel it is evaluated from the exact edge values, as `min 1/zᵢ + Σ eᵢ · (1/zᵢ − min 1/zᵢ) /
//!    area` (non-negative terms, so no cancellation, and exactly `z` for a triangle of constant
//!    depth); along the span it is `1/z₀ + n · d(1/z)/dx` for the n-th pixel (no accumulation, no
//!    division). Fragments clearly behind the stored depth (`(1/z) · stored < 1 − 2⁻²⁰`) are
//!    rejected with one multiplication; the others get `z = 1 / (1/z)`, the only division per
//!    fragment, and the usual `z < stored` test.
//! 3. **Weights** `wᵢ = eᵢ · (1 / (zᵢ · area)) · z` (perspective-correct), with `eᵢ` stepped from the
//!    span's start, only for fragments that pass.
//!
//! The reciprocals `1/area`, `1/zᵢ` and `1/dyᵢ` are taken once per triangle. Inputs outside the
//! ranges where these steps cannot overflow or lose the result (coordinates beyond ±10¹⁸ pixels,
//! absurd depths, buffers wider than 2²² pixels) fall back to testing every pixel of the bounding
//! box.

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

/// The edge function of edge a→b at point p: twice the signed area of (a, b, p), positive on the inside
/// of a triangle with positive signed area. Coverage is decided by exactly this f32 expression.
#[inline]
fn edge(ax: f32, ay: f32, bx: f32, by: f32, px: f32, py: f32) -> f32 {
    (bx - ax) * (py - ay) - (by - ay) * (px - ax)
}

/// Is edge a→b a top or left edge of a triangle with positive signed area (pixel coordinates)?
#[inline]
fn is_top_left(ax: f32, ay: f32, bx: f32, by: f32) -> bool {
    (ay == by && bx > ax) || by < ay
}

/// The pixel columns `[lo, hi)` of a row as the bounds `lo − 0.5`, `hi + 0.5` for
/// [`Edge::boundary`]'s clamping.
#[derive(Clone, Copy, Debug)]
struct Row {
    below: f32,
    above: f32,
}

impl Row {
    fn new(lo: u32, hi: u32) -> Row {
        Row {
            below: lo as f32 - 0.5,
            above: hi as f32 + 0.5,
        }
    }
}

/// One edge a→b of a positively wound triangle, set up for row-by-row evaluation of [`edge`].
#[derive(Clone, Copy, Debug)]
struct Edge {
    ax: f32,
    ay: f32,
    /// `bx − ax`
    dx: f32,
    /// `by − ay`: the edge function falls by about this much per pixel step in x.
    dy: f32,
    inv_dy: f32,
    /// `ax + 0.5`
    ax_half: f32,
    /// `|ax| + 2`
    abs_ax_2: f32,
    /// 0 when the edge bounds a row's span on the left (`dy < 0`), else +∞.
    left: f32,
    /// 0 when the edge bounds a row's span on the right (`dy > 0`), else +∞.
    right: f32,
    top_left: bool,
}

impl Edge {
    fn new(a: ScreenVertex, b: ScreenVertex) -> Edge {
        let dy = b.y - a.y;
        Edge {
            ax: a.x,
            ay: a.y,
            dx: b.x - a.x,
            dy,
            inv_dy: 1.0 / dy,
            ax_half: a.x + 0.5,
            abs_ax_2: a.x.abs() + 2.0,
            left: if dy < 0.0 { 0.0 } else { f32::INFINITY },
            right: if dy > 0.0 { 0.0 } else { f32::INFINITY },
            top_left: is_top_left(a.x, a.y, b.x, b.y),
        }
    }

    /// The row term `(bx − ax)·(cy − ay)` of [`edge`] for pixel-centre row `cy`.
    #[inline]
    fn row(&self, cy: f32) -> f32 {
        self.dx * (cy - self.ay)
    }

    /// [`edge`] at `(cx, cy)`, given `row = self.row(cy)`: the same operations in the same order, so
    /// bit for bit the same value.
    #[inline]
    fn at(&self, row: f32, cx: f32) -> f32 {
        row - self.dy * (cx - self.ax)
    }

    /// Does this edge let pixel `px` of the row in? Positive inside, zero only on a top or left edge.
    #[inline]
    fn covers(&self, row: f32, px: u32) -> bool {
        let e = self.at(row, px as f32 + 0.5);
        e > 0.0 || (e == 0.0 && self.top_left)
    }

    /// The pixels `[lower, upper)` of row `[lo, hi)` this edge lets in.
    ///
    /// Along a row the rounded edge function is monotone in x (each of its operations rounds a
    /// monotone function of x), so the covered pixels are a half-line: left of the first uncovered
    /// pixel when `dy > 0`, from the first covered pixel on when `dy < 0`, all or nothing when `dy =
    /// 0`. The edge function is zero at `x = ax + row / dy`, so that boundary is the first pixel
    /// whose centre lies past the crossing: `⌊ax + 0.5 + row / dy⌋`. The estimate is used as is when
    /// rounding cannot have moved it ([`Edge::boundary`]); otherwise, as when a vertex or edge
    /// passes through a pixel centre, the boundary is found with the exact per-pixel test
    /// ([`Edge::walk`]). Either way the result is exactly the set of pixels the per-pixel test
    /// accepts.
    #[inline]
    fn limits(&self, row: f32, lo: u32, hi: u32) -> (u32, u32) {
        let (x, certain) = self.boundary(row, Row::new(lo, hi));
        if !certain {
            return self.walk(row, lo, hi);
        }
        let x = (x.max(lo as f32).min(hi as f32)) as u32;
        if self.dy > 0.0 {
            (lo, x)
        } else {
            (x, hi)
        }
    }

    /// The boundary pixel `⌊p⌋` (as a float, within a pixel of the row `[lo, hi]`) from the analytic
    /// crossing, and whether rounding cannot have moved it.
    ///
    /// With `u = 2⁻²⁴`, the estimate `p = (ax + 0.5) + row · (1/dy)` is within about `5u(|ax| +
    /// |q| + 1)` (`q = row/dy`) of the true `crossing + 0.5`, and the rounded edge function at a
    /// centre `cx` has the sign of the exact one at a point within `2u·|cx − ax|` of `cx`. So when `p`
    /// is farther than `δ = 2⁻¹⁹(|ax| + |q| + 2)` from every integer (the two pixel centres next to
    /// the crossing are farther from it than those errors), `⌊p⌋` is exact. Estimates outside the
    /// row are clamped to half a pixel outside it, where the same holds. Horizontal edges (infinite
    /// or NaN `q`) are never certain.
    #[inline]
    fn boundary(&self, row: f32, span: Row) -> (f32, bool) {
        // Adding and subtracting 1.5 · 2²³ rounds to the nearest integer (|p| < 2²²).
        const ROUND: f32 = 12_582_912.0;
        let q = row * self.inv_dy;
        let p = self.ax_half + q;
        // Clamp (a NaN p fails both comparisons and becomes `lo − 0.5`).
        let p = if p > span.below { p } else { span.below };
        let p = if p < span.above { p } else { span.above };
        let nearest = (p + ROUND) - ROUND;
        let off = p - nearest; // exact, in [−0.5, 0.5]
        let floor = if off < 0.0 { nearest - 1.0 } else { nearest };
        let delta = (self.abs_ax_2 + q.abs()) * (1.0 / (1 << 19) as f32);
        (floor, delta < 0.25 && off.abs() > delta)
    }

    /// [`Edge::limits`] by testing pixels one by one, starting at the analytic estimate.
    #[cold]
    #[inline(never)]
    fn walk(&self, row: f32, lo: u32, hi: u32) -> (u32, u32) {
        if self.dy == 0.0 {
            // Horizontal: the same value all along the row.
            return if self.covers(row, lo) {
                (lo, hi)
            } else {
                (lo, lo)
            };
        }
        let p = self.ax_half + row * self.inv_dy;
        let mut x = (p.max(lo as f32).min(hi as f32) as u32).clamp(lo, hi);
        if self.dy > 0.0 {
            // Covered on the left of the crossing: find the first uncovered pixel.
            if x > lo && !self.covers(row, x - 1) {
                x -= 1;
                while x > lo && !self.covers(row, x - 1) {
                    x -= 1;
                }
            } else {
                while x < hi && self.covers(row, x) {
                    x += 1;
                }
            }
            (lo, x)
        } else {
            // Covered on the right of the crossing: find the first covered pixel.
            if x < hi && !self.covers(row, x) {
                x += 1;
                while x < hi && !self.covers(row, x) {
                    x += 1;
                }
            } else {
                while x > lo && self.covers(row, x - 1) {
                    x -= 1;
                }
            }
            (x, hi)
        }
    }
}

/// `⌊x⌋` of `x` clamped to `[−1, limit + 1]` (`f32::floor` is a libm call on baseline x86-64).
#[inline]
fn floor_within(x: f32, limit: f32) -> i64 {
    let x = x.max(-1.0).min(limit + 1.0);
    let t = x as i64;
    t - i64::from(t as f32 > x)
}

/// `⌈x⌉` of `x` clamped to `[−1, limit + 1]`.
#[inline]
fn ceil_within(x: f32, limit: f32) -> i64 {
    let x = x.max(-1.0).min(limit + 1.0);
    let t = x as i64;
    t + i64::from((t as f32) < x)
}

/// A triangle that passed the tests every triangle goes through first: its vertices ordered so
/// that their signed area is positive (`order` maps them back to the caller's), that area, and
/// whether the caller's winding faces the camera.
#[derive(Clone, Copy, Debug)]
struct Oriented {
    v: [ScreenVertex; 3],
    order: [usize; 3],
    area: f32,
    front_facing: bool,
}

/// `None` for a triangle that draws nothing: a vertex nearer than `near` or not finite, no area,
/// or facing away under [`Cull::Back`].
fn orient(vertices: [ScreenVertex; 3], cull: Cull, near: f32) -> Option<Oriented> {
    let [a, b, c] = vertices;
    if [a, b, c].iter().any(|v| {
        v.depth.is_nan() || near.is_nan() || v.depth < near || !v.x.is_finite() || !v.y.is_finite()
    }) {
        return None;
    }
    let area = edge(a.x, a.y, b.x, b.y, c.x, c.y);
    if area == 0.0 || !area.is_finite() {
        return None;
    }
    let front_facing = area < 0.0;
    if cull == Cull::Back && !front_facing {
        return None;
    }
    let (v, order) = if area > 0.0 {
        ([a, b, c], [0, 1, 2])
    } else {
        ([a, c, b], [0, 2, 1])
    };
    Some(Oriented {
        v,
        order,
        area: area.abs(),
        front_facing,
    })
}

/// Rasterizes one triangle. Triangles with a vertex nearer than `near` (or not finite) are skipped.
/// `shade` is called for every covered pixel nearer than the depth buffer, which is then updated.
pub fn draw_triangle(
    buffer: &mut DepthBuffer,
    vertices: [ScreenVertex; 3],
    cull: Cull,
    near: f32,
    shade: impl FnMut(Fragment),
) {
    let Some(oriented) = orient(vertices, cull, near) else {
        return;
    };
    let Oriented {
        v,
        area,
        front_facing,
        ..
    } = oriented;
    let [a, b, c] = vertices;
    // The caller's signed area is positive where its winding faces away from the camera.
    let area_positive = !front_facing;

    let (w, h) = (buffer.width as f32, buffer.height as f32);
    let min_x = floor_within(a.x.min(b.x).min(c.x), w).max(0);
    let max_x = ceil_within(a.x.max(b.x).max(c.x), w).min(buffer.width as i64);
    let min_y = floor_within(a.y.min(b.y).min(c.y), h).max(0);
    let max_y = ceil_within(a.y.max(b.y).max(c.y), h).min(buffer.height as i64);
    if min_x >= max_x || min_y >= max_y {
        return;
    }
    let bounds = Bounds {
        x: (min_x as u32, max_x as u32),
        y: (min_y as u32, max_y as u32),
    };
    // Weight i belongs to the edge opposite vertex i, directed so that the triangle is positively
    // wound: in the fast path they are kept in the caller's vertex order, so the weights need no
    // reordering per pixel.
    let edges = [
        Edge::new(v[1], v[2]),
        Edge::new(v[2], v[0]),
        Edge::new(v[0], v[1]),
    ];
    let inv_depth = [a, b, c].map(|p| 1.0 / p.depth);
    let inv_area = 1.0 / area;
    let base = inv_depth[0].min(inv_depth[1]).min(inv_depth[2]);
    let spans = Spans {
        top: inv_depth[0].max(inv_depth[1]).max(inv_depth[2]),
        edges: if area_positive {
            edges
        } else {
            [edges[0], edges[2], edges[1]]
        },
        base,
        rise: inv_depth.map(|d| (d - base) * inv_area),
        scale: inv_depth.map(|d| d * inv_area),
        front_facing,
    };
    // Within these limits no edge function, weight or depth can overflow, underflow to zero or
    // become NaN, and every 1/z is positive.
    let sane = buffer.width < 1 << 22
        && v.iter().all(|p| p.x.abs() <= 1e18 && p.y.abs() <= 1e18)
        && spans.scale.iter().all(|&s| (1e-30..=1e30).contains(&s));
    if sane {
        spans.draw(buffer, bounds, shade);
    } else {
        // Extreme input (huge coordinates, absurd depths): every pixel of the bounding box tested
        // on its own.
        reference::draw_oriented(buffer, oriented, shade);
    }
}

/// Pixel rows and columns `[start, end)` of a triangle's bounding box, clipped to the buffer.
#[derive(Clone, Copy, Debug)]
struct Bounds {
    x: (u32, u32),
    y: (u32, u32),
}

/// The fast path's triangle, everything indexed by the caller's vertex `i`: `edges[i]` is the edge
/// opposite vertex `i` (its edge function `eᵢ` is `λᵢ · area`), `λᵢ/zᵢ = eᵢ · scale[i]`, and
/// `1/z = Σ λᵢ/zᵢ = base + Σ eᵢ · rise[i]` (as `Σ λᵢ = 1`) with `base` the smallest `1/zᵢ`, so that
/// every term is non-negative (no cancellation) and a triangle of constant depth gets exactly that
/// depth.
#[derive(Clone, Copy, Debug)]
struct Spans {
    edges: [Edge; 3],
    base: f32,
    /// The largest `1/zᵢ`: with `base`, the range every `1/z` inside the triangle lies in.
    top: f32,
    rise: [f32; 3],
    scale: [f32; 3],
    front_facing: bool,
}

impl Spans {
    /// Per row, the covered span from the three edges, then one depth per pixel.
    #[inline]
    fn draw(&self, buffer: &mut DepthBuffer, bounds: Bounds, mut shade: impl FnMut(Fragment)) {
        let Spans {
            edges: [e0, e1, e2],
            base,
            top,
            rise: [g0, g1, g2],
            scale: [s0, s1, s2],
            front_facing,
        } = *self;
        let max = |a: f32, b: f32| if a > b { a } else { b };
        let min = |a: f32, b: f32| if a < b { a } else { b };
        let width = buffer.width as usize;
        let (lo, hi) = bounds.x;
        let (lo_f, hi_f) = (lo as f32, hi as f32);
        let row = Row::new(lo, hi);
        // d(1/z)/dx; the base cancels as Σ dyᵢ = 0.
        let dz = -(e0.dy * g0 + e1.dy * g1 + e2.dy * g2);
        for py in bounds.y.0..bounds.y.1 {
            let cy = py as f32 + 0.5;
            let (r0, r1, r2) = (e0.row(cy), e1.row(cy), e2.row(cy));
            let (b0, b1, b2) = (
                e0.boundary(r0, row),
                e1.boundary(r1, row),
                e2.boundary(r2, row),
            );
            let (start, end) = if b0.1 & b1.1 & b2.1 {
                // Each edge bounds one side: the other side's offset is +∞.
                let start = max(
                    max(lo_f, b0.0 - e0.left),
                    max(b1.0 - e1.left, b2.0 - e2.left),
                );
                let end = min(
                    min(hi_f, b0.0 + e0.right),
                    min(b1.0 + e1.right, b2.0 + e2.right),
                );
                if start >= end {
                    continue;
                }
                (start as u32, end as u32)
            } else {
                let (l0, l1, l2) = (
                    e0.limits(r0, lo, hi),
                    e1.limits(r1, lo, hi),
                    e2.limits(r2, lo, hi),
                );
                let start = l0.0.max(l1.0).max(l2.0);
                let end = l0.1.min(l1.1).min(l2.1);
                if start >= end {
                    continue;
                }
                (start, end)
            };
            let row_start = py as usize * width;
            let depths = &mut buffer.depth[row_start + start as usize..row_start + end as usize];
            // The edge functions at the span's first pixel, exactly as the coverage test has them;
            // along the row they fall by dyᵢ per pixel, and 1/z changes by `dz`.
            let cx = start as f32 + 0.5;
            let (a0, a1, a2) = (e0.at(r0, cx), e1.at(r1, cx), e2.at(r2, cx));
            let z0 = base + (a0 * g0 + a1 * g1 + a2 * g2);
            let mut n = 0.0f32; // pixels from the span's start (exact)
            for (px, stored) in (start..end).zip(depths) {
                // Kept within the vertices' range, which rounding might leave by an ulp (so 1/z
                // stays positive, as the per-pixel evaluation's sum of non-negative terms is).
                let inv_z = min(max(z0 + dz * n, base), top);
                let step = n;
                n += 1.0;
                // Cheap rejection without dividing: inv_z · stored < 1 − 2⁻²⁰ means the rounded
                // depth 1 / inv_z is certainly ≥ stored.
                if inv_z * *stored < 1.0 - 1.0 / (1 << 20) as f32 {
                    continue;
                }
                let depth = 1.0 / inv_z;
                if depth >= *stored {
                    continue;
                }
                *stored = depth;
                // λᵢ · area, not below 0 (where an edge passes through the span's last pixels,
                // stepping may round an exact 0 to a tiny negative value).
                let (w0, w1, w2) = (
                    max(a0 - e0.dy * step, 0.0),
                    max(a1 - e1.dy * step, 0.0),
                    max(a2 - e2.dy * step, 0.0),
                );
                shade(Fragment {
                    x: px,
                    y: py,
                    index: row_start + px as usize,
                    depth,
                    weights: [w0 * s0 * depth, w1 * s1 * depth, w2 * s2 * depth],
                    front_facing,
                });
            }
        }
    }
}

/// The rasterizer as it was before spans and incremental depth: every pixel of the bounding box
/// tested with the three edge functions, λ = e / area, depth = 1 / Σ λᵢ/zᵢ (three divisions per
/// covered pixel). [`draw_triangle`] falls back to it for extreme input (coordinates beyond 1e18,
/// 1/z beyond 1e-30..1e30), where its incremental spans could overflow; the tests check the spans
/// against it fragment for fragment, and `cargo bench --bench raster` measures both.
pub mod reference {
    use super::*;

    /// Draws one triangle as [`super::draw_triangle`] does, pixel by pixel.
    pub fn draw_triangle(
        buffer: &mut DepthBuffer,
        vertices: [ScreenVertex; 3],
        cull: Cull,
        near: f32,
        shade: impl FnMut(Fragment),
    ) {
        if let Some(oriented) = orient(vertices, cull, near) {
            draw_oriented(buffer, oriented, shade);
        }
    }

    /// The pixel loop of [`draw_triangle`], for a triangle [`orient`] accepted.
    pub(super) fn draw_oriented(
        buffer: &mut DepthBuffer,
        oriented: Oriented,
        mut shade: impl FnMut(Fragment),
    ) {
        let Oriented {
            v,
            order,
            area,
            front_facing,
        } = oriented;
        // The pixel rows or columns `[floor(min), ceil(max))` the three coordinates span,
        // clipped to `[0, limit]`.
        let span = |c: [f32; 3], limit: f32| {
            let lo = c.iter().copied().fold(f32::INFINITY, f32::min);
            let hi = c.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            (lo.floor().max(0.0), hi.ceil().min(limit))
        };
        let (min_x, max_x) = span(v.map(|p| p.x), buffer.width as f32);
        let (min_y, max_y) = span(v.map(|p| p.y), buffer.height as f32);
        if min_x >= max_x || min_y >= max_y {
            return;
        }
        let edges = [(1, 2), (2, 0), (0, 1)];
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
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sv(x: f32, y: f32, depth: f32) -> ScreenVertex {
        ScreenVertex { x, y, depth }
    }

    /// The fragments [`reference::draw_triangle`] gives, in its order.
    fn reference_fragments(
        buffer: &mut DepthBuffer,
        vertices: [ScreenVertex; 3],
        cull: Cull,
        near: f32,
    ) -> Vec<Fragment> {
        let mut out = Vec::new();
        reference::draw_triangle(buffer, vertices, cull, near, |f| out.push(f));
        out
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
            let mut colour = [0u8; 16];
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

    #[test]
    fn the_same_triangle_drawn_twice_draws_nothing_the_second_time() {
        let mut buffer = DepthBuffer::new(16, 16);
        let tri = [sv(0.3, 0.7, 2.0), sv(15.2, 3.1, 7.0), sv(4.4, 15.9, 3.5)];
        let mut first = 0;
        draw_triangle(&mut buffer, tri, Cull::None, 0.1, |_| first += 1);
        let mut second = 0;
        draw_triangle(&mut buffer, tri, Cull::None, 0.1, |_| second += 1);
        assert!(first > 50);
        assert_eq!(second, 0);
    }

    #[test]
    fn extreme_depths_take_the_per_pixel_path_and_match_the_reference_exactly() {
        for depth in [1e36f32, 3e-37] {
            let tri = [
                sv(0.5, 0.25, depth),
                sv(7.5, 1.0, depth * 2.0),
                sv(2.0, 7.75, depth),
            ];
            let (mut ours, mut theirs) = (DepthBuffer::new(8, 8), DepthBuffer::new(8, 8));
            let mut a = Vec::new();
            draw_triangle(&mut ours, tri, Cull::None, 0.0, |f| a.push(f));
            let b = reference_fragments(&mut theirs, tri, Cull::None, 0.0);
            assert!(!b.is_empty());
            assert_eq!(a, b);
            assert_eq!(ours, theirs);
        }
    }

    mod properties {
        use super::*;
        use proptest::prelude::*;

        const W: u32 = 64;
        const H: u32 = 48;

        /// A coordinate: anywhere around the buffer, snapped to a 1/8-pixel grid now and then so
        /// that pixel centres land exactly on edges and vertices (fill-rule ties) often.
        fn coordinate(extent: f32) -> impl Strategy<Value = f32> {
            prop_oneof![
                3 => -20.0f32..extent + 20.0,
                2 => (-160i32..(extent as i32 + 20) * 8).prop_map(|i| i as f32 / 8.0),
                1 => (-2i32..(extent as i32 + 2)).prop_map(|i| i as f32 + 0.5),
                1 => (-160i32..(extent as i32 + 20) * 8, -1e-4f32..1e-4)
                    .prop_map(|(i, jitter)| i as f32 / 8.0 + jitter),
                1 => -5000.0f32..5000.0,
            ]
        }

        fn vertex() -> impl Strategy<Value = ScreenVertex> {
            (coordinate(W as f32), coordinate(H as f32), 0.2f32..100.0)
                .prop_map(|(x, y, depth)| sv(x, y, depth))
        }

        /// Triangles of all shapes, including slivers: the third vertex close to the line through
        /// the first two.
        fn triangle() -> impl Strategy<Value = [ScreenVertex; 3]> {
            prop_oneof![
                3 => [vertex(), vertex(), vertex()],
                1 => (vertex(), vertex(), 0.0f32..1.0, -0.05f32..0.05, 0.2f32..100.0).prop_map(
                    |(a, b, t, off, depth)| {
                        let (dx, dy) = (b.x - a.x, b.y - a.y);
                        let c = sv(a.x + t * dx - off * dy, a.y + t * dy + off * dx, depth);
                        [a, b, c]
                    }
                ),
                1 => (coordinate(W as f32), coordinate(H as f32), prop::array::uniform3(
                        (-4.0f32..4.0, -4.0f32..4.0, 0.5f32..30.0))).prop_map(|(x, y, d)| {
                        d.map(|(ox, oy, depth)| sv(x + ox, y + oy, depth))
                    }),
            ]
        }

        /// What is in the buffer before the triangle: nothing, something nearer than any
        /// triangle, or something farther.
        fn background() -> impl Strategy<Value = Vec<f32>> {
            prop::collection::vec(
                prop_oneof![Just(f32::INFINITY), Just(0.1f32), Just(1000.0f32)],
                (W * H) as usize,
            )
        }

        fn buffer_from(depths: &[f32]) -> DepthBuffer {
            DepthBuffer {
                width: W,
                height: H,
                depth: depths.to_vec(),
            }
        }

        /// The relative rounding error float evaluation of the barycentric weights can have at
        /// pixel `(x, y)`, beyond the usual few ulps: the edge functions are differences of
        /// products, so their error scales with the size of those products against the area (large
        /// for slivers and for far-away vertices; both rasterizers inherit it), and 1/z mixes
        /// the vertices' 1/zᵢ, so its relative error grows with their ratio.
        fn rounding(tri: [ScreenVertex; 3], x: u32, y: u32) -> f32 {
            let (cx, cy) = (x as f64 + 0.5, y as f64 + 0.5);
            let p = tri.map(|v| (v.x as f64, v.y as f64));
            let area = ((p[1].0 - p[0].0) * (p[2].1 - p[0].1)
                - (p[1].1 - p[0].1) * (p[2].0 - p[0].0))
                .abs();
            let terms: f64 = (0..3)
                .map(|k| {
                    let (a, b) = (p[(k + 1) % 3], p[(k + 2) % 3]);
                    ((b.0 - a.0) * (cy - a.1)).abs() + ((b.1 - a.1) * (cx - a.0)).abs()
                })
                .sum();
            let depths = tri.map(|v| v.depth as f64);
            let ratio = depths.iter().fold(0.0f64, |m, &d| m.max(d))
                / depths.iter().fold(f64::INFINITY, |m, &d| m.min(d));
            (8.0 * f32::EPSILON as f64 * (terms / area) * ratio) as f32
        }

        fn close(a: f32, b: f32, relative: f32) -> bool {
            a == b || (a - b).abs() <= relative * a.abs().max(b.abs())
        }

        proptest! {
            #![proptest_config(ProptestConfig {
                cases: 3000,
                max_global_rejects: 100_000,
                ..ProptestConfig::default()
            })]

            #[test]
            fn matches_the_reference_rasterizer(
                tri in triangle(),
                back in any::<bool>(),
                near in prop_oneof![Just(0.1f32), 0.2f32..30.0],
                depths in background(),
            ) {
                let cull = if back { Cull::Back } else { Cull::None };
                let mut ours = buffer_from(&depths);
                let mut theirs = buffer_from(&depths);
                let mut got = Vec::new();
                draw_triangle(&mut ours, tri, cull, near, |f| got.push(f));
                let want = reference_fragments(&mut theirs, tri, cull, near);
                prop_assert_eq!(got.len(), want.len(), "{:?}", tri);
                for (g, w) in got.iter().zip(&want) {
                    prop_assert_eq!((g.x, g.y, g.index, g.front_facing), (w.x, w.y, w.index, w.front_facing));
                    let tolerance = 1e-4 + rounding(tri, g.x, g.y);
                    prop_assert!(close(g.depth, w.depth, tolerance), "{:?} vs {:?}", g, w);
                    for k in 0..3 {
                        prop_assert!((g.weights[k] - w.weights[k]).abs() <= tolerance, "{:?} vs {:?}", g, w);
                    }
                    prop_assert_eq!(ours.depth[g.index], g.depth);
                    prop_assert_eq!(theirs.depth[w.index], w.depth);
                }
                // Nothing else changed.
                for fragment in &got {
                    ours.depth[fragment.index] = depths[fragment.index];
                }
                prop_assert!(ours.depth == depths);
            }

            /// Wherever the analytic row boundary of an edge is trusted, it is the one the exact
            /// per-pixel test finds.
            #[test]
            fn analytic_boundaries_agree_with_the_exact_test(
                a in (coordinate(W as f32), coordinate(H as f32)),
                b in (coordinate(W as f32), coordinate(H as f32)),
                scale in prop_oneof![Just(1.0f32), Just(16.0f32), Just(1000.0f32)],
                top_left in any::<bool>(),
            ) {
                let (a, b) = (sv(a.0 * scale, a.1 * scale, 1.0), sv(b.0 * scale, b.1 * scale, 1.0));
                let mut e = Edge::new(a, b);
                prop_assume!(e.dy != 0.0);
                e.top_left = top_left;
                let (lo, hi) = (0, (W as f32 * scale) as u32);
                let rows = (a.y.min(b.y).floor().max(0.0) as u32)..(a.y.max(b.y).ceil().max(0.0) as u32);
                for py in rows.take(200) {
                    let row = e.row(py as f32 + 0.5);
                    if e.boundary(row, Row::new(lo, hi)).1 {
                        prop_assert_eq!(e.limits(row, lo, hi), e.walk(row, lo, hi), "{:?} row {}", e, py);
                    }
                }
            }

            /// A convex polygon (vertices on a 1/8-pixel grid, either winding) split into triangles
            /// in two different ways: each way covers every pixel at most once, and both cover the
            /// same pixels — the fill rule neither drops nor doubles pixels on shared edges.
            #[test]
            fn triangulations_of_a_polygon_cover_each_pixel_once(
                centre in (8.0f32..56.0, 8.0f32..40.0),
                radii in (2.0f32..30.0, 2.0f32..30.0),
                mut angles in prop::collection::vec(0.0f32..std::f32::consts::TAU, 3..9),
                reverse in any::<bool>(),
            ) {
                angles.sort_by(f32::total_cmp);
                let snap = |v: f32| (v * 8.0).round() / 8.0;
                let mut poly: Vec<ScreenVertex> = angles
                    .iter()
                    .map(|a| sv(snap(centre.0 + radii.0 * a.cos()), snap(centre.1 + radii.1 * a.sin()), 5.0))
                    .collect();
                poly.dedup_by(|a, b| a.x == b.x && a.y == b.y);
                if reverse {
                    poly.reverse();
                }
                let n = poly.len();
                // Strictly convex after snapping: all turns the same way, none straight.
                let turns: Vec<f32> = (0..n)
                    .map(|i| {
                        let (a, b, c) = (poly[i], poly[(i + 1) % n], poly[(i + 2) % n]);
                        edge(a.x, a.y, b.x, b.y, c.x, c.y)
                    })
                    .collect();
                prop_assume!(n >= 3 && (turns.iter().all(|&t| t > 0.0) || turns.iter().all(|&t| t < 0.0)));
                let inner = sv(
                    snap(poly.iter().map(|p| p.x).sum::<f32>() / n as f32),
                    snap(poly.iter().map(|p| p.y).sum::<f32>() / n as f32),
                    5.0,
                );
                // The inner point, snapped, must stay strictly inside.
                prop_assume!((0..n).all(|i| {
                    let (a, b) = (poly[i], poly[(i + 1) % n]);
                    edge(a.x, a.y, b.x, b.y, inner.x, inner.y) * turns[0] > 0.0
                }));
                let fan_from_vertex: Vec<[ScreenVertex; 3]> =
                    (1..n - 1).map(|i| [poly[0], poly[i], poly[i + 1]]).collect();
                let fan_from_inside: Vec<[ScreenVertex; 3]> =
                    (0..n).map(|i| [inner, poly[i], poly[(i + 1) % n]]).collect();
                let mut coverage = Vec::new();
                for tris in [fan_from_vertex, fan_from_inside] {
                    let mut count = vec![0u32; (W * H) as usize];
                    for tri in tris {
                        // A fresh buffer per triangle: coverage alone, no depth test between them.
                        let mut buffer = DepthBuffer::new(W, H);
                        draw_triangle(&mut buffer, tri, Cull::None, 0.1, |f| count[f.index] += 1);
                    }
                    prop_assert!(count.iter().all(|&c| c <= 1));
                    coverage.push(count);
                }
                prop_assert_eq!(&coverage[0], &coverage[1]);
            }
        }
    }
}
