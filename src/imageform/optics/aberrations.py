"""Lens aberrations as image effects with physical parameters.

- Spherical aberration: marginal rays focus short of paraxial ones; the blur at the circle of
  least confusion grows with the cube of the aperture (and, with ``field_coefficient``,
  quadratically across the field).
- Lateral chromatic aberration: each channel imaged with its own magnification about the
  optical centre (colour fringes that grow towards the corners).
- Axial (longitudinal) chromatic aberration: each channel has its own focal length, so
  defocus differs by channel.

Vignetting is in :mod:`imageform.optics.vignetting`, distortion in
:mod:`imageform.geometry.distortion`, defocus in :mod:`imageform.optics.defocus`.
Images are NumPy ``(H, W, C)`` (``(H, W)`` for the monochrome effects).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np

from imageform import _deprecate
from imageform._backend import to_numpy
from imageform._typing import ArrayLike
from imageform._validate import (
    as_image,
    as_int,
    as_real,
    as_real_array,
    as_reals,
    check_positive,
    check_real_values,
    finite_result,
    format_shape,
)
from imageform.errors import InvalidInputError
from imageform.geometry.undistort import remap_bilinear
from imageform.optics.defocus import _check_blur_radius, blur_by_radius

__all__ = [
    "ChromaticFocalLengths",
    "axial_chromatic_aberration",
    "axial_chromatic_blur_diameters",
    "chromatic_focal_lengths",
    "lateral_chromatic_aberration",
    "spherical_aberration",
    "spherical_blur_radius",
]


def _center(shape: tuple[int, ...], center: tuple[float, float] | None) -> tuple[float, float]:
    h, w = shape[0], shape[1]
    if center is None:
        return (w - 1) / 2, (h - 1) / 2
    cu, cv = as_reals(center, "center", 2)
    return cu, cv


def _is_nan(value: object) -> bool:
    return isinstance(value, float | np.floating) and math.isnan(value)


def _image(image: Any, ndim: tuple[int, ...], want: str) -> np.ndarray:
    """Check the image: a NumPy float array of ``ndim`` dimensions, not empty."""
    arr = np.asarray(to_numpy(as_image(image, "image", channels=None)))
    if arr.ndim not in ndim or 0 in arr.shape:
        raise InvalidInputError(
            f"expected image of shape {want}, non-empty, got {format_shape(arr.shape)}"
        )
    return arr


@_deprecate.parameters(positional=("focal_length", "f_number", "sa_coefficient"))
def spherical_blur_radius(*, focal_length: float, f_number: float, sa_coefficient: float) -> float:
    r"""Radius (m) of the circle of least confusion of a lens with spherical aberration.

    ``focal_length`` in metres; every parameter is keyword-only.

    The marginal ray (height ``h = f / 2N`` in the pupil) focuses ``LSA = S h² / f`` short of
    the paraxial focus (longitudinal aberration ∝ h²); it meets the paraxial image plane at
    the transverse aberration ``TSA = LSA · h / f`` (∝ h³); the smallest blur, a quarter of
    the way back, has radius ``TSA / 4``:

    .. math::

        r_{lc} = \frac{S h^3}{4 f^2} = \frac{S f}{32 N^3}

    ``S`` (``sa_coefficient``, dimensionless, ``>= 0``) sets the lens's aberration; halving
    ``N`` makes the blur 8 × larger. Source: W. J. Smith, *Modern Optical Engineering*,
    4th ed., §3.4 (LSA ∝ h², TSA ∝ h³, least confusion at 3/4 LSA with diameter TSA/2);
    Hecht, *Optics*, 5th ed., §6.3.1.

    Examples
    --------
    >>> r = spherical_blur_radius(focal_length=0.05, f_number=2.0, sa_coefficient=0.5)
    >>> round(r * 1e6, 4)  # micrometres
    97.6562
    """
    f = check_positive(focal_length, "focal_length (m)")
    n = check_positive(f_number, "f_number")
    s = check_positive(sa_coefficient, "sa_coefficient", allow_zero=True)
    return float(
        finite_result(
            "the blur radius S f / (32 N³)",
            lambda: s * f / (32.0 * n**3),
            focal_length=f,
            f_number=n,
            sa_coefficient=s,
        )
    )


@_deprecate.parameters(renamed={"centre": "center"})
def spherical_aberration(
    image: ArrayLike,
    *,
    focal_length: float,
    f_number: float,
    pixel_pitch: float,
    sa_coefficient: float,
    field_coefficient: float = 0.0,
    center: tuple[float, float] | None = None,
) -> np.ndarray:
    r"""Blur an image by spherical aberration at a given aperture, growing across the field.

    ``focal_length`` and ``pixel_pitch`` in metres; ``center`` ``(c_u, c_v)`` in pixels
    (default the image center).

    .. math::

        R_{px}(\rho) = \frac{r_{lc}}{p}\,(1 + g \rho^2),\quad
        \rho = \frac{\lVert (u, v) - c \rVert}{\lVert \text{corner} - c \rVert}

    with ``r_lc`` from :func:`spherical_blur_radius`, ``p`` the pixel pitch and ``g`` the
    ``field_coefficient``. The PSF is modelled as the uniform disc of least confusion.
    Pure third-order spherical aberration (Seidel W040) is the same across the field; ``g``
    lets the blur grow off axis as real lenses' oblique spherical aberration and field
    curvature do (the lecture's "blur that grows with aperture and field").

    Examples
    --------
    >>> img = np.zeros((41, 41)); img[20, 20] = 1.0
    >>> out = spherical_aberration(img, focal_length=0.05, f_number=2, pixel_pitch=10e-6,
    ...                            sa_coefficient=0.5)
    >>> round(float(out.sum()), 9)  # light is conserved
    1.0
    """
    arr = _image(image, (2, 3), "(H, W) or (H, W, C)")
    p = check_positive(pixel_pitch, "pixel_pitch (m)")
    g = check_positive(field_coefficient, "field_coefficient", allow_zero=True)
    r_lc = spherical_blur_radius(
        focal_length=focal_length, f_number=f_number, sa_coefficient=sa_coefficient
    )
    names = "focal_length, f_number, sa_coefficient, field_coefficient and pixel_pitch"
    r0 = finite_result(f"the blur radius from {names}", lambda: r_lc / p, pixel_pitch=p)
    rmax = finite_result(
        f"the blur radius from {names}", lambda: r0 * (1.0 + g), field_coefficient=g
    )
    _check_blur_radius(rmax, arr.shape, names)
    h, w = arr.shape[:2]
    cu, cv = _center(arr.shape, center)
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    corner = max(math.hypot(x - cu, y - cv) for x in (0, w - 1) for y in (0, h - 1)) or 1.0
    rho2 = ((u - cu) ** 2 + (v - cv) ** 2) / corner**2
    return blur_by_radius(arr, r0 * (1.0 + g * rho2))


@_deprecate.parameters(renamed={"centre": "center"})
def lateral_chromatic_aberration(
    image: ArrayLike,
    magnification: Sequence[float],
    *,
    center: tuple[float, float] | None = None,
    fill: float = 0.0,
) -> np.ndarray:
    r"""Scale each channel about the optical centre by its own magnification (colour fringes).

    .. math::

        I'_c(\mathbf{p}) = I_c\!\left(\mathbf{c}
            + \frac{\mathbf{p} - \mathbf{c}}{m_c}\right)

    A feature at distance ``r`` from the centre ``c`` appears in channel ``c`` at ``m_c r``.
    Typical lenses have ``|m_c - 1|`` of 1e-4 … 3e-3 relative to green.

    Parameters
    ----------
    image : array (H, W, C)
        The image, one magnification per channel.
    magnification : sequence of C floats
        Per-channel magnification about ``center``, ``> 0`` (e.g. ``(1.002, 1.0, 0.998)``
        for R, G, B).
    center : (c_u, c_v), optional
        The optical center (column, row); default the image center.
    fill : float
        Value where a shrunk channel samples outside the image (finite, or NaN to mark
        those pixels).

    Notes
    -----
    Source: Hecht, *Optics*, 5th ed., §6.3.2 (lateral colour: magnification depends on
    wavelength); bilinear resampling as :func:`imageform.geometry.remap_bilinear`.

    Examples
    --------
    >>> img = np.zeros((1, 5, 2)); img[0, 3] = 1.0
    >>> lateral_chromatic_aberration(img, (1.0, 2.0))[0, :, 1].tolist()  # x = 3 → 4
    [0.0, 0.0, 0.0, 0.5, 1.0]
    """
    arr = _image(image, (3,), "(H, W, C)")
    mags = as_reals(magnification, "magnification", positive=True)
    if len(mags) != arr.shape[-1]:
        raise InvalidInputError(
            f"expected magnification as {arr.shape[-1]} values (one per channel), got {len(mags)}"
        )
    # NaN is allowed: it marks the samples from outside the image (the simulator keeps the
    # unshifted value there)
    fv = math.nan if _is_nan(fill) else as_real(fill, "fill")
    h, w = arr.shape[:2]
    cu, cv = _center(arr.shape, center)
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    out = np.empty_like(arr)
    for c, m in enumerate(mags):
        mp = finite_result(
            "the sampling positions c + (p - c) / m",
            lambda m=m: np.stack([cu + (u - cu) / m, cv + (v - cv) / m], axis=-1),
            magnification=m,
            center=(cu, cv),
        )
        out[..., c] = remap_bilinear(arr[..., c], mp, fill=fv)
    return out


class ChromaticFocalLengths(NamedTuple):
    """Result of :func:`chromatic_focal_lengths` (m); a sequence for ``focal_lengths=``."""

    red: float
    green: float
    blue: float


@_deprecate.parameters(positional=("focal_length", "abbe_number"))
def chromatic_focal_lengths(*, focal_length: float, abbe_number: float) -> ChromaticFocalLengths:
    r"""Focal lengths for red, green, blue of a singlet of Abbe number ``V`` (d-line focus ``f``).

    ``focal_length`` (the d-line focal length, metres) and ``abbe_number`` are keyword-only.

    A thin lens has ``1/f ∝ n(λ) - 1``, so ``f_C - f_F ≈ f / V`` between the C (656 nm) and
    F (486 nm) lines. Taking red ≈ C, green ≈ d (588 nm), blue ≈ F and splitting the spread
    evenly about d (a first-order approximation):

    .. math::

        f_R = f\left(1 + \frac{1}{2V}\right),\ f_G = f,\
        f_B = f\left(1 - \frac{1}{2V}\right)

    Source: Hecht, *Optics*, 5th ed., §6.3.2 (longitudinal chromatic aberration, Abbe number).

    Examples
    --------
    >>> fl = chromatic_focal_lengths(focal_length=0.05, abbe_number=64.17)  # N-BK7
    >>> [round(x * 1e3, 4) for x in fl]
    [50.3896, 50.0, 49.6104]
    """
    f = check_positive(focal_length, "focal_length (m)")
    v = check_positive(abbe_number, "abbe_number")
    red, blue = finite_result(
        "the focal lengths f (1 ± 1/(2V))",
        lambda: (f * (1 + 0.5 / v), f * (1 - 0.5 / v)),
        focal_length=f,
        abbe_number=v,
    )
    return ChromaticFocalLengths(red, f, blue)


def axial_chromatic_blur_diameters(
    depth: ArrayLike,
    *,
    focal_lengths: Sequence[float],
    f_number: float,
    focus: float,
    reference: int = 1,
) -> np.ndarray:
    r"""Blur-disc diameter (m) per channel of points at ``depth``; shape ``(*depth.shape, C)``.

    The sensor sits where channel ``reference`` (green) focuses the plane at ``focus``:
    ``d_s = f_ref s / (s - f_ref)``. Channel ``c`` images a point at depth ``d`` at
    ``d_c = f_c d / (d - f_c)``; its cone (aperture ``A = f_ref / N``) cuts the sensor in a
    disc of diameter

    .. math::

        b_c(d) = A \frac{|d_c - d_s|}{d_c}

    (with all ``f_c`` equal this is the circle of confusion). Source: thin-lens geometry,
    Hecht §5.2; Wikipedia "Circle of confusion".

    Examples
    --------
    >>> fl = chromatic_focal_lengths(focal_length=0.05, abbe_number=64.17)
    >>> b = axial_chromatic_blur_diameters(2.0, focal_lengths=fl, f_number=2, focus=2)
    >>> [round(float(x) * 1e6, 2) for x in b]  # µm: green sharp, red and blue blurred
    [198.25, 0.0, 201.36]
    """
    fs = list(as_reals(focal_lengths, "focal_lengths (m)", positive=True))
    ref = as_int(reference, "reference")
    if not 0 <= ref < len(fs):
        raise InvalidInputError(
            f"expected reference in [0, {len(fs) - 1}] (an index into the {len(fs)} "
            f"focal_lengths), got {ref}"
        )
    n = check_positive(f_number, "f_number")
    s = check_positive(focus, "focus (m)")
    fr = fs[ref]
    if s <= max(fs):
        raise InvalidInputError(
            f"focus distance {s:g} m is inside a focal length ({max(fs):g} m of "
            "focal_lengths): no real image"
        )
    d = as_real_array(depth, "depth (m)", finite=False)
    if np.any(~(d > max(fs))):
        raise InvalidInputError(
            f"expected depth beyond every focal length (> {max(fs):g} m) so that each channel "
            "forms a real image"
        )

    def blur() -> np.ndarray:
        a = fr / n
        ds = fr * s / (s - fr)
        out = []
        for f in fs:
            dc = np.where(np.isinf(d), f, f * d / (d - f))  # d = inf: the image at f
            out.append(a * np.abs(dc - ds) / dc)
        return np.stack(out, axis=-1)

    return finite_result("the blur diameters", blur, focal_lengths=tuple(fs), f_number=n, focus=s)


def axial_chromatic_aberration(
    image: ArrayLike,
    depth: ArrayLike,
    *,
    focal_lengths: Sequence[float],
    f_number: float,
    focus: float,
    pixel_pitch: float,
    reference: int = 1,
) -> np.ndarray:
    r"""Blur each channel by its own defocus disc (:func:`axial_chromatic_blur_diameters`).

    .. math::

        I'_c = \mathrm{blur}\!\left(I_c, \frac{b_c(d)}{2p}\right)

    Parameters
    ----------
    image : array (H, W, C)
        The all-in-focus image, one focal length per channel.
    depth : float or array (H, W)
        Scene depth per pixel (m).
    focal_lengths : C floats
        Per-channel focal lengths (m), e.g. from :func:`chromatic_focal_lengths`.
    f_number, focus, pixel_pitch : float
        The f-number, the focus distance (m) and the sensor pixel pitch (m).
    reference : int
        The channel in focus at ``focus`` (default 1, green).

    Examples
    --------
    >>> img = np.zeros((31, 31, 3)); img[15, 15] = 1.0
    >>> fl = chromatic_focal_lengths(focal_length=0.05, abbe_number=64.17)
    >>> out = axial_chromatic_aberration(img, 2.0, focal_lengths=fl, f_number=2, focus=2,
    ...                                  pixel_pitch=20e-6)
    >>> float(out[15, 15, 1]), bool(out[15, 15, 0] < 0.1)  # green sharp, red blurred
    (1.0, True)
    """
    fls = as_reals(focal_lengths, "focal_lengths (m)", positive=True)
    arr = _image(image, (3,), f"(H, W, {len(fls)})")
    if arr.shape[-1] != len(fls):
        raise InvalidInputError(
            f"expected image (H, W, {len(fls)}) for {len(fls)} focal_lengths, "
            f"got {format_shape(arr.shape)}"
        )
    p = check_positive(pixel_pitch, "pixel_pitch (m)")
    d = as_real_array(depth, "depth", check=False)
    if d.ndim not in (0, 2) or (d.ndim == 2 and d.shape != arr.shape[:2]):
        raise InvalidInputError(
            f"expected depth scalar or of shape {arr.shape[:2]}, got {format_shape(d.shape)}"
        )
    check_real_values(d, "depth (m)", finite=False)
    b = axial_chromatic_blur_diameters(
        d, focal_lengths=fls, f_number=f_number, focus=focus, reference=reference
    )
    names = "depth, focal_lengths, f_number, focus and pixel_pitch"
    rr = finite_result(f"the blur radius from {names}", lambda: b / (2 * p), pixel_pitch=p)
    _check_blur_radius(float(np.max(rr)), arr.shape, names)
    r = np.broadcast_to(rr, (*arr.shape[:2], arr.shape[-1]))
    return blur_by_radius(arr, np.ascontiguousarray(r))
