r"""Chromatic adaptation (von Kries-type): XYZ scaling, von Kries, Bradford, CAT02, CAT16.

A colour seen under a source white is mapped to the colour that looks the same under a
destination white by scaling the cone-like responses ``ρ = M_CAT XYZ``:

.. math:: XYZ_d = M_{CAT}^{-1}\,\mathrm{diag}\!\left(D\frac{Y_s}{Y_d}\frac{\rho_{d}}{\rho_{s}}
    + 1 - D\right) M_{CAT}\, XYZ_s

with :math:`\rho_s, \rho_d` the responses to the two whites and ``D`` the degree of
adaptation (1: complete, the default).
"""

from __future__ import annotations

from types import MappingProxyType
from typing import Literal

import numpy as np

from imageform._backend import device_of, namespace
from imageform._dask import chunkwise
from imageform._typing import Array, ArrayLike
from imageform._validate import as_points_strict, as_real, check_name
from imageform.color.whitepoints import resolve_white
from imageform.errors import InvalidInputError

__all__ = [
    "CAT_MATRICES",
    "chromatic_adaptation",
    "chromatic_adaptation_matrix",
]

_CAT = {
    # The identity: XYZ themselves are scaled ("wrong von Kries").
    "xyz_scaling": np.eye(3),
    # Hunt-Pointer-Estevez cone space, normalised to illuminant E (von Kries transform as
    # tabulated by Lindbloom, "Chromatic Adaptation"; Fairchild, Color Appearance Models).
    "von_kries": np.array(
        [[0.40024, 0.70760, -0.08081], [-0.22630, 1.16532, 0.04570], [0.0, 0.0, 0.91822]]
    ),
    # Lam (1985) / Hunt's Bradford transform, linearised (CIE 159:2004 uses it in CIECAM97s).
    "bradford": np.array(
        [[0.8951, 0.2664, -0.1614], [-0.7502, 1.7135, 0.0367], [0.0389, -0.0685, 1.0296]]
    ),
    # CIE 159:2004 (CIECAM02), eq. (7).
    "cat02": np.array(
        [[0.7328, 0.4296, -0.1624], [-0.7036, 1.6975, 0.0061], [0.0030, 0.0136, 0.9834]]
    ),
    # Li et al. (2017), "Comprehensive color solutions: CAM16, CAT16, and CAM16-UCS",
    # Color Res. Appl. 42(6), 703-718, eq. (3).
    "cat16": np.array(
        [
            [0.401288, 0.650173, -0.051461],
            [-0.250268, 1.204414, 0.045854],
            [-0.002079, 0.048952, 0.953127],
        ]
    ),
}
for _m in _CAT.values():
    _m.setflags(write=False)

#: The cone-response matrices ``M_CAT`` by method name (read-only).
CAT_MATRICES: MappingProxyType[str, np.ndarray] = MappingProxyType(_CAT)


def chromatic_adaptation_matrix(
    src_white: str | ArrayLike,
    dst_white: str | ArrayLike,
    method: Literal["bradford", "cat02", "cat16", "von_kries", "xyz_scaling"] = "bradford",
    *,
    degree: float = 1.0,
    observer: int = 2,
) -> np.ndarray:
    r"""Return the 3x3 matrix that adapts XYZ from ``src_white`` to ``dst_white``.

    .. math:: M = M_{CAT}^{-1}\,\mathrm{diag}\!\left(D\frac{Y_s}{Y_d}\frac{\rho_d}{\rho_s}
        + 1 - D\right) M_{CAT},\qquad \rho = M_{CAT}\,XYZ_w

    Apply it to row vectors: ``xyz_dst = xyz_src @ M.T``.

    Parameters
    ----------
    src_white, dst_white : str or array_like
        Whites: an illuminant name (``"D65"``), an RGB space name, ``(x, y)`` or ``(X, Y, Z)``
        (see :func:`imageform.color.resolve_white`).
    method : {"bradford", "cat02", "cat16", "von_kries", "xyz_scaling"}
        The chromatic adaptation transform's cone space: Bradford (default), CAT02, CAT16,
        von Kries (Hunt-Pointer-Estévez) or plain XYZ scaling.
    degree : float
        Degree of adaptation ``D`` in [0, 1] (CIE 159:2004); 1 adapts completely.
    observer : {2, 10}
        Observer of named illuminants.

    Returns
    -------
    ndarray, shape (3, 3), float64

    References
    ----------
    B. Lindbloom, "Chromatic Adaptation" (brucelindbloom.com), for the method and the
    Bradford/von Kries D65 -> D50 matrices; CIE 159:2004 (CAT02, D); Li et al. (2017) (CAT16).

    Examples
    --------
    Lindbloom's Bradford D65 -> D50 matrix (his whites, 7 decimals):

    >>> M = chromatic_adaptation_matrix((0.95047, 1.0, 1.08883), (0.96422, 1.0, 0.82521))
    >>> M.round(7)[0].tolist()
    [1.0478112, 0.0228866, -0.050127]
    """
    key = check_name(method, _CAT, "chromatic adaptation method")
    D = as_real(degree, "degree")
    if not 0.0 <= D <= 1.0:
        raise InvalidInputError(f"expected degree of adaptation D in [0, 1], got {degree!r}")
    ws = resolve_white(src_white, observer=observer, name="src_white")
    wd = resolve_white(dst_white, observer=observer, name="dst_white")
    m = _CAT[key]
    rho_s = m @ ws
    rho_d = m @ wd
    if np.any(rho_s == 0):
        raise InvalidInputError(
            f"source white {tuple(ws.tolist())} has a zero {key} response; cannot adapt from it"
        )
    gain = D * (ws[1] / wd[1]) * (rho_d / rho_s) + (1.0 - D)
    out: np.ndarray = np.linalg.solve(m, gain[:, None] * m)
    return out


@chunkwise(1)
def chromatic_adaptation(
    xyz: ArrayLike,
    src_white: str | ArrayLike,
    dst_white: str | ArrayLike,
    method: Literal["bradford", "cat02", "cat16", "von_kries", "xyz_scaling"] = "bradford",
    *,
    degree: float = 1.0,
    observer: int = 2,
) -> Array:
    r"""Adapt XYZ seen under ``src_white`` to the corresponding colours under ``dst_white``.

    .. math:: XYZ_d = M\,XYZ_s,\quad M = M_{CAT}^{-1}\,\mathrm{diag}(\rho_d/\rho_s)\,M_{CAT}

    Parameters
    ----------
    xyz : array_like, shape (..., 3)
        CIE XYZ (Y = 1 at the source white); any Array-API array.
    src_white, dst_white : str or array_like
        See :func:`chromatic_adaptation_matrix`.
    method : {"bradford", "cat02", "cat16", "von_kries", "xyz_scaling"}
        The chromatic adaptation transform's cone space: Bradford (default), CAT02, CAT16,
        von Kries (Hunt-Pointer-Estévez) or plain XYZ scaling.
    degree : float
        Degree of adaptation in [0, 1].
    observer : {2, 10}
        Observer of named illuminants.

    Returns
    -------
    array, shape (..., 3)
        Same namespace and dtype as ``xyz``.

    References
    ----------
    See :func:`chromatic_adaptation_matrix`.

    Examples
    --------
    The D65 white (CIE 15:2004 x, y = 0.31271, 0.32902) goes to the D50 white:

    >>> out = chromatic_adaptation([0.950430, 1.0, 1.088801], "D65", "D50", "cat02")
    >>> [round(float(v), 4) for v in out]
    [0.9642, 1.0, 0.8251]
    """
    mat = chromatic_adaptation_matrix(
        src_white, dst_white, method, degree=degree, observer=observer
    )
    from imageform.color import _gpu

    on_gpu = _gpu.adapt(xyz, mat)  # a CUDA array: one kernel
    if on_gpu is not None:
        return on_gpu
    xp = namespace(xyz)
    x = as_points_strict(xyz, "xyz", 3, xp=xp)
    mt = xp.asarray(mat.T.copy(), dtype=x.dtype, device=device_of(x))
    return x @ mt
