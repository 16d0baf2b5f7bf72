"""Scenes: every loader through lenspath.load, the broken-file corpus as
Python exceptions, and scenes built from numpy arrays."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import lenspath

from .conftest import REPO

BROKEN = REPO / "crates/lenspath/tests/data/broken"


def _expected() -> list[tuple[str, str]]:
    lines = (BROKEN / "EXPECTED.txt").read_text().splitlines()
    return [
        tuple(part.strip() for part in line.split(" => ", 1))
        for line in lines
        if line.strip() and not line.startswith("#")
    ]


@pytest.mark.parametrize(("file", "message"), _expected(), ids=[f for f, _ in _expected()])
def test_broken_files_raise_scene_error_or_os_error_naming_the_file(file: str, message: str) -> None:
    with pytest.raises((lenspath.SceneError, OSError)) as info:
        lenspath.load(BROKEN / file)
    assert file in str(info.value)
    assert message in str(info.value)


@pytest.mark.parametrize("path", sorted((REPO / "scenes").glob("*.toml")), ids=lambda p: p.name)
def test_example_scene_files_load(path: Path, shared) -> None:
    scene = lenspath.load(path)
    assert scene.triangle_count + scene.sphere_count > 0
    assert scene.light_count > 0


@pytest.mark.parametrize("name", ["CBspheres_lambertian.dae", "CBbunny.dae"])
def test_cs184_scenes_load_and_render(shared, name: str) -> None:
    scene = lenspath.load(shared / "scenes/cs184/sky" / name)
    image = lenspath.render(scene, lenspath.Camera.pinhole(), spp=1, resolution=(32, 24))
    assert image.mean() > 0.01


def test_meshes_from_numpy_any_dtype() -> None:
    scene = lenspath.Scene()
    white = scene.add_material("diffuse", reflectance=(0.7, 0.7, 0.7))
    assert scene.add_material("metal", eta=(0.2, 0.9, 1.1), k=(3.9, 2.4, 2.2), roughness=0.1) == 1
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=np.float64)
    scene.add_mesh(vertices, np.array([[0, 1, 2]], dtype=np.int64), white)
    scene.add_sphere((0, 0, -2), 0.5, white, emission=(2, 2, 2))
    counts = (scene.mesh_count, scene.triangle_count, scene.sphere_count, scene.material_count, scene.light_count)
    assert counts == (1, 1, 1, 2, 1)


@pytest.mark.parametrize(
    ("add", "error", "message"),
    [
        (
            lambda s: s.add_mesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 7]], 0),
            lenspath.SceneError,
            "triangle 0 indexes a vertex beyond the 3",
        ),
        (
            lambda s: s.add_mesh([[0, 0, np.nan], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], 0),
            lenspath.SceneError,
            "NaN|finite",
        ),
        (lambda s: s.add_mesh([[0, 0], [1, 0]], [[0, 1, 2]], 0), ValueError, "N x 3"),
        (lambda s: s.add_sphere((0, 0, 0), 1.0, 5), lenspath.SceneError, "material"),
        (lambda s: s.add_material("velvet"), ValueError, "unknown material kind 'velvet'"),
        (lambda s: s.add_material("metal"), ValueError, "a metal needs eta"),
        (lambda s: s.look_at((0, 0, 0), (0, 0, 0)), ValueError, "eye and target must differ"),
    ],
)
def test_bad_scene_content_is_refused_where_it_is_added(add, error, message) -> None:
    scene = lenspath.Scene()
    scene.add_material("diffuse")
    with pytest.raises(error, match=message):
        add(scene)
    # Nothing half-added.
    assert scene.mesh_count == scene.sphere_count == 0


def test_a_scene_without_a_view_cannot_render() -> None:
    scene = lenspath.Scene()
    with pytest.raises(ValueError, match="has no view; call look_at"):
        lenspath.render(scene, spp=1, resolution=(8, 8))
