"""Makes the README's pictures with the Python package: the default scene through
the 50 mm lens, the four built-in lenses' layouts, and the contact sheet of the
CS184 course scenes. Needs ../shared beside the repository for the contact sheet
only (its scenes/cs184/; without it the sheet is skipped, saying so).

    pip install .[notebook]        # lenspath, with matplotlib for the labels
    python examples/readme_pictures.py [--out-dir docs] [--spp 512] [--sheet-spp 128]
                                       [--shared ../shared]

It writes OUT_DIR/images/cornell-spheres.png (the same image as
`lenspath render --spp 512 --out ...`, bit for bit), OUT_DIR/lenses/NAME.svg (as
`lenspath lens NAME --plot ...`), OUT_DIR/lenses/NAME-focal-shift.svg for a lens that
disperses (as `lenspath lens NAME --focal-shift-plot ...`) and
OUT_DIR/images/cs184-contact-sheet.png.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

import lenspath

REPO = Path(__file__).resolve().parent.parent
TILE = (192, 144)  # contact-sheet tiles, pixels
LABEL_PX = 16


def main_image(out_dir: Path, spp: int, resolution: tuple[int, int] | None) -> Path:
    """The README's first picture: the built-in scene through its own camera (dgauss50)."""
    path = out_dir / "images" / "cornell-spheres.png"
    path.parent.mkdir(parents=True, exist_ok=True)
    lenspath.write(path, lenspath.render("cornell-spheres", spp=spp, resolution=resolution, progress=True))
    return path


# The lenses the README draws: the four built-in tables (the other shipped lenses,
# `lenspath.builtin_lenses()`, are drawn by `lenspath lens NAME --plot`).
README_LENSES = ("dgauss50", "wide22", "tele250", "fisheye10")


def lens_layouts(out_dir: Path) -> list[Path]:
    """The README's lenses' layouts, as SVG, and the chromatic focal shift of those whose
    glasses disperse."""
    folder = out_dir / "lenses"
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for name in README_LENSES:
        lens = lenspath.Lens.builtin(name)
        path = folder / f"{name}.svg"
        path.write_text(lens.plot())
        paths.append(path)
        if lens.chromatic()["longitudinal_color_mm"] != 0.0:
            path = folder / f"{name}-focal-shift.svg"
            path.write_text(lens.focal_shift_plot())
            paths.append(path)
    return paths


def srgb8(linear: np.ndarray) -> np.ndarray:
    """Linear RGB to 8-bit sRGB (IEC 61966-2-1), as lenspath writes PNG."""
    c = np.clip(linear, 0.0, 1.0)
    encoded = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)
    values: np.ndarray = np.round(encoded * 255.0).astype(np.uint8)
    return values


def contact_sheet(out_dir: Path, shared: Path, spp: int, columns: int = 6) -> Path | None:
    """Every CS184 scene in `shared` through its own camera (pinhole, the course renderer's view), labelled."""
    cs184 = shared / "scenes" / "cs184"
    if not cs184.is_dir():
        print(f"skipping the contact sheet: {cs184} is absent (../shared beside the repository)")
        return None
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenes = sorted(cs184.glob("*/*.dae"))
    (w, h), rows = TILE, (len(scenes) + columns - 1) // columns
    sheet = np.full((rows * (h + LABEL_PX), columns * w, 3), 255, np.uint8)
    dpi = 100
    figure = plt.figure(figsize=(sheet.shape[1] / dpi, sheet.shape[0] / dpi), dpi=dpi)
    for i, scene in enumerate(scenes):
        image = lenspath.render(lenspath.load(scene), lenspath.Camera.pinhole(), spp=spp, resolution=TILE)
        x, y = (i % columns) * w, (i // columns) * (h + LABEL_PX)
        sheet[y : y + h, x : x + w] = srgb8(image)
        label = f"{scene.parent.name}/{scene.stem}".replace("sky_p3-2_sp23", "p3-2")
        figure.text((x + 3) / sheet.shape[1], 1 - (y + h + 12) / sheet.shape[0], label, fontsize=7)
    figure.figimage(sheet, origin="upper", zorder=0)
    path = out_dir / "images" / "cs184-contact-sheet.png"
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_suffix(".partial.png")
    figure.savefig(partial, dpi=dpi)
    plt.close(figure)
    partial.replace(path)  # atomically, as lenspath writes
    return path


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out-dir", type=Path, default=REPO / "examples" / "out")
    parser.add_argument("--spp", type=int, default=512, help="samples per pixel of the main picture")
    parser.add_argument("--sheet-spp", type=int, default=128, help="samples per pixel of each contact-sheet tile")
    parser.add_argument("--resolution", type=int, nargs=2, metavar=("W", "H"), help="of the main picture")
    parser.add_argument("--shared", type=Path, default=REPO.parent / "shared", help="the shared assets' folder")
    args = parser.parse_args()
    made = [main_image(args.out_dir, args.spp, tuple(args.resolution) if args.resolution else None)]
    made += lens_layouts(args.out_dir)
    sheet = contact_sheet(args.out_dir, args.shared, args.sheet_spp)
    made += [sheet] if sheet else []
    for path in made:
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
