//! Any text through the OBJ loader (material libraries are absent), and any
//! scene it accepts through validation and BVH construction.
#![no_main]

use std::path::Path;

use lenspath::accel::BvhSettings;
use lenspath::io::obj::parse_obj;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let no_mtl = |_: &Path| Err(tobj::LoadError::OpenFileFailed);
    if let Ok(loaded) = parse_obj(text, Path::new("fuzz.obj"), &no_mtl) {
        let _ = loaded.scene.compile(&BvhSettings::default());
    }
});
