"""Rendering across machines on Dask (``dask.distributed``); docs/distributed.md.

:func:`render` cuts one image into tiles and renders them on a cluster's
workers; :func:`map_renders` renders many images (a focus sweep, a turntable).
Every pixel is rendered by the same code with the same sample sequence as in
:func:`lenspath.render`, so the merged image is bit-identical to a
single-machine render with the same seed, whatever the tiling, the number of
workers, or the workers lost on the way (Dask renders a lost worker's tiles
again).

Workers make the scene themselves, once per worker process: a built-in scene by
name, a scene file from its path (which must be readable on every worker, as on
a shared file system) after checking that its content hash matches the
client's copy. The scene and its BVH stay cached on the worker, keyed by that
hash, for the following tiles and jobs.
"""

from __future__ import annotations

import hashlib
import os
import pickle
import threading
import uuid
from collections import OrderedDict
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import numpy.typing as npt

from . import _core
from ._core import Camera, Scene

if TYPE_CHECKING:
    from distributed import Client

__all__ = ["map_renders", "render"]

Image = npt.NDArray[np.float32] | dict[str, npt.NDArray[np.float32]]

# Keyword arguments of a job, as lenspath.render takes them.
_RENDER_OPTIONS = frozenset(
    {"spp", "resolution", "seed", "max_depth", "light_samples", "threads", "aovs", "sampler", "integrator"}
)
# Scenes a worker keeps: enough for a batch alternating between a few scenes.
_CACHED_SCENES = 4


@dataclass(frozen=True)
class _SceneRef:
    """How a worker makes a scene, and the key it caches it under."""

    key: str
    builtin: str | None = None
    mesh_triangles: int | None = None  # None: Scene.builtin's default
    path: str | None = None
    allow_read: tuple[str, ...] = ()  # folders the scene file may read besides its own


def _file_sha256(path: str) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _file_key(path: str, allow_read: tuple[str, ...]) -> str:
    """The cache key of a scene file: its content, and the folders it may read."""
    return f"sha256:{_file_sha256(path)}" + "".join(f":{a}" for a in allow_read)


def _scene_ref(scene: Scene | str | os.PathLike[str]) -> _SceneRef:
    """The reference workers make ``scene`` from: a built-in name or a file with its hash."""
    allow_read: tuple[str, ...] = ()
    if isinstance(scene, Scene):
        # Pickling gives the recipe, and refuses scenes built in Python.
        make, args = scene.__reduce__()
        if make is _core.load:
            scene, allowed = args
            allow_read = tuple(os.path.abspath(os.fspath(a)) for a in allowed)
        else:
            name, triangles = args
            return _SceneRef(key=f"builtin:{name}:{triangles}", builtin=name, mesh_triangles=triangles)
    builtin = _core.builtin_scene_named(scene) if isinstance(scene, (str, os.PathLike)) else None
    if builtin is not None:
        # By name: the worker makes it (cornell-mesh has a million triangles to build).
        return _SceneRef(key=f"builtin:{builtin}", builtin=builtin)
    if isinstance(scene, (str, os.PathLike)):
        path = os.path.abspath(os.fspath(scene))
        if not os.path.isfile(path):
            raise FileNotFoundError(f"{path}: no such scene file")
        return _SceneRef(key=_file_key(path, allow_read), path=path, allow_read=allow_read)
    raise TypeError(f"scene must be a lenspath.Scene, a built-in scene name or a path, not {type(scene).__name__}")


# Per worker process: the scenes it has made, and how many times it made one.
_scenes: OrderedDict[str, Scene] = OrderedDict()
_scenes_lock = threading.Lock()
_scene_loads = 0


def _worker_scene(ref: _SceneRef) -> Scene:
    """The scene ``ref`` names, made and compiled once per worker process."""
    global _scene_loads
    # One lock: tiles starting together on a worker's threads wait for one load.
    with _scenes_lock:
        scene = _scenes.get(ref.key)
        if scene is not None:
            _scenes.move_to_end(ref.key)
            return scene
        if ref.builtin is not None:
            scene = (
                Scene.builtin(ref.builtin)
                if ref.mesh_triangles is None
                else Scene.builtin(ref.builtin, ref.mesh_triangles)
            )
        else:
            assert ref.path is not None
            here = _file_key(ref.path, ref.allow_read)
            if here != ref.key:
                raise RuntimeError(
                    f"{ref.path} differs on this worker from the client's copy "
                    f"({here[:15]}... here, {ref.key[:15]}... there); every worker needs the same file"
                )
            scene = _core.load(ref.path, allow_read=list(ref.allow_read))
        scene.compile()
        _scenes[ref.key] = scene
        while len(_scenes) > _CACHED_SCENES:
            _scenes.popitem(last=False)
        _scene_loads += 1
        return scene


# Per worker process: cameras by their pickled form. Tiles arrive with fresh
# copies; one object per camera keeps the realistic camera's exit-pupil tables
# (built on its first render, a tenth of a second) for the following tiles.
_cameras: OrderedDict[bytes, Camera] = OrderedDict()


def _worker_camera(camera: Camera | None) -> Camera:
    """The worker's one copy of ``camera`` (None: the scene's realistic camera, ``Camera.realistic()``)."""
    key = pickle.dumps(camera)
    with _scenes_lock:
        cached = _cameras.get(key)
        if cached is None:
            cached = _cameras[key] = camera if camera is not None else Camera.realistic()
            while len(_cameras) > 4 * _CACHED_SCENES:
                _cameras.popitem(last=False)
        _cameras.move_to_end(key)
        return cached


def scene_loads() -> int:
    """How many scenes this process has made for tiles (run on workers by the tests)."""
    return _scene_loads


def _threads_per_tile() -> int:
    """A worker's cores shared among the tiles it renders at once (its Dask threads)."""
    from distributed import get_worker

    try:
        nthreads = get_worker().state.nthreads
    except (ValueError, AttributeError):
        nthreads = 1
    # The cores this process may use (a batch system's allocation), not the machine's.
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    return max(1, cores // max(1, nthreads))


def _render_tile(
    ref: _SceneRef,
    camera: Camera | None,
    options: dict[str, Any],
    crop: tuple[int, int, int, int],
) -> Image:
    """One tile of one job, on a worker."""
    scene = _worker_scene(ref)
    threads = options.get("threads") or _threads_per_tile()
    result: Image = _core.render(scene, _worker_camera(camera), **{**options, "threads": threads, "crop": crop})
    return result


def _image_size(ref: _SceneRef) -> tuple[int, int]:
    """The image size of a job that gives none: the scene file's, else the library's default."""
    resolution: tuple[int, int] = _worker_scene(ref).resolution or _core.defaults()["resolution"]
    return resolution


def _tiles(width: int, height: int, tile_size: int | None) -> list[tuple[int, int, int, int]]:
    """The image cut into ``tile_size`` squares (x, y, width, height); None: one tile."""
    if tile_size is None:
        return [(0, 0, width, height)]
    if tile_size < 1:
        raise ValueError(f"tile_size must be a positive number of pixels, got {tile_size}")
    return [
        (x, y, min(tile_size, width - x), min(tile_size, height - y))
        for y in range(0, height, tile_size)
        for x in range(0, width, tile_size)
    ]


def _progress_bar(total: int, desc: str) -> Callable[[int], None] | None:
    try:
        from tqdm.auto import tqdm  # type: ignore[import-untyped, unused-ignore]
    except ImportError:
        return None
    bar = tqdm(total=total, unit="tile", desc=desc)

    def advance(done: int) -> None:
        bar.update(done - bar.n)
        if done >= total:
            bar.close()

    return advance


def map_renders(
    jobs: Sequence[Mapping[str, Any]],
    client: Client,
    *,
    tile_size: int | None = None,
    progress: bool | Callable[[int, int], Any] = True,
) -> list[Image]:
    """Renders every job on ``client``'s cluster; returns the images in the jobs' order.

    A job is a mapping of :func:`lenspath.render`'s arguments: ``scene`` (a
    built-in name, a scene file path or a ``Scene`` loaded from one),
    ``camera`` and any of ``spp``, ``resolution``, ``seed``, ``max_depth``,
    ``light_samples``, ``threads`` (per tile; default the worker's cores over
    its Dask threads), ``aovs``, ``sampler`` and ``integrator``. Each image is that of
    ``lenspath.render(**job)``, bit for bit (a guided render's tiles each
    train the whole image's guide first, so they cost that training each). ``tile_size``: cut each image
    into squares of that many pixels (None: one task per image). ``progress``:
    True for a tqdm bar over tiles, or a callable ``(tiles_done, tiles_total)``.
    """
    from distributed import as_completed

    prepared = []
    for number, job in enumerate(jobs):
        unknown = set(job) - _RENDER_OPTIONS - {"scene", "camera"}
        if unknown or "scene" not in job:
            what = f"unknown arguments {sorted(unknown)}" if unknown else "no scene"
            raise ValueError(f"job {number}: {what}; a job takes scene, camera, {', '.join(sorted(_RENDER_OPTIONS))}")
        options = {k: v for k, v in job.items() if k in _RENDER_OPTIONS}
        if options.get("aovs") is not None:
            options["aovs"] = list(options["aovs"])
        prepared.append((_scene_ref(job["scene"]), job.get("camera"), options))

    # Image sizes: the jobs', else the scene files' (asked of a worker, which keeps the scene).
    asked = {
        number: client.submit(_image_size, ref, pure=False)
        for number, (ref, _, options) in enumerate(prepared)
        if options.get("resolution") is None
    }
    run = uuid.uuid4().hex[:8]
    futures = {}
    outputs: list[Image] = []
    for number, (ref, camera, options) in enumerate(prepared):
        width, height = asked[number].result() if number in asked else options["resolution"]
        options["resolution"] = (width, height)
        rgb = np.zeros((height, width, 3), np.float32)
        want_depth = bool(options.get("aovs"))
        outputs.append({"rgb": rgb, "depth": np.full((height, width), np.inf, np.float32)} if want_depth else rgb)
        for crop in _tiles(width, height, tile_size):
            x, y, w, h = crop
            key = f"lenspath-tile-{run}-{number}-{x}-{y}"
            futures[client.submit(_render_tile, ref, camera, options, crop, key=key, pure=False)] = (number, crop)

    callback: Callable[[int, int], Any] | None
    if progress is True:
        advance = _progress_bar(len(futures), "lenspath tiles")
        callback = (lambda done, _total: advance(done)) if advance else None
    else:
        callback = progress or None
    try:
        for done, future in enumerate(as_completed(futures), start=1):  # type: ignore[no-untyped-call]
            number, (x, y, w, h) = futures[future]
            tile = future.result()
            out = outputs[number]
            if isinstance(out, dict):
                assert isinstance(tile, dict)
                out["rgb"][y : y + h, x : x + w] = tile["rgb"]
                out["depth"][y : y + h, x : x + w] = tile["depth"]
            else:
                out[y : y + h, x : x + w] = tile
            del future
            if callback is not None:
                callback(done, len(futures))
    except BaseException:
        client.cancel(list(futures))  # type: ignore[no-untyped-call]
        raise
    return outputs


def render(
    scene: Scene | str | os.PathLike[str],
    camera: Camera | None = None,
    *,
    client: Client,
    spp: int | None = None,
    resolution: tuple[int, int] | None = None,
    seed: int | None = None,
    max_depth: int | None = None,
    light_samples: int | None = None,
    threads: int | None = None,
    aovs: Sequence[str] | None = None,
    sampler: Literal["sobol", "independent"] | None = None,
    integrator: Literal["path", "guided"] | None = None,
    tile_size: int = 64,
    progress: bool | Callable[[int, int], Any] = True,
) -> Image:
    """:func:`lenspath.render` on ``client``'s Dask cluster, in ``tile_size`` × ``tile_size`` tiles.

    Takes the same arguments (``scene`` a built-in name, a scene file path every
    worker can read, or a ``Scene`` loaded from one) and returns the same image,
    bit for bit (a setting left out is the scene file's, else the library's
    default, as there). ``threads`` is per tile (default: a worker's cores over its
    Dask threads). ``progress``: True for a tqdm bar over tiles, or a callable
    ``(tiles_done, tiles_total)``.
    """
    job: dict[str, Any] = {
        "scene": scene,
        "camera": camera,
        "spp": spp,
        "resolution": resolution,
        "seed": seed,
        "max_depth": max_depth,
        "light_samples": light_samples,
        "threads": threads,
        "sampler": sampler,
        "integrator": integrator,
    }
    if aovs is not None:
        job["aovs"] = aovs
    return map_renders([job], client, tile_size=tile_size, progress=progress)[0]
