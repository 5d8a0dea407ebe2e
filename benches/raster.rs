//! Micro-benchmark of [`suitcap::raster::draw_triangle`]: jittered triangle meshes of different
//! triangle sizes drawn into a 1280×720 depth buffer with a shading closure that reads the weights
//! (as the garment renderer does), plus the same mesh drawn a second time behind the first (every
//! fragment fails the depth test). `…_visible` includes clearing the depth buffer (about 0.1 ms).
//! Each case also runs the previous per-pixel rasterizer (`old_…`, [`suitcap::raster::reference`])
//! for comparison on a busy machine. Times are CPU time of the benchmark thread.
//!
//! Run: `cargo bench --bench raster` (add `-- --quick` for a shorter run).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

use suitcap::raster::{draw_triangle, reference, Cull, DepthBuffer, Fragment, ScreenVertex};

#[path = "common/cpu_time.rs"]
mod cpu_time;
use cpu_time::ThreadCpu;

const W: u32 = 1280;
const H: u32 = 720;

/// A grid of `cell`-pixel quads (two triangles each) with jittered corners over a `size` region
/// centred in the frame, depth varying across it.
fn mesh(cell: f32, size: (f32, f32), seed: u64) -> Vec<[ScreenVertex; 3]> {
    let mut rng = Pcg64::seed_from_u64(seed);
    let (nx, ny) = ((size.0 / cell) as usize, (size.1 / cell) as usize);
    let (x0, y0) = ((W as f32 - size.0) / 2.0, (H as f32 - size.1) / 2.0);
    let jitter = cell * 0.3;
    let mut grid = Vec::with_capacity((nx + 1) * (ny + 1));
    for j in 0..=ny {
        for i in 0..=nx {
            grid.push(ScreenVertex {
                x: x0 + i as f32 * cell + rng.gen_range(-jitter..=jitter),
                y: y0 + j as f32 * cell + rng.gen_range(-jitter..=jitter),
                depth: 200.0 + 30.0 * (i as f32 / nx as f32) + 10.0 * (j as f32 / ny as f32),
            });
        }
    }
    let at = |i: usize, j: usize| grid[j * (nx + 1) + i];
    let mut tris = Vec::with_capacity(2 * nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            tris.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            tris.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    tris
}

fn behind(tris: &[[ScreenVertex; 3]]) -> Vec<[ScreenVertex; 3]> {
    tris.iter()
        .map(|t| {
            t.map(|v| ScreenVertex {
                depth: v.depth + 100.0,
                ..v
            })
        })
        .collect()
}

fn draw(buffer: &mut DepthBuffer, pixels: &mut [f32], tris: &[[ScreenVertex; 3]]) {
    for (n, t) in tris.iter().enumerate() {
        let lit = [n as f32 * 1e-4, 0.5, 1.0];
        draw_triangle(buffer, *t, Cull::None, 1.0, |f| shade(pixels, &f, &lit));
    }
}

fn draw_old(buffer: &mut DepthBuffer, pixels: &mut [f32], tris: &[[ScreenVertex; 3]]) {
    for (n, t) in tris.iter().enumerate() {
        let lit = [n as f32 * 1e-4, 0.5, 1.0];
        reference::draw_triangle(buffer, *t, Cull::None, 1.0, |f| shade(pixels, &f, &lit));
    }
}

#[inline]
fn shade(pixels: &mut [f32], f: &Fragment, lit: &[f32; 3]) {
    pixels[f.index] = f.weights[0] * lit[0] + f.weights[1] * lit[1] + f.weights[2] * lit[2];
}

fn benches(c: &mut Criterion<ThreadCpu>) {
    let mut g = c.benchmark_group("draw_triangle");
    let mut buffer = DepthBuffer::new(W, H);
    let mut old_buffer = DepthBuffer::new(W, H);
    let mut pixels = vec![0.0f32; (W * H) as usize];
    for (name, cell, size) in [
        ("tiny_3px", 3.0, (300.0, 300.0)),
        ("small_9px", 9.0, (640.0, 360.0)),
        ("medium_40px", 40.0, (640.0, 360.0)),
        ("large_360px", 360.0, (1080.0, 720.0)),
    ] {
        let tris = mesh(cell, size, 7);
        let hidden = behind(&tris);
        let covered = size.0 * size.1;
        eprintln!(
            "{name}: {} triangles, ~{:.0} pixels each",
            tris.len(),
            covered / tris.len() as f32
        );
        g.bench_function(format!("{name}_visible"), |b| {
            b.iter(|| {
                buffer.clear(W, H);
                draw(&mut buffer, &mut pixels, black_box(&tris));
            })
        });
        g.bench_function(format!("old_{name}_visible"), |b| {
            b.iter(|| {
                old_buffer.clear(W, H);
                draw_old(&mut old_buffer, &mut pixels, black_box(&tris));
            })
        });
        buffer.clear(W, H);
        draw(&mut buffer, &mut pixels, &tris);
        g.bench_function(format!("{name}_hidden"), |b| {
            b.iter(|| draw(&mut buffer, &mut pixels, black_box(&hidden)))
        });
        old_buffer.clear(W, H);
        draw_old(&mut old_buffer, &mut pixels, &tris);
        g.bench_function(format!("old_{name}_hidden"), |b| {
            b.iter(|| draw_old(&mut old_buffer, &mut pixels, black_box(&hidden)))
        });
    }
    g.finish();
}

criterion_group! {
    name = raster;
    config = Criterion::default().with_measurement(ThreadCpu).sample_size(30);
    targets = benches
}
criterion_main!(raster);
