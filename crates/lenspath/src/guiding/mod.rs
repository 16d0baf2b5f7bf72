//! Path guiding: a learned distribution of the light arriving at each
//! region of the scene, which the guided path tracer samples directions
//! from beside the BSDF (Müller, Gross and Novák 2017, "Practical Path
//! Guiding for Efficient Light-Transport Simulation").
//!
//! The guide is an SD-tree: a binary tree over space ([`Guide`], split
//! where many path vertices fall) whose leaves each hold a quadtree over
//! directions ([`directional::DirectionalTree`], subdivided where much light
//! arrives). It is trained in iterations of doubling sample counts: each
//! iteration's paths are guided by the previous iteration's tree and record
//! the light they find into a tree of the same shape, which then becomes the
//! next one to sample, refined. Paths are sampled from the guide and the BSDF
//! together (one-sample MIS with the balance of their densities), so every
//! direction the BSDF can take stays reachable and the estimate unbiased
//! whatever the guide learned.
//!
//! Training is deterministic: records are kept in the order of the pixels
//! that made them and applied leaf by leaf in that order, so the trained
//! guide does not depend on the thread count ([`Guide::learn`]).

pub mod directional;
pub mod map;

use glam::{Vec2, Vec3, Vec3A};
use rayon::prelude::*;

use crate::math::Bounds3;
use crate::sampling::Rng;
use crate::spectrum::SampledSpectrum;
use directional::{to_square, DirectionalTree};

/// The share of guided directions sampled from the BSDF rather than the
/// guide (Müller et al. use one half).
pub const BSDF_SAMPLING_FRACTION: f32 = 0.5;

/// A spatial leaf splits once it got more than this many records times the
/// square root of its iteration's samples per pixel (Müller et al.'s
/// c = 12000 is for 1280×720 images; this is the same per pixel count
/// scaled to lenspath's smaller default images).
const SPLIT_RECORDS: f64 = 4000.0;

/// Deepest the spatial tree grows.
const MAX_SPATIAL_DEPTH: u32 = 48;

/// A spatial node: an inner node splits its box in half along `axis`
/// (children low, high); a leaf holds the directional trees of its region.
#[derive(Clone, Debug)]
enum SpatialNode {
    Inner { axis: u8, children: [u32; 2] },
    Leaf(u32),
}

/// Surfaces are told apart by which of the six axis directions their
/// normal is nearest: a region holds a directional distribution for each,
/// so a floor and the wall beside it (or a sphere's top and its side), which
/// see the same light from different sides, do not share one.
const ORIENTATIONS: usize = 6;

/// Which of the `ORIENTATIONS` a surface with normal `n` has.
#[inline(always)]
pub fn orientation(n: Vec3) -> u8 {
    let a = n.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    2 * axis + u8::from(n[axis as usize] < 0.0)
}

/// What the guide knows of one orientation of surface in one region.
#[derive(Clone, Debug, Default)]
struct Learned {
    /// Sampled by this iteration's paths.
    sampling: DirectionalTree,
    /// Filled by this iteration's records.
    building: DirectionalTree,
}

/// What the guide knows of one region of space.
#[derive(Clone, Debug, Default)]
struct Region {
    /// One per surface orientation.
    learned: [Learned; ORIENTATIONS],
    /// Records this iteration, of every orientation.
    records: u64,
}

/// One observation of light arriving at a path vertex: the spatial leaf it
/// fell in, its surface's orientation, the direction on the unit square, and
/// the radiance divided by the density the direction was sampled with (so a
/// leaf's sum estimates the light arriving through it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GuideRecord {
    leaf: u32,
    orientation: u8,
    square: Vec2,
    energy: f32,
}

/// A trained (or training) SD-tree over a scene.
#[derive(Clone, Debug)]
pub struct Guide {
    /// The scene's bounds made a cube, so splits alternate over equal edges.
    bounds: Bounds3,
    nodes: Vec<SpatialNode>,
    regions: Vec<Region>,
    /// Iterations learned.
    iterations: u32,
}

impl Guide {
    /// A guide over a scene with bounds `bounds` that knows nothing yet.
    pub fn new(bounds: Bounds3) -> Self {
        let centre = (bounds.min + bounds.max) * 0.5;
        let half = (bounds.diagonal().max_element() * 0.5).max(1e-3) * 1.001;
        Guide {
            bounds: Bounds3 {
                min: centre - Vec3A::splat(half),
                max: centre + Vec3A::splat(half),
            },
            nodes: vec![SpatialNode::Leaf(0)],
            regions: vec![Region::default()],
            iterations: 0,
        }
    }

    /// Iterations of training it has learned from.
    pub fn iterations(&self) -> u32 {
        self.iterations
    }

    /// Spatial leaves (regions with their own directional distribution).
    pub fn region_count(&self) -> usize {
        self.regions.len()
    }

    /// The directional leaves over all regions.
    pub fn directional_leaf_count(&self) -> usize {
        self.regions
            .iter()
            .flat_map(|r| &r.learned)
            .map(|l| l.sampling.leaf_count())
            .sum()
    }

    /// The spatial leaf holding `p`.
    #[inline(always)]
    pub fn leaf_at(&self, p: Vec3) -> u32 {
        self.locate(p).0
    }

    /// The spatial leaf holding `p` and the edges of its box.
    #[inline(always)]
    fn locate(&self, p: Vec3) -> (u32, Vec3A) {
        let mut lo = self.bounds.min;
        let mut hi = self.bounds.max;
        let p = Vec3A::from(p);
        let mut node = 0usize;
        loop {
            match self.nodes[node] {
                SpatialNode::Leaf(region) => return (region, hi - lo),
                SpatialNode::Inner { axis, children } => {
                    let a = usize::from(axis);
                    let mid = 0.5 * (lo[a] + hi[a]);
                    if p[a] < mid {
                        hi[a] = mid;
                        node = children[0] as usize;
                    } else {
                        lo[a] = mid;
                        node = children[1] as usize;
                    }
                }
            }
        }
    }

    /// The distribution a path at point `p` on a surface with normal
    /// `normal` samples, if the guide learned light there.
    #[inline(always)]
    pub fn distribution(&self, p: Vec3, normal: Vec3) -> Option<&DirectionalTree> {
        let tree = self.distribution_at(p, normal);
        (tree.total() > 0.0).then_some(tree)
    }

    /// The directional distribution at point `p` on a surface with normal
    /// `normal`, learned or not (for plots of what the guide learned).
    pub fn distribution_at(&self, p: Vec3, normal: Vec3) -> &DirectionalTree {
        &self.regions[self.leaf_at(p) as usize].learned[usize::from(orientation(normal))].sampling
    }

    /// Adds `records` (in the order they were made) to the trees being
    /// built. Each leaf takes its records in their order, whichever thread
    /// applies them, so the sums and the guide are the same for any thread
    /// count.
    pub fn learn(&mut self, records: &[GuideRecord]) {
        // A stable counting sort by leaf keeps each leaf's records in order.
        let mut start = vec![0usize; self.regions.len() + 1];
        for r in records {
            start[r.leaf as usize + 1] += 1;
        }
        for i in 1..start.len() {
            start[i] += start[i - 1];
        }
        let mut next = start.clone();
        let mut sorted = vec![(0u8, Vec2::ZERO, 0f32); records.len()];
        for r in records {
            let slot = &mut next[r.leaf as usize];
            sorted[*slot] = (r.orientation, r.square, r.energy);
            *slot += 1;
        }
        self.regions.par_iter_mut().enumerate().for_each(|(leaf, region)| {
            let mine = &sorted[start[leaf]..start[leaf + 1]];
            region.records += mine.len() as u64;
            for &(orientation, square, energy) in mine {
                region.learned[usize::from(orientation)]
                    .building
                    .add(square, f64::from(energy));
            }
        });
    }

    /// Ends a training iteration of `spp` samples per pixel: splits the
    /// regions that got many records, makes what each region learned its
    /// distribution to sample (refined), and empties the trees to build.
    pub fn end_iteration(&mut self, spp: u32) {
        let threshold = SPLIT_RECORDS * f64::from(spp).sqrt();
        let mut stack = vec![(0usize, 0u32)];
        while let Some((node, depth)) = stack.pop() {
            match self.nodes[node] {
                SpatialNode::Inner { children, .. } => {
                    stack.extend(children.iter().map(|&c| (c as usize, depth + 1)));
                }
                SpatialNode::Leaf(region) => {
                    let r = &mut self.regions[region as usize];
                    if (r.records as f64) <= threshold || depth >= MAX_SPATIAL_DEPTH {
                        continue;
                    }
                    // Both halves start from what the whole learned, with half its records each.
                    r.records /= 2;
                    let twin = r.clone();
                    let (low, high) = (self.nodes.len(), self.nodes.len() + 1);
                    self.regions.push(twin);
                    self.nodes.push(SpatialNode::Leaf(region));
                    self.nodes.push(SpatialNode::Leaf(self.regions.len() as u32 - 1));
                    self.nodes[node] = SpatialNode::Inner {
                        axis: (depth % 3) as u8,
                        children: [low as u32, high as u32],
                    };
                    stack.push((low, depth + 1));
                    stack.push((high, depth + 1));
                }
            }
        }
        self.regions.par_iter_mut().for_each(|r| {
            for l in &mut r.learned {
                // What no path reached this time keeps what it knew.
                if l.building.total() > 0.0 {
                    l.sampling = l.building.refined();
                    l.building = l.sampling.emptied();
                }
            }
            r.records = 0;
        });
        self.iterations += 1;
    }
}

/// Most guided vertices of one path whose light is recorded: the rest of a
/// longer path is traced but not learned from.
const RECORDED_VERTICES: usize = 16;

/// A vertex waiting for the light the rest of its path brings.
#[derive(Clone, Copy, Default)]
struct PendingVertex {
    position: Vec3,
    orientation: u8,
    square: Vec2,
    /// The path throughput after this vertex's scattering: a contribution
    /// `c` to the path's estimate is `throughput · L` with `L` the radiance
    /// it brings into this vertex.
    throughput: SampledSpectrum,
    /// The density the continuation direction was sampled with.
    pdf: f32,
    radiance: SampledSpectrum,
}

/// What one training path records: the light found after each of its
/// guided vertices, and its light samples.
pub struct PathRecorder<'a> {
    out: &'a mut Vec<GuideRecord>,
    guide: &'a Guide,
    /// Draws where in its neighbourhood a record lands.
    rng: Rng,
    pending: [PendingVertex; RECORDED_VERTICES],
    count: usize,
}

impl<'a> PathRecorder<'a> {
    /// A recorder appending to `out` what a path through `guide`'s scene
    /// finds; `seed` (the path's own) places its records.
    pub fn new(out: &'a mut Vec<GuideRecord>, guide: &'a Guide, seed: u64) -> Self {
        PathRecorder {
            out,
            guide,
            rng: Rng::new(seed),
            pending: [PendingVertex::default(); RECORDED_VERTICES],
            count: 0,
        }
    }

    /// The path's estimate grows by `c`: each waiting vertex gets its share
    /// of it as light arriving along its continuation.
    #[inline(always)]
    pub fn contribution(&mut self, c: SampledSpectrum) {
        for v in &mut self.pending[..self.count] {
            let lanes = v.throughput.cmpgt(SampledSpectrum::ZERO);
            v.radiance += SampledSpectrum::select(lanes, c / v.throughput, SampledSpectrum::ZERO);
        }
    }

    /// A guided vertex at `position` on a surface with normal `normal`
    /// continued in direction `wi` (world space), sampled with density
    /// `pdf`, leaving throughput `throughput`.
    #[inline(always)]
    pub fn scattered(&mut self, position: Vec3, normal: Vec3, wi: Vec3, pdf: f32, throughput: SampledSpectrum) {
        if self.count < RECORDED_VERTICES && pdf > 0.0 {
            self.pending[self.count] = PendingVertex {
                position,
                orientation: orientation(normal),
                square: to_square(wi),
                throughput,
                pdf,
                radiance: SampledSpectrum::ZERO,
            };
            self.count += 1;
        }
    }

    /// The path ended: records the light each guided vertex received.
    /// Each record lands at a point drawn uniformly from a box the size of
    /// its vertex's region around the vertex (Müller et al.'s stochastic
    /// spatial box filter): regions learn from their neighbours' vertices
    /// too, so a small region's distribution is less noisy and a boundary
    /// between regions does not show.
    pub fn finish(mut self) {
        for i in 0..self.count {
            let v = self.pending[i];
            // A vertex that found no light is recorded too: it counts toward
            // splitting its region, which is where paths go, lit or not.
            let energy = v.radiance.element_sum() / 4.0 / v.pdf;
            if !(energy.is_finite() && energy >= 0.0) {
                continue;
            }
            let (_, size) = self.guide.locate(v.position);
            let jitter = Vec3A::new(self.rng.uniform(), self.rng.uniform(), self.rng.uniform()) - Vec3A::splat(0.5);
            let leaf = self.guide.leaf_at((Vec3A::from(v.position) + jitter * size).into());
            self.out.push(GuideRecord {
                leaf,
                orientation: v.orientation,
                square: v.square,
                energy,
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    fn records(guide: &Guide, n: usize, seed: u64) -> Vec<GuideRecord> {
        let mut rng = Rng::new(seed);
        (0..n)
            .map(|_| {
                let p = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 2.0;
                GuideRecord {
                    leaf: guide.leaf_at(p),
                    orientation: (rng.next_u64() % 6) as u8,
                    square: Vec2::new(rng.uniform(), rng.uniform()),
                    energy: if p.x < 1.0 { 1.0 } else { rng.uniform() * 3.0 },
                }
            })
            .collect()
    }

    /// Learning the same records in one call or several, with one thread or
    /// many, gives the same guide: its sampling densities agree bit for bit.
    #[test]
    fn learning_is_independent_of_threads_and_batches() {
        let bounds = Bounds3 {
            min: Vec3A::ZERO,
            max: Vec3A::splat(2.0),
        };
        let train = |threads: usize, batches: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let mut guide = Guide::new(bounds);
                for iteration in 0..3 {
                    let all = records(&guide, 30_000 << iteration, iteration);
                    for chunk in all.chunks(all.len().div_ceil(batches)) {
                        guide.learn(chunk);
                    }
                    guide.end_iteration(1 << iteration);
                }
                guide
            })
        };
        let (a, b) = (train(1, 1), train(4, 7));
        assert!(a.region_count() > 4, "{} regions", a.region_count());
        assert_eq!(a.region_count(), b.region_count());
        let mut rng = Rng::new(99);
        for _ in 0..1000 {
            let p = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 2.0;
            let square = Vec2::new(rng.uniform(), rng.uniform());
            let n = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) - 0.5;
            let (da, db) = (a.distribution_at(p, n), b.distribution_at(p, n));
            assert_eq!(da.pdf(square).to_bits(), db.pdf(square).to_bits());
        }
    }
}
