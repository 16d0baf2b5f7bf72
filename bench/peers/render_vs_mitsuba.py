#!/usr/bin/env python3
"""lenspath's renderer against Mitsuba 3 (PyPI `mitsuba`) on the same scene, in one
run: wall time at equal samples per pixel, and whether the images agree.

    python3 bench/peers/render_vs_mitsuba.py [--res 480 360] [--spp 16] [--max-depth 16]
                                             [--check-spp 1024] [--check-res 120 90]
                                             [--scene cornell-spheres|cornell-dragon] [--spectral]

The scene is lenspath's built-in `cornell-spheres` (white, red and blue diffuse
walls, two diffuse spheres, a one-sided square light under the ceiling), built
here once for each renderer from the same numbers (crates/lenspath/src/builtin.rs),
seen through the same pinhole camera; or, with `--scene cornell-dragon`, the same
box with the Stanford dragon (../shared/meshes/dragon_100k.ply, 100 k triangles,
1.2 units long) on its floor instead of the spheres. Mitsuba renders it with its `path`
integrator in `scalar_rgb` and, when it runs here, `llvm_ad_rgb` (Dr.Jit's LLVM JIT
needs libLLVM 16 or newer: on Debian 12, `apt-get install libllvm19`; the newest
libLLVM found is handed to it through DRJIT_LIBLLVM_PATH unless that is set, and
with 14 or 15 it aborts, "cannot select fminimum"); lenspath on all
threads with one light sample and, like Mitsuba's default, the `independent`
sampler (uniform random numbers; lenspath's default scrambled Sobol is timed too).
Mitsuba's `max_depth` counts the camera segment, so it is lenspath's plus one.
lenspath's transport is always spectral; with `--spectral` Mitsuba renders in
`scalar_spectral` and `llvm_ad_spectral` instead (its RGB colours upsampled by the
same Jakob & Hanika method, emitters times D65, as lenspath does).

Agreement: both rendered with `--check-spp` samples at `--check-res`, averaged
over 6 x 6-pixel blocks (so Monte Carlo noise is well below 1%); the mean absolute
relative difference of the blocks must be under 2% for the two to render the same
scene with unbiased integrators.

Makes its virtual environment in bench/.venv-peers (numpy, mitsuba) on first use
and installs lenspath there with `pip install .` (the `dist` profile's build). The walls are
handed to Mitsuba as OBJ files in a temporary folder, loaded inside the timing.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from common import ROOT, in_venv, machine, read_binary_ply

SHARED = ROOT.parent / "shared"

WHITE, RED, BLUE = (0.73, 0.73, 0.73), (0.63, 0.065, 0.05), (0.08, 0.16, 0.62)
SPHERE_WHITE = (0.75, 0.75, 0.75)
LIGHT = (15.0, 12.5, 9.0)
# Quads counter-clockwise seen from the side they face (into the box; the light faces down).
QUADS = [
    ([(-1, 0, 1), (1, 0, 1), (1, 0, -1), (-1, 0, -1)], WHITE, None),  # floor
    ([(-1, 2, -1), (1, 2, -1), (1, 2, 1), (-1, 2, 1)], WHITE, None),  # ceiling
    ([(-1, 0, -1), (1, 0, -1), (1, 2, -1), (-1, 2, -1)], WHITE, None),  # back
    ([(-1, 0, 1), (-1, 0, -1), (-1, 2, -1), (-1, 2, 1)], RED, None),  # left
    ([(1, 0, -1), (1, 0, 1), (1, 2, 1), (1, 2, -1)], BLUE, None),  # right
    ([(-0.25, 1.98, -0.25), (0.25, 1.98, -0.25), (0.25, 1.98, 0.25), (-0.25, 1.98, 0.25)], WHITE, LIGHT),
]
SPHERES = [((-0.42, 0.33, -0.3), 0.33), ((0.45, 0.33, 0.25), 0.33)]
EYE, TARGET, FOV_Y = (0.0, 1.0, 3.85), (0.0, 0.92, 0.0), 29.0


def dragon():
    """The Stanford dragon (../shared/meshes/dragon_100k.ply) 1.2 units long, on the box's floor
    at its centre: vertices and triangles."""
    vertices, faces = read_binary_ply(SHARED / "meshes" / "dragon_100k.ply")
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    scale = 1.2 / (hi - lo).max()
    centre = (lo + hi) / 2
    placed = (vertices - [centre[0], lo[1], centre[2]]) * scale
    return placed.astype("float32"), faces


@dataclass
class Job:
    """One render: the scene (its extra meshes ready as arrays) and the settings."""

    scene: str
    meshes: list  # (vertices, faces, colour) beside the box's walls
    width: int
    height: int
    spp: int
    max_depth: int

    @property
    def spheres(self):
        return SPHERES if self.scene == "cornell-spheres" else []


def lenspath_scene(job: Job):
    import numpy as np

    import lenspath

    scene = lenspath.Scene()
    materials = {}

    def material(colour):
        if colour not in materials:
            materials[colour] = scene.add_material("diffuse", reflectance=colour)
        return materials[colour]

    for corners, colour, emission in QUADS:
        quad = np.array(corners, np.float32)
        scene.add_mesh(quad, np.array([[0, 1, 2], [0, 2, 3]]), material(colour), emission=emission)
    for vertices, faces, colour in job.meshes:
        scene.add_mesh(vertices, faces, material(colour))
    for center, radius in job.spheres:
        scene.add_sphere(center, radius, material(SPHERE_WHITE))
    scene.look_at(EYE, TARGET, fov_deg=FOV_Y)
    return scene


def write_ply(path: Path, vertices, faces) -> None:
    """A binary PLY of float x y z and uchar-counted int triangles."""
    import numpy as np

    header = (
        f"ply\nformat binary_little_endian 1.0\nelement vertex {len(vertices)}\n"
        "property float x\nproperty float y\nproperty float z\n"
        f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    records = np.empty(len(faces), np.dtype([("n", "u1"), ("i", "<i4", 3)]))
    records["n"], records["i"] = 3, faces
    path.write_bytes(header.encode() + vertices.astype("<f4").tobytes() + records.tobytes())


def mitsuba_scene(mi, folder: Path, job: Job):
    def rgb(c):
        return {"type": "rgb", "value": list(c)}

    def mesh(path: Path, colour, emission=None):
        # Face normals: lenspath shades triangles flat (the arrays carry no normals).
        shape = {"type": path.suffix[1:], "filename": str(path), "face_normals": True}
        shape["bsdf"] = {"type": "diffuse", "reflectance": rgb(colour)}
        if emission:
            shape["emitter"] = {"type": "area", "radiance": rgb(emission)}
        return shape

    shapes = {}
    for k, (corners, colour, emission) in enumerate(QUADS):
        obj = folder / f"quad{k}.obj"
        obj.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in corners) + "f 1 2 3\nf 1 3 4\n")
        shapes[f"quad{k}"] = mesh(obj, colour, emission)
    for k, (vertices, faces, colour) in enumerate(job.meshes):
        ply = folder / f"mesh{k}.ply"
        write_ply(ply, vertices, faces)
        shapes[f"mesh{k}"] = mesh(ply, colour)
    for k, (center, radius) in enumerate(job.spheres):
        shapes[f"sphere{k}"] = {
            "type": "sphere",
            "center": list(center),
            "radius": radius,
            "bsdf": {"type": "diffuse", "reflectance": rgb(SPHERE_WHITE)},
        }
    return mi.load_dict(
        {
            "type": "scene",
            "integrator": {"type": "path", "max_depth": job.max_depth + 1},
            "sensor": {
                "type": "perspective",
                "fov": FOV_Y,
                "fov_axis": "y",
                "to_world": mi.ScalarTransform4f().look_at(origin=EYE, target=TARGET, up=(0, 1, 0)),
                "sampler": {"type": "independent", "sample_count": job.spp},
                "film": {
                    "type": "hdrfilm",
                    "width": job.width,
                    "height": job.height,
                    "rfilter": {"type": "box"},
                    "pixel_format": "rgb",
                },
            },
            **shapes,
        }
    )


def render_lenspath(job: Job, sampler: str = "independent", seed: int = 0):
    import lenspath

    started = time.perf_counter()
    scene = lenspath_scene(job)
    resolution = (job.width, job.height)
    image = lenspath.render(
        scene,
        lenspath.Camera.pinhole(),
        spp=job.spp,
        resolution=resolution,
        max_depth=job.max_depth,
        sampler=sampler,
        seed=seed,
    )
    return image, time.perf_counter() - started


def render_mitsuba(variant: str, job: Job, seed: int = 0):
    import mitsuba as mi
    import numpy as np

    mi.set_variant(variant)
    with tempfile.TemporaryDirectory() as folder:
        started = time.perf_counter()
        scene = mitsuba_scene(mi, Path(folder), job)
        image = np.array(mi.render(scene, spp=job.spp, seed=seed))
    return image[:, :, :3], time.perf_counter() - started


def newest_libllvm() -> str | None:
    """The newest libLLVM shared library in the usual Debian places, if any."""
    found = []
    for folder in [Path("/usr/lib/x86_64-linux-gnu"), *Path("/usr/lib").glob("llvm-*/lib")]:
        for lib in folder.glob("libLLVM-*.so"):
            if match := re.fullmatch(r"libLLVM-(\d+)\.so", lib.name):
                found.append((int(match.group(1)), str(lib)))
    return max(found)[1] if found else None


def variant_runs(variant: str) -> bool:
    """Whether a Mitsuba variant renders here: tried in a child process, since a JIT
    backend that cannot compile (an old libLLVM) aborts the process."""
    probe = f"import mitsuba as mi; mi.set_variant({variant!r}); mi.render(mi.load_dict(mi.cornell_box()), spp=1)"
    return subprocess.run([sys.executable, "-c", probe], capture_output=True).returncode == 0


def block_mard(a, b, block: int = 6) -> float:
    """Mean absolute relative difference of block means (noise averages out in blocks)."""
    h, w = (a.shape[0] // block) * block, (a.shape[1] // block) * block

    def blocks(x):
        return x[:h, :w].reshape(h // block, block, w // block, block, 3).mean(axis=(1, 3))

    ba, bb = blocks(a), blocks(b)
    return float(abs(ba - bb).mean() / ((ba + bb) / 2).mean())


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", choices=["cornell-spheres", "cornell-dragon"], default="cornell-spheres")
    parser.add_argument("--res", type=int, nargs=2, default=(480, 360), metavar=("W", "H"))
    parser.add_argument("--spp", type=int, default=16)
    parser.add_argument("--max-depth", type=int, default=16)
    parser.add_argument("--rounds", type=int, default=3, help="best of this many timings")
    parser.add_argument("--check-spp", type=int, default=1024)
    parser.add_argument("--check-res", type=int, nargs=2, default=(120, 90), metavar=("W", "H"))
    parser.add_argument("--spectral", action="store_true", help="Mitsuba's spectral variants instead of RGB")
    parser.add_argument("--json", type=Path, help="also write the figures here")
    args = parser.parse_args()
    in_venv(["numpy", "mitsuba"], install_lenspath=True)
    colour = "spectral" if args.spectral else "rgb"
    variants = [f"scalar_{colour}"]
    if "DRJIT_LIBLLVM_PATH" not in os.environ and (libllvm := newest_libllvm()):
        os.environ["DRJIT_LIBLLVM_PATH"] = libllvm
    if variant_runs(f"llvm_ad_{colour}"):
        variants.append(f"llvm_ad_{colour}")
    else:
        print(
            f"llvm_ad_{colour} does not run here (it needs libLLVM 16 or newer); scalar_{colour} only",
            file=sys.stderr,
        )
    extra = [(*dragon(), SPHERE_WHITE)] if args.scene == "cornell-dragon" else []
    job = Job(args.scene, extra, *args.res, args.spp, args.max_depth)
    print(
        f"{job.scene}, {job.width}x{job.height}, {job.spp} spp, max depth {job.max_depth} "
        f"(lenspath's; Mitsuba's {job.max_depth + 1}), pinhole"
    )
    cpu = machine()
    print(cpu)
    ours = min(render_lenspath(job)[1] for _ in range(args.rounds))
    sobol = min(render_lenspath(job, "sobol")[1] for _ in range(args.rounds))
    print(f"  lenspath independent  {ours:7.2f} s")
    print(f"  lenspath sobol        {sobol:7.2f} s")
    figures: dict = {
        "scene": job.scene,
        "machine": cpu,
        "lenspath_s": ours,
        "lenspath_sobol_s": sobol,
        "mitsuba_s": {},
        "agreement": {},
    }
    for variant in variants:
        theirs = min(render_mitsuba(variant, job)[1] for _ in range(args.rounds))
        figures["mitsuba_s"][variant] = theirs
        print(
            f"  Mitsuba {variant:<13} {theirs:7.2f} s   lenspath time / Mitsuba's: {ours / theirs:.2f} "
            f"(sobol {sobol / theirs:.2f})"
        )
    check = Job(args.scene, extra, *args.check_res, args.check_spp, args.max_depth)
    reference, _ = render_lenspath(check)
    for variant in variants:
        image, _ = render_mitsuba(variant, check)
        mard = block_mard(reference, image)
        ratio = reference.mean() / image.mean()
        verdict = "agree" if mard < 0.02 else "DISAGREE"
        figures["agreement"][variant] = {"block_mard": mard, "mean_ratio": float(ratio)}
        print(
            f"  agreement with {variant} at {check.width}x{check.height}, {check.spp} spp: "
            f"block MARD {100 * mard:.2f}%, mean ratio {ratio:.4f}: {verdict}"
        )
    if args.json:
        args.json.write_text(json.dumps(figures, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
