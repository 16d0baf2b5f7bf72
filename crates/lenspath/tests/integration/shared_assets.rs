//! Tests on the third-party meshes and lens tables in ../shared (see ../shared/ASSETS.md).
//! They skip, saying so, when ../shared is not beside the repository (`shared_folder`).

use std::path::PathBuf;

use glam::Vec3;
use lenspath::accel::{Bvh, BvhSettings, PrimGeometry};
use lenspath::io::load_mesh;
use lenspath::raysets::{coherent_rays, incoherent_rays};
use lenspath::shapes::{intersect_triangle, TriangleRay};

use crate::shared_folder::shared;

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

/// The unscaled tables (older distance-from-previous convention) are the
/// scaled ones up to scale, and the scaled ones are the built-in lenses.
#[test]
fn unscaled_lens_tables_match_their_scaled_twins() {
    use lenspath::lens::{LensPrescription, LensSystem};
    for (unscaled, scaled, builtin, factor) in [
        ("lenses/dgauss.dat", "lenses/dgauss.50mm.dat", "dgauss50", 0.5),
        ("lenses/wide.dat", "lenses/wide.22mm.dat", "wide22", 0.22),
        ("lenses/telephoto.dat", "lenses/telephoto.250mm.dat", "tele250", 2.5),
        ("lenses/fisheye.dat", "lenses/fisheye.10mm.dat", "fisheye10", 0.1),
    ] {
        let (Some(unscaled_path), Some(scaled_path)) = (shared(unscaled), shared(scaled)) else {
            return;
        };
        let load = |p: &PathBuf| LensPrescription::load(p.to_str().unwrap()).unwrap();
        let (small, big) = (load(&scaled_path), load(&unscaled_path).scaled(factor));
        assert_eq!(small.surfaces().len(), big.surfaces().len(), "{unscaled}");
        // The last thickness is absent from the older tables (the sensor is placed by focusing).
        let last = small.surfaces().len() - 1;
        for (i, (a, b)) in small.surfaces().iter().zip(big.surfaces()).enumerate() {
            let close = |x: f64, y: f64| (x - y).abs() <= 1e-9 + 1e-6 * x.abs().max(y.abs());
            assert!(
                close(a.radius_mm, b.radius_mm),
                "{unscaled} row {i}: radius {} vs {}",
                a.radius_mm,
                b.radius_mm
            );
            assert!(close(a.ior_d(), b.ior_d()), "{unscaled} row {i}: index");
            assert!(
                close(a.aperture_diameter_mm, b.aperture_diameter_mm),
                "{unscaled} row {i}: aperture"
            );
            if i < last {
                assert!(close(a.thickness_mm, b.thickness_mm), "{unscaled} row {i}: thickness");
            }
        }
        let efl = |l: &LensPrescription| LensSystem::new(l).paraxial().unwrap().effective_focal_length_mm;
        let unscaled_efl = efl(&load(&unscaled_path));
        assert!(
            (efl(&small) / unscaled_efl / factor - 1.0).abs() < 1e-6,
            "{unscaled}: focal lengths"
        );
        // The built-in is pbrt's table, to which it may add its glasses' dispersion.
        let geometry = |l: &LensPrescription| {
            l.surfaces()
                .iter()
                .map(|s| (s.radius_mm, s.thickness_mm, s.ior_d(), s.aperture_diameter_mm))
                .collect::<Vec<_>>()
        };
        assert_eq!(
            geometry(&small),
            geometry(&LensPrescription::load(builtin).unwrap()),
            "{builtin}"
        );
    }
}
