//! Image output by file extension: PNG (8-bit sRGB with exposure) and
//! OpenEXR (linear float RGB plus a `Z` depth channel, placed in its frame
//! and described by its header: [`super::exr`]). Files are written to a
//! temporary name beside the target and renamed, so a reader never sees a
//! half-written file and a failed write never destroys the old one.

use std::collections::BTreeMap;
use std::path::Path;

use super::exr::{encode_exr, read_exr_image, ExrImage, HeaderValue};
use crate::camera::ApertureShape;
use crate::color::{srgb_to_linear, to_srgb8};
use crate::error::{Error, Result};
use crate::film::Image;
use crate::fs::{io_error, write_atomically};
use crate::FileKind;

/// EXR attribute: the samples per pixel every pixel reached.
pub const SPP_ATTRIBUTE: &str = "lenspath/spp";
/// EXR attribute: the samples per pixel asked for.
pub const SPP_REQUESTED_ATTRIBUTE: &str = "lenspath/sppRequested";
/// The (reached, requested) pair lenspath wrote before 0.1.0's EXR headers; still read.
const OLD_SPP_ATTRIBUTE: &str = "lenspathSpp";

/// What an EXR says beyond its pixels: the frame the image lies in and the
/// attributes of the render that made it. PNG keeps none of it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ImageHeader {
    /// For a crop: the whole frame's size and the image's top-left pixel in
    /// it (the EXR display window and data window). `None`: the image is the frame.
    pub frame: Option<((u32, u32), (i32, i32))>,
    /// Attributes by OpenEXR name (standard ones and `lenspath/...`).
    pub attributes: BTreeMap<String, HeaderValue>,
}

/// Supported output formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// 8-bit sRGB PNG.
    Png,
    /// 32-bit float OpenEXR with R, G, B and Z channels.
    Exr,
}

impl ImageFormat {
    /// The format for `path`'s extension, or an error naming the supported ones.
    pub fn from_path(path: &Path) -> Result<ImageFormat> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("png") => Ok(ImageFormat::Png),
            Some("exr") => Ok(ImageFormat::Exr),
            other => Err(Error::InvalidArgument(format!(
                "{}: unknown image extension {}; use .png or .exr",
                path.display(),
                other.map_or("(none)".to_string(), |e| format!("'.{e}'"))
            ))),
        }
    }
}

/// An image read for processing, and how its values were stored.
#[derive(Clone, Debug)]
pub struct ReadImage {
    /// The pixels, in linear light (PNG and JPEG are decoded from sRGB).
    pub image: Image,
    /// Whether the file held display-referred 8- or 16-bit sRGB values (PNG,
    /// JPEG) rather than linear floats (EXR): its highlights are clipped at 1.
    pub display_referred: bool,
    /// An EXR's header (empty for PNG and JPEG): what a tool that writes
    /// the processed image carries over.
    pub header: ImageHeader,
}

/// Reads a PNG, JPEG or EXR image as linear RGB (see [`ReadImage`]).
pub fn read_image(path: &Path) -> Result<ReadImage> {
    if is_exr(path) {
        let (image, header) = read_exr_with_header(path)?;
        return Ok(ReadImage {
            image,
            display_referred: false,
            header,
        });
    }
    let decoded = decode(path)?.to_rgb32f();
    let (width, height) = decoded.dimensions();
    let rgb: Vec<f32> = decoded.into_raw().into_iter().map(srgb_to_linear).collect();
    Ok(ReadImage {
        image: Image {
            width,
            height,
            depth: vec![f32::INFINITY; rgb.len() / 3],
            rgb,
            spp_min: 0,
            spp_requested: 0,
        },
        display_referred: true,
        header: ImageHeader::default(),
    })
}

/// An aperture mask ([`ApertureShape::Mask`]) from a grayscale PNG, JPEG
/// or EXR image ([`read_gray`]; values above 1 count as 1); a bad mask is an
/// error naming the file.
pub fn read_aperture_mask(path: &Path) -> Result<ApertureShape> {
    let (width, height, values) = read_gray(path)?;
    ApertureShape::mask(width, height, values).map_err(|e| Error::Parse {
        kind: FileKind::Image,
        path: path.to_path_buf(),
        message: e.to_string(),
    })
}

/// Reads a grayscale map such as an aperture mask: width, height and values
/// row-major from the top. PNG and JPEG gray levels are read as fractions of
/// full white, not linearised (a painted mask's gray is its transmission);
/// EXR values as stored; colour becomes Rec. 709 luminance.
pub fn read_gray(path: &Path) -> Result<(usize, usize, Vec<f32>)> {
    let luminance = |rgb: &[f32]| crate::color::luminance([rgb[0], rgb[1], rgb[2]]);
    if is_exr(path) {
        let image = read_exr(path)?;
        let values = image.rgb.chunks_exact(3).map(luminance).collect();
        return Ok((image.width as usize, image.height as usize, values));
    }
    let decoded = decode(path)?.to_rgb32f();
    let (width, height) = decoded.dimensions();
    let values = decoded.as_raw().chunks_exact(3).map(luminance).collect();
    Ok((width as usize, height as usize, values))
}

fn is_exr(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"))
}

/// Decodes a PNG or JPEG, with errors naming the file.
fn decode(path: &Path) -> Result<::image::DynamicImage> {
    let reader = ::image::ImageReader::open(path)
        .map_err(|e| io_error(path, e))?
        .with_guessed_format()
        .map_err(|e| io_error(path, e))?;
    reader.decode().map_err(|e| match e {
        ::image::ImageError::IoError(io) => io_error(path, io),
        other => Error::Parse {
            kind: crate::FileKind::Image,
            path: path.to_path_buf(),
            message: format!("not a readable PNG, JPEG or EXR image: {other}"),
        },
    })
}

/// Fails early (before a long render) when `path` has an unknown extension
/// or its directory cannot be written.
pub fn check_output_path(path: &Path) -> Result<ImageFormat> {
    let format = ImageFormat::from_path(path)?;
    crate::fs::check_writable(path)?;
    Ok(format)
}

/// Writes `image` to `path` atomically, in the format its extension names.
/// `exposure` (in stops) scales PNG output only; EXR stays linear.
pub fn write_image(path: &Path, image: &Image, exposure: f32) -> Result<()> {
    write_image_with_header(path, image, exposure, &ImageHeader::default())
}

/// [`write_image`], an EXR carrying `header` (a PNG ignores it).
pub fn write_image_with_header(path: &Path, image: &Image, exposure: f32, header: &ImageHeader) -> Result<()> {
    let bytes = encode_image(image, ImageFormat::from_path(path)?, exposure, header)?;
    write_atomically(path, |tmp| std::fs::write(tmp, &bytes).map_err(|e| io_error(tmp, e)))
}

/// The bytes of `image` as a `format` file (what [`write_image_with_header`]
/// writes; a PNG ignores `header`).
pub fn encode_image(image: &Image, format: ImageFormat, exposure: f32, header: &ImageHeader) -> Result<Vec<u8>> {
    match format {
        ImageFormat::Png => encode_8bit(image, exposure, ::image::ImageFormat::Png),
        ImageFormat::Exr => encode_exr(&exr_of_image(image, header)),
    }
}

/// A JPEG of `image` (sRGB, `exposure` stops): the small frames `lenspath view` streams.
pub fn encode_jpeg(image: &Image, exposure: f32) -> Result<Vec<u8>> {
    encode_8bit(image, exposure, ::image::ImageFormat::Jpeg)
}

/// `image` as an EXR: R, G, B and Z, placed and described by `header`, with
/// the samples per pixel when it was rendered.
pub fn exr_of_image(image: &Image, header: &ImageHeader) -> ExrImage {
    let mut exr = ExrImage::new(image.width, image.height);
    let n = image.width as usize * image.height as usize;
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        exr.channels
            .insert(name.into(), (0..n).map(|i| image.rgb[3 * i + c]).collect());
    }
    exr.channels.insert("Z".into(), image.depth.clone());
    if let Some((display_size, data_origin)) = header.frame {
        (exr.display_size, exr.data_origin) = (display_size, data_origin);
    }
    if image.spp_requested > 0 {
        let int = |v: u32| HeaderValue::Int(v.min(i32::MAX as u32) as i32);
        exr.attributes.insert(SPP_ATTRIBUTE.into(), int(image.spp_min));
        exr.attributes
            .insert(SPP_REQUESTED_ATTRIBUTE.into(), int(image.spp_requested));
    }
    exr.attributes
        .extend(header.attributes.iter().map(|(k, v)| (k.clone(), v.clone())));
    exr
}

fn encode_8bit(image: &Image, exposure: f32, format: ::image::ImageFormat) -> Result<Vec<u8>> {
    let bytes = to_srgb8(&image.rgb, exposure);
    let mut out = std::io::Cursor::new(Vec::new());
    ::image::write_buffer_with_format(
        &mut out,
        &bytes,
        image.width,
        image.height,
        ::image::ExtendedColorType::Rgb8,
        format,
    )
    .map_err(|e| Error::InvalidArgument(format!("cannot encode the image as {format:?}: {e}")))?;
    Ok(out.into_inner())
}

/// Reads an EXR: RGB (or a single gray channel, `Y` or the only one), `Z`
/// if present (else infinite depth), and the samples per pixel if recorded.
pub fn read_exr(path: &Path) -> Result<Image> {
    Ok(image_of_exr(path, &read_exr_image(path)?)?.0)
}

/// [`read_exr`] with the file's header.
pub fn read_exr_with_header(path: &Path) -> Result<(Image, ImageHeader)> {
    image_of_exr(path, &read_exr_image(path)?)
}

/// The image an EXR holds (see [`read_exr`]) and its header.
fn image_of_exr(path: &Path, exr: &ExrImage) -> Result<(Image, ImageHeader)> {
    let find = |name: &str| exr.channels.get(name);
    // RGB, or one gray channel (Y, or the only one there is) for all three.
    let (r, g, b) = match (find("R"), find("G"), find("B")) {
        (Some(r), Some(g), Some(b)) => (r, g, b),
        _ => {
            let only = (exr.channels.len() == 1)
                .then(|| exr.channels.values().next())
                .flatten();
            let gray = find("Y").or(only).ok_or_else(|| Error::Parse {
                kind: crate::FileKind::Image,
                path: path.to_path_buf(),
                message: "no 'R' channel".into(),
            })?;
            (gray, gray, gray)
        }
    };
    let n = r.len();
    let int = |name: &str| match exr.attributes.get(name) {
        Some(HeaderValue::Int(v)) => Some(((*v).max(0) as u32, 0)),
        Some(HeaderValue::IntPair([reached, requested])) => {
            Some(((*reached).max(0) as u32, (*requested).max(0) as u32))
        }
        _ => None,
    };
    let (spp_min, spp_requested) = match (int(SPP_ATTRIBUTE), int(SPP_REQUESTED_ATTRIBUTE)) {
        (Some((reached, _)), Some((requested, _))) => (reached, requested),
        _ => int(OLD_SPP_ATTRIBUTE).unwrap_or((0, 0)),
    };
    let frame = (exr.display_size != (exr.width, exr.height) || exr.data_origin != (0, 0))
        .then_some((exr.display_size, exr.data_origin));
    let image = Image {
        width: exr.width,
        height: exr.height,
        rgb: (0..n).flat_map(|i| [r[i], g[i], b[i]]).collect(),
        depth: find("Z").cloned().unwrap_or_else(|| vec![f32::INFINITY; n]),
        spp_min,
        spp_requested,
    };
    Ok((
        image,
        ImageHeader {
            frame,
            attributes: exr.attributes.clone(),
        },
    ))
}
