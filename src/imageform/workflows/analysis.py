"""Biomedical colour-analysis workflows.

``segment``, ``stain-normalize``, ``fit-correction`` and ``harmonize`` (see docs/biomedical.md).

``fit-correction`` fits a colour correction between two devices from a chart (two chart
images, or a CSV of patch values) and writes it as JSON; ``harmonize`` applies such a file to
an image (and runs file by file in ``imageform batch``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from imageform.errors import InvalidInputError
from imageform.workflows._images import ImageIn, ImageOut, read, write
from imageform.workflows._spec import Input, Output, Result, Run, Workflow, option

__all__ = [
    "WORKFLOWS",
    "FitCorrectionOptions",
    "HarmonizeOptions",
    "SegmentOptions",
    "StainNormalizeOptions",
]

_CSV_COLUMNS = ("a_r", "a_g", "a_b", "b_r", "b_g", "b_b")
#: Stain-normalisation methods; the first is the default everywhere.
STAIN_METHODS = ("macenko", "reinhard")


def _rgb(path: Path, opts: Any) -> Any:
    img = read(path, opts)
    if img.shape[-1] != 3:
        raise InvalidInputError(f"{path}: expected an RGB image, got {img.shape[-1]} channel(s)")
    return img


# ---------------------------------------------------------------- segment


def _range(text: str | None, flag: str) -> tuple[float, float] | None:
    if text is None:
        return None
    import math

    from imageform._validate import describe

    parts = str(text).split(":")
    try:
        lo, hi = (float(p) for p in parts)
    except ValueError:
        lo = hi = math.nan
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise InvalidInputError(
            f"expected {flag} as LOW:HIGH of finite numbers (e.g. 0:20), got {describe(text)}"
        )
    return lo, hi


@dataclass(frozen=True, kw_only=True)
class SegmentOptions(ImageIn):
    """Options of ``imageform segment``."""

    h: str | None = option(
        None,
        help="Hue range LOW:HIGH in degrees (LOW > HIGH wraps); default 0:40.",
        metavar="LO:HI",
    )
    s: str | None = option(None, help="Saturation LOW:HIGH; default 30/255:1.", metavar="LO:HI")
    v: str | None = option(None, help="Value LOW:HIGH; default 80/255:1.", metavar="LO:HI")
    opencv_ranges: bool = option(
        False, help="Read --h in 0-180 and --s/--v in 0-255 (OpenCV's units)."
    )
    open_radius: int = option(
        2, help="Opening disc radius in pixels (0: none).", minimum=0, maximum=1000
    )
    close_radius: int = option(
        2, help="Closing disc radius in pixels (0: none).", minimum=0, maximum=1000
    )
    min_area: int = option(64, help="Remove components smaller than this (pixels).", minimum=0)
    overlay: Path | None = option(
        None, help="Also write the image with the mask blended over it (PNG).", output=True
    )

    def check(self) -> None:
        """Check that ``--h``, ``--s`` and ``--v`` are valid ranges."""
        super().check()
        for flag, value in (("--h", self.h), ("--s", self.s), ("--v", self.v)):
            _range(value, flag)


def segment(run: Run, opts: SegmentOptions, *, out: Path, image: Path) -> Result:
    """``imageform segment``: a tissue mask by HSV thresholds (0 / 255 PNG)."""
    import numpy as np

    from imageform.analysis import overlay_mask, segment_hsv
    from imageform.io import write_image

    img = _rgb(image, opts)
    seg = segment_hsv(
        img,
        _range(opts.h, "--h"),
        _range(opts.s, "--s"),
        _range(opts.v, "--v"),
        opencv_ranges=opts.opencv_ranges,
        open_radius=opts.open_radius,
        close_radius=opts.close_radius,
        min_area=opts.min_area,
    )
    write_image(run.file(out), np.where(seg.mask, np.uint8(255), np.uint8(0))[..., None])
    if opts.overlay is not None:
        write(run, opts.overlay, overlay_mask(img, seg.mask), opts, like=img)
    summary = {
        "input": image,
        "mask": out,
        "overlay": opts.overlay,
        "tissue_fraction": seg.fraction,
        "tissue_pixels": int(seg.mask.sum()),
        "pixels": int(seg.mask.size),
        "h_degrees": list(seg.h),
        "s": list(seg.s),
        "v": list(seg.v),
    }
    wrap = " (wraps through 0)" if seg.wraps else ""
    text = (
        f"hue {seg.h[0]:g}..{seg.h[1]:g} degrees{wrap}, S {seg.s[0]:.4g}..{seg.s[1]:.4g},"
        f" V {seg.v[0]:.4g}..{seg.v[1]:.4g}",
        f"tissue fraction {100 * seg.fraction:.2f} % "
        f"({summary['tissue_pixels']} of {summary['pixels']} pixels); mask: {out}",
    )
    return Result(summary, text)


# ---------------------------------------------------------------- stain normalisation


@dataclass(frozen=True, kw_only=True)
class StainNormalizeOptions(ImageIn, ImageOut):
    """Options of ``imageform stain-normalize`` (and ``imageform batch stain-normalize``)."""

    target: Path = option(
        help="Reference slide image, or its statistics saved with --save-target (.json).",
        input=True,
        metavar="FILE",
    )
    method: str = option(
        "macenko",
        help="Macenko (optical-density stain vectors) or Reinhard (CIELAB statistics).",
        choices=STAIN_METHODS,
    )
    save_target: Path | None = option(
        None, help="Also save the target's statistics as JSON (reused with --target).", output=True
    )

    def check(self) -> None:
        """Check the options and take ``target`` as a path."""
        super().check()
        object.__setattr__(self, "target", Path(self.target))


def _stain_target(opts: StainNormalizeOptions) -> Any:
    from imageform import analysis

    if opts.target.suffix.lower() == ".json":
        kind = analysis.MacenkoStains if opts.method == "macenko" else analysis.ReinhardStats
        return kind.from_json(opts.target)
    ref = _rgb(opts.target, opts)
    return (
        analysis.macenko_stains(ref) if opts.method == "macenko" else analysis.reinhard_stats(ref)
    )


def stain_normalize(run: Run, opts: StainNormalizeOptions, *, out: Path, image: Path) -> Result:
    """``imageform stain-normalize``: bring a slide's stain colours to a target's."""
    import numpy as np

    from imageform import analysis

    img = _rgb(image, opts)
    stats = _stain_target(opts)
    fn = analysis.macenko_normalize if opts.method == "macenko" else analysis.reinhard_normalize
    result = fn(img, stats)
    n_out = write(run, out, np.asarray(result), opts, like=img)
    if opts.save_target is not None:
        stats.to_json(run.file(opts.save_target))
    summary: dict[str, Any] = {
        "input": image,
        "output": out,
        "method": opts.method,
        "target": opts.target,
        "values_clipped": n_out,
    }
    if opts.method == "macenko":
        summary["target_stain_matrix"] = np.asarray(stats.stain_matrix).tolist()
        summary["target_max_concentrations"] = np.asarray(stats.max_concentrations).tolist()
    else:
        summary["target_lab_mean"] = list(stats.mean)
        summary["target_lab_std"] = list(stats.std)
    return Result(summary, (f"{opts.method}: wrote {out}",))


# ---------------------------------------------------------------- colour correction


@dataclass(frozen=True, kw_only=True)
class FitCorrectionOptions(ImageIn):
    """Options of ``imageform fit-correction``."""

    method: str = option(
        "linear",
        help="linear (3x3 in linear light) or root-polynomial.",
        choices=("linear", "root_polynomial"),
    )
    degree: int = option(2, help="Root-polynomial degree (1 to 3).", minimum=1, maximum=3)
    rows: int = option(4, help="Chart rows (the chart fills the frame).", minimum=1, maximum=1000)
    cols: int = option(6, help="Chart columns.", minimum=1, maximum=1000)


def _patches_csv(path: Path) -> tuple[Any, Any]:
    import csv

    import numpy as np

    with path.open(newline="") as fh:
        reader = csv.DictReader(fh)
        missing = [c for c in _CSV_COLUMNS if c not in (reader.fieldnames or [])]
        if missing:
            raise InvalidInputError(
                f"expected CSV columns {','.join(_CSV_COLUMNS)} in {path}; missing "
                f"{','.join(missing)}"
            )
        try:
            rows = [[float(r[c]) for c in _CSV_COLUMNS] for r in reader]
        except (TypeError, ValueError) as exc:
            raise InvalidInputError(f"non-numeric value in {path}: {exc}") from None
    if not rows:
        raise InvalidInputError(f"{path} holds no patch rows")
    arr = np.asarray(rows, dtype=np.float64).reshape((-1, 6))
    return arr[:, :3], arr[:, 3:]


def fit_correction(run: Run, opts: FitCorrectionOptions, *, out: Path, charts: Any) -> Result:
    """``imageform fit-correction``: fit device A -> device B from a chart.

    Writes the JSON that ``imageform harmonize --correction`` reads; ΔE00 per patch before and
    after.
    """
    from imageform.analysis import chart_patches, correction_report, fit_color_correction

    files = [Path(p) for p in charts]
    pa: Any
    pb: Any
    if len(files) == 1 and files[0].suffix.lower() == ".csv":
        pa, pb = _patches_csv(files[0])
        n = len(pa)
    elif len(files) == 2 and all(p.suffix.lower() != ".csv" for p in files):
        pa = chart_patches(_rgb(files[0], opts), opts.rows, opts.cols)
        pb = chart_patches(_rgb(files[1], opts), opts.rows, opts.cols)
        n = len(pa.means)
    else:
        raise InvalidInputError(
            "expected CHART_A CHART_B (two chart images, device A then the reference B) or "
            f"one PATCHES.csv (columns {','.join(_CSV_COLUMNS)}), got "
            f"{' '.join(str(p) for p in files) or 'nothing'}"
        )
    corr = fit_color_correction(pa, pb, opts.method, opts.degree)
    rep = correction_report(pa, pb, corr)
    corr.to_json(run.file(out))
    stats = rep.summary()
    summary = {
        "inputs": files,
        "output": out,
        "method": corr.method,
        "degree": corr.degree,
        "patches": n,
        "patches_fitted": corr.n_patches,
        "delta_e00_before": rep.delta_e_before,
        "delta_e00_after": rep.delta_e_after,
        "patch_valid": rep.valid,
        **stats,
        "matrix": corr.matrix,
    }
    text = [
        f"{corr.method} (degree {corr.degree}) fitted on {corr.n_patches} of {n} patches, "
        "in linear light",
        "patch  ΔE00 before  after",
    ]
    for i, (x, y) in enumerate(zip(rep.delta_e_before, rep.delta_e_after, strict=True)):
        flag = "" if rep.valid[i] else "  (left out: saturated or missing)"
        text.append(f"{i:5d}  {x:11.3f}  {y:5.3f}{flag}")
    text += [
        f"mean   {stats['mean_before']:11.3f}  {stats['mean_after']:5.3f}",
        f"max    {stats['max_before']:11.3f}  {stats['max_after']:5.3f}",
        f"wrote {out} (apply it with imageform harmonize IMAGE -o OUT --correction {out})",
    ]
    return Result(summary, tuple(text))


@dataclass(frozen=True, kw_only=True)
class HarmonizeOptions(ImageIn, ImageOut):
    """Options of ``imageform harmonize`` (and ``imageform batch harmonize``)."""

    correction: Path = option(
        help="Colour correction written by imageform fit-correction (.json).",
        input=True,
        metavar="FILE",
    )

    def check(self) -> None:
        """Check the options and take ``correction`` as a path."""
        super().check()
        object.__setattr__(self, "correction", Path(self.correction))


def harmonize(run: Run, opts: HarmonizeOptions, *, out: Path, image: Path) -> Result:
    """``imageform harmonize``: apply a fitted colour correction to an image of device A."""
    import numpy as np

    from imageform.analysis import ColorCorrection

    corr = ColorCorrection.from_json(opts.correction)
    img = _rgb(image, opts)
    result = np.asarray(corr.apply(img))
    n_out = write(run, out, result, opts, like=img)
    summary = {
        "input": image,
        "output": out,
        "correction": opts.correction,
        "method": corr.method,
        "degree": corr.degree,
        "values_clipped": n_out,
    }
    return Result(summary, (f"corrected {image} -> {out} ({corr.method})",))


_IMG = Input("image", "Input image (PNG 8/16-bit, TIFF, JPEG or .npy).")

WORKFLOWS = (
    Workflow(
        "segment",
        "Tissue mask by HSV thresholds (the lecture's endoscopy case study).",
        "imageform.workflows.analysis:segment",
        SegmentOptions,
        (_IMG,),
        Output("Mask to write (PNG, 0 / 255)."),
        suffixes=(".png", ".tif", ".tiff", ".npy"),
        group="analysis",
    ),
    Workflow(
        "stain-normalize",
        "Stain normalisation of a slide image: Macenko (optical density) or Reinhard (Lab).",
        "imageform.workflows.analysis:stain_normalize",
        StainNormalizeOptions,
        (_IMG,),
        Output("Output image (PNG keeps the input's bit depth; TIFF float32)."),
        batch=True,
        group="analysis",
    ),
    Workflow(
        "fit-correction",
        "Fit a colour correction between two devices from a chart; write it for harmonize.",
        "imageform.workflows.analysis:fit_correction",
        FitCorrectionOptions,
        (
            Input(
                "charts",
                "CHART_A CHART_B: the chart imaged by device A and by the reference device B; "
                "or one PATCHES.csv with columns a_r,a_g,a_b,b_r,b_g,b_b.",
                many=True,
                metavar="CHART_A CHART_B | PATCHES.csv",
            ),
        ),
        Output("Correction to write (.json), read by imageform harmonize --correction."),
        suffixes=(".json",),
        group="analysis",
    ),
    Workflow(
        "harmonize",
        "Apply a colour correction (from fit-correction) to an image of device A.",
        "imageform.workflows.analysis:harmonize",
        HarmonizeOptions,
        (_IMG,),
        Output("Output image (PNG keeps the input's bit depth; TIFF float32)."),
        batch=True,
        group="analysis",
    ),
)
