"""imageform — image formation, end to end.

How a scene becomes pixels (light, optics, sensor, digitisation, colour) and how to go back
(camera geometry, calibration, pose, vanishing points, colour measurement and correction),
with one set of conventions (see ``docs/conventions.md``):

- camera frame x right, y down, z forward; ``X_cam = R @ X_world + t``; ``P = K [R | t]``;
- pixel ``(u, v)`` = (column, row), the centre of the top-left pixel is ``(0, 0)``;
- points ``(..., N, 3)``, matrices applied to row vectors; points with ``z <= 0`` come back
  as NaN with a validity mask, never mirrored in front of the camera;
- images channels-last RGB floats; float32 in → float32 out.

Subpackages: :mod:`imageform.geometry`, :mod:`imageform.color`, :mod:`imageform.spectral`,
:mod:`imageform.optics`, :mod:`imageform.sensor`, :mod:`imageform.simulate`,
:mod:`imageform.analysis`, :mod:`imageform.io`, :mod:`imageform.report`.
"""

from __future__ import annotations

from imageform import errors, geometry
from imageform.errors import (
    DegenerateConfigurationError,
    ImageformError,
    InvalidInputError,
    UnknownOptionError,
)

__version__ = "0.1.0"

__all__ = [
    "DegenerateConfigurationError",
    "ImageformError",
    "InvalidInputError",
    "UnknownOptionError",
    "__version__",
    "errors",
    "geometry",
]
