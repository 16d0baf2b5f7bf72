//! Blur kernels: a mask image or an aperture shape, sized and normalised to
//! unit sum, the way the bokeh post-process convolves with them.

use crate::camera::Aperture;
use crate::error::{Error, Result};

/// The largest kernel side, pixels: a bokeh wider than a 16k image is no
/// longer a blur, and its FFT would need tens of gigabytes.
pub const MAX_KERNEL_SIDE_PX: u32 = 16384;

/// Fails unless `diameter_px` is a kernel diameter: finite, at least 1 and
/// at most [`MAX_KERNEL_SIDE_PX`], and its square kernel (weights and the
/// raster they are made from) fits the memory budget.
pub fn check_kernel_diameter(diameter_px: f64) -> Result<()> {
    if !(1.0..=f64::from(MAX_KERNEL_SIDE_PX)).contains(&diameter_px) {
        return Err(Error::InvalidArgument(format!(
            "a bokeh kernel's diameter must be 1 to {MAX_KERNEL_SIDE_PX} pixels, got {diameter_px}"
        )));
    }
    let side = diameter_px.ceil() as u64 + 2;
    crate::memory::check_fits(&|| format!("a bokeh kernel {side} pixels across"), side * side * 8)
}

/// How large the mask becomes as a kernel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KernelSize {
    /// The mask's own pixels.
    Native,
    /// Scaled so its longer side is this many pixels, aspect kept.
    LongerSide(u32),
    /// Resized to exactly this width and height (`--size full`: the image's,
    /// as the course project resized its mask).
    Exactly(u32, u32),
}

/// A blur kernel: non-negative weights summing to 1, row-major from the top.
/// Its centre pixel is (`width / 2`, `height / 2`).
#[derive(Clone, Debug, PartialEq)]
pub struct Kernel {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Weights, row-major from the top row.
    pub weights: Vec<f32>,
}

impl Kernel {
    /// A kernel from mask values (row-major, `width` × `height`), resized
    /// as `size` asks (a triangle filter, which averages when shrinking) and
    /// normalised.
    pub fn from_mask(width: usize, height: usize, values: &[f32], size: KernelSize) -> Result<Kernel> {
        if width == 0 || height == 0 || values.len() != width * height {
            return Err(Error::InvalidArgument(format!(
                "mask of {width}x{height} pixels needs {} values, got {}",
                width * height,
                values.len()
            )));
        }
        if values.iter().any(|v| !v.is_finite() || *v < 0.0) {
            return Err(Error::InvalidArgument(
                "mask values must be finite and not negative".into(),
            ));
        }
        match size {
            KernelSize::Native => {}
            KernelSize::LongerSide(n) => check_kernel_diameter(f64::from(n))?,
            KernelSize::Exactly(w, h) => check_kernel_diameter(f64::from(w.max(h)))?,
        }
        let (new_width, new_height) = match size {
            KernelSize::Native => (width, height),
            KernelSize::LongerSide(n) => {
                let scale = f64::from(n) / width.max(height) as f64;
                let side = |s: usize| ((s as f64 * scale).round() as usize).max(1);
                (side(width), side(height))
            }
            KernelSize::Exactly(w, h) => (w as usize, h as usize),
        };
        if new_width == 0 || new_height == 0 {
            return Err(Error::InvalidArgument("a kernel needs at least one pixel".into()));
        }
        let weights = if (new_width, new_height) == (width, height) {
            values.to_vec()
        } else {
            let buffer = image::ImageBuffer::<image::Luma<f32>, Vec<f32>>::from_raw(
                width as u32,
                height as u32,
                values.to_vec(),
            )
            .expect("the length was checked");
            image::imageops::resize(
                &buffer,
                new_width as u32,
                new_height as u32,
                image::imageops::FilterType::Triangle,
            )
            .into_raw()
            .into_iter()
            .map(|v| v.max(0.0))
            .collect()
        };
        Kernel::normalised(new_width, new_height, weights)
    }

    /// `aperture` rasterised as a kernel `diameter_px` across (odd-sized, so
    /// it is centred on a pixel).
    pub fn from_aperture(aperture: &Aperture, diameter_px: f64) -> Kernel {
        let side = 2 * (0.5 * diameter_px).ceil() as usize + 1;
        // The shape spans `diameter_px` of the `side` pixels.
        let weights = aperture.rasterize(side, side, side as f64 / diameter_px.max(1e-9));
        Kernel::normalised(side, side, weights).unwrap_or(Kernel::identity())
    }

    /// The kernel that leaves an image as it is.
    pub fn identity() -> Kernel {
        Kernel {
            width: 1,
            height: 1,
            weights: vec![1.0],
        }
    }

    fn normalised(width: usize, height: usize, mut weights: Vec<f32>) -> Result<Kernel> {
        let sum: f64 = weights.iter().map(|&w| f64::from(w)).sum();
        if sum.is_nan() || sum <= 0.0 {
            return Err(Error::InvalidArgument("the mask is black: nothing to blur with".into()));
        }
        for w in &mut weights {
            *w = (f64::from(*w) / sum) as f32;
        }
        Ok(Kernel { width, height, weights })
    }

    /// The kernel turned by 180° (about its centre pixel when its sides are odd).
    pub fn rotated_180(&self) -> Kernel {
        Kernel {
            weights: self.weights.iter().rev().copied().collect(),
            ..*self
        }
    }

    /// The centre pixel (column, row).
    pub fn centre(&self) -> (usize, usize) {
        (self.width / 2, self.height / 2)
    }

    /// Weights that are not zero.
    pub fn open_pixels(&self) -> usize {
        self.weights.iter().filter(|&&w| w != 0.0).count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::ApertureShape;

    #[test]
    fn masks_are_sized_and_normalised() {
        let values: Vec<f32> = (0..40 * 20).map(|k| (k % 7) as f32).collect();
        for (size, expected) in [
            (KernelSize::Native, (40, 20)),
            (KernelSize::LongerSide(10), (10, 5)),
            (KernelSize::Exactly(480, 360), (480, 360)),
        ] {
            let k = Kernel::from_mask(40, 20, &values, size).unwrap();
            assert_eq!((k.width, k.height), expected);
            let sum: f64 = k.weights.iter().map(|&w| f64::from(w)).sum();
            assert!((sum - 1.0).abs() < 1e-5 && k.weights.iter().all(|&w| w >= 0.0));
        }
        let black = Kernel::from_mask(2, 2, &[0.0; 4], KernelSize::Native).unwrap_err();
        assert!(black.to_string().contains("black"), "{black}");
    }

    /// A triangle aperture as a kernel: the corner up, its area the
    /// triangle's, and upside down once turned.
    #[test]
    fn aperture_kernels_have_the_shape() {
        let aperture = Aperture::new(&ApertureShape::parse("blades:3").unwrap()).unwrap();
        let k = Kernel::from_aperture(&aperture, 41.0);
        assert_eq!((k.width, k.height), (43, 43));
        let open = k.weights.iter().filter(|&&w| w > 0.0).count() as f64;
        let expected = aperture.open_fraction() * std::f64::consts::PI * 20.5 * 20.5;
        assert!((open / expected - 1.0).abs() < 0.1, "{open} vs {expected}");
        let row_mass = |k: &Kernel, row: usize| k.weights[row * k.width..(row + 1) * k.width].iter().sum::<f32>();
        // The top rows hold the narrow corner, the bottom rows the wide base.
        assert!(row_mass(&k, 13) < row_mass(&k, 29));
        let turned = k.rotated_180();
        assert!(row_mass(&turned, 13) > row_mass(&turned, 29));
    }
}
