"""``imageform lens`` (depth-of-field table) and ``imageform undistort`` (remove distortion)."""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Annotated, Any

import typer

from imageform.errors import InvalidInputError, UnknownOptionError

__all__ = ["load_camera_toml", "parse_length", "register"]

_UNITS = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "in": 0.0254, "ft": 0.3048}
_STOPS = (1.4, 2.0, 2.8, 4.0, 5.6, 8.0, 11.0, 16.0, 22.0)


def parse_length(text: str, name: str, *, default_unit: str = "m") -> float:
    """``"50mm"`` → 0.05 (metres); ``"inf"`` → ``math.inf``; a bare number is ``default_unit``.

    >>> parse_length("50mm", "focal"), parse_length("2", "focus")
    (0.05, 2.0)
    """
    t = text.strip().lower().replace(" ", "")
    if t in ("inf", "infinity"):
        return math.inf
    m = re.fullmatch(r"([-+]?(?:\d+\.?\d*|\.\d+)(?:e[-+]?\d+)?)([a-zµ]*)", t)
    if not m:
        raise InvalidInputError(
            f"expected {name} as a number with a unit (e.g. 50mm, 2m, 0.03mm), got {text!r}"
        )
    unit = m.group(2) or default_unit
    if unit not in _UNITS:
        raise UnknownOptionError(
            f"unknown unit {unit!r} for {name}; valid: {', '.join(sorted(_UNITS))}"
        )
    return float(m.group(1)) * _UNITS[unit]


def _finite_or_none(obj: Any) -> Any:
    """JSON has no infinity: ``inf`` (an infinite far limit) becomes ``null``."""
    if isinstance(obj, dict):
        return {k: _finite_or_none(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_finite_or_none(v) for v in obj]
    if isinstance(obj, float) and math.isinf(obj):
        return None
    return obj


def _fmt(x: float) -> str:
    return "inf" if math.isinf(x) else f"{x:.3f} m"


def lens(
    focal: str = typer.Option(..., "--focal", help="Focal length, e.g. 50mm."),
    f_number: float = typer.Option(..., "--f-number", help="f-number N = f/D, e.g. 2.8."),
    focus: str = typer.Option(..., "--focus", help="Focus distance from the lens, e.g. 2m."),
    coc: str = typer.Option("0.03mm", "--coc", help="Circle of confusion diameter, e.g. 0.03mm."),
    json_out: bool = typer.Option(False, "--json", help="Print machine-readable results."),
) -> None:
    """Depth of field of a thin lens: near and far limits, hyperfocal distance, per f-stop."""
    from imageform.optics import aperture_diameter, depth_of_field, thin_lens

    f = parse_length(focal, "--focal", default_unit="mm")
    s = parse_length(focus, "--focus")
    c = parse_length(coc, "--coc", default_unit="mm")
    if math.isinf(s):
        raise InvalidInputError("--focus must be finite; for infinity focus use the hyperfocal row")
    if s <= f:
        thin_lens(f=f, d_o=s)  # raises the explanatory virtual-image / infinity error
    dof = depth_of_field(f, f_number, s, c)
    sol = thin_lens(f=f, d_o=s)
    stops = sorted({*_STOPS, float(f_number)})
    table = []
    for n in stops:
        d = depth_of_field(f, n, s, c)
        table.append(
            {
                "f_number": n,
                "near_m": d.near,
                "far_m": d.far,
                "total_m": d.total,
                "hyperfocal_m": d.hyperfocal,
            }
        )
    result = {
        "focal_length_m": f,
        "f_number": float(f_number),
        "focus_m": s,
        "coc_m": c,
        "aperture_diameter_m": aperture_diameter(f, f_number),
        "image_distance_m": sol.d_i,
        "magnification": sol.magnification,
        "hyperfocal_m": dof.hyperfocal,
        "near_m": dof.near,
        "far_m": dof.far,
        "total_m": dof.total,
        "in_front_m": dof.in_front,
        "behind_m": dof.behind,
        "table": table,
    }
    if json_out:
        from imageform.cli._common import print_json

        print_json(_finite_or_none(result))
        return
    from rich.console import Console
    from rich.table import Table

    con = Console(width=110)
    con.print(
        f"f = {f * 1e3:g} mm, N = {f_number:g} "
        f"(D = {aperture_diameter(f, f_number) * 1e3:.2f} mm), "
        f"focus {s:g} m, c = {c * 1e3:g} mm\n"
        f"image distance {sol.d_i * 1e3:.3f} mm, magnification {sol.magnification:.5f}\n"
        f"hyperfocal {dof.hyperfocal:.3f} m; sharp from {_fmt(dof.near)} to {_fmt(dof.far)} "
        f"(depth of field {_fmt(dof.total)}: {_fmt(dof.in_front)} in front, "
        f"{_fmt(dof.behind)} behind)"
    )
    t = Table(title=f"Depth of field at {s:g} m by f-number")
    for col in ("f-number", "near", "far", "total", "hyperfocal"):
        t.add_column(col, justify="right")
    for row in table:
        mark = " *" if row["f_number"] == float(f_number) else ""
        t.add_row(
            f"f/{row['f_number']:g}{mark}",
            _fmt(row["near_m"]),
            _fmt(row["far_m"]),
            _fmt(row["total_m"]),
            _fmt(row["hyperfocal_m"]),
        )
    con.print(t)


_CAMERA_KEYS = {
    "fx",
    "fy",
    "cx",
    "cy",
    "skew",
    "model",
    "k1",
    "k2",
    "k3",
    "k4",
    "k5",
    "k6",
    "p1",
    "p2",
}
_MODELS = {
    "brown_conrady": ("k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"),
    "kannala_brandt": ("k1", "k2", "k3", "k4"),
    "division": ("k1", "k2"),
}


def load_camera_toml(path: Path) -> tuple[Any, Any]:
    """Read ``K`` and a distortion model from a camera TOML file.

    Keys (top level or in a ``[camera]`` table): ``fx, fy, cx, cy`` (pixels, required),
    ``skew`` (default 0), ``model`` (``brown_conrady`` default, ``kannala_brandt``,
    ``division``) and that model's coefficients (``k1, k2, p1, p2, k3, k4, k5, k6`` /
    ``k1..k4`` / ``k1, k2``; missing ones are 0).
    """
    import tomllib

    import numpy as np

    from imageform._validate import check_option
    from imageform.geometry.distortion import BrownConrady, DivisionModel, KannalaBrandt

    if not path.is_file():
        raise InvalidInputError(f"camera file {path} does not exist")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise InvalidInputError(f"{path} is not valid TOML: {exc}") from exc
    cam = data.get("camera", data)
    if not isinstance(cam, dict):
        raise InvalidInputError(f"{path}: [camera] must be a table")
    unknown = set(cam) - _CAMERA_KEYS
    if unknown:
        raise UnknownOptionError(
            f"{path}: unknown key(s) {', '.join(sorted(unknown))}; valid: "
            f"{', '.join(sorted(_CAMERA_KEYS))}"
        )
    missing = [k for k in ("fx", "fy", "cx", "cy") if k not in cam]
    if missing:
        raise InvalidInputError(f"{path}: missing {', '.join(missing)} (pixels)")
    model = check_option(cam.get("model", "brown_conrady"), _MODELS, "distortion model")
    extra = {k for k in cam if k[0] in "kp" and k not in _MODELS[model]}
    if extra:
        raise InvalidInputError(
            f"{path}: {', '.join(sorted(extra))} not part of the {model} model "
            f"({', '.join(_MODELS[model])})"
        )
    try:
        vals = {k: float(cam[k]) for k in cam if k != "model"}
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"{path}: camera values must be numbers ({exc})") from exc
    K = np.array(
        [[vals["fx"], vals.get("skew", 0.0), vals["cx"]], [0.0, vals["fy"], vals["cy"]], [0, 0, 1]]
    )
    if vals["fx"] <= 0 or vals["fy"] <= 0:
        raise InvalidInputError(f"{path}: fx and fy must be > 0 pixels")
    coeffs = {k: vals.get(k, 0.0) for k in _MODELS[model]}
    cls = {
        "brown_conrady": BrownConrady,
        "kannala_brandt": KannalaBrandt,
        "division": DivisionModel,
    }
    return K, cls[model](**coeffs)


def undistort(
    input_path: Annotated[
        Path, typer.Argument(metavar="IN", help="Distorted image (PNG, JPEG, TIFF).")
    ],
    output_path: Annotated[Path, typer.Argument(metavar="OUT", help="Where to write the result.")],
    camera: Annotated[Path, typer.Option("--camera", help="Camera TOML: fx, fy, cx, cy, k1, ...")],
    force: Annotated[bool, typer.Option("--force", help="Overwrite OUT if it exists.")] = False,
    json_out: Annotated[
        bool, typer.Option("--json", help="Print machine-readable results.")
    ] = False,
) -> None:
    """Remove lens distortion (bilinear remap with the camera's K and distortion model)."""
    import numpy as np

    from imageform.cli._common import check_output_path, print_json
    from imageform.cli._image_files import read_image, write_image
    from imageform.geometry.undistort import undistort_image

    check_output_path(output_path, inputs=(input_path, camera), force=force)
    K, model = load_camera_toml(camera)
    img = read_image(input_path)
    out = undistort_image(img, K, model)
    write_image(output_path, out, bits=16 if img.dtype == np.uint16 else 8)
    if json_out:
        print_json(
            {
                "input": str(input_path),
                "output": str(output_path),
                "shape": list(out.shape),
                "model": type(model).__name__,
                "coefficients": list(model.coeffs),
            }
        )
    else:
        typer.echo(f"wrote {output_path} ({out.shape[1]}x{out.shape[0]}, {type(model).__name__})")


def register(app: typer.Typer) -> None:
    app.command("lens")(lens)
    app.command("undistort")(undistort)
