//! Developing a raw frame into an image: black level off and scaled to the
//! white level, bilinear demosaicking, the colour matrix back to CIE XYZ
//! and on to linear sRGB. The scene's white under D65 lands on sRGB white
//! (the DNG colour model: `ColorMatrix1` maps XYZ to the camera under D65,
//! Adobe DNG Specification 1.4, ch. 6).

use glam::{DVec3, Vec3};

use super::{Cfa, RawFrame};
use crate::film::Image;
use crate::spectrum::cie;

/// `frame` developed to linear sRGB, 1 at the white level.
pub fn develop(frame: &RawFrame) -> Image {
    let (w, h) = (frame.width as usize, frame.height as usize);
    let range = f64::from(frame.white_level_dn - frame.black_level_dn);
    let signal: Vec<f64> = frame
        .dn
        .iter()
        .map(|&v| (f64::from(v) - f64::from(frame.black_level_dn)) / range)
        .collect();
    let tables = cie::tables();
    let camera_to_xyz = frame.xyz_to_camera.inverse();
    let mut rgb = Vec::with_capacity(3 * w * h);
    for y in 0..h {
        for x in 0..w {
            let srgb: Vec3 = if frame.cfa == Cfa::Mono {
                // One channel: grey, white where the neutral's green is.
                Vec3::splat((signal[y * w + x] / frame.neutral.y) as f32)
            } else {
                let camera = DVec3::from_array([0, 1, 2].map(|c| bilinear(frame, &signal, x, y, c)));
                tables.xyz_to_rgb((camera_to_xyz * camera).as_vec3())
            };
            rgb.extend_from_slice(&srgb.to_array());
        }
    }
    Image {
        width: frame.width,
        height: frame.height,
        rgb,
        depth: vec![f32::INFINITY; w * h],
        spp_min: 0,
        spp_requested: 0,
    }
}

/// Channel `c` at pixel (`x`, `y`): its own reading where the filter passes
/// `c`, else the mean of the nearest neighbours that read it (the 3 × 3
/// pixels around it hold one or more of each Bayer channel).
fn bilinear(frame: &RawFrame, signal: &[f64], x: usize, y: usize, c: usize) -> f64 {
    let (w, h) = (frame.width as usize, frame.height as usize);
    let reads = |x: usize, y: usize| frame.cfa.channel(x as u32, y as u32) == c;
    if reads(x, y) {
        return signal[y * w + x];
    }
    let (mut sum, mut n) = (0.0, 0);
    // Edge neighbours first (a green site's red and blue, a red site's
    // greens), the corners only when no edge neighbour reads `c`.
    for ring in [
        &[(0, -1), (-1, 0), (1, 0), (0, 1)][..],
        &[(-1, -1), (1, -1), (-1, 1), (1, 1)][..],
    ] {
        for (dx, dy) in ring {
            let (nx, ny) = (x as i64 + dx, y as i64 + dy);
            if nx < 0 || ny < 0 || nx >= w as i64 || ny >= h as i64 {
                continue;
            }
            if reads(nx as usize, ny as usize) {
                sum += signal[ny as usize * w + nx as usize];
                n += 1;
            }
        }
        if n > 0 {
            return sum / f64::from(n);
        }
    }
    0.0
}
