//! Standard ray sets for measuring traversal speed (`lenspath bench bvh`,
//! the criterion benches and the peer comparisons use the same ones).

use glam::Vec3;

use crate::ray::Ray;
use crate::sampling::{uniform_sphere, Rng};

/// Rays from a grid camera outside the bounds toward the mesh.
pub fn coherent_rays(lo: Vec3, hi: Vec3, n: usize) -> Vec<Ray> {
    let centre = 0.5 * (lo + hi);
    let radius = 0.5 * (hi - lo).length();
    let eye = centre + Vec3::new(0.6, 0.5, 1.0).normalize() * radius * 2.5;
    let forward = (centre - eye).normalize();
    let right = forward.cross(Vec3::Y).normalize();
    let up = right.cross(forward);
    let side = (n as f64).sqrt().ceil() as usize;
    // A field of view that just covers the bounding sphere.
    let half = (radius / (eye - centre).length()).asin().tan();
    (0..n)
        .map(|i| {
            let (x, y) = ((i % side) as f32, (i / side) as f32);
            let sx = (2.0 * (x + 0.5) / side as f32 - 1.0) * half;
            let sy = (1.0 - 2.0 * (y + 0.5) / side as f32) * half;
            Ray::new(eye, (forward + sx * right + sy * up).normalize())
        })
        .collect()
}

/// Uniformly random origins inside the bounds with uniformly random directions.
pub fn incoherent_rays(lo: Vec3, hi: Vec3, n: usize) -> Vec<Ray> {
    let mut rng = Rng::new(42);
    (0..n)
        .map(|_| {
            let t = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform());
            Ray::new(lo + t * (hi - lo), uniform_sphere(rng.uniform(), rng.uniform()))
        })
        .collect()
}
