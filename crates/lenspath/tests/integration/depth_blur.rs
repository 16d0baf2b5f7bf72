//! Depth-aware lens blur against the real thing: two checkerboards at
//! different depths (one before the focus plane, one beyond) rendered
//! through a thin lens, and through a pinhole with their depths, then
//! blurred by `bokeh::depth_blur`. Away from depth edges the two must agree
//! far better than the sharp image does.

use std::sync::atomic::AtomicBool;

use glam::Vec3;
use lenspath::accel::BvhSettings;
use lenspath::bokeh::{depth_blur, CircleOfConfusion};
use lenspath::builtin::{add_checkerboard, checker_scene};
use lenspath::camera::{Aperture, ApertureShape, Camera, CameraPose, PerspectiveCamera};
use lenspath::film::Image;
use lenspath::integrator::Integrator;
use lenspath::render::{render, RenderSettings};

const W: u32 = 160;
const H: u32 = 120;
const APERTURE_RADIUS: f32 = 0.2;
const FOV_Y_DEG: f32 = 40.0;
const FOCUS_DISTANCE: f32 = 2.5;

fn shoot(camera: &dyn Camera, spp: u32) -> Image {
    // A board of 20 cm squares at 4 m filling the view, and one of 5 cm
    // squares at 1.5 m covering part of it.
    let mut scene = checker_scene();
    add_checkerboard(&mut scene, (-3.0, 3.0), (-2.5, 2.5), 4.0, 0.2);
    add_checkerboard(&mut scene, (-0.45, 0.15), (-0.3, 0.25), 1.5, 0.05);
    let settings = RenderSettings {
        width: W,
        height: H,
        spp,
        integrator: Integrator::path(1, 1),
        seed: 5,
        ..RenderSettings::default()
    };
    let compiled = scene.compile(&BvhSettings::default()).unwrap();
    render(&compiled, camera, &settings, &|_, _| {}, &AtomicBool::new(false))
        .unwrap()
        .image
}

/// Mean absolute difference over the pixels `keep` selects, relative to the reference's mean.
fn relative_error(a: &[f32], reference: &[f32], keep: &[bool]) -> f64 {
    let (mut diff, mut sum) = (0.0, 0.0);
    for (i, _) in keep.iter().enumerate().filter(|(_, &k)| k) {
        for c in 0..3 {
            diff += f64::from((a[3 * i + c] - reference[3 * i + c]).abs());
            sum += f64::from(reference[3 * i + c]);
        }
    }
    diff / sum
}

#[test]
fn depth_blur_of_a_pinhole_render_matches_a_thin_lens_render_away_from_depth_edges() {
    let pose = CameraPose::look_at(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y);
    let pinhole = PerspectiveCamera::pinhole(pose, FOV_Y_DEG, W, H);
    let thin = PerspectiveCamera::thin_lens(pose, FOV_Y_DEG, W, H, APERTURE_RADIUS, FOCUS_DISTANCE);
    let sharp = shoot(&pinhole, 256);
    let real = shoot(&thin, 256);
    let coc = CircleOfConfusion::thin_lens_camera(
        f64::from(APERTURE_RADIUS),
        f64::from(FOCUS_DISTANCE),
        f64::from(FOV_Y_DEG),
        H,
    )
    .unwrap();
    let aperture = Aperture::new(&ApertureShape::Circle).unwrap();
    let (w, h) = (W as usize, H as usize);
    let blurred = depth_blur(&sharp.rgb, &sharp.depth, w, h, &coc, &aperture).unwrap();

    // Away from depth edges: the depths within the largest blur radius (plus
    // a pixel) of a pixel vary by under 3%.
    let largest = sharp
        .depth
        .iter()
        .map(|&z| 0.5 * coc.diameter_px(f64::from(z)).abs())
        .fold(0.0, f64::max);
    let reach = largest.ceil() as i64 + 1;
    let away: Vec<bool> = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as i64, (i / w) as i64);
            let (mut lo, mut hi) = (f32::INFINITY, 0f32);
            for dy in -reach..=reach {
                for dx in -reach..=reach {
                    let (u, v) = (x + dx, y + dy);
                    if u >= 0 && v >= 0 && u < w as i64 && v < h as i64 {
                        let z = sharp.depth[v as usize * w + u as usize];
                        lo = lo.min(z);
                        hi = hi.max(z);
                    }
                }
            }
            hi.is_finite() && hi < 1.03 * lo
        })
        .collect();
    let near_edges: Vec<bool> = away.iter().map(|a| !a).collect();
    let share = away.iter().filter(|&&a| a).count() as f64 / (w * h) as f64;
    let blurred_error = relative_error(&blurred, &real.rgb, &away);
    let sharp_error = relative_error(&sharp.rgb, &real.rgb, &away);
    let edge_error = relative_error(&blurred, &real.rgb, &near_edges);
    let sharp_edge_error = relative_error(&sharp.rgb, &real.rgb, &near_edges);
    eprintln!(
        "largest blur radius {largest:.1} px; {:.0}% of pixels away from depth edges: \
         blurred {:.2}% vs sharp {:.2}%; near edges: blurred {:.2}% vs sharp {:.2}%",
        100.0 * share,
        100.0 * blurred_error,
        100.0 * sharp_error,
        100.0 * edge_error,
        100.0 * sharp_edge_error
    );
    assert!(largest > 3.0, "the test needs visible blur, got {largest:.1} px");
    assert!(
        share > 0.3,
        "only {:.0}% of the pixels are away from depth edges",
        100.0 * share
    );
    assert!(
        blurred_error < 0.1 * sharp_error && blurred_error < 0.04,
        "away from depth edges: blurred {blurred_error:.4}, sharp {sharp_error:.4}"
    );
}
