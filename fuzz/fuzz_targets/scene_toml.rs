//! Any text through the lenspath TOML scene parser (referenced files are
//! absent), and any scene it accepts through validation and BVH construction.
#![no_main]

use std::path::Path;

use lenspath::accel::BvhSettings;
use lenspath::io::scene_file::parse_scene_file;
use lenspath::Error;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let no_files = |p: &Path| Err(Error::InvalidArgument(format!("{}: no files while fuzzing", p.display())));
    if let Ok(loaded) = parse_scene_file(text, Path::new("fuzz.toml"), &no_files) {
        let _ = loaded.scene.compile(&BvhSettings::default());
    }
});
