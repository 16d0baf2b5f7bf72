"""examples/readme_pictures.py runs, and makes what the CLI makes with the same settings."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import lenspath

from .conftest import REPO, SHARED


def test_readme_pictures_match_the_clis(cli, tmp_path: Path) -> None:
    out = tmp_path / "docs"
    args = ["--out-dir", str(out), "--spp", "2", "--sheet-spp", "1", "--resolution", "64", "48"]
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
