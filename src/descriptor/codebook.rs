//! k-means codebooks and soft vector quantisation.
//!
//! A frame yields a variable number of local histograms (one per marker, per HOG block, per contour
//! point). A [`Codebook`] of k centres, learned by k-means (`linfa-clustering`, fixed seed) over the
//! training frames' histograms, turns them into one fixed-length vector: each histogram votes softly
//! into its 5 nearest centres with Gaussian weights (σ² = the mean squared distance of those 5, so
//! the vote adapts to how far the histogram is from the codebook), the weights of one vote sum to 1,
//! and the frame's k votes are normalised to sum 1. The result is one block of the frame descriptor.
//!
//! The distances to the k centres are ‖h‖² + ‖c‖² − 2 h·c, the products taken over the histogram's
//! non-zero bins only against the centres stored bin by bin: most of a Feature Context's 180 bins
//! are empty, and the whole frame descriptor came out 1.3–1.8× faster than with one full distance
//! per centre (same descriptors to six decimals).
//!
//! Training spends nearly all its time in k-means' distances (the FC codebook's: 20,000 histograms
//! of 180 bins against 200 centres, 40 rounds). linfa's default Euclidean distance sums the squares
//! one after the other through `ndarray-stats`, which no compiler may vectorise; [`KMeansL2`]
//! gives linfa [`crate::stats::squared_distance`] instead (eight partial sums, as the RVM's kernel
//! uses), so the codebooks differ from the default distance's in the last bits of the sums.

use std::path::{Path, PathBuf};

use linfa::prelude::*;
use linfa::DatasetBase;
use linfa_clustering::KMeans;
use linfa_nn::distance::Distance;
use ndarray::{Array2, ArrayView, Dimension};
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;

use crate::model::{ModelError, ModelFile};
use crate::stats::squared_distance;

/// Version of the codebook files (the HOG codebook's is
/// [`HOG_CODEBOOK_VERSION`](super::HOG_CODEBOOK_VERSION): its histograms changed meaning).
pub const CODEBOOK_VERSION: u32 = 1;
/// Number of nearest centres a histogram votes into.
pub const SOFT_VOTES: usize = 5;

/// k centres of dimension `dim`.
#[derive(Clone, Debug, PartialEq)]
pub struct Codebook {
    dim: usize,
    centres: Vec<f32>,
    /// The centres transposed (`dim × k`): a histogram's products with all k centres are then, bin
    /// by bin, runs of k contiguous multiply-adds, and its empty bins (most of a Feature Context's
    /// 180) cost nothing.
    by_bin: Vec<f32>,
    /// ‖c‖² of each centre.
    norms: Vec<f32>,
}

/// Why a codebook could not be learned.
#[derive(Debug, thiserror::Error)]
pub enum CodebookError {
    #[error(
        "{what}: {got} training vectors for {k} centres; need at least as many vectors as centres"
    )]
    TooFewVectors { what: String, got: usize, k: usize },
    #[error("{what}: k-means failed: {message}")]
    KMeans { what: String, message: String },
}

impl Codebook {
    /// A codebook from `k × dim` centre values.
    pub fn from_centres(dim: usize, centres: Vec<f32>) -> Option<Codebook> {
        (dim > 0 && !centres.is_empty() && centres.len().is_multiple_of(dim))
            .then(|| Codebook::new(dim, centres))
    }

    /// `centres` must hold a positive multiple of `dim` values.
    fn new(dim: usize, centres: Vec<f32>) -> Codebook {
        let k = centres.len() / dim;
        let mut by_bin = vec![0.0; centres.len()];
        for (c, centre) in centres.chunks_exact(dim).enumerate() {
            for (bin, &value) in centre.iter().enumerate() {
                by_bin[bin * k + c] = value;
            }
        }
        let norms = centres
            .chunks_exact(dim)
            .map(|c| c.iter().map(|v| v * v).sum())
            .collect();
        Codebook {
            dim,
            centres,
            by_bin,
            norms,
        }
    }

    pub fn k(&self) -> usize {
        self.centres.len() / self.dim
    }

    pub fn dim(&self) -> usize {
        self.dim
    }

    pub fn centre(&self, i: usize) -> &[f32] {
        &self.centres[i * self.dim..(i + 1) * self.dim]
    }

    /// The squared distances from `histogram` to every centre, into `out` (k values), as
    /// ‖h‖² + ‖c‖² − 2 h·c over the histogram's non-zero bins.
    pub fn squared_distances(&self, histogram: &[f32], out: &mut [f32]) {
        let k = self.k();
        out.iter_mut().for_each(|v| *v = 0.0);
        let mut own = 0.0f32;
        for (bin, &h) in histogram.iter().enumerate() {
            if h == 0.0 {
                continue;
            }
            own += h * h;
            let row = &self.by_bin[bin * k..(bin + 1) * k];
            for (dot, &c) in out.iter_mut().zip(row) {
                *dot += h * c;
            }
        }
        for (v, &norm) in out.iter_mut().zip(&self.norms) {
            *v = (own + norm - 2.0 * *v).max(0.0);
        }
    }

    /// Adds the soft vote of `histogram` (weights summing to 1 over its nearest centres) to `votes`.
    pub fn vote(&self, histogram: &[f32], votes: &mut [f32]) {
        self.vote_with(histogram, votes, &mut vec![0.0; self.k()]);
    }

    /// [`Codebook::vote`] with a caller's buffer of k values for the distances.
    fn vote_with(&self, histogram: &[f32], votes: &mut [f32], distances: &mut [f32]) {
        let n = SOFT_VOTES.min(self.k());
        let mut best: [(f32, usize); SOFT_VOTES] = [(f32::INFINITY, 0); SOFT_VOTES];
        self.squared_distances(histogram, distances);
        for (c, &d) in distances.iter().enumerate() {
            if d < best[n - 1].0 {
                let mut at = n - 1;
                while at > 0 && best[at - 1].0 > d {
                    best[at] = best[at - 1];
                    at -= 1;
                }
                best[at] = (d, c);
            }
        }
        let sigma2 = (best[..n].iter().map(|b| b.0).sum::<f32>() / n as f32).max(1e-12);
        let weights: Vec<f32> = best[..n]
            .iter()
            .map(|b| (-(b.0 - best[0].0) / (2.0 * sigma2)).exp())
            .collect();
        let total: f32 = weights.iter().sum();
        for (w, b) in weights.iter().zip(&best[..n]) {
            votes[b.1] += w / total;
        }
    }

    /// The normalised votes of many histograms (`count × dim` values) into `out` (k values): all zero
    /// when there are none.
    pub fn quantise(&self, histograms: &[f32], out: &mut [f32]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        let mut count = 0usize;
        let mut distances = vec![0.0; self.k()];
        for h in histograms.chunks_exact(self.dim) {
            self.vote_with(h, out, &mut distances);
            count += 1;
        }
        if count > 0 {
            out.iter_mut().for_each(|v| *v /= count as f32);
        }
    }

    /// k-means over `vectors` (`n × dim`), subsampled to at most `max_vectors` with `seed`.
    /// Returns the codebook and the inertia (mean squared distance of a vector to its centre).
    pub fn train(
        what: &str,
        vectors: &[f32],
        dim: usize,
        k: usize,
        max_vectors: usize,
        seed: u64,
    ) -> Result<(Codebook, f64), CodebookError> {
        let n = vectors.len() / dim.max(1);
        if n < k || k == 0 {
            return Err(CodebookError::TooFewVectors {
                what: what.into(),
                got: n,
                k,
            });
        }
        let mut rng = Pcg64Mcg::seed_from_u64(seed);
        let mut order: Vec<usize> = (0..n).collect();
        order.shuffle(&mut rng);
        order.truncate(max_vectors.max(k));
        let mut data = Vec::with_capacity(order.len() * dim);
        for &i in &order {
            data.extend_from_slice(&vectors[i * dim..(i + 1) * dim]);
        }
        let array = Array2::from_shape_vec((order.len(), dim), data).map_err(|e| {
            CodebookError::KMeans {
                what: what.into(),
                message: e.to_string(),
            }
        })?;
        let dataset = DatasetBase::from(array);
        let model = KMeans::params_with(k, rng, KMeansL2)
            .n_runs(1)
            .max_n_iterations(40)
            .tolerance(1e-4)
            .fit(&dataset)
            .map_err(|e| CodebookError::KMeans {
                what: what.into(),
                message: e.to_string(),
            })?;
        let centres: Vec<f32> = model.centroids().iter().copied().collect();
        let codebook = Codebook::new(dim, centres);
        // linfa reports the inertia already divided by the number of samples.
        let inertia = model.inertia() as f64;
        Ok((codebook, inertia))
    }

    /// Writes the codebook as a model file of `kind` at `version`.
    pub fn save(&self, path: &Path, kind: &str, version: u32) -> Result<(), ModelError> {
        let mut m = ModelFile::new(kind, version);
        m.push("centres", &[self.k(), self.dim], self.centres.clone());
        m.write(path)
    }

    /// Reads a codebook of `kind` at `version` with exactly `k` centres of `dim`.
    pub fn load(
        path: &Path,
        kind: &str,
        version: u32,
        k: usize,
        dim: usize,
    ) -> Result<Codebook, ModelError> {
        let m = ModelFile::read(path, kind, version)?;
        let centres = m.array(path, "centres", &[k, dim])?.to_vec();
        Ok(Codebook::new(dim, centres))
    }
}

/// Euclidean distance for linfa's k-means over the rows' contiguous slices, with
/// [`squared_distance`]'s eight partial sums (linfa's `L2Dist` sums one square after the other).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct KMeansL2;

impl Distance<f32> for KMeansL2 {
    fn distance<D: Dimension>(&self, a: ArrayView<f32, D>, b: ArrayView<f32, D>) -> f32 {
        self.rdistance(a, b).sqrt()
    }

    #[inline]
    fn rdistance<D: Dimension>(&self, a: ArrayView<f32, D>, b: ArrayView<f32, D>) -> f32 {
        assert_eq!(a.shape(), b.shape(), "k-means rows of different lengths");
        match (a.as_slice(), b.as_slice()) {
            (Some(a), Some(b)) => squared_distance(a, b),
            _ => a.iter().zip(b.iter()).fold(0.0, |sum, (x, y)| {
                let d = x - y;
                sum + d * d
            }),
        }
    }

    fn rdist_to_dist(&self, rdist: f32) -> f32 {
        rdist.sqrt()
    }

    fn dist_to_rdist(&self, dist: f32) -> f32 {
        dist * dist
    }
}

/// Where a suit keeps each codebook.
pub fn codebook_path(suit_dir: &Path, kind: &str) -> PathBuf {
    suit_dir.join(format!("{kind}.bin"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn the_k_means_distance_is_the_euclidean_one_on_rows_and_strided_views() {
        use linfa_nn::distance::L2Dist;
        let rows = ndarray::array![[3.0f32, 0.0, 1.0], [0.0, 4.0, 1.0]];
        let (a, b) = (rows.row(0), rows.row(1));
        assert_eq!(KMeansL2.rdistance(a, b), 25.0);
        assert_eq!(KMeansL2.distance(a, b), 5.0);
        // Columns are strided views: the fallback sum gives the same.
        let (c0, c1) = (rows.column(0), rows.column(1));
        assert_eq!(KMeansL2.rdistance(c0, c1), 9.0 + 16.0);
        // Against linfa's own distance on a histogram-sized row (eight-lane sums differ only in
        // rounding).
        let long: Vec<f32> = (0..180).map(|i| ((i * 37) % 11) as f32 / 11.0).collect();
        let other: Vec<f32> = long.iter().rev().copied().collect();
        let (x, y) = (
            ndarray::ArrayView1::from(&long[..]),
            ndarray::ArrayView1::from(&other[..]),
        );
        let ours = KMeansL2.rdistance(x, y);
        let linfas = L2Dist.rdistance(x, y);
        assert!((ours - linfas).abs() <= 1e-5 * linfas, "{ours} vs {linfas}");
        assert_eq!(KMeansL2.rdist_to_dist(25.0), 5.0);
        assert_eq!(KMeansL2.dist_to_rdist(5.0), 25.0);
    }

    fn grid_codebook() -> Codebook {
        // Six centres on a line: (0,0), (1,0), …, (5,0).
        Codebook::from_centres(2, (0..6).flat_map(|i| [i as f32, 0.0]).collect()).expect("valid")
    }

    #[test]
    fn a_vote_goes_to_the_nearest_centres_and_sums_to_one() {
        let c = grid_codebook();
        let mut votes = vec![0.0; 6];
        c.vote(&[0.0, 0.0], &mut votes);
        assert!((votes.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        assert!(votes[0] > votes[1] && votes[1] > votes[2] && votes[5] == 0.0);
        // Exactly between centres 2 and 3: equal votes.
        let mut votes = vec![0.0; 6];
        c.vote(&[2.5, 0.0], &mut votes);
        assert!((votes[2] - votes[3]).abs() < 1e-6);
    }

    #[test]
    fn quantising_nothing_gives_zeros() {
        let mut out = vec![1.0; 6];
        grid_codebook().quantise(&[], &mut out);
        assert!(out.iter().all(|&v| v == 0.0));
    }

    #[test]
    fn kmeans_finds_three_clusters_and_round_trips() {
        let mut data = Vec::new();
        for i in 0..300 {
            let centre = [[0.0, 0.0], [10.0, 0.0], [0.0, 10.0]][i % 3];
            let jitter = (i as f32 * 0.618).fract() - 0.5;
            data.extend_from_slice(&[centre[0] + jitter, centre[1] - jitter]);
        }
        let (codebook, inertia) = Codebook::train("test", &data, 2, 3, 1000, 7).expect("trains");
        assert!(inertia < 0.2, "{inertia}");
        let mut found: Vec<(i32, i32)> = (0..3)
            .map(|i| {
                (
                    codebook.centre(i)[0].round() as i32,
                    codebook.centre(i)[1].round() as i32,
                )
            })
            .collect();
        found.sort();
        assert_eq!(found, vec![(0, 0), (0, 10), (10, 0)]);
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("c.bin");
        codebook
            .save(&path, "test-codebook", CODEBOOK_VERSION)
            .expect("save");
        assert_eq!(
            Codebook::load(&path, "test-codebook", CODEBOOK_VERSION, 3, 2).expect("load"),
            codebook
        );
        assert!(Codebook::load(&path, "test-codebook", CODEBOOK_VERSION, 4, 2).is_err());
        assert!(Codebook::load(&path, "test-codebook", CODEBOOK_VERSION + 1, 3, 2).is_err());
        assert!(Codebook::train("few", &data[..4], 2, 3, 10, 1).is_err());
    }

    proptest! {
        #[test]
        fn distances_over_the_non_zero_bins_are_the_euclidean_ones(
            centres in proptest::collection::vec(-1.0f32..1.0, 4 * 9),
            histogram in proptest::collection::vec(prop_oneof![Just(0.0f32), 0.0f32..1.0], 9),
        ) {
            let codebook = Codebook::from_centres(9, centres).expect("valid");
            let mut distances = vec![0.0; 4];
            codebook.squared_distances(&histogram, &mut distances);
            for (c, &d) in distances.iter().enumerate() {
                let direct: f32 = histogram
                    .iter()
                    .zip(codebook.centre(c))
                    .map(|(h, c)| (h - c) * (h - c))
                    .sum();
                prop_assert!((d - direct).abs() < 1e-5 * (1.0 + direct), "{} vs {}", d, direct);
            }
        }

        #[test]
        fn soft_votes_of_any_vector_sum_to_one(v in proptest::collection::vec(-10.0f32..10.0, 2)) {
            let mut votes = vec![0.0; 6];
            grid_codebook().vote(&v, &mut votes);
            prop_assert!((votes.iter().sum::<f32>() - 1.0).abs() < 1e-5);
            prop_assert!(votes.iter().all(|w| w.is_finite() && *w >= 0.0));
        }
    }
}
