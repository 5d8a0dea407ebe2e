//! Printable sewing panels of the suit's marker layout at true size (`suitcap suit pattern`).
//!
//! A suit is made to measure: the body model of one subject ([`crate::body`]) decides the size of every
//! patterned part. Each suit-covered [`BodyPart`] (material [`Material::Suit`]) becomes one flat
//! [`Panel`]: its tube is cut open along the seam line s = 0 and laid flat. The vertical axis is u, the
//! centimetres along the bone including both end caps; the horizontal axis is the arc length around,
//! `circumference_at(u) · s`, centred on the panel's middle line, so the left and right outlines are the
//! part's circumference profile and the two edges are sewn together into the tube. On the caps the
//! panel narrows to a rounded point (a half-ellipsoid cannot be flattened; the cloth is gathered there).
//!
//! The markers are drawn where the body model paints them ([`crate::body::MarkerGrid::marker_at`]): in u
//! a `marker_size_cm` band around the row centre, in s the marker's share of its row's perimeter. On the
//! straight part of a limb that is a true 4 × 4 cm square at its (u, s) centre; on a tapering part its
//! sides follow the taper (a fraction of a millimetre), and on the caps the shape narrows with the
//! panel, so what is printed is exactly what the generator renders and the regressor was trained on.
//!
//! Orientation: the printed face is the outside of the suit. The upper end of the part (standing, arms:
//! the shoulder end) is at the top of the panel, and s runs in the direction that makes the print read
//! correctly from outside (not mirrored); notches on both edges mark the ends of the bone.
//!
//! Each panel carries the stitch line (solid; the tube's true perimeter), a 1 cm seam allowance whose
//! outer edge is the cutting line (dashed), the part name and subject, a 10 cm scale bar to check the
//! print size, and optionally each marker's id. Colours are the suit's HSV colours read as sRGB.
//!
//! Output per panel, written atomically into the output directory: `NAME.svg` in true size (width and
//! height in mm, viewBox in mm) and `NAME.png` at the chosen DPI (pixels = cm / 2.54 · dpi, rounded),
//! with the DPI stored in the PNG's `pHYs` chunk (the `image` crate's encoder cannot write it, so the
//! chunk is inserted after `IHDR` here). The PNG labels use a built-in 5 × 7 pixel font (upper case).
//! The writers hand back the list of files written.

use std::f32::consts::FRAC_PI_2;
use std::path::{Path, PathBuf};

use image::{Rgb, RgbImage};

use crate::body::{Body, BodyPart, Material, MissingJoint, Subject};
use crate::bvh::{BvhError, Motion};
use crate::suit::{SuitDefinition, SuitError};

/// Width of the seam allowance around the stitch line.
pub const SEAM_ALLOWANCE_CM: f32 = 1.0;
/// Blank paper around the cutting line.
pub const MARGIN_CM: f32 = 1.0;
/// Height of the strip under the panel with the name, the notes and the scale bar.
pub const FOOTER_CM: f32 = 3.0;
/// Length of the scale bar.
pub const RULER_CM: f32 = 10.0;
/// Narrowest page, so the footer fits beside the scale bar.
pub const MIN_PAGE_WIDTH_CM: f32 = 24.0;
/// Default print resolution.
pub const DEFAULT_DPI: f32 = 150.0;
/// Accepted print resolutions.
pub const MIN_DPI: f32 = 10.0;
pub const MAX_DPI: f32 = 600.0;
/// Largest PNG written, in pixels (about 300 MB of RGB while drawing).
pub const MAX_PIXELS: u64 = 100_000_000;
/// The subject a pattern is made for when none is named.
pub const DEFAULT_SUBJECT: &str = "chidi";
/// Accepted body height and girth of a made-to-measure subject.
pub const HEIGHT_RANGE_CM: (f32, f32) = (100.0, 230.0);
pub const GIRTH_RANGE: (f32, f32) = (0.6, 1.8);

const CM_PER_INCH: f32 = 2.54;
/// Samples per end cap of the outline (uniform in the cap's angle, so the ends come out round).
const CAP_STEPS: usize = 24;
/// Longest step of the outline along the straight section.
const OUTLINE_STEP_CM: f32 = 1.0;
/// Samples per marker side along u.
const MARKER_SIDE_STEPS: usize = 8;
const INK: [u8; 3] = [25, 25, 25];
const PAPER: [u8; 3] = [255, 255, 255];

/// A point on the page in centimetres: x to the right, y down, origin at the top left corner.
pub type Point = [f32; 2];

/// What to draw.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatternOptions {
    /// PNG resolution in dots per inch.
    pub dpi: f32,
    /// Write each marker's id on it.
    pub marker_ids: bool,
}

impl Default for PatternOptions {
    fn default() -> Self {
        PatternOptions {
            dpi: DEFAULT_DPI,
            marker_ids: false,
        }
    }
}

/// One marker as drawn on a panel.
#[derive(Clone, Debug, PartialEq)]
pub struct PanelMarker {
    /// The marker's id ([`crate::body::MarkerCell::id`]).
    pub id: u32,
    /// sRGB colour.
    pub colour: [u8; 3],
    pub centre: Point,
    /// Closed outline (page cm).
    pub outline: Vec<Point>,
}

/// One flat sewing panel of one body part, in page centimetres.
#[derive(Clone, Debug, PartialEq)]
pub struct Panel {
    /// The body part's name, also the file stem.
    pub name: String,
    /// Notes printed under the name.
    pub notes: Vec<String>,
    pub width_cm: f32,
    pub height_cm: f32,
    /// sRGB colour of the cloth.
    pub cloth: [u8; 3],
    /// The stitch line: the tube's perimeter profile (closed polygon).
    pub stitch: Vec<Point>,
    /// The cutting line, `SEAM_ALLOWANCE_CM` outside the stitch line (closed polygon).
    pub cut: Vec<Point>,
    /// Short marks across the allowance at the two ends of the bone.
    pub notches: Vec<[Point; 2]>,
    pub markers: Vec<PanelMarker>,
    /// Top of the footer strip.
    pub footer_top: f32,
}

/// A pattern that cannot be made; names the file or the option at fault.
#[derive(Debug, thiserror::Error)]
pub enum PatternError {
    #[error(transparent)]
    Suit(#[from] SuitError),
    #[error(transparent)]
    Bvh(#[from] BvhError),
    #[error("{path}: {source}")]
    Body { path: PathBuf, source: MissingJoint },
    #[error(
        "unknown subject '{0}'; built-in subjects: ana, ben, chidi, dana, emil, fumiko (or 0..5)"
    )]
    UnknownSubject(String),
    #[error("{option}: {message}")]
    Option {
        option: &'static str,
        message: String,
    },
    #[error("panel '{part}': {width}x{height} pixels at {dpi} dpi is more than {MAX_PIXELS}; choose a lower --dpi")]
    TooLarge {
        part: String,
        width: u32,
        height: u32,
        dpi: f32,
    },
    #[error("{path}: cannot write: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: cannot encode the PNG: {message}")]
    Encode { path: PathBuf, message: String },
}

/// The subject a pattern is made for: a built-in subject by name or index (default
/// [`DEFAULT_SUBJECT`]), with its height and girth replaced by the measurements given (the result is
/// then called "custom" and keeps the named subject's limb ratios).
pub fn pattern_subject(
    name: Option<&str>,
    height_cm: Option<f32>,
    girth: Option<f32>,
) -> Result<Subject, PatternError> {
    let base_name = name.unwrap_or(DEFAULT_SUBJECT);
    let mut subject = Subject::find(base_name)
        .ok_or_else(|| PatternError::UnknownSubject(base_name.to_owned()))?
        .clone();
    if let Some(h) = height_cm {
        let (lo, hi) = HEIGHT_RANGE_CM;
        if !(lo..=hi).contains(&h) {
            return Err(PatternError::Option {
                option: "--height",
                message: format!("{h} cm is not in {lo}..={hi} cm"),
            });
        }
        subject.height_cm = h;
        subject.name = "custom";
    }
    if let Some(g) = girth {
        let (lo, hi) = GIRTH_RANGE;
        if !(lo..=hi).contains(&g) {
            return Err(PatternError::Option {
                option: "--girth",
                message: format!("{g} is not in {lo}..={hi} (1 = the base figure's build)"),
            });
        }
        subject.girth = g;
        subject.name = "custom";
    }
    Ok(subject)
}

/// Checks the print resolution.
pub fn check_dpi(dpi: f32) -> Result<(), PatternError> {
    if !(MIN_DPI..=MAX_DPI).contains(&dpi) {
        return Err(PatternError::Option {
            option: "--dpi",
            message: format!("{dpi} is not in {MIN_DPI}..={MAX_DPI}"),
        });
    }
    Ok(())
}

/// Writes the panels of every suit part of `subject`'s body for the suit in `suit_dir` (its
/// `suit.toml` and the training skeleton `skeleton.bvh`) into `out_dir` (created if needed).
pub fn write_suit_pattern(
    suit_dir: &Path,
    subject: &Subject,
    out_dir: &Path,
    options: &PatternOptions,
) -> Result<Vec<PathBuf>, PatternError> {
    check_dpi(options.dpi)?;
    let suit = SuitDefinition::load_dir(suit_dir)?;
    let skeleton_path = suit_dir.join(crate::pose::regressor::SKELETON_FILE);
    let motion = Motion::load(&skeleton_path)?;
    // The suit's skeleton is the regressor's template, already scaled to one training subject:
    // bring it back to the base figure's height before scaling it to this subject.
    let to_base =
        crate::body::BASE_HEIGHT_CM / crate::body_size::skeleton_height_cm(&motion.skeleton);
    let base = motion.skeleton.map_offsets(|_, offset| offset * to_base);
    let skeleton = subject.scale_skeleton(&base);
    let body = Body::new(subject, &skeleton).map_err(|source| PatternError::Body {
        path: skeleton_path,
        source,
    })?;
    write_body_pattern(&suit, &body, subject, out_dir, options)
}

/// Writes one SVG and one PNG per suit part of `body` into `out_dir` (created if needed).
pub fn write_body_pattern(
    suit: &SuitDefinition,
    body: &Body,
    subject: &Subject,
    out_dir: &Path,
    options: &PatternOptions,
) -> Result<Vec<PathBuf>, PatternError> {
    check_dpi(options.dpi)?;
    let note = subject_note(subject);
    let panels: Vec<Panel> = (0..body.parts.len())
        .filter(|&index| body.parts[index].material == Material::Suit)
        .map(|index| panel(suit, body, index, &note))
        .collect();
    // Refuse an oversized print before writing anything.
    for p in &panels {
        check_png_size(p, options.dpi)?;
    }
    std::fs::create_dir_all(out_dir).map_err(|source| PatternError::Write {
        path: out_dir.to_owned(),
        source,
    })?;
    let mut written = Vec::new();
    for p in &panels {
        written.extend(write_panel(p, out_dir, options)?);
    }
    Ok(written)
}

/// The subject line printed on every panel.
pub fn subject_note(subject: &Subject) -> String {
    format!(
        "subject {}: {:.0} cm, girth {:.2}, arms x{:.2}, legs x{:.2}",
        subject.name, subject.height_cm, subject.girth, subject.arm_ratio, subject.leg_ratio
    )
}

/// Writes `DIR/NAME.svg` and `DIR/NAME.png` of one panel; returns both paths.
pub fn write_panel(
    panel: &Panel,
    out_dir: &Path,
    options: &PatternOptions,
) -> Result<Vec<PathBuf>, PatternError> {
    check_dpi(options.dpi)?;
    let svg_path = out_dir.join(format!("{}.svg", panel.name));
    let png_path = out_dir.join(format!("{}.png", panel.name));
    let image = panel_png(panel, options.dpi, options.marker_ids)?;
    let png = encode_png(&image, options.dpi).map_err(|message| PatternError::Encode {
        path: png_path.clone(),
        message,
    })?;
    let svg = panel_svg(panel, options.marker_ids);
    for (path, bytes) in [(&svg_path, svg.as_bytes()), (&png_path, &png[..])] {
        crate::io::write_atomic(path, bytes).map_err(|source| PatternError::Write {
            path: path.clone(),
            source,
        })?;
    }
    Ok(vec![svg_path, png_path])
}

/// sRGB bytes of a suit colour.
fn srgb8(hsv: crate::colour::Hsv) -> [u8; 3] {
    hsv.to_rgb()
        .map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8)
}

/// Where (u, s) of a part lands on its panel.
#[derive(Clone, Copy, Debug)]
struct Placement {
    u_min: f32,
    u_max: f32,
    /// u grows upwards on the page (the part's end is its upper end).
    flipped: bool,
    x_centre: f32,
    y_top: f32,
}

impl Placement {
    fn new(part: &BodyPart, x_centre: f32, y_top: f32) -> Placement {
        let (cap_start, cap_end) = part.cap_lengths();
        let axis = (part.end - part.start).normalize_or_zero();
        Placement {
            u_min: -cap_start,
            u_max: part.length() + cap_end,
            flipped: axis.y > 0.5,
            x_centre,
            y_top,
        }
    }

    fn y(&self, u: f32) -> f32 {
        if self.flipped {
            self.y_top + (self.u_max - u)
        } else {
            self.y_top + (u - self.u_min)
        }
    }

    /// Page position of surface point (u, s). Viewed from outside with u pointing up the page, s grows
    /// to the right (the cross-section turns from its first axis towards `axis × first axis`), so a
    /// panel with u pointing down runs s to the left.
    fn point(&self, part: &BodyPart, u: f32, s: f32) -> Point {
        let direction = if self.flipped { 1.0 } else { -1.0 };
        [
            self.x_centre + direction * (s - 0.5) * part.circumference_at(u),
            self.y(u),
        ]
    }
}

/// The u values at which the outline is sampled: round caps, ≤ 1 cm steps along the bone.
fn outline_samples(part: &BodyPart) -> Vec<f32> {
    let (cap_start, cap_end) = part.cap_lengths();
    let length = part.length();
    let mut us = Vec::new();
    for k in 0..CAP_STEPS {
        let psi = FRAC_PI_2 * (CAP_STEPS - k) as f32 / CAP_STEPS as f32;
        us.push(-cap_start * psi.sin());
    }
    let sections = ((length / OUTLINE_STEP_CM).ceil() as usize).max(1);
    for k in 0..=sections {
        us.push(length * k as f32 / sections as f32);
    }
    for k in 1..=CAP_STEPS {
        let psi = FRAC_PI_2 * k as f32 / CAP_STEPS as f32;
        us.push(length + cap_end * psi.sin());
    }
    us.dedup();
    us
}

/// Removes consecutive (and closing) points closer than 1 µm.
fn dedup_closed(mut points: Vec<Point>) -> Vec<Point> {
    let near = |a: Point, b: Point| (a[0] - b[0]).abs() < 1e-4 && (a[1] - b[1]).abs() < 1e-4;
    points.dedup_by(|b, a| near(*a, *b));
    while points.len() > 1 && near(points[0], points[points.len() - 1]) {
        points.pop();
    }
    points
}

/// Twice the signed area of a closed polygon.
fn signed_area2(points: &[Point]) -> f32 {
    (0..points.len())
        .map(|i| {
            let (a, b) = (points[i], points[(i + 1) % points.len()]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum()
}

/// The closed polygon `distance` outside `points` (mitred corners, miters limited to 3 × distance).
pub fn offset_polygon(points: &[Point], distance: f32) -> Vec<Point> {
    let n = points.len();
    if n < 3 {
        return points.to_vec();
    }
    let sign = if signed_area2(points) >= 0.0 {
        1.0
    } else {
        -1.0
    };
    let normal = |a: Point, b: Point| -> Point {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let len = (dx * dx + dy * dy).sqrt().max(1e-9);
        [sign * dy / len, -sign * dx / len]
    };
    (0..n)
        .map(|i| {
            let (prev, here, next) = (points[(i + n - 1) % n], points[i], points[(i + 1) % n]);
            let (n1, n2) = (normal(prev, here), normal(here, next));
            let sum = [n1[0] + n2[0], n1[1] + n2[1]];
            let len = (sum[0] * sum[0] + sum[1] * sum[1]).sqrt();
            let m = if len > 1e-6 {
                [sum[0] / len, sum[1] / len]
            } else {
                n1
            };
            let cos = (m[0] * n1[0] + m[1] * n1[1]).max(1.0 / 3.0);
            let d = distance / cos;
            [here[0] + m[0] * d, here[1] + m[1] * d]
        })
        .collect()
}

/// The flat panel of part `index` of `body` for `suit`, with the markers printed on it
/// ([`Body::marker_grid`]); `subject` is the line naming who it is made for.
pub fn panel(suit: &SuitDefinition, body: &Body, index: usize, subject: &str) -> Panel {
    let part = &body.parts[index];
    let us = outline_samples(part);
    let widest = us
        .iter()
        .map(|&u| part.circumference_at(u))
        .fold(0.0f32, f32::max);
    let border = MARGIN_CM + SEAM_ALLOWANCE_CM;
    let width_cm = (widest + 2.0 * border).max(MIN_PAGE_WIDTH_CM);
    let place = Placement::new(part, width_cm * 0.5, border);
    let total = place.u_max - place.u_min;
    let footer_top = border + total + SEAM_ALLOWANCE_CM;
    let height_cm = footer_top + MARGIN_CM + FOOTER_CM;

    let mut stitch: Vec<Point> = us.iter().map(|&u| place.point(part, u, 0.0)).collect();
    stitch.extend(us.iter().rev().map(|&u| place.point(part, u, 1.0)));
    let stitch = dedup_closed(stitch);
    let cut = offset_polygon(&stitch, SEAM_ALLOWANCE_CM);

    let mut notches = Vec::new();
    for u in [0.0, part.length()] {
        for s in [0.0, 1.0] {
            let p = place.point(part, u, s);
            let outward = if p[0] < place.x_centre { -1.0 } else { 1.0 };
            notches.push([p, [p[0] + outward * SEAM_ALLOWANCE_CM, p[1]]]);
        }
    }

    let grid = body.marker_grid(index, suit);
    let half = suit.marker_size_cm * 0.5;
    let markers: Vec<PanelMarker> = grid
        .cells()
        .map(|cell| {
            let ds = half / part.circumference_at(cell.centre_u).max(1e-6);
            let side = |s: f32| {
                (0..=MARKER_SIDE_STEPS)
                    .map(move |k| {
                        cell.centre_u - half + 2.0 * half * k as f32 / MARKER_SIDE_STEPS as f32
                    })
                    .map(move |u| (u, s))
            };
            let mut outline: Vec<Point> = side(cell.centre_s - ds)
                .map(|(u, s)| place.point(part, u, s))
                .collect();
            let back: Vec<(f32, f32)> = side(cell.centre_s + ds).collect();
            outline.extend(back.into_iter().rev().map(|(u, s)| place.point(part, u, s)));
            PanelMarker {
                id: cell.id,
                colour: suit
                    .markers
                    .get(cell.colour)
                    .map(|c| srgb8(c.hsv))
                    .unwrap_or(INK),
                centre: place.point(part, cell.centre_u, cell.centre_s),
                outline,
            }
        })
        .collect();

    let notes = vec![
        format!(
            "{subject}; suit '{}': {} markers, {} cm on a {} cm grid",
            suit.name,
            markers.len(),
            suit.marker_size_cm,
            suit.pitch_cm()
        ),
        format!(
            "print at 100 %: the bar is {RULER_CM} cm. Cut on the dashed line ({SEAM_ALLOWANCE_CM} cm allowance), sew on the solid line."
        ),
        "Left and right edges join into a tube, print outside. Top = upper end (arms: shoulder). Notches: bone ends."
            .to_owned(),
    ];

    Panel {
        name: part.name.to_owned(),
        notes,
        width_cm,
        height_cm,
        cloth: srgb8(suit.background.hsv),
        stitch,
        cut,
        notches,
        markers,
        footer_top,
    }
}

/// Positions of the footer's items, shared by the SVG and the PNG.
struct Footer {
    name_at: Point,
    name_height: f32,
    notes: Vec<(Point, f32)>,
    ruler_at: Point,
    ruler_height: f32,
    ruler_label_at: Point,
    label_height: f32,
}

/// Glyph advance of the built-in font as a multiple of the text height.
const ADVANCE: f32 = 6.0 / 7.0;

fn footer(panel: &Panel) -> Footer {
    let top = panel.footer_top;
    let left = MARGIN_CM;
    let usable = panel.width_cm - 2.0 * MARGIN_CM;
    let fit = |text: &str, width: f32, height: f32| {
        height.min(width / (text.chars().count().max(1) as f32 * ADVANCE))
    };
    let name_height = fit(&panel.name, usable - RULER_CM - 1.0, 0.8);
    let notes = panel
        .notes
        .iter()
        .enumerate()
        .map(|(i, note)| ([left, top + 1.25 + 0.5 * i as f32], fit(note, usable, 0.32)))
        .collect();
    let ruler_x = panel.width_cm - MARGIN_CM - RULER_CM;
    Footer {
        name_at: [left, top + 0.2],
        name_height,
        notes,
        ruler_at: [ruler_x, top + 0.2],
        ruler_height: 0.4,
        ruler_label_at: [ruler_x, top + 0.7],
        label_height: 0.3,
    }
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn hex([r, g, b]: [u8; 3]) -> String {
    format!("#{r:02x}{g:02x}{b:02x}")
}

/// Black or white, whichever reads better on `colour`.
fn label_colour([r, g, b]: [u8; 3]) -> [u8; 3] {
    let luma = 0.299 * f32::from(r) + 0.587 * f32::from(g) + 0.114 * f32::from(b);
    if luma > 140.0 {
        INK
    } else {
        PAPER
    }
}

fn svg_points(points: &[Point]) -> String {
    points
        .iter()
        .map(|p| format!("{:.2},{:.2}", p[0] * 10.0, p[1] * 10.0))
        .collect::<Vec<_>>()
        .join(" ")
}

/// The panel as an SVG document in true size: every coordinate in millimetres.
pub fn panel_svg(panel: &Panel, marker_ids: bool) -> String {
    use std::fmt::Write as _;
    let mm = |cm: f32| cm * 10.0;
    let (w, h) = (mm(panel.width_cm), mm(panel.height_cm));
    let mut s = String::new();
    let _ = writeln!(s, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w:.2}mm" height="{h:.2}mm" viewBox="0 0 {w:.2} {h:.2}">"#
    );
    let _ = writeln!(s, "<title>{}</title>", escape(&panel.name));
    let _ = writeln!(
        s,
        r##"<rect x="0" y="0" width="{w:.2}" height="{h:.2}" fill="#ffffff"/>"##
    );
    let cloth = hex(panel.cloth);
    let _ = writeln!(
        s,
        r#"<polygon id="allowance" points="{}" fill="{cloth}" stroke="none"/>"#,
        svg_points(&panel.cut)
    );
    let _ = writeln!(s, r#"<g id="markers" stroke="none">"#);
    for m in &panel.markers {
        let _ = writeln!(
            s,
            r#"<polygon id="m{}" points="{}" fill="{}"/>"#,
            m.id,
            svg_points(&m.outline),
            hex(m.colour)
        );
    }
    let _ = writeln!(s, "</g>");
    let ink = hex(INK);
    let _ = writeln!(
        s,
        r#"<polygon id="stitch" points="{}" fill="none" stroke="{ink}" stroke-width="0.4"/>"#,
        svg_points(&panel.stitch)
    );
    let _ = writeln!(
        s,
        r#"<polygon id="cut" points="{}" fill="none" stroke="{ink}" stroke-width="0.5" stroke-dasharray="5 3"/>"#,
        svg_points(&panel.cut)
    );
    for [a, b] in &panel.notches {
        let _ = writeln!(
            s,
            r#"<line x1="{:.2}" y1="{:.2}" x2="{:.2}" y2="{:.2}" stroke="{ink}" stroke-width="0.6"/>"#,
            mm(a[0]),
            mm(a[1]),
            mm(b[0]),
            mm(b[1])
        );
    }
    if marker_ids {
        let _ = writeln!(
            s,
            r#"<g id="marker-ids" font-family="sans-serif" font-size="6" text-anchor="middle" dominant-baseline="central">"#
        );
        for m in &panel.markers {
            let _ = writeln!(
                s,
                r#"<text x="{:.2}" y="{:.2}" fill="{}">{}</text>"#,
                mm(m.centre[0]),
                mm(m.centre[1]),
                hex(label_colour(m.colour)),
                m.id
            );
        }
        let _ = writeln!(s, "</g>");
    }
    let f = footer(panel);
    let text = |s: &mut String, at: Point, height: f32, content: &str| {
        // The SVG's baseline sits at the bottom of the built-in font's cell.
        let _ = writeln!(
            s,
            r#"<text x="{:.2}" y="{:.2}" font-family="sans-serif" font-size="{:.2}" fill="{ink}">{}</text>"#,
            mm(at[0]),
            mm(at[1] + height),
            mm(height * 1.2),
            escape(content)
        );
    };
    text(&mut s, f.name_at, f.name_height, &panel.name);
    for (note, (at, height)) in panel.notes.iter().zip(&f.notes) {
        text(&mut s, *at, *height, note);
    }
    let _ = writeln!(s, r#"<g id="scale-bar">"#);
    for k in 0..RULER_CM as usize {
        let fill = if k % 2 == 0 { ink.as_str() } else { "#ffffff" };
        let _ = writeln!(
            s,
            r#"<rect x="{:.2}" y="{:.2}" width="10" height="{:.2}" fill="{fill}"/>"#,
            mm(f.ruler_at[0] + k as f32),
            mm(f.ruler_at[1]),
            mm(f.ruler_height)
        );
    }
    let _ = writeln!(
        s,
        r#"<rect x="{:.2}" y="{:.2}" width="{:.2}" height="{:.2}" fill="none" stroke="{ink}" stroke-width="0.2"/>"#,
        mm(f.ruler_at[0]),
        mm(f.ruler_at[1]),
        mm(RULER_CM),
        mm(f.ruler_height)
    );
    let _ = writeln!(s, "</g>");
    text(
        &mut s,
        f.ruler_label_at,
        f.label_height,
        &format!("{RULER_CM} cm"),
    );
    let _ = writeln!(s, "</svg>");
    s
}

/// Pixels covering `cm` at `dpi`.
pub fn png_pixels(cm: f32, dpi: f32) -> u32 {
    (cm / CM_PER_INCH * dpi).round().max(1.0) as u32
}

/// The panel's PNG size at `dpi`, checked against the DPI range and [`MAX_PIXELS`].
pub fn check_png_size(panel: &Panel, dpi: f32) -> Result<(u32, u32), PatternError> {
    check_dpi(dpi)?;
    let (w, h) = (
        png_pixels(panel.width_cm, dpi),
        png_pixels(panel.height_cm, dpi),
    );
    if u64::from(w) * u64::from(h) > MAX_PIXELS {
        return Err(PatternError::TooLarge {
            part: panel.name.clone(),
            width: w,
            height: h,
            dpi,
        });
    }
    Ok((w, h))
}

/// The panel as an image at `dpi` (checked against [`MAX_PIXELS`]).
pub fn panel_png(panel: &Panel, dpi: f32, marker_ids: bool) -> Result<RgbImage, PatternError> {
    let (w, h) = check_png_size(panel, dpi)?;
    let k = dpi / CM_PER_INCH;
    let px = |p: &Point| [p[0] * k, p[1] * k];
    let to_px = |points: &[Point]| points.iter().map(px).collect::<Vec<_>>();
    let mut img = RgbImage::from_pixel(w, h, Rgb(PAPER));
    fill_polygon(&mut img, &to_px(&panel.cut), panel.cloth);
    for m in &panel.markers {
        fill_polygon(&mut img, &to_px(&m.outline), m.colour);
    }
    let thin = (0.04 * k).max(1.0);
    stroke_closed(&mut img, &to_px(&panel.stitch), thin, None, INK);
    stroke_closed(
        &mut img,
        &to_px(&panel.cut),
        (0.05 * k).max(1.0),
        Some((0.5 * k, 0.3 * k)),
        INK,
    );
    for [a, b] in &panel.notches {
        draw_segment(&mut img, px(a), px(b), (0.06 * k).max(1.0), INK);
    }
    if marker_ids {
        for m in &panel.markers {
            let text = m.id.to_string();
            let height = 0.5 * k;
            let width = text.len() as f32 * ADVANCE * height;
            let at = [
                m.centre[0] * k - width * 0.5,
                m.centre[1] * k - height * 0.5,
            ];
            draw_text(&mut img, &text, at, height, label_colour(m.colour));
        }
    }
    let f = footer(panel);
    draw_text(
        &mut img,
        &panel.name,
        px(&f.name_at),
        f.name_height * k,
        INK,
    );
    for (note, (at, height)) in panel.notes.iter().zip(&f.notes) {
        draw_text(&mut img, note, px(at), height * k, INK);
    }
    for cell in 0..RULER_CM as usize {
        let x0 = f.ruler_at[0] + cell as f32;
        let colour = if cell % 2 == 0 { INK } else { PAPER };
        fill_rect(
            &mut img,
            [x0 * k, f.ruler_at[1] * k],
            [(x0 + 1.0) * k, (f.ruler_at[1] + f.ruler_height) * k],
            colour,
        );
    }
    let (x0, y0) = (f.ruler_at[0], f.ruler_at[1]);
    let corners = [
        [x0, y0],
        [x0 + RULER_CM, y0],
        [x0 + RULER_CM, y0 + f.ruler_height],
        [x0, y0 + f.ruler_height],
    ];
    stroke_closed(&mut img, &to_px(&corners), thin, None, INK);
    draw_text(
        &mut img,
        &format!("{RULER_CM} cm"),
        px(&f.ruler_label_at),
        f.label_height * k,
        INK,
    );
    Ok(img)
}

/// Fills pixels whose centres lie inside the closed polygon (even-odd rule), coordinates in pixels.
fn fill_polygon(img: &mut RgbImage, points: &[[f32; 2]], colour: [u8; 3]) {
    if points.len() < 3 {
        return;
    }
    let (w, h) = img.dimensions();
    let y_min = points.iter().map(|p| p[1]).fold(f32::INFINITY, f32::min);
    let y_max = points
        .iter()
        .map(|p| p[1])
        .fold(f32::NEG_INFINITY, f32::max);
    let first_row = (y_min - 0.5).ceil().max(0.0) as u32;
    let end_row = ((y_max - 0.5).floor() + 1.0).clamp(0.0, h as f32) as u32;
    let mut crossings = Vec::new();
    for row in first_row..end_row {
        let yc = row as f32 + 0.5;
        crossings.clear();
        for i in 0..points.len() {
            let (a, b) = (points[i], points[(i + 1) % points.len()]);
            if (a[1] <= yc) != (b[1] <= yc) {
                crossings.push(a[0] + (yc - a[1]) / (b[1] - a[1]) * (b[0] - a[0]));
            }
        }
        crossings.sort_by(f32::total_cmp);
        for pair in crossings.chunks_exact(2) {
            let start = (pair[0] - 0.5).ceil().clamp(0.0, w as f32) as u32;
            let end = (pair[1] - 0.5).ceil().clamp(0.0, w as f32) as u32;
            for x in start..end {
                img.put_pixel(x, row, Rgb(colour));
            }
        }
    }
}

/// Fills the axis-aligned box between two corners (pixels).
fn fill_rect(img: &mut RgbImage, a: [f32; 2], b: [f32; 2], colour: [u8; 3]) {
    fill_polygon(img, &[a, [b[0], a[1]], b, [a[0], b[1]]], colour);
}

/// Paints pixels whose centres are within `width / 2` of the segment a–b (pixels).
fn draw_segment(img: &mut RgbImage, a: [f32; 2], b: [f32; 2], width: f32, colour: [u8; 3]) {
    let (w, h) = img.dimensions();
    let r = 0.5 * width.max(1.0);
    let x0 = (a[0].min(b[0]) - r).floor().max(0.0) as u32;
    let y0 = (a[1].min(b[1]) - r).floor().max(0.0) as u32;
    let x1 = ((a[0].max(b[0]) + r).ceil().max(0.0) as u32).min(w);
    let y1 = ((a[1].max(b[1]) + r).ceil().max(0.0) as u32).min(h);
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = (dx * dx + dy * dy).max(1e-12);
    for y in y0..y1 {
        for x in x0..x1 {
            let (px, py) = (x as f32 + 0.5, y as f32 + 0.5);
            let t = (((px - a[0]) * dx + (py - a[1]) * dy) / len2).clamp(0.0, 1.0);
            let (ex, ey) = (a[0] + t * dx - px, a[1] + t * dy - py);
            if ex * ex + ey * ey <= r * r {
                img.put_pixel(x, y, Rgb(colour));
            }
        }
    }
}

/// Strokes a closed polyline, solid or dashed (`(on, off)` lengths in pixels).
fn stroke_closed(
    img: &mut RgbImage,
    points: &[[f32; 2]],
    width: f32,
    dash: Option<(f32, f32)>,
    colour: [u8; 3],
) {
    let n = points.len();
    if n < 2 {
        return;
    }
    // Distance along the dash pattern at the start of the current segment.
    let mut phase = 0.0f32;
    for i in 0..n {
        let (a, b) = (points[i], points[(i + 1) % n]);
        let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
        match dash {
            None => draw_segment(img, a, b, width, colour),
            Some((on, off)) => {
                let period = (on + off).max(1e-3);
                let mut t = 0.0;
                while t < len {
                    let in_period = (phase + t) % period;
                    let (is_on, left) = if in_period < on {
                        (true, on - in_period)
                    } else {
                        (false, period - in_period)
                    };
                    let step = left.min(len - t).max(1e-3);
                    if is_on {
                        let at = |s: f32| {
                            [
                                a[0] + (b[0] - a[0]) * s / len,
                                a[1] + (b[1] - a[1]) * s / len,
                            ]
                        };
                        draw_segment(img, at(t), at(t + step), width, colour);
                    }
                    t += step;
                }
                phase = (phase + len) % period;
            }
        }
    }
}

/// The built-in 5 × 7 font: rows top to bottom, bit 4 = leftmost column. Lower case is drawn as
/// upper case; unknown characters as '?'.
fn glyph(c: char) -> [u8; 7] {
    match c.to_ascii_uppercase() {
        '0' => [0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E],
        '1' => [0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E],
        '2' => [0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F],
        '3' => [0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E],
        '4' => [0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02],
        '5' => [0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E],
        '6' => [0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E],
        '7' => [0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08],
        '8' => [0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E],
        '9' => [0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C],
        'A' => [0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11],
        'B' => [0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E],
        'C' => [0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E],
        'D' => [0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C],
        'E' => [0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F],
        'F' => [0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10],
        'G' => [0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F],
        'H' => [0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11],
        'I' => [0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E],
        'J' => [0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C],
        'K' => [0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11],
        'L' => [0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F],
        'M' => [0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11],
        'N' => [0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11],
        'O' => [0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E],
        'P' => [0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10],
        'Q' => [0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D],
        'R' => [0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11],
        'S' => [0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E],
        'T' => [0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04],
        'U' => [0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E],
        'V' => [0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04],
        'W' => [0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A],
        'X' => [0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11],
        'Y' => [0x11, 0x11, 0x11, 0x0A, 0x04, 0x04, 0x04],
        'Z' => [0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F],
        ' ' => [0; 7],
        '_' => [0, 0, 0, 0, 0, 0, 0x1F],
        '-' => [0, 0, 0, 0x1F, 0, 0, 0],
        '.' => [0, 0, 0, 0, 0, 0x0C, 0x0C],
        ',' => [0, 0, 0, 0, 0x0C, 0x04, 0x08],
        ':' => [0, 0x0C, 0x0C, 0, 0x0C, 0x0C, 0],
        ';' => [0, 0x0C, 0x0C, 0, 0x0C, 0x04, 0x08],
        '=' => [0, 0, 0x1F, 0, 0x1F, 0, 0],
        '/' => [0, 0x01, 0x02, 0x04, 0x08, 0x10, 0],
        '(' => [0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02],
        ')' => [0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08],
        '%' => [0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03],
        '\'' => [0x04, 0x04, 0x08, 0, 0, 0, 0],
        _ => [0x0E, 0x11, 0x01, 0x02, 0x04, 0, 0x04],
    }
}

/// Draws `text` with its top-left corner at `at` (pixels), glyphs `height` pixels tall.
fn draw_text(img: &mut RgbImage, text: &str, at: [f32; 2], height: f32, colour: [u8; 3]) {
    let cell = height / 7.0;
    for (i, c) in text.chars().enumerate() {
        let left = at[0] + i as f32 * 6.0 * cell;
        for (row, bits) in glyph(c).iter().enumerate() {
            for col in 0..5 {
                if bits & (0x10 >> col) != 0 {
                    let x = left + col as f32 * cell;
                    let y = at[1] + row as f32 * cell;
                    // At least one pixel per font cell, so small text stays legible.
                    let size = cell.max(1.0);
                    fill_rect(img, [x, y], [x + size, y + size], colour);
                }
            }
        }
    }
}

/// CRC-32 (ISO-HDLC, as PNG uses) of `bytes`.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = 0xFFFF_FFFFu32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

const PNG_SIGNATURE: &[u8; 8] = b"\x89PNG\r\n\x1a\n";

/// One PNG chunk: its type and its data.
pub type PngChunk<'a> = ([u8; 4], &'a [u8]);

/// The chunks of a PNG as (type, data), or why they cannot be read.
pub fn png_chunks(png: &[u8]) -> Result<Vec<PngChunk<'_>>, String> {
    if png.len() < 8 || &png[..8] != PNG_SIGNATURE {
        return Err("not a PNG (bad signature)".into());
    }
    let mut chunks = Vec::new();
    let mut at = 8usize;
    while at < png.len() {
        let header = png
            .get(at..at + 8)
            .ok_or_else(|| format!("chunk header at byte {at} is truncated"))?;
        let len = u32::from_be_bytes([header[0], header[1], header[2], header[3]]) as usize;
        let kind = [header[4], header[5], header[6], header[7]];
        let data = at
            .checked_add(8 + len)
            .and_then(|end| png.get(at + 8..end))
            .ok_or_else(|| format!("chunk at byte {at} is truncated"))?;
        chunks.push((kind, data));
        at += 12 + len;
    }
    Ok(chunks)
}

/// Encodes `image` as PNG with a `pHYs` chunk saying `dpi` (in pixels per metre, as PNG stores it).
pub fn encode_png(image: &RgbImage, dpi: f32) -> Result<Vec<u8>, String> {
    let mut plain = Vec::new();
    image
        .write_to(
            &mut std::io::Cursor::new(&mut plain),
            image::ImageFormat::Png,
        )
        .map_err(|e| e.to_string())?;
    let chunks = png_chunks(&plain)?;
    if chunks.first().map(|c| &c.0) != Some(b"IHDR") {
        return Err("the encoder's PNG does not start with IHDR".into());
    }
    let per_metre = (dpi / 0.0254).round() as u32;
    let mut phys = Vec::with_capacity(9);
    phys.extend_from_slice(&per_metre.to_be_bytes());
    phys.extend_from_slice(&per_metre.to_be_bytes());
    phys.push(1); // unit: metre
    let mut out = Vec::with_capacity(plain.len() + 21);
    out.extend_from_slice(PNG_SIGNATURE);
    let mut put = |kind: &[u8; 4], data: &[u8]| {
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let start = out.len();
        out.extend_from_slice(kind);
        out.extend_from_slice(data);
        let crc = crc32(&out[start..]);
        out.extend_from_slice(&crc.to_be_bytes());
    };
    for (i, (kind, data)) in chunks.iter().enumerate() {
        if kind == b"pHYs" {
            continue;
        }
        put(kind, data);
        if i == 0 {
            put(b"pHYs", &phys);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::test_cylinder as cylinder;
    use crate::suit::shipped_default as suit;

    /// The cylinder alone, as a body.
    fn lone_cylinder() -> Body {
        Body {
            parts: vec![cylinder()],
            rest_pose: vec![glam::Affine3A::IDENTITY],
        }
    }

    const PERIMETER: f32 = std::f32::consts::TAU * 10.0; // 62.83 cm

    fn attribute(svg: &str, name: &str) -> String {
        let key = format!(" {name}=\"");
        let start = svg.find(&key).expect(name) + key.len();
        let end = svg[start..].find('"').expect("closing quote") + start;
        svg[start..end].to_owned()
    }

    #[test]
    fn cylinder_panel_has_true_size_in_svg_and_png() {
        let p = panel(&suit(), &lone_cylinder(), 0, "subject test");
        // Width: perimeter + 2 × (1 cm allowance + 1 cm margin) = 66.83 cm; height: 50 cm of tube
        // (30 + two 10 cm caps) + 4 cm + 3 cm footer = 57 cm.
        assert!(
            (p.width_cm - (PERIMETER + 4.0)).abs() < 0.02,
            "{}",
            p.width_cm
        );
        assert!((p.height_cm - 57.0).abs() < 1e-4, "{}", p.height_cm);
        let svg = panel_svg(&p, true);
        let width: f32 = attribute(&svg, "width")
            .trim_end_matches("mm")
            .parse()
            .expect("mm");
        let height: f32 = attribute(&svg, "height")
            .trim_end_matches("mm")
            .parse()
            .expect("mm");
        assert!(attribute(&svg, "width").ends_with("mm"));
        assert!((width - 668.3).abs() < 0.2, "{width}");
        assert!((height - 570.0).abs() < 0.01, "{height}");
        assert_eq!(
            attribute(&svg, "viewBox"),
            format!("0 0 {width:.2} {height:.2}")
        );
        // 54 markers, each with its id.
        assert_eq!(svg.matches("<polygon id=\"m").count(), 54);
        assert!(svg.contains(">20201</text>"));
        // At 100 dpi: 66.83 / 2.54 · 100 = 2631.2 → 2631 px, 57 / 2.54 · 100 = 2244.1 → 2244 px.
        let img = panel_png(&p, 100.0, false).expect("png");
        assert_eq!(img.dimensions(), (2631, 2244));
    }

    #[test]
    fn markers_are_where_the_body_model_puts_them() {
        let s = suit();
        let part = cylinder();
        let p = panel(&s, &lone_cylinder(), 0, "subject test");
        // Marker 7 + 8 + 1 (row 2, column 1) on the straight section: u = 8 cm, s = 1.5 / 8.
        let cell = part.markers(&s)[7 + 8 + 1];
        assert_eq!(cell.id, 20201);
        assert!((cell.centre_u - 8.0).abs() < 1e-5);
        // The cylinder points up (+Y), so u grows up the page from the bottom of the tube at
        // y = 2 + 50 cm, and s grows to the right from the left edge at x = 2 cm.
        let x = 2.0 + PERIMETER * 1.5 / 8.0; // 13.78 cm
        let y = 2.0 + (40.0 - 8.0); // 34 cm
        let m = p
            .markers
            .iter()
            .find(|m| m.id == cell.id)
            .expect("on the panel");
        assert!(
            (m.centre[0] - x).abs() < 0.01 && (m.centre[1] - y).abs() < 1e-4,
            "{:?}",
            m.centre
        );
        let colour = srgb8(s.markers[cell.colour].hsv);
        assert_eq!(m.colour, colour);

        let dpi = 100.0;
        let img = panel_png(&p, dpi, false).expect("png");
        let at = |xcm: f32, ycm: f32| {
            let k = dpi / 2.54;
            img.get_pixel((xcm * k) as u32, (ycm * k) as u32).0
        };
        assert_eq!(at(x, y), colour);
        // 1.5 cm off-centre is still the 4 cm marker, 2.5 cm off is cloth (the gap is 3 cm).
        assert_eq!(at(x + 1.5, y - 1.5), colour);
        assert_eq!(at(x + 2.5, y), srgb8(s.background.hsv));
        assert_eq!(at(x, y + 2.5), srgb8(s.background.hsv));
        // Outside the cutting line: paper.
        assert_eq!(at(0.5, y), PAPER);
        // Every marker's centre pixel has its colour (ids off, so nothing covers them).
        for m in &p.markers {
            assert_eq!(at(m.centre[0], m.centre[1]), m.colour, "marker {}", m.id);
        }
    }

    #[test]
    fn panels_read_correctly_from_outside() {
        // For every suit part of the default subject: page-right × page-up is the outward normal.
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let motion = Motion::load(&root.join("suits/default/skeleton.bvh")).expect("skeleton");
        let subject = pattern_subject(None, None, None).expect("chidi");
        let body = Body::new(&subject, &subject.scale_skeleton(&motion.skeleton)).expect("body");
        let mut suit_parts = 0;
        for part in body.parts.iter().filter(|p| p.material == Material::Suit) {
            suit_parts += 1;
            let place = Placement::new(part, 0.0, 0.0);
            let (u, s) = (part.length() * 0.5, 0.3);
            let point = |u: f32, s: f32| part.surface_point(u, part.theta_for(u, s)).0;
            let normal = part.surface_point(u, part.theta_for(u, s)).1;
            // 3-D directions of +x and −y (page up) on the panel.
            let page = |du: f32, ds: f32| place.point(part, u + du, s + ds);
            let (p0, ps, pu) = (page(0.0, 0.0), page(0.0, 0.01), page(0.1, 0.0));
            let s_dir = (point(u, s + 0.01) - point(u, s)) * (ps[0] - p0[0]).signum();
            let u_dir = (point(u + 0.1, s) - point(u, s)) * (p0[1] - pu[1]).signum();
            assert!(
                s_dir.cross(u_dir).dot(normal) > 0.0,
                "{} is mirrored",
                part.name
            );
        }
        assert_eq!(suit_parts, 11);
    }

    #[test]
    fn allowance_lies_one_centimetre_outside_the_stitch_line() {
        let p = panel(&suit(), &lone_cylinder(), 0, "subject test");
        // On the straight section the stitch line is vertical at x = 2 and x = 2 + 62.83.
        let left = p.cut.iter().map(|q| q[0]).fold(f32::INFINITY, f32::min);
        let right = p.cut.iter().map(|q| q[0]).fold(f32::NEG_INFINITY, f32::max);
        assert!((left - 1.0).abs() < 0.01 && (right - (PERIMETER + 3.0)).abs() < 0.02);
        let top = p.cut.iter().map(|q| q[1]).fold(f32::INFINITY, f32::min);
        let bottom = p.cut.iter().map(|q| q[1]).fold(f32::NEG_INFINITY, f32::max);
        assert!(
            (top - 1.0).abs() < 0.01 && (bottom - 53.0).abs() < 0.01,
            "{top} {bottom}"
        );
        // A unit square offset by 1: corners mitred to (−1, −1) … (2, 2).
        let square = offset_polygon(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], 1.0);
        for (q, e) in square
            .iter()
            .zip([[-1.0, -1.0], [2.0, -1.0], [2.0, 2.0], [-1.0, 2.0]])
        {
            assert!(
                (q[0] - e[0]).abs() < 1e-5 && (q[1] - e[1]).abs() < 1e-5,
                "{q:?}"
            );
        }
    }

    #[test]
    fn png_carries_its_dpi() {
        let img = RgbImage::from_pixel(3, 2, Rgb([1, 2, 3]));
        let bytes = encode_png(&img, 254.0).expect("encode");
        let chunks = png_chunks(&bytes).expect("chunks");
        assert_eq!(&chunks[0].0, b"IHDR");
        assert_eq!(&chunks[1].0, b"pHYs");
        // 254 dpi = 10000 pixels per metre, unit 1 (metre).
        assert_eq!(chunks[1].1, [0, 0, 0x27, 0x10, 0, 0, 0x27, 0x10, 1]);
        let back = image::load_from_memory(&bytes).expect("decodes").to_rgb8();
        assert_eq!(back, img);
        // CRC-32 check value.
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
    }

    #[test]
    fn subjects_and_options_are_checked() {
        assert_eq!(
            pattern_subject(None, None, None).expect("default").name,
            "chidi"
        );
        let custom = pattern_subject(Some("ana"), Some(170.0), Some(1.1)).expect("custom");
        assert_eq!(
            (custom.name, custom.height_cm, custom.girth),
            ("custom", 170.0, 1.1)
        );
        assert_eq!(
            custom.arm_ratio,
            Subject::find("ana").expect("ana").arm_ratio
        );
        let err = pattern_subject(Some("zed"), None, None)
            .unwrap_err()
            .to_string();
        assert!(err.contains("zed"), "{err}");
        let err = pattern_subject(None, Some(20.0), None)
            .unwrap_err()
            .to_string();
        assert!(err.contains("--height"), "{err}");
        let err = pattern_subject(None, None, Some(5.0))
            .unwrap_err()
            .to_string();
        assert!(err.contains("--girth"), "{err}");
        assert!(check_dpi(5000.0).unwrap_err().to_string().contains("--dpi"));
    }

    #[test]
    fn default_suit_pattern_is_written() {
        let dir = tempfile::tempdir().expect("tempdir");
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let subject = pattern_subject(None, None, None).expect("chidi");
        let options = PatternOptions {
            dpi: 20.0,
            marker_ids: true,
        };
        let files = write_suit_pattern(&root.join("suits/default"), &subject, dir.path(), &options)
            .expect("pattern");
        assert_eq!(files.len(), 22);
        for f in &files {
            assert!(f.exists(), "{}", f.display());
        }
        assert!(dir.path().join("right_upper_arm.svg").exists());
        // 600 dpi makes the pelvis panel about 22000 × 11000 pixels: refused before anything is written.
        let empty = dir.path().join("big");
        let big = PatternOptions {
            dpi: 600.0,
            marker_ids: false,
        };
        let err = write_suit_pattern(&root.join("suits/default"), &subject, &empty, &big)
            .unwrap_err()
            .to_string();
        assert!(err.contains("pelvis") && err.contains("--dpi"), "{err}");
        assert!(!empty.exists());
        let err = write_suit_pattern(&root.join("nowhere"), &subject, dir.path(), &options)
            .unwrap_err()
            .to_string();
        assert!(err.contains("nowhere"), "{err}");
    }
}
