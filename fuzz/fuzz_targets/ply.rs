//! Any bytes through the PLY reader, and any mesh it accepts into a BVH.
#![no_main]

use std::path::Path;

use lenspath::accel::BvhSettings;
use lenspath::io::import::mesh_scene;
use lenspath::io::ply::parse_ply;
use lenspath::io::Warnings;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut warnings = Warnings::default();
    if let Ok(mesh) = parse_ply(data, Path::new("fuzz.ply"), &mut warnings) {
        let _ = mesh_scene(mesh, warnings, "PLY").scene.compile(&BvhSettings::default());
    }
});
