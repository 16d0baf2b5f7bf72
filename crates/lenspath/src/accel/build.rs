//! The BVH build: a binned SAH binary tree, its subtrees built in parallel,
//! collapsed to the wide tree and leaf packs that rays traverse.
//!
//! The binary tree follows Wald, "On fast Construction of SAH-based Bounding
//! Volume Hierarchies" (2007) and pbrt-v4 `BVHAggregate`: primitives are
//! binned by centroid along all three axes and the split minimising
//! `C_trav + C_isect · (SA(L)·N(L) + SA(R)·N(R)) / SA(P)` is taken.
//!
//! Large subtrees are built in parallel, each into its own array of nodes,
//! and the arrays are joined in the tree's order (see [`Node`]): the tree,
//! and so every image, is the same bytes for any thread count.

use glam::{Vec3A, Vec4};
use rayon::prelude::*;

use super::layout::{LeafPack, TrianglePack, WideNode, PACK, QUADS, WIDTH};
use super::primitive::PrimGeometry;
use super::settings::BvhSettings;
use crate::math::Bounds3;

/// A binary node: 32 bytes. The nodes lie in depth-first order, each
/// subtree's root first, then its left subtree, then its right one: the
/// left child of interior node `i` is `i + 1`, and the node holds how far
/// after it the right child is. Since every link is relative, a subtree's
/// nodes are the same wherever they end up, so large subtrees are built in
/// parallel into arrays of their own and joined after (on one thread, the
/// whole tree into one).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub(super) struct Node {
    pub(super) min: [f32; 3],
    /// A leaf's first primitive (in the build's order); for an interior
    /// node, how many places after it its right child is.
    link: u32,
    pub(super) max: [f32; 3],
    /// How many primitives the subtree holds, [`LEAF`] set for leaves.
    count: u32,
}

/// The bit of [`Node::count`] set in leaves.
const LEAF: u32 = 1 << 31;

impl Node {
    /// A leaf over the primitives from `first` on.
    fn leaf(b: &Bounds3, first: usize, count: usize) -> Node {
        Node {
            min: b.min.to_array(),
            link: first as u32,
            max: b.max.to_array(),
            count: count as u32 | LEAF,
        }
    }

    /// An interior node; its link to the right child is set once that
    /// child's place is known.
    fn interior(b: &Bounds3, count: usize) -> Node {
        Node {
            min: b.min.to_array(),
            link: 0,
            max: b.max.to_array(),
            count: count as u32,
        }
    }

    /// Its box.
    pub(super) fn bounds(&self) -> Bounds3 {
        Bounds3 {
            min: Vec3A::from_array(self.min),
            max: Vec3A::from_array(self.max),
        }
    }

    /// Whether it is a leaf.
    pub(super) fn is_leaf(&self) -> bool {
        self.count & LEAF != 0
    }

    /// How many primitives its subtree holds.
    pub(super) fn count(&self) -> usize {
        (self.count & !LEAF) as usize
    }
}

/// The right child of interior node `i` (the left one is `i + 1`).
pub(super) fn right_child(nodes: &[Node], i: usize) -> usize {
    i + nodes[i].link as usize
}

/// The primitives (in the build's order) under node `i`: from its leftmost
/// leaf's first on.
pub(super) fn primitives(nodes: &[Node], i: usize) -> std::ops::Range<u32> {
    let mut leftmost = i;
    while !nodes[leftmost].is_leaf() {
        leftmost += 1;
    }
    let first = nodes[leftmost].link;
    first..first + nodes[i].count() as u32
}

/// Subtrees of at least this many primitives build their two children in
/// parallel; smaller ones are one task. Chosen, not tuned (a 2-core machine
/// cannot tell): tinybvh's threaded build hands over subtrees of 2,000.
const PARALLEL_MIN_PRIMITIVES: usize = 4096;

/// Nodes of at least this many primitives bin only every
/// `count / BINNING_SAMPLES`-th of them (512 to 1,023, half or fewer); their
/// partition then finds the children's exact boxes. The SAH cost of the
/// trees this makes is within ±0.4% of full binning's on the dragon, Lucy
/// and the 1 M knot, and the knot's one-thread build takes about 0.83× the
/// time (BENCHMARKS.md, forty-first session).
const SAMPLED_BINNING_MIN_PRIMITIVES: usize = 2048;

/// How many primitives a large node bins, at least (see
/// [`SAMPLED_BINNING_MIN_PRIMITIVES`]).
const BINNING_SAMPLES: usize = 512;

/// The binary tree, what it cost, and the primitives' order in it.
pub(super) struct BinaryTree {
    /// In depth-first order (see [`Node`]).
    pub(super) nodes: Vec<Node>,
    /// Primitive `order[k]` of the input is the `k`-th of the tree.
    pub(super) order: Vec<u32>,
    pub(super) stats: SubtreeStats,
}

/// What a subtree adds to the build's statistics. Subtrees' statistics are
/// added in the tree's order, whatever thread built them, so the SAH cost's
/// rounding does not depend on the thread count.
#[derive(Clone, Copy, Default)]
pub(super) struct SubtreeStats {
    pub(super) nodes: usize,
    pub(super) leaves: usize,
    pub(super) max_depth: usize,
    pub(super) sah_cost: f32,
}

impl SubtreeStats {
    fn leaf(&mut self, depth: usize, cost: f32) {
        self.nodes += 1;
        self.leaves += 1;
        self.max_depth = self.max_depth.max(depth);
        self.sah_cost += cost;
    }

    fn interior(&mut self, depth: usize, cost: f32) {
        self.nodes += 1;
        self.max_depth = self.max_depth.max(depth);
        self.sah_cost += cost;
    }

    fn then(self, other: SubtreeStats) -> SubtreeStats {
        SubtreeStats {
            nodes: self.nodes + other.nodes,
            leaves: self.leaves + other.leaves,
            max_depth: self.max_depth.max(other.max_depth),
            sah_cost: self.sah_cost + other.sah_cost,
        }
    }
}

/// A build task: a primitive range and its boxes.
struct Task {
    start: usize,
    end: usize,
    bounds: Bounds3,
    centroid_bounds: Bounds3,
    depth: usize,
}

/// One builder's working memory: the SAH bins (even and odd primitives'
/// grids), the sweep's right-side sums, and a large node's sampled boxes.
struct Scratch {
    grids: Box<[[[Bin; 3]; 256]; 2]>,
    right_area: Vec<[f32; 3]>,
    right_count: Vec<[u32; 3]>,
    sample: Vec<Bounds3>,
}

impl Scratch {
    fn new(bins: usize) -> Scratch {
        Scratch {
            grids: Box::new([[[EMPTY_BIN; 3]; 256]; 2]),
            right_area: vec![[0.0; 3]; bins],
            right_count: vec![[0; 3]; bins],
            sample: Vec::new(),
        }
    }
}

/// The binned SAH tree over primitives with boxes `bounds` (in the current
/// rayon pool: its subtrees are built in parallel).
pub(super) fn binary_tree(mut bounds: Vec<Bounds3>, settings: &BvhSettings) -> BinaryTree {
    let n = bounds.len();
    let mut order: Vec<u32> = (0..n as u32).into_par_iter().collect();
    if n == 0 {
        return BinaryTree {
            nodes: Vec::new(),
            order,
            stats: SubtreeStats::default(),
        };
    }
    // Min and max are exact, so these do not depend on how the work is split.
    let (root_bounds, root_centroids) = bounds
        .par_iter()
        .fold(
            || (Bounds3::EMPTY, Bounds3::EMPTY),
            |(b, c), p| (b.union(*p), c.grow(p.centroid())),
        )
        .reduce(
            || (Bounds3::EMPTY, Bounds3::EMPTY),
            |(b0, c0), (b1, c1)| (b0.union(b1), c0.union(c1)),
        );
    let builder = Builder {
        settings,
        bins: settings.bins.clamp(2, 256),
        root_area: root_bounds.surface_area().max(f32::MIN_POSITIVE),
        one_thread: rayon::current_num_threads() == 1,
    };
    let root = Task {
        start: 0,
        end: n,
        bounds: root_bounds,
        centroid_bounds: root_centroids,
        depth: 0,
    };
    // On one thread the whole tree is one piece, with room for the most
    // nodes it can have (pages never written are never touched).
    let mut pieces = vec![Vec::with_capacity(if builder.one_thread { 2 * n - 1 } else { 0 })];
    let stats = builder.subtree(root, &mut bounds, &mut order, &mut pieces);
    let nodes = if pieces.len() == 1 {
        pieces.pop().unwrap_or_default()
    } else {
        join(&pieces)
    };
    BinaryTree { nodes, order, stats }
}

/// The pieces of a tree's node array, one after another in one array
/// (copied in parallel).
fn join(pieces: &[Vec<Node>]) -> Vec<Node> {
    let total = pieces.iter().map(Vec::len).sum();
    let mut nodes: Vec<Node> = Vec::with_capacity(total);
    let mut places = Vec::with_capacity(pieces.len());
    let mut rest = &mut nodes.spare_capacity_mut()[..total];
    for piece in pieces {
        let (place, after) = rest.split_at_mut(piece.len());
        places.push(place);
        rest = after;
    }
    places.into_par_iter().zip(pieces).for_each(|(place, piece)| {
        for (slot, node) in place.iter_mut().zip(piece) {
            slot.write(*node);
        }
    });
    // SAFETY: the places cover the first `total` entries, each written above.
    unsafe { nodes.set_len(total) };
    nodes
}

/// What every task of one build shares.
struct Builder<'a> {
    settings: &'a BvhSettings,
    bins: usize,
    root_area: f32,
    /// Whether the pool has one thread: then the whole tree is built into
    /// one array, with no pieces to join.
    one_thread: bool,
}

impl Builder<'_> {
    /// Builds `task`'s subtree over the primitives `bounds` and `order`:
    /// appends its nodes in depth-first order to `pieces`, which are to be
    /// joined one after another. Large subtrees build their two children in
    /// parallel, each into pieces of its own, when the pool has threads to
    /// spare.
    fn subtree(
        &self,
        task: Task,
        bounds: &mut [Bounds3],
        order: &mut [u32],
        pieces: &mut Vec<Vec<Node>>,
    ) -> SubtreeStats {
        let mut scratch = Scratch::new(self.bins);
        let mut stats = SubtreeStats::default();
        let count = task.end - task.start;
        if count < PARALLEL_MIN_PRIMITIVES {
            // Smaller ones run here, as a loop over a stack of tasks, each
            // a left child or a right one with its parent's place.
            let nodes = pieces.last_mut().expect("a piece to append to");
            nodes.reserve(2 * count - 1);
            let base = task.start;
            let mut stack: Vec<(Task, Option<usize>)> = Vec::with_capacity(64);
            stack.push((task, None));
            while let Some((task, parent)) = stack.pop() {
                let place = nodes.len();
                if let Some(parent) = parent {
                    nodes[parent].link = (place - parent) as u32;
                }
                let (s, e) = (task.start - base, task.end - base);
                let (node, children) = self.node(&mut scratch, &task, &mut bounds[s..e], &mut order[s..e], &mut stats);
                nodes.push(node);
                if let Some((left, right)) = children {
                    stack.extend([(right, Some(place)), (left, None)]);
                }
            }
            return stats;
        }
        let (node, children) = self.node(&mut scratch, &task, bounds, order, &mut stats);
        drop(scratch);
        let (piece, place) = (pieces.len() - 1, pieces[pieces.len() - 1].len());
        pieces[piece].push(node);
        let Some((left, right)) = children else {
            return stats;
        };
        let split = left.end - left.start;
        let (left_bounds, right_bounds) = bounds.split_at_mut(split);
        let (left_order, right_order) = order.split_at_mut(split);
        let (l, r) = if self.one_thread {
            let l = self.subtree(left, left_bounds, left_order, pieces);
            (l, self.subtree(right, right_bounds, right_order, pieces))
        } else {
            let (mut left_pieces, mut right_pieces) = (vec![Vec::new()], vec![Vec::new()]);
            let (l, r) = rayon::join(
                || self.subtree(left, left_bounds, left_order, &mut left_pieces),
                || self.subtree(right, right_bounds, right_order, &mut right_pieces),
            );
            pieces.extend(left_pieces);
            pieces.extend(right_pieces);
            (l, r)
        };
        // The right child follows the left subtree's nodes.
        pieces[piece][place].link = 1 + l.nodes as u32;
        stats.then(l).then(r)
    }

    /// Makes `task`'s node: a leaf, or an interior node with its two
    /// children's tasks.
    fn node(
        &self,
        scratch: &mut Scratch,
        task: &Task,
        bounds: &mut [Bounds3],
        order: &mut [u32],
        stats: &mut SubtreeStats,
    ) -> (Node, Option<(Task, Task)>) {
        let settings = self.settings;
        let count = task.end - task.start;
        let node_area = task.bounds.surface_area();
        let parent_area = node_area.max(f32::MIN_POSITIVE);
        let area_fraction = node_area / self.root_area;
        let leaf_cost = settings.intersection_cost * count as f32;
        let leaf = |stats: &mut SubtreeStats| {
            stats.leaf(task.depth, leaf_cost * area_fraction);
            (Node::leaf(&task.bounds, task.start, count), None)
        };

        // Degenerate: one primitive, or all centroids in one point.
        let extent = task.centroid_bounds.diagonal();
        if count == 1 || (extent.max_element() <= 0.0 && count <= settings.max_leaf_size) {
            return leaf(stats);
        }

        // A subtree the collapse packs into one wide leaf whatever its
        // shape: splitting it would be work the wide tree never sees.
        if count <= settings.max_leaf_size && packs_whole(count, area_fraction) {
            return leaf(stats);
        }

        // Two primitives: the only split is one per side; no binning needed.
        if count == 2 {
            let (a, b) = (bounds[0], bounds[1]);
            let split_cost = settings.traversal_cost
                + settings.intersection_cost * (a.surface_area() + b.surface_area()) / parent_area;
            if count <= settings.max_leaf_size && leaf_cost <= split_cost {
                return leaf(stats);
            }
            stats.interior(task.depth, settings.traversal_cost * area_fraction);
            let one = |start: usize, b: Bounds3| Task {
                start,
                end: start + 1,
                bounds: b,
                centroid_bounds: Bounds3::from_point(b.centroid()),
                depth: task.depth + 1,
            };
            return (
                Node::interior(&task.bounds, 2),
                Some((one(task.start, a), one(task.start + 1, b))),
            );
        }

        // Deep in the tree, halving the range bounds the depth (`max_sah_depth`).
        let sah_allowed = task.depth < settings.max_sah_depth;

        // Bin the centroids: along all three axes, or only the longest one in
        // small nodes. Small nodes also use fewer bins, so the sweep costs
        // no more than the binning.
        let node_bins = self.bins.min(count.max(4));
        let cmin = task.centroid_bounds.min;
        let scale = Vec3A::select(
            extent.cmpgt(Vec3A::ZERO),
            Vec3A::splat(node_bins as f32 * (1.0 - 1e-6)) / extent,
            Vec3A::ZERO,
        );
        let mut split: Option<(usize, usize, f32)> = None;
        let axes = if count < settings.all_axes_min_primitives {
            let a = task.centroid_bounds.max_extent_axis();
            a..a + 1
        } else {
            0..3
        };
        let Scratch {
            grids,
            right_area,
            right_count,
            sample,
        } = scratch;
        let sampled = axes.len() == 3 && count >= SAMPLED_BINNING_MIN_PRIMITIVES;
        if extent.max_element() > 0.0 && sah_allowed {
            let [grid, odd_grid] = &mut **grids;
            let last = (node_bins - 1) as f32;
            let binner = Binner {
                cmin,
                scale,
                last: Vec3A::splat(last),
            };
            if axes.len() == 3 {
                // Even and odd primitives go to separate grids, merged
                // after: consecutive primitives in one bin then do not wait
                // on each other's stores.
                reset(grid, node_bins, 0..3);
                reset(odd_grid, node_bins, 0..3);
                let binned = if sampled {
                    sample.clear();
                    sample.extend(bounds.iter().step_by(count / BINNING_SAMPLES));
                    &sample[..]
                } else {
                    &bounds[..]
                };
                binner.bin_all_axes(grid, odd_grid, binned);
                for (bin, odd) in grid[..node_bins].iter_mut().zip(&odd_grid[..node_bins]) {
                    for axis in 0..3 {
                        bin[axis].merge(&odd[axis]);
                    }
                }
            } else {
                reset(grid, node_bins, axes.clone());
                match axes.start {
                    0 => binner.bin_one_axis::<0>(grid, bounds),
                    1 => binner.bin_one_axis::<1>(grid, bounds),
                    _ => binner.bin_one_axis::<2>(grid, bounds),
                }
            }
            let bin_grid = &*grid;
            // Sweep from the right to know the right side of every plane...
            // An empty bin adds no new plane, so only non-empty bins cost work.
            let mut acc = [Bounds3::EMPTY; 3];
            let mut acc_area = [0f32; 3];
            let mut acc_count = [0u32; 3];
            for i in (1..node_bins).rev() {
                for axis in axes.clone() {
                    let bin = &bin_grid[i][axis];
                    if bin.count > 0 {
                        acc[axis] = acc[axis].union(bin.bounds());
                        acc_area[axis] = acc[axis].surface_area();
                        acc_count[axis] += bin.count;
                    }
                    right_area[i][axis] = acc_area[axis];
                    right_count[i][axis] = acc_count[axis];
                }
            }
            // ...then from the left, evaluating the SAH at each distinct plane.
            let mut left = [Bounds3::EMPTY; 3];
            let mut left_count = [0u32; 3];
            for i in 1..node_bins {
                for axis in axes.clone() {
                    let bin = &bin_grid[i - 1][axis];
                    if bin.count == 0 {
                        continue;
                    }
                    left[axis] = left[axis].union(bin.bounds());
                    left_count[axis] += bin.count;
                    if right_count[i][axis] == 0 {
                        continue;
                    }
                    let cost = settings.traversal_cost
                        + settings.intersection_cost
                            * (left[axis].surface_area() * left_count[axis] as f32
                                + right_area[i][axis] * right_count[i][axis] as f32)
                            / parent_area;
                    if split.is_none_or(|(_, _, c)| cost < c) {
                        split = Some((axis, i, cost));
                    }
                }
            }
        }

        let split_cost = split.map_or(f32::INFINITY, |s| s.2);
        if count <= settings.max_leaf_size && leaf_cost <= split_cost {
            return leaf(stats);
        }

        // Partition the range with the binning's own arithmetic, so every
        // primitive lands on the side its bin is on; the children's
        // centroid bounds come from this pass, their bounds from the bins
        // (or, where only a sample was binned, from this pass too).
        let (mid, left_bounds, right_bounds, left_cb, right_cb) = match split {
            Some((axis, plane, _)) => {
                let part = Partition {
                    axis_min: cmin[axis],
                    axis_scale: scale[axis],
                    plane: plane as f32,
                };
                let sides = if sampled {
                    part.run_along::<true>(axis, bounds, order)
                } else {
                    part.run_along::<false>(axis, bounds, order)
                };
                let [lcb, rcb] = sides.centroid_bounds;
                if sampled {
                    let [lb, rb] = sides.bounds;
                    (sides.mid, lb, rb, lcb, rcb)
                } else {
                    let bin_grid = &grids[0];
                    let fold = |range: std::ops::Range<usize>| {
                        bin_grid[range]
                            .iter()
                            .fold(Bounds3::EMPTY, |b, bin| b.union(bin[axis].bounds()))
                    };
                    (sides.mid, fold(0..plane), fold(plane..node_bins), lcb, rcb)
                }
            }
            None => {
                // All centroids coincide, or the tree is deep: split the range in the middle.
                let mid = count / 2;
                let fold = |r: &[Bounds3]| r.iter().fold(Bounds3::EMPTY, |b, p| b.union(*p));
                let c = task.centroid_bounds;
                (mid, fold(&bounds[..mid]), fold(&bounds[mid..]), c, c)
            }
        };
        stats.interior(task.depth, settings.traversal_cost * area_fraction);
        let mid = task.start + mid;
        let children = (
            Task {
                start: task.start,
                end: mid,
                bounds: left_bounds,
                centroid_bounds: left_cb,
                depth: task.depth + 1,
            },
            Task {
                start: mid,
                end: task.end,
                bounds: right_bounds,
                centroid_bounds: right_cb,
                depth: task.depth + 1,
            },
        );
        (Node::interior(&task.bounds, count), Some(children))
    }
}

/// A SAH bin: the box of its primitives, kept as (−min, max) so that growing
/// it is one `max` over eight lanes (as tinybvh's `BuildAVX` bins), and
/// their count.
#[derive(Clone, Copy)]
#[repr(C, align(32))]
struct Bin {
    neg_min: Vec3A,
    max: Vec3A,
    count: u32,
}

const EMPTY_BIN: Bin = Bin {
    neg_min: Vec3A::NEG_INFINITY,
    max: Vec3A::NEG_INFINITY,
    count: 0,
};

impl Bin {
    /// Its box.
    fn bounds(&self) -> Bounds3 {
        Bounds3 {
            min: -self.neg_min,
            max: self.max,
        }
    }

    /// Takes in the primitives of `other`.
    fn merge(&mut self, other: &Bin) {
        self.neg_min = self.neg_min.max(other.neg_min);
        self.max = self.max.max(other.max);
        self.count += other.count;
    }
}

/// The largest subtree the collapse turns into one wide leaf (two packs).
/// Measured on the dragon, Lucy and the 1 M knot (one thread, interleaved
/// rounds): against four, incoherent rays +8 to +26% and coherent ones
/// −3 to +8%; against twelve, or a SAH choice between a subtree and its
/// packs, faster on all three.
const WIDE_LEAF_PRIMITIVES: usize = 2 * PACK;

/// ... when its box has at most this fraction of the root box's surface
/// area. Deep in a mesh's tree (where such subtrees have 10⁻⁴ of it) a
/// leaf's packs save the box tests of its last levels; but a few large
/// primitives near the root, such as the walls of a room, are better in
/// their own boxes, which only the rays that hit them enter (a flat box
/// around an axis-aligned quad is the quad). Measured on cornell-spheres
/// (callgrind, 160×120, 8 spp): 1.12 G instructions without the area bound,
/// 0.92 G with it; the dragon's tree is unchanged.
const WIDE_LEAF_MAX_AREA_FRACTION: f32 = 0.01;

/// Whether a subtree of `count` primitives whose box has `area_fraction` of
/// the root box's surface area becomes one wide leaf (the two rules above).
/// The binary build makes such a subtree one leaf instead of splitting it
/// down to single primitives: the collapse would pack it whatever its shape.
/// Measured (1 M knot, one thread, costs 1:8): 1.87 M binary nodes → 0.34 M,
/// the binary build 250 → 188 ms; the wide tree the same.
#[inline(always)]
fn packs_whole(count: usize, area_fraction: f32) -> bool {
    count <= WIDE_LEAF_PRIMITIVES && area_fraction <= WIDE_LEAF_MAX_AREA_FRACTION
}

/// The binary tree `nodes` (see [`Node`]) as a wide tree: each wide node
/// takes a binary node's children and keeps opening the interior one of
/// largest surface area until it has [`WIDTH`] (Wald et al. 2008, "Getting
/// rid of packets"; Embree's BVH4 and BVH8 collapse). A small subtree of at
/// most [`WIDE_LEAF_PRIMITIVES`] primitives is not opened but becomes one
/// leaf, its triangles tested [`PACK`] at a time in one SIMD step (Embree's
/// `Triangle4` leaves): the last levels of box tests become one or two
/// triangle tests. The leaves' packs hold the primitives `prims[order[k]]`
/// (binary tree order `k`).
///
/// The tree's shape is decided first, writing only links: the top of the
/// tree, then the binary subtrees below it in parallel (see
/// [`SHAPE_TASK_PRIMITIVES`]); the boxes and packs, nearly all of the bytes,
/// are then filled in parallel, straight into allocations of their final
/// size. The wide nodes lie in that order: the top's, then each subtree's.
pub(super) fn collapse<T: Copy + Send + Sync>(
    nodes: &[Node],
    prims: &[(PrimGeometry, T)],
    order: &[u32],
) -> WideTree<T> {
    if nodes.is_empty() {
        return WideTree {
            wide: Vec::new(),
            packs: Vec::new(),
            pack_ranges: Vec::new(),
        };
    }
    let root_area = nodes[0].bounds().surface_area().max(f32::MIN_POSITIVE);
    let mut top = Shape::of(nodes, 0, root_area, SHAPE_TASK_PRIMITIVES);
    let below: Vec<Shape> = top
        .deferred
        .par_iter()
        .map(|&(_, _, c)| Shape::of(nodes, c, root_area, 0))
        .collect();
    // Each subtree's nodes and packs follow the top's and those of the
    // subtrees before it: its links are shifted by those counts, and its
    // root is where the top's lane points.
    let mut offsets = vec![(0, 0)];
    let (mut link_offset, mut pack_offset) = (top.links.len() as u32, top.pack_ranges.len() as u32);
    for (shape, &(slot, lane, _)) in below.iter().zip(&top.deferred) {
        top.links[slot].child[lane] = link_offset;
        offsets.push((link_offset, pack_offset));
        link_offset += shape.links.len() as u32;
        pack_offset += shape.pack_ranges.len() as u32;
    }
    let shapes = || std::iter::once(&top).chain(&below);
    let links: Vec<(&WideLinks, (u32, u32))> = shapes()
        .zip(&offsets)
        .flat_map(|(shape, &offset)| shape.links.iter().map(move |l| (l, offset)))
        .collect();
    let mut wide = huge_vec(links.len());
    links
        .par_iter()
        .map(|&(l, (link_offset, pack_offset))| l.node(nodes, link_offset, pack_offset))
        .collect_into_vec(&mut wide);
    let pack_ranges: Vec<(u32, u32)> = shapes().flat_map(|shape| shape.pack_ranges.iter().copied()).collect();
    let mut packs = huge_vec(pack_ranges.len());
    pack_ranges
        .par_iter()
        .map(|&(first, end)| pack(prims, &order[first as usize..end as usize]))
        .collect_into_vec(&mut packs);
    WideTree {
        wide,
        packs,
        pack_ranges,
    }
}

/// What [`collapse`] makes.
pub(super) struct WideTree<T> {
    pub(super) wide: Vec<WideNode>,
    /// The leaves' packs with their lanes' tags.
    pub(super) packs: Vec<LeafPack<T>>,
    /// Each pack's range of the binary tree's order `k`.
    pub(super) pack_ranges: Vec<(u32, u32)>,
}

/// The slot of each primitive in the binary tree's order `k`, from the
/// packs' ranges of `k` (see [`collapse`]).
#[cfg(test)]
pub(super) fn slots_in_binary_order(pack_ranges: &[(u32, u32)], n: usize) -> Vec<u32> {
    let mut slots = vec![u32::MAX; n];
    for (index, &(first, end)) in pack_ranges.iter().enumerate() {
        for (lane, k) in (first..end).enumerate() {
            slots[k as usize] = (index * PACK + lane) as u32;
        }
    }
    slots
}

/// A wide node without its boxes: what the collapse decides serially.
#[derive(Clone, Copy)]
struct WideLinks {
    /// The binary node behind each lane.
    binary: [u32; WIDTH],
    child: [u32; WIDTH],
    count: [u16; WIDTH],
    lanes: u16,
    leaves: u16,
}

impl WideLinks {
    /// The wide node, its lanes' boxes those of their binary nodes, its
    /// children's indices shifted by `link_offset` (wide nodes) or
    /// `pack_offset` (packs).
    fn node(&self, nodes: &[Node], link_offset: u32, pack_offset: u32) -> WideNode {
        let mut node = WideNode {
            min: [[Vec4::ZERO; QUADS]; 3],
            max: [[Vec4::ZERO; QUADS]; 3],
            child: self.child,
            count: self.count,
            lanes: self.lanes,
            leaves: self.leaves,
        };
        for lane in 0..self.lanes.count_ones() as usize {
            node.child[lane] += if self.leaves & (1 << lane) != 0 {
                pack_offset
            } else {
                link_offset
            };
            let b = &nodes[self.binary[lane] as usize];
            for axis in 0..3 {
                node.min[axis][lane / 4][lane % 4] = b.min[axis];
                node.max[axis][lane / 4][lane % 4] = b.max[axis];
            }
        }
        node
    }
}

/// Binary subtrees of fewer primitives than this, below the top of the
/// tree, are each collapsed as one parallel task.
const SHAPE_TASK_PRIMITIVES: usize = 1 << 14;

/// The shape of (part of) the wide tree.
struct Shape {
    /// Its wide nodes' links (children indexed within this shape).
    links: Vec<WideLinks>,
    /// The primitive range of each pack, in the order the leaves are met.
    pack_ranges: Vec<(u32, u32)>,
    /// The interior children left to other shapes: (wide node, lane, binary node).
    deferred: Vec<(usize, usize, usize)>,
}

impl Shape {
    /// The shape of the wide tree over binary node `root`, leaving the
    /// interior children of fewer than `defer_below` primitives to others.
    fn of(nodes: &[Node], root: usize, root_area: f32, defer_below: usize) -> Shape {
        let candidate = |i: usize| Candidate::new(nodes, i, root_area);
        let root = candidate(root);
        let empty = WideLinks {
            binary: [0; WIDTH],
            child: [0; WIDTH],
            count: [0; WIDTH],
            lanes: 0,
            leaves: 0,
        };
        let mut links = vec![empty];
        let (mut pack_ranges, mut deferred) = (Vec::new(), Vec::new());
        // A leaf root becomes one wide node with a single leaf lane.
        let mut pending = vec![(0usize, if root.wide_leaf { None } else { Some(root.node) })];
        while let Some((slot, binary)) = pending.pop() {
            // Up to WIDTH children, on the stack (no allocation per node).
            let mut children = [root; WIDTH];
            let mut len = match binary {
                None => 1,
                Some(i) => {
                    children[..2].copy_from_slice(&[candidate(i + 1), candidate(right_child(nodes, i))]);
                    2
                }
            };
            while len < WIDTH {
                let widest = children[..len]
                    .iter()
                    .enumerate()
                    .filter(|(_, c)| !c.wide_leaf)
                    .max_by(|a, b| a.1.area.total_cmp(&b.1.area));
                let Some((k, &c)) = widest else { break };
                children[k] = candidate(c.node + 1);
                children[len] = candidate(right_child(nodes, c.node));
                len += 1;
            }
            let mut node = empty;
            for (lane, c) in children[..len].iter().enumerate() {
                node.binary[lane] = c.node as u32;
                node.lanes |= 1 << lane;
                if c.wide_leaf {
                    let std::ops::Range { start: first, end } = primitives(nodes, c.node);
                    node.child[lane] = pack_ranges.len() as u32;
                    node.count[lane] = (end - first) as u16;
                    node.leaves |= 1 << lane;
                    pack_ranges.extend((first..end).step_by(PACK).map(|p| (p, end.min(p + PACK as u32))));
                } else if nodes[c.node].count() < defer_below {
                    deferred.push((slot, lane, c.node));
                } else {
                    node.child[lane] = links.len() as u32;
                    links.push(empty);
                    pending.push((node.child[lane] as usize, Some(c.node)));
                }
            }
            links[slot] = node;
        }
        Shape {
            links,
            pack_ranges,
            deferred,
        }
    }
}

/// A binary node the collapse may open, with what it decides by, worked
/// out once (the choice looks at each child several times).
#[derive(Clone, Copy)]
struct Candidate {
    node: usize,
    area: f32,
    /// Whether it becomes a wide leaf: every binary leaf, and every subtree
    /// of at most [`WIDE_LEAF_PRIMITIVES`] primitives whose box has at most
    /// the area limit of surface (see [`WIDE_LEAF_MAX_AREA_FRACTION`]).
    wide_leaf: bool,
}

impl Candidate {
    fn new(nodes: &[Node], node: usize, root_area: f32) -> Candidate {
        let n = &nodes[node];
        let area = n.bounds().surface_area();
        Candidate {
            node,
            area,
            wide_leaf: n.is_leaf() || packs_whole(n.count(), area / root_area),
        }
    }
}

/// A pack of the wide leaves holding the primitives `prims[i]` for `i` in
/// `members` (one to four), and its lanes' tags.
fn pack<T: Copy>(prims: &[(PrimGeometry, T)], members: &[u32]) -> LeafPack<T> {
    let mut pack = TrianglePack {
        corners: [[Vec4::ZERO; 3]; 3],
    };
    let mut tags = [prims[members[0] as usize].1; PACK];
    for (lane, &prim) in members.iter().enumerate() {
        let (geometry, tag) = &prims[prim as usize];
        tags[lane] = *tag;
        match geometry {
            PrimGeometry::Triangle(p) => {
                for (k, corner) in p.iter().enumerate() {
                    for axis in 0..3 {
                        pack.corners[k][axis][lane] = corner[axis];
                    }
                }
            }
            PrimGeometry::Sphere { center, radius } => {
                for axis in 0..3 {
                    pack.corners[0][axis][lane] = center[axis];
                }
                pack.corners[1][0][lane] = *radius;
                pack.corners[2][0][lane] = f32::NAN;
            }
        }
    }
    LeafPack { geometry: pack, tags }
}

/// An empty vector with room for `capacity` elements whose memory Linux may
/// back with 2 MB pages (transparent huge pages on `madvise`, as Embree's
/// allocator asks). For the arrays rays read at random (wide nodes and
/// packs), where each 4 KB page would cost a TLB miss: incoherent rays
/// through the 1 M knot +16% (median of 7 interleaved rounds). Not for the
/// build's own arrays: written once, in order, their 2 MB pages cost more
/// to get (the kernel compacts and clears them; 0.08–0.58 s of system time
/// a 1 M build) than their fewer page faults save.
fn huge_vec<T>(capacity: usize) -> Vec<T> {
    let v: Vec<T> = Vec::with_capacity(capacity);
    #[cfg(target_os = "linux")]
    {
        const PAGE: usize = 4096;
        let bytes = capacity * size_of::<T>();
        if bytes >= 2 << 20 {
            // Advice is given for whole pages: here those of the allocation's
            // mapping (a large allocation is a mapping of its own).
            let start = v.as_ptr() as usize / PAGE * PAGE;
            let end = (v.as_ptr() as usize + bytes).next_multiple_of(PAGE);
            // SAFETY: advice only, on pages of this allocation's mapping.
            unsafe { libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE) };
        }
    }
    v
}

fn reset(grid: &mut [[Bin; 3]; 256], n: usize, axes: std::ops::Range<usize>) {
    for bin in &mut grid[..n] {
        for axis in axes.clone() {
            bin[axis] = EMPTY_BIN;
        }
    }
}

/// Maps centroids to bins. Axis loops are unrolled and bins are indexed
/// `& 255` into fixed arrays, so the hot loops carry no bounds checks.
struct Binner {
    cmin: Vec3A,
    scale: Vec3A,
    last: Vec3A,
}

impl Binner {
    #[inline(always)]
    fn indices(&self, b: &Bounds3) -> [u32; 3] {
        bin_indices(((b.centroid() - self.cmin) * self.scale).min(self.last))
    }

    #[inline(always)]
    fn add<const A: usize>(grid: &mut [[Bin; 3]; 256], k: u32, b: &Bounds3) {
        let bin = &mut grid[(k & 255) as usize][A];
        bin.neg_min = bin.neg_min.max(-b.min);
        bin.max = bin.max.max(b.max);
        bin.count += 1;
    }

    /// Bins `prims` along all three axes, even ones into `grid`, odd ones
    /// into `odd_grid`: with AVX where the CPU has it (the same bins).
    fn bin_all_axes(&self, grid: &mut [[Bin; 3]; 256], odd_grid: &mut [[Bin; 3]; 256], prims: &[Bounds3]) {
        #[cfg(target_arch = "x86_64")]
        if cpu_has_avx() {
            // SAFETY: the CPU has the feature the function is compiled for.
            return unsafe { self.bin_all_axes_avx(grid, odd_grid, prims) };
        }
        self.bin_all_axes_portable(grid, odd_grid, prims);
    }

    /// [`Binner::bin_all_axes`] without SIMD beyond the baseline.
    fn bin_all_axes_portable(&self, grid: &mut [[Bin; 3]; 256], odd_grid: &mut [[Bin; 3]; 256], prims: &[Bounds3]) {
        let mut pairs = prims.chunks_exact(2);
        for pair in &mut pairs {
            let (k0, k1) = (self.indices(&pair[0]), self.indices(&pair[1]));
            Self::add::<0>(grid, k0[0], &pair[0]);
            Self::add::<0>(odd_grid, k1[0], &pair[1]);
            Self::add::<1>(grid, k0[1], &pair[0]);
            Self::add::<1>(odd_grid, k1[1], &pair[1]);
            Self::add::<2>(grid, k0[2], &pair[0]);
            Self::add::<2>(odd_grid, k1[2], &pair[1]);
        }
        if let [b] = pairs.remainder() {
            let k = self.indices(b);
            Self::add::<0>(grid, k[0], b);
            Self::add::<1>(grid, k[1], b);
            Self::add::<2>(grid, k[2], b);
        }
    }

    /// [`Binner::bin_all_axes`] with each box grown by one 8-lane `max`.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    fn bin_all_axes_avx(&self, grid: &mut [[Bin; 3]; 256], odd_grid: &mut [[Bin; 3]; 256], prims: &[Bounds3]) {
        use std::arch::x86_64::{__m256, _mm256_castsi256_ps, _mm256_loadu_ps, _mm256_max_ps, _mm256_setr_epi32};
        use std::arch::x86_64::{_mm256_store_ps, _mm256_xor_ps};
        // Flips the sign of the min corner's four lanes: (min, max) → (−min, max).
        let flip = _mm256_castsi256_ps(_mm256_setr_epi32(i32::MIN, i32::MIN, i32::MIN, i32::MIN, 0, 0, 0, 0));
        let load = |b: &Bounds3| {
            // SAFETY: `Bounds3` is `repr(C)`: 32 bytes, min then max.
            _mm256_xor_ps(unsafe { _mm256_loadu_ps((b as *const Bounds3).cast()) }, flip)
        };
        let add = |grid: &mut [[Bin; 3]; 256], axis: usize, k: u32, f: __m256| {
            let bin = &mut grid[(k & 255) as usize][axis];
            let lanes = (bin as *mut Bin).cast::<f32>();
            // SAFETY: a `Bin` is `repr(C, align(32))` and opens with its 32
            // bytes of (−min, max), the same `max_ps` as `Binner::add`'s.
            unsafe { _mm256_store_ps(lanes, _mm256_max_ps(_mm256_loadu_ps(lanes), f)) };
            bin.count += 1;
        };
        let mut pairs = prims.chunks_exact(2);
        for pair in &mut pairs {
            let (k0, k1) = (self.indices(&pair[0]), self.indices(&pair[1]));
            let (f0, f1) = (load(&pair[0]), load(&pair[1]));
            for axis in 0..3 {
                add(grid, axis, k0[axis], f0);
                add(odd_grid, axis, k1[axis], f1);
            }
        }
        if let [b] = pairs.remainder() {
            let f = load(b);
            for (axis, k) in self.indices(b).into_iter().enumerate() {
                add(grid, axis, k, f);
            }
        }
    }

    fn bin_one_axis<const A: usize>(&self, grid: &mut [[Bin; 3]; 256], prims: &[Bounds3]) {
        for b in prims {
            Self::add::<A>(grid, self.indices(b)[A], b);
        }
    }
}

/// Splits a primitive range at a bin plane with the binning's own arithmetic
/// (the same IEEE operations per lane), so each primitive goes where its bin is.
struct Partition {
    axis_min: f32,
    axis_scale: f32,
    plane: f32,
}

impl Partition {
    /// [`Partition::run`] along `axis`.
    #[inline(always)]
    fn run_along<const BOXES: bool>(&self, axis: usize, bounds: &mut [Bounds3], order: &mut [u32]) -> Sides {
        match axis {
            0 => self.run::<0, BOXES>(bounds, order),
            1 => self.run::<1, BOXES>(bounds, order),
            _ => self.run::<2, BOXES>(bounds, order),
        }
    }

    /// Partitions `bounds` (and `order` alike) in place; returns the split
    /// index, the centroid bounds of both sides and, with `BOXES`, their
    /// bounds.
    fn run<const A: usize, const BOXES: bool>(&self, bounds: &mut [Bounds3], order: &mut [u32]) -> Sides {
        // Hoare's scheme: scan in from both ends and swap only pairs that are
        // both on the wrong side (a quarter of a random range, where moving
        // every right-side primitive to the end would swap half of it).
        let (mut i, mut j) = (0, bounds.len());
        let (mut lcb, mut rcb) = (Bounds3::EMPTY, Bounds3::EMPTY);
        let (mut lb, mut rb) = (Bounds3::EMPTY, Bounds3::EMPTY);
        // The binning puts x in bin trunc(min(x, last)); for x ≥ 0 and an
        // integer plane ≤ last that bin is left of the plane iff x < plane.
        let left = |c: Vec3A| (c[A] - self.axis_min) * self.axis_scale < self.plane;
        'scan: loop {
            // The first primitive from the left that belongs right...
            let right_centroid = loop {
                if i == j {
                    break 'scan;
                }
                let c = bounds[i].centroid();
                if !left(c) {
                    break c;
                }
                lcb = lcb.grow(c);
                if BOXES {
                    lb = lb.union(bounds[i]);
                }
                i += 1;
            };
            // ...and the first from the right that belongs left.
            let left_centroid = loop {
                j -= 1;
                if j == i {
                    rcb = rcb.grow(right_centroid);
                    if BOXES {
                        rb = rb.union(bounds[i]);
                    }
                    break 'scan;
                }
                let c = bounds[j].centroid();
                if left(c) {
                    break c;
                }
                rcb = rcb.grow(c);
                if BOXES {
                    rb = rb.union(bounds[j]);
                }
            };
            bounds.swap(i, j);
            order.swap(i, j);
            lcb = lcb.grow(left_centroid);
            rcb = rcb.grow(right_centroid);
            if BOXES {
                lb = lb.union(bounds[i]);
                rb = rb.union(bounds[j]);
            }
            i += 1;
        }
        Sides {
            mid: i,
            centroid_bounds: [lcb, rcb],
            bounds: [lb, rb],
        }
    }
}

/// A partition's result: where the right side starts, and both sides'
/// centroid bounds and (if asked for) bounds.
struct Sides {
    mid: usize,
    centroid_bounds: [Bounds3; 2],
    bounds: [Bounds3; 2],
}

/// Truncates three non-negative floats to bin indices in one conversion.
#[inline(always)]
fn bin_indices(v: Vec3A) -> [u32; 3] {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{__m128, __m128i, _mm_cvttps_epi32};
        // SAFETY: SSE2 is part of the x86_64 baseline; the casts reinterpret
        // 16-byte SIMD values of the same size.
        let k: [u32; 4] = unsafe { std::mem::transmute::<__m128i, [u32; 4]>(_mm_cvttps_epi32(__m128::from(v))) };
        [k[0], k[1], k[2]]
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        [v.x as u32, v.y as u32, v.z as u32]
    }
}

/// Whether this CPU runs the AVX binning of the BVH build.
#[cfg(target_arch = "x86_64")]
fn cpu_has_avx() -> bool {
    std::is_x86_feature_detected!("avx")
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::accel::tests::{random_triangles, room_walls};
    use crate::accel::Bvh;
    use crate::sampling::Rng;

    /// The binary nodes a traversal from the root can reach.
    fn reachable(nodes: &[Node]) -> Vec<usize> {
        let (mut found, mut stack) = (Vec::new(), vec![0]);
        while let Some(i) = stack.pop() {
            found.push(i);
            if !nodes[i].is_leaf() {
                stack.extend([i + 1, right_child(nodes, i)]);
            }
        }
        found
    }

    /// Built in one thread and in four, the tree is the same bytes: its
    /// wide nodes, packs, tags and SAH cost (summed in the tree's order).
    /// 40 000 primitives, so the top of the tree is split between threads.
    #[test]
    fn the_tree_is_the_same_for_any_thread_count() {
        let mut prims = random_triangles(40_000, &mut Rng::new(9));
        prims.extend(room_walls(100_000));
        let build = |threads: usize| {
            let pool = crate::parallel::worker_pool(Some(threads)).unwrap();
            pool.install(|| Bvh::build(prims.clone(), &BvhSettings::default()))
        };
        let (one, four) = (build(1), build(4));
        let bytes = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let boxes = |b: &Bvh<u32>| {
            b.wide
                .iter()
                .flat_map(|n| n.min.iter().chain(&n.max).flatten().flat_map(|q| q.to_array()))
                .collect::<Vec<f32>>()
        };
        let corners = |b: &Bvh<u32>| {
            b.packs
                .iter()
                .flat_map(|p| p.geometry.corners.iter().flatten().flat_map(|q| q.to_array()))
                .collect::<Vec<f32>>()
        };
        let links = |b: &Bvh<u32>| {
            b.wide
                .iter()
                .map(|n| (n.child, n.count, n.lanes, n.leaves))
                .collect::<Vec<_>>()
        };
        assert!(one.stats().nodes > 2 * PARALLEL_MIN_PRIMITIVES / 8);
        assert_eq!(bytes(&boxes(&one)), bytes(&boxes(&four)));
        assert_eq!(bytes(&corners(&one)), bytes(&corners(&four)));
        assert_eq!(links(&one), links(&four));
        let tags = |b: &Bvh<u32>| b.packs.iter().map(|p| p.tags).collect::<Vec<_>>();
        assert_eq!(tags(&one), tags(&four));
        assert_eq!(one.stats().sah_cost.to_bits(), four.stats().sah_cost.to_bits());
        assert_eq!(one.stats().nodes, four.stats().nodes);
    }

    /// Every binary node's box is exactly the union of its primitives'
    /// boxes, in the large nodes whose binning saw only a sample of them
    /// as in the small ones: a box from the sample alone would be too small
    /// and cull hits.
    #[test]
    fn node_boxes_are_exactly_their_primitives_boxes() {
        let mut prims = random_triangles(20_000, &mut Rng::new(13));
        prims.extend(room_walls(20_000));
        let bvh = Bvh::build(prims, &BvhSettings::default());
        let nodes = &bvh.nodes;
        let mut sampled = 0;
        for i in reachable(nodes) {
            let range = primitives(nodes, i);
            sampled += usize::from(range.len() >= SAMPLED_BINNING_MIN_PRIMITIVES);
            let union = range.fold(Bounds3::EMPTY, |b, k| {
                b.union(bvh.primitive(bvh.slot_of[k as usize]).bounds())
            });
            assert_eq!(
                (nodes[i].min, nodes[i].max),
                (union.min.to_array(), union.max.to_array()),
                "node {i}"
            );
        }
        assert!(
            sampled >= 7,
            "only {sampled} nodes binned a sample: the test would prove little"
        );
    }

    /// The collapse packs the small subtrees of a dense cluster into wide
    /// leaves but opens those of a room's walls down to their own boxes.
    #[test]
    fn collapse_packs_small_subtrees_but_not_large_walls() {
        let mut prims = random_triangles(3000, &mut Rng::new(3))
            .into_iter()
            .map(|(mut g, tag)| {
                // Shrink the cluster to a tenth of the room.
                if let PrimGeometry::Triangle(t) = &mut g {
                    *t = t.map(|p| p * 0.1 + Vec3::splat(5.0));
                }
                (g, tag)
            })
            .collect::<Vec<_>>();
        prims.extend(room_walls(20_000));
        let bvh = Bvh::build(prims.clone(), &BvhSettings::default());
        let nodes = &bvh.nodes;
        let root_area = nodes[0].bounds().surface_area();
        let reachable = reachable(nodes);
        let range = |i: usize| primitives(nodes, i);
        let is_wall = |i: usize| range(i).all(|k| bvh.tag(bvh.slot_of[k as usize]) >= 20_000);
        // Subtrees of several primitives that the collapse could pack.
        let small = |i: usize| (2..=WIDE_LEAF_PRIMITIVES).contains(&range(i).len());
        let leaf = |i: usize| Candidate::new(nodes, i, root_area).wide_leaf;
        let count = |f: &dyn Fn(usize) -> bool| reachable.iter().filter(|&&i| f(i)).count();
        // Packed by the area rule, not because the SAH made a leaf.
        let by_rule = |i: usize| packs_whole(range(i).len(), nodes[i].bounds().surface_area() / root_area);
        let packed_cluster = count(&|i| small(i) && leaf(i) && by_rule(i) && !is_wall(i));
        let opened_walls = count(&|i| small(i) && !leaf(i) && is_wall(i));
        let packed_walls = count(&|i| small(i) && by_rule(i) && is_wall(i));
        assert!(packed_cluster > 100, "cluster subtrees packed: {packed_cluster}");
        assert!(opened_walls > 0, "wall subtrees opened: {opened_walls}");
        assert_eq!(packed_walls, 0, "a wall subtree was packed");
        // Every primitive sits in its own pack lane, which holds its tag.
        let mut slots = bvh.slot_of.clone();
        slots.sort_unstable();
        slots.dedup();
        assert_eq!(slots.len(), prims.len());
        let mut tags: Vec<u32> = slots.iter().map(|&slot| bvh.tag(slot)).collect();
        tags.sort_unstable();
        assert_eq!(tags, prims.iter().map(|p| p.1).collect::<Vec<_>>());
        let lanes: usize = bvh
            .wide
            .iter()
            .flat_map(|n| {
                (0..WIDTH)
                    .filter(|&l| n.leaves & (1 << l) != 0)
                    .map(|l| usize::from(n.count[l]))
            })
            .sum();
        assert_eq!(lanes, prims.len());
    }

    /// The AVX binning fills the same bins as the portable one, bit for bit
    /// (so the tree does not depend on the CPU), over a range with an odd
    /// count and negative zeros among the coordinates.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx_binning_matches_the_portable_one_bit_for_bit() {
        if !cpu_has_avx() {
            eprintln!("skipped: this CPU has no AVX");
            return;
        }
        let mut prims: Vec<Bounds3> = random_triangles(1001, &mut Rng::new(5))
            .iter()
            .map(|(g, _)| g.bounds())
            .collect();
        prims[7].min.x = -0.0;
        prims[8].max.y = -0.0;
        let all = prims.iter().fold(Bounds3::EMPTY, |b, p| b.union(*p));
        let bins = 8;
        let binner = Binner {
            cmin: all.min,
            scale: Vec3A::splat(bins as f32 * (1.0 - 1e-6)) / all.diagonal(),
            last: Vec3A::splat((bins - 1) as f32),
        };
        let bits = |bin: &Bin| {
            let b = bin.bounds();
            (
                b.min.to_array().map(f32::to_bits),
                b.max.to_array().map(f32::to_bits),
                bin.count,
            )
        };
        let mut grids = [(); 2].map(|_| Box::new([[[EMPTY_BIN; 3]; 256]; 2]));
        let [even, odd] = &mut *grids[0];
        binner.bin_all_axes_portable(even, odd, &prims);
        let [even, odd] = &mut *grids[1];
        // SAFETY: the CPU has AVX (checked above).
        unsafe { binner.bin_all_axes_avx(even, odd, &prims) };
        for (g, (portable, avx)) in grids[0].iter().zip(grids[1].iter()).enumerate() {
            for (k, (p, a)) in portable.iter().zip(avx.iter()).enumerate().take(bins) {
                for axis in 0..3 {
                    assert_eq!(bits(&p[axis]), bits(&a[axis]), "grid {g}, bin {k}, axis {axis}");
                }
            }
        }
        let binned: u32 = grids[1].iter().flat_map(|g| g[..bins].iter().map(|b| b[0].count)).sum();
        assert_eq!(binned, 1001);
    }
}
