"""``imageform chart``: find a ColorChecker in an uncropped photograph and fit a correction.

It measures the patches and fits the colour correction to the chart's published sRGB values
(docs/howto-color-chart.md).

Writes a JSON file (``kind: "colorchecker"``): the chart's corners and homography, every
patch's centre, sampling quad, mean and flags, the correction (the fit ``fit-correction``
does, measured -> reference) and CIEDE2000 per patch before and after. ``--correction``
also writes the correction alone, the file ``imageform harmonize --correction`` reads;
``--csv`` the table of the usable patches, whose ``a_*``/``b_*`` columns
``imageform fit-correction`` reads;
``--overlay`` the photograph with the detected lattice drawn over it.

A separate command rather than a ``--detect`` option of ``fit-correction``: that command
pairs two charts (device A, device B) and takes a CSV, while a photograph of a ColorChecker
is corrected against the chart's published values, and its detection has outputs of its
own (corners, overlay) that ``fit-correction`` has no place for.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, get_args

from imageform.errors import InvalidInputError
from imageform.workflows._images import ImageIn, patches_in_srgb, read
from imageform.workflows._spec import Input, Output, Result, Run, Workflow, check_suffix, option

__all__ = ["WORKFLOWS", "ChartOptions"]


#: Values of a chart correction's ``--method`` (also ``fit-correction``, ``harmonize``):
#: a 3x3 matrix in linear light or root-polynomial.
CorrectionMethod = Literal["linear", "root_polynomial"]


@dataclass(frozen=True, kw_only=True)
class ChartOptions(ImageIn):
    """Options of ``imageform chart``."""

    method: CorrectionMethod = option(
        "linear",
        help="Correction model: linear (3x3 in linear light) or root-polynomial.",
        choices=get_args(CorrectionMethod),
    )
    degree: int = option(2, help="Root-polynomial degree (1 to 3).")
    min_score: float = option(
        0.8, help="Least R^2 of the colour fit that accepts a chart (0 to 1)."
    )
    max_size: int = option(1024, help="Long side of the working image of the detection (pixels).")
    overlay: Path | None = option(
        None, help="Also write the photograph with the detected chart drawn (PNG).", output=True
    )
    csv: Path | None = option(
        None,
        help="Also write the patch table (CSV; fit-correction reads its a_*/b_* columns).",
        output=True,
    )
    correction: Path | None = option(
        None,
        help="Also write the correction alone (.json, read by harmonize --correction).",
        output=True,
    )
    src: str = option(
        "auto",
        flag="--from",
        help=(
            "RGB space of the photograph; auto: the one the file declares (ICC profile, "
            "EXIF), else srgb. The patch means are brought to sRGB from it."
        ),
        metavar="SPACE",
    )

    def check(self) -> None:
        """Check ``--degree`` (1 to 3), ``--max-size``, ``--min-score`` (-1 to 1), ``--from``."""
        from imageform._validate import as_int, as_real
        from imageform.workflows._images import rgb_space_or_auto

        super().check()
        check_suffix(self.csv, ".csv", "--csv", "the patch table (CSV)")
        check_suffix(self.correction, ".json", "--correction", "the correction (JSON)")
        as_int(self.degree, "--degree", minimum=1, maximum=3)
        as_int(self.max_size, "--max-size", minimum=64, maximum=100_000)
        as_real(self.min_score, "--min-score", minimum=-1.0, maximum=1.0)
        src = rgb_space_or_auto(self.src, "a photograph of a chart is encoded RGB")
        object.__setattr__(self, "src", src)


def _draw(img: Any, polylines: list[Any], colour: tuple[float, float, float]) -> None:
    """Draw closed polylines (K, 2) of (u, v) points in place, 2 pixels wide."""
    import numpy as np

    hgt, wid = img.shape[:2]
    for poly in polylines:
        pts = np.asarray(poly, dtype=np.float64)
        for a, b in zip(pts, np.roll(pts, -1, axis=0), strict=True):
            n = int(np.ceil(np.abs(b - a).max())) * 2 + 2
            t = np.linspace(0.0, 1.0, n)[:, None]
            seg = a + t * (b - a)
            for du in (0, 1):
                for dv in (0, 1):
                    u = np.round(seg[:, 0]).astype(int) + du
                    v = np.round(seg[:, 1]).astype(int) + dv
                    ok = (u >= 0) & (u < wid) & (v >= 0) & (v < hgt)
                    img[v[ok], u[ok]] = colour


def _overlay(rgb: Any, det: Any, valid: Any) -> Any:
    import numpy as np

    out = np.array(rgb, dtype=np.float64, copy=True)
    _draw(out, [det.corners], (1.0, 0.9, 0.0))
    _draw(out, [q for q, ok in zip(det.quads, valid, strict=True) if ok], (0.0, 1.0, 0.2))
    _draw(out, [q for q, ok in zip(det.quads, valid, strict=True) if not ok], (1.0, 0.0, 0.0))
    # the first patch (dark skin, top left of the upright chart) marked by a cross
    c = det.centers[0]
    r = 0.25 * float(np.linalg.norm(det.centers[1] - det.centers[0]))
    _draw(
        out,
        [np.array([c - [r, 0], c + [r, 0]]), np.array([c - [0, r], c + [0, r]])],
        (1.0, 1.0, 1.0),
    )
    return out


def _write_csv(path: Path, det: Any, pat: Any, ref: Any) -> None:
    """Write the usable patches (saturated and missing ones left out), one row each."""
    import csv

    import numpy as np

    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["patch", "u", "v", "a_r", "a_g", "a_b", "b_r", "b_g", "b_b", "valid"])
        for k in np.flatnonzero(pat.valid):
            w.writerow(
                [k, f"{det.centers[k, 0]:.3f}", f"{det.centers[k, 1]:.3f}"]
                + [f"{x:.6f}" for x in pat.means[k]]
                + [f"{x:.6f}" for x in ref[k]]
                + [int(pat.valid[k])]
            )


def chart(run: Run, opts: ChartOptions, *, out: Path, image: Path) -> Result:
    """``imageform chart``: detect the ColorChecker, measure it, fit the correction."""
    import warnings

    import numpy as np

    from imageform._jsonio import write_json
    from imageform.analysis import (
        ChartNotFoundError,
        ChartPatches,
        ChartWarning,
        correction_report,
        detect_colorchecker,
        fit_color_correction,
        measure_chart_patches,
    )
    from imageform.analysis.synthetic import COLORCHECKER_SRGB8
    from imageform.io import write_image

    img = read(image, opts, colours=True)
    if img.ndim != 3 or img.shape[-1] != 3:
        raise InvalidInputError(f"{image}: expected an RGB image, got shape {img.shape}")
    det = detect_colorchecker(img, max_size=opts.max_size, min_score=opts.min_score)
    if not det.found:
        raise ChartNotFoundError(f"no ColorChecker found in the image: {det.reason}")
    space = opts.src
    if space == "auto":
        from imageform.io import image_color_space
        from imageform.workflows._images import declared_space

        space = declared_space(run, image, image_color_space(image), grey=False)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ChartWarning)
        pat = measure_chart_patches(img, det, max_std=_MAX_STD)
        pat = patches_in_srgb(pat, space)  # the means as sRGB values (floats: none clipped)
        ref = np.asarray(COLORCHECKER_SRGB8, dtype=np.float64) / 255.0
        means = np.where(np.isfinite(pat.means), pat.means, 0.0)
        filled = ChartPatches(means, pat.std, pat.saturated, pat.missing, pat.used)
        corr = fit_color_correction(filled, ref, opts.method, opts.degree)
        rep = correction_report(filled, ref, corr)
    left_out = _left_out(det, pat)
    for w in caught:  # measure_chart_patches' own counts overlap: one note below instead
        if not str(w.message).startswith("measure_chart_patches:"):
            run.note(f"note: {w.message}")
    n_out = sum(len(v) for v in left_out.values())
    if n_out:
        why = ", ".join(f"{len(idx)} {_REASONS[k]} {idx}" for k, idx in left_out.items() if idx)
        run.note(f"note: {n_out} of {len(pat.valid)} patches left out of the fit: {why} (0-based)")
    fallback = next(
        (str(w.message) for w in caught if str(w.message).startswith("fit_color_correction: the")),
        None,
    )
    stats = rep.summary()
    payload = {
        "kind": "colorchecker",
        "image": str(image),
        "image_size": [int(img.shape[1]), int(img.shape[0])],
        "image_space": space,
        "chart": det.to_dict(),
        "patches": {
            "means_srgb": pat.means.tolist(),
            "std": pat.std.tolist(),
            "saturated": pat.saturated.tolist(),
            "missing": pat.missing.tolist(),
            "reference_srgb": ref.tolist(),
        },
        "correction": {
            "method": corr.method,
            "degree": int(corr.degree),
            "transfer": corr.transfer,
            "matrix": corr.matrix.tolist(),
            "n_patches": int(corr.n_patches),
            "requested": {"method": opts.method, "degree": int(opts.degree)},
            "fallback": fallback,
        },
        "delta_e00_before": rep.delta_e_before.tolist(),
        "delta_e00_after": rep.delta_e_after.tolist(),
        **stats,
    }
    write_json(run.file(out), payload)
    if opts.correction is not None:
        corr.to_json(run.file(opts.correction))
    if opts.csv is not None:
        _write_csv(run.file(opts.csv), det, pat, ref)
    if opts.overlay is not None:
        ov = _overlay(np.asarray(img, dtype=np.float64) / _scale(img), det, pat.valid)
        write_image(run.file(opts.overlay), np.round(np.clip(ov, 0, 1) * 255).astype(np.uint8))
    summary = {
        "input": image,
        "output": out,
        "overlay": opts.overlay,
        "csv": opts.csv,
        "correction": opts.correction,
        "score": det.score,
        "rotation_degrees": det.rotation,
        "mirrored": det.mirrored,
        "corners": det.corners,
        "patches_found": int(det.segmented.sum()),
        "patches_valid": int(pat.valid.sum()),
        "patches_left_out": left_out,
        "method": corr.method,
        "degree": corr.degree,
        "delta_e00_before": rep.delta_e_before,
        "delta_e00_after": rep.delta_e_after,
        **stats,
    }
    text = [
        f"ColorChecker found{' mirrored' if det.mirrored else ''}: score R2 {det.score:.4f}, "
        f"rotation {det.rotation:.1f} deg, "
        f"{int(det.segmented.sum())} of 24 patches segmented, {int(pat.valid.sum())} usable"
        + (f", {n_out} left out" if n_out else ""),
        "corners (u, v): " + ", ".join(f"({u:.1f}, {v:.1f})" for u, v in det.corners),
        f"{corr.method} (degree {corr.degree}) correction to the chart's sRGB values, "
        f"fitted on {corr.n_patches} patches",
        f"ΔE00 mean {stats['mean_before']:.3f} -> {stats['mean_after']:.3f}, "
        f"max {stats['max_before']:.3f} -> {stats['max_after']:.3f}",
        f"wrote {out}",
    ]
    return Result(summary, tuple(text))


#: Largest per-channel standard deviation of a flat patch (encoded, [0, 1] scale).
_MAX_STD = 0.04
#: Why a patch is left out of the fit, in the order a patch is counted (each once).
_REASONS = {
    "outside_image": "outside the image",
    "colour_outlier": "colour outlier(s) (occluded?)",
    "saturated": "saturated",
    "not_flat": f"not flat (a channel's std above {_MAX_STD:g})",
}


def _left_out(det: Any, pat: Any) -> dict[str, list[int]]:
    """Return the patches left out of the fit by reason, each patch under one reason only.

    ``measure_chart_patches`` counts a saturated patch that is also not flat twice (as
    saturated and as missing): here the first reason of :data:`_REASONS` that applies.
    """
    import numpy as np

    empty = ~np.isfinite(np.asarray(pat.means)).all(axis=1)
    outlier = np.asarray(det.outliers, dtype=bool) & ~empty
    saturated = np.asarray(pat.saturated, dtype=bool) & ~empty & ~outlier
    not_flat = np.asarray(pat.missing, dtype=bool) & ~empty & ~outlier & ~saturated
    masks = {"outside_image": empty, "colour_outlier": outlier}
    masks |= {"saturated": saturated, "not_flat": not_flat}
    return {k: np.flatnonzero(m).tolist() for k, m in masks.items()}


def _scale(img: Any) -> float:
    import numpy as np

    dt = np.asarray(img).dtype
    return 255.0 if dt == np.uint8 else 65535.0 if dt == np.uint16 else 1.0


WORKFLOWS = (
    Workflow(
        "chart",
        "Find a ColorChecker in a photograph, measure its patches, fit the colour correction.",
        "imageform.workflows.chart:chart",
        ChartOptions,
        (Input("image", "Photograph with a ColorChecker Classic (24 patches) anywhere in it."),),
        Output("Result to write (.json): corners, patches, correction, ΔE00 before/after."),
        suffixes=(".json",),
        group="analysis",
    ),
)
