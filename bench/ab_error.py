#!/usr/bin/env python3
"""Two lenspath builds, interleaved: the error each leaves at equal samples, the time it takes, and
the product of the two (error at equal time: lower is better), for a change to the sampling.

    target/python-venv/bin/python bench/ab_error.py OLD_BINARY NEW_BINARY SCENE
        [--res 240x180] [--spp 16 64 256] [--seeds 3] [--ref-spp 8192] [-- EXTRA RENDER ARGS]

Each build renders SCENE (a built-in name or a file) through a pinhole camera at max depth 16,
`--seeds` seeds at each sample count, the two builds taking turns so that the machine's load
falls on both alike; MSE over every pixel and channel against a converged reference, rendered
once by OLD_BINARY with `--ref-spp` samples and another seed and kept in target/bench-references
(both builds must be unbiased: a change that moves the mean shows as error neither can lose).
Times are each render's own (lenspath's "rendered ... in T s"), medians over the seeds.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

import lenspath

ROOT = Path(__file__).resolve().parents[1]


def render(binary: str, scene: str, res: str, spp: int, seed: int, extra: list[str], out: Path) -> float:
    """Renders to `out`; returns the render's own time in seconds."""
    command = [binary, "render", scene, "--camera", "pinhole", "--res", res, "--spp", str(spp)]
    command += ["--max-depth", "16", "--seed", str(seed), "--out", str(out), *extra]
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode:
        sys.exit(f"{' '.join(command)}: {done.stderr.strip()}")
    return float(re.search(r"rendered .* in ([0-9.]+) s", done.stderr + done.stdout).group(1))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("old")
    parser.add_argument("new")
    parser.add_argument("scene")
    parser.add_argument("--res", default="240x180")
    parser.add_argument("--spp", type=int, nargs="+", default=[16, 64, 256])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--ref-spp", type=int, default=8192)
    argv = sys.argv[1:]
    split = argv.index("--") if "--" in argv else len(argv)
    args = parser.parse_args(argv[:split])
    args.extra = argv[split + 1 :]
    references = ROOT / "target" / "bench-references"
    references.mkdir(parents=True, exist_ok=True)
    name = Path(args.scene).stem
    extra = re.sub(r"[^A-Za-z0-9.=-]+", "_", "_".join(args.extra))  # a file name, whatever the arguments
    reference = references / f"ab-{name}-{args.res}-{args.ref_spp}spp-{extra}.exr"
    if not reference.exists():
        seconds = render(args.old, args.scene, args.res, args.ref_spp, 1_000_003, args.extra, reference)
        print(f"reference: {args.ref_spp} spp in {seconds:.0f} s", flush=True)
    converged = lenspath.read(reference)[..., :3]
    print(f"{name} {args.res}: MSE and seconds, old | new | new / old (error, time, error x time)")
    with tempfile.TemporaryDirectory() as folder:
        for spp in args.spp:
            figures = {"old": ([], []), "new": ([], [])}
            for seed in range(1, args.seeds + 1):
                for build, binary in (("old", args.old), ("new", args.new)):
                    out = Path(folder) / f"{build}.exr"
                    seconds = render(binary, args.scene, args.res, spp, seed, args.extra, out)
                    figures[build][0].append(float(np.mean((lenspath.read(out)[..., :3] - converged) ** 2)))
                    figures[build][1].append(seconds)
            (e_old, t_old), (e_new, t_new) = ((np.mean(e), np.median(t)) for e, t in figures.values())
            print(
                f"  {spp:5d} spp: {e_old:.3e} {t_old:7.3f} s | {e_new:.3e} {t_new:7.3f} s | "
                f"{e_new / e_old:.3f} {t_new / t_old:.3f} {e_new * t_new / (e_old * t_old):.3f}",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
