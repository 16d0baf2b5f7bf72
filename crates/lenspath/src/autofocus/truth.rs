//! The ground truth a patch's focus is checked against: fine sweeps with two
//! independent seeds, with more samples until they agree
//! ([`Focuser::ground_truth`]).

use super::search::Focuser;
use super::signal::{log_parabola_peak, peak_index, Detail};
use crate::error::Result;

/// The most samples the ground truth takes, as a multiple of the strategies'
/// ([`Focuser::ground_truth`]): at 32× the two seeds of three dim or glassy
/// patches still disagreed by 0.9 to 1.6 DoF, so the truth was itself noisy.
pub const TRUTH_MAX_SPP_FACTOR: u32 = 128;

/// How far apart, in DoF, the ground truth's two seeds may put the peak for
/// it to count as converged ([`Focuser::ground_truth`]).
pub const TRUTH_SEED_SPREAD_DOF: f64 = 0.25;

/// The reference focus of a patch.
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
pub struct GroundTruth {
    /// Sensor position of the sharpest patch, mm behind the stop (read
    /// under its old name `sensor_z_mm` too, which earlier files have).
    #[serde(alias = "sensor_z_mm")]
    pub sensor_depth_mm: f64,
    /// How far two independent fine sweeps put the peak apart, in DoF (noise).
    pub seed_spread_dof: f64,
    /// Samples per pixel that brought the spread within [`TRUTH_SEED_SPREAD_DOF`] (or the most tried).
    pub spp: u32,
    /// The conjugate of the patch's dominant depth, mm behind the stop (`None` if the probes hit nothing).
    pub depth_conjugate_z_mm: Option<f64>,
    /// The lens's best-contrast sensor position for that depth at the patch's
    /// place in the field (what the `depth` strategy starts from).
    pub lens_best_focus_z_mm: Option<f64>,
}

impl GroundTruth {
    /// Whether computing it again could not do better: its seeds agree within
    /// [`TRUTH_SEED_SPREAD_DOF`], or it already took the most samples allowed
    /// for strategies rendering at `strategy_spp`.
    pub fn is_settled(&self, strategy_spp: u32) -> bool {
        self.seeds_agree() || self.spp >= TRUTH_MAX_SPP_FACTOR * strategy_spp
    }

    /// Whether its two seeds' peaks agree within [`TRUTH_SEED_SPREAD_DOF`]
    /// (when they do not, even at the most samples, it is no reference).
    pub fn seeds_agree(&self) -> bool {
        self.seed_spread_dof <= TRUTH_SEED_SPREAD_DOF
    }
}

impl Focuser<'_> {
    /// The reference focus: the peak of a fine sweep (half-pitch steps over
    /// ±5 pitches around the peak of a coarse 4-pitch scan at the coarse
    /// scale, widened while its maximum is near an end), located by a
    /// least-squares parabola through the log-scores within 1.5 DoF of its
    /// maximum, with two seeds; the
    /// samples are doubled (from 4× the settings', up to
    /// [`TRUTH_MAX_SPP_FACTOR`]×) until the seeds agree within
    /// [`TRUTH_SEED_SPREAD_DOF`].
    /// Its evaluations are not counted anywhere. It is found in the film's
    /// noiseless radiance, also when the search looks through a sensor.
    pub fn ground_truth(&mut self) -> Result<GroundTruth> {
        self.without_sensor(Self::noiseless_truth)
    }

    /// [`Focuser::ground_truth`] without a sensor.
    fn noiseless_truth(&mut self) -> Result<GroundTruth> {
        let saved = (std::mem::take(&mut self.evaluations), self.camera_rays);
        let seed = self.settings.seed;
        let mut spp = 4 * self.settings.spp;
        let coarse_best = {
            let mut best = (f64::NEG_INFINITY, self.range_mm.0);
            for z in self.grid(4.0 * self.pitch_mm) {
                let s = self.measure_at(z, spp, seed ^ 0x5eed, Detail::Coarse)?;
                if s > best.0 {
                    best = (s, z);
                }
            }
            best.1
        };
        let (near, far) = self.range_mm;
        let half_pitch = 0.5 * self.pitch_mm;
        let mut fine: Vec<f64> = (-10..=10)
            .map(|i| coarse_best + f64::from(i) * half_pitch)
            .filter(|z| (near - 1e-9..=far + 1e-9).contains(z))
            .collect();
        // The coarse scan can miss the peak by a step or two: while the fine
        // scan's maximum is within two steps of an end, widen it there by ten.
        loop {
            let i = peak_index(&self.scan(&fine, spp, seed ^ 0xf1e1d)?);
            let (first, last) = (fine[0], fine[fine.len() - 1]);
            if i <= 1 && first - half_pitch >= near - 1e-9 {
                fine.splice(
                    0..0,
                    (1..=10)
                        .rev()
                        .map(|k| first - f64::from(k) * half_pitch)
                        .filter(|&z| z >= near - 1e-9),
                );
            } else if i + 2 >= fine.len() && last + half_pitch <= far + 1e-9 {
                fine.extend(
                    (1..=10)
                        .map(|k| last + f64::from(k) * half_pitch)
                        .filter(|&z| z <= far + 1e-9),
                );
            } else {
                break;
            }
        }
        let result = loop {
            let mut peaks = [0.0; 2];
            for (k, peak) in peaks.iter_mut().enumerate() {
                let seed = seed.wrapping_add(1000 + k as u32);
                let points = self.scan(&fine, spp, seed)?;
                let i = peak_index(&points);
                // A least-squares fit over ±1.5 DoF (about 15 half-pitch
                // steps), not the three points around the maximum: those
                // are a fifth of a DoF apart, and noise tilts their parabola.
                *peak = log_parabola_peak(&points, fine[i], 1.5 * self.depth_of_focus_mm(fine[i]));
            }
            let z = 0.5 * (peaks[0] + peaks[1]);
            let spread = (peaks[0] - peaks[1]).abs() / self.depth_of_focus_mm(z);
            if spread <= TRUTH_SEED_SPREAD_DOF || spp >= TRUTH_MAX_SPP_FACTOR * self.settings.spp {
                break (z, spread, spp);
            }
            spp *= 2;
        };
        let range = self.range_focus()?;
        (self.evaluations, self.camera_rays) = saved;
        Ok(GroundTruth {
            sensor_depth_mm: result.0,
            seed_spread_dof: result.1,
            spp: result.2,
            depth_conjugate_z_mm: range.map(|r| r.conjugate_z_mm),
            lens_best_focus_z_mm: range.map(|r| r.best_focus_z_mm),
        })
    }
}
