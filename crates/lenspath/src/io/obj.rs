//! Wavefront OBJ meshes with MTL materials (read with tobj): groups and
//! objects become meshes, polygons are fan-triangulated, negative (relative)
//! indices are resolved, normals are used when present.
//!
//! A first pass over the text checks every `v` and `f` line, so a bad number
//! or an index out of range is reported with its line; tobj then reads the
//! checked text. MTL materials map to the closest lenspath material
//! (documented in docs/scene-format.md):
//! - `Ke` > 0 → emitter with radiance `Ke`;
//! - `d` < 1, or `illum` 4, 6, 7 or 9 (glass) → dielectric with `eta = Ni`
//!   (1.5 when absent), transmittance `Tf` (or 1);
//! - `illum` 3, or `Ks` > 0 with `Kd` = 0: metal: a conductor whose normal-incidence
//!   reflectance is `Ks`, roughness α = √(2 / (Ns + 2)) (the Phong-to-Beckmann
//!   correspondence, Walter et al. 2007 §5.2), a mirror when `Ns` ≥ 1000;
//! - otherwise diffuse with reflectance `Kd`.

use std::io::BufReader;
use std::path::Path;

use glam::Vec3;

use super::import::{
    conductor_from_reflectance, intern_material, LoadedScene, MeshBuilder, SceneOptions, Warnings, DEFAULT_MATERIAL,
    DEFAULT_REFLECTANCE, EMITTER_MATERIAL,
};
use crate::error::{Error, Result};
use crate::glass::Dispersion;
use crate::materials::Material;
use crate::math::Rgb;
use crate::scene::Scene;
use crate::shapes::TriangleMesh;
use crate::spectrum::Emission;

/// Reads an OBJ file and the MTL files it names (beside it, within `scope`).
pub fn load_obj(path: &Path, scope: &super::ReadScope) -> Result<LoadedScene> {
    let text = crate::fs::read_text(path, crate::FileKind::Scene)?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    // tobj's error for a library cannot say why; a refused one is told in a warning.
    let refused = std::cell::RefCell::new(None);
    let mut loaded = parse_obj(&text, path, &|mtl| match scope.check(&dir.join(mtl)) {
        Ok(file) => tobj::load_mtl(file),
        Err(e) => {
            *refused.borrow_mut() = Some(e.to_string());
            Err(tobj::LoadError::OpenFileFailed)
        }
    })?;
    if let Some(why) = refused.into_inner() {
        loaded.warnings.add(format!("material library not read: {why}"));
    }
    Ok(loaded)
}

/// Parses OBJ text; `load_mtl` reads a material library named by `mtllib`.
pub fn parse_obj(text: &str, path: &Path, load_mtl: &dyn Fn(&Path) -> tobj::MTLLoadResult) -> Result<LoadedScene> {
    check_lines(text).map_err(|(line, message)| Error::Parse {
        kind: crate::FileKind::Scene,
        path: path.to_path_buf(),
        message: format!("line {line}: {message}"),
    })?;
    let options = tobj::LoadOptions {
        triangulate: false,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, materials) =
        tobj::load_obj_buf(&mut BufReader::new(text.as_bytes()), &options, load_mtl).map_err(|e| Error::Parse {
            kind: crate::FileKind::Scene,
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
    let mut warnings = Warnings::default();
    let materials = materials.unwrap_or_else(|e| {
        warnings.add(format!("material library could not be read ({e}): used grey diffuse"));
        Vec::new()
    });
    let mut scene = Scene::default();
    let converted: Vec<(Material, Option<Rgb>)> =
        materials.iter().map(|m| convert_material(m, &mut warnings)).collect();
    for model in models {
        let m = model.mesh;
        let mut builder = MeshBuilder {
            mesh: TriangleMesh {
                positions: m
                    .positions
                    .chunks_exact(3)
                    .map(|p| Vec3::new(p[0], p[1], p[2]))
                    .collect(),
                normals: (!m.normals.is_empty() && m.normals.len() == m.positions.len()).then(|| {
                    m.normals
                        .chunks_exact(3)
                        .map(|n| Vec3::new(n[0], n[1], n[2]).normalize_or_zero())
                        .collect()
                }),
                ..Default::default()
            },
            ..Default::default()
        };
        let mut start = 0usize;
        let arities: Vec<u32> = if m.face_arities.is_empty() {
            vec![3; m.indices.len() / 3]
        } else {
            m.face_arities.clone()
        };
        for n in arities {
            let end = start + n as usize;
            builder.polygon(&m.indices[start..end]);
            start = end;
        }
        let name = if model.name.is_empty() {
            "unnamed group".to_string()
        } else {
            model.name.clone()
        };
        let mut mesh = builder.finish(&format!("{}: {name}", path.display()), &mut warnings);
        if mesh.indices.is_empty() {
            continue;
        }
        let (material, emission) = match m.material_id {
            Some(id) if id < converted.len() => converted[id],
            Some(_) => {
                warnings.add("a group uses a material the MTL file does not define: used grey diffuse");
                (DEFAULT_MATERIAL, None)
            }
            None => (DEFAULT_MATERIAL, None),
        };
        mesh.material = intern_material(&mut scene, material);
        mesh.emission = emission.map(Emission::from);
        scene.meshes.push(mesh);
    }
    if scene.meshes.is_empty() {
        return Err(Error::Parse {
            kind: crate::FileKind::Scene,
            path: path.to_path_buf(),
            message: "no faces with area: nothing to render".into(),
        });
    }
    Ok(LoadedScene::completed(
        scene,
        SceneOptions::default(),
        0,
        warnings,
        "OBJ",
    ))
}

/// The closest lenspath material to an MTL entry (see the module notes).
fn convert_material(m: &tobj::Material, warnings: &mut Warnings) -> (Material, Option<Rgb>) {
    let rgb = |c: Option<[f32; 3]>| c.map(Rgb::from_array).filter(|c| c.is_finite());
    let param = |key: &str| {
        let v: Vec<f32> = m
            .unknown_param
            .get(key)?
            .split_whitespace()
            .filter_map(|t| t.parse().ok())
            .collect();
        match v[..] {
            [x] => Some(Rgb::splat(x)),
            [r, g, b, ..] => Some(Rgb::new(r, g, b)),
            _ => None,
        }
    };
    let kd = rgb(m.diffuse).unwrap_or(DEFAULT_REFLECTANCE).clamp(Rgb::ZERO, Rgb::ONE);
    let ks = rgb(m.specular).unwrap_or(Rgb::ZERO).clamp(Rgb::ZERO, Rgb::ONE);
    let ke = rgb(m.emissive)
        .or_else(|| param("Ke"))
        .unwrap_or(Rgb::ZERO)
        .max(Rgb::ZERO);
    let illum = m.illumination_model.unwrap_or(2);
    let ns = m.shininess.filter(|n| n.is_finite() && *n >= 0.0).unwrap_or(0.0);
    if m.diffuse_texture.is_some() {
        warnings.add(format!(
            "material '{}': textures are not supported; used its Kd colour",
            m.name
        ));
    }
    if ke.max_element() > 0.0 {
        return (EMITTER_MATERIAL, Some(ke));
    }
    if m.dissolve.is_some_and(|d| d < 1.0) || matches!(illum, 4 | 6 | 7 | 9) {
        let eta = m.optical_density.filter(|n| *n > 0.0 && n.is_finite()).unwrap_or(1.5);
        let transmittance = param("Tf").unwrap_or(Rgb::ONE).clamp(Rgb::ZERO, Rgb::ONE);
        return (
            Material::Dielectric {
                eta: Dispersion::Constant(f64::from(eta)),
                reflectance: Rgb::ONE,
                transmittance,
            },
            None,
        );
    }
    if illum == 3 || (ks.max_element() > 0.0 && kd.max_element() == 0.0) {
        if ns >= 1000.0 {
            return (Material::Mirror { reflectance: ks }, None);
        }
        return (conductor_from_reflectance(ks, (2.0 / (ns + 2.0)).sqrt()), None);
    }
    (Material::Diffuse { reflectance: kd }, None)
}

/// Checks the `v` and `f` lines: numbers parse and are finite, every face index
/// (1-based, or negative counting back) refers to a vertex defined before it.
fn check_lines(text: &str) -> std::result::Result<(), (usize, String)> {
    let (mut positions, mut texcoords, mut normals) = (0i64, 0i64, 0i64);
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = raw.split('#').next().unwrap_or("").trim();
        let mut words = line.split_ascii_whitespace();
        let Some(keyword) = words.next() else { continue };
        match keyword {
            "v" | "vn" | "vt" => {
                let needed = if keyword == "vt" { 1 } else { 3 };
                let values: Vec<&str> = words.collect();
                if values.len() < needed {
                    return Err((
                        line_no,
                        format!("'{keyword}' needs at least {needed} numbers, found {}", values.len()),
                    ));
                }
                for v in values.iter().take(if keyword == "v" { 3 } else { values.len() }) {
                    match v.parse::<f32>() {
                        Ok(x) if x.is_finite() => {}
                        _ => return Err((line_no, format!("'{v}' is not a finite number"))),
                    }
                }
                match keyword {
                    "v" => positions += 1,
                    "vt" => texcoords += 1,
                    _ => normals += 1,
                }
            }
            "f" => {
                let corners: Vec<&str> = words.collect();
                if corners.len() < 3 {
                    return Err((
                        line_no,
                        format!("a face needs at least 3 vertices, found {}", corners.len()),
                    ));
                }
                for corner in corners {
                    for (k, part) in corner.split('/').enumerate() {
                        if part.is_empty() && k > 0 {
                            continue;
                        }
                        let (what, count) = match k {
                            0 => ("vertex", positions),
                            1 => ("texture coordinate", texcoords),
                            2 => ("normal", normals),
                            _ => return Err((line_no, format!("'{corner}' has more than three indices"))),
                        };
                        let index: i64 = part.parse().map_err(|_| {
                            (
                                line_no,
                                format!("'{corner}' is not a face vertex (v, v/vt, v//vn or v/vt/vn)"),
                            )
                        })?;
                        let resolved = if index < 0 { count + index + 1 } else { index };
                        if index == 0 || resolved < 1 || resolved > count {
                            return Err((
                                line_no,
                                format!("face refers to {what} {index}, but {count} are defined before this line"),
                            ));
                        }
                    }
                }
            }
            _ => {}
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str, mtl: &'static str) -> Result<LoadedScene> {
        parse_obj(text, Path::new("test.obj"), &move |_| {
            tobj::load_mtl_buf(&mut mtl.as_bytes())
        })
    }

    #[test]
    fn groups_negative_indices_and_polygons() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\ng quad\nf -4 -3 -2 -1\ng tri\nf 1 2 3\n";
        let loaded = parse(text, "").unwrap();
        assert_eq!(loaded.scene.meshes.len(), 2);
        assert_eq!(loaded.scene.triangle_count(), 3);
        assert!(loaded.scene.meshes[0].normals.is_none());
    }

    #[test]
    fn mtl_maps_to_the_closest_material() {
        let mtl = "newmtl red\nKd 0.8 0.1 0.1\nnewmtl lamp\nKd 0 0 0\nKe 5 5 4\nnewmtl glass\nKd 0 0 0\nd 0.2\nNi 1.33\nnewmtl gold\nKd 0 0 0\nKs 0.9 0.7 0.3\nNs 200\n";
        let text = "mtllib x.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\ng a\nusemtl red\nf 1 2 3\ng b\nusemtl lamp\nf 1 2 3\ng c\nusemtl glass\nf 1 2 3\ng d\nusemtl gold\nf 1 2 3\n";
        let loaded = parse(text, mtl).unwrap();
        let s = &loaded.scene;
        let mat = |i: usize| s.materials[s.meshes[i].material as usize];
        assert_eq!(
            mat(0),
            Material::Diffuse {
                reflectance: Rgb::new(0.8, 0.1, 0.1)
            }
        );
        assert_eq!(s.meshes[1].emission, Some(Rgb::new(5.0, 5.0, 4.0).into()));
        assert!(matches!(mat(2), Material::Dielectric { eta, .. } if (eta.n_d() - 1.33).abs() < 1e-6));
        let Material::Conductor { eta, k, alpha } = mat(3) else {
            panic!("{:?}", mat(3))
        };
        // Normal-incidence reflectance of the conductor equals Ks.
        let f0 = crate::materials::fresnel_complex(1.0, eta.x, k.x);
        assert!((f0 - 0.9).abs() < 1e-3, "{f0}");
        assert!((alpha - (2.0f32 / 202.0).sqrt()).abs() < 1e-6);
    }

    #[test]
    fn bad_lines_are_reported_with_their_number() {
        let err = parse("v 0 0 0\nv 1 0 0\nv 1 nan 0\n", "").unwrap_err().to_string();
        assert!(err.contains("line 3") && err.contains("'nan'"), "{err}");
        let err = parse("v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 4\n", "")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("line 4: face refers to vertex 4, but 3 are defined"),
            "{err}"
        );
        let err = parse("v 0 0 0\nf 1 -2 1\n", "").unwrap_err().to_string();
        assert!(err.contains("vertex -2"), "{err}");
    }
}
