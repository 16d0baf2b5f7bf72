//! The film: pixel reconstruction filters and the finished image.
//!
//! Filters are applied by importance sampling (pbrt-v4 §8.8): each sample's
//! offset from its pixel centre is drawn from the filter itself, so every
//! sample lands in exactly one pixel with weight 1 and a pixel is the plain
//! mean of its samples. Tiles never share pixels, which keeps renders
//! bit-identical for any thread count and tile order.

use glam::Vec2;

use crate::sampling::{erf, erf_inv};

/// A pixel reconstruction filter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Filter {
    /// Box of radius 0.5 pixel: each pixel averages its own area.
    Box,
    /// Gaussian truncated at `radius` pixels.
    Gaussian {
        /// Standard deviation in pixels (pbrt's default 0.5).
        sigma: f32,
        /// Truncation radius in pixels (pbrt's default 1.5).
        radius: f32,
    },
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
}
