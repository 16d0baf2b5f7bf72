//! The paraxial (first-order) trace of a placed lens: focal length,
//! principal planes, pupils and f-number in each meridian, and the
//! paraxial chief ray for lateral colour.

use super::surface::Meridian;
use super::system::{Direction, LensSystem};
use crate::error::{Error, Result};

/// A paraxial ray in travel coordinates: position along the travel direction, height, slope.
#[derive(Clone, Copy, Debug)]
struct ParaxialRay {
    z: f64,
    y: f64,
    u: f64,
}

/// First-order (paraxial) data, lengths in mm in lens coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParaxialData {
    /// Effective focal length (P′ to F′).
    pub effective_focal_length_mm: f64,
    /// Rear vertex to rear focal point F′.
    pub back_focal_distance_mm: f64,
    /// Front focal point F to front vertex.
    pub front_focal_distance_mm: f64,
    /// Rear focal point F′.
    pub rear_focal_point_z_mm: f64,
    /// Front focal point F.
    pub front_focal_point_z_mm: f64,
    /// Rear principal plane P′.
    pub rear_principal_plane_z_mm: f64,
    /// Front principal plane P.
    pub front_principal_plane_z_mm: f64,
    /// Entrance pupil (image of the stop seen from the scene).
    pub entrance_pupil_z_mm: f64,
    /// Entrance pupil diameter.
    pub entrance_pupil_diameter_mm: f64,
    /// Exit pupil (image of the stop seen from the sensor).
    pub exit_pupil_z_mm: f64,
    /// Exit pupil diameter.
    pub exit_pupil_diameter_mm: f64,
    /// Focal length over entrance pupil diameter (for an object at infinity).
    pub f_number: f64,
}

impl LensSystem {
    /// How many times more of the scene's width than of its height the lens
    /// takes in per mm of sensor: its vertical over its horizontal paraxial
    /// focal length (1 for a rotationally symmetric lens; 2 for a "2×"
    /// anamorphic). Stretching an image's width by it desqueezes it.
    pub fn squeeze(&self) -> Result<f64> {
        if self.is_rotationally_symmetric() {
            return Ok(1.0);
        }
        let [horizontal, vertical] = Meridian::BOTH.map(|m| self.paraxial_in(m).map(|p| p.effective_focal_length_mm));
        Ok(vertical? / horizontal?)
    }

    /// Surfaces in travel order as (position along travel, signed paraxial
    /// curvature in `meridian` in travel coordinates, index before, index after).
    /// Travelling toward the scene mirrors the axis, which flips the curvatures.
    fn travel_sequence(
        &self,
        direction: Direction,
        range: std::ops::Range<usize>,
        meridian: Meridian,
    ) -> Vec<(f64, f64, f64, f64)> {
        let m = meridian as usize;
        let mut seq: Vec<_> = self.surfaces[range]
            .iter()
            .map(|s| match direction {
                Direction::ToSensor => (s.vertex.z_mm, s.paraxial_curvature[m], s.ior_front, s.ior_back),
                Direction::ToScene => (-s.vertex.z_mm, -s.paraxial_curvature[m], s.ior_back, s.ior_front),
            })
            .collect();
        if direction == Direction::ToScene {
            seq.reverse();
        }
        seq
    }

    /// The paraxial (y–nu) trace: transfer `y += d·u`, refraction
    /// `n′u′ = n·u − y·(n′ − n)·c` (Smith, *Modern Optical Engineering*, ch. 2).
    fn paraxial_trace(seq: &[(f64, f64, f64, f64)], mut ray: ParaxialRay) -> ParaxialRay {
        for &(z, curvature, n1, n2) in seq {
            ray.y += (z - ray.z) * ray.u;
            ray.z = z;
            ray.u = (n1 * ray.u - ray.y * (n2 - n1) * curvature) / n2;
        }
        ray
    }

    /// First-order data from paraxial traces: in the horizontal meridian,
    /// which for a rotationally symmetric lens is every meridian (see
    /// [`LensSystem::paraxial_in`] for an anamorphic lens's other one).
    pub fn paraxial(&self) -> Result<ParaxialData> {
        self.paraxial_in(Meridian::Horizontal)
    }

    /// First-order data in `meridian`, from paraxial traces there.
    pub fn paraxial_in(&self, meridian: Meridian) -> Result<ParaxialData> {
        let all = 0..self.surfaces.len();
        // A ray parallel to the axis at unit height, each way.
        let focal = |direction: Direction| -> Result<(f64, f64)> {
            let seq = self.travel_sequence(direction, all.clone(), meridian);
            let start = ParaxialRay {
                z: seq[0].0,
                y: 1.0,
                u: 0.0,
            };
            let out = Self::paraxial_trace(&seq, start);
            if out.u == 0.0 {
                return Err(Error::InvalidArgument(format!(
                    "{} is afocal (parallel light leaves parallel)",
                    self.prescription.name
                )));
            }
            // Focal point: where the exit ray meets the axis; principal plane: where it is at height 1.
            Ok((out.z - out.y / out.u, out.z + (1.0 - out.y) / out.u))
        };
        let (rear_focal, rear_principal) = focal(Direction::ToSensor)?;
        let (front_focal, front_principal) = focal(Direction::ToScene)?;
        // Pupils: images of the stop through the elements on either side.
        let pupil = |direction: Direction| {
            let range = match direction {
                Direction::ToSensor => self.stop + 1..self.surfaces.len(),
                Direction::ToScene => 0..self.stop,
            };
            let seq = self.travel_sequence(direction, range, meridian);
            let r = self.stop_radius_mm();
            let chief = Self::paraxial_trace(&seq, ParaxialRay { z: 0.0, y: 0.0, u: 1.0 });
            let edge = Self::paraxial_trace(&seq, ParaxialRay { z: 0.0, y: r, u: 0.0 });
            let z = chief.z - chief.y / chief.u;
            let radius = (edge.y + (z - edge.z) * edge.u).abs();
            (z, 2.0 * radius)
        };
        let (exit_z, exit_d) = pupil(Direction::ToSensor);
        let (entrance_z, entrance_d) = pupil(Direction::ToScene);
        let efl = rear_focal - rear_principal;
        Ok(ParaxialData {
            effective_focal_length_mm: efl,
            back_focal_distance_mm: rear_focal - self.rear_z_mm(),
            front_focal_distance_mm: self.front_z_mm() + front_focal,
            rear_focal_point_z_mm: rear_focal,
            front_focal_point_z_mm: -front_focal,
            rear_principal_plane_z_mm: rear_principal,
            front_principal_plane_z_mm: -front_principal,
            entrance_pupil_z_mm: -entrance_z,
            entrance_pupil_diameter_mm: entrance_d,
            exit_pupil_z_mm: exit_z,
            exit_pupil_diameter_mm: exit_d,
            f_number: efl / entrance_d,
        })
    }

    /// Height on the plane `image_z_mm` of the paraxial chief ray (the ray
    /// through the centre of the stop) from an object at infinity at a field
    /// angle whose tangent is `tan_field`. Compared across wavelengths on one
    /// plane it is the lateral colour (Smith, *Modern Optical Engineering*, §10.4).
    pub fn paraxial_chief_ray_height(&self, tan_field: f64, image_z_mm: f64) -> f64 {
        // Toward the scene the axis is mirrored: a stop slope of 1 toward
        // the sensor starts as −1, and the object-space slope is −u out.
        let front = self.travel_sequence(Direction::ToScene, 0..self.stop, Meridian::Horizontal);
        let object = Self::paraxial_trace(
            &front,
            ParaxialRay {
                z: 0.0,
                y: 0.0,
                u: -1.0,
            },
        );
        let scale = tan_field / -object.u;
        let back = self.travel_sequence(
            Direction::ToSensor,
            self.stop + 1..self.surfaces.len(),
            Meridian::Horizontal,
        );
        let image = Self::paraxial_trace(
            &back,
            ParaxialRay {
                z: 0.0,
                y: 0.0,
                u: scale,
            },
        );
        image.y + (image_z_mm - image.z) * image.u
    }
}

#[cfg(test)]
mod tests {
    use super::super::prescription::{LensPrescription, BUILTIN_LENSES};
    use super::super::system::test_support::*;
    use super::*;

    #[test]
    fn builtin_focal_lengths_are_as_named() {
        for (name, focal) in [
            ("dgauss50", 50.0),
            ("wide22", 22.0),
            ("tele250", 250.0),
            ("fisheye10", 10.0),
        ] {
            let efl = builtin(name).paraxial().unwrap().effective_focal_length_mm;
            assert!(relative(efl, focal) < 0.02, "{name}: {efl} mm");
        }
    }

    /// The system matrix as a product of 2×2 refraction and transfer
    /// matrices on (y, n·u) (Gerrard & Burch, *Introduction to Matrix Methods in Optics*).
    fn abcd(lens: &LensPrescription) -> [[f64; 2]; 2] {
        let mul = |a: [[f64; 2]; 2], b: [[f64; 2]; 2]| {
            [
                [
                    a[0][0] * b[0][0] + a[0][1] * b[1][0],
                    a[0][0] * b[0][1] + a[0][1] * b[1][1],
                ],
                [
                    a[1][0] * b[0][0] + a[1][1] * b[1][0],
                    a[1][0] * b[0][1] + a[1][1] * b[1][1],
                ],
            ]
        };
        let mut m = [[1.0, 0.0], [0.0, 1.0]];
        let mut n_before = 1.0;
        let last = lens.surfaces.len() - 1;
        for (i, s) in lens.surfaces.iter().enumerate() {
            let power = if s.is_stop() {
                0.0
            } else {
                (s.ior_d() - n_before) / s.radius_mm
            };
            m = mul([[1.0, 0.0], [-power, 1.0]], m);
            if i < last {
                m = mul([[1.0, s.thickness_mm / s.ior_d()], [0.0, 1.0]], m);
            }
            n_before = s.ior_d();
        }
        m
    }

    #[test]
    fn paraxial_data_match_an_abcd_product() {
        for (name, _) in BUILTIN_LENSES {
            let prescription = LensPrescription::load(name).unwrap();
            let [[a, _], [c, d]] = abcd(&prescription);
            let p = LensSystem::new(&prescription).paraxial().unwrap();
            let checks = [
                ("EFL", p.effective_focal_length_mm, -1.0 / c),
                ("BFD", p.back_focal_distance_mm, -a / c),
                ("FFD", p.front_focal_distance_mm, -d / c),
            ];
            for (what, ours, matrix) in checks {
                assert!(relative(ours, matrix) < 1e-9, "{name} {what}: {ours} vs {matrix}");
            }
        }
    }
}
