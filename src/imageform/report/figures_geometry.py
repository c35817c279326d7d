r"""The simulation report's geometry figures.

The scene and the camera frustum seen from above, and the vanishing point and horizon drawn on the
output image.

The top view looks down the world's up axis (``SimulationResult.world_up``; the simulator's
world is z up) and is turned so that the camera looks up the page: a world point X is drawn
at

.. math:: (x, y) = \big((X - C) \cdot \hat r,\ (X - C) \cdot \hat f\big),\quad
    \hat f = \frac{a - (a \cdot \hat u)\hat u}{\lVert \cdot \rVert},\quad
    \hat r = \hat f \times \hat u

with C the camera centre, û the world's up, a the optical axis (the third row of R; the
image's up direction, the negated second row, when the camera looks straight down). An
object left of the camera is drawn left, a nearer one lower (:func:`top_view_project`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from imageform._typing import ArrayLike
from imageform._validate import (
    as_int,
    as_real_array,
    check_real_values,
    describe,
    format_shape,
)
from imageform.errors import InvalidInputError
from imageform.report._checks import check_result
from imageform.simulate.result import SimulationResult
from imageform.simulate.truth import vanishing_errors

if TYPE_CHECKING:
    import PIL.Image
    from matplotlib.figure import Figure

__all__ = [
    "image_corner_pixels",
    "plot_top_view",
    "top_view_axes",
    "top_view_data",
    "top_view_project",
    "vanishing_overlay",
    "vanishing_summary",
]


def image_corner_pixels(width: int, height: int) -> np.ndarray:
    """Return the outer corners ``(4, 2)`` of the image, clockwise from the top left.

    Corners at the pixel edges, with the centre of the top-left pixel at (0, 0).

    Examples
    --------
    >>> image_corner_pixels(4, 3).tolist()
    [[-0.5, -0.5], [3.5, -0.5], [3.5, 2.5], [-0.5, 2.5]]
    """
    w = float(as_int(width, "width", minimum=1))
    h = float(as_int(height, "height", minimum=1))
    return np.array([[-0.5, -0.5], [w - 0.5, -0.5], [w - 0.5, h - 0.5], [-0.5, h - 0.5]])


def top_view_axes(R: ArrayLike, world_up: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Return the unit vectors ``(right, ahead)`` of the top view in world coordinates.

    ``ahead`` is the camera's optical axis (or, looking straight down, its image-up direction)
    flattened onto the ground plane perpendicular to ``world_up``; ``right = ahead x up``.

    Examples
    --------
    >>> R = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])  # z-up world, looking along +y
    >>> [v.tolist() for v in top_view_axes(R, (0, 0, 1))]
    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    """
    Rm = as_real_array(R, "R", ndim=2, check=False)
    if Rm.shape != (3, 3):
        raise InvalidInputError(f"expected R of shape (3, 3), got {format_shape(Rm.shape)}")
    check_real_values(Rm, "R")
    up = as_real_array(world_up, "world_up", ndim=1, check=False)
    n = float(np.linalg.norm(up)) if up.shape == (3,) else 0.0
    if not np.isfinite(n) or n == 0:
        raise InvalidInputError(
            f"expected world_up to be a finite non-zero 3-vector, got {describe(world_up)}"
        )
    up = up / n
    for d in (Rm[2], -Rm[1]):
        flat = d - (d @ up) * up
        norm = float(np.linalg.norm(flat))
        if norm > 1e-9:
            ahead = flat / norm
            return np.cross(ahead, up), ahead
    raise InvalidInputError("the camera's axes are degenerate with world_up")  # pragma: no cover


def top_view_project(points: ArrayLike, data: dict[str, Any]) -> np.ndarray:
    """Project world points ``(N, 3)`` to top-view coordinates ``(N, 2)`` (metres).

    The coordinates are right of the camera and ahead of it (the camera centre at the origin).
    ``data`` from :func:`top_view_data`.
    """
    X = np.asarray(points, dtype=np.float64).reshape(-1, 3) - data["camera_center_m"]
    return np.stack([X @ data["view_right"], X @ data["view_ahead"]], axis=-1)


def top_view_data(result: SimulationResult) -> dict[str, Any]:
    """Return what the top view draws, in world coordinates (metres).

    ``camera_center_m`` :math:`C = -R^T t`; ``frustum_far_corners_m`` ``(4, 3)`` the points
    imaged at the image corners at camera depth ``frustum_depth_m`` (``Camera.unproject``),
    the depth of the farthest scene corner in front of the camera (1 m if none is);
    ``optical_axis_end_m`` the point on the optical axis at that depth; ``quads_m`` the
    scene's objects as ``{name: corners (4, 3)}``; ``world_up`` and the view's axes
    ``view_right``, ``view_ahead`` (:func:`top_view_axes`). Rays whose corner pixel cannot
    be undistorted are NaN.
    """
    check_result(result)
    cam = result.camera
    width, height = result.image_size
    centre = np.asarray(cam.center, dtype=np.float64)
    depth = 0.0
    for q in result.quads:
        z = np.asarray(cam.world_to_camera(np.asarray(q.corners, dtype=np.float64)))[:, 2]
        if np.any(z > 0):
            depth = max(depth, float(z[z > 0].max()))
    depth = depth if depth > 0 else 1.0
    far = np.asarray(cam.unproject(image_corner_pixels(width, height), np.full(4, depth)))
    R = np.asarray(cam.R, dtype=np.float64)
    right, ahead = top_view_axes(R, result.world_up)
    return {
        "camera_center_m": centre,
        "frustum_depth_m": depth,
        "frustum_far_corners_m": far,
        "optical_axis_end_m": centre + depth * R[2],
        "quads_m": {q.name: np.asarray(q.corners, dtype=np.float64) for q in result.quads},
        "world_up": np.asarray(result.world_up, dtype=np.float64),
        "view_right": right,
        "view_ahead": ahead,
    }


def plot_top_view(data: dict[str, Any]) -> Figure:
    """Plot the scene from above (looking down ``world_up``), the camera looking up the page.

    The figure shows the objects' outlines, the camera centre at the origin, the frustum rays
    through the image corners and the optical axis, all :func:`top_view_project`-ed. ``data`` from
    :func:`top_view_data`.
    """
    from imageform.report.figures_color import _subplots

    fig, ax = _subplots(figsize=(6.8, 6.8))
    for i, (name, corners) in enumerate(data["quads_m"].items()):
        p = top_view_project(np.vstack([corners, corners[:1]]), data)
        ax.plot(p[:, 0], p[:, 1], "-", color=f"C{i % 10}", lw=2, label=name)
        m = p[:-1].mean(axis=0)
        # labels of objects left of the camera end at them, of the others start there
        ha = "right" if m[0] < -1e-9 else ("left" if m[0] > 1e-9 else "center")
        ax.annotate(name, (m[0], m[1]), fontsize=7, ha=ha, va="bottom", color=f"C{i % 10}")
    far = data["frustum_far_corners_m"]
    ok = np.all(np.isfinite(far), axis=1)
    for j, q in enumerate(top_view_project(far[ok], data)):
        ax.plot(
            [0.0, q[0]],
            [0.0, q[1]],
            "--",
            color="0.3",
            lw=0.9,
            label="frustum rays (image corners)" if j == 0 else None,
        )
    if ok.sum() >= 2:
        ring = top_view_project(np.vstack([far[ok], far[ok][:1]]), data)
        ax.plot(ring[:, 0], ring[:, 1], ":", color="0.3", lw=0.8)
    a = top_view_project(data["optical_axis_end_m"], data)[0]
    ax.plot([0.0, a[0]], [0.0, a[1]], "-.", color="C3", lw=0.9, label="optical axis")
    ax.plot([0.0], [0.0], "o", ms=8, mfc="k", mec="w", label="camera centre", zorder=5)
    _world_axes(ax, data)
    ax.set_xlabel("right of the camera (m)")
    ax.set_ylabel("ahead of the camera (m)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, lw=0.3)
    ax.legend(loc="best", fontsize=7)
    ax.set_title(f"Scene and camera frustum from above (depth {data['frustum_depth_m']:.2f} m)")
    # fixed margins (what tight_layout found for the built-in scene, with room to spare):
    # tight_layout measures every text twice more, a fifth of the figure's time
    fig.subplots_adjust(left=0.13, right=0.975, bottom=0.09, top=0.945)
    return fig


def _world_axes(ax: Any, data: dict[str, Any]) -> None:
    """Small arrows in the lower left showing the world axes that lie in the ground plane."""
    up = data["world_up"] / np.linalg.norm(data["world_up"])
    tail = np.array([0.12, 0.12])
    for k, name in enumerate("xyz"):
        e = np.zeros(3)
        e[k] = 1.0
        if abs(float(e @ up)) > 1e-6:
            continue  # the up axis (or one not in the ground plane)
        d = np.array([e @ data["view_right"], e @ data["view_ahead"]])
        head = tail + 0.07 * d
        arrow = {"arrowstyle": "->", "color": "0.35", "lw": 0.9}
        ax.annotate("", xy=head, xytext=tail, xycoords="axes fraction", arrowprops=arrow)
        ax.annotate(
            f"world {name}",
            xy=tail + 0.1 * d,
            xycoords="axes fraction",
            fontsize=7,
            color="0.35",
            ha="center",
            va="center",
        )


def vanishing_summary(result: SimulationResult) -> dict[str, Any] | None:
    """Return the true and detected vanishing point and horizon, with their errors.

    The vanishing points ``vanishing_point_px``, ``detected_vanishing_point_px`` (homogeneous pixel
    coordinates ``(u, v, 1)``, or ``(x, y, 0)`` at infinity) and horizons ``horizon_px``,
    ``detected_horizon_px`` (the line ``a u + b v + c = 0`` in pixel coordinates), with
    :func:`imageform.simulate.truth.vanishing_errors`: ``vanishing_point_error_px`` (distance of the
    finite points; ``None`` without a detection) and ``horizon_angle_error_deg``. ``None`` without
    rails.

    Examples
    --------
    >>> from imageform.geometry import Camera
    >>> from imageform.simulate.result import Stage, VanishingTruth
    >>> r = SimulationResult((Stage("o", "o", "o", np.zeros((4, 4, 3)), "srgb"),),
    ...     Camera(np.eye(3)), (4, 4), vanishing=VanishingTruth(np.array([3.0, 4.0, 1.0]),
    ...     np.array([0.0, 1.0, -4.0]), np.array([0.0, 0.0, 1.0]), None))
    >>> vanishing_summary(r)["vanishing_point_error_px"]
    5.0
    """
    check_result(result)
    v = result.vanishing
    if v is None:
        return None

    def norm(p: Any) -> np.ndarray | None:
        if p is None:
            return None
        a = np.asarray(p, dtype=np.float64).ravel()
        return a / a[2] if a.size == 3 and a[2] != 0 else a

    errors = vanishing_errors(v)
    return {
        "vanishing_point_px": norm(v.vanishing_point),
        "horizon_px": np.asarray(v.horizon, dtype=np.float64),
        "detected_vanishing_point_px": norm(v.detected_vanishing_point),
        "detected_horizon_px": (
            None if v.detected_horizon is None else np.asarray(v.detected_horizon)
        ),
        **errors,
    }


def vanishing_overlay(result: SimulationResult, display: np.ndarray) -> PIL.Image.Image | None:
    """Return the output picture ``display`` (uint8 RGB) with the vanishing points and horizons.

    The true and detected ones are drawn by
    :func:`imageform.report.overlays.draw_vanishing_truth_overlay`; ``None`` without rails.
    """
    check_result(result)
    from imageform.report.overlays import _to_rgb8, draw_vanishing_truth_overlay

    picture = _to_rgb8(display, "display")
    v = result.vanishing
    if v is None:
        return None
    return draw_vanishing_truth_overlay(
        picture,
        v.vanishing_point,
        v.horizon,
        detected_vanishing_point=v.detected_vanishing_point,
        detected_horizon=v.detected_horizon,
    )
