//! The lens layout as SVG, drawn to scale like an optical-design program's
//! layout view: elements with their glass shaded, the stop, the sensor at
//! infinity focus, and real ray fans from infinity at three field angles
//! (for a lens whose glasses disperse, each fan at the F, d and C lines, in
//! blue, green and red); and the chromatic focal shift plot.

use std::fmt::Write as _;

use glam::DVec3;

use super::chromatic::focal_shift;
use super::prescription::LensSurface;
use super::surface::Meridian;
use super::system::{Direction, LensRay, LensSystem};
use super::LensAnalysis;
use crate::error::Result;
use crate::glass::{C_LINE_NM, D_LINE_NM, F_LINE_NM};

/// Field angles drawn, as fractions of the half diagonal field.
const FIELD_FRACTIONS: [f64; 3] = [0.0, 0.7, 1.0];
/// Each field's colour, for a lens that does not disperse.
const FAN_COLOURS: [&str; 3] = ["#1f77b4", "#2ca02c", "#d62728"];
/// The lines a dispersive lens's fans are traced at: name, wavelength (nm)
/// and colour (blue F, green d, red C: the optical-design convention).
const LINE_COLOURS: [(&str, f64, &str); 3] = [
    ("F", F_LINE_NM, "#1f4fd8"),
    ("d", D_LINE_NM, "#2a9d3a"),
    ("C", C_LINE_NM, "#d62728"),
];
const RAYS_PER_FAN: usize = 7;

/// One drawn ray of a fan.
#[derive(Clone, Debug)]
pub struct FanRay {
    /// Its field, as a fraction of the half diagonal field.
    pub field_fraction: f64,
    /// The wavelength it is traced at, nm.
    pub wavelength_nm: f64,
    /// Its path, (z, height) in mm.
    pub path: Polyline,
    /// The colour it is drawn in (CSS): its wavelength's when the lens
    /// disperses, else its field's.
    pub colour: &'static str,
}

/// A polyline in the layout's coordinates: (z along the axis, height), mm.
pub type Polyline = Vec<(f64, f64)>;

/// What a layout drawing shows, in lens coordinates (z along the axis from
/// the stop toward the sensor, height in the meridional plane; mm): drawn as
/// SVG by [`layout_svg`] and by the Python package's matplotlib helper.
#[derive(Clone, Debug)]
pub struct Layout {
    /// A one-line caption: the lens, its focal length, f-number and field.
    pub title: String,
    /// Each glass element's closed outline.
    pub elements: Vec<Polyline>,
    /// The stop's two blades, from its opening outward.
    pub stop: [Polyline; 2],
    /// The sensor, at infinity focus.
    pub sensor: Polyline,
    /// Real rays from infinity to the sensor: at the d line, or at the F, d
    /// and C lines when the lens disperses.
    pub rays: Vec<FanRay>,
    /// The z range to show.
    pub z_range_mm: (f64, f64),
    /// Half the height to show.
    pub half_height_mm: f64,
}

/// The layout of `system` with its sensor (`sensor_diagonal_mm`) at the
/// infinity focus from `analysis`.
pub fn layout(system: &LensSystem, analysis: &LensAnalysis, sensor_diagonal_mm: f64) -> Layout {
    layout_focused(system, analysis, sensor_diagonal_mm, analysis.infinity_focus_mm)
}

/// [`layout`] with the sensor `sensor_depth_mm` mm behind the stop (where it is
/// focused now): the rays from infinity meet it blurred unless it is at the
/// infinity focus.
pub fn layout_focused(
    system: &LensSystem,
    analysis: &LensAnalysis,
    sensor_diagonal_mm: f64,
    sensor_depth_mm: f64,
) -> Layout {
    let surfaces: Vec<_> = system.surface_layout().collect();
    let largest_aperture = surfaces.iter().map(|s| s.2).fold(0.0, f64::max);

    // Elements: each glass gap between two surfaces.
    let elements = surfaces
        .windows(2)
        .filter(|pair| pair[0].3 > 1.0)
        .map(|pair| {
            let ((za, sa, aa, _), (zb, sb, ab, _)) = (pair[0], pair[1]);
            // Validation saw every surface reach its clear aperture.
            // The horizontal section, where the ray fans are traced.
            let sag = |s: &LensSurface, h: f64| s.sag_mm(h, Meridian::Horizontal).unwrap_or(0.0);
            let front = (0..=32)
                .map(|k| -aa + 2.0 * aa * k as f64 / 32.0)
                .map(|h| (za + sag(sa, h), h));
            let back = (0..=32)
                .map(|k| ab - 2.0 * ab * k as f64 / 32.0)
                .map(|h| (zb + sag(sb, h), h));
            front.chain(back).collect()
        })
        .collect();
    let outer = system.stop_radius_mm() + 0.25 * largest_aperture;
    let blade = |sign: f64| vec![(0.0, sign * system.stop_radius_mm()), (0.0, sign * outer)];
    let max_field = (0.5 * analysis.diagonal_fov_deg).to_radians();
    // Each wavelength with its colour (`None`: colour the fans by field).
    let lines: Vec<(f64, Option<&'static str>)> = if system.is_dispersive() {
        LINE_COLOURS.iter().map(|&(_, nm, colour)| (nm, Some(colour))).collect()
    } else {
        vec![(system.wavelength_nm(), None)]
    };
    let mut rays = Vec::new();
    for &(wavelength_nm, line_colour) in &lines {
        let at_line = system.at_wavelength(wavelength_nm);
        for (field_index, &field_fraction) in FIELD_FRACTIONS.iter().enumerate() {
            rays.extend(
                ray_fan(&at_line, field_fraction * max_field, sensor_depth_mm)
                    .into_iter()
                    .map(|path| FanRay {
                        field_fraction,
                        wavelength_nm,
                        path: path.iter().map(|p| (p.z, p.x)).collect(),
                        colour: line_colour.unwrap_or(FAN_COLOURS[field_index]),
                    }),
            );
        }
    }
    Layout {
        title: format!(
            "{} — EFL {:.2} mm, f/{:.2}, {:.1}° diagonal field ({:.0} mm sensor diagonal), {}{}",
            system.prescription().name(),
            analysis.effective_focal_length_mm,
            analysis.f_number,
            analysis.diagonal_fov_deg,
            sensor_diagonal_mm,
            if sensor_depth_mm == analysis.infinity_focus_mm {
                "focused at infinity".to_string()
            } else {
                format!("sensor {sensor_depth_mm:.3} mm behind the stop")
            },
            if system.is_dispersive() {
                "; rays at F, d, C"
            } else {
                ""
            }
        ),
        elements,
        stop: [blade(1.0), blade(-1.0)],
        sensor: vec![
            (sensor_depth_mm, 0.5 * sensor_diagonal_mm),
            (sensor_depth_mm, -0.5 * sensor_diagonal_mm),
        ],
        rays,
        z_range_mm: (
            system.front_z_mm() - 0.15 * (sensor_depth_mm - system.front_z_mm()),
            sensor_depth_mm + 2.0,
        ),
        half_height_mm: largest_aperture.max(0.5 * sensor_diagonal_mm) * 1.15,
    }
}

/// The SVG drawing of `system` with its sensor (`sensor_diagonal_mm`) at the
/// infinity focus from `analysis` (see [`layout`]).
pub fn layout_svg(system: &LensSystem, analysis: &LensAnalysis, sensor_diagonal_mm: f64) -> String {
    layout_to_svg(&layout(system, analysis, sensor_diagonal_mm))
}

/// The SVG drawing of a [`Layout`].
pub fn layout_to_svg(l: &Layout) -> String {
    let (z0, z1) = l.z_range_mm;
    let width_px = 1000.0;
    let scale = width_px / (z1 - z0);
    let height_px = 2.0 * l.half_height_mm * scale + 40.0;
    let points = |line: &Polyline| -> String {
        let p: Vec<String> = line
            .iter()
            .map(|&(z, h)| format!("{:.2},{:.2}", (z - z0) * scale, height_px / 2.0 - h * scale))
            .collect();
        p.join(" ")
    };

    let mut svg = String::new();
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width_px:.0}" height="{height_px:.0}" viewBox="0 0 {width_px:.0} {height_px:.0}">"#
    );
    let _ = writeln!(svg, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        svg,
        r##"<text x="8" y="18" font-family="sans-serif" font-size="14">{}</text>"##,
        l.title
    );
    let _ = writeln!(
        svg,
        r##"<line x1="0" y1="{0:.2}" x2="{width_px:.0}" y2="{0:.2}" stroke="#888" stroke-dasharray="6 4"/>"##,
        height_px / 2.0
    );
    for outline in &l.elements {
        let _ = writeln!(
            svg,
            r##"<polygon points="{}" fill="#cfe3f5" stroke="#234" stroke-width="1.2"/>"##,
            points(outline)
        );
    }
    for blade in &l.stop {
        let _ = writeln!(
            svg,
            r##"<polyline points="{}" stroke="black" stroke-width="3"/>"##,
            points(blade)
        );
    }
    let _ = writeln!(
        svg,
        r##"<polyline points="{}" stroke="#444" stroke-width="4"/>"##,
        points(&l.sensor)
    );
    for ray in &l.rays {
        let _ = writeln!(
            svg,
            r#"<polyline points="{}" fill="none" stroke="{}" stroke-width="0.9" stroke-opacity="0.75"/>"#,
            points(&ray.path),
            ray.colour
        );
    }
    svg.push_str("</svg>\n");
    svg
}

/// Paths of rays from infinity at `field` radians that reach the sensor,
/// spread evenly over the heights at which they pass.
fn ray_fan(system: &LensSystem, field: f64, sensor_depth_mm: f64) -> Vec<Vec<DVec3>> {
    let direction = DVec3::new(field.sin(), 0.0, field.cos());
    let start_z = system.front_z_mm() - 0.1 * (sensor_depth_mm - system.front_z_mm());
    // A ray by its height where it crosses the front vertex plane.
    let ray_at = |h: f64| LensRay {
        origin: DVec3::new(
            h - direction.x / direction.z * (system.front_z_mm() - start_z),
            0.0,
            start_z,
        ),
        direction,
    };
    let reach = system.front_aperture_radius_mm() * 1.5;
    let passing: Vec<f64> = (0..=2000)
        .map(|k| -reach + 2.0 * reach * k as f64 / 2000.0)
        .filter(|&h| system.trace(&ray_at(h), Direction::ToSensor).is_some())
        .collect();
    let (Some(&lo), Some(&hi)) = (passing.first(), passing.last()) else {
        return Vec::new();
    };
    (0..RAYS_PER_FAN)
        .filter_map(|k| {
            let h = lo + (hi - lo) * k as f64 / (RAYS_PER_FAN - 1) as f64;
            let ray = ray_at(h);
            let mut path = vec![ray.origin];
            let out = system.trace_visiting(&ray, Direction::ToSensor, |p| path.push(p))?;
            path.push(out.at_z(sensor_depth_mm)?);
            Some(path)
        })
        .collect()
}

/// Wavelengths of the focal shift curve: 400 to 700 nm, every 5 nm (the
/// range lens designers plot; a photographic lens is corrected over it).
const FOCAL_SHIFT_RANGE_NM: (f64, f64, f64) = (400.0, 700.0, 5.0);

/// The chromatic focal shift plot as SVG: the paraxial focus against
/// wavelength, relative to the d line's (focal shift in µm across, wavelength
/// up, as OpticStudio's "Chromatic Focal Shift"), with the F, d and C lines
/// marked. A lens that does not disperse draws a vertical line at 0.
pub fn focal_shift_svg(system: &LensSystem) -> Result<String> {
    let (first, last, step) = FOCAL_SHIFT_RANGE_NM;
    let count = ((last - first) / step).round() as usize + 1;
    let wavelengths: Vec<f64> = (0..count).map(|k| first + step * k as f64).collect();
    let curve: Vec<(f64, f64)> = focal_shift(system, &wavelengths)?
        .into_iter()
        .map(|(nm, shift_mm)| (nm, shift_mm * 1e3))
        .collect();
    // A symmetric shift axis in "nice" steps that holds the curve.
    let widest = curve.iter().map(|c| c.1.abs()).fold(0.0, f64::max);
    let tick = nice_step(widest.max(1.0) / 2.0);
    let half_range = tick * (widest / tick).ceil().max(1.0);
    let (width, height, margin) = (640.0, 480.0, 70.0);
    let x = |shift_um: f64| margin + (shift_um + half_range) / (2.0 * half_range) * (width - 2.0 * margin);
    let y = |nm: f64| height - margin - (nm - first) / (last - first) * (height - 2.0 * margin);
    let mut svg = String::new();
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(svg, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        svg,
        r#"<text x="{}" y="24" font-size="14" text-anchor="middle">{} — chromatic focal shift (paraxial, from the d line)</text>"#,
        width / 2.0,
        system.prescription().name()
    );
    // Axes, grid and ticks.
    let ticks = (half_range / tick).round() as i64;
    for k in -ticks..=ticks {
        let shift = k as f64 * tick;
        let _ = writeln!(
            svg,
            r##"<line x1="{0:.1}" y1="{1:.1}" x2="{0:.1}" y2="{2:.1}" stroke="{3}"/><text x="{0:.1}" y="{4:.1}" text-anchor="middle">{5}</text>"##,
            x(shift),
            y(first),
            y(last),
            if k == 0 { "#888" } else { "#e4e4e4" },
            y(first) + 16.0,
            format_number(shift)
        );
    }
    for nm in (first as i64..=last as i64).step_by(50) {
        let nm = nm as f64;
        let _ = writeln!(
            svg,
            r##"<line x1="{0:.1}" y1="{1:.1}" x2="{2:.1}" y2="{1:.1}" stroke="#e4e4e4"/><text x="{3:.1}" y="{4:.1}" text-anchor="end">{nm}</text>"##,
            x(-half_range),
            y(nm),
            x(half_range),
            x(-half_range) - 6.0,
            y(nm) + 4.0
        );
    }
    let _ = writeln!(
        svg,
        r#"<text x="{}" y="{}" text-anchor="middle">focal shift (µm; + away from the lens)</text>"#,
        width / 2.0,
        height - margin + 36.0
    );
    let _ = writeln!(
        svg,
        r#"<text transform="translate(20 {}) rotate(-90)" text-anchor="middle">wavelength (nm)</text>"#,
        height / 2.0
    );
    for (name, nm, colour) in LINE_COLOURS {
        let _ = writeln!(
            svg,
            r#"<line x1="{0:.1}" y1="{1:.1}" x2="{2:.1}" y2="{1:.1}" stroke="{colour}" stroke-dasharray="4 3"/><text x="{3:.1}" y="{4:.1}" fill="{colour}">{name}</text>"#,
            x(-half_range),
            y(nm),
            x(half_range),
            x(half_range) + 4.0,
            y(nm) + 4.0
        );
    }
    let points: Vec<String> = curve
        .iter()
        .map(|&(nm, shift)| format!("{:.2},{:.2}", x(shift), y(nm)))
        .collect();
    let _ = writeln!(
        svg,
        r#"<polyline points="{}" fill="none" stroke="black" stroke-width="1.6"/>"#,
        points.join(" ")
    );
    svg.push_str("</svg>\n");
    Ok(svg)
}

/// 1, 2 or 5 times a power of ten, at least `x`.
pub(super) fn nice_step(x: f64) -> f64 {
    let power = 10f64.powf(x.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * power)
        .find(|&s| s >= x)
        .unwrap_or(10.0 * power)
}

/// A tick label without trailing zeros.
pub(super) fn format_number(v: f64) -> String {
    let s = format!("{v:.3}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}
