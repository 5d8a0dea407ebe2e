//! Pose error measures: per joint, the mean absolute difference of its three Euler angles wrapped to
//! ±180° (the source paper's measure) and the geodesic angle between the two rotations (which does not
//! depend on how a rotation is split into Euler angles); where the joints are, in centimetres, with
//! the root aligned ([`PositionErrors`], the MPJPE of the pose-estimation literature); and how well
//! training motions cover a test motion ([`nearest_pose_errors`]): the error that picking the
//! closest training pose every time, knowing the truth, would still make.

use glam::{Affine3A, Vec3};

use super::{compose, PoseLayout};
pub use crate::skeleton::wrap_degrees;
use crate::skeleton::Skeleton;

/// Accumulated errors per estimated joint.
#[derive(Clone, Debug, PartialEq)]
pub struct JointErrors {
    pub names: Vec<String>,
    euler: Vec<f64>,
    geodesic: Vec<f64>,
    pub frames: usize,
}

impl JointErrors {
    pub fn new(names: Vec<String>) -> JointErrors {
        let n = names.len();
        JointErrors {
            names,
            euler: vec![0.0; n],
            geodesic: vec![0.0; n],
            frames: 0,
        }
    }

    /// Adds one frame: the ground truth and the estimate, both full BVH frames of `layout`'s skeleton.
    pub fn add(&mut self, layout: &PoseLayout, truth: &[f32], estimate: &[f32]) {
        for (j, ((_, channels), order)) in layout.joints.iter().zip(&layout.orders).enumerate() {
            let (a, b) = (channels.map(|c| truth[c]), channels.map(|c| estimate[c]));
            self.euler[j] += a
                .iter()
                .zip(&b)
                .map(|(x, y)| wrap_degrees(x - y).abs() as f64)
                .sum::<f64>()
                / 3.0;
            let r = compose(*order, a).transpose() * compose(*order, b);
            let cos = ((r.x_axis.x + r.y_axis.y + r.z_axis.z - 1.0) * 0.5).clamp(-1.0, 1.0);
            self.geodesic[j] += (cos.acos().to_degrees()) as f64;
        }
        self.frames += 1;
    }

    pub fn merge(&mut self, other: &JointErrors) {
        for j in 0..self.euler.len() {
            self.euler[j] += other.euler[j];
            self.geodesic[j] += other.geodesic[j];
        }
        self.frames += other.frames;
    }

    /// Mean Euler error of joint `j`, degrees.
    pub fn euler(&self, j: usize) -> f64 {
        self.euler[j] / self.frames.max(1) as f64
    }

    /// Mean geodesic error of joint `j`, degrees.
    pub fn geodesic(&self, j: usize) -> f64 {
        self.geodesic[j] / self.frames.max(1) as f64
    }

    /// Mean over joints of the Euler error.
    pub fn mean_euler(&self) -> f64 {
        (0..self.names.len()).map(|j| self.euler(j)).sum::<f64>() / self.names.len().max(1) as f64
    }

    pub fn mean_geodesic(&self) -> f64 {
        (0..self.names.len()).map(|j| self.geodesic(j)).sum::<f64>()
            / self.names.len().max(1) as f64
    }

    /// `joint,euler_deg,geodesic_deg,position_cm` rows, then `mean`; the position column (from
    /// `positions`, over the same frames) is empty for the root and without positions.
    pub fn to_csv(&self, positions: Option<&PositionErrors>) -> String {
        let cm = |value: Option<f64>| value.map_or(String::new(), |v| format!("{v:.3}"));
        let mut out = String::from("joint,euler_deg,geodesic_deg,position_cm\n");
        for (j, name) in self.names.iter().enumerate() {
            let position = cm(positions.and_then(|p| p.of_suit_joint(j)));
            out.push_str(&format!(
                "{name},{:.3},{:.3},{position}\n",
                self.euler(j),
                self.geodesic(j)
            ));
        }
        out.push_str(&format!(
            "mean,{:.3},{:.3},{}\n",
            self.mean_euler(),
            self.mean_geodesic(),
            cm(positions.map(PositionErrors::mean_cm))
        ));
        out
    }
}

/// Accumulated position errors per estimated joint after the root: the distance (cm) between
/// where forward kinematics puts the joint (its BVH joint's origin: the elbow for a forearm, the
/// knee for a shin) from the true frame and from the estimated one, both on the truth's skeleton
/// and with the root's position channels zeroed. Bone lengths and the root's place are thus the
/// same for both, so this is the joint angles' error in centimetres (the root-aligned mean per
/// joint position error, MPJPE). A bone's twist about its own axis moves none of its joints:
/// it counts in the angle measures and not here, until a bent child shows it.
#[derive(Clone, Debug, PartialEq)]
pub struct PositionErrors {
    /// The suit's joints after the root.
    pub names: Vec<String>,
    cm: Vec<f64>,
    pub frames: usize,
    /// Scratch: the two frames with the root at the origin, and their world transforms.
    frames_scratch: [Vec<f32>; 2],
    world: [Vec<Affine3A>; 2],
}

impl PositionErrors {
    /// For the suit's joints `names` (the root first, which is left out).
    pub fn new(names: &[String]) -> PositionErrors {
        let names = names.get(1..).unwrap_or_default().to_vec();
        PositionErrors {
            cm: vec![0.0; names.len()],
            names,
            frames: 0,
            frames_scratch: Default::default(),
            world: Default::default(),
        }
    }

    /// Adds one frame: the ground truth and the estimate, both full BVH frames of `skeleton`, whose
    /// joints `layout` names.
    pub fn add(
        &mut self,
        skeleton: &Skeleton,
        layout: &PoseLayout,
        truth: &[f32],
        estimate: &[f32],
    ) {
        for ((scratch, world), frame) in self
            .frames_scratch
            .iter_mut()
            .zip(&mut self.world)
            .zip([truth, estimate])
        {
            scratch.clear();
            scratch.extend_from_slice(frame);
            for &c in &layout.root_position {
                if let Some(v) = scratch.get_mut(c) {
                    *v = 0.0;
                }
            }
            skeleton.forward_kinematics(scratch, world);
        }
        let at = |world: &[Affine3A], joint: usize| {
            world
                .get(joint)
                .map_or(Vec3::ZERO, |t| Vec3::from(t.translation))
        };
        for (sum, &(joint, _)) in self.cm.iter_mut().zip(layout.joints.iter().skip(1)) {
            *sum += at(&self.world[0], joint).distance(at(&self.world[1], joint)) as f64;
        }
        self.frames += 1;
    }

    pub fn merge(&mut self, other: &PositionErrors) {
        for (a, b) in self.cm.iter_mut().zip(&other.cm) {
            *a += b;
        }
        self.frames += other.frames;
    }

    /// Mean position error of the `j`-th joint after the root, cm.
    pub fn cm(&self, j: usize) -> f64 {
        self.cm
            .get(j)
            .map_or(0.0, |s| s / self.frames.max(1) as f64)
    }

    /// Mean position error of the suit's joint `j` (as [`JointErrors`] counts them), cm; `None`
    /// for the root, which is aligned.
    pub fn of_suit_joint(&self, j: usize) -> Option<f64> {
        j.checked_sub(1).map(|k| self.cm(k))
    }

    /// Mean over the joints after the root, cm.
    pub fn mean_cm(&self) -> f64 {
        (0..self.names.len()).map(|j| self.cm(j)).sum::<f64>() / self.names.len().max(1) as f64
    }
}

/// The Euler angles (degrees, each joint's channel order, wrapped to ±180°) of the suit's joints
/// after the root in each of `frames`, `frames × (J − 1)` triples. The root is left out: its
/// rotation relative to the camera depends on where the camera stands, not on the motion.
pub fn body_angles<'a>(
    layout: &PoseLayout,
    frames: impl Iterator<Item = &'a [f32]>,
) -> Vec<[f32; 3]> {
    frames
        .flat_map(|frame| {
            layout.joints[1..]
                .iter()
                .map(move |(_, channels)| channels.map(|c| wrap_degrees(frame[c])))
        })
        .collect()
}

/// For each pose of `query` (`joints` triples from [`body_angles`]), the paper's error measure
/// (mean over joints and angles of the wrapped absolute difference) to the closest pose of
/// `reference`: how far the nearest training pose is. A regressor can blend training poses, so
/// this is no bound, but a test motion whose poses are far from every training pose asks it to
/// extrapolate. `None` when `reference` is empty.
pub fn nearest_pose_errors(
    reference: &[[f32; 3]],
    query: &[[f32; 3]],
    joints: usize,
) -> Option<Vec<f32>> {
    use rayon::prelude::*;
    if reference.is_empty() || joints == 0 {
        return None;
    }
    // `wrap_degrees(a - b).abs()` for angles already wrapped by `body_angles`, without the float
    // remainder in the innermost loop.
    let angle = |a: f32, b: f32| {
        let d = (a - b).abs();
        d.min(360.0 - d)
    };
    Some(
        query
            .par_chunks_exact(joints)
            .map(|q| {
                let mut best = f32::INFINITY;
                for r in reference.chunks_exact(joints) {
                    let mut sum = 0.0;
                    for (a, b) in q.iter().zip(r) {
                        sum += angle(a[0], b[0]) + angle(a[1], b[1]) + angle(a[2], b[2]);
                        if sum >= best {
                            break;
                        }
                    }
                    best = best.min(sum);
                }
                best / (3 * joints) as f32
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pose layout of a shoulder and an elbow (the two-joint arm's BVH), three channels each.
    fn two_joint_layout() -> PoseLayout {
        let skeleton = crate::skeleton::tests::two_joint_arm();
        let joint = |name: &str, parent| crate::suit::SuitJoint {
            name: name.into(),
            parent,
            bvh: name.into(),
        };
        let suit = crate::suit::SuitSkeleton {
            joints: vec![joint("shoulder", None), joint("elbow", Some(0))],
        };
        PoseLayout::new(&suit, &skeleton).expect("layout")
    }

    #[test]
    fn wrapping() {
        assert_eq!(wrap_degrees(350.0), -10.0);
        assert_eq!(wrap_degrees(-190.0), 170.0);
        assert_eq!(wrap_degrees(10.0), 10.0);
    }

    #[test]
    fn a_known_error_on_a_two_joint_skeleton() {
        let layout = two_joint_layout();
        let truth = [0.0, 0.0, 0.0, 10.0, 0.0, 0.0, 350.0, 0.0, 0.0];
        // The elbow's Z angle is off by 20° across the wrap (350° vs 10°); the shoulder is exact.
        let estimate = [5.0, 0.0, 0.0, 10.0, 0.0, 0.0, 10.0, 0.0, 0.0];
        let mut e = JointErrors::new(vec!["shoulder".into(), "elbow".into()]);
        e.add(&layout, &truth, &estimate);
        assert!(e.euler(0).abs() < 1e-9);
        assert!((e.euler(1) - 20.0 / 3.0).abs() < 1e-4);
        assert!((e.geodesic(1) - 20.0).abs() < 1e-2);
        assert!((e.mean_euler() - 10.0 / 3.0).abs() < 1e-4);
    }

    #[test]
    fn a_known_position_error_on_a_two_joint_skeleton() {
        let skeleton = crate::skeleton::tests::two_joint_arm();
        let layout = two_joint_layout();
        let names = ["shoulder".to_string(), "elbow".to_string()];
        let mut e = PositionErrors::new(&names);
        assert_eq!(e.names, ["elbow"]);
        // The root 7 cm off and the elbow's own angle 90° off move nothing the measure sees: the
        // root is aligned and the elbow joint stays where the shoulder puts it.
        let truth = [0.0; 9];
        let mut estimate = [0.0; 9];
        estimate[0] = 7.0;
        estimate[6] = 90.0;
        e.add(&skeleton, &layout, &truth, &estimate);
        assert_eq!(e.cm(0), 0.0);
        // The shoulder turned 90° about Z swings the elbow, 10 cm out along X, onto +Y: √2 · 10 cm.
        let mut turned = [0.0; 9];
        turned[3] = 90.0;
        e.add(&skeleton, &layout, &truth, &turned);
        assert!(
            (e.cm(0) - 10.0 * 2f64.sqrt() / 2.0).abs() < 1e-4,
            "{}",
            e.cm(0)
        );
        assert!((e.mean_cm() - e.cm(0)).abs() < 1e-12);
        let mut both = PositionErrors::new(&names);
        both.merge(&e);
        assert_eq!((both.frames, both.cm(0)), (2, e.cm(0)));
        let mut angles = JointErrors::new(names.to_vec());
        angles.add(&layout, &truth, &estimate);
        angles.add(&layout, &truth, &turned);
        assert_eq!(
            angles.to_csv(Some(&e)),
            "joint,euler_deg,geodesic_deg,position_cm\n\
             shoulder,15.000,45.000,\n\
             elbow,15.000,45.000,7.071\n\
             mean,15.000,45.000,7.071\n"
        );
    }

    #[test]
    fn nearest_pose_across_the_wrap() {
        // Two reference poses of two joints: A = (0, 0, 0), (10, 0, 0); B = (90, 0, 0), (90, 0, 0).
        let reference = [
            [0.0, 0.0, 0.0],
            [10.0, 0.0, 0.0],
            [90.0, 0.0, 0.0],
            [90.0, 0.0, 0.0],
        ];
        let query = [
            [0.0, 0.0, 0.0],
            [10.0, 0.0, 0.0], // A itself: 0
            [179.0, 0.0, 0.0],
            [90.0, 0.0, 0.0], // B: 89 / 6; A: (179 + 80) / 6
            [-179.0, 0.0, 0.0],
            [-170.0, 0.0, 0.0], // A: (179 + 180) / 6; B across the wrap: (91 + 100) / 6
        ];
        let errors = nearest_pose_errors(&reference, &query, 2).expect("reference");
        assert_eq!(errors.len(), 3);
        assert_eq!(errors[0], 0.0);
        assert!((errors[1] - 89.0 / 6.0).abs() < 1e-4);
        assert!((errors[2] - 191.0 / 6.0).abs() < 1e-4);
        assert_eq!(nearest_pose_errors(&[], &query, 2), None);
    }

    #[test]
    fn body_angles_leave_out_the_root_and_wrap() {
        let layout = two_joint_layout();
        let frames = [
            [0.0, 0.0, 0.0, 10.0, 20.0, 30.0, 350.0, 5.0, -5.0],
            [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0],
        ];
        let angles = body_angles(&layout, frames.iter().map(|f| &f[..]));
        assert_eq!(angles, vec![[-10.0, 5.0, -5.0], [7.0, 8.0, 9.0]]);
    }

    proptest::proptest! {
        #[test]
        fn every_reference_pose_is_its_own_nearest(values in proptest::collection::vec(-180.0f32..180.0, 3 * 4 * 5), pick in 0usize..5) {
            let poses: Vec<[f32; 3]> = values.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
            let query = &poses[4 * pick..4 * pick + 4];
            let errors = nearest_pose_errors(&poses, query, 4).expect("reference");
            proptest::prop_assert_eq!(errors, vec![0.0]);
        }
    }
}
