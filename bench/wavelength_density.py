#!/usr/bin/env python3
"""Which wavelength density leaves the least colour noise: one camera sample's variance of
its linear-sRGB estimate, for densities ∝ ‖(r̄, ḡ, b̄)(λ)‖^a and pbrt-v4's luminance-shaped one.

    target/python-venv/bin/python bench/wavelength_density.py [--powers 0.3 0.5 1] [--spectra 60]

A sample carries four wavelengths, a uniform u and its rotations by ¼, each drawn from the
density by inversion (lenspath's `SampledWavelengths::sample_visible`); the film's estimate of
R, G, B is the mean over the four of S(λ) (r̄, ḡ, b̄)(λ) / p(λ). Its variance over u (a fine
midpoint grid, so exact to plotting precision), summed over the three channels and divided by
the squared length of the true RGB, is printed for D65 white and, as the mean and median,
over random smooth reflectances under D65: spectra of the Jakob–Hanika family (a sigmoid of a
quadratic in λ, the form lenspath's RGB colours take), one to three bounces' products. Every
density has lenspath's floor of 1/1000 of its peak. Reads the CIE tables the renderer embeds
(crates/lenspath/data/cie); the sRGB matrix is IEC 61966-2-1's.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

CIE = Path(__file__).resolve().parents[1] / "crates" / "lenspath" / "data" / "cie"
XYZ_TO_SRGB = np.array(
    [[3.2404542, -1.5371385, -0.4985314], [-0.9692660, 1.8760108, 0.0415560], [0.0556434, -0.2040259, 1.0572252]]
)


def tables():
    """Wavelengths (1 nm, 360–830), (r̄, ḡ, b̄) as linear sRGB, and D65 on the same grid."""
    xyz = np.loadtxt(CIE / "cie1931_2deg_xyz.csv", delimiter=",", skiprows=1)
    d65 = np.loadtxt(CIE / "illuminant_d65.csv", delimiter=",", skiprows=1)
    lam = xyz[:, 0]
    return lam, xyz[:, 1:4] @ XYZ_TO_SRGB.T, np.interp(lam, d65[:, 0], d65[:, 1])


def colour_variance(weights, spectrum, rgb_bar, grid: int = 2048) -> float:
    """One sample's relative variance of the four-wavelength RGB estimate of `spectrum`."""
    weights = weights + 1e-3 * weights.max()
    p = weights / weights.sum()  # probability of each 1 nm bin
    cdf = np.concatenate([[0.0], np.cumsum(p)])
    u = ((np.arange(grid)[:, None] + 0.5) / grid + np.arange(4)[None, :] / 4) % 1.0
    bin_ = np.clip(np.searchsorted(cdf, u, side="right") - 1, 0, len(p) - 1)
    estimates = (spectrum[bin_][..., None] * rgb_bar[bin_] / p[bin_][..., None]).mean(axis=1)
    return float(estimates.var(axis=0).sum() / (estimates.mean(axis=0) ** 2).sum())


def random_spectra(lam, d65, count: int, seed: int = 1):
    """`count` products of one to three random Jakob–Hanika reflectances, times D65."""
    rng = np.random.default_rng(seed)
    x = (lam - lam[0]) / (lam[-1] - lam[0]) - 0.5
    spectra = []
    for k in range(count):
        spectrum = d65.copy()
        for _ in range(1 + k % 3):
            c = rng.normal(0.0, 1.0, 3) * [30.0, 30.0, 4.0]
            z = c[0] * x * x + c[1] * x + c[2]
            spectrum = spectrum * (0.5 + z / (2.0 * np.sqrt(1.0 + z * z)))
        spectra.append(spectrum)
    return spectra


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--powers", type=float, nargs="+", default=[0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 1.0])
    parser.add_argument("--spectra", type=int, default=60)
    args = parser.parse_args()
    lam, rgb_bar, d65 = tables()
    norm = np.linalg.norm(rgb_bar, axis=1)
    densities = {f"‖(r̄, ḡ, b̄)‖^{a:g}": norm**a for a in args.powers}
    densities["pbrt-v4 visible"] = 1.0 / np.cosh(0.0072 * (lam - 538.0)) ** 2
    spectra = random_spectra(lam, d65, args.spectra)
    print(f"{'density':22s} {'D65 white':>10s} {'random mean':>12s} {'random median':>14s}")
    for name, weights in densities.items():
        white = colour_variance(weights, d65, rgb_bar)
        random = np.array([colour_variance(weights, s, rgb_bar) for s in spectra])
        print(f"{name:22s} {white:10.4f} {random.mean():12.4f} {np.median(random):14.4f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
