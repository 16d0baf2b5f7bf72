//! Contrast autofocus on what a sensor reads (issue 32): with a
//! [`FocusSensor`], each patch image a search scores is a raw frame captured
//! from the patch's film ([`crate::sensor::capture`]: shot, read and
//! fixed-pattern noise, clipping, quantisation), and the focus measure reads
//! its [`SensorSignal`].
//!
//! The exposure is a camera's: metered from the search's first frame when
//! the sensor has auto exposure (within its exposure-time and ISO limits)
//! and then held for the whole search, as a camera locks its exposure while
//! it focuses. The frames taken at one lens position (a scored pair, a light
//! field's groups) share that exposure's time, so every strategy collects
//! one exposure's light per position and pays the read noise once per frame.

use crate::color::luminance;
use crate::error::Result;
use crate::film::FilmRadiometry;
use crate::film::{Image, PixelRect};
use crate::names::Named;
use crate::sampling::mix64;
use crate::sensor::develop::develop;
use crate::sensor::{capture, Development, RawFrame, SensorSettings, ToneCurve};

/// What contrast autofocus reads off a raw frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SensorSignal {
    /// The green pixels over the black level, a red or blue pixel taking
    /// the mean of its green neighbours (on a monochrome sensor, every
    /// pixel): nothing developed, as a camera's contrast AF reads its
    /// sensor. The default.
    #[default]
    RawGreen,
    /// The developed frame's luminance (demosaicked, white-balanced, the
    /// camera matrix to linear sRGB; no tone curve).
    Luminance,
}

impl Named for SensorSignal {
    const WHAT: &'static str = "autofocus sensor signal";
    const NAMED: &'static [(SensorSignal, &'static str)] = &[
        (SensorSignal::RawGreen, "raw-green"),
        (SensorSignal::Luminance, "luminance"),
    ];
}

impl SensorSignal {
    /// This signal of `frame` as a grey RGB image (three equal channels, as
    /// the focus measures take), 1 at the white level over black;
    /// `development` says how [`SensorSignal::Luminance`] demosaicks.
    pub fn read(self, frame: &RawFrame, development: &Development) -> Vec<f32> {
        let (w, h) = (frame.width as usize, frame.height as usize);
        let grey: Vec<f32> = match self {
            SensorSignal::RawGreen => {
                let black = frame.black_level_dn as f32;
                let scale = 1.0 / (frame.white_level_dn - frame.black_level_dn) as f32;
                let value = |x: usize, y: usize| (f32::from(frame.dn[y * w + x]) - black) * scale;
                let is_green = |x: usize, y: usize| frame.cfa.channel(x as u32, y as u32) == 1;
                (0..h)
                    .flat_map(|y| (0..w).map(move |x| (x, y)))
                    .map(|(x, y)| {
                        if is_green(x, y) {
                            return value(x, y);
                        }
                        // A Bayer pattern's four side neighbours are green.
                        let around = [(x.wrapping_sub(1), y), (x + 1, y), (x, y.wrapping_sub(1)), (x, y + 1)];
                        let (sum, n) = around
                            .iter()
                            .filter(|&&(x, y)| x < w && y < h)
                            .fold((0.0, 0.0), |(sum, n), &(x, y)| (sum + value(x, y), n + 1.0));
                        sum / n
                    })
                    .collect()
            }
            SensorSignal::Luminance => {
                let linear = Development {
                    tone_curve: ToneCurve::Linear,
                    ..*development
                };
                develop(frame, &linear)
                    .rgb
                    .chunks_exact(3)
                    .map(|p| luminance([p[0], p[1], p[2]]))
                    .collect()
            }
        };
        grey.iter().flat_map(|&v| [v; 3]).collect()
    }
}

/// The sensor a contrast search looks through, and what it reads.
#[derive(Clone, Debug, PartialEq)]
pub struct FocusSensor {
    /// The sensor. Its exposure is the search's, or with auto exposure its
    /// limits; its frame seed starts the search's frames.
    pub sensor: SensorSettings,
    /// What the focus measure reads of each frame.
    pub signal: SensorSignal,
}

/// A search's sensor exposure: none until its first frame, then that frame's
/// (metered, with auto exposure) held for the rest of the search, as a camera
/// locks its exposure while it focuses.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct HeldExposure(Option<SensorSettings>);

impl HeldExposure {
    /// The exposure held, once a frame has been taken.
    pub(super) fn held(&self) -> Option<&SensorSettings> {
        self.0.as_ref()
    }

    /// `film`, a `patch` image of film readings through a camera of
    /// radiometry `optics`, as the search sees it: itself without a sensor;
    /// with one, the signal of one of `frames` frames taken at this lens
    /// position (they share the held exposure's time), `key` telling the
    /// frames of a search apart (their temporal noise is independent).
    pub(super) fn see(
        &mut self,
        sensor: Option<&FocusSensor>,
        patch: PixelRect,
        film: Vec<f32>,
        optics: Option<FilmRadiometry>,
        (frames, key): (u32, u64),
    ) -> Result<Vec<f32>> {
        let Some(focus_sensor) = sensor else {
            return Ok(film);
        };
        let optics = optics.ok_or_else(crate::sensor::needs_a_lens)?;
        let image = Image {
            width: patch.width,
            height: patch.height,
            depth: vec![f32::INFINITY; film.len() / 3],
            rgb: film,
            spp_min: 0,
            spp_requested: 0,
        };
        // The first frame meters (with auto exposure); the search holds it.
        let held = self
            .0
            .get_or_insert_with(|| SensorSettings {
                auto_exposure: None,
                ..focus_sensor.sensor.metered(&image, &optics)
            })
            .clone();
        let frame_settings = SensorSettings {
            exposure_time_s: held.exposure_time_s / f64::from(frames.max(1)),
            frame_seed: mix64(held.frame_seed.wrapping_add(key)),
            ..held
        };
        let frame = capture(&image, (patch.x0, patch.y0), &optics, &frame_settings)?;
        Ok(focus_sensor.signal.read(&frame, &frame_settings.development))
    }
}

/// A key for the frame `k` of those at sensor position `z_mm` taken with
/// render seed `seed`: distinct positions, seeds and frames give
/// independent temporal noise.
pub(super) fn frame_key(z_mm: f64, seed: u32, k: usize) -> u64 {
    mix64(z_mm.to_bits() ^ (u64::from(seed) << 32 | k as u64))
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::sensor::{Cfa, Exposure, SpectralResponse};

    /// A 4 × 4 RGGB frame, black 64, white 1023, of the given digital numbers.
    fn frame(dn: Vec<u16>) -> RawFrame {
        let ideal = SpectralResponse::named("ideal").unwrap();
        RawFrame {
            width: 4,
            height: 4,
            dn,
            cfa: Cfa::Rggb,
            black_level_dn: 64,
            white_level_dn: 1023,
            electrons_per_dn: 1.0,
            xyz_to_camera: ideal.xyz_to_camera(),
            as_shot_neutral: ideal.d65_neutral() / ideal.d65_neutral().max_element(),
            exposure: Exposure {
                exposure_time_s: 0.01,
                iso: 100.0,
                sensor_name: "ideal".into(),
            },
        }
    }

    #[test]
    fn raw_green_keeps_green_pixels_and_fills_the_others_from_their_neighbours() {
        // Green pixels (x + y odd in RGGB) count 64 + 10·(index); red and blue 1000.
        let dn: Vec<u16> = (0..16u16)
            .map(|i| if (i % 4 + i / 4) % 2 == 1 { 64 + 10 * i } else { 1000 })
            .collect();
        let grey = SensorSignal::RawGreen.read(&frame(dn.clone()), &Development::default());
        let level = |i: usize| f32::from(dn[i] - 64) / 959.0;
        for (i, px) in grey.chunks_exact(3).enumerate() {
            assert!(px[0] == px[1] && px[1] == px[2], "grey: {px:?}");
            let (x, y) = (i % 4, i / 4);
            let expected = if (x + y) % 2 == 1 {
                level(i)
            } else {
                let around: Vec<usize> = [
                    (x as i32 - 1, y as i32),
                    (x as i32 + 1, y as i32),
                    (x as i32, y as i32 - 1),
                    (x as i32, y as i32 + 1),
                ]
                .into_iter()
                .filter(|&(x, y)| (0..4).contains(&x) && (0..4).contains(&y))
                .map(|(x, y)| (y * 4 + x) as usize)
                .collect();
                around.iter().map(|&j| level(j)).sum::<f32>() / around.len() as f32
            };
            assert!(
                (px[0] - expected).abs() < 1e-6,
                "pixel ({x}, {y}): {} vs {expected}",
                px[0]
            );
        }
    }

    #[test]
    fn a_flat_d65_grey_reads_the_same_in_both_signals() {
        // A flat frame whose channels read the ideal sensor's D65 neutral at
        // half scale: white-balanced and developed it is grey 0.5 · (1, 1, 1),
        // luminance 0.5; its raw green is the green channel's level.
        let f = frame(vec![0; 16]);
        let neutral: DVec3 = f.as_shot_neutral;
        let dn: Vec<u16> = (0..16u32)
            .map(|i| {
                let channel = Cfa::Rggb.channel(i % 4, i / 4);
                (64.0 + 959.0 * 0.5 * neutral[channel]).round() as u16
            })
            .collect();
        let f = RawFrame { dn, ..f };
        let luminance = SensorSignal::Luminance.read(&f, &Development::default());
        for v in luminance.iter() {
            assert!((v - 0.5).abs() < 2e-3, "luminance {v}");
        }
        let green = SensorSignal::RawGreen.read(&f, &Development::default());
        for v in green.iter() {
            assert!((f64::from(*v) - 0.5 * neutral.y).abs() < 1e-3, "raw green {v}");
        }
    }

    #[test]
    fn signal_names_round_trip() {
        for &(signal, name) in SensorSignal::NAMED {
            assert_eq!(SensorSignal::parse(name).unwrap(), signal);
            assert_eq!(signal.name(), name);
        }
        let err = SensorSignal::parse("blue").unwrap_err().to_string();
        assert!(err.contains("raw-green, luminance"), "{err}");
    }
}
