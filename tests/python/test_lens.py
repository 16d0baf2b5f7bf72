"""lenspath.Lens: the CLI's analysis, focusing, vectorised tracing, tables and their errors."""

from __future__ import annotations

import json
import subprocess

import numpy as np
import pytest

import lenspath

# The built-in tables, at the scales of a camera lens (the lentil designs include 1 mm
# fisheyes and 100 mm lenses that focus no nearer than a few focal lengths).
LENSES = ("dgauss50", "wide22", "tele250", "fisheye10")


@pytest.mark.parametrize("name", lenspath.builtin_lenses())
def test_analysis_equals_the_clis(cli, name: str) -> None:
    out = subprocess.run([str(cli), "lens", name, "--json"], check=True, capture_output=True, text=True)
    theirs = json.loads(out.stdout)
    ours = lenspath.Lens.builtin(name).analysis()
    # One report in the library: every key and every number the same.
    assert ours == theirs
    assert {"lines", "longitudinal_color_mm", "passing_fraction_centre", "passing_fraction_corner"} <= set(ours)
    assert set(ours["lines"]) == {"g", "F", "d", "C"}


def test_every_shipped_lens_is_offered_and_listed(cli) -> None:
    out = subprocess.run([str(cli), "lens", "--list", "--json"], check=True, capture_output=True, text=True)
    listed = json.loads(out.stdout)
    assert [lens["name"] for lens in listed] == lenspath.builtin_lenses()
    assert set(LENSES) < set(lenspath.builtin_lenses())
    for entry in listed:
        lens = lenspath.Lens.builtin(entry["name"])
        assert lens.analysis()["effective_focal_length_mm"] == entry["focal_length_mm"], entry["name"]
    # Any lentil entry by id, also one the list leaves out (lentil's own test lenses).
    assert lenspath.Lens.builtin("lentil:9993").focal_length_mm == pytest.approx(99.93, abs=0.01)
    # An anamorphic one: its own focal length in each meridian (rayoptics: 31.4876, 60.5546).
    anamorphic = lenspath.Lens.builtin("lentil:2004").analysis()["anamorphic"]
    assert anamorphic["horizontal"]["effective_focal_length_mm"] == pytest.approx(31.4876, abs=1e-4)
    assert anamorphic["vertical"]["effective_focal_length_mm"] == pytest.approx(60.5546, abs=1e-4)
    assert anamorphic["squeeze"] == pytest.approx(60.5546 / 31.4876, rel=1e-5)
    assert lenspath.Lens.builtin("dgauss50").analysis()["anamorphic"] is None


@pytest.mark.parametrize("name", LENSES)
def test_focusing_round_trips(name: str) -> None:
    lens = lenspath.Lens.builtin(name)
    f = lens.focal_length_mm
    for distance_mm in [8 * f, 40 * f, 1000 * f]:
        sensor = lens.sensor_depth_mm_for(distance_mm)
        assert lens.infinity_focus_mm < sensor
        assert lens.focus_distance_mm(sensor) == pytest.approx(distance_mm, rel=1e-6)
    # In front of the infinity focus nothing is in focus.
    assert lens.focus_distance_mm(lens.infinity_focus_mm - 0.5) is None


@pytest.mark.parametrize("name", LENSES)
def test_tracing_to_the_scene_and_back_returns_the_ray(name: str) -> None:
    lens = lenspath.Lens.builtin(name)
    rng = np.random.default_rng(1)
    n = 500
    sensor = lens.infinity_focus_mm
    origins = np.column_stack([rng.uniform(-3, 3, n), rng.uniform(-3, 3, n), np.full(n, sensor)])
    rear = lens.analysis()["rear_vertex_mm"]
    aperture = lens.table[-1, 3] / 2
    targets = np.column_stack([rng.uniform(-aperture, aperture, (n, 2)) * 0.7, np.full(n, rear)])
    out_o, out_d, passed = lens.trace(origins, targets - origins, toward="scene")
    assert 0.1 < passed.mean() <= 1.0
    assert np.isnan(out_o[~passed]).all()
    # Back from a point 10 mm out in the scene along each ray.
    start = out_o[passed] + 10.0 * out_d[passed]
    back_o, back_d, back_passed = lens.trace(start, -out_d[passed], toward="sensor")
    assert back_passed.all()
    # Where the returning ray meets the sensor plane is where it started.
    t = (sensor - back_o[:, 2]) / back_d[:, 2]
    hit = back_o + back_d * t[:, None]
    np.testing.assert_allclose(hit, origins[passed], atol=1e-8)


def test_a_table_round_trips_and_stopping_down_changes_the_f_number() -> None:
    lens = lenspath.Lens.builtin("dgauss50")
    again = lenspath.Lens.from_table(lens.table, name="copy")
    # The table keeps the d-line indices, not the glasses: every figure at the d line round-trips;
    # the colour lines (and the pupils through 360-830 nm that the passing fractions use) do not.
    by_glass = {"lens", "lines", "longitudinal_color_mm", "lateral_color_mm"}
    by_glass |= {"passing_fraction_centre", "passing_fraction_corner"}
    ours, theirs = again.analysis(), lens.analysis()
    assert set(ours) == set(theirs)
    for key in set(ours) - by_glass:
        assert ours[key] == theirs[key], key
    assert ours["lens"] == "copy"
    assert ours["longitudinal_color_mm"] == 0.0, "no glass in a table of indices: no colour"
    assert lens.stopped_down(8.0).f_number == pytest.approx(8.0, rel=1e-6)
    assert "<svg" in lens.plot()


def test_a_thin_lens_table_obeys_the_lensmakers_equation() -> None:
    # A thin biconvex element (R = ±100 mm, n = 1.5) then the stop:
    # 1/f = (n - 1)(1/R1 - 1/R2) = 0.5 · 0.02, f = 100 mm.
    table = [[100.0, 0.01, 1.5, 20.0], [-100.0, 1.0, 1.0, 20.0], [0.0, 1.0, 1.0, 10.0]]
    lens = lenspath.Lens.from_table(table)
    assert lens.effective_focal_length_mm == pytest.approx(100.0, rel=1e-3)


@pytest.mark.parametrize(
    ("table", "message"),
    [
        ("1 2 3\n", "line 1"),
        ("50 5 1.6 nan\n0 5 1 20\n", "line 1"),
        ("50 5 1.6 30\n-50 5 1 30\n", "stop"),
    ],
    ids=["columns", "nan", "no-stop"],
)
def test_broken_lens_files_raise_lens_error_naming_the_file(tmp_path, table: str, message: str) -> None:
    path = tmp_path / "broken.dat"
    path.write_text(table)
    with pytest.raises(lenspath.LensError, match=message) as info:
        lenspath.Lens.load(path)
    assert "broken.dat" in str(info.value)


def test_lens_errors_by_kind(tmp_path) -> None:
    with pytest.raises(ValueError, match="unknown built-in lens 'zeiss'"):
        lenspath.Lens.builtin("zeiss")
    with pytest.raises(OSError, match="missing.dat"):
        lenspath.Lens.load(tmp_path / "missing.dat")
    with pytest.raises(ValueError, match="4 columns"):
        lenspath.Lens.from_table(np.zeros((3, 5)))
    with pytest.raises(ValueError, match="toward must be 'scene' or 'sensor'"):
        lenspath.Lens.builtin("dgauss50").trace([[0, 0, 0]], [[0, 0, 1]], toward="up")


def test_shared_lens_tables_load(shared) -> None:
    tables = sorted((shared / "lenses").glob("*.dat"))
    assert tables, "no lens tables in ../shared/lenses"
    for path in tables:
        lens = lenspath.Lens.load(path)
        assert lens.focal_length_mm > 0, path


def test_the_old_names_of_the_focus_conversions_still_work_and_say_the_new_ones() -> None:
    lens = lenspath.Lens.builtin("dgauss50")
    with pytest.warns(DeprecationWarning, match="use sensor_depth_mm_for"):
        old_sensor = lens.sensor_for_distance(2000.0)
    assert old_sensor == lens.sensor_depth_mm_for(2000.0)
    with pytest.warns(DeprecationWarning, match="use focus_distance_mm"):
        old_distance = lens.focus_distance(old_sensor)
    assert old_distance == lens.focus_distance_mm(old_sensor)


def test_glass_tool_gives_lines_partial_dispersion_and_equivalents(cli, tmp_path) -> None:
    out = subprocess.run([str(cli), "glass", "N-BK7", "--json"], check=True, capture_output=True, text=True)
    bk7 = json.loads(out.stdout)
    # Schott's catalogue: n_F 1.52238, n_C 1.51432, P_g,F 0.5349.
    assert bk7["glass"]["indices"]["n_F"] == pytest.approx(1.52238, abs=1e-5)
    assert bk7["glass"]["indices"]["n_C"] == pytest.approx(1.51432, abs=1e-5)
    assert bk7["glass"]["partial_dispersion_g_f"] == pytest.approx(0.5349, abs=5e-4)
    # Internal transmittance from the catalogue's extinction (Schott's data sheet: 0.997 and
    # 0.992 through 10 and 25 mm at 400 nm).
    transmittance = bk7["glass"]["internal_transmittance"]
    assert transmittance["thickness_mm"] == [10.0, 25.0]
    h_line = transmittance["values"][transmittance["wavelength_nm"].index(404.66)]
    assert h_line == pytest.approx([0.997, 0.993], abs=1e-3)
    makers = [g["glass"].split(":")[0] for g in bk7["nearest_of_each_maker"]]
    assert makers == ["schott", "ohara", "hoya", "cdgm", "sumita", "hikari"]
    plot = tmp_path / "abbe.svg"
    subprocess.run([str(cli), "glass", "--lens", "dgauss50", "--plot", str(plot)], check=True, capture_output=True)
    assert plot.read_text().count('stroke="#c00"') == 5  # dgauss50's five distinct glasses, marked
    # tessar100's three glasses are constant indices: listed, but with no V_d to place them by.
    args = [str(cli), "glass", "--lens", "tessar100", "--json", "--plot", str(plot)]
    constant = json.loads(subprocess.run(args, check=True, capture_output=True, text=True).stdout)["lens_glasses"]
    assert len(constant) == 3 and all(g["v_d"] is None for g in constant)
    assert plot.read_text().count('stroke="#c00"') == 0
    bad = subprocess.run([str(cli), "glass", "N-BK8"], capture_output=True, text=True)
    assert bad.returncode == 2 and "unknown glass 'N-BK8'" in bad.stderr


def test_desqueezing_stretches_only_an_anamorphic_lens_image() -> None:
    """``desqueeze=True`` keeps the sensor's width and makes it the squeeze times taller: a
    different picture through an anamorphic lens, the same one through a round lens."""
    options = {"spp": 2, "resolution": (40, 30)}

    def shot(lens: str, desqueeze: bool | None) -> np.ndarray:
        return lenspath.render("cornell-spheres", lenspath.Camera.realistic(lens, desqueeze=desqueeze), **options)

    assert np.array_equal(shot("dgauss50", True), shot("dgauss50", None))
    squeezed, desqueezed = shot("lentil:2004", False), shot("lentil:2004", True)
    assert squeezed.shape == desqueezed.shape
    assert not np.array_equal(squeezed, desqueezed)
