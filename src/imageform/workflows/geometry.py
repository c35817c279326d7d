"""Geometry workflows on points: project, pose, triangulate.

Every camera comes from a camera file (:mod:`imageform.io.camera_file`, docs/camera-file.md)
and every field of it is honoured: K with its skew, the distortion model, the pose, the image
size. Commands that estimate a camera write one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.workflows._spec import Input, Options, Output, Result, Run, Workflow, option
from imageform.workflows._tables import camera_from, read_table, write_table

__all__ = ["WORKFLOWS", "PoseOptions", "ProjectOptions", "TriangulateOptions"]


def _finite(value: float | None, flag: str, *, positive: bool = False) -> None:
    if value is None:
        return
    if not math.isfinite(value):
        raise InvalidInputError(f"expected {flag} as a finite number, got {value}")
    if positive and value <= 0:
        raise InvalidInputError(
            f"expected {flag} > 0 pixels, got {value:g} (zero makes K singular, a negative "
            "focal length mirrors the image)"
        )


# ---------------------------------------------------------------- project


@dataclass(frozen=True, kw_only=True)
class ProjectOptions(Options):
    """Options of ``imageform project``."""

    camera: Path | None = option(
        None,
        help="Camera file (docs/camera-file.md): K, distortion and pose, all applied.",
        metavar="FILE",
        input=True,
    )
    fx: float | None = option(None, help="Without --camera: focal length in pixels (x), > 0.")
    fy: float | None = option(None, help="Focal length in pixels (y), > 0; default --fx.")
    cx: float | None = option(None, help="Principal point column in pixels (default 0).")
    cy: float | None = option(None, help="Principal point row in pixels (default 0).")
    skew: float | None = option(None, help="Skew, K[0, 1] in pixels (default 0).")

    def check(self) -> None:
        """Check that the camera is given as ``--camera FILE`` or as ``--fx ...``, not both."""
        super().check()
        pinhole = [f for f in ("fx", "fy", "cx", "cy", "skew") if getattr(self, f) is not None]
        if self.camera is not None and pinhole:
            flags = ", ".join("--" + f for f in pinhole)
            raise InvalidInputError(
                f"give the camera as --camera FILE or as --fx ..., not both (got {flags})"
            )
        if self.camera is None and self.fx is None:
            raise InvalidInputError("give the camera as --camera FILE or --fx [--fy --cx --cy]")
        _finite(self.fx, "--fx", positive=True)
        _finite(self.fy, "--fy", positive=True)
        for f in ("cx", "cy", "skew"):
            _finite(getattr(self, f), "--" + f)


def project(run: Run, opts: ProjectOptions, *, out: Path, points: Path) -> Result:
    """``imageform project``: 3-D points through a camera to pixels.

    Rows that are not finite, or at or behind the camera (``z_cam <= 0``), are written as
    ``nan, nan, 0``; the summary counts them.
    """
    import numpy as np

    from imageform.geometry import Camera, intrinsic_matrix

    has_pose = False
    if opts.camera is not None:
        cf = camera_from(opts.camera)
        cam, model, has_pose = cf.camera, cf.distortion_model, cf.has_pose
    else:
        assert opts.fx is not None
        K = intrinsic_matrix(
            opts.fx,
            opts.fy if opts.fy is not None else opts.fx,
            opts.cx or 0.0,
            opts.cy or 0.0,
            opts.skew or 0.0,
        )
        cam, model = Camera(K), "none"
    table = read_table(points, columns=3, what="3 columns (X, Y, Z)")
    X = _xyz(table)
    finite = np.all(np.isfinite(X), axis=1)
    uv = np.full((len(X), 2), np.nan)
    valid = np.zeros(len(X), dtype=bool)
    behind = 0
    if finite.any():
        Xf = X[finite]
        uv_f, ok = cam.project(Xf)
        uv[finite], valid[finite] = np.asarray(uv_f), np.asarray(ok)
        z = (Xf @ np.asarray(cam.R).T + np.asarray(cam.t))[:, 2]
        behind = int(np.count_nonzero(z <= 0))
    write_table(
        run.file(out),
        ("u", "v", "valid"),
        ((u, v, int(ok)) for (u, v), ok in zip(uv, valid, strict=True)),
    )
    n, n_valid = len(X), int(valid.sum())
    outside = None
    if cam.image_size is not None and n_valid:
        outside = int(np.count_nonzero(~np.asarray(cam.in_image(uv[valid]))))
    summary = {
        "input": points,
        "output": out,
        "camera": opts.camera,
        "distortion": model,
        "pose": has_pose,
        "points": n,
        "valid": n_valid,
        "invalid": n - n_valid,
        "not_finite": int(np.count_nonzero(~finite)),
        "behind_camera": behind,
        "outside_image": outside,
    }
    text = [f"projected {n} points -> {out}: {n_valid} valid"]
    if n - n_valid:
        text[0] += (
            f", {n - n_valid} invalid (written as nan with valid = 0: "
            f"{summary['not_finite']} not finite, {behind} at or behind the camera)"
        )
    if outside:
        w, h = cam.image_size or (0, 0)
        text.append(f"{outside} valid points fall outside the {w} x {h} px image")
    if not has_pose:
        text.append("the camera has no pose: X, Y, Z are taken in the camera frame")
    return Result(summary, tuple(text))


def _xyz(table: Any) -> Any:
    cols = table.named(("x", "y", "z"))
    return table.numbers((0, 1, 2) if cols is None else cols, finite=False)


# ---------------------------------------------------------------- pose


@dataclass(frozen=True, kw_only=True)
class PoseOptions(Options):
    """Options of ``imageform pose``."""

    ransac: bool = option(False, help="Reject outliers with RANSAC.")
    threshold: float = option(2.0, help="RANSAC inlier threshold in pixels.")
    view: str | None = option(
        None,
        help="With a table that has an image column (imageform calibrate --corners): "
        "the image whose rows to use.",
        metavar="NAME",
    )

    def check(self) -> None:
        """Check that ``--threshold`` is a finite number of pixels > 0."""
        super().check()
        if not (math.isfinite(self.threshold) and self.threshold > 0):
            raise InvalidInputError(f"expected --threshold > 0 pixels, got {self.threshold}")


def _correspondences(table: Any, view: str | None) -> tuple[Any, list[int]]:
    """X, Y, Z, u, v of the chosen rows (by header names if present, else by position)."""
    names = ("x", "y", "z", "u", "v")
    img = table.column("image")
    rows = list(range(len(table.rows)))
    if img is not None:
        views = list(dict.fromkeys(r[img] for r in table.rows))
        if view is None and len(views) > 1:
            raise InvalidInputError(
                f"{table.path} holds {len(views)} images; choose one with --view "
                f"({', '.join(views[:5])}{' ...' if len(views) > 5 else ''})"
            )
        pick = view if view is not None else views[0]
        rows = [i for i in rows if table.rows[i][img] == pick]
        if not rows:
            raise InvalidInputError(
                f"{table.path}: no rows of image {pick!r}; it holds {', '.join(views[:5])}"
            )
    elif view is not None:
        raise InvalidInputError(f"--view needs a table with an image column; {table.path} has none")
    named = table.named(names)
    if named is not None:
        return table.numbers(named, finite=True, rows=rows), rows
    if len(table.rows[0]) != 5:
        raise InvalidInputError(
            f"{table.path}: expected 5 columns (X, Y, Z, u, v) or a header naming them, "
            f"got {len(table.rows[0])} columns"
        )
    return table.numbers(range(5), finite=True, rows=rows), rows


def pose(run: Run, opts: PoseOptions, *, out: Path | None, camera: Path, points: Path) -> Result:
    """``imageform pose``: where a calibrated camera is, from 3-D/2-D correspondences.

    Uses the camera file's K and distortion (every model); writes the camera file with the
    pose (world to camera, in the unit of X, Y, Z).
    """
    import numpy as np

    from imageform.geometry import solve_pnp, solve_pnp_ransac

    cf = camera_from(camera)
    cam = cf.camera
    table = read_table(points, what="5 columns (X, Y, Z, u, v)")
    data, _ = _correspondences(table, opts.view)
    K, dist = np.asarray(cam.K), cam.distortion
    if opts.ransac:
        res = solve_pnp_ransac(data[:, :3], data[:, 3:], K, dist, threshold=opts.threshold)
    else:
        res = solve_pnp(data[:, :3], data[:, 3:], K, dist)
    n_in = int(np.count_nonzero(res.inliers))
    if not bool(res.valid):
        raise DegenerateConfigurationError(
            f"no valid pose from {points}: the best fit leaves points at or behind the camera "
            "(check the correspondences and the camera file)"
        )
    if cf.has_pose:
        run.note(f"note: the pose in {camera} is replaced by the estimated one")
    summary: dict[str, Any] = {
        "camera": camera,
        "input": points,
        "view": opts.view,
        "rvec": res.rvec,
        "t": res.tvec,
        "R": res.R,
        "rms_px": float(res.rms),
        "inliers": n_in,
        "points": int(data.shape[0]),
        "output": out,
    }
    if out is not None:
        from imageform.io import write_camera

        posed = cf.with_pose(
            res.R,
            res.tvec,
            command="imageform pose" + (" --ransac" if opts.ransac else ""),
            based_on=camera.name,
            rms_px=float(res.rms),
            points_used=n_in,
            images=(opts.view,) if opts.view else (),
        )
        write_camera(run.file(out), posed)
    rv = ", ".join(f"{v:.6f}" for v in np.asarray(res.rvec))
    tv = ", ".join(f"{v:.6g}" for v in np.asarray(res.tvec))
    text = [
        f"rvec ({rv}) rad, t ({tv}); RMS {float(res.rms):.4f} px, {n_in}/{data.shape[0]} inliers"
    ]
    if out is not None:
        text.append(f"wrote {out}")
    return Result(summary, tuple(text))


# ---------------------------------------------------------------- triangulate


@dataclass(frozen=True, kw_only=True)
class TriangulateOptions(Options):
    """Options of ``imageform triangulate``."""

    sigma: float = option(1.0, help="Pixel noise (standard deviation, px) for the uncertainties.")
    views: str | None = option(
        None,
        help="With a table that has an image column (imageform calibrate --corners): the "
        "image of each camera, comma-separated, in the cameras' order.",
        metavar="A,B,...",
    )

    def check(self) -> None:
        """Check that ``--sigma`` is a finite number of pixels > 0."""
        super().check()
        if not (math.isfinite(self.sigma) and self.sigma > 0):
            raise InvalidInputError(f"expected --sigma > 0 pixels, got {self.sigma}")


def _observations(table: Any, n_cams: int, views: str | None) -> Any:
    """Return the (M, 2V) pixel columns of a wide or a long table.

    A wide table has u, v per camera; a long one an image column and X, Y, Z naming each point.
    """
    import numpy as np

    img = table.column("image")
    if img is None:
        if views is not None:
            raise InvalidInputError(
                f"--views needs a table with an image column; {table.path} has none"
            )
        if len(table.rows[0]) != 2 * n_cams:
            raise InvalidInputError(
                f"{table.path}: expected {2 * n_cams} columns (u, v per camera) for {n_cams} "
                f"cameras, got {len(table.rows[0])}"
            )
        return table.numbers(range(2 * n_cams), finite=False)
    names = [v.strip() for v in (views or "").split(",") if v.strip()]
    if len(names) != n_cams:
        raise InvalidInputError(
            f"{table.path} has an image column: name the image of each of the {n_cams} "
            f"cameras with --views A,B,... (got {len(names)})"
        )
    cols = [table.column(c) for c in ("x", "y", "z", "u", "v")]
    if None in cols:
        raise InvalidInputError(f"{table.path}: expected columns image, X, Y, Z, u, v")
    keys: dict[tuple[str, ...], int] = {}
    cells: dict[tuple[int, int], int] = {}
    for i, row in enumerate(table.rows):
        if row[img] not in names:
            continue
        key = tuple(row[c].strip() for c in cols[:3])
        keys.setdefault(key, len(keys))
        cell = (keys[key], names.index(row[img]))
        if cell in cells:
            raise InvalidInputError(
                f"{table.path}:{table.lines[i]}: point ({', '.join(key)}) of image "
                f"{row[img]!r} appears twice (first on line {table.lines[cells[cell]]})"
            )
        cells[cell] = i
    for name in names:
        if not any(table.rows[i][img] == name for i in range(len(table.rows))):
            raise InvalidInputError(f"{table.path}: no rows of image {name!r}")
    uv = np.full((len(keys), 2 * n_cams), np.nan)
    for (m, k), i in cells.items():
        uv[m, 2 * k : 2 * k + 2] = table.numbers(cols[3:], finite=False, rows=[i])[0]
    return uv


def triangulate(
    run: Run, opts: TriangulateOptions, *, out: Path, observations: Path, cameras: list[Path]
) -> Result:
    """``imageform triangulate``: points seen in two or more posed cameras, with uncertainty.

    Pixels are undistorted with each camera file's own model before the DLT and the
    refinement (Hartley & Zisserman, 2nd ed., sec. 12.2).
    """
    import numpy as np

    from imageform.geometry import triangulate_points

    if len(cameras) < 2:
        raise InvalidInputError(f"triangulate needs 2 or more camera files, got {len(cameras)}")
    cams = [camera_from(p, need_pose=True, what=", which triangulation needs") for p in cameras]
    centres = [np.asarray(c.camera.center) for c in cams]
    for i in range(len(cams)):
        for j in range(i + 1, len(cams)):
            if np.allclose(
                centres[i], centres[j], rtol=0, atol=1e-12 * (1 + abs(centres[i]).max())
            ):
                raise DegenerateConfigurationError(
                    f"{cameras[i]} and {cameras[j]} have the same centre: no baseline to "
                    "triangulate from"
                )
    table = read_table(observations, what=f"{2 * len(cams)} columns (u, v per camera)")
    data = _observations(table, len(cams), opts.views)
    Ps, uvs = [], []
    for k, (path, cf) in enumerate(zip(cameras, cams, strict=True)):
        cam = cf.camera
        K, R, t = (np.asarray(a, dtype=np.float64) for a in (cam.K, cam.R, cam.t))
        uv = data[:, 2 * k : 2 * k + 2]
        if cam.distortion is not None:
            seen = np.all(np.isfinite(uv), axis=1)
            xy = np.full_like(uv, np.nan)
            if seen.any():
                xy[seen] = np.asarray(cam.undistort_pixels(uv[seen]))
            lost = int(np.count_nonzero(seen & ~np.all(np.isfinite(xy), axis=1)))
            if lost:
                raise InvalidInputError(
                    f"{path}: {lost} observation(s) lie outside the valid radius of its "
                    f"{cf.distortion_model} model (undistortion did not converge)"
                )
            uv = xy @ K[:2, :2].T + K[:2, 2]
        Ps.append(K @ np.hstack([R, t[:, None]]))
        uvs.append(uv)
    res = triangulate_points(np.stack(Ps), np.stack(uvs), sigma=opts.sigma)
    n, n_valid = len(res.points), int(np.count_nonzero(res.valid))
    if n_valid == 0:
        raise DegenerateConfigurationError(
            f"none of the {n} points could be triangulated: each needs two cameras that see "
            "it, in front of both, with rays that are not parallel"
        )
    sd = np.sqrt(np.einsum("mii->mi", res.covariance))
    write_table(
        run.file(out),
        ("X", "Y", "Z", "sX", "sY", "sZ", "rms", "valid"),
        (
            (*X, *s, r, int(ok))
            for X, s, r, ok in zip(res.points, sd, res.rms, res.valid, strict=True)
        ),
    )
    summary = {
        "input": observations,
        "cameras": list(cameras),
        "output": out,
        "points": n,
        "valid": n_valid,
        "invalid": n - n_valid,
        "rms_px_median": float(np.nanmedian(res.rms[res.valid])),
    }
    text = f"triangulated {n} points -> {out}: {n_valid} valid"
    if n - n_valid:
        text += f", {n - n_valid} invalid (nan with valid = 0: unseen, behind or no baseline)"
    return Result(summary, (text,))


WORKFLOWS = (
    Workflow(
        "project",
        "Project 3-D points (CSV) through a camera file or a pinhole to pixels (CSV).",
        "imageform.workflows.geometry:project",
        ProjectOptions,
        (Input("points", "CSV of X, Y, Z per line (a header is allowed)."),),
        Output("CSV to write: u, v, valid (nan and 0 for points that have no image)."),
        suffixes=(".csv",),
        group="geometry",
        description="Every field of the camera file is applied: K with skew, the distortion "
        "model, the pose. Non-finite points and points at or behind the camera are written as "
        "nan with valid = 0 and counted.",
    ),
    Workflow(
        "pose",
        "Camera pose from 3-D/2-D correspondences (PnP + refinement, optional RANSAC).",
        "imageform.workflows.geometry:pose",
        PoseOptions,
        (
            Input("camera", "Camera file (from imageform calibrate)."),
            Input("points", "CSV of X, Y, Z, u, v (or imageform calibrate --corners with --view)."),
        ),
        Output("Camera file to write, with the pose.", required=False),
        suffixes=(".toml",),
        group="geometry",
    ),
    Workflow(
        "triangulate",
        "Triangulate points seen by two or more posed cameras, with their uncertainty.",
        "imageform.workflows.geometry:triangulate",
        TriangulateOptions,
        (
            Input(
                "observations",
                "CSV of u1, v1, u2, v2, ... per point (empty = unseen), or imageform "
                "calibrate --corners with --views.",
            ),
            Input("cameras", "Camera files with a pose, one per view.", many=True),
        ),
        Output("CSV to write: X, Y, Z, sX, sY, sZ, rms, valid."),
        suffixes=(".csv",),
        group="geometry",
    ),
)
