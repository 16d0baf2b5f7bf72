"""lenspath.distributed on a real Dask cluster of worker processes on loopback:
the merged images are bit-identical to single-machine renders, the scene is
made once per worker, and a worker killed mid-render loses nothing."""

from __future__ import annotations

import os
import pickle
import signal
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

import lenspath
from lenspath import Camera, Lens, Scene

distributed = pytest.importorskip("distributed")
from lenspath import distributed as lpd  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
GLASS_AND_GOLD = REPO / "scenes" / "glass-and-gold.toml"


def _cluster(workers: int) -> tuple[object, object]:
    cluster = distributed.LocalCluster(
        n_workers=workers,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address=":0",
        silence_logs=40,
    )
    return cluster, distributed.Client(cluster)


@pytest.fixture(scope="module")
def client() -> Iterator[distributed.Client]:
    cluster, client = _cluster(2)
    yield client
    client.close()
    cluster.close()


CAMERAS = {
    "realistic": Camera.realistic("dgauss50", f_number=2.8),
    "thin-lens-blades": Camera.thin_lens(0.08, 3.2, aperture="blades:6:15:0.3"),
    "pinhole": Camera.pinhole(),
}


@pytest.mark.parametrize("tile_size", [32, 23])
@pytest.mark.parametrize("camera", CAMERAS.values(), ids=CAMERAS.keys())
def test_tiled_render_is_bit_identical_to_a_local_one(
    client: distributed.Client, camera: Camera, tile_size: int
) -> None:
    args = {"spp": 3, "resolution": (80, 60), "seed": 5}
    local = lenspath.render("cornell-spheres", camera, **args)
    merged = lpd.render("cornell-spheres", camera, client=client, tile_size=tile_size, progress=False, **args)
    assert merged.dtype == np.float32 and merged.shape == (60, 80, 3)
    assert np.array_equal(merged, local)


def test_depth_is_merged_too(client: distributed.Client) -> None:
    args = {"spp": 2, "resolution": (48, 40), "aovs": ["depth"]}
    local = lenspath.render("cornell-spheres", **args)
    merged = lpd.render("cornell-spheres", client=client, tile_size=16, progress=False, **args)
    assert isinstance(merged, dict) and isinstance(local, dict)
    assert np.array_equal(merged["rgb"], local["rgb"])
    assert np.array_equal(merged["depth"], local["depth"])


def test_a_scene_file_is_loaded_once_per_worker(client: distributed.Client) -> None:
    before = client.run(lpd.scene_loads)
    calls: list[tuple[int, int]] = []
    merged = lpd.render(GLASS_AND_GOLD, client=client, spp=1, tile_size=40, progress=lambda d, t: calls.append((d, t)))
    # The file's resolution (640 x 480): 16 x 12 tiles.
    assert merged.shape == (480, 640, 3)
    assert calls[-1] == (192, 192) and len(calls) == 192
    loads = {w: n - before[w] for w, n in client.run(lpd.scene_loads).items()}
    assert all(n <= 1 for n in loads.values()) and sum(loads.values()) >= 1, loads
    local = lenspath.render(GLASS_AND_GOLD, spp=1)
    assert np.array_equal(merged, local)
    # A second render of the same file finds it cached everywhere.
    lpd.render(lenspath.load(GLASS_AND_GOLD), client=client, spp=1, resolution=(64, 48), progress=False)
    again = {w: n - before[w] for w, n in client.run(lpd.scene_loads).items()}
    assert all(again[w] == loads[w] for w in loads if loads[w] == 1), (loads, again)


def test_map_renders_a_focus_sweep(client: distributed.Client) -> None:
    lens = Lens.builtin("dgauss50").stopped_down(4.0)
    jobs = [
        {
            "scene": "cornell-spheres",
            "camera": Camera.realistic(lens, sensor_depth_mm=z),
            "spp": 2,
            "resolution": (40, 30),
        }
        for z in (51.5, 52.5, 54.0)
    ]
    images = lpd.map_renders(jobs, client, progress=False)
    for job, image in zip(jobs, images, strict=True):
        assert np.array_equal(image, lenspath.render(**job))
    assert not np.array_equal(images[0], images[2]), "the sensor position changes the image"
    tiled = lpd.map_renders(jobs, client, tile_size=16, progress=False)
    assert all(np.array_equal(a, b) for a, b in zip(images, tiled, strict=True))


@pytest.mark.parametrize(
    ("job", "error", "match"),
    [
        ({"scene": "cornell-spheres", "sp": 4}, ValueError, r"job 0: unknown arguments \['sp'\]"),
        ({"spp": 4}, ValueError, "job 0: no scene"),
        ({"scene": "/no/such/scene.toml"}, FileNotFoundError, "no such scene file"),
        ({"scene": Scene()}, TypeError, "built or changed in Python and cannot be pickled"),
        ({"scene": 3}, TypeError, "scene must be a lenspath.Scene"),
    ],
)
def test_bad_jobs_are_refused_before_anything_runs(
    client: distributed.Client, job: dict[str, object], error: type[Exception], match: str
) -> None:
    with pytest.raises(error, match=match):
        lpd.map_renders([job], client, progress=False)


def test_a_worker_error_reaches_the_caller(client: distributed.Client) -> None:
    with pytest.raises(ValueError, match="samples per pixel must be in"):
        lpd.render("cornell-spheres", client=client, spp=0, resolution=(16, 16), progress=False)


def test_cameras_lenses_and_scenes_pickle_to_the_same_render() -> None:
    scene = Scene.builtin("cornell-spheres")
    cameras = [
        *CAMERAS.values(),
        Camera.realistic(Lens.builtin("wide22").stopped_down(4.0), focus_distance=2.5, aperture="star:5:0.4"),
        Camera.realistic(aperture=np.eye(8, dtype=np.float32) + 0.2),
        Camera.realistic("lentil:2004", desqueeze=True),
    ]
    for camera in cameras:
        copy = pickle.loads(pickle.dumps(camera))
        a = lenspath.render(scene, camera, spp=1, resolution=(32, 24))
        b = lenspath.render(pickle.loads(pickle.dumps(scene)), copy, spp=1, resolution=(32, 24))
        assert np.array_equal(a, b)
    loaded = pickle.loads(pickle.dumps(lenspath.load(GLASS_AND_GOLD)))
    assert loaded.source == str(GLASS_AND_GOLD)
    changed = Scene.builtin("cornell-spheres")
    changed.add_environment((0.1, 0.1, 0.1))
    assert changed.source is None
    with pytest.raises(TypeError, match="cannot be pickled"):
        pickle.dumps(changed)


def test_a_worker_killed_mid_render_loses_nothing() -> None:
    cluster, client = _cluster(2)
    try:
        pids = client.run(os.getpid)
        killed: list[int] = []

        def kill_one_worker(done: int, total: int) -> None:
            # After a few tiles, while the rest are queued or rendering on both workers.
            if done == 3 and not killed:
                pid = next(iter(pids.values()))
                os.kill(pid, signal.SIGKILL)
                killed.append(pid)

        args = {"spp": 4, "resolution": (96, 72), "seed": 2}
        merged = lpd.render("cornell-spheres", client=client, tile_size=12, progress=kill_one_worker, **args)
        assert killed, "the render finished before a worker could be killed"
        assert killed[0] not in client.run(os.getpid).values(), "the killed worker is gone"
        assert np.array_equal(merged, lenspath.render("cornell-spheres", **args))
    finally:
        client.close()
        cluster.close()
