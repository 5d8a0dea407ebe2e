//! The stretch constraints' Gauss–Seidel sweep, eight edges at a time.
//!
//! The solver hands this module its stretch constraints in sweep order (anchors outward,
//! interleaved so that neighbours share no vertex) and gets back [`EdgeBlocks`]: runs of up to
//! eight consecutive constraints that share no vertex, packed lane by lane. [`sweep`] projects
//! one block per step: the end points are loaded, transposed to x, y and z rows, projected in all
//! lanes at once and stored back. Because the edges of a block share no vertex, this is the same
//! computation as projecting them one after another, in the same arithmetic per edge: the
//! positions are bit-identical to a scalar sweep in the same order (a test checks it), only
//! cheaper. The sweeps were about half of the solver's time, each projection a dot product across
//! one `Vec3A`'s lanes and a division for one edge, one waiting for the next.
//!
//! On x86-64 a block is one pass of 8-lane AVX where the processor has it (checked at run time)
//! and two interleaved 4-lane SSE2 passes otherwise (SSE2 is part of every x86-64 processor);
//! elsewhere the lanes are projected one by one. A block of eight rather than four because one
//! block's chain of dependent operations (loads, transposes, the division, stores) is what
//! limits the sweep, not the count of instructions: with blocks of four in SSE2 the sweep took
//! about 1.45× less time than edge by edge (from `perf`'s sample shares) and most of its samples
//! sat on the instruction after the division. Blocks of eight made the solver's whole run about
//! 8 % faster again (`cloth_quality`'s kick T-shirt at 4,000 vertices, five alternated runs).
//!
//! Each projection computes its correction `(l − l₀)/l` from `l²/l₀²` without a square root
//! ([`stretch_correction`]).

use glam::Vec3A;

/// Constraints per block.
const LANES: usize = 8;

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

/// Up to [`LANES`] vertex-disjoint constraints lane by lane. The lanes past a short block's last
/// constraint repeat its first vertex at both ends with zero shares; they are computed and never
/// stored.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
struct EdgeBlock {
    i: [u32; LANES],
    j: [u32; LANES],
    inv_rest2: [f32; LANES],
    ci: [f32; LANES],
    cj: [f32; LANES],
}

/// A sweep's constraints packed into blocks of vertex-disjoint neighbours, in sweep order.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct EdgeBlocks {
    blocks: Vec<EdgeBlock>,
    /// The index of each block's first constraint, and the number of constraints at the end.
    starts: Vec<u32>,
}

impl EdgeBlocks {
    /// Packs `constraints`, in order, into blocks: a block takes the next constraint unless it is
    /// full or already holds one of that constraint's vertices. Interleaved constraints fill
    /// most blocks.
    pub fn pack(constraints: &[DistanceConstraint]) -> EdgeBlocks {
        let mut blocks = Vec::with_capacity(constraints.len() / LANES + 1);
        let mut starts = Vec::with_capacity(constraints.len() / LANES + 2);
        let mut lanes: Vec<DistanceConstraint> = Vec::with_capacity(LANES);
        let shares_a_vertex = |lanes: &[DistanceConstraint], c: &DistanceConstraint| {
            lanes
                .iter()
                .any(|l| l.i == c.i || l.i == c.j || l.j == c.i || l.j == c.j)
        };
        for (k, c) in constraints.iter().enumerate() {
            if lanes.len() == LANES || shares_a_vertex(&lanes, c) {
                blocks.push(block(&lanes));
                lanes.clear();
            }
            if lanes.is_empty() {
                starts.push(k as u32);
            }
            lanes.push(*c);
        }
        if !lanes.is_empty() {
            blocks.push(block(&lanes));
        }
        starts.push(constraints.len() as u32);
        EdgeBlocks { blocks, starts }
    }

    /// Each block with its first constraint's index and its count of constraints.
    fn iter(&self) -> impl Iterator<Item = (&EdgeBlock, u32, usize)> {
        self.blocks
            .iter()
            .zip(self.starts.windows(2))
            .map(|(b, s)| (b, s[0], (s[1] - s[0]) as usize))
    }
}

/// Packs one to [`LANES`] vertex-disjoint constraints.
fn block(lanes: &[DistanceConstraint]) -> EdgeBlock {
    let first = lanes[0];
    let idle = DistanceConstraint {
        i: first.i,
        j: first.i,
        inv_rest2: 0.0,
        ci: 0.0,
        cj: 0.0,
    };
    let lane = |l: usize| lanes.get(l).copied().unwrap_or(idle);
    EdgeBlock {
        i: std::array::from_fn(|l| lane(l).i),
        j: std::array::from_fn(|l| lane(l).j),
        inv_rest2: std::array::from_fn(|l| lane(l).inv_rest2),
        ci: std::array::from_fn(|l| lane(l).ci),
        cj: std::array::from_fn(|l| lane(l).cj),
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

/// One Gauss–Seidel sweep over the blocks, in order: each edge's ends move by `∓ d·c·s` (`d` the
/// edge vector, `s` [`stretch_correction`], times `compression` for a compressed edge).
///
/// Panics if a block names a vertex outside `x` (the solver builds both from the same mesh).
pub(super) fn sweep(x: &mut [Vec3A], blocks: &EdgeBlocks, compression: f32) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx") {
            // SAFETY: the processor has AVX (checked just above).
            unsafe { x86::sweep_avx(x, blocks, compression) }
        } else {
            // SAFETY: SSE2 is part of the x86-64 baseline: every x86-64 processor has it.
            unsafe { x86::sweep_sse2(x, blocks, compression) }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    sweep_lanes(x, blocks, compression);
}

/// Appends to `out`, in order, the indices (into the packed constraints) of the edges whose
/// squared length over their squared rest length is above `hi2` or below `lo2`: the strain
/// limit's first look at every edge.
pub(super) fn outside_bounds(
    x: &[Vec3A],
    blocks: &EdgeBlocks,
    lo2: f32,
    hi2: f32,
    out: &mut Vec<u32>,
) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: SSE2 is part of the x86-64 baseline.
    unsafe {
        x86::outside_bounds_sse2(x, blocks, lo2, hi2, out)
    }
    #[cfg(not(target_arch = "x86_64"))]
    outside_bounds_lanes(x, blocks, lo2, hi2, out);
}

/// [`outside_bounds`] one lane at a time.
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
fn outside_bounds_lanes(x: &[Vec3A], blocks: &EdgeBlocks, lo2: f32, hi2: f32, out: &mut Vec<u32>) {
    for (b, start, count) in blocks.iter() {
        for l in 0..count {
            let d = x[b.j[l] as usize] - x[b.i[l] as usize];
            let r2 = d.length_squared() * b.inv_rest2[l];
            if r2 > hi2 || r2 < lo2 {
                out.push(start + l as u32);
            }
        }
    }
}

/// [`sweep`] one lane at a time: the portable path (tested beside the SIMD kernels).
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
fn sweep_lanes(x: &mut [Vec3A], blocks: &EdgeBlocks, compression: f32) {
    for (b, _, count) in blocks.iter() {
        for l in 0..count {
            let (i, j) = (b.i[l] as usize, b.j[l] as usize);
            let d = x[j] - x[i];
            let mut s = stretch_correction(d.length_squared() * b.inv_rest2[l]);
            if s < 0.0 {
                s *= compression;
            }
            x[i] += d * (b.ci[l] * s);
            x[j] -= d * (b.cj[l] * s);
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    //! The block kernels: 8-lane AVX, and 4-lane SSE2 twice. The 256-bit unpacks and shuffles
    //! work within each 128-bit half, so the AVX kernel is the SSE2 one on two quads at once:
    //! lanes 0–3 in the low halves, 4–7 in the high ones.
    use std::arch::x86_64::*;

    use glam::Vec3A;

    use super::{EdgeBlocks, LANES};

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

    /// Lanes `from..from + 4` of `a`.
    #[inline]
    #[target_feature(enable = "sse2")]
    fn load4(a: &[f32; LANES], from: usize) -> __m128 {
        _mm_set_ps(a[from + 3], a[from + 2], a[from + 1], a[from])
    }

    /// `(dx² + dy²) + dz²`, as glam's `Vec3A::length_squared` adds them.
    #[inline]
    #[target_feature(enable = "sse2")]
    fn squared_lengths(d: [__m128; 3]) -> __m128 {
        _mm_add_ps(
            _mm_add_ps(_mm_mul_ps(d[0], d[0]), _mm_mul_ps(d[1], d[1])),
            _mm_mul_ps(d[2], d[2]),
        )
    }

    /// The projection of four edges whose ends are the rows `i` and `j`: their new ends.
    #[inline]
    #[target_feature(enable = "sse2")]
    fn project4(
        i: [__m128; 3],
        j: [__m128; 3],
        inv_rest2: __m128,
        ci: __m128,
        cj: __m128,
        compression: __m128,
    ) -> ([__m128; 4], [__m128; 4]) {
        let one = _mm_set1_ps(1.0);
        let d = [0, 1, 2].map(|k| _mm_sub_ps(j[k], i[k]));
        let u = _mm_mul_ps(squared_lengths(d), inv_rest2);
        // 2(u − 1)/(1 + 3u), as `stretch_correction` computes it.
        let s = _mm_div_ps(
            _mm_mul_ps(_mm_set1_ps(2.0), _mm_sub_ps(u, one)),
            _mm_add_ps(one, _mm_mul_ps(_mm_set1_ps(3.0), u)),
        );
        let squashed = _mm_cmplt_ps(s, _mm_setzero_ps());
        let s = _mm_or_ps(
            _mm_and_ps(squashed, _mm_mul_ps(s, compression)),
            _mm_andnot_ps(squashed, s),
        );
        let (si, sj) = (_mm_mul_ps(ci, s), _mm_mul_ps(cj, s));
        (
            points([0, 1, 2].map(|k| _mm_add_ps(i[k], _mm_mul_ps(d[k], si)))),
            points([0, 1, 2].map(|k| _mm_sub_ps(j[k], _mm_mul_ps(d[k], sj)))),
        )
    }

    /// [`super::sweep`] on SSE2: a block's two quads loaded, projected, then stored.
    #[target_feature(enable = "sse2")]
    pub(super) fn sweep_sse2(x: &mut [Vec3A], blocks: &EdgeBlocks, compression: f32) {
        let compression = _mm_set1_ps(compression);
        for (b, _, count) in blocks.iter() {
            let ends = |ends: &[u32; LANES], from: usize| {
                rows(std::array::from_fn(|l| {
                    __m128::from(x[ends[from + l] as usize])
                }))
            };
            let quad = |from: usize| {
                project4(
                    ends(&b.i, from),
                    ends(&b.j, from),
                    load4(&b.inv_rest2, from),
                    load4(&b.ci, from),
                    load4(&b.cj, from),
                    compression,
                )
            };
            let (low, high) = (quad(0), quad(4));
            for l in 0..count {
                let (new_i, new_j) = if l < 4 { &low } else { &high };
                x[b.i[l] as usize] = Vec3A::from(new_i[l % 4]);
                x[b.j[l] as usize] = Vec3A::from(new_j[l % 4]);
            }
        }
    }

    /// [`rows`] for eight points, lanes 0–3 in the low halves and 4–7 in the high ones.
    #[inline]
    #[target_feature(enable = "avx")]
    fn rows8(p: [__m256; 4]) -> [__m256; 3] {
        let t0 = _mm256_unpacklo_ps(p[0], p[1]);
        let t1 = _mm256_unpacklo_ps(p[2], p[3]);
        let t2 = _mm256_unpackhi_ps(p[0], p[1]);
        let t3 = _mm256_unpackhi_ps(p[2], p[3]);
        [
            _mm256_shuffle_ps::<0b01_00_01_00>(t0, t1),
            _mm256_shuffle_ps::<0b11_10_11_10>(t0, t1),
            _mm256_shuffle_ps::<0b01_00_01_00>(t2, t3),
        ]
    }

    /// The inverse of [`rows8`].
    #[inline]
    #[target_feature(enable = "avx")]
    fn points8(r: [__m256; 3]) -> [__m256; 4] {
        let zero = _mm256_setzero_ps();
        let t0 = _mm256_unpacklo_ps(r[0], r[1]);
        let t1 = _mm256_unpacklo_ps(r[2], zero);
        let t2 = _mm256_unpackhi_ps(r[0], r[1]);
        let t3 = _mm256_unpackhi_ps(r[2], zero);
        [
            _mm256_shuffle_ps::<0b01_00_01_00>(t0, t1),
            _mm256_shuffle_ps::<0b11_10_11_10>(t0, t1),
            _mm256_shuffle_ps::<0b01_00_01_00>(t2, t3),
            _mm256_shuffle_ps::<0b11_10_11_10>(t2, t3),
        ]
    }

    #[inline]
    #[target_feature(enable = "avx")]
    fn load8(a: &[f32; LANES]) -> __m256 {
        _mm256_set_ps(a[7], a[6], a[5], a[4], a[3], a[2], a[1], a[0])
    }

    /// [`super::sweep`] on AVX: one block per pass.
    #[target_feature(enable = "avx")]
    pub(super) fn sweep_avx(x: &mut [Vec3A], blocks: &EdgeBlocks, compression: f32) {
        let one = _mm256_set1_ps(1.0);
        let compression = _mm256_set1_ps(compression);
        for (b, _, count) in blocks.iter() {
            // Point k and point k + 4 in one register, for k = 0..4.
            let ends = |ends: &[u32; LANES]| {
                rows8(std::array::from_fn(|k| {
                    _mm256_set_m128(
                        __m128::from(x[ends[k + 4] as usize]),
                        __m128::from(x[ends[k] as usize]),
                    )
                }))
            };
            let (i, j) = (ends(&b.i), ends(&b.j));
            let d = [0, 1, 2].map(|k| _mm256_sub_ps(j[k], i[k]));
            // (dx² + dy²) + dz², then 2(u − 1)/(1 + 3u): the arithmetic of the scalar sweep.
            let l2 = _mm256_add_ps(
                _mm256_add_ps(_mm256_mul_ps(d[0], d[0]), _mm256_mul_ps(d[1], d[1])),
                _mm256_mul_ps(d[2], d[2]),
            );
            let u = _mm256_mul_ps(l2, load8(&b.inv_rest2));
            let s = _mm256_div_ps(
                _mm256_mul_ps(_mm256_set1_ps(2.0), _mm256_sub_ps(u, one)),
                _mm256_add_ps(one, _mm256_mul_ps(_mm256_set1_ps(3.0), u)),
            );
            let squashed = _mm256_cmp_ps::<_CMP_LT_OQ>(s, _mm256_setzero_ps());
            let s = _mm256_blendv_ps(s, _mm256_mul_ps(s, compression), squashed);
            let (si, sj) = (
                _mm256_mul_ps(load8(&b.ci), s),
                _mm256_mul_ps(load8(&b.cj), s),
            );
            let new_i = points8([0, 1, 2].map(|k| _mm256_add_ps(i[k], _mm256_mul_ps(d[k], si))));
            let new_j = points8([0, 1, 2].map(|k| _mm256_sub_ps(j[k], _mm256_mul_ps(d[k], sj))));
            for l in 0..count {
                let (k, high) = (l % 4, l >= 4);
                let half = |p: __m256| {
                    if high {
                        _mm256_extractf128_ps::<1>(p)
                    } else {
                        _mm256_castps256_ps128(p)
                    }
                };
                x[b.i[l] as usize] = Vec3A::from(half(new_i[k]));
                x[b.j[l] as usize] = Vec3A::from(half(new_j[k]));
            }
        }
    }

    /// [`super::outside_bounds`] on SSE2.
    #[target_feature(enable = "sse2")]
    pub(super) fn outside_bounds_sse2(
        x: &[Vec3A],
        blocks: &EdgeBlocks,
        lo2: f32,
        hi2: f32,
        out: &mut Vec<u32>,
    ) {
        let (lo2, hi2) = (_mm_set1_ps(lo2), _mm_set1_ps(hi2));
        for (b, start, count) in blocks.iter() {
            let mut bits = 0;
            for from in [0, 4] {
                let ends = |ends: &[u32; LANES]| {
                    rows(std::array::from_fn(|l| {
                        __m128::from(x[ends[from + l] as usize])
                    }))
                };
                let (i, j) = (ends(&b.i), ends(&b.j));
                let d = [0, 1, 2].map(|k| _mm_sub_ps(j[k], i[k]));
                let r2 = _mm_mul_ps(squared_lengths(d), load4(&b.inv_rest2, from));
                let outside = _mm_or_ps(_mm_cmpgt_ps(r2, hi2), _mm_cmplt_ps(r2, lo2));
                bits |= _mm_movemask_ps(outside) << from;
            }
            // Only the block's constraints (the idle lanes have zero length).
            bits &= (1 << count) - 1;
            while bits != 0 {
                out.push(start + bits.trailing_zeros());
                bits &= bits - 1;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic scatter of points and edges `k → k + step` for steps 1 to 3: first in runs
    /// that share no vertex (`k` in one residue class modulo `2·step`: full blocks, and short ones
    /// where a run ends), then again for the first 20 points in mesh order (blocks of one or two).
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
        let mut edge = |k: usize, step: usize| {
            let rest = step as f32 * (0.8 + 0.4 * (next() + 0.5));
            let (wi, wj) = (if k.is_multiple_of(7) { 0.0 } else { 1.0 }, 1.0);
            DistanceConstraint {
                i: k as u32,
                j: (k + step) as u32,
                inv_rest2: 1.0 / (rest * rest),
                ci: wi / (wi + wj + 0.01),
                cj: wj / (wi + wj + 0.01),
            }
        };
        let mut constraints = Vec::new();
        for step in [1, 2, 3] {
            for phase in 0..2 * step {
                for k in (phase..n - step).step_by(2 * step) {
                    constraints.push(edge(k, step));
                }
            }
        }
        for k in 0..20 {
            for step in [1, 2, 3] {
                constraints.push(edge(k, step));
            }
        }
        (x, constraints)
    }

    type Kernel = fn(&mut [Vec3A], &EdgeBlocks, f32);

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
        let blocks = EdgeBlocks::pack(&constraints);
        sweep(&mut x, &blocks, 0.8);
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
        outside_bounds(&x, &blocks, lo2, hi2, &mut found);
        outside_bounds_lanes(&x, &blocks, lo2, hi2, &mut by_lane);
        assert_eq!(found, expected);
        assert_eq!(by_lane, expected);
    }

    #[test]
    fn constraints_in_a_block_share_no_vertex_and_keep_their_order() {
        // 0–1, 2–3, 1–2 (shares with both), then eight disjoint ones: the third starts a new
        // block, which takes seven more before it is full.
        let c = |i, j| DistanceConstraint {
            i,
            j,
            inv_rest2: 1.0,
            ci: 0.5,
            cj: 0.5,
        };
        let mut constraints = vec![c(0, 1), c(2, 3), c(1, 2)];
        constraints.extend((0..8).map(|k| c(10 + 2 * k, 11 + 2 * k)));
        let blocks = EdgeBlocks::pack(&constraints);
        assert_eq!(blocks.starts, [0, 2, 10, 11]);
        assert_eq!(blocks.blocks[0].i[..2], [0, 2]);
        assert_eq!(
            blocks.blocks[0].ci,
            [0.5, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        );
        assert_eq!(blocks.blocks[1].i, [1, 10, 12, 14, 16, 18, 20, 22]);
        assert_eq!(blocks.blocks[2].i[0], 24);
        // The idle lanes repeat lane 0's first vertex at both ends.
        assert_eq!(blocks.blocks[2].i[1..], [24; 7]);
        assert_eq!(blocks.blocks[2].j[1..], [24; 7]);
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
        sweep(&mut x, &EdgeBlocks::pack(&[c]), 1.0);
        let moved = 2.0 * 0.5 * (6.0 / 13.0);
        assert!((x[0].x - moved).abs() < 1e-6, "{:?}", x[0]);
        assert!((x[1].x - (2.0 - moved)).abs() < 1e-6, "{:?}", x[1]);
        assert_eq!((x[0].y, x[0].z, x[1].y, x[1].z), (0.0, 0.0, 0.0, 0.0));
    }

    #[test]
    fn the_block_sweeps_give_the_same_positions_as_one_constraint_after_another() {
        for compression in [1.0, 0.8, 0.0] {
            let (start, constraints) = strip(97);
            let blocks = EdgeBlocks::pack(&constraints);
            let full = blocks
                .starts
                .windows(2)
                .filter(|s| s[1] - s[0] == 8)
                .count();
            let short = blocks.starts.windows(2).filter(|s| s[1] - s[0] < 4).count();
            assert!(
                full > 20 && short > 20,
                "{full} full blocks, {short} short ones"
            );
            let mut plain = start.clone();
            // Each kernel this machine can run, and the dispatching `sweep`.
            let mut kernels: Vec<(&str, Kernel)> = vec![("lanes", sweep_lanes), ("sweep", sweep)];
            #[cfg(target_arch = "x86_64")]
            {
                // SAFETY: SSE2 is part of the x86-64 baseline.
                kernels.push(("sse2", |x, b, c| unsafe { x86::sweep_sse2(x, b, c) }));
                if std::arch::is_x86_feature_detected!("avx") {
                    // SAFETY: the processor has AVX (checked just above).
                    kernels.push(("avx", |x, b, c| unsafe { x86::sweep_avx(x, b, c) }));
                }
            }
            let mut results = vec![start; kernels.len()];
            for _ in 0..5 {
                sweep_one_by_one(&mut plain, &constraints, compression);
                for ((_, kernel), x) in kernels.iter().zip(&mut results) {
                    kernel(x, &blocks, compression);
                }
            }
            for ((name, _), x) in kernels.iter().zip(&results) {
                for k in 0..plain.len() {
                    // Bit for bit: the same arithmetic on each edge, in an order that cannot
                    // matter.
                    assert_eq!(plain[k].to_array(), x[k].to_array(), "{name}, vertex {k}");
                }
            }
        }
    }
}
