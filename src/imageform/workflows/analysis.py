"""Biomedical colour-analysis workflows.

``segment``, ``stain-normalize``, ``fit-correction`` and ``harmonize`` (see docs/biomedical.md).

``fit-correction`` fits a colour correction between two devices from a chart (two chart
images, one chart image against the ColorChecker's published values, or a CSV of patch
values) and writes it as JSON; ``harmonize`` applies such a file to an image, or fits one
from ``--chart`` itself (and runs file by file in ``imageform batch``). Chart images may be
cropped to the chart or be photographs with a ColorChecker anywhere in them
(``--chart-layout``, :mod:`imageform.workflows._charts`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, get_args

from imageform import _deprecate
from imageform.errors import InvalidInputError
from imageform.workflows import _charts
from imageform.workflows._images import (
    OPTS_FRAME,
    ImageIn,
    ImageOut,
    RgbFrom,
    image_out_renames,
    in_srgb,
    input_space,
    read,
    refuse_unscaled_floats,
    write,
)
from imageform.workflows._spec import Input, Output, Result, Run, Workflow, check_suffix, option
from imageform.workflows.chart import CorrectionMethod

__all__ = [
    "WORKFLOWS",
    "FitCorrectionOptions",
    "HarmonizeOptions",
    "SegmentOptions",
    "StainNormalizeOptions",
]

_CSV_COLUMNS = ("a_r", "a_g", "a_b", "b_r", "b_g", "b_b")
# Stain-normalisation methods: imageform.analysis.STAIN_NORMALIZATION_METHODS (the one
# registry), spelled out so that --help imports no NumPy; tests/test_registries.py checks
# that they are the same. This module's public STAIN_METHODS is deprecated.
_StainMethod = Literal["macenko", "reinhard"]
_STAIN_METHODS = get_args(_StainMethod)
#: macenko_normalize's concentration references (its ``reference``), spelled out likewise.
_ScaleBy = Literal["max", "mean"]
__getattr__ = _deprecate.module_getattr(
    "imageform.workflows.analysis",
    {
        "STAIN_METHODS": (
            "imageform.analysis.STAIN_NORMALIZATION_METHODS",
            _deprecate.Lazy("imageform.analysis", "STAIN_NORMALIZATION_METHODS"),
        )
    },
)


def _rgb(path: Path, opts: Any, frame: Any = OPTS_FRAME) -> Any:
    img = read(path, opts, colours=True, frame=frame)
    if img.shape[-1] != 3:
        raise InvalidInputError(f"{path}: expected an RGB image, got {img.shape[-1]} channel(s)")
    refuse_unscaled_floats(path, img)
    return img


def _srgb(
    run: Run, path: Path, opts: Any, *, clip: bool, frame: Any = OPTS_FRAME
) -> tuple[Any, Any, str]:
    """Read an RGB image; return it as read, as sRGB (``--from``/declared space), the space.

    ``frame``: the input's ``--frame`` by default; ``None`` for a file that goes with it.
    """
    img = _rgb(path, opts, frame)
    space = input_space(run, path, opts)
    return img, in_srgb(run, path, img, space, clip=clip), space


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
class SegmentOptions(ImageIn, RgbFrom):
    """Options of ``imageform segment``."""

    h: str | None = option(
        None,
        help="Hue range LOW:HIGH in degrees, 0-360 (OpenCV's 0-180 with --opencv-ranges; "
        "LOW > HIGH wraps); default 0:40.",
        metavar="LO:HI",
    )
    s: str | None = option(
        None,
        help="Saturation LOW:HIGH, 0-1 (OpenCV's 0-255 with --opencv-ranges); default 30/255:1.",
        metavar="LO:HI",
    )
    v: str | None = option(
        None,
        help="Value LOW:HIGH, 0-1 (OpenCV's 0-255 with --opencv-ranges); default 80/255:1.",
        metavar="LO:HI",
    )
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

    read_as, img, space = _srgb(run, image, opts, clip=True)
    try:
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
    except InvalidInputError as exc:  # the library's keywords as this command's flags
        msg = re.sub(r"\bexpected ([hsv]) ", r"expected --\1 ", str(exc))
        raise InvalidInputError(msg.replace("opencv_ranges=True", "--opencv-ranges")) from None
    write_image(run.file(out), np.where(seg.mask, np.uint8(255), np.uint8(0))[..., None])
    if opts.overlay is not None:
        write(run, opts.overlay, overlay_mask(img, seg.mask), opts, like=read_as)
    summary = {
        "input": image,
        "from": space,
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


@image_out_renames
@dataclass(frozen=True, kw_only=True)
class StainNormalizeOptions(ImageIn, ImageOut, RgbFrom):
    """Options of ``imageform stain-normalize`` (and ``imageform batch stain-normalize``)."""

    target: Path = option(
        help="Reference slide image, or its statistics saved with --save-target (.json).",
        input=True,
        metavar="FILE",
    )
    method: _StainMethod = option(
        "macenko",
        help="Macenko (optical-density stain vectors) or Reinhard (CIELAB statistics).",
        choices=_STAIN_METHODS,
    )
    save_target: Path | None = option(
        None, help="Also save the target's statistics as JSON (reused with --target).", output=True
    )
    mask: str | None = option(
        None,
        help="Pixels the statistics are taken on: auto (no pen ink, black ink, dark folds, "
        "and brown dye and grey where the image holds eosin; the default for macenko), he "
        "(also brown dye and grey, H&E only), none (every "
        "pixel; the default for reinhard) or a mask image (non-zero: use).",
        metavar="auto|he|none|FILE",
    )
    scale_by: _ScaleBy = option(
        "max",
        help="macenko: the concentrations matched to the target's: max (the 99th percentile, "
        "Macenko's) or mean (the same at any pixel size: a thumbnail against a tile "
        "measured at full resolution).",
        choices=get_args(_ScaleBy),
    )

    def check(self) -> None:
        """Check the options and take ``target`` as a path."""
        super().check()
        object.__setattr__(self, "target", Path(self.target))
        check_suffix(self.save_target, ".json", "--save-target", "the target's statistics (JSON)")
        if self.scale_by != "max" and self.method != "macenko":
            raise InvalidInputError(
                f"--scale-by {self.scale_by} goes with --method macenko only (reinhard matches "
                "the Lab means and standard deviations)"
            )
        if self.mask is not None:
            key = str(self.mask).strip().lower()
            object.__setattr__(self, "mask", key if key in _MASK_WORDS else str(self.mask))


#: The words ``--mask`` takes (anything else is a mask image's path).
_MASK_WORDS = ("auto", "he", "none")

#: The most pixels an image's stain statistics are measured on: a larger image is sampled
#: every ``step``-th row and column, as ``imageform chunked stain-normalize`` samples level 0
#: (:data:`imageform.batch.chunked.STAIN_SAMPLE_PIXELS`, the same number: tests check it).
_STAIN_SAMPLE_PIXELS = 4_000_000


def _sample_step(img: Any) -> int:
    """Return the smallest step ``s`` such that ``img[::s, ::s]`` fits the sample's pixels."""
    h, w = int(img.shape[0]), int(img.shape[1])
    step = 1
    while -(-h // step) * -(-w // step) > _STAIN_SAMPLE_PIXELS:
        step += 1
    return step


def _stain_mask(
    opts: StainNormalizeOptions,
    img: Any,
    *,
    target: bool = False,
    path: Path | None = None,
    step: int = 1,
    i0: Any = "auto",
) -> Any:
    """Return what ``--mask`` means for one image's sample ``img[::step, ::step]``.

    A keyword (Macenko: the estimator makes its own mask on the sample) or booleans of the
    sample's shape. ``auto`` and ``he`` on a file that states its pixel size (``path``; OME or
    Aperio TIFF): :func:`~imageform.analysis.tissue_mask` with that ``pixel_size_um`` (times
    ``step``), as booleans; Macenko's with ``i0``, the sample's background estimate that the
    stains are measured with too. A mask image is of the whole image's size, sampled alike.
    """
    import numpy as np

    from imageform import analysis
    from imageform.io import pixel_size_um

    key = opts.mask or ("auto" if opts.method == "macenko" else "none")
    if key not in _MASK_WORDS:
        if target:  # a mask image belongs to the image, the target gets the default
            key = "auto" if opts.method == "macenko" else "none"
        else:
            raw = np.asarray(read(Path(key), opts, alpha="drop", frame=None))
            m = (raw != 0).any(axis=-1) if raw.ndim == 3 else raw != 0
            if m.shape != img.shape[:-1]:
                raise InvalidInputError(
                    f"{key}: expected a mask of the image's size {img.shape[1]} x "
                    f"{img.shape[0]}, got {m.shape[-1]} x {m.shape[0]}"
                )
            return m[::step, ::step]
    if key == "none":
        return None
    size = pixel_size_um(path) if path is not None else None
    mpp = None if size is None else float(np.sqrt(size[0] * size[1])) * step
    sample = img[::step, ::step]
    he: bool | Literal["auto"] = True if key == "he" else "auto"  # the H&E rules where eosin is
    if opts.method == "macenko":  # the estimator's own I0 and no glass rule, as mask="auto"
        if mpp is None:
            return key
        return analysis.tissue_mask(sample, glass=False, he=he, i0=i0, pixel_size_um=mpp)
    return analysis.tissue_mask(sample, he=he, pixel_size_um=mpp)


def _stain_target(run: Run, opts: StainNormalizeOptions) -> Any:
    from imageform import analysis

    if opts.target.suffix.lower() == ".json":
        kind = analysis.MacenkoStains if opts.method == "macenko" else analysis.ReinhardStats
        try:
            return kind.from_json(opts.target)
        except InvalidInputError as exc:  # a target saved by the other method
            saved = {"'macenko_stains'": "macenko", "'reinhard_stats'": "reinhard"}
            other = next((m for k, m in saved.items() if str(exc).endswith(f"got kind {k}")), None)
            if other is None or other == opts.method:
                raise
            raise InvalidInputError(
                f"--target {opts.target} was saved by --method {other}: normalise with "
                f"--method {other}, or give the reference image for --method {opts.method}"
            ) from None
    ref = _srgb(run, opts.target, opts, clip=True, frame=None)[1]
    step = _sample_step(ref)
    sample = ref[::step, ::step]
    if opts.method == "macenko":
        est = analysis.estimate_background(sample)  # once, for the mask and the stains
        mask = _stain_mask(opts, ref, target=True, path=opts.target, step=step, i0=est)
        return _macenko(sample, mask, f"--target {opts.target}", est)
    mask = _stain_mask(opts, ref, target=True, path=opts.target, step=step)
    return analysis.reinhard_stats(sample, mask)


def _macenko(img: Any, mask: Any, what: str, i0: Any = "auto") -> Any:
    """:func:`~imageform.analysis.macenko_stains` of ``img``, its refusal in the command's words.

    The library's "mask=None keeps them" is ``--mask none`` here, and the message names the
    image (the input or ``--target``) it is about.
    """
    from imageform import analysis
    from imageform.errors import DegenerateConfigurationError

    try:
        return analysis.macenko_stains(img, mask=mask, i0=i0)
    except DegenerateConfigurationError as exc:
        msg = str(exc).replace("mask=None keeps them", "--mask none keeps them")
        raise DegenerateConfigurationError(f"{what}: {msg}") from None


def stain_normalize(run: Run, opts: StainNormalizeOptions, *, out: Path, image: Path) -> Result:
    """``imageform stain-normalize``: bring a slide's stain colours to a target's."""
    import numpy as np

    from imageform import analysis

    read_as, img, space = _srgb(run, image, opts, clip=True)
    stats = _stain_target(run, opts)
    step = _sample_step(img)  # the statistics of a large image from a regular sample
    sample = img[::step, ::step]
    # the sample's background, estimated once for the mask and the stains
    est = analysis.estimate_background(sample) if opts.method == "macenko" else "auto"
    mask = _stain_mask(opts, img, path=image, step=step, i0=est)
    if step > 1:
        run.note(
            f"stain statistics measured on one row and column in {step} "
            f"({sample.shape[1]} x {sample.shape[0]} px), as chunked processing samples"
        )
    source = _macenko(sample, mask, str(image), est) if opts.method == "macenko" else None
    if source is not None:
        result = analysis.macenko_normalize(
            img,
            stats,
            source=source,
            reference=opts.scale_by,
        )
    else:
        own = analysis.reinhard_stats(sample, mask)
        result = analysis.reinhard_normalize(img, stats, source_stats=own)
    n_out = write(run, out, np.asarray(result), opts, like=read_as)
    if opts.save_target is not None:
        stats.to_json(run.file(opts.save_target))
    summary: dict[str, Any] = {
        "input": image,
        "from": space,
        "output": out,
        "method": opts.method,
        "target": opts.target,
        "values_clipped": n_out,
    }
    if source is not None:
        summary["target_stain_matrix"] = np.asarray(stats.stain_matrix).tolist()
        summary["target_max_concentrations"] = np.asarray(stats.max_concentrations).tolist()
        summary["scale_by"] = opts.scale_by
        summary["target_i0"], summary["target_i0_source"] = list(stats.i0), stats.i0_source
        summary["source_i0"], summary["source_i0_source"] = list(source.i0), source.i0_source
    else:
        summary["target_lab_mean"] = list(stats.mean)
        summary["target_lab_std"] = list(stats.std)
    text = [f"{opts.method}: wrote {out}"]
    for name, st in (("image", source), ("target", stats)) if source is not None else ():
        if st.i0_source == "default":
            text.append(
                f"no glass found on the {name}: incident light I0 = 240/255 (the reference "
                "code's default)"
            )
    return Result(summary, tuple(text))


# ---------------------------------------------------------------- colour correction

# imageform.analysis.CORRECTION_METHODS (the one list), spelled out so that --help imports
# no NumPy; tests/test_registries.py checks that they are the same.
_CORRECTION_METHODS = get_args(CorrectionMethod)


@dataclass(frozen=True, kw_only=True)
class FitCorrectionOptions(ImageIn, RgbFrom):
    """Options of ``imageform fit-correction``."""

    method: CorrectionMethod = option(
        "linear",
        help="linear (3x3 in linear light) or root-polynomial.",
        choices=_CORRECTION_METHODS,
    )
    degree: int = option(2, help="Root-polynomial degree (1 to 3).", minimum=1, maximum=3)
    rows: int = option(
        4, help="Rows of the grid of a chart cropped to fill the frame.", minimum=1, maximum=1000
    )
    cols: int = option(6, help="Columns of that grid.", minimum=1, maximum=1000)
    chart_layout: _charts.ChartLayout = option(
        "auto", help=_charts.CHART_LAYOUT_HELP, choices=_charts.CHART_LAYOUTS
    )
    overlay: Path | None = option(
        None, help="Also write CHART_A with the sampled chart drawn over it (PNG).", output=True
    )
    overlay_b: Path | None = option(
        None, help="Also write CHART_B with the sampled chart drawn over it (PNG).", output=True
    )


def _reference_patches(chart: Any, reference: Any, flag: str) -> Any:
    """Return the reference's values for ``chart``.

    ``reference`` (a ChartInput), the ``b_*`` columns of a CSV chart, or the ColorChecker's
    published sRGB values.
    """
    import numpy as np

    from imageform.analysis.synthetic import COLORCHECKER_SRGB8

    if reference is not None:
        return reference.patches
    if chart.reference is not None:
        return chart.reference
    n = len(chart.patches.means)
    if n != 24:
        raise InvalidInputError(
            f"{flag} {chart.path} has {n} patches; without a reference chart it must be a "
            "24-patch ColorChecker (its published values are the reference)"
        )
    return np.asarray(COLORCHECKER_SRGB8, dtype=np.float64) / 255.0


def _fit(run: Run, chart: Any, ref: Any, method: str, degree: int) -> tuple[Any, Any]:
    """Fit the correction and report it; ChartWarnings become notes."""
    import warnings

    from imageform.analysis import ChartWarning, correction_report, fit_color_correction

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ChartWarning)
        corr = fit_color_correction(chart.patches, ref, method, degree)
        rep = correction_report(chart.patches, ref, corr)
    for w in caught:
        run.note(f"note: {w.message}")
    return corr, rep


def fit_correction(run: Run, opts: FitCorrectionOptions, *, out: Path, charts: Any) -> Result:
    """``imageform fit-correction``: fit device A -> device B from a chart.

    Writes the JSON that ``imageform harmonize --correction`` reads; ΔE00 per patch before and
    after. Charts are images (cropped to the chart, or photographs with a ColorChecker anywhere
    in them: ``--chart-layout``), or one CSV; one image alone is fitted to the ColorChecker's
    published sRGB values.
    """
    files = [Path(p) for p in charts]
    csvs = [p.suffix.lower() == ".csv" for p in files]
    if not (len(files) == 1 or (len(files) == 2 and not any(csvs))):
        raise InvalidInputError(
            "expected CHART_A CHART_B (two chart images, device A then the reference B), one "
            f"chart image, or one PATCHES.csv (columns {','.join(_CSV_COLUMNS)}), got "
            f"{' '.join(str(p) for p in files) or 'nothing'}"
        )
    kw: dict[str, Any] = {"layout": opts.chart_layout, "rows": opts.rows, "cols": opts.cols}
    kw["run"] = run  # image charts' patch means in sRGB (--from, or the space declared)
    chart_a = _charts.read_chart(files[0], opts, flag="CHART_A", **kw)
    chart_b = _charts.read_chart(files[1], opts, flag="CHART_B", **kw) if len(files) == 2 else None
    if csvs[0] and chart_a.reference is None:
        raise InvalidInputError(
            f"expected CSV columns {','.join(_CSV_COLUMNS)} in {files[0]}; missing "
            f"{','.join(_CSV_COLUMNS[3:])}"
        )
    if opts.overlay_b is not None and chart_b is None:
        raise InvalidInputError("--overlay-b draws CHART_B: give two chart images")
    pa = chart_a.patches
    pb = _reference_patches(chart_a, chart_b, "CHART_A")
    n = len(pa.means)
    corr, rep = _fit(run, chart_a, pb, opts.method, opts.degree)
    corr.to_json(run.file(out))
    if opts.overlay is not None:
        _charts.write_overlay(run, opts.overlay, chart_a, "CHART_A")
    if opts.overlay_b is not None and chart_b is not None:
        _charts.write_overlay(run, opts.overlay_b, chart_b, "CHART_B")
    stats = rep.summary()
    summary = {
        "inputs": files,
        "output": out,
        "method": corr.method,
        "degree": corr.degree,
        "patches": n,
        "patches_fitted": corr.n_patches,
        "chart_a": _charts.summary(chart_a),
        "chart_b": None if chart_b is None else _charts.summary(chart_b),
        "reference": "CHART_B"
        if chart_b is not None
        else ("csv" if chart_a.reference is not None else "colorchecker"),
        "overlay": opts.overlay,
        "overlay_b": opts.overlay_b,
        "delta_e00_before": rep.delta_e_before,
        "delta_e00_after": rep.delta_e_after,
        "patch_valid": rep.valid,
        **stats,
        "matrix": corr.matrix,
    }
    found = [f"{name} {c.path}: {c.layout}" for name, c in (("A", chart_a), ("B", chart_b)) if c]
    text = [
        "charts: " + "; ".join(found),
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


@image_out_renames
@dataclass(frozen=True, kw_only=True)
class HarmonizeOptions(ImageIn, ImageOut, RgbFrom):
    """Options of ``imageform harmonize`` (and ``imageform batch harmonize``)."""

    correction: Path | None = option(
        None,
        help="Colour correction written by imageform fit-correction or chart (.json).",
        input=True,
        metavar="FILE",
    )
    chart: Path | None = option(
        None,
        help="Instead of --correction: device A's chart (a photograph with a ColorChecker, a "
        "cropped chart, or a CSV), fitted here to --reference.",
        input=True,
        metavar="FILE",
    )
    reference: Path | None = option(
        None,
        help="--chart's reference: device B's chart (image or CSV); default the CSV's b_* "
        "columns, else the ColorChecker's published sRGB values.",
        input=True,
        metavar="FILE",
    )
    method: CorrectionMethod = option(
        "linear",
        help="--chart: linear (3x3 in linear light) or root-polynomial.",
        choices=_CORRECTION_METHODS,
    )
    degree: int = option(2, help="--chart: root-polynomial degree (1 to 3).", minimum=1, maximum=3)
    chart_layout: _charts.ChartLayout = option(
        "auto", help=_charts.CHART_LAYOUT_HELP, choices=_charts.CHART_LAYOUTS
    )
    overlay: Path | None = option(
        None,
        help="--chart: also write the chart image with what was sampled drawn (PNG).",
        output=True,
    )
    save_correction: Path | None = option(
        None,
        help="--chart: also write the fitted correction (.json, for --correction).",
        output=True,
    )

    def check(self) -> None:
        """Check the options and take ``correction`` as a path."""
        super().check()
        if self.correction is not None and self.chart is not None:
            raise InvalidInputError("expected --correction FILE or --chart FILE, got both")
        check_suffix(self.save_correction, ".json", "--save-correction", "the correction (JSON)")
        for name in ("correction", "chart", "reference"):
            v = getattr(self, name)
            if v is not None:
                object.__setattr__(self, name, Path(v))
        if self.chart is None:
            extra = [
                flag
                for flag, v in (
                    ("--reference", self.reference),
                    ("--overlay", self.overlay),
                    ("--save-correction", self.save_correction),
                )
                if v is not None
            ]
            if extra:
                raise InvalidInputError(f"{', '.join(extra)} go(es) with --chart, not --correction")


def harmonize(run: Run, opts: HarmonizeOptions, *, out: Path, image: Path) -> Result:
    """``imageform harmonize``: apply a colour correction to an image of device A.

    A fitted one (``--correction``), or one fitted here from device A's chart (``--chart``: a
    photograph with a ColorChecker in it, a cropped chart or a CSV).
    """
    import numpy as np

    from imageform.analysis import ColorCorrection

    if opts.correction is None and opts.chart is None:
        raise InvalidInputError(
            "expected --correction FILE (from imageform fit-correction) or --chart FILE (a "
            "chart to fit one from), got neither"
        )
    read_as, img, space = _srgb(run, image, opts, clip=False)
    summary: dict[str, Any] = {"input": image, "output": out, "from": space}
    if opts.chart is not None:
        same = opts.chart.resolve() == Path(image).resolve()
        chart = _charts.read_chart(
            opts.chart,
            opts,
            flag="--chart",
            layout=opts.chart_layout,
            image=read_as if same else None,
            run=run,
        )
        ref_in = (
            None
            if opts.reference is None
            else _charts.read_chart(
                opts.reference, opts, flag="--reference", layout=opts.chart_layout, run=run
            )
        )
        ref = _reference_patches(chart, ref_in, "--chart")
        corr, rep = _fit(run, chart, ref, opts.method, opts.degree)
        stats = rep.summary()
        summary.update(
            chart=_charts.summary(chart),
            reference=str(opts.reference)
            if opts.reference is not None
            else ("csv" if chart.reference is not None else "colorchecker"),
            overlay=opts.overlay,
            save_correction=opts.save_correction,
            patches_fitted=corr.n_patches,
            delta_e00_before=rep.delta_e_before,
            delta_e00_after=rep.delta_e_after,
            **stats,
        )
    else:
        corr = ColorCorrection.from_json(opts.correction)  # type: ignore[arg-type]
        summary["correction"] = opts.correction
    result = np.asarray(corr.apply(img))
    n_out = write(run, out, result, opts, like=read_as)
    if opts.chart is not None:
        if opts.save_correction is not None:
            corr.to_json(run.file(opts.save_correction))
        if opts.overlay is not None:
            _charts.write_overlay(run, opts.overlay, chart, "--chart")
    summary.update(method=corr.method, degree=corr.degree, values_clipped=n_out)
    text = [f"corrected {image} -> {out} ({corr.method})"]
    if opts.chart is not None:
        text.insert(
            0,
            f"chart {opts.chart} ({chart.layout}): {corr.method} fitted on {corr.n_patches} "
            f"patches, ΔE00 mean {stats['mean_before']:.3f} -> {stats['mean_after']:.3f}, "
            f"max {stats['max_before']:.3f} -> {stats['max_after']:.3f}",
        )
    return Result(summary, tuple(text))


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
        batch=True,
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
                "CHART_A [CHART_B]: the chart imaged by device A and by the reference device B "
                "(cropped, or photographs with a ColorChecker anywhere; without CHART_B the "
                "ColorChecker's published values), or one PATCHES.csv (a_r,a_g,a_b,b_r,b_g,b_b).",
                many=True,
                metavar="CHART_A [CHART_B] | PATCHES.csv",
            ),
        ),
        Output("Correction to write (.json), read by imageform harmonize --correction."),
        suffixes=(".json",),
        group="analysis",
    ),
    Workflow(
        "harmonize",
        "Apply a colour correction (from fit-correction, or fitted from --chart) to an image.",
        "imageform.workflows.analysis:harmonize",
        HarmonizeOptions,
        (_IMG,),
        Output("Output image (PNG keeps the input's bit depth; TIFF float32)."),
        batch=True,
        group="analysis",
    ),
)
