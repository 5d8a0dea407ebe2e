//! Relevance Vector Machine (RVM) regression from a per-frame image descriptor
//! to a pose vector.
//!
//! # What it does
//! Multi-output sparse Bayesian regression (Tipping 2001) over a Gaussian-kernel
//! basis `φ_j(x) = exp(−‖x − c_j‖² / (2w²))` plus a constant bias column. The
//! candidate centres `c_j` are training descriptors: a seeded k-means (k-means++
//! initialisation, Lloyd iterations) picks `S` centres and each is replaced by
//! the training descriptor nearest to it ([`candidate_centres`]). Training uses
//! the fast marginal-likelihood algorithm (Tipping & Faul 2003): one prior
//! precision α per basis function shared by all `V` outputs and one noise
//! precision β shared by all outputs, so each candidate's optimum is closed-form,
//! `α_i = s_i² / (Σ_v q_iv²/V − s_i)` (pruned when the denominator is ≤ 0). Every
//! iteration the add / re-estimate / delete step that most increases the
//! marginal likelihood is taken.
//!
//! # What it gives to the next stage
//! A [`Rvm`]: the surviving relevance vectors (a few hundred descriptors), their
//! weights and a bias row. [`Rvm::predict_into`] maps one descriptor (304 values)
//! to the posterior-mean pose vector (`3 + 6·J` sin/cos values) with no
//! allocation; pose decoding turns the sin/cos pairs back into angles.
//!
//! # Why it is written by hand
//! No maintained Rust crate implements the RVM (sparse Bayesian regression,
//! Tipping 2001) with the fast marginal-likelihood algorithm (Tipping & Faul
//! 2003). The small dense linear algebra it needs (Cholesky factorisation with
//! increasing jitter, triangular solves) is written here over row-major `f64`
//! slices; no matrix is ever explicitly inverted.
//!
//! # Numerical safeguards
//! Targets are centred (the means go back into the bias row); α is clamped to
//! `[1e-12, 1e12]`; a candidate whose basis column is (almost) in the span of the
//! active set is never added (this is what makes duplicated or nearly collinear
//! descriptors harmless); a failed Cholesky factorisation is retried with
//! increasing diagonal jitter; β is clamped to a range set by the target
//! variance; the bias basis is never deleted, so the model cannot become empty.
//!
//! # Cost
//! The `N × (S+1)` kernel matrix and `Φᵀy` are computed once in parallel. Per
//! iteration, the sparsity and quality factors of all candidates are updated
//! incrementally (Tipping & Faul, appendix) from the cached products `Φᵀφ_j` of
//! the active bases: `O(S·M + S·V)` plus one `O(N·S)` column `Φᵀφ_i` on an
//! addition. The Cholesky factor of the `M × M` posterior precision is grown by
//! one row on an addition and rank-one updated on a re-estimation (`O(M²)`);
//! it is refactorised (`O(M³/6)`) on a deletion, when an update loses positive
//! definiteness, and whenever β changes. Every `max(10, M/5)` iterations (every
//! iteration for the first ten, and before stopping) β is re-estimated and all
//! factors are recomputed from scratch (`O(S·M² + S·M·V)`), which also removes
//! the drift of the incremental updates. Measured (synthetic, 2 cores): N = 5000,
//! S = 1500, V = 105 trains in ~7 s when ~400 bases survive; a kernel so
//! narrow that most candidates survive (M ≈ 1260) takes ~23 s (5000 iterations).

// Negated comparisons (`!(x > 0.0)`) are deliberate: they also reject NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use rayon::prelude::*;

use crate::stats::squared_distance;

/// Smallest prior precision α.
pub const ALPHA_MIN: f64 = 1e-12;
/// Largest prior precision α (a basis at this value is effectively pruned).
pub const ALPHA_MAX: f64 = 1e12;
/// A candidate is only added when the part of its basis column not explained
/// by the active set (`S_i / (β φ_iᵀφ_i)`) exceeds this fraction.
const ALIGN_MIN: f64 = 1e-5;
/// β is re-estimated (and all factors recomputed) every `max(BETA_EVERY, M/5)`
/// iterations (`M` active bases) after the first ten, in which it is
/// re-estimated every iteration, and before stopping.
pub const BETA_EVERY: usize = 10;
/// Maximum Lloyd iterations of the candidate k-means.
const KMEANS_ITERATIONS: usize = 10;
/// Pairs sampled by [`median_distance`].
const MEDIAN_PAIRS: usize = 2000;

/// Options of [`Rvm::train`].
#[derive(Clone, Debug, PartialEq)]
pub struct TrainOptions {
    /// Number of candidate basis centres `S` (k-means centres). When it is at
    /// least the number of samples, every sample is a candidate.
    pub basis: usize,
    /// Kernel width `w` in descriptor units: `φ(x) = exp(−‖x − c‖² / (2w²))`.
    pub width: f32,
    /// Maximum number of add / re-estimate / delete iterations.
    pub max_iterations: usize,
    /// Convergence tolerance on `|Δ log α|` of the active bases.
    pub tolerance: f64,
    /// Seed of the candidate k-means.
    pub seed: u64,
}

impl TrainOptions {
    /// Options with `S = basis`, width `w`, 5000 iterations, tolerance 1e-3, seed 0.
    pub fn new(basis: usize, width: f32) -> Self {
        TrainOptions {
            basis,
            width,
            max_iterations: 5000,
            tolerance: 1e-3,
            seed: 0,
        }
    }
}

/// A trained RVM regressor.
#[derive(Clone, Debug, PartialEq)]
pub struct Rvm {
    /// Descriptor dimension.
    pub dim: usize,
    /// Number of outputs `V`.
    pub outputs: usize,
    /// Kernel width `w`.
    pub width: f32,
    /// Relevance vectors, `r × dim` row-major.
    pub relevance_vectors: Vec<f32>,
    /// Weights, `(r + 1) × outputs` row-major; the last row is the bias.
    pub weights: Vec<f32>,
    /// Noise variance σ² = 1/β (of the targets, shared by all outputs).
    pub noise: f32,
}

/// What training did.
#[derive(Clone, Debug, PartialEq)]
pub struct TrainReport {
    /// Candidate basis functions (excluding the bias).
    pub candidates: usize,
    /// Relevance vectors kept (excluding the bias).
    pub relevance_vectors: usize,
    /// Iterations run.
    pub iterations: usize,
    /// Final noise variance σ².
    pub noise: f64,
    /// Log marginal likelihood of the (centred) targets under the final model.
    pub log_marginal_likelihood: f64,
    /// Wall-clock training time, including candidate selection.
    pub seconds: f64,
}

/// Errors of [`Rvm::train`].
#[derive(thiserror::Error, Debug, Clone, PartialEq)]
pub enum RvmError {
    #[error("too few samples: {samples} (need at least {minimum})")]
    TooFewSamples { samples: usize, minimum: usize },
    #[error("{what} has {len} values but {rows} rows × {columns} columns are expected")]
    ShapeMismatch {
        what: &'static str,
        len: usize,
        rows: usize,
        columns: usize,
    },
    #[error("{what} is zero")]
    ZeroDimension { what: &'static str },
    #[error("non-finite {what} value at row {row}, column {column}")]
    NonFinite {
        what: &'static str,
        row: usize,
        column: usize,
    },
    #[error("invalid option {option}: {reason}")]
    InvalidOption {
        option: &'static str,
        reason: String,
    },
    #[error("numerical failure: {0}")]
    Numerical(String),
}

// ---------------------------------------------------------------------------
// Small dense kernels
// ---------------------------------------------------------------------------

#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0f64; 4];
    let ca = a.chunks_exact(4);
    let cb = b.chunks_exact(4);
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for k in 0..4 {
            acc[k] += x[k] * y[k];
        }
    }
    let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
    for (x, y) in ra.iter().zip(rb) {
        s += x * y;
    }
    s
}

#[inline]
fn axpy(a: f64, x: &[f64], y: &mut [f64]) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi += a * xi;
    }
}

/// Lower Cholesky factor of the symmetric `m × m` row-major `a` (only the lower
/// triangle is read) with `jitter` added to the diagonal; `None` when a pivot
/// is not clearly positive or not finite.
fn cholesky(a: &[f64], m: usize, jitter: f64) -> Option<Vec<f64>> {
    let mut l = vec![0.0; m * m];
    for i in 0..m {
        for j in 0..=i {
            let (head, row_i) = l.split_at_mut(i * m);
            let s = if j < i {
                a[i * m + j] - dot(&row_i[..j], &head[j * m..j * m + j])
            } else {
                a[i * m + i] + jitter - dot(&row_i[..i], &row_i[..i])
            };
            if j == i {
                let d = a[i * m + i] + jitter;
                if !(s.is_finite() && s > d.abs() * 1e-14 && s > 0.0) {
                    return None;
                }
                row_i[i] = s.sqrt();
            } else {
                row_i[j] = s / head[j * m + j];
            }
        }
    }
    Some(l)
}

/// Cholesky factor with increasing diagonal jitter on failure.
fn cholesky_jitter(a: &[f64], m: usize) -> Result<Vec<f64>, RvmError> {
    if let Some(l) = cholesky(a, m, 0.0) {
        return Ok(l);
    }
    let mean_diag = (0..m).map(|i| a[i * m + i].abs()).sum::<f64>() / m.max(1) as f64;
    let mut jitter = mean_diag.max(1e-300) * 1e-12;
    for _ in 0..6 {
        if let Some(l) = cholesky(a, m, jitter) {
            return Ok(l);
        }
        jitter *= 100.0;
    }
    Err(RvmError::Numerical(format!(
        "Cholesky factorisation of the {m}×{m} posterior precision failed even with jitter {jitter:e}"
    )))
}

/// Solves `L x = b` in place (`L` lower, row-major).
fn forward(l: &[f64], m: usize, b: &mut [f64]) {
    for i in 0..m {
        let s = dot(&l[i * m..i * m + i], &b[..i]);
        b[i] = (b[i] - s) / l[i * m + i];
    }
}

/// Solves `Lᵀ x = b` in place.
fn backward(l: &[f64], m: usize, b: &mut [f64]) {
    for i in (0..m).rev() {
        b[i] /= l[i * m + i];
        let bi = b[i];
        for k in 0..i {
            b[k] -= l[i * m + k] * bi;
        }
    }
}

/// Solves `(L Lᵀ) x = b` in place.
fn chol_solve(l: &[f64], m: usize, b: &mut [f64]) {
    forward(l, m, b);
    backward(l, m, b);
}

/// Solves `(L Lᵀ) X = B` in place for `B` of `m × v` row-major.
fn chol_solve_multi(l: &[f64], m: usize, b: &mut [f64], v: usize) {
    for i in 0..m {
        let (done, rest) = b.split_at_mut(i * v);
        let bi = &mut rest[..v];
        for k in 0..i {
            let c = l[i * m + k];
            if c != 0.0 {
                axpy(-c, &done[k * v..(k + 1) * v], bi);
            }
        }
        let inv = 1.0 / l[i * m + i];
        bi.iter_mut().for_each(|x| *x *= inv);
    }
    for i in (0..m).rev() {
        let (head, rest) = b.split_at_mut(i * v);
        let bi = &mut rest[..v];
        let inv = 1.0 / l[i * m + i];
        bi.iter_mut().for_each(|x| *x *= inv);
        for k in 0..i {
            let c = l[i * m + k];
            if c != 0.0 {
                axpy(-c, bi, &mut head[k * v..(k + 1) * v]);
            }
        }
    }
}

/// Updates the lower factor `L` (`m × m`) of `H` in place to that of
/// `H + δ e_j e_jᵀ` (rank-one update for δ > 0, downdate for δ < 0).
/// Returns false (leaving `l` unusable) when a downdate loses positive
/// definiteness; the caller then refactorises.
fn chol_rank_one_diag(l: &mut [f64], m: usize, j: usize, delta: f64) -> bool {
    let sign = if delta >= 0.0 { 1.0 } else { -1.0 };
    let mut x = vec![0.0; m];
    x[j] = delta.abs().sqrt();
    for k in j..m {
        let lkk = l[k * m + k];
        let r2 = lkk * lkk + sign * x[k] * x[k];
        if !(r2.is_finite() && r2 > lkk * lkk * 1e-14 && r2 > 0.0) {
            return false;
        }
        let r = r2.sqrt();
        let c = r / lkk;
        let s = x[k] / lkk;
        l[k * m + k] = r;
        for i in k + 1..m {
            let lik = (l[i * m + k] + sign * s * x[i]) / c;
            x[i] = c * x[i] - s * lik;
            l[i * m + k] = lik;
        }
    }
    true
}

/// Appends row `h` (the new last row of the symmetric `H`, length `m + 1`) to
/// the `m × m` lower factor `l`, giving the `(m+1) × (m+1)` factor; `None` when
/// the new pivot is not clearly positive.
fn chol_append(l: &[f64], m: usize, h: &[f64]) -> Option<Vec<f64>> {
    let mut row = h[..m].to_vec();
    forward(l, m, &mut row);
    let pivot = h[m] - dot(&row, &row);
    if !(pivot.is_finite() && pivot > h[m].abs() * 1e-14 && pivot > 0.0) {
        return None;
    }
    let k = m + 1;
    let mut out = vec![0.0; k * k];
    for i in 0..m {
        out[i * k..i * k + i + 1].copy_from_slice(&l[i * m..i * m + i + 1]);
    }
    out[m * k..m * k + m].copy_from_slice(&row);
    out[m * k + m] = pivot.sqrt();
    Some(out)
}

// ---------------------------------------------------------------------------
// Candidate selection
// ---------------------------------------------------------------------------

fn nearest_centre(row: &[f32], centres: &[f32], dim: usize, k: usize) -> (usize, f32) {
    let mut best = (0usize, f32::INFINITY);
    for c in 0..k {
        let d = squared_distance(row, &centres[c * dim..(c + 1) * dim]);
        if d < best.1 {
            best = (c, d);
        }
    }
    best
}

/// Candidate basis centres: indices (ascending, distinct) of training rows.
///
/// Seeded k-means over the rows of `x` (`n × dim`, row-major) with `s` centres:
/// k-means++ initialisation, then at most 10 Lloyd iterations (stopping early
/// when no assignment changes); for each non-empty cluster the member nearest
/// to its centre is returned. Fewer than `s` indices come back when clusters
/// are empty or rows are duplicated. When `s ≥ n`, every row is returned.
/// Deterministic for a given seed (the parallel parts only map rows).
pub fn candidate_centres(x: &[f32], n: usize, dim: usize, s: usize, seed: u64) -> Vec<usize> {
    let n = x.len().checked_div(dim).map_or(0, |rows| n.min(rows));
    if n == 0 || s == 0 {
        return Vec::new();
    }
    if s >= n {
        return (0..n).collect();
    }
    let row = |i: usize| &x[i * dim..(i + 1) * dim];
    let mut rng = Pcg64::seed_from_u64(seed);

    // k-means++ initialisation.
    let first = rng.gen_range(0..n);
    let mut centres: Vec<f32> = Vec::with_capacity(s * dim);
    centres.extend_from_slice(row(first));
    let mut d2: Vec<f64> = (0..n)
        .into_par_iter()
        .map(|i| squared_distance(row(i), row(first)) as f64)
        .collect();
    let mut k = 1;
    while k < s {
        let total: f64 = d2.iter().filter(|d| d.is_finite()).sum();
        if !(total > 0.0) {
            break; // every remaining row duplicates a centre
        }
        let mut target = rng.gen::<f64>() * total;
        let mut pick = None;
        for (i, &d) in d2.iter().enumerate() {
            if d > 0.0 && d.is_finite() {
                pick = Some(i);
                if target < d {
                    break;
                }
                target -= d;
            }
        }
        let Some(pick) = pick else { break };
        let c = row(pick).to_vec();
        centres.extend_from_slice(&c);
        d2.par_iter_mut().enumerate().for_each(|(i, d)| {
            let e = squared_distance(row(i), &c) as f64;
            if e < *d {
                *d = e;
            }
        });
        k += 1;
    }

    // Lloyd iterations.
    let mut assign = vec![usize::MAX; n];
    let mut dist = vec![f32::INFINITY; n];
    for iteration in 0..=KMEANS_ITERATIONS {
        let new: Vec<(usize, f32)> = (0..n)
            .into_par_iter()
            .map(|i| nearest_centre(row(i), &centres, dim, k))
            .collect();
        let changed = new.iter().zip(&assign).any(|(a, b)| a.0 != *b);
        for (i, (a, d)) in new.into_iter().enumerate() {
            assign[i] = a;
            dist[i] = d;
        }
        if !changed || iteration == KMEANS_ITERATIONS {
            break;
        }
        let mut sums = vec![0.0f64; k * dim];
        let mut counts = vec![0usize; k];
        for (i, &c) in assign.iter().enumerate() {
            counts[c] += 1;
            for (acc, &value) in sums[c * dim..(c + 1) * dim].iter_mut().zip(row(i)) {
                *acc += value as f64;
            }
        }
        for c in 0..k {
            if counts[c] > 0 {
                let inv = 1.0 / counts[c] as f64;
                for t in 0..dim {
                    centres[c * dim + t] = (sums[c * dim + t] * inv) as f32;
                }
            }
        }
    }

    let mut best = vec![(f32::INFINITY, usize::MAX); k];
    for i in 0..n {
        let c = assign[i];
        if c < k && (dist[i] < best[c].0 || best[c].1 == usize::MAX) {
            best[c] = (dist[i], i);
        }
    }
    let mut out: Vec<usize> = best
        .into_iter()
        .filter(|b| b.1 != usize::MAX)
        .map(|b| b.1)
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}

/// Median Euclidean distance between up to 2000 random pairs of distinct rows
/// of `x` (`n × dim`); a sensible default scale for the kernel width. 0 when
/// there are fewer than two rows.
pub fn median_distance(x: &[f32], n: usize, dim: usize, seed: u64) -> f32 {
    let n = x.len().checked_div(dim).map_or(0, |rows| n.min(rows));
    if n < 2 {
        return 0.0;
    }
    let row = |i: usize| &x[i * dim..(i + 1) * dim];
    let mut rng = Pcg64::seed_from_u64(seed);
    let pairs = MEDIAN_PAIRS.min(n.saturating_mul(n - 1) / 2).max(1);
    let mut d: Vec<f32> = (0..pairs)
        .map(|_| {
            let i = rng.gen_range(0..n);
            let mut j = rng.gen_range(0..n - 1);
            if j >= i {
                j += 1;
            }
            squared_distance(row(i), row(j)).sqrt()
        })
        .collect();
    d.sort_by(|a, b| a.total_cmp(b));
    d[d.len() / 2]
}

// ---------------------------------------------------------------------------
// Training
// ---------------------------------------------------------------------------

fn validate(
    x: &[f32],
    n: usize,
    dim: usize,
    y: &[f32],
    outputs: usize,
    o: &TrainOptions,
) -> Result<(), RvmError> {
    if dim == 0 {
        return Err(RvmError::ZeroDimension {
            what: "descriptor dimension",
        });
    }
    if outputs == 0 {
        return Err(RvmError::ZeroDimension {
            what: "number of outputs",
        });
    }
    if n < 2 {
        return Err(RvmError::TooFewSamples {
            samples: n,
            minimum: 2,
        });
    }
    if n.checked_mul(dim) != Some(x.len()) {
        return Err(RvmError::ShapeMismatch {
            what: "descriptor matrix",
            len: x.len(),
            rows: n,
            columns: dim,
        });
    }
    if n.checked_mul(outputs) != Some(y.len()) {
        return Err(RvmError::ShapeMismatch {
            what: "target matrix",
            len: y.len(),
            rows: n,
            columns: outputs,
        });
    }
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        return Err(RvmError::NonFinite {
            what: "descriptor",
            row: i / dim,
            column: i % dim,
        });
    }
    if let Some(i) = y.iter().position(|v| !v.is_finite()) {
        return Err(RvmError::NonFinite {
            what: "target",
            row: i / outputs,
            column: i % outputs,
        });
    }
    if !(o.width.is_finite() && o.width > 0.0) {
        return Err(RvmError::InvalidOption {
            option: "width",
            reason: format!("must be finite and > 0, got {}", o.width),
        });
    }
    if o.basis == 0 {
        return Err(RvmError::InvalidOption {
            option: "basis",
            reason: "need at least one candidate".into(),
        });
    }
    if !(o.tolerance.is_finite() && o.tolerance >= 0.0) {
        return Err(RvmError::InvalidOption {
            option: "tolerance",
            reason: format!("must be finite and ≥ 0, got {}", o.tolerance),
        });
    }
    Ok(())
}

#[derive(Clone, Copy, Debug)]
enum Action {
    Nothing,
    Add(f64),
    Reestimate(usize, f64),
    Delete(usize),
}

#[derive(Clone, Copy, Debug)]
struct Eval {
    gain: f64,
    action: Action,
    /// |Δ log α| of an active basis that would be re-estimated.
    dlog: f64,
    /// An addition or deletion is possible.
    structural: bool,
}

const NO_EVAL: Eval = Eval {
    gain: f64::NEG_INFINITY,
    action: Action::Nothing,
    dlog: 0.0,
    structural: false,
};

/// Marginal-likelihood contribution of one basis at precision α (relative to
/// α = ∞), for `V` outputs with sparsity `s` and summed squared quality `qsum`.
#[inline]
fn ell(alpha: f64, s: f64, qsum: f64, vf: f64) -> f64 {
    -0.5 * vf * (s / alpha).ln_1p() + 0.5 * qsum / (alpha + s)
}

/// Training state. Basis index `p ∈ 0..P`; `P − 1` is the bias.
struct Fit<'a> {
    n: usize,
    p: usize,
    v: usize,
    bias: usize,
    /// Kernel matrix, `P` columns of length `N`.
    phi: &'a [f64],
    /// `φ_pᵀφ_p`.
    diag: Vec<f64>,
    /// `Φᵀ Y` (centred), `P × V`.
    phity: Vec<f64>,
    /// `‖Y‖²_F` of the centred targets.
    yy: f64,
    beta: f64,
    beta_range: (f64, f64),
    active: Vec<usize>,
    alpha: Vec<f64>,
    /// `Φᵀ φ_j` for each active basis `j` (length `P`).
    cols: Vec<Vec<f64>>,
    /// Position of each basis in `active`, `usize::MAX` when inactive.
    pos: Vec<usize>,
    /// Sparsity factors `S_p` and quality factors `Q_pv` (`P × V`).
    big_s: Vec<f64>,
    big_q: Vec<f64>,
    /// Cholesky factor of `H = A + β Φ_Mᵀ Φ_M` (`M × M`).
    chol: Vec<f64>,
}

impl<'a> Fit<'a> {
    fn column(&self, p: usize) -> &[f64] {
        &self.phi[p * self.n..(p + 1) * self.n]
    }

    fn gram_column(&self, i: usize) -> Vec<f64> {
        let ci = self.column(i);
        (0..self.p)
            .into_par_iter()
            .map(|p| dot(self.column(p), ci))
            .collect()
    }

    fn refactor(&mut self) -> Result<(), RvmError> {
        let m = self.active.len();
        let mut h = vec![0.0; m * m];
        for j in 0..m {
            for l in 0..=j {
                h[j * m + l] = self.beta * self.cols[j][self.active[l]];
            }
            h[j * m + j] += self.alpha[j];
        }
        self.chol = cholesky_jitter(&h, m)?;
        Ok(())
    }

    /// Posterior mean `μ = β H⁻¹ Φ_Mᵀ Y` (`M × V`), by Cholesky solves.
    fn mean(&self) -> Vec<f64> {
        let (m, v) = (self.active.len(), self.v);
        let mut b = vec![0.0; m * v];
        for (j, &a) in self.active.iter().enumerate() {
            for c in 0..v {
                b[j * v + c] = self.beta * self.phity[a * v + c];
            }
        }
        chol_solve_multi(&self.chol, m, &mut b, v);
        b
    }

    /// Recomputes all `S_p`, `Q_pv` from the current Cholesky factor.
    fn full_statistics(&mut self) {
        const CHUNK: usize = 32;
        let (m, v, beta) = (self.active.len(), self.v, self.beta);
        let mu = self.mean();
        let cols = &self.cols;
        let chol = &self.chol;
        let diag = &self.diag;
        let phity = &self.phity;
        self.big_s
            .par_chunks_mut(CHUNK)
            .zip(self.big_q.par_chunks_mut(CHUNK * v))
            .enumerate()
            .for_each(|(ci, (s_out, q_out))| {
                let a = ci * CHUNK;
                let len = s_out.len();
                // Z = L⁻¹ K_chunkᵀ, row j = (col_j − Σ_{l<j} L_jl z_l) / L_jj.
                let mut z = vec![0.0; m * len];
                for j in 0..m {
                    let (done, rest) = z.split_at_mut(j * len);
                    let zj = &mut rest[..len];
                    zj.copy_from_slice(&cols[j][a..a + len]);
                    for l in 0..j {
                        let c = chol[j * m + l];
                        if c != 0.0 {
                            axpy(-c, &done[l * len..(l + 1) * len], zj);
                        }
                    }
                    let inv = 1.0 / chol[j * m + j];
                    zj.iter_mut().for_each(|x| *x *= inv);
                }
                for t in 0..len {
                    let mut acc = 0.0;
                    for j in 0..m {
                        let zz = z[j * len + t];
                        acc += zz * zz;
                    }
                    s_out[t] = beta * diag[a + t] - beta * beta * acc;
                }
                for t in 0..len {
                    let pi = a + t;
                    let q = &mut q_out[t * v..(t + 1) * v];
                    for c in 0..v {
                        q[c] = beta * phity[pi * v + c];
                    }
                    for j in 0..m {
                        let kj = beta * cols[j][pi];
                        if kj != 0.0 {
                            axpy(-kj, &mu[j * v..(j + 1) * v], q);
                        }
                    }
                }
            });
    }

    /// Re-estimates β from the residual: `β = V (N − Σ γ_j) / ‖Y − Φ_M μ‖²_F`,
    /// `γ_j = 1 − α_j Σ_jj`. The residual uses `‖Y‖² − 2⟨μ, Φ_MᵀY⟩ + ⟨μ, Φ_MᵀΦ_M μ⟩`.
    fn update_beta(&mut self) {
        let (m, v) = (self.active.len(), self.v);
        let mu = self.mean();
        // diag(Σ) from L⁻¹ e_j (the columns of L⁻¹ are not kept).
        let mut gamma = 0.0;
        let mut e = vec![0.0; m];
        for j in 0..m {
            e.iter_mut().for_each(|x| *x = 0.0);
            e[j] = 1.0;
            // forward substitution starting at row j (rows above are zero)
            for i in j..m {
                let s = dot(&self.chol[i * m + j..i * m + i], &e[j..i]);
                e[i] = (e[i] - s) / self.chol[i * m + i];
            }
            let sjj: f64 = e[j..].iter().map(|x| x * x).sum();
            gamma += 1.0 - self.alpha[j] * sjj;
        }
        let mut cross = 0.0;
        let mut quad = 0.0;
        let mut kmu = vec![0.0; v];
        for j in 0..m {
            let aj = self.active[j];
            cross += dot(&mu[j * v..(j + 1) * v], &self.phity[aj * v..(aj + 1) * v]);
            kmu.iter_mut().for_each(|x| *x = 0.0);
            for l in 0..m {
                axpy(
                    self.cols[j][self.active[l]],
                    &mu[l * v..(l + 1) * v],
                    &mut kmu,
                );
            }
            quad += dot(&mu[j * v..(j + 1) * v], &kmu);
        }
        let resid = (self.yy - 2.0 * cross + quad)
            .max(self.yy * 1e-14)
            .max(1e-300);
        let dof = (self.n as f64 - gamma).max(1.0);
        let beta = v as f64 * dof / resid;
        let beta = if beta.is_finite() {
            beta
        } else {
            self.beta_range.1
        };
        self.beta = beta.clamp(self.beta_range.0, self.beta_range.1);
    }

    fn evaluate(&self, p: usize, vf: f64) -> Eval {
        let v = self.v;
        let sp = self.big_s[p];
        let qsum_raw: f64 = self.big_q[p * v..(p + 1) * v].iter().map(|q| q * q).sum();
        let j = self.pos[p];
        if j == usize::MAX {
            // inactive: s = S, q = Q
            if !(self.diag[p] > 0.0 && sp > ALIGN_MIN * self.beta * self.diag[p]) {
                return NO_EVAL;
            }
            let theta = qsum_raw / vf - sp;
            if !(theta > 0.0) {
                return NO_EVAL;
            }
            let r = theta / sp;
            let gain = 0.5 * vf * (r - r.ln_1p());
            let alpha = (sp * sp / theta).clamp(ALPHA_MIN, ALPHA_MAX);
            if !gain.is_finite() {
                return NO_EVAL;
            }
            return Eval {
                gain,
                action: Action::Add(alpha),
                dlog: 0.0,
                structural: true,
            };
        }
        let a = self.alpha[j];
        let denom = a - sp;
        if !(denom > 0.0) {
            return NO_EVAL; // numerically inconsistent; refreshed at the next β update
        }
        let s = a * sp / denom;
        let qsum = qsum_raw * (a / denom) * (a / denom);
        let theta = qsum / vf - s;
        let old = ell(a, s, qsum, vf);
        let (action, new_alpha) = if theta > 0.0 {
            let na = (s * s / theta).clamp(ALPHA_MIN, ALPHA_MAX);
            (Action::Reestimate(j, na), na)
        } else if p == self.bias || self.active.len() <= 1 {
            (Action::Reestimate(j, ALPHA_MAX), ALPHA_MAX)
        } else {
            let gain = -old;
            if !gain.is_finite() {
                return NO_EVAL;
            }
            return Eval {
                gain,
                action: Action::Delete(j),
                dlog: 0.0,
                structural: true,
            };
        };
        let gain = ell(new_alpha, s, qsum, vf) - old;
        let dlog = (new_alpha / a).ln().abs();
        if !(gain.is_finite() && dlog.is_finite()) {
            return NO_EVAL;
        }
        Eval {
            gain,
            action,
            dlog,
            structural: false,
        }
    }

    /// `Σ e_j` and `μ_j` (row `j` of the posterior mean).
    fn sigma_column_and_mean_row(&self, j: usize) -> (Vec<f64>, Vec<f64>) {
        let (m, v) = (self.active.len(), self.v);
        let mut sj = vec![0.0; m];
        sj[j] = 1.0;
        chol_solve(&self.chol, m, &mut sj);
        let mut mu = vec![0.0; v];
        for (l, &a) in self.active.iter().enumerate() {
            axpy(self.beta * sj[l], &self.phity[a * v..(a + 1) * v], &mut mu);
        }
        (sj, mu)
    }

    /// `out_p = Σ_l K[p, l] w_l` over the active columns.
    fn k_times(&self, w: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.p];
        for (col, &wl) in self.cols.iter().zip(w) {
            if wl != 0.0 {
                axpy(wl, col, &mut out);
            }
        }
        out
    }

    /// Rank-one correction shared by re-estimation and deletion:
    /// `S_p += κ u_p²`, `Q_pv += κ μ_jv u_p`, with `u = β K Σ_j`.
    fn apply_rank_one(&mut self, kappa: f64, sj: &[f64], mu_j: &[f64]) {
        let v = self.v;
        let u = self.k_times(sj);
        let beta = self.beta;
        self.big_s
            .par_iter_mut()
            .zip(self.big_q.par_chunks_mut(v))
            .zip(u.par_iter())
            .for_each(|((s, q), &up)| {
                let up = beta * up;
                *s += kappa * up * up;
                axpy(kappa * up, mu_j, q);
            });
    }

    fn reestimate(&mut self, j: usize, new_alpha: f64) -> Result<(), RvmError> {
        let old = self.alpha[j];
        if new_alpha == old {
            return Ok(());
        }
        let (sj, mu_j) = self.sigma_column_and_mean_row(j);
        let kappa = 1.0 / (sj[j] + 1.0 / (new_alpha - old));
        if kappa.is_finite() {
            self.apply_rank_one(kappa, &sj, &mu_j);
        }
        self.alpha[j] = new_alpha;
        let m = self.active.len();
        if chol_rank_one_diag(&mut self.chol, m, j, new_alpha - old) {
            Ok(())
        } else {
            self.refactor()
        }
    }

    fn delete(&mut self, j: usize) -> Result<(), RvmError> {
        let (sj, mu_j) = self.sigma_column_and_mean_row(j);
        let kappa = 1.0 / sj[j];
        if kappa.is_finite() {
            self.apply_rank_one(kappa, &sj, &mu_j);
        }
        let p = self.active.remove(j);
        self.alpha.remove(j);
        self.cols.remove(j);
        self.pos[p] = usize::MAX;
        for (k, &a) in self.active.iter().enumerate() {
            self.pos[a] = k;
        }
        self.refactor()
    }

    fn add(&mut self, i: usize, alpha: f64) -> Result<(), RvmError> {
        let (m, v, beta) = (self.active.len(), self.v, self.beta);
        let col = self.gram_column(i);
        let mut z: Vec<f64> = self.active.iter().map(|&a| col[a]).collect();
        chol_solve(&self.chol, m, &mut z);
        let kz = self.k_times(&z);
        let sig = 1.0 / (alpha + self.big_s[i]);
        let mu_i: Vec<f64> = self.big_q[i * v..(i + 1) * v]
            .iter()
            .map(|q| sig * q)
            .collect();
        if sig.is_finite() {
            self.big_s
                .par_iter_mut()
                .zip(self.big_q.par_chunks_mut(v))
                .enumerate()
                .for_each(|(p, (s, q))| {
                    let t = beta * col[p] - beta * beta * kz[p];
                    *s -= sig * t * t;
                    axpy(-t, &mu_i, q);
                });
        }
        let mut h: Vec<f64> = self.active.iter().map(|&a| beta * col[a]).collect();
        h.push(beta * col[i] + alpha);
        let appended = chol_append(&self.chol, m, &h);
        self.active.push(i);
        self.alpha.push(alpha);
        self.cols.push(col);
        self.pos[i] = m;
        match appended {
            Some(l) => {
                self.chol = l;
                Ok(())
            }
            None => self.refactor(),
        }
    }

    fn log_marginal_likelihood(&self) -> f64 {
        let (m, v, n) = (self.active.len(), self.v as f64, self.n as f64);
        let mu = self.mean();
        let logdet_h: f64 = (0..m).map(|i| 2.0 * self.chol[i * m + i].ln()).sum();
        let log_alpha: f64 = self.alpha.iter().map(|a| a.ln()).sum();
        let mut fit = 0.0;
        for (j, &a) in self.active.iter().enumerate() {
            fit += dot(
                &mu[j * self.v..(j + 1) * self.v],
                &self.phity[a * self.v..(a + 1) * self.v],
            );
        }
        let data = self.beta * self.yy - self.beta * fit;
        -0.5 * (n * v * (2.0 * std::f64::consts::PI).ln() - n * v * self.beta.ln() - v * log_alpha
            + v * logdet_h
            + data)
    }
}

impl Rvm {
    /// Trains on `x` (`n × dim` descriptors, row-major) and `y` (`n × outputs`
    /// targets, row-major). See the module documentation for the method.
    pub fn train(
        x: &[f32],
        n: usize,
        dim: usize,
        y: &[f32],
        outputs: usize,
        options: &TrainOptions,
    ) -> Result<(Rvm, TrainReport), RvmError> {
        Rvm::train_with_progress(x, n, dim, y, outputs, options, &mut |_, _| {})
    }

    /// [`Rvm::train`], calling `progress(iteration, active basis functions)` as each add /
    /// re-estimate / delete iteration starts (for a progress bar).
    pub fn train_with_progress(
        x: &[f32],
        n: usize,
        dim: usize,
        y: &[f32],
        outputs: usize,
        options: &TrainOptions,
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<(Rvm, TrainReport), RvmError> {
        let start = Instant::now();
        validate(x, n, dim, y, outputs, options)?;
        let v = outputs;
        let candidates = candidate_centres(x, n, dim, options.basis, options.seed);
        let s = candidates.len();
        let p = s + 1;
        let bias = s;

        // Kernel matrix, column-major (one column per candidate, then the bias).
        let g = 1.0 / (2.0 * options.width as f64 * options.width as f64);
        let mut phi = vec![0.0f64; p * n];
        phi.par_chunks_mut(n).enumerate().for_each(|(c, col)| {
            if c == bias {
                col.iter_mut().for_each(|e| *e = 1.0);
            } else {
                let centre = &x[candidates[c] * dim..(candidates[c] + 1) * dim];
                for (i, e) in col.iter_mut().enumerate() {
                    let d2 = squared_distance(&x[i * dim..(i + 1) * dim], centre) as f64;
                    *e = (-d2 * g).exp();
                }
            }
        });

        // Centred targets, column-major.
        let mut y_mean = vec![0.0f64; v];
        for r in 0..n {
            for c in 0..v {
                y_mean[c] += y[r * v + c] as f64;
            }
        }
        y_mean.iter_mut().for_each(|m| *m /= n as f64);
        let mut yc = vec![0.0f64; v * n];
        for r in 0..n {
            for c in 0..v {
                yc[c * n + r] = y[r * v + c] as f64 - y_mean[c];
            }
        }
        let yy: f64 = yc.iter().map(|e| e * e).sum();
        let var = (yy / (n * v) as f64).max(1e-8);

        let diag: Vec<f64> = phi.par_chunks(n).map(|col| dot(col, col)).collect();
        let phity: Vec<f64> = (0..p * v)
            .into_par_iter()
            .map(|k| {
                dot(
                    &phi[(k / v) * n..(k / v + 1) * n],
                    &yc[(k % v) * n..(k % v + 1) * n],
                )
            })
            .collect();

        let beta0 = 1.0 / (0.01 * var);
        let mut fit = Fit {
            n,
            p,
            v,
            bias,
            phi: &phi,
            diag,
            phity,
            yy,
            beta: beta0,
            beta_range: (1.0 / (10.0 * var), 1.0 / (1e-6 * var)),
            active: Vec::new(),
            alpha: Vec::new(),
            cols: Vec::new(),
            pos: vec![usize::MAX; p],
            big_s: vec![0.0; p],
            big_q: vec![0.0; p * v],
            chol: Vec::new(),
        };
        // Start from the bias alone.
        let vf = v as f64;
        let s0 = beta0 * fit.diag[bias];
        let qsum0: f64 = fit.phity[bias * v..(bias + 1) * v]
            .iter()
            .map(|q| beta0 * beta0 * q * q)
            .sum();
        let theta0 = qsum0 / vf - s0;
        let alpha0 = if theta0 > 0.0 {
            (s0 * s0 / theta0).clamp(ALPHA_MIN, ALPHA_MAX)
        } else {
            ALPHA_MAX
        };
        let bias_col = fit.gram_column(bias);
        fit.active.push(bias);
        fit.alpha.push(alpha0);
        fit.cols.push(bias_col);
        fit.pos[bias] = 0;
        fit.refactor()?;
        fit.full_statistics();

        let mut fresh = true;
        let mut iterations = 0;
        let mut since_beta = 0;
        while iterations < options.max_iterations {
            iterations += 1;
            progress(iterations, fit.active.len());
            let evals: Vec<Eval> = (0..p)
                .into_par_iter()
                .map(|q| fit.evaluate(q, vf))
                .collect();
            let mut best = NO_EVAL;
            let mut best_index = 0;
            let mut structural = false;
            let mut max_dlog = 0.0f64;
            for (k, e) in evals.iter().enumerate() {
                structural |= e.structural;
                max_dlog = max_dlog.max(e.dlog);
                if e.gain > best.gain {
                    best = *e;
                    best_index = k;
                }
            }
            let converged = (!structural && max_dlog < options.tolerance) || !(best.gain > 0.0);
            if converged {
                if fresh {
                    break;
                }
                fit.update_beta();
                fit.refactor()?;
                fit.full_statistics();
                fresh = true;
                continue;
            }
            match best.action {
                Action::Add(alpha) => fit.add(best_index, alpha)?,
                Action::Reestimate(j, alpha) => fit.reestimate(j, alpha)?,
                Action::Delete(j) => fit.delete(j)?,
                Action::Nothing => {}
            }
            fresh = false;
            since_beta += 1;
            // The full refresh costs O(S·M²); space it out as the model grows.
            let period = BETA_EVERY.max(fit.active.len() / 5);
            if iterations < 10 || since_beta >= period {
                since_beta = 0;
                fit.update_beta();
                fit.refactor()?;
                fit.full_statistics();
                fresh = true;
            }
        }

        let mu = fit.mean();
        if mu.iter().any(|w| !w.is_finite()) || fit.alpha.iter().any(|a| !a.is_finite()) {
            return Err(RvmError::Numerical("non-finite posterior weights".into()));
        }
        let mut relevance_vectors = Vec::new();
        let mut weights = Vec::new();
        let mut bias_row = y_mean.clone();
        for (j, &a) in fit.active.iter().enumerate() {
            let row = &mu[j * v..(j + 1) * v];
            if a == bias {
                for (b, w) in bias_row.iter_mut().zip(row) {
                    *b += w;
                }
            } else {
                relevance_vectors
                    .extend_from_slice(&x[candidates[a] * dim..(candidates[a] + 1) * dim]);
                weights.extend(row.iter().map(|&w| w as f32));
            }
        }
        weights.extend(bias_row.iter().map(|&w| w as f32));
        let r = relevance_vectors.len() / dim;
        let report = TrainReport {
            candidates: s,
            relevance_vectors: r,
            iterations,
            noise: 1.0 / fit.beta,
            log_marginal_likelihood: fit.log_marginal_likelihood(),
            seconds: start.elapsed().as_secs_f64(),
        };
        let model = Rvm {
            dim,
            outputs: v,
            width: options.width,
            relevance_vectors,
            weights,
            noise: (1.0 / fit.beta) as f32,
        };
        Ok((model, report))
    }

    /// Number of relevance vectors.
    pub fn len(&self) -> usize {
        self.relevance_vectors
            .len()
            .checked_div(self.dim)
            .unwrap_or(0)
    }

    /// True when the model has no relevance vector (bias only).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// One prediction: a distance to each relevance vector and a matrix-vector
    /// product. No allocation beyond `out`.
    ///
    /// # Panics
    /// If `x.len() != self.dim` or `out.len() != self.outputs`.
    pub fn predict_into(&self, x: &[f32], out: &mut [f32]) {
        assert_eq!(
            x.len(),
            self.dim,
            "descriptor length must equal the model dimension"
        );
        assert_eq!(
            out.len(),
            self.outputs,
            "output length must equal the number of outputs"
        );
        let v = self.outputs;
        let r = self.len();
        out.copy_from_slice(&self.weights[r * v..(r + 1) * v]);
        let g = 1.0 / (2.0 * self.width * self.width);
        for j in 0..r {
            let d2 = squared_distance(x, &self.relevance_vectors[j * self.dim..(j + 1) * self.dim]);
            let k = (-d2 * g).exp();
            if k == 0.0 {
                continue;
            }
            for (o, w) in out.iter_mut().zip(&self.weights[j * v..(j + 1) * v]) {
                *o += k * w;
            }
        }
    }

    /// One prediction into a new vector of `outputs` values.
    ///
    /// # Panics
    /// If `x.len() != self.dim`.
    pub fn predict(&self, x: &[f32]) -> Vec<f32> {
        let mut out = vec![0.0; self.outputs];
        self.predict_into(x, &mut out);
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::{prop_assert, proptest, ProptestConfig};

    fn normal(rng: &mut Pcg64) -> f64 {
        let u1: f64 = rng.gen::<f64>().max(1e-300);
        let u2: f64 = rng.gen();
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }

    fn sinc(x: f64) -> f64 {
        if x == 0.0 {
            1.0
        } else {
            x.sin() / x
        }
    }

    /// 100 samples of y = sinc(x) + N(0, noise²) on x ∈ [−10, 10].
    fn sinc_data(noise: f64, seed: u64) -> (Vec<f32>, Vec<f32>) {
        let mut rng = Pcg64::seed_from_u64(seed);
        let x: Vec<f32> = (0..100)
            .map(|i| (-10.0 + 20.0 * i as f64 / 99.0) as f32)
            .collect();
        let y: Vec<f32> = x
            .iter()
            .map(|&x| (sinc(x as f64) + noise * normal(&mut rng)) as f32)
            .collect();
        (x, y)
    }

    fn sinc_rmse(model: &Rvm) -> f64 {
        let grid: Vec<f64> = (0..1000).map(|i| -10.0 + 20.0 * i as f64 / 999.0).collect();
        let se: f64 = grid
            .iter()
            .map(|&x| (model.predict(&[x as f32])[0] as f64 - sinc(x)).powi(2))
            .sum();
        (se / grid.len() as f64).sqrt()
    }

    fn assert_finite(model: &Rvm) {
        assert!(
            model.weights.iter().all(|w| w.is_finite()),
            "non-finite weight"
        );
        assert!(model.noise.is_finite() && model.noise > 0.0);
    }

    #[test]
    fn sinc_regression_is_sparse_and_accurate() {
        let (x, y) = sinc_data(0.1, 1);
        let (model, report) = Rvm::train(&x, 100, 1, &y, 1, &TrainOptions::new(100, 2.0)).unwrap();
        let rmse = sinc_rmse(&model);
        eprintln!("sinc: rmse {rmse:.4} {report:?}");
        assert_finite(&model);
        assert!(rmse < 0.1, "rmse {rmse} report {report:?}");
        assert!(
            report.relevance_vectors < 20 && report.relevance_vectors > 1,
            "{report:?}"
        );
        assert!(report.log_marginal_likelihood.is_finite());
        assert_eq!(report.relevance_vectors, model.len());
    }

    #[test]
    fn progress_is_reported_every_iteration_and_ends_where_the_report_does() {
        let (x, y) = sinc_data(0.1, 1);
        let mut seen = Vec::new();
        let (model, report) = Rvm::train_with_progress(
            &x,
            100,
            1,
            &y,
            1,
            &TrainOptions::new(100, 2.0),
            &mut |iteration, active| seen.push((iteration, active)),
        )
        .expect("trains");
        assert_eq!(seen.len(), report.iterations);
        assert!(seen.iter().enumerate().all(|(k, &(i, _))| i == k + 1));
        // The last count of active basis functions is the relevance vectors and maybe the bias.
        let last = seen.last().map_or(0, |s| s.1);
        assert!(
            last == model.len() || last == model.len() + 1,
            "{last} {report:?}"
        );
    }

    #[test]
    fn two_outputs_sin_and_cos() {
        let mut rng = Pcg64::seed_from_u64(2);
        let n = 100;
        let x: Vec<f32> = (0..n)
            .map(|i| (2.0 * std::f64::consts::PI * i as f64 / (n - 1) as f64) as f32)
            .collect();
        let mut y = Vec::new();
        for &xi in &x {
            y.push((xi as f64).sin() as f32 + 0.05 * normal(&mut rng) as f32);
            y.push((xi as f64).cos() as f32 + 0.05 * normal(&mut rng) as f32);
        }
        let (model, report) = Rvm::train(&x, n, 1, &y, 2, &TrainOptions::new(n, 1.0)).unwrap();
        let mut se = [0.0f64; 2];
        let m = 500;
        for i in 0..m {
            let t = 2.0 * std::f64::consts::PI * i as f64 / (m - 1) as f64;
            let p = model.predict(&[t as f32]);
            se[0] += (p[0] as f64 - t.sin()).powi(2);
            se[1] += (p[1] as f64 - t.cos()).powi(2);
        }
        for (k, s) in se.iter().enumerate() {
            let rmse = (s / m as f64).sqrt();
            assert!(rmse < 0.1, "output {k}: rmse {rmse}, {report:?}");
        }
    }

    /// 2-D descriptors (x, 0.5·x) for the sinc problem.
    fn lift(x: &[f32]) -> Vec<f32> {
        x.iter().flat_map(|&v| [v, 0.5 * v]).collect()
    }

    fn sinc_rmse_2d(model: &Rvm) -> f64 {
        let grid: Vec<f64> = (0..1000).map(|i| -10.0 + 20.0 * i as f64 / 999.0).collect();
        let se: f64 = grid
            .iter()
            .map(|&x| (model.predict(&[x as f32, 0.5 * x as f32])[0] as f64 - sinc(x)).powi(2))
            .sum();
        (se / grid.len() as f64).sqrt()
    }

    #[test]
    fn duplicated_descriptors_train() {
        let (x, y) = sinc_data(0.1, 3);
        let x2 = lift(&x);
        let mut xd = Vec::new();
        let mut yd = Vec::new();
        for i in 0..100 {
            for _ in 0..2 {
                xd.extend_from_slice(&x2[2 * i..2 * i + 2]);
                yd.push(y[i]);
            }
        }
        let (model, report) =
            Rvm::train(&xd, 200, 2, &yd, 1, &TrainOptions::new(200, 2.0)).unwrap();
        assert_finite(&model);
        assert!(report.relevance_vectors > 1, "{report:?}");
        let rmse = sinc_rmse_2d(&model);
        eprintln!("rmse {rmse:.4} {report:?}");
        assert!(rmse < 0.1, "rmse {rmse} {report:?}");
    }

    #[test]
    fn nearly_collinear_descriptors_train() {
        let (x, y) = sinc_data(0.1, 4);
        let x2 = lift(&x);
        let mut rng = Pcg64::seed_from_u64(5);
        let mut xd = x2.clone();
        xd.extend(x2.iter().map(|&v| v + 1e-7 * normal(&mut rng) as f32));
        let mut yd = y.clone();
        yd.extend_from_slice(&y);
        let (model, report) =
            Rvm::train(&xd, 200, 2, &yd, 1, &TrainOptions::new(200, 2.0)).unwrap();
        assert_finite(&model);
        assert!(report.relevance_vectors > 1, "{report:?}");
        let rmse = sinc_rmse_2d(&model);
        eprintln!("rmse {rmse:.4} {report:?}");
        assert!(rmse < 0.1, "rmse {rmse} {report:?}");
    }

    #[test]
    fn constant_targets_predict_the_constant() {
        let mut rng = Pcg64::seed_from_u64(6);
        let n = 60;
        let x: Vec<f32> = (0..n * 3).map(|_| rng.gen::<f32>() * 4.0).collect();
        let y: Vec<f32> = (0..n).flat_map(|_| [3.5f32, -1.25]).collect();
        let (model, report) = Rvm::train(&x, n, 3, &y, 2, &TrainOptions::new(n, 1.0)).unwrap();
        assert_finite(&model);
        assert!(!report.log_marginal_likelihood.is_nan());
        for i in 0..n {
            let p = model.predict(&x[i * 3..i * 3 + 3]);
            assert!(
                (p[0] - 3.5).abs() < 1e-4 && (p[1] + 1.25).abs() < 1e-4,
                "{p:?} {report:?}"
            );
        }
    }

    #[test]
    fn too_few_samples_is_an_error() {
        let e = Rvm::train(&[1.0], 1, 1, &[1.0], 1, &TrainOptions::new(10, 1.0)).unwrap_err();
        assert_eq!(
            e,
            RvmError::TooFewSamples {
                samples: 1,
                minimum: 2
            }
        );
        assert!(e.to_string().contains("too few samples"));
    }

    #[test]
    fn non_finite_input_names_row_and_column() {
        let mut x = vec![0.5f32; 10 * 3];
        x[3 * 3 + 1] = f32::NAN;
        let y = vec![1.0f32; 10];
        let e = Rvm::train(&x, 10, 3, &y, 1, &TrainOptions::new(5, 1.0)).unwrap_err();
        assert_eq!(
            e,
            RvmError::NonFinite {
                what: "descriptor",
                row: 3,
                column: 1
            }
        );
        assert!(e.to_string().contains("row 3, column 1"), "{e}");
        let x = vec![0.5f32; 10 * 3];
        let mut y = vec![1.0f32; 20];
        y[7 * 2 + 1] = f32::INFINITY;
        let e = Rvm::train(&x, 10, 3, &y, 2, &TrainOptions::new(5, 1.0)).unwrap_err();
        assert_eq!(
            e,
            RvmError::NonFinite {
                what: "target",
                row: 7,
                column: 1
            }
        );
    }

    #[test]
    fn shape_and_option_errors() {
        let x = vec![0.5f32; 29];
        let y = vec![1.0f32; 10];
        assert!(matches!(
            Rvm::train(&x, 10, 3, &y, 1, &TrainOptions::new(5, 1.0)),
            Err(RvmError::ShapeMismatch { .. })
        ));
        let x = vec![0.5f32; 30];
        assert!(matches!(
            Rvm::train(&x, 10, 3, &y[..9], 1, &TrainOptions::new(5, 1.0)),
            Err(RvmError::ShapeMismatch { .. })
        ));
        assert!(matches!(
            Rvm::train(&x, 10, 3, &y, 1, &TrainOptions::new(5, 0.0)),
            Err(RvmError::InvalidOption { .. })
        ));
        assert!(matches!(
            Rvm::train(&x, 10, 3, &y, 1, &TrainOptions::new(0, 1.0)),
            Err(RvmError::InvalidOption { .. })
        ));
    }

    #[test]
    fn predict_into_agrees_and_fits_noiseless_training_points() {
        let n = 50;
        let x: Vec<f32> = (0..n)
            .map(|i| (6.0 * i as f64 / (n - 1) as f64) as f32)
            .collect();
        let y: Vec<f32> = x
            .iter()
            .flat_map(|&v| [(v as f64).sin() as f32, (0.5 * v as f64).cos() as f32])
            .collect();
        let (model, report) = Rvm::train(&x, n, 1, &y, 2, &TrainOptions::new(n, 1.0)).unwrap();
        let mut out = [0.0f32; 2];
        for i in 0..n {
            model.predict_into(&x[i..i + 1], &mut out);
            let p = model.predict(&x[i..i + 1]);
            assert_eq!(p, out.to_vec());
            assert!(
                (out[0] - y[2 * i]).abs() < 0.02 && (out[1] - y[2 * i + 1]).abs() < 0.02,
                "{i}: {out:?} {report:?}"
            );
        }
    }

    #[test]
    fn kmeans_candidates_are_distinct_and_deterministic() {
        let mut rng = Pcg64::seed_from_u64(7);
        let (n, d) = (500, 4);
        let mut x = Vec::new();
        for i in 0..n {
            let c = (i % 5) as f64 * 3.0;
            for _ in 0..d {
                x.push((c + normal(&mut rng)) as f32);
            }
        }
        let a = candidate_centres(&x, n, d, 50, 11);
        let b = candidate_centres(&x, n, d, 50, 11);
        assert_eq!(a, b);
        assert!(a.len() > 40 && a.len() <= 50, "{}", a.len());
        assert!(a.windows(2).all(|w| w[0] < w[1]));
        assert!(a.iter().all(|&i| i < n));
        assert_eq!(
            candidate_centres(&x, n, d, 1000, 0),
            (0..n).collect::<Vec<_>>()
        );
        // duplicated rows: still distinct indices
        let dup: Vec<f32> = x[..40].iter().chain(&x[..40]).copied().collect();
        let c = candidate_centres(&dup, 20, d, 15, 3);
        assert!(c.windows(2).all(|w| w[0] < w[1]));
        let m = median_distance(&x, n, d, 1);
        assert!(m > 0.0 && m.is_finite());
        assert_eq!(median_distance(&x, 1, d, 1), 0.0);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn cholesky_solves_spd_systems(m in 1usize..12, seed in 0u64..1000) {
            let mut rng = Pcg64::seed_from_u64(seed);
            let b: Vec<f64> = (0..m * m).map(|_| rng.gen::<f64>() - 0.5).collect();
            let mut a = vec![0.0; m * m];
            for i in 0..m { for j in 0..m { for k in 0..m { a[i * m + j] += b[k * m + i] * b[k * m + j]; } } a[i * m + i] += 0.1; }
            let rhs: Vec<f64> = (0..m).map(|_| rng.gen::<f64>()).collect();
            let l = cholesky_jitter(&a, m).unwrap();
            let mut xs = rhs.clone();
            chol_solve(&l, m, &mut xs);
            for i in 0..m {
                let r: f64 = (0..m).map(|j| a[i * m + j] * xs[j]).sum::<f64>() - rhs[i];
                prop_assert!(r.abs() < 1e-8);
            }
            let mut multi: Vec<f64> = rhs.iter().flat_map(|&r| [r, 2.0 * r]).collect();
            chol_solve_multi(&l, m, &mut multi, 2);
            for i in 0..m { prop_assert!((multi[2 * i] - xs[i]).abs() < 1e-9 && (multi[2 * i + 1] - 2.0 * xs[i]).abs() < 1e-9); }
        }
    }

    #[test]
    fn incremental_factor_matches_refactorisation() {
        let m = 6;
        let mut rng = Pcg64::seed_from_u64(9);
        let b: Vec<f64> = (0..(m + 1) * (m + 1))
            .map(|_| rng.gen::<f64>() - 0.5)
            .collect();
        let k = m + 1;
        let mut a = vec![0.0; k * k];
        for i in 0..k {
            for j in 0..k {
                for t in 0..k {
                    a[i * k + j] += b[t * k + i] * b[t * k + j];
                }
            }
            a[i * k + i] += 0.5;
        }
        let sub: Vec<f64> = (0..m).flat_map(|i| a[i * k..i * k + m].to_vec()).collect();
        let l = cholesky(&sub, m, 0.0).unwrap();
        let grown = chol_append(&l, m, &a[m * k..m * k + k]).unwrap();
        let full = cholesky(&a, k, 0.0).unwrap();
        assert!(grown.iter().zip(&full).all(|(x, y)| (x - y).abs() < 1e-10));
        for delta in [0.7, -0.3] {
            let mut up = full.clone();
            assert!(chol_rank_one_diag(&mut up, k, 2, delta));
            let mut a2 = a.clone();
            a2[2 * k + 2] += delta;
            let want = cholesky(&a2, k, 0.0).unwrap();
            assert!(
                up.iter().zip(&want).all(|(x, y)| (x - y).abs() < 1e-10),
                "delta {delta}"
            );
        }
        let mut down = full.clone();
        assert!(!chol_rank_one_diag(&mut down, k, 0, -1e6));
    }

    #[test]
    fn singular_gram_gets_jitter() {
        // rank-one 3×3 matrix: plain Cholesky fails, jitter succeeds
        let a = [1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0];
        assert!(cholesky(&a, 3, 0.0).is_none());
        let l = cholesky_jitter(&a, 3).unwrap();
        assert!(l.iter().all(|v| v.is_finite()));
    }
}
