//! lenspath's own scene file (TOML, read with serde): camera and lens, film,
//! integrator settings, named materials, lights, and shapes that are spheres,
//! quads or mesh files in any format lenspath reads, each with a transform. A
//! `base` scene file (say a CS184 Cornell box) or a `builtin` scene can be
//! extended, and a `[sensor]` records it through an image sensor. The
//! schema, with examples, is docs/scene-format.md; unknown keys
//! are errors, so a typo never passes silently. [`SceneSettingsFile`] writes
//! the camera and render settings over a base scene (what `lenspath view`
//! saves).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use glam::{Mat4, Vec3};
use serde::{Deserialize, Serialize};

use super::import::{
    intern_material, scene_bounds, subject_distance, transform_mesh, LensOptions, LoadedScene, SceneOptions, Warnings,
    EMITTER_MATERIAL,
};
use crate::builtin::{builtin_scene, DEFAULT_MESH_TRIANGLES};
use crate::camera::{ApertureShape, CameraPose};
use crate::error::{Error, Result};
use crate::glass::Dispersion;
use crate::integrator::IntegratorKind;
use crate::lights::Light;
use crate::materials::Material;
use crate::math::Rgb;
use crate::names::Named;
use crate::sampling::SamplerKind;
use crate::scene::{Scene, SceneView};
use crate::sensor::{Cfa, Demosaic, SensorDescription, ToneCurve, WhiteBalance};
use crate::shapes::{Sphere, TriangleMesh};
use crate::spectrum::Emission;

/// A colour: one grey value or `[r, g, b]`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
#[serde(untagged)]
enum Color {
    Grey(f32),
    Rgb([f32; 3]),
}

impl Color {
    fn rgb(self) -> Rgb {
        match self {
            Color::Grey(v) => Rgb::splat(v),
            Color::Rgb(c) => Rgb::from_array(c),
        }
    }
}

/// What a light or an emitting shape gives off: a [`Color`], a black body
/// (`{ blackbody_k = 2700, luminance = 5 }`) or a table of
/// `[wavelength_nm, value]` pairs (`{ spectrum = [[585, 0], [589, 1], [593, 0]],
/// luminance = 2 }`); a spectrum's luminance defaults to 1, RGB white's.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(untagged)]
enum EmissionSpec {
    Color(Color),
    Blackbody {
        blackbody_k: f32,
        #[serde(skip_serializing_if = "Option::is_none")]
        luminance: Option<f32>,
    },
    Table {
        spectrum: Vec<[f32; 2]>,
        #[serde(skip_serializing_if = "Option::is_none")]
        luminance: Option<f32>,
    },
}

impl EmissionSpec {
    fn emission(&self) -> std::result::Result<Emission, String> {
        match self {
            EmissionSpec::Color(c) => Ok(c.rgb().into()),
            EmissionSpec::Blackbody { blackbody_k, luminance } => {
                Emission::blackbody(*blackbody_k, luminance.unwrap_or(1.0)).map_err(|e| e.to_string())
            }
            EmissionSpec::Table { spectrum, luminance } => {
                let pairs: Vec<(f32, f32)> = spectrum.iter().map(|[l, v]| (*l, *v)).collect();
                Emission::tabulated(&pairs, luminance.unwrap_or(1.0)).map_err(|e| e.to_string())
            }
        }
    }
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    /// Another scene file whose shapes, materials, lights and camera this one starts from.
    base: Option<PathBuf>,
    /// A built-in scene to start from instead (`cornell-spheres`, ...).
    builtin: Option<String>,
    /// Triangles of the built-in `cornell-mesh`'s procedural mesh.
    #[serde(skip_serializing_if = "Option::is_none")]
    mesh_triangles: Option<usize>,
    scene_unit_m: Option<f64>,
    camera: Option<CameraSpec>,
    film: Option<FilmSpec>,
    integrator: Option<IntegratorSpec>,
    #[serde(skip_serializing_if = "Option::is_none")]
    sensor: Option<SensorTable>,
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    materials: BTreeMap<String, MaterialSpec>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    lights: Vec<LightSpec>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    shapes: Vec<ShapeSpec>,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct CameraSpec {
    eye: [f32; 3],
    look_at: [f32; 3],
    #[serde(default = "y_up")]
    up: [f32; 3],
    fov_y_deg: Option<f32>,
    focus_distance: Option<f32>,
    /// Focus by the sensor's place instead: mm behind the aperture stop.
    sensor_depth_mm: Option<f64>,
    lens: Option<String>,
    f_number: Option<f64>,
    sensor_mm: Option<[f64; 2]>,
    aperture: Option<String>,
    /// Whether the lens's glasses disperse (default: they do).
    #[serde(skip_serializing_if = "Option::is_none")]
    dispersion: Option<bool>,
    /// Whether the pupil diffracts (default: `camera::DEFAULT_DIFFRACTION`).
    #[serde(skip_serializing_if = "Option::is_none")]
    diffraction: Option<bool>,
    /// Whether an anamorphic lens's image is desqueezed (default: it is not).
    #[serde(skip_serializing_if = "Option::is_none")]
    desqueeze: Option<bool>,
}

fn y_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct FilmSpec {
    width: u32,
    height: u32,
}

/// A scene file's `[sensor]` table (and `lenspath view`'s sensor settings):
/// [`SensorDescription`]'s fields with the same names and units, its
/// choices spelt as the CLI spells them; an absent field is the default.
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs)] // The fields are SensorDescription's, documented there.
pub struct SensorTable {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub model: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cfa: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub exposure_time_s: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub iso: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub white_luminance_cd_m2: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub peak_qe: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub read_noise_e: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub full_well_e_per_um2: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dark_current_e_per_s_um2: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dsnu_e: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub prnu: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bit_depth: Option<u32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub black_level_dn: Option<u32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frame_seed: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fixed_pattern_seed: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub white_balance: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub demosaic: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tone_curve: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub auto_exposure: Option<bool>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_exposure_time_s: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_iso: Option<f64>,
}

impl SensorTable {
    /// The sensor the table describes (its choices read, not yet resolved).
    pub fn description(&self) -> Result<SensorDescription> {
        Ok(SensorDescription {
            model: self.model.clone(),
            peak_qe: self.peak_qe,
            cfa: self.cfa.as_deref().map(Cfa::parse).transpose()?,
            exposure_time_s: self.exposure_time_s,
            iso: self.iso,
            white_luminance_cd_m2: self.white_luminance_cd_m2,
            read_noise_e: self.read_noise_e,
            full_well_e_per_um2: self.full_well_e_per_um2,
            dark_current_e_per_s_um2: self.dark_current_e_per_s_um2,
            dsnu_e: self.dsnu_e,
            prnu: self.prnu,
            bit_depth: self.bit_depth,
            black_level_dn: self.black_level_dn,
            frame_seed: self.frame_seed,
            fixed_pattern_seed: self.fixed_pattern_seed,
            white_balance: self.white_balance.as_deref().map(WhiteBalance::parse).transpose()?,
            demosaic: self.demosaic.as_deref().map(Demosaic::parse).transpose()?,
            tone_curve: self.tone_curve.as_deref().map(ToneCurve::parse).transpose()?,
            auto_exposure: self.auto_exposure,
            max_exposure_time_s: self.max_exposure_time_s,
            max_iso: self.max_iso,
        })
    }

    /// The table that reads back as `d`.
    pub fn of(d: &SensorDescription) -> SensorTable {
        SensorTable {
            model: d.model.clone(),
            cfa: d.cfa.map(|c| c.name().into()),
            exposure_time_s: d.exposure_time_s,
            iso: d.iso,
            white_luminance_cd_m2: d.white_luminance_cd_m2,
            peak_qe: d.peak_qe,
            read_noise_e: d.read_noise_e,
            full_well_e_per_um2: d.full_well_e_per_um2,
            dark_current_e_per_s_um2: d.dark_current_e_per_s_um2,
            dsnu_e: d.dsnu_e,
            prnu: d.prnu,
            bit_depth: d.bit_depth,
            black_level_dn: d.black_level_dn,
            frame_seed: d.frame_seed,
            fixed_pattern_seed: d.fixed_pattern_seed,
            white_balance: d.white_balance.map(|w| w.spelling()),
            demosaic: d.demosaic.map(|m| m.name().into()),
            tone_curve: d.tone_curve.map(|t| t.name().into()),
            auto_exposure: d.auto_exposure,
            max_exposure_time_s: d.max_exposure_time_s,
            max_iso: d.max_iso,
        }
    }
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct IntegratorSpec {
    /// `path` or `guided` ([`IntegratorKind::NAMES`]).
    #[serde(rename = "type", skip_serializing_if = "Option::is_none")]
    kind: Option<String>,
    spp: Option<u32>,
    max_depth: Option<u32>,
    light_samples: Option<u32>,
    seed: Option<u32>,
    sampler: Option<String>,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
enum MaterialSpec {
    Diffuse {
        reflectance: Color,
    },
    Mirror {
        reflectance: Color,
    },
    Dielectric {
        /// A constant index (no dispersion).
        #[serde(skip_serializing_if = "Option::is_none")]
        eta: Option<f32>,
        /// A catalogue glass (`N-BK7`, `ohara:S-LAH59`): its dispersion.
        #[serde(skip_serializing_if = "Option::is_none")]
        glass: Option<String>,
        /// n_d, with `v_d` for the Abbe (Cauchy) dispersion model.
        #[serde(skip_serializing_if = "Option::is_none")]
        n_d: Option<f64>,
        #[serde(skip_serializing_if = "Option::is_none")]
        v_d: Option<f64>,
        reflectance: Option<Color>,
        transmittance: Option<Color>,
    },
    Conductor {
        /// RGB indices, or `metal` instead.
        #[serde(skip_serializing_if = "Option::is_none")]
        eta: Option<Color>,
        #[serde(skip_serializing_if = "Option::is_none")]
        k: Option<Color>,
        /// A measured metal by name (`gold`, `Ag`...).
        #[serde(skip_serializing_if = "Option::is_none")]
        metal: Option<String>,
        #[serde(default)]
        alpha: f32,
    },
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
enum LightSpec {
    Point {
        position: [f32; 3],
        intensity: EmissionSpec,
    },
    Spot {
        position: [f32; 3],
        look_at: [f32; 3],
        intensity: EmissionSpec,
        /// The cone's half angle (pbrt's `coneangle`, Mitsuba's `cutoff_angle`).
        cutoff_angle_deg: Option<f32>,
        /// Deprecated: the cone's full angle.
        #[serde(skip_serializing_if = "Option::is_none")]
        cone_angle_deg: Option<f32>,
        #[serde(default)]
        exponent: f32,
    },
    Directional {
        direction: [f32; 3],
        irradiance: EmissionSpec,
    },
    Environment {
        radiance: EmissionSpec,
    },
}

#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct TransformSpec {
    scale: Option<Color>,
    #[serde(default)]
    rotate: Vec<RotationSpec>,
    translate: Option<[f32; 3]>,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RotationSpec {
    axis: [f32; 3],
    degrees: f32,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
enum ShapeSpec {
    Sphere {
        center: [f32; 3],
        radius: f32,
        material: Option<String>,
        emission: Option<EmissionSpec>,
    },
    Quad {
        corner: [f32; 3],
        edge_u: [f32; 3],
        edge_v: [f32; 3],
        material: Option<String>,
        emission: Option<EmissionSpec>,
    },
    Mesh {
        file: PathBuf,
        material: Option<String>,
        emission: Option<EmissionSpec>,
        #[serde(default)]
        transform: TransformSpec,
    },
}

/// Reads a lenspath TOML scene file; the files it names (base scene,
/// meshes, a lens table), and theirs, must be within `scope`.
pub fn load_scene_file(path: &Path, scope: &super::ReadScope) -> Result<LoadedScene> {
    load_included(path, &[], scope)
}

/// Most scene files deep a chain of `base` and mesh files may go: far more
/// than any scene needs, and well within the stack of any thread that
/// loads a scene (a chain of 1 700 overflowed the CLI's).
pub const MAX_INCLUDE_DEPTH: usize = 64;

/// Loads `path`, which `including` (outermost first) reached through `base` or mesh files.
fn load_included(path: &Path, including: &[PathBuf], scope: &super::ReadScope) -> Result<LoadedScene> {
    if including.len() >= MAX_INCLUDE_DEPTH {
        return Err(Error::InvalidScene(too_deep(&including[0], path)));
    }
    let text = crate::fs::read_text(path, crate::FileKind::Scene)?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let canonical = path.canonicalize().map_err(|e| crate::fs::io_error(path, e))?;
    let mut chain = including.to_vec();
    chain.push(canonical);
    parse_scene_file(&text, path, &|file: &Path| {
        let file = dir.join(file);
        let canonical = scope.check(&file)?;
        if file.extension().is_some_and(|e| e.eq_ignore_ascii_case("toml")) {
            if chain.contains(&canonical) {
                return Err(Error::InvalidArgument(format!(
                    "{} includes itself (a cycle of base or mesh files)",
                    file.display()
                )));
            }
            load_included(&file, &chain, scope)
        } else {
            super::load_scene_in(&file, scope)
        }
    })
    .and_then(|mut loaded| {
        // Lens files named in the scene are relative to it, and within its scope.
        if let Some(lens) = loaded.options.lens.as_mut().and_then(|l| l.lens.as_mut()) {
            if lens.contains(['/', '\\', '.']) {
                let file = dir.join(&*lens);
                scope.check(&file).map_err(|e| Error::Parse {
                    kind: crate::FileKind::Scene,
                    path: path.to_path_buf(),
                    message: format!("[camera] lens: {e}"),
                })?;
                *lens = file.display().to_string();
            }
        }
        Ok(loaded)
    })
}

/// The message of a chain of included files from `outermost` that reached
/// `path` past [`MAX_INCLUDE_DEPTH`].
fn too_deep(outermost: &Path, path: &Path) -> String {
    format!(
        "{}: more than {MAX_INCLUDE_DEPTH} scene files deep (a chain of base or mesh files reaching {})",
        outermost.display(),
        path.display()
    )
}

/// `e`, an error loading a file this scene file includes, said as `fail`
/// says it after `what` ("base", "shape 3"); a chain too deep is passed on
/// as it is, or its message would name every file of the chain.
fn included_error(e: Error, what: &str, fail: impl Fn(String) -> Error) -> Error {
    match e {
        Error::InvalidScene(m) if m.contains("scene files deep") => Error::InvalidScene(m),
        e => fail(format!("{what}: {e}")),
    }
}

/// Parses scene-file text; `load` reads the `base` and mesh files it names.
pub fn parse_scene_file(text: &str, path: &Path, load: &dyn Fn(&Path) -> Result<LoadedScene>) -> Result<LoadedScene> {
    let fail = |m: String| Error::Parse {
        kind: crate::FileKind::Scene,
        path: path.to_path_buf(),
        message: m,
    };
    let file: SceneFile = toml::from_str(text).map_err(|e| fail(one_line(&e, text)))?;

    let (mut scene, mut options, mut warnings, mut cameras) = match (&file.base, &file.builtin) {
        (Some(_), Some(_)) => return Err(fail("give base or builtin, not both".into())),
        (None, Some(name)) => {
            let triangles = file.mesh_triangles.unwrap_or(DEFAULT_MESH_TRIANGLES);
            let scene = builtin_scene(name, triangles).map_err(|e| fail(format!("builtin: {e}")))?;
            (scene, SceneOptions::default(), Warnings::default(), 1)
        }
        (Some(base), None) => {
            let b = load(base).map_err(|e| included_error(e, "base", fail))?;
            let mut warnings = Warnings::default();
            for (w, n) in b.warnings.iter() {
                warnings.add_n(format!("{}: {w}", base.display()), n);
            }
            (b.scene, b.options, warnings, b.cameras)
        }
        (None, None) => (Scene::default(), SceneOptions::default(), Warnings::default(), 0),
    };
    if file.mesh_triangles.is_some() && file.builtin.is_none() {
        return Err(fail(
            "mesh_triangles goes with builtin (the procedural mesh of cornell-mesh)".into(),
        ));
    }
    if let Some(unit) = file.scene_unit_m {
        if !(unit > 0.0 && unit.is_finite()) {
            return Err(fail(format!("scene_unit_m must be positive, got {unit}")));
        }
        options.scene_unit_m = Some(unit);
    }
    if let Some(film) = &file.film {
        if film.width == 0 || film.height == 0 {
            return Err(fail("[film] width and height must be positive".into()));
        }
        options.resolution = Some((film.width, film.height));
    }
    if let Some(i) = &file.integrator {
        options.spp = i.spp.or(options.spp);
        options.max_depth = i.max_depth.or(options.max_depth);
        options.light_samples = i.light_samples.or(options.light_samples);
        options.seed = i.seed.or(options.seed);
        if let Some(name) = &i.kind {
            let kind = IntegratorKind::parse(name).map_err(|e| fail(format!("[integrator] type: {e}")))?;
            options.integrator = Some(kind);
        }
        if let Some(name) = &i.sampler {
            let kind = SamplerKind::parse(name).map_err(|e| fail(format!("[integrator] sampler: {e}")))?;
            options.sampler = Some(kind);
        }
    }

    // Materials, by name.
    let mut material_ids = BTreeMap::new();
    for (name, spec) in &file.materials {
        let m = material(spec).map_err(|e| fail(format!("[materials.{name}]: {e}")))?;
        material_ids.insert(name.as_str(), intern_material(&mut scene, m));
    }
    let material_id = |scene: &mut Scene, what: &str, name: &Option<String>, emission: &Option<Emission>| match name {
        Some(n) => material_ids
            .get(n.as_str())
            .copied()
            .ok_or_else(|| fail(format!("{what}: material '{n}' is not defined in [materials]"))),
        None if emission.is_some() => Ok(intern_material(scene, EMITTER_MATERIAL)),
        None => Err(fail(format!("{what}: needs a material (or an emission)"))),
    };

    for (i, spec) in file.lights.iter().enumerate() {
        scene.lights.push(
            light(spec, &mut |w: String| {
                warnings.add(format!("{}: lights[{i}]: {w}", path.display()))
            })
            .map_err(|e| fail(format!("lights[{i}]: {e}")))?,
        );
    }

    for (i, spec) in file.shapes.iter().enumerate() {
        let what = format!("shapes[{i}]");
        let emission = spec.emission().map_err(|e| fail(format!("{what}: emission: {e}")))?;
        match spec {
            ShapeSpec::Sphere {
                center,
                radius,
                material,
                ..
            } => {
                let material = material_id(&mut scene, &what, material, &emission)?;
                scene.spheres.push(Sphere {
                    center: Vec3::from_array(*center),
                    radius: *radius,
                    material,
                    emission,
                });
            }
            ShapeSpec::Quad {
                corner,
                edge_u,
                edge_v,
                material,
                ..
            } => {
                let material = material_id(&mut scene, &what, material, &emission)?;
                let (p, u, v) = (
                    Vec3::from_array(*corner),
                    Vec3::from_array(*edge_u),
                    Vec3::from_array(*edge_v),
                );
                if u.cross(v).length_squared() == 0.0 {
                    return Err(fail(format!("{what}: edge_u and edge_v must span a plane")));
                }
                scene.meshes.push(TriangleMesh {
                    positions: vec![p, p + u, p + u + v, p + v],
                    indices: vec![[0, 1, 2], [0, 2, 3]],
                    material,
                    emission,
                    ..Default::default()
                });
            }
            ShapeSpec::Mesh {
                file: mesh_file,
                material,
                transform,
                ..
            } => {
                let m = matrix(transform).map_err(|e| fail(format!("{what}: {e}")))?;
                let sub = load(mesh_file).map_err(|e| included_error(e, &what, fail))?;
                for (w, n) in sub.warnings.iter() {
                    // The sub-file's own default camera and light are not wanted here.
                    if !w.starts_with("no camera") && !w.starts_with("no lights") {
                        warnings.add_n(format!("{}: {w}", mesh_file.display()), n);
                    }
                }
                let forced = match material {
                    Some(_) => Some(material_id(&mut scene, &what, material, &emission)?),
                    None if emission.is_some() => Some(intern_material(&mut scene, EMITTER_MATERIAL)),
                    None => None,
                };
                let sub_scene = sub.scene;
                for mut mesh in sub_scene.meshes {
                    transform_mesh(&mut mesh, &m);
                    mesh.material = match forced {
                        Some(id) => id,
                        None => intern_material(&mut scene, sub_scene.materials[mesh.material as usize]),
                    };
                    if emission.is_some() {
                        mesh.emission = emission.clone();
                    }
                    scene.meshes.push(mesh);
                }
                let scale = m.transform_vector3(Vec3::X).length();
                for mut s in sub_scene.spheres {
                    s.center = m.transform_point3(s.center);
                    s.radius *= scale;
                    s.material = match forced {
                        Some(id) => id,
                        None => intern_material(&mut scene, sub_scene.materials[s.material as usize]),
                    };
                    scene.spheres.push(s);
                }
            }
        }
    }

    if let Some(cam) = &file.camera {
        cameras += 1;
        let (eye, target, up) = (
            Vec3::from_array(cam.eye),
            Vec3::from_array(cam.look_at),
            Vec3::from_array(cam.up),
        );
        let pose = CameraPose::try_look_at(eye, target, up).map_err(|m| fail(format!("[camera]: {m}")))?;
        let fov_y_deg = cam.fov_y_deg.unwrap_or(super::import::DEFAULT_FOV_Y_DEG);
        crate::camera::check_fov_deg(fov_y_deg).map_err(|m| fail(format!("[camera] fov_y_deg: {m}")))?;
        let focus_distance = match cam.focus_distance {
            Some(d) if d > 0.0 && d.is_finite() => d,
            Some(d) => return Err(fail(format!("[camera]: focus_distance must be positive, got {d}"))),
            None => subject_distance(&pose, &scene_bounds(&scene)),
        };
        scene.view = Some(SceneView {
            pose,
            fov_y_deg,
            focus_distance,
        });
        // A shape's spelling, or else a mask image relative to this file.
        let aperture = match &cam.aperture {
            None => None,
            Some(text) => Some(match ApertureShape::parse(text) {
                Ok(shape) => shape,
                Err(_) if text.contains(['.', '/', '\\']) && !text.contains(':') => {
                    let dir = path.parent().unwrap_or(Path::new(""));
                    crate::io::image::read_aperture_mask(&dir.join(text))?
                }
                Err(e) => return Err(fail(format!("[camera]: {e}"))),
            }),
        };
        let sensor_depth_mm = match cam.sensor_depth_mm {
            Some(_) if cam.focus_distance.is_some() => {
                return Err(fail(
                    "[camera]: give focus_distance or sensor_depth_mm, not both".into(),
                ))
            }
            Some(mm) if !(mm > 0.0 && mm.is_finite()) => {
                return Err(fail(format!("[camera]: sensor_depth_mm must be positive, got {mm}")))
            }
            depth => depth,
        };
        if cam.lens.is_some()
            || cam.f_number.is_some()
            || cam.sensor_mm.is_some()
            || cam.focus_distance.is_some()
            || sensor_depth_mm.is_some()
            || aperture.is_some()
            || cam.dispersion.is_some()
            || cam.diffraction.is_some()
            || cam.desqueeze.is_some()
        {
            options.lens = Some(LensOptions {
                lens: cam.lens.clone(),
                f_number: cam.f_number,
                sensor_mm: cam.sensor_mm.map(|[w, h]| (w, h)),
                focus_distance: cam.focus_distance.map(f64::from),
                sensor_depth_mm,
                aperture,
                dispersion: cam.dispersion,
                diffraction: cam.diffraction,
                desqueeze: cam.desqueeze,
            });
        }
    }
    if let Some(spec) = &file.sensor {
        // Over the base file's sensor, and checked now so the error names this file.
        let described = spec.description().map_err(|e| fail(format!("[sensor]: {e}")))?;
        let described = match &options.sensor {
            Some(base) => described.over(base),
            None => described,
        };
        described.resolve().map_err(|e| fail(format!("[sensor]: {e}")))?;
        options.sensor = Some(described);
    }
    scene.validate().map_err(|e| fail(e.to_string()))?;
    Ok(LoadedScene::completed(
        scene,
        options,
        cameras,
        warnings,
        "lenspath TOML",
    ))
}

/// The scene a [`SceneSettingsFile`] starts from.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneBase {
    /// A built-in scene (`builtin = "..."`, `mesh_triangles = ...`).
    Builtin {
        /// Its name.
        name: String,
        /// Triangles of its procedural mesh (`cornell-mesh`).
        mesh_triangles: usize,
    },
    /// A scene file of any format lenspath reads (`base = "..."`).
    File(PathBuf),
}

/// A scene file that sets only the view, the realistic camera and the render
/// over a base scene: what `lenspath view` saves, so that `lenspath render
/// FILE` gives the image the viewer showed, bit for bit. Every number is
/// written in its shortest exact form, so it reads back to the same bits.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneSettingsFile {
    /// The scene.
    pub base: SceneBase,
    /// Metres per scene unit.
    pub scene_unit_m: f64,
    /// The camera's place, scene units.
    pub eye: Vec3,
    /// The point it looks at.
    pub look_at: Vec3,
    /// Its up direction.
    pub up: Vec3,
    /// Built-in lens name or lens table path.
    pub lens: String,
    /// f-number (`None`: wide open).
    pub f_number: Option<f64>,
    /// Sensor width in mm (its height follows the image aspect).
    pub sensor_width_mm: f64,
    /// The sensor's place, mm behind the aperture stop.
    pub sensor_depth_mm: f64,
    /// The aperture's shape (a mask cannot be written: it is an image).
    pub aperture: ApertureShape,
    /// Whether the lens's glasses disperse (written only when they do not).
    pub dispersion: bool,
    /// Whether the pupil diffracts (written only when it differs from the default).
    pub diffraction: bool,
    /// Image width and height in pixels.
    pub resolution: (u32, u32),
    /// The integrator.
    pub integrator: IntegratorKind,
    /// Samples per pixel.
    pub spp: u32,
    /// Maximum path depth.
    pub max_depth: u32,
    /// Shadow rays per area or environment light per hit.
    pub light_samples: u32,
    /// Seed of the sample sequences.
    pub seed: u32,
    /// The sample sequence.
    pub sampler: SamplerKind,
    /// The image sensor (`None`: none).
    pub sensor: Option<SensorDescription>,
}

impl SceneSettingsFile {
    /// The file's text.
    pub fn to_toml(&self) -> Result<String> {
        let aperture = self
            .aperture
            .spelling()
            .ok_or_else(|| Error::InvalidArgument("a mask aperture cannot be written into a scene file".into()))?;
        let (builtin, mesh_triangles, base) = match &self.base {
            SceneBase::Builtin { name, mesh_triangles } => (
                Some(name.clone()),
                (*mesh_triangles != DEFAULT_MESH_TRIANGLES).then_some(*mesh_triangles),
                None,
            ),
            SceneBase::File(path) => (None, None, Some(path.clone())),
        };
        let file = SceneFile {
            base,
            builtin,
            mesh_triangles,
            scene_unit_m: Some(self.scene_unit_m),
            camera: Some(CameraSpec {
                eye: self.eye.to_array(),
                look_at: self.look_at.to_array(),
                up: self.up.to_array(),
                fov_y_deg: None,
                focus_distance: None,
                sensor_depth_mm: Some(self.sensor_depth_mm),
                lens: Some(self.lens.clone()),
                f_number: self.f_number,
                sensor_mm: Some([
                    self.sensor_width_mm,
                    self.sensor_width_mm * f64::from(self.resolution.1) / f64::from(self.resolution.0),
                ]),
                aperture: Some(aperture),
                dispersion: (!self.dispersion).then_some(false),
                diffraction: (self.diffraction != crate::camera::DEFAULT_DIFFRACTION).then_some(self.diffraction),
                desqueeze: None,
            }),
            film: Some(FilmSpec {
                width: self.resolution.0,
                height: self.resolution.1,
            }),
            integrator: Some(IntegratorSpec {
                kind: Some(self.integrator.name().into()),
                spp: Some(self.spp),
                max_depth: Some(self.max_depth),
                light_samples: Some(self.light_samples),
                seed: Some(self.seed),
                sampler: Some(self.sampler.name().into()),
            }),
            sensor: self.sensor.as_ref().map(SensorTable::of),
            materials: BTreeMap::new(),
            lights: Vec::new(),
            shapes: Vec::new(),
        };
        toml::to_string(&file).map_err(|e| Error::InvalidArgument(format!("cannot write the scene file: {e}")))
    }
}

/// The TOML parser's message on one line ("line L, column C: what").
fn one_line(e: &toml::de::Error, text: &str) -> String {
    let message = e.message().trim().replace('\n', " ");
    match e.span() {
        Some(span) => {
            let before = &text.as_bytes()[..span.start.min(text.len())];
            let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
            let column = before.iter().rev().take_while(|&&b| b != b'\n').count() + 1;
            format!("line {line}, column {column}: {message}")
        }
        None => message,
    }
}

fn material(spec: &MaterialSpec) -> std::result::Result<Material, String> {
    Ok(match spec {
        MaterialSpec::Diffuse { reflectance } => Material::Diffuse {
            reflectance: reflectance.rgb(),
        },
        MaterialSpec::Mirror { reflectance } => Material::Mirror {
            reflectance: reflectance.rgb(),
        },
        MaterialSpec::Dielectric {
            eta,
            glass,
            n_d,
            v_d,
            reflectance,
            transmittance,
        } => Material::Dielectric {
            eta: Dispersion::described(eta.map(f64::from), glass.as_deref(), *n_d, *v_d).map_err(|e| e.to_string())?,
            reflectance: reflectance.map_or(Rgb::ONE, Color::rgb),
            transmittance: transmittance.map_or(Rgb::ONE, Color::rgb),
        },
        MaterialSpec::Conductor { eta, k, metal, alpha } => {
            Material::conductor(eta.map(Color::rgb), k.map(Color::rgb), metal.as_deref(), *alpha)
                .map_err(|e| e.to_string())?
        }
    })
}

impl ShapeSpec {
    /// What the shape's `emission` describes (`None`: it does not emit).
    fn emission(&self) -> std::result::Result<Option<Emission>, String> {
        let (ShapeSpec::Sphere { emission, .. } | ShapeSpec::Quad { emission, .. } | ShapeSpec::Mesh { emission, .. }) =
            self;
        emission.as_ref().map(EmissionSpec::emission).transpose()
    }
}

/// The light `spec` describes; `deprecated` is told of old spellings.
fn light(spec: &LightSpec, deprecated: &mut dyn FnMut(String)) -> std::result::Result<Light, String> {
    Ok(match *spec {
        LightSpec::Point {
            position,
            ref intensity,
        } => Light::Point {
            position: Vec3::from_array(position),
            intensity: intensity.emission()?,
        },
        LightSpec::Spot {
            position,
            look_at,
            ref intensity,
            cutoff_angle_deg,
            cone_angle_deg,
            exponent,
        } => {
            let direction = Vec3::from_array(look_at) - Vec3::from_array(position);
            if direction.length_squared() == 0.0 {
                return Err("look_at must differ from position".into());
            }
            let cutoff_angle_deg = match (cutoff_angle_deg, cone_angle_deg) {
                (Some(half), None) => half,
                (None, Some(full)) => {
                    deprecated(format!(
                        "cone_angle_deg (the full angle) is deprecated; use cutoff_angle_deg = {}, the half angle",
                        0.5 * full
                    ));
                    0.5 * full
                }
                (Some(_), Some(_)) => {
                    return Err("give cutoff_angle_deg, not also cone_angle_deg (its old name)".into())
                }
                (None, None) => return Err("a spot light needs cutoff_angle_deg (the cone's half angle)".into()),
            };
            Light::spot(
                Vec3::from_array(position),
                direction,
                intensity.emission()?,
                cutoff_angle_deg,
                exponent,
            )
            .map_err(|e| e.to_string())?
        }
        LightSpec::Directional {
            direction,
            ref irradiance,
        } => Light::Directional {
            direction: Vec3::from_array(direction)
                .try_normalize()
                .ok_or("direction must be non-zero")?,
            irradiance: irradiance.emission()?,
        },
        LightSpec::Environment { ref radiance } => Light::Environment {
            radiance: radiance.emission()?,
        },
    })
}

/// Scale, then the rotations in order, then the translation.
fn matrix(t: &TransformSpec) -> std::result::Result<Mat4, String> {
    let scale = t.scale.map_or(Vec3::ONE, Color::rgb);
    if !(scale.is_finite() && scale.min_element().abs() > 0.0) {
        return Err(format!("transform scale must be finite and non-zero, got {scale}"));
    }
    let mut m = Mat4::from_scale(scale);
    for r in &t.rotate {
        let axis = Vec3::from_array(r.axis)
            .try_normalize()
            .ok_or("rotation axis is zero")?;
        m = Mat4::from_axis_angle(axis, r.degrees.to_radians()) * m;
    }
    m = Mat4::from_translation(Vec3::from_array(t.translate.unwrap_or_default())) * m;
    if !m.is_finite() {
        return Err("transform is not finite".into());
    }
    Ok(m)
}
