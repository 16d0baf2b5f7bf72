//! Memory budgets: what a render or a blur will allocate, estimated before
//! it starts, against what the machine has, so that a job too large is
//! refused with the figures instead of aborting on a failed allocation.
//!
//! The budget is the memory the system reports available (`MemAvailable`,
//! and a cgroup's `memory.max` when lower), or the `LENSPATH_MAX_MEMORY`
//! environment variable (bytes, or with K, M, G, T: `LENSPATH_MAX_MEMORY=8G`)
//! when set, which may be lower or higher. Where neither is known, nothing
//! is refused.

use crate::error::{Error, Result};

/// The environment variable that sets the budget, over the machine's.
pub const MAX_MEMORY_ENV: &str = "LENSPATH_MAX_MEMORY";

/// Bytes a render holds per pixel of its region: the accumulated sums, counts
/// and depths (32 B), the image with its depth channel (16 B) and the encoded
/// output (measured 70.7 B a pixel for 2000×1500 and 4000×3000 renders).
pub const RENDER_BYTES_PER_PIXEL: u64 = 72;

/// Bytes an FFT blur holds per pixel of its padded grid: three real planes in
/// and out and the complex spectra of one plane and of the kernel.
pub const FFT_BYTES_PER_PADDED_PIXEL: u64 = 40;

/// The memory a job may use, bytes: [`MAX_MEMORY_ENV`] if set, else what the
/// system reports available; `None` where neither is known.
pub fn budget_bytes() -> Result<Option<u64>> {
    if let Ok(text) = std::env::var(MAX_MEMORY_ENV) {
        return parse_bytes(&text).map(Some).ok_or_else(|| {
            Error::InvalidArgument(format!(
                "{MAX_MEMORY_ENV}={text:?} is not a size such as 8G, 512M or 1000000000"
            ))
        });
    }
    Ok(available_bytes())
}

/// Fails when `needed` bytes do not fit the budget, naming `what` needs them.
pub fn check_fits(what: &dyn Fn() -> String, needed: u64) -> Result<()> {
    match budget_bytes()? {
        Some(budget) if needed > budget => Err(Error::InvalidArgument(format!(
            "{} needs about {}, more than the {} available \
             (the machine's free memory, or {MAX_MEMORY_ENV} when set)",
            what(),
            gigabytes(needed),
            gigabytes(budget)
        ))),
        _ => Ok(()),
    }
}

/// `bytes` as "12.3 GB" or "45.6 MB".
fn gigabytes(bytes: u64) -> String {
    if bytes >= 1_000_000_000 {
        format!("{:.1} GB", bytes as f64 / 1e9)
    } else {
        format!("{:.1} MB", bytes as f64 / 1e6)
    }
}

/// A size such as `8G`, `512M`, `64k` or `1000` (bytes; powers of 1024).
fn parse_bytes(text: &str) -> Option<u64> {
    let t = text.trim();
    let (number, scale) = match t.char_indices().last()? {
        (i, c) if c.is_ascii_alphabetic() => {
            let power = "KMGT".find(c.to_ascii_uppercase())? as u32 + 1;
            (&t[..i], 1024u64.checked_pow(power)?)
        }
        _ => (t, 1),
    };
    let value: f64 = number.trim().parse().ok()?;
    (value.is_finite() && value >= 0.0).then_some((value * scale as f64) as u64)
}

/// What the system reports available: `MemAvailable` from `/proc/meminfo`,
/// lowered to the cgroup v2 limit when the process runs under one.
fn available_bytes() -> Option<u64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok()?;
    let available_kb: u64 = meminfo
        .lines()
        .find_map(|l| l.strip_prefix("MemAvailable:"))?
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    let mut available = available_kb * 1024;
    let cgroup = |file: &str| -> Option<u64> { std::fs::read_to_string(file).ok()?.trim().parse().ok() };
    if let (Some(limit), Some(used)) = (
        cgroup("/sys/fs/cgroup/memory.max"),
        cgroup("/sys/fs/cgroup/memory.current"),
    ) {
        available = available.min(limit.saturating_sub(used));
    }
    Some(available)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_read_with_their_units() {
        assert_eq!(parse_bytes("1000"), Some(1000));
        assert_eq!(parse_bytes("8G"), Some(8 << 30));
        assert_eq!(parse_bytes("1.5k"), Some(1536));
        assert_eq!(parse_bytes(" 512 m "), Some(512 << 20));
        for bad in ["", "G", "-1G", "8Q", "lots", "NaN"] {
            assert_eq!(parse_bytes(bad), None, "{bad}");
        }
    }

    #[test]
    fn the_machine_reports_some_memory_on_linux() {
        if cfg!(target_os = "linux") {
            let bytes = available_bytes().expect("/proc/meminfo has MemAvailable");
            assert!(bytes > 1 << 20, "{bytes}");
        }
    }
}
