//! Generator speed, per stage, one 640×480 frame on one thread:
//! `cargo bench -p suitcap-tools --bench synth`.
//! The whole-run figure (all cores, PNG writing included) is what `suitcap-synth` prints.

use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion};
use glam::Vec3;
use rand::SeedableRng;

use suitcap::body::{Body, SUBJECTS};
use suitcap::bvh::Motion;
use suitcap::camera::{Camera, Intrinsics};
use suitcap::suit::SuitDefinition;
use suitcap_tools::backgrounds::{load_plate, Crop};
use suitcap_tools::render::{compose, BodyLayer, BodyRenderer, Lighting, Sensor};

fn bench(c: &mut Criterion) {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let suit = SuitDefinition::load_dir(&repo.join("suits/default")).expect("suit");
    let motion = Motion::load(&repo.join("tests/data/mocap/cmu_02_01_walk.bvh")).expect("clip");
    let subject = &SUBJECTS[1];
    let skeleton = subject.scale_skeleton(&motion.skeleton);
    let body = Body::new(subject, &skeleton).expect("body");
    let mut frame = motion.frame(100).to_vec();
    subject.scale_root_translation(&motion.skeleton, &mut frame);
    let mut world = Vec::new();
    skeleton.forward_kinematics(&frame, &mut world);
    let hip = Vec3::from(world[0].translation);
    let (w, h) = (640, 480);
    let intrinsics = Intrinsics::from_fov(w, h, 58.0);
    let distance = intrinsics.fy * subject.height_cm / (0.6 * h as f32);
    let camera = Camera::look_at(
        intrinsics,
        hip + Vec3::new(40.0, 30.0, distance),
        hip,
        Vec3::Y,
    );
    let renderer = BodyRenderer::new(&suit, subject, &body, camera);
    let lighting = Lighting {
        direction: Vec3::new(0.3, 1.0, 0.6).normalize(),
        ambient: 0.45,
        exposure: 1.0,
    };
    let sensor = Sensor {
        gain: 1.0,
        blur_sigma: 0.7,
        read_noise: 2.0,
        shot_noise: 0.04,
    };
    let plate = load_plate(
        &repo.join("tests/data/backgrounds/photos/opencv_home.jpg"),
        w,
        h,
        Crop {
            zoom: 1.0,
            pan_x: 0.5,
            pan_y: 0.5,
        },
    )
    .expect("plate");
    let plate: Vec<[f32; 3]> = plate.pixels().map(|p| p.0.map(f32::from)).collect();
    let mut layer = BodyLayer::new(w, h);
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
    let (mut background, mut scratch) = (plate.clone(), Vec::new());

    let mut group = c.benchmark_group("synth_640x480");
    group.sample_size(30);
    group.bench_function("draw_body", |b| {
        b.iter(|| renderer.draw(&world, &lighting, &mut layer))
    });
    group.bench_function("visible_markers", |b| {
        b.iter(|| renderer.visible_markers(&world, &layer))
    });
    group.bench_function("compose_blur_noise", |b| {
        b.iter(|| {
            background.clear();
            background.extend_from_slice(&plate);
            compose(&mut background, &layer, &sensor, &mut rng, &mut scratch)
        })
    });
    let image = compose(&mut plate.clone(), &layer, &sensor, &mut rng, &mut scratch);
    group.bench_function("png_encode_fast", |b| {
        b.iter(|| {
            let mut bytes = Vec::with_capacity(1 << 20);
            let encoder = image::codecs::png::PngEncoder::new_with_quality(
                &mut bytes,
                image::codecs::png::CompressionType::Fast,
                image::codecs::png::FilterType::Sub,
            );
            image::ImageEncoder::write_image(
                encoder,
                image.as_raw(),
                w,
                h,
                image::ExtendedColorType::Rgb8,
            )
            .expect("encode");
            bytes
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
