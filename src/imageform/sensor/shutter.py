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

from imageform._typing import ArrayLike
from imageform._validate import (
    as_int,
    as_real,
    as_real_array,
    check_memory,
    check_option,
    check_positive,
    check_real_values,
    describe,
    finite_result,
    format_shape,
)
from imageform.errors import InvalidInputError

#: The most midpoint-rule instants :func:`shutter_capture` takes per row (each one renders).
_MAX_SAMPLES = 100_000

__all__ = ["rolling_shutter_points", "rolling_shutter_skew", "row_start_times", "shutter_capture"]


def rolling_shutter_skew(velocity: float, line_time: float) -> float:
    r"""Horizontal shift per row (pixels/row) of an object moving at ``velocity`` px/s.

    .. math:: \Delta x_{row} = v\, t_{line}

    Source: C.-K. Liang, L.-W. Chang, H. H. Chen, "Analysis and compensation of rolling
    shutter effect", IEEE TIP 17(8), 2008, §II.

    Examples
    --------
    >>> rolling_shutter_skew(1000.0, 20e-6)  # 1000 px/s, 20 µs per line
    0.02
    """
    t = check_positive(line_time, "line_time (s)", allow_zero=True)
    v = as_real(velocity, "velocity (px/s)")
    return float(finite_result("the skew", lambda: v * t, velocity=v, line_time=t))


def row_start_times(rows: int, *, mode: str, line_time: float) -> np.ndarray:
    """Start of exposure of each row (s): all 0 (global) or ``r · t_line`` (rolling).

    Examples
    --------
    >>> row_start_times(3, mode="rolling", line_time=1e-3).tolist()
    [0.0, 0.001, 0.002]
    """
    m = check_option(mode, ("global", "rolling"), "shutter mode")
    t = check_positive(line_time, "line_time (s)", allow_zero=True)
    n = as_int(rows, "rows", minimum=1)
    check_memory(n * 16.0, "rows", f"{n} row start times")
    r = np.arange(n, dtype=np.float64)
    if m != "rolling":
        return np.zeros_like(r)
    return finite_result("the row start times", lambda: r * t, rows=n, line_time=t)


def rolling_shutter_points(
    points_uv: ArrayLike, velocity_uv: ArrayLike, *, line_time: float, t0: float = 0.0
) -> np.ndarray:
    r"""Where a rolling shutter records points moving at constant velocity (instant exposure).

    A point at ``p(t) = p_0 + v (t - t_0)`` is recorded by the row ``r`` whose read-out time
    ``r · t_line`` it occupies: ``r = y_0 + v_y (r t_line - t_0)``, hence

    .. math::

        r = \frac{y_0 - v_y t_0}{1 - v_y t_{line}},\qquad
        u = x_0 + v_x (r\, t_{line} - t_0)

    ``points_uv`` ``(..., 2)`` in pixels at time ``t0``, ``velocity_uv`` ``(..., 2)`` px/s.

    Examples
    --------
    >>> rolling_shutter_points([[10.0, 100.0]], [1000.0, 0.0], line_time=1e-5).tolist()
    [[11.0, 100.0]]
    """
    p = as_real_array(points_uv, "points_uv", check=False)
    if p.ndim < 1 or p.shape[-1] != 2:
        raise InvalidInputError(
            f"expected points_uv of shape (..., 2), got {format_shape(p.shape)}"
        )
    vel = as_real_array(velocity_uv, "velocity_uv", check=False)
    try:
        v = np.broadcast_to(vel, p.shape)
    except ValueError:
        raise InvalidInputError(
            f"expected velocity_uv of shape (..., 2) broadcastable to points_uv's "
            f"{format_shape(p.shape)}, got {format_shape(vel.shape)}"
        ) from None
    check_real_values(p, "points_uv")
    check_real_values(vel, "velocity_uv")
    tl = check_positive(line_time, "line_time (s)", allow_zero=True)
    t0v = as_real(t0, "t0 (s)")
    with np.errstate(all="ignore"):
        den = 1.0 - v[..., 1] * tl
    if np.any(~(den > 0)):
        raise InvalidInputError(
            "an object moving down at >= one row per line time outruns the shutter: no solution "
            "(velocity_uv, line_time)"
        )

    def solve() -> np.ndarray:
        r = (p[..., 1] - v[..., 1] * t0v) / den
        u = p[..., 0] + v[..., 0] * (r * tl - t0v)
        return np.stack([u, r], axis=-1)

    return finite_result(
        "the recorded points", solve, points_uv=p, velocity_uv=vel, line_time=tl, t0=t0v
    )


def shutter_capture(
    render: Callable[[float], ArrayLike],
    *,
    exposure_time: float,
    mode: str,
    line_time: float,
    samples: int = 8,
) -> np.ndarray:
    r"""Integrate a time-varying scene under a global or rolling shutter.

    .. math::

        I(r, c) = \frac{1}{t_{exp}} \int_{t_r}^{t_r + t_{exp}} L(r, c, t)\,dt,\quad
        t_r = 0 \text{ (global)},\ r\,t_{line} \text{ (rolling)}

    The integral is the midpoint rule with ``samples`` instants per row.

    Parameters
    ----------
    render : callable ``t -> array (H, W) or (H, W, C)``
        The scene's irradiance image at time ``t`` (s).
    exposure_time, line_time : float
        Seconds (``exposure_time > 0``).
    mode : {"global", "rolling"}
        Every row exposed at once, or row ``i`` starting ``i * line_time`` later.
    samples : int
        Instants per row of the midpoint rule over the exposure.

    Examples
    --------
    >>> bar = lambda t: (np.abs(np.arange(8) - (2 + 1000 * t)) < 0.5)[None].repeat(4, 0) * 1.0
    >>> img = shutter_capture(bar, exposure_time=1e-6, mode="rolling", line_time=1e-3,
    ...                       samples=1)
    >>> img.argmax(axis=1).tolist()  # the bar moves 1 px per row: a skewed bar
    [2, 3, 4, 5]
    """
    if not callable(render):
        raise TypeError(f"expected render as a callable t -> image, got {describe(render)}")
    te = check_positive(exposure_time, "exposure_time (s)")
    n_samples = as_int(samples, "samples", minimum=1, maximum=_MAX_SAMPLES)
    m = check_option(mode, ("global", "rolling"), "shutter mode")
    check_positive(line_time, "line_time (s)", allow_zero=True)
    first = _frame(render, 0.0, None)
    if m == "global":  # every instant is cached: samples frames at once
        check_memory(float(n_samples) * first.nbytes, "samples", f"{n_samples} cached frames")
    starts = row_start_times(first.shape[0], mode=m, line_time=line_time)
    offsets = (np.arange(n_samples) + 0.5) / n_samples * te
    out = np.zeros_like(first)
    cache: dict[float, np.ndarray] = {}
    for r, t_r in enumerate(starts):
        acc = np.zeros_like(first[r])
        for dt in offsets:
            t = float(t_r + dt)
            if t not in cache:
                cache[t] = _frame(render, t, first.shape)
            acc += cache[t][r]
        out[r] = acc / n_samples
        if m == "rolling":
            cache.clear()
    return out


def _frame(render: Callable[[float], Any], t: float, shape: tuple[int, ...] | None) -> np.ndarray:
    """``render(t)`` as a finite float64 image ``(H, W)`` or ``(H, W, C)`` (of ``shape``)."""
    name = f"render({t:g})"
    img = as_real_array(render(t), name, check=False)
    if img.ndim not in (2, 3) or 0 in img.shape or (shape is not None and img.shape != shape):
        want = "(H, W) or (H, W, C), non-empty" if shape is None else format_shape(shape)
        raise InvalidInputError(
            f"expected render(t) to return an image of shape {want}, got "
            f"{format_shape(img.shape)} at t = {t:g} s"
        )
    check_real_values(img, name)
    return img
