//! What controls one render: `RenderSettings` and what its film records
//! (`FilmResponse`), their checks, and the region a render covers.

use crate::error::{Error, Result};
use crate::film::{Filter, PixelRect};
use crate::guiding::Guide;
use crate::integrator::Integrator;
use crate::math::Rgb;
use crate::ray::Ray;
use crate::sampling::{Sampler, SamplerKind, MAX_SAMPLES_PER_PIXEL};
use crate::scene::CompiledScene;
use crate::sensor::SpectralResponse;
use crate::spectrum::{SampledWavelengths, LAMBDA_MAX_NM, LAMBDA_MIN_NM};

/// Everything that controls one render.
#[derive(Clone, Copy, Debug)]
pub struct RenderSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// The integrator and its settings (path depth, light sampling).
    pub integrator: Integrator,
    /// Seed of the sample sequences: the same seed gives the same image.
    pub seed: u32,
    /// The sample sequence: Sobol (the default) or independent.
    pub sampler: SamplerKind,
    /// Pixel reconstruction filter.
    pub filter: Filter,
    /// Worker threads; `None` uses every core.
    pub threads: Option<usize>,
    /// Edge of the square tiles, in pixels.
    pub tile_size: u32,
    /// Render only this rectangle of the image (pbrt's crop window): the
    /// output is the rectangle, each pixel exactly as in the full render.
    /// For patches rendered many times, as autofocus does.
    pub crop: Option<PixelRect>,
    /// Compute the depth (Z) channel: one extra camera ray per pixel, in the
    /// first pass. Off for renders only their colour is wanted from, such as
    /// autofocus patches.
    pub depth: bool,
    /// What the film records of the light: linear sRGB (the default), the
    /// radiance at one wavelength, or a sensor's channels ([`FilmResponse`]).
    pub film: FilmResponse,
}

/// What a pixel's three numbers are.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum FilmResponse {
    /// Linear sRGB radiance, from the CIE matching functions.
    #[default]
    Srgb,
    /// The spectral radiance at this one wavelength, nm, the same in all
    /// three channels: every sample carries it alone (a lens designer's
    /// monochromatic image).
    Monochromatic {
        /// The wavelength, nm.
        wavelength_nm: f32,
    },
    /// Each channel's photoelectron rate through this sensor response per
    /// unit étendue ([`SpectralResponse::electron_rate`]), for
    /// [`crate::sensor::capture`].
    Sensor(&'static SpectralResponse),
}

impl FilmResponse {
    /// The film of the scene's radiance: at `wavelength_nm` when given
    /// ([`FilmResponse::Monochromatic`]), else as linear sRGB.
    pub fn radiance(wavelength_nm: Option<f32>) -> FilmResponse {
        wavelength_nm.map_or(FilmResponse::Srgb, |wavelength_nm| FilmResponse::Monochromatic {
            wavelength_nm,
        })
    }

    /// This film read out by a sensor of `response`; fails for a
    /// monochromatic film, since a sensor records colour.
    pub fn read_by(self, response: &'static SpectralResponse) -> Result<FilmResponse> {
        match self {
            FilmResponse::Monochromatic { .. } => Err(Error::InvalidArgument(
                "a sensor records colour: render it across the visible, not at one wavelength".into(),
            )),
            _ => Ok(FilmResponse::Sensor(response)),
        }
    }

    /// The one wavelength every sample carries, nm, for a monochromatic film.
    pub fn wavelength_nm(self) -> Option<f32> {
        match self {
            FilmResponse::Monochromatic { wavelength_nm } => Some(wavelength_nm),
            _ => None,
        }
    }

    /// The wavelengths a camera sample carries on this film: `drawn` (those
    /// the sample drew across the visible), or the film's one wavelength.
    #[inline(always)]
    pub(crate) fn wavelengths(self, drawn: SampledWavelengths) -> SampledWavelengths {
        match self {
            FilmResponse::Monochromatic { wavelength_nm } => SampledWavelengths::single(wavelength_nm),
            _ => drawn,
        }
    }

    /// What the film records of the light arriving along a camera ray at
    /// the wavelengths `lambda` ([`Integrator::radiance`]'s arguments).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn reading(
        self,
        integrator: &Integrator,
        scene: &CompiledScene,
        guide: Option<&Guide>,
        camera_ray: Ray,
        lambda: SampledWavelengths,
        sampler: &mut Sampler,
        rays: &mut u64,
    ) -> Rgb {
        match self {
            FilmResponse::Srgb => integrator.li(scene, guide, camera_ray, lambda, sampler, rays),
            // One wavelength at density 1: the estimate is the radiance itself.
            FilmResponse::Monochromatic { .. } => Rgb::splat(
                integrator
                    .li_spectrum(scene, guide, camera_ray, lambda, sampler, rays)
                    .0
                    .x,
            ),
            FilmResponse::Sensor(response) => {
                let (l, lambda) = integrator.li_spectrum(scene, guide, camera_ray, lambda, sampler, rays);
                response.electron_rate(&lambda, l)
            }
        }
    }
}

/// Image size in pixels, (width, height), when neither the caller nor the scene file gives one.
pub const DEFAULT_IMAGE_SIZE: (u32, u32) = (640, 480);
/// Samples per pixel when neither the caller nor the scene file gives them.
pub const DEFAULT_SPP: u32 = 64;
/// Seed of the sample sequences when neither the caller nor the scene file gives one.
pub const DEFAULT_SEED: u32 = 0;
/// Edge of the square tiles a render is cut into, pixels.
pub const DEFAULT_TILE_SIZE: u32 = 16;
/// The most shadow rays per light and hit a render takes.
pub const MAX_LIGHT_SAMPLES: u32 = 1024;

impl Default for RenderSettings {
    /// The library's defaults: these `DEFAULT_*` values, the path tracer's
    /// (`integrator::DEFAULT_*`), box filter, every core, the depth channel.
    fn default() -> Self {
        RenderSettings {
            width: DEFAULT_IMAGE_SIZE.0,
            height: DEFAULT_IMAGE_SIZE.1,
            spp: DEFAULT_SPP,
            integrator: Integrator::default(),
            seed: DEFAULT_SEED,
            sampler: SamplerKind::default(),
            filter: Filter::default(),
            threads: None,
            tile_size: DEFAULT_TILE_SIZE,
            crop: None,
            depth: true,
            film: FilmResponse::Srgb,
        }
    }
}

impl RenderSettings {
    /// The pixel that point `(x, y)` of the image lies in, the point given
    /// as fractions of the image's width and height from its top left (0 to
    /// 1; a point on the right or bottom edge is in the last pixel). Fails
    /// for a point outside the image.
    pub fn pixel_at(&self, (x, y): (f64, f64)) -> Result<(u32, u32)> {
        if !((0.0..=1.0).contains(&x) && (0.0..=1.0).contains(&y)) {
            return Err(Error::InvalidArgument(format!(
                "a point of the image is given as fractions of its width and height from its top left \
                 (0 to 1), got ({x}, {y})"
            )));
        }
        let at = |f: f64, size: u32| ((f * f64::from(size)) as u32).min(size.saturating_sub(1));
        Ok((at(x, self.width), at(y, self.height)))
    }

    /// Rejects settings that cannot make an image.
    pub fn validate(&self) -> Result<()> {
        let fail = |m: String| Err(Error::InvalidArgument(m));
        if self.width == 0 || self.height == 0 {
            return fail(format!(
                "image size must be positive, got {}x{}",
                self.width, self.height
            ));
        }
        if self.width > 65_536 || self.height > 65_536 {
            return fail(format!(
                "image size {}x{} exceeds 65536 pixels on a side",
                self.width, self.height
            ));
        }
        if self.spp == 0 || self.spp > MAX_SAMPLES_PER_PIXEL {
            return fail(format!(
                "samples per pixel must be in 1..={MAX_SAMPLES_PER_PIXEL}, got {}",
                self.spp
            ));
        }
        // 0, emitters only, is a depth.
        if self.integrator.max_depth() > MAX_PATH_DEPTH {
            return fail(format!(
                "max depth must be at most {MAX_PATH_DEPTH}, got {}",
                self.integrator.max_depth()
            ));
        }
        if self.integrator.light_samples() > MAX_LIGHT_SAMPLES {
            return fail(format!(
                "light samples must be at most {MAX_LIGHT_SAMPLES}, got {}",
                self.integrator.light_samples()
            ));
        }
        crate::parallel::check_threads(self.threads)?;
        let (width, height) = self.crop.map_or((self.width, self.height), |c| (c.width, c.height));
        crate::memory::check_fits(
            &|| format!("a {width}x{height} render"),
            u64::from(width) * u64::from(height) * crate::memory::RENDER_BYTES_PER_PIXEL,
        )?;
        if self.tile_size == 0 {
            return fail("tile size must be positive".into());
        }
        if let Some(c) = self.crop {
            let inside =
                |start: u32, len: u32, size: u32| len > 0 && start.checked_add(len).is_some_and(|end| end <= size);
            if !inside(c.x0, c.width, self.width) || !inside(c.y0, c.height, self.height) {
                return fail(format!(
                    "crop {}x{} at ({}, {}) is empty or leaves the {}x{} image",
                    c.width, c.height, c.x0, c.y0, self.width, self.height
                ));
            }
        }
        if let Some(nm) = self.film.wavelength_nm() {
            if !(LAMBDA_MIN_NM..=LAMBDA_MAX_NM).contains(&nm) {
                return fail(format!(
                    "wavelength must be in {LAMBDA_MIN_NM}..={LAMBDA_MAX_NM} nm, got {nm}"
                ));
            }
        }
        if let Filter::Gaussian { sigma, radius } = self.filter {
            if !(sigma > 0.0 && radius > 0.0 && sigma.is_finite() && radius.is_finite()) {
                return fail(format!(
                    "Gaussian filter needs positive sigma and radius, got {sigma} and {radius}"
                ));
            }
        }
        Ok(())
    }
}

/// The deepest path a render may ask for (scattering events): deeper paths
/// carry nothing Russian roulette would not have ended long before.
pub const MAX_PATH_DEPTH: u32 = 1024;

/// The region a render covers: its crop, else the whole image.
pub(super) fn region(settings: &RenderSettings) -> PixelRect {
    settings.crop.unwrap_or(PixelRect {
        x0: 0,
        y0: 0,
        width: settings.width,
        height: settings.height,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A monochromatic film cannot be read out by a sensor, and says why;
    /// a colour film can, and a film at one wavelength carries it alone.
    #[test]
    fn a_sensor_reads_a_colour_film_only() {
        let response = SpectralResponse::named("sony_ilce_7m3").unwrap();
        let mono = FilmResponse::radiance(Some(550.0));
        assert_eq!(mono, FilmResponse::Monochromatic { wavelength_nm: 550.0 });
        let err = mono.read_by(response).unwrap_err().to_string();
        assert!(err.contains("a sensor records colour"), "{err}");
        let colour = FilmResponse::radiance(None);
        assert_eq!(colour, FilmResponse::Srgb);
        assert_eq!(colour.read_by(response).unwrap(), FilmResponse::Sensor(response));
        let drawn = SampledWavelengths::sample_visible(0.3);
        assert_eq!(colour.wavelengths(drawn), drawn);
        assert_eq!(mono.wavelengths(drawn), SampledWavelengths::single(550.0));
        let out_of_range = RenderSettings {
            film: FilmResponse::radiance(Some(200.0)),
            ..RenderSettings::default()
        };
        let err = out_of_range.validate().unwrap_err().to_string();
        assert!(err.contains("wavelength must be in"), "{err}");
    }
}
