//! Summary statistics and distances over plain slices, shared by the command lines' reports
//! (per-stage timings, depth ratios), the body-size estimate, the RVM and the codebooks' k-means.

/// The median of `values`: the middle value of an odd count, the mean of the two middle values of
/// an even count; `None` when `values` is empty. Sorts a copy in IEEE total order (NaNs last).
pub fn median<T: Copy + Into<f64>>(values: &[T]) -> Option<f64> {
    let mut sorted: Vec<f64> = values.iter().map(|&v| v.into()).collect();
    sorted.sort_by(f64::total_cmp);
    let n = sorted.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(sorted[n / 2]),
        _ => Some(0.5 * (sorted[n / 2 - 1] + sorted[n / 2])),
    }
}

/// Squared Euclidean distance of two `f32` rows (over the shorter's length), summed in eight
/// partial sums so that the compiler can keep them in one vector register.
#[inline]
pub fn squared_distance(a: &[f32], b: &[f32]) -> f32 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0f32; 8];
    let ca = a.chunks_exact(8);
    let cb = b.chunks_exact(8);
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for k in 0..8 {
            let d = x[k] - y[k];
            acc[k] += d * d;
        }
    }
    let mut s = ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]));
    for (x, y) in ra.iter().zip(rb) {
        let d = x - y;
        s += d * d;
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_median_ignores_one_bad_value_and_averages_an_even_count() {
        assert_eq!(median(&[9.0f64, 1.0, 1.1]), Some(1.1));
        assert_eq!(median(&[2.0f32, 1.0]), Some(1.5));
        assert_eq!(median(&[7.0f32]), Some(7.0));
        assert_eq!(median::<f64>(&[]), None);
    }

    #[test]
    fn squared_distance_sums_the_lanes_and_the_remainder() {
        // Eleven values: one chunk of eight and three left over. Differences 1, 2, 0, …, 0 in the
        // chunk and 3, 0, 4 after it: 1 + 4 + 9 + 16 = 30.
        let a = [1.0f32, 2.0, 5.0, 5.0, 5.0, 5.0, 5.0, 5.0, 3.0, 7.0, 4.0];
        let b = [0.0f32, 0.0, 5.0, 5.0, 5.0, 5.0, 5.0, 5.0, 0.0, 7.0, 0.0];
        assert_eq!(squared_distance(&a, &b), 30.0);
        assert_eq!(squared_distance(&b, &a), 30.0);
        // A 3-4-5 triangle, shorter than one chunk; the longer row is cut to the shorter.
        assert_eq!(squared_distance(&[3.0, 4.0], &[0.0, 0.0, 9.0]), 25.0);
        assert_eq!(squared_distance(&[], &[]), 0.0);
    }
}
