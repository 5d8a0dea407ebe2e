//! A grouped bar chart of per-joint errors, like the source paper's Fig. 4/5: one group of bars
//! per joint, one bar per series (a method, or a measure such as Euler and geodesic error), and a
//! last group with each series' mean.
//!
//! One `Layout` places everything; [`BarChart::svg`] writes it as SVG text (the experiments'
//! chart, for documents) and [`BarChart::image`] draws it with tiny-skia into an RGB image, which
//! `suitcap-train eval --chart` saves as PNG. The image's text uses the overlays' 5×7 bitmap font
//! ([`crate::composite::font`]), the joints' names rotated as in the SVG.

use image::RgbImage;
use tiny_skia::{FillRule, Paint, PathBuilder, Pixmap, Rect, Transform};

use crate::composite::font;

/// One series of bars: a value per joint (degrees) and their mean.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    pub name: String,
    pub values: Vec<f64>,
    pub mean: f64,
}

/// The chart's content.
#[derive(Clone, Debug, PartialEq)]
pub struct BarChart {
    pub title: String,
    pub joints: Vec<String>,
    pub series: Vec<Series>,
}

/// The series' colours, in turn.
const COLOURS: [[u8; 3]; 6] = [
    [0x1f, 0x77, 0xb4],
    [0xff, 0x7f, 0x0e],
    [0x2c, 0xa0, 0x2c],
    [0xd6, 0x27, 0x28],
    [0x94, 0x67, 0xbd],
    [0x8c, 0x56, 0x4b],
];
/// The grid lines' grey.
const GRID: [u8; 3] = [0xdd, 0xdd, 0xdd];
/// The angle of the joints' names below the bars (degrees clockwise from the x axis).
const LABEL_ANGLE_DEG: f32 = 60.0;
/// Pixels of the image per unit of the layout (the SVG's units).
const IMAGE_SCALE: f32 = 2.0;

/// Where everything goes, in the SVG's units (pixels at 1:1).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Layout {
    bar: f64,
    group_width: f64,
    left: f64,
    top: f64,
    plot_height: f64,
    width: f64,
    height: f64,
    /// The value at the top of the plot: four whole steps, so that the five grid lines fall on
    /// whole numbers, at least the largest finite value (and at least 4).
    max: f64,
}

/// One bar: its rectangle and its series' index.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Bar {
    x: f64,
    y: f64,
    width: f64,
    height: f64,
    series: usize,
}

impl Layout {
    fn new(chart: &BarChart) -> Layout {
        let groups = chart.joints.len() + 1;
        let bar = 10.0;
        let group_width = bar * chart.series.len().max(1) as f64 + 8.0;
        let (left, top, plot_height) = (50.0, 40.0, 260.0);
        let max = chart
            .series
            .iter()
            .flat_map(|s| s.values.iter().copied().chain(std::iter::once(s.mean)))
            .filter(|v| v.is_finite())
            .fold(1.0f64, f64::max);
        let max = 4.0 * (max / 4.0).ceil();
        Layout {
            bar,
            group_width,
            left,
            top,
            plot_height,
            width: left + group_width * groups as f64 + 20.0,
            height: top + plot_height + 110.0,
            max,
        }
    }

    /// The height of value `v` in the plot (`v` clamped to 0..=max).
    fn y(&self, v: f64) -> f64 {
        self.top + self.plot_height * (1.0 - v.clamp(0.0, self.max) / self.max)
    }

    /// The horizontal grid lines: (value, height), five from 0 to the top.
    fn ticks(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        (0..=4).map(|k| {
            let v = self.max * k as f64 / 4.0;
            (v, self.y(v))
        })
    }

    /// Every bar of a finite value, group by group (the joints, then the means).
    fn bars<'a>(&'a self, chart: &'a BarChart) -> impl Iterator<Item = Bar> + 'a {
        let joints = chart.joints.len();
        (0..=joints).flat_map(move |g| {
            let x0 = self.group_x(g);
            chart.series.iter().enumerate().filter_map(move |(m, s)| {
                let v = if g < joints {
                    s.values.get(g).copied().unwrap_or(0.0)
                } else {
                    s.mean
                };
                v.is_finite().then(|| Bar {
                    x: x0 + m as f64 * self.bar,
                    y: self.y(v),
                    width: self.bar,
                    height: self.top + self.plot_height - self.y(v),
                    series: m,
                })
            })
        })
    }

    /// The left edge of group `g`'s first bar.
    fn group_x(&self, g: usize) -> f64 {
        self.left + g as f64 * self.group_width + 4.0
    }

    /// Where group `g`'s label starts (it runs down and right at [`LABEL_ANGLE_DEG`]).
    fn label_anchor(&self, g: usize) -> (f64, f64) {
        (
            self.group_x(g) + self.group_width / 2.0,
            self.top + self.plot_height + 8.0,
        )
    }

    /// The top-left corner of series `m`'s legend square.
    fn legend(&self, m: usize) -> (f64, f64) {
        (self.left + m as f64 * 150.0, self.height - 21.0)
    }
}

/// The label under group `g`: the joint's name, or "mean".
fn group_label(chart: &BarChart, g: usize) -> &str {
    chart.joints.get(g).map_or("mean", String::as_str)
}

/// A series' legend text: its name and mean.
fn legend_text(s: &Series) -> String {
    format!("{} ({:.2}°)", s.name, s.mean)
}

fn hex([r, g, b]: [u8; 3]) -> String {
    format!("#{r:02x}{g:02x}{b:02x}")
}

impl BarChart {
    /// The chart as an SVG document.
    pub fn svg(&self) -> String {
        let l = Layout::new(self);
        let mut svg = format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{:.0}\" height=\"{:.0}\" font-family=\"sans-serif\" font-size=\"11\">\n\
             <rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n<text x=\"{}\" y=\"20\" font-size=\"14\">{}</text>\n",
            l.width, l.height, l.left, self.title
        );
        for (v, y) in l.ticks() {
            svg.push_str(&format!(
                "<line x1=\"{}\" x2=\"{:.1}\" y1=\"{y:.1}\" y2=\"{y:.1}\" stroke=\"{}\"/><text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{v:.0}</text>\n",
                l.left,
                l.width - 20.0,
                hex(GRID),
                l.left - 4.0,
                y + 4.0,
            ));
        }
        for b in l.bars(self) {
            svg.push_str(&format!(
                "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"{}\" height=\"{:.1}\" fill=\"{}\"/>\n",
                b.x,
                b.y,
                b.width,
                b.height,
                hex(COLOURS[b.series % COLOURS.len()])
            ));
        }
        for g in 0..=self.joints.len() {
            let (x, y) = l.label_anchor(g);
            svg.push_str(&format!(
                "<text x=\"{x:.1}\" y=\"{y:.1}\" transform=\"rotate({LABEL_ANGLE_DEG} {x:.1} {y:.1})\">{}</text>\n",
                group_label(self, g)
            ));
        }
        for (m, s) in self.series.iter().enumerate() {
            let (x, y) = l.legend(m);
            svg.push_str(&format!(
                "<rect x=\"{x:.1}\" y=\"{y:.1}\" width=\"10\" height=\"10\" fill=\"{}\"/><text x=\"{:.1}\" y=\"{:.1}\">{}</text>\n",
                hex(COLOURS[m % COLOURS.len()]),
                x + 14.0,
                y + 9.0,
                legend_text(s)
            ));
        }
        svg.push_str("</svg>\n");
        svg
    }

    /// The chart drawn into an image, `IMAGE_SCALE` pixels per SVG unit.
    pub fn image(&self) -> RgbImage {
        let l = Layout::new(self);
        let s = IMAGE_SCALE;
        let (width, height) = (
            (l.width as f32 * s).ceil() as u32,
            (l.height as f32 * s).ceil() as u32,
        );
        let Some(mut pixmap) = Pixmap::new(width, height) else {
            return RgbImage::new(width, height);
        };
        pixmap.fill(tiny_skia::Color::WHITE);
        let at = |v: f64| v as f32 * s;
        let black = [0, 0, 0];
        text(
            &mut pixmap,
            &self.title,
            (at(l.left), 8.0 * s),
            3.0,
            0.0,
            black,
        );
        for (v, y) in l.ticks() {
            fill(
                &mut pixmap,
                Rect::from_xywh(at(l.left), at(y), at(l.width - 20.0 - l.left), 1.0),
                GRID,
            );
            let label = format!("{v:.0}");
            let w = label.len() as f32 * font::PITCH_X as f32 * s;
            text(
                &mut pixmap,
                &label,
                (at(l.left - 4.0) - w, at(y) - 3.5 * s),
                s,
                0.0,
                black,
            );
        }
        for b in l.bars(self) {
            fill(
                &mut pixmap,
                Rect::from_xywh(at(b.x), at(b.y), at(b.width), at(b.height)),
                COLOURS[b.series % COLOURS.len()],
            );
        }
        for g in 0..=self.joints.len() {
            let (x, y) = l.label_anchor(g);
            text(
                &mut pixmap,
                group_label(self, g),
                (at(x), at(y)),
                s,
                LABEL_ANGLE_DEG,
                black,
            );
        }
        for (m, series) in self.series.iter().enumerate() {
            let (x, y) = l.legend(m);
            fill(
                &mut pixmap,
                Rect::from_xywh(at(x), at(y), 10.0 * s, 10.0 * s),
                COLOURS[m % COLOURS.len()],
            );
            text(
                &mut pixmap,
                &legend_text(series),
                (at(x + 14.0), at(y + 1.5)),
                s,
                0.0,
                black,
            );
        }
        let mut image = RgbImage::new(width, height);
        for (out, p) in image.pixels_mut().zip(pixmap.pixels()) {
            // Opaque (drawn on white), so premultiplied equals straight.
            out.0 = [p.red(), p.green(), p.blue()];
        }
        image
    }
}

impl BarChart {
    /// [`BarChart::image`] encoded as PNG.
    pub fn png(&self) -> Result<Vec<u8>, image::ImageError> {
        let mut bytes = Vec::new();
        self.image().write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Png,
        )?;
        Ok(bytes)
    }
}

fn paint(rgb: [u8; 3]) -> Paint<'static> {
    let mut paint = Paint::default();
    paint.set_color_rgba8(rgb[0], rgb[1], rgb[2], 255);
    paint
}

/// Fills `rect` (nothing for a rectangle of no area).
fn fill(pixmap: &mut Pixmap, rect: Option<Rect>, rgb: [u8; 3]) {
    if let Some(rect) = rect {
        let mut paint = paint(rgb);
        paint.anti_alias = false;
        pixmap.fill_rect(rect, &paint, Transform::identity(), None);
    }
}

/// Draws `line` in the bitmap font, `scale` pixels per font pixel, its top-left corner at
/// `(x, y)`, turned `angle_deg` clockwise about that corner.
fn text(
    pixmap: &mut Pixmap,
    line: &str,
    (x, y): (f32, f32),
    scale: f32,
    angle_deg: f32,
    rgb: [u8; 3],
) {
    let mut pb = PathBuilder::new();
    for (col, c) in line.chars().enumerate() {
        let left = (col as u32 * font::PITCH_X) as f32 * scale;
        for (gy, x0, x1) in font::runs(c) {
            if let Some(rect) = Rect::from_ltrb(
                left + x0 as f32 * scale,
                gy as f32 * scale,
                left + x1 as f32 * scale,
                (gy + 1) as f32 * scale,
            ) {
                pb.push_rect(rect);
            }
        }
    }
    if let Some(path) = pb.finish() {
        let transform = Transform::from_rotate(angle_deg).post_translate(x, y);
        let mut paint = paint(rgb);
        paint.anti_alias = angle_deg != 0.0;
        pixmap.fill_path(&path, &paint, FillRule::Winding, transform, None);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chart(series: Vec<(&str, Vec<f64>, f64)>) -> BarChart {
        BarChart {
            title: "t".into(),
            joints: vec!["pelvis".into(), "head".into()],
            series: series
                .into_iter()
                .map(|(name, values, mean)| Series {
                    name: name.into(),
                    values,
                    mean,
                })
                .collect(),
        }
    }

    #[test]
    fn one_bar_per_joint_and_series_plus_means() {
        let svg = chart(vec![
            ("fc", vec![2.0, 4.0], 3.0),
            ("hog", vec![1.0, 5.0], 3.0),
        ])
        .svg();
        // 2 series × (2 joints + mean) bars, 2 legend squares, 1 background.
        assert_eq!(svg.matches("<rect").count(), 2 * 3 + 2 + 1);
        assert!(svg.contains(">pelvis<") && svg.contains(">mean<") && svg.contains("fc (3.00°)"));
    }

    #[test]
    fn the_image_has_the_layouts_size_and_its_bars_where_the_layout_puts_them() {
        // Values 2 and 4 of a top of 4: the first bar half the plot's height, the second all of it.
        let c = chart(vec![("euler", vec![2.0, 4.0], 3.0)]);
        let l = Layout::new(&c);
        assert_eq!(l.max, 4.0);
        let image = c.image();
        assert_eq!(
            image.dimensions(),
            (
                (l.width * 2.0).ceil() as u32,
                (l.height * 2.0).ceil() as u32
            )
        );
        let blue = COLOURS[0];
        let pixel = |x: f64, y: f64| image.get_pixel((x * 2.0) as u32, (y * 2.0) as u32).0;
        let bottom = l.top + l.plot_height;
        // Pelvis (group 0): 2 of 4, so blue from half-way down to the bottom, white above.
        let x = l.group_x(0) + l.bar / 2.0;
        assert_eq!(pixel(x, bottom - 1.0), blue);
        assert_eq!(pixel(x, l.top + 0.55 * l.plot_height), blue);
        assert_eq!(pixel(x, l.top + 0.45 * l.plot_height), [255, 255, 255]);
        // Head (group 1): the whole height.
        assert_eq!(pixel(l.group_x(1) + l.bar / 2.0, l.top + 1.0), blue);
    }

    #[test]
    fn a_value_that_is_not_a_number_draws_no_bar_and_does_not_move_the_scale() {
        let c = chart(vec![("euler", vec![f64::NAN, 5.0], f64::INFINITY)]);
        let l = Layout::new(&c);
        // 5 → four steps of 2.
        assert_eq!(l.max, 8.0);
        assert_eq!(l.bars(&c).count(), 1);
        assert_eq!(c.svg().matches("<rect").count(), 1 + 1 + 1);
        let _ = c.image();
    }

    #[test]
    fn an_empty_chart_is_still_a_picture() {
        let c = BarChart {
            title: "nothing".into(),
            joints: Vec::new(),
            series: Vec::new(),
        };
        let image = c.image();
        assert!(image.width() > 0 && image.height() > 0);
        assert!(c.svg().ends_with("</svg>\n"));
    }
}
