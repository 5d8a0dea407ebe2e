//! Cloth: garments simulated on the posed body's collision capsules (work in progress).

pub mod capsule;
pub mod garment;
pub mod material;
pub mod obj;
pub mod proxies;
pub mod solver;
pub mod topology;

pub use capsule::Capsule;

#[cfg(test)]
mod scratch {
    use super::proxies::*;
    use std::path::Path;
    #[test]
    fn dump_rest() {
        let clip = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mocap/cmu_02_01_walk.bvh");
        let motion = crate::bvh::Motion::load(&clip).unwrap();
        let subject = crate::body::Subject::find("chidi").unwrap();
        let rig = BodyRig::for_subject(subject, &motion.skeleton, 0.5).unwrap();
        let mut pose = BodyPose::default();
        rig.pose(&rig.rest_frame(), &mut pose);
        for (i, j) in rig.skeleton().joints().iter().enumerate() {
            if j.name.contains("Thumb") || j.name.contains("Index") || j.name.contains("Mid") || j.name.contains("Ring") || j.name.contains("Pinky") { continue; }
            println!("{i} {} {:?}", j.name, pose.bones[i].translation);
        }
        for (p, c) in rig.proxies().iter().zip(&pose.capsules) {
            println!("{} a={:?} b={:?} ra={} rb={}", rig.body().parts[p.part].name, c.a, c.b, c.radius_a, c.radius_b);
        }
        println!("frame0 {:?}", &motion.frame(0)[..12]);
    }
}
