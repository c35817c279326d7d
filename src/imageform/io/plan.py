"""A surgical plan in the board's frame: points, polylines or a triangle mesh (``track --plan``).

Two kinds of file:

- **CSV** with a header naming ``x``, ``y``, ``z`` (case-insensitive, in the board's unit,
  the unit of ``--square``) and, optionally, ``path``: rows with the same ``path`` value, in
  file order, form one polyline (a planned cut, a trajectory); rows with an empty ``path``
  (or without the column) are single points (targets, landmarks).
- **A triangle mesh** (``.ply``, ``.obj``, ``.stl``, ``.off``: an organ's surface, a tumour
  segmented before surgery), read with trimesh (the ``video`` extra); drawn as its edges.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from imageform._validate import describe
from imageform.errors import InvalidInputError

__all__ = ["PLAN_MESH_SUFFIXES", "Plan", "read_plan"]

#: Mesh files read with trimesh.
PLAN_MESH_SUFFIXES = (".ply", ".obj", ".stl", ".off")

#: Most points a plan may have (a mesh's vertices included).
_MAX_POINTS = 2_000_000


@dataclass(frozen=True)
class Plan:
    """Points, polylines and triangles in the board's frame.

    Attributes
    ----------
    points : ndarray (N, 3)
        Every vertex.
    polylines : tuple of ndarray
        Each an index array into ``points``, drawn as connected segments.
    singles : ndarray (k,)
        Indices of points drawn on their own.
    edges : ndarray (E, 2)
        Index pairs drawn as segments (a mesh's unique edges).
    """

    points: NDArray[np.float64]
    polylines: tuple[NDArray[np.int64], ...] = ()
    singles: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, np.int64))
    edges: NDArray[np.int64] = field(default_factory=lambda: np.zeros((0, 2), np.int64))


def _read_csv(path: Path) -> Plan:
    with path.open(newline="", encoding="utf-8-sig") as fh:
        rows = list(csv.reader(fh))
    if not rows:
        raise InvalidInputError(f"plan {path} is empty")
    header = [h.strip().lower() for h in rows[0]]
    missing = [c for c in ("x", "y", "z") if c not in header]
    if missing:
        raise InvalidInputError(
            f"plan {path}: the header needs columns x, y, z (and optionally path), got "
            f"{describe(','.join(rows[0]))}"
        )
    ix, iy, iz = (header.index(c) for c in ("x", "y", "z"))
    ip = header.index("path") if "path" in header else None
    pts: list[tuple[float, float, float]] = []
    paths: dict[str, list[int]] = {}
    singles: list[int] = []
    for n, row in enumerate(rows[1:], start=2):
        if not any(cell.strip() for cell in row):
            continue
        try:
            p = (float(row[ix]), float(row[iy]), float(row[iz]))
        except (ValueError, IndexError):
            raise InvalidInputError(f"plan {path}, line {n}: expected numbers x, y, z") from None
        if not all(math.isfinite(v) for v in p):
            raise InvalidInputError(f"plan {path}, line {n}: x, y, z must be finite")
        if len(pts) >= _MAX_POINTS:
            raise InvalidInputError(f"plan {path} has more than {_MAX_POINTS} points")
        name = row[ip].strip() if ip is not None and ip < len(row) else ""
        (paths.setdefault(name, []) if name else singles).append(len(pts))
        pts.append(p)
    if not pts:
        raise InvalidInputError(f"plan {path} has no points")
    return Plan(
        np.array(pts, np.float64),
        tuple(np.array(v, np.int64) for v in paths.values()),
        np.array(singles, np.int64),
    )


def _read_mesh(path: Path) -> Plan:
    from imageform._optional import require

    trimesh = require("trimesh", what="reading a mesh plan")
    try:
        mesh = trimesh.load(str(path), force="mesh", process=False)
        v = np.asarray(mesh.vertices, np.float64)
        f = np.asarray(mesh.faces, np.int64)
    except Exception as exc:  # trimesh raises many kinds
        raise InvalidInputError(
            f"plan {path} is not a mesh trimesh can read ({type(exc).__name__})"
        ) from None
    if v.ndim != 2 or v.shape[1] != 3 or v.shape[0] == 0:
        raise InvalidInputError(f"plan {path} has no vertices")
    if v.shape[0] > _MAX_POINTS:
        raise InvalidInputError(f"plan {path} has more than {_MAX_POINTS} vertices")
    if not np.all(np.isfinite(v)):
        raise InvalidInputError(f"plan {path} has vertices that are not finite")
    if f.size:
        e = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
        edges = np.unique(e, axis=0)
        return Plan(v, edges=edges)
    return Plan(v, singles=np.arange(v.shape[0], dtype=np.int64))


def read_plan(path: str | Path) -> Plan:
    r"""Read a plan: a CSV of points and polylines, or a triangle mesh.

    Parameters
    ----------
    path : str or Path
        ``.csv`` (columns ``x, y, z[, path]``) or a mesh (``.ply``, ``.obj``, ``.stl``,
        ``.off``), in the board's frame and unit.

    Returns
    -------
    Plan

    Raises
    ------
    InvalidInputError
        A missing file, a CSV without ``x, y, z`` columns or with a value that is not a
        finite number, an empty plan, a mesh trimesh cannot read.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "plan.csv"
    >>> _ = f.write_text("x,y,z,path\n0,0,0,cut\n30,0,0,cut\n30,30,0,cut\n15,15,-10,\n")
    >>> plan = read_plan(f)
    >>> plan.points.shape, [p.tolist() for p in plan.polylines], plan.singles.tolist()
    ((4, 3), [[0, 1, 2]], [3])
    """
    p = Path(path)
    if not p.exists():
        raise InvalidInputError(f"plan {p} does not exist")
    if not p.is_file():
        raise InvalidInputError(f"plan {p} is not a regular file")
    suffix = p.suffix.lower()
    if suffix == ".csv":
        return _read_csv(p)
    if suffix in PLAN_MESH_SUFFIXES:
        return _read_mesh(p)
    raise InvalidInputError(
        f"expected a plan as .csv or a mesh ({', '.join(PLAN_MESH_SUFFIXES)}), got "
        f"{describe(p.name, 60)}"
    )
