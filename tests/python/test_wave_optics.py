"""Lens.psf and Lens.mtf: the CLI's wave-optics figures, the Airy pattern of a
stopped-down lens, the MTF as the PSF's Fourier transform (numpy's, not
ours), agreement with optiland on four real lenses, and their errors."""

from __future__ import annotations

import json
import pickle
import subprocess
from pathlib import Path

import numpy as np
import pytest

import lenspath

# A biconvex element (R = ±100 mm, 4 mm thick, n = 1.5, f ≈ 100 mm) in front of the stop.
SINGLET = [[100.0, 4.0, 1.5, 20.0], [-100.0, 1.0, 1.0, 20.0], [0.0, 1.0, 1.0, 10.0]]

# optiland 0.6.3's FFT PSF, FFT MTF, wavefront and Fringe Zernike fit of dgauss50, tessar100,
# triplet50 and asph31 at three fields and three wavelengths (made by bench/wave_optics_peers.py).
OPTILAND = json.loads((Path(__file__).parents[1] / "data" / "optiland_wave_reference.json").read_text())


def test_the_mtf_equals_the_clis(cli) -> None:
    args = ["lens", "dgauss50", "--fstop", "8", "--mtf", "10", "--pupil-samples", "64", "--json"]
    out = subprocess.run([str(cli), *args], check=True, capture_output=True, text=True)
    theirs = json.loads(out.stdout)["wave"][0]
    ours = lenspath.Lens.builtin("dgauss50").stopped_down(8.0).mtf(10.0, pupil_samples=64)
    # One analysis in the library; the two builds may differ in a float's last bit.
    for key in ("strehl_ratio", "mtf50_tangential_per_mm", "sensor_depth_mm", "working_f_number"):
        assert ours[key] == pytest.approx(theirs[key], rel=1e-12), key
    assert len(ours["wavelengths"]) == len(theirs["wavelengths"]) == 1
    columns = {"frequencies_per_mm": "frequency_per_mm", "tangential": "tangential", "sagittal": "sagittal"}
    columns["diffraction_limit"] = "diffraction_limit"
    for key, sample_key in columns.items():
        expected = [sample[sample_key] for sample in theirs["mtf"]]
        np.testing.assert_allclose(ours[key], expected, rtol=1e-12, atol=1e-15, err_msg=key)


def test_a_stopped_down_singlet_on_axis_makes_the_airy_pattern() -> None:
    lens = lenspath.Lens.from_table(SINGLET).stopped_down(16.0)
    wavelength_nm = 550.0
    psf, (dx_um, dy_um) = lens.psf(0.0, wavelength_nm=wavelength_nm)
    figures = lens.mtf(0.0, wavelength_nm=wavelength_nm)
    assert psf.sum() == pytest.approx(1.0, abs=1e-9)
    assert figures["strehl_ratio"] > 0.95, "near perfect at f/16"
    size = psf.shape[0]
    y, x = np.mgrid[0:size, 0:size] - size // 2
    radius_um = np.hypot(x * dx_um, y * dy_um)
    # 83.8 % of an Airy pattern's energy lies within its first dark ring, 1.22 λN.
    first_zero_um = 1.22 * wavelength_nm * 1e-3 * figures["working_f_number"]
    assert psf[radius_um <= first_zero_um].sum() == pytest.approx(0.838, abs=0.015)
    # The first bright ring (at 1.64 λN) outshines the first dark one.
    section = psf[size // 2, size // 2 :]
    along_x_um = np.arange(section.size) * dx_um
    dark = section[np.argmin(np.abs(along_x_um - first_zero_um))]
    bright = section[np.argmin(np.abs(along_x_um - first_zero_um * 1.64 / 1.22))]
    assert bright > 5 * dark


def test_the_mtf_is_the_psfs_fourier_transform() -> None:
    lens = lenspath.Lens.builtin("dgauss50").stopped_down(4.0)
    psf, (dx_um, dy_um) = lens.psf(10.0, pupil_samples=64)
    figures = lens.mtf(10.0, frequencies_per_mm=[20.0, 40.0], pupil_samples=64)
    size = psf.shape[0]
    y_mm = (np.arange(size) - size // 2) * dy_um * 1e-3
    x_mm = (np.arange(size) - size // 2) * dx_um * 1e-3
    for k, frequency in enumerate(figures["frequencies_per_mm"]):
        # Tangential: frequencies along y (the array's rows); sagittal along x.
        tangential = abs(np.sum(psf.sum(axis=1) * np.exp(-2j * np.pi * frequency * y_mm)))
        sagittal = abs(np.sum(psf.sum(axis=0) * np.exp(-2j * np.pi * frequency * x_mm)))
        assert figures["tangential"][k] == pytest.approx(tangential, abs=0.01)
        assert figures["sagittal"][k] == pytest.approx(sagittal, abs=0.01)
    assert abs(figures["tangential"][1] - figures["sagittal"][1]) > 0.02, "off axis T and S differ"


@pytest.mark.parametrize(
    "case",
    OPTILAND["cases"],
    ids=[f"{c['lens']}-{c['field_deg']:g}deg-{c['wavelength_nm']:g}nm" for c in OPTILAND["cases"]],
)
def test_the_wave_optics_agrees_with_optiland(case: dict) -> None:
    # The bounds: MTF within 0.02 to 100 /mm, Strehl within 0.01, RMS wavefront within 2 %.
    lens = lenspath.Lens.builtin(case["lens"])
    if case["f_number"] is not None:
        lens = lens.stopped_down(case["f_number"])
    ours = lens.mtf(
        case["field_deg"],
        frequencies_per_mm=OPTILAND["frequencies_per_mm"],
        wavelength_nm=case["wavelength_nm"],
        sensor_depth_mm=case["sensor_depth_mm"],
        pupil_samples=OPTILAND["pupil_samples"],
        padding=OPTILAND["padding"],
    )
    theirs = case["optiland"]
    mono = ours["wavelengths"][0]
    assert mono["strehl_ratio"] == pytest.approx(theirs["strehl_ratio"], abs=0.01)
    assert mono["rms_wavefront_waves"] == pytest.approx(theirs["rms_wavefront_waves"], rel=0.02)
    np.testing.assert_allclose(ours["tangential"], theirs["mtf_tangential"], atol=0.02)
    np.testing.assert_allclose(ours["sagittal"], theirs["mtf_sagittal"], atol=0.02)
    # The OPD's sign: each clear Fringe term (defocus, astigmatism, coma, spherical) has optiland's sign.
    zernike = np.array(mono["zernike_fringe_waves"][: len(theirs["zernike_fringe_waves"])])
    reference = np.array(theirs["zernike_fringe_waves"])
    clear = np.abs(reference) > 0.05
    assert np.all(np.sign(zernike[clear]) == np.sign(reference[clear])), (zernike, reference)
    assert zernike[3] == pytest.approx(reference[3], abs=0.1), "Z4, defocus"


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"field_deg": 95.0}, "within ±90°, got 95"),
        ({"wavelength_nm": [500.0, 600.0], "weights": [1.0]}, "weights gives 1 weights for 2 wavelengths"),
        ({"wavelength_nm": "green"}, "a number or a sequence"),
        ({"padding": 1}, "padding must be at least 2"),
        ({"sensor_depth_mm": -5.0}, "behind the rear element"),
    ],
    ids=["field", "weights", "wavelength", "padding", "depth"],
)
def test_bad_questions_raise_value_error_naming_the_value(kwargs: dict[str, object], message: str) -> None:
    lens = lenspath.Lens.builtin("dgauss50")
    with pytest.raises(ValueError, match=message):
        lens.psf(**kwargs)  # type: ignore[arg-type]


def test_a_diffracting_camera_is_the_scene_files_and_survives_pickling(tmp_path) -> None:
    """``Camera.realistic(diffraction=True)`` and a scene file's ``diffraction = true`` give one
    image, which differs from the one without (f/22: the Airy disc is 30 µm, a pixel of 36 mm / 48)."""
    scene_file = tmp_path / "diffracting.toml"
    scene_file.write_text(
        'builtin = "cornell-spheres"\n[camera]\neye = [0, 1, 3.9]\nlook_at = [0, 1, 0]\n'
        "f_number = 22.0\ndiffraction = true\n"
    )
    options = {"spp": 4, "resolution": (48, 36), "seed": 3}
    camera = lenspath.Camera.realistic(f_number=22.0, diffraction=True)
    by_keyword = lenspath.render(scene_file, camera, **options)
    by_file = lenspath.render(scene_file, **options)
    assert np.array_equal(by_keyword, by_file)
    plain = lenspath.render(scene_file, lenspath.Camera.realistic(f_number=22.0, diffraction=False), **options)
    assert not np.array_equal(plain, by_file)
    assert "diffraction=True" in repr(camera)
    copy = pickle.loads(pickle.dumps(camera))
    assert np.array_equal(lenspath.render(scene_file, copy, **options), by_file)
