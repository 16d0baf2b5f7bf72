//! Everything that tunes the BVH (one settings struct, as tinybvh's) and
//! what a build reports.

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
            // As good a tree as 16 bins, built faster (BENCHMARKS.md, issue 34).
            bins: 8,
            traversal_cost: 1.0,
            intersection_cost: 8.0,
            max_leaf_size: 8,
            max_sah_depth: 32,
            // A faster build for a tree nearly as good as all axes everywhere (BENCHMARKS.md, issue 34).
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
