//! White balance: the channels' reading of the light the camera is set
//! for (the DNG `AsShotNeutral`, Adobe DNG Specification 1.4, ch. 6). A
//! raw developer divides each channel by it, so a surface that reflects
//! that light evenly develops to white ([`super::develop`]).

use glam::DVec3;

use super::SpectralResponse;
use crate::film::Image;
use crate::spectrum::planck;
use crate::{Error, Result};

/// What light the camera is balanced for.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum WhiteBalance {
    /// CIE D65 daylight (the colour matrix's own white): the default, the
    /// scenes' own white (an RGB emitter's white is D65).
    #[default]
    Daylight,
    /// A black body at this temperature, K (tungsten is about 2856 K,
    /// CIE illuminant A).
    Kelvin(f64),
    /// The mean of each channel over the frame is grey (Buchsbaum 1980's
    /// grey-world assumption, a camera's simplest automatic balance).
    GreyWorld,
}

impl WhiteBalance {
    /// Reads `daylight` (or `d65`), `grey-world` (or `auto`), or a
    /// temperature such as `2856K` (or `2856`).
    pub fn parse(text: &str) -> Result<WhiteBalance> {
        let lower = text.trim().to_ascii_lowercase();
        let balance = match lower.as_str() {
            "daylight" | "d65" => WhiteBalance::Daylight,
            "grey-world" | "gray-world" | "auto" => WhiteBalance::GreyWorld,
            _ => {
                let kelvin: f64 = lower.strip_suffix('k').unwrap_or(&lower).parse().map_err(|_| {
                    Error::InvalidArgument(format!(
                        "unknown white balance '{text}': give daylight, grey-world or a temperature such as 3200K"
                    ))
                })?;
                WhiteBalance::Kelvin(kelvin)
            }
        };
        balance.validate()?;
        Ok(balance)
    }

    /// The spelling [`Self::parse`] reads back.
    pub fn spelling(&self) -> String {
        match self {
            WhiteBalance::Daylight => "daylight".into(),
            WhiteBalance::Kelvin(k) => format!("{k}K"),
            WhiteBalance::GreyWorld => "grey-world".into(),
        }
    }

    /// Fails unless a temperature is one a black body shows colour at.
    pub fn validate(&self) -> Result<()> {
        match self {
            WhiteBalance::Kelvin(k) if !(*k >= 1000.0 && *k <= 40_000.0) => Err(Error::InvalidArgument(format!(
                "a white balance temperature must be 1000 to 40000 K, not {k}"
            ))),
            _ => Ok(()),
        }
    }

    /// The channels' reading of the balanced-for light, largest 1, through
    /// `response`; `film` is the sensor render's film (grey world's mean).
    pub fn neutral(&self, response: &SpectralResponse, film: &Image) -> DVec3 {
        let reading = match self {
            WhiteBalance::Daylight => return response.d65_neutral(),
            WhiteBalance::Kelvin(k) => response.reading(|nm| f64::from(planck(nm as f32, *k as f32))),
            WhiteBalance::GreyWorld => {
                let sum: DVec3 = film
                    .rgb
                    .chunks_exact(3)
                    .map(|p| DVec3::new(p[0].into(), p[1].into(), p[2].into()))
                    .sum();
                sum.max(DVec3::ZERO)
            }
        };
        if reading.min_element() > 0.0 && reading.is_finite() {
            reading / reading.max_element()
        } else {
            // A frame with no light in a channel has no grey to find.
            response.d65_neutral()
        }
    }
}
