"""One source of truth: the CLI, `lenspath.render`, `lenspath.distributed`
and a scene file saved by `lenspath view` give byte-identical images of every
scene in scenes/ and every built-in scene, with and without overrides. What
an option left out means is decided once, in the library
(`lenspath::setup`), so the front ends cannot drift apart again."""

from __future__ import annotations

import subprocess
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import lenspath
from lenspath import Camera

from .conftest import REPO, SHARED, absent_shared_reason, scene_needs_shared
from .test_viewer import Viewer, find_chromium, playwright_api, wait_for_spp

distributed = pytest.importorskip("distributed")
from lenspath import distributed as lpd  # noqa: E402

RESOLUTION = (48, 36)
SPP = 2
#: cornell-mesh's procedural mesh, smaller than its default million triangles.
MESH_TRIANGLES = 20_000

SCENE_FILES = sorted((REPO / "scenes").glob("*.toml"))
#: Every scene file, then every built-in scene.
SCENES: list[str] = [str(p) for p in SCENE_FILES] + lenspath.builtin_scenes()


def scene_id(scene: str) -> str:
    return Path(scene).stem


#: Two sets of overrides: only the size and samples (everything else the
#: scene file's, else the defaults), and every render setting and the f-stop.
OVERRIDES: dict[str, dict[str, Any]] = {
    "file-settings": {},
    "overridden": {
        "max_depth": 3,
        "light_samples": 2,
        "seed": 7,
        "sampler": "independent",
        "integrator": "guided",
        "f_number": 4.0,
    },
}


def cli_flags(o: dict[str, Any]) -> list[str]:
    flags = ["--res", f"{RESOLUTION[0]}x{RESOLUTION[1]}", "--spp", str(SPP)]
    names = {"max_depth": "--max-depth", "light_samples": "--light-samples", "seed": "--seed"}
    names |= {"sampler": "--sampler", "integrator": "--integrator", "f_number": "--fstop"}
    for key, flag in names.items():
        if key in o:
            flags += [flag, str(o[key])]
    return flags


def python_args(o: dict[str, Any]) -> tuple[Camera | None, dict[str, Any]]:
    camera = Camera.realistic(f_number=o["f_number"]) if "f_number" in o else None
    kwargs = {k: v for k, v in o.items() if k != "f_number"}
    return camera, {"spp": SPP, "resolution": RESOLUTION, **kwargs}


def where(scene: str) -> list[str]:
    """The CLI's arguments naming `scene` (those reading ../shared allowed to)."""
    if scene_needs_shared(scene):
        return [scene, "--allow-read", str(SHARED)]
    if scene.endswith(".toml"):
        return [scene]
    return ["--scene", scene, "--mesh-triangles", str(MESH_TRIANGLES)]


def python_scene(scene: str) -> lenspath.Scene | str:
    if scene_needs_shared(scene):
        return lenspath.load(scene, allow_read=[SHARED])
    return scene if scene.endswith(".toml") else lenspath.Scene.builtin(scene, MESH_TRIANGLES)


def cli_render(cli: Path, scene: str, flags: list[str], out: Path) -> np.ndarray:
    subprocess.run([str(cli), "render", *where(scene), *flags, "--out", str(out)], check=True, capture_output=True)
    return lenspath.read(out)


@pytest.fixture(scope="module")
def client() -> Iterator[Any]:
    cluster = distributed.LocalCluster(
        n_workers=1, threads_per_worker=2, processes=True, host="127.0.0.1", dashboard_address=":0", silence_logs=40
    )
    client = distributed.Client(cluster)
    yield client
    client.close()
    cluster.close()


@pytest.fixture(scope="module")
def chromium() -> Iterator[Any]:
    with playwright_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=find_chromium())
        yield browser
        browser.close()


def viewer_saved_file(
    cli: Path, chromium: Any, scene: str, o: dict[str, Any], tmp_path: Path
) -> tuple[Path, np.ndarray]:
    """The scene file `lenspath view` saves after the page sets `o` and renders SPP samples, and its image."""
    viewer = Viewer(cli, *where(scene), resolution=RESOLUTION)
    try:
        page = chromium.new_page()
        page.goto(viewer.url)
        wait_for_spp(page, 1)
        status, answer = viewer.post("api/settings", {"max_spp": SPP, **o})
        assert status == 200, answer
        wait_for_spp(page, SPP, after_generation=viewer.state()["generation"] - 1)
        saved = tmp_path / "viewer.toml"
        saved.write_text(viewer.get("api/scene.toml").decode())
        (tmp_path / "viewer.exr").write_bytes(viewer.get("api/image.exr"))
        page.close()
        return saved, lenspath.read(tmp_path / "viewer.exr")
    finally:
        viewer.stop()


@pytest.mark.parametrize("overrides", OVERRIDES.values(), ids=OVERRIDES.keys())
@pytest.mark.parametrize("scene", SCENES, ids=[scene_id(s) for s in SCENES])
def test_every_front_end_gives_the_same_image(
    cli: Path, client: Any, chromium: Any, scene: str, overrides: dict[str, Any], tmp_path: Path
) -> None:
    if scene_needs_shared(scene) and not SHARED.is_dir():
        pytest.skip(f"{scene} needs ../shared: {absent_shared_reason()}")
    reference = cli_render(cli, scene, cli_flags(overrides), tmp_path / "cli.exr")
    assert reference.shape == (RESOLUTION[1], RESOLUTION[0], 3)
    assert reference.mean() > 0

    camera, kwargs = python_args(overrides)
    local = lenspath.render(python_scene(scene), camera, **kwargs)
    assert np.array_equal(local, reference), "lenspath.render differs from lenspath render"

    tiled = lpd.render(python_scene(scene), camera, client=client, tile_size=16, progress=False, **kwargs)
    assert np.array_equal(tiled, reference), "lenspath.distributed.render differs from lenspath render"

    saved, shown = viewer_saved_file(cli, chromium, scene, overrides, tmp_path)
    # The saved file names the scene file as its base, in another folder: allowed explicitly.
    allow = ["--allow-read", str(Path(scene).parent)] if scene.endswith(".toml") else []
    allow += ["--allow-read", str(SHARED)] if scene_needs_shared(scene) else []
    again = cli_render(cli, str(saved), allow, tmp_path / "saved.exr")
    assert scene.endswith(".toml") or f"builtin = {scene!r}".replace("'", '"') in saved.read_text()
    assert np.array_equal(shown, reference), "the viewer shows another image than lenspath render"
    assert np.array_equal(again, reference), "the viewer's saved scene renders another image"


def test_the_scene_files_settings_are_used_by_python(cli: Path, tmp_path: Path) -> None:
    """The case that started it: glass-and-gold's max_depth = 12 and light_samples
    were ignored by Python, and the images differed by up to 0.12."""
    scene = str(REPO / "scenes" / "glass-and-gold.toml")
    text = Path(scene).read_text()
    assert "max_depth = 12" in text
    cli_image = cli_render(cli, scene, ["--res", "64x48", "--spp", "4"], tmp_path / "cli.exr")
    python_image = lenspath.render(scene, spp=4, resolution=(64, 48))
    assert np.array_equal(cli_image, python_image)
    # And the setting matters: the library default depth gives another image. Paths past 12
    # bounces are rare (at 4 spp none may reach a pixel), so at 64 spp.
    at_file_depth = lenspath.render(scene, spp=64, resolution=(64, 48))
    assert not np.array_equal(at_file_depth, lenspath.render(scene, spp=64, resolution=(64, 48), max_depth=16))


def test_the_defaults_are_the_librarys() -> None:
    d = lenspath.defaults()
    assert (d["spp"], d["max_depth"], d["light_samples"], d["seed"]) == (64, 16, 1, 0)
    assert d["resolution"] == (640, 480) and d["sampler"] == "sobol" and d["lens"] == "dgauss50"
    assert (d["integrator"], d["guide_training_spp"]) == ("path", 15)
    assert (d["autofocus_spp"], d["autofocus_max_depth"], d["autofocus_patience"]) == (16, 8, 12)
    assert (d["autofocus_metric"], d["autofocus_strategy"], d["autofocus_sensor_signal"]) == (
        "tenengrad",
        "fast",
        "raw-green",
    )


#: A sensor set in every front end's spelling: the scene file's `[sensor]` keys
#: (also Python's `Sensor` arguments and the viewer's), and the CLI's flags.
SENSOR = {"model": "nikon_d850", "cfa": "gbrg", "iso": 800.0, "exposure_time_s": 0.02, "white_balance": "3200K"}
SENSOR_FLAGS = ["--sensor-model", "nikon_d850", "--cfa", "gbrg", "--iso", "800", "--exposure-time", "0.02"]
SENSOR_FLAGS += ["--white-balance", "3200K", "--sensor", "4.8x3.6"]


def test_every_front_end_gives_the_same_sensor_frame(cli: Path, chromium: Any, tmp_path: Path) -> None:
    from PIL import Image

    scene = "cornell-spheres"
    flags = ["--res", f"{RESOLUTION[0]}x{RESOLUTION[1]}", "--spp", str(SPP), *SENSOR_FLAGS]
    developed = cli_render(cli, scene, [*flags, "--raw", str(tmp_path / "cli.png")], tmp_path / "cli.exr")
    mosaic = np.asarray(Image.open(tmp_path / "cli.png"), dtype=np.uint16)
    assert mosaic.shape == (RESOLUTION[1], RESOLUTION[0]) and mosaic.max() > 64

    camera = Camera.realistic(sensor_width_mm=4.8)
    frame = lenspath.render(
        python_scene(scene), camera, spp=SPP, resolution=RESOLUTION, sensor=lenspath.Sensor(**SENSOR)
    )
    assert np.array_equal(frame.mosaic, mosaic), "lenspath.render's raw frame differs from lenspath render --raw"
    assert np.array_equal(frame.develop(), developed), "RawFrame.develop() differs from lenspath render --out"

    # The same sensor from a scene file's [sensor] table.
    table = "\n".join(f"{k} = {v!r}".replace("'", '"') for k, v in SENSOR.items())
    scene_file = tmp_path / "with_sensor.toml"
    scene_file.write_text(
        f'builtin = "cornell-spheres"\n[camera]\neye = [0, 1, 3.8]\nlook_at = [0, 1, 0]\nsensor_mm = [4.8, 3.6]\n'
        f"[sensor]\n{table}\n"
    )
    shape = ["--res", f"{RESOLUTION[0]}x{RESOLUTION[1]}", "--spp", str(SPP)]
    from_file = cli_render(cli, str(scene_file), [*shape, "--raw", str(tmp_path / "file.png")], tmp_path / "f.exr")
    file_mosaic = np.asarray(Image.open(tmp_path / "file.png"), dtype=np.uint16)
    python_developed = lenspath.render(str(scene_file), spp=SPP, resolution=RESOLUTION)
    python_frame = lenspath.render(str(scene_file), spp=SPP, resolution=RESOLUTION, sensor=lenspath.Sensor())
    assert np.array_equal(python_frame.mosaic, file_mosaic), "Python's frame differs from the CLI's, from a file"
    assert np.array_equal(python_developed, from_file), "a file's [sensor] develops alike in Python and the CLI"

    # The viewer: the page's sensor settings show the developed frame, and the saved file has them.
    saved, shown = viewer_saved_file(cli, chromium, str(scene_file), {}, tmp_path)
    assert "[sensor]" in saved.read_text() and 'white_balance = "3200K"' in saved.read_text()
    again = cli_render(cli, str(saved), ["--allow-read", str(scene_file.parent)], tmp_path / "saved.exr")
    assert np.array_equal(shown, from_file), "the viewer shows another developed frame than lenspath render"
    assert np.array_equal(again, from_file), "the viewer's saved scene develops another frame"
