//! Scene loading: a 1 M-triangle binary PLY (the procedural knot, written at
//! start), and the 100 k-triangle Stanford dragon as OBJ and PLY and the
//! CS184 CBbunny COLLADA scene from ../shared when present. Targets (issue 4):
//! the 1 M PLY under 1 s, the OBJ dragon under 0.3 s.

use std::path::{Path, PathBuf};

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use lenspath::builtin::torus_knot;
use lenspath::io::load_scene;
use lenspath::io::ply::write_ply;

fn files(dir: &Path) -> Vec<(String, PathBuf, u64)> {
    let knot = dir.join("knot_1m.ply");
    write_ply(&knot, &torus_knot(1_000_000).unwrap()).unwrap();
    let mut files = vec![("knot_1m_binary_ply".to_string(), knot, 1_000_000)];
    let shared = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared");
    for (name, path, triangles) in [
        ("dragon_100k_obj", "meshes/dragon_100k.obj", 100_000),
        ("dragon_100k_binary_ply", "meshes/dragon_100k.ply", 100_000),
        ("cbbunny_dae", "scenes/cs184/sky/CBbunny.dae", 28_588),
    ] {
        let p = shared.join(path);
        if p.exists() {
            files.push((name.to_string(), p, triangles));
        } else {
            eprintln!("skipping {name}: ../shared is not beside the repository");
        }
    }
    files
}

fn load(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let mut group = c.benchmark_group("load_scene");
    group.sample_size(10);
    for (name, path, triangles) in files(dir.path()) {
        group.throughput(Throughput::Elements(triangles));
        group.bench_function(BenchmarkId::from_parameter(&name), |b| {
            b.iter(|| load_scene(&path).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, load);
criterion_main!(benches);
