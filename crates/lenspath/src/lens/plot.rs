//! The lens layout as SVG, drawn to scale like an optical-design program's
//! layout view: elements with their glass shaded, the stop, the sensor at
//! infinity focus, and real ray fans from infinity at three field angles.

use std::fmt::Write as _;

use glam::DVec3;

use super::system::{Direction, LensRay, LensSystem};
use super::LensAnalysis;

/// Field angles drawn, as fractions of the half diagonal field.
const FIELD_FRACTIONS: [f64; 3] = [0.0, 0.7, 1.0];
const FAN_COLOURS: [&str; 3] = ["#1f77b4", "#2ca02c", "#d62728"];
const RAYS_PER_FAN: usize = 7;

/// Sag of a spherical surface: its axial offset from the vertex at height `y`.
fn sag(radius: f64, y: f64) -> f64 {
    if radius == 0.0 {
        0.0
    } else {
        radius - radius.signum() * (radius * radius - y * y).max(0.0).sqrt()
    }
}

/// The SVG drawing of `system` with its sensor (`sensor_diagonal_mm`) at the
/// infinity focus from `analysis`.
pub fn layout_svg(system: &LensSystem, analysis: &LensAnalysis, sensor_diagonal_mm: f64) -> String {
    let layout: Vec<(f64, f64, f64, f64)> = system.surface_layout().collect();
    let sensor_z = analysis.infinity_focus_mm;
    let half_height = layout.iter().map(|s| s.2).fold(0.5 * sensor_diagonal_mm, f64::max) * 1.15;
    let (z0, z1) = (system.front_z() - 0.15 * (sensor_z - system.front_z()), sensor_z + 2.0);
    let width_px = 1000.0;
    let scale = width_px / (z1 - z0);
    let height_px = 2.0 * half_height * scale + 40.0;
    let x = |z: f64| (z - z0) * scale;
    let y = |h: f64| height_px / 2.0 - h * scale;

    let mut svg = String::new();
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width_px:.0}" height="{height_px:.0}" viewBox="0 0 {width_px:.0} {height_px:.0}">"#
    );
    let _ = writeln!(svg, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        svg,
        r##"<text x="8" y="18" font-family="sans-serif" font-size="14">{} — EFL {:.2} mm, f/{:.2}, {:.1}° diagonal field ({:.0} mm sensor diagonal), focused at infinity</text>"##,
        system.prescription().name(),
        analysis.effective_focal_length_mm,
        analysis.f_number,
        analysis.diagonal_fov_deg,
        sensor_diagonal_mm
    );
    let _ = writeln!(
        svg,
        r##"<line x1="0" y1="{0:.2}" x2="{width_px:.0}" y2="{0:.2}" stroke="#888" stroke-dasharray="6 4"/>"##,
        y(0.0)
    );

    // Elements: each glass gap between two surfaces.
    for pair in layout.windows(2) {
        let ((za, ra, aa, ior), (zb, rb, ab, _)) = (pair[0], pair[1]);
        if ior <= 1.0 {
            continue;
        }
        let mut points = Vec::new();
        for k in 0..=32 {
            let h = -aa + 2.0 * aa * k as f64 / 32.0;
            points.push((za + sag(ra, h), h));
        }
        for k in 0..=32 {
            let h = ab - 2.0 * ab * k as f64 / 32.0;
            points.push((zb + sag(rb, h), h));
        }
        let path: Vec<String> = points
            .iter()
            .map(|&(z, h)| format!("{:.2},{:.2}", x(z), y(h)))
            .collect();
        let _ = writeln!(
            svg,
            r##"<polygon points="{}" fill="#cfe3f5" stroke="#234" stroke-width="1.2"/>"##,
            path.join(" ")
        );
    }

    // The stop: two blades from its opening outward.
    let outer = system.stop_radius() + 0.25 * layout.iter().map(|s| s.2).fold(0.0, f64::max);
    for sign in [1.0, -1.0] {
        let _ = writeln!(
            svg,
            r##"<line x1="{0:.2}" y1="{1:.2}" x2="{0:.2}" y2="{2:.2}" stroke="black" stroke-width="3"/>"##,
            x(0.0),
            y(sign * system.stop_radius()),
            y(sign * outer)
        );
    }
    // The sensor.
    let _ = writeln!(
        svg,
        r##"<line x1="{0:.2}" y1="{1:.2}" x2="{0:.2}" y2="{2:.2}" stroke="#444" stroke-width="4"/>"##,
        x(sensor_z),
        y(0.5 * sensor_diagonal_mm),
        y(-0.5 * sensor_diagonal_mm)
    );

    // Ray fans from infinity.
    let max_field = (0.5 * analysis.diagonal_fov_deg).to_radians();
    for (fraction, colour) in FIELD_FRACTIONS.iter().zip(FAN_COLOURS) {
        let field = fraction * max_field;
        for path in ray_fan(system, field, sensor_z) {
            let pts: Vec<String> = path.iter().map(|p| format!("{:.2},{:.2}", x(p.z), y(p.x))).collect();
            let _ = writeln!(
                svg,
                r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="0.9"/>"#,
                pts.join(" ")
            );
        }
    }
    svg.push_str("</svg>\n");
    svg
}

/// Paths of rays from infinity at `field` radians that reach the sensor,
/// spread evenly over the heights at which they pass.
fn ray_fan(system: &LensSystem, field: f64, sensor_z: f64) -> Vec<Vec<DVec3>> {
    let direction = DVec3::new(field.sin(), 0.0, field.cos());
    let start_z = system.front_z() - 0.1 * (sensor_z - system.front_z());
    // A ray by its height where it crosses the front vertex plane.
    let ray_at = |h: f64| LensRay {
        origin: DVec3::new(
            h - direction.x / direction.z * (system.front_z() - start_z),
            0.0,
            start_z,
        ),
        direction,
    };
    let reach = system.front_aperture_radius() * 1.5;
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
            path.push(out.at_z(sensor_z)?);
            Some(path)
        })
        .collect()
}
