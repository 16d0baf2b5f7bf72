"""lenspath.autofocus: the CLI's answer for the same settings, a camera focused
where it says, the errors; and the matplotlib drawings of lenspath.plot."""

from __future__ import annotations

import json
import subprocess

import numpy as np
import pytest

import lenspath

#: The README's patch: the nearer sphere of cornell-spheres.
NEAR_SPHERE = (0.52, 0.70, 0.10, 0.12)


@pytest.mark.parametrize("strategy", ["fast", "early-exit", "rangefinder", "depth"])
def test_same_settings_give_the_clis_answer(cli, strategy: str) -> None:
    args = ["--scene", "cornell-spheres", "--patch", "0.52,0.70,0.10,0.12", "--res", "160x120", "--spp", "4"]
    out = subprocess.run(
        [str(cli), "autofocus", *args, "--strategy", strategy, "--fstop", "2.8", "--json"],
        check=True,
        capture_output=True,
        text=True,
    )
    theirs = json.loads(out.stdout)
    camera = lenspath.Camera.realistic("dgauss50", f_number=2.8)
    ours = lenspath.autofocus("cornell-spheres", NEAR_SPHERE, camera, strategy=strategy, spp=4, resolution=(160, 120))
    assert ours.strategy == theirs["strategy"] == strategy
    assert ours.sensor_depth_mm == theirs["sensor_depth_mm"]
    assert ours.focus_distance == theirs["focus_distance"]
    assert ours.camera_rays == theirs["camera_rays"]
    assert ours.evaluations.shape == (theirs["evaluations"], 2)
    assert ours.patch_renders == theirs["patch_renders"]
    assert ours.light_fields == theirs["light_fields"]
    assert ours.depth_of_focus_mm == theirs["depth_of_focus_mm"]
    assert ours.fallbacks == theirs["fallbacks"]


def test_a_strategy_that_cannot_do_what_it_is_named_for_says_so() -> None:
    # At 64x48 and 1 spp the fast search's budget leaves too few rays for its light field.
    starved = lenspath.autofocus("cornell-spheres", NEAR_SPHERE, strategy="fast", spp=1, resolution=(64, 48))
    assert starved.light_fields == 0
    assert len(starved.fallbacks) == 1
    assert "under 2 samples per pixel" in starved.fallbacks[0]
    assert "fallbacks=" in repr(starved)
    # Only sky in the patch: no probe ray hits anything, so range finding falls back to contrast.
    sky = lenspath.Scene()
    grey = sky.add_material("diffuse")
    sky.add_sphere((0.0, -1.0, 0.0), 0.5, grey)
    sky.add_environment((1.0, 1.0, 1.0))
    sky.look_at((0.0, 0.0, 5.0), (0.0, 0.0, 0.0))
    blind = lenspath.autofocus(sky, (0.0, 0.0, 0.2, 0.2), strategy="rangefinder", spp=1, resolution=(64, 48))
    assert any("no surface in the patch to range on" in f for f in blind.fallbacks), blind.fallbacks


@pytest.mark.parametrize("signal", ["raw-green", "luminance"])
def test_through_a_sensor_the_cli_and_python_focus_on_the_same_frames(cli, signal: str) -> None:
    # Dim light (2 cd/m² from a white emitter of 1): the frames are metered to the
    # longest exposure time, and the ISO rises.
    args = ["--scene", "cornell-spheres", "--patch", "0.52,0.70,0.10,0.12", "--res", "160x120", "--spp", "4"]
    sensor = ["--sensor-model", "ideal", "--auto-exposure", "--white-luminance", "2", "--af-signal", signal]
    out = subprocess.run(
        [str(cli), "autofocus", *args, *sensor, "--strategy", "fast", "--json"],
        check=True,
        capture_output=True,
        text=True,
    )
    theirs = json.loads(out.stdout)
    dim = lenspath.Sensor("ideal", auto_exposure=True, white_luminance_cd_m2=2.0)
    ours = lenspath.autofocus(
        "cornell-spheres", NEAR_SPHERE, spp=4, resolution=(160, 120), sensor=dim, sensor_signal=signal
    )
    assert ours.sensor_depth_mm == theirs["sensor_depth_mm"]
    assert (ours.exposure_time_s, ours.iso) == (theirs["exposure_time_s"], theirs["iso"])
    assert ours.exposure_time_s == pytest.approx(1 / 30)
    assert ours.iso > 55
    assert np.array_equal(ours.evaluations[:, 1], [p["score"] for p in theirs["points"]])
    # Without a sensor the same search has no exposure.
    plain = lenspath.autofocus("cornell-spheres", NEAR_SPHERE, spp=4, resolution=(160, 120))
    assert (plain.exposure_time_s, plain.iso) == (None, None)


def test_the_focused_camera_renders_the_patch_sharper_than_either_side_of_it() -> None:
    # 64 samples: through the dispersive dgauss50 the depth strategy's contrast refinement
    # needed more than the default 16 to stay within a depth of focus of the contrast peak
    # (measured before the lens's wavelengths were weighted; see docs/autofocus.md).
    camera = lenspath.Camera.realistic("dgauss50")
    result = lenspath.autofocus("cornell-spheres", NEAR_SPHERE, camera, strategy="depth", resolution=(320, 240), spp=64)
    assert result.focus_distance is not None
    assert "sensor_depth_mm" in repr(result)
    patch = (166, 168, 32, 29)  # the patch in pixels at 320 x 240

    def sharpness(camera: lenspath.Camera) -> float:
        # The patch alone at 1024 samples, scored on luminance as autofocus scores it.
        image = lenspath.render("cornell-spheres", camera, spp=1024, resolution=(320, 240), max_depth=4, crop=patch)
        luminance = image @ np.array([0.2126, 0.7152, 0.0722], np.float32)
        return lenspath.focus_measure(np.repeat(luminance[..., None], 3, axis=2), "tenengrad")

    # 8 DoF either side the sphere's edge is visibly soft (the score about 0.6 of the focused one).
    shift = 8 * result.depth_of_focus_mm
    focused = sharpness(result.camera)
    for z in (result.sensor_depth_mm - shift, result.sensor_depth_mm + shift):
        assert focused > 1.3 * sharpness(lenspath.Camera.realistic("dgauss50", sensor_depth_mm=z)), z


def test_the_sweep_visits_every_pixel_pitch_and_keeps_its_best() -> None:
    result = lenspath.autofocus("cornell-spheres", NEAR_SPHERE, strategy="sweep", spp=2, resolution=(80, 60))
    z, score = result.evaluations[:, 0], result.evaluations[:, 1]
    assert np.all(np.diff(z) > 0)
    assert result.sensor_depth_mm == z[np.argmax(score)]


@pytest.mark.parametrize(
    ("kwargs", "error", "message"),
    [
        ({"patch": (0.9, 0.5, 0.2, 0.1)}, ValueError, "inside it"),
        ({"patch": (0.5, 0.5, 0.0, 0.1)}, ValueError, "inside it"),
        ({"strategy": "phase"}, ValueError, "unknown autofocus strategy 'phase'"),
        ({"metric": "sharpness"}, ValueError, "unknown focus measure 'sharpness'"),
        ({"camera": lenspath.Camera.pinhole()}, ValueError, "realistic camera"),
        ({"spp": 0}, ValueError, "at least 1 sample per pixel"),
        ({"sensor": lenspath.Sensor(), "sensor_signal": "blue"}, ValueError, "unknown autofocus sensor signal 'blue'"),
    ],
)
def test_bad_arguments_raise_with_a_clear_message(kwargs, error, message) -> None:
    args = {"patch": NEAR_SPHERE} | kwargs
    with pytest.raises(error, match=message):
        lenspath.autofocus("cornell-spheres", resolution=(64, 48), **args)


@pytest.fixture
def axes():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure = plt.figure()
    yield figure.add_subplot()
    plt.close(figure)


@pytest.mark.parametrize("name", ["dgauss50", "wide22", "tele250", "fisheye10", "lentil:0001", "lentil:0014"])
def test_lens_layout_draws_every_glass_element_and_the_ray_fans(axes, name: str) -> None:
    import lenspath.plot

    lens = lenspath.Lens.builtin(name)
    layout = lens.layout()
    table = lens.table
    # An element is a gap filled with glass (index above 1) between two surfaces.
    assert len(layout["elements"]) == int(np.sum(table[:-1, 2] > 1.0))
    assert len(layout["rays"]) >= 3 * 5  # three fields, most rays of each fan pass
    sensor = layout["sensor"]
    assert sensor[0, 0] == pytest.approx(lens.infinity_focus_mm)
    # Rays from infinity on axis meet at the sensor's centre, within the lens's aberration.
    # A lens whose glasses disperse (dgauss50, the lentil designs) has its fans drawn at the F, d
    # and C lines.
    disperses = lens.chromatic()["longitudinal_color_mm"] != 0.0
    assert disperses == (name == "dgauss50" or name.startswith("lentil:"))
    assert {round(wavelength, 1) for _, wavelength, _, _ in layout["rays"]} == (
        {486.1, 587.6, 656.3} if disperses else {587.6}
    )
    on_axis = [path for field, _, _, path in layout["rays"] if field == 0.0]
    # 0.2 mm at 50 mm f/2; the 100 mm f/1.1 double Gauss and the aspheric fisheye blur more.
    assert max(abs(path[-1, 1]) for path in on_axis) < (0.2 if not name.startswith("lentil") else 0.3)
    lenspath.plot.lens_layout(lens, ax=axes)
    assert len(axes.patches) == len(layout["elements"])


def test_focus_curve_draws_the_search(axes) -> None:
    import lenspath.plot

    result = lenspath.autofocus("cornell-spheres", NEAR_SPHERE, strategy="fast", spp=2, resolution=(80, 60))
    lenspath.plot.focus_curve(result, ax=axes)
    line = axes.lines[0]
    assert len(line.get_xdata()) == len(result.evaluations)


def test_the_old_name_of_the_chosen_sensor_depth_still_works_and_says_the_new_one() -> None:
    result = lenspath.autofocus(
        "cornell-spheres", (0.52, 0.70, 0.10, 0.12), resolution=(64, 48), strategy="rangefinder"
    )
    with pytest.warns(DeprecationWarning, match="use sensor_depth_mm"):
        assert result.sensor_mm == result.sensor_depth_mm
