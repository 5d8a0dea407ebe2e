//! The try-on stages after the pose: body size → cloth → garment render → composite with overlays.
//!
//! [`ClothStage`] turns each estimated pose (BVH channels of the regressor's template skeleton) into a
//! simulated garment. It first measures the person ([`BodySizeEstimator`], a few frames of silhouette
//! against the template body at the marker-pitch depth; recorded input is measured ahead with
//! [`ClothStage::measure`], so the garment is on from the first frame), then builds the collision
//! rig at that size, generates (or loads) the garment around its rest pose, dresses it — blended
//! from the rest pose into the current pose and settled — and from then on advances the cloth by
//! the real time between frames in fixed substeps, with the body interpolated at every substep.
//! When nobody is seen the garment is hidden; after [`LOST_AFTER_FRAMES`] such frames the garment
//! is taken off and put on again when the person comes back.
//!
//! [`RenderStage`] draws the garment from the camera's viewpoint ([`crate::render`]) and composites
//! it into the frame with the debug overlays the user switched on ([`crate::composite`]).
//! [`runner`] runs the stages on their own threads; `suitcap run`, `drape`, `live`, `demo` and
//! `bench` are built from these pieces.

pub mod runner;

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use glam::{Affine3A, Vec2, Vec3};
use image::RgbImage;

use crate::body::Body;
use crate::body_size::{BodySize, BodySizeEstimator, Silhouette};
use crate::camera::Camera;
use crate::cloth::garment::{GarmentError, GarmentKind, GarmentMesh, GarmentParams};
use crate::cloth::material::Material;
use crate::cloth::obj::{
    garment_from_mesh, load_obj, obj_name, ObjError, ObjMesh, DEFAULT_ANCHOR_BAND_CM,
};
use crate::cloth::proxies::{BodyRig, DEFAULT_MARGIN_CM};
use crate::cloth::solver::{Cloth, ClothError, FrameQuality, Inertia, SolverSettings};
use crate::cloth::Capsule;
use crate::composite::{CompositeError, Compositor, MarkerDot, TextStyle};
use crate::descriptor::markers::DetectedMarker;
use crate::mask::Mask;
use crate::render::{GarmentRenderer, RenderSettings};
use crate::skeleton::Skeleton;

/// How much of its bone's travelling and turning a garment on *estimated* poses feels
/// ([`SolverSettings::inertia`]; `run`, `demo`, `live`, `bench`). An estimated body shakes: over the nine
/// selection renderings (`suitcap run` with the shipped suit against the generator's motion, fifth
/// session of 2026-12-07) the root's RMS angular acceleration was 1.2–4.1 times the true one's
/// and its RMS linear acceleration 2.8–63 times (per-sequence medians of true / estimated: 0.57
/// and 0.18), and the cloth felt all of it: in the quick start a heading that turns 35° over two
/// frames and 27° back over the next threw the T-shirt up to the chest for ten frames. Scaled by
/// about those shares, the cloth feels about as much acceleration as the true motion would give
/// it. docs/measurements.md has what it did on the quick start and the test sequences.
pub const ESTIMATED_POSE_INERTIA: Inertia = Inertia {
    linear: 0.2,
    angular: 0.5,
};

/// Frames without a person after which the garment is taken off (dressed again on return).
pub const LOST_AFTER_FRAMES: u32 = 15;

/// Which garment to wear.
#[derive(Clone, Debug, PartialEq)]
pub enum GarmentChoice {
    Procedural(GarmentKind),
    /// A triangle mesh in rest-pose world centimetres (see [`crate::cloth::obj`]).
    Obj(PathBuf),
}

impl GarmentChoice {
    /// `tshirt`, `skirt`, `dress`, or a path ending in `.obj`.
    pub fn parse(text: &str) -> Result<GarmentChoice, GarmentError> {
        if text.to_ascii_lowercase().ends_with(".obj") {
            return Ok(GarmentChoice::Obj(PathBuf::from(text)));
        }
        text.parse().map(GarmentChoice::Procedural)
    }

    pub fn name(&self) -> String {
        match self {
            GarmentChoice::Procedural(kind) => kind.name().to_owned(),
            GarmentChoice::Obj(path) => path.display().to_string(),
        }
    }

    /// The next procedural garment (what the live app's garment key switches to).
    pub fn next(&self) -> GarmentChoice {
        let kinds = GarmentKind::ALL;
        let next = match self {
            GarmentChoice::Procedural(kind) => {
                let at = kinds.iter().position(|k| k == kind).unwrap_or(0);
                kinds[(at + 1) % kinds.len()]
            }
            GarmentChoice::Obj(_) => kinds[0],
        };
        GarmentChoice::Procedural(next)
    }
}

/// Live (coarse garment, 40 substeps) or quality (about 4× the vertices, 80 substeps).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SimulationMode {
    Live,
    Quality,
}

/// How the cloth stage dresses the person.
#[derive(Clone, Debug)]
pub struct ClothOptions {
    pub garment: GarmentChoice,
    pub material: Material,
    pub mode: SimulationMode,
    /// Frames with a person used to measure their size before the garment is put on.
    pub sizing_frames: usize,
    /// Use this size instead of measuring (e.g. when the skeleton is already the person's).
    pub known_size: Option<BodySize>,
    /// Garment edge length instead of the mode's (cm).
    pub edge_cm: Option<f32>,
    /// Count the vertices that tunnel through the body ([`Cloth::check_tunnelling`]) into each
    /// frame's quality figures: for `drape`, where time does not matter.
    pub check_tunnelling: bool,
    /// [`SolverSettings::inertia`]: [`Inertia::FULL`] (the default) for true motion,
    /// [`ESTIMATED_POSE_INERTIA`] for the poses the pose stage estimates.
    pub inertia: Inertia,
    /// Recorded input: the runner holds the frames back from the first one with a person until
    /// the person is measured ([`ClothStage::measure`]), then dresses the garment on the first of
    /// them, so it is worn from there on instead of after the measuring frames. At most
    /// [`HELD_SIZING_FRAMES_PER_NEEDED`] × `sizing_frames` frames are held; if fewer were measured
    /// by then, or when the recording ends, the size comes from those measured
    /// ([`ClothStage::settle_size`]). Off for a live picture, which is not held back.
    pub dress_from_first_frame: bool,
}

/// How many frames, per measuring frame needed, the runner holds back at most for
/// [`ClothOptions::dress_from_first_frame`] (frames whose silhouette does not measure, or without
/// a person, are held too).
pub const HELD_SIZING_FRAMES_PER_NEEDED: usize = 2;

impl ClothOptions {
    pub fn new(garment: GarmentChoice, mode: SimulationMode) -> ClothOptions {
        ClothOptions {
            garment,
            material: Material::medium(),
            mode,
            sizing_frames: match mode {
                SimulationMode::Live => 10,
                SimulationMode::Quality => 20,
            },
            known_size: None,
            edge_cm: None,
            check_tunnelling: false,
            inertia: Inertia::FULL,
            dress_from_first_frame: false,
        }
    }

    fn solver_settings(&self) -> SolverSettings {
        let settings = match self.mode {
            SimulationMode::Live => SolverSettings::live(),
            SimulationMode::Quality => SolverSettings::quality(),
        };
        SolverSettings {
            inertia: self.inertia,
            ..settings
        }
    }

    fn garment_params(&self) -> GarmentParams {
        let params = match self.mode {
            SimulationMode::Live => GarmentParams::live(),
            SimulationMode::Quality => GarmentParams::quality(),
        };
        GarmentParams {
            edge_cm: self.edge_cm.unwrap_or(params.edge_cm),
            ..params
        }
    }
}

/// Why the cloth stage cannot dress the person.
#[derive(Debug, thiserror::Error)]
pub enum TryOnError {
    #[error(transparent)]
    Cloth(#[from] ClothError),
    #[error(transparent)]
    Garment(#[from] GarmentError),
    #[error(transparent)]
    Body(#[from] crate::body::MissingJoint),
    #[error(transparent)]
    Obj(#[from] ObjError),
}

/// What the garment is doing in a frame.
#[derive(Clone, Debug, PartialEq)]
pub enum ClothStatus {
    /// Measuring the person: `seen` of `needed` frames.
    Sizing { seen: usize, needed: usize },
    /// Simulated and shown, on a body of the measured `size`.
    Worn { size: BodySize },
    /// Nobody in view: hidden.
    NoPerson,
    /// No garment was asked for, or it could not be simulated (the runner's output carries the
    /// error).
    Off,
}

/// The garment of one frame, owned, for the render stage.
#[derive(Clone, Debug)]
pub struct ClothFrame {
    pub status: ClothStatus,
    /// World positions (cm); empty unless [`ClothStatus::Worn`].
    pub positions: Vec<Vec3>,
    pub triangles: Arc<Vec<[u32; 3]>>,
    /// The body's collision capsules this frame.
    pub capsules: Vec<Capsule>,
    /// The capsules drawn depth-only in the render ([`BodyRig::occluders`]).
    pub occluders: Vec<Capsule>,
    pub quality: Option<FrameQuality>,
    /// The garment was dressed again (a jump in the pose, a new garment, the person came back).
    pub redressed: bool,
    pub milliseconds: f64,
}

impl ClothFrame {
    pub fn hidden(status: ClothStatus, milliseconds: f64) -> ClothFrame {
        ClothFrame {
            status,
            positions: Vec::new(),
            triangles: Arc::new(Vec::new()),
            capsules: Vec::new(),
            occluders: Vec::new(),
            quality: None,
            redressed: false,
            milliseconds,
        }
    }
}

struct Simulation {
    rig: BodyRig,
    cloth: Cloth,
    /// The garment has sleeves (cuffs): the render hides less of the shoulders.
    sleeves: bool,
    triangles: Arc<Vec<[u32; 3]>>,
    garment: GarmentChoice,
}

/// Body size, rig and cloth for one stream.
pub struct ClothStage {
    options: ClothOptions,
    template: Skeleton,
    template_body: Body,
    sizer: BodySizeEstimator,
    size: Option<BodySize>,
    simulation: Option<Simulation>,
    /// The pose and time of the last frame the cloth was advanced to.
    last: Option<(Vec<f32>, f64)>,
    missing: u32,
    /// An OBJ garment's mesh, read once when the stage is made (so a file that cannot be used is
    /// an error before the first frame, not after the body was measured) and anchored anew for
    /// each body.
    obj: Option<(PathBuf, ObjMesh)>,
}

impl ClothStage {
    /// A cloth stage for poses on `template` (the regressor's skeleton, or a mocap clip's).
    pub fn new(template: &Skeleton, options: ClothOptions) -> Result<ClothStage, TryOnError> {
        let template_body = crate::body_size::template_body(template)?;
        let obj = match &options.garment {
            GarmentChoice::Obj(path) => Some((path.clone(), load_obj(path)?)),
            GarmentChoice::Procedural(_) => None,
        };
        Ok(ClothStage {
            size: options.known_size,
            options,
            template: template.clone(),
            template_body,
            sizer: BodySizeEstimator::new(),
            simulation: None,
            last: None,
            missing: 0,
            obj,
        })
    }

    /// The person's size once measured.
    pub fn size(&self) -> Option<BodySize> {
        self.size
    }

    pub fn garment(&self) -> &GarmentChoice {
        &self.options.garment
    }

    /// Wears another garment from the next frame on.
    pub fn set_garment(&mut self, garment: GarmentChoice) {
        self.options.garment = garment;
    }

    /// How many frames the runner may hold back while the person is measured
    /// ([`ClothOptions::dress_from_first_frame`]); `None` when it holds none.
    pub fn sizing_hold(&self) -> Option<usize> {
        self.options
            .dress_from_first_frame
            .then_some(HELD_SIZING_FRAMES_PER_NEEDED * self.options.sizing_frames.max(1))
    }

    /// Measures the person in one frame without advancing the cloth: the frame counts towards
    /// the size as [`ClothStage::advance`] would count it. For input that can be held back while
    /// the person is measured (the runner's recorded input), so that the garment is on from the
    /// first frame; those frames then go through [`ClothStage::advance`] in order, which measures
    /// nothing more. Returns whether the size is known.
    pub fn measure(
        &mut self,
        frame: &[f32],
        person: bool,
        silhouette: Silhouette,
        camera: &Camera,
    ) -> bool {
        if self.size.is_none() && person {
            self.sizer.add_frame(
                silhouette,
                &self.template_body,
                &self.template,
                frame,
                camera,
            );
            if self.sizer.frames() >= self.options.sizing_frames {
                self.size = Some(self.sizer.estimate());
            }
        }
        self.size.is_some()
    }

    /// Ends the measurement with the frames counted so far, when there were any but fewer than
    /// [`ClothOptions::sizing_frames`] (a recording that ends, or whose held frames run out, before
    /// enough were measured). Returns whether the size is known.
    pub fn settle_size(&mut self) -> bool {
        if self.size.is_none() && self.sizer.frames() > 0 {
            self.size = Some(self.sizer.estimate());
        }
        self.size.is_some()
    }

    /// Advances to the pose `frame` seen at `time_s` (stream clock, seconds); `person` false when
    /// nobody was found. `silhouette` and `camera` serve the body-size measurement.
    pub fn advance(
        &mut self,
        frame: &[f32],
        time_s: f64,
        person: bool,
        silhouette: Silhouette,
        camera: &Camera,
    ) -> Result<ClothFrame, TryOnError> {
        let started = Instant::now();
        let ms = |started: Instant| started.elapsed().as_secs_f64() * 1e3;
        if !person {
            self.missing += 1;
            if self.missing >= LOST_AFTER_FRAMES {
                self.simulation = None;
                self.last = None;
            }
            return Ok(ClothFrame::hidden(ClothStatus::NoPerson, ms(started)));
        }
        self.missing = 0;
        self.measure(frame, person, silhouette, camera);
        let Some(size) = self.size else {
            let status = ClothStatus::Sizing {
                seen: self.sizer.frames(),
                needed: self.options.sizing_frames,
            };
            return Ok(ClothFrame::hidden(status, ms(started)));
        };
        let wanted = &self.options.garment;
        let mut redressed = false;
        let stale = self
            .simulation
            .as_ref()
            .is_none_or(|s| &s.garment != wanted);
        if stale || self.last.is_none() {
            let mut simulation = self.build(size)?;
            simulation.cloth.dress(&simulation.rig, frame);
            self.simulation = Some(simulation);
            redressed = true;
        } else if let (Some(simulation), Some((last_frame, last_time))) =
            (self.simulation.as_mut(), self.last.as_ref())
        {
            let seconds = (time_s - last_time) as f32;
            let info = simulation
                .cloth
                .advance(&simulation.rig, last_frame, frame, seconds);
            redressed = info.redressed;
        }
        self.last = Some((frame.to_vec(), time_s));
        let Some(simulation) = self.simulation.as_ref() else {
            return Ok(ClothFrame::hidden(ClothStatus::NoPerson, ms(started)));
        };
        let cloth = &simulation.cloth;
        Ok(ClothFrame {
            status: ClothStatus::Worn { size },
            positions: cloth.positions().iter().map(|&p| Vec3::from(p)).collect(),
            triangles: Arc::clone(&simulation.triangles),
            capsules: cloth.pose().capsules.clone(),
            occluders: simulation
                .rig
                .occluders(&cloth.pose().capsules, simulation.sleeves),
            quality: Some(cloth.quality()),
            redressed,
            milliseconds: ms(started),
        })
    }

    fn build(&self, size: BodySize) -> Result<Simulation, TryOnError> {
        let (subject, skeleton) = size.subject(&self.template);
        let body = Body::new(&subject, &skeleton)?;
        let rig = BodyRig::new(skeleton, body, DEFAULT_MARGIN_CM);
        let mesh = match &self.options.garment {
            GarmentChoice::Procedural(kind) => {
                GarmentMesh::generate(*kind, &rig, &self.options.garment_params())?
            }
            GarmentChoice::Obj(path) => {
                let mesh = match &self.obj {
                    Some((read, mesh)) if read == path => mesh.clone(),
                    _ => load_obj(path)?,
                };
                garment_from_mesh(obj_name(path), mesh, &rig, DEFAULT_ANCHOR_BAND_CM)
            }
        };
        let mut cloth = Cloth::new(
            &mesh,
            &self.options.material,
            &self.options.solver_settings(),
            &rig,
        )?;
        cloth.check_tunnelling(self.options.check_tunnelling);
        Ok(Simulation {
            sleeves: !mesh.cuffs.is_empty(),
            triangles: Arc::new(cloth.triangles().to_vec()),
            rig,
            cloth,
            garment: self.options.garment.clone(),
        })
    }
}

/// Which debug overlays to draw.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Overlays {
    pub mask: bool,
    pub markers: bool,
    pub skeleton: bool,
    pub timings: bool,
}

/// What the render stage needs to know about the pose of a frame for the overlays.
#[derive(Clone, Debug, Default)]
pub struct PoseOverlay {
    pub mask: Option<Mask>,
    pub markers: Vec<DetectedMarker>,
    /// Projected bones: (parent joint pixel, child joint pixel).
    pub bones: Vec<(Vec2, Vec2)>,
}

impl PoseOverlay {
    /// The overlay data of a pose: the mask, the markers and the skeleton (`frame` on `skeleton`)
    /// projected through `camera`.
    pub fn new(
        mask: Option<Mask>,
        markers: Vec<DetectedMarker>,
        skeleton: &Skeleton,
        frame: &[f32],
        camera: &Camera,
    ) -> PoseOverlay {
        let mut world: Vec<Affine3A> = Vec::new();
        skeleton.forward_kinematics(frame, &mut world);
        let pixel = |i: usize| {
            world
                .get(i)
                .and_then(|t| camera.project(Vec3::from(t.translation)))
                .map(|p| p.pixel)
        };
        let bones = skeleton
            .joints()
            .iter()
            .enumerate()
            .filter_map(|(i, joint)| Some((pixel(joint.parent?)?, pixel(i)?)))
            .collect();
        PoseOverlay {
            mask,
            markers,
            bones,
        }
    }
}

/// Garment renderer and compositor for one stream.
pub struct RenderStage {
    renderer: GarmentRenderer,
    compositor: Compositor,
    /// RGB of each suit marker colour, for the marker overlay.
    marker_colours: Vec<[u8; 3]>,
}

impl RenderStage {
    pub fn new(settings: RenderSettings, marker_colours: Vec<[u8; 3]>) -> RenderStage {
        RenderStage {
            renderer: GarmentRenderer::new(settings),
            compositor: Compositor::new(settings.parallel),
            marker_colours,
        }
    }

    /// Draws the garment (when worn) and the overlays into `frame`; `text` lines go top left when
    /// timings are on, `banner` lines (status, recording, drops) always. With `person`, the
    /// frame's mask of the person, the body hides the garment only where the camera sees the
    /// person ([`GarmentRenderer::render_over`]). Returns the milliseconds spent rendering and
    /// compositing.
    #[allow(clippy::too_many_arguments)] // independent per-frame inputs; a struct adds only noise
    pub fn draw(
        &mut self,
        frame: &mut RgbImage,
        camera: &Camera,
        cloth: &ClothFrame,
        person: Option<&Mask>,
        pose: &PoseOverlay,
        overlays: Overlays,
        text: &[String],
        banner: &[String],
    ) -> Result<(f64, f64), CompositeError> {
        let started = Instant::now();
        let worn = matches!(cloth.status, ClothStatus::Worn { .. }) && !cloth.positions.is_empty();
        if worn {
            self.renderer.render_over(
                camera,
                &cloth.positions,
                &cloth.triangles,
                &cloth.occluders,
                person,
            );
        }
        let render_ms = started.elapsed().as_secs_f64() * 1e3;
        let started = Instant::now();
        let plain = overlays == Overlays::default() && banner.is_empty();
        if plain {
            if worn {
                self.compositor.composite(frame, self.renderer.layer())?;
            }
        } else {
            let mut canvas = self.compositor.canvas(frame)?;
            if let (true, Some(mask)) = (overlays.mask, pose.mask.as_ref()) {
                canvas.mask(mask, [255, 0, 255, 70])?;
            }
            if worn {
                canvas.garment(self.renderer.layer())?;
            }
            if overlays.markers {
                let dots: Vec<MarkerDot> = pose
                    .markers
                    .iter()
                    .map(|m| MarkerDot {
                        centre: m.centre,
                        colour: self
                            .marker_colours
                            .get(m.colour)
                            .copied()
                            .unwrap_or([255, 255, 255]),
                    })
                    .collect();
                canvas.markers(&dots, 3.0);
            }
            if overlays.skeleton {
                canvas.skeleton(&pose.bones, [255, 230, 0], 2.0);
            }
            let style = TextStyle::default();
            let mut y = 6.0;
            if !banner.is_empty() {
                canvas.text(6.0, y, banner, &style);
                y += (banner.len() as f32) * 8.0 * style.scale as f32 + 8.0;
            }
            if overlays.timings && !text.is_empty() {
                canvas.text(6.0, y, text, &style);
            }
            canvas.finish(frame)?;
        }
        Ok((render_ms, started.elapsed().as_secs_f64() * 1e3))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Intrinsics;
    use std::path::Path;

    fn walk() -> crate::bvh::Motion {
        let clip =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mocap/cmu_02_01_walk.bvh");
        crate::bvh::Motion::load(&clip).expect("clip")
    }

    /// A coarse live skirt (4 cm edges, quick to dress) on the walk's own skeleton.
    fn stage(motion: &crate::bvh::Motion, known_size: Option<BodySize>) -> ClothStage {
        let mut options = ClothOptions::new(
            GarmentChoice::Procedural(GarmentKind::Skirt),
            SimulationMode::Live,
        );
        options.edge_cm = Some(4.0);
        options.sizing_frames = 3;
        options.known_size = known_size;
        ClothStage::new(&motion.skeleton, options).expect("stage")
    }

    /// Advances `stage` to the walk's frame `k` (30 frames/s), with or without a person seen; the
    /// silhouette is empty (the sizing sees nothing in it).
    fn step(
        stage: &mut ClothStage,
        motion: &crate::bvh::Motion,
        k: usize,
        person: bool,
    ) -> ClothFrame {
        let camera = Camera::look_at(
            Intrinsics::from_fov(64, 48, 60.0),
            Vec3::new(0.0, 100.0, 400.0),
            Vec3::ZERO,
            Vec3::Y,
        );
        let empty = Mask::empty(64, 48);
        stage
            .advance(
                motion.frame(k),
                k as f64 / 30.0,
                person,
                Silhouette::whole(&empty),
                &camera,
            )
            .expect("advances")
    }

    #[test]
    fn nothing_is_worn_until_the_person_was_measured() {
        let motion = walk();
        let mut stage = stage(&motion, None);
        for k in 0..4 {
            let frame = step(&mut stage, &motion, k, true);
            // An empty silhouette measures nothing, so the count stays at 0 of 3.
            assert_eq!(frame.status, ClothStatus::Sizing { seen: 0, needed: 3 });
            assert!(frame.positions.is_empty() && !frame.redressed);
        }
        assert_eq!(stage.size(), None);
        let frame = step(&mut stage, &motion, 4, false);
        assert_eq!(frame.status, ClothStatus::NoPerson);
    }

    /// The camera of [`step`], at 128×96 so that the walk's first frames are seen whole.
    fn whole_view() -> Camera {
        Camera::look_at(
            Intrinsics::from_fov(128, 96, 60.0),
            Vec3::new(0.0, 100.0, 400.0),
            Vec3::new(0.0, 90.0, 0.0),
            Vec3::Y,
        )
    }

    /// The template body of `stage` posed at the walk's frame `k`, as [`whole_view`] sees it: a
    /// silhouette that measures the template's own size.
    fn own_silhouette(stage: &ClothStage, motion: &crate::bvh::Motion, k: usize) -> Mask {
        let mut world = Vec::new();
        motion
            .skeleton
            .forward_kinematics(motion.frame(k), &mut world);
        let mut depth = crate::raster::DepthBuffer::new(128, 96);
        crate::body_size::BodyMasker::new(&stage.template_body).mask(
            &world,
            &whole_view(),
            &mut depth,
        )
    }

    #[test]
    fn a_recording_measured_ahead_is_dressed_at_its_first_frame() {
        let motion = walk();
        let camera = whole_view();
        let mut stage = stage(&motion, None);
        let masks: Vec<Mask> = (0..3).map(|k| own_silhouette(&stage, &motion, k)).collect();
        let measure = |stage: &mut ClothStage, k: usize, person: bool| {
            stage.measure(
                motion.frame(k),
                person,
                Silhouette::whole(&masks[k]),
                &camera,
            )
        };
        assert!(!measure(&mut stage, 0, true));
        // A frame without a person measures nothing.
        assert!(!measure(&mut stage, 1, false));
        assert!(!measure(&mut stage, 1, true));
        assert!(measure(&mut stage, 2, true));
        let size = stage.size().expect("measured");
        assert_eq!(size.frames, 3);
        // The template measured on its own silhouette is the template's size.
        assert!((size.height_scale - 1.0).abs() < 0.05, "{size:?}");
        // The held frames then go through `advance` from the first one: worn at once, measured no
        // further.
        let mut advance = |k: usize| {
            let silhouette = Silhouette::whole(&masks[k]);
            let time = k as f64 / 30.0;
            let frame = stage.advance(motion.frame(k), time, true, silhouette, &camera);
            frame.expect("advances")
        };
        let first = advance(0);
        assert_eq!(first.status, ClothStatus::Worn { size });
        assert!(first.redressed && !first.positions.is_empty());
        assert!(!advance(1).redressed);
        assert_eq!(stage.size(), Some(size));
    }

    #[test]
    fn a_recording_too_short_to_measure_fully_is_sized_from_what_was_measured() {
        let motion = walk();
        let camera = whole_view();
        let mut stage = stage(&motion, None);
        // Nothing measured: no size to settle on.
        let empty = Mask::empty(128, 96);
        assert!(!stage.measure(motion.frame(0), true, Silhouette::whole(&empty), &camera));
        assert!(!stage.settle_size());
        let mask = own_silhouette(&stage, &motion, 1);
        assert!(!stage.measure(motion.frame(1), true, Silhouette::whole(&mask), &camera));
        assert!(stage.settle_size());
        assert_eq!(stage.size().map(|s| s.frames), Some(1));
    }

    #[test]
    fn the_garment_stays_on_through_a_short_loss_and_is_put_on_again_after_a_long_one() {
        let motion = walk();
        let mut stage = stage(&motion, Some(BodySize::TEMPLATE));
        let first = step(&mut stage, &motion, 0, true);
        assert_eq!(
            first.status,
            ClothStatus::Worn {
                size: BodySize::TEMPLATE
            }
        );
        assert!(first.redressed && !first.positions.is_empty());
        let second = step(&mut stage, &motion, 1, true);
        assert!(!second.redressed);
        assert_eq!(second.positions.len(), first.positions.len());
        // Lost for one frame fewer than the limit: hidden, then worn on without dressing again.
        let mut k = 2;
        for _ in 1..LOST_AFTER_FRAMES {
            let hidden = step(&mut stage, &motion, k, false);
            assert_eq!(hidden.status, ClothStatus::NoPerson);
            assert!(hidden.positions.is_empty());
            k += 1;
        }
        let back = step(&mut stage, &motion, k, true);
        assert!(matches!(back.status, ClothStatus::Worn { .. }) && !back.redressed);
        // Lost for the limit: taken off, and dressed again when the person is back.
        for _ in 0..LOST_AFTER_FRAMES {
            k += 1;
            step(&mut stage, &motion, k, false);
        }
        k += 1;
        assert!(step(&mut stage, &motion, k, true).redressed);
        k += 1;
        assert!(!step(&mut stage, &motion, k, true).redressed);
        // Another garment is put on at the next frame.
        stage.set_garment(GarmentChoice::Procedural(GarmentKind::TShirt));
        k += 1;
        let shirt = step(&mut stage, &motion, k, true);
        assert!(shirt.redressed && shirt.positions.len() != first.positions.len());
    }
}
