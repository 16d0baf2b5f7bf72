//! `lenspath bench bvh`: BVH build time and traversal throughput on a mesh.
//! Loading the mesh and generating rays are not timed.

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;
use glam::Vec3;
use lenspath::accel::{Bvh, BvhSettings, PrimGeometry};
use lenspath::builtin::torus_knot;
use lenspath::fs::write_bytes;
use lenspath::io::load_mesh;
use lenspath::io::ply::write_ply;
use lenspath::ray::Ray;
use lenspath::raysets::{coherent_rays, incoherent_rays};
use lenspath::{Error, Result};
use rayon::prelude::*;

use crate::Outcome;

/// Options of `lenspath bench bvh`.
#[derive(Args, Debug)]
pub struct BvhArgs {
    /// Mesh file (.ply or .obj).
    #[arg(required_unless_present = "procedural", conflicts_with = "procedural")]
    mesh: Option<PathBuf>,
    /// Use the procedural torus-knot mesh with about N triangles instead.
    #[arg(long, value_name = "N")]
    procedural: Option<usize>,
    /// Rays per traversal measurement.
    #[arg(long, default_value_t = 1_000_000)]
    rays: usize,
    /// Threads for the build and the traversal measurements (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// SAH bins per axis.
    #[arg(long, default_value_t = BvhSettings::default().bins)]
    bins: usize,
    /// Nodes with fewer primitives bin only their longest axis.
    #[arg(long, value_name = "N", default_value_t = BvhSettings::default().all_axes_min_primitives)]
    all_axes_below: usize,
    /// SAH cost of one primitive test relative to one node visit.
    #[arg(long, value_name = "C", default_value_t = BvhSettings::default().intersection_cost)]
    intersection_cost: f32,
    /// Also write the benchmarked mesh as binary PLY (to run other BVH builders on the same triangles).
    #[arg(long, value_name = "FILE")]
    save_mesh: Option<PathBuf>,
    /// Also write the ray sets and lenspath's closest-hit distances into this folder, as raw
    /// little-endian float32 (to run other tracers on the same rays and compare): `coherent_rays.f32`
    /// and `incoherent_rays.f32` (N x 6: origin, direction), `coherent_t.f32` and `incoherent_t.f32`
    /// (N; inf where nothing is hit).
    #[arg(long, value_name = "DIR")]
    save_rays: Option<PathBuf>,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    json: bool,
}

/// Millions of any-hit (shadow) rays per second, and the count of blocked rays.
fn trace_any<T: Copy + Send + Sync>(bvh: &Bvh<T>, rays: &[Ray], pool: &rayon::ThreadPool) -> (f64, usize) {
    let started = Instant::now();
    let blocked = pool.install(|| {
        rays.par_chunks(4096)
            .map(|chunk| chunk.iter().filter(|r| bvh.intersect_any(r, f32::INFINITY)).count())
            .sum()
    });
    (rays.len() as f64 / started.elapsed().as_secs_f64() / 1e6, blocked)
}

/// Writes `rays` (origin, direction) and their closest-hit distances under `dir` as `NAME_rays.f32` and `NAME_t.f32`.
fn save_rays<T: Copy + Send + Sync>(bvh: &Bvh<T>, rays: &[Ray], dir: &Path, name: &str) -> Result<()> {
    let rays_f32: Vec<f32> = rays
        .iter()
        .flat_map(|r| r.origin.to_array().into_iter().chain(r.direction.to_array()))
        .collect();
    let t: Vec<f32> = rays
        .par_iter()
        .map(|r| bvh.intersect(r, f32::INFINITY).map_or(f32::INFINITY, |h| h.t))
        .collect();
    let bytes = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    write_bytes(&dir.join(format!("{name}_rays.f32")), &bytes(&rays_f32))?;
    write_bytes(&dir.join(format!("{name}_t.f32")), &bytes(&t))
}

/// Millions of closest-hit rays per second, and the hit count.
fn trace<T: Copy + Send + Sync>(bvh: &Bvh<T>, rays: &[Ray], pool: &rayon::ThreadPool) -> (f64, usize) {
    let started = Instant::now();
    let hits = pool.install(|| {
        rays.par_chunks(4096)
            .map(|chunk| {
                chunk
                    .iter()
                    .filter(|r| bvh.intersect(r, f32::INFINITY).is_some())
                    .count()
            })
            .sum()
    });
    (rays.len() as f64 / started.elapsed().as_secs_f64() / 1e6, hits)
}

/// Runs `lenspath bench bvh`.
pub fn run_bvh(args: BvhArgs) -> Result<Outcome> {
    if args.rays == 0 {
        return Err(Error::InvalidArgument("--rays must be positive".into()));
    }
    if args.threads == Some(0) {
        return Err(Error::InvalidArgument("--threads must be at least 1".into()));
    }
    if !(2..=256).contains(&args.bins) {
        return Err(Error::InvalidArgument(format!(
            "--bins must be in 2..=256, got {}",
            args.bins
        )));
    }
    if !(args.intersection_cost.is_finite() && args.intersection_cost > 0.0) {
        return Err(Error::InvalidArgument(format!(
            "--intersection-cost must be positive, got {}",
            args.intersection_cost
        )));
    }
    let (name, mesh) = match (&args.mesh, args.procedural) {
        (Some(path), _) => (path.display().to_string(), load_mesh(path)?),
        (None, Some(n)) => (format!("procedural torus knot ({n})"), torus_knot(n)?),
        (None, None) => unreachable!("clap requires one of them"),
    };
    if let Some(path) = &args.save_mesh {
        write_ply(path, &mesh)?;
    }
    let prims: Vec<_> = mesh
        .triangles()
        .enumerate()
        .map(|(i, t)| (PrimGeometry::Triangle(t), i as u32))
        .collect();
    let settings = BvhSettings {
        bins: args.bins,
        all_axes_min_primitives: args.all_axes_below,
        intersection_cost: args.intersection_cost,
        ..Default::default()
    };
    // Built on the threads the rays are traced on.
    let pool = lenspath::parallel::worker_pool(args.threads)?;
    let bvh = pool.install(|| Bvh::build(prims, &settings));
    let stats = *bvh.stats();
    let bounds = bvh.bounds();
    let (lo, hi) = (Vec3::from(bounds.min), Vec3::from(bounds.max));
    let coherent = coherent_rays(lo, hi, args.rays);
    let incoherent = incoherent_rays(lo, hi, args.rays);
    let (coherent_mrays, coherent_hits) = trace(&bvh, &coherent, &pool);
    let (incoherent_mrays, incoherent_hits) = trace(&bvh, &incoherent, &pool);
    let (coherent_any_mrays, _) = trace_any(&bvh, &coherent, &pool);
    let (incoherent_any_mrays, incoherent_blocked) = trace_any(&bvh, &incoherent, &pool);
    debug_assert_eq!(incoherent_blocked, incoherent_hits);
    let threads = pool.current_num_threads();
    if let Some(dir) = &args.save_rays {
        std::fs::create_dir_all(dir).map_err(|e| Error::Io {
            path: dir.clone(),
            source: e,
        })?;
        save_rays(&bvh, &coherent, dir, "coherent")?;
        save_rays(&bvh, &incoherent, dir, "incoherent")?;
    }

    if args.json {
        let json = serde_json::json!({
            "mesh": name,
            "triangles": mesh.indices.len(),
            "build_ms": stats.build_ms,
            "build_mtris_s": mesh.indices.len() as f64 / stats.build_ms / 1e3,
            "nodes": stats.nodes,
            "leaves": stats.leaves,
            "max_depth": stats.max_depth,
            "sah_cost": stats.sah_cost,
            "memory_bytes": stats.memory_bytes,
            "threads": threads,
            "rays": args.rays,
            "coherent_mrays_s": coherent_mrays,
            "coherent_hit_fraction": coherent_hits as f64 / args.rays as f64,
            "incoherent_mrays_s": incoherent_mrays,
            "incoherent_hit_fraction": incoherent_hits as f64 / args.rays as f64,
            "coherent_any_hit_mrays_s": coherent_any_mrays,
            "incoherent_any_hit_mrays_s": incoherent_any_mrays,
        });
        println!("{json}");
    } else {
        println!("mesh                {name}");
        println!("triangles           {}", mesh.indices.len());
        println!(
            "build               {:.1} ms ({:.2} M triangles/s, 1 thread)",
            stats.build_ms,
            mesh.indices.len() as f64 / stats.build_ms / 1e3
        );
        println!(
            "tree                {} nodes, {} leaves, depth {}, SAH cost {:.2}",
            stats.nodes, stats.leaves, stats.max_depth, stats.sah_cost
        );
        println!(
            "memory              {:.1} MB ({:.1} bytes a triangle: wide nodes, packs with the geometry, tags)",
            stats.memory_bytes as f64 / 1e6,
            stats.memory_bytes as f64 / mesh.indices.len() as f64
        );
        println!(
            "coherent rays       {coherent_mrays:.2} M rays/s on {threads} threads ({:.0}% hit)",
            100.0 * coherent_hits as f64 / args.rays as f64
        );
        println!(
            "incoherent rays     {incoherent_mrays:.2} M rays/s on {threads} threads ({:.0}% hit)",
            100.0 * incoherent_hits as f64 / args.rays as f64
        );
        println!(
            "any-hit rays        {coherent_any_mrays:.2} (coherent), {incoherent_any_mrays:.2} (incoherent) M rays/s"
        );
    }
    Ok(Outcome::Done)
}
