//! The body: subjects' proportions, tapered elliptic capsules along the bones, and the suit pattern on them.
//!
//! A [`Subject`] scales the mocap skeleton (height, limb ratios) and the flesh around it (girth).
//! [`Body::new`] builds one [`BodyPart`] per bone segment, a capsule whose cross-section is an ellipse
//! that tapers linearly from one end to the other and is closed by half-ellipsoid caps. Each part
//! moves rigidly with its joint. Suit parts carry the marker grid in physical units: rows every
//! `pitch` centimetres along the bone, columns every ≥ `pitch` centimetres of arc around it, so a
//! marker is a `marker_size_cm` square on any subject; where two suit parts overlap one grid is
//! printed ([`Body::marker_grid`]). The generator rasterizes [`PartMesh`]es and paints them with
//! the printed grids, the pattern printer prints them, and the cloth stage uses the same capsules
//! as collision proxies.

use std::f32::consts::TAU;

use glam::{Affine3A, Vec2, Vec3};

use crate::skeleton::Skeleton;
use crate::suit::SuitDefinition;

/// Height of the unscaled mocap figure (the Daz "Aiko3" of the shipped CMU conversion), top of head.
pub const BASE_HEIGHT_CM: f32 = 166.0;

/// How far each shoulder joint lies sideways from the chest joint in the rest pose, on the base
/// figure, cm ([`Subject::fit_shoulders`]; times the subject's girth and height scale). The shipped
/// CMU skeletons put it 11.5 cm out, so the hanging upper arm's axis lay 5 cm inside the chest part
/// (16.5 cm to each side at its top) and a T-shirt's torso tube covered the arms. At 19.6 cm (a
/// shoulder breadth of 49 cm on the base figure: broad) the hanging upper arm, 4.9 cm thick at the
/// top, clears the chest below the armpit, and the sleeves sit around the arms (docs/measurements.md,
/// second session of 2026-12-07).
pub const SHOULDER_HALF_BREADTH_CM: f32 = 19.6;

/// What a part is made of, which decides its colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Material {
    /// Suit cloth with the marker pattern.
    Suit,
    Skin,
    Shoe,
}

/// Proportions and colours of one person.
#[derive(Clone, Debug, PartialEq)]
pub struct Subject {
    pub name: &'static str,
    pub height_cm: f32,
    /// Multiplies every radius (1 = the base figure's build).
    pub girth: f32,
    /// Multiplies arm bone lengths on top of the height scale.
    pub arm_ratio: f32,
    /// Multiplies leg bone lengths on top of the height scale.
    pub leg_ratio: f32,
    /// Skin albedo, linear RGB in [0, 1].
    pub skin: [f32; 3],
    /// Shoe albedo.
    pub shoe: [f32; 3],
}

/// The built-in subjects the generator renders, selectable by name or index.
pub const SUBJECTS: [Subject; 6] = [
    Subject {
        name: "ana",
        height_cm: 158.0,
        girth: 0.92,
        arm_ratio: 1.00,
        leg_ratio: 0.97,
        skin: [0.87, 0.68, 0.58],
        shoe: [0.06, 0.06, 0.07],
    },
    Subject {
        name: "ben",
        height_cm: 186.0,
        girth: 1.12,
        arm_ratio: 1.03,
        leg_ratio: 1.02,
        skin: [0.62, 0.44, 0.32],
        shoe: [0.10, 0.08, 0.07],
    },
    Subject {
        name: "chidi",
        height_cm: 176.0,
        girth: 1.00,
        arm_ratio: 1.05,
        leg_ratio: 1.05,
        skin: [0.36, 0.24, 0.18],
        shoe: [0.05, 0.05, 0.05],
    },
    Subject {
        name: "dana",
        height_cm: 165.0,
        girth: 1.22,
        arm_ratio: 0.97,
        leg_ratio: 0.95,
        skin: [0.78, 0.58, 0.44],
        shoe: [0.12, 0.10, 0.10],
    },
    Subject {
        name: "emil",
        height_cm: 193.0,
        girth: 0.95,
        arm_ratio: 1.04,
        leg_ratio: 1.08,
        skin: [0.93, 0.76, 0.68],
        shoe: [0.08, 0.08, 0.10],
    },
    Subject {
        name: "fumiko",
        height_cm: 152.0,
        girth: 0.90,
        arm_ratio: 0.98,
        leg_ratio: 0.96,
        skin: [0.90, 0.74, 0.60],
        shoe: [0.15, 0.12, 0.12],
    },
];

impl Subject {
    /// A built-in subject by name (case-insensitive) or index.
    pub fn find(name_or_index: &str) -> Option<&'static Subject> {
        if let Ok(index) = name_or_index.parse::<usize>() {
            return SUBJECTS.get(index);
        }
        SUBJECTS
            .iter()
            .find(|s| s.name.eq_ignore_ascii_case(name_or_index))
    }

    fn height_scale(&self) -> f32 {
        self.height_cm / BASE_HEIGHT_CM
    }

    /// Bone-length factor of joint `index`: arms and legs get their ratios on top of the height scale.
    fn bone_scale(&self, skeleton: &Skeleton, index: usize) -> f32 {
        let h = self.height_scale();
        let in_subtree = |names: &[&str]| {
            names
                .iter()
                .filter_map(|n| skeleton.find(n))
                .any(|root| skeleton.is_ancestor(root, index))
        };
        if in_subtree(&["rShldr", "lShldr"]) {
            h * self.arm_ratio
        } else if in_subtree(&["rThigh", "lThigh"]) {
            h * self.leg_ratio
        } else {
            h
        }
    }

    /// The mocap skeleton with this subject's bone lengths and its shoulders fitted
    /// ([`Subject::fit_shoulders`]).
    pub fn scale_skeleton(&self, skeleton: &Skeleton) -> Skeleton {
        let scales: Vec<f32> = (0..skeleton.len())
            .map(|i| self.bone_scale(skeleton, i))
            .collect();
        self.fit_shoulders(&skeleton.map_offsets(|i, offset| offset * scales[i]))
    }

    /// The skeleton with both shoulder joints (`rShldr`, `lShldr`) moved sideways, so that they
    /// lie [`SHOULDER_HALF_BREADTH_CM`] (times this subject's girth and height scale) from the
    /// chest joint in the rest pose; the rest of each arm moves with its shoulder. The distance is
    /// set, not added to, so fitting a fitted skeleton changes nothing. A skeleton without a chest
    /// or shoulder joints is returned unchanged.
    pub fn fit_shoulders(&self, skeleton: &Skeleton) -> Skeleton {
        let Some(chest) = skeleton.find("chest") else {
            return skeleton.clone();
        };
        let target = SHOULDER_HALF_BREADTH_CM * self.girth * self.height_scale();
        let positions = skeleton.joint_positions(&vec![0.0; skeleton.channel_count()]);
        let mut shift = vec![0.0f32; skeleton.len()];
        for shoulder in ["rShldr", "lShldr"].iter().filter_map(|n| skeleton.find(n)) {
            let lateral = positions[shoulder].x - positions[chest].x;
            shift[shoulder] = target.copysign(lateral) - lateral;
        }
        skeleton.map_offsets(|i, offset| offset + Vec3::X * shift[i])
    }

    /// Scales a frame's root translation so that the feet of the scaled figure stay on the floor:
    /// height by the leg scale, ground-plane motion by the height scale.
    pub fn scale_root_translation(&self, skeleton: &Skeleton, frame: &mut [f32]) {
        let h = self.height_scale();
        let root = skeleton.joint(0);
        for (k, channel) in root.channels.iter().enumerate() {
            let scale = match channel {
                crate::skeleton::Channel::Yposition => h * self.leg_ratio,
                crate::skeleton::Channel::Xposition | crate::skeleton::Channel::Zposition => h,
                _ => 1.0,
            };
            if let Some(v) = frame.get_mut(root.first_channel + k) {
                *v *= scale;
            }
        }
    }
}

/// A capsule with elliptic, linearly tapering cross-section, in its joint's local frame.
#[derive(Clone, Debug, PartialEq)]
pub struct BodyPart {
    pub name: &'static str,
    /// Joint whose world transform moves the part.
    pub joint: usize,
    pub start: Vec3,
    pub end: Vec3,
    /// Semi-axes (along `width_axis`, across it) at `start`.
    pub radii_start: Vec2,
    pub radii_end: Vec2,
    /// Unit vector ⟂ to the bone along which the first semi-axis lies.
    pub width_axis: Vec3,
    /// Length of each end cap along the bone, as a fraction of the smaller semi-axis.
    pub cap: f32,
    /// Whether the start and the end cap carry markers: not where the part meets another suit part
    /// end to end (elbows, knees, the waist), so that the rows are laid out over the visible
    /// cloth. Markers near any other overlap (a limb rising out of the side of the trunk at the
    /// shoulders and hips) are left out by [`Body::marker_grid`].
    pub patterned_caps: [bool; 2],
    pub material: Material,
    /// Pattern surface id (the part's index), part of every marker id on it.
    pub surface: u32,
}

/// A vertex of a part's mesh, in the part's joint frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceVertex {
    pub position: Vec3,
    pub normal: Vec3,
    /// Centimetres along the bone from `start` (negative or beyond the length on the caps).
    pub u: f32,
    /// Fraction of the way around the cross-section by arc length, in [0, 1].
    pub s: f32,
}

/// Triangles wound so that `(b − a) × (c − a)` points out of the surface.
#[derive(Clone, Debug, PartialEq)]
pub struct PartMesh {
    pub vertices: Vec<SurfaceVertex>,
    pub triangles: Vec<[u32; 3]>,
}

/// One marker of the suit pattern on one body part.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MarkerCell {
    /// `surface · 10000 + row · 100 + column`.
    pub id: u32,
    /// Index into the suit's marker colours.
    pub colour: usize,
    pub row: u32,
    pub column: u32,
    /// Centre in (u cm, s fraction) surface coordinates.
    pub centre_u: f32,
    pub centre_s: f32,
}

/// The marker layout of one body part, precomputed for per-pixel lookups.
#[derive(Clone, Debug, PartialEq)]
pub struct MarkerGrid {
    surface: u32,
    pitch: f32,
    half_size: f32,
    /// `u` of the start of the first row.
    first_row_u: f32,
    /// Per row: number of columns and the perimeter they share.
    rows: Vec<(u32, f32)>,
    layout_seed: u64,
    colours: usize,
    /// Ids of the grid's cells that are not printed (sorted): they lie under or against another
    /// suit part ([`Body::marker_grid`]).
    unprinted: Vec<u32>,
}

impl MarkerGrid {
    fn printed(&self, id: u32) -> bool {
        self.unprinted.binary_search(&id).is_err()
    }

    fn cell(&self, row: u32, column: u32) -> MarkerCell {
        let columns = self.rows[row as usize].0;
        MarkerCell {
            id: self.surface * 10_000 + row * 100 + column,
            colour: crate::suit::layout_colour(
                self.layout_seed,
                self.colours,
                self.surface,
                row as i32,
                column,
            ),
            row,
            column,
            centre_u: self.first_row_u + (row as f32 + 0.5) * self.pitch,
            centre_s: (column as f32 + 0.5) / columns as f32,
        }
    }

    /// The marker covering surface point (`u` cm along the bone, `s` fraction around), if any.
    pub fn marker_at(&self, u: f32, s: f32) -> Option<MarkerCell> {
        let along = u - self.first_row_u;
        if along < 0.0 {
            return None;
        }
        let row = (along / self.pitch) as u32;
        let &(columns, circumference) = self.rows.get(row as usize)?;
        if columns == 0 {
            return None;
        }
        if (along - (row as f32 + 0.5) * self.pitch).abs() > self.half_size {
            return None;
        }
        let around = s.rem_euclid(1.0) * columns as f32;
        let column = (around as u32).min(columns - 1);
        let cell_width = circumference / columns as f32;
        if ((around - column as f32 - 0.5) * cell_width).abs() > self.half_size {
            return None;
        }
        Some(self.cell(row, column)).filter(|cell| self.printed(cell.id))
    }

    /// Every printed marker of the grid, row by row.
    pub fn cells(&self) -> impl Iterator<Item = MarkerCell> + '_ {
        (0..self.rows.len() as u32)
            .flat_map(move |row| {
                (0..self.rows[row as usize].0).map(move |column| self.cell(row, column))
            })
            .filter(|cell| self.printed(cell.id))
    }
}

/// Samples per quarter ellipse for the arc-length tables.
const ARC_STEPS: usize = 64;

impl BodyPart {
    pub fn length(&self) -> f32 {
        (self.end - self.start).length()
    }

    fn axis(&self) -> Vec3 {
        (self.end - self.start).normalize_or(Vec3::Y)
    }

    /// The two unit directions of the cross-section: along the width axis and across it.
    fn section_axes(&self) -> (Vec3, Vec3) {
        let d = self.axis();
        let mut e1 = self.width_axis - d * self.width_axis.dot(d);
        if e1.length_squared() < 1e-6 {
            e1 = d.any_orthonormal_vector();
        }
        let e1 = e1.normalize();
        (e1, d.cross(e1))
    }

    /// Semi-axes at `u` cm along the bone (clamped to the straight section).
    pub fn radii_at(&self, u: f32) -> Vec2 {
        let t = (u / self.length().max(1e-6)).clamp(0.0, 1.0);
        self.radii_start.lerp(self.radii_end, t)
    }

    /// Lengths of the start and end caps along the bone.
    pub fn cap_lengths(&self) -> (f32, f32) {
        (
            self.cap * self.radii_start.x.min(self.radii_start.y),
            self.cap * self.radii_end.x.min(self.radii_end.y),
        )
    }

    /// Scale of the cross-section at `u`: 1 on the straight section, √(1 − t²) at the fraction t of
    /// the way along a half-ellipsoid cap, 0 beyond it.
    pub fn section_scale(&self, u: f32) -> f32 {
        let (cap_start, cap_end) = self.cap_lengths();
        let length = self.length();
        let t = if u < 0.0 {
            -u / cap_start.max(1e-6)
        } else if u > length {
            (u - length) / cap_end.max(1e-6)
        } else {
            0.0
        };
        (1.0 - t.min(1.0).powi(2)).sqrt()
    }

    /// Perimeter of the cross-section at `u` (caps included).
    pub fn circumference_at(&self, u: f32) -> f32 {
        let r = self.radii_at(u);
        ellipse_arc_table(r.x, r.y)[4 * ARC_STEPS] * self.section_scale(u)
    }

    /// Point and outward normal at `u` cm along the bone (negative or beyond the length: on a cap)
    /// and angle `theta` around it.
    pub fn surface_point(&self, u: f32, theta: f32) -> (Vec3, Vec3) {
        let (e1, e2) = self.section_axes();
        let d = self.axis();
        let length = self.length().max(1e-6);
        let clamped = u.clamp(0.0, length);
        let r = self.radii_at(clamped);
        let (sin, cos) = theta.sin_cos();
        let radial = e1 * (r.x * cos) + e2 * (r.y * sin);
        let axial = u - clamped;
        if axial == 0.0 {
            let slope = (self.radii_end - self.radii_start) / length;
            // Gradient of the implicit surface (x/a)² + (y/b)² = 1 with a, b tapering along d.
            let normal = (e1 * (cos / r.x) + e2 * (sin / r.y)
                - d * (slope.x * cos * cos / r.x + slope.y * sin * sin / r.y))
                .normalize_or(e1);
            return (self.start + d * u + radial, normal);
        }
        // Half-ellipsoid cap: the section shrinks to the pole; the normal is the ellipsoid's gradient.
        let (cap_start, cap_end) = self.cap_lengths();
        let cap = if axial < 0.0 { cap_start } else { cap_end }.max(1e-3);
        let t = (axial / cap).clamp(-1.0, 1.0);
        let scale = (1.0 - t * t).sqrt();
        let normal = (e1 * (scale * cos / r.x) + e2 * (scale * sin / r.y) + d * (t / cap))
            .normalize_or(d * t.signum());
        (
            self.start + d * (clamped + t * cap) + radial * scale,
            normal,
        )
    }

    /// Angle at which the arc length from θ = 0 is the fraction `s` of the perimeter at `u`.
    pub fn theta_for(&self, u: f32, s: f32) -> f32 {
        let r = self.radii_at(u);
        theta_on(&ellipse_arc_table(r.x, r.y), s)
    }

    /// Triangle mesh: `around` segments around, rings about every `ring_spacing` cm, five rings per cap.
    pub fn mesh(&self, around: usize, ring_spacing: f32) -> PartMesh {
        let length = self.length();
        let d = self.axis();
        // Rings: (u along the bone, scale of the cross-section: 1 on the straight part, less on the caps).
        let mut rings: Vec<(f32, f32)> = Vec::new();
        const CAP_RINGS: usize = 5;
        let (cap_start, cap_end) = self.cap_lengths();
        for k in 0..CAP_RINGS {
            let phi = (CAP_RINGS - k) as f32 / CAP_RINGS as f32 * std::f32::consts::FRAC_PI_2;
            rings.push((-cap_start * phi.sin(), phi.cos()));
        }
        let sections = ((length / ring_spacing).ceil() as usize).max(1);
        for k in 0..=sections {
            rings.push((length * k as f32 / sections as f32, 1.0));
        }
        for k in 1..=CAP_RINGS {
            let phi = k as f32 / CAP_RINGS as f32 * std::f32::consts::FRAC_PI_2;
            rings.push((length + cap_end * phi.sin(), phi.cos()));
        }

        let mut vertices = Vec::with_capacity(rings.len() * (around + 1) + 2);
        for &(u, _) in &rings {
            let r = self.radii_at(u);
            let table = ellipse_arc_table(r.x, r.y);
            for k in 0..=around {
                let theta = TAU * k as f32 / around as f32;
                let (position, normal) = self.surface_point(u, theta);
                let step = k * ARC_STEPS * 4 / around;
                let s = table[step.min(4 * ARC_STEPS)] / table[4 * ARC_STEPS];
                vertices.push(SurfaceVertex {
                    position,
                    normal,
                    u,
                    s,
                });
            }
        }
        // Poles closing both caps.
        let first_pole = vertices.len() as u32;
        vertices.push(SurfaceVertex {
            position: self.start - d * cap_start,
            normal: -d,
            u: -cap_start,
            s: 0.0,
        });
        vertices.push(SurfaceVertex {
            position: self.end + d * cap_end,
            normal: d,
            u: length + cap_end,
            s: 0.0,
        });

        let stride = (around + 1) as u32;
        let mut triangles = Vec::with_capacity(2 * rings.len() * around + 2 * around);
        let mut push = |t: [u32; 3]| {
            // Wind outward: compare the face normal with the vertices' normals.
            let [a, b, c] = t.map(|i| vertices[i as usize]);
            let face = (b.position - a.position).cross(c.position - a.position);
            if face.dot(a.normal + b.normal + c.normal) >= 0.0 {
                triangles.push(t);
            } else {
                triangles.push([t[0], t[2], t[1]]);
            }
        };
        for ring in 0..rings.len() as u32 - 1 {
            for k in 0..around as u32 {
                let a = ring * stride + k;
                let b = a + 1;
                let c = a + stride + 1;
                let dd = a + stride;
                push([a, b, c]);
                push([a, c, dd]);
            }
        }
        let last_ring = (rings.len() as u32 - 1) * stride;
        for k in 0..around as u32 {
            push([first_pole, k, k + 1]);
            push([first_pole + 1, last_ring + k, last_ring + k + 1]);
        }
        PartMesh {
            vertices,
            triangles,
        }
    }

    /// The marker grid of this part for `suit`: rows along the straight section and the caps that
    /// carry markers ([`BodyPart::patterned_caps`]), each with as many columns as its perimeter holds
    /// (none close to a pole). Empty for parts that are not suit cloth.
    pub fn marker_grid(&self, suit: &SuitDefinition) -> MarkerGrid {
        let pitch = suit.pitch_cm();
        let (cap_start, cap_end) = self.cap_lengths();
        let low = if self.patterned_caps[0] {
            -cap_start
        } else {
            0.0
        };
        let high = self.length() + if self.patterned_caps[1] { cap_end } else { 0.0 };
        let total = high - low;
        let rows = if self.material == Material::Suit {
            (total / pitch).floor() as u32
        } else {
            0
        };
        let first_row_u = low + (total - rows as f32 * pitch) * 0.5;
        let rows = (0..rows)
            .map(|row| {
                let circumference = self.circumference_at(first_row_u + (row as f32 + 0.5) * pitch);
                ((circumference / pitch).floor() as u32, circumference)
            })
            .collect();
        MarkerGrid {
            surface: self.surface,
            pitch,
            half_size: suit.marker_size_cm * 0.5,
            first_row_u,
            rows,
            layout_seed: suit.layout_seed,
            colours: suit.markers.len(),
            unprinted: Vec::new(),
        }
    }

    /// Whether `point` (in the part's joint frame) lies inside the capsule grown by `margin` cm
    /// (semi-axes and cap lengths each `margin` longer).
    pub fn contains(&self, point: Vec3, margin: f32) -> bool {
        let (e1, e2) = self.section_axes();
        let relative = point - self.start;
        let u = relative.dot(self.axis());
        let (cap_start, cap_end) = self.cap_lengths();
        let length = self.length();
        let t = if u < 0.0 {
            -u / (cap_start + margin).max(1e-6)
        } else if u > length {
            (u - length) / (cap_end + margin).max(1e-6)
        } else {
            0.0
        };
        if t >= 1.0 {
            return false;
        }
        let r = self.radii_at(u) + Vec2::splat(margin);
        (relative.dot(e1) / r.x).powi(2) + (relative.dot(e2) / r.y).powi(2) <= 1.0 - t * t
    }

    /// The marker covering surface point (`u`, `s`), if any, on this part alone (without the
    /// markers [`Body::marker_grid`] leaves out where parts meet). Only suit parts carry markers.
    /// (Per-pixel callers should build a grid once and ask it.)
    pub fn marker_at(&self, suit: &SuitDefinition, u: f32, s: f32) -> Option<MarkerCell> {
        self.marker_grid(suit).marker_at(u, s)
    }

    /// Every marker of the pattern on this part alone (see [`BodyPart::marker_at`]).
    pub fn markers(&self, suit: &SuitDefinition) -> Vec<MarkerCell> {
        self.marker_grid(suit).cells().collect()
    }

    /// The point of a marker square at (`a`, `b`) ∈ [−1, 1]² across it (along the part's axis and
    /// round it; (0, 0) is its centre, (±1, ±1) its corners) and the outward surface normal there,
    /// in the part's local frame.
    pub fn marker_point(
        &self,
        suit: &SuitDefinition,
        cell: &MarkerCell,
        (a, b): (f32, f32),
    ) -> (Vec3, Vec3) {
        self.marker_points(suit, cell, &[a], &[b])[0]
    }

    /// [`BodyPart::marker_point`] at every pair of `along` × `around` (row by row: one row per
    /// entry of `along`), with one cross-section's arc table per row.
    pub fn marker_points(
        &self,
        suit: &SuitDefinition,
        cell: &MarkerCell,
        along: &[f32],
        around: &[f32],
    ) -> Vec<(Vec3, Vec3)> {
        let half = suit.marker_size_cm * 0.5;
        let ds = half / self.circumference_at(cell.centre_u);
        let mut points = Vec::with_capacity(along.len() * around.len());
        for &a in along {
            let u = cell.centre_u + a * half;
            let r = self.radii_at(u);
            let table = ellipse_arc_table(r.x, r.y);
            points.extend(
                around
                    .iter()
                    .map(|&b| self.surface_point(u, theta_on(&table, cell.centre_s + b * ds))),
            );
        }
        points
    }
}

/// The angle at which the arc length from θ = 0 is the fraction `s` of the perimeter, on an
/// ellipse's [`ellipse_arc_table`].
fn theta_on(table: &[f32; 4 * ARC_STEPS + 1], s: f32) -> f32 {
    let target = s.rem_euclid(1.0) * table[4 * ARC_STEPS];
    let i = table
        .partition_point(|&a| a < target)
        .clamp(1, 4 * ARC_STEPS);
    let (a0, a1) = (table[i - 1], table[i]);
    let frac = if a1 > a0 {
        (target - a0) / (a1 - a0)
    } else {
        0.0
    };
    (i as f32 - 1.0 + frac) * TAU / (4 * ARC_STEPS) as f32
}

/// Cumulative arc length of the ellipse (a cos θ, b sin θ) at θ = k·2π/(4·ARC_STEPS), k = 0..=4·ARC_STEPS.
fn ellipse_arc_table(a: f32, b: f32) -> [f32; 4 * ARC_STEPS + 1] {
    let mut table = [0.0f32; 4 * ARC_STEPS + 1];
    let step = TAU / (4 * ARC_STEPS) as f32;
    for k in 1..=4 * ARC_STEPS {
        let mid = (k as f32 - 0.5) * step;
        let speed = ((a * mid.sin()).powi(2) + (b * mid.cos()).powi(2)).sqrt();
        table[k] = table[k - 1] + speed * step;
    }
    table
}

/// How far outside another suit part (in the rest pose) a marker's centre must lie to be printed
/// ([`Body::marker_grid`]). Measured on the five marker sequences of `scripts/eval_markers.sh`
/// (ground-truth masks): margins of 0, 1, 2 and 3.5 cm print 233, 218, 188 and 132 of the 270
/// markers on the default subject and give the dance a recall of 0.951, 0.954, 0.953 and 0.962
/// (0.937 with both grids printed on the overlaps): 1 cm keeps four fifths of the markers, which the
/// Feature Context is made of, for most of the gain. Leaving the trunk's grid whole and dropping
/// only the limbs' markers kept more (247) but gave the dance 0.937–0.946 at 1–3.5 cm.
pub const SEAM_MARGIN_CM: f32 = 1.0;

/// A subject's body on a (scaled) skeleton.
#[derive(Clone, Debug, PartialEq)]
pub struct Body {
    pub parts: Vec<BodyPart>,
    /// World transform of every joint of the skeleton in its rest pose (all channels zero): where
    /// the parts sit relative to each other on the suit as it was cut and printed.
    pub rest_pose: Vec<Affine3A>,
}

/// The skeleton lacks a joint the body model hangs a part on.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("the body model needs BVH joint '{0}', which the motion's skeleton lacks (expected the CMU/Daz joint names of the shipped mocap)")]
pub struct MissingJoint(pub String);

impl Body {
    /// Builds the subject's parts on `skeleton`, which must already be scaled by
    /// [`Subject::scale_skeleton`].
    pub fn new(subject: &Subject, skeleton: &Skeleton) -> Result<Body, MissingJoint> {
        let find = |name: &str| {
            skeleton
                .find(name)
                .ok_or_else(|| MissingJoint(name.to_owned()))
        };
        let offset =
            |name: &str| -> Result<Vec3, MissingJoint> { Ok(skeleton.joint(find(name)?).offset) };
        let h = subject.height_scale();
        let g = subject.girth * h;
        let r = |a: f32, b: f32| Vec2::new(a, b) * g;
        let mut parts = Vec::new();
        let mut add = |name,
                       joint: &str,
                       start: Vec3,
                       end: Vec3,
                       rs: Vec2,
                       re: Vec2,
                       width_axis: Vec3,
                       cap: f32,
                       patterned_caps: [bool; 2],
                       material| {
            let surface = parts.len() as u32;
            parts.push(BodyPart {
                name,
                joint: find(joint)?,
                start,
                end,
                radii_start: rs,
                radii_end: re,
                width_axis,
                cap,
                patterned_caps,
                material,
                surface,
            });
            Ok::<(), MissingJoint>(())
        };
        use Material::*;
        let abdomen = offset("abdomen")?;
        let chest = offset("chest")?;
        let neck = offset("neck")?;
        add(
            "pelvis",
            "hip",
            Vec3::new(0.0, -7.0, 0.5) * h,
            abdomen,
            r(15.5, 10.5),
            r(13.8, 9.6),
            Vec3::X,
            0.7,
            [true, false],
            Suit,
        )?;
        add(
            "abdomen",
            "abdomen",
            Vec3::ZERO,
            chest,
            r(13.8, 9.6),
            r(14.8, 10.0),
            Vec3::X,
            0.5,
            [false, false],
            Suit,
        )?;
        add(
            "chest",
            "chest",
            Vec3::ZERO,
            neck * 0.86,
            r(15.2, 10.2),
            r(16.5, 9.5),
            Vec3::X,
            0.55,
            [false, true],
            Suit,
        )?;
        add(
            "neck",
            "neck",
            Vec3::ZERO,
            offset("head")?,
            r(5.4, 5.4),
            r(5.0, 5.0),
            Vec3::X,
            1.0,
            [true, true],
            Skin,
        )?;
        add(
            "head",
            "head",
            Vec3::new(0.0, 3.0, 1.5) * h,
            Vec3::new(0.0, 11.0, 1.5) * h,
            r(7.6, 9.0),
            r(7.6, 9.0),
            Vec3::X,
            1.0,
            [true, true],
            Skin,
        )?;
        for side in ["r", "l"] {
            let j = |n: &str| format!("{side}{n}");
            let hand = offset(&j("Hand"))?;
            add(
                if side == "r" {
                    "right_upper_arm"
                } else {
                    "left_upper_arm"
                },
                &j("Shldr"),
                Vec3::ZERO,
                offset(&j("ForeArm"))?,
                r(4.9, 4.9),
                r(4.3, 4.3),
                Vec3::Z,
                1.0,
                [false, false],
                Suit,
            )?;
            add(
                if side == "r" {
                    "right_forearm"
                } else {
                    "left_forearm"
                },
                &j("ForeArm"),
                Vec3::ZERO,
                hand,
                r(4.2, 4.2),
                r(3.0, 3.0),
                Vec3::Z,
                1.0,
                [false, true],
                Suit,
            )?;
            let hand_dir = hand.normalize_or(Vec3::X);
            add(
                if side == "r" {
                    "right_hand"
                } else {
                    "left_hand"
                },
                &j("Hand"),
                hand_dir * 1.0,
                hand_dir * 14.0 * h * subject.arm_ratio,
                r(4.3, 1.8),
                r(3.8, 1.5),
                Vec3::Z,
                1.0,
                [true, true],
                Skin,
            )?;
            add(
                if side == "r" {
                    "right_thigh"
                } else {
                    "left_thigh"
                },
                &j("Thigh"),
                Vec3::ZERO,
                offset(&j("Shin"))?,
                r(8.4, 8.0),
                r(5.6, 5.4),
                Vec3::X,
                1.0,
                [false, false],
                Suit,
            )?;
            add(
                if side == "r" {
                    "right_shin"
                } else {
                    "left_shin"
                },
                &j("Shin"),
                Vec3::ZERO,
                offset(&j("Foot"))?,
                r(5.3, 5.3),
                r(3.9, 3.9),
                Vec3::X,
                1.0,
                [false, true],
                Suit,
            )?;
            let toe = skeleton
                .joint(find(&j("Foot"))?)
                .end_site
                .unwrap_or(Vec3::new(0.0, -3.7, 12.1) * h);
            add(
                if side == "r" {
                    "right_foot"
                } else {
                    "left_foot"
                },
                &j("Foot"),
                Vec3::new(0.0, -3.6, -3.5) * h,
                toe + Vec3::new(0.0, 0.6, 0.0) * h,
                r(4.4, 3.4),
                r(4.0, 2.6),
                Vec3::X,
                1.0,
                [true, true],
                Shoe,
            )?;
        }
        Ok(Body::from_parts(parts, skeleton))
    }

    /// A body of the given parts on `skeleton` (each part's `joint` indexes it).
    pub fn from_parts(parts: Vec<BodyPart>, skeleton: &Skeleton) -> Body {
        let mut rest_pose = Vec::new();
        skeleton.forward_kinematics(&vec![0.0; skeleton.channel_count()], &mut rest_pose);
        Body { parts, rest_pose }
    }

    /// The printed marker grid of part `index`: its own grid ([`BodyPart::marker_grid`]) without
    /// the markers whose centre lies, in the rest pose, inside another suit part or within
    /// [`SEAM_MARGIN_CM`] of its surface. A printed suit's cloth runs on across a joint with one
    /// grid, while two capsules overlap there (a limb rising out of the side of the trunk at the
    /// shoulders and hips, the thighs inside the pelvis), and both grids would print squares a few
    /// millimetres apart: two same-coloured squares blur into one blob on camera.
    pub fn marker_grid(&self, index: usize, suit: &SuitDefinition) -> MarkerGrid {
        let part = &self.parts[index];
        let mut grid = part.marker_grid(suit);
        let to_world = self.rest_pose[part.joint];
        let others: Vec<(&BodyPart, Affine3A)> = self
            .parts
            .iter()
            .enumerate()
            .filter(|&(k, other)| k != index && other.material == Material::Suit)
            .map(|(_, other)| (other, self.rest_pose[other.joint].inverse() * to_world))
            .collect();
        grid.unprinted = grid
            .cells()
            .filter(|cell| {
                let theta = part.theta_for(cell.centre_u, cell.centre_s);
                let centre = part.surface_point(cell.centre_u, theta).0;
                others.iter().any(|(other, to_other)| {
                    other.contains(to_other.transform_point3(centre), SEAM_MARGIN_CM)
                })
            })
            .map(|cell| cell.id)
            .collect();
        grid
    }
}

/// A test part: a suit-patterned cylinder of radius 10 cm, 30 cm straight along +Y from the
/// origin, with two 10 cm caps.
#[cfg(test)]
pub(crate) fn test_cylinder() -> BodyPart {
    BodyPart {
        name: "test",
        joint: 0,
        start: Vec3::ZERO,
        end: Vec3::new(0.0, 30.0, 0.0),
        radii_start: Vec2::splat(10.0),
        radii_end: Vec2::splat(10.0),
        width_axis: Vec3::X,
        cap: 1.0,
        patterned_caps: [true, true],
        material: Material::Suit,
        surface: 2,
    }
}

#[cfg(test)]
mod tests {
    use super::test_cylinder as cylinder;
    use super::*;
    use crate::suit::shipped_default as suit;
    use std::path::Path;

    #[test]
    fn a_circle_has_perimeter_two_pi_r() {
        let c = cylinder().circumference_at(5.0);
        assert!((c - TAU * 10.0).abs() < 0.01, "{c}");
        // Ramanujan's approximation for an ellipse 15 × 10.
        let table = ellipse_arc_table(15.0, 10.0);
        let (a, b) = (15.0f32, 10.0f32);
        let h = ((a - b) / (a + b)).powi(2);
        let ramanujan =
            std::f32::consts::PI * (a + b) * (1.0 + 3.0 * h / (10.0 + (4.0 - 3.0 * h).sqrt()));
        assert!((table[4 * ARC_STEPS] - ramanujan).abs() < 0.05);
    }

    #[test]
    fn grid_of_a_capsule_covers_the_caps() {
        // 30 cm straight + two 10 cm caps = 50 cm; pitch 7: 7 rows (49 cm) starting at u = −9.5,
        // row centres −6, 1, 8, …, 36. The straight rows have a 62.8 cm perimeter → 8 columns; the
        // first and last rows sit 6 cm into a cap, where the section is √(1 − 0.6²) = 0.8 as wide:
        // 50.3 cm → 7 columns. 7 + 5·8 + 7 = 54 markers.
        let part = cylinder();
        let s = suit();
        let markers = part.markers(&s);
        assert_eq!(markers.len(), 54);
        assert!((markers[0].centre_u + 6.0).abs() < 1e-5);
        assert!((markers[7].centre_u - 1.0).abs() < 1e-5);
        assert_eq!(markers[7 + 8 + 1].id, 2 * 10_000 + 2 * 100 + 1);
        // A point at a marker's centre is on that marker; 3 cm along the bone is in the gap.
        let m = markers[7 + 8 + 1];
        assert_eq!(part.marker_at(&s, m.centre_u, m.centre_s), Some(m));
        assert_eq!(part.marker_at(&s, m.centre_u + 3.0, m.centre_s), None);
        assert_eq!(part.marker_at(&s, m.centre_u + 1.9, m.centre_s), Some(m));
    }

    #[test]
    fn caps_at_a_joint_carry_no_markers() {
        let s = suit();
        // 30 cm straight, no patterned cap: 4 rows of 7 cm, 1 cm spare at each end.
        let part = BodyPart {
            patterned_caps: [false, false],
            ..cylinder()
        };
        let rows: Vec<f32> = part.markers(&s).iter().map(|m| m.centre_u).collect();
        let mut centres = rows.clone();
        centres.dedup();
        assert_eq!(centres, [4.5, 11.5, 18.5, 25.5]);
        assert!(rows.iter().all(|u| u - 2.0 >= 0.0 && u + 2.0 <= 30.0));
        for s_frac in [0.0, 0.3, 0.7] {
            for u in [-9.0, -5.0, -1.0, 31.0, 35.0, 39.0] {
                assert_eq!(part.marker_at(&s, u, s_frac), None, "u {u}");
            }
        }
        // Only the start cap patterned: 40 cm → 5 rows from 2.5 cm into the cap.
        let part = BodyPart {
            patterned_caps: [true, false],
            ..cylinder()
        };
        let mut centres: Vec<f32> = part.markers(&s).iter().map(|m| m.centre_u).collect();
        centres.dedup();
        assert_eq!(centres, [-4.0, 3.0, 10.0, 17.0, 24.0]);
    }

    #[test]
    fn capsule_contains_points_inside_its_grown_surface() {
        let part = cylinder(); // radius 10, 0..30 along Y, 10 cm caps
        assert!(part.contains(Vec3::new(9.9, 15.0, 0.0), 0.0));
        assert!(!part.contains(Vec3::new(10.1, 15.0, 0.0), 0.0));
        assert!(part.contains(Vec3::new(10.9, 15.0, 0.0), 1.0));
        assert!(part.contains(Vec3::new(0.0, 40.9, 0.0), 1.0));
        assert!(!part.contains(Vec3::new(0.0, -11.1, 0.0), 1.0));
        // On the start cap halfway down (u = −5): the section is √(1 − 0.5²) = 0.866 as wide.
        assert!(part.contains(Vec3::new(8.6, -5.0, 0.0), 0.0));
        assert!(!part.contains(Vec3::new(8.8, -5.0, 0.0), 0.0));
    }

    #[test]
    fn overlapping_parts_print_one_grid() {
        let s = suit();
        // A 5 cm arm rising out of the side of the 10 cm cylinder along +X at half its height:
        // 40 cm with both caps → 5 rows at u = 1, 8, 15, 22, 29, 4 columns (31.4 cm perimeter).
        // The rows at u = 1 and 8 lie inside the cylinder or within 1 cm of it (their farthest
        // point is √(8² + 5²) = 9.4 cm from its axis); the rows from u = 15 on are printed.
        let arm = BodyPart {
            name: "arm",
            start: Vec3::new(0.0, 15.0, 0.0),
            end: Vec3::new(30.0, 15.0, 0.0),
            radii_start: Vec2::splat(5.0),
            radii_end: Vec2::splat(5.0),
            width_axis: Vec3::Z,
            surface: 3,
            ..cylinder()
        };
        let body = Body {
            parts: vec![cylinder(), arm.clone()],
            rest_pose: vec![Affine3A::IDENTITY],
        };
        assert_eq!(arm.markers(&s).len(), 20);
        let printed: Vec<MarkerCell> = body.marker_grid(1, &s).cells().collect();
        assert_eq!(printed.len(), 12);
        assert!(printed.iter().all(|m| m.row >= 2));
        let hidden = arm.markers(&s)[1];
        assert_eq!(
            arm.marker_at(&s, hidden.centre_u, hidden.centre_s),
            Some(hidden)
        );
        assert_eq!(
            body.marker_grid(1, &s)
                .marker_at(hidden.centre_u, hidden.centre_s),
            None
        );
        // The cylinder loses the markers under the arm's end and beside it, and only those.
        let grid = body.marker_grid(0, &s);
        let lost: Vec<MarkerCell> = cylinder()
            .markers(&s)
            .into_iter()
            .filter(|m| grid.marker_at(m.centre_u, m.centre_s).is_none())
            .collect();
        assert!(!lost.is_empty());
        for m in cylinder().markers(&s) {
            let centre = cylinder()
                .surface_point(m.centre_u, cylinder().theta_for(m.centre_u, m.centre_s))
                .0;
            assert_eq!(
                lost.contains(&m),
                arm.contains(centre, SEAM_MARGIN_CM),
                "{m:?}"
            );
        }
        let printed_on_body: usize = (0..body.parts.len())
            .map(|index| body.marker_grid(index, &s).cells().count())
            .sum();
        assert_eq!(printed_on_body, 54 - lost.len() + 12);
    }

    #[test]
    fn a_markers_points_lie_where_its_cell_says_row_by_row() {
        let part = cylinder();
        let s = suit();
        let m = part.markers(&s)[7 + 5];
        let (along, around) = ([-1.0, 0.5, 1.0], [-1.0, -0.25, 0.5, 1.0]);
        let points = part.marker_points(&s, &m, &along, &around);
        assert_eq!(points.len(), 12);
        // Half the 4 cm side along the axis, and as a share of the perimeter round it.
        let ds = 2.0 / part.circumference_at(m.centre_u);
        for (k, point) in points.iter().enumerate() {
            let (a, b) = (along[k / 4], around[k % 4]);
            let u = m.centre_u + 2.0 * a;
            let expected = part.surface_point(u, part.theta_for(u, m.centre_s + b * ds));
            assert_eq!(*point, expected, "({a}, {b})");
        }
    }

    #[test]
    fn markers_are_four_centimetre_squares() {
        let part = cylinder();
        let s = suit();
        let m = part.markers(&s)[7 + 5]; // on the straight section
        let corner = |a: f32, b: f32| part.marker_point(&s, &m, (a, b)).0;
        let side_along = corner(-1.0, -1.0).distance(corner(1.0, -1.0));
        let side_around = corner(-1.0, -1.0).distance(corner(-1.0, 1.0));
        assert!((side_along - 4.0).abs() < 0.01, "{side_along}");
        // A 4 cm arc on a 10 cm radius has a 3.97 cm chord.
        assert!((side_around - 3.973).abs() < 0.02, "{side_around}");
        let (centre, normal) = part.marker_point(&s, &m, (0.0, 0.0));
        assert!((centre.x.powi(2) + centre.z.powi(2)).sqrt() - 10.0 < 1e-3);
        // The normal points outward, away from the axis.
        let radial = Vec3::new(centre.x, 0.0, centre.z).normalize();
        assert!(normal.dot(radial) > 0.99, "{normal}");
    }

    #[test]
    fn mesh_is_closed_and_wound_outward() {
        let part = cylinder();
        let mesh = part.mesh(16, 5.0);
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|i| mesh.vertices[i as usize].position);
            let centroid = (a + b + c) / 3.0;
            let n = (b - a).cross(c - a);
            let radial = centroid - Vec3::new(0.0, centroid.y.clamp(0.0, 30.0), 0.0);
            assert!(n.dot(radial) >= -1e-3, "inward triangle {t:?}");
        }
        // Every vertex lies on the capsule: within r of the segment.
        for v in &mesh.vertices {
            let axis_point = Vec3::new(0.0, v.position.y.clamp(0.0, 30.0), 0.0);
            assert!(
                (v.position.distance(axis_point) - 10.0).abs() < 0.05,
                "{v:?}"
            );
        }
    }

    #[test]
    fn subjects_scale_the_skeleton() {
        let clip = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mocap/cmu_09_01_run.bvh");
        let motion = crate::bvh::Motion::load(&clip).expect("clip");
        let tall = Subject::find("emil").expect("emil");
        let scaled = tall.scale_skeleton(&motion.skeleton);
        let shin = motion.skeleton.find("rShin").expect("rShin");
        let ratio =
            scaled.joint(shin).offset.length() / motion.skeleton.joint(shin).offset.length();
        assert!((ratio - 193.0 / BASE_HEIGHT_CM * 1.08).abs() < 1e-4);
        let body = Body::new(tall, &scaled).expect("body");
        assert_eq!(body.parts.len(), 17);
        assert_eq!(Subject::find("2").map(|s| s.name), Some("chidi"));
        assert_eq!(Subject::find("Ana").map(|s| s.name), Some("ana"));
        assert!(Subject::find("zed").is_none());
    }

    #[test]
    fn shoulders_are_set_at_the_breadth_and_fitting_twice_changes_nothing() {
        let clip = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mocap/cmu_09_01_run.bvh");
        let motion = crate::bvh::Motion::load(&clip).expect("clip");
        let dana = Subject::find("dana").expect("dana");
        let fitted = dana.scale_skeleton(&motion.skeleton);
        let rest = vec![0.0; fitted.channel_count()];
        let at = |skeleton: &Skeleton, name: &str| {
            skeleton.joint_positions(&rest)[skeleton.find(name).expect("joint")]
        };
        let want = SHOULDER_HALF_BREADTH_CM * 1.22 * 165.0 / BASE_HEIGHT_CM;
        let chest = at(&fitted, "chest");
        assert!((at(&fitted, "rShldr").x - chest.x + want).abs() < 1e-3);
        assert!((at(&fitted, "lShldr").x - chest.x - want).abs() < 1e-3);
        // The arm below moves with its shoulder; the shoulder's height and depth stay.
        let unfitted = motion
            .skeleton
            .map_offsets(|i, o| o * dana.bone_scale(&motion.skeleton, i));
        let (hand, shoulder) = (at(&fitted, "lHand"), at(&fitted, "lShldr"));
        let (hand0, shoulder0) = (at(&unfitted, "lHand"), at(&unfitted, "lShldr"));
        assert!(((hand - shoulder) - (hand0 - shoulder0)).length() < 1e-3);
        assert!((shoulder.y - shoulder0.y).abs() < 1e-3 && (shoulder.z - shoulder0.z).abs() < 1e-3);
        assert_eq!(dana.fit_shoulders(&fitted), fitted);
    }
}
