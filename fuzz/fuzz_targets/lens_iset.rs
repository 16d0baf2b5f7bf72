//! Any text through the ISET lens JSON reader, and any lens it accepts
//! through the lens analysis and back through the table reader: errors are
//! fine, panics are not.
#![no_main]

use lenspath::lens::{iset, AnalysisSettings, LensAnalysis, LensPrescription, LensSystem, TableConvention};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    if let Ok(lens) = iset::parse(text, "fuzz.json") {
        let system = LensSystem::new(&lens);
        let _ = LensAnalysis::new(&system, &AnalysisSettings::default());
        let _ = system.sensor_z_for_focus_distance(2000.0, 0.1);
        LensPrescription::parse(&lens.table_text(), "fuzz.dat", TableConvention::ThicknessToNext)
            .expect("a converted lens's table reads back");
    }
});
