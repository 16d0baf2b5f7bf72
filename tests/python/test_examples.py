"""The examples run: readme_pictures.py makes what the CLI makes with the same settings, and
guiding_pictures.py makes its pictures."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np

import lenspath

from .conftest import REPO, SHARED


def test_readme_pictures_match_the_clis(cli, tmp_path: Path) -> None:
    out = tmp_path / "docs"
    args = ["--out-dir", str(out), "--spp", "2", "--sheet-spp", "1", "--resolution", "64", "48"]
    args += ["--shared", str(SHARED)]
    subprocess.run([sys.executable, str(REPO / "examples" / "readme_pictures.py"), *args], check=True)

    theirs = tmp_path / "cli.png"
    subprocess.run(
        [str(cli), "render", "--spp", "2", "--res", "64x48", "--out", str(theirs)], check=True, capture_output=True
    )
    assert (out / "images" / "cornell-spheres.png").read_bytes() == theirs.read_bytes()
    for name in ("dgauss50", "wide22", "tele250", "fisheye10"):
        plot = tmp_path / f"{name}.svg"
        subprocess.run([str(cli), "lens", name, "--plot", str(plot)], check=True, capture_output=True)
        assert (out / "lenses" / f"{name}.svg").read_text() == plot.read_text(), name
    # dgauss50's glasses disperse (its patent's Abbe numbers): its focal shift is drawn too.
    shift = tmp_path / "shift.svg"
    subprocess.run([str(cli), "lens", "dgauss50", "--focal-shift-plot", str(shift)], check=True, capture_output=True)
    assert (out / "lenses" / "dgauss50-focal-shift.svg").read_text() == shift.read_text()
    assert sorted(p.name for p in (out / "lenses").glob("*-focal-shift.svg")) == ["dgauss50-focal-shift.svg"]
    sheet = out / "images" / "cs184-contact-sheet.png"
    assert sheet.is_file() == (SHARED / "scenes" / "cs184").is_dir()
    if sheet.is_file():
        tiles = len(list((SHARED / "scenes" / "cs184").glob("*/*.dae")))
        rows = (tiles + 5) // 6
        assert lenspath.read(sheet).shape == (rows * (144 + 16), 6 * 192, 3)


def test_guiding_pictures_compare_the_integrators_and_map_the_guide(cli, tmp_path: Path) -> None:
    args = ["--lenspath", str(cli), "--out-dir", str(tmp_path), "--res", "64x48", "--seconds", "0.3"]
    run = subprocess.run(
        [sys.executable, str(REPO / "examples" / "guiding_pictures.py"), *args],
        capture_output=True,
        text=True,
    )
    assert run.returncode == 0, run.stderr
    for scene in ("glass-and-gold", "caustics"):
        # The path tracer's image, the guided one's and their difference, 4 pixels apart.
        assert lenspath.read(tmp_path / f"guiding-{scene}.png").shape == (48, 3 * 64 + 2 * 4, 3)
        assert f"{scene}: guided" in run.stdout
    maps = lenspath.read(tmp_path / "guiding-maps.png")
    assert maps.shape == (256, 3 * 256 + 2 * 4, 3)
    # Each map's centre (the direction along the normal) is inside its disc: not the grey outside.
    centres = maps[128, [128, 128 + 260, 128 + 520]]
    grey = lenspath.read(tmp_path / "guiding-maps.png")[0, 0]
    assert not np.any(np.all(np.isclose(centres, grey), axis=1))
