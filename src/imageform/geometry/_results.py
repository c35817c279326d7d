"""Result types shared by the projection modules (camera, distortion) without an import cycle.

Public through :mod:`imageform.geometry` (and :mod:`imageform.geometry.camera`).
"""

from __future__ import annotations

from typing import NamedTuple

from imageform._typing import Array

__all__ = ["Projection"]


class Projection(NamedTuple):
    """Result of a projection: pixel coordinates and which of them are real images.

    ``uv`` is ``(..., N, 2)`` with NaN where ``valid`` is False (point at or behind the
    camera, ``z_cam <= 0``, or not finite).
    """

    uv: Array
    valid: Array
