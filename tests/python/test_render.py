"""lenspath.render: arrays out, the CLI's image bit for bit, determinism,
analytic scenes built in Python, the GIL, interrupts and leaks."""

from __future__ import annotations

import os
import pathlib
import signal
import subprocess
import threading

import numpy as np
import pytest

import lenspath


@pytest.mark.parametrize("name", lenspath.builtin_scenes())
def test_builtin_scenes_render_to_float_arrays(name: str) -> None:
    image = lenspath.render(name, spp=2, resolution=(40, 30))
    assert image.shape == (30, 40, 3)
    assert image.dtype == np.float32
    assert np.isfinite(image).all()
    # A lit Cornell box: everything visible is lit or is the light.
    assert 0.01 < image.mean() < 10.0


def test_a_path_naming_a_builtin_scene_is_that_scene_as_on_the_command_line() -> None:
    # The library's rule (lenspath::io::builtin_scene_named), whatever the argument's type.
    assert lenspath._core.builtin_scene_named(pathlib.Path("cornell-spheres")) == "cornell-spheres"
    assert lenspath._core.builtin_scene_named("scenes/cornell-spheres.toml") is None
    by_path = lenspath.render(pathlib.Path("cornell-spheres"), spp=1, resolution=(16, 12))
    by_name = lenspath.render("cornell-spheres", spp=1, resolution=(16, 12))
    assert np.array_equal(by_path, by_name)


def test_the_mesh_scene_takes_a_triangle_count() -> None:
    scene = lenspath.Scene.builtin("cornell-mesh", mesh_triangles=2000)
    assert 1500 < scene.triangle_count < 2500  # the knot's tessellation rounds the count
    assert lenspath.render(scene, spp=1, resolution=(16, 12)).shape == (12, 16, 3)


@pytest.mark.parametrize(
    ("camera", "sampler", "flags"),
    [
        (None, None, []),
        (lenspath.Camera.pinhole(), None, ["--camera", "pinhole"]),
        (
            lenspath.Camera.thin_lens(0.05, focus_distance=3.0),
            None,
            ["--camera", "thin-lens", "--aperture-radius", "0.05", "--focus-distance", "3"],
        ),
        (lenspath.Camera.realistic("wide22", f_number=4.0), None, ["--lens", "wide22", "--fstop", "4"]),
        (
            lenspath.Camera.realistic("wide22", f_number=16.0, diffraction=True),
            None,
            ["--lens", "wide22", "--fstop", "16", "--diffraction", "on"],
        ),
        (lenspath.Camera.pinhole(), "independent", ["--camera", "pinhole", "--sampler", "independent"]),
    ],
    ids=["default", "pinhole", "thin-lens", "realistic", "diffraction", "independent-sampler"],
)
def test_same_settings_give_the_clis_image_bit_for_bit(cli, tmp_path, camera, sampler, flags) -> None:
    out = tmp_path / "cli.exr"
    subprocess.run(
        [
            str(cli),
            "render",
            "--scene",
            "cornell-spheres",
            "--res",
            "48x36",
            "--spp",
            "3",
            "--seed",
            "5",
            "--max-depth",
            "6",
            *flags,
            "--out",
            str(out),
        ],
        check=True,
        capture_output=True,
    )
    ours = lenspath.render("cornell-spheres", camera, spp=3, resolution=(48, 36), seed=5, max_depth=6, sampler=sampler)
    theirs = lenspath.read(out)
    assert np.array_equal(ours, theirs), f"max difference {np.abs(ours - theirs).max()}"


def test_same_seed_same_image_for_any_thread_count() -> None:
    a = lenspath.render("cornell-spheres", spp=2, resolution=(32, 24), seed=9, threads=1)
    b = lenspath.render("cornell-spheres", spp=2, resolution=(32, 24), seed=9, threads=2)
    c = lenspath.render("cornell-spheres", spp=2, resolution=(32, 24), seed=10, threads=2)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


def test_depth_aov_is_the_distance_along_the_view_axis() -> None:
    # A pinhole looking straight at an emissive quad 2 units away: every
    # pixel's depth is 2 and its radiance the quad's emission. The depth is
    # exact; the colour is estimated from four wavelengths a sample (about
    # 0.3% noise per pixel at 256 spp in R and B), so it is rendered at
    # 1024 spp and checked per pixel to 1%.
    scene = lenspath.Scene()
    black = scene.add_material("diffuse", reflectance=(0, 0, 0))
    quad = np.array([[-5, -5, -2], [5, -5, -2], [5, 5, -2], [-5, 5, -2]], dtype=np.float32)
    scene.add_mesh(quad, [[0, 1, 2], [0, 2, 3]], black, emission=(0.25, 0.5, 1.0))
    scene.look_at((0, 0, 0), (0, 0, -1), fov_deg=60)
    out = lenspath.render(scene, lenspath.Camera.pinhole(), spp=1024, resolution=(20, 10), aovs=["depth"])
    assert set(out) == {"rgb", "depth"}
    np.testing.assert_allclose(out["depth"], 2.0, rtol=1e-5)
    np.testing.assert_allclose(out["rgb"], np.broadcast_to([0.25, 0.5, 1.0], (10, 20, 3)), rtol=1e-2)


@pytest.mark.parametrize("sampler", ["sobol", "independent"])
def test_a_diffuse_sphere_under_a_uniform_sky_has_its_albedo(sampler: str) -> None:
    # White furnace: a convex diffuse sphere of albedo 0.5 lit by a uniform
    # environment of radiance 1 reflects exactly 0.5 everywhere (every
    # reflected ray escapes); next-event estimation and MIS must not bias it.
    scene = lenspath.Scene()
    grey = scene.add_material("diffuse", reflectance=(0.5, 0.5, 0.5))
    scene.add_sphere((0, 0, -3), 1.0, grey)
    scene.add_environment((1.0, 1.0, 1.0))
    scene.look_at((0, 0, 0), (0, 0, -3), fov_deg=10)
    image = lenspath.render(scene, lenspath.Camera.pinhole(), spp=64, resolution=(8, 8), sampler=sampler)
    np.testing.assert_allclose(image.mean(), 0.5, rtol=0.01)


@pytest.mark.parametrize(
    ("call", "error", "message"),
    [
        (lambda: lenspath.render("cornell-spheres", spp=0), ValueError, "samples per pixel must be in 1"),
        (lambda: lenspath.render("cornell-spheres", resolution=(0, 10)), ValueError, "image size must be positive"),
        (lambda: lenspath.render("cornell-spheres", aovs=["normals"]), ValueError, "unknown AOV 'normals'"),
        (
            lambda: lenspath.render("cornell-spheres", sampler="halton"),  # type: ignore[call-overload]
            ValueError,
            "unknown sampler 'halton'; use one of sobol, independent",
        ),
        (
            lambda: lenspath.render("cornell-spheres", integrator="bdpt"),  # type: ignore[call-overload]
            ValueError,
            "unknown integrator 'bdpt'; use one of path, guided",
        ),
        (
            lambda: lenspath.render("cornell-spheres", threads=100_000),
            ValueError,
            "100000 threads asked for; at most 1024",
        ),
        (lambda: lenspath.render("no-such-scene.obj"), OSError, "no-such-scene.obj"),
        (lambda: lenspath.render(42), TypeError, "scene must be"),
        (lambda: lenspath.Camera.realistic("nikkor"), ValueError, "unknown built-in lens 'nikkor'"),
        (lambda: lenspath.Camera.thin_lens(-1.0), ValueError, "aperture_radius must be zero or positive"),
        (lambda: lenspath.Camera.realistic(aperture="blades:2"), ValueError, "blades"),
        (lambda: lenspath.Camera.realistic(focus_distance=2.0, sensor_depth_mm=52.0), ValueError, "not both"),
    ],
)
def test_bad_arguments_raise_with_a_clear_message(call, error, message) -> None:
    with pytest.raises(error, match=message):
        call()


def test_the_gil_is_released_while_rendering() -> None:
    ticks = 0
    done = threading.Event()

    def count() -> None:
        nonlocal ticks
        while not done.is_set():
            ticks += 1

    counter = threading.Thread(target=count)
    counter.start()
    try:
        lenspath.render("cornell-spheres", spp=16, resolution=(96, 72), threads=1)
    finally:
        done.set()
        counter.join()
    # With the GIL held for the whole render the counter would barely move.
    assert ticks > 10_000


def test_an_exception_in_the_progress_callback_stops_the_render() -> None:
    calls = []

    def progress(done: int, total: int) -> None:
        calls.append((done, total))
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        lenspath.render("cornell-spheres", spp=60_000, resolution=(64, 48), progress=progress)
    # Stopped at the first report, long before its 184 M samples.
    assert len(calls) == 1


@pytest.mark.skipif(not hasattr(signal, "SIGINT") or os.name != "posix", reason="needs POSIX signals")
def test_ctrl_c_stops_the_render_and_raises_keyboard_interrupt() -> None:
    reports = []
    # Python's Ctrl-C handler, as an interactive session has it: a process
    # started as a background job (`cmd &` in a script) inherits SIGINT ignored.
    previous_handler = signal.signal(signal.SIGINT, signal.default_int_handler)
    # A real SIGINT to this process while the render runs, as Ctrl-C sends.
    timer = threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            lenspath.render(
                "cornell-spheres", spp=60_000, resolution=(64, 48), progress=lambda d, t: reports.append((d, t))
            )
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, previous_handler)
    # It stopped where it was, far short of its 184 M samples.
    done, total = reports[-1]
    assert total == 64 * 48 * 60_000
    assert done < total // 10


def test_progress_reports_reach_the_total() -> None:
    reports = []
    lenspath.render("cornell-spheres", spp=2, resolution=(32, 24), progress=lambda d, t: reports.append((d, t)))
    assert reports[-1] == (32 * 24 * 2, 32 * 24 * 2)


def _resident_mb() -> float:
    with open("/proc/self/statm") as f:
        pages = int(f.read().split()[1])
    return pages * 4096 / 2**20


@pytest.mark.skipif(not __import__("os").path.exists("/proc/self/statm"), reason="needs /proc (Linux)")
def test_repeated_renders_do_not_leak() -> None:
    import sys

    image = lenspath.render("cornell-spheres", spp=1, resolution=(128, 96))
    assert sys.getrefcount(image) == 2  # the name and getrefcount's argument
    for _ in range(5):
        lenspath.render("cornell-spheres", spp=1, resolution=(128, 96))
    before = _resident_mb()
    for _ in range(40):
        lenspath.render("cornell-spheres", spp=1, resolution=(128, 96))
    # 40 renders of a 147 kB image: a leak of even one image each would add 6 MB.
    assert _resident_mb() - before < 4.0


def test_the_old_name_of_the_sensor_depth_still_works_and_says_the_new_one() -> None:
    with pytest.warns(DeprecationWarning, match="use sensor_depth_mm"):
        old = lenspath.Camera.realistic("dgauss50", sensor_mm=52.0)
    new = lenspath.Camera.realistic("dgauss50", sensor_depth_mm=52.0)
    args = {"spp": 1, "resolution": (32, 24)}
    assert np.array_equal(
        lenspath.render("cornell-spheres", old, **args), lenspath.render("cornell-spheres", new, **args)
    )
    with pytest.raises(ValueError, match="not also sensor_mm"):
        lenspath.Camera.realistic(sensor_mm=52.0, sensor_depth_mm=52.0)


@pytest.mark.parametrize("fov_deg", [float("nan"), 0.0, 180.0, -10.0])
@pytest.mark.parametrize("make", [lenspath.Camera.pinhole, lambda fov: lenspath.Camera.thin_lens(0.05, fov_deg=fov)])
def test_python_cameras_get_the_library_checks(make, fov_deg: float) -> None:
    """The check the CLI's --fov had is the library's now (lenspath::setup), so Python gets it too."""
    with pytest.raises(ValueError, match="field of view must be between 0 and 180 degrees"):
        lenspath.render("cornell-spheres", make(fov_deg), spp=1, resolution=(8, 6))
