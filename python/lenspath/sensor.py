"""The image sensor: from photons to a raw frame, and its development.

    >>> import lenspath
    >>> frame = lenspath.render("cornell-spheres", sensor=lenspath.sensor.Sensor(iso=400), spp=16)
    >>> frame.mosaic.dtype, frame.cfa
    (dtype('uint16'), 'rggb')
    >>> image = frame.develop()  # linear sRGB, (H, W, 3) float32

``Sensor`` describes a sensor (its arguments are the scene file's ``[sensor]``
keys, docs/sensor.md); ``render(..., sensor=...)`` returns the ``RawFrame`` it
reads out: the mosaic of digital numbers as numpy, the levels, pattern and
colour matrix a raw developer needs, ``develop()`` and ``write()`` (DNG,
16-bit PNG or TIFF). ``models()`` lists the spectral responses.
"""

from __future__ import annotations

from ._core import RawFrame, Sensor
from ._core import sensor_models as models

__all__ = ["RawFrame", "Sensor", "models"]
