//! Full renders of the built-in Cornell box with spheres, on all cores:
//! 480×360, max depth 16, at 4 spp × 4 light samples and 16 × 16 through a
//! pinhole, and at 4 × 4 through the dgauss50 lens (camera set-up included).

use std::sync::atomic::AtomicBool;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use lenspath::accel::BvhSettings;
use lenspath::builtin::builtin_scene;
use lenspath::camera::{LensFocus, PerspectiveCamera, RealisticCamera, RealisticCameraSettings};
use lenspath::integrator::Integrator;
use lenspath::lens::LensPrescription;
use lenspath::render::{render, PixelRect, RenderSettings};

fn cornell(c: &mut Criterion) {
    let scene = builtin_scene("cornell-spheres", 0).unwrap();
    let view = scene.view.unwrap();
    let compiled = scene.compile(&BvhSettings::default()).unwrap();
    let camera = PerspectiveCamera::pinhole(view.pose, view.fov_y_deg, 480, 360);
    let mut group = c.benchmark_group("render_cornell_spheres_480x360");
    group.sample_size(10);
    for (spp, light_samples) in [(4, 4), (16, 16)] {
        let settings = RenderSettings {
            width: 480,
            height: 360,
            spp,
            integrator: Integrator::path(16, light_samples),
            ..Default::default()
        };
        let id = BenchmarkId::from_parameter(format!("{spp}spp_{light_samples}ls"));
        group.bench_function(id, |b| {
            b.iter(|| render(&compiled, &camera, &settings, &|_, _| {}, &AtomicBool::new(false)).unwrap())
        });
    }
    let settings = RenderSettings {
        width: 480,
        height: 360,
        spp: 4,
        integrator: Integrator::path(16, 4),
        ..Default::default()
    };
    let lens = RealisticCameraSettings::new(
        LensPrescription::load("dgauss50").unwrap(),
        (36.0, 27.0),
        LensFocus::Distance(f64::from(view.focus_distance)),
    );
    group.bench_function("4spp_4ls_dgauss50", |b| {
        b.iter(|| {
            let camera = RealisticCamera::new(view.pose, 480, 360, &lens).unwrap();
            render(&compiled, &camera, &settings, &|_, _| {}, &AtomicBool::new(false)).unwrap()
        })
    });
    group.finish();
}

/// Setting up the realistic camera (focusing, bounding the exit pupil): for
/// the whole image, and for a 64×64 patch as autofocus renders many times.
fn camera_setup(c: &mut Criterion) {
    let view = builtin_scene("cornell-spheres", 0).unwrap().view.unwrap();
    let lens = RealisticCameraSettings::new(
        LensPrescription::load("dgauss50").unwrap(),
        (36.0, 27.0),
        LensFocus::Distance(f64::from(view.focus_distance)),
    );
    let mut group = c.benchmark_group("realistic_camera_setup_640x480");
    group.sample_size(20);
    group.bench_function("full", |b| {
        b.iter(|| RealisticCamera::new(view.pose, 640, 480, &lens).unwrap())
    });
    for (name, x0, y0) in [("patch_64_centre", 288, 208), ("patch_64_off_centre", 500, 60)] {
        let region = PixelRect {
            x0,
            y0,
            width: 64,
            height: 64,
        };
        group.bench_function(name, |b| {
            b.iter(|| RealisticCamera::for_region(view.pose, 640, 480, &lens, region).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, cornell, camera_setup);
criterion_main!(benches);
