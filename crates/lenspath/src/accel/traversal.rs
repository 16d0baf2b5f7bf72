//! Walking the wide tree: closest-hit and any-hit traversal (nearest child
//! first, the rest on a stack sorted by entry distance), its leaves' packs
//! tested four or eight triangles at once, and the binary tree's traversal
//! the tests check it against.

use std::mem::{size_of, MaybeUninit};

#[cfg(test)]
use super::build;
use super::layout::{LeafPack, TrianglePack, WideNode, PACK, WIDTH};
#[cfg(target_arch = "x86_64")]
use super::node_test::cpu_has_avx2;
use super::node_test::TraversalRay;
use super::primitive::{Hit, PrimGeometry};
use super::Bvh;
use crate::ray::Ray;
#[cfg(target_arch = "x86_64")]
use crate::shapes::intersect_triangles8;
use crate::shapes::{intersect_sphere, intersect_triangle, intersect_triangles4};

/// A child on the wide traversal's stack: a wide node (`count` 0) or a
/// leaf (its first pack and primitive count), and where the ray enters it.
#[derive(Clone, Copy)]
pub(super) struct Visit {
    pub(super) child: u32,
    pub(super) count: u16,
    pub(super) t_near: f32,
}

impl<T: Copy> Bvh<T> {
    /// The closest hit with `0 < t < t_max`.
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        self.traverse_for_this_cpu::<false>(ray, t_max)
    }

    /// True when anything lies on the ray in `0 < t < t_max` (shadow rays):
    /// stops at the first hit found.
    pub fn intersect_any(&self, ray: &Ray, t_max: f32) -> bool {
        self.traverse_for_this_cpu::<true>(ray, t_max).is_some()
    }

    /// The wide traversal compiled for AVX2 where the CPU has it, else the
    /// portable one (runtime dispatch: the binary stays portable).
    #[inline(always)]
    pub(super) fn traverse_for_this_cpu<const ANY: bool>(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        #[cfg(target_arch = "x86_64")]
        if cpu_has_avx2() {
            // SAFETY: the CPU has the features the function is compiled for.
            return unsafe { self.traverse_wide_avx2::<ANY>(ray, t_max) };
        }
        self.traverse_wide::<ANY, false>(ray, t_max)
    }

    /// The traversal compiled for AVX2, its node test eight lanes wide.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn traverse_wide_avx2<const ANY: bool>(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        self.traverse_wide::<ANY, true>(ray, t_max)
    }

    /// The wide traversal: one slab test for a node's children; the nearest
    /// one the ray enters, node or leaf, is visited next (for any hit, the
    /// first in lane order), the others pushed with their entry distance
    /// (for closest hits sorted, see [`sort_nearest_last`]) so a pop beyond
    /// the closest hit is dropped unvisited. Leaves are visited in that
    /// order too, not a node's leaves before its interior children
    /// (BENCHMARKS.md, issue 34, forty-fifth session).
    #[inline(always)]
    pub(super) fn traverse_wide<const ANY: bool, const AVX2: bool>(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        if self.wide.is_empty() {
            return None;
        }
        let tr = TraversalRay::new(ray);
        let mut t_max = t_max;
        let mut closest: Option<Hit> = None;
        // Left uninitialised: zeroing it costs a coherent ray much of its
        // time. Only entries below `sp` are read, all written.
        let mut stack = [const { MaybeUninit::<Visit>::uninit() }; WIDE_STACK];
        let mut sp = 0usize;
        let mut current = Visit {
            child: 0,
            count: 0,
            t_near: 0.0,
        };
        loop {
            if current.count != 0 {
                if let Some(hit) = self.intersect_leaf::<ANY, AVX2>(&tr, ray, current.child, current.count, t_max) {
                    if ANY {
                        return Some(hit);
                    }
                    t_max = hit.t;
                    closest = Some(hit);
                }
            } else {
                let node = &self.wide[current.child as usize];
                let (mut mask, t_near) = tr.entries::<AVX2>(node, t_max);
                // Everything the ray enters is fetched at once, overlapping the
                // cache misses that otherwise come one after another.
                self.prefetch_children(node, mask);
                // Children, leaves or not, visited nearest first (with
                // `ANY`, the first in lane order).
                let mut next: Option<Visit> = None;
                let pushed = sp;
                while mask != 0 {
                    let lane = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    let entry = Visit {
                        child: node.child[lane],
                        count: node.count[lane],
                        t_near: t_near[lane],
                    };
                    match next {
                        None => next = Some(entry),
                        // Any hit ends the search: the order of the rest
                        // matters less than the compares (as in Embree's
                        // any-hit traversal).
                        Some(_) if ANY => {
                            stack[sp].write(entry);
                            sp += 1;
                        }
                        Some(best) => {
                            let (near, far) = if entry.t_near < best.t_near {
                                (entry, best)
                            } else {
                                (best, entry)
                            };
                            stack[sp].write(far);
                            sp += 1;
                            next = Some(near);
                        }
                    }
                }
                if !ANY {
                    // SAFETY: the entries from `pushed` to `sp` were written just now.
                    let siblings = unsafe {
                        std::slice::from_raw_parts_mut(stack[pushed..sp].as_mut_ptr().cast::<Visit>(), sp - pushed)
                    };
                    sort_nearest_last(siblings);
                }
                if let Some(next) = next {
                    current = next;
                    continue;
                }
            }
            loop {
                if sp == 0 {
                    return closest;
                }
                sp -= 1;
                // SAFETY: every entry below the stack pointer was written by a push.
                let entry = unsafe { stack[sp].assume_init() };
                if entry.t_near <= t_max {
                    current = entry;
                    break;
                }
            }
        }
    }

    /// Asks for the children of `node` in `lanes` (nodes, or a leaf's
    /// packs) to be brought into the cache.
    #[inline(always)]
    pub(super) fn prefetch_children(&self, node: &WideNode, lanes: u32) {
        let mut fetch = lanes;
        while fetch != 0 {
            let lane = fetch.trailing_zeros() as usize;
            fetch &= fetch - 1;
            let child = node.child[lane] as usize;
            if node.leaves & (1 << lane) != 0 {
                let packs = (node.count[lane] as usize).div_ceil(PACK);
                // The corners only: the tags are read for the closest hit alone.
                prefetch(
                    self.packs.as_ptr().wrapping_add(child),
                    (packs - 1) * size_of::<LeafPack<T>>() + size_of::<TrianglePack>(),
                );
            } else {
                prefetch(self.wide.as_ptr().wrapping_add(child), size_of::<WideNode>());
            }
        }
    }

    /// The binary tree's traversal (pbrt-v4's): the reference the wide
    /// one is checked against.
    #[cfg(test)]
    pub(super) fn traverse<const ANY: bool>(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        if self.nodes.is_empty() {
            return None;
        }
        let tr = TraversalRay::new(ray);
        let mut closest: Option<Hit> = None;
        let mut t_max = t_max;
        let mut stack = [0u32; 64];
        let mut sp = 0usize;
        let mut current = 0usize;
        loop {
            let node = &self.nodes[current];
            if tr.hits_box(node, t_max) {
                if node.is_leaf() {
                    for prim in build::primitives(&self.nodes, current) {
                        let slot = self.slot_of[prim as usize];
                        if let Some(hit) = intersect_prim(&tr, ray, self.primitive(slot), slot, t_max) {
                            if ANY {
                                return Some(hit);
                            }
                            t_max = hit.t;
                            closest = Some(hit);
                        }
                    }
                } else {
                    // Left child first, the right one later.
                    stack[sp] = build::right_child(&self.nodes, current) as u32;
                    sp += 1;
                    current += 1;
                    continue;
                }
            }
            if sp == 0 {
                return closest;
            }
            sp -= 1;
            current = stack[sp] as usize;
        }
    }

    /// The closest hit before `t_max` (with `ANY`, the first found) in the
    /// leaf of `count` primitives whose packs start at `first_pack`. With
    /// `AVX2`, a leaf of two packs has its eight triangles tested in one step.
    #[inline(always)]
    pub(super) fn intersect_leaf<const ANY: bool, const AVX2: bool>(
        &self,
        tr: &TraversalRay,
        ray: &Ray,
        first_pack: u32,
        count: u16,
        t_max: f32,
    ) -> Option<Hit> {
        let first = first_pack as usize;
        let packs = &self.packs[first..first + (count as usize).div_ceil(PACK)];
        let first_slot = first_pack * PACK as u32;
        // Bit `k` for the leaf's primitive in slot `first_slot + k`.
        let used = (1u32 << count) - 1;
        #[cfg(target_arch = "x86_64")]
        if AVX2 {
            if let [low, high] = packs {
                let (low, high) = (&low.geometry, &high.geometry);
                // SAFETY: `AVX2` is only set by `traverse_wide_avx2` and
                // `occluded_packet_avx2`, which run on CPUs with the features.
                return unsafe { self.intersect_pack_pair::<ANY>(tr, ray, low, high, first_slot, used, t_max) };
            }
        }
        let (mut t_max, mut closest) = (t_max, None);
        for (j, pack) in packs.iter().enumerate() {
            let slot = first_slot + (j * PACK) as u32;
            let lanes = (used >> (j * PACK)) & 0xf;
            if let Some(hit) = self.intersect_pack::<ANY>(tr, ray, &pack.geometry, slot, lanes, t_max) {
                if ANY {
                    return Some(hit);
                }
                t_max = hit.t;
                closest = Some(hit);
            }
        }
        closest
    }

    /// The closest hit in `pack`'s `lanes` (bit `k` for lane `k`; its slots
    /// from `first_slot` on) before `t_max` (with `ANY`, the first found):
    /// its triangles in one SIMD test, then see [`Self::resolve`].
    #[inline(always)]
    fn intersect_pack<const ANY: bool>(
        &self,
        tr: &TraversalRay,
        ray: &Ray,
        pack: &TrianglePack,
        first_slot: u32,
        lanes: u32,
        t_max: f32,
    ) -> Option<Hit> {
        let spheres = pack.spheres() & lanes;
        let triangles = lanes & !spheres;
        if triangles == 0 {
            return self.resolve::<ANY, PACK>(tr, ray, first_slot, 0, spheres, [[0.0; PACK]; 3], t_max);
        }
        let found = intersect_triangles4(&tr.tri, &pack.corners, t_max);
        self.resolve::<ANY, PACK>(
            tr,
            ray,
            first_slot,
            found.hit & triangles,
            spheres | (found.redo & triangles),
            [found.t.to_array(), found.b1.to_array(), found.b2.to_array()],
            t_max,
        )
    }

    /// [`Self::intersect_pack`] for a leaf's two packs at once, `low`'s
    /// lanes first: the closest hit of their primitives, ties going to the
    /// lowest lane as when the packs are tested one after the other.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    #[inline]
    #[allow(clippy::too_many_arguments)]
    fn intersect_pack_pair<const ANY: bool>(
        &self,
        tr: &TraversalRay,
        ray: &Ray,
        low: &TrianglePack,
        high: &TrianglePack,
        first_slot: u32,
        lanes: u32,
        t_max: f32,
    ) -> Option<Hit> {
        let spheres = (low.spheres() | high.spheres() << PACK) & lanes;
        let triangles = lanes & !spheres;
        // SAFETY: the CPU has AVX (this function's features).
        let found = unsafe { intersect_triangles8(&tr.tri, &low.corners, &high.corners, t_max) };
        self.resolve::<ANY, { 2 * PACK }>(
            tr,
            ray,
            first_slot,
            found.hit & triangles,
            spheres | (found.redo & triangles),
            [found.t, found.b1, found.b2],
            t_max,
        )
    }

    /// The closest of `N` lanes from slot `first_slot` on: the SIMD test's
    /// `hits` with their distances and barycentrics, then the `scalar`
    /// lanes (spheres, and triangles the SIMD test handed back) one by one.
    /// Ties go to the lowest lane, as a scalar loop over the same
    /// primitives would have it.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn resolve<const ANY: bool, const N: usize>(
        &self,
        tr: &TraversalRay,
        ray: &Ray,
        first_slot: u32,
        mut hits: u32,
        mut scalar: u32,
        [t, b1, b2]: [[f32; N]; 3],
        t_max: f32,
    ) -> Option<Hit> {
        let mut closest: Option<Hit> = None;
        let (t_limit, mut t_max) = (t_max, t_max);
        while hits != 0 {
            let lane = hits.trailing_zeros() as usize;
            hits &= hits - 1;
            if t[lane] < t_max {
                t_max = t[lane];
                closest = Some(Hit {
                    t: t_max,
                    prim: first_slot + lane as u32,
                    b1: b1[lane],
                    b2: b2[lane],
                });
                if ANY {
                    return closest;
                }
            }
        }
        while scalar != 0 {
            let lane = scalar.trailing_zeros();
            scalar &= scalar - 1;
            let prim = first_slot + lane;
            // Tested against the lanes' own range, so a lane before the best
            // hit so far wins a tie, as in a scalar loop over the lanes.
            if let Some(hit) = intersect_prim(tr, ray, self.primitive(prim), prim, t_limit) {
                if closest.is_none_or(|c| hit.t < c.t || (hit.t == c.t && hit.prim < c.prim)) {
                    closest = Some(hit);
                    if ANY {
                        return closest;
                    }
                }
            }
        }
        closest
    }
}

/// Sorts a node's pushed children so the nearest is popped first: a closest-hit
/// ray then drops more of them unvisited once it has a hit (Embree sorts them
/// too). Insertion sort: there are at most `WIDTH - 1`. Any-hit rays, whose
/// `t_max` never shrinks, gain nothing and skip it.
#[inline(always)]
fn sort_nearest_last(siblings: &mut [Visit]) {
    for i in 1..siblings.len() {
        let entry = siblings[i];
        let mut j = i;
        while j > 0 && siblings[j - 1].t_near < entry.t_near {
            siblings[j] = siblings[j - 1];
            j -= 1;
        }
        siblings[j] = entry;
    }
}

/// The hit of `ray` with `geometry` (primitive `prim`) before `t_max`.
#[inline(always)]
fn intersect_prim(tr: &TraversalRay, ray: &Ray, geometry: PrimGeometry, prim: u32, t_max: f32) -> Option<Hit> {
    match geometry {
        PrimGeometry::Triangle(p) => intersect_triangle(&tr.tri, &p, t_max).map(|(t, b1, b2)| Hit { t, prim, b1, b2 }),
        PrimGeometry::Sphere { center, radius } => intersect_sphere(ray, center, radius, t_max).map(|t| Hit {
            t,
            prim,
            b1: 0.0,
            b2: 0.0,
        }),
    }
}

/// Asks for the `bytes` from `start` to be brought into the cache (a hint:
/// no fault for any address, nothing on other targets).
#[inline(always)]
pub(super) fn prefetch<T>(start: *const T, bytes: usize) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let start = start.cast::<i8>();
        for offset in (0..bytes).step_by(PREFETCH_STRIDE) {
            // SAFETY: a prefetch never faults, whatever the address.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(start.wrapping_add(offset)) };
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (start, bytes);
}

/// Bytes between the prefetched addresses: one a cache line (every other
/// line gained less: BENCHMARKS.md, issue 34).
const PREFETCH_STRIDE: usize = 64;

/// Deepest the wide traversal's stack can get: it pushes at most
/// `WIDTH - 1` children a level, and the wide tree is no deeper than the binary one
/// (at most 32 SAH levels plus halving, see `BvhSettings::max_sah_depth`).
pub(super) const WIDE_STACK: usize = (WIDTH - 1) * 64;
