"""Images in and out, focus measures and bokeh on numpy arrays."""

from __future__ import annotations

import subprocess

import numpy as np
import pytest

import lenspath


def _checker(size: int = 64, square: int = 4) -> np.ndarray:
    y, x = np.mgrid[0:size, 0:size]
    board = (((x // square) + (y // square)) % 2).astype(np.float32)
    return np.repeat(board[:, :, None], 3, axis=2) * 0.8 + 0.1


def test_exr_round_trips_exactly(tmp_path) -> None:
    image = np.random.default_rng(3).random((20, 30, 3), dtype=np.float32) * 5
    lenspath.write(tmp_path / "a.exr", image)
    np.testing.assert_array_equal(lenspath.read(tmp_path / "a.exr"), image)


def test_png_round_trips_within_one_code_value(tmp_path) -> None:
    image = np.random.default_rng(4).random((20, 30, 3), dtype=np.float32)
    lenspath.write(tmp_path / "a.png", image)
    back = lenspath.read(tmp_path / "a.png")
    # sRGB 8-bit: the code values are at most half a step apart, and a step is at most 1/80 in linear light near 1.
    assert np.abs(back - image).max() < 0.01


@pytest.mark.parametrize(("dtype", "full_scale"), [(np.uint8, 255), (np.uint16, 65535)])
def test_integer_images_are_srgb_encoded(tmp_path, dtype, full_scale: int) -> None:
    # An 8- or 16-bit image is what Pillow, imageio and OpenCV give for a PNG: its values are
    # sRGB-encoded, so a uint8 render written back must match the float one, not turn white.
    linear = np.random.default_rng(5).random((12, 16, 3), dtype=np.float32)
    encoded = np.where(linear <= 0.0031308, 12.92 * linear, 1.055 * linear ** (1 / 2.4) - 0.055)
    ints = np.round(encoded * full_scale).astype(dtype)
    lenspath.write(tmp_path / "ints.exr", ints)
    # Half a code value, times the decoding's steepest slope (2.28, at white).
    np.testing.assert_allclose(lenspath.read(tmp_path / "ints.exr"), linear, atol=0.5 * 2.28 / full_scale)


def test_grey_images_are_2d_arrays(tmp_path) -> None:
    grey = np.random.default_rng(6).random((10, 14), dtype=np.float32)
    lenspath.write(tmp_path / "grey.exr", grey)
    np.testing.assert_array_equal(lenspath.read(tmp_path / "grey.exr"), np.repeat(grey[:, :, None], 3, axis=2))
    board = _checker()
    assert lenspath.focus_measure(board[:, :, 0]) == lenspath.focus_measure(board)
    blurred = lenspath.bokeh(board[:, :, 0], aperture="circle", diameter_px=5)
    assert blurred.shape == (64, 64, 3)
    with pytest.raises(ValueError, match=r"drop the alpha channel with image\[\.\.\., :3\]"):
        lenspath.write(tmp_path / "rgba.exr", np.zeros((4, 4, 4), dtype=np.float32))


def test_classes_say_what_they_are() -> None:
    lens = lenspath.Lens.builtin("dgauss50")
    camera = lenspath.Camera.realistic(lens, f_number=2.8, focus_distance=2.5)
    assert repr(camera) == "Camera.realistic(lens='dgauss50', focus_distance=2.5, f_number=2.8)"
    assert repr(lenspath.Camera.pinhole(fov_deg=30)) == "Camera.pinhole(fov_deg=30)"
    assert repr(lenspath.Camera.thin_lens()) == "Camera.thin_lens()"
    for thing in (lens, lenspath.Scene.builtin("cornell-empty"), lenspath.Glass("N-BK7"), lenspath.Sensor("ideal")):
        assert " object at 0x" not in repr(thing), repr(thing)


def test_image_errors(tmp_path) -> None:
    with pytest.raises(ValueError, match="H x W x 3"):
        lenspath.write(tmp_path / "a.exr", np.zeros((4, 4, 2), dtype=np.float32))
    with pytest.raises(OSError, match="nothing.png"):
        lenspath.read(tmp_path / "nothing.png")
    with pytest.raises(ValueError, match=r"\.tiff"):
        lenspath.write(tmp_path / "a.tiff", np.zeros((4, 4, 3), dtype=np.float32))


@pytest.mark.parametrize("metric", lenspath.focus_measures())
def test_every_focus_measure_falls_as_the_image_is_blurred_more(metric: str) -> None:
    sharp = _checker()
    scores = [lenspath.focus_measure(sharp, metric)]
    for diameter in [3, 5, 9, 15]:
        scores.append(lenspath.focus_measure(lenspath.bokeh(sharp, aperture="circle", diameter_px=diameter), metric))
    assert all(a > b for a, b in zip(scores, scores[1:], strict=False)), scores


def test_unknown_focus_measure() -> None:
    with pytest.raises(ValueError, match="sharpness"):
        lenspath.focus_measure(_checker(), "sharpness")


@pytest.mark.parametrize("aperture", ["circle", "blades:6", "star:5:0.4"])
def test_bokeh_keeps_a_uniform_image_uniform_and_agrees_across_methods(aperture: str) -> None:
    flat = np.full((40, 50, 3), 0.3, dtype=np.float32)
    np.testing.assert_allclose(lenspath.bokeh(flat, aperture=aperture, diameter_px=11), 0.3, rtol=1e-4)
    image = _checker(48)
    direct = lenspath.bokeh(image, aperture=aperture, diameter_px=11, method="direct")
    fft = lenspath.bokeh(image, aperture=aperture, diameter_px=11, method="fft")
    np.testing.assert_allclose(direct, fft, atol=1e-5)


def test_a_point_light_becomes_the_mask() -> None:
    mask = np.zeros((9, 9), dtype=np.float32)
    mask[2:7, 4] = 1.0  # a vertical bar
    image = np.zeros((31, 31, 3), dtype=np.float32)
    image[15, 15] = 1.0
    out = lenspath.bokeh(image, mask=mask, edges="black")
    assert out.sum() == pytest.approx(3.0, rel=1e-5)  # energy kept
    lit = np.argwhere(out[:, :, 0] > 1e-6)
    assert set(lit[:, 1]) == {15} and len(lit) == 5


def test_bokeh_errors() -> None:
    image = _checker()
    with pytest.raises(ValueError, match="give aperture"):
        lenspath.bokeh(image)
    with pytest.raises(ValueError, match="needs diameter_px"):
        lenspath.bokeh(image, aperture="blades:6")
    with pytest.raises(ValueError, match="unknown edge treatment 'wrap'; use one of renormalize, black"):
        lenspath.bokeh(image, aperture="circle", diameter_px=5, edges="wrap")


def test_lens_blur_gives_the_clis_image_bit_for_bit(cli, tmp_path) -> None:
    rendered = tmp_path / "render.exr"
    blurred = tmp_path / "blurred.exr"
    common = ["--res", "64x48", "--spp", "2", "--camera", "pinhole"]
    subprocess.run([str(cli), "render", *common, "--out", str(rendered)], check=True, capture_output=True)
    lens_flags = ["--focus-distance", "2.5", "--focal-length", "50", "--fstop", "1.4", "--mask", "blades:6"]
    subprocess.run(
        [str(cli), "bokeh", str(rendered), *lens_flags, "--out", str(blurred)], check=True, capture_output=True
    )
    out = lenspath.render("cornell-spheres", lenspath.Camera.pinhole(), spp=2, resolution=(64, 48), aovs=["depth"])
    ours = lenspath.lens_blur(out["rgb"], out["depth"], 2.5, focal_length_mm=50, f_number=1.4, aperture="blades:6")
    assert np.array_equal(ours, lenspath.read(blurred))
    assert not np.array_equal(ours, out["rgb"])


def test_lens_blur_keeps_the_focus_plane_sharp() -> None:
    image = np.random.default_rng(3).random((40, 60, 3), dtype=np.float32)
    sharp = lenspath.lens_blur(image, np.full((40, 60), 2.0), 2.0, lens="dgauss50")
    np.testing.assert_allclose(sharp, image, atol=1e-6)


def test_lens_blur_spreads_a_point_over_the_thin_lens_circle_of_confusion() -> None:
    # One bright pixel and the black around it, all 10 m away, the lens focused at 0.6 m.
    size, width_mm = 201, 36.0
    image = np.zeros((size, size, 3), np.float32)
    image[100, 100] = 1.0
    lens = lenspath.Lens.builtin("dgauss50")
    blurred = lenspath.lens_blur(image, np.full((size, size), 10.0), 0.6, lens=lens, sensor_width_mm=width_mm)
    # Thin lens (Potmesil and Chakravarty 1981): c = A s (1/D - 1/z), A = f/N, 1/s = 1/f - 1/D.
    f, n = lens.effective_focal_length_mm, lens.f_number
    s_mm = f * 600.0 / (600.0 - f)
    diameter_px = f / n * s_mm * (1 / 600.0 - 1 / 10_000.0) * size / width_mm
    y, x = np.mgrid[0:size, 0:size] - 100
    weights = blurred[:, :, 0]
    np.testing.assert_allclose(weights.sum(), 1.0, rtol=1e-3)  # energy kept
    # A uniform disc of diameter d has a mean squared radius of d^2 / 8.
    mean_r2 = (weights * (x**2 + y**2)).sum() / weights.sum()
    np.testing.assert_allclose(np.sqrt(8 * mean_r2), diameter_px, rtol=0.03)
    assert diameter_px > 10  # wide enough for the moments to measure it


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({}, "describe one lens"),
        ({"lens": "dgauss50", "focal_length_mm": 50}, "describe one lens"),
        ({"focal_length_mm": 50}, "focal_length_mm needs f_number"),
        ({"aperture_radius": 0.1}, "aperture_radius needs fov_deg"),
        ({"focal_length_mm": 50, "f_number": 2, "scene_unit_m": 0}, "scene unit must be a positive"),
        ({"lens": "dgauss50", "aperture": np.full((4, 4), -1.0)}, "finite and not negative"),
        ({"lens": "dgauss50", "aperture": 7}, "aperture must be a shape name"),
    ],
)
def test_lens_blur_errors(kwargs, message: str) -> None:
    image = np.zeros((8, 8, 3), np.float32)
    with pytest.raises(ValueError, match=message):
        lenspath.lens_blur(image, np.ones((8, 8)), 2.0, **kwargs)
    with pytest.raises(ValueError, match="depth must be 8 x 8 like the image"):
        lenspath.lens_blur(image, np.ones((8, 9)), 2.0, lens="dgauss50")


@pytest.mark.parametrize(
    ("aperture", "open_fraction"),
    [
        (None, 1.0),
        (np.ones((12, 12)), 1.0),  # all open: the circle clips it to the circle
        (np.repeat([[1.0] * 32 + [0.0] * 32], 64, axis=0), 0.5),  # the left half
        ("blades:6", 3 * np.sqrt(3) / (2 * np.pi)),  # a hexagon inscribed in the stop
    ],
    ids=["circle", "open-mask", "half-mask", "hexagon"],
)
def test_a_shaped_aperture_passes_its_open_fraction_of_the_light(aperture, open_fraction: float) -> None:
    # Under a uniform sky of radiance 1 every ray brings 1 times its aperture weight.
    scene = lenspath.Scene()
    scene.add_environment((1.0, 1.0, 1.0))
    scene.look_at((0, 0, 0), (0, 0, -1), fov_deg=30)
    camera = lenspath.Camera.thin_lens(0.1, focus_distance=1.0, aperture=aperture)
    image = lenspath.render(scene, camera, spp=64, resolution=(32, 32))
    np.testing.assert_allclose(image.mean(), open_fraction, rtol=0.01)


def test_a_mask_array_shapes_the_defocus_blur() -> None:
    square = lenspath.Camera.thin_lens(0.2, focus_distance=1.0, aperture=np.ones((16, 16)))
    disc = lenspath.Camera.thin_lens(0.2, focus_distance=1.0)
    a = lenspath.render("cornell-spheres", square, spp=4, resolution=(48, 36))
    b = lenspath.render("cornell-spheres", disc, spp=4, resolution=(48, 36))
    assert not np.array_equal(a, b)
