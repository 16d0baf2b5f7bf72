//! The binary tree collapsed to the wide tree rays traverse: [`WIDTH`]
//! children a node, small subtrees one leaf of triangle packs.

use glam::Vec4;
use rayon::prelude::*;

use super::build::{primitives, right_child, Node};
use super::layout::{packs_whole, LeafPack, TrianglePack, WideNode, PACK, QUADS, WIDTH};
use super::primitive::PrimGeometry;

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
    /// [`packs_whole`] takes.
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
/// packs), where each 4 KB page would cost a TLB miss. Not for the build's
/// own arrays: written once, in order, their 2 MB pages cost more to get
/// (the kernel compacts and clears them) than their fewer page faults save
/// (BENCHMARKS.md, "the traversal's arrays on 2 MB pages").
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

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::accel::build::tests::reachable;
    use crate::accel::layout::WIDE_LEAF_PRIMITIVES;
    use crate::accel::settings::BvhSettings;
    use crate::accel::tests::{random_triangles, room_walls};
    use crate::accel::Bvh;
    use crate::sampling::Rng;

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
}
