//! Colour encodings: the sRGB transfer function both ways, and a linear
//! image as 8-bit sRGB (what PNG and JPEG output and the viewer's frames
//! hold). The image formats themselves are in `io::image`.

use crate::film::Image;

/// Relative luminance Y of a linear sRGB colour: the Y row of the sRGB
/// (Rec. 709 primaries, D65) to CIE XYZ matrix, IEC 61966-2-1.
pub fn luminance(rgb: [f32; 3]) -> f32 {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
}

/// The sRGB transfer function (IEC 61966-2-1) from linear to encoded.
pub fn linear_to_srgb(x: f32) -> f32 {
    if x <= 0.003_130_8 {
        12.92 * x.max(0.0)
    } else {
        1.055 * x.min(1.0).powf(1.0 / 2.4) - 0.055
    }
}

/// The sRGB transfer function (IEC 61966-2-1) from encoded to linear.
pub fn srgb_to_linear(x: f32) -> f32 {
    if x <= 0.040_45 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

/// 8-bit sRGB bytes of the image after an exposure of `exposure` stops.
pub fn to_srgb8(image: &Image, exposure: f32) -> Vec<u8> {
    let scale = exposure.exp2();
    image
        .rgb
        .iter()
        .map(|&v| (linear_to_srgb(v * scale) * 255.0 + 0.5).clamp(0.0, 255.0) as u8)
        .collect()
}
