//! Autofocus on an analytic scene: a checkerboard plane facing the camera at
//! a known distance. Every strategy must land within one depth of focus of the
//! sensor position that focuses that distance, and the cheap ones must cost a
//! small part of the sweep.

use glam::Vec3;
use lenspath::accel::BvhSettings;
use lenspath::autofocus::{AutofocusSettings, FocusMeasure, Focuser, Strategy};
use lenspath::builtin::{add_checkerboard, checker_scene};
use lenspath::camera::{CameraPose, LensFocus, RealisticCameraSettings};
use lenspath::integrator::Integrator;
use lenspath::lens::LensPrescription;
use lenspath::render::PixelRect;
use lenspath::scene::CompiledScene;

/// The centre 24 × 24 pixels of the 320 × 240 image.
const CENTRE: PixelRect = PixelRect {
    x0: 148,
    y0: 108,
    width: 24,
    height: 24,
};

/// The centre 48 × 48 pixels: room for an edge and the band-pass's wide
/// Gaussian (σ = 4 pixels) on either side of it.
const CENTRE_WIDE: PixelRect = PixelRect {
    x0: 136,
    y0: 96,
    width: 48,
    height: 48,
};

fn focuser(scene: &CompiledScene, f_number: Option<f64>, patch: PixelRect, spp: u32) -> Focuser<'_> {
    focuser_with(scene, LensPrescription::load("dgauss50").unwrap(), f_number, patch, spp)
}

fn focuser_with(
    scene: &CompiledScene,
    lens: LensPrescription,
    f_number: Option<f64>,
    patch: PixelRect,
    spp: u32,
) -> Focuser<'_> {
    let pose = CameraPose::look_at(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y);
    let (width, height) = (320, 240);
    let mut camera = RealisticCameraSettings::new(lens, (36.0, 27.0), LensFocus::SensorPositionMm(0.0));
    camera.f_number = f_number;
    let settings = AutofocusSettings {
        camera,
        width,
        height,
        patch,
        measure: FocusMeasure::Tenengrad,
        spp,
        integrator: Integrator::path(2, 1),
        seed: 7,
        threads: None,
    };
    Focuser::new(scene, pose, settings).unwrap()
}

/// A checkerboard filling the view `distance` metres away, squares of 2 cm
/// (about 5 pixels at 1.5 m).
fn board_at(distance: f32) -> CompiledScene {
    let mut scene = checker_scene();
    add_checkerboard(&mut scene, (-0.8, 0.8), (-0.6, 0.6), distance, 0.02);
    scene.compile(&BvhSettings::default()).unwrap()
}

#[test]
fn every_strategy_focuses_a_plane_at_its_conjugate() {
    let distance = 1.5;
    let scene = board_at(distance);
    // At f/5.6 the lens's spherical aberration moves its best focus by well under a DoF.
    let mut f = focuser(&scene, Some(5.6), CENTRE, 4);
    let conjugate = f.sensor_z_for_distance(f64::from(distance)).unwrap();
    let back = f.focus_distance_at(conjugate).unwrap();
    assert!((back - f64::from(distance)).abs() < 1e-3, "{back}");
    let dof = f.depth_of_focus_mm(conjugate);
    let sweep = f.run(Strategy::Sweep).unwrap();
    for strategy in [
        Strategy::Sweep,
        Strategy::EarlyExit { patience: 12 },
        Strategy::Fast,
        Strategy::Rangefinder,
        Strategy::Depth,
    ] {
        let r = f.run(strategy).unwrap();
        let error = (r.sensor_z_mm - conjugate) / dof;
        assert!(error.abs() <= 1.0, "{strategy:?}: {error:+.2} DoF from the conjugate");
        assert!(r.focus_distance.is_some(), "{strategy:?}");
        match strategy {
            Strategy::Fast => assert!(
                r.camera_rays * 10 <= sweep.camera_rays,
                "fast used {} camera rays, the sweep {}",
                r.camera_rays,
                sweep.camera_rays
            ),
            // 64 probe rays; for depth, a light field within 2% of the sweep's rays.
            Strategy::Rangefinder | Strategy::Depth => {
                let light_field_rays = if strategy == Strategy::Depth {
                    sweep.camera_rays / 50
                } else {
                    0
                };
                assert_eq!(r.patch_renders(), 0, "{strategy:?}");
                assert_eq!(r.light_fields, usize::from(strategy == Strategy::Depth), "{strategy:?}");
                assert!(
                    r.camera_rays <= 64 + light_field_rays,
                    "{strategy:?}: {} rays",
                    r.camera_rays
                );
            }
            _ => {}
        }
    }
    // The sweep's step is the pixel pitch, over the whole range.
    let (near, far) = f.sweep_range_mm();
    let steps = ((far - near) / f.pixel_pitch_mm()).floor() as usize + 1;
    assert_eq!(sweep.evaluations.len(), steps);
}

/// On a lens with strong longitudinal colour (a plain N-BK7 singlet wide open at f/2.8, its
/// F and C foci 0.77 mm apart) every strategy lands where the polychromatic
/// image is sharpest: within a depth of focus of the fine sweep's peak
/// (the sweep steps the sensor by a pixel pitch and judges each render's
/// luminance).
#[test]
fn on_a_lens_with_strong_colour_every_strategy_lands_on_the_sweeps_peak() {
    let distance = 1.5;
    let scene = board_at(distance);
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/lenses/bk7-singlet-50.dat");
    let singlet = LensPrescription::load(path.to_str().unwrap()).unwrap();
    let mut f = focuser_with(&scene, singlet, None, CENTRE, 4);
    let sweep = f.run(Strategy::Sweep).unwrap();
    let dof = f.depth_of_focus_mm(sweep.sensor_z_mm);
    let conjugate = f.sensor_z_for_distance(f64::from(distance)).unwrap();
    eprintln!(
        "sweep peak {:.4} mm, the d line's conjugate {conjugate:.4} mm, depth of focus {dof:.4} mm",
        sweep.sensor_z_mm
    );
    for strategy in [
        Strategy::EarlyExit { patience: 12 },
        Strategy::Fast,
        Strategy::Rangefinder,
        Strategy::Depth,
    ] {
        let r = f.run(strategy).unwrap();
        let error = (r.sensor_z_mm - sweep.sensor_z_mm) / dof;
        eprintln!(
            "{strategy:?}: {:.4} mm, {error:+.2} DoF from the sweep's peak",
            r.sensor_z_mm
        );
        assert!(
            error.abs() <= 1.0,
            "{strategy:?}: {error:+.2} DoF from the sweep's peak"
        );
    }
}

/// The observer sees every evaluation as it is made, in order, run after run
/// (what `lenspath view` draws as the search goes).
#[test]
fn the_observer_sees_every_evaluation_in_order() {
    let scene = board_at(1.5);
    let seen = std::sync::Mutex::new(Vec::new());
    let mut f = focuser(&scene, Some(5.6), CENTRE, 2);
    f.on_evaluation(|e| seen.lock().unwrap().push(*e));
    let mut last = 0;
    for strategy in [Strategy::EarlyExit { patience: 3 }, Strategy::Depth] {
        let r = f.run(strategy).unwrap();
        let seen = seen.lock().unwrap();
        assert_eq!(seen[last..], r.evaluations[..], "{strategy:?}");
        last = seen.len();
    }
    assert!(last > 0, "early-exit renders patches");
}

/// The depth strategy ranges on what most of the patch sees: a patch mostly on
/// a near plane with a far plane behind focuses on the near one.
#[test]
fn depth_focuses_on_the_dominant_surface() {
    // The patch sees about ±27 mm at 1 m: a near board over its left three
    // quarters, a far one behind everything.
    let mut scene = checker_scene();
    add_checkerboard(&mut scene, (-3.0, 3.0), (-2.0, 2.0), 3.0, 0.04);
    add_checkerboard(&mut scene, (-0.2, 0.0135), (-0.2, 0.2), 1.0, 0.005);
    let scene = scene.compile(&BvhSettings::default()).unwrap();
    let mut f = focuser(&scene, None, CENTRE, 4);
    let conjugate_near = f.sensor_z_for_distance(1.0).unwrap();
    let z = f.range_focus().unwrap().unwrap().conjugate_z_mm;
    assert!(
        (z - conjugate_near).abs() < 0.5 * f.depth_of_focus_mm(z),
        "ranged at {z} mm, the near board is at {conjugate_near} mm"
    );
}

/// Wide open, the range finder's lens model (through-focus modulation at the
/// patch's place in the field) predicts where contrast peaks better than the
/// plain conjugate of the depth: off the axis, field curvature moves the best
/// focus back.
#[test]
fn range_focus_predicts_the_contrast_peak_off_axis() {
    let distance = 1.5;
    let mut scene = checker_scene();
    add_checkerboard(&mut scene, (-1.2, 1.2), (-0.9, 0.9), distance, 0.02);
    let scene = scene.compile(&BvhSettings::default()).unwrap();
    // Near the corner: 19° off the axis.
    let corner = PixelRect {
        x0: 272,
        y0: 196,
        width: 32,
        height: 32,
    };
    let mut f = focuser(&scene, None, corner, 4);
    let range = f.range_focus().unwrap().unwrap();
    assert!(range.dominant_fraction > 0.99, "{range:?}");
    let truth = f.ground_truth().unwrap();
    let dof = f.depth_of_focus_mm(truth.sensor_z_mm);
    let predicted = (range.best_focus_z_mm - truth.sensor_z_mm) / dof;
    let conjugate = (range.conjugate_z_mm - truth.sensor_z_mm) / dof;
    eprintln!("truth {truth:?}: lens best focus {predicted:+.2} DoF, conjugate {conjugate:+.2} DoF");
    assert!(
        predicted.abs() < 0.5,
        "lens best focus {predicted:+.2} DoF from the contrast peak"
    );
    assert!(
        predicted.abs() < conjugate.abs(),
        "{predicted:+.2} vs conjugate {conjugate:+.2}"
    );
}

/// The depth strategy's contrast refinement focuses on what carries the
/// contrast, not on what most of the patch sees: a plain dark board 1 m away
/// covers a quarter of the patch, its edge against a plain bright wall 2 m
/// away (5.7 DoF behind). The range finder ranges on the wall; the only
/// detail is the board's edge, sharp when the board is in focus, and the
/// light field reaches every depth the probes saw (the glass and gold
/// spheres' silhouettes in glass-and-gold are this case).
#[test]
fn depth_focuses_on_the_edge_the_contrast_comes_from() {
    let mut scene = checker_scene();
    add_checkerboard(&mut scene, (-3.0, 3.0), (-2.0, 2.0), 2.0, 10.0);
    add_checkerboard(&mut scene, (-0.3, -0.027), (-0.3, 0.3), 1.0, 10.0);
    scene.meshes.last_mut().unwrap().material = 1;
    let scene = scene.compile(&BvhSettings::default()).unwrap();
    // At the command line's 16 samples: at 4, a light field within 2% of
    // the sweep's rays has 5 samples per pixel, and the curve is noise.
    let mut f = focuser(&scene, None, CENTRE_WIDE, 16);
    let near = f.sensor_z_for_distance(1.0).unwrap();
    let far = f.sensor_z_for_distance(2.0).unwrap();
    let dof = f.depth_of_focus_mm(near);
    let ranged = f.range_focus().unwrap().unwrap().conjugate_z_mm;
    assert!(
        (ranged - far).abs() < 0.5 * dof,
        "ranged at {ranged} mm, the wall at {far} mm"
    );
    let r = f.run(Strategy::Depth).unwrap();
    let error = (r.sensor_z_mm - near) / dof;
    assert!(
        error.abs() <= 1.0,
        "depth at {:.4} mm, {error:+.2} DoF from the board's conjugate {near:.4} (the wall's {far:.4})",
        r.sensor_z_mm
    );
}
