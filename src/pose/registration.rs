//! Silhouette registration of the root: the posed template body moved in the image plane until its
//! projection overlaps the person's silhouette best.
//!
//! The regressed root offset and the head/hand/shoe correction ([`super::correction`]) leave the body
//! several centimetres off in the image, which the pose angles do not care about but a garment drawn
//! over the video does. Here the template body (head, hands and shoes included, as in the
//! segmenter's masks), posed by the frame, is rasterized on a grid about 160 cells wide (a quarter
//! of the resolution at 640 × 480; [`BodyMasker`]), and the integer shift within ±15 % of the image width that puts most model
//! pixels on the (block-reduced) silhouette is found coarse to fine; the root moves parallel to the
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
        let (dx, dy) = best_overlap(&model, &target, reach)?;
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
/// (same size), searched coarse to fine; ties go to the smaller shift. `None` when no shift
/// overlaps at all.
pub fn best_overlap(model: &Mask, target: &Mask, reach: i32) -> Option<(i32, i32)> {
    let width = model.width() as i32;
    let height = model.height() as i32;
    let points: Vec<(i32, i32)> = model
        .pixels()
        .iter()
        .enumerate()
        .filter(|(_, &p)| p)
        .map(|(i, _)| (i as i32 % width, i as i32 / width))
        .collect();
    if points.is_empty() {
        return None;
    }
    let hits = |dx: i32, dy: i32| -> i64 {
        points
            .iter()
            .filter(|&&(x, y)| {
                let (tx, ty) = (x + dx, y + dy);
                tx >= 0 && ty >= 0 && tx < width && ty < height && target.get(tx as u32, ty as u32)
            })
            .count() as i64
    };
    let better = |a: (i64, i32, i32), b: (i64, i32, i32)| {
        a.0 > b.0 || (a.0 == b.0 && a.1 * a.1 + a.2 * a.2 < b.1 * b.1 + b.2 * b.2)
    };
    let mut best = (hits(0, 0), 0, 0);
    let coarse = 2;
    for dy in (-reach..=reach).step_by(coarse as usize) {
        for dx in (-reach..=reach).step_by(coarse as usize) {
            let candidate = (hits(dx, dy), dx, dy);
            if better(candidate, best) {
                best = candidate;
            }
        }
    }
    let (_, cx, cy) = best;
    for dy in cy - 1..=cy + 1 {
        for dx in cx - 1..=cx + 1 {
            let candidate = (hits(dx, dy), dx, dy);
            if better(candidate, best) {
                best = candidate;
            }
        }
    }
    (best.0 > 0).then_some((best.1, best.2))
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
