//! Suit segmentation: the person's mask from each frame (source paper sec. 3.1.1, after Criminisi et
//! al. 2006, "Bilayer segmentation of live video").
//!
//! The segmenter minimises a binary energy on the pixel grid — unaries from learned colour, gradient,
//! motion and temporal lookup tables, pairwise weights from the learned neighbourhood table — with an
//! s-t minimum cut, then keeps one person region. [`features`] quantises pixels, [`tables`] learns and
//! stores the likelihoods, [`train`] fits them to frames with masks, [`segmenter`] runs them per frame
//! on [`maxflow`] (a grid max-flow written for this), [`cleanup`] and [`snap`], with [`room`], the
//! room behind the person learned pixel by pixel, and [`hands`], where the suit's arms end;
//! [`gcg`] reads and writes frame graphs in the GCG1 format of the reference solver
//! (`../shared/peers/maxflow/`). The
//! [`Mask`](crate::mask::Mask) it returns goes to marker detection.

pub mod cleanup;
pub mod features;
pub mod gcg;
pub mod hands;
pub mod maxflow;
pub mod room;
pub mod segmenter;
pub mod snap;
pub mod tables;
pub mod train;

pub use segmenter::{Segmentation, Segmenter, SegmenterOptions, StageTimes};
pub use tables::{SegmenterTables, Weights};
pub use train::{
    search_weights, train_segmenter, SearchOutcome, SearchStep, TrainReport, TrainingFrame,
    WeightSearch, MAX_VALIDATION_FRAMES, MIN_VALIDATION_FRAMES,
};
