//! The per-frame segmenter: learned tables → grid graph → min-cut → clean-up → full-resolution mask.
//!
//! For every frame [`Segmenter::segment`]:
//! 1. box-downscales the frame by the tables' factor and computes colour bins and gradients;
//! 2. builds the graph: unaries `σ_C·C + σ_G·G + σ_M·M + σ_T·T` per pixel (the motion and temporal terms
//!    use the segmenter's own masks of the previous one and two frames; the first frame uses the label
//!    prior and the second the terms it has), pairwise weights from the neighbourhood table on the four
//!    axial edges (a label-pair energy A, B, D becomes an edge weight (2B − A − D)/2 plus (D − A)/2 on
//!    both nodes' person cost);
//! 3. cuts it with [`GridMaxFlow`] (the search buffers are reused from frame to frame);
//! 4. keeps the connected region that carries the most suit cloth next to markers, fills its small holes
//!    ([`cleanup`](super::cleanup)), and reports what that changed;
//! 5. upsamples to the frame's size and decides the pixels of the boundary band at full resolution from
//!    their own colour and the upsampled cut.
//!
//! A frame with nobody in it gives an empty mask. The mask goes to marker detection and the descriptors.

use std::time::Instant;

use image::RgbImage;

use super::cleanup::{fill_holes, keep_person_region, CleanupReport};
use super::features::{
    colour_index, contrast_bin, downscale, temporal_bin, ColourLut, FrameFeatures, MarkerGate,
    TEMPORAL_BINS,
};
use super::maxflow::{GridGraph, GridMaxFlow};
use super::tables::SegmenterTables;
use crate::mask::Mask;
use crate::suit::SuitDefinition;

/// Tuning of the clean-up and the boundary refinement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmenterOptions {
    /// The person region must cover at least this fraction of the image, else the mask is empty.
    pub min_person_fraction: f32,
    /// Background holes up to this fraction of the image are filled.
    pub max_hole_fraction: f32,
    /// Weight of the upsampled cut against the full-resolution colour in the boundary band (nats).
    pub refine_prior: f32,
}

impl Default for SegmenterOptions {
    fn default() -> Self {
        SegmenterOptions {
            min_person_fraction: 0.002,
            max_hole_fraction: 0.001,
            refine_prior: 3.0,
        }
    }
}

/// Milliseconds per stage of one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageTimes {
    pub features: f64,
    pub graph: f64,
    pub cut: f64,
    pub cleanup: f64,
    pub refine: f64,
}

impl StageTimes {
    pub fn total(&self) -> f64 {
        self.features + self.graph + self.cut + self.cleanup + self.refine
    }
}

/// The result for one frame.
#[derive(Clone, Debug)]
pub struct Segmentation {
    pub mask: Mask,
    pub cleanup: CleanupReport,
    /// The max-flow (= minimum energy) of the cut.
    pub flow: f64,
    pub times: StageTimes,
}

/// A segmenter with its history; one per video stream.
pub struct Segmenter {
    tables: SegmenterTables,
    options: SegmenterOptions,
    lut: ColourLut,
    /// Per contrast bin: edge weight and the person-cost adjustment of both endpoints.
    edge_weight: Vec<f32>,
    edge_adjust: Vec<f32>,
    gate: MarkerGate,
    maxflow: GridMaxFlow,
    graph: GridGraph,
    small: Vec<[u8; 3]>,
    features: FrameFeatures,
    previous: Option<FrameFeatures>,
    previous_mask: Option<Vec<bool>>,
    before_previous_mask: Option<Vec<bool>>,
    ids: Vec<u32>,
    unary: Vec<[f32; 2]>,
}

impl Segmenter {
    pub fn new(
        tables: SegmenterTables,
        suit: &SuitDefinition,
        options: SegmenterOptions,
    ) -> Segmenter {
        // Pairwise energies A (both background), B (different), D (both person) per contrast bin,
        // each −ln p(contrast | pair) − ln p(pair equal or different).
        let n = &tables.neighbourhood;
        let sigma = tables.weights.neighbourhood;
        let [equal, different] = tables.pair_prior;
        let bins = n[0].len();
        let mut edge_weight = Vec::with_capacity(bins);
        let mut edge_adjust = Vec::with_capacity(bins);
        for k in 0..bins {
            let (a, b, d) = (
                n[0][k] + equal,
                0.5 * (n[1][k] + n[2][k]) + different,
                n[3][k] + equal,
            );
            edge_weight.push(sigma * (0.5 * (2.0 * b - a - d)).max(0.0));
            edge_adjust.push(sigma * 0.5 * (d - a));
        }
        Segmenter {
            tables,
            options,
            lut: ColourLut::new(),
            edge_weight,
            edge_adjust,
            gate: MarkerGate::new(suit),
            maxflow: GridMaxFlow::new(),
            graph: GridGraph::new(0, 0),
            small: Vec::new(),
            features: FrameFeatures::default(),
            previous: None,
            previous_mask: None,
            before_previous_mask: None,
            ids: Vec::new(),
            unary: Vec::new(),
        }
    }

    pub fn tables(&self) -> &SegmenterTables {
        &self.tables
    }

    /// Forgets the history (a new sequence, or the camera moved).
    pub fn reset(&mut self) {
        self.previous = None;
        self.previous_mask = None;
        self.before_previous_mask = None;
    }

    /// Builds the frame's graph (without cutting it); the graph is then available from [`Segmenter::graph`].
    pub fn build_graph(&mut self, frame: &RgbImage) {
        let (w, h) = downscale(frame, self.tables.downscale, &mut self.small);
        self.features
            .compute(&self.small, w, h, &self.lut, &self.gate);
        self.fill_graph();
    }

    /// The graph of the last frame, e.g. to dump it as GCG1 and compare solvers.
    pub fn graph(&self) -> &GridGraph {
        &self.graph
    }

    fn fill_graph(&mut self) {
        let (w, h) = (self.features.width, self.features.height);
        if self.graph.width() != w || self.graph.height() != h {
            self.graph = GridGraph::new(w, h);
            self.reset();
        }
        let t = &self.tables;
        let s = t.weights;
        let f = &self.features;
        self.unary.clear();
        self.unary.reserve(w * h);
        let history = self.previous.as_ref().zip(self.previous_mask.as_ref());
        for i in 0..w * h {
            let c = f.colour[i];
            let colour = colour_index(c, f.proximity[i]);
            let mut u = [0usize, 1].map(|l| {
                s.colour * t.colour[l][colour] + s.gradient * t.gradient[l][f.gradient[i] as usize]
            });
            match history {
                Some((prev, prev_mask)) => {
                    let dt = c.val.abs_diff(prev.colour[i].val) as u32;
                    let bin = f.gradient_magnitude[i] as usize * TEMPORAL_BINS + temporal_bin(dt);
                    let lp = prev_mask[i] as usize;
                    for (l, ul) in u.iter_mut().enumerate() {
                        *ul += s.motion * t.motion[2 * l + lp][bin];
                    }
                    match &self.before_previous_mask {
                        Some(pp) => {
                            let lpp = pp[i] as usize;
                            for (l, ul) in u.iter_mut().enumerate() {
                                *ul += s.temporal * t.temporal[4 * l + 2 * lp + lpp];
                            }
                        }
                        None => {
                            for (l, ul) in u.iter_mut().enumerate() {
                                *ul += s.temporal * t.prior[l];
                            }
                        }
                    }
                }
                None => {
                    for (l, ul) in u.iter_mut().enumerate() {
                        *ul += s.temporal * t.prior[l];
                    }
                }
            }
            self.unary.push(u);
        }
        let (source, sink, right, down) = self.graph.parts_mut();
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                if x + 1 < w {
                    let bin = contrast_bin(f.colour[i], f.colour[i + 1]);
                    right[y * (w - 1) + x] = self.edge_weight[bin];
                    self.unary[i][1] += self.edge_adjust[bin];
                    self.unary[i + 1][1] += self.edge_adjust[bin];
                }
                if y + 1 < h {
                    let bin = contrast_bin(f.colour[i], f.colour[i + w]);
                    down[i] = self.edge_weight[bin];
                    self.unary[i][1] += self.edge_adjust[bin];
                    self.unary[i + w][1] += self.edge_adjust[bin];
                }
            }
        }
        for (i, u) in self.unary.iter().enumerate() {
            let m = u[0].min(u[1]);
            source[i] = u[0] - m; // cost of labelling i background
            sink[i] = u[1] - m; // cost of labelling i person
        }
    }

    /// Segments one frame.
    pub fn segment(&mut self, frame: &RgbImage) -> Segmentation {
        let mut times = StageTimes::default();
        let started = Instant::now();
        let (w, h) = downscale(frame, self.tables.downscale, &mut self.small);
        self.features
            .compute(&self.small, w, h, &self.lut, &self.gate);
        times.features = ms(started);

        let started = Instant::now();
        self.fill_graph();
        times.graph = ms(started);

        let started = Instant::now();
        let result = self.maxflow.solve(&self.graph);
        times.cut = ms(started);
        let mut labels = result.labels;

        let started = Instant::now();
        let n = (w * h) as f32;
        let (colours, proximity) = (&self.features.colour, &self.features.proximity);
        let mut ids = std::mem::take(&mut self.ids);
        let mut report = keep_person_region(
            &mut labels,
            w,
            h,
            // Suit cloth next to a marker: what only the suit looks like (a red poster is all marker
            // colour, a lawn all cloth colour, neither has the two interleaved).
            |i| {
                if proximity[i] <= 3 && self.gate.is_cloth(colours[i]) {
                    1.0
                } else {
                    0.01
                }
            },
            (self.options.min_person_fraction * n).ceil() as usize,
            &mut ids,
        );
        fill_holes(
            &mut labels,
            w,
            h,
            (self.options.max_hole_fraction * n) as usize,
            &mut ids,
            &mut report,
        );
        self.ids = ids;
        times.cleanup = ms(started);

        let started = Instant::now();
        let mask = self.refine(frame, &labels, w, h);
        times.refine = ms(started);

        // History for the next frame.
        self.before_previous_mask = self.previous_mask.take();
        self.previous_mask = Some(labels);
        std::mem::swap(
            self.previous.get_or_insert_with(FrameFeatures::default),
            &mut self.features,
        );
        Segmentation {
            mask,
            cleanup: report,
            flow: result.flow,
            times,
        }
    }

    /// Proximity bin of low-resolution pixel `i` of the frame being refined.
    fn previous_proximity(&self, i: usize) -> u8 {
        self.features.proximity.get(i).copied().unwrap_or(u8::MAX)
    }

    /// Upsamples the low-resolution labels to the frame; pixels whose bilinear neighbourhood is mixed
    /// are decided by their own colour against the upsampled cut.
    fn refine(&self, frame: &RgbImage, labels: &[bool], w: usize, h: usize) -> Mask {
        let (fw, fh) = (frame.width(), frame.height());
        let f = self.tables.downscale.max(1) as f32;
        let mut out = vec![false; fw as usize * fh as usize];
        if w == 0 || h == 0 {
            return Mask::from_pixels(fw, fh, out).unwrap_or_else(|| Mask::empty(fw, fh));
        }
        let sigma = self.tables.weights.colour;
        let prior = self.options.refine_prior;
        let raw = frame.as_raw();
        for y in 0..fh as usize {
            let sy = ((y as f32 + 0.5) / f - 0.5).clamp(0.0, (h - 1) as f32);
            let (y0, ty) = (sy as usize, sy.fract());
            let y1 = (y0 + 1).min(h - 1);
            for x in 0..fw as usize {
                let sx = ((x as f32 + 0.5) / f - 0.5).clamp(0.0, (w - 1) as f32);
                let (x0, tx) = (sx as usize, sx.fract());
                let x1 = (x0 + 1).min(w - 1);
                let l = |xx: usize, yy: usize| labels[yy * w + xx] as u8 as f32;
                let m = (l(x0, y0) * (1.0 - tx) + l(x1, y0) * tx) * (1.0 - ty)
                    + (l(x0, y1) * (1.0 - tx) + l(x1, y1) * tx) * ty;
                let i = y * fw as usize + x;
                out[i] = if m <= 0.0 {
                    false
                } else if m >= 1.0 {
                    true
                } else {
                    let p = i * 3;
                    let c = self.lut.get([raw[p], raw[p + 1], raw[p + 2]]);
                    let near =
                        (sx.round() as usize).min(w - 1) + (sy.round() as usize).min(h - 1) * w;
                    let k = colour_index(c, self.previous_proximity(near));
                    let e_fg = sigma * self.tables.colour[1][k] + prior * (1.0 - m);
                    let e_bg = sigma * self.tables.colour[0][k] + prior * m;
                    e_fg < e_bg
                };
            }
        }
        Mask::from_pixels(fw, fh, out).unwrap_or_else(|| Mask::empty(fw, fh))
    }
}

fn ms(started: Instant) -> f64 {
    started.elapsed().as_secs_f64() * 1e3
}
