//! The bounding volume hierarchy: a binned SAH binary tree (built in
//! parallel, in `accel/build.rs`) collapsed to 8 children a node with leaves of up
//! to 8 primitives in packs of four triangles, and closest-hit / any-hit
//! traversal of the wide tree (one SIMD slab test for eight boxes, AVX2
//! where the CPU has it, one SIMD watertight test for four triangles),
//! checked against the binary tree's.

use std::mem::{offset_of, MaybeUninit};
use std::time::Instant;

use glam::{Vec3, Vec3A, Vec4};
use rayon::prelude::*;

use crate::math::Bounds3;
use crate::ray::Ray;
#[cfg(target_arch = "x86_64")]
use crate::shapes::intersect_triangles8;
use crate::shapes::{intersect_sphere, intersect_triangle, intersect_triangles4, triangle_bounds, TriangleRay};

mod build;
mod packet;
pub use packet::SHADOW_PACKET;

/// Everything that tunes the BVH, in one place (as tinybvh's settings).
#[derive(Clone, Copy, Debug)]
pub struct BvhSettings {
    /// SAH bins per axis (2..=256).
    pub bins: usize,
    /// Relative cost of visiting one interior node.
    pub traversal_cost: f32,
    /// Relative cost of one primitive intersection test (pbrt's 1:8 by default).
    pub intersection_cost: f32,
    /// Leaves never hold more primitives than this, whatever the SAH says.
    pub max_leaf_size: usize,
    /// Below this depth splits follow the SAH; deeper, ranges are halved, so a
    /// tree is at most `max_sah_depth + log2(n)` deep. Clamped to 32, which
    /// keeps every tree within the 64-entry traversal stack whatever the input.
    pub max_sah_depth: usize,
    /// Nodes with fewer primitives than this bin only along their longest
    /// centroid axis (a third of the work where the tree has most nodes);
    /// larger nodes try all three axes.
    pub all_axes_min_primitives: usize,
}

impl Default for BvhSettings {
    fn default() -> Self {
        BvhSettings {
            // 8 bins: SAH cost within 0.5% of 16 bins on the 1 M mesh, build 8% faster.
            bins: 8,
            traversal_cost: 1.0,
            intersection_cost: 8.0,
            max_leaf_size: 8,
            max_sah_depth: 32,
            // Measured on the 1 M mesh: build 9% faster, SAH cost 0.5% higher than all axes everywhere.
            all_axes_min_primitives: 32,
        }
    }
}

/// What the build produced and how long it took.
#[derive(Clone, Copy, Debug, Default)]
pub struct BuildStats {
    /// Primitives in the tree.
    pub primitives: usize,
    /// All nodes, interior and leaf.
    pub nodes: usize,
    /// Leaf nodes.
    pub leaves: usize,
    /// Deepest leaf (the root is depth 0).
    pub max_depth: usize,
    /// SAH cost of the whole tree with the settings' costs, relative to the root's area.
    pub sah_cost: f32,
    /// Wall time of the build, in milliseconds.
    pub build_ms: f64,
    /// Bytes the tree holds for traversal and shading: its wide nodes, leaf
    /// packs (which hold the primitives' geometry) and the packs' lanes' tags
    /// (the binary tree the build makes is dropped).
    pub memory_bytes: usize,
}

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
    fn bounds(&self) -> Bounds3 {
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

/// A node of the wide tree: its children's boxes side by side (one SIMD
/// lane each, as Embree and tinybvh lay them out), so one slab test meets all
/// eight; 256 bytes, on four cache lines. A child is a leaf when its `count`
/// (of primitives) is non-zero: `child` is then its first pack in
/// `Bvh::packs`, and the leaf fills `count.div_ceil(4)` packs. Otherwise
/// `child` indexes `Bvh::wide`. Lanes beyond `lanes` are unused.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct WideNode {
    min: [[Vec4; QUADS]; 3],
    max: [[Vec4; QUADS]; 3],
    child: [u32; WIDTH],
    count: [u16; WIDTH],
    /// Bit `k` set for the lanes in use.
    lanes: u16,
    /// Bit `k` set for the lanes that are leaves.
    leaves: u16,
}

/// Up to four consecutive primitives of a wide leaf, triangles' corners side
/// by side (`corners[k][axis]`, one lane each, as Embree's `Triangle4`), so
/// one SIMD watertight test meets all four: 144 bytes. Lane `k` of pack `p`
/// is the primitive in slot `4p + k`; how many lanes are in use is the
/// leaf's count in its wide node. A sphere's lane holds its centre in
/// `corners[0]`, its radius in `corners[1][0]` and a NaN in `corners[2][0]`
/// (no triangle corner is NaN: scenes are checked for finite positions);
/// spheres (rare) are tested one by one. The packs are the tree's only copy
/// of the geometry.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
struct TrianglePack {
    corners: [[Vec4; 3]; 3],
}

// What the memory figures in BENCHMARKS.md assume: no header, no padding.
const _: () = assert!(size_of::<TrianglePack>() == 144);

/// A pack with its lanes' tags right after its corners (an unused lane
/// repeats lane 0's tag). A closest hit's tag is read as soon as the
/// traversal returns, and here it mostly shares a cache line with the
/// corners just tested; in an array of its own it was a cache miss for
/// nearly every hit. Measured against that array (interleaved renders, 2
/// threads, images identical): 0.97-0.98x the time on the Cornell dragon
/// and spheres; `bench bvh` unchanged within its noise, since the
/// traversal prefetches only the corners.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
struct LeafPack<T> {
    geometry: TrianglePack,
    tags: [T; PACK],
}

// No padding between or after the tags (for the scene's 8-byte tags and
// 4-byte ones): memory per triangle as with the tags apart.
const _: () = assert!(size_of::<LeafPack<[u32; 2]>>() == 144 + 32);
const _: () = assert!(size_of::<LeafPack<u32>>() == 144 + 16);

/// Children of a wide node: Embree's BVH8 on AVX2 machines. Measured
/// against 4 (interleaved rounds, one thread, 300 k rays, median of the
/// rounds' ratios): incoherent closest hits +17% on the dragon, +26% on the
/// 1 M knot, +1 to +20% on Lucy; coherent ones −6 to +22%. A 256-byte node
/// is fetched in parallel lines; what the tree loses is levels, each a
/// dependent memory access.
const WIDTH: usize = 8;

/// The SIMD quads a wide node's boxes fill.
const QUADS: usize = WIDTH / 4;

/// Primitives in one [`TrianglePack`].
const PACK: usize = 4;

/// A BVH over triangles and spheres, with `T` the caller's per-primitive tag
/// (for the scene: which shape a primitive came from).
#[derive(Clone, Debug)]
pub struct Bvh<T> {
    /// The binary tree the build makes, kept in tests as the reference
    /// traversal's.
    #[cfg(test)]
    nodes: Vec<build::Node>,
    /// Bounds of everything in the tree.
    bounds: Bounds3,
    /// The same tree collapsed to [`WIDTH`] children a node: what rays traverse.
    wide: Vec<WideNode>,
    /// The wide tree's leaves, four primitives a pack (see [`TrianglePack`]),
    /// with their tags.
    packs: Vec<LeafPack<T>>,
    /// The slot of each primitive in the binary tree's order, for the
    /// reference traversal.
    #[cfg(test)]
    slot_of: Vec<u32>,
    stats: BuildStats,
}

/// 1 + 2γ₃ (pbrt-v4): widens the far slab distance so rounding never
/// culls a box the ray touches, e.g. the flat box of an axis-aligned quad.
const SLAB_SAFETY: f32 = 1.0 + 2.0 * 3.0 * f32::EPSILON * 0.5 / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// A child on the wide traversal's stack: a wide node (`count` 0) or a
/// leaf (its first pack and primitive count), and where the ray enters it.
#[derive(Clone, Copy)]
struct Visit {
    child: u32,
    count: u16,
    t_near: f32,
}

/// Per-ray traversal constants.
struct TraversalRay {
    origin: Vec3A,
    inv_dir: Vec3A,
    /// Per axis, where in a [`WideNode`] the planes the ray enters by lie
    /// (bytes from its start: the boxes' `min` where the direction is
    /// positive, else `max`), and the ones it leaves by.
    near_far_offsets: [(usize, usize); 3],
    tri: TriangleRay,
}

impl TraversalRay {
    fn new(ray: &Ray) -> Self {
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
    fn wide_entries(&self, node: &WideNode, t_max: f32) -> (u32, [f32; WIDTH]) {
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
    fn entries<const AVX2: bool>(&self, node: &WideNode, t_max: f32) -> (u32, [f32; WIDTH]) {
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
    fn wide_entries_avx2(&self, node: &WideNode, t_max: f32) -> (u32, [f32; WIDTH]) {
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
    fn wide_slabs_avx2(&self, node: &WideNode, t_max: f32) -> (std::arch::x86_64::__m256, std::arch::x86_64::__m256) {
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
            // as `inv` has the direction's sign. Measured against the min
            // and max (`bench/ab_bvh.py`, 9 rounds, twice): incoherent rays
            // +1 to +4%, coherent ones -1 to +4%; renders unchanged.
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
    fn hits_box(&self, node: &build::Node, t_max: f32) -> bool {
        let t0 = (Vec3A::from_array(node.min) - self.origin) * self.inv_dir;
        let t1 = (Vec3A::from_array(node.max) - self.origin) * self.inv_dir;
        let t_near = t0.min(t1).max_element().max(0.0);
        let t_far = t0.max(t1).min_element() * SLAB_SAFETY;
        t_near <= t_far.min(t_max)
    }
}

impl<T: Copy + Send + Sync> Bvh<T> {
    /// Builds the hierarchy over `prims` (geometry with its tag), in the
    /// current rayon pool. The tree is the same for any number of threads.
    pub fn build(prims: Vec<(PrimGeometry, T)>, settings: &BvhSettings) -> Bvh<T> {
        let started = Instant::now();
        // Leaf sizes are stored in 16 bits; the SAH never wants huge leaves anyway.
        let settings = &BvhSettings {
            max_leaf_size: settings.max_leaf_size.clamp(1, 255),
            max_sah_depth: settings.max_sah_depth.min(32),
            ..*settings
        };
        let n = prims.len();
        let bounds: Vec<Bounds3> = prims.par_iter().map(|(g, _)| g.bounds()).collect();
        let tree = build::binary_tree(bounds, settings);
        // The geometry and the tags go into the wide leaves' packs.
        let build::WideTree {
            wide,
            packs,
            pack_ranges,
        } = build::collapse(&tree.nodes, &prims, &tree.order);
        #[cfg(test)]
        let slot_of = build::slots_in_binary_order(&pack_ranges, n);
        drop(pack_ranges);
        let memory_bytes = size_of_val(wide.as_slice()) + size_of_val(packs.as_slice());
        let stats = BuildStats {
            primitives: n,
            nodes: tree.stats.nodes,
            leaves: tree.stats.leaves,
            max_depth: tree.stats.max_depth,
            sah_cost: tree.stats.sah_cost,
            build_ms: started.elapsed().as_secs_f64() * 1e3,
            memory_bytes,
        };
        Bvh {
            bounds: tree.nodes.first().map_or(Bounds3::EMPTY, build::Node::bounds),
            #[cfg(test)]
            nodes: tree.nodes,
            wide,
            #[cfg(test)]
            slot_of,
            packs,
            stats,
        }
    }
}

impl<T: Copy> Bvh<T> {
    /// Build statistics.
    pub fn stats(&self) -> &BuildStats {
        &self.stats
    }

    /// Bounds of everything in the tree (empty for an empty tree).
    pub fn bounds(&self) -> Bounds3 {
        self.bounds
    }

    /// The caller's tag of the primitive in slot `prim` (a [`Hit`]'s).
    #[inline]
    pub fn tag(&self, prim: u32) -> T {
        let slot = prim as usize;
        self.packs[slot / PACK].tags[slot % PACK]
    }

    /// The geometry of the primitive in slot `prim` (a [`Hit`]'s).
    #[inline]
    pub fn primitive(&self, prim: u32) -> PrimGeometry {
        let slot = prim as usize;
        self.packs[slot / PACK].geometry.lane(slot % PACK)
    }

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
    fn traverse_for_this_cpu<const ANY: bool>(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
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
    fn traverse_wide_avx2<const ANY: bool>(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        self.traverse_wide::<ANY, true>(ray, t_max)
    }

    /// The wide traversal: one slab test for a node's children; the nearest
    /// one the ray enters, node or leaf, is visited next (for any hit, the
    /// first in lane order), the others pushed with their entry distance
    /// (for closest hits sorted, see [`sort_nearest_last`]) so a pop beyond
    /// the closest hit is dropped unvisited. Visiting leaves in that order
    /// too, rather than a node's leaves before its interior children,
    /// measured +2 to +4% on incoherent and coherent closest hits
    /// (interleaved rounds, one thread, 15 rounds, medians over the dragon,
    /// Lucy and the 1 M knot), any-hit unchanged.
    #[inline(always)]
    fn traverse_wide<const ANY: bool, const AVX2: bool>(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        if self.wide.is_empty() {
            return None;
        }
        let tr = TraversalRay::new(ray);
        let mut t_max = t_max;
        let mut closest: Option<Hit> = None;
        // Left uninitialised: zeroing it (1.5 KB then, 5 KB now) cost a
        // coherent ray about a sixth of its time. Only entries below `sp`
        // are read, all written.
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
                        // any-hit traversal). Measured against nearest
                        // first, 2 × 15 rounds: incoherent any-hit +1 to
                        // +5%, coherent −3 to 0%.
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
    fn prefetch_children(&self, node: &WideNode, lanes: u32) {
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
    fn traverse<const ANY: bool>(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
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
    fn intersect_leaf<const ANY: bool, const AVX2: bool>(
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
/// too). Insertion sort: there are at most `WIDTH - 1`. Measured against
/// leaving them in lane order (interleaved rounds, one thread, 15 rounds,
/// medians): incoherent closest hits +3% on the dragon and Lucy, +6% on the
/// 1 M knot, coherent ones unchanged; any-hit rays, whose `t_max` never
/// shrinks, gain nothing and skip it.
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

impl TrianglePack {
    /// Bit `k` set where lane `k` holds a sphere (see [`TrianglePack`]).
    #[inline(always)]
    fn spheres(&self) -> u32 {
        self.corners[2][0].is_nan_mask().bitmask()
    }

    /// The geometry in `lane`.
    #[inline]
    fn lane(&self, lane: usize) -> PrimGeometry {
        let corner = |k: usize| {
            Vec3::new(
                self.corners[k][0][lane],
                self.corners[k][1][lane],
                self.corners[k][2][lane],
            )
        };
        if self.spheres() & (1 << lane) != 0 {
            PrimGeometry::Sphere {
                center: corner(0),
                radius: self.corners[1][0][lane],
            }
        } else {
            PrimGeometry::Triangle([corner(0), corner(1), corner(2)])
        }
    }
}

/// Whether this CPU runs the AVX2 traversal (it needs AVX2 and FMA).
#[cfg(target_arch = "x86_64")]
fn cpu_has_avx2() -> bool {
    std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma")
}

/// Asks for the `bytes` from `start` to be brought into the cache (a hint:
/// no fault for any address, nothing on other targets).
#[inline(always)]
fn prefetch<T>(start: *const T, bytes: usize) {
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

/// Bytes between the prefetched addresses: one a cache line. Prefetching
/// the children a ray enters, measured against none (interleaved rounds, one
/// thread, median of the rounds' ratios): incoherent closest hits +15% on
/// the 1 M knot, +12% on the dragon, +7% on Lucy, any-hit +4 to +17%;
/// coherent rays, whose nodes are mostly cached already, −4% to +4%; the
/// course's dragon render unchanged. Every other line (128) gained less.
const PREFETCH_STRIDE: usize = 64;

/// Deepest the wide traversal's stack can get: it pushes at most
/// `WIDTH - 1` children a level, and the wide tree is no deeper than the binary one
/// (at most 32 SAH levels plus halving, see `BvhSettings::max_sah_depth`).
const WIDE_STACK: usize = (WIDTH - 1) * 64;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    pub(super) fn random_triangles(n: usize, rng: &mut Rng) -> Vec<(PrimGeometry, u32)> {
        (0..n)
            .map(|i| {
                let c = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 10.0;
                let mut corner = || c + (Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) - 0.5) * 0.6;
                (PrimGeometry::Triangle([corner(), corner(), corner()]), i as u32)
            })
            .collect()
    }

    /// The floor, ceiling and three walls of a room around the random
    /// triangles' 10-unit cube: two triangles each, tagged from `first_tag`.
    pub(super) fn room_walls(first_tag: u32) -> Vec<(PrimGeometry, u32)> {
        let (lo, hi) = (-1.0, 11.0);
        let quads = [
            [(lo, lo, lo), (hi, lo, lo), (hi, lo, hi), (lo, lo, hi)],
            [(lo, hi, lo), (lo, hi, hi), (hi, hi, hi), (hi, hi, lo)],
            [(lo, lo, lo), (lo, hi, lo), (hi, hi, lo), (hi, lo, lo)],
            [(lo, lo, lo), (lo, lo, hi), (lo, hi, hi), (lo, hi, lo)],
            [(hi, lo, lo), (hi, hi, lo), (hi, hi, hi), (hi, lo, hi)],
        ];
        quads
            .iter()
            .flat_map(|q| {
                let [a, b, c, d] = q.map(|(x, y, z)| Vec3::new(x, y, z));
                [[a, b, c], [a, c, d]]
            })
            .enumerate()
            .map(|(i, t)| (PrimGeometry::Triangle(t), first_tag + i as u32))
            .collect()
    }

    fn brute_force(prims: &[(PrimGeometry, u32)], ray: &Ray) -> Option<(f32, u32)> {
        let tr = TriangleRay::new(ray);
        let mut best: Option<(f32, u32)> = None;
        for (g, tag) in prims {
            let t = match g {
                PrimGeometry::Triangle(p) => intersect_triangle(&tr, p, f32::INFINITY).map(|h| h.0),
                PrimGeometry::Sphere { center, radius } => intersect_sphere(ray, *center, *radius, f32::INFINITY),
            };
            if let Some(t) = t {
                if best.is_none_or(|(bt, _)| t < bt) {
                    best = Some((t, *tag));
                }
            }
        }
        best
    }

    /// 10^5 random rays: the BVH (its wide traversal and the binary
    /// reference) finds exactly the brute-force closest hit and the same
    /// any-hit answer, for several bin counts and leaf sizes.
    #[test]
    fn bvh_matches_brute_force_on_random_rays() {
        let mut rng = Rng::new(7);
        let mut prims = random_triangles(3000, &mut rng);
        for i in 0..40 {
            let center = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 10.0;
            prims.push((
                PrimGeometry::Sphere {
                    center,
                    radius: 0.05 + 0.3 * rng.uniform(),
                },
                10_000 + i,
            ));
        }
        prims.extend(room_walls(20_000));
        let configs = [
            BvhSettings::default(),
            BvhSettings {
                bins: 4,
                max_leaf_size: 1,
                ..Default::default()
            },
            BvhSettings {
                bins: 64,
                traversal_cost: 1.0,
                intersection_cost: 1.0,
                max_leaf_size: 16,
                max_sah_depth: 32,
                all_axes_min_primitives: 0,
            },
        ];
        let mut hits = 0;
        for (c, settings) in configs.iter().enumerate() {
            let bvh = Bvh::build(prims.clone(), settings);
            let rays = if c == 0 { 100_000 } else { 20_000 };
            for _ in 0..rays {
                let o = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 14.0 - 2.0;
                let d = crate::sampling::uniform_sphere(rng.uniform(), rng.uniform());
                let ray = Ray::new(o, d);
                let expected = brute_force(&prims, &ray);
                let got = bvh.intersect(&ray, f32::INFINITY).map(|h| (h.t, bvh.tag(h.prim)));
                assert_eq!(got, expected, "closest hit differs for {ray:?}");
                // The portable traversal gives the very same hit as the
                // dispatched one (AVX2 where the CPU has it).
                assert_eq!(
                    bvh.traverse_wide::<false, false>(&ray, f32::INFINITY),
                    bvh.intersect(&ray, f32::INFINITY)
                );
                // The binary tree's traversal, the wide one's reference, agrees too.
                let binary = bvh
                    .traverse::<false>(&ray, f32::INFINITY)
                    .map(|h| (h.t, bvh.tag(h.prim)));
                assert_eq!(binary, expected, "binary traversal differs for {ray:?}");
                assert_eq!(bvh.intersect_any(&ray, f32::INFINITY), expected.is_some());
                if let Some((t, _)) = expected {
                    hits += 1;
                    // A shadow ray stopping short of the closest hit sees nothing.
                    assert!(!bvh.intersect_any(&ray, t * 0.999));
                }
            }
            assert!(bvh.stats().leaves > 0 && bvh.stats().nodes == 2 * bvh.stats().leaves - 1);
        }
        assert!(
            hits > 10_000,
            "too few rays hit anything ({hits}): the test would prove little"
        );
    }

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

    #[test]
    fn sah_tree_is_cheaper_than_a_single_leaf() {
        let mut rng = Rng::new(3);
        let prims = random_triangles(5000, &mut rng);
        let bvh = Bvh::build(prims, &BvhSettings::default());
        let s = bvh.stats();
        assert_eq!(s.primitives, 5000);
        // A flat list would cost 8 · 5000 = 40000.
        assert!(s.sah_cost < 400.0, "SAH cost {}", s.sah_cost);
        assert!(s.max_depth < 40);
        // What traversal holds: 40 bytes a triangle in full packs (more in
        // part-filled ones), 4 of slot, 4 of tag, some for the nodes: 89 on
        // this random soup, 72 on scanned meshes. A second copy of the
        // geometry (40 more) or the binary tree (60 or so) would show.
        let per_triangle = s.memory_bytes as f32 / 5000.0;
        assert!((60.0..100.0).contains(&per_triangle), "{per_triangle} bytes a triangle");
    }

    /// Primitives spread over 15 orders of magnitude (exponential spacing):
    /// still exact against brute force, and shallow.
    #[test]
    fn exponentially_spaced_primitives_match_brute_force() {
        let n = 1200;
        let prims: Vec<_> = (0..n)
            .map(|i| {
                let x = 1.03f32.powi(i as i32);
                let tri = [
                    Vec3::new(x, 0.0, 0.0),
                    Vec3::new(x, 1e-3 * x, 0.0),
                    Vec3::new(x, 0.0, 1e-3 * x),
                ];
                (PrimGeometry::Triangle(tri), i)
            })
            .collect();
        let bvh = Bvh::build(prims.clone(), &BvhSettings::default());
        assert!(bvh.stats().max_depth <= 64, "depth {}", bvh.stats().max_depth);
        let mut rng = Rng::new(5);
        let mut hits = 0;
        for _ in 0..2000 {
            let i = (rng.uniform() * n as f32) as i32;
            let x = 1.03f32.powi(i);
            // Aim at triangle i from off-axis, across the whole chain.
            let target = Vec3::new(x, 2e-4 * x, 2e-4 * x);
            let origin = Vec3::new(x * (1.1 + rng.uniform()), 0.3 * x, -0.5 * x);
            let ray = Ray::new(origin, (target - origin).normalize());
            let expected = brute_force(&prims, &ray);
            assert_eq!(
                bvh.intersect(&ray, f32::INFINITY).map(|h| (h.t, bvh.tag(h.prim))),
                expected
            );
            hits += usize::from(expected.is_some());
        }
        assert!(hits > 1800, "only {hits} of 2000 aimed rays hit");
    }

    /// Past `max_sah_depth` ranges are halved: the depth is bounded by
    /// max_sah_depth + ⌈log2 n⌉ and the tree stays exact.
    #[test]
    fn depth_is_bounded_past_the_sah_depth() {
        let mut rng = Rng::new(21);
        let prims = random_triangles(3000, &mut rng);
        // Leaves of one primitive, so that nothing stops the splitting early.
        let single = BvhSettings {
            max_leaf_size: 1,
            ..Default::default()
        };
        let free = Bvh::build(prims.clone(), &single);
        let settings = BvhSettings {
            max_sah_depth: 2,
            ..single
        };
        let bounded = Bvh::build(prims.clone(), &settings);
        let limit = 2 + 12; // ⌈log2 3000⌉ = 12
        assert!(
            free.stats().max_depth > limit,
            "the unbounded tree must be deeper for this to test anything"
        );
        assert!(
            bounded.stats().max_depth <= limit,
            "depth {}",
            bounded.stats().max_depth
        );
        for _ in 0..5000 {
            let o = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 14.0 - 2.0;
            let ray = Ray::new(o, crate::sampling::uniform_sphere(rng.uniform(), rng.uniform()));
            let expected = brute_force(&prims, &ray);
            assert_eq!(
                bounded
                    .intersect(&ray, f32::INFINITY)
                    .map(|h| (h.t, bounded.tag(h.prim))),
                expected
            );
        }
    }

    #[test]
    fn identical_primitives_still_build() {
        let tri = PrimGeometry::Triangle([Vec3::ZERO, Vec3::X, Vec3::Y]);
        let prims: Vec<_> = (0..100u32).map(|i| (tri, i)).collect();
        let bvh = Bvh::build(prims, &BvhSettings::default());
        let ray = Ray::new(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z);
        assert!(bvh.intersect(&ray, f32::INFINITY).is_some());
        assert!(bvh.stats().nodes > 1);
        let empty: Bvh<u32> = Bvh::build(Vec::new(), &BvhSettings::default());
        assert!(empty.intersect(&ray, f32::INFINITY).is_none());
    }
}
