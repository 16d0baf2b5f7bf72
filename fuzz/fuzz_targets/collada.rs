//! Any text through the COLLADA loader, and any scene it accepts through
//! validation and BVH construction: errors are fine, panics are not.
#![no_main]

use std::path::Path;

use lenspath::accel::BvhSettings;
use lenspath::io::collada::parse_collada;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    if let Ok(loaded) = parse_collada(text, Path::new("fuzz.dae")) {
        let _ = loaded.scene.compile(&BvhSettings::default());
    }
});
