"""Scenes: every loader through lenspath.load, the broken-file corpus as
Python exceptions, and scenes built from numpy arrays."""

from __future__ import annotations

import pickle
import subprocess
from pathlib import Path

import numpy as np
import pytest

import lenspath

from .conftest import REPO, SHARED, absent_shared_reason, scene_needs_shared

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


EXAMPLE_SCENES = sorted((REPO / "scenes").glob("*.toml"))


@pytest.mark.parametrize("path", EXAMPLE_SCENES, ids=lambda p: p.name)
def test_example_scene_files_load(path: Path) -> None:
    if scene_needs_shared(path) and not SHARED.is_dir():
        pytest.skip(f"{path.name} needs ../shared: {absent_shared_reason()}")
    scene = lenspath.load(path, allow_read=[SHARED] if scene_needs_shared(path) else [])
    assert scene.triangle_count + scene.sphere_count > 0
    assert scene.light_count > 0


@pytest.mark.parametrize("path", [p for p in EXAMPLE_SCENES if scene_needs_shared(p)], ids=lambda p: p.name)
def test_an_example_needing_shared_says_so_and_fails_in_one_line_without_it(cli, path: Path, tmp_path: Path) -> None:
    # Its opening comment says what it needs; in a clone with no ../shared beside it (made here,
    # whatever this machine has) it fails with exit code 2 and one line naming the missing file.
    opening = "\n".join(line for line in path.read_text().splitlines()[:6] if line.startswith("#"))
    assert "Needs ../shared" in opening, opening
    (tmp_path / "repo" / "scenes").mkdir(parents=True)
    copy = tmp_path / "repo" / "scenes" / path.name
    copy.write_text(path.read_text())
    done = subprocess.run(
        [str(cli), "render", str(copy), "--spp", "1", "--res", "8x6", "--out", str(tmp_path / "out.png")],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    assert "../shared/" in lines[0], lines[0]
    assert not (tmp_path / "out.png").exists()


def test_a_scene_reads_only_from_its_folder_unless_allowed(tmp_path: Path) -> None:
    (tmp_path / "scene").mkdir()
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes/tri.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    scene_file = tmp_path / "scene/s.toml"
    scene_file.write_text('builtin = "cornell-empty"\n[[shapes]]\ntype = "mesh"\nfile = "../meshes/tri.obj"\n')
    with pytest.raises(lenspath.SceneError, match="is outside the folders this scene may read"):
        lenspath.load(scene_file)
    scene = lenspath.load(scene_file, allow_read=[tmp_path / "meshes"])
    # Pickled (as lenspath.distributed sends scenes), it loads again with the same folders.
    again = pickle.loads(pickle.dumps(scene))
    assert again.triangle_count == scene.triangle_count


@pytest.mark.parametrize(
    ("name", "triangles"),
    [("bun_zipper.ply", 69_451), ("dragon_100k.ply", 100_000), ("dragon_100k.obj", 100_000)],
)
def test_shared_meshes_load_with_their_face_counts(shared, name: str, triangles: int) -> None:
    # The counts are ../shared/ASSETS.md's, from the files' headers and face lists.
    scene = lenspath.load(shared / "meshes" / name)
    assert (scene.mesh_count, scene.triangle_count) == (1, triangles)
    image = lenspath.render(scene, lenspath.Camera.pinhole(), spp=1, resolution=(24, 18))
    assert np.isfinite(image).all() and image.max() > 0


@pytest.mark.parametrize("name", ["valid.gltf", "valid.glb"])
def test_gltf_files_load(name: str) -> None:
    scene = lenspath.load(REPO / "fuzz/seeds/gltf" / name)
    assert (scene.mesh_count, scene.triangle_count) == (2, 2)


@pytest.mark.parametrize("name", ["CBspheres_lambertian.dae", "CBbunny.dae"])
def test_cs184_scenes_load_and_render(shared, name: str) -> None:
    scene = lenspath.load(shared / "scenes/cs184/sky" / name)
    image = lenspath.render(scene, lenspath.Camera.pinhole(), spp=1, resolution=(32, 24))
    assert image.mean() > 0.01


def test_the_old_material_names_still_work_and_say_the_new_ones() -> None:
    def sphere_of(kind: str, **material: object) -> np.ndarray:
        scene = _lit_floor(height=4.0)
        m = scene.add_material(kind, eta=(0.2, 0.9, 1.1), k=(3.9, 2.4, 2.2), **material)
        scene.add_sphere((0, 0.1, 0), 0.1, m)
        scene.add_environment((1.0, 1.0, 1.0))
        image = lenspath.render(scene, lenspath.Camera.pinhole(), spp=2, resolution=(16, 16))
        assert image.mean() > 0.05
        return image

    with pytest.warns(DeprecationWarning, match="use 'conductor'"), pytest.warns(DeprecationWarning, match="use alpha"):
        old = sphere_of("metal", roughness=0.2)
    assert np.array_equal(old, sphere_of("conductor", alpha=0.2))
    with pytest.warns(DeprecationWarning, match="use 'dielectric'"):
        old_glass = sphere_of("glass")
    assert np.array_equal(old_glass, sphere_of("dielectric"))


def test_meshes_from_numpy_any_dtype() -> None:
    scene = lenspath.Scene()
    white = scene.add_material("diffuse", reflectance=(0.7, 0.7, 0.7))
    assert scene.add_material("conductor", eta=(0.2, 0.9, 1.1), k=(3.9, 2.4, 2.2), alpha=0.1) == 1
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
        (lambda s: s.add_material("conductor"), ValueError, "a conductor needs either eta and k"),
        (lambda s: s.look_at((0, 0, 0), (0, 0, 0)), ValueError, r"eye \[0, 0, 0\] and target \[0, 0, 0\] must differ"),
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


def test_compile_builds_on_the_threads_asked_and_gives_the_same_image() -> None:
    """A BVH built on one thread is the one built on every core: the same image, bit for bit."""
    one = lenspath.Scene.builtin("cornell-spheres")
    one.compile(threads=1)
    every = lenspath.Scene.builtin("cornell-spheres")
    every.compile()
    settings = {"spp": 2, "resolution": (32, 24), "camera": lenspath.Camera.pinhole()}
    np.testing.assert_array_equal(lenspath.render(one, **settings), lenspath.render(every, **settings))


@pytest.mark.parametrize(("threads", "message"), [(0, "threads must be at least 1"), (100_000, "at most")])
def test_compile_refuses_a_thread_count_no_pool_can_have(threads: int, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        lenspath.Scene.builtin("cornell-spheres").compile(threads=threads)


def _lit_floor(height: float = 2.0, albedo: float = 0.5) -> lenspath.Scene:
    """A large diffuse floor (y = 0) seen straight down from ``height`` through a 4° pinhole."""
    scene = lenspath.Scene()
    grey = scene.add_material("diffuse", reflectance=(albedo, albedo, albedo))
    vertices = np.array([[-50, 0, -50], [50, 0, -50], [50, 0, 50], [-50, 0, 50]], np.float32)
    scene.add_mesh(vertices, np.array([[0, 3, 2], [0, 2, 1]]), grey)  # facing +y
    scene.look_at((0, height, 0), (0, 0, 0), up=(0, 0, -1), fov_deg=4)
    return scene


def _centre(scene: lenspath.Scene) -> np.ndarray:
    # 64 spp: a coloured light's spectrum is estimated from four wavelengths a sample.
    image = lenspath.render(scene, lenspath.Camera.pinhole(), spp=64, resolution=(16, 16), max_depth=1)
    return image[6:10, 6:10].mean(axis=(0, 1))


def test_a_point_light_lights_a_floor_by_the_inverse_square_law() -> None:
    # Lambert: L = (albedo / pi) * I cos(theta) / r^2, here straight below (cos = 1, r = 1.5).
    scene = _lit_floor()
    scene.add_point_light((0, 1.5, 0), (10.0, 20.0, 30.0))
    expected = 0.5 / np.pi * np.array([10.0, 20.0, 30.0]) / 1.5**2
    np.testing.assert_allclose(_centre(scene), expected, rtol=0.01)


def test_a_directional_light_gives_irradiance_times_the_cosine() -> None:
    scene = _lit_floor()
    # Travelling down at 60 degrees from the vertical: E cos(60) on the floor.
    scene.add_directional_light((np.sin(np.pi / 3), -np.cos(np.pi / 3), 0), (4.0, 4.0, 4.0))
    np.testing.assert_allclose(_centre(scene), 0.5 / np.pi * 4.0 * 0.5, rtol=0.01)


def test_a_spot_light_lights_only_its_cone() -> None:
    scene = _lit_floor(height=4.0)
    # Straight down from 1 m with a 2 degree half angle: a disc of radius 3.5 cm, inside the
    # 4 degree view of 28 cm; the view's centre gets the full on-axis intensity.
    scene.add_spot_light((0, 1, 0), (0, -1, 0), (8.0, 8.0, 8.0), cutoff_angle_deg=2.0)
    image = lenspath.render(scene, lenspath.Camera.pinhole(), spp=16, resolution=(32, 32), max_depth=1)
    np.testing.assert_allclose(image[15:17, 15:17].mean(), 0.5 / np.pi * 8.0, rtol=0.01)
    assert image[0:4, 0:4].max() == 0.0


def test_the_old_name_of_the_spot_cutoff_still_works_and_says_the_new_one() -> None:
    old, new = _lit_floor(height=4.0), _lit_floor(height=4.0)
    with pytest.warns(DeprecationWarning, match="use cutoff_angle_deg"):
        old.add_spot_light((0, 1, 0), (0, -1, 0), (8.0, 8.0, 8.0), cone_angle_deg=2.0)
    new.add_spot_light((0, 1, 0), (0, -1, 0), (8.0, 8.0, 8.0), cutoff_angle_deg=2.0)
    args = {"spp": 2, "resolution": (16, 16), "max_depth": 1}
    camera = lenspath.Camera.pinhole()
    assert np.array_equal(lenspath.render(old, camera, **args), lenspath.render(new, camera, **args))
    with pytest.raises(ValueError, match="not also cone_angle_deg"):
        new.add_spot_light((0, 1, 0), (0, -1, 0), (1, 1, 1), cutoff_angle_deg=2.0, cone_angle_deg=2.0)


@pytest.mark.parametrize(
    ("add", "message"),
    [
        (lambda s: s.add_point_light((0, np.nan, 0), (1, 1, 1)), "position must be finite"),
        (lambda s: s.add_point_light((0, 0, 0), (1, -1, 1)), "intensity must be finite and non-negative"),
        (lambda s: s.add_directional_light((0, 0, 0), (1, 1, 1)), "direction must be a finite, non-zero"),
        (lambda s: s.add_spot_light((0, 0, 0), (0, -1, 0), (1, 1, 1), 0.0), r"cutoff_angle_deg must be in \(0, 180\]"),
        (lambda s: s.add_sphere((0, 0, 0), 1.0, 0, emission=(1, np.inf, 1)), "emission must be finite"),
    ],
)
def test_bad_lights_are_refused(add, message: str) -> None:
    scene = lenspath.Scene()
    scene.add_material("diffuse")
    with pytest.raises(ValueError, match=message):
        add(scene)
    assert scene.light_count == 0
