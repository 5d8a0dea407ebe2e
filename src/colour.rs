//! HSV colour: the space the suit is defined in and the segmenter and marker detector classify in.
//!
//! Hue is in degrees on the circle [0, 360), saturation and value in [0, 1]. Conversions are the
//! standard hexcone model over RGB in [0, 1].

use serde::{Deserialize, Serialize};

/// A colour as hue (degrees), saturation and value.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Hsv {
    pub hue: f32,
    pub saturation: f32,
    pub value: f32,
}

impl Hsv {
    /// RGB in [0, 1].
    pub fn to_rgb(self) -> [f32; 3] {
        let h = self.hue.rem_euclid(360.0) / 60.0;
        let c = self.value * self.saturation;
        let x = c * (1.0 - (h % 2.0 - 1.0).abs());
        let m = self.value - c;
        let (r, g, b) = match h as u32 {
            0 => (c, x, 0.0),
            1 => (x, c, 0.0),
            2 => (0.0, c, x),
            3 => (0.0, x, c),
            4 => (x, 0.0, c),
            _ => (c, 0.0, x),
        };
        [r + m, g + m, b + m]
    }

    /// From RGB in [0, 1]. Grey (zero saturation) gets hue 0.
    pub fn from_rgb([r, g, b]: [f32; 3]) -> Hsv {
        let max = r.max(g).max(b);
        let min = r.min(g).min(b);
        let delta = max - min;
        let hue = if delta <= 0.0 {
            0.0
        } else if max == r {
            60.0 * ((g - b) / delta).rem_euclid(6.0)
        } else if max == g {
            60.0 * ((b - r) / delta + 2.0)
        } else {
            60.0 * ((r - g) / delta + 4.0)
        };
        let saturation = if max > 0.0 { delta / max } else { 0.0 };
        Hsv {
            hue,
            saturation,
            value: max,
        }
    }
}

/// Smallest absolute difference between two hues, in degrees, in [0, 180].
pub fn hue_distance(a: f32, b: f32) -> f32 {
    let d = (a - b).rem_euclid(360.0);
    d.min(360.0 - d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn primaries_have_the_textbook_hues() {
        let red = Hsv::from_rgb([1.0, 0.0, 0.0]);
        let cyan = Hsv::from_rgb([0.0, 1.0, 1.0]);
        let purple = Hsv::from_rgb([0.5, 0.0, 1.0]);
        assert_eq!((red.hue, red.saturation, red.value), (0.0, 1.0, 1.0));
        assert_eq!(cyan.hue, 180.0);
        assert_eq!(purple.hue, 270.0);
        assert_eq!(Hsv::from_rgb([0.5, 0.5, 0.5]).saturation, 0.0);
    }

    #[test]
    fn round_trip_over_the_hue_circle() {
        for step in 0..72 {
            let hsv = Hsv {
                hue: step as f32 * 5.0,
                saturation: 0.7,
                value: 0.8,
            };
            let back = Hsv::from_rgb(hsv.to_rgb());
            assert!(
                hue_distance(back.hue, hsv.hue) < 1e-3,
                "{hsv:?} -> {back:?}"
            );
            assert!((back.saturation - 0.7).abs() < 1e-5 && (back.value - 0.8).abs() < 1e-5);
        }
    }

    #[test]
    fn hue_distance_wraps() {
        assert_eq!(hue_distance(350.0, 10.0), 20.0);
        assert_eq!(hue_distance(0.0, 180.0), 180.0);
        assert_eq!(hue_distance(-90.0, 270.0), 0.0);
    }
}
