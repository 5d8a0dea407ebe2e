//! The pose pipeline for one stream: frame → mask → descriptor → pose vector → BVH frame.
//!
//! [`PosePipeline`] holds a suit's trained models and the per-stream state (the segmenter's history, the
//! last pose). [`PosePipeline::process`] segments the frame (or takes a given mask), describes it,
//! regresses the pose vector with the RVM and decodes it through the camera into a BVH frame of the
//! suit's skeleton. A frame with nobody in it keeps the previous pose and is flagged, so a take has one
//! BVH frame per video frame.

use std::path::Path;
use std::time::Instant;

use image::RgbImage;

use crate::body_size::Silhouette;
use crate::camera::Camera;
use crate::descriptor::{Codebooks, Describer};
use crate::mask::Mask;
use crate::model::ModelError;
use crate::pose::regressor::{Regressor, RegressorError};
use crate::segment::{Segmenter, SegmenterOptions, SegmenterTables};
use crate::suit::{SuitDefinition, SuitError};

/// A suit's models that cannot be loaded.
#[derive(Debug, thiserror::Error)]
pub enum PipelineError {
    #[error(transparent)]
    Suit(#[from] SuitError),
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error(transparent)]
    Regressor(#[from] RegressorError),
    #[error(transparent)]
    Manifest(#[from] crate::manifest::ManifestError),
}

/// Milliseconds per stage.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PoseTimes {
    pub segment: f64,
    pub describe: f64,
    pub regress: f64,
}

/// The result for one frame.
#[derive(Clone, Debug)]
pub struct PoseFrame {
    /// BVH channel values of the suit's skeleton.
    pub frame: Vec<f32>,
    /// False when nobody was seen: `frame` is then the previous pose (or the template).
    pub person: bool,
    pub mask: Mask,
    /// The box of the suit alone, from the segmenter ([`crate::segment::Segmentation::suit_box`];
    /// `None` when a mask was given without it).
    pub suit_box: Option<(u32, u32, u32, u32)>,
    /// The suit markers detected in the frame (empty when nobody was seen).
    pub markers: Vec<crate::descriptor::markers::DetectedMarker>,
    /// The regressed pose vector (empty when nobody was seen).
    pub pose: Vec<f32>,
    /// Root position channels before the position correction.
    pub root_before_correction: [f32; 3],
    /// The depth of the suit's surface the marker grid gave (cm), where the root was put.
    pub marker_depth_cm: Option<f32>,
    /// The image shift onto the head, hand and shoe blobs, where that correction ran.
    pub correction: Option<glam::Vec2>,
    /// The image shift the silhouette registration applied to the root after the correction.
    pub registration: Option<glam::Vec2>,
    /// The frame was part of a root glitch and `frame` was filled in between the poses around it
    /// ([`crate::pose::smoothing::RootGlitchRepair`], recorded input in the try-on runner).
    pub root_glitch_filled: bool,
    pub times: PoseTimes,
}

impl<'a> From<&'a PoseFrame> for Silhouette<'a> {
    /// The mask the pose was estimated in, with the suit's box where the segmenter gave one.
    fn from(pose: &'a PoseFrame) -> Silhouette<'a> {
        Silhouette {
            mask: &pose.mask,
            suit_box: pose.suit_box,
        }
    }
}

/// One stream's pose estimator.
pub struct PosePipeline {
    pub suit: SuitDefinition,
    segmenter: Segmenter,
    describer: Describer,
    codebooks: Codebooks,
    pub regressor: Regressor,
    last: Option<Vec<f32>>,
    pose: Vec<f32>,
    correction_parts: Option<crate::pose::correction::CorrectionParts>,
    lut: crate::segment::features::ColourLut,
    /// Put the root at the depth the marker grid gives, or where it gives none move it onto the
    /// head, hand and shoe blobs (on by default).
    pub position_correction: bool,
    /// Also move it onto the blobs when the markers gave the depth (off by default). The source
    /// paper corrects the position by the head, hands and feet alone; with the depth from the
    /// markers and the silhouette registration after it, the blobs' shift moved the root away
    /// from the truth in the image on average, for the registration to undo: on nine fresh
    /// renderings of training motions the root came out 7.0 px from the truth with the shift and
    /// 6.2 px without (the registration's penalty then at 1); on the six pose test sequences 8.0 and 7.5 px (9.9 and 9.7 cm), on the
    /// bundled demo 10.0 and 9.3 px; without the registration the shift left the six sequences'
    /// root where the regressor put it (11.7 px) and the demo's worse (12.0 → 14.6 px)
    /// (docs/measurements.md, fourth session of 2026-12-05).
    pub landmarks_with_marker_depth: bool,
    /// Then centre the posed template body on the silhouette (on by default; `None` when the
    /// skeleton lacks the body model's joints).
    registration: Option<crate::pose::registration::Registration>,
    pub silhouette_registration: bool,
}

impl PosePipeline {
    /// A second segmenter of the suit, for a thread of its own (the pipeline's stages on threads
    /// segment frame n + 1 while frame n is described), with the same options as the pipeline's.
    pub fn load_segmenter(suit_dir: &Path) -> Result<Segmenter, PipelineError> {
        let suit = SuitDefinition::load_dir(suit_dir)?;
        Ok(Segmenter::new(
            SegmenterTables::load(suit_dir)?,
            &suit,
            SegmenterOptions::default(),
        ))
    }

    /// Loads every model of a suit directory, and checks that they are the ones its manifest
    /// records ([`crate::manifest::verify`]).
    pub fn load(suit_dir: &Path) -> Result<PosePipeline, PipelineError> {
        let suit = SuitDefinition::load_dir(suit_dir)?;
        let segmenter = Segmenter::new(
            SegmenterTables::load(suit_dir)?,
            &suit,
            SegmenterOptions::default(),
        );
        let codebooks = Codebooks::load(suit_dir)?;
        let regressor = Regressor::load(suit_dir, &suit)?;
        // Every file whole, but were they trained together?
        crate::manifest::verify(suit_dir)?;
        let describer = Describer::new(&suit);
        let pose = vec![0.0; regressor.layout.len()];
        let correction_parts =
            crate::pose::correction::CorrectionParts::new(&regressor.skeleton.skeleton);
        let registration = crate::body_size::template_body(&regressor.skeleton.skeleton)
            .ok()
            .map(|body| crate::pose::registration::Registration::new(&body));
        Ok(PosePipeline {
            suit,
            segmenter,
            describer,
            codebooks,
            regressor,
            last: None,
            pose,
            correction_parts,
            lut: crate::segment::features::ColourLut::new(),
            position_correction: true,
            landmarks_with_marker_depth: false,
            registration,
            silhouette_registration: true,
        })
    }

    /// Forgets the stream's history (a new take, or the camera moved).
    pub fn reset(&mut self) {
        self.segmenter.reset();
        self.last = None;
    }

    /// Estimates the pose in one frame seen by `camera`; `given` (a mask, and the suit's box when
    /// a segmenter elsewhere made it) replaces the segmenter.
    pub fn process(
        &mut self,
        image: &RgbImage,
        camera: &Camera,
        given: Option<Silhouette>,
    ) -> PoseFrame {
        let mut times = PoseTimes::default();
        let started = Instant::now();
        let (mask, suit_box) = match given {
            Some(given) => (given.mask.clone(), given.suit_box),
            None => {
                let segmentation = self.segmenter.segment(image);
                (segmentation.mask, segmentation.suit_box)
            }
        };
        times.segment = ms(started);
        let started = Instant::now();
        let (descriptor, markers) =
            self.describer
                .describe(image, &mask, self.regressor.descriptor, &self.codebooks);
        times.describe = ms(started);
        let bbox = mask.bounding_box();
        let (Some((x0, y0, x1, y1)), true) = (bbox, descriptor.person) else {
            let frame = self
                .last
                .clone()
                .unwrap_or_else(|| self.regressor.template().to_vec());
            let root_before_correction = self.regressor.layout.root_position.map(|c| frame[c]);
            return PoseFrame {
                frame,
                person: false,
                mask,
                suit_box,
                markers: Vec::new(),
                pose: Vec::new(),
                root_before_correction,
                marker_depth_cm: None,
                correction: None,
                registration: None,
                root_glitch_filled: false,
                times,
            };
        };
        let started = Instant::now();
        self.regressor
            .predict_into(&descriptor.values, &mut self.pose);
        let bbox = (x0 as f32, y0 as f32, x1 as f32, y1 as f32);
        let mut frame = self.regressor.layout.decode(
            &self.regressor.skeleton.skeleton,
            &self.pose,
            self.regressor.template(),
            camera,
            bbox,
        );
        let root_before_correction = self.regressor.layout.root_position.map(|c| frame[c]);
        let marker_depth_cm = self
            .position_correction
            .then(|| {
                crate::pose::correction::depth_from_markers(
                    &markers.iter().map(|m| m.centre).collect::<Vec<_>>(),
                    self.suit.pitch_cm(),
                    camera.intrinsics.fy,
                )
            })
            .flatten();
        let skeleton = &self.regressor.skeleton.skeleton;
        let root_position = self.regressor.layout.root_position;
        let correction = match (&self.correction_parts, marker_depth_cm) {
            (_, Some(depth)) if !self.landmarks_with_marker_depth => {
                crate::pose::correction::root_to_depth(
                    &mut frame,
                    skeleton,
                    root_position,
                    camera,
                    depth,
                );
                None
            }
            (Some(parts), _) if self.position_correction => {
                let landmarks = crate::pose::correction::find_landmarks(image, &mask, &self.lut);
                crate::pose::correction::correct_root(
                    &mut frame,
                    skeleton,
                    root_position,
                    parts,
                    camera,
                    &landmarks,
                    (y1 - y0) as f32,
                    marker_depth_cm,
                )
            }
            _ => None,
        };
        let registration = match (&mut self.registration, self.silhouette_registration) {
            (Some(registration), true) => registration.register(
                &self.regressor.skeleton.skeleton,
                &mut frame,
                self.regressor.layout.root_position,
                &mask,
                camera,
            ),
            _ => None,
        };
        times.regress = ms(started);
        self.last = Some(frame.clone());
        PoseFrame {
            frame,
            person: true,
            mask,
            suit_box,
            markers,
            pose: self.pose.clone(),
            root_before_correction,
            marker_depth_cm,
            correction,
            registration,
            root_glitch_filled: false,
            times,
        }
    }
}

fn ms(started: Instant) -> f64 {
    started.elapsed().as_secs_f64() * 1e3
}
