//! Clean-up of the cut: keep one person region and fill its small holes.
//!
//! The min-cut labels every pixel independently of any notion of "one person", so stray foreground
//! (a suit-coloured object in the room) and small background holes (a shadowed fold) remain.
//! [`keep_person_region`] labels the 4-connected foreground components, keeps the one with the highest
//! score (the caller scores pixels, e.g. suit cloth next to a marker, so that a large flat green poster
//! does not beat a smaller person) if it is big enough, and removes the rest; [`fill_holes`] fills background
//! components that do not touch the image border and are smaller than a limit. Both report what they
//! changed, which the segmenter passes on in its output.

/// What the clean-up changed in one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CleanupReport {
    pub components_removed: usize,
    pub pixels_removed: usize,
    pub holes_filled: usize,
    pub pixels_filled: usize,
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
            for_each_neighbour(i, width, height, |j| {
                if labels[j] == value && ids[j] == u32::MAX {
                    ids[j] = id;
                    stack.push(j);
                }
            });
        }
        stats.push((count, border));
    }
    stats
}

/// Keeps the foreground component with the highest total `score` (ties: the larger) if it has at least
/// `min_area` pixels; clears everything else. With no component that large the mask becomes empty.
pub fn keep_person_region(
    labels: &mut [bool],
    width: usize,
    height: usize,
    score: impl Fn(usize) -> f32,
    min_area: usize,
    ids: &mut Vec<u32>,
) -> CleanupReport {
    let stats = components(labels, width, height, true, ids);
    let mut scores = vec![0.0f32; stats.len()];
    for (i, &id) in ids.iter().enumerate() {
        if id != u32::MAX {
            scores[id as usize] += score(i);
        }
    }
    let best = (0..stats.len())
        .filter(|&c| stats[c].0 >= min_area)
        .max_by(|&a, &b| {
            scores[a]
                .total_cmp(&scores[b])
                .then(stats[a].0.cmp(&stats[b].0))
        });
    let mut report = CleanupReport::default();
    for (c, &(count, _)) in stats.iter().enumerate() {
        if Some(c) != best {
            report.components_removed += 1;
            report.pixels_removed += count;
        }
    }
    for (label, &id) in labels.iter_mut().zip(ids.iter()) {
        if id != u32::MAX && Some(id as usize) != best {
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

/// How far the person's parts outside the suit (head, hands, shoes) reach from it, as a share of the
/// suit region's height: the head of an upright person is about an eighth of their height.
pub const PART_REACH: f32 = 0.15;

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
/// region's height of it (3-4 chamfer distance, written to `distance`).
pub fn part_band(
    suit: &[bool],
    width: usize,
    height: usize,
    reach: f32,
    distance: &mut Vec<u16>,
    band: &mut Vec<bool>,
) {
    band.clear();
    band.resize(suit.len(), false);
    let pixels = (reach * region_height(suit, width) as f32).ceil() as usize;
    if pixels == 0 || width == 0 {
        return;
    }
    // The distance transform on the suit's bounding box grown by the reach: a 3-4 chamfer path no
    // longer than the reach stays within it, so the band is the same as on the whole image.
    let (mut x0, mut y0, mut x1, mut y1) = (width, height, 0, 0);
    for (i, _) in suit.iter().enumerate().filter(|(_, &s)| s) {
        let (x, y) = (i % width, i / width);
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    let (x0, y0) = (x0.saturating_sub(pixels), y0.saturating_sub(pixels));
    let (x1, y1) = ((x1 + pixels).min(width - 1), (y1 + pixels).min(height - 1));
    let (bw, bh) = (x1 + 1 - x0, y1 + 1 - y0);
    distance.clear();
    for y in y0..=y1 {
        distance.extend(suit[y * width + x0..=y * width + x1].iter().map(|&s| {
            if s {
                0
            } else {
                super::features::FAR
            }
        }));
    }
    super::features::chamfer(distance, bw, bh);
    let reach = pixels as u32 * 3;
    for y in 0..bh {
        for x in 0..bw {
            let i = (y + y0) * width + x + x0;
            band[i] = !suit[i] && (distance[y * bw + x] as u32) <= reach;
        }
    }
}

/// Adds to the person the band pixels (see [`part_band`]) that look like a part of the person
/// (`part_like`) and are 4-connected to the suit through such pixels; `person` starts as the suit
/// and ends as suit + parts, `part` marks the added pixels. Returns how many were added.
pub fn attach_parts(
    person: &mut [bool],
    band: &[bool],
    width: usize,
    height: usize,
    part_like: impl Fn(usize) -> bool,
    part: &mut Vec<bool>,
    stack: &mut Vec<usize>,
) -> usize {
    part.clear();
    part.resize(person.len(), false);
    stack.clear();
    stack.extend((0..person.len()).filter(|&i| person[i]));
    let mut added = 0;
    while let Some(i) = stack.pop() {
        for_each_neighbour(i, width, height, |j| {
            if band[j] && !person[j] && part_like(j) {
                person[j] = true;
                part[j] = true;
                added += 1;
                stack.push(j);
            }
        });
    }
    added
}

/// Calls `visit` with each 4-neighbour of pixel `i` inside a `width`×`height` grid.
fn for_each_neighbour(i: usize, width: usize, height: usize, mut visit: impl FnMut(usize)) {
    let (x, y) = (i % width, i / width);
    if x > 0 {
        visit(i - 1);
    }
    if x + 1 < width {
        visit(i + 1);
    }
    if y > 0 {
        visit(i - width);
    }
    if y + 1 < height {
        visit(i + width);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn keeps_the_highest_scoring_region() {
        let (mut m, w, h) = grid(&["##...", "##..#", ".....", "...##"]);
        let mut ids = Vec::new();
        // Equal scores: the larger (the 2×2 block) wins.
        let report = keep_person_region(&mut m, w, h, |_| 1.0, 1, &mut ids);
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
            |i| if i >= 18 { 10.0 } else { 1.0 },
            1,
            &mut ids,
        );
        assert_eq!(m, grid(&[".....", ".....", ".....", "...##"]).0);
    }

    #[test]
    fn too_small_a_region_leaves_an_empty_mask() {
        let (mut m, w, h) = grid(&["#....", ".....", "....#"]);
        let mut ids = Vec::new();
        keep_person_region(&mut m, w, h, |_| 1.0, 2, &mut ids);
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
        let added = attach_parts(&mut person, &band, w, h, like, &mut part, &mut stack);
        assert_eq!(added, 3);
        assert_eq!(
            &person[w..2 * w],
            &[true, true, true, true, true, false, false, false]
        );
        assert!(part[w] && part[w + 3] && part[w + 4] && !part[w + 1] && !part[5 * w + 6]);
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
}
