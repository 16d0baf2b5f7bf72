//! The shapes of refracting surfaces: spheres, flats, even aspheres (a
//! conic plus an even polynomial) and cylinders, with their sag, its slope,
//! and the exact intersection of a ray with an asphere.
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
        }
    }

    /// True unless the surface is a cylinder.
    pub fn is_rotationally_symmetric(&self) -> bool {
        !matches!(self, SurfaceShape::Cylindrical(_))
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
/// `vertex_z` and curvature `curvature`, found by Newton's method on
/// f(t) = vertex_z + sag(h²(t)) − z(t) from `t_start` (the hit on the
/// vertex sphere or plane, which picks the right sheet), as Spencer & Murty
/// (1962) trace general surfaces. Returns t and the unit normal (the
/// gradient of f: (2x·s′, 2y·s′, −1) with s′ = dz/d(h²)); `None` when it does
/// not converge to [`ASPHERE_TOLERANCE_MM`] within 40 steps, or the ray leaves
/// the surface's domain.
#[inline]
pub(crate) fn intersect_even_asphere(
    origin: DVec3,
    direction: DVec3,
    vertex_z: f64,
    curvature: f64,
    asphere: &EvenAsphere,
    t_start: f64,
) -> Option<(f64, DVec3)> {
    let mut t = t_start;
    for _ in 0..ASPHERE_MAX_STEPS {
        let p = origin + direction * t;
        let (sag, slope) = asphere.sag_and_slope(curvature, p.x * p.x + p.y * p.y)?;
        let gradient = DVec3::new(2.0 * p.x * slope, 2.0 * p.y * slope, -1.0);
        let f = vertex_z + sag - p.z;
        let df_dt = gradient.dot(direction);
        if df_dt == 0.0 || !df_dt.is_finite() {
            return None;
        }
        let step = f / df_dt;
        t -= step;
        if step.abs() <= ASPHERE_TOLERANCE_MM {
            let p = origin + direction * t;
            let (_, slope) = asphere.sag_and_slope(curvature, p.x * p.x + p.y * p.y)?;
            return Some((t, DVec3::new(2.0 * p.x * slope, 2.0 * p.y * slope, -1.0).normalize()));
        }
    }
    None
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
