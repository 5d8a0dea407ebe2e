//! Clean-up of the cut: keep the person's region, fill its small holes, remove what cannot be suit,
//! attach head, hands and shoes.
//!
//! The min-cut labels every pixel independently of any notion of "one person", so stray foreground
//! (a suit-coloured object in the room) and small background holes (a shadowed fold) remain.
//! [`keep_person_region`] labels the 4-connected foreground components, keeps the one with the highest
//! score (the caller scores pixels, e.g. suit cloth next to a marker, so that a large flat green poster
//! does not beat a smaller person) if it is big enough, with the pieces of suit near it that something
//! in front cut off ([`RegionRule`]), and removes the rest; [`fill_holes`] fills background components
//! that do not touch the image border and are smaller than a limit. Both report what they changed,
//! which the segmenter passes on in its output. [`clean`] runs both on the box around the foreground
//! only ([`PixelBox`]), with the same result as on the whole grid. [`remove_large_off_cloth`] takes
//! out the pieces of the region that are not cloth and too large for a marker, and
//! [`remove_far_from_markers`] the cloth farther from every marker than the suit's can be.
//! [`attach_parts`] then grows the suit into a band around it ([`part_band`]) through pixels of a
//! part's colour, in pieces shaped like a head, a hand or a shoe ([`PartLimits`]); [`expected_head`]
//! and [`expected_shoes`] mark where a head is expected above the suit and shoes below it, for a
//! last look where less was found. The person mask goes to the refinement at full resolution,
//! whose result [`fill_suit_holes`] rids of the holes that are mostly the suit's colours.

use crate::mask::bounding_box_of;

/// What the clean-up changed in one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CleanupReport {
    pub components_removed: usize,
    pub pixels_removed: usize,
    pub holes_filled: usize,
    pub pixels_filled: usize,
    /// Pieces of the cut too large for a marker that are not cloth ([`remove_large_off_cloth`]).
    pub off_cloth_pieces: usize,
    pub off_cloth_pixels: usize,
    /// Pixels of the cut farther from every marker than the suit's cloth can be
    /// ([`remove_far_from_markers`]).
    pub far_from_markers_pixels: usize,
    /// Holes of the suit's colours filled in the full-resolution mask ([`fill_suit_holes`]), and
    /// their pixels (frame pixels, not the cut's).
    pub suit_holes_filled: usize,
    pub suit_hole_pixels: usize,
}

/// 4-connected components of pixels equal to `value`; returns the component id of every pixel
/// (`u32::MAX` for the other value) and each component's pixel count and whether it touches the border.
pub fn components(
    labels: &[bool],
    width: usize,
    height: usize,
    value: bool,
    ids: &mut Vec<u32>,
) -> Vec<(usize, bool)> {
    ids.clear();
    ids.resize(labels.len(), u32::MAX);
    let mut stats = Vec::new();
    let mut stack = Vec::new();
    for start in 0..labels.len() {
        if labels[start] != value || ids[start] != u32::MAX {
            continue;
        }
        let id = stats.len() as u32;
        let (mut count, mut border) = (0usize, false);
        ids[start] = id;
        stack.push(start);
        while let Some(i) = stack.pop() {
            count += 1;
            let (x, y) = (i % width, i / width);
            border |= x == 0 || y == 0 || x + 1 == width || y + 1 == height;
            for j in neighbours4(i, width, height).into_iter().flatten() {
                if labels[j] == value && ids[j] == u32::MAX {
                    ids[j] = id;
                    stack.push(j);
                }
            }
        }
        stats.push((count, border));
    }
    stats
}

/// How [`keep_person_region`] picks the person among the foreground components.
pub struct RegionRule<'a> {
    /// Per pixel: how much it looks like the person (e.g. suit cloth next to a marker).
    pub score: &'a dyn Fn(usize) -> f32,
    /// Per pixel: does it have a marker's colour?
    pub marker: &'a dyn Fn(usize) -> bool,
    /// The main region has at least this many pixels.
    pub min_area: usize,
    /// Pieces are kept within this share of the main region's height of it (0: none).
    pub reach: f32,
}

/// Keeps the foreground component with the highest total `score` (ties: the larger) if it has at
/// least `min_area` pixels, and with it the other components of at least a quarter of `min_area`
/// whose score per pixel and share of marker pixels are at least half of its own and that come
/// within `reach` × its height of it. The person is one region unless something in front of them
/// — their own hand on the hip, a passing object — cuts the suit in two; the pieces are then as
/// suit-like as the main one, markers included, and near it, while a leak into a suit-coloured
/// part of the room is cloth colour without markers. Everything else is cleared; with no
/// component that large the mask becomes empty.
pub fn keep_person_region(
    labels: &mut [bool],
    width: usize,
    height: usize,
    rule: &RegionRule,
    ids: &mut Vec<u32>,
) -> CleanupReport {
    let RegionRule {
        score,
        marker,
        min_area,
        reach,
    } = *rule;
    let stats = components(labels, width, height, true, ids);
    let (mut scores, mut markers) = (vec![0.0f32; stats.len()], vec![0usize; stats.len()]);
    for (i, &id) in ids.iter().enumerate() {
        if id != u32::MAX {
            scores[id as usize] += score(i);
            markers[id as usize] += marker(i) as usize;
        }
    }
    let best = (0..stats.len())
        .filter(|&c| stats[c].0 >= min_area)
        .max_by(|&a, &b| {
            scores[a]
                .total_cmp(&scores[b])
                .then(stats[a].0.cmp(&stats[b].0))
        });
    let mut keep = vec![false; stats.len()];
    if let Some(best) = best {
        keep[best] = true;
        let density = |c: usize| scores[c] / stats[c].0 as f32;
        let marker_share = |c: usize| markers[c] as f32 / stats[c].0 as f32;
        let candidate = |c: usize| {
            c != best
                && 4 * stats[c].0 >= min_area
                && density(c) >= 0.5 * density(best)
                && marker_share(c) >= 0.5 * marker_share(best)
        };
        // The main region's own mask and distance map, only when some piece could be kept.
        if reach > 0.0 && (0..stats.len()).any(candidate) {
            let main: Vec<bool> = ids.iter().map(|&id| id == best as u32).collect();
            let pixels = (reach * region_height(&main, width) as f32).ceil() as usize;
            let mut distance = Vec::new();
            if let Some(b) = distance_near(&main, width, height, pixels, &mut distance) {
                for y in b.y0..b.y1 {
                    for x in b.x0..b.x1 {
                        let id = ids[y * width + x];
                        if id != u32::MAX
                            && candidate(id as usize)
                            && distance[(y - b.y0) * b.width() + x - b.x0] as usize <= 3 * pixels
                        {
                            keep[id as usize] = true;
                        }
                    }
                }
            }
        }
    }
    let mut report = CleanupReport::default();
    for (c, &(count, _)) in stats.iter().enumerate() {
        if !keep[c] {
            report.components_removed += 1;
            report.pixels_removed += count;
        }
    }
    for (label, &id) in labels.iter_mut().zip(ids.iter()) {
        if id != u32::MAX && !keep[id as usize] {
            *label = false;
        }
    }
    report
}

/// Fills background components that do not touch the border and have at most `max_hole` pixels.
pub fn fill_holes(
    labels: &mut [bool],
    width: usize,
    height: usize,
    max_hole: usize,
    ids: &mut Vec<u32>,
    report: &mut CleanupReport,
) {
    let stats = components(labels, width, height, false, ids);
    let fill: Vec<bool> = stats
        .iter()
        .map(|&(count, border)| !border && count <= max_hole)
        .collect();
    for (c, &f) in fill.iter().enumerate() {
        if f {
            report.holes_filled += 1;
            report.pixels_filled += stats[c].0;
        }
    }
    for (label, &id) in labels.iter_mut().zip(ids.iter()) {
        if id != u32::MAX && fill[id as usize] {
            *label = true;
        }
    }
}

/// Fills the enclosed background components (4-connected, not reaching the image's border) of at
/// most `max_hole` pixels of which at least `min_suit_share` are of the suit's colours (`is_suit`,
/// by index into `labels`): a marker or two that the cut or the refinement left out because the
/// room has their colour, where the room seen through a gap between the limbs shows the room's
/// colours. Returns the holes and the pixels filled.
///
/// It runs on the full-resolution mask of every frame, so it labels background *runs* (a row's
/// stretch of background pixels) rather than pixels, joining the runs of neighbouring rows that
/// overlap; only the pixels of the holes small enough are looked at one by one. Within the box
/// around the person, a run that reaches the box's edge is the room around the person.
pub fn fill_suit_holes(
    labels: &mut [bool],
    (width, height): (usize, usize),
    (max_hole, min_suit_share): (usize, f32),
    is_suit: impl Fn(usize) -> bool,
    runs: &mut Vec<HoleRun>,
    parent: &mut Vec<u32>,
) -> (usize, usize) {
    let Some((x0, y0, x1, y1)) =
        bounding_box_of(&labels[..(width * height).min(labels.len())], width)
    else {
        return (0, 0);
    };
    runs.clear();
    parent.clear();
    // Background runs row by row, each joined to the overlapping runs of the row above.
    let mut above = 0..0;
    for y in y0..y1 {
        let row = &labels[y * width..y * width + width];
        let start = runs.len();
        let mut x = x0;
        while x < x1 {
            if row[x] {
                x += 1;
                continue;
            }
            let from = x;
            while x < x1 && !row[x] {
                x += 1;
            }
            let id = runs.len() as u32;
            runs.push(HoleRun {
                y,
                x: from..x,
                open: from == x0 || x == x1 || y == y0 || y + 1 == y1,
            });
            parent.push(id);
            for k in above.clone() {
                let r = &runs[k];
                if r.x.start < x && from < r.x.end {
                    let (a, b) = (find_root(parent, id), find_root(parent, k as u32));
                    parent[a.max(b)] = a.min(b) as u32;
                }
            }
        }
        above = start..runs.len();
    }
    // Per component (its root): pixels and whether it reaches the box's edge.
    let mut size = vec![0usize; runs.len()];
    let mut open = vec![false; runs.len()];
    for (k, run) in runs.iter().enumerate() {
        let root = find_root(parent, k as u32);
        parent[k] = root as u32; // every run now points at its root
        size[root] += run.x.len();
        open[root] |= run.open;
    }
    let candidate = |root: usize| !open[root] && size[root] <= max_hole;
    let mut suit = vec![0usize; runs.len()];
    for (k, run) in runs.iter().enumerate() {
        let root = parent[k] as usize;
        if candidate(root) {
            suit[root] += run
                .x
                .clone()
                .filter(|&x| is_suit(run.y * width + x))
                .count();
        }
    }
    let fill: Vec<bool> = (0..runs.len())
        .map(|root| candidate(root) && suit[root] as f32 >= min_suit_share * size[root] as f32)
        .collect();
    let (mut holes, mut pixels) = (0, 0);
    for (k, run) in runs.iter().enumerate() {
        let root = parent[k] as usize;
        if fill[root] {
            labels[run.y * width + run.x.start..run.y * width + run.x.end].fill(true);
            holes += (root == k) as usize;
            pixels += run.x.len();
        }
    }
    (holes, pixels)
}

/// A row's stretch of background pixels within the box around the person, for
/// [`fill_suit_holes`]; `open` when it touches the box's edge.
#[derive(Clone, Debug)]
pub struct HoleRun {
    y: usize,
    x: std::ops::Range<usize>,
    open: bool,
}

/// The root of `i` in a union-find forest, halving the path on the way.
pub(crate) fn find_root(parent: &mut [u32], mut i: u32) -> usize {
    while parent[i as usize] != i {
        let grand = parent[parent[i as usize] as usize];
        parent[i as usize] = grand;
        i = grand;
    }
    i as usize
}

/// A rectangle of grid pixels, columns `x0..x1` and rows `y0..y1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelBox {
    pub x0: usize,
    pub y0: usize,
    pub x1: usize,
    pub y1: usize,
}

impl PixelBox {
    /// The box around the set pixels of `region` (row-major, `width` × `height`), grown by `margin`
    /// on each side and clipped to the grid; `None` when no pixel is set.
    pub fn around(region: &[bool], width: usize, height: usize, margin: usize) -> Option<PixelBox> {
        let grid = &region[..(width * height).min(region.len())];
        let (x0, y0, x1, y1) = bounding_box_of(grid, width)?;
        Some(PixelBox {
            x0: x0.saturating_sub(margin),
            y0: y0.saturating_sub(margin),
            x1: (x1 + margin).min(width),
            y1: (y1 + margin).min(height),
        })
    }

    pub fn width(&self) -> usize {
        self.x1 - self.x0
    }

    pub fn height(&self) -> usize {
        self.y1 - self.y0
    }

    pub fn contains(&self, x: usize, y: usize) -> bool {
        (self.x0..self.x1).contains(&x) && (self.y0..self.y1).contains(&y)
    }

    /// Index in the `width`-wide grid of index `i` of the box's own (row-major) pixels.
    #[inline]
    pub fn grid_index(&self, i: usize, width: usize) -> usize {
        (self.y0 + i / self.width()) * width + self.x0 + i % self.width()
    }

    /// The box's pixels of `grid` (`width` wide), row-major, into `out`.
    pub fn crop<T: Copy>(&self, grid: &[T], width: usize, out: &mut Vec<T>) {
        out.clear();
        for y in self.y0..self.y1 {
            out.extend_from_slice(&grid[y * width + self.x0..y * width + self.x1]);
        }
    }

    /// Writes `crop` (the box's pixels, row-major) back into `grid` (`width` wide).
    pub fn paste<T: Copy>(&self, crop: &[T], width: usize, grid: &mut [T]) {
        for (y, row) in (self.y0..self.y1).zip(crop.chunks_exact(self.width().max(1))) {
            grid[y * width + self.x0..y * width + self.x1].copy_from_slice(row);
        }
    }
}

/// [`keep_person_region`] (when a `rule` is given) then [`fill_holes`], computed on the box around the
/// foreground grown by one pixel and clipped to the grid: the same result as on the whole grid, in
/// time that grows with the person rather than the frame. Every foreground component lies inside
/// the box; the box's edge is background, and a background component that touches it is joined to
/// the region around the person, which reaches the image border, so it is not a hole.
pub fn clean(
    labels: &mut [bool],
    width: usize,
    height: usize,
    rule: Option<&RegionRule>,
    max_hole: usize,
    crop: &mut Vec<bool>,
    ids: &mut Vec<u32>,
) -> CleanupReport {
    let Some(b) = PixelBox::around(labels, width, height, 1) else {
        return CleanupReport::default();
    };
    b.crop(labels, width, crop);
    let (bw, bh) = (b.width(), b.height());
    let mut report = match rule {
        Some(rule) => {
            let score = |i: usize| (rule.score)(b.grid_index(i, width));
            let marker = |i: usize| (rule.marker)(b.grid_index(i, width));
            let in_box = RegionRule {
                score: &score,
                marker: &marker,
                ..*rule
            };
            keep_person_region(crop, bw, bh, &in_box, ids)
        }
        None => CleanupReport::default(),
    };
    fill_holes(crop, bw, bh, max_hole, ids, &mut report);
    b.paste(crop, width, labels);
    report
}

/// The 3-4 chamfer distance (3 per pixel step, 4 per diagonal) from the set pixels of `region`, on
/// the box around them grown by `reach` pixels, into `distance` (box-sized, row-major); returns the
/// box, `None` when no pixel is set. Exact up to `reach` pixels from the region — a chamfer path that
/// short stays within the box — and every pixel outside the box is farther than `reach`.
pub fn distance_near(
    region: &[bool],
    width: usize,
    height: usize,
    reach: usize,
    distance: &mut Vec<u16>,
) -> Option<PixelBox> {
    let b = PixelBox::around(region, width, height, reach)?;
    chamfer_in_box(b, |x, y| region[y * width + x], distance);
    Some(b)
}

/// The 3-4 chamfer distance within the box `b` from the grid pixels `(x, y)` that `seed` accepts,
/// into `distance` (box-sized, row-major).
fn chamfer_in_box(b: PixelBox, seed: impl Fn(usize, usize) -> bool, distance: &mut Vec<u16>) {
    distance.clear();
    for y in b.y0..b.y1 {
        distance.extend((b.x0..b.x1).map(|x| if seed(x, y) { 0 } else { super::features::FAR }));
    }
    super::features::chamfer(distance, b.width(), b.height());
}

/// How far the person's parts outside the suit (head, hands, shoes) reach from it, as a share of the
/// suit region's height: the head of an upright person is about an eighth of their height. The
/// band in which training counts the part colours, and how near the main region another piece of
/// suit is kept.
pub const PART_REACH: f32 = 0.15;

/// How far the segmenter looks for the head, hands and shoes around the suit at run time, as a
/// share of the suit region's height. A head with its neck is 0.16–0.2 of it, and the band of
/// [`PART_REACH`] cut the top off upright heads (walk 02_01 over the moving video). On the six
/// pose test sequences with the shipped tables 0.15 → 0.2 gave 0.9229, 0.8212, 0.9440, 0.9526,
/// 0.9421, 0.8474 → 0.9292, 0.8220, 0.9514, 0.9510, 0.9501, 0.8633 IoU, and the default suit's
/// weight search the same weights (docs/measurements.md, second session of 2026-12-05). A head
/// that the wide band joins to background of its colour is looked for again within
/// [`PART_REACH`] ([`attach_parts_narrowing`]).
pub const ATTACH_REACH: f32 = 0.2;

/// The 4-neighbours of pixel `i` of a `width` × `height` grid (`None` beyond its edges).
#[inline]
pub fn neighbours4(i: usize, width: usize, height: usize) -> [Option<usize>; 4] {
    let (x, y) = (i % width, i / width);
    [
        (x > 0).then(|| i - 1),
        (x + 1 < width).then(|| i + 1),
        (y > 0).then(|| i - width),
        (y + 1 < height).then(|| i + width),
    ]
}

/// Unlabels every 4-connected piece of `region ∧ off_cloth` larger than `max_area` pixels and
/// returns how many pieces and pixels that removed. On the suit everything that is not cloth is a
/// marker, and markers are 4 cm squares with 3 cm of cloth between them, so a larger piece of the
/// person's region that is not cloth is background the cut took in (an orange, a tabby cat,
/// skin-coloured wood between the legs; the head, hands and shoes are attached afterwards). The
/// pieces are the [`components`] of the box around the region; `crop` and `ids` are scratch.
pub fn remove_large_off_cloth(
    region: &mut [bool],
    width: usize,
    height: usize,
    off_cloth: impl Fn(usize) -> bool,
    max_area: usize,
    crop: &mut Vec<bool>,
    ids: &mut Vec<u32>,
) -> (usize, usize) {
    let Some(b) = PixelBox::around(region, width, height, 0) else {
        return (0, 0);
    };
    crop.clear();
    crop.extend((0..b.width() * b.height()).map(|k| {
        let i = b.grid_index(k, width);
        region[i] && off_cloth(i)
    }));
    let stats = components(crop, b.width(), b.height(), true, ids);
    let too_large = |count: usize| count > max_area;
    for (k, _) in ids
        .iter()
        .enumerate()
        .filter(|&(_, &id)| id != u32::MAX && too_large(stats[id as usize].0))
    {
        region[b.grid_index(k, width)] = false;
    }
    let mut removed = (0, 0);
    for &(count, _) in stats.iter().filter(|&&(count, _)| too_large(count)) {
        removed = (removed.0 + 1, removed.1 + count);
    }
    removed
}

/// Unlabels the pixels of `region` farther than `reach` pixels (the 3-4 chamfer distance) from
/// every marker of the region, and returns how many. The markers are the pixels of a marker's
/// colour (`marker`) in the region or in a hole of it up to `hole` pixels across (the cut can
/// leave a marker out of the suit around it): outside the region, a pixel with region within
/// `hole` pixels left, right, above and below it. The suit prints a marker in every cell of its
/// grid, so its cloth is never far from one; a cloth-coloured object that the cut joined to the
/// person is, beyond a stretch of it, and the room beside it does not count even where it has a
/// marker's colour. `distance` is scratch.
pub fn remove_far_from_markers(
    region: &mut [bool],
    width: usize,
    height: usize,
    marker: impl Fn(usize) -> bool,
    (reach, hole): (usize, usize),
    distance: &mut Vec<u16>,
) -> usize {
    let Some(b) = PixelBox::around(region, width, height, 0) else {
        return 0;
    };
    // Region within `hole` pixels of (x, y) along (dx, dy).
    let region_along = |(x, y): (usize, usize), (dx, dy): (isize, isize)| {
        (1..=hole as isize).any(|step| {
            let (nx, ny) = (x as isize + dx * step, y as isize + dy * step);
            (0..width as isize).contains(&nx)
                && (0..height as isize).contains(&ny)
                && region[ny as usize * width + nx as usize]
        })
    };
    chamfer_in_box(
        b,
        |x, y| {
            let i = y * width + x;
            marker(i)
                && (region[i]
                    || [(-1, 0), (1, 0), (0, -1), (0, 1)]
                        .into_iter()
                        .all(|d| region_along((x, y), d)))
        },
        distance,
    );
    let limit = (3 * reach.min(super::features::FAR as usize / 3)) as u16;
    let mut removed = 0;
    for (y, row) in (b.y0..b.y1).zip(distance.chunks_exact(b.width())) {
        let pixels = &mut region[y * width + b.x0..y * width + b.x1];
        for (p, &d) in pixels.iter_mut().zip(row) {
            if *p && d > limit {
                *p = false;
                removed += 1;
            }
        }
    }
    removed
}

/// Rows spanned by the set pixels of `region` (row-major, `width` wide); 0 when none is set.
pub fn region_height(region: &[bool], width: usize) -> usize {
    let first = region.iter().position(|&p| p);
    let last = region.iter().rposition(|&p| p);
    match (first, last) {
        (Some(a), Some(b)) => b / width - a / width + 1,
        _ => 0,
    }
}

/// The attachment band: pixels not in `suit` within `reach` (e.g. [`PART_REACH`]) of the suit
/// region's height of it (see [`part_bands`]).
pub fn part_band(
    suit: &[bool],
    width: usize,
    height: usize,
    reach: f32,
    distance: &mut Vec<u16>,
    band: &mut Vec<bool>,
) {
    let mut none = Vec::new();
    part_bands(
        suit,
        width,
        height,
        (reach, 0.0),
        distance,
        (band, &mut none),
    );
}

/// The attachment bands: pixels not in `suit` within `reach` (e.g. [`ATTACH_REACH`]) of the suit
/// region's height of it into `band`, and within the smaller `narrow_reach` (e.g. [`PART_REACH`])
/// into `narrow` (3-4 chamfer distance, written to `distance`, computed once for both).
pub fn part_bands(
    suit: &[bool],
    width: usize,
    height: usize,
    (reach, narrow_reach): (f32, f32),
    distance: &mut Vec<u16>,
    (band, narrow): (&mut Vec<bool>, &mut Vec<bool>),
) {
    for b in [&mut *band, &mut *narrow] {
        b.clear();
        b.resize(suit.len(), false);
    }
    let suit_height = region_height(suit, width) as f32;
    let pixels = (reach * suit_height).ceil() as usize;
    if pixels == 0 || width == 0 {
        return;
    }
    let Some(b) = distance_near(suit, width, height, pixels, distance) else {
        return;
    };
    let (x0, y0, bw, bh) = (b.x0, b.y0, b.width(), b.height());
    let (reach, narrow_reach) = (
        pixels as u32 * 3,
        (narrow_reach * suit_height).ceil().min(pixels as f32) as u32 * 3,
    );
    for y in 0..bh {
        for x in 0..bw {
            let i = (y + y0) * width + x + x0;
            let d = distance[y * bw + x] as u32;
            band[i] = !suit[i] && d <= reach;
            narrow[i] = !suit[i] && d <= narrow_reach;
        }
    }
}

/// The least share of its bounding box a round part fills (see [`PartLimits::max_round_area`]):
/// heads measured on the demo clip 0.68–0.82, pieces of background that joined the person over an
/// orange photograph 0.28–0.59.
pub const ROUND_FILL: f32 = 0.6;

/// Where a head is expected above the suit, for the head look of a frame whose part test found
/// less than a head above it ([`expected_head`]), in cm on the person: an ellipse 16 cm wide and
/// 24 cm tall (a head with its neck; adults' head breadth is about 15 cm and chin to crown about
/// 23 cm), reaching [`HEAD_OVERLAP_CM`] into the suit's top rows, above the middle of the suit's
/// top [`NECK_ROWS_CM`].
pub const HEAD_HALF_WIDTH_CM: f32 = 8.0;
/// See [`HEAD_HALF_WIDTH_CM`].
pub const HEAD_HALF_HEIGHT_CM: f32 = 12.0;
/// How far the expected head's ellipse reaches down into the suit's top rows, cm (the suit's
/// collar sits below the chin).
pub const HEAD_OVERLAP_CM: f32 = 2.0;
/// The suit's rows whose pixels place the neck: the middle of the suit in its top 8 cm.
pub const NECK_ROWS_CM: f32 = 8.0;

/// Marks in `head` (resized to the grid) the pixels outside `suit` where a head is expected: the
/// ellipse of [`HEAD_HALF_WIDTH_CM`] × [`HEAD_HALF_HEIGHT_CM`] centred above the mean column of
/// the suit's pixels in its top [`NECK_ROWS_CM`], reaching [`HEAD_OVERLAP_CM`] into the suit's
/// top row `top`, at `px_per_cm` grid pixels per cm. Image up is taken as the person's up, as the
/// part limits take it. Returns how many pixels were marked (none without suit in its top rows).
pub fn expected_head(
    suit: &[bool],
    width: usize,
    top: usize,
    px_per_cm: f32,
    head: &mut Vec<bool>,
) -> usize {
    let Some(height) = start_marks(suit, width, px_per_cm, head) else {
        return 0;
    };
    let neck_rows = top..(top + (NECK_ROWS_CM * px_per_cm).ceil().max(1.0) as usize).min(height);
    let (mut sum, mut count) = (0.0f64, 0usize);
    for y in neck_rows {
        for (x, _) in suit[y * width..(y + 1) * width]
            .iter()
            .enumerate()
            .filter(|(_, &s)| s)
        {
            sum += x as f64;
            count += 1;
        }
    }
    if count == 0 {
        return 0;
    }
    let cx = (sum / count as f64) as f32;
    let (a, b) = (
        HEAD_HALF_WIDTH_CM * px_per_cm,
        HEAD_HALF_HEIGHT_CM * px_per_cm,
    );
    let cy = top as f32 + HEAD_OVERLAP_CM * px_per_cm - b;
    mark_ellipse(suit, width, (cx, cy), (a, b), head)
}

/// Where shoes are expected below the suit, for the look of a frame whose part test found less
/// than that below it ([`expected_shoes`]), in cm on the person: an ellipse 16 cm wide and 12 cm
/// tall (a shoe seen from the front, the side or between) centred [`SHOE_DROP_CM`] below the
/// lowest suit pixel of each run of columns that the suit's bottom [`ANKLE_ROWS_CM`] cover (a
/// leg's end, or two legs side by side).
pub const SHOE_HALF_WIDTH_CM: f32 = 8.0;
/// See [`SHOE_HALF_WIDTH_CM`].
pub const SHOE_HALF_HEIGHT_CM: f32 = 6.0;
/// How far below the suit's lowest pixel of a leg the expected shoe's centre lies, cm.
pub const SHOE_DROP_CM: f32 = 2.0;
/// The suit's bottom rows whose pixels place the ankles.
pub const ANKLE_ROWS_CM: f32 = 6.0;

/// Marks in `shoes` (resized to the grid) the pixels outside `suit` where shoes are expected: for
/// each run of adjacent columns holding suit in the rows of the suit's bottom [`ANKLE_ROWS_CM`]
/// (above `bottom`, the row after the suit's last), the ellipse of [`SHOE_HALF_WIDTH_CM`] ×
/// [`SHOE_HALF_HEIGHT_CM`] centred on the run's middle column, [`SHOE_DROP_CM`] below its lowest
/// suit pixel, at `px_per_cm` grid pixels per cm, unless the ellipse reaches the grid's bottom
/// row (a foot at the frame's edge: on CMU kick 10_03 of the pose test sequences the look took in
/// the lens flares under such feet, 0.9871 → 0.9785 IoU). Returns how many pixels were marked
/// (where two ellipses overlap, once).
pub fn expected_shoes(
    suit: &[bool],
    width: usize,
    bottom: usize,
    px_per_cm: f32,
    shoes: &mut Vec<bool>,
) -> usize {
    let Some(height) = start_marks(suit, width, px_per_cm, shoes) else {
        return 0;
    };
    let rows = (ANKLE_ROWS_CM * px_per_cm).ceil().max(1.0) as usize;
    // Each column's lowest suit row within the ankle rows.
    let mut lowest: Vec<Option<usize>> = vec![None; width];
    for y in bottom.saturating_sub(rows)..bottom.min(height) {
        for (x, low) in lowest.iter_mut().enumerate() {
            if suit[y * width + x] {
                *low = Some(y);
            }
        }
    }
    let (a, b) = (
        SHOE_HALF_WIDTH_CM * px_per_cm,
        SHOE_HALF_HEIGHT_CM * px_per_cm,
    );
    let mut marked = 0;
    let mut x = 0;
    while x < width {
        let start = x;
        let mut end_row = None;
        while let Some(Some(y)) = lowest.get(x) {
            end_row = end_row.max(Some(*y));
            x += 1;
        }
        let Some(end_row) = end_row else {
            x += 1;
            continue;
        };
        let centre = (
            (start + x - 1) as f32 / 2.0,
            end_row as f32 + SHOE_DROP_CM * px_per_cm,
        );
        // A shoe whose ellipse reaches the frame's bottom edge is partly out of the picture,
        // and what the look finds there is mostly what lies under the feet.
        if centre.1 + b >= height as f32 {
            continue;
        }
        marked += mark_ellipse(suit, width, centre, (a, b), shoes);
    }
    marked
}

/// Clears `marks` to the grid's size; returns the grid's height, or `None` when there is nothing
/// to mark (no width, or no pixels per cm).
fn start_marks(
    suit: &[bool],
    width: usize,
    px_per_cm: f32,
    marks: &mut Vec<bool>,
) -> Option<usize> {
    marks.clear();
    marks.resize(suit.len(), false);
    (width > 0 && px_per_cm > 0.0).then(|| suit.len() / width)
}

/// Marks in `marks` the pixels outside `suit` within the ellipse of half axes `(a, b)` about
/// `centre` (grid pixels); returns how many it marked that were not marked before.
fn mark_ellipse(
    suit: &[bool],
    width: usize,
    (cx, cy): (f32, f32),
    (a, b): (f32, f32),
    marks: &mut [bool],
) -> usize {
    let height = suit.len() / width;
    let span = |centre: f32, half: f32, limit: usize| {
        let lo = (centre - half).floor().max(0.0) as usize;
        let hi = ((centre + half).ceil() + 1.0).clamp(0.0, limit as f32) as usize;
        lo..hi.max(lo)
    };
    let mut marked = 0;
    for y in span(cy, b, height) {
        for x in span(cx, a, width) {
            let (dx, dy) = ((x as f32 - cx) / a, (y as f32 - cy) / b);
            let i = y * width + x;
            if dx * dx + dy * dy <= 1.0 && !suit[i] && !marks[i] {
                marks[i] = true;
                marked += 1;
            }
        }
    }
    marked
}

/// What an attached part (head, hand, shoe) may look like, in pixels of the grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PartLimits {
    /// The largest part of any shape: a hand or a shoe.
    pub max_area: usize,
    /// The largest part of any shape that reaches as high as the suit region's top row or higher:
    /// a head, maybe with a hand in front of it (drinking, waving), which is no longer round.
    /// Background of a part's colour that the flood runs into beside a limb or between the legs
    /// is held to `max_area`.
    pub max_top_area: usize,
    /// The largest round part: one that fills at least [`ROUND_FILL`] of its bounding box, as a
    /// head does (an ellipse fills π/4 of its box). Seen from the side or over a crouch the suit
    /// shows less of its area and a head's piece grows to 12 % of it, while background of a skin
    /// colour that the flood runs into is ragged.
    pub max_round_area: usize,
    /// The least area per pixel of contact with the suit: a head, a hand or a shoe joins the suit
    /// through a narrow neck, wrist or ankle, while background of a part's colour that the flood
    /// ran into lies along the suit in a thin strip.
    pub min_depth: f32,
    /// The largest area per pixel of contact with the suit of a piece beside it, one that reaches
    /// neither the suit's top row nor its bottom one (a hand, not a head or a shoe): a hand joins
    /// the sleeve at its wrist, background of a part's colour beside a leg is a large piece that
    /// the flood entered through a pixel or two.
    pub max_side_depth: f32,
}

/// Adds to the person the band pixels (see [`part_band`]) that look like a part of the person
/// (`part_like`) and are 4-connected to the suit through such pixels; `person` starts as the suit
/// and ends as suit + parts, `part` marks the added pixels. A connected piece of added pixels
/// outside the `limits` (larger, or too shallow for its contact with the suit) is not a head, a
/// hand or a shoe but background of a part's colour, and is taken back.
#[allow(clippy::too_many_arguments)]
pub fn attach_parts(
    person: &mut [bool],
    band: &[bool],
    width: usize,
    height: usize,
    part_like: impl Fn(usize) -> bool,
    limits: PartLimits,
    part: &mut Vec<bool>,
    stack: &mut Vec<usize>,
) -> Attached {
    part.clear();
    part.resize(person.len(), false);
    let suit_top = person.iter().position(|&p| p).map_or(0, |i| i / width);
    let suit_bottom = person.iter().rposition(|&p| p).map_or(0, |i| i / width);
    stack.clear();
    stack.extend((0..person.len()).filter(|&i| person[i]));
    while let Some(i) = stack.pop() {
        for j in neighbours4(i, width, height).into_iter().flatten() {
            if band[j] && !person[j] && part_like(j) {
                person[j] = true;
                part[j] = true;
                stack.push(j);
            }
        }
    }
    let Some(b) = PixelBox::around(part, width, height, 0) else {
        return Attached::default();
    };
    let (mut crop, mut ids) = (Vec::new(), Vec::new());
    b.crop(part, width, &mut crop);
    let stats = components(&crop, b.width(), b.height(), true, &mut ids);
    // Pixels of each piece that touch the suit, and its bounding box (x0, x1, y0, y1) in the crop.
    let mut contact = vec![0usize; stats.len()];
    let mut boxes = vec![(usize::MAX, 0, usize::MAX, 0); stats.len()];
    for (k, &id) in ids.iter().enumerate() {
        if id != u32::MAX {
            let i = b.grid_index(k, width);
            let touches = neighbours4(i, width, height)
                .into_iter()
                .flatten()
                .any(|j| person[j] && !part[j]);
            contact[id as usize] += touches as usize;
            let (x, y) = (k % b.width(), k / b.width());
            let e = &mut boxes[id as usize];
            *e = (e.0.min(x), e.1.max(x), e.2.min(y), e.3.max(y));
        }
    }
    let at_top = |c: usize| boxes[c].2 + b.y0 <= suit_top;
    let fits = |c: usize| {
        let area = stats[c].0;
        let (x0, x1, y0, y1) = boxes[c];
        let round = area as f32 >= ROUND_FILL * ((x1 - x0 + 1) * (y1 - y0 + 1)) as f32;
        let at_top = at_top(c);
        // The largest limit of those that apply.
        let max_area = limits
            .max_area
            .max(if at_top { limits.max_top_area } else { 0 })
            .max(if round { limits.max_round_area } else { 0 });
        let beside = !at_top && y1 + b.y0 < suit_bottom;
        area <= max_area
            && area as f32 >= limits.min_depth * contact[c] as f32
            && !(beside && area as f32 > limits.max_side_depth * contact[c] as f32)
    };
    let mut attached = Attached::default();
    for (k, &id) in ids.iter().enumerate() {
        if id == u32::MAX {
            continue;
        }
        if fits(id as usize) {
            attached.added += 1;
        } else {
            let i = b.grid_index(k, width);
            person[i] = false;
            part[i] = false;
            attached.taken_back += 1;
            attached.taken_back_at_top += at_top(id as usize) as usize;
        }
    }
    attached
}

/// What [`attach_parts`] did, in pixels of the grid.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Attached {
    /// Pixels added to the person as head, hands or shoes.
    pub added: usize,
    /// Pixels of pieces outside the limits, taken back.
    pub taken_back: usize,
    /// Of those, the pixels of pieces that reach as high as the suit's top row (a head, or
    /// background above the shoulders).
    pub taken_back_at_top: usize,
}

/// Adds to `person` and `part` the pixels `found` marks as parts that `part` does not; returns
/// how many.
pub fn add_parts(person: &mut [bool], part: &mut [bool], found: &[bool]) -> usize {
    let mut added = 0;
    for ((p, q), &n) in person.iter_mut().zip(part.iter_mut()).zip(found) {
        if n && !*q {
            (*p, *q) = (true, true);
            added += 1;
        }
    }
    added
}

/// [`attach_parts`] within `band`, and where that took back a piece reaching the suit's top row, a
/// second look for heads within `narrow` (a band inside `band`): the pieces of that pass that
/// reach as high as the suit's top row and fit `max_top_area` are added too (`part` marks the
/// added pixels of both). The wide band lets an upright head join whole, but where the head meets
/// background of its colour it joins more of that than the narrow band does, and the piece, too
/// large for a head, was taken back whole: on the dance over the cat photograph the head went
/// missing in the first frames, and the body size measured on them came out 168 cm for a 193 cm
/// subject (182 cm with the narrow band). Hands and shoes get no second look: beside the legs the
/// narrow band's pieces are mostly background (given a second look for every piece, the jump of
/// the pose test sequences lost 0.011 IoU; for heads only 0.003, the other five within 0.0001;
/// see docs/measurements.md, third session of 2026-12-05). `scratch` holds the second pass's
/// person and parts.
#[allow(clippy::too_many_arguments)]
pub fn attach_parts_narrowing(
    person: &mut [bool],
    (band, narrow): (&[bool], &[bool]),
    width: usize,
    height: usize,
    part_like: impl Fn(usize) -> bool,
    limits: PartLimits,
    part: &mut Vec<bool>,
    stack: &mut Vec<usize>,
    scratch: &mut (Vec<bool>, Vec<bool>),
) -> Attached {
    let wide = attach_parts(person, band, width, height, &part_like, limits, part, stack);
    if wide.taken_back_at_top == 0 {
        return wide;
    }
    // The second pass starts from the suit again: the person without the parts just added.
    let (narrow_person, narrow_part) = scratch;
    narrow_person.clear();
    narrow_person.extend(person.iter().zip(part.iter()).map(|(&p, &q)| p && !q));
    let heads = PartLimits {
        max_area: 0,
        max_round_area: 0,
        ..limits
    };
    attach_parts(
        narrow_person,
        narrow,
        width,
        height,
        &part_like,
        heads,
        narrow_part,
        stack,
    );
    // The narrow pass's pieces lie within the wide pass's, so only those taken back are new.
    let readded = add_parts(person, part, narrow_part);
    Attached {
        added: wide.added + readded,
        taken_back: wide.taken_back - readded,
        taken_back_at_top: wide.taken_back_at_top - readded,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fill_suit_holes_fills_small_holes_of_the_suits_colours_only() {
        // A 12 × 6 person with holes ('o': background of the suit's colours, '.': of another
        // colour). With max_hole 3 and a share of 0.8 three are filled: the L of three pixels
        // over two rows and the two single pixels at (9, 1) and (10, 2), which touch corner to
        // corner only. Kept: the hole of the room's colour, the five pixels over rows 3 and 4
        // (too large) and the pixel at the top right, which is the room around the person.
        let rows = [
            "###########o",
            "#oo#..###o##",
            "#o########o#",
            "######oooo##",
            "#########o##",
            "############",
        ];
        let (w, h) = (12, 6);
        let grid = |rows: &[&str], f: fn(char) -> bool| -> Vec<bool> {
            rows.iter().flat_map(|r| r.chars().map(f)).collect()
        };
        let mut labels = grid(&rows, |c| c == '#');
        let suit = grid(&rows, |c| c != '.');
        let (mut runs, mut parent) = (Vec::new(), Vec::new());
        let filled = fill_suit_holes(
            &mut labels,
            (w, h),
            (3, 0.8),
            |i| suit[i],
            &mut runs,
            &mut parent,
        );
        assert_eq!(filled, (3, 5));
        let expected = [
            "###########o",
            "####..######",
            "############",
            "######oooo##",
            "#########o##",
            "############",
        ];
        assert_eq!(labels, grid(&expected, |c| c == '#'));
        // Nothing of the suit's colours: nothing filled; nobody: nothing to fill.
        let mut ring = grid(&["###", "#.#", "###"], |c| c == '#');
        let kept = fill_suit_holes(
            &mut ring,
            (3, 3),
            (4, 0.8),
            |_| false,
            &mut runs,
            &mut parent,
        );
        assert_eq!((kept, ring[4]), ((0, 0), false));
        let mut nobody = vec![false; 9];
        let none = fill_suit_holes(
            &mut nobody,
            (3, 3),
            (4, 0.0),
            |_| true,
            &mut runs,
            &mut parent,
        );
        assert_eq!((none, nobody), ((0, 0), vec![false; 9]));
    }

    #[test]
    fn add_parts_adds_only_what_is_new_and_counts_it() {
        // Four pixels: the suit, a part already there, a new part, nothing.
        let mut person = vec![true, true, false, false];
        let mut part = vec![false, true, false, false];
        let found = [false, true, true, false];
        assert_eq!(add_parts(&mut person, &mut part, &found), 1);
        assert_eq!(person, [true, true, true, false]);
        assert_eq!(part, [false, true, true, false]);
    }

    /// A rule with no marker pixels anywhere (so every piece passes the marker test).
    fn rule<'a>(score: &'a dyn Fn(usize) -> f32, min_area: usize, reach: f32) -> RegionRule<'a> {
        RegionRule {
            score,
            marker: &|_| false,
            min_area,
            reach,
        }
    }

    /// Limits that judge a piece by its area alone, and let none through: the tests set the areas
    /// (and any depth rule) they look at.
    const AREA_ONLY: PartLimits = PartLimits {
        max_area: 0,
        max_top_area: 0,
        max_round_area: 0,
        min_depth: 0.0,
        max_side_depth: f32::INFINITY,
    };

    fn grid(rows: &[&str]) -> (Vec<bool>, usize, usize) {
        let w = rows[0].len();
        (
            rows.iter()
                .flat_map(|r| r.chars().map(|c| c == '#'))
                .collect(),
            w,
            rows.len(),
        )
    }

    #[test]
    fn the_expected_head_is_an_ellipse_above_the_middle_of_the_suits_top_rows() {
        // Suit columns 4–7 from row 6 down; at 0.25 px per cm the ellipse is 2 × 3 px (half
        // axes), its centre at x 5.5 (the neck rows 6–7), y 6 + 0.5 − 3 = 3.5. Row 1:
        // (2.5/3)² = 0.69 leaves |x − 5.5| ≤ 2·√0.31 = 1.1; rows 2–5: (≤ 1.5/3)² ≤ 0.25 leaves
        // |x − 5.5| ≤ 1.73; row 6 is suit where the ellipse reaches it.
        let (suit, w, _) = grid(&[
            "............",
            "............",
            "............",
            "............",
            "............",
            "............",
            "....####....",
            "....####....",
            "....####....",
            "....####....",
        ]);
        let (expected, _, _) = grid(&[
            "............",
            ".....##.....",
            "....####....",
            "....####....",
            "....####....",
            "....####....",
            "............",
            "............",
            "............",
            "............",
        ]);
        let mut head = Vec::new();
        assert_eq!(expected_head(&suit, w, 6, 0.25, &mut head), 18);
        assert_eq!(head, expected);
        // No suit in the top rows named: nothing expected.
        assert_eq!(expected_head(&suit, w, 1, 0.25, &mut head), 0);
        assert!(head.iter().all(|&h| !h));
    }

    #[test]
    fn the_expected_shoes_are_ellipses_below_each_legs_lowest_suit_pixel() {
        // Legs in columns 2–3 and 8–10 down to row 5 (bottom 6); at 0.25 px per cm the ankle
        // rows are 4–5, the ellipses 2 × 1.5 px (half axes) about (2.5, 5.5) and (9, 5.5). Rows
        // 5 and 6: (0.5/1.5)² = 0.11 leaves |x − centre| ≤ 2·√0.89 = 1.89; rows 4 and 7 only the
        // centre column, which only the right leg has (row 4 is its suit).
        let (suit, w, _) = grid(&[
            "..##....###...",
            "..##....###...",
            "..##....###...",
            "..##....###...",
            "..##....###...",
            "..##....###...",
            "..............",
            "..............",
            "..............",
            "..............",
        ]);
        let (expected, _, _) = grid(&[
            "..............",
            "..............",
            "..............",
            "..............",
            "..............",
            ".#..#.........",
            ".####...###...",
            ".........#....",
            "..............",
            "..............",
        ]);
        let mut shoes = Vec::new();
        assert_eq!(expected_shoes(&suit, w, 6, 0.25, &mut shoes), 10);
        assert_eq!(shoes, expected);
        // No suit in the ankle rows: nothing expected.
        assert_eq!(expected_shoes(&suit, w, 9, 0.25, &mut shoes), 0);
        assert!(shoes.iter().all(|&s| !s));
        // Legs down to row 8 of 10: the ellipses (centre row 8.5, half height 1.5) reach the
        // bottom row, so nothing is expected.
        let (tall, _, _) = grid(&[
            "..##....###...",
            "..##....###...",
            "..##....###...",
            "..##....###...",
            "..##....###...",
            "..##....###...",
            "..##....###...",
            "..##....###...",
            "..##....###...",
            "..............",
        ]);
        assert_eq!(expected_shoes(&tall, w, 9, 0.25, &mut shoes), 0);
        assert!(shoes.iter().all(|&s| !s));
    }

    #[test]
    fn off_cloth_pieces_larger_than_the_limit_are_removed() {
        // 6×4, all person; off cloth: a 2×2 block (4 px, a marker) and an L of 5 px (not one).
        #[rustfmt::skip]
        let off = [
            1, 1, 0, 0, 0, 0,
            1, 1, 0, 1, 0, 0,
            0, 0, 0, 1, 0, 0,
            0, 0, 0, 1, 1, 1,
        ];
        let mut region = vec![true; 24];
        region[17] = false; // not the person: stays out
        let (mut crop, mut ids) = (Vec::new(), Vec::new());
        let found =
            remove_large_off_cloth(&mut region, 6, 4, |i| off[i] == 1, 4, &mut crop, &mut ids);
        assert_eq!(found, (1, 5));
        let removed: Vec<usize> = (0..24).filter(|&i| !region[i]).collect();
        assert_eq!(removed, [9, 15, 17, 21, 22, 23]);
        // At a limit of 3 the marker goes too; an empty region changes nothing.
        let mut region = vec![true; 24];
        assert_eq!(
            remove_large_off_cloth(&mut region, 6, 4, |i| off[i] == 1, 3, &mut crop, &mut ids),
            (2, 9)
        );
        let mut empty = vec![false; 24];
        assert_eq!(
            remove_large_off_cloth(&mut empty, 6, 4, |_| true, 0, &mut crop, &mut ids),
            (0, 0)
        );
    }

    #[test]
    fn cloth_farther_than_the_reach_from_every_marker_is_removed() {
        // A 9×3 strip of person; its one marker pixel at (1, 1) (index 10). The 3-4 chamfer
        // distance from it: 3 per step along a row or column, 4 per diagonal step, so column x of
        // rows 0 and 2 is 4 + 3·(x − 2) away for x ≥ 2, and of row 1 3·(x − 1).
        let strip = || grid(&["#########", "#########", "#########"]);
        let (mut region, w, h) = strip();
        let marker = |i: usize| i == 10;
        let far = |region: &mut [bool], marker: &dyn Fn(usize) -> bool, reach: usize| {
            remove_far_from_markers(region, w, h, marker, (reach, 2), &mut Vec::new())
        };
        // Reach 3 px (limit 9): row 1 keeps x ≤ 4, rows 0 and 2 x ≤ 3 (x = 4 is 10 away).
        let removed = far(&mut region, &marker, 3);
        assert_eq!(region, grid(&["####.....", "#####....", "####....."]).0);
        assert_eq!(removed, 27 - 13);
        // The marker a hole of the region (the cut left it out; holes up to 2 px across): the same.
        let (mut holed, ..) = grid(&["#########", "#.#######", "#########"]);
        far(&mut holed, &marker, 3);
        assert_eq!(holed, grid(&["####.....", "#.###....", "####....."]).0);
        // Beside the region, in the room, it is no marker of the region: everything goes.
        let (mut beside, ..) = grid(&["#########", ".########", "#########"]);
        let room_marker = |i: usize| i == 9;
        assert_eq!(far(&mut beside, &room_marker, 3), 26);
        // A reach beyond the strip keeps it whole; with no marker everything goes; an empty
        // region changes nothing.
        let (mut whole, ..) = strip();
        assert_eq!(far(&mut whole, &marker, 8), 0);
        assert_eq!(far(&mut whole, &|_| false, 8), 27);
        let mut empty = vec![false; 27];
        assert_eq!(far(&mut empty, &marker, 0), 0);
    }

    #[test]
    fn keeps_the_highest_scoring_region() {
        let (mut m, w, h) = grid(&["##...", "##..#", ".....", "...##"]);
        let mut ids = Vec::new();
        // Equal scores: the larger (the 2×2 block) wins.
        let report = keep_person_region(&mut m, w, h, &rule(&|_| 1.0, 1, 0.0), &mut ids);
        assert_eq!(m, grid(&["##...", "##...", ".....", "....."]).0);
        assert_eq!(
            report,
            CleanupReport {
                components_removed: 2,
                pixels_removed: 3,
                ..Default::default()
            }
        );
        // Score the bottom-right pair higher: it wins despite being smaller.
        let (mut m, _, _) = grid(&["##...", "##..#", ".....", "...##"]);
        keep_person_region(
            &mut m,
            w,
            h,
            &rule(&|i| if i >= 18 { 10.0 } else { 1.0 }, 1, 0.0),
            &mut ids,
        );
        assert_eq!(m, grid(&[".....", ".....", ".....", "...##"]).0);
    }

    #[test]
    fn suit_like_pieces_near_the_person_are_kept() {
        // A 4-row body (markers in column 0) cut at row 4 (a hand on the hip); below it a piece
        // with markers, beside that one a piece of cloth colour alone, far off a third piece.
        let (mut m, w, h) = grid(&[
            "##......", "##......", "##......", "##......", "........", "##.##...", "##.##...",
            "........", "........", "......##",
        ]);
        let marker = |i: usize| i.is_multiple_of(w) || i % w == 6;
        let score = |_: usize| 1.0;
        let rule = RegionRule {
            score: &score,
            marker: &marker,
            min_area: 4,
            // 0.75 × 4 rows = 3 pixels (chamfer 9): both pieces below are within reach
            // (chamfer 6 and 8), the far one is not.
            reach: 0.75,
        };
        let mut ids = Vec::new();
        let report = keep_person_region(&mut m, w, h, &rule, &mut ids);
        assert_eq!(
            m,
            grid(&[
                "##......", "##......", "##......", "##......", "........", "##......", "##......",
                "........", "........", "........",
            ])
            .0
        );
        assert_eq!((report.components_removed, report.pixels_removed), (2, 6));
    }

    #[test]
    fn too_small_a_region_leaves_an_empty_mask() {
        let (mut m, w, h) = grid(&["#....", ".....", "....#"]);
        let mut ids = Vec::new();
        keep_person_region(&mut m, w, h, &rule(&|_| 1.0, 2, 0.0), &mut ids);
        assert!(m.iter().all(|&p| !p));
    }

    #[test]
    fn parts_attach_within_the_band_and_only_through_part_like_pixels() {
        // An 8-row suit column at x = 1..=2; PART_REACH · 8 = 1.2 → a reach of 2 pixels (chamfer 6).
        let (suit, w, h) = grid(&[
            "........", ".##.....", ".##.....", ".##.....", ".##.....", ".##.....", ".##.....",
            ".##.....", ".##.....", "........",
        ]);
        assert_eq!(region_height(&suit, w), 8);
        let (mut distance, mut band) = (Vec::new(), Vec::new());
        part_band(&suit, w, h, PART_REACH, &mut distance, &mut band);
        // Row 1: x = 0 (1 px), 3 (1 px), 4 (2 px) are in the band, 5 (3 px) is not.
        assert_eq!(
            &band[w..2 * w],
            &[true, false, false, true, true, false, false, false]
        );
        // Part-like: everything in row 1 and x = 6 of row 5 (in no band: never reached).
        let like = |i: usize| i / w == 1 || i == 5 * w + 6;
        let mut person = suit.clone();
        let (mut part, mut stack) = (Vec::new(), Vec::new());
        let limits = |max_area| PartLimits {
            max_area,
            ..AREA_ONLY
        };
        let added = attach_parts(
            &mut person,
            &band,
            w,
            h,
            like,
            limits(3),
            &mut part,
            &mut stack,
        )
        .added;
        assert_eq!(added, 3);
        assert_eq!(
            &person[w..2 * w],
            &[true, true, true, true, true, false, false, false]
        );
        assert!(part[w] && part[w + 3] && part[w + 4] && !part[w + 1] && !part[5 * w + 6]);
        // A cap of 1 pixel per piece takes the 2-pixel piece at x = 3..=4 back.
        let mut person = suit.clone();
        let added = attach_parts(
            &mut person,
            &band,
            w,
            h,
            like,
            limits(1),
            &mut part,
            &mut stack,
        )
        .added;
        assert_eq!(added, 1);
        assert!(person[w] && !person[w + 3] && !person[w + 4] && !part[w + 3]);
        // Depth: the pixel at x = 0 touches the suit with its 1 pixel (depth 1), the piece at
        // x = 3..=4 with 1 of its 2 (depth 2); a least depth of 1.5 keeps the second only.
        let mut person = suit.clone();
        let deep = PartLimits {
            max_area: 10,
            min_depth: 1.5,
            ..AREA_ONLY
        };
        let added = attach_parts(&mut person, &band, w, h, like, deep, &mut part, &mut stack).added;
        assert_eq!(added, 2);
        assert!(!person[w] && person[w + 3] && person[w + 4]);
    }

    #[test]
    fn a_round_part_may_be_larger_than_a_ragged_one() {
        // Suit in columns 0..=1; a 3 × 3 block beside it (9 px, fills its box) and a ragged strip
        // of 7 px in a 5 × 3 box (fill 0.47 < ROUND_FILL), everything outside the suit in the band.
        let (person, w, h) = grid(&[
            "##......", "#####...", "#####...", "#####...", "##......", "#######.", "##....#.",
            "##....#.",
        ]);
        let suit: Vec<bool> = (0..w * h).map(|i| i % w < 2).collect();
        let band: Vec<bool> = suit.iter().map(|&s| !s).collect();
        let attach = |max_round_area| {
            let limits = PartLimits {
                max_area: 4,
                max_top_area: 4,
                max_round_area,
                ..AREA_ONLY
            };
            attach_from(&suit, &band, (w, h), |i| person[i], limits)
        };
        let (added, grown) = attach(9);
        assert_eq!(added, 9);
        assert!(grown[w + 4] && grown[3 * w + 2] && !grown[5 * w + 2] && !grown[7 * w + 6]);
        let (added, _) = attach(0);
        assert_eq!(added, 0);
    }

    /// A person drawn in `rows` (see [`grid`]) whose suit is two columns wide (2..=3) from row 3
    /// down: the part-like pixels, the width and height, the suit, and a band of everything else.
    fn upright(rows: &[&str]) -> (Vec<bool>, usize, usize, Vec<bool>, Vec<bool>) {
        let (person, w, h) = grid(rows);
        let suit: Vec<bool> = (0..w * h)
            .map(|i| (2..=3).contains(&(i % w)) && i / w >= 3)
            .collect();
        let band = suit.iter().map(|&s| !s).collect();
        (person, w, h, suit, band)
    }

    /// [`attach_parts`] from `suit` within `band`: the pixels it added and the person it grew.
    fn attach_from(
        suit: &[bool],
        band: &[bool],
        (w, h): (usize, usize),
        like: impl Fn(usize) -> bool,
        limits: PartLimits,
    ) -> (usize, Vec<bool>) {
        let (mut part, mut stack) = (Vec::new(), Vec::new());
        let mut grown = suit.to_vec();
        let added = attach_parts(&mut grown, band, w, h, like, limits, &mut part, &mut stack).added;
        (added, grown)
    }

    #[test]
    fn a_piece_beside_the_suit_may_not_hang_on_by_a_pixel() {
        // Suit in rows 3..=7, columns 2..=3. Beside it (rows 4..=5) a piece of 5 px that touches
        // the suit with one pixel (depth 5); on its bottom row a piece of 3 px that touches it with
        // one (depth 3, a shoe: not beside the suit).
        let (person, w, h, suit, band) = upright(&[
            "........", "........", "........", "..##....", "..#####.", "..##.##.", "..##....",
            "..#####.",
        ]);
        let attach = |max_side_depth| {
            let limits = PartLimits {
                max_area: 5,
                max_side_depth,
                ..AREA_ONLY
            };
            attach_from(&suit, &band, (w, h), |i| person[i], limits)
        };
        let (added, grown) = attach(5.0);
        assert_eq!(added, 8);
        assert_eq!(grown, person);
        // At most 2 px per pixel of contact: the piece beside goes, the shoe (depth 3) stays.
        let (added, grown) = attach(2.0);
        assert_eq!(added, 3);
        assert!(grown[7 * w + 6] && !grown[4 * w + 4] && !grown[5 * w + 6]);
    }

    #[test]
    fn a_ragged_part_at_the_top_may_be_larger_than_one_beside_the_suit() {
        // Suit in rows 3..=7, columns 2..=3; two ragged pieces of 6 px in 4 × 3 boxes (fill 0.5 <
        // ROUND_FILL): one on top of the suit reaching above its top row (a head with a hand
        // before it), one beside it lower down (background between the legs).
        let (person, w, h, suit, band) = upright(&[
            ".....#..", "....##..", "..###...", "..##....", "..####..", "..##.##.", "..##..##",
            "..##....",
        ]);
        let attach = |max_top_area| {
            let limits = PartLimits {
                max_area: 3,
                max_top_area,
                max_round_area: 3,
                ..AREA_ONLY
            };
            attach_from(&suit, &band, (w, h), |i| person[i], limits)
        };
        let (added, grown) = attach(6);
        assert_eq!(added, 6);
        assert!(grown[5] && grown[w + 4] && grown[2 * w + 2]);
        assert!(!grown[4 * w + 4] && !grown[6 * w + 7]);
        assert_eq!(attach(3).0, 0);
    }

    #[test]
    fn a_head_too_large_in_the_wide_band_is_looked_for_again_in_the_narrow_one() {
        // Suit in rows 3..=7, columns 2..=3. Above it a head (rows 1..=2) under a strip of
        // background of its colour (row 0); beside it a 2 × 2 piece (rows 5..=6, columns 4..=5).
        // The wide band is everything outside the suit, the narrow one leaves out row 0 and
        // column 5.
        let (person, w, h, suit, wide) = upright(&[
            "..####..", "..##....", "..##....", "..##....", "..##....", "..####..", "..####..",
            "..##....",
        ]);
        let like = |i: usize| person[i];
        let narrow: Vec<bool> = (0..w * h)
            .map(|i| !suit[i] && i / w >= 1 && i % w != 5)
            .collect();
        let limits = PartLimits {
            max_area: 1,
            max_top_area: 4,
            ..AREA_ONLY
        };
        let (mut part, mut stack, mut scratch) = (Vec::new(), Vec::new(), (Vec::new(), Vec::new()));
        // Within the wide band alone the head's piece (8 px) and the side piece (4 px) are too large.
        let mut grown = suit.clone();
        let attached = attach_parts(&mut grown, &wide, w, h, like, limits, &mut part, &mut stack);
        assert_eq!((attached.added, attached.taken_back), (0, 12));
        assert_eq!(attached.taken_back_at_top, 8);
        assert_eq!(grown, suit);
        // The second look keeps the head (4 px, at the top); the side piece, 2 px within the
        // narrow band but no head, stays out.
        let mut grown = suit.clone();
        let attached = attach_parts_narrowing(
            &mut grown,
            (&wide, &narrow),
            w,
            h,
            like,
            limits,
            &mut part,
            &mut stack,
            &mut scratch,
        );
        assert_eq!((attached.added, attached.taken_back), (4, 8));
        assert_eq!(attached.taken_back_at_top, 4);
        let head = [w + 2, w + 3, 2 * w + 2, 2 * w + 3];
        for i in 0..w * h {
            assert_eq!(grown[i], suit[i] || head.contains(&i), "pixel {i}");
            assert_eq!(part[i], head.contains(&i), "part {i}");
        }
    }

    #[test]
    fn fills_enclosed_holes_but_not_the_outside() {
        let (mut m, w, h) = grid(&[".....", ".###.", ".#.#.", ".###.", "....."]);
        let mut ids = Vec::new();
        let mut report = CleanupReport::default();
        fill_holes(&mut m, w, h, 1, &mut ids, &mut report);
        assert_eq!(m, grid(&[".....", ".###.", ".###.", ".###.", "....."]).0);
        assert_eq!((report.holes_filled, report.pixels_filled), (1, 1));
        let (mut m, _, _) = grid(&[".....", ".###.", ".#.#.", ".###.", "....."]);
        let mut report = CleanupReport::default();
        fill_holes(&mut m, w, h, 0, &mut ids, &mut report);
        assert_eq!(report.holes_filled, 0);
    }
    #[test]
    fn a_box_around_the_set_pixels_grown_and_clipped() {
        let (m, w, h) = grid(&[".....", "..#..", "...#.", "....."]);
        let b = PixelBox::around(&m, w, h, 0).expect("two set pixels");
        assert_eq!((b.x0, b.y0, b.x1, b.y1), (2, 1, 4, 3));
        let b = PixelBox::around(&m, w, h, 2).expect("two set pixels");
        assert_eq!((b.x0, b.y0, b.x1, b.y1), (0, 0, 5, 4));
        assert_eq!(PixelBox::around(&[false; 20], w, h, 1), None);
        let b = PixelBox::around(&m, w, h, 0).expect("two set pixels");
        let mut crop = Vec::new();
        b.crop(&m, w, &mut crop);
        assert_eq!(crop, vec![true, false, false, true]);
        assert_eq!(b.grid_index(3, w), 2 * w + 3);
        let mut pasted = vec![false; 20];
        b.paste(&crop, w, &mut pasted);
        assert_eq!(pasted, m);
    }

    #[test]
    fn distances_near_a_region_match_the_whole_grid() {
        let (m, w, h) = grid(&["........", "........", "...#....", "........", "........"]);
        let mut near = Vec::new();
        let b = distance_near(&m, w, h, 1, &mut near).expect("a set pixel");
        assert_eq!((b.x0, b.y0, b.x1, b.y1), (2, 1, 5, 4));
        // 3 per step, 4 per diagonal: the 3×3 ring around the pixel.
        assert_eq!(near, vec![4, 3, 4, 3, 0, 3, 4, 3, 4]);
    }

    proptest::proptest! {
        #[test]
        fn cleaning_in_the_box_equals_cleaning_the_whole_grid(
            cells in proptest::collection::vec(proptest::bool::weighted(0.4), 1..200),
            width in 1usize..16,
            min_area in 1usize..6,
            max_hole in 0usize..8,
            reach in 0.0f32..1.0,
        ) {
            let height = cells.len() / width;
            proptest::prop_assume!(height > 0);
            let labels = &cells[..width * height];
            let score = |i: usize| (i % 7) as f32;
            let mut ids = Vec::new();
            let mut whole = labels.to_vec();
            let marker = |i: usize| i.is_multiple_of(3);
            let rule = RegionRule { score: &score, marker: &marker, min_area, reach };
            let mut expected = keep_person_region(&mut whole, width, height, &rule, &mut ids);
            fill_holes(&mut whole, width, height, max_hole, &mut ids, &mut expected);
            let mut boxed = labels.to_vec();
            let report = clean(&mut boxed, width, height, Some(&rule), max_hole, &mut Vec::new(), &mut ids);
            proptest::prop_assert_eq!(&boxed, &whole);
            // The box leaves out background outside it, which is never a hole or removed region.
            proptest::prop_assert_eq!(report, expected);
        }
    }
}
