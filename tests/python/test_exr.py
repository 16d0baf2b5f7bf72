"""EXR as the ecosystem writes it, checked with the OpenEXR package (the Academy's own library):
a crop keeps its frame, a render's header carries the standard attributes and lenspath's settings,
and Python's read_exr / write_exr round-trip every channel and attribute."""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest

import lenspath

OpenEXR = pytest.importorskip("OpenEXR", reason="the EXR checks need the OpenEXR package (pip install .[test])")

#: What OpenEXR's header holds beyond the attributes: the layout, which the writers choose.
LAYOUT = {"channels", "compression", "dataWindow", "displayWindow", "lineOrder", "type", "tiles", "chunkCount"}


def openexr(path: Path) -> tuple[dict, dict]:
    """OpenEXR's reading of `path`: its header and its channels' pixels by name."""
    f = OpenEXR.File(str(path), separate_channels=True)
    return f.header(), {name: c.pixels for name, c in f.channels().items()}


def same_value(ours, theirs) -> bool:
    return bool(np.allclose(np.asarray(ours, dtype=np.float64), np.asarray(theirs, dtype=np.float64), rtol=1e-7))


def render(cli: Path, out: Path, *flags: str) -> None:
    subprocess.run([str(cli), "render", "--res", "64x48", "--spp", "2", *flags, "--out", str(out)], check=True)


def test_a_crop_keeps_its_frame_and_the_header_describes_the_render(cli, tmp_path) -> None:
    out = tmp_path / "crop.exr"
    render(cli, out, "--crop", "10,8,20,16", "--fstop", "2.8")
    header, pixels = openexr(out)
    # pbrt's convention: the whole frame is the display window, the crop the data window.
    assert [list(w) for w in header["displayWindow"]] == [[0, 0], [63, 47]]
    assert [list(w) for w in header["dataWindow"]] == [[10, 8], [29, 23]]
    assert set(pixels) == {"R", "G", "B", "Z"} and pixels["R"].shape == (16, 20)
    assert header["aperture"] == pytest.approx(2.8)
    assert header["software"] == f"lenspath {lenspath.__version__}"
    assert header["lenspath/lens"] == "dgauss50"
    assert (header["lenspath/spp"], header["lenspath/sppRequested"]) == (2, 2)
    assert same_value(header["chromaticities"], (0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290))
    # The focus is the view's subject, in metres (scene units of 1 m).
    scene = lenspath.Scene.builtin("cornell-spheres")
    assert scene.name == "cornell-spheres"
    assert header["focus"] == pytest.approx(header["lenspath/focusDistance"])
    # lenspath reads what OpenEXR reads.
    ours = lenspath.read_exr(out)
    assert ours["display_window"] == (64, 48) and ours["data_origin"] == (10, 8)
    for name, value in ours["attributes"].items():
        assert same_value(value, header[name]) if not isinstance(value, str) else value == header[name], name
    assert set(ours["attributes"]) == set(header) - LAYOUT - {
        "pixelAspectRatio",
        "screenWindowCenter",
        "screenWindowWidth",
    }
    for name, values in pixels.items():
        np.testing.assert_array_equal(ours["channels"][name], values)


def test_a_pinhole_renders_world_to_ndc_as_openexr_defines_it(cli, tmp_path) -> None:
    out = tmp_path / "pinhole.exr"
    render(cli, out, "--camera", "pinhole")
    header, _ = openexr(out)
    # OpenEXR's matrices multiply row vectors: p_camera = p_world · worldToCamera.
    world_from_camera = np.linalg.inv(header["worldToCamera"].astype(np.float64))
    to_ndc = header["worldToNDC"].astype(np.float64)
    tan_y = np.tan(np.radians(header["lenspath/fovYDeg"]) / 2)
    tan_x = tan_y * 64 / 48

    def ndc(camera_point) -> np.ndarray:
        h = np.append(camera_point, 1.0) @ world_from_camera @ to_ndc
        return h[:2] / h[3]

    # The view axis meets the middle of the display window, the frustum's corners its corners:
    # (0, 0) top left and (1, 1) bottom right (camera space: x right, y up, z forward).
    np.testing.assert_allclose(ndc([0, 0, 3]), [0.5, 0.5], atol=1e-5)
    np.testing.assert_allclose(ndc([-tan_x * 2, tan_y * 2, 2]), [0, 0], atol=1e-5)
    np.testing.assert_allclose(ndc([tan_x, -tan_y, 1]), [1, 1], atol=1e-5)


def test_a_file_openexr_wrote_round_trips_through_lenspath(tmp_path) -> None:
    rng = np.random.default_rng(7)
    channels = {name: rng.random((6, 9), dtype=np.float32) for name in ("R", "G", "B", "A", "Z", "mask.alpha")}
    attributes = {
        "owner": "a lens enthusiast",
        "comments": "λ = 546 nm",
        "focus": 2.5,
        "expTime": 0.004,
        "isoSpeed": 400.0,
        "worldToNDC": rng.random((4, 4), dtype=np.float32),
        "capDate": "2026:11:26 20:00:00",
        "studio/take": 12,
        "studio/offset": (3, -4),
        "studio/center": (0.5, 0.25),
    }
    first = tmp_path / "openexr.exr"
    OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage, **attributes}, channels).write(
        str(first)
    )
    again = tmp_path / "lenspath.exr"
    lenspath.write_exr(again, **lenspath.read_exr(first))
    (h1, p1), (h2, p2) = openexr(first), openexr(again)
    assert set(p2) == set(channels)
    for name in channels:
        np.testing.assert_array_equal(p2[name], p1[name])
    for name in set(h1) - LAYOUT:
        assert same_value(h2[name], h1[name]) if not isinstance(h1[name], str) else h2[name] == h1[name], name
    # Written again, the same bytes: the header is written in name order.
    third = tmp_path / "third.exr"
    lenspath.write_exr(third, **lenspath.read_exr(again))
    assert third.read_bytes() == again.read_bytes()


def test_write_keeps_only_what_it_is_given(tmp_path) -> None:
    image = np.ones((4, 5, 3), dtype=np.float32)
    lenspath.write(tmp_path / "plain.exr", image)
    plain = lenspath.read_exr(tmp_path / "plain.exr")
    assert set(plain["channels"]) == {"R", "G", "B"}
    assert not any(name.startswith("lenspath/") for name in plain["attributes"])
    depth = np.full((4, 5), 2.0, dtype=np.float32)
    lenspath.write(tmp_path / "deep.exr", image, depth=depth, attributes={"owner": "me", "take": 3})
    deep = lenspath.read_exr(tmp_path / "deep.exr")
    np.testing.assert_array_equal(deep["channels"]["Z"], depth)
    assert (deep["attributes"]["owner"], deep["attributes"]["take"]) == ("me", 3)


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda p: lenspath.write(p / "a.png", np.ones((2, 2, 3)), attributes={"owner": "me"}), "PNG keeps no"),
        (lambda p: lenspath.write(p / "a.exr", np.ones((2, 2, 3)), depth=np.ones((3, 2))), "depth must be 2 x 2"),
        (lambda p: lenspath.write_exr(p / "a.exr", {}), "at least one channel"),
        (lambda p: lenspath.write_exr(p / "a.exr", {"R": np.ones((2, 2)), "G": np.ones((3, 2))}), "channel 'G'"),
        (lambda p: lenspath.write_exr(p / "a.exr", {"R": np.ones((2, 2))}, {"bad": [1, 2, 3]}), "attribute 'bad'"),
        (lambda p: lenspath.write_exr(p / "a.exr", {"R": np.ones((2, 2))}, {"flag": True}), "attribute 'flag'"),
    ],
)
def test_exr_errors(tmp_path, call, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        call(tmp_path)
