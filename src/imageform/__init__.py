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
:mod:`imageform.analysis`, :mod:`imageform.io`, :mod:`imageform.report`,
:mod:`imageform.workflows` (file-level operations), :mod:`imageform.batch` and
:mod:`imageform.cli`.

The namespace is lazy (PEP 562): ``import imageform`` loads only :mod:`imageform.errors`;
each subpackage is imported the first time it is used, so ``imageform.color.convert(...)``
works after a bare ``import imageform`` and costs only what the colour package needs.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from imageform import errors
from imageform.errors import (
    DegenerateConfigurationError,
    ImageformError,
    InvalidInputError,
    UnknownOptionError,
)

if TYPE_CHECKING:  # the lazy subpackages, for type checkers and IDEs
    from imageform import (
        analysis,
        batch,
        cli,
        color,
        geometry,
        io,
        optics,
        report,
        sensor,
        simulate,
        spectral,
        workflows,
    )

__version__ = "0.1.0"

#: The subpackages reachable as attributes, imported on first use (``tests/test_lazy_import.py``
#: checks that this lists every public subpackage on disk).
_SUBPACKAGES = (
    "analysis",
    "batch",
    "cli",
    "color",
    "geometry",
    "io",
    "optics",
    "report",
    "sensor",
    "simulate",
    "spectral",
    "workflows",
)

__all__ = [
    "DegenerateConfigurationError",
    "ImageformError",
    "InvalidInputError",
    "UnknownOptionError",
    "__version__",
    "analysis",
    "batch",
    "cli",
    "color",
    "errors",
    "geometry",
    "io",
    "optics",
    "report",
    "sensor",
    "simulate",
    "spectral",
    "workflows",
]


def __getattr__(name: str) -> Any:
    """Import the subpackage ``name`` on first access (PEP 562)."""
    if name in _SUBPACKAGES:
        # import_module also binds the subpackage as an attribute of this module, so the
        # next access is an ordinary attribute lookup
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_SUBPACKAGES})
