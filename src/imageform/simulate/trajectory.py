r"""A camera moving through the scene: a trajectory in, frames with their true poses out.

``imageform simulate --trajectory PATH.csv --video OUT.mp4`` renders the scene along a camera
path through the whole chain (optics, noise, the camera's processing), one simulation per
frame, and writes the true poses beside the video, so that tracking (``imageform track``) is
measured against the truth.

A trajectory is a CSV with a ``time_s`` column and, per row, the camera's pose, either

- ``rx, ry, rz, tx, ty, tz``: world to camera, :math:`X_c = R X_w + t`, ``r`` a Rodrigues
  vector, ``t`` in metres (the columns of ``imageform track``'s ``poses.csv``), or
- ``eye_x, eye_y, eye_z, target_x, target_y, target_z`` (metres): the camera at ``eye``
  looking at ``target``, the scene's up vector up.

The truth (:func:`board_poses`) is the pose of the scene's checkerboard in the camera frame
(``X_c = R X_b + t``, millimetres, the board's origin at its first inner corner and its
axes along the rows and columns of corners, as :func:`~imageform.geometry.checkerboard_points`
and ``imageform track --board checkerboard:COLSxROWS`` count them), or the camera's own pose
in the world (metres) when the scene has no checkerboard.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from imageform._typing import ArrayLike
from imageform._validate import describe
from imageform.errors import InvalidInputError

if TYPE_CHECKING:
    from imageform.simulate.scene import Scene

__all__ = ["MAX_TRAJECTORY_FRAMES", "Trajectory", "board_poses", "read_trajectory", "render_frames"]

#: Most frames of one trajectory (each is a whole simulation).
MAX_TRAJECTORY_FRAMES = 100_000

_POSE = ("rx", "ry", "rz", "tx", "ty", "tz")
_LOOK = ("eye_x", "eye_y", "eye_z", "target_x", "target_y", "target_z")


class Trajectory:
    """Times and world-to-camera poses of a moving camera.

    Attributes
    ----------
    times : ndarray (n,)
        Seconds, increasing.
    R : ndarray (n, 3, 3)
        World to camera rotations.
    t : ndarray (n, 3)
        World to camera translations (metres).
    """

    def __init__(
        self, times: NDArray[np.float64], R: NDArray[np.float64], t: NDArray[np.float64]
    ) -> None:
        self.times, self.R, self.t = times, R, t

    def __len__(self) -> int:
        """How many frames."""
        return int(self.times.shape[0])

    @property
    def fps(self) -> float:
        """The frame rate: one over the median time step (30 for a single frame)."""
        if len(self) < 2:
            return 30.0
        return float(1.0 / np.median(np.diff(self.times)))


def read_trajectory(path: str | Path, *, up: ArrayLike = (0.0, 0.0, 1.0)) -> Trajectory:
    """Read a trajectory CSV (``time_s`` and a pose or an eye and a target per row).

    Parameters
    ----------
    path : str or Path
        The CSV file.
    up : array_like (3,)
        The up vector of look-at rows (the scene's: z up).

    Returns
    -------
    Trajectory

    Raises
    ------
    InvalidInputError
        A missing file, a header without ``time_s`` and one of the two pose forms, a value
        that is not a finite number, times that do not increase, no rows.
    """
    from imageform.geometry import look_at, rvec_to_matrix

    p = Path(path)
    if not p.is_file():
        raise InvalidInputError(f"trajectory {p} does not exist or is not a file")
    with p.open(newline="", encoding="utf-8-sig") as fh:
        rows = list(csv.reader(fh))
    if not rows:
        raise InvalidInputError(f"trajectory {p} is empty")
    header = [h.strip().lower() for h in rows[0]]
    form = _POSE if all(c in header for c in _POSE) else _LOOK
    need = ("time_s", *form)
    if not all(c in header for c in need):
        raise InvalidInputError(
            f"trajectory {p}: the header needs time_s and rx,ry,rz,tx,ty,tz (world to camera) "
            f"or eye_x,eye_y,eye_z,target_x,target_y,target_z, got "
            f"{describe(','.join(rows[0]))}"
        )
    cols = [header.index(c) for c in need]
    times: list[float] = []
    Rs: list[NDArray[np.float64]] = []
    ts: list[NDArray[np.float64]] = []
    for n, row in enumerate(rows[1:], start=2):
        if not any(c.strip() for c in row):
            continue
        try:
            v = [float(row[i]) for i in cols]
        except (ValueError, IndexError):
            raise InvalidInputError(f"trajectory {p}, line {n}: expected numbers") from None
        if not all(math.isfinite(x) for x in v):
            raise InvalidInputError(f"trajectory {p}, line {n}: values must be finite")
        if len(times) >= MAX_TRAJECTORY_FRAMES:
            raise InvalidInputError(f"trajectory {p} has more than {MAX_TRAJECTORY_FRAMES} rows")
        if form is _POSE:
            R = np.asarray(rvec_to_matrix(np.array(v[1:4])), np.float64)
            t = np.array(v[4:7], np.float64)
        else:
            eye, target = np.array(v[1:4]), np.array(v[4:7])
            if np.linalg.norm(target - eye) == 0:
                raise InvalidInputError(f"trajectory {p}, line {n}: eye and target coincide")
            pose = look_at(eye, target, np.asarray(up, np.float64))
            R, t = np.asarray(pose.R, np.float64), np.asarray(pose.t, np.float64)
        times.append(v[0])
        Rs.append(R)
        ts.append(t)
    if not times:
        raise InvalidInputError(f"trajectory {p} has no rows")
    tt = np.array(times)
    if np.any(np.diff(tt) <= 0):
        raise InvalidInputError(f"trajectory {p}: time_s must increase from row to row")
    return Trajectory(tt, np.array(Rs), np.array(ts))


def _board(scene: Any) -> tuple[Any, tuple[int, int], float] | None:
    """Return the scene's one checkerboard: the object, its inner corners, its square (m)."""
    boards = [o for o in scene.objects if o.kind == "checkerboard"]
    if len(boards) != 1:
        return None
    obj = boards[0]
    cols, rows = (int(x) for x in obj.config.squares)
    return obj, (cols - 1, rows - 1), float(obj.config.square_size_m)


def board_poses(
    scene: Scene, trajectory: Trajectory
) -> tuple[str, list[tuple[np.ndarray, np.ndarray]]] | None:
    """Return the scene's checkerboard in each frame's camera frame (mm); None without one.

    The board frame: the origin at the first inner corner (one square in from the top-left
    square, inside the board's light border),
    x along the rows (``edge_right``), y down the columns (``edge_down``), z = x × y.
    Returns ``("checkerboard:COLSxROWS", [(R, t_mm), ...])``.
    """
    found = _board(scene)
    if found is None:
        return None
    obj, (cols, rows), square = found
    x = obj.edge_right / np.linalg.norm(obj.edge_right)
    y = obj.edge_down / np.linalg.norm(obj.edge_down)
    R_wb = np.column_stack([x, y, np.cross(x, y)])
    margin = float(obj.config.margin_squares) * square  # the light border around the squares
    t_wb = obj.origin + (margin + square) * (x + y)
    out = []
    for R, t in zip(trajectory.R, trajectory.t, strict=True):
        out.append((R @ R_wb, 1000.0 * (R @ t_wb + t)))
    return f"checkerboard:{cols}x{rows}", out


def render_frames(
    scene: Scene,
    trajectory: Trajectory,
    *,
    rng: int = 0,
    progress: Callable[[str, float], None] | None = None,
) -> Iterator[NDArray[np.uint8]]:
    """Render the scene from every pose of ``trajectory`` through the whole chain.

    Yields each frame's encoded output as ``(H, W, 3)`` uint8 RGB; the sensor noise of frame
    ``i`` is seeded with ``rng + i``.
    """
    from imageform.simulate.pipeline import simulate

    n = len(trajectory)
    for i, (R, t) in enumerate(zip(trajectory.R, trajectory.t, strict=True)):
        if progress is not None:
            progress(f"frame {i + 1} of {n}", (i + 0.5) / n)
        cam = {"R": R.tolist(), "t_m": t.tolist()}
        res = simulate(scene.with_changes(camera=cam, views=[]), rng=rng + i, measure=False)
        img = np.asarray(res.stages[-1].image, np.float64)
        yield np.round(np.clip(img, 0.0, 1.0) * 255).astype(np.uint8)
