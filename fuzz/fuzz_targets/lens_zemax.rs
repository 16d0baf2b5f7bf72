//! Any bytes through the Zemax `.zmx` reader (UTF-8 or UTF-16), and any lens
//! it accepts through the lens analysis and back through the table reader:
//! errors are fine, panics are not.
#![no_main]

use lenspath::lens::{zemax, AnalysisSettings, LensAnalysis, LensPrescription, LensSystem, TableConvention};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(lens) = zemax::parse(data, "fuzz.zmx") {
        let system = LensSystem::new(&lens);
        let _ = LensAnalysis::new(&system, &AnalysisSettings::default());
        let _ = system.sensor_z_for_focus_distance(2000.0, 0.1);
        // What it writes back must read back.
        LensPrescription::parse(&lens.table_text(), "fuzz.dat", TableConvention::ThicknessToNext)
            .expect("a converted lens's table reads back");
    }
});
