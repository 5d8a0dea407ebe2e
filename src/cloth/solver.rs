//! The cloth solver: extended position-based dynamics (XPBD) with small substeps, on the CPU.
//!
//! **Why it is written here.** No maintained Rust crate simulates cloth with XPBD against moving
//! tapered capsules with long-range attachments: the physics engines on crates.io (rapier, avian,
//! …) simulate rigid bodies and have no cloth, and the few cloth crates are unmaintained
//! experiments with mass-spring or PBD cloth, none with tapered-capsule collision, tethers or a
//! per-substep kinematic body. The method is small and well documented, so it is implemented
//! directly from the papers.
//!
//! **Method.** Macklin, Müller and Chentanez 2016 (XPBD) with the "small steps" scheme of Macklin et
//! al. 2019: a frame of `1/fps` seconds is `substeps` solver steps of one constraint iteration each
//! (40 × 1 live; see [`SolverSettings::live`] for why 40). Per substep of length `h`:
//!
//! 1. The body is posed at the substep's time by interpolating the two skeleton frames
//!    ([`BodyRig::pose_between`]), so a fast limb moves at most a centimetre or so per substep.
//! 2. Free vertices: velocity += `h·g`; air drag (quadratic along the per-vertex normal, linear along
//!    the surface, each clamped so it never reverses the velocity); damping; predicted position
//!    `x += h·v`. Rigid anchors are kinematic (inverse mass 0) and jump to `bone · local`. The
//!    normals are those of the previous frame's end: recomputed once a frame, not every substep,
//!    except while the garment is put on, when it moves far in a frame (first session of
//!    2026-12-07: `cargo bench --bench cloth` about 12–15 % faster, the median per case over two
//!    pairs of runs alternated with the build before; `scripts/eval_cloth.sh`'s 46 cases still
//!    within the strain targets).
//! 3. Constraints, Gauss–Seidel, in this order:
//!    - **loose anchors** (a dress's waist): toward their slack of `bone · local`, by the fraction
//!      `1 − exp(−h/τ)` of the way per substep (`τ` = `loose_anchor_seconds`, 100 ms: about 2 %
//!      of the way per live substep, a quarter per frame), not all of it. Held hard, the waist
//!      fought the tethers from the neckline whenever the spine arched or the pelvis tilted
//!      further than the slack allows: every substep the belt pulled the waist ring back by up to
//!      4 cm, the edges above it starting the sweeps 150–240 % long, and the sweeps left the
//!      bodice's edges strained — while the waist still ended each frame up to 4.7 cm beyond its
//!      slack. Given way softly (5 ms), the kick's (CMU 10_03) worst-frame 95th-percentile strain
//!      fell from 3.0 to 2.3–2.4 %; but on CMU 11_01's kick, whose spine flexes further, the
//!      bodice's back still stretched to 3.1–3.3 % (4 cm of slack). With 6 cm of slack
//!      ([`DRESS_WAIST_SLACK_CM`](super::garment::DRESS_WAIST_SLACK_CM)) and 100 ms the dress
//!      keeps the 95th percentile under 2 % (≤ 1.80 %) on the 23 dress cases measured (20 live,
//!      3 in the quality mode; kick 11_01 on three subjects and its own skeleton among them),
//!      while its waist lies on average 3.1–3.4 cm from its place on the walk (2.8–3.1 cm
//!      before) and 4.4–5.5 cm on the kicks, jump and punch (3.5–4.2 cm before),
//!      at most 10.8 cm in one frame ([`FrameQuality::belt_offset_cm`]; docs/measurements.md,
//!      first session of 2026-12-06);
//!    - **cuffs** (a T-shirt's sleeve ends, [`Cuff`](super::garment::Cuff)): a vertex farther
//!      than its reach (5 cm) from its upper arm's capsule is put back at that distance.
//!      Collisions alone did not keep an arm in its sleeve: where the arm sinks into the chest the
//!      trunk wins, so an arm lowered from the T-pose pressed the sleeve's underside into the
//!      chest and came out through it. A cuff vertex that slid more than `cuff_slide_cm` (3 cm)
//!      up its arm, towards the shoulder, from its place at rest is drawn back down the arm's
//!      axis softly, like a loose anchor (time constant `cuff_hold_seconds`, 50 ms), but only
//!      while all its edges are shorter than at rest (cloth bunched at the sleeve's end, not a
//!      sleeve pulled taut over the shoulder), and not while [`Cloth::dress`] brings the arms down
//!      from the T-pose. A shirt cut in the T-pose has too little cloth over the shoulder of a
//!      lowered arm, so lowering the arms drew the sleeves up into a bunch at the shoulder and
//!      nothing brought them back. On eighteen T-shirt cases of `examples/cloth_quality.rs` (walk
//!      02_01 and kick 10_03 of the benchmark; the dance and jump test clips, CMU kick 11_01 and the
//!      quick start's kick on their own skeletons; each at 2,000 and 4,000 vertices and in the
//!      quality mode) the sleeve ends sat 7.5–12.5 cm up the arm on average over the frames and
//!      8.4–17.0 cm in the worst frame; held, 6.3–10.4 and 6.8–12.0 cm, every case still within
//!      the strain targets (worst-frame 95th percentile 0.4–1.7 %, largest 8.2–9.4 %; one free
//!      vertex 0.4 mm inside a capsule in one frame of the kick's 4,000-vertex T-shirt). Tried:
//!      the hold without the slack test (sleeves 4.7–7.1 cm up) kept the strain targets on
//!      fifteen of the cases but left a sleeve-end vertex 2.4–2.9 mm inside an arm where it meets
//!      the chest (kick 11_01, and `suitcap drape` on the quick start's clip); leaving out the
//!      sleeve-end vertices within 2 cm of the trunk instead, 3 of 15 cases went over 10 %;
//!      stronger holds (2 cm / 20 ms, 1 cm / 10 ms with the slack test) put one or two cases over
//!      10 %; held while dressing, the dance's quality T-shirt tore at the armpit (110 %) in its
//!      first frame;
//!    - **tethers** (long-range attachments, Kim, Tang and Zordan 2012): each free vertex may be no
//!      farther from its nearest rigid anchor than its geodesic rest distance, found by Dijkstra
//!      from all rigid anchors over two-ring steps of the mesh (paths along edges alone zigzag and
//!      overestimate by up to 8 %); unilateral. They come before the stretch sweeps: a tether moves
//!      its vertex alone, and projected after the sweeps (as they were at first) they left
//!      that vertex's edges to take the move — on the kick the dress's worst edges were about 15 %
//!      long after the sweeps and 30–50 % after the tethers. Before them, the sweeps spread the pull
//!      over the neighbouring edges, at the price of a tether left slightly violated at the end of
//!      a substep (it is projected again in the next one). On CMU walk 02_01 and kick 10_03 the
//!      worst frame's 95th-percentile strain fell in all eight cases of `cargo bench --bench cloth`
//!      (kick dress 4.2 → 3.0 %, kick T-shirt 2.0–2.6 → 1.9–2.2 %), at no cost;
//!    - **stretch**: one distance constraint per edge, compliance from the material, ordered from the
//!      anchors outward so a sweep carries corrections down the garment. The stretch constraints
//!      are swept `stretch_sweeps` times (6 live) within the one iteration: with a single sweep the
//!      Gauss–Seidel error of a hanging garment (which grows like `N²·g·h²` over `N` edges) left
//!      its edges 3–4 % long at rest. Within runs of 256 the constraints are reordered so that
//!      neighbours share no vertex (`interleave`): projected in mesh order, each waited for the
//!      square root and division of the one before, and the sweeps took two thirds of the frame;
//!      interleaved, the processor overlaps them and a frame takes about half the time. Runs of
//!      eight such vertex-disjoint neighbours are then projected at once, one per SIMD lane
//!      (`super::stretch`; the positions are bit-identical to projecting them one by
//!      one): with that, the SIMD box test in the collisions and the strain limit's SIMD scan,
//!      the eight cases of `cargo bench --bench cloth` ran at 1.43× the frame rate (summed;
//!      alternated runs of both builds on 2026-12-02, two each; 1.31× with blocks of four).
//!      Compressed edges get `compression` (0.8) of their correction: cloth buckles rather than
//!      compresses, a 2 cm mesh cannot show the buckles, and full-strength compression projections were seen to
//!      pump energy into crumpled regions (and on the kick they raised the worst frame's
//!      95th-percentile strain, e.g. dress 2,000 vertices 2.29 → 2.70 %). Each projection computes
//!      its correction `(l − l₀)/l` from `l²/l₀²` without a square root
//!      (`stretch::stretch_correction`, a Padé approximant exact at
//!      rest and to second order; a sweep takes about an eighth less
//!      time). The sweeps are accelerated with the Chebyshev semi-iterative method (Wang 2015, "A
//!      Chebyshev semi-iterative approach for accelerating projective and position-based dynamics"):
//!      after each sweep from the second on, the iterate is pushed on from the one two sweeps back
//!      by a weight `ω` (1.39 at the second sweep, then about 1.27: `chebyshev_weight`,
//!      `chebyshev_rho` = ρ = 0.75). Gauss–Seidel
//!      removes the short-wavelength error in the first sweeps and the long-wavelength error slowly
//!      (the corrections of successive plain sweeps shrink by 0.38, 0.54, 0.77, 0.87, 0.91 on the
//!      kick), which is what the extrapolation speeds up. ρ is a chosen constant, not estimated:
//!      on the kick (`cargo bench --bench cloth`, the worst frame's 95th-percentile strain in the
//!      four cases T-shirt 2k / 4k, dress 2k / 4k, at 40 × 6) ρ = 0.7 gave 1.81 / 1.56 / 1.95 /
//!      1.73 %, 0.75 gave 1.63 / 1.69 / 1.71 / 1.84 %, 0.8 gave 1.90 / 1.63 / 2.02 / 1.67 %, 0.85 gave
//!      1.68 / 1.56 / 2.08 / 1.71 %, and 0.95 diverged (33–60 %, at 32 × 6): the nonlinear, unsymmetric sweep
//!      is not the linear symmetric iteration the method assumes, so ρ must stay well below the
//!      sweeps' asymptotic ratio. Plain over-relaxation of each projection instead (SOR, ω = 1.3 and
//!      1.6) made every kick case worse (2.2–3.1 %);
//!    - **bending**: the isometric bending model of Bergou et al. 2006 as one linear vector
//!      constraint `Σ Kᵢxᵢ` per interior edge with cotangent weights `K` from the (flat, as sewn)
//!      rest shape — cheaper than the dihedral-angle constraint, no trigonometry, and exact in one
//!      projection;
//!    - **collision** against the posed capsules: a vertex closer than `collision_offset` to a
//!      capsule is pushed out along the capsule's normal. The trunk comes first; cloth that rests
//!      on an arm ([`collision_group`](super::proxies::collision_group)) then meets the arms, and
//!      the trunk again if an arm pushed it in. Trunk cloth ignores the arms and the sleeve enters
//!      them over a 16 cm ramp (`ARM_RAMP_CM`; 6 cm until the eighth session of 2026-12-06, 10 cm
//!      until the second of 2026-12-07), because the arms meet the torso at the shoulders and
//!      no cloth position there is outside both. (Where a pose presses an arm into the torso, the
//!      arm gives way: [`BodyRig`].) Arm cloth (a sleeve, a dress's
//!      armhole) within 2 cm of the trunk may also lie inside an arm, from the ramp's 16 cm deep on
//!      the trunk's surface to nothing 2 cm off it (`buried_arm_allowance`): before, the trunk won
//!      on its surface and the arm pushed everything else out at once, so where a lowered arm sank
//!      into the chest one armpit vertex stayed on the trunk inside the arm while its neighbour, 3
//!      mm off the trunk, went out to the arm's far side. With the quality mode's 1 cm edges that
//!      tore armpit edges to 244 % (the dressed first frame of the quick start's kick) and 583 %
//!      (walk 02_01), and the live T-shirt on CMU 05_12's dance to 135–271 %, where no strain limit
//!      could help, the collisions undoing it every round. (A fade over 1 cm instead of 2 cm left
//!      the kick's 4,000-vertex T-shirt at 10.6 %.) The try-on part of docs/measurements.md has the
//!      figures;
//!    - **strain limit** (Provot 1995, "Deformation constraints in a mass-spring model to describe
//!      rigid cloth behavior"): the edges still more than `strain_limit` (9 %) longer or shorter
//!      than at rest are found, projected back onto that bound four times, a vertex in contact
//!      taking a fifth of its share (so the free cloth follows the cloth a capsule holds instead of
//!      pulling it back in), and the vertices moved meet the capsules again; the round repeats
//!      until no edge is outside the bound, at most six times (`Cloth::limit_strain`), 32 times in
//!      a frame's last substep, whose positions are the ones drawn and measured
//!      (`FRAME_END_STRAIN_LIMIT_PASSES`). The last round meets the trunk only: where a
//!      sleeve (or a dress's armhole) ramps into an arm, the arm's push moved one end of an edge
//!      further out than the other after the limit had set it (on CMU 13_39's jump the
//!      4,000-vertex dress kept 13.0 % and the quality T-shirt 11.1 %; now 9.0 % and 9.2 %;
//!      without the arms in every round the jump's T-shirt had 17.3 %). One
//!      XPBD iteration leaves the bulk of the edges within 2 %, but a few edges where a capsule pushes
//!      one end and not the other reached 20–50 % on the kick: the armpit, where trunk cloth lies
//!      inside an arm sunk into the chest while the arm pushes the sleeve's ramp vertices out, and
//!      the skirt over a raised thigh. The bound is 9 %, not the 10 % the issue allows, because the
//!      collisions come last and may move a vertex back a little. The first round scans every
//!      edge's length, the later ones only the edges of the vertices moved: on the kick's
//!      4,000-vertex T-shirt, the case with the most edges outside, the limit adds 7 % to the
//!      instructions of the run (callgrind: 42.2 against 39.4 billion; 16 % when every round
//!      scanned every edge). On the estimated, jittery poses of `suitcap bench` it costs more:
//!      about 165 edges (of 12,000) stay outside round after round, held there by the collisions,
//!      so every substep runs all six rounds, and the cloth stage takes 25 ms a frame instead of
//!      19–21 ms (28 ms before the moved vertices were kept by stamp instead of sorted). Stopping
//!      when a round makes no progress, dropping edges a round did not bring halfway back, a
//!      tolerance of 0.5–1 % for the later rounds or two projections per round instead of four each
//!      saved at most 3 ms and let the kick's largest strain back up to 11–20 %. On CMU walk 02_01 and kick
//!      10_03 (`cargo bench --bench cloth`, the eight cases) the largest strain in any frame fell
//!      from 9.4–20.7 % (walk) and 19.3–49.6 % (kick) to at most 9.0 % and 9.95 %. One round over
//!      all edges left the kick at 10.4–19.4 %; several rounds with the old sleeve join tore a
//!      0.4 cm sliver edge to 626 % at the start of the walk, which is why the sleeve rings are now
//!      even in angle ([`GarmentMesh`] has no such slivers); bounds of 7 % and 8 % were no better
//!      (the largest strain of the kick's dress swung between 11 % and 21 %).
//! 4. Velocity `v = (x − x_prev)/h`; for a vertex in contact the velocity away from the surface
//!    (relative to the surface's own motion) is dropped — depenetration is a position fix, not a
//!    bounce — and Coulomb friction takes up to `μ × depth/h` off its sliding velocity (friction at
//!    the velocity level: applied to positions it undid the constraint projections and fed energy
//!    in); then the speed is clamped to `max_speed`.
//!
//! With λ starting at zero every substep and one iteration, each XPBD update is
//! `Δλ = −C/(Σwᵢ|∇Cᵢ|² + α/h²)`, precomputed per constraint: the solver carries no multipliers.
//!
//! **What else was tried on the kick** (the worst frame's 95th-percentile strain, T-shirt 2k / 4k,
//! dress 2k / 4k, all at 32 × 6; it was 1.93 / 2.18 / 2.29 / 2.36 %). On the worst frame the top 5 %
//! of edges are spread over the garment, about half of them compressed (the front of the skirt
//! over the raised thigh, the T-shirt's front hem) and half stretched (the bodice, the T-shirt's
//! back at armpit height); the sleeve-join slivers make the maxima, not the 95th percentile.
//! Within a substep of the dress's worst frame the 95th percentile is 2.40 % after the
//! integration, 2.68 % after the tethers, 1.97 % after the sweeps, 2.01 % after bending and
//! 2.28 % after the collisions. Not kept: sweeping alternately forwards and backwards (2.36 / 2.99
//! / 2.76 / 3.09 %: the anchors-outward order is what carries the weight down); bending before
//! the sweeps (2.07 / 2.00 / 2.55 / 2.37 %); a collision pass and a stretch sweep between the
//! sweeps and the final collisions (1.72 / 2.47 / 2.11 / 2.41 %, and a quarter slower); tether
//! slack of 1 % or 3 % (up to 2.7 and 2.95 %: the tight tethers help); no bending at all (2.00 /
//! 2.32 / 2.28 / 2.45 %) or ten times softer (2.09 / 2.13 / 2.16 / 2.58 %); the dress's waist belt
//! off (dress 2.04 / 2.35 %) or at τ = 50 ms (2.18 / 2.39 %); Chebyshev sweeps at 32 substeps
//! (ρ = 0.6–0.8: 1.70–2.20 / 2.02–2.17 / 2.11–2.35 / 2.17–2.32 %).
//!
//! **Broad phase.** Once per frame each capsule's box swept over the frame (poses at t = 0, ½, 1,
//! padded) is tested against a box around each vertex sized by how far it can travel in the frame;
//! the survivors are the vertex's candidate list for all substeps (about 2–4 of ~30 capsules). A
//! vertex that outruns its box falls back to testing every capsule, so the lists are never wrong.
//!
//! **Tunnelling.** Collisions are tested at the end of each substep only, so cloth that a limb
//! crosses within one substep, or that a collision pushes out on the limb's far side, would pass
//! through it unseen: the deepest-vertex figure at a frame's end does not show it. With
//! [`Cloth::check_tunnelling`] on, every substep follows each free vertex's path as the body sees
//! it (its start carried along with each capsule's bone) and counts the vertices whose path went
//! through the inner half of a capsule they meet, from outside that core to outside it
//! ([`PreparedCapsule::path_passes_through`]); [`FrameQuality::tunnelled`] sums them since the
//! frame began. A 4 cm-radius bar swept through a hanging sheet at 9 m/s with one substep a frame
//! passes 42 vertices (a test); at 3 m/s with the live 40 substeps, none. Off by default (it costs
//! about as much as the collisions): it is a measurement for `cloth_quality`, the benchmark's
//! untimed quality runs and `suitcap drape`.
//!
//! **Time.** The substep length is fixed (`1/(fps·substeps)`) whatever the camera does:
//! [`Cloth::step_frame`] runs one frame's worth, [`Cloth::advance`] as many substeps as a given
//! interval holds. A root that moves more than `jump_distance_cm` or turns more than
//! `jump_turn_degrees` in one frame is treated as a jump: the cloth is moved rigidly with the root
//! and its velocities zeroed ([`Cloth::teleport`]); a
//! capsule end that moves more than `pose_jump_cm` relative to the root (a tracking glitch, or the
//! calibration T-pose a mocap clip starts with) makes the garment dress again on the new pose.
//! [`Cloth::dress`] starts a garment: rest pose → the first frame's pose blended over
//! `blend_frames`, then `settle_frames` at that pose. [`Cloth::reset`] does that again (lost
//! tracking).
//!
//! **Inertia.** With [`SolverSettings::inertia`] below full, every substep first carries the free
//! vertices rigidly along the rest of the garment's own bone's move (the bone most rigid anchors
//! hang on: the chest for a T-shirt or a dress, the hip for a skirt) — `1 − linear` of its
//! joint's travel and `1 − angular` of its turn about that joint — and turns their velocities
//! alike, so that only the given shares of the body's travelling and turning are felt as inertia
//! (the linear and angular inertia of game cloth solvers such as NvCloth). The vertices'
//! velocities are then relative to the carry, and so is the surface motion friction compares them
//! with. The limbs' motion relative to that bone is felt in full. For true motion (`drape`, the
//! benchmark) the inertia is full, the physics as it is; the try-on of estimated poses feels less
//! ([`crate::tryon::ESTIMATED_POSE_INERTIA`]), since an estimated body's heading and depth shake
//! from frame to frame in ways a real one's do not.
//!
//! **Determinism.** Everything runs on one thread in a fixed order, with no hash maps and no parallel
//! reductions: the same inputs give bit-identical positions.
//!
//! Hands to the renderer: [`Cloth::positions`], [`Cloth::normals`], [`Cloth::triangles`] and the
//! posed body ([`Cloth::pose`]); to the command line: [`FrameQuality`] per frame and a
//! [`QualitySummary`] per motion ([`run_motion`], [`evaluate`]).

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::fmt;

use glam::{Affine3A, Vec3, Vec3A};

use crate::body::{MissingJoint, Subject};
use crate::bvh::{Motion, ResampleError};
use crate::skeleton::MAX_ROOT_TURN_DEG_PER_S;

use super::capsule::{Aabb, Capsule, PreparedCapsule};
use super::garment::{Anchor, GarmentError, GarmentKind, GarmentMesh, GarmentParams};
use super::material::Material;
use super::proxies::{BodyPose, BodyRig, DEFAULT_MARGIN_CM, GROUP_ARMS, GROUP_TRUNK};
use super::stretch::{self, DistanceConstraint, EdgeBlocks};
use super::topology::{hinges, unique_edges, Adjacency};

/// Constraints reordered together by [`interleave`].
const INTERLEAVE_WINDOW: usize = 256;

/// Arm collision weight: 0 for cloth at least as near the trunk as an arm at rest, rising smoothly
/// to 1 for cloth this much nearer an arm than the trunk, cm; cloth on the ramp may lie inside an
/// arm by up to (1 − weight) times this. 16 cm since the second session of 2026-12-07, when the
/// shoulders moved out so that the hanging arms clear the chest and the arms began to give way to
/// the trunk ([`BodyRig`](super::proxies::BodyRig)). On the 23 T-shirt cases of
/// `scripts/eval_cloth.sh` (chosen on them, so optimistic), trial builds with 7 / 10 / 12 / 14 /
/// **16** cm left 9 / 1 / 1 / 0 / **0** cases over 2 % in their worst frame's 95th percentile and
/// 8 / 1 / 0 / 0 / **0** with an edge over 10 %; but the committed code at 14 cm left 1 and 2 (the
/// outcome swings with any change: the folds are chaotic), and at 16 cm none, with the largest
/// strain 9.08 % (9.82 % at 2,100 and 3,900 vertices instead of 2,000 and 4,000). (10 cm, chosen
/// in the eighth session of 2026-12-06 for the body whose arms lay inside the chest, had replaced
/// 6 cm.) The top of a lowered shoulder stands out of the sleeve (a shirt cut in the T-pose has
/// too little cloth over it); limiting the ramp to cloth near the trunk covered it but broke the
/// strain targets (docs/measurements.md, third session of 2026-12-07), so the renderer draws the
/// shirt over it instead ([`BodyRig::occluders`](super::proxies::BodyRig::occluders)).
const ARM_RAMP_CM: f32 = 16.0;

/// Cloth this close to the trunk's collision surface lies on the trunk, cm.
const ON_TRUNK_CM: f32 = 0.05;

/// Where an arm lies against or inside the trunk, arm cloth this near the trunk may lie inside the
/// arm: up to [`ARM_RAMP_CM`] on the trunk's surface, falling linearly to nothing at this gap, cm
/// ([`buried_arm_allowance`]).
const BURIED_ARM_GAP_CM: f32 = 2.0;

/// The share of a capsule's radius, around its axis, through which a vertex's path in one substep
/// counts as tunnelling ([`Cloth::check_tunnelling`]): deep enough that cloth sliding over the
/// surface never reaches it, and that a vertex inside it would have been pushed out on the far side.
const TUNNEL_CORE_SHARE: f32 = 0.5;

/// Rounds of the strain limit per substep: find the edges outside the bound, project them, collide
/// the vertices moved ([`Cloth::limit_strain`]); it stops early when no edge is outside.
const STRAIN_LIMIT_PASSES: usize = 6;

/// Rounds of the strain limit in a frame's last substep, whose positions are the frame's: drawn,
/// measured and handed on. Where the body model's arm sinks into the chest, the collisions hold a
/// few armpit edges outside the bound round after round, and six rounds left the largest strain
/// of three of `cloth_quality`'s 46 cases at 10.1–11.7 % and of the demo's live T-shirt drape at
/// 13.9 % in single frames. More rounds in every substep brought those down too (at 16 rounds one
/// case over 10 %) but cost a quarter of `suitcap bench`'s frame rate, whose jittery estimated
/// poses keep edges outside in most substeps, and put more vertices through an arm while the
/// garment is put on; at a frame's end only (not while dressing) they cost nothing measurable and
/// left every case within 10 % (16 rounds: the demo's drape 10.35 %; 32: 9.04 %). The substeps
/// in between keep [`STRAIN_LIMIT_PASSES`]: their states are not seen, and an edge they leave
/// outside the bound for a substep or two is brought back by the frame's end.
const FRAME_END_STRAIN_LIMIT_PASSES: usize = 32;

/// Projections of the edges found outside the bound per round of the strain limit.
const STRAIN_LIMIT_SWEEPS: usize = 4;

/// The share of its inverse mass a vertex in contact with a capsule has in the strain limit.
const STRAIN_LIMIT_CONTACT_SHARE: f32 = 0.2;

/// Solver settings. [`SolverSettings::live`] is the default.
#[derive(Clone, Debug, PartialEq)]
pub struct SolverSettings {
    /// Simulation frame rate (the rate of [`Cloth::step_frame`] calls), frames/s.
    pub fps: f32,
    /// Substeps per frame.
    pub substeps: u32,
    /// Constraint iterations per substep.
    pub iterations: u32,
    /// cm/s².
    pub gravity: Vec3,
    /// Velocity clamp, cm/s.
    pub max_speed: f32,
    /// Distance kept between cloth vertices and the (inflated) capsules, cm.
    pub collision_offset: f32,
    /// Tethers allow the geodesic rest distance × (1 + slack).
    pub tether_slack: f32,
    /// Time constant with which a loose anchor (a dress's waist) pulls its vertex back within its
    /// slack, s: each substep of length `h` moves it `1 − exp(−h/τ)` of the way. 0 projects it
    /// all the way (a hard constraint). 0.1 s (see the module documentation).
    pub loose_anchor_seconds: f32,
    /// Sweeps over the stretch constraints per iteration (see the module documentation).
    pub stretch_sweeps: u32,
    /// Chebyshev acceleration of the stretch sweeps (Wang 2015): the assumed spectral radius `ρ`
    /// of one sweep, in `[0, 1)`; 0 sweeps plainly. See the module documentation.
    pub chebyshev_rho: f32,
    /// Fraction of a compressed edge's correction applied (1 = as stiff in compression as in
    /// tension). Cloth buckles rather than compresses; full-strength compression projections on a
    /// 2 cm mesh that cannot represent the buckles feed energy into it.
    pub compression: f32,
    /// A root move larger than this in one frame (`1/fps`) is a jump: the cloth is teleported with
    /// the root, cm.
    pub jump_distance_cm: f32,
    /// A root turn larger than this in one frame is a jump too (a tracking glitch that spins the
    /// body), degrees: the cloth turns with the root, not whipped through the air. By default
    /// what a person can turn in a frame ([`MAX_ROOT_TURN_DEG_PER_S`]); the quick start's
    /// estimated poses once turn 48.9° in a frame and back over the next two.
    pub jump_turn_degrees: f32,
    /// A capsule end moving more than this relative to the root in one frame is a pose jump (a
    /// tracking glitch, or a mocap clip's calibration T-pose frame): the garment is dressed again on
    /// the new pose, cm. The fastest real motion in the bundled clips (a kick) moves 34 cm.
    pub pose_jump_cm: f32,
    /// Frames over which [`Cloth::dress`] blends from the rest pose to the first frame.
    pub blend_frames: u32,
    /// Frames [`Cloth::dress`] then holds the first frame.
    pub settle_frames: u32,
    /// Strain limit after the collisions, as a fraction of the rest length (0: off).
    pub strain_limit: f32,
    /// How far a sleeve's end may slide up its arm, towards the shoulder, from where it sits at
    /// rest before it is drawn back down, cm (infinite: never; see the module documentation).
    pub cuff_slide_cm: f32,
    /// Time constant with which a sleeve's end that slid further is drawn back, s: each substep
    /// of length `h` moves it `1 − exp(−h/τ)` of the way (as `loose_anchor_seconds`).
    pub cuff_hold_seconds: f32,
    /// How much of the garment's bone's own travelling and turning the cloth feels (see
    /// *Inertia* in the module documentation): [`Inertia::FULL`] simulates in the world as it is.
    pub inertia: Inertia,
}

/// Shares, each in [0, 1], of a garment's bone's travel (`linear`) and turn about its joint
/// (`angular`) that the cloth feels as inertia; the rest carries it rigidly
/// ([`SolverSettings::inertia`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inertia {
    pub linear: f32,
    pub angular: f32,
}

impl Inertia {
    /// All of it: the cloth simulated in the world.
    pub const FULL: Inertia = Inertia {
        linear: 1.0,
        angular: 1.0,
    };

    fn is_full(self) -> bool {
        self.linear >= 1.0 && self.angular >= 1.0
    }
}

impl SolverSettings {
    /// Live mode: 30 frames/s, 40 substeps × 1 iteration, 6 Chebyshev-accelerated stretch sweeps
    /// (ρ = 0.75), a 9 % strain limit.
    ///
    /// The strain left by the single iteration falls with the square of the substep and about
    /// linearly with the sweeps: on CMU walk 02_01 and kick 10_03 (`cargo bench --bench cloth`, 4,000
    /// vertices) the worst frame's 95th-percentile strain was 4.8 % (walk T-shirt) and 9.0 % (kick
    /// T-shirt) with 16 × 4, and 2.0 % and 2.6 % with 32 × 6. Since the constraints are interleaved
    /// (`interleave`) 32 × 6 costs what 16 × 4 used to (about 12 ms a frame at 4,000 vertices).
    ///
    /// At 32 × 6 the kick's worst frame was still 1.9–2.4 % in the four cases of the bench, and
    /// substeps, not sweeps, brought it down (T-shirt 2k / 4k, dress 2k / 4k): 32 × 12 gave 1.92 /
    /// 1.94 / 2.01 / 1.92 %, 64 × 6 1.47 / 1.31 / 1.70 / 1.55 %, 40 × 6 1.83 / 1.71 / 2.16 / 2.08 %,
    /// 44 × 6 1.73 / 1.57 / 2.01 / 1.94 %, 48 × 5 1.80 / 1.71 / 2.19 / 1.92 %, 48 × 4 2.01 / 1.76 /
    /// 2.34 / 2.27 %, 40 × 5 1.84 / 1.92 / 2.08 / 2.23 %. None within the speed target met 2 % in
    /// all four; 40 × 6 with the Chebyshev sweeps (see the module documentation) gives 1.63 / 1.69 /
    /// 1.71 / 1.84 % and the walk 0.7–1.2 % (was 1.1–1.7 %), and the square-root-free projection
    /// pays for part of the 25 % more substeps. The worst frame moves by ±0.3 % with any small
    /// change (the kick's folds are chaotic): with the exact square root the same settings gave
    /// 1.90 / 1.45 / 1.59 / 1.79 %. At 2,500 and 3,300 vertices the kick gives 1.71 / 1.44 / 1.90 /
    /// 1.80 % (32 × 6 plain: 2.14 / 2.31 / 2.47 / 2.48 %). Nothing diverged with the other
    /// materials either, and each was better than with 32 × 6 plain (which does not meet 2 % with
    /// them): light (= chiffon) 2.28 / 1.99 / 2.51 / 2.43 % (was 2.66 / 3.35 / 3.03 / 3.53 %), stiff
    /// (= denim) 1.79 / 2.72 / 1.95 / 2.33 % (was 2.50 / 3.34 / 2.21 / 3.25 %).
    ///
    /// Speed: a frame takes about 1.2–1.3 times as long as with 32 plain sweeps (0.76–0.83 of the old
    /// frame rate, runs of the old and new code alternated on a busy machine), so the bench's old
    /// 78–84 frames/s at 4,000 vertices and 158–168 at 2,000 become about 62–66 and 125–133: the
    /// targets (60 and 120) are met with little to spare. The Chebyshev relaxation costs about a
    /// third of a sweep each time. 36 × 6 would leave more speed (about 0.88 of the old rate) but
    /// only just meets the strain target on the kick (1.93 / 1.72 / 1.89 / 1.95 %); 40 × 5 gives
    /// 1.95 / 1.59 / 1.80 / 1.99 %.
    ///
    /// The strain limit (9 %, after the collisions; see the module documentation) brings the
    /// largest strain in any frame under 10 % in all eight cases of the bench (it was up to 50 %
    /// on the kick) and leaves the 95th percentile as it was, within the ±0.3 % the kick's folds
    /// move it by. At 36 substeps with the limit the kick's 2,000-vertex dress has a p95 of 2.03 %.
    pub fn live() -> SolverSettings {
        SolverSettings {
            fps: 30.0,
            substeps: 40,
            iterations: 1,
            gravity: Vec3::new(0.0, -981.0, 0.0),
            max_speed: 1000.0,
            collision_offset: 0.2,
            tether_slack: 0.0,
            loose_anchor_seconds: 0.1,
            stretch_sweeps: 6,
            chebyshev_rho: 0.75,
            compression: 0.8,
            jump_distance_cm: 50.0,
            jump_turn_degrees: MAX_ROOT_TURN_DEG_PER_S / 30.0,
            pose_jump_cm: 60.0,
            blend_frames: 30,
            settle_frames: 20,
            strain_limit: 0.09,
            cuff_slide_cm: 3.0,
            cuff_hold_seconds: 0.05,
            inertia: Inertia::FULL,
        }
    }

    /// Quality mode (recorded input): twice the substeps, and the strain limit at 8.5 %. With the
    /// quality garments' 1 cm edges the collisions that follow the limit moved one armpit edge of
    /// the kick's T-shirt (CMU 10_03) from 9 % to 10.3 % (before the limit's last round left the
    /// arms out); at 8.5 % the largest strain of the four quality cases of `cargo bench --bench
    /// cloth` (walk and kick, T-shirt and dress) is now 8.5–9.1 %, and 8.5 % on the quick start's
    /// clip.
    pub fn quality() -> SolverSettings {
        SolverSettings {
            substeps: 80,
            strain_limit: 0.085,
            ..SolverSettings::live()
        }
    }

    /// Substep length, seconds.
    pub fn substep_seconds(&self) -> f32 {
        1.0 / (self.fps * self.substeps.max(1) as f32)
    }
}

impl Default for SolverSettings {
    fn default() -> SolverSettings {
        SolverSettings::live()
    }
}

/// Why a cloth cannot be built or run.
#[derive(Debug, thiserror::Error)]
pub enum ClothError {
    #[error(transparent)]
    Garment(#[from] GarmentError),
    #[error(transparent)]
    Body(#[from] MissingJoint),
    #[error(transparent)]
    Resample(#[from] ResampleError),
    #[error("garment '{garment}': anchor {index} is bound to bone {bone}, the skeleton has {bones} joints")]
    AnchorBone {
        garment: String,
        index: usize,
        bone: usize,
        bones: usize,
    },
    #[error("garment '{garment}': cuff {index} is held around bone {bone}, which has no collision capsule (the skeleton has {bones} joints)")]
    CuffBone {
        garment: String,
        index: usize,
        bone: usize,
        bones: usize,
    },
    #[error("solver setting {name} = {value} is out of range ({expected})")]
    Setting {
        name: &'static str,
        value: f32,
        expected: &'static str,
    },
    #[error("the motion has no frames")]
    NoFrames,
}

/// What one frame's step did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepInfo {
    /// The root jumped and the cloth was teleported with it.
    pub jumped: bool,
    /// The pose jumped and the garment was dressed again on the new pose.
    pub redressed: bool,
    pub substeps: u32,
}

/// Quality figures for the cloth's current state.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameQuality {
    /// 95th percentile of edge strain |l − l₀|/l₀ (stretch and compression).
    pub strain_p95: f32,
    pub strain_max: f32,
    /// The same for stretch alone, max(0, l − l₀)/l₀ (compressed edges count as 0).
    pub stretch_p95: f32,
    pub stretch_max: f32,
    /// Deepest free (simulated) vertex inside a capsule it collides with, cm (0 if none); see
    /// [`FrameQuality::other_group_cm`] for the arms' overlap with the trunk.
    pub penetration_cm: f32,
    /// Deepest anchored (kinematic) vertex inside a capsule of its group, cm.
    pub anchor_penetration_cm: f32,
    /// Deepest vertex inside an arm capsule where that is by design: trunk cloth under an arm, or
    /// arm cloth held on the trunk where the arm overlaps it, cm. Not part of the targets.
    pub other_group_cm: f32,
    /// Farthest a cuff vertex (a sleeve's end) lies from its limb's capsules, cm (0 for a garment
    /// without cuffs).
    pub cuff_gap_cm: f32,
    /// How far the sleeves' ends lie up their arms, towards the shoulders, from where they sat at
    /// rest: the mean over the cuff vertices, cm (0 for a garment without cuffs).
    pub cuff_slide_cm: f32,
    /// How far the loose anchors' vertices (a dress's waist) lie from their bound places on the
    /// hip bone: the mean over those vertices, cm (0 for a garment without loose anchors). Their
    /// slack lets them move that far without a pull; beyond it the belt draws them back softly.
    pub belt_offset_cm: f32,
    /// Σ ½ m v², erg (g·cm²/s²; 10⁷ erg = 1 J).
    pub kinetic_energy: f32,
    /// Fastest vertex, cm/s.
    pub max_speed: f32,
    /// Free vertices that tunnelled through a capsule they meet, summed over the substeps since
    /// the last frame began (for the first frame, since dressing began): their path in one
    /// substep, seen from the body, went through the inner half of the capsule while starting and
    /// ending outside it. `None` unless [`Cloth::check_tunnelling`] is on.
    pub tunnelled: Option<u32>,
}

#[derive(Clone, Copy, Debug)]
struct Edge {
    i: u32,
    j: u32,
    rest: f32,
    /// 1 / rest².
    inv_rest2: f32,
    /// wᵢ / (wᵢ + wⱼ + α/h²), and the same for j.
    ci: f32,
    cj: f32,
}

#[derive(Clone, Copy, Debug)]
struct Bend {
    v: [u32; 4],
    k: [f32; 4],
    /// wᵢKᵢ / (Σ wK² + α/h²).
    c: [f32; 4],
}

/// A [`Cuff`](super::garment::Cuff): `vertex` no farther than `reach` from the capsules whose
/// indices are `cuff_capsules[capsules]`.
#[derive(Clone, Debug)]
struct CuffLimit {
    vertex: u32,
    reach: f32,
    capsules: std::ops::Range<usize>,
    /// The capsule along whose axis the sleeve end's slide is measured (the bone's first), and
    /// the vertex's coordinate along that axis at rest (cm from the capsule's `a` end).
    axis_capsule: usize,
    rest_along: f32,
}

/// A vertex's coordinate along a capsule's axis (cm from its `a` end towards `b`), and that unit
/// axis.
fn along_axis(capsule: &Capsule, p: Vec3A) -> (f32, Vec3A) {
    let (a, b) = (Vec3A::from(capsule.a), Vec3A::from(capsule.b));
    let axis = (b - a).normalize_or_zero();
    ((p - a).dot(axis), axis)
}

#[derive(Clone, Copy, Debug)]
struct Tether {
    vertex: u32,
    anchor: u32,
    max: f32,
}

/// A garment being simulated.
#[derive(Clone, Debug)]
pub struct Cloth {
    name: String,
    settings: SolverSettings,
    material: Material,
    rest: Vec<Vec3A>,
    triangles: Vec<[u32; 3]>,
    mass: Vec<f32>,
    inv_mass: Vec<f32>,
    anchors: Vec<Anchor>,
    /// The bone whose motion carries the cloth below full [`SolverSettings::inertia`]: the one
    /// most rigid anchors are bound to.
    carry_bone: usize,
    /// This substep's carry ([`Cloth::carry_delta`]), `None` at full inertia.
    carry: Option<Affine3A>,
    cuffs: Vec<CuffLimit>,
    /// Capsule indices of the cuffs' bones.
    cuff_capsules: Vec<u16>,
    edges: Vec<Edge>,
    /// `edges` packed eight at a time for the stretch sweeps.
    edge_blocks: EdgeBlocks,
    bends: Vec<Bend>,
    tethers: Vec<Tether>,
    // State.
    x: Vec<Vec3A>,
    v: Vec<Vec3A>,
    prev: Vec<Vec3A>,
    normals: Vec<Vec3A>,
    pose: BodyPose,
    pose_before: BodyPose,
    // Per-substep capsule data.
    prepared: Vec<PreparedCapsule>,
    /// Each capsule's box grown by the collision offset, as `[min, max]` in SIMD vectors.
    boxes: Vec<[Vec3A; 2]>,
    back: Vec<Affine3A>,
    /// Joint and collision group of each capsule (the rig's proxies).
    capsule_joints: Vec<usize>,
    capsule_groups: Vec<u8>,
    /// How strongly each vertex is pushed out of the arm capsules (0: trunk cloth, ignores the
    /// arms; 1: arm cloth), from where it lies at rest.
    arm_weight: Vec<f32>,
    /// Per vertex, this substep: the last contact's normal (zero if none) and the body surface's
    /// displacement there.
    contact_normal: Vec<Vec3A>,
    contact_motion: Vec<Vec3A>,
    contact_depth: Vec<f32>,
    // Per-frame broad phase.
    swept: Vec<Aabb>,
    candidate_start: Vec<u32>,
    /// How many of each vertex's candidates (the first ones) are trunk capsules.
    candidate_trunk: Vec<u8>,
    candidates: Vec<u16>,
    candidate_origin: Vec<Vec3A>,
    candidate_reach2: Vec<f32>,
    all_capsules: Vec<u16>,
    /// How many of `all_capsules` (the first ones) are trunk capsules.
    all_trunk: usize,
    scratch_pose: BodyPose,
    scratch_pose2: BodyPose,
    start_frame: Vec<f32>,
    blend_a: Vec<f32>,
    blend_b: Vec<f32>,
    /// True while [`Cloth::dress`] blends from the rest pose into the first frame: the sleeves
    /// then ride up freely (no cuff hold).
    dressing: bool,
    /// The two previous iterates of the Chebyshev-accelerated stretch sweeps.
    sweep_even: Vec<Vec3A>,
    sweep_odd: Vec<Vec3A>,
    /// Each vertex's edges (`incidence.edges(v)`: indices into `edges`).
    incidence: Adjacency,
    /// The strain limit's edges outside the bound and the vertices it moved, this round, and the
    /// round in which each edge was last looked at.
    limit_edges: Vec<u32>,
    limit_moved: Vec<u32>,
    limit_seen: Vec<u32>,
    limit_moved_at: Vec<u32>,
    limit_round: u32,
    /// Whether substeps count the vertices that tunnel through a capsule ([`Cloth::check_tunnelling`]),
    /// how many did since the last frame began (or dressing), and the per-substep scratch: each
    /// capsule's core and the map carrying a point of its bone from one substep ago to now.
    tunnel_check: bool,
    tunnelled: u32,
    cores: Vec<PreparedCapsule>,
    forward: Vec<Affine3A>,
}

impl Cloth {
    /// A cloth for `garment` made of `material`, its anchors driven by `rig`'s bones.
    pub fn new(
        garment: &GarmentMesh,
        material: &Material,
        settings: &SolverSettings,
        rig: &BodyRig,
    ) -> Result<Cloth, ClothError> {
        garment.validate()?;
        let bones = rig.skeleton().len();
        if let Some((index, a)) = garment
            .anchors
            .iter()
            .enumerate()
            .find(|(_, a)| a.bone >= bones)
        {
            return Err(ClothError::AnchorBone {
                garment: garment.name.clone(),
                index,
                bone: a.bone,
                bones,
            });
        }
        // Each cuff's bone's capsules, and where along the first of them the cuff lies at rest.
        let mut rest_pose = BodyPose::default();
        rig.pose(&rig.rest_frame(), &mut rest_pose);
        let mut cuffs = Vec::with_capacity(garment.cuffs.len());
        let mut cuff_capsules = Vec::new();
        for (index, c) in garment.cuffs.iter().enumerate() {
            let start = cuff_capsules.len();
            cuff_capsules.extend(
                rig.proxies()
                    .iter()
                    .enumerate()
                    .filter(|(_, p)| p.joint == c.bone)
                    .map(|(k, _)| k as u16),
            );
            if cuff_capsules.len() == start {
                return Err(ClothError::CuffBone {
                    garment: garment.name.clone(),
                    index,
                    bone: c.bone,
                    bones,
                });
            }
            let axis_capsule = cuff_capsules[start] as usize;
            let rest_along = match (
                rest_pose.capsules.get(axis_capsule),
                garment.positions.get(c.vertex as usize),
            ) {
                (Some(capsule), Some(&p)) => along_axis(capsule, p.into()).0,
                _ => 0.0,
            };
            cuffs.push(CuffLimit {
                vertex: c.vertex,
                reach: c.reach_cm,
                capsules: start..cuff_capsules.len(),
                axis_capsule,
                rest_along,
            });
        }
        let check = |name: &'static str, value: f32, ok: bool, expected: &'static str| {
            if ok {
                Ok(())
            } else {
                Err(ClothError::Setting {
                    name,
                    value,
                    expected,
                })
            }
        };
        check(
            "inertia.linear",
            settings.inertia.linear,
            (0.0..=1.0).contains(&settings.inertia.linear),
            "between 0 and 1",
        )?;
        check(
            "inertia.angular",
            settings.inertia.angular,
            (0.0..=1.0).contains(&settings.inertia.angular),
            "between 0 and 1",
        )?;
        check(
            "fps",
            settings.fps,
            settings.fps > 0.0 && settings.fps.is_finite(),
            "> 0",
        )?;
        check(
            "substeps",
            settings.substeps as f32,
            (1..=1000).contains(&settings.substeps),
            "1..=1000",
        )?;
        check(
            "iterations",
            settings.iterations as f32,
            (1..=100).contains(&settings.iterations),
            "1..=100",
        )?;
        check(
            "chebyshev_rho",
            settings.chebyshev_rho,
            (0.0..1.0).contains(&settings.chebyshev_rho),
            "0 ≤ ρ < 1",
        )?;
        check(
            "strain_limit",
            settings.strain_limit,
            (0.0..1.0).contains(&settings.strain_limit),
            "0 (off) ≤ limit < 1",
        )?;
        check(
            "loose_anchor_seconds",
            settings.loose_anchor_seconds,
            settings.loose_anchor_seconds >= 0.0 && settings.loose_anchor_seconds.is_finite(),
            ">= 0 s",
        )?;
        check(
            "cuff_slide_cm",
            settings.cuff_slide_cm,
            settings.cuff_slide_cm >= 0.0,
            ">= 0 cm (infinite: off)",
        )?;
        check(
            "cuff_hold_seconds",
            settings.cuff_hold_seconds,
            settings.cuff_hold_seconds > 0.0 && settings.cuff_hold_seconds.is_finite(),
            "> 0 s",
        )?;
        check(
            "density",
            material.density_g_per_cm2,
            material.density_g_per_cm2 > 0.0 && material.density_g_per_cm2.is_finite(),
            "> 0 g/cm²",
        )?;
        let n = garment.positions.len();
        let rest: Vec<Vec3A> = garment.positions.iter().map(|&p| p.into()).collect();
        let mut area = vec![0.0f32; n];
        for t in &garment.triangles {
            let [a, b, c] = t.map(|i| rest[i as usize]);
            let third = (b - a).cross(c - a).length() / 6.0;
            for &i in t {
                area[i as usize] += third;
            }
        }
        let mass: Vec<f32> = area
            .iter()
            .map(|a| a * material.density_g_per_cm2)
            .collect();
        let mut inv_mass: Vec<f32> = mass
            .iter()
            .map(|&m| if m > 0.0 { 1.0 / m } else { 0.0 })
            .collect();
        for a in &garment.anchors {
            if a.slack_cm <= 0.0 {
                inv_mass[a.vertex as usize] = 0.0;
            }
        }
        let mut cloth = Cloth {
            name: garment.name.clone(),
            settings: settings.clone(),
            material: material.clone(),
            rest: rest.clone(),
            triangles: garment.triangles.clone(),
            mass,
            inv_mass,
            anchors: garment.anchors.clone(),
            carry_bone: carry_bone(&garment.anchors),
            carry: None,
            cuffs,
            cuff_capsules,
            edges: Vec::new(),
            edge_blocks: EdgeBlocks::default(),
            bends: Vec::new(),
            tethers: Vec::new(),
            x: rest.clone(),
            v: vec![Vec3A::ZERO; n],
            prev: rest.clone(),
            normals: vec![Vec3A::Y; n],
            pose: BodyPose::default(),
            pose_before: BodyPose::default(),
            prepared: Vec::new(),
            boxes: Vec::new(),
            back: Vec::new(),
            capsule_joints: rig.proxies().iter().map(|p| p.joint).collect(),
            capsule_groups: rig.proxies().iter().map(|p| p.group).collect(),
            arm_weight: vec![0.0; n],
            swept: Vec::new(),
            candidate_start: Vec::new(),
            candidate_trunk: Vec::new(),
            candidates: Vec::new(),
            contact_normal: vec![Vec3A::ZERO; n],
            contact_motion: vec![Vec3A::ZERO; n],
            contact_depth: vec![0.0; n],
            candidate_origin: vec![Vec3A::ZERO; n],
            candidate_reach2: vec![-1.0; n],
            all_capsules: Vec::new(),
            all_trunk: 0,
            scratch_pose: BodyPose::default(),
            scratch_pose2: BodyPose::default(),
            start_frame: Vec::new(),
            blend_a: Vec::new(),
            blend_b: Vec::new(),
            dressing: false,
            sweep_even: Vec::new(),
            sweep_odd: Vec::new(),
            incidence: Adjacency::new(0, &[]),
            limit_edges: Vec::new(),
            limit_moved: Vec::new(),
            limit_seen: Vec::new(),
            limit_moved_at: Vec::new(),
            limit_round: 0,
            tunnel_check: false,
            tunnelled: 0,
            cores: Vec::new(),
            forward: Vec::new(),
        };
        cloth.build_constraints();
        cloth.update_normals();
        let rest_frame = rig.rest_frame();
        rig.pose(&rest_frame, &mut cloth.pose);
        cloth.pose_before = cloth.pose.clone();
        let prepared: Vec<PreparedCapsule> =
            cloth.pose.capsules.iter().map(|c| c.prepared()).collect();
        // Arm cloth is cloth nearer an arm than the trunk at rest, with a smooth ramp between: a
        // hard boundary between cloth that the arm pushes and cloth it passes through tears the
        // sleeve from the armhole whenever the arm sinks into the torso. (A shirt's armpit ring,
        // just under the arm in the T-pose but no nearer to it than to the chest, is trunk cloth.)
        for (v, p) in cloth.rest.iter().enumerate() {
            let nearest = |group: u8| {
                prepared
                    .iter()
                    .zip(&cloth.capsule_groups)
                    .filter(|(_, g)| **g == group)
                    .map(|(c, _)| c.distance(*p))
                    .fold(f32::INFINITY, f32::min)
            };
            let lead = (nearest(GROUP_TRUNK) - nearest(GROUP_ARMS)) / ARM_RAMP_CM;
            let lead = if lead.is_finite() {
                lead.clamp(0.0, 1.0)
            } else {
                0.0
            };
            cloth.arm_weight[v] = lead * lead * (3.0 - 2.0 * lead);
        }
        Ok(cloth)
    }

    fn build_constraints(&mut self) {
        let h = self.settings.substep_seconds();
        let h2 = h * h;
        let n = self.rest.len();
        let edge_list = unique_edges(&self.triangles);
        // Geodesic distance to the nearest anchor: Dijkstra from all anchors at once over the
        // mesh's two-ring neighbourhoods (straight rest-shape steps to every vertex within two
        // edges). Paths along the edges alone zigzag and overestimate the distance by up to ~8 %,
        // which would let the tethers allow that much stretch; with two-ring steps the excess is
        // about 1 %.
        let adjacency = Adjacency::new(n, &edge_list);
        let mut distance = vec![f32::INFINITY; n];
        let mut source = vec![u32::MAX; n];
        let mut heap = BinaryHeap::new();
        // Tethers hang from the rigid anchors only; a loose anchor (a dress's waist) is a belt held
        // by its own slack. Tethering one stretch of cloth to anchor rings on two bones would pin
        // it on both sides and put all of the bones' relative motion (the back lengthening as the
        // spine flexes) into the one row where the two regions meet.
        for a in self.anchors.iter().filter(|a| a.slack_cm <= 0.0) {
            let v = a.vertex as usize;
            distance[v] = 0.0;
            source[v] = a.vertex;
            heap.push(Reverse((OrderedF32(0.0), a.vertex)));
        }
        let mut ring: Vec<u32> = Vec::new();
        while let Some(Reverse((OrderedF32(d), v))) = heap.pop() {
            if d > distance[v as usize] {
                continue;
            }
            ring.clear();
            for &w in adjacency.neighbours(v as usize) {
                ring.push(w);
                ring.extend_from_slice(adjacency.neighbours(w as usize));
            }
            ring.sort_unstable();
            ring.dedup();
            for &w in &ring {
                if w == v {
                    continue;
                }
                let nd = d + self.rest[v as usize].distance(self.rest[w as usize]);
                if nd < distance[w as usize] {
                    distance[w as usize] = nd;
                    source[w as usize] = source[v as usize];
                    heap.push(Reverse((OrderedF32(nd), w)));
                }
            }
        }
        let alpha = self.material.stretch_compliance / h2;
        let mut edges: Vec<(f32, Edge)> = edge_list
            .iter()
            .filter_map(|&[i, j]| {
                let (wi, wj) = (self.inv_mass[i as usize], self.inv_mass[j as usize]);
                let rest = self.rest[i as usize].distance(self.rest[j as usize]);
                if wi + wj <= 0.0 || rest <= 1e-6 {
                    return None;
                }
                let denominator = wi + wj + alpha;
                let order = distance[i as usize].min(distance[j as usize]);
                Some((
                    order,
                    Edge {
                        i,
                        j,
                        rest,
                        inv_rest2: 1.0 / (rest * rest),
                        ci: wi / denominator,
                        cj: wj / denominator,
                    },
                ))
            })
            .collect();
        edges.sort_by(|a, b| {
            a.0.total_cmp(&b.0)
                .then(a.1.i.cmp(&b.1.i))
                .then(a.1.j.cmp(&b.1.j))
        });
        let edges: Vec<Edge> = edges.into_iter().map(|(_, e)| e).collect();
        self.edges = interleave(&edges, n, |e| [e.i, e.j]);
        let constraints: Vec<DistanceConstraint> = self
            .edges
            .iter()
            .map(|e| DistanceConstraint {
                i: e.i,
                j: e.j,
                inv_rest2: e.inv_rest2,
                ci: e.ci,
                cj: e.cj,
            })
            .collect();
        self.edge_blocks = EdgeBlocks::pack(&constraints);
        // Each vertex's edges (indices into `self.edges`), for the strain limit's later rounds.
        let ends: Vec<[u32; 2]> = self.edges.iter().map(|e| [e.i, e.j]).collect();
        self.incidence = Adjacency::new(n, &ends);

        let bends: Vec<Bend> = hinges(&self.triangles)
            .into_iter()
            .filter_map(|v| {
                let [x0, x1, x2, x3] = v.map(|i| self.rest[i as usize]);
                let cot = |a: Vec3A, b: Vec3A| {
                    let s = a.cross(b).length();
                    if s > 1e-9 {
                        a.dot(b) / s
                    } else {
                        0.0
                    }
                };
                let (e0, e1, e2, e3, e4) = (x1 - x0, x2 - x0, x3 - x0, x2 - x1, x3 - x1);
                let (c01, c02, c03, c04) = (cot(e0, e1), cot(e0, e2), cot(-e0, e3), cot(-e0, e4));
                let k = [c03 + c04, c01 + c02, -c01 - c03, -c02 - c04];
                let areas = 0.5 * (e0.cross(e1).length() + e0.cross(e2).length());
                if areas <= 1e-9 {
                    return None;
                }
                let alpha = self.material.bend_compliance * areas / 3.0 / h2;
                let w = v.map(|i| self.inv_mass[i as usize]);
                let denominator: f32 = (0..4).map(|m| w[m] * k[m] * k[m]).sum::<f32>() + alpha;
                if denominator.is_nan() || denominator <= 0.0 || w.iter().all(|&w| w == 0.0) {
                    return None;
                }
                Some(Bend {
                    v,
                    k,
                    c: [0, 1, 2, 3].map(|m| w[m] * k[m] / denominator),
                })
            })
            .collect();
        self.bends = interleave(&bends, n, |b| b.v);

        let slack = 1.0 + self.settings.tether_slack.max(0.0);
        self.tethers = (0..n)
            .filter(|&v| self.inv_mass[v] > 0.0 && source[v] != u32::MAX && distance[v].is_finite())
            .map(|v| Tether {
                vertex: v as u32,
                anchor: source[v],
                max: distance[v] * slack,
            })
            .collect();
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    pub fn settings(&self) -> &SolverSettings {
        &self.settings
    }

    pub fn material(&self) -> &Material {
        &self.material
    }

    /// Current vertex positions, world cm.
    pub fn positions(&self) -> &[Vec3A] {
        &self.x
    }

    /// Per-vertex unit normals (area-weighted, outward as the garment is wound), as of the end of
    /// the last frame stepped.
    pub fn normals(&self) -> &[Vec3A] {
        &self.normals
    }

    pub fn velocities(&self) -> &[Vec3A] {
        &self.v
    }

    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Rest positions (the garment mesh's).
    pub fn rest_positions(&self) -> &[Vec3A] {
        &self.rest
    }

    pub fn anchors(&self) -> &[Anchor] {
        &self.anchors
    }

    /// The body pose of the last substep (its capsules are what the cloth collided with).
    pub fn pose(&self) -> &BodyPose {
        &self.pose
    }

    pub fn vertex_count(&self) -> usize {
        self.x.len()
    }

    /// Sets every vertex position (e.g. a start shape other than the rest shape) and zeroes the
    /// velocities. Extra values are ignored; missing vertices keep their positions.
    pub fn set_positions(&mut self, positions: &[Vec3]) {
        for (x, p) in self.x.iter_mut().zip(positions) {
            *x = (*p).into();
        }
        self.prev.clone_from(&self.x);
        self.v.fill(Vec3A::ZERO);
        self.update_normals();
    }

    /// The rigid move that carries the free vertices below full [`SolverSettings::inertia`] over
    /// this substep: the carrying bone from `pose_before`'s place to `1 − linear` of the way to
    /// `pose`'s (its joint's position, by lerp) and `1 − angular` of its turn (by slerp).
    fn carry_delta(&self, inertia: Inertia) -> Option<Affine3A> {
        let bone = self.carry_bone;
        let (from, to) = (
            self.pose_before.bones.get(bone)?,
            self.pose.bones.get(bone)?,
        );
        let (_, q0, t0) = from.to_scale_rotation_translation();
        let (_, q1, t1) = to.to_scale_rotation_translation();
        let part = Affine3A::from_rotation_translation(
            q0.slerp(q1, 1.0 - inertia.angular),
            t0.lerp(t1, 1.0 - inertia.linear),
        );
        Some(part * from.inverse())
    }

    /// Moves the cloth rigidly by `to · from⁻¹` and stops it: a teleport with the body's root.
    pub fn teleport(&mut self, from: &Affine3A, to: &Affine3A) {
        let delta = *to * from.inverse();
        for x in &mut self.x {
            *x = delta.transform_point3a(*x);
        }
        self.prev.clone_from(&self.x);
        self.v.fill(Vec3A::ZERO);
        self.update_normals();
    }

    /// Puts the garment on: rest shape at the rest pose moved with the first frame's root, the other
    /// joints blended to `first_frame` over `blend_frames` frames (smoothstep), then `settle_frames`
    /// frames holding it.
    pub fn dress(&mut self, rig: &BodyRig, first_frame: &[f32]) {
        self.tunnelled = 0;
        self.x.clone_from(&self.rest);
        self.prev.clone_from(&self.rest);
        self.v.fill(Vec3A::ZERO);
        let rest_frame = rig.rest_frame();
        let mut start = rest_frame.clone();
        for k in rig.root_channels() {
            if let (Some(s), Some(&f)) = (start.get_mut(k), first_frame.get(k)) {
                *s = f;
            }
        }
        rig.pose(&rest_frame, &mut self.pose_before);
        rig.pose(&start, &mut self.pose);
        let (from, to) = (
            self.pose_before.bones.first().copied().unwrap_or_default(),
            self.pose.bones.first().copied().unwrap_or_default(),
        );
        self.teleport(&from, &to);
        let blend = self.settings.blend_frames;
        // The sleeves ride up freely while the arms come down from the T-pose, and are drawn back
        // down their arms while the first pose is held.
        self.dressing = true;
        let mut a = std::mem::take(&mut self.blend_a);
        let mut b = std::mem::take(&mut self.blend_b);
        for k in 0..blend {
            let smooth = |t: f32| t * t * (3.0 - 2.0 * t);
            rig.interpolate(&start, first_frame, smooth(k as f32 / blend as f32), &mut a);
            rig.interpolate(
                &start,
                first_frame,
                smooth((k + 1) as f32 / blend as f32),
                &mut b,
            );
            self.run(rig, &a, &b, self.settings.substeps);
        }
        self.blend_a = a;
        self.blend_b = b;
        self.dressing = false;
        for _ in 0..self.settings.settle_frames {
            self.run(rig, first_frame, first_frame, self.settings.substeps);
        }
    }

    /// Whether the substeps from now on count the vertices that tunnel through a capsule
    /// ([`FrameQuality::tunnelled`]). Off by default: it tests every free vertex's path against
    /// its capsules each substep, and `cloth_quality`'s eight cases ran at 0.56–0.69 of their frame
    /// rate with it on (2026-12-06).
    pub fn check_tunnelling(&mut self, on: bool) {
        self.tunnel_check = on;
        self.tunnelled = 0;
    }

    /// Starts over from the rest shape and dresses again on `frame` (tracking was lost).
    pub fn reset(&mut self, rig: &BodyRig, frame: &[f32]) {
        self.dress(rig, frame);
    }

    /// One frame (`1/fps` s, `substeps` substeps) with the body moving from `prev_frame` to
    /// `next_frame`.
    pub fn step_frame(
        &mut self,
        rig: &BodyRig,
        prev_frame: &[f32],
        next_frame: &[f32],
    ) -> StepInfo {
        self.tunnelled = 0;
        self.run(rig, prev_frame, next_frame, self.settings.substeps)
    }

    /// As many fixed-length substeps as `seconds` holds (at least one), with the body moving from
    /// `prev_frame` to `next_frame`: for cameras whose frame interval is not `1/fps`.
    pub fn advance(
        &mut self,
        rig: &BodyRig,
        prev_frame: &[f32],
        next_frame: &[f32],
        seconds: f32,
    ) -> StepInfo {
        let h = self.settings.substep_seconds();
        let substeps = if seconds.is_finite() && seconds > 0.0 {
            ((seconds / h).round() as u32).clamp(1, 100_000)
        } else {
            1
        };
        self.tunnelled = 0;
        self.run(rig, prev_frame, next_frame, substeps)
    }

    fn run(
        &mut self,
        rig: &BodyRig,
        prev_frame: &[f32],
        next_frame: &[f32],
        substeps: u32,
    ) -> StepInfo {
        let h = self.settings.substep_seconds();
        let mut start = std::mem::take(&mut self.start_frame);
        start.clear();
        start.extend_from_slice(prev_frame);
        // Jump thresholds are per 1/fps; scale them to this interval.
        let scale = (substeps as f32 * h * self.settings.fps).max(1.0);
        if self.pose_jump(rig, prev_frame, next_frame) > self.settings.pose_jump_cm * scale {
            self.start_frame = start;
            self.dress(rig, next_frame);
            return StepInfo {
                jumped: true,
                redressed: true,
                substeps: 0,
            };
        }
        let jumped = rig
            .root_position(prev_frame)
            .distance(rig.root_position(next_frame))
            > self.settings.jump_distance_cm * scale
            || rig.root_turn_degrees(prev_frame, next_frame)
                > self.settings.jump_turn_degrees * scale;
        if jumped {
            for k in rig.root_channels() {
                let value = next_frame.get(k).copied().unwrap_or(0.0);
                if let Some(s) = start.get_mut(k) {
                    *s = value;
                }
            }
            rig.pose(prev_frame, &mut self.pose_before);
            rig.pose(&start, &mut self.pose);
            let (from, to) = (
                self.pose_before.bones.first().copied().unwrap_or_default(),
                self.pose.bones.first().copied().unwrap_or_default(),
            );
            self.teleport(&from, &to);
        }
        self.capsule_joints.clear();
        self.capsule_joints
            .extend(rig.proxies().iter().map(|p| p.joint));
        self.capsule_groups.clear();
        self.capsule_groups
            .extend(rig.proxies().iter().map(|p| p.group));
        rig.pose(&start, &mut self.pose);
        self.build_candidates(rig, &start, next_frame, substeps as f32 * h);
        for s in 0..substeps {
            std::mem::swap(&mut self.pose, &mut self.pose_before);
            rig.pose_between(
                &start,
                next_frame,
                (s + 1) as f32 / substeps as f32,
                &mut self.pose,
            );
            let rounds = if s + 1 == substeps && !self.dressing {
                FRAME_END_STRAIN_LIMIT_PASSES
            } else {
                STRAIN_LIMIT_PASSES
            };
            // While the garment is put on it moves far in a frame (the arms come down from the
            // rest pose), and the normals follow it every substep; else once a frame (below).
            if self.dressing {
                self.update_normals();
            }
            self.carry = if self.dressing || self.settings.inertia.is_full() {
                None
            } else {
                self.carry_delta(self.settings.inertia)
            };
            self.substep(h, rounds);
        }
        // Once a frame, not every substep (9 % of the solver's time): the normals serve the air
        // drag, which a frame's turn of the cloth hardly changes, and the renderer, which gets
        // them for the positions it draws.
        self.update_normals();
        self.start_frame = start;
        StepInfo {
            jumped,
            redressed: false,
            substeps,
        }
    }

    /// Largest move of a capsule end relative to the root between two frames, cm.
    fn pose_jump(&mut self, rig: &BodyRig, a: &[f32], b: &[f32]) -> f32 {
        rig.pose(a, &mut self.scratch_pose);
        rig.pose(b, &mut self.scratch_pose2);
        let (pa, pb) = (&self.scratch_pose, &self.scratch_pose2);
        let (Some(ra), Some(rb)) = (pa.bones.first(), pb.bones.first()) else {
            return 0.0;
        };
        let (ra, rb) = (ra.inverse(), rb.inverse());
        pa.capsules
            .iter()
            .zip(&pb.capsules)
            .map(|(ca, cb)| {
                let da = ra
                    .transform_point3(ca.a)
                    .distance(rb.transform_point3(cb.a));
                let db = ra
                    .transform_point3(ca.b)
                    .distance(rb.transform_point3(cb.b));
                da.max(db)
            })
            .fold(0.0f32, f32::max)
    }

    /// Candidate capsules per vertex for the coming frame.
    fn build_candidates(&mut self, rig: &BodyRig, start: &[f32], next: &[f32], seconds: f32) {
        let count = self.pose.capsules.len();
        self.swept.clear();
        self.swept
            .extend(self.pose.capsules.iter().map(|c| c.aabb()));
        for t in [0.5f32, 1.0] {
            rig.pose_between(start, next, t, &mut self.scratch_pose);
            for (s, c) in self.swept.iter_mut().zip(&self.scratch_pose.capsules) {
                *s = s.union(&c.aabb());
            }
        }
        // Pad for the curved path of a rotating limb between the sampled times.
        for s in &mut self.swept {
            *s = s.expanded(2.0);
        }
        self.all_capsules.clear();
        self.all_capsules
            .extend((0..count.min(u16::MAX as usize)).map(|c| c as u16));
        // Trunk capsules first, then the arms'.
        let groups = &self.capsule_groups;
        self.all_capsules
            .sort_by_key(|&c| (groups.get(c as usize) != Some(&GROUP_TRUNK), c));
        self.all_trunk = self
            .all_capsules
            .iter()
            .filter(|&&c| self.is_trunk(c as usize))
            .count();
        let offset = self.settings.collision_offset;
        let fall = 0.5 * self.settings.gravity.length() * seconds * seconds;
        self.candidate_start.clear();
        self.candidate_trunk.clear();
        self.candidates.clear();
        for v in 0..self.x.len() {
            self.candidate_start.push(self.candidates.len() as u32);
            self.candidate_trunk.push(0);
            if self.inv_mass[v] == 0.0 {
                self.candidate_reach2[v] = -1.0;
                continue;
            }
            let p = self.x[v];
            let reach = offset + 1.0 + 1.5 * self.v[v].length() * seconds + fall;
            let around = Aabb {
                min: Vec3::from(p) - Vec3::splat(reach),
                max: Vec3::from(p) + Vec3::splat(reach),
            };
            let arms = self.arm_weight[v] > 0.0;
            // Trunk capsules first, then the arms'; trunk cloth ignores the arms.
            let mut trunk = 0u8;
            for &c in &self.all_capsules {
                let c = c as usize;
                if self.swept[c].overlaps(&around) && self.collides(arms, c) {
                    self.candidates.push(c as u16);
                    trunk += u8::from(self.is_trunk(c));
                }
            }
            self.candidate_trunk[v] = trunk;
            self.candidate_origin[v] = p;
            self.candidate_reach2[v] = (reach - offset).powi(2);
        }
        self.candidate_start.push(self.candidates.len() as u32);
    }

    /// One substep of `h` seconds, with up to `strain_limit_rounds` rounds of the strain limit.
    fn substep(&mut self, h: f32, strain_limit_rounds: usize) {
        // Capsules at this substep, and the map taking a point on a capsule back to where that
        // point of the body was one substep ago (for friction).
        let count = self.pose.capsules.len();
        self.prepared.clear();
        self.boxes.clear();
        self.back.clear();
        let offset = self.settings.collision_offset;
        for c in &self.pose.capsules {
            self.prepared.push(c.prepared());
            let b = c.aabb().expanded(offset);
            self.boxes.push([b.min.into(), b.max.into()]);
        }
        self.back.resize(count, Affine3A::IDENTITY);
        self.update_back_transforms();

        self.integrate(h);
        for a in &self.anchors {
            if a.slack_cm <= 0.0 {
                if let Some(bone) = self.pose.bones.get(a.bone) {
                    self.x[a.vertex as usize] = bone.transform_point3a(a.local.into());
                }
            }
        }
        let tau = self.settings.loose_anchor_seconds;
        let belt = if tau > 0.0 {
            1.0 - (-h / tau).exp()
        } else {
            1.0
        };
        let cuff_hold = if self.settings.cuff_slide_cm.is_finite() && !self.dressing {
            1.0 - (-h / self.settings.cuff_hold_seconds).exp()
        } else {
            0.0
        };
        for _ in 0..self.settings.iterations {
            self.solve_loose_anchors(belt);
            self.solve_cuffs(cuff_hold);
            // Tethers before the stretch sweeps, so that the sweeps spread each tether's pull over
            // the edges around its vertex (see the module documentation).
            self.solve_tethers();
            self.stretch_sweeps();
            self.solve_bending();
            self.solve_collisions();
            self.limit_strain(strain_limit_rounds);
        }
        let inv_h = 1.0 / h;
        let max_speed = self.settings.max_speed;
        let mu = self.material.friction;
        // The vertices' velocities are relative to the carry (it moved them without speed), so
        // the surface's motion is taken relative to it too.
        let uncarry = self.carry.map(|c| c.inverse());
        for (k, ((v, x), p)) in self.v.iter_mut().zip(&self.x).zip(&self.prev).enumerate() {
            let mut velocity = (*x - *p) * inv_h;
            // Contact: the push out of a capsule is a position fix, not a bounce, so the velocity
            // away from the surface (relative to the surface's own motion) is dropped — a vertex
            // caught where two capsules overlap would otherwise gain speed every substep. Coulomb
            // friction then takes up to μ × the normal velocity change (depth / h) off the sliding
            // velocity. Friction at the velocity level leaves the constraint projections alone.
            let n = self.contact_normal[k];
            if n != Vec3A::ZERO {
                let carried = uncarry.map_or(Vec3A::ZERO, |u| *p - u.transform_point3a(*p));
                let surface = (self.contact_motion[k] - carried) * inv_h;
                let relative = velocity - surface;
                let along = relative.dot(n);
                let tangential = relative - n * along;
                let slide = tangential.length();
                let stop = mu * self.contact_depth[k] * inv_h;
                let kept = if slide > stop {
                    1.0 - stop / slide
                } else {
                    0.0
                };
                velocity = surface + tangential * kept + n * along.min(0.0);
            }
            let speed2 = velocity.length_squared();
            if speed2 > max_speed * max_speed {
                velocity *= max_speed / speed2.sqrt();
            }
            *v = velocity;
        }
        if self.tunnel_check {
            self.count_passages();
        }
    }

    fn update_back_transforms(&mut self) {
        for (k, back) in self.back.iter_mut().enumerate() {
            let j = self.capsule_joints.get(k).copied().unwrap_or(usize::MAX);
            *back = match (self.pose_before.bones.get(j), self.pose.bones.get(j)) {
                (Some(before), Some(now)) => *before * now.inverse(),
                _ => Affine3A::IDENTITY,
            };
        }
    }

    fn update_normals(&mut self) {
        self.normals.fill(Vec3A::ZERO);
        for t in &self.triangles {
            let [a, b, c] = t.map(|i| self.x[i as usize]);
            let n = (b - a).cross(c - a);
            for &i in t {
                self.normals[i as usize] += n;
            }
        }
        for n in &mut self.normals {
            *n = n.normalize_or_zero();
        }
    }

    fn integrate(&mut self, h: f32) {
        let g = Vec3A::from(self.settings.gravity) * h;
        let kn = self.material.drag_normal / self.material.density_g_per_cm2 * h;
        let kt = (self.material.drag_tangential / self.material.density_g_per_cm2 * h).min(1.0);
        let keep = (1.0 - self.material.damping * h).clamp(0.0, 1.0);
        let carry = self.carry;
        for v in 0..self.x.len() {
            if let (Some(carry), true) = (carry, self.inv_mass[v] > 0.0) {
                // Carried with the garment's bone: moved and turned alike, no speed gained.
                self.x[v] = carry.transform_point3a(self.x[v]);
                self.v[v] = carry.matrix3 * self.v[v];
            }
            self.prev[v] = self.x[v];
            if self.inv_mass[v] == 0.0 {
                continue;
            }
            let mut velocity = self.v[v] + g;
            let n = self.normals[v];
            let vn = velocity.dot(n);
            let normal_part = n * vn;
            let tangential = velocity - normal_part;
            velocity -= normal_part * (kn * vn.abs()).min(1.0) + tangential * kt;
            velocity *= keep;
            self.v[v] = velocity;
            self.x[v] += velocity * h;
        }
    }

    /// Loose anchors: `fraction` of the way back within their slack of the bound position.
    fn solve_loose_anchors(&mut self, fraction: f32) {
        for a in &self.anchors {
            if a.slack_cm > 0.0 {
                if let Some(bone) = self.pose.bones.get(a.bone) {
                    let target = bone.transform_point3a(a.local.into());
                    let d = self.x[a.vertex as usize] - target;
                    let l2 = d.length_squared();
                    if l2 > a.slack_cm * a.slack_cm {
                        let l = l2.sqrt();
                        self.x[a.vertex as usize] -= d * ((1.0 - a.slack_cm / l) * fraction);
                    }
                }
            }
        }
    }

    /// Cuffs: a sleeve end farther than its reach from its limb's surface is put back at that
    /// distance from the nearest of the limb's capsules; one that slid further than
    /// `cuff_slide_cm` up the arm is drawn back down by the fraction `hold` of the excess.
    fn solve_cuffs(&mut self, hold: f32) {
        let slide = self.settings.cuff_slide_cm;
        for c in &self.cuffs {
            let v = c.vertex as usize;
            // Only cloth bunched at the sleeve's end is drawn down: while any of its edges is
            // taut the pull would stretch the sleeve over the shoulder.
            let slack = || {
                self.incidence.edges(v).iter().all(|&k| {
                    let e = &self.edges[k as usize];
                    self.x[e.i as usize].distance(self.x[e.j as usize]) < e.rest
                })
            };
            if hold > 0.0 {
                if let Some(capsule) = self.pose.capsules.get(c.axis_capsule) {
                    let (along, axis) = along_axis(capsule, self.x[v]);
                    let excess = c.rest_along - slide - along;
                    if excess > 0.0 && slack() {
                        self.x[v] += axis * (excess * hold);
                    }
                }
            }
            let p = self.x[v];
            let nearest = self.cuff_capsules[c.capsules.clone()]
                .iter()
                .filter_map(|&k| self.prepared.get(k as usize))
                .map(|capsule| capsule.query(p))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            if let Some((d, n)) = nearest {
                if d > c.reach {
                    self.x[v] = p - n * (d - c.reach);
                }
            }
        }
    }

    fn solve_tethers(&mut self) {
        for t in &self.tethers {
            let a = self.x[t.anchor as usize];
            let p = self.x[t.vertex as usize];
            let d = p - a;
            let l2 = d.length_squared();
            if l2 > t.max * t.max {
                self.x[t.vertex as usize] = a + d * (t.max / l2.sqrt());
            }
        }
    }

    /// `stretch_sweeps` sweeps over the stretch constraints, Chebyshev-accelerated when
    /// `chebyshev_rho` > 0: after sweep `k` the iterate is `x₋ + ω_k (x̃ − x₋)`, `x̃` the sweep's
    /// result and `x₋` the iterate two sweeps back ([`chebyshev_weight`]).
    fn stretch_sweeps(&mut self) {
        let sweeps = self.settings.stretch_sweeps.max(1);
        let rho = self.settings.chebyshev_rho;
        if rho <= 0.0 {
            for _ in 0..sweeps {
                self.solve_stretch();
            }
            return;
        }
        // The iterates two sweeps back, alternately in `even` (x₀, x₂, …) and `odd` (x₁, x₃, …):
        // each relaxation reads `x_{k−1}` and leaves `x_{k+1}` in its place.
        let mut even = std::mem::take(&mut self.sweep_even);
        let mut odd = std::mem::take(&mut self.sweep_odd);
        even.clone_from(&self.x);
        self.solve_stretch();
        if sweeps > 2 {
            odd.clone_from(&self.x);
        }
        let mut omega = 1.0;
        for k in 1..sweeps {
            self.solve_stretch();
            omega = chebyshev_weight(k, rho, omega);
            let two_back = if k % 2 == 1 { &mut even } else { &mut odd };
            over_relax(&mut self.x, two_back, omega);
        }
        self.sweep_even = even;
        self.sweep_odd = odd;
    }

    fn solve_stretch(&mut self) {
        let compression = self.settings.compression.clamp(0.0, 1.0);
        stretch::sweep(&mut self.x, &self.edge_blocks, compression);
    }

    fn solve_bending(&mut self) {
        let x = &mut self.x;
        for b in &self.bends {
            let [i0, i1, i2, i3] = b.v.map(|i| i as usize);
            let c = x[i0] * b.k[0] + x[i1] * b.k[1] + x[i2] * b.k[2] + x[i3] * b.k[3];
            x[i0] -= c * b.c[0];
            x[i1] -= c * b.c[1];
            x[i2] -= c * b.c[2];
            x[i3] -= c * b.c[3];
        }
    }

    fn solve_collisions(&mut self) {
        for v in 0..self.x.len() {
            self.collide_vertex(v, true, true);
        }
    }

    /// Strain limiting after the collisions (Provot 1995; see the module documentation): up to
    /// `rounds` rounds ([`STRAIN_LIMIT_PASSES`], [`FRAME_END_STRAIN_LIMIT_PASSES`]), the edges
    /// longer than `1 + strain_limit` or shorter than `1 − strain_limit` times their rest length
    /// are found, projected onto that bound [`STRAIN_LIMIT_SWEEPS`] times (a vertex in contact
    /// takes [`STRAIN_LIMIT_CONTACT_SHARE`] of its share, so free cloth follows the cloth a capsule
    /// holds rather than pulling it back in), and the vertices moved meet the capsules again (in
    /// the last round the trunk's only). The first round looks at every edge, the later ones only
    /// at the edges of the vertices the round before moved.
    fn limit_strain(&mut self, rounds: usize) {
        let limit = self.settings.strain_limit;
        if limit <= 0.0 {
            return;
        }
        let (lo2, hi2) = ((1.0 - limit) * (1.0 - limit), (1.0 + limit) * (1.0 + limit));
        let outside = |x: &[Vec3A], e: &Edge| {
            let r2 = (x[e.j as usize] - x[e.i as usize]).length_squared() * e.inv_rest2;
            r2 > hi2 || r2 < lo2
        };
        self.limit_edges.clear();
        stretch::outside_bounds(&self.x, &self.edge_blocks, lo2, hi2, &mut self.limit_edges);
        self.limit_seen.resize(self.edges.len(), 0);
        self.limit_moved_at.resize(self.x.len(), 0);
        for round in 0..rounds {
            if self.limit_edges.is_empty() {
                return;
            }
            self.limit_round = self.limit_round.wrapping_add(1).max(1);
            self.limit_moved.clear();
            let x = &mut self.x;
            for _ in 0..STRAIN_LIMIT_SWEEPS {
                for &k in &self.limit_edges {
                    let e = &self.edges[k as usize];
                    let (i, j) = (e.i as usize, e.j as usize);
                    let d = x[j] - x[i];
                    let r2 = d.length_squared() * e.inv_rest2;
                    let share = |v: usize| {
                        let contact = if self.contact_depth[v] > 0.0 {
                            STRAIN_LIMIT_CONTACT_SHARE
                        } else {
                            1.0
                        };
                        self.inv_mass[v] * contact
                    };
                    if let Some((move_i, move_j)) =
                        limit_projection(d, r2, share(i), share(j), limit)
                    {
                        x[i] += move_i;
                        x[j] += move_j;
                        for v in [e.i, e.j] {
                            if self.limit_moved_at[v as usize] != self.limit_round {
                                self.limit_moved_at[v as usize] = self.limit_round;
                                self.limit_moved.push(v);
                            }
                        }
                    }
                }
            }
            // The last round leaves the arms out: where a sleeve ramps into an arm, the arm's push
            // moved one end of an edge further than the other and undid the round's work.
            let last_round = round + 1 == rounds;
            for k in 0..self.limit_moved.len() {
                self.collide_vertex(self.limit_moved[k] as usize, false, !last_round);
            }
            if last_round {
                return;
            }
            // The next round: the moved vertices' edges still (or now) outside the bound.
            let stamp = self.limit_round;
            self.limit_edges.clear();
            for &v in &self.limit_moved {
                for &k in self.incidence.edges(v as usize) {
                    if self.limit_seen[k as usize] != stamp
                        && outside(&self.x, &self.edges[k as usize])
                    {
                        self.limit_seen[k as usize] = stamp;
                        self.limit_edges.push(k);
                    }
                }
            }
            // In mesh order (the interleaved order of the sweeps), as the first round.
            self.limit_edges.sort_unstable();
        }
    }

    /// Pushes vertex `v` out of the capsules it collides with, the arms' only when `arms`.
    /// `fresh`: the substep's first pass, which also clears the vertex's contact when it touches
    /// nothing.
    #[inline(always)]
    fn collide_vertex(&mut self, v: usize, fresh: bool, arms: bool) {
        let offset = self.settings.collision_offset;
        let reach2 = self.candidate_reach2[v];
        if reach2 < 0.0 {
            return;
        }
        let mut p = self.x[v];
        if fresh {
            self.contact_normal[v] = Vec3A::ZERO;
            self.contact_depth[v] = 0.0;
        }
        let weight = self.arm_weight[v];
        let (trunk, arms_list) = self.capsules_for(v, p);
        // Depenetrate from the trunk; then, for arm cloth not lying on the trunk, from the arms
        // (by the arm weight), and from the trunk again if an arm pushed it in (the trunk wins
        // where they overlap). Remember the deepest contact for the velocity update (friction).
        let mut deepest: Option<(f32, Vec3A, usize)> = None;
        // Pushes `p` out of capsule `c` to `offset − allowed` from its surface; returns whether it
        // moved and the distance from the capsule afterwards (infinite outside its box).
        let resolve =
            |p: &mut Vec3A, c: usize, allowed: f32, deepest: &mut Option<(f32, Vec3A, usize)>| {
                let [min, max] = self.boxes[c];
                if !(p.cmpge(min) & p.cmple(max)).all() {
                    return (false, f32::INFINITY);
                }
                // The distance alone first: most tests find the vertex outside, and the normal
                // costs a division and a normalisation.
                let target = offset - allowed;
                let d = self.prepared[c].distance(*p);
                if d < target {
                    let (d, n) = self.prepared[c].query(*p);
                    let depth = (target - d).max(0.0);
                    *p += n * depth;
                    if deepest.is_none_or(|(best, _, _)| depth > best) {
                        *deepest = Some((depth, n, c));
                    }
                    (true, target)
                } else {
                    (false, d)
                }
            };
        let mut trunk_distance = f32::INFINITY;
        for &c in trunk {
            let (_, d) = resolve(&mut p, c as usize, 0.0, &mut deepest);
            if d < trunk_distance {
                trunk_distance = d;
            }
        }
        let near_trunk = arm_allowance_by_trunk(trunk_distance, offset);
        if arms && weight > 0.0 && near_trunk.is_finite() {
            // Cloth on the ramp between trunk and arm cloth may lie inside an arm by up to
            // (1 − weight) × ARM_RAMP_CM: the sleeve enters the arm gradually; and cloth near the
            // trunk may lie in an arm pressed against it (the trunk wins on its surface).
            let allowed = ((1.0 - weight) * ARM_RAMP_CM).max(near_trunk);
            let mut pushed = false;
            for &c in arms_list {
                pushed |= resolve(&mut p, c as usize, allowed, &mut deepest).0;
            }
            if pushed {
                for &c in trunk {
                    resolve(&mut p, c as usize, 0.0, &mut deepest);
                }
            }
        }
        if let Some((depth, n, c)) = deepest {
            self.contact_normal[v] = n;
            self.contact_motion[v] = p - self.back[c].transform_point3a(p);
            self.contact_depth[v] = depth;
        }
        self.x[v] = p;
    }

    /// The capsules free vertex `v`, now at `p`, meets, the trunk's and then the arms': its
    /// candidates for this frame while it stays within their reach, else every capsule.
    fn capsules_for(&self, v: usize, p: Vec3A) -> (&[u16], &[u16]) {
        let (list, trunk_count): (&[u16], usize) =
            if (p - self.candidate_origin[v]).length_squared() <= self.candidate_reach2[v] {
                let (a, b) = (
                    self.candidate_start[v] as usize,
                    self.candidate_start[v + 1] as usize,
                );
                (&self.candidates[a..b], self.candidate_trunk[v] as usize)
            } else {
                (&self.all_capsules, self.all_trunk)
            };
        list.split_at(trunk_count.min(list.len()))
    }

    /// Counts the free vertices whose path in this substep, seen from the body (the path's start
    /// carried along with the capsule's bone), went through the inner [`TUNNEL_CORE_SHARE`] of a
    /// capsule they meet while both its ends lie outside that core: cloth that tunnelled through
    /// a limb between two collision tests, which the tests that follow cannot see. As in
    /// [`Cloth::quality`]'s penetration figure, the arms count only for fully arm cloth away from
    /// the trunk: elsewhere cloth may lie inside an arm by design (trunk cloth under a lowered
    /// arm, the ramp into a sleeve, arm cloth on the trunk where the arm sinks into it).
    fn count_passages(&mut self) {
        self.cores.clear();
        self.cores.extend(self.pose.capsules.iter().map(|c| {
            Capsule::new(
                c.a,
                c.b,
                TUNNEL_CORE_SHARE * c.radius_a,
                TUNNEL_CORE_SHARE * c.radius_b,
            )
            .prepared()
        }));
        self.forward.clear();
        self.forward.extend(self.back.iter().map(|b| b.inverse()));
        let mut passages = 0;
        for v in 0..self.x.len() {
            if self.candidate_reach2[v] < 0.0 {
                continue;
            }
            let (from, to) = (self.prev[v], self.x[v]);
            let (trunk, arms) = self.capsules_for(v, to);
            let through = |&c: &u16| {
                let c = c as usize;
                self.cores[c].path_passes_through(self.forward[c].transform_point3a(from), to)
            };
            let arms_count = self.arm_weight[v] >= 1.0 && {
                let offset = self.settings.collision_offset;
                let trunk_distance = trunk
                    .iter()
                    .map(|&c| self.prepared[c as usize].distance(to))
                    .fold(f32::INFINITY, f32::min);
                arm_allowance_by_trunk(trunk_distance, offset) <= 0.0
            };
            let arms = if arms_count { arms } else { &[] };
            passages += u32::from(trunk.iter().chain(arms).any(through));
        }
        self.tunnelled += passages;
    }

    /// Does a vertex (with or without arm weight) collide with capsule `c`? Trunk cloth ignores the
    /// arms; see [`crate::cloth::proxies::collision_group`].
    #[inline]
    fn collides(&self, arms: bool, c: usize) -> bool {
        arms || self.is_trunk(c)
    }

    /// Is capsule `c` one of the trunk's?
    #[inline]
    fn is_trunk(&self, c: usize) -> bool {
        self.capsule_groups.get(c) == Some(&GROUP_TRUNK)
    }

    /// Σ ½ m v², erg.
    pub fn kinetic_energy(&self) -> f32 {
        self.v
            .iter()
            .zip(&self.mass)
            .zip(&self.inv_mass)
            .filter(|(_, &w)| w > 0.0)
            .map(|((v, m), _)| 0.5 * m * v.length_squared())
            .sum()
    }

    /// Strain, penetration and energy of the current state against the current pose.
    pub fn quality(&self) -> FrameQuality {
        let mut strains: Vec<f32> = self
            .edges
            .iter()
            .map(|e| {
                let l = self.x[e.i as usize].distance(self.x[e.j as usize]);
                (l - e.rest) / e.rest
            })
            .collect();
        let mut stretches: Vec<f32> = strains.iter().map(|s| s.max(0.0)).collect();
        for s in &mut strains {
            *s = s.abs();
        }
        let (strain_p95, strain_max) = percentile_95_and_max(&mut strains);
        let (stretch_p95, stretch_max) = percentile_95_and_max(&mut stretches);
        let capsules: Vec<(Aabb, PreparedCapsule, u8)> = self
            .pose
            .capsules
            .iter()
            .enumerate()
            .map(|(k, c)| {
                let group = self.capsule_groups.get(k).copied().unwrap_or(GROUP_TRUNK);
                (c.aabb(), c.prepared(), group)
            })
            .collect();
        let mut penetration = 0.0f32;
        let mut anchor_penetration = 0.0f32;
        let mut other_group = 0.0f32;
        for (v, &p) in self.x.iter().enumerate() {
            // Fully arm cloth counts arm capsules (except where it lies on the trunk, which wins,
            // or so near it that an arm pressed against the trunk may hold it:
            // [`buried_arm_allowance`]); trunk cloth and the ramp between do not.
            let arm_cloth = self.arm_weight[v] >= 1.0;
            let offset = self.settings.collision_offset;
            let trunk_distance = capsules
                .iter()
                .filter(|(b, _, g)| *g == GROUP_TRUNK && b.expanded(offset).contains(Vec3::from(p)))
                .map(|(_, c, _)| c.distance(p))
                .fold(f32::INFINITY, f32::min);
            let allowed = arm_allowance_by_trunk(trunk_distance, offset);
            let (mut own, mut other) = (0.0f32, 0.0f32);
            for (b, c, g) in &capsules {
                if b.contains(Vec3::from(p)) {
                    let depth = -c.distance(p);
                    if *g == GROUP_TRUNK || (arm_cloth && allowed <= 0.0) {
                        own = own.max(depth);
                    } else if arm_cloth {
                        own = own.max(depth - allowed);
                        other = other.max(depth);
                    } else {
                        other = other.max(depth);
                    }
                }
            }
            if self.inv_mass[v] > 0.0 {
                penetration = penetration.max(own);
            } else {
                anchor_penetration = anchor_penetration.max(own);
            }
            other_group = other_group.max(other);
        }
        let cuff_gap = self
            .cuffs
            .iter()
            .map(|c| {
                let p = self.x[c.vertex as usize];
                self.cuff_capsules[c.capsules.clone()]
                    .iter()
                    .filter_map(|&k| capsules.get(k as usize))
                    .map(|(_, capsule, _)| capsule.distance(p))
                    .fold(f32::INFINITY, f32::min)
            })
            .fold(0.0f32, f32::max);
        let cuff_slide = if self.cuffs.is_empty() {
            0.0
        } else {
            self.cuffs
                .iter()
                .map(|c| {
                    self.pose
                        .capsules
                        .get(c.axis_capsule)
                        .map_or(0.0, |capsule| {
                            c.rest_along - along_axis(capsule, self.x[c.vertex as usize]).0
                        })
                })
                .sum::<f32>()
                / self.cuffs.len() as f32
        };
        let (belt_sum, belt_count) = self
            .anchors
            .iter()
            .filter(|a| a.slack_cm > 0.0)
            .filter_map(|a| {
                let bone = self.pose.bones.get(a.bone)?;
                Some((self.x[a.vertex as usize] - bone.transform_point3a(a.local.into())).length())
            })
            .fold((0.0f32, 0usize), |(s, n), d| (s + d, n + 1));
        let belt_offset = if belt_count == 0 {
            0.0
        } else {
            belt_sum / belt_count as f32
        };
        FrameQuality {
            strain_p95,
            strain_max,
            stretch_p95,
            stretch_max,
            penetration_cm: penetration,
            anchor_penetration_cm: anchor_penetration,
            other_group_cm: other_group,
            cuff_gap_cm: cuff_gap,
            cuff_slide_cm: cuff_slide,
            belt_offset_cm: belt_offset,
            kinetic_energy: self.kinetic_energy(),
            max_speed: self.v.iter().map(|v| v.length()).fold(0.0f32, f32::max),
            tunnelled: self.tunnel_check.then_some(self.tunnelled),
        }
    }
}

/// Reorders each run of [`INTERLEAVE_WINDOW`] consecutive constraints so that constraints next to
/// each other share no vertex: a greedy colouring inside the run, the colours emitted in turn.
///
/// Gauss–Seidel projections are a chain of dependent loads and stores when neighbouring constraints
/// share a vertex (each waits for the square root and division of the one before); interleaved,
/// the processor overlaps them. The order across runs (from the anchors outward) is kept, so the
/// sweep still carries corrections down the garment; inside a run of 256 the order does not change
/// convergence measurably (`cargo bench --bench cloth`).
fn interleave<T: Copy, const K: usize>(
    items: &[T],
    vertex_count: usize,
    vertices: impl Fn(&T) -> [u32; K],
) -> Vec<T> {
    let mut out = Vec::with_capacity(items.len());
    // Per vertex, the colours already used by a constraint on it in this run (one bit each).
    let mut used: Vec<u64> = vec![0; vertex_count];
    let mut colour_of = Vec::with_capacity(INTERLEAVE_WINDOW);
    for run in items.chunks(INTERLEAVE_WINDOW) {
        colour_of.clear();
        let mut colours = 0u32;
        for item in run {
            let vs = vertices(item);
            let taken = vs.iter().fold(0u64, |t, &v| t | used[v as usize]);
            // With more than 64 colours needed (never seen), the rest share the last one.
            let c = (!taken).trailing_zeros().min(63);
            colour_of.push(c);
            colours = colours.max(c + 1);
            for v in vs {
                used[v as usize] |= 1 << c;
            }
        }
        for c in 0..colours {
            out.extend(
                run.iter()
                    .zip(&colour_of)
                    .filter(|(_, &k)| k == c)
                    .map(|(item, _)| *item),
            );
        }
        for item in run {
            for v in vertices(item) {
                used[v as usize] = 0;
            }
        }
    }
    out
}

/// How deep arm cloth `gap` cm off the trunk's collision surface may lie inside an arm capsule:
/// [`ARM_RAMP_CM`] on the surface, nothing from [`BURIED_ARM_GAP_CM`] off. The body's arms sink
/// into its chest and hips; where they do, cloth on the trunk is left inside the arm (the trunk
/// wins), and a sleeve vertex a few millimetres off the trunk, pushed out to the arm's far
/// surface, would tear the edge between the two. The allowance makes the arm's push fade in
/// over the first centimetres off the trunk instead.
fn buried_arm_allowance(gap: f32) -> f32 {
    (ARM_RAMP_CM * (1.0 - gap / BURIED_ARM_GAP_CM)).clamp(0.0, ARM_RAMP_CM)
}

/// How deep arm cloth whose nearest trunk capsule is `trunk_distance` cm away may lie inside an arm
/// capsule, the collisions keeping cloth `offset` off the capsules: without bound on the trunk
/// (within [`ON_TRUNK_CM`] of its collision surface: the trunk wins), else
/// [`buried_arm_allowance`]. The collisions and the penetration figure both go by it.
fn arm_allowance_by_trunk(trunk_distance: f32, offset: f32) -> f32 {
    if trunk_distance < offset + ON_TRUNK_CM {
        f32::INFINITY
    } else {
        buried_arm_allowance(trunk_distance - offset)
    }
}

/// The moves of an edge's two ends `i → j` (`d = xⱼ − xᵢ`, `r2` = its squared length over the
/// squared rest length) that put it back on the strain limit's bound, `1 ± limit` times the rest
/// length, shared in proportion to the weights; `None` when it is within the bound or neither end
/// may move.
fn limit_projection(d: Vec3A, r2: f32, wi: f32, wj: f32, limit: f32) -> Option<(Vec3A, Vec3A)> {
    let (lo, hi) = (1.0 - limit, 1.0 + limit);
    if (r2 <= hi * hi && r2 >= lo * lo) || wi + wj <= 0.0 || r2 <= 0.0 {
        return None;
    }
    let r = r2.sqrt();
    let bound = if r > hi { hi } else { lo };
    let s = (r - bound) / (r * (wi + wj));
    Some((d * (s * wi), -d * (s * wj)))
}

/// Chebyshev semi-iterative weight `ω` for sweep `k` (from 0) given the previous sweep's weight
/// (Wang 2015, after Golub and Van Loan): 1, then `2/(2 − ρ²)`, then `4/(4 − ρ²ω)`; it falls
/// towards `2/(1 + √(1 − ρ²))`.
fn chebyshev_weight(k: u32, rho: f32, previous: f32) -> f32 {
    match k {
        0 => 1.0,
        1 => 2.0 / (2.0 - rho * rho),
        _ => 4.0 / (4.0 - rho * rho * previous),
    }
}

/// `x ← before + ω (x − before)` for every vertex (kinematic ones have `x = before`), and
/// `before ← x`.
fn over_relax(x: &mut [Vec3A], before: &mut [Vec3A], omega: f32) {
    for (x, b) in x.iter_mut().zip(before) {
        *x = *b + (*x - *b) * omega;
        *b = *x;
    }
}

/// 95th percentile (nearest rank) and maximum; reorders `values`.
fn percentile_95_and_max(values: &mut [f32]) -> (f32, f32) {
    if values.is_empty() {
        return (0.0, 0.0);
    }
    let max = values.iter().copied().fold(0.0f32, f32::max);
    let k = ((values.len() - 1) as f32 * 0.95).round() as usize;
    let (_, p95, _) = values.select_nth_unstable_by(k, |a, b| a.total_cmp(b));
    (*p95, max)
}

/// f32 ordered by `total_cmp`, for the Dijkstra heap.
#[derive(Clone, Copy, Debug, PartialEq)]
struct OrderedF32(f32);

impl Eq for OrderedF32 {}

impl PartialOrd for OrderedF32 {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for OrderedF32 {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

/// Quality over a whole motion.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct QualitySummary {
    pub garment: String,
    pub vertices: usize,
    /// Frames simulated after dressing.
    pub frames: usize,
    /// Worst and mean per-frame 95th-percentile edge strain (the figures from here on include the
    /// dressed first frame).
    pub strain_p95_worst: f32,
    pub strain_p95_mean: f32,
    /// Largest edge strain in any frame.
    pub strain_max: f32,
    /// The same three for stretch alone.
    pub stretch_p95_worst: f32,
    pub stretch_p95_mean: f32,
    pub stretch_max: f32,
    /// Deepest free vertex inside a capsule at the end of any frame, cm.
    pub penetration_max_cm: f32,
    /// Deepest anchored vertex inside a capsule at the end of any frame, cm.
    pub anchor_penetration_max_cm: f32,
    /// Farthest a sleeve's end lies from its arm at the end of any frame, cm
    /// ([`FrameQuality::cuff_gap_cm`]).
    pub cuff_gap_max_cm: f32,
    /// The sleeves' ends' slide up the arms ([`FrameQuality::cuff_slide_cm`]): its mean over the
    /// frames and its largest value, cm.
    pub cuff_slide_mean_cm: f32,
    pub cuff_slide_max_cm: f32,
    /// The loose anchors' offset from their bound places ([`FrameQuality::belt_offset_cm`]): its
    /// mean over the frames and its largest value, cm.
    pub belt_offset_mean_cm: f32,
    pub belt_offset_max_cm: f32,
    /// Vertices that tunnelled through a capsule ([`FrameQuality::tunnelled`]), summed over the
    /// frames after the first, and the frames with any; and the same while the garment was put on
    /// (the arms brought down from the rest pose to the first frame's). `None` unless the cloth
    /// was checking ([`Cloth::check_tunnelling`]).
    pub tunnelled: Option<usize>,
    pub tunnelled_frames: usize,
    pub tunnelled_dressing: Option<usize>,
    /// Frames handled as root jumps (teleports) or pose jumps (dressed again).
    pub jumps: usize,
    pub redresses: usize,
    /// Wall-clock seconds spent stepping (dressing excluded; not part of the deterministic output).
    pub step_seconds: f64,
}

impl QualitySummary {
    /// Simulated frames per wall-clock second.
    pub fn frames_per_second(&self) -> f64 {
        if self.step_seconds > 0.0 {
            self.frames as f64 / self.step_seconds
        } else {
            0.0
        }
    }

    /// Does the run meet the issue's quality targets (strain p95 ≤ 2 %, max ≤ 10 %, no free vertex
    /// deeper than 2 mm, and, where it was checked, no tunnelling while the body moves through the
    /// motion: the dressing is not part of it)?
    pub fn meets_targets(&self) -> bool {
        self.strain_p95_worst <= 0.02
            && self.strain_max <= 0.10
            && self.penetration_max_cm <= 0.2
            && self.tunnelled.unwrap_or(0) == 0
    }
}

impl fmt::Display for QualitySummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: {} vertices, {} frames: |strain| p95 {:.2} % (worst frame) / {:.2} % (mean), max {:.1} %; \
             stretch p95 {:.2} % / {:.2} %, max {:.1} %; \
             deepest vertex {:.2} mm inside a capsule (anchors {:.2} mm); {}; {} jumps ({} dressed again); {:.1} frames/s",
            self.garment,
            self.vertices,
            self.frames,
            100.0 * self.strain_p95_worst,
            100.0 * self.strain_p95_mean,
            100.0 * self.strain_max,
            100.0 * self.stretch_p95_worst,
            100.0 * self.stretch_p95_mean,
            100.0 * self.stretch_max,
            10.0 * self.penetration_max_cm,
            10.0 * self.anchor_penetration_max_cm,
            match (self.tunnelled, self.tunnelled_dressing) {
                (Some(n), Some(d)) => format!(
                    "{n} vertices tunnelled through a capsule ({} frames; {d} while dressing)",
                    self.tunnelled_frames
                ),
                _ => "tunnelling not checked".to_string(),
            },
            self.jumps,
            self.redresses,
            self.frames_per_second()
        )
    }
}

/// How fast the hands and the feet move between the frames of `motion` (the frames the cloth is
/// given), metres per second: the fastest of the CMU/Daz `rHand`/`lHand` and of `rFoot`/`lFoot`
/// (0 where the skeleton has neither). Issue 6 asks for no tunnelling at 3 m/s hand speed; the
/// benchmark prints these beside its quality figures, and
/// `a_fast_capsule_does_not_tunnel_through_a_hanging_sheet` tests the solver at that speed.
pub fn peak_limb_speeds(motion: &Motion) -> (f32, f32) {
    let peak = |joints: [&str; 2]| {
        joints
            .iter()
            .filter_map(|j| motion.peak_joint_speed(j))
            .fold(0.0f32, f32::max)
            / 100.0
    };
    (peak(["rHand", "lHand"]), peak(["rFoot", "lFoot"]))
}

/// Dresses `cloth` on the first frame of `motion` (frames on the rig's skeleton) and simulates the
/// rest, calling `on_frame(index, cloth, quality)` after each frame; returns the summary. A motion
/// whose frame rate differs from the solver's is stepped by its own frame time with fixed substeps.
pub fn run_motion(
    rig: &BodyRig,
    cloth: &mut Cloth,
    motion: &Motion,
    mut on_frame: impl FnMut(usize, &Cloth, &FrameQuality),
) -> Result<QualitySummary, ClothError> {
    if motion.frame_count() == 0 {
        return Err(ClothError::NoFrames);
    }
    cloth.dress(rig, motion.frame(0));
    let same_rate =
        ((motion.frame_rate() as f32 - cloth.settings.fps) / cloth.settings.fps).abs() < 1e-3;
    let mut summary = QualitySummary {
        garment: cloth.name.clone(),
        vertices: cloth.vertex_count(),
        ..QualitySummary::default()
    };
    // The dressed first frame is an output frame like the others, so it counts too.
    let mut p95_sum = 0.0f64;
    let mut stretch_sum = 0.0f64;
    let mut slide_sum = 0.0f64;
    let mut belt_sum = 0.0f64;
    let mut record = |summary: &mut QualitySummary, q: &FrameQuality| {
        summary.strain_p95_worst = summary.strain_p95_worst.max(q.strain_p95);
        summary.strain_max = summary.strain_max.max(q.strain_max);
        summary.stretch_p95_worst = summary.stretch_p95_worst.max(q.stretch_p95);
        summary.stretch_max = summary.stretch_max.max(q.stretch_max);
        summary.penetration_max_cm = summary.penetration_max_cm.max(q.penetration_cm);
        summary.anchor_penetration_max_cm = summary
            .anchor_penetration_max_cm
            .max(q.anchor_penetration_cm);
        summary.cuff_gap_max_cm = summary.cuff_gap_max_cm.max(q.cuff_gap_cm);
        summary.cuff_slide_max_cm = summary.cuff_slide_max_cm.max(q.cuff_slide_cm);
        slide_sum += q.cuff_slide_cm as f64;
        summary.belt_offset_max_cm = summary.belt_offset_max_cm.max(q.belt_offset_cm);
        belt_sum += q.belt_offset_cm as f64;
        p95_sum += q.strain_p95 as f64;
        stretch_sum += q.stretch_p95 as f64;
    };
    let first = cloth.quality();
    on_frame(0, cloth, &first);
    record(&mut summary, &first);
    summary.tunnelled_dressing = first.tunnelled.map(|n| n as usize);
    summary.tunnelled = first.tunnelled.map(|_| 0);
    let mut stepping = std::time::Duration::ZERO;
    for k in 1..motion.frame_count() {
        let t0 = std::time::Instant::now();
        let info = if same_rate {
            cloth.step_frame(rig, motion.frame(k - 1), motion.frame(k))
        } else {
            cloth.advance(
                rig,
                motion.frame(k - 1),
                motion.frame(k),
                motion.frame_time as f32,
            )
        };
        stepping += t0.elapsed();
        let q = cloth.quality();
        on_frame(k, cloth, &q);
        summary.frames += 1;
        summary.jumps += info.jumped as usize;
        summary.redresses += info.redressed as usize;
        record(&mut summary, &q);
        if let (Some(total), Some(n)) = (summary.tunnelled.as_mut(), q.tunnelled) {
            *total += n as usize;
            summary.tunnelled_frames += usize::from(n > 0);
        }
    }
    let recorded = (summary.frames + 1) as f64;
    summary.strain_p95_mean = (p95_sum / recorded) as f32;
    summary.stretch_p95_mean = (stretch_sum / recorded) as f32;
    summary.cuff_slide_mean_cm = (slide_sum / recorded) as f32;
    summary.belt_offset_mean_cm = (belt_sum / recorded) as f32;
    summary.step_seconds = stepping.as_secs_f64();
    Ok(summary)
}

/// The whole evaluation from a mocap clip: the subject's rig, the clip scaled to the subject and
/// resampled to the solver's rate, the garment generated, dressed and simulated over the clip.
pub fn evaluate(
    motion: &Motion,
    subject: &Subject,
    kind: GarmentKind,
    garment: &GarmentParams,
    material: &Material,
    settings: &SolverSettings,
) -> Result<QualitySummary, ClothError> {
    let rig = BodyRig::for_subject(subject, &motion.skeleton, DEFAULT_MARGIN_CM)?;
    let scaled = rig.scale_motion(motion);
    let (resampled, _) = scaled.resample(0, None, settings.fps as f64)?;
    let mesh = GarmentMesh::generate(kind, &rig, garment)?;
    let mut cloth = Cloth::new(&mesh, material, settings, &rig)?;
    run_motion(&rig, &mut cloth, &resampled, |_, _, _| {})
}

/// The bone most of `anchors` are rigidly bound to (the loose ones if none is rigid; the root if
/// there are none): the garment's own frame, which carries it below full inertia.
fn carry_bone(anchors: &[Anchor]) -> usize {
    let rigid = anchors.iter().any(|a| a.slack_cm <= 0.0);
    let mut counts: Vec<usize> = Vec::new();
    for a in anchors.iter().filter(|a| !rigid || a.slack_cm <= 0.0) {
        if counts.len() <= a.bone {
            counts.resize(a.bone + 1, 0);
        }
        counts[a.bone] += 1;
    }
    counts
        .iter()
        .enumerate()
        .max_by_key(|&(bone, &count)| (count, std::cmp::Reverse(bone)))
        .map_or(0, |(bone, _)| bone)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::{Body, BodyPart, Material as Tissue};
    use crate::cloth::capsule::Capsule;
    use crate::cloth::garment::tests::chidi;
    use crate::cloth::garment::{Cuff, SLEEVE_CUFF_REACH_CM};
    use crate::skeleton::{Channel, Joint, Skeleton};
    use glam::Vec2;
    use std::path::Path;

    /// A rig of two joints: "world" (the root, three position channels) and "mover" (its child,
    /// three position channels), with round capsules on the mover.
    fn rig_with(parts: Vec<BodyPart>) -> BodyRig {
        let position = vec![Channel::Xposition, Channel::Yposition, Channel::Zposition];
        let skeleton = Skeleton::new(vec![
            Joint {
                name: "world".into(),
                parent: None,
                offset: Vec3::ZERO,
                channels: position.clone(),
                first_channel: 0,
                end_site: None,
            },
            Joint {
                name: "mover".into(),
                parent: Some(0),
                offset: Vec3::ZERO,
                channels: position,
                first_channel: 3,
                end_site: None,
            },
        ])
        .expect("skeleton");
        let body = Body::from_parts(parts, &skeleton);
        BodyRig::new(skeleton, body, 0.0)
    }

    fn bar(start: Vec3, end: Vec3, radius: f32) -> BodyPart {
        BodyPart {
            name: "bar",
            joint: 1,
            start,
            end,
            radii_start: Vec2::splat(radius),
            radii_end: Vec2::splat(radius),
            width_axis: Vec3::Y.any_orthonormal_vector(),
            cap: 1.0,
            patterned_caps: [true, true],
            material: Tissue::Skin,
            surface: 0,
        }
    }

    fn pin(mesh: &mut GarmentMesh, vertex: u32, at: Vec3) {
        mesh.anchors.push(Anchor {
            vertex,
            bone: 0,
            local: at,
            slack_cm: 0.0,
        });
    }

    fn settle(cloth: &mut Cloth, rig: &BodyRig, frames: usize) {
        let still = [0.0f32; 6];
        for _ in 0..frames {
            cloth.step_frame(rig, &still, &still);
        }
    }

    fn walk() -> (BodyRig, Motion) {
        let rig = chidi();
        let clip = Motion::load(
            &Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mocap/cmu_02_01_walk.bvh"),
        )
        .expect("clip");
        let (frames, _) = rig
            .scale_motion(&clip)
            .resample(crate::bvh::CMU_CALIBRATION_FRAMES, Some(12), 30.0)
            .expect("resample");
        (rig, frames)
    }

    #[test]
    fn interleaving_separates_constraints_that_share_a_vertex() {
        // A chain 0–1–2–3–4: edges 0 and 2 share no vertex (colour 0), nor do 1 and 3 (colour 1).
        let chain = [[0u32, 1], [1, 2], [2, 3], [3, 4]];
        assert_eq!(
            interleave(&chain, 5, |e| *e),
            vec![[0, 1], [2, 3], [1, 2], [3, 4]]
        );
        // Runs are coloured on their own and keep their order: the same chain split into runs of
        // 256 by a longer list comes back as a permutation with every run's items in it.
        let long: Vec<[u32; 2]> = (0..600).map(|k| [k, k + 1]).collect();
        let out = interleave(&long, 601, |e| *e);
        for (run_in, run_out) in long
            .chunks(INTERLEAVE_WINDOW)
            .zip(out.chunks(INTERLEAVE_WINDOW))
        {
            let mut a = run_in.to_vec();
            let mut b = run_out.to_vec();
            a.sort_unstable();
            b.sort_unstable();
            assert_eq!(a, b);
        }
        // Inside a run of the long chain no two neighbours share a vertex: the even edges, then the
        // odd ones ([254, 255] is followed by [1, 2]).
        let shared = out[..INTERLEAVE_WINDOW]
            .windows(2)
            .filter(|w| w[0].iter().any(|v| w[1].contains(v)))
            .count();
        assert_eq!(shared, 0);
    }

    #[test]
    fn the_strain_limit_puts_an_edge_back_on_its_bound_in_proportion_to_the_weights() {
        // Rest length 2, now 3 along X (r = 1.5): back to 2.18, the 0.82 shared 1 : 0.2.
        let d = Vec3A::new(3.0, 0.0, 0.0);
        let (mi, mj) = limit_projection(d, 2.25, 1.0, 0.2, 0.09).expect("outside");
        assert!(
            (mi - Vec3A::new(0.82 / 1.2, 0.0, 0.0)).length() < 1e-5,
            "{mi}"
        );
        assert!(
            (mj - Vec3A::new(-0.82 * 0.2 / 1.2, 0.0, 0.0)).length() < 1e-5,
            "{mj}"
        );
        assert!(((d - mi + mj).length() - 2.18).abs() < 1e-5);
        // Squashed to 1.5 (r = 0.75): pushed apart to 1.82, equally.
        let d = Vec3A::new(0.0, 1.5, 0.0);
        let (mi, mj) = limit_projection(d, 0.5625, 1.0, 1.0, 0.09).expect("outside");
        assert!((mi - Vec3A::new(0.0, -0.16, 0.0)).length() < 1e-5, "{mi}");
        assert!((mj - Vec3A::new(0.0, 0.16, 0.0)).length() < 1e-5, "{mj}");
        // Within the bound, or both ends fixed: nothing.
        assert_eq!(
            limit_projection(Vec3A::X * 2.1, 1.1025, 1.0, 1.0, 0.09),
            None
        );
        assert_eq!(limit_projection(Vec3A::X * 3.0, 2.25, 0.0, 0.0, 0.09), None);
    }

    #[test]
    fn a_torn_sheet_is_pulled_back_within_the_strain_limit() {
        // A free 2 × 2 cm square of two triangles (no capsules), one corner dragged 3 cm away.
        let rig = rig_with(Vec::new());
        let mesh = GarmentMesh::sheet("square", Vec3::ZERO, Vec3::X * 2.0, Vec3::Z * 2.0, 1, 1);
        let settings = SolverSettings::live();
        let mut cloth = Cloth::new(&mesh, &Material::medium(), &settings, &rig).expect("cloth");
        let corner = GarmentMesh::sheet_vertex(1, 1, 1) as usize;
        cloth.x[corner] += Vec3A::new(3.0, 0.0, 3.0);
        cloth.limit_strain(STRAIN_LIMIT_PASSES);
        for e in &cloth.edges {
            let l = cloth.x[e.i as usize].distance(cloth.x[e.j as usize]);
            let strain = (l - e.rest) / e.rest;
            assert!(strain.abs() <= settings.strain_limit + 2e-3, "{strain}");
        }
        // Without the limit the corner stays where it was dragged.
        let mut unlimited = Cloth::new(
            &mesh,
            &Material::medium(),
            &SolverSettings {
                strain_limit: 0.0,
                ..settings.clone()
            },
            &rig,
        )
        .expect("cloth");
        unlimited.x[corner] += Vec3A::new(3.0, 0.0, 3.0);
        let dragged = unlimited.x[corner];
        unlimited.limit_strain(STRAIN_LIMIT_PASSES);
        assert_eq!(unlimited.x[corner], dragged);
    }

    #[test]
    fn chebyshev_weights_start_at_one_and_settle_at_the_optimum() {
        let rho = 0.75f32;
        let mut omega = 1.0;
        let mut weights = Vec::new();
        for k in 0..40 {
            omega = chebyshev_weight(k, rho, omega);
            weights.push(omega);
        }
        assert_eq!(weights[0], 1.0);
        assert!(weights.iter().all(|&w| (1.0..2.0).contains(&w)));
        let optimum = 2.0 / (1.0 + (1.0 - rho * rho).sqrt());
        assert!((weights[39] - optimum).abs() < 1e-5, "{weights:?}");
        let mut x = vec![Vec3A::ONE, Vec3A::ZERO];
        let mut before = vec![Vec3A::ZERO, Vec3A::ZERO];
        over_relax(&mut x, &mut before, 1.5);
        assert_eq!(x, vec![Vec3A::splat(1.5), Vec3A::ZERO]);
        assert_eq!(before, x);
    }

    #[test]
    fn the_belt_offset_is_the_loose_anchors_mean_distance_and_the_belt_takes_it_to_the_slack() {
        // A 2 × 2 cm sheet in the XZ plane, its corner 0 pinned; corners 1 and 3 belted loosely
        // (1 cm of slack) to points 3 cm and 5 cm straight above them, so the offset is
        // (3 + 5) / 2 = 4 cm; a full pull leaves each on its slack, 1 cm.
        let rig = rig_with(vec![]);
        let mut mesh = GarmentMesh::sheet("belt", Vec3::ZERO, Vec3::X * 2.0, Vec3::Z * 2.0, 1, 1);
        pin(&mut mesh, 0, Vec3::ZERO);
        let mut unbelted =
            Cloth::new(&mesh, &Material::medium(), &SolverSettings::live(), &rig).expect("cloth");
        for (vertex, lift) in [(1u32, 3.0f32), (3, 5.0)] {
            let at = mesh.positions[vertex as usize] + Vec3::Y * lift;
            mesh.anchors.push(Anchor {
                vertex,
                bone: 0,
                local: at,
                slack_cm: 1.0,
            });
        }
        let mut cloth =
            Cloth::new(&mesh, &Material::medium(), &SolverSettings::live(), &rig).expect("cloth");
        let still = [0.0f32; 6];
        rig.pose(&still, &mut cloth.pose);
        rig.pose(&still, &mut unbelted.pose);
        assert_eq!(unbelted.quality().belt_offset_cm, 0.0);
        assert!((cloth.quality().belt_offset_cm - 4.0).abs() < 1e-5);
        cloth.solve_loose_anchors(1.0);
        assert!((cloth.quality().belt_offset_cm - 1.0).abs() < 1e-5);
    }

    #[test]
    fn flat_hinges_have_no_bending_and_folded_ones_do() {
        // Two triangles sharing an edge, flat: Σ Kᵢxᵢ = 0; folded by 90°: not.
        let rig = rig_with(vec![]);
        let mut mesh = GarmentMesh::sheet("hinge", Vec3::ZERO, Vec3::X * 2.0, Vec3::Z * 2.0, 1, 1);
        pin(&mut mesh, 0, Vec3::ZERO);
        let cloth =
            Cloth::new(&mesh, &Material::medium(), &SolverSettings::live(), &rig).expect("cloth");
        assert_eq!(cloth.bends.len(), 1);
        let b = cloth.bends[0];
        assert!(b.k.iter().sum::<f32>().abs() < 1e-5);
        let curvature =
            |x: &[Vec3A]| (0..4).fold(Vec3A::ZERO, |acc, m| acc + x[b.v[m] as usize] * b.k[m]);
        assert!(curvature(&cloth.x).length() < 1e-5);
        let mut folded = cloth.x.clone();
        let tip = b.v[3] as usize;
        let hinge = 0.5 * (folded[b.v[0] as usize] + folded[b.v[1] as usize]);
        folded[tip] = hinge + Vec3A::Y * (folded[tip] - hinge).length();
        assert!(curvature(&folded).length() > 0.5);
    }

    #[test]
    fn hammock_sags_like_a_catenary() {
        // A 40 × 40 cm square pinned along two opposite edges 32 cm apart: every row hangs as a
        // catenary of length L = 40 over span D = 32. 2a·sinh(D/2a) = L gives a = 13.53 cm and a
        // sag a·(cosh(D/2a) − 1) = 10.62 cm. Chiffon bends so little (bending length 1.3 cm) that
        // the sag should match within 0.5 cm (the residual stretch of the solver lengthens the
        // rows by well under 1 %, which deepens the sag by under 0.3 cm).
        let (side, span, n) = (40.0f32, 32.0f32, 20usize);
        let rig = rig_with(vec![]);
        let mut mesh = GarmentMesh::sheet(
            "hammock",
            Vec3::new(-side / 2.0, 0.0, -side / 2.0),
            Vec3::X * side,
            Vec3::Z * side,
            n,
            n,
        );
        let squeeze = |p: Vec3| Vec3::new(p.x * span / side, p.y, p.z);
        for r in 0..=n {
            for c in [0, n] {
                let v = GarmentMesh::sheet_vertex(n, r, c);
                let at = squeeze(mesh.positions[v as usize]);
                pin(&mut mesh, v, at);
            }
        }
        let start: Vec<Vec3> = mesh.positions.iter().map(|&p| squeeze(p)).collect();
        let mut cloth =
            Cloth::new(&mesh, &Material::light(), &SolverSettings::live(), &rig).expect("cloth");
        cloth.set_positions(&start);
        settle(&mut cloth, &rig, 240);
        // Expected sag by bisection on u = D/2a: sinh(u)/u = L/D.
        let (mut lo, mut hi) = (1e-3f64, 10.0f64);
        for _ in 0..100 {
            let u = 0.5 * (lo + hi);
            if u.sinh() / u < (side / span) as f64 {
                lo = u;
            } else {
                hi = u;
            }
        }
        let a = span as f64 / (2.0 * lo);
        let expected = (a * (lo.cosh() - 1.0)) as f32;
        assert!((expected - 10.62).abs() < 0.01, "{expected}");
        let middle: f32 = (0..=n)
            .map(|r| cloth.positions()[GarmentMesh::sheet_vertex(n, r, n / 2) as usize].y)
            .sum::<f32>()
            / (n + 1) as f32;
        assert!(
            (-middle - expected).abs() < 0.5,
            "sag {} vs {expected}",
            -middle
        );
        let q = cloth.quality();
        assert!(q.strain_max < 0.02, "{q:?}");
        assert!(q.kinetic_energy < 1.0, "{q:?}");
    }

    #[test]
    fn curtain_pinned_at_two_corners_hangs_its_full_length_with_bounded_strain() {
        // A 40 × 40 cm cotton-jersey square pinned at its two top corners 40 cm apart, starting
        // horizontal: it swings down and settles hanging, each free edge straight below its pin,
        // so the bottom corners end 40 cm below the pins (the tethers allow no more; gravity no
        // less than a few per cent), and no edge stretches much.
        let (side, n) = (40.0f32, 20usize);
        let rig = rig_with(vec![]);
        let mut mesh = GarmentMesh::sheet(
            "curtain",
            Vec3::new(-side / 2.0, 0.0, 0.0),
            Vec3::X * side,
            Vec3::Z * side,
            n,
            n,
        );
        for c in [0, n] {
            let v = GarmentMesh::sheet_vertex(n, 0, c);
            let at = mesh.positions[v as usize];
            pin(&mut mesh, v, at);
        }
        let mut cloth =
            Cloth::new(&mesh, &Material::medium(), &SolverSettings::live(), &rig).expect("cloth");
        let mut worst = FrameQuality::default();
        let still = [0.0f32; 6];
        for k in 0..150 {
            cloth.step_frame(&rig, &still, &still);
            if k >= 60 {
                let q = cloth.quality();
                worst.strain_p95 = worst.strain_p95.max(q.strain_p95);
                worst.strain_max = worst.strain_max.max(q.strain_max);
            }
        }
        for c in [0, n] {
            let corner = cloth.positions()[GarmentMesh::sheet_vertex(n, n, c) as usize];
            assert!(
                corner.y < -0.97 * side && corner.y > -side * 1.001,
                "corner {c}: {corner}"
            );
        }
        assert!(worst.strain_p95 < 0.02, "{worst:?}");
        assert!(worst.strain_max < 0.10, "{worst:?}");
    }

    #[test]
    fn vertices_inside_a_capsule_are_pushed_out() {
        // A capsule of radius 5 along X through the origin; a small pinned sheet whose free corner
        // starts 2 cm from the axis (3 cm inside).
        let rig = rig_with(vec![bar(
            Vec3::new(-20.0, 0.0, 0.0),
            Vec3::new(20.0, 0.0, 0.0),
            5.0,
        )]);
        let mut mesh = GarmentMesh::sheet(
            "patch",
            Vec3::new(-2.0, 10.0, 0.0),
            Vec3::X * 4.0,
            Vec3::new(0.0, -8.0, 0.0),
            2,
            4,
        );
        for c in 0..=2 {
            let v = GarmentMesh::sheet_vertex(2, 0, c);
            let at = mesh.positions[v as usize];
            pin(&mut mesh, v, at);
        }
        let settings = SolverSettings::live();
        let mut cloth = Cloth::new(&mesh, &Material::medium(), &settings, &rig).expect("cloth");
        let inside = cloth.positions()[GarmentMesh::sheet_vertex(2, 4, 1) as usize];
        assert!((inside - Vec3A::new(0.0, 2.0, 0.0)).length() < 1e-5);
        assert!(
            Capsule::new(
                Vec3::new(-20.0, 0.0, 0.0),
                Vec3::new(20.0, 0.0, 0.0),
                5.0,
                5.0
            )
            .signed_distance(inside.into())
                < -2.9
        );
        cloth.step_frame(&rig, &[0.0; 6], &[0.0; 6]);
        let q = cloth.quality();
        assert_eq!(q.penetration_cm, 0.0, "{q:?}");
        for p in cloth.positions() {
            let d = cloth.pose().capsules[0].signed_distance((*p).into());
            assert!(d > settings.collision_offset - 0.05, "{p} at {d}");
        }
    }

    /// A 40 × 40 cm sheet of 20 × 20 cells hanging from its pinned top edge in the plane z = 0, and
    /// a rig whose one capsule, a horizontal bar of radius 4 (a forearm) 25 cm down, moves with the
    /// "mover" joint's z position (channel 5); and the sheet's cells per side.
    fn sheet_before_a_bar() -> (BodyRig, GarmentMesh, usize) {
        let (side, n) = (40.0f32, 20usize);
        let rig = rig_with(vec![bar(
            Vec3::new(-40.0, -25.0, 0.0),
            Vec3::new(40.0, -25.0, 0.0),
            4.0,
        )]);
        let mut mesh = GarmentMesh::sheet(
            "sheet",
            Vec3::new(-side / 2.0, 0.0, 0.0),
            Vec3::X * side,
            Vec3::new(0.0, -side, 0.0),
            n,
            n,
        );
        for c in 0..=n {
            let v = GarmentMesh::sheet_vertex(n, 0, c);
            let at = mesh.positions[v as usize];
            pin(&mut mesh, v, at);
        }
        (rig, mesh, n)
    }

    #[test]
    fn a_fast_capsule_does_not_tunnel_through_a_hanging_sheet() {
        // A 40 × 40 cm sheet hangs from its top edge in the plane z = 0. A horizontal capsule of
        // radius 4 (a forearm) 25 cm down sweeps from 8 cm behind it to 12 cm in front at
        // 300 cm/s (3 m/s: 10 cm per 30 Hz frame, 0.6 cm per substep). After every frame, each
        // column of the sheet, closed by a loop far in front, must not wind around the capsule's
        // axis: the capsule stays behind the cloth.
        let (rig, mesh, n) = sheet_before_a_bar();
        let mut cloth =
            Cloth::new(&mesh, &Material::medium(), &SolverSettings::live(), &rig).expect("cloth");
        cloth.check_tunnelling(true);
        let frame = |z: f32| [0.0, 0.0, 0.0, 0.0, 0.0, z];
        let mut z = -8.0f32;
        settle(&mut cloth, &rig, 0);
        for _ in 0..10 {
            cloth.step_frame(&rig, &frame(z), &frame(z));
        }
        let winding = |cloth: &Cloth, column: usize, axis: (f64, f64)| {
            let mut polygon: Vec<(f64, f64)> = (0..=n)
                .map(|r| {
                    let p = cloth.positions()[GarmentMesh::sheet_vertex(n, r, column) as usize];
                    (p.z as f64, p.y as f64)
                })
                .collect();
            let (top, bottom) = (polygon[0], polygon[n]);
            polygon.extend([(1e3, bottom.1), (1e3, 1e3), (top.0, 1e3)]);
            let mut turn = 0.0f64;
            for k in 0..polygon.len() {
                let (a, b) = (polygon[k], polygon[(k + 1) % polygon.len()]);
                let (ax, ay, bx, by) = (a.0 - axis.0, a.1 - axis.1, b.0 - axis.0, b.1 - axis.1);
                turn += (ax * by - ay * bx).atan2(ax * bx + ay * by);
            }
            (turn / std::f64::consts::TAU).round() as i32
        };
        let mut pushed = false;
        for step in 0..8 {
            let next = (z + 10.0).min(12.0);
            cloth.step_frame(&rig, &frame(z), &frame(next));
            z = next;
            for column in 0..=n {
                assert_eq!(
                    winding(&cloth, column, (z as f64, -25.0)),
                    0,
                    "step {step} column {column}"
                );
            }
            let q = cloth.quality();
            assert!(q.penetration_cm < 0.2, "step {step}: {q:?}");
            assert_eq!(q.tunnelled, Some(0), "step {step}");
            pushed |= cloth.positions().iter().any(|p| p.z > 10.0);
        }
        assert!(pushed, "the capsule should have pushed the sheet forward");
    }

    #[test]
    fn a_capsule_too_fast_for_one_substep_is_counted_as_tunnelling() {
        // The same sheet and bar, one substep a frame, and the bar crossing the sheet's plane
        // from 8 cm behind to 22 cm in front in one frame (9 m/s): nothing meets the sheet between
        // the two collision tests, so the bar comes out in front and the sheet hangs where it
        // was. Seen from the bar, the sheet's two rows beside its axis (1 cm from it, y = −24 and
        // −26) moved through it: 2 × 21 vertices.
        let (rig, mesh, _) = sheet_before_a_bar();
        let settings = SolverSettings {
            substeps: 1,
            ..SolverSettings::live()
        };
        let mut cloth = Cloth::new(&mesh, &Material::medium(), &settings, &rig).expect("cloth");
        let frame = |z: f32| [0.0, 0.0, 0.0, 0.0, 0.0, z];
        cloth.step_frame(&rig, &frame(-8.0), &frame(-8.0));
        assert_eq!(cloth.quality().tunnelled, None, "not checked yet");
        cloth.check_tunnelling(true);
        cloth.step_frame(&rig, &frame(-8.0), &frame(-8.0));
        assert_eq!(cloth.quality().tunnelled, Some(0));
        cloth.step_frame(&rig, &frame(-8.0), &frame(22.0));
        let tunnelled = cloth.quality().tunnelled.expect("checked");
        assert!(
            cloth.positions().iter().all(|p| p.z < 5.0),
            "the sheet should have stayed behind"
        );
        assert_eq!(tunnelled, 42);
        // The next frame starts a new count.
        cloth.step_frame(&rig, &frame(22.0), &frame(22.0));
        assert_eq!(cloth.quality().tunnelled, Some(0));
    }

    #[test]
    fn a_garment_on_a_still_body_comes_to_rest() {
        let (rig, frames) = walk();
        let mesh =
            GarmentMesh::generate(GarmentKind::Skirt, &rig, &GarmentParams::live()).expect("skirt");
        let mut cloth =
            Cloth::new(&mesh, &Material::medium(), &SolverSettings::live(), &rig).expect("cloth");
        let pose = frames.frame(0);
        cloth.dress(&rig, pose);
        let free_mass: f32 = (cloth.mass.iter().zip(&cloth.inv_mass))
            .filter(|(_, &w)| w > 0.0)
            .map(|(m, _)| m)
            .sum();
        let mut energies = Vec::new();
        for _ in 0..300 {
            cloth.step_frame(&rig, pose, pose);
            energies.push(cloth.kinetic_energy());
        }
        // Air drag, damping and friction take the swing out of it: after ten seconds less than
        // 10 % of the energy the settling started with is left, and the cloth's root-mean-square
        // speed is below 1 cm/s. The more substeps, the less the solver damps by itself, and the
        // longer the skirt's slow pendulum sway takes to die out: with 16 substeps about 10 % was
        // left after three seconds; with 32, 3.8 % after five and 0.8 % after ten; with 40 (and
        // Chebyshev-accelerated sweeps), 12 % after five and 6.8 % (37 erg, 0.86 cm/s for the
        // 100 g skirt flaring by 12°) after ten. The skirt flaring by 24° (166 g): 1.25 % and
        // 0.59 cm/s after ten seconds, 0.43–0.46 cm/s from fifteen to thirty (a 30° flare, 198 g,
        // swayed longer: 0.93 cm/s after ten, 0.6–0.7 from twenty on).
        let mean = |e: &[f32]| e.iter().sum::<f32>() / e.len() as f32;
        let (first, last) = (
            mean(&energies[..10]),
            mean(&energies[energies.len() - 10..]),
        );
        let rms_speed = (2.0 * last / free_mass).sqrt();
        assert!(
            last < 0.1 * first && rms_speed < 1.0,
            "{rms_speed} cm/s, {free_mass} g: {energies:?}"
        );
    }

    #[test]
    fn the_same_inputs_give_bit_identical_output() {
        let (rig, frames) = walk();
        let mesh = GarmentMesh::generate(GarmentKind::TShirt, &rig, &GarmentParams::live())
            .expect("tshirt");
        let run = || {
            let mut settings = SolverSettings::live();
            settings.blend_frames = 5;
            settings.settle_frames = 2;
            let mut cloth = Cloth::new(&mesh, &Material::medium(), &settings, &rig).expect("cloth");
            cloth.dress(&rig, frames.frame(0));
            for k in 1..6 {
                cloth.step_frame(&rig, frames.frame(k - 1), frames.frame(k));
            }
            cloth
                .positions()
                .iter()
                .flat_map(|p| p.to_array().map(f32::to_bits))
                .collect::<Vec<u32>>()
        };
        assert_eq!(run(), run());
    }

    #[test]
    fn dressed_garments_are_outside_the_body() {
        let (rig, frames) = walk();
        for kind in GarmentKind::ALL {
            let mesh = GarmentMesh::generate(kind, &rig, &GarmentParams::live()).expect("garment");
            let mut cloth = Cloth::new(&mesh, &Material::medium(), &SolverSettings::live(), &rig)
                .expect("cloth");
            cloth.dress(&rig, frames.frame(0));
            let q = cloth.quality();
            // No simulated vertex inside a capsule it collides with (0.2 mm of numerical
            // tolerance), nor an anchored one.
            assert!(q.penetration_cm < 0.02, "{}: {q:?}", mesh.name);
            assert!(q.anchor_penetration_cm < 0.02, "{}: {q:?}", mesh.name);
            assert!(q.strain_max < 0.5, "{}: {q:?}", mesh.name);
            // And it keeps to that over a few walking frames.
            for k in 1..frames.frame_count() {
                cloth.step_frame(&rig, frames.frame(k - 1), frames.frame(k));
                let q = cloth.quality();
                assert!(q.penetration_cm < 0.2, "{} frame {k}: {q:?}", mesh.name);
            }
        }
    }

    #[test]
    fn the_arms_stay_in_the_sleeves_when_they_are_lowered() {
        // Dressing blends from the T-pose to the walk's first frame, arms hanging: before the
        // cuffs, the arms came out through the sleeves' undersides and most sleeve-end vertices
        // were 5–16 cm off the arm within a few frames.
        let (rig, frames) = walk();
        let mesh = GarmentMesh::generate(GarmentKind::TShirt, &rig, &GarmentParams::live())
            .expect("tshirt");
        assert!(!mesh.cuffs.is_empty());
        let mut cloth =
            Cloth::new(&mesh, &Material::medium(), &SolverSettings::live(), &rig).expect("cloth");
        cloth.dress(&rig, frames.frame(0));
        for k in 1..frames.frame_count() {
            cloth.step_frame(&rig, frames.frame(k - 1), frames.frame(k));
        }
        let worst = cloth.quality().cuff_gap_cm;
        // The later constraints of a substep may move a cuff vertex a little past its reach.
        assert!(worst < SLEEVE_CUFF_REACH_CM + 1.0, "{worst} cm");
    }

    #[test]
    fn the_sleeves_do_not_ride_up_to_the_shoulders() {
        // Lowering the arms from the T-pose draws the sleeves up towards the shoulders (a shirt
        // cut in the T-pose has too little cloth over a lowered arm's shoulder). After dressing
        // and twelve frames of the walk the sleeve ends sit 6.7 cm up the arm from their place
        // at rest when free, 6.4 cm when held beyond `cuff_slide_cm`; on the body before the
        // second session of 2026-12-07, whose lowered upper arms lay inside the chest and drew
        // the sleeves further up, 10.6 and 8.8 cm. The hold may not make it worse, and the
        // sleeve ends stay well short of the shoulder.
        let (rig, frames) = walk();
        let mesh = GarmentMesh::generate(GarmentKind::TShirt, &rig, &GarmentParams::live())
            .expect("tshirt");
        let slide_after_walk = |settings: SolverSettings| {
            let mut cloth = Cloth::new(&mesh, &Material::medium(), &settings, &rig).expect("cloth");
            cloth.dress(&rig, frames.frame(0));
            for k in 1..frames.frame_count() {
                cloth.step_frame(&rig, frames.frame(k - 1), frames.frame(k));
            }
            cloth.quality()
        };
        let held = slide_after_walk(SolverSettings::live());
        let free = slide_after_walk(SolverSettings {
            cuff_slide_cm: f32::INFINITY,
            ..SolverSettings::live()
        });
        assert!(
            held.cuff_slide_cm <= free.cuff_slide_cm + 0.1,
            "held {held:?}, free {free:?}"
        );
        assert!(held.cuff_slide_cm < 8.0, "{held:?}");
        assert!(held.strain_max < 0.10, "{held:?}");
    }

    #[test]
    fn an_arm_buried_in_the_trunk_lets_the_cloth_beside_it_go_gradually() {
        // On the trunk's collision surface the trunk wins (any depth), 1 cm off it half of the
        // ramp, from 2 cm off nothing: no jump between neighbouring vertices.
        assert_eq!(buried_arm_allowance(0.0), ARM_RAMP_CM);
        assert_eq!(buried_arm_allowance(1.0), ARM_RAMP_CM / 2.0);
        assert_eq!(buried_arm_allowance(BURIED_ARM_GAP_CM), 0.0);
        assert_eq!(buried_arm_allowance(10.0), 0.0);
        assert_eq!(buried_arm_allowance(f32::INFINITY), 0.0);
        // Every 0.5 mm off the trunk the allowance falls by the same step, never more: 10 cm over
        // 2 cm is 2.5 mm per 0.5 mm.
        let slope = ARM_RAMP_CM / BURIED_ARM_GAP_CM;
        for k in 0..40 {
            let gap = k as f32 * 0.05;
            let step = buried_arm_allowance(gap) - buried_arm_allowance(gap + 0.05);
            assert!((0.0..=slope * 0.05 + 1e-3).contains(&step), "{gap}: {step}");
        }
    }

    /// A clip of `tests/data/` or the quick start's, and a rig of its own skeleton at girth 1 (what
    /// `suitcap drape` wears without masks).
    fn clip_and_its_rig(path: &str) -> (Motion, BodyRig) {
        clip_and_a_rig_of_size(path, crate::body_size::BodySize::TEMPLATE)
    }

    /// A clip in the repository and a rig of `size` on its skeleton.
    fn clip_and_a_rig_of_size(path: &str, size: crate::body_size::BodySize) -> (Motion, BodyRig) {
        let clip = Motion::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join(path)).expect("clip");
        let (subject, skeleton) = size.subject(&clip.skeleton);
        let body = Body::new(&subject, &skeleton).expect("body");
        (clip, BodyRig::new(skeleton, body, DEFAULT_MARGIN_CM))
    }

    /// `mesh` in the medium fabric at the live settings, dressed and run over `clip`.
    fn run_live(mesh: &GarmentMesh, rig: &BodyRig, clip: &Motion) -> QualitySummary {
        let mut cloth =
            Cloth::new(mesh, &Material::medium(), &SolverSettings::live(), rig).expect("cloth");
        run_motion(rig, &mut cloth, clip, |_, _, _| {}).expect("run")
    }

    #[test]
    fn a_fine_sleeve_pressed_between_arm_and_chest_does_not_tear_while_dressing() {
        // The quick start's kick starts crouched, arms low and sunk into the chest. Dressing the
        // quality mode's 1 cm T-shirt on it (as `suitcap drape` does without masks) once left a
        // sleeve vertex on the trunk inside the arm and its neighbour, 3 mm off the trunk, pushed
        // out to the arm's far side: that first frame's largest edge strain was 244 %.
        let (clip, rig) = clip_and_its_rig("suits/default/demo/640x480/motion.bvh");
        let mesh = GarmentMesh::generate(GarmentKind::TShirt, &rig, &GarmentParams::quality())
            .expect("tshirt");
        let mut cloth = Cloth::new(&mesh, &Material::medium(), &SolverSettings::quality(), &rig)
            .expect("cloth");
        cloth.dress(&rig, clip.frame(0));
        let q = cloth.quality();
        assert!(q.strain_max < 0.10, "{} %", 100.0 * q.strain_max);
        assert!(q.penetration_cm < 0.2, "{} cm", q.penetration_cm);
    }

    #[test]
    fn the_demo_clips_live_t_shirt_keeps_its_strain_within_the_targets_in_every_frame() {
        // The quick start's kick sized as `suitcap drape --masks` sizes it from the segmenter's
        // masks (1.017 × the clip's skeleton, girth 1.19; 2,184 vertices): with the sleeve's ramp
        // into the arm at 6 cm one frame's 95th-percentile strain was 2.74 % in `suitcap drape`
        // (2.15 % here), over the issue's 2 %; at 10 cm ([`ARM_RAMP_CM`]) it is about 1.2 %.
        let size = crate::body_size::BodySize {
            height_scale: 1.017,
            girth: 1.19,
            ..crate::body_size::BodySize::TEMPLATE
        };
        let (clip, rig) = clip_and_a_rig_of_size("suits/default/demo/640x480/motion.bvh", size);
        let mesh = GarmentMesh::generate(GarmentKind::TShirt, &rig, &GarmentParams::live())
            .expect("tshirt");
        let summary = run_live(&mesh, &rig, &clip);
        let percent = |v: f32| 100.0 * v;
        assert!(
            summary.strain_p95_worst <= 0.02,
            "worst frame's 95th percentile {} %",
            percent(summary.strain_p95_worst)
        );
        assert!(
            summary.strain_max < 0.10,
            "{} %",
            percent(summary.strain_max)
        );
        assert!(
            summary.penetration_max_cm < 0.2,
            "{} cm",
            summary.penetration_max_cm
        );
    }

    #[test]
    fn a_sleeve_stays_whole_when_a_raised_arm_comes_down_against_the_chest() {
        // CMU 05_12's dance (arms high, torso turning) as the generator rendered it for subject
        // dana: the live T-shirt tore at the armpit (largest strain 206 %; 135 % and 271 % at
        // 2,000 and 4,000 vertices) before arm cloth near the trunk was let into an arm sunk into
        // it ([`buried_arm_allowance`]).
        let (clip, rig) = clip_and_its_rig("tests/data/mocap/synth_05_12_dance_dana.bvh");
        let mesh = GarmentMesh::generate(GarmentKind::TShirt, &rig, &GarmentParams::live())
            .expect("tshirt");
        let summary = run_live(&mesh, &rig, &clip);
        assert!(
            summary.strain_max < 0.10,
            "{} %",
            100.0 * summary.strain_max
        );
    }

    #[test]
    fn an_arm_does_not_undo_the_strain_limit_at_an_armhole() {
        // CMU 13_39's jump as the generator rendered it for subject chidi: the 4,000-vertex dress
        // kept armhole edges at 13 % in one frame while the strain limit's every round ended with
        // the arms pushing the armhole's ramp cloth out again; the last round now meets the trunk
        // only.
        let (clip, rig) = clip_and_its_rig("tests/data/mocap/synth_13_39_jump_chidi.bvh");
        let (mesh, _) =
            GarmentMesh::with_vertex_count(GarmentKind::Dress, &rig, 4000, 2.5).expect("dress");
        let summary = run_live(&mesh, &rig, &clip);
        assert!(
            summary.strain_max < 0.10,
            "{} %",
            100.0 * summary.strain_max
        );
        assert!(
            summary.penetration_max_cm < 0.2,
            "{} cm",
            summary.penetration_max_cm
        );
    }

    /// A live skirt dressed quickly (4 frames' blend, 2 settling) on the walk's first frame, with
    /// the rig and that frame.
    fn skirt_dressed_on_the_walk() -> (BodyRig, Cloth, Vec<f32>) {
        let (rig, frames) = walk();
        let mesh =
            GarmentMesh::generate(GarmentKind::Skirt, &rig, &GarmentParams::live()).expect("skirt");
        let mut settings = SolverSettings::live();
        settings.blend_frames = 4;
        settings.settle_frames = 2;
        let mut cloth = Cloth::new(&mesh, &Material::medium(), &settings, &rig).expect("cloth");
        let first = frames.frame(0).to_vec();
        cloth.dress(&rig, &first);
        (rig, cloth, first)
    }

    #[test]
    fn a_root_jump_teleports_the_cloth_and_a_pose_jump_dresses_again() {
        let (rig, mut cloth, a) = skirt_dressed_on_the_walk();
        let before = cloth.positions()[0];
        // The root (Xposition is channel 0) jumps 1 m along X.
        let mut b = a.clone();
        b[0] += 100.0;
        let info = cloth.step_frame(&rig, &a, &b);
        assert!(info.jumped && !info.redressed);
        let moved = cloth.positions()[0] - before;
        assert!(
            (moved.x - 100.0).abs() < 3.0 && moved.length() < 104.0,
            "{moved}"
        );
        assert!(cloth.quality().max_speed < 200.0);
        // From the walk to the T-pose at once: every limb jumps.
        let mut t_pose = rig.rest_frame();
        t_pose[..3].copy_from_slice(&b[..3]);
        let info = cloth.step_frame(&rig, &b, &t_pose);
        assert!(info.redressed);
        assert!(cloth.quality().penetration_cm < 0.02);
        // Other frame intervals run as many fixed substeps as fit.
        let h = cloth.settings.substep_seconds();
        assert_eq!(
            cloth.advance(&rig, &t_pose, &t_pose, 0.04).substeps,
            (0.04 / h).round() as u32
        );
        assert_eq!(cloth.advance(&rig, &t_pose, &t_pose, f32::NAN).substeps, 1);
    }

    /// The cloth's positions seen from its body's root.
    fn in_root_frame(cloth: &Cloth) -> Vec<Vec3A> {
        let root = cloth.pose().bones[0].inverse();
        cloth
            .positions()
            .iter()
            .map(|&p| root.transform_point3a(p))
            .collect()
    }

    /// The farthest any vertex of `cloth` moved, seen from its body's root, since it was at
    /// `before` ([`in_root_frame`]).
    fn farthest_from(before: &[Vec3A], cloth: &Cloth) -> f32 {
        before
            .iter()
            .zip(&in_root_frame(cloth))
            .map(|(p, q)| p.distance(*q))
            .fold(0.0f32, f32::max)
    }

    #[test]
    fn below_full_inertia_the_garment_is_carried_partly_with_its_bone() {
        let (rig, cloth, a) = skirt_dressed_on_the_walk();
        // The skirt hangs on the hip, the root.
        assert_eq!(cloth.carry_bone, 0);
        let before = in_root_frame(&cloth);
        // The farthest any vertex moved, seen from the root, over one frame to `next`.
        let moved = |next: &[f32], inertia: Inertia| {
            let mut c = cloth.clone();
            c.settings.inertia = inertia;
            assert!(!c.step_frame(&rig, &a, next).jumped);
            farthest_from(&before, &c)
        };
        // The skirt still settles a little on a body that does not move.
        let settling = moved(&a, Inertia::FULL);
        let angular = |angular| Inertia {
            linear: 1.0,
            angular,
        };
        let linear = |linear| Inertia {
            linear,
            angular: 1.0,
        };
        // At full inertia the hem lags more than 10 cm behind the hips, at half the share about
        // half as far, and carried fully it moves on the body as on a body that stood still.
        let lags_by_its_share = |next: &[f32], share: &dyn Fn(f32) -> Inertia| {
            let (full, half, none) = (
                moved(next, Inertia::FULL),
                moved(next, share(0.5)),
                moved(next, share(0.0)),
            );
            assert!(full > 10.0, "{full} cm");
            assert!(
                half < 0.6 * full && half > 0.4 * full,
                "{half} of {full} cm"
            );
            assert!(none < settling + 0.2, "{none} cm, {settling} cm settling");
            full
        };
        // 30° in a frame about the vertical (channel 4): fast, but not a jump (19.1, 9.4 and
        // 2.7 cm). The linear share does not matter to a turn about the carrying joint.
        let mut turned = a.clone();
        turned[4] += 30.0;
        let full = lags_by_its_share(&turned, &angular);
        let travel_free = moved(&turned, linear(0.0));
        assert!(
            (travel_free - full).abs() < 0.01,
            "{travel_free} against {full} cm"
        );
        // 30 cm sideways in a frame (Xposition, channel 0; a jump is 50).
        let mut moved_aside = a.clone();
        moved_aside[0] += 30.0;
        lags_by_its_share(&moved_aside, &linear);
    }

    #[test]
    fn a_garment_is_carried_by_the_bone_most_of_its_rigid_anchors_hang_on() {
        let anchor = |bone: usize, slack_cm: f32| Anchor {
            vertex: 0,
            bone,
            local: Vec3::ZERO,
            slack_cm,
        };
        // Two rigid on bone 3, three loose on bone 5: bone 3.
        let mixed = [
            anchor(3, 0.0),
            anchor(5, 2.0),
            anchor(3, 0.0),
            anchor(5, 2.0),
            anchor(5, 2.0),
        ];
        assert_eq!(carry_bone(&mixed), 3);
        // Only loose ones: theirs; a tie: the lower bone; none: the root.
        assert_eq!(
            carry_bone(&[anchor(5, 2.0), anchor(2, 1.0), anchor(5, 1.0)]),
            5
        );
        assert_eq!(carry_bone(&[anchor(4, 0.0), anchor(2, 0.0)]), 2);
        assert_eq!(carry_bone(&[]), 0);
        // The T-shirt hangs on the chest.
        let (rig, _) = walk();
        let mesh = GarmentMesh::generate(GarmentKind::TShirt, &rig, &GarmentParams::live())
            .expect("tshirt");
        let cloth =
            Cloth::new(&mesh, &Material::medium(), &SolverSettings::live(), &rig).expect("cloth");
        assert_eq!(rig.skeleton().joints()[cloth.carry_bone].name, "chest");
    }

    #[test]
    fn a_root_turn_too_fast_for_a_person_turns_the_cloth_with_the_body() {
        let (rig, mut cloth, a) = skirt_dressed_on_the_walk();
        let before = in_root_frame(&cloth);
        // CMU's root channels are X, Y, Z position then Z, Y, X rotation: channel 4 turns the body
        // about the vertical. 20° in a frame is a fast turn a dancer makes; 90° is a glitch.
        let yaw = |degrees: f32| {
            let mut frame = a.clone();
            frame[4] += degrees;
            frame
        };
        assert!((rig.root_turn_degrees(&a, &yaw(90.0)) - 90.0).abs() < 0.01);
        let mut turned = cloth.clone();
        assert!(!cloth.clone().step_frame(&rig, &a, &yaw(20.0)).jumped);
        let info = cloth.step_frame(&rig, &a, &yaw(90.0));
        assert!(info.jumped && !info.redressed);
        // Seen from the root the garment hardly moved: it turned with the body.
        let moved = farthest_from(&before, &cloth);
        assert!(moved < 2.0, "{moved} cm");
        // Without the jump the same turn whips the hem around the legs.
        turned.settings.jump_turn_degrees = 180.0;
        assert!(!turned.step_frame(&rig, &a, &yaw(90.0)).jumped);
        let whipped = farthest_from(&before, &turned);
        assert!(whipped > 20.0, "{whipped} cm");
    }

    #[test]
    fn bad_inputs_are_errors_not_panics() {
        let rig = rig_with(vec![]);
        let mut mesh = GarmentMesh::sheet("s", Vec3::ZERO, Vec3::X, Vec3::Z, 1, 1);
        mesh.anchors.push(Anchor {
            vertex: 0,
            bone: 7,
            local: Vec3::ZERO,
            slack_cm: 0.0,
        });
        assert!(matches!(
            Cloth::new(&mesh, &Material::medium(), &SolverSettings::live(), &rig),
            Err(ClothError::AnchorBone { bone: 7, .. })
        ));
        mesh.anchors.clear();
        // A cuff around a bone without a capsule (the rig has none at all).
        mesh.cuffs.push(Cuff {
            vertex: 0,
            bone: 0,
            reach_cm: 5.0,
        });
        assert!(matches!(
            Cloth::new(&mesh, &Material::medium(), &SolverSettings::live(), &rig),
            Err(ClothError::CuffBone { index: 0, .. })
        ));
        mesh.cuffs.clear();
        let settings = SolverSettings {
            substeps: 0,
            ..SolverSettings::live()
        };
        assert!(Cloth::new(&mesh, &Material::medium(), &settings, &rig).is_err());
        for strain_limit in [-0.1, 1.0, f32::NAN] {
            let settings = SolverSettings {
                strain_limit,
                ..SolverSettings::live()
            };
            assert!(matches!(
                Cloth::new(&mesh, &Material::medium(), &settings, &rig),
                Err(ClothError::Setting {
                    name: "strain_limit",
                    ..
                })
            ));
        }
        for linear in [-0.5, 1.5, f32::NAN] {
            let settings = SolverSettings {
                inertia: Inertia {
                    linear,
                    angular: 0.5,
                },
                ..SolverSettings::live()
            };
            assert!(matches!(
                Cloth::new(&mesh, &Material::medium(), &settings, &rig),
                Err(ClothError::Setting {
                    name: "inertia.linear",
                    ..
                })
            ));
        }
        mesh.triangles.push([0, 1, 9]);
        assert!(Cloth::new(&mesh, &Material::medium(), &SolverSettings::live(), &rig).is_err());
        // Frames of the wrong length are padded with zeros, not a panic.
        mesh.triangles.pop();
        let mut cloth =
            Cloth::new(&mesh, &Material::medium(), &SolverSettings::live(), &rig).expect("cloth");
        cloth.step_frame(&rig, &[], &[1.0; 40]);
        assert!(cloth.positions().iter().all(|p| p.is_finite()));
    }
}
