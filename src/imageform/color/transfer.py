"""Transfer functions: encoded (non-linear) RGB values to linear light and back.

Every pair is ``<name>_to_linear`` (decode: encoded value V to linear value L) and
``linear_to_<name>`` (encode). Constants are written as the standards write them; where a
standard gives only one threshold of a piecewise curve, the other is derived from the
forward function, so that the two pieces meet where the standard says.

Values outside [0, 1] are allowed (they occur after gamut mapping between RGB spaces): the
piecewise curves extend their linear segment below 0; pure power laws extend as odd
functions, ``sign(V) |V|^γ``. Nothing is clipped.

The lecture's rule: *decode before any linear operation* (averaging, resizing, blurring,
matrixing) and re-encode afterwards; :mod:`imageform.color.linear_light` shows the error of
the wrong way.
"""

from __future__ import annotations

from typing import Any

from imageform._backend import namespace
from imageform._colormath import pos_pow as _pos_pow
from imageform._colormath import srgb_decode as _srgb_decode
from imageform._colormath import srgb_encode as _srgb_encode
from imageform._dask import chunkwise
from imageform._typing import Array, ArrayLike
from imageform._validate import as_image_strict, check_name, check_positive
from imageform.color._gpu import transfer as _gpu_transfer

__all__ = [
    "ADOBE_RGB_GAMMA",
    "TRANSFER_FUNCTIONS",
    "adobe_rgb_to_linear",
    "decode",
    "encode",
    "gamma_to_linear",
    "linear_to_adobe_rgb",
    "linear_to_gamma",
    "linear_to_prophoto",
    "linear_to_rec709",
    "linear_to_rec2020",
    "linear_to_srgb",
    "prophoto_to_linear",
    "rec709_to_linear",
    "rec2020_to_linear",
    "srgb_to_linear",
]

# ITU-R BT.709-6, item 1.2: V = 1.099 L^0.45 - 0.099 for L >= 0.018, V = 4.500 L below.
_BT709_ALPHA = 1.099
_BT709_BETA = 0.018
_BT709_EXP = 0.45
_BT709_SLOPE = 4.5

# ITU-R BT.2020-2, Table 4: α = 1.09929682680944, β = 0.018053968510807 (the exact values
# that make the curve continuous in value and slope; 709's 1.099 / 0.018 are their roundings).
_BT2020_ALPHA = 1.09929682680944
_BT2020_BETA = 0.018053968510807

#: Adobe RGB (1998) Color Image Encoding, v2005-05, clause 4.3.1.2: γ = 2 51/256 = 563/256.
ADOBE_RGB_GAMMA = 563.0 / 256.0

# ISO 22028-2:2013 (ROMM RGB / ProPhoto), clause 5.3: V = 16 L for L < E_t = 1/512,
# V = L^(1/1.8) above.
_ROMM_ET = 1.0 / 512.0
_ROMM_GAMMA = 1.8
_ROMM_SLOPE = 16.0


# ---------------------------------------------------------------- private kernels (clean arrays)
def _gamma_decode(xp: Any, v: Any, gamma: float) -> Any:
    return xp.copysign(xp.pow(xp.abs(v), gamma), v)  # odd extension, NaN stays NaN


def _gamma_encode(xp: Any, lin: Any, gamma: float) -> Any:
    return xp.copysign(xp.pow(xp.abs(lin), 1.0 / gamma), lin)


def _bt_encode(xp: Any, lin: Any, alpha: float, beta: float) -> Any:
    hi = alpha * _pos_pow(xp, lin, _BT709_EXP) - (alpha - 1.0)
    return xp.where(lin < beta, _BT709_SLOPE * lin, hi)


def _bt_decode(xp: Any, v: Any, alpha: float, beta: float) -> Any:
    v_beta = _BT709_SLOPE * beta  # encoded breakpoint derived from the forward function
    hi = _pos_pow(xp, (v + (alpha - 1.0)) / alpha, 1.0 / _BT709_EXP)
    return xp.where(v < v_beta, v / _BT709_SLOPE, hi)


def _romm_encode(xp: Any, lin: Any) -> Any:
    hi = _pos_pow(xp, lin, 1.0 / _ROMM_GAMMA)
    return xp.where(lin < _ROMM_ET, _ROMM_SLOPE * lin, hi)


def _romm_decode(xp: Any, v: Any) -> Any:
    v_t = _ROMM_SLOPE * _ROMM_ET  # = 1/32, derived from the forward function
    hi = _pos_pow(xp, v, _ROMM_GAMMA)
    return xp.where(v < v_t, v / _ROMM_SLOPE, hi)


def _kernel_step(name: str, decode: bool, gamma: float = 2.2) -> tuple[str, tuple[float, ...]]:
    """Return the CUDA kernel step of transfer function ``name`` (:mod:`imageform._cuda`)."""
    d = "dec" if decode else "enc"
    if name == "srgb":
        return (f"{d}_srgb", ())
    if name == "gamma":
        return (f"{d}_gamma", (gamma,))
    if name == "adobe_rgb":
        return (f"{d}_gamma", (ADOBE_RGB_GAMMA,))
    if name == "rec709":
        return (f"{d}_bt", (_BT709_ALPHA, _BT709_BETA))
    if name == "rec2020":
        return (f"{d}_bt", (_BT2020_ALPHA, _BT2020_BETA))
    if name == "prophoto":
        return (f"{d}_romm", ())
    return ("identity", ())  # "linear"


def _prep(values: object, name: str) -> tuple[Any, Any]:
    # encoded values must be in [0, 1]-ish (0-255 floats are caught); linear light may exceed 1
    x = as_image_strict(values, name, channels=None, range_check=not name.startswith("linear"))
    return namespace(x), x


# ---------------------------------------------------------------- public functions
@chunkwise(1)
def srgb_to_linear(values: ArrayLike) -> Array:
    r"""Decode sRGB values to linear light (the IEC 61966-2-1 piecewise curve, exact).

    .. math::
        L = \begin{cases} V / 12.92 & V \le 0.04045 \\
        \left(\frac{V + 0.055}{1.055}\right)^{2.4} & V > 0.04045 \end{cases}

    The breakpoint used is ``12.92 * 0.0031308 = 0.040449936`` (derived from the forward
    function; the standard prints it rounded to 0.04045).

    Parameters
    ----------
    values : array_like, shape (...)
        Encoded sRGB in [0, 1] (floats), or uint8/uint16 full-range code values.

    Returns
    -------
    array, shape (...)
        Linear values; float32 for float32/integer input, float64 for float64.

    Notes
    -----
    Source: IEC 61966-2-1:1999, clause 5.2, eq. (5)-(6).

    Examples
    --------
    >>> round(float(srgb_to_linear(0.5)), 6)
    0.214041
    """
    gpu = _gpu_transfer(values, _kernel_step("srgb", True), what="sRGB values")
    if gpu is not None:
        return gpu
    xp, v = _prep(values, "sRGB values")
    return _srgb_decode(xp, v)


@chunkwise(1)
def linear_to_srgb(values: ArrayLike) -> Array:
    r"""Encode linear light as sRGB (IEC 61966-2-1, exact).

    .. math::
        V = \begin{cases} 12.92 L & L \le 0.0031308 \\
        1.055 L^{1/2.4} - 0.055 & L > 0.0031308 \end{cases}

    Parameters
    ----------
    values : array_like, shape (...)
        Linear values (1 = reference white). Values outside [0, 1] are encoded, not clipped.

    Returns
    -------
    array, shape (...)

    Notes
    -----
    Source: IEC 61966-2-1:1999, clause 5.3, eq. (8)-(9).

    Examples
    --------
    >>> round(float(linear_to_srgb(0.18)), 6)
    0.461356
    """
    gpu = _gpu_transfer(values, _kernel_step("srgb", False), what="linear values")
    if gpu is not None:
        return gpu
    xp, x = _prep(values, "linear values")
    return _srgb_encode(xp, x)


@chunkwise(1)
def gamma_to_linear(values: ArrayLike, gamma: float = 2.2) -> Array:
    r"""Decode a pure power law: :math:`L = \operatorname{sign}(V) |V|^{\gamma}`.

    The lecture's display gamma is 2.2 (the default).

    Parameters
    ----------
    values : array_like, shape (...)
        Encoded values in [0, 1].
    gamma : float
        Exponent, > 0.

    Notes
    -----
    Source: the lecture ("gamma 2.2"); the odd extension to negatives is imageform's.

    Examples
    --------
    >>> round(float(gamma_to_linear(0.5)), 6)
    0.217638
    """
    g = check_positive(gamma, "gamma")
    gpu = _gpu_transfer(values, _kernel_step("gamma", True, g), what="encoded values")
    if gpu is not None:
        return gpu
    xp, v = _prep(values, "encoded values")
    return _gamma_decode(xp, v, g)


@chunkwise(1)
def linear_to_gamma(values: ArrayLike, gamma: float = 2.2) -> Array:
    r"""Encode with a pure power law: :math:`V = \operatorname{sign}(L) |L|^{1/\gamma}`.

    Examples
    --------
    >>> round(float(linear_to_gamma(0.217638)), 5)
    0.5
    """
    g = check_positive(gamma, "gamma")
    gpu = _gpu_transfer(values, _kernel_step("gamma", False, g), what="linear values")
    if gpu is not None:
        return gpu
    xp, x = _prep(values, "linear values")
    return _gamma_encode(xp, x, g)


@chunkwise(1)
def adobe_rgb_to_linear(values: ArrayLike) -> Array:
    """Decode Adobe RGB (1998): :math:`L = V^{563/256}` (odd extension below 0).

    Source: Adobe RGB (1998) Color Image Encoding, v2005-05, clause 4.3.1.2.

    Examples
    --------
    >>> round(float(adobe_rgb_to_linear(0.5)), 6)
    0.217756
    """
    gpu = _gpu_transfer(values, _kernel_step("adobe_rgb", True), what="Adobe RGB values")
    if gpu is not None:
        return gpu
    xp, v = _prep(values, "Adobe RGB values")
    return _gamma_decode(xp, v, ADOBE_RGB_GAMMA)


@chunkwise(1)
def linear_to_adobe_rgb(values: ArrayLike) -> Array:
    """Encode Adobe RGB (1998): :math:`V = L^{256/563}`.

    Examples
    --------
    >>> round(float(linear_to_adobe_rgb(0.217756)), 5)
    0.5
    """
    gpu = _gpu_transfer(values, _kernel_step("adobe_rgb", False), what="linear values")
    if gpu is not None:
        return gpu
    xp, x = _prep(values, "linear values")
    return _gamma_encode(xp, x, ADOBE_RGB_GAMMA)


@chunkwise(1)
def linear_to_rec709(values: ArrayLike) -> Array:
    r"""Rec. 709 OETF (camera encoding).

    .. math::
        V = \begin{cases} 4.5 L & L < 0.018 \\ 1.099 L^{0.45} - 0.099 & L \ge 0.018
        \end{cases}

    Source: ITU-R BT.709-6 (2015), Part 1, item 1.2.

    Examples
    --------
    >>> round(float(linear_to_rec709(0.18)), 6)
    0.409008
    """
    gpu = _gpu_transfer(values, _kernel_step("rec709", False), what="linear values")
    if gpu is not None:
        return gpu
    xp, x = _prep(values, "linear values")
    return _bt_encode(xp, x, _BT709_ALPHA, _BT709_BETA)


@chunkwise(1)
def rec709_to_linear(values: ArrayLike) -> Array:
    """Inverse of the Rec. 709 OETF (breakpoint 4.5 x 0.018 = 0.081).

    Note: this inverts the camera OETF; a Rec. 709 *display* decodes with the BT.1886 EOTF.
    The rounded constants make the OETF jump from 0.081 to 0.081243 at L = 0.018: encoded
    values inside that gap decode to L >= 0.018 but do not re-encode to themselves.

    Examples
    --------
    >>> round(float(rec709_to_linear(0.409008)), 5)
    0.18
    """
    gpu = _gpu_transfer(values, _kernel_step("rec709", True), what="Rec. 709 values")
    if gpu is not None:
        return gpu
    xp, v = _prep(values, "Rec. 709 values")
    return _bt_decode(xp, v, _BT709_ALPHA, _BT709_BETA)


@chunkwise(1)
def linear_to_rec2020(values: ArrayLike) -> Array:
    """Rec. 2020 OETF: Rec. 709's curve with α = 1.09929682680944, β = 0.018053968510807.

    The exact α, β of BT.2020-2 are used (colour-science's default, for 10-bit systems, uses
    709's rounded 1.099 / 0.018: a difference of up to 1.6e-4).

    Source: ITU-R BT.2020-2 (2015), Table 4.

    Examples
    --------
    >>> round(float(linear_to_rec2020(0.18)), 6)
    0.408848
    """
    gpu = _gpu_transfer(values, _kernel_step("rec2020", False), what="linear values")
    if gpu is not None:
        return gpu
    xp, x = _prep(values, "linear values")
    return _bt_encode(xp, x, _BT2020_ALPHA, _BT2020_BETA)


@chunkwise(1)
def rec2020_to_linear(values: ArrayLike) -> Array:
    """Inverse of the Rec. 2020 OETF.

    Examples
    --------
    >>> round(float(rec2020_to_linear(0.5)), 6)
    0.259719
    """
    gpu = _gpu_transfer(values, _kernel_step("rec2020", True), what="Rec. 2020 values")
    if gpu is not None:
        return gpu
    xp, v = _prep(values, "Rec. 2020 values")
    return _bt_decode(xp, v, _BT2020_ALPHA, _BT2020_BETA)


@chunkwise(1)
def linear_to_prophoto(values: ArrayLike) -> Array:
    """ProPhoto (ROMM RGB) encoding: 16 L below 1/512, :math:`L^{1/1.8}` above.

    Source: ISO 22028-2:2013, clause 5.3.

    Examples
    --------
    >>> round(float(linear_to_prophoto(0.18)), 6)
    0.385711
    """
    gpu = _gpu_transfer(values, _kernel_step("prophoto", False), what="linear values")
    if gpu is not None:
        return gpu
    xp, x = _prep(values, "linear values")
    return _romm_encode(xp, x)


@chunkwise(1)
def prophoto_to_linear(values: ArrayLike) -> Array:
    """ProPhoto (ROMM RGB) decoding: V / 16 below 1/32, :math:`V^{1.8}` above.

    Examples
    --------
    >>> round(float(prophoto_to_linear(0.5)), 6)
    0.287175
    """
    gpu = _gpu_transfer(values, _kernel_step("prophoto", True), what="ProPhoto values")
    if gpu is not None:
        return gpu
    xp, v = _prep(values, "ProPhoto values")
    return _romm_decode(xp, v)


#: Transfer function names accepted by :func:`decode` / :func:`encode`.
TRANSFER_FUNCTIONS: tuple[str, ...] = (
    "srgb",
    "gamma",
    "rec709",
    "rec2020",
    "adobe_rgb",
    "prophoto",
    "linear",
)


def _decode_clean(xp: Any, v: Any, name: str, gamma: float = 2.2) -> Any:
    if name == "srgb":
        return _srgb_decode(xp, v)
    if name == "gamma":
        return _gamma_decode(xp, v, gamma)
    if name == "rec709":
        return _bt_decode(xp, v, _BT709_ALPHA, _BT709_BETA)
    if name == "rec2020":
        return _bt_decode(xp, v, _BT2020_ALPHA, _BT2020_BETA)
    if name == "adobe_rgb":
        return _gamma_decode(xp, v, ADOBE_RGB_GAMMA)
    if name == "prophoto":
        return _romm_decode(xp, v)
    return v


def _encode_clean(xp: Any, x: Any, name: str, gamma: float = 2.2) -> Any:
    if name == "srgb":
        return _srgb_encode(xp, x)
    if name == "gamma":
        return _gamma_encode(xp, x, gamma)
    if name == "rec709":
        return _bt_encode(xp, x, _BT709_ALPHA, _BT709_BETA)
    if name == "rec2020":
        return _bt_encode(xp, x, _BT2020_ALPHA, _BT2020_BETA)
    if name == "adobe_rgb":
        return _gamma_encode(xp, x, ADOBE_RGB_GAMMA)
    if name == "prophoto":
        return _romm_encode(xp, x)
    return x


@chunkwise(1)
def decode(values: ArrayLike, transfer: str = "srgb", *, gamma: float = 2.2) -> Array:
    """Decode encoded values to linear light with the transfer function named ``transfer``.

    Parameters
    ----------
    values : array_like, shape (...)
        Encoded values in [0, 1].
    transfer : str
        One of :data:`TRANSFER_FUNCTIONS`.
    gamma : float
        Exponent for ``transfer="gamma"``.

    Examples
    --------
    >>> round(float(decode(0.5, "gamma", gamma=2.2)), 6)
    0.217638
    """
    name = check_name(transfer, TRANSFER_FUNCTIONS, "transfer function")
    g = check_positive(gamma, "gamma")
    gpu = _gpu_transfer(values, _kernel_step(name, True, g), what="encoded values")
    if gpu is not None:
        return gpu
    xp, v = _prep(values, "encoded values")
    return _decode_clean(xp, v, name, g)


@chunkwise(1)
def encode(values: ArrayLike, transfer: str = "srgb", *, gamma: float = 2.2) -> Array:
    """Encode linear light with the transfer function named ``transfer`` (see :func:`decode`).

    Examples
    --------
    >>> round(float(encode(0.214041, "srgb")), 5)
    0.5
    """
    name = check_name(transfer, TRANSFER_FUNCTIONS, "transfer function")
    g = check_positive(gamma, "gamma")
    gpu = _gpu_transfer(values, _kernel_step(name, False, g), what="linear values")
    if gpu is not None:
        return gpu
    xp, x = _prep(values, "linear values")
    return _encode_clean(xp, x, name, g)
