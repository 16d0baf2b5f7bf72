//! A picture of what a guide learned at one point: its density over the
//! whole sphere of directions, in the Lambert azimuthal equal-area
//! projection centred on the surface normal (Snyder 1987, "Map
//! Projections: A Working Manual", USGS Professional Paper 1395, §24).
//!
//! The projection keeps area: a direction at angle θ from the normal lies at
//! radius `2 sin(θ/2)` of a disc of radius 2, the normal at the centre, the
//! surface's horizon on the circle of radius √2, the direction into the
//! surface on the rim. The disc's area is 4π, so one unit of area on it is
//! one steradian, and the sum of the density over the map's pixels times
//! their area is the share of the guide's samples they hold.

use glam::{Vec2, Vec3};

use super::directional::to_square;
use super::Guide;
use crate::error::{Error, Result};
use crate::math::Frame;

/// Samples of the guide [`DensityMap::share_above_surface`] is counted over.
pub const SHARE_SAMPLES: u32 = 1 << 16;

/// The guide's density around one surface point, as a square image of the
/// equal-area disc: the picture's bottom is toward the viewer (the camera),
/// its top away from it, as if looking down onto the surface from above.
#[derive(Clone, Debug, PartialEq)]
pub struct DensityMap {
    /// Edge of the square image, in pixels.
    pub size: u32,
    /// Row-major, top row first: the guide's density per steradian in the
    /// direction at each pixel's centre, 0 outside the disc.
    pub density_per_sr: Vec<f32>,
    /// The share of the guide's samples that leave above the surface,
    /// counted over [`SHARE_SAMPLES`] stratified samples of the guide (0
    /// where it learned no light).
    pub share_above_surface: f32,
    /// The density summed over the disc's pixels times their solid angle:
    /// near 1 where the guide learned light and its leaves are larger than
    /// the map's pixels (a leaf smaller than a pixel counts as the whole
    /// pixel or not at all), 0 where it learned none.
    pub total_probability: f32,
    /// Directional leaves of the distribution shown.
    pub leaves: usize,
}

impl DensityMap {
    /// The edges, in pixels, a map may have.
    pub const SIZES: std::ops::RangeInclusive<u32> = 8..=4096;

    /// Fails for a map edge of `size` pixels outside [`DensityMap::SIZES`].
    pub fn check_size(size: u32) -> Result<()> {
        if Self::SIZES.contains(&size) {
            return Ok(());
        }
        Err(Error::InvalidArgument(format!(
            "a guide map's size must be {} to {} pixels, got {size}",
            Self::SIZES.start(),
            Self::SIZES.end()
        )))
    }

    /// The map of `guide`'s distribution at point `p` of a surface whose
    /// normal on the side the path arrives from is `normal`, with `toward_viewer`
    /// (a direction from `p` to the camera) at the picture's bottom; `size`
    /// pixels square.
    pub fn at(guide: &Guide, p: Vec3, normal: Vec3, toward_viewer: Vec3, size: u32) -> Self {
        let tree = guide.distribution_at(p, normal);
        let frame = viewer_frame(normal, toward_viewer);
        let pixel_sr = pixel_width(size).powi(2);
        let mut density_per_sr = vec![0.0f32; (size * size) as usize];
        let mut total = 0.0f64;
        for (i, density) in density_per_sr.iter_mut().enumerate() {
            let Some(local) = from_disc(disc_point(size, i)) else {
                continue;
            };
            *density = tree.pdf(to_square(frame.from_local(local)));
            total += f64::from(*density * pixel_sr);
        }
        // Counted from samples, not from the map's pixels: right however small the leaves.
        let strata = SHARE_SAMPLES.isqrt();
        let above = (0..strata * strata)
            .filter_map(|i| tree.sample((Vec2::new((i % strata) as f32, (i / strata) as f32) + 0.5) / strata as f32))
            .filter(|(d, _)| d.dot(normal) > 0.0)
            .count();
        DensityMap {
            size,
            density_per_sr,
            share_above_surface: above as f32 / (strata * strata) as f32,
            total_probability: total as f32,
            leaves: tree.leaf_count(),
        }
    }

    /// Where pixel `i` (row-major) of the map lies on the disc of radius 2
    /// (its centre), and one pixel's width there: for drawings over the map.
    pub fn disc_point(&self, i: usize) -> (Vec2, f32) {
        (disc_point(self.size, i), pixel_width(self.size))
    }

    /// The largest density on the map, per steradian.
    pub fn max_density_per_sr(&self) -> f32 {
        self.density_per_sr.iter().copied().fold(0.0, f32::max)
    }
}

/// One pixel's width on the disc of radius 2, for a map `size` pixels square.
fn pixel_width(size: u32) -> f32 {
    4.0 / size as f32
}

/// The centre of pixel `i` (row-major) of a map `size` pixels square, on
/// the disc of radius 2.
fn disc_point(size: u32, i: usize) -> Vec2 {
    let (x, y) = ((i as u32 % size) as f32, (i as u32 / size) as f32);
    (Vec2::new(x, y) + 0.5) * pixel_width(size) - 2.0
}

/// The local frame of the map: `n` out of the picture toward whoever looks
/// at it, the viewer's side of the surface toward the picture's bottom (+y,
/// image rows growing downward), so that +x is to the viewer's right.
fn viewer_frame(n: Vec3, toward_viewer: Vec3) -> Frame {
    let down = toward_viewer - n * n.dot(toward_viewer);
    if down.length_squared() < 1e-8 {
        // Seen head-on: any tangent will do.
        return Frame::from_normal(n);
    }
    let t = down.normalize();
    Frame { s: n.cross(t), t, n }
}

/// The local direction at point `d` of the disc of radius 2 (Lambert's
/// inverse: z = 1 − ρ²/2, the tangent part scaled by √(1 − ρ²/4)); `None`
/// outside the disc.
fn from_disc(d: Vec2) -> Option<Vec3> {
    let rho2 = d.length_squared();
    (rho2 <= 4.0).then(|| {
        let scale = (1.0 - rho2 / 4.0).max(0.0).sqrt();
        Vec3::new(d.x * scale, d.y * scale, 1.0 - rho2 / 2.0)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lambert's projection keeps area: the disc's pixels, each of
    /// (4/size)² sr, hold 4π sr in all and 2π above the horizon; its
    /// inverse gives unit directions with the normal at the centre.
    #[test]
    fn the_disc_holds_the_sphere_with_equal_areas() {
        let size = 400u32;
        let pixel_sr = (4.0 / size as f64).powi(2);
        let (mut all, mut above) = (0.0, 0.0);
        for i in 0..(size * size) as usize {
            if let Some(v) = from_disc(disc_point(size, i)) {
                assert!((v.length() - 1.0).abs() < 1e-5);
                all += pixel_sr;
                if v.z > 0.0 {
                    above += pixel_sr;
                }
            }
        }
        let sphere = 4.0 * std::f64::consts::PI;
        assert!((all / sphere - 1.0).abs() < 2e-3, "{all} sr of {sphere}");
        assert!((above / (sphere / 2.0) - 1.0).abs() < 2e-3, "{above} sr above");
        assert_eq!(from_disc(Vec2::ZERO), Some(Vec3::Z));
        let horizon = from_disc(Vec2::new(2f32.sqrt(), 0.0)).unwrap();
        assert!(horizon.z.abs() < 1e-6 && (horizon.x - 1.0).abs() < 1e-6);
    }

    /// The viewer's side of the surface is the picture's bottom, and the
    /// picture is seen from above the surface: its x (right) and y (down)
    /// turn the way a view down the normal does (x × y = −n).
    #[test]
    fn the_viewer_is_at_the_bottom() {
        let frame = viewer_frame(Vec3::Y, Vec3::new(0.0, 1.0, 2.0).normalize());
        assert!((frame.t - Vec3::Z).length() < 1e-6);
        assert!(
            (frame.s - Vec3::X).length() < 1e-6,
            "right, seen from above and from +z"
        );
        assert!((frame.s.cross(frame.t) + Vec3::Y).length() < 1e-6);
        let head_on = viewer_frame(Vec3::Y, Vec3::Y);
        assert!(head_on.n == Vec3::Y && head_on.s.dot(Vec3::Y).abs() < 1e-6);
    }
}
