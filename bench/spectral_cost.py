"""What colour costs, on the default scene at 128x96: time at equal spp, and
mean squared error against each configuration's own converged reference at
equal spp and at equal time.

The two renders of each comparison run side by side, one thread each, each
pinned to its own core and the cores swapped from one pair to the next, so
both see the same load on a shared machine; the time ratio is the median of
the pairs' ratios, given with its spread. The errors are the means over the
seeds (each render is deterministic).

Spectral transport against the RGB renderer it replaced (through dgauss50
with --no-dispersion, so nothing disperses):

    target/python-venv/bin/python bench/spectral_cost.py transport RGB_BINARY SPECTRAL_BINARY

RGB_BINARY is a lenspath built from commit 6b3116f (before spectral transport).

dgauss50's dispersion (its patent's Abbe numbers; each sample's four
wavelengths weighted through the lens, docs/spectral.md) against the same
lens with --no-dispersion (every glass at its d-line index), with one binary:

    target/python-venv/bin/python bench/spectral_cost.py dispersion BINARY"""

from __future__ import annotations

import argparse
import os
import pathlib
import subprocess
import tempfile
import threading
import time

import numpy as np

import lenspath


def image(path: pathlib.Path) -> np.ndarray:
    return np.asarray(lenspath.read(path))[..., :3].astype(np.float64)


class Renderer:
    """One configuration to render: its argv without resolution, spp, seed and output."""

    def __init__(self, command: list[str], res: str, out: pathlib.Path) -> None:
        self.command, self.res, self.out = command, res, out

    def render(self, spp: int, seed: int, name: str, core: int | None) -> tuple[pathlib.Path, float]:
        """Renders on one thread (pinned to `core` when given); returns the image's path and the wall time."""
        path = self.out / f"{name}.exr"
        command = [*self.command, "--res", self.res, "--spp", str(spp)]
        command += ["--threads", "1", "--seed", str(seed), "--out", str(path)]
        pin = None if core is None else (lambda: os.sched_setaffinity(0, {core}))
        start = time.perf_counter()
        subprocess.run(command, check=True, capture_output=True, preexec_fn=pin)
        return path, time.perf_counter() - start


def side_by_side(jobs: list[tuple[Renderer, int, int, str]]) -> list[tuple[pathlib.Path, float]]:
    """Runs the renders (renderer, spp, seed, name) at the same moment, the
    i-th on core i when the machine has that many; returns each one's result."""
    cores = sorted(os.sched_getaffinity(0))
    results: list[tuple[pathlib.Path, float] | None] = [None] * len(jobs)

    def run(i: int) -> None:
        renderer, spp, seed, name = jobs[i]
        core = cores[i] if len(cores) >= len(jobs) else None
        results[i] = renderer.render(spp, seed, name, core)

    threads = [threading.Thread(target=run, args=(i,)) for i in range(len(jobs))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    if any(r is None for r in results):
        raise RuntimeError("a render failed")
    return [r for r in results if r is not None]


def compare(renderers: dict[str, Renderer], reference_spp: int, seeds: int) -> None:
    """Prints, for two renderers, the second's time and error against the first's."""
    a, b = renderers
    references = side_by_side([(r, reference_spp, 7, f"ref-{k}") for k, r in renderers.items()])
    reference = {k: image(path) for k, (path, _) in zip(renderers, references, strict=True)}
    for spp in (64, 256):
        ratios: list[float] = []
        errors: dict[str, list[float]] = {k: [] for k in renderers}
        for seed in range(1, seeds + 1):
            # Alternate which renderer gets the first core.
            order = [a, b] if seed % 2 else [b, a]
            done = side_by_side([(renderers[k], spp, seed, f"{k}-{spp}-{seed}") for k in order])
            result = dict(zip(order, done, strict=True))
            ratios.append(result[b][1] / result[a][1])
            for k, (path, _) in result.items():
                errors[k].append(float(((image(path) - reference[k]) ** 2).mean()))
        r = np.array(ratios)
        e = {k: float(np.mean(v)) for k, v in errors.items()}
        median = float(np.median(r))
        q1, q3 = np.percentile(r, [25, 75])
        print(
            f"{spp} spp, {seeds} pairs: time {b} / {a} median {median:.3f}x "
            f"(quartiles {q1:.3f}-{q3:.3f}, range {r.min():.3f}-{r.max():.3f}); "
            f"MSE {a} {e[a]:.3e}, {b} {e[b]:.3e} ({e[b] / e[a]:.3f}x at equal spp, "
            f"{e[b] * median / e[a]:.3f}x at equal time)"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("mode", choices=["transport", "dispersion"])
    parser.add_argument("binaries", nargs="+")
    parser.add_argument("--res", default="128x96")
    parser.add_argument("--reference-spp", type=int, default=8192)
    parser.add_argument("--seeds", type=int, default=8, help="pairs of renders per spp (default 8)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        out = pathlib.Path(tmp)
        if args.mode == "transport":
            rgb, spectral = args.binaries
            commands = {"rgb": [rgb, "render"], "spectral": [spectral, "render", "--no-dispersion"]}
        else:
            (binary,) = args.binaries
            commands = {"plain": [binary, "render", "--no-dispersion"], "dispersive": [binary, "render"]}
        renderers = {k: Renderer(c, args.res, out) for k, c in commands.items()}
        compare(renderers, args.reference_spp, args.seeds)


if __name__ == "__main__":
    main()
