//! A lens prescription placed on its optical axis: exact ray tracing through
//! every surface in both directions, the paraxial (y–nu) trace, and focusing.
//!
//! Lens coordinates, in mm, f64 throughout: `z` runs along the optical axis
//! from the scene toward the sensor with the aperture stop at `z = 0`, so
//! sensor positions are distances behind the stop (the CS184 lens
//! simulator's convention); `x` and `y` are across the axis.

use glam::DVec3;

use super::prescription::{LensPrescription, LensSurface};
use super::surface::{
    intersect_by_newton, intersect_even_asphere, CylinderAxis, EvenAsphere, Meridian, SurfaceShape, Toric,
};
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
enum Intersection {
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
struct Surface {
    /// Vertex position on the axis.
    z: f64,
    /// Signed vertex radius (0: the stop; infinite: a flat).
    radius: f64,
    /// How to find a ray's hit.
    intersection: Intersection,
    /// Vertex curvature as paraxial optics sees it (with an asphere's A₂)
    /// in the horizontal and the vertical meridian, 1/mm.
    paraxial_curvature: [f64; 2],
    /// Clear aperture radius (for the stop: the current, possibly stopped-down, radius).
    aperture_radius: f64,
    /// Index in front of (scene side) and behind (sensor side) the surface.
    ior_front: f64,
    ior_back: f64,
    /// Precomputed for tracing: 1/|radius| and the index ratios n₁/n₂ each way.
    inv_abs_radius: f64,
    eta_to_sensor: f64,
    eta_to_scene: f64,
}

/// A lens ready to trace, at one wavelength: each glass's index is the
/// one it has there ([`LensSystem::new`] is the d line; see
/// [`LensSystem::at_wavelength`]).
#[derive(Clone, Debug)]
pub struct LensSystem {
    prescription: LensPrescription,
    surfaces: Vec<Surface>,
    stop: usize,
    wavelength_nm: f64,
}

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

    fn placed(prescription: &LensPrescription, wavelength_nm: f64) -> LensSystem {
        let stop = prescription.stop_index();
        let before_stop: f64 = prescription.surfaces[..stop].iter().map(|s| s.thickness_mm).sum();
        let mut z = -before_stop;
        let mut ior_front = 1.0;
        let surfaces = prescription
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
                    z,
                    radius: s.radius_mm,
                    intersection,
                    paraxial_curvature: Meridian::BOTH.map(|m| s.shape.paraxial_curvature(s.curvature(), m)),
                    aperture_radius: 0.5 * s.aperture_diameter_mm,
                    ior_front,
                    ior_back: ior,
                    inv_abs_radius: s.curvature().abs(),
                    eta_to_sensor: ior_front / ior,
                    eta_to_scene: ior / ior_front,
                };
                z += s.thickness_mm;
                ior_front = ior;
                surface
            })
            .collect();
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
    pub fn front_z(&self) -> f64 {
        self.surfaces[0].z
    }

    /// Rear vertex position.
    pub fn rear_z(&self) -> f64 {
        self.surfaces[self.surfaces.len() - 1].z
    }

    /// Clear aperture radius of the rear element.
    pub fn rear_aperture_radius(&self) -> f64 {
        self.surfaces[self.surfaces.len() - 1].aperture_radius
    }

    /// Clear aperture radius of the front element.
    pub fn front_aperture_radius(&self) -> f64 {
        self.surfaces[0].aperture_radius
    }

    /// Current radius of the aperture stop, mm.
    pub fn stop_radius(&self) -> f64 {
        self.surfaces[self.stop].aperture_radius
    }

    /// The surfaces as (vertex z, the prescription's surface, clear aperture
    /// radius as stopped now, index behind), front to back.
    pub fn surface_layout(&self) -> impl Iterator<Item = (f64, &LensSurface, f64, f64)> + '_ {
        self.surfaces
            .iter()
            .zip(self.prescription.surfaces())
            .map(|(s, given)| (s.z, given, s.aperture_radius, s.ior_back))
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

    /// Traces `ray` through every surface in `direction`. `None` when the ray
    /// misses a surface, is clipped by an aperture or the stop, or is totally
    /// internally reflected. The returned ray starts on the last surface crossed.
    pub fn trace(&self, ray: &LensRay, direction: Direction) -> Option<LensRay> {
        self.trace_visiting(ray, direction, |_| {})
    }

    /// [`LensSystem::trace`], calling `visit` with each point where the ray
    /// meets a surface (also the one where it is blocked, if it reaches it).
    pub fn trace_visiting(&self, ray: &LensRay, direction: Direction, mut visit: impl FnMut(DVec3)) -> Option<LensRay> {
        let mut ray = *ray;
        for k in 0..self.surfaces.len() {
            ray = self.cross(self.surface_in_travel_order(k, direction), &ray, direction, &mut visit)?;
        }
        Some(ray)
    }

    /// [`LensSystem::trace`], also returning where the ray crossed the
    /// aperture stop (what a shaped aperture's transmission is read at).
    pub fn trace_via_stop(&self, ray: &LensRay, direction: Direction) -> Option<(LensRay, DVec3)> {
        let stop_in_travel = match direction {
            Direction::ToSensor => self.stop,
            Direction::ToScene => self.surfaces.len() - 1 - self.stop,
        };
        let (mut crossed, mut at_stop) = (0, DVec3::ZERO);
        let out = self.trace_visiting(ray, direction, |p| {
            if crossed == stop_in_travel {
                at_stop = p;
            }
            crossed += 1;
        })?;
        Some((out, at_stop))
    }

    /// One ray through each of `systems` (one lens, or the same lens at
    /// different wavelengths as [`LensSystem::at_wavelength`] makes them),
    /// all at once. Their arithmetic chains are independent, so the
    /// processor overlaps them: tracing is bound by the latency of square
    /// roots, not by their throughput.
    pub fn trace_each<const N: usize>(
        systems: [&LensSystem; N],
        rays: &[LensRay; N],
        direction: Direction,
    ) -> [Option<LensRay>; N] {
        let surfaces = systems[0].surfaces.len();
        debug_assert!(systems.iter().all(|s| s.surfaces.len() == surfaces));
        let mut out = rays.map(Some);
        for k in 0..surfaces {
            for (ray, system) in out.iter_mut().zip(systems) {
                if let Some(r) = ray {
                    *ray = system.cross(system.surface_in_travel_order(k, direction), r, direction, &mut |_| {});
                }
            }
        }
        out
    }

    #[inline(always)]
    fn surface_in_travel_order(&self, k: usize, direction: Direction) -> &Surface {
        match direction {
            Direction::ToSensor => &self.surfaces[k],
            Direction::ToScene => &self.surfaces[self.surfaces.len() - 1 - k],
        }
    }

    /// Carries `ray` across one surface: intersection, aperture clipping, refraction.
    #[inline(always)]
    fn cross(
        &self,
        surface: &Surface,
        ray: &LensRay,
        direction: Direction,
        visit: &mut impl FnMut(DVec3),
    ) -> Option<LensRay> {
        let (t, normal) = match &surface.intersection {
            Intersection::Aperture => {
                let forward = match direction {
                    Direction::ToSensor => ray.direction.z > 0.0,
                    Direction::ToScene => ray.direction.z < 0.0,
                };
                if !forward {
                    return None;
                }
                let p = ray.origin + ray.direction * ((surface.z - ray.origin.z) / ray.direction.z);
                visit(p);
                let inside = p.x * p.x + p.y * p.y <= surface.aperture_radius * surface.aperture_radius;
                return inside.then_some(*ray);
            }
            Intersection::Plane => ((surface.z - ray.origin.z) / ray.direction.z, DVec3::Z),
            Intersection::Sphere => intersect_sphere(ray, surface, direction)?,
            Intersection::Asphere(asphere) => intersect_asphere(ray, surface, asphere, direction)?,
            Intersection::Cylinder(axis) => intersect_cylinder(ray, surface, *axis, direction)?,
            Intersection::Toric(toric) => intersect_toric(ray, surface, toric, direction)?,
        };
        // Also rejects NaN (a tangent ray).
        if t.is_nan() || t <= 0.0 {
            return None;
        }
        let p = ray.origin + ray.direction * t;
        visit(p);
        if p.x * p.x + p.y * p.y > surface.aperture_radius * surface.aperture_radius {
            return None;
        }
        let eta = match direction {
            Direction::ToSensor => surface.eta_to_sensor,
            Direction::ToScene => surface.eta_to_scene,
        };
        let direction = if eta == 1.0 {
            ray.direction
        } else {
            refract(ray.direction, normal, eta)?
        };
        Some(LensRay { origin: p, direction })
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
                Direction::ToSensor => (s.z, s.paraxial_curvature[m], s.ior_front, s.ior_back),
                Direction::ToScene => (-s.z, -s.paraxial_curvature[m], s.ior_back, s.ior_front),
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
            let r = self.stop_radius();
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
            back_focal_distance_mm: rear_focal - self.rear_z(),
            front_focal_distance_mm: self.front_z() + front_focal,
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
        let start = meridian.across() * height_mm + DVec3::new(0.0, 0.0, self.front_z() - 1.0);
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
    pub fn infinity_focus_z(&self, height_mm: f64) -> Result<f64> {
        self.between_meridians(|m| Ok(self.real_focus_at_infinity_in(height_mm, m)?.0))
    }

    /// Sensor position focusing an on-axis object point at `object_z` (in
    /// front of the lens), by a real ray meeting the front vertex plane at
    /// `height_mm` (for an anamorphic lens, midway between its meridians').
    pub fn real_image_z(&self, object_z: f64, height_mm: f64) -> Result<f64> {
        if object_z >= self.front_z() {
            return Err(Error::InvalidArgument(format!(
                "{}: the object must be in front of the lens",
                self.prescription.name
            )));
        }
        self.between_meridians(|m| {
            let ray = LensRay::between(
                DVec3::new(0.0, 0.0, object_z),
                m.across() * height_mm + DVec3::new(0.0, 0.0, self.front_z()),
            );
            Ok(self.image_of(&ray, "object", m)?.1)
        })
    }

    /// The object distance (mm, from the sensor plane to the object, as a
    /// focus-distance scale reads) that a sensor at `sensor_z` focuses, by a
    /// real ray from the sensor's centre meeting the rear vertex plane at
    /// `height_mm`. `None` when nothing in front of the lens is in focus there
    /// (the sensor is nearer than the infinity focus). For an anamorphic
    /// lens, the distance whose two line foci `sensor_z` lies midway between:
    /// the inverse of [`LensSystem::sensor_z_for_focus_distance`].
    pub fn focus_distance_mm(&self, sensor_z: f64, height_mm: f64) -> Option<f64> {
        if self.is_rotationally_symmetric() {
            return self.focus_distance_in(sensor_z, height_mm, Meridian::Horizontal);
        }
        // Bisection in the object's vergence 1/d, which the sensor
        // position grows with: 0 is infinity.
        let sensor_at = |vergence: f64| self.sensor_z_for_focus_distance(1.0 / vergence, height_mm).ok();
        if sensor_z <= self.infinity_focus_z(height_mm).ok()? {
            return None;
        }
        let focal = self.paraxial().ok()?.effective_focal_length_mm.abs();
        let (mut lo, mut hi) = (0.0, 1e-3 / focal);
        for doubling in 0.. {
            match sensor_at(hi) {
                Some(z) if z < sensor_z && doubling < 200 => (lo, hi) = (hi, 2.0 * hi),
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
                Some(z) if z < sensor_z => lo = mid,
                _ => hi = mid,
            }
        }
        let distance = 2.0 / (lo + hi);
        (sensor_z - distance < self.front_z()).then_some(distance)
    }

    /// [`LensSystem::focus_distance_mm`] by one real ray in `meridian`.
    fn focus_distance_in(&self, sensor_z: f64, height_mm: f64, meridian: Meridian) -> Option<f64> {
        let ray = LensRay::between(
            DVec3::new(0.0, 0.0, sensor_z),
            meridian.across() * height_mm + DVec3::new(0.0, 0.0, self.rear_z()),
        );
        let out = self.trace(&ray, Direction::ToScene)?;
        // In focus only if the ray leaves heading toward the axis.
        if !out.heads_toward_axis(meridian) {
            return None;
        }
        let object_z = out.axis_crossing_z(meridian)?;
        (object_z < self.front_z()).then_some(sensor_z - object_z)
    }

    /// The sensor position whose real-ray conjugate is `distance_mm` from the
    /// sensor plane: the inverse of [`LensSystem::focus_distance_mm`], by
    /// bisection (for an anamorphic lens, midway between the positions that
    /// focus each meridian).
    pub fn sensor_z_for_focus_distance(&self, distance_mm: f64, height_mm: f64) -> Result<f64> {
        self.between_meridians(|m| self.sensor_z_for_focus_distance_in(distance_mm, height_mm, m))
    }

    /// [`LensSystem::sensor_z_for_focus_distance`] in one meridian.
    fn sensor_z_for_focus_distance_in(&self, distance_mm: f64, height_mm: f64, meridian: Meridian) -> Result<f64> {
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
impl LensRay {
    /// The ray from (x, y) = `start`, 50 mm in front of `lens`'s front
    /// vertex, along (`slope`, 1): how the tests launch the skew rays they
    /// compare with rayoptics (`bench/peers/lens_vs_rayoptics.py`).
    pub(crate) fn skew(lens: &LensSystem, start: [f64; 2], slope: [f64; 2]) -> LensRay {
        LensRay {
            origin: DVec3::new(start[0], start[1], lens.front_z() - 50.0),
            direction: DVec3::new(slope[0], slope[1], 1.0).normalize(),
        }
    }
}

/// The hit of `ray` on the spherical `surface`, on the cap around its
/// vertex, with the unit normal there
/// (pointing away from the centre), for a ray travelling `travel`.
/// After pbrt-v4 `RealisticCamera::IntersectSphericalElement`.
#[inline(always)]
fn intersect_sphere(ray: &LensRay, surface: &Surface, travel: Direction) -> Option<(f64, DVec3)> {
    let radius = surface.radius;
    let center = DVec3::new(0.0, 0.0, surface.z + radius);
    let oc = ray.origin - center;
    let b = oc.dot(ray.direction);
    let c = oc.length_squared() - radius * radius;
    let discriminant = b * b - c;
    if discriminant < 0.0 {
        return None;
    }
    // The vertex side is hit first when travel goes from the vertex toward
    // the centre. Decided by the travel direction, not by the sign of the
    // ray's z, so rays far off axis (even past 90°) take the right cap.
    let want_near = (travel == Direction::ToSensor) == (radius > 0.0);
    // -b ± √D directly: the root wanted is never the one near 0 (that would
    // be a ray starting on this very surface), so cancellation costs at most
    // |b|/|t| ≤ 1e4 ulps, ~1e-12 mm, and no division sits on the ray's path.
    let root = discriminant.sqrt();
    let t = if want_near { -b - root } else { -b + root };
    let p = ray.origin + ray.direction * t;
    Some((t, (p - center) * surface.inv_abs_radius))
}

/// The hit of `ray` on the cylindrical `surface` whose axis runs along
/// `axis`, with the unit normal there: [`intersect_sphere`]'s computation in
/// the plane the cylinder curves in, the ray's component along the axis
/// dropped (it only carries the ray along the cylinder).
#[inline(always)]
fn intersect_cylinder(ray: &LensRay, surface: &Surface, axis: CylinderAxis, travel: Direction) -> Option<(f64, DVec3)> {
    let keep = match axis {
        CylinderAxis::X => DVec3::new(0.0, 1.0, 1.0),
        CylinderAxis::Y => DVec3::new(1.0, 0.0, 1.0),
    };
    let radius = surface.radius;
    let center = DVec3::new(0.0, 0.0, surface.z + radius);
    let (oc, d) = ((ray.origin - center) * keep, ray.direction * keep);
    // |oc + t·d|² = R², with d no longer a unit vector.
    let a = d.length_squared();
    let b = oc.dot(d);
    let c = oc.length_squared() - radius * radius;
    let discriminant = b * b - a * c;
    if discriminant < 0.0 || a == 0.0 {
        return None;
    }
    let want_near = (travel == Direction::ToSensor) == (radius > 0.0);
    let root = discriminant.sqrt();
    let t = if want_near { (-b - root) / a } else { (-b + root) / a };
    let p = ray.origin + ray.direction * t;
    Some((t, (p - center) * keep * surface.inv_abs_radius))
}

/// The hit of `ray` on an aspheric `surface`, with the unit normal there:
/// Newton's method from the vertex sphere's hit on the right cap (or the
/// vertex plane's, for a flat base or a sphere the ray misses).
#[inline(always)]
fn intersect_asphere(
    ray: &LensRay,
    surface: &Surface,
    asphere: &EvenAsphere,
    travel: Direction,
) -> Option<(f64, DVec3)> {
    let t_start = match surface.radius.is_finite() {
        true => intersect_sphere(ray, surface, travel).map(|(t, _)| t),
        false => None,
    }
    .unwrap_or((surface.z - ray.origin.z) / ray.direction.z);
    intersect_even_asphere(
        ray.origin,
        ray.direction,
        surface.z,
        1.0 / surface.radius,
        asphere,
        t_start,
    )
}

/// The hit of `ray` on a toric `surface`, with the unit normal there:
/// Newton's method from the hit on the cylinder of its profile (the surface
/// before its axis is bent), or on the vertex plane for a flat profile or a
/// cylinder the ray misses.
#[inline(always)]
fn intersect_toric(ray: &LensRay, surface: &Surface, toric: &Toric, travel: Direction) -> Option<(f64, DVec3)> {
    let t_start = match surface.radius.is_finite() {
        true => intersect_cylinder(ray, surface, toric.axis, travel).map(|(t, _)| t),
        false => None,
    }
    .unwrap_or((surface.z - ray.origin.z) / ray.direction.z);
    let curvature = 1.0 / surface.radius;
    intersect_by_newton(ray.origin, ray.direction, surface.z, t_start, |x, y| {
        toric.sag_and_gradient(curvature, x, y)
    })
}

/// Snell's law in vector form (pbrt-v4 `Refract`), `eta = n1 / n2`; `None`
/// on total internal reflection.
fn refract(d: DVec3, normal: DVec3, eta: f64) -> Option<DVec3> {
    let n = if normal.dot(d) > 0.0 { -normal } else { normal };
    let cos_i = -n.dot(d);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    // Unit length is preserved exactly in exact arithmetic; f64 keeps it to ~1e-16 per surface.
    Some(eta * d + (eta * cos_i - cos_t) * n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lens::prescription::BUILTIN_LENSES;
    use crate::lens::TableConvention;

    fn builtin(name: &str) -> LensSystem {
        LensSystem::new(&LensPrescription::load(name).unwrap())
    }

    fn relative(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }

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
            let sensor_z = lens.rear_z() + image_distance;
            let to_object = lens.focus_distance_mm(sensor_z, 0.1).unwrap();
            let object_distance = to_object - image_distance - t;
            let lhs = 1.0 / object_distance + 1.0 / image_distance;
            assert!(
                relative(lhs, 1.0 / f) < 1e-4,
                "s' {image_distance}: 1/s + 1/s' = {lhs}, 1/f = {}",
                1.0 / f
            );
        }
    }

    /// An aspheric singlet (a Thorlabs AL50100-style front: R 50.3583 mm,
    /// k −0.789119, A4 2.10405e-7, A6 1.76468e-11, A8 1.02641e-15; 10.2 mm of
    /// n 1.5168; flat back; the stop 1 mm in front).
    const ASPHERIC_SINGLET: &str = "0 1 0 50\n\
        50.3583 10.2 1.5168 50 conic=-0.789119 a4=2.10405e-7 a6=1.76468e-11 a8=1.02641e-15\n\
        inf 90 1 50\n";

    /// Its paraxial data and its real rays against rayoptics 0.9.8 (an
    /// independent lens design package: `EvenPolynomial` profile, its own
    /// intersection), numbers from `bench/peers/lens_vs_rayoptics.py`: where
    /// rays parallel to the axis at six heights cross it behind the flat.
    /// Aspheric correction keeps them within 0.02 mm of each other; a sphere
    /// of the same vertex radius would spread them over 2 mm.
    #[test]
    fn an_aspheric_singlet_traces_as_rayoptics_does() {
        let prescription =
            LensPrescription::parse(ASPHERIC_SINGLET, "asphere", TableConvention::ThicknessToNext).unwrap();
        let lens = LensSystem::new(&prescription);
        let p = lens.paraxial().unwrap();
        assert!(
            relative(p.effective_focal_length_mm, 97.44253095975233) < 1e-12,
            "{p:?}"
        );
        assert!(relative(p.back_focal_distance_mm, 90.71784741544855) < 1e-12, "{p:?}");
        let rayoptics = [
            (1.0, 90.71782685358782),
            (5.0, 90.7173195272318),
            (10.0, 90.71556052066026),
            (15.0, 90.71202707596034),
            (20.0, 90.70575610870647),
            (24.0, 90.69779614631487),
        ];
        for (height, crossing) in rayoptics {
            let (focus_z, _) = lens.real_focus_at_infinity(height).unwrap();
            let ours = focus_z - lens.rear_z();
            assert!(
                (ours - crossing).abs() < 1e-9,
                "h {height}: {ours} vs rayoptics {crossing}"
            );
        }
        // The same vertex sphere without the aspheric terms: 2 mm of spherical aberration.
        let sphere = LensPrescription::parse(
            "0 1 0 50\n50.3583 10.2 1.5168 50\ninf 90 1 50\n",
            "sphere",
            TableConvention::ThicknessToNext,
        )
        .unwrap();
        let sphere = LensSystem::new(&sphere);
        let spread = sphere.real_focus_at_infinity(1.0).unwrap().0 - sphere.real_focus_at_infinity(24.0).unwrap().0;
        assert!(spread > 2.0, "{spread}");
    }

    /// A cemented doublet of two toric surfaces, bent each way, and a
    /// cylinder behind them (indices 1.62 and 1.72; the stop 4 mm in front).
    const TORIC_DOUBLET: &str = "0 4 0 20\n\
        40 6 1.62 24 toric=x:25\n\
        -30 2.5 1.72 24 toric=y:-55\n\
        -90 30 1 24 cylinder=y\n";

    /// The doublet against rayoptics 0.9.8 given the same surfaces (its
    /// `YToroid` and `XToroid` profiles, its own intersection; numbers from
    /// `bench/peers/lens_vs_rayoptics.py`): where skew rays from 50 mm in
    /// front of the stop cross the plane 10 mm behind the rear vertex, and
    /// each meridian's focal length (rayoptics: a parallel ray 0.01 mm off
    /// the axis; here paraxial). A toric surface whose rotation radius equals
    /// its vertex radius is the sphere: the same rays through that lens and
    /// through the spherical one agree to 1e-9 mm.
    #[test]
    fn a_toric_doublet_traces_as_rayoptics_does() {
        let parse = |table: &str| {
            LensSystem::new(&LensPrescription::parse(table, "toric", TableConvention::ThicknessToNext).unwrap())
        };
        let lens = parse(TORIC_DOUBLET);
        assert!(!lens.is_rotationally_symmetric());
        let rayoptics = [
            ([3.0, 0.0], [0.0, 0.0], [1.7646003152678418, 0.0]),
            ([0.0, 3.0], [0.0, 0.0], [0.0, 2.3562714843778347]),
            ([2.0, -3.0], [0.03, 0.05], [2.572718041603636, 0.5305933728825611]),
            ([-5.0, 4.0], [0.06, -0.03], [-0.13752418734624894, 1.4084580619388918]),
            ([5.0, 5.0], [-0.08, -0.04], [-0.7939871738920763, 1.6163819915061635]),
            ([-6.0, -2.0], [0.1, 0.07], [1.1351628807279583, 2.458333875159638]),
        ];
        for (start, slope, expected) in rayoptics {
            let out = lens.trace(&LensRay::skew(&lens, start, slope), Direction::ToSensor);
            let behind = out.and_then(|o| o.at_z(lens.rear_z() + 10.0)).expect("passes");
            assert!(
                (behind.x - expected[0]).abs() < 1e-9 && (behind.y - expected[1]).abs() < 1e-9,
                "{start:?} {slope:?}: {behind} vs rayoptics {expected:?}"
            );
            // And back: the exit ray traced toward the scene returns to the start.
            let back = lens.trace(
                &LensRay {
                    origin: DVec3::new(behind.x, behind.y, lens.rear_z() + 10.0),
                    direction: -out.unwrap().direction,
                },
                Direction::ToScene,
            );
            let start_again = back.and_then(|b| b.at_z(lens.front_z() - 50.0)).expect("returns");
            assert!(
                (start_again.x - start[0]).abs() < 1e-9 && (start_again.y - start[1]).abs() < 1e-9,
                "{start:?}: back at {start_again}"
            );
        }
        for (meridian, expected) in Meridian::BOTH.into_iter().zip([34.740491534574026, 72.53632743773711]) {
            let efl = lens.paraxial_in(meridian).unwrap().effective_focal_length_mm;
            assert!((efl - expected).abs() < 1e-5, "{meridian:?}: {efl} vs {expected}");
        }
        let as_toric = parse("0 4 0 20\n40 6 1.62 24 toric=y:40\n-30 2.5 1.72 24 toric=x:-30\n-90 30 1 24\n");
        let spherical = parse("0 4 0 20\n40 6 1.62 24\n-30 2.5 1.72 24\n-90 30 1 24\n");
        for (start, slope, _) in rayoptics {
            let [a, b] = [&as_toric, &spherical].map(|lens| {
                let out = lens
                    .trace(&LensRay::skew(lens, start, slope), Direction::ToSensor)
                    .unwrap();
                out.at_z(lens.rear_z() + 10.0).unwrap()
            });
            assert!((a - b).length() < 1e-9, "{start:?} {slope:?}: {a} vs {b}");
        }
    }

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

    #[test]
    fn focusing_round_trips() {
        // lentil 2004 is anamorphic: it focuses midway between its meridians.
        let names = BUILTIN_LENSES.iter().map(|(name, _)| *name).chain(["lentil:2004"]);
        for name in names {
            let lens = builtin(name);
            let infinity = lens.infinity_focus_z(0.1).unwrap();
            let focal = lens.paraxial().unwrap().effective_focal_length_mm;
            // Objects from 6 f in front of the lens (a telephoto's closest
            // real focus is about 4 f from the sensor) to far away.
            for multiple in [6.0, 10.0, 40.0, 400.0, 4000.0] {
                let metres = (infinity - lens.front_z() + multiple * focal) * 1e-3;
                let z = lens.sensor_z_for_focus_distance(metres * 1e3, 0.1).unwrap();
                assert!(z > infinity, "{name} at {metres} m");
                let back = lens.focus_distance_mm(z, 0.1).unwrap();
                assert!(relative(back, metres * 1e3) < 1e-6, "{name} at {metres} m: {back} mm");
                let [h, v] = Meridian::BOTH.map(|m| lens.sensor_z_for_focus_distance_in(metres * 1e3, 0.1, m).unwrap());
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

    #[test]
    fn tracing_to_the_scene_and_back_returns_the_ray() {
        let aspheric = LensPrescription::parse(ASPHERIC_SINGLET, "asphere", TableConvention::ThicknessToNext).unwrap();
        let lenses = BUILTIN_LENSES
            .iter()
            .map(|(name, _)| (name.to_string(), builtin(name)))
            .chain([("asphere".to_string(), LensSystem::new(&aspheric))]);
        for (name, lens) in lenses {
            let sensor_z = lens.real_focus_at_infinity(0.1).unwrap().0;
            let film = DVec3::new(1.3, -0.7, sensor_z);
            let mut checked = 0;
            for k in 0..400 {
                let a = k as f64 * 2.399;
                let r = lens.rear_aperture_radius() * 0.9 * ((k as f64 + 0.5) / 400.0).sqrt();
                let ray = LensRay::between(film, DVec3::new(r * a.cos(), r * a.sin(), lens.rear_z()));
                let Some(out) = lens.trace(&ray, Direction::ToScene) else {
                    continue;
                };
                // The same ray, with the point where it crossed the stop (at z = 0).
                let (via, at_stop) = lens.trace_via_stop(&ray, Direction::ToScene).unwrap();
                assert_eq!((via.origin, via.direction), (out.origin, out.direction));
                assert!(at_stop.z.abs() < 1e-12 && at_stop.truncate().length() <= lens.stop_radius());
                let back = LensRay {
                    origin: out.origin + out.direction * 25.0,
                    direction: -out.direction,
                };
                let returned = lens.trace(&back, Direction::ToSensor).expect("reversible");
                let hit = returned.at_z(sensor_z).unwrap();
                assert!(
                    (hit - film).length() < 1e-9,
                    "{name}: returned to {hit:?}, not {film:?}"
                );
                assert!((returned.direction + ray.direction).length() < 1e-12);
                // Going back, it crosses the stop where it crossed it going out.
                let (_, back_at_stop) = lens.trace_via_stop(&back, Direction::ToSensor).unwrap();
                assert!(
                    (back_at_stop - at_stop).length() < 1e-9,
                    "{name}: {back_at_stop:?} vs {at_stop:?}"
                );
                checked += 1;
            }
            assert!(checked > 10, "{name}: only {checked} rays passed");
        }
    }

    #[test]
    fn tracing_rays_together_gives_each_its_own_result() {
        let lens = builtin("wide22");
        let sensor_z = lens.real_focus_at_infinity(0.1).unwrap().0;
        let rays: Vec<LensRay> = (0..64)
            .map(|k| {
                let film = DVec3::new(0.3 * k as f64, -0.1 * k as f64, sensor_z);
                let a = k as f64 * 2.399;
                let target = DVec3::new(4.0 * a.cos(), 4.0 * a.sin(), lens.rear_z());
                LensRay::between(film, target)
            })
            .collect();
        let (mut passed, mut blocked) = (0, 0);
        let mut count = |out: Option<LensRay>| {
            if out.is_some() {
                passed += 1
            } else {
                blocked += 1
            }
        };
        for pair in rays.chunks_exact(2) {
            let together = LensSystem::trace_each([&lens, &lens], &[pair[0], pair[1]], Direction::ToScene);
            for (ray, out) in pair.iter().zip(together) {
                assert_eq!(out, lens.trace(ray, Direction::ToScene));
                count(out);
            }
        }
        // Through the lens at three wavelengths at once (a dispersive one).
        let dgauss = builtin("dgauss50");
        let systems = [400.0, 550.0, 700.0].map(|nm| dgauss.at_wavelength(nm));
        let sensor_z = dgauss.real_focus_at_infinity(0.1).unwrap().0;
        for k in 0..32 {
            let film = DVec3::new(0.5 * k as f64, 0.2 * k as f64, sensor_z);
            let rays = [0.0, 2.1, 4.2].map(|a: f64| {
                let target = DVec3::new(9.0 * (a + k as f64).cos(), 9.0 * (a + k as f64).sin(), dgauss.rear_z());
                LensRay::between(film, target)
            });
            let together = LensSystem::trace_each([&systems[0], &systems[1], &systems[2]], &rays, Direction::ToScene);
            for ((system, ray), out) in systems.iter().zip(&rays).zip(together) {
                assert_eq!(out, system.trace(ray, Direction::ToScene));
                count(out);
            }
        }
        assert!(
            passed > 0 && blocked > 0,
            "{passed} passed, {blocked} blocked: both cases matter"
        );
    }

    #[test]
    fn the_fisheye_covers_its_design_field() {
        // Muller's fisheye is specified for a 155.9° field (Smith, Modern Lens Design, p. 164).
        let lens = builtin("fisheye10");
        let sensor_z = lens.real_focus_at_infinity(0.1).unwrap().0;
        let rear = lens.rear_aperture_radius();
        let widest = (0..600)
            .flat_map(|k| (0..400).map(move |j| (k, j)))
            .filter_map(|(k, j)| {
                let film = DVec3::new(0.05 * k as f64, 0.0, sensor_z);
                let x = -rear + 2.0 * rear * j as f64 / 400.0;
                lens.trace(
                    &LensRay::between(film, DVec3::new(x, 0.0, lens.rear_z())),
                    Direction::ToScene,
                )
            })
            .map(|out| (-out.direction.z).acos().to_degrees())
            .fold(0.0, f64::max);
        assert!(
            (widest - 155.9 / 2.0).abs() < 2.0,
            "widest ray leaves {widest}° off axis"
        );
    }

    /// Rays can leave a lens more than 90° off its axis (going partly
    /// backwards), as in fisheyes wider than 180°: a ball of dense glass
    /// does it, for rays that cross it far off its axis. Tracing makes no assumption
    /// about the hemisphere a ray travels in, so they come back exactly.
    #[test]
    fn rays_past_90_degrees_leave_and_return() {
        let table = "10 20 1.9 19.99\n-10 2 1 19.99\n0 0 0 19.9\n";
        let ball = LensPrescription::parse(table, "ball", TableConvention::ThicknessToNext).unwrap();
        let lens = LensSystem::new(&ball);
        let sensor_z = 3.0;
        let (mut past_90, mut widest) = (0, 0.0f64);
        for i in 0..200 {
            for j in 0..200 {
                let film = DVec3::new(-30.0 + 0.3 * i as f64, 0.0, sensor_z);
                let target = DVec3::new(-9.9 + 0.099 * j as f64, 0.0, lens.rear_z());
                let ray = LensRay::between(film, target);
                let Some(out) = lens.trace(&ray, Direction::ToScene) else {
                    continue;
                };
                widest = widest.max((-out.direction.z).acos().to_degrees());
                // Toward the scene is -z: past 90° the ray heads toward +z.
                if out.direction.z > 0.0 {
                    past_90 += 1;
                    let back = LensRay {
                        origin: out.origin + out.direction * 5.0,
                        direction: -out.direction,
                    };
                    let returned = lens.trace(&back, Direction::ToSensor).expect("reversible");
                    assert!((returned.at_z(sensor_z).unwrap() - film).length() < 1e-9);
                }
            }
        }
        assert!(past_90 > 10, "only {past_90} rays left past 90° (widest {widest}°)");
    }

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
            let _ = lens.sensor_z_for_focus_distance(2000.0, 0.1);
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
