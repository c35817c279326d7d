r"""Simulation of colour-vision deficiency (protan, deutan, tritan) in linear sRGB.

Three models, each with a severity in [0, 1]:

- ``"machado2009"``: Machado, Oliveira & Fernandes (2009), *A physiologically-based model for
  simulation of color vision deficiency*, IEEE TVCG 15(6):1291-1298. Their pre-computed
  matrices for severities 0.0, 0.1, ..., 1.0 (shipped exactly as published,
  ``spectral/data/cvd_machado2009.csv``) act on linear RGB; between tenths the two nearest
  matrices are interpolated linearly, as the authors suggest.
- ``"brettel1997"``: Brettel, Viénot & Mollon (1997), *Computerized simulation of color
  appearance for dichromats*, JOSA A 14(10):2647-2655. In LMS space the missing cone's
  response is replaced so that the stimulus falls on one of two half-planes through the
  neutral axis and a monochromatic anchor (475/575 nm for protan and deutan, 485/660 nm for
  tritan); the half-plane is chosen by the side of the plane through the neutral axis and the
  missing cone's axis.
- ``"vienot1999"``: Viénot, Brettel & Mollon (1999), *Digital video colourmaps for checking
  the legibility of displays by dichromats*, Color Res. Appl. 24(4):243-252: one plane through
  black, white and the display's blue (protan/deutan: Brettel's two half-planes nearly
  coincide for a display). For tritan the paper gives no plane; we use white and the red
  primary (the libDaltonLens choice), with a note that Brettel 1997 is the better tritan model.

LMS for Brettel and Viénot: :math:`\mathrm{LMS} = M_{SP}\,\mathrm{XYZ}` with the Smith & Pokorny
(1975) matrix that Viénot et al. (1999, eq. 3) use, XYZ from linear sRGB (IEC 61966-2-1) and the
anchors' XYZ from the CIE 1931 colour-matching functions. For severity :math:`s < 1` these two
models blend linearly: :math:`(1 - s)\,\mathrm{rgb} + s\,\mathrm{sim}(\mathrm{rgb})`.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any, NamedTuple

import numpy as np

from imageform._backend import device_of, is_numpy_namespace, namespace
from imageform._dask import chunkwise
from imageform._typing import Array, ArrayLike
from imageform._validate import as_bool, as_image_strict, as_real, check_name
from imageform.errors import InvalidInputError

__all__ = [
    "CVD_DEFICIENCIES",
    "CVD_METHODS",
    "BrettelPlanes",
    "brettel_planes",
    "cvd_matrix",
    "machado_matrix",
    "simulate_cvd",
]

CVD_DEFICIENCIES = ("protan", "deutan", "tritan")
CVD_METHODS = ("machado2009", "brettel1997", "vienot1999")
_ALIASES = {
    "protanopia": "protan",
    "protanomaly": "protan",
    "protanope": "protan",
    "deuteranopia": "deutan",
    "deuteranomaly": "deutan",
    "deuteranope": "deutan",
    "tritanopia": "tritan",
    "tritanomaly": "tritan",
    "tritanope": "tritan",
}
_METHOD_ALIASES = {"machado": "machado2009", "brettel": "brettel1997", "vienot": "vienot1999"}

# Smith & Pokorny (1975) cone fundamentals from Judd-Vos XYZ, as Viénot et al. (1999) eq. 3.
_M_SP = np.array(
    [
        [0.15514, 0.54312, -0.03286],
        [-0.15514, 0.45684, 0.03286],
        [0.0, 0.0, 0.01608],
    ]
)
_ANCHORS_NM = {"protan": (475.0, 575.0), "deutan": (475.0, 575.0), "tritan": (485.0, 660.0)}
_MISSING = {"protan": 0, "deutan": 1, "tritan": 2}


def _deficiency(name: object) -> str:
    if isinstance(name, str):
        key = name.strip().lower()
        key = _ALIASES.get(key, key)
        if key in CVD_DEFICIENCIES:
            return key
    valid = [*CVD_DEFICIENCIES, *_ALIASES]
    return check_name(name, valid, "colour-vision deficiency", "deficiency")


def _method(name: object) -> str:
    if isinstance(name, str):
        key = name.strip().lower().replace("-", "").replace("_", "")
        key = _METHOD_ALIASES.get(key, key)
        if key in CVD_METHODS:
            return key
    return check_name(name, CVD_METHODS, "CVD simulation method")


def _severity(severity: object) -> float:
    s = as_real(severity, "severity")
    if not 0.0 <= s <= 1.0:
        raise InvalidInputError(f"expected a severity in [0, 1], got {severity!r}")
    return s


@lru_cache(maxsize=1)
def _machado_table() -> dict[str, np.ndarray]:
    from imageform.spectral.data import read_table

    table = read_table("cvd_machado2009")  # columns: deficiency, severity, m00 ... m22
    out: dict[str, np.ndarray] = {}
    for d in CVD_DEFICIENCIES:
        mats = [
            row[1:].reshape(3, 3)
            for name, row in zip(table.labels, table.values, strict=True)
            if name == d
        ]
        arr = np.stack(mats)
        arr.setflags(write=False)
        out[d] = arr
    return out


def machado_matrix(deficiency: str, severity: float = 1.0) -> np.ndarray:
    """Machado et al. (2009) linear-RGB matrix, interpolated between tenths of severity.

    Examples
    --------
    >>> machado_matrix("deutan", 1.0)[0].tolist()
    [0.367322, 0.860646, -0.227968]
    """
    d, s = _deficiency(deficiency), _severity(severity)
    table = _machado_table()[d]
    i = min(int(np.floor(s * 10.0 + 1e-9)), 9)
    t = s * 10.0 - i
    return np.asarray((1.0 - t) * table[i] + t * table[i + 1])


@lru_cache(maxsize=1)
def _rgb_lms() -> tuple[np.ndarray, np.ndarray]:
    """Linear sRGB to LMS and back, (3, 3) each (cached, read-only: shared by every call)."""
    from imageform.color.rgb_spaces import rgb_to_xyz_matrix

    t = _M_SP @ rgb_to_xyz_matrix("srgb")
    t_inv = np.linalg.inv(t)
    t.setflags(write=False)
    t_inv.setflags(write=False)
    return t, t_inv


def _anchor_lms(wavelength: float) -> np.ndarray:
    from imageform.spectral.data import cmfs

    xyz = cmfs(2).interpolate([wavelength]).values[0]
    return np.asarray(_M_SP @ xyz)


def _projection(missing: int, white: np.ndarray, anchor: np.ndarray) -> np.ndarray:
    """LMS matrix replacing component ``missing`` to land on the plane (0, white, anchor)."""
    n = np.cross(white, anchor)
    p = np.eye(3)
    p[missing] = -n / n[missing]
    p[missing, missing] = 0.0
    return p


class BrettelPlanes(NamedTuple):
    """The result of :func:`brettel_planes` (linear sRGB)."""

    #: Projection (3, 3) on the half-plane of the long-wavelength anchor.
    H1: np.ndarray
    #: Projection (3, 3) on the other half-plane.
    H2: np.ndarray
    #: Normal (3,) of the separating plane: ``H1`` where ``n @ rgb >= 0``.
    n: np.ndarray


def brettel_planes(deficiency: str) -> BrettelPlanes:
    """Brettel et al. (1997) in linear sRGB: ``(H1, H2, n)``, (3, 3), (3, 3), (3,).

    A colour ``rgb`` maps to ``H1 @ rgb`` where ``n @ rgb >= 0`` and to ``H2 @ rgb`` elsewhere;
    ``H1`` uses the long-wavelength anchor (575 nm, or 660 nm for tritan).

    Examples
    --------
    >>> h1, h2, n = brettel_planes("protan")
    >>> [round(float(v), 6) for v in h1 @ [1.0, 1.0, 1.0]]
    [1.0, 1.0, 1.0]
    """
    h1, h2, n = _brettel_planes(_deficiency(deficiency))  # named before the cache hashes it
    # copies: the caller owns (and may write) the result; the cached planes are read-only
    return BrettelPlanes(h1.copy(), h2.copy(), n.copy())


@lru_cache(maxsize=8)
def _brettel_planes(d: str) -> BrettelPlanes:
    """:func:`brettel_planes` of a checked name (cached, read-only arrays: shared)."""
    t, t_inv = _rgb_lms()
    white = t @ np.ones(3)
    k = _MISSING[d]
    short, long_ = (_anchor_lms(w) for w in _ANCHORS_NM[d])
    p_long = _projection(k, white, long_)
    p_short = _projection(k, white, short)
    axis = np.zeros(3)
    axis[k] = 1.0
    n_sep = np.cross(white, axis)
    # orient n_sep so that the long-wavelength anchor lies on its positive side
    if n_sep @ long_ < 0:
        n_sep = -n_sep
    planes = BrettelPlanes(t_inv @ p_long @ t, t_inv @ p_short @ t, t.T @ n_sep)
    for a in planes:
        a.setflags(write=False)
    return planes


@lru_cache(maxsize=8)
def _vienot_matrix(d: str) -> np.ndarray:
    """Viénot's projection (3, 3) for a checked name (cached, read-only: shared)."""
    t, t_inv = _rgb_lms()
    white = t @ np.ones(3)
    third = t @ (np.array([1.0, 0.0, 0.0]) if d == "tritan" else np.array([0.0, 0.0, 1.0]))
    m = np.asarray(t_inv @ _projection(_MISSING[d], white, third) @ t)
    m.setflags(write=False)
    return m


def cvd_matrix(deficiency: str, severity: float = 1.0, method: str = "machado2009") -> np.ndarray:
    """Return the linear-sRGB matrix of a linear model (Machado 2009 or Viénot 1999), (3, 3).

    Brettel (1997) is piecewise linear: see :func:`brettel_planes`.

    Examples
    --------
    >>> [round(float(v), 4) for v in cvd_matrix("protan", 1.0, "vienot1999") @ [1.0, 0, 0]]
    [0.1089, 0.1089, 0.0045]
    """
    d, s, m = _deficiency(deficiency), _severity(severity), _method(method)
    if m == "machado2009":
        return machado_matrix(d, s)
    if m == "brettel1997":
        raise InvalidInputError(
            "Brettel (1997) is piecewise linear (two half-planes): use brettel_planes()"
        )
    return np.asarray((1.0 - s) * np.eye(3) + s * _vienot_matrix(d))


@chunkwise(1)
def simulate_cvd(
    image: ArrayLike,
    deficiency: str,
    severity: float = 1.0,
    method: str = "machado2009",
    *,
    linear: bool = False,
    clip: bool = False,
) -> Array:
    r"""Simulate how an image looks to a protan, deutan or tritan observer.

    The model acts on linear sRGB: encoded input (``linear=False``, the default) is decoded
    with the sRGB transfer function (IEC 61966-2-1), transformed, and encoded again.

    .. math:: \mathrm{rgb}' = M(s)\,\mathrm{rgb}

    with :math:`M(s)` Machado's matrix, Viénot's projection blended with the identity, or
    Brettel's two half-plane projections (chosen per pixel), see the module docstring.

    Parameters
    ----------
    image : array_like, shape (..., 3)
        sRGB (encoded in [0, 1], or uint8/uint16), or linear sRGB if ``linear``.
    deficiency : {"protan", "deutan", "tritan"}
        Also "protanopia", "deuteranomaly", ... (the severity sets -opia vs -omaly).
    severity : float in [0, 1]
        1 = dichromacy, 0 = normal vision.
    method : {"machado2009", "brettel1997", "vienot1999"}
        Machado et al.'s matrices (any severity), Brettel et al.'s two half-planes or
        Viénot et al.'s single plane (see the module docstring).
    linear : bool
        Input and output are linear sRGB.
    clip : bool
        Clip the result to [0, 1]. Otherwise out-of-gamut results (Machado's matrices have
        negative entries) are returned as they are, never clipped silently.

    Returns
    -------
    array, shape (..., 3), the input's namespace and float dtype.

    Examples
    --------
    >>> import numpy as np
    >>> out = simulate_cvd(np.array([1.0, 0.0, 0.0]), "deutan", method="machado2009", linear=True)
    >>> [round(float(v), 6) for v in out]
    [0.367322, 0.280085, -0.01182]
    """
    d, s, m = _deficiency(deficiency), _severity(severity), _method(method)
    img = as_image_strict(image, "image")
    xp = namespace(img)
    from imageform.color.transfer import linear_to_srgb, srgb_to_linear

    linear = as_bool(linear, "linear")
    clip = as_bool(clip, "clip")
    lin = img if linear else srgb_to_linear(img)
    dev = device_of(lin)

    def mat(a: np.ndarray) -> Any:
        return xp.asarray(a, dtype=lin.dtype, device=dev)

    if m == "brettel1997":
        # the cached read-only planes, only read here; torch.asarray would share a float64
        # one and warn that it is not writable, so other namespaces get writable copies
        h1, h2, n = _brettel_planes(d) if is_numpy_namespace(xp) else brettel_planes(d)
        side = lin @ mat(n)
        sim = xp.where((side >= 0)[..., None], lin @ mat(h1).T, lin @ mat(h2).T)
        out = (1.0 - s) * lin + s * sim if s < 1.0 else sim
    else:
        out = lin @ mat(cvd_matrix(d, s, m)).T
    if clip:
        out = xp.clip(out, 0.0, 1.0)
    return out if linear else linear_to_srgb(out)
