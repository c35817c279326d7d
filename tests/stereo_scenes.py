"""A rectified stereo pair with known disparity, ray-cast with NumPy (tests and benchmark).

Two pinhole cameras, focal length ``f`` px, principal point at the image centre, the right
camera ``baseline`` mm to the right of the left (``X_right = X_left - (B, 0, 0)``: the pair
is rectified, ``d = f B / Z``). The scene: a slanted plane behind, a fronto-parallel plane
in front of part of it (a disparity step) and a sphere; every surface carries a 3-D value
noise texture of its world coordinates (three octaves), so both views see the same
texture. Each pixel averages ``ss x ss`` rays (antialiasing). The truth is the disparity of
the surface hit by the left pixel's centre ray, and ``visible`` says whether the right
camera sees that point (not occluded, inside its image).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


class StereoScene(NamedTuple):
    left: np.ndarray  # (H, W) float64 in [0, 1]
    right: np.ndarray
    disparity: np.ndarray  # (H, W) true disparity of the left pixels (px)
    depth: np.ndarray  # (H, W) true Z (mm)
    visible: np.ndarray  # (H, W) bool: the right camera sees the left pixel's point
    f: float
    baseline: float


def _noise3(p: np.ndarray, scale: float, seed: int) -> np.ndarray:
    """Trilinear value noise of points ``p`` (..., 3) on a lattice of ``scale`` mm."""
    q = p / scale
    i = np.floor(q).astype(np.int64)
    t = q - i
    t = t * t * (3 - 2 * t)
    out = np.zeros(p.shape[:-1])
    for dx in (0, 1):
        for dy in (0, 1):
            for dz in (0, 1):
                a, b, c = i[..., 0] + dx, i[..., 1] + dy, i[..., 2] + dz
                h = (a * 73856093) ^ (b * 19349663) ^ (c * 83492791) ^ (seed * 2654435761)
                h = (h * 2246822519 + 3266489917) & 0xFFFFFFFF
                v = ((h >> 8) & 0xFFFF) / 65535.0
                wx = t[..., 0] if dx else 1 - t[..., 0]
                wy = t[..., 1] if dy else 1 - t[..., 1]
                wz = t[..., 2] if dz else 1 - t[..., 2]
                out += v * wx * wy * wz
    return out


def _texture(p: np.ndarray, seed: int) -> np.ndarray:
    v = (
        0.5 * _noise3(p, 6.0, seed)
        + 0.3 * _noise3(p, 2.5, seed + 1)
        + 0.2 * _noise3(p, 15, seed + 2)
    )
    return np.clip(0.1 + 0.8 * v, 0.0, 1.0)


def _hit(o: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Point hit by rays from ``o`` (3,) along ``r`` (..., 3) (the nearest surface)."""
    t = np.full(r.shape[:-1], np.inf)
    # slanted plane: Z = 1100 + 0.25 X + 0.15 Y  ->  n . P = 1100 with n = (-0.25, -0.15, 1)
    n, c = np.array([-0.25, -0.15, 1.0]), 1100.0
    den = r @ n
    tp = (c - o @ n) / den
    t = np.where((den > 0) & (tp > 0), np.minimum(t, tp), t)
    # front plane Z = 700 over X in [-300, -60], Y in [-200, 150]
    tz = (700.0 - o[2]) / r[..., 2]
    P = o + tz[..., None] * r
    inside = (P[..., 0] > -300) & (P[..., 0] < -60) & (P[..., 1] > -200) & (P[..., 1] < 150)
    t = np.where(inside & (tz > 0), np.minimum(t, tz), t)
    # sphere: centre (150, 40, 850), radius 160
    cs, rad = np.array([150.0, 40.0, 850.0]), 160.0
    oc = o - cs
    a = np.sum(r * r, axis=-1)
    b = 2 * (r @ oc)
    disc = b * b - 4 * a * (oc @ oc - rad * rad)
    ts = (-b - np.sqrt(np.maximum(disc, 0))) / (2 * a)
    t = np.where((disc > 0) & (ts > 0), np.minimum(t, ts), t)
    return o + t[..., None] * r


def _rays(u: np.ndarray, v: np.ndarray, f: float, cx: float, cy: float) -> np.ndarray:
    return np.stack([(u - cx) / f, (v - cy) / f, np.ones_like(u)], axis=-1)


def render_view(
    K: np.ndarray, distortion: object, R: np.ndarray, t: np.ndarray, size: tuple[int, int],
    *, ss: int = 3, seed: int = 0,
) -> np.ndarray:  # fmt: skip
    """Render the scene by a camera ``X_cam = R X + t`` (K, a distortion model or None)."""
    w, h = size
    off = (np.arange(ss) + 0.5) / ss - 0.5
    o = -R.T @ t
    acc = np.zeros((h, w))
    v0, u0 = np.mgrid[0:h, 0:w].astype(np.float64)
    for sy in off:
        for sx in off:
            y = (v0 + sy - K[1, 2]) / K[1, 1]
            x = (u0 + sx - K[0, 2] - K[0, 1] * y) / K[0, 0]
            xy = np.stack([x, y], axis=-1)
            if distortion is not None:
                xy = np.asarray(distortion.undistort(xy).xy)  # type: ignore[attr-defined]
            d = np.concatenate([xy, np.ones((h, w, 1))], axis=-1) @ R  # R.T @ d per pixel
            acc += _texture(_hit(o, d), seed)
    return acc / ss**2


def hit_points(o: np.ndarray, rays: np.ndarray) -> np.ndarray:
    """The scene's points hit by rays from ``o`` along ``rays`` (..., 3) (left camera frame)."""
    return _hit(np.asarray(o, dtype=np.float64), rays)


def render_pair(
    width: int = 320, height: int = 240, *, f: float = 400.0, baseline: float = 60.0,
    ss: int = 3, seed: int = 0,
) -> StereoScene:  # fmt: skip
    """Render the scene in both cameras (see the module's documentation)."""
    cx, cy = (width - 1) / 2.0, (height - 1) / 2.0
    off = (np.arange(ss) + 0.5) / ss - 0.5
    views = []
    for ox in (0.0, baseline):
        o = np.array([ox, 0.0, 0.0])
        acc = np.zeros((height, width))
        for sy in off:
            for sx in off:
                v, u = np.mgrid[0:height, 0:width].astype(np.float64)
                P = _hit(o, _rays(u + sx, v + sy, f, cx, cy))
                acc += _texture(P, seed)
        views.append(acc / ss**2)
    v, u = np.mgrid[0:height, 0:width].astype(np.float64)
    P = _hit(np.zeros(3), _rays(u, v, f, cx, cy))
    Z = P[..., 2]
    disp = f * baseline / Z
    # the right camera sees P when its own ray through P's pixel hits P first
    ur = u - disp
    Pr = _hit(np.array([baseline, 0.0, 0.0]), _rays(ur, v, f, cx, cy))
    visible = (np.abs(Pr[..., 2] - Z) < 1e-3 * Z) & (ur >= 0) & (ur <= width - 1)
    return StereoScene(views[0], views[1], disp, Z, visible, f, baseline)
