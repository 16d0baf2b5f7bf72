"""How soon `lenspath view` shows the first preview of a change, at 480x360.

Starts `target/dist/lenspath view` on a free loopback port, opens the page
in Debian's headless Chromium (Playwright, from the test extras), and makes
changes the way a person does: f-stops and the focus slider (which build the
camera again) and orbits (which move it). For each it records:

- server: from the change request's arrival to the preview sent (checking the
  settings, building or moving the camera, a half-size one-sample render, the
  JPEG): the frame message's `latency_ms`; and to the first full-size frame
  (`full_latency_ms`);
- page: from the control's input event to the preview drawn on the canvas,
  and to the first full-size frame drawn (the browser's clock), which adds the
  request, the WebSocket and decoding.

Usage: target/python-venv/bin/python bench/viewer_latency.py [--changes 30] [--json FILE]
(`cargo build --profile dist --features viewer,x86-64-v3` and `bash scripts/test.sh`, which makes the venv, first.)
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import statistics
import subprocess
from pathlib import Path

from playwright.sync_api import sync_playwright

ROOT = Path(__file__).resolve().parents[1]

#: Changes a setting the way a control does and waits for the frames of the
#: change; returns the page's milliseconds to the preview and to the first full-size frame.
CHANGE_AND_WAIT = """async ([selector, value, orbit]) => {
    const canvas = document.getElementById("frame");
    const before = Number(canvas.dataset.generation);
    const start = performance.now();
    let preview = null;
    const done = new Promise((resolve) => {
        const watch = new MutationObserver(() => {
            if (Number(canvas.dataset.generation) <= before) return;
            preview ??= performance.now() - start;
            if (Number(canvas.dataset.spp) >= 1) { watch.disconnect(); resolve(performance.now() - start); }
        });
        watch.observe(canvas, { attributes: true });
    });
    if (orbit) {
        const box = canvas.getBoundingClientRect();
        const at = (dx) => ({
            clientX: box.left + 200 + dx, clientY: box.top + 150, button: 2, bubbles: true, pointerId: 1,
        });
        canvas.dispatchEvent(new PointerEvent("pointerdown", at(0)));
        canvas.dispatchEvent(new PointerEvent("pointermove", at(Number(value))));
        canvas.dispatchEvent(new PointerEvent("pointerup", at(Number(value))));
    } else {
        const control = document.querySelector(selector);
        control.value = value;
        control.dispatchEvent(new Event("input"));
    }
    const full = await done;
    return [preview, full];
}"""


def summary(values: list[float]) -> dict:
    ordered = sorted(values)
    return {
        "median_ms": statistics.median(ordered),
        "p90_ms": ordered[int(0.9 * (len(ordered) - 1))],
        "max_ms": ordered[-1],
        "n": len(ordered),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--changes", type=int, default=30, help="changes of each kind")
    parser.add_argument("--json", type=Path, help="write the results here")
    args = parser.parse_args()

    binary = ROOT / "target/dist/lenspath"
    viewer = subprocess.Popen([str(binary), "view", "--port", "0"], stdout=subprocess.PIPE, text=True)
    url = re.search(r"http://[\d.]+:\d+/", viewer.stdout.readline()).group(0)
    server_ms: dict[str, dict[str, list[float]]] = {}
    page_ms: dict[str, dict[str, list[float]]] = {}
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=shutil.which("chromium"))
            page = browser.new_page(viewport={"width": 1400, "height": 900})
            latencies: dict[str, list[float]] = {"preview": [], "full": []}

            def on_websocket(ws) -> None:
                def on_frame(payload) -> None:
                    if isinstance(payload, str):
                        message = json.loads(payload)
                        if message.get("type") == "frame":
                            for key, field in [("preview", "latency_ms"), ("full", "full_latency_ms")]:
                                if message.get(field) is not None:
                                    latencies[key].append(message[field])

                ws.on("framereceived", on_frame)

            page.on("websocket", on_websocket)
            page.goto(url)
            page.wait_for_function("Number(document.getElementById('frame').dataset.spp) >= 4")
            state = json.loads(page.evaluate("fetch('/api/state').then(r => r.text())"))
            lo, hi = state["focus_range_mm"]
            fstop_steps = int(page.locator("#fstop").get_attribute("max"))
            kinds = {
                "f-stop": ("#fstop", lambda i: str((3 * i + 3) % (fstop_steps + 1)), False),
                "focus": ("#sensor-depth", lambda i: str(lo + (hi - lo) * ((7 * i) % 20) / 40), False),
                "orbit": ("#frame", lambda i: str(20 if i % 2 else -20), True),
            }
            for i in range(args.changes):
                for kind, (selector, value, orbit) in kinds.items():
                    before = {k: len(v) for k, v in latencies.items()}
                    preview, full = page.evaluate(CHANGE_AND_WAIT, [selector, value(i), orbit])
                    page.wait_for_function("Number(document.getElementById('frame').dataset.spp) >= 2")
                    page_ms.setdefault(kind, {"preview": [], "full": []})
                    page_ms[kind]["preview"].append(preview)
                    page_ms[kind]["full"].append(full)
                    server_ms.setdefault(kind, {"preview": [], "full": []})
                    for k in latencies:
                        server_ms[kind][k].extend(latencies[k][before[k] :])
            browser.close()
    finally:
        viewer.kill()
    results = {
        kind: {
            f"{where} {frame}": summary(times[kind][frame])
            for where, times in [("server", server_ms), ("page", page_ms)]
            for frame in ["preview", "full"]
        }
        for kind in page_ms
    }
    print(f"lenspath view, 480x360, cornell-spheres through dgauss50, {args.changes} changes of each kind")
    print("milliseconds: median / p90 / max")
    columns = ["server preview", "page preview", "server full", "page full"]
    print(f"{'change':8}" + "".join(f"{c:>20}" for c in columns))
    for kind, r in results.items():
        cells = [f"{r[c]['median_ms']:.0f} / {r[c]['p90_ms']:.0f} / {r[c]['max_ms']:.0f}" for c in columns]
        print(f"{kind:8}" + "".join(f"{c:>20}" for c in cells))
    if args.json:
        args.json.write_text(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
