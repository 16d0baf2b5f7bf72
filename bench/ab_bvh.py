#!/usr/bin/env python3
"""Interleaved A/B of two lenspath builds' BVH traversal: `lenspath bench bvh` on the
dragon, Lucy and the 1 M-triangle knot, one thread, the two builds taking turns (which
goes first alternates by round), and the median and range of NEW's rate over OLD's for
closest and any-hit, coherent and incoherent rays.

    python3 bench/ab_bvh.py OLD_BINARY NEW_BINARY [--rounds 15] [--rays 300000]

The ratios of one round spread by several per cent on a shared machine; the median of
15 rounds settles to about 1%. Without ../shared only the knot is run.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
from pathlib import Path

# The meshes of the Embree comparison (bench/peers/bvh_vs_embree.py), by its names.
sys.path.insert(0, str(Path(__file__).resolve().parent / "peers"))
from bvh_vs_embree import MESHES, PROCEDURAL, SHARED  # noqa: E402

RATES = [
    "incoherent_mrays_s",
    "coherent_mrays_s",
    "incoherent_any_hit_mrays_s",
    "coherent_any_hit_mrays_s",
]


def bench(binary: str, mesh_args: list[str], rays: int) -> dict:
    command = [binary, "bench", "bvh", *mesh_args, "--rays", str(rays), "--threads", "1", "--json"]
    return json.loads(subprocess.run(command, capture_output=True, text=True, check=True).stdout)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("old", help="the baseline lenspath binary")
    parser.add_argument("new", help="the lenspath binary measured against it")
    parser.add_argument("--rounds", type=int, default=15)
    parser.add_argument("--rays", type=int, default=300_000)
    args = parser.parse_args()
    meshes = dict([*MESHES, PROCEDURAL]) if SHARED.is_dir() else dict([PROCEDURAL])
    if not SHARED.is_dir():
        print(f"{SHARED} is absent: only the procedural knot", file=sys.stderr)
    ratios: dict[str, dict[str, list[float]]] = {mesh: {rate: [] for rate in RATES} for mesh in meshes}
    for round_ in range(args.rounds):
        for mesh, mesh_args in meshes.items():
            turns = [("old", args.old), ("new", args.new)]
            if round_ % 2:
                turns.reverse()
            results = {name: bench(binary, mesh_args, args.rays) for name, binary in turns}
            for rate in RATES:
                ratios[mesh][rate].append(results["new"][rate] / results["old"][rate])
        print(f"round {round_ + 1} of {args.rounds}", file=sys.stderr)
    print(f"NEW over OLD, median of {args.rounds} rounds (range)")
    for mesh, by_rate in ratios.items():
        cells = [
            f"{rate.removesuffix('_mrays_s')} {statistics.median(r):.3f} ({min(r):.3f}-{max(r):.3f})"
            for rate, r in by_rate.items()
        ]
        print(f"  {mesh:<12}" + "   ".join(cells))
    return 0


if __name__ == "__main__":
    sys.exit(main())
