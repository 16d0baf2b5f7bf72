"""Every public function with empty, degenerate and non-finite inputs: it answers or raises an
``Exception`` with its reason; a Rust panic never crosses into Python (pyo3's ``PanicException``
is a ``BaseException`` that ``except Exception`` misses)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import lenspath

EMPTY = np.zeros((0, 0, 3), np.float32)
ROW = np.zeros((1, 0, 3), np.float32)
PIXEL = np.zeros((1, 1, 3), np.float32)
NAN = np.full((4, 4, 3), np.nan, np.float32)
IMAGES = {"empty": EMPTY, "1x0": ROW, "1x1": PIXEL, "nan": NAN}
NUMBERS = [0.0, -1.0, math.nan, math.inf, 1e30]


def _lens() -> lenspath.Lens:
    return lenspath.Lens.builtin("dgauss50")


def _scene_with(call):
    scene = lenspath.Scene()
    material = scene.add_material("diffuse")
    return lambda: call(scene, material)


#: An expected outcome: None, an answer; else the exception's type and a pattern its message matches.
Outcome = tuple[type[Exception], str] | None


def _unless(bad: list[float], v: float, outcome: Outcome) -> Outcome:
    """`outcome` for the values in `bad` (compared so that NaN matches NaN), else an answer."""
    return outcome if any(v == b or (math.isnan(v) and math.isnan(b)) for b in bad) else None


NOT_POSITIVE = [0.0, -1.0, math.nan, math.inf]  # every number of NUMBERS but the huge one
WAVELENGTH = (ValueError, "a wavelength must be a positive number of nm, got")

#: Each call and what it must do: answer, or raise its reason. Some answers are lenient on
#: nonsense (a pinhole's NaN field of view): they are listed as they are, so a change shows here.
CALLS: dict[str, tuple[object, Outcome]] = {
    **{f"focus_measure({k})": ((lambda im=im: lenspath.focus_measure(im)), None) for k, im in IMAGES.items()},
    **{
        f"write exr({k})": (
            (lambda im=im, tmp="x.exr": lenspath.write(tmp, im)),
            (ValueError, "cannot write the EXR: it needs pixels and a channel") if im.size == 0 else None,
        )
        for k, im in IMAGES.items()
    },
    **{
        f"bokeh({k}, blades, {d})": (
            (lambda im=im, d=d: lenspath.bokeh(im, aperture="blades:6", diameter_px=d)),
            _unless([math.nan, 0.0], d, (ValueError, "diameter must be 1 to 16384 pixels, got")),
        )
        for k, im in IMAGES.items()
        for d in [1.0, 3.0, math.nan, 0.0]
    },
    **{
        f"bokeh({k}, mask)": ((lambda im=im: lenspath.bokeh(im, mask=np.ones((3, 3)))), None)
        for k, im in IMAGES.items()
    },
    **{
        f"lens_blur({k}, {fd})": (
            (
                lambda im=im, fd=fd: lenspath.lens_blur(
                    im, np.ones(im.shape[:2], np.float32), fd, focal_length_mm=50, f_number=2.8, fov_deg=40
                )
            ),
            _unless(
                [0.0, math.nan], fd, (ValueError, r"a 50 mm lens cannot focus at .* m \(closer than its focal length\)")
            ),
        )
        for k, im in IMAGES.items()
        for fd in [1.0, 0.0, math.nan]
    },
    **{f"Camera.pinhole({v})": ((lambda v=v: lenspath.Camera.pinhole(v)), None) for v in NUMBERS},
    **{
        f"Camera.thin_lens({v})": (
            (lambda v=v: lenspath.Camera.thin_lens(v)),
            _unless([-1.0, math.nan, math.inf], v, (ValueError, "aperture_radius must be zero or positive, got")),
        )
        for v in NUMBERS
    },
    **{
        f"Lens.stopped_down({v})": (
            (lambda v=v: _lens().stopped_down(v)),
            _unless(NOT_POSITIVE, v, (ValueError, "f-number must be positive, got"))
            or (ValueError, "dgauss50: the parallel ray is blocked inside the lens"),
        )
        for v in NUMBERS
    },
    **{f"Lens.focus_distance_mm({v})": ((lambda v=v: _lens().focus_distance_mm(v)), None) for v in NUMBERS},
    **{
        f"Lens.sensor_depth_mm_for({v})": (
            (lambda v=v: _lens().sensor_depth_mm_for(v)),
            _unless(NOT_POSITIVE, v, (ValueError, "focus distance must be positive and finite, got")),
        )
        for v in NUMBERS
    },
    **{f"Lens.chromatic({v})": ((lambda v=v: _lens().chromatic(v)), None) for v in NUMBERS},
    **{
        f"Lens.focal_shift([{v}])": (
            (lambda v=v: _lens().focal_shift(np.array([v]))),
            _unless(NOT_POSITIVE, v, WAVELENGTH),
        )
        for v in NUMBERS
    },
    **{
        f"Glass.index({v})": ((lambda v=v: lenspath.Glass("N-BK7").index(v)), _unless(NOT_POSITIVE, v, WAVELENGTH))
        for v in NUMBERS
    },
    **{
        f"Glass.abbe({v})": (
            (lambda v=v: lenspath.Glass.abbe(v, v)),
            _unless(NOT_POSITIVE, v, (ValueError, "n_d must be a finite number above 1, got")),
        )
        for v in NUMBERS
    },
    **{
        f"Emission.blackbody({v})": (
            (lambda v=v: lenspath.Emission.blackbody(v, v)),
            _unless(NOT_POSITIVE, v, (ValueError, "a black body's temperature must be positive kelvin, got")),
        )
        for v in NUMBERS
    },
    **{
        f"Scene.add_sphere(r={v})": (
            _scene_with(lambda s, m, v=v: s.add_sphere((0, 0, 0), v, m)),
            (lenspath.SceneError, "sphere 0: centre must be finite and radius positive, both within 1e18"),
        )
        for v in NUMBERS
    },
    "Lens.from_table(empty)": (lambda: lenspath.Lens.from_table(np.zeros((0, 4))), (lenspath.LensError, "no surfaces")),
    "Lens.from_table(nan)": (
        lambda: lenspath.Lens.from_table(np.full((3, 4), np.nan)),
        (lenspath.LensError, "line 1: radius 'NaN' is not finite"),
    ),
    "Lens.focal_shift(empty)": (lambda: _lens().focal_shift(np.array([])), None),
    "Emission.tabulated(empty)": (
        lambda: lenspath.Emission.tabulated([], []),
        (ValueError, r"needs at least two \(wavelength_nm, value\) pairs, got 0"),
    ),
    "Scene.add_mesh(empty)": (
        _scene_with(lambda s, m: s.add_mesh(np.zeros((0, 3)), np.zeros((0, 3), np.int64), m)),
        None,
    ),
    "Scene.add_mesh(index 5 of 3)": (
        _scene_with(lambda s, m: s.add_mesh(np.zeros((3, 3)), np.array([[0, 1, 5]]), m)),
        (lenspath.SceneError, "mesh 0: triangle 0 indexes a vertex beyond the 3 it has"),
    ),
    "render(1x1)": (lambda: lenspath.render("cornell-spheres", spp=1, resolution=(1, 1)), None),
    "render(empty scene)": (
        lambda: lenspath.render(lenspath.Scene(), spp=1, resolution=(8, 6)),
        (ValueError, "has no view; call look_at first"),
    ),
}


@pytest.mark.parametrize("name", list(CALLS))
def test_degenerate_input_answers_or_raises_its_reason(name: str, tmp_path, monkeypatch) -> None:
    # A panic would be pyo3's PanicException, a BaseException: neither an answer nor these.
    monkeypatch.chdir(tmp_path)
    call, outcome = CALLS[name]
    if outcome is None:
        call()
    else:
        kind, pattern = outcome
        with pytest.raises(kind, match=pattern):
            call()


@pytest.mark.parametrize("image", [EMPTY, ROW], ids=["0x0", "1x0"])
def test_an_empty_image_blurs_to_itself(image: np.ndarray) -> None:
    # It panicked inside the convolution ("chunk_size must not be zero").
    assert lenspath.bokeh(image, aperture="blades:6", diameter_px=3.0).shape == image.shape


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: lenspath.bokeh(PIXEL, aperture="circle", diameter_px=1e5), "must be 1 to 16384 pixels, got 100000"),
        (lambda: lenspath.bokeh(PIXEL, mask=np.ones((3, 3)), diameter_px=1e5), "must be 1 to 16384 pixels"),
        (lambda: lenspath.render("cornell-spheres", spp=-1), "spp must be a whole number from 0, got -1"),
        (lambda: lenspath.render("cornell-spheres", seed=-1), "seed must be a whole number from 0, got -1"),
        (lambda: lenspath.render("cornell-spheres", threads=-2), "threads must be a whole number from 0, got -2"),
        (
            lambda: lenspath.autofocus("cornell-spheres", (0.4, 0.4, 0.2, 0.2), spp=-1),
            "spp must be a whole number from 0, got -1",
        ),
        (
            _scene_with(lambda s, m: s.add_mesh(np.eye(3), np.array([[0, 1, 1.7]]), m)),
            "indices must be whole numbers from 0; triangle 0 has 1.7",
        ),
        (
            _scene_with(lambda s, m: s.add_mesh(np.eye(3), np.array([[0, 1, -1]]), m)),
            "indices must be whole numbers from 0; triangle 0 has -1",
        ),
        (lambda: lenspath.Glass("N-BK7").index(math.nan), "a wavelength must be a positive number of nm, got NaN"),
        (lambda: lenspath.Glass("N-BK7").index([500.0, 0.0]), "a wavelength must be a positive number of nm, got 0"),
        (lambda: _lens().focal_shift(np.array([-1.0])), "a wavelength must be a positive number of nm, got -1"),
        (
            lambda: lenspath.Scene().look_at((1e38, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
            r"look_at: eye \[1(0)+, 0, 0\] and target \[0, 0, 0\] must be finite and within ±1e18",
        ),
        (
            lambda: lenspath.render("cornell-spheres", camera=lenspath.Camera.realistic(sensor_depth_mm=1e9)),
            "would magnify 10x",
        ),
    ],
)
def test_what_would_exhaust_or_mislead_is_refused(call, message: str) -> None:
    # A 1e5-pixel kernel tried to allocate 40 GB and aborted the interpreter; a NaN wavelength gave
    # index 0; a camera 1e38 away rendered a blank image, a sensor 1e9 mm back a black one.
    with pytest.raises(ValueError, match=message):
        call()


def test_a_render_larger_than_the_memory_budget_is_refused_before_it_starts(monkeypatch) -> None:
    # 20000x20000 aborted the interpreter on a failed allocation; the budget makes it machine-independent.
    monkeypatch.setenv("LENSPATH_MAX_MEMORY", "16G")
    with pytest.raises(ValueError, match=r"a 20000x20000 render needs about 28.8 GB, more than the 17.2 GB available"):
        lenspath.render("cornell-spheres", resolution=(20000, 20000), spp=1)
    monkeypatch.setenv("LENSPATH_MAX_MEMORY", "lots")
    with pytest.raises(ValueError, match='LENSPATH_MAX_MEMORY="lots" is not a size'):
        lenspath.render("cornell-spheres", resolution=(8, 6), spp=1)
