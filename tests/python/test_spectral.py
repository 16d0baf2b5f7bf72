"""Spectral rendering from Python: catalogue glasses, dispersive and
measured materials, and renders that stay RGB-compatible."""

from __future__ import annotations

import numpy as np
import pytest

import lenspath


def test_glass_index_matches_the_schott_datasheet() -> None:
    bk7 = lenspath.Glass("N-BK7")
    assert (bk7.maker, bk7.name) == ("schott", "N-BK7")
    assert bk7.index(587.5618) == pytest.approx(1.5168, abs=1e-5)
    # F and C lines from Schott's N-BK7 datasheet.
    assert np.allclose(bk7.index([486.1327, 656.2725]), [1.52238, 1.51432], atol=1e-5)
    assert bk7.v_d == pytest.approx(64.17, abs=0.02)
    model = lenspath.Glass.abbe(1.5168, 64.17)
    assert model.maker is None
    assert model.n_d == pytest.approx(1.5168) and model.v_d == pytest.approx(64.17)


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: lenspath.Glass("N-BK8"), "unknown glass 'N-BK8'"),
        (lambda: lenspath.Glass("zeiss:BK7"), "unknown glass maker 'zeiss'"),
        (lambda: lenspath.Glass.abbe(1.5, -3.0), "V_d must be a positive Abbe number"),
    ],
)
def test_bad_glasses_are_refused(make, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        make()


def _sphere_scene(**material) -> lenspath.Scene:
    scene = lenspath.Scene()
    m = scene.add_material(**material)
    scene.add_sphere((0.0, 0.0, 0.0), 1.0, m)
    scene.add_environment((1.0, 1.0, 1.0))
    scene.look_at((0.0, 0.0, 4.0), (0.0, 0.0, 0.0), fov_deg=20.0)
    return scene


@pytest.mark.parametrize(
    ("material", "match"),
    [
        ({"kind": "dielectric", "eta": (1.5, 1.5, 1.5), "glass": "N-BK7"}, "one of eta, glass, or n_d"),
        ({"kind": "dielectric", "v_d": 40.0}, "one of eta, glass, or n_d"),
        ({"kind": "conductor", "metal": "unobtainium"}, "unknown metal 'unobtainium'"),
        ({"kind": "conductor", "metal": "gold", "eta": (1, 1, 1), "k": (1, 1, 1)}, "either eta and k"),
    ],
)
def test_bad_materials_are_refused(material: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        lenspath.Scene().add_material(**material)


def test_white_furnace_holds_for_dispersive_glass_and_measured_silver_is_bright() -> None:
    """A sphere of catalogue glass in a white environment vanishes (every
    wavelength is conserved, whatever way it bends); polished silver reflects
    above 90% of a white environment, gold reflects red more than blue."""
    camera = lenspath.Camera.pinhole()
    glass = lenspath.render(_sphere_scene(kind="dielectric", glass="SF11"), camera=camera, spp=64, resolution=(16, 16))
    centre = glass[4:12, 4:12].reshape(-1, 3).mean(axis=0)
    assert np.allclose(centre, 1.0, atol=0.02), centre
    silver = lenspath.render(
        _sphere_scene(kind="conductor", metal="silver"), camera=camera, spp=16, resolution=(16, 16)
    )
    assert silver[6:10, 6:10].mean() > 0.9
    gold = lenspath.render(_sphere_scene(kind="conductor", metal="Au"), camera=camera, spp=16, resolution=(16, 16))
    red, _, blue = gold[6:10, 6:10].reshape(-1, 3).mean(axis=0)
    assert red > 2 * blue, (red, blue)


def test_lights_given_as_spectra_render_in_their_colour() -> None:
    """A white sphere under a 3200 K black-body sky renders the black body's
    colour (the CIE integral ``Emission.rgb`` gives), as does one lit by a
    point light whose spectrum is a table."""
    lamp = lenspath.Emission.blackbody(3200.0, luminance=1.0)
    assert "3200 K" in repr(lamp)
    scene = lenspath.Scene()
    white = scene.add_material("diffuse", reflectance=(1.0, 1.0, 1.0))
    scene.add_sphere((0.0, 0.0, 0.0), 1.0, white)
    scene.add_environment(lamp)
    scene.look_at((0.0, 0.0, 4.0), (0.0, 0.0, 0.0), fov_deg=20.0)
    image = lenspath.render(scene, lenspath.Camera.pinhole(), spp=256, resolution=(16, 16))
    centre = image[4:12, 4:12].reshape(-1, 3).mean(axis=0)
    assert np.allclose(centre, lamp.rgb, rtol=0.02), (centre, lamp.rgb)
    red, _, blue = lamp.rgb
    assert red > 1.5 * blue  # a tungsten lamp is warm
    green = lenspath.Emission.tabulated([500.0, 530.0, 560.0], [0.0, 1.0, 0.0], luminance=2.0)
    assert green.rgb[1] > max(green.rgb[0], green.rgb[2])


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: lenspath.Emission.blackbody(100.0), "gives no visible light"),
        (lambda: lenspath.Emission.blackbody(-5.0), "temperature must be positive"),
        (lambda: lenspath.Emission.tabulated([900.0, 1000.0], [1.0, 1.0]), "no visible light"),
        (lambda: lenspath.Emission.tabulated([500.0, 400.0], [1.0, 1.0]), "wavelengths must increase"),
        (lambda: lenspath.Emission.tabulated([500.0, 600.0], [1.0]), "one value each"),
    ],
)
def test_bad_light_spectra_are_refused(make, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        make()


def test_a_monochromatic_render_is_grey_and_reads_the_spectral_radiance() -> None:
    """At one wavelength every channel is the same; the sky of a table lamp
    reads the table's (scaled) value there, and nothing outside the table."""
    scene = lenspath.Scene()
    scene.add_environment(lenspath.Emission.tabulated([500.0, 600.0], [1.0, 1.0]))
    scene.look_at((0.0, 0.0, 4.0), (0.0, 0.0, 0.0), fov_deg=20.0)
    camera = lenspath.Camera.pinhole()
    inside = lenspath.render(scene, camera, spp=4, resolution=(8, 8), wavelength_nm=550.0)
    assert np.all(inside == inside[0, 0, 0]) and inside[0, 0, 0] > 0
    outside = lenspath.render(scene, camera, spp=4, resolution=(8, 8), wavelength_nm=450.0)
    assert np.all(outside == 0.0)
    with pytest.raises(ValueError, match="wavelength must be in 360..=830 nm"):
        lenspath.render(scene, camera, spp=1, resolution=(8, 8), wavelength_nm=1000.0)


def test_lens_colour_figures_from_python_match_the_cli(cli) -> None:
    """``Lens.chromatic()`` gives the numbers ``lenspath lens --json`` prints,
    ``focal_shift`` is zero at the d line and is BFD(F) - BFD(d) at F, and a
    ray traced at two wavelengths through dgauss50 leaves in two directions."""
    import json
    import subprocess

    lens = lenspath.Lens.builtin("dgauss50")
    figures = lens.chromatic()
    printed = json.loads(subprocess.run([cli, "lens", "dgauss50", "--json"], capture_output=True, check=True).stdout)
    assert figures["longitudinal_color_mm"] == pytest.approx(printed["longitudinal_color_mm"], rel=1e-12)
    assert figures["lateral_color_mm"] == pytest.approx(printed["lateral_color_mm"], rel=1e-12)
    for line in "gFdC":
        assert figures["lines"][line] == pytest.approx(printed["lines"][line], rel=1e-12)
    lines = figures["lines"]
    shift = lens.focal_shift([lines["d"]["wavelength_nm"], lines["F"]["wavelength_nm"]])
    assert shift[0] == pytest.approx(0.0, abs=1e-12)
    assert shift[1] == pytest.approx(
        lines["F"]["back_focal_distance_mm"] - lines["d"]["back_focal_distance_mm"], rel=1e-9
    )
    origin, direction = np.array([[0.0, 5.0, 40.0]]), np.array([[0.0, -0.05, -1.0]])
    _, blue, _ = lens.trace(origin, direction, wavelength_nm=450.0)
    _, red, _ = lens.trace(origin, direction, wavelength_nm=650.0)
    assert not np.allclose(blue, red, rtol=0, atol=1e-9)
    assert "<svg" in lens.focal_shift_plot()


def test_a_dispersive_lens_keeps_its_glasses_through_pickle_and_its_table_text(tmp_path) -> None:
    """dgauss50's glass column survives pickling (what ``lenspath.distributed`` sends to
    workers) and ``table_text`` (a file ``Lens.load`` reads back)."""
    import pickle

    lens = lenspath.Lens.builtin("dgauss50").stopped_down(4.0)
    copy = pickle.loads(pickle.dumps(lens))
    assert copy.chromatic() == lens.chromatic() and copy.f_number == lens.f_number
    assert lens.chromatic()["longitudinal_color_mm"] < -0.05
    assert "47.1" in lens.table_text.splitlines()[0]
    path = tmp_path / "dgauss50.dat"
    path.write_text(lens.table_text)
    assert lenspath.Lens.load(path).chromatic() == lenspath.Lens.builtin("dgauss50").chromatic()


def test_a_camera_without_dispersion_is_the_scene_files_and_keeps_its_wavelengths(tmp_path) -> None:
    """``Camera.realistic(dispersion=False)`` and a scene file's ``dispersion = false`` give one
    image, which differs from the dispersive default's and is less noisy in colour (the
    dispersive lens weighs each wavelength by where it lands: measured 1.4x the colour noise)."""
    scene_file = tmp_path / "plain.toml"
    scene_file.write_text(
        'builtin = "cornell-spheres"\n[camera]\neye = [0, 1, 3.9]\nlook_at = [0, 1, 0]\ndispersion = false\n'
    )
    options = {"spp": 8, "resolution": (48, 36)}
    by_keyword = lenspath.render(scene_file, lenspath.Camera.realistic(dispersion=False), **options)
    by_file = lenspath.render(scene_file, **options)
    assert np.array_equal(by_keyword, by_file)
    dispersive = lenspath.render(scene_file, lenspath.Camera.realistic(dispersion=True), **options)
    assert not np.array_equal(dispersive, by_file)

    def chroma_noise(camera: lenspath.Camera) -> float:
        # Two seeds' difference holds only noise; less its grey, only colour noise.
        a, b = (lenspath.render(scene_file, camera, seed=seed, **options) for seed in (1, 2))
        return float(np.std((a - a.mean(axis=2, keepdims=True)) - (b - b.mean(axis=2, keepdims=True))))

    plain_noise = chroma_noise(lenspath.Camera.realistic(dispersion=False))
    assert 1.2 * plain_noise < chroma_noise(lenspath.Camera.realistic(dispersion=True))
