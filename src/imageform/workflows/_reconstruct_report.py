"""report.html of ``imageform reconstruct``: the cameras and points, the errors, what failed.

The simulate report's style (:mod:`imageform.report.html_parts`): one self-contained page,
two figures embedded as PNG ``data:`` URIs (views from above and from the side; histograms
of the reprojection errors and track lengths), a table of the frames and the notes.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from imageform.report import html_parts as hp

__all__ = ["write_report"]

#: Points drawn in the views at most (a random subset beyond; the page stays light).
_MAX_DRAWN = 20_000


def _plt() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _limits(points: np.ndarray, cameras: np.ndarray) -> tuple[float, float]:
    """Return the points' 1st to 99th percentile and every camera, with a margin.

    A few far points do not shrink the rest; no camera is left outside.
    """
    lo, hi = np.percentile(points, [1, 99]) if points.size else (np.inf, -np.inf)
    if cameras.size:
        lo, hi = min(lo, float(cameras.min())), max(hi, float(cameras.max()))
    pad = 0.08 * max(hi - lo, 1e-9)
    return float(lo - pad), float(hi + pad)


def _views(rec: Any) -> bytes:
    """Draw the points and cameras from above (x, z) and from the side (z, -y)."""
    plt = _plt()
    reg = np.flatnonzero(rec.registered)
    centres = np.array([-rec.R[i].T @ rec.t[i] for i in reg]).reshape(-1, 3)
    axes_z = np.array([rec.R[i][2] for i in reg]).reshape(-1, 3)  # optical axes in the world
    P, C = rec.points, rec.colors
    if P.shape[0] > _MAX_DRAWN:
        keep = np.random.default_rng(0).choice(P.shape[0], _MAX_DRAWN, replace=False)
        P, C = P[keep], C[keep]
    fig, axs = plt.subplots(1, 2, figsize=(11, 5))
    dot = 5.0 if P.shape[0] < 3000 else 1.5
    for ax, (i, j, sj, title) in zip(
        axs,
        ((0, 2, 1.0, "from above (x right, z forward)"), (2, 1, -1.0, "from the side (z, up)")),
        strict=True,
    ):
        xl = _limits(P[:, i], centres[:, i])
        yl = _limits(sj * P[:, j], sj * centres[:, j])
        span = max(xl[1] - xl[0], yl[1] - yl[0])
        ax.scatter(P[:, i], sj * P[:, j], s=dot, c=C / 255.0, linewidths=0, rasterized=True)
        ax.plot(centres[:, i], sj * centres[:, j], "-o", color="#c0392b", ms=3, lw=1)
        arrow = 0.06 * span
        ax.quiver(
            centres[:, i], sj * centres[:, j], axes_z[:, i], sj * axes_z[:, j],
            color="#c0392b", angles="xy", scale_units="xy", scale=1 / arrow, width=0.003,
        )  # fmt: skip
        if centres.shape[0]:
            ax.annotate(f"frame {reg[0]}", (centres[0, i], sj * centres[0, j]), fontsize=8)
        ax.set_xlim(*xl)
        ax.set_ylim(*yl)
        ax.set_aspect("equal", adjustable="box")
        ax.set_xlabel("xyz"[i])
        ax.set_ylabel(("-" if sj < 0 else "") + "xyz"[j])
        ax.set_title(title)
    fig.tight_layout()
    return hp.figure_png(fig)


def _histograms(rec: Any) -> bytes:
    plt = _plt()
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 3.6))
    r = np.asarray(rec.residuals_px, np.float64)
    if r.size:
        a1.hist(r, bins=np.linspace(0, max(4.0, float(r.max())), 61), color="#2c7fb8")
        a1.axvline(float(np.median(r)), color="k", lw=1, ls="--", label="median")
        a1.legend()
    a1.set_xlabel("reprojection error (px)")
    a1.set_ylabel("observations")
    a1.set_title(f"{r.size} observations after bundle adjustment")
    n = np.asarray(rec.track_length, np.int64)
    if n.size:
        a2.hist(n, bins=np.arange(1.5, n.max() + 1.5), color="#41ab5d", rwidth=0.85)
    a2.set_xlabel("track length (frames that see the point)")
    a2.set_ylabel("points")
    a2.set_title(f"{n.size} points")
    fig.tight_layout()
    return hp.figure_png(fig)


def _fmt(x: float | None, spec: str = ".3f") -> str:
    return "—" if x is None or not math.isfinite(x) else f"{x:{spec}}"


def write_report(
    path: Path,
    rec: Any,
    names: Sequence[str],
    metrics: Mapping[str, Any],
    *,
    title_source: str,
) -> Path:
    """Write report.html of the reconstruction ``rec`` (a Reconstruction) to ``path``."""
    n = len(names)
    nreg = int(np.sum(rec.registered))
    head = [
        ["frames", str(n)],
        ["registered", f"{nreg} ({100 * nreg / max(n, 1):.0f} %)"],
        ["points", str(rec.points.shape[0])],
        ["mean track length", _fmt(metrics.get("track_length_mean"), ".2f")],
        ["median reprojection error", _fmt(metrics.get("reprojection_px_median")) + " px"],
        ["RMS reprojection error", _fmt(metrics.get("reprojection_px_rms")) + " px"],
    ]
    intr = metrics.get("intrinsics") or {}
    if intr.get("focal_fixed") is not None:  # refined: its one verdict, metrics.json's
        sd = intr.get("focal_px_sd")
        head.append(
            [
                "focal length",
                f"{intr['focal_px']:.1f} px +- "
                + ("inf" if sd is None else f"{sd:.1f} px")
                + (", fixed by the frames" if intr["focal_fixed"] else ", not fixed by the frames"),
            ]
        )
    stages = metrics.get("seconds", {})
    head += [[f"time: {k}", f"{v:.2f} s"] for k, v in stages.items()]
    overview = (
        "<p>Structure from motion: SIFT keypoints matched between neighbouring frames, each "
        "pair verified by its essential matrix, an initial pair with parallax, the other "
        "frames registered by PnP, the points triangulated, then bundle adjustment of every "
        "pose and point. The world is the camera frame of the first registered frame, frame 0 "
        "whenever it is registered (its pose is r = t = 0 in cameras.csv); the scale "
        "is arbitrary (the initial pair's baseline is 1).</p>"
        + hp.table(["", "value"], head, left=(0,))
    )
    views = hp.figure(
        _views(rec),
        "cameras and points from above and from the side",
        "The points in their colour and the registered cameras (red: centres in frame order, "
        "arrows along the optical axes), from above and from the side (the world frame, that "
        "of the first registered camera: x right, y down, z forward). The axes show the "
        "points' 1st to 99th percentile and every camera.",
    )
    hists = hp.figure(
        _histograms(rec),
        "histograms of reprojection errors and track lengths",
        "Left: distance between each kept observation and its point's projection after "
        "bundle adjustment. Right: how many frames see each point (a longer track, a "
        "better-constrained point).",
    )
    unreg = [f"{i} ({names[i]})" for i in np.flatnonzero(~rec.registered).tolist()]
    failed = [hp.note(t) for t in rec.notes]
    if unreg:
        failed.append(hp.note(f"not registered: {', '.join(unreg)}"))
    if not failed:
        failed.append("<p>Every frame was registered; nothing to report.</p>")
    rows = [
        [str(i), name, "yes" if rec.registered[i] else "no", _fmt(float(rec.rms_px[i]))]
        for i, name in enumerate(names)
    ]
    body = "".join(
        [
            hp.section("overview", "Overview", overview),
            hp.section("views", "Cameras and points", views),
            hp.section("errors", "Reprojection errors and tracks", hists),
            hp.section("failed", "What failed", "".join(failed)),
            hp.section(
                "frames",
                "Frames",
                hp.table(["frame", "name", "registered", "RMS (px)"], rows, left=(1,))
                + hp.json_block(dict(metrics), "metrics.json"),
            ),
        ]
    )
    nav = [
        ("overview", "Overview"),
        ("views", "Cameras and points"),
        ("errors", "Errors"),
        ("failed", "What failed"),
        ("frames", "Frames"),
    ]
    sub = f"<p>{hp.e(title_source)}: {nreg} of {n} frames, {rec.points.shape[0]} points</p>"
    path.write_text(hp.page("imageform reconstruction", sub, nav, body), encoding="utf-8")
    return path
