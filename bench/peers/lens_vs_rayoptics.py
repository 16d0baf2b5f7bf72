"""Reference numbers from rayoptics (an independent lens design package) for
lenspath's lens tests:

- `lens::chromatic::tests::lines_agree_with_rayoptics`: the paraxial effective
  focal length and back focal length (last glass surface to focus) at the g, F,
  d and C lines of a thin N-BK7 singlet, an N-BK7/SF5 cemented achromat and
  rayoptics' documented Cooke triplet, with its own Schott catalogue.
- `lens::trace::tests::an_aspheric_singlet_traces_as_rayoptics_does`: an even
  asphere (conic and A4-A8) on a singlet; where parallel rays cross the axis.
- `lens::lentil::tests::the_aspheric_fisheye_traces_as_rayoptics_does`: the
  lentil database's 0014 (A4-A10 on four surfaces), read from `../shared` as
  lenspath reads it; where real rays cross a plane behind the lens.
- `lens::lentil::tests::the_anamorphic_prime_traces_as_rayoptics_does`: lentil's
  2004, whose cylinders rayoptics models as toroids; skew rays, and each meridian's
  focal length.
- `lens::trace::tests::a_toric_doublet_traces_as_rayoptics_does`: two toric
  surfaces (one bent each way) and a cylinder on a cemented doublet; skew rays
  and each meridian's focal length.
- `tests/integration/lens_files.rs`: Zemax files (one with TOROIDAL surfaces, which
  rayoptics reads as `YToroid`), and ISET3d files whose stop sits on a
  curved surface's vertex, read by both tools.
- `crates/lenspath/lenses/README.md`: the shipped tables taken from rayoptics'
  own files (triplet50, nikon-z14, achromat100), their EFL and BFL there.

Run in a virtual environment with `pip install rayoptics` (0.9.8 gave the
recorded numbers):

    python bench/peers/lens_vs_rayoptics.py
"""

import json
from pathlib import Path

import numpy as np
from rayoptics.elem.profiles import EvenPolynomial
from rayoptics.environment import FieldSpec, OpticalModel, PupilSpec, WvlSpec
from rayoptics.raytr import raytrace

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


D_LINE_NM = 587.5618


def d_line_model(object_distance_mm: float) -> OpticalModel:
    """An empty model traced at the d line, the object `object_distance_mm` in front."""
    opm = OpticalModel()
    osp = opm["optical_spec"]
    osp["pupil"] = PupilSpec(osp, key=["object", "epd"], value=2)
    osp["fov"] = FieldSpec(osp, key=["object", "angle"], flds=[0.0])
    osp["wvls"] = WvlSpec([(D_LINE_NM, 1.0)], ref_wl=0)
    opm.radius_mode = True
    opm["seq_model"].gaps[0].thi = object_distance_mm
    return opm


def last_ray(opm: OpticalModel, start_y: float, angle_deg: float):
    """Point and direction of a meridional ray after the last surface (its local frame)."""
    a = np.radians(angle_deg)
    path = raytrace.trace(
        opm["seq_model"], np.array([0.0, start_y, 0.0]), np.array([0.0, np.sin(a), np.cos(a)]), D_LINE_NM
    )[0]
    return path[-2][0], path[-2][1]


# The aspheric singlet: an AL50100-style front asphere on n 1.5168, flat back.
singlet = d_line_model(1e10)
singlet["seq_model"].add_surface([0.0, 1.0])
singlet["seq_model"].add_surface([50.3583, 10.2, 1.5168, 64.17])
singlet["seq_model"].ifcs[-2].profile = EvenPolynomial(
    r=50.3583, cc=-0.789119, coefs=[0.0, 2.10405e-7, 1.76468e-11, 1.02641e-15]
)
singlet["seq_model"].add_surface([0.0, 90.0])
singlet.update_model()
fod = singlet["analysis_results"]["parax_data"].fod
print(f"aspheric singlet: EFL {float(fod.efl)!r}, bfl {float(fod.bfl)!r}")
for height in (1.0, 5.0, 10.0, 15.0, 20.0, 24.0):
    p, d = last_ray(singlet, height, 0.0)
    print(f"  parallel ray at {height} mm crosses the axis {float(p[2] - p[1] * d[2] / d[1])!r} mm behind the flat")

# lentil 0014, as lenspath::lens::lentil reads it: flats from radii >= 99999 mm,
# the iris as the stop, n_d (V_d only matters off the d line), A4-A10 on a sphere.
lentil = Path(__file__).resolve().parents[2].parent / "shared" / "lenses" / "lentil" / "lenses.json"


def lentil_model(lens_id: str, profile) -> OpticalModel:
    """A lentil design as lenspath reads it, 50 mm behind the object plane; `profile(element,
    radius)` gives a surface's rayoptics profile, or None to keep it spherical."""
    opm = d_line_model(50.0)
    sm = opm["seq_model"]
    for e in json.loads(lentil.read_text())[lens_id]["optical-elements-patent"]:
        flat = e["material"] == "iris" or abs(e["radius"]) >= 99999
        r = 0.0 if flat else e["radius"]
        if e["material"] in ("air", "iris") or e["ior"] in (None, 1.0):
            sm.add_surface([r, e["thickness"]])
        else:
            sm.add_surface([r, e["thickness"], e["ior"], e["abbe"]])
        if e["material"] == "iris":
            sm.set_stop()
        shape = profile(e, r)
        if shape is not None:
            sm.ifcs[-2].profile = shape
    opm.update_model()
    return opm


fisheye = lentil_model(
    "0014",
    lambda e, r: (
        EvenPolynomial(r=r, cc=0.0, coefs=[0.0, *e["aspherical-equation"]]) if e["aspherical-equation"] else None
    ),
)
fod = fisheye["analysis_results"]["parax_data"].fod
print(f"lentil 0014: EFL {float(fod.efl)!r}, bfl {float(fod.bfl)!r}")
for height, angle in [(0.5, 0.0), (2.0, 0.0), (-4.0, 20.0), (-12.0, 40.0), (-8.0, 40.0), (-16.0, 60.0)]:
    # Start 50 mm in front, aimed to cross the front vertex plane at `height`.
    p, d = last_ray(fisheye, height - np.tan(np.radians(angle)) * 50.0, angle)
    behind = float(p[1] + d[1] * (10.0 - p[2]) / d[2])
    print(f"  ray at {height} mm, {angle} deg: height {behind!r} 10 mm behind the rear vertex")

# Zemax files (crates/lenspath/tests/data/lenses), as rayoptics reads them, at the d
# line; `tests/integration/lens_files.rs::zemax_files_trace_as_rayoptics_reads_them`. rayoptics
# has no L-TIM28 (it substitutes S-TIM28), so that glass gets lenspath's n_d.
from opticalglass.opticalmedium import ConstantIndex  # noqa: E402
from rayoptics.environment import open_model  # noqa: E402

LENS_FILES = Path(__file__).resolve().parents[2] / "crates" / "lenspath" / "tests" / "data" / "lenses"
for name in ("US08427765-1.ZMX", "US00583336-2-scaled.zmx"):
    opm = open_model(str(LENS_FILES / name))
    sm = opm["seq_model"]
    opm["optical_spec"]["wvls"] = WvlSpec([(D_LINE_NM, 1.0)], ref_wl=0)
    if name.startswith("US08427765"):
        sm.gaps[3].medium = ConstantIndex(1.689479492377863, "L-TIM28 (lenspath's n_d)")
    opm.update_model()
    fod = opm["analysis_results"]["parax_data"].fod
    print(f"{name}: EFL {float(fod.efl)!r}, bfl {float(fod.bfl)!r}")
    sm.gaps[0].thi = 50.0  # rays start 50 mm in front of the first surface
    for height in (1.0, 4.0):
        p, d = last_ray(opm, height, 0.0)
        behind = float(p[1] + d[1] * (10.0 - p[2]) / d[2])
        print(f"  parallel ray at {height} mm: height {behind!r} 10 mm behind the rear vertex")


# ISET3d lens files (crates/lenspath/tests/data/lenses/iset3d-*.json) given to rayoptics
# surface by surface, constant indices, the stop where ior and radius are 0;
# `tests/integration/lens_files.rs::a_stop_on_a_curved_vertex_clips_at_the_entrance_pupil`.
for name in ("iset3d-cooke40deg-zemax.json", "iset3d-petzval-zemax.json"):
    opm = OpticalModel()
    sm, osp = opm["seq_model"], opm["optical_spec"]
    osp["pupil"] = PupilSpec(osp, key=["object", "epd"], value=5.0)
    osp["fov"] = FieldSpec(osp, key=["object", "angle"], flds=[0.0])
    osp["wvls"] = WvlSpec([(D_LINE_NM, 1.0)], ref_wl=0)
    opm.radius_mode = True
    sm.gaps[0].thi = 1e10
    for surface in json.loads((LENS_FILES / name).read_text())["surfaces"]:
        n = surface["ior"] or 1.0
        columns = [surface["radius"], surface["thickness"]] + ([] if n == 1.0 else [n, 50.0])
        sm.add_surface(columns, sd=surface["semi_aperture"])
        if surface["ior"] == 0 and surface["radius"] == 0:
            sm.set_stop()
    opm.update_model()
    fod = opm["analysis_results"]["parax_data"].fod
    print(f"{name}: EFL {float(fod.efl)!r}, bfl {float(fod.bfl)!r}")

# The rayoptics files the shipped tables triplet50, nikon-z14 and achromat100 come from.
RAYOPTICS = Path(__import__("rayoptics").__file__).parent
SOURCES = ("models/Sasian Triplet.roa", "optical/tests/Nikon Nikkor Z 14-30mm f-4 S.roa", "codev/tests/CODV_32327.seq")
for name in SOURCES:
    opm = open_model(str(RAYOPTICS / name))
    fod = opm["analysis_results"]["parax_data"].fod
    print(f"{name}: EFL {float(fod.efl)!r}, bfl {float(fod.bfl)!r}")

# lentil 2004, the anamorphic prime (US 6,310,731), as lenspath::lens::lentil reads it:
# `cyl-y` curves in the x-z plane (rayoptics' XToroid with no sweep curvature), `cyl-x`
# in the y-z plane (YToroid); `lens::lentil::tests::the_anamorphic_prime_traces_as_rayoptics_does`.
# Skew rays start 50 mm in front of the front vertex; where they cross the plane 10 mm
# behind the rear vertex, and the paraxial focal lengths of parallel rays 0.01 mm off
# the axis in each meridian (rayoptics' paraxial model sees only the y-z plane).
from rayoptics.elem.profiles import XToroid, YToroid  # noqa: E402

CYLINDERS = {"cyl-y": XToroid, "cyl-x": YToroid}
anamorphic = lentil_model(
    "2004", lambda e, r: CYLINDERS[e["lens-geometry"]](r=r, rR=0.0) if e["lens-geometry"] in CYLINDERS else None
)


def skew_ray(opm: OpticalModel, start: tuple, direction: tuple):
    """Point and direction of a ray after the last surface (its local frame)."""
    d = np.array(direction) / np.linalg.norm(direction)
    path = raytrace.trace(opm["seq_model"], np.array(start), d, D_LINE_NM)[0]
    return path[-2][0], path[-2][1]


def print_skew_rays(name: str, opm: OpticalModel, rays: list, meridians: bool = True):
    """Where each (start, direction) ray crosses the plane 10 mm behind the last surface and,
    with `meridians`, each meridian's focal length from a parallel ray 0.01 mm off the axis."""
    for start, direction in rays:
        p, d = skew_ray(opm, start, direction)
        behind = p + d * (10.0 - p[2]) / d[2]
        print(f"{name} ray from {start} along {direction}: ({float(behind[0])!r}, {float(behind[1])!r})")
    for axis in (0, 1) if meridians else ():
        start = [0.0, 0.0, 0.0]
        start[axis] = 0.01
        p, d = skew_ray(opm, tuple(start), (0.0, 0.0, 1.0))
        print(f"{name} meridian {'xy'[axis]}: focal length {float(-0.01 / d[axis] * d[2])!r} (0.01 mm ray)")


print_skew_rays(
    "lentil 2004",
    anamorphic,
    [
        ((3.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
        ((0.0, 3.0, 0.0), (0.0, 0.0, 1.0)),
        ((2.0, -3.0, 0.0), (0.03, 0.05, 1.0)),
        ((-6.0, 4.0, 0.0), (0.06, -0.03, 1.0)),
        ((5.0, 5.0, 0.0), (-0.08, -0.04, 1.0)),
    ],
)


# A toric doublet, as lenspath's table `TORIC_DOUBLET` (lens::trace::tests) writes it:
# stop in front, `toric=x:R` is rayoptics' YToroid (profile in y-z, swept with radius R
# in x-z), `toric=y:R` its XToroid, `cylinder=y` an XToroid with no sweep curvature.
# Skew rays start 50 mm in front of the stop; where they cross the plane 10 mm behind
# the rear vertex, and each meridian's paraxial focal length from a parallel ray 0.01 mm
# off the axis; `lens::trace::tests::a_toric_doublet_traces_as_rayoptics_does`.
toric = d_line_model(50.0)
sm = toric["seq_model"]
sm.add_surface([0.0, 4.0])
sm.set_stop()
for radius, thickness, index, profile in [
    (40.0, 6.0, 1.62, YToroid(r=40.0, rR=25.0)),
    (-30.0, 2.5, 1.72, XToroid(r=-30.0, rR=-55.0)),
    (-90.0, 30.0, None, XToroid(r=-90.0, rR=0.0)),
]:
    sm.add_surface([radius, thickness] + ([] if index is None else [index, 50.0]))
    sm.ifcs[-2].profile = profile
toric.update_model()
TORIC_RAYS = [
    ((3.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
    ((0.0, 3.0, 0.0), (0.0, 0.0, 1.0)),
    ((2.0, -3.0, 0.0), (0.03, 0.05, 1.0)),
    ((-5.0, 4.0, 0.0), (0.06, -0.03, 1.0)),
    ((5.0, 5.0, 0.0), (-0.08, -0.04, 1.0)),
    ((-6.0, -2.0, 0.0), (0.1, 0.07, 1.0)),
]
print_skew_rays("toric doublet", toric, TORIC_RAYS)


# The Zemax file with TOROIDAL surfaces, read by rayoptics (YToroid, rR = PARM 1);
# `tests/integration/lens_files.rs::a_toroidal_zemax_file_traces_as_rayoptics_reads_it`.
opm = open_model(str(LENS_FILES / "toric-doublet.zmx"))
opm["optical_spec"]["wvls"] = WvlSpec([(D_LINE_NM, 1.0)], ref_wl=0)
opm["seq_model"].gaps[0].thi = 50.0
opm.update_model()
print_skew_rays("toric-doublet.zmx", opm, TORIC_RAYS[:4], meridians=False)
