//! Render checkpoints: a render's [`Accumulation`] saved to a file, so a
//! stopped or killed render can continue (`lenspath render --checkpoint`,
//! `--resume`). The file is little-endian binary:
//!
//! | bytes | what |
//! |---|---|
//! | 20 | `lenspath checkpoint\n` |
//! | 4 | format version (2) |
//! | 4 + n | the fingerprint: length, then UTF-8 text naming what was rendered |
//! | 16 | region: x0, y0, width, height (u32) |
//! | 24 per pixel | the sums, three f64 each |
//! | 4 per pixel | the sample counts (u32) |
//! | 4 per pixel | the depths (f32) |
//! | 4 | CRC-32 (IEEE) of every byte before it |
//!
//! A damaged file (a flipped bit, a truncated write, sums no render could
//! make) is refused rather than continued into a wrong image.
//!
//! The fingerprint is the caller's: the CLI puts there everything the image
//! depends on except the sample count (`setup::RenderSetup::fingerprint`),
//! so a checkpoint is never continued with another scene, camera or seed
//! ([`resume_state`]).

use std::io::{Read, Write};
use std::path::Path;

use glam::DVec3;

use crate::error::{Error, Result};
use crate::film::PixelRect;
use crate::fs::{io_error, write_atomically};
use crate::render::Accumulation;

const MAGIC: &[u8; 20] = b"lenspath checkpoint\n";
const VERSION: u32 = 2;

/// The state saved in `path`, checked to be of the render `fingerprint` describes.
pub fn resume_state(path: &Path, fingerprint: &str) -> Result<Accumulation> {
    let (saved, state) = read_checkpoint(path)?;
    if saved != fingerprint {
        return Err(Error::InvalidArgument(format!(
            "{} is the checkpoint of another render (the scene, camera or settings differ, or \
             another lenspath made it):\n  saved:    {saved}\n  this one: {fingerprint}",
            path.display()
        )));
    }
    Ok(state)
}

/// Writes `state` and its `fingerprint` to `path` atomically (temporary file + rename).
pub fn write_checkpoint(path: &Path, fingerprint: &str, state: &Accumulation) -> Result<()> {
    write_atomically(path, |tmp| {
        let n = state.sum.len();
        let mut bytes = Vec::with_capacity(48 + fingerprint.len() + 32 * n);
        bytes.extend_from_slice(MAGIC);
        bytes.extend_from_slice(&VERSION.to_le_bytes());
        bytes.extend_from_slice(&(fingerprint.len() as u32).to_le_bytes());
        bytes.extend_from_slice(fingerprint.as_bytes());
        let r = state.region;
        for v in [r.x0, r.y0, r.width, r.height] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        for s in &state.sum {
            for c in s.to_array() {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
        for c in &state.count {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
        for d in &state.depth {
            bytes.extend_from_slice(&d.to_le_bytes());
        }
        let checksum = crc32fast::hash(&bytes);
        bytes.extend_from_slice(&checksum.to_le_bytes());
        let mut file = std::fs::File::create(tmp).map_err(|e| io_error(path, e))?;
        file.write_all(&bytes).map_err(|e| io_error(path, e))?;
        // On disk before the rename, so a crash cannot leave an empty checkpoint.
        file.sync_all().map_err(|e| io_error(path, e))
    })
}

/// Reads a checkpoint: its fingerprint and the saved state.
pub fn read_checkpoint(path: &Path) -> Result<(String, Accumulation)> {
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|mut f| f.read_to_end(&mut bytes))
        .map_err(|e| io_error(path, e))?;
    parse_checkpoint(&bytes).map_err(|message| Error::Parse {
        kind: crate::FileKind::Checkpoint,
        path: path.to_path_buf(),
        message,
    })
}

/// Splits the front off a byte slice, failing with what was being read.
struct Reader<'a> {
    bytes: &'a [u8],
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize, what: &str) -> std::result::Result<&'a [u8], String> {
        if self.bytes.len() < n {
            return Err(format!(
                "the file ends inside {what}; it is not a whole lenspath checkpoint"
            ));
        }
        let (head, rest) = self.bytes.split_at(n);
        self.bytes = rest;
        Ok(head)
    }

    fn u32(&mut self, what: &str) -> std::result::Result<u32, String> {
        Ok(u32::from_le_bytes(self.take(4, what)?.try_into().expect("4 bytes")))
    }
}

/// A checkpoint from its bytes: its fingerprint and state, or what is wrong
/// (the file name is added by [`read_checkpoint`]).
pub fn parse_checkpoint(bytes: &[u8]) -> std::result::Result<(String, Accumulation), String> {
    if !bytes.starts_with(MAGIC) {
        return Err("not a lenspath checkpoint (the header is missing)".into());
    }
    let mut r = Reader {
        bytes: &bytes[MAGIC.len()..],
    };
    let version = r.u32("the version")?;
    if version != VERSION {
        return Err(format!(
            "checkpoint format version {version}; this lenspath reads version {VERSION}"
        ));
    }
    let Some(body_len) = bytes.len().checked_sub(4).filter(|&n| n >= MAGIC.len() + 4) else {
        return Err("the file ends inside the checksum; it is not a whole lenspath checkpoint".into());
    };
    let (body, stored) = bytes.split_at(body_len);
    if crc32fast::hash(body) != u32::from_le_bytes(stored.try_into().expect("4 bytes")) {
        return Err("the checksum does not match: the file is damaged (or was cut short)".into());
    }
    r.bytes = &body[MAGIC.len() + 4..];
    let length = r.u32("the fingerprint's length")? as usize;
    let fingerprint = std::str::from_utf8(r.take(length, "the fingerprint")?)
        .map_err(|_| "the fingerprint is not UTF-8".to_string())?
        .to_string();
    let region = PixelRect {
        x0: r.u32("the region")?,
        y0: r.u32("the region")?,
        width: r.u32("the region")?,
        height: r.u32("the region")?,
    };
    let n = region.width as usize * region.height as usize;
    let needed = n.checked_mul(32).filter(|&b| b == r.bytes.len());
    if needed.is_none() {
        return Err(format!(
            "a {}x{} region needs {} bytes of pixel data, the file has {}",
            region.width,
            region.height,
            32 * u128::from(region.width) * u128::from(region.height),
            r.bytes.len()
        ));
    }
    let f64_at = |b: &[u8], i: usize| f64::from_le_bytes(b[8 * i..8 * i + 8].try_into().expect("8 bytes"));
    let sums = r.take(24 * n, "the sums")?;
    let sum: Vec<DVec3> = (0..n)
        .map(|i| DVec3::new(f64_at(sums, 3 * i), f64_at(sums, 3 * i + 1), f64_at(sums, 3 * i + 2)))
        .collect();
    let count: Vec<u32> = r
        .take(4 * n, "the counts")?
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes(c.try_into().expect("4 bytes")))
        .collect();
    let depth: Vec<f32> = r
        .take(4 * n, "the depths")?
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes")))
        .collect();
    check_sums(&sum, &count, &depth)?;
    Ok((
        fingerprint,
        Accumulation {
            region,
            sum,
            count,
            depth,
        },
    ))
}

/// Fails for accumulated values no render makes: a sum that is not finite
/// or larger than its samples could add up to (each sample is an `f32`), a
/// NaN or negative depth.
fn check_sums(sum: &[DVec3], count: &[u32], depth: &[f32]) -> std::result::Result<(), String> {
    for (i, (s, &n)) in sum.iter().zip(count).enumerate() {
        let bound = f64::from(n) * f64::from(f32::MAX);
        if !s.is_finite() || s.abs().max_element() > bound {
            return Err(format!(
                "pixel {i} of the region holds the sum {s} of {n} samples, which no render makes"
            ));
        }
    }
    if let Some(i) = depth.iter().position(|d| d.is_nan() || *d < 0.0) {
        return Err(format!("pixel {i} of the region has the depth {}", depth[i]));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state() -> Accumulation {
        Accumulation {
            region: PixelRect {
                x0: 3,
                y0: 1,
                width: 2,
                height: 2,
            },
            sum: vec![
                DVec3::new(0.1, 1e39, -0.0),
                DVec3::splat(f64::MIN_POSITIVE),
                DVec3::ONE,
                DVec3::ZERO,
            ],
            count: vec![7, 7, 1, u32::MAX],
            depth: vec![1.5, f32::INFINITY, 0.0, 3.25],
        }
    }

    #[test]
    fn a_checkpoint_reads_back_bit_for_bit() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.ckpt");
        write_checkpoint(&path, "scene x, seed 3", &state()).unwrap();
        let (fingerprint, back) = read_checkpoint(&path).unwrap();
        assert_eq!(fingerprint, "scene x, seed 3");
        assert_eq!(back, state());
    }

    #[test]
    fn damaged_checkpoints_are_rejected_with_the_reason() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.ckpt");
        write_checkpoint(&path, "f", &state()).unwrap();
        let whole = std::fs::read(&path).unwrap();
        // The same file with `edit` applied and its checksum made right again.
        let resealed = |edit: &dyn Fn(&mut Vec<u8>)| {
            let mut bytes = whole[..whole.len() - 4].to_vec();
            edit(&mut bytes);
            let checksum = crc32fast::hash(&bytes);
            bytes.extend_from_slice(&checksum.to_le_bytes());
            bytes
        };
        // The first pixel's first sum starts after the header, version, fingerprint and region.
        let first_sum = MAGIC.len() + 4 + 4 + 1 + 16;
        let mut flipped = whole.clone();
        flipped[first_sum + 3] ^= 0x10;
        let set_sum =
            |value: f64| resealed(&|b: &mut Vec<u8>| b[first_sum..first_sum + 8].copy_from_slice(&value.to_le_bytes()));
        for (bytes, expected) in [
            (b"PNG".to_vec(), "not a lenspath checkpoint"),
            (whole[..26].to_vec(), "ends inside the checksum"),
            (whole[..whole.len() - 1].to_vec(), "the checksum does not match"),
            (flipped, "the checksum does not match"),
            (
                resealed(&|b: &mut Vec<u8>| b.truncate(b.len() - 1)),
                "needs 128 bytes of pixel data, the file has 127",
            ),
            (
                resealed(&|b: &mut Vec<u8>| b.truncate(28)),
                "ends inside the fingerprint",
            ),
            (set_sum(f64::NAN), "pixel 0 of the region holds the sum [NaN"),
            (set_sum(1e300), "which no render makes"),
        ] {
            std::fs::write(&path, bytes).unwrap();
            let message = read_checkpoint(&path).unwrap_err().to_string();
            assert!(
                message.contains(expected) && message.contains("a.ckpt"),
                "{expected}: {message}"
            );
        }
    }
}
