//! Pose error measures: per joint, the mean absolute difference of its three Euler angles wrapped to
//! ±180° (the source paper's measure) and the geodesic angle between the two rotations (which does not
//! depend on how a rotation is split into Euler angles).

use super::{compose, PoseLayout};

/// `a − b` wrapped to [−180°, 180°).
pub fn wrap_degrees(d: f32) -> f32 {
    (d + 180.0).rem_euclid(360.0) - 180.0
}

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

    /// `joint,euler_deg,geodesic_deg` rows, then `mean`.
    pub fn to_csv(&self) -> String {
        let mut out = String::from("joint,euler_deg,geodesic_deg\n");
        for (j, name) in self.names.iter().enumerate() {
            out.push_str(&format!(
                "{name},{:.3},{:.3}\n",
                self.euler(j),
                self.geodesic(j)
            ));
        }
        out.push_str(&format!(
            "mean,{:.3},{:.3}\n",
            self.mean_euler(),
            self.mean_geodesic()
        ));
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrapping() {
        assert_eq!(wrap_degrees(350.0), -10.0);
        assert_eq!(wrap_degrees(-190.0), 170.0);
        assert_eq!(wrap_degrees(10.0), 10.0);
    }

    #[test]
    fn a_known_error_on_a_two_joint_skeleton() {
        let skeleton = crate::skeleton::tests::two_joint_arm();
        let suit = crate::suit::SuitSkeleton {
            joints: vec![
                crate::suit::SuitJoint {
                    name: "shoulder".into(),
                    parent: None,
                    bvh: "shoulder".into(),
                },
                crate::suit::SuitJoint {
                    name: "elbow".into(),
                    parent: Some(0),
                    bvh: "elbow".into(),
                },
            ],
        };
        let layout = PoseLayout::new(&suit, &skeleton).expect("layout");
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
}
