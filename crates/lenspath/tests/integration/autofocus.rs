//! Autofocus on an analytic scene: a checkerboard plane facing the camera at
//! a known distance. Every strategy must land within one depth of focus of the
//! sensor position that focuses that distance, and the cheap ones must cost a
//! small part of the sweep.

use glam::Vec3;
use lenspath::accel::BvhSettings;
use lenspath::autofocus::{AutofocusSettings, FocusMeasure, FocusSensor, Focuser, SensorSignal, Strategy};
use lenspath::builtin::{add_checkerboard, checker_scene};
use lenspath::camera::{CameraPose, LensFocus, RealisticCameraSettings};
use lenspath::integrator::Integrator;
use lenspath::lens::LensPrescription;
use lenspath::render::PixelRect;
use lenspath::scene::CompiledScene;
use lenspath::sensor::SensorDescription;

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
    let (width, height) = (320, 240);
    let mut camera = RealisticCameraSettings::new(lens, (36.0, 27.0), LensFocus::SensorDepthMm(0.0));
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
        sensor: None,
    };
    Focuser::new(scene, pose(), settings).unwrap()
}

/// The camera at the origin looking down −z.
fn pose() -> CameraPose {
    CameraPose::look_at(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y)
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
    let conjugate = f.sensor_depth_mm_for_distance(f64::from(distance)).unwrap();
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
        let error = (r.sensor_depth_mm - conjugate) / dof;
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
    let dof = f.depth_of_focus_mm(sweep.sensor_depth_mm);
    let conjugate = f.sensor_depth_mm_for_distance(f64::from(distance)).unwrap();
    eprintln!(
        "sweep peak {:.4} mm, the d line's conjugate {conjugate:.4} mm, depth of focus {dof:.4} mm",
        sweep.sensor_depth_mm
    );
    for strategy in [
        Strategy::EarlyExit { patience: 12 },
        Strategy::Fast,
        Strategy::Rangefinder,
        Strategy::Depth,
    ] {
        let r = f.run(strategy).unwrap();
        let error = (r.sensor_depth_mm - sweep.sensor_depth_mm) / dof;
        eprintln!(
            "{strategy:?}: {:.4} mm, {error:+.2} DoF from the sweep's peak",
            r.sensor_depth_mm
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
    let conjugate_near = f.sensor_depth_mm_for_distance(1.0).unwrap();
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
    let dof = f.depth_of_focus_mm(truth.sensor_depth_mm);
    let predicted = (range.best_focus_z_mm - truth.sensor_depth_mm) / dof;
    let conjugate = (range.conjugate_z_mm - truth.sensor_depth_mm) / dof;
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
    let near = f.sensor_depth_mm_for_distance(1.0).unwrap();
    let far = f.sensor_depth_mm_for_distance(2.0).unwrap();
    let dof = f.depth_of_focus_mm(near);
    let ranged = f.range_focus().unwrap().unwrap().conjugate_z_mm;
    assert!(
        (ranged - far).abs() < 0.5 * dof,
        "ranged at {ranged} mm, the wall at {far} mm"
    );
    let r = f.run(Strategy::Depth).unwrap();
    let error = (r.sensor_depth_mm - near) / dof;
    assert!(
        error.abs() <= 1.0,
        "depth at {:.4} mm, {error:+.2} DoF from the board's conjugate {near:.4} (the wall's {far:.4})",
        r.sensor_depth_mm
    );
}

/// The board's centre through the default sensor with auto exposure, lit so
/// the patch's mean luminance is `ev` (EV at ISO 100: 2^EV · 12.5/100
/// cd/m²), the measure reading `signal`.
fn through_sensor<'a>(scene: &'a CompiledScene, ev: f64, signal: SensorSignal) -> Focuser<'a> {
    let mut f = focuser(scene, Some(5.6), CENTRE, 4);
    let relative = f.patch_luminance(f.sensor_depth_mm_for_distance(1.5).unwrap()).unwrap();
    let sensor = SensorDescription {
        auto_exposure: Some(true),
        white_luminance_cd_m2: Some(ev.exp2() * 0.125 / relative),
        ..SensorDescription::default()
    }
    .resolve()
    .unwrap();
    let mut settings = f.settings().clone();
    settings.sensor = Some(FocusSensor { sensor, signal });
    Focuser::new(scene, pose(), settings).unwrap()
}

/// Contrast autofocus on the sensor's frames: in good light every contrast
/// strategy still lands within a DoF of the board's conjugate, on either
/// signal; the exposure is metered once and held (half the light, twice the
/// time; past the longest time, the ISO up to its limit); the frames are
/// deterministic and a new frame seed is new noise.
#[test]
fn autofocus_through_a_sensor_focuses_in_good_light_and_holds_a_metered_exposure() {
    let scene = board_at(1.5);
    let conjugate = focuser(&scene, Some(5.6), CENTRE, 4)
        .sensor_depth_mm_for_distance(1.5)
        .unwrap();
    let defaults = SensorDescription::default().resolve().unwrap();
    let limits = (
        lenspath::defaults::SENSOR_MAX_EXPOSURE_TIME_S,
        lenspath::defaults::SENSOR_MAX_ISO,
    );
    for signal in [SensorSignal::RawGreen, SensorSignal::Luminance] {
        let mut f = through_sensor(&scene, 12.0, signal);
        let dof = f.depth_of_focus_mm(conjugate);
        for strategy in [Strategy::Sweep, Strategy::Fast, Strategy::Depth] {
            let r = f.run(strategy).unwrap();
            let error = (r.sensor_depth_mm - conjugate) / dof;
            eprintln!(
                "{signal:?} {strategy:?}: {error:+.2} DoF, {:?} s at ISO {:?}",
                r.exposure_time_s, r.iso
            );
            assert!(
                error.abs() <= 1.0,
                "{signal:?} {strategy:?}: {error:+.2} DoF from the conjugate"
            );
            // EV 12 at f/5.6 meters under the longest time, at the base ISO.
            let t = r.exposure_time_s.unwrap();
            assert!(t < limits.0, "{t} s");
            assert_eq!(r.iso, Some(defaults.unity_gain_iso));
        }
    }
    // One EV less light: twice the time (the first frame, which meters, is
    // the same render at half the radiance).
    let time_at = |ev: f64| {
        through_sensor(&scene, ev, SensorSignal::RawGreen)
            .run(Strategy::Fast)
            .unwrap()
    };
    let (bright, dimmer) = (time_at(14.0), time_at(13.0));
    let ratio = dimmer.exposure_time_s.unwrap() / bright.exposure_time_s.unwrap();
    assert!((ratio - 2.0).abs() < 1e-9, "one EV less light: exposure time ×{ratio}");
    // In dim light: the longest time at the highest ISO.
    let dark = time_at(2.0);
    assert_eq!((dark.exposure_time_s, dark.iso), (Some(limits.0), Some(limits.1)));
    // The same frames again; another frame seed, other noise.
    let again = time_at(2.0);
    assert_eq!(dark.evaluations, again.evaluations);
    let mut f = through_sensor(&scene, 2.0, SensorSignal::RawGreen);
    let mut settings = f.settings().clone();
    settings.sensor.as_mut().unwrap().sensor.frame_seed = 1;
    f = Focuser::new(&scene, pose(), settings).unwrap();
    let other = f.run(Strategy::Fast).unwrap();
    assert_ne!(dark.evaluations, other.evaluations);
}
