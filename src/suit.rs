//! Suit definition: `suits/NAME/suit.toml`.
//!
//! A suit is cloth of one background colour (yellowish green) printed with square markers in three
//! colours (cyan, purple, red), the four hues 90° apart. Markers are `marker_size_cm` squares laid on a
//! grid of pitch `marker_size_cm + marker_gap_cm` over every patterned body part; each grid cell's
//! colour is drawn from the layout seed, so the same suit always looks the same on any body (see
//! [`SuitDefinition::marker_colour`]). The file also names the skeleton the regressor estimates, mapped
//! to the joints of the mocap that trains it. The generator paints the pattern from here; the marker
//! detector reads the colours and gates; the pose stage reads the skeleton.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::colour::{hue_distance, Hsv};
use crate::skeleton::Skeleton;

/// Version of the `suit.toml` format this build reads.
pub const SUIT_FORMAT: u32 = 1;

/// At most this many marker colours: the Feature Context histogram has one colour bin per marker
/// colour ([`FC_COLOURS`](crate::descriptor::feature_context::FC_COLOURS)).
pub const MAX_MARKER_COLOURS: usize = crate::descriptor::feature_context::FC_COLOURS;

/// A named colour of the suit.
#[derive(Clone, Debug, PartialEq)]
pub struct SuitColour {
    pub name: String,
    pub hsv: Hsv,
}

/// Thresholds the marker detector uses to decide that a pixel has a meaningful hue.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DetectionGates {
    /// A pixel belongs to a colour when its hue is within this many degrees of the colour's hue.
    pub hue_tolerance_deg: f32,
    /// Below this saturation a pixel's hue is noise.
    pub min_saturation: f32,
    /// Below this value a pixel's hue is noise.
    pub min_value: f32,
}

/// One joint the regressor estimates.
#[derive(Clone, Debug, PartialEq)]
pub struct SuitJoint {
    pub name: String,
    /// Index of the parent within [`SuitSkeleton::joints`]; `None` for the root.
    pub parent: Option<usize>,
    /// Name of the joint in the training mocap's BVH hierarchy.
    pub bvh: String,
}

/// The estimated joints, parents before children, the root first.
#[derive(Clone, Debug, PartialEq)]
pub struct SuitSkeleton {
    pub joints: Vec<SuitJoint>,
}

/// A validated `suit.toml`.
#[derive(Clone, Debug, PartialEq)]
pub struct SuitDefinition {
    pub name: String,
    pub marker_size_cm: f32,
    pub marker_gap_cm: f32,
    pub layout_seed: u64,
    pub background: SuitColour,
    /// The marker colours; a marker's colour index refers to this list.
    pub markers: Vec<SuitColour>,
    pub detection: DetectionGates,
    pub skeleton: SuitSkeleton,
}

/// A suit file that cannot be used; names the file and the field.
#[derive(Debug, thiserror::Error)]
pub enum SuitError {
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
        field: String,
        message: String,
    },
}

/// A mocap skeleton that does not carry the suit's joints.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum BindError {
    #[error("suit joint '{joint}' maps to BVH joint '{bvh}', which the motion does not have (it has: {available})")]
    UnknownJoint {
        joint: String,
        bvh: String,
        available: String,
    },
    #[error("suit joint '{joint}' has parent '{parent}', but BVH joint '{parent_bvh}' is not an ancestor of '{bvh}'")]
    NotAnAncestor {
        joint: String,
        parent: String,
        parent_bvh: String,
        bvh: String,
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SuitFile {
    format: u32,
    name: String,
    pattern: PatternFile,
    colours: ColoursFile,
    detection: DetectionGates,
    skeleton: Vec<JointFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PatternFile {
    marker_size_cm: f32,
    marker_gap_cm: f32,
    layout_seed: u64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ColoursFile {
    background: ColourFile,
    markers: Vec<ColourFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ColourFile {
    name: String,
    hue: f32,
    saturation: f32,
    value: f32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JointFile {
    name: String,
    parent: Option<String>,
    bvh: String,
}

/// The file of a suit directory that defines it.
pub const SUIT_FILE: &str = "suit.toml";

/// The suit the commands use without `--suit`: `suits/default` under the current directory (the
/// repository, as the quick start runs), else the one of the repository this build was made
/// from, so a binary run from elsewhere still finds the suit it ships with; `suits/default` when
/// neither has a `suit.toml` (loading it then names that path).
pub fn default_suit_dir() -> PathBuf {
    first_suit_dir(
        PathBuf::from("suits/default"),
        Path::new(env!("CARGO_MANIFEST_DIR")).join("suits/default"),
    )
}

/// `here` if it holds a suit or `built` does not, else `built`.
fn first_suit_dir(here: PathBuf, built: PathBuf) -> PathBuf {
    if !here.join(SUIT_FILE).is_file() && built.join(SUIT_FILE).is_file() {
        return built;
    }
    here
}

impl SuitDefinition {
    /// Reads `DIR/suit.toml`.
    pub fn load_dir(dir: &Path) -> Result<SuitDefinition, SuitError> {
        SuitDefinition::load(&dir.join(SUIT_FILE))
    }

    /// Reads and validates a suit file.
    pub fn load(path: &Path) -> Result<SuitDefinition, SuitError> {
        let text = std::fs::read_to_string(path).map_err(|source| SuitError::Io {
            path: path.to_owned(),
            source,
        })?;
        SuitDefinition::parse(&text, path)
    }

    /// Parses and validates suit text; `path` names the source in errors.
    pub fn parse(text: &str, path: &Path) -> Result<SuitDefinition, SuitError> {
        let file: SuitFile = toml::from_str(text).map_err(|e| SuitError::Format {
            path: path.to_owned(),
            message: e.to_string(),
        })?;
        let field = |field: String, message: String| SuitError::Field {
            path: path.to_owned(),
            field,
            message,
        };

        if file.format != SUIT_FORMAT {
            return Err(field(
                "format".into(),
                format!(
                    "{} is not the suit format this build reads ({SUIT_FORMAT})",
                    file.format
                ),
            ));
        }
        if file.name.trim().is_empty() {
            return Err(field("name".into(), "must not be empty".into()));
        }
        let p = &file.pattern;
        if !(p.marker_size_cm > 0.5 && p.marker_size_cm < 50.0) {
            return Err(field(
                "pattern.marker_size_cm".into(),
                format!("{} is not in (0.5, 50)", p.marker_size_cm),
            ));
        }
        if !(p.marker_gap_cm >= 0.5 && p.marker_gap_cm < 50.0) {
            return Err(field(
                "pattern.marker_gap_cm".into(),
                format!("{} is not in [0.5, 50)", p.marker_gap_cm),
            ));
        }

        let colour = |c: &ColourFile, at: String| -> Result<SuitColour, SuitError> {
            if !(0.0..360.0).contains(&c.hue) {
                return Err(field(
                    format!("{at}.hue"),
                    format!("{} is not in [0, 360)", c.hue),
                ));
            }
            if !(0.0..=1.0).contains(&c.saturation) {
                return Err(field(
                    format!("{at}.saturation"),
                    format!("{} is not in [0, 1]", c.saturation),
                ));
            }
            if !(0.0..=1.0).contains(&c.value) {
                return Err(field(
                    format!("{at}.value"),
                    format!("{} is not in [0, 1]", c.value),
                ));
            }
            Ok(SuitColour {
                name: c.name.clone(),
                hsv: Hsv {
                    hue: c.hue,
                    saturation: c.saturation,
                    value: c.value,
                },
            })
        };
        let background = colour(&file.colours.background, "colours.background".into())?;
        let markers = file
            .colours
            .markers
            .iter()
            .enumerate()
            .map(|(i, c)| colour(c, format!("colours.markers[{i}]")))
            .collect::<Result<Vec<_>, _>>()?;
        if markers.is_empty() {
            return Err(field(
                "colours.markers".into(),
                "lists no marker colour".into(),
            ));
        }
        if markers.len() > MAX_MARKER_COLOURS {
            return Err(field(
                "colours.markers".into(),
                format!(
                    "lists {} marker colours; the Feature Context descriptor has bins for at most {MAX_MARKER_COLOURS}",
                    markers.len()
                ),
            ));
        }

        let d = file.detection;
        if !(d.hue_tolerance_deg > 0.0 && d.hue_tolerance_deg < 90.0) {
            return Err(field(
                "detection.hue_tolerance_deg".into(),
                format!("{} is not in (0, 90)", d.hue_tolerance_deg),
            ));
        }
        if !(0.0..1.0).contains(&d.min_saturation) {
            return Err(field(
                "detection.min_saturation".into(),
                format!("{} is not in [0, 1)", d.min_saturation),
            ));
        }
        if !(0.0..1.0).contains(&d.min_value) {
            return Err(field(
                "detection.min_value".into(),
                format!("{} is not in [0, 1)", d.min_value),
            ));
        }
        // Every pair of suit colours must be told apart by the hue gate.
        let all: Vec<(String, &SuitColour)> =
            std::iter::once(("colours.background".to_string(), &background))
                .chain(
                    markers
                        .iter()
                        .enumerate()
                        .map(|(i, m)| (format!("colours.markers[{i}]"), m)),
                )
                .collect();
        for (i, (name_a, a)) in all.iter().enumerate() {
            for (name_b, b) in &all[i + 1..] {
                let distance = hue_distance(a.hsv.hue, b.hsv.hue);
                if distance < 2.0 * d.hue_tolerance_deg {
                    return Err(field(
                        format!("{name_b}.hue"),
                        format!(
                            "is {distance:.0}° from {name_a} ('{}'); colours must be at least twice \
                             detection.hue_tolerance_deg ({}°) apart",
                            a.name, d.hue_tolerance_deg
                        ),
                    ));
                }
            }
        }

        let mut joints: Vec<SuitJoint> = Vec::with_capacity(file.skeleton.len());
        for (i, j) in file.skeleton.iter().enumerate() {
            let at = format!("skeleton[{i}]");
            if joints.iter().any(|k| k.name == j.name) {
                return Err(field(
                    format!("{at}.name"),
                    format!("'{}' appears twice", j.name),
                ));
            }
            if joints.iter().any(|k| k.bvh == j.bvh) {
                return Err(field(
                    format!("{at}.bvh"),
                    format!("'{}' is mapped twice", j.bvh),
                ));
            }
            let parent = match (&j.parent, i) {
                (None, 0) => None,
                (None, _) => {
                    return Err(field(
                        format!("{at}.parent"),
                        "only the first joint (the root) may lack a parent".into(),
                    ))
                }
                (Some(p), 0) => {
                    return Err(field(
                        format!("{at}.parent"),
                        format!("the first joint is the root; it cannot have parent '{p}'"),
                    ))
                }
                (Some(p), _) => {
                    Some(joints.iter().position(|k| &k.name == p).ok_or_else(|| {
                        field(
                            format!("{at}.parent"),
                            format!("'{p}' is not a joint listed before '{}'", j.name),
                        )
                    })?)
                }
            };
            joints.push(SuitJoint {
                name: j.name.clone(),
                parent,
                bvh: j.bvh.clone(),
            });
        }
        if joints.is_empty() {
            return Err(field("skeleton".into(), "lists no joint".into()));
        }

        Ok(SuitDefinition {
            name: file.name,
            marker_size_cm: p.marker_size_cm,
            marker_gap_cm: p.marker_gap_cm,
            layout_seed: p.layout_seed,
            background,
            markers,
            detection: d,
            skeleton: SuitSkeleton { joints },
        })
    }

    /// Distance between the centres of neighbouring markers.
    pub fn pitch_cm(&self) -> f32 {
        self.marker_size_cm + self.marker_gap_cm
    }

    /// Colour index of the marker in grid cell (`row`, `column`) of body surface `surface`: a hash of
    /// the layout seed and the cell, so the pattern is fixed by the suit and independent of who wears it.
    pub fn marker_colour(&self, surface: u32, row: i32, column: u32) -> usize {
        layout_colour(self.layout_seed, self.markers.len(), surface, row, column)
    }
}

/// Colour index of grid cell (`row`, `column`) of `surface` in the layout drawn from `seed` over
/// `colours` marker colours (see [`SuitDefinition::marker_colour`]).
pub fn layout_colour(seed: u64, colours: usize, surface: u32, row: i32, column: u32) -> usize {
    let key = seed ^ (u64::from(surface) << 48) ^ ((row as u32 as u64) << 24) ^ u64::from(column);
    (splitmix64(key) % colours.max(1) as u64) as usize
}

impl SuitSkeleton {
    /// The joints' names (the suit's own, not the BVH's), root first.
    pub fn joint_names(&self) -> Vec<String> {
        self.joints.iter().map(|j| j.name.clone()).collect()
    }

    /// Index in `skeleton` of each suit joint, checking that every name exists and every suit parent
    /// is an ancestor of its child in the BVH hierarchy.
    pub fn bind(&self, skeleton: &Skeleton) -> Result<Vec<usize>, BindError> {
        let mut indices = Vec::with_capacity(self.joints.len());
        for joint in &self.joints {
            let index = skeleton
                .find(&joint.bvh)
                .ok_or_else(|| BindError::UnknownJoint {
                    joint: joint.name.clone(),
                    bvh: joint.bvh.clone(),
                    available: skeleton
                        .joints()
                        .iter()
                        .map(|j| j.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", "),
                })?;
            if let Some(parent) = joint.parent {
                if !skeleton.is_ancestor(indices[parent], index) {
                    let p = &self.joints[parent];
                    return Err(BindError::NotAnAncestor {
                        joint: joint.name.clone(),
                        parent: p.name.clone(),
                        parent_bvh: p.bvh.clone(),
                        bvh: joint.bvh.clone(),
                    });
                }
            }
            indices.push(index);
        }
        Ok(indices)
    }
}

/// SplitMix64 (Steele, Lea, Flood 2014): a fixed, well-mixed 64-bit hash, so layouts never change
/// with a dependency's version.
pub fn splitmix64(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

/// The shipped default suit (`suits/default/suit.toml`), for the unit tests of the modules that
/// draw, print or detect its markers.
#[cfg(test)]
pub(crate) fn shipped_default() -> SuitDefinition {
    SuitDefinition::load_dir(&Path::new(env!("CARGO_MANIFEST_DIR")).join("suits/default"))
        .expect("the shipped default suit loads")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn default_text() -> String {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("suits/default/suit.toml");
        std::fs::read_to_string(path).expect("default suit exists")
    }

    fn parse(text: &str) -> Result<SuitDefinition, SuitError> {
        SuitDefinition::parse(text, Path::new("suit.toml"))
    }

    #[test]
    fn the_default_suit_is_found_from_here_and_from_elsewhere() {
        let tmp = tempfile::tempdir().unwrap();
        let (here, built) = (tmp.path().join("here"), tmp.path().join("built"));
        // Neither holds a suit: the relative path, which loading then names.
        assert_eq!(first_suit_dir(here.clone(), built.clone()), here);
        std::fs::create_dir_all(&built).unwrap();
        std::fs::write(built.join(SUIT_FILE), "").unwrap();
        assert_eq!(first_suit_dir(here.clone(), built.clone()), built);
        std::fs::create_dir_all(&here).unwrap();
        std::fs::write(here.join(SUIT_FILE), "").unwrap();
        assert_eq!(first_suit_dir(here.clone(), built), here);
        // Tests run in the repository, which has the suit.
        assert_eq!(default_suit_dir(), PathBuf::from("suits/default"));
    }

    #[test]
    fn default_suit_is_valid_and_matches_the_design() {
        let suit = parse(&default_text()).expect("valid");
        assert_eq!(suit.marker_size_cm, 4.0);
        assert_eq!(suit.pitch_cm(), 7.0);
        let hues: Vec<f32> = suit.markers.iter().map(|m| m.hsv.hue).collect();
        assert_eq!(hues.len(), 3);
        // The four hues are 90° apart.
        for h in &hues {
            assert_eq!(hue_distance(*h, suit.background.hsv.hue) % 90.0, 0.0);
            assert!(hue_distance(*h, suit.background.hsv.hue) >= 90.0);
        }
        assert_eq!(suit.skeleton.joints[0].parent, None);
    }

    #[test]
    fn default_suit_binds_to_the_shipped_mocap() {
        let suit = parse(&default_text()).expect("valid");
        let clip = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mocap/cmu_09_01_run.bvh");
        let motion = crate::bvh::Motion::load(&clip).expect("clip");
        let indices = suit.skeleton.bind(&motion.skeleton).expect("binds");
        assert_eq!(indices.len(), suit.skeleton.joints.len());
    }

    #[test]
    fn bad_fields_are_named() {
        let text = default_text();
        let cases = [
            (
                text.replacen("hue = 180.0", "hue = 400.0", 1),
                "colours.markers[1].hue",
            ),
            (
                text.replacen("marker_size_cm = 4.0", "marker_size_cm = -4.0", 1),
                "pattern.marker_size_cm",
            ),
            (
                text.replacen("hue = 180.0", "hue = 95.0", 1),
                "colours.markers[1].hue",
            ),
            (
                text.replacen("parent = \"chest\"", "parent = \"nowhere\"", 1),
                ".parent",
            ),
            (text.replacen("format = 1", "format = 7", 1), "format"),
            (
                text.replacen(
                    "[[colours.markers]]",
                    "[[colours.markers]]\nname = \"blue\"\nhue = 225.0\nsaturation = 0.8\nvalue = 0.7\n\n[[colours.markers]]",
                    1,
                ),
                "colours.markers",
            ),
        ];
        for (bad, field) in cases {
            let err = parse(&bad).expect_err(field).to_string();
            assert!(
                err.contains(field) && err.contains("suit.toml"),
                "{field}: {err}"
            );
        }
        assert!(parse("name = 3").is_err());
    }

    #[test]
    fn unknown_bvh_joint_is_a_clear_error() {
        let text = default_text().replacen("bvh = \"rShin\"", "bvh = \"rKnee\"", 1);
        let suit = parse(&text).expect("valid file");
        let clip = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mocap/cmu_09_01_run.bvh");
        let motion = crate::bvh::Motion::load(&clip).expect("clip");
        let err = suit.skeleton.bind(&motion.skeleton).unwrap_err();
        assert!(
            matches!(&err, BindError::UnknownJoint { bvh, .. } if bvh == "rKnee"),
            "{err}"
        );
    }

    #[test]
    fn layout_is_fixed_by_the_seed() {
        let suit = parse(&default_text()).expect("valid");
        let colours: Vec<usize> = (0..300)
            .map(|c| suit.marker_colour(3, c / 20 - 2, c as u32 % 20))
            .collect();
        let again: Vec<usize> = (0..300)
            .map(|c| suit.marker_colour(3, c / 20 - 2, c as u32 % 20))
            .collect();
        assert_eq!(colours, again);
        // All three colours are used in roughly equal shares.
        for k in 0..3 {
            let share = colours.iter().filter(|&&c| c == k).count();
            assert!((70..130).contains(&share), "colour {k}: {share} of 300");
        }
        let mut other = suit.clone();
        other.layout_seed += 1;
        let different = (0..300)
            .filter(|&c| other.marker_colour(3, 0, c) != suit.marker_colour(3, 0, c))
            .count();
        assert!(different > 100);
    }
}
