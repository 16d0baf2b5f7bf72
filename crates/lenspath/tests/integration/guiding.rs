//! The guided path tracer: unbiased (it renders the exact answer of an
//! analytic scene and the path tracer's means) and deterministic (threads,
//! crops, continued renders and a guide trained beforehand give the same
//! bytes).

use std::sync::atomic::AtomicBool;

use glam::Vec3;
use lenspath::accel::BvhSettings;
use lenspath::builtin::builtin_scene;
use lenspath::camera::{CameraPose, PerspectiveCamera};
use lenspath::film::Image;
use lenspath::glass::Dispersion;
use lenspath::integrator::{guiding_can_help, Integrator, IntegratorKind, PathSettings};
use lenspath::lights::Light;
use lenspath::materials::Material;
use lenspath::math::Rgb;
use lenspath::render::{render, render_from, train_guide, Continuation, PixelRect, RenderSettings};
use lenspath::scene::{CompiledScene, Scene};
use lenspath::shapes::Sphere;

use crate::render_analytic::mean_and_error;

fn guided(max_depth: u32, training_spp: u32) -> Integrator {
    Integrator::new(
        IntegratorKind::Guided,
        PathSettings {
            max_depth,
            light_samples: 1,
        },
        training_spp,
    )
}

fn settings(width: u32, height: u32, spp: u32, integrator: Integrator, seed: u32) -> RenderSettings {
    RenderSettings {
        width,
        height,
        spp,
        integrator,
        seed,
        ..RenderSettings::default()
    }
}

fn rendered(scene: &CompiledScene, camera: &PerspectiveCamera, s: &RenderSettings) -> Image {
    let out = render(scene, camera, s, &|_, _| {}, &AtomicBool::new(false)).unwrap();
    assert!(!out.stats.cancelled && out.stats.invalid_samples == 0);
    out.image
}

/// A white diffuse sphere in a uniform sky of radiance 1 vanishes (every
/// pixel 1), guided as unguided: the guide's density enters the MIS weights
/// and the throughput consistently. A perfect mirror beside it (which
/// vanishes too) is what switches guiding on.
#[test]
fn a_guided_white_furnace_sphere_disappears() {
    let scene = Scene {
        spheres: vec![
            Sphere {
                center: Vec3::ZERO,
                radius: 1.0,
                material: 0,
                emission: None,
            },
            Sphere {
                center: Vec3::new(1.9, 0.0, 0.0),
                radius: 0.8,
                material: 1,
                emission: None,
            },
        ],
        materials: vec![
            Material::Diffuse { reflectance: Rgb::ONE },
            Material::Mirror { reflectance: Rgb::ONE },
        ],
        lights: vec![Light::Environment {
            radiance: Rgb::ONE.into(),
        }],
        ..Default::default()
    }
    .compile(&BvhSettings::default())
    .unwrap();
    assert!(guiding_can_help(&scene));
    let pose = CameraPose::look_at(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y);
    let camera = PerspectiveCamera::pinhole(pose, 25.0, 24, 24);
    let image = rendered(&scene, &camera, &settings(24, 24, 128, guided(100, 15), 1));
    for channel in 0..3 {
        let block: Vec<f32> = (8..16)
            .flat_map(|y| (8..16).map(move |x| (x, y)))
            .map(|(x, y)| image.pixel(x, y)[channel])
            .collect();
        let (mean, err) = mean_and_error(&block);
        assert!(
            (mean - 1.0).abs() < 4.0 * err + 2e-3,
            "channel {channel}: {mean} ± {err}, expected 1"
        );
    }
}

/// The Cornell box with its nearer sphere made of glass (which throws a
/// caustic the guide learns).
fn cornell_box_with_a_glass_sphere() -> Scene {
    let mut scene = builtin_scene("cornell-spheres", 0).unwrap();
    scene.materials.push(Material::Dielectric {
        eta: Dispersion::Constant(1.5),
        reflectance: Rgb::ONE,
        transmittance: Rgb::ONE,
    });
    scene.spheres[1].material = scene.materials.len() as u32 - 1;
    scene
}

/// On the Cornell box with a glass sphere the guided render's mean pixel is
/// the path tracer's within the noise, channel by channel, and its images
/// are bit-identical for one thread or two, for a crop of them and for a
/// render continued from a saved state.
#[test]
fn guided_cornell_box_is_unbiased_and_deterministic() {
    let scene = cornell_box_with_a_glass_sphere();
    let view = scene.view.unwrap();
    let scene = scene.compile(&BvhSettings::default()).unwrap();
    assert!(guiding_can_help(&scene));
    let camera = PerspectiveCamera::pinhole(view.pose, view.fov_y_deg, 64, 48);
    let path = rendered(&scene, &camera, &settings(64, 48, 128, Integrator::path(16, 1), 3));
    let guided_settings = settings(64, 48, 128, guided(16, 7), 4);
    let one_thread = RenderSettings {
        threads: Some(1),
        ..guided_settings
    };
    let guided_image = rendered(&scene, &camera, &guided_settings);
    for c in 0..3 {
        let diff: Vec<f32> = path
            .rgb
            .chunks(3)
            .zip(guided_image.rgb.chunks(3))
            .map(|(p, g)| p[c] - g[c])
            .collect();
        let (mean, err) = mean_and_error(&diff);
        assert!(err > 0.0);
        assert!(mean.abs() < 4.0 * err, "channel {c}: path − guided = {mean} ± {err}");
    }

    assert_eq!(
        rendered(&scene, &camera, &one_thread).rgb,
        guided_image.rgb,
        "1 thread vs all"
    );
    let crop = PixelRect {
        x0: 21,
        y0: 13,
        width: 20,
        height: 17,
    };
    let cropped = rendered(
        &scene,
        &camera,
        &RenderSettings {
            crop: Some(crop),
            ..guided_settings
        },
    );
    for y in 0..crop.height {
        for x in 0..crop.width {
            assert_eq!(cropped.pixel(x, y), guided_image.pixel(crop.x0 + x, crop.y0 + y));
        }
    }
    // Half the samples, saved, then continued: the guide is trained again, the same.
    let half = RenderSettings {
        spp: 64,
        ..guided_settings
    };
    let mut saved = None;
    let mut save = |a: &lenspath::render::Accumulation| {
        saved = Some(a.clone());
        Ok(())
    };
    let never = AtomicBool::new(false);
    let checkpoints = lenspath::render::Checkpoints {
        every: std::time::Duration::from_secs(3600),
        save: &mut save,
    };
    let checkpointed = Continuation {
        checkpoints: Some(checkpoints),
        ..Continuation::default()
    };
    render_from(&scene, &camera, &half, checkpointed, &|_, _| {}, &never).unwrap();
    let continued = Continuation {
        start: saved,
        ..Continuation::default()
    };
    let continued = render_from(&scene, &camera, &guided_settings, continued, &|_, _| {}, &never).unwrap();
    assert_eq!(continued.image.rgb, guided_image.rgb, "continued vs uninterrupted");
    // A guide trained beforehand (as the viewer does, once for all its steps) renders the same image.
    let guide = train_guide(&scene, &camera, &guided_settings, &never).unwrap().unwrap();
    assert_eq!(guide.iterations(), 3, "7 training samples: iterations of 1, 2 and 4");
    let given = Continuation {
        guide: Some(&guide),
        ..Continuation::default()
    };
    let with_guide = render_from(&scene, &camera, &guided_settings, given, &|_, _| {}, &never).unwrap();
    assert_eq!(with_guide.image.rgb, guided_image.rgb, "a guide trained beforehand");
}

/// Where every surface is diffuse (the Cornell box with its two white
/// spheres) a guided render switches itself off: it trains no guide and
/// gives the path tracer's image byte for byte. Made glass, one sphere
/// turns it on again.
#[test]
fn guiding_switches_itself_off_where_nothing_is_specular() {
    let scene = builtin_scene("cornell-spheres", 0).unwrap();
    let view = scene.view.unwrap();
    let compiled = scene.compile(&BvhSettings::default()).unwrap();
    assert!(!guiding_can_help(&compiled));
    let camera = PerspectiveCamera::pinhole(view.pose, view.fov_y_deg, 32, 24);
    let guided_settings = settings(32, 24, 16, guided(16, 7), 5);
    let never = AtomicBool::new(false);
    assert!(train_guide(&compiled, &camera, &guided_settings, &never)
        .unwrap()
        .is_none());
    assert_eq!(
        rendered(&compiled, &camera, &guided_settings).rgb,
        rendered(&compiled, &camera, &settings(32, 24, 16, Integrator::path(16, 1), 5)).rgb,
        "guided without a guide vs the path tracer"
    );

    let glass = cornell_box_with_a_glass_sphere()
        .compile(&BvhSettings::default())
        .unwrap();
    assert!(guiding_can_help(&glass));
    let guide = train_guide(&glass, &camera, &guided_settings, &never).unwrap().unwrap();
    assert_eq!(guide.iterations(), 3);
    assert_ne!(
        rendered(&glass, &camera, &guided_settings).rgb,
        rendered(&glass, &camera, &settings(32, 24, 16, Integrator::path(16, 1), 5)).rgb,
        "a guided render with glass samples the guide"
    );
}
