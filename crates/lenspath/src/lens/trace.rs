//! Exact ray tracing through a placed lens, surface by surface in either
//! direction: intersection, clipping by each clear aperture and the stop,
//! and refraction by Snell's law.

use glam::DVec3;

use super::surface::{intersect_asphere, intersect_cylinder, intersect_sphere, intersect_toric};
use super::system::{Direction, Intersection, LensRay, LensSystem, Surface};

impl LensSystem {
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

    /// [`LensSystem::trace`], also returning the ray's optical path length
    /// from its origin to the last surface crossed: the sum of each medium's
    /// index times the distance travelled in it, mm (a stop bends nothing
    /// and adds nothing).
    pub fn trace_optical_path(&self, ray: &LensRay, direction: Direction) -> Option<(LensRay, f64)> {
        let (mut ray, mut path_mm) = (*ray, 0.0);
        for k in 0..self.surfaces.len() {
            let surface = self.surface_in_travel_order(k, direction);
            let next = self.cross(surface, &ray, direction, &mut |_| {})?;
            let index = match direction {
                Direction::ToSensor => surface.ior_front,
                Direction::ToScene => surface.ior_back,
            };
            path_mm += index * next.origin.distance(ray.origin);
            ray = next;
        }
        Some((ray, path_mm))
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
        let (origin, toward_positive_z) = (ray.origin, surface.arrives_toward_positive_z(direction));
        let (t, normal) = match &surface.intersection {
            Intersection::Aperture => {
                let forward = match toward_positive_z {
                    true => ray.direction.z > 0.0,
                    false => ray.direction.z < 0.0,
                };
                if !forward {
                    return None;
                }
                let p = origin + ray.direction * ((surface.vertex.z_mm - origin.z) / ray.direction.z);
                visit(p);
                let inside = p.x * p.x + p.y * p.y <= surface.aperture_radius * surface.aperture_radius;
                return inside.then_some(*ray);
            }
            Intersection::Plane => ((surface.vertex.z_mm - origin.z) / ray.direction.z, DVec3::Z),
            Intersection::Sphere => intersect_sphere(origin, ray.direction, &surface.vertex, toward_positive_z)?,
            Intersection::Asphere(asphere) => {
                intersect_asphere(origin, ray.direction, &surface.vertex, asphere, toward_positive_z)?
            }
            Intersection::Cylinder(axis) => {
                intersect_cylinder(origin, ray.direction, &surface.vertex, *axis, toward_positive_z)?
            }
            Intersection::Toric(toric) => {
                intersect_toric(origin, ray.direction, &surface.vertex, toric, toward_positive_z)?
            }
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
    use super::super::prescription::{LensPrescription, BUILTIN_LENSES};
    use super::super::surface::{Meridian, SurfaceShape};
    use super::super::system::test_support::*;
    use super::super::TableConvention;
    use super::*;

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
            let ours = focus_z - lens.rear_z_mm();
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
            let behind = out.and_then(|o| o.at_z(lens.rear_z_mm() + 10.0)).expect("passes");
            assert!(
                (behind.x - expected[0]).abs() < 1e-9 && (behind.y - expected[1]).abs() < 1e-9,
                "{start:?} {slope:?}: {behind} vs rayoptics {expected:?}"
            );
            // And back: the exit ray traced toward the scene returns to the start.
            let back = lens.trace(
                &LensRay {
                    origin: DVec3::new(behind.x, behind.y, lens.rear_z_mm() + 10.0),
                    direction: -out.unwrap().direction,
                },
                Direction::ToScene,
            );
            let start_again = back.and_then(|b| b.at_z(lens.front_z_mm() - 50.0)).expect("returns");
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
                out.at_z(lens.rear_z_mm() + 10.0).unwrap()
            });
            assert!((a - b).length() < 1e-9, "{start:?} {slope:?}: {a} vs {b}");
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
            let sensor_depth_mm = lens.real_focus_at_infinity(0.1).unwrap().0;
            let film = DVec3::new(1.3, -0.7, sensor_depth_mm);
            let mut checked = 0;
            for k in 0..400 {
                let a = k as f64 * 2.399;
                let r = lens.rear_aperture_radius_mm() * 0.9 * ((k as f64 + 0.5) / 400.0).sqrt();
                let ray = LensRay::between(film, DVec3::new(r * a.cos(), r * a.sin(), lens.rear_z_mm()));
                let Some(out) = lens.trace(&ray, Direction::ToScene) else {
                    continue;
                };
                // The same ray, with the point where it crossed the stop (at z = 0).
                let (via, at_stop) = lens.trace_via_stop(&ray, Direction::ToScene).unwrap();
                assert_eq!((via.origin, via.direction), (out.origin, out.direction));
                assert!(at_stop.z.abs() < 1e-12 && at_stop.truncate().length() <= lens.stop_radius_mm());
                let back = LensRay {
                    origin: out.origin + out.direction * 25.0,
                    direction: -out.direction,
                };
                let returned = lens.trace(&back, Direction::ToSensor).expect("reversible");
                let hit = returned.at_z(sensor_depth_mm).unwrap();
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
        let sensor_depth_mm = lens.real_focus_at_infinity(0.1).unwrap().0;
        let rays: Vec<LensRay> = (0..64)
            .map(|k| {
                let film = DVec3::new(0.3 * k as f64, -0.1 * k as f64, sensor_depth_mm);
                let a = k as f64 * 2.399;
                let target = DVec3::new(4.0 * a.cos(), 4.0 * a.sin(), lens.rear_z_mm());
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
        let sensor_depth_mm = dgauss.real_focus_at_infinity(0.1).unwrap().0;
        for k in 0..32 {
            let film = DVec3::new(0.5 * k as f64, 0.2 * k as f64, sensor_depth_mm);
            let rays = [0.0, 2.1, 4.2].map(|a: f64| {
                let target = DVec3::new(
                    9.0 * (a + k as f64).cos(),
                    9.0 * (a + k as f64).sin(),
                    dgauss.rear_z_mm(),
                );
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
        let sensor_depth_mm = lens.real_focus_at_infinity(0.1).unwrap().0;
        let rear = lens.rear_aperture_radius_mm();
        let widest = (0..600)
            .flat_map(|k| (0..400).map(move |j| (k, j)))
            .filter_map(|(k, j)| {
                let film = DVec3::new(0.05 * k as f64, 0.0, sensor_depth_mm);
                let x = -rear + 2.0 * rear * j as f64 / 400.0;
                lens.trace(
                    &LensRay::between(film, DVec3::new(x, 0.0, lens.rear_z_mm())),
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
        let sensor_depth_mm = 3.0;
        let (mut past_90, mut widest) = (0, 0.0f64);
        for i in 0..200 {
            for j in 0..200 {
                let film = DVec3::new(-30.0 + 0.3 * i as f64, 0.0, sensor_depth_mm);
                let target = DVec3::new(-9.9 + 0.099 * j as f64, 0.0, lens.rear_z_mm());
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
                    assert!((returned.at_z(sensor_depth_mm).unwrap() - film).length() < 1e-9);
                }
            }
        }
        assert!(past_90 > 10, "only {past_90} rays left past 90° (widest {widest}°)");
    }

    /// `prescription` laid out the other way along the axis: every
    /// thickness negative and every surface bent the other way, so its
    /// vertices run toward −z and light goes to the sensor toward −z.
    fn mirrored_in_z(prescription: &LensPrescription) -> LensPrescription {
        let mut mirrored = prescription.clone();
        for s in &mut mirrored.surfaces {
            s.radius_mm = -s.radius_mm;
            s.thickness_mm = -s.thickness_mm;
            match &mut s.shape {
                SurfaceShape::EvenAsphere(asphere) => asphere.coefficients = asphere.coefficients.map(|a| -a),
                SurfaceShape::Toric(toric) => toric.rotation_radius_mm = -toric.rotation_radius_mm,
                SurfaceShape::Spherical | SurfaceShape::Cylindrical(_) => {}
            }
        }
        mirrored
    }

    /// The tracer takes each surface's sense of travel from the vertices'
    /// order, not from the direction of tracing: a lens whose surfaces run
    /// toward −z (what a mirror's negative thicknesses make) traces as the
    /// mirror image of the same lens laid out toward +z, for spheres,
    /// aspheres, torics and cylinders, both ways, and blocks the same rays.
    #[test]
    fn a_lens_laid_out_toward_negative_z_traces_as_its_mirror_image() {
        let flip = |v: DVec3| DVec3::new(v.x, v.y, -v.z);
        let flip_ray = |r: LensRay| LensRay {
            origin: flip(r.origin),
            direction: flip(r.direction),
        };
        let parse = |table: &str| LensPrescription::parse(table, "test", TableConvention::ThicknessToNext).unwrap();
        let prescriptions = [
            LensPrescription::load("dgauss50").unwrap(),
            LensPrescription::load("asph31").unwrap(),
            LensPrescription::load("lentil:2004").unwrap(),
            parse(TORIC_DOUBLET),
        ];
        for prescription in prescriptions {
            let lens = LensSystem::new(&prescription);
            let mirrored = LensSystem::new(&mirrored_in_z(&prescription));
            assert_eq!(mirrored.front_z_mm(), -lens.front_z_mm(), "{}", prescription.name);
            let (mut passed, mut blocked) = (0, 0);
            for k in 0..300 {
                let a = k as f64 * 2.399;
                let r = lens.front_aperture_radius_mm() * ((k as f64 + 0.5) / 300.0).sqrt();
                let start = [r * a.cos(), r * a.sin()];
                let slope = [0.004 * (k % 7) as f64 - 0.012, 0.003 * (k % 5) as f64 - 0.006];
                let ray = LensRay::skew(&lens, start, slope);
                let out = lens.trace(&ray, Direction::ToSensor);
                let out_mirrored = mirrored.trace(&flip_ray(ray), Direction::ToSensor);
                assert_eq!(out.is_some(), out_mirrored.is_some(), "{} ray {k}", prescription.name);
                let (Some(out), Some(out_mirrored)) = (out, out_mirrored) else {
                    blocked += 1;
                    continue;
                };
                passed += 1;
                assert!((flip(out_mirrored.origin) - out.origin).length() < 1e-9);
                assert!((flip(out_mirrored.direction) - out.direction).length() < 1e-12);
                // And back toward the scene, crossing the stop at the same place.
                let back = LensRay {
                    origin: out.origin + out.direction * 5.0,
                    direction: -out.direction,
                };
                let (returned, at_stop) = lens.trace_via_stop(&back, Direction::ToScene).expect("reversible");
                let (returned_mirrored, at_stop_mirrored) = mirrored
                    .trace_via_stop(&flip_ray(back), Direction::ToScene)
                    .expect("reversible");
                assert!((flip(returned_mirrored.origin) - returned.origin).length() < 1e-9);
                assert!((flip(at_stop_mirrored) - at_stop).length() < 1e-9);
            }
            assert!(
                passed > 20 && blocked > 0,
                "{}: {passed} passed, {blocked} blocked: both cases matter",
                prescription.name
            );
        }
    }
}
