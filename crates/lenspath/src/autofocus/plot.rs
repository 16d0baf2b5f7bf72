//! Autofocus plots as SVG: the focus curve (the measure against the sensor
//! position, one series of points per strategy, vertical lines at chosen
//! positions) and the working range (accuracy against light).

use std::fmt::Write;

use super::search::Evaluation;

/// Colours of successive series.
const COLOURS: [&str; 6] = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b"];

/// One strategy's points on the plot.
pub struct Series<'a> {
    /// Legend label.
    pub label: &'a str,
    /// Its evaluations.
    pub points: &'a [Evaluation],
    /// The sensor position it chose, drawn as a vertical line.
    pub chosen_mm: Option<f64>,
    /// Join the points with a line (for a sweep) instead of drawing them as dots.
    pub line: bool,
}

/// An SVG plot of `series`, with `truth_mm` (if any) as a dashed black line.
/// Scores are scaled so each series' maximum is 1, since series rendered at
/// different sample counts differ in scale.
pub fn focus_curve_svg(title: &str, series: &[Series], truth_mm: Option<f64>) -> String {
    let xs = series
        .iter()
        .flat_map(|s| s.points.iter().map(|e| e.sensor_depth_mm).chain(s.chosen_mm))
        .chain(truth_mm);
    let chart = Chart::new(
        title,
        span(xs),
        "sensor position behind the stop (mm)",
        "focus measure (each series scaled to its maximum)",
        3,
    );
    let mut svg = chart.start();
    if let Some(t) = truth_mm {
        chart.vertical(&mut svg, t, "black", r#" stroke-dasharray="5,4""#);
    }
    for (i, s) in series.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        let max = s.points.iter().map(|e| e.score).fold(0.0f64, f64::max);
        let scale = if max > 0.0 { 1.0 / max } else { 0.0 };
        let mut points: Vec<(f64, f64)> = s.points.iter().map(|e| (e.sensor_depth_mm, e.score * scale)).collect();
        if s.line {
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            chart.polyline(&mut svg, &points, colour);
        } else {
            chart.dots(&mut svg, &points, colour);
        }
        if let Some(z) = s.chosen_mm {
            chart.vertical(&mut svg, z, colour, "");
        }
        chart.legend(&mut svg, i, Some(colour), s.label);
    }
    if truth_mm.is_some() {
        chart.legend(&mut svg, series.len(), None, "- - - ground truth");
    }
    svg.push_str("</svg>\n");
    svg
}

/// An SVG plot of autofocus accuracy against light: per strategy, the
/// fraction of runs within 1 DoF (0 to 1) at each scene luminance in EV
/// (ISO 100), points joined by lines.
pub fn working_range_svg(title: &str, series: &[(&str, Vec<(f64, f64)>)]) -> String {
    let chart = Chart::new(
        title,
        span(series.iter().flat_map(|(_, points)| points.iter().map(|p| p.0))),
        "scene luminance (EV at ISO 100)",
        "runs within 1 DoF",
        1,
    );
    let mut svg = chart.start();
    for (i, (label, points)) in series.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        chart.polyline(&mut svg, points, colour);
        chart.dots(&mut svg, points, colour);
        chart.legend(&mut svg, i, Some(colour), label);
    }
    svg.push_str("</svg>\n");
    svg
}

/// The range of `xs`, widened to a unit when it is empty or one value.
fn span(xs: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x), b.max(x)));
    if !lo.is_finite() {
        (0.0, 1.0)
    } else if hi <= lo {
        (lo - 0.5, lo + 0.5)
    } else {
        (lo, hi)
    }
}

/// A plot's frame: x from its span, y from 0 to 1, axes with five ticks.
struct Chart<'a> {
    title: &'a str,
    x_span: (f64, f64),
    x_label: &'a str,
    y_label: &'a str,
    /// Decimals of the x ticks.
    x_decimals: usize,
}

impl<'a> Chart<'a> {
    const WIDTH: f64 = 720.0;
    const HEIGHT: f64 = 420.0;
    const MARGIN: f64 = 56.0;

    fn new(title: &'a str, x_span: (f64, f64), x_label: &'a str, y_label: &'a str, x_decimals: usize) -> Chart<'a> {
        Chart {
            title,
            x_span,
            x_label,
            y_label,
            x_decimals,
        }
    }

    fn px(&self, x: f64) -> f64 {
        let (lo, hi) = self.x_span;
        Self::MARGIN + (x - lo) / (hi - lo) * (Self::WIDTH - 2.0 * Self::MARGIN)
    }

    fn py(&self, y: f64) -> f64 {
        Self::HEIGHT - Self::MARGIN - y * (Self::HEIGHT - 2.0 * Self::MARGIN)
    }

    /// The SVG's opening, the title, the axes and their labels.
    fn start(&self) -> String {
        let (w, h, margin) = (Self::WIDTH, Self::HEIGHT, Self::MARGIN);
        let mut svg = String::new();
        let _ = writeln!(
            svg,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="12">"#
        );
        let _ = writeln!(svg, r#"<rect width="{w}" height="{h}" fill="white"/>"#);
        let _ = writeln!(
            svg,
            r#"<text x="{margin}" y="20" font-size="14">{}</text>"#,
            escape(self.title)
        );
        let _ = writeln!(
            svg,
            r#"<path d="M{margin},{} V{} H{}" fill="none" stroke="black"/>"#,
            margin,
            h - margin,
            w - margin
        );
        let (lo, hi) = self.x_span;
        for k in 0..=4 {
            let x = lo + (hi - lo) * f64::from(k) / 4.0;
            let _ = writeln!(
                svg,
                r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{x:.decimals$}</text>"#,
                self.px(x),
                h - margin + 16.0,
                decimals = self.x_decimals
            );
        }
        let _ = writeln!(
            svg,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
            w / 2.0,
            h - 12.0,
            escape(self.x_label)
        );
        let _ = writeln!(
            svg,
            r#"<text x="16" y="{:.1}" transform="rotate(-90 16 {:.1})" text-anchor="middle">{}</text>"#,
            h / 2.0,
            h / 2.0,
            escape(self.y_label)
        );
        svg
    }

    /// A vertical line at `x`, with extra attributes `style`.
    fn vertical(&self, svg: &mut String, x: f64, colour: &str, style: &str) {
        let _ = writeln!(
            svg,
            r#"<line x1="{x:.1}" y1="{}" x2="{x:.1}" y2="{}" stroke="{colour}"{style}/>"#,
            Self::MARGIN,
            Self::HEIGHT - Self::MARGIN,
            x = self.px(x)
        );
    }

    fn polyline(&self, svg: &mut String, points: &[(f64, f64)], colour: &str) {
        let path: Vec<String> = points
            .iter()
            .map(|&(x, y)| format!("{:.1},{:.1}", self.px(x), self.py(y)))
            .collect();
        let _ = writeln!(
            svg,
            r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="1.5"/>"#,
            path.join(" ")
        );
    }

    fn dots(&self, svg: &mut String, points: &[(f64, f64)], colour: &str) {
        for &(x, y) in points {
            let _ = writeln!(
                svg,
                r#"<circle cx="{:.1}" cy="{:.1}" r="3.5" fill="{colour}" fill-opacity="0.7"/>"#,
                self.px(x),
                self.py(y)
            );
        }
    }

    /// Legend line `i`: a swatch of `colour` (none: text only) and `label`.
    fn legend(&self, svg: &mut String, i: usize, colour: Option<&str>, label: &str) {
        let (x, y) = (Self::WIDTH - Self::MARGIN - 200.0, 40.0 + 16.0 * i as f64);
        match colour {
            Some(colour) => {
                let _ = writeln!(
                    svg,
                    r#"<rect x="{x:.1}" y="{:.1}" width="10" height="10" fill="{colour}"/><text x="{:.1}" y="{y:.1}">{}</text>"#,
                    y - 9.0,
                    x + 15.0,
                    escape(label)
                );
            }
            None => {
                let _ = writeln!(svg, r#"<text x="{x:.1}" y="{y:.1}">{}</text>"#, escape(label));
            }
        }
    }
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}
