"""A tiny line renderer for tests: 3-D segments of a 'Manhattan' scene drawn through a camera."""

from __future__ import annotations

import numpy as np
from PIL import Image, ImageDraw

from imageform.geometry import project_points


def render_manhattan(
    K: np.ndarray,
    R: np.ndarray,
    t: np.ndarray,
    size: tuple[int, int] = (768, 512),
    n_per_axis: int = 40,
    seed: int = 0,
    supersample: int = 4,
) -> np.ndarray:
    """Grey image (H, W) in [0, 1] of segments parallel to the world axes, anti-aliased."""
    rng = np.random.default_rng(seed)
    w, h = size
    s = supersample
    canvas = Image.new("L", (w * s, h * s), 40)
    draw = ImageDraw.Draw(canvas)
    centre = -R.T @ t
    fwd = R.T @ np.array([0.0, 0.0, 1.0])
    for axis in range(3):
        for _ in range(n_per_axis):
            p0 = centre + fwd * rng.uniform(6, 20) + rng.uniform(-6, 6, size=3)
            d = np.zeros(3)
            d[axis] = rng.uniform(1.5, 4.0)
            X = np.stack([p0, p0 + d])
            uv, valid = project_points(X, K, R, t)
            if not valid.all():
                continue
            a, b = (uv + 0.5) * s - 0.5
            draw.line([tuple(a), tuple(b)], fill=230, width=2 * s)
    small = canvas.resize((w, h), Image.BOX)
    return np.asarray(small, dtype=np.float64) / 255.0


def render_seaside(
    size: tuple[int, int] = (768, 512),
    *,
    pitch_deg: float = -3.0,
    roll_deg: float = 2.0,
    f: float = 700.0,
    height: float = 1.5,
    seed: int = 0,
) -> tuple[np.ndarray, np.ndarray]:
    """Grey image (H, W) in [0, 1] of open sea under a sky, and its true horizon (a, b, c).

    A camera ``height`` above a wavy sea plane, pitched by ``pitch_deg`` (down < 0) and
    rolled by ``roll_deg``: the sky is a gradient brighter upwards; each pixel below the
    horizon sees the sea at depth ``Z = f height / y`` (``y`` its distance below the
    horizon), where a sum of wave trains (crests across the view, slightly turned) is drawn
    with a contrast fading with distance; the horizon edge is anti-aliased; 1 % noise. The
    horizon of a camera pitched by ``p`` is the row ``v = c_y + f tan(p)`` (a camera looking
    down, ``p < 0``, sees it above the centre), turned by the roll about the principal point.
    """
    rng = np.random.default_rng(seed)
    w, h = size
    vv, uu = np.mgrid[0:h, 0:w].astype(np.float64)
    cx, cy = (w - 1) / 2, (h - 1) / 2
    r = np.deg2rad(roll_deg)
    v0 = cy + f * np.tan(np.deg2rad(pitch_deg))  # the horizon's row at the centre
    x = (uu - cx) * np.cos(r) + (vv - v0) * np.sin(r)
    y = -(uu - cx) * np.sin(r) + (vv - v0) * np.cos(r)  # distance below the horizon
    sky = 0.6 + 0.3 * np.clip(-y / max(v0, 1.0), 0.0, 1.0)
    depth = f * height / np.maximum(y, 0.5)
    across = x * depth / f
    waves = np.zeros_like(y)
    for k, (kz, kx) in enumerate(((2.1, 0.05), (3.3, -0.08), (5.2, 0.12), (1.3, 0.02))):
        waves += np.sin(kz * depth + kx * across + rng.uniform(0, 2 * np.pi)) / (k + 1)
    sea = 0.3 + 0.05 * waves * np.exp(-depth / 60.0) + 0.08 * np.clip(y / h, 0.0, 1.0)
    a = np.clip(y + 0.5, 0.0, 1.0)  # share of each pixel below the horizon
    img = (1 - a) * sky + a * sea + rng.normal(0.0, 0.01, (h, w))
    line = np.array([-np.sin(r), np.cos(r), 0.0])
    line[2] = -(line[0] * cx + line[1] * v0)
    return np.clip(img, 0.0, 1.0), line
