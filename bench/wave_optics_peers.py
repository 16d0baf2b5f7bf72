"""lenspath's wave-optics analysis against optiland's (PyPI, MIT): the same
lens, field, wavelength and sensor plane in both, compared by Strehl ratio,
RMS wavefront error, Fringe Zernike terms and the FFT MTF.

Each lens goes to optiland surface by surface from lenspath's own table
(radius, thickness, aperture, even-asphere terms), with each glass's index
at the wavelength from lenspath's glass model (``IdealMaterial``), so the
comparison is of the wave optics, not of two glass catalogues; the paraxial
focal lengths are checked to agree first. The image plane is lenspath's
infinity focus at 587.56 nm, the same for all three wavelengths.

Writes tests/data/optiland_wave_reference.json (optiland's figures, which
tests/python/test_wave_optics.py holds lenspath to) and prints the agreement
table for BENCHMARKS.md. Needs lenspath and optiland in one environment:

    python -m venv /tmp/ovenv && /tmp/ovenv/bin/pip install optiland==0.6.3 target/wheels/lenspath-*.whl
    /tmp/ovenv/bin/python bench/wave_optics_peers.py
"""

from __future__ import annotations

import json
import sys
import warnings
from importlib.metadata import version
from pathlib import Path

import numpy as np

import lenspath

warnings.filterwarnings("ignore")  # optiland's deprecation notices for the Optic.add_* calls

from optiland import optic as optiland_optic  # noqa: E402
from optiland.materials import IdealMaterial  # noqa: E402
from optiland.mtf import FFTMTF  # noqa: E402
from optiland.physical_apertures import RadialAperture  # noqa: E402
from optiland.psf import FFTPSF  # noqa: E402
from optiland.wavefront import Wavefront, ZernikeOPD  # noqa: E402

REFERENCE = Path(__file__).resolve().parents[1] / "tests" / "data" / "optiland_wave_reference.json"
# Lens, f-number (None: wide open) and three field angles, degrees: the axis, mid field, near the corner.
CASES = [
    ("dgauss50", 4.0, (0.0, 10.0, 18.0)),
    ("tessar100", None, (0.0, 7.0, 11.0)),
    ("triplet50", None, (0.0, 10.0, 18.0)),
    ("asph31", 4.0, (0.0, 8.0, 14.0)),
]
WAVELENGTHS_NM = (486.13, 587.56, 656.27)
FREQUENCIES_PER_MM = [10.0 * k for k in range(1, 11)]
PUPIL_SAMPLES = 128
PADDING = 4
ZERNIKE_TERMS = 9  # Fringe Z1..Z9: piston, tilts, defocus, astigmatism, coma, spherical


def table_rows(lens: lenspath.Lens) -> list[dict[str, object]]:
    """The lens's table text as rows: radius, thickness, n_d, aperture, glass, aspheric terms."""
    rows = []
    for line in lens.table_text.splitlines():
        words = line.split("#")[0].split()
        if not words:
            continue
        radius, thickness, n_d, aperture = (float(w) for w in words[:4])
        glass = next((w for w in words[4:] if "=" not in w), None)
        terms = dict(w.split("=") for w in words[4:] if "=" in w)
        rows.append(
            {"radius": radius, "thickness": thickness, "n_d": n_d, "aperture": aperture, "glass": glass, "terms": terms}
        )
    return rows


def index_at(row: dict[str, object], wavelength_nm: float) -> float:
    """The index after the surface at `wavelength_nm`, as lenspath disperses it."""
    n_d = float(row["n_d"])  # type: ignore[arg-type]
    glass = row["glass"]
    if n_d in (0.0, 1.0):
        return 1.0
    if glass is None:
        return n_d
    try:
        model = lenspath.Glass.abbe(n_d, float(glass))  # type: ignore[arg-type]
    except ValueError:
        model = lenspath.Glass(str(glass))
    return float(model.index(wavelength_nm))


def optiland_model(
    lens: lenspath.Lens, stop_diameter_mm: float, wavelength_nm: float, image_distance_mm: float, fields_deg
) -> object:
    """`lens` as an optiland Optic at one wavelength with its stop `stop_diameter_mm` across, the image
    `image_distance_mm` behind its rear vertex."""
    rows = table_rows(lens)
    model = optiland_optic.Optic()
    model.add_surface(index=0, radius=np.inf, thickness=np.inf)
    for k, row in enumerate(rows):
        is_stop = row["radius"] == 0.0 and row["n_d"] == 0.0
        radius = np.inf if row["radius"] == 0.0 else row["radius"]
        thickness = image_distance_mm if k == len(rows) - 1 else row["thickness"]
        n = index_at(row, wavelength_nm)
        terms = row["terms"]
        kwargs: dict[str, object] = {
            "index": k + 1,
            "radius": radius,
            "thickness": thickness,
            "is_stop": is_stop,
            "material": IdealMaterial(n=n) if n != 1.0 else "air",
        }
        diameter_mm = stop_diameter_mm if is_stop else float(row["aperture"])  # type: ignore[arg-type]
        kwargs["aperture"] = RadialAperture(r_max=0.5 * diameter_mm)
        if terms:
            powers = [int(key[1:]) for key in terms if key.startswith("a")]
            coefficients = [0.0] * (max(powers) // 2 if powers else 0)
            for key, value in terms.items():
                if key.startswith("a"):
                    coefficients[int(key[1:]) // 2 - 1] = float(value)
            kwargs.update(surface_type="even_asphere", conic=float(terms.get("conic", 0.0)), coefficients=coefficients)
        model.add_surface(**kwargs)
    model.add_surface(index=len(rows) + 1)
    # The stop's size sets the beam, and optiland's iterative ray aiming fills it, as lenspath's real pupil does.
    model.set_aperture(aperture_type="float_by_stop_size", value=stop_diameter_mm)
    model.set_field_type("angle")
    for field in fields_deg:
        model.add_field(y=field)
    model.add_wavelength(value=wavelength_nm * 1e-3, is_primary=True)
    model.set_ray_aiming("iterative")
    return model


def optiland_figures(model, field_deg: float, max_field_deg: float, wavelength_nm: float) -> dict[str, object]:
    wavelength_um = wavelength_nm * 1e-3
    field = (0.0, field_deg / max_field_deg if max_field_deg else 0.0)
    grid = PUPIL_SAMPLES * PADDING
    psf = FFTPSF(model, field, wavelength_um, num_rays=PUPIL_SAMPLES, grid_size=grid)
    mtf = FFTMTF(model, [field], wavelength_um, num_rays=PUPIL_SAMPLES, grid_size=grid, max_freq=200.0)
    data = mtf.mtf[0]
    tangential = np.interp(FREQUENCIES_PER_MM, np.asarray(mtf.freq_tang[0]), np.asarray(data[0]))
    sagittal = np.interp(FREQUENCIES_PER_MM, np.asarray(mtf.freq_sag[0]), np.asarray(data[1]))
    wavefront = Wavefront(model, [field], [wavelength_um], num_rays=PUPIL_SAMPLES, distribution="uniform")
    opd_data = wavefront.get_data(wavefront.fields[0], wavefront.wavelengths[0])
    valid = np.asarray(opd_data.intensity) > 0
    opd = np.asarray(opd_data.opd)[valid]
    zernike = ZernikeOPD(model, field, wavelength_um, num_rings=32, zernike_type="fringe", num_terms=ZERNIKE_TERMS)
    return {
        "strehl_ratio": float(np.max(np.asarray(psf.psf))) / 100.0,
        "rms_wavefront_waves": float(np.sqrt(np.mean((opd - opd.mean()) ** 2))),
        "zernike_fringe_waves": [float(c) for c in zernike.coeffs],
        "mtf_tangential": tangential.tolist(),
        "mtf_sagittal": sagittal.tolist(),
        "effective_focal_length_mm": float(model.paraxial.f2()),
    }


def main() -> int:
    cases = []
    for name, f_number, fields in CASES:
        lens = lenspath.Lens.builtin(name)
        stop_row = next(row for row in table_rows(lens) if row["radius"] == 0.0)
        stop_diameter_mm = float(stop_row["aperture"])  # type: ignore[arg-type]
        if f_number is not None:
            # lenspath stops down by the paraxial f-number: the stop's diameter scales as 1/N.
            stop_diameter_mm *= lens.f_number / f_number
            lens = lens.stopped_down(f_number)
        analysis = lens.analysis()
        sensor_depth_mm = lens.infinity_focus_mm
        image_distance_mm = sensor_depth_mm - analysis["rear_vertex_mm"]
        for wavelength_nm in WAVELENGTHS_NM:
            model = optiland_model(lens, stop_diameter_mm, wavelength_nm, image_distance_mm, fields)
            for field_deg in fields:
                theirs = optiland_figures(model, field_deg, max(fields), wavelength_nm)
                ours = lens.mtf(
                    field_deg,
                    frequencies_per_mm=FREQUENCIES_PER_MM,
                    wavelength_nm=wavelength_nm,
                    sensor_depth_mm=sensor_depth_mm,
                    pupil_samples=PUPIL_SAMPLES,
                    padding=PADDING,
                )
                mono = ours["wavelengths"][0]
                case = {
                    "lens": name,
                    "f_number": f_number,
                    "field_deg": field_deg,
                    "wavelength_nm": wavelength_nm,
                    "sensor_depth_mm": sensor_depth_mm,
                    "optiland": theirs,
                    "lenspath": {
                        "strehl_ratio": mono["strehl_ratio"],
                        "rms_wavefront_waves": mono["rms_wavefront_waves"],
                        "zernike_fringe_waves": mono["zernike_fringe_waves"][:ZERNIKE_TERMS],
                        "mtf_tangential": ours["tangential"].tolist(),
                        "mtf_sagittal": ours["sagittal"].tolist(),
                    },
                }
                cases.append(case)
                print_case(case)
    REFERENCE.parent.mkdir(parents=True, exist_ok=True)
    reference = {
        "made_by": "bench/wave_optics_peers.py",
        "optiland": version("optiland"),
        "pupil_samples": PUPIL_SAMPLES,
        "padding": PADDING,
        "frequencies_per_mm": FREQUENCIES_PER_MM,
        "cases": [{k: v for k, v in case.items() if k != "lenspath"} for case in cases],
    }
    REFERENCE.write_text(json.dumps(reference, indent=1) + "\n")
    print_summary(cases)
    return 0


def print_case(case: dict[str, object]) -> None:
    ours, theirs = case["lenspath"], case["optiland"]
    mtf_gap = max(
        np.max(np.abs(np.subtract(ours["mtf_tangential"], theirs["mtf_tangential"]))),
        np.max(np.abs(np.subtract(ours["mtf_sagittal"], theirs["mtf_sagittal"]))),
    )
    print(
        f"{case['lens']:<10} f/{case['f_number'] or 'open':<5} {case['field_deg']:>5.1f}°"
        f" {case['wavelength_nm']:>7.2f} nm"
        f"  Strehl {ours['strehl_ratio']:.4f} / {theirs['strehl_ratio']:.4f}"
        f"  RMS {ours['rms_wavefront_waves']:.4f} / {theirs['rms_wavefront_waves']:.4f}"
        f"  max |ΔMTF| {mtf_gap:.4f}",
        flush=True,
    )


def print_summary(cases: list[dict[str, object]]) -> None:
    print("\n| lens | f/ | fields (°) | max abs ΔStrehl | max rel ΔRMS | max abs ΔMTF (10-100 /mm) |")
    print("|---|---|---|---|---|---|")
    for name, f_number, fields in CASES:
        mine = [c for c in cases if c["lens"] == name]
        d_strehl = max(abs(c["lenspath"]["strehl_ratio"] - c["optiland"]["strehl_ratio"]) for c in mine)
        d_rms = max(
            abs(c["lenspath"]["rms_wavefront_waves"] / c["optiland"]["rms_wavefront_waves"] - 1.0) for c in mine
        )
        d_mtf = max(
            max(
                np.max(np.abs(np.subtract(c["lenspath"][k], c["optiland"][k])))
                for k in ("mtf_tangential", "mtf_sagittal")
            )
            for c in mine
        )
        listed = ", ".join(f"{f:g}" for f in fields)
        print(f"| {name} | {f_number or 'open'} | {listed} | {d_strehl:.4f} | {100 * d_rms:.2f} % | {d_mtf:.4f} |")


if __name__ == "__main__":
    sys.exit(main())
