#!/usr/bin/env python3
"""Draws the peer comparisons as one bar chart of speed ratios (lenspath's speed over
the peer's; above 1 lenspath is faster) with issue 8's targets marked, from the JSON
files the two benchmarks write:

    python3 bench/peers/bvh_vs_embree.py --json /tmp/bvh.json
    python3 bench/peers/render_vs_mitsuba.py --json /tmp/spheres.json
    python3 bench/peers/render_vs_mitsuba.py --scene cornell-dragon --json /tmp/dragon.json
    python3 bench/peers/plot_ratios.py /tmp/bvh.json /tmp/spheres.json /tmp/dragon.json --out docs/images/peers.svg

Runs in bench/.venv-peers, adding matplotlib to it.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
from pathlib import Path

from bvh_vs_embree import ratios_by_mesh
from common import in_venv

# Issue 8's targets, as lenspath speed / peer speed.
TARGETS = {"coherent closest": 0.7, "incoherent closest": 0.5, "build": 1.0, "render": 1.0}


def bars(paths: list[Path]) -> list[tuple[str, float, float | None]]:
    """(label, ratio, target) for every comparison in the files."""
    out = []
    for path in paths:
        data = json.loads(path.read_text())
        if isinstance(data, list):  # bvh_vs_embree: one row per mesh (and run, with --repeat)
            # The median over the runs: one bar a comparison.
            for mesh, by_key in ratios_by_mesh(data).items():
                out.append((f"{mesh} build", statistics.median(by_key["build"]), TARGETS["build"]))
                for key in ("coherent_closest", "incoherent_closest", "coherent_any_hit", "incoherent_any_hit"):
                    label = key.replace("_", " ")
                    out.append((f"{mesh} {label}", statistics.median(by_key[key]), TARGETS.get(label)))
        else:  # render_vs_mitsuba: one scene
            for variant, seconds in data["mitsuba_s"].items():
                ratio = seconds / data["lenspath_s"]
                out.append((f"{data['scene']} render vs {variant}", ratio, TARGETS["render"]))
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("files", type=Path, nargs="+")
    parser.add_argument("--out", type=Path, default=Path("peers.svg"))
    args = parser.parse_args()
    in_venv(["numpy", "matplotlib"])
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = bars(args.files)
    figure, ax = plt.subplots(figsize=(9, 0.32 * len(rows) + 1.2))
    y = range(len(rows))
    colours = [
        "#7f7f7f" if target is None else "#2ca02c" if ratio >= target else "#d62728" for _, ratio, target in rows
    ]
    ax.barh(list(y), [r for _, r, _ in rows], color=colours)
    for k, (_, _, target) in enumerate(rows):
        if target is not None:
            ax.plot([target, target], [k - 0.4, k + 0.4], color="black", linewidth=2)
    ax.set_yticks(list(y), [label for label, _, _ in rows], fontsize=8)
    ax.invert_yaxis()
    ax.axvline(1.0, color="#888", linestyle="--", linewidth=0.8)
    ax.set_xlabel("lenspath speed / peer speed (black ticks: issue 8's targets; green met, red not, grey none)")
    ax.set_title("lenspath against Embree (BVH, one thread) and Mitsuba 3 (renders, all threads)", fontsize=10)
    figure.tight_layout()
    partial = args.out.with_suffix(".partial" + args.out.suffix)
    figure.savefig(partial)
    partial.replace(args.out)
    print(args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
