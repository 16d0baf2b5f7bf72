#!/usr/bin/env python3
"""lenspath's BVH against Embree (the `embreex` binding from PyPI) on the same
triangles and the same rays, in one run: build time, closest-hit and any-hit
Mrays/s on 1 M coherent camera rays and 1 M incoherent random rays, on one thread
and on all cores; the bytes a triangle each holds; and whether the two agree on
every hit distance.

    python3 bench/peers/bvh_vs_embree.py [--rays 1000000] [--rounds 3] [--repeat 1] [--json out.json]

Makes its virtual environment in bench/.venv-peers (numpy, embreex) the first
time and reruns itself there; builds lenspath with cargo. The meshes are
../shared/meshes/dragon_100k.ply and lucy_100k.obj and the 1 M-triangle
procedural torus knot.

Fairness notes: embreex traces in a Cython loop of rtcIntersect1 / rtcOccluded1
calls, one ray at a time on one thread (its per-ray Python-free overhead is
included; lenspath's timing is of its own loop). That loop holds the GIL, so
Embree's all-cores figure runs one process a core, each with its own copy of the
scene, tracing an equal share of the rays from a common start (wall time until
the last finishes); lenspath's uses its thread pool. Every figure is the best of
`--rounds` runs, for both (each lenspath run a process of its own). Embree's build
uses its default (multi-threaded TBB) builder; lenspath's build is single-threaded.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from common import ROOT, in_venv, machine, read_binary_ply

SHARED = ROOT.parent / "shared" / "meshes"
MESHES = [("dragon_100k", [str(SHARED / "dragon_100k.ply")]), ("lucy_100k", [str(SHARED / "lucy_100k.obj")])]
PROCEDURAL = ("knot_1m", ["--procedural", "1000000"])


def lenspath_bench(binary: Path, mesh_args: list[str], rays: int, threads: int | None, out: Path | None) -> dict:
    command = [str(binary), "bench", "bvh", "--json", "--rays", str(rays)]
    if threads:
        command += ["--threads", str(threads)]
    if out is not None:
        command += ["--save-rays", str(out), "--save-mesh", str(out / "mesh.ply")]
    command += mesh_args
    return json.loads(subprocess.run(command, check=True, capture_output=True, text=True).stdout)


def embree_scene(device, vertices, faces):
    """An Embree scene of the triangles on `device`, built."""
    import numpy as np
    from embreex import rtcore_scene
    from embreex.mesh_construction import TriangleMesh

    scene = rtcore_scene.EmbreeScene(device)
    TriangleMesh(scene, vertices, faces)
    # embreex commits (builds) the scene on its first query.
    scene.run(np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32))
    return scene


def embree_measure(vertices, faces, ray_sets: dict, rounds: int) -> dict:
    from embreex import rtcore

    # One device for every build, made outside the timing (it starts Embree's thread pool).
    device = rtcore.EmbreeDevice()
    builds = []
    for _ in range(rounds):
        started = time.perf_counter()
        scene = embree_scene(device, vertices, faces)
        builds.append(time.perf_counter() - started)
    result = {"build_ms": 1e3 * min(builds)}
    for name, (origins, directions, _) in ray_sets.items():
        for query, key in (("INTERSECT", "closest"), ("OCCLUDED", "any_hit")):
            times = []
            for _ in range(rounds):
                started = time.perf_counter()
                scene.run(origins, directions, query=query)
                times.append(time.perf_counter() - started)
            result[f"{name}_{key}_mrays_s"] = len(origins) / min(times) / 1e6
    result["scene"] = scene
    return result


def embree_memory_bytes(vertices, faces) -> int:
    """Bytes Embree holds for a committed scene of the triangles (its BVH and its own
    copies of the triangles), counted by its memory monitor callback, called through
    ctypes on embreex's bundled libembree4 (embreex does not expose the callback). The
    vertex and index buffers are shared with numpy, so not counted: the caller keeps
    them alive (lenspath's figure is all its traversal needs: its packs hold the corners)."""
    import ctypes
    from pathlib import Path

    import embreex
    import numpy as np

    library = next((Path(embreex.__file__).parent.parent / "embreex.libs").glob("libembree4*.so*"))
    embree = ctypes.CDLL(str(library))
    monitor_type = ctypes.CFUNCTYPE(ctypes.c_bool, ctypes.c_void_p, ctypes.c_ssize_t, ctypes.c_bool)
    held = [0]

    def monitor(_user, change, _post):
        held[0] += change
        return True

    callback = monitor_type(monitor)
    pointer = ctypes.c_void_p
    signatures = {
        "rtcNewDevice": (pointer, [ctypes.c_char_p]),
        "rtcSetDeviceMemoryMonitorFunction": (None, [pointer, monitor_type, pointer]),
        "rtcNewScene": (pointer, [pointer]),
        "rtcNewGeometry": (pointer, [pointer, ctypes.c_int]),
        "rtcSetSharedGeometryBuffer": (
            None,
            [pointer, ctypes.c_int, ctypes.c_uint, ctypes.c_int, pointer] + [ctypes.c_size_t] * 3,
        ),
        "rtcCommitGeometry": (None, [pointer]),
        "rtcAttachGeometry": (ctypes.c_uint, [pointer, pointer]),
        "rtcReleaseGeometry": (None, [pointer]),
        "rtcCommitScene": (None, [pointer]),
        "rtcReleaseScene": (None, [pointer]),
        "rtcReleaseDevice": (None, [pointer]),
    }
    for name, (result, arguments) in signatures.items():
        getattr(embree, name).restype = result
        getattr(embree, name).argtypes = arguments
    # Embree reads vertices with 16-byte loads: one float of padding after the last.
    padded = np.zeros(vertices.size + 1, np.float32)
    padded[: vertices.size] = vertices.ravel()
    indices = np.ascontiguousarray(faces, np.uint32)
    device = embree.rtcNewDevice(None)
    embree.rtcSetDeviceMemoryMonitorFunction(device, callback, None)
    scene = embree.rtcNewScene(device)
    geometry = embree.rtcNewGeometry(device, 0)  # RTC_GEOMETRY_TYPE_TRIANGLE
    # RTC_BUFFER_TYPE_VERTEX with RTC_FORMAT_FLOAT3, RTC_BUFFER_TYPE_INDEX with RTC_FORMAT_UINT3.
    embree.rtcSetSharedGeometryBuffer(geometry, 1, 0, 0x9003, padded.ctypes.data, 0, 12, len(vertices))
    embree.rtcSetSharedGeometryBuffer(geometry, 0, 0, 0x5003, indices.ctypes.data, 0, 12, len(indices))
    embree.rtcCommitGeometry(geometry)
    embree.rtcAttachGeometry(scene, geometry)
    embree.rtcReleaseGeometry(geometry)
    embree.rtcCommitScene(scene)
    bytes_held = held[0]
    embree.rtcReleaseScene(scene)
    embree.rtcReleaseDevice(device)
    return bytes_held


def _embree_share(vertices, faces, origins, directions, barrier, results) -> None:
    """One process's share of an all-cores measurement: build, wait for the others, trace."""
    from embreex import rtcore

    scene = embree_scene(rtcore.EmbreeDevice(), vertices, faces)
    barrier.wait()
    started = time.perf_counter()
    scene.run(origins, directions, query="INTERSECT")
    results.put((started, time.perf_counter()))


def embree_all_cores(vertices, faces, origins, directions, processes: int, rounds: int) -> float:
    """Closest-hit Mrays/s of `processes` single-threaded Embree processes sharing the rays."""
    context = multiprocessing.get_context("fork")
    best = 0.0
    for _ in range(rounds):
        barrier, results = context.Barrier(processes), context.Queue()
        shares = [
            context.Process(target=_embree_share, args=(vertices, faces, o, d, barrier, results))
            for o, d in zip(_split(origins, processes), _split(directions, processes), strict=True)
        ]
        for process in shares:
            process.start()
        spans = [results.get() for _ in shares]
        for process in shares:
            process.join()
        wall = max(end for _, end in spans) - min(start for start, _ in spans)
        best = max(best, len(origins) / wall / 1e6)
    return best


def _split(array, parts: int) -> list:
    import numpy as np

    return [np.ascontiguousarray(a) for a in np.array_split(array, parts)]


def agreement(scene, origins, directions, lenspath_t) -> dict:
    """How often Embree and lenspath agree: both miss, or both hit within 1e-4 relative distance."""
    import numpy as np

    tfar = scene.run(origins, directions, output=1)["tfar"]
    embree_hit = tfar < 1e30
    lenspath_hit = np.isfinite(lenspath_t)
    both = embree_hit & lenspath_hit
    close = np.abs(tfar[both] - lenspath_t[both]) <= 1e-4 * np.maximum(1.0, tfar[both])
    return {
        "hit_mismatch": int((embree_hit != lenspath_hit).sum()),
        "distance_mismatch": int((~close).sum()),
        "agree_fraction": float(((embree_hit == lenspath_hit).sum() - (~close).sum()) / len(tfar)),
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rays", type=int, default=1_000_000)
    parser.add_argument("--rounds", type=int, default=3, help="best of this many timings each")
    parser.add_argument("--json", type=Path, help="also write every figure here")
    parser.add_argument("--meshes", nargs="*", help="only these (dragon_100k, lucy_100k, knot_1m)")
    parser.add_argument(
        "--repeat",
        type=int,
        default=1,
        help="run the whole comparison this many times and end with each ratio's median and range "
        "(the runs' rows go to --json one after another, each with its run number; plot_ratios.py draws their medians)",
    )
    args = parser.parse_args()
    in_venv(["numpy", "embreex"])
    subprocess.run(["cargo", "build", "--profile", "dist", "--quiet"], cwd=ROOT, check=True)
    binary = ROOT / "target" / "dist" / "lenspath"
    meshes = [m for m in [*MESHES, PROCEDURAL] if not args.meshes or m[0] in args.meshes]
    if not SHARED.is_dir():
        print(f"{SHARED} is absent: only the procedural mesh", file=sys.stderr)
        meshes = [m for m in meshes if m is PROCEDURAL]
    cpu = machine()
    print(cpu)
    rows = []
    for run in range(args.repeat):
        if args.repeat > 1:
            print(f"\nrun {run + 1} of {args.repeat}")
        for name, mesh_args in meshes:
            row = compare(binary, name, mesh_args, args)
            row["run"] = run
            row["machine"] = cpu
            rows.append(row)
            print_row(row)
    if args.repeat > 1:
        print_medians(rows)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=2))
    return 0


def compare(binary: Path, name: str, mesh_args: list[str], args: argparse.Namespace) -> dict:
    """One mesh's row: both BVHs built and traced, their figures side by side."""
    import numpy as np

    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        ours = [lenspath_bench(binary, mesh_args, args.rays, 1, out if r == 0 else None) for r in range(args.rounds)]
        # Best of as many runs as Embree's all-cores figure, as for one thread.
        ours_all_runs = [lenspath_bench(binary, mesh_args, args.rays, None, None) for _ in range(args.rounds)]
        ours_all = ours_all_runs[0]
        vertices, faces = read_binary_ply(out / "mesh.ply")
        ray_sets = {}
        for kind in ("coherent", "incoherent"):
            raw = np.fromfile(out / f"{kind}_rays.f32", np.float32).reshape(-1, 6)
            t = np.fromfile(out / f"{kind}_t.f32", np.float32)
            ray_sets[kind] = (np.ascontiguousarray(raw[:, :3]), np.ascontiguousarray(raw[:, 3:]), t)
        embree = embree_measure(vertices, faces, ray_sets, args.rounds)
        for kind, (origins, directions, _) in ray_sets.items():
            embree[f"{kind}_closest_all_cores_mrays_s"] = embree_all_cores(
                vertices, faces, origins, directions, ours_all["threads"], args.rounds
            )
        checks = {k: agreement(embree["scene"], o, d, t) for k, (o, d, t) in ray_sets.items()}

    def best(key: str, runs: list[dict] = ours) -> float:
        return max(r[key] for r in runs)

    row = {
        "mesh": name,
        "triangles": len(faces),
        "vertices": len(vertices),
        "lenspath_build_ms": min(r["build_ms"] for r in ours),
        "embree_build_ms": embree["build_ms"],
        "agreement": checks,
        "lenspath_threads": ours_all["threads"],
        "lenspath_memory_bytes": ours[0]["memory_bytes"],
        "embree_memory_bytes": embree_memory_bytes(vertices, faces),
    }
    for kind in ("coherent", "incoherent"):
        row[f"{kind}_closest"] = (best(f"{kind}_mrays_s"), embree[f"{kind}_closest_mrays_s"])
        row[f"{kind}_any_hit"] = (best(f"{kind}_any_hit_mrays_s"), embree[f"{kind}_any_hit_mrays_s"])
        row[f"{kind}_closest_all_threads"] = (
            best(f"{kind}_mrays_s", ours_all_runs),
            embree[f"{kind}_closest_all_cores_mrays_s"],
        )
    return row


RATIOS = [
    "coherent_closest",
    "incoherent_closest",
    "coherent_any_hit",
    "incoherent_any_hit",
    "coherent_closest_all_threads",
    "incoherent_closest_all_threads",
]


def ratios_by_mesh(rows: list[dict]) -> dict[str, dict[str, list[float]]]:
    """Each mesh's ratios (lenspath's speed over Embree's: "build" and each of
    `RATIOS`), one a row: a run's with --repeat."""
    out: dict[str, dict[str, list[float]]] = {}
    for row in rows:
        ratios = out.setdefault(row["mesh"], {key: [] for key in ["build", *RATIOS]})
        ratios["build"].append(row["embree_build_ms"] / row["lenspath_build_ms"])
        for key in RATIOS:
            ratios[key].append(row[key][0] / row[key][1])
    return out


def print_medians(rows: list[dict]) -> None:
    """Each mesh's ratios over the runs: median and range."""
    import statistics

    runs = 1 + max(row["run"] for row in rows)
    print(f"\nmedians of {runs} runs (lenspath's speed over Embree's; range in brackets)")
    for mesh, by_key in ratios_by_mesh(rows).items():
        print(f"  {mesh}")
        for key, ratios in by_key.items():
            print(f"    {key:<31}{statistics.median(ratios):5.2f}  ({min(ratios):.2f}-{max(ratios):.2f})")


def print_row(row: dict) -> None:
    print(f"\n{row['mesh']} ({row['triangles']:,} triangles)")
    build_ratio = row["embree_build_ms"] / row["lenspath_build_ms"]
    print(
        f"  build            lenspath {row['lenspath_build_ms']:8.1f} ms (1 thread)   "
        f"Embree {row['embree_build_ms']:8.1f} ms (default builder)   lenspath speed {build_ratio:.2f}x Embree's"
    )
    triangles = row["triangles"]
    ours, theirs = row["lenspath_memory_bytes"] / triangles, row["embree_memory_bytes"] / triangles
    buffers = (12 * triangles + 12 * row["vertices"]) / triangles
    print(
        f"  memory           lenspath {ours:6.1f} B/triangle (nodes, packs with the geometry, tags)   "
        f"Embree {theirs:6.1f} B/triangle (BVH and its triangles; the caller's {buffers:.1f} of buffers besides)"
    )
    for key in ("coherent_closest", "incoherent_closest", "coherent_any_hit", "incoherent_any_hit"):
        ours, theirs = row[key]
        print(f"  {key:<19}lenspath {ours:6.2f} Mrays/s   Embree {theirs:6.2f} Mrays/s   ratio {ours / theirs:.2f}")
    for kind in ("coherent", "incoherent"):
        ours, theirs = row[f"{kind}_closest_all_threads"]
        print(
            f"  {kind} closest, {row['lenspath_threads']} cores  lenspath {ours:6.2f} Mrays/s   "
            f"Embree {theirs:6.2f} Mrays/s   ratio {ours / theirs:.2f}"
        )
    for kind, check in row["agreement"].items():
        print(
            f"  agreement ({kind}): {100 * check['agree_fraction']:.4f}% of rays "
            f"({check['hit_mismatch']} hit/miss and {check['distance_mismatch']} distance mismatches)"
        )


if __name__ == "__main__":
    sys.exit(main())
