//! Raw frames out: DNG (Adobe Digital Negative 1.4, a TIFF with the tags a
//! raw developer needs), or the mosaic alone as a 16-bit greyscale PNG or
//! TIFF. Written atomically, like every output.

use std::io::Cursor;
use std::path::Path;

use glam::DMat3;
use tiff::encoder::{colortype, Rational, SRational, TiffEncoder};
use tiff::tags::Tag;

use super::{Cfa, RawFrame};
use crate::fs::write_bytes;
use crate::{Error, Result};

/// DNG tags (Adobe DNG Specification 1.4.0.0, ch. 4), by number.
mod dng_tag {
    pub const CFA_REPEAT_PATTERN_DIM: u16 = 33421;
    pub const CFA_PATTERN: u16 = 33422;
    pub const DNG_VERSION: u16 = 50706;
    pub const DNG_BACKWARD_VERSION: u16 = 50707;
    pub const UNIQUE_CAMERA_MODEL: u16 = 50708;
    pub const CFA_PLANE_COLOR: u16 = 50710;
    pub const CFA_LAYOUT: u16 = 50711;
    pub const BLACK_LEVEL: u16 = 50714;
    pub const WHITE_LEVEL: u16 = 50717;
    pub const COLOR_MATRIX_1: u16 = 50721;
    pub const AS_SHOT_NEUTRAL: u16 = 50728;
    pub const CALIBRATION_ILLUMINANT_1: u16 = 50778;
    /// PhotometricInterpretation of a colour filter array (TIFF/EP).
    pub const PHOTOMETRIC_CFA: u16 = 32803;
    /// PhotometricInterpretation of linear samples (a monochrome sensor).
    pub const PHOTOMETRIC_LINEAR_RAW: u16 = 34892;
    /// CalibrationIlluminant: D65 (EXIF LightSource).
    pub const ILLUMINANT_D65: u16 = 21;
    /// EXIF ExposureTime (TIFF/EP), s.
    pub const EXPOSURE_TIME: u16 = 33434;
    /// EXIF ISOSpeedRatings (TIFF/EP).
    pub const ISO_SPEED_RATINGS: u16 = 34855;
}

/// The raw formats, by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RawFormat {
    /// Adobe DNG: the mosaic with its black and white levels, pattern and
    /// colour matrix.
    Dng,
    /// The mosaic as a 16-bit greyscale PNG (digital numbers as they are).
    Png16,
    /// The mosaic as a 16-bit greyscale TIFF.
    Tiff16,
}

impl RawFormat {
    /// The format `path`'s extension names.
    pub fn of(path: &Path) -> Result<RawFormat> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        match ext.as_str() {
            "dng" => Ok(RawFormat::Dng),
            "png" => Ok(RawFormat::Png16),
            "tif" | "tiff" => Ok(RawFormat::Tiff16),
            _ => Err(Error::InvalidArgument(format!(
                "{}: a raw frame is written as .dng, .png (16-bit mosaic) or .tif (16-bit mosaic)",
                path.display()
            ))),
        }
    }
}

/// Writes `frame` to `path` in the format its extension names.
pub fn write_raw(path: &Path, frame: &RawFrame) -> Result<()> {
    let format = RawFormat::of(path)?;
    let encoded = match format {
        RawFormat::Png16 => png16(frame),
        RawFormat::Tiff16 | RawFormat::Dng => tiff16(frame, format == RawFormat::Dng),
    }
    .map_err(|message| Error::InvalidArgument(format!("{}: {message}", path.display())))?;
    write_bytes(path, &encoded)
}

fn png16(frame: &RawFrame) -> std::result::Result<Vec<u8>, String> {
    let image = image::ImageBuffer::<image::Luma<u16>, _>::from_raw(frame.width, frame.height, frame.dn.clone())
        .ok_or("the mosaic's size does not match its pixels")?;
    let mut bytes = Cursor::new(Vec::new());
    image
        .write_to(&mut bytes, image::ImageFormat::Png)
        .map_err(|e| e.to_string())?;
    Ok(bytes.into_inner())
}

fn tiff16(frame: &RawFrame, dng: bool) -> std::result::Result<Vec<u8>, String> {
    let mut bytes = Cursor::new(Vec::new());
    {
        let mut encoder = TiffEncoder::new(&mut bytes).map_err(|e| e.to_string())?;
        let mut image = encoder
            .new_image::<colortype::Gray16>(frame.width, frame.height)
            .map_err(|e| e.to_string())?;
        if dng {
            dng_tags(image.encoder(), frame).map_err(|e| e.to_string())?;
        }
        image.write_data(&frame.dn).map_err(|e| e.to_string())?;
    }
    Ok(bytes.into_inner())
}

fn dng_tags<W: std::io::Write + std::io::Seek, K: tiff::encoder::TiffKind>(
    tags: &mut tiff::encoder::DirectoryEncoder<'_, W, K>,
    frame: &RawFrame,
) -> tiff::TiffResult<()> {
    use dng_tag::*;
    let mono = frame.cfa == Cfa::Mono;
    tags.write_tag(Tag::NewSubfileType, 0u32)?;
    tags.write_tag(Tag::Make, "lenspath")?;
    tags.write_tag(Tag::Model, frame.exposure.sensor_name.as_str())?;
    tags.write_tag(Tag::Software, concat!("lenspath ", env!("CARGO_PKG_VERSION")))?;
    tags.write_tag(Tag::Unknown(DNG_VERSION), &[1u8, 4, 0, 0][..])?;
    tags.write_tag(Tag::Unknown(DNG_BACKWARD_VERSION), &[1u8, 1, 0, 0][..])?;
    tags.write_tag(
        Tag::Unknown(UNIQUE_CAMERA_MODEL),
        format!("lenspath {}", frame.exposure.sensor_name).as_str(),
    )?;
    tags.write_tag(Tag::Unknown(BLACK_LEVEL), frame.black_level_dn)?;
    tags.write_tag(Tag::Unknown(WHITE_LEVEL), frame.white_level_dn)?;
    tags.write_tag(Tag::Unknown(CALIBRATION_ILLUMINANT_1), ILLUMINANT_D65)?;
    tags.write_tag(Tag::Unknown(EXPOSURE_TIME), rational(frame.exposure.exposure_time_s))?;
    tags.write_tag(
        Tag::Unknown(ISO_SPEED_RATINGS),
        frame.exposure.iso.round().clamp(1.0, 65535.0) as u16,
    )?;
    if mono {
        tags.write_tag(Tag::PhotometricInterpretation, PHOTOMETRIC_LINEAR_RAW)?;
        // One channel: its row of the matrix (green's, what it reads).
        let row = frame.xyz_to_camera.row(1);
        tags.write_tag(Tag::Unknown(COLOR_MATRIX_1), &[row.x, row.y, row.z].map(srational)[..])?;
        tags.write_tag(Tag::Unknown(AS_SHOT_NEUTRAL), &[rational(1.0)][..])?;
    } else {
        tags.write_tag(Tag::PhotometricInterpretation, PHOTOMETRIC_CFA)?;
        tags.write_tag(Tag::Unknown(CFA_REPEAT_PATTERN_DIM), &[2u16, 2][..])?;
        tags.write_tag(Tag::Unknown(CFA_PATTERN), &frame.cfa.block().map(|c| c as u8)[..])?;
        tags.write_tag(Tag::Unknown(CFA_PLANE_COLOR), &[0u8, 1, 2][..])?;
        tags.write_tag(Tag::Unknown(CFA_LAYOUT), 1u16)?;
        tags.write_tag(Tag::Unknown(COLOR_MATRIX_1), &matrix(frame.xyz_to_camera)[..])?;
        let n = frame.as_shot_neutral;
        tags.write_tag(Tag::Unknown(AS_SHOT_NEUTRAL), &[n.x, n.y, n.z].map(rational)[..])?;
    }
    Ok(())
}

/// Row-major, as DNG stores a matrix.
fn matrix(m: DMat3) -> [SRational; 9] {
    let rows = [m.row(0), m.row(1), m.row(2)];
    std::array::from_fn(|i| srational(rows[i / 3][i % 3]))
}

/// `v` to 1/10⁶.
fn srational(v: f64) -> SRational {
    SRational {
        n: (v * 1e6).round() as i32,
        d: 1_000_000,
    }
}

fn rational(v: f64) -> Rational {
    Rational {
        n: (v.max(0.0) * 1e6).round() as u32,
        d: 1_000_000,
    }
}
