"""What spectral transport costs against the RGB renderer it replaced, on
the default scene through dgauss50 (nothing disperses): time at equal spp,
and mean squared error against each renderer's own converged reference at
equal spp and at equal time. One thread, interleaved runs, two seeds.

    target/python-venv/bin/python bench/spectral_cost.py RGB_BINARY SPECTRAL_BINARY

RGB_BINARY is a lenspath built from commit 6b3116f (before spectral transport)."""

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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("rgb")
    parser.add_argument("spectral")
    parser.add_argument("--res", default="128x96")
    parser.add_argument("--reference-spp", type=int, default=8192)
    args = parser.parse_args()
    binaries = {"rgb": args.rgb, "spectral": args.spectral}
    with tempfile.TemporaryDirectory() as tmp:
        out = pathlib.Path(tmp)

        def render(kind: str, spp: int, seed: int, name: str) -> tuple[np.ndarray, float]:
            path = out / f"{name}.exr"
            command = [binaries[kind], "render", "--res", args.res, "--spp", str(spp)]
            command += ["--threads", "1", "--seed", str(seed), "--out", str(path)]
            start = time.perf_counter()
            subprocess.run(command, check=True, capture_output=True)
            return image(path), time.perf_counter() - start

        reference = {k: render(k, args.reference_spp, 7, f"ref-{k}")[0] for k in binaries}
        for spp in (64, 256):
            seconds: dict[str, list[float]] = {k: [] for k in binaries}
            errors: dict[str, list[float]] = {k: [] for k in binaries}
            for seed in (1, 2):
                for kind in binaries:
                    img, t = render(kind, spp, seed, f"{kind}-{spp}-{seed}")
                    seconds[kind].append(t)
                    errors[kind].append(float(((img - reference[kind]) ** 2).mean()))
            t = {k: np.mean(v) for k, v in seconds.items()}
            e = {k: np.mean(v) for k, v in errors.items()}
            print(
                f"{spp} spp: time rgb {t['rgb']:.2f} s, spectral {t['spectral']:.2f} s "
                f"({t['spectral'] / t['rgb']:.3f}x); MSE rgb {e['rgb']:.3e}, spectral {e['spectral']:.3e} "
                f"({e['spectral'] / e['rgb']:.3f}x at equal spp, "
                f"{e['spectral'] * t['spectral'] / (e['rgb'] * t['rgb']):.3f}x at equal time)"
            )


if __name__ == "__main__":
    main()
