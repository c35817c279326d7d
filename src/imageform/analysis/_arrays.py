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
    "exact_quantile",
    "exact_quantiles",
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


def exact_quantile(values: Any, q: float, *, bins: int = 4096) -> float:
    """Return the ``q``-th percentile (NumPy's linear interpolation) of a 1-D Dask array.

    Exact, in two passes of reductions: a histogram locates the bins holding the two order
    statistics that the linear rule interpolates between, then only the values inside
    those bins are gathered and sorted. The result equals ``np.percentile`` on the
    computed array (same order statistics, same interpolation).
    """
    return exact_quantiles([(values, q)], bins=bins)[0]


def exact_quantiles(items: list[tuple[Any, float]], *, bins: int = 4096) -> list[float]:
    """:func:`exact_quantile` of several ``(values, q)`` pairs, their passes computed together.

    Each pass (the counts and ranges, the histograms, the values gathered from the bins) is
    one ``dask.compute`` of all the pairs, so the graphs they share (a Macenko fit's optical
    densities) are computed once per pass: three passes, not four per pair.
    """
    import dask
    import dask.array as da

    stats = dask.compute(*[(da.isfinite(v).sum(), v.min(), v.max()) for v, _ in items])
    plans: list[Any] = []
    for (values, q), (n, lo, hi) in zip(items, stats, strict=True):
        n = int(n)
        if n == 0:
            raise InvalidInputError("cannot take a percentile of no values")
        lo, hi = float(lo), float(hi)
        pos = q / 100.0 * (n - 1)
        k = int(np.floor(pos))
        if hi == lo:
            plans.append(lo)
            continue
        # one bin index expression for counting and for gathering, so the two always agree
        idx = da.minimum(da.floor((values - lo) * (bins / (hi - lo))), bins - 1).astype(np.int64)
        plans.append((values, idx, (k, min(k + 1, n - 1)), pos - k))
    todo = [p for p in plans if not isinstance(p, float)]
    counts = dask.compute(*[da.bincount(p[1], minlength=bins) for p in todo])
    gathers: list[Any] = []
    where: list[list[tuple[int, int]]] = []
    for (values, idx, ranks, _), cnt in zip(todo, counts, strict=True):
        cum = np.cumsum(np.asarray(cnt))
        at = []
        for r in ranks:
            b = int(np.searchsorted(cum, r, side="right"))
            below = int(cum[b - 1]) if b > 0 else 0
            at.append((len(gathers), r - below))
            gathers.append(values[idx == b])
        where.append(at)
    inside = [np.sort(np.asarray(g)) for g in dask.compute(*gathers)]
    done = iter(
        [inside[i0][j0], inside[i1][j1], frac]
        for ((i0, j0), (i1, j1)), (_, _, _, frac) in zip(where, todo, strict=True)
    )
    out = []
    for p in plans:
        if isinstance(p, float):
            out.append(p)
        else:
            a, b, frac = next(done)
            out.append(float(a) + frac * (float(b) - float(a)))
    return out


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
