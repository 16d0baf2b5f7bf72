//! Scene files: the CS184 course scenes in ../shared (skipped, saying so, when
//! ../shared is absent), the shipped scenes/ examples, glTF and TOML files made
//! here, and the corpus of broken files under tests/data/broken with the message
//! each must give.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use glam::Vec3;
use lenspath::accel::BvhSettings;
use lenspath::builtin::DEFAULT_MESH_TRIANGLES;
use lenspath::camera::{ApertureShape, PerspectiveCamera};
use lenspath::film::Image;
use lenspath::io::{load_scene, LoadedScene};
use lenspath::lights::Light;
use lenspath::materials::Material;
use lenspath::math::Rgb;
use lenspath::render::{render, RenderSettings};
use lenspath::sampling::SamplerKind;
use lenspath::setup::{realistic_settings, RealisticDescription};

use crate::shared_folder::{repo, shared};

/// A small pinhole render of a loaded scene through its own view.
fn quick_render(loaded: LoadedScene, width: u32, height: u32, spp: u32) -> Image {
    let view = loaded.scene.view.expect("loaders always set a view");
    let camera = PerspectiveCamera::pinhole(view.pose, view.fov_y_deg, width, height);
    let settings = RenderSettings {
        width,
        height,
        spp,
        ..Default::default()
    };
    let compiled = loaded.scene.compile(&BvhSettings::default()).unwrap();
    render(&compiled, &camera, &settings, &|_, _| {}, &AtomicBool::new(false))
        .unwrap()
        .image
}

/// Mean RGB over a block of pixels given in fractions of the image.
fn block(image: &Image, x: (f32, f32), y: (f32, f32)) -> [f64; 3] {
    let (w, h) = (image.width as f32, image.height as f32);
    let mut sum = [0.0f64; 3];
    let mut n = 0.0;
    for py in (y.0 * h) as u32..(y.1 * h) as u32 {
        for px in (x.0 * w) as u32..(x.1 * w) as u32 {
            let p = image.pixel(px, py);
            for c in 0..3 {
                sum[c] += f64::from(p[c]);
            }
            n += 1.0;
        }
    }
    sum.map(|s| s / n)
}

/// Every CS184 scene loads with the triangle and sphere counts of ASSETS.md
/// (the p3-2 versions, whose lamp quad is commented out, get their area light
/// as a 2-triangle emitter), and renders as the course shows it: the camera
/// in front of the box, red wall on the left, blue on the right, the lamp the
/// brightest thing at the top, the meshedit models in the middle of a black frame.
#[test]
fn cs184_scenes_load_and_render_as_the_course_shows_them() {
    let table: [(&str, usize, usize); 22] = [
        ("sky/CBempty.dae", 12, 0),
        ("sky/CBspheres_lambertian.dae", 12, 2),
        ("sky/CBspheres.dae", 12, 2),
        ("sky/CBspheres_microfacet_al_ag.dae", 12, 2),
        ("sky/CBspheres_refract.dae", 10 + 2, 2),
        ("sky/CBgems.dae", 252, 0),
        ("sky/CBcoil.dae", 7_884, 0),
        ("sky/CBbunny.dae", 28_588, 0),
        ("sky/CBbunny_microfacet_cu.dae", 28_588, 0),
        ("sky/bunny.dae", 33_696, 0),
        ("meshedit/teapot.dae", 2_464, 0),
        ("meshedit/cow.dae", 5_856, 0),
        ("meshedit/beetle.dae", 7_558, 0),
        ("meshedit/maxplanck.dae", 50_801, 0),
        ("sky_p3-2_sp23/CBempty.dae", 10, 0),
        ("sky_p3-2_sp23/CBspheres_lambertian.dae", 10 + 2, 2),
        ("sky_p3-2_sp23/CBspheres.dae", 10 + 2, 2),
        ("sky_p3-2_sp23/CBspheres_microfacet_al_ag.dae", 10 + 2, 2),
        ("sky_p3-2_sp23/CBgems.dae", 250 + 2, 0),
        ("sky_p3-2_sp23/CBcoil.dae", 7_882 + 2, 0),
        ("sky_p3-2_sp23/CBbunny.dae", 28_586 + 2, 0),
        ("sky_p3-2_sp23/CBbunny_microfacet_cu.dae", 28_586 + 2, 0),
    ];
    for (path, triangles, spheres) in table {
        let Some(file) = shared(&format!("scenes/cs184/{path}")) else {
            return;
        };
        let loaded = load_scene(&file).unwrap_or_else(|e| panic!("{e}"));
        let s = &loaded.scene;
        assert_eq!((s.triangle_count(), s.spheres.len()), (triangles, spheres), "{path}");
        assert_eq!(loaded.cameras, 1, "{path}");
        let boxed = path.contains("/CB") && !path.ends_with("CBempty.dae");
        let image = quick_render(loaded, 64, 48, 8);
        if boxed {
            let left = block(&image, (0.22, 0.28), (0.4, 0.6));
            let right = block(&image, (0.72, 0.78), (0.4, 0.6));
            assert!(left[0] > 1.3 * left[2], "{path}: left wall is not red: {left:?}");
            assert!(right[2] > 1.3 * right[0], "{path}: right wall is not blue: {right:?}");
            // The lamp (radiance 10) is the brightest pixel, in the top middle of the image.
            let (mut best, mut at) = (0.0f32, (0, 0));
            for y in 0..image.height {
                for x in 0..image.width {
                    let g = image.pixel(x, y)[1];
                    if g > best {
                        (best, at) = (g, (x, y));
                    }
                }
            }
            assert!(best >= 5.0, "{path}: no lamp pixel (radiance 10), brightest {best}");
            let (fx, fy) = (at.0 as f32 / 64.0, at.1 as f32 / 48.0);
            assert!(
                (0.3..0.7).contains(&fx) && fy < 0.4,
                "{path}: brightest pixel at {at:?}"
            );
        }
        if path.starts_with("meshedit/") {
            let centre = block(&image, (0.4, 0.6), (0.4, 0.6));
            let corner = block(&image, (0.0, 0.1), (0.0, 0.1));
            assert!(
                centre.iter().sum::<f64>() > 0.05,
                "{path}: model not in view {centre:?}"
            );
            assert_eq!(corner, [0.0; 3], "{path}: background is not black");
        }
    }
}

/// The materials of the CS184 BSDFs arrive with their parameters.
#[test]
fn cs184_bsdfs_map_to_lenspath_materials() {
    let Some(file) = shared("scenes/cs184/sky/CBspheres_microfacet_al_ag.dae") else {
        return;
    };
    let s = load_scene(&file).unwrap().scene;
    let alphas: Vec<f32> = s
        .materials
        .iter()
        .filter_map(|m| match m {
            Material::Conductor { alpha, .. } => Some(*alpha),
            _ => None,
        })
        .collect();
    assert_eq!(alphas.len(), 2);
    assert!(alphas.contains(&0.25) && alphas.contains(&0.025), "{alphas:?}");
    let Some(file) = shared("scenes/cs184/sky/CBgems.dae") else {
        return;
    };
    let s = load_scene(&file).unwrap().scene;
    assert!(s.materials.iter().any(|m| matches!(m,
        Material::Dielectric { eta, transmittance, .. } if (eta.n_d() - 1.45).abs() < 1e-6 && transmittance.to_array() == [1.0, 0.75, 0.75])));
    let Some(file) = shared("scenes/cs184/meshedit/teapot.dae") else {
        return;
    };
    let s = load_scene(&file).unwrap().scene;
    assert!(matches!(s.lights[..], [Light::Directional { .. }]));
}

/// The scenes/ examples load; those that need ../shared say so in a comment and skip here without it.
#[test]
fn shipped_example_scenes_load() {
    let dir = repo("scenes");
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        if text.contains("../shared") && shared("ASSETS.md").is_none() {
            continue;
        }
        // Those naming ../shared read from it when allowed to (`--allow-read ../shared`).
        let allowed: Vec<PathBuf> = shared("ASSETS.md")
            .map(|f| f.parent().unwrap().to_path_buf())
            .into_iter()
            .collect();
        let scope = lenspath::io::ReadScope::of_scene(&path, &allowed).unwrap();
        let loaded = lenspath::io::load_scene_in(&path, &scope).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            loaded.scene.triangle_count() + loaded.scene.spheres.len() > 0,
            "{}",
            path.display()
        );
        assert!(loaded.cameras >= 1, "{}: examples set their camera", path.display());
        seen += 1;
    }
    assert!(seen >= 1, "no example scenes in {}", dir.display());
}

/// A glTF file with a camera, a punctual light, an emissive and a metallic
/// material, its buffer embedded as a data URI, beside it as a .bin with a
/// percent-encoded name, and in a .glb.
#[test]
fn gltf_nodes_cameras_lights_and_materials() {
    use base64::Engine;
    // One triangle in the z = -2 plane, facing +z (toward the camera at the origin).
    let mut bin = Vec::new();
    for v in [-1.0f32, -1.0, 0.0, 1.0, -1.0, 0.0, 0.0, 1.0, 0.0] {
        bin.extend(v.to_le_bytes());
    }
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bin)
    );
    let json = |uri: &str| {
        format!(
            r#"{{
  "asset": {{"version": "2.0"}},
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {{"KHR_lights_punctual": {{"lights": [{{"type": "point", "color": [1, 0.5, 0.25], "intensity": 4}}]}}}},
  "scene": 0,
  "scenes": [{{"nodes": [0, 1, 2, 3]}}],
  "nodes": [
    {{"mesh": 0, "translation": [0, 0, -2]}},
    {{"mesh": 1, "translation": [0, 0, -3], "scale": [2, 2, 2]}},
    {{"camera": 0}},
    {{"extensions": {{"KHR_lights_punctual": {{"light": 0}}}}, "translation": [0, 3, 0]}}
  ],
  "cameras": [{{"type": "perspective", "perspective": {{"yfov": 0.7, "znear": 0.1}}}}],
  "meshes": [
    {{"primitives": [{{"attributes": {{"POSITION": 0}}, "material": 0}}]}},
    {{"primitives": [{{"attributes": {{"POSITION": 0}}, "material": 1}}]}}
  ],
  "materials": [
    {{"pbrMetallicRoughness": {{"baseColorFactor": [0.9, 0.6, 0.2, 1], "metallicFactor": 1, "roughnessFactor": 0.5}}}},
    {{"pbrMetallicRoughness": {{"baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0}}, "emissiveFactor": [1, 1, 1]}}
  ],
  "buffers": [{{"byteLength": 36{uri}}}],
  "bufferViews": [{{"buffer": 0, "byteLength": 36}}],
  "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                  "min": [-1, -1, 0], "max": [1, 1, 0]}}]
}}"#
        )
    };
    let dir = tempfile::tempdir().unwrap();
    let gltf_path = dir.path().join("scene.gltf");
    std::fs::write(&gltf_path, json(&format!(r#", "uri": "{uri}""#))).unwrap();
    // The same scene with its buffer in a .bin beside it.
    let bin_path = dir.path().join("scene with spaces.gltf");
    std::fs::write(dir.path().join("tri angle.bin"), &bin).unwrap();
    std::fs::write(&bin_path, json(r#", "uri": "tri%20angle.bin""#)).unwrap();
    // And as binary glTF: a JSON chunk and a BIN chunk, each padded to 4 bytes.
    let mut chunk = json("").into_bytes();
    chunk.resize(chunk.len().div_ceil(4) * 4, b' ');
    let mut glb = Vec::new();
    glb.extend(0x4654_6C67u32.to_le_bytes()); // "glTF"
    glb.extend(2u32.to_le_bytes());
    glb.extend(((12 + 8 + chunk.len() + 8 + bin.len()) as u32).to_le_bytes());
    glb.extend((chunk.len() as u32).to_le_bytes());
    glb.extend(0x4E4F_534Au32.to_le_bytes()); // "JSON"
    glb.extend(&chunk);
    glb.extend((bin.len() as u32).to_le_bytes());
    glb.extend(0x004E_4942u32.to_le_bytes()); // "BIN\0"
    glb.extend(&bin);
    let glb_path = dir.path().join("scene.glb");
    std::fs::write(&glb_path, glb).unwrap();
    for path in [&gltf_path, &bin_path, &glb_path] {
        let loaded = load_scene(path).unwrap_or_else(|e| panic!("{e}"));
        let s = &loaded.scene;
        assert_eq!(loaded.cameras, 1);
        assert_eq!(s.meshes.len(), 2);
        assert_eq!(s.meshes[0].positions[2].to_array(), [0.0, 1.0, -2.0]);
        assert_eq!(s.meshes[1].positions[1].to_array(), [2.0, -2.0, -3.0]);
        let Material::Conductor { alpha, .. } = s.materials[s.meshes[0].material as usize] else {
            panic!("metallic base colour should give a conductor");
        };
        assert_eq!(alpha, 0.25);
        assert_eq!(s.meshes[1].emission, Some(Rgb::ONE.into()));
        assert!(matches!(&s.lights[..], [Light::Point { intensity, position }]
            if *intensity == Rgb::new(4.0, 2.0, 1.0).into() && position.to_array() == [0.0, 3.0, 0.0]));
        let view = s.view.unwrap();
        assert!((view.fov_y_deg - 0.7f32.to_degrees()).abs() < 1e-4);
    }
}

/// A TOML scene that extends the CS184 empty box with a mesh gets the box,
/// its camera placement and lamp, and the mesh where the transform puts it.
#[test]
fn toml_scene_extends_a_base_and_places_a_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let ply = dir.path().join("tri.ply");
    std::fs::write(
        &ply,
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
    )
    .unwrap();
    let toml = r#"
scene_unit_m = 0.5
[film]
width = 32
height = 24
[integrator]
spp = 2
sampler = "independent"
[materials.gold]
type = "conductor"
eta = [0.143, 0.374, 1.442]
k = [3.983, 2.385, 1.603]
alpha = 0.1
[[lights]]
type = "spot"
position = [0, 0, 5]
look_at = [0, 0, 0]
intensity = 3
cutoff_angle_deg = 30
[[shapes]]
type = "mesh"
file = "tri.ply"
material = "gold"
transform = { scale = 2, rotate = [{ axis = [0, 0, 1], degrees = 90 }], translate = [1, 0, 0] }
[[shapes]]
type = "sphere"
center = [0, 0, -1]
radius = 0.5
emission = [2, 2, 2]
[camera]
eye = [0, 0, 10]
look_at = [0, 0, 0]
lens = "wide22"
f_number = 4
aperture = "star:5:0.4"
"#;
    let path = dir.path().join("scene.toml");
    std::fs::write(&path, toml).unwrap();
    let loaded = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    let s = &loaded.scene;
    let p = &s.meshes[0].positions;
    // (1,0,0) scaled by 2 → (2,0,0), turned 90° about z → (0,2,0), moved → (1,2,0).
    assert!((p[1] - glam::Vec3::new(1.0, 2.0, 0.0)).length() < 1e-5, "{p:?}");
    assert!(matches!(s.materials[s.meshes[0].material as usize], Material::Conductor { alpha, .. } if alpha == 0.1));
    assert_eq!(s.spheres[0].emission.as_ref().map(|e| e.to_rgb().x), Some(2.0));
    let spot = Light::spot(Vec3::new(0.0, 0.0, 5.0), Vec3::NEG_Z, Rgb::splat(3.0).into(), 30.0, 0.0).unwrap();
    assert_eq!(s.lights, std::slice::from_ref(&spot));
    assert!(loaded.warnings.is_empty(), "{}", loaded.warnings);
    // The old key, the full angle, still means the same light, and says what replaces it.
    let old = toml.replace("cutoff_angle_deg = 30", "cone_angle_deg = 60");
    std::fs::write(&path, old).unwrap();
    let loaded_old = load_scene(&path).unwrap();
    assert_eq!(loaded_old.scene.lights, [spot]);
    let text = loaded_old.warnings.to_string();
    assert!(text.contains("use cutoff_angle_deg = 30, the half angle"), "{text}");
    assert_eq!(loaded.options.resolution, Some((32, 24)));
    assert_eq!(loaded.options.spp, Some(2));
    assert_eq!(loaded.options.sampler, Some(SamplerKind::Independent));
    assert_eq!(loaded.options.scene_unit_m, Some(0.5));
    let lens = loaded.options.lens.unwrap();
    assert_eq!((lens.lens.as_deref(), lens.f_number), (Some("wide22"), Some(4.0)));
    assert_eq!(lens.aperture, Some(ApertureShape::parse("star:5:0.4").unwrap()));
    // A mask image, relative to the scene file; a misspelt shape is an error naming it.
    let mask = dir.path().join("mask.png");
    image::GrayImage::from_fn(8, 8, |x, _| image::Luma([if x < 4 { 255 } else { 0 }]))
        .save(&mask)
        .unwrap();
    std::fs::write(&path, toml.replace("star:5:0.4", "mask.png")).unwrap();
    let loaded = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    assert!(matches!(loaded.options.lens.unwrap().aperture, Some(ApertureShape::Mask(m)) if m.width == 8));
    std::fs::write(&path, toml.replace("star:5:0.4", "hexagon")).unwrap();
    let e = load_scene(&path).unwrap_err().to_string();
    assert!(
        e.contains("scene.toml") && e.contains("aperture shape 'hexagon'"),
        "{e}"
    );
}

/// What `lenspath view` saves reads back to the same bits: the pose from the
/// same eye, target and up, the sensor's place, the f-number, the aperture and
/// the render settings, over a built-in scene or a scene file.
#[test]
fn settings_file_reads_back_exactly() {
    use glam::Vec3;
    use lenspath::camera::{CameraPose, LensFocus};
    use lenspath::io::scene_file::{SceneBase, SceneSettingsFile};
    use lenspath::sensor::{Cfa, Demosaic, SensorDescription, ToneCurve, WhiteBalance};
    let dir = tempfile::tempdir().unwrap();
    let mut written = SceneSettingsFile {
        base: SceneBase::Builtin {
            name: "cornell-spheres".into(),
            mesh_triangles: DEFAULT_MESH_TRIANGLES,
        },
        scene_unit_m: 0.1 + 0.2,
        eye: Vec3::new(0.1, 1.0 / 3.0, 3.7e-7),
        look_at: Vec3::new(-0.25, 0.7, 1e6 / 7.0),
        up: Vec3::new(0.01, 1.0, 0.0),
        lens: "wide22".into(),
        f_number: Some(2.0_f64.sqrt() * 4.0),
        sensor_width_mm: 36.0 / 7.0,
        sensor_depth_mm: 51.234_567_890_123_45,
        aperture: ApertureShape::parse("blades:7:12.345678901:0.3").unwrap(),
        dispersion: false,
        diffraction: true,
        resolution: (123, 45),
        spp: 37,
        max_depth: 9,
        light_samples: 3,
        seed: 4_000_000_000,
        sampler: SamplerKind::Independent,
        integrator: lenspath::integrator::IntegratorKind::Guided,
        sensor: Some(SensorDescription {
            model: Some("nikon_d850".into()),
            cfa: Some(Cfa::Gbrg),
            exposure_time_s: Some(1.0 / 3.0),
            iso: Some(400.0),
            prnu: Some(0.1 + 0.2),
            bit_depth: Some(14),
            frame_seed: Some(1 << 62),
            white_balance: Some(WhiteBalance::Kelvin(3200.5)),
            demosaic: Some(Demosaic::Bilinear),
            tone_curve: Some(ToneCurve::Filmic),
            ..SensorDescription::default()
        }),
    };
    let base_file = dir.path().join("base.toml");
    std::fs::write(
        &base_file,
        "[[shapes]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nemission = 1\n",
    )
    .unwrap();
    let builtin = SceneBase::Builtin {
        name: "cornell-spheres".into(),
        mesh_triangles: DEFAULT_MESH_TRIANGLES,
    };
    for base in [builtin, SceneBase::File(base_file)] {
        written.base = base;
        let path = dir.path().join("saved.toml");
        std::fs::write(&path, written.to_toml().unwrap()).unwrap();
        let loaded = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
        let view = loaded.scene.view.unwrap();
        assert_eq!(view.pose, CameraPose::look_at(written.eye, written.look_at, written.up));
        let o = &loaded.options;
        assert_eq!(o.resolution, Some(written.resolution));
        assert_eq!((o.spp, o.max_depth, o.light_samples), (Some(37), Some(9), Some(3)));
        assert_eq!(
            (o.seed, o.sampler, o.integrator),
            (
                Some(4_000_000_000),
                Some(SamplerKind::Independent),
                Some(lenspath::integrator::IntegratorKind::Guided)
            )
        );
        assert_eq!(o.scene_unit_m, Some(written.scene_unit_m));
        let camera = realistic_settings(o, &view, &RealisticDescription::default(), 123, 45).unwrap();
        assert_eq!(camera.focus, LensFocus::SensorDepthMm(written.sensor_depth_mm));
        assert_eq!(camera.f_number, written.f_number);
        assert_eq!(camera.sensor_mm.0, written.sensor_width_mm);
        assert_eq!(camera.aperture, written.aperture);
        assert_eq!(camera.lens.name(), "wide22");
        assert!(!camera.dispersion);
        assert!(camera.diffraction);
        assert_eq!(o.sensor, written.sensor);
    }
    // A mask cannot be spelt; a file with both bases, or both focus keys, is an error.
    written.aperture = ApertureShape::mask(2, 2, vec![1.0; 4]).unwrap();
    assert!(written.to_toml().unwrap_err().to_string().contains("mask"));
    let path = dir.path().join("both.toml");
    for (text, message) in [
        ("builtin = \"cornell-spheres\"\nbase = \"x.dae\"\n", "base or builtin"),
        ("builtin = \"cornell-nothing\"\n", "builtin: unknown"),
        (
            "builtin = \"cornell-spheres\"\n[camera]\neye = [0, 1, 4]\nlook_at = [0, 1, 0]\nfocus_distance = 2\nsensor_depth_mm = 50\n",
            "not both",
        ),
        (
            "builtin = \"cornell-spheres\"\n[camera]\neye = [0, 1, 4]\nlook_at = [0, 1, 0]\nsensor_depth_mm = -1\n",
            "sensor_depth_mm must be positive",
        ),
    ] {
        std::fs::write(&path, text).unwrap();
        let e = load_scene(&path).unwrap_err().to_string();
        assert!(e.contains("both.toml") && e.contains(message), "{e}");
    }
}

/// Lights and emitters may be given as spectra: a black body or a table,
/// scaled to a luminance (default 1), beside plain RGB.
#[test]
fn toml_lights_take_black_bodies_and_spectrum_tables() {
    use lenspath::spectrum::Emission;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("lamps.toml");
    std::fs::write(
        &path,
        r#"
[[lights]]
type = "point"
position = [0, 2, 0]
intensity = { blackbody_k = 2700, luminance = 5 }

[[lights]]
type = "environment"
radiance = 0.1

[[shapes]]
type = "sphere"
center = [0, 0, 0]
radius = 0.5
emission = { spectrum = [[585, 0], [589, 1], [593, 0]] }
"#,
    )
    .unwrap();
    let s = load_scene(&path).unwrap_or_else(|e| panic!("{e}")).scene;
    let Light::Point { intensity, .. } = &s.lights[0] else {
        panic!("{:?}", s.lights[0]);
    };
    assert_eq!(*intensity, Emission::blackbody(2700.0, 5.0).unwrap());
    assert_eq!(
        s.lights[1],
        Light::Environment {
            radiance: Rgb::splat(0.1).into()
        }
    );
    let sodium = Emission::tabulated(&[(585.0, 0.0), (589.0, 1.0), (593.0, 0.0)], 1.0).unwrap();
    assert_eq!(s.spheres[0].emission, Some(sodium));
}

/// Hand-made broken files under tests/data/broken, each with the message it must give:
/// the file name, the line or element, and what is wrong; never a panic.
#[test]
fn broken_files_give_clear_errors() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/broken");
    let expected = std::fs::read_to_string(dir.join("EXPECTED.txt")).unwrap();
    let mut checked = 0;
    for line in expected.lines().filter(|l| !l.trim().is_empty() && !l.starts_with('#')) {
        let (file, message) = line.split_once(" => ").expect("lines are 'file => message'");
        let path = dir.join(file.trim());
        assert!(path.exists(), "{} is listed but missing", path.display());
        let err = match load_scene(&path) {
            Ok(_) => panic!("{file}: loaded, but should fail with '{message}'"),
            Err(e) => e.to_string(),
        };
        assert!(
            err.contains(file.trim()),
            "{file}: the message does not name the file: {err}"
        );
        assert!(err.contains(message.trim()), "{file}: expected '{message}', got: {err}");
        checked += 1;
    }
    let on_disk = std::fs::read_dir(&dir).unwrap().count() - 1;
    assert_eq!(checked, on_disk, "every broken file needs a line in EXPECTED.txt");
}

/// Recoverable oddities load, each counted in a warning.
#[test]
fn oddities_are_skipped_with_counted_warnings() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/odd");
    let loaded = load_scene(&dir.join("degenerate.obj")).unwrap();
    let text = loaded.warnings.to_string();
    assert!(text.contains("skipped degenerate triangles (×2)"), "{text}");
    let loaded = load_scene(&dir.join("unknown_elements.dae")).unwrap();
    let text = loaded.warnings.to_string();
    assert!(text.contains("<lines> primitives are not supported; skipped"), "{text}");
    assert!(loaded.scene.triangle_count() == 1, "{text}");
}

#[test]
fn unknown_extension_is_a_clear_error() {
    let err = load_scene(Path::new("scene.blend")).unwrap_err().to_string();
    assert!(err.contains("scene.blend: unknown scene format"), "{err}");
}

/// A chain of scene files each naming the next as its base (2 000 of them,
/// which overflowed the stack) is refused at the library's depth limit,
/// with one readable message naming where the chain starts.
#[test]
fn a_deep_chain_of_base_files_is_refused_not_a_stack_overflow() {
    let dir = tempfile::tempdir().unwrap();
    let name = |i: usize| format!("chain{i:04}.toml");
    for i in 0..2000 {
        std::fs::write(dir.path().join(name(i)), format!("base = \"{}\"\n", name(i + 1))).unwrap();
    }
    std::fs::write(dir.path().join(name(2000)), "builtin = \"cornell-spheres\"\n").unwrap();
    let err = load_scene(&dir.path().join(name(0))).unwrap_err().to_string();
    let limit = lenspath::io::scene_file::MAX_INCLUDE_DEPTH;
    assert!(err.contains(&format!("more than {limit} scene files deep")), "{err}");
    assert!(err.contains(&name(0)) && err.lines().count() == 1, "{err}");
    // Just within the limit loads.
    let err_at = |start: usize| load_scene(&dir.path().join(name(start))).map(|_| ());
    assert!(err_at(2000 - limit + 1).is_ok());
    assert!(err_at(2000 - limit).is_err());
}

/// A scene reads the files it names only from its own folder (`..` and
/// symbolic links resolved), unless a folder is allowed explicitly: a glTF
/// buffer, a TOML base or mesh file, an OBJ material library outside it is
/// refused (the library skipped with a warning), never read.
#[test]
fn a_scene_reads_only_from_its_folder_unless_another_is_allowed() {
    use lenspath::io::{load_scene_in, ReadScope};
    let dir = tempfile::tempdir().unwrap();
    let (inside, outside) = (dir.path().join("scene"), dir.path().join("elsewhere"));
    std::fs::create_dir_all(inside.join("sub")).unwrap();
    std::fs::create_dir_all(&outside).unwrap();
    let triangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    std::fs::write(outside.join("mesh.obj"), triangle).unwrap();
    std::fs::write(inside.join("sub/mesh.obj"), triangle).unwrap();
    std::fs::write(outside.join("red.mtl"), "newmtl red\nKd 1 0 0\n").unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink(outside.join("mesh.obj"), inside.join("link.obj")).unwrap();
    let mesh_scene =
        |file: &str| format!("builtin = \"cornell-empty\"\n[[shapes]]\ntype = \"mesh\"\nfile = \"{file}\"\n");
    let cases = [
        ("up.toml", mesh_scene("../elsewhere/mesh.obj")),
        (
            "absolute.toml",
            mesh_scene(&outside.join("mesh.obj").display().to_string()),
        ),
        ("base.toml", "base = \"../elsewhere/mesh.obj\"\n".to_string()),
        #[cfg(unix)]
        ("link.toml", mesh_scene("link.obj")),
    ];
    for (name, text) in &cases {
        let path = inside.join(name);
        std::fs::write(&path, text).unwrap();
        let err = load_scene(&path).unwrap_err().to_string();
        assert!(
            err.contains(name) && err.contains("is outside the folders this scene may read"),
            "{name}: {err}"
        );
        // Allowed explicitly, it loads.
        let scope = ReadScope::of_scene(&path, std::slice::from_ref(&outside)).unwrap();
        load_scene_in(&path, &scope).unwrap_or_else(|e| panic!("{name} with the folder allowed: {e}"));
    }
    std::fs::write(inside.join("fine.toml"), mesh_scene("sub/mesh.obj")).unwrap();
    load_scene(&inside.join("fine.toml")).unwrap();

    let gltf = |uri: &str| {
        format!(
            r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"uri":"{uri}","byteLength":4}}],"scenes":[{{"nodes":[]}}],"scene":0}}"#
        )
    };
    for uri in ["/etc/passwd", "../elsewhere/mesh.obj"] {
        std::fs::write(inside.join("b.gltf"), gltf(uri)).unwrap();
        let err = load_scene(&inside.join("b.gltf")).unwrap_err().to_string();
        assert!(
            err.contains("is outside the folders this scene may read"),
            "{uri}: {err}"
        );
    }

    std::fs::write(
        inside.join("m.obj"),
        format!("mtllib ../elsewhere/red.mtl\nusemtl red\n{triangle}"),
    )
    .unwrap();
    let loaded = load_scene(&inside.join("m.obj")).unwrap();
    let warnings = loaded.warnings.to_string();
    assert!(warnings.contains("material library not read"), "{warnings}");
    assert!(loaded
        .scene
        .materials
        .iter()
        .all(|m| !matches!(m, Material::Diffuse { reflectance } if reflectance.x == 1.0 && reflectance.y == 0.0)));
}
