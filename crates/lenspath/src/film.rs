//! The film: pixel reconstruction filters and the finished image.
//!
//! Filters are applied by importance sampling (pbrt-v4 §8.8): each sample's
//! offset from its pixel centre is drawn from the filter itself, so every
//! sample lands in exactly one pixel with weight 1 and a pixel is the plain
//! mean of its samples. Tiles never share pixels, which keeps renders
//! bit-identical for any thread count and tile order.

use glam::Vec2;

use crate::error::{Error, Result};
use crate::names::Named;
use crate::sampling::{erf, erf_inv};

/// The light a camera's film reading stands for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilmRadiometry {
    /// Sensor irradiance per unit scene radiance that a reading of 1
    /// stands for, sr (π/(4N²) on the axis of a lens at f-number N focused
    /// at infinity: the camera equation, Slater, *Remote Sensing*, 1980).
    pub irradiance_per_reading_sr: f64,
    /// Pixel pitch (width, height), µm: the sensor's size over the image's.
    pub pixel_pitch_um: (f64, f64),
}

impl FilmRadiometry {
    /// A pixel's area, µm².
    pub fn pixel_area_um2(&self) -> f64 {
        self.pixel_pitch_um.0 * self.pixel_pitch_um.1
    }
}

/// A pixel reconstruction filter.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Filter {
    /// Box of radius 0.5 pixel: each pixel averages its own area.
    #[default]
    Box,
    /// Gaussian truncated at `radius` pixels.
    Gaussian {
        /// Standard deviation in pixels (pbrt's default 0.5).
        sigma: f32,
        /// Truncation radius in pixels (pbrt's default 1.5).
        radius: f32,
    },
}

impl Named for Filter {
    const WHAT: &'static str = "filter";
    const NAMED: &'static [(Filter, &'static str)] = &[(Filter::Box, "box"), (Filter::GAUSSIAN, "gaussian")];
}

impl Filter {
    /// pbrt's default Gaussian.
    pub const GAUSSIAN: Filter = Filter::Gaussian {
        sigma: 0.5,
        radius: 1.5,
    };

    /// Offset from the pixel centre, in pixels, distributed as the filter.
    #[inline]
    pub fn sample_offset(&self, u: Vec2) -> Vec2 {
        match *self {
            Filter::Box => u - Vec2::splat(0.5),
            Filter::Gaussian { sigma, radius } => {
                let s = sigma * std::f32::consts::SQRT_2;
                let edge = erf(radius / s);
                let inv = |u: f32| (s * erf_inv(edge * (2.0 * u - 1.0))).clamp(-radius, radius);
                Vec2::new(inv(u.x), inv(u.y))
            }
        }
    }

    /// Density, per pixel², of [`Filter::sample_offset`] at `offset`: the
    /// filter normalised to integrate to 1, which is also a sample's weight
    /// toward the pixel at that offset.
    #[inline]
    pub fn pdf(&self, offset: Vec2) -> f32 {
        match *self {
            Filter::Box => {
                let inside = offset.x.abs() <= 0.5 && offset.y.abs() <= 0.5;
                f32::from(u8::from(inside))
            }
            Filter::Gaussian { sigma, radius } => {
                if offset.x.abs() > radius || offset.y.abs() > radius {
                    return 0.0;
                }
                // A normal density per axis, renormalised to its truncation.
                let s = sigma * std::f32::consts::SQRT_2;
                let axis_mass = erf(radius / s) * sigma * (2.0 * std::f32::consts::PI).sqrt();
                (-offset.length_squared() / (2.0 * sigma * sigma)).exp() / (axis_mass * axis_mass)
            }
        }
    }
}

/// A rendered image: linear RGB, the camera depth of each pixel, and the
/// samples per pixel it holds.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear RGB, row-major from the top-left, 3 floats per pixel.
    pub rgb: Vec<f32>,
    /// Distance along the camera's viewing axis to the surface seen through
    /// each pixel centre (infinite where nothing is hit).
    pub depth: Vec<f32>,
    /// Fewest samples any pixel received.
    pub spp_min: u32,
    /// Samples per pixel that were asked for.
    pub spp_requested: u32,
}

impl Image {
    /// Pixel `(x, y)` as RGB.
    pub fn pixel(&self, x: u32, y: u32) -> [f32; 3] {
        let i = 3 * (y as usize * self.width as usize + x as usize);
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }

    /// Mean of all pixels, per channel.
    pub fn mean(&self) -> [f64; 3] {
        let mut sum = [0f64; 3];
        for px in self.rgb.chunks_exact(3) {
            for c in 0..3 {
                sum[c] += f64::from(px[c]);
            }
        }
        let n = (self.width as usize * self.height as usize).max(1) as f64;
        sum.map(|s| s / n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    #[test]
    fn gaussian_offsets_have_the_filter_variance() {
        let f = Filter::Gaussian {
            sigma: 0.5,
            radius: 3.0,
        };
        let mut rng = Rng::new(3);
        let n = 200_000;
        let mut var = 0.0f64;
        for _ in 0..n {
            let o = f.sample_offset(Vec2::new(rng.uniform(), rng.uniform()));
            assert!(o.abs().max_element() <= 3.0);
            var += f64::from(o.x * o.x);
        }
        assert!((var / n as f64 - 0.25).abs() < 0.005, "variance {}", var / n as f64);
        let b = Filter::Box.sample_offset(Vec2::new(0.0, 0.999));
        assert!(b.x == -0.5 && b.y < 0.5);
    }

    /// Each filter's density integrates to 1 and matches a histogram of its
    /// sampled offsets.
    #[test]
    fn filter_pdf_is_the_density_of_its_offsets() {
        for filter in [Filter::Box, Filter::GAUSSIAN] {
            let (lo, step) = (-1.6f32, 0.02f32);
            let n = (-2.0 * lo / step) as usize;
            let cell = |i: usize| lo + (i as f32 + 0.5) * step;
            let integral: f32 = (0..n * n)
                .map(|k| filter.pdf(Vec2::new(cell(k % n), cell(k / n))) * step * step)
                .sum();
            assert!((integral - 1.0).abs() < 2e-3, "{filter:?} integrates to {integral}");
            // The share of offsets within 0.25 pixel of the centre.
            let mut rng = Rng::new(5);
            let samples = 200_000;
            let near = (0..samples)
                .filter(|_| {
                    filter
                        .sample_offset(Vec2::new(rng.uniform(), rng.uniform()))
                        .abs()
                        .max_element()
                        < 0.25
                })
                .count() as f32
                / samples as f32;
            let m = (0.5 / step) as usize;
            let predicted: f32 = (0..m * m)
                .map(|k| {
                    filter.pdf(Vec2::new(
                        -0.25 + (k % m) as f32 * step + 0.5 * step,
                        -0.25 + (k / m) as f32 * step + 0.5 * step,
                    )) * step
                        * step
                })
                .sum();
            assert!(
                (near - predicted).abs() < 5e-3,
                "{filter:?}: {near} sampled, {predicted} from the pdf"
            );
        }
    }
}

/// A rectangle in fractions of the image (0 to 1): the top-left corner `x`,
/// `y` and the size; how autofocus patches are given, whatever the resolution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalizedRect {
    /// Left edge, fraction of the width.
    pub x: f64,
    /// Top edge, fraction of the height.
    pub y: f64,
    /// Width, fraction of the image's.
    pub width: f64,
    /// Height, fraction of the image's.
    pub height: f64,
}

impl NormalizedRect {
    /// The rectangle, checked to be non-empty and inside the image.
    pub fn new(x: f64, y: f64, width: f64, height: f64) -> Result<Self> {
        let inside =
            x >= 0.0 && y >= 0.0 && width > 0.0 && height > 0.0 && x + width <= 1.0 + 1e-9 && y + height <= 1.0 + 1e-9;
        if !inside {
            return Err(Error::InvalidArgument(format!(
                "a patch is X,Y,WIDTH,HEIGHT as fractions of the image, inside it, such as \
                 0.55,0.7,0.1,0.12; got {x},{y},{width},{height}"
            )));
        }
        Ok(NormalizedRect { x, y, width, height })
    }

    /// The pixels it covers in a `width` × `height` image (at least 3 × 3).
    pub fn to_pixels(self, width: u32, height: u32) -> PixelRect {
        let (w, h) = (f64::from(width), f64::from(height));
        let x0 = ((self.x * w).round() as u32).min(width.saturating_sub(3));
        let y0 = ((self.y * h).round() as u32).min(height.saturating_sub(3));
        PixelRect {
            x0,
            y0,
            width: ((self.width * w).round() as u32).clamp(3, width - x0),
            height: ((self.height * h).round() as u32).clamp(3, height - y0),
        }
    }
}

/// A rectangle of pixels: columns `x0..x0 + width`, rows `y0..y0 + height`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelRect {
    /// First column.
    pub x0: u32,
    /// First row.
    pub y0: u32,
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
}
