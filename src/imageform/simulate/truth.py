"""Ground truth of a scene and measurements on the simulated images.

- ColorChecker: CIELAB under D65 from the reflectances (CIE 015:2018 eqs. 7.1-7.3 via
  :func:`imageform.spectral.spectrum_to_xyz`, then :func:`imageform.color.xyz_to_lab`), the
  patch centres projected through the camera, and the patch means of an image.
- Rails: the true vanishing point :math:`v \\sim K R d` of the rail direction d (distorted
  like every image point when the camera has a distortion model) and the horizon, the
  vanishing line :math:`l \\sim K^{-T} R n` of the ground plane of normal n (Hartley &
  Zisserman, 2nd ed., §8.6.1-8.6.2).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from imageform.color import delta_e_ciede2000, linear_srgb_to_xyz, xyz_to_lab, xyz_to_xy
from imageform.geometry.camera import Camera
from imageform.geometry.vanishing import horizon_line
from imageform.simulate.result import ColorCheckerTruth, VanishingTruth
from imageform.simulate.scene import SceneObject
from imageform.spectral import COLORCHECKER_PATCHES, colorchecker_reflectances, spectrum_to_xyz

__all__ = [
    "colorchecker_truth",
    "detect_vanishing",
    "patch_means",
    "patch_stats",
    "rails_truth",
    "xy_of_linear_srgb",
]


def colorchecker_truth(obj: SceneObject, camera: Camera) -> ColorCheckerTruth:
    """Ground-truth Lab (D65) and image positions of the 24 patches of ``obj``.

    The sampling radius is a third of the smallest projected half-patch (so that windows stay
    inside the patches in perspective).
    """
    xyz = spectrum_to_xyz(colorchecker_reflectances(), "D65")
    lab = np.asarray(xyz_to_lab(xyz, white="D65"))
    i, j = np.meshgrid(np.arange(6), np.arange(4))
    a = (i.ravel() + 0.5) / 6.0
    b = (j.ravel() + 0.5) / 4.0
    centres = obj.origin + a[:, None] * obj.edge_right + b[:, None] * obj.edge_down
    uv = np.asarray(camera.project(centres).uv)
    half = (1.0 - obj.params["gap_fraction"]) / 2
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


def _windows(truth: ColorCheckerTruth, h: int, w: int) -> list[tuple[slice, slice] | None]:
    r = truth.sample_radius_px
    out: list[tuple[slice, slice] | None] = []
    for u, v in np.asarray(truth.centres_uv):
        if not (np.isfinite(u) and np.isfinite(v)):
            out.append(None)
            continue
        r0, r1 = max(math.ceil(v - r), 0), min(math.floor(v + r) + 1, h)
        c0, c1 = max(math.ceil(u - r), 0), min(math.floor(u + r) + 1, w)
        out.append((slice(r0, r1), slice(c0, c1)) if r0 < r1 and c0 < c1 else None)
    return out


def patch_means(image: np.ndarray, truth: ColorCheckerTruth) -> np.ndarray:
    """Mean ``(24, C)`` of each patch window (pixels whose centres are within
    ``sample_radius_px`` of the patch centre along both axes); NaN outside the image.

    >>> t = ColorCheckerTruth(("a",), np.zeros((1, 3)), np.array([[1.0, 1.0]]), 1.0)
    >>> patch_means(np.arange(27.0).reshape(3, 3, 3), t).tolist()
    [[12.0, 13.0, 14.0]]
    """
    return patch_stats(image, truth)[0]


def patch_stats(image: np.ndarray, truth: ColorCheckerTruth) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard deviation ``(24, C)`` of each patch window."""
    img = np.asarray(image, dtype=np.float64)
    if img.ndim == 2:
        img = img[..., None]
    h, w, c = img.shape
    mean = np.full((len(truth.names), c), np.nan)
    std = np.full((len(truth.names), c), np.nan)
    for k, win in enumerate(_windows(truth, h, w)):
        if win is None:
            continue
        block = img[win].reshape(-1, c)
        mean[k] = block.mean(axis=0)
        std[k] = block.std(axis=0)
    return mean, std


def xy_of_linear_srgb(rgb: np.ndarray) -> np.ndarray:
    """Chromaticity xy ``(..., 2)`` of linear-sRGB colours (CIE 015:2018 eq. 7.4).

    >>> xy_of_linear_srgb(np.array([1.0, 1.0, 1.0])).round(4).tolist()
    [0.3127, 0.329]
    """
    arr = np.asarray(rgb, dtype=np.float64)
    out = np.full((*arr.shape[:-1], 2), np.nan)
    ok = np.all(np.isfinite(arr), axis=-1)
    out[ok] = np.asarray(xyz_to_xy(linear_srgb_to_xyz(arr[ok])))
    return out


def delta_e_patches(linear_srgb: np.ndarray, lab_truth: np.ndarray) -> np.ndarray:
    """CIEDE2000 of linear-sRGB patch colours ``(24, 3)`` against ``lab_truth`` (D65)."""
    rgb = np.asarray(linear_srgb, dtype=np.float64)
    out = np.full(rgb.shape[0], np.nan)
    ok = np.all(np.isfinite(rgb), axis=-1)
    lab = np.asarray(xyz_to_lab(linear_srgb_to_xyz(rgb[ok]), white="D65"))
    out[ok] = np.asarray(delta_e_ciede2000(lab, np.asarray(lab_truth)[ok]))
    return out


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
    """True vanishing point of the rails of ``ground`` and the horizon of its plane.

    The rails run along the object's ``-edge_down`` (towards its top edge). Under lens
    distortion the point is distorted like any image point; the horizon is the pinhole
    line (a distorted horizon is a curve).
    """
    d = -ground.edge_down / np.linalg.norm(ground.edge_down)
    n = np.cross(ground.edge_right, ground.edge_down)
    n = -n / np.linalg.norm(n)  # right x down points into the ground; the normal is up
    K = np.asarray(camera.image_plane_K, dtype=np.float64)
    hor = np.asarray(horizon_line(K, np.asarray(camera.R), n))
    return VanishingTruth(vanishing_point=_finite_vp(camera, d), horizon=hor)


def _line_angle(l1: np.ndarray, l2: np.ndarray) -> float:
    a1 = math.atan2(-l1[0], l1[1])
    a2 = math.atan2(-l2[0], l2[1])
    d = abs(a1 - a2) % math.pi
    return math.degrees(min(d, math.pi - d))


def detect_vanishing(
    image: np.ndarray, truth: VanishingTruth, seed: int = 0
) -> tuple[VanishingTruth, dict[str, Any]]:
    """Run :func:`imageform.geometry.detect_vanishing_points` on ``image`` and compare.

    The detected point matched to the rails is the finite one nearest the truth. The
    detected horizon is the detector's own (from its K) when it found an orthogonal triplet;
    otherwise the line through the rails' point and the other detected point that makes the
    most level line (horizontal directions vanish on the horizon). Returns the filled truth
    and ``{"vanishing_point_error_px", "horizon_angle_error_deg"}`` (None when not found).
    """
    from imageform.errors import DegenerateConfigurationError
    from imageform.geometry import detect_vanishing_points

    err: dict[str, Any] = {"vanishing_point_error_px": None, "horizon_angle_error_deg": None}
    try:
        res = detect_vanishing_points(np.asarray(image), seed=seed)
    except DegenerateConfigurationError:
        return truth, err
    vps = np.asarray(res.vanishing_points, dtype=np.float64)
    t = truth.vanishing_point / truth.vanishing_point[2]
    finite = [k for k in range(len(vps)) if vps[k, 2] != 0]
    if not finite:
        return truth, err
    pts = [vps[k] / vps[k, 2] for k in finite]
    dist = [float(np.hypot(*(p[:2] - t[:2]))) for p in pts]
    best = int(np.argmin(dist))
    vp = pts[best]
    err["vanishing_point_error_px"] = dist[best]
    horizon = None
    if res.horizon is not None:
        horizon = np.asarray(res.horizon, dtype=np.float64)
    else:
        others = [vps[k] for k in range(len(vps)) if k != finite[best]]
        lines = [np.cross(vp, o) for o in others]
        lines = [ln / math.hypot(ln[0], ln[1]) for ln in lines if math.hypot(ln[0], ln[1]) > 0]
        if lines:
            horizon = min(lines, key=lambda ln: abs(ln[0]))
    if horizon is not None:
        if horizon[1] < 0:
            horizon = -horizon
        err["horizon_angle_error_deg"] = _line_angle(horizon, truth.horizon)
    filled = VanishingTruth(truth.vanishing_point, truth.horizon, vp, horizon)
    return filled, err
