//! Any bytes through the glTF loader (.gltf JSON or .glb; external buffers are
//! absent), and any scene it accepts through validation and BVH construction.
#![no_main]

use std::path::Path;

use lenspath::accel::BvhSettings;
use lenspath::io::gltf::parse_gltf;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let no_files = |_: &str| Err("no files while fuzzing".to_string());
    if let Ok(loaded) = parse_gltf(data, Path::new("fuzz.gltf"), &no_files) {
        let _ = loaded.scene.compile(&BvhSettings::default());
    }
});
