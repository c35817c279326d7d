"""The camera's stages after the renderer, one function each: typed inputs, typed outputs.

:func:`imageform.simulate.simulate` composes them in this order (the stage names are those
of :class:`~imageform.simulate.SimulationResult`'s stages):

1. :func:`apply_lens` (``optics``): lateral chromatic aberration, then defocus blur.
2. :func:`exposure_time` and :func:`capture_raw` (``raw``): photons to electrons with noise,
   full-well clipping, gain, ADC (:meth:`imageform.sensor.SensorModel.capture`), the CFA.
3. :func:`normalize_raw` and :func:`demosaic_raw` (``demosaiced``).
4. :func:`correct_lens_shading` (``shading_corrected``).
5. :func:`balance_white` (``white_balanced``).
6. :func:`correct_color` (``color_corrected``).
7. :func:`encode_output` (``output``), and :func:`decode_output` to measure it.

:func:`measure_photon_transfer` is the sensor's EMVA 1288 measurement beside the chain.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from imageform._validate import (
    as_int,
    as_real,
    as_real_array,
    as_reals,
    check_name,
    check_type,
    describe,
    real_array,
)
from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.geometry.camera import Camera
from imageform.io import CameraColor, CameraOptics
from imageform.sensor.emva import PhotonTransferData
from imageform.sensor.model import SensorModel
from imageform.simulate.colorfit import _fit_matrix
from imageform.simulate.config import LensConfig, SensorConfig
from imageform.simulate.render import RenderOutput
from imageform.simulate.truth import NEUTRAL_PATCHES
from imageform.spectral import COLORCHECKER_PATCHES

__all__ = [
    "DIFFRACTION_BANDS",
    "ColorCorrected",
    "Encoded",
    "WhiteBalanced",
    "apply_lens",
    "balance_white",
    "capture_raw",
    "correct_color",
    "correct_lens_shading",
    "decode_output",
    "demosaic_raw",
    "diffraction_blur",
    "diffraction_psf_kernel",
    "encode_output",
    "exposure_time",
    "gaussian_sigma_for_mtf50",
    "measure_photon_transfer",
    "measured_color_matrix",
    "measured_optics_blur",
    "normalize_raw",
    "wave_defocus_blur",
]


@dataclass(frozen=True)
class WhiteBalanced:
    """:func:`balance_white`'s output: the ``image`` and the per-channel ``gains`` (3,)."""

    image: np.ndarray
    gains: np.ndarray

    def __post_init__(self) -> None:
        """``gains``: three finite reals (issue 16)."""
        gains = real_array(self.gains, "gains", ndim=1)
        if gains.shape != (3,):
            raise InvalidInputError(f"expected gains of shape (3,), got {gains.shape}")
        object.__setattr__(self, "gains", gains)


@dataclass(frozen=True)
class ColorCorrected:
    """:func:`correct_color`'s output: linear sRGB ``image`` and the ``matrix`` M (3, 3).

    ``image = camera RGB @ M``.
    """

    image: np.ndarray
    matrix: np.ndarray

    def __post_init__(self) -> None:
        """``matrix``: a finite real (3, 3) (issue 16)."""
        matrix = real_array(self.matrix, "matrix", ndim=2)
        if matrix.shape != (3, 3):
            raise InvalidInputError(f"expected matrix of shape (3, 3), got {matrix.shape}")
        object.__setattr__(self, "matrix", matrix)


@dataclass(frozen=True)
class Encoded:
    """:func:`encode_output`'s output: the encoded ``image`` in [0, 1] and the ``transfer`` name.

    ``transfer`` is the name of the transfer function applied.
    """

    image: np.ndarray
    transfer: str


def apply_lens(
    rendered: RenderOutput, camera: Camera, lens: LensConfig, focal_length_mm: float
) -> np.ndarray:
    r"""Lateral chromatic aberration, then depth-dependent defocus, on the rendered rate.

    Each channel is scaled by its magnification about the principal point
    (:func:`imageform.optics.lateral_chromatic_aberration`); a channel shrunk by ``m < 1``
    keeps its unshifted value where it would sample outside the frame. Each pixel is then
    blurred by the disc of its circle of confusion
    :math:`c = (f/N) |d - s| / d \cdot f / (s - f)` at the pitch ``f / f_x``
    (:func:`imageform.optics.defocus_radius_px`, :func:`imageform.optics.blur_by_radius`);
    no blur when every radius is under 0.25 px.
    """
    from imageform.optics import blur_by_radius, defocus_radius_px, lateral_chromatic_aberration

    check_type(rendered, RenderOutput, "rendered")
    check_type(camera, Camera, "camera")
    check_type(lens, LensConfig, "lens")
    focal_length_mm = as_real(focal_length_mm, "focal_length_mm", positive=True)
    if lens.defocus and focal_length_mm * 1e-3 >= lens.focus_distance_m:
        raise InvalidInputError(
            f"expected focal_length_mm below the focus distance ({lens.focus_distance_m:g} m), "
            f"got {focal_length_mm:g} mm"
        )
    img = rendered.rate
    mags = tuple(lens.lateral_ca)
    if any(m != 1.0 for m in mags):
        K = np.asarray(camera.K)
        shifted = lateral_chromatic_aberration(
            img, mags, center=(float(K[0, 2]), float(K[1, 2])), fill=np.nan
        )
        # a channel shrunk by m < 1 samples outside the frame at the border: keep the
        # unshifted value there (the lens would have imaged light from beyond the frame)
        img = np.where(np.isnan(shifted), img, shifted)
    if lens.psf == "wave":
        f = focal_length_mm * 1e-3
        pitch = f / float(np.asarray(camera.K)[0, 0])
        rad = (
            defocus_radius_px(
                rendered.depth,
                focal_length=f,
                f_number=lens.f_number,
                focus=lens.focus_distance_m,
                pixel_pitch=pitch,
            )
            if lens.defocus
            else np.zeros(img.shape[:2])
        )
        # the pupil's PSF holds both the defocus and the diffraction: no separate stage
        return np.maximum(wave_defocus_blur(img, rad, f_number=lens.f_number, pixel_pitch=pitch), 0)
    if lens.defocus:
        f = focal_length_mm * 1e-3
        # the pitch at which the lens's image is sampled: f / fx (the camera's pixels)
        pitch = f / float(np.asarray(camera.K)[0, 0])
        rad = defocus_radius_px(
            rendered.depth,
            focal_length=f,
            f_number=lens.f_number,
            focus=lens.focus_distance_m,
            pixel_pitch=pitch,
        )
        if float(np.max(rad)) >= 0.25:
            img = blur_by_radius(img, rad, step=0.5, max_layers=12)
            # the FFT convolution leaves round-off of ~1e-13 around zero; light is >= 0
            img = np.maximum(img, 0.0)
    if lens.diffraction:
        pitch = focal_length_mm * 1e-3 / float(np.asarray(camera.K)[0, 0])
        img = diffraction_blur(img, f_number=lens.f_number, pixel_pitch=pitch)
    return np.asarray(img)


#: Wavelength bands (m) of the B, G, R channels for :func:`diffraction_blur`: 400-500,
#: 500-600 and 600-700 nm, five wavelengths each, equal weights (a flat spectrum through
#: box-shaped channel sensitivities).
DIFFRACTION_BANDS = (
    (420e-9, 440e-9, 460e-9, 480e-9, 500e-9),
    (500e-9, 525e-9, 550e-9, 575e-9, 600e-9),
    (600e-9, 625e-9, 650e-9, 675e-9, 700e-9),
)


#: The most samples across the fine grid of :func:`diffraction_psf_kernel` (``n k``): a
#: 2047-sample polychromatic PSF takes about 3 s per channel, 16383 would take minutes and
#: gigabytes (issue 16: bounded before anything is computed). The kernel is then at least
#: 680 pixels wide, larger than the images this blur is meant for.
MAX_KERNEL_SAMPLES = 2048


def diffraction_psf_kernel(
    wavelengths: tuple[float, ...], *, f_number: float, pixel_pitch: float
) -> np.ndarray:
    r"""Return the diffraction PSF of a circular aperture over ``wavelengths``, band-limited.

    Band-limited to the pixel grid: the kernel whose transfer function on the grid is the optics'
    own MTF.

    The renderer's pixels are already area averages (the pixel aperture's MTF is in the
    image), so the lens stage must add only the optics: its kernel is the inverse DFT of the
    band-averaged MTF of the circular pupil (Goodman eq. 6-31) sampled on the ``n x n``
    frequencies of the pixel grid up to Nyquist,

    .. math:: h[x] = \frac{1}{n^2} \sum_m \overline{\mathrm{MTF}}
        \big(\lVert m\rVert / (n p)\big)\, e^{2\pi i\, m \cdot x / n},

    with ``p`` the pixel pitch and ``n`` odd, the kernel reaching ``10 lambda N`` of the
    longest wavelength from its centre (the Airy pattern's wings wrap around beyond that). The
    kernel sums to 1; its DTFT equals the continuous pupil MTF at the grid's frequencies (within
    0.02 in between, up to Nyquist), so the simulated image's MTF is the pixel's times the optics',
    as in a camera. (Until 2026-11 the kernel was the Airy pattern integrated over each pixel:
    the pixel's MTF then entered twice and the optics' was folded above 1 cycle/pixel, up to
    17 % off at f/2.8 with 2 um pixels.)
    """
    from imageform.optics import diffraction_limited_mtf

    wavelengths = as_reals(wavelengths, "wavelengths (m)", positive=True)
    f_number = as_real(f_number, "f_number", positive=True)
    pixel_pitch = as_real(pixel_pitch, "pixel_pitch (m)", positive=True)
    lam_n = max(wavelengths) * f_number
    if not lam_n / pixel_pitch < MAX_KERNEL_SAMPLES:
        raise InvalidInputError(
            f"f_number {f_number:g}, pixel_pitch {pixel_pitch:g} m and wavelengths up to "
            f"{max(wavelengths):.3g} m give a diffraction kernel of more than "
            f"{MAX_KERNEL_SAMPLES} samples (a lower f_number)"
        )
    half = max(1, math.ceil(10 * lam_n / pixel_pitch))  # ~98 % of the light
    n = 2 * half + 1
    if n > MAX_KERNEL_SAMPLES:
        raise InvalidInputError(
            f"f_number {f_number:g} and pixel_pitch {pixel_pitch:g} m give a diffraction kernel "
            f"of {n} samples (at most {MAX_KERNEL_SAMPLES}: a lower f_number)"
        )
    m = np.fft.fftfreq(n)  # cycles per pixel, |m| < 1/2
    nu = np.hypot(m[:, None], m[None, :]) / (pixel_pitch * 1e3)  # cycles/mm
    mtf = np.mean(
        [diffraction_limited_mtf(nu, wavelength=w, f_number=f_number) for w in wavelengths],
        axis=0,
    )
    kernel = np.fft.fftshift(np.fft.ifft2(mtf).real)
    return np.asarray(kernel / kernel.sum())


def diffraction_blur(image: np.ndarray, *, f_number: float, pixel_pitch: float) -> np.ndarray:
    """Convolve each channel of ``image (H, W, 3)`` (R, G, B) with its band's diffraction PSF.

    The PSF is band-limited (:func:`diffraction_psf_kernel`, :data:`DIFFRACTION_BANDS`); borders
    reflected; light is kept >= 0.

    An Airy disc well inside a pixel still moves a little light (its wings) to neighbours.
    """
    from scipy.signal import fftconvolve

    if not isinstance(image, np.ndarray) or image.ndim != 3 or image.shape[2] != 3:
        raise InvalidInputError(f"expected image as an (H, W, 3) array, got {describe(image)}")
    out = np.empty_like(image)
    for ch, band in enumerate(reversed(DIFFRACTION_BANDS)):  # R, G, B
        kernel = diffraction_psf_kernel(band, f_number=f_number, pixel_pitch=pixel_pitch)
        p = kernel.shape[0] // 2
        if min(image.shape[:2]) > p:
            padded = np.pad(image[..., ch], p, mode="reflect")
        else:
            padded = np.pad(image[..., ch], p, mode="symmetric")
        out[..., ch] = fftconvolve(padded, kernel, mode="valid")
    return np.maximum(out, 0.0)


def wave_defocus_blur(
    image: np.ndarray, radius_px: float | np.ndarray, *, f_number: float, pixel_pitch: float
) -> np.ndarray:
    r"""Blur each channel by the wave-optics PSF of each pixel's defocus.

    The geometric disc of radius :math:`R` pixels (the circle of confusion
    :math:`c = 2 R p`) becomes the Zernike defocus term of the pupil,
    :math:`c_4 = c / (16 \sqrt{3}\, N)` metres RMS (:func:`imageform.optics.zernike_defocus`),
    and the PSF is that pupil's Fraunhofer pattern over the channel's band (three wavelengths
    of :data:`DIFFRACTION_BANDS`, equal weights; :func:`imageform.optics.polychromatic_psf`),
    so diffraction is included: at :math:`R = 0` it is the Airy pattern, and for a defocus
    of many waves it tends to the geometric disc. Each pixel blends the PSFs of the two
    nearest radii of a ladder (:func:`imageform.optics.blur_by_radius`, 12 radii at most).

    Parameters
    ----------
    image : ndarray, shape (H, W, 3)
        R, G, B light on the sensor.
    radius_px : float or ndarray, shape (H, W)
        Geometric defocus radius per pixel (pixels, >= 0).
    f_number : float
        Working f-number ``N``.
    pixel_pitch : float
        Pixel pitch (m).

    Returns
    -------
    ndarray, shape (H, W, 3)

    Raises
    ------
    InvalidInputError
        ``image`` not (H, W, 3), or a defocus too large for the PSF's sampling.
    """
    from imageform.optics import blur_by_radius, polychromatic_psf, zernike_defocus

    if not isinstance(image, np.ndarray) or image.ndim != 3 or image.shape[2] != 3:
        raise InvalidInputError(f"expected image as an (H, W, 3) array, got {describe(image)}")
    fn = as_real(f_number, "f_number", positive=True, maximum=1000.0)
    pitch = as_real(pixel_pitch, "pixel_pitch", positive=True, maximum=1e-3)
    r = as_real_array(radius_px, "radius_px", nonnegative=True)
    if r.ndim != 0 and r.shape != image.shape[:2]:
        raise InvalidInputError(
            f"expected radius_px as a number or an {image.shape[:2]} array, got {describe(r)}"
        )
    reach = float(r.max()) + 6.0 * DIFFRACTION_BANDS[-1][-1] * fn / pitch
    if reach > 1024:
        raise InvalidInputError(
            f"radius_px, f_number and pixel_pitch give a PSF {2 * reach:.3g} pixels wide; "
            "expected at most 2048"
        )
    rad = np.broadcast_to(r, image.shape[:2])
    out = np.empty_like(image)
    for ch, band in enumerate(reversed(DIFFRACTION_BANDS)):  # R, G, B
        lams = band[::2]

        def kernel(r: float, lams: tuple[float, ...] = lams) -> np.ndarray:
            c4 = zernike_defocus(2.0 * r * pitch, f_number=fn)
            half = math.ceil(r + 6.0 * max(lams) * fn / pitch)  # the disc and the Airy rings
            return polychromatic_psf(
                [0.0, 0.0, 0.0, c4],
                wavelengths=lams,
                f_number=fn,
                pixel_pitch=pitch,
                size=2 * max(half, 2) + 1,
            )

        out[..., ch] = blur_by_radius(image[..., ch], rad, step=0.5, max_layers=12, kernel=kernel)
    return out


def exposure_time(rate: np.ndarray, config: SensorConfig, sensor: SensorModel) -> float:
    r"""Return the exposure (s): ``config.exposure_time_s``, or the automatic one for ``"auto"``.

    For ``"auto"``, the time that brings the 99.5th percentile of the brightest channel to
    ``auto_exposure_level`` of the full well: :math:`t = a\, FW / \dot e_{99.5}`.

    Raises
    ------
    InvalidInputError
        ``"auto"`` on a black scene.
    """
    check_type(config, SensorConfig, "config")
    check_type(sensor, SensorModel, "sensor")
    rate = real_array(rate, "rate", ndim=(2, 3), finite=False)
    if config.exposure_time_s != "auto":
        return float(config.exposure_time_s)
    if rate.size == 0:
        raise InvalidInputError(f"expected rate with at least one pixel, got shape {rate.shape}")
    bright = float(np.percentile(rate.max(axis=-1), 99.5))
    if not math.isfinite(bright):
        raise InvalidInputError(f"rate contains NaN or inf (99.5th percentile {bright:g})")
    if bright <= 0:
        raise InvalidInputError("rate: the scene is black: auto exposure has nothing to measure")
    return float(config.auto_exposure_level) * sensor.full_well / bright


def capture_raw(
    mean_electrons: np.ndarray,
    sensor: SensorModel,
    config: SensorConfig,
    exposure_time_s: float,
    rng: np.random.Generator,
) -> np.ndarray:
    """Mean electrons ``(H, W, 3)`` to the mosaicked raw image ``(H, W)`` uint16 (DN).

    With ``config.noise``: :meth:`imageform.sensor.SensorModel.capture` (Poisson shot and
    dark noise, full-well clipping, fixed pattern, read noise, gain, black level, ADC);
    without: the mean signal, clipped to the full well, plus the mean dark signal, through
    the gain and the ADC. Then the CFA keeps one channel per photosite.
    """
    from imageform.sensor.cfa import cfa_masks

    if config.noise:
        dn = sensor.capture(mean_electrons, exposure_time=exposure_time_s, rng=rng)
    else:
        e = np.minimum(mean_electrons, sensor.full_well) + sensor.dark_current * exposure_time_s
        analog = sensor.system_gain * e + sensor.black_level
        dn = np.clip(np.floor(analog + 0.5), 0, sensor.max_dn).astype(np.uint16)
    masks = cfa_masks(mean_electrons.shape[:2], config.cfa)
    return np.asarray((dn * masks).sum(axis=-1), dtype=np.uint16)


def normalize_raw(raw: np.ndarray, sensor: SensorModel, exposure_time_s: float) -> np.ndarray:
    r"""Raw DN to [0, 1]: black level and mean dark signal subtracted, divided by the range.

    .. math:: x = (DN - B - K\, I_{dark}\, t) / (DN_{max} - B)
    """
    raw = real_array(raw, "raw", ndim=2, finite=False)  # float64 (the one conversion)
    check_type(sensor, SensorModel, "sensor")
    exposure_time_s = as_real(exposure_time_s, "exposure_time_s", nonnegative=True)
    dark_dn = sensor.system_gain * sensor.dark_current * exposure_time_s
    return (raw - sensor.black_level - dark_dn) / (sensor.max_dn - sensor.black_level)


def demosaic_raw(normalized: np.ndarray, cfa: str, method: str) -> np.ndarray:
    """Return camera RGB ``(H, W, 3)`` float64 from the normalised mosaic.

    Demosaiced by :func:`imageform.sensor.demosaic.demosaic`.
    """
    from imageform.sensor.cfa import CFA_PATTERNS
    from imageform.sensor.demosaic import DEMOSAIC_METHODS, demosaic

    if not isinstance(cfa, str):
        raise TypeError(f"expected cfa as a CFA pattern name, got {describe(cfa)}")
    if cfa.strip().upper() not in CFA_PATTERNS:
        raise UnknownOptionError(
            f"unknown CFA pattern {describe(cfa, 30)} for cfa; valid: {', '.join(CFA_PATTERNS)}"
        )
    cfa = cfa.strip().upper()
    method = check_name(method, DEMOSAIC_METHODS, "demosaicing method", "method")
    kind = getattr(getattr(normalized, "dtype", None), "kind", "")
    if kind in ("i", "u"):  # digital numbers: the caller divides by the white level first
        raise InvalidInputError(
            f"expected normalized as floats (the raw mosaic divided by its white level), got "
            f"{describe(normalized)}"
        )
    arr = real_array(normalized, "normalized", ndim=2, finite=False)
    if min(arr.shape) < 2:
        raise InvalidInputError(
            f"expected normalized as a mosaic of at least 2x2 pixels, got shape {arr.shape}"
        )
    lo, hi = float(arr.min()), float(arr.max())  # one pass; demosaic reads it whole anyway
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise InvalidInputError("normalized contains NaN or inf")
    if lo < -1e3 or hi > 1e3 or (hi > 1.5 and bool(np.all(arr == np.round(arr)))):
        raise InvalidInputError(
            f"expected normalized as a raw image scaled to about [0, 1], got {lo:g}..{hi:g}"
        )
    return np.asarray(demosaic(arr, cfa, method, allow_odd=True), dtype=np.float64)


def correct_lens_shading(image: np.ndarray, falloff: np.ndarray) -> np.ndarray:
    """Flat-field correction: ``image`` divided by the vignetting map ``falloff`` (H, W)."""
    img = real_array(image, "image", ndim=3, finite=False)
    fall = real_array(falloff, "falloff", ndim=2, finite=False)
    if fall.shape != img.shape[:2]:
        raise InvalidInputError(
            f"expected falloff of the image's shape {img.shape[:2]}, got {fall.shape}"
        )
    if fall.size and not float(fall.min()) > 0:  # one pass over (H, W); NaN fails too
        raise InvalidInputError(f"expected falloff > 0 everywhere, got min {float(fall.min()):g}")
    return np.asarray(img / fall[..., None])


def balance_white(
    image: np.ndarray, method: str, chart_rgb: np.ndarray | None = None
) -> WhiteBalanced:
    r"""White balance in linear light, the green channel kept.

    ``"none"``: gains 1. ``"colorchecker"``: the gains that make the mean of the chart's
    :data:`~imageform.simulate.truth.NEUTRAL_PATCHES` grey, :math:`g_c = \mathrm{mean}_p
    (G_p / C_p)`, from ``chart_rgb`` (24, 3) (the patch means). Otherwise
    :func:`imageform.color.white_balance` with that method.

    Raises
    ------
    InvalidInputError
        ``"colorchecker"`` without ``chart_rgb``.
    """
    from imageform.color import WHITE_BALANCE_METHODS, white_balance

    if not isinstance(method, str):
        raise TypeError(f"expected method as a white-balance method name, got {describe(method)}")
    if method == "none":
        return WhiteBalanced(image, np.ones(3))
    if method == "colorchecker":
        if chart_rgb is None:
            raise InvalidInputError("white_balance = 'colorchecker' needs a colorchecker object")
        idx = [COLORCHECKER_PATCHES.index(name) for name in NEUTRAL_PATCHES]
        neutral = np.asarray(chart_rgb)[idx]
        with np.errstate(all="ignore"):
            gains = np.nanmean(neutral[:, 1:2] / neutral, axis=0)
        if not np.all(np.isfinite(gains) & (gains > 0)):
            raise InvalidInputError(
                "chart_rgb: white_balance = 'colorchecker' found no measured neutral patch "
                "(the chart's greys are outside the image or black)"
            )
        return WhiteBalanced(image * gains, gains)
    try:
        res = white_balance(image, method, transfer="linear", normalize="green")
    except UnknownOptionError:
        valid = ", ".join(("none", "colorchecker", *WHITE_BALANCE_METHODS))
        raise UnknownOptionError(
            f"unknown white-balance method {describe(method, 30)} for method; valid: {valid}"
        ) from None
    return WhiteBalanced(np.asarray(res.image), np.asarray(res.gains))


def correct_color(
    image: np.ndarray, method: str, chart_rgb: np.ndarray | None = None
) -> ColorCorrected:
    """Camera RGB to linear sRGB by a 3x3 matrix: ``image @ M``.

    ``"colorchecker"`` (with ``chart_rgb``, the white-balanced patch means (24, 3)): M is
    the least-squares fit of the patches to their ground-truth linear sRGB under D65
    (:func:`imageform.analysis.fit_color_correction` with ``transfer="linear"``; ``M`` is
    its matrix transposed). ``"none"`` (or no chart): M = I.
    """
    from imageform.analysis import ColorCorrection
    from imageform.color import xyz_to_linear_srgb
    from imageform.spectral import colorchecker_reflectances, spectrum_to_xyz

    M = np.eye(3)
    if method == "colorchecker" and chart_rgb is not None:
        target = np.asarray(
            xyz_to_linear_srgb(spectrum_to_xyz(colorchecker_reflectances(), illuminant="D65"))
        )
        M = _fit_matrix(chart_rgb, target)
    corrected = ColorCorrection("linear", 1, np.asarray(M, np.float64).T, transfer="linear")
    return ColorCorrected(np.asarray(corrected.apply(image)), M)


def encode_output(linear_srgb: np.ndarray, space: str, transfer: str) -> Encoded:
    """Convert linear sRGB to the output ``space``, clip to [0, 1] and encode with ``transfer``.

    The primaries are the output ``space``'s; the clipping to the display range is an explicit step;
    ``transfer="space"`` applies the space's own.
    """
    from imageform.color import RGB_SPACES, encode, linear_srgb_to_xyz, xyz_to_linear_rgb

    linear_srgb = real_array(linear_srgb, "linear_srgb", finite=False)
    lin = (
        linear_srgb
        if space == "srgb"
        else xyz_to_linear_rgb(linear_srgb_to_xyz(linear_srgb), space)
    )
    tf = RGB_SPACES[space].transfer if transfer == "space" else transfer
    clipped = np.clip(np.asarray(lin), 0.0, 1.0)
    return Encoded(np.asarray(encode(clipped, tf)), tf)


def decode_output(encoded: Encoded, space: str) -> np.ndarray:
    """Decode the encoded output back to linear sRGB (to measure it against the truth)."""
    from imageform.color import decode, linear_rgb_to_xyz, xyz_to_linear_srgb

    check_type(encoded, Encoded, "encoded")
    lin = np.asarray(decode(encoded.image, encoded.transfer))
    return lin if space == "srgb" else np.asarray(xyz_to_linear_srgb(linear_rgb_to_xyz(lin, space)))


def measure_photon_transfer(sensor: SensorModel, rng: np.random.Generator) -> PhotonTransferData:
    """Measure the EMVA 1288 photon transfer of the green channel at 550 nm.

    Dark to beyond saturation: 20 exposure times from 1e-3 to 1.3 times the saturation time, 48x48
    flat-field pairs at 0.05 W/m² (:func:`imageform.sensor.emva.simulate_photon_transfer`).
    """
    from imageform.sensor.emva import simulate_photon_transfer
    from imageform.sensor.model import photons_per_pixel

    irradiance = 0.05  # W/m²
    per_s = float(
        photons_per_pixel(irradiance, 550.0, pixel_area=sensor.pixel_area, exposure_time=1.0)
    )
    qe = float(sensor.quantum_efficiency(550.0)[1]) * sensor.fill_factor
    t_sat = sensor.full_well / max(per_s * qe, 1e-300)
    times = t_sat * np.geomspace(1e-3, 1.3, 20)
    return simulate_photon_transfer(
        sensor,
        irradiance=irradiance,
        wavelength_nm=550.0,
        exposure_times=times,
        rng=rng,
        shape=(48, 48),
        channel=1,
    )


# --- a measured camera's lens and colour (issue 18; imageform.simulate.apply_camera_file) ---


def _sub_box(f: float, n: int) -> float:
    """|MTF| of the mean of ``n`` point samples across a pixel at ``f`` cycles/pixel."""
    den = n * math.sin(math.pi * f / n)
    if abs(den) < 1e-12:  # f = 0, or a multiple of n (the samples alias to DC)
        return 1.0
    return abs(math.sin(math.pi * f) / den)


def gaussian_sigma_for_mtf50(mtf50: float, *, supersampling: int = 0) -> float:
    r"""Return the Gaussian PSF's sigma (pixels) that gives a system MTF50 of ``mtf50``.

    ``mtf50`` is in cycles per pixel. A Gaussian of sigma :math:`\sigma` has
    :math:`\mathrm{MTF}(f) = e^{-2\pi^2\sigma^2 f^2}`, so on its own
    :math:`\sigma = \sqrt{\ln 2 / (2\pi^2)} / f_{50}`. A slanted-edge measurement also sees the
    pixel aperture: with ``supersampling`` S > 0 (the renderer's S point samples across each
    pixel, MTF :math:`|\sin(\pi f) / (S \sin(\pi f / S))|`) sigma is solved from
    :math:`e^{-2\pi^2\sigma^2 f_{50}^2}\, \mathrm{box}_S(f_{50}) = 1/2`; 0 when the pixel alone
    is already that blurred.

    Examples
    --------
    >>> round(gaussian_sigma_for_mtf50(0.25), 4)
    0.7496
    >>> round(gaussian_sigma_for_mtf50(0.25, supersampling=4), 4)
    0.6942
    """
    f = as_real(mtf50, "mtf50 (cycles/pixel)", positive=True, maximum=10.0)
    n = as_int(supersampling, "supersampling", minimum=0)
    box = _sub_box(f, n) if n else 1.0
    if box <= 0.5:
        return 0.0
    return math.sqrt(math.log(box / 0.5) / (2 * math.pi**2)) / f


def _gaussian_blur(channel: np.ndarray, sigma: float) -> np.ndarray:
    r"""``channel`` blurred by a Gaussian of ``sigma`` pixels with its continuous MTF.

    The transfer function on the pixel grid is the continuous one,
    :math:`e^{-2\pi^2\sigma^2 f^2}` up to Nyquist (a sampled Gaussian kernel of sigma < 1 px
    has a much higher MTF: 0.77 instead of 0.62 at 0.35 cycles/pixel for sigma = 0.45):
    multiplied in the DFT of each axis, the borders reflected over 6 sigma (at least 8 pixels).
    """
    pad = max(8, math.ceil(6 * sigma))
    a = np.pad(channel, pad, mode="reflect" if min(channel.shape) > pad else "symmetric")
    for axis in (0, 1):
        n = a.shape[axis]
        f = np.fft.rfftfreq(n)
        h = np.exp(-2 * math.pi**2 * sigma**2 * f**2)
        shape = [1, 1]
        shape[axis] = h.size
        a = np.fft.irfft(np.fft.rfft(a, axis=axis) * h.reshape(shape), n=n, axis=axis)
    return np.asarray(a[pad:-pad, pad:-pad])


#: Wavelengths (m) of the R, G, B channels for a Zernike PSF (the bands of
#: :data:`imageform.simulate.stages.DIFFRACTION_BANDS`, three per channel).
_ZERNIKE_BANDS = (
    (610e-9, 650e-9, 690e-9),
    (510e-9, 550e-9, 590e-9),
    (430e-9, 465e-9, 500e-9),
)


def measured_optics_blur(
    image: np.ndarray, optics: CameraOptics, *, pixel_pitch: float, supersampling: int
) -> np.ndarray:
    r"""``image (H, W, 3)`` blurred by the camera file's lens model.

    The image is R, G, B, already integrated over each pixel by the renderer; borders are
    reflected, light kept >= 0.

    ``diffraction``: :func:`imageform.simulate.stages.diffraction_blur` at ``f_number``.
    ``zernike``: per channel the polychromatic PSF of the aberrated pupil
    (:func:`imageform.optics.polychromatic_psf`, coefficients in waves at ``wavelength_nm``
    turned into metres of optical path), point-sampled at ``pixel_pitch``; with
    ``zernike_zones``, field-dependent: the image blurred by each zone's pupil (tiled
    convolution, an isoplanatic patch per zone) and the results blended with bilinear
    weights between the zone centres, :math:`I' = \sum_z w_z(p)\,(I * h_z)(p)`,
    :math:`\sum_z w_z = 1`.
    ``gaussian``: a Gaussian of ``gaussian_sigma_px`` (its continuous MTF on the pixel grid).
    ``mtf50``: the Gaussian of :func:`gaussian_sigma_for_mtf50` for each channel's MTF50 (the
    pixel aperture of ``supersampling`` accounted for).
    """
    check_type(optics, CameraOptics, "optics", "an imageform.io.CameraOptics")
    img = real_array(image, "image", ndim=3)
    if img.shape[2] != 3:
        raise InvalidInputError(f"expected image as an (H, W, 3) array, got {describe(image)}")
    pixel_pitch = as_real(pixel_pitch, "pixel_pitch (m)", positive=True)
    supersampling = as_int(supersampling, "supersampling", minimum=0)
    model = optics.model
    if model == "diffraction":
        assert optics.f_number is not None
        return diffraction_blur(img, f_number=optics.f_number, pixel_pitch=pixel_pitch)
    out = np.empty_like(img)
    if model in ("gaussian", "mtf50"):
        if model == "gaussian":
            sigmas: tuple[float, ...] = (float(optics.gaussian_sigma_px or 0.0),) * 3
        else:
            rgb = optics.mtf50_rgb()
            assert rgb is not None
            sigmas = tuple(gaussian_sigma_for_mtf50(m, supersampling=supersampling) for m in rgb)
        for c in range(3):
            out[..., c] = _gaussian_blur(img[..., c], sigmas[c]) if sigmas[c] > 0 else img[..., c]
        return np.maximum(out, 0.0)
    # zernike: one pupil, or one per zone of the field blended bilinearly
    assert optics.wavelength_nm is not None and optics.f_number is not None
    if optics.zernike_zones is None:
        assert optics.zernike is not None
        return np.maximum(
            _zernike_blur(img, optics.zernike, optics.wavelength_nm, optics.f_number, pixel_pitch),
            0.0,
        )
    zones = optics.zernike_zones
    rows, cols = len(zones), len(zones[0])
    wy = _zone_weights(img.shape[0], rows)
    wx = _zone_weights(img.shape[1], cols)
    out[:] = 0.0
    for i in range(rows):
        for k in range(cols):
            if not (wy[i].any() and wx[k].any()):
                continue
            blurred = _zernike_blur(
                img, zones[i][k], optics.wavelength_nm, optics.f_number, pixel_pitch
            )
            out += (wy[i][:, None] * wx[k][None, :])[..., None] * blurred
    return np.maximum(out, 0.0)


def _zone_weights(n: int, zones: int) -> np.ndarray:
    """Return ``(zones, n)`` bilinear weights of the zone centres along one image axis.

    Zone ``i`` is centred at ``(i + 1/2) n / zones``; between two centres the weights fall
    linearly, beyond the first and last centre the nearest zone has all the weight: they sum
    to 1 at every pixel (a partition of unity, so a uniform field gives the one-pupil blur).
    """
    x = np.arange(n) + 0.5
    centres = (np.arange(zones) + 0.5) * n / zones
    w = np.zeros((zones, n))
    if zones == 1:
        w[0] = 1.0
        return w
    pos = np.clip(np.interp(x, centres, np.arange(zones)), 0, zones - 1)
    lo = np.floor(pos).astype(int)
    hi = np.minimum(lo + 1, zones - 1)
    frac = pos - lo
    np.add.at(w, (lo, np.arange(n)), 1.0 - frac)
    np.add.at(w, (hi, np.arange(n)), frac)
    return w


def _zernike_blur(
    img: np.ndarray,
    zernike: tuple[float, ...],
    wavelength_nm: float,
    f_number: float,
    pixel_pitch: float,
) -> np.ndarray:
    """Convolve each channel with the polychromatic PSF of the pupil with these aberrations."""
    from scipy.signal import fftconvolve

    from imageform.optics import polychromatic_psf

    coeffs = {j + 1: w * wavelength_nm * 1e-9 for j, w in enumerate(zernike)}
    rms_waves = math.sqrt(sum(w * w for w in zernike[3:]))
    reach = 10 * 700e-9 * f_number * (1 + 4 * rms_waves) / pixel_pitch
    half = min(64, max(2, math.ceil(reach)))
    size = 2 * half + 1
    out = np.empty_like(img)
    for c, band in enumerate(_ZERNIKE_BANDS):
        kernel = polychromatic_psf(
            coeffs, wavelengths=band, f_number=f_number, pixel_pitch=pixel_pitch, size=size
        )
        if min(img.shape[:2]) > half:
            padded = np.pad(img[..., c], half, mode="reflect")
        else:
            padded = np.pad(img[..., c], half, mode="symmetric")
        out[..., c] = fftconvolve(padded, kernel, mode="valid")
    return out


def measured_color_matrix(color: CameraColor) -> np.ndarray | None:
    r"""Return the simulator's colour-correction matrix ``M`` of the file's ``ccm``.

    ``linear sRGB = camera RGB @ M``, while the file's ``ccm`` is ``out = ccm @ rgb``: ``M`` is
    ``ccm.T``, or for ``ccm_to = "xyz"`` :math:`(M_{XYZ \to sRGB}\, \mathrm{ccm})^T`; None
    without a ``ccm``.
    """
    check_type(color, CameraColor, "color", "an imageform.io.CameraColor")
    if color.ccm is None:
        return None
    ccm = np.asarray(color.ccm, dtype=np.float64)
    if color.ccm_to == "xyz":
        from imageform.color import xyz_to_linear_srgb

        to_srgb = np.asarray(xyz_to_linear_srgb(np.eye(3))).T  # columns: images of X, Y, Z
        ccm = to_srgb @ ccm
    return np.asarray(ccm.T)
