//! Collision proxies: the body's elliptic parts as round tapered capsules, posed every substep.
//!
//! [`body_proxies`] turns each [`BodyPart`] (a capsule with an elliptic, tapering cross-section in
//! its joint's frame) into round [`Capsule`]s the solver can test exactly: where the two semi-axes
//! differ by more than [`STADIUM_RATIO`] at either end, capsules of the minor radius offset by
//! ±(major − minor) along the major axis (a stadium cross-section that contains the ellipse);
//! otherwise one capsule of the mean radius. Two capsules alone are not a stadium but the union of
//! two discs, which dips by `r − √(r² − o²)` midway (1.3 cm on the pelvis: the cloth would sink into
//! the belly), so a third capsule on the axis fills the middle, leaving a dip of
//! `r − √(r² − o²/4)` (about 0.3 cm, inside the margin). Every radius is inflated by a margin (0.5 cm by
//! default). A round capsule's end is a hemisphere of its radius, while a part's cap reaches
//! `cap · minor semi-axis` beyond its end point, so each end is moved inward by the difference (never
//! past the other end): the proxy reaches exactly as far along the bone as the part does. Each
//! [`ProxyCapsule`] remembers the part and joint it came from.
//!
//! [`BodyRig`] holds the (subject-scaled) skeleton, the body and its proxies. Given two skeleton
//! frames (BVH channel vectors, angles in degrees, root translation already scaled to the subject)
//! and `t ∈ [0, 1]` it interpolates the channels — rotation channels by the shortest angular
//! difference, position channels linearly — runs forward kinematics and fills a reusable
//! [`BodyPose`]: the bone transforms (for kinematic anchors) and the posed capsules (for collisions).
//! The solver asks for one pose per substep, so a fast limb moves smoothly between video frames.
//! Where a pose presses an arm into the trunk deeper than it lies there in the rest pose (mocap
//! skeletons know nothing of flesh), the rig moves the arm's capsules out until they only touch
//! (`BodyRig::yield_arms`): the flesh gives way, and the cloth between arm and chest keeps a
//! place outside both.

use std::ops::Range;

use glam::{Affine3A, Vec3, Vec3A};

use crate::body::{Body, BodyPart, MissingJoint, Subject};
use crate::bvh::Motion;
use crate::skeleton::{interpolate_frames, Skeleton};

use super::capsule::{Capsule, PreparedCapsule};

/// Semi-axis ratio above which a part becomes two capsules (a stadium) instead of one.
pub const STADIUM_RATIO: f32 = 1.2;

/// Default inflation of every proxy radius, centimetres.
pub const DEFAULT_MARGIN_CM: f32 = 0.5;

/// Collision group of the trunk, head and legs.
pub const GROUP_TRUNK: u8 = 0;
/// Collision group of the arms and hands.
pub const GROUP_ARMS: u8 = 1;

/// `capsule` (an upper arm, `a` at the shoulder) starting one radius further along its axis, at
/// most halfway, its radius there as the taper gives it.
fn without_shoulder_ball(capsule: Capsule) -> Capsule {
    let length = capsule.a.distance(capsule.b);
    if length <= 0.0 {
        return capsule;
    }
    let (a, radius_a) = capsule.sphere_at((capsule.radius_a / length).min(0.5));
    Capsule::new(a, capsule.b, radius_a, capsule.radius_b)
}

/// The collision group of a body part by name: arms (upper arm, forearm, hand) or trunk (the rest).
///
/// The arms rise out of the torso at the shoulders, and a pose may still press an arm against the
/// chest (the rig moves it out only until it touches), so the side of a loose shirt may meet a
/// hanging arm. The solver lets cloth that rests on the trunk ignore the arms, and resolves cloth
/// that rests on an arm against the arms first and the trunk last (the trunk wins where they
/// overlap). Until the second session of 2026-12-07 the body's hanging upper arms lay inside its
/// chest, which this split was first made for.
/// What the cloth leaves inside an arm there is hidden by the renderer's depth test, as the real arm
/// hides the shirt it presses against the torso.
pub fn collision_group(part_name: &str) -> u8 {
    if part_name.contains("upper_arm")
        || part_name.contains("forearm")
        || part_name.contains("hand")
    {
        GROUP_ARMS
    } else {
        GROUP_TRUNK
    }
}

/// One round tapered capsule in its joint's local frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProxyCapsule {
    /// Index of the body part it approximates.
    pub part: usize,
    /// Joint whose world transform moves it.
    pub joint: usize,
    /// [`collision_group`] of the part.
    pub group: u8,
    /// Local capsule (endpoints in the joint's frame, inflated radii).
    pub local: Capsule,
}

impl ProxyCapsule {
    /// The capsule in world space for the given bone transforms (as `forward_kinematics` fills them).
    pub fn posed(&self, bones: &[Affine3A]) -> Capsule {
        let bone = bones.get(self.joint).copied().unwrap_or(Affine3A::IDENTITY);
        Capsule {
            a: bone.transform_point3(self.local.a),
            b: bone.transform_point3(self.local.b),
            radius_a: self.local.radius_a,
            radius_b: self.local.radius_b,
        }
    }
}

/// Round capsules approximating every part of `body`, radii inflated by `margin_cm`.
pub fn body_proxies(body: &Body, margin_cm: f32) -> Vec<ProxyCapsule> {
    let mut out = Vec::with_capacity(body.parts.len() * 2);
    for (index, part) in body.parts.iter().enumerate() {
        part_proxies(index, part, margin_cm, &mut out);
    }
    out
}

fn part_proxies(index: usize, part: &BodyPart, margin: f32, out: &mut Vec<ProxyCapsule>) {
    let along = part.end - part.start;
    let length = along.length();
    let d = if length > 1e-6 {
        along / length
    } else {
        Vec3::Y
    };
    let mut e1 = part.width_axis - d * part.width_axis.dot(d);
    if e1.length_squared() < 1e-6 {
        e1 = d.any_orthonormal_vector();
    }
    let e1 = e1.normalize();
    let e2 = d.cross(e1);
    let (rs, re) = (part.radii_start, part.radii_end);
    let ratio = |r: glam::Vec2| r.max_element() / r.min_element().max(1e-6);
    let stadium = ratio(rs) > STADIUM_RATIO || ratio(re) > STADIUM_RATIO;
    let (cap_start, cap_end) = part.cap_lengths();
    // Radii and sideways offsets at each end.
    let (r_start, r_end, offset_start, offset_end, major) = if stadium {
        let major = if rs.x + re.x >= rs.y + re.y { e1 } else { e2 };
        (
            rs.min_element(),
            re.min_element(),
            rs.max_element() - rs.min_element(),
            re.max_element() - re.min_element(),
            major,
        )
    } else {
        ((rs.x + rs.y) * 0.5, (re.x + re.y) * 0.5, 0.0, 0.0, e1)
    };
    // Pull the ends in so the hemispheres reach as far as the part's caps.
    let mut pull_start = (r_start - cap_start).max(0.0);
    let mut pull_end = (r_end - cap_end).max(0.0);
    if pull_start + pull_end > length {
        let scale = length / (pull_start + pull_end);
        pull_start *= scale;
        pull_end *= scale;
    }
    let a = part.start + d * pull_start;
    let b = part.end - d * pull_end;
    let signs: &[f32] = if stadium { &[-1.0, 0.0, 1.0] } else { &[0.0] };
    for &sign in signs {
        out.push(ProxyCapsule {
            part: index,
            joint: part.joint,
            group: collision_group(part.name),
            local: Capsule {
                a: a + major * (sign * offset_start),
                b: b + major * (sign * offset_end),
                radius_a: r_start + margin,
                radius_b: r_end + margin,
            },
        });
    }
}

/// A posed body: bone transforms and world capsules, refilled in place.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BodyPose {
    /// World transform of every joint.
    pub bones: Vec<Affine3A>,
    /// World capsule of every proxy, in [`BodyRig::proxies`] order.
    pub capsules: Vec<Capsule>,
    /// The (interpolated) channel values this pose was computed from.
    pub frame: Vec<f32>,
}

/// The skeleton, body and proxies of one subject: turns skeleton frames into [`BodyPose`]s.
#[derive(Clone, Debug)]
pub struct BodyRig {
    skeleton: Skeleton,
    body: Body,
    proxies: Vec<ProxyCapsule>,
    subject: Option<Subject>,
    rotation: Vec<bool>,
    root_channels: Range<usize>,
    /// Per proxy, how deep the spheres at [`YIELD_SAMPLES`] points along it reach into the trunk
    /// in the rest pose (arm proxies only; empty until [`BodyRig::new`] has measured them).
    rest_overlap: Vec<[f32; YIELD_SAMPLES]>,
}

/// Points along an arm capsule (both ends included) at which its reach into the trunk is measured.
const YIELD_SAMPLES: usize = 5;

/// For each of [`YIELD_SAMPLES`] points along `arm`, how deep the capsule's sphere there reaches
/// into the trunk capsule it enters deepest (negative: clear of every one by that much), and that
/// capsule's outward normal at the point (the normal only for that capsule: most points are
/// tested against a dozen).
fn trunk_reach(arm: &Capsule, trunk: &[PreparedCapsule]) -> [(f32, Vec3A); YIELD_SAMPLES] {
    std::array::from_fn(|k| {
        let (centre, radius) = arm.sphere_at(k as f32 / (YIELD_SAMPLES - 1) as f32);
        let point = Vec3A::from(centre);
        let mut deepest: Option<(f32, &PreparedCapsule)> = None;
        for capsule in trunk {
            let depth = radius - capsule.distance(point);
            if deepest.is_none_or(|(d, _)| depth > d) {
                deepest = Some((depth, capsule));
            }
        }
        match deepest {
            Some((depth, capsule)) => (depth, capsule.query(point).1),
            None => (f32::NEG_INFINITY, Vec3A::ZERO),
        }
    })
}

/// How far to move `arm` so that none of its [`YIELD_SAMPLES`] points reaches deeper into the
/// trunk than `rest` (its reach at those points in the rest pose; a point clear at rest may touch):
/// the points' excess depths pushed along the trunk's normals there, each less what the pushes
/// before it already moved the arm that way.
fn push_out_of_trunk(
    arm: &Capsule,
    rest: &[f32; YIELD_SAMPLES],
    trunk: &[PreparedCapsule],
) -> Vec3 {
    let mut push = Vec3A::ZERO;
    for ((depth, normal), rest) in trunk_reach(arm, trunk).into_iter().zip(rest) {
        let excess = depth - rest.max(0.0) - push.dot(normal);
        if excess > 0.0 {
            push += normal * excess;
        }
    }
    Vec3::from(push)
}

impl BodyRig {
    /// A rig from a skeleton (already scaled to the subject) and the body built on it.
    pub fn new(skeleton: Skeleton, body: Body, margin_cm: f32) -> BodyRig {
        let proxies = body_proxies(&body, margin_cm);
        let rotation = skeleton.rotation_channels();
        let root_channels = match skeleton.joints().first() {
            Some(root) => root.first_channel..root.first_channel + root.channels.len(),
            None => 0..0,
        };
        let mut rig = BodyRig {
            skeleton,
            body,
            proxies,
            subject: None,
            rotation,
            root_channels,
            rest_overlap: Vec::new(),
        };
        let mut rest = BodyPose::default();
        rig.pose(&rig.rest_frame(), &mut rest);
        let trunk = rig.trunk_capsules(&rest.capsules);
        rig.rest_overlap = rest
            .capsules
            .iter()
            .zip(&rig.proxies)
            .map(|(c, p)| match p.group {
                GROUP_ARMS => trunk_reach(c, &trunk).map(|(depth, _)| depth),
                _ => [f32::NEG_INFINITY; YIELD_SAMPLES],
            })
            .collect();
        rig
    }

    fn trunk_capsules(&self, capsules: &[Capsule]) -> Vec<PreparedCapsule> {
        capsules
            .iter()
            .zip(&self.proxies)
            .filter(|(_, p)| p.group == GROUP_TRUNK)
            .map(|c| c.0.prepared())
            .collect()
    }

    /// Moves each posed arm capsule out of the trunk, along the trunk's normals, until no point of
    /// it reaches deeper into the trunk than in the rest pose (a point clear of the trunk at rest
    /// may touch it): the mocap skeleton knows nothing of flesh, and a swinging or lowered arm
    /// passes into the chest or hips, where the cloth between them had no place outside both. The
    /// flesh gives way instead, as a real arm pressed against the chest does. The capsules move
    /// whole (a translation, their radii kept), so cloth cannot be pulled across a thinned arm.
    fn yield_arms(&self, capsules: &mut [Capsule]) {
        let trunk = self.trunk_capsules(capsules);
        for ((capsule, proxy), rest) in capsules
            .iter_mut()
            .zip(&self.proxies)
            .zip(&self.rest_overlap)
        {
            if proxy.group != GROUP_ARMS {
                continue;
            }
            let push = push_out_of_trunk(capsule, rest, &trunk);
            capsule.a += push;
            capsule.b += push;
        }
    }

    /// The rig of a built-in subject on the mocap's (unscaled) skeleton.
    pub fn for_subject(
        subject: &Subject,
        mocap_skeleton: &Skeleton,
        margin_cm: f32,
    ) -> Result<BodyRig, MissingJoint> {
        let skeleton = subject.scale_skeleton(mocap_skeleton);
        let body = Body::new(subject, &skeleton)?;
        let mut rig = BodyRig::new(skeleton, body, margin_cm);
        rig.subject = Some(subject.clone());
        Ok(rig)
    }

    pub fn skeleton(&self) -> &Skeleton {
        &self.skeleton
    }

    pub fn body(&self) -> &Body {
        &self.body
    }

    pub fn proxies(&self) -> &[ProxyCapsule] {
        &self.proxies
    }

    pub fn subject(&self) -> Option<&Subject> {
        self.subject.as_ref()
    }

    /// Channels of the root joint within a frame.
    pub fn root_channels(&self) -> Range<usize> {
        self.root_channels.clone()
    }

    /// A mocap motion on this rig's skeleton: the subject's root-translation scaling applied to every
    /// frame (unchanged values when the rig has no subject). The motion must have the rig's layout.
    pub fn scale_motion(&self, motion: &Motion) -> Motion {
        motion.with_skeleton(self.skeleton.clone(), |frame| {
            if let Some(subject) = &self.subject {
                subject.scale_root_translation(&self.skeleton, frame);
            }
        })
    }

    /// The rest pose's frame: every channel zero (the shipped skeleton's T-pose at the origin).
    pub fn rest_frame(&self) -> Vec<f32> {
        vec![0.0; self.skeleton.channel_count()]
    }

    /// `out = a + t·(b − a)` channel by channel, rotations by the shortest angular difference
    /// (degrees). Missing values in a short frame count as zero.
    pub fn interpolate(&self, a: &[f32], b: &[f32], t: f32, out: &mut Vec<f32>) {
        interpolate_frames(&self.rotation, a, b, t, out);
    }

    /// Root joint position for a frame (world, centimetres).
    pub fn root_position(&self, frame: &[f32]) -> Vec3 {
        if self.skeleton.is_empty() {
            return Vec3::ZERO;
        }
        Vec3::from(self.skeleton.local_transform(0, frame).translation)
    }

    /// Angle of the turn that takes the root's orientation in frame `a` to that in frame `b`,
    /// degrees in [0, 180].
    pub fn root_turn_degrees(&self, a: &[f32], b: &[f32]) -> f32 {
        self.skeleton.root_turn_degrees(a, b)
    }

    /// The capsules the renderer draws depth-only to hide the garment behind the body
    /// (`capsules`, posed by [`BodyRig::pose`], in [`BodyRig::proxies`] order). Under
    /// a garment with sleeves each upper arm's capsule starts one radius further down the arm:
    /// a garment cut in the T-pose has too little cloth over a lowered arm's shoulder, whose
    /// round top then stands out of the sleeve and would show the real shoulder through the
    /// garment (the cloth behind it is drawn there instead). Below the ball of the shoulder the
    /// arm keeps its full thickness, so the real arm still hides what is behind it.
    pub fn occluders(&self, capsules: &[Capsule], sleeves: bool) -> Vec<Capsule> {
        capsules
            .iter()
            .zip(&self.proxies)
            .map(|(&capsule, proxy)| {
                let upper_arm = self
                    .body
                    .parts
                    .get(proxy.part)
                    .is_some_and(|part| part.name.contains("upper_arm"));
                if sleeves && upper_arm {
                    without_shoulder_ball(capsule)
                } else {
                    capsule
                }
            })
            .collect()
    }

    /// Poses the body for one frame.
    pub fn pose(&self, frame: &[f32], pose: &mut BodyPose) {
        pose.frame.clear();
        pose.frame.extend_from_slice(frame);
        self.finish_pose(pose);
    }

    /// Poses the body at `t` between two frames.
    pub fn pose_between(&self, a: &[f32], b: &[f32], t: f32, pose: &mut BodyPose) {
        let mut frame = std::mem::take(&mut pose.frame);
        self.interpolate(a, b, t, &mut frame);
        pose.frame = frame;
        self.finish_pose(pose);
    }

    fn finish_pose(&self, pose: &mut BodyPose) {
        self.skeleton
            .forward_kinematics(&pose.frame, &mut pose.bones);
        pose.capsules.clear();
        pose.capsules
            .extend(self.proxies.iter().map(|p| p.posed(&pose.bones)));
        if !self.rest_overlap.is_empty() {
            self.yield_arms(&mut pose.capsules);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::Material;
    use glam::Vec2;
    use std::path::Path;

    #[test]
    fn an_arm_pressed_into_the_trunk_moves_out_by_what_it_reaches_deeper_than_at_rest() {
        // A trunk 10 cm thick around the y axis, an upright arm 5 cm thick whose axis is 12 cm
        // off it: the arm reaches 3 cm into the trunk all along.
        let trunk = [Capsule::new(Vec3::ZERO, Vec3::new(0.0, 50.0, 0.0), 10.0, 10.0).prepared()];
        let arm = Capsule::new(
            Vec3::new(12.0, 10.0, 0.0),
            Vec3::new(12.0, 40.0, 0.0),
            5.0,
            5.0,
        );
        let reach = trunk_reach(&arm, &trunk);
        assert!(reach
            .iter()
            .all(|(d, n)| (d - 3.0).abs() < 1e-4 && (*n - Vec3A::X).length() < 1e-5));
        // Clear of the trunk at rest: out until it touches. In it by 1 cm at rest: out by 2 cm.
        let push = push_out_of_trunk(&arm, &[-4.0; YIELD_SAMPLES], &trunk);
        assert!((push - Vec3::new(3.0, 0.0, 0.0)).length() < 1e-4, "{push}");
        let push = push_out_of_trunk(&arm, &[1.0; YIELD_SAMPLES], &trunk);
        assert!((push - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-4, "{push}");
        // No deeper than at rest, or clear of the trunk: it stays.
        assert_eq!(
            push_out_of_trunk(&arm, &[3.0; YIELD_SAMPLES], &trunk),
            Vec3::ZERO
        );
        let clear = Capsule::new(
            Vec3::new(20.0, 10.0, 0.0),
            Vec3::new(20.0, 40.0, 0.0),
            5.0,
            5.0,
        );
        assert_eq!(
            push_out_of_trunk(&clear, &[-4.0; YIELD_SAMPLES], &trunk),
            Vec3::ZERO
        );
        // Tilted into the trunk, 1 cm in at its top and 5 cm at its bottom: moved by the deepest.
        let tilted = Capsule::new(
            Vec3::new(10.0, 10.0, 0.0),
            Vec3::new(14.0, 40.0, 0.0),
            5.0,
            5.0,
        );
        let push = push_out_of_trunk(&tilted, &[-4.0; YIELD_SAMPLES], &trunk);
        assert!((push - Vec3::new(5.0, 0.0, 0.0)).length() < 1e-4, "{push}");
    }

    /// Subject chidi's rig on CMU walk 02_01's skeleton, and the walk scaled to it.
    fn chidi_walking() -> (BodyRig, Motion) {
        let clip =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mocap/cmu_02_01_walk.bvh");
        let motion = Motion::load(&clip).expect("clip");
        let chidi = Subject::find("chidi").expect("chidi");
        let rig = BodyRig::for_subject(chidi, &motion.skeleton, DEFAULT_MARGIN_CM).expect("rig");
        let motion = rig.scale_motion(&motion);
        (rig, motion)
    }

    #[test]
    fn a_posed_rig_keeps_its_arms_out_of_its_trunk() {
        // Walk 02_01 on chidi: in no frame does an arm reach deeper into the trunk than at rest.
        let (rig, motion) = chidi_walking();
        let mut pose = BodyPose::default();
        let mut pushed = 0;
        for f in 0..motion.frame_count() {
            rig.pose(motion.frame(f), &mut pose);
            let trunk = rig.trunk_capsules(&pose.capsules);
            for ((c, p), rest) in pose
                .capsules
                .iter()
                .zip(&rig.proxies)
                .zip(&rig.rest_overlap)
            {
                if p.group == GROUP_ARMS {
                    for ((depth, _), rest) in trunk_reach(c, &trunk).into_iter().zip(rest) {
                        assert!(depth <= rest.max(0.0) + 0.05, "frame {f}: {depth} > {rest}");
                    }
                    let posed = p.posed(&pose.bones);
                    pushed += usize::from(posed.a.distance(c.a) > 0.5);
                }
            }
        }
        // And the walk's lowered arms did need it.
        assert!(pushed > 0);
    }

    #[test]
    fn under_sleeves_the_upper_arms_hide_the_garment_from_below_the_shoulder_ball() {
        // A tapered arm 30 cm long, 5 cm thick at the shoulder and 4 cm at the elbow: it starts
        // 5 cm further down, 4.83 cm thick there, and ends where it did.
        let arm = Capsule::new(Vec3::ZERO, Vec3::new(0.0, -30.0, 0.0), 5.0, 4.0);
        let taken = without_shoulder_ball(arm);
        assert!(taken.a.distance(Vec3::new(0.0, -5.0, 0.0)) < 1e-5);
        assert!((taken.radius_a - (5.0 - 1.0 / 6.0)).abs() < 1e-5);
        assert_eq!((taken.b, taken.radius_b), (arm.b, arm.radius_b));
        // The ball's top is no longer inside; 10 cm down the arm is as thick as before.
        let top = Vec3::new(0.0, 4.0, 0.0);
        assert!(arm.signed_distance(top) < 0.0 && taken.signed_distance(top) > 0.0);
        let side = Vec3::new(4.6, -10.0, 0.0);
        assert!(arm.signed_distance(side) < 0.0 && taken.signed_distance(side) < 0.0);
        // A stub shorter than two radii keeps its far half.
        let stub = Capsule::new(Vec3::ZERO, Vec3::new(0.0, -6.0, 0.0), 5.0, 5.0);
        assert!(
            without_shoulder_ball(stub)
                .a
                .distance(Vec3::new(0.0, -3.0, 0.0))
                < 1e-5
        );

        // On a rig: only the upper arms change, and only under sleeves.
        let (rig, motion) = chidi_walking();
        let mut pose = BodyPose::default();
        rig.pose(motion.frame(5), &mut pose);
        assert_eq!(rig.occluders(&pose.capsules, false), pose.capsules);
        let occluders = rig.occluders(&pose.capsules, true);
        let changed: Vec<&str> = pose
            .capsules
            .iter()
            .zip(&occluders)
            .zip(rig.proxies())
            .filter(|((a, b), _)| a != b)
            .map(|(_, p)| rig.body().parts[p.part].name)
            .collect();
        assert_eq!(changed, ["right_upper_arm", "left_upper_arm"]);
    }

    fn part(radii_start: Vec2, radii_end: Vec2, cap: f32) -> BodyPart {
        BodyPart {
            name: "test",
            joint: 0,
            start: Vec3::ZERO,
            end: Vec3::new(0.0, 30.0, 0.0),
            radii_start,
            radii_end,
            width_axis: Vec3::X,
            cap,
            patterned_caps: [true, true],
            material: Material::Suit,
            surface: 0,
        }
    }

    #[test]
    fn round_part_is_one_capsule_of_the_mean_radius() {
        let body = Body {
            parts: vec![part(Vec2::new(5.0, 4.6), Vec2::new(4.0, 4.0), 1.0)],
            rest_pose: vec![glam::Affine3A::IDENTITY],
        };
        let proxies = body_proxies(&body, 0.5);
        assert_eq!(proxies.len(), 1);
        let c = proxies[0].local;
        assert!((c.radius_a - 5.3).abs() < 1e-6 && (c.radius_b - 4.5).abs() < 1e-6);
        // Mean radius 4.8 against a cap of 4.6: pulled in by 0.2 cm at the start, not at the end.
        assert!((c.a.y - 0.2).abs() < 1e-5 && (c.b.y - 30.0).abs() < 1e-5);
    }

    #[test]
    fn flat_part_is_a_stadium_of_three_capsules() {
        // 15 × 10 semi-axes, cap 0.7: capsules of radius 10 (+0.5) centred at −5, 0, +5 along X;
        // ends pulled in by 10 − 7 = 3 cm.
        let body = Body {
            parts: vec![part(Vec2::new(15.0, 10.0), Vec2::new(15.0, 10.0), 0.7)],
            rest_pose: vec![glam::Affine3A::IDENTITY],
        };
        let proxies = body_proxies(&body, 0.5);
        assert_eq!(proxies.len(), 3);
        let (l, m, r) = (proxies[0].local, proxies[1].local, proxies[2].local);
        assert!((l.a - Vec3::new(-5.0, 3.0, 0.0)).length() < 1e-5, "{l:?}");
        assert!((m.a - Vec3::new(0.0, 3.0, 0.0)).length() < 1e-5, "{m:?}");
        assert!((r.b - Vec3::new(5.0, 27.0, 0.0)).length() < 1e-5, "{r:?}");
        assert_eq!(l.radius_a, 10.5);
        let union = |p: Vec3| {
            l.signed_distance(p)
                .min(m.signed_distance(p))
                .min(r.signed_distance(p))
        };
        // The union contains the ellipse's extreme points (15, y, 0) and (0, y, 10) with the margin.
        for p in [Vec3::new(15.0, 15.0, 0.0), Vec3::new(0.0, 15.0, 10.0)] {
            assert!(union(p) <= -0.5 + 1e-4, "{p} {}", union(p));
        }
        // The worst dip, midway between two centres: the surface at x = 2.5 is at
        // z = √(10.5² − 2.5²) = 10.198, 0.30 cm below the stadium's flat side at 10.5.
        let top = (10.5f32 * 10.5 - 2.5 * 2.5).sqrt();
        assert!(union(Vec3::new(2.5, 15.0, top)).abs() < 1e-4);
        assert!((10.5 - top - 0.302).abs() < 1e-3);
        // And the caps: the part reaches y = −7; so does the proxy (sphere bottom at 3 − 10.5 + 0.5).
        assert!((l.a.y - l.radius_a + 0.5 - (-7.0)).abs() < 1e-4);
    }

    #[test]
    fn rotations_interpolate_the_short_way() {
        let (rig, _) = chidi_walking();
        let n = rig.skeleton().channel_count();
        let mut a = vec![0.0; n];
        let mut b = vec![0.0; n];
        a[0] = 10.0; // Xposition
        b[0] = 20.0;
        a[3] = 170.0; // Zrotation of the root
        b[3] = -170.0;
        let mut out = Vec::new();
        rig.interpolate(&a, &b, 0.5, &mut out);
        assert_eq!(out[0], 15.0);
        assert!((out[3] - 180.0).abs() < 1e-4, "{}", out[3]);
        let mut pose = BodyPose::default();
        rig.pose_between(&a, &b, 0.25, &mut pose);
        assert_eq!(pose.bones.len(), rig.skeleton().len());
        assert_eq!(pose.capsules.len(), rig.proxies().len());
        assert!((rig.root_position(&pose.frame).x - 12.5).abs() < 1e-5);
        // 17 parts: pelvis, abdomen, chest, both hands and both feet are flat enough for stadiums.
        assert_eq!(rig.proxies().len(), 17 + 2 * 7);
    }
}
