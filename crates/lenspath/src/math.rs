//! Small geometric helpers shared by every module: colours, bounding boxes, orthonormal frames.

use glam::{Vec3, Vec3A};

/// The largest scene coordinate lenspath accepts, in scene units: it
/// computes in 32-bit floats, whose squares overflow past about 1.8e19, so
/// beyond this the distance between two points is no longer a number.
pub const MAX_SCENE_COORDINATE: f32 = 1e18;

/// True when every coordinate of `p` is finite and within
/// ±[`MAX_SCENE_COORDINATE`].
pub fn within_scene_range(p: Vec3) -> bool {
    p.is_finite() && p.abs().max_element() <= MAX_SCENE_COORDINATE
}

/// A linear RGB radiometric quantity (radiance, reflectance, power...).
pub type Rgb = Vec3;

/// An axis-aligned bounding box. Empty boxes have `min > max`. `repr(C)`:
/// the BVH build loads one as 32 bytes, min then max.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Bounds3 {
    /// Lower corner.
    pub min: Vec3A,
    /// Upper corner.
    pub max: Vec3A,
}

impl Bounds3 {
    /// The empty box: the identity of [`Bounds3::union`].
    pub const EMPTY: Bounds3 = Bounds3 {
        min: Vec3A::splat(f32::INFINITY),
        max: Vec3A::splat(f32::NEG_INFINITY),
    };

    /// The box around a single point.
    #[inline]
    pub fn from_point(p: Vec3A) -> Self {
        Bounds3 { min: p, max: p }
    }

    /// The smallest box holding both boxes.
    #[inline]
    pub fn union(self, other: Bounds3) -> Bounds3 {
        Bounds3 {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// The smallest box holding this box and a point.
    #[inline]
    pub fn grow(self, p: Vec3A) -> Bounds3 {
        Bounds3 {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// True when the box holds no point.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    /// Edge lengths (zero for an empty box).
    #[inline]
    pub fn diagonal(&self) -> Vec3A {
        (self.max - self.min).max(Vec3A::ZERO)
    }

    /// Surface area; zero for an empty or flat-to-a-line box.
    #[inline]
    pub fn surface_area(&self) -> f32 {
        let d = self.diagonal();
        2.0 * d.dot(glam::Vec3A::new(d.y, d.z, d.x))
    }

    /// Centre of the box.
    #[inline]
    pub fn centroid(&self) -> Vec3A {
        0.5 * (self.min + self.max)
    }

    /// Axis (0 = x, 1 = y, 2 = z) along which the box is longest.
    #[inline]
    pub fn max_extent_axis(&self) -> usize {
        let d = self.diagonal();
        if d.x >= d.y && d.x >= d.z {
            0
        } else if d.y >= d.z {
            1
        } else {
            2
        }
    }
}

/// An orthonormal frame `(s, t, n)`; local coordinates have the normal along +z.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    /// First tangent.
    pub s: Vec3,
    /// Second tangent.
    pub t: Vec3,
    /// Normal.
    pub n: Vec3,
}

impl Frame {
    /// A frame around the unit normal `n`: the branchless construction of
    /// Duff et al., "Building an Orthonormal Basis, Revisited", JCGT 2017.
    #[inline]
    pub fn from_normal(n: Vec3) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        Frame {
            s: Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
            t: Vec3::new(b, sign + n.y * n.y * a, -n.y),
            n,
        }
    }

    /// World direction to local coordinates.
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    /// Local direction to world coordinates.
    #[inline]
    pub fn from_local(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal_for_all_normals() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.3, -0.8, 0.1).normalize(),
            Vec3::new(0.0, 0.0, -0.99999).normalize(),
        ] {
            let f = Frame::from_normal(n);
            assert!((f.s.length() - 1.0).abs() < 1e-5);
            assert!((f.t.length() - 1.0).abs() < 1e-5);
            assert!(f.s.dot(f.t).abs() < 1e-5 && f.s.dot(n).abs() < 1e-5 && f.t.dot(n).abs() < 1e-5);
            let v = Vec3::new(0.2, 0.5, -0.7);
            assert!((f.from_local(f.to_local(v)) - v).length() < 1e-5);
        }
    }

    #[test]
    fn bounds_surface_area_and_union() {
        let b = Bounds3::from_point(Vec3A::ZERO).grow(Vec3A::new(1.0, 2.0, 3.0));
        assert_eq!(b.surface_area(), 2.0 * (2.0 + 6.0 + 3.0));
        assert!(Bounds3::EMPTY.is_empty());
        assert_eq!(Bounds3::EMPTY.union(b), b);
        assert_eq!(b.max_extent_axis(), 2);
    }
}
