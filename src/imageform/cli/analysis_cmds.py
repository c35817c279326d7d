"""``imageform segment``, ``stain-normalize`` and ``harmonize``: applied colour analysis.

Tissue segmentation by HSV thresholds, stain normalisation (Macenko, Reinhard) and colour
harmonisation between two devices from a chart (see docs/biomedical.md).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import typer

__all__ = ["register"]

_CSV_COLUMNS = ("a_r", "a_g", "a_b", "b_r", "b_g", "b_b")


def _range(text: str, name: str) -> tuple[float, float]:
    from imageform.errors import InvalidInputError

    parts = text.split(":")
    try:
        lo, hi = (float(p) for p in parts)
    except ValueError as exc:
        raise InvalidInputError(f"expected --{name} as LOW:HIGH (e.g. 0:20), got {text!r}") from exc
    return lo, hi


def _read(path: Path) -> Any:
    from imageform.io import read_image

    return read_image(path)


def _write(path: Path, image: Any, *, sixteen: bool, clip: bool) -> int:
    """Write encoded values; returns how many values were outside [0, 1] (clipped if asked)."""
    import numpy as np

    from imageform.io import image_format, write_image

    arr = np.asarray(image)
    outside = int(np.count_nonzero((arr < 0) | (arr > 1)))
    fmt = image_format(path)
    write_image(path, arr, bits=16 if sixteen else 8, clip=clip and fmt == "png")
    return outside


def segment_cmd(
    image_in: Path = typer.Argument(..., help="Input image (sRGB PNG 8/16-bit, TIFF, .npy)."),
    h: str | None = typer.Option(
        None, "--h", help="Hue range LOW:HIGH in degrees (LOW > HIGH wraps); default 0:40."
    ),
    s: str | None = typer.Option(None, "--s", help="Saturation LOW:HIGH; default 30/255:1."),
    v: str | None = typer.Option(None, "--v", help="Value LOW:HIGH; default 80/255:1."),
    opencv_ranges: bool = typer.Option(
        False, "--opencv-ranges", help="Read --h in 0-180 and --s/--v in 0-255 (OpenCV)."
    ),
    open_radius: int = typer.Option(2, help="Opening disc radius (pixels, 0 = none)."),
    close_radius: int = typer.Option(2, help="Closing disc radius (pixels, 0 = none)."),
    min_area: int = typer.Option(64, help="Remove components smaller than this (pixels)."),
    out: Path = typer.Option(..., "--out", help="Mask PNG to write (0 / 255)."),
    overlay: Path | None = typer.Option(None, "--overlay", help="Overlay PNG to write."),
    force: bool = typer.Option(False, "--force", help="Overwrite existing outputs."),
    json_out: bool = typer.Option(False, "--json", help="Print machine-readable results."),
) -> None:
    """Tissue mask by HSV thresholds (the lecture's endoscopy case study)."""
    import warnings

    import numpy as np

    from imageform.analysis import overlay_mask, segment_hsv
    from imageform.cli._common import check_output_path, print_json
    from imageform.io import write_image

    check_output_path(out, inputs=(image_in,), force=force)
    if overlay is not None:
        check_output_path(overlay, inputs=(image_in, out), force=force)
    img = _read(image_in)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        # a range not given: the lecture's (H 0-20, S 30-255, V 80-255 in OpenCV units)
        hh = None if h is None else _range(h, "h")
        ss = None if s is None else _range(s, "s")
        vv = None if v is None else _range(v, "v")
        seg = segment_hsv(
            img,
            hh,
            ss,
            vv,
            opencv_ranges=opencv_ranges,
            open_radius=open_radius,
            close_radius=close_radius,
            min_area=min_area,
        )
    write_image(out, np.where(seg.mask, np.uint8(255), np.uint8(0))[..., None])
    if overlay is not None:
        write_image(overlay, overlay_mask(img, seg.mask), clip=False)
    result = {
        "tissue_fraction": seg.fraction,
        "tissue_pixels": int(seg.mask.sum()),
        "pixels": int(seg.mask.size),
        "h_degrees": list(seg.h),
        "s": list(seg.s),
        "v": list(seg.v),
        "mask": str(out),
        "overlay": None if overlay is None else str(overlay),
        "warnings": [str(w.message) for w in caught],
    }
    if json_out:
        print_json(result)
        return
    wrap = " (wraps through 0)" if seg.wraps else ""
    typer.echo(
        f"hue {seg.h[0]:g}..{seg.h[1]:g} degrees{wrap}, S {seg.s[0]:.4g}..{seg.s[1]:.4g},"
        f" V {seg.v[0]:.4g}..{seg.v[1]:.4g}"
    )
    typer.echo(
        f"tissue fraction {100 * seg.fraction:.2f} % "
        f"({result['tissue_pixels']} of {result['pixels']} pixels); mask: {out}"
    )
    for w in caught:
        typer.echo(f"warning: {w.message}", err=True)


def stain_normalize_cmd(
    image_in: Path = typer.Argument(..., help="Input slide image (RGB)."),
    image_out: Path = typer.Argument(..., help="Output image (PNG 8/16-bit, TIFF float)."),
    method: str = typer.Option("macenko", help="macenko or reinhard."),
    target: Path = typer.Option(..., "--target", help="Reference image or saved stats JSON."),
    save_target: Path | None = typer.Option(
        None, "--save-target", help="Save the target's statistics as JSON."
    ),
    clip: bool = typer.Option(False, "--clip", help="Clip to [0, 1] for PNG output."),
    force: bool = typer.Option(False, "--force", help="Overwrite an existing output."),
    json_out: bool = typer.Option(False, "--json", help="Print machine-readable results."),
) -> None:
    """Stain normalisation: Macenko (optical density) or Reinhard (CIELAB statistics)."""
    import numpy as np

    from imageform._validate import check_option
    from imageform.analysis import (
        MacenkoStains,
        ReinhardStats,
        macenko_normalize,
        macenko_stains,
        reinhard_normalize,
        reinhard_stats,
    )
    from imageform.cli._common import check_output_path, print_json

    key = check_option(method, ("macenko", "reinhard"), "stain-normalisation method")
    check_output_path(image_out, inputs=(image_in, target), force=force)
    if save_target is not None:
        check_output_path(save_target, inputs=(image_in, target, image_out), force=force)
    img = _read(image_in)
    stats: Any
    if target.suffix.lower() == ".json":
        stats = (
            MacenkoStains.from_json(target) if key == "macenko" else ReinhardStats.from_json(target)
        )
    else:
        ref = _read(target)
        stats = macenko_stains(ref) if key == "macenko" else reinhard_stats(ref)
    out = macenko_normalize(img, stats) if key == "macenko" else reinhard_normalize(img, stats)
    outside = _write(image_out, out, sixteen=img.dtype == np.uint16, clip=clip)
    if save_target is not None:
        stats.to_json(save_target)
    payload: dict[str, Any] = {
        "method": key,
        "output": str(image_out),
        "values_outside_0_1": outside,
    }
    if key == "macenko":
        payload["target_stain_matrix"] = np.asarray(stats.stain_matrix).tolist()
        payload["target_max_concentrations"] = np.asarray(stats.max_concentrations).tolist()
    else:
        payload["target_lab_mean"] = list(stats.mean)
        payload["target_lab_std"] = list(stats.std)
    if json_out:
        print_json(payload)
        return
    typer.echo(f"{key}: wrote {image_out}")
    if outside:
        typer.echo(f"note: {outside} values outside [0, 1]" + (" were clipped" if clip else ""))


def _patches_csv(path: Path) -> tuple[Any, Any]:
    import csv

    import numpy as np

    from imageform.errors import InvalidInputError

    if not path.is_file():
        raise InvalidInputError(f"patch CSV {path} does not exist")
    with path.open(newline="") as fh:
        reader = csv.DictReader(fh)
        missing = [c for c in _CSV_COLUMNS if c not in (reader.fieldnames or [])]
        if missing:
            raise InvalidInputError(
                f"expected CSV columns {', '.join(_CSV_COLUMNS)} in {path}; missing {missing}"
            )
        try:
            rows = [[float(r[c]) for c in _CSV_COLUMNS] for r in reader]
        except ValueError as exc:
            raise InvalidInputError(f"non-numeric value in {path}: {exc}") from exc
    arr = np.asarray(rows, dtype=np.float64).reshape((-1, 6))
    return arr[:, :3], arr[:, 3:]


def harmonize_cmd(
    chart_a: Path | None = typer.Option(None, "--chart-a", help="Chart imaged on device A."),
    chart_b: Path | None = typer.Option(None, "--chart-b", help="Chart on device B (reference)."),
    patches_csv: Path | None = typer.Option(
        None, "--patches-csv", help="Patch values instead of charts: a_r,a_g,a_b,b_r,b_g,b_b."
    ),
    rows: int = typer.Option(4, help="Chart rows (the chart fills the frame)."),
    cols: int = typer.Option(6, help="Chart columns."),
    method: str = typer.Option("linear", help="linear or root-polynomial."),
    degree: int = typer.Option(2, help="Root-polynomial degree (1-3)."),
    apply: tuple[Path, Path] | None = typer.Option(
        None, "--apply", help="IN OUT: correct an image from device A."
    ),
    save: Path | None = typer.Option(None, "--save", help="Save the correction as JSON."),
    clip: bool = typer.Option(False, "--clip", help="Clip the corrected image for PNG output."),
    force: bool = typer.Option(False, "--force", help="Overwrite existing outputs."),
    json_out: bool = typer.Option(False, "--json", help="Print machine-readable results."),
) -> None:
    """Fit a colour correction from device A's chart to device B's; ΔE00 per patch."""
    import warnings

    import numpy as np

    from imageform.analysis import chart_patches, correction_report, fit_color_correction
    from imageform.cli._common import check_output_path, print_json
    from imageform.errors import InvalidInputError

    inputs = tuple(p for p in (chart_a, chart_b, patches_csv) if p is not None)
    if apply is not None:
        inputs = (*inputs, apply[0])
        check_output_path(apply[1], inputs=inputs, force=force)
    if save is not None:
        check_output_path(save, inputs=inputs, force=force)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        if patches_csv is not None:
            if chart_a is not None or chart_b is not None:
                raise InvalidInputError("give --patches-csv or --chart-a/--chart-b, not both")
            a, b = _patches_csv(patches_csv)
            pa: Any = a
            pb: Any = b
        elif chart_a is not None and chart_b is not None:
            pa = chart_patches(_read(chart_a), rows, cols)
            pb = chart_patches(_read(chart_b), rows, cols)
            a, b = pa.means, pb.means
        else:
            raise InvalidInputError("expected --chart-a and --chart-b, or --patches-csv")
        corr = fit_color_correction(pa, pb, method.replace("-", "_"), degree)
    rep = correction_report(pa, pb, corr)
    summary = rep.summary()
    if save is not None:
        corr.to_json(save)
    outside = None
    if apply is not None:
        img = _read(apply[0])
        outside = _write(apply[1], corr.apply(img), sixteen=img.dtype == np.uint16, clip=clip)
    if json_out:
        print_json(
            {
                "method": corr.method,
                "degree": corr.degree,
                "patches": len(a),
                "patches_fitted": corr.n_patches,
                "delta_e00_before": rep.delta_e_before,
                "delta_e00_after": rep.delta_e_after,
                "patch_valid": rep.valid,
                **summary,
                "matrix": corr.matrix,
                "saved": None if save is None else str(save),
                "applied": None if apply is None else str(apply[1]),
                "values_outside_0_1": outside,
                "warnings": [str(w.message) for w in caught],
            }
        )
        return
    typer.echo(
        f"{corr.method} (degree {corr.degree}) fitted on {corr.n_patches} of {len(a)} "
        "patches, in linear light"
    )
    typer.echo("patch  ΔE00 before  after")
    for i, (x, y) in enumerate(zip(rep.delta_e_before, rep.delta_e_after, strict=True)):
        flag = "" if rep.valid[i] else "  (left out: saturated or missing)"
        typer.echo(f"{i:5d}  {x:11.3f}  {y:5.3f}{flag}")
    typer.echo(f"mean   {summary['mean_before']:11.3f}  {summary['mean_after']:5.3f}")
    typer.echo(f"max    {summary['max_before']:11.3f}  {summary['max_after']:5.3f}")
    for w in caught:
        typer.echo(f"warning: {w.message}", err=True)
    if apply is not None:
        typer.echo(f"corrected {apply[0]} -> {apply[1]}")


def register(app: typer.Typer) -> None:
    app.command("segment")(segment_cmd)
    app.command("stain-normalize")(stain_normalize_cmd)
    app.command("harmonize")(harmonize_cmd)
