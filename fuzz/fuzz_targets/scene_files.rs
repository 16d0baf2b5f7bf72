//! A scene graph of several files (issue 36: the limits of `base` and mesh
//! chains): the input is cut at `\n====\n` into up to eight TOML or OBJ
//! files, `s0.toml`, `s1.toml`, ... (a part starting with `v ` or `f ` is
//! `sN.obj` instead), written to a folder of their own; `s0.toml` is loaded
//! as a user would, and every scene that loads compiles. Errors (cycles,
//! files outside the folder, broken files) are fine; panics, stack overflows
//! and reads outside the folder are not.
#![no_main]

use lenspath::accel::BvhSettings;
use lenspath::io::load_scene;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let dir = std::env::temp_dir().join(format!("lenspath-fuzz-scenes-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for (i, part) in text.split("\n====\n").take(8).enumerate() {
        let ext = if part.starts_with("v ") || part.starts_with("f ") { "obj" } else { "toml" };
        std::fs::write(dir.join(format!("s{i}.{ext}")), part).unwrap();
    }
    if let Ok(loaded) = load_scene(&dir.join("s0.toml")) {
        let _ = loaded.scene.compile(&BvhSettings::default());
    }
});
