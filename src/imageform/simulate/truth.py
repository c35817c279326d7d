r"""Ground truth of a scene and measurements on the simulated images.

- ColorChecker: CIELAB under D65 from the reflectances (CIE 015:2018 eqs. 7.1-7.3 via
  :func:`imageform.spectral.spectrum_to_xyz`, then :func:`imageform.color.xyz_to_lab`), the
  patch centres projected through the camera, the patch means of an image and
  :func:`measure_colorchecker` (CIEDE2000 and luminance SNR per patch: the one measurement
  the simulator and the report both give).
- Rails: the true vanishing point :math:`v \sim K R d` of the rail direction d (distorted
  like every image point when the camera has a distortion model) and the horizon, the
  vanishing line :math:`l \sim K^{-T} R n` of the ground plane of normal n (Hartley &
  Zisserman, 2nd ed., §8.6.1-8.6.2), and :func:`vanishing_errors` against a detection.
- The light: its correlated colour temperature from its spectrum (:func:`light_cct`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from imageform._validate import as_int, check_type, describe, real_array
from imageform.color import (
    delta_e_ciede2000,
    linear_srgb_to_luminance,
    linear_srgb_to_xyz,
    xy_to_cct,
    xyz_to_lab,
    xyz_to_xy,
)
from imageform.errors import InvalidInputError
from imageform.geometry.camera import Camera
from imageform.geometry.vanishing import horizon_line
from imageform.simulate._rng import RNGLike, random_source
from imageform.simulate.config import ColorCheckerConfig
from imageform.simulate.result import ColorCheckerTruth, PatchMeasurements, VanishingTruth
from imageform.simulate.scene import SceneObject
from imageform.spectral import COLORCHECKER_PATCHES, colorchecker_reflectances, spectrum_to_xyz
from imageform.spectral.spectrum import Spectrum

__all__ = [
    "NEUTRAL_PATCHES",
    "colorchecker_truth",
    "delta_e_patches",
    "detect_vanishing",
    "light_cct",
    "measure_colorchecker",
    "patch_means",
    "patch_stats",
    "patch_windows",
    "rails_truth",
    "vanishing_errors",
    "xy_of_linear_srgb",
]

#: The ColorChecker patches a chart white balance averages: the four middle greys (the white
#: may clip, the black is noisy).
NEUTRAL_PATCHES: tuple[str, ...] = (
    "neutral 8 (.23 D)",
    "neutral 6.5 (.44 D)",
    "neutral 5 (.70 D)",
    "neutral 3.5 (1.05 D)",
)


#: The largest colour value :func:`delta_e_patches` takes (beyond it CIELAB overflows).
_MAX_COLOUR = 1e15


def colorchecker_truth(obj: SceneObject, camera: Camera) -> ColorCheckerTruth:
    """Ground-truth Lab (D65) and image positions of the 24 patches of ``obj``.

    The sampling radius is a third of the smallest projected half-patch (so that windows stay
    inside the patches in perspective).
    """
    check_type(obj, SceneObject, "obj")
    check_type(camera, Camera, "camera")
    if not isinstance(obj.config, ColorCheckerConfig):
        raise InvalidInputError(f"expected a colorchecker object, got a {obj.kind}")
    xyz = spectrum_to_xyz(colorchecker_reflectances(), illuminant="D65")
    lab = np.asarray(xyz_to_lab(xyz, white="D65"))
    i, j = np.meshgrid(np.arange(6), np.arange(4))
    a = (i.ravel() + 0.5) / 6.0
    b = (j.ravel() + 0.5) / 4.0
    centres = obj.origin + a[:, None] * obj.edge_right + b[:, None] * obj.edge_down
    uv = np.asarray(camera.project(centres).uv)
    half = (1.0 - obj.config.gap_fraction) / 2
    da = half / 6.0
    corner = obj.origin + (a[:, None] + da) * obj.edge_right + b[:, None] * obj.edge_down
    cu = np.asarray(camera.project(corner).uv)
    db = half / 4.0
    corner2 = obj.origin + a[:, None] * obj.edge_right + (b[:, None] + db) * obj.edge_down
    cv = np.asarray(camera.project(corner2).uv)
    half_px = np.minimum(np.linalg.norm(cu - uv, axis=1), np.linalg.norm(cv - uv, axis=1))
    radius = float(np.nanmin(half_px)) / 2.0 if np.any(np.isfinite(half_px)) else 0.0
    # at least 0.5 px: every window then holds the pixel nearest its centre
    return ColorCheckerTruth(COLORCHECKER_PATCHES, lab, uv, max(radius, 0.5))


def patch_windows(
    truth: ColorCheckerTruth, height: int, width: int
) -> list[tuple[slice, slice] | None]:
    """Return the square window ``(rows, cols)`` sampled around each patch centre.

    Pixels whose centres lie within ``sample_radius_px`` of the centre along both axes, cut to the
    image (``None`` where nothing of the window is inside).

    Examples
    --------
    >>> t = ColorCheckerTruth(("a",), np.zeros((1, 3)), np.array([[10.0, 5.0]]), 2.0)
    >>> patch_windows(t, 20, 20)
    [(slice(3, 8, None), slice(8, 13, None))]
    """
    if not isinstance(truth, ColorCheckerTruth):
        raise TypeError(f"expected truth as a ColorCheckerTruth, got {describe(truth)}")
    height = as_int(height, "height", minimum=0, maximum=10**9)
    width = as_int(width, "width", minimum=0, maximum=10**9)
    c = np.asarray(truth.centers_uv, dtype=np.float64)
    r = float(truth.sample_radius_px)
    if c.ndim != 2 or c.shape[1] != 2 or not np.isfinite(r) or r < 0:
        raise InvalidInputError(
            f"expected centers_uv of shape (n, 2) and sample_radius_px >= 0, "
            f"got {c.shape} and {truth.sample_radius_px!r}"
        )
    out: list[tuple[slice, slice] | None] = []
    for u, v in c:
        if not (np.isfinite(u) and np.isfinite(v)):
            out.append(None)
            continue
        r0, r1 = max(math.ceil(v - r), 0), min(math.floor(v + r) + 1, height)
        c0, c1 = max(math.ceil(u - r), 0), min(math.floor(u + r) + 1, width)
        out.append((slice(r0, r1), slice(c0, c1)) if r0 < r1 and c0 < c1 else None)
    return out


def patch_means(image: np.ndarray, truth: ColorCheckerTruth) -> np.ndarray:
    """Mean ``(24, C)`` of each patch window (:func:`patch_windows`); NaN outside the image.

    Examples
    --------
    >>> t = ColorCheckerTruth(("a",), np.zeros((1, 3)), np.array([[1.0, 1.0]]), 1.0)
    >>> patch_means(np.arange(27.0).reshape(3, 3, 3), t).tolist()
    [[12.0, 13.0, 14.0]]
    """
    return patch_stats(image, truth)[0]


def patch_stats(image: np.ndarray, truth: ColorCheckerTruth) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard deviation ``(24, C)`` of each patch window."""
    check_type(truth, ColorCheckerTruth, "truth")
    img = real_array(image, "image", ndim=(2, 3), finite=False)  # NaN: an unmeasured pixel
    if img.ndim == 2:
        img = img[..., None]
    if img.size == 0:
        raise InvalidInputError(f"expected image with at least one pixel, got shape {img.shape}")
    h, w, c = img.shape
    mean = np.full((len(truth.names), c), np.nan)
    std = np.full((len(truth.names), c), np.nan)
    for k, win in enumerate(patch_windows(truth, h, w)):
        if win is None:
            continue
        block = img[win].reshape(-1, c)
        mean[k] = block.mean(axis=0)
        std[k] = block.std(axis=0)
    return mean, std


def xy_of_linear_srgb(rgb: np.ndarray) -> np.ndarray:
    """Chromaticity xy ``(..., 2)`` of linear-sRGB colours (CIE 015:2018 eq. 7.4).

    Examples
    --------
    >>> xy_of_linear_srgb(np.array([1.0, 1.0, 1.0])).round(4).tolist()
    [0.3127, 0.329]
    """
    arr = real_array(rgb, "rgb", last=3, finite=False)  # a NaN row: a patch not measured
    out = np.full((*arr.shape[:-1], 2), np.nan)
    ok = np.all(np.isfinite(arr), axis=-1)
    out[ok] = np.asarray(xyz_to_xy(linear_srgb_to_xyz(arr[ok])))
    return out


def delta_e_patches(linear_srgb: np.ndarray, lab_truth: np.ndarray) -> np.ndarray:
    """CIEDE2000 of linear-sRGB patch colours ``(24, 3)`` against ``lab_truth`` (D65).

    A row of NaN is a patch not measured (outside the image): its ΔE00 is NaN. A row only
    partly NaN, or any inf, is refused.
    """
    rgb = real_array(linear_srgb, "linear_srgb", ndim=2, last=3, finite=False, min_size=3)
    lab = real_array(lab_truth, "lab_truth", ndim=2, last=3)
    if lab.shape != rgb.shape:
        raise InvalidInputError(
            f"expected lab_truth of linear_srgb's shape {rgb.shape}, got {lab.shape}"
        )
    nan = np.isnan(rgb)
    if np.isinf(rgb).any() or (nan.any(axis=1) & ~nan.all(axis=1)).any():
        raise InvalidInputError(
            "linear_srgb contains inf or a row only partly NaN (a whole NaN row: not measured)"
        )
    for arr, name in ((rgb, "linear_srgb"), (lab, "lab_truth")):
        big = float(np.nanmax(np.abs(arr))) if not np.isnan(arr).all() else 0.0
        if big > _MAX_COLOUR:
            raise InvalidInputError(
                f"expected {name} within ±{_MAX_COLOUR:g} (a colour value), got {big:g}"
            )
    return _lab_and_delta_e(rgb, lab)[1]


def _lab_and_delta_e(linear_srgb: np.ndarray, lab_truth: np.ndarray) -> tuple[Any, Any]:
    rgb = np.asarray(linear_srgb, dtype=np.float64)
    lab = np.full(rgb.shape, np.nan)
    out = np.full(rgb.shape[0], np.nan)
    ok = np.all(np.isfinite(rgb), axis=-1)
    if ok.any():
        lab[ok] = np.asarray(xyz_to_lab(linear_srgb_to_xyz(rgb[ok]), white="D65"))
        out[ok] = np.asarray(delta_e_ciede2000(lab[ok], np.asarray(lab_truth)[ok]))
    return lab, out


def measure_colorchecker(
    output_linear_srgb: np.ndarray,
    snr_linear_srgb: np.ndarray,
    truth: ColorCheckerTruth,
    *,
    snr_stage: str,
) -> PatchMeasurements:
    r"""Measure every patch: colour on the output, noise on a linear stage.

    Colour: the mean linear sRGB of each patch window (:func:`patch_windows`) of
    ``output_linear_srgb`` (the output decoded to linear sRGB), converted to XYZ and CIELAB
    (white: CIE D65, the ground truth's) and compared with ``truth.lab_d65`` by CIEDE2000:

    .. math:: \Delta E_{00}\big(\mathrm{Lab}(\overline{\mathrm{RGB}}), \mathrm{Lab}_{truth}\big)

    Noise: on ``snr_linear_srgb`` (the stage named ``snr_stage``), the luminance of each pixel
    :math:`Y = 0.2126 R + 0.7152 G + 0.0722 B`
    (:func:`imageform.color.linear_srgb_to_luminance`) gives

    .. math:: \mathrm{SNR} = 20 \log_{10}\big(\overline{Y} / \sigma_Y\big)\ \mathrm{dB}

    over the window (``inf`` where σ = 0, NaN where the mean is not positive).

    Source: CIE 142-2001 / Sharma, Wu & Dalal (2005) for ΔE00; ITU-R BT.709-6 for Y;
    ISO 15739:2013 §6 (the SNR of a uniform patch, on the luminance channel).
    """
    from imageform.color.cielab import lab_to_xyz
    from imageform.color.delta_e import describe_delta_e
    from imageform.color.rgb_spaces import xyz_to_linear_srgb
    from imageform.color.transfer import linear_to_srgb

    lab_truth = np.asarray(truth.lab_d65, dtype=np.float64)
    n = len(truth.names)
    if lab_truth.shape != (n, 3) or np.asarray(truth.centers_uv).shape != (n, 2):
        raise InvalidInputError(
            f"expected lab_d65 ({n}, 3) and centers_uv ({n}, 2) for {n} patch names, got "
            f"{lab_truth.shape} and {np.asarray(truth.centers_uv).shape}"
        )
    rgb = patch_means(output_linear_srgb, truth)[:, :3]
    lab, de = _lab_and_delta_e(rgb, lab_truth)
    readings = tuple(describe_delta_e(d) if np.isfinite(d) else "not measured" for d in de)
    lum = np.asarray(linear_srgb_to_luminance(np.asarray(snr_linear_srgb, dtype=np.float64)))
    mean, std = patch_stats(lum, truth)
    mu, sd = mean[:, 0], std[:, 0]
    snr = np.full(n, np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):
        ok = (mu > 0) & (sd > 0)
        snr[ok] = 20.0 * np.log10(mu[ok] / sd[ok])
    snr[(mu > 0) & (sd == 0)] = np.inf
    truth_lin = np.asarray(xyz_to_linear_srgb(lab_to_xyz(lab_truth, white="D65")))
    truth_srgb = np.asarray(linear_to_srgb(np.clip(truth_lin, 0.0, 1.0)))
    return PatchMeasurements(
        names=tuple(truth.names),
        lab_truth=lab_truth,
        lab_measured=lab,
        delta_e00=de,
        readings=readings,
        snr_luminance_db=snr,
        snr_stage=snr_stage,
        truth_srgb=truth_srgb,
    )


def light_cct(spd: Spectrum) -> tuple[float, float]:
    """Correlated colour temperature (K) and Duv of a light from its spectrum.

    The light's chromaticity xy (CIE 1931 2°, :func:`imageform.spectral.spectrum_to_xyz`
    with ``illuminant=None``) and Robertson's method
    (:func:`imageform.color.xy_to_cct`; CIE 15:2004 eq. 3.3).

    Examples
    --------
    >>> from imageform.spectral import illuminant
    >>> cct, duv = light_cct(illuminant("A"))
    >>> round(cct), abs(duv) < 1e-3
    (2856, True)
    """
    check_type(spd, Spectrum, "spd")
    xy = np.asarray(xyz_to_xy(spectrum_to_xyz(spd, illuminant=None)))
    cct, duv = xy_to_cct(xy)
    return float(cct), float(duv)


def _finite_vp(camera: Camera, d_world: np.ndarray) -> np.ndarray:
    R = np.asarray(camera.R, dtype=np.float64)
    K = np.asarray(camera.image_plane_K, dtype=np.float64)
    dc = R @ d_world
    if camera.distortion is not None and dc[2] > 0:
        xy = np.asarray(camera.distortion.distort(dc[:2] / dc[2]))
        p = K @ np.array([xy[0], xy[1], 1.0])
        return p / p[2]
    p = K @ dc
    return p / p[2] if p[2] != 0 else p / np.linalg.norm(p)


def rails_truth(ground: SceneObject, camera: Camera) -> VanishingTruth:
    """Return the true vanishing point of the rails of ``ground`` and the horizon of its plane.

    The rails run along the object's ``-edge_down`` (towards its top edge). Under lens
    distortion the point is distorted like any image point; the horizon is the pinhole
    line (a distorted horizon is a curve): :func:`imageform.geometry.horizon_line` with the
    ground's normal as ``up`` (the world's up axis, z, for a level ground).
    """
    check_type(ground, SceneObject, "ground")
    check_type(camera, Camera, "camera")
    d = -ground.edge_down / np.linalg.norm(ground.edge_down)
    n = np.cross(ground.edge_right, ground.edge_down)
    n = -n / np.linalg.norm(n)  # right x down points into the ground; the normal is up
    hor = np.asarray(
        horizon_line(np.asarray(camera.image_plane_K, dtype=np.float64), np.asarray(camera.R), up=n)
    )
    return VanishingTruth(vanishing_point=_finite_vp(camera, d), horizon=hor)


def _line_angle(l1: np.ndarray, l2: np.ndarray) -> float:
    a1 = math.atan2(-l1[0], l1[1])
    a2 = math.atan2(-l2[0], l2[1])
    d = abs(a1 - a2) % math.pi
    return math.degrees(min(d, math.pi - d))


def vanishing_errors(v: VanishingTruth) -> dict[str, float | None]:
    """Return the vanishing point's error (pixels) and the horizon's angle error (degrees).

    ``vanishing_point_error_px``: the distance (pixels) between the detected and the true vanishing
    point (both finite; else ``None``); ``horizon_angle_error_deg``: the angle between the detected
    and the true horizon (``None`` without a detected horizon).

    Examples
    --------
    >>> vanishing_errors(VanishingTruth(np.array([3.0, 4.0, 1.0]), np.array([0.0, 1.0, -4.0]),
    ...                                 np.array([0.0, 0.0, 1.0]), np.array([0.0, 1.0, -2.0])))
    {'vanishing_point_error_px': 5.0, 'horizon_angle_error_deg': 0.0}
    """
    check_type(v, VanishingTruth, "v")
    out: dict[str, float | None] = {
        "vanishing_point_error_px": None,
        "horizon_angle_error_deg": None,
    }
    t = np.asarray(v.vanishing_point, dtype=np.float64)
    if v.detected_vanishing_point is not None:
        d = np.asarray(v.detected_vanishing_point, dtype=np.float64)
        if t[2] != 0 and d[2] != 0:
            out["vanishing_point_error_px"] = float(np.hypot(*(d[:2] / d[2] - t[:2] / t[2])))
    if v.detected_horizon is not None:
        out["horizon_angle_error_deg"] = _line_angle(
            np.asarray(v.detected_horizon, dtype=np.float64), np.asarray(v.horizon)
        )
    return out


def detect_vanishing(
    image: np.ndarray,
    truth: VanishingTruth,
    *,
    camera: Camera | None = None,
    rng: RNGLike = None,
    seed: int | None = None,
) -> tuple[VanishingTruth, dict[str, Any]]:
    """Run :func:`imageform.geometry.detect_vanishing_points` on ``image`` and compare.

    The detected point matched to the rails is the finite one nearest the truth. The
    detected horizon is the detector's own (from its K) when it found an orthogonal triplet;
    otherwise the line through the rails' point and the other detected point that makes the
    most level line (horizontal directions vanish on the horizon). Returns the filled truth
    and :func:`vanishing_errors` (``None`` where nothing was found).

    With ``camera`` (the camera that rendered ``image``) and its lens distortion, the image
    is first undistorted with that model (:func:`imageform.geometry.undistort_image`, the
    same K), as ``imageform vanishing --camera`` does: a distorted image's rails are curves,
    which no straight-line detector fits reliably (a calibrated webcam's k1 = -0.29 put the
    detection 2400-3800 px off for some noise draws; undistorted, 0.2-0.5 px). The segments
    are LSD's (:func:`imageform.geometry.detect_line_segments`' default). The point nearest
    the pinhole truth is mapped back through the distortion and compared with the distorted
    truth in the image's pixels (``vanishing_point_error_px``; errors through a lens are
    measured in the image, docs/design.md); where the model does not map it back one to one,
    the undistorted point is reported with its distance to the pinhole truth. The horizon is
    a pinhole line either way.

    ``rng`` seeds the detector's RANSAC (an int seed, a Generator to draw the seed from, or
    None); ``seed`` is its deprecated name.
    """
    from imageform.geometry import detect_line_segments, detect_vanishing_points, undistort_image

    source = random_source(rng, seed, "detect_vanishing")
    nothing = vanishing_errors(truth)
    # LSD (the detector's default) on the undistorted image: on the built-in scene 0.27 px
    # off the truth at 1280 x 720, 0.53 px at 320 x 180 (the "simple" detector: 0.67 and
    # 2.16 px; on the distorted image it was 1.45 and 4.27 px, LSD 27.7 px on the curved
    # rails). An image without lines gives no vanishing point (an empty set), never an error.
    arr = np.asarray(image)
    distortion = None if camera is None else camera.distortion
    K = None
    if camera is not None and distortion is not None:
        check_type(camera, Camera, "camera")
        K = np.asarray(camera.image_plane_K, dtype=np.float64)
        arr = np.asarray(undistort_image(arr, K, distortion, keep_dtype=True))
    res = detect_vanishing_points(
        segments=detect_line_segments(arr),
        image_size=(arr.shape[1], arr.shape[0]),
        rng=source.int_seed(),
    )
    vps = np.asarray(res.vanishing_points, dtype=np.float64)
    t = truth.vanishing_point / truth.vanishing_point[2]
    if K is not None and distortion is not None:
        t = _undistort_point(t, K, distortion)
        if t is None:  # the truth outside the model's invertible radius: nothing to compare
            return truth, nothing
    finite = [k for k in range(len(vps)) if vps[k, 2] != 0]
    if not finite:
        return truth, nothing
    pts = [vps[k] / vps[k, 2] for k in finite]
    dist = [float(np.hypot(*(p[:2] - t[:2]))) for p in pts]
    best = int(np.argmin(dist))
    vp = pts[best]
    horizon = None
    if res.horizon is not None:
        horizon = np.asarray(res.horizon, dtype=np.float64)
    else:
        others = [vps[k] for k in range(len(vps)) if k != finite[best]]
        lines = [np.cross(vp, o) for o in others]
        lines = [ln / math.hypot(ln[0], ln[1]) for ln in lines if math.hypot(ln[0], ln[1]) > 0]
        if lines:
            horizon = min(lines, key=lambda ln: abs(ln[0]))
    if horizon is not None and horizon[1] < 0:
        horizon = -horizon
    if K is None or distortion is None:
        filled = VanishingTruth(truth.vanishing_point, truth.horizon, vp, horizon)
        return filled, vanishing_errors(filled)
    shown = _distort_point(vp, K, distortion)
    filled = VanishingTruth(truth.vanishing_point, truth.horizon, shown, horizon)
    errors = vanishing_errors(filled)  # in the image's pixels, beside the distorted truth
    if shown is vp:  # not mapped back (beyond the model's one-to-one range): pinhole pixels
        errors["vanishing_point_error_px"] = dist[best]
    return filled, errors


def _undistort_point(p: np.ndarray, K: np.ndarray, distortion: Any) -> np.ndarray | None:
    """Return the pinhole pixel of the distorted pixel ``p``.

    ``None`` where the model's Newton inverse does not converge to an invertible point.
    """
    xy = np.linalg.solve(K, p)
    und = distortion.undistort(xy[:2] / xy[2])
    if not bool(np.all(und.valid)):
        return None
    q = K @ np.array([*np.asarray(und.xy, dtype=np.float64), 1.0])
    return q / q[2]


def _distort_point(p: np.ndarray, K: np.ndarray, distortion: Any) -> np.ndarray:
    """Return the distorted pixel of the pinhole pixel ``p``.

    Where the model does not map it back one to one (its inverse does not return ``p``),
    ``p`` itself.
    """
    xy = np.linalg.solve(K, p)
    d = np.asarray(distortion.distort(xy[:2] / xy[2]), dtype=np.float64)
    q = K @ np.array([d[0], d[1], 1.0])
    q = q / q[2]
    back = _undistort_point(q, K, distortion)
    if back is None or float(np.hypot(*(back[:2] - p[:2]))) > 1e-6 * (1.0 + np.hypot(*p[:2])):
        return p
    return q
