//! Feature Context: for each marker, a log-polar histogram of the markers around it.
//!
//! Source paper sec. 3.1.2. Around each detected marker, the neighbours within radius `R` (found with a
//! `kiddo` k-d tree radius query) are binned by log-distance (5 bins), angle against the image's
//! horizontal axis (12 bins) and colour (3 bins): 180 values, normalised to sum 1. `R` and the distance
//! bins scale with the silhouette's height, so the histogram does not change with the distance to the
//! camera or the person's place in the picture. The per-marker histograms are vector-quantised against
//! the 200-centre Feature Context codebook into the first 200 values of the frame descriptor.

use glam::Vec2;
use kiddo::{KdTree, SquaredEuclidean};

use super::markers::DetectedMarker;

pub const FC_RADIAL: usize = 5;
pub const FC_ANGULAR: usize = 12;
pub const FC_COLOURS: usize = 3;
/// Length of one marker's histogram.
pub const FC_LEN: usize = FC_RADIAL * FC_ANGULAR * FC_COLOURS;
/// The neighbourhood radius as a fraction of the silhouette's height.
pub const FC_RADIUS: f32 = 0.35;

/// Bin of a neighbour at offset `d` (pixels, image axes: x right, y down) with colour `colour`, for
/// radius `radius`; `None` outside the radius. Distance bins have outer edges R/16, R/8, R/4, R/2, R
/// (the first also takes everything nearer); angle bins are 30° wide starting at the +x axis and
/// turning towards −y (up in the image), i.e. counter-clockwise as seen.
pub fn bin(d: Vec2, colour: usize, radius: f32) -> Option<usize> {
    let r = d.length();
    if r > radius || r == 0.0 || colour >= FC_COLOURS {
        return None;
    }
    let radial = ((r / radius).log2() + FC_RADIAL as f32)
        .floor()
        .clamp(0.0, FC_RADIAL as f32 - 1.0) as usize;
    let angle = (-d.y).atan2(d.x).rem_euclid(std::f32::consts::TAU);
    let angular =
        ((angle / std::f32::consts::TAU * FC_ANGULAR as f32) as usize).min(FC_ANGULAR - 1);
    Some((radial * FC_ANGULAR + angular) * FC_COLOURS + colour)
}

/// The Feature Context histogram of every marker, for a silhouette `height` pixels tall, as
/// `markers.len() × FC_LEN` values. A marker with no neighbour has an all-zero histogram.
pub fn feature_contexts(markers: &[DetectedMarker], height: f32) -> Vec<f32> {
    let radius = FC_RADIUS * height;
    let mut out = vec![0.0f32; markers.len() * FC_LEN];
    if markers.len() < 2 || radius.is_nan() || radius <= 0.0 {
        return out;
    }
    let mut tree: KdTree<f32, 2> = KdTree::with_capacity(markers.len());
    for (i, m) in markers.iter().enumerate() {
        tree.add(&[m.centre.x, m.centre.y], i as u64);
    }
    for (i, m) in markers.iter().enumerate() {
        let histogram = &mut out[i * FC_LEN..(i + 1) * FC_LEN];
        let mut count = 0.0f32;
        for neighbour in
            tree.within_unsorted::<SquaredEuclidean>(&[m.centre.x, m.centre.y], radius * radius)
        {
            let j = neighbour.item as usize;
            if j == i {
                continue;
            }
            if let Some(b) = bin(markers[j].centre - m.centre, markers[j].colour, radius) {
                histogram[b] += 1.0;
                count += 1.0;
            }
        }
        if count > 0.0 {
            histogram.iter_mut().for_each(|v| *v /= count);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn marker(x: f32, y: f32, colour: usize) -> DetectedMarker {
        DetectedMarker {
            centre: Vec2::new(x, y),
            colour,
            area: 16,
        }
    }

    #[test]
    fn three_markers_give_the_known_bins() {
        // Height 200 → radius 70. From the marker at (100, 100):
        // - a red marker 20 px to the right: r/R = 0.286 → log2 = −1.81 → radial bin 3; angle 0 → bin 0;
        // - a cyan marker 60 px up: r/R = 0.857 → radial bin 4; angle 90° → angular bin 3.
        let markers = [
            marker(100.0, 100.0, 2),
            marker(120.0, 100.0, 0),
            marker(100.0, 40.0, 1),
        ];
        let fc = feature_contexts(&markers, 200.0);
        let first = &fc[..FC_LEN];
        let red = (3 * FC_ANGULAR) * FC_COLOURS;
        let cyan = (4 * FC_ANGULAR + 3) * FC_COLOURS + 1;
        assert_eq!(first[red], 0.5);
        assert_eq!(first[cyan], 0.5);
        assert_eq!(first.iter().sum::<f32>(), 1.0);
        // The red marker sees the purple one 20 px to its left: angle 180° → angular bin 6.
        let second = &fc[FC_LEN..2 * FC_LEN];
        assert_eq!(second[(3 * FC_ANGULAR + 6) * FC_COLOURS + 2], 0.5);
    }

    /// Whether some neighbour of marker `i` lies within float rounding of a bin edge (radial or angular)
    /// or of the radius: moving the picture may then put it on the other side of that edge.
    fn sees_a_neighbour_on_an_edge(markers: &[DetectedMarker], i: usize, radius: f32) -> bool {
        const EPS: f32 = 1e-3;
        markers.iter().enumerate().any(|(j, n)| {
            let d = n.centre - markers[i].centre;
            let r = d.length();
            if j == i || r > radius * (1.0 + EPS) {
                return false;
            }
            let radial = (r / radius).log2();
            let angular = (-d.y).atan2(d.x).rem_euclid(std::f32::consts::TAU)
                / std::f32::consts::TAU
                * FC_ANGULAR as f32;
            let off_integer = |v: f32| (v - v.round()).abs();
            (radial > -(FC_RADIAL as f32) && off_integer(radial) < EPS)
                || off_integer(angular) < EPS
        })
    }

    #[test]
    fn a_lonely_marker_has_an_empty_histogram() {
        let fc = feature_contexts(&[marker(0.0, 0.0, 0), marker(500.0, 0.0, 1)], 100.0);
        assert!(fc.iter().all(|&v| v == 0.0));
        assert!(feature_contexts(&[], 100.0).is_empty());
    }

    proptest! {
        #[test]
        fn shifting_and_scaling_the_person_leaves_fc_unchanged(
            points in proptest::collection::vec((0.0f32..100.0, 0.0f32..200.0, 0usize..3), 2..40),
            shift in (-300.0f32..300.0, -300.0f32..300.0),
            scale in 0.5f32..3.0,
        ) {
            let markers: Vec<DetectedMarker> = points.iter().map(|&(x, y, c)| marker(x, y, c)).collect();
            let moved: Vec<DetectedMarker> = points
                .iter()
                .map(|&(x, y, c)| marker(x * scale + shift.0, y * scale + shift.1, c))
                .collect();
            let a = feature_contexts(&markers, 200.0);
            let b = feature_contexts(&moved, 200.0 * scale);
            for m in 0..markers.len() {
                // A neighbour exactly on a bin edge may round to the other side after scaling.
                if sees_a_neighbour_on_an_edge(&markers, m, FC_RADIUS * 200.0) {
                    continue;
                }
                let range = m * FC_LEN..(m + 1) * FC_LEN;
                let differing = a[range.clone()].iter().zip(&b[range]).filter(|(p, q)| (*p - *q).abs() > 1e-4).count();
                prop_assert_eq!(differing, 0, "marker {}", m);
            }
        }

        #[test]
        fn rotating_by_180_degrees_moves_each_angle_bin_by_6(
            points in proptest::collection::vec((0.0f32..100.0, 0.0f32..200.0, 0usize..3), 2..30),
        ) {
            let markers: Vec<DetectedMarker> = points.iter().map(|&(x, y, c)| marker(x, y, c)).collect();
            let rotated: Vec<DetectedMarker> = points.iter().map(|&(x, y, c)| marker(500.0 - x, 400.0 - y, c)).collect();
            let a = feature_contexts(&markers, 200.0);
            let b = feature_contexts(&rotated, 200.0);
            for m in 0..markers.len() {
                // A neighbour exactly on a bin edge can fall on the other side after rotation.
                if sees_a_neighbour_on_an_edge(&markers, m, FC_RADIUS * 200.0) {
                    continue;
                }
                let mut differing = 0;
                for r in 0..FC_RADIAL {
                    for t in 0..FC_ANGULAR {
                        for c in 0..FC_COLOURS {
                            let at = |t: usize| m * FC_LEN + (r * FC_ANGULAR + t) * FC_COLOURS + c;
                            if (a[at(t)] - b[at((t + 6) % FC_ANGULAR)]).abs() > 1e-5 {
                                differing += 1;
                            }
                        }
                    }
                }
                prop_assert_eq!(differing, 0, "marker {}", m);
            }
        }
    }
}
