"""`lenspath view` end to end, in a real headless browser (Debian's Chromium,
driven by Playwright): the page shows frames, the f-stop changes the image
and changing it back gives the same pixels, a click autofocuses where `lenspath
autofocus` does, the saved settings render the saved image bit for bit,
orbit and zoom move the camera, a dropped lens table is offered, bad input
is an error on the page and never stops the server, and rendering stops when
no page is open."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

import lenspath

from .conftest import REPO

playwright_api = pytest.importorskip(
    "playwright.sync_api", reason="Playwright is in the test extras: pip install '.[test]'"
)

#: Small enough that every step is quick on two cores.
RESOLUTION = (240, 180)
#: The nearer sphere of cornell-spheres (the README's patch).
NEAR_SPHERE_CENTRE = (0.57, 0.76)


def find_chromium() -> str:
    """Debian's Chromium (scripts/test.sh installs it where it can), else skip; in CI it must be there."""
    for candidate in [os.environ.get("LENSPATH_CHROMIUM"), "chromium", "chromium-browser", "google-chrome"]:
        if candidate and (path := shutil.which(candidate)):
            return path
    message = "no Chromium for the viewer's browser tests: `apt-get install chromium` (scripts/test.sh does as root)"
    if os.environ.get("CI"):
        pytest.fail(message)
    pytest.skip(message)


class Viewer:
    """A running `lenspath view` and its URL."""

    def __init__(self, cli: Path, *args: str, resolution: tuple[int, int] = RESOLUTION) -> None:
        self.process = subprocess.Popen(
            [str(cli), "view", "--port", "0", "--res", f"{resolution[0]}x{resolution[1]}", *args],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        line = self.process.stdout.readline()
        found = re.search(r"http://[\d.]+:\d+/", line)
        if not found:
            self.process.kill()
            raise AssertionError(f"no URL in {line!r}; stderr: {self.process.stderr.read()}")
        self.url = found.group(0)

    def get(self, path: str) -> bytes:
        with urllib.request.urlopen(self.url + path.lstrip("/"), timeout=30) as response:
            return response.read()

    def state(self) -> dict:
        return json.loads(self.get("api/state"))

    def post(self, path: str, body: bytes | dict, content_type: str = "application/json") -> tuple[int, dict]:
        data = json.dumps(body).encode() if isinstance(body, dict) else body
        request = urllib.request.Request(self.url + path.lstrip("/"), data=data, headers={"Content-Type": content_type})
        try:
            with urllib.request.urlopen(request, timeout=30) as response:
                return response.status, json.loads(response.read())
        except urllib.error.HTTPError as e:
            return e.code, json.loads(e.read())

    def stop(self) -> None:
        self.process.kill()
        self.process.wait()


@pytest.fixture(scope="module")
def chromium() -> Iterator:
    path = find_chromium()
    with playwright_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=path)
        yield browser
        browser.close()


@pytest.fixture
def viewer(cli: Path) -> Iterator[Viewer]:
    v = Viewer(cli)
    yield v
    v.stop()


def open_page(chromium, viewer: Viewer, max_spp: int):
    page = chromium.new_page(viewport={"width": 1200, "height": 900})
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.errors = errors
    page.goto(viewer.url)
    wait_for_spp(page, 1)
    set_number(page, "#max-spp", max_spp)
    settle(page, viewer)
    return page


def settle(page, viewer: Viewer, timeout_s: float = 60) -> None:
    """Waits until the page shows an image of the server's latest settings."""
    deadline = time.monotonic() + timeout_s
    while generation(page) != viewer.state()["generation"]:
        assert time.monotonic() < deadline, "the page never caught up with the settings"
        time.sleep(0.05)


def set_number(page, selector: str, value: float) -> None:
    page.locator(selector).fill(str(value))
    page.locator(selector).dispatch_event("change")


def generation(page) -> int:
    """The settings generation of the image the page shows."""
    return int(page.locator("#frame").get_attribute("data-generation") or -1)


def wait_for_spp(page, spp: int, after_generation: int = -1, timeout_s: float = 60) -> None:
    """Waits until the page shows an image of at least `spp` samples from a generation after `after_generation`."""
    page.wait_for_function(
        "([spp, g]) => { const e = document.getElementById('frame');"
        " return Number(e.dataset.spp) >= spp && Number(e.dataset.generation) > g; }",
        arg=[spp, after_generation],
        timeout=timeout_s * 1000,
    )


def canvas_pixels(page) -> list[int]:
    return page.evaluate(
        "() => { const c = document.getElementById('frame');"
        " return Array.from(c.getContext('2d').getImageData(0, 0, c.width, c.height).data); }"
    )


def test_f_stop_changes_the_image_and_back_gives_the_same_pixels(chromium, viewer: Viewer) -> None:
    page = open_page(chromium, viewer, max_spp=4)
    wait_for_spp(page, 4)
    wide_open = canvas_pixels(page)
    assert len(wide_open) == 4 * RESOLUTION[0] * RESOLUTION[1]

    g = generation(page)
    page.locator("#fstop").fill("12")  # two stops down, in thirds
    wait_for_spp(page, 4, after_generation=g)
    stopped_down = canvas_pixels(page)
    assert page.locator("#fstop-value").inner_text() == f"f/{viewer.state()['settings']['f_number']:.1f}"
    assert viewer.state()["settings"]["f_number"] == pytest.approx(4 * viewer.state()["wide_open_f_number"])
    changed = sum(abs(a - b) for a, b in zip(wide_open, stopped_down, strict=True)) / len(wide_open)
    assert changed > 1.0, "stopping down two stops changes the image"

    g = generation(page)
    page.locator("#fstop").fill("0")
    wait_for_spp(page, 4, after_generation=g)
    assert canvas_pixels(page) == wide_open, "the same settings and seed give the same image"
    assert page.errors == []


def test_the_sensor_panel_records_through_a_sensor_and_back(chromium, viewer: Viewer, tmp_path: Path) -> None:
    page = open_page(chromium, viewer, max_spp=2)
    wait_for_spp(page, 2)
    radiance = canvas_pixels(page)
    assert page.locator("#sensor-iso").is_disabled()

    g = generation(page)
    page.locator("#sensor-on").check()
    wait_for_spp(page, 2, after_generation=g)
    sensor = viewer.state()["settings"]["sensor"]
    assert sensor["model"] == "sony_ilce_7m3" and sensor["iso"] == 55.0
    developed = canvas_pixels(page)
    assert developed != radiance, "the developed frame is another image"
    assert page.locator("#sensor-exposure-taken").inner_text() == "taken at 1/60 s, ISO 55"

    # Four stops more gain: brighter, with the noise of a short exposure.
    g = generation(page)
    set_number(page, "#sensor-iso", 880)
    wait_for_spp(page, 2, after_generation=g)
    assert viewer.state()["settings"]["sensor"]["iso"] == 880.0
    brighter = canvas_pixels(page)
    assert sum(brighter) > 1.5 * sum(developed)
    # The EXR download records how the frame was taken, as `lenspath render --sensor` does.
    (tmp_path / "taken.exr").write_bytes(viewer.get("api/image.exr"))
    attributes = lenspath.read_exr(tmp_path / "taken.exr")["attributes"]
    assert attributes["isoSpeed"] == 880.0 and abs(attributes["expTime"] - 1 / 60) < 1e-6
    assert attributes["lenspath/sensor"] == "sony_ilce_7m3"

    # Metered: the camera chooses, and the default scene is dim enough to need the gain.
    g = generation(page)
    page.locator("#sensor-auto").check()
    wait_for_spp(page, 2, after_generation=g)
    assert page.locator("#sensor-iso").is_disabled()
    assert page.locator("#sensor-exposure-taken").inner_text().startswith("taken at 1/30 s, ISO ")

    g = generation(page)
    page.locator("#sensor-on").uncheck()
    wait_for_spp(page, 2, after_generation=g)
    assert viewer.state()["settings"]["sensor"] is None
    assert canvas_pixels(page) == radiance, "without the sensor the image is the radiance again"
    assert page.errors == []


def test_click_autofocuses_where_the_cli_does(chromium, viewer: Viewer, cli: Path, tmp_path: Path) -> None:
    page = open_page(chromium, viewer, max_spp=2)
    box = page.locator("#frame").bounding_box()
    x, y = NEAR_SPHERE_CENTRE
    g = generation(page)
    with page.expect_request("**/api/autofocus") as request:
        page.locator("#frame").click(position={"x": x * box["width"], "y": y * box["height"]})
    patch = request.value.post_data_json["patch"]
    assert patch[2:] == [0.1, 0.12]
    page.wait_for_function("document.getElementById('af-result').dataset.sensorMm !== undefined", timeout=60_000)
    viewer_sensor_mm = float(page.locator("#af-result").get_attribute("data-sensor-mm"))
    # The curve was drawn as the search went, and the focus moved there.
    assert page.locator("#af-curve circle").count() >= 5
    page.wait_for_function(f"Math.abs(document.getElementById('sensor-depth').value - {viewer_sensor_mm}) < 1e-9")
    wait_for_spp(page, 2, after_generation=g)

    # The same camera, from the viewer's own settings file, through `lenspath autofocus`.
    scene_file = tmp_path / "view.toml"
    scene_file.write_bytes(viewer.get("api/scene.toml"))
    out = subprocess.run(
        [str(cli), "autofocus", str(scene_file), "--patch", ",".join(repr(v) for v in patch)]
        + ["--res", f"{RESOLUTION[0]}x{RESOLUTION[1]}", "--json"],
        check=True,
        capture_output=True,
        text=True,
    )
    assert json.loads(out.stdout)["sensor_depth_mm"] == viewer_sensor_mm
    assert page.errors == []


def test_a_dragged_rectangle_is_the_patch(chromium, viewer: Viewer) -> None:
    page = open_page(chromium, viewer, max_spp=1)
    page.locator("#af-strategy").select_option("rangefinder")
    box = page.locator("#frame").bounding_box()
    corners = [(0.30, 0.55), (0.48, 0.80)]
    (x0, y0), (x1, y1) = [(box["x"] + x * box["width"], box["y"] + y * box["height"]) for x, y in corners]
    with page.expect_request("**/api/autofocus") as request:
        page.mouse.move(x0, y0)
        page.mouse.down()
        page.mouse.move(x1, y1, steps=5)
        page.mouse.up()
    sent = request.value.post_data_json
    assert sent["strategy"] == "rangefinder" and sent["metric"] == "tenengrad"
    assert sent["patch"] == pytest.approx([0.30, 0.55, 0.18, 0.25], abs=2 / box["width"])
    assert page.locator("#patch-box").is_visible()
    page.wait_for_function("document.getElementById('af-result').dataset.sensorMm !== undefined", timeout=60_000)
    lo, hi = viewer.state()["focus_range_mm"]
    assert lo <= float(page.locator("#af-result").get_attribute("data-sensor-mm")) <= hi
    assert page.errors == []


def test_saved_settings_render_the_saved_image_bit_for_bit(chromium, viewer: Viewer, cli: Path, tmp_path: Path) -> None:
    page = open_page(chromium, viewer, max_spp=3)
    g = generation(page)
    page.locator("#aperture-kind").select_option("blades")
    set_number(page, "#aperture-count", 5)
    page.locator("#fstop").fill("3")
    wait_for_spp(page, 1, after_generation=g)
    settle(page, viewer)
    wait_for_spp(page, 3, after_generation=generation(page) - 1)
    # The downloads the Save links give.
    with page.expect_download() as download:
        page.locator("#save-toml").click()
    scene_file = tmp_path / "saved.toml"
    download.value.save_as(scene_file)
    with page.expect_download() as download:
        page.locator("#save-png").click()
    download.value.save_as(tmp_path / "viewer.png")
    (tmp_path / "viewer.exr").write_bytes(viewer.get("api/image.exr"))
    text = scene_file.read_text()
    assert 'aperture = "blades:5:0:0"' in text and "spp = 3" in text, text

    for suffix in ["png", "exr"]:
        subprocess.run(
            [str(cli), "render", str(scene_file), "--out", str(tmp_path / f"cli.{suffix}")],
            check=True,
            capture_output=True,
        )
    # (Compared as booleans: pytest's diff of two differing images would take minutes.)
    same_png = (tmp_path / "viewer.png").read_bytes() == (tmp_path / "cli.png").read_bytes()
    assert same_png, "the PNG differs"
    # The EXR's channels bit for bit, and the header's camera and settings (not the scene's
    # name or the comments: the CLI names the scene file).
    ours, theirs = lenspath.read_exr(tmp_path / "viewer.exr"), lenspath.read_exr(tmp_path / "cli.exr")
    assert sorted(ours["channels"]) == sorted(theirs["channels"]) == ["B", "G", "R", "Z"]
    for name, values in ours["channels"].items():
        assert np.array_equal(values, theirs["channels"][name]), f"the EXR's {name} differs"
    same = ["worldToCamera", "aperture", "lenspath/camera", "lenspath/lens", "lenspath/integrator"]
    same += ["lenspath/maxDepth", "lenspath/lightSamples", "lenspath/sampler", "lenspath/seed"]
    for name in same:
        assert name in ours["attributes"], f"the viewer's EXR has no {name}"
        assert np.array_equal(ours["attributes"][name], theirs["attributes"][name]), name


def test_orbit_zoom_and_pan_move_the_camera(chromium, viewer: Viewer) -> None:
    page = open_page(chromium, viewer, max_spp=1)
    before = viewer.state()["settings"]
    box = page.locator("#frame").bounding_box()
    cx, cy = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    g = generation(page)
    page.mouse.move(cx, cy)
    page.mouse.down(button="right")
    page.mouse.move(cx + 60, cy + 20, steps=4)
    page.mouse.up(button="right")
    wait_for_spp(page, 1, after_generation=g)
    settle(page, viewer)
    orbited = viewer.state()["settings"]

    def distance(s: dict) -> float:
        return sum((e - t) ** 2 for e, t in zip(s["eye"], s["target"], strict=True)) ** 0.5

    assert orbited["target"] == before["target"]
    assert orbited["eye"] != before["eye"]
    assert distance(orbited) == pytest.approx(distance(before), rel=1e-5)

    g = generation(page)
    page.mouse.move(cx, cy)
    page.mouse.wheel(0, -300)
    wait_for_spp(page, 1, after_generation=g)
    settle(page, viewer)
    zoomed = viewer.state()["settings"]
    assert distance(zoomed) < 0.9 * distance(orbited)
    assert zoomed["target"] == before["target"]

    # Shift + right-drag pans: eye and target move together.
    g = generation(page)
    page.keyboard.down("Shift")
    page.mouse.down(button="right")
    page.mouse.move(cx - 40, cy + 30, steps=4)
    page.mouse.up(button="right")
    page.keyboard.up("Shift")
    wait_for_spp(page, 1, after_generation=g)
    settle(page, viewer)
    panned = viewer.state()["settings"]
    moved = [e - z for e, z in zip(panned["eye"], zoomed["eye"], strict=True)]
    assert any(abs(m) > 1e-3 for m in moved)
    assert [t - z for t, z in zip(panned["target"], zoomed["target"], strict=True)] == pytest.approx(moved, abs=1e-5)
    assert distance(panned) == pytest.approx(distance(zoomed), rel=1e-5)
    assert page.errors == []


def test_a_dropped_lens_table_is_offered_drawn_and_saved(chromium, viewer: Viewer, cli: Path, tmp_path: Path) -> None:
    page = open_page(chromium, viewer, max_spp=1)
    table = (REPO / "crates/lenspath/lenses/wide22.dat").read_text()
    g = generation(page)
    page.evaluate(
        """(text) => {
            const transfer = new DataTransfer();
            transfer.items.add(new File([text], "my-wide.dat"));
            document.getElementById("lens-drop").dispatchEvent(new DragEvent("drop", { dataTransfer: transfer }));
        }""",
        table,
    )
    wait_for_spp(page, 1, after_generation=g)
    state = viewer.state()
    assert "my-wide.dat" in state["lenses"]
    assert state["settings"]["lens"] == "my-wide.dat"
    assert state["focal_length_mm"] == pytest.approx(22, rel=0.05)
    svg = viewer.get("api/layout.svg").decode()
    assert svg.startswith("<svg") and f"sensor {state['sensor_depth_mm']:.3f} mm" in svg
    # The saved file names the table, to be put beside it; then it renders the same image.
    settle(page, viewer)
    text = viewer.get("api/scene.toml").decode()
    assert "'my-wide.dat' was dropped" in text and 'lens = "my-wide.dat"' in text
    (tmp_path / "view.toml").write_text(text)
    (tmp_path / "my-wide.dat").write_text(table)
    (tmp_path / "viewer.png").write_bytes(viewer.get("api/image.png"))
    subprocess.run([str(cli), "render", str(tmp_path / "view.toml"), "--out", str(tmp_path / "cli.png")], check=True)
    assert (tmp_path / "cli.png").read_bytes() == (tmp_path / "viewer.png").read_bytes()
    assert page.errors == []


@pytest.mark.parametrize(
    ("path", "body", "match"),
    [
        ("api/settings", {"f_number": -2}, "f_number must be a positive number"),
        ("api/settings", {"aperture": "hexagon"}, "aperture shape 'hexagon'"),
        ("api/settings", {"fstop": 4}, "unknown setting 'fstop'"),
        ("api/settings", {"max_spp": "many"}, "bad setting"),
        ("api/settings", {"focus": {"by": "distance", "distance_m": 0}}, "focus must be a positive"),
        ("api/settings", {"lens": "/etc/passwd"}, "outside the scene's folder"),
        ("api/settings", {"eye": [0, 1, 0], "target": [0, 1, 0]}, "must differ"),
        ("api/settings", {"eye": [1e38, 1, 0]}, "within ±1e18 scene units"),
        ("api/settings", {"max_depth": 5000}, "max depth must be at most 1024, got 5000"),
        ("api/settings", {"sensor": {"iso": -5}}, "sensor: the sensor's ISO must be positive"),
        ("api/settings", {"sensor": {"cfa": "rgbw"}}, "sensor: unknown colour filter array 'rgbw'"),
        ("api/settings", {"sensor": {"gain": 2}}, "bad setting"),
        ("api/settings", b"{not json", "not JSON"),
        ("api/autofocus", {"patch": [0.9, 0.9, 0.5, 0.5]}, "inside"),
        ("api/autofocus", {"patch": [0.4, 0.4, 0.1, 0.1], "metric": "sharpness"}, "unknown focus measure"),
        ("api/lens?name=bad.dat", b"# radius thickness ior aperture\n1 2 3\n", "bad.dat"),
        ("api/lens?name=../x.dat", b"", "plain file name"),
        ("api/lens?name=a%0Ab.dat", b"", "plain file name"),
        ("api/lens?name=x%22.dat", b"", "plain file name"),
        ("api/lens?name=dgauss50", b"", "named like the built-in lens 'dgauss50'"),
    ],
)
def test_bad_input_is_refused_with_its_reason(viewer: Viewer, path: str, body, match: str) -> None:
    before = viewer.state()
    status, answer = viewer.post(path, body)
    assert status == 400
    assert re.search(re.escape(match), answer["error"]), answer["error"]
    after = viewer.state()
    assert after["generation"] == before["generation"] and after["settings"] == before["settings"]


def test_an_error_shows_on_the_page_and_the_viewer_goes_on(chromium, viewer: Viewer) -> None:
    page = open_page(chromium, viewer, max_spp=1)
    page.locator("#lens-path").fill("/etc/hostname")
    page.locator("#lens-path-form button").click()
    page.wait_for_selector("#error:not([hidden])")
    assert "outside the scene's folder" in page.locator("#error").inner_text()
    g = generation(page)
    page.locator("#lens").select_option("tele250")
    wait_for_spp(page, 1, after_generation=g)
    page.wait_for_selector("#error", state="hidden")
    assert viewer.state()["settings"]["lens"] == "tele250"


def test_the_mtf_panel_follows_the_lens_as_it_renders(chromium, viewer: Viewer) -> None:
    # Wide open, then at f/16: the plot is the lens's at the view's f-stop and sensor, three fields.
    svg = viewer.get("api/mtf.svg").decode()
    assert svg.startswith("<svg") and svg.count("<polyline") == 7, "the limit, T and S at three fields"
    status, _ = viewer.post("api/settings", {"f_number": 16})
    assert status == 200
    assert "f/16.00 working" in viewer.get("api/mtf.svg").decode()
    page = open_page(chromium, viewer, max_spp=4)
    page.locator("#mtf-details summary").click()
    page.wait_for_function("() => document.getElementById('mtf').naturalWidth > 0", timeout=60_000)
    # A render setting is a new generation but the same optics: the plot is not fetched again; a new f-stop is.
    shown = page.locator("#mtf").get_attribute("src")
    g = generation(page)
    set_number(page, "#max-spp", 8)
    wait_for_spp(page, 1, after_generation=g)
    assert page.locator("#mtf").get_attribute("src") == shown
    g = generation(page)
    page.locator("#fstop").fill("3")
    wait_for_spp(page, 1, after_generation=g)
    assert page.locator("#mtf").get_attribute("src") != shown
    assert page.errors == []
    page.close()


def test_other_hosts_are_refused(viewer: Viewer) -> None:
    request = urllib.request.Request(viewer.url + "api/state", headers={"Host": "example.com"})
    with pytest.raises(urllib.error.HTTPError, match="403"):
        urllib.request.urlopen(request, timeout=10)
    request = urllib.request.Request(viewer.url + "api/state", headers={"Origin": "http://example.com"})
    with pytest.raises(urllib.error.HTTPError, match="403"):
        urllib.request.urlopen(request, timeout=10)


def cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads CPU time from /proc (Linux)")
def test_rendering_stops_when_no_page_is_open(chromium, viewer: Viewer) -> None:
    page = open_page(chromium, viewer, max_spp=4096)
    wait_for_spp(page, 16)
    pid = viewer.process.pid
    start = cpu_seconds(pid)
    time.sleep(1.0)
    busy = cpu_seconds(pid) - start
    assert busy > 0.5, f"rendering with a page open uses the cores ({busy:.2f} s of CPU in 1 s)"
    page.close()
    time.sleep(0.5)
    start = cpu_seconds(pid)
    time.sleep(1.0)
    idle = cpu_seconds(pid) - start
    assert idle < 0.1, f"with no page open the viewer rests ({idle:.2f} s of CPU in 1 s)"
