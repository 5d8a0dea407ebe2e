//! Procedural garments sized from the body in its rest pose: a T-shirt, a skirt and a dress.
//!
//! Every garment is generated around the subject's body in the rest pose (all channels zero: the
//! shipped CMU/Daz skeleton stands in a T-pose at the origin, arms along ±X, facing +Z), from the same
//! inflated collision capsules the solver uses, so the subject's size drives the garment:
//!
//! - **Rings.** A garment is a stack of horizontal rings. At each height the torso capsules' cross
//!   sections (discs) are fitted by an ellipse centred on the body's mid-plane that contains all of
//!   them (semi-axes from the extreme discs, then scaled up until the ellipse's support function
//!   bounds every disc's in 72 directions), plus the ease. Ring vertices are spaced evenly by arc
//!   length, one edge length apart; rings one edge length apart.
//! - **T-shirt.** A torso tube from just below the hip joint to shoulder height whose width never
//!   shrinks going down (it hangs straight from the chest). Above the armpit the columns beyond
//!   `x_cut` on each side are left out — the armholes, wide enough front to back for the upper arm —
//!   leaving a front and a back panel. Each front column runs on to its mirror column at the back
//!   along a half-ellipse over the shoulders, as low as clears the trunk and arms, and a round neck
//!   opening is cut out of that yoke around the neck's axis ([`CREW_NECK_EASE_CM`] wider than the
//!   neck with its ease). A short sleeve tube is welded to each armhole
//!   (its first ring *is* the armhole's boundary loop, so the mesh is one connected piece) and
//!   blends in two rings to a circle around the upper arm, ending about half-way to the elbow, its
//!   last ring held around the arm ([`Cuff`], [`SLEEVE_CUFF_REACH_CM`]). The
//!   sleeve's vertices are evenly spaced along the armhole and, on the circle, evenly in angle:
//!   kept at the armhole's directions from the arm's axis (an armhole is taller than it is deep,
//!   so equal arcs subtend unequal angles), the circle crowded them at the armpit's corners into
//!   edges a fifth of the usual length, which the solver squashed and tore.
//! - **Skirt.** Rings from the waist (70 % of the way from the hip joint to the abdomen joint) to just
//!   above the knees, flaring by 24° (a full skirt, [`SKIRT_FLARE_DEG`]) and never narrower than the
//!   hips and thighs below; each ring has as many vertices as its perimeter needs, and neighbouring
//!   rings are stitched by walking both in step by arc-length fraction.
//! - **Dress.** The T-shirt's bodice (fitted: following the body's cross-sections) from the natural
//!   waist (the abdomen joint) up, with armholes and shoulder straps but no sleeves and a square
//!   neckline (the columns within the neck's reach stay open down to the top ring), continued
//!   below the waist by the skirt's rings flaring by 12° (an A-line, [`DRESS_FLARE_DEG`]), all in
//!   one mesh.
//!
//! Triangles are wound so that `(b − a) × (c − a)` points away from the body, consistently across
//! the whole mesh. Finally every vertex still closer than half the ease to a capsule (a disc between
//! fitted directions, a sleeve over the arm) is pushed out to that distance.
//!
//! **Anchors** are vertices bound to a bone (bone index, position in the bone's frame at rest):
//! for the T-shirt the neckline loop and two rings of its neighbours (chest bone), for the skirt
//! the waistband's two top rings (hip bone), for the dress its neckline up to the neck joint's
//! height (chest bone; the head tilting forward reaches the strap tops beside the neck) rigidly and
//! its waist ring to the hip loosely (within [`DRESS_WAIST_SLACK_CM`]: bending the spine lengthens
//! the back between the two bones by a few centimetres, which two rigid rings would force into the
//! bodice as stretch).
//!
//! Hands to the solver: a [`GarmentMesh`] — rest positions in world centimetres, triangles, anchors
//! and cuffs.

use std::f32::consts::{PI, TAU};
use std::str::FromStr;

use glam::{Affine3A, Vec2, Vec3};

use super::capsule::{Capsule, PreparedCapsule};
use super::proxies::{BodyPose, BodyRig};
use super::topology::{boundary_loops, unique_edges, Adjacency};

/// A vertex bound to a bone: rigidly (`slack_cm` 0, the vertex is kinematic) or loosely (the
/// vertex is simulated and drawn back within `slack_cm` of its bound position, softly: see
/// [`SolverSettings::loose_anchor_seconds`](super::solver::SolverSettings::loose_anchor_seconds)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Anchor {
    pub vertex: u32,
    /// Joint index in the rig's skeleton.
    pub bone: usize,
    /// Position in the bone's local frame (its rest position mapped through the bone's rest inverse).
    pub local: Vec3,
    /// How far the vertex may stray from its bound position, cm (0: rigid).
    pub slack_cm: f32,
}

/// A garment's rest shape: positions in rest-pose world centimetres, outward-wound triangles, anchors.
#[derive(Clone, Debug, PartialEq)]
pub struct GarmentMesh {
    pub name: String,
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    pub anchors: Vec<Anchor>,
    /// Vertices kept around a limb (a T-shirt's sleeve ends).
    pub cuffs: Vec<Cuff>,
}

/// A vertex of a sleeve's end held around its limb: never farther than `reach_cm` from the surface
/// of bone `bone`'s collision capsules. Within that reach the vertex is free: it slides along the
/// limb, turns about it and hangs to one side as it likes, but the arm cannot leave the sleeve (see
/// [`SLEEVE_CUFF_REACH_CM`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cuff {
    pub vertex: u32,
    /// Joint index in the rig's skeleton.
    pub bone: usize,
    pub reach_cm: f32,
}

/// The procedural garments.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GarmentKind {
    TShirt,
    Skirt,
    Dress,
}

impl GarmentKind {
    pub const ALL: [GarmentKind; 3] = [GarmentKind::TShirt, GarmentKind::Skirt, GarmentKind::Dress];

    pub fn name(self) -> &'static str {
        match self {
            GarmentKind::TShirt => "tshirt",
            GarmentKind::Skirt => "skirt",
            GarmentKind::Dress => "dress",
        }
    }
}

impl FromStr for GarmentKind {
    type Err = GarmentError;

    fn from_str(s: &str) -> Result<GarmentKind, GarmentError> {
        GarmentKind::ALL
            .into_iter()
            .find(|k| {
                k.name().eq_ignore_ascii_case(s)
                    || (s.eq_ignore_ascii_case("t-shirt") && *k == GarmentKind::TShirt)
            })
            .ok_or_else(|| GarmentError::UnknownKind(s.to_owned()))
    }
}

/// How finely and loosely a garment is cut.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GarmentParams {
    /// Target edge length, cm.
    pub edge_cm: f32,
    /// Ease: how far the cloth stands off the body's proxies at rest, cm.
    pub ease_cm: f32,
}

impl GarmentParams {
    /// Live mode: 2 cm edges.
    pub fn live() -> GarmentParams {
        GarmentParams {
            edge_cm: 2.0,
            ease_cm: 2.5,
        }
    }

    /// Quality mode: 1 cm edges (about four times the vertices).
    pub fn quality() -> GarmentParams {
        GarmentParams {
            edge_cm: 1.0,
            ..GarmentParams::live()
        }
    }
}

impl Default for GarmentParams {
    fn default() -> GarmentParams {
        GarmentParams::live()
    }
}

/// Why a garment cannot be made or used.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum GarmentError {
    #[error("unknown garment '{0}' (expected tshirt, skirt or dress)")]
    UnknownKind(String),
    #[error("the body has no part '{0}' (procedural garments need the parts Body::new builds)")]
    MissingPart(&'static str),
    #[error("the skeleton has no joint '{0}' (procedural garments need the CMU/Daz joint names)")]
    MissingJoint(&'static str),
    #[error("edge length {0} cm is not a positive number (e.g. 2 for live, 1 for quality)")]
    BadEdge(f32),
    #[error("ease {0} cm is not a non-negative number")]
    BadEase(f32),
    #[error("garment '{name}': {message}")]
    Invalid { name: String, message: String },
}

impl GarmentMesh {
    /// A procedural garment for the rig's body.
    pub fn generate(
        kind: GarmentKind,
        rig: &BodyRig,
        params: &GarmentParams,
    ) -> Result<GarmentMesh, GarmentError> {
        if !(params.edge_cm > 0.05 && params.edge_cm.is_finite()) {
            return Err(GarmentError::BadEdge(params.edge_cm));
        }
        if !(params.ease_cm >= 0.0 && params.ease_cm.is_finite()) {
            return Err(GarmentError::BadEase(params.ease_cm));
        }
        let rest = Rest::new(rig);
        let mesh = match kind {
            GarmentKind::TShirt => tshirt(&rest, params)?,
            GarmentKind::Skirt => skirt(&rest, params)?,
            GarmentKind::Dress => dress(&rest, params)?,
        };
        mesh.validate()?;
        Ok(mesh)
    }

    /// The garment with the edge length that brings its vertex count nearest `target`; returns it
    /// with that edge length.
    pub fn with_vertex_count(
        kind: GarmentKind,
        rig: &BodyRig,
        target: usize,
        ease_cm: f32,
    ) -> Result<(GarmentMesh, f32), GarmentError> {
        let mut edge = 2.0f32;
        let mut best: Option<(GarmentMesh, f32)> = None;
        for _ in 0..5 {
            let mesh = GarmentMesh::generate(
                kind,
                rig,
                &GarmentParams {
                    edge_cm: edge,
                    ease_cm,
                },
            )?;
            let n = mesh.positions.len().max(1);
            let better = best
                .as_ref()
                .is_none_or(|(b, _)| n.abs_diff(target) < b.positions.len().abs_diff(target));
            let next = edge * (n as f32 / target.max(1) as f32).sqrt();
            if better {
                best = Some((mesh, edge));
            }
            if n.abs_diff(target) * 100 < target {
                break;
            }
            edge = next;
        }
        best.ok_or(GarmentError::BadEdge(edge))
    }

    /// A flat rectangular sheet of `columns × rows` quads from `corner`, spanning `along` and `down`
    /// (no anchors). For tests and demonstrations.
    pub fn sheet(
        name: &str,
        corner: Vec3,
        along: Vec3,
        down: Vec3,
        columns: usize,
        rows: usize,
    ) -> GarmentMesh {
        let (columns, rows) = (columns.max(1), rows.max(1));
        let mut positions = Vec::with_capacity((columns + 1) * (rows + 1));
        for r in 0..=rows {
            for c in 0..=columns {
                positions.push(
                    corner + along * (c as f32 / columns as f32) + down * (r as f32 / rows as f32),
                );
            }
        }
        let id = |r: usize, c: usize| (r * (columns + 1) + c) as u32;
        let mut triangles = Vec::with_capacity(2 * rows * columns);
        for r in 0..rows {
            for c in 0..columns {
                let (a, b, cc, d) = (id(r, c), id(r, c + 1), id(r + 1, c + 1), id(r + 1, c));
                if (r + c) % 2 == 0 {
                    triangles.push([a, cc, b]);
                    triangles.push([a, d, cc]);
                } else {
                    triangles.push([a, d, b]);
                    triangles.push([b, d, cc]);
                }
            }
        }
        GarmentMesh {
            name: name.to_owned(),
            positions,
            triangles,
            anchors: Vec::new(),
            cuffs: Vec::new(),
        }
    }

    /// Index of the vertex at row `r`, column `c` of a [`GarmentMesh::sheet`] with `columns` quads
    /// per row.
    pub fn sheet_vertex(columns: usize, r: usize, c: usize) -> u32 {
        (r * (columns.max(1) + 1) + c) as u32
    }

    /// Checks indices, finiteness and degenerate triangles.
    pub fn validate(&self) -> Result<(), GarmentError> {
        let invalid = |message: String| GarmentError::Invalid {
            name: self.name.clone(),
            message,
        };
        if self.triangles.is_empty() {
            return Err(invalid("no triangles".into()));
        }
        let n = self.positions.len();
        if let Some(v) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(invalid(format!("vertex {v} is not finite")));
        }
        for (k, t) in self.triangles.iter().enumerate() {
            if t.iter().any(|&v| v as usize >= n) {
                return Err(invalid(format!(
                    "triangle {k} {t:?} refers past the {n} vertices"
                )));
            }
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                return Err(invalid(format!("triangle {k} {t:?} repeats a vertex")));
            }
        }
        for a in &self.anchors {
            if a.vertex as usize >= n
                || !a.local.is_finite()
                || a.slack_cm.is_nan()
                || a.slack_cm < 0.0
            {
                return Err(invalid(format!("anchor {a:?} is invalid")));
            }
        }
        for c in &self.cuffs {
            if c.vertex as usize >= n || !(c.reach_cm.is_finite() && c.reach_cm >= 0.0) {
                return Err(invalid(format!("cuff {c:?} is invalid")));
            }
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------------
// The rest pose.

/// The body in its rest pose, as the generators see it.
struct Rest<'a> {
    rig: &'a BodyRig,
    pose: BodyPose,
    prepared: Vec<PreparedCapsule>,
}

impl<'a> Rest<'a> {
    fn new(rig: &'a BodyRig) -> Rest<'a> {
        let mut pose = BodyPose::default();
        rig.pose(&rig.rest_frame(), &mut pose);
        let prepared = pose.capsules.iter().map(Capsule::prepared).collect();
        Rest {
            rig,
            pose,
            prepared,
        }
    }

    fn joint(&self, name: &'static str) -> Result<usize, GarmentError> {
        self.rig
            .skeleton()
            .find(name)
            .ok_or(GarmentError::MissingJoint(name))
    }

    fn joint_position(&self, name: &'static str) -> Result<Vec3, GarmentError> {
        let j = self.joint(name)?;
        Ok(Vec3::from(self.pose.bones[j].translation))
    }

    fn part_name(&self, capsule: usize) -> &'static str {
        let part = self.rig.proxies()[capsule].part;
        self.rig.body().parts[part].name
    }

    /// Posed capsules of the named parts; every name must exist.
    fn capsules_of(&self, parts: &[&'static str]) -> Result<Vec<Capsule>, GarmentError> {
        for &name in parts {
            if !self.rig.body().parts.iter().any(|p| p.name == name) {
                return Err(GarmentError::MissingPart(name));
            }
        }
        Ok(self
            .pose
            .capsules
            .iter()
            .enumerate()
            .filter(|(k, _)| parts.contains(&self.part_name(*k)))
            .map(|(_, c)| *c)
            .collect())
    }

    /// Smallest signed distance to any capsule of a part not excluded.
    fn clearance(&self, p: Vec3, exclude: &[&str]) -> f32 {
        self.prepared
            .iter()
            .enumerate()
            .filter(|(k, _)| !exclude.contains(&self.part_name(*k)))
            .map(|(_, c)| c.distance(p.into()))
            .fold(f32::INFINITY, f32::min)
    }

    fn bone_local(&self, bone: usize, p: Vec3) -> Vec3 {
        self.pose.bones[bone].inverse().transform_point3(p)
    }
}

// ---------------------------------------------------------------------------------------------
// Cross-sections and rings.

/// Discs where the horizontal plane at `y` cuts the capsules: (centre (x, z), radius).
fn section(capsules: &[Capsule], y: f32) -> Vec<(Vec2, f32)> {
    const SAMPLES: usize = 32;
    let mut out = Vec::new();
    for c in capsules {
        for k in 0..=SAMPLES {
            let (centre, r) = c.sphere_at(k as f32 / SAMPLES as f32);
            let dy = y - centre.y;
            if dy.abs() < r {
                out.push((Vec2::new(centre.x, centre.z), (r * r - dy * dy).sqrt()));
            }
        }
    }
    out
}

/// Semi-axes of an ellipse centred at (0, zc) containing every disc.
fn fit_ellipse(discs: &[(Vec2, f32)], zc: f32) -> Option<Vec2> {
    if discs.is_empty() {
        return None;
    }
    let mut a0 = 0.0f32;
    let mut b0 = 0.0f32;
    for (c, r) in discs {
        a0 = a0.max(c.x.abs() + r);
        b0 = b0.max((c.y - zc).abs() + r);
    }
    let (a0, b0) = (a0.max(1.0), b0.max(1.0));
    let mut scale = 1.0f32;
    const DIRECTIONS: usize = 72;
    for k in 0..DIRECTIONS {
        let (s, co) = (TAU * k as f32 / DIRECTIONS as f32).sin_cos();
        let support = ((a0 * co).powi(2) + (b0 * s).powi(2)).sqrt();
        for (c, r) in discs {
            scale = scale.max((c.x * co + (c.y - zc) * s + r) / support);
        }
    }
    Some(Vec2::new(a0, b0) * scale)
}

/// Ramanujan's perimeter of an ellipse with semi-axes `s`.
fn ellipse_perimeter(s: Vec2) -> f32 {
    let (a, b) = (s.x, s.y);
    let h = ((a - b) / (a + b)).powi(2);
    PI * (a + b) * (1.0 + 3.0 * h / (10.0 + (4.0 - 3.0 * h).sqrt()))
}

/// `n` points evenly spaced by arc length on the ellipse (x = a cos θ, z = zc + b sin θ) at height
/// `y`, from θ = 0 (+X) towards +Z.
fn ellipse_ring(y: f32, zc: f32, semi: Vec2, n: usize) -> Vec<Vec3> {
    const STEPS: usize = 512;
    let mut table = [0.0f32; STEPS + 1];
    let step = TAU / STEPS as f32;
    for k in 1..=STEPS {
        let mid = (k as f32 - 0.5) * step;
        let speed = ((semi.x * mid.sin()).powi(2) + (semi.y * mid.cos()).powi(2)).sqrt();
        table[k] = table[k - 1] + speed * step;
    }
    let total = table[STEPS];
    (0..n)
        .map(|k| {
            let target = total * k as f32 / n as f32;
            let i = table.partition_point(|&a| a < target).clamp(1, STEPS);
            let (a0, a1) = (table[i - 1], table[i]);
            let frac = if a1 > a0 {
                (target - a0) / (a1 - a0)
            } else {
                0.0
            };
            let theta = (i as f32 - 1.0 + frac) * step;
            Vec3::new(semi.x * theta.cos(), y, zc + semi.y * theta.sin())
        })
        .collect()
}

// ---------------------------------------------------------------------------------------------
// Mesh building.

#[derive(Default)]
struct Builder {
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
}

impl Builder {
    fn vertex(&mut self, p: Vec3) -> u32 {
        self.positions.push(p);
        (self.positions.len() - 1) as u32
    }

    /// A quad with corners a = (row, col), b = (row, col + 1), c = (row + 1, col + 1),
    /// d = (row + 1, col), where "row + 1" is up and "col + 1" is right seen from outside, so the
    /// outward normal is up × right. `flip` picks the other diagonal.
    fn quad(&mut self, a: u32, b: u32, c: u32, d: u32, flip: bool) {
        if flip {
            self.triangles.push([a, c, b]);
            self.triangles.push([a, d, c]);
        } else {
            self.triangles.push([a, d, b]);
            self.triangles.push([b, d, c]);
        }
    }

    /// Stitches a closed ring to the closed ring above it, walking both by arc-length fraction
    /// (vertex k of an n-ring sits at k/n). Both rings run in the same sense (right, seen from
    /// outside).
    fn loft(&mut self, lower: &[u32], upper: &[u32], upper_first: bool) {
        let even = |n: usize| (0..n).map(|k| k as f64 / n as f64).collect::<Vec<_>>();
        self.loft_at(
            lower,
            &even(lower.len()),
            upper,
            &even(upper.len()),
            upper_first,
        );
    }

    /// [`Builder::loft`] with each vertex's fraction of the way around given (increasing from 0).
    /// Triangles run the lower ring backwards (k + 1 → k) and the upper ring forwards.
    fn loft_at(
        &mut self,
        lower: &[u32],
        lower_at: &[f64],
        upper: &[u32],
        upper_at: &[f64],
        upper_first: bool,
    ) {
        let (nl, nu) = (lower.len(), upper.len());
        if nl == 0 || nu == 0 || lower_at.len() != nl || upper_at.len() != nu {
            return;
        }
        let next = |at: &[f64], k: usize| at.get(k + 1).copied().unwrap_or(1.0);
        let (mut k, mut j) = (0usize, 0usize);
        while k < nl || j < nu {
            let advance_lower = if k == nl {
                false
            } else if j == nu {
                true
            } else {
                match next(lower_at, k).total_cmp(&next(upper_at, j)) {
                    std::cmp::Ordering::Less => true,
                    std::cmp::Ordering::Greater => false,
                    std::cmp::Ordering::Equal => !upper_first,
                }
            };
            if advance_lower {
                self.triangles
                    .push([lower[k % nl], upper[j % nu], lower[(k + 1) % nl]]);
                k += 1;
            } else {
                self.triangles
                    .push([lower[k % nl], upper[j % nu], upper[(j + 1) % nu]]);
                j += 1;
            }
        }
    }
}

/// How a bodice's neck opening is cut.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Neckline {
    /// The columns within the neck's reach stay open down to the top ring, between shoulder straps
    /// (the dress).
    Square,
    /// Every column between the armholes runs over the shoulders, and a round opening
    /// [`CREW_NECK_EASE_CM`] wider than the neck is cut out around the neck's axis (the T-shirt).
    Crew,
}

impl Neckline {
    /// How much wider than the neck with its ease the opening is, cm.
    fn extra_room_cm(self) -> f32 {
        match self {
            Neckline::Square => 0.0,
            Neckline::Crew => CREW_NECK_EASE_CM,
        }
    }

    /// Whether the strap of the front column at `x` (cm from the middle) runs over the shoulder
    /// when the opening is `neck_half` wide: a square neckline leaves the columns within the neck's
    /// reach open, a crew neckline runs every column over and cuts the opening out afterwards.
    fn has_strap(self, x: f32, neck_half: f32) -> bool {
        self == Neckline::Crew || x.abs() >= neck_half
    }

    /// The body parts the straps' paths need not clear: the head always; the neck too when the
    /// round opening is cut around it afterwards.
    fn parts_straps_ignore(self) -> &'static [&'static str] {
        match self {
            Neckline::Square => &["head"],
            Neckline::Crew => &["head", "neck"],
        }
    }
}

/// How much wider than the neck (its capsule plus the ease) a T-shirt's round neck opening is, cm.
/// The neckline is anchored to the chest, so the neck bending forward must not reach it: with the
/// opening at the ease alone the dance's bowed head pressed the front neckline into tears (maximum
/// strain 116–164 % while dressing). Chosen on the cloth benchmark's 18 T-shirt cases (walk and kick
/// at 2,000 and 4,000 vertices and the quality mode, the demo clip, dance, jump, kick 11), with the
/// neckline and two rings of its neighbours anchored: 0 and 1 cm left four and five cases over a
/// target (the dance's bowed head still tearing the front, up to 142 %), 2, 3 and 4.5 cm two, three
/// and two (maxima 10.1–13.8 %, single armpit edges), 3.5 and 5 cm one and two (10.3 %; 10.3 % and
/// a p95 of 2.07 %), 4 cm none; with one ring, as the square neck had, 4 cm left one (p95 2.22 %).
/// The opening is centred on the neck's axis, which stands behind the chest's middle, so it dips
/// lower at the back than at the front, unlike a tailored crew neck; centred 2 or 3 cm further
/// forward it put two of the 18 cases over the maximum (10.2–11.5 %).
/// Against the square neckline of before (the columns within the neck's reach open down to the
/// shoulder line, the straps' inner edges anchored), every case stays within the targets (95th
/// percentile 0.36–1.84 % against 0.43–1.67 %, maxima ≤ 9.93 % against ≤ 9.44 %), and the sleeve
/// ends ride about a centimetre further up the arm (mean 6.9–10.8 cm against 6.3–10.4).
pub const CREW_NECK_EASE_CM: f32 = 4.0;

/// The T-shirt and dress bodice: a tube of rings of `n` columns with the armhole columns left out
/// above the armpit ring, and the cloth over the shoulders around the neck opening.
struct Bodice {
    /// Vertex of (ring, column), `None` in the armholes.
    grid: Vec<Vec<Option<u32>>>,
    /// Columns left out above `armpit`.
    x_cut: f32,
    /// Half the neck opening's width.
    neck_half: f32,
    neckline: Neckline,
}

struct BodiceSpec {
    /// Height and semi-axes of each ring, bottom to top.
    rings: Vec<(f32, Vec2)>,
    zc: f32,
    n: usize,
    /// Index of the armpit ring (the last full ring).
    armpit: usize,
}

fn build_bodice(
    b: &mut Builder,
    rest: &Rest,
    spec: &BodiceSpec,
    params: &GarmentParams,
    neckline: Neckline,
) -> Result<Bodice, GarmentError> {
    let n = spec.n;
    let top = spec.rings.len() - 1;
    let shoulder = rest
        .joint_position("rShldr")?
        .lerp(rest.joint_position("lShldr")?, 0.5);
    let arm = rest.capsules_of(&["right_upper_arm"])?;
    let arm_radius = arm.first().map_or(6.0, |c| c.radius_a);
    let neck = rest.capsules_of(&["neck"])?;
    let neck_radius = neck.first().map_or(6.0, |c| c.radius_a);
    let (top_y, top_semi) = spec.rings[top];
    // The armhole must let the upper arm through with a centimetre to spare front and back.
    let reach = (shoulder.z - arm_radius - 1.0 - spec.zc)
        .abs()
        .max((shoulder.z + arm_radius + 1.0 - spec.zc).abs());
    let x_cut = top_semi.x * (1.0 - (reach / top_semi.y).min(0.9).powi(2)).sqrt();
    let neck_half =
        (neck_radius + params.ease_cm + neckline.extra_room_cm()).min(x_cut - 1.5 * params.edge_cm);

    let rings: Vec<Vec<Vec3>> = spec
        .rings
        .iter()
        .map(|&(y, semi)| ellipse_ring(y, spec.zc, semi, n))
        .collect();
    let top_ring = &rings[top];
    let in_armhole = |k: usize| top_ring[k].x.abs() > x_cut;
    let mut grid: Vec<Vec<Option<u32>>> = Vec::with_capacity(rings.len());
    for (i, ring) in rings.iter().enumerate() {
        grid.push(
            ring.iter()
                .enumerate()
                .map(|(k, &p)| (i <= spec.armpit || !in_armhole(k)).then(|| b.vertex(p)))
                .collect(),
        );
    }
    for i in 0..top {
        for k in 0..n {
            let k1 = (k + 1) % n;
            if let (Some(a), Some(bb), Some(c), Some(d)) =
                (grid[i][k], grid[i][k1], grid[i + 1][k1], grid[i + 1][k])
            {
                b.quad(a, bb, c, d, (i + k) % 2 == 1);
            }
        }
    }

    // Straps: front column k (0 < k < n/2) to its mirror n − k over the shoulder, along a path
    // clear of the trunk and arms. A square neckline leaves the columns within the neck's reach
    // open; a crew neckline runs every column over and cuts out what lies within `neck_half` of the
    // neck's axis, so the opening is round (see `CREW_NECK_EASE_CM`).
    let strap_columns: Vec<usize> = (1..n / 2)
        .filter(|&k| {
            grid[top][k].is_some()
                && grid[top][n - k].is_some()
                && neckline.has_strap(top_ring[k].x, neck_half)
        })
        .collect();
    let neck_axis = neck
        .first()
        .map(|c| (c.a, (c.b - c.a).normalize_or(Vec3::Y)))
        .unwrap_or((Vec3::new(0.0, top_y, spec.zc), Vec3::Y));
    let in_neck_opening = |p: Vec3| {
        let r = p - neck_axis.0;
        neckline == Neckline::Crew && (r - neck_axis.1 * r.dot(neck_axis.1)).length() < neck_half
    };
    let ignored = neckline.parts_straps_ignore();
    let clear = 0.5 * params.ease_cm + 0.5;
    let paths: Vec<Vec<Vec3>> = strap_columns
        .iter()
        .map(|&k| {
            let front = top_ring[k];
            let back = top_ring[n - k];
            strap_path(rest, front, back, clear, ignored)
        })
        .collect();
    let longest = paths
        .iter()
        .map(|p| polyline_length(p))
        .fold(0.0f32, f32::max);
    let segments = ((longest / params.edge_cm).round() as usize).max(2);
    let mut strap_ids: Vec<Vec<Option<u32>>> = Vec::with_capacity(strap_columns.len());
    for (s, &k) in strap_columns.iter().enumerate() {
        let points = resample(&paths[s], segments);
        // The two columns beside each armhole are never cut: where the shoulders are narrow for
        // the neck, an opening reaching them would run into the armhole (one hole, no sleeve).
        let beside_armhole = s < 2 || s + 2 >= strap_columns.len();
        let mut ids = Vec::with_capacity(segments + 1);
        for (j, p) in points.iter().enumerate() {
            ids.push(if j == 0 {
                grid[top][k]
            } else if j == segments {
                grid[top][n - k]
            } else if !beside_armhole && in_neck_opening(*p) {
                None
            } else {
                Some(b.vertex(*p))
            });
        }
        strap_ids.push(ids);
    }
    if !strap_ids
        .iter()
        .any(|ids| ids[1..segments].iter().all(Option::is_some))
    {
        return Err(GarmentError::Invalid {
            name: "bodice".into(),
            message: format!(
                "no room for the shoulders between the neck ({neck_half:.1} cm) and the armholes ({x_cut:.1} cm); use a shorter edge or less ease"
            ),
        });
    }
    for s in 0..strap_columns.len().saturating_sub(1) {
        if strap_columns[s + 1] != strap_columns[s] + 1 {
            continue;
        }
        for j in 0..segments {
            let corners = [
                strap_ids[s][j],
                strap_ids[s + 1][j],
                strap_ids[s + 1][j + 1],
                strap_ids[s][j + 1],
            ];
            match corners {
                [Some(a), Some(bb), Some(c), Some(d)] => {
                    b.quad(a, bb, c, d, (j + strap_columns[s]) % 2 == 1)
                }
                // Where the neckline crosses the quad, its remaining half (wound as the quad is:
                // a → d → c → b), so the neckline steps diagonally rather than in stairs.
                _ => {
                    let present: Vec<u32> =
                        [0, 3, 2, 1].iter().filter_map(|&i| corners[i]).collect();
                    if let [x, y, z] = present[..] {
                        b.triangles.push([x, y, z]);
                    }
                }
            }
        }
    }
    Ok(Bodice {
        grid,
        x_cut,
        neck_half,
        neckline,
    })
}

/// Half-ellipse from `front` up over the shoulder to `back` (same x), as low as keeps `clear`
/// centimetres from every capsule but those of the `ignored` parts.
fn strap_path(rest: &Rest, front: Vec3, back: Vec3, clear: f32, ignored: &[&str]) -> Vec<Vec3> {
    const SAMPLES: usize = 64;
    let path = |height: f32| -> Vec<Vec3> {
        (0..=SAMPLES)
            .map(|k| {
                let phi = PI * k as f32 / SAMPLES as f32;
                let t = 0.5 - 0.5 * phi.cos();
                let base = front.lerp(back, t);
                base + Vec3::Y * (height * phi.sin())
            })
            .collect()
    };
    // Never ask for more room than the panel's own top vertices have (the outermost columns sit
    // next to the armhole, closer to the arm than `clear`).
    let need = clear
        .min(rest.clearance(front, ignored))
        .min(rest.clearance(back, ignored))
        - 0.01;
    let ok = |height: f32| {
        path(height)
            .iter()
            .all(|&p| rest.clearance(p, ignored) >= need)
    };
    let (mut lo, mut hi) = (0.0f32, 40.0f32);
    if ok(lo) {
        return path(lo);
    }
    for _ in 0..24 {
        let mid = 0.5 * (lo + hi);
        if ok(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    path(hi)
}

fn polyline_length(points: &[Vec3]) -> f32 {
    points.windows(2).map(|w| w[0].distance(w[1])).sum()
}

/// `segments + 1` points evenly spaced by arc length along a polyline (ends included).
fn resample(points: &[Vec3], segments: usize) -> Vec<Vec3> {
    let total = polyline_length(points);
    let mut out = Vec::with_capacity(segments + 1);
    let mut walked = 0.0f32;
    let mut i = 0usize;
    for s in 0..=segments {
        let target = total * s as f32 / segments as f32;
        while i + 2 < points.len() && walked + points[i].distance(points[i + 1]) < target {
            walked += points[i].distance(points[i + 1]);
            i += 1;
        }
        let seg = points[i].distance(points[(i + 1).min(points.len() - 1)]);
        let t = if seg > 0.0 {
            ((target - walked) / seg).clamp(0.0, 1.0)
        } else {
            0.0
        };
        out.push(points[i].lerp(points[(i + 1).min(points.len() - 1)], t));
    }
    out
}

/// A short sleeve welded to an armhole loop (the loop runs as the bodice's triangles run it).
///
/// Rings of evenly spaced vertices, sampled at even arc-length fractions of the armhole loop so they
/// do not inherit its uneven spacing: the first halfway between the loop and a circle around the
/// arm, the rest circles tapering to the arm's radius plus the ease, ending about half-way down the
/// upper arm. The loop is stitched to the first ring by arc-length fraction. Returns the last ring.
fn build_sleeve(
    b: &mut Builder,
    armhole: &[u32],
    shoulder: Vec3,
    elbow: Vec3,
    arm: &Capsule,
    params: &GarmentParams,
) -> Vec<u32> {
    let d = (elbow - shoulder).normalize_or(Vec3::X);
    let upper_arm = elbow.distance(shoulder);
    let l = armhole.len();
    if l < 3 {
        return Vec::new();
    }
    let loop_points: Vec<Vec3> = armhole.iter().map(|&v| b.positions[v as usize]).collect();
    // Arc-length fraction of each loop vertex.
    let mut along_loop = Vec::with_capacity(l + 1);
    along_loop.push(0.0f64);
    for m in 0..l {
        let step = loop_points[m].distance(loop_points[(m + 1) % l]) as f64;
        along_loop.push(along_loop[m] + step);
    }
    let perimeter = along_loop[l].max(1e-6);
    let loop_at: Vec<f64> = along_loop[..l].iter().map(|a| a / perimeter).collect();
    let axial_of = |p: Vec3| (p - shoulder).dot(d);
    let radial_of = |p: Vec3| p - shoulder - d * axial_of(p);
    let count = l as f32;
    let centre = loop_points.iter().map(|&p| radial_of(p)).sum::<Vec3>() / count;
    let mean_radius = loop_points
        .iter()
        .map(|&p| radial_of(p).distance(centre))
        .sum::<f32>()
        / count;
    let start = loop_points
        .iter()
        .map(|&p| axial_of(p))
        .fold(f32::NEG_INFINITY, f32::max);
    let end = (0.55 * upper_arm).max(start + 2.0 * params.edge_cm);
    let rings = (((end - start) / params.edge_cm).round() as usize).max(2);
    let arm_at = |a: f32| arm.sphere_at((a / upper_arm.max(1e-3)).clamp(0.0, 1.0)).1;
    let end_radius = arm_at(end) + params.ease_cm;
    let around = ((std::f32::consts::TAU * 0.5 * (mean_radius + end_radius) / params.edge_cm)
        .round() as usize)
        .max(8);
    // Loop samples at even fractions.
    let samples: Vec<Vec3> = (0..around)
        .map(|k| {
            let target = perimeter * k as f64 / around as f64;
            let m = along_loop.partition_point(|&a| a <= target).clamp(1, l) - 1;
            let span = (along_loop[m + 1] - along_loop[m]).max(1e-9);
            let t = ((target - along_loop[m]) / span) as f32;
            loop_points[m].lerp(loop_points[(m + 1) % l], t)
        })
        .collect();
    let ring_at: Vec<f64> = (0..around).map(|k| k as f64 / around as f64).collect();
    // The circle's vertices: as many directions from the sleeve's axis as samples, evenly spread
    // in angle from the start that best matches the samples' own directions (the samples are even
    // in arc length along the armhole, which is no circle).
    let u = d.any_orthonormal_vector();
    let w = d.cross(u);
    let sample_angles: Vec<f32> = samples
        .iter()
        .map(|&q| {
            let r = radial_of(q) - centre;
            r.dot(w).atan2(r.dot(u))
        })
        .collect();
    let even_dirs: Vec<Vec3> = even_angles(&sample_angles)
        .into_iter()
        .map(|a| u * a.cos() + w * a.sin())
        .collect();
    let mut previous: Vec<u32> = armhole.to_vec();
    let mut previous_at = loop_at;
    for j in 1..=rings {
        let f = (j as f32 / 2.0).min(1.0);
        let along = start + (end - start) * j as f32 / rings as f32;
        let radius = mean_radius + (end_radius - mean_radius) * j as f32 / rings as f32;
        let ring: Vec<u32> = samples
            .iter()
            .zip(&even_dirs)
            .map(|(&q, &dir)| {
                let (a, r) = (axial_of(q), radial_of(q));
                b.vertex(shoulder + d * (a + (along - a) * f) + r.lerp(dir * radius, f))
            })
            .collect();
        b.loft_at(&previous, &previous_at, &ring, &ring_at, j % 2 == 0);
        previous = ring;
        previous_at = ring_at.clone();
    }
    previous
}

/// Angles spaced evenly around the circle, as many as `angles` (directions in order around a
/// loop, radians), turning the same way and starting where the mean offset from them is zero.
fn even_angles(angles: &[f32]) -> Vec<f32> {
    let mut unwrapped: Vec<f32> = Vec::with_capacity(angles.len());
    for &a in angles {
        let mut a = a;
        if let Some(&last) = unwrapped.last() {
            a -= TAU * ((a - last) / TAU).round();
        }
        unwrapped.push(a);
    }
    let (Some(&first), Some(&last)) = (unwrapped.first(), unwrapped.last()) else {
        return Vec::new();
    };
    let turn = if last >= first { 1.0 } else { -1.0 };
    let step = turn * TAU / unwrapped.len() as f32;
    let start = unwrapped
        .iter()
        .enumerate()
        .map(|(k, a)| a - step * k as f32)
        .sum::<f32>()
        / unwrapped.len() as f32;
    (0..unwrapped.len())
        .map(|k| start + step * k as f32)
        .collect()
}

/// Torso z centre: the middle of the discs' front-to-back extent over the given heights.
fn section_centre(capsules: &[Capsule], heights: &[f32]) -> f32 {
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for &y in heights {
        for (c, r) in section(capsules, y) {
            lo = lo.min(c.y - r);
            hi = hi.max(c.y + r);
        }
    }
    if lo.is_finite() && hi.is_finite() {
        0.5 * (lo + hi)
    } else {
        0.0
    }
}

fn even_ceil(x: f32, minimum: usize) -> usize {
    let n = (x.round() as usize).max(minimum);
    n + n % 2
}

/// Heights from `bottom` to `top` in about `edge` steps (both ends included).
fn heights(bottom: f32, top: f32, edge: f32) -> Vec<f32> {
    let segments = (((top - bottom) / edge).round() as usize).max(2);
    (0..=segments)
        .map(|i| bottom + (top - bottom) * i as f32 / segments as f32)
        .collect()
}

const TORSO: [&str; 6] = [
    "pelvis",
    "abdomen",
    "chest",
    "neck",
    "right_thigh",
    "left_thigh",
];
const LEGS: [&str; 7] = [
    "pelvis",
    "abdomen",
    "right_thigh",
    "left_thigh",
    "right_shin",
    "left_shin",
    "chest",
];

/// Ellipse per height (fitted to the discs, plus ease).
fn fitted(capsules: &[Capsule], ys: &[f32], zc: f32, ease: f32) -> Vec<(f32, Vec2)> {
    let mut out: Vec<(f32, Vec2)> = Vec::with_capacity(ys.len());
    for &y in ys {
        let semi = fit_ellipse(&section(capsules, y), zc)
            .or_else(|| out.last().map(|l| l.1 - Vec2::splat(ease)))
            .unwrap_or(Vec2::new(10.0, 8.0));
        out.push((y, semi + Vec2::splat(ease)));
    }
    out
}

fn bodice_spec(
    rest: &Rest,
    params: &GarmentParams,
    bottom: f32,
    hang_straight: bool,
) -> Result<BodiceSpec, GarmentError> {
    let shoulder = rest
        .joint_position("rShldr")?
        .lerp(rest.joint_position("lShldr")?, 0.5);
    let arm_radius = rest
        .capsules_of(&["right_upper_arm"])?
        .first()
        .map_or(6.0, |c| c.radius_a);
    let torso = rest.capsules_of(&TORSO)?;
    let top = shoulder.y;
    let ys = heights(bottom, top, params.edge_cm);
    let zc = section_centre(&torso, &ys);
    let mut rings = fitted(&torso, &ys, zc, params.ease_cm);
    if hang_straight {
        for i in (0..rings.len() - 1).rev() {
            rings[i].1 = rings[i].1.max(rings[i + 1].1);
        }
    }
    let armpit_y = shoulder.y - arm_radius - params.ease_cm;
    let armpit = ys
        .iter()
        .rposition(|&y| y <= armpit_y)
        .unwrap_or(0)
        .min(ys.len().saturating_sub(3));
    let widest = rings
        .iter()
        .map(|r| ellipse_perimeter(r.1))
        .fold(0.0f32, f32::max);
    Ok(BodiceSpec {
        rings,
        zc,
        n: even_ceil(widest / params.edge_cm, 16),
        armpit,
    })
}

/// The boundary loop whose centroid best matches `pick` (smallest score).
fn find_loop(b: &Builder, loops: &[Vec<u32>], score: impl Fn(Vec3) -> f32) -> Option<Vec<u32>> {
    loops
        .iter()
        .map(|l| {
            let c =
                l.iter().map(|&v| b.positions[v as usize]).sum::<Vec3>() / l.len().max(1) as f32;
            (score(c), l)
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, l)| l.clone())
}

/// The neck opening's boundary loop and `rings` rings of its neighbours, bound rigidly to the chest.
fn neckline_anchors(
    b: &Builder,
    rest: &Rest,
    bodice: &Bodice,
    top_y: f32,
    rings: usize,
) -> Result<Vec<Anchor>, GarmentError> {
    let loops = boundary_loops(&b.triangles);
    let neck_half = bodice.neck_half;
    let neck = find_loop(b, &loops, |c| {
        c.x.abs() + (c.y - top_y).min(0.0).abs() * 2.0
    })
    .filter(|l| {
        l.iter()
            .all(|&v| b.positions[v as usize].x.abs() <= neck_half + bodice.x_cut)
    })
    .ok_or_else(|| GarmentError::Invalid {
        name: "neckline".into(),
        message: "no neck hole found".into(),
    })?;
    let chest = rest.joint("chest")?;
    let mut vertices = neck.clone();
    if rings > 0 {
        let adjacency = Adjacency::new(b.positions.len(), &unique_edges(&b.triangles));
        for _ in 0..rings {
            let current = vertices.clone();
            for &v in &current {
                vertices.extend_from_slice(adjacency.neighbours(v as usize));
            }
            vertices.sort_unstable();
            vertices.dedup();
        }
    }
    vertices.sort_unstable();
    vertices.dedup();
    if bodice.neckline == Neckline::Square {
        // Not the tops of the straps beside the neck: the head, tilting forward, reaches down to
        // them and would press into cloth that cannot give way. (A crew neckline keeps
        // `CREW_NECK_EASE_CM` more room around the neck.)
        let neck_y = rest.joint_position("neck")?.y;
        vertices.retain(|&v| b.positions[v as usize].y <= neck_y);
    }
    Ok(vertices
        .into_iter()
        .map(|v| Anchor {
            vertex: v,
            bone: chest,
            local: rest.bone_local(chest, b.positions[v as usize]),
            slack_cm: 0.0,
        })
        .collect())
}

/// Pushes every vertex at least `clear` cm out of every capsule, then recomputes anchor locals.
fn push_out(rest: &Rest, positions: &mut [Vec3], clear: f32) {
    for p in positions.iter_mut() {
        for _ in 0..6 {
            let mut moved = false;
            for c in &rest.prepared {
                let (d, n) = c.query((*p).into());
                if d < clear {
                    *p += Vec3::from(n) * (clear - d);
                    moved = true;
                }
            }
            if !moved {
                break;
            }
        }
    }
}

fn finish(
    rest: &Rest,
    name: &str,
    mut b: Builder,
    mut anchors: Vec<Anchor>,
    cuffs: Vec<Cuff>,
    ease: f32,
) -> GarmentMesh {
    push_out(rest, &mut b.positions, 0.5 * ease);
    for a in &mut anchors {
        a.local = rest.bone_local(a.bone, b.positions[a.vertex as usize]);
    }
    GarmentMesh {
        name: name.to_owned(),
        positions: b.positions,
        triangles: b.triangles,
        anchors,
        cuffs,
    }
}

/// How far a T-shirt's sleeve end may stand off the upper arm's capsule, cm ([`Cuff`]; it is cut at
/// the ease, 2.5 cm, off it). Without it nothing but the collisions held a sleeve on its arm, and
/// where the arm sinks into the torso the trunk wins: lowering the arms from the rest T-pose while
/// dressing, the arm pressed the sleeve's underside into the chest and came out through it, so on
/// CMU walk 02_01 and kick 10_03 most sleeve-end vertices were 5–16 cm off the arm within a few
/// frames and stayed off. The sleeve end may still slide along the arm: held also at its place along the arm
/// (within 2.5 cm), the sleeve of a shirt cut in the T-pose had to stretch over the shoulder of a
/// lowered arm, and the worst frame's 95th-percentile strain of `cargo bench --bench cloth`'s
/// T-shirts rose from 0.7–1.7 % to 2.5–4.3 % (maximum 15–20 %); allowed 5, 8 or 11 cm towards the
/// shoulder, 1.8–2.7 % (9–32 %), 1.1–2.2 % (9–14 %), 0.8–1.8 % (9–11 %). Tried on 2026-12-02 with
/// the armpit fix (the solver's `buried_arm_allowance`): the same hold (2.5, 5 and 8 cm of
/// slide) while dressing also lengthened every edge it stretched by more than 2 % (a cut fitted
/// to the first pose, up to twice the cut length): the walk's T-shirts stayed within the targets
/// (p95 0.9–1.7 %, maxima 9.0–10.0 %) but the kick's did not (p95 1.8–3.3 %, maxima 12–27 %,
/// the armhole's back seam stretched as the arms swing): not kept. Nor was cutting and dressing
/// from a rest pose with the upper arms lowered 20° or 35° (walk within the targets, the kick's
/// raised arms stretched it: p95 2.5–3.9 %, maxima 14–20 %). A sleeve that keeps its length on a
/// lowered and a raised arm needs more cloth where the arm bends (a sleeve cap, underarm ease),
/// not only another cutting pose (not done). What is done (2026-12-03): the solver draws a
/// sleeve end that slid more than 3 cm up the arm and lies in bunched cloth back down softly
/// (`SolverSettings::cuff_slide_cm`), which keeps the sleeves about 2 cm further down the arm on
/// average (up to 8 cm in the worst frames) within the strain targets.
pub const SLEEVE_CUFF_REACH_CM: f32 = 5.0;

fn tshirt(rest: &Rest, params: &GarmentParams) -> Result<GarmentMesh, GarmentError> {
    let hip = rest.joint_position("hip")?;
    let abdomen = rest.joint_position("abdomen")?;
    let hem = hip.y - 0.25 * (abdomen.y - hip.y);
    let spec = bodice_spec(rest, params, hem, true)?;
    let mut b = Builder::default();
    let bodice = build_bodice(&mut b, rest, &spec, params, Neckline::Crew)?;
    let top_y = spec.rings[spec.rings.len() - 1].0;
    let anchors = neckline_anchors(&b, rest, &bodice, top_y, 2)?;
    let mut cuffs = Vec::new();
    // Sleeves on the two armhole loops, their ends held around the upper arms.
    let loops = boundary_loops(&b.triangles);
    for (side, shoulder_name, elbow_name, part) in [
        (-1.0f32, "rShldr", "rForeArm", "right_upper_arm"),
        (1.0, "lShldr", "lForeArm", "left_upper_arm"),
    ] {
        let shoulder = rest.joint_position(shoulder_name)?;
        let elbow = rest.joint_position(elbow_name)?;
        let arm = rest
            .capsules_of(&[part])?
            .first()
            .copied()
            .ok_or(GarmentError::MissingPart(part))?;
        let armhole = find_loop(&b, &loops, |c| -(c.x * side) + (c.y - shoulder.y).abs())
            .filter(|l| l.iter().all(|&v| b.positions[v as usize].x * side > 0.0))
            .ok_or_else(|| GarmentError::Invalid {
                name: "tshirt".into(),
                message: format!("no armhole found on the {shoulder_name} side"),
            })?;
        let end = build_sleeve(&mut b, &armhole, shoulder, elbow, &arm, params);
        let bone = rest.joint(shoulder_name)?;
        cuffs.extend(end.into_iter().map(|vertex| Cuff {
            vertex,
            bone,
            reach_cm: SLEEVE_CUFF_REACH_CM,
        }));
    }
    Ok(finish(rest, "tshirt", b, anchors, cuffs, params.ease_cm))
}

/// How far the skirt flares out from the vertical, degrees: a full skirt, whose hem has room for a
/// thigh raised in a kick. Chosen on the cloth benchmark's walk and kick (live settings, 2,000 and
/// 4,000 vertices, the kick's worst-frame 95th-percentile strain): at 12° (an A-line, with no cloth
/// to spare over the thigh, stretched and compressed over it in front) 2.34 / 2.75 %; with rings
/// spaced as at 12° whatever the flare, 6° 5.04 / 3.86 % (and a walk edge at 11.7 %), 18° 2.10 /
/// 2.24 %, 20° 1.99 / 2.08 %, 30° 1.57 / 1.85 %;
/// with rings one edge apart along the slant (as now) 24° 1.47 / 1.62 %, 30° 1.56 / 1.87 %, 36°
/// 1.36 / 1.41 % but an edge of the walk's at 11.1 %. 24° is the smallest flare tried that meets
/// the targets on both (and on the three held-out clips of docs/measurements.md, checked afterwards).
pub const SKIRT_FLARE_DEG: f32 = 24.0;
/// The dress's skirt flares less (an A-line): it hangs from a waist that follows the hip loosely,
/// and meets the strain targets as it is.
pub const DRESS_FLARE_DEG: f32 = 12.0;

/// Skirt rings from `waist_y` down to the hem, flaring by `flare_deg`: (height, semi-axes), top
/// first.
fn skirt_rings(
    rest: &Rest,
    params: &GarmentParams,
    waist_y: f32,
    waist_semi: Option<Vec2>,
    zc: f32,
    flare_deg: f32,
) -> Result<Vec<(f32, Vec2)>, GarmentError> {
    let knee = rest
        .joint_position("rShin")?
        .lerp(rest.joint_position("lShin")?, 0.5);
    let hem = knee.y + 3.0;
    let legs = rest.capsules_of(&LEGS)?;
    let flare = flare_deg.to_radians().tan();
    // Rings one edge apart along the flared slant.
    let step = params.edge_cm * flare_deg.to_radians().cos();
    let ys: Vec<f32> = heights(hem, waist_y, step).into_iter().rev().collect();
    let mut out: Vec<(f32, Vec2)> = Vec::with_capacity(ys.len());
    for (i, &y) in ys.iter().enumerate() {
        let body = fit_ellipse(&section(&legs, y), zc).unwrap_or(Vec2::new(10.0, 8.0));
        let semi = if i == 0 {
            waist_semi.unwrap_or(body + Vec2::splat(0.4 * params.ease_cm + 0.5))
        } else {
            let above = out[i - 1].1;
            let flared = out[0].1 + Vec2::splat(flare * (waist_y - y));
            above.max(flared).max(body + Vec2::splat(params.ease_cm))
        };
        out.push((y, semi));
    }
    Ok(out)
}

/// Rings of a flared skirt hung from `waist` (the first ring's vertices), top down; returns the
/// bottom ring.
fn build_skirt_rings(b: &mut Builder, waist: Vec<u32>, rings: &[(f32, Vec2)], zc: f32, edge: f32) {
    let mut upper = waist;
    for (i, &(y, semi)) in rings.iter().enumerate().skip(1) {
        let n = ((ellipse_perimeter(semi) / edge).round() as usize).max(upper.len());
        let lower: Vec<u32> = ellipse_ring(y, zc, semi, n)
            .into_iter()
            .map(|p| b.vertex(p))
            .collect();
        b.loft(&lower, &upper, i % 2 == 0);
        upper = lower;
    }
}

fn skirt(rest: &Rest, params: &GarmentParams) -> Result<GarmentMesh, GarmentError> {
    let hip = rest.joint_position("hip")?;
    let abdomen = rest.joint_position("abdomen")?;
    let waist_y = hip.y + 0.7 * (abdomen.y - hip.y);
    let legs = rest.capsules_of(&LEGS)?;
    let zc = section_centre(&legs, &[waist_y, hip.y]);
    let rings = skirt_rings(rest, params, waist_y, None, zc, SKIRT_FLARE_DEG)?;
    let mut b = Builder::default();
    let (y0, semi0) = rings[0];
    let n0 = even_ceil(ellipse_perimeter(semi0) / params.edge_cm, 16);
    let waist: Vec<u32> = ellipse_ring(y0, zc, semi0, n0)
        .into_iter()
        .map(|p| b.vertex(p))
        .collect();
    build_skirt_rings(&mut b, waist.clone(), &rings, zc, params.edge_cm);
    // The waistband: the top ring and the one below it, on the hip bone.
    let hip_bone = rest.joint("hip")?;
    let adjacency = Adjacency::new(b.positions.len(), &unique_edges(&b.triangles));
    let mut band = waist.clone();
    for &v in &waist {
        band.extend_from_slice(adjacency.neighbours(v as usize));
    }
    band.sort_unstable();
    band.dedup();
    let anchors = band
        .into_iter()
        .map(|v| Anchor {
            vertex: v,
            bone: hip_bone,
            local: Vec3::ZERO,
            slack_cm: 0.0,
        })
        .collect();
    Ok(finish(
        rest,
        "skirt",
        b,
        anchors,
        Vec::new(),
        params.ease_cm,
    ))
}

/// How far the dress's waist may move from its place on the hip bone before the belt pulls it
/// back, cm. With 2.5 cm the kick (CMU 10_03), whose spine arches further than a walk's, left the
/// bodice front 5.1 % strained at the 95th percentile in its worst frame (4,000 vertices, live
/// settings); with 4 cm, 4.2 % (3.0 % once the solver projected its tethers before the stretch
/// sweeps, 2.4 % with the soft belt of
/// [`SolverSettings::loose_anchor_seconds`](super::solver::SolverSettings::loose_anchor_seconds)).
/// CMU 11_01's kick still stretched the bodice's back to 3.1–3.3 % with 4 cm; 6 cm with a softer
/// belt (100 ms) keeps it under 2 % (chosen over 4 / 6 / 8 cm and 5–100 ms on the cases of
/// docs/measurements.md, first session of 2026-12-06).
pub const DRESS_WAIST_SLACK_CM: f32 = 6.0;

fn dress(rest: &Rest, params: &GarmentParams) -> Result<GarmentMesh, GarmentError> {
    let abdomen = rest.joint_position("abdomen")?;
    let waist_y = abdomen.y;
    let spec = bodice_spec(rest, params, waist_y, false)?;
    let mut b = Builder::default();
    let bodice = build_bodice(&mut b, rest, &spec, params, Neckline::Square)?;
    let top_y = spec.rings[spec.rings.len() - 1].0;
    let mut anchors = neckline_anchors(&b, rest, &bodice, top_y, 0)?;
    let waist: Vec<u32> = bodice.grid[0].iter().map(|v| v.unwrap_or(0)).collect();
    let rings = skirt_rings(
        rest,
        params,
        waist_y,
        Some(spec.rings[0].1),
        spec.zc,
        DRESS_FLARE_DEG,
    )?;
    build_skirt_rings(&mut b, waist.clone(), &rings, spec.zc, params.edge_cm);
    let hip_bone = rest.joint("hip")?;
    // The waist follows the hip loosely: the neckline hangs from the chest, and the back of the
    // bodice lengthens by a few centimetres whenever the spine flexes, which two rigid rings on
    // different bones would have to take as stretch.
    anchors.extend(waist.iter().map(|&v| Anchor {
        vertex: v,
        bone: hip_bone,
        local: Vec3::ZERO,
        slack_cm: DRESS_WAIST_SLACK_CM,
    }));
    Ok(finish(
        rest,
        "dress",
        b,
        anchors,
        Vec::new(),
        params.ease_cm,
    ))
}

/// Bone rest transforms for binding arbitrary meshes (the OBJ loader's anchors).
pub(crate) fn rest_pose(rig: &BodyRig) -> BodyPose {
    let mut pose = BodyPose::default();
    rig.pose(&rig.rest_frame(), &mut pose);
    pose
}

/// The local position of `p` in `bone`'s rest frame.
pub(crate) fn to_bone_local(bones: &[Affine3A], bone: usize, p: Vec3) -> Vec3 {
    bones
        .get(bone)
        .map_or(p, |b| b.inverse().transform_point3(p))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::cloth::proxies::DEFAULT_MARGIN_CM;
    use crate::cloth::topology::consistently_wound;
    use std::path::Path;

    pub fn chidi() -> BodyRig {
        let clip =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mocap/cmu_02_01_walk.bvh");
        let motion = crate::bvh::Motion::load(&clip).expect("clip");
        let subject = crate::body::Subject::find("chidi").expect("chidi");
        BodyRig::for_subject(subject, &motion.skeleton, DEFAULT_MARGIN_CM).expect("rig")
    }

    #[test]
    fn ellipse_ring_is_even_and_symmetric() {
        let ring = ellipse_ring(5.0, 1.0, Vec2::new(15.0, 10.0), 40);
        assert_eq!(ring.len(), 40);
        assert!((ring[0] - Vec3::new(15.0, 5.0, 1.0)).length() < 1e-4);
        // Mirror columns k and n − k have the same x, opposite z about the centre.
        for k in 1..20 {
            let (f, b) = (ring[k], ring[40 - k]);
            assert!(
                (f.x - b.x).abs() < 2e-3 && (f.z - 1.0 + b.z - 1.0).abs() < 2e-3,
                "{k}"
            );
        }
        let perimeter = ellipse_perimeter(Vec2::new(15.0, 10.0));
        for k in 0..40 {
            let step = ring[k].distance(ring[(k + 1) % 40]);
            assert!((step - perimeter / 40.0).abs() < 0.02, "{k} {step}");
        }
    }

    #[test]
    fn even_angles_spread_crowded_directions_around_the_circle() {
        // Four directions crowded at 0, 10°, 20° and 180° (wrapping through ±π): even would be
        // 90° apart, turning anticlockwise, starting at the mean offset (0 + 10 + 20 + 180
        // − 0 − 90 − 180 − 270)/4 = −82.5°.
        let deg = |d: f32| d.to_radians();
        let even = even_angles(&[deg(0.0), deg(10.0), deg(20.0), deg(-180.0)]);
        let expected = [-82.5, 7.5, 97.5, 187.5].map(deg);
        for (a, e) in even.iter().zip(expected) {
            assert!((a - e).abs() < 1e-4, "{even:?}");
        }
        // Clockwise loops stay clockwise; nothing in, nothing out.
        let cw = even_angles(&[deg(0.0), deg(-90.0), deg(-180.0), deg(90.0)]);
        assert!((cw[1] - cw[0] + deg(90.0)).abs() < 1e-4, "{cw:?}");
        assert!(even_angles(&[]).is_empty());
    }

    #[test]
    fn fitted_ellipse_contains_the_discs() {
        let discs = vec![(Vec2::new(-5.0, 0.0), 11.0), (Vec2::new(5.0, 0.0), 11.0)];
        let semi = fit_ellipse(&discs, 0.0).expect("fit");
        for (c, r) in &discs {
            for k in 0..360 {
                let (s, co) = (k as f32).to_radians().sin_cos();
                let p = *c + Vec2::new(co, s) * *r;
                let inside = (p.x / semi.x).powi(2) + (p.y / semi.y).powi(2);
                assert!(inside <= 1.0 + 1e-3, "{p} {semi}");
            }
        }
    }

    fn check_garment(mesh: &GarmentMesh, rig: &BodyRig) {
        mesh.validate().expect("valid");
        assert!(consistently_wound(&mesh.triangles), "{}", mesh.name);
        // One connected piece.
        let adjacency = Adjacency::new(mesh.positions.len(), &unique_edges(&mesh.triangles));
        let mut seen = vec![false; mesh.positions.len()];
        let mut stack = vec![0u32];
        seen[0] = true;
        while let Some(v) = stack.pop() {
            for &w in adjacency.neighbours(v as usize) {
                if !seen[w as usize] {
                    seen[w as usize] = true;
                    stack.push(w);
                }
            }
        }
        assert!(seen.iter().all(|&s| s), "{} is in pieces", mesh.name);
        // Outward: most triangle normals point away from the nearest capsule axis.
        let rest = Rest::new(rig);
        let mut outward = 0;
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            let n = (b - a).cross(c - a);
            let centroid = (a + b + c) / 3.0;
            let nearest = rest
                .pose
                .capsules
                .iter()
                .map(|cap| cap.closest(centroid))
                .min_by(|x, y| x.distance.total_cmp(&y.distance))
                .expect("capsules");
            if n.dot(nearest.normal) > 0.0 {
                outward += 1;
            }
        }
        assert!(
            outward * 100 > mesh.triangles.len() * 95,
            "{}: {outward} of {} outward",
            mesh.name,
            mesh.triangles.len()
        );
        // No slivers: the shortest edge at least 0.4 of the mean (the sleeve join once made
        // edges a fifth of the mean, which the solver squashed by half).
        let lengths: Vec<f32> = unique_edges(&mesh.triangles)
            .iter()
            .map(|&[i, j]| mesh.positions[i as usize].distance(mesh.positions[j as usize]))
            .collect();
        let mean = lengths.iter().sum::<f32>() / lengths.len() as f32;
        let shortest = lengths.iter().copied().fold(f32::INFINITY, f32::min);
        assert!(
            shortest >= 0.4 * mean,
            "{}: {shortest} of {mean}",
            mesh.name
        );
        // Clear of the body at rest.
        for p in &mesh.positions {
            assert!(rest.clearance(*p, &[]) > 0.5, "{} {p}", mesh.name);
        }
        // Anchors map back to their rest positions.
        for a in &mesh.anchors {
            let world = rest.pose.bones[a.bone].transform_point3(a.local);
            assert!(world.distance(mesh.positions[a.vertex as usize]) < 1e-3);
        }
        assert!(!mesh.anchors.is_empty());
    }

    #[test]
    fn garments_fit_the_body() {
        let rig = chidi();
        for kind in GarmentKind::ALL {
            let mesh = GarmentMesh::generate(kind, &rig, &GarmentParams::live()).expect("garment");
            check_garment(&mesh, &rig);
            let loops = boundary_loops(&mesh.triangles);
            // T-shirt: hem, neck, two sleeve ends; skirt: waist and hem; dress: neck, two armholes, hem.
            let expected = match kind {
                GarmentKind::TShirt => 4,
                GarmentKind::Skirt => 2,
                GarmentKind::Dress => 4,
            };
            assert_eq!(loops.len(), expected, "{}", mesh.name);
            println!(
                "{}: {} vertices, {} triangles, {} anchors",
                mesh.name,
                mesh.positions.len(),
                mesh.triangles.len(),
                mesh.anchors.len()
            );
        }
    }

    #[test]
    fn a_tshirt_has_a_round_neck_anchored_all_round() {
        let rig = chidi();
        let params = GarmentParams::live();
        let mesh = GarmentMesh::generate(GarmentKind::TShirt, &rig, &params).expect("tshirt");
        let rest = Rest::new(&rig);
        let neck = rest.capsules_of(&["neck"]).expect("neck")[0];
        let axis = (neck.b - neck.a).normalize();
        let from_axis = |p: Vec3| {
            let r = p - neck.a;
            (r - axis * r.dot(axis)).length()
        };
        // The neck loop is the boundary loop nearest the neck's axis.
        let loops = boundary_loops(&mesh.triangles);
        let mean_distance = |l: &Vec<u32>| {
            l.iter()
                .map(|&v| from_axis(mesh.positions[v as usize]))
                .sum::<f32>()
                / l.len() as f32
        };
        let neckline = loops
            .iter()
            .min_by(|a, b| mean_distance(a).total_cmp(&mean_distance(b)))
            .expect("loops");
        // Round: every vertex of the loop is the opening's radius (the neck's capsule, the ease and
        // the crew neck's room) from the axis, give or take an edge where the cut crosses a quad.
        let radius = neck.radius_a + params.ease_cm + CREW_NECK_EASE_CM;
        for &v in neckline {
            let d = from_axis(mesh.positions[v as usize]);
            assert!(
                (radius - 0.5..radius + params.edge_cm).contains(&d),
                "vertex {v} {d} cm from the neck's axis, opening {radius}"
            );
        }
        // The front of the opening stands above the shoulder line, where the bodice's top ring
        // lies and where a square neckline's front edge runs.
        let shoulder_y = rest.joint_position("rShldr").expect("shoulder").y;
        let front_lowest = neckline
            .iter()
            .map(|&v| mesh.positions[v as usize])
            .filter(|p| p.z > neck.a.z)
            .map(|p| p.y)
            .fold(f32::INFINITY, f32::min);
        assert!(
            front_lowest > shoulder_y + 2.0 * params.edge_cm,
            "front {front_lowest}, shoulders {shoulder_y}"
        );
        // The whole neckline is bound to the chest.
        let anchored: Vec<u32> = mesh.anchors.iter().map(|a| a.vertex).collect();
        assert!(neckline.iter().all(|v| anchored.contains(v)));
    }

    #[test]
    fn every_built_in_subject_gets_every_garment_in_both_modes() {
        // The smallest subject's shoulders must still leave room around the crew neck. (Only
        // that the garments are made, whole and anchored: ana's 2 cm T-shirt has one edge of
        // 0.34 × the mean where the sleeve's first ring meets the armhole at the armpit, under
        // `check_garment`'s 0.4.)
        let clip =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mocap/cmu_02_01_walk.bvh");
        let motion = crate::bvh::Motion::load(&clip).expect("clip");
        for index in 0..6 {
            let subject = crate::body::Subject::find(&index.to_string()).expect("subject");
            let rig =
                BodyRig::for_subject(subject, &motion.skeleton, DEFAULT_MARGIN_CM).expect("rig");
            assert_every_garment_is_whole(&rig, subject.name);
        }
    }

    /// Every garment of both modes is made for `rig`, whole (the skirt's waist and hem; the
    /// T-shirt's and the dress's neck, hem and two arm openings as boundary loops) and anchored;
    /// `case` names the rig in a failure.
    fn assert_every_garment_is_whole(rig: &BodyRig, case: &str) {
        for params in [GarmentParams::live(), GarmentParams::quality()] {
            for kind in GarmentKind::ALL {
                let case = format!("{case}, {} cm {kind:?}", params.edge_cm);
                let mesh = GarmentMesh::generate(kind, rig, &params)
                    .unwrap_or_else(|e| panic!("{case}: {e}"));
                let loops = boundary_loops(&mesh.triangles).len();
                let expected = if kind == GarmentKind::Skirt { 2 } else { 4 };
                assert_eq!(loops, expected, "{case}");
                assert!(!mesh.anchors.is_empty(), "{case}");
            }
        }
    }

    /// The sizes `suitcap run` and `live` measure a person at (any height and girth the body-size
    /// estimate may report, on the suit's skeleton) all get every garment, whole: with the crew
    /// neck cut as far as the neck asked, narrow shoulders let the opening run into an armhole
    /// (seen in `suitcap run` on the walk 02_01 test sequence, measured at 1.2 × the skeleton,
    /// girth 0.85: no T-shirt for the whole take).
    #[test]
    fn every_measured_body_size_gets_every_garment() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("suits/default/skeleton.bvh");
        let template = crate::bvh::Motion::load(&path).expect("skeleton").skeleton;
        for height_scale in [0.85f32, 0.9, 0.95, 1.0, 1.05, 1.1, 1.15, 1.2] {
            for girth in (0..=12).map(|k| 0.8 + 0.05 * k as f32) {
                let size = crate::body_size::BodySize {
                    height_scale,
                    girth,
                    frames: 10,
                };
                let (subject, skeleton) = size.subject(&template);
                let body = crate::body::Body::new(&subject, &skeleton).expect("body");
                let rig = BodyRig::new(skeleton, body, DEFAULT_MARGIN_CM);
                assert_every_garment_is_whole(&rig, &format!("{height_scale} × {girth}"));
            }
        }
    }

    #[test]
    fn quality_mode_has_about_four_times_the_vertices() {
        let rig = chidi();
        let live =
            GarmentMesh::generate(GarmentKind::Skirt, &rig, &GarmentParams::live()).expect("live");
        let fine = GarmentMesh::generate(GarmentKind::Skirt, &rig, &GarmentParams::quality())
            .expect("fine");
        let ratio = fine.positions.len() as f32 / live.positions.len() as f32;
        assert!((3.4..4.6).contains(&ratio), "{ratio}");
        let (mesh, edge) =
            GarmentMesh::with_vertex_count(GarmentKind::TShirt, &rig, 3000, 2.5).expect("sized");
        assert!(
            mesh.positions.len().abs_diff(3000) < 150,
            "{} at {edge}",
            mesh.positions.len()
        );
        check_garment(&mesh, &rig);
    }

    #[test]
    fn bad_parameters_are_rejected() {
        let rig = chidi();
        let bad = GarmentParams {
            edge_cm: 0.0,
            ease_cm: 2.0,
        };
        assert_eq!(
            GarmentMesh::generate(GarmentKind::Dress, &rig, &bad),
            Err(GarmentError::BadEdge(0.0))
        );
        assert_eq!("Dress".parse::<GarmentKind>(), Ok(GarmentKind::Dress));
        assert!("cape".parse::<GarmentKind>().is_err());
    }
}
