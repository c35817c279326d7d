"""Optics workflows: ``imageform lens`` (thin-lens depth of field by f-number)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from imageform.errors import InvalidInputError
from imageform.workflows._spec import Options, Result, Run, Workflow, option

__all__ = ["STOPS", "WORKFLOWS", "LensOptions"]

#: The full f-stops of the table (the chosen f-number is added).
STOPS = (1.4, 2.0, 2.8, 4.0, 5.6, 8.0, 11.0, 16.0, 22.0)


@dataclass(frozen=True, kw_only=True)
class LensOptions(Options):
    """Options of ``imageform lens`` (lengths with a unit; see imageform._units)."""

    focal: str | float = option(
        help="Focal length with a unit: 50mm, 5cm, 0.05m (a bare number is in mm).",
        metavar="LENGTH",
    )
    f_number: float = option(help="f-number N = f / D, e.g. 2.8.", metavar="N")
    focus: str | float = option(
        help="Focus distance from the lens with a unit: 2m, 0.5 m, 500mm, 6ft (a bare number is "
        "in m).",
        metavar="LENGTH",
    )
    coc: str | float = option(
        "0.03mm",
        help="Circle of confusion diameter with a unit: 0.03mm, 30um (a bare number is in mm).",
        metavar="LENGTH",
    )

    def check(self) -> None:
        """Check the lengths and that ``--f-number`` is finite and > 0."""
        super().check()
        self.lengths()
        if not (math.isfinite(self.f_number) and self.f_number > 0):
            raise InvalidInputError(f"expected --f-number > 0, got {self.f_number:g}")

    def lengths(self) -> tuple[float, float, float]:
        """Focal length, focus distance and circle of confusion in metres."""
        from imageform._units import parse_length

        return (
            parse_length(self.focal, "--focal", default_unit="mm"),
            parse_length(self.focus, "--focus", default_unit="m"),
            parse_length(self.coc, "--coc", default_unit="mm"),
        )


def _bare_notes(opts: LensOptions) -> list[str]:
    """Return notes for bare numbers that look given in the other unit (--focus 2000)."""
    notes = []
    focal, focus = _bare(opts.focal), _bare(opts.focus)
    if focus is not None and focus >= 100:
        notes.append(
            f"note: --focus {focus:g} is read as {focus:g} m (a bare --focus is in metres); "
            f"write {focus:g}mm for millimetres"
        )
    if focal is not None and focal < 1:
        notes.append(
            f"note: --focal {focal:g} is read as {focal:g} mm (a bare --focal is in "
            f"millimetres); write {focal:g}m for metres"
        )
    return notes


def _bare(value: str | float) -> float | None:
    """Return the number of a length given without a unit, else None."""
    try:
        return float(str(value).strip())
    except ValueError:
        return None


def _fmt(x: float) -> str:
    return "inf" if math.isinf(x) else f"{x:.3f} m"


def lens(run: Run, opts: LensOptions, *, out: None) -> Result:
    """``imageform lens``: near and far limits of sharpness, hyperfocal distance, per f-stop."""
    from rich.table import Table

    from imageform.optics import aperture_diameter, depth_of_field, thin_lens

    f, s, c = opts.lengths()
    for note in _bare_notes(opts):
        run.note(note)
    n = float(opts.f_number)
    if s == f:
        raise InvalidInputError(
            f"--focus {s:g} m equals the focal length: the image forms at infinity"
        )
    if s < f:
        raise InvalidInputError(
            f"--focus {s:g} m is inside the focal length {f:g} m: the lens forms no real image "
            "there, only a virtual upright one on the object's side (as a magnifying glass), "
            "which no sensor can record; focus beyond the focal length"
        )
    dof = depth_of_field(focal_length=f, f_number=n, focus=s, coc=c)
    sol = thin_lens(focal_length=f, d_o=s)
    rows: list[dict[str, Any]] = []
    for stop in sorted({*STOPS, n}):
        d = depth_of_field(focal_length=f, f_number=stop, focus=s, coc=c)
        rows.append(
            {
                "f_number": stop,
                "near_m": d.near,
                "far_m": d.far,
                "total_m": d.total,
                "hyperfocal_m": d.hyperfocal,
            }
        )
    diameter = aperture_diameter(focal_length=f, f_number=n)
    summary = {
        "focal_length_m": f,
        "f_number": n,
        "focus_m": s,
        "coc_m": c,
        "aperture_diameter_m": diameter,
        "image_distance_m": sol.d_i,
        "magnification": sol.magnification,
        "hyperfocal_m": dof.hyperfocal,
        "near_m": dof.near,
        "far_m": dof.far,
        "total_m": dof.total,
        "in_front_m": dof.in_front,
        "behind_m": dof.behind,
        "table": rows,
    }
    head = [
        f"f = {f * 1e3:g} mm, N = {n:g} (D = {diameter * 1e3:.2f} mm), "
        f"focus {s:g} m, c = {c * 1e3:g} mm",
        f"image distance {sol.d_i * 1e3:.3f} mm, magnification {sol.magnification:.5f}",
        f"hyperfocal {dof.hyperfocal:.3f} m; sharp from {_fmt(dof.near)} to {_fmt(dof.far)} "
        f"(depth of field {_fmt(dof.total)}: {_fmt(dof.in_front)} in front, "
        f"{_fmt(dof.behind)} behind)",
    ]
    t = Table(title=f"Depth of field at {s:g} m by f-number")
    for col in ("f-number", "near", "far", "total", "hyperfocal"):
        t.add_column(col, justify="right")
    for row in rows:
        mark = " *" if row["f_number"] == n else ""
        t.add_row(
            f"f/{row['f_number']:g}{mark}",
            _fmt(row["near_m"]),
            _fmt(row["far_m"]),
            _fmt(row["total_m"]),
            _fmt(row["hyperfocal_m"]),
        )
    return Result(summary, (*head, t))


WORKFLOWS = (
    Workflow(
        "lens",
        "Depth of field of a thin lens: near and far limits, hyperfocal distance, per f-stop.",
        "imageform.workflows.optics:lens",
        LensOptions,
        (),
        None,
        suffixes=(),
        group="optics",
        description="Lengths take a unit (50mm, 2m, 0.5 m, 0.03mm, 1in; m, cm, mm, um, nm, in, "
        "ft); a bare number keeps its old meaning: mm for --focal and --coc, m for --focus. "
        "--json gives every length in metres (keys ending _m) and an infinite far limit as null.",
    ),
)
