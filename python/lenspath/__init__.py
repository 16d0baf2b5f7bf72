"""lenspath: a physically based path tracer whose camera is a real compound lens.

    >>> import lenspath
    >>> image = lenspath.render("cornell-spheres", spp=16, resolution=(320, 240))
    >>> image.shape, image.dtype
    ((240, 320, 3), dtype('float32'))

Images are linear RGB float32 arrays of shape (height, width, 3). The native
module ``lenspath._core`` does the work; this package adds the conveniences
(scenes by path or name, progress bars). See ``_core.pyi`` for every signature.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from typing import Any, Literal, overload

import numpy as np
import numpy.typing as npt

from . import _core, sensor
from ._core import (
    MAX_SAMPLES_PER_PIXEL,
    AutofocusResult,
    Camera,
    Emission,
    Glass,
    Lens,
    LensError,
    LenspathError,
    RawFrame,
    Scene,
    SceneError,
    Sensor,
    bokeh,
    builtin_lenses,
    builtin_scenes,
    defaults,
    focus_measure,
    focus_measures,
    lens_blur,
    load,
    read,
    read_exr,
    sensor_models,
    write,
    write_exr,
)

__version__: str = _core.__version__

__all__ = [
    "MAX_SAMPLES_PER_PIXEL",
    "AutofocusResult",
    "Camera",
    "Emission",
    "Glass",
    "Lens",
    "LensError",
    "LenspathError",
    "RawFrame",
    "Scene",
    "SceneError",
    "Sensor",
    "autofocus",
    "bokeh",
    "builtin_lenses",
    "builtin_scenes",
    "defaults",
    "focus_measure",
    "focus_measures",
    "guide_map",
    "lens_blur",
    "load",
    "read",
    "read_exr",
    "render",
    "sensor",
    "sensor_models",
    "write",
    "write_exr",
]


def _as_scene(scene: Scene | str | os.PathLike[str]) -> Scene:
    """A Scene as given, a built-in scene by name, or a scene file by path."""
    if isinstance(scene, Scene):
        return scene
    if isinstance(scene, (str, os.PathLike)):
        builtin = _core.builtin_scene_named(scene)
        return Scene.builtin(builtin) if builtin is not None else load(scene)
    raise TypeError(f"scene must be a lenspath.Scene, a built-in scene name or a path, not {type(scene).__name__}")


def _tqdm_progress() -> Callable[[int, int], None] | None:
    """A progress callback drawing a tqdm bar (the notebook one in Jupyter), or None without tqdm."""
    try:
        from tqdm.auto import tqdm  # type: ignore[import-untyped, unused-ignore]
    except ImportError:
        return None
    bar = None

    def update(done: int, total: int) -> None:
        nonlocal bar
        if bar is None and total > 0:
            bar = tqdm(total=total, unit="sample", unit_scale=True, desc="lenspath")
        if bar is not None:
            bar.update(done - bar.n)
            if done >= total:
                bar.close()

    return update


@overload
def render(
    scene: Scene | str | os.PathLike[str],
    camera: Camera | None = None,
    *,
    spp: int | None = None,
    resolution: tuple[int, int] | None = None,
    seed: int | None = None,
    max_depth: int | None = None,
    light_samples: int | None = None,
    threads: int | None = None,
    aovs: None = None,
    crop: tuple[int, int, int, int] | None = None,
    progress: bool | Callable[[int, int], Any] = False,
    sampler: Literal["sobol", "independent"] | None = None,
    wavelength_nm: float | None = None,
    integrator: Literal["path", "guided"] | None = None,
    sensor: None = None,
) -> npt.NDArray[np.float32]: ...
@overload
def render(
    scene: Scene | str | os.PathLike[str],
    camera: Camera | None = None,
    *,
    spp: int | None = None,
    resolution: tuple[int, int] | None = None,
    seed: int | None = None,
    max_depth: int | None = None,
    light_samples: int | None = None,
    threads: int | None = None,
    aovs: None = None,
    crop: tuple[int, int, int, int] | None = None,
    progress: bool | Callable[[int, int], Any] = False,
    sampler: Literal["sobol", "independent"] | None = None,
    wavelength_nm: float | None = None,
    integrator: Literal["path", "guided"] | None = None,
    sensor: Sensor,
) -> RawFrame: ...
@overload
def render(
    scene: Scene | str | os.PathLike[str],
    camera: Camera | None = None,
    *,
    spp: int | None = None,
    resolution: tuple[int, int] | None = None,
    seed: int | None = None,
    max_depth: int | None = None,
    light_samples: int | None = None,
    threads: int | None = None,
    aovs: Sequence[str],
    crop: tuple[int, int, int, int] | None = None,
    progress: bool | Callable[[int, int], Any] = False,
    sampler: Literal["sobol", "independent"] | None = None,
    wavelength_nm: float | None = None,
    integrator: Literal["path", "guided"] | None = None,
    sensor: None = None,
) -> dict[str, npt.NDArray[np.float32]]: ...
def render(
    scene: Scene | str | os.PathLike[str],
    camera: Camera | None = None,
    *,
    spp: int | None = None,
    resolution: tuple[int, int] | None = None,
    seed: int | None = None,
    max_depth: int | None = None,
    light_samples: int | None = None,
    threads: int | None = None,
    aovs: Sequence[str] | None = None,
    crop: tuple[int, int, int, int] | None = None,
    progress: bool | Callable[[int, int], Any] = False,
    sampler: Literal["sobol", "independent"] | None = None,
    wavelength_nm: float | None = None,
    integrator: Literal["path", "guided"] | None = None,
    sensor: Sensor | None = None,
) -> npt.NDArray[np.float32] | dict[str, npt.NDArray[np.float32]] | RawFrame:
    """Renders ``scene`` and returns linear RGB, float32, shape (height, width, 3).

    ``scene`` is a :class:`Scene`, a built-in scene name (``"cornell-spheres"``)
    or a scene file path. ``camera=None`` uses the realistic camera with the
    scene's own settings, exactly as ``lenspath render`` does, so the same
    settings and seed give the CLI's image bit for bit. Every setting left
    out (None) is the scene file's, else the library's default (``spp`` 64,
    ``max_depth`` 16, ``light_samples`` 1, ``seed`` 0, ``resolution``
    (640, 480): ``lenspath.defaults()``); the library resolves them, as for
    the CLI. ``resolution`` is (width, height). With
    ``aovs=["depth"]`` the result is a dict with ``"rgb"`` and ``"depth"``
    (distance along the view axis, inf where nothing is hit). ``crop=(x, y,
    width, height)`` renders only that rectangle of pixels, each exactly as in
    the full image (``lenspath.distributed`` renders tiles so). ``sampler``:
    ``"sobol"`` (scrambled Sobol', the default) or ``"independent"``
    (uniform random numbers, as Mitsuba's and pbrt's ``independent``),
    default the scene file's. ``wavelength_nm`` renders at that one
    wavelength (360-830 nm): every channel is the spectral radiance there, a
    monochromatic image (default: colour across the visible). ``integrator``:
    ``"path"`` (the path tracer, the default) or ``"guided"`` (path guiding:
    a guide of where light comes from is trained first, then steers the
    paths; for caustics and light through glass or off metal; docs/guiding.md;
    a scene with no glass, mirror or smooth metal renders as with ``"path"``,
    without training), default the scene file's. ``progress``:
    True for a tqdm bar, or a callable ``(samples_done, samples_total)``. The
    GIL is released while rendering; Ctrl-C stops the render and raises
    KeyboardInterrupt.

    ``sensor=lenspath.Sensor(...)`` records the light through an image sensor
    (its settings over the scene file's ``[sensor]``) and returns the
    :class:`RawFrame` it reads out (``.mosaic``, ``.develop()``, ``.write()``),
    the frame ``lenspath render --raw`` writes. Without ``sensor`` a scene
    file's ``[sensor]`` still applies and the result is the developed image,
    as ``lenspath render --out`` writes it.
    """
    callback = _tqdm_progress() if progress is True else (progress or None)
    return _core.render(
        _as_scene(scene),
        camera,
        spp=spp,
        resolution=resolution,
        seed=seed,
        max_depth=max_depth,
        light_samples=light_samples,
        threads=threads,
        aovs=None if aovs is None else list(aovs),
        crop=crop,
        progress=callback,
        sampler=sampler,
        wavelength_nm=wavelength_nm,
        integrator=integrator,
        sensor=sensor,
    )


def guide_map(
    scene: Scene | str | os.PathLike[str],
    camera: Camera | None = None,
    *,
    at: tuple[float, float],
    resolution: tuple[int, int] | None = None,
    seed: int | None = None,
    max_depth: int | None = None,
    light_samples: int | None = None,
    threads: int | None = None,
    sampler: Literal["sobol", "independent"] | None = None,
    size: int = 256,
) -> dict[str, Any]:
    """What a guided render's guide learned at the surface seen at ``at`` (fractions of the
    image from its top left): its density over the sphere of directions as an equal-area
    disc, ``lenspath render --guide-map``'s. ``scene`` as for :func:`render`; see
    ``_core.pyi`` for the result."""
    return _core.guide_map(
        _as_scene(scene),
        camera,
        at=at,
        resolution=resolution,
        seed=seed,
        max_depth=max_depth,
        light_samples=light_samples,
        threads=threads,
        sampler=sampler,
        size=size,
    )


def autofocus(
    scene: Scene | str | os.PathLike[str],
    patch: tuple[float, float, float, float],
    camera: Camera | None = None,
    *,
    metric: str | None = None,
    strategy: str | None = None,
    patience: int | None = None,
    spp: int | None = None,
    resolution: tuple[int, int] | None = None,
    seed: int | None = None,
    max_depth: int | None = None,
    threads: int | None = None,
    sensor: Sensor | None = None,
    sensor_signal: str | None = None,
) -> AutofocusResult:
    """Focuses a realistic camera on ``patch`` (x, y, width, height as fractions of the
    image) by rendering it, as ``lenspath autofocus`` does; returns where and at what cost.

    ``scene`` is a :class:`Scene`, a built-in scene name or a scene file path;
    ``camera`` a ``Camera.realistic(...)`` (None: the scene's lens) whose focus is
    ignored. ``strategy``: "sweep", "early-exit" (stops after ``patience`` steps
    without a new best), "fast" (range finder, then the contrast peak
    refocused from a light field), "rangefinder" (probe rays and the lens model) or
    "depth" (range finder, then a short contrast refinement);
    ``metric`` one of ``focus_measures()``. ``result.camera`` is the camera
    focused there, ready for :func:`render`; ``lenspath.plot.focus_curve(result)``
    draws the search. Settings left out (None) are the library's defaults for
    patch renders (``metric`` "tenengrad", ``strategy`` "fast", ``patience`` 12,
    ``spp`` 16, ``max_depth`` 8, ``seed`` 0: ``lenspath.defaults()``), and
    ``resolution`` is the scene file's, else (640, 480).

    With ``sensor`` (a :class:`Sensor`, over the scene file's ``[sensor]``) contrast
    autofocus scores the sensor's noisy frames, reading ``sensor_signal`` of them
    ("raw-green", the default, or "luminance"), at an exposure metered from the first
    frame (with ``auto_exposure``) and held; ``result.exposure_time_s`` and
    ``result.iso`` say which.
    """
    x, y, width, height = patch
    return _core.autofocus(
        _as_scene(scene),
        (x, y, width, height),
        camera,
        metric=metric,
        strategy=strategy,
        patience=patience,
        spp=spp,
        resolution=resolution,
        seed=seed,
        max_depth=max_depth,
        threads=threads,
        sensor=sensor,
        sensor_signal=sensor_signal,
    )
