//! Any text through the lens-table parser, and any table it accepts through
//! the lens analysis: errors are fine, panics are not.
#![no_main]

use lenspath::lens::{AnalysisSettings, LensAnalysis, LensPrescription, LensSystem, TableConvention};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    for convention in [
        TableConvention::Auto,
        TableConvention::ThicknessToNext,
        TableConvention::DistanceFromPrevious,
    ] {
        if let Ok(lens) = LensPrescription::parse(text, "fuzz.dat", convention) {
            let system = LensSystem::new(&lens);
            let _ = LensAnalysis::new(&system, &AnalysisSettings::default());
            let _ = system.with_f_number(8.0);
            let _ = system.sensor_z_for_focus_distance(2000.0, 0.1);
        }
    }
});
