"""Images in and out, focus measures and bokeh on numpy arrays."""

from __future__ import annotations

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
    with pytest.raises(ValueError, match="edges must be"):
        lenspath.bokeh(image, aperture="circle", diameter_px=5, edges="wrap")
