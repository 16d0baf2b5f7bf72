"""lenspath.guide_map: what a guided render's guide learned at a point of the image, the same
map as `lenspath render --guide-map`."""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest

import lenspath

from .conftest import REPO

CAUSTICS = str(REPO / "scenes" / "caustics.toml")
FLOOR = (0.5, 0.95)  # a point of caustics.toml's floor, in front of the spheres


def test_a_floor_points_map_holds_the_guides_whole_probability_above_the_floor() -> None:
    m = lenspath.guide_map(CAUSTICS, at=FLOOR, resolution=(48, 36))
    density = m["density_per_sr"]
    assert density.shape == (256, 256) and density.dtype == np.float32
    # Equal areas: each pixel of the disc of radius 2 covers (4/256)² sr.
    assert abs(float(density.sum()) * (4 / 256) ** 2 - 1.0) < 0.03
    assert abs(m["total_probability"] - float(density.sum()) * (4 / 256) ** 2) < 1e-3
    assert m["share_above_surface"] > 0.95
    assert m["pixel"] == (24, 34)
    assert m["leaves"] > 4


def test_the_python_map_is_the_clis(cli: Path, tmp_path: Path) -> None:
    exr = tmp_path / "map.exr"
    flags = ["--res", "48x36", "--spp", "1", "--integrator", "guided", "--out", str(tmp_path / "x.png")]
    subprocess.run(
        [str(cli), "render", CAUSTICS, *flags, "--guide-map", str(exr), "--guide-at", "0.5,0.95"],
        check=True,
        capture_output=True,
    )
    theirs = lenspath.read_exr(exr)["channels"]["Y"]
    ours = lenspath.guide_map(CAUSTICS, at=FLOOR, resolution=(48, 36))["density_per_sr"]
    assert np.array_equal(theirs, ours)


@pytest.mark.parametrize(
    ("scene", "kwargs", "message"),
    [
        ("cornell-spheres", {"at": (0.5, 0.5)}, "guiding is off for cornell-spheres"),
        (CAUSTICS, {"at": (0.3, 0.5)}, r"pixel \(14, 18\) sees glass, a mirror or smooth metal"),
        (CAUSTICS, {"at": (1.5, 0.5)}, "fractions of its width and height"),
        (CAUSTICS, {"at": FLOOR, "size": 2}, "size must be 8 to 4096"),
        (CAUSTICS, {"at": FLOOR, "sampler": "halton"}, "unknown sampler 'halton'"),
    ],
)
def test_bad_requests_raise_with_a_clear_message(scene: str, kwargs: dict[str, object], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        lenspath.guide_map(scene, resolution=(48, 36), **kwargs)  # type: ignore[arg-type]
