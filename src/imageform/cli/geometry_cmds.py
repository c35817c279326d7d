"""``imageform project``: project 3-D points from a CSV through a camera."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import typer

__all__ = ["load_camera_toml", "register"]

_CAMERA_KEYS = {"fx", "fy", "cx", "cy", "skew", "width", "height", "rvec", "R", "t", "image_plane"}
# distortion written by `imageform calibrate` (accepted; `project` ignores it for now)
_CAMERA_KEYS |= {"k1", "k2", "p1", "p2", "k3"}


def load_camera_toml(path: Path) -> Any:
    """A :class:`~imageform.geometry.Camera` from a TOML file.

    Keys (top level or in a ``[camera]`` table): ``fx, fy, cx, cy`` (pixels), optional
    ``skew``, ``width``, ``height``, ``image_plane`` ("virtual"/"real"), pose as ``rvec``
    (Rodrigues, radians) or ``R`` (3×3 rows), and ``t`` (world-to-camera translation).
    """
    import tomllib

    from imageform.errors import InvalidInputError
    from imageform.geometry import Camera, intrinsic_matrix, rvec_to_matrix

    try:
        data = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise InvalidInputError(f"{path}: not valid TOML: {exc}") from exc
    cam = data.get("camera", data)
    unknown = set(cam) - _CAMERA_KEYS
    if unknown:
        raise InvalidInputError(
            f"{path}: unknown camera key(s) {sorted(unknown)}; valid: {sorted(_CAMERA_KEYS)}"
        )
    missing = [k for k in ("fx", "fy", "cx", "cy") if k not in cam]
    if missing:
        raise InvalidInputError(f"{path}: missing camera key(s) {missing}")
    if "rvec" in cam and "R" in cam:
        raise InvalidInputError(f"{path}: give the rotation as rvec or R, not both")
    K = intrinsic_matrix(cam["fx"], cam["fy"], cam["cx"], cam["cy"], cam.get("skew", 0.0))
    identity = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
    R = rvec_to_matrix(cam["rvec"]) if "rvec" in cam else cam.get("R", identity)
    size = (cam["width"], cam["height"]) if "width" in cam and "height" in cam else None
    return Camera(K, R, cam.get("t", [0.0, 0.0, 0.0]), size, cam.get("image_plane", "virtual"))


def _read_points(path: Path) -> Any:
    import numpy as np

    from imageform.errors import InvalidInputError

    rows: list[list[float]] = []
    with path.open(newline="") as fh:
        for lineno, row in enumerate(csv.reader(fh), start=1):
            if not row or row[0].lstrip().startswith("#"):
                continue
            try:
                vals = [float(v) for v in row]
            except ValueError:
                if not rows and lineno == 1:
                    continue  # a header line
                raise InvalidInputError(f"{path}:{lineno}: expected numbers, got {row}") from None
            if len(vals) != 3:
                raise InvalidInputError(
                    f"{path}:{lineno}: expected 3 columns (X, Y, Z), got {len(vals)}"
                )
            rows.append(vals)
    if not rows:
        raise InvalidInputError(f"{path}: no points")
    return np.asarray(rows)


def project(
    points_csv: Path = typer.Argument(..., help="CSV of X, Y, Z per line (a header is allowed)."),
    out: Path = typer.Option(..., "--out", "-o", help="Output CSV: u, v, valid."),
    camera: Path | None = typer.Option(None, help="Camera TOML (fx, fy, cx, cy, rvec/R, t ...)."),
    fx: float | None = typer.Option(None, help="Focal length in pixels (x)."),
    fy: float | None = typer.Option(None, help="Focal length in pixels (y); default fx."),
    cx: float = typer.Option(0.0, help="Principal point column."),
    cy: float = typer.Option(0.0, help="Principal point row."),
    skew: float = typer.Option(0.0, help="Skew."),
    force: bool = typer.Option(False, "--force", help="Overwrite an existing output."),
    json_out: bool = typer.Option(False, "--json", help="Print a JSON summary."),
) -> None:
    """Project 3-D points through a pinhole camera; z <= 0 is written as NaN with valid=0."""
    import numpy as np

    from imageform.cli._common import check_output_path, print_json
    from imageform.errors import InvalidInputError
    from imageform.geometry import Camera, intrinsic_matrix

    if camera is not None and fx is not None:
        raise InvalidInputError("give the camera as --camera FILE or as --fx ..., not both")
    if camera is None and fx is None:
        raise InvalidInputError("give the camera as --camera FILE or --fx/--fy/--cx/--cy")
    check_output_path(out, inputs=(points_csv,) + ((camera,) if camera else ()), force=force)
    if camera is not None:
        cam = load_camera_toml(camera)
    else:
        assert fx is not None
        cam = Camera(intrinsic_matrix(fx, fy if fy is not None else fx, cx, cy, skew))
    X = _read_points(points_csv)
    uv, valid = cam.project(X)
    with out.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["u", "v", "valid"])
        for (u, v), ok in zip(uv, valid, strict=True):
            w.writerow([repr(float(u)), repr(float(v)), int(ok)])
    summary = {"points": len(X), "valid": int(np.sum(valid)), "output": str(out)}
    if json_out:
        print_json(summary)
    else:
        typer.echo(f"projected {summary['points']} points ({summary['valid']} in front) -> {out}")


def register(app: typer.Typer) -> None:
    app.command("project")(project)
