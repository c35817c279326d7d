"""Global versus rolling shutter.

A *global* shutter exposes every row over the same interval ``[0, t_exp]``. A *rolling*
shutter (most CMOS sensors) starts row ``r`` at ``r · t_line``: an object moving sideways at
``v`` pixels per second is caught ``v · t_line`` pixels further along on every row below,
so vertical edges lean (skew) by ``v · t_line`` pixels per row.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from imageform._validate import check_option, check_positive
from imageform.errors import InvalidInputError

__all__ = ["rolling_shutter_points", "rolling_shutter_skew", "row_start_times", "shutter_capture"]


def rolling_shutter_skew(velocity: float, line_time: float) -> float:
    """Horizontal shift per row (pixels/row) of an object moving at ``velocity`` px/s.

    .. math:: \\Delta x_{row} = v\\, t_{line}

    Source: C.-K. Liang, L.-W. Chang, H. H. Chen, "Analysis and compensation of rolling
    shutter effect", IEEE TIP 17(8), 2008, §II.

    >>> rolling_shutter_skew(1000.0, 20e-6)  # 1000 px/s, 20 µs per line
    0.02
    """
    t = check_positive(line_time, "line_time (s)", allow_zero=True)
    try:
        v = float(velocity)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"expected a number for velocity, got {velocity!r}") from exc
    return v * t


def row_start_times(rows: int, *, mode: str, line_time: float) -> np.ndarray:
    """Start of exposure of each row (s): all 0 (global) or ``r · t_line`` (rolling).

    >>> row_start_times(3, mode="rolling", line_time=1e-3).tolist()
    [0.0, 0.001, 0.002]
    """
    m = check_option(mode, ("global", "rolling"), "shutter mode")
    t = check_positive(line_time, "line_time (s)", allow_zero=True)
    if int(rows) < 1:
        raise InvalidInputError(f"expected rows >= 1, got {rows!r}")
    r = np.arange(int(rows), dtype=np.float64)
    return r * t if m == "rolling" else np.zeros_like(r)


def rolling_shutter_points(
    points_uv: Any, velocity_uv: Any, *, line_time: float, t0: float = 0.0
) -> np.ndarray:
    """Where a rolling shutter records points moving at constant velocity (instant exposure).

    A point at ``p(t) = p_0 + v (t - t_0)`` is recorded by the row ``r`` whose read-out time
    ``r · t_line`` it occupies: ``r = y_0 + v_y (r t_line - t_0)``, hence

    .. math::

        r = \\frac{y_0 - v_y t_0}{1 - v_y t_{line}},\\qquad
        u = x_0 + v_x (r\\, t_{line} - t_0)

    ``points_uv`` ``(..., 2)`` in pixels at time ``t0``, ``velocity_uv`` ``(..., 2)`` px/s.

    >>> rolling_shutter_points([[10.0, 100.0]], [1000.0, 0.0], line_time=1e-5).tolist()
    [[11.0, 100.0]]
    """
    p = np.asarray(points_uv, dtype=np.float64)
    v = np.broadcast_to(np.asarray(velocity_uv, dtype=np.float64), p.shape)
    if p.shape[-1] != 2:
        raise InvalidInputError(f"expected points_uv of shape (..., 2), got {p.shape}")
    tl = check_positive(line_time, "line_time (s)", allow_zero=True)
    den = 1.0 - v[..., 1] * tl
    if np.any(den <= 0):
        raise InvalidInputError(
            "an object moving down at >= one row per line time outruns the shutter: no solution"
        )
    r = (p[..., 1] - v[..., 1] * t0) / den
    u = p[..., 0] + v[..., 0] * (r * tl - t0)
    return np.stack([u, r], axis=-1)


def shutter_capture(
    render: Callable[[float], Any],
    *,
    exposure_time: float,
    mode: str,
    line_time: float,
    samples: int = 8,
) -> np.ndarray:
    """Integrate a time-varying scene under a global or rolling shutter.

    .. math::

        I(r, c) = \\frac{1}{t_{exp}} \\int_{t_r}^{t_r + t_{exp}} L(r, c, t)\\,dt,\\quad
        t_r = 0 \\text{ (global)},\\ r\\,t_{line} \\text{ (rolling)}

    The integral is the midpoint rule with ``samples`` instants per row.

    Parameters
    ----------
    render : callable ``t -> array (H, W) or (H, W, C)``
        The scene's irradiance image at time ``t`` (s).
    exposure_time, line_time : float
        Seconds (``exposure_time > 0``).
    mode : {"global", "rolling"}
    samples : int

    >>> bar = lambda t: (np.abs(np.arange(8) - (2 + 1000 * t)) < 0.5)[None].repeat(4, 0) * 1.0
    >>> img = shutter_capture(bar, exposure_time=1e-6, mode="rolling", line_time=1e-3,
    ...                       samples=1)
    >>> img.argmax(axis=1).tolist()  # the bar moves 1 px per row: a skewed bar
    [2, 3, 4, 5]
    """
    te = check_positive(exposure_time, "exposure_time (s)")
    if not isinstance(samples, int) or samples < 1:
        raise InvalidInputError(f"expected samples >= 1 (int), got {samples!r}")
    first = np.asarray(render(0.0), dtype=np.float64)
    if first.ndim not in (2, 3):
        raise InvalidInputError(f"render(t) must return (H, W) or (H, W, C), got {first.shape}")
    m = check_option(mode, ("global", "rolling"), "shutter mode")
    starts = row_start_times(first.shape[0], mode=m, line_time=line_time)
    offsets = (np.arange(samples) + 0.5) / samples * te
    out = np.zeros_like(first)
    cache: dict[float, np.ndarray] = {}
    for r, t_r in enumerate(starts):
        acc = np.zeros_like(first[r])
        for dt in offsets:
            t = float(t_r + dt)
            if t not in cache:
                cache[t] = np.asarray(render(t), dtype=np.float64)
            acc += cache[t][r]
        out[r] = acc / samples
        if m == "rolling":
            cache.clear()
    return out
