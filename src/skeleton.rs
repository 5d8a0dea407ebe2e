//! Joint hierarchy and forward kinematics.
//!
//! A [`Skeleton`] is the `HIERARCHY` part of a BVH file as plain data: joints in file order, each with
//! its parent, its rest `OFFSET`, its channels and an optional end site. [`Skeleton::forward_kinematics`]
//! turns one frame of channel values into a world transform per joint, following the usual BVH
//! convention: a joint's local transform is `T(offset) · T(position channels) · R(c₁) · R(c₂) · R(c₃)`
//! with the rotation channels multiplied in the order the file lists them (so `Zrotation Xrotation
//! Yrotation` is `Rz·Rx·Ry`), and a joint's world transform is its parent's world transform times its
//! local one. The renderer, the body proxies of the cloth simulation and the pose decoder all read
//! joint positions and frames from here.

use glam::{Affine3A, Mat3A, Quat, Vec3, Vec3A};

/// One degree of freedom of a BVH joint. Angles are in degrees, positions in the file's units.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Channel {
    Xposition,
    Yposition,
    Zposition,
    Xrotation,
    Yrotation,
    Zrotation,
}

impl Channel {
    /// The channel's name as written in a BVH file.
    pub fn name(self) -> &'static str {
        match self {
            Channel::Xposition => "Xposition",
            Channel::Yposition => "Yposition",
            Channel::Zposition => "Zposition",
            Channel::Xrotation => "Xrotation",
            Channel::Yrotation => "Yrotation",
            Channel::Zrotation => "Zrotation",
        }
    }

    /// Parses a BVH channel name (case-insensitive, as readers in the wild accept).
    pub fn from_name(name: &str) -> Option<Channel> {
        [
            Channel::Xposition,
            Channel::Yposition,
            Channel::Zposition,
            Channel::Xrotation,
            Channel::Yrotation,
            Channel::Zrotation,
        ]
        .into_iter()
        .find(|c| c.name().eq_ignore_ascii_case(name))
    }

    pub fn is_rotation(self) -> bool {
        matches!(
            self,
            Channel::Xrotation | Channel::Yrotation | Channel::Zrotation
        )
    }

    /// Unit axis of the channel (x, y or z).
    pub fn axis(self) -> Vec3A {
        match self {
            Channel::Xposition | Channel::Xrotation => Vec3A::X,
            Channel::Yposition | Channel::Yrotation => Vec3A::Y,
            Channel::Zposition | Channel::Zrotation => Vec3A::Z,
        }
    }
}

/// One joint of a [`Skeleton`].
#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    pub name: String,
    /// Index of the parent joint; `None` for the root. Parents always come before their children.
    pub parent: Option<usize>,
    /// Rest offset from the parent joint, in the parent's frame.
    pub offset: Vec3,
    pub channels: Vec<Channel>,
    /// Index of this joint's first channel within a frame's values.
    pub first_channel: usize,
    /// Offset of the `End Site`, if the joint has one.
    pub end_site: Option<Vec3>,
}

/// A BVH joint hierarchy. Joints are stored in file order: the root first, parents before children.
#[derive(Clone, Debug, PartialEq)]
pub struct Skeleton {
    joints: Vec<Joint>,
    channel_count: usize,
}

/// Why a list of joints is not a valid skeleton.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SkeletonError {
    #[error("the skeleton has no joints")]
    Empty,
    #[error(
        "joint {index} ('{name}'): the first joint must be the root and only it may lack a parent"
    )]
    BadRoot { index: usize, name: String },
    #[error("joint {index} ('{name}'): parent {parent} does not come before it")]
    ParentOrder {
        index: usize,
        name: String,
        parent: usize,
    },
    #[error("joint name '{0}' appears twice")]
    DuplicateName(String),
    #[error("joint {index} ('{name}'): first channel is {got}, expected {expected}")]
    ChannelLayout {
        index: usize,
        name: String,
        got: usize,
        expected: usize,
    },
}

impl Skeleton {
    /// Builds a skeleton, checking the parent order, the single root, unique names and the channel layout.
    pub fn new(joints: Vec<Joint>) -> Result<Skeleton, SkeletonError> {
        if joints.is_empty() {
            return Err(SkeletonError::Empty);
        }
        let mut expected_channel = 0;
        for (index, joint) in joints.iter().enumerate() {
            match joint.parent {
                None if index != 0 => {
                    return Err(SkeletonError::BadRoot {
                        index,
                        name: joint.name.clone(),
                    })
                }
                Some(_) if index == 0 => {
                    return Err(SkeletonError::BadRoot {
                        index,
                        name: joint.name.clone(),
                    })
                }
                Some(parent) if parent >= index => {
                    return Err(SkeletonError::ParentOrder {
                        index,
                        name: joint.name.clone(),
                        parent,
                    })
                }
                _ => {}
            }
            if joints[..index].iter().any(|j| j.name == joint.name) {
                return Err(SkeletonError::DuplicateName(joint.name.clone()));
            }
            if joint.first_channel != expected_channel {
                return Err(SkeletonError::ChannelLayout {
                    index,
                    name: joint.name.clone(),
                    got: joint.first_channel,
                    expected: expected_channel,
                });
            }
            expected_channel += joint.channels.len();
        }
        Ok(Skeleton {
            joints,
            channel_count: expected_channel,
        })
    }

    pub fn joints(&self) -> &[Joint] {
        &self.joints
    }

    pub fn joint(&self, index: usize) -> &Joint {
        &self.joints[index]
    }

    pub fn len(&self) -> usize {
        self.joints.len()
    }

    pub fn is_empty(&self) -> bool {
        self.joints.is_empty()
    }

    /// Number of channel values in one frame.
    pub fn channel_count(&self) -> usize {
        self.channel_count
    }

    /// Index of the joint with this exact name.
    pub fn find(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Is `ancestor` on the path from `joint` to the root (or `joint` itself)?
    pub fn is_ancestor(&self, ancestor: usize, joint: usize) -> bool {
        let mut current = Some(joint);
        while let Some(j) = current {
            if j == ancestor {
                return true;
            }
            current = self.joints[j].parent;
        }
        false
    }

    /// The same hierarchy with every joint's offset (and end site) replaced by `f(joint index, offset)`.
    pub fn map_offsets(&self, mut f: impl FnMut(usize, Vec3) -> Vec3) -> Skeleton {
        let joints = self
            .joints
            .iter()
            .enumerate()
            .map(|(i, j)| Joint {
                offset: f(i, j.offset),
                end_site: j.end_site.map(|e| f(i, e)),
                ..j.clone()
            })
            .collect();
        Skeleton {
            joints,
            channel_count: self.channel_count,
        }
    }

    /// Angle of the turn that takes the root's orientation in frame `a` to that in frame `b`,
    /// degrees in [0, 180]; 0 for an empty skeleton.
    pub fn root_turn_degrees(&self, a: &[f32], b: &[f32]) -> f32 {
        if self.joints.is_empty() {
            return 0.0;
        }
        let rotation =
            |frame: &[f32]| Quat::from_mat3a(&self.local_transform(0, frame).matrix3).normalize();
        rotation(a).angle_between(rotation(b)).to_degrees()
    }

    /// Local transform of joint `index` for one frame of channel values.
    pub fn local_transform(&self, index: usize, frame: &[f32]) -> Affine3A {
        let joint = &self.joints[index];
        let mut translation = Vec3A::from(joint.offset);
        let mut rotation = Mat3A::IDENTITY;
        for (k, &channel) in joint.channels.iter().enumerate() {
            let value = frame.get(joint.first_channel + k).copied().unwrap_or(0.0);
            if channel.is_rotation() {
                rotation *= Mat3A::from_axis_angle(channel.axis().into(), value.to_radians());
            } else {
                translation += channel.axis() * value;
            }
        }
        Affine3A {
            matrix3: rotation,
            translation,
        }
    }

    /// World transform of every joint for one frame, written into `world` (resized to the joint count).
    /// Missing channel values (a short frame) count as zero; callers validate frame lengths on load.
    pub fn forward_kinematics(&self, frame: &[f32], world: &mut Vec<Affine3A>) {
        world.clear();
        for index in 0..self.joints.len() {
            let local = self.local_transform(index, frame);
            let transform = match self.joints[index].parent {
                Some(parent) => world[parent] * local,
                None => local,
            };
            world.push(transform);
        }
    }

    /// World positions of every joint for one frame.
    pub fn joint_positions(&self, frame: &[f32]) -> Vec<Vec3> {
        let mut world = Vec::with_capacity(self.joints.len());
        self.forward_kinematics(frame, &mut world);
        world.iter().map(|t| Vec3::from(t.translation)).collect()
    }

    /// Which values of a frame are rotations (degrees), in frame order; the others are positions.
    pub fn rotation_channels(&self) -> Vec<bool> {
        let mut rotation = vec![false; self.channel_count];
        for joint in &self.joints {
            for (k, channel) in joint.channels.iter().enumerate() {
                if let Some(slot) = rotation.get_mut(joint.first_channel + k) {
                    *slot = channel.is_rotation();
                }
            }
        }
        rotation
    }
}

/// The fastest a person's root turns, degrees per second: the fastest root turn in the CMU clips
/// we have, resampled to 30 frames/s (their calibration frame left out), is 23.8° in a frame (05_11,
/// a pirouette; 05_07 17.2°, 05_02 13.0°, every other clip below 13°), 714°/s; this is half as much
/// again, 35° at 30 frames/s. The quick start's estimated poses once turn 48.9° in a frame.
pub const MAX_ROOT_TURN_DEG_PER_S: f32 = 1050.0;

/// `out = a + t·(b − a)` value by value, the values `rotation` marks (see
/// [`Skeleton::rotation_channels`]) by the shortest angular difference in degrees, so that 170° to
/// −170° passes through 180°, not through 0°. `out` gets `rotation.len()` values; a value missing
/// from a short frame counts as zero.
pub fn interpolate_frames(rotation: &[bool], a: &[f32], b: &[f32], t: f32, out: &mut Vec<f32>) {
    out.clear();
    out.extend(rotation.iter().enumerate().map(|(k, &is_rotation)| {
        let va = a.get(k).copied().unwrap_or(0.0);
        let vb = b.get(k).copied().unwrap_or(0.0);
        let delta = if is_rotation {
            wrap_degrees(vb - va)
        } else {
            vb - va
        };
        va + delta * t
    }));
}

/// An angle difference `a − b` wrapped to [−180°, 180°) (degrees): the short way round.
pub fn wrap_degrees(delta: f32) -> f32 {
    (delta + 180.0).rem_euclid(360.0) - 180.0
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A two-joint arm: a root with 6 channels at the origin and an elbow 10 units along +X
    /// that rotates about Z, ending 5 units further along X.
    pub fn two_joint_arm() -> Skeleton {
        Skeleton::new(vec![
            Joint {
                name: "shoulder".into(),
                parent: None,
                offset: Vec3::ZERO,
                channels: vec![
                    Channel::Xposition,
                    Channel::Yposition,
                    Channel::Zposition,
                    Channel::Zrotation,
                    Channel::Yrotation,
                    Channel::Xrotation,
                ],
                first_channel: 0,
                end_site: None,
            },
            Joint {
                name: "elbow".into(),
                parent: Some(0),
                offset: Vec3::new(10.0, 0.0, 0.0),
                channels: vec![Channel::Zrotation, Channel::Xrotation, Channel::Yrotation],
                first_channel: 6,
                end_site: Some(Vec3::new(5.0, 0.0, 0.0)),
            },
        ])
        .expect("valid fixture")
    }

    #[test]
    fn frames_interpolate_rotations_the_short_way_and_positions_straight() {
        assert_eq!(wrap_degrees(350.0), -10.0);
        assert_eq!(wrap_degrees(-350.0), 10.0);
        assert_eq!(wrap_degrees(90.0), 90.0);
        let arm = two_joint_arm();
        let rotation = arm.rotation_channels();
        assert_eq!(
            rotation,
            [false, false, false, true, true, true, true, true, true]
        );
        let a = [10.0, 0.0, 0.0, 170.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let b = [20.0, 0.0, 0.0, -170.0, 0.0, 0.0, 90.0, 0.0, 0.0];
        let mut out = Vec::new();
        interpolate_frames(&rotation, &a, &b, 0.25, &mut out);
        assert_eq!(out.len(), 9);
        assert_eq!(out[0], 12.5);
        assert!((out[3] - 175.0).abs() < 1e-4, "{}", out[3]);
        assert_eq!(out[6], 22.5);
        // A short frame's missing values count as zero.
        interpolate_frames(&rotation, &a[..4], &b, 1.0, &mut out);
        assert_eq!(out[6], 90.0);
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-4
    }

    #[test]
    fn rest_pose_places_joints_at_their_offsets() {
        let arm = two_joint_arm();
        let positions = arm.joint_positions(&[0.0; 9]);
        assert!(close(positions[0], Vec3::ZERO));
        assert!(close(positions[1], Vec3::new(10.0, 0.0, 0.0)));
    }

    #[test]
    fn root_rotation_about_z_swings_the_elbow_up() {
        // Zrotation 90° turns +X into +Y: the elbow moves from (10,0,0) to (0,10,0).
        let arm = two_joint_arm();
        let frame = [1.0, 2.0, 3.0, 90.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let positions = arm.joint_positions(&frame);
        assert!(close(positions[0], Vec3::new(1.0, 2.0, 3.0)));
        assert!(close(positions[1], Vec3::new(1.0, 12.0, 3.0)));
    }

    #[test]
    fn elbow_rotation_moves_only_the_end_site() {
        let arm = two_joint_arm();
        let frame = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 90.0, 0.0, 0.0];
        let mut world = Vec::new();
        arm.forward_kinematics(&frame, &mut world);
        let end = world[1].transform_point3(Vec3::new(5.0, 0.0, 0.0));
        assert!(close(
            Vec3::from(world[1].translation),
            Vec3::new(10.0, 0.0, 0.0)
        ));
        assert!(close(end, Vec3::new(10.0, 5.0, 0.0)));
    }

    #[test]
    fn rotations_compose_in_listed_order() {
        // Root channels Z, Y, X: R = Rz(90)·Ry(90). Applied to the elbow offset (10,0,0):
        // Ry(90) sends +X to −Z, then Rz(90) leaves −Z unchanged → (0,0,−10).
        let arm = two_joint_arm();
        let frame = [0.0, 0.0, 0.0, 90.0, 90.0, 0.0, 0.0, 0.0, 0.0];
        let positions = arm.joint_positions(&frame);
        assert!(
            close(positions[1], Vec3::new(0.0, 0.0, -10.0)),
            "{:?}",
            positions[1]
        );
    }

    #[test]
    fn invalid_hierarchies_are_rejected() {
        let mut joints = two_joint_arm().joints().to_vec();
        joints[1].name = "shoulder".into();
        assert_eq!(
            Skeleton::new(joints).unwrap_err(),
            SkeletonError::DuplicateName("shoulder".into())
        );
        let mut joints = two_joint_arm().joints().to_vec();
        joints[1].first_channel = 3;
        assert!(matches!(
            Skeleton::new(joints),
            Err(SkeletonError::ChannelLayout { .. })
        ));
        assert_eq!(Skeleton::new(vec![]).unwrap_err(), SkeletonError::Empty);
    }
}
