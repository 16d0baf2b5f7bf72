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
    /// Real rays from infinity to the sensor: (field, as a fraction of the
    /// half diagonal field, and the ray's path).
    pub rays: Vec<(f64, Polyline)>,
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

/// [`layout`] with the sensor `sensor_z` mm behind the stop (where it is
/// focused now): the rays from infinity meet it blurred unless it is at the
/// infinity focus.
pub fn layout_focused(system: &LensSystem, analysis: &LensAnalysis, sensor_diagonal_mm: f64, sensor_z: f64) -> Layout {
    let surfaces: Vec<(f64, f64, f64, f64)> = system.surface_layout().collect();
    let largest_aperture = surfaces.iter().map(|s| s.2).fold(0.0, f64::max);

    // Elements: each glass gap between two surfaces.
    let elements = surfaces
        .windows(2)
        .filter(|pair| pair[0].3 > 1.0)
        .map(|pair| {
            let ((za, ra, aa, _), (zb, rb, ab, _)) = (pair[0], pair[1]);
            let front = (0..=32)
                .map(|k| -aa + 2.0 * aa * k as f64 / 32.0)
                .map(|h| (za + sag(ra, h), h));
            let back = (0..=32)
                .map(|k| ab - 2.0 * ab * k as f64 / 32.0)
                .map(|h| (zb + sag(rb, h), h));
            front.chain(back).collect()
        })
        .collect();
    let outer = system.stop_radius() + 0.25 * largest_aperture;
    let blade = |sign: f64| vec![(0.0, sign * system.stop_radius()), (0.0, sign * outer)];
    let max_field = (0.5 * analysis.diagonal_fov_deg).to_radians();
    let rays = FIELD_FRACTIONS
        .iter()
        .flat_map(|&fraction| {
            ray_fan(system, fraction * max_field, sensor_z)
                .into_iter()
                .map(move |path| (fraction, path.iter().map(|p| (p.z, p.x)).collect()))
        })
        .collect();
    Layout {
        title: format!(
            "{} — EFL {:.2} mm, f/{:.2}, {:.1}° diagonal field ({:.0} mm sensor diagonal), {}",
            system.prescription().name(),
            analysis.effective_focal_length_mm,
            analysis.f_number,
            analysis.diagonal_fov_deg,
            sensor_diagonal_mm,
            if sensor_z == analysis.infinity_focus_mm {
                "focused at infinity".to_string()
            } else {
                format!("sensor {sensor_z:.3} mm behind the stop")
            }
        ),
        elements,
        stop: [blade(1.0), blade(-1.0)],
        sensor: vec![
            (sensor_z, 0.5 * sensor_diagonal_mm),
            (sensor_z, -0.5 * sensor_diagonal_mm),
        ],
        rays,
        z_range_mm: (system.front_z() - 0.15 * (sensor_z - system.front_z()), sensor_z + 2.0),
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
    for (fraction, path) in &l.rays {
        let colour = FIELD_FRACTIONS
            .iter()
            .position(|f| f == fraction)
            .map_or(FAN_COLOURS[0], |i| FAN_COLOURS[i]);
        let _ = writeln!(
            svg,
            r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="0.9"/>"#,
            points(path)
        );
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
