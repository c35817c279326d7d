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
