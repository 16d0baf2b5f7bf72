//! Rays and the offset that keeps a spawned ray from re-hitting the surface it leaves.

use glam::Vec3;

/// A ray `origin + t * direction`. Directions need not be normalised, but
/// every ray the integrator spawns has a unit direction.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    /// Where the ray starts.
    pub origin: Vec3,
    /// Where it goes.
    pub direction: Vec3,
}

impl Ray {
    /// A ray from `origin` along `direction`.
    #[inline]
    pub fn new(origin: Vec3, direction: Vec3) -> Self {
        Ray { origin, direction }
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.direction
    }
}

/// Moves `p` off its surface (normal `n`) to the side `w` points to, by a
/// distance that grows with |p| as float rounding does. A simpler stand-in
/// for pbrt-v4's error-bound offset (`OffsetRayOrigin`), calibrated so the
/// watertightness and furnace tests see no self-intersection.
#[inline]
pub fn offset_origin(p: Vec3, n: Vec3, w: Vec3) -> Vec3 {
    let magnitude = p.abs().max_element();
    let offset = 1e-5 * (1.0 + magnitude);
    if w.dot(n) >= 0.0 {
        p + offset * n
    } else {
        p - offset * n
    }
}
