//! Pinhole camera: intrinsics, extrinsics in the mocap's world frame, projection, `camera.toml`.
//!
//! Axes follow OpenCV: in the camera frame x points right, y down and z forward (depth). The world is
//! the motion capture's frame: centimetres, Y up. A world point `p` has camera coordinates
//! `R·p + t` (`rotation`, `translation`) and projects to pixel `(fx·x/z + cx, fy·y/z + cy)` with pixel
//! centres at integer + 0.5 (pixel (0,0) covers [0,1)×[0,1)). The generator writes this file beside its
//! frames; the root recovery of the pose stage and the garment renderer read it.

use std::path::{Path, PathBuf};

use glam::{Mat3, Vec2, Vec3};
use serde::{Deserialize, Serialize};

/// Image size and pinhole parameters, in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Intrinsics {
    pub width: u32,
    pub height: u32,
    pub fx: f32,
    pub fy: f32,
    pub cx: f32,
    pub cy: f32,
}

impl Intrinsics {
    /// Square pixels, principal point at the image centre, `horizontal_fov_deg` across the width.
    pub fn from_fov(width: u32, height: u32, horizontal_fov_deg: f32) -> Intrinsics {
        let f = width as f32 * 0.5 / (horizontal_fov_deg.to_radians() * 0.5).tan();
        Intrinsics {
            width,
            height,
            fx: f,
            fy: f,
            cx: width as f32 * 0.5,
            cy: height as f32 * 0.5,
        }
    }
}

/// A calibrated camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub intrinsics: Intrinsics,
    /// World → camera rotation (rows: camera x, y, z axes in world coordinates).
    pub rotation: Mat3,
    /// World → camera translation, in world units.
    pub translation: Vec3,
}

/// A point in front of the camera, projected.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projected {
    /// Pixel coordinates (continuous; pixel centres at +0.5).
    pub pixel: Vec2,
    /// Depth along the optical axis, in world units.
    pub depth: f32,
}

/// A `camera.toml` that cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum CameraError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Format { path: PathBuf, message: String },
    #[error("{path}: field {field}: {message}")]
    Field {
        path: PathBuf,
        field: &'static str,
        message: String,
    },
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraFile {
    intrinsics: Intrinsics,
    extrinsics: ExtrinsicsFile,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct ExtrinsicsFile {
    /// World → camera rotation, row-major.
    rotation: [[f32; 3]; 3],
    /// World → camera translation (cm).
    translation: [f32; 3],
    /// Camera centre in the world (cm); redundant, checked against the other two.
    position: [f32; 3],
}

impl Camera {
    /// A camera at `eye` looking at `target`, with world `up` pointing up in the image.
    pub fn look_at(intrinsics: Intrinsics, eye: Vec3, target: Vec3, up: Vec3) -> Camera {
        let forward = (target - eye).normalize();
        let right = forward.cross(up).normalize();
        let down = forward.cross(right);
        let rotation = Mat3::from_cols(right, down, forward).transpose();
        Camera {
            intrinsics,
            rotation,
            translation: -(rotation * eye),
        }
    }

    /// Camera centre in world coordinates.
    pub fn position(&self) -> Vec3 {
        -(self.rotation.transpose() * self.translation)
    }

    /// World point → camera coordinates.
    pub fn to_camera(&self, world: Vec3) -> Vec3 {
        self.rotation * world + self.translation
    }

    /// Camera coordinates → pixel, or `None` behind the camera (depth ≤ 1e-3).
    pub fn project_camera(&self, p: Vec3) -> Option<Projected> {
        if p.z <= 1e-3 {
            return None;
        }
        let k = &self.intrinsics;
        Some(Projected {
            pixel: Vec2::new(k.fx * p.x / p.z + k.cx, k.fy * p.y / p.z + k.cy),
            depth: p.z,
        })
    }

    /// World point → pixel, or `None` behind the camera.
    pub fn project(&self, world: Vec3) -> Option<Projected> {
        self.project_camera(self.to_camera(world))
    }

    /// World point seen at `pixel` at `depth` along the optical axis (inverse of [`Camera::project`]).
    pub fn unproject(&self, pixel: Vec2, depth: f32) -> Vec3 {
        let k = &self.intrinsics;
        let p = Vec3::new(
            (pixel.x - k.cx) / k.fx * depth,
            (pixel.y - k.cy) / k.fy * depth,
            depth,
        );
        self.rotation.transpose() * (p - self.translation)
    }

    /// The `camera.toml` text of this camera.
    pub fn to_toml(&self) -> String {
        let r = self.rotation.transpose(); // columns of the transpose are the rows of `rotation`
        let file = CameraFile {
            intrinsics: self.intrinsics,
            extrinsics: ExtrinsicsFile {
                rotation: [
                    r.x_axis.to_array(),
                    r.y_axis.to_array(),
                    r.z_axis.to_array(),
                ],
                translation: self.translation.to_array(),
                position: self.position().to_array(),
            },
        };
        let body = toml::to_string(&file).unwrap_or_default();
        format!(
            "# suitcap camera. Pinhole; camera axes x right, y down, z forward (OpenCV).\n\
             # World = the motion capture's frame: centimetres, Y up. camera = rotation · world + translation.\n\
             # Pixel centres at integer + 0.5.\n{body}"
        )
    }

    /// Reads and validates a `camera.toml`.
    pub fn load(path: &Path) -> Result<Camera, CameraError> {
        let text = std::fs::read_to_string(path).map_err(|source| CameraError::Io {
            path: path.to_owned(),
            source,
        })?;
        Camera::parse(&text, path)
    }

    /// Parses and validates `camera.toml` text; `path` names the source in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Camera, CameraError> {
        let file: CameraFile = toml::from_str(text).map_err(|e| CameraError::Format {
            path: path.to_owned(),
            message: e.to_string(),
        })?;
        let field = |field: &'static str, message: String| CameraError::Field {
            path: path.to_owned(),
            field,
            message,
        };
        let k = file.intrinsics;
        if k.width == 0 || k.height == 0 {
            return Err(field("intrinsics.width/height", "must be positive".into()));
        }
        for (name, v) in [("intrinsics.fx", k.fx), ("intrinsics.fy", k.fy)] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(field(name, format!("{v} is not a positive number")));
            }
        }
        for (name, v) in [("intrinsics.cx", k.cx), ("intrinsics.cy", k.cy)] {
            if !v.is_finite() {
                return Err(field(name, format!("{v} is not a finite number")));
            }
        }
        let e = &file.extrinsics;
        let rows = e.rotation.map(Vec3::from_array);
        let rotation = Mat3::from_cols(rows[0], rows[1], rows[2]).transpose();
        let orthonormality = (rotation * rotation.transpose() - Mat3::IDENTITY)
            .to_cols_array()
            .iter()
            .fold(0.0f32, |m, v| m.max(v.abs()));
        // NaN is not orthonormal either.
        if orthonormality.is_nan() || orthonormality >= 1e-3 || rotation.determinant() <= 0.0 {
            return Err(field(
                "extrinsics.rotation",
                format!(
                    "is not a rotation (|R·Rᵀ − I| = {orthonormality:.2e}, det = {:.3})",
                    rotation.determinant()
                ),
            ));
        }
        let translation = Vec3::from_array(e.translation);
        if !translation.is_finite() {
            return Err(field("extrinsics.translation", "is not finite".into()));
        }
        let camera = Camera {
            intrinsics: k,
            rotation,
            translation,
        };
        let position = Vec3::from_array(e.position);
        let disagreement = camera.position().distance(position);
        // NaN disagrees too.
        if disagreement.is_nan() || disagreement >= 0.1 {
            return Err(field(
                "extrinsics.position",
                format!("{position} disagrees with −Rᵀ·t = {}", camera.position()),
            ));
        }
        Ok(camera)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera::look_at(
            Intrinsics::from_fov(640, 480, 90.0),
            Vec3::new(0.0, 100.0, -300.0),
            Vec3::new(0.0, 100.0, 0.0),
            Vec3::Y,
        )
    }

    #[test]
    fn target_projects_to_the_principal_point() {
        let c = camera();
        let p = c.project(Vec3::new(0.0, 100.0, 0.0)).expect("in front");
        assert!((p.pixel - Vec2::new(320.0, 240.0)).length() < 1e-4);
        assert!((p.depth - 300.0).abs() < 1e-3);
    }

    #[test]
    fn image_axes_point_right_and_down() {
        // Looking along +Z with Y up, the viewer's right is world −X. With a 90° fov, fx = 320:
        // a point 300 cm ahead and 150 cm to the right lands 160 px right of centre.
        let c = camera();
        let right = c.project(Vec3::new(-150.0, 100.0, 0.0)).expect("in front");
        assert!(
            (right.pixel - Vec2::new(480.0, 240.0)).length() < 1e-3,
            "{:?}",
            right.pixel
        );
        let up = c.project(Vec3::new(0.0, 250.0, 0.0)).expect("in front");
        assert!(
            (up.pixel - Vec2::new(320.0, 80.0)).length() < 1e-3,
            "{:?}",
            up.pixel
        );
        assert!(c.project(Vec3::new(0.0, 100.0, -400.0)).is_none());
    }

    #[test]
    fn unproject_inverts_project() {
        let c = camera();
        let world = Vec3::new(37.0, 12.0, 55.0);
        let p = c.project(world).expect("in front");
        assert!((c.unproject(p.pixel, p.depth) - world).length() < 1e-3);
    }

    #[test]
    fn toml_round_trip_and_validation() {
        let c = camera();
        let text = c.to_toml();
        let back = Camera::parse(&text, Path::new("camera.toml")).expect("parses");
        assert!((back.translation - c.translation).length() < 1e-4);
        let bad = text.replace("fx = ", "fx = -");
        let err = Camera::parse(&bad, Path::new("cam.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("cam.toml") && err.contains("intrinsics.fx"),
            "{err}"
        );
        let bad = text.replace("position = [", "position = [5000.0, ");
        assert!(Camera::parse(&bad, Path::new("cam.toml")).is_err());
    }
}
