//! The BVH's binary tree: binned SAH (Wald, "On fast Construction of
//! SAH-based Bounding Volume Hierarchies", 2007; pbrt-v4 `BVHAggregate`),
//! a node at a time in named steps: whether it stays a leaf, its split
//! (two primitives one a side; more at the cheapest bin plane,
//! [`super::binning`]) and its partition ([`super::partition`]).
//!
//! Large subtrees are built in parallel, each into its own array of nodes,
//! and the arrays are joined in the tree's order (see [`Node`]): the tree,
//! and so every image, is the same bytes for any thread count.

use glam::Vec3A;
use rayon::prelude::*;

use super::binning::{NodeBins, Scratch};
use super::layout::packs_whole;
use super::partition::Sides;
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

    /// Makes `task`'s node, and counts it in `stats`: a leaf, or an
    /// interior node with its two children's tasks.
    fn node(
        &self,
        scratch: &mut Scratch,
        task: &Task,
        bounds: &mut [Bounds3],
        order: &mut [u32],
        stats: &mut SubtreeStats,
    ) -> (Node, Option<(Task, Task)>) {
        let count = task.end - task.start;
        let node_area = task.bounds.surface_area();
        let area_fraction = node_area / self.root_area;
        let costs = NodeCosts {
            parent_area: node_area.max(f32::MIN_POSITIVE),
            leaf: self.settings.intersection_cost * count as f32,
        };
        let children = if self.stays_leaf(task, area_fraction) {
            None
        } else if count == 2 {
            self.split_pair(task, bounds, &costs)
        } else {
            self.split_binned(scratch, task, bounds, order, &costs)
        };
        match children {
            None => {
                stats.leaf(task.depth, costs.leaf * area_fraction);
                (Node::leaf(&task.bounds, task.start, count), None)
            }
            Some(children) => {
                stats.interior(task.depth, self.settings.traversal_cost * area_fraction);
                (Node::interior(&task.bounds, count), Some(children))
            }
        }
    }

    /// Whether `task` is a leaf whatever a split would cost: one
    /// primitive; all centroids in one point; or a subtree the collapse
    /// packs into one wide leaf whatever its shape, where splitting would
    /// be work the wide tree never sees.
    fn stays_leaf(&self, task: &Task, area_fraction: f32) -> bool {
        let count = task.end - task.start;
        let fits = count <= self.settings.max_leaf_size;
        count == 1
            || (fits && task.centroid_bounds.diagonal().max_element() <= 0.0)
            || (fits && packs_whole(count, area_fraction))
    }

    /// Whether a leaf of `count` primitives may be made and costs no more than `split_cost`.
    fn leaf_is_cheaper(&self, count: usize, costs: &NodeCosts, split_cost: f32) -> bool {
        count <= self.settings.max_leaf_size && costs.leaf <= split_cost
    }

    /// A node of two primitives split one a side (the only split: nothing
    /// to bin); `None` where a leaf costs less.
    fn split_pair(&self, task: &Task, bounds: &[Bounds3], costs: &NodeCosts) -> Option<(Task, Task)> {
        let settings = self.settings;
        let (a, b) = (bounds[0], bounds[1]);
        let split_cost = settings.traversal_cost
            + settings.intersection_cost * (a.surface_area() + b.surface_area()) / costs.parent_area;
        if self.leaf_is_cheaper(2, costs, split_cost) {
            return None;
        }
        let one = |start: usize, b: Bounds3| Task {
            start,
            end: start + 1,
            bounds: b,
            centroid_bounds: Bounds3::from_point(b.centroid()),
            depth: task.depth + 1,
        };
        Some((one(task.start, a), one(task.start + 1, b)))
    }

    /// A node of three or more primitives split at its binned SAH plane,
    /// or halved where the tree is deep (`max_sah_depth` bounds its depth)
    /// or no plane separates them; `None` where a leaf costs less.
    fn split_binned(
        &self,
        scratch: &mut Scratch,
        task: &Task,
        bounds: &mut [Bounds3],
        order: &mut [u32],
        costs: &NodeCosts,
    ) -> Option<(Task, Task)> {
        let count = task.end - task.start;
        let bins = NodeBins::new(&task.centroid_bounds, count, self.bins, self.settings);
        let binned = task.centroid_bounds.diagonal().max_element() > 0.0 && task.depth < self.settings.max_sah_depth;
        let split = if binned {
            bins.best_split(scratch, bounds, self.settings, costs.parent_area)
        } else {
            None
        };
        if self.leaf_is_cheaper(count, costs, split.map_or(f32::INFINITY, |s| s.cost)) {
            return None;
        }
        let sides = match split {
            Some(split) => bins.partition(split, scratch, bounds, order),
            None => halves(&task.centroid_bounds, bounds),
        };
        Some(task.children(&sides))
    }
}

/// What a node's leaf and split costs are measured against.
struct NodeCosts {
    /// The node box's surface area (at least the smallest positive float).
    parent_area: f32,
    /// The SAH cost of making it a leaf, before the area weighting.
    leaf: f32,
}

impl Task {
    /// The two tasks this one's range makes, split as `sides` says.
    fn children(&self, sides: &Sides) -> (Task, Task) {
        let mid = self.start + sides.mid;
        let [left_cb, right_cb] = sides.centroid_bounds;
        let [left_bounds, right_bounds] = sides.bounds;
        (
            Task {
                start: self.start,
                end: mid,
                bounds: left_bounds,
                centroid_bounds: left_cb,
                depth: self.depth + 1,
            },
            Task {
                start: mid,
                end: self.end,
                bounds: right_bounds,
                centroid_bounds: right_cb,
                depth: self.depth + 1,
            },
        )
    }
}

/// Primitives `bounds` split in the middle of their range, both halves
/// keeping the node's centroid bounds.
fn halves(centroid_bounds: &Bounds3, bounds: &[Bounds3]) -> Sides {
    let mid = bounds.len() / 2;
    let fold = |r: &[Bounds3]| r.iter().fold(Bounds3::EMPTY, |b, p| b.union(*p));
    Sides {
        mid,
        centroid_bounds: [*centroid_bounds; 2],
        bounds: [fold(&bounds[..mid]), fold(&bounds[mid..])],
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::accel::binning::SAMPLED_BINNING_MIN_PRIMITIVES;
    use crate::accel::tests::{random_triangles, room_walls};
    use crate::accel::Bvh;
    use crate::sampling::Rng;

    /// The binary nodes a traversal from the root can reach.
    pub(in crate::accel) fn reachable(nodes: &[Node]) -> Vec<usize> {
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
}
