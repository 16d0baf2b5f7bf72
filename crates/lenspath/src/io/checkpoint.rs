//! Render checkpoints: a render's [`Accumulation`] saved to a file, so a
//! stopped or killed render can continue (`lenspath render --checkpoint`,
//! `--resume`). The file is little-endian binary:
//!
//! | bytes | what |
//! |---|---|
//! | 20 | `lenspath checkpoint\n` |
//! | 4 | format version (1) |
//! | 4 + n | the fingerprint: length, then UTF-8 text naming what was rendered |
//! | 16 | region: x0, y0, width, height (u32) |
//! | 24 per pixel | the sums, three f64 each |
//! | 4 per pixel | the sample counts (u32) |
//! | 4 per pixel | the depths (f32) |
//!
//! The fingerprint is the caller's: the CLI puts there everything the image
//! depends on except the sample count, so a checkpoint is never continued
//! with another scene, camera or seed.

use std::io::{Read, Write};
use std::path::Path;

use glam::DVec3;

use super::{io_error, write_atomically};
use crate::error::{Error, Result};
use crate::film::PixelRect;
use crate::render::Accumulation;

const MAGIC: &[u8; 20] = b"lenspath checkpoint\n";
const VERSION: u32 = 1;

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
    let mut r = Reader { bytes };
    if r.take(MAGIC.len(), "the header").ok() != Some(MAGIC.as_slice()) {
        return Err("not a lenspath checkpoint (the header is missing)".into());
    }
    let version = r.u32("the version")?;
    if version != VERSION {
        return Err(format!(
            "checkpoint format version {version}; this lenspath reads version {VERSION}"
        ));
    }
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
    let sum = (0..n)
        .map(|i| DVec3::new(f64_at(sums, 3 * i), f64_at(sums, 3 * i + 1), f64_at(sums, 3 * i + 2)))
        .collect();
    let count = r
        .take(4 * n, "the counts")?
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes(c.try_into().expect("4 bytes")))
        .collect();
    let depth = r
        .take(4 * n, "the depths")?
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes")))
        .collect();
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
                DVec3::new(0.1, 1e300, -0.0),
                DVec3::splat(f64::MIN_POSITIVE),
                DVec3::ONE,
                DVec3::ZERO,
            ],
            count: vec![7, 7, 0, u32::MAX],
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
        for (bytes, expected) in [
            (b"PNG".to_vec(), "not a lenspath checkpoint"),
            (whole[..28].to_vec(), "ends inside the fingerprint"),
            (
                whole[..whole.len() - 1].to_vec(),
                "needs 128 bytes of pixel data, the file has 127",
            ),
        ] {
            std::fs::write(&path, bytes).unwrap();
            let message = read_checkpoint(&path).unwrap_err().to_string();
            assert!(message.contains(expected) && message.contains("a.ckpt"), "{message}");
        }
    }
}
