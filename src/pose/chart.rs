//! A grouped bar chart of per-joint errors as SVG, like the source paper's Fig. 4/5: one group of
//! bars per joint, one bar per method, plus each method's mean.

/// `series`: (method name, per-joint values, mean). Values in degrees.
pub fn bar_chart_svg(title: &str, joints: &[String], series: &[(String, Vec<f64>, f64)]) -> String {
    const COLOURS: [&str; 6] = [
        "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b",
    ];
    let groups = joints.len() + 1;
    let bar = 10.0;
    let group_width = bar * series.len().max(1) as f64 + 8.0;
    let (left, top, plot_h) = (50.0, 40.0, 260.0);
    let width = left + group_width * groups as f64 + 20.0;
    let height = top + plot_h + 110.0;
    let max = series
        .iter()
        .flat_map(|s| s.1.iter().copied().chain(std::iter::once(s.2)))
        .fold(1.0f64, f64::max)
        .ceil();
    let y = |v: f64| top + plot_h * (1.0 - v / max);
    let mut svg = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width:.0}\" height=\"{height:.0}\" font-family=\"sans-serif\" font-size=\"11\">\n\
         <rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n<text x=\"{left}\" y=\"20\" font-size=\"14\">{title}</text>\n"
    );
    for k in 0..=4 {
        let v = max * k as f64 / 4.0;
        svg.push_str(&format!(
            "<line x1=\"{left}\" x2=\"{:.1}\" y1=\"{y:.1}\" y2=\"{y:.1}\" stroke=\"#ddd\"/><text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{v:.0}</text>\n",
            width - 20.0,
            left - 4.0,
            y(v) + 4.0,
            y = y(v)
        ));
    }
    for g in 0..groups {
        let x0 = left + g as f64 * group_width + 4.0;
        for (m, (_, values, mean)) in series.iter().enumerate() {
            let v = if g < joints.len() {
                values.get(g).copied().unwrap_or(0.0)
            } else {
                *mean
            };
            svg.push_str(&format!(
                "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"{bar}\" height=\"{:.1}\" fill=\"{}\"/>\n",
                x0 + m as f64 * bar,
                y(v),
                top + plot_h - y(v),
                COLOURS[m % COLOURS.len()]
            ));
        }
        let label = if g < joints.len() {
            joints[g].as_str()
        } else {
            "mean"
        };
        let lx = x0 + group_width / 2.0;
        let ly = top + plot_h + 8.0;
        svg.push_str(&format!("<text x=\"{lx:.1}\" y=\"{ly:.1}\" transform=\"rotate(60 {lx:.1} {ly:.1})\">{label}</text>\n"));
    }
    for (m, (name, _, mean)) in series.iter().enumerate() {
        let x = left + m as f64 * 150.0;
        let ly = height - 12.0;
        svg.push_str(&format!(
            "<rect x=\"{x:.1}\" y=\"{:.1}\" width=\"10\" height=\"10\" fill=\"{}\"/><text x=\"{:.1}\" y=\"{ly:.1}\">{name} ({mean:.2}°)</text>\n",
            ly - 9.0,
            COLOURS[m % COLOURS.len()],
            x + 14.0
        ));
    }
    svg.push_str("</svg>\n");
    svg
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_bar_per_joint_and_method_plus_means() {
        let joints = vec!["pelvis".to_string(), "head".to_string()];
        let series = vec![
            ("fc".to_string(), vec![2.0, 4.0], 3.0),
            ("hog".to_string(), vec![1.0, 5.0], 3.0),
        ];
        let svg = bar_chart_svg("t", &joints, &series);
        // 2 methods × (2 joints + mean) bars, 2 legend squares, 1 background.
        assert_eq!(svg.matches("<rect").count(), 2 * 3 + 2 + 1);
        assert!(svg.contains(">pelvis<") && svg.contains(">mean<") && svg.contains("fc (3.00°)"));
    }
}
