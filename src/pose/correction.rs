//! Position correction (source paper sec. 3.2): the head, the hands and the shoes are found in the frame
//! by their colour, and the regressed body is moved so that its head, hands and feet project onto them.
//!
//! Inside the person's mask, skin pixels (hue within 50° of orange-red, moderate saturation, not too
//! dark) and shoe pixels (very dark) are grouped into 4-connected blobs. The head is the skin blob
//! nearest the top of the silhouette; the other skin blobs are hand candidates; dark blobs in the lower
//! third are shoe candidates. The body parts' centres (from the capsule body model) are projected
//! through the camera; each is paired with the nearest blob of its kind within a fifth of the
//! silhouette's height. The pairs' spread about their centroid, projected against observed, rescales the
//! root's depth (a body drawn too small is too far away), and the centroids' displacement moves the root
//! parallel to the image plane. With fewer than two pairs nothing moves; with a spread under 10 pixels
//! only the displacement is used.
//!
//! Before that, the suit itself gives the absolute scale that a silhouette cannot (a tall person far
//! away looks like a short one near by): markers sit on a grid of known pitch, so the typical distance
//! between neighbouring marker centres in pixels gives the depth of the suit's surface
//! ([`depth_from_markers`]); the root is put on its camera ray at that depth plus
//! [`ROOT_BEHIND_SURFACE_CM`] ([`root_to_depth`]). When this is available the landmark spread does
//! not rescale the depth, and the pose pipeline uses the depth alone: the blobs' shift on top of it
//! moved the root away from the truth in the image on average (see
//! `PosePipeline::landmarks_with_marker_depth`); the silhouette registration places it instead.

use glam::{Affine3A, Vec2, Vec3};
use image::RgbImage;

use crate::body::{Body, BodyPart, SUBJECTS};
use crate::camera::Camera;
use crate::mask::Mask;
use crate::segment::cleanup::components;
use crate::segment::features::ColourLut;
use crate::skeleton::Skeleton;

/// Colour blobs found in one frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Landmarks {
    pub head: Option<Vec2>,
    pub hands: Vec<Vec2>,
    pub feet: Vec<Vec2>,
}

/// Is this a skin-coloured pixel (hue, saturation, value on 0–255)?
fn is_skin(hue: u8, sat: u8, val: u8) -> bool {
    // Hue 340°..360° and 0°..50° on the 256-step circle: 242..=255 and 0..=35.
    (hue <= 35 || hue >= 242) && (30..=170).contains(&sat) && val >= 50
}

/// Finds the head, hand and shoe blobs inside `mask`.
pub fn find_landmarks(frame: &RgbImage, mask: &Mask, lut: &ColourLut) -> Landmarks {
    let Some((x0, y0, x1, y1)) = mask.bounding_box() else {
        return Landmarks::default();
    };
    if frame.dimensions() != (mask.width(), mask.height()) {
        return Landmarks::default();
    }
    let (w, h) = ((x1 - x0) as usize, (y1 - y0) as usize);
    let width = frame.width() as usize;
    let raw = frame.as_raw();
    let mut skin = vec![false; w * h];
    let mut dark = vec![false; w * h];
    for y in 0..h {
        for x in 0..w {
            let i = (y + y0 as usize) * width + x + x0 as usize;
            if !mask.pixels()[i] {
                continue;
            }
            let c = lut.get([raw[3 * i], raw[3 * i + 1], raw[3 * i + 2]]);
            skin[y * w + x] = c.chromatic && is_skin(c.hue, c.sat, c.val);
            dark[y * w + x] = c.val < 50;
        }
    }
    let min_area = (w * h / 2000).max(4);
    let blobs = |pixels: &[bool]| -> Vec<(Vec2, usize)> {
        let mut ids = Vec::new();
        let stats = components(pixels, w, h, true, &mut ids);
        let mut sums = vec![Vec2::ZERO; stats.len()];
        for (i, &id) in ids.iter().enumerate() {
            if id != u32::MAX {
                sums[id as usize] += Vec2::new((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
            }
        }
        stats
            .iter()
            .zip(sums)
            .filter(|((count, _), _)| *count >= min_area)
            .map(|((count, _), sum)| {
                (
                    sum / *count as f32 + Vec2::new(x0 as f32, y0 as f32),
                    *count,
                )
            })
            .collect()
    };
    let mut skin_blobs = blobs(&skin);
    skin_blobs.sort_by(|a, b| a.0.y.total_cmp(&b.0.y));
    let head = skin_blobs
        .first()
        .filter(|b| b.0.y < y0 as f32 + 0.35 * h as f32)
        .map(|b| b.0);
    let hands = skin_blobs
        .iter()
        .skip(head.is_some() as usize)
        .map(|b| b.0)
        .collect();
    let feet = blobs(&dark)
        .into_iter()
        .filter(|b| b.0.y > y0 as f32 + 0.66 * h as f32)
        .map(|b| b.0)
        .collect();
    Landmarks { head, hands, feet }
}

/// Depth of the pelvis behind the visible suit surface (half a torso's depth), in cm.
pub const ROOT_BEHIND_SURFACE_CM: f32 = 10.0;

/// How much shorter than the printed pitch the 95th percentile of the detected markers'
/// nearest-neighbour distances comes out: their median ratio on six of the default suit's training
/// sequences (punch 02_05, dance 05_02, run 09_04, sit 13_01, traffic 13_26, drink 14_37) was
/// 0.960 (0.935–0.989). Ground-truth marker centres with at least 60 % of their area visible give
/// 0.98–1.01: the detector adds foreshortened and partly hidden markers whose centres sit closer.
/// Since the generator stopped printing markers on the caps where two suit parts meet (no more
/// doubled squares at the joints, 2026-12-03), 0.96 put the root too near on the same six
/// sequences (median estimated / true depth 0.988, `suitcap-train eval` prints it); 0.97 gave 0.998
/// (0.972–1.019 per sequence). Since it also leaves out the markers where two parts overlap at the
/// shoulders and hips (`SEAM_MARGIN_CM` in `body.rs`), whose seams lengthen some nearest-neighbour
/// distances, 0.97 gave 0.982 (0.959–1.003) on the same six, so the constant became 0.97 / 0.982
/// (1.002 with it, 0.979–1.023; the same after the detector's sliver rule).
pub const DETECTED_PITCH_SHORTFALL: f32 = 0.99;

/// Depth (cm) of the suit's surface from the marker grid: the 95th percentile of each marker's
/// distance to its nearest neighbour, divided by [`DETECTED_PITCH_SHORTFALL`], is taken as the
/// pitch in pixels. Foreshortened markers on the sides of limbs are nearer each other; the upper
/// tail sees the ones facing the camera. (The median was 141 cm off on the test sequences; the 90th
/// percentile without the shortfall put the root 6–15 % too far on all six, and the body-size
/// estimate, which renders the template body at this depth, 4–12 % too tall.) Needs at least 12
/// markers.
pub fn depth_from_markers(centres: &[Vec2], pitch_cm: f32, focal: f32) -> Option<f32> {
    if centres.len() < 12 {
        return None;
    }
    let mut nearest: Vec<f32> = centres
        .iter()
        .enumerate()
        .map(|(i, a)| {
            centres
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, b)| a.distance(*b))
                .fold(f32::INFINITY, f32::min)
        })
        .filter(|d| d.is_finite() && *d > 0.5)
        .collect();
    if nearest.len() < 12 {
        return None;
    }
    nearest.sort_by(f32::total_cmp);
    let pitch_px = nearest[nearest.len() * 19 / 20] / DETECTED_PITCH_SHORTFALL;
    Some(focal * pitch_cm / pitch_px)
}

/// The body parts whose centres are matched, on a neutral body over `skeleton`.
#[derive(Clone, Debug)]
pub struct CorrectionParts {
    head: Option<BodyPart>,
    hands: Vec<BodyPart>,
    feet: Vec<BodyPart>,
}

impl CorrectionParts {
    /// Parts of the default-proportioned body on `skeleton` (None if it lacks the CMU joint names).
    pub fn new(skeleton: &Skeleton) -> Option<CorrectionParts> {
        let body = Body::new(&SUBJECTS[2], skeleton).ok()?;
        let find = |name: &str| body.parts.iter().find(|p| p.name == name).cloned();
        Some(CorrectionParts {
            head: find("head"),
            hands: ["right_hand", "left_hand"]
                .iter()
                .filter_map(|n| find(n))
                .collect(),
            feet: ["right_foot", "left_foot"]
                .iter()
                .filter_map(|n| find(n))
                .collect(),
        })
    }
}

/// Puts the root of `frame` on its camera ray at [`ROOT_BEHIND_SURFACE_CM`] behind the suit's
/// surface at `surface_depth` (cm, from [`depth_from_markers`]): the depth alone, the root's pixel
/// unchanged.
pub fn root_to_depth(
    frame: &mut [f32],
    skeleton: &Skeleton,
    root_position: [usize; 3],
    camera: &Camera,
    surface_depth: f32,
) {
    let mut world = Vec::new();
    skeleton.forward_kinematics(frame, &mut world);
    let Some(root) = world.first().map(|t| Vec3::from(t.translation)) else {
        return;
    };
    if let Some(p) = camera.project(root) {
        let moved = camera.unproject(p.pixel, surface_depth + ROOT_BEHIND_SURFACE_CM);
        for (axis, &c) in root_position.iter().enumerate() {
            frame[c] += moved[axis] - root[axis];
        }
    }
}

fn centre(part: &BodyPart, world: &[Affine3A]) -> Vec3 {
    world[part.joint].transform_point3((part.start + part.end) * 0.5)
}

/// Moves the root of `frame` (root position channels `root_position`) so the projected head, hands and
/// feet land on the landmarks. Returns the image shift applied, if any.
#[allow(clippy::too_many_arguments)] // independent per-frame inputs; a struct adds only noise
pub fn correct_root(
    frame: &mut [f32],
    skeleton: &Skeleton,
    root_position: [usize; 3],
    parts: &CorrectionParts,
    camera: &Camera,
    landmarks: &Landmarks,
    silhouette_height: f32,
    surface_depth: Option<f32>,
) -> Option<Vec2> {
    let mut world = Vec::new();
    if let Some(depth) = surface_depth {
        root_to_depth(frame, skeleton, root_position, camera, depth);
    }
    skeleton.forward_kinematics(frame, &mut world);
    let reach = 0.2 * silhouette_height;
    // (projected, observed) pixel pairs.
    let mut pairs: Vec<(Vec2, Vec2)> = Vec::new();
    let mut pair = |part: &BodyPart, candidates: &[Vec2]| {
        let Some(p) = camera.project(centre(part, &world)) else {
            return;
        };
        if let Some(best) = candidates
            .iter()
            .min_by(|a, b| a.distance(p.pixel).total_cmp(&b.distance(p.pixel)))
        {
            if best.distance(p.pixel) <= reach {
                pairs.push((p.pixel, *best));
            }
        }
    };
    if let (Some(part), Some(head)) = (&parts.head, landmarks.head) {
        pair(part, &[head]);
    }
    for part in &parts.hands {
        pair(part, &landmarks.hands);
    }
    for part in &parts.feet {
        pair(part, &landmarks.feet);
    }
    if pairs.len() < 2 {
        return None;
    }
    let n = pairs.len() as f32;
    let centroid_projected = pairs.iter().map(|p| p.0).sum::<Vec2>() / n;
    let centroid_observed = pairs.iter().map(|p| p.1).sum::<Vec2>() / n;
    let spread = |c: Vec2, pick: fn(&(Vec2, Vec2)) -> Vec2| {
        pairs.iter().map(|p| pick(p).distance(c)).sum::<f32>() / n
    };
    let (spread_projected, spread_observed) = (
        spread(centroid_projected, |p| p.0),
        spread(centroid_observed, |p| p.1),
    );
    let scale = if surface_depth.is_none() && spread_projected > 10.0 && spread_observed > 10.0 {
        (spread_observed / spread_projected).clamp(0.67, 1.5)
    } else {
        1.0
    };
    let root = Vec3::from(world[0].translation);
    let projected = camera.project(root)?;
    // The root keeps its place relative to the matched parts, scaled with them.
    let pixel = centroid_observed + (projected.pixel - centroid_projected) * scale;
    let shift = pixel - projected.pixel;
    let moved = camera.unproject(pixel, projected.depth / scale);
    let delta = moved - root;
    for (axis, &c) in root_position.iter().enumerate() {
        frame[c] += delta[axis];
    }
    Some(shift)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn a_grid_of_markers_gives_its_depth() {
        // A 6 × 4 grid 14 px apart, pitch 7 cm, focal 600 px: depth = 600 · 7 / 14 = 300 cm, times
        // the detector's shortfall (0.99): 297 cm.
        let centres: Vec<Vec2> = (0..24)
            .map(|i| Vec2::new((i % 6) as f32 * 14.0, (i / 6) as f32 * 14.0))
            .collect();
        let depth = depth_from_markers(&centres, 7.0, 600.0).expect("enough markers");
        assert!((depth - 297.0).abs() < 1e-3, "{depth}");
        assert!(depth_from_markers(&centres[..5], 7.0, 600.0).is_none());
    }

    #[test]
    fn skin_and_markers_are_told_apart() {
        let lut = ColourLut::new();
        let class = |rgb: [u8; 3]| {
            let c = lut.get(rgb);
            c.chromatic && is_skin(c.hue, c.sat, c.val)
        };
        assert!(class([222, 173, 148])); // light skin
        assert!(class([92, 61, 46])); // dark skin
        assert!(!class([204, 31, 31])); // red marker: too saturated
        assert!(!class([123, 184, 64])); // suit cloth
    }

    #[test]
    fn a_shifted_body_is_moved_back_onto_its_landmarks() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let motion = crate::bvh::Motion::load(&root.join("tests/data/mocap/cmu_09_01_run.bvh"))
            .expect("clip");
        let parts = CorrectionParts::new(&motion.skeleton).expect("parts");
        let camera = Camera::look_at(
            crate::camera::Intrinsics::from_fov(640, 480, 60.0),
            Vec3::new(0.0, 100.0, 450.0),
            Vec3::new(0.0, 90.0, 0.0),
            Vec3::Y,
        );
        let truth = motion.frame(60).to_vec();
        // Landmarks where the true body's parts project.
        let mut world = Vec::new();
        motion.skeleton.forward_kinematics(&truth, &mut world);
        let project = |p: &BodyPart| camera.project(centre(p, &world)).expect("visible").pixel;
        let landmarks = Landmarks {
            head: parts.head.as_ref().map(project),
            hands: parts.hands.iter().map(project).collect(),
            feet: parts.feet.iter().map(project).collect(),
        };
        // The estimate is the truth moved 8 cm sideways, or 60 cm away from the camera; correction
        // brings the root back (to within a few centimetres for depth: the scale is a first-order fix).
        for (axis, amount, tolerance) in [(0usize, 8.0f32, 1.0f32), (2, -60.0, 6.0)] {
            let mut estimate = truth.clone();
            estimate[axis] += amount;
            let shift = correct_root(
                &mut estimate,
                &motion.skeleton,
                [0, 1, 2],
                &parts,
                &camera,
                &landmarks,
                300.0,
                None,
            );
            assert!(shift.is_some());
            let error = Vec3::new(
                estimate[0] - truth[0],
                estimate[1] - truth[1],
                estimate[2] - truth[2],
            )
            .length();
            assert!(
                error < tolerance,
                "axis {axis}: root still {error:.2} cm off"
            );
        }
        // Without landmarks nothing moves.
        let mut untouched = truth.clone();
        untouched[0] += 8.0;
        assert!(correct_root(
            &mut untouched,
            &motion.skeleton,
            [0, 1, 2],
            &parts,
            &camera,
            &Landmarks::default(),
            300.0,
            None
        )
        .is_none());
        assert_eq!(untouched[0], truth[0] + 8.0);
    }

    #[test]
    fn the_marker_depth_moves_the_root_along_its_ray() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let motion = crate::bvh::Motion::load(&root.join("tests/data/mocap/cmu_09_01_run.bvh"))
            .expect("clip");
        // The camera of the test above, 450 cm in front of the runner.
        let camera = Camera::look_at(
            crate::camera::Intrinsics::from_fov(640, 480, 60.0),
            Vec3::new(0.0, 100.0, 450.0),
            Vec3::new(0.0, 90.0, 0.0),
            Vec3::Y,
        );
        let mut frame = motion.frame(60).to_vec();
        let mut world = Vec::new();
        motion.skeleton.forward_kinematics(&frame, &mut world);
        let before = camera
            .project(Vec3::from(world[0].translation))
            .expect("visible");
        root_to_depth(&mut frame, &motion.skeleton, [0, 1, 2], &camera, 250.0);
        motion.skeleton.forward_kinematics(&frame, &mut world);
        let after = camera
            .project(Vec3::from(world[0].translation))
            .expect("visible");
        // Same pixel, the depth the markers say plus the root's distance behind the surface.
        assert!(
            after.pixel.distance(before.pixel) < 1e-3,
            "{after:?} {before:?}"
        );
        assert!(
            (after.depth - (250.0 + ROOT_BEHIND_SURFACE_CM)).abs() < 1e-2,
            "{after:?}"
        );
    }
}
