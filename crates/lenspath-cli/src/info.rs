//! `lenspath info`: what a scene file holds, as lenspath loaded it.

use std::path::PathBuf;

use clap::Args;
use lenspath::builtin::DEFAULT_MESH_TRIANGLES;
use lenspath::io::import::scene_bounds;
use lenspath::io::LoadedScene;
use lenspath::lights::Light;
use lenspath::materials::Material;
use lenspath::Result;
use serde_json::json;

use crate::Outcome;

/// Options of `lenspath info`.
#[derive(Args, Debug)]
pub struct InfoArgs {
    /// Scene file (.dae, .obj, .ply, .gltf, .glb, .toml) or a built-in scene's name.
    file: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    allow_read: crate::flags::AllowRead,
}

/// Runs `lenspath info`.
pub fn run(args: InfoArgs) -> Result<Outcome> {
    let loaded = args.allow_read.load_scene(&args.file, DEFAULT_MESH_TRIANGLES)?;
    let summary = summarize(&loaded);
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&summary).expect("a JSON value serializes")
        );
        return Ok(Outcome::Done);
    }
    let s = &loaded.scene;
    println!("{} ({})", args.file.display(), loaded.format);
    println!("  meshes      {}", s.meshes.len());
    println!("  triangles   {}", s.triangle_count());
    println!("  spheres     {}", s.spheres.len());
    // " (2 diffuse, 1 mirror)", or nothing when there are none.
    let by_kind = |v: &serde_json::Value| {
        let kinds: Vec<String> = v
            .as_object()
            .into_iter()
            .flatten()
            .filter(|(_, n)| n.as_u64() != Some(0))
            .map(|(k, n)| format!("{n} {k}"))
            .collect();
        if kinds.is_empty() {
            String::new()
        } else {
            format!(" ({})", kinds.join(", "))
        }
    };
    println!("  materials   {}{}", s.materials.len(), by_kind(&summary["materials"]));
    println!("  emitters    {} (area lights)", summary["emitters"]);
    println!("  lights      {}{}", s.lights.len(), by_kind(&summary["lights"]));
    println!("  cameras     {}", loaded.cameras);
    let b = &summary["bounds"];
    println!("  bounds      min {} max {}", b["min"], b["max"]);
    if let Some(unit) = loaded.options.scene_unit_m {
        println!("  scene unit  {unit} m");
    }
    if let Some(v) = &s.view {
        let eye = v.pose.render_from_camera.translation;
        println!(
            "  view        eye ({:.3}, {:.3}, {:.3}), vertical fov {:.2}°, subject at {:.3}",
            eye.x, eye.y, eye.z, v.fov_y_deg, v.focus_distance
        );
    }
    if loaded.warnings.is_empty() {
        println!("  warnings    none");
    } else {
        println!("  warnings");
        for (what, n) in loaded.warnings.iter() {
            println!("    {what}{}", if n > 1 { format!(" (×{n})") } else { String::new() });
        }
    }
    Ok(Outcome::Done)
}

/// Counts of everything in the loaded scene, as JSON.
fn summarize(loaded: &LoadedScene) -> serde_json::Value {
    let s = &loaded.scene;
    let count = |f: &dyn Fn(&Material) -> bool| s.materials.iter().filter(|m| f(m)).count();
    let lights = |f: &dyn Fn(&Light) -> bool| s.lights.iter().filter(|l| f(l)).count();
    let bounds = scene_bounds(s);
    let emitters = s.emitter_count();
    json!({
        "format": loaded.format,
        "meshes": s.meshes.len(),
        "triangles": s.triangle_count(),
        "spheres": s.spheres.len(),
        "materials": {
            "diffuse": count(&|m| matches!(m, Material::Diffuse { .. })),
            "mirror": count(&|m| matches!(m, Material::Mirror { .. })),
            "dielectric": count(&|m| matches!(m, Material::Dielectric { .. })),
            "conductor": count(&|m| matches!(m, Material::Conductor { .. } | Material::MeasuredConductor { .. })),
        },
        "emitters": emitters,
        "lights": {
            "point": lights(&|l| matches!(l, Light::Point { .. })),
            "spot": lights(&|l| matches!(l, Light::Spot { .. })),
            "directional": lights(&|l| matches!(l, Light::Directional { .. })),
            "environment": lights(&|l| matches!(l, Light::Environment { .. })),
        },
        "cameras": loaded.cameras,
        "bounds": {
            "min": if bounds.is_empty() { json!(null) } else { json!(bounds.min.to_array()) },
            "max": if bounds.is_empty() { json!(null) } else { json!(bounds.max.to_array()) },
        },
        "scene_unit_m": loaded.options.scene_unit_m,
        "warnings": loaded.warnings.iter().map(|(w, n)| json!({"warning": w, "count": n})).collect::<Vec<_>>(),
    })
}
