//! Renders one synthetic frame: the suited body over a background plate, with light, blur and noise.
//!
//! [`BodyRenderer`] holds a subject's body meshes and the suit pattern. For one frame's joint
//! transforms it rasterizes every part with the z-buffer of `suitcap::raster`, paints suit parts with
//! the marker grid (looked up per pixel in physical surface units, so markers stay 4 cm squares at any
//! distance), skin and shoes with their albedo, and shades with Lambert + ambient light. The result is a
//! [`BodyLayer`]: colour, depth and marker id per pixel. [`compose`] puts the layer over the
//! background, applies the exposure gain, a Gaussian blur and sensor noise (read + shot), and returns
//! the 8-bit frame. The ground-truth mask is the set of pixels the body covers before blur;
//! [`BodyRenderer::visible_markers`] reports each visible marker's projected centre and the share of
//! its square that faces the camera unoccluded (sampled on the body's surface and tested against the
//! layer's depth and against the inside of the other parts).

use std::collections::HashMap;

use glam::{Affine3A, Vec2, Vec3, Vec3A};
use image::{GrayImage, RgbImage};
use rand::Rng;
use rand_distr::StandardNormal;

use suitcap::body::{Body, BodyPart, MarkerCell, MarkerGrid, Material, PartMesh, Subject};
use suitcap::camera::Camera;
use suitcap::raster::{draw_triangle, Cull, DepthBuffer, ScreenVertex};
use suitcap::suit::SuitDefinition;

/// Nearest depth drawn (cm).
const NEAR_CM: f32 = 5.0;
/// "No marker" in [`BodyLayer::marker`].
pub const NO_MARKER: u32 = u32::MAX;
/// Points per side of a marker's square sampled for its visible fraction
/// ([`BodyRenderer::visible_markers`]).
pub const VISIBILITY_SAMPLES: usize = 8;
/// How far (cm) a marker's surface point may lie behind the depth drawn at its pixel and still be
/// what is seen there: the drawn mesh's chords lie up to a few millimetres inside the curved
/// surface the points are taken on, an arm in front of the chest is centimetres nearer.
pub const VISIBILITY_DEPTH_CM: f32 = 1.0;

/// How far from another part a marker's centre may lie for its square to be tested against that
/// part's inside, cm: more than the 2.9 cm from a 4 cm square's centre to its corners.
const BURIED_SEARCH_CM: f32 = 3.0;

/// Lighting of the body for one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lighting {
    /// Unit vector towards the light, world frame.
    pub direction: Vec3,
    /// Ambient share in [0, 1]; the diffuse light has intensity 1 − ambient.
    pub ambient: f32,
    /// Overall gain of the body's radiance.
    pub exposure: f32,
}

/// Per-pixel result of drawing the body.
#[derive(Clone, Debug)]
pub struct BodyLayer {
    pub width: u32,
    pub height: u32,
    pub depth: DepthBuffer,
    /// Shaded colour, 0–255 scale, valid where depth is finite.
    pub colour: Vec<[f32; 3]>,
    /// Index into [`BodyRenderer::markers`] of the marker seen at each pixel, or [`NO_MARKER`].
    pub marker: Vec<u32>,
}

impl BodyLayer {
    pub fn new(width: u32, height: u32) -> BodyLayer {
        let n = width as usize * height as usize;
        BodyLayer {
            width,
            height,
            depth: DepthBuffer::new(width, height),
            colour: vec![[0.0; 3]; n],
            marker: vec![NO_MARKER; n],
        }
    }

    /// Nothing drawn: every pixel the room's.
    pub fn clear(&mut self) {
        self.depth.clear(self.width, self.height);
        self.marker.fill(NO_MARKER);
    }

    pub fn covered(&self, index: usize) -> bool {
        self.depth.as_slice()[index].is_finite()
    }

    /// The ground-truth mask: 255 where the body covers the pixel centre.
    pub fn mask(&self) -> GrayImage {
        let pixels = self
            .depth
            .as_slice()
            .iter()
            .map(|d| if d.is_finite() { 255 } else { 0 })
            .collect();
        GrayImage::from_raw(self.width, self.height, pixels)
            .unwrap_or_else(|| GrayImage::new(self.width, self.height))
    }
}

/// A marker visible in one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct VisibleMarker {
    pub id: u32,
    /// Index into the suit's marker colours.
    pub colour: usize,
    /// Projected centre, pixels.
    pub centre: Vec2,
    /// Share of the marker's square that faces the camera unoccluded and not inside another part
    /// (see [`VISIBILITY_SAMPLES`]): 4 × 4 cm of surface, however foreshortened.
    pub visible_fraction: f32,
    /// Visible pixels.
    pub visible_px: u32,
}

/// A subject's body, meshed, with the suit pattern, ready to draw from one camera.
pub struct BodyRenderer<'a> {
    pub suit: &'a SuitDefinition,
    pub body: &'a Body,
    pub camera: Camera,
    meshes: Vec<PartMesh>,
    grids: Vec<MarkerGrid>,
    /// Every marker of the suit on this body: (part index, cell).
    pub markers: Vec<(usize, MarkerCell)>,
    marker_index: HashMap<u32, u32>,
    suit_albedo: [f32; 3],
    marker_albedo: Vec<[f32; 3]>,
    skin: [f32; 3],
    shoe: [f32; 3],
}

impl<'a> BodyRenderer<'a> {
    pub fn new(
        suit: &'a SuitDefinition,
        subject: &Subject,
        body: &'a Body,
        camera: Camera,
    ) -> BodyRenderer<'a> {
        let meshes = body.parts.iter().map(|p| p.mesh(24, 4.0)).collect();
        let grids: Vec<MarkerGrid> = (0..body.parts.len())
            .map(|i| body.marker_grid(i, suit))
            .collect();
        let markers: Vec<(usize, MarkerCell)> = grids
            .iter()
            .enumerate()
            .flat_map(|(i, grid)| grid.cells().map(move |m| (i, m)))
            .collect();
        let marker_index = markers
            .iter()
            .enumerate()
            .map(|(k, (_, m))| (m.id, k as u32))
            .collect();
        BodyRenderer {
            suit,
            body,
            camera,
            meshes,
            grids,
            markers,
            marker_index,
            suit_albedo: suit.background.hsv.to_rgb(),
            marker_albedo: suit.markers.iter().map(|m| m.hsv.to_rgb()).collect(),
            skin: subject.skin,
            shoe: subject.shoe,
        }
    }

    /// Draws the body for one frame's joint world transforms into `layer`.
    pub fn draw(&self, world: &[Affine3A], lighting: &Lighting, layer: &mut BodyLayer) {
        layer.clear();
        let light = lighting.direction.normalize_or(Vec3::Y);
        let mut screen: Vec<ScreenVertex> = Vec::new();
        let mut normals: Vec<Vec3> = Vec::new();
        for ((part, mesh), grid) in self.body.parts.iter().zip(&self.meshes).zip(&self.grids) {
            let transform = world[part.joint];
            screen.clear();
            normals.clear();
            for v in &mesh.vertices {
                let p = Vec3::from(transform.transform_point3a(Vec3A::from(v.position)));
                let c = self.camera.to_camera(p);
                // Points behind the near plane get a depth below it so the triangle is skipped.
                screen.push(match self.camera.project_camera(c) {
                    Some(pr) => ScreenVertex::from(pr),
                    None => ScreenVertex {
                        x: 0.0,
                        y: 0.0,
                        depth: 0.0,
                    },
                });
                normals.push(Vec3::from(transform.matrix3 * Vec3A::from(v.normal)));
            }
            let albedo_plain = match part.material {
                Material::Suit => self.suit_albedo,
                Material::Skin => self.skin,
                Material::Shoe => self.shoe,
            };
            for tri in &mesh.triangles {
                let [a, b, c] = tri.map(|i| i as usize);
                draw_triangle(
                    &mut layer.depth,
                    [screen[a], screen[b], screen[c]],
                    Cull::Back,
                    NEAR_CM,
                    |f| {
                        let w = f.weights;
                        let (va, vb, vc) =
                            (&mesh.vertices[a], &mesh.vertices[b], &mesh.vertices[c]);
                        let mut albedo = albedo_plain;
                        let mut marker = NO_MARKER;
                        if part.material == Material::Suit {
                            let u = w[0] * va.u + w[1] * vb.u + w[2] * vc.u;
                            let s = w[0] * va.s + w[1] * vb.s + w[2] * vc.s;
                            if let Some(cell) = grid.marker_at(u, s) {
                                albedo = self.marker_albedo[cell.colour];
                                marker = self
                                    .marker_index
                                    .get(&cell.id)
                                    .copied()
                                    .unwrap_or(NO_MARKER);
                            }
                        }
                        let n = (normals[a] * w[0] + normals[b] * w[1] + normals[c] * w[2])
                            .normalize_or(Vec3::Z);
                        let diffuse = n.dot(light).max(0.0);
                        let radiance = (lighting.ambient + (1.0 - lighting.ambient) * diffuse)
                            * lighting.exposure
                            * 255.0;
                        layer.colour[f.index] = albedo.map(|c| c * radiance);
                        layer.marker[f.index] = marker;
                    },
                );
            }
        }
    }

    /// A marker's projected centre and the share of its square the camera sees: of
    /// [`VISIBILITY_SAMPLES`]² points spread evenly over the square on the body's surface, those
    /// that face the camera, lie no more than [`VISIBILITY_DEPTH_CM`] behind what `layer` drew at
    /// their pixel (not behind an arm in front, another part, or round the far side of their own
    /// limb) and not inside another part (`to_joint`: each joint's world-to-joint transform).
    /// Where two parts' capsules cross (an upper arm pressed into the chest, a bent elbow) both
    /// surfaces are drawn within a centimetre of each other along the seam, and a square of each
    /// would count as seen at nearly the same pixels; on flesh, the square under the arm is
    /// covered. `None` when its centre is behind the camera.
    fn marker_visibility(
        &self,
        (world, to_joint): (&[Affine3A], &[Affine3A]),
        part: usize,
        cell: &MarkerCell,
        layer: &BodyLayer,
    ) -> Option<(Vec2, f32)> {
        let p = &self.body.parts[part];
        let transform = world[p.joint];
        let (centre, _) = p.marker_point(self.suit, cell, (0.0, 0.0));
        let centre_world = transform.transform_point3(centre);
        // The other parts near enough to the square to hold some of it (its corners are within
        // 2.9 cm of its centre).
        let near: Vec<&BodyPart> = self
            .body
            .parts
            .iter()
            .enumerate()
            .filter(|&(k, other)| {
                k != part
                    && other.contains(
                        to_joint[other.joint].transform_point3(centre_world),
                        BURIED_SEARCH_CM,
                    )
            })
            .map(|(_, other)| other)
            .collect();
        let centre = self.camera.project(centre_world)?;
        let eye = self.camera.position();
        let n = VISIBILITY_SAMPLES;
        let across: [f32; VISIBILITY_SAMPLES] =
            std::array::from_fn(|k| (2 * k + 1) as f32 / n as f32 - 1.0);
        let mut seen = 0;
        for (point, normal) in p.marker_points(self.suit, cell, &across, &across) {
            let point = transform.transform_point3(point);
            let normal = Vec3::from(transform.matrix3 * Vec3A::from(normal));
            if (point - eye).dot(normal) >= 0.0 {
                continue;
            }
            let Some(projected) = self.camera.project(point) else {
                continue;
            };
            let (x, y) = (projected.pixel.x.floor(), projected.pixel.y.floor());
            if x < 0.0 || y < 0.0 || x >= layer.width as f32 || y >= layer.height as f32 {
                continue;
            }
            let drawn = layer.depth.get(x as u32, y as u32);
            let buried = || {
                near.iter()
                    .any(|other| other.contains(to_joint[other.joint].transform_point3(point), 0.0))
            };
            seen += (projected.depth <= drawn + VISIBILITY_DEPTH_CM && !buried()) as usize;
        }
        Some((centre.pixel, seen as f32 / (n * n) as f32))
    }

    /// Every marker with at least one visible pixel in `layer` (drawn with the same `world`).
    pub fn visible_markers(&self, world: &[Affine3A], layer: &BodyLayer) -> Vec<VisibleMarker> {
        let mut counts = vec![0u32; self.markers.len()];
        for &m in &layer.marker {
            if m != NO_MARKER {
                counts[m as usize] += 1;
            }
        }
        let to_joint: Vec<Affine3A> = world.iter().map(|t| t.inverse()).collect();
        let mut out = Vec::new();
        for (k, &count) in counts.iter().enumerate() {
            if count == 0 {
                continue;
            }
            let (part, cell) = &self.markers[k];
            let Some((centre, fraction)) =
                self.marker_visibility((world, &to_joint), *part, cell, layer)
            else {
                continue;
            };
            out.push(VisibleMarker {
                id: cell.id,
                colour: cell.colour,
                centre,
                visible_fraction: fraction,
                visible_px: count,
            });
        }
        out
    }
}

/// Camera effects applied to the composited frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sensor {
    /// Global gain (auto-exposure drift) applied to the whole frame.
    pub gain: f32,
    pub blur_sigma: f32,
    /// Read noise σ on the 0–255 scale.
    pub read_noise: f32,
    /// Shot noise: variance grows by this much per unit of signal (0–255 scale).
    pub shot_noise: f32,
}

/// Separable Gaussian blur of an RGB f32 image in place (`scratch` is reused between calls).
pub fn gaussian_blur(
    rgb: &mut [[f32; 3]],
    width: usize,
    height: usize,
    sigma: f32,
    scratch: &mut Vec<[f32; 3]>,
) {
    if sigma <= 0.0 {
        return;
    }
    let radius = (2.5 * sigma).ceil() as usize;
    let mut kernel: Vec<f32> = (0..=2 * radius)
        .map(|i| {
            let d = i as f32 - radius as f32;
            (-d * d / (2.0 * sigma * sigma)).exp()
        })
        .collect();
    let sum: f32 = kernel.iter().sum();
    kernel.iter_mut().for_each(|k| *k /= sum);
    scratch.clear();
    scratch.resize(rgb.len(), [0.0; 3]);
    let r = radius as isize;
    for y in 0..height {
        let row = &rgb[y * width..(y + 1) * width];
        for x in 0..width {
            let mut acc = [0.0f32; 3];
            for (k, weight) in kernel.iter().enumerate() {
                let xx = (x as isize + k as isize - r).clamp(0, width as isize - 1) as usize;
                let p = row[xx];
                acc[0] += p[0] * weight;
                acc[1] += p[1] * weight;
                acc[2] += p[2] * weight;
            }
            scratch[y * width + x] = acc;
        }
    }
    for y in 0..height {
        for x in 0..width {
            let mut acc = [0.0f32; 3];
            for (k, weight) in kernel.iter().enumerate() {
                let yy = (y as isize + k as isize - r).clamp(0, height as isize - 1) as usize;
                let p = scratch[yy * width + x];
                acc[0] += p[0] * weight;
                acc[1] += p[1] * weight;
                acc[2] += p[2] * weight;
            }
            rgb[y * width + x] = acc;
        }
    }
}

/// Composites `layer` over `background` (both 0–255 RGB f32), applies the sensor and quantizes.
pub fn compose(
    background: &mut [[f32; 3]],
    layer: &BodyLayer,
    sensor: &Sensor,
    rng: &mut impl Rng,
    scratch: &mut Vec<[f32; 3]>,
) -> RgbImage {
    let (width, height) = (layer.width as usize, layer.height as usize);
    for (i, pixel) in background.iter_mut().enumerate() {
        if layer.covered(i) {
            *pixel = layer.colour[i];
        }
        for c in pixel.iter_mut() {
            *c *= sensor.gain;
        }
    }
    gaussian_blur(background, width, height, sensor.blur_sigma, scratch);
    let mut out = Vec::with_capacity(width * height * 3);
    for pixel in background.iter() {
        for &c in pixel {
            let v = c.clamp(0.0, 255.0);
            let sigma = (sensor.read_noise * sensor.read_noise + sensor.shot_noise * v).sqrt();
            let noise: f32 = rng.sample(StandardNormal);
            out.push((v + sigma * noise).round().clamp(0.0, 255.0) as u8);
        }
    }
    RgbImage::from_raw(layer.width, layer.height, out)
        .unwrap_or_else(|| RgbImage::new(layer.width, layer.height))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;
    use suitcap::body::SUBJECTS;
    use suitcap::bvh::Motion;
    use suitcap::camera::Intrinsics;
    use suitcap::skeleton::{Channel, Joint, Skeleton};

    fn repo(path: &str) -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(path)
    }

    struct Fixture {
        suit: SuitDefinition,
        body: Body,
        world: Vec<Affine3A>,
        camera: Camera,
    }

    /// The run clip's frame 100 on subject 0, seen from 3.5 m in front.
    fn fixture(width: u32, height: u32) -> Fixture {
        let suit = SuitDefinition::load_dir(&repo("suits/default")).expect("suit");
        let motion = Motion::load(&repo("tests/data/mocap/cmu_09_01_run.bvh")).expect("clip");
        let subject = &SUBJECTS[0];
        let skeleton = subject.scale_skeleton(&motion.skeleton);
        let body = Body::new(subject, &skeleton).expect("body");
        let mut frame = motion.frame(100).to_vec();
        subject.scale_root_translation(&motion.skeleton, &mut frame);
        let mut world = Vec::new();
        skeleton.forward_kinematics(&frame, &mut world);
        let hip = Vec3::from(world[0].translation);
        let camera = Camera::look_at(
            Intrinsics::from_fov(width, height, 55.0),
            hip + Vec3::new(0.0, 20.0, 350.0),
            hip,
            Vec3::Y,
        );
        Fixture {
            suit,
            body,
            world,
            camera,
        }
    }

    /// The fixture's body drawn by a renderer for the first subject, into a layer of the
    /// camera's size.
    fn drawn(f: &Fixture) -> (BodyRenderer<'_>, BodyLayer) {
        let renderer = BodyRenderer::new(&f.suit, &SUBJECTS[0], &f.body, f.camera);
        let mut layer = BodyLayer::new(f.camera.intrinsics.width, f.camera.intrinsics.height);
        renderer.draw(&f.world, &lighting(), &mut layer);
        (renderer, layer)
    }

    fn lighting() -> Lighting {
        Lighting {
            direction: Vec3::new(0.3, 1.0, 0.5).normalize(),
            ambient: 0.5,
            exposure: 1.0,
        }
    }

    /// Möller–Trumbore: distance along the ray to the triangle, if hit.
    fn ray_triangle(origin: Vec3, dir: Vec3, [a, b, c]: [Vec3; 3]) -> Option<f32> {
        let (e1, e2) = (b - a, c - a);
        let p = dir.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-9 {
            return None;
        }
        let t0 = origin - a;
        let u = t0.dot(p) / det;
        let q = t0.cross(e1);
        let v = dir.dot(q) / det;
        let t = e2.dot(q) / det;
        (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0).then_some(t)
    }

    #[test]
    fn mask_equals_the_pixels_a_ray_cast_finds_on_the_body() {
        let (w, h) = (120, 90);
        let f = fixture(w, h);
        let (_, layer) = drawn(&f);
        let mask = layer.mask();
        // Independent check: cast a ray through every pixel centre against every body triangle.
        let triangles: Vec<[Vec3; 3]> = f
            .body
            .parts
            .iter()
            .zip(f.body.parts.iter().map(|p| p.mesh(24, 4.0)))
            .flat_map(|(part, mesh)| {
                let t = f.world[part.joint];
                mesh.triangles
                    .iter()
                    .map(|tri| tri.map(|i| t.transform_point3(mesh.vertices[i as usize].position)))
                    .collect::<Vec<_>>()
            })
            .collect();
        let origin = f.camera.position();
        let (mut covered, mut mismatches) = (0, 0);
        for y in 0..h {
            for x in 0..w {
                let target = f
                    .camera
                    .unproject(Vec2::new(x as f32 + 0.5, y as f32 + 0.5), 100.0);
                let dir = (target - origin).normalize();
                let hit = triangles
                    .iter()
                    .any(|&t| ray_triangle(origin, dir, t).is_some());
                covered += hit as usize;
                if hit != (mask.get_pixel(x, y).0[0] == 255) {
                    mismatches += 1;
                }
            }
        }
        assert!(covered > 250, "the body covers {covered} pixels");
        assert!(mismatches <= 2, "{mismatches} of {covered} pixels differ");
    }

    #[test]
    fn a_marker_appears_at_its_projected_place_in_its_colour() {
        let (w, h) = (640, 480);
        let f = fixture(w, h);
        let (renderer, layer) = drawn(&f);
        let visible = renderer.visible_markers(&f.world, &layer);
        let mut checked = 0;
        for m in visible.iter().filter(|m| m.visible_fraction > 0.95) {
            let k = renderer
                .markers
                .iter()
                .position(|(_, c)| c.id == m.id)
                .expect("known marker") as u32;
            let (mut sum, mut n) = (Vec2::ZERO, 0.0f32);
            for (i, &id) in layer.marker.iter().enumerate() {
                if id == k {
                    sum += Vec2::new((i % w as usize) as f32 + 0.5, (i / w as usize) as f32 + 0.5);
                    n += 1.0;
                }
            }
            if n < 16.0 {
                // Seen at a grazing angle (a frontal square is about 40 px here): the centroid of a
                // square wrapped round a limb drifts from its projected centre by up to half its
                // side (0.45·√area measured on a 12 px marker of the forearm).
                continue;
            }
            checked += 1;
            // The centroid of the marker's own pixels is its projected centre, up to the asymmetry of a
            // square wrapped around a limb seen obliquely and pixel quantization: within 0.3·√area
            // pixels, a third of its side (a marker in the wrong cell is a whole 7 cm pitch off).
            let tolerance = (0.3 * n.sqrt()).max(1.0);
            assert!(
                (sum / n).distance(m.centre) < tolerance,
                "marker {} centroid {:?} vs {:?} ({n} px)",
                m.id,
                sum / n,
                m.centre
            );
            // The pixel under the projected centre has the marker's hue.
            let index = m.centre.y as usize * w as usize + m.centre.x as usize;
            let hsv = suitcap::colour::Hsv::from_rgb(layer.colour[index].map(|c| c / 255.0));
            let expected = f.suit.markers[m.colour].hsv.hue;
            assert!(
                suitcap::colour::hue_distance(hsv.hue, expected) < 5.0,
                "marker {}: hue {} vs {expected}",
                m.id,
                hsv.hue
            );
        }
        assert!(
            checked > 20,
            "{checked} whole markers of at least 16 pixels"
        );
    }

    #[test]
    fn a_marker_facing_the_camera_is_wholly_visible_and_one_on_the_outline_about_half() {
        let (w, h) = (640, 480);
        let f = fixture(w, h);
        let (renderer, layer) = drawn(&f);
        let eye = f.camera.position();
        let (mut facing, mut outline) = (0, 0);
        for m in renderer.visible_markers(&f.world, &layer) {
            let k = renderer
                .markers
                .iter()
                .position(|(_, c)| c.id == m.id)
                .expect("known marker");
            let (part, cell) = &renderer.markers[k];
            let p = &f.body.parts[*part];
            let transform = f.world[p.joint];
            let at = |a: f32, b: f32| {
                let (point, normal) = p.marker_point(&f.suit, cell, (a, b));
                let point = transform.transform_point3(point);
                let normal = Vec3::from(transform.matrix3 * Vec3A::from(normal));
                (point, normal.dot((eye - point).normalize()))
            };
            // The pixels of its square seen face-on (shoelace over its projected corners).
            let corners = [(-1.0, -1.0), (-1.0, 1.0), (1.0, 1.0), (1.0, -1.0)]
                .map(|(a, b)| f.camera.project(at(a, b).0).expect("in front").pixel);
            let square = (0..4)
                .map(|i| corners[i].perp_dot(corners[(i + 1) % 4]))
                .sum::<f32>()
                .abs()
                / 2.0;
            let (_, cos) = at(0.0, 0.0);
            if cos > 0.9 && m.visible_px as f32 >= 0.9 * square {
                // Square to the camera, and as many pixels of its colour as its square covers.
                facing += 1;
                assert!(
                    m.visible_fraction > 0.95,
                    "marker {}: {}",
                    m.id,
                    m.visible_fraction
                );
            } else if cos.abs() < 0.1 {
                // Its centre on the limb's outline: about half of it lies round the far side.
                outline += 1;
                assert!(
                    (0.2..=0.8).contains(&m.visible_fraction),
                    "marker {}: {}",
                    m.id,
                    m.visible_fraction
                );
            }
        }
        assert!(
            facing > 10 && outline > 3,
            "{facing} facing, {outline} on the outline"
        );
    }

    #[test]
    fn a_marker_inside_another_part_is_not_seen_even_with_nothing_drawn_in_front() {
        // A suit cylinder (radius 10 cm, 30 cm along +Y) seen from +Z with an empty depth layer, so
        // only the test against other parts can hide a sample. A bar of radius 5 cm along X
        // through the centre of a marker facing the camera covers its whole square (its corners
        // lie within 2.1 cm of the bar's axis): none of it is seen; the marker two rows (14 cm)
        // below, at least 12 cm from the bar's axis: all of it is seen.
        let suit = SuitDefinition::load_dir(&repo("suits/default")).expect("suit");
        let part = |name, start, end, radius| BodyPart {
            name,
            joint: 0,
            start,
            end,
            radii_start: Vec2::splat(radius),
            radii_end: Vec2::splat(radius),
            width_axis: Vec3::X,
            cap: 1.0,
            patterned_caps: [true, true],
            material: Material::Suit,
            surface: 0,
        };
        let cylinder = part("cylinder", Vec3::ZERO, Vec3::Y * 30.0, 10.0);
        // The markers of the column facing 22.5° right of the camera, at heights 1, 8, 15, 22 and
        // 29 cm: the one at 15 and the one two rows (14 cm) below it.
        let column: Vec<(MarkerCell, Vec3)> = cylinder
            .marker_grid(&suit)
            .cells()
            .filter_map(|cell| {
                let (point, normal) = cylinder.marker_point(&suit, &cell, (0.0, 0.0));
                (normal.z > 0.9 && normal.x > 0.0).then_some((cell, point))
            })
            .collect();
        let at = |y: f32| {
            *column
                .iter()
                .find(|(_, p)| (p.y - y).abs() < 0.5)
                .expect("a marker at that height")
        };
        let ((covered, centre), (clear, _)) = (at(15.0), at(1.0));
        let bar = part("bar", centre - Vec3::X * 20.0, centre + Vec3::X * 20.0, 5.0);
        let skeleton = Skeleton::new(vec![Joint {
            name: "world".into(),
            parent: None,
            offset: Vec3::ZERO,
            channels: vec![Channel::Xposition, Channel::Yposition, Channel::Zposition],
            first_channel: 0,
            end_site: None,
        }])
        .expect("skeleton");
        let body = Body::from_parts(vec![cylinder, bar], &skeleton);
        let camera = Camera::look_at(
            Intrinsics::from_fov(320, 240, 40.0),
            Vec3::new(0.0, 15.0, 300.0),
            Vec3::new(0.0, 15.0, 0.0),
            Vec3::Y,
        );
        let renderer = BodyRenderer::new(&suit, &SUBJECTS[0], &body, camera);
        let layer = BodyLayer::new(320, 240);
        let world = [Affine3A::IDENTITY];
        let seen = |cell: &MarkerCell| {
            renderer
                .marker_visibility((&world, &world), 0, cell, &layer)
                .expect("in front of the camera")
                .1
        };
        assert_eq!(seen(&covered), 0.0);
        assert_eq!(seen(&clear), 1.0);
    }

    #[test]
    fn blur_keeps_a_flat_image_flat_and_spreads_an_impulse() {
        let mut flat = vec![[100.0; 3]; 25];
        let mut scratch = Vec::new();
        gaussian_blur(&mut flat, 5, 5, 0.8, &mut scratch);
        assert!(flat.iter().all(|p| (p[0] - 100.0).abs() < 1e-3));
        let mut impulse = vec![[0.0; 3]; 25];
        impulse[12] = [100.0; 3];
        gaussian_blur(&mut impulse, 5, 5, 0.8, &mut scratch);
        let total: f32 = impulse.iter().map(|p| p[0]).sum();
        assert!((total - 100.0).abs() < 1e-2);
        assert!(impulse[12][0] < 100.0 && impulse[11][0] > 0.0 && impulse[11][0] == impulse[13][0]);
    }
}
