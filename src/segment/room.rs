//! The room behind the person, pixel by pixel: what each pixel of the cut's grid showed in the
//! frames in which it lay well away from the person.
//!
//! The segmenter's online background model is a colour histogram over the whole frame: it says
//! which colours the room has, not where. Beside a leg over an orange's pith, or beside a head over
//! cat fur, the room has a skin's colour, and the part test (head, hands, shoes) took it in. A
//! camera on a stand sees the same room behind the person in every frame, so a pixel that now
//! shows what it showed while the person was elsewhere is room, whatever its colour. [`RoomModel`]
//! keeps a running mean of each grid pixel's colour over the frames it was learned in
//! ([`RoomModel::learn`]) and tells whether a pixel shows it again ([`RoomModel::shows_room`]),
//! after this frame's overall brightness is matched to the model's ([`RoomModel::gain`]), so a
//! light turned up or down does not make the whole room look new. A pixel never learned is
//! unknown and left to the colour tables; so is anything that moves in the room (it does not show
//! its running mean) and a room seen by a moving camera. Within the band in which heads, hands and
//! shoes are looked for, the segmenter learns only pixels whose colour is not a part's (a head the
//! part test missed would otherwise be learned as room where it stands, and then never be found
//! again; [`RoomSettings::band_part_odds`]), and forgets the model when it is reset (a new stream,
//! or the camera moved).
//!
//! Gives the segmenter two things: a band pixel that shows the room is not a part, and the cut
//! counts a pixel that shows the room [`RoomSettings::cut_bonus`] nats likelier background.
//!
//! Written here rather than taken from a crate: it is a running mean and a comparison over the
//! cut's grid, and the background subtractors that do more (OpenCV's mixtures of Gaussians) would
//! bring a C++ library into the build.

/// Per grid pixel: the running mean colour over the frames it was learned in, and in how many.
#[derive(Clone, Debug, Default)]
pub struct RoomModel {
    width: usize,
    height: usize,
    mean: Vec<[f32; 3]>,
    frames: Vec<u16>,
}

/// How [`RoomModel`] learns and compares.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoomSettings {
    /// The running mean's weight of a new frame once a pixel has been learned `1/rate` times
    /// (before, every frame counts alike).
    pub rate: f32,
    /// Frames a pixel must have been learned in before it is compared (a stream's first frame,
    /// which the segmenter segments in several passes, is learned in each).
    pub min_frames: u16,
    /// Largest difference in any channel (0–255, after the gain) of a pixel that shows the room.
    pub tolerance: f32,
    /// How much likelier (nats, on the background's energy) the cut counts a pixel that shows
    /// the room to be background.
    pub cut_bonus: f32,
    /// Within the band around the suit where heads, hands and shoes are looked for, a pixel is
    /// learned only if its colour is not likelier a part's than the room's (the segmenter's
    /// part and background colour likelihoods, nats) by more than this: a head the part test
    /// missed, learned as room where it stands, would never be found there again, but the room
    /// between the legs and beside the arms, which the person never leaves for long, would
    /// otherwise never be learned. `f32::NEG_INFINITY`: the band is never learned.
    pub band_part_odds: f32,
}

impl Default for RoomSettings {
    /// Chosen with `suitcap segment --truth` on the nine selection renderings (mean IoU 0.9635
    /// without the room; docs/measurements.md, second session of 2026-12-06): the tolerance at
    /// rate 0.1, two frames and the part test alone: 5 / 7 / **10** / 13 / 16 / 24 / 32 gave
    /// 0.9650 / 0.9651 / **0.9654** / 0.9652 / 0.9648 / 0.9629 / 0.9607; the rate 0.03 / 0.3 and
    /// one or four frames moved it by 0.0001 at most (at tolerance 16). The cut's bonus at
    /// tolerance 10: 2 / **5** / 10 / 20 nats gave 0.9656 / **0.9658** / 0.9661 / 0.9662; 5, not
    /// 20, so that where the room has the suit's colour the suit's own pattern can still win the
    /// cut (above 5 the gain was 0.0004). A pixel that differs from the room counted as a part
    /// (channel difference over 40 or 80) lost 0.027 and 0.019: clutter, light and shadows differ
    /// from the room too. The band's part odds, on the 24 selection renderings
    /// (docs/measurements.md, tenth session of 2026-12-07; the band kept out 0.9507): −4 / −2 /
    /// −1 / 0 / **1** / 2 / 3 / 5 nats gave 0.9510 / 0.9528 / 0.9537 / 0.9537 / **0.9544** /
    /// 0.9540 / 0.9538 / 0.9531.
    fn default() -> RoomSettings {
        RoomSettings {
            rate: 0.1,
            min_frames: 2,
            tolerance: 10.0,
            cut_bonus: 5.0,
            band_part_odds: 1.0,
        }
    }
}

impl RoomModel {
    pub fn new() -> RoomModel {
        RoomModel::default()
    }

    /// Forgets everything (a new stream, or the camera moved).
    pub fn clear(&mut self) {
        self.mean.clear();
        self.frames.clear();
        self.width = 0;
        self.height = 0;
    }

    /// Learns the pixels of `rgb` (`width` × `height`, row-major) that `far` marks; a grid of
    /// another size starts the model afresh.
    pub fn learn(
        &mut self,
        rgb: &[[u8; 3]],
        width: usize,
        height: usize,
        far: &[bool],
        settings: &RoomSettings,
    ) {
        let n = width * height;
        if width != self.width || height != self.height || self.mean.len() != n {
            self.width = width;
            self.height = height;
            self.mean = vec![[0.0; 3]; n];
            self.frames = vec![0; n];
        }
        // The weight of the n-th frame, max(1/n, rate), looked up rather than divided for.
        let settled = (1.0 / settings.rate.max(1e-3)).ceil() as usize;
        let weights: Vec<f32> = (0..=settled)
            .map(|k| (1.0 / k.max(1) as f32).max(settings.rate))
            .collect();
        for (((p, m), count), _) in rgb
            .iter()
            .zip(&mut self.mean)
            .zip(&mut self.frames)
            .zip(far)
            .filter(|(_, &far)| far)
        {
            *count = count.saturating_add(1);
            let weight = weights[(*count as usize).min(settled)];
            for (m, &c) in m.iter_mut().zip(p) {
                *m += weight * (c as f32 - *m);
            }
        }
    }

    /// Whether pixel `i` has been learned often enough to be compared.
    #[inline]
    pub fn knows(&self, i: usize, settings: &RoomSettings) -> bool {
        self.frames
            .get(i)
            .is_some_and(|&n| n >= settings.min_frames.max(1))
    }

    /// The brightness of this frame against the model's: Σ of the channels of `rgb` over Σ of the
    /// means, over the known pixels `use_pixel` accepts (the room away from the person) in every
    /// other row and column (a global figure: a quarter of the pixels give it to well within the
    /// tolerance, at a quarter of the cost); 1 when there are none or the model is of another size.
    pub fn gain(
        &self,
        rgb: &[[u8; 3]],
        use_pixel: impl Fn(usize) -> bool,
        settings: &RoomSettings,
    ) -> f32 {
        if rgb.len() != self.mean.len() {
            return 1.0;
        }
        let (mut now, mut then) = (0.0f64, 0.0f64);
        for y in (0..self.height).step_by(2) {
            let (mut row_now, mut row_then) = (0u32, 0.0f32);
            for i in (y * self.width..(y + 1) * self.width).step_by(2) {
                if self.knows(i, settings) && use_pixel(i) {
                    row_now += rgb[i].iter().map(|&c| c as u32).sum::<u32>();
                    row_then += self.mean[i].iter().sum::<f32>();
                }
            }
            now += row_now as f64;
            then += row_then as f64;
        }
        if then > 0.0 && now > 0.0 {
            (now / then) as f32
        } else {
            1.0
        }
    }

    /// [`RoomModel::shows_room`] of every pixel of `rgb` into `out` (all false when the model is
    /// of another size).
    pub fn room_pixels(
        &self,
        rgb: &[[u8; 3]],
        gain: f32,
        settings: &RoomSettings,
        out: &mut Vec<bool>,
    ) {
        out.clear();
        if rgb.len() != self.mean.len() {
            out.resize(rgb.len(), false);
            return;
        }
        let min_frames = settings.min_frames.max(1);
        out.extend(
            rgb.iter()
                .zip(&self.mean)
                .zip(&self.frames)
                .map(|((&p, m), &n)| n >= min_frames && within(p, m, gain, settings.tolerance)),
        );
    }

    /// Whether pixel `i`, of colour `p`, shows the room it showed before: known, and within the
    /// tolerance of its mean times `gain` in every channel.
    #[inline]
    pub fn shows_room(&self, i: usize, p: [u8; 3], gain: f32, settings: &RoomSettings) -> bool {
        self.knows(i, settings) && within(p, &self.mean[i], gain, settings.tolerance)
    }
}

/// Whether colour `p` lies within `tolerance` of `mean` × `gain` in every channel.
#[inline]
fn within(p: [u8; 3], mean: &[f32; 3], gain: f32, tolerance: f32) -> bool {
    p.iter()
        .zip(mean)
        .all(|(&c, &m)| (c as f32 - gain * m).abs() <= tolerance)
}

#[cfg(test)]
mod tests {
    use super::*;

    const SETTINGS: RoomSettings = RoomSettings {
        rate: 0.25,
        min_frames: 2,
        tolerance: 10.0,
        cut_bonus: 5.0,
        band_part_odds: 1.0,
    };

    #[test]
    fn a_pixel_is_known_after_min_frames_and_its_mean_is_the_average_until_then() {
        let mut room = RoomModel::new();
        // A 2 × 1 grid; only pixel 0 is ever far from the person.
        room.learn(&[[100, 0, 0], [7, 7, 7]], 2, 1, &[true, false], &SETTINGS);
        assert!(!room.knows(0, &SETTINGS));
        room.learn(&[[120, 0, 0], [7, 7, 7]], 2, 1, &[true, false], &SETTINGS);
        assert!(room.knows(0, &SETTINGS));
        assert!(!room.knows(1, &SETTINGS));
        // Two frames weigh ½ each: mean 110.
        assert!(room.shows_room(0, [110, 0, 0], 1.0, &SETTINGS));
        assert!(room.shows_room(0, [120, 0, 0], 1.0, &SETTINGS));
        assert!(!room.shows_room(0, [121, 0, 0], 1.0, &SETTINGS));
        // The unknown pixel never shows the room.
        assert!(!room.shows_room(1, [7, 7, 7], 1.0, &SETTINGS));
        // The whole grid at once says the same.
        let mut seen = Vec::new();
        room.room_pixels(&[[110, 0, 0], [7, 7, 7]], 1.0, &SETTINGS, &mut seen);
        assert_eq!(seen, [true, false]);
        room.room_pixels(&[[110, 0, 0]], 1.0, &SETTINGS, &mut seen);
        assert_eq!(seen, [false]);
    }

    #[test]
    fn after_enough_frames_a_new_frame_weighs_the_rate() {
        let mut room = RoomModel::new();
        for _ in 0..8 {
            room.learn(&[[100, 100, 100]], 1, 1, &[true], &SETTINGS);
        }
        // 100 + 0.25 · (200 − 100) = 125.
        room.learn(&[[200, 200, 200]], 1, 1, &[true], &SETTINGS);
        assert!(room.shows_room(0, [125, 125, 125], 1.0, &SETTINGS));
        assert!(!room.shows_room(0, [136, 125, 125], 1.0, &SETTINGS));
    }

    #[test]
    fn a_brighter_frame_shows_the_same_room_after_the_gain() {
        let mut room = RoomModel::new();
        let before = [[100, 50, 20], [40, 40, 40], [200, 100, 0]];
        for _ in 0..2 {
            room.learn(&before, 3, 1, &[true; 3], &SETTINGS);
        }
        let brighter: Vec<[u8; 3]> = before
            .iter()
            .map(|p| p.map(|c| (c as f32 * 1.2) as u8))
            .collect();
        let gain = room.gain(&brighter, |_| true, &SETTINGS);
        assert!((gain - 1.2).abs() < 0.01, "{gain}");
        assert!(room.shows_room(0, brighter[0], gain, &SETTINGS));
        assert!(!room.shows_room(0, brighter[0], 1.0, &SETTINGS));
        // Pixels the caller leaves out do not count, and no known pixel at all gives 1.
        assert_eq!(room.gain(&brighter, |_| false, &SETTINGS), 1.0);
    }

    #[test]
    fn another_grid_size_starts_afresh_and_clear_forgets() {
        let mut room = RoomModel::new();
        for _ in 0..2 {
            room.learn(&[[9, 9, 9]], 1, 1, &[true], &SETTINGS);
        }
        assert!(room.knows(0, &SETTINGS));
        room.learn(&[[9, 9, 9], [9, 9, 9]], 2, 1, &[true; 2], &SETTINGS);
        assert!(!room.knows(0, &SETTINGS));
        assert_eq!(room.gain(&[[9, 9, 9]], |_| true, &SETTINGS), 1.0);
        room.clear();
        assert!(!room.knows(0, &SETTINGS));
    }
}
