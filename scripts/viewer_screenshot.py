"""Makes docs/images/viewer.png, the README's picture of `lenspath view`: the
default scene stopped down a little, autofocused by a click on the nearer
sphere, refined to 64 samples per pixel.

Usage: target/python-venv/bin/python scripts/viewer_screenshot.py
(`cargo build --release --features viewer` and `bash scripts/test.sh`, which makes the venv with Playwright, first.)
"""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

from playwright.sync_api import sync_playwright

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs/images/viewer.png"


def main() -> None:
    viewer = subprocess.Popen(
        [str(ROOT / "target/release/lenspath"), "view", "--port", "0"], stdout=subprocess.PIPE, text=True
    )
    url = re.search(r"http://[\d.]+:\d+/", viewer.stdout.readline()).group(0)
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=shutil.which("chromium"))
            page = browser.new_page(viewport={"width": 1360, "height": 860})
            page.goto(url)
            page.wait_for_function("Number(document.getElementById('frame').dataset.spp) >= 1")
            page.locator("#aperture-kind").select_option("blades")
            page.locator("#aperture-count").fill("7")
            page.locator("#aperture-count").dispatch_event("change")
            box = page.locator("#frame").bounding_box()
            page.locator("#frame").click(position={"x": 0.57 * box["width"], "y": 0.76 * box["height"]})
            page.wait_for_function(
                "document.getElementById('af-result').dataset.sensorMm !== undefined", timeout=60_000
            )
            page.wait_for_function("Number(document.getElementById('frame').dataset.spp) >= 64", timeout=120_000)
            page.screenshot(path=str(OUT))
            browser.close()
    finally:
        viewer.kill()
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
