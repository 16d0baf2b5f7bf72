"""The sensor's raw frames read by an independent raw decoder: LibRaw (through rawpy)."""

from __future__ import annotations

import struct
import subprocess

import numpy as np
import pytest
from PIL import Image

rawpy = pytest.importorskip("rawpy", reason="rawpy (LibRaw) is in the test extras: pip install '.[test]'")

# LibRaw's colour indices of a 2 x 2 block (R, G, B, second G) for each pattern.
PATTERNS = {"rggb": [[0, 1], [3, 2]], "bggr": [[2, 3], [1, 0]]}


def _render_raw(cli, tmp_path, cfa: str, raw_name: str) -> None:
    subprocess.run(
        [
            str(cli),
            "render",
            "--res",
            "48x32",
            "--spp",
            "2",
            "--sensor",
            "2.4x1.6",
            "--sensor-model",
            "nikon_d850",
            "--iso",
            "400",
            "--cfa",
            cfa,
            "--raw",
            str(tmp_path / raw_name),
            "--out",
            str(tmp_path / f"{raw_name}.developed.png"),
        ],
        check=True,
        capture_output=True,
    )


def _dng_tag(data: bytes, tag: int) -> list[float]:
    """A (signed) rational tag of a little-endian TIFF's first IFD, divided out (TIFF 6.0, section 2)."""
    ifd = struct.unpack_from("<I", data, 4)[0]
    for i in range(struct.unpack_from("<H", data, ifd)[0]):
        entry_tag, kind, count, offset = struct.unpack_from("<HHII", data, ifd + 2 + 12 * i)
        if entry_tag == tag:
            fmt = "<ii" if kind == 10 else "<II"
            return [n / d for n, d in (struct.unpack_from(fmt, data, offset + 8 * k) for k in range(count))]
    raise KeyError(tag)


@pytest.mark.parametrize("cfa", sorted(PATTERNS))
def test_libraw_reads_the_dng_as_written(cli, tmp_path, cfa) -> None:
    _render_raw(cli, tmp_path, cfa, "frame.dng")
    _render_raw(cli, tmp_path, cfa, "frame.png")
    mosaic = np.asarray(Image.open(tmp_path / "frame.png"), dtype=np.uint16)
    data = (tmp_path / "frame.dng").read_bytes()
    with rawpy.imread(str(tmp_path / "frame.dng")) as raw:
        # The digital numbers, the levels and the pattern.
        np.testing.assert_array_equal(raw.raw_image, mosaic)
        assert raw.black_level_per_channel == [64, 64, 64, 64]
        assert raw.white_level == 1023
        assert raw.color_desc == b"RGBG"
        colours = raw.raw_colors[:2, :2].tolist()
        assert colours == PATTERNS[cfa]
        # The white balance is the inverse of AsShotNeutral.
        neutral = np.array(_dng_tag(data, 50728))
        np.testing.assert_allclose(np.array(raw.daylight_whitebalance[:3]) * neutral, 1.0, rtol=1e-5)
        # Its camera -> sRGB matrix is the one ColorMatrix1 gives (dcraw's cam_xyz_coeff: rows of
        # XYZ->camera times sRGB->XYZ normalised to sum 1, inverted).
        xyz_to_camera = np.array(_dng_tag(data, 50721)).reshape(3, 3)
        srgb_to_xyz = np.array(
            [[0.412453, 0.357580, 0.180423], [0.212671, 0.715160, 0.072169], [0.019334, 0.119193, 0.950227]]
        )
        camera_from_srgb = xyz_to_camera @ srgb_to_xyz
        camera_from_srgb /= camera_from_srgb.sum(axis=1, keepdims=True)
        np.testing.assert_allclose(np.array(raw.color_matrix)[:, :3], np.linalg.inv(camera_from_srgb), atol=1e-4)


# ---- The Python API: lenspath.sensor ----

import pickle  # noqa: E402

import lenspath  # noqa: E402
from lenspath.sensor import RawFrame, Sensor, models  # noqa: E402


def test_a_sensor_fills_in_the_librarys_defaults_and_pickles() -> None:
    sensor = Sensor("ideal", iso=400, cfa="bggr")
    settings = sensor.settings()
    assert settings["model"] == "ideal" and settings["iso"] == 400.0 and settings["cfa"] == "bggr"
    defaults = Sensor().settings()
    assert (defaults["model"], defaults["bit_depth"], defaults["black_level_dn"]) == ("sony_ilce_7m3", 10, 64)
    assert (defaults["white_balance"], defaults["demosaic"], defaults["tone_curve"]) == ("daylight", "mhc", "linear")
    assert (defaults["auto_exposure"], defaults["max_iso"]) == (False, 3520.0)
    assert repr(Sensor(auto_exposure=True)) == "Sensor(auto_exposure=True)"
    assert repr(sensor) == "Sensor(cfa='bggr', iso=400.0, model='ideal')"
    assert pickle.loads(pickle.dumps(sensor)).settings() == settings
    assert "ideal" in models() and "nikon_d850" in models() and len(models()) == 18


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        ({"cfa": "rgbw"}, "unknown colour filter array 'rgbw'"),
        ({"model": "leica_m3"}, "unknown sensor 'leica_m3'"),
        ({"iso": -100}, "ISO must be positive"),
        ({"bit_depth": 20}, "bit depth must be 1 to 16"),
        ({"white_balance": "tungsten"}, "unknown white balance 'tungsten'"),
        ({"demosaic": "ahd"}, "unknown demosaicking method 'ahd'"),
    ],
)
def test_a_bad_sensor_setting_is_a_clear_error(arguments, message) -> None:
    with pytest.raises(ValueError, match=message):
        Sensor(**arguments)


def test_a_sensor_render_gives_a_raw_frame_raw_developers_read(tmp_path) -> None:
    camera = lenspath.Camera.realistic(sensor_width_mm=2.4)
    frame = lenspath.render("cornell-spheres", camera, spp=2, resolution=(48, 32), sensor=Sensor(iso=400))
    assert isinstance(frame, RawFrame)
    assert frame.mosaic.dtype == np.uint16 and frame.mosaic.shape == (32, 48)
    assert (frame.cfa, frame.black_level_dn, frame.white_level_dn) == ("rggb", 64, 1023)
    assert frame.xyz_to_camera.shape == (3, 3) and max(frame.as_shot_neutral) == 1.0
    developed = frame.develop()
    assert developed.shape == (32, 48, 3) and developed.dtype == np.float32
    assert not np.array_equal(developed, frame.develop(demosaic="bilinear"))
    assert (frame.exposure_time_s, frame.iso) == (pytest.approx(1 / 60), 400.0)
    metered = lenspath.render("cornell-spheres", camera, spp=2, resolution=(48, 32), sensor=Sensor(auto_exposure=True))
    assert metered.exposure_time_s <= 1 / 30 and metered.iso >= 55.0
    frame.write(tmp_path / "frame.dng")
    with rawpy.imread(str(tmp_path / "frame.dng")) as raw:
        np.testing.assert_array_equal(raw.raw_image, frame.mosaic)
    with pytest.raises(ValueError, match="through a lens"):
        lenspath.render("cornell-spheres", lenspath.Camera.pinhole(), spp=1, resolution=(8, 8), sensor=Sensor())
    with pytest.raises(ValueError, match="without AOVs"):
        lenspath.render("cornell-spheres", spp=1, resolution=(8, 8), sensor=Sensor(), aovs=["depth"])  # type: ignore[call-overload]
