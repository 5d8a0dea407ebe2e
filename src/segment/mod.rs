//! Suit segmentation: the person's mask from each frame (source paper sec. 3.1.1, after Criminisi et
//! al. 2006, "Bilayer segmentation of live video").
//!
//! The segmenter minimises a binary energy on the pixel grid — unaries from learned colour, gradient,
//! motion and temporal lookup tables, pairwise weights from the learned neighbourhood table — with an
//! s-t minimum cut. This module so far holds the cut itself: [`maxflow`], a grid max-flow written for
//! the 4-connected pixel grid, and [`gcg`], the GCG1 file format in which frame graphs are exchanged
//! with the reference solver (`../shared/peers/maxflow/`). The learned tables and the per-frame graph
//! construction are not written yet.

pub mod gcg;
pub mod maxflow;
