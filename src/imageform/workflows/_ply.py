"""A coloured point cloud as a PLY file (``imageform reconstruct``'s ``points.ply``).

Written as binary little-endian PLY (Turk's format, as trimesh, Open3D, MeshLab and
CloudCompare read it): one ``vertex`` element with ``x, y, z`` (float), ``red, green, blue``
(uchar) and ``track_length`` (int, how many frames see the point). The reader takes what this
writer writes, and the ASCII and binary files of other writers with scalar vertex properties.

References
----------
G. Turk, "The PLY polygon file format", 1994 (paulbourke.net/dataformats/ply/).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from imageform._validate import describe
from imageform.errors import InvalidInputError

__all__ = ["read_points_ply", "write_points_ply"]

#: PLY scalar types and their NumPy spelling (without the byte order).
_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}  # fmt: skip

_FORMATS = {"ascii": None, "binary_little_endian": "<", "binary_big_endian": ">"}


def write_points_ply(
    path: str | Path, points: Any, colors: Any, track_length: Any, *, comment: str = ""
) -> Path:
    """Write points ``(P, 3)``, their colours ``(P, 3)`` uint8 and track lengths ``(P,)``.

    Binary little-endian; the coordinates as 32-bit floats. ``track_length`` None leaves the
    property out (a depth map's points: ``imageform depth --points``).
    """
    p = np.asarray(points, np.float64).reshape(-1, 3)
    c = np.asarray(colors)
    n = np.ones(p.shape[0], np.int32) if track_length is None else np.asarray(track_length)
    if c.shape != p.shape or c.dtype != np.uint8 or n.shape != (p.shape[0],):
        raise InvalidInputError(
            f"expected colors (P, 3) uint8 and track_length (P,) for {p.shape[0]} points, got "
            f"{describe(c)} and {describe(n)}"
        )
    fields = [("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("red", "u1"), ("green", "u1"),
              ("blue", "u1")]  # fmt: skip
    if track_length is not None:
        fields.append(("track_length", "<i4"))
    rec = np.zeros(p.shape[0], dtype=fields)
    rec["x"], rec["y"], rec["z"] = p[:, 0], p[:, 1], p[:, 2]
    rec["red"], rec["green"], rec["blue"] = c[:, 0], c[:, 1], c[:, 2]
    if track_length is not None:
        rec["track_length"] = n
    lines = ["ply", "format binary_little_endian 1.0"]
    lines += [f"comment {line}" for line in comment.splitlines() if line.strip()]
    lines += [f"element vertex {p.shape[0]}"]
    lines += [f"property float {a}" for a in "xyz"]
    lines += [f"property uchar {a}" for a in ("red", "green", "blue")]
    lines += ["property int track_length"] if track_length is not None else []
    lines += ["end_header"]
    out = Path(path)
    with out.open("wb") as fh:
        fh.write(("\n".join(lines) + "\n").encode("ascii", "replace"))
        fh.write(rec.tobytes())
    return out


def read_points_ply(path: str | Path) -> dict[str, np.ndarray]:
    """Read the vertex element of a PLY file: ``{property name: array}``, in file order.

    ASCII or binary; a file whose vertex element is not the first, or that has list
    properties in it, is refused in one line.
    """
    p = Path(path)
    with p.open("rb") as fh:
        if fh.readline().strip() != b"ply":
            raise InvalidInputError(f"{p} is not a PLY file (no 'ply' line)")
        fmt, count, props, other_before = None, None, [], False
        element = None
        while True:
            raw = fh.readline()
            if not raw:
                raise InvalidInputError(f"{p}: the PLY header has no end_header")
            words = raw.decode("ascii", "replace").split()
            if not words or words[0] in ("comment", "obj_info"):
                continue
            if words[0] == "end_header":
                break
            if words[0] == "format" and len(words) >= 2:
                if words[1] not in _FORMATS:
                    raise InvalidInputError(f"{p}: unknown PLY format {words[1]!r}")
                fmt = words[1]
            elif words[0] == "element" and len(words) == 3:
                element = words[1]
                if element == "vertex":
                    count = int(words[2])
                elif count is None:
                    other_before = True
            elif words[0] == "property" and element == "vertex":
                if words[1] == "list" or len(words) != 3 or words[1] not in _TYPES:
                    raise InvalidInputError(f"{p}: unsupported vertex property {raw!r}")
                props.append((words[2], _TYPES[words[1]]))
        if fmt is None or count is None or other_before:
            raise InvalidInputError(f"{p}: expected a PLY file whose first element is vertex")
        order = _FORMATS[fmt]
        if order is None:
            table = np.loadtxt(fh, ndmin=2, max_rows=count) if count else np.zeros((0, len(props)))
            if table.shape != (count, len(props)):
                raise InvalidInputError(f"{p}: expected {count} vertices, got {table.shape[0]}")
            return {name: table[:, j].astype(kind) for j, (name, kind) in enumerate(props)}
        dtype = np.dtype([(name, order + kind) for name, kind in props])
        data = fh.read(dtype.itemsize * count)
        if len(data) != dtype.itemsize * count:
            raise InvalidInputError(f"{p} is truncated: {count} vertices announced")
        rec = np.frombuffer(data, dtype=dtype, count=count)
        return {name: rec[name].astype(rec[name].dtype.newbyteorder("=")) for name, _ in props}
