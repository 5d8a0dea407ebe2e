//! Garment rendering from the real camera's viewpoint: the simulated garment becomes a premultiplied
//! RGBA layer, transparent wherever no garment shows, which [`crate::composite`] blends over the video
//! frame.
//!
//! One frame, in [`GarmentRenderer::render`]:
//!
//! 1. Project the garment's vertices with the real [`Camera`]. The layer covers only the bounding
//!    rectangle of the projection (plus a pixel for the edge fins), so the cost follows the garment's
//!    size on screen, not the frame's.
//! 2. Area-weighted vertex normals (the unnormalized face normals summed at each vertex), lit per
//!    vertex for both sides of the cloth with a directional light plus ambient ([`Light`]), and
//!    interpolated across each triangle (Gouraud shading, smooth at the garment's ~2 cm edges).
//! 3. Rasterize with [`crate::raster::draw_triangle`] and one z-buffer, band by band ([`band`]):
//!    the garment's front faces in [`GarmentStyle::front`]; then the body's collision capsules
//!    *depth-only*, each tessellated to a small closed mesh ([`capsule_mesh`]) with its radii reduced
//!    by [`RenderSettings::capsule_inset`] so cloth lying on the body wins the depth test — where a
//!    capsule is nearer than the cloth (an arm in front) it erases the cloth's pixel and the real arm
//!    of the camera image shows — given the frame's mask of the person
//!    ([`GarmentRenderer::render_over`]), only where the camera sees the person, since the capsules
//!    are an estimate and the room has no arm to show; then the back faces (the garment's inside,
//!    seen through a neckline or under a hem) in [`GarmentStyle::back`], both sides drawn
//!    ([`crate::raster::Cull::None`]).
//!    Per 8 × 8 tile farthest depths ([`occlusion`]) skip capsules hidden inside the garment and back
//!    faces behind the front cloth or the body without walking their pixels; the result is the same
//!    as drawing everything in any order.
//! 4. Antialias the silhouette with *fins* ([`silhouette`]): a 0.75-pixel-wide quad outside every
//!    silhouette edge, depth-tested like the garment, blending the edge's colour with the pixel's
//!    coverage. Only the pixels along the outline pay for it, and occlusion by the body and by nearer
//!    cloth stays correct; edges where a capsule cuts the cloth stay aliased (the real arm's own
//!    outline is there anyway).
//!
//! With [`RenderSettings::parallel`] the bands render concurrently on the rayon pool. All buffers
//! live in the renderer and are reused, so a steady stream of frames allocates nothing. Garment
//! triangles with a vertex nearer than [`RenderSettings::near`] are skipped, not clipped.

pub mod band;
pub mod capsule_mesh;
pub mod occlusion;
pub mod silhouette;

use glam::{Vec2, Vec3};
use rayon::prelude::*;
use tiny_skia::{Pixmap, PixmapRef};

use crate::camera::Camera;
use crate::cloth::Capsule;
use crate::mask::Mask;
use crate::raster::ScreenVertex;
use band::{Band, CapsuleSpan, PersonPixels, Scene};
use capsule_mesh::CapsuleMesh;
use silhouette::{EdgeTable, Facing};

/// A directional light plus ambient. Intensity = `ambient + diffuse · max(0, n · l)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Direction *towards* the light in camera coordinates (x right, y down, z forward), so the same
    /// setting lights the garment alike from any camera placement; need not be unit length.
    pub direction: Vec3,
    pub ambient: f32,
    pub diffuse: f32,
}

impl Default for Light {
    /// From the upper left, a little behind the camera.
    fn default() -> Light {
        Light {
            direction: Vec3::new(-0.35, -0.6, -1.0),
            ambient: 0.35,
            diffuse: 0.75,
        }
    }
}

/// The garment's two colours: outside (faces towards the camera) and inside (faces away).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GarmentStyle {
    pub front: [u8; 3],
    pub back: [u8; 3],
}

impl Default for GarmentStyle {
    fn default() -> GarmentStyle {
        GarmentStyle {
            front: [52, 96, 200],
            back: [200, 160, 90],
        }
    }
}

/// What the renderer draws and how.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    pub light: Light,
    pub style: GarmentStyle,
    /// How much the capsule radii shrink for the depth pass (world units, cm).
    pub capsule_inset: f32,
    /// Capsule tessellation: vertices around the axis, and rings on each end sphere.
    pub capsule_segments: u32,
    pub capsule_rings: u32,
    /// Triangles with a vertex nearer than this (cm along the optical axis) are not drawn.
    pub near: f32,
    /// Antialias the garment's silhouette edges.
    pub antialias: bool,
    /// Render horizontal bands of the layer in parallel on the rayon pool.
    pub parallel: bool,
}

impl Default for RenderSettings {
    fn default() -> RenderSettings {
        RenderSettings {
            light: Light::default(),
            style: GarmentStyle::default(),
            capsule_inset: 0.5,
            capsule_segments: 12,
            capsule_rings: 3,
            near: 1.0,
            antialias: true,
            parallel: false,
        }
    }
}

/// A rectangle of frame pixels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PixelRect {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

/// The rendered garment: premultiplied RGBA over a rectangle of the frame; every pixel outside the
/// rectangle is fully transparent.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GarmentLayer {
    frame_width: u32,
    frame_height: u32,
    /// Zero-sized when nothing is drawn.
    rect: PixelRect,
    /// `rect.width × rect.height` pixels, row-major, premultiplied RGBA.
    data: Vec<u8>,
}

impl GarmentLayer {
    /// A transparent layer for a frame of the given size.
    pub fn empty(frame_width: u32, frame_height: u32) -> GarmentLayer {
        GarmentLayer {
            frame_width,
            frame_height,
            ..GarmentLayer::default()
        }
    }

    /// A layer from premultiplied RGBA pixels covering `rect`; `None` if `rect` leaves the frame or
    /// `data` is not `4 · width · height` bytes.
    pub fn from_premultiplied(
        frame_width: u32,
        frame_height: u32,
        rect: PixelRect,
        data: Vec<u8>,
    ) -> Option<GarmentLayer> {
        let fits = rect.x.checked_add(rect.width)? <= frame_width
            && rect.y.checked_add(rect.height)? <= frame_height;
        (fits && data.len() == rect.width as usize * rect.height as usize * 4).then_some(
            GarmentLayer {
                frame_width,
                frame_height,
                rect,
                data,
            },
        )
    }

    pub fn frame_size(&self) -> (u32, u32) {
        (self.frame_width, self.frame_height)
    }

    /// The rectangle holding the drawn pixels; `None` when the layer is empty.
    pub fn bounds(&self) -> Option<PixelRect> {
        (self.rect.width > 0 && self.rect.height > 0).then_some(self.rect)
    }

    /// The pixels of [`GarmentLayer::bounds`], row-major premultiplied RGBA.
    pub fn data(&self) -> &[u8] {
        &self.data
    }

    /// The pixels of [`GarmentLayer::bounds`] as a tiny-skia pixmap.
    pub fn pixmap(&self) -> Option<PixmapRef<'_>> {
        let rect = self.bounds()?;
        PixmapRef::from_bytes(&self.data, rect.width, rect.height)
    }

    /// Premultiplied RGBA at frame pixel (x, y); transparent outside the bounds.
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 4] {
        let r = self.rect;
        if x < r.x || y < r.y || x - r.x >= r.width || y - r.y >= r.height {
            return [0; 4];
        }
        let i = 4 * ((y - r.y) as usize * r.width as usize + (x - r.x) as usize);
        [
            self.data[i],
            self.data[i + 1],
            self.data[i + 2],
            self.data[i + 3],
        ]
    }

    /// The layer as a whole-frame pixmap (for inspection and tests; allocates).
    pub fn to_frame_pixmap(&self) -> Option<Pixmap> {
        let mut out = Pixmap::new(self.frame_width, self.frame_height)?;
        if let Some(src) = self.pixmap() {
            let paint = tiny_skia::PixmapPaint {
                blend_mode: tiny_skia::BlendMode::Source,
                ..Default::default()
            };
            out.draw_pixmap(
                self.rect.x as i32,
                self.rect.y as i32,
                src,
                &paint,
                tiny_skia::Transform::identity(),
                None,
            );
        }
        Some(out)
    }

    /// Resizes to `rect` (or empty) and clears to transparent, keeping the allocation.
    fn reset(&mut self, frame_width: u32, frame_height: u32, rect: Option<PixelRect>) {
        self.frame_width = frame_width;
        self.frame_height = frame_height;
        self.rect = rect.unwrap_or_default();
        self.data.clear();
        self.data
            .resize(self.rect.width as usize * self.rect.height as usize * 4, 0);
    }
}

/// Renders garments frame after frame, reusing its buffers.
#[derive(Clone, Debug)]
pub struct GarmentRenderer {
    settings: RenderSettings,
    capsule_mesh: CapsuleMesh,
    layer: GarmentLayer,
    /// Garment vertices in layer pixel coordinates (NaN when not drawable).
    screen: Vec<ScreenVertex>,
    normals: Vec<Vec3>,
    /// Per vertex: lit intensity of the outside and of the inside.
    intensity: Vec<[f32; 2]>,
    facing: Vec<Facing>,
    edges: EdgeTable,
    capsule_world: Vec<Vec3>,
    /// The capsules in view, tessellated and projected, one after the other …
    capsule_screen: Vec<ScreenVertex>,
    /// … where each starts and how many cone bands it has.
    capsule_spans: Vec<CapsuleSpan>,
    bands: Vec<Band>,
}

impl Default for GarmentRenderer {
    fn default() -> GarmentRenderer {
        GarmentRenderer::new(RenderSettings::default())
    }
}

impl GarmentRenderer {
    pub fn new(settings: RenderSettings) -> GarmentRenderer {
        GarmentRenderer {
            capsule_mesh: CapsuleMesh::new(settings.capsule_segments, settings.capsule_rings),
            settings,
            layer: GarmentLayer::default(),
            screen: Vec::new(),
            normals: Vec::new(),
            intensity: Vec::new(),
            facing: Vec::new(),
            edges: EdgeTable::default(),
            capsule_world: Vec::new(),
            capsule_screen: Vec::new(),
            capsule_spans: Vec::new(),
            bands: Vec::new(),
        }
    }

    pub fn settings(&self) -> &RenderSettings {
        &self.settings
    }

    pub fn set_settings(&mut self, settings: RenderSettings) {
        if (settings.capsule_segments, settings.capsule_rings)
            != (self.settings.capsule_segments, self.settings.capsule_rings)
        {
            self.capsule_mesh = CapsuleMesh::new(settings.capsule_segments, settings.capsule_rings);
        }
        self.settings = settings;
    }

    /// The layer of the last [`GarmentRenderer::render`].
    pub fn layer(&self) -> &GarmentLayer {
        &self.layer
    }

    /// Renders the garment (`vertices` in world cm, `triangles` wound with `(b − a) × (c − a)`
    /// outward) as seen by `camera`, hidden where the body's `capsules` are in front. Triangles with an
    /// index out of range are skipped.
    pub fn render(
        &mut self,
        camera: &Camera,
        vertices: &[Vec3],
        triangles: &[[u32; 3]],
        capsules: &[Capsule],
    ) -> &GarmentLayer {
        self.render_over(camera, vertices, triangles, capsules, None)
    }

    /// [`GarmentRenderer::render`] over a frame in which the camera sees the person where `person`
    /// (a mask of the frame's size) is set: the capsules hide the garment only there. The body the
    /// garment is simulated on is estimated; where an arm of it strays off the real one onto the
    /// room, hiding the garment would show the room through a hole, with no arm in it. A mask of
    /// another size is ignored.
    pub fn render_over(
        &mut self,
        camera: &Camera,
        vertices: &[Vec3],
        triangles: &[[u32; 3]],
        capsules: &[Capsule],
        person: Option<&Mask>,
    ) -> &GarmentLayer {
        let (width, height) = (camera.intrinsics.width, camera.intrinsics.height);
        let near = self.settings.near;
        project_vertices(camera, vertices, near, &mut self.screen);
        let Some(rect) = layer_bounds(&self.screen, width, height, 1) else {
            self.layer.reset(width, height, None);
            return &self.layer;
        };
        let origin = Vec2::new(rect.x as f32, rect.y as f32);
        for v in &mut self.screen {
            v.x -= origin.x;
            v.y -= origin.y;
        }
        self.layer.reset(width, height, Some(rect));

        self.project_capsules(camera, capsules, origin, rect);
        vertex_normals(vertices, triangles, &mut self.normals);
        let light = &self.settings.light;
        let towards_light = camera.rotation.transpose() * light.direction.normalize_or_zero();
        vertex_intensity(
            &self.normals,
            towards_light,
            light.ambient,
            light.diffuse,
            &mut self.intensity,
        );
        triangle_facing(&self.screen, triangles, near, &mut self.facing);
        if self.settings.antialias {
            self.edges.update(triangles);
        }

        let style = self.settings.style;
        let scene = Scene {
            screen: &self.screen,
            triangles,
            facing: &self.facing,
            intensity: &self.intensity,
            colours: [style.front, style.back].map(|c| c.map(f32::from)),
            capsule_mesh: &self.capsule_mesh,
            capsule_screen: &self.capsule_screen,
            capsule_spans: &self.capsule_spans,
            edges: if self.settings.antialias {
                self.edges.edges()
            } else {
                &[]
            },
            near,
            person: person
                .filter(|m| (m.width(), m.height()) == (width, height))
                .map(|mask| PersonPixels {
                    mask,
                    origin: (rect.x, rect.y),
                }),
        };
        let threads = if self.settings.parallel {
            rayon::current_num_threads().max(1)
        } else {
            1
        };
        let rows = band_rows(rect.height, threads);
        let band_bytes = rows as usize * rect.width as usize * 4;
        let count = self.layer.data.len().div_ceil(band_bytes);
        if self.bands.len() < count {
            self.bands.resize_with(count, Band::default);
        }
        if count > 1 {
            self.layer
                .data
                .par_chunks_mut(band_bytes)
                .zip(self.bands.par_iter_mut())
                .enumerate()
                .for_each(|(b, (pixels, band))| {
                    band.render(&scene, b as u32 * rows, rect.width, pixels)
                });
        } else {
            let work = self.layer.data.chunks_mut(band_bytes).zip(&mut self.bands);
            for (b, (pixels, band)) in work.enumerate() {
                band.render(&scene, b as u32 * rows, rect.width, pixels);
            }
        }
        &self.layer
    }

    /// Tessellates and projects the inset capsules whose projection reaches the layer.
    fn project_capsules(
        &mut self,
        camera: &Camera,
        capsules: &[Capsule],
        origin: Vec2,
        rect: PixelRect,
    ) {
        let near = self.settings.near;
        let (w, h) = (rect.width as f32, rect.height as f32);
        self.capsule_screen.clear();
        self.capsule_spans.clear();
        for capsule in capsules {
            let Some(cone_segments) = self.capsule_mesh.vertices(
                capsule,
                self.settings.capsule_inset,
                &mut self.capsule_world,
            ) else {
                continue;
            };
            let start = self.capsule_screen.len();
            self.capsule_screen.extend(
                self.capsule_world
                    .iter()
                    .map(|&p| to_screen(camera, p, near, origin)),
            );
            let in_view = screen_extent(&self.capsule_screen[start..])
                .is_some_and(|(lo, hi)| hi.x >= 0.0 && hi.y >= 0.0 && lo.x <= w && lo.y <= h);
            if in_view {
                self.capsule_spans.push(CapsuleSpan {
                    start,
                    cone_segments,
                });
            } else {
                self.capsule_screen.truncate(start);
            }
        }
    }
}

/// Rows per band: the layer's height split over `threads`, at least 32 rows a band.
fn band_rows(height: u32, threads: usize) -> u32 {
    height.div_ceil(threads.max(1) as u32).max(32).max(1)
}

/// World point → layer pixel coordinates (`origin` = the layer's top-left frame pixel); NaN when
/// nearer than `near` or behind the camera.
fn to_screen(camera: &Camera, p: Vec3, near: f32, origin: Vec2) -> ScreenVertex {
    match camera.project(p) {
        Some(q) if q.depth >= near && q.pixel.is_finite() => ScreenVertex {
            x: q.pixel.x - origin.x,
            y: q.pixel.y - origin.y,
            depth: q.depth,
        },
        _ => ScreenVertex {
            x: f32::NAN,
            y: f32::NAN,
            depth: f32::NAN,
        },
    }
}

/// Projects `vertices` into frame pixel coordinates (NaN where not drawable) into `out`.
pub fn project_vertices(
    camera: &Camera,
    vertices: &[Vec3],
    near: f32,
    out: &mut Vec<ScreenVertex>,
) {
    out.clear();
    out.extend(
        vertices
            .iter()
            .map(|&p| to_screen(camera, p, near, Vec2::ZERO)),
    );
}

/// Smallest and largest pixel position of the drawable vertices.
fn screen_extent(screen: &[ScreenVertex]) -> Option<(Vec2, Vec2)> {
    let mut lo = Vec2::splat(f32::INFINITY);
    let mut hi = Vec2::splat(f32::NEG_INFINITY);
    for v in screen.iter().filter(|v| v.depth.is_finite()) {
        lo = lo.min(Vec2::new(v.x, v.y));
        hi = hi.max(Vec2::new(v.x, v.y));
    }
    (lo.x <= hi.x).then_some((lo, hi))
}

/// The frame rectangle covering the drawable projected vertices plus `margin` pixels, clipped to the
/// frame; `None` if it is empty.
pub fn layer_bounds(
    screen: &[ScreenVertex],
    width: u32,
    height: u32,
    margin: u32,
) -> Option<PixelRect> {
    let (lo, hi) = screen_extent(screen)?;
    let m = margin as f32;
    let x0 = (lo.x.floor() - m).clamp(0.0, width as f32) as u32;
    let y0 = (lo.y.floor() - m).clamp(0.0, height as f32) as u32;
    let x1 = (hi.x.ceil() + m).clamp(0.0, width as f32) as u32;
    let y1 = (hi.y.ceil() + m).clamp(0.0, height as f32) as u32;
    (x1 > x0 && y1 > y0).then_some(PixelRect {
        x: x0,
        y: y0,
        width: x1 - x0,
        height: y1 - y0,
    })
}

/// Area-weighted vertex normals: each triangle adds `(b − a) × (c − a)` (twice its area times its unit
/// normal) to its three vertices; the sums are normalized (zero for unused or degenerate vertices).
/// Triangles with an index out of range are skipped.
pub fn vertex_normals(vertices: &[Vec3], triangles: &[[u32; 3]], out: &mut Vec<Vec3>) {
    out.clear();
    out.resize(vertices.len(), Vec3::ZERO);
    for tri in triangles {
        let [a, b, c] = tri.map(|i| i as usize);
        let (Some(&pa), Some(&pb), Some(&pc)) = (vertices.get(a), vertices.get(b), vertices.get(c))
        else {
            continue;
        };
        let n = (pb - pa).cross(pc - pa);
        out[a] += n;
        out[b] += n;
        out[c] += n;
    }
    for n in out.iter_mut() {
        *n = n.normalize_or_zero();
    }
}

/// Per vertex, the lit intensity of the outside (normal `n`) and of the inside (normal `−n`) under a
/// light in direction `towards_light` (unit, same frame as the normals).
pub fn vertex_intensity(
    normals: &[Vec3],
    towards_light: Vec3,
    ambient: f32,
    diffuse: f32,
    out: &mut Vec<[f32; 2]>,
) {
    out.clear();
    out.extend(normals.iter().map(|n| {
        let d = n.dot(towards_light);
        [
            ambient + diffuse * d.max(0.0),
            ambient + diffuse * (-d).max(0.0),
        ]
    }));
}

/// Facing of every triangle (hidden when an index is out of range).
pub fn triangle_facing(
    screen: &[ScreenVertex],
    triangles: &[[u32; 3]],
    near: f32,
    out: &mut Vec<Facing>,
) {
    out.clear();
    out.extend(triangles.iter().map(|tri| {
        match (
            screen.get(tri[0] as usize),
            screen.get(tri[1] as usize),
            screen.get(tri[2] as usize),
        ) {
            (Some(&a), Some(&b), Some(&c)) => silhouette::facing([a, b, c], near),
            _ => Facing::Hidden,
        }
    }));
}

/// `colour · intensity`, rounded and clamped to 0..=255.
#[inline]
pub fn shade(colour: [f32; 3], intensity: f32) -> [u8; 3] {
    // Written out per channel (`colour.map(..)` was compiled as an out-of-line call per pixel, a
    // fifth of the render + composite benchmark's time); `as u8` saturates (below 0 and NaN give
    // 0, above 255 gives 255), which is the clamp.
    let channel = |c: f32| (c * intensity + 0.5) as u8;
    [channel(colour[0]), channel(colour[1]), channel(colour[2])]
}

/// Source-over of an opaque colour at `coverage` (0..=1) onto a premultiplied RGBA pixel.
#[inline]
pub fn blend_opaque_over(dst: &mut [u8], rgb: [u8; 3], coverage: f32) {
    let a = (coverage.clamp(0.0, 1.0) * 255.0 + 0.5) as u32;
    let keep = 255 - a;
    for (d, s) in dst.iter_mut().zip([rgb[0], rgb[1], rgb[2], 255]) {
        *d = ((u32::from(s) * a + u32::from(*d) * keep + 127) / 255) as u8;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Intrinsics;

    /// A 64 × 64 camera at the origin looking along +Z (world X to the image's left, Y up), fx = 32.
    fn camera() -> Camera {
        Camera::look_at(
            Intrinsics::from_fov(64, 64, 90.0),
            Vec3::ZERO,
            Vec3::new(0.0, 0.0, 100.0),
            Vec3::Y,
        )
    }

    /// Flat lighting, so a pixel's colour is exactly its side's style colour.
    fn flat() -> RenderSettings {
        RenderSettings {
            light: Light {
                direction: Vec3::Z,
                ambient: 1.0,
                diffuse: 0.0,
            },
            ..RenderSettings::default()
        }
    }

    /// A triangle at depth `z` around the optical axis, ±`s` cm; wound so its outward normal points
    /// at the camera (front) or away (back).
    fn triangle(z: f32, s: f32, front: bool) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let v = vec![
            Vec3::new(-s, -s, z),
            Vec3::new(s, -s, z),
            Vec3::new(0.0, s, z),
        ];
        // (b − a) × (c − a) = (2s, 0, 0) × (s, 2s, 0) = (0, 0, 4s²): +Z, away from the camera.
        let t = if front { [0, 2, 1] } else { [0, 1, 2] };
        (v, vec![t])
    }

    /// A bar along world X at depth 100 cm, 10 cm thick: covers the image centre.
    fn bar() -> Capsule {
        Capsule {
            a: Vec3::new(-60.0, 0.0, 100.0),
            b: Vec3::new(60.0, 0.0, 100.0),
            radius_a: 10.0,
            radius_b: 10.0,
        }
    }

    #[test]
    fn a_capsule_hides_the_garment_only_where_the_camera_sees_the_person() {
        let mut r = GarmentRenderer::new(flat());
        // At row 32 the triangle is ±20 cm wide at 150 cm (fx 32): about columns 28..36, behind
        // the bar (rows 29..35).
        let (v, t) = triangle(150.0, 40.0, true);
        // The person seen in the frame's left half only (columns 0..32).
        let mut person = Mask::empty(64, 64);
        for y in 0..64 {
            for x in 0..32 {
                person.pixels_mut()[y * 64 + x] = true;
            }
        }
        let layer = r.render_over(&camera(), &v, &t, &[bar()], Some(&person));
        let (left, right) = (layer.pixel(30, 32), layer.pixel(34, 32));
        // Left of column 32 the bar hides the triangle; right of it the bar is an estimate over
        // the room, and the triangle shows.
        assert_eq!((left[3], right[3]), (0, 255));
        // Nobody seen: the bar hides nothing; a mask of another size is ignored.
        let nobody = Mask::empty(64, 64);
        let layer = r.render_over(&camera(), &v, &t, &[bar()], Some(&nobody));
        assert_eq!(layer.pixel(32, 32)[3], 255);
        let other = Mask::empty(32, 32);
        let layer = r.render_over(&camera(), &v, &t, &[bar()], Some(&other));
        assert_eq!(layer.pixel(34, 32)[3], 0);
    }

    #[test]
    fn a_triangle_behind_a_capsule_is_hidden_and_one_in_front_is_drawn() {
        let mut r = GarmentRenderer::new(flat());
        let (v, t) = triangle(150.0, 5.0, true);
        // Without the body the triangle covers the centre pixel …
        assert_eq!(r.render(&camera(), &v, &t, &[]).pixel(32, 32)[3], 255);
        // … behind the capsule it is hidden entirely: the layer stays transparent.
        let layer = r.render(&camera(), &v, &t, &[bar()]);
        let bounds = layer.bounds().expect("the triangle is in view");
        assert!(layer.data().iter().all(|&b| b == 0), "{bounds:?}");
        // In front of the capsule it is drawn.
        let (v, t) = triangle(80.0, 5.0, true);
        let layer = r.render(&camera(), &v, &t, &[bar()]);
        assert_eq!(layer.pixel(32, 32), [52, 96, 200, 255]);
    }

    #[test]
    fn cloth_lying_on_the_capsule_wins_the_depth_test() {
        // A patch exactly on the capsule's surface (depth 90 = 100 − radius) is drawn thanks to the inset.
        let mut r = GarmentRenderer::new(flat());
        let (v, t) = triangle(90.0, 3.0, true);
        assert_eq!(r.render(&camera(), &v, &t, &[bar()]).pixel(32, 32)[3], 255);
    }

    #[test]
    fn facing_picks_the_front_or_back_colour() {
        let mut r = GarmentRenderer::new(flat());
        for (front, colour) in [(true, [52, 96, 200]), (false, [200, 160, 90])] {
            let (v, t) = triangle(100.0, 20.0, front);
            let px = r.render(&camera(), &v, &t, &[]).pixel(32, 32);
            assert_eq!(
                px,
                [colour[0], colour[1], colour[2], 255],
                "front = {front}"
            );
        }
    }

    #[test]
    fn the_lit_side_is_brighter() {
        let settings = RenderSettings {
            light: Light {
                direction: Vec3::new(0.0, 0.0, -1.0), // straight from the camera
                ambient: 0.2,
                diffuse: 0.8,
            },
            ..RenderSettings::default()
        };
        let mut r = GarmentRenderer::new(settings);
        let (v, t) = triangle(100.0, 20.0, true);
        let px = r.render(&camera(), &v, &t, &[]).pixel(32, 32);
        assert_eq!(px, [52, 96, 200, 255]); // n · l = 1: full intensity
        let tilted = RenderSettings {
            light: Light {
                direction: Vec3::new(1.0, 0.0, 0.0),
                ..settings.light
            },
            ..settings
        };
        r.set_settings(tilted);
        let px = r.render(&camera(), &v, &t, &[]).pixel(32, 32);
        assert_eq!(px, [10, 19, 40, 255]); // n · l = 0: ambient only
    }

    #[test]
    fn an_empty_garment_gives_a_transparent_layer() {
        let mut r = GarmentRenderer::default();
        let layer = r.render(&camera(), &[], &[], &[bar()]);
        assert!(layer.bounds().is_none());
        assert_eq!(layer.frame_size(), (64, 64));
        let full = layer.to_frame_pixmap().expect("size");
        assert!(full.data().iter().all(|&b| b == 0));
        // A garment entirely behind the camera is empty too.
        let (v, t) = triangle(-50.0, 5.0, true);
        assert!(r.render(&camera(), &v, &t, &[]).bounds().is_none());
    }

    #[test]
    fn silhouette_edges_get_partial_alpha() {
        let mut r = GarmentRenderer::new(flat());
        let (v, t) = triangle(100.0, 20.0, true);
        let layer = r.render(&camera(), &v, &t, &[]);
        let alphas: Vec<u8> = layer.data().chunks(4).map(|p| p[3]).collect();
        let partial = alphas.iter().filter(|&&a| a > 0 && a < 255).count();
        let full = alphas.iter().filter(|&&a| a == 255).count();
        assert!(partial > 10 && full > 50, "{partial} partial, {full} full");
        // With fx = 32 and x mirrored, the vertices project to (38.4, 38.4), (25.6, 38.4) and the apex
        // (32, 25.6). The right edge runs x = 32 + (y − 25.6)/2, so row 32 (centre y = 32.5) crosses
        // it at x = 35.45: pixel 34 (centre 34.5) is inside, pixel 35 (centre 35.5) just outside and
        // partly covered, pixel 37 beyond the fin.
        let px = layer.pixel(35, 32);
        assert!(px[3] > 0 && px[3] < 255, "{px:?}");
        assert_eq!(layer.pixel(34, 32)[3], 255);
        assert_eq!(layer.pixel(37, 32)[3], 0);
        // Premultiplied: no channel exceeds alpha.
        assert!(px[..3].iter().all(|&c| c <= px[3]));
        // Without antialiasing no pixel is partial.
        r.set_settings(RenderSettings {
            antialias: false,
            ..flat()
        });
        let layer = r.render(&camera(), &v, &t, &[]);
        assert!(layer.data().chunks(4).all(|p| p[3] == 0 || p[3] == 255));
    }

    #[test]
    fn same_inputs_same_layer_and_buffers_are_reused() {
        let mut r = GarmentRenderer::default();
        let (v, t) = triangle(100.0, 20.0, true);
        let first = r.render(&camera(), &v, &t, &[bar()]).clone();
        let ptr = r.layer().data().as_ptr();
        let second = r.render(&camera(), &v, &t, &[bar()]);
        assert_eq!(&first, second);
        assert_eq!(second.data().as_ptr(), ptr);
    }

    #[test]
    fn parallel_bands_give_the_same_layer() {
        // A 256 × 256 view, so the layer is cut into several bands.
        let camera = Camera::look_at(
            Intrinsics::from_fov(256, 256, 60.0),
            Vec3::ZERO,
            Vec3::new(0.0, 0.0, 100.0),
            Vec3::Y,
        );
        let v = vec![
            Vec3::new(-40.0, -40.0, 140.0),
            Vec3::new(40.0, -40.0, 140.0),
            Vec3::new(0.0, 45.0, 150.0),
            Vec3::new(0.0, 0.0, 110.0),
        ];
        // A tetrahedron with one face left out, so some of its inside shows.
        let t = vec![[0, 1, 2], [1, 3, 2], [2, 3, 0]];
        let mut single = GarmentRenderer::default();
        let expected = single.render(&camera, &v, &t, &[bar()]).clone();
        assert!(expected.data().chunks(4).any(|p| p[3] == 255));
        let mut parallel = GarmentRenderer::new(RenderSettings {
            parallel: true,
            ..RenderSettings::default()
        });
        assert_eq!(parallel.render(&camera, &v, &t, &[bar()]), &expected);
    }

    #[test]
    fn the_inside_shows_through_an_opening() {
        // A box open towards the camera: its far wall is seen from inside, in the back colour.
        let mut r = GarmentRenderer::new(flat());
        let (x, y, z0, z1) = (30.0, 30.0, 100.0, 140.0);
        let v = vec![
            Vec3::new(-x, -y, z1),
            Vec3::new(x, -y, z1),
            Vec3::new(x, y, z1),
            Vec3::new(-x, y, z1),
            Vec3::new(-x, -y, z0),
            Vec3::new(x, -y, z0),
            Vec3::new(x, y, z0),
            Vec3::new(-x, y, z0),
        ];
        // Far wall (outward normal +Z, away from the camera) and the four sides, no near wall.
        let t = vec![
            [0, 1, 2],
            [0, 2, 3],
            [0, 4, 5],
            [0, 5, 1],
            [1, 5, 6],
            [1, 6, 2],
            [2, 6, 7],
            [2, 7, 3],
            [3, 7, 4],
            [3, 4, 0],
        ];
        let px = r.render(&camera(), &v, &t, &[]).pixel(32, 32);
        assert_eq!(px, [200, 160, 90, 255]);
    }

    #[test]
    fn out_of_range_indices_are_skipped() {
        let mut r = GarmentRenderer::default();
        let (v, _) = triangle(100.0, 20.0, true);
        let layer = r.render(&camera(), &v, &[[0, 2, 7]], &[]);
        assert!(layer.data().iter().all(|&b| b == 0));
    }

    #[test]
    fn normals_are_area_weighted() {
        // Two triangles at vertex 0: a big one facing +Z and a small one facing +X.
        let v = [
            Vec3::ZERO,
            Vec3::new(10.0, 0.0, 0.0),
            Vec3::new(0.0, 10.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
        ];
        let mut n = Vec::new();
        vertex_normals(&v, &[[0, 1, 2], [0, 3, 4]], &mut n);
        let expected = Vec3::new(1.0, 0.0, 100.0).normalize();
        assert!((n[0] - expected).length() < 1e-6, "{}", n[0]);
        assert_eq!(n[1], Vec3::Z);
    }

    #[test]
    fn blending_an_opaque_colour_at_half_coverage() {
        let mut px = [0, 0, 200, 255];
        blend_opaque_over(&mut px, [100, 0, 0], 0.5);
        // a = 128: 100·128/255 = 50.2; 200·127/255 = 99.6.
        assert_eq!(px, [50, 0, 100, 255]);
        let mut clear = [0u8; 4];
        blend_opaque_over(&mut clear, [100, 0, 0], 0.5);
        assert_eq!(clear, [50, 0, 0, 128]);
    }

    #[test]
    fn shading_rounds_and_clamps_each_channel() {
        // 100 · 0.5 = 50; 201 · 0.5 = 100.5 rounds up; 200 · 2 = 400 clamps to 255.
        assert_eq!(shade([100.0, 201.0, 200.0], 0.5), [50, 101, 100]);
        assert_eq!(shade([100.0, 201.0, 200.0], 2.0), [200, 255, 255]);
        assert_eq!(shade([100.0, 0.0, 255.0], -1.0), [0, 0, 0]);
        assert_eq!(shade([100.0, 0.0, 255.0], f32::NAN), [0, 0, 0]);
    }
}
