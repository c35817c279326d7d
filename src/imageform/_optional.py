"""Optional dependencies: import one, or fail with one line naming the install command.

``imageform batch`` and ``imageform chunked`` need the ``scale`` extra (dask, distributed,
zarr); figures need ``plot`` (matplotlib). A missing one is a :class:`MissingExtraError`
(an :class:`~imageform.errors.ImageformError`, so the command line prints its one line and
exits 1), never an ``ImportError`` traceback.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from imageform.errors import ImageformError

__all__ = ["EXTRAS", "MissingExtraError", "require"]

#: The extra that provides each optional module (top-level name).
EXTRAS = {
    "dask": "scale",
    "distributed": "scale",
    "zarr": "scale",
    "matplotlib": "plot",
    "torch": "torch",
    "rawpy": "raw",
    "av": "video",
    "trimesh": "video",
    "cv2": "reconstruct",
    "pillow_heif": "heif",
    "pydicom": "dicom",
}


class MissingExtraError(ImageformError, ImportError):
    """An optional dependency is not installed; the message names the install command."""


def require(module: str, *, what: str) -> ModuleType:
    """Import ``module`` (``"dask.array"``), or raise :class:`MissingExtraError`.

    The error names the extra to install and what needs it.

    Examples
    --------
    >>> require("numpy", what="a test").__name__
    'numpy'
    >>> try:
    ...     require("no_such_module_x", what="a test")
    ... except MissingExtraError as exc:
    ...     print(exc)
    a test needs no_such_module_x, which is not installed: pip install no_such_module_x
    """
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        top = module.split(".")[0]
        missing = (getattr(exc, "name", None) or top).split(".")[0]
        extra = EXTRAS.get(missing) or EXTRAS.get(top)
        how = f'pip install "imageform[{extra}]"' if extra else f"pip install {missing}"
        raise MissingExtraError(f"{what} needs {missing}, which is not installed: {how}") from None
