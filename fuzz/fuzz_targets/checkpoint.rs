//! Render checkpoints from any bytes (`--resume`): errors are fine, panics
//! and allocations the file's size does not justify are not; what parses
//! writes back to the same bytes. Each input is tried as it is and sealed
//! with its checksum, so the fuzzer reaches the checks behind the checksum
//! (seeds are checkpoints without their last four bytes).
#![no_main]

use lenspath::io::checkpoint::{parse_checkpoint, write_checkpoint};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut sealed = data.to_vec();
    sealed.extend_from_slice(&crc32fast::hash(data).to_le_bytes());
    for bytes in [data, &sealed] {
        round_trip(bytes);
    }
});

fn round_trip(data: &[u8]) {
    if let Ok((fingerprint, state)) = parse_checkpoint(data) {
        let n = state.region.width as usize * state.region.height as usize;
        assert!(state.sum.len() == n && state.count.len() == n && state.depth.len() == n);
        let dir = std::env::temp_dir().join(format!("lenspath-fuzz-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("c.ckpt");
        write_checkpoint(&path, &fingerprint, &state).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), data, "a parsed checkpoint writes back unchanged");
    }
}
