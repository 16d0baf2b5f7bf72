//! Full renders of the built-in Cornell box with spheres, on all cores:
//! 480×360, max depth 16, at 4 spp × 4 light samples and 16 × 16.

use std::sync::atomic::AtomicBool;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use lenspath::accel::BvhSettings;
use lenspath::builtin::builtin_scene;
use lenspath::camera::PerspectiveCamera;
use lenspath::integrator::PathSettings;
use lenspath::render::{render, RenderSettings};

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
            path: PathSettings {
                max_depth: 16,
                light_samples,
            },
            ..Default::default()
        };
        let id = BenchmarkId::from_parameter(format!("{spp}spp_{light_samples}ls"));
        group.bench_function(id, |b| {
            b.iter(|| render(&compiled, &camera, &settings, &|_, _| {}, &AtomicBool::new(false)).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, cornell);
criterion_main!(benches);
