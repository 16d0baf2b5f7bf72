//! SVG plots of the wave-optics analysis ([`super::wave_analysis`]): the MTF
//! against frequency per field beside the diffraction limit (OpticStudio's
//! "FFT MTF": tangential solid, sagittal dashed), and sections of the PSF
//! through its centre beside a perfect lens's, both scaled so that the
//! perfect lens peaks at 1 (the lens's peak then reads as its Strehl ratio).

use std::fmt::Write;

use super::plot::{format_number, nice_step};
use super::psf::PointSpread;
use super::wave_analysis::{WaveAnalysis, WaveResult};

/// One colour per field, in the order asked (more fields reuse them).
const FIELD_COLOURS: [&str; 6] = ["#1f77b4", "#2ca02c", "#d62728", "#9467bd", "#ff7f0e", "#8c564b"];
/// The diffraction limit's colour.
const LIMIT_COLOUR: &str = "#9a9a9a";
/// The plots' size and margin, px; the legend stands right of the axes.
const WIDTH: f64 = 800.0;
const HEIGHT: f64 = 480.0;
const MARGIN: f64 = 70.0;
const LEGEND_WIDTH: f64 = 170.0;
/// The PSF plot spans at least this many Airy first-zero radii each side.
const PSF_SPAN_AIRY_RADII: f64 = 3.0;
/// …and at least the radius holding this share of the energy.
const PSF_SPAN_ENERGY: f64 = 0.95;

/// A plot's frame: the SVG header, white ground, title, axes with grid
/// lines and tick labels over x in [0 or −x_max, x_max] and y in [0, y_max].
struct Frame {
    svg: String,
    x_min: f64,
    x_max: f64,
    y_max: f64,
}

impl Frame {
    fn new(title: &str, (x_min, x_max): (f64, f64), y_max: f64, (x_label, y_label): (&str, &str)) -> Frame {
        let mut frame = Frame {
            svg: String::new(),
            x_min,
            x_max,
            y_max,
        };
        let svg = &mut frame.svg;
        let _ = writeln!(
            svg,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{HEIGHT}" viewBox="0 0 {WIDTH} {HEIGHT}" font-family="sans-serif" font-size="12">"#
        );
        let _ = writeln!(svg, r#"<rect width="100%" height="100%" fill="white"/>"#);
        let _ = writeln!(
            svg,
            r#"<text x="{}" y="24" font-size="14" text-anchor="middle">{}</text>"#,
            WIDTH / 2.0,
            escape(title)
        );
        let x_tick = nice_step((x_max - x_min) / 10.0);
        let first = (x_min / x_tick).ceil() as i64;
        let last = (x_max / x_tick).floor() as i64;
        for k in first..=last {
            let v = k as f64 * x_tick;
            let x = frame.x(v);
            let _ = writeln!(
                frame.svg,
                r##"<line x1="{x:.1}" y1="{:.1}" x2="{x:.1}" y2="{:.1}" stroke="{}"/><text x="{x:.1}" y="{:.1}" text-anchor="middle">{}</text>"##,
                frame.y(0.0),
                frame.y(y_max),
                if k == 0 { "#888" } else { "#e4e4e4" },
                frame.y(0.0) + 16.0,
                format_number(v)
            );
        }
        let y_tick = nice_step(y_max / 10.0);
        for k in 0..=(y_max / y_tick + 1e-9).floor() as i64 {
            let v = k as f64 * y_tick;
            let y = frame.y(v);
            let _ = writeln!(
                frame.svg,
                r##"<line x1="{:.1}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="{}"/><text x="{:.1}" y="{:.1}" text-anchor="end">{}</text>"##,
                frame.x(x_min),
                frame.x(x_max),
                if k == 0 { "#888" } else { "#e4e4e4" },
                frame.x(x_min) - 6.0,
                y + 4.0,
                format_number(v)
            );
        }
        let _ = writeln!(
            frame.svg,
            r#"<text x="{}" y="{}" text-anchor="middle">{x_label}</text>"#,
            0.5 * (WIDTH - LEGEND_WIDTH),
            HEIGHT - MARGIN + 36.0
        );
        let _ = writeln!(
            frame.svg,
            r#"<text transform="translate(20 {}) rotate(-90)" text-anchor="middle">{y_label}</text>"#,
            HEIGHT / 2.0
        );
        frame
    }

    fn x(&self, v: f64) -> f64 {
        MARGIN + (v - self.x_min) / (self.x_max - self.x_min) * (WIDTH - LEGEND_WIDTH - 2.0 * MARGIN)
    }

    fn y(&self, v: f64) -> f64 {
        HEIGHT - MARGIN - v / self.y_max * (HEIGHT - 2.0 * MARGIN)
    }

    /// A curve through `points`; `dashed` for the sagittal.
    fn curve(&mut self, points: &[(f64, f64)], colour: &str, width: f64, dashed: bool) {
        let path: Vec<String> = points
            .iter()
            .map(|&(u, v)| format!("{:.2},{:.2}", self.x(u), self.y(v.min(self.y_max))))
            .collect();
        let dash = if dashed { r#" stroke-dasharray="6 4""# } else { "" };
        let _ = writeln!(
            self.svg,
            r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="{width}"{dash}/>"#,
            path.join(" ")
        );
    }

    /// The `row`th legend entry at the top right.
    fn legend(&mut self, row: usize, text: &str, colour: &str, dashed: bool) {
        let (x, y) = (WIDTH - LEGEND_WIDTH - MARGIN + 16.0, MARGIN + 16.0 * row as f64);
        let dash = if dashed { r#" stroke-dasharray="6 4""# } else { "" };
        let _ = writeln!(
            self.svg,
            r#"<line x1="{x:.1}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="{colour}" stroke-width="1.6"{dash}/><text x="{:.1}" y="{:.1}">{}</text>"#,
            x + 24.0,
            x + 30.0,
            y + 4.0,
            escape(text)
        );
    }

    fn finish(mut self) -> String {
        self.svg.push_str("</svg>\n");
        self.svg
    }
}

/// The MTF plot of `analyses` (one per field, as `lenspath lens --mtf`
/// makes them) of the lens named `lens_name`: modulation against cycles per
/// mm from 0 to the highest frequency asked, the first analysis's
/// diffraction limit in grey.
pub fn mtf_svg(lens_name: &str, analyses: &[WaveAnalysis]) -> String {
    let top_frequency = analyses
        .iter()
        .flat_map(|a| a.mtf.iter().map(|s| s.frequency_per_mm))
        .fold(0.0, f64::max)
        .max(1.0);
    let title = match analyses.first() {
        Some(a) => format!(
            "{lens_name} — MTF at {} nm, f/{:.2} working",
            wavelength_list(a),
            a.working_f_number
        ),
        None => format!("{lens_name} — MTF"),
    };
    let mut frame = Frame::new(
        &title,
        (0.0, top_frequency),
        1.0,
        ("spatial frequency (cycles/mm)", "modulation"),
    );
    let with_zero = |points: Vec<(f64, f64)>| {
        let mut all = vec![(0.0, 1.0)];
        all.extend(points.into_iter().filter(|p| p.0 > 0.0));
        all
    };
    if let Some(first) = analyses.first() {
        let limit = with_zero(
            first
                .mtf
                .iter()
                .map(|s| (s.frequency_per_mm, s.diffraction_limit))
                .collect(),
        );
        frame.curve(&limit, LIMIT_COLOUR, 2.4, false);
        frame.legend(0, "diffraction limit", LIMIT_COLOUR, false);
    }
    for (k, a) in analyses.iter().enumerate() {
        let colour = FIELD_COLOURS[k % FIELD_COLOURS.len()];
        let tangential = with_zero(a.mtf.iter().map(|s| (s.frequency_per_mm, s.tangential)).collect());
        let sagittal = with_zero(a.mtf.iter().map(|s| (s.frequency_per_mm, s.sagittal)).collect());
        frame.curve(&tangential, colour, 1.6, false);
        frame.curve(&sagittal, colour, 1.6, true);
        let field = format_number(a.field_deg);
        frame.legend(1 + 2 * k, &format!("{field}° tangential"), colour, false);
        frame.legend(2 + 2 * k, &format!("{field}° sagittal"), colour, true);
    }
    frame.finish()
}

/// Sections of `result`'s polychromatic PSF through its centre, along x
/// (sagittal) and y (tangential), beside a perfect lens's, in µm from the
/// chief ray's image point; scaled so that the perfect lens peaks at 1.
pub fn psf_svg(lens_name: &str, result: &WaveResult) -> String {
    let a = &result.analysis;
    let perfect = &result.diffraction_limited_psf;
    let perfect_peak = peak_density(perfect);
    let mean_wavelength_um = weighted_mean_wavelength_nm(a) * 1e-3;
    let airy_zero_um = 1.22 * mean_wavelength_um * a.working_f_number;
    let half_span_um = (PSF_SPAN_AIRY_RADII * airy_zero_um)
        .max(energy_radius_mm(&result.psf, PSF_SPAN_ENERGY) * 1e3)
        .min(half_width_um(&result.psf));
    let sections = [(0, "sagittal (x)"), (1, "tangential (y)")].map(|(axis, name)| {
        let section = section(&result.psf, axis, half_span_um, perfect_peak);
        (section, name)
    });
    let reference = section(perfect, 0, half_span_um, perfect_peak);
    let highest = sections
        .iter()
        .flat_map(|(s, _)| s.iter().map(|p| p.1))
        .fold(1.0, f64::max);
    let title = format!(
        "{lens_name} — PSF at {}°, {} nm (Strehl {:.3})",
        format_number(a.field_deg),
        wavelength_list(a),
        a.strehl_ratio
    );
    let mut frame = Frame::new(
        &title,
        (-half_span_um, half_span_um),
        nice_step(highest / 5.0) * (highest / nice_step(highest / 5.0)).ceil(),
        (
            "distance from the chief ray's image point (µm)",
            "intensity (perfect lens's peak = 1)",
        ),
    );
    frame.curve(&reference, LIMIT_COLOUR, 2.4, false);
    frame.legend(0, "diffraction limit", LIMIT_COLOUR, false);
    for (k, (section, name)) in sections.iter().enumerate() {
        frame.curve(section, FIELD_COLOURS[k], 1.6, k == 0);
        frame.legend(1 + k, name, FIELD_COLOURS[k], k == 0);
    }
    frame.finish()
}

/// The section of `psf` through its centre along `axis` (0: x, 1: y) within
/// ±`half_span_um`, as (µm, intensity density over `peak`).
fn section(psf: &PointSpread, axis: usize, half_span_um: f64, peak: f64) -> Vec<(f64, f64)> {
    let (size, spacing) = (psf.size(), psf.spacing_mm());
    let centre = size / 2;
    let area = spacing[0] * spacing[1];
    (0..size)
        .filter_map(|k| {
            let position_um = (k as f64 - centre as f64) * spacing[axis] * 1e3;
            let index = if axis == 0 {
                centre * size + k
            } else {
                k * size + centre
            };
            (position_um.abs() <= half_span_um).then(|| (position_um, psf.intensity()[index] / area / peak))
        })
        .collect()
}

/// The highest intensity per unit area.
fn peak_density(psf: &PointSpread) -> f64 {
    let [dx, dy] = psf.spacing_mm();
    psf.intensity().iter().copied().fold(0.0, f64::max) / (dx * dy)
}

/// The smallest radius (mm) that holds `share` of the energy, by bisection.
fn energy_radius_mm(psf: &PointSpread, share: f64) -> f64 {
    let (mut low, mut high) = (0.0, half_width_um(psf) * 1e-3);
    for _ in 0..30 {
        let middle = 0.5 * (low + high);
        if psf.encircled_energy(middle) < share {
            low = middle;
        } else {
            high = middle;
        }
    }
    high
}

/// The grid's half width along its narrower axis, µm.
fn half_width_um(psf: &PointSpread) -> f64 {
    let [dx, dy] = psf.spacing_mm();
    0.5 * (psf.size() - 1) as f64 * dx.min(dy) * 1e3
}

fn weighted_mean_wavelength_nm(a: &WaveAnalysis) -> f64 {
    let total: f64 = a.wavelengths.iter().map(|w| w.weight).sum();
    a.wavelengths.iter().map(|w| w.wavelength_nm * w.weight).sum::<f64>() / total
}

/// "587.6" or "486.1, 587.6, 656.3".
fn wavelength_list(a: &WaveAnalysis) -> String {
    let names: Vec<String> = a
        .wavelengths
        .iter()
        .map(|w| format!("{:.1}", w.wavelength_nm))
        .collect();
    names.join(", ")
}

/// `text` safe inside SVG text (a lens name may hold `&` or `<`).
fn escape(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lens::wave_analysis::WaveAnalysisSettings;
    use crate::lens::wavefront::tests::singlet;

    /// The plots are well-formed SVG with a curve per section, and the PSF
    /// plot's lens section peaks at its Strehl ratio (within the grid's
    /// sampling of the peak) against the perfect lens's 1.
    #[test]
    fn the_plots_draw_each_curve_and_the_psf_peaks_at_its_strehl_ratio() {
        let system = singlet().with_f_number(11.0).unwrap();
        let settings = WaveAnalysisSettings {
            pupil_samples: 64,
            ..WaveAnalysisSettings::default()
        };
        let result = WaveAnalysis::with_psf(&system, &settings).unwrap();
        let svg = psf_svg("singlet & co", &result);
        assert!(svg.starts_with("<svg") && svg.ends_with("</svg>\n") && svg.contains("singlet &amp; co"));
        assert_eq!(svg.matches("<polyline").count(), 3);
        let peak = section(&result.psf, 1, 5.0, peak_density(&result.diffraction_limited_psf))
            .iter()
            .map(|p| p.1)
            .fold(0.0, f64::max);
        let strehl = result.analysis.strehl_ratio;
        assert!((peak - strehl).abs() < 0.03, "peak {peak} against Strehl {strehl}");

        let tilted = WaveAnalysis::new(
            &system,
            &WaveAnalysisSettings {
                field_deg: 5.0,
                ..settings.clone()
            },
        )
        .unwrap();
        let svg = mtf_svg("singlet", &[result.analysis.clone(), tilted]);
        assert_eq!(svg.matches("<polyline").count(), 5, "the limit and T, S per field");
        assert!(svg.contains("5° sagittal"));
    }
}
