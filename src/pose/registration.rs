//! Silhouette registration of the root: the posed template body moved in the image plane until its
//! projection overlaps the person's silhouette best.
//!
//! The regressed root offset and the head/hand/shoe correction ([`super::correction`]) leave the body
//! several centimetres off in the image, which the pose angles do not care about but a garment drawn
//! over the video does. Here the template body (head, hands and shoes included, as in the
//! segmenter's masks), posed by the frame, is rasterized on a grid about 160 cells wide (a quarter
//! of the resolution at 640 × 480; [`BodyMasker`]), and the integer shift within ±15 % of the image width that puts most model
//! pixels on the (block-reduced) silhouette, less a cost growing with the square of the shift
//! (`SHIFT_PENALTY`), is found coarse to fine; the root moves parallel to the
//! image plane by that shift × depth / focal length. Overlap, unlike aligning centroids, is not
//! dragged by a segmentation leak or by legs leaving the picture: a leak adds the same pixels to
//! every candidate shift that does not reach it. Depth is left alone: in one view it trades off
//! against the person's size, which the marker pitch fixes and [`crate::body_size`] measures.

use glam::{Affine3A, Vec2, Vec3};

use crate::body::Body;
use crate::body_size::BodyMasker;
use crate::camera::{Camera, Intrinsics};
use crate::mask::Mask;
use crate::raster::DepthBuffer;
use crate::skeleton::Skeleton;

/// The search reaches this share of the image width in every direction.
const MAX_SHIFT_FRACTION: f32 = 0.15;

/// What a shift costs, in overlapping cells per squared cell of shift (on the grid of
/// [`Registration::cells_across`] cells, so alike at every resolution; the body's area and a
/// misplacement of a given share of its height both grow with the square of its size, so alike
/// at every distance too). Without it the largest overlap alone decided, and where the estimated
/// pose differs from the person's (a kick's raised leg, a lean towards the camera with the legs
/// leaving the picture) a shift of the wrong shape onto other parts of the silhouette overlapped a
/// few cells more: on the bundled demo's frame 43 it moved the root 68 pixels down, 57 pixels from
/// the truth where the regressor alone was 17 off. Chosen on nine fresh renderings of training
/// motions (every third clip of a fifth rendering, seeds 2101–2127), with the root at the marker
/// depth and not shifted onto the head, hand and shoe blobs (as the pipeline runs): mean image
/// distance of the root after the registration 7.0 / 6.2 / **5.8** / 6.0 / 6.6 px at ½, 1, 2, 4,
/// 8 (8.5 px with no penalty and the blobs' shift). On the six pose test sequences 9.3 → 7.6 px
/// (10.5 → 9.7 cm) and on the demo 13.0 → 8.8 px with both changes (docs/measurements.md, fourth
/// session of 2026-12-05, which also has the test figures of the values tried on the way).
const SHIFT_PENALTY: f64 = 2.0;

/// The registration of one stream: the template body's meshes and scratch buffers.
#[derive(Clone, Debug)]
pub struct Registration {
    masker: BodyMasker,
    depth: DepthBuffer,
    world: Vec<Affine3A>,
    /// The model is rasterized and compared on a grid about this many cells wide: the resolution
    /// divisor is the image width over it (4 at 640 pixels, 9 at 1440), so the search costs the
    /// same at every camera resolution.
    pub cells_across: u32,
}

impl Registration {
    /// A registration against the segmenter's masks, which cover the whole person (head, hands and
    /// shoes are attached to the suit since the segmenter's model version 6).
    pub fn new(body: &Body) -> Registration {
        Registration {
            masker: BodyMasker::new(body),
            depth: DepthBuffer::new(1, 1),
            world: Vec::new(),
            cells_across: 160,
        }
    }

    /// Moves the root (`root_position`: the frame's X, Y, Z position channels, world cm) of `frame`
    /// on `skeleton` so the body's projection overlaps `silhouette` best. Returns the image shift
    /// applied (full-resolution pixels), or `None` when nothing could be measured.
    pub fn register(
        &mut self,
        skeleton: &Skeleton,
        frame: &mut [f32],
        root_position: [usize; 3],
        silhouette: &Mask,
        camera: &Camera,
    ) -> Option<Vec2> {
        if root_position.iter().any(|&c| c >= frame.len()) || silhouette.is_empty() {
            return None;
        }
        let downscale = (camera.intrinsics.width / self.cells_across.max(1)).max(1);
        let small = downscaled(camera, downscale);
        let factor = downscale as f32;
        skeleton.forward_kinematics(frame, &mut self.world);
        let model = self.masker.mask(&self.world, &small, &mut self.depth);
        let target = block_mask(
            silhouette,
            downscale,
            small.intrinsics.width,
            small.intrinsics.height,
        );
        let reach = (MAX_SHIFT_FRACTION * small.intrinsics.width as f32) as i32;
        let (dx, dy) = best_overlap(&model, &target, reach, SHIFT_PENALTY)?;
        let shift = Vec2::new(dx as f32, dy as f32) * factor;
        let root_world = self.world.first().map(|t| Vec3::from(t.translation))?;
        let depth = camera.to_camera(root_world).z;
        if depth.is_nan() || depth <= 1.0 {
            return None;
        }
        let k = &camera.intrinsics;
        let in_camera = Vec3::new(shift.x * depth / k.fx, shift.y * depth / k.fy, 0.0);
        let in_world = camera.rotation.transpose() * in_camera;
        for (axis, &c) in root_position.iter().enumerate() {
            frame[c] += in_world[axis];
        }
        Some(shift)
    }
}

/// `mask` at `1/factor` resolution (`width × height`): a cell is person when at least half of its
/// block is.
pub fn block_mask(mask: &Mask, factor: u32, width: u32, height: u32) -> Mask {
    let f = factor.max(1) as usize;
    let (w, h) = (mask.width() as usize, mask.height() as usize);
    let mut counts = vec![0u32; width as usize * height as usize];
    for (y, row) in mask.pixels().chunks(w.max(1)).enumerate() {
        let cy = (y / f).min(height as usize - 1);
        for (x, _) in row.iter().enumerate().filter(|(_, &p)| p) {
            counts[cy * width as usize + (x / f).min(width as usize - 1)] += 1;
        }
    }
    let half = ((f * f) as u32).div_ceil(2);
    let _ = h;
    let pixels = counts.iter().map(|&c| c >= half).collect();
    Mask::from_pixels(width, height, pixels).unwrap_or_else(|| Mask::empty(width, height))
}

/// The integer shift (within ±`reach` cells) that puts most of `model`'s pixels on `target`
/// (same size), less `shift_penalty` × its squared length in cells, searched coarse to fine; ties
/// go to the smaller shift. `None` when the shift found overlaps nothing. The masks are compared
/// as rows of bits, 64 cells a word: a shift's overlap is
/// the popcount of each model row AND the target's row shifted, three words a row on the
/// 160-cell-wide grid, where one test per model cell took 1,500–2,000 per shift (about 650 shifts;
/// the root stage took 0.5 ms longer per 640×480 frame that way).
pub fn best_overlap(
    model: &Mask,
    target: &Mask,
    reach: i32,
    shift_penalty: f64,
) -> Option<(i32, i32)> {
    let model = BitRows::new(model);
    let target = BitRows::new(target);
    let rows = model.set_rows()?;
    let hits = |dx: i32, dy: i32| overlap(&model, rows.clone(), &target, dx, dy);
    let score = |dx: i32, dy: i32| hits(dx, dy) as f64 - shift_penalty * (dx * dx + dy * dy) as f64;
    let better = |a: (f64, i32, i32), b: (f64, i32, i32)| {
        a.0 > b.0 || (a.0 == b.0 && a.1 * a.1 + a.2 * a.2 < b.1 * b.1 + b.2 * b.2)
    };
    let mut best = (score(0, 0), 0, 0);
    let coarse = 2;
    for dy in (-reach..=reach).step_by(coarse as usize) {
        for dx in (-reach..=reach).step_by(coarse as usize) {
            let candidate = (score(dx, dy), dx, dy);
            if better(candidate, best) {
                best = candidate;
            }
        }
    }
    let (_, cx, cy) = best;
    for dy in cy - 1..=cy + 1 {
        for dx in cx - 1..=cx + 1 {
            let candidate = (score(dx, dy), dx, dy);
            if better(candidate, best) {
                best = candidate;
            }
        }
    }
    (hits(best.1, best.2) > 0).then_some((best.1, best.2))
}

/// A mask's rows as bits: cell x of a row is bit x % 64 of the row's word x / 64; the bits past
/// the width are zero.
struct BitRows {
    words_per_row: usize,
    height: usize,
    bits: Vec<u64>,
}

impl BitRows {
    fn new(mask: &Mask) -> BitRows {
        let width = mask.width() as usize;
        let words_per_row = width.div_ceil(64);
        let mut bits = vec![0u64; words_per_row * mask.height() as usize];
        if width > 0 {
            for (row, words) in mask
                .pixels()
                .chunks_exact(width)
                .zip(bits.chunks_exact_mut(words_per_row))
            {
                for (cells, word) in row.chunks(64).zip(words.iter_mut()) {
                    *word = cells
                        .iter()
                        .enumerate()
                        .fold(0, |w, (i, &p)| w | (p as u64) << i);
                }
            }
        }
        BitRows {
            words_per_row,
            height: mask.height() as usize,
            bits,
        }
    }

    /// Row `y`'s words, `None` outside the mask.
    fn row(&self, y: i32) -> Option<&[u64]> {
        let y = usize::try_from(y).ok().filter(|&y| y < self.height)?;
        Some(&self.bits[y * self.words_per_row..(y + 1) * self.words_per_row])
    }

    /// The rows from the first to the last with a set cell; `None` when no cell is set.
    fn set_rows(&self) -> Option<std::ops::Range<usize>> {
        let set = |y: &usize| {
            self.row(*y as i32)
                .is_some_and(|r| r.iter().any(|&w| w != 0))
        };
        let first = (0..self.height).find(set)?;
        let last = (0..self.height).rev().find(set)?;
        Some(first..last + 1)
    }
}

/// How many set cells of `model`'s `rows` land on set cells of `target` when shifted by (dx, dy):
/// per row, the popcount of each model word AND the target's cells under it.
fn overlap(
    model: &BitRows,
    rows: std::ops::Range<usize>,
    target: &BitRows,
    dx: i32,
    dy: i32,
) -> u32 {
    let mut count = 0u32;
    for y in rows {
        let Some(target_row) = target.row(y as i32 + dy) else {
            continue;
        };
        for (k, &word) in model.row(y as i32).unwrap_or(&[]).iter().enumerate() {
            if word != 0 {
                count += (word & bits_from(target_row, 64 * k as i32 + dx)).count_ones();
            }
        }
    }
    count
}

/// The 64 cells of `row` from column `start` on (bit i = cell start + i), zero where they fall
/// outside the row.
fn bits_from(row: &[u64], start: i32) -> u64 {
    let word = |k: i32| {
        usize::try_from(k)
            .ok()
            .and_then(|k| row.get(k))
            .copied()
            .unwrap_or(0)
    };
    let (k, offset) = (start.div_euclid(64), start.rem_euclid(64) as u32);
    if offset == 0 {
        word(k)
    } else {
        (word(k) >> offset) | (word(k + 1) << (64 - offset))
    }
}

/// The camera with its image scaled down by `factor` (intrinsics divided, extrinsics unchanged).
pub fn downscaled(camera: &Camera, factor: u32) -> Camera {
    let f = factor.max(1) as f32;
    let k = camera.intrinsics;
    Camera {
        intrinsics: Intrinsics {
            width: (k.width as f32 / f).ceil() as u32,
            height: (k.height as f32 / f).ceil() as u32,
            fx: k.fx / f,
            fy: k.fy / f,
            cx: k.cx / f,
            cy: k.cy / f,
        },
        ..*camera
    }
}

/// Mean position of the mask's pixels (pixel centres at +0.5), or `None` for an empty mask.
pub fn centroid(mask: &Mask) -> Option<Vec2> {
    centroid_within(mask, [0.0, 0.0, f32::INFINITY, f32::INFINITY])
}

/// Mean position of the mask's pixels inside `[x0, y0, x1, y1)` (clipped to the image).
pub fn centroid_within(mask: &Mask, [x0, y0, x1, y1]: [f32; 4]) -> Option<Vec2> {
    let width = mask.width() as usize;
    let clip = |v: f32, max: usize| (v.max(0.0).floor() as usize).min(max);
    let (cx0, cx1) = (clip(x0, width), clip(x1.ceil(), width));
    let (cy0, cy1) = (
        clip(y0, mask.height() as usize),
        clip(y1.ceil(), mask.height() as usize),
    );
    let (mut sx, mut sy, mut n) = (0.0f64, 0.0f64, 0usize);
    for row in cy0..cy1 {
        let pixels = &mask.pixels()[row * width + cx0..row * width + cx1];
        let mut count = 0usize;
        let mut sum = 0usize;
        for (x, _) in pixels.iter().enumerate().filter(|(_, &p)| p) {
            count += 1;
            sum += x + cx0;
        }
        sx += sum as f64 + 0.5 * count as f64;
        sy += (row as f64 + 0.5) * count as f64;
        n += count;
    }
    (n > 0).then(|| Vec2::new((sx / n as f64) as f32, (sy / n as f64) as f32))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body_size::{template_body, BodyMasker};
    use std::path::Path;

    #[test]
    fn the_centroid_of_a_two_by_two_block_is_its_middle() {
        let mut m = Mask::empty(4, 4);
        for (x, y) in [(1, 1), (2, 1), (1, 2), (2, 2)] {
            m.pixels_mut()[y * 4 + x] = true;
        }
        assert_eq!(centroid(&m), Some(Vec2::new(2.0, 2.0)));
        assert_eq!(centroid(&Mask::empty(3, 3)), None);
        // Only the left column inside the window [0, 2) × [0, 4).
        assert_eq!(
            centroid_within(&m, [0.0, 0.0, 2.0, 4.0]),
            Some(Vec2::new(1.5, 2.0))
        );
    }

    /// The overlap of `model` shifted by (dx, dy) with `target`, one test per model pixel: the
    /// definition the bit rows compute.
    fn overlap_by_pixels(model: &Mask, target: &Mask, dx: i32, dy: i32) -> usize {
        let (w, h) = (model.width() as i32, model.height() as i32);
        (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                let (tx, ty) = (x + dx, y + dy);
                model.get(x as u32, y as u32)
                    && tx >= 0
                    && ty >= 0
                    && tx < w
                    && ty < h
                    && target.get(tx as u32, ty as u32)
            })
            .count()
    }

    proptest::proptest! {
        /// On masks 1–150 cells wide (rows of one to three words), the bit rows' overlap at
        /// shifts within and across words equals the count pixel by pixel, and the shift found
        /// overlaps the target.
        #[test]
        fn the_bit_rows_count_the_overlap_pixel_by_pixel(
            width in 1u32..150,
            height in 1u32..10,
            model_seed in proptest::collection::vec(0u32..100_000, 1..40),
            target_seed in proptest::collection::vec(0u32..100_000, 1..40),
        ) {
            let n = width * height;
            let mask = |seed: &[u32]| {
                Mask::from_fn(width, height, |x, y| seed.iter().any(|&s| s % n == y * width + x))
            };
            let (model, target) = (mask(&model_seed), mask(&target_seed));
            let (bm, bt) = (BitRows::new(&model), BitRows::new(&target));
            for (dx, dy) in [(0, 0), (1, 0), (-1, 0), (63, 1), (-64, -1), (65, 2), (-130, 0), (7, -3)] {
                let by_bits = overlap(&bm, bm.set_rows().unwrap_or(0..0), &bt, dx, dy);
                proptest::prop_assert_eq!(by_bits as usize, overlap_by_pixels(&model, &target, dx, dy));
            }
            if let Some((dx, dy)) = best_overlap(&model, &target, 4, 0.25) {
                proptest::prop_assert!(overlap_by_pixels(&model, &target, dx, dy) > 0);
            }
        }
    }

    #[test]
    fn a_shifted_block_is_found_at_its_shift() {
        // A 3 × 2 block at (10, 3) in the model, at (80, 5) in the target: 70 cells right (across
        // a word boundary) and 2 down.
        let block = |x0: u32, y0: u32| {
            Mask::from_fn(100, 8, move |x, y| {
                (x0..x0 + 3).contains(&x) && (y0..y0 + 2).contains(&y)
            })
        };
        assert_eq!(
            best_overlap(&block(10, 3), &block(80, 5), 72, 0.0),
            Some((70, 2))
        );
        assert_eq!(
            best_overlap(&block(10, 3), &Mask::empty(100, 8), 72, 0.0),
            None
        );
    }

    #[test]
    fn a_far_shift_must_overlap_more_than_it_costs() {
        // The model's 3 × 2 block at (10, 3) overlaps a 2 × 2 piece at (11, 3) by 4 cells where
        // it is, and a whole 3 × 2 block at (60, 3) by 6 cells 50 cells to the right.
        let target = Mask::from_fn(100, 8, |x, y| {
            (3..5).contains(&y) && ((11..13).contains(&x) || (60..63).contains(&x))
        });
        let model = Mask::from_fn(100, 8, |x, y| (3..5).contains(&y) && (10..13).contains(&x));
        // Overlap alone: 6 cells beat 4. With a cell of overlap per squared cell of shift, the
        // far block would cost 2,500: the model stays (a shift of 1 also overlaps 4 but costs 1).
        assert_eq!(best_overlap(&model, &target, 60, 0.0), Some((50, 0)));
        assert_eq!(best_overlap(&model, &target, 60, 1.0), Some((0, 0)));
        // Nothing overlapping anywhere nearby, and too far to pay for: no shift.
        let far = Mask::from_fn(100, 8, |x, y| (x, y) == (90, 3));
        assert_eq!(best_overlap(&model, &far, 85, 1.0), None);
    }

    /// A body rendered 12 cm to the side of where the frame puts it is moved back onto it.
    #[test]
    fn a_root_off_to_the_side_is_moved_onto_the_silhouette() {
        let clip =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mocap/cmu_02_01_walk.bvh");
        let motion = crate::bvh::Motion::load(&clip).expect("clip");
        let skeleton = &motion.skeleton;
        let body = template_body(skeleton).expect("body");
        let root = skeleton.joint(0);
        let channel = |name: crate::skeleton::Channel| {
            root.first_channel
                + root
                    .channels
                    .iter()
                    .position(|c| *c == name)
                    .expect("channel")
        };
        use crate::skeleton::Channel::*;
        let root_position = [channel(Xposition), channel(Yposition), channel(Zposition)];
        let truth: Vec<f32> = motion.frame(40).to_vec();
        let hip = Vec3::new(
            truth[root_position[0]],
            truth[root_position[1]],
            truth[root_position[2]],
        );
        let camera = Camera::look_at(
            Intrinsics::from_fov(320, 240, 60.0),
            hip + Vec3::new(0.0, 10.0, 450.0),
            hip,
            Vec3::Y,
        );
        let mut world = Vec::new();
        skeleton.forward_kinematics(&truth, &mut world);
        let mut depth = DepthBuffer::new(320, 240);
        let silhouette = BodyMasker::new(&body).mask(&world, &camera, &mut depth);
        let mut frame = truth.clone();
        frame[root_position[0]] += 12.0; // camera x is world x here
        let mut registration = Registration::new(&body);
        let shift = registration
            .register(skeleton, &mut frame, root_position, &silhouette, &camera)
            .expect("measured");
        assert!(shift.x < 0.0, "{shift:?}");
        let error = (frame[root_position[0]] - truth[root_position[0]]).abs();
        assert!(error < 2.0, "root still {error} cm off");
    }
}
