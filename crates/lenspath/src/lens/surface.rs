//! The shapes of refracting surfaces: spheres, flats, even aspheres (a
//! conic plus an even polynomial), cylinders and toric surfaces, with their
//! sag, its slope, and the exact intersection of a ray with each of them.
//!
//! Sag is measured along the axis from the vertex, positive toward the
//! sensor, as a function of the height `h` from the axis (for a cylinder,
//! the distance from its axis plane); a surface's curvature `c` is 1 / its
//! vertex radius (0 for a flat).

use glam::DVec3;

/// The shape of a refracting surface beyond its vertex radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SurfaceShape {
    /// A sphere of the surface's radius (a plane when the radius is infinite).
    Spherical,
    /// An even asphere whose base conic has the surface's vertex radius.
    EvenAsphere(EvenAsphere),
    /// A circular cylinder of the surface's radius whose axis runs along
    /// `CylinderAxis` (lentil's `cyl-x` / `cyl-y`): it curves only in the
    /// other meridian, which is what makes a lens anamorphic.
    Cylindrical(CylinderAxis),
    /// A cylinder whose axis is bent into an arc: the surface curves in
    /// both meridians, with a different radius in each (a toric surface,
    /// Zemax's TOROIDAL).
    Toric(Toric),
}

/// A toric surface: the circle of the surface's vertex radius in one
/// meridian (the profile) swept around an axis that is parallel to the
/// other transverse axis and crosses the optical axis `rotation_radius_mm`
/// behind the vertex. Equivalently the cylinder `Cylindrical(axis)` with
/// its axis bent into an arc of that radius; an infinite radius leaves the
/// cylinder, and a radius equal to the vertex radius gives a sphere.
///
/// With p the height in the profile's meridian and a along the bent axis,
/// g(p) the profile circle's sag and c′ = 1 / (R − g(p)) (R the rotation
/// radius): z = g(p) + c′·a² / (1 + √(1 − c′²·a²)), the sag of a circle of
/// radius R − g(p) at a (the torus of Zemax's TOROIDAL and rayoptics'
/// `YToroid` / `XToroid` with a spherical profile).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Toric {
    /// The direction the unbent cylinder's axis runs in: the surface's
    /// vertex radius curves the other meridian, the rotation radius this one.
    pub axis: CylinderAxis,
    /// Signed radius, mm, of the arc the axis is bent into (positive when its
    /// centre lies toward the sensor, as a vertex radius): the surface's
    /// radius in the axis's own meridian.
    pub rotation_radius_mm: f64,
}

impl Toric {
    /// Sag and its two partial derivatives (∂z/∂x, ∂z/∂y) at (x, y) on a
    /// toric surface of vertex curvature `curvature`; `None` where the
    /// surface does not reach.
    #[inline]
    pub fn sag_and_gradient(&self, curvature: f64, x: f64, y: f64) -> Option<(f64, f64, f64)> {
        // p across the profile's meridian, a along the bent axis.
        let (p, a) = match self.axis {
            CylinderAxis::X => (y, x),
            CylinderAxis::Y => (x, y),
        };
        let (c, rotation_curvature) = (curvature, 1.0 / self.rotation_radius_mm);
        let profile_root = (1.0 - c * c * p * p).sqrt();
        let profile = c * p * p / (1.0 + profile_root);
        let profile_slope = c * p / profile_root;
        // The circle the profile point sweeps: radius R − g(p), curvature c′.
        let bend = 1.0 - rotation_curvature * profile;
        let swept = rotation_curvature / bend;
        let root = (1.0 - swept * swept * a * a).sqrt();
        if !(root > 0.0 && profile_root > 0.0 && bend != 0.0) {
            return None;
        }
        let swept_sag = swept * a * a / (1.0 + root);
        let dz_da = swept * a / root;
        // ∂/∂c′ of c′a²/(1 + √(1 − c′²a²)), and dc′/dp = c′²·g′(p).
        let dz_dswept = a * a / (1.0 + root) + swept * swept * a.powi(4) / (root * (1.0 + root) * (1.0 + root));
        let dz_dp = profile_slope * (1.0 + swept * swept * dz_dswept);
        let sag = profile + swept_sag;
        Some(match self.axis {
            CylinderAxis::X => (sag, dz_da, dz_dp),
            CylinderAxis::Y => (sag, dz_dp, dz_da),
        })
    }

    /// The same surface on a lens with every length multiplied by `factor`.
    pub fn scaled(&self, factor: f64) -> Toric {
        Toric {
            rotation_radius_mm: self.rotation_radius_mm * factor,
            ..*self
        }
    }
}

/// The direction a cylindrical surface's axis runs in, across the optical axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CylinderAxis {
    /// Along x (the sensor's width): the surface curves in the vertical (y–z) meridian.
    X,
    /// Along y (the sensor's height): the surface curves in the horizontal (x–z) meridian.
    Y,
}

impl CylinderAxis {
    /// The meridian the surface curves in.
    pub fn curved_meridian(self) -> Meridian {
        match self {
            CylinderAxis::X => Meridian::Vertical,
            CylinderAxis::Y => Meridian::Horizontal,
        }
    }

    /// How lens tables and lentil spell it (`x`, `y`).
    pub fn spelling(self) -> &'static str {
        match self {
            CylinderAxis::X => "x",
            CylinderAxis::Y => "y",
        }
    }

    /// The axis [`CylinderAxis::spelling`] spells as `text`.
    pub fn from_spelling(text: &str) -> Option<CylinderAxis> {
        [CylinderAxis::X, CylinderAxis::Y]
            .into_iter()
            .find(|axis| axis.spelling() == text)
    }
}

/// A plane through the optical axis, in which first-order optics is traced.
/// A rotationally symmetric lens is the same in every one; an anamorphic
/// lens has its own focal length in each of these two.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Meridian {
    /// The x–z plane: across the sensor's width.
    Horizontal,
    /// The y–z plane: across the sensor's height.
    Vertical,
}

impl Meridian {
    /// Both, horizontal first.
    pub const BOTH: [Meridian; 2] = [Meridian::Horizontal, Meridian::Vertical];

    /// The unit vector across the axis in this meridian.
    pub fn across(self) -> DVec3 {
        match self {
            Meridian::Horizontal => DVec3::X,
            Meridian::Vertical => DVec3::Y,
        }
    }

    /// The component of `v` across the axis in this meridian.
    #[inline]
    pub fn component(self, v: DVec3) -> f64 {
        match self {
            Meridian::Horizontal => v.x,
            Meridian::Vertical => v.y,
        }
    }

    /// Its name as reports print it.
    pub fn name(self) -> &'static str {
        match self {
            Meridian::Horizontal => "horizontal",
            Meridian::Vertical => "vertical",
        }
    }
}

impl SurfaceShape {
    /// Sag at height² `h2` on a surface of vertex curvature `curvature`;
    /// `None` where the surface does not reach (outside a conic's domain).
    pub fn sag(&self, curvature: f64, h2: f64) -> Option<f64> {
        match self {
            SurfaceShape::Spherical | SurfaceShape::Cylindrical(_) => {
                EvenAsphere::SPHERE.sag_and_slope(curvature, h2).map(|(z, _)| z)
            }
            SurfaceShape::EvenAsphere(a) => a.sag_and_slope(curvature, h2).map(|(z, _)| z),
            // The profile's section, as for a cylinder.
            SurfaceShape::Toric(t) => {
                let (x, y) = match t.axis {
                    CylinderAxis::X => (0.0, h2.sqrt()),
                    CylinderAxis::Y => (h2.sqrt(), 0.0),
                };
                t.sag_and_gradient(curvature, x, y).map(|(z, _, _)| z)
            }
        }
    }

    /// Curvature of the surface at its vertex in `meridian`: what paraxial optics sees.
    pub fn paraxial_curvature(&self, curvature: f64, meridian: Meridian) -> f64 {
        match self {
            SurfaceShape::Spherical => curvature,
            // z ≈ (c/2 + A2) h² near the axis.
            SurfaceShape::EvenAsphere(a) => curvature + 2.0 * a.coefficients[0],
            SurfaceShape::Cylindrical(axis) if axis.curved_meridian() == meridian => curvature,
            SurfaceShape::Cylindrical(_) => 0.0,
            SurfaceShape::Toric(t) if t.axis.curved_meridian() == meridian => curvature,
            SurfaceShape::Toric(t) => 1.0 / t.rotation_radius_mm,
        }
    }

    /// True unless the surface is a cylinder or a toric surface.
    pub fn is_rotationally_symmetric(&self) -> bool {
        !matches!(self, SurfaceShape::Cylindrical(_) | SurfaceShape::Toric(_))
    }

    /// The shape a lens file gives as a conic constant and the polynomial
    /// terms of h^`first_order`, h^(`first_order` + 2), …: a sphere when all
    /// are zero; `None` when `first_order` is not an even power from 2 or
    /// the terms run past h²⁰ (each reader names its own limit).
    pub fn from_terms(conic: f64, first_order: usize, terms: &[f64]) -> Option<SurfaceShape> {
        if first_order < 2 || first_order % 2 != 0 || first_order / 2 - 1 + terms.len() > 10 {
            return None;
        }
        if conic == 0.0 && terms.iter().all(|&a| a == 0.0) {
            return Some(SurfaceShape::Spherical);
        }
        let mut asphere = EvenAsphere {
            conic,
            ..EvenAsphere::SPHERE
        };
        let first = first_order / 2 - 1;
        asphere.coefficients[first..first + terms.len()].copy_from_slice(terms);
        Some(SurfaceShape::EvenAsphere(asphere))
    }

    /// The same shape on a lens with every length multiplied by `factor`.
    pub fn scaled(&self, factor: f64) -> SurfaceShape {
        match self {
            SurfaceShape::Spherical | SurfaceShape::Cylindrical(_) => *self,
            SurfaceShape::EvenAsphere(a) => SurfaceShape::EvenAsphere(a.scaled(factor)),
            SurfaceShape::Toric(t) => SurfaceShape::Toric(t.scaled(factor)),
        }
    }
}

/// An even asphere (ISO 10110-12; Zemax's EVENASPH, Code V's ASP):
///
/// z(h) = c·h² / (1 + √(1 − (1 + k)·c²·h²)) + Σᵢ₌₁…₁₀ A₂ᵢ·h²ⁱ
///
/// with c the vertex curvature, k the conic constant (0 sphere, −1
/// paraboloid, < −1 hyperboloid, between −1 and 0 prolate and above 0
/// oblate ellipsoid) and A₂ … A₂₀ the polynomial coefficients, in
/// mm^(1−2i).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EvenAsphere {
    /// Conic constant k.
    pub conic: f64,
    /// A₂, A₄, …, A₂₀: the coefficient of h², h⁴, …, h²⁰.
    pub coefficients: [f64; 10],
}

impl EvenAsphere {
    /// A sphere written as an asphere: no conic, no polynomial.
    pub const SPHERE: EvenAsphere = EvenAsphere {
        conic: 0.0,
        coefficients: [0.0; 10],
    };

    /// The power of h each coefficient multiplies.
    pub const ORDERS: [u32; 10] = [2, 4, 6, 8, 10, 12, 14, 16, 18, 20];

    /// Sag and its derivative with respect to h², at height² `h2`; `None`
    /// outside the base conic's domain (where 1 − (1 + k)·c²·h² < 0; at 0,
    /// its rim, the slope is infinite).
    #[inline]
    pub fn sag_and_slope(&self, curvature: f64, h2: f64) -> Option<(f64, f64)> {
        let c = curvature;
        let root_arg = 1.0 - (1.0 + self.conic) * c * c * h2;
        if root_arg < 0.0 && c != 0.0 {
            return None;
        }
        let root = root_arg.sqrt();
        // d/d(h²) of the conic term: c / (2√(1 − (1 + k)c²h²)).
        let (mut sag, mut slope) = (c * h2 / (1.0 + root), 0.5 * c / root);
        if c == 0.0 {
            (sag, slope) = (0.0, 0.0);
        }
        // Horner in h² for Σ A₂ᵢ (h²)ⁱ and Σ i·A₂ᵢ (h²)ⁱ⁻¹.
        let (mut poly, mut poly_slope) = (0.0, 0.0);
        for (i, &a) in self.coefficients.iter().enumerate().rev() {
            poly_slope = poly_slope * h2 + (i + 1) as f64 * a;
            poly = (poly + a) * h2;
        }
        Some((sag + poly, slope + poly_slope))
    }

    /// The same surface on a lens with every length multiplied by `factor`:
    /// z′(h′) = factor·z(h′/factor), so A₂ᵢ scales by factor^(1−2i).
    pub fn scaled(&self, factor: f64) -> EvenAsphere {
        let mut coefficients = self.coefficients;
        for (a, order) in coefficients.iter_mut().zip(Self::ORDERS) {
            *a *= factor.powi(1 - order as i32);
        }
        EvenAsphere {
            conic: self.conic,
            coefficients,
        }
    }
}

/// How close a converged asphere hit lies to the surface, along the ray, mm.
pub const ASPHERE_TOLERANCE_MM: f64 = 1e-10;

/// Newton steps before an asphere intersection is given up as failed.
const ASPHERE_MAX_STEPS: usize = 40;

/// The hit of the ray `origin + t·direction` on the even asphere of vertex
/// `vertex_z` and curvature `curvature`: [`intersect_by_newton`] with the
/// asphere's sag, whose gradient is (2x·s′, 2y·s′) with s′ = dz/d(h²).
#[inline]
fn intersect_even_asphere(
    origin: DVec3,
    direction: DVec3,
    vertex_z: f64,
    curvature: f64,
    asphere: &EvenAsphere,
    t_start: f64,
) -> Option<(f64, DVec3)> {
    intersect_by_newton(origin, direction, vertex_z, t_start, |x, y| {
        let (sag, slope) = asphere.sag_and_slope(curvature, x * x + y * y)?;
        Some((sag, 2.0 * x * slope, 2.0 * y * slope))
    })
}

/// The hit of the ray `origin + t·direction` on the surface of vertex
/// `vertex_z` whose sag and its partial derivatives at (x, y) are
/// `sag_and_gradient(x, y)` = (z, ∂z/∂x, ∂z/∂y), found by Newton's method on
/// f(t) = vertex_z + sag(x(t), y(t)) − z(t) from `t_start` (the hit on a
/// nearby sphere, cylinder or plane, which picks the right sheet), as
/// Spencer & Murty (1962) trace general surfaces. Returns t and the unit
/// normal (the gradient of f: (∂z/∂x, ∂z/∂y, −1)); `None` when it does not
/// converge to [`ASPHERE_TOLERANCE_MM`] within 40 steps, or the ray leaves
/// the surface's domain.
#[inline]
pub(crate) fn intersect_by_newton(
    origin: DVec3,
    direction: DVec3,
    vertex_z: f64,
    t_start: f64,
    sag_and_gradient: impl Fn(f64, f64) -> Option<(f64, f64, f64)>,
) -> Option<(f64, DVec3)> {
    let mut t = t_start;
    for _ in 0..ASPHERE_MAX_STEPS {
        let p = origin + direction * t;
        let (sag, dz_dx, dz_dy) = sag_and_gradient(p.x, p.y)?;
        let gradient = DVec3::new(dz_dx, dz_dy, -1.0);
        let f = vertex_z + sag - p.z;
        let df_dt = gradient.dot(direction);
        if df_dt == 0.0 || !df_dt.is_finite() {
            return None;
        }
        let step = f / df_dt;
        t -= step;
        if step.abs() <= ASPHERE_TOLERANCE_MM {
            let p = origin + direction * t;
            let (_, dz_dx, dz_dy) = sag_and_gradient(p.x, p.y)?;
            return Some((t, DVec3::new(dz_dx, dz_dy, -1.0).normalize()));
        }
    }
    None
}

/// A surface's vertex as a ray meets it: where it sits on the axis and its
/// signed vertex radius.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Vertex {
    /// Position on the axis, mm.
    pub z_mm: f64,
    /// Signed vertex radius, mm (infinite: a flat; 0: the stop).
    pub radius_mm: f64,
    /// 1 / |radius|, which scales the centre-to-hit vector to the unit normal.
    pub inv_abs_radius: f64,
}

impl Vertex {
    /// Where the ray `origin + t·direction` crosses the vertex plane.
    #[inline(always)]
    fn plane_t(&self, origin: DVec3, direction: DVec3) -> f64 {
        (self.z_mm - origin.z) / direction.z
    }
}

/// The hit of the ray `origin + t·direction` on the sphere of `vertex`, on
/// the cap around the vertex, with the unit normal there (pointing away
/// from the centre), for a ray travelling toward +z or not.
/// After pbrt-v4 `RealisticCamera::IntersectSphericalElement`.
#[inline(always)]
pub(crate) fn intersect_sphere(
    origin: DVec3,
    direction: DVec3,
    vertex: &Vertex,
    toward_positive_z: bool,
) -> Option<(f64, DVec3)> {
    let radius = vertex.radius_mm;
    let center = DVec3::new(0.0, 0.0, vertex.z_mm + radius);
    let oc = origin - center;
    let b = oc.dot(direction);
    let c = oc.length_squared() - radius * radius;
    let discriminant = b * b - c;
    if discriminant < 0.0 {
        return None;
    }
    // The vertex side is hit first when travel goes from the vertex toward
    // the centre. Decided by the sense of travel, not by the sign of the
    // ray's z, so rays far off axis (even past 90°) take the right cap.
    let want_near = toward_positive_z == (radius > 0.0);
    // -b ± √D directly: the root wanted is never the one near 0 (that would
    // be a ray starting on this very surface), so cancellation costs at most
    // |b|/|t| ≤ 1e4 ulps, ~1e-12 mm, and no division sits on the ray's path.
    let root = discriminant.sqrt();
    let t = if want_near { -b - root } else { -b + root };
    let p = origin + direction * t;
    Some((t, (p - center) * vertex.inv_abs_radius))
}

/// The hit on the cylinder of `vertex` whose axis runs along `axis`, with
/// the unit normal there: [`intersect_sphere`]'s computation in the plane
/// the cylinder curves in, the ray's component along the axis dropped (it
/// only carries the ray along the cylinder).
#[inline(always)]
pub(crate) fn intersect_cylinder(
    origin: DVec3,
    direction: DVec3,
    vertex: &Vertex,
    axis: CylinderAxis,
    toward_positive_z: bool,
) -> Option<(f64, DVec3)> {
    let keep = match axis {
        CylinderAxis::X => DVec3::new(0.0, 1.0, 1.0),
        CylinderAxis::Y => DVec3::new(1.0, 0.0, 1.0),
    };
    let radius = vertex.radius_mm;
    let center = DVec3::new(0.0, 0.0, vertex.z_mm + radius);
    let (oc, d) = ((origin - center) * keep, direction * keep);
    // |oc + t·d|² = R², with d no longer a unit vector.
    let a = d.length_squared();
    let b = oc.dot(d);
    let c = oc.length_squared() - radius * radius;
    let discriminant = b * b - a * c;
    if discriminant < 0.0 || a == 0.0 {
        return None;
    }
    let want_near = toward_positive_z == (radius > 0.0);
    let root = discriminant.sqrt();
    let t = if want_near { (-b - root) / a } else { (-b + root) / a };
    let p = origin + direction * t;
    Some((t, (p - center) * keep * vertex.inv_abs_radius))
}

/// The hit on the even asphere of `vertex`, with the unit normal there:
/// Newton's method from the vertex sphere's hit on the right cap (or the
/// vertex plane's, for a flat base or a sphere the ray misses).
#[inline(always)]
pub(crate) fn intersect_asphere(
    origin: DVec3,
    direction: DVec3,
    vertex: &Vertex,
    asphere: &EvenAsphere,
    toward_positive_z: bool,
) -> Option<(f64, DVec3)> {
    let t_start = match vertex.radius_mm.is_finite() {
        true => intersect_sphere(origin, direction, vertex, toward_positive_z).map(|(t, _)| t),
        false => None,
    }
    .unwrap_or_else(|| vertex.plane_t(origin, direction));
    intersect_even_asphere(origin, direction, vertex.z_mm, 1.0 / vertex.radius_mm, asphere, t_start)
}

/// The hit on the toric surface of `vertex`, with the unit normal there:
/// Newton's method from the hit on the cylinder of its profile (the surface
/// before its axis is bent), or on the vertex plane for a flat profile or a
/// cylinder the ray misses.
#[inline(always)]
pub(crate) fn intersect_toric(
    origin: DVec3,
    direction: DVec3,
    vertex: &Vertex,
    toric: &Toric,
    toward_positive_z: bool,
) -> Option<(f64, DVec3)> {
    let t_start = match vertex.radius_mm.is_finite() {
        true => intersect_cylinder(origin, direction, vertex, toric.axis, toward_positive_z).map(|(t, _)| t),
        false => None,
    }
    .unwrap_or_else(|| vertex.plane_t(origin, direction));
    let curvature = 1.0 / vertex.radius_mm;
    intersect_by_newton(origin, direction, vertex.z_mm, t_start, |x, y| {
        toric.sag_and_gradient(curvature, x, y)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The conic term with k = 0 is the sphere's sag R − √(R² − h²), and its
    /// slope the sphere's; the polynomial adds its own terms exactly.
    #[test]
    fn sag_and_slope_are_the_formula_and_its_derivative() {
        let radius = 40.0;
        for h in [0.0, 3.0, 11.0, 25.0, 39.0] {
            let (z, _) = EvenAsphere::SPHERE.sag_and_slope(1.0 / radius, h * h).unwrap();
            let sphere = radius - (radius * radius - h * h).sqrt();
            assert!((z - sphere).abs() < 1e-12, "h {h}: {z} vs {sphere}");
        }
        let asphere = EvenAsphere {
            conic: -1.7,
            coefficients: [1e-3, 2e-5, -3e-8, 4e-11, 0.0, 0.0, 0.0, 0.0, 0.0, 1e-30],
        };
        let c = 1.0 / 25.0;
        for h in [0.5, 4.0, 9.0, 14.0] {
            let h2: f64 = h * h;
            let (z, slope) = asphere.sag_and_slope(c, h2).unwrap();
            let conic = c * h2 / (1.0 + (1.0 - (1.0 + asphere.conic) * c * c * h2).sqrt());
            let poly: f64 = asphere
                .coefficients
                .iter()
                .zip(EvenAsphere::ORDERS)
                .map(|(a, order)| a * h.powi(order as i32))
                .sum();
            assert!((z - (conic + poly)).abs() < 1e-12 * (1.0 + z.abs()), "h {h}");
            // The slope against a central difference in h².
            let d = 1e-4 * h2;
            let numeric =
                (asphere.sag_and_slope(c, h2 + d).unwrap().0 - asphere.sag_and_slope(c, h2 - d).unwrap().0) / (2.0 * d);
            assert!(
                (slope - numeric).abs() < 1e-7 * (1.0 + slope.abs()),
                "h {h}: {slope} vs {numeric}"
            );
        }
        // An oblate ellipsoid ends where 1 − (1 + k)c²h² reaches 0.
        let oblate = EvenAsphere {
            conic: 3.0,
            coefficients: [0.0; 10],
        };
        assert!(oblate.sag_and_slope(0.1, 4.0 * 4.0).is_some());
        assert!(oblate.sag_and_slope(0.1, 5.1 * 5.1).is_none());
    }

    /// Scaling a lens scales every sag: z′(f·h) = f·z(h).
    #[test]
    fn a_scaled_asphere_has_the_scaled_sag() {
        let asphere = EvenAsphere {
            conic: -0.6,
            coefficients: [0.0, 3e-5, -2e-8, 1e-11, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        };
        let (c, factor) = (1.0 / 30.0, 2.5);
        let big = asphere.scaled(factor);
        for h in [1.0, 5.0, 10.0] {
            let z = asphere.sag_and_slope(c, h * h).unwrap().0;
            let z_big = big.sag_and_slope(c / factor, (factor * h) * (factor * h)).unwrap().0;
            assert!((z_big - factor * z).abs() < 1e-12, "h {h}: {z_big} vs {}", factor * z);
        }
    }

    /// A toric surface's sag lies on its torus, (z − R)² + a² = (R − g(p))²
    /// (the profile point swept round the axis R behind the vertex), its
    /// gradient is the sag's central difference, and an infinite rotation
    /// radius leaves the cylinder while one equal to the vertex radius gives
    /// the sphere.
    #[test]
    fn a_toric_sag_lies_on_its_torus() {
        let c = 1.0 / 40.0;
        for (axis, rotation_radius_mm) in [
            (CylinderAxis::X, 25.0),
            (CylinderAxis::Y, -55.0),
            (CylinderAxis::X, -70.0),
        ] {
            let toric = Toric {
                axis,
                rotation_radius_mm,
            };
            for (x, y) in [
                (0.0, 0.0),
                (3.0, 0.0),
                (0.0, 7.0),
                (5.0, -6.0),
                (-9.0, 8.0),
                (10.5, 2.0),
            ] {
                let (z, dz_dx, dz_dy) = toric.sag_and_gradient(c, x, y).unwrap();
                let (p, a) = match axis {
                    CylinderAxis::X => (y, x),
                    CylinderAxis::Y => (x, y),
                };
                let g = 40.0 - (40.0f64 * 40.0 - p * p).sqrt();
                let r = rotation_radius_mm;
                let torus = (z - r).powi(2) + a * a - (r - g).powi(2);
                assert!(torus.abs() < 1e-9, "{axis:?} {r} at ({x}, {y}): {torus}");
                let d = 1e-5;
                let sag = |x: f64, y: f64| toric.sag_and_gradient(c, x, y).unwrap().0;
                let numeric = (
                    (sag(x + d, y) - sag(x - d, y)) / (2.0 * d),
                    (sag(x, y + d) - sag(x, y - d)) / (2.0 * d),
                );
                assert!(
                    (dz_dx - numeric.0).abs() < 1e-7 && (dz_dy - numeric.1).abs() < 1e-7,
                    "{axis:?} {r} at ({x}, {y}): ({dz_dx}, {dz_dy}) vs {numeric:?}"
                );
            }
        }
        for (x, y) in [(3.0, 4.0), (-8.0, 1.0)] {
            let flat_bend = Toric {
                axis: CylinderAxis::X,
                rotation_radius_mm: 1e300,
            };
            let cylinder = EvenAsphere::SPHERE.sag_and_slope(c, y * y).unwrap().0;
            assert!((flat_bend.sag_and_gradient(c, x, y).unwrap().0 - cylinder).abs() < 1e-12);
            let sphere_bend = Toric {
                axis: CylinderAxis::Y,
                rotation_radius_mm: 40.0,
            };
            let sphere = EvenAsphere::SPHERE.sag_and_slope(c, x * x + y * y).unwrap().0;
            assert!((sphere_bend.sag_and_gradient(c, x, y).unwrap().0 - sphere).abs() < 1e-12);
        }
        // Beyond the swept circle (radius 25 − g at the rim) there is no surface.
        let tight = Toric {
            axis: CylinderAxis::X,
            rotation_radius_mm: 25.0,
        };
        assert!(tight.sag_and_gradient(c, 25.5, 0.0).is_none());
    }

    /// Hits land on the surface to the tolerance, with the normal
    /// perpendicular to it, for rays steep and shallow, from either side.
    #[test]
    fn intersections_land_on_the_surface() {
        let asphere = EvenAsphere {
            conic: -2.2,
            coefficients: [0.0, 4e-5, -1e-7, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        };
        let (c, vertex_z) = (1.0 / 18.0, 3.0);
        let mut hits = 0;
        for k in 0..200 {
            let a = k as f64 * 0.731;
            let origin = DVec3::new(6.0 * a.cos(), 6.0 * a.sin(), -20.0);
            let target = DVec3::new(9.0 * (1.7 * a).sin(), 9.0 * (2.3 * a).cos(), vertex_z);
            let direction = (target - origin).normalize();
            for (o, d) in [(origin, direction), (origin + direction * 60.0, -direction)] {
                let t_start = (vertex_z - o.z) / d.z;
                let Some((t, normal)) = intersect_even_asphere(o, d, vertex_z, c, &asphere, t_start) else {
                    continue;
                };
                let p = o + d * t;
                let h2 = p.x * p.x + p.y * p.y;
                let (sag, _) = asphere.sag_and_slope(c, h2).unwrap();
                assert!(
                    (vertex_z + sag - p.z).abs() < 1e-9,
                    "off the surface by {}",
                    vertex_z + sag - p.z
                );
                // A tangent along the surface: from p toward a neighbour on it.
                let q = DVec3::new(p.x + 1e-4, p.y, 0.0);
                let q = DVec3::new(
                    q.x,
                    q.y,
                    vertex_z + asphere.sag_and_slope(c, q.x * q.x + q.y * q.y).unwrap().0,
                );
                assert!(normal.dot((q - p).normalize()).abs() < 1e-3);
                hits += 1;
            }
        }
        assert!(hits > 300, "{hits}");
    }
}
