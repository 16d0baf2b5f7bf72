//! OpenEXR files as the ecosystem writes them: one layer of float channels,
//! a data window placed in the display window (a crop keeps the whole
//! frame's size and its own offset, as pbrt writes one), and header
//! attributes by their OpenEXR names: the standard ones (`worldToCamera`,
//! `worldToNDC`, `focus`, `aperture`, `expTime`, `isoSpeed`,
//! `chromaticities`, `owner`, `comments`, ...; "Technical Introduction to
//! OpenEXR", Standard Attributes) and lenspath's render settings under
//! `lenspath/`. Attributes are written in name order (as OpenEXR's own
//! library does), so the same image gives the same bytes.

use std::collections::BTreeMap;
use std::path::Path;

use exr::math::Vec2;
use exr::meta::attribute::{AttributeValue, Chromaticities, IntegerBounds, Text};

use crate::error::{Error, Result};
use crate::fs::{io_error, write_atomically};

/// A header attribute's value: the OpenEXR types lenspath reads and writes.
#[derive(Clone, Debug, PartialEq)]
pub enum HeaderValue {
    /// `int`.
    Int(i32),
    /// `float`.
    Float(f32),
    /// `double`.
    Double(f64),
    /// `string`.
    Text(String),
    /// `v2i`.
    IntPair([i32; 2]),
    /// `v2f`.
    FloatPair([f32; 2]),
    /// `m44f`, row-major as stored: OpenEXR multiplies row vectors, `p · M`
    /// (so these 16 numbers are a column-vector matrix's columns, glam's
    /// `Mat4::to_cols_array`).
    Matrix([f32; 16]),
    /// `chromaticities`: red, green, blue and white CIE xy.
    Chromaticities([f32; 8]),
}

/// The chromaticities of lenspath's RGB: linear Rec. 709 / sRGB primaries, D65 white (ITU-R BT.709).
pub const REC709_CHROMATICITIES: [f32; 8] = [0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290];

/// One image layer of an EXR file: its channels as 32-bit floats, where it
/// lies in the frame, and its attributes.
#[derive(Clone, Debug, PartialEq)]
pub struct ExrImage {
    /// Width in pixels (the data window's).
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Channels by name, each one value per pixel, row-major from the top
    /// (written in name order, as OpenEXR requires).
    pub channels: BTreeMap<String, Vec<f32>>,
    /// The whole frame's size (the display window), for a crop bigger than the image.
    pub display_size: (u32, u32),
    /// The image's top-left pixel in the frame (the data window's origin).
    pub data_origin: (i32, i32),
    /// Header attributes by OpenEXR name, beyond those that describe the pixels' layout.
    pub attributes: BTreeMap<String, HeaderValue>,
}

impl ExrImage {
    /// An image of `width` × `height` with no channels yet, filling its frame, with lenspath's
    /// RGB chromaticities.
    pub fn new(width: u32, height: u32) -> Self {
        ExrImage {
            width,
            height,
            channels: BTreeMap::new(),
            display_size: (width, height),
            data_origin: (0, 0),
            attributes: BTreeMap::from([(
                "chromaticities".to_string(),
                HeaderValue::Chromaticities(REC709_CHROMATICITIES),
            )]),
        }
    }
}

/// The standard attributes exr keeps in typed fields, by OpenEXR name.
const STANDARD_TEXT: [&str; 4] = ["owner", "comments", "capDate", "software"];
const STANDARD_FLOAT: [&str; 5] = ["focus", "expTime", "aperture", "isoSpeed", "utcOffset"];
const STANDARD_MATRIX: [&str; 2] = ["worldToCamera", "worldToNDC"];

/// The bytes of `image` as an EXR file (32-bit float channels, ZIP16
/// compression, attributes in name order).
pub fn encode_exr(image: &ExrImage) -> Result<Vec<u8>> {
    use exr::prelude::{
        AnyChannel, AnyChannels, Encoding, FlatSamples, Layer, LayerAttributes, LineOrder, SmallVec, WritableImage,
    };
    let invalid = |m: String| Error::InvalidArgument(format!("cannot write the EXR: {m}"));
    let pixels = image.width as usize * image.height as usize;
    if image.width == 0 || image.height == 0 || image.channels.is_empty() {
        return Err(invalid(format!(
            "it needs pixels and a channel, got {}x{} with {} channels",
            image.width,
            image.height,
            image.channels.len()
        )));
    }
    let mut list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for (name, values) in &image.channels {
        if values.len() != pixels || name.is_empty() {
            return Err(invalid(format!(
                "channel '{name}' holds {} values for {pixels} pixels",
                values.len()
            )));
        }
        list.push(AnyChannel::new(name.as_str(), FlatSamples::F32(values.clone())));
    }
    let mut layer_attributes = LayerAttributes {
        layer_position: Vec2(image.data_origin.0, image.data_origin.1),
        ..LayerAttributes::default()
    };
    let mut chromaticities = None;
    for (name, value) in &image.attributes {
        let n = name.as_str();
        match value {
            HeaderValue::Text(t) if STANDARD_TEXT.contains(&n) => {
                let text = Some(exr_text(t));
                match n {
                    "owner" => layer_attributes.owner = text,
                    "comments" => layer_attributes.comments = text,
                    "capDate" => layer_attributes.capture_date = text,
                    _ => layer_attributes.software_name = text,
                }
            }
            HeaderValue::Float(v) if STANDARD_FLOAT.contains(&n) => match n {
                "focus" => layer_attributes.focus = Some(*v),
                "expTime" => layer_attributes.exposure = Some(*v),
                "aperture" => layer_attributes.aperture = Some(*v),
                "isoSpeed" => layer_attributes.iso_speed = Some(*v),
                _ => layer_attributes.utc_offset = Some(*v),
            },
            HeaderValue::Matrix(m) if STANDARD_MATRIX.contains(&n) => match n {
                "worldToCamera" => layer_attributes.world_to_camera = Some(*m),
                _ => layer_attributes.world_to_normalized_device = Some(*m),
            },
            HeaderValue::Chromaticities(c) if n == "chromaticities" => chromaticities = Some(*c),
            other => {
                layer_attributes.other.insert(exr_text(name), exr_value(other));
            }
        }
    }
    let layer = Layer::new(
        (image.width as usize, image.height as usize),
        layer_attributes,
        // Blocks in increasing order: exr compresses them in parallel, and in
        // the order they finish the file's bytes would differ from run to run.
        Encoding {
            line_order: LineOrder::Increasing,
            ..Encoding::FAST_LOSSLESS
        },
        AnyChannels::sort(list),
    );
    let mut exr_image = exr::image::Image::from_layer(layer);
    exr_image.attributes.display_window =
        IntegerBounds::new((0, 0), (image.display_size.0 as usize, image.display_size.1 as usize));
    exr_image.attributes.chromaticities = chromaticities.map(to_exr_chromaticities);
    let mut out = std::io::Cursor::new(Vec::new());
    exr_image
        .write()
        .to_buffered(&mut out)
        .map_err(|e| invalid(e.to_string()))?;
    let mut bytes = out.into_inner();
    sort_header_attributes(&mut bytes);
    Ok(bytes)
}

/// Writes `image` to `path` atomically.
pub fn write_exr(path: &Path, image: &ExrImage) -> Result<()> {
    let bytes = encode_exr(image)?;
    write_atomically(path, |tmp| std::fs::write(tmp, &bytes).map_err(|e| io_error(tmp, e)))
}

/// Reads the first layer of an EXR file: every channel as 32-bit floats, the
/// windows, and the attributes lenspath knows the types of (others are skipped).
pub fn read_exr_image(path: &Path) -> Result<ExrImage> {
    use exr::prelude::read_first_flat_layer_from_file;
    let fail = |m: String| Error::Parse {
        kind: crate::FileKind::Image,
        path: path.to_path_buf(),
        message: m,
    };
    let file = read_first_flat_layer_from_file(path).map_err(|e| fail(e.to_string()))?;
    let layer = &file.layer_data;
    let (width, height) = (layer.size.0 as u32, layer.size.1 as u32);
    let channels = layer
        .channel_data
        .list
        .iter()
        .map(|c| (from_exr_text(&c.name), c.sample_data.values_as_f32().collect()))
        .collect();
    let window = file.attributes.display_window;
    if window.position != Vec2(0, 0) {
        return Err(fail(format!(
            "its display window starts at {:?}, not at (0, 0) (lenspath reads frames that start at the origin)",
            window.position
        )));
    }
    let a = &layer.attributes;
    let mut attributes = BTreeMap::new();
    let texts = [
        ("owner", &a.owner),
        ("comments", &a.comments),
        ("capDate", &a.capture_date),
        ("software", &a.software_name),
    ];
    for (name, value) in texts {
        if let Some(t) = value {
            attributes.insert(name.to_string(), HeaderValue::Text(from_exr_text(t)));
        }
    }
    let floats = [
        ("focus", a.focus),
        ("expTime", a.exposure),
        ("aperture", a.aperture),
        ("isoSpeed", a.iso_speed),
        ("utcOffset", a.utc_offset),
    ];
    for (name, value) in floats {
        if let Some(v) = value {
            attributes.insert(name.to_string(), HeaderValue::Float(v));
        }
    }
    for (name, value) in [
        ("worldToCamera", a.world_to_camera),
        ("worldToNDC", a.world_to_normalized_device),
    ] {
        if let Some(m) = value {
            attributes.insert(name.to_string(), HeaderValue::Matrix(m));
        }
    }
    if let Some(c) = &file.attributes.chromaticities {
        attributes.insert(
            "chromaticities".to_string(),
            HeaderValue::Chromaticities(from_exr_chromaticities(c)),
        );
    }
    for (name, value) in a.other.iter().chain(file.attributes.other.iter()) {
        if let Some(v) = header_value(value) {
            attributes.insert(from_exr_text(name), v);
        }
    }
    Ok(ExrImage {
        width,
        height,
        channels,
        display_size: (window.size.0 as u32, window.size.1 as u32),
        data_origin: (a.layer_position.0, a.layer_position.1),
        attributes,
    })
}

/// `text` as exr's text: its UTF-8 bytes (OpenEXR's strings are bytes; its
/// own library and Python binding read them as UTF-8).
fn exr_text(text: &str) -> Text {
    Text::from_slice_unchecked(text.as_bytes())
}

/// exr's text as a string, read as UTF-8.
fn from_exr_text(text: &Text) -> String {
    String::from_utf8_lossy(text.as_slice()).into_owned()
}

/// Red, green, blue and white xy as exr holds them.
fn to_exr_chromaticities(c: [f32; 8]) -> Chromaticities {
    Chromaticities {
        red: Vec2(c[0], c[1]),
        green: Vec2(c[2], c[3]),
        blue: Vec2(c[4], c[5]),
        white: Vec2(c[6], c[7]),
    }
}

/// exr's chromaticities as red, green, blue and white xy.
fn from_exr_chromaticities(c: &Chromaticities) -> [f32; 8] {
    [
        c.red.0, c.red.1, c.green.0, c.green.1, c.blue.0, c.blue.1, c.white.0, c.white.1,
    ]
}

/// A value as exr writes it.
fn exr_value(value: &HeaderValue) -> AttributeValue {
    match value {
        HeaderValue::Int(v) => AttributeValue::I32(*v),
        HeaderValue::Float(v) => AttributeValue::F32(*v),
        HeaderValue::Double(v) => AttributeValue::F64(*v),
        HeaderValue::Text(t) => AttributeValue::Text(exr_text(t)),
        HeaderValue::IntPair([x, y]) => AttributeValue::IntVec2(Vec2(*x, *y)),
        HeaderValue::FloatPair([x, y]) => AttributeValue::FloatVec2(Vec2(*x, *y)),
        HeaderValue::Matrix(m) => AttributeValue::Matrix4x4(*m),
        HeaderValue::Chromaticities(c) => AttributeValue::Chromaticities(to_exr_chromaticities(*c)),
    }
}

/// exr's value as lenspath's, for the types it knows.
fn header_value(value: &AttributeValue) -> Option<HeaderValue> {
    Some(match value {
        AttributeValue::I32(v) => HeaderValue::Int(*v),
        AttributeValue::F32(v) => HeaderValue::Float(*v),
        AttributeValue::F64(v) => HeaderValue::Double(*v),
        AttributeValue::Text(t) => HeaderValue::Text(from_exr_text(t)),
        AttributeValue::IntVec2(v) => HeaderValue::IntPair([v.0, v.1]),
        AttributeValue::FloatVec2(v) => HeaderValue::FloatPair([v.0, v.1]),
        AttributeValue::Matrix4x4(m) => HeaderValue::Matrix(*m),
        AttributeValue::Chromaticities(c) => HeaderValue::Chromaticities(from_exr_chromaticities(c)),
        _ => return None,
    })
}

/// Sorts a single-part EXR's header attributes by name, in place. exr keeps
/// custom attributes in a `HashMap`, whose order changes from run to run;
/// sorted, the same image gives the same bytes. The header's length does
/// not change, so the offset table after it stays right. Leaves the bytes
/// as they are if they do not parse as a header.
fn sort_header_attributes(bytes: &mut [u8]) {
    // Magic number and version field, then `name\0type\0size:i32 value` until an empty name.
    let mut at = 8;
    let mut attributes: Vec<(usize, usize)> = Vec::new();
    let nul_after = |from: usize| bytes.get(from..)?.iter().position(|&b| b == 0).map(|i| from + i);
    loop {
        let Some(name_end) = nul_after(at) else { return };
        if name_end == at {
            break;
        }
        let Some(type_end) = nul_after(name_end + 1) else {
            return;
        };
        let Some(size) = bytes
            .get(type_end + 1..type_end + 5)
            .map(|s| i32::from_le_bytes([s[0], s[1], s[2], s[3]]))
        else {
            return;
        };
        let end = type_end + 5 + size.max(0) as usize;
        if end > bytes.len() {
            return;
        }
        attributes.push((at, end));
        at = end;
    }
    let Some(&(start, _)) = attributes.first() else { return };
    let name = |&(s, _): &(usize, usize)| {
        let end = bytes[s..].iter().position(|&b| b == 0).unwrap_or(0);
        bytes[s..s + end].to_vec()
    };
    let mut sorted = attributes.clone();
    sorted.sort_by_key(name);
    let header: Vec<u8> = sorted.iter().flat_map(|&(s, e)| bytes[s..e].to_vec()).collect();
    bytes[start..start + header.len()].copy_from_slice(&header);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> ExrImage {
        let mut image = ExrImage::new(3, 2);
        image.channels.insert("R".into(), vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0]);
        image.channels.insert("Z".into(), vec![f32::INFINITY; 6]);
        image.display_size = (8, 6);
        image.data_origin = (4, 1);
        for (name, value) in [
            ("owner", HeaderValue::Text("me".into())),
            ("focus", HeaderValue::Float(2.5)),
            ("worldToCamera", HeaderValue::Matrix(std::array::from_fn(|i| i as f32))),
            ("lenspath/spp", HeaderValue::Int(64)),
            ("lenspath/integrator", HeaderValue::Text("path".into())),
            ("lenspath/pair", HeaderValue::IntPair([1, -2])),
            ("lenspath/double", HeaderValue::Double(0.1)),
            ("lenspath/floats", HeaderValue::FloatPair([0.5, 0.25])),
        ] {
            image.attributes.insert(name.into(), value);
        }
        image
    }

    #[test]
    fn an_exr_reads_back_as_written_and_its_bytes_do_not_depend_on_the_run() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.exr");
        let image = sample();
        write_exr(&path, &image).unwrap();
        assert_eq!(read_exr_image(&path).unwrap(), image);
        // Several custom attributes: exr's HashMap order would vary between
        // maps; sorted, every encoding gives the same bytes.
        let first = encode_exr(&image).unwrap();
        for _ in 0..8 {
            assert_eq!(encode_exr(&image.clone()).unwrap(), first);
        }
    }

    #[test]
    fn sorting_the_header_keeps_the_pixels_readable() {
        let image = sample();
        let bytes = encode_exr(&image).unwrap();
        let names: Vec<String> = {
            let mut at = 8;
            let mut names = Vec::new();
            while bytes[at] != 0 {
                let n = bytes[at..].iter().position(|&b| b == 0).unwrap();
                names.push(String::from_utf8_lossy(&bytes[at..at + n]).into_owned());
                let t = at + n + 1 + bytes[at + n + 1..].iter().position(|&b| b == 0).unwrap();
                let size = i32::from_le_bytes(bytes[t + 1..t + 5].try_into().unwrap()) as usize;
                at = t + 5 + size;
            }
            names
        };
        let mut sorted = names.clone();
        sorted.sort();
        assert_eq!(names, sorted);
        assert!(names.contains(&"dataWindow".to_string()) && names.contains(&"lenspath/spp".to_string()));
    }

    #[test]
    fn bad_channels_are_refused_and_text_is_utf8() {
        let mut image = sample();
        image.channels.insert("G".into(), vec![0.0; 5]);
        let err = encode_exr(&image).unwrap_err().to_string();
        assert!(err.contains("channel 'G' holds 5 values for 6 pixels"), "{err}");
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("λ.exr");
        let mut image = sample();
        image
            .attributes
            .insert("comments".into(), HeaderValue::Text("λ = 550 nm, Ø 50 mm".into()));
        image
            .attributes
            .insert("lenspath/scene".into(), HeaderValue::Text("сцена.toml".into()));
        write_exr(&path, &image).unwrap();
        assert_eq!(read_exr_image(&path).unwrap(), image);
    }
}
