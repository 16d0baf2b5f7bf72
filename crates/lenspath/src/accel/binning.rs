//! A node's SAH split: its primitives' centroids binned along the axes
//! (Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies",
//! 2007; the AVX binning beside its portable twin, the same bins bit for
//! bit), a sweep over the bin planes for the cheapest, and the partition
//! at it.

use glam::Vec3A;

use super::partition::{Partition, Sides};
use super::settings::BvhSettings;
use crate::math::Bounds3;

/// Nodes of at least this many primitives bin only every
/// `count / BINNING_SAMPLES`-th of them (512 to 1,023, half or fewer); their
/// partition then finds the children's exact boxes. The trees cost what
/// full binning's do, within noise, for less build time (BENCHMARKS.md,
/// "Sampled binning").
pub(super) const SAMPLED_BINNING_MIN_PRIMITIVES: usize = 2048;

/// How many primitives a large node bins, at least (see
/// [`SAMPLED_BINNING_MIN_PRIMITIVES`]).
const BINNING_SAMPLES: usize = 512;

/// One builder's working memory: the SAH bins (even and odd primitives'
/// grids), the sweep's right-side sums, and a large node's sampled boxes.
pub(super) struct Scratch {
    grids: Box<[[[Bin; 3]; 256]; 2]>,
    right_area: Vec<[f32; 3]>,
    right_count: Vec<[u32; 3]>,
    sample: Vec<Bounds3>,
}

impl Scratch {
    /// Room for `bins` bins a node.
    pub(super) fn new(bins: usize) -> Scratch {
        Scratch {
            grids: Box::new([[[EMPTY_BIN; 3]; 256]; 2]),
            right_area: vec![[0.0; 3]; bins],
            right_count: vec![[0; 3]; bins],
            sample: Vec::new(),
        }
    }
}

/// The plane a node splits at: `plane` bins from the low end along `axis`,
/// and its SAH cost.
#[derive(Clone, Copy)]
pub(super) struct Split {
    axis: usize,
    plane: usize,
    pub(super) cost: f32,
}

/// How one node's primitives are binned: how many bins, along which axes,
/// the centroid-to-bin map, and whether only a sample of them is binned.
pub(super) struct NodeBins {
    bins: usize,
    axes: std::ops::Range<usize>,
    binner: Binner,
    sampled: bool,
}

impl NodeBins {
    /// The binning of a node of `count` primitives whose centroids span
    /// `centroid_bounds`, with at most `max_bins` bins: along all three
    /// axes, or only the longest one in small nodes. Small nodes also use
    /// fewer bins, so the sweep costs no more than the binning.
    pub(super) fn new(centroid_bounds: &Bounds3, count: usize, max_bins: usize, settings: &BvhSettings) -> NodeBins {
        let bins = max_bins.min(count.max(4));
        let extent = centroid_bounds.diagonal();
        let scale = Vec3A::select(
            extent.cmpgt(Vec3A::ZERO),
            Vec3A::splat(bins as f32 * (1.0 - 1e-6)) / extent,
            Vec3A::ZERO,
        );
        let axes = if count < settings.all_axes_min_primitives {
            let a = centroid_bounds.max_extent_axis();
            a..a + 1
        } else {
            0..3
        };
        NodeBins {
            bins,
            sampled: axes.len() == 3 && count >= SAMPLED_BINNING_MIN_PRIMITIVES,
            axes,
            binner: Binner {
                cmin: centroid_bounds.min,
                scale,
                last: Vec3A::splat((bins - 1) as f32),
            },
        }
    }

    /// The cheapest split of the node's primitives, boxes `bounds`, its own
    /// box's surface area `parent_area` (`None` when no plane has
    /// primitives on both sides). Leaves the bins in `scratch` for
    /// [`NodeBins::partition`].
    pub(super) fn best_split(
        &self,
        scratch: &mut Scratch,
        bounds: &[Bounds3],
        settings: &BvhSettings,
        parent_area: f32,
    ) -> Option<Split> {
        self.bin(scratch, bounds);
        self.sweep(scratch, settings, parent_area)
    }

    /// Bins the centroids of `bounds` (or of a sample of them).
    fn bin(&self, scratch: &mut Scratch, bounds: &[Bounds3]) {
        let Scratch { grids, sample, .. } = scratch;
        let [grid, odd_grid] = &mut **grids;
        let n = self.bins;
        if self.axes.len() == 3 {
            // Even and odd primitives go to separate grids, merged after:
            // consecutive primitives in one bin then do not wait on each
            // other's stores.
            reset(grid, n, 0..3);
            reset(odd_grid, n, 0..3);
            let binned = if self.sampled {
                sample.clear();
                sample.extend(bounds.iter().step_by(bounds.len() / BINNING_SAMPLES));
                &sample[..]
            } else {
                bounds
            };
            self.binner.bin_all_axes(grid, odd_grid, binned);
            for (bin, odd) in grid[..n].iter_mut().zip(&odd_grid[..n]) {
                for axis in 0..3 {
                    bin[axis].merge(&odd[axis]);
                }
            }
        } else {
            reset(grid, n, self.axes.clone());
            match self.axes.start {
                0 => self.binner.bin_one_axis::<0>(grid, bounds),
                1 => self.binner.bin_one_axis::<1>(grid, bounds),
                _ => self.binner.bin_one_axis::<2>(grid, bounds),
            }
        }
    }

    /// The SAH's cheapest plane among the bins' (pbrt-v4's sweep).
    fn sweep(&self, scratch: &mut Scratch, settings: &BvhSettings, parent_area: f32) -> Option<Split> {
        let Scratch {
            grids,
            right_area,
            right_count,
            ..
        } = scratch;
        let bin_grid = &grids[0];
        let node_bins = self.bins;
        // Sweep from the right to know the right side of every plane...
        // An empty bin adds no new plane, so only non-empty bins cost work.
        let mut acc = [Bounds3::EMPTY; 3];
        let mut acc_area = [0f32; 3];
        let mut acc_count = [0u32; 3];
        for i in (1..node_bins).rev() {
            for axis in self.axes.clone() {
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
        let mut best: Option<Split> = None;
        let mut left = [Bounds3::EMPTY; 3];
        let mut left_count = [0u32; 3];
        for i in 1..node_bins {
            for axis in self.axes.clone() {
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
                if best.is_none_or(|b| cost < b.cost) {
                    best = Some(Split { axis, plane: i, cost });
                }
            }
        }
        best
    }

    /// Partitions the node's primitives `bounds` (and `order` alike) at
    /// `split` with the binning's own arithmetic, so every primitive lands
    /// on the side its bin is on. The sides' centroid bounds come from the
    /// partition's pass, their bounds from the bins of `scratch` (or, where
    /// only a sample was binned, from that pass too).
    pub(super) fn partition(
        &self,
        split: Split,
        scratch: &Scratch,
        bounds: &mut [Bounds3],
        order: &mut [u32],
    ) -> Sides {
        let Split { axis, plane, .. } = split;
        let part = Partition {
            axis_min: self.binner.cmin[axis],
            axis_scale: self.binner.scale[axis],
            plane: plane as f32,
        };
        if self.sampled {
            return part.run_along::<true>(axis, bounds, order);
        }
        let sides = part.run_along::<false>(axis, bounds, order);
        let bin_grid = &scratch.grids[0];
        let fold = |range: std::ops::Range<usize>| {
            bin_grid[range]
                .iter()
                .fold(Bounds3::EMPTY, |b, bin| b.union(bin[axis].bounds()))
        };
        Sides {
            bounds: [fold(0..plane), fold(plane..self.bins)],
            ..sides
        }
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

/// A bin with nothing in it.
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

/// Empties the first `n` bins of `grid` along `axes`.
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
    use super::*;
    use crate::accel::tests::random_triangles;
    use crate::sampling::Rng;

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
