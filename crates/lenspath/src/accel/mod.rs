//! The bounding volume hierarchy: a binned SAH binary tree (built in
//! parallel, in [`build`]) collapsed to 8 children a node with leaves of up
//! to 8 primitives in packs of four triangles ([`layout`]), and closest-hit
//! / any-hit traversal of the wide tree ([`traversal`]: one SIMD slab test
//! for eight boxes, [`node_test`], AVX2 where the CPU has it; one SIMD
//! watertight test for four triangles), checked against the binary tree's;
//! shadow rays from one point as a packet ([`packet`]).

use std::time::Instant;

use rayon::prelude::*;

use crate::math::Bounds3;

mod binning;
mod build;
mod collapse;
mod layout;
mod node_test;
mod packet;
mod partition;
mod primitive;
mod settings;
mod traversal;
use layout::{LeafPack, WideNode, PACK};
pub use packet::SHADOW_PACKET;
pub use primitive::{Hit, PrimGeometry};
pub use settings::{BuildStats, BvhSettings};

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
        let collapse::WideTree {
            wide,
            packs,
            pack_ranges,
        } = collapse::collapse(&tree.nodes, &prims, &tree.order);
        #[cfg(test)]
        let slot_of = collapse::slots_in_binary_order(&pack_ranges, n);
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ray::Ray;
    use crate::sampling::Rng;
    use crate::shapes::{intersect_sphere, intersect_triangle, TriangleRay};
    use glam::Vec3;

    pub(in crate::accel) fn random_triangles(n: usize, rng: &mut Rng) -> Vec<(PrimGeometry, u32)> {
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
    pub(in crate::accel) fn room_walls(first_tag: u32) -> Vec<(PrimGeometry, u32)> {
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
