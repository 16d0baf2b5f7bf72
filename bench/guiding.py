"""Path guiding against the plain path tracer (issue 33): error against a
converged reference as a function of wall time, on the same machine in one run.

    target/python-venv/bin/python bench/guiding.py SCENE REFERENCE.exr [--spp 16 32 64 128] [--seed 1]

SCENE is a scene file (scenes/glass-and-gold.toml, scenes/caustics.toml) or a
built-in scene name; REFERENCE an EXR of it rendered long with the path tracer
at the size to compare at, for example

    lenspath render scenes/glass-and-gold.toml --res 320x240 --spp 2048 --seed 7 --out ref.exr

Both integrators render the scene at each --spp (the guided one trains its
guide first, `defaults()["guide_training_spp"]` samples per pixel, counted in its time) through the
scene's own camera. For each render: the wall time, the mean squared error
against the reference (all pixels; and the top third of the image, the back
wall in both scenes), the fireflies there (pixels over three times the median
of their 5x5 neighbourhood, and over 1e-3), and the mean's ratio to the
reference's. Then the error ratio at equal time: each integrator's MSE is
interpolated (log-log) at the other's times; a ratio above 1 means guiding
has less error in the same time. The reference's own noise is in every MSE:
keep its samples well above the largest --spp (64x or more)."""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

import lenspath

WEIGHTS = np.array([0.2126, 0.7152, 0.0722], dtype=np.float32)


def fireflies(image: np.ndarray) -> int:
    """Pixels over three times the median luminance of their 5x5 neighbourhood."""
    y = image @ WEIGHTS
    padded = np.pad(y, 2, mode="edge")
    windows = np.lib.stride_tricks.sliding_window_view(padded, (5, 5))
    median = np.median(windows, axis=(-1, -2))
    return int(((y > 3 * median) & (y > 1e-3)).sum())


def interpolate(times: list[float], errors: list[float], at: float) -> float:
    """log MSE against log time, linearly between measured points (extrapolated at the ends)."""
    lt, le = np.log(times), np.log(errors)
    if len(lt) == 1:
        return math.exp(le[0])
    i = int(np.clip(np.searchsorted(lt, math.log(at)), 1, len(lt) - 1))
    slope = (le[i] - le[i - 1]) / (lt[i] - lt[i - 1])
    return math.exp(le[i - 1] + slope * (math.log(at) - lt[i - 1]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("scene")
    parser.add_argument("reference")
    parser.add_argument("--spp", type=int, nargs="+", default=[16, 32, 64, 128])
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()

    reference = lenspath.read(args.reference)
    height, width = reference.shape[:2]
    wall = slice(0, height // 3)
    print(f"{args.scene} at {width}x{height}, reference {args.reference} (mean {reference.mean():.5f})")
    header = ["integrator", "spp", "seconds", "MSE", "wall MSE", "fireflies", "mean ratio"]
    print(" ".join(f"{h:>{w}}" for h, w in zip(header, [10, 5, 8, 10, 10, 9, 10], strict=True)))
    curves: dict[str, tuple[list[float], list[float]]] = {}
    for integrator in ["path", "guided"]:
        times, errors = [], []
        for spp in args.spp:
            start = time.perf_counter()
            image = lenspath.render(
                args.scene, spp=spp, resolution=(width, height), seed=args.seed, integrator=integrator
            )
            seconds = time.perf_counter() - start
            mse = float(((image - reference) ** 2).mean())
            wall_mse = float(((image[wall] - reference[wall]) ** 2).mean())
            ratio = float(image.mean() / reference.mean())
            print(
                f"{integrator:>10} {spp:>5} {seconds:>8.2f} {mse:>10.3e} {wall_mse:>10.3e} "
                f"{fireflies(image[wall]):>9} {ratio:>10.4f}"
            )
            times.append(seconds)
            errors.append(mse)
        curves[integrator] = (times, errors)
    (path_t, path_e), (guided_t, guided_e) = curves["path"], curves["guided"]
    print("equal time: path MSE / guided MSE")
    for t, e in zip(guided_t, guided_e, strict=True):
        print(f"  at {t:7.2f} s (guided measured): {interpolate(path_t, path_e, t) / e:.3f}")
    for t, e in zip(path_t, path_e, strict=True):
        print(f"  at {t:7.2f} s (path measured):   {e / interpolate(guided_t, guided_e, t):.3f}")


if __name__ == "__main__":
    main()
