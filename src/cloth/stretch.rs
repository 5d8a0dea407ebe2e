//! The stretch constraints' Gauss–Seidel sweep, four edges at a time.
//!
//! The solver hands this module its stretch constraints in sweep order (anchors outward,
//! interleaved so that neighbours share no vertex) and gets back [`EdgeQuads`]: runs of up to
//! four consecutive constraints that share no vertex, packed lane by lane. [`sweep`] projects one
//! quad per step: the eight end points are loaded, transposed to x, y and z rows, projected in
//! the four lanes at once and stored back. Because the edges of a quad share no vertex, this is the
//! same computation as projecting them one after another, in the same arithmetic per edge: the
//! positions are bit-identical to a scalar sweep in the same order (a test checks it), only
//! cheaper. The sweeps were about half of the solver's time, each projection a dot product across
//! one `Vec3A`'s lanes and a division for one edge; on x86-64 the quad kernel uses SSE2, which
//! every x86-64 processor has, and elsewhere the same quads are projected lane by lane.
//!
//! Each projection computes its correction `(l − l₀)/l` from `l²/l₀²` without a square root
//! ([`stretch_correction`]).

use glam::Vec3A;

/// One stretch (distance) constraint as the sweep needs it: the ends `i → j`, `1/l₀²`, and the
/// share of the correction each end takes (`wᵢ/(wᵢ + wⱼ + α/h²)`, the same for `j`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct DistanceConstraint {
    pub i: u32,
    pub j: u32,
    pub inv_rest2: f32,
    pub ci: f32,
    pub cj: f32,
}

/// Four constraints lane by lane. Lanes past a short quad's last constraint repeat its first
/// vertex at both ends with zero shares: they move nothing, and are stored before the real lanes.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
pub(super) struct EdgeQuad {
    i: [u32; 4],
    j: [u32; 4],
    inv_rest2: [f32; 4],
    ci: [f32; 4],
    cj: [f32; 4],
}

/// A sweep's constraints packed into quads of vertex-disjoint neighbours, in sweep order.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct EdgeQuads {
    quads: Vec<EdgeQuad>,
    /// The index of each quad's first constraint, and the number of constraints at the end.
    starts: Vec<u32>,
}

impl EdgeQuads {
    /// Packs `constraints`, in order, into quads: a quad takes the next constraint unless it is
    /// full or already holds one of that constraint's vertices. Interleaved constraints fill
    /// almost every quad.
    pub fn pack(constraints: &[DistanceConstraint]) -> EdgeQuads {
        let mut quads = Vec::with_capacity(constraints.len() / 4 + 1);
        let mut starts = Vec::with_capacity(constraints.len() / 4 + 2);
        let mut lanes: Vec<DistanceConstraint> = Vec::with_capacity(4);
        let shares_a_vertex = |lanes: &[DistanceConstraint], c: &DistanceConstraint| {
            lanes
                .iter()
                .any(|l| l.i == c.i || l.i == c.j || l.j == c.i || l.j == c.j)
        };
        for (k, c) in constraints.iter().enumerate() {
            if lanes.len() == 4 || shares_a_vertex(&lanes, c) {
                quads.push(quad(&lanes));
                lanes.clear();
            }
            if lanes.is_empty() {
                starts.push(k as u32);
            }
            lanes.push(*c);
        }
        if !lanes.is_empty() {
            quads.push(quad(&lanes));
        }
        starts.push(constraints.len() as u32);
        EdgeQuads { quads, starts }
    }
}

/// Packs one to four vertex-disjoint constraints; the lanes past them move nothing.
fn quad(lanes: &[DistanceConstraint]) -> EdgeQuad {
    let first = lanes[0];
    let idle = DistanceConstraint {
        i: first.i,
        j: first.i,
        inv_rest2: 0.0,
        ci: 0.0,
        cj: 0.0,
    };
    let lane = |l: usize| lanes.get(l).copied().unwrap_or(idle);
    EdgeQuad {
        i: [0, 1, 2, 3].map(|l| lane(l).i),
        j: [0, 1, 2, 3].map(|l| lane(l).j),
        inv_rest2: [0, 1, 2, 3].map(|l| lane(l).inv_rest2),
        ci: [0, 1, 2, 3].map(|l| lane(l).ci),
        cj: [0, 1, 2, 3].map(|l| lane(l).cj),
    }
}

/// The distance constraint's correction `(l − l₀)/l` from `u = l²/l₀²`, without a square root:
/// `1 − u^(−1/2)` with `u^(−1/2)` replaced by its [1/1] Padé approximant about `u = 1`,
/// `(3 + u)/(1 + 3u)`, which gives `2(u − 1)/(1 + 3u)`.
///
/// Exact at rest (`u = 1`) and to second order in the strain, so the projection converges to the
/// same lengths; at larger strains it corrects slightly less than the exact projection (10 %
/// stretch: 0.0907 for 0.0909; 100 %: 0.46 for 0.5; 50 % compression: −0.86 for −1) and stays
/// between −2 and 2/3 however far the edge is pulled or squashed, so a projection never
/// overshoots or flips an edge (and an edge squashed to nothing, where the exact form is
/// unbounded, is left alone). The square root and division of the exact form took about an eighth
/// of each sweep.
#[inline]
pub(super) fn stretch_correction(u: f32) -> f32 {
    2.0 * (u - 1.0) / (1.0 + 3.0 * u)
}

/// One Gauss–Seidel sweep over the quads, in order: each edge's ends move by `∓ d·c·s` (`d` the
/// edge vector, `s` [`stretch_correction`], times `compression` for a compressed edge).
///
/// Panics if a quad names a vertex outside `x` (the solver builds both from the same mesh).
pub(super) fn sweep(x: &mut [Vec3A], quads: &EdgeQuads, compression: f32) {
    #[cfg(target_arch = "x86_64")]
    sse2::sweep(x, &quads.quads, compression);
    #[cfg(not(target_arch = "x86_64"))]
    sweep_lanes(x, &quads.quads, compression);
}

/// Appends to `out`, in order, the indices (into the packed constraints) of the edges whose
/// squared length over their squared rest length is above `hi2` or below `lo2`: the strain
/// limit's first look at every edge.
pub(super) fn outside_bounds(
    x: &[Vec3A],
    quads: &EdgeQuads,
    lo2: f32,
    hi2: f32,
    out: &mut Vec<u32>,
) {
    #[cfg(target_arch = "x86_64")]
    sse2::outside_bounds(x, quads, lo2, hi2, out);
    #[cfg(not(target_arch = "x86_64"))]
    outside_bounds_lanes(x, quads, lo2, hi2, out);
}

/// [`outside_bounds`] one lane at a time.
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
fn outside_bounds_lanes(x: &[Vec3A], quads: &EdgeQuads, lo2: f32, hi2: f32, out: &mut Vec<u32>) {
    for (q, start) in quads.quads.iter().zip(quads.starts.windows(2)) {
        for l in 0..(start[1] - start[0]) as usize {
            let d = x[q.j[l] as usize] - x[q.i[l] as usize];
            let r2 = d.length_squared() * q.inv_rest2[l];
            if r2 > hi2 || r2 < lo2 {
                out.push(start[0] + l as u32);
            }
        }
    }
}

/// [`sweep`] one lane at a time, the idle lanes first: the portable path, and the reference the
/// SSE2 kernel is tested against.
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
fn sweep_lanes(x: &mut [Vec3A], quads: &[EdgeQuad], compression: f32) {
    for q in quads {
        for l in (0..4).rev() {
            let (i, j) = (q.i[l] as usize, q.j[l] as usize);
            let d = x[j] - x[i];
            let mut s = stretch_correction(d.length_squared() * q.inv_rest2[l]);
            if s < 0.0 {
                s *= compression;
            }
            x[i] += d * (q.ci[l] * s);
            x[j] -= d * (q.cj[l] * s);
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod sse2 {
    //! The quad kernel on SSE2 (part of every x86-64 processor, so no run-time detection).
    use std::arch::x86_64::*;

    use glam::Vec3A;

    use super::{EdgeQuad, EdgeQuads};

    /// Four points' x, y and z as rows (`_MM_TRANSPOSE4_PS` without the fourth row).
    #[inline]
    #[target_feature(enable = "sse2")]
    fn rows(p: [__m128; 4]) -> [__m128; 3] {
        let t0 = _mm_unpacklo_ps(p[0], p[1]); // x0 x1 y0 y1
        let t1 = _mm_unpacklo_ps(p[2], p[3]); // x2 x3 y2 y3
        let t2 = _mm_unpackhi_ps(p[0], p[1]); // z0 z1 w0 w1
        let t3 = _mm_unpackhi_ps(p[2], p[3]); // z2 z3 w2 w3
        [
            _mm_movelh_ps(t0, t1),
            _mm_movehl_ps(t1, t0),
            _mm_movelh_ps(t2, t3),
        ]
    }

    /// The inverse of [`rows`]: four points (w = 0) from x, y and z rows.
    #[inline]
    #[target_feature(enable = "sse2")]
    fn points(r: [__m128; 3]) -> [__m128; 4] {
        let zero = _mm_setzero_ps();
        let t0 = _mm_unpacklo_ps(r[0], r[1]); // x0 y0 x1 y1
        let t1 = _mm_unpacklo_ps(r[2], zero); // z0 0 z1 0
        let t2 = _mm_unpackhi_ps(r[0], r[1]); // x2 y2 x3 y3
        let t3 = _mm_unpackhi_ps(r[2], zero); // z2 0 z3 0
        [
            _mm_movelh_ps(t0, t1),
            _mm_movehl_ps(t1, t0),
            _mm_movelh_ps(t2, t3),
            _mm_movehl_ps(t3, t2),
        ]
    }

    #[inline]
    #[target_feature(enable = "sse2")]
    fn load(a: &[f32; 4]) -> __m128 {
        _mm_set_ps(a[3], a[2], a[1], a[0])
    }

    pub(super) fn sweep(x: &mut [Vec3A], quads: &[EdgeQuad], compression: f32) {
        // SAFETY: SSE2 is part of the x86-64 baseline: every x86-64 processor has it.
        unsafe { sweep_sse2(x, quads, compression) }
    }

    pub(super) fn outside_bounds(
        x: &[Vec3A],
        quads: &EdgeQuads,
        lo2: f32,
        hi2: f32,
        out: &mut Vec<u32>,
    ) {
        // SAFETY: as in `sweep`.
        unsafe { outside_bounds_sse2(x, quads, lo2, hi2, out) }
    }

    #[target_feature(enable = "sse2")]
    fn outside_bounds_sse2(x: &[Vec3A], quads: &EdgeQuads, lo2: f32, hi2: f32, out: &mut Vec<u32>) {
        let (lo2, hi2) = (_mm_set1_ps(lo2), _mm_set1_ps(hi2));
        for (q, start) in quads.quads.iter().zip(quads.starts.windows(2)) {
            let [ix, iy, iz] = rows(q.i.map(|v| __m128::from(x[v as usize])));
            let [jx, jy, jz] = rows(q.j.map(|v| __m128::from(x[v as usize])));
            let r2 = _mm_mul_ps(
                squared_lengths(_mm_sub_ps(jx, ix), _mm_sub_ps(jy, iy), _mm_sub_ps(jz, iz)),
                load(&q.inv_rest2),
            );
            let out_of_bounds = _mm_or_ps(_mm_cmpgt_ps(r2, hi2), _mm_cmplt_ps(r2, lo2));
            // Only the quad's real lanes (the idle ones have zero length).
            let lanes = (1 << (start[1] - start[0])) - 1;
            let mut bits = _mm_movemask_ps(out_of_bounds) & lanes;
            while bits != 0 {
                out.push(start[0] + bits.trailing_zeros());
                bits &= bits - 1;
            }
        }
    }

    /// `(dx² + dy²) + dz²`, as glam's `Vec3A::length_squared` adds them.
    #[inline]
    #[target_feature(enable = "sse2")]
    fn squared_lengths(dx: __m128, dy: __m128, dz: __m128) -> __m128 {
        _mm_add_ps(
            _mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)),
            _mm_mul_ps(dz, dz),
        )
    }

    #[target_feature(enable = "sse2")]
    fn sweep_sse2(x: &mut [Vec3A], quads: &[EdgeQuad], compression: f32) {
        let one = _mm_set1_ps(1.0);
        let two = _mm_set1_ps(2.0);
        let three = _mm_set1_ps(3.0);
        let zero = _mm_setzero_ps();
        let squash = _mm_set1_ps(compression);
        for q in quads {
            let pi = q.i.map(|v| __m128::from(x[v as usize]));
            let pj = q.j.map(|v| __m128::from(x[v as usize]));
            let [ix, iy, iz] = rows(pi);
            let [jx, jy, jz] = rows(pj);
            let (dx, dy, dz) = (_mm_sub_ps(jx, ix), _mm_sub_ps(jy, iy), _mm_sub_ps(jz, iz));
            let u = _mm_mul_ps(squared_lengths(dx, dy, dz), load(&q.inv_rest2));
            let s = _mm_div_ps(
                _mm_mul_ps(two, _mm_sub_ps(u, one)),
                _mm_add_ps(one, _mm_mul_ps(three, u)),
            );
            let squashed = _mm_cmplt_ps(s, zero);
            let s = _mm_or_ps(
                _mm_and_ps(squashed, _mm_mul_ps(s, squash)),
                _mm_andnot_ps(squashed, s),
            );
            let si = _mm_mul_ps(load(&q.ci), s);
            let sj = _mm_mul_ps(load(&q.cj), s);
            let ni = points([
                _mm_add_ps(ix, _mm_mul_ps(dx, si)),
                _mm_add_ps(iy, _mm_mul_ps(dy, si)),
                _mm_add_ps(iz, _mm_mul_ps(dz, si)),
            ]);
            let nj = points([
                _mm_sub_ps(jx, _mm_mul_ps(dx, sj)),
                _mm_sub_ps(jy, _mm_mul_ps(dy, sj)),
                _mm_sub_ps(jz, _mm_mul_ps(dz, sj)),
            ]);
            // Idle lanes (past a short quad's end) rewrite lane 0's first vertex unchanged, so
            // they are stored first and lane 0 last.
            for l in (0..4).rev() {
                x[q.i[l] as usize] = Vec3A::from(ni[l]);
                x[q.j[l] as usize] = Vec3A::from(nj[l]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic scatter of points and edges (a triangle strip and its diagonals).
    fn strip(n: usize) -> (Vec<Vec3A>, Vec<DistanceConstraint>) {
        let mut state = 0x2545_f491_u32;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            (state as f32 / u32::MAX as f32) - 0.5
        };
        let x: Vec<Vec3A> = (0..n)
            .map(|k| Vec3A::new(k as f32 + next(), next() * 3.0, next()))
            .collect();
        let mut constraints = Vec::new();
        for k in 0..n {
            for step in [1, 2, 3] {
                if k + step < n {
                    let rest = step as f32 * (0.8 + 0.4 * (next() + 0.5));
                    let (wi, wj) = (if k % 7 == 0 { 0.0 } else { 1.0 }, 1.0);
                    constraints.push(DistanceConstraint {
                        i: k as u32,
                        j: (k + step) as u32,
                        inv_rest2: 1.0 / (rest * rest),
                        ci: wi / (wi + wj + 0.01),
                        cj: wj / (wi + wj + 0.01),
                    });
                }
            }
        }
        (x, constraints)
    }

    /// The plain sweep: one constraint after another.
    fn sweep_one_by_one(x: &mut [Vec3A], constraints: &[DistanceConstraint], compression: f32) {
        for c in constraints {
            let (i, j) = (c.i as usize, c.j as usize);
            let d = x[j] - x[i];
            let mut s = stretch_correction(d.length_squared() * c.inv_rest2);
            if s < 0.0 {
                s *= compression;
            }
            x[i] += d * (c.ci * s);
            x[j] -= d * (c.cj * s);
        }
    }

    #[test]
    fn the_square_root_free_correction_matches_the_exact_one_near_rest_and_never_overshoots() {
        assert_eq!(stretch_correction(1.0), 0.0);
        for strain in [-0.5f32, -0.1, -0.02, 0.005, 0.02, 0.1, 0.5, 1.0, 10.0] {
            let l = 1.0 + strain;
            let exact = (l - 1.0) / l;
            let approx = stretch_correction(l * l);
            // Same sign, never more than the exact correction, third-order close.
            assert!(approx * exact > 0.0, "{strain}");
            assert!(
                approx.abs() <= exact.abs() + 1e-7,
                "{strain}: {approx} vs {exact}"
            );
            if strain.abs() <= 0.1 {
                assert!(
                    (approx - exact).abs() <= 0.5 * strain.abs().powi(3) + 1e-7,
                    "{strain}"
                );
            }
            assert!(approx > -2.0 && approx < 2.0 / 3.0);
        }
    }

    #[test]
    fn the_edges_outside_the_bounds_are_found_in_order() {
        let (mut x, constraints) = strip(61);
        let quads = EdgeQuads::pack(&constraints);
        sweep(&mut x, &quads, 0.8);
        let (lo2, hi2) = (0.97f32 * 0.97, 1.03f32 * 1.03);
        let expected: Vec<u32> = constraints
            .iter()
            .enumerate()
            .filter(|(_, c)| {
                let r2 = (x[c.j as usize] - x[c.i as usize]).length_squared() * c.inv_rest2;
                r2 > hi2 || r2 < lo2
            })
            .map(|(k, _)| k as u32)
            .collect();
        assert!(!expected.is_empty() && expected.len() < constraints.len());
        let (mut found, mut by_lane) = (Vec::new(), Vec::new());
        outside_bounds(&x, &quads, lo2, hi2, &mut found);
        outside_bounds_lanes(&x, &quads, lo2, hi2, &mut by_lane);
        assert_eq!(found, expected);
        assert_eq!(by_lane, expected);
    }

    #[test]
    fn constraints_in_a_quad_share_no_vertex_and_keep_their_order() {
        // 0–1, 2–3, 1–2 (shares with both), 4–5: the third starts a new quad.
        let c = |i, j| DistanceConstraint {
            i,
            j,
            inv_rest2: 1.0,
            ci: 0.5,
            cj: 0.5,
        };
        let quads = EdgeQuads::pack(&[c(0, 1), c(2, 3), c(1, 2), c(4, 5)]);
        assert_eq!(quads.quads.len(), 2);
        assert_eq!(quads.quads[0].i[..2], [0, 2]);
        assert_eq!(quads.quads[0].ci, [0.5, 0.5, 0.0, 0.0]);
        assert_eq!(quads.quads[1].i[..2], [1, 4]);
        // The idle lanes repeat lane 0's first vertex at both ends.
        assert_eq!(quads.quads[1].i[2..], [1, 1]);
        assert_eq!(quads.quads[1].j[2..], [1, 1]);
    }

    #[test]
    fn a_stretched_edge_between_two_free_ends_is_pulled_in_from_both() {
        // Rest length 1, length 2: u = 4, s = 2·3/13; each end moves d·½·s toward the other.
        let mut x = vec![Vec3A::ZERO, Vec3A::new(2.0, 0.0, 0.0)];
        let c = DistanceConstraint {
            i: 0,
            j: 1,
            inv_rest2: 1.0,
            ci: 0.5,
            cj: 0.5,
        };
        sweep(&mut x, &EdgeQuads::pack(&[c]), 1.0);
        let moved = 2.0 * 0.5 * (6.0 / 13.0);
        assert!((x[0].x - moved).abs() < 1e-6, "{:?}", x[0]);
        assert!((x[1].x - (2.0 - moved)).abs() < 1e-6, "{:?}", x[1]);
        assert_eq!((x[0].y, x[0].z, x[1].y, x[1].z), (0.0, 0.0, 0.0, 0.0));
    }

    #[test]
    fn the_quad_sweep_gives_the_same_positions_as_one_constraint_after_another() {
        for compression in [1.0, 0.8, 0.0] {
            let (start, constraints) = strip(97);
            let quads = EdgeQuads::pack(&constraints);
            assert!(quads.quads.len() < constraints.len(), "nothing was packed");
            let (mut plain, mut lanes, mut packed) = (start.clone(), start.clone(), start);
            for _ in 0..5 {
                sweep_one_by_one(&mut plain, &constraints, compression);
                sweep_lanes(&mut lanes, &quads.quads, compression);
                sweep(&mut packed, &quads, compression);
            }
            for k in 0..plain.len() {
                // Bit for bit: the same arithmetic on each edge, in an order that cannot matter.
                assert_eq!(plain[k].to_array(), lanes[k].to_array(), "vertex {k}");
                assert_eq!(plain[k].to_array(), packed[k].to_array(), "vertex {k}");
            }
        }
    }
}
