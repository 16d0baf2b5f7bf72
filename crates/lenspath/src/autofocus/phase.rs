//! Phase detection, as a camera's phase-detect autofocus sensor does it: the
//! patch seen through one half of the aperture and through the other shifts
//! apart in proportion to the defocus. The shift between the two images
//! (their cross-correlation's peak, [`disparity`]) and the lens's own
//! through-focus behaviour ([`PhaseCalibration`]: how fast the halves
//! separate, and where the lens's best contrast lies relative to zero
//! separation) give the sensor position in one measurement.
//!
//! What makes it better than a range finder for autofocus: the images are
//! rendered, so the shift is the one of whatever carries the patch's contrast
//! (a sphere's silhouette in front of a plain wall, a reflection, an image
//! refracted by glass, a caustic), weighted by that contrast, where probe rays
//! only report the nearest surface most of the patch covers.

/// Two halves of the aperture stop, split across one axis of the lens.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Split {
    /// The halves x < 0 and x > 0 of the stop: images shift along the image rows.
    LeftRight,
    /// The halves y < 0 and y > 0: images shift along the image columns.
    TopBottom,
}

impl Split {
    /// Both splits, as a cross-type phase-detect sensor has them: a split sees
    /// only edges across its axis, so one alone is blind to half the patches.
    pub const BOTH: [Split; 2] = [Split::LeftRight, Split::TopBottom];

    /// The lens-coordinate axis the stop is split across (0: x, 1: y).
    pub fn axis(self) -> usize {
        match self {
            Split::LeftRight => 0,
            Split::TopBottom => 1,
        }
    }

    /// Transmission masks over the stop's bounding square (row-major, top
    /// row first, as [`crate::camera::ApertureShape::mask`] takes them) for
    /// the − half and the + half: `(width, height, values)` each.
    pub fn half_masks(self) -> [(usize, usize, Vec<f32>); 2] {
        match self {
            Split::LeftRight => [(2, 1, vec![1.0, 0.0]), (2, 1, vec![0.0, 1.0])],
            // Top row first: the + half (y > 0) is the first row.
            Split::TopBottom => [(1, 2, vec![0.0, 1.0]), (1, 2, vec![1.0, 0.0])],
        }
    }
}

/// How far the image through the + half lies from the image through the −
/// half, along one image axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disparity {
    /// The shift, pixels: the + half's image is the − half's moved by this much.
    pub shift_px: f64,
    /// How sharply the cross-correlation peaks there (minus its second
    /// difference, per pixel): the energy of the detail both images share
    /// that varies along the axis. It weighs this split's reading against the
    /// other's: a split across which every edge runs sees a flat peak, whose
    /// place says nothing.
    pub strength: f64,
}

/// The shift between two images of `width` × `height` RGB pixels
/// (band-passed, so zero-mean) along `axis` (0: along rows, 1: along
/// columns), searched up to `max_shift_px` either way: the peak of their
/// cross-correlation C(d) = mean over the overlap of minus(p)·plus(p + d),
/// refined to a fraction of a pixel by the parabola through it and its
/// neighbours. Render noise does not bias it when the two renders are
/// independent: the expected product of independent zero-mean noises is zero.
/// `None` when the images share no detail (the correlation never exceeds 0)
/// or the peak is at an end of the search.
pub fn disparity(
    minus: &[f32],
    plus: &[f32],
    width: usize,
    height: usize,
    axis: usize,
    max_shift_px: usize,
) -> Option<Disparity> {
    let extent = if axis == 0 { width } else { height };
    let max_shift = max_shift_px.min(extent.saturating_sub(2) / 2) as isize;
    let correlation = |d: isize| -> f64 {
        let (mut sum, mut count) = (0.0f64, 0usize);
        for y in 0..height as isize {
            for x in 0..width as isize {
                let (sx, sy) = if axis == 0 { (x + d, y) } else { (x, y + d) };
                if sx < 0 || sy < 0 || sx >= width as isize || sy >= height as isize {
                    continue;
                }
                let (a, b) = (
                    3 * (y as usize * width + x as usize),
                    3 * (sy as usize * width + sx as usize),
                );
                sum += (0..3)
                    .map(|c| f64::from(minus[a + c]) * f64::from(plus[b + c]))
                    .sum::<f64>();
                count += 1;
            }
        }
        sum / count.max(1) as f64
    };
    let values: Vec<f64> = (-max_shift..=max_shift).map(correlation).collect();
    let best = (0..values.len()).max_by(|&a, &b| values[a].total_cmp(&values[b]))?;
    if values[best] <= 0.0 {
        return None;
    }
    // At an end of the search the peak may lie beyond it: no reading.
    if best == 0 || best + 1 == values.len() {
        return None;
    }
    let (a, b, c) = (values[best - 1], values[best], values[best + 1]);
    let curvature = a - 2.0 * b + c;
    (curvature < 0.0).then(|| Disparity {
        shift_px: best as f64 - max_shift as f64 + (0.5 * (a - c) / curvature).clamp(-0.5, 0.5),
        strength: -curvature,
    })
}

/// What the lens says about one split of its stop for a point in the scene
/// (from [`crate::lens::SpotBundle::half_pupil_separation`] and
/// [`crate::lens::SpotBundle::best_focus_z`]): the factory calibration of a
/// phase-detect sensor, computed from the prescription.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhaseCalibration {
    /// How fast the halves' images separate as the sensor moves back, mm of
    /// separation (lens coordinates, + half minus − half) per mm.
    pub separation_per_mm: f64,
    /// The lens's best-contrast sensor position minus the position where the
    /// halves' images coincide, mm: spherical aberration puts them apart.
    pub best_minus_zero_mm: f64,
}

impl PhaseCalibration {
    /// The best-contrast sensor position, given that at sensor position
    /// `sensor_z_mm` the halves' images lie `separation_mm` apart (lens
    /// coordinates, + half minus − half).
    pub fn best_focus_z(&self, sensor_z_mm: f64, separation_mm: f64) -> f64 {
        sensor_z_mm - separation_mm / self.separation_per_mm + self.best_minus_zero_mm
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth random texture (sum of sinusoids) sampled at x + `shift_x`, y + `shift_y`.
    fn texture(width: usize, height: usize, shift_x: f64, shift_y: f64) -> Vec<f32> {
        let waves = [
            (0.31, 0.07, 0.3),
            (-0.12, 0.27, 1.1),
            (0.19, -0.22, 2.0),
            (0.05, 0.41, 0.7),
            (0.37, 0.18, 2.9),
        ];
        let mut out = Vec::with_capacity(3 * width * height);
        for y in 0..height {
            for x in 0..width {
                let (px, py) = (x as f64 + shift_x, y as f64 + shift_y);
                let v: f64 = waves
                    .iter()
                    .map(|(fx, fy, phase)| (fx * px + fy * py + phase).sin())
                    .sum();
                out.extend([v as f32, 0.5 * v as f32, -v as f32]);
            }
        }
        out
    }

    #[test]
    fn disparity_finds_a_known_shift_along_either_axis() {
        let (w, h) = (48, 40);
        let minus = texture(w, h, 0.0, 0.0);
        // The + image is the − image moved by +2.3 pixels along x: plus(x) = minus(x − 2.3).
        let plus = texture(w, h, -2.3, 0.0);
        let d = disparity(&minus, &plus, w, h, 0, 8).unwrap();
        assert!((d.shift_px - 2.3).abs() < 0.15, "{d:?}");
        let plus = texture(w, h, 0.0, 1.6);
        let d = disparity(&minus, &plus, w, h, 1, 8).unwrap();
        assert!((d.shift_px + 1.6).abs() < 0.15, "{d:?}");
    }

    #[test]
    fn unrelated_images_have_no_disparity() {
        let (w, h) = (16, 16);
        let minus = vec![0.0f32; 3 * w * h];
        assert!(disparity(&minus, &texture(w, h, 0.0, 0.0), w, h, 0, 4).is_none());
    }

    #[test]
    fn calibration_turns_a_separation_into_a_sensor_position() {
        // Halves separating by −0.1 mm per mm (they cross in front of the
        // sensor when it is too far back), best contrast 0.02 mm behind the crossing.
        let c = PhaseCalibration {
            separation_per_mm: -0.1,
            best_minus_zero_mm: 0.02,
        };
        // At 52 mm the halves are 0.01 mm apart: they cross at 52.1.
        assert!((c.best_focus_z(52.0, 0.01) - 52.12).abs() < 1e-12);
    }
}
