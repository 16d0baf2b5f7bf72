//! glTF 2.0 scenes (`.gltf` with `.bin` or embedded data, and binary `.glb`),
//! read with the gltf crate: the default scene's node tree with its
//! transforms, triangle meshes, perspective cameras, KHR_lights_punctual.
//!
//! Metallic-roughness materials map to lenspath's (Khronos glTF 2.0 spec,
//! appendix B):
//! - `KHR_materials_transmission` factor ≥ 0.5 → dielectric, `eta` from
//!   `KHR_materials_ior` (1.5), transmittance = base colour;
//! - metallic ≥ 0.5 → conductor whose normal-incidence reflectance is the base
//!   colour, α = roughness²;
//! - otherwise diffuse with the base colour;
//! - emissive factor × `KHR_materials_emissive_strength` > 0 → the mesh is also an area light.
//!
//! Light intensities (candela, lux) are taken as lenspath's radiometric units
//! one to one. Spot lights keep their outer cone and drop the soft inner edge.

use std::collections::HashMap;
use std::path::Path;

use base64::Engine;
use glam::{Mat4, Vec3};
use gltf::khr_lights_punctual::Kind;
use gltf::mesh::Mode;

use super::import::{
    conductor_from_reflectance, focus_on_subject, intern_material, transform_mesh, LoadedScene, MeshBuilder,
    SceneOptions, Warnings, MAX_TRIANGLES,
};
use crate::camera::CameraPose;
use crate::error::{Error, Result};
use crate::glass::Dispersion;
use crate::lights::Light;
use crate::materials::Material;
use crate::math::Rgb;
use crate::scene::{Scene, SceneView};
use crate::shapes::TriangleMesh;
use crate::spectrum::Emission;

/// Deepest node nesting followed.
const MAX_NODE_DEPTH: usize = 256;

/// Most node instances followed (shared subtrees can multiply exponentially).
const MAX_NODE_VISITS: usize = 1_000_000;

/// Reads a `.gltf` or `.glb` file; external buffers are read from beside it.
pub fn load_gltf(path: &Path, scope: &super::ReadScope) -> Result<LoadedScene> {
    let bytes = std::fs::read(path).map_err(|e| crate::fs::io_error(path, e))?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    parse_gltf(&bytes, path, &|uri| {
        let file = scope.check(&dir.join(uri)).map_err(|e| e.to_string())?;
        std::fs::read(&file).map_err(|e| format!("{}: {e}", file.display()))
    })
}

/// Parses glTF bytes; `read_uri` fetches an external buffer by its (decoded) relative URI.
pub fn parse_gltf(
    bytes: &[u8],
    path: &Path,
    read_uri: &dyn Fn(&str) -> std::result::Result<Vec<u8>, String>,
) -> Result<LoadedScene> {
    let fail = |m: String| Error::Parse {
        kind: crate::FileKind::Scene,
        path: path.to_path_buf(),
        message: m,
    };
    check_glb_header(bytes).map_err(&fail)?;
    let invalid = |e: gltf::Error| fail(format!("not valid glTF 2.0: {e}"));
    let unvalidated = gltf::Gltf::from_slice_without_validation(bytes).map_err(invalid)?;
    let json = unvalidated.document.into_json();
    check_accessor_references(&json).map_err(&fail)?;
    let gltf = gltf::Gltf {
        document: gltf::Document::from_json(json).map_err(invalid)?,
        blob: unvalidated.blob,
    };
    let mut buffers = Vec::new();
    for buffer in gltf.buffers() {
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => gltf.blob.clone().ok_or_else(|| {
                fail(format!(
                    "buffer {} refers to the GLB binary chunk, which is missing",
                    buffer.index()
                ))
            })?,
            gltf::buffer::Source::Uri(uri) => {
                if let Some(rest) = uri.strip_prefix("data:") {
                    let (_, payload) = rest
                        .split_once(";base64,")
                        .ok_or_else(|| fail(format!("buffer {}: data URI is not base64", buffer.index())))?;
                    base64::engine::general_purpose::STANDARD
                        .decode(payload)
                        .map_err(|e| fail(format!("buffer {}: bad base64 data: {e}", buffer.index())))?
                } else {
                    let decoded = urlencoding::decode(uri)
                        .map_err(|e| fail(format!("buffer {}: bad URI: {e}", buffer.index())))?;
                    read_uri(&decoded)
                        .map_err(|e| fail(format!("buffer {}: cannot read '{uri}': {e}", buffer.index())))?
                }
            }
        };
        if data.len() < buffer.length() {
            return Err(fail(format!(
                "buffer {} declares {} bytes but holds {}",
                buffer.index(),
                buffer.length(),
                data.len()
            )));
        }
        buffers.push(data);
    }

    let mut loader = Loader {
        buffers: &buffers,
        scene: Scene::default(),
        warnings: Warnings::default(),
        materials: HashMap::new(),
        cameras: 0,
        triangles: 0,
        node_visits: 0,
        fail: &fail,
    };
    let scene = gltf
        .default_scene()
        .or_else(|| gltf.scenes().next())
        .ok_or_else(|| fail("no scene: the file has nothing to render".into()))?;
    for node in scene.nodes() {
        loader.node(&node, Mat4::IDENTITY, &mut Vec::new())?;
    }
    let Loader {
        mut scene,
        warnings,
        cameras,
        ..
    } = loader;
    if scene.meshes.is_empty() {
        return Err(fail("no triangles in the scene: nothing to render".into()));
    }
    focus_on_subject(&mut scene);
    // glTF's unit is the metre.
    let options = SceneOptions {
        scene_unit_m: Some(1.0),
        ..Default::default()
    };
    Ok(LoadedScene::completed(scene, options, cameras, warnings, "glTF"))
}

/// The GLB header's length must be the file's (the glTF 2.0 specification,
/// "Binary glTF Layout"): shorter, and what follows it would be dropped
/// silently; longer, and the gltf crate subtracts before it checks (found
/// by fuzzing).
fn check_glb_header(bytes: &[u8]) -> std::result::Result<(), String> {
    if !bytes.starts_with(b"glTF") {
        return Ok(());
    }
    let word = |at: usize| {
        bytes
            .get(at..at + 4)
            .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]) as usize)
    };
    let (Some(version), Some(length)) = (word(4), word(8)) else {
        return Err(format!("GLB header is cut short ({} bytes)", bytes.len()));
    };
    if version != 2 {
        return Err(format!("GLB version {version}; lenspath reads glTF 2.0"));
    }
    if length < 12 + 8 || length != bytes.len() {
        return Err(format!(
            "GLB header gives a length of {length} bytes, but the file has {} (and a GLB needs at least 20)",
            bytes.len()
        ));
    }
    Ok(())
}

/// Every accessor a mesh primitive names must exist: gltf-json's validation
/// of a primitive's POSITION accessor indexes the accessor list before the
/// reference itself is checked (found by fuzzing).
fn check_accessor_references(json: &gltf::json::Root) -> std::result::Result<(), String> {
    let count = json.accessors.len();
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let used = prim.attributes.values().chain(prim.indices.as_ref());
            if let Some(bad) = used.map(|i| i.value()).find(|&i| i >= count) {
                return Err(format!(
                    "mesh {m} primitive {p} uses accessor {bad}, but the file has {count}"
                ));
            }
        }
    }
    Ok(())
}

/// An accessor's elements must lie inside its buffer view: the gltf crate's
/// readers compute the extent without checking (`count − 1` underflows for an
/// empty accessor; found by fuzzing). Sparse accessors are refused.
fn check_accessor_extent(a: &gltf::Accessor) -> std::result::Result<(), String> {
    if a.sparse().is_some() {
        return Err(format!(
            "accessor {} is sparse, which lenspath does not read",
            a.index()
        ));
    }
    if a.count() == 0 {
        return Err(format!("accessor {} has no elements", a.index()));
    }
    if let Some(view) = a.view() {
        let stride = view.stride().unwrap_or(a.size());
        let end = stride
            .checked_mul(a.count() - 1)
            .and_then(|v| v.checked_add(a.offset()))
            .and_then(|v| v.checked_add(a.size()));
        if end.is_none_or(|end| end > view.length()) {
            return Err(format!(
                "accessor {} ({} elements) runs past the end of buffer view {} ({} bytes)",
                a.index(),
                a.count(),
                view.index(),
                view.length()
            ));
        }
    }
    Ok(())
}

struct Loader<'a> {
    buffers: &'a [Vec<u8>],
    scene: Scene,
    warnings: Warnings,
    materials: HashMap<Option<usize>, (Material, Option<Rgb>)>,
    cameras: usize,
    triangles: usize,
    node_visits: usize,
    fail: &'a dyn Fn(String) -> Error,
}

impl Loader<'_> {
    fn node(&mut self, node: &gltf::Node, parent: Mat4, stack: &mut Vec<usize>) -> Result<()> {
        if stack.contains(&node.index()) {
            return Err((self.fail)(format!(
                "node {} is its own ancestor (a cycle)",
                node.index()
            )));
        }
        if stack.len() >= MAX_NODE_DEPTH {
            return Err((self.fail)(format!("nodes nest deeper than {MAX_NODE_DEPTH} levels")));
        }
        self.node_visits += 1;
        if self.node_visits > MAX_NODE_VISITS {
            return Err((self.fail)(format!(
                "shared nodes expand to more than {MAX_NODE_VISITS} instances"
            )));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if !world.is_finite() {
            return Err((self.fail)(format!("node {}: transform is not finite", node.index())));
        }
        if let Some(mesh) = node.mesh() {
            self.mesh(&mesh, &world)?;
        }
        if let Some(camera) = node.camera() {
            self.camera(node, &camera, &world)?;
        }
        if let Some(light) = node.light() {
            self.light(node, &light, &world)?;
        }
        stack.push(node.index());
        for child in node.children() {
            self.node(&child, world, stack)?;
        }
        stack.pop();
        Ok(())
    }

    fn mesh(&mut self, mesh: &gltf::Mesh, world: &Mat4) -> Result<()> {
        for prim in mesh.primitives() {
            let what = format!("mesh {} primitive {}", mesh.index(), prim.index());
            if prim.mode() != Mode::Triangles {
                self.warnings.add(format!(
                    "primitives in mode {:?} are not supported (only triangles); skipped",
                    prim.mode()
                ));
                continue;
            }
            // The gltf crate's readers assume the types the spec requires (and
            // hit `unreachable!` otherwise; found by fuzzing): check them first.
            use gltf::accessor::{DataType, Dimensions};
            use gltf::Semantic;
            let typed = |semantic: Semantic| {
                prim.get(&semantic)
                    .is_none_or(|a| a.data_type() == DataType::F32 && a.dimensions() == Dimensions::Vec3)
            };
            if !typed(Semantic::Positions) || !typed(Semantic::Normals) {
                return Err((self.fail)(format!(
                    "{what}: POSITION and NORMAL must be float VEC3 accessors"
                )));
            }
            for a in [
                prim.get(&Semantic::Positions),
                prim.get(&Semantic::Normals),
                prim.indices(),
            ]
            .into_iter()
            .flatten()
            {
                check_accessor_extent(&a).map_err(|e| (self.fail)(format!("{what}: {e}")))?;
            }
            if let Some(a) = prim.indices() {
                if !matches!(a.data_type(), DataType::U8 | DataType::U16 | DataType::U32)
                    || a.dimensions() != Dimensions::Scalar
                {
                    return Err((self.fail)(format!(
                        "{what}: indices must be an unsigned integer SCALAR accessor, not {:?} {:?}",
                        a.data_type(),
                        a.dimensions()
                    )));
                }
            }
            let reader = prim.reader(|b| self.buffers.get(b.index()).map(Vec::as_slice));
            let positions: Vec<Vec3> = reader
                .read_positions()
                .ok_or_else(|| (self.fail)(format!("{what}: no POSITION data")))?
                .map(Vec3::from_array)
                .collect();
            if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
                return Err((self.fail)(format!("{what}: vertex {i} is not finite")));
            }
            let normals: Option<Vec<Vec3>> = reader
                .read_normals()
                .map(|ns| ns.map(|n| Vec3::from_array(n).normalize_or_zero()).collect());
            let indices: Vec<u32> = match reader.read_indices() {
                Some(ix) => ix.into_u32().collect(),
                None => (0..positions.len() as u32).collect(),
            };
            if indices.len() % 3 != 0 {
                return Err((self.fail)(format!(
                    "{what}: {} indices is not a whole number of triangles",
                    indices.len()
                )));
            }
            if let Some(&bad) = indices.iter().find(|&&i| i as usize >= positions.len()) {
                return Err((self.fail)(format!(
                    "{what}: index {bad} is out of range ({} vertices)",
                    positions.len()
                )));
            }
            self.triangles += indices.len() / 3;
            if self.triangles > MAX_TRIANGLES {
                return Err((self.fail)(format!("the scene exceeds {MAX_TRIANGLES} triangles")));
            }
            let mut builder = MeshBuilder {
                mesh: TriangleMesh {
                    normals: normals.filter(|n| n.len() == positions.len()),
                    positions,
                    ..Default::default()
                },
                ..Default::default()
            };
            for t in indices.chunks_exact(3) {
                builder.triangle([t[0], t[1], t[2]]);
            }
            let mut tri_mesh = builder.finish(&what, &mut self.warnings);
            if tri_mesh.indices.is_empty() {
                continue;
            }
            transform_mesh(&mut tri_mesh, world);
            let (material, emission) = self.material(&prim.material());
            tri_mesh.material = intern_material(&mut self.scene, material);
            tri_mesh.emission = emission.map(Emission::from);
            self.scene.meshes.push(tri_mesh);
        }
        Ok(())
    }

    fn material(&mut self, m: &gltf::Material) -> (Material, Option<Rgb>) {
        if let Some(converted) = self.materials.get(&m.index()) {
            return *converted;
        }
        let pbr = m.pbr_metallic_roughness();
        let [r, g, b, _] = pbr.base_color_factor();
        let base = Rgb::new(r, g, b).clamp(Rgb::ZERO, Rgb::ONE);
        if pbr.base_color_texture().is_some() {
            self.warnings
                .add("textures are not supported: used the base colour factor");
        }
        let transmission = m.transmission().map_or(0.0, |t| t.transmission_factor());
        let material = if transmission >= 0.5 {
            let ior = f64::from(m.ior().filter(|n| *n > 0.0 && n.is_finite()).unwrap_or(1.5));
            // KHR_materials_dispersion gives 20 / V_d; 0 (its default) is none.
            let dispersion = m
                .extension_value("KHR_materials_dispersion")
                .and_then(|v| v.get("dispersion"))
                .and_then(|v| v.as_f64())
                .filter(|d| *d > 0.0 && d.is_finite());
            Material::Dielectric {
                eta: match dispersion {
                    Some(d) => Dispersion::from_abbe(ior, 20.0 / d).unwrap_or(Dispersion::Constant(ior)),
                    None => Dispersion::Constant(ior),
                },
                reflectance: Rgb::ONE,
                transmittance: base,
            }
        } else if pbr.metallic_factor() >= 0.5 {
            let roughness = pbr.roughness_factor().clamp(0.0, 1.0);
            conductor_from_reflectance(base, roughness * roughness)
        } else {
            Material::Diffuse { reflectance: base }
        };
        let emission = Rgb::from_array(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0);
        let emission = (emission.is_finite() && emission.max_element() > 0.0).then_some(emission.max(Rgb::ZERO));
        self.materials.insert(m.index(), (material, emission));
        (material, emission)
    }

    fn camera(&mut self, node: &gltf::Node, camera: &gltf::Camera, world: &Mat4) -> Result<()> {
        self.cameras += 1;
        if self.scene.view.is_some() {
            return Ok(());
        }
        let gltf::camera::Projection::Perspective(p) = camera.projection() else {
            self.warnings.add("an orthographic camera is not supported; skipped");
            return Ok(());
        };
        let fov_y_deg = p.yfov().to_degrees();
        if !(fov_y_deg > 0.0 && fov_y_deg < 180.0) {
            return Err((self.fail)(format!(
                "camera {}: yfov {} rad is not between 0 and π",
                camera.index(),
                p.yfov()
            )));
        }
        let eye = world.transform_point3(Vec3::ZERO);
        let forward = world.transform_vector3(Vec3::NEG_Z);
        let up = world.transform_vector3(Vec3::Y);
        let pose = CameraPose::try_look_at(eye, eye + forward, up)
            .map_err(|m| (self.fail)(format!("node {}: camera transform: {m}", node.index())))?;
        self.scene.view = Some(SceneView {
            pose,
            fov_y_deg,
            focus_distance: 0.0, // set from the bounds once everything is loaded
        });
        Ok(())
    }

    fn light(&mut self, node: &gltf::Node, light: &gltf::khr_lights_punctual::Light, world: &Mat4) -> Result<()> {
        let color = Rgb::from_array(light.color()) * light.intensity();
        if !color.is_finite() || color.min_element() < 0.0 {
            return Err((self.fail)(format!(
                "light {}: colour × intensity must be finite and ≥ 0",
                light.index()
            )));
        }
        let position = world.transform_point3(Vec3::ZERO);
        let direction = world
            .transform_vector3(Vec3::NEG_Z)
            .try_normalize()
            .ok_or_else(|| (self.fail)(format!("node {}: light transform is degenerate", node.index())))?;
        self.scene.lights.push(match light.kind() {
            Kind::Point => Light::Point {
                position,
                intensity: color.into(),
            },
            Kind::Directional => Light::Directional {
                direction,
                irradiance: color.into(),
            },
            Kind::Spot { outer_cone_angle, .. } => Light::Spot {
                position,
                direction,
                intensity: color.into(),
                cos_cutoff: outer_cone_angle.clamp(0.0, std::f32::consts::FRAC_PI_2).cos(),
                exponent: 0.0,
            },
        });
        Ok(())
    }
}
