//! The light field inside the camera: refocused where it was recorded it is
//! the render, and refocused elsewhere it is what a render there sees (the
//! same image up to noise), on a checkerboard plane whose sharpness depends
//! strongly on the sensor position.

use std::sync::atomic::AtomicBool;

use glam::Vec3;
use lenspath::accel::BvhSettings;
use lenspath::autofocus::light_field::{LightField, Recording, Splat};
use lenspath::autofocus::{FocusMeasure, Patch};
use lenspath::builtin::{add_checkerboard, checker_scene};
use lenspath::camera::{CameraPose, LensFocus, RealisticCamera, RealisticCameraSettings};
use lenspath::film::Filter;
use lenspath::integrator::Integrator;
use lenspath::lens::{LensPrescription, LensSystem};
use lenspath::render::{render, FilmResponse, PixelRect, RenderSettings};
use lenspath::scene::CompiledScene;

const SIZE: (u32, u32) = (320, 240);

/// 32 × 32 pixels, off the axis (the image breathes as the sensor moves).
const PATCH: PixelRect = PixelRect {
    x0: 200,
    y0: 60,
    width: 32,
    height: 32,
};

/// 32 × 32 pixels on the image's top edge: refocused toward the lens, its
/// samples come from film points above the image, which the light field
/// records all the same.
const EDGE_PATCH: PixelRect = PixelRect {
    x0: 200,
    y0: 0,
    width: 32,
    height: 32,
};

const PATH: Integrator = Integrator::path(2, 1);

fn plane(distance: f32) -> CompiledScene {
    let mut scene = checker_scene();
    add_checkerboard(&mut scene, (-2.0, 2.0), (-1.5, 1.5), distance, 0.02);
    scene.compile(&BvhSettings::default()).unwrap()
}

fn pose() -> CameraPose {
    CameraPose::look_at(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y)
}

/// dgauss50 with the sensor `sensor_depth_mm` behind the stop; its glasses
/// disperse or, without `dispersion`, each has its d-line index.
fn settings(dispersion: bool, sensor_depth_mm: f64) -> RealisticCameraSettings {
    RealisticCameraSettings {
        dispersion,
        ..RealisticCameraSettings::new(
            LensPrescription::load("dgauss50").unwrap(),
            (36.0, 27.0),
            LensFocus::SensorDepthMm(sensor_depth_mm),
        )
    }
}

/// `patch` rendered with the sensor at `sensor_depth_mm`, RGB row by row.
fn render_patch(
    scene: &CompiledScene,
    dispersion: bool,
    patch: PixelRect,
    sensor_depth_mm: f64,
    spp: u32,
    seed: u32,
) -> Vec<f32> {
    let camera =
        RealisticCamera::for_region(pose(), SIZE.0, SIZE.1, &settings(dispersion, sensor_depth_mm), patch).unwrap();
    let render_settings = RenderSettings {
        width: SIZE.0,
        height: SIZE.1,
        spp,
        integrator: PATH,
        seed,
        filter: Filter::Box,
        threads: None,
        tile_size: 16,
        crop: Some(patch),
        depth: false,
        ..Default::default()
    };
    render(scene, &camera, &render_settings, &|_, _| {}, &AtomicBool::new(false))
        .unwrap()
        .image
        .rgb
}

/// A light field of `patch` recorded at `sensor_depth_mm` that reaches `reach`.
fn record(
    scene: &CompiledScene,
    dispersion: bool,
    patch: PixelRect,
    sensor_depth_mm: f64,
    reach: (f64, f64),
    spp: u32,
    seed: u32,
) -> LightField {
    let settings = settings(dispersion, sensor_depth_mm);
    let patch_camera = RealisticCamera::for_region(pose(), SIZE.0, SIZE.1, &settings, patch).unwrap();
    let region = LightField::region_for(&patch_camera, patch, reach);
    let camera = LightField::recording_camera(pose(), SIZE.0, SIZE.1, &settings, region).unwrap();
    let recording = Recording {
        spp,
        seed,
        integrator: PATH,
        threads: None,
        film: FilmResponse::Srgb,
    };
    LightField::record(scene, camera, region, &recording).unwrap()
}

/// Mean absolute difference of two images' luminance, as autofocus scores them.
fn difference(a: &[f32], b: &[f32]) -> f64 {
    let y = |c: &[f32]| f64::from(lenspath::color::luminance([c[0], c[1], c[2]]));
    a.chunks_exact(3)
        .zip(b.chunks_exact(3))
        .map(|(x, z)| (y(x) - y(z)).abs())
        .sum::<f64>()
        / (a.len() / 3) as f64
}

/// The sensor position focusing `distance` metres, and the DoF (one pixel of blur) there.
fn focus(distance: f64) -> (f64, f64) {
    let system = LensSystem::new(&LensPrescription::load("dgauss50").unwrap());
    let z = system.sensor_depth_mm_for_focus_distance(distance * 1e3, 0.1).unwrap();
    let paraxial = system.paraxial().unwrap();
    let pitch = 36.0f64.hypot(27.0) / f64::from(SIZE.0).hypot(f64::from(SIZE.1));
    (
        z,
        pitch * (z - paraxial.exit_pupil_z_mm) / paraxial.exit_pupil_diameter_mm,
    )
}

#[test]
fn refocused_where_it_was_recorded_a_light_field_is_the_render() {
    let scene = plane(1.5);
    let (z, dof) = focus(1.5);
    let field = record(&scene, true, PATCH, z, (z - 3.0 * dof, z + 3.0 * dof), 8, 11);
    assert_eq!(field.samples() % 8, 0);
    // The same samples, summed in the same order: the same bits.
    assert_eq!(
        field.refocus(z, PATCH, Splat::Box).unwrap(),
        render_patch(&scene, true, PATCH, z, 8, 11)
    );
}

/// Refocused 3 DoF from where it was recorded, the light field's patch is
/// as close to a render there as an independent render is: within 1.4× the
/// renders' own difference through dgauss50, with or without dispersion
/// (measured 1.05–1.22 without, 1.04–1.15 with). A dispersive lens's
/// records weigh their wavelengths for the pixel recorded and follow the
/// hero's line when refocused. Either way it is much closer than the patch
/// where it was recorded.
#[test]
fn refocused_elsewhere_a_light_field_sees_what_a_render_there_sees() {
    let scene = plane(1.5);
    let (focused, dof) = focus(1.5);
    // Recorded 3 DoF behind focus, refocused onto the plane and 3 DoF in front.
    let recorded_at = focused + 3.0 * dof;
    for dispersion in [false, true] {
        for patch in [PATCH, EDGE_PATCH] {
            let field = record(
                &scene,
                dispersion,
                patch,
                recorded_at,
                (focused - 4.0 * dof, recorded_at + dof),
                64,
                3,
            );
            for target in [focused, focused - 3.0 * dof] {
                let refocused = field.refocus(target, patch, Splat::Box).unwrap();
                let rendered = render_patch(&scene, dispersion, patch, target, 64, 5);
                let noise = difference(&render_patch(&scene, dispersion, patch, target, 64, 9), &rendered);
                let error = difference(&refocused, &rendered);
                // Much closer than the image where it was recorded (6 pixels of blur apart).
                let unmoved = difference(&field.refocus(recorded_at, patch, Splat::Box).unwrap(), &rendered);
                assert!(
                    error < 1.4 * noise && error < 0.5 * unmoved,
                    "dispersion {dispersion}, {patch:?} at {:+.1} DoF: {error:.4} from a render there, renders differ by {noise:.4}, the recording by {unmoved:.4}",
                    (target - focused) / dof
                );
            }
            // Beyond the margin it was recorded with, it refuses.
            assert!(field.refocus(focused - 12.0 * dof, patch, Splat::Box).is_none());
        }
    }
}

/// Bilinear splats make the refocused image, and so a focus measure of it,
/// change smoothly with the sensor position; box pixels make it jitter as
/// samples jump between pixels. Measured as the second differences of the
/// Tenengrad over quarter-DoF steps through focus, relative to its value
/// (measured: 0.0044 against 0.024).
#[test]
fn bilinear_splats_refocus_smoothly() {
    let scene = plane(1.5);
    let (focused, dof) = focus(1.5);
    let field = record(
        &scene,
        true,
        PATCH,
        focused,
        (focused - 4.0 * dof, focused + 4.0 * dof),
        4,
        7,
    );
    let jitter = |splat: Splat| {
        let scores: Vec<f64> = (-12..=12)
            .map(|k| {
                let rgb = field
                    .refocus(focused + f64::from(k) * 0.25 * dof, PATCH, splat)
                    .unwrap();
                FocusMeasure::Tenengrad.evaluate(&Patch::new(32, 32, &rgb).unwrap())
            })
            .collect();
        let rough: f64 = scores
            .windows(3)
            .map(|w| ((w[0] - 2.0 * w[1] + w[2]) / w[1]).powi(2))
            .sum();
        (rough / (scores.len() - 2) as f64).sqrt()
    };
    let (bilinear, boxed) = (jitter(Splat::Bilinear), jitter(Splat::Box));
    assert!(bilinear < 0.5 * boxed, "bilinear jitter {bilinear:.4}, box {boxed:.4}");
}
