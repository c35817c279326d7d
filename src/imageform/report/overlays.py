"""Overlays drawn on images (PIL): line segments coloured by vanishing point, the horizon."""

from __future__ import annotations

import functools
import math
from typing import TYPE_CHECKING, Any

import numpy as np

from imageform._typing import ArrayLike
from imageform._validate import as_real, as_real_array, check_memory, describe, format_shape
from imageform.errors import InvalidInputError

if TYPE_CHECKING:
    import PIL.Image

    from imageform.geometry.distortion import DistortionModel
    from imageform.geometry.tracking import BoardPose
    from imageform.geometry.vp_detection import VanishingPointResult
    from imageform.io.plan import Plan

__all__ = [
    "DETECTED_COLOUR",
    "TRUE_COLOUR",
    "draw_pose_overlay",
    "draw_vanishing_overlay",
    "draw_vanishing_truth_overlay",
]

#: Okabe-Ito colours for VP groups (colour-blind safe); grey for unassigned segments.
_COLOURS = [(230, 159, 0), (86, 180, 233), (0, 158, 115), (204, 121, 167), (213, 94, 0)]
_GREY = (150, 150, 150)
#: Colours of the true (bluish green) and detected (vermillion) vanishing point and horizon.
TRUE_COLOUR = (0, 158, 115)
DETECTED_COLOUR = (213, 94, 0)


#: The widest margin :func:`draw_vanishing_truth_overlay` adds, in image sizes per side.
MAX_MARGIN = 2.0


def _to_rgb8(image: ArrayLike, name: str = "image") -> np.ndarray:
    """Return ``image`` (H, W) or (H, W, 3), uint8 or floats in [0, 1], as uint8 RGB.

    Anything else is refused naming ``name``.
    """
    if image is None or isinstance(image, str | bytes):
        raise InvalidInputError(f"expected {name} as an (H, W, 3) array, got {describe(image)}")
    if type(image).__module__.startswith("torch"):
        image = image.detach().cpu().numpy()  # type: ignore[union-attr]
    arr = np.asarray(image)
    if arr.dtype.kind not in "uif":
        raise InvalidInputError(f"expected {name} as numbers, got {describe(image)}")
    if arr.ndim not in (2, 3) or (arr.ndim == 3 and arr.shape[-1] != 3) or arr.size == 0:
        raise InvalidInputError(
            f"expected {name} of shape (H, W) or (H, W, 3), non-empty, got "
            f"{format_shape(arr.shape)}"
        )
    if arr.dtype != np.uint8:
        if not np.isfinite(arr).all():
            raise InvalidInputError(f"{name} contains NaN or inf")
        arr = np.clip(np.asarray(arr, dtype=np.float64) * 255.0 + 0.5, 0, 255).astype(np.uint8)
    if arr.ndim == 2:
        arr = np.repeat(arr[..., None], 3, axis=-1)
    return arr


def _homogeneous(p: object, name: str, sizes: tuple[int, ...]) -> np.ndarray | None:
    """Return a point or line in homogeneous pixel coordinates as float64 (``None`` stays ``None``).

    Non-finite values are allowed (such a point or line is not drawn).
    """
    if p is None:
        return None
    v = as_real_array(p, name, finite=False, ndim=(1, 2)).ravel()
    if v.size not in sizes:
        want = " or ".join(str(n) for n in sizes)
        raise InvalidInputError(f"expected {name} as {want} numbers, got {describe(p)}")
    return v


def _line_in_box(line: ArrayLike, w: float, h: float) -> list[tuple[float, float]] | None:
    """Return the two PIL points where the line ``a u + b v + c = 0`` crosses the canvas' edges.

    PIL points have the pixel centre at +0.5; the left and right edges are used (top and bottom
    edges for a steep line).
    """
    a, b, c = (float(x) for x in np.asarray(line, dtype=np.float64))
    if not (math.isfinite(a) and math.isfinite(b) and math.isfinite(c)):
        return None
    if abs(b) >= abs(a) and abs(b) > 1e-12:
        us = (-0.5, w - 0.5)
        return [(u + 0.5, -(a * u + c) / b + 0.5) for u in us]
    if abs(a) > 1e-12:
        vs = (-0.5, h - 0.5)
        return [(-(b * v + c) / a + 0.5, v + 0.5) for v in vs]
    return None


def _draw_line(
    draw: Any, line: ArrayLike, w: float, h: float, colour: tuple[int, int, int], k: int = 1
) -> None:
    """Draw the line, ``2k`` px wide in ``colour`` over ``5k`` px of black."""
    pts = _line_in_box(line, w, h)
    if pts is not None:
        draw.line(pts, fill=(0, 0, 0), width=5 * k)
        draw.line(pts, fill=colour, width=2 * k)


def draw_vanishing_overlay(image: ArrayLike, result: VanishingPointResult) -> PIL.Image.Image:
    """Draw the segments coloured by vanishing point and the horizon, as an RGB PIL image.

    VPs inside the view are marked, the horizon is white over black. ``result`` is a
    :class:`~imageform.geometry.VanishingPointResult`.
    """
    from PIL import Image, ImageDraw

    base = Image.fromarray(_to_rgb8(image), "RGB")
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
        _draw_line(draw, result.horizon, w, h, (255, 255, 255))
    return canvas


def draw_vanishing_truth_overlay(
    image: ArrayLike,
    vanishing_point: ArrayLike,
    horizon: ArrayLike | None = None,
    *,
    detected_vanishing_point: ArrayLike | None = None,
    detected_horizon: ArrayLike | None = None,
    max_margin: float = 0.5,
) -> PIL.Image.Image:
    """Draw the true and the detected vanishing point and horizon on ``image`` (RGB PIL image).

    The true vanishing point is a bluish-green ring and cross, the true horizon bluish-green over
    black, and the detected ones vermillion.

    Points and lines are homogeneous pixel coordinates (``(u, v, w)``; ``a u + b v + c = 0``),
    pixel centre of the top-left pixel at (0, 0). A vanishing point outside the image gets a
    grey margin around the image so that it shows, up to ``max_margin`` times the image size
    on each side (farther ones, and points at infinity, are not drawn); the image's top-left
    pixel then sits at ``canvas.info["offset"]`` ``(ox, oy)`` (``(0, 0)`` without margin).

    Examples
    --------
    >>> im = draw_vanishing_truth_overlay(np.zeros((40, 60, 3)), [30.0, 20.0, 1.0], [0, 1, -20])
    >>> im.getpixel((30, 20)) == TRUE_COLOUR, im.info["offset"]
    (True, (0, 0))
    """
    from PIL import Image, ImageDraw

    arr = _to_rgb8(image)
    h, w = arr.shape[:2]
    max_margin = as_real(max_margin, "max_margin", minimum=0.0, maximum=MAX_MARGIN)
    vps = {
        "vanishing_point": _homogeneous(vanishing_point, "vanishing_point", (2, 3)),
        "detected_vanishing_point": _homogeneous(
            detected_vanishing_point, "detected_vanishing_point", (2, 3)
        ),
    }
    lines = {
        "horizon": _homogeneous(horizon, "horizon", (3,)),
        "detected_horizon": _homogeneous(detected_horizon, "detected_horizon", (3,)),
    }
    k = max(1, round(max(w, h) / 640))  # marks grow with the image (1 up to 960 px wide)
    pts: list[tuple[np.ndarray, tuple[int, int, int]]] = []
    for v, colour in (
        (vps["vanishing_point"], TRUE_COLOUR),
        (vps["detected_vanishing_point"], DETECTED_COLOUR),
    ):
        if v is None:
            continue
        if v.size == 2:
            v = np.append(v, 1.0)
        if v[2] != 0 and np.all(np.isfinite(v)):
            uv = v[:2] / v[2]
            if (
                -max_margin * w - 0.5 <= uv[0] < (1 + max_margin) * w - 0.5
                and -max_margin * h - 0.5 <= uv[1] < (1 + max_margin) * h - 0.5
            ):
                pts.append((uv, colour))
    pad = 12 * k
    lo = np.minimum(np.min([uv for uv, _ in pts], axis=0) - pad, 0) if pts else np.zeros(2)
    hi = np.maximum(np.max([uv for uv, _ in pts], axis=0) + pad, [w - 1, h - 1]) if pts else None
    ox, oy = int(np.ceil(-lo[0])), int(np.ceil(-lo[1]))
    cw = w + ox + (int(np.ceil(hi[0] - (w - 1))) if hi is not None else 0)
    ch = h + oy + (int(np.ceil(hi[1] - (h - 1))) if hi is not None else 0)
    check_memory(3.0 * cw * ch, "max_margin", f"a {cw}x{ch} overlay canvas")
    base = Image.fromarray(arr, "RGB")
    canvas = Image.new("RGB", (cw, ch), (128, 128, 128))
    canvas.paste(Image.blend(base, Image.new("RGB", base.size, (0, 0, 0)), 0.25), (ox, oy))
    draw = ImageDraw.Draw(canvas)
    for line, colour in (
        (lines["detected_horizon"], DETECTED_COLOUR),
        (lines["horizon"], TRUE_COLOUR),
    ):
        if line is not None:
            a, b, c = line
            _draw_line(draw, (a, b, c - a * ox - b * oy), cw, ch, colour, k)
    for uv, colour in reversed(pts):
        x, y = uv[0] + ox + 0.5, uv[1] + oy + 0.5
        r0, r1, c0 = 9 * k, 8 * k, 4 * k
        draw.ellipse([x - r0, y - r0, x + r0, y + r0], outline=(0, 0, 0), width=5 * k)
        draw.ellipse([x - r1, y - r1, x + r1, y + r1], outline=colour, width=3 * k)
        if colour == TRUE_COLOUR:
            draw.line([(x - c0, y), (x + c0, y)], fill=colour, width=2 * k)
            draw.line([(x, y - c0), (x, y + c0)], fill=colour, width=2 * k)
    canvas.info["offset"] = (ox, oy)
    return canvas


#: Colours of the board axes (x, y, z: vermillion, bluish green, blue) and of the plan
#: (yellow) and the detected corners (sky blue), Okabe-Ito.
_AXES = ((213, 94, 0), (0, 158, 115), (0, 114, 178))
_PLAN = (240, 228, 66)
_CORNER = (86, 180, 233)


#: Drawn coordinates farther than this from the image are dropped (PIL's integer range).
_FAR_PX = 1e6


def _segments_uv(
    groups: list[tuple[np.ndarray, np.ndarray, int]], camera: Any
) -> list[list[list[tuple[float, float]]]]:
    """Return, per group ``(a, b, pieces)``, the polylines (PIL points) of segments ``a -> b``.

    ``a`` and ``b`` are ``(n, 3)`` points; each segment is cut into ``pieces`` so that lens
    distortion bends it as the lens does. All groups are projected in one call of
    :meth:`~imageform.geometry.Camera.project` (the full camera model); a piece with an end
    at or behind the camera (or projected to NaN) is not drawn.
    """
    chunks = []
    for a, b, pieces in groups:
        s = np.linspace(0.0, 1.0, pieces + 1)
        chunks.append((a[:, None, :] + (b - a)[:, None, :] * s[None, :, None]).reshape(-1, 3))
    flat = np.concatenate(chunks) if chunks else np.zeros((0, 3))
    if flat.shape[0] == 0:
        return [[] for _ in groups]
    uv_all, ok_all = camera.project(flat)
    uv_all = np.asarray(uv_all, np.float64) + 0.5
    ok_all = np.asarray(ok_all, bool) & np.all(
        np.isfinite(uv_all) & (np.abs(uv_all) < _FAR_PX), axis=-1
    )
    out: list[list[list[tuple[float, float]]]] = []
    start = 0
    for a, _, pieces in groups:
        n = a.shape[0] * (pieces + 1)
        uv = uv_all[start : start + n].reshape(a.shape[0], pieces + 1, 2)
        ok = ok_all[start : start + n].reshape(a.shape[0], pieces + 1)
        start += n
        lines: list[list[tuple[float, float]]] = []
        for seg, good, whole in zip(uv.tolist(), ok, ok.all(axis=1), strict=True):
            if whole:  # the usual case: the whole segment in front of the camera
                lines.append([(p[0], p[1]) for p in seg])
                continue
            run: list[tuple[float, float]] = []
            for p, g in zip(seg, good, strict=True):
                if g:
                    run.append((p[0], p[1]))
                else:
                    if len(run) > 1:
                        lines.append(run)
                    run = []
            if len(run) > 1:
                lines.append(run)
        out.append(lines)
    return out


@functools.lru_cache(maxsize=1)
def _label_font() -> Any:
    """PIL's default font, loaded once (loading it costs more than drawing a label)."""
    from PIL import ImageFont

    return ImageFont.load_default()


def _draw_in_place(
    out: np.ndarray, shapes: list[tuple[str, Any, tuple[int, int, int], int]]
) -> None:
    """Draw ``shapes`` on ``out`` (uint8 RGB, changed in place) through a PIL crop.

    Only the box around the shapes goes through PIL (a frame's conversions cost more than
    the drawing); shifting the coordinates by whole pixels leaves the rasterisation as it
    would be on the whole frame. Shapes: ``("line", points, colour, width)``, ``("ellipse",
    box, ...)``, ``("rectangle", box, ...)`` (filled) and ``("text", (x, y, text), ...)``.
    """
    from PIL import Image, ImageDraw

    if not shapes:
        return
    h, w = out.shape[:2]
    lo, hi = np.array([np.inf, np.inf]), np.array([-np.inf, -np.inf])
    for kind, geom, _, width in shapes:
        if kind == "text":  # a bound, not measured: PIL's default font is under 10 x 14 px
            x, y, text = geom
            xy = np.array([[x, y], [x + 10 * len(text), y + 14]], np.float64)
        else:
            xy = np.asarray(geom, np.float64).reshape(-1, 2)
        lo = np.minimum(lo, xy.min(axis=0) - width - 2)
        hi = np.maximum(hi, xy.max(axis=0) + width + 2)
    x0, y0 = max(0, math.floor(lo[0])), max(0, math.floor(lo[1]))
    x1, y1 = min(w, math.ceil(hi[0]) + 1), min(h, math.ceil(hi[1]) + 1)
    if x1 <= x0 or y1 <= y0:
        return  # everything falls outside the frame
    crop = Image.fromarray(out[y0:y1, x0:x1], "RGB")
    draw = ImageDraw.Draw(crop)
    for kind, geom, colour, width in shapes:
        if kind == "line":
            draw.line([(u - x0, v - y0) for u, v in geom], fill=colour, width=width)
        elif kind == "ellipse":
            u0, v0, u1, v1 = geom
            draw.ellipse([u0 - x0, v0 - y0, u1 - x0, v1 - y0], outline=colour, width=width)
        elif kind == "rectangle":
            u0, v0, u1, v1 = geom
            draw.rectangle([u0 - x0, v0 - y0, u1 - x0, v1 - y0], fill=colour)
        else:
            x, y, text = geom
            draw.text((x - x0, y - y0), text, fill=colour, font=_label_font())
    out[y0:y1, x0:x1] = np.asarray(crop)


def draw_pose_overlay(
    image: ArrayLike,
    pose: BoardPose,
    K: ArrayLike,
    distortion: DistortionModel | None = None,
    *,
    plan: Plan | None = None,
    axis_length: float | None = None,
    label: str | None = None,
) -> np.ndarray:
    r"""Draw a tracked board's axes, its corners and a plan on a frame; return uint8 RGB.

    Everything is projected through the full camera model, :math:`x = K\, d(\pi(R X + t))`
    with :math:`\pi` the division by depth and ``d`` the lens distortion
    (:meth:`imageform.geometry.Camera.project`; Hartley & Zisserman eq. 6.11, Brown 1966 for
    ``d``); segments are cut into pieces so that distortion bends them, and a piece at or
    behind the camera is never drawn. A frame whose pose was not found gets only the label.
    ``image`` is not changed.

    Parameters
    ----------
    image : array_like (H, W, 3) or (H, W)
        The frame (uint8, or floats in [0, 1]).
    pose : BoardPose
        From :meth:`imageform.geometry.BoardTracker.update`.
    K : array_like (3, 3)
        The camera's intrinsics.
    distortion : distortion model, optional
        The camera's lens distortion.
    plan : Plan, optional
        Points, polylines and edges in the board's frame (:func:`imageform.io.read_plan`).
    axis_length : float, optional
        Length of the drawn axes in the board's unit (default: 3 squares' worth, the span of
        the corners over 3).
    label : str, optional
        Text drawn at the top left (the frame number, the reprojection error ...).

    Returns
    -------
    ndarray (H, W, 3) uint8
        A new array: the frame with the drawing.
    """
    from imageform.geometry.camera import Camera

    arr = _to_rgb8(image)
    out = arr.copy() if np.may_share_memory(arr, np.asarray(image)) else arr  # never draw on it
    shapes: list[tuple[str, Any, tuple[int, int, int], int]] = []
    if pose.found:
        R, t = np.asarray(pose.R, np.float64), np.asarray(pose.tvec, np.float64)
        camera = Camera(np.asarray(K, np.float64), R, t, distortion=distortion)
        if axis_length is None:
            span = np.ptp(np.asarray(pose.object_points, np.float64), axis=0)
            axis_length = float(max(span.max(), 1e-9)) / 3
        origin, tips = np.zeros((1, 3)), np.eye(3) * axis_length
        # x, y on the board, z = x cross y (into it): one group each
        groups = [(origin, tips[i : i + 1], 8) for i in range(3)]
        single = np.zeros((0, 3))
        if plan is not None:
            pts = np.asarray(plan.points, np.float64)
            a_idx = [np.asarray(plan.edges[:, 0], np.int64)]
            b_idx = [np.asarray(plan.edges[:, 1], np.int64)]
            for line in plan.polylines:
                a_idx.append(line[:-1])
                b_idx.append(line[1:])
            ia, ib = np.concatenate(a_idx), np.concatenate(b_idx)
            single = pts[plan.singles]
            groups += [(pts[ia], pts[ib], 8), (single, single, 1)]
        runs = _segments_uv(groups, camera)
        if plan is not None:
            shapes += [("line", run, _PLAN, 3) for run in runs[3]]
            for run in runs[4]:
                x, y = run[0]
                shapes.append(("ellipse", (x - 5, y - 5, x + 5, y + 5), _PLAN, 3))
        for u, v in (np.asarray(pose.image_points, np.float64) + 0.5).tolist():
            shapes.append(("ellipse", (u - 3, v - 3, u + 3, v + 3), _CORNER, 2))
        for lines, colour in zip(runs[:3], _AXES, strict=True):
            shapes += [("line", ln, colour, 4) for ln in lines]
    _draw_in_place(out, shapes)
    if label:  # a box of its own: the board's drawing rarely reaches the top left corner
        box = ("rectangle", (0, 0, 8 + 7 * len(label), 20), (0, 0, 0), 0)
        _draw_in_place(out, [box, ("text", (4, 4, label), (255, 255, 255), 0)])
    return out
