//! Micro-benchmark of [`suitcap::raster::draw_triangle`]: jittered triangle meshes of different
//! triangle sizes drawn into a 1280×720 depth buffer with a shading closure that reads the weights
//! (as the garment renderer does), plus the same mesh drawn a second time behind the first (every
//! fragment fails the depth test). `…_visible` includes clearing the depth buffer (about 0.1 ms).
//! Each case also runs the previous per-pixel rasterizer (`old_…`, kept below) for comparison on a
//! busy machine. Times are CPU time of the benchmark thread.
//!
//! Run: `cargo bench --bench raster` (add `-- --quick` for a shorter run).

use std::hint::black_box;

use criterion::measurement::{Measurement, ValueFormatter, WallTime};
use criterion::{criterion_group, criterion_main, Criterion};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

use suitcap::raster::{draw_triangle, Cull, DepthBuffer, Fragment, ScreenVertex};

/// CPU time of the measuring thread (from `/proc/thread-self/schedstat`, in ns): the single-threaded
/// cost, less disturbed by other processes on a shared machine.
struct ThreadCpu;

fn thread_cpu_ns() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    text.split_whitespace().next()?.parse().ok()
}

impl Measurement for ThreadCpu {
    type Intermediate = u64;
    type Value = u64;

    fn start(&self) -> u64 {
        thread_cpu_ns().unwrap_or(0)
    }
    fn end(&self, start: u64) -> u64 {
        thread_cpu_ns().unwrap_or(0).saturating_sub(start)
    }
    fn add(&self, a: &u64, b: &u64) -> u64 {
        a + b
    }
    fn zero(&self) -> u64 {
        0
    }
    fn to_f64(&self, value: &u64) -> f64 {
        *value as f64
    }
    fn formatter(&self) -> &dyn ValueFormatter {
        static WALL: WallTime = WallTime;
        WALL.formatter()
    }
}

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

fn draw_old(buffer: &mut old::Buffer, pixels: &mut [f32], tris: &[[ScreenVertex; 3]]) {
    for (n, t) in tris.iter().enumerate() {
        let lit = [n as f32 * 1e-4, 0.5, 1.0];
        old::draw_triangle(buffer, *t, Cull::None, 1.0, |f| shade(pixels, &f, &lit));
    }
}

#[inline]
fn shade(pixels: &mut [f32], f: &Fragment, lit: &[f32; 3]) {
    pixels[f.index] = f.weights[0] * lit[0] + f.weights[1] * lit[1] + f.weights[2] * lit[2];
}

fn benches(c: &mut Criterion<ThreadCpu>) {
    let mut g = c.benchmark_group("draw_triangle");
    let mut buffer = DepthBuffer::new(W, H);
    let mut old_buffer = old::Buffer::new(W, H);
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
                old_buffer.clear();
                draw_old(&mut old_buffer, &mut pixels, black_box(&tris));
            })
        });
        buffer.clear(W, H);
        draw(&mut buffer, &mut pixels, &tris);
        g.bench_function(format!("{name}_hidden"), |b| {
            b.iter(|| draw(&mut buffer, &mut pixels, black_box(&hidden)))
        });
        old_buffer.clear();
        draw_old(&mut old_buffer, &mut pixels, &tris);
        g.bench_function(format!("old_{name}_hidden"), |b| {
            b.iter(|| draw_old(&mut old_buffer, &mut pixels, black_box(&hidden)))
        });
    }
    g.finish();
}

/// The rasterizer before spans (every pixel of the bounding box tested with three edge functions,
/// three divisions per covered pixel), for comparison.
mod old {
    use suitcap::raster::{Cull, Fragment, ScreenVertex};

    pub struct Buffer {
        width: u32,
        height: u32,
        depth: Vec<f32>,
    }

    impl Buffer {
        pub fn new(width: u32, height: u32) -> Buffer {
            Buffer {
                width,
                height,
                depth: vec![f32::INFINITY; (width * height) as usize],
            }
        }

        pub fn clear(&mut self) {
            self.depth.fill(f32::INFINITY);
        }
    }

    #[inline]
    fn edge(ax: f32, ay: f32, bx: f32, by: f32, px: f32, py: f32) -> f32 {
        (bx - ax) * (py - ay) - (by - ay) * (px - ax)
    }

    #[inline]
    fn is_top_left(ax: f32, ay: f32, bx: f32, by: f32) -> bool {
        (ay == by && bx > ax) || by < ay
    }

    pub fn draw_triangle(
        buffer: &mut Buffer,
        vertices: [ScreenVertex; 3],
        cull: Cull,
        near: f32,
        mut shade: impl FnMut(Fragment),
    ) {
        let [a, b, c] = vertices;
        if [a, b, c].iter().any(|v| {
            v.depth.is_nan()
                || near.is_nan()
                || v.depth < near
                || !v.x.is_finite()
                || !v.y.is_finite()
        }) {
            return;
        }
        let area = edge(a.x, a.y, b.x, b.y, c.x, c.y);
        if area == 0.0 || !area.is_finite() {
            return;
        }
        let front_facing = area < 0.0;
        if cull == Cull::Back && !front_facing {
            return;
        }
        let (v, order) = if area > 0.0 {
            ([a, b, c], [0, 1, 2])
        } else {
            ([a, c, b], [0, 2, 1])
        };
        let area = area.abs();
        let (w, h) = (buffer.width as f32, buffer.height as f32);
        let min_x = v
            .iter()
            .map(|p| p.x)
            .fold(f32::INFINITY, f32::min)
            .floor()
            .max(0.0);
        let max_x = v
            .iter()
            .map(|p| p.x)
            .fold(f32::NEG_INFINITY, f32::max)
            .ceil()
            .min(w);
        let min_y = v
            .iter()
            .map(|p| p.y)
            .fold(f32::INFINITY, f32::min)
            .floor()
            .max(0.0);
        let max_y = v
            .iter()
            .map(|p| p.y)
            .fold(f32::NEG_INFINITY, f32::max)
            .ceil()
            .min(h);
        if min_x >= max_x || min_y >= max_y {
            return;
        }
        let edges = [(1, 2), (2, 0), (0, 1)];
        let top_left = edges.map(|(i, j)| is_top_left(v[i].x, v[i].y, v[j].x, v[j].y));
        let inv_depth = v.map(|p| 1.0 / p.depth);
        let width = buffer.width as usize;
        for py in min_y as u32..max_y as u32 {
            let cy = py as f32 + 0.5;
            for px in min_x as u32..max_x as u32 {
                let cx = px as f32 + 0.5;
                let mut lambda = [0.0f32; 3];
                let mut inside = true;
                for (k, &(i, j)) in edges.iter().enumerate() {
                    let e = edge(v[i].x, v[i].y, v[j].x, v[j].y, cx, cy);
                    if e < 0.0 || (e == 0.0 && !top_left[k]) {
                        inside = false;
                        break;
                    }
                    lambda[k] = e / area;
                }
                if !inside {
                    continue;
                }
                let inv_z =
                    lambda[0] * inv_depth[0] + lambda[1] * inv_depth[1] + lambda[2] * inv_depth[2];
                let depth = 1.0 / inv_z;
                let index = py as usize * width + px as usize;
                if depth >= buffer.depth[index] {
                    continue;
                }
                buffer.depth[index] = depth;
                let mut weights = [0.0f32; 3];
                for k in 0..3 {
                    weights[order[k]] = lambda[k] * inv_depth[k] * depth;
                }
                shade(Fragment {
                    x: px,
                    y: py,
                    index,
                    depth,
                    weights,
                    front_facing,
                });
            }
        }
    }
}

criterion_group! {
    name = raster;
    config = Criterion::default().with_measurement(ThreadCpu).sample_size(30);
    targets = benches
}
criterion_main!(raster);
