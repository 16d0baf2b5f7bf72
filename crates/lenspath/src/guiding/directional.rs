//! The directional half of the SD-tree: a quadtree over the sphere of
//! directions, whose leaves hold how much light arrived from within them
//! (Müller et al. 2017, "Practical Path Guiding", section 3.2).
//!
//! Directions map to the unit square by the cylindrical (Lambert)
//! projection `u = (cos θ + 1) / 2`, `v = φ / 2π`, which preserves area: a
//! density over the square is the density over the sphere times 4π.

use std::f32::consts::{PI, TAU};

use glam::{Vec2, Vec3};

/// Deepest a quadtree grows: 4^-20 of the sphere, far below what a guide
/// can learn.
const MAX_DEPTH: u32 = 20;

/// A quadrant whose share of its tree's energy is above this is subdivided
/// when the tree is refined (Müller et al.'s ρ).
const SUBDIVIDE_SHARE: f64 = 0.01;

/// ... and only when it got at least this many records: each of its four
/// children then expects a quarter of them or more in the next iteration
/// (which has twice the samples). Without it a quadrant that held much
/// energy in few records is cut finer than the next iteration's records
/// fill, and its empty leaves leave holes (zero density) exactly where the
/// light was.
const SUBDIVIDE_RECORDS: u32 = 64;

/// The unit square point of a unit direction.
#[inline(always)]
pub fn to_square(d: Vec3) -> Vec2 {
    let u = ((d.z.clamp(-1.0, 1.0) + 1.0) * 0.5).min(ONE_BELOW);
    let mut phi = d.y.atan2(d.x);
    if phi < 0.0 {
        phi += TAU;
    }
    Vec2::new(u, (phi / TAU).clamp(0.0, ONE_BELOW))
}

/// The largest f32 below 1, so a point never falls off the square's far edge.
const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

/// The unit direction of a unit square point ([`to_square`]'s inverse).
#[inline(always)]
pub fn from_square(p: Vec2) -> Vec3 {
    let z = 2.0 * p.x - 1.0;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (sin_phi, cos_phi) = (TAU * p.y).sin_cos();
    Vec3::new(r * cos_phi, r * sin_phi, z)
}

/// One node: the energy in each of its four quadrants (quadrant `x + 2y`,
/// `x` set for `u ≥ ½`, `y` for `v ≥ ½` of the node's square) and, for a
/// subdivided quadrant, the index of the node that splits it (0 for a leaf:
/// the root is never anyone's child).
#[derive(Clone, Debug, PartialEq)]
struct Node {
    energy: [f64; 4],
    /// Records that fell in each quadrant.
    records: [u32; 4],
    child: [u32; 4],
}

impl Node {
    const EMPTY: Node = Node {
        energy: [0.0; 4],
        records: [0; 4],
        child: [0; 4],
    };

    fn total(&self) -> f64 {
        self.energy.iter().sum()
    }
}

/// The quadrant of a node's square that `p` (in the node's own unit square)
/// lies in, and `p` in that quadrant's unit square.
#[inline(always)]
fn descend(p: Vec2) -> (usize, Vec2) {
    let (qx, qy) = (p.x >= 0.5, p.y >= 0.5);
    let q = usize::from(qx) + 2 * usize::from(qy);
    let offset = Vec2::new(f32::from(u8::from(qx)), f32::from(u8::from(qy)));
    (q, (2.0 * p - offset).clamp(Vec2::ZERO, Vec2::splat(ONE_BELOW)))
}

/// A quadtree of incident energy over the sphere of directions: sampled in
/// proportion to its leaves' energy, and filled by [`DirectionalTree::add`].
#[derive(Clone, Debug, PartialEq)]
pub struct DirectionalTree {
    nodes: Vec<Node>,
}

impl Default for DirectionalTree {
    fn default() -> Self {
        DirectionalTree {
            nodes: vec![Node::EMPTY],
        }
    }
}

impl DirectionalTree {
    /// The energy it holds: the sum over its leaves.
    pub fn total(&self) -> f64 {
        self.nodes[0].total()
    }

    /// Leaves (quadrants that are not subdivided).
    pub fn leaf_count(&self) -> usize {
        self.nodes
            .iter()
            .map(|n| n.child.iter().filter(|&&c| c == 0).count())
            .sum()
    }

    /// Adds `energy` around the point `square`: spread evenly over a box
    /// the size of the leaf holding it, centred on it (clipped to the unit
    /// square), into every leaf the box overlaps in proportion to the
    /// overlap (Müller et al.'s directional box filter). A record near a
    /// leaf's edge so feeds its neighbour too, and no leaf next to much
    /// light is left empty by chance.
    pub fn add(&mut self, square: Vec2, energy: f64) {
        let size = self.leaf_size_at(square);
        let lo = (square - Vec2::splat(0.5 * size)).max(Vec2::ZERO);
        let hi = (square + Vec2::splat(0.5 * size)).min(Vec2::ONE);
        let area = f64::from((hi - lo).x) * f64::from((hi - lo).y);
        if area <= 0.0 {
            return self.add_at(square, energy);
        }
        let density = energy / area;
        // (node, its square's origin and edge)
        let mut stack = vec![(0usize, Vec2::ZERO, 1.0f32)];
        while let Some((node, origin, edge)) = stack.pop() {
            let half = 0.5 * edge;
            for q in 0..4 {
                let corner = origin + Vec2::new((q & 1) as f32, (q >> 1) as f32) * half;
                let overlap = (hi.min(corner + Vec2::splat(half)) - lo.max(corner)).max(Vec2::ZERO);
                let overlap_area = f64::from(overlap.x) * f64::from(overlap.y);
                if overlap_area <= 0.0 {
                    continue;
                }
                let n = &mut self.nodes[node];
                n.energy[q] += density * overlap_area;
                n.records[q] += 1;
                if n.child[q] != 0 {
                    stack.push((n.child[q] as usize, corner, half));
                }
            }
        }
    }

    /// The edge (in the unit square) of the leaf holding `square`.
    fn leaf_size_at(&self, square: Vec2) -> f32 {
        let (mut node, mut p, mut size) = (0usize, square, 1.0f32);
        loop {
            let (q, inner) = descend(p);
            size *= 0.5;
            match self.nodes[node].child[q] {
                0 => return size,
                c => (node, p) = (c as usize, inner),
            }
        }
    }

    /// Adds `energy` to the leaf holding the point `square` (and so to every
    /// node above it).
    fn add_at(&mut self, square: Vec2, energy: f64) {
        let (mut node, mut p) = (0usize, square);
        loop {
            let (q, inner) = descend(p);
            self.nodes[node].energy[q] += energy;
            self.nodes[node].records[q] += 1;
            match self.nodes[node].child[q] {
                0 => return,
                c => (node, p) = (c as usize, inner),
            }
        }
    }

    /// Density per steradian with which [`DirectionalTree::sample`] returns
    /// the direction at `square`; zero for a tree without energy.
    #[inline(always)]
    pub fn pdf(&self, square: Vec2) -> f32 {
        let (mut node, mut p) = (0usize, square);
        let mut density = 1.0f64;
        loop {
            let n = &self.nodes[node];
            let total = n.total();
            if total <= 0.0 {
                return 0.0;
            }
            let (q, inner) = descend(p);
            density *= 4.0 * n.energy[q] / total;
            match n.child[q] {
                0 => return (density / (4.0 * f64::from(PI))) as f32,
                c => (node, p) = (c as usize, inner),
            }
        }
    }

    /// A direction drawn in proportion to the leaves' energy (uniform
    /// within a leaf) from the uniform point `u`, with its density per
    /// steradian. `None` when the tree holds no energy.
    #[inline(always)]
    pub fn sample(&self, mut u: Vec2) -> Option<(Vec3, f32)> {
        let mut node = 0usize;
        // The chosen leaf's square, as an origin and a size in the unit square.
        let (mut origin, mut size) = (Vec2::ZERO, 1.0f32);
        let mut density = 1.0f64;
        loop {
            let n = &self.nodes[node];
            let total = n.total();
            if total <= 0.0 {
                return None;
            }
            // Pick the column (u ≥ ½ or not) by its share, then the row
            // within it, reusing each coordinate rescaled to [0, 1).
            let left = (n.energy[0] + n.energy[2]) / total;
            let qx = f64::from(u.x) >= left;
            u.x = if qx {
                ((f64::from(u.x) - left) / (1.0 - left)) as f32
            } else {
                (f64::from(u.x) / left) as f32
            };
            let column = if qx {
                [n.energy[1], n.energy[3]]
            } else {
                [n.energy[0], n.energy[2]]
            };
            let lower = column[0] / (column[0] + column[1]);
            let qy = f64::from(u.y) >= lower;
            u.y = if qy {
                ((f64::from(u.y) - lower) / (1.0 - lower)) as f32
            } else {
                (f64::from(u.y) / lower) as f32
            };
            u = u.clamp(Vec2::ZERO, Vec2::splat(ONE_BELOW));
            let q = usize::from(qx) + 2 * usize::from(qy);
            density *= 4.0 * n.energy[q] / total;
            size *= 0.5;
            origin += Vec2::new(f32::from(u8::from(qx)), f32::from(u8::from(qy))) * size;
            match n.child[q] {
                0 => {
                    let square = (origin + u * size).clamp(Vec2::ZERO, Vec2::splat(ONE_BELOW));
                    return Some((from_square(square), (density / (4.0 * f64::from(PI))) as f32));
                }
                c => node = c as usize,
            }
        }
    }

    /// The tree to sample next: this one's energy, on a structure
    /// subdivided where a quadrant holds more than `SUBDIVIDE_SHARE` of
    /// the total and merged where it holds less (Müller et al. 2017, §3.3).
    /// A quadrant that was a leaf and is subdivided spreads its energy
    /// evenly over its four children.
    pub fn refined(&self) -> DirectionalTree {
        let total = self.total();
        let mut out = DirectionalTree { nodes: vec![] };
        // (the new node, its source node if it has one, its uniform energy
        // and records per quadrant otherwise, depth)
        let mut stack = vec![(0usize, Some(0usize), (0.0f64, 0u32), 1u32)];
        out.nodes.push(Node::EMPTY);
        while let Some((at, source, even, depth)) = stack.pop() {
            for q in 0..4 {
                let (energy, records, child_source) = match source {
                    Some(s) => {
                        let n = &self.nodes[s];
                        (
                            n.energy[q],
                            n.records[q],
                            (n.child[q] != 0).then_some(n.child[q] as usize),
                        )
                    }
                    None => (even.0, even.1, None),
                };
                out.nodes[at].energy[q] = energy;
                if depth < MAX_DEPTH && total > 0.0 && energy / total > SUBDIVIDE_SHARE && records >= SUBDIVIDE_RECORDS
                {
                    let child = out.nodes.len();
                    out.nodes.push(Node::EMPTY);
                    out.nodes[at].child[q] = child as u32;
                    stack.push((child, child_source, (energy / 4.0, records / 4), depth + 1));
                }
            }
        }
        out
    }

    /// The same structure with no energy: what the next iteration fills.
    pub fn emptied(&self) -> DirectionalTree {
        let mut out = self.clone();
        for n in &mut out.nodes {
            n.energy = [0.0; 4];
            n.records = [0; 4];
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{uniform_sphere, Rng};

    #[test]
    fn the_square_mapping_is_inverted() {
        let mut rng = Rng::new(3);
        for _ in 0..1000 {
            let d = uniform_sphere(rng.uniform(), rng.uniform());
            let back = from_square(to_square(d));
            assert!((back - d).length() < 1e-5, "{d} -> {back}");
        }
    }

    /// A tree fed with light from one cone: sampling it gives directions
    /// whose density matches `pdf`, the density integrates to one, and most
    /// samples fall in the cone.
    #[test]
    fn a_learned_tree_samples_by_its_pdf() {
        let mut rng = Rng::new(7);
        let cone = Vec3::new(0.3, -0.5, 0.8).normalize();
        let mut tree = DirectionalTree::default();
        for _ in 0..4 {
            let mut building = tree.emptied();
            for _ in 0..20_000 {
                let d = uniform_sphere(rng.uniform(), rng.uniform());
                let light = if d.dot(cone) > 0.95 { 10.0 } else { 0.1 };
                building.add(to_square(d), light * 4.0 * f64::from(PI));
            }
            tree = building.refined();
        }
        assert!(tree.leaf_count() > 20, "{} leaves", tree.leaf_count());
        // ∫ pdf dω by uniform sampling of the sphere.
        let n = 200_000;
        let integral: f64 = (0..n)
            .map(|_| f64::from(tree.pdf(to_square(uniform_sphere(rng.uniform(), rng.uniform())))))
            .sum::<f64>()
            * 4.0
            * f64::from(PI)
            / f64::from(n);
        assert!((integral - 1.0).abs() < 0.02, "∫pdf = {integral}");
        // Samples carry the density pdf() gives, and land in the cone as often as it holds energy.
        let (mut in_cone, mut count) = (0, 0);
        for _ in 0..20_000 {
            let (d, pdf) = tree.sample(Vec2::new(rng.uniform(), rng.uniform())).unwrap();
            let expected = tree.pdf(to_square(d));
            assert!((pdf - expected).abs() <= 1e-3 * expected, "{pdf} vs {expected}");
            in_cone += usize::from(d.dot(cone) > 0.95);
            count += 1;
        }
        // The cone (2.5% of the sphere) holds 10/(10*0.025+0.1*0.975) = 72% of the light.
        let share = in_cone as f64 / f64::from(count);
        assert!((0.6..0.8).contains(&share), "{share} of samples in the cone");
    }

    #[test]
    fn an_empty_tree_cannot_be_sampled() {
        let tree = DirectionalTree::default();
        assert!(tree.sample(Vec2::new(0.3, 0.3)).is_none());
        assert_eq!(tree.pdf(Vec2::new(0.3, 0.3)), 0.0);
    }
}
