"""Ray casting against parallelograms (numba), with its plain array twin.

``raycast_quads(xy, origin, normal, dual_a, dual_b)`` casts, for each row ``(x, y)`` of
``xy``, the camera-frame ray ``s (x, y, 1)``, ``s > 0``, against every quad ``q`` (camera
frame: corner ``O_q``, normal ``n_q``, dual edge vectors ``g_a, g_b``)::

    s_q = (n_q . O_q) / (n_q . d);  X = s_q d;  a = (X - O_q) . g_a;  b = (X - O_q) . g_b

and keeps the nearest ``s`` with ``0 <= a < 1`` and ``0 <= b < 1``. Outputs: the quad index
(-1 for a miss), ``a``, ``b`` and the depth ``z = s`` (the ray's z is 1; ``inf`` for a
miss). Rays with NaN coordinates miss. The twin is
:func:`imageform.simulate.render.raycast_quads_numpy`; ``tests/simulate/test_render.py``
checks they agree (same index, a and b to 1e-12).

The rays run on numba's threads through :func:`imageform._kernels.jit.run_tasks` (a serial
``nogil`` kernel over a range of rays), not a ``parallel=True`` ``prange``: numba's parallel
lowering cost about a second of CPU more on a first ``imageform simulate``.
"""

from __future__ import annotations

import numpy as np

from imageform._kernels.jit import njit, run_tasks

__all__ = ["raycast_quads"]


@njit(fastmath=False, nogil=True)
def _raycast_kernel(i0, i1, xy, origin, normal, ga, gb, idx, a_out, b_out, depth):  # type: ignore[no-untyped-def]  # pragma: no cover
    # rays i0 .. i1 - 1
    nq = origin.shape[0]
    inf = np.inf
    for i in range(np.uint64(i0), np.uint64(i1)):  # unsigned: no wrap-around code
        dx = xy[i, 0]
        dy = xy[i, 1]
        best = inf
        bi = -1
        ba = 0.0
        bb = 0.0
        if np.isfinite(dx) and np.isfinite(dy):
            for q in range(nq):
                den = normal[q, 0] * dx + normal[q, 1] * dy + normal[q, 2]
                if den == 0.0:
                    continue
                num = (
                    normal[q, 0] * origin[q, 0]
                    + normal[q, 1] * origin[q, 1]
                    + normal[q, 2] * origin[q, 2]
                )
                s = num / den
                if s <= 0.0 or s >= best:
                    continue
                rx = s * dx - origin[q, 0]
                ry = s * dy - origin[q, 1]
                rz = s - origin[q, 2]
                aa = rx * ga[q, 0] + ry * ga[q, 1] + rz * ga[q, 2]
                if aa < 0.0 or aa >= 1.0:
                    continue
                bq = rx * gb[q, 0] + ry * gb[q, 1] + rz * gb[q, 2]
                if bq < 0.0 or bq >= 1.0:
                    continue
                best = s
                bi = q
                ba = aa
                bb = bq
        idx[i] = bi
        a_out[i] = ba
        b_out[i] = bb
        depth[i] = best


def raycast_quads(
    xy: np.ndarray, origin: np.ndarray, normal: np.ndarray, dual_a: np.ndarray, dual_b: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Nearest quad hit by each ray ``(x, y, 1)``; float64 in, ``(idx, a, b, depth)`` out."""
    pts = np.ascontiguousarray(xy, dtype=np.float64)
    n = pts.shape[0]
    idx = np.empty(n, dtype=np.int32)
    a = np.empty(n)
    b = np.empty(n)
    depth = np.empty(n)
    o, nq, ga, gb = (
        np.ascontiguousarray(v, dtype=np.float64) for v in (origin, normal, dual_a, dual_b)
    )
    run_tasks(_raycast_kernel, n, pts, o, nq, ga, gb, idx, a, b, depth)
    return idx, a, b, depth
