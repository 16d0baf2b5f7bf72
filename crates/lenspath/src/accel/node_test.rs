//! The wide node test: which of a node's eight children's boxes a ray
//! enters, and where. The portable test, four lanes at a time, and the AVX2
//! kernel, eight at once, side by side: the same numbers bit for bit.

use std::mem::{offset_of, size_of};

use glam::{Vec3A, Vec4};

#[cfg(test)]
use super::build;
use super::layout::{WideNode, QUADS, WIDTH};
use crate::ray::Ray;
use crate::shapes::TriangleRay;

/// 1 + 2γ₃ (pbrt-v4): widens the far slab distance so rounding never
/// culls a box the ray touches, e.g. the flat box of an axis-aligned quad.
pub(super) const SLAB_SAFETY: f32 = 1.0 + 2.0 * 3.0 * f32::EPSILON * 0.5 / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// Per-ray traversal constants.
pub(super) struct TraversalRay {
    pub(super) origin: Vec3A,
    pub(super) inv_dir: Vec3A,
    /// Per axis, where in a [`WideNode`] the planes the ray enters by lie
    /// (bytes from its start: the boxes' `min` where the direction is
    /// positive, else `max`), and the ones it leaves by.
    pub(super) near_far_offsets: [(usize, usize); 3],
    pub(super) tri: TriangleRay,
}

impl TraversalRay {
    pub(super) fn new(ray: &Ray) -> Self {
        // A zero component becomes a tiny one so 0 · ∞ never makes a NaN.
        let d = Vec3A::from(ray.direction);
        let d = Vec3A::select(d.abs().cmplt(Vec3A::splat(1e-30)), Vec3A::splat(1e-30).copysign(d), d);
        let (min, max) = (offset_of!(WideNode, min), offset_of!(WideNode, max));
        let row = size_of::<[Vec4; QUADS]>();
        let near_far_offsets = std::array::from_fn(|axis| {
            let (near, far) = if d[axis] < 0.0 { (max, min) } else { (min, max) };
            (near + axis * row, far + axis * row)
        });
        TraversalRay {
            origin: Vec3A::from(ray.origin),
            inv_dir: d.recip(),
            near_far_offsets,
            tri: TriangleRay::new(ray),
        }
    }

    /// Which of `node`'s children's boxes the ray meets before `t_max` (bit
    /// `k` for lane `k`), and where it enters each: four lanes at a time.
    #[inline(always)]
    pub(super) fn wide_entries(&self, node: &WideNode, t_max: f32) -> (u32, [f32; WIDTH]) {
        let (o, inv) = (self.origin, self.inv_dir);
        let mut hit = 0;
        let mut entries = [0.0; WIDTH];
        for q in 0..QUADS {
            let slab = |axis: usize, o: f32, inv: f32| {
                let t0 = (node.min[axis][q] - Vec4::splat(o)) * inv;
                let t1 = (node.max[axis][q] - Vec4::splat(o)) * inv;
                (t0.min(t1), t0.max(t1))
            };
            let (nx, fx) = slab(0, o.x, inv.x);
            let (ny, fy) = slab(1, o.y, inv.y);
            let (nz, fz) = slab(2, o.z, inv.z);
            let t_near = nx.max(ny).max(nz).max(Vec4::ZERO);
            let t_far = fx.min(fy).min(fz) * SLAB_SAFETY;
            hit |= t_near.cmple(t_far.min(Vec4::splat(t_max))).bitmask() << (4 * q);
            entries[4 * q..4 * q + 4].copy_from_slice(&t_near.to_array());
        }
        (hit & u32::from(node.lanes), entries)
    }

    /// [`Self::wide_entries`], or with `AVX2` [`Self::wide_entries_avx2`].
    #[inline(always)]
    pub(super) fn entries<const AVX2: bool>(&self, node: &WideNode, t_max: f32) -> (u32, [f32; WIDTH]) {
        #[cfg(target_arch = "x86_64")]
        if AVX2 {
            // SAFETY: `AVX2` is only set by `traverse_wide_avx2`, which runs
            // on CPUs with the features.
            return unsafe { self.wide_entries_avx2(node, t_max) };
        }
        self.wide_entries(node, t_max)
    }

    /// [`Self::wide_entries`] for all eight lanes in one AVX step, bit for
    /// bit the same result (the test `avx2_node_test_matches_the_portable_one_lane_for_lane`
    /// checks it).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    #[inline]
    pub(super) fn wide_entries_avx2(&self, node: &WideNode, t_max: f32) -> (u32, [f32; WIDTH]) {
        use std::arch::x86_64::*;
        let (inside, t_near) = self.wide_slabs_avx2(node, t_max);
        let mut entries = [0.0; WIDTH];
        // SAFETY: `entries` holds eight floats.
        unsafe { _mm256_storeu_ps(entries.as_mut_ptr(), t_near) };
        (_mm256_movemask_ps(inside) as u32 & u32::from(node.lanes), entries)
    }

    /// The AVX2 slab test of `node`'s eight boxes: all ones in the lanes the
    /// ray enters before `t_max` (unused lanes included), and the entry
    /// distances.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    #[inline]
    pub(super) fn wide_slabs_avx2(
        &self,
        node: &WideNode,
        t_max: f32,
    ) -> (std::arch::x86_64::__m256, std::arch::x86_64::__m256) {
        use std::arch::x86_64::*;
        const { assert!(WIDTH == 8) };
        let (o, inv) = (self.origin.to_array(), self.inv_dir.to_array());
        let mut near = [_mm256_setzero_ps(); 3];
        let mut far = [_mm256_setzero_ps(); 3];
        let start: *const u8 = (node as *const WideNode).cast();
        for axis in 0..3 {
            // The planes by the direction's sign (Embree's near/far offsets):
            // no min and max of the two distances. The same numbers as the
            // scalar test's: with `min <= max` in every lane, unused ones
            // too, the near plane's distance is the smaller after rounding,
            // as `inv` has the direction's sign (faster than the min and
            // max: BENCHMARKS.md, issue 34, fiftieth session).
            let (near_offset, far_offset) = self.near_far_offsets[axis];
            // SAFETY: both offsets are of one of the node's `[Vec4; 2]`
            // rows, eight contiguous floats.
            let (enter, leave) = unsafe {
                (
                    _mm256_loadu_ps(start.add(near_offset).cast()),
                    _mm256_loadu_ps(start.add(far_offset).cast()),
                )
            };
            let (o, inv) = (_mm256_set1_ps(o[axis]), _mm256_set1_ps(inv[axis]));
            near[axis] = _mm256_mul_ps(_mm256_sub_ps(enter, o), inv);
            far[axis] = _mm256_mul_ps(_mm256_sub_ps(leave, o), inv);
        }
        let t_near = _mm256_max_ps(
            _mm256_max_ps(_mm256_max_ps(near[0], near[1]), near[2]),
            _mm256_setzero_ps(),
        );
        let t_far = _mm256_mul_ps(
            _mm256_min_ps(_mm256_min_ps(far[0], far[1]), far[2]),
            _mm256_set1_ps(SLAB_SAFETY),
        );
        let inside = _mm256_cmp_ps::<_CMP_LE_OQ>(t_near, _mm256_min_ps(t_far, _mm256_set1_ps(t_max)));
        (inside, t_near)
    }

    #[cfg(test)]
    #[inline(always)]
    pub(super) fn hits_box(&self, node: &build::Node, t_max: f32) -> bool {
        let t0 = (Vec3A::from_array(node.min) - self.origin) * self.inv_dir;
        let t1 = (Vec3A::from_array(node.max) - self.origin) * self.inv_dir;
        let t_near = t0.min(t1).max_element().max(0.0);
        let t_far = t0.max(t1).min_element() * SLAB_SAFETY;
        t_near <= t_far.min(t_max)
    }
}

/// Whether this CPU runs the AVX2 traversal (it needs AVX2 and FMA).
#[cfg(target_arch = "x86_64")]
#[inline]
pub(super) fn cpu_has_avx2() -> bool {
    std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma")
}

#[cfg(test)]
mod tests {
    use super::super::tests::{random_triangles, room_walls};
    use super::super::{Bvh, BvhSettings};
    use super::*;
    use crate::sampling::Rng;
    use glam::Vec3;

    /// The AVX2 node test gives bit for bit the portable one's mask and
    /// entry distances on every node of a tree, for random rays (some with
    /// zero direction components) and closest-hit limits.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx2_node_test_matches_the_portable_one_lane_for_lane() {
        if !cpu_has_avx2() {
            eprintln!("skipped: this CPU has no AVX2 and FMA");
            return;
        }
        let mut rng = Rng::new(11);
        let mut prims = random_triangles(2000, &mut rng);
        prims.extend(room_walls(20_000));
        let bvh = Bvh::build(prims, &BvhSettings::default());
        let mut compared = 0;
        for i in 0..2000 {
            let mut o = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 14.0 - 2.0;
            let mut d = crate::sampling::uniform_sphere(rng.uniform(), rng.uniform());
            if i % 4 == 0 {
                d[i / 4 % 3] = 0.0;
            } else if i % 4 == 1 {
                // Aimed at a wall's flat box, where only the far distance's
                // widening keeps the box: the same in both kernels.
                let wall = [-1.0, 11.0][i / 4 % 2];
                let mut target = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 12.0 - 1.0;
                target[i / 8 % 3] = wall;
                d = target - o;
            } else if i % 4 == 2 {
                // In a wall's plane: the flat box is met at one point.
                o[i / 8 % 3] = [-1.0, 11.0][i / 4 % 2];
                d[i / 8 % 3] = 0.0;
            }
            let tr = TraversalRay::new(&Ray::new(o, d.normalize()));
            let t_max = if i % 2 == 0 {
                f32::INFINITY
            } else {
                20.0 * rng.uniform()
            };
            for node in &bvh.wide {
                let (mask, entries) = tr.wide_entries(node, t_max);
                // SAFETY: the CPU has AVX2 and FMA (checked above).
                let (mask_avx2, entries_avx2) = unsafe { tr.wide_entries_avx2(node, t_max) };
                assert_eq!(mask, mask_avx2);
                assert_eq!(entries.map(f32::to_bits), entries_avx2.map(f32::to_bits));
                compared += mask.count_ones();
            }
        }
        assert!(compared > 10_000, "too few boxes hit ({compared})");
    }
}
