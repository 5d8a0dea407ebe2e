//! The pose vector the regressor predicts, and its decoding into a BVH frame (source paper sec. 3.2).
//!
//! For the suit's J estimated joints ([`PoseLayout`]) the vector holds, per joint, the sine and cosine of
//! its three BVH rotation angles in the file's own channel order (6 values), then the root's image
//! offset from the silhouette box's centre (2 values, in box heights) and its depth (1 value: camera
//! depth × box height / focal length / [`DEPTH_SCALE`], which is about the person's height in metres
//! and does not change with the distance; the scale keeps it in the range of the other values, which
//! matters because the regressor shares one noise level across all outputs): 6·J + 3 values (105 for the default suit's 17 joints). The root's
//! rotation is expressed relative to the camera, since that is what the image shows; decoding turns
//! it back into the world with the camera's extrinsics and puts the root where the offset and depth
//! say, through the intrinsics. Decoding rescales each (sin, cos) pair to unit length before `atan2`.
//! The joints the suit does not estimate keep the values of a template frame.
//!
//! A regressor may instead be trained on the first two columns of each joint's rotation matrix
//! ([`RotationEncoding::MatrixColumns`], also six values per joint): see there for why.

pub mod chart;
pub mod correction;
pub mod eval;
pub mod exemplars;
pub mod registration;
pub mod regressor;
pub mod rvm;
pub mod smoothing;

use glam::{Mat3, Vec2, Vec3};

use crate::camera::Camera;
use crate::skeleton::{Channel, Skeleton};
use crate::suit::{BindError, SuitSkeleton};

/// Rotation of one channel's axis by `degrees`.
fn axis_rotation(channel: Channel, degrees: f32) -> Mat3 {
    Mat3::from_axis_angle(Vec3::from(channel.axis()), degrees.to_radians())
}

/// The rotation `R_a(α)·R_b(β)·R_c(γ)` of three rotation channels in order.
pub fn compose(channels: [Channel; 3], degrees: [f32; 3]) -> Mat3 {
    axis_rotation(channels[0], degrees[0])
        * axis_rotation(channels[1], degrees[1])
        * axis_rotation(channels[2], degrees[2])
}

fn axis_index(c: Channel) -> usize {
    match c {
        Channel::Xrotation | Channel::Xposition => 0,
        Channel::Yrotation | Channel::Yposition => 1,
        Channel::Zrotation | Channel::Zposition => 2,
    }
}

/// Euler angles (degrees) of `r` for three distinct rotation axes in order, so that
/// `compose(channels, decompose(channels, r)) == r` (the middle angle in [−90°, 90°]).
pub fn decompose(channels: [Channel; 3], r: Mat3) -> [f32; 3] {
    let (i, j, k) = (
        axis_index(channels[0]),
        axis_index(channels[1]),
        axis_index(channels[2]),
    );
    // +1 for an even permutation of (x, y, z), −1 for an odd one.
    let s = if (j + 3 - i) % 3 == 1 { 1.0 } else { -1.0 };
    let m = |row: usize, col: usize| r.col(col)[row];
    let beta = (s * m(i, k)).clamp(-1.0, 1.0).asin();
    let (alpha, gamma) = if beta.cos() > 1e-6 {
        ((-s * m(j, k)).atan2(m(k, k)), (-s * m(i, j)).atan2(m(i, i)))
    } else {
        // Gimbal lock: only α ± γ is defined; put it all in α.
        ((s * m(k, j)).atan2(m(j, j)), 0.0)
    };
    [alpha.to_degrees(), beta.to_degrees(), gamma.to_degrees()]
}

/// How a joint's rotation is written into its six values of the pose vector.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum RotationEncoding {
    /// The paper's: sine and cosine of each of the three BVH angles, in the file's channel order.
    #[default]
    EulerSinCos,
    /// The first two columns of the rotation matrix (Zhou et al. 2019, "On the continuity of
    /// rotation representations in neural networks"), made orthonormal again by Gram–Schmidt when
    /// decoded, then taken apart into the joint's BVH angles. Near gimbal lock (a shoulder whose
    /// arm is raised past the horizontal: the middle angle of Z-X-Y near ±90°), rotations a few
    /// degrees apart have Euler triples tens of degrees apart, and a regressor that averages the
    /// sines and cosines of its training poses averages unrelated angles there; the matrix
    /// entries change as little as the rotation does.
    MatrixColumns,
}

impl RotationEncoding {
    pub const ALL: [RotationEncoding; 2] = [
        RotationEncoding::EulerSinCos,
        RotationEncoding::MatrixColumns,
    ];

    /// The name on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            RotationEncoding::EulerSinCos => "euler",
            RotationEncoding::MatrixColumns => "matrix",
        }
    }

    /// The code stored in the regressor's model file.
    pub fn code(self) -> f32 {
        match self {
            RotationEncoding::EulerSinCos => 0.0,
            RotationEncoding::MatrixColumns => 1.0,
        }
    }

    pub fn from_code(code: f32) -> Option<RotationEncoding> {
        Self::ALL.into_iter().find(|e| e.code() == code)
    }

    /// The six values of the rotation whose BVH angles are `degrees` (channel order `order`).
    fn encode(self, order: [Channel; 3], degrees: [f32; 3], out: &mut Vec<f32>) {
        match self {
            RotationEncoding::EulerSinCos => {
                for a in degrees {
                    let (s, c) = a.to_radians().sin_cos();
                    out.push(s);
                    out.push(c);
                }
            }
            RotationEncoding::MatrixColumns => {
                let r = compose(order, degrees);
                out.extend_from_slice(&r.x_axis.to_array());
                out.extend_from_slice(&r.y_axis.to_array());
            }
        }
    }

    /// The BVH angles (channel order `order`) of six values; any six finite values give finite
    /// angles (a zero pair or column decodes as no rotation). Of a rotation matrix's two Euler
    /// triples, the one with the middle angle in [−90°, 90°] ([`decompose`]): the convention the
    /// shipped CMU clips are written in (a knee bent past a right angle is about (−175°, 80°,
    /// 175°) there, the same rotation as (0°, 100°, 0°)). Choosing the triple nearer a template
    /// frame's or the smaller one instead put the thighs and shins 2.5–6.5° further from the truth
    /// (docs/measurements.md, sixth session of 2026-12-05).
    fn decode(self, order: [Channel; 3], values: &[f32]) -> [f32; 3] {
        match self {
            RotationEncoding::EulerSinCos => {
                let mut angles = [0.0f32; 3];
                for (k, a) in angles.iter_mut().enumerate() {
                    let (s, c) = (values[2 * k], values[2 * k + 1]);
                    let norm = (s * s + c * c).sqrt();
                    *a = if norm > 1e-9 {
                        (s / norm).atan2(c / norm).to_degrees()
                    } else {
                        0.0
                    };
                }
                angles
            }
            RotationEncoding::MatrixColumns => {
                let r = orthonormal(
                    Vec3::from_slice(&values[..3]),
                    Vec3::from_slice(&values[3..6]),
                );
                decompose(order, r)
            }
        }
    }
}

/// The rotation whose first column points along `a` and whose second lies in the plane of `a`
/// and `b` (Gram–Schmidt); the identity's columns stand in for a zero or parallel input.
fn orthonormal(a: Vec3, b: Vec3) -> Mat3 {
    let x = a.try_normalize().unwrap_or(Vec3::X);
    let y = (b - x * x.dot(b))
        .try_normalize()
        .unwrap_or_else(|| x.any_orthonormal_vector());
    Mat3::from_cols(x, y, x.cross(y))
}

/// Where each estimated joint's values live in a BVH frame.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseLayout {
    /// Per suit joint: its BVH joint index and the frame indices of its three rotation channels.
    pub joints: Vec<(usize, [usize; 3])>,
    /// Channel types of each joint's rotations, in file order.
    pub orders: Vec<[Channel; 3]>,
    /// Frame indices of the root's X, Y, Z position channels.
    pub root_position: [usize; 3],
    /// How each joint's rotation is written.
    pub rotations: RotationEncoding,
}

/// A skeleton the pose vector cannot describe.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum LayoutError {
    #[error(transparent)]
    Bind(#[from] BindError),
    #[error("BVH joint '{0}' does not have exactly three rotation channels")]
    Rotations(String),
    #[error("the root joint '{0}' has no X, Y and Z position channels")]
    RootPosition(String),
    #[error("the suit's first joint '{0}' is not the BVH root")]
    Root(String),
}

/// World units (cm) per unit of the pose vector's depth value.
pub const DEPTH_SCALE: f32 = 100.0;

/// Length of a pose vector for `joints` joints.
pub fn pose_len(joints: usize) -> usize {
    6 * joints + 3
}

impl PoseLayout {
    pub fn new(suit: &SuitSkeleton, skeleton: &Skeleton) -> Result<PoseLayout, LayoutError> {
        let indices = suit.bind(skeleton)?;
        let mut joints = Vec::new();
        let mut orders = Vec::new();
        for &j in &indices {
            let joint = skeleton.joint(j);
            let rotations: Vec<(usize, Channel)> = joint
                .channels
                .iter()
                .enumerate()
                .filter(|(_, c)| c.is_rotation())
                .map(|(k, &c)| (joint.first_channel + k, c))
                .collect();
            let [a, b, c] = rotations[..] else {
                return Err(LayoutError::Rotations(joint.name.clone()));
            };
            joints.push((j, [a.0, b.0, c.0]));
            orders.push([a.1, b.1, c.1]);
        }
        let root = skeleton.joint(0);
        if indices.first() != Some(&0) {
            return Err(LayoutError::Root(
                suit.joints
                    .first()
                    .map(|j| j.bvh.clone())
                    .unwrap_or_default(),
            ));
        }
        let position = |axis: Channel| {
            root.channels
                .iter()
                .position(|&c| c == axis)
                .map(|k| root.first_channel + k)
        };
        let root_position = match (
            position(Channel::Xposition),
            position(Channel::Yposition),
            position(Channel::Zposition),
        ) {
            (Some(x), Some(y), Some(z)) => [x, y, z],
            _ => return Err(LayoutError::RootPosition(root.name.clone())),
        };
        Ok(PoseLayout {
            joints,
            orders,
            root_position,
            rotations: RotationEncoding::default(),
        })
    }

    /// The same layout with another rotation encoding.
    pub fn with_rotations(self, rotations: RotationEncoding) -> PoseLayout {
        PoseLayout { rotations, ..self }
    }

    pub fn len(&self) -> usize {
        pose_len(self.joints.len())
    }

    pub fn is_empty(&self) -> bool {
        self.joints.is_empty()
    }

    /// The pose vector of a BVH frame seen by `camera`, with the person's silhouette box
    /// (x0, y0, x1, y1) in that camera's image.
    pub fn encode(
        &self,
        skeleton: &Skeleton,
        frame: &[f32],
        camera: &Camera,
        bbox: (f32, f32, f32, f32),
    ) -> Vec<f32> {
        let mut out = Vec::with_capacity(self.len());
        for (n, ((_, channels), order)) in self.joints.iter().zip(&self.orders).enumerate() {
            let mut angles = channels.map(|c| frame[c]);
            if n == 0 {
                let world = compose(*order, angles);
                angles = decompose(*order, camera.rotation * world);
            }
            self.rotations.encode(*order, angles, &mut out);
        }
        let root = root_world(skeleton, frame, self.root_position);
        let (centre, height) = box_centre_height(bbox);
        match camera.project(root) {
            Some(p) => {
                let offset = (p.pixel - centre) / height;
                out.extend_from_slice(&[
                    offset.x,
                    offset.y,
                    p.depth * height / camera.intrinsics.fy / DEPTH_SCALE,
                ]);
            }
            None => out.extend_from_slice(&[0.0, 0.0, 0.0]),
        }
        out
    }

    /// Each estimated joint's three BVH angles (degrees, channel order) as the pose vector holds
    /// them, the root's relative to the camera: what the held-back error of training compares.
    pub fn joint_angles(&self, pose: &[f32]) -> Vec<[f32; 3]> {
        self.orders
            .iter()
            .enumerate()
            .map(|(n, order)| self.rotations.decode(*order, &pose[6 * n..6 * n + 6]))
            .collect()
    }

    /// A BVH frame from a pose vector: the estimated joints from the vector, everything else from
    /// `template` (same layout), the root rotation and position through `camera` and the box.
    pub fn decode(
        &self,
        skeleton: &Skeleton,
        pose: &[f32],
        template: &[f32],
        camera: &Camera,
        bbox: (f32, f32, f32, f32),
    ) -> Vec<f32> {
        let mut frame = template.to_vec();
        for (n, ((_, channels), order)) in self.joints.iter().zip(&self.orders).enumerate() {
            let mut angles = self.rotations.decode(*order, &pose[6 * n..6 * n + 6]);
            if n == 0 {
                let in_camera = compose(*order, angles);
                angles = decompose(*order, camera.rotation.transpose() * in_camera);
            }
            for (c, a) in channels.iter().zip(angles) {
                frame[*c] = a;
            }
        }
        let j = 6 * self.joints.len();
        let (centre, height) = box_centre_height(bbox);
        let pixel = centre + Vec2::new(pose[j], pose[j + 1]) * height;
        let depth = pose[j + 2] * DEPTH_SCALE * camera.intrinsics.fy / height.max(1e-3);
        let world = camera.unproject(pixel, depth.max(1.0));
        let offset = skeleton.joint(0).offset;
        for (axis, &c) in self.root_position.iter().enumerate() {
            frame[c] = world[axis] - offset[axis];
        }
        frame
    }
}

fn box_centre_height((x0, y0, x1, y1): (f32, f32, f32, f32)) -> (Vec2, f32) {
    (
        Vec2::new(0.5 * (x0 + x1), 0.5 * (y0 + y1)),
        (y1 - y0).max(1.0),
    )
}

/// World position of the root joint for one frame.
fn root_world(skeleton: &Skeleton, frame: &[f32], position: [usize; 3]) -> Vec3 {
    skeleton.joint(0).offset + Vec3::new(frame[position[0]], frame[position[1]], frame[position[2]])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Intrinsics;
    use proptest::prelude::*;
    use std::path::Path;

    const ORDERS: [[Channel; 3]; 2] = [
        [Channel::Zrotation, Channel::Xrotation, Channel::Yrotation],
        [Channel::Zrotation, Channel::Yrotation, Channel::Xrotation],
    ];

    fn close(a: Mat3, b: Mat3) -> bool {
        (a - b).to_cols_array().iter().all(|v| v.abs() < 1e-4)
    }

    proptest! {
        #[test]
        fn decompose_inverts_compose(a in -179.0f32..179.0, b in -89.0f32..89.0, c in -179.0f32..179.0, order in 0usize..2) {
            let r = compose(ORDERS[order], [a, b, c]);
            let back = decompose(ORDERS[order], r);
            prop_assert!(close(compose(ORDERS[order], back), r));
            prop_assert!((back[1] - b).abs() < 0.05);
        }
    }

    fn fixture() -> (crate::bvh::Motion, PoseLayout, Camera) {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let suit =
            crate::suit::SuitDefinition::load_dir(&root.join("suits/default")).expect("suit");
        let motion = crate::bvh::Motion::load(&root.join("tests/data/mocap/cmu_09_01_run.bvh"))
            .expect("clip");
        let layout = PoseLayout::new(&suit.skeleton, &motion.skeleton).expect("layout");
        let camera = Camera::look_at(
            Intrinsics::from_fov(640, 480, 60.0),
            Vec3::new(150.0, 140.0, 400.0),
            Vec3::new(0.0, 90.0, 0.0),
            Vec3::Y,
        );
        (motion, layout, camera)
    }

    #[test]
    fn default_suit_has_105_values() {
        let (_, layout, _) = fixture();
        assert_eq!(layout.len(), 105);
    }

    #[test]
    fn encode_then_decode_gives_back_the_frame() {
        let (motion, layout, camera) = fixture();
        for rotations in RotationEncoding::ALL {
            round_trip(&motion, &layout.clone().with_rotations(rotations), &camera);
        }
    }

    fn round_trip(motion: &crate::bvh::Motion, layout: &PoseLayout, camera: &Camera) {
        let bbox = (250.0, 100.0, 390.0, 420.0);
        let template = motion.frame(0).to_vec();
        for f in [20, 60, 120] {
            let frame = motion.frame(f);
            let pose = layout.encode(&motion.skeleton, frame, camera, bbox);
            assert_eq!(pose.len(), 105);
            let back = layout.decode(&motion.skeleton, &pose, &template, camera, bbox);
            for ((_, channels), order) in layout.joints.iter().zip(&layout.orders) {
                let a = compose(*order, channels.map(|c| frame[c]));
                let b = compose(*order, channels.map(|c| back[c]));
                assert!(
                    close(a, b),
                    "{:?}, frame {f}: rotations differ",
                    layout.rotations
                );
            }
            for &c in &layout.root_position {
                assert!(
                    (frame[c] - back[c]).abs() < 0.05,
                    "frame {f}: root {} vs {}",
                    frame[c],
                    back[c]
                );
            }
        }
    }

    #[test]
    fn a_knee_bent_past_a_right_angle_decodes_as_the_clips_write_it() {
        // Z-X-Y (0°, 100°, 0°) is written (180°, 80°, 180°) by the CMU conversion, with the middle
        // angle within ±90°; decoded from its matrix columns it comes back so.
        let order = ORDERS[0];
        let mut values = Vec::new();
        RotationEncoding::MatrixColumns.encode(order, [0.0, 100.0, 0.0], &mut values);
        let back = RotationEncoding::MatrixColumns.decode(order, &values);
        assert!((back[1] - 80.0).abs() < 0.01, "{back:?}");
        assert!((back[0].abs() - 180.0).abs() < 0.01 && (back[2].abs() - 180.0).abs() < 0.01);
    }

    #[test]
    fn matrix_columns_of_a_quarter_turn_about_z() {
        // R_z(90°) takes x to y and y to −x: its first two columns are (0, 1, 0) and (−1, 0, 0).
        let order = ORDERS[0];
        let mut out = Vec::new();
        RotationEncoding::MatrixColumns.encode(order, [90.0, 0.0, 0.0], &mut out);
        let expected = [0.0, 1.0, 0.0, -1.0, 0.0, 0.0];
        assert!(
            out.iter().zip(expected).all(|(a, b)| (a - b).abs() < 1e-6),
            "{out:?}"
        );
        // Scaled and skewed columns decode to the same rotation.
        let skewed = [0.0, 3.0, 0.0, -2.0, 0.5, 0.0];
        let angles = RotationEncoding::MatrixColumns.decode(order, &skewed);
        assert!(
            close(compose(order, angles), compose(order, [90.0, 0.0, 0.0])),
            "{angles:?}"
        );
    }

    #[test]
    fn near_gimbal_lock_close_rotations_have_close_matrix_columns() {
        // Z-X-Y: (10°, 89°, 20°) and, just past the pole, (12°, 92°, 17°), whose angles in the
        // middle angle's range are (−168°, 88°, −163°): rotations about 3° apart whose first and
        // last angles differ by about 180°.
        let order = ORDERS[0];
        let a = [10.0, 89.0, 20.0];
        let b = decompose(order, compose(order, [12.0, 92.0, 17.0]));
        assert!(
            (b[0] + 168.0).abs() < 0.01 && (b[1] - 88.0).abs() < 0.01,
            "{b:?}"
        );
        let relative = compose(order, a).transpose() * compose(order, b);
        let trace = relative.x_axis.x + relative.y_axis.y + relative.z_axis.z;
        let degrees = ((trace - 1.0) / 2.0).clamp(-1.0, 1.0).acos().to_degrees();
        assert!(degrees < 5.0, "{degrees}");
        let gap = |encoding: RotationEncoding| {
            let (mut ea, mut eb) = (Vec::new(), Vec::new());
            encoding.encode(order, a, &mut ea);
            encoding.encode(order, b, &mut eb);
            ea.iter()
                .zip(&eb)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0f32, f32::max)
        };
        assert!(gap(RotationEncoding::MatrixColumns) < 0.1);
        assert!(gap(RotationEncoding::EulerSinCos) > 1.5);
    }

    proptest! {
        #[test]
        fn any_six_values_decode_to_a_rotation(values in proptest::collection::vec(-2.0f32..2.0, 105)) {
            let (motion, layout, camera) = fixture();
            let layout = layout.with_rotations(RotationEncoding::MatrixColumns);
            let bbox = (250.0, 100.0, 390.0, 420.0);
            let back = layout.decode(&motion.skeleton, &values, motion.frame(0), &camera, bbox);
            prop_assert!(back.iter().all(|v| v.is_finite()));
            let again = layout.encode(&motion.skeleton, &back, &camera, bbox);
            for columns in again[..102].chunks(6) {
                let (x, y) = (Vec3::from_slice(&columns[..3]), Vec3::from_slice(&columns[3..]));
                prop_assert!((x.length() - 1.0).abs() < 1e-4 && (y.length() - 1.0).abs() < 1e-4);
                prop_assert!(x.dot(y).abs() < 1e-4);
            }
        }

        #[test]
        fn decoded_angles_come_from_unit_sin_cos_pairs(values in proptest::collection::vec(-2.0f32..2.0, 105)) {
            let (motion, layout, camera) = fixture();
            let bbox = (250.0, 100.0, 390.0, 420.0);
            let back = layout.decode(&motion.skeleton, &values, motion.frame(0), &camera, bbox);
            let again = layout.encode(&motion.skeleton, &back, &camera, bbox);
            for pair in again[..102].chunks(2) {
                prop_assert!((pair[0] * pair[0] + pair[1] * pair[1] - 1.0).abs() < 1e-4);
            }
            prop_assert!(back.iter().all(|v| v.is_finite()));
        }
    }
}
