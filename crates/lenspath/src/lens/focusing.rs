//! Focusing a placed lens by real rays: its real focal point, the sensor
//! position that focuses a given object distance and its inverse, and for
//! an anamorphic lens the plane between its two meridians' line foci.

use glam::DVec3;

use super::surface::Meridian;
use super::system::{Direction, LensRay, LensSystem};
use crate::error::{Error, Result};

impl LensSystem {
    /// The real-ray image of a scene ray in `meridian`: where it crosses the
    /// axis behind the lens.
    fn image_of(&self, ray: &LensRay, what: &str, meridian: Meridian) -> Result<(LensRay, f64)> {
        let out = self.trace(ray, Direction::ToSensor).ok_or_else(|| self.blocked(what))?;
        // A real image only when the ray leaves heading toward the axis.
        match out.axis_crossing_z(meridian) {
            Some(z) if out.heads_toward_axis(meridian) => Ok((out, z)),
            _ => Err(Error::InvalidArgument(format!(
                "{}: the {what} ray leaves the lens diverging, so it forms no real image",
                self.prescription.name
            ))),
        }
    }

    fn blocked(&self, what: &str) -> Error {
        Error::InvalidArgument(format!(
            "{}: the {what} ray is blocked inside the lens; try a smaller --ray-height-mm",
            self.prescription.name
        ))
    }

    /// The meridians real rays are traced in: one for a rotationally
    /// symmetric lens, both for an anamorphic one.
    fn traced_meridians(&self) -> &'static [Meridian] {
        if self.is_rotationally_symmetric() {
            &Meridian::BOTH[..1]
        } else {
            &Meridian::BOTH
        }
    }

    /// The mean of `figure` over [`LensSystem::traced_meridians`]: for an
    /// anamorphic lens the plane midway between its two meridians' line
    /// foci, where the blur is smallest (the circle of least confusion).
    fn between_meridians(&self, figure: impl Fn(Meridian) -> Result<f64>) -> Result<f64> {
        let meridians = self.traced_meridians();
        let mut sum = 0.0;
        for &m in meridians {
            sum += figure(m)?;
        }
        Ok(sum / meridians.len() as f64)
    }

    /// Real-ray rear focal point and principal plane from a ray parallel to
    /// the axis at `height_mm` (the CS184 lens simulator's choice is 0.1 mm)
    /// in the horizontal meridian; see [`LensSystem::real_focus_at_infinity_in`].
    pub fn real_focus_at_infinity(&self, height_mm: f64) -> Result<(f64, f64)> {
        self.real_focus_at_infinity_in(height_mm, Meridian::Horizontal)
    }

    /// Real-ray rear focal point and principal plane in `meridian`.
    pub fn real_focus_at_infinity_in(&self, height_mm: f64, meridian: Meridian) -> Result<(f64, f64)> {
        let start = meridian.across() * height_mm + DVec3::new(0.0, 0.0, self.front_z_mm() - 1.0);
        let ray = LensRay {
            origin: start,
            direction: DVec3::Z,
        };
        let (out, focal_z) = self.image_of(&ray, "parallel", meridian)?;
        let (out_height, out_slope) = (meridian.component(out.origin), meridian.component(out.direction));
        let principal_z = out.origin.z + (height_mm - out_height) * out.direction.z / out_slope;
        Ok((focal_z, principal_z))
    }

    /// The sensor position at which objects at infinity focus: the real
    /// focus of [`LensSystem::real_focus_at_infinity`], for an anamorphic
    /// lens midway between its two meridians' (where the camera puts it).
    pub fn infinity_focus_z_mm(&self, height_mm: f64) -> Result<f64> {
        self.between_meridians(|m| Ok(self.real_focus_at_infinity_in(height_mm, m)?.0))
    }

    /// Sensor position focusing an on-axis object point at `object_z` (in
    /// front of the lens), by a real ray meeting the front vertex plane at
    /// `height_mm` (for an anamorphic lens, midway between its meridians').
    pub fn real_image_z_mm(&self, object_z: f64, height_mm: f64) -> Result<f64> {
        if object_z >= self.front_z_mm() {
            return Err(Error::InvalidArgument(format!(
                "{}: the object must be in front of the lens",
                self.prescription.name
            )));
        }
        self.between_meridians(|m| {
            let ray = LensRay::between(
                DVec3::new(0.0, 0.0, object_z),
                m.across() * height_mm + DVec3::new(0.0, 0.0, self.front_z_mm()),
            );
            Ok(self.image_of(&ray, "object", m)?.1)
        })
    }

    /// The object distance (mm, from the sensor plane to the object, as a
    /// focus-distance scale reads) that a sensor at `sensor_depth_mm` focuses, by a
    /// real ray from the sensor's centre meeting the rear vertex plane at
    /// `height_mm`. `None` when nothing in front of the lens is in focus there
    /// (the sensor is nearer than the infinity focus). For an anamorphic
    /// lens, the distance whose two line foci `sensor_depth_mm` lies midway between:
    /// the inverse of [`LensSystem::sensor_depth_mm_for_focus_distance`].
    pub fn focus_distance_mm(&self, sensor_depth_mm: f64, height_mm: f64) -> Option<f64> {
        if self.is_rotationally_symmetric() {
            return self.focus_distance_in(sensor_depth_mm, height_mm, Meridian::Horizontal);
        }
        // Bisection in the object's vergence 1/d, which the sensor
        // position grows with: 0 is infinity.
        let sensor_at = |vergence: f64| self.sensor_depth_mm_for_focus_distance(1.0 / vergence, height_mm).ok();
        if sensor_depth_mm <= self.infinity_focus_z_mm(height_mm).ok()? {
            return None;
        }
        let focal = self.paraxial().ok()?.effective_focal_length_mm.abs();
        let (mut lo, mut hi) = (0.0, 1e-3 / focal);
        for doubling in 0.. {
            match sensor_at(hi) {
                Some(z) if z < sensor_depth_mm && doubling < 200 => (lo, hi) = (hi, 2.0 * hi),
                Some(_) => break,
                // Closer than the lens focuses: the answer lies below.
                None if doubling > 0 => break,
                None => return None,
            }
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            match sensor_at(mid) {
                Some(z) if z < sensor_depth_mm => lo = mid,
                _ => hi = mid,
            }
        }
        let distance = 2.0 / (lo + hi);
        (sensor_depth_mm - distance < self.front_z_mm()).then_some(distance)
    }

    /// [`LensSystem::focus_distance_mm`] by one real ray in `meridian`.
    fn focus_distance_in(&self, sensor_depth_mm: f64, height_mm: f64, meridian: Meridian) -> Option<f64> {
        let ray = LensRay::between(
            DVec3::new(0.0, 0.0, sensor_depth_mm),
            meridian.across() * height_mm + DVec3::new(0.0, 0.0, self.rear_z_mm()),
        );
        let out = self.trace(&ray, Direction::ToScene)?;
        // In focus only if the ray leaves heading toward the axis.
        if !out.heads_toward_axis(meridian) {
            return None;
        }
        let object_z = out.axis_crossing_z(meridian)?;
        (object_z < self.front_z_mm()).then_some(sensor_depth_mm - object_z)
    }

    /// The sensor position whose real-ray conjugate is `distance_mm` from the
    /// sensor plane: the inverse of [`LensSystem::focus_distance_mm`], by
    /// bisection (for an anamorphic lens, midway between the positions that
    /// focus each meridian).
    pub fn sensor_depth_mm_for_focus_distance(&self, distance_mm: f64, height_mm: f64) -> Result<f64> {
        self.between_meridians(|m| self.sensor_depth_mm_for_focus_distance_in(distance_mm, height_mm, m))
    }

    /// [`LensSystem::sensor_depth_mm_for_focus_distance`] in one meridian.
    fn sensor_depth_mm_for_focus_distance_in(
        &self,
        distance_mm: f64,
        height_mm: f64,
        meridian: Meridian,
    ) -> Result<f64> {
        let (infinity_z, _) = self.real_focus_at_infinity_in(height_mm, meridian)?;
        if !(distance_mm.is_finite() && distance_mm > 0.0) {
            return Err(Error::InvalidArgument(format!(
                "focus distance must be positive and finite, got {distance_mm} mm"
            )));
        }
        // Bracket: just behind the infinity focus the conjugate is very far;
        // moving the sensor back brings it closer.
        let focal = self.paraxial()?.effective_focal_length_mm.abs();
        let mut lo = infinity_z;
        let mut hi = infinity_z + 1e-3 * focal;
        let too_close = || {
            Error::InvalidArgument(format!(
                "{} cannot focus at {:.4} m",
                self.prescription.name,
                distance_mm * 1e-3
            ))
        };
        // At most 200 doublings, whatever the lens (extreme tables could make
        // the limits below NaN).
        for doubling in 0.. {
            if doubling == 200 {
                return Err(too_close());
            }
            match self.focus_distance_in(hi, height_mm, meridian) {
                Some(d) if d <= distance_mm => break,
                Some(_) => {
                    lo = hi;
                    hi = infinity_z + 2.0 * (hi - infinity_z);
                    if hi - infinity_z > 100.0 * focal {
                        return Err(too_close());
                    }
                }
                None if hi > infinity_z + focal => return Err(too_close()),
                None => {
                    lo = hi;
                    hi = infinity_z + 2.0 * (hi - infinity_z);
                }
            }
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            match self.focus_distance_in(mid, height_mm, meridian) {
                Some(d) if d <= distance_mm => hi = mid,
                _ => lo = mid,
            }
        }
        Ok(0.5 * (lo + hi))
    }
}

#[cfg(test)]
mod tests {
    use super::super::prescription::{LensPrescription, BUILTIN_LENSES};
    use super::super::system::test_support::*;
    use super::super::TableConvention;
    use super::*;

    /// A stop, then one biconvex element: radii ±100 mm, n = 1.5, 0.01 mm thick.
    fn thin_lens() -> LensSystem {
        let table = "0 0 0 20\n100 0.01 1.5 20\n-100 0 1 20\n";
        LensSystem::new(&LensPrescription::parse(table, "thin", TableConvention::ThicknessToNext).unwrap())
    }

    #[test]
    fn a_thin_element_follows_the_lensmaker_and_thin_lens_equations() {
        let lens = thin_lens();
        let (n, r1, r2, t) = (1.5, 100.0, -100.0, 0.01);
        // Thick-lens lensmaker's equation (Hecht, Optics, eq. 6.2): exact paraxially.
        let f = 1.0 / ((n - 1.0) * (1.0 / r1 - 1.0 / r2 + (n - 1.0) * t / (n * r1 * r2)));
        let p = lens.paraxial().unwrap();
        assert!(
            relative(p.effective_focal_length_mm, f) < 1e-12,
            "{} vs {f}",
            p.effective_focal_length_mm
        );
        // Gaussian lens equation 1/s + 1/s' = 1/f with real rays near the axis.
        for image_distance in [110.0, 150.0, 200.0, 400.0] {
            let sensor_depth_mm = lens.rear_z_mm() + image_distance;
            let to_object = lens.focus_distance_mm(sensor_depth_mm, 0.1).unwrap();
            let object_distance = to_object - image_distance - t;
            let lhs = 1.0 / object_distance + 1.0 / image_distance;
            assert!(
                relative(lhs, 1.0 / f) < 1e-4,
                "s' {image_distance}: 1/s + 1/s' = {lhs}, 1/f = {}",
                1.0 / f
            );
        }
    }

    #[test]
    fn focusing_round_trips() {
        // lentil 2004 is anamorphic: it focuses midway between its meridians.
        let names = BUILTIN_LENSES.iter().map(|(name, _)| *name).chain(["lentil:2004"]);
        for name in names {
            let lens = builtin(name);
            let infinity = lens.infinity_focus_z_mm(0.1).unwrap();
            let focal = lens.paraxial().unwrap().effective_focal_length_mm;
            // Objects from 6 f in front of the lens (a telephoto's closest
            // real focus is about 4 f from the sensor) to far away.
            for multiple in [6.0, 10.0, 40.0, 400.0, 4000.0] {
                let metres = (infinity - lens.front_z_mm() + multiple * focal) * 1e-3;
                let z = lens.sensor_depth_mm_for_focus_distance(metres * 1e3, 0.1).unwrap();
                assert!(z > infinity, "{name} at {metres} m");
                let back = lens.focus_distance_mm(z, 0.1).unwrap();
                assert!(relative(back, metres * 1e3) < 1e-6, "{name} at {metres} m: {back} mm");
                let [h, v] = Meridian::BOTH.map(|m| {
                    lens.sensor_depth_mm_for_focus_distance_in(metres * 1e3, 0.1, m)
                        .unwrap()
                });
                assert!(
                    (z - 0.5 * (h + v)).abs() < 1e-9,
                    "{name} at {metres} m: {z} between {h} and {v}"
                );
                assert_eq!(lens.is_rotationally_symmetric(), h == v, "{name}");
            }
            assert_eq!(
                lens.focus_distance_mm(infinity - 0.01, 0.1),
                None,
                "{name}: beyond infinity"
            );
        }
    }
}
