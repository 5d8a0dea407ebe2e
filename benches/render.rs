//! Render + composite benchmark at 1280×720: a closed ellipsoid "garment" of 3,842 vertices around a
//! body-sized position (filling about a quarter of the frame) over 25 body capsules, two forearms
//! crossing in front of it. Measures the renderer alone, the garment composite alone (one thread and
//! rayon bands), their sum, and the full-frame overlay canvas. Target (issue 6): render + composite
//! ≤ 5 ms median on the 2-core machine.
//!
//! Run: `cargo bench --bench render` (add `-- --quick` for a shorter run).

use std::f32::consts::{PI, TAU};
use std::hint::black_box;

use criterion::measurement::Measurement;
use criterion::{criterion_group, criterion_main, Criterion};
use glam::Vec3;
use image::RgbImage;

use suitcap::camera::{Camera, Intrinsics};
use suitcap::cloth::Capsule;
use suitcap::composite::{Compositor, TextStyle};
use suitcap::render::{GarmentRenderer, RenderSettings};

#[path = "common/cpu_time.rs"]
mod cpu_time;
use cpu_time::{thread_cpu_ns, ThreadCpu};

const CENTRE: Vec3 = Vec3::new(0.0, 120.0, 0.0);

/// A closed ellipsoid with `rings` latitude rings of `segments` vertices plus two poles, wound
/// outward.
fn ellipsoid(radii: Vec3, rings: u32, segments: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut v = vec![CENTRE - Vec3::Y * radii.y];
    for r in 1..=rings {
        let lat = -PI / 2.0 + PI * r as f32 / (rings + 1) as f32;
        for s in 0..segments {
            let lon = TAU * s as f32 / segments as f32;
            let dir = Vec3::new(lat.cos() * lon.cos(), lat.sin(), lat.cos() * lon.sin());
            v.push(CENTRE + dir * radii);
        }
    }
    v.push(CENTRE + Vec3::Y * radii.y);
    let ring = |r: u32, s: u32| 1 + r * segments + s % segments;
    let top = v.len() as u32 - 1;
    let mut t = Vec::new();
    for s in 0..segments {
        t.push([0, ring(0, s), ring(0, s + 1)]);
        t.push([top, ring(rings - 1, s + 1), ring(rings - 1, s)]);
    }
    for r in 0..rings - 1 {
        for s in 0..segments {
            t.push([ring(r, s), ring(r + 1, s), ring(r + 1, s + 1)]);
            t.push([ring(r, s), ring(r + 1, s + 1), ring(r, s + 1)]);
        }
    }
    // Make sure the winding is outward whatever the parametrization's handedness.
    let [a, b, c] = t[2 * segments as usize].map(|i| v[i as usize]);
    if (b - a).cross(c - a).dot((a + b + c) / 3.0 - CENTRE) < 0.0 {
        for tri in &mut t {
            tri.swap(1, 2);
        }
    }
    (v, t)
}

fn cap(a: [f32; 3], b: [f32; 3], radius_a: f32, radius_b: f32) -> Capsule {
    Capsule {
        a: Vec3::from_array(a),
        b: Vec3::from_array(b),
        radius_a,
        radius_b,
    }
}

/// 25 capsules of a standing body; the forearms cross in front of the torso (the camera is at −Z).
fn body() -> Vec<Capsule> {
    let mut c = vec![
        cap([0.0, 80.0, 0.0], [0.0, 105.0, 0.0], 16.0, 15.0), // pelvis → spine
        cap([0.0, 105.0, 0.0], [0.0, 130.0, 0.0], 15.0, 16.0),
        cap([0.0, 130.0, 0.0], [0.0, 150.0, 0.0], 16.0, 14.0),
        cap([0.0, 150.0, 0.0], [0.0, 160.0, 0.0], 6.0, 5.0), // neck
        cap([0.0, 160.0, 0.0], [0.0, 178.0, 0.0], 9.0, 8.0), // head
    ];
    for side in [-1.0f32, 1.0] {
        let x = 18.0 * side;
        c.extend([
            cap([0.0, 148.0, 0.0], [x, 150.0, 0.0], 7.0, 7.0), // clavicle
            cap([x, 150.0, 0.0], [x * 1.5, 120.0, -10.0], 7.0, 5.5), // upper arm
            cap([x * 1.5, 120.0, -10.0], [-x * 0.6, 110.0, -40.0], 5.0, 4.0), // forearm, crossing
            cap([-x * 0.6, 110.0, -40.0], [-x, 108.0, -42.0], 4.0, 3.5), // hand
            cap([x * 0.5, 80.0, 0.0], [x * 0.55, 40.0, 2.0], 9.0, 6.0), // thigh
            cap([x * 0.55, 40.0, 2.0], [x * 0.55, 5.0, 0.0], 6.0, 4.5), // shin
            cap([x * 0.55, 5.0, 0.0], [x * 0.55, 3.0, -15.0], 4.0, 3.5), // foot
            cap([x * 0.3, 95.0, 0.0], [x * 0.5, 80.0, 0.0], 10.0, 9.0), // hip
            cap([x * 0.6, 135.0, 0.0], [x * 0.8, 145.0, 0.0], 9.0, 8.0), // chest side
            cap([x * 0.5, 115.0, 0.0], [x * 0.6, 125.0, 0.0], 10.0, 10.0), // waist side
        ]);
    }
    c
}

fn scene() -> (Camera, Vec<Vec3>, Vec<[u32; 3]>, Vec<Capsule>, RgbImage) {
    let camera = Camera::look_at(
        Intrinsics::from_fov(1280, 720, 60.0),
        Vec3::new(0.0, 120.0, -250.0),
        CENTRE,
        Vec3::Y,
    );
    let (v, t) = ellipsoid(Vec3::new(55.0, 60.0, 28.0), 60, 64);
    let frame = RgbImage::from_fn(1280, 720, |x, y| {
        image::Rgb([(x % 256) as u8, (y % 256) as u8, ((x + y) % 256) as u8])
    });
    (camera, v, t, body(), frame)
}

fn report_scene() -> (Camera, Vec<Vec3>, Vec<[u32; 3]>, Vec<Capsule>, RgbImage) {
    let (camera, vertices, triangles, capsules, frame) = scene();
    let mut renderer = GarmentRenderer::default();
    let layer = renderer.render(&camera, &vertices, &triangles, &capsules);
    if let Some(bounds) = layer.bounds() {
        let drawn = layer.data().chunks(4).filter(|p| p[3] > 0).count();
        eprintln!(
            "garment: {} vertices, {} triangles, {} capsules; layer {}×{} at ({}, {}), {} pixels drawn ({:.1} % of the frame)",
            vertices.len(),
            triangles.len(),
            capsules.len(),
            bounds.width,
            bounds.height,
            bounds.x,
            bounds.y,
            drawn,
            100.0 * drawn as f64 / (1280.0 * 720.0)
        );
    }
    (camera, vertices, triangles, capsules, frame)
}

/// The benchmarks of one group: `parallel` selects rayon bands in renderer and compositor.
fn benches_for<M: Measurement>(c: &mut Criterion<M>, group: &str, modes: &[(&str, bool)]) {
    let (camera, vertices, triangles, capsules, frame) = report_scene();
    let mut renderer = GarmentRenderer::default();
    let layer = renderer
        .render(&camera, &vertices, &triangles, &capsules)
        .clone();
    let mut g = c.benchmark_group(group);
    for &(name, parallel) in modes {
        renderer.set_settings(RenderSettings {
            parallel,
            ..RenderSettings::default()
        });
        let mut compositor = Compositor::new(parallel);
        let mut out = frame.clone();
        g.bench_function(format!("render_{name}"), |b| {
            b.iter(|| {
                black_box(renderer.render(&camera, &vertices, &triangles, &capsules));
            })
        });
        g.bench_function(format!("composite_{name}"), |b| {
            b.iter(|| compositor.composite(&mut out, &layer).expect("same size"))
        });
        g.bench_function(format!("render_and_composite_{name}"), |b| {
            b.iter(|| {
                let layer = renderer.render(&camera, &vertices, &triangles, &capsules);
                compositor.composite(&mut out, layer).expect("same size");
            })
        });
        g.bench_function(format!("canvas_with_text_{name}"), |b| {
            b.iter(|| {
                let mut canvas = compositor.canvas(&frame).expect("canvas");
                canvas.garment(&layer).expect("same size");
                canvas.text(
                    8.0,
                    8.0,
                    &["segment 4.1 ms", "cloth 3.2 ms", "drops 0", "REC"],
                    &TextStyle::default(),
                );
                canvas.finish(&mut out).expect("same size");
            })
        });
    }
    g.finish();
}

/// Wall-clock time, one thread and rayon.
fn wall(c: &mut Criterion) {
    benches_for(c, "render_1280x720", &[("single", false), ("rayon", true)]);
}

/// CPU time of the one thread doing the work (skipped where the kernel does not report it).
fn cpu(c: &mut Criterion<ThreadCpu>) {
    if thread_cpu_ns().is_some() {
        benches_for(c, "render_1280x720_thread_cpu", &[("single", false)]);
    }
}

criterion_group! {
    name = wall_clock;
    config = Criterion::default().sample_size(40);
    targets = wall
}
criterion_group! {
    name = thread_cpu;
    config = Criterion::default().with_measurement(ThreadCpu).sample_size(40);
    targets = cpu
}
criterion_main!(wall_clock, thread_cpu);
