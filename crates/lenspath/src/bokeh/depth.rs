//! Depth-aware lens blur: each pixel blurred by its own circle of confusion,
//! in the aperture's shape, without the classic artefacts of doing it per
//! pixel (docs/bokeh.md).
//!
//! The method is layered scatter: the signed circle of confusion (CoC)
//! splits the image into depth layers (a pixel between two layer radii is
//! shared between them by linear weights, so nothing bands). Each layer's
//! premultiplied colour αI and coverage α are convolved with the aperture
//! kernel of its radius, and the layers are composited back to front with
//! the *over* operator. So a sharp foreground never bleeds into the blurred
//! background behind it (the background layer is blurred without it), and
//! a blurred foreground spreads over the sharp background (its coverage
//! spreads with its colour). What the foreground hid is not in the image:
//! where the final coverage is below 1 the colour is renormalised by it,
//! which extends the nearby layers into the gap.

use rayon::prelude::*;

use super::convolve::{convolve_planes, Edges, Method};
use super::kernel::Kernel;
use crate::camera::Aperture;
use crate::error::{Error, Result};

/// The thin-lens circle of confusion in pixels: a point at distance z images
/// as a disc of signed diameter c(z) = A · s · (1/D − 1/z), A the aperture
/// diameter and D the focus distance (in any one unit), s the lens-to-sensor
/// distance in pixels. Positive beyond the focus plane, negative before it.
/// (Potmesil and Chakravarty 1981; pbrt's thin lens gives the same.)
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CircleOfConfusion {
    /// Aperture diameter, in the unit of the distances.
    pub aperture_diameter: f64,
    /// Focus distance D, in the unit of the distances.
    pub focus_distance: f64,
    /// Lens-to-sensor distance in pixels.
    pub sensor_distance_px: f64,
}

impl CircleOfConfusion {
    /// A real thin lens: focal length and f-number, focused at
    /// `focus_distance_mm`, on a sensor `sensor_width_mm` wide imaged by
    /// `width_px` pixels; distances in mm.
    pub fn thin_lens(
        focal_length_mm: f64,
        f_number: f64,
        focus_distance_mm: f64,
        sensor_width_mm: f64,
        width_px: u32,
    ) -> Result<CircleOfConfusion> {
        let positive = |v: f64| v > 0.0 && v.is_finite();
        if !(positive(focal_length_mm) && positive(f_number) && positive(sensor_width_mm)) {
            return Err(Error::InvalidArgument(format!(
                "focal length ({focal_length_mm} mm), f-number ({f_number}) and sensor width ({sensor_width_mm} mm) must be positive"
            )));
        }
        if !(focus_distance_mm > focal_length_mm && focus_distance_mm.is_finite()) {
            return Err(Error::InvalidArgument(format!(
                "a {focal_length_mm} mm lens cannot focus at {:.4} m (closer than its focal length)",
                focus_distance_mm / 1e3
            )));
        }
        // The Gaussian lens equation: 1/s = 1/f − 1/D.
        let sensor_distance_mm = focal_length_mm * focus_distance_mm / (focus_distance_mm - focal_length_mm);
        Ok(CircleOfConfusion {
            aperture_diameter: focal_length_mm / f_number,
            focus_distance: focus_distance_mm,
            sensor_distance_px: sensor_distance_mm * f64::from(width_px) / sensor_width_mm,
        })
    }

    /// [`CircleOfConfusion::thin_lens`] for depths in scene units of
    /// `scene_unit_m` metres: `focus_distance` in scene units too.
    pub fn thin_lens_in_scene_units(
        focal_length_mm: f64,
        f_number: f64,
        focus_distance: f64,
        scene_unit_m: f64,
        sensor_width_mm: f64,
        width_px: u32,
    ) -> Result<CircleOfConfusion> {
        if !(scene_unit_m > 0.0 && scene_unit_m.is_finite()) {
            return Err(Error::InvalidArgument(format!(
                "the scene unit must be a positive number of metres, got {scene_unit_m}"
            )));
        }
        let mm = scene_unit_m * 1e3;
        let coc = CircleOfConfusion::thin_lens(
            focal_length_mm,
            f_number,
            focus_distance * mm,
            sensor_width_mm,
            width_px,
        )?;
        // The depths stay in scene units: scale the lens's lengths instead.
        Ok(CircleOfConfusion {
            aperture_diameter: coc.aperture_diameter / mm,
            focus_distance,
            ..coc
        })
    }

    /// The thin-lens camera of pbrt and lenspath (`--camera thin-lens`):
    /// aperture radius and focus distance in scene units, vertical field of
    /// view, image height in pixels.
    pub fn thin_lens_camera(
        aperture_radius: f64,
        focus_distance: f64,
        fov_y_deg: f64,
        height_px: u32,
    ) -> Result<CircleOfConfusion> {
        if !(aperture_radius >= 0.0 && focus_distance > 0.0 && fov_y_deg > 0.0 && fov_y_deg < 180.0) {
            return Err(Error::InvalidArgument(format!(
                "aperture radius ({aperture_radius}) must be at least 0, focus distance ({focus_distance}) positive, field of view ({fov_y_deg}°) between 0 and 180"
            )));
        }
        Ok(CircleOfConfusion {
            aperture_diameter: 2.0 * aperture_radius,
            focus_distance,
            sensor_distance_px: 0.5 * f64::from(height_px) / (0.5 * fov_y_deg.to_radians()).tan(),
        })
    }

    /// Signed diameter in pixels of the blur of a point at `distance`
    /// (infinite: the limit, A·s/D).
    pub fn diameter_px(&self, distance: f64) -> f64 {
        let inverse = if distance.is_finite() {
            1.0 / distance.max(1e-12)
        } else {
            0.0
        };
        self.aperture_diameter * self.sensor_distance_px * (1.0 / self.focus_distance - inverse)
    }
}

/// Radii (pixels) of the depth layers on the positive side: 0, then steps
/// of at most one pixel or a quarter of the radius, up to `max`.
fn layer_radii(max: f64) -> Vec<f64> {
    let mut radii = vec![0.0];
    let mut r = 1.0f64;
    while radii.last().copied().unwrap_or(0.0) < max {
        radii.push(r.min(max.max(1.0)));
        r = (r + 1.0).max(1.25 * r);
    }
    radii
}

/// Blurs `rgb` (`width`×`height`, 3 floats a pixel, linear) by the circle of
/// confusion each pixel's `depth` gives, in `aperture`'s shape (turned by
/// 180° for the foreground, as a real lens turns it).
pub fn depth_blur(
    rgb: &[f32],
    depth: &[f32],
    width: usize,
    height: usize,
    coc: &CircleOfConfusion,
    aperture: &Aperture,
) -> Result<Vec<f32>> {
    let n = width * height;
    if rgb.len() != 3 * n || depth.len() != n {
        return Err(Error::InvalidArgument(format!(
            "a {width}x{height} image needs {} colour values and {n} depths, got {} and {}",
            3 * n,
            rgb.len(),
            depth.len()
        )));
    }
    if let Some(bad) = depth.iter().find(|z| z.is_nan() || **z <= 0.0) {
        return Err(Error::InvalidArgument(format!(
            "depths must be positive (or infinite), found {bad}"
        )));
    }
    // Signed blur radius of every pixel, and the layers spanning them.
    let radius: Vec<f64> = depth.par_iter().map(|&z| 0.5 * coc.diameter_px(f64::from(z))).collect();
    let (low, high) = radius.iter().fold((0f64, 0f64), |(lo, hi), &r| (lo.min(r), hi.max(r)));
    let mut layers: Vec<f64> = layer_radii(-low).into_iter().skip(1).map(|r| -r).collect();
    layers.extend(layer_radii(high));
    layers.sort_by(|a, b| b.total_cmp(a)); // back (largest) to front
    layers.dedup();

    let mut colour = vec![0f32; 3 * n];
    let mut coverage = vec![0f32; n];
    for (k, &centre) in layers.iter().enumerate() {
        // Hat weights between this layer's neighbours on the radius axis.
        let (farther, nearer) = (k.checked_sub(1).map(|i| layers[i]), layers.get(k + 1).copied());
        let weight = |r: f64| -> f32 {
            let w = if r >= centre {
                farther.map_or(1.0, |f| (f - r) / (f - centre))
            } else {
                nearer.map_or(1.0, |m| (r - m) / (centre - m))
            };
            w.clamp(0.0, 1.0) as f32
        };
        let alpha: Vec<f32> = radius.par_iter().map(|&r| weight(r)).collect();
        let Some(bounds) = Bounds::of(&alpha, width) else {
            continue;
        };
        let diameter = 2.0 * centre.abs();
        let kernel = if diameter < 1.0 {
            Kernel::identity()
        } else if centre < 0.0 {
            Kernel::from_aperture(aperture, diameter).rotated_180()
        } else {
            Kernel::from_aperture(aperture, diameter)
        };
        // Only the layer's bounding box, grown by the kernel's reach, is convolved.
        let window = bounds.grown(kernel.width / 2, kernel.height / 2, width, height);
        let (ww, wh) = (window.x1 - window.x0, window.y1 - window.y0);
        let mut planes = vec![vec![0f32; ww * wh]; 4];
        for y in 0..wh {
            for x in 0..ww {
                let i = (window.y0 + y) * width + window.x0 + x;
                let a = alpha[i];
                for c in 0..3 {
                    planes[c][y * ww + x] = a * rgb[3 * i + c];
                }
                planes[3][y * ww + x] = a;
            }
        }
        let blurred = convolve_planes(&planes, ww, wh, &kernel, Method::Auto, Edges::Black);
        // Over: the layer in front of what is behind it.
        for y in 0..wh {
            for x in 0..ww {
                let (j, i) = (y * ww + x, (window.y0 + y) * width + window.x0 + x);
                let a = blurred[3][j].clamp(0.0, 1.0);
                for c in 0..3 {
                    colour[3 * i + c] = blurred[c][j] + (1.0 - a) * colour[3 * i + c];
                }
                coverage[i] = a + (1.0 - a) * coverage[i];
            }
        }
    }
    // What no layer covered fully is renormalised by its coverage.
    colour.par_chunks_mut(3).zip(coverage.par_iter()).for_each(|(px, &a)| {
        if a > 1e-6 {
            for v in px {
                *v /= a;
            }
        }
    });
    Ok(colour)
}

/// A pixel rectangle [x0, x1) × [y0, y1).
#[derive(Clone, Copy, Debug)]
struct Bounds {
    x0: usize,
    y0: usize,
    x1: usize,
    y1: usize,
}

impl Bounds {
    /// The bounding box of the non-zero values of a `width`-wide plane.
    fn of(plane: &[f32], width: usize) -> Option<Bounds> {
        let mut b: Option<Bounds> = None;
        for (i, _) in plane.iter().enumerate().filter(|(_, &v)| v > 0.0) {
            let (x, y) = (i % width, i / width);
            b = Some(match b {
                None => Bounds {
                    x0: x,
                    y0: y,
                    x1: x + 1,
                    y1: y + 1,
                },
                Some(b) => Bounds {
                    x0: b.x0.min(x),
                    y0: b.y0.min(y),
                    x1: b.x1.max(x + 1),
                    y1: b.y1.max(y + 1),
                },
            });
        }
        b
    }

    fn grown(self, dx: usize, dy: usize, width: usize, height: usize) -> Bounds {
        Bounds {
            x0: self.x0.saturating_sub(dx),
            y0: self.y0.saturating_sub(dy),
            x1: (self.x1 + dx).min(width),
            y1: (self.y1 + dy).min(height),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bokeh::convolve_rgb;
    use crate::camera::ApertureShape;

    const W: usize = 64;
    const H: usize = 48;

    fn circle() -> Aperture {
        Aperture::new(&ApertureShape::Circle).unwrap()
    }

    /// Blur diameter 16 px at distance 4 (for the test's circle of confusion,
    /// focused at 1), none at distance 1, −16 px at distance 0.5.
    fn coc() -> CircleOfConfusion {
        CircleOfConfusion {
            aperture_diameter: 1.0,
            focus_distance: 1.0,
            sensor_distance_px: 16.0 / 0.75,
        }
    }

    fn scene(square_depth: f32, background_depth: f32) -> (Vec<f32>, Vec<f32>) {
        // Red background, a green square in the middle (x, y in 24..40, 16..32).
        let inside = |i: usize| (24..40).contains(&(i % W)) && (16..32).contains(&(i / W));
        let rgb = (0..W * H)
            .flat_map(|i| if inside(i) { [0.0, 1.0, 0.0] } else { [1.0, 0.0, 0.0] })
            .collect();
        let depth = (0..W * H)
            .map(|i| if inside(i) { square_depth } else { background_depth })
            .collect();
        (rgb, depth)
    }

    #[test]
    fn thin_lens_circle_of_confusion_follows_the_lens_equation() {
        // 50 mm f/2 focused at 2 m, 36 mm sensor over 3600 px (10 µm pixels):
        // a point at infinity blurs to A·s/D = 25 mm · 51.28 mm / 2000 mm = 0.641 mm = 64.1 px.
        let c = CircleOfConfusion::thin_lens(50.0, 2.0, 2000.0, 36.0, 3600).unwrap();
        assert!(
            (c.diameter_px(f64::INFINITY) - 64.1).abs() < 0.1,
            "{}",
            c.diameter_px(f64::INFINITY)
        );
        assert!(c.diameter_px(2000.0).abs() < 1e-9);
        assert!(c.diameter_px(1000.0) < 0.0);
        assert!(CircleOfConfusion::thin_lens(50.0, 2.0, 40.0, 36.0, 100).is_err());
    }

    /// One depth whose blur radius is a layer's: the same as convolving the
    /// whole image with that kernel, edges renormalised.
    #[test]
    fn a_single_depth_is_a_plain_convolution() {
        let (rgb, _) = scene(4.0, 4.0);
        let depth = vec![4.0; W * H];
        let out = depth_blur(&rgb, &depth, W, H, &coc(), &circle()).unwrap();
        let kernel = Kernel::from_aperture(&circle(), 16.0);
        let mut expected = rgb.clone();
        convolve_rgb(&mut expected, W, H, &kernel, Method::Direct, Edges::Renormalize);
        for i in 0..W * H {
            for c in 0..3 {
                assert!((out[3 * i + c] - expected[3 * i + c]).abs() < 1e-4, "pixel {i}");
            }
        }
    }

    /// A sharp square in front of a blurred background does not bleed into it.
    #[test]
    fn a_sharp_foreground_does_not_bleed_into_the_background() {
        let (rgb, depth) = scene(1.0, 4.0);
        let out = depth_blur(&rgb, &depth, W, H, &coc(), &circle()).unwrap();
        let at = |x: usize, y: usize| &out[3 * (y * W + x)..3 * (y * W + x) + 3];
        // Just outside the square: red only; inside: still sharp green.
        for (x, y) in [(22, 24), (41, 24), (32, 14), (32, 33)] {
            assert!(
                at(x, y)[1] < 1e-3 && (at(x, y)[0] - 1.0).abs() < 1e-3,
                "({x}, {y}): {:?}",
                at(x, y)
            );
        }
        assert!((at(25, 17)[1] - 1.0).abs() < 1e-3, "{:?}", at(25, 17));
    }

    /// A blurred square in front of a sharp background spreads over it.
    #[test]
    fn a_blurred_foreground_covers_the_sharp_background() {
        let (rgb, depth) = scene(0.5, 1.0);
        let out = depth_blur(&rgb, &depth, W, H, &coc(), &circle()).unwrap();
        let at = |x: usize, y: usize| &out[3 * (y * W + x)..3 * (y * W + x) + 3];
        // 3 px outside the square's edge (the blur reaches 8): partly green.
        let outside = at(20, 24);
        assert!(outside[1] > 0.2 && outside[0] < 0.8, "{outside:?}");
        // Far from the square the background stays sharp red.
        assert!((at(2, 2)[0] - 1.0).abs() < 1e-4 && at(2, 2)[1].abs() < 1e-4);
    }
}
