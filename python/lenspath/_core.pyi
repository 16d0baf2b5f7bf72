"""Type stub of the native module ``lenspath._core`` (crates/lenspath-py).

Lengths on lenses are in mm in lens coordinates: ``z`` runs along the axis
from the scene toward the sensor, the aperture stop at 0, so a sensor
position is its distance behind the stop. Scene distances are in scene units
(metres unless the scene says otherwise). Images are linear RGB float32 arrays
of shape (height, width, 3); array arguments may be any array-like, converted.
"""

from collections.abc import Callable, Mapping, Sequence
from os import PathLike
from typing import Any, Literal, TypeAlias, final, overload

import numpy as np
import numpy.typing as npt

__version__: str
#: The most samples per pixel a render takes.
MAX_SAMPLES_PER_PIXEL: int
__all__ = [
    "MAX_SAMPLES_PER_PIXEL",
    "Emission",
    "LenspathError",
    "SceneError",
    "LensError",
    "Scene",
    "Glass",
    "Lens",
    "Camera",
    "Sensor",
    "RawFrame",
    "sensor_models",
    "_sensor_from_settings",
    "load",
    "builtin_scenes",
    "builtin_scene_named",
    "builtin_lenses",
    "defaults",
    "render",
    "read",
    "write",
    "read_exr",
    "write_exr",
    "run_cli",
    "focus_measure",
    "focus_measures",
    "guide_map",
    "bokeh",
    "lens_blur",
    "AutofocusResult",
    "autofocus",
    "__version__",
]

class LenspathError(Exception):
    """Base class of lenspath's own errors."""

class SceneError(LenspathError):
    """A scene file is broken or inconsistent; the message names the file, the element and the fault."""

class LensError(LenspathError):
    """A lens table is broken; the message names the file, the line and the fault."""

@final
class Scene:
    """A scene: shapes, materials, lights and the view it was made for."""

    def __init__(self) -> None:
        """An empty scene; add materials, shapes and a view (``look_at``)."""
    @staticmethod
    def builtin(name: str, mesh_triangles: int = 1_000_000) -> Scene:
        """A built-in scene by name (``builtin_scenes()``); ``mesh_triangles`` sizes ``cornell-mesh``."""
    @property
    def name(self) -> str:
        """The built-in name or the file path."""
    @property
    def source(self) -> str | None:
        """The file it was loaded from or the built-in scene's name; None once built or changed in Python."""
    def compile(self, *, threads: int | None = None) -> None:
        """Builds its BVH now, on ``threads`` threads (default: all cores); otherwise the first render
        does, on that render's threads. Renders share it until the scene changes; the tree is the
        same for any thread count."""
    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        """Pickles as ``Scene.builtin(...)`` or ``load(path)``; TypeError for a scene built in Python."""
    @property
    def mesh_count(self) -> int:
        """Triangle meshes."""
    @property
    def triangle_count(self) -> int:
        """Triangles over all meshes."""
    @property
    def sphere_count(self) -> int:
        """Spheres."""
    @property
    def material_count(self) -> int:
        """Materials (``add_material`` returns their indices)."""
    @property
    def light_count(self) -> int:
        """Point, spot, directional and environment lights plus emissive shapes."""
    @property
    def resolution(self) -> tuple[int, int] | None:
        """The (width, height) the scene file asks for, or None."""
    def add_material(
        self,
        kind: Literal["diffuse", "mirror", "dielectric", "conductor", "glass", "metal"],
        *,
        reflectance: tuple[float, float, float] = (0.8, 0.8, 0.8),
        eta: tuple[float, float, float] | None = None,
        k: tuple[float, float, float] | None = None,
        alpha: float | None = None,
        roughness: float | None = None,
        glass: str | None = None,
        n_d: float | None = None,
        v_d: float | None = None,
        metal: str | None = None,
    ) -> int:
        """Adds a material and returns its index, with the scene files' names: ``diffuse`` and
        ``mirror`` use ``reflectance``; ``dielectric`` takes one of ``eta[0]`` (a constant
        index; default 1.5), ``glass`` (a catalogue glass, ``"N-BK7"``: it disperses) or
        ``n_d`` with optionally ``v_d`` (the Abbe model); ``conductor`` needs ``eta`` and
        ``k`` per channel, or a measured ``metal`` (``"gold"``, ``"Ag"``...), and a GGX
        ``alpha`` (default 0). The kinds ``glass`` and ``metal`` and the keyword
        ``roughness`` are the deprecated old names."""
    def add_mesh(
        self,
        vertices: npt.ArrayLike,
        indices: npt.ArrayLike,
        material: int,
        *,
        emission: tuple[float, float, float] | Emission | None = None,
    ) -> None:
        """Adds a triangle mesh: ``vertices`` N x 3, ``indices`` M x 3 (counter-clockwise
        front faces); ``emission`` (radiance) makes it an area light. Raises SceneError
        for an index out of range, a NaN vertex or an unknown material."""
    def add_sphere(
        self,
        center: tuple[float, float, float],
        radius: float,
        material: int,
        *,
        emission: tuple[float, float, float] | Emission | None = None,
    ) -> None:
        """Adds a sphere; ``emission`` makes it an area light."""
    def add_environment(self, radiance: tuple[float, float, float] | Emission) -> None:
        """Adds a uniform environment light: ``radiance`` from every direction the scene does not block."""
    def add_point_light(
        self, position: tuple[float, float, float], intensity: tuple[float, float, float] | Emission
    ) -> None:
        """Adds an isotropic point light: ``intensity`` in W/sr per channel, or a spectrum."""
    def add_spot_light(
        self,
        position: tuple[float, float, float],
        direction: tuple[float, float, float],
        intensity: tuple[float, float, float] | Emission,
        cutoff_angle_deg: float | None = None,
        exponent: float = 0.0,
        *,
        cone_angle_deg: float | None = None,
    ) -> None:
        """Adds a spot light pointing along ``direction``: ``intensity`` (W/sr) on its axis,
        falling off as cos^``exponent`` of the angle from it, none beyond ``cutoff_angle_deg``,
        the cone's half angle (as pbrt's ``coneangle`` and Mitsuba's ``cutoff_angle``, and the
        scene file's key); ``cone_angle_deg`` is its deprecated old name."""
    def add_directional_light(
        self, direction: tuple[float, float, float], irradiance: tuple[float, float, float] | Emission
    ) -> None:
        """Adds a distant light (the sun) travelling along ``direction``: ``irradiance`` on a
        surface facing it."""
    def look_at(
        self,
        eye: tuple[float, float, float],
        target: tuple[float, float, float],
        up: tuple[float, float, float] = (0.0, 1.0, 0.0),
        fov_deg: float = 40.0,
        focus_distance: float | None = None,
    ) -> None:
        """Sets the view: the camera at ``eye`` looking at ``target``, vertical field of
        view ``fov_deg`` (pinhole and thin lens), subject at ``focus_distance`` (default:
        the target's distance), which the lens cameras focus on unless told otherwise."""

def load(path: str | PathLike[str], allow_read: Sequence[str | PathLike[str]] | None = None) -> Scene:
    """Loads a scene file (COLLADA .dae, OBJ, PLY, glTF .gltf/.glb, lenspath .toml) by extension.
    The files it names (buffers, material libraries, base scenes, meshes, lens tables) are read
    only from its own folder and the ``allow_read`` folders (a scene from elsewhere cannot read
    your other files). Raises SceneError for a broken file or a file named outside those folders,
    OSError when it cannot be read."""

def run_cli(argv: Sequence[str | PathLike[str]]) -> int:
    """Runs the ``lenspath`` command line ``argv`` (the program's name first) in this process and
    returns its exit code (what ``python -m lenspath`` and the ``lenspath`` script call)."""

def builtin_scenes() -> list[str]:
    """The built-in scenes' names."""

def builtin_scene_named(name: str | PathLike[str]) -> str | None:
    """The built-in scene a scene argument names, if any (the rule every front end applies: a
    built-in scene's name is that scene, anything else a scene file's path)."""

@final
class Emission:
    """A spectrum a light or an emitting shape gives off, scaled to a luminance (1: as bright as
    RGB white). Every scene method that takes an RGB amount of light also takes one."""

    @staticmethod
    def blackbody(temperature_k: float, luminance: float = 1.0) -> Emission:
        """Planck's black body at ``temperature_k`` (500 K or more)."""
    @staticmethod
    def tabulated(wavelengths_nm: Sequence[float], values: Sequence[float], luminance: float = 1.0) -> Emission:
        """``values`` at increasing ``wavelengths_nm``: linear between them, zero beyond the ends."""
    @property
    def rgb(self) -> tuple[float, float, float]:
        """Its colour as linear sRGB."""

@final
class Glass:
    """An optical glass of the embedded catalogues (Schott, Ohara, Hoya, CDGM, Sumita,
    Hikari) by name, ``Glass("N-BK7")`` or ``Glass("ohara:S-LAH59")``; a bare name is
    looked up in that order. Raises ``ValueError`` for an unknown name."""

    def __new__(cls, name: str) -> Glass: ...
    @staticmethod
    def abbe(n_d: float, v_d: float) -> Glass:
        """A model glass with index ``n_d`` at the d line and Abbe number ``v_d``
        (two-term Cauchy)."""
    @overload
    def index(self, wavelength_nm: float) -> float:
        """The index of refraction at ``wavelength_nm`` (a number, or an array of them)."""
    @overload
    def index(self, wavelength_nm: npt.ArrayLike) -> npt.NDArray[np.float64]: ...
    @property
    def maker(self) -> str | None:
        """The catalogue (``"schott"``), None for a model glass."""
    @property
    def name(self) -> str:
        """The glass's name."""
    @property
    def n_d(self) -> float:
        """The index at the d line, 587.5618 nm."""
    @property
    def v_d(self) -> float:
        """The Abbe number (n_d - 1) / (n_F - n_C)."""

@final
class Lens:
    """A real compound lens placed on its axis, wide open or stopped down."""

    @staticmethod
    def builtin(name: str) -> Lens:
        """A shipped lens (``builtin_lenses()``: dgauss50, triplet50, tessar100, nikon-z14 ... and
        lentil designs such as lentil:0001), or any lentil database entry (``lentil:0014``)."""
    @staticmethod
    def load(path: str | PathLike[str]) -> Lens:
        """A lens table file (pbrt / CS184 format, with optional glass and aspheric columns), a
        Zemax ``.zmx`` file or an ISET lens ``.json``. Raises LensError for a broken file, naming
        the line (or the surface)."""
    @staticmethod
    def from_table(table: npt.ArrayLike, name: str = "table") -> Lens:
        """A lens from an N x 4 table (radius, thickness to the next surface, index,
        aperture diameter; mm; radius 0 marks the stop). Raises LensError when invalid."""
    def stopped_down(self, f_number: float) -> Lens:
        """This lens with its stop closed to paraxial f-number ``f_number``."""
    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        """Pickles as its name, table text (glass column included) and stop."""
    @staticmethod
    def _from_state(name: str, table_text: str, stopped_to: float | None) -> Lens:
        """The lens ``__reduce__`` describes."""
    @property
    def table_text(self) -> str:
        """The prescription as table text (radius, thickness to the next surface, index,
        aperture, and the glass column where the lens has one; mm), as ``Lens.load`` reads."""
    @property
    def name(self) -> str:
        """The built-in name or the table file's."""
    @property
    def table(self) -> npt.NDArray[np.float64]:
        """The prescription as an N x 4 array (as ``from_table`` takes it)."""
    def analysis(self) -> dict[str, Any]:
        """What ``lenspath lens --json`` prints for the lens as placed, on a 36 x 24 mm sensor, the
        same report (``lenspath::lens_report::LensReport``): focal lengths, pupils, focus range and
        the other first-order and real-ray figures, floats; ``"lines"``, the g, F, d and C lines'
        wavelength, focal length and back focal distance; ``"longitudinal_color_mm"``,
        ``"lateral_color_mm"`` (at ``"lateral_color_field_height_mm"``); the shares of camera rays
        that pass at the image centre and corner (``"passing_fraction_centre"``,
        ``"passing_fraction_corner"``); ``"anamorphic"`` is None, or for a lens with cylinders its
        ``"squeeze"`` and the ``"horizontal"`` and ``"vertical"`` meridians' focal length,
        f-number, entrance pupil, field of view and infinity focus."""
    @property
    def focal_length_mm(self) -> float:
        """Real-ray focal length, |P' - F'|."""
    @property
    def effective_focal_length_mm(self) -> float:
        """Paraxial effective focal length."""
    @property
    def f_number(self) -> float:
        """Paraxial f-number."""
    @property
    def infinity_focus_mm(self) -> float:
        """Sensor position focusing infinity, mm behind the stop."""
    @property
    def close_focus_mm(self) -> float:
        """Sensor position focusing the close-focus object (5 focal lengths away)."""
    def focus_distance_mm(self, sensor_depth_mm: float, ray_height_mm: float = 0.1) -> float | None:
        """Distance in focus (mm from the sensor plane) with the sensor ``sensor_depth_mm``
        behind the stop; None when nothing in front of the lens is in focus."""
    def sensor_depth_mm_for(self, distance_mm: float, ray_height_mm: float = 0.1) -> float:
        """Sensor depth (mm behind the stop) focusing ``distance_mm`` from the sensor plane."""
    def focus_distance(self, sensor_mm: float, ray_height_mm: float = 0.1) -> float | None:
        """Deprecated: ``focus_distance_mm``."""
    def sensor_for_distance(self, distance_mm: float, ray_height_mm: float = 0.1) -> float:
        """Deprecated: ``sensor_depth_mm_for``."""
    def trace(
        self,
        origins: npt.ArrayLike,
        directions: npt.ArrayLike,
        toward: Literal["scene", "sensor"] = "scene",
        wavelength_nm: float | None = None,
    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.bool_]]:
        """Traces N rays (N x 3 origins and directions, lens coordinates) through every
        surface, at ``wavelength_nm`` (default: the d line) when the glasses disperse. Returns
        (origins, unit directions, passed) as they leave the last surface; blocked rays are NaN
        rows with passed False."""
    def chromatic(self, sensor_diagonal_mm: float | None = None) -> dict[str, Any]:
        """The colour figures ``lenspath lens --json`` prints: ``lines`` (g, F, d, C: each
        ``wavelength_nm``, ``effective_focal_length_mm``, ``back_focal_distance_mm``),
        ``longitudinal_color_mm`` (BFD(F) - BFD(C)), ``lateral_color_mm`` (F - C chief-ray
        heights on the d-line image plane) at ``lateral_color_field_height_mm`` (half the
        sensor diagonal; default 36 x 24 mm)."""
    def focal_shift(self, wavelengths_nm: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """The paraxial back focal distance at each wavelength minus the d line's, mm."""
    def focal_shift_plot(self) -> str:
        """The chromatic focal shift plot (400-700 nm) as SVG text."""
    def plot(self, sensor_diagonal_mm: float | None = None) -> str:
        """The lens layout (elements, stop, rays) as SVG text, with a sensor
        ``sensor_diagonal_mm`` across (default: 36 x 24 mm), as ``lenspath lens --plot`` draws it."""
    def layout(self, sensor_diagonal_mm: float | None = None) -> dict[str, Any]:
        """What ``plot`` draws, as arrays of (z, height) rows in mm (z along the axis from the
        stop): ``elements`` (closed outlines), ``stop`` (two blades), ``sensor`` (at infinity
        focus), ``rays`` ((field fraction, wavelength in nm, colour, path) tuples: at the d line,
        or at the F, d and C lines when the glasses disperse), ``z_range_mm``,
        ``half_height_mm``, ``title``. ``lenspath.plot.lens_layout`` draws it with matplotlib."""
    def psf(
        self,
        field_deg: float = 0.0,
        wavelength_nm: float | Sequence[float] | None = None,
        weights: Sequence[float] | None = None,
        sensor_depth_mm: float | None = None,
        pupil_samples: int | None = None,
        padding: int | None = None,
    ) -> tuple[npt.NDArray[np.float64], tuple[float, float]]:
        """The polychromatic PSF at ``field_deg`` by FFT of the real lens's pupil function (as
        ``lenspath lens --psf``): a unit-sum square array, rows along y (tangential), centred on
        the chief ray's image point, and its sample spacing (x, y) in um. ``wavelength_nm``: one
        or several (default: the lens's wavelength), ``weights`` one each (default: equal);
        ``sensor_depth_mm`` behind the stop (default: the infinity focus); ``pupil_samples`` a
        side and the zero ``padding`` default to the library's (128, 4). Raises ValueError for
        a bad field, wavelength or depth."""
    def mtf(
        self,
        field_deg: float = 0.0,
        frequencies_per_mm: Sequence[float] | None = None,
        wavelength_nm: float | Sequence[float] | None = None,
        weights: Sequence[float] | None = None,
        sensor_depth_mm: float | None = None,
        through_focus_per_mm: float | None = None,
        pupil_samples: int | None = None,
        padding: int | None = None,
    ) -> dict[str, Any]:
        """The wave-optics figures at ``field_deg``, as ``lenspath lens --mtf --json`` gives one
        field: ``strehl_ratio``, ``working_f_number``, ``sensor_depth_mm``, ``psf_spacing_um``,
        ``mtf50_tangential_per_mm`` / ``mtf50_sagittal_per_mm`` (None beyond the grid),
        ``wavelengths`` (per wavelength: ``rms_wavefront_waves``, ``strehl_ratio``,
        ``pupil_passing_fraction``, ``zernike_fringe_waves`` Z1..Z37), ``through_focus`` when
        ``through_focus_per_mm`` is given; and the MTF as arrays ``frequencies_per_mm``
        (default 0 to 100 every 5), ``tangential``, ``sagittal``, ``diffraction_limit``.
        Other arguments as ``psf``'s."""

def builtin_lenses() -> list[str]:
    """The shipped lenses' names (``lenspath lens --list``): the built-in tables, then the
    lentil database's designs."""

@final
class Camera:
    """A camera for ``render``; what it leaves unset comes from the scene."""

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        """Pickles as its kind and settings."""
    @staticmethod
    def _from_state(state: tuple[Any, ...], realistic: tuple[float | None, ...]) -> Camera:
        """The camera ``__reduce__`` describes."""
    @staticmethod
    def pinhole(fov_deg: float | None = None) -> Camera:
        """An ideal pinhole; ``fov_deg`` (vertical) defaults to the scene's."""
    @staticmethod
    def thin_lens(
        aperture_radius: float | None = None,
        focus_distance: float | None = None,
        fov_deg: float | None = None,
        aperture: str | npt.ArrayLike | None = None,
    ) -> Camera:
        """An ideal thin lens of ``aperture_radius`` (scene units; default 0.05) focused at
        ``focus_distance`` (default: the scene's subject); ``aperture`` a shape (default: the
        scene file's, else "circle"): "circle", "blades:N[:ROT[:CURV]]", "star:N[:INNER[:ROT]]",
        or a 2-D array of transmissions over the stop's bounding square."""
    @staticmethod
    def realistic(
        lens: Lens | str | None = None,
        *,
        focus_distance: float | None = None,
        sensor_depth_mm: float | None = None,
        sensor_mm: float | None = None,
        f_number: float | None = None,
        sensor_width_mm: float | None = None,
        aperture: str | npt.ArrayLike | None = None,
        scene_unit_m: float | None = None,
        dispersion: bool | None = None,
        desqueeze: bool | None = None,
        diffraction: bool | None = None,
    ) -> Camera:
        """A real lens (default: the scene file's, else dgauss50) focused at ``focus_distance``
        (scene units from the sensor) or with the sensor ``sensor_depth_mm`` behind the stop
        (not both; ``sensor_mm`` is its deprecated old name), stopped down to ``f_number``, a
        ``sensor_width_mm`` wide sensor (default 36; its height follows the image), an
        ``aperture`` shape, ``scene_unit_m`` metres per unit; ``dispersion=False`` gives every
        glass its d-line index (no colour, a little less colour noise; default: the scene file's,
        else glasses disperse); ``desqueeze=True`` stretches an anamorphic lens's image by its
        squeeze (the sensor's height grows by it; default: the scene file's, else squeezed);
        ``diffraction=True`` spreads each film point by the aperture's Fraunhofer pattern at the
        ray's wavelength and the lens's working f-number (default: the scene file's, else off)."""

@overload
def render(
    scene: Scene,
    camera: Camera | None = None,
    *,
    spp: int | None = None,
    resolution: tuple[int, int] | None = None,
    seed: int | None = None,
    max_depth: int | None = None,
    light_samples: int | None = None,
    threads: int | None = None,
    aovs: None = None,
    crop: tuple[int, int, int, int] | None = None,
    progress: Callable[[int, int], Any] | None = None,
    sampler: Literal["sobol", "independent"] | None = None,
    wavelength_nm: float | None = None,
    integrator: Literal["path", "guided"] | None = None,
    sensor: None = None,
) -> npt.NDArray[np.float32]: ...
@overload
def render(
    scene: Scene,
    camera: Camera | None = None,
    *,
    spp: int | None = None,
    resolution: tuple[int, int] | None = None,
    seed: int | None = None,
    max_depth: int | None = None,
    light_samples: int | None = None,
    threads: int | None = None,
    aovs: None = None,
    crop: tuple[int, int, int, int] | None = None,
    progress: Callable[[int, int], Any] | None = None,
    sampler: Literal["sobol", "independent"] | None = None,
    wavelength_nm: float | None = None,
    integrator: Literal["path", "guided"] | None = None,
    sensor: Sensor,
) -> RawFrame: ...
@overload
def render(
    scene: Scene,
    camera: Camera | None = None,
    *,
    spp: int | None = None,
    resolution: tuple[int, int] | None = None,
    seed: int | None = None,
    max_depth: int | None = None,
    light_samples: int | None = None,
    threads: int | None = None,
    aovs: list[str],
    crop: tuple[int, int, int, int] | None = None,
    progress: Callable[[int, int], Any] | None = None,
    sampler: Literal["sobol", "independent"] | None = None,
    wavelength_nm: float | None = None,
    integrator: Literal["path", "guided"] | None = None,
    sensor: None = None,
) -> dict[str, npt.NDArray[np.float32]]: ...
@overload
def render(
    scene: Scene,
    camera: Camera | None = None,
    *,
    spp: int | None = None,
    resolution: tuple[int, int] | None = None,
    seed: int | None = None,
    max_depth: int | None = None,
    light_samples: int | None = None,
    threads: int | None = None,
    aovs: list[str] | None = None,
    crop: tuple[int, int, int, int] | None = None,
    progress: Callable[[int, int], Any] | None = None,
    sampler: Literal["sobol", "independent"] | None = None,
    wavelength_nm: float | None = None,
    integrator: Literal["path", "guided"] | None = None,
    sensor: Sensor | None = None,
) -> npt.NDArray[np.float32] | dict[str, npt.NDArray[np.float32]] | RawFrame: ...
def guide_map(
    scene: Scene,
    camera: Camera | None = None,
    *,
    at: tuple[float, float],
    resolution: tuple[int, int] | None = None,
    seed: int | None = None,
    max_depth: int | None = None,
    light_samples: int | None = None,
    threads: int | None = None,
    sampler: Literal["sobol", "independent"] | None = None,
    size: int = 256,
) -> dict[str, Any]:
    """What the guide of a guided render (``render(..., integrator="guided")`` with the same
    settings) learned at the surface seen at ``at``, a point of the image as fractions of its
    width and height from its top left: the guide's density over the sphere of directions
    there, in the Lambert azimuthal equal-area projection centred on the surface normal, as
    ``lenspath render --guide-map`` writes it. Returns a dict: ``"density_per_sr"`` (float32,
    (size, size): per steradian at each pixel's direction, 0 outside the disc of the sphere;
    the normal at the centre, the horizon the circle of radius size/(2√2), the camera's side
    at the bottom; each pixel covers (4/size)² sr), ``"pixel"`` (the image pixel, x and y),
    ``"share_above_surface"``, ``"total_probability"`` (the density summed over the pixels
    times their solid angle) and ``"leaves"`` (the directional leaves there). Raises
    ValueError where guiding is off (no glass, mirror or smooth metal in the scene), for a
    point that sees nothing or sees glass, a mirror or smooth metal, and for a bad ``at``
    (docs/guiding.md)."""

@final
class Sensor:
    """An image sensor for ``render(..., sensor=...)``: photons to a raw frame (shot noise,
    read noise, dark current, fixed patterns, full well, gain, bit depth, colour filter array)
    and its development. Every argument left out is the scene file's ``[sensor]``, else the
    library's default (ISETCam's Sony IMX363 behind the measured Sony α7 III colour filters);
    the names and spellings are the scene file's (docs/sensor.md)."""

    def __new__(
        cls,
        model: str | None = None,
        *,
        cfa: Literal["rggb", "bggr", "grbg", "gbrg", "mono"] | None = None,
        exposure_time_s: float | None = None,
        iso: float | None = None,
        white_luminance_cd_m2: float | None = None,
        peak_qe: float | None = None,
        read_noise_e: float | None = None,
        full_well_e_per_um2: float | None = None,
        dark_current_e_per_s_um2: float | None = None,
        dsnu_e: float | None = None,
        prnu: float | None = None,
        bit_depth: int | None = None,
        black_level_dn: int | None = None,
        frame_seed: int | None = None,
        fixed_pattern_seed: int | None = None,
        white_balance: str | None = None,
        demosaic: Literal["mhc", "bilinear"] | None = None,
        tone_curve: Literal["linear", "filmic"] | None = None,
        auto_exposure: bool | None = None,
        max_exposure_time_s: float | None = None,
        max_iso: float | None = None,
    ) -> Sensor: ...
    def settings(self) -> dict[str, Any]:
        """Every setting with the defaults filled in (a scene file's ``[sensor]`` aside)."""
    def __reduce__(self) -> tuple[Any, tuple[dict[str, Any]]]: ...

def _sensor_from_settings(settings: dict[str, Any]) -> Sensor: ...
def sensor_models() -> list[str]:
    """The spectral responses a Sensor may name: ``ideal`` (CIE x̄ȳz̄) and 17 measured cameras."""

@final
class RawFrame:
    """A raw frame a sensor read out: the mosaic of digital numbers and what a raw developer
    needs to read it."""

    @property
    def mosaic(self) -> npt.NDArray[np.uint16]:
        """The digital numbers, shape (height, width)."""
    @property
    def cfa(self) -> str:
        """The colour filter array at the top-left pixel: rggb, bggr, grbg, gbrg or mono."""
    @property
    def black_level_dn(self) -> int:
        """Digital number of no light."""
    @property
    def white_level_dn(self) -> int:
        """Largest digital number."""
    @property
    def electrons_per_dn(self) -> float:
        """Electrons per digital number."""
    @property
    def xyz_to_camera(self) -> npt.NDArray[np.float64]:
        """CIE XYZ to the sensor's channels under D65 (DNG ColorMatrix1), 3 × 3."""
    @property
    def as_shot_neutral(self) -> tuple[float, float, float]:
        """The channels' reading of the balanced-for white, largest 1 (DNG AsShotNeutral)."""
    @property
    def sensor_name(self) -> str:
        """The spectral response's name."""
    @property
    def exposure_time_s(self) -> float:
        """The exposure time, s (metered, with auto exposure)."""
    @property
    def iso(self) -> float:
        """The ISO speed (metered, with auto exposure)."""
    def develop(
        self,
        *,
        demosaic: Literal["mhc", "bilinear"] | None = None,
        tone_curve: Literal["linear", "filmic"] | None = None,
    ) -> npt.NDArray[np.float32]:
        """Linear sRGB (H, W, 3): white balance, demosaic, colour matrix, tone curve; what is
        left out is the render's development (what ``lenspath render --out`` writes)."""
    def write(self, path: str | PathLike[str]) -> None:
        """Writes .dng (raw developers read it) or .png / .tif (the 16-bit mosaic), atomically."""

def defaults() -> dict[str, Any]:
    """The library's defaults: what a setting left out of ``render`` or ``autofocus`` becomes
    when the scene file does not give it (resolution, spp, max_depth, light_samples, seed,
    sampler, integrator, guide_training_spp, scene_unit_m, lens, sensor_width_mm,
    thin_lens_aperture_radius, autofocus_*)."""

def read(path: str | PathLike[str]) -> npt.NDArray[np.float32]:
    """Reads a PNG, JPEG (decoded from sRGB) or EXR image as linear RGB (H, W, 3)."""

def write(
    path: str | PathLike[str],
    image: npt.ArrayLike,
    exposure: float = 0.0,
    *,
    depth: npt.ArrayLike | None = None,
    attributes: Mapping[str, _ExrAttribute] | None = None,
) -> None:
    """Writes an image: .png as sRGB after ``exposure`` stops, .exr as floats (R, G, B, and Z
    when ``depth``, (H, W), is given; ``attributes`` in the header, as ``read_exr`` gives
    them); atomically (a temporary file renamed). Images, here and wherever a function takes
    one, are (H, W, 3) RGB or (H, W) grey arrays; floats are linear light, uint8 and uint16 are
    sRGB-encoded values (what Pillow, imageio and OpenCV read from a PNG or JPEG) and are
    decoded to linear."""

_ExrAttribute: TypeAlias = (
    int | float | str | tuple[int, int] | tuple[float, float] | tuple[float, ...] | npt.NDArray[Any]
)

def read_exr(path: str | PathLike[str]) -> dict[str, Any]:
    """Every channel of an EXR and its header: ``{"channels": {name: (H, W) float32},
    "attributes": {name: value}, "display_window": (width, height), "data_origin": (x, y)}``.
    A crop rendered with ``lenspath render --crop`` keeps the whole frame as its display window
    and its place as the data window's origin. Attribute values: ``int``; ``float`` (OpenEXR
    float) or ``numpy.float64`` (double); ``str``; two ints (v2i) or two floats (v2f); a
    (4, 4) float32 array (m44f, row-major as stored: OpenEXR's row-vector convention); 8
    floats (chromaticities: red, green, blue, white xy). Other attribute types are skipped.
    ``write_exr(path, **read_exr(other))`` writes the same image and header."""

def write_exr(
    path: str | PathLike[str],
    channels: Mapping[str, npt.ArrayLike],
    attributes: Mapping[str, _ExrAttribute] | None = None,
    display_window: tuple[int, int] | None = None,
    data_origin: tuple[int, int] | None = None,
) -> None:
    """Writes named (H, W) channels as a 32-bit float EXR, atomically, with ``attributes``
    (as ``read_exr`` gives them; Rec. 709 chromaticities unless given), the frame
    ``display_window`` (default: the channels' size) and the channels' top-left pixel at
    ``data_origin`` in it (default (0, 0)). Attributes are written in name order, so the same input gives the
    same bytes."""

def focus_measure(image: npt.ArrayLike, metric: str | None = None) -> float:
    """A focus measure of an image (RGB or grey, as ``write`` takes): ``focus_measures()`` lists them
    (variance, normalized-variance, sml, tenengrad, brenner, laplacian-energy, vollath); ``None``,
    the autofocus default (``defaults()["autofocus_metric"]``)."""

def focus_measures() -> list[str]:
    """The focus measures' names."""

def bokeh(
    image: npt.ArrayLike,
    *,
    aperture: str | None = None,
    mask: npt.ArrayLike | None = None,
    diameter_px: float | None = None,
    edges: Literal["renormalize", "black"] | None = None,
    method: Literal["auto", "direct", "fft"] | None = None,
) -> npt.NDArray[np.float32]:
    """Blurs an image (RGB or grey, as ``write`` takes) with a bokeh kernel: an ``aperture`` shape ``diameter_px``
    across, or a 2-D ``mask`` (resized so its longer side is ``diameter_px``, if given). ``edges``: "renormalize"
    (the default: no dark border) or "black"; ``method``: "auto" (the default: whichever is faster), "direct"
    or "fft"."""

@final
class AutofocusResult:
    """What ``autofocus`` found and what it cost."""

    @property
    def sensor_depth_mm(self) -> float:
        """The chosen sensor position, mm behind the stop."""
    @property
    def sensor_mm(self) -> float:
        """Deprecated: ``sensor_depth_mm``."""
    @property
    def focus_distance(self) -> float | None:
        """The distance in focus there (scene units from the sensor); None beyond infinity."""
    @property
    def metric(self) -> str:
        """The focus measure's name."""
    @property
    def strategy(self) -> str:
        """The search strategy's name."""
    @property
    def evaluations(self) -> npt.NDArray[np.float64]:
        """Every scored patch image as a (sensor_mm, score) row, in order: patch renders and refocused light fields."""
    @property
    def patch_renders(self) -> int:
        """How many of the evaluations are patch renders."""
    @property
    def light_fields(self) -> int:
        """Light fields recorded (the patch with a margin, refocused to many sensor positions)."""
    @property
    def camera_rays(self) -> int:
        """Camera rays traced (patch render and light-field samples and range-finder probes)."""
    @property
    def fallbacks(self) -> list[str]:
        """What the strategy could not do as its name says, and what it did instead (empty when it
        did all of it): no surface in the patch to range on, or too little budget left for the
        contrast refinement."""
    @property
    def seconds(self) -> float:
        """Wall time."""
    @property
    def depth_of_focus_mm(self) -> float:
        """The sensor shift that grows the blur circle to one pixel there: the unit of focus errors."""
    @property
    def camera(self) -> Camera:
        """The camera given, with its sensor at ``sensor_depth_mm``."""
    @property
    def exposure_time_s(self) -> float | None:
        """Through a sensor: the exposure time its frames were taken at, s (None without one)."""
    @property
    def iso(self) -> float | None:
        """Through a sensor: the ISO speed its frames were taken at (None without one)."""

def autofocus(
    scene: Scene,
    patch: tuple[float, float, float, float],
    camera: Camera | None = None,
    *,
    metric: str | None = None,
    strategy: str | None = None,
    patience: int | None = None,
    spp: int | None = None,
    resolution: tuple[int, int] | None = None,
    seed: int | None = None,
    max_depth: int | None = None,
    threads: int | None = None,
    sensor: Sensor | None = None,
    sensor_signal: str | None = None,
) -> AutofocusResult:
    """Focuses a realistic camera on ``patch`` (x, y, width, height in fractions of the image)
    by rendering it (``strategy``: sweep, early-exit, fast, rangefinder, depth). With ``sensor``
    (over the scene file's ``[sensor]``) contrast autofocus scores the sensor's noisy frames,
    reading ``sensor_signal`` of them (``raw-green``, the default, or ``luminance``), at an
    exposure metered from the first frame and held. Raises ValueError for a bad patch, metric,
    strategy, sensor or a camera that is not realistic."""

def lens_blur(
    image: npt.ArrayLike,
    depth: npt.ArrayLike,
    focus_distance: float,
    *,
    lens: Lens | str | None = None,
    f_number: float | None = None,
    focal_length_mm: float | None = None,
    aperture_radius: float | None = None,
    fov_deg: float | None = None,
    sensor_width_mm: float | None = None,
    scene_unit_m: float | None = None,
    aperture: str | npt.ArrayLike | None = None,
) -> npt.NDArray[np.float32]:
    """Depth-aware lens blur (``lenspath bokeh --focus-distance``): each pixel of the (H, W, 3)
    ``image`` blurred by the thin-lens circle of confusion of its (H, W) ``depth`` (distance
    along the view axis, scene units, as ``render(..., aovs=["depth"])`` gives), in the
    ``aperture``'s shape, the foreground not bleeding into a sharp background. The lens: ``lens``
    (its paraxial focal length and f-number; ``f_number`` stops it down), or ``focal_length_mm``
    with ``f_number``, both on a ``sensor_width_mm`` sensor (default 36 mm) with ``scene_unit_m``
    metres per unit (default 1: the realistic camera's defaults);
    or the thin-lens camera's ``aperture_radius`` (scene units) with its ``fov_deg``."""
