//! Image output by file extension: PNG (8-bit sRGB with exposure) and
//! OpenEXR (linear float RGB plus a `Z` depth channel). Files are written
//! to a temporary name beside the target and renamed, so a reader never
//! sees a half-written file and a failed write never destroys the old one.

use std::path::Path;

use super::{io_error, write_atomically};
use crate::color::{srgb_to_linear, to_srgb8};
use crate::error::{Error, Result};
use crate::film::Image;

/// EXR header attribute holding (samples per pixel reached, requested).
pub const SPP_ATTRIBUTE: &str = "lenspathSpp";

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
}

/// Reads a PNG, JPEG or EXR image as linear RGB (see [`ReadImage`]).
pub fn read_image(path: &Path) -> Result<ReadImage> {
    if is_exr(path) {
        return Ok(ReadImage {
            image: read_exr(path)?,
            display_referred: false,
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
    super::check_writable(path)?;
    Ok(format)
}

/// Writes `image` to `path` atomically, in the format its extension names.
/// `exposure` (in stops) scales PNG output only; EXR stays linear.
pub fn write_image(path: &Path, image: &Image, exposure: f32) -> Result<()> {
    let format = ImageFormat::from_path(path)?;
    let bytes = encode_image(image, format, exposure)?;
    write_atomically(path, |tmp| std::fs::write(tmp, &bytes).map_err(|e| io_error(tmp, e)))
}

/// The bytes of `image` as a `format` file (what [`write_image`] writes).
pub fn encode_image(image: &Image, format: ImageFormat, exposure: f32) -> Result<Vec<u8>> {
    match format {
        ImageFormat::Png => encode_8bit(image, exposure, ::image::ImageFormat::Png),
        ImageFormat::Exr => encode_exr(image),
    }
}

/// A JPEG of `image` (sRGB, `exposure` stops): the small frames `lenspath view` streams.
pub fn encode_jpeg(image: &Image, exposure: f32) -> Result<Vec<u8>> {
    encode_8bit(image, exposure, ::image::ImageFormat::Jpeg)
}

fn encode_8bit(image: &Image, exposure: f32, format: ::image::ImageFormat) -> Result<Vec<u8>> {
    let bytes = to_srgb8(image, exposure);
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

fn encode_exr(image: &Image) -> Result<Vec<u8>> {
    use exr::prelude::{
        AnyChannel, AnyChannels, AttributeValue, Encoding, FlatSamples, Layer, LayerAttributes, LineOrder, SmallVec,
        Text, WritableImage,
    };
    let n = image.width as usize * image.height as usize;
    let channel = |c: usize| (0..n).map(|i| image.rgb[3 * i + c]).collect::<Vec<f32>>();
    let mut list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    list.push(AnyChannel::new("R", FlatSamples::F32(channel(0))));
    list.push(AnyChannel::new("G", FlatSamples::F32(channel(1))));
    list.push(AnyChannel::new("B", FlatSamples::F32(channel(2))));
    list.push(AnyChannel::new("Z", FlatSamples::F32(image.depth.clone())));
    let mut attributes = LayerAttributes::default();
    // One attribute (samples reached, samples requested): exr keeps custom
    // attributes in a HashMap, and a single entry keeps the bytes deterministic.
    attributes.other.insert(
        Text::from(SPP_ATTRIBUTE),
        AttributeValue::IntVec2(exr::math::Vec2(image.spp_min as i32, image.spp_requested as i32)),
    );
    let layer = Layer::new(
        (image.width as usize, image.height as usize),
        attributes,
        // Blocks in increasing order: exr compresses them in parallel, and in
        // the order they finish the file's bytes would differ from run to run.
        Encoding {
            line_order: LineOrder::Increasing,
            ..Encoding::FAST_LOSSLESS
        },
        AnyChannels::sort(list),
    );
    let mut out = std::io::Cursor::new(Vec::new());
    exr::image::Image::from_layer(layer)
        .write()
        .to_buffered(&mut out)
        .map_err(|e| Error::InvalidArgument(format!("cannot encode the image as EXR: {e}")))?;
    Ok(out.into_inner())
}

/// Reads an EXR: RGB (or a single gray channel, `Y` or the only one), `Z`
/// if present (else infinite depth), and lenspath's spp attribute if present.
pub fn read_exr(path: &Path) -> Result<Image> {
    use exr::prelude::{read_first_flat_layer_from_file, AttributeValue, Text};
    let fail = |m: String| Error::Parse {
        kind: crate::FileKind::Image,
        path: path.to_path_buf(),
        message: m,
    };
    let img = read_first_flat_layer_from_file(path).map_err(|e| fail(e.to_string()))?;
    let size = img.layer_data.size;
    let find = |name: &str| {
        img.layer_data
            .channel_data
            .list
            .iter()
            .find(|c| c.name == *name)
            .map(|c| c.sample_data.values_as_f32().collect::<Vec<f32>>())
            .ok_or_else(|| fail(format!("no '{name}' channel")))
    };
    // RGB, or one gray channel (Y, or the only one there is) for all three.
    let channels = &img.layer_data.channel_data.list;
    let (r, g, b) = match (find("R"), find("G"), find("B")) {
        (Ok(r), Ok(g), Ok(b)) => (r, g, b),
        _ => {
            let gray = find("Y").or_else(|e| match &channels[..] {
                [only] => Ok(only.sample_data.values_as_f32().collect()),
                _ => Err(e),
            })?;
            (gray.clone(), gray.clone(), gray)
        }
    };
    let depth = find("Z").unwrap_or_else(|_| vec![f32::INFINITY; r.len()]);
    let (spp_min, spp_requested) = match img.layer_data.attributes.other.get(&Text::from(SPP_ATTRIBUTE)) {
        Some(AttributeValue::IntVec2(v)) => (v.0.max(0) as u32, v.1.max(0) as u32),
        _ => (0, 0),
    };
    Ok(Image {
        width: size.0 as u32,
        height: size.1 as u32,
        rgb: (0..r.len()).flat_map(|i| [r[i], g[i], b[i]]).collect(),
        depth,
        spp_min,
        spp_requested,
    })
}
