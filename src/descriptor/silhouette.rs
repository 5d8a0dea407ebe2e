//! Shape contexts of the silhouette's outer contour: the Agarwal & Triggs silhouette descriptor
//! (the baseline against which the HOG descriptor is compared).
//!
//! Pipeline ([`silhouette_shape_contexts`]): the outer boundary of the largest 4-connected person
//! region ([`outer_contour`]) → [`CONTOUR_POINTS`] points evenly spaced along it
//! ([`resample_closed`]) → one 60-value shape-context histogram per point ([`shape_contexts`]). The
//! next stage (k-means codebook vector quantisation) treats each of the 400 histograms as one local
//! feature vector and accumulates their codeword assignments into the frame's bag-of-features
//! vector. Each histogram sums to 1, so every contour point carries equal weight.
//!
//! Conventions (image coordinates, x to the right, **y downwards**):
//! * contour points are **pixel centres**: pixel (x, y) is the point (x, y) (integer coordinates);
//! * the contour runs **clockwise as seen on screen** (right along the top edge first), i.e. its
//!   shoelace area Σ (xᵢ·yᵢ₊₁ − xᵢ₊₁·yᵢ)/2 in (x, y) coordinates is positive;
//! * shape-context layout: value `r * SC_ANGULAR + a` for radial bin `r` (0 = innermost) and angular
//!   bin `a`; angular bin `a` covers directions [−π + a·30°, −π + (a+1)·30°) of atan2(dy, dx) of the
//!   *other* point relative to this one, so the descriptor is deliberately **not** rotation invariant
//!   (angle 0 = +x, +π/2 = down the image);
//! * radial scale: the mean distance `m` between all pairs of the points; radial edges are
//!   `m·(1/8)·16^(k/5)` for k = 0..=5, i.e. log-spaced from m/8 to 2m. Points closer than the first
//!   inner edge (including coincident points) count in the innermost bin, points farther than 2m are
//!   ignored. This makes the descriptor scale invariant.

use crate::mask::Mask;
use crate::segment::cleanup::neighbours4;
use glam::Vec2;
use std::f32::consts::PI;

/// Points the contour is resampled to.
pub const CONTOUR_POINTS: usize = 400;
/// Log-spaced radial bins.
pub const SC_RADIAL: usize = 5;
/// Angular bins over [−π, π).
pub const SC_ANGULAR: usize = 12;
/// Values per shape-context histogram.
pub const SC_BINS: usize = SC_RADIAL * SC_ANGULAR;
/// Innermost radial edge, as a fraction of the mean pairwise distance.
pub const SC_INNER_RADIUS: f32 = 0.125;
/// Outermost radial edge, as a fraction of the mean pairwise distance.
pub const SC_OUTER_RADIUS: f32 = 2.0;

/// Moore neighbourhood, clockwise on screen starting from west: (dx, dy).
const DIRS: [(i64, i64); 8] = [
    (-1, 0),
    (-1, -1),
    (0, -1),
    (1, -1),
    (1, 0),
    (1, 1),
    (0, 1),
    (-1, 1),
];
const WEST: usize = 0;

/// Outer boundary of the largest 4-connected person region, as pixel-centre points (pixel (x, y) is
/// the point (x, y)) in order, clockwise as seen on screen (y down), starting at the region's first
/// pixel in raster order.
///
/// Moore-neighbour tracing with Jacob's stopping criterion, in the form "stop when the first move
/// (start pixel → second pixel, entered from the same backtrack neighbour) is about to be repeated",
/// which also terminates on one-pixel-wide parts that are traversed twice. Consecutive points
/// (including last → first) are 8-neighbours; a pixel on a one-pixel-wide part may appear more than
/// once. Holes and all other components are ignored (other components count as background). Ties in
/// size go to the region met first in raster order. An isolated pixel gives one point; an empty mask
/// gives an empty Vec.
pub fn outer_contour(mask: &Mask) -> Vec<Vec2> {
    let Some(region) = largest_component(mask) else {
        return Vec::new();
    };
    let (w, h) = (mask.width() as i64, mask.height() as i64);
    let inside = |(x, y): (i64, i64)| {
        x >= 0 && y >= 0 && x < w && y < h && region.label[(y * w + x) as usize] == region.id
    };
    let start = ((region.start as i64) % w, (region.start as i64) / w);
    let to_point = |(x, y): (i64, i64)| Vec2::new(x as f32, y as f32);

    // The start pixel is the first in raster order, so its west neighbour is background.
    let Some(first) = moore_step(start, WEST, &inside) else {
        return vec![to_point(start)];
    };
    // The tracing is a deterministic map on states (pixel, backtrack direction); the state after
    // the first move lies on the boundary cycle, so it recurs. At most 8·area states exist.
    let mut contour = Vec::new();
    let mut state = first;
    for _ in 0..=8 * region.size {
        contour.push(to_point(state.0));
        match moore_step(state.0, state.1, &inside) {
            Some(next) if next == first => break,
            Some(next) => state = next,
            None => break,
        }
    }
    // The cycle was recorded from the second pixel; its last pixel is the start: put it first.
    contour.rotate_right(1);
    contour
}

/// From pixel `p`, entered with background neighbour in direction `backtrack`, the next boundary
/// pixel clockwise and the direction (from it) of its new backtrack neighbour.
fn moore_step(
    p: (i64, i64),
    backtrack: usize,
    inside: &impl Fn((i64, i64)) -> bool,
) -> Option<((i64, i64), usize)> {
    for k in 1..8 {
        let d = (backtrack + k) % 8;
        let c = (p.0 + DIRS[d].0, p.1 + DIRS[d].1);
        if inside(c) {
            // The previously examined (background) neighbour of p, seen from c.
            let prev = DIRS[(d + 7) % 8];
            let rel = (prev.0 - DIRS[d].0, prev.1 - DIRS[d].1);
            let new_backtrack = DIRS.iter().position(|&q| q == rel).unwrap_or(WEST);
            return Some((c, new_backtrack));
        }
    }
    None
}

/// The largest 4-connected foreground component: per-pixel labels, its label, size and first pixel.
struct Component {
    label: Vec<u32>,
    id: u32,
    size: usize,
    start: usize,
}

fn largest_component(mask: &Mask) -> Option<Component> {
    let (w, h) = (mask.width() as usize, mask.height() as usize);
    let px = mask.pixels();
    if w == 0 || h == 0 || px.len() != w * h {
        return None;
    }
    let mut label = vec![0u32; w * h];
    let mut stack = Vec::new();
    let mut best: Option<(u32, usize, usize)> = None; // (id, size, start)
    let mut next_id = 0u32;
    for start in 0..w * h {
        if !px[start] || label[start] != 0 {
            continue;
        }
        next_id += 1;
        label[start] = next_id;
        stack.push(start);
        let mut size = 0;
        while let Some(i) = stack.pop() {
            size += 1;
            for n in neighbours4(i, w, h).into_iter().flatten() {
                if px[n] && label[n] == 0 {
                    label[n] = next_id;
                    stack.push(n);
                }
            }
        }
        if !matches!(best, Some((_, s, _)) if s >= size) {
            best = Some((next_id, size, start));
        }
    }
    best.map(|(id, size, start)| Component {
        label,
        id,
        size,
        start,
    })
}

/// `n` points evenly spaced by arc length along the closed polyline `contour` (the segment from the
/// last point back to the first included), starting at `contour[0]`. Empty if `contour` is empty or
/// `n` is 0; `n` copies of the point if the contour has zero length.
pub fn resample_closed(contour: &[Vec2], n: usize) -> Vec<Vec2> {
    if contour.is_empty() || n == 0 {
        return Vec::new();
    }
    let m = contour.len();
    let segment = |i: usize| (contour[i], contour[(i + 1) % m]);
    let lengths: Vec<f64> = (0..m)
        .map(|i| {
            let (a, b) = segment(i);
            (b - a).as_dvec2().length()
        })
        .collect();
    let total: f64 = lengths.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        return vec![contour[0]; n];
    }
    let step = total / n as f64;
    let mut out = Vec::with_capacity(n);
    let (mut i, mut start_of_segment) = (0, 0.0);
    for k in 0..n {
        let s = k as f64 * step;
        while i + 1 < m && start_of_segment + lengths[i] <= s {
            start_of_segment += lengths[i];
            i += 1;
        }
        let (a, b) = segment(i);
        let t = if lengths[i] > 0.0 {
            ((s - start_of_segment) / lengths[i]).clamp(0.0, 1.0)
        } else {
            0.0
        };
        out.push((a.as_dvec2() + (b - a).as_dvec2() * t).as_vec2());
    }
    out
}

/// Shape-context histogram (5 log-radial × 12 angular = 60 values, layout `r * 12 + a`, each
/// normalised to sum 1) at every point; see the module documentation for the bins and the scale.
/// O(n²): each unordered pair is visited once. A point with no other point within the outer radius
/// (only possible with fewer than 2 points) gets the uniform histogram 1/60.
pub fn shape_contexts(points: &[Vec2]) -> Vec<[f32; SC_BINS]> {
    let n = points.len();
    if n == 0 {
        return Vec::new();
    }
    let mut sum = 0.0f64;
    for (i, &p) in points.iter().enumerate() {
        sum += points[i + 1..]
            .iter()
            .map(|&q| (q - p).length() as f64)
            .sum::<f64>();
    }
    let pairs = (n * (n - 1) / 2).max(1) as f64;
    let mean = (sum / pairs) as f32;
    // All points coincident (or non-finite input): any positive scale puts them in the first bin.
    let scale = if mean > 0.0 && mean.is_finite() {
        mean
    } else {
        1.0
    };
    // Squared radial edges: inner edges 1..=4, then the outer edge.
    let edge = |k: usize| {
        let r = scale
            * SC_INNER_RADIUS
            * (SC_OUTER_RADIUS / SC_INNER_RADIUS).powf(k as f32 / SC_RADIAL as f32);
        r * r
    };
    let inner: [f32; SC_RADIAL - 1] = std::array::from_fn(|k| edge(k + 1));
    let outer = edge(SC_RADIAL);

    let mut histograms = vec![[0.0f32; SC_BINS]; n];
    for i in 0..n {
        for j in i + 1..n {
            let d = points[j] - points[i];
            let d2 = d.length_squared();
            // Beyond the outer radius, or NaN: ignored.
            if d2 > outer || d2.is_nan() {
                continue;
            }
            let r = inner.iter().take_while(|&&e| d2 >= e).count();
            let a = angular_bin(d);
            histograms[i][r * SC_ANGULAR + a] += 1.0;
            histograms[j][r * SC_ANGULAR + (a + SC_ANGULAR / 2) % SC_ANGULAR] += 1.0;
        }
    }
    for h in &mut histograms {
        let total: f32 = h.iter().sum();
        if total > 0.0 {
            h.iter_mut().for_each(|v| *v /= total);
        } else {
            *h = [1.0 / SC_BINS as f32; SC_BINS];
        }
    }
    histograms
}

/// Angular bin of direction `d`: ⌊(atan2(dy, dx) + π) / 30°⌋, with +π wrapped to bin 0.
fn angular_bin(d: Vec2) -> usize {
    let theta = super::hog::fast_atan2(d.y, d.x);
    let b = ((theta + PI) * (SC_ANGULAR as f32 / (2.0 * PI))) as usize;
    b.min(SC_ANGULAR) % SC_ANGULAR
}

/// The whole pipeline: outer contour → [`CONTOUR_POINTS`] evenly spaced points → shape contexts.
/// Empty for an empty mask. The contour is first moved so its bounding box starts at the origin
/// (exact for integer pixel coordinates), so translating the mask changes nothing, bit for bit.
pub fn silhouette_shape_contexts(mask: &Mask) -> Vec<[f32; SC_BINS]> {
    let contour = outer_contour(mask);
    if contour.is_empty() {
        return Vec::new();
    }
    let min = contour
        .iter()
        .fold(Vec2::splat(f32::INFINITY), |m, &p| m.min(p));
    let contour: Vec<Vec2> = contour.iter().map(|&p| p - min).collect();
    shape_contexts(&resample_closed(&contour, CONTOUR_POINTS))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A crude person: head, torso, arms out to one side, two legs.
    fn person(x: u32, y: u32) -> bool {
        let head = (x as i32 - 20).pow(2) + (y as i32 - 6).pow(2) <= 25;
        let torso = (14..27).contains(&x) && (11..34).contains(&y);
        let arm = (27..38).contains(&x) && (13..17).contains(&y);
        let other_arm = (9..14).contains(&x) && (13..28).contains(&y);
        let legs = ((14..19).contains(&x) || (22..27).contains(&x)) && (34..52).contains(&y);
        head || torso || arm || other_arm || legs
    }

    fn is_8_neighbour(a: Vec2, b: Vec2) -> bool {
        let d = (a - b).abs();
        d.max_element() == 1.0
    }

    fn shoelace(c: &[Vec2]) -> f32 {
        (0..c.len())
            .map(|i| c[i].perp_dot(c[(i + 1) % c.len()]))
            .sum::<f32>()
            / 2.0
    }

    fn mean_histogram(h: &[[f32; SC_BINS]]) -> [f32; SC_BINS] {
        let mut m = [0.0; SC_BINS];
        for row in h {
            for (a, b) in m.iter_mut().zip(row) {
                *a += b / h.len() as f32;
            }
        }
        m
    }

    #[test]
    fn square_contour_is_its_boundary_pixels_in_order() {
        // 10×10 square at (3, 2) in a 16×14 mask: 36 boundary pixels, clockwise from (3, 2).
        let mask = Mask::from_fn(16, 14, |x, y| (3..13).contains(&x) && (2..12).contains(&y));
        let c = outer_contour(&mask);
        assert_eq!(c.len(), 36);
        assert_eq!(c[0], Vec2::new(3.0, 2.0));
        assert_eq!(c[1], Vec2::new(4.0, 2.0), "goes right along the top first");
        for i in 0..c.len() {
            assert!(
                is_8_neighbour(c[i], c[(i + 1) % c.len()]),
                "{} {}",
                c[i],
                c[(i + 1) % c.len()]
            );
            let on_edge = c[i].x == 3.0 || c[i].x == 12.0 || c[i].y == 2.0 || c[i].y == 11.0;
            assert!(on_edge, "{}", c[i]);
        }
        let mut sorted: Vec<(i32, i32)> = c.iter().map(|p| (p.x as i32, p.y as i32)).collect();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted.len(), 36, "each boundary pixel once");
        assert!(shoelace(&c) > 0.0, "clockwise on screen");
    }

    #[test]
    fn single_pixel_and_empty_masks() {
        let one = Mask::from_fn(5, 5, |x, y| x == 2 && y == 3);
        assert_eq!(outer_contour(&one), vec![Vec2::new(2.0, 3.0)]);
        assert!(outer_contour(&Mask::empty(5, 5)).is_empty());
        assert!(outer_contour(&Mask::empty(0, 0)).is_empty());
        assert!(silhouette_shape_contexts(&Mask::empty(5, 5)).is_empty());
        assert!(silhouette_shape_contexts(&Mask::empty(0, 7)).is_empty());
        // A single pixel still gives 400 valid histograms (all points coincide: innermost bin).
        let h = silhouette_shape_contexts(&one);
        assert_eq!(h.len(), CONTOUR_POINTS);
        assert!(h.iter().all(|h| (h.iter().sum::<f32>() - 1.0).abs() < 1e-5));
    }

    #[test]
    fn largest_component_wins_and_holes_are_ignored() {
        // A 3×3 blob at the top left (first in raster order) and a 6×6 ring (with a hole) below.
        let mask = Mask::from_fn(12, 12, |x, y| {
            let small = x < 3 && y < 3;
            let ring = (4..10).contains(&x)
                && (4..10).contains(&y)
                && !((6..8).contains(&x) && (6..8).contains(&y));
            small || ring
        });
        let c = outer_contour(&mask);
        assert_eq!(c[0], Vec2::new(4.0, 4.0));
        assert_eq!(c.len(), 20, "outer boundary of the 6×6 ring only");
        // Diagonal-only contact does not join 4-connected components.
        let diagonal = Mask::from_fn(4, 4, |x, y| {
            (x == 0 && y == 0) || (x == 1 && y == 1) || (x == 2 && y == 1)
        });
        assert_eq!(
            outer_contour(&diagonal),
            vec![Vec2::new(1.0, 1.0), Vec2::new(2.0, 1.0)]
        );
    }

    #[test]
    fn thin_line_is_traced_there_and_back() {
        let mask = Mask::from_fn(7, 3, |x, y| y == 1 && (1..6).contains(&x));
        let c = outer_contour(&mask);
        let xs: Vec<f32> = c.iter().map(|p| p.x).collect();
        assert_eq!(xs, vec![1.0, 2.0, 3.0, 4.0, 5.0, 4.0, 3.0, 2.0]);
    }

    #[test]
    fn resampled_square_is_evenly_spaced() {
        let square = [
            Vec2::new(0.0, 0.0),
            Vec2::new(10.0, 0.0),
            Vec2::new(10.0, 10.0),
            Vec2::new(0.0, 10.0),
        ];
        for (n, spacing) in [(40, 1.0f32), (16, 2.5), (8, 5.0)] {
            let r = resample_closed(&square, n);
            assert_eq!(r.len(), n);
            assert_eq!(r[0], square[0]);
            for i in 0..n {
                let d = (r[(i + 1) % n] - r[i]).length();
                assert!((d / spacing - 1.0).abs() < 1e-3, "n {n}, i {i}: {d}");
            }
        }
        // The square mask's own contour (36 unit steps) resampled to 72 points: spacing 0.5.
        let mask = Mask::from_fn(12, 12, |x, y| (1..11).contains(&x) && (1..11).contains(&y));
        let r = resample_closed(&outer_contour(&mask), 72);
        for i in 0..72 {
            let d = (r[(i + 1) % 72] - r[i]).length();
            assert!((d / 0.5 - 1.0).abs() < 1e-3, "{i}: {d}");
        }
        assert!(resample_closed(&[], 5).is_empty());
        assert!(resample_closed(&square, 0).is_empty());
        assert_eq!(resample_closed(&[Vec2::ONE], 3), vec![Vec2::ONE; 3]);
    }

    #[test]
    fn circle_contexts_agree_up_to_angular_shift() {
        let n = CONTOUR_POINTS;
        let circle: Vec<Vec2> = (0..n)
            .map(|k| {
                let phi = k as f64 * std::f64::consts::TAU / n as f64;
                Vec2::new(
                    (100.0 + 50.0 * phi.cos()) as f32,
                    (80.0 + 50.0 * phi.sin()) as f32,
                )
            })
            .collect();
        let h = shape_contexts(&circle);
        let radial = |h: &[f32; SC_BINS]| -> [f32; SC_RADIAL] {
            std::array::from_fn(|r| h[r * SC_ANGULAR..(r + 1) * SC_ANGULAR].iter().sum())
        };
        let reference = radial(&h[0]);
        for (k, hk) in h.iter().enumerate() {
            let rk = radial(hk);
            for r in 0..SC_RADIAL {
                assert!(
                    (rk[r] - reference[r]).abs() < 1e-5,
                    "point {k} radial {r}: {rk:?} vs {reference:?}"
                );
            }
        }
        // A quarter turn round the circle (100 points) is exactly 3 angular bins.
        for k in 0..n {
            let (a, b) = (&h[k], &h[(k + n / 4) % n]);
            let diff: f32 = (0..SC_RADIAL)
                .flat_map(|r| (0..SC_ANGULAR).map(move |t| (r, t)))
                .map(|(r, t)| {
                    (a[r * SC_ANGULAR + t] - b[r * SC_ANGULAR + (t + 3) % SC_ANGULAR]).abs()
                })
                .sum();
            assert!(diff <= 4.0 / (n - 1) as f32 + 1e-5, "point {k}: L1 {diff}");
        }
    }

    #[test]
    fn scaling_the_mask_by_two_changes_little() {
        let small = Mask::from_fn(48, 56, person);
        let big = Mask::from_fn(96, 112, |x, y| person(x / 2, y / 2));
        let (a, b) = (
            silhouette_shape_contexts(&small),
            silhouette_shape_contexts(&big),
        );
        let (ma, mb) = (mean_histogram(&a), mean_histogram(&b));
        let l1: f32 = ma.iter().zip(&mb).map(|(x, y)| (x - y).abs()).sum();
        println!("mean-histogram L1 difference after ×2 scaling: {l1:.4}");
        assert!(l1 < 0.1, "{l1}");
    }

    #[test]
    fn translating_the_mask_changes_nothing() {
        let a = Mask::from_fn(48, 56, person);
        let b = Mask::from_fn(70, 90, |x, y| x >= 13 && y >= 21 && person(x - 13, y - 21));
        assert_eq!(silhouette_shape_contexts(&a), silhouette_shape_contexts(&b));
    }

    #[test]
    fn every_histogram_sums_to_one() {
        let h = silhouette_shape_contexts(&Mask::from_fn(48, 56, person));
        assert_eq!(h.len(), CONTOUR_POINTS);
        for row in &h {
            assert!((row.iter().sum::<f32>() - 1.0).abs() < 1e-5);
        }
        assert!(shape_contexts(&[]).is_empty());
        assert_eq!(
            shape_contexts(&[Vec2::ZERO]),
            vec![[1.0 / SC_BINS as f32; SC_BINS]]
        );
    }

    #[test]
    fn timing_person_200x400() {
        // Not asserted; run with `cargo test --release -- --nocapture timing`.
        let mask = Mask::from_fn(220, 420, |x, y| person(x * 48 / 210, y * 56 / 410));
        let contour = outer_contour(&mask);
        let points = resample_closed(&contour, CONTOUR_POINTS);
        let runs = 20;
        let t = std::time::Instant::now();
        let mut sink = 0.0;
        for _ in 0..runs {
            sink += shape_contexts(&points)[0][0];
        }
        let sc = t.elapsed().as_secs_f64() / runs as f64;
        let t = std::time::Instant::now();
        for _ in 0..runs {
            sink += silhouette_shape_contexts(&mask)[0][0];
        }
        let all = t.elapsed().as_secs_f64() / runs as f64;
        println!(
            "silhouette: contour {} px; shape_contexts(400) {:.3} ms; whole pipeline {:.3} ms ({sink})",
            contour.len(),
            sc * 1e3,
            all * 1e3
        );
    }

    /// The traced outer boundary of the largest component contains every one of its pixels that is
    /// 4-adjacent to the exterior background (the background 4-connected to outside the image), and
    /// only pixels 8-adjacent to it.
    fn check_against_exterior(mask: &Mask, contour: &[Vec2]) {
        let Some(comp) = largest_component(mask) else {
            assert!(contour.is_empty());
            return;
        };
        let (w, h) = (mask.width() as i64, mask.height() as i64);
        let in_region = |x: i64, y: i64| {
            x >= 0 && y >= 0 && x < w && y < h && comp.label[(y * w + x) as usize] == comp.id
        };
        // Exterior on the grid padded by one pixel all round.
        let (pw, ph) = (w + 2, h + 2);
        let mut exterior = vec![false; (pw * ph) as usize];
        let mut stack = vec![(-1i64, -1i64)];
        exterior[0] = true;
        while let Some((x, y)) = stack.pop() {
            for (nx, ny) in [(x - 1, y), (x + 1, y), (x, y - 1), (x, y + 1)] {
                let inside_pad = nx >= -1 && ny >= -1 && nx <= w && ny <= h;
                if inside_pad && !in_region(nx, ny) && !exterior[((ny + 1) * pw + nx + 1) as usize]
                {
                    exterior[((ny + 1) * pw + nx + 1) as usize] = true;
                    stack.push((nx, ny));
                }
            }
        }
        let is_ext = |x: i64, y: i64| exterior[((y + 1) * pw + x + 1) as usize];
        let on_contour: std::collections::HashSet<(i64, i64)> =
            contour.iter().map(|p| (p.x as i64, p.y as i64)).collect();
        for y in 0..h {
            for x in 0..w {
                if !in_region(x, y) {
                    continue;
                }
                let four = [(x - 1, y), (x + 1, y), (x, y - 1), (x, y + 1)];
                if four.iter().any(|&(a, b)| is_ext(a, b)) {
                    assert!(
                        on_contour.contains(&(x, y)),
                        "({x}, {y}) missing from {contour:?}"
                    );
                }
            }
        }
        for &(x, y) in &on_contour {
            assert!(in_region(x, y));
            let eight = DIRS.iter().any(|&(dx, dy)| is_ext(x + dx, y + dy));
            assert!(eight, "({x}, {y}) is not on the outer boundary");
        }
    }

    proptest! {
        #[test]
        fn random_masks_never_panic(
            (w, h, pixels) in (0u32..24, 0u32..24).prop_flat_map(|(w, h)| {
                (Just(w), Just(h), proptest::collection::vec(any::<bool>(), (w * h) as usize))
            }),
        ) {
            let mask = Mask::from_pixels(w, h, pixels).expect("size");
            let c = outer_contour(&mask);
            prop_assert_eq!(c.is_empty(), mask.is_empty());
            for i in 0..c.len() {
                let (p, q) = (c[i], c[(i + 1) % c.len()]);
                prop_assert!(mask.get(p.x as u32, p.y as u32));
                prop_assert!(c.len() == 1 || is_8_neighbour(p, q), "{} {}", p, q);
            }
            check_against_exterior(&mask, &c);
            let h = silhouette_shape_contexts(&mask);
            prop_assert!(h.is_empty() == mask.is_empty());
            prop_assert!(h.is_empty() || h.len() == CONTOUR_POINTS);
            for row in &h {
                prop_assert!(row.iter().all(|v| v.is_finite() && *v >= 0.0));
                prop_assert!((row.iter().sum::<f32>() - 1.0).abs() < 1e-4);
            }
        }
    }
}
