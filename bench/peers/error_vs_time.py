#!/usr/bin/env python3
"""Error at equal time: lenspath against Mitsuba 3 on the same scene, the figure a user
feels (how far from converged the image is after the time they waited).

    python3 bench/peers/error_vs_time.py [--scene cornell-spheres|cornell-dragon] [--res 480 360]
                                         [--max-depth 16] [--budgets 2 8 30] [--ref-spp 8192]
                                         [--runs 1] [--json F] [--plot F.svg]

The scene and both renderers' settings are render_vs_mitsuba.py's (same numbers, pinhole,
all threads, box filter; Mitsuba's `path` integrator in `llvm_ad_rgb`, or `scalar_rgb` where
its JIT cannot run). Each renderer renders at 1, 2, 4, ... samples per pixel until a render
takes longer than the largest budget (`--runs` renders at each count, other seeds: the
median time and the mean error), the three renderers' renders interleaved at each count so
that a slow stretch of a shared machine falls on all of them (`common.interleaved_sweeps`;
before the forty-ninth session each renderer swept alone, one after the other); each render
is timed from scene construction to the finished image (Mitsuba's JIT kernels are compiled
by an untimed render at the same sample count first), and its mean squared error is taken
over every pixel and channel against a converged reference: the mean of the two renderers'
own `--ref-spp` renders (other seeds), so neither is measured against itself; the
reference's own variance adds the same small amount to both renderers' errors. lenspath
renders with its defaults (scrambled Sobol) and with the `independent` sampler, Mitsuba's.
At each budget the error is read off each curve by log-log interpolation, and the ratio
lenspath / Mitsuba printed (below 1: lenspath's image is closer to converged at that
time). `--plot` draws the curves (log-log) as SVG.

Runs in bench/.venv-peers (numpy, mitsuba, matplotlib, and this lenspath by `pip install .`,
the `dist` profile's build), as render_vs_mitsuba.py does.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from common import ROOT, at_time, in_venv, interleaved_sweeps, machine
from render_vs_mitsuba import SPHERE_WHITE, Job, dragon, newest_libllvm, render_lenspath, render_mitsuba, variant_runs

CACHE = ROOT / "target" / "bench-references"


def reference(job: Job, variant: str, ref_spp: int):
    """The mean of lenspath's and Mitsuba's renders at `ref_spp`, cached in target/."""
    import numpy as np

    path = CACHE / f"{job.scene}-{job.width}x{job.height}-d{job.max_depth}-{ref_spp}spp-{variant}.npy"
    if path.exists():
        return np.load(path)
    ref_job = Job(job.scene, job.meshes, job.width, job.height, ref_spp, job.max_depth)
    ours, t_ours = render_lenspath(ref_job, "sobol", seed=1_000_003)
    theirs, t_theirs = render_mitsuba(variant, ref_job, seed=1_000_003)
    print(f"  reference: lenspath {t_ours:.0f} s, Mitsuba {t_theirs:.0f} s at {ref_spp} spp", flush=True)
    image = 0.5 * (ours + theirs)
    CACHE.mkdir(parents=True, exist_ok=True)
    np.save(path, image)
    return image


def measure_with(render, job: Job, reference, warm_up: bool):
    """`interleaved_sweeps`' measure for one renderer: a render at `spp` with the seed of
    `run` (the first run at a count preceded, with `warm_up`, by an untimed render at it),
    its seconds and its mean squared error against `reference`."""
    import numpy as np

    def measure(spp: int, run: int) -> tuple[float, float]:
        at = Job(job.scene, job.meshes, job.width, job.height, spp, job.max_depth)
        if warm_up and run == 0:
            render(at, seed=spp + 7)
        image, seconds = render(at, seed=spp + 100_000 * run)
        return seconds, float(np.mean((image - reference) ** 2))

    return measure


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", choices=["cornell-spheres", "cornell-dragon"], default="cornell-spheres")
    parser.add_argument("--res", type=int, nargs=2, default=(480, 360), metavar=("W", "H"))
    parser.add_argument("--max-depth", type=int, default=16)
    parser.add_argument("--budgets", type=float, nargs="+", default=[2.0, 8.0, 30.0])
    parser.add_argument("--ref-spp", type=int, default=8192)
    parser.add_argument("--runs", type=int, default=1, help="renders at each sample count (median time, mean MSE)")
    parser.add_argument("--json", type=Path, help="also write the curves and ratios here")
    parser.add_argument("--plot", type=Path, help="draw the curves here (SVG)")
    args = parser.parse_args()
    in_venv(["numpy", "mitsuba", "matplotlib"], install_lenspath=True)
    if "DRJIT_LIBLLVM_PATH" not in os.environ and (libllvm := newest_libllvm()):
        os.environ["DRJIT_LIBLLVM_PATH"] = libllvm
    variant = "llvm_ad_rgb" if variant_runs("llvm_ad_rgb") else "scalar_rgb"
    extra = [(*dragon(), SPHERE_WHITE)] if args.scene == "cornell-dragon" else []
    job = Job(args.scene, extra, *args.res, 1, args.max_depth)
    print(f"{job.scene}, {job.width}x{job.height}, max depth {job.max_depth}, pinhole; Mitsuba {variant}")
    cpu = machine()
    print(cpu)
    ref = reference(job, variant, args.ref_spp)
    longest = max(args.budgets)
    measures = {
        name: measure_with(render, job, ref, warm_up)
        for name, render, warm_up in [
            ("lenspath", lambda j, seed: render_lenspath(j, "sobol", seed=seed), False),
            ("lenspath independent", lambda j, seed: render_lenspath(j, "independent", seed=seed), False),
            (f"Mitsuba {variant}", lambda j, seed: render_mitsuba(variant, j, seed=seed), True),
        ]
    }
    curves = interleaved_sweeps(measures, longest, args.runs)
    ratios = {}
    mitsuba = curves[f"Mitsuba {variant}"]
    print("  budget   lenspath / Mitsuba MSE   (independent sampler)")
    for budget in args.budgets:
        theirs = at_time(mitsuba, budget)
        ours, ours_independent = (at_time(curves[n], budget) for n in ("lenspath", "lenspath independent"))
        if None in (theirs, ours, ours_independent):
            print(f"  {budget:6.1f} s  (outside a curve)")
            continue
        ratios[budget] = {"sobol": ours / theirs, "independent": ours_independent / theirs}
        print(f"  {budget:6.1f} s  {ours / theirs:6.3f}                   ({ours_independent / theirs:.3f})")
    if args.json:
        args.json.write_text(
            json.dumps({"scene": job.scene, "variant": variant, "machine": cpu, "curves": curves, "ratios": ratios})
        )
    if args.plot:
        import matplotlib

        matplotlib.use("svg")
        import matplotlib.pyplot as plt

        figure, axes = plt.subplots(figsize=(6, 4))
        for name, rows in curves.items():
            axes.loglog([t for _, t, _ in rows], [e for _, _, e in rows], marker="o", label=name)
        for budget in args.budgets:
            axes.axvline(budget, color="0.85", zorder=0)
        axes.set_xlabel("wall time, s (2 cores)")
        axes.set_ylabel("MSE against the converged image")
        axes.set_title(f"{job.scene} {job.width}x{job.height}, max depth {job.max_depth}")
        axes.legend()
        figure.tight_layout()
        figure.savefig(args.plot, metadata={"Date": None})
    return 0


if __name__ == "__main__":
    sys.exit(main())
