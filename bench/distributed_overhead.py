"""What scale-out and checkpoints cost on one machine, in the same run.

- lenspath.distributed.render on a LocalCluster (as many single-thread worker
  processes as cores, 64-pixel tiles) against lenspath.render with every core:
  the price of tiling, scheduling and the per-worker scene load, with the images
  compared bit for bit.
- `lenspath render --checkpoint --checkpoint-every 1s` against the same render
  without checkpoints: the price of the saves.

Run with the package installed (scripts/test.sh's venv has it and dask):
    target/python-venv/bin/python bench/distributed_overhead.py [--spp 64]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np
from distributed import Client, LocalCluster

import lenspath
from lenspath import distributed

REPO = Path(__file__).resolve().parents[1]
SCENE = REPO / "scenes" / "glass-and-gold.toml"


def timed(run):  # type: ignore[no-untyped-def]
    start = time.perf_counter()
    result = run()
    return result, time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--spp", type=int, default=64)
    parser.add_argument("--cli", default=str(REPO / "target" / "dist" / "lenspath"))
    args = parser.parse_args()
    cores = len(os.sched_getaffinity(0))

    local, local_s = timed(lambda: lenspath.render(SCENE, spp=args.spp))
    with LocalCluster(n_workers=cores, threads_per_worker=1, dashboard_address=":0") as cluster, Client(cluster) as c:
        merged, dask_s = timed(lambda: distributed.render(SCENE, client=c, spp=args.spp, progress=False))
    same = np.array_equal(local, merged)
    print(f"{SCENE.name} 640x480, {args.spp} spp, {cores} cores")
    print(f"  lenspath.render:             {local_s:7.2f} s")
    print(f"  distributed.render (Dask):   {dask_s:7.2f} s   {dask_s / local_s:.2f}x  (images identical: {same})")

    with tempfile.TemporaryDirectory() as tmp:
        base = [args.cli, "render", str(SCENE), "--spp", str(args.spp), "--out", f"{tmp}/a.exr"]
        _, plain_s = timed(lambda: subprocess.run(base, check=True, capture_output=True))
        ckpt = [*base[:-1], f"{tmp}/b.exr", "--checkpoint", f"{tmp}/b.ckpt", "--checkpoint-every", "1s"]
        _, ckpt_s = timed(lambda: subprocess.run(ckpt, check=True, capture_output=True))
        same = Path(f"{tmp}/a.exr").read_bytes() == Path(f"{tmp}/b.exr").read_bytes()
    print(f"  lenspath render:             {plain_s:7.2f} s")
    print(f"  ... --checkpoint-every 1s:   {ckpt_s:7.2f} s   {ckpt_s / plain_s:.2f}x  (EXR identical: {same})")


if __name__ == "__main__":
    main()
