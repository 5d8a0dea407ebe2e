//! Where the hands are expected: at the ends of the suit's arms.
//!
//! The segmenter's part stage attaches the head, hands and shoes to the suit by colour, and loses
//! a hand over a room of skin's colour (a cat's fur, wood, coffee), where that colour is likelier
//! room than hand. The suit's own outline says where a hand must be: beyond the end of a sleeve.
//! [`arm_ends`] finds the ends of the suit's limbs on the cut's grid as the local maxima of the
//! distance from the trunk walked inside the suit, leaves out those of the neck (the suit's top
//! rows) and of the legs (its bottom rows), and gives each remaining end the direction its limb
//! points in; [`hand_pixels`] lists the pixels of the ellipse a hand fills beyond it. The
//! segmenter's last look then leans the part test towards the part there, as it does for the head
//! and the shoes. The walks and distances are small passes over the cut's `bool` grid, written
//! here like the clean-up's: the segmenter keeps its masks as plain slices, not images, and runs
//! them within its per-frame budget (about 0.3 ms).

use std::collections::VecDeque;
use std::ops::Range;

/// A hand's half length along its arm, cm (a hand is about 18–19 cm from wrist to fingertip).
pub const HAND_HALF_LENGTH_CM: f32 = 9.0;
/// A hand's half width across its arm, cm.
pub const HAND_HALF_WIDTH_CM: f32 = 5.0;
/// How far the hand's centre lies beyond the sleeve's end, cm: the wrist sits just past it.
pub const HAND_OFFSET_CM: f32 = 9.0;
/// How far back along the limb its direction is taken, cm.
pub const AXIS_CM: f32 = 15.0;
/// The radius within which a limb's end is the farthest suit pixel from the trunk, cm.
pub const END_RADIUS_CM: f32 = 10.0;
/// How far from the trunk, walked inside the suit, an end must be to be an arm's, cm (an arm
/// hangs 50–60 cm from the shoulder, itself 15–20 cm from the trunk's middle).
pub const MIN_ARM_CM: f32 = 40.0;
/// The suit's top rows, cm, whose ends are the neck's.
pub const NECK_CM: f32 = 12.0;
/// The suit's bottom rows, cm, whose ends are the legs'.
pub const ANKLE_CM: f32 = 15.0;
/// How tall the suit is, cm: from the neck to the ankles of a 170 cm person. The suit's rows on
/// the grid over this give the pixels per cm every length here is scaled by.
pub const SUIT_HEIGHT_CM: f32 = 140.0;

/// The end of one of the suit's arms on the grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArmEnd {
    /// The middle of the sleeve's end (x, y): the suit pixels within a few steps of its
    /// farthest pixel.
    pub at: (usize, usize),
    /// The unit direction the arm points in at its end (from elbow towards wrist).
    pub direction: (f32, f32),
}

/// Scratch buffers for [`arm_ends`].
#[derive(Clone, Debug, Default)]
pub struct ArmScratch {
    steps: Vec<u32>,
    window: Vec<u32>,
    row_max: Vec<u32>,
    queue: VecDeque<usize>,
    near: Vec<u32>,
    crop: Vec<bool>,
    lines: LineScratch,
}

/// Scratch buffers for [`window_max`]: one row or column, its sliding maximum, and the running
/// maxima [`sliding_max`] builds it from.
#[derive(Clone, Debug, Default)]
struct LineScratch {
    line: Vec<u32>,
    line_max: Vec<u32>,
    forwards: Vec<u32>,
    backwards: Vec<u32>,
}

const UNREACHED: u32 = u32::MAX;

/// The ends of the arms of `suit` (row-major, `width` wide; its rows `rows`, `px_per_cm` grid
/// pixels per cm of the person): at most two, the farthest from the trunk first. The trunk is the
/// suit pixel deepest inside it; a limb's end is a suit pixel whose walk from the trunk
/// (8-connected steps) is the longest within [`END_RADIUS_CM`] and at least [`MIN_ARM_CM`]; ends
/// in the top [`NECK_CM`] or the bottom [`ANKLE_CM`] of the rows are the neck's and the legs'. An
/// arm held in front of the body ends inside the silhouette and has no end here.
pub fn arm_ends(
    suit: &[bool],
    width: usize,
    rows: Range<usize>,
    px_per_cm: f32,
    scratch: &mut ArmScratch,
) -> Vec<ArmEnd> {
    if width == 0 || px_per_cm <= 0.0 || rows.is_empty() {
        return Vec::new();
    }
    // The work is done in the suit's box grown by a pixel (the grid's edge counts as outside).
    let height = suit.len() / width;
    let Some((x0, y0, x1, y1)) = crate::mask::bounding_box_of(suit, width) else {
        return Vec::new();
    };
    let (x0, y0) = (x0.saturating_sub(1), y0.saturating_sub(1));
    let (x1, y1) = ((x1 + 1).min(width), (y1 + 1).min(height));
    let mut crop = std::mem::take(&mut scratch.crop);
    crop.clear();
    for y in y0..y1 {
        crop.extend_from_slice(&suit[y * width + x0..y * width + x1]);
    }
    let rows = rows.start.saturating_sub(y0)..rows.end.saturating_sub(y0);
    let mut ends = arm_ends_in(&crop, x1 - x0, rows, px_per_cm, scratch);
    scratch.crop = crop;
    for end in &mut ends {
        end.at = (end.at.0 + x0, end.at.1 + y0);
    }
    ends
}

/// [`arm_ends`] on a grid that is the suit's box.
fn arm_ends_in(
    suit: &[bool],
    width: usize,
    rows: Range<usize>,
    px_per_cm: f32,
    scratch: &mut ArmScratch,
) -> Vec<ArmEnd> {
    let height = suit.len() / width;
    let Some(trunk) = deepest(suit, width, height) else {
        return Vec::new();
    };
    walk(
        suit,
        width,
        height,
        &[trunk],
        None,
        &mut scratch.steps,
        &mut scratch.queue,
    );
    let radius = (END_RADIUS_CM * px_per_cm).round().max(1.0) as usize;
    window_max(
        &scratch.steps,
        (width, height),
        radius,
        (&mut scratch.row_max, &mut scratch.window),
        &mut scratch.lines,
    );
    let min_steps = (MIN_ARM_CM * px_per_cm) as u32;
    let neck_end = rows.start + (NECK_CM * px_per_cm) as usize;
    let ankle_start = rows.end.saturating_sub((ANKLE_CM * px_per_cm) as usize);
    let mut ends: Vec<(u32, usize)> = (0..suit.len())
        .filter(|&i| {
            let s = scratch.steps[i];
            let y = i / width;
            s != UNREACHED
                && s >= min_steps
                && s == scratch.window[i]
                && y >= neck_end
                && y < ankle_start
        })
        .map(|i| (scratch.steps[i], i))
        .collect();
    ends.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
    let axis = (AXIS_CM * px_per_cm).round().max(1.0) as u32;
    let mut found: Vec<ArmEnd> = Vec::new();
    for (_, i) in ends {
        let at = (i % width, i / width);
        // A plateau's other pixels, and the same arm's: one end per radius.
        let close = |e: &ArmEnd| {
            let (dx, dy) = (e.at.0 as f32 - at.0 as f32, e.at.1 as f32 - at.1 as f32);
            dx * dx + dy * dy <= (2 * radius * radius) as f32
        };
        if found.iter().any(close) {
            continue;
        }
        // The limb's direction: from the middle of its stretch between half of `axis` and
        // `axis` steps back to the middle of its last steps (the end's own pixel may be a
        // corner of the sleeve's cut).
        walk(
            suit,
            width,
            height,
            &[i],
            Some(axis),
            &mut scratch.near,
            &mut scratch.queue,
        );
        let tip_steps = (axis / 4).max(1);
        let mut sums = [(0.0f32, 0.0f32, 0usize); 2];
        for (j, &s) in scratch.near.iter().enumerate() {
            let k = if s <= tip_steps {
                0
            } else if s != UNREACHED && s >= axis / 2 {
                1
            } else {
                continue;
            };
            sums[k].0 += (j % width) as f32;
            sums[k].1 += (j / width) as f32;
            sums[k].2 += 1;
        }
        if sums[0].2 == 0 || sums[1].2 == 0 {
            continue;
        }
        let mean = |(x, y, n): (f32, f32, usize)| (x / n as f32, y / n as f32);
        let (tip, back) = (mean(sums[0]), mean(sums[1]));
        let (dx, dy) = (tip.0 - back.0, tip.1 - back.1);
        let length = (dx * dx + dy * dy).sqrt();
        if length < 0.5 {
            continue;
        }
        found.push(ArmEnd {
            at: (tip.0.round() as usize, tip.1.round() as usize),
            direction: (dx / length, dy / length),
        });
        if found.len() == 2 {
            break;
        }
    }
    found
}

/// The pixels outside `suit` (row-major indices, into `pixels`, cleared first) of the ellipse a
/// hand fills beyond `end`: [`HAND_HALF_LENGTH_CM`] along the arm, [`HAND_HALF_WIDTH_CM`] across,
/// centred [`HAND_OFFSET_CM`] past the sleeve's end.
pub fn hand_pixels(
    suit: &[bool],
    width: usize,
    end: &ArmEnd,
    px_per_cm: f32,
    pixels: &mut Vec<usize>,
) {
    pixels.clear();
    if width == 0 {
        return;
    }
    let height = suit.len() / width;
    let (ux, uy) = end.direction;
    let offset = HAND_OFFSET_CM * px_per_cm;
    let (cx, cy) = (end.at.0 as f32 + ux * offset, end.at.1 as f32 + uy * offset);
    let (a, b) = (
        HAND_HALF_LENGTH_CM * px_per_cm,
        HAND_HALF_WIDTH_CM * px_per_cm,
    );
    let reach = a.max(b);
    let lo = |c: f32| (c - reach).floor().max(0.0) as usize;
    let hi = |c: f32, limit: usize| ((c + reach).ceil() + 1.0).clamp(0.0, limit as f32) as usize;
    for y in lo(cy)..hi(cy, height) {
        for x in lo(cx)..hi(cx, width) {
            let (px, py) = (x as f32 - cx, y as f32 - cy);
            let (along, across) = ((px * ux + py * uy) / a, (py * ux - px * uy) / b);
            let i = y * width + x;
            if along * along + across * across <= 1.0 && !suit[i] {
                pixels.push(i);
            }
        }
    }
}

/// The suit pixel farthest from every pixel outside it (the 8-connected distance; ties: the
/// first in row order), or `None` without suit.
fn deepest(suit: &[bool], width: usize, height: usize) -> Option<usize> {
    // Two raster passes of the 8-connected (chessboard) distance to the nearest non-suit pixel,
    // the grid's border counting as outside.
    let mut d: Vec<u32> = suit
        .iter()
        .map(|&s| if s { u32::MAX / 2 } else { 0 })
        .collect();
    for y in 0..height {
        for x in 0..width {
            let i = y * width + x;
            if d[i] == 0 {
                continue;
            }
            let mut m = if x == 0 || y == 0 {
                0
            } else {
                d[i - width - 1]
            };
            if y > 0 {
                m = m.min(d[i - width]);
                if x + 1 < width {
                    m = m.min(d[i - width + 1]);
                } else {
                    m = 0;
                }
            }
            if x > 0 {
                m = m.min(d[i - 1]);
            }
            d[i] = d[i].min(m + 1);
        }
    }
    for y in (0..height).rev() {
        for x in (0..width).rev() {
            let i = y * width + x;
            if d[i] == 0 {
                continue;
            }
            let mut m = if x + 1 == width || y + 1 == height {
                0
            } else {
                d[i + width + 1]
            };
            if y + 1 < height {
                m = m.min(d[i + width]);
                if x > 0 {
                    m = m.min(d[i + width - 1]);
                } else {
                    m = 0;
                }
            }
            if x + 1 < width {
                m = m.min(d[i + 1]);
            }
            d[i] = d[i].min(m + 1);
        }
    }
    let mut best: Option<(u32, usize)> = None;
    for (i, &v) in d.iter().enumerate() {
        if v > 0 && best.is_none_or(|(b, _)| v > b) {
            best = Some((v, i));
        }
    }
    best.map(|(_, i)| i)
}

/// Breadth-first walk inside `suit` from `starts` in 8-connected steps, up to `limit` steps if
/// given: `steps` holds each pixel's count ([`UNREACHED`] for the others).
fn walk(
    suit: &[bool],
    width: usize,
    height: usize,
    starts: &[usize],
    limit: Option<u32>,
    steps: &mut Vec<u32>,
    queue: &mut VecDeque<usize>,
) {
    steps.clear();
    steps.resize(suit.len(), UNREACHED);
    queue.clear();
    for &s in starts {
        steps[s] = 0;
        queue.push_back(s);
    }
    while let Some(i) = queue.pop_front() {
        let next = steps[i] + 1;
        if limit.is_some_and(|l| next > l) {
            continue;
        }
        let (x, y) = (i % width, i / width);
        for dy in -1isize..=1 {
            for dx in -1isize..=1 {
                let (Some(nx), Some(ny)) = (x.checked_add_signed(dx), y.checked_add_signed(dy))
                else {
                    continue;
                };
                if nx >= width || ny >= height {
                    continue;
                }
                let j = ny * width + nx;
                if suit[j] && steps[j] == UNREACHED {
                    steps[j] = next;
                    queue.push_back(j);
                }
            }
        }
    }
}

/// The largest reached value of `values` (`width` × `height`) within the square of half side
/// `radius` about each pixel, into `out` ([`UNREACHED`] counts as nothing reached): a sliding
/// maximum along the rows, then along the columns of that.
fn window_max(
    values: &[u32],
    (width, height): (usize, usize),
    radius: usize,
    (rows, out): (&mut Vec<u32>, &mut Vec<u32>),
    lines: &mut LineScratch,
) {
    let LineScratch {
        line,
        line_max,
        forwards,
        backwards,
    } = lines;
    rows.clear();
    rows.resize(values.len(), 0);
    for y in 0..height {
        line.clear();
        line.extend(values[y * width..(y + 1) * width].iter().map(|&v| {
            if v == UNREACHED {
                0
            } else {
                v
            }
        }));
        sliding_max(line, radius, (forwards, backwards), line_max);
        rows[y * width..(y + 1) * width].copy_from_slice(line_max);
    }
    out.clear();
    out.resize(values.len(), 0);
    for x in 0..width {
        line.clear();
        line.extend((0..height).map(|y| rows[y * width + x]));
        sliding_max(line, radius, (forwards, backwards), line_max);
        for (y, &v) in line_max.iter().enumerate() {
            out[y * width + x] = v;
        }
    }
}

/// The maximum of `line` within `radius` of each place, into `out` (van Herk and Gil–Werman:
/// running maxima forwards and backwards within blocks of the window's length, so that every
/// window, the line padded with `radius` zeros at each end, is the end of one block and the
/// start of the next; a few operations a place whatever the radius).
fn sliding_max(
    line: &[u32],
    radius: usize,
    (forwards, backwards): (&mut Vec<u32>, &mut Vec<u32>),
    out: &mut Vec<u32>,
) {
    let n = line.len();
    let block = 2 * radius + 1;
    let padded = n + 2 * radius;
    let value = |j: usize| {
        if j < radius || j >= radius + n {
            0
        } else {
            line[j - radius]
        }
    };
    // forwards[j]: the maximum from the start of j's block to j; backwards[j]: from j to its end.
    forwards.clear();
    forwards.resize(padded, 0);
    backwards.clear();
    backwards.resize(padded, 0);
    for j in 0..padded {
        forwards[j] = if j % block == 0 {
            value(j)
        } else {
            forwards[j - 1].max(value(j))
        };
    }
    for j in (0..padded).rev() {
        backwards[j] = if j + 1 == padded || (j + 1) % block == 0 {
            value(j)
        } else {
            backwards[j + 1].max(value(j))
        };
    }
    out.clear();
    // Place i's window is [i, i + 2·radius] of the padded line.
    out.extend((0..n).map(|i| backwards[i].max(forwards[i + 2 * radius])));
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A grid from rows of '#' (suit) and '.'.
    fn grid(rows: &[&str]) -> (Vec<bool>, usize) {
        let width = rows[0].len();
        let suit = rows
            .iter()
            .flat_map(|r| r.chars().map(|c| c == '#'))
            .collect();
        (suit, width)
    }

    #[test]
    fn a_stick_figures_arm_ends_where_its_sleeve_does_and_points_on() {
        // A 5-wide trunk from row 2 to 13 with legs, and a right arm held out at rows 6–7 to
        // x = 17. At 0.25 px per cm an arm's end must be 10 steps from the trunk (40 cm) and the
        // farthest within 3 px (10 cm); the neck's rows are the top 3, the legs' the bottom 3.
        // The trunk's deepest pixel is (6, 4); the arm's farthest pixel (17, 6), 11 steps away.
        // Its last step (x 16–17, rows 6–7) has its middle at (16.5, 6.5), rounded (17, 7);
        // 2–4 steps back (x 13–15) the arm's middle is level with it, so it points right.
        let (suit, width) = grid(&[
            "......................",
            "......................",
            "....#####.............",
            "....#####.............",
            "....#####.............",
            "....#####.............",
            "....##############....",
            "....##############....",
            "....#####.............",
            "....#####.............",
            "....##.##.............",
            "....##.##.............",
            "....##.##.............",
            "....##.##.............",
            "......................",
        ]);
        let rows = 2..14;
        let mut scratch = ArmScratch::default();
        let ends = arm_ends(&suit, width, rows, 0.25, &mut scratch);
        assert_eq!(ends.len(), 1, "{ends:?}");
        assert_eq!(ends[0].at.0, 17);
        assert_eq!(ends[0].at.1, 7);
        assert!(ends[0].direction.0 > 0.95, "{:?}", ends[0].direction);
        // The hand's ellipse lies beyond it, outside the suit, to the right: centred 2.25 px
        // past (17, 7), 2.25 px long and 1.25 px wide each way.
        let mut pixels = Vec::new();
        hand_pixels(&suit, width, &ends[0], 0.25, &mut pixels);
        assert!(pixels.contains(&(7 * width + 19)), "{pixels:?}");
        for &i in &pixels {
            assert!(!suit[i]);
            assert!(i % width >= 17, "at x {}", i % width);
        }
    }

    #[test]
    fn a_trunk_without_arms_has_no_arm_ends() {
        let (suit, width) = grid(&[
            "..........",
            "...####...",
            "...####...",
            "...####...",
            "...####...",
            "...#..#...",
            "...#..#...",
            "..........",
        ]);
        let ends = arm_ends(&suit, width, 1..7, 0.25, &mut ArmScratch::default());
        assert!(ends.is_empty(), "{ends:?}");
        assert!(arm_ends(&[false; 12], 4, 0..0, 0.25, &mut ArmScratch::default()).is_empty());
    }

    #[test]
    fn the_sliding_maximum_is_the_maximum_of_each_window() {
        let line = [3u32, 0, 7, 1, 1, 9, 2, 0, 0, 4, 5];
        for radius in 0..5 {
            let (mut out, mut runs) = (Vec::new(), (Vec::new(), Vec::new()));
            sliding_max(&line, radius, (&mut runs.0, &mut runs.1), &mut out);
            let expected: Vec<u32> = (0..line.len())
                .map(|i| {
                    let (lo, hi) = (i.saturating_sub(radius), (i + radius).min(line.len() - 1));
                    *line[lo..=hi].iter().max().expect("non-empty")
                })
                .collect();
            assert_eq!(out, expected, "radius {radius}");
        }
        let mut out = vec![1];
        sliding_max(&[], 2, (&mut Vec::new(), &mut Vec::new()), &mut out);
        assert!(out.is_empty());
    }

    #[test]
    fn the_deepest_pixel_is_the_middle_of_the_widest_part() {
        let (suit, width) = grid(&[
            ".......", //
            ".#####.", //
            ".#####.", //
            ".#####.", //
            ".#####.", //
            ".#####.", //
            "...#...", //
        ]);
        assert_eq!(deepest(&suit, width, 7), Some(3 * width + 3));
    }
}
