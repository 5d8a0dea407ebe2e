//! Summary statistics over plain slices, shared by the command lines' reports (per-stage
//! timings, depth ratios) and the body-size estimate.

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
}
