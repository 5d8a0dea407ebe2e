//! s-t minimum cut / maximum flow on a 4-connected pixel grid.
//!
//! The segmenter expresses its binary energy (unary costs per pixel, contrast-sensitive Potts weights
//! between 4-neighbours) as a [`GridGraph`]; [`GridMaxFlow::solve`] returns the maximum flow (= the
//! minimum energy) and a labelling ([`MaxFlowResult::labels`], `true` = source side = foreground) that
//! the next stage turns into the per-frame foreground mask.
//!
//! No Rust crate is fit for this (the general-purpose max-flows in petgraph and rs-graph take seconds on
//! one 640x480 frame); this is the Boykov–Kolmogorov algorithm written from the papers (Boykov &
//! Kolmogorov 2004, PAMI 'An experimental comparison of min-cut/max-flow algorithms'), specialised for
//! 4-connected grids in a cache-friendly layout in the spirit of GridCut (Jamriska et al. 2012).
//!
//! Implementation notes:
//! * the grid is padded by one ring of inert nodes (all capacities zero, never in a tree), so a
//!   neighbour is always `i ± 1` or `i ± stride` without boundary tests;
//! * each node is one 32-byte, 32-aligned record holding the residual capacities towards its four
//!   neighbours, its residual terminal capacity (`> 0`: from the source, `< 0`: to the sink), its tree,
//!   its parent as a direction code and the timestamp/distance pair of the BK origin-check heuristic;
//! * the two terminal capacities of a node are cancelled against each other at start (the flow
//!   min(src, sink) through the node); then a pre-pass routes flow before the search trees are grown:
//!   every vertical path source→p→q→sink is saturated, then each row and then each column gets a
//!   1-D max-flow pass (a sweep computing how much sink capacity is reachable further along, then a
//!   sweep carrying flow towards it; right then left, down then up), 8 rows or columns in lock-step
//!   so that the sweeps' dependency chains overlap (one AVX register where the processor has it).
//!   On the reference graph this leaves the trees 5.5K augmentations instead of 29K, at about
//!   1.5 ms for the passes;
//! * every pre-pass step is a push along a residual edge, which keeps the cost of every cut (the
//!   flow is an ordinary augmentation; a rounding remainder that stays on a node is residual source
//!   capacity there), so the result is unchanged;
//! * residuals are `f32` (as in the reference); the flow is summed in `f64` as Σ (src − residual
//!   src) when the trees start, which counts the cancelled and pre-pass flow alike, plus the
//!   bottleneck of each augmenting path;
//! * the roots are made strip by strip right after the column pass, while the strip is in the
//!   cache; then the trees grow by one level: a free node next to a root joins it as a child if the
//!   edge between them has residual capacity in the tree's direction; then only tree nodes that
//!   touch a free node or the other tree start active (a node inside its own tree has nothing to do
//!   until adoption frees a neighbour, which re-activates it as in BK). On the reference graph 9K
//!   nodes start active instead of 114K and growth steps fall from 211K to 48K (−10 %);
//! * a byte copy of the tree codes beside the node records (0.3 MB at 640x480) is read by the first
//!   level and the activation, which look at a node's record only where the copy shows that it can
//!   qualify (a free node next to a tree, a tree node next to another code: 61K and 11K of 307K
//!   nodes on the reference graph); the search keeps the copy up to date where a node joins or
//!   leaves a tree, and the labels are read from it instead of from the 10 MB of records. With the
//!   flow summed as above and each node filled in one store, the reference graph solves in 12.1–12.7
//!   ms against 14.2–14.8 ms before (alternated runs, 2026-12-05), masks unchanged;
//! * the active set is a FIFO of node indices with an in-queue flag, orphans are a FIFO too (ring
//!   buffers); the node a few places ahead in each queue is prefetched, since the solver is bound by
//!   memory latency;
//! * augmentation walks each side of the path once, chasing parent links, and records the nodes;
//!   the update pass then works from that list, so its steps do not wait on each other (−7 %);
//! * tried and measured slower (or no better) on the reference graph, so not used: 8x8-tiled node
//!   storage; solving 32..256-pixel tiles on their own before the global search; tree and parent
//!   codes in byte arrays beside the node records (+14 % instructions, no faster); recording the
//!   origin-check walk of adoption to stamp distances from the list (+1..6 %); a LIFO active queue
//!   (+50 %) or orphan queue (+3 %); adopting the first valid parent instead of the nearest (+2 %);
//!   other neighbour orders in growth, queueing a path's orphans root side first, other prefetch
//!   distances (all within ±3 %, noise); growing only the source tree (before the one-level start:
//!   −5 % here, +6 % on 1440x1080; after it +10 % and +15 %); a second row pass after the column
//!   pass (+13 %); running the line passes on the node records in place instead of 8-lane copies
//!   (+7 % in the pre-pass); the horizontal short-path pushes before the row pass (the row pass
//!   covers them; without them the trees have 5 % fewer augmentations); dropping the vertical
//!   short-path pushes too (+2..10 %); the column pass in bands of 16..128 rows while they are in
//!   the cache (7.3K..11.5K augmentations instead of 5.5K); 4 or 16 lines in lock-step instead of 8
//!   (no gain); attaching free nodes also to already attached left/up neighbours, i.e. many levels
//!   in raster order (fewer growth steps but more orphans, +4..13 %); the root sweep made
//!   branch-free over all nodes (+10 % in the pre-pass); filling a row in one pass of zipped
//!   iterators (no change); a second start level (free nodes next to first-level nodes; growth
//!   steps 48K -> 37K, time within ±4 %); the pre-pass on the residuals in separate arrays, one per
//!   direction, with the node records written once after it (+15..20 %: the column pass reads
//!   three arrays); the first level made branch-free (+12..44 % in its sweep), or made per strip of
//!   8 or 32 columns while the strip is in the cache (+2..6 %); prefetching the row below in the first
//!   level's sweep, gathering the column pass row by row instead of lane by lane, transparent huge
//!   pages for the node array (all within ±1 %);
//! * all buffers live in [`GridMaxFlow`] and are reused: solving graphs of an unchanged size does not
//!   allocate apart from the returned label vector.

// Direction codes index both the capacity array and the offset table in the hot loops.
#![allow(clippy::needless_range_loop)]

use std::fmt;

/// Error building a [`GridGraph`] from parts: names the offending field.
#[derive(Debug, Clone, PartialEq)]
pub enum GraphError {
    /// A capacity array has the wrong length for the grid size.
    LengthMismatch {
        field: &'static str,
        expected: usize,
        actual: usize,
    },
    /// A capacity is NaN, infinite or negative.
    BadValue {
        field: &'static str,
        index: usize,
        value: f32,
    },
    /// The grid is too large to be indexed with 32-bit node numbers.
    TooLarge { width: usize, height: usize },
}

impl fmt::Display for GraphError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GraphError::LengthMismatch {
                field,
                expected,
                actual,
            } => write!(f, "`{field}` has {actual} values, expected {expected}"),
            GraphError::BadValue {
                field,
                index,
                value,
            } => write!(
                f,
                "`{field}`[{index}] = {value} is not a finite, non-negative capacity"
            ),
            GraphError::TooLarge { width, height } => {
                write!(f, "grid {width}x{height} is too large")
            }
        }
    }
}

impl std::error::Error for GraphError {}

/// Largest padded node count we index with `u32`.
const MAX_PADDED_NODES: usize = u32::MAX as usize - 1;

fn padded_count(width: usize, height: usize) -> Option<usize> {
    let n = width.checked_add(2)?.checked_mul(height.checked_add(2)?)?;
    if n > MAX_PADDED_NODES {
        None
    } else {
        Some(n)
    }
}

/// A 4-connected grid graph: per node terminal capacities and per edge undirected weights.
///
/// Node `i = y*W + x`. `source[i]`: capacity source→i (cost of labelling i background);
/// `sink[i]`: capacity i→sink (cost of labelling i foreground); `right[y*(W-1)+x]`: weight of the
/// undirected edge (x,y)–(x+1,y); `down[y*W+x]`: weight of the edge (x,y)–(x,y+1).
#[derive(Debug, Clone, PartialEq)]
pub struct GridGraph {
    width: usize,
    height: usize,
    source: Vec<f32>,
    sink: Vec<f32>,
    right: Vec<f32>,
    down: Vec<f32>,
}

impl GridGraph {
    /// An all-zero graph of `width` x `height` nodes.
    ///
    /// # Panics
    /// If the grid cannot be indexed with 32-bit node numbers (over ~4·10⁹ nodes).
    pub fn new(width: usize, height: usize) -> Self {
        assert!(
            padded_count(width, height).is_some(),
            "grid {width}x{height} is too large"
        );
        let n = width * height;
        GridGraph {
            width,
            height,
            source: vec![0.0; n],
            sink: vec![0.0; n],
            right: vec![0.0; height * width.saturating_sub(1)],
            down: vec![0.0; height.saturating_sub(1) * width],
        }
    }

    /// Builds a graph from its arrays, checking lengths (`W*H`, `W*H`, `H*(W-1)`, `(H-1)*W`) and that
    /// every value is finite and `>= 0`.
    pub fn from_parts(
        width: usize,
        height: usize,
        source: Vec<f32>,
        sink: Vec<f32>,
        right: Vec<f32>,
        down: Vec<f32>,
    ) -> Result<Self, GraphError> {
        if padded_count(width, height).is_none() {
            return Err(GraphError::TooLarge { width, height });
        }
        let n = width * height;
        let fields: [(&'static str, &[f32], usize); 4] = [
            ("source", &source, n),
            ("sink", &sink, n),
            ("right", &right, height * width.saturating_sub(1)),
            ("down", &down, height.saturating_sub(1) * width),
        ];
        for (field, values, expected) in fields {
            if values.len() != expected {
                return Err(GraphError::LengthMismatch {
                    field,
                    expected,
                    actual: values.len(),
                });
            }
            if let Some((index, &value)) = values
                .iter()
                .enumerate()
                .find(|(_, v)| !(v.is_finite() && **v >= 0.0))
            {
                return Err(GraphError::BadValue {
                    field,
                    index,
                    value,
                });
            }
        }
        Ok(GridGraph {
            width,
            height,
            source,
            sink,
            right,
            down,
        })
    }

    pub fn width(&self) -> usize {
        self.width
    }

    pub fn height(&self) -> usize {
        self.height
    }

    /// Sets the terminal capacities of node (x, y).
    ///
    /// # Panics
    /// If (x, y) is outside the grid.
    pub fn set_terminal(&mut self, x: usize, y: usize, source_cap: f32, sink_cap: f32) {
        assert!(
            x < self.width && y < self.height,
            "node ({x},{y}) outside grid"
        );
        let i = y * self.width + x;
        self.source[i] = source_cap;
        self.sink[i] = sink_cap;
    }

    /// Sets the weight of the edge (x,y)–(x+1,y).
    ///
    /// # Panics
    /// If `x + 1 >= width` or `y >= height`.
    pub fn set_right(&mut self, x: usize, y: usize, w: f32) {
        assert!(
            x + 1 < self.width && y < self.height,
            "right edge ({x},{y}) outside grid"
        );
        self.right[y * (self.width - 1) + x] = w;
    }

    /// Sets the weight of the edge (x,y)–(x,y+1).
    ///
    /// # Panics
    /// If `x >= width` or `y + 1 >= height`.
    pub fn set_down(&mut self, x: usize, y: usize, w: f32) {
        assert!(
            x < self.width && y + 1 < self.height,
            "down edge ({x},{y}) outside grid"
        );
        self.down[y * self.width + x] = w;
    }

    /// Mutable views of the four capacity arrays (source, sink, right, down), for a caller that fills
    /// a whole frame's graph at once. Every value written must be finite and `>= 0`.
    pub fn parts_mut(&mut self) -> (&mut [f32], &mut [f32], &mut [f32], &mut [f32]) {
        (
            &mut self.source,
            &mut self.sink,
            &mut self.right,
            &mut self.down,
        )
    }

    pub fn source(&self) -> &[f32] {
        &self.source
    }

    pub fn sink(&self) -> &[f32] {
        &self.sink
    }

    pub fn right(&self) -> &[f32] {
        &self.right
    }

    pub fn down(&self) -> &[f32] {
        &self.down
    }

    /// Cost of a labelling in `f64`: Σ_{L=0} src + Σ_{L=1} sink + Σ_{edges cut} w
    /// (`true` = source side = foreground).
    ///
    /// # Panics
    /// If `labels.len() != width * height`.
    pub fn cut_cost(&self, labels: &[bool]) -> f64 {
        let (w, h) = (self.width, self.height);
        assert_eq!(labels.len(), w * h, "labels length must be width*height");
        let mut e = 0.0f64;
        for (i, &l) in labels.iter().enumerate() {
            e += if l { self.sink[i] } else { self.source[i] } as f64;
        }
        if w > 1 {
            for y in 0..h {
                for x in 0..w - 1 {
                    if labels[y * w + x] != labels[y * w + x + 1] {
                        e += self.right[y * (w - 1) + x] as f64;
                    }
                }
            }
        }
        for y in 0..h.saturating_sub(1) {
            for x in 0..w {
                if labels[y * w + x] != labels[(y + 1) * w + x] {
                    e += self.down[y * w + x] as f64;
                }
            }
        }
        e
    }
}

/// Result of [`GridMaxFlow::solve`].
#[derive(Debug, Clone, PartialEq)]
pub struct MaxFlowResult {
    /// Value of the maximum flow = cost of the minimum cut.
    pub flow: f64,
    /// Minimum-cut labelling, row-major, `true` = source side (foreground).
    pub labels: Vec<bool>,
}

// Tree membership.
const FREE: u8 = 0;
const SRC: u8 = 1;
const SNK: u8 = 2;
// Parent codes: 0..=3 are directions (left, right, up, down; reverse = d ^ 1).
const TERMINAL: u8 = 4;
const ORPHAN: u8 = 5;
const NO_PARENT: u8 = 6;
const INF_DIST: u32 = u32::MAX;

/// `min` for values that are never NaN (compiles to one instruction, unlike `f32::min`).
#[inline(always)]
fn fmin(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}

/// `max` for values that are never NaN.
#[inline(always)]
fn fmax(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}

/// Σ `values` in `f64`, in eight running sums so that the additions do not wait on each other.
fn sum_f64(values: &[f32]) -> f64 {
    let mut acc = [0.0f64; 8];
    let mut chunks = values.chunks_exact(8);
    for c in &mut chunks {
        for k in 0..8 {
            acc[k] += c[k] as f64;
        }
    }
    for (a, &v) in acc.iter_mut().zip(chunks.remainder()) {
        *a += v as f64;
    }
    acc.iter().sum()
}

/// Saturates source→p→q→sink or source→q→p→sink for node `p` and the node `q` below it
/// (branch-free: at most one of the two amounts is non-zero, so every update is exact).
#[inline(always)]
fn push_short_vertical(p: &mut Node, q: &mut Node) {
    let (tp, tq) = (p.tr, q.tr);
    let (cpq, cqp) = (p.cap[3], q.cap[2]);
    let fwd = fmin(fmin(fmax(tp, 0.0), fmax(-tq, 0.0)), cpq);
    let bwd = fmin(fmin(fmax(tq, 0.0), fmax(-tp, 0.0)), cqp);
    let delta = fwd - bwd;
    p.cap[3] = cpq - delta;
    p.tr = tp - delta;
    q.cap[2] = cqp + delta;
    q.tr = tq + delta;
}

/// Writes row `y` of `g` into `cells` (the row's nodes in the padded grid): residual capacities
/// towards the four neighbours (zero towards the padding) and the cancelled terminal capacity,
/// each node in one store.
fn fill_row(cells: &mut [Node], g: &GridGraph, y: usize) {
    let (w, h) = (g.width, g.height);
    let cells = &mut cells[..w];
    let src = &g.source[y * w..(y + 1) * w];
    let snk = &g.sink[y * w..(y + 1) * w];
    let right = &g.right[y * (w - 1)..(y + 1) * (w - 1)];
    let up = if y > 0 {
        Some(&g.down[(y - 1) * w..y * w])
    } else {
        None
    };
    let down = if y + 1 < h {
        Some(&g.down[y * w..(y + 1) * w])
    } else {
        None
    };
    for x in 0..w {
        let cap = [
            if x > 0 { right[x - 1] } else { 0.0 },
            if x + 1 < w { right[x] } else { 0.0 },
            up.map_or(0.0, |u| u[x]),
            down.map_or(0.0, |d| d[x]),
        ];
        cells[x] = Node {
            cap,
            tr: src[x] - snk[x],
            ..Node::default()
        };
    }
}

/// Makes `node` a root of its tree if it has residual terminal capacity, free otherwise, and copies
/// its tree code to `tree`. Branch-free: the signs of the residuals are noise-like.
#[inline(always)]
fn make_root(node: &mut Node, tree: &mut u8) {
    let (pos, neg) = ((node.tr > 0.0) as u8, (node.tr < 0.0) as u8);
    node.tree = pos * SRC + neg * SNK;
    node.parent = NO_PARENT - (pos | neg) * (NO_PARENT - TERMINAL);
    node.dist = 1;
    *tree = node.tree;
}

/// Grows the trees by one level before the search: a free node `i` next to a root joins that root's
/// tree as its child if the edge between them has residual capacity in the tree's direction (the
/// first such neighbour, source roots first). Roots are known from the signs of the terminal
/// residuals alone, so the nodes can be visited in any order once those are final. Saves the
/// growth steps of the roots, which then often have no free neighbour left and stay passive.
#[inline(always)]
fn attach_to_root(nodes: &mut [Node], i: usize, off: &[isize; 4]) {
    let ni = *at(nodes, i);
    let mut snk_dir = None;
    for d in 0..4 {
        let nj = *at(nodes, (i as isize + off[d]) as usize);
        if nj.tr > 0.0 && nj.cap[d ^ 1] > 0.0 {
            set_parent(at(nodes, i), SRC, d);
            return;
        }
        if snk_dir.is_none() && nj.tr < 0.0 && ni.cap[d] > 0.0 {
            snk_dir = Some(d);
        }
    }
    if let Some(d) = snk_dir {
        set_parent(at(nodes, i), SNK, d);
    }
}

fn set_parent(n: &mut Node, tree: u8, d: usize) {
    n.tree = tree;
    n.parent = d as u8;
    n.dist = 2;
}

/// For each of the `flags.len()` nodes from node `row` on (a row of the padded grid, or part of
/// one), whether `keep(code, [left, right, up, down])` holds for its tree code in `trees` and its
/// four neighbours' (1 or 0; a loop the compiler vectorises).
#[inline(always)]
fn cross_flags(
    trees: &[u8],
    row: usize,
    stride: usize,
    flags: &mut [u8],
    keep: impl Fn(u8, [u8; 4]) -> bool,
) {
    let t = &trees[row - 1 - stride..row + stride + flags.len()];
    let s = stride;
    for (x, f) in flags.iter_mut().enumerate() {
        let n = [t[s + x], t[s + x + 2], t[x + 1], t[2 * s + x + 1]];
        *f = keep(t[s + x + 1], n) as u8;
    }
}

/// Whether tree node `i` touches, through a residual edge in its tree's direction, a node outside
/// its tree (free nodes in the padding count; their edges have zero capacity). Branch-free: the
/// trees of neighbouring nodes are noise-like.
#[inline(always)]
fn touches_other_tree(nodes: &mut [Node], i: usize, off: &[isize; 4]) -> bool {
    let ni = *at(nodes, i);
    let (is_src, is_snk) = (ni.tree == SRC, ni.tree == SNK);
    let mut act = false;
    for d in 0..4 {
        let nj = *at(nodes, (i as isize + off[d]) as usize);
        // Tree residual: out of i in the source tree, into i in the sink tree.
        let res = (is_src & (ni.cap[d] > 0.0)) | (is_snk & (nj.cap[d ^ 1] > 0.0));
        act |= res & (nj.tree != ni.tree);
    }
    act
}

/// Lines (rows or columns) routed together by [`push_along_lines`] (one SIMD lane each).
const LINE_BATCH: usize = 8;
type Lanes = [f32; LINE_BATCH];

/// Scratch for [`push_along_lines`]: per position along the lines, one lane per line of the batch.
#[derive(Clone, Debug, Default)]
struct LineScratch {
    tr: Vec<Lanes>,
    /// Residual capacity towards the previous position (left or up).
    lo: Vec<Lanes>,
    /// Residual capacity towards the next position (right or down).
    hi: Vec<Lanes>,
    demand: Vec<Lanes>,
}

/// One batch of straight lines of the padded grid: `n <= LINE_BATCH` lines of `len` nodes, line
/// `lane` starting at node `first + lane * lane_step` and advancing by `step`; `lo_dir` is the
/// direction code towards the previous node (`0` for rows, `2` for columns; `lo_dir + 1` is the
/// other way).
#[derive(Clone, Copy, Debug)]
struct Lines {
    first: usize,
    lane_step: usize,
    step: usize,
    len: usize,
    n: usize,
    lo_dir: usize,
}

impl Lines {
    fn node(&self, lane: usize, k: usize) -> usize {
        self.first + lane * self.lane_step + k * self.step
    }
}

/// Saturates, within each line of the batch, paths from nodes with residual source capacity to
/// nodes with residual sink capacity further along, then further back (a 1-D max-flow pass per line
/// and direction, see [`sweep_lanes`]). The lines are independent, so they are processed in
/// lock-step, one lane each, which breaks the sweeps' dependency chains.
fn push_along_lines(nodes: &mut [Node], lines: Lines, s: &mut LineScratch) {
    let len = lines.len;
    if len < 2 {
        return;
    }
    let (lo, hi) = (lines.lo_dir, lines.lo_dir + 1);
    for v in [&mut s.tr, &mut s.lo, &mut s.hi] {
        v.clear();
        v.resize(len, [0.0; LINE_BATCH]);
    }
    s.demand.clear();
    s.demand.resize(len + 1, [0.0; LINE_BATCH]);
    for lane in 0..lines.n {
        for k in 0..len {
            let node = &nodes[lines.node(lane, k)];
            s.tr[k][lane] = node.tr;
            s.lo[k][lane] = node.cap[lo];
            s.hi[k][lane] = node.cap[hi];
        }
    }
    // Unused lanes are all zero: nothing flows in them.
    sweep_both_ways(s);
    for lane in 0..lines.n {
        for k in 0..len {
            let node = &mut nodes[lines.node(lane, k)];
            node.tr = s.tr[k][lane];
            node.cap[lo] = s.lo[k][lane];
            node.cap[hi] = s.hi[k][lane];
        }
    }
}

/// The two sweeps of [`push_along_lines`] (towards the line's end, then back), compiled for AVX
/// where the processor has it (checked at run time): the eight lanes are then one register. About
/// 4 % of the solve on the reference graph (11.86 against 12.41 ms, twelve alternated runs); the
/// same arithmetic, so the same residuals.
fn sweep_both_ways(s: &mut LineScratch) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the processor has AVX (checked just above).
        return unsafe { sweep_both_ways_avx(s) };
    }
    sweep_both_ways_with(s)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn sweep_both_ways_avx(s: &mut LineScratch) {
    sweep_both_ways_with(s)
}

#[inline(always)]
fn sweep_both_ways_with(s: &mut LineScratch) {
    sweep_lanes(&mut s.tr, &mut s.hi, &mut s.lo, &mut s.demand, false);
    sweep_lanes(&mut s.tr, &mut s.lo, &mut s.hi, &mut s.demand, true);
}

/// One direction of the row pass, for each lane: `fwd[x]` is the residual capacity from column x
/// to the next column in the sweep (`x + 1`, or `x - 1` if `leftward`), `back[x]` the opposite one.
///
/// A backward sweep computes, for each position, the sink capacity reachable from it (its own plus
/// what the next edge lets through to the rest); a forward sweep then carries flow from node to
/// node, never more than the rest can absorb. Each step is an ordinary push along a residual edge;
/// a rounding remainder stays on a node as residual source capacity, which is also a valid state
/// (the flow is still Σ source − residual source, see [`GridMaxFlow::solve`]).
#[inline(always)]
fn sweep_lanes(
    tr: &mut [Lanes],
    fwd: &mut [Lanes],
    back: &mut [Lanes],
    demand: &mut [Lanes],
    leftward: bool,
) {
    let w = tr.len();
    let pos = |k: usize| if leftward { w - 1 - k } else { k };
    // demand[k]: sink capacity reachable from the k-th position of the sweep onwards; the edge
    // out of the last position leads to the padding and has zero capacity.
    demand[w] = [0.0; LINE_BATCH];
    for k in (0..w).rev() {
        let x = pos(k);
        let next = demand[k + 1];
        let mut d = [0.0; LINE_BATCH];
        for l in 0..LINE_BATCH {
            d[l] = fmax(-tr[x][l], 0.0) + fmin(fwd[x][l], next[l]);
        }
        demand[k] = d;
    }
    let mut carry = [0.0f32; LINE_BATCH];
    for k in 0..w {
        let x = pos(k);
        let next = demand[k + 1];
        for l in 0..LINE_BATCH {
            let t = tr[x][l] + carry[l];
            let f = fmin(fmin(fmax(t, 0.0), fwd[x][l]), next[l]);
            tr[x][l] = t - f;
            fwd[x][l] -= f;
            carry[l] = f;
        }
        if k + 1 < w {
            let xn = pos(k + 1);
            for l in 0..LINE_BATCH {
                back[xn][l] += carry[l];
            }
        }
    }
}

/// FIFO of node indices in a ring buffer that always keeps one free slot, so a conditional push can
/// write unconditionally.
#[derive(Debug, Default)]
struct Fifo {
    buf: Vec<u32>,
    head: usize,
    tail: usize,
}

impl Fifo {
    fn new() -> Self {
        Fifo::default()
    }

    /// A queue for at most `n` entries at a time (grows if that is ever exceeded).
    fn with_capacity(n: usize) -> Self {
        Fifo {
            buf: vec![0; (n + 1).next_power_of_two()],
            head: 0,
            tail: 0,
        }
    }

    fn len(&self) -> usize {
        self.tail - self.head
    }

    #[cfg(test)]
    fn capacity(&self) -> usize {
        self.buf.len()
    }

    fn clear(&mut self) {
        self.head = 0;
        self.tail = 0;
    }

    #[inline(always)]
    fn mask(&self) -> usize {
        self.buf.len().wrapping_sub(1)
    }

    #[cold]
    fn grow(&mut self) {
        let mut buf = vec![0; (2 * self.buf.len()).max(16)];
        let n = self.len();
        for (k, slot) in buf.iter_mut().enumerate().take(n) {
            *slot = self.buf[(self.head + k) & self.mask()];
        }
        self.buf = buf;
        self.head = 0;
        self.tail = n;
    }

    #[inline(always)]
    fn push(&mut self, v: u32) {
        self.push_if(v, true);
    }

    /// Pushes `v` if `cond`, without a branch on `cond`.
    #[inline(always)]
    fn push_if(&mut self, v: u32, cond: bool) {
        if self.len() + 1 >= self.buf.len() {
            self.grow();
        }
        let m = self.mask();
        self.buf[self.tail & m] = v;
        self.tail += cond as usize;
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<u32> {
        if self.head == self.tail {
            return None;
        }
        let v = self.buf[self.head & self.mask()];
        self.head += 1;
        Some(v)
    }

    /// The entry `k` places behind the front, if any.
    #[inline(always)]
    fn peek(&self, k: usize) -> Option<u32> {
        if k < self.len() {
            Some(self.buf[(self.head + k) & self.mask()])
        } else {
            None
        }
    }
}

/// How far ahead in the active queue nodes are prefetched.
const PREFETCH_AHEAD: usize = 8;
/// How far ahead in the orphan queue nodes are prefetched.
const PREFETCH_AHEAD_ORPHANS: usize = 4;

/// Hints the CPU to load node `i` into the cache (no-op off x86-64 or out of range).
#[inline(always)]
fn prefetch(nodes: &[Node], i: usize) {
    #[cfg(target_arch = "x86_64")]
    if i < nodes.len() {
        // SAFETY: the pointer is in bounds; prefetching has no other effect on memory.
        unsafe {
            use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
            _mm_prefetch::<_MM_HINT_T0>(nodes.as_ptr().add(i) as *const i8);
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (nodes, i);
}

/// Prefetches node `i` and its four neighbours (`stride` = row length of the padded grid).
#[inline(always)]
fn prefetch_around(nodes: &[Node], i: usize, stride: usize) {
    prefetch(nodes, i);
    prefetch(nodes, i.wrapping_sub(1));
    prefetch(nodes, i + 1);
    prefetch(nodes, i.wrapping_sub(stride));
    prefetch(nodes, i + stride);
}

/// Node `i` without a bounds check.
///
/// Every index the solver forms is a grid node (inside the padding ring) or one of its four
/// neighbours, which lie in the padding ring at worst; padding nodes have zero capacities and never
/// enter a tree, so no index beyond them is ever formed. `debug_assert` guards this in tests.
#[inline(always)]
fn at(nodes: &mut [Node], i: usize) -> &mut Node {
    debug_assert!(i < nodes.len());
    // SAFETY: see above; i < nodes.len() by construction of the padded grid.
    unsafe { nodes.get_unchecked_mut(i) }
}

#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(32))]
struct Node {
    /// Residual capacity from this node to the neighbour in direction d.
    cap: [f32; 4],
    /// Residual terminal capacity: > 0 from the source, < 0 to the sink.
    tr: f32,
    /// Timestamp of the last time `dist` was known exact.
    ts: u32,
    /// Distance (in edges) to the terminal of its tree.
    dist: u32,
    tree: u8,
    parent: u8,
    in_queue: u8,
}

/// Work counters of the last [`GridMaxFlow::solve`] (for tuning and benchmarks).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SolveStats {
    /// Nodes active after initialisation.
    pub initially_active: u64,
    /// Growth steps (an active node scanned).
    pub growths: u64,
    /// Augmenting paths found by the trees.
    pub augmentations: u64,
    /// Tree edges walked while augmenting (both passes).
    pub path_edges: u64,
    /// Orphans processed in adoption.
    pub orphans: u64,
}

/// Where the time of the last [`GridMaxFlow::solve`] went, milliseconds (for benchmarks).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SolveTimes {
    /// Filling the node records, the pre-pass and the start of the trees.
    pub prepare_ms: f64,
    /// The search: growth, augmentation and adoption.
    pub search_ms: f64,
    /// Reading the labels out.
    pub labels_ms: f64,
}

/// Reusable max-flow solver for [`GridGraph`]s. Buffers are kept between calls, so solving a graph of
/// the same size again does not reallocate them.
#[derive(Debug)]
pub struct GridMaxFlow {
    nodes: Vec<Node>,
    active: Fifo,
    orphans: Fifo,
    /// Scratch list of the nodes on the current augmenting path.
    path: Vec<u32>,
    /// Scratch for the row passes of the pre-pass.
    rows: LineScratch,
    /// A byte copy of the nodes' tree codes (padded like `nodes`): the start of the trees reads
    /// it, the search keeps it up to date, and the labels are read from it.
    trees: Vec<u8>,
    /// The flow of the augmenting paths of the current solve.
    augmented: f64,
    /// Scratch for the start of the trees: which nodes of a row could qualify.
    flags: Vec<u8>,
    stride: usize,
    dims: (usize, usize),
    stats: SolveStats,
    times: SolveTimes,
    /// Saturate source→p→q→sink paths in one sweep before growing trees.
    pub(crate) prepass: bool,
}

impl Default for GridMaxFlow {
    fn default() -> Self {
        Self::new()
    }
}

impl GridMaxFlow {
    pub fn new() -> Self {
        GridMaxFlow {
            nodes: Vec::new(),
            active: Fifo::new(),
            orphans: Fifo::new(),
            path: Vec::new(),
            rows: LineScratch::default(),
            trees: Vec::new(),
            augmented: 0.0,
            flags: Vec::new(),
            stride: 0,
            dims: (0, 0),
            stats: SolveStats::default(),
            times: SolveTimes::default(),
            prepass: true,
        }
    }

    /// Turns the source→p→q→sink pre-pass on or off (on by default; off only for comparisons).
    pub fn set_prepass(&mut self, on: bool) {
        self.prepass = on;
    }

    /// Work counters of the last solve.
    pub fn stats(&self) -> SolveStats {
        self.stats
    }

    /// Where the time of the last solve went.
    pub fn times(&self) -> SolveTimes {
        self.times
    }

    /// Computes the maximum flow and a minimum cut of `g`.
    pub fn solve(&mut self, g: &GridGraph) -> MaxFlowResult {
        let (w, h) = (g.width, g.height);
        if w == 0 || h == 0 {
            return MaxFlowResult {
                flow: 0.0,
                labels: Vec::new(),
            };
        }
        self.stats = SolveStats::default();
        self.augmented = 0.0;
        // The flow is what left the source: Σ src − residual src, where the residual source capacity
        // of a node is its terminal residual when positive (its sink link is then saturated). That
        // counts the cancelled and pre-pass flow, known when the trees start; each augmentation
        // then adds its bottleneck.
        let started = std::time::Instant::now();
        let flow_before_search = self.prepare(g);
        self.stats.initially_active = self.active.len() as u64;
        let prepared = std::time::Instant::now();
        self.run();
        let searched = std::time::Instant::now();
        let flow = flow_before_search + self.augmented;
        let stride = self.stride;
        let mut labels = Vec::with_capacity(w * h);
        for y in 0..h {
            let row = (y + 1) * stride + 1;
            labels.extend(self.trees[row..row + w].iter().map(|&t| t == SRC));
        }
        let ms = |from: std::time::Instant, to: std::time::Instant| (to - from).as_secs_f64() * 1e3;
        self.times = SolveTimes {
            prepare_ms: ms(started, prepared),
            search_ms: ms(prepared, searched),
            labels_ms: ms(searched, std::time::Instant::now()),
        };
        MaxFlowResult { flow, labels }
    }

    /// Copies the graph into the padded node array, cancels terminal pairs, routes flow along the
    /// short paths, rows and columns (if enabled), makes every node with residual terminal capacity
    /// a root of its tree, grows the trees by one level and activates the nodes that touch another
    /// tree. Three sweeps: over the rows (fill, short paths, row pass a batch of rows behind), over
    /// strips of columns (column pass, roots), and over the rows of a byte copy of the trees (first
    /// level and activation, each only where the copy shows it could apply). Returns the flow so far:
    /// Σ src − Σ residual source capacity.
    #[inline(never)]
    fn prepare(&mut self, g: &GridGraph) -> f64 {
        let (w, h) = (g.width, g.height);
        let stride = w + 2;
        // from_parts/new guarantee this fits in u32.
        let total = stride * (h + 2);
        self.stride = stride;
        if self.nodes.len() != total {
            self.nodes.clear();
            self.nodes.resize(total, Node::default());
            self.trees.clear();
            self.trees.resize(total, FREE);
            // Each node is at most once in each queue (in-queue flag; ORPHAN parent code).
            self.active = Fifo::with_capacity(total);
            self.orphans = Fifo::with_capacity(total);
        } else {
            if self.dims != (w, h) {
                // Same node count, other shape: the padding ring moved, so clear everything.
                self.nodes.fill(Node::default());
                self.trees.fill(FREE);
            }
            // Otherwise the padding ring is still all-zero and free; the interior is rewritten below.
            self.active.clear();
            self.orphans.clear();
        }
        self.dims = (w, h);
        self.flags.resize(w, 0);
        let prepass = self.prepass;
        let nodes = &mut self.nodes;
        let trees = &mut self.trees;
        let flags = &mut self.flags;
        let active = &mut self.active;
        let rows = &mut self.rows;
        let off = [-1isize, 1, -(stride as isize), stride as isize];
        // Rows [0, passed) have had the row pass. Row r of the graph is the padded row r + 1.
        let mut passed = 0;
        let mut source_total = 0.0;
        for y in 0..h {
            let row = (y + 1) * stride + 1;
            fill_row(&mut nodes[row..row + w], g, y);
            source_total += sum_f64(&g.source[y * w..(y + 1) * w]);
            if !prepass {
                continue;
            }
            // Short vertical paths source→p→q→sink first; the row pass below covers the
            // horizontal ones (and longer paths along the row).
            if y > 0 {
                let (above, this) = nodes[row - stride..row + w].split_at_mut(stride);
                for (p, q) in above[..w].iter_mut().zip(this) {
                    push_short_vertical(p, q);
                }
            }
            // Rows [0, complete) have seen all their short paths: route what is left along them,
            // a batch of rows at a time while they are still in the cache.
            let complete = if y + 1 == h { h } else { y };
            while complete - passed >= LINE_BATCH || (complete == h && passed < h) {
                let n = LINE_BATCH.min(complete - passed);
                let lines = Lines {
                    first: (passed + 1) * stride + 1,
                    lane_step: stride,
                    step: 1,
                    len: w,
                    n,
                    lo_dir: 0,
                };
                push_along_lines(nodes, lines, rows);
                passed += n;
            }
        }
        // Then along the columns, a strip of columns at a time. The terminal residuals of a strip
        // are then final: its roots are made while it is in the cache (and copied to `trees`).
        let row_of = |y: usize| (y + 1) * stride + 1;
        let mut residual_source = [0.0f64; LINE_BATCH];
        for x0 in (0..w).step_by(LINE_BATCH) {
            let n = LINE_BATCH.min(w - x0);
            if prepass {
                let lines = Lines {
                    first: row_of(0) + x0,
                    lane_step: 1,
                    step: stride,
                    len: h,
                    n,
                    lo_dir: 2,
                };
                push_along_lines(nodes, lines, rows);
            }
            for y in 0..h {
                let cells = row_of(y) + x0..row_of(y) + x0 + n;
                let strip = nodes[cells.clone()].iter_mut().zip(&mut trees[cells]);
                for ((node, t), acc) in strip.zip(&mut residual_source) {
                    make_root(node, t);
                    *acc += fmax(node.tr, 0.0) as f64;
                }
            }
        }
        // Then the first level of the trees, and the activation of the nodes that touch, through a
        // residual edge, a node outside their own tree (one row behind, once the row below has its
        // first level). A root surrounded by its own tree is passive; adoption re-activates it if a
        // neighbour is freed, as for any passive node. Both look only at the nodes that the byte
        // copy of the trees shows could qualify (a vectorised pass over a row): a free node next
        // to a node in a tree, a node in a tree next to one that is not in the same tree.
        for y in 0..=h {
            if y < h {
                // A free node can only join a root next to it.
                let row = row_of(y);
                cross_flags(trees, row, stride, flags, |c, n| {
                    (c == FREE) & (n != [FREE; 4])
                });
                for (x, &f) in flags.iter().enumerate() {
                    if f != 0 {
                        attach_to_root(nodes, row + x, &off);
                        trees[row + x] = at(nodes, row + x).tree;
                    }
                }
            }
            if y >= 1 {
                // Only a node with a neighbour outside its tree can touch another tree.
                let row = row_of(y - 1);
                cross_flags(trees, row, stride, flags, |c, n| {
                    (c != FREE) & (n != [c; 4])
                });
                for (x, &f) in flags.iter().enumerate() {
                    if f != 0 {
                        let i = row + x;
                        let act = touches_other_tree(nodes, i, &off);
                        at(nodes, i).in_queue = act as u8;
                        active.push_if(i as u32, act);
                    }
                }
            }
        }
        source_total - residual_source.iter().sum::<f64>()
    }

    /// The BK main loop: grow, augment, adopt until no active node is left.
    #[inline(never)]
    fn run(&mut self) {
        let stride = self.stride as isize;
        let off = [-1isize, 1, -stride, stride];
        let mut time: u32 = 0;
        let mut current: Option<usize> = None;
        loop {
            // Pick the node to grow from: the current one if still in a tree, else the next active.
            let i = match current.take() {
                Some(i) if at(&mut self.nodes, i).tree != FREE => i,
                _ => {
                    let mut next = None;
                    while let Some(k) = self.active.pop() {
                        // The queue is a BFS front scattered over the grid: fetch the node a few places
                        // ahead (and its vertical neighbours) while this one is processed.
                        if let Some(f) = self.active.peek(PREFETCH_AHEAD) {
                            prefetch_around(&self.nodes, f as usize, stride as usize);
                        }
                        let k = k as usize;
                        at(&mut self.nodes, k).in_queue = 0;
                        if at(&mut self.nodes, k).tree != FREE {
                            next = Some(k);
                            break;
                        }
                    }
                    match next {
                        Some(k) => k,
                        None => break,
                    }
                }
            };

            // Growth.
            self.stats.growths += 1;
            let ni = *at(&mut self.nodes, i);
            let mut bridge: Option<(usize, usize, usize)> = None; // (source-tree node, sink-tree node, dir)
            if ni.tree == SRC {
                for d in 0..4 {
                    if ni.cap[d] > 0.0 {
                        let j = (i as isize + off[d]) as usize;
                        let nj = at(&mut self.nodes, j);
                        if nj.tree == FREE {
                            nj.tree = SRC;
                            self.trees[j] = SRC;
                            nj.parent = (d ^ 1) as u8;
                            nj.ts = ni.ts;
                            nj.dist = ni.dist + 1;
                            if nj.in_queue == 0 {
                                nj.in_queue = 1;
                                self.active.push(j as u32);
                            }
                        } else if nj.tree == SNK {
                            bridge = Some((i, j, d));
                            break;
                        } else if nj.ts <= ni.ts && nj.dist > ni.dist {
                            nj.parent = (d ^ 1) as u8;
                            nj.ts = ni.ts;
                            nj.dist = ni.dist + 1;
                        }
                    }
                }
            } else {
                for d in 0..4 {
                    let j = (i as isize + off[d]) as usize;
                    let nj = at(&mut self.nodes, j);
                    if nj.cap[d ^ 1] > 0.0 {
                        if nj.tree == FREE {
                            nj.tree = SNK;
                            self.trees[j] = SNK;
                            nj.parent = (d ^ 1) as u8;
                            nj.ts = ni.ts;
                            nj.dist = ni.dist + 1;
                            if nj.in_queue == 0 {
                                nj.in_queue = 1;
                                self.active.push(j as u32);
                            }
                        } else if nj.tree == SRC {
                            bridge = Some((j, i, d ^ 1));
                            break;
                        } else if nj.ts <= ni.ts && nj.dist > ni.dist {
                            nj.parent = (d ^ 1) as u8;
                            nj.ts = ni.ts;
                            nj.dist = ni.dist + 1;
                        }
                    }
                }
            }

            if let Some((s, t, d)) = bridge {
                time += 1;
                self.stats.augmentations += 1;
                self.augment(s, t, d, &off);
                self.adopt(time, &off);
                // Keep growing from the same node while it stays in a tree.
                current = Some(i);
            }
        }
    }

    #[inline]
    fn make_orphan(&mut self, u: usize) {
        at(&mut self.nodes, u).parent = ORPHAN;
        self.orphans.push(u as u32);
    }

    /// Pushes the bottleneck along source-root → s → t → sink-root; collects saturated tree edges'
    /// children as orphans.
    ///
    /// The first pass chases the parent links of both sides and records the nodes in `path`; the
    /// second pass updates the residuals from that list, so its iterations do not wait on each other.
    #[inline(never)]
    fn augment(&mut self, s: usize, t: usize, d: usize, off: &[isize; 4]) {
        let nodes = &mut self.nodes;
        let orphans = &mut self.orphans;
        let path = &mut self.path;
        path.clear();
        let mut b = at(nodes, s).cap[d];
        // Source side: edge parent → u has residual at(nodes, parent).cap[(p ^ 1) & 3].
        let mut u = s;
        loop {
            path.push(u as u32);
            let p = at(nodes, u).parent as usize;
            if p == TERMINAL as usize {
                break;
            }
            let par = (u as isize + off[p & 3]) as usize;
            b = fmin(b, at(nodes, par).cap[(p ^ 1) & 3]);
            u = par;
        }
        b = fmin(b, at(nodes, u).tr);
        let split = path.len();
        // Sink side: edge u → parent has residual at(nodes, u).cap[p & 3].
        let mut u = t;
        loop {
            path.push(u as u32);
            let p = at(nodes, u).parent as usize;
            if p == TERMINAL as usize {
                break;
            }
            b = fmin(b, at(nodes, u).cap[p & 3]);
            u = (u as isize + off[p & 3]) as usize;
        }
        b = fmin(b, -at(nodes, u).tr);

        self.augmented += b as f64;
        at(nodes, s).cap[d] -= b;
        at(nodes, t).cap[d ^ 1] += b;
        let (src_side, snk_side) = path.split_at(split);
        for pair in src_side.windows(2) {
            let (u, par) = (pair[0] as usize, pair[1] as usize);
            let p = at(nodes, u).parent as usize;
            at(nodes, par).cap[(p ^ 1) & 3] -= b;
            at(nodes, u).cap[p & 3] += b;
            if at(nodes, par).cap[(p ^ 1) & 3] == 0.0 {
                at(nodes, u).parent = ORPHAN;
                orphans.push(u as u32);
            }
        }
        if let Some(&root) = src_side.last() {
            let n = at(nodes, root as usize);
            n.tr -= b;
            if n.tr == 0.0 {
                n.parent = ORPHAN;
                orphans.push(root);
            }
        }
        for pair in snk_side.windows(2) {
            let (u, par) = (pair[0] as usize, pair[1] as usize);
            let p = at(nodes, u).parent as usize;
            at(nodes, u).cap[p & 3] -= b;
            at(nodes, par).cap[(p ^ 1) & 3] += b;
            if at(nodes, u).cap[p & 3] == 0.0 {
                at(nodes, u).parent = ORPHAN;
                orphans.push(u as u32);
            }
        }
        if let Some(&root) = snk_side.last() {
            let n = at(nodes, root as usize);
            n.tr += b;
            if n.tr == 0.0 {
                n.parent = ORPHAN;
                orphans.push(root);
            }
        }
        // Both sides hold at least their start node; each further node is one tree edge.
        self.stats.path_edges += 2 * (path.len() as u64 - 2);
    }

    /// Adoption stage: finds each orphan a new parent with a valid origin in its own tree, or frees it.
    #[inline(never)]
    fn adopt(&mut self, time: u32, off: &[isize; 4]) {
        let stride = off[3] as usize;
        while let Some(u) = self.orphans.pop() {
            if let Some(f) = self.orphans.peek(PREFETCH_AHEAD_ORPHANS) {
                prefetch_around(&self.nodes, f as usize, stride);
            }
            let u = u as usize;
            self.stats.orphans += 1;
            let tree = at(&mut self.nodes, u).tree;
            let mut best_dir = NO_PARENT;
            let mut best_dist = INF_DIST;
            for d in 0..4 {
                let j = (u as isize + off[d]) as usize;
                if at(&mut self.nodes, j).tree != tree {
                    continue;
                }
                let residual = if tree == SRC {
                    at(&mut self.nodes, j).cap[d ^ 1]
                } else {
                    at(&mut self.nodes, u).cap[d]
                };
                if residual <= 0.0 {
                    continue;
                }
                // Origin check: walk to the root, stopping at a node already verified this round.
                let mut k = j;
                let mut dist: u32 = 0;
                loop {
                    let nk = at(&mut self.nodes, k);
                    if nk.ts == time {
                        dist += nk.dist;
                        break;
                    }
                    let p = nk.parent;
                    dist += 1;
                    if p == TERMINAL {
                        nk.ts = time;
                        nk.dist = 1;
                        break;
                    }
                    if p >= ORPHAN {
                        dist = INF_DIST;
                        break;
                    }
                    k = (k as isize + off[p as usize & 3]) as usize;
                }
                if dist == INF_DIST {
                    continue;
                }
                if dist < best_dist {
                    best_dist = dist;
                    best_dir = d as u8;
                }
                // Stamp the verified path with exact distances.
                let mut k = j;
                let mut dk = dist;
                while at(&mut self.nodes, k).ts != time {
                    let nk = at(&mut self.nodes, k);
                    nk.ts = time;
                    nk.dist = dk;
                    dk -= 1;
                    k = (k as isize + off[nk.parent as usize & 3]) as usize;
                }
            }

            if best_dir != NO_PARENT {
                let nu = at(&mut self.nodes, u);
                nu.parent = best_dir;
                nu.ts = time;
                nu.dist = best_dist + 1;
                continue;
            }

            // No parent: free u; neighbours that could re-grow into it become active, its children orphans.
            for d in 0..4 {
                let j = (u as isize + off[d]) as usize;
                if at(&mut self.nodes, j).tree != tree {
                    continue;
                }
                let residual = if tree == SRC {
                    at(&mut self.nodes, j).cap[d ^ 1]
                } else {
                    at(&mut self.nodes, u).cap[d]
                };
                if residual > 0.0 && at(&mut self.nodes, j).in_queue == 0 {
                    at(&mut self.nodes, j).in_queue = 1;
                    self.active.push(j as u32);
                }
                if at(&mut self.nodes, j).parent as usize == d ^ 1 {
                    self.make_orphan(j);
                }
            }
            let nu = at(&mut self.nodes, u);
            nu.tree = FREE;
            nu.parent = NO_PARENT;
            self.trees[u] = FREE;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn rel_close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * a.abs().max(b.abs()).max(1.0)
    }

    fn brute_force_min(g: &GridGraph) -> f64 {
        let n = g.width() * g.height();
        let mut best = f64::INFINITY;
        let mut labels = vec![false; n];
        for mask in 0u32..(1u32 << n) {
            for (k, l) in labels.iter_mut().enumerate() {
                *l = (mask >> k) & 1 == 1;
            }
            best = best.min(g.cut_cost(&labels));
        }
        best
    }

    #[test]
    fn the_line_sweeps_give_the_same_residuals_in_avx_and_without() {
        // Lines of 50 nodes, eight lanes, residuals of both signs and capacities from a simple
        // generator; both builds of the sweeps must agree bit for bit.
        let mut seed = 12345u32;
        let mut next = || {
            seed = seed.wrapping_mul(1_103_515_245).wrapping_add(12_345);
            (seed >> 8) as f32 / (1u32 << 24) as f32
        };
        let mut lanes = |len: usize, signed: bool| -> Vec<Lanes> {
            (0..len)
                .map(|_| std::array::from_fn(|_| if signed { 2.0 * next() - 1.0 } else { next() }))
                .collect()
        };
        let start = LineScratch {
            tr: lanes(50, true),
            lo: lanes(50, false),
            hi: lanes(50, false),
            demand: vec![[0.0; LINE_BATCH]; 51],
        };
        let (mut plain, mut dispatched) = (start.clone(), start.clone());
        sweep_both_ways_with(&mut plain);
        sweep_both_ways(&mut dispatched);
        assert_ne!(plain.tr, start.tr, "something flowed");
        let bits = |s: &LineScratch| {
            [&s.tr, &s.lo, &s.hi]
                .map(|v| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>())
        };
        assert_eq!(bits(&plain), bits(&dispatched));
    }

    #[test]
    fn cross_flags_look_at_a_node_and_its_four_neighbours() {
        // A padded 3x2 grid (stride 5): S = source tree, T = sink tree, . = free.
        //   . . . . .
        //   . S S T .
        //   . S . S .
        //   . . . . .
        let (f, s, t) = (FREE, SRC, SNK);
        #[rustfmt::skip]
        let trees = [
            f, f, f, f, f,
            f, s, s, t, f,
            f, s, f, s, f,
            f, f, f, f, f,
        ];
        let mut flags = [9u8; 3];
        // Free nodes next to a tree: only the free one in the second row.
        cross_flags(&trees, 6, 5, &mut flags, |c, n| {
            (c == FREE) & (n != [FREE; 4])
        });
        assert_eq!(flags, [0, 0, 0]);
        cross_flags(&trees, 11, 5, &mut flags, |c, n| {
            (c == FREE) & (n != [FREE; 4])
        });
        assert_eq!(flags, [0, 1, 0]);
        // Tree nodes with a neighbour outside their tree: every one here touches the padding.
        cross_flags(&trees, 6, 5, &mut flags, |c, n| (c != FREE) & (n != [c; 4]));
        assert_eq!(flags, [1, 1, 1]);
        // Part of a row: the middle node of the first row alone.
        let mut one = [9u8; 1];
        cross_flags(&trees, 7, 5, &mut one, |c, n| {
            c == SRC && n == [SRC, SNK, FREE, FREE]
        });
        assert_eq!(one, [1]);
    }

    #[test]
    fn two_by_one_by_hand() {
        // a=(0,0): src 5, sink 1; b=(1,0): src 1, sink 4; edge a–b weight 2.
        // Labellings (a,b): (S,S): sink a + sink b = 1+4 = 5; (T,T): 5+1 = 6;
        // (S,T): sink a + src b + w = 1+1+2 = 4; (T,S): 5+4+2 = 11. Min cut 4, a source side, b sink side.
        let mut g = GridGraph::new(2, 1);
        g.set_terminal(0, 0, 5.0, 1.0);
        g.set_terminal(1, 0, 1.0, 4.0);
        g.set_right(0, 0, 2.0);
        let r = GridMaxFlow::new().solve(&g);
        assert!((r.flow - 4.0).abs() < 1e-9, "flow {}", r.flow);
        assert_eq!(r.labels, vec![true, false]);
        assert!((g.cut_cost(&r.labels) - 4.0).abs() < 1e-9);
    }

    #[test]
    fn two_by_two_by_hand() {
        // Nodes a=(0,0) b=(1,0) c=(0,1) d=(1,1).
        // a: src 10 sink 0; d: src 0 sink 10; b, c: no terminal links.
        // Edges: a–b 3, c–d 4 (right); a–c 2, b–d 1 (down).
        // Any cut must separate a (S) from d (T). Paths a-b-d (min(3,1)=1) and a-c-d (min(2,4)=2):
        // max flow 3. Min cut {a,c} | {b,d}: cuts a–b (3) + c–d (4) = 7; {a} | rest: 3+2 = 5;
        // {a,b,c} | {d}: 1+4 = 5; {a,b} | {c,d}: 2+1 = 3  <- minimum = 3.
        let mut g = GridGraph::new(2, 2);
        g.set_terminal(0, 0, 10.0, 0.0);
        g.set_terminal(1, 1, 0.0, 10.0);
        g.set_right(0, 0, 3.0);
        g.set_right(0, 1, 4.0);
        g.set_down(0, 0, 2.0);
        g.set_down(1, 0, 1.0);
        let r = GridMaxFlow::new().solve(&g);
        assert!((r.flow - 3.0).abs() < 1e-9, "flow {}", r.flow);
        assert_eq!(r.labels, vec![true, true, false, false]);
        assert!((brute_force_min(&g) - 3.0).abs() < 1e-9);
    }

    #[test]
    fn line_passes_route_chains_both_ways() {
        // One row (or column): source 5 at one end, sink 3 at the other, every edge 4. The max flow
        // 3 goes along the line, which the line passes find alone, so the search trees have
        // nothing left to augment.
        for (vertical, backwards) in [(false, false), (false, true), (true, false), (true, true)] {
            let (w, h) = if vertical { (1, 6) } else { (6, 1) };
            let mut g = GridGraph::new(w, h);
            let (a, b) = if backwards { (5, 0) } else { (0, 5) };
            let at = |k: usize| if vertical { (0, k) } else { (k, 0) };
            g.set_terminal(at(a).0, at(a).1, 5.0, 0.0);
            g.set_terminal(at(b).0, at(b).1, 0.0, 3.0);
            for k in 0..5 {
                if vertical {
                    g.set_down(0, k, 4.0);
                } else {
                    g.set_right(k, 0, 4.0);
                }
            }
            let mut mf = GridMaxFlow::new();
            let r = mf.solve(&g);
            assert!((r.flow - 3.0).abs() < 1e-9, "flow {}", r.flow);
            assert_eq!(mf.stats().augmentations, 0);
            assert!((g.cut_cost(&r.labels) - 3.0).abs() < 1e-9);
        }
    }

    /// A `w`×`h` grid whose capacities are `step` × 0..`levels` from a linear congruential sequence
    /// started at `seed` (ties and zeros on purpose).
    fn lcg_grid(w: usize, h: usize, seed: u32, levels: u32, step: f32) -> GridGraph {
        let mut g = GridGraph::new(w, h);
        let mut r = seed;
        let mut next = || {
            r = r.wrapping_mul(1_103_515_245).wrapping_add(12_345);
            ((r >> 16) % levels) as f32 * step
        };
        for y in 0..h {
            for x in 0..w {
                let (a, b) = (next(), next());
                g.set_terminal(x, y, a, b);
                if x + 1 < w {
                    let v = next();
                    g.set_right(x, y, v);
                }
                if y + 1 < h {
                    let v = next();
                    g.set_down(x, y, v);
                }
            }
        }
        g
    }

    #[test]
    fn line_pass_batches_match_plain_search() {
        // 19 rows and 9 columns: full and partial batches of rows and of columns.
        let (w, h) = (LINE_BATCH + 1, 2 * LINE_BATCH + 3);
        let g = lcg_grid(w, h, 7, 9, 0.5);
        let with = GridMaxFlow::new().solve(&g);
        let mut plain = GridMaxFlow::new();
        plain.set_prepass(false);
        let without = plain.solve(&g);
        assert!(
            rel_close(with.flow, without.flow, 1e-6),
            "{} vs {}",
            with.flow,
            without.flow
        );
        assert!(rel_close(with.flow, g.cut_cost(&with.labels), 1e-6));
    }

    #[test]
    fn free_nodes_start_attached_to_a_neighbouring_root() {
        // Row of three: source root, free node, sink root (pre-pass off, so nothing moves first).
        // The free node joins the source root if it can receive from it, else the sink root.
        for (w01, tree, parent) in [(4.0, SRC, 0u8), (0.0, SNK, 1u8)] {
            let mut g = GridGraph::new(3, 1);
            g.set_terminal(0, 0, 5.0, 0.0);
            g.set_terminal(2, 0, 0.0, 3.0);
            g.set_right(0, 0, w01);
            g.set_right(1, 0, 4.0);
            let mut mf = GridMaxFlow::new();
            mf.set_prepass(false);
            mf.prepare(&g);
            let middle = mf.nodes[mf.stride + 2];
            assert_eq!((middle.tree, middle.parent, middle.dist), (tree, parent, 2));
            let r = mf.solve(&g);
            let expected = if w01 > 0.0 { 3.0 } else { 0.0 };
            assert!((r.flow - expected).abs() < 1e-9, "flow {}", r.flow);
            assert!((g.cut_cost(&r.labels) - expected).abs() < 1e-9);
        }
    }

    #[test]
    fn empty_and_single() {
        let r = GridMaxFlow::new().solve(&GridGraph::new(0, 5));
        assert_eq!(r.flow, 0.0);
        assert!(r.labels.is_empty());
        let mut g = GridGraph::new(1, 1);
        g.set_terminal(0, 0, 2.0, 3.0);
        let r = GridMaxFlow::new().solve(&g);
        assert_eq!(r.flow, 2.0);
        assert_eq!(r.labels, vec![false]);
    }

    #[test]
    fn from_parts_names_field() {
        let e = GridGraph::from_parts(3, 2, vec![0.0; 6], vec![0.0; 6], vec![0.0; 4], vec![0.0; 2])
            .unwrap_err();
        assert!(matches!(
            e,
            GraphError::LengthMismatch {
                field: "down",
                expected: 3,
                actual: 2
            }
        ));
        let mut sink = vec![0.0; 6];
        sink[4] = f32::NAN;
        let e = GridGraph::from_parts(3, 2, vec![0.0; 6], sink, vec![0.0; 4], vec![0.0; 3])
            .unwrap_err();
        assert!(matches!(
            e,
            GraphError::BadValue {
                field: "sink",
                index: 4,
                ..
            }
        ));
        assert!(e.to_string().contains("sink"));
        let e = GridGraph::from_parts(
            3,
            2,
            vec![0.0; 6],
            vec![0.0; 6],
            vec![-1.0; 4],
            vec![0.0; 3],
        )
        .unwrap_err();
        assert!(matches!(
            e,
            GraphError::BadValue {
                field: "right",
                index: 0,
                ..
            }
        ));
        assert!(GridGraph::from_parts(1, 1, vec![1.0], vec![2.0], vec![], vec![]).is_ok());
    }

    #[test]
    fn reuse_does_not_reallocate() {
        let mut g = GridGraph::new(7, 5);
        for y in 0..5 {
            for x in 0..7 {
                g.set_terminal(x, y, (x * 3 % 5) as f32, (y * 7 % 4) as f32);
            }
        }
        let mut mf = GridMaxFlow::new();
        let a = mf.solve(&g);
        let p = (
            mf.nodes.as_ptr(),
            mf.nodes.capacity(),
            mf.trees.as_ptr(),
            mf.active.capacity(),
            mf.orphans.capacity(),
        );
        let b = mf.solve(&g);
        assert_eq!(
            p,
            (
                mf.nodes.as_ptr(),
                mf.nodes.capacity(),
                mf.trees.as_ptr(),
                mf.active.capacity(),
                mf.orphans.capacity()
            )
        );
        assert_eq!(a, b);
    }

    #[test]
    fn reuse_across_shapes() {
        // 3x4 and 4x3 have the same padded node count: the padding ring must be reset.
        let mut mf = GridMaxFlow::new();
        for (k, (w, h)) in [(3, 4), (4, 3), (3, 4), (10, 1), (1, 10), (5, 5)]
            .into_iter()
            .enumerate()
        {
            let g = lcg_grid(w, h, k as u32 + 1, 7, 1.0);
            let r = mf.solve(&g);
            let fresh = GridMaxFlow::new().solve(&g);
            assert!(
                rel_close(r.flow, fresh.flow, 1e-6),
                "{w}x{h}: {} vs {}",
                r.flow,
                fresh.flow
            );
            assert!(rel_close(r.flow, g.cut_cost(&r.labels), 1e-6));
            assert!(w * h > 20 || rel_close(r.flow, brute_force_min(&g), 1e-6));
        }
    }

    /// Capacity drawn from a small set (zeros and ties likely) or a continuous range.
    fn cap() -> impl Strategy<Value = f32> {
        prop_oneof![
            3 => Just(0.0f32),
            3 => (1u8..4).prop_map(|v| v as f32),
            4 => 0.0f32..10.0,
        ]
    }

    fn graph(max_w: usize, max_h: usize) -> impl Strategy<Value = GridGraph> {
        (1..=max_w, 1..=max_h).prop_flat_map(|(w, h)| {
            let n = w * h;
            (
                proptest::collection::vec(cap(), n),
                proptest::collection::vec(cap(), n),
                proptest::collection::vec(cap(), h * (w - 1)),
                proptest::collection::vec(cap(), (h - 1) * w),
            )
                .prop_map(move |(s, t, r, d)| GridGraph::from_parts(w, h, s, t, r, d).unwrap())
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(400))]
        #[test]
        fn small_graphs_match_brute_force(g in graph(4, 4), prepass in any::<bool>()) {
            let mut mf = GridMaxFlow::new();
            mf.prepass = prepass;
            let r = mf.solve(&g);
            let cut = g.cut_cost(&r.labels);
            prop_assert!(rel_close(r.flow, cut, 1e-4), "flow {} cut {}", r.flow, cut);
            let best = brute_force_min(&g);
            prop_assert!(rel_close(r.flow, best, 1e-4), "flow {} brute {}", r.flow, best);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(60))]
        #[test]
        fn grid_30x20_flow_equals_cut(
            s in proptest::collection::vec(cap(), 600),
            t in proptest::collection::vec(cap(), 600),
            r in proptest::collection::vec(cap(), 20 * 29),
            d in proptest::collection::vec(cap(), 19 * 30),
        ) {
            let g = GridGraph::from_parts(30, 20, s, t, r, d).unwrap();
            let mut mf = GridMaxFlow::new();
            let a = mf.solve(&g);
            let cut = g.cut_cost(&a.labels);
            prop_assert!(rel_close(a.flow, cut, 1e-4), "flow {} cut {}", a.flow, cut);
            let b = mf.solve(&g);
            prop_assert_eq!(a.flow, b.flow);
            let mut plain = GridMaxFlow::new();
            plain.prepass = false;
            let c = plain.solve(&g);
            prop_assert!(rel_close(a.flow, c.flow, 1e-4), "prepass {} plain {}", a.flow, c.flow);
        }
    }
}
