//! The per-frame segmenter: learned tables → grid graph → min-cut → clean-up → full-resolution mask.
//!
//! For every frame [`Segmenter::segment`]:
//! 1. box-downscales the frame by the tables' factor (for frames taller than the training's, by a
//!    larger one that keeps the cut's grid near the trained one: [`SegmenterTables::cut_factor`])
//!    and computes colour bins and gradients;
//! 2. builds the graph: unaries `σ_C·C + σ_G·G + σ_M·M + σ_T·T` per pixel (the motion and temporal terms
//!    use the segmenter's own masks of the previous one and two frames; the first frame uses the label
//!    prior instead ([`SegmenterOptions::label_prior_share`]), and is segmented again until its
//!    mask settles, each pass learning the room from the one before
//!    ([`SegmenterOptions::first_frame_passes`]), and from scratch without the prior if its suit
//!    left out most of what looks like the suit ([`FIRST_FRAME_MAX_LEFT_OUT`]); the second uses
//!    the motion term and that prior; a later frame found empty while most of what looks like
//!    the suit was left out is segmented again without the history,
//!    [`SegmenterOptions::lost_person_retry`]),
//!    pairwise weights from the neighbourhood table on the four
//!    axial edges (a label-pair energy A, B, D becomes an edge weight (2B − A − D)/2; the (D − A)/2 it
//!    would add to both nodes' person cost is left out, see [`Segmenter::new`]). The cut looks for the
//!    suit: its colour table is trained on the suit part of the masks only;
//! 3. cuts it with [`GridMaxFlow`] (the search buffers are reused from frame to frame);
//!    the background's colour likelihood mixes the trained table with a background colour histogram
//!    learned online from this stream's own confident background pixels (more than
//!    [`SegmenterOptions::adapt_margin`] pixels from the person, decaying by
//!    [`SegmenterOptions::adapt_rate`] per frame), as bilayer segmenters do: the 20 training frames
//!    cannot show the room the suit will be used in, the stream itself does after one frame; and
//!    a pixel that shows what it showed while the person was elsewhere (the room learned pixel by
//!    pixel from those pixels, within the part band only those of no part's colour,
//!    [`room`](super::room),
//!    [`SegmenterOptions::room`]) counts as likelier background;
//! 4. keeps the connected region that carries the most suit cloth next to markers, with the pieces of
//!    suit near it that an arm or an object in front cut off ([`SegmenterOptions::piece_reach`]), fills
//!    small holes ([`cleanup`](super::cleanup)); removes the pieces that are not the suit's cloth
//!    and larger than a few of its markers (on the suit everything that is not cloth is a 4 cm
//!    marker with cloth around it, so such a piece is an orange, fur or skin-coloured background
//!    that the smoothness pulled in, often between the legs:
//!    [`SegmenterOptions::off_cloth_max_markers`]) and the cloth farther from every marker than
//!    the suit's can be (a cloth-coloured object touching the person:
//!    [`SegmenterOptions::cloth_reach_cm`]), and reports what that changed; then attaches
//!    the head, hands and shoes: pixels of a band around the suit ([`SegmenterOptions::part_reach`])
//!    connected to it whose colour is likelier under the learned part table than under the (online)
//!    background and that do not show the room learned pixel by pixel, in pieces shaped like a
//!    head, a hand or a shoe ([`SegmenterOptions::part_max_share`],
//!    [`SegmenterOptions::part_max_top_share`], [`SegmenterOptions::part_max_round_share`],
//!    [`SegmenterOptions::part_min_depth`]; a piece beside the suit, a hand, may not hang on by a
//!    pixel or two of contact: [`SegmenterOptions::part_max_side_depth`]); a head that the band
//!    joined to too much background is looked for again within a narrower band
//!    ([`SegmenterOptions::part_reach_narrow`]); where the previous frame attached a head or
//!    shoes, the part test leans towards the part
//!    ([`SegmenterOptions::part_memory`]), so a head over a room of its colour is not lost every
//!    other frame; where less than a head's area was found above the suit, or less than the
//!    shoes' below it, a last look floods only the ellipses where they are expected (above the
//!    suit's top rows, below each leg's end), the part test leaning towards the part there
//!    ([`SegmenterOptions::part_look`]), and likewise where a hand is expected beyond the end of
//!    a suit's arm and less than a quarter of it was found ([`hands`](super::hands),
//!    [`SegmenterOptions::hand_look`]); and the part test's colours mix
//!    the trained table (every training subject's skin and shoes) with this person's own,
//!    learned from the heads and shoes attached in the frames before
//!    ([`SegmenterOptions::part_colour_share`]), the hands' test within the suit's rows more than
//!    the head's and shoes' ([`SegmenterOptions::hand_colour_share`]);
//! 5. upsamples to the frame's size and decides the pixels of the boundary band at full resolution from
//!    their own colour and the upsampled cut; then moves the outline onto the frame's colour edge
//!    in up to four passes, a marker-coloured outline pixel staying person unless the room beside
//!    it has a marker's hue too ([`snap`](super::snap), [`SegmenterOptions::snap`]); and decides
//!    each outline pixel once more by how much of the person's colour beside it the pixel holds
//!    ([`SegmenterOptions::unmix`]); last fills the enclosed holes of up to a few markers' area
//!    that are mostly of the suit's colours, markers the cut lost to a room of their colour
//!    ([`SegmenterOptions::suit_hole_markers`]; all three counted in the refinement's time).
//!
//! A frame with nobody in it gives an empty mask. The mask goes to marker detection and the descriptors;
//! the box of the suit alone ([`Segmentation::suit_box`]) to the body-size measurement.

use std::time::Instant;

use image::RgbImage;

use super::cleanup::{
    add_parts, attach_parts, attach_parts_narrowing, clean, distance_near, expected_head,
    expected_shoes, fill_suit_holes, part_bands, region_height, remove_far_from_markers,
    remove_large_off_cloth, CleanupReport, HoleRun, PartLimits, PixelBox, RegionRule, ATTACH_REACH,
    PART_REACH,
};
use super::features::{
    colour_index, contrast_bin, downscale, is_near_pattern, is_suit_pattern, shows_suit_pattern,
    temporal_bin, temporal_difference, ColourLut, FrameFeatures, MarkerGate, COLOUR_BINS,
    PATTERN_CLASSES, TEMPORAL_BINS,
};
use super::hands::{arm_ends, hand_pixels, ArmScratch, SUIT_HEIGHT_CM};
use super::maxflow::{GridGraph, GridMaxFlow};
use super::room::{RoomModel, RoomSettings};
use super::snap::{snap_to_colour_edges, unmix_outline, Snapping, Unmixing};
use super::tables::SegmenterTables;
use crate::mask::{bounding_box_of, grow_square_into, Mask};
use crate::suit::SuitDefinition;

/// Tuning of the clean-up and the boundary refinement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SegmenterOptions {
    /// The person region must cover at least this fraction of the image, else the mask is empty.
    pub min_person_fraction: f32,
    /// Background holes up to this fraction of the image are filled: at 640×480 (the cut's grid
    /// 320 × 240) 23 pixels of the grid, about two markers' area for a person 300 pixels tall (a
    /// marker the cut missed, a shadowed fold); larger enclosed gaps are mostly the room seen
    /// between bent legs or between an arm and the body. 0.001 until the first session of
    /// 2026-12-06; chosen on the nine selection renderings: 0.0002 / 0.0003 / 0.0004 / 0.0006 /
    /// 0.001 / none gave 0.9630 / 0.9635 / 0.9634 / 0.9633 / 0.9630 / 0.9622 mean IoU.
    pub max_hole_fraction: f32,
    /// After the refinement, enclosed holes of the full-resolution mask up to this many markers'
    /// areas (at the mask's height taken as [`PERSON_HEIGHT_CM`]) and at least
    /// [`SUIT_HOLE_MIN_SHARE`] of the suit's colours are filled ([`fill_suit_holes`]): markers
    /// the cut left out because the room has their colour (cyan markers in front of a teal
    /// disc), which the cut's hole filling, at a fixed share of the image, misses when two lie
    /// side by side, and which the refinement can open again. 0: off. Chosen on the nine
    /// selection renderings (mean IoU; recall and precision of the markers in the segmenter's
    /// masks): off 0.9523 (0.8966, 0.9876), 1 / 2 / 3 / **4** / 6 / 8 markers 0.9532 / 0.9540 /
    /// 0.9543 / **0.9543** / 0.9543 / 0.9541 (recall 0.8994 / 0.9016 / 0.9024 / **0.9027** /
    /// 0.9027 / 0.9022, precision 0.9879–0.9884); at 4, a share of 0.6 / 0.8 / 0.95 gave 0.9543
    /// / 0.9543 / 0.9541 (recall 0.9029 / 0.9027 / 0.9019). docs/measurements.md, fourth session
    /// of 2026-12-07.
    pub suit_hole_markers: f32,
    /// Weight of the upsampled cut against the full-resolution colour in the boundary band (nats).
    pub refine_prior: f32,
    /// Widen the boundary band to the cells next to a label change, not only those across it.
    pub refine_wide: bool,
    /// The edge snapping after the refinement (see [`snap`](super::snap)): four passes (0: none)
    /// with samples within 3 pixels; an outline pixel of a marker's colour stays person unless at
    /// least half of the room's samples around it have that marker's colour too
    /// ([`Snapping::keep_room_share`]; above 1: always, as before the tenth session of 2026-12-05).
    pub snap: Snapping,
    /// After the snapping, each outline pixel decided by linear unmixing between the colours
    /// sampled inside and outside along the outline's normal (see
    /// [`unmix_outline`]; `None`: not). The masks added up to 8 times
    /// as many pixels one pixel outside the true outline as they missed one pixel inside (a blur
    /// of the green cloth and a blue room reads as cyan, a marker's colour, which the snapping
    /// keeps). Chosen on the nine selection renderings (mean IoU; the three validation
    /// sequences of `scripts/eval_segmenter.sh` after the slash), off 0.9695 / 0.9671: samples 2 px
    /// away, contrast ≥ 30, residual ≤ 0.2 of it 0.9708 / 0.9683; residual 0.1 / **0.15** 0.9711
    /// / 0.9686, 0.9710 / 0.9686; at 0.15, contrast 20 / 40 0.9710 / 0.9686 each; distance 1 /
    /// **1.5** / 2.5 0.9713 / 0.9688, **0.9712 / 0.9688**, 0.9707 / 0.9682; a second and third
    /// pass 0.9713 / 0.9689, 0.9712 / 0.9689. 1.5 px, in the middle of the flat top.
    pub unmix: Option<Unmixing>,
    /// Share of the online background histogram that each new frame replaces (0 = no adaptation).
    pub adapt_rate: f32,
    /// Background pixels closer than this to the person (at the cut's resolution) are not learned.
    pub adapt_margin: u32,
    /// Weight of the online histogram in the background colour likelihood once it exists.
    pub adapt_share: f32,
    /// How often a stream's first frame is segmented at most (with adaptation on), each pass
    /// learning from the one before, until the mask stops changing. Without history the first
    /// frames missed what the online models had not yet learned (a head, hands, red markers over
    /// a red-brown room): the dance 05_12 started at its tenth frame had 0.771 there, 0.931 when
    /// the stream had started ten frames earlier. Chosen with `suitcap segment --truth` (third
    /// session of 2026-12-07 in docs/measurements.md): passes 1 / 2 / 4 / **8** / 16 gave that
    /// frame 0.700 / 0.771 / 0.824 / **0.861** / 0.855, the 50 frames from it 0.9247 / 0.9345 /
    /// 0.9414 / **0.9439** / 0.9432, the six pose test sequences – / 0.9379 / – / **0.9391** /
    /// 0.9391. Keeping each pass's mask as the next one's history instead held its errors
    /// (0.9346 at 8).
    pub first_frame_passes: u32,
    /// The weight, relative to σ_T, of the label prior (the person's and the background's share
    /// of the training frames) that stands in for the temporal term in the frames without a
    /// second-order history (a stream's first two). A first frame that leaves most of its
    /// suit-looking pixels out is segmented again without it ([`FIRST_FRAME_MAX_LEFT_OUT`]).
    pub label_prior_share: f32,
    /// A frame in the middle of a stream whose mask came out empty while more than a person's
    /// least area of it looks like the suit, most of it left out, is segmented again without the
    /// history (the room and the colours learned so far are kept) and without the label prior:
    /// the history, which says the room is room, holds out a person stepping in from the
    /// frame's edge a sliver at a time, or one it lost. Chosen on the 24 selection renderings
    /// (docs/measurements.md, tenth session of 2026-12-07): 0.9544 → 0.9546 (walk 09_12, which
    /// leaves the picture and steps back in, 0.9093 → 0.9149); again on every frame that left most
    /// of the suit out, not only empty ones, the kick over the aloe (703) fell 0.9261 → 0.8460.
    pub lost_person_retry: bool,
    /// How far the head, hands and shoes are looked for around the suit, as a share of the suit
    /// region's height (0: the mask is the suit only).
    pub part_reach: f32,
    /// Where a piece found within `part_reach` that reaches the suit's top row is too large or
    /// too shallow for a part, a head is looked for again within this narrower band, as a share of
    /// the suit region's height (see [`attach_parts_narrowing`]; 0 or `part_reach`: the second
    /// look finds nothing new).
    pub part_reach_narrow: f32,
    /// How near the main region, as a share of its height, another piece of the suit is kept (see
    /// [`keep_person_region`](super::cleanup::keep_person_region); 0: the main region only).
    pub piece_reach: f32,
    /// The largest piece attached as a part (a hand, a shoe), as a share of the suit's area: a
    /// hand or a shoe is 2–5 % of it. Pale or skin-coloured background beside the legs or the
    /// trunk (the pith of an orange, cat fur) joins as larger ragged pieces: at 10 % they were kept
    /// (pose test sequences 0.894, 0.922, 0.937, 0.809, 0.806, 0.918 IoU against 0.903, 0.922,
    /// 0.940, 0.840, 0.811, 0.928 at 5 % for every piece, 0.909, 0.922, 0.944, 0.839, 0.811, 0.928
    /// with [`SegmenterOptions::part_max_top_share`] beside it).
    pub part_max_share: f32,
    /// The largest piece that reaches as high as the suit's top row or higher (see
    /// [`PartLimits::max_top_area`]): a head, about 6 % of the suit's area seen from the front,
    /// with a hand before it when drinking or waving.
    pub part_max_top_share: f32,
    /// The same for a round piece (see [`PartLimits::max_round_area`]): a head seen from the side
    /// or over a crouch was 12 % of the suit's area on the demo clip.
    pub part_max_round_share: f32,
    /// The least area of an attached part per pixel of its contact with the suit, as a share of
    /// the suit's height: a hand is about 0.06 of it deep, a strip of background along an arm a
    /// pixel or two. 0.03 until the ninth session of 2026-12-05; with the person's own part
    /// colours ([`SegmenterOptions::part_colour_share`]) looked at again on the twelve selection
    /// renderings: 0.01 / 0.015 / **0.02** / 0.025 / 0.03 / 0.045 gave mean IoU 0.9487 / 0.9490 /
    /// 0.9489 / 0.9484 / 0.9473 / 0.9415 (0.02: eleven of the twelve up, run 09_05 +0.007): a
    /// head or hand seen partly, shallower than the rule allowed, is kept.
    pub part_min_depth: f32,
    /// The largest area of a part beside the suit (one that reaches neither the suit's top row nor
    /// its bottom one: a hand) per pixel of its contact with the suit, as a share of the suit's
    /// height. A hand joins at its wrist; background of a skin's colour beside a leg or an arm
    /// (an orange's flesh and pith) is a large piece that the flood entered through a pixel or
    /// two. Chosen on the nine selection renderings (mean IoU): off 0.9615, 0.6 / 0.4 / 0.35 /
    /// **0.3** / 0.25 / 0.2 → 0.9622 / 0.9626 / 0.9628 / **0.9630** / 0.9632 / 0.9627; 0.3 from
    /// the flat top, the one that takes back fewer hands (a hand seen joined to its sleeve by one
    /// pixel of the cut's grid is 0.37–0.39 deep).
    pub part_max_side_depth: f32,
    /// The largest piece of the cut that is not the suit's cloth (markers, or anything else
    /// chromatic), in marker areas (the suit's marker size on a person of [`PERSON_HEIGHT_CM`]
    /// as tall as the cut region); larger pieces are background ([`remove_large_off_cloth`]; 0:
    /// kept). Chosen on the three validation sequences of `scripts/eval_segmenter.sh` (mean IoU
    /// with the tables and weights trained without it: off 0.9338, 4 markers 0.9379, 8 0.9371,
    /// 16 0.9358).
    pub off_cloth_max_markers: f32,
    /// How far from the nearest marker of the cut the suit's cloth can be, in cm on a person of
    /// [`PERSON_HEIGHT_CM`] as tall as the cut region (or as [`STANDING_AREA_SHARE`] makes its
    /// area, when that is taller: a crouch); farther pixels are background
    /// ([`remove_far_from_markers`]; 0: no limit). The suit prints a 4 cm marker every 7 cm, but
    /// a cloth-coloured object in the room that touches the person is joined to the suit by the
    /// cut: the parts of it near the room's pixels of a marker's hue pass the pattern test above,
    /// so a green square on the coffee photograph stayed as a rim around it (bend 02_06 of the
    /// selection renderings, 97 of 556 frames under 0.8 IoU). Chosen on the nine selection
    /// renderings (mean IoU; the three validation sequences of `scripts/eval_segmenter.sh` after
    /// the slash): off 0.9682 / 0.9671; 12 / 16 / **24** / 32 cm 0.9689 / 0.9696 / **0.9695** /
    /// 0.9693, 0.9674 / 0.9671 / **0.9671** / 0.9671: 24 cm, on the flat top, away from short
    /// reaches, where the shadowed side of a crouch (markers the cut's grid does not show) went
    /// too in a first form of the rule. Counting the markers of the region only, not those in
    /// its holes, 24 cm gave 0.9692 / 0.9671; with the region's height alone as the scale, a
    /// crouch lost the suit in whole frames (12 cm: 0.9549).
    pub cloth_reach_cm: f32,
    /// Nats by which a band pixel's part test favours the part where the previous frame attached
    /// a part above the suit's top row or below its bottom row (a head, shoes, a hand raised or
    /// lowered past them) within [`PART_MEMORY_RADIUS`] cut pixels (0: no memory). Where the
    /// room has a skin's colour (coffee, cat fur) the online background makes a head likelier
    /// background than part in some frames and not in others; remembered, the head found in one
    /// frame is kept in the next. Not the parts beside the suit: remembering every part kept
    /// background attached beside the hands (on the nine selection renderings and three more of
    /// the palest subject, mean IoU 0.9374 without memory, 0.9373 / 0.9370 / 0.9369 at 0.5 / 1 /
    /// 2 nats for every part; the drink's hand and can lost 0.02). Heads only: 0.9389,
    /// **0.9391**, 0.9391, 0.9387 at 1, 1.5, 2, 3 nats (radius 2; radius 1 or 3 at 1.5 nats
    /// 0.9389, 0.9391); at 1.5 the run over coffee +0.008, the palest subject over coffee
    /// +0.011, no rendering down by more than 0.0004. Where the memory joins a head to
    /// background beside it into a piece too large for a head (taken back whole), the pieces
    /// found without it are kept (0.9392). The parts below the suit too: **0.9425** (bend 02_06
    /// +0.026, the run over coffee +0.008, nothing down by more than 0.0001; docs/measurements.md,
    /// eighth session of 2026-12-05). It can still carry background of a head's colour along for
    /// a few frames (a star's halo joined to a head for two frames, then both dropped in the
    /// third, in `scripts/eval_segmenter.sh`'s walk).
    pub part_memory: f32,
    /// Nats by which the part test favours the part within the ellipses where a head and shoes
    /// are expected ([`expected_head`]: above the middle of the suit's top rows;
    /// [`expected_shoes`]: below each leg's end; sized by the suit's height), in a last look in
    /// frames where the other passes attached fewer pixels above the suit's top row, or below its
    /// bottom row, than those ellipses hold (0: no such look). The look floods from the suit
    /// through the band's pixels within the lacking ellipses only, under the same part limits, and
    /// adds what it finds. Over a room with much of a skin's colour (cat fur, coffee, an orange)
    /// the online background makes the head likelier background than part, and where the head
    /// touches such background the piece grows too large for a head and is taken back: a dance
    /// over the cat photograph lost its head in most frames; dark shoes over a dark hedge were
    /// never flooded (a walk lost them in most frames). Chosen on the nine selection renderings
    /// (mean IoU; the three validation sequences of `scripts/eval_segmenter.sh` after the slash):
    /// off 0.9673 / 0.9601. Heads only: where nothing was found above the top row, 3 / 6 / 12
    /// nats 0.9674 / 0.9674 / 0.9673 (0.9606 each); where less than the ellipse was found, 3 /
    /// **6** / 12 nats 0.9675 / **0.9680** / 0.9667 (0.9607 each; less than half or one and a
    /// half times the ellipse at 6 nats 0.9675, 0.9675; three times 0.9625). Shoes too, at 6
    /// nats: **0.9682 / 0.9671**; shoe ellipses 12 or 20 cm wide 0.9680 / 0.9670, 0.9674 / 0.9673,
    /// 8 or 16 cm tall 0.9682 / 0.9665, 0.9679 / 0.9671, 0 or 4 cm below the leg 0.9680 /
    /// 0.9663, 0.9677 / 0.9677, ankle rows of 3 or 10 cm 0.9680 / 0.9669, 0.9681 / 0.9682.
    /// Placing the head's ellipse where the part test scores best, within half a head of the
    /// neck, lost heads to dark pupils and shadows (the dance of the pose test sequences 0.8734 →
    /// 0.8635), so it stays above the neck (docs/measurements.md, ninth session of 2026-12-06).
    pub part_look: f32,
    /// How many nats the last look leans towards the part within the ellipse where a hand is
    /// expected beyond each end of the suit's arms ([`hands`](super::hands)), for a hand of
    /// which less than [`HAND_FOUND_SHARE`] of that ellipse was found (0: no look for hands, as
    /// before the ninth session of 2026-12-07). A hand over a room of skin's colours (the cat's
    /// fur) is otherwise lost whole. Chosen on the 24 selection renderings with the label prior
    /// at half its weight (docs/measurements.md, ninth session of 2026-12-07): 0 / 2 / **3**
    /// gave 0.9518 / 0.9524 / **0.9528** (15 of 24 gaining, 6 losing). With the prior at its
    /// whole weight 3 gave 0.9295 and 6 0.9288 (11 of 24 losing) against 0.9280: the ellipse
    /// follows the forearm and a bent wrist does not, so a stronger lean takes in room beside
    /// the hand.
    pub hand_look: f32,
    /// Share of the person's own head and shoe colours in the part test's colour likelihood (0:
    /// the trained part table alone, as before the ninth session of 2026-12-05). The trained
    /// table holds every training subject's skin, hair and shoes, so a background of any skin's
    /// colour passes it (cat fur beside a pale head, bricks beside a walker's hands); mixed with
    /// a histogram of the colours attached above and below the suit's rows in the frames before
    /// (learned like the room's, [`SegmenterOptions::part_colour_rate`]), the test leans towards
    /// this person's colours. Chosen with `suitcap segment --truth` on the nine selection
    /// renderings and three of the palest subject (mean IoU 0.9425 without): shares 0.2 / 0.3 /
    /// 0.45 / 0.6 at rate 0.3 gave 0.9449 / **0.9473** / 0.9474 / 0.9473, rates 0.15 / 0.6 at
    /// share 0.3 0.9474 / 0.9473 (the drink's hand and can +0.023, the run over coffee +0.016,
    /// the bend −0.008); learned from every attached part (hands too), 0.9422–0.9439 (the
    /// drink's can learned as a hand's colour). docs/measurements.md, ninth session.
    pub part_colour_share: f32,
    /// The same share for the part test within the suit's rows, where the parts are hands: a
    /// hand is skin like this person's head, and the background beside the legs and the trunk
    /// (an orange's pith, bricks, cat fur) passes the trained table of every subject's skin.
    /// Chosen on the nine selection renderings (mean IoU 0.9589 at 0.3, as above the rows): 0.5 /
    /// 0.6 / **0.75** / 0.9 / 1 gave 0.9601 / 0.9605 / **0.9615** / 0.9608 / 0.9581 (at 0.75 the
    /// drink's hands +0.014, walk 07_04 +0.007, dance 05_04 +0.004, the bend −0.005; markers'
    /// recall and precision over the nine within 0.0001); docs/measurements.md, tenth session.
    /// The refinement of part pixels keeps the head-and-shoe mix. With `part_colour_share` 0
    /// nothing is learned and both tests use the trained table.
    pub hand_colour_share: f32,
    /// Share of the online part-colour histogram that each frame's head and shoes replace.
    pub part_colour_rate: f32,
    /// The room pixel by pixel ([`RoomModel`], learned like the room's colours, from the pixels
    /// well away from the person, and beyond the part band): a band pixel that shows what it
    /// showed while the person was elsewhere is not a part, and the cut counts a pixel that shows
    /// it likelier background. `None`: off (as before the second session of 2026-12-06).
    pub room: Option<RoomSettings>,
}

/// How far (cut pixels, chessboard) the previous frame's parts reach for
/// [`SegmenterOptions::part_memory`].
pub const PART_MEMORY_RADIUS: usize = 2;

/// The share of a hole's pixels that must be of the suit's colours (a marker's or the cloth's)
/// for [`SegmenterOptions::suit_hole_markers`] to fill it.
pub const SUIT_HOLE_MIN_SHARE: f32 = 0.8;

/// The share of a stream's first frame's suit-looking pixels that its suit may leave out before
/// the frame is segmented again without the label prior ([`Segmenter::segment`]). A person in
/// front of a room keeps nearly all of them (the room rarely holds the suit's interleaving of cloth
/// and markers); a first frame the prior hid keeps a few percent. The same test decides whether a
/// frame found empty later in the stream is looked at again
/// ([`SegmenterOptions::lost_person_retry`]).
pub const FIRST_FRAME_MAX_LEFT_OUT: f32 = 0.5;

/// The share of a hand's expected ellipse that the part test must have found for the hand to
/// count as found; less, and the last look floods the ellipse ([`SegmenterOptions::hand_look`]).
pub const HAND_FOUND_SHARE: f32 = 0.25;

/// The height a person is taken to have when the marker size is turned into pixels. The cut
/// region (without the head, which is attached later) is shorter than the person, so the marker is
/// taken a little smaller than it is; [`SegmenterOptions::off_cloth_max_markers`] was chosen so.
pub const PERSON_HEIGHT_CM: f32 = 170.0;

/// A standing person's mask covers about this share of its height squared (the selection
/// renderings' true masks: a walk 0.15, a run 0.18; a crouch up to 0.34), so the square root of
/// the cut region's area over it is a height that a crouch or a bend does not shrink.
pub const STANDING_AREA_SHARE: f32 = 0.15;

impl Default for SegmenterOptions {
    fn default() -> Self {
        SegmenterOptions {
            min_person_fraction: 0.002,
            max_hole_fraction: 0.0003,
            suit_hole_markers: 4.0,
            refine_prior: 3.0,
            refine_wide: true,
            snap: Snapping {
                radius: 3,
                passes: 4,
                keep_room_share: 0.5,
            },
            unmix: Some(Unmixing {
                distance: 1.5,
                min_contrast: 30.0,
                max_residual: 0.15,
            }),
            adapt_rate: 0.3,
            adapt_margin: 4,
            adapt_share: 0.7,
            first_frame_passes: 8,
            label_prior_share: 1.0,
            lost_person_retry: true,
            part_reach: ATTACH_REACH,
            part_reach_narrow: PART_REACH,
            piece_reach: PART_REACH,
            part_max_share: 0.05,
            part_max_top_share: 0.1,
            part_max_round_share: 0.2,
            part_min_depth: 0.02,
            part_max_side_depth: 0.3,
            off_cloth_max_markers: 4.0,
            cloth_reach_cm: 24.0,
            part_memory: 1.5,
            part_look: 6.0,
            hand_look: 3.0,
            part_colour_share: 0.3,
            hand_colour_share: 0.75,
            part_colour_rate: 0.3,
            room: Some(RoomSettings::default()),
        }
    }
}

/// Milliseconds per stage of one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageTimes {
    pub features: f64,
    pub graph: f64,
    pub cut: f64,
    pub cleanup: f64,
    pub refine: f64,
    /// Learning the room's colours and keeping this frame for the next one's motion terms.
    pub history: f64,
}

impl std::ops::AddAssign for StageTimes {
    fn add_assign(&mut self, other: StageTimes) {
        self.features += other.features;
        self.graph += other.graph;
        self.cut += other.cut;
        self.cleanup += other.cleanup;
        self.refine += other.refine;
        self.history += other.history;
    }
}

impl StageTimes {
    pub fn total(&self) -> f64 {
        self.features + self.graph + self.cut + self.cleanup + self.refine + self.history
    }
}

/// The result for one frame.
#[derive(Clone, Debug)]
pub struct Segmentation {
    pub mask: Mask,
    /// The box of the suit alone in frame pixels ((x0, y0, x1, y1), x1 and y1 exclusive): the cut
    /// after its clean-up, before the head, hands and shoes are attached; `None` with nobody in
    /// the frame. The body-size measurement takes the person's height from it, which a head left
    /// off the mask does not shorten.
    pub suit_box: Option<(u32, u32, u32, u32)>,
    pub cleanup: CleanupReport,
    /// The max-flow (= minimum energy) of the cut.
    pub flow: f64,
    pub times: StageTimes,
    /// How often this frame was segmented: more than once for a stream's first frame
    /// ([`SegmenterOptions::first_frame_passes`]) and for a frame found empty and looked at again.
    pub passes: u32,
    /// Whether the frame, found empty in the middle of a stream, was segmented again without the
    /// history ([`SegmenterOptions::lost_person_retry`]).
    pub looked_again: bool,
}

/// A segmenter with its history; one per video stream.
pub struct Segmenter {
    tables: SegmenterTables,
    options: SegmenterOptions,
    lut: ColourLut,
    /// Per contrast bin: the edge weight.
    edge_weight: Vec<f32>,
    gate: MarkerGate,
    maxflow: GridMaxFlow,
    graph: GridGraph,
    small: Vec<[u8; 3]>,
    features: FrameFeatures,
    previous: Option<FrameFeatures>,
    previous_mask: Option<Vec<bool>>,
    before_previous_mask: Option<Vec<bool>>,
    ids: Vec<u32>,
    crop: Vec<bool>,
    /// The unary tables multiplied by their weights σ (see [`UnaryTables`]).
    unary_tables: UnaryTables,
    /// Online background colour histogram over colour bins (sums to 1 once it exists).
    online_background: Option<Vec<f32>>,
    /// Online histogram of the person's head and shoe colours over colour bins (sums to 1 once it
    /// exists; [`SegmenterOptions::part_colour_share`]).
    online_part: Option<Vec<f32>>,
    /// Part colour NLL per colour bin used for the current frame: the trained table mixed with
    /// `online_part`.
    part_bin: Vec<f32>,
    /// The same within the suit's rows (hands; [`SegmenterOptions::hand_colour_share`]).
    hand_bin: Vec<f32>,
    /// Background colour NLL per joint colour × pattern index used for the current frame.
    background_colour: Vec<f32>,
    /// p(pattern class | background) of the trained table.
    background_pattern: [f32; PATTERN_CLASSES],
    /// Background colour NLL per colour bin (the pattern classes summed), trained and online mixed.
    background_bin: Vec<f32>,
    /// Background colour NLL per colour bin of the trained table alone.
    trained_background_bin: Vec<f32>,
    distance: Vec<u16>,
    band: Vec<bool>,
    narrow_band: Vec<bool>,
    part: Vec<bool>,
    /// The previous frame's parts above and below the suit's rows grown by
    /// [`PART_MEMORY_RADIUS`] (empty: none), and the row pass's scratch.
    previous_parts: Vec<bool>,
    grown_rows: Vec<bool>,
    /// Where a head is expected above this frame's suit and shoes below it
    /// ([`SegmenterOptions::part_look`]).
    head_prior: Vec<bool>,
    /// Where hands are expected beyond the ends of this frame's suit's arms
    /// ([`SegmenterOptions::hand_look`]).
    hand_prior: Vec<bool>,
    /// The expected hands of which too little was found: where the last look floods.
    hand_marks: Vec<bool>,
    arm_scratch: ArmScratch,
    /// Set while a stream's first frame is segmented again without the label prior
    /// ([`Segmenter::segment`]).
    label_prior_off: bool,
    shoe_prior: Vec<bool>,
    /// The last look's person and parts, and its band (the part band within the priors).
    look_parts: (Vec<bool>, Vec<bool>),
    look_band: Vec<bool>,
    /// The person and parts found without the memory, where the memory's pass took back a head.
    plain_parts: (Vec<bool>, Vec<bool>),
    /// The person and parts of the narrow band's pass (see [`attach_parts_narrowing`]).
    narrow_parts: (Vec<bool>, Vec<bool>),
    stack: Vec<usize>,
    /// A marker's side as a share of the cut region's height (the suit's marker size on a
    /// person of [`PERSON_HEIGHT_CM`]).
    marker_side_share: f32,
    /// The room pixel by pixel ([`SegmenterOptions::room`]).
    room: RoomModel,
    /// Per grid pixel of this frame: does it show the room ([`RoomModel::room_pixels`])?
    room_seen: Vec<bool>,
    /// Scratch: the grid pixels the room is learned from.
    far: Vec<bool>,
    /// Scratch of [`fill_suit_holes`]: the mask's background runs and their union-find forest.
    hole_runs: Vec<HoleRun>,
    hole_parent: Vec<u32>,
}

/// Pixel counts over the colour bins, from which the online background and part colours are
/// learned.
struct BinHistogram {
    counts: Vec<f32>,
    total: f32,
}

impl BinHistogram {
    fn new() -> BinHistogram {
        BinHistogram {
            counts: vec![0.0; COLOUR_BINS],
            total: 0.0,
        }
    }

    /// Counts one pixel of colour bin `bin`.
    #[inline]
    fn add(&mut self, bin: u16) {
        self.counts[bin as usize] += 1.0;
        self.total += 1.0;
    }

    /// The counts as shares summing to 1; `None` when no pixel was counted.
    fn normalised(mut self) -> Option<Vec<f32>> {
        if self.total < 1.0 {
            return None;
        }
        let total = self.total;
        self.counts.iter_mut().for_each(|v| *v /= total);
        Some(self.counts)
    }
}

/// Blends this frame's normalised `histogram` into the running one, `(1 − rate)·old + rate·new`
/// (the first frame's alone when there is none yet), and returns it.
fn blend_online(online: &mut Option<Vec<f32>>, histogram: Vec<f32>, rate: f32) -> &[f32] {
    match online {
        Some(old) => {
            for (o, n) in old.iter_mut().zip(&histogram) {
                *o = (1.0 - rate) * *o + rate * n;
            }
        }
        None => *online = Some(histogram),
    }
    online.as_deref().unwrap_or_default()
}

/// `−ln((1 − share)·e^(−trained_nll) + share·online)`, a probability floored at 1e-6: a trained
/// table's entry mixed with an online histogram's (`online`, a probability).
fn mixed_nll(trained_nll: f32, share: f32, online: f32) -> f32 {
    let p = (1.0 - share) * (-trained_nll).exp() + share * online;
    -(p.max(1e-6)).ln()
}

/// The part test's two tables from the trained part table (`trained`, NLL per colour bin) and the
/// person's own head and shoe colours (`online`, a histogram): `part`, for the head and the shoes,
/// mixes them at `part_share`, `hand`, for the hands within the suit's rows, at `hand_share`.
fn mix_part_tables(
    trained: &[f32],
    online: &[f32],
    (part_share, hand_share): (f32, f32),
    (part, hand): (&mut [f32], &mut [f32]),
) {
    for (table, share) in [(part, part_share), (hand, hand_share)] {
        for ((v, &nll), &p) in table.iter_mut().zip(trained).zip(online) {
            *v = mixed_nll(nll, share, p);
        }
    }
}

/// −ln Σ_class p(class · COLOUR_BINS + bin) of a joint colour × pattern NLL table.
fn marginal_nll(joint: &[f32]) -> Vec<f32> {
    (0..COLOUR_BINS)
        .map(|bin| {
            let p: f32 = (0..PATTERN_CLASSES)
                .map(|c| (-joint[c * COLOUR_BINS + bin]).exp())
                .sum();
            -(p.max(1e-6)).ln()
        })
        .collect()
}

/// The tables of the unary terms, each multiplied by its weight σ once, so that a pixel's energy is
/// a sum of lookups: the suit's colour × pattern (C), gradient (G), motion (M), the second-order temporal
/// prior (T) and the label prior used when there is no history.
#[derive(Clone, Debug)]
struct UnaryTables {
    /// The suit's colour × pattern table; the background's is mixed with the room's colours each
    /// frame (`Segmenter::background_colour`).
    suit_colour: Vec<f32>,
    gradient: [Vec<f32>; 2],
    motion: [Vec<f32>; 4],
    temporal: [f32; 8],
    prior: [f32; 2],
}

impl UnaryTables {
    fn new(t: &SegmenterTables) -> UnaryTables {
        let s = t.weights;
        let scaled = |table: &[f32], sigma: f32| table.iter().map(|v| sigma * v).collect();
        UnaryTables {
            suit_colour: scaled(&t.colour[1], s.colour),
            gradient: [0, 1].map(|l| scaled(&t.gradient[l], s.gradient)),
            motion: [0, 1, 2, 3].map(|k| scaled(&t.motion[k], s.motion)),
            temporal: t.temporal.map(|v| s.temporal * v),
            prior: t.prior.map(|v| s.temporal * v),
        }
    }
}

impl Segmenter {
    pub fn new(
        tables: SegmenterTables,
        suit: &SuitDefinition,
        options: SegmenterOptions,
    ) -> Segmenter {
        // Pairwise energies A (both background), B (different), D (both person) per contrast bin,
        // each −ln p(contrast | pair) − ln p(pair equal or different); the edge weight is
        // (2B − A − D)/2. The rest of the pair energy, (D − A)/2 on both nodes' person cost, would say
        // how smooth the person is against the training room; a new room is smoother or rougher, so
        // it is left out (with it, a smooth orange or a cat's fur next to the suit became person).
        let n = &tables.neighbourhood;
        let sigma = tables.weights.neighbourhood;
        let [equal, different] = tables.pair_prior;
        let bins = n[0].len();
        let mut edge_weight = Vec::with_capacity(bins);
        // `k` indexes four tables at once; a 4-way zip would read worse.
        #[allow(clippy::needless_range_loop)]
        for k in 0..bins {
            let (a, b, d) = (
                n[0][k] + equal,
                0.5 * (n[1][k] + n[2][k]) + different,
                n[3][k] + equal,
            );
            edge_weight.push(sigma * (0.5 * (2.0 * b - a - d)).max(0.0));
        }
        let background_pattern = std::array::from_fn(|class| {
            tables.colour[0][class * COLOUR_BINS..(class + 1) * COLOUR_BINS]
                .iter()
                .map(|nll| (-nll).exp())
                .sum::<f32>()
        });
        let background_colour = tables.colour[0].clone();
        let part_bin = tables.part.clone();
        let trained_background_bin = marginal_nll(&tables.colour[0]);
        let background_bin = trained_background_bin.clone();
        let unary_tables = UnaryTables::new(&tables);
        Segmenter {
            tables,
            options,
            lut: ColourLut::new(),
            edge_weight,
            gate: MarkerGate::new(suit),
            maxflow: GridMaxFlow::new(),
            graph: GridGraph::new(0, 0),
            small: Vec::new(),
            features: FrameFeatures::default(),
            previous: None,
            previous_mask: None,
            before_previous_mask: None,
            ids: Vec::new(),
            crop: Vec::new(),
            unary_tables,
            online_background: None,
            online_part: None,
            hand_bin: part_bin.clone(),
            part_bin,
            background_colour,
            background_pattern,
            background_bin,
            trained_background_bin,
            distance: Vec::new(),
            band: Vec::new(),
            narrow_band: Vec::new(),
            part: Vec::new(),
            previous_parts: Vec::new(),
            grown_rows: Vec::new(),
            head_prior: Vec::new(),
            hand_prior: Vec::new(),
            hand_marks: Vec::new(),
            arm_scratch: ArmScratch::default(),
            label_prior_off: false,
            shoe_prior: Vec::new(),
            look_parts: (Vec::new(), Vec::new()),
            look_band: Vec::new(),
            plain_parts: (Vec::new(), Vec::new()),
            narrow_parts: (Vec::new(), Vec::new()),
            stack: Vec::new(),
            marker_side_share: suit.marker_size_cm / PERSON_HEIGHT_CM,
            room: RoomModel::new(),
            room_seen: Vec::new(),
            far: Vec::new(),
            hole_runs: Vec::new(),
            hole_parent: Vec::new(),
        }
    }

    pub fn tables(&self) -> &SegmenterTables {
        &self.tables
    }

    /// Forgets the history and the learned background (a new sequence, or the camera moved).
    pub fn reset(&mut self) {
        self.previous = None;
        self.forget_history();
        self.previous_parts.clear();
        self.online_background = None;
        self.online_part = None;
        self.room.clear();
        self.part_bin.clone_from(&self.tables.part);
        self.hand_bin.clone_from(&self.tables.part);
        self.background_colour.clone_from(&self.tables.colour[0]);
        self.background_bin.clone_from(&self.trained_background_bin);
    }

    /// Learns the background colours of this frame from pixels well away from the person and
    /// refreshes the background colour likelihood for the next frame; learns the room pixel by
    /// pixel from those of them beyond the part band, and from those within it whose colour is
    /// not a part's ([`RoomSettings::band_part_odds`]).
    fn adapt_background(&mut self, labels: &[bool]) {
        let o = self.options;
        if o.adapt_rate <= 0.0 && o.room.is_none() {
            return;
        }
        let (w, h) = (self.features.width, self.features.height);
        // Pixels farther than the margin from the person: everything outside the box of
        // `distance_near`, and the far pixels inside it.
        let margin = o.adapt_margin as usize;
        let near = distance_near(labels, w, h, margin + 1, &mut self.distance);
        let mut histogram = BinHistogram::new();
        let band_part_odds = o.room.map_or(f32::NEG_INFINITY, |r| r.band_part_odds);
        self.far.clear();
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                let far = match near {
                    Some(b) if b.contains(x, y) => {
                        self.distance[(y - b.y0) * b.width() + x - b.x0] as usize > 3 * margin
                    }
                    _ => true,
                };
                if far {
                    histogram.add(self.features.colour[i].bin);
                }
                // A head the part test missed lies within the band: learned as room, it would
                // never be found there again. So a band pixel is learned only if its colour is
                // not likelier a part's than the room's by more than the odds.
                let in_band = self.band.get(i).copied().unwrap_or(false);
                let part_like = || {
                    let bin = self.features.colour[i].bin as usize;
                    let part = self.part_bin[bin].min(self.hand_bin[bin]);
                    self.background_bin[bin] - part > band_part_odds
                };
                self.far.push(far && !(in_band && part_like()));
            }
        }
        if let Some(settings) = &o.room {
            self.room.learn(&self.small, w, h, &self.far, settings);
        }
        if o.adapt_rate <= 0.0 {
            return;
        }
        let Some(histogram) = histogram.normalised() else {
            return;
        };
        let online = blend_online(&mut self.online_background, histogram, o.adapt_rate);
        // p_bg(colour, pattern) = (1 − s)·trained + s·online(colour)·p_trained(pattern | bg).
        let share = o.adapt_share;
        for class in 0..PATTERN_CLASSES {
            // `bin` also gives the index `k` into the trained table, so it stays an index.
            #[allow(clippy::needless_range_loop)]
            for bin in 0..COLOUR_BINS {
                let k = class * COLOUR_BINS + bin;
                let online_p = online[bin] * self.background_pattern[class];
                self.background_colour[k] = mixed_nll(self.tables.colour[0][k], share, online_p);
            }
        }
        let trained = &self.trained_background_bin;
        for (bin, v) in self.background_bin.iter_mut().enumerate() {
            *v = mixed_nll(trained[bin], share, online[bin]);
        }
    }

    /// Learns the person's head and shoe colours from this frame's parts above and below the
    /// suit's rows (`suit_rows`, cut rows) and refreshes the part colour likelihood for the rest of
    /// this frame (the refinement) and the next
    /// ([`SegmenterOptions::part_colour_share`]).
    fn adapt_part_colours(&mut self, w: usize, suit_rows: std::ops::Range<usize>) {
        let o = self.options;
        if o.part_colour_share <= 0.0 || w == 0 {
            return;
        }
        let mut histogram = BinHistogram::new();
        for (i, _) in self.part.iter().enumerate().filter(|(_, &p)| p) {
            if !suit_rows.contains(&(i / w)) {
                histogram.add(self.features.colour[i].bin);
            }
        }
        let Some(histogram) = histogram.normalised() else {
            return;
        };
        let online = blend_online(&mut self.online_part, histogram, o.part_colour_rate);
        mix_part_tables(
            &self.tables.part,
            online,
            (o.part_colour_share, o.hand_colour_share),
            (&mut self.part_bin, &mut self.hand_bin),
        );
    }

    /// Builds the frame's graph (without cutting it); the graph is then available from [`Segmenter::graph`].
    pub fn build_graph(&mut self, frame: &RgbImage) {
        let factor = self.tables.cut_factor(frame.height());
        let (w, h) = downscale(frame, factor, &mut self.small);
        self.features
            .compute(&self.small, w, h, &self.lut, &self.gate);
        self.fill_graph();
    }

    /// The graph of the last frame, e.g. to dump it as GCG1 and compare solvers.
    pub fn graph(&self) -> &GridGraph {
        &self.graph
    }

    /// The room learned so far, pixel by pixel on the cut's grid.
    pub fn room(&self) -> &RoomModel {
        &self.room
    }

    fn fill_graph(&mut self) {
        let (w, h) = (self.features.width, self.features.height);
        if self.graph.width() != w || self.graph.height() != h {
            self.graph = GridGraph::new(w, h);
            self.reset();
        }
        let u = &self.unary_tables;
        let f = &self.features;
        let history = self.previous.as_ref().zip(self.previous_mask.as_ref());
        let before_previous = self.before_previous_mask.as_deref();
        let sigma_c = self.tables.weights.colour;
        let background_colour = &self.background_colour;
        // The room: this frame's brightness against the model's, over the known pixels that were
        // not the person in the previous frame.
        match &self.options.room {
            Some(settings) => {
                let previous = self.previous_mask.as_deref();
                let gain =
                    self.room
                        .gain(&self.small, |i| previous.is_none_or(|m| !m[i]), settings);
                self.room
                    .room_pixels(&self.small, gain, settings, &mut self.room_seen);
            }
            None => {
                self.room_seen.clear();
                self.room_seen.resize(w * h, false);
            }
        }
        let (room_seen, room_bonus) = (
            &self.room_seen,
            self.options.room.map_or(0.0, |r| r.cut_bonus),
        );
        let (source, sink, right, down) = self.graph.parts_mut();
        // Without a second-order history, the label prior stands in for the temporal term.
        let share = if self.label_prior_off {
            0.0
        } else {
            self.options.label_prior_share
        };
        let prior = u.prior.map(|v| share * v);
        for i in 0..w * h {
            let c = f.colour[i];
            let colour = colour_index(c, f.pattern[i]);
            let gradient = f.gradient[i] as usize;
            // The background's colour is the trained table mixed with the room's colours learned
            // online (see `adapt_background`); the suit's is the trained table.
            let mut e = [
                sigma_c * background_colour[colour] + u.gradient[0][gradient],
                u.suit_colour[colour] + u.gradient[1][gradient],
            ];
            match history {
                Some((prev, prev_mask)) => {
                    let dt = temporal_difference(c, prev.colour[i]);
                    let bin = f.gradient_magnitude[i] as usize * TEMPORAL_BINS + temporal_bin(dt);
                    let lp = prev_mask[i] as usize;
                    for (l, el) in e.iter_mut().enumerate() {
                        *el += u.motion[2 * l + lp][bin]
                            + match before_previous {
                                Some(pp) => u.temporal[4 * l + 2 * lp + pp[i] as usize],
                                None => prior[l],
                            };
                    }
                }
                None => {
                    e[0] += prior[0];
                    e[1] += prior[1];
                }
            }
            if room_seen[i] {
                e[0] -= room_bonus;
            }
            let m = e[0].min(e[1]);
            source[i] = e[0] - m; // cost of labelling i background
            sink[i] = e[1] - m; // cost of labelling i person
        }
        for y in 0..h {
            let row = &f.colour[y * w..(y + 1) * w];
            for (x, pair) in row.windows(2).enumerate() {
                right[y * (w - 1) + x] = self.edge_weight[contrast_bin(pair[0], pair[1])];
            }
            if y + 1 < h {
                let below = &f.colour[(y + 1) * w..(y + 2) * w];
                for (x, (&a, &b)) in row.iter().zip(below).enumerate() {
                    down[y * w + x] = self.edge_weight[contrast_bin(a, b)];
                }
            }
        }
    }

    /// Segments one frame.
    pub fn segment(&mut self, frame: &RgbImage) -> Segmentation {
        if self.online_background.is_none()
            && self.previous.is_none()
            && self.options.adapt_rate > 0.0
        {
            // The first frame of a stream: no background seen yet.
            let first = self.segment_first(frame);
            if !self.suit_left_out() {
                return first;
            }
            // Most of what looks like the suit was left out: the label prior, which says most
            // of a frame is room, outweighed colours that tell this suit from this room by
            // little, and the room learned from that mask holds the suit. Start the stream
            // again without the prior.
            self.reset();
            return self.again_without_prior(frame, &first, Segmenter::segment_first);
        }
        let once = self.segment_once(frame);
        if !self.options.lost_person_retry || !once.mask.is_empty() || !self.suit_left_out() {
            return once;
        }
        // Nobody found, yet much of the frame looks like the suit: the history held the person
        // out. Look again without it and without the prior that stands in for it.
        self.forget_history();
        let mut again = self.again_without_prior(frame, &once, Segmenter::segment_once);
        again.looked_again = true;
        again
    }

    /// `frame` segmented by `segment` without the label prior, after `earlier` (whose time and
    /// passes are counted in).
    fn again_without_prior(
        &mut self,
        frame: &RgbImage,
        earlier: &Segmentation,
        segment: fn(&mut Segmenter, &RgbImage) -> Segmentation,
    ) -> Segmentation {
        self.label_prior_off = true;
        let mut again = segment(self, frame);
        self.label_prior_off = false;
        again.times += earlier.times;
        again.passes += earlier.passes;
        again
    }

    /// Forgets the labels of the frames before, so that the next frame is cut without the
    /// motion and temporal terms (the room and the colours learned are kept).
    fn forget_history(&mut self) {
        self.previous_mask = None;
        self.before_previous_mask = None;
    }

    /// A stream's first frame: segmented once to learn the room's colours away from the person,
    /// then again with them, each pass learning more (the room pixel by pixel, the person's own
    /// head and shoe colours), until the mask stops changing or the passes run out.
    fn segment_first(&mut self, frame: &RgbImage) -> Segmentation {
        let mut last = self.segment_once(frame);
        for pass in 2..=self.options.first_frame_passes {
            self.forget_history();
            let mut next = self.segment_once(frame);
            next.times += last.times;
            next.passes = pass;
            let settled = next.mask == last.mask;
            last = next;
            if settled {
                break;
            }
        }
        last
    }

    /// Whether the frame just segmented (a first frame, or one whose mask came out empty) left
    /// out of its suit (the cleaned cut) more than [`FIRST_FRAME_MAX_LEFT_OUT`] of its pixels
    /// that look like the suit (cloth or a marker's colour within the suit's interleaving of the
    /// two, [`shows_suit_pattern`] from class 3), when they are at least a person's least area
    /// ([`SegmenterOptions::min_person_fraction`]).
    fn suit_left_out(&self) -> bool {
        let (Some(features), Some(suit)) = (&self.previous, &self.previous_mask) else {
            return false;
        };
        let (mut like, mut inside) = (0usize, 0usize);
        for (i, &s) in suit.iter().enumerate() {
            if shows_suit_pattern(features, &self.gate, i, 3) {
                like += 1;
                inside += s as usize;
            }
        }
        let least = self.options.min_person_fraction * suit.len() as f32;
        like as f32 >= least && (like - inside) as f32 > FIRST_FRAME_MAX_LEFT_OUT * like as f32
    }

    fn segment_once(&mut self, frame: &RgbImage) -> Segmentation {
        let mut times = StageTimes::default();
        let started = Instant::now();
        let factor = self.tables.cut_factor(frame.height());
        let (w, h) = downscale(frame, factor, &mut self.small);
        self.features
            .compute(&self.small, w, h, &self.lut, &self.gate);
        times.features = ms(started);

        let started = Instant::now();
        self.fill_graph();
        times.graph = ms(started);

        let started = Instant::now();
        let result = self.maxflow.solve(&self.graph);
        times.cut = ms(started);
        let mut labels = result.labels;

        let started = Instant::now();
        self.keep_near_pattern(&mut labels, w, h);
        let max_hole = (self.options.max_hole_fraction * (w * h) as f32) as usize;
        let mut ids = std::mem::take(&mut self.ids);
        let mut crop = std::mem::take(&mut self.crop);
        let mut report = self.clean_cut(&mut labels, (w, h), max_hole, (&mut crop, &mut ids));
        // The suit alone: its box (to the frame for the body size) and its rows (the part limits').
        let suit_bounds = bounding_box_of(&labels, w);
        // The suit's rows: the hands lie within them, the head and the shoes above and below.
        let suit_rows = suit_bounds.map_or(0..0, |(_, y0, _, y1)| y0.min(h)..y1.min(h));
        let suit_box = suit_bounds.map(|(x0, y0, x1, y1)| {
            let to_frame = |v: usize, limit: u32| ((v * factor as usize) as u32).min(limit);
            let (fw, fh) = (frame.width(), frame.height());
            (
                to_frame(x0, fw),
                to_frame(y0, fh),
                to_frame(x1, fw),
                to_frame(y1, fh),
            )
        });
        let person = self.attach_person_parts(
            &labels,
            (w, h),
            suit_rows,
            max_hole,
            &mut report,
            (&mut crop, &mut ids),
        );
        self.ids = ids;
        self.crop = crop;
        times.cleanup = ms(started);

        let started = Instant::now();
        let mut mask = self.refine(frame, &person, w, h);
        snap_to_colour_edges(frame, &mut mask, self.options.snap, |rgb| {
            self.gate.marker_index(self.lut.get(rgb))
        });
        if let Some(unmixing) = self.options.unmix {
            unmix_outline(frame, &mut mask, unmixing);
        }
        self.fill_mask_suit_holes(frame, &mut mask, &mut report);
        times.refine = ms(started);

        // History for the next frame.
        let started = Instant::now();
        self.adapt_background(&person);
        self.before_previous_mask = self.previous_mask.take();
        self.previous_mask = Some(labels);
        std::mem::swap(
            self.previous.get_or_insert_with(FrameFeatures::default),
            &mut self.features,
        );
        times.history = ms(started);
        Segmentation {
            mask,
            suit_box,
            cleanup: report,
            flow: result.flow,
            times,
            passes: 1,
            looked_again: false,
        }
    }

    /// The suit is where its pattern is: takes out of the cut `labels` the pixels far from any
    /// pixel of the pattern (a yellow-green or orange region next to the suit that the smoothness
    /// pulled in). This is `features::suit_support` on the cut's pixels only, with the looser
    /// seeds of `features::is_near_pattern`: a 3-4 chamfer distance of at most 3 · SUIT_RADIUS = 6
    /// is one of these 13 offsets.
    fn keep_near_pattern(&self, labels: &mut [bool], w: usize, h: usize) {
        let seed = |j: usize| is_near_pattern(&self.features, &self.gate, j);
        const NEAR: [(isize, isize); 13] = [
            (0, 0),
            (-1, 0),
            (1, 0),
            (0, -1),
            (0, 1),
            (-1, -1),
            (1, -1),
            (-1, 1),
            (1, 1),
            (-2, 0),
            (2, 0),
            (0, -2),
            (0, 2),
        ];
        debug_assert_eq!(super::features::SUIT_RADIUS, 2);
        if let Some(b) = PixelBox::around(labels, w, h, 0) {
            for y in b.y0..b.y1 {
                for x in b.x0..b.x1 {
                    let i = y * w + x;
                    if labels[i] {
                        labels[i] = NEAR.iter().any(|&(dx, dy)| {
                            let (nx, ny) = (x as isize + dx, y as isize + dy);
                            nx >= 0
                                && ny >= 0
                                && (nx as usize) < w
                                && (ny as usize) < h
                                && seed(ny as usize * w + nx as usize)
                        });
                    }
                }
            }
        }
    }

    /// The clean-up of the cut (see [`clean`]): the person's region kept and its small holes
    /// filled, then the pieces that are not cloth and too large for a marker and the cloth far
    /// from every marker taken out. Returns what it changed.
    fn clean_cut(
        &mut self,
        labels: &mut [bool],
        (w, h): (usize, usize),
        max_hole: usize,
        (crop, ids): (&mut Vec<bool>, &mut Vec<u32>),
    ) -> CleanupReport {
        let n = (w * h) as f32;
        let (colours, pattern) = (&self.features.colour, &self.features.pattern);
        // Suit cloth next to a marker: what only the suit looks like (a red poster is all marker
        // colour, a lawn all cloth colour, neither has the two interleaved).
        let score = |i: usize| {
            if is_suit_pattern(pattern[i], 3) && self.gate.is_cloth(colours[i]) {
                1.0
            } else {
                0.01
            }
        };
        let marker = |i: usize| self.gate.is_marker(colours[i]);
        let rule = RegionRule {
            score: &score,
            marker: &marker,
            min_area: (self.options.min_person_fraction * n).ceil() as usize,
            reach: self.options.piece_reach,
        };
        let mut report = clean(labels, w, h, Some(&rule), max_hole, crop, ids);
        // Pieces of the cut that are not cloth and larger than a few markers are background.
        if self.options.off_cloth_max_markers > 0.0 {
            let side = self.marker_side_share * region_height(labels, w) as f32;
            let max_area = (self.options.off_cloth_max_markers * side * side).ceil() as usize;
            let gate = &self.gate;
            (report.off_cloth_pieces, report.off_cloth_pixels) = remove_large_off_cloth(
                labels,
                w,
                h,
                |i| colours[i].chromatic && !gate.is_cloth(colours[i]),
                max_area,
                crop,
                ids,
            );
        }
        // Cloth farther from every marker than the suit's can be is a cloth-coloured object.
        if self.options.cloth_reach_cm > 0.0 {
            let area = labels.iter().filter(|&&l| l).count() as f32;
            let height = (region_height(labels, w) as f32).max((area / STANDING_AREA_SHARE).sqrt());
            let reach = (self.options.cloth_reach_cm / PERSON_HEIGHT_CM * height).ceil() as usize;
            // A marker the cut left out is a hole up to a marker's size across.
            let hole = (self.marker_side_share * height).ceil() as usize + 1;
            let gate = &self.gate;
            report.far_from_markers_pixels = remove_far_from_markers(
                labels,
                w,
                h,
                |i| gate.is_marker(colours[i]),
                (reach, hole),
                &mut self.distance,
            );
        }
        report
    }

    /// The head, hands and shoes attached to the cleaned cut `labels` (the suit; `suit_rows` its
    /// rows): the part bands' pixels that look like a part ([`attach_parts_narrowing`]), again
    /// without the memory where that took back a head, and a last look where a head or shoes
    /// are expected and less was found; the parts are remembered for the next frame and their
    /// colours learned. Returns the person: suit and parts, its small holes filled.
    fn attach_person_parts(
        &mut self,
        labels: &[bool],
        (w, h): (usize, usize),
        suit_rows: std::ops::Range<usize>,
        max_hole: usize,
        report: &mut CleanupReport,
        (crop, ids): (&mut Vec<bool>, &mut Vec<u32>),
    ) -> Vec<bool> {
        let colours = &self.features.colour;
        // The parts outside the suit: band pixels whose colour is likelier a part than background.
        let mut person = labels.to_vec();
        part_bands(
            labels,
            w,
            h,
            (self.options.part_reach, self.options.part_reach_narrow),
            &mut self.distance,
            (&mut self.band, &mut self.narrow_band),
        );
        let sigma = self.tables.weights.colour;
        let (part_nll, prior, bg) = (&self.part_bin, self.tables.part_prior, &self.background_bin);
        let hand_nll = &self.hand_bin;
        let hand_rows = &suit_rows;
        let suit_area = labels.iter().filter(|&&l| l).count() as f32;
        let memory = if self.previous_parts.len() == w * h {
            self.options.part_memory
        } else {
            0.0
        };
        let previous_parts = &self.previous_parts;
        let room_seen = &self.room_seen;
        // Where a head and shoes are expected, for the last look below.
        let part_look = self.options.part_look;
        let px_per_cm = suit_rows.len() as f32 / PERSON_HEIGHT_CM;
        // Both are made (grid-sized) whenever either can be looked for; how many pixels each
        // expects (0: none, or no look).
        let may_look = part_look > 0.0 && !suit_rows.is_empty();
        let (head_expected, shoes_expected) = if may_look {
            (
                expected_head(labels, w, suit_rows.start, px_per_cm, &mut self.head_prior),
                expected_shoes(labels, w, suit_rows.end, px_per_cm, &mut self.shoe_prior),
            )
        } else {
            (0, 0)
        };
        // Where the suit's arms end: the hands' ellipses, kept for the last look below.
        let hand_px_per_cm = suit_rows.len() as f32 / SUIT_HEIGHT_CM;
        self.hand_prior.clear();
        self.hand_prior.resize(w * h, false);
        let hand_ends = if may_look && self.options.hand_look > 0.0 {
            arm_ends(
                labels,
                w,
                suit_rows.clone(),
                hand_px_per_cm,
                &mut self.arm_scratch,
            )
        } else {
            Vec::new()
        };
        // Each hand's pixels (its ellipse outside the suit).
        let hands: Vec<Vec<usize>> = hand_ends
            .iter()
            .map(|end| {
                let mut pixels = Vec::new();
                hand_pixels(labels, w, end, hand_px_per_cm, &mut pixels);
                for &i in &pixels {
                    self.hand_prior[i] = true;
                }
                pixels
            })
            .collect();
        let hand_look = self.options.hand_look;
        let (head_prior, shoe_prior) = (&self.head_prior, &self.shoe_prior);
        let hand_prior = &self.hand_prior;
        let part_like_looking = |remember: bool, looking: bool| {
            move |i: usize| {
                if room_seen[i] {
                    return false;
                }
                let bin = colours[i].bin as usize;
                let remembered = if remember && previous_parts[i] {
                    memory
                } else {
                    0.0
                } + if looking && (head_prior[i] || shoe_prior[i]) {
                    part_look
                } else {
                    0.0
                } + if looking && hand_prior[i] {
                    hand_look
                } else {
                    0.0
                };
                let nll = if hand_rows.contains(&(i / w)) {
                    hand_nll[bin]
                } else {
                    part_nll[bin]
                };
                sigma * nll + prior[1] - remembered < sigma * bg[bin] + prior[0]
            }
        };
        let part_like = |remember: bool| part_like_looking(remember, false);
        let limits = PartLimits {
            max_area: (self.options.part_max_share * suit_area) as usize,
            max_top_area: (self.options.part_max_top_share * suit_area) as usize,
            max_round_area: (self.options.part_max_round_share * suit_area) as usize,
            min_depth: self.options.part_min_depth * suit_rows.len() as f32,
            max_side_depth: self.options.part_max_side_depth * suit_rows.len() as f32,
        };
        let mut attached = attach_parts_narrowing(
            &mut person,
            (&self.band, &self.narrow_band),
            w,
            h,
            part_like(memory > 0.0),
            limits,
            &mut self.part,
            &mut self.stack,
            &mut self.narrow_parts,
        );
        if memory > 0.0 && attached.taken_back_at_top > 0 {
            // The memory can join a head to background beside it into a piece too large for a
            // head, which is then taken back whole: the pieces found without it are added too.
            let (plain_person, plain_part) = &mut self.plain_parts;
            plain_person.clear();
            plain_person.extend_from_slice(labels);
            attach_parts_narrowing(
                plain_person,
                (&self.band, &self.narrow_band),
                w,
                h,
                part_like(false),
                limits,
                plain_part,
                &mut self.stack,
                &mut self.narrow_parts,
            );
            attached.added += add_parts(&mut person, &mut self.part, plain_part);
        }
        // Less found above the suit's top row than a head's area, or below its bottom row than
        // the shoes': a last look for them within the ellipses where they are expected.
        let lacking =
            |found: &[bool], expected: usize| found.iter().filter(|&&p| p).count() < expected;
        let (above, below) = self.part.split_at(suit_rows.start * w);
        let below = &below[(suit_rows.len() * w).min(below.len())..];
        let look_head = lacking(above, head_expected);
        let look_shoes = lacking(below, shoes_expected);
        // The hands of which less than a share of their ellipse was found.
        self.hand_marks.clear();
        self.hand_marks.resize(w * h, false);
        let mut look_hands = false;
        for pixels in &hands {
            let found = pixels.iter().filter(|&&i| self.part[i]).count();
            if (found as f32) < HAND_FOUND_SHARE * pixels.len() as f32 {
                look_hands = true;
                for &i in pixels {
                    self.hand_marks[i] = true;
                }
            }
        }
        if look_head || look_shoes || look_hands {
            let (look_person, look_part) = &mut self.look_parts;
            look_person.clone_from(&person);
            self.look_band.clear();
            self.look_band.extend(
                self.band
                    .iter()
                    .zip(head_prior.iter().zip(shoe_prior.iter()))
                    .zip(self.hand_marks.iter())
                    .map(|((&b, (&head, &shoe)), &hand)| {
                        b && ((look_head && head) || (look_shoes && shoe) || hand)
                    }),
            );
            attach_parts(
                look_person,
                &self.look_band,
                w,
                h,
                part_like_looking(memory > 0.0, true),
                limits,
                look_part,
                &mut self.stack,
            );
            attached.added += add_parts(&mut person, &mut self.part, look_part);
        }
        // The head and the shoes: the parts above the suit's top row and below its bottom row
        // (none with nobody in the frame). On a stream's first frame, segmented in several
        // passes, each look remembers the one before.
        if self.options.part_memory > 0.0 {
            grow_square_into(
                &self.part,
                (w, h),
                (0, 0, w, h),
                PART_MEMORY_RADIUS,
                |y| !suit_rows.contains(&y),
                &mut self.grown_rows,
                &mut self.previous_parts,
            );
        }
        self.adapt_part_colours(w, suit_rows);
        if attached.added > 0 {
            let filled = clean(&mut person, w, h, None, max_hole, crop, ids);
            report.holes_filled += filled.holes_filled;
            report.pixels_filled += filled.pixels_filled;
        }
        person
    }

    /// Fills the enclosed holes of the full-resolution `mask` that are small and mostly of the
    /// suit's colours ([`fill_suit_holes`]; [`SegmenterOptions::suit_hole_markers`]).
    fn fill_mask_suit_holes(
        &mut self,
        frame: &RgbImage,
        mask: &mut Mask,
        report: &mut CleanupReport,
    ) {
        if self.options.suit_hole_markers > 0.0 {
            let height = mask.bounding_box().map_or(0, |(_, y0, _, y1)| y1 - y0) as f32;
            let side = self.marker_side_share * height;
            let max_hole = (self.options.suit_hole_markers * side * side) as usize;
            let (fw, fh) = (frame.width() as usize, frame.height() as usize);
            let (gate, lut, pixels) = (&self.gate, &self.lut, frame.as_raw());
            let is_suit = |i: usize| {
                let c = lut.get([pixels[3 * i], pixels[3 * i + 1], pixels[3 * i + 2]]);
                gate.is_marker(c) || gate.is_cloth(c)
            };
            (report.suit_holes_filled, report.suit_hole_pixels) = fill_suit_holes(
                mask.pixels_mut(),
                (fw, fh),
                (max_hole, SUIT_HOLE_MIN_SHARE),
                is_suit,
                &mut self.hole_runs,
                &mut self.hole_parent,
            );
        }
    }

    /// Pattern class of low-resolution pixel `i` of the frame being refined.
    fn pattern_at(&self, i: usize) -> u8 {
        self.features.pattern.get(i).copied().unwrap_or(u8::MAX)
    }

    /// Upsamples the low-resolution labels to the frame; pixels whose bilinear neighbourhood is mixed
    /// are decided by their own colour against the upsampled cut.
    fn refine(&self, frame: &RgbImage, labels: &[bool], w: usize, h: usize) -> Mask {
        let (fw, fh) = (frame.width(), frame.height());
        let f = self.tables.cut_factor(fh) as f32;
        // A cell with no corner in the box around the person grown by a pixel is background and
        // not near an edge: the output there stays background (all of it without a person).
        let Some(b) = PixelBox::around(labels, w, h, 1) else {
            return Mask::empty(fw, fh);
        };
        let mut out = vec![false; fw as usize * fh as usize];
        let sigma = self.tables.weights.colour;
        let prior = self.options.refine_prior;
        let raw = frame.as_raw();
        // Low-resolution pixels with a differently labelled pixel among their 8 neighbours: with a
        // wide band, the cells around them are decided per pixel too (the cut, at half the
        // resolution, can be a pixel off, and that pixel is two at full resolution).
        let wide = self.options.refine_wide;
        let near = if wide {
            mixed_3x3_in(labels, w, h, b)
        } else {
            Vec::new()
        };
        let fw_us = fw as usize;
        // Per output column: the low-resolution column it interpolates from, and where the run of
        // output columns sharing that cell (x0, x0 + 1) ends. The same for every row, so computed
        // once: finding the runs per row and pixel took half of this stage's time at 1440x1080.
        let column = |x: usize| ((x as f32 + 0.5) / f - 0.5).clamp(0.0, (w - 1) as f32);
        let columns: Vec<f32> = (0..fw_us).map(column).collect();
        let mut run_end = vec![fw_us; fw_us];
        for x in (0..fw_us.saturating_sub(1)).rev() {
            run_end[x] = if columns[x + 1] as usize == columns[x] as usize {
                run_end[x + 1]
            } else {
                x + 1
            };
        }
        let touches = |c0: usize, start: usize, end: usize| c0 + 1 >= start && c0 < end;
        let first_x = columns
            .iter()
            .position(|&c| touches(c as usize, b.x0, b.x1))
            .unwrap_or(fw_us);
        let end_x = columns
            .iter()
            .position(|&c| c as usize >= b.x1)
            .unwrap_or(fw_us);
        for y in 0..fh as usize {
            let sy = ((y as f32 + 0.5) / f - 0.5).clamp(0.0, (h - 1) as f32);
            let (y0, ty) = (sy as usize, sy.fract());
            if !touches(y0, b.y0, b.y1) {
                continue;
            }
            let y1 = (y0 + 1).min(h - 1);
            let row = &mut out[y * fw_us..(y + 1) * fw_us];
            let mut x = first_x;
            while x < end_x {
                let x0 = columns[x] as usize;
                let x1 = (x0 + 1).min(w - 1);
                let end = run_end[x];
                let corners = [
                    labels[y0 * w + x0],
                    labels[y0 * w + x1],
                    labels[y1 * w + x0],
                    labels[y1 * w + x1],
                ];
                let uniform = corners.iter().all(|&c| c == corners[0]);
                let close = wide
                    && (near[y0 * w + x0]
                        || near[y0 * w + x1]
                        || near[y1 * w + x0]
                        || near[y1 * w + x1]);
                if uniform && !close {
                    row[x..end].fill(corners[0]);
                    x = end;
                    continue;
                }
                for (xx, value) in row.iter_mut().enumerate().take(end).skip(x) {
                    let sx = columns[xx];
                    let tx = sx - x0 as f32;
                    let l = |c: bool| c as u8 as f32;
                    let m = (l(corners[0]) * (1.0 - tx) + l(corners[1]) * tx) * (1.0 - ty)
                        + (l(corners[2]) * (1.0 - tx) + l(corners[3]) * tx) * ty;
                    *value = if m <= 0.0 && !close {
                        false
                    } else if m >= 1.0 && !close {
                        true
                    } else {
                        let p = (y * fw_us + xx) * 3;
                        let c = self.lut.get([raw[p], raw[p + 1], raw[p + 2]]);
                        let near =
                            (sx.round() as usize).min(w - 1) + (sy.round() as usize).min(h - 1) * w;
                        let k = colour_index(c, self.pattern_at(near));
                        let suit = sigma * self.tables.colour[1][k];
                        let fg = if self.part.get(near).copied().unwrap_or(false) {
                            suit.min(sigma * self.part_bin[c.bin as usize])
                        } else {
                            suit
                        };
                        let e_fg = fg + prior * (1.0 - m);
                        let e_bg = sigma * self.background_colour[k] + prior * m;
                        e_fg < e_bg
                    };
                }
                x = end;
            }
        }
        Mask::from_pixels(fw, fh, out).unwrap_or_else(|| Mask::empty(fw, fh))
    }
}

/// [`mixed_3x3_in`], finding the box itself.
#[cfg(test)]
fn mixed_3x3(labels: &[bool], w: usize, h: usize) -> Vec<bool> {
    match PixelBox::around(labels, w, h, 1) {
        Some(b) => mixed_3x3_in(labels, w, h, b),
        None => vec![false; w * h],
    }
}

/// Per pixel of a `w`×`h` label grid: does its 3×3 neighbourhood (clipped at the border) hold both
/// labels? Row-wise any/all over three columns, then over three rows, inside `b`, the box around
/// the set pixels grown by one: only pixels in it can be mixed, and windows clipped to it see the
/// same labels (its edge is unset, and so is everything beyond).
fn mixed_3x3_in(labels: &[bool], w: usize, h: usize, b: PixelBox) -> Vec<bool> {
    let mut mixed = vec![false; w * h];
    let (bw, bh) = (b.width(), b.height());
    let (mut any, mut all) = (vec![false; bw * bh], vec![false; bw * bh]);
    for y in 0..bh {
        let row = &labels[(b.y0 + y) * w + b.x0..(b.y0 + y) * w + b.x1];
        for x in 0..bw {
            let window = &row[x.saturating_sub(1)..(x + 2).min(bw)];
            any[y * bw + x] = window.iter().any(|&l| l);
            all[y * bw + x] = window.iter().all(|&l| l);
        }
    }
    for y in 0..bh {
        let (y0, y1) = (y.saturating_sub(1), (y + 2).min(bh));
        for x in 0..bw {
            let some = (y0..y1).any(|ny| any[ny * bw + x]);
            let every = (y0..y1).all(|ny| all[ny * bw + x]);
            mixed[(b.y0 + y) * w + b.x0 + x] = some && !every;
        }
    }
    mixed
}

fn ms(started: Instant) -> f64 {
    started.elapsed().as_secs_f64() * 1e3
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_histogram_counts_each_bin_once_per_pixel_and_sums_to_one() {
        // Bins 3, 3, 5, 3: three quarters in bin 3, a quarter in bin 5.
        let mut counts = BinHistogram::new();
        [3, 3, 5, 3].into_iter().for_each(|bin| counts.add(bin));
        let histogram = counts.normalised().expect("four pixels");
        assert_eq!(histogram.len(), COLOUR_BINS);
        assert_eq!((histogram[3], histogram[5]), (0.75, 0.25));
        assert_eq!(histogram.iter().sum::<f32>(), 1.0);
        assert_eq!(BinHistogram::new().normalised(), None);
    }

    #[test]
    fn the_first_histogram_is_taken_whole_and_later_ones_blended_at_the_rate() {
        let mut online = None;
        assert_eq!(blend_online(&mut online, vec![1.0, 0.0], 0.25), [1.0, 0.0]);
        // 0.75 · (1, 0) + 0.25 · (0, 1).
        assert_eq!(
            blend_online(&mut online, vec![0.0, 1.0], 0.25),
            [0.75, 0.25]
        );
        assert_eq!(online, Some(vec![0.75, 0.25]));
    }

    #[test]
    fn the_hands_table_leans_on_the_persons_own_colours_at_its_own_share() {
        // Two bins: the training subjects' parts fill both alike (p = 0.5 each), this person's
        // head shows only bin 1.
        let trained = [2f32.ln(), 2f32.ln()];
        let online = [0.0, 1.0];
        let (mut part, mut hand) = ([0.0; 2], [0.0; 2]);
        mix_part_tables(&trained, &online, (0.3, 0.75), (&mut part, &mut hand));
        // Head and shoes: 0.7 · 0.5 = 0.35 and 0.35 + 0.3 = 0.65.
        assert!((part[0] + 0.35f32.ln()).abs() < 1e-6 && (part[1] + 0.65f32.ln()).abs() < 1e-6);
        // Hands: 0.25 · 0.5 = 0.125 and 0.125 + 0.75 = 0.875.
        assert!((hand[0] + 0.125f32.ln()).abs() < 1e-6 && (hand[1] + 0.875f32.ln()).abs() < 1e-6);
    }

    #[test]
    fn a_trained_entry_mixes_with_the_online_share_of_the_probability() {
        // Share 0: the trained NLL itself; share 1: −ln of the online part alone.
        assert!((mixed_nll(2.0, 0.0, 0.0) - 2.0).abs() < 1e-6);
        assert!((mixed_nll(2.0, 1.0, 0.5) - 2.0f32.ln()).abs() < 1e-6);
        // Half of e^0 = 1 and half of 0.5 of the online: p = 0.5 + 0.25 = 0.75.
        assert!((mixed_nll(0.0, 0.5, 0.5) + 0.75f32.ln()).abs() < 1e-6);
        // Nothing in either: the floor, 1e-6.
        assert!((mixed_nll(f32::INFINITY, 0.5, 0.0) + 1e-6f32.ln()).abs() < 1e-3);
    }

    #[test]
    fn mixed_3x3_marks_both_sides_of_a_label_edge() {
        // Two columns of person on the left of a 4×4 grid: columns 1 and 2 see both labels.
        let labels: Vec<bool> = (0..16).map(|i| i % 4 < 2).collect();
        let expected: Vec<bool> = (0..16).map(|i| matches!(i % 4, 1 | 2)).collect();
        assert_eq!(mixed_3x3(&labels, 4, 4), expected);
        // One person pixel in the corner: it and its three neighbours.
        let mut corner = vec![false; 16];
        corner[15] = true;
        let mixed: Vec<usize> = (0..16).filter(|&i| mixed_3x3(&corner, 4, 4)[i]).collect();
        assert_eq!(mixed, vec![10, 11, 14, 15]);
    }

    #[test]
    fn mixed_3x3_agrees_with_the_window_definition() {
        let (w, h) = (7, 5);
        let mut r = 3u32;
        let labels: Vec<bool> = (0..w * h)
            .map(|_| {
                r = r.wrapping_mul(1_103_515_245).wrapping_add(12_345);
                (r >> 16).is_multiple_of(3)
            })
            .collect();
        let mixed = mixed_3x3(&labels, w, h);
        for y in 0..h {
            for x in 0..w {
                let window: Vec<bool> = (y.saturating_sub(1)..(y + 2).min(h))
                    .flat_map(|ny| (x.saturating_sub(1)..(x + 2).min(w)).map(move |nx| (nx, ny)))
                    .map(|(nx, ny)| labels[ny * w + nx])
                    .collect();
                let both = window.contains(&true) && window.contains(&false);
                assert_eq!(mixed[y * w + x], both, "({x}, {y})");
            }
        }
    }
}
