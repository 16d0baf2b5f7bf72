//! Geometry: indexed triangle meshes and analytic spheres, their ray
//! intersection tests and the surface data a hit yields.

use glam::{Vec2, Vec3, Vec3A, Vec4};

use crate::math::Bounds3;
use crate::ray::Ray;
use crate::spectrum::Emission;

/// Index into [`crate::scene::Scene::materials`].
pub type MaterialId = u32;

/// An indexed triangle mesh in world space.
#[derive(Clone, Debug, Default)]
pub struct TriangleMesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Optional per-vertex shading normals (same length as `positions`).
    pub normals: Option<Vec<Vec3>>,
    /// Optional per-vertex texture coordinates.
    pub uvs: Option<Vec<Vec2>>,
    /// Triangles as vertex-index triples; the front face winds counter-clockwise.
    pub indices: Vec<[u32; 3]>,
    /// Surface material.
    pub material: MaterialId,
    /// Emitted radiance from the front face, making the mesh an area light.
    pub emission: Option<Emission>,
}

impl TriangleMesh {
    /// The corners of every triangle, in index order.
    pub fn triangles(&self) -> impl Iterator<Item = [Vec3; 3]> + '_ {
        (0..self.indices.len()).map(|i| self.triangle(i))
    }

    /// The three corners of triangle `i`.
    #[inline]
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        let [a, b, c] = self.indices[i];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }
}

/// An analytic sphere.
#[derive(Clone, Debug)]
pub struct Sphere {
    /// Centre in world space.
    pub center: Vec3,
    /// Radius (> 0).
    pub radius: f32,
    /// Surface material.
    pub material: MaterialId,
    /// Emitted radiance from the outside, making the sphere an area light.
    pub emission: Option<Emission>,
}

impl Sphere {
    /// World-space bounds.
    pub fn bounds(&self) -> Bounds3 {
        let c = Vec3A::from(self.center);
        Bounds3 {
            min: c - Vec3A::splat(self.radius),
            max: c + Vec3A::splat(self.radius),
        }
    }
}

/// Bounds of a triangle given by its corners.
#[inline]
pub fn triangle_bounds(p: &[Vec3; 3]) -> Bounds3 {
    let a = Vec3A::from(p[0]);
    let b = Vec3A::from(p[1]);
    let c = Vec3A::from(p[2]);
    Bounds3 {
        min: a.min(b).min(c),
        max: a.max(b).max(c),
    }
}

/// Per-ray constants of the watertight triangle test: the axis permutation
/// and shear that map the ray direction onto +z.
#[derive(Clone, Copy, Debug)]
pub struct TriangleRay {
    origin: Vec3,
    kx: usize,
    ky: usize,
    kz: usize,
    shear: Vec3,
}

impl TriangleRay {
    /// Precomputes the permutation and shear for `ray`.
    #[inline]
    pub fn new(ray: &Ray) -> Self {
        let d = ray.direction.to_array();
        let kz = ray.direction.abs().max_position();
        let kx = if kz == 2 { 0 } else { kz + 1 };
        let ky = if kx == 2 { 0 } else { kx + 1 };
        // One division, not three: every triangle sees the same shear, so
        // the test stays watertight.
        let inv_dz = 1.0 / d[kz];
        TriangleRay {
            origin: ray.origin,
            kx,
            ky,
            kz,
            shear: Vec3::new(-d[kx] * inv_dz, -d[ky] * inv_dz, inv_dz),
        }
    }
}

/// Watertight ray–triangle intersection (Woop, Benthin and Wald, "Watertight
/// Ray/Triangle Intersection", JCGT 2013; as in pbrt-v4 `IntersectTriangle`).
/// Returns `(t, b1, b2)` with barycentrics of `p1` and `p2`, for `0 < t < t_max`.
/// Edge functions that round to zero are recomputed in f64, so a ray
/// through a shared edge or vertex hits at least one of the triangles.
#[inline]
pub fn intersect_triangle(r: &TriangleRay, p: &[Vec3; 3], t_max: f32) -> Option<(f32, f32, f32)> {
    let (kx, ky, kz) = (r.kx, r.ky, r.kz);
    // Translate to the ray origin, permute so the ray runs along +z, shear.
    let a = p[0] - r.origin;
    let b = p[1] - r.origin;
    let c = p[2] - r.origin;
    let (az, bz, cz) = (a[kz], b[kz], c[kz]);
    let ax = a[kx] + r.shear.x * az;
    let ay = a[ky] + r.shear.y * az;
    let bx = b[kx] + r.shear.x * bz;
    let by = b[ky] + r.shear.y * bz;
    let cx = c[kx] + r.shear.x * cz;
    let cy = c[ky] + r.shear.y * cz;

    // Scaled barycentric coordinates (2D edge functions).
    let mut u = cx * by - cy * bx;
    let mut v = ax * cy - ay * cx;
    let mut w = bx * ay - by * ax;
    if u == 0.0 || v == 0.0 || w == 0.0 {
        u = (cx as f64 * by as f64 - cy as f64 * bx as f64) as f32;
        v = (ax as f64 * cy as f64 - ay as f64 * cx as f64) as f32;
        w = (bx as f64 * ay as f64 - by as f64 * ax as f64) as f32;
    }
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 {
        return None;
    }
    // Scaled hit distance, compared against the range before dividing.
    let sz = r.shear.z;
    let t_scaled = u * (sz * az) + v * (sz * bz) + w * (sz * cz);
    if det < 0.0 && (t_scaled >= 0.0 || t_scaled < t_max * det) {
        return None;
    }
    if det > 0.0 && (t_scaled <= 0.0 || t_scaled > t_max * det) {
        return None;
    }
    let inv_det = 1.0 / det;
    let t = t_scaled * inv_det;
    if t <= 0.0 || t >= t_max {
        return None;
    }
    Some((t, v * inv_det, w * inv_det))
}

/// What [`intersect_triangles4`] found, one lane a triangle.
#[derive(Clone, Copy, Debug)]
pub struct Triangles4Hit {
    /// Bit `k` set where triangle `k` is hit in `(0, t_max)`.
    pub hit: u32,
    /// Bit `k` set where an edge function of triangle `k` rounded to zero:
    /// the scalar test, with its f64 recomputation, must decide that lane.
    pub redo: u32,
    /// Hit distances (meaningful where `hit`).
    pub t: Vec4,
    /// Barycentrics of the second corners.
    pub b1: Vec4,
    /// Barycentrics of the third corners.
    pub b2: Vec4,
}

/// [`intersect_triangle`] for four triangles at once, corners given side by
/// side (`corners[k][axis]` holds corner `k` of the four triangles). Each
/// lane does the scalar test's IEEE operations in the same order, so a hit
/// has bit for bit the scalar test's distance and barycentrics; lanes whose
/// edge functions round to zero are left to the scalar test (`redo`).
#[inline(always)]
pub fn intersect_triangles4(r: &TriangleRay, corners: &[[Vec4; 3]; 3], t_max: f32) -> Triangles4Hit {
    let (kx, ky, kz) = (r.kx, r.ky, r.kz);
    let o = r.origin;
    let (ox, oy, oz) = (Vec4::splat(o[kx]), Vec4::splat(o[ky]), Vec4::splat(o[kz]));
    let (sx, sy, sz) = (Vec4::splat(r.shear.x), Vec4::splat(r.shear.y), Vec4::splat(r.shear.z));
    // Translate, permute, shear: (x, y, z) of one corner of the four triangles.
    let corner = |k: usize| {
        let z = corners[k][kz] - oz;
        ((corners[k][kx] - ox) + sx * z, (corners[k][ky] - oy) + sy * z, z)
    };
    let (ax, ay, az) = corner(0);
    let (bx, by, bz) = corner(1);
    let (cx, cy, cz) = corner(2);
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    let zero = Vec4::ZERO;
    let redo = u.cmpeq(zero) | v.cmpeq(zero) | w.cmpeq(zero);
    let mut miss = (u.cmplt(zero) | v.cmplt(zero) | w.cmplt(zero)) & (u.cmpgt(zero) | v.cmpgt(zero) | w.cmpgt(zero));
    let det = u + v + w;
    miss |= det.cmpeq(zero);
    let t_scaled = u * (sz * az) + v * (sz * bz) + w * (sz * cz);
    let t_max4 = Vec4::splat(t_max);
    let range = t_max4 * det;
    miss |= det.cmplt(zero) & (t_scaled.cmpge(zero) | t_scaled.cmplt(range));
    miss |= det.cmpgt(zero) & (t_scaled.cmple(zero) | t_scaled.cmpgt(range));
    let inv_det = Vec4::ONE / det;
    let t = t_scaled * inv_det;
    miss |= t.cmple(zero) | t.cmpge(t_max4);
    let redo = redo.bitmask();
    Triangles4Hit {
        hit: !miss.bitmask() & !redo & 0xf,
        redo,
        t,
        b1: v * inv_det,
        b2: w * inv_det,
    }
}

/// What [`intersect_triangles8`] found, one lane a triangle.
#[derive(Clone, Copy, Debug)]
pub struct Triangles8Hit {
    /// Bit `k` set where triangle `k` is hit in `(0, t_max)`.
    pub hit: u32,
    /// Bit `k` set where an edge function of triangle `k` rounded to zero
    /// (see [`Triangles4Hit::redo`]).
    pub redo: u32,
    /// Hit distances (meaningful where `hit`).
    pub t: [f32; 8],
    /// Barycentrics of the second corners.
    pub b1: [f32; 8],
    /// Barycentrics of the third corners.
    pub b2: [f32; 8],
}

/// [`intersect_triangles4`] for eight triangles in one AVX step: those of
/// `low` in lanes 0–3, those of `high` in lanes 4–7. The same IEEE
/// operations in the same order, so each lane is bit for bit the four-wide
/// (and so the scalar) test's. When no lane can be a hit the division is
/// skipped, and `t`, `b1` and `b2` are left zero.
///
/// # Safety
/// The CPU must have AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
pub unsafe fn intersect_triangles8(
    r: &TriangleRay,
    low: &[[Vec4; 3]; 3],
    high: &[[Vec4; 3]; 3],
    t_max: f32,
) -> Triangles8Hit {
    use std::arch::x86_64::*;
    let (kx, ky, kz) = (r.kx, r.ky, r.kz);
    let o = r.origin;
    let (ox, oy, oz) = (_mm256_set1_ps(o[kx]), _mm256_set1_ps(o[ky]), _mm256_set1_ps(o[kz]));
    let (sx, sy, sz) = (
        _mm256_set1_ps(r.shear.x),
        _mm256_set1_ps(r.shear.y),
        _mm256_set1_ps(r.shear.z),
    );
    let lanes = |k: usize, axis: usize| _mm256_set_m128(high[k][axis].into(), low[k][axis].into());
    let (sub, mul, add) = (_mm256_sub_ps, _mm256_mul_ps, _mm256_add_ps);
    // Translate, permute, shear, as `intersect_triangles4`.
    let corner = |k: usize| {
        let z = sub(lanes(k, kz), oz);
        (
            add(sub(lanes(k, kx), ox), mul(sx, z)),
            add(sub(lanes(k, ky), oy), mul(sy, z)),
            z,
        )
    };
    let (ax, ay, az) = corner(0);
    let (bx, by, bz) = corner(1);
    let (cx, cy, cz) = corner(2);
    let u = sub(mul(cx, by), mul(cy, bx));
    let v = sub(mul(ax, cy), mul(ay, cx));
    let w = sub(mul(bx, ay), mul(by, ax));
    let zero = _mm256_setzero_ps();
    let (or, and) = (_mm256_or_ps, _mm256_and_ps);
    let eq = |a, b| _mm256_cmp_ps::<_CMP_EQ_OQ>(a, b);
    let lt = |a, b| _mm256_cmp_ps::<_CMP_LT_OQ>(a, b);
    let le = |a, b| _mm256_cmp_ps::<_CMP_LE_OQ>(a, b);
    let redo = _mm256_movemask_ps(or(or(eq(u, zero), eq(v, zero)), eq(w, zero))) as u32;
    let mut miss = and(
        or(or(lt(u, zero), lt(v, zero)), lt(w, zero)),
        or(or(lt(zero, u), lt(zero, v)), lt(zero, w)),
    );
    let det = add(add(u, v), w);
    miss = or(miss, eq(det, zero));
    let t_scaled = add(add(mul(u, mul(sz, az)), mul(v, mul(sz, bz))), mul(w, mul(sz, cz)));
    let t_max8 = _mm256_set1_ps(t_max);
    let range = mul(t_max8, det);
    miss = or(miss, and(lt(det, zero), or(le(zero, t_scaled), lt(t_scaled, range))));
    miss = or(miss, and(lt(zero, det), or(le(t_scaled, zero), lt(range, t_scaled))));
    let mut found = Triangles8Hit {
        hit: !(_mm256_movemask_ps(miss) as u32) & !redo & 0xff,
        redo,
        t: [0.0; 8],
        b1: [0.0; 8],
        b2: [0.0; 8],
    };
    if found.hit == 0 {
        return found;
    }
    let inv_det = _mm256_div_ps(_mm256_set1_ps(1.0), det);
    let t = mul(t_scaled, inv_det);
    found.hit &= !(_mm256_movemask_ps(or(le(t, zero), le(t_max8, t))) as u32);
    // SAFETY: each array holds eight floats.
    unsafe {
        _mm256_storeu_ps(found.t.as_mut_ptr(), t);
        _mm256_storeu_ps(found.b1.as_mut_ptr(), mul(v, inv_det));
        _mm256_storeu_ps(found.b2.as_mut_ptr(), mul(w, inv_det));
    }
    found
}

/// Ray–sphere intersection: the nearest root in `(0, t_max)`, from outside
/// or inside. Uses the numerically stable form of Hearn and Baker /
/// "Precision Improvements for Ray/Sphere Intersection" (Ray Tracing Gems, ch. 7).
#[inline]
pub fn intersect_sphere(ray: &Ray, center: Vec3, radius: f32, t_max: f32) -> Option<f32> {
    let f = ray.origin - center;
    let a = ray.direction.length_squared();
    let b_half = -f.dot(ray.direction);
    // Discriminant computed from the distance of the centre to the ray line,
    // which keeps precision for small spheres far away.
    let l = f + (b_half / a) * ray.direction;
    let disc = radius * radius - l.length_squared();
    if disc < 0.0 {
        return None;
    }
    let sq = (a * disc).sqrt();
    let c = f.length_squared() - radius * radius;
    let q = if b_half >= 0.0 { b_half + sq } else { b_half - sq };
    let (mut t0, mut t1) = (c / q, q / a);
    if q == 0.0 {
        t0 = 0.0;
        t1 = 0.0;
    }
    if t0 > t1 {
        std::mem::swap(&mut t0, &mut t1);
    }
    if t0 > 0.0 && t0 < t_max {
        Some(t0)
    } else if t1 > 0.0 && t1 < t_max {
        Some(t1)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hits(ray: &Ray, p: &[Vec3; 3]) -> bool {
        intersect_triangle(&TriangleRay::new(ray), p, f32::INFINITY).is_some()
    }

    #[test]
    fn triangle_hit_distance_and_barycentrics() {
        let p = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let ray = Ray::new(Vec3::new(0.25, 0.5, 2.0), Vec3::new(0.0, 0.0, -1.0));
        let (t, b1, b2) = intersect_triangle(&TriangleRay::new(&ray), &p, f32::INFINITY).unwrap();
        assert!((t - 2.0).abs() < 1e-6);
        assert!((b1 - 0.25).abs() < 1e-6 && (b2 - 0.5).abs() < 1e-6);
        // Behind the origin, outside, and beyond t_max: no hit.
        assert!(!hits(
            &Ray::new(Vec3::new(0.25, 0.5, -2.0), Vec3::new(0.0, 0.0, -1.0)),
            &p
        ));
        assert!(!hits(
            &Ray::new(Vec3::new(0.75, 0.5, 2.0), Vec3::new(0.0, 0.0, -1.0)),
            &p
        ));
        assert!(intersect_triangle(&TriangleRay::new(&ray), &p, 1.5).is_none());
    }

    /// Rays aimed exactly at shared edges and vertices of a fan of triangles
    /// must hit at least one triangle: no ray slips through the mesh.
    #[test]
    fn triangle_fan_is_watertight_on_shared_edges_and_vertices() {
        // A fan of 12 triangles around a centre vertex, tilted out of any axis plane.
        let n_tris = 12;
        let centre = Vec3::new(0.1, 0.2, 0.3);
        let tilt = glam::Quat::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 0.2);
        let rim: Vec<Vec3> = (0..n_tris)
            .map(|i| {
                let a = i as f32 / n_tris as f32 * std::f32::consts::TAU;
                centre + tilt * Vec3::new(a.cos() * 1.3, a.sin() * 0.9, 0.0)
            })
            .collect();
        let tris: Vec<[Vec3; 3]> = (0..n_tris).map(|i| [centre, rim[i], rim[(i + 1) % n_tris]]).collect();
        let normal = tilt * Vec3::Z;
        let mut rng = 0x2545F4914F6CDD1Du64;
        let mut next = || {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            (rng >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut missed = 0;
        let mut tested = 0;
        for corner in &rim {
            for k in 0..2000 {
                // Points on the shared edge centre–corner (k == 0: the centre vertex itself).
                let s = if k == 0 { 0.0 } else { next() };
                let target = centre + s * (*corner - centre);
                let dir = (-normal + 0.8 * Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5)).normalize();
                let ray = Ray::new(target - 3.7 * dir, dir);
                tested += 1;
                if !tris.iter().any(|t| hits(&ray, t)) {
                    missed += 1;
                }
            }
        }
        assert_eq!(
            missed, 0,
            "{missed} of {tested} rays through shared edges slipped through"
        );
    }

    /// Four triangles and a ray (with its `t_max`) a case, for the SIMD
    /// kernels: random triangles, grid triangles with rays through their
    /// shared edges and corners, and finite `t_max` that cuts some hits off.
    fn simd_cases() -> Vec<([[Vec3; 3]; 4], Ray, f32)> {
        let mut rng = crate::sampling::Rng::new(11);
        let mut random = || Vec3::new(rng.uniform(), rng.uniform(), rng.uniform());
        let mut cases: Vec<([[Vec3; 3]; 4], Ray, f32)> = Vec::new();
        for i in 0..20_000 {
            let tris = [(); 4].map(|_| {
                let c = random() * 4.0;
                [c + random() - 0.5, c + random() - 0.5, c + random() - 0.5]
            });
            let origin = random() * 6.0 - 1.0;
            let target = tris[i % 4][0] * 0.4 + tris[i % 4][1] * 0.3 + tris[i % 4][2] * 0.3;
            let dir = if i % 3 == 0 { random() - 0.5 } else { target - origin };
            let t_max = if i % 5 == 0 { 2.0 * random().x } else { f32::INFINITY };
            cases.push((tris, Ray::new(origin, dir.normalize()), t_max));
        }
        // Unit-grid triangles: rays aimed at shared edges and corners, where
        // edge functions round to zero.
        let grid = |x: f32, y: f32| {
            [
                Vec3::new(x, y, 0.0),
                Vec3::new(x + 1.0, y, 0.0),
                Vec3::new(x, y + 1.0, 0.0),
            ]
        };
        let quad = [
            grid(0.0, 0.0),
            grid(1.0, 0.0),
            grid(0.0, 1.0),
            [grid(1.0, 1.0)[1], grid(1.0, 1.0)[2], Vec3::new(1.0, 1.0, 0.0)],
        ];
        for i in 0..2_000 {
            let target = Vec3::new((i % 5) as f32 * 0.5, (i / 5 % 5) as f32 * 0.5, 0.0);
            let origin = target + Vec3::new(random().x - 0.5, random().y - 0.5, 1.0 + random().z);
            cases.push((quad, Ray::new(origin, (target - origin).normalize()), f32::INFINITY));
        }
        cases
    }

    /// The SIMD kernel against the scalar test it mirrors: on every lane it
    /// hits where the scalar test hits, with bit-identical distance and
    /// barycentrics, or hands the lane back (`redo`); random triangles,
    /// grid triangles with rays through their shared edges and corners,
    /// and finite `t_max` that cuts some hits off.
    #[test]
    fn four_wide_triangle_test_matches_the_scalar_test() {
        let cases = simd_cases();
        let (mut hits, mut redos) = (0, 0);
        for (tris, ray, t_max) in &cases {
            let r = TriangleRay::new(ray);
            let corners = pack_corners(tris);
            let simd = intersect_triangles4(&r, &corners, *t_max);
            for (lane, tri) in tris.iter().enumerate() {
                let scalar = intersect_triangle(&r, tri, *t_max);
                if simd.redo & (1 << lane) != 0 {
                    redos += 1;
                    continue;
                }
                let got = (simd.hit & (1 << lane) != 0).then(|| (simd.t[lane], simd.b1[lane], simd.b2[lane]));
                let bits = |h: Option<(f32, f32, f32)>| h.map(|(t, b1, b2)| [t.to_bits(), b1.to_bits(), b2.to_bits()]);
                assert_eq!(bits(got), bits(scalar), "lane {lane} of {tris:?} for {ray:?}");
                hits += usize::from(scalar.is_some());
            }
        }
        assert!(
            hits > 10_000 && redos > 100,
            "too few hits ({hits}) or redone lanes ({redos}) to prove much"
        );
    }

    /// Four triangles' corners side by side, as the BVH's packs hold them.
    fn pack_corners(tris: &[[Vec3; 3]; 4]) -> [[Vec4; 3]; 3] {
        [0, 1, 2].map(|k| [0, 1, 2].map(|axis| Vec4::from_array(tris.map(|t| t[k][axis]))))
    }

    /// The eight-wide kernel against the four-wide one, each half of it: the
    /// same hit and redo lanes, and bit for bit the same distances and
    /// barycentrics where a lane is hit. The high half holds the next
    /// case's triangles under this case's ray.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn eight_wide_triangle_test_matches_the_four_wide_one() {
        if !std::is_x86_feature_detected!("avx") {
            eprintln!("skipped: this CPU has no AVX");
            return;
        }
        let cases = simd_cases();
        let mut hits = 0;
        for (case, next) in cases.iter().zip(cases.iter().cycle().skip(1)) {
            let (tris, ray, t_max) = case;
            let r = TriangleRay::new(ray);
            let (low, high) = (pack_corners(tris), pack_corners(&next.0));
            // SAFETY: the CPU has AVX (checked above).
            let wide = unsafe { intersect_triangles8(&r, &low, &high, *t_max) };
            for (half, corners) in [low, high].iter().enumerate() {
                let four = intersect_triangles4(&r, corners, *t_max);
                assert_eq!((wide.hit >> (4 * half)) & 0xf, four.hit, "hits of {case:?}");
                assert_eq!((wide.redo >> (4 * half)) & 0xf, four.redo, "redone lanes of {case:?}");
                for lane in (0..4).filter(|lane| four.hit & (1 << lane) != 0) {
                    let k = 4 * half + lane;
                    let bits = |x: [f32; 3]| x.map(f32::to_bits);
                    assert_eq!(
                        bits([wide.t[k], wide.b1[k], wide.b2[k]]),
                        bits([four.t[lane], four.b1[lane], four.b2[lane]]),
                        "lane {k} of {case:?}"
                    );
                    hits += 1;
                }
            }
        }
        assert!(hits > 10_000, "too few hits ({hits}) to prove much");
    }

    #[test]
    fn sphere_hit_from_outside_and_inside() {
        let c = Vec3::new(1.0, 2.0, 3.0);
        let outside = Ray::new(c + Vec3::new(0.0, 0.0, 5.0), Vec3::new(0.0, 0.0, -1.0));
        assert!((intersect_sphere(&outside, c, 2.0, f32::INFINITY).unwrap() - 3.0).abs() < 1e-5);
        let inside = Ray::new(c + Vec3::new(0.5, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0));
        assert!((intersect_sphere(&inside, c, 2.0, f32::INFINITY).unwrap() - 1.5).abs() < 1e-5);
        let away = Ray::new(c + Vec3::new(0.0, 0.0, 5.0), Vec3::new(0.0, 0.0, 1.0));
        assert!(intersect_sphere(&away, c, 2.0, f32::INFINITY).is_none());
        let grazing_miss = Ray::new(c + Vec3::new(2.001, 0.0, 5.0), Vec3::new(0.0, 0.0, -1.0));
        assert!(intersect_sphere(&grazing_miss, c, 2.0, f32::INFINITY).is_none());
        // A tiny sphere far away is still hit (precision of the discriminant).
        let far = Ray::new(Vec3::new(0.0, 0.0, 1.0e4), Vec3::new(0.0, 0.0, -1.0));
        let t = intersect_sphere(&far, Vec3::ZERO, 1e-2, f32::INFINITY).unwrap();
        assert!((t - (1.0e4 - 1e-2)).abs() < 1e-2);
    }
}
