//! Light sources: point, spot, directional, constant environment, and area lights
//! (emissive triangle meshes and spheres) with their sampling routines.

use glam::{Vec2, Vec3};

use crate::error::{Error, Result};
use crate::sampling::{uniform_sphere, uniform_triangle, Distribution1D, UNIFORM_SPHERE_PDF};
use crate::spectrum::{Emission, Spectrum};

/// A light a scene declares directly. Area lights come from emissive shapes.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// Isotropic point light.
    Point {
        /// Position.
        position: Vec3,
        /// Radiant intensity (W/sr).
        intensity: Emission,
    },
    /// Spot light: a point light whose intensity falls off as cos^exponent of the
    /// angle from its axis and is zero outside the cone (the OpenGL / COLLADA 1.4
    /// spot model, COLLADA spec §light "spot").
    Spot {
        /// Position.
        position: Vec3,
        /// Axis the light points along (unit).
        direction: Vec3,
        /// Radiant intensity on the axis (W/sr).
        intensity: Emission,
        /// Cosine of the cone's half angle.
        cos_cutoff: f32,
        /// Falloff exponent (0: uniform inside the cone).
        exponent: f32,
    },
    /// Distant light, such as the sun.
    Directional {
        /// Direction the light travels in (unit).
        direction: Vec3,
        /// Irradiance on a surface facing the light.
        irradiance: Emission,
    },
    /// Constant radiance arriving from every direction not blocked by the scene.
    Environment {
        /// Radiance.
        radiance: Emission,
    },
}

/// The geometry of an area light, in scene space.
#[derive(Clone, Debug)]
pub enum AreaShape {
    /// Emissive triangles; light leaves the front (counter-clockwise) face.
    Triangles {
        /// Corners of each triangle.
        triangles: Vec<[Vec3; 3]>,
        /// Unit normal of each triangle's front face.
        normals: Vec<Vec3>,
        /// Triangle choice proportional to area.
        by_area: Distribution1D,
    },
    /// Two emissive triangles that make a parallelogram (the quad light of
    /// most scenes), sampled as one: `corner + u·edge_u + v·edge_v` is
    /// uniform by area with no choice of triangle, no division and no
    /// branch, and keeps the stratification of `(u, v)`.
    Parallelogram {
        /// One corner.
        corner: Vec3,
        /// The edge from it along which `u` runs.
        edge_u: Vec3,
        /// The edge from it along which `v` runs.
        edge_v: Vec3,
        /// Unit normal of the front face.
        normal: Vec3,
    },
    /// Emissive sphere; light leaves the outside.
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius.
        radius: f32,
    },
}

/// An emissive shape with uniform radiance.
#[derive(Clone, Debug)]
pub struct AreaLight {
    /// Where it is.
    pub shape: AreaShape,
    /// Emitted spectral radiance.
    pub emission: Spectrum,
    /// Total surface area.
    pub area: f32,
}

impl AreaLight {
    /// An area light over `triangles`; `None` when they have no area.
    pub fn from_triangles(triangles: Vec<[Vec3; 3]>, emission: Spectrum) -> Option<Self> {
        let crosses: Vec<Vec3> = triangles.iter().map(|[a, b, c]| (*b - *a).cross(*c - *a)).collect();
        let areas: Vec<f32> = crosses.iter().map(|n| 0.5 * n.length()).collect();
        let area: f32 = areas.iter().sum();
        if area <= 0.0 || !area.is_finite() {
            return None;
        }
        if let Some(shape) = parallelogram(&triangles, &crosses) {
            return Some(AreaLight { shape, emission, area });
        }
        // Zero-area triangles are never chosen; their normal is left zero.
        let normals = crosses.iter().map(|n| n.normalize_or_zero()).collect();
        Some(AreaLight {
            shape: AreaShape::Triangles {
                by_area: Distribution1D::new(&areas),
                triangles,
                normals,
            },
            emission,
            area,
        })
    }

    /// An area light on a sphere.
    pub fn from_sphere(center: Vec3, radius: f32, emission: Spectrum) -> Self {
        AreaLight {
            shape: AreaShape::Sphere { center, radius },
            emission,
            area: 4.0 * std::f32::consts::PI * radius * radius,
        }
    }

    /// A point on the light, uniform by area: position and outward normal.
    // Inlined into `SampleLight::sample`: called, it returns the pair through
    // memory, and the path loop's 8-byte reload of the 4-byte stores stalled
    // store forwarding (a tenth of the fat-LTO path loop on the dragon,
    // BENCHMARKS.md).
    #[inline(always)]
    fn sample_point(&self, u: Vec2) -> (Vec3, Vec3) {
        match &self.shape {
            AreaShape::Triangles {
                triangles,
                normals,
                by_area,
            } => {
                let (i, _, ux) = by_area.sample(u.x);
                let [a, b, c] = triangles[i];
                let [b0, b1, b2] = uniform_triangle(Vec2::new(ux, u.y));
                (b0 * a + b1 * b + b2 * c, normals[i])
            }
            AreaShape::Parallelogram {
                corner,
                edge_u,
                edge_v,
                normal,
            } => (*corner + u.x * *edge_u + u.y * *edge_v, *normal),
            AreaShape::Sphere { center, radius } => {
                let n = uniform_sphere(u.x, u.y);
                (*center + *radius * n, n)
            }
        }
    }

    /// Density per solid angle of sampling the point at `distance` along a
    /// direction meeting the light's normal with cosine `cos_light`, from `p`.
    pub fn pdf(&self, distance: f32, cos_light: f32) -> f32 {
        if cos_light <= 0.0 {
            return 0.0;
        }
        distance * distance / (cos_light * self.area)
    }
}

/// A light sampled from a shading point, as the path loop's direct lighting
/// does: [`AreaLight`] and [`Light`] alike.
// A trait, statically dispatched, rather than a closure around the call: once
// `AreaLight::sample_point` inlined, the compiler left such a closure out of
// line, where it runs as baseline x86-64 code instead of in the path loop's
// AVX2 copy (a fifth of the dragon's render; BENCHMARKS.md).
pub trait SampleLight {
    /// A direction from `p` toward the light for `u` in [0, 1)², with what
    /// arrives along it and its density; `None` when nothing does.
    fn sample(&self, p: Vec3, u: Vec2) -> Option<LightSample>;
}

impl SampleLight for AreaLight {
    /// Uniform by area (pbrt-v4 §12.2).
    #[inline(always)]
    fn sample(&self, p: Vec3, u: Vec2) -> Option<LightSample> {
        let (q, n) = self.sample_point(u);
        let to_light = q - p;
        let dist2 = to_light.length_squared();
        if dist2 == 0.0 {
            return None;
        }
        let distance = dist2.sqrt();
        let wi = to_light * distance.recip();
        let cos_light = -n.dot(wi);
        if cos_light <= 0.0 {
            return None; // the back faces p
        }
        Some(LightSample {
            wi,
            scale: 1.0,
            pdf: dist2 / (cos_light * self.area),
            distance,
            delta: false,
        })
    }
}

impl SampleLight for Light {
    #[inline(always)]
    fn sample(&self, p: Vec3, u: Vec2) -> Option<LightSample> {
        let delta = self.is_delta();
        match self {
            Light::Point { position, .. } => {
                let to_light = *position - p;
                let dist2 = to_light.length_squared();
                (dist2 > 0.0).then(|| LightSample {
                    wi: to_light / dist2.sqrt(),
                    scale: 1.0 / dist2,
                    pdf: 1.0,
                    distance: dist2.sqrt(),
                    delta,
                })
            }
            Light::Spot {
                position,
                direction,
                cos_cutoff,
                exponent,
                ..
            } => {
                let to_light = *position - p;
                let dist2 = to_light.length_squared();
                if dist2 <= 0.0 {
                    return None;
                }
                let wi = to_light / dist2.sqrt();
                let cos_axis = -wi.dot(*direction);
                (cos_axis >= *cos_cutoff && cos_axis > 0.0).then(|| LightSample {
                    wi,
                    scale: cos_axis.powf(*exponent) / dist2,
                    pdf: 1.0,
                    distance: dist2.sqrt(),
                    delta,
                })
            }
            Light::Directional { direction, .. } => Some(LightSample {
                wi: -*direction,
                scale: 1.0,
                pdf: 1.0,
                distance: f32::INFINITY,
                delta,
            }),
            Light::Environment { .. } => Some(LightSample {
                wi: uniform_sphere(u.x, u.y),
                scale: 1.0,
                pdf: UNIFORM_SPHERE_PDF,
                distance: f32::INFINITY,
                delta,
            }),
        }
    }
}

/// The parallelogram two triangles make, when they make one: they share
/// an edge, face the same way, and the corner each has off that edge is
/// the other's mirror image through the edge's midpoint (to a millionth of
/// the quad's size, so that sampling it is sampling the triangles).
fn parallelogram(triangles: &[[Vec3; 3]], crosses: &[Vec3]) -> Option<AreaShape> {
    let ([first, second], [n0, n1]) = (triangles, crosses) else {
        return None;
    };
    let normal = n0.try_normalize()?;
    if n1.try_normalize()?.dot(normal) < 1.0 - 1e-6 {
        return None;
    }
    // The corner of `first` off the shared edge, and the edge.
    for k in 0..3 {
        let (apex, p, q) = (first[k], first[(k + 1) % 3], first[(k + 2) % 3]);
        let shares = |v: Vec3| second.contains(&v);
        if !(shares(p) && shares(q)) {
            continue;
        }
        let opposite = second.iter().copied().find(|v| *v != p && *v != q)?;
        let size = (p - apex).length().max((q - apex).length());
        if (opposite - (p + q - apex)).length() > 1e-6 * size {
            return None;
        }
        return Some(AreaShape::Parallelogram {
            corner: apex,
            edge_u: p - apex,
            edge_v: q - apex,
            normal,
        });
    }
    None
}

/// A sampled direction toward a light and what arrives along it.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit direction from the shading point to the light.
    pub wi: Vec3,
    /// What arrives, before visibility, as a factor on the light's emission
    /// spectrum: incident radiance is `scale` × emission (irradiance for
    /// delta lights: 1 / distance² for a point light).
    pub scale: f32,
    /// Density per solid angle (1 for delta lights).
    pub pdf: f32,
    /// Distance to the light sample (infinite for distant lights).
    pub distance: f32,
    /// True for point and directional lights (no MIS with BSDF sampling).
    pub delta: bool,
}

impl Light {
    /// A spot light at `position` pointing along `direction` (normalised
    /// here): `intensity` on its axis, falling off as cos^`exponent` of the
    /// angle from it, none beyond `cutoff_angle_deg`, the cone's half angle
    /// (pbrt's `coneangle`, Mitsuba's `cutoff_angle`), in (0, 180]. The one
    /// rule every front end's spot light goes through.
    pub fn spot(
        position: Vec3,
        direction: Vec3,
        intensity: Emission,
        cutoff_angle_deg: f32,
        exponent: f32,
    ) -> Result<Light> {
        let fail = |m: String| Err(Error::InvalidArgument(m));
        if !(cutoff_angle_deg > 0.0 && cutoff_angle_deg <= 180.0) {
            return fail(format!("cutoff_angle_deg must be in (0, 180], got {cutoff_angle_deg}"));
        }
        if !(exponent >= 0.0 && exponent.is_finite()) {
            return fail(format!("exponent must be 0 or more, got {exponent}"));
        }
        let Some(direction) = direction.try_normalize() else {
            return fail(format!(
                "a spot light's direction must be finite and non-zero, got {direction}"
            ));
        };
        Ok(Light::Spot {
            position,
            direction,
            intensity,
            cos_cutoff: cutoff_angle_deg.to_radians().cos(),
            exponent,
        })
    }

    /// True for lights at a point or direction (point, spot, directional):
    /// every sample of one is the same ray.
    pub fn is_delta(&self) -> bool {
        !matches!(self, Light::Environment { .. })
    }

    /// For a light seen along escaping rays (the environment), the density
    /// with which [`SampleLight::sample`] picks a direction; what is seen is its
    /// emission.
    pub fn escaped_pdf(&self) -> Option<f32> {
        match *self {
            Light::Environment { .. } => Some(UNIFORM_SPHERE_PDF),
            _ => None,
        }
    }

    /// What it emits as the scene gives it: intensity, irradiance or radiance.
    pub fn emission(&self) -> &Emission {
        match self {
            Light::Point { intensity, .. } | Light::Spot { intensity, .. } => intensity,
            Light::Directional { irradiance, .. } => irradiance,
            Light::Environment { radiance } => radiance,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// Irradiance at a point below a square light, estimated by light
    /// sampling, equals the closed-form form factor of a parallel rectangle
    /// (Hottel's crossed-strings result, as tabulated by Howell's catalogue C-11).
    #[test]
    fn square_light_irradiance_matches_form_factor() {
        let (a, h) = (1.0f32, 0.7f32);
        let quad = [
            Vec3::new(-a, -a, h),
            Vec3::new(a, -a, h),
            Vec3::new(a, a, h),
            Vec3::new(-a, a, h),
        ];
        // Wound so the normal faces -z, toward the receiver at the origin.
        let light = AreaLight::from_triangles(
            vec![[quad[0], quad[2], quad[1]], [quad[0], quad[3], quad[2]]],
            Spectrum::Constant(1.0),
        )
        .unwrap();
        let mut rng = Rng::new(4);
        let n = 400_000;
        let mut e = 0.0f64;
        for _ in 0..n {
            if let Some(s) = light.sample(Vec3::ZERO, Vec2::new(rng.uniform(), rng.uniform())) {
                e += f64::from(s.scale * s.wi.z / s.pdf);
            }
        }
        let e = e / n as f64;
        // Point-to-rectangle view factor, corner formula summed over four quadrants:
        // F = 1/(2π) [A/√(1+A²) atan(B/√(1+A²)) + B/√(1+B²) atan(A/√(1+B²))], A = B = a/h.
        let x = f64::from(a / h);
        let s = (1.0 + x * x).sqrt();
        let f_corner = (2.0 * x / s * (x / s).atan()) / (2.0 * std::f64::consts::PI);
        let expected = std::f64::consts::PI * 4.0 * f_corner; // E = π L F
        assert!((e - expected).abs() / expected < 0.01, "irradiance {e} vs {expected}");
    }

    /// Two triangles that make a parallelogram are sampled as one, on
    /// the triangles, uniformly (the samples' mean is the centre, a quarter
    /// of them in each quarter); two that do not (a kite) stay triangles.
    #[test]
    fn a_quad_of_two_triangles_is_sampled_as_a_parallelogram() {
        let (a, b, c, d) = (
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(2.0, 0.0, 1.0),
            Vec3::new(3.0, 1.0, 1.0),
            Vec3::new(1.0, 1.0, 1.0),
        );
        let quad = AreaLight::from_triangles(vec![[a, b, c], [a, c, d]], Spectrum::Constant(1.0)).unwrap();
        assert!(matches!(quad.shape, AreaShape::Parallelogram { .. }));
        assert!((quad.area - 2.0).abs() < 1e-6);
        let mut rng = Rng::new(3);
        let (n, mut sum, mut quarters) = (100_000, Vec3::ZERO, [0; 4]);
        for _ in 0..n {
            let (p, normal) = quad.sample_point(Vec2::new(rng.uniform(), rng.uniform()));
            assert_eq!(normal, Vec3::Z);
            // Inside: 0 ≤ y ≤ 1 and y ≤ x ≤ y + 2.
            assert!(
                p.y >= 0.0 && p.y <= 1.0 && p.x >= p.y - 1e-6 && p.x <= p.y + 2.0 + 1e-6,
                "{p}"
            );
            sum += p;
            quarters[usize::from(p.y > 0.5) * 2 + usize::from(p.x - p.y > 1.0)] += 1;
        }
        let mean = sum / n as f32;
        assert!((mean - Vec3::new(1.5, 0.5, 1.0)).length() < 0.01, "{mean}");
        assert!(
            quarters.iter().all(|&q| (q as f32 / n as f32 - 0.25).abs() < 0.01),
            "{quarters:?}"
        );
        let kite = Vec3::new(1.0, 2.0, 1.0);
        let not_quad = AreaLight::from_triangles(vec![[a, b, c], [a, c, kite]], Spectrum::Constant(1.0)).unwrap();
        assert!(matches!(not_quad.shape, AreaShape::Triangles { .. }));
    }

    /// A spot light: inverse-square on its axis, cos^e falloff inside the cone, dark outside.
    #[test]
    fn spot_light_falls_off_inside_its_cone() {
        let spot = Light::Spot {
            position: Vec3::new(0.0, 0.0, 2.0),
            direction: Vec3::NEG_Z,
            intensity: crate::math::Rgb::splat(8.0).into(),
            cos_cutoff: 30f32.to_radians().cos(),
            exponent: 2.0,
        };
        let on_axis = spot.sample(Vec3::ZERO, Vec2::ZERO).unwrap();
        assert!((on_axis.scale * 8.0 - 2.0).abs() < 1e-6);
        // 20° off axis at the same distance: 8·cos²20°/4.
        let p = Vec3::new(
            2.0 * 20f32.to_radians().sin(),
            0.0,
            2.0 - 2.0 * 20f32.to_radians().cos(),
        );
        let off = spot.sample(p, Vec2::ZERO).unwrap();
        assert!((off.scale * 8.0 - 2.0 * 20f32.to_radians().cos().powi(2)).abs() < 1e-5);
        let outside = Vec3::new(
            2.0 * 40f32.to_radians().sin(),
            0.0,
            2.0 - 2.0 * 40f32.to_radians().cos(),
        );
        assert!(spot.sample(outside, Vec2::ZERO).is_none());
    }

    #[test]
    fn sphere_light_pdf_matches_sample() {
        let light = AreaLight::from_sphere(Vec3::new(0.0, 0.0, 5.0), 1.0, Spectrum::Constant(1.0));
        let mut rng = Rng::new(8);
        let mut seen = 0;
        for _ in 0..1000 {
            if let Some(s) = light.sample(Vec3::ZERO, Vec2::new(rng.uniform(), rng.uniform())) {
                seen += 1;
                let q = s.wi * s.distance;
                let n = (q - Vec3::new(0.0, 0.0, 5.0)).normalize();
                let pdf = light.pdf(s.distance, -n.dot(s.wi));
                assert!((pdf - s.pdf).abs() < 1e-3 * pdf);
            }
        }
        assert!(seen > 300);
    }
}
