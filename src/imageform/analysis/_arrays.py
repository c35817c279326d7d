"""Input handling shared by the analysis tools: in-memory NumPy or lazy Dask.

The analysis recipes are NumPy computations (``scipy.ndimage`` morphology, small SVDs).
Large images arrive as Dask arrays and stay lazy: pointwise steps run chunk by chunk
(``map_blocks``), neighbourhood steps with an overlap (``map_overlap``) and global
statistics as real Dask reductions (sums, an exact two-pass quantile). Other array
libraries (PyTorch, array-api-strict) are converted to NumPy at the boundary.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from imageform._backend import to_numpy
from imageform._jsonio import write_json as _write_json
from imageform._validate import as_image, as_path, check_nonempty, describe, format_shape
from imageform.errors import InvalidInputError

__all__ = [
    "image_in",
    "is_dask",
    "read_json",
    "target_source",
    "write_json",
]

_INTEGER_SCALE = {np.dtype(np.uint8): 255.0, np.dtype(np.uint16): 65535.0}


def is_dask(x: object) -> bool:
    """Return True for a Dask array (checked without importing Dask)."""
    return type(x).__module__.startswith("dask.") and hasattr(x, "map_blocks")


def image_in(
    image: object,
    name: str = "image",
    *,
    channels: int | None = 3,
    range_check: bool = True,
    nonempty: bool = False,
) -> Any:
    """Return an RGB image as floats in [0, 1]: NumPy through ``as_image``, Dask kept lazy.

    ``range_check=False`` for linear-light values, which may exceed 1; ``nonempty=True``
    refuses an image without a pixel ("empty image", naming ``name``).

    Dask input: uint8/uint16 are divided by 255/65535 lazily (float32), float32/float64
    are kept; the 0-255-floats range check of ``as_image`` needs a pass over the data and
    is skipped to stay lazy (documented in the tools that accept Dask).
    """
    if nonempty:
        checked = image_in(image, name, channels=channels, range_check=range_check)
        return check_nonempty(checked, name)
    if is_dask(image):
        arr: Any = image
        if channels is not None and (arr.ndim < 1 or arr.shape[-1] != channels):
            raise InvalidInputError(
                f"expected {name} with {channels} channels on axis -1, "
                f"got shape {format_shape(tuple(arr.shape))}"
            )
        dt = np.dtype(arr.dtype)
        if dt in _INTEGER_SCALE:
            return arr.astype(np.float32) / np.float32(_INTEGER_SCALE[dt])
        if dt.kind == "f":
            return arr if dt in (np.float32, np.float64) else arr.astype(np.float32)
        raise InvalidInputError(
            f"expected {name} as uint8, uint16 or floats in [0, 1], got dtype {dt}"
        )
    if not isinstance(image, np.ndarray) and hasattr(image, "__array_namespace__"):
        image = to_numpy(image)
    return np.asarray(as_image(image, name, channels=channels, range_check=range_check))


def write_json(path: str | Path, payload: dict[str, Any]) -> None:
    """Write ``payload`` as indented JSON (arrays as nested lists), atomically, NaN as null.

    The one JSON writer, :func:`imageform._jsonio.write_json`. An output that cannot be
    written (a folder, a device, a missing folder) is refused in one line naming ``path``,
    before anything is written.
    """
    _write_json(path, payload, indent=2)


def read_json(path: str | Path, kind: str) -> dict[str, Any]:
    """Read a JSON file written by ``write_json`` and check its ``kind`` field."""
    p = as_path(path, "path")
    if not p.is_file():
        raise InvalidInputError(f"{kind} file {p} does not exist")
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
    except UnicodeDecodeError:
        raise InvalidInputError(
            f"{p} is not a {kind!r} file: not text (the file is JSON, as imageform writes it)"
        ) from None
    except json.JSONDecodeError as exc:
        raise InvalidInputError(f"{p} is not valid JSON: {exc}") from exc
    if not isinstance(data, dict) or data.get("kind") != kind:
        got = data.get("kind") if isinstance(data, dict) else type(data).__name__
        raise InvalidInputError(f"expected a {kind!r} JSON file in {p}, got kind {got!r}")
    return data


def target_source(target: object, name: str, what: str) -> Any:
    """Return a normalisation target that is not a statistics object: a JSON path or an image.

    An existing JSON file is returned as its :class:`~pathlib.Path`; an image is validated under the
    parameter's own ``name`` (never reported as ``image``).
    """
    from pathlib import Path

    if target is None:
        raise TypeError(f"expected {name} as an image, {what} or a JSON path, got None")
    if isinstance(target, str | Path):
        path = Path(target)
        if not path.is_file():
            raise InvalidInputError(
                f"expected {name} as an image, {what} or an existing JSON file, got "
                f"{describe(str(target))} (no such file)"
            )
        return path
    return image_in(target, name)
