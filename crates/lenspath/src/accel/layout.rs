//! The wide tree's memory layout: 8-wide nodes with their children's boxes
//! side by side, and leaf packs of four primitives' corners side by side
//! with their tags, as the SIMD tests read them.

use std::mem::size_of;

use glam::{Vec3, Vec4};

use super::primitive::PrimGeometry;

/// A node of the wide tree: its children's boxes side by side (one SIMD
/// lane each, as Embree and tinybvh lay them out), so one slab test meets all
/// eight; 256 bytes, on four cache lines. A child is a leaf when its `count`
/// (of primitives) is non-zero: `child` is then its first pack in
/// `Bvh::packs`, and the leaf fills `count.div_ceil(4)` packs. Otherwise
/// `child` indexes `Bvh::wide`. Lanes beyond `lanes` are unused.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(super) struct WideNode {
    pub(super) min: [[Vec4; QUADS]; 3],
    pub(super) max: [[Vec4; QUADS]; 3],
    pub(super) child: [u32; WIDTH],
    pub(super) count: [u16; WIDTH],
    /// Bit `k` set for the lanes in use.
    pub(super) lanes: u16,
    /// Bit `k` set for the lanes that are leaves.
    pub(super) leaves: u16,
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
pub(super) struct TrianglePack {
    pub(super) corners: [[Vec4; 3]; 3],
}

// What the memory figures in BENCHMARKS.md assume: no header, no padding.
const _: () = assert!(size_of::<TrianglePack>() == 144);

/// A pack with its lanes' tags right after its corners (an unused lane
/// repeats lane 0's tag). A closest hit's tag is read as soon as the
/// traversal returns, and here it mostly shares a cache line with the
/// corners just tested; in an array of its own it was a cache miss for
/// nearly every hit (BENCHMARKS.md, issue 34, fiftieth session).
#[derive(Clone, Copy, Debug)]
#[repr(C)]
pub(super) struct LeafPack<T> {
    pub(super) geometry: TrianglePack,
    pub(super) tags: [T; PACK],
}

// No padding between or after the tags (for the scene's 8-byte tags and
// 4-byte ones): memory per triangle as with the tags apart.
const _: () = assert!(size_of::<LeafPack<[u32; 2]>>() == 144 + 32);
const _: () = assert!(size_of::<LeafPack<u32>>() == 144 + 16);

/// Children of a wide node: Embree's BVH8 on AVX2 machines, faster than 4
/// (BENCHMARKS.md, issue 34). A 256-byte node is fetched in parallel
/// lines; what the tree loses is levels, each a dependent memory access.
pub(super) const WIDTH: usize = 8;

/// The SIMD quads a wide node's boxes fill.
pub(super) const QUADS: usize = WIDTH / 4;

/// Primitives in one [`TrianglePack`].
pub(super) const PACK: usize = 4;

/// The largest subtree the collapse turns into one wide leaf: two packs,
/// the fastest of four, eight and twelve primitives on the dragon, Lucy and
/// the 1 M knot (BENCHMARKS.md, "BVH build: SIMD bins").
pub(super) const WIDE_LEAF_PRIMITIVES: usize = 2 * PACK;

/// ... when its box has at most this fraction of the root box's surface
/// area. Deep in a mesh's tree (where such subtrees have 10⁻⁴ of it) a
/// leaf's packs save the box tests of its last levels; but a few large
/// primitives near the root, such as the walls of a room, are better in
/// their own boxes, which only the rays that hit them enter (a flat box
/// around an axis-aligned quad is the quad).
pub(super) const WIDE_LEAF_MAX_AREA_FRACTION: f32 = 0.01;

/// Whether a subtree of `count` primitives whose box has `area_fraction` of
/// the root box's surface area becomes one wide leaf (the two rules above).
/// The binary build makes such a subtree one leaf instead of splitting it
/// down to single primitives: the collapse would pack it whatever its shape.
#[inline(always)]
pub(super) fn packs_whole(count: usize, area_fraction: f32) -> bool {
    count <= WIDE_LEAF_PRIMITIVES && area_fraction <= WIDE_LEAF_MAX_AREA_FRACTION
}

impl TrianglePack {
    /// Bit `k` set where lane `k` holds a sphere (see [`TrianglePack`]).
    #[inline(always)]
    pub(super) fn spheres(&self) -> u32 {
        self.corners[2][0].is_nan_mask().bitmask()
    }

    /// The geometry in `lane`.
    #[inline]
    pub(super) fn lane(&self, lane: usize) -> PrimGeometry {
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
