r"""RGB colour spaces defined by primaries, white point and transfer function.

Matrices are derived, never typed: the normalised primary matrix of SMPTE RP 177-1993,

.. math::
    M = [\mathbf{P}_R\; \mathbf{P}_G\; \mathbf{P}_B]\,\operatorname{diag}(\mathbf{S}),
    \qquad \mathbf{S} = [\mathbf{P}_R\; \mathbf{P}_G\; \mathbf{P}_B]^{-1} \mathbf{W},

where :math:`\mathbf{P}_i = (x_i/y_i, 1, (1-x_i-y_i)/y_i)` are the primaries and
:math:`\mathbf{W}` the white (Y = 1). Each space keeps the white *its standard writes*;
for sRGB that is IEC 61966-2-1's D65 (0.3127, 0.3290) — the matrix then rounds to the
4-digit matrix printed in the standard (clause 5.2) — not CIE 15:2004's (0.31271, 0.32902).

XYZ produced from an RGB space is relative to that space's white (Y = 1 at RGB white). No
chromatic adaptation happens here: ProPhoto's white is D50, the others' D65.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from types import MappingProxyType
from typing import Any

import numpy as np

from imageform._backend import constant, namespace
from imageform._dask import chunkwise
from imageform._typing import Array, ArrayLike
from imageform._validate import as_image_strict, as_real_ndarray, check_name, describe
from imageform.errors import DegenerateConfigurationError, InvalidInputError

__all__ = [
    "RGB_SPACES",
    "RGBSpace",
    "linear_rgb_to_xyz",
    "linear_srgb_to_xyz",
    "rgb_space",
    "rgb_to_xyz_matrix",
    "xyz_to_linear_rgb",
    "xyz_to_linear_srgb",
    "xyz_to_rgb_matrix",
]


@dataclass(frozen=True)
class RGBSpace:
    """An RGB colour space: primaries and white as chromaticities, a transfer function name.

    ``transfer`` names a function of :mod:`imageform.color.transfer` (``"srgb"``,
    ``"adobe_rgb"``, ``"rec709"``, ``"rec2020"``, ``"prophoto"``).
    """

    name: str
    primaries_xy: tuple[tuple[float, float], tuple[float, float], tuple[float, float]]
    white_xy: tuple[float, float]
    transfer: str
    source: str

    def __post_init__(self) -> None:
        """Check every field: the names, primaries, white point and transfer function."""
        # validated here, so that a space built by hand cannot give NaN matrices later
        from imageform.color.transfer import TRANSFER_FUNCTIONS

        for field_name in ("name", "source"):
            if not isinstance(getattr(self, field_name), str):
                raise TypeError(
                    f"expected {field_name} as a str, got {describe(getattr(self, field_name))}"
                )
        prim = as_real_ndarray(self.primaries_xy, "primaries_xy")
        if prim.shape != (3, 2):
            raise InvalidInputError(
                f"expected primaries_xy as three (x, y) pairs, got shape {prim.shape}"
            )
        white = as_real_ndarray(self.white_xy, "white_xy")
        if white.shape != (2,):
            raise InvalidInputError(f"expected white_xy as (x, y), got shape {white.shape}")
        for arr, what in ((prim, "primaries_xy"), (white, "white_xy")):
            if not (np.abs(arr).max() <= 10.0 and np.all(arr[..., 1] != 0)):
                raise InvalidInputError(
                    f"expected {what} as chromaticities (|x|, |y| <= 10, y != 0), got "
                    f"{describe(arr.tolist(), 60)}"
                )
        if not white[1] > 0:
            raise InvalidInputError(f"expected white_xy with y > 0, got {white.tolist()}")
        check_name(self.transfer, TRANSFER_FUNCTIONS, "transfer function")
        pairs = tuple((float(x), float(y)) for x, y in prim)
        object.__setattr__(self, "primaries_xy", pairs)
        object.__setattr__(self, "white_xy", (float(white[0]), float(white[1])))

    def matrix_to_xyz(self) -> np.ndarray:
        """Return the derived RGB -> XYZ matrix (float64, (3, 3)); see :func:`rgb_to_xyz_matrix`."""
        return _npm(self.primaries_xy, self.white_xy).copy()


_D65_ITU = (0.3127, 0.3290)  # D65 as IEC 61966-2-1 / ITU-R BT.709 / BT.2020 write it

_SPACES = {
    # IEC 61966-2-1:1999, clause 5.1 (Table 1: primaries and D65 white).
    "srgb": RGBSpace(
        "sRGB",
        ((0.6400, 0.3300), (0.3000, 0.6000), (0.1500, 0.0600)),
        _D65_ITU,
        "srgb",
        "IEC 61966-2-1:1999, clause 5.1",
    ),
    # ITU-R BT.709-6 (2015), Part 1, items 1.3-1.4: same primaries/white as sRGB, 709 OETF.
    "rec709": RGBSpace(
        "Rec. 709",
        ((0.640, 0.330), (0.300, 0.600), (0.150, 0.060)),
        _D65_ITU,
        "rec709",
        "ITU-R BT.709-6, items 1.3-1.4",
    ),
    # Adobe RGB (1998) Color Image Encoding, v2005-05, clause 4.3.1.1 and 4.3.1.2.
    "adobe_rgb": RGBSpace(
        "Adobe RGB (1998)",
        ((0.6400, 0.3300), (0.2100, 0.7100), (0.1500, 0.0600)),
        _D65_ITU,
        "adobe_rgb",
        "Adobe RGB (1998) Color Image Encoding v2005-05, clause 4.3.1",
    ),
    # SMPTE EG 432-1:2010 P3 primaries with D65 white (Apple Display P3), sRGB transfer.
    "display_p3": RGBSpace(
        "Display P3",
        ((0.680, 0.320), (0.265, 0.690), (0.150, 0.060)),
        _D65_ITU,
        "srgb",
        "SMPTE EG 432-1:2010 (P3-D65 primaries); sRGB transfer (Apple Display P3)",
    ),
    # ITU-R BT.2020-2 (2015), Table 3 (primaries, D65) and Table 4 (OETF).
    "rec2020": RGBSpace(
        "Rec. 2020",
        ((0.708, 0.292), (0.170, 0.797), (0.131, 0.046)),
        _D65_ITU,
        "rec2020",
        "ITU-R BT.2020-2, Tables 3-4",
    ),
    # ISO 22028-2:2013 (ROMM RGB), clause 5.2: primaries and D50 white (0.3457, 0.3585).
    "prophoto": RGBSpace(
        "ProPhoto RGB (ROMM)",
        ((0.7347, 0.2653), (0.1596, 0.8404), (0.0366, 0.0001)),
        (0.3457, 0.3585),
        "prophoto",
        "ISO 22028-2:2013, clause 5.2",
    ),
}

#: RGB spaces by key: srgb, rec709, adobe_rgb, display_p3, rec2020, prophoto.
RGB_SPACES: MappingProxyType[str, RGBSpace] = MappingProxyType(_SPACES)

_ALIASES = {
    "adobe": "adobe_rgb",
    "adobergb": "adobe_rgb",
    "adobe_rgb_1998": "adobe_rgb",
    "p3": "display_p3",
    "displayp3": "display_p3",
    "bt709": "rec709",
    "bt2020": "rec2020",
    "prophoto_rgb": "prophoto",
    "romm": "prophoto",
    "romm_rgb": "prophoto",
}


def _space_key(name: str) -> str:
    key = name.strip().lower().replace("-", "_").replace(" ", "_").replace(".", "")
    key = key.replace("(1998)", "_1998").strip("_")
    return _ALIASES.get(key, key)


def rgb_space(space: str | RGBSpace) -> RGBSpace:
    """Return the :class:`RGBSpace` named ``space``.

    ``space`` is a key of :data:`RGB_SPACES`, any case, with ``-``, spaces or dots, or an
    alias such as ``"p3"``, ``"bt2020"``, ``"romm"``; an :class:`RGBSpace` is returned as it
    is.

    Examples
    --------
    >>> rgb_space("Display-P3").name
    'Display P3'
    """
    if isinstance(space, RGBSpace):
        return space
    if isinstance(space, str):
        key = _space_key(space)
        if key in RGB_SPACES:
            return RGB_SPACES[key]
    return RGB_SPACES[check_name(space, RGB_SPACES, "RGB space")]


def _xy_to_xyz_col(xy: tuple[float, float]) -> np.ndarray:
    x, y = xy
    return np.array([x / y, 1.0, (1.0 - x - y) / y])


@cache
def _npm(primaries: tuple[tuple[float, float], ...], white: tuple[float, float]) -> np.ndarray:
    p = np.stack([_xy_to_xyz_col(xy) for xy in primaries], axis=1)
    if abs(np.linalg.det(p)) < 1e-12:
        raise DegenerateConfigurationError(
            f"the primaries {primaries} are collinear in xy: they span no gamut"
        )
    s = np.linalg.solve(p, _xy_to_xyz_col(white))
    m = p * s[np.newaxis, :]
    m.setflags(write=False)
    return m


def rgb_to_xyz_matrix(space: str | RGBSpace = "srgb") -> np.ndarray:
    r"""Return the 3x3 matrix from linear RGB of ``space`` to XYZ (Y = 1 at the space's white).

    Derived from the primaries and white point (SMPTE RP 177-1993, clause 3.3):

    .. math::
        M = P \operatorname{diag}(P^{-1} W), \quad
        P_{:,i} = (x_i / y_i,\; 1,\; (1 - x_i - y_i) / y_i)^T

    Apply to channels-last images as ``rgb @ M.T``.

    Parameters
    ----------
    space : str or RGBSpace
        A key of :data:`RGB_SPACES` or an :class:`RGBSpace`.

    Returns
    -------
    ndarray, shape (3, 3), float64

    Notes
    -----
    Source: SMPTE RP 177-1993; primaries and whites per :data:`RGB_SPACES` ``.source``.

    Examples
    --------
    >>> rgb_to_xyz_matrix("srgb").round(4)[0].tolist()
    [0.4124, 0.3576, 0.1805]
    >>> rgb_to_xyz_matrix("srgb")[1].round(6).tolist()
    [0.212639, 0.715169, 0.072192]
    """
    sp = rgb_space(space)
    return _npm(sp.primaries_xy, sp.white_xy).copy()


def xyz_to_rgb_matrix(space: str | RGBSpace = "srgb") -> np.ndarray:
    """Return the inverse of :func:`rgb_to_xyz_matrix` (XYZ to linear RGB), float64 (3, 3).

    Examples
    --------
    >>> xyz_to_rgb_matrix("srgb").round(4)[0].tolist()
    [3.241, -1.5374, -0.4986]
    """
    return np.linalg.inv(rgb_to_xyz_matrix(space))


def _apply_matrix(x: Any, m: np.ndarray) -> Any:
    """``x @ m.T`` in the namespace of ``x`` (m is float64 NumPy, cast to x's dtype)."""
    xp = namespace(x)
    mt = constant(m.T, x, xp)
    return x @ mt


@chunkwise(1)
def linear_rgb_to_xyz(rgb: ArrayLike, space: str | RGBSpace = "srgb") -> Array:
    r"""Linear RGB of ``space`` to CIE XYZ (relative to the space's white, Y = 1 there).

    .. math:: (X, Y, Z)^T = M\,(R, G, B)^T

    Parameters
    ----------
    rgb : array_like, shape (..., 3)
        Linear (decoded) RGB.
    space : str or RGBSpace
        The RGB space (a name from :data:`RGB_SPACES` or an :class:`RGBSpace`).

    Returns
    -------
    array, shape (..., 3)

    Examples
    --------
    >>> linear_rgb_to_xyz([1.0, 1.0, 1.0], "prophoto").round(4).tolist()
    [0.9643, 1.0, 0.8251]
    """
    m = rgb_to_xyz_matrix(space)
    x = as_image_strict(rgb, "linear RGB", range_check=False)
    return _apply_matrix(x, m)


@chunkwise(1)
def xyz_to_linear_rgb(xyz: ArrayLike, space: str | RGBSpace = "srgb") -> Array:
    """CIE XYZ to linear RGB of ``space`` (the inverse of :func:`linear_rgb_to_xyz`).

    Out-of-gamut colours give components below 0 or above 1; nothing is clipped.

    Examples
    --------
    >>> xyz_to_linear_rgb([0.950456, 1.0, 1.089058]).round(5).tolist()
    [1.0, 1.0, 1.0]
    """
    m = xyz_to_rgb_matrix(space)
    x = as_image_strict(xyz, "XYZ", range_check=False)
    return _apply_matrix(x, m)


@chunkwise(1)
def linear_srgb_to_xyz(rgb: ArrayLike) -> Array:
    r"""Linear sRGB to CIE XYZ with the derived IEC 61966-2-1 matrix (D65, Y = 1).

    .. math::
        \begin{pmatrix}X\\Y\\Z\end{pmatrix} \approx
        \begin{pmatrix}0.4124 & 0.3576 & 0.1805\\ 0.2126 & 0.7152 & 0.0722\\
        0.0193 & 0.1192 & 0.9505\end{pmatrix}
        \begin{pmatrix}R\\G\\B\end{pmatrix}

    Parameters
    ----------
    rgb : array_like, shape (..., 3)
        Linear sRGB (see :func:`imageform.color.srgb_to_linear`).

    Returns
    -------
    array, shape (..., 3)

    Notes
    -----
    Source: IEC 61966-2-1:1999, clause 5.2 (matrix derived from clause 5.1's primaries).

    Examples
    --------
    >>> linear_srgb_to_xyz([1.0, 0.0, 0.0]).round(4).tolist()
    [0.4124, 0.2126, 0.0193]
    """
    return linear_rgb_to_xyz(rgb, "srgb")


@chunkwise(1)
def xyz_to_linear_srgb(xyz: ArrayLike) -> Array:
    """CIE XYZ (D65, Y = 1) to linear sRGB; inverse of :func:`linear_srgb_to_xyz`.

    Source: IEC 61966-2-1:1999, clause 5.3 (matrix derived, not the printed 4-digit one).

    Examples
    --------
    >>> xyz_to_linear_srgb([0.9505, 1.0, 1.0891]).round(3).tolist()
    [1.0, 1.0, 1.0]
    """
    return xyz_to_linear_rgb(xyz, "srgb")
