//! `lenspath render --guide-map FILE --guide-at X,Y`: the picture of what a
//! guided render's guide learned at one pixel's surface
//! ([`lenspath::guiding::map::DensityMap`]), as a false-colour PNG or an EXR
//! of the density itself.

use std::path::Path;

use lenspath::color::srgb_to_linear;
use lenspath::error::Result;
use lenspath::film::Image;
use lenspath::guiding::map::DensityMap;
use lenspath::io::exr::{write_exr, ExrImage};
use lenspath::io::image::{write_image, ImageFormat};

/// Edge of the written map, in pixels.
pub const MAP_SIZE: u32 = 256;

/// Writes `map` to `path`: an EXR holds the density per steradian in its
/// `Y` channel (0 outside the disc); a PNG shows it in false colour,
/// brightness following the square root of the density over its maximum
/// (so weak lobes show beside a strong one), the disc's outside grey and
/// the surface's horizon a grey circle.
pub fn write_guide_map(path: &Path, map: &DensityMap) -> Result<()> {
    let size = map.size;
    match ImageFormat::from_path(path)? {
        ImageFormat::Exr => {
            let mut exr = ExrImage::new(size, size);
            exr.channels.insert("Y".into(), map.density_per_sr.clone());
            write_exr(path, &exr)
        }
        ImageFormat::Png => {
            let max = map.max_density_per_sr().max(f32::MIN_POSITIVE);
            let mut rgb = Vec::with_capacity(3 * map.density_per_sr.len());
            for (i, &density) in map.density_per_sr.iter().enumerate() {
                let (point, pixel) = map.disc_point(i);
                let rho = point.length();
                let srgb = if (rho - 2f32.sqrt()).abs() < 0.75 * pixel {
                    [0.75; 3]
                } else if rho > 2.0 {
                    [0.35; 3]
                } else {
                    heat((density / max).sqrt())
                };
                rgb.extend(srgb.map(srgb_to_linear));
            }
            let image = Image {
                width: size,
                height: size,
                rgb,
                depth: vec![f32::INFINITY; (size * size) as usize],
                spp_min: 0,
                spp_requested: 0,
            };
            write_image(path, &image, 0.0)
        }
    }
}

/// A black–purple–red–yellow–white colour scale, sRGB-encoded, for `t` in
/// [0, 1].
fn heat(t: f32) -> [f32; 3] {
    const STOPS: [[f32; 3]; 5] = [
        [0.0, 0.0, 0.0],
        [0.35, 0.05, 0.55],
        [0.9, 0.15, 0.15],
        [1.0, 0.8, 0.1],
        [1.0, 1.0, 1.0],
    ];
    let x = t.clamp(0.0, 1.0) * (STOPS.len() - 1) as f32;
    let i = (x as usize).min(STOPS.len() - 2);
    let f = x - i as f32;
    std::array::from_fn(|c| STOPS[i][c] + f * (STOPS[i + 1][c] - STOPS[i][c]))
}
