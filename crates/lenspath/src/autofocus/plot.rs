//! The focus curve as SVG: the measure against the sensor position, one
//! series of points per strategy, vertical lines at chosen positions.

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
    let (w, h, margin) = (720.0, 420.0, 56.0);
    let xs = series
        .iter()
        .flat_map(|s| s.points.iter().map(|e| e.sensor_z_mm).chain(s.chosen_mm))
        .chain(truth_mm);
    let (mut lo, mut hi) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x), b.max(x)));
    if !lo.is_finite() {
        (lo, hi) = (0.0, 1.0);
    }
    if hi <= lo {
        (lo, hi) = (lo - 0.5, lo + 0.5);
    }
    let px = |z: f64| margin + (z - lo) / (hi - lo) * (w - 2.0 * margin);
    let py = |v: f64| h - margin - v * (h - 2.0 * margin);
    let mut svg = String::new();
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(svg, r#"<rect width="{w}" height="{h}" fill="white"/>"#);
    let _ = writeln!(
        svg,
        r#"<text x="{margin}" y="20" font-size="14">{}</text>"#,
        escape(title)
    );
    // Axes with five ticks.
    let _ = writeln!(
        svg,
        r#"<path d="M{margin},{} V{} H{}" fill="none" stroke="black"/>"#,
        margin,
        h - margin,
        w - margin
    );
    for k in 0..=4 {
        let z = lo + (hi - lo) * f64::from(k) / 4.0;
        let _ = writeln!(
            svg,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{z:.3}</text>"#,
            px(z),
            h - margin + 16.0
        );
    }
    let _ = writeln!(
        svg,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">sensor position behind the stop (mm)</text>"#,
        w / 2.0,
        h - 12.0
    );
    let _ = writeln!(
        svg,
        r#"<text x="16" y="{:.1}" transform="rotate(-90 16 {:.1})" text-anchor="middle">focus measure (each series scaled to its maximum)</text>"#,
        h / 2.0,
        h / 2.0
    );
    if let Some(t) = truth_mm {
        let _ = writeln!(
            svg,
            r#"<line x1="{x:.1}" y1="{}" x2="{x:.1}" y2="{}" stroke="black" stroke-dasharray="5,4"/>"#,
            margin,
            h - margin,
            x = px(t)
        );
    }
    for (i, s) in series.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        let max = s.points.iter().map(|e| e.score).fold(0.0f64, f64::max);
        let scale = if max > 0.0 { 1.0 / max } else { 0.0 };
        let mut points: Vec<&Evaluation> = s.points.iter().collect();
        if s.line {
            points.sort_by(|a, b| a.sensor_z_mm.total_cmp(&b.sensor_z_mm));
            let path: Vec<String> = points
                .iter()
                .map(|e| format!("{:.1},{:.1}", px(e.sensor_z_mm), py(e.score * scale)))
                .collect();
            let _ = writeln!(
                svg,
                r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="1.5"/>"#,
                path.join(" ")
            );
        } else {
            for e in points {
                let _ = writeln!(
                    svg,
                    r#"<circle cx="{:.1}" cy="{:.1}" r="3.5" fill="{colour}" fill-opacity="0.7"/>"#,
                    px(e.sensor_z_mm),
                    py(e.score * scale)
                );
            }
        }
        if let Some(z) = s.chosen_mm {
            let _ = writeln!(
                svg,
                r#"<line x1="{x:.1}" y1="{}" x2="{x:.1}" y2="{}" stroke="{colour}"/>"#,
                margin,
                h - margin,
                x = px(z)
            );
        }
        let ly = 40.0 + 16.0 * i as f64;
        let _ = writeln!(
            svg,
            r#"<rect x="{:.1}" y="{:.1}" width="10" height="10" fill="{colour}"/><text x="{:.1}" y="{:.1}">{}</text>"#,
            w - margin - 200.0,
            ly - 9.0,
            w - margin - 185.0,
            ly,
            escape(s.label)
        );
    }
    if truth_mm.is_some() {
        let ly = 40.0 + 16.0 * series.len() as f64;
        let _ = writeln!(
            svg,
            r#"<text x="{:.1}" y="{ly:.1}">- - - ground truth</text>"#,
            w - margin - 200.0
        );
    }
    svg.push_str("</svg>\n");
    svg
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}
