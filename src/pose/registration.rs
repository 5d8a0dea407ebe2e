//! Silhouette registration of the root: the posed template body moved in the image plane until its
//! projection sits on the person's silhouette.
//!
//! The regressed root offset and the head/hand/shoe correction ([`super::correction`]) leave the body
//! several centimetres off in the image, which the pose angles do not care about but a garment drawn
//! over the video does. Here the template body, posed by the frame, is rasterized at a reduced
//! resolution ([`BodyMasker`]), and the root is moved parallel to the image plane by the difference of
//! the two masks' centroids (pixels × depth / focal length), twice (the second pass takes up what the
//! first one's change of occlusion and perspective moved). Depth is left alone: in one view it
//! trades off against the person's size, which the marker pitch fixes and
//! [`crate::body_size`] measures. Hands on hips or a leg kicked out change both masks alike, so the
//! centroids stay comparable when the pose is right; when the mask is empty or the model projects
//! off the image nothing moves.

use glam::{Affine3A, Vec2, Vec3};

use crate::body::Body;
use crate::body_size::BodyMasker;
use crate::camera::{Camera, Intrinsics};
use crate::mask::Mask;
use crate::raster::DepthBuffer;
use crate::skeleton::Skeleton;

/// Passes of the centroid alignment.
const PASSES: usize = 2;

/// The silhouette counts within the model's bounding box grown by this share of its height.
const WINDOW_MARGIN: f32 = 0.15;

/// A shift larger than this share of the image width is taken for a wrong pose, not an offset.
const MAX_SHIFT_FRACTION: f32 = 0.25;

/// The registration of one stream: the template body's meshes and scratch buffers.
#[derive(Clone, Debug)]
pub struct Registration {
    masker: BodyMasker,
    depth: DepthBuffer,
    world: Vec<Affine3A>,
    /// Resolution divisor of the model's rasterization.
    pub downscale: u32,
}

impl Registration {
    pub fn new(body: &Body) -> Registration {
        Registration {
            masker: BodyMasker::new(body),
            depth: DepthBuffer::new(1, 1),
            world: Vec::new(),
            downscale: 4,
        }
    }

    /// Moves the root (`root_position`: the frame's X, Y, Z position channels, world cm) of `frame`
    /// on `skeleton` so the body's projection is centred on `silhouette`. Returns the total image
    /// shift applied (full-resolution pixels), or `None` when nothing could be measured.
    pub fn register(
        &mut self,
        skeleton: &Skeleton,
        frame: &mut [f32],
        root_position: [usize; 3],
        silhouette: &Mask,
        camera: &Camera,
    ) -> Option<Vec2> {
        if root_position.iter().any(|&c| c >= frame.len()) {
            return None;
        }
        if silhouette.is_empty() {
            return None;
        }
        let small = downscaled(camera, self.downscale);
        let factor = self.downscale as f32;
        let mut total = Vec2::ZERO;
        for _ in 0..PASSES {
            skeleton.forward_kinematics(frame, &mut self.world);
            let model = self.masker.mask(&self.world, &small, &mut self.depth);
            let (Some(model_centre), Some(model_box)) = (centroid(&model), model.bounding_box())
            else {
                break;
            };
            // Only the silhouette near the model counts, so a segmentation leak elsewhere in the
            // picture does not pull the body away from the person.
            let margin = WINDOW_MARGIN * (model_box.3 - model_box.1) as f32;
            let window = [
                model_box.0 as f32 - margin,
                model_box.1 as f32 - margin,
                model_box.2 as f32 + margin,
                model_box.3 as f32 + margin,
            ]
            .map(|v| v * factor);
            let Some(target) = centroid_within(silhouette, window) else {
                break;
            };
            // Pixel centres: a low-resolution pixel i covers full-resolution [f·i, f·(i+1)).
            let shift = target - model_centre * factor;
            if shift.length() > MAX_SHIFT_FRACTION * camera.intrinsics.width as f32 {
                return None;
            }
            let root = Vec3::new(frame[root_position[0]], frame[root_position[1]], frame[root_position[2]]);
            let root_world = self.world.first().map_or(root, |t| Vec3::from(t.translation));
            let depth = camera.to_camera(root_world).z;
            if !(depth > 1.0) {
                return None;
            }
            let k = &camera.intrinsics;
            let in_camera = Vec3::new(shift.x * depth / k.fx, shift.y * depth / k.fy, 0.0);
            let in_world = camera.rotation.transpose() * in_camera;
            for (axis, &c) in root_position.iter().enumerate() {
                frame[c] += in_world[axis];
            }
            total += shift;
        }
        (total != Vec2::ZERO).then_some(total)
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
    let (cy0, cy1) = (clip(y0, mask.height() as usize), clip(y1.ceil(), mask.height() as usize));
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
        assert_eq!(centroid_within(&m, [0.0, 0.0, 2.0, 4.0]), Some(Vec2::new(1.5, 2.0)));
    }

    /// A body rendered 12 cm to the side of where the frame puts it is moved back onto it.
    #[test]
    fn a_root_off_to_the_side_is_moved_onto_the_silhouette() {
        let clip = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mocap/cmu_02_01_walk.bvh");
        let motion = crate::bvh::Motion::load(&clip).expect("clip");
        let skeleton = &motion.skeleton;
        let body = template_body(skeleton).expect("body");
        let root = skeleton.joint(0);
        let channel = |name: crate::skeleton::Channel| {
            root.first_channel + root.channels.iter().position(|c| *c == name).expect("channel")
        };
        use crate::skeleton::Channel::*;
        let root_position = [channel(Xposition), channel(Yposition), channel(Zposition)];
        let truth: Vec<f32> = motion.frame(40).to_vec();
        let hip = Vec3::new(truth[root_position[0]], truth[root_position[1]], truth[root_position[2]]);
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
