//! RVM inference benchmark on the shipped default suit: the descriptors of the bundled demo clip's 60
//! frames (`suits/default/demo/640x480/`, segmented and described by the suit's own models in the
//! set-up, not timed), then per frame
//! - `predict`: the RVM alone (a distance to each relevance vector and a matrix-vector product,
//!   `Rvm::predict_into`);
//! - `predict + exemplars`: the RVM and the blend towards the nearest exemplars
//!   (`Regressor::predict_into`, `pose::exemplars`), the "inference for one frame ≤ 1 ms";
//! - `predict + exemplars + decode`: the same and the pose vector decoded into the BVH frame
//!   through the camera (`PoseLayout::decode`), which is what the pipeline's regression stage does
//!   before the root's position correction.
//!
//! Each iteration takes the next frame's descriptor in turn, so the kernel's zeros (relevance vectors
//! too far from the frame, skipped in the product) are those of real frames. Times are wall-clock
//! (the thread's CPU time, as `benches/render.rs` uses, ticks too coarsely for a tenth of a
//! millisecond): run it on an otherwise idle machine.
//!
//! Run: `cargo bench --bench regressor` (add `-- --quick` for a shorter run).

use std::hint::black_box;
use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion};

use suitcap::camera::Camera;
use suitcap::descriptor::{Codebooks, Describer};
use suitcap::pipeline::PosePipeline;
use suitcap::pose::regressor::Regressor;
use suitcap::suit::SuitDefinition;

/// The demo clip's descriptors (those with a person in them) and bounding boxes.
struct Frames {
    descriptors: Vec<Vec<f32>>,
    boxes: Vec<(f32, f32, f32, f32)>,
}

fn describe_demo(suit_dir: &Path, suit: &SuitDefinition, regressor: &Regressor) -> Frames {
    let clip = suit_dir.join("demo/640x480");
    let mut segmenter = PosePipeline::load_segmenter(suit_dir).expect("the default segmenter");
    let codebooks = Codebooks::load(suit_dir).expect("the default codebooks");
    let mut describer = Describer::new(suit);
    let mut names: Vec<_> = std::fs::read_dir(clip.join("frames"))
        .expect("the demo frames")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    names.sort();
    let mut frames = Frames {
        descriptors: Vec::new(),
        boxes: Vec::new(),
    };
    for path in names {
        let image = image::open(&path).expect("a demo frame").to_rgb8();
        let mask = segmenter.segment(&image).mask;
        let (descriptor, _) = describer.describe(&image, &mask, regressor.descriptor, &codebooks);
        if let (Some((x0, y0, x1, y1)), true) = (mask.bounding_box(), descriptor.person) {
            frames.descriptors.push(descriptor.values);
            frames
                .boxes
                .push((x0 as f32, y0 as f32, x1 as f32, y1 as f32));
        }
    }
    assert!(
        !frames.descriptors.is_empty(),
        "nobody found in the demo clip"
    );
    frames
}

fn bench(c: &mut Criterion) {
    let suit_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("suits/default");
    let suit = SuitDefinition::load_dir(&suit_dir).expect("the default suit");
    let regressor = Regressor::load(&suit_dir, &suit).expect("the default regressor");
    let camera =
        Camera::load(&suit_dir.join("demo/640x480/camera.toml")).expect("the demo's camera");
    let frames = describe_demo(&suit_dir, &suit, &regressor);
    eprintln!(
        "regressor: {} relevance vectors of {} values, {} outputs; {} demo frames described",
        regressor.rvm.len(),
        regressor.rvm.dim,
        regressor.rvm.outputs,
        frames.descriptors.len()
    );
    let mut pose = vec![0.0; regressor.rvm.outputs];
    // The next frame's descriptor regressed into `pose`, by the RVM alone or with the
    // exemplars' blend as the pipeline runs it; its index.
    let mut k = 0;
    let mut regress_next = |pose: &mut [f32], with_exemplars: bool| {
        k = (k + 1) % frames.descriptors.len();
        let descriptor = black_box(&frames.descriptors[k]);
        if with_exemplars {
            regressor.predict_into(descriptor, pose);
        } else {
            regressor.rvm.predict_into(descriptor, pose);
        }
        k
    };
    let mut group = c.benchmark_group("regressor");
    group.bench_function("predict", |b| {
        b.iter(|| {
            regress_next(&mut pose, false);
            black_box(&pose);
        })
    });
    group.bench_function("predict + exemplars", |b| {
        b.iter(|| {
            regress_next(&mut pose, true);
            black_box(&pose);
        })
    });
    group.bench_function("predict + exemplars + decode", |b| {
        b.iter(|| {
            let k = regress_next(&mut pose, true);
            black_box(regressor.layout.decode(
                &regressor.skeleton.skeleton,
                &pose,
                regressor.template(),
                &camera,
                frames.boxes[k],
            ))
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
