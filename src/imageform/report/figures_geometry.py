"""The simulation report's geometry figures: the scene and the camera frustum seen from above,
and the vanishing point and horizon drawn on the output image.

The top view projects world points onto the ground plane by dropping y (world x right,
y down, z forward, as the camera convention of DESIGN.md): x across, z up the page.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from imageform.simulate.result import SimulationResult

__all__ = [
    "image_corner_pixels",
    "plot_top_view",
    "top_view_data",
    "vanishing_overlay",
    "vanishing_summary",
]


def image_corner_pixels(width: int, height: int) -> np.ndarray:
    """The outer corners ``(4, 2)`` of the image (pixel edges, centre of the top-left pixel at
    (0, 0)), clockwise from the top left.

    >>> image_corner_pixels(4, 3).tolist()
    [[-0.5, -0.5], [3.5, -0.5], [3.5, 2.5], [-0.5, 2.5]]
    """
    w, h = float(width), float(height)
    return np.array([[-0.5, -0.5], [w - 0.5, -0.5], [w - 0.5, h - 0.5], [-0.5, h - 0.5]])


def top_view_data(result: SimulationResult) -> dict[str, Any]:
    """What the top view draws, in world coordinates (metres).

    ``camera_center`` :math:`C = -R^T t`; ``frustum_far_corners`` ``(4, 3)`` the points imaged at
    the image corners at camera depth ``frustum_depth_m`` (``Camera.unproject``), the depth
    of the farthest scene corner in front of the camera (1 m if none is);
    ``optical_axis_end`` the point on the optical axis at that depth; ``quads`` the scene's
    objects as ``{name: corners (4, 3)}``. Rays whose corner pixel cannot be undistorted are
    NaN.
    """
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
    axis = centre + depth * np.asarray(cam.R, dtype=np.float64)[2]
    return {
        "camera_center": centre,
        "frustum_depth_m": depth,
        "frustum_far_corners": far,
        "optical_axis_end": axis,
        "quads": {q.name: np.asarray(q.corners, dtype=np.float64) for q in result.quads},
    }


def plot_top_view(data: dict[str, Any]) -> Any:
    """Figure: the scene's quads, the camera centre and the frustum rays through the image
    corners, projected onto the ground (x–z) plane. ``data`` from :func:`top_view_data`."""
    from imageform.report.figures_color import _pyplot

    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.8, 6.8))
    c = data["camera_center"]
    for i, (name, corners) in enumerate(data["quads"].items()):
        ring = np.vstack([corners, corners[:1]])
        ax.plot(ring[:, 0], ring[:, 2], "-", color=f"C{i % 10}", lw=2, label=name)
        ax.annotate(
            name,
            (corners[:, 0].mean(), corners[:, 2].mean()),
            fontsize=7,
            ha="center",
            color=f"C{i % 10}",
        )
    far = data["frustum_far_corners"]
    for j, p in enumerate(far):
        if np.all(np.isfinite(p)):
            ax.plot(
                [c[0], p[0]],
                [c[2], p[2]],
                "--",
                color="0.3",
                lw=0.9,
                label="frustum rays (image corners)" if j == 0 else None,
            )
    ok = np.all(np.isfinite(far), axis=1)
    if ok.sum() >= 2:
        ring = np.vstack([far[ok], far[ok][:1]])
        ax.plot(ring[:, 0], ring[:, 2], ":", color="0.3", lw=0.8)
    a = data["optical_axis_end"]
    ax.plot([c[0], a[0]], [c[2], a[2]], "-.", color="C3", lw=0.9, label="optical axis")
    ax.plot([c[0]], [c[2]], "o", ms=8, mfc="k", mec="w", label="camera centre", zorder=5)
    ax.set_xlabel("world x (m)")
    ax.set_ylabel("world z (m)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, lw=0.3)
    ax.legend(loc="best", fontsize=7)
    ax.set_title(f"Scene and camera frustum from above (depth {data['frustum_depth_m']:.2f} m)")
    fig.tight_layout()
    return fig


def vanishing_summary(result: SimulationResult) -> dict[str, Any] | None:
    """True and detected vanishing point (pixels, homogeneous normalised to w = 1 where
    finite) and horizon, and the detection error ``error_px`` (Euclidean distance of the
    finite points; ``None`` when there is no detection). ``None`` without rails.

    >>> from imageform.geometry import Camera
    >>> from imageform.simulate.result import Stage, VanishingTruth
    >>> r = SimulationResult((Stage("o", "o", "o", np.zeros((4, 4, 3)), "srgb"),),
    ...     Camera(np.eye(3)), (4, 4), vanishing=VanishingTruth(np.array([3.0, 4.0, 1.0]),
    ...     np.array([0.0, 1.0, -4.0]), np.array([0.0, 0.0, 1.0]), None))
    >>> vanishing_summary(r)["error_px"]
    5.0
    """
    v = result.vanishing
    if v is None:
        return None

    def norm(p: Any) -> np.ndarray | None:
        if p is None:
            return None
        a = np.asarray(p, dtype=np.float64).ravel()
        return a / a[2] if a.size == 3 and a[2] != 0 else a

    true_vp, det_vp = norm(v.vanishing_point), norm(v.detected_vanishing_point)
    err = None
    if true_vp is not None and det_vp is not None and true_vp[2] == 1 and det_vp[2] == 1:
        err = float(np.hypot(*(det_vp[:2] - true_vp[:2])))
    return {
        "vanishing_point": true_vp,
        "horizon": np.asarray(v.horizon, dtype=np.float64),
        "detected_vanishing_point": det_vp,
        "detected_horizon": None if v.detected_horizon is None else np.asarray(v.detected_horizon),
        "error_px": err,
    }


def vanishing_overlay(result: SimulationResult, display: np.ndarray) -> Any:
    """The output picture ``display`` (uint8 RGB) with the true and detected vanishing point
    and horizon (:func:`imageform.report.overlays.draw_vanishing_truth_overlay`); ``None``
    without rails."""
    from imageform.report.overlays import draw_vanishing_truth_overlay

    v = result.vanishing
    if v is None:
        return None
    return draw_vanishing_truth_overlay(
        display,
        v.vanishing_point,
        v.horizon,
        detected_vanishing_point=v.detected_vanishing_point,
        detected_horizon=v.detected_horizon,
    )
