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
