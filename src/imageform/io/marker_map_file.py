"""The marker map file: ArUco markers rigidly attached to one object (track --board markers:).

A TOML file, as the camera file::

    format = "imageform-marker-map"
    version = 1
    dictionary = "4x4_50"   # the markers' ArUco dictionary
    unit = "mm"             # the unit of the corners, and of the poses tracked

    [[markers]]
    id = 0
    # top-left, top-right, bottom-right, bottom-left as printed, in the object's frame
    corners = [[0.0, 0.0, 0.0], [40.0, 0.0, 0.0], [40.0, 40.0, 0.0], [0.0, 40.0, 0.0]]

    [[markers]]
    id = 1
    corners = [...]

Each ``[[markers]]`` table is one marker; its corners must form a square (within 2 %). The
frame is the object's (a tool's, a cube's): a plan drawn on the overlay is in it.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from imageform._files import atomic_write
from imageform._validate import as_path, describe
from imageform.errors import InvalidInputError
from imageform.geometry.marker_map import MarkerMap
from imageform.io._camera_toml import Reader, load_toml, toml_string, toml_value

__all__ = ["MARKER_MAP_FORMAT", "MARKER_MAP_VERSION", "read_marker_map", "write_marker_map"]

#: The ``format`` key of a marker map file.
MARKER_MAP_FORMAT = "imageform-marker-map"
#: The version this imageform writes (and the newest it reads).
MARKER_MAP_VERSION = 1

_KEYS = ("format", "version", "dictionary", "unit", "markers")
#: Most markers one map may hold (the largest predefined dictionary's).
_MAX_MARKERS = 1000


def read_marker_map(path: str | Path, *, dictionary: str | None = None) -> MarkerMap:
    """Read a marker map file (TOML: ``dictionary``, ``unit`` and ``[[markers]]`` id, corners).

    Parameters
    ----------
    path : str or Path
        The file.
    dictionary : str, optional, keyword-only
        The dictionary when the file names none (a file that names one keeps it).

    Returns
    -------
    MarkerMap

    Raises
    ------
    InvalidInputError
        A missing or unreadable file, invalid TOML, a missing or bad key (the message names
        the file and the key), an id twice, corners that are not a square.
    UnknownOptionError
        A key this format does not have.

    Examples
    --------
    >>> import tempfile
    >>> from imageform.geometry import grid_marker_map
    >>> p = Path(tempfile.mkdtemp()) / "tool.toml"
    >>> _ = write_marker_map(p, grid_marker_map((2, 2), 30.0, 6.0, dictionary="4x4_50"))
    >>> m = read_marker_map(p)
    >>> m.ids.tolist(), m.dictionary, m.unit, m.corners[3, 2].tolist()
    ([0, 1, 2, 3], '4x4_50', 'mm', [66.0, 66.0, 0.0])
    """
    p = as_path(path, "path")
    data = load_toml(p, "marker map", "TOML (docs/tracking.md)")
    r = Reader(str(p))
    r.known(data, _KEYS, "")
    fmt = data.get("format", MARKER_MAP_FORMAT)
    if fmt != MARKER_MAP_FORMAT:
        raise r.fail("format", f"expected {MARKER_MAP_FORMAT!r}, got {describe(fmt)}")
    version = r.count(data.get("version", MARKER_MAP_VERSION), "version", minimum=1)
    if version > MARKER_MAP_VERSION:
        raise r.fail(
            "version",
            f"version {version} is newer than this imageform reads ({MARKER_MAP_VERSION})",
        )
    name = r.text(data.get("dictionary", dictionary or "6x6_250"), "dictionary")
    unit = r.text(data.get("unit", "mm"), "unit")
    markers = data.get("markers")
    if not isinstance(markers, list) or not markers:
        raise r.fail("markers", "expected one [[markers]] table or more (id, corners)")
    if len(markers) > _MAX_MARKERS:
        raise r.fail("markers", f"expected at most {_MAX_MARKERS} markers, got {len(markers)}")
    ids: list[int] = []
    corners: list[np.ndarray] = []
    for n, mk in enumerate(markers):
        key = f"markers[{n}]"
        if not isinstance(mk, dict):
            raise r.fail(key, f"expected a table (id, corners), got {describe(mk)}")
        r.known(mk, ("id", "corners"), key + ".")
        if "id" not in mk or "corners" not in mk:
            raise r.fail(key, "expected both id and corners")
        ids.append(r.count(mk["id"], f"{key}.id"))
        c = mk["corners"]
        if not isinstance(c, list) or len(c) != 4:
            raise r.fail(f"{key}.corners", f"expected 4 corners [x, y, z], got {describe(c)}")
        corners.append(np.array([r.vector(v, f"{key}.corners[{i}]") for i, v in enumerate(c)]))
    try:
        return MarkerMap(np.array(ids, np.int64), np.stack(corners), name, unit)
    except InvalidInputError as exc:
        raise InvalidInputError(f"{p}: {exc}") from None


def _text(marker_map: MarkerMap) -> str:
    lines = [
        f"format = {toml_string(MARKER_MAP_FORMAT)}",
        f"version = {MARKER_MAP_VERSION}",
        f"dictionary = {toml_string(marker_map.dictionary)}",
        f"unit = {toml_string(marker_map.unit)}",
        "",
        "# corners: top-left, top-right, bottom-right, bottom-left as printed",
    ]
    for i, c in zip(marker_map.ids, marker_map.corners, strict=True):
        rows: list[Any] = [[float(v) for v in row] for row in c]
        lines += ["", "[[markers]]", f"id = {int(i)}", f"corners = {toml_value(rows)}"]
    return "\n".join(lines) + "\n"


def write_marker_map(path: str | Path, marker_map: MarkerMap) -> Path:
    """Write ``marker_map`` as a marker map file (TOML), atomically; return the path.

    Parameters
    ----------
    path : str or Path
        The file to write (replaced if it exists).
    marker_map : MarkerMap
        The map (:func:`~imageform.geometry.grid_marker_map` makes a planar grid).

    Returns
    -------
    Path
        The path written.

    Examples
    --------
    >>> import tempfile
    >>> from imageform.geometry import grid_marker_map
    >>> p = write_marker_map(Path(tempfile.mkdtemp()) / "g.toml", grid_marker_map((1, 1), 5.0, 0.0))
    >>> p.read_text().splitlines()[0]
    'format = "imageform-marker-map"'
    """
    p = as_path(path, "path")
    if not isinstance(marker_map, MarkerMap):
        raise InvalidInputError(f"expected marker_map as a MarkerMap, got {describe(marker_map)}")
    text = _text(marker_map)
    atomic_write(p, lambda tmp: tmp.write_text(text, encoding="utf-8"))
    return Path(p)
