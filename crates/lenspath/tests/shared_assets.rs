//! Tests on the third-party meshes in ../shared (see ../shared/ASSETS.md).
//! They skip, saying so, when ../shared is not beside the repository.

use std::path::PathBuf;

use glam::Vec3;
use lenspath::accel::{Bvh, BvhSettings, PrimGeometry};
use lenspath::io::mesh::load_mesh;
use lenspath::raysets::{coherent_rays, incoherent_rays};
use lenspath::shapes::{intersect_triangle, TriangleRay};

fn shared(path: &str) -> Option<PathBuf> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared")
        .join(path);
    if p.exists() {
        Some(p)
    } else {
        eprintln!("skipping: {} not found (../shared is absent)", p.display());
        None
    }
}

/// Vertex and triangle counts from ASSETS.md, for ASCII and binary PLY and OBJ.
#[test]
fn meshes_load_with_the_documented_counts() {
    for (path, vertices, triangles) in [
        ("meshes/dragon_100k.ply", 50_000, 100_000),
        ("meshes/bun_zipper.ply", 35_947, 69_451),
        ("meshes/dragon_vrip_res3.ply", 22_998, 47_794),
        ("meshes/dragon_100k.obj", 50_000, 100_000),
        ("meshes/lucy_100k.obj", 49_987, 99_970),
    ] {
        let Some(file) = shared(path) else { return };
        let mesh = load_mesh(&file).unwrap();
        assert_eq!(
            (mesh.positions.len(), mesh.indices.len()),
            (vertices, triangles),
            "{path}"
        );
    }
}

/// The BVH on the real dragon agrees with brute force on camera and random rays.
#[test]
fn dragon_bvh_matches_brute_force() {
    let Some(file) = shared("meshes/dragon_100k.ply") else {
        return;
    };
    let mesh = load_mesh(&file).unwrap();
    let tris: Vec<[Vec3; 3]> = mesh.triangles().collect();
    let prims = tris
        .iter()
        .enumerate()
        .map(|(i, t)| (PrimGeometry::Triangle(*t), i as u32))
        .collect();
    let bvh = Bvh::build(prims, &BvhSettings::default());
    let b = bvh.bounds();
    let (lo, hi) = (Vec3::from(b.min), Vec3::from(b.max));
    let mut hits = 0;
    for ray in coherent_rays(lo, hi, 400)
        .into_iter()
        .chain(incoherent_rays(lo, hi, 400))
    {
        let tr = TriangleRay::new(&ray);
        let expected = tris
            .iter()
            .filter_map(|t| intersect_triangle(&tr, t, f32::INFINITY).map(|h| h.0))
            .min_by(f32::total_cmp);
        let got = bvh.intersect(&ray, f32::INFINITY).map(|h| h.t);
        assert_eq!(got, expected);
        hits += usize::from(got.is_some());
    }
    assert!(hits > 100, "only {hits} of 800 rays hit the dragon");
}
