#!/usr/bin/env python3
"""Issue 33's targets against the path tracer it was filed against: an older build's path tracer
and this build's path and guided integrators, at several sample counts and seeds, timed whole.

    target/python-venv/bin/python bench/guiding_against_builds.py OLD_BINARY NEW_BINARY SCENE REF.exr OUT.json
        [--res 320x240] [--spp 16 32 64 128] [--seeds 1 2 3] [--integrators old-path path guided]

Each render is `BINARY render SCENE --res WxH --spp N --seed S --out F` through the scene's own
(realistic) camera, the contenders taking turns; its time is the whole process's, so a guided
render's training counts. Against REF.exr (a converged render of the same scene, another seed):
MSE over every pixel and channel; the share of it in the reference's highlights (luminance above
1, grown by one pixel: the lamp seen in glass and metal, and bright caustics); the wall's MSE (the
image's top third) and its fireflies (bench/guiding.py's measure). Prints equal-time ratios (one
contender's MSE interpolated log-log at another's times) and writes every render's figures to
OUT.json. bench/guiding.py compares the two integrators of one build through the Python package.

The camera → glass or metal → lamp part of the error, which no change at diffuse vertices (a
guide, photons, manifold sampling) can lower, is this script run on the scene with every diffuse
reflectance set to 0 (`--integrators path`, its own reference).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from guiding import WEIGHTS, fireflies, interpolate

import lenspath


def read(path: Path) -> np.ndarray:
    """The RGB channels of an image lenspath wrote."""
    return np.asarray(lenspath.read(path))[..., :3]


def highlights(reference: np.ndarray) -> np.ndarray:
    """The reference's pixels of luminance above 1, grown by one pixel (not across the edges)."""
    bright = np.pad(reference @ WEIGHTS > 1.0, 1)
    return np.lib.stride_tricks.sliding_window_view(bright, (3, 3)).any(axis=(-1, -2))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("old")
    parser.add_argument("new")
    parser.add_argument("scene")
    parser.add_argument("reference", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("--res", default="320x240")
    parser.add_argument("--spp", type=int, nargs="+", default=[16, 32, 64, 128])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--integrators", nargs="+", default=["old-path", "path", "guided"])
    args = parser.parse_args()
    commands = {
        "old-path": [args.old, "render", args.scene],
        "path": [args.new, "render", args.scene, "--integrator", "path"],
        "guided": [args.new, "render", args.scene, "--integrator", "guided"],
    }
    reference = read(args.reference)
    mask = highlights(reference)
    wall = slice(0, reference.shape[0] // 3)
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        out = Path(scratch) / "render.exr"
        for spp in args.spp:
            for seed in args.seeds:
                for name in args.integrators:
                    command = commands[name] + ["--res", args.res, "--spp", str(spp), "--seed", str(seed)]
                    started = time.perf_counter()
                    done = subprocess.run(command + ["--out", str(out)], capture_output=True, text=True)
                    seconds = time.perf_counter() - started
                    if done.returncode:
                        sys.exit(f"{' '.join(command)}: {done.stderr.strip()}")
                    image = read(out)
                    error = ((image - reference) ** 2).mean(-1)
                    row = {
                        "integrator": name,
                        "spp": spp,
                        "seed": seed,
                        "seconds": seconds,
                        "mse": float(error.mean()),
                        "highlight_mse": float(error[mask].sum() / error.size),
                        "wall_mse": float(error[wall].mean()),
                        "fireflies": fireflies(image[wall]),
                        "mean_ratio": float(image.mean() / reference.mean()),
                    }
                    rows.append(row)
                    print(json.dumps(row), flush=True)
    args.out.write_text(json.dumps({"scene": args.scene, "highlight_pixels": int(mask.sum()), "rows": rows}, indent=1))

    def mean(name: str, spp: int, key: str) -> float:
        return float(np.mean([r[key] for r in rows if r["integrator"] == name and r["spp"] == spp]))

    print(f"\n{'integrator':>10} {'spp':>4} {'seconds':>8} {'MSE':>10} {'highlights':>10} {'wall MSE':>10} fireflies")
    for spp in args.spp:
        for name in args.integrators:
            counts = [r["fireflies"] for r in rows if r["integrator"] == name and r["spp"] == spp]
            print(
                f"{name:>10} {spp:>4} {mean(name, spp, 'seconds'):>8.2f} {mean(name, spp, 'mse'):>10.3e} "
                f"{mean(name, spp, 'highlight_mse'):>10.2e} {mean(name, spp, 'wall_mse'):>10.2e} "
                f"{min(counts)}-{max(counts)}"
            )
    for a in args.integrators:
        for b in args.integrators:
            if a == b:
                continue
            times = [mean(a, spp, "seconds") for spp in args.spp]
            errors = [mean(a, spp, "mse") for spp in args.spp]
            ratios = [interpolate(times, errors, mean(b, spp, "seconds")) / mean(b, spp, "mse") for spp in args.spp]
            print(f"{a} MSE / {b} MSE at {b}'s times: " + " ".join(f"{r:.2f}" for r in ratios))
    return 0


if __name__ == "__main__":
    sys.exit(main())
