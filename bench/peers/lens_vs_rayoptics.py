"""Reference numbers for `lens::chromatic::tests::lines_agree_with_rayoptics`:
the paraxial effective focal length and back focal length (last glass surface
to focus) at the g, F, d and C lines of a thin N-BK7 singlet, an N-BK7/SF5
cemented achromat and rayoptics' documented Cooke triplet, by rayoptics with
its own Schott catalogue (opticalglass). Run in a virtual environment with
`pip install rayoptics`:

    python bench/peers/lens_vs_rayoptics.py
"""

from rayoptics.environment import FieldSpec, OpticalModel, PupilSpec, WvlSpec

LINES_NM = (435.8343, 486.1327, 587.5618, 656.2725)
LENSES = {
    "singlet": [[100.0, 0.001, "N-BK7", "Schott"], [-100.0, 1.0]],
    "achromat": [[61.07, 4.0, "N-BK7", "Schott"], [-44.17, 2.5, "SF5", "Schott"], [-128.89, 1.0]],
    "triplet": [
        [23.713, 4.831, "N-LAK9", "Schott"],
        [7331.288, 5.86],
        [-24.456, 0.975, "N-SF5", "Schott"],
        [21.896, 4.822],
        [86.759, 3.127, "N-LAK9", "Schott"],
        [-20.4942, 41.2365],
    ],
}


def first_order(rows: list, reference: int) -> tuple[float, float]:
    """(EFL, bfl) with the model's reference wavelength set to LINES_NM[reference]."""
    opm = OpticalModel()
    sm, osp = opm["seq_model"], opm["optical_spec"]
    osp["pupil"] = PupilSpec(osp, key=["object", "epd"], value=10)
    osp["fov"] = FieldSpec(osp, key=["object", "angle"], flds=[0.0])
    osp["wvls"] = WvlSpec([(nm, 1.0) for nm in LINES_NM], ref_wl=reference)
    opm.radius_mode = True
    sm.gaps[0].thi = 1e10
    for row in rows:
        sm.add_surface(row)
    opm.update_model()
    fod = opm["analysis_results"]["parax_data"].fod
    return float(fod.efl), float(fod.bfl)


for name, rows in LENSES.items():
    for k, nm in enumerate(LINES_NM):
        efl, bfl = first_order(rows, k)
        print(f"{name} {nm} nm: EFL {efl!r}, bfl {bfl!r}")
