//! The synthetic mocap-aligned video generator: a suited person driven by real motion capture,
//! rendered over real photographs or video, written as a dataset (see `suitcap::dataset`).
//!
//! [`generate`] resamples the clip to the camera's rate, scales skeleton and root motion to the
//! subject, places a camera that keeps the whole motion in view from a seed-chosen side and height,
//! draws the scene's light, exposure drift, sensor noise, blur, background plate and clutter from the
//! seed, renders all frames in parallel with rayon (each frame's noise from its own seeded generator,
//! so the output is byte-identical for a given seed whatever the thread count), and writes frames,
//! masks, `motion.bvh`, `camera.toml`, `markers.csv` and, last, `manifest.toml`.

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{bail, Context};
use glam::{Affine3A, Quat, Vec3};
use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use image::{ImageEncoder, RgbImage};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use rayon::prelude::*;

use suitcap::body::{Body, Subject, SUBJECTS};
use suitcap::bvh::Motion;
use suitcap::camera::{Camera, Intrinsics};
use suitcap::dataset::{
    self, ClipInfo, Manifest, MarkerRecord, SceneInfo, SubjectInfo, SuitInfo, DATASET_FORMAT,
};
use suitcap::suit::{splitmix64, SuitDefinition};

use crate::backgrounds::{self, BackgroundSource, Clutter, Crop, VIDEO_FPS};
use crate::render::{compose, BodyLayer, BodyRenderer, Lighting, Sensor};

/// Everything the generator is asked for.
#[derive(Clone, Debug)]
pub struct SynthOptions {
    pub bvh: PathBuf,
    pub out: PathBuf,
    /// First source frame used (skip the T-pose and the blend-in of the shipped clips).
    pub start_frame: usize,
    /// Number of output frames; `None` = as many as the clip holds.
    pub frames: Option<usize>,
    pub fps: f64,
    pub width: u32,
    pub height: u32,
    /// Built-in subject name or index; `None` = chosen by the seed.
    pub subject: Option<String>,
    pub backgrounds: Vec<PathBuf>,
    pub suit_dir: PathBuf,
    pub seed: u64,
    /// Replace an existing dataset in `out`.
    pub overwrite: bool,
    /// The command line, recorded in the manifest.
    pub command: String,
    /// Frame ranges rendered without the person (the room and its clutter only, an empty mask, no
    /// markers): someone who steps into view after the camera started, or leaves and comes back.
    pub absent: Vec<Range<usize>>,
}

impl SynthOptions {
    /// `bvh` rendered into `out` in the suit of `suit_dir` over `backgrounds`, the rest as the
    /// command line's defaults: from clip frame 12, every frame, 30 frames/s, 640×480, the subject
    /// chosen by the seed, seed 1, an existing dataset not replaced.
    pub fn new(bvh: PathBuf, out: PathBuf, suit_dir: PathBuf, backgrounds: Vec<PathBuf>) -> Self {
        SynthOptions {
            bvh,
            out,
            start_frame: 12,
            frames: None,
            fps: 30.0,
            width: 640,
            height: 480,
            subject: None,
            backgrounds,
            suit_dir,
            seed: 1,
            overwrite: false,
            command: String::new(),
            absent: Vec::new(),
        }
    }
}

/// What a run produced.
#[derive(Clone, Debug)]
pub struct Summary {
    pub frames: usize,
    pub subject: &'static str,
    pub background: String,
    pub seconds_rendering: f64,
    pub seconds_total: f64,
    pub mean_visible_markers: f64,
}

/// The scene drawn from the seed, shared by every frame.
pub struct Scene {
    pub camera: Camera,
    pub horizontal_fov_deg: f32,
    pub light_direction: Vec3,
    pub ambient: f32,
    pub exposure: f32,
    pub exposure_drift: f32,
    pub exposure_period_s: f32,
    pub exposure_phase: f32,
    pub read_noise: f32,
    pub shot_noise: f32,
    pub blur_sigma: f32,
}

/// World transforms of every joint for every frame.
pub fn pose_all(motion: &Motion) -> Vec<Vec<Affine3A>> {
    motion
        .frames()
        .map(|frame| {
            let mut world = Vec::with_capacity(motion.skeleton.len());
            motion.skeleton.forward_kinematics(frame, &mut world);
            world
        })
        .collect()
}

/// Places a camera that sees every joint of every frame (plus the top of the head) with a 5 % margin,
/// looking at the motion's centre from `azimuth_deg` off the figure's mean facing direction, but no
/// farther than `max_distance_cm`: a clip that crosses a room then leaves the picture in places, as a
/// real performer would, rather than shrinking the person to a few pixels.
pub fn place_camera(
    poses: &[Vec<Affine3A>],
    intrinsics: Intrinsics,
    azimuth_deg: f32,
    height_cm: f32,
    head_room_cm: f32,
    max_distance_cm: f32,
) -> Camera {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    let mut facing = Vec3::ZERO;
    for world in poses {
        for t in world {
            let p = Vec3::from(t.translation);
            lo = lo.min(p);
            hi = hi.max(p);
        }
        if let Some(root) = world.first() {
            let f = Vec3::from(root.matrix3 * glam::Vec3A::Z);
            facing += Vec3::new(f.x, 0.0, f.z);
        }
    }
    hi.y += head_room_cm;
    lo.y = lo.y.min(0.0);
    lo -= Vec3::new(15.0, 0.0, 15.0);
    hi += Vec3::new(15.0, 0.0, 15.0);
    let facing = facing.normalize_or(Vec3::Z);
    let towards_camera = Quat::from_rotation_y(azimuth_deg.to_radians()) * facing;
    let centre = (lo + hi) * 0.5;
    let corners: Vec<Vec3> = (0..8)
        .map(|i| {
            Vec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
        })
        .collect();
    let (w, h) = (intrinsics.width as f32, intrinsics.height as f32);
    let mut distance = 150.0;
    loop {
        let eye = Vec3::new(centre.x, height_cm, centre.z) + towards_camera * distance;
        let camera = Camera::look_at(intrinsics, eye, centre, Vec3::Y);
        let fits = corners.iter().all(|&c| match camera.project(c) {
            Some(p) => {
                p.pixel.x > 0.05 * w
                    && p.pixel.x < 0.95 * w
                    && p.pixel.y > 0.05 * h
                    && p.pixel.y < 0.95 * h
            }
            None => false,
        });
        if fits || distance >= max_distance_cm {
            return camera;
        }
        distance += 10.0;
    }
}

/// A background plate sequence: one photograph, or the video frames that the clip's duration needs.
enum Plates {
    Still(Arc<Vec<[f32; 3]>>),
    Video(Vec<Arc<Vec<[f32; 3]>>>),
}

impl Plates {
    fn at(&self, t: f64) -> &Arc<Vec<[f32; 3]>> {
        match self {
            Plates::Still(p) => p,
            Plates::Video(frames) => {
                // Play forwards, then backwards, so a long clip never jumps.
                let n = frames.len();
                let k = (t * VIDEO_FPS).floor() as usize;
                let period = (2 * n).saturating_sub(2).max(1);
                let k = k % period;
                &frames[if k < n { k } else { period - k }]
            }
        }
    }
}

fn to_f32(image: &RgbImage) -> Vec<[f32; 3]> {
    image.pixels().map(|p| p.0.map(f32::from)).collect()
}

/// Writes 8-bit pixels (`colour` says RGB or grey) as a PNG with fast compression: the generator's
/// frames are large and many, and writing them is a noticeable part of a run.
fn write_png(
    path: &Path,
    pixels: &[u8],
    width: u32,
    height: u32,
    colour: image::ExtendedColorType,
) -> anyhow::Result<()> {
    let file =
        std::fs::File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    let encoder = PngEncoder::new_with_quality(
        std::io::BufWriter::new(file),
        CompressionType::Fast,
        FilterType::Sub,
    );
    encoder
        .write_image(pixels, width, height, colour)
        .with_context(|| format!("cannot write {}", path.display()))
}

/// Picks the subject: by name/index if given, else by the seed.
pub fn choose_subject(name: Option<&str>, seed: u64) -> anyhow::Result<&'static Subject> {
    match name {
        Some(n) => Subject::find(n).with_context(|| {
            let names: Vec<String> = SUBJECTS
                .iter()
                .enumerate()
                .map(|(i, s)| format!("{i}={}", s.name))
                .collect();
            format!(
                "unknown subject '{n}'; built-in subjects: {}",
                names.join(", ")
            )
        }),
        None => Ok(&SUBJECTS[(splitmix64(seed) % SUBJECTS.len() as u64) as usize]),
    }
}

/// Generates a dataset. `progress` is called once per rendered frame (from worker threads).
pub fn generate(options: &SynthOptions, progress: &(dyn Fn() + Sync)) -> anyhow::Result<Summary> {
    let started = Instant::now();
    if options.width < 16 || options.height < 16 {
        bail!(
            "--size {}x{} is too small (at least 16x16)",
            options.width,
            options.height
        );
    }
    let suit = SuitDefinition::load_dir(&options.suit_dir)?;
    let clip = Motion::load(&options.bvh)?;
    suit.skeleton.bind(&clip.skeleton).with_context(|| {
        format!(
            "{}: the clip does not carry the suit's joints",
            options.bvh.display()
        )
    })?;
    let subject = choose_subject(options.subject.as_deref(), options.seed)?;
    let (resampled, source_frames) = clip
        .resample(options.start_frame, options.frames, options.fps)
        .with_context(|| {
            format!(
                "{}: cannot take the frames asked for",
                options.bvh.display()
            )
        })?;
    if resampled.frame_count() == 0 {
        bail!("{}: no frames to render", options.bvh.display());
    }
    if let Some(r) = options
        .absent
        .iter()
        .find(|r| r.start >= resampled.frame_count())
    {
        bail!(
            "--absent {}..{}: the clip gives only {} frames",
            r.start,
            r.end,
            resampled.frame_count()
        );
    }
    let skeleton = subject.scale_skeleton(&clip.skeleton);
    let motion = resampled.with_skeleton(skeleton.clone(), |frame| {
        subject.scale_root_translation(&clip.skeleton, frame)
    });
    let body =
        Body::new(subject, &skeleton).with_context(|| format!("{}", options.bvh.display()))?;
    let poses = pose_all(&motion);

    // Scene parameters, all from the seed.
    let mut rng = Pcg64Mcg::seed_from_u64(splitmix64(options.seed ^ 0x5CE4E));
    let fov = rng.gen_range(50.0..65.0f32);
    let intrinsics = Intrinsics::from_fov(options.width, options.height, fov);
    // The person spans at least about 60 % of the image height.
    let max_distance = intrinsics.fy * subject.height_cm / (0.6 * options.height as f32);
    let camera = place_camera(
        &poses,
        intrinsics,
        rng.gen_range(-40.0..40.0),
        rng.gen_range(95.0..170.0) * subject.height_cm / 170.0,
        22.0 * subject.height_cm / 166.0,
        max_distance,
    );
    let to_camera = (camera.position() - Vec3::from(poses[0][0].translation)).normalize_or(Vec3::Z);
    let light_direction = (Quat::from_rotation_y(rng.gen_range(-1.0..1.0f32))
        * Vec3::new(to_camera.x, 0.0, to_camera.z).normalize_or(Vec3::Z)
        + Vec3::Y * rng.gen_range(0.3..2.0f32))
    .normalize();
    let scene = Scene {
        camera,
        horizontal_fov_deg: fov,
        light_direction,
        ambient: rng.gen_range(0.3..0.6),
        exposure: rng.gen_range(0.85..1.15),
        exposure_drift: rng.gen_range(0.0..0.12),
        exposure_period_s: rng.gen_range(2.0..8.0),
        exposure_phase: rng.gen_range(0.0..std::f32::consts::TAU),
        read_noise: rng.gen_range(1.0..3.5),
        shot_noise: rng.gen_range(0.01..0.08),
        blur_sigma: rng.gen_range(0.5..0.9),
    };

    // Background plate and clutter.
    let sources = backgrounds::discover(&options.backgrounds)?;
    let source = &sources[rng.gen_range(0..sources.len())];
    let crop = Crop {
        zoom: rng.gen_range(1.0..1.4),
        pan_x: rng.gen(),
        pan_y: rng.gen(),
    };
    let (w, h) = (options.width, options.height);
    let duration = motion.frame_count() as f64 / options.fps;
    let (plates, background_names, background_is_video) = match source {
        BackgroundSource::Photo(path) => {
            let plate = backgrounds::load_plate(path, w, h, crop)?;
            (
                Plates::Still(Arc::new(to_f32(&plate))),
                vec![path.display().to_string()],
                false,
            )
        }
        BackgroundSource::Video { frames, .. } => {
            let needed = ((duration * VIDEO_FPS).ceil() as usize + 1).min(frames.len());
            let used = &frames[..needed];
            let plates = used
                .par_iter()
                .map(|p| backgrounds::load_plate(p, w, h, crop).map(|img| Arc::new(to_f32(&img))))
                .collect::<Result<Vec<_>, _>>()?;
            (
                Plates::Video(plates),
                used.iter().map(|p| p.display().to_string()).collect(),
                true,
            )
        }
    };
    let photos: Vec<&PathBuf> = sources
        .iter()
        .filter_map(|s| match s {
            BackgroundSource::Photo(p) => Some(p),
            BackgroundSource::Video { .. } => None,
        })
        .collect();
    let texture_photo = match photos.len() {
        0 => None,
        n => Some(backgrounds::load_plate(
            photos[rng.gen_range(0..n)],
            w,
            h,
            Crop {
                zoom: 1.0,
                pan_x: 0.5,
                pan_y: 0.5,
            },
        )?),
    };
    let clutter: Vec<Clutter> = (0..rng.gen_range(3..8))
        .map(|_| Clutter::random(&mut rng, w, h, texture_photo.as_ref()))
        .collect();

    // Output directory: an old manifest goes first, so an interrupted run leaves an incomplete dataset.
    let out = &options.out;
    suitcap::dataset::prepare_dataset_dir(out, options.overwrite)?;

    // Render every frame in parallel.
    let renderer = BodyRenderer::new(&suit, subject, &body, scene.camera);
    let render_started = Instant::now();
    let per_frame: Vec<Vec<MarkerRecord>> = (0..motion.frame_count())
        .into_par_iter()
        .map_init(
            || (BodyLayer::new(w, h), Vec::new(), Vec::new()),
            |(layer, background, scratch), k| -> anyhow::Result<Vec<MarkerRecord>> {
                let t = k as f64 / options.fps;
                let world = &poses[k];
                let lighting = Lighting {
                    direction: scene.light_direction,
                    ambient: scene.ambient,
                    exposure: scene.exposure,
                };
                if options.absent.iter().any(|r| r.contains(&k)) {
                    layer.clear();
                } else {
                    renderer.draw(world, &lighting, layer);
                }
                background.clear();
                background.extend_from_slice(plates.at(t));
                for object in &clutter {
                    object.draw(t as f32, background, w, h);
                }
                let gain = 1.0
                    + scene.exposure_drift
                        * (std::f32::consts::TAU * t as f32 / scene.exposure_period_s
                            + scene.exposure_phase)
                            .sin();
                let sensor = Sensor {
                    gain,
                    blur_sigma: scene.blur_sigma,
                    read_noise: scene.read_noise,
                    shot_noise: scene.shot_noise,
                };
                let mut frame_rng = Pcg64Mcg::seed_from_u64(splitmix64(
                    options.seed.wrapping_mul(0x9E37).wrapping_add(k as u64),
                ));
                let image = compose(background, layer, &sensor, &mut frame_rng, scratch);
                write_png(
                    &dataset::frame_path(out, k),
                    image.as_raw(),
                    w,
                    h,
                    image::ExtendedColorType::Rgb8,
                )?;
                write_png(
                    &dataset::mask_path(out, k),
                    layer.mask().as_raw(),
                    w,
                    h,
                    image::ExtendedColorType::L8,
                )?;
                let markers = renderer
                    .visible_markers(world, layer)
                    .into_iter()
                    .map(|m| MarkerRecord {
                        frame: k,
                        marker_id: m.id,
                        colour: suit.markers[m.colour].name.clone(),
                        x: m.centre.x,
                        y: m.centre.y,
                        visible_fraction: m.visible_fraction,
                        visible_px: m.visible_px,
                    })
                    .collect();
                progress();
                Ok(markers)
            },
        )
        .collect::<anyhow::Result<_>>()?;
    let seconds_rendering = render_started.elapsed().as_secs_f64();

    let write = |name: &str, bytes: &[u8]| {
        let path = out.join(name);
        suitcap::io::write_atomic(&path, bytes)
            .with_context(|| format!("cannot write {}", path.display()))
    };
    motion.write(&out.join("motion.bvh"))?;
    write("camera.toml", scene.camera.to_toml().as_bytes())?;
    let records: Vec<MarkerRecord> = per_frame.into_iter().flatten().collect();
    write("markers.csv", dataset::markers_to_csv(&records).as_bytes())?;
    let manifest = Manifest {
        format: DATASET_FORMAT,
        generator: format!("suitcap-synth {}", env!("CARGO_PKG_VERSION")),
        command: options.command.clone(),
        frames: motion.frame_count(),
        fps: options.fps,
        width: w,
        height: h,
        seed: Some(options.seed),
        clip: ClipInfo {
            name: options
                .bvh
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
            source_fps: clip.frame_rate(),
            start_frame: options.start_frame,
            source_frames,
        },
        subject: Some(SubjectInfo {
            name: subject.name.to_owned(),
            height_cm: subject.height_cm,
            girth: subject.girth,
            arm_ratio: subject.arm_ratio,
            leg_ratio: subject.leg_ratio,
        }),
        suit: SuitInfo {
            name: suit.name.clone(),
            layout_seed: suit.layout_seed,
            marker_size_cm: suit.marker_size_cm,
            marker_gap_cm: suit.marker_gap_cm,
        },
        scene: Some(SceneInfo {
            backgrounds: background_names,
            background_is_video,
            horizontal_fov_deg: scene.horizontal_fov_deg,
            light_direction: scene.light_direction.to_array(),
            ambient: scene.ambient,
            exposure: scene.exposure,
            exposure_drift: scene.exposure_drift,
            exposure_period_s: scene.exposure_period_s,
            read_noise: scene.read_noise,
            shot_noise: scene.shot_noise,
            blur_sigma: scene.blur_sigma,
            clutter_objects: clutter.len(),
        }),
        recording: None,
    };
    write("manifest.toml", manifest.to_toml().as_bytes())?;

    Ok(Summary {
        frames: motion.frame_count(),
        subject: subject.name,
        background: source.describe(),
        seconds_rendering,
        seconds_total: started.elapsed().as_secs_f64(),
        mean_visible_markers: records.len() as f64 / motion.frame_count() as f64,
    })
}
