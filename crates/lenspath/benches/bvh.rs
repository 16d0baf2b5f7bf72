//! BVH build and traversal: the 1 M-triangle procedural mesh, and the
//! Stanford dragon from ../shared when it is present.

use std::path::Path;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::Vec3;
use lenspath::accel::{Bvh, BvhSettings, PrimGeometry};
use lenspath::builtin::torus_knot;
use lenspath::io::load_mesh;
use lenspath::raysets::{coherent_rays, incoherent_rays};
use lenspath::shapes::TriangleMesh;

fn primitives(mesh: &TriangleMesh) -> Vec<(PrimGeometry, u32)> {
    mesh.triangles()
        .enumerate()
        .map(|(i, t)| (PrimGeometry::Triangle(t), i as u32))
        .collect()
}

fn meshes() -> Vec<(String, TriangleMesh)> {
    let mut meshes = vec![("torus_knot_1m".to_string(), torus_knot(1_000_000).unwrap())];
    let dragon = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/meshes/dragon_100k.ply");
    match load_mesh(&dragon) {
        Ok(mesh) => meshes.push(("dragon_100k".to_string(), mesh)),
        Err(e) => eprintln!("skipping the dragon ({e}): ../shared is not beside the repository"),
    }
    meshes
}

fn bvh(c: &mut Criterion) {
    let settings = BvhSettings::default();
    for (name, mesh) in meshes() {
        let prims = primitives(&mesh);
        let mut group = c.benchmark_group("bvh_build");
        group.sample_size(10);
        group.throughput(Throughput::Elements(prims.len() as u64));
        group.bench_function(BenchmarkId::from_parameter(&name), |b| {
            b.iter_batched(
                || prims.clone(),
                |p| Bvh::build(p, &settings),
                criterion::BatchSize::LargeInput,
            )
        });
        group.finish();

        let bvh = Bvh::build(prims, &settings);
        let bounds = bvh.bounds();
        let (lo, hi) = (Vec3::from(bounds.min), Vec3::from(bounds.max));
        let n = 100_000;
        let mut group = c.benchmark_group("bvh_traverse_1thread");
        group.sample_size(10);
        group.throughput(Throughput::Elements(n as u64));
        for (kind, rays) in [
            ("coherent", coherent_rays(lo, hi, n)),
            ("incoherent", incoherent_rays(lo, hi, n)),
        ] {
            group.bench_function(BenchmarkId::new(kind, &name), |b| {
                b.iter(|| {
                    rays.iter()
                        .filter(|r| bvh.intersect(r, f32::INFINITY).is_some())
                        .count()
                })
            });
        }
        group.finish();
    }
}

criterion_group!(benches, bvh);
criterion_main!(benches);
