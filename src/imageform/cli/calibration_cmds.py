"""``imageform calibrate``, ``imageform pose`` and ``imageform triangulate``."""

from __future__ import annotations

import csv
import glob
import re
import sys
import warnings
from pathlib import Path
from typing import Any

import typer

__all__ = ["parse_board", "parse_length_mm", "register"]

_UNITS_MM = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "in": 25.4, "": 1.0}


def parse_board(text: str) -> tuple[int, int]:
    """``"9x6"`` -> ``(9, 6)``: inner corners per row x per column (OpenCV's patternSize)."""
    from imageform.errors import InvalidInputError

    m = re.fullmatch(r"\s*(\d+)\s*[xX×]\s*(\d+)\s*", text)
    if not m or int(m.group(1)) < 2 or int(m.group(2)) < 2:
        raise InvalidInputError(
            f"expected --board COLSxROWS of inner corners (e.g. 9x6), got {text!r}"
        )
    return int(m.group(1)), int(m.group(2))


def parse_length_mm(text: str) -> float:
    """``"25mm"``, ``"2.5cm"``, ``"0.025m"``, ``"1in"`` or a bare number (mm) -> millimetres."""
    from imageform.errors import InvalidInputError

    m = re.fullmatch(r"\s*([0-9]*\.?[0-9]+(?:[eE][-+]?\d+)?)\s*(mm|cm|m|in)?\s*", text)
    if not m or float(m.group(1)) <= 0:
        raise InvalidInputError(
            f"expected --square as a positive length with unit mm, cm, m or in (e.g. 25mm), "
            f"got {text!r}"
        )
    return float(m.group(1)) * _UNITS_MM[m.group(2) or ""]


def _expand(patterns: list[str]) -> list[Path]:
    from imageform.errors import InvalidInputError

    files: list[Path] = []
    for p in patterns:
        hits = sorted(glob.glob(p)) if any(c in p for c in "*?[") else [p]
        if not hits:
            raise InvalidInputError(f"no files match {p!r}")
        files += [Path(h) for h in hits]
    return files


def _warn(msg: str) -> None:
    typer.echo(f"imageform: warning: {msg}", err=True)


def _plot(path: Path, res: Any, names: list[str]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4.5))
    for name, r in zip(names, res.residuals, strict=True):
        ax1.scatter(r[:, 0], r[:, 1], s=6, label=name)
    ax1.set_xlabel("u error (px)")
    ax1.set_ylabel("v error (px)")
    ax1.set_aspect("equal")
    ax1.set_title(f"reprojection errors (RMS {res.rms:.4f} px)")
    ax2.bar(np.arange(len(names)), res.per_view_rms)
    ax2.set_xticks(np.arange(len(names)), names, rotation=60, ha="right", fontsize=7)
    ax2.set_ylabel("RMS per view (px)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def calibrate(
    images: list[str] = typer.Argument(..., help="Image files or quoted glob patterns."),
    board: str = typer.Option(..., help="Inner corners COLSxROWS, e.g. 9x6."),
    square: str = typer.Option("1", help="Square size with unit (25mm, 2.5cm); bare = mm."),
    out: Path = typer.Option(..., "--out", "-o", help="Camera TOML to write."),
    plot: Path | None = typer.Option(None, help="Write a reprojection-error plot (PNG)."),
    half_window: int | None = typer.Option(
        None, help="Sub-pixel window half size (OpenCV's tutorial: 11); default adaptive."
    ),
    fix: list[str] = typer.Option([], help="Parameter to hold fixed (repeatable): k3, p1 ..."),
    skew: bool = typer.Option(False, help="Estimate the skew."),
    force: bool = typer.Option(False, "--force", help="Overwrite existing outputs."),
    json_out: bool = typer.Option(False, "--json", help="Print a JSON summary."),
) -> None:
    """Calibrate a camera from checkerboard views (Zhang + Levenberg-Marquardt)."""
    import numpy as np

    from imageform.cli._common import check_output_path, print_json
    from imageform.cli._image_files import read_image
    from imageform.errors import DegenerateConfigurationError, InvalidInputError
    from imageform.geometry import calibrate_camera, checkerboard_points
    from imageform.geometry.checkerboard import find_checkerboard

    size = parse_board(board)
    square_mm = parse_length_mm(square)
    files = _expand(images)
    check_output_path(out, inputs=tuple(files), force=force)
    if plot is not None:
        check_output_path(plot, inputs=tuple(files), force=force)
    shape0: tuple[int, ...] | None = None
    corners, names = [], []
    with typer.progressbar(files, label="detecting", file=sys.stderr) as bar:
        for f in bar:
            img = read_image(f)
            if shape0 is None:
                shape0 = img.shape[:2]
            elif img.shape[:2] != shape0:
                raise InvalidInputError(
                    f"expected all images of one size, got {files[0]} of {shape0[1]} x "
                    f"{shape0[0]} px and {f} of {img.shape[1]} x {img.shape[0]} px"
                )
            det = find_checkerboard(img, size, half_window=half_window)
            if det.found:
                assert det.corners is not None
                corners.append(det.corners)
                names.append(f.name)
            else:
                _warn(f"{f}: no {board} board found ({det.reason})")
    if not corners:
        raise DegenerateConfigurationError(
            f"no {size[0]}x{size[1]} checkerboard found in any of the {len(files)} images "
            "(check --board: inner corners, not squares)"
        )
    assert shape0 is not None
    obj = checkerboard_points(size, square_mm)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = calibrate_camera(
            [obj] * len(corners), corners, (shape0[1], shape0[0]), skew=skew, fix=tuple(fix)
        )
    for w in caught:
        _warn(str(w.message))
    res.to_toml(out)
    if plot is not None:
        _plot(plot, res, names)
    rows = [
        {"view": n, "rms_px": float(e), "max_px": float(np.max(p))}
        for n, e, p in zip(names, res.per_view_rms, res.per_point_errors, strict=True)
    ]
    K, d = res.K, res.distortion
    summary = {
        "views_used": len(names),
        "views_total": len(files),
        "rms_px": res.rms,
        "fx": K[0, 0],
        "fy": K[1, 1],
        "cx": K[0, 2],
        "cy": K[1, 2],
        "skew": K[0, 1],
        "distortion": dict(zip(("k1", "k2", "p1", "p2", "k3"), d.coeffs[:5], strict=True)),
        "std": res.std,
        "per_view": rows,
        "output": str(out),
    }
    if json_out:
        print_json(summary)
        return
    typer.echo(f"{'view':<24} {'RMS px':>8} {'max px':>8}")
    for r in rows:
        typer.echo(f"{r['view']:<24} {r['rms_px']:8.4f} {r['max_px']:8.4f}")
    typer.echo(
        f"RMS {res.rms:.4f} px over {len(names)} views; fx {K[0, 0]:.3f} ± {res.std['fx']:.3f}, "
        f"fy {K[1, 1]:.3f} ± {res.std['fy']:.3f}, cx {K[0, 2]:.3f}, cy {K[1, 2]:.3f}"
    )
    typer.echo(f"k1..k3 {', '.join(f'{c:.6g}' for c in d.coeffs[:5])} -> {out}")


def _read_table(path: Path, ncols: int | None, what: str) -> Any:
    import numpy as np

    from imageform.errors import InvalidInputError

    if not path.is_file():
        raise InvalidInputError(f"{path} does not exist")
    rows: list[list[float]] = []
    with path.open(newline="") as fh:
        for lineno, row in enumerate(csv.reader(fh), start=1):
            if not row or row[0].lstrip().startswith("#"):
                continue
            try:
                vals = [float(v) if v.strip() else float("nan") for v in row]
            except ValueError:
                if not rows and lineno == 1:
                    continue  # header
                raise InvalidInputError(f"{path}:{lineno}: expected numbers, got {row}") from None
            if ncols is not None and len(vals) != ncols:
                raise InvalidInputError(
                    f"{path}:{lineno}: expected {what}, got {len(vals)} columns"
                )
            rows.append(vals)
    if not rows:
        raise InvalidInputError(f"{path}: no rows")
    if len({len(r) for r in rows}) > 1:
        raise InvalidInputError(f"{path}: rows of different lengths; expected {what}")
    return np.asarray(rows)


def pose(
    camera: Path = typer.Option(..., help="Camera TOML (from `imageform calibrate`)."),
    points: Path = typer.Option(..., help="CSV of X, Y, Z, u, v per correspondence."),
    out: Path | None = typer.Option(None, "--out", "-o", help="Camera TOML with the pose."),
    ransac: bool = typer.Option(False, help="Reject outliers with RANSAC."),
    threshold: float = typer.Option(2.0, help="RANSAC inlier threshold (px)."),
    force: bool = typer.Option(False, "--force", help="Overwrite an existing output."),
    json_out: bool = typer.Option(False, "--json", help="Print a JSON summary."),
) -> None:
    """Camera pose from 3-D/2-D correspondences (linear PnP + refinement, optional RANSAC)."""
    from imageform.cli._common import check_output_path, print_json
    from imageform.geometry import CalibrationResult, solve_pnp, solve_pnp_ransac

    if out is not None:
        check_output_path(out, inputs=(camera, points), force=force)
    cal = CalibrationResult.from_toml(camera)
    data = _read_table(points, 5, "5 columns (X, Y, Z, u, v)")
    if ransac:
        res = solve_pnp_ransac(data[:, :3], data[:, 3:], cal.K, cal.distortion, threshold=threshold)
    else:
        res = solve_pnp(data[:, :3], data[:, 3:], cal.K, cal.distortion)
    summary = {
        "rvec": res.rvec,
        "t": res.tvec,
        "rms_px": float(res.rms),
        "inliers": int(res.inliers.sum()),
        "points": int(data.shape[0]),
        "valid": bool(res.valid),
    }
    if out is not None:
        text = cal.to_toml().split("\n\n[calibration]")[0]
        text += f"\nrvec = {[float(v) for v in res.rvec]}\nt = {[float(v) for v in res.tvec]}\n"
        out.write_text(text)
        summary["output"] = str(out)
    if json_out:
        print_json(summary)
        return
    typer.echo(
        f"rvec {[round(float(v), 6) for v in res.rvec]} t {[round(float(v), 6) for v in res.tvec]}"
        f" RMS {float(res.rms):.4f} px, {summary['inliers']}/{summary['points']} inliers"
        + ("" if res.valid else " (INVALID: points behind the camera)")
    )


def triangulate(
    camera: list[Path] = typer.Option(..., help="Camera TOML with pose (repeat per view)."),
    points: Path = typer.Option(..., help="CSV of u1, v1, u2, v2, ... per point (empty = unseen)."),
    out: Path = typer.Option(..., "--out", "-o", help="CSV: X, Y, Z, sX, sY, sZ, rms, valid."),
    sigma: float = typer.Option(1.0, help="Pixel noise (std) for the uncertainties."),
    force: bool = typer.Option(False, "--force", help="Overwrite an existing output."),
    json_out: bool = typer.Option(False, "--json", help="Print a JSON summary."),
) -> None:
    """Triangulate points seen in two or more calibrated views, with their uncertainty."""
    import numpy as np

    from imageform.cli._common import check_output_path, print_json
    from imageform.cli.geometry_cmds import load_camera_toml
    from imageform.errors import InvalidInputError
    from imageform.geometry import CalibrationResult, triangulate_points

    check_output_path(out, inputs=(points, *camera), force=force)
    V = len(camera)
    data = _read_table(points, 2 * V, f"{2 * V} columns (u, v per camera)")
    Ps, uvs = [], []
    for k, path in enumerate(camera):
        cam = load_camera_toml(path)
        K, R, t = (np.asarray(a, dtype=float) for a in (cam.K, cam.R, cam.t))
        d = CalibrationResult.from_toml(path).distortion
        uv = data[:, 2 * k : 2 * k + 2]
        if any(d.coeffs):
            y = (uv[:, 1] - K[1, 2]) / K[1, 1]
            x = (uv[:, 0] - K[0, 2] - K[0, 1] * y) / K[0, 0]
            xy, ok = d.undistort(np.stack([x, y], -1))
            if not np.all(ok | np.isnan(x)):
                raise InvalidInputError(f"{path}: some points lie outside the distortion model")
            uv = np.stack(
                [K[0, 0] * xy[:, 0] + K[0, 1] * xy[:, 1] + K[0, 2], K[1, 1] * xy[:, 1] + K[1, 2]],
                -1,
            )
        Ps.append(K @ np.hstack([R, t[:, None]]))
        uvs.append(uv)
    res = triangulate_points(np.stack(Ps), np.stack(uvs), sigma=sigma)
    sd = np.sqrt(np.einsum("mii->mi", res.covariance))
    with out.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["X", "Y", "Z", "sX", "sY", "sZ", "rms", "valid"])
        for X, s, r, ok in zip(res.points, sd, res.rms, res.valid, strict=True):
            w.writerow([*(repr(float(v)) for v in (*X, *s, r)), int(ok)])
    summary = {"points": len(res.points), "valid": int(res.valid.sum()), "output": str(out)}
    if json_out:
        print_json(summary)
    else:
        typer.echo(f"triangulated {summary['points']} points ({summary['valid']} valid) -> {out}")


def register(app: typer.Typer) -> None:
    app.command("calibrate")(calibrate)
    app.command("pose")(pose)
    app.command("triangulate")(triangulate)
