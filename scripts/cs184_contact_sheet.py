"""Renders every CS184 course scene in ../shared/scenes/cs184 small, through the scene's own
camera (pinhole, the view the course renderer shows), and assembles a labelled contact sheet.

    cargo build --release && python3 scripts/cs184_contact_sheet.py [--spp 128] \
        [--out docs/images/cs184-contact-sheet.png]

Needs Pillow (pip install pillow) and ../shared beside the repository.
"""

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

from PIL import Image, ImageDraw

REPO = Path(__file__).resolve().parent.parent
SHARED = REPO.parent / "shared" / "scenes" / "cs184"
WIDTH, HEIGHT, LABEL = 192, 144, 16


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spp", type=int, default=128)
    parser.add_argument("--out", type=Path, default=REPO / "docs" / "images" / "cs184-contact-sheet.png")
    parser.add_argument("--columns", type=int, default=6)
    args = parser.parse_args()
    if not SHARED.is_dir():
        print(f"{SHARED} not found: ../shared must be beside the repository", file=sys.stderr)
        return 2
    scenes = sorted(SHARED.glob("*/*.dae"))
    binary = REPO / "target" / "release" / "lenspath"
    tiles = []
    with tempfile.TemporaryDirectory() as tmp:
        for scene in scenes:
            out = Path(tmp) / f"{scene.parent.name}-{scene.stem}.png"
            subprocess.run(
                [
                    str(binary),
                    "render",
                    str(scene),
                    "--camera",
                    "pinhole",
                    "--res",
                    f"{WIDTH}x{HEIGHT}",
                    "--spp",
                    str(args.spp),
                    "--out",
                    str(out),
                ],
                check=True,
                stderr=subprocess.DEVNULL,
            )
            tiles.append((f"{scene.parent.name}/{scene.stem}", Image.open(out).convert("RGB")))
    rows = (len(tiles) + args.columns - 1) // args.columns
    sheet = Image.new("RGB", (args.columns * WIDTH, rows * (HEIGHT + LABEL)), "white")
    draw = ImageDraw.Draw(sheet)
    for i, (name, tile) in enumerate(tiles):
        x, y = (i % args.columns) * WIDTH, (i // args.columns) * (HEIGHT + LABEL)
        sheet.paste(tile, (x, y))
        draw.text((x + 3, y + HEIGHT + 2), name.replace("sky_p3-2_sp23", "p3-2"), fill="black")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    tmp_out = args.out.with_suffix(".tmp.png")
    sheet.save(tmp_out)
    tmp_out.replace(args.out)
    print(f"{len(tiles)} scenes -> {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
