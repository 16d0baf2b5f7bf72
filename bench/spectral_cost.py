"""What colour costs, on the default scene at 128x96: time at equal spp, and
mean squared error against each configuration's own converged reference at
equal spp and at equal time. One thread, interleaved runs, two seeds.

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
import pathlib
import subprocess
import tempfile
import time

import numpy as np

import lenspath


def image(path: pathlib.Path) -> np.ndarray:
    return np.asarray(lenspath.read(path))[..., :3].astype(np.float64)


def compare(commands: dict[str, list[str]], res: str, reference_spp: int, out: pathlib.Path) -> None:
    """Prints, for two render commands (name: argv without spp, seed and
    output), the second's time and error against the first's."""

    def render(kind: str, spp: int, seed: int, name: str) -> tuple[np.ndarray, float]:
        path = out / f"{name}.exr"
        command = [*commands[kind], "--res", res, "--spp", str(spp)]
        command += ["--threads", "1", "--seed", str(seed), "--out", str(path)]
        start = time.perf_counter()
        subprocess.run(command, check=True, capture_output=True)
        return image(path), time.perf_counter() - start

    a, b = commands
    reference = {k: render(k, reference_spp, 7, f"ref-{k}")[0] for k in commands}
    for spp in (64, 256):
        seconds: dict[str, list[float]] = {k: [] for k in commands}
        errors: dict[str, list[float]] = {k: [] for k in commands}
        for seed in (1, 2):
            for kind in commands:
                img, t = render(kind, spp, seed, f"{kind}-{spp}-{seed}")
                seconds[kind].append(t)
                errors[kind].append(float(((img - reference[kind]) ** 2).mean()))
        t = {k: np.mean(v) for k, v in seconds.items()}
        e = {k: np.mean(v) for k, v in errors.items()}
        print(
            f"{spp} spp: time {a} {t[a]:.2f} s, {b} {t[b]:.2f} s ({t[b] / t[a]:.3f}x); "
            f"MSE {a} {e[a]:.3e}, {b} {e[b]:.3e} ({e[b] / e[a]:.3f}x at equal spp, "
            f"{e[b] * t[b] / (e[a] * t[a]):.3f}x at equal time)"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("mode", choices=["transport", "dispersion"])
    parser.add_argument("binaries", nargs="+")
    parser.add_argument("--res", default="128x96")
    parser.add_argument("--reference-spp", type=int, default=8192)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        out = pathlib.Path(tmp)
        if args.mode == "transport":
            rgb, spectral = args.binaries
            commands = {"rgb": [rgb, "render"], "spectral": [spectral, "render", "--no-dispersion"]}
        else:
            (binary,) = args.binaries
            commands = {"plain": [binary, "render", "--no-dispersion"], "dispersive": [binary, "render"]}
        compare(commands, args.res, args.reference_spp, out)


if __name__ == "__main__":
    main()
