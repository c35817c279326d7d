"""Overlays drawn on images (PIL): line segments coloured by vanishing point, the horizon."""

from __future__ import annotations

from typing import Any

import numpy as np

from imageform._typing import ArrayLike

__all__ = ["draw_vanishing_overlay"]

#: Okabe-Ito colours for VP groups (colour-blind safe); grey for unassigned segments.
_COLOURS = [(230, 159, 0), (86, 180, 233), (0, 158, 115), (204, 121, 167), (213, 94, 0)]
_GREY = (150, 150, 150)


def draw_vanishing_overlay(image: ArrayLike, result: Any) -> Any:
    """An RGB PIL image: segments coloured by vanishing point, VPs inside the view marked,
    the horizon in white over black. ``result`` is a
    :class:`~imageform.geometry.VanishingPointResult`."""
    from PIL import Image, ImageDraw

    arr = np.asarray(image)
    if arr.dtype != np.uint8:
        arr = np.clip(np.asarray(arr, dtype=np.float64) * 255.0 + 0.5, 0, 255).astype(np.uint8)
    if arr.ndim == 2:
        arr = np.repeat(arr[..., None], 3, axis=-1)
    base = Image.fromarray(arr, "RGB")
    # dim the photo so the drawing stands out
    canvas = Image.blend(base, Image.new("RGB", base.size, (0, 0, 0)), 0.35)
    draw = ImageDraw.Draw(canvas)
    seg = result.segments
    for (a, b), lab in zip(seg.endpoints, result.labels, strict=True):
        colour = _COLOURS[lab % len(_COLOURS)] if lab >= 0 else _GREY
        draw.line([tuple(a + 0.5), tuple(b + 0.5)], fill=colour, width=2)
    w, h = canvas.size
    for j, v in enumerate(result.vanishing_points):
        if v[2] != 0 and -0.5 <= v[0] < w - 0.5 and -0.5 <= v[1] < h - 0.5:
            x, y = v[0] + 0.5, v[1] + 0.5
            c = _COLOURS[j % len(_COLOURS)]
            draw.ellipse([x - 7, y - 7, x + 7, y + 7], outline=c, width=3)
    if result.horizon is not None:
        a, b, c = result.horizon
        if abs(b) > 1e-9:
            ys = [-(a * u + c) / b for u in (0.0, w - 1.0)]
            pts = [(0.5, ys[0] + 0.5), (w - 0.5, ys[1] + 0.5)]
            draw.line(pts, fill=(0, 0, 0), width=5)
            draw.line(pts, fill=(255, 255, 255), width=2)
    return canvas
