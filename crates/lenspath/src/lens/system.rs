//! A lens prescription placed on its optical axis, ready to trace: each
//! surface's vertex, intersection rule, clear aperture and indices at one
//! wavelength. Tracing is in [`super::trace`], the paraxial trace in
//! [`super::paraxial`], focusing in [`super::focusing`].
//!
//! Lens coordinates, in mm, f64 throughout: `z` runs along the optical axis
//! from the scene toward the sensor with the aperture stop at `z = 0`, so
//! sensor positions are distances behind the stop (the CS184 lens
//! simulator's convention); `x` and `y` are across the axis.

use glam::DVec3;

use super::prescription::{LensPrescription, LensSurface};
use super::surface::{CylinderAxis, EvenAsphere, Meridian, SurfaceShape, Toric, Vertex};
use crate::error::{Error, Result};
use crate::glass::D_LINE_NM;

/// A ray in lens coordinates (mm) with a unit direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LensRay {
    /// Origin.
    pub origin: DVec3,
    /// Unit direction.
    pub direction: DVec3,
}

impl LensRay {
    /// The ray from `origin` toward `target`.
    pub fn between(origin: DVec3, target: DVec3) -> LensRay {
        LensRay {
            origin,
            direction: (target - origin).normalize(),
        }
    }

    /// Where the ray (as a line) meets the axial plane at `z`, if it is not parallel to it.
    pub fn at_z(&self, z: f64) -> Option<DVec3> {
        (self.direction.z != 0.0).then(|| self.origin + self.direction * ((z - self.origin.z) / self.direction.z))
    }

    /// The `z` where the ray (as a line) crosses the axis in `meridian` (for
    /// rays in that plane), if it is not parallel to the axis.
    pub fn axis_crossing_z(&self, meridian: Meridian) -> Option<f64> {
        let (height, slope) = (meridian.component(self.origin), meridian.component(self.direction));
        (slope != 0.0).then(|| self.origin.z - height * self.direction.z / slope)
    }

    /// Whether the ray heads toward the axis in `meridian` (its height and
    /// slope there have opposite signs): only then does it form a real
    /// image (or object) where it crosses it.
    pub fn heads_toward_axis(&self, meridian: Meridian) -> bool {
        meridian.component(self.origin) * meridian.component(self.direction) < 0.0
    }
}

/// Which way light goes through the lens.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    /// From the scene through the front element to the sensor.
    ToSensor,
    /// From the sensor through the rear element out into the scene.
    ToScene,
}

/// How a surface is intersected.
#[derive(Clone, Copy, Debug)]
pub(super) enum Intersection {
    /// A plane between equal indices (the stop; a flat in air): it clips
    /// but bends nothing, so a ray is tested where its line crosses the
    /// plane and goes on from where it was. Lens files put the stop on a
    /// curved surface's vertex, whose rim then lies beyond the plane: the
    /// ray meets that surface before (or after) the plane along its line.
    Aperture,
    /// A flat between different indices: the plane of the vertex.
    Plane,
    /// A sphere of the surface's radius.
    Sphere,
    /// An even asphere, by Newton's method from the vertex sphere's hit.
    Asphere(EvenAsphere),
    /// A cylinder of the surface's radius with its axis along the given direction.
    Cylinder(CylinderAxis),
    /// A toric surface, by Newton's method from its unbent cylinder's hit.
    Toric(Toric),
}

/// One surface on the axis.
#[derive(Clone, Copy, Debug)]
pub(super) struct Surface {
    /// Its vertex on the axis and vertex radius.
    pub(super) vertex: Vertex,
    /// How to find a ray's hit.
    pub(super) intersection: Intersection,
    /// Vertex curvature as paraxial optics sees it (with an asphere's A₂)
    /// in the horizontal and the vertical meridian, 1/mm.
    pub(super) paraxial_curvature: [f64; 2],
    /// Clear aperture radius (for the stop: the current, possibly stopped-down, radius).
    pub(super) aperture_radius: f64,
    /// Index in front of (scene side) and behind (sensor side) the surface.
    pub(super) ior_front: f64,
    pub(super) ior_back: f64,
    /// The index ratios n₁/n₂ each way, precomputed for tracing.
    pub(super) eta_to_sensor: f64,
    pub(super) eta_to_scene: f64,
    /// Whether light meets this surface moving toward +z, going to the
    /// sensor and going to the scene: which cap of a sphere it meets, which
    /// way it must cross a stop. Set from the vertices' order
    /// ([`set_senses_of_travel`]), not from the direction alone, so a lens
    /// whose surfaces run toward −z (negative thicknesses) traces as well.
    pub(super) arrives_toward_positive_z_to_sensor: bool,
    pub(super) arrives_toward_positive_z_to_scene: bool,
}

impl Surface {
    /// The sense in which light going `direction` meets this surface.
    #[inline(always)]
    pub(super) fn arrives_toward_positive_z(&self, direction: Direction) -> bool {
        match direction {
            Direction::ToSensor => self.arrives_toward_positive_z_to_sensor,
            Direction::ToScene => self.arrives_toward_positive_z_to_scene,
        }
    }
}

/// Sets each surface's sense of arrival from the vertices' order. Light
/// going to the sensor crosses each gap from one vertex toward the next, so
/// the gap's sign is its sense there (and light going to the scene crosses
/// it the other way); a gap of no length (a stop on a vertex) keeps the
/// sense before it, and light enters the lens in the sense of its first gap.
fn set_senses_of_travel(surfaces: &mut [Surface]) {
    let gap_sense = |k: usize| {
        let gap = surfaces[k + 1].vertex.z_mm - surfaces[k].vertex.z_mm;
        (gap != 0.0 && !gap.is_nan()).then_some(gap > 0.0)
    };
    let gaps: Vec<Option<bool>> = (0..surfaces.len().saturating_sub(1)).map(gap_sense).collect();
    let mut sense = gaps.iter().flatten().next().copied().unwrap_or(true);
    for (k, surface) in surfaces.iter_mut().enumerate() {
        surface.arrives_toward_positive_z_to_sensor = sense;
        if let Some(Some(leaving)) = gaps.get(k) {
            sense = *leaving;
        }
        surface.arrives_toward_positive_z_to_scene = !sense;
    }
}

/// A lens ready to trace, at one wavelength: each glass's index is the
/// one it has there ([`LensSystem::new`] is the d line; see
/// [`LensSystem::at_wavelength`]).
#[derive(Clone, Debug)]
pub struct LensSystem {
    pub(super) prescription: LensPrescription,
    pub(super) surfaces: Vec<Surface>,
    pub(super) stop: usize,
    wavelength_nm: f64,
}

impl LensSystem {
    /// Places `prescription` on the axis with its stop at z = 0, wide open,
    /// at the d line (587.56 nm), where tables give their indices.
    pub fn new(prescription: &LensPrescription) -> LensSystem {
        Self::placed(prescription, D_LINE_NM)
    }

    /// This lens (stopped down as it is) at `wavelength_nm`: every glass at
    /// its index there. The same lens when no glass disperses.
    pub fn at_wavelength(&self, wavelength_nm: f64) -> LensSystem {
        let mut system = Self::placed(&self.prescription, wavelength_nm);
        for (s, mine) in system.surfaces.iter_mut().zip(&self.surfaces) {
            s.aperture_radius = mine.aperture_radius;
        }
        system
    }

    /// The wavelength, nm, it is traced at.
    pub fn wavelength_nm(&self) -> f64 {
        self.wavelength_nm
    }

    /// True when some glass's index changes with wavelength.
    pub fn is_dispersive(&self) -> bool {
        self.prescription.is_dispersive()
    }

    /// False for an anamorphic lens (one with a cylindrical surface).
    pub fn is_rotationally_symmetric(&self) -> bool {
        self.prescription.is_rotationally_symmetric()
    }

    fn placed(prescription: &LensPrescription, wavelength_nm: f64) -> LensSystem {
        let stop = prescription.stop_index();
        let before_stop: f64 = prescription.surfaces[..stop].iter().map(|s| s.thickness_mm).sum();
        let mut z = -before_stop;
        let mut ior_front = 1.0;
        let mut surfaces = prescription
            .surfaces
            .iter()
            .map(|s| {
                let ior = s.medium.index(wavelength_nm);
                // A flat cylinder is a plane too.
                let flat =
                    s.curvature() == 0.0 && !matches!(s.shape, SurfaceShape::EvenAsphere(_) | SurfaceShape::Toric(_));
                let intersection = match s.shape {
                    _ if flat && ior == ior_front => Intersection::Aperture,
                    _ if flat => Intersection::Plane,
                    SurfaceShape::Spherical => Intersection::Sphere,
                    SurfaceShape::EvenAsphere(asphere) => Intersection::Asphere(asphere),
                    SurfaceShape::Cylindrical(axis) => Intersection::Cylinder(axis),
                    SurfaceShape::Toric(toric) => Intersection::Toric(toric),
                };
                let surface = Surface {
                    vertex: Vertex {
                        z_mm: z,
                        radius_mm: s.radius_mm,
                        inv_abs_radius: s.curvature().abs(),
                    },
                    intersection,
                    paraxial_curvature: Meridian::BOTH.map(|m| s.shape.paraxial_curvature(s.curvature(), m)),
                    aperture_radius: 0.5 * s.aperture_diameter_mm,
                    ior_front,
                    ior_back: ior,
                    eta_to_sensor: ior_front / ior,
                    eta_to_scene: ior / ior_front,
                    arrives_toward_positive_z_to_sensor: true,
                    arrives_toward_positive_z_to_scene: false,
                };
                z += s.thickness_mm;
                ior_front = ior;
                surface
            })
            .collect::<Vec<_>>();
        set_senses_of_travel(&mut surfaces);
        LensSystem {
            prescription: prescription.clone(),
            surfaces,
            stop,
            wavelength_nm,
        }
    }

    /// The prescription this system was built from.
    pub fn prescription(&self) -> &LensPrescription {
        &self.prescription
    }

    /// Front vertex position.
    pub fn front_z_mm(&self) -> f64 {
        self.surfaces[0].vertex.z_mm
    }

    /// Rear vertex position.
    pub fn rear_z_mm(&self) -> f64 {
        self.surfaces[self.surfaces.len() - 1].vertex.z_mm
    }

    /// Clear aperture radius of the rear element.
    pub fn rear_aperture_radius_mm(&self) -> f64 {
        self.surfaces[self.surfaces.len() - 1].aperture_radius
    }

    /// Clear aperture radius of the front element.
    pub fn front_aperture_radius_mm(&self) -> f64 {
        self.surfaces[0].aperture_radius
    }

    /// Current radius of the aperture stop, mm.
    pub fn stop_radius_mm(&self) -> f64 {
        self.surfaces[self.stop].aperture_radius
    }

    /// The surfaces as (vertex z, the prescription's surface, clear aperture
    /// radius as stopped now, index behind), front to back.
    pub fn surface_layout(&self) -> impl Iterator<Item = (f64, &LensSurface, f64, f64)> + '_ {
        self.surfaces
            .iter()
            .zip(self.prescription.surfaces())
            .map(|(s, given)| (s.vertex.z_mm, given, s.aperture_radius, s.ior_back))
    }

    /// The same lens stopped down (or opened up to its full aperture) to the
    /// paraxial f-number `f_number`; fails when the lens cannot open that wide.
    pub fn with_f_number(&self, f_number: f64) -> Result<LensSystem> {
        let wide_open = Self::placed(&self.prescription, self.wavelength_nm);
        let data = wide_open.paraxial()?;
        if !(f_number.is_finite() && f_number > 0.0) {
            return Err(Error::InvalidArgument(format!(
                "f-number must be positive, got {f_number}"
            )));
        }
        if f_number < data.f_number * (1.0 - 1e-9) {
            return Err(Error::InvalidArgument(format!(
                "f/{f_number} is faster than {} opens (f/{:.2} wide open)",
                self.prescription.name, data.f_number
            )));
        }
        // The entrance pupil scales with the stop (paraxial imaging is linear).
        let mut system = wide_open;
        system.surfaces[system.stop].aperture_radius *= data.f_number / f_number;
        Ok(system)
    }
}

#[cfg(test)]
pub(super) mod test_support {
    //! What the lens module's tests share.
    use super::*;
    impl LensRay {
        /// The ray from (x, y) = `start`, 50 mm in front of `lens`'s front
        /// vertex, along (`slope`, 1): how the tests launch the skew rays they
        /// compare with rayoptics (`bench/peers/lens_vs_rayoptics.py`).
        pub(crate) fn skew(lens: &LensSystem, start: [f64; 2], slope: [f64; 2]) -> LensRay {
            LensRay {
                origin: DVec3::new(start[0], start[1], lens.front_z_mm() - 50.0),
                direction: DVec3::new(slope[0], slope[1], 1.0).normalize(),
            }
        }
    }

    pub(crate) fn builtin(name: &str) -> LensSystem {
        LensSystem::new(&LensPrescription::load(name).unwrap())
    }

    pub(crate) fn relative(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }
}

#[cfg(test)]
mod tests {
    use super::test_support::*;
    use super::*;

    /// Found by fuzzing (fuzz/lens_table): focusing a lens of extreme
    /// numbers used to search for its bracket forever. It must end, with an
    /// answer or an error, and nothing may panic. The found table
    /// (`0 37 0 8.` / `-9.58584 22.E88 51 3.1`) now fails validation (it
    /// leaves the sensor in glass), so its surfaces are built directly here;
    /// the bound on the search stays as a second line of defence.
    #[test]
    fn extreme_lenses_end_in_an_answer_or_an_error() {
        let surface = |radius_mm, thickness_mm, ior, aperture_diameter_mm| LensSurface {
            radius_mm,
            shape: SurfaceShape::Spherical,
            thickness_mm,
            medium: crate::glass::Dispersion::Constant(ior),
            aperture_diameter_mm,
        };
        let lenses = [
            // The fuzz find, read with thickness-to-next and with distance-from-previous columns.
            vec![surface(0.0, 37.0, 1.0, 8.0), surface(-9.58584, 22e88, 51.0, 3.1)],
            vec![surface(0.0, 22e88, 1.0, 8.0), surface(-9.58584, 0.0, 51.0, 3.1)],
            vec![
                surface(1e300, 1.0, 1.5, 10.0),
                surface(0.0, 1.0, 1.0, 5.0),
                surface(-1e300, 0.0, 1.0, 10.0),
            ],
            vec![
                surface(5.0, 1e300, 1.5, 2.0),
                surface(0.0, 1.0, 1.0, 1.0),
                surface(-5.0, 0.0, 1.0, 2.0),
            ],
        ];
        for surfaces in lenses {
            let lens = LensSystem::new(&LensPrescription {
                name: "extreme".into(),
                columns: surfaces.iter().map(|s| (s.ior_d(), None)).collect(),
                surfaces,
            });
            let _ = crate::lens::LensAnalysis::new(&lens, &crate::lens::AnalysisSettings::default());
            let _ = lens.sensor_depth_mm_for_focus_distance(2000.0, 0.1);
            let _ = lens.with_f_number(8.0);
        }
    }

    #[test]
    fn stopping_down_scales_the_pupils() {
        let lens = builtin("dgauss50");
        let open = lens.paraxial().unwrap();
        let f8 = lens.with_f_number(8.0).unwrap().paraxial().unwrap();
        assert!(relative(f8.f_number, 8.0) < 1e-12);
        assert!(
            relative(
                f8.exit_pupil_diameter_mm / open.exit_pupil_diameter_mm,
                open.f_number / 8.0
            ) < 1e-12
        );
        let err = lens.with_f_number(1.4).unwrap_err().to_string();
        assert!(err.contains("f/1.4 is faster than dgauss50"), "{err}");
    }
}
