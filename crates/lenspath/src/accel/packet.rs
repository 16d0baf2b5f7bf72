//! Shadow rays in packets: the rays from one point toward a light, traced
//! through the wide tree together.
//!
//! With several light samples a vertex (the CS184 course's renderer takes 16)
//! most of a render is shadow rays that cross a few nodes each (four on
//! average in the course's dragon scene): their cost is the traversal's
//! per-node bookkeeping, branches and stack, not the box tests. Rays from one
//! point toward one light cross nearly the same nodes, so the packet walks
//! the tree once (masked packet traversal, Wald, Slusallek, Benthin and
//! Wagner, "Interactive Rendering with Coherent Ray Tracing", 2001, on a
//! wide tree as in Embree's `occluded16`): at each node every ray that
//! reached it does its own slab test (one AVX2 step for the eight children),
//! each child is entered once, with the rays that hit its box, and at a leaf
//! those rays test its triangles. A ray is tested at exactly the nodes and
//! leaves its single-ray traversal visits, so every answer is
//! [`Bvh::intersect_any`]'s, bit for bit; what is shared is the walk.
//!
//! Per-ray tests, not a frustum (Reshetov et al. 2005: six planes culling
//! boxes for the whole packet): shadow rays from one point to a light
//! spread so that a packet's frustum enters many more nodes than each ray
//! does (BENCHMARKS.md, "Shadow rays in packets").

use std::mem::MaybeUninit;

use glam::Vec3;

use super::layout::{WideNode, WIDTH};
#[cfg(target_arch = "x86_64")]
use super::node_test::cpu_has_avx2;
use super::node_test::TraversalRay;
use super::traversal::WIDE_STACK;
use super::Bvh;
use crate::ray::Ray;

/// Rays a packet holds at most.
pub const SHADOW_PACKET: usize = 16;

impl<T: Copy> Bvh<T> {
    /// Which of the rays from `origin` to each of `targets` (at most
    /// [`SHADOW_PACKET`]) are blocked in `0 < t < t_max`, `t` in units of
    /// `target − origin`: bit `i` for `targets[i]`. The answers are
    /// [`Bvh::intersect_any`]'s for `Ray::new(origin, target − origin)`.
    pub fn occluded_from(&self, origin: Vec3, targets: &[Vec3], t_max: f32) -> u32 {
        assert!(
            targets.len() <= SHADOW_PACKET,
            "a shadow packet holds at most {SHADOW_PACKET} rays"
        );
        if targets.is_empty() || self.wide.is_empty() {
            return 0;
        }
        let rays: [Ray; SHADOW_PACKET] =
            std::array::from_fn(|i| Ray::new(origin, targets[i.min(targets.len() - 1)] - origin));
        let rays = &rays[..targets.len()];
        #[cfg(target_arch = "x86_64")]
        if cpu_has_avx2() {
            // SAFETY: the CPU has the features the function is compiled for.
            return unsafe { self.occluded_packet_avx2(rays, t_max) };
        }
        self.occluded_packet::<false>(rays, t_max)
    }

    /// The packet traversal compiled for AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn occluded_packet_avx2(&self, rays: &[Ray], t_max: f32) -> u32 {
        self.occluded_packet::<true>(rays, t_max)
    }

    /// The packet's walk: at each node the rays that reached it do their
    /// own slab tests, and each child is entered once, by the rays that hit
    /// its box; a ray leaves the packet at its first hit, the walk ends when
    /// none is left.
    #[inline(always)]
    fn occluded_packet<const AVX2: bool>(&self, rays: &[Ray], t_max: f32) -> u32 {
        let traversal: [TraversalRay; SHADOW_PACKET] =
            std::array::from_fn(|i| TraversalRay::new(&rays[i.min(rays.len() - 1)]));
        let all: u32 = (1 << rays.len()) - 1;
        let mut unresolved = all;
        // Nodes to visit, each with the rays that entered it.
        let mut stack = [const { MaybeUninit::<(u32, u32)>::uninit() }; WIDE_STACK];
        let mut sp = 0usize;
        let (mut current, mut arrived) = (0usize, all);
        loop {
            let node = &self.wide[current];
            let (by_child, entered) = rays_by_child::<AVX2>(&traversal, arrived & unresolved, node, t_max);
            self.prefetch_children(node, entered);
            // Leaves: each ray that entered one tests its triangles.
            let mut leaves = entered & u32::from(node.leaves);
            while leaves != 0 {
                let lane = leaves.trailing_zeros() as usize;
                leaves &= leaves - 1;
                let mut testing = by_child[lane] & unresolved;
                while testing != 0 {
                    let i = testing.trailing_zeros() as usize;
                    testing &= testing - 1;
                    if self
                        .intersect_leaf::<true, AVX2>(
                            &traversal[i],
                            &rays[i],
                            node.child[lane],
                            node.count[lane],
                            t_max,
                        )
                        .is_some()
                    {
                        unresolved &= !(1 << i);
                    }
                }
            }
            if unresolved == 0 {
                break;
            }
            // Interior children: the first visited next, the others pushed.
            let mut interior = entered & !u32::from(node.leaves);
            if interior != 0 {
                let lane = interior.trailing_zeros() as usize;
                interior &= interior - 1;
                (current, arrived) = (node.child[lane] as usize, by_child[lane]);
                while interior != 0 {
                    let lane = interior.trailing_zeros() as usize;
                    interior &= interior - 1;
                    stack[sp].write((node.child[lane], by_child[lane]));
                    sp += 1;
                }
                continue;
            }
            if sp == 0 {
                break;
            }
            sp -= 1;
            // SAFETY: every entry below the stack pointer was written by a push.
            let (node, rays) = unsafe { stack[sp].assume_init() };
            (current, arrived) = (node as usize, rays);
        }
        all & !unresolved
    }
}

/// For each of `node`'s children, the rays among `rays` (bits into
/// `traversal`) whose slab test enters its box before `t_max`; and the
/// children any of them enters.
#[inline(always)]
fn rays_by_child<const AVX2: bool>(
    traversal: &[TraversalRay; SHADOW_PACKET],
    rays: u32,
    node: &WideNode,
    t_max: f32,
) -> ([u32; WIDTH], u32) {
    #[cfg(target_arch = "x86_64")]
    if AVX2 {
        // SAFETY: `AVX2` is only set by `occluded_packet_avx2`, which runs
        // on CPUs with the features.
        return unsafe { rays_by_child_avx2(traversal, rays, node, t_max) };
    }
    let mut by_child = [0u32; WIDTH];
    let mut entered = 0;
    let mut pending = rays;
    while pending != 0 {
        let i = pending.trailing_zeros();
        pending &= pending - 1;
        let mut mask = traversal[i as usize].entries::<false>(node, t_max).0;
        entered |= mask;
        while mask != 0 {
            by_child[mask.trailing_zeros() as usize] |= 1 << i;
            mask &= mask - 1;
        }
    }
    (by_child, entered)
}

/// [`rays_by_child`] with AVX2: each ray's slab test leaves all ones in the
/// lanes it enters, which keep its bit; no branch a lane.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn rays_by_child_avx2(
    traversal: &[TraversalRay; SHADOW_PACKET],
    rays: u32,
    node: &WideNode,
    t_max: f32,
) -> ([u32; WIDTH], u32) {
    use std::arch::x86_64::*;
    let mut by_child = _mm256_setzero_si256();
    let mut pending = rays;
    while pending != 0 {
        let i = pending.trailing_zeros();
        pending &= pending - 1;
        let (inside, _) = traversal[i as usize].wide_slabs_avx2(node, t_max);
        by_child = _mm256_or_si256(
            by_child,
            _mm256_and_si256(_mm256_castps_si256(inside), _mm256_set1_epi32(1 << i)),
        );
    }
    let mut lanes = [0u32; WIDTH];
    // SAFETY: `lanes` holds eight 32-bit integers.
    unsafe { _mm256_storeu_si256(lanes.as_mut_ptr().cast(), by_child) };
    let none = _mm256_cmpeq_epi32(by_child, _mm256_setzero_si256());
    let entered = !(_mm256_movemask_ps(_mm256_castsi256_ps(none)) as u32) & u32::from(node.lanes);
    (lanes, entered)
}

#[cfg(test)]
mod tests {
    use super::super::tests::{random_triangles, room_walls};
    use super::*;
    use crate::accel::{BvhSettings, PrimGeometry};
    use crate::sampling::Rng;

    /// Packets from random points toward random small lights (and toward a
    /// point: sixteen copies of one ray) give each ray the answer
    /// `intersect_any` gives it alone, with the dispatched and the portable
    /// kernels, for every packet size; both answers occur often.
    #[test]
    fn packets_answer_as_their_rays_do_alone() {
        let mut rng = Rng::new(5);
        let mut prims = random_triangles(3000, &mut rng);
        prims.push((
            PrimGeometry::Sphere {
                center: Vec3::splat(5.0),
                radius: 1.0,
            },
            9_000,
        ));
        prims.extend(room_walls(20_000));
        let bvh = Bvh::build(prims, &BvhSettings::default());
        let t_max = 1.0 - 1e-4;
        let (mut blocked, mut clear) = (0, 0);
        for packet in 0..3000 {
            let origin = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 12.0 - 1.0;
            let corner = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 12.0 - 1.0;
            let size = [0.0, 0.3, 3.0][packet % 3];
            let (edge_u, edge_v) = (Vec3::new(size, 0.0, 0.0), Vec3::new(0.0, size, 0.0));
            let count = 1 + packet % SHADOW_PACKET;
            let targets: Vec<Vec3> = (0..count)
                .map(|_| corner + rng.uniform() * edge_u + rng.uniform() * edge_v)
                .collect();
            let got = bvh.occluded_from(origin, &targets, t_max);
            let portable = bvh.occluded_packet::<false>(
                &targets
                    .iter()
                    .map(|&t| Ray::new(origin, t - origin))
                    .collect::<Vec<_>>(),
                t_max,
            );
            assert_eq!(portable, got, "the portable kernel differs for packet {packet}");
            for (i, &target) in targets.iter().enumerate() {
                let alone = bvh.intersect_any(&Ray::new(origin, target - origin), t_max);
                assert_eq!(got >> i & 1 == 1, alone, "ray {i} of packet {packet} differs");
                if alone {
                    blocked += 1;
                } else {
                    clear += 1;
                }
            }
            assert_eq!(got >> count, 0, "bits beyond the packet's rays are set");
        }
        assert!(blocked > 3000 && clear > 3000, "blocked {blocked}, clear {clear}");
    }
}
