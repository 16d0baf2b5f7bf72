//! What the BVH holds and finds: a primitive's geometry and a ray's hit.

use glam::{Vec3, Vec3A};

use crate::math::Bounds3;
use crate::shapes::triangle_bounds;

/// One primitive's geometry (the tree keeps it in its leaf packs).
#[derive(Clone, Copy, Debug)]
pub enum PrimGeometry {
    /// A triangle by its three corners.
    Triangle([Vec3; 3]),
    /// A sphere.
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius.
        radius: f32,
    },
}

impl PrimGeometry {
    pub(super) fn bounds(&self) -> Bounds3 {
        match self {
            PrimGeometry::Triangle(p) => triangle_bounds(p),
            PrimGeometry::Sphere { center, radius } => Bounds3 {
                min: Vec3A::from(*center) - Vec3A::splat(*radius),
                max: Vec3A::from(*center) + Vec3A::splat(*radius),
            },
        }
    }
}

/// A closest hit: the distance, the primitive (its slot in the tree, see
/// [`Bvh::primitive`]) and, for triangles, the barycentrics of corners 1 and 2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// The primitive's slot: its pack's index · 4 + its lane.
    pub prim: u32,
    /// Barycentric coordinate of the second corner (triangles).
    pub b1: f32,
    /// Barycentric coordinate of the third corner (triangles).
    pub b2: f32,
}
