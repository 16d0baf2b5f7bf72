"""matplotlib drawings of lenspath's results (``pip install lenspath[notebook]``).

    >>> import lenspath, lenspath.plot
    >>> ax = lenspath.plot.lens_layout(lenspath.Lens.builtin("dgauss50"))

Each function draws into ``ax`` (a new figure's axes when None) and returns it.
The geometry comes from the library (``Lens.layout``), the same as ``Lens.plot``'s SVG.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from ._core import AutofocusResult, Lens


def _axes(ax: Axes | None) -> Axes:
    """``ax``, or the axes of a new figure."""
    if ax is not None:
        return ax
    try:
        import matplotlib.pyplot as plt
    except ImportError as e:
        raise ImportError("lenspath.plot needs matplotlib: pip install matplotlib") from e
    return plt.figure(figsize=(10, 4)).add_subplot()


def lens_layout(lens: Lens, ax: Axes | None = None, sensor_diagonal_mm: float | None = None) -> Axes:
    """The lens to scale: glass elements, the stop, the sensor at infinity focus and real
    ray fans from infinity on axis, at 0.7 and at the full field (mm, z along the axis); the
    sensor ``sensor_diagonal_mm`` across (default: 36 x 24 mm)."""
    layout: dict[str, Any] = lens.layout(sensor_diagonal_mm)
    ax = _axes(ax)
    ax.axhline(0.0, color="#888", linestyle="--", linewidth=0.8)
    for outline in layout["elements"]:
        ax.fill(outline[:, 0], outline[:, 1], facecolor="#cfe3f5", edgecolor="#234", linewidth=1.2)
    for blade in layout["stop"]:
        ax.plot(blade[:, 0], blade[:, 1], color="black", linewidth=3)
    sensor = layout["sensor"]
    ax.plot(sensor[:, 0], sensor[:, 1], color="#444", linewidth=4)
    for _field, _wavelength, colour, path in layout["rays"]:
        ax.plot(path[:, 0], path[:, 1], color=colour, linewidth=0.8)
    ax.set_xlim(*layout["z_range_mm"])
    ax.set_ylim(-layout["half_height_mm"], layout["half_height_mm"])
    ax.set_aspect("equal")
    ax.set_xlabel("z (mm, from the stop)")
    ax.set_ylabel("height (mm)")
    ax.set_title(layout["title"], fontsize=9)
    return ax


def focus_curve(result: AutofocusResult, ax: Axes | None = None, label: str | None = None) -> Axes:
    """An autofocus search: each evaluation's score (patch renders and patch images refocused
    from a light field) against its sensor position, and the chosen position."""
    ax = _axes(ax)
    points = np.asarray(result.evaluations)
    order = np.argsort(points[:, 0], kind="stable")
    name = label or f"{result.strategy} ({result.metric})"
    ax.plot(points[order, 0], points[order, 1], "o-", markersize=3, linewidth=0.8, label=name)
    ax.axvline(result.sensor_depth_mm, color="black", linewidth=1, label=f"chosen: {result.sensor_depth_mm:.4f} mm")
    ax.set_xlabel("sensor position (mm behind the stop)")
    ax.set_ylabel(f"{result.metric} score")
    ax.legend()
    return ax
