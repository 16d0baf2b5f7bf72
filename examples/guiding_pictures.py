"""Makes docs/guiding.md's pictures with the `lenspath` command: the path tracer against the
guided one at equal time on the two caustic scenes, with their difference, and what the guide
learned at a few points.

    python examples/guiding_pictures.py [--lenspath BIN] [--out-dir docs/images] [--seconds 4]
                                        [--res 320x240]

For each of scenes/glass-and-gold.toml and scenes/caustics.toml it times both integrators at
two sample counts, fits time = a + b * spp to each, renders each at the samples that fit in
--seconds (the guided one's training counted), and writes OUT_DIR/guiding-SCENE.png: the path
tracer's image, the guided one's, and guided minus path (red where the guided image is
brighter, blue where darker, full colour at the 99th percentile of the difference). Then
OUT_DIR/guiding-maps.png: the guide's density (`lenspath render --guide-map`) at the caustic
under glass-and-gold's glass sphere, on its red wall beside the gold sphere, and at caustics'
focused spot, side by side. The times and sample counts are printed, for the captions.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import lenspath

REPO = Path(__file__).resolve().parent.parent
SCENES = ("glass-and-gold", "caustics")
#: Where the maps look, as fractions of the image (x, y from the top left).
MAP_POINTS = (
    ("glass-and-gold", (0.234, 0.825)),  # the caustic under the glass sphere
    ("glass-and-gold", (0.88, 0.35)),  # the red wall right of the gold sphere
    ("caustics", (0.184, 0.708)),  # the glass sphere's focused spot on the floor
)
GAP = 4  # pixels between panels


def render(binary: str, scene: str, res: tuple[int, int], spp: int, integrator: str, out: Path, *extra: str) -> float:
    """Renders `scene` and returns the wall time of the whole command, in seconds."""
    args = [binary, "render", str(REPO / "scenes" / f"{scene}.toml"), "--res", f"{res[0]}x{res[1]}"]
    args += ["--spp", str(spp), "--integrator", integrator, "--out", str(out), *extra]
    start = time.perf_counter()
    run = subprocess.run(args, capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit(f"{' '.join(args)} failed ({run.returncode}):\n{run.stderr}")
    return time.perf_counter() - start


def spp_in(binary: str, scene: str, res: tuple[int, int], integrator: str, seconds: float, work: Path) -> int:
    """The samples per pixel `integrator` renders in `seconds`, from a line through two timings.

    Each timing is the faster of two runs (a loaded machine only ever adds time). When the two
    sample counts time within noise of each other (tiny images), the slope is no measure of the
    cost of a sample: the dearer run's time over its samples bounds it from above instead, which
    keeps the count within what the command accepts."""
    low, high = 4, 16

    def timed(spp: int) -> float:
        return min(render(binary, scene, res, spp, integrator, work / "t.exr") for _ in range(2))

    t_low, t_high = timed(low), timed(high)
    per_spp = (t_high - t_low) / (high - low)
    if per_spp < 0.1 * t_high / high:
        per_spp, overhead = t_high / high, 0.0
    else:
        overhead = t_low - low * per_spp
    return int(np.clip((seconds - overhead) / per_spp, 1, lenspath.MAX_SAMPLES_PER_PIXEL))


def signed(diff: np.ndarray) -> np.ndarray:
    """Guided minus path, luminance, as red (positive) and blue (negative) in linear RGB."""
    y = diff @ np.array([0.2126, 0.7152, 0.0722], dtype=np.float32)
    scale = max(float(np.percentile(np.abs(y), 99)), 1e-6)
    t = np.clip(y / scale, -1.0, 1.0)[..., None]
    red, blue = np.array([1.0, 0.05, 0.02]), np.array([0.02, 0.1, 1.0])
    colour: np.ndarray = np.where(t > 0, t * red, -t * blue).astype(np.float32)
    return colour


def side_by_side(panels: list[np.ndarray]) -> np.ndarray:
    """The panels in a row on white, GAP pixels apart."""
    height = max(p.shape[0] for p in panels)
    width = sum(p.shape[1] for p in panels) + GAP * (len(panels) - 1)
    sheet = np.ones((height, width, 3), dtype=np.float32)
    x = 0
    for p in panels:
        sheet[: p.shape[0], x : x + p.shape[1]] = p
        x += p.shape[1] + GAP
    return sheet


def comparison(binary: str, scene: str, res: tuple[int, int], seconds: float, out_dir: Path, work: Path) -> Path:
    """The path tracer and the guided one at equal time on `scene`, and their difference."""
    images = {}
    for integrator in ("path", "guided"):
        spp = spp_in(binary, scene, res, integrator, seconds, work)
        exr = work / f"{scene}-{integrator}.exr"
        took = render(binary, scene, res, spp, integrator, exr)
        print(f"{scene}: {integrator} {spp} spp in {took:.2f} s")
        images[integrator] = lenspath.read(exr)
    path, guided = images["path"], images["guided"]
    out = out_dir / f"guiding-{scene}.png"
    lenspath.write(out, side_by_side([path, guided, signed(guided - path)]))
    return out


def guide_maps(binary: str, res: tuple[int, int], out_dir: Path, work: Path) -> Path:
    """The guide's density at each of MAP_POINTS, side by side."""
    maps = []
    for i, (scene, (fx, fy)) in enumerate(MAP_POINTS):
        point = f"{fx},{fy}"
        png = work / f"map{i}.png"
        render(binary, scene, res, 1, "guided", work / "t.exr", "--guide-map", str(png), "--guide-at", point)
        maps.append(lenspath.read(png))
        print(f"{scene}: guide map at {point} of the image")
    out = out_dir / "guiding-maps.png"
    lenspath.write(out, side_by_side(maps))
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--lenspath", default=shutil.which("lenspath") or str(REPO / "target/release/lenspath"))
    parser.add_argument("--out-dir", type=Path, default=REPO / "docs" / "images")
    parser.add_argument("--seconds", type=float, default=4.0, help="each render's time budget")
    parser.add_argument("--res", default="320x240", help="WIDTHxHEIGHT")
    args = parser.parse_args()
    width, height = (int(v) for v in args.res.split("x"))
    res = (width, height)
    args.out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        for scene in SCENES:
            print(comparison(args.lenspath, scene, res, args.seconds, args.out_dir, work))
        print(guide_maps(args.lenspath, res, args.out_dir, work))
    return 0


if __name__ == "__main__":
    sys.exit(main())
