"""Colour workflows: convert, white-balance, delta-e, cvd, gamut, palette-check."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any, Literal, get_args

from imageform.errors import InvalidInputError
from imageform.workflows._charts import ChartLayout
from imageform.workflows._images import (
    ImageIn,
    ImageOut,
    OnDevice,
    RgbFrom,
    as_values,
    declared_space,
    frame_option,
    gpu_bands,
    image_out_renames,
    input_space,
    on_gpu,
    one_image_frame,
    read,
    refuse_absent_device,
    refuse_unscaled_floats,
    rgb_space_or_auto,
    stored_as,
    tiff_number_type,
    write,
    write_mapped,
)
from imageform.workflows._spec import (
    Input,
    Options,
    Output,
    Result,
    Run,
    Workflow,
    normalize_choice,
    option,
)

__all__ = [
    "CHUNKED_CHOICES",
    "CHUNKED_HELP",
    "CHUNKED_OPTIONS",
    "DISPLAYABLE_SPACES",
    "WORKFLOWS",
    "ConvertOptions",
    "CvdOptions",
    "DeltaEOptions",
    "GamutOptions",
    "PaletteCheckOptions",
    "WhiteBalanceOptions",
]

# spaces whose values are encoded (or linear) RGB-like in [0, 1]: integer images can hold them
_DISPLAYABLE = (
    "srgb",
    "linear_srgb",
    "bgr",
    "gray",
    "cmy",
    "rec709",
    "adobe_rgb",
    "display_p3",
    "rec2020",
    "prophoto",
    "linear_rec709",
    "linear_adobe_rgb",
    "linear_display_p3",
    "linear_rec2020",
    "linear_prophoto",
)

#: Colour spaces whose values are RGB-like in [0, 1] (an integer image can hold them).
DISPLAYABLE_SPACES = _DISPLAYABLE

#: The options ``imageform chunked COMMAND`` honours, per command: workflow field -> the name
#: ``imageform.batch.chunked``'s block functions take. The command line lists only these
#: (``--alpha``, ``--max-pixels`` ... were listed in ``--help`` and ignored or refused).
CHUNKED_OPTIONS = MappingProxyType(
    {
        "stain_normalize": MappingProxyType(
            {"target": "target", "method": "method", "scale_by": "scale-by"}
        ),
        "convert": MappingProxyType({"src": "from", "dst": "to", "white": "white"}),
        "white_balance": MappingProxyType(
            {
                "method": "method",
                "p": "p",
                "normalize": "normalize",
                "illuminant": "illuminant",
                "cct": "cct",
            }
        ),
    }
)
#: The white-balance methods whose illuminant chunked processing streams (a reduction over
#: every block, or none: manual); the other methods need the whole image in memory.
_ChunkedWbMethod = Literal["gray_world", "shades_of_gray", "manual"]
#: The options whose choices ``imageform chunked COMMAND`` narrows: command -> field -> names
#: (its ``--help`` lists these alone, and the others are refused).
CHUNKED_CHOICES: Mapping[str, Mapping[str, tuple[str, ...]]] = MappingProxyType(
    {"white_balance": MappingProxyType({"method": get_args(_ChunkedWbMethod)})}
)
#: The help of an option ``imageform chunked COMMAND`` words for its narrower choices:
#: command -> field -> help (``--p`` of the single command names gray-edge too).
CHUNKED_HELP: Mapping[str, Mapping[str, str]] = MappingProxyType(
    {"white_balance": MappingProxyType({"p": "shades-of-gray: Minkowski norm p, 1 to 10000."})}
)

# ---------------------------------------------------------------- convert

_YccStandard = Literal["bt601", "bt709", "bt2020"]
_YccRange = Literal["full", "limited"]
_GrayMethod = Literal["rec601", "rec709"]
#: ``delta-e --method`` and the simulation models of ``cvd`` and ``palette-check``.
_DeltaEMethod = Literal["ciede2000", "cie76", "cie94", "cmc"]
_CvdMethod = Literal["machado2009", "brettel1997", "vienot1999"]
#: ``gamut --coords``: CIE 1931 xy or CIE 1976 u'v'.
_Coords = Literal["xy", "uv"]


@image_out_renames
@dataclass(frozen=True, kw_only=True)
class ConvertOptions(ImageIn, ImageOut, OnDevice):
    """Options of ``imageform convert``."""

    src: str = option(
        "auto",
        flag="--from",
        help=(
            "Colour space of the input; auto: the one the file declares (ICC profile, PNG "
            "sRGB chunk, EXIF), else srgb (gray for a grey image)."
        ),
        metavar="SPACE",
    )
    dst: str = option(
        "srgb",
        flag="--to",
        help="Colour space of the output (see imageform.color.SPACES).",
        metavar="SPACE",
    )
    white: str | None = option(
        None,
        help="Reference white for lab, luv, lch, xyy (e.g. D50); default the RGB space's own "
        "white (D65 for sRGB).",
    )
    standard: _YccStandard | None = option(
        None, help="Y'CbCr standard; default bt601.", choices=get_args(_YccStandard)
    )
    ycc_range: _YccRange | None = option(
        None,
        flag="--range",
        help="Y'CbCr range: full (default) or limited (studio: 16-235 at 8 bits).",
        choices=get_args(_YccRange),
    )
    code_bits: int | None = option(
        None,
        help="Y'CbCr as code values of this many bits (8, 10 or 12), unrounded floats; default "
        "analog values (Y' in [0, 1], Cb and Cr in [-0.5, 0.5]), and 8 for --range limited.",
        metavar="N",
    )
    gray_method: _GrayMethod | None = option(
        None,
        flag="--gray-method",
        help="Grey conversion: rec601 luma (default) or rec709 luminance.",
        choices=get_args(_GrayMethod),
    )
    window: str | None = option(
        None,
        help="DICOM input: map its values to [0, 1] through a VOI window first: auto (the "
        "file's window, else its VOI LUT, else its min to max) or CENTER,WIDTH (e.g. 40,400).",
        metavar="auto|C,W",
    )

    def check(self) -> None:
        """Check the options and normalise the ``--from`` and ``--to`` space names."""
        super().check()
        from imageform.color import space_name

        if self.window is not None:
            object.__setattr__(self, "window", _window_option(self.window))

        if str(self.src).strip().lower() == "auto":
            object.__setattr__(self, "src", "auto")
        else:
            object.__setattr__(self, "src", space_name(self.src, "--from (src)"))
        object.__setattr__(self, "dst", space_name(self.dst, "--to (dst)"))

    def check_used(self) -> None:
        """Refuse, in the command's flags, an option the conversion does not use (before reading).

        The library's own error names its parameters (``bit_depth``, ``observer``); options are
        checked one by one at construction (tests/cli/test_grammar.py), so this runs first thing
        in the command instead.
        """
        if self.code_bits is not None and self.code_bits not in (8, 10, 12):
            raise InvalidInputError(f"expected --code-bits 8, 10 or 12, got {self.code_bits}")
        ends = {self.src, self.dst}
        source = "the file's space" if self.src == "auto" else self.src
        for flags, given, spaces in (
            (
                "--standard, --range and --code-bits apply",
                (self.standard, self.ycc_range, self.code_bits),
                {"ycbcr"},
            ),
            ("--gray-method applies", (self.gray_method,), {"gray"}),
            ("--white applies", (self.white,), {"lab", "lch", "luv", "xyy"}),
        ):
            if any(v is not None for v in given) and not ends & spaces:
                raise InvalidInputError(
                    f"{flags} to a conversion from or to {' or '.join(sorted(spaces))}, not "
                    f"{source} -> {self.dst}"
                )

    def check_output(self, path: Path) -> None:
        """Refuse a PNG or JPEG output for a space whose values do not fit an integer image."""
        from imageform.io import image_format

        super().check_output(path)

        from imageform.io.icc import RGB_PROFILED

        fmt = image_format(path)
        if fmt in ("netpbm", "pfm") and self.dst in RGB_PROFILED and self.dst != "srgb":
            name = "Netpbm" if fmt == "netpbm" else "PFM"
            raise InvalidInputError(
                f"{name} has no colour profile to declare {self.dst}: write {path.stem}.png or "
                f"{path.stem}.tif"
            )
        if fmt in ("png", "jpeg", "netpbm") and self.dst not in _DISPLAYABLE:
            raise InvalidInputError(
                f"{self.dst} values do not fit an integer image: write {path.stem}.tif or "
                f"{path.stem}.npy (PNG and JPEG hold RGB-like spaces: {', '.join(_DISPLAYABLE)})"
            )

    def params(self) -> dict[str, Any]:
        """Return the keyword parameters of :func:`imageform.color.convert`."""
        p: dict[str, Any] = {"alpha": "keep" if self.alpha == "keep" else "reject"}
        for key, val in (
            ("white", self.white),
            ("standard", self.standard),
            ("signal_range", self.ycc_range),
            ("bit_depth", self.code_bits),
            ("method", self.gray_method),
        ):
            if val is not None:
                p[key] = val
        return p


def _window_option(value: object) -> str | tuple[float, float]:
    """``--window``: ``auto`` or ``CENTER,WIDTH`` (two numbers), else one line."""
    import math

    if isinstance(value, (tuple, list)) and len(value) == 2:
        value = f"{value[0]},{value[1]}"
    text = str(value).strip().lower()
    if text == "auto":
        return "auto"
    parts = text.replace(" ", "").split(",")
    try:
        c, w = (float(v) for v in parts)
    except ValueError:
        raise InvalidInputError(
            f"expected --window auto or CENTER,WIDTH (e.g. 40,400), got {str(value)[:40]!r}"
        ) from None
    if not (math.isfinite(c) and math.isfinite(w)) or w < 1:
        raise InvalidInputError(f"expected --window CENTER,WIDTH with a width >= 1, got {text!r}")
    return (c, w)


def _read_dicom(image: Path, opts: ConvertOptions) -> Any:
    """Read the input's ``--frame``, a DICOM's through ``--window``; else one line.

    A file of several images without ``--frame`` is refused naming the option
    (``read_image``'s refusal names the Python call); ``--window`` applies to DICOM alone.
    """
    from imageform.io import image_frames, image_info, read_dicom

    if opts.frame is None:
        frames = image_frames(image)
        if frames.total > 1:
            what = " x ".join(f"{n} {w}" for w, n in frames.axes)
            held = (
                f"is a multi-frame DICOM of {frames.total} frames"
                if _is_dicom(image)
                else f"holds {frames.total} images ({what})"
            )
            raise InvalidInputError(
                f"{image} {held}; convert one with --frame N (0 to {frames.total - 1})"
            )
    if opts.window is None and not _is_dicom(image):
        return read(image, opts, colours=True, frame=opts.frame)
    if not _is_dicom(image) and image_info(image, frame=opts.frame).format != "dicom":
        raise InvalidInputError(f"--window applies to DICOM input; {image} is not a DICOM file")
    return read_dicom(image, frame=opts.frame, window=opts.window, max_pixels=opts.max_pixels)


def convert(run: Run, opts: ConvertOptions, *, out: Path, image: Path) -> Result:
    """``imageform convert``: one image file from one colour space to another."""
    refuse_absent_device(opts)  # before any file is read
    from imageform.color import SPACES, convert, path
    from imageform.io import RGB_PROFILED, image_color_space, image_format

    dst = opts.dst
    opts.check_used()  # the output was checked by execute (check_output), before this
    img = _read_dicom(image, opts)
    if opts.window is None and img.dtype.kind == "f":
        _refuse_unwindowed(image, img, opts.frame)
    src, declared = opts.src, None
    if src == "auto":
        declared = image_color_space(image)
        src = declared_space(run, image, declared, grey=img.shape[-1] == 1)
    edges = path(src, dst)
    if src != "gray" and img.shape[-1] == 1:
        raise InvalidInputError(f"{image} is a grey image; convert it with --from gray")
    params = opts.params()
    fn: Any = lambda band: convert(as_values(band, src), src, dst, **params)  # noqa: E731
    if opts.device == "cuda":
        fn = gpu_bands(run, f"{src} -> {dst} on a {img.dtype} image", fn)
    # an RGB space's ICC profile is embedded; a TIFF in another space (lab, xyz ...) records
    # its name in the description, so that info and --from auto read it back
    tiff = image_format(out) == "tiff"
    tag = dst if dst in RGB_PROFILED or (tiff and dst != "srgb") else None
    n_out, dtype, lo, hi, shape = write_mapped(run, out, img, fn, opts, like=img, color_space=tag)
    summary = {
        "input": image,
        "output": out,
        "from": src,
        "declared": None if declared is None else declared.name,
        "icc_profile_written": tag in RGB_PROFILED and tag != "srgb",
        "color_space_recorded": tag is not None and tag not in RGB_PROFILED,
        "to": dst,
        "path": [e.function for e in edges],
        "shape": list(shape),
        "dtype": str(dtype),
        "channels": SPACES[dst][1],
        "min": lo,
        "max": hi,
        "values_clipped": n_out,
        "device": opts.device,
    }
    how = " -> ".join(summary["path"]) or "copy"
    return Result(summary, (f"{image} ({src}) -> {out} ({dst}): {how}",))


def _refuse_unwindowed(image: Path, img: Any, frame: int | None) -> None:
    """Refuse a DICOM's float values outside [0, 1] (Hounsfield units ...) without ``--window``."""
    import numpy as np

    from imageform.io import image_info

    lo, hi = float(np.min(img)), float(np.max(img))
    numbers = tiff_number_type(image) if lo < 0 or hi > 1 else None
    if numbers is not None:
        what = "signed numbers" if numbers.startswith("int") else "numbers"
        raise InvalidInputError(
            f"{image} holds {numbers} samples ({what}, {lo:.6g} to {hi:.6g}: a "
            "detector's or a CT's values, not colours); scale them to [0, 1] first"
        )
    if (lo < 0 or hi > 1) and (
        _is_dicom(image) or image_info(image, frame=frame).format == "dicom"
    ):
        raise InvalidInputError(
            f"{image} holds DICOM values from {lo:.6g} to {hi:.6g} (its Modality LUT's output, "
            "not colours); pass --window auto (its VOI window) or --window CENTER,WIDTH"
        )


# ---------------------------------------------------------------- white balance

#: ``--method``: :data:`imageform.color.WHITE_BALANCE_METHODS` (the one registry) with the
#: ``max_rgb`` alias, and ``chart``. Spelled out so that ``--help`` imports no NumPy;
#: tests/test_registries.py checks it against the registry.
_WbMethod = Literal[
    "gray_world",
    "white_patch",
    "max_rgb",
    "shades_of_gray",
    "gray_edge",
    "grayness_index",
    "pca",
    "manual",
    "chart",
]
_WB_METHODS = get_args(_WbMethod)
_WbNormalize = Literal["mean", "green"]


@image_out_renames
@dataclass(frozen=True, kw_only=True)
class WhiteBalanceOptions(ImageIn, ImageOut, OnDevice):
    """Options of ``imageform white-balance``."""

    method: _WbMethod = option("gray_world", help="Illuminant estimate.", choices=_WB_METHODS)
    percentile: float | None = option(
        None,
        help="white-patch: percentile of each channel (0-100; default 99, max-rgb 100); "
        "grayness-index: percent of the pixels taken as grey (default 0.1); pca: percent "
        "of darkest and of brightest pixels (default 3.5, at most 50).",
        minimum=0,
        maximum=100,
    )
    # the bounds are the library's (MAX_MINKOWSKI_P, MAX_SIGMA, Robertson's 600 mired; checked
    # by tests/cli/test_white_balance_words.py), so that a mistake is named by its flag
    p: float = option(
        6.0,
        help="shades-of-gray / gray-edge: Minkowski norm p, 1 to 10000.",
        minimum=1.0,
        maximum=1e4,
    )
    sigma: float = option(
        1.0,
        help="gray-edge, grayness-index: Gaussian scale in pixels, 0 to 1000.",
        minimum=0.0,
        maximum=1000.0,
    )
    illuminant: str | None = option(None, help="manual: illuminant name, e.g. A, D50, F2.")
    cct: float | None = option(
        None,
        help="manual: correlated colour temperature in kelvin, 1667 or above (an sRGB "
        "image holds the whites from 1900 K).",
        minimum=1e6 / 600,
    )
    normalize: _WbNormalize = option(
        "mean",
        help="Keep the mean grey level or the green channel.",
        choices=get_args(_WbNormalize),
    )
    chart: Path | None = option(
        None,
        help="chart: the image holding the ColorChecker (a photograph or a cropped chart) or "
        "its patch CSV; default the input image itself.",
        input=True,
        metavar="FILE",
    )
    chart_layout: ChartLayout = option(
        "auto",
        help="chart: how the chart is found in an image: auto (a cropped chart when its grid "
        "validates, else detected anywhere in the photograph), cropped, detect.",
        choices=get_args(ChartLayout),
    )
    overlay: Path | None = option(
        None,
        help="chart: also write the chart image with the sampled patches drawn (PNG).",
        output=True,
    )

    mask: str = option(
        "none",
        help="The pixels the light is measured by (the estimating methods): none (every "
        "pixel), unclipped (no channel at the top code: clipped highlights left out, as the "
        "colour-constancy sets do), fov (an endoscope's field of view, without its black "
        "surround) or a mask image of the image's size (non-zero: use). The gains apply to "
        "every pixel.",
        metavar="none|unclipped|fov|FILE",
    )

    def check(self) -> None:
        """Check --illuminant, --mask, and that --chart and --overlay go with --method chart."""
        super().check()
        if self.illuminant is not None:
            _check_illuminant(self.illuminant)
        key = str(self.mask).strip()
        object.__setattr__(self, "mask", key.lower() if key.lower() in _WB_MASKS else key)
        method = normalize_choice(self.method, _WB_METHODS, "--method")
        if self.mask != "none" and method in ("manual", "chart"):
            raise InvalidInputError(
                f"--mask goes with the methods that measure the light in the image, not "
                f"--method {self.method} (a given white or the chart's grey patches)"
            )
        if self.chart is not None:
            object.__setattr__(self, "chart", Path(self.chart))
        method = normalize_choice(self.method, _WB_METHODS, "--method")
        if method == "pca" and self.percentile is not None and not 0 < self.percentile <= 50:
            raise InvalidInputError(  # the library's rule, named by the flag before the read
                f"expected --percentile in (0, 50] for --method pca (the share of darkest and "
                f"of brightest pixels; default 3.5), got {self.percentile:g}"
            )
        if method != "chart":
            used = [f for f, v in (("--chart", self.chart), ("--overlay", self.overlay)) if v]
            if used:
                raise InvalidInputError(f"{', '.join(used)} go(es) with --method chart only")

    def params(self) -> dict[str, Any]:
        """Keywords of :func:`imageform.color.white_balance`."""
        return {
            "normalize": self.normalize,
            "percentile": self.percentile,
            "p": self.p,
            "sigma": self.sigma,
            "illuminant": self.illuminant,
            "cct": self.cct,
        }


#: ``white-balance --mask``'s words (anything else is a mask image's path).
_WB_MASKS = ("none", "unclipped", "fov")


def white_balance_mask(image: Any, mask: str, path: Path, read_mask: Any) -> Any:
    """Return the pixels ``--mask`` keeps for the illuminant estimate (None: every pixel).

    ``unclipped``: no channel at the top of the sample's range (the integer type's largest
    code, 1.0 for floats); ``fov``: :func:`imageform.geometry.field_of_view_mask` of the
    image; otherwise ``read_mask(path)`` gives the mask image (non-zero: use).
    """
    import numpy as np

    if mask == "none":
        return None
    a = np.asarray(image)
    h, w = a.shape[:2]
    if mask == "unclipped":
        top = np.iinfo(a.dtype).max if a.dtype.kind == "u" else 1.0
        keep = np.all(a[..., :3] < top, axis=-1)
        if not keep.any():
            raise InvalidInputError(f"{path}: every pixel has a clipped channel (--mask unclipped)")
        return keep
    if mask == "fov":
        from imageform.geometry import field_of_view_mask

        return np.asarray(field_of_view_mask(a))
    from imageform.workflows._images import mask_of

    src = Path(mask)
    if not src.is_file():
        raise InvalidInputError(
            f"--mask {mask} is no file (give none, unclipped, fov or a mask image)"
        )
    return mask_of(read_mask(src), src, h, w, "the image", "no pixel would be used")


def declared_encoding(space: str | None) -> tuple[str, str]:
    """Return (transfer function, RGB space) of an image file that declares ``space``.

    White balance divides the illuminant out in linear light: a file that declares a linear
    space (a linear-light TIFF's profile) is decoded with ``"linear"``, one in Adobe RGB or
    ProPhoto with their own curves; a file that declares nothing, or a space that is no RGB
    space, is read as sRGB. The space is that of ``--method manual``'s white.
    """
    from imageform.color import RGB_SPACES

    name = str(space or "srgb")
    if name.startswith("linear_") and name[len("linear_") :] in RGB_SPACES:
        return "linear", name[len("linear_") :]
    if name in RGB_SPACES:
        return RGB_SPACES[name].transfer, name
    return "srgb", "srgb"


def _check_illuminant(name: str) -> None:
    """Refuse an ``--illuminant`` that is no white point or RGB space, naming the flag."""
    from imageform._validate import describe
    from imageform.color import RGB_SPACES, WHITEPOINTS_XY, resolve_white
    from imageform.errors import UnknownOptionError

    try:
        resolve_white(name, name="--illuminant")
    except UnknownOptionError:
        names = ", ".join([*WHITEPOINTS_XY[2], *RGB_SPACES])
        raise UnknownOptionError(
            f"unknown --illuminant {describe(name, 30)}; valid: an illuminant or RGB space "
            f"name ({names})"
        ) from None


def white_balance(run: Run, opts: WhiteBalanceOptions, *, out: Path, image: Path) -> Result:
    """``imageform white-balance``: estimate the illuminant and divide it out in linear light."""
    import numpy as np

    refuse_absent_device(opts)  # before any file is read
    if opts.method == "manual" and (opts.illuminant is None) == (opts.cct is None):
        raise InvalidInputError(  # the library's words are its keywords, illuminant= and cct=
            "--method manual takes one of --cct KELVIN (e.g. 3200) or --illuminant NAME "
            "(e.g. A, D50, F2)"
        )
    img = read(image, opts, colours=True)
    if img.shape[-1] != 3:
        raise InvalidInputError(f"{image}: expected an RGB image, got {img.shape[-1]} channel(s)")
    refuse_unscaled_floats(image, img)
    from imageform.io import RGB_PROFILED, image_color_space

    declared = image_color_space(image).name  # the output keeps the input's profile
    tag = declared if declared in RGB_PROFILED else None
    transfer, space = declared_encoding(declared)  # a linear file is balanced as linear
    chart = None
    flag = "IMAGE" if opts.chart is None else "--chart"
    if normalize_choice(opts.method, _WB_METHODS, "--method") == "chart":
        from imageform.analysis import chart_white_balance
        from imageform.workflows import _charts

        src = Path(image) if opts.chart is None else opts.chart
        same = src.resolve() == Path(image).resolve()
        if not same and src.suffix.lower() != ".csv" and image_color_space(src).name != declared:
            # the patches are decoded with the image's curve and the gains applied in its
            # space: a chart file encoded otherwise would give wrong gains without a word
            raise InvalidInputError(
                f"--chart {src} declares {image_color_space(src).name or 'srgb'}, IMAGE "
                f"declares {declared or 'srgb'}: convert one to the other's space first"
            )
        chart = _charts.read_chart(
            src, opts, flag=flag, layout=opts.chart_layout, image=img if same else None
        )
        _charts.notes(run, chart, flag)
        balanced, gains = chart_white_balance(
            img, chart.patches, normalize=opts.normalize, transfer=transfer, space=space
        )
        if opts.device == "cuda":
            run.note("note: --device cuda: --method chart runs on the CPU")
        n_out = write(run, out, np.asarray(balanced), opts, like=img, color_space=tag)
    else:  # the gains from the whole image, applied a band of rows at a time
        from imageform.color.white_balance import (
            apply_white_balance_gains,
            white_balance_gains,
        )

        # the estimate reads the whole image on the CPU; the gains are applied on the device
        keep = white_balance_mask(
            img, opts.mask, image, lambda p: read(p, opts, colours=True, frame=None)
        )
        gains = np.asarray(
            white_balance_gains(
                img, opts.method, transfer=transfer, space=space, mask=keep, **opts.params()
            )
        )
        fn: Any = lambda band: apply_white_balance_gains(band, gains, transfer=transfer)  # noqa: E731
        if opts.device == "cuda":
            fn = gpu_bands(run, f"the gains on a {img.dtype} image", fn)
        n_out = write_mapped(run, out, img, fn, opts, like=img, color_space=tag)[0]
    if chart is not None and opts.overlay is not None:
        _charts.write_overlay(run, opts.overlay, chart, flag)
    g = [float(v) for v in np.asarray(gains)]
    summary: dict[str, Any] = {
        "input": image,
        "output": out,
        "method": opts.method,
        "mask": opts.mask,
        "gains": g,
        "values_clipped": n_out,
        "device": opts.device,
    }
    if chart is not None:
        summary["chart"] = _charts.summary(chart)
        summary["overlay"] = opts.overlay
    text = (
        f"gains (R, G, B) in linear light: {g[0]:.4f} {g[1]:.4f} {g[2]:.4f}"
        + ("" if chart is None else f" (from the grey patches, chart {chart.layout})"),
        f"wrote {out}",
    )
    return Result(summary, text)


# ---------------------------------------------------------------- delta E

_PERCENTILES = (50.0, 90.0, 95.0, 99.0)


@dataclass(frozen=True, kw_only=True)
class DeltaEOptions(ImageIn, OnDevice):
    """Options of ``imageform delta-e``."""

    method: _DeltaEMethod = option(
        "ciede2000",
        help="Colour-difference formula.",
        choices=get_args(_DeltaEMethod),
    )
    heatmap: Path | None = option(
        None, help="Also write a heat map of ΔE (PNG, colour scale 0 to 10).", output=True
    )
    src: str = option(
        "auto",
        flag="--from",
        help=(
            "RGB space of both images; auto: the one each file declares (ICC profile, PNG "
            "sRGB chunk, EXIF), else srgb."
        ),
        metavar="SPACE",
    )

    def check(self) -> None:
        """Check the options and normalise the ``--from`` space name (an RGB space)."""
        super().check()
        src = rgb_space_or_auto(self.src, "delta-e compares RGB images", linear=True)
        object.__setattr__(self, "src", src)


def delta_e(run: Run, opts: DeltaEOptions, *, out: None, reference: Path, test: Path) -> Result:
    """``imageform delta-e``: ΔE between two RGB images of the same size."""
    import numpy as np

    from imageform.color.convert import convert
    from imageform.color.delta_e import delta_e as de_fn
    from imageform.color.delta_e import describe_delta_e

    refuse_absent_device(opts)  # before any file is read
    a, b = read(reference, opts, colours=True), read(test, opts, colours=True)
    for path, arr in ((reference, a), (test, b)):
        if arr.shape[-1] != 3:
            raise InvalidInputError(
                f"{path}: expected an RGB image, got {arr.shape[-1]} channel(s)"
            )
        refuse_unscaled_floats(path, arr)
    if a.shape != b.shape:
        raise InvalidInputError(
            f"images differ in size: {reference} is {a.shape[1]} x {a.shape[0]} px, "
            f"{test} {b.shape[1]} x {b.shape[0]} px"
        )

    spaces = [opts.src, opts.src]
    if opts.src == "auto":
        from imageform.io import image_color_space

        spaces = [declared_space(run, p, image_color_space(p), grey=False)
                  for p in (reference, test)]  # fmt: skip
    sa, sb = spaces

    def lab_delta_e(x: Any, y: Any) -> Any:
        lab_a, lab_b = convert(as_values(x, sa), sa, "lab"), convert(as_values(y, sb), sb, "lab")
        return de_fn(lab_a, lab_b, opts.method)

    de = None
    if opts.device == "cuda":  # three kernels: two conversions and the difference
        de = on_gpu(run, f"delta-e of {a.dtype} images", lab_delta_e, a, b)
    if de is None:
        de = np.asarray(lab_delta_e(a, b))
    mean, worst = float(de.mean()), float(de.max())
    pct = {f"p{q:g}": float(np.percentile(de, q)) for q in _PERCENTILES}
    above1, above10 = float(np.mean(de > 1.0)), float(np.mean(de > 10.0))
    if opts.heatmap is not None:
        from matplotlib import colormaps

        from imageform.io import write_image

        rgb = colormaps["magma"](np.clip(de / 10.0, 0.0, 1.0))[..., :3]
        write_image(run.file(opts.heatmap), rgb)
    summary = {
        "spaces": spaces,
        "reference": reference,
        "test": test,
        "method": opts.method,
        "pixels": int(de.size),
        "mean": mean,
        "max": worst,
        "percentiles": pct,
        "reading": describe_delta_e(mean),
        "fraction_above_1": above1,
        "fraction_above_10": above10,
        "heatmap": opts.heatmap,
        "device": opts.device,
    }
    text = [
        f"ΔE ({opts.method}) over {de.size} pixels",
        f"  mean {mean:.4f}   max {worst:.4f}   ({describe_delta_e(mean)})",
        *(f"  {k:>4} {v:.4f}" for k, v in pct.items()),
        f"  above 1 (perceptible): {100 * above1:.2f} %   above 10 (obvious): "
        f"{100 * above10:.2f} %",
    ]
    if opts.heatmap is not None:
        text.append(f"  heat map (0 to 10): {opts.heatmap}")
    return Result(summary, tuple(text))


# ---------------------------------------------------------------- colour-vision deficiency


@image_out_renames
@dataclass(frozen=True, kw_only=True)
class CvdOptions(ImageIn, ImageOut, RgbFrom):
    """Options of ``imageform cvd``."""

    deficiency: str = option(
        flag="--type",
        help="protan, deutan or tritan (also protanopia, deuteranomaly ...).",
    )
    severity: float = option(1.0, help="0 (normal vision) to 1 (dichromat).")
    method: _CvdMethod = option(
        "machado2009",
        help="Simulation model.",
        choices=get_args(_CvdMethod),
    )


def cvd(run: Run, opts: CvdOptions, *, out: Path, image: Path) -> Result:
    """``imageform cvd``: what a colour-vision deficient observer sees (in linear RGB)."""
    from imageform.color import convert
    from imageform.color.cvd import simulate_cvd
    from imageform.io import RGB_PROFILED

    arr = read(image, opts, colours=True)
    if arr.shape[-1] != 3:
        raise InvalidInputError(f"{image}: expected an RGB image, got {arr.shape[-1]} channel(s)")
    refuse_unscaled_floats(image, arr)
    space = input_space(run, image, opts)

    def band(b: Any) -> Any:  # the models are defined on sRGB: there and back (floats)
        srgb = b if space == "srgb" else convert(as_values(b, space), space, "srgb")
        seen = simulate_cvd(srgb, opts.deficiency, opts.severity, opts.method)
        return seen if space == "srgb" else convert(seen, "srgb", space)

    tag = space if space in RGB_PROFILED else None
    n_out = write_mapped(run, out, arr, band, opts, like=arr, color_space=tag)[0]
    summary = {
        "input": image,
        "from": space,
        "output": out,
        "deficiency": opts.deficiency,
        "severity": opts.severity,
        "method": opts.method,
        "values_clipped": n_out,
    }
    text = (f"wrote {out} ({opts.method}, {opts.deficiency}, severity {opts.severity:g})",)
    return Result(summary, text)


# ---------------------------------------------------------------- gamut


@dataclass(frozen=True, kw_only=True)
class GamutOptions(Options):
    """Options of ``imageform gamut``."""

    spaces: str = option(
        "srgb,display-p3,rec2020", help="Comma-separated RGB spaces (srgb, adobe-rgb, ...)."
    )
    coords: _Coords = option(
        "xy", help="Diagram coordinates for -o: xy or uv (u'v').", choices=get_args(_Coords)
    )

    def names(self) -> list[str]:
        """Return the spaces, split."""
        names = [s.strip() for s in self.spaces.split(",") if s.strip()]
        if not names:
            raise InvalidInputError("expected --spaces as one or more RGB space names")
        return names


def gamut(run: Run, opts: GamutOptions, *, out: Path | None) -> Result:
    """``imageform gamut``: gamut areas and coverage; with -o, the chromaticity diagram."""
    from imageform.color.chromaticity import visible_area
    from imageform.color.gamut import gamut_figures

    figs = gamut_figures(opts.names())
    vxy, vuv = visible_area("xy"), visible_area("uv")
    text = [
        f"visible region (380-780 nm locus): area xy {vxy:.4f}, u'v' {vuv:.4f}",
        f"{'space':<22}{'area xy':>9}{'cover xy':>10}{'area uv':>9}{'cover uv':>10}",
        *(
            f"{f.space:<22}{f.area_xy:>9.4f}{f.coverage_xy:>9.1f}%"
            f"{f.area_uv:>9.4f}{f.coverage_uv:>9.1f}%"
            for f in figs
        ),
    ]
    if out is not None:
        import matplotlib

        matplotlib.use("Agg")
        from imageform.report.chromaticity_plot import plot_chromaticity_diagram

        plot_chromaticity_diagram(opts.names(), coords=opts.coords, path=run.file(out))
        text.append(f"wrote {out}")
    summary = {
        "visible_area_xy": vxy,
        "visible_area_uv": vuv,
        "spaces": [f.as_dict() for f in figs],
        "plot": out,
    }
    return Result(summary, tuple(text))


# ---------------------------------------------------------------- palette check


@dataclass(frozen=True, kw_only=True)
class PaletteCheckOptions(Options):
    """Options of ``imageform palette-check``."""

    threshold: float = option(10.0, help="Smallest acceptable ΔE00 between two colours.")
    method: _CvdMethod = option(
        "machado2009",
        help="Colour-vision-deficiency model.",
        choices=get_args(_CvdMethod),
    )


def palette_check(run: Run, opts: PaletteCheckOptions, *, out: None, colors: str) -> Result:
    """``imageform palette-check``: smallest pairwise ΔE00, normal and for each deficiency.

    The check fails (exit 3) when a condition is under the threshold.
    """
    from imageform.color.palettes import palette_check as check

    r = check(colors, threshold=opts.threshold, method=opts.method)
    text = [f"{len(r.colors)} colours, threshold ΔE00 {r.threshold:g} ({opts.method})"]
    for cond, v in r.min_delta_e.items():
        i, j = r.closest_pair[cond]
        verdict = "pass" if r.passes[cond] else "FAIL"
        text.append(f"  {cond:<7} min ΔE00 {v:6.2f}  (colours {i} and {j})  {verdict}")
    ok = all(r.passes.values())
    return Result(r.as_dict(), tuple(text), check_failed=not ok)


_IMG = Input(
    "image",
    "Input image (PNG, JPEG, TIFF, .npy, WebP, BMP, GIF, PGM/PPM/PBM/PAM, PFM, Radiance HDR, "
    "TGA, QOI, ICO; HEIF with the heif extra, DICOM with the dicom extra).",
)


@dataclass(frozen=True, kw_only=True)
class InfoOptions(Options):
    """Options of ``imageform info``."""

    frame: int | None = frame_option(
        "Describe this image of a file holding several (a TIFF stack's page, z-plane, time "
        "point or channel; a GIF's or WebP's frame), 0 the first; without it they are listed."
    )


def info(run: Run, opts: InfoOptions, *, out: None, image: Path) -> Result:
    """``imageform info``: what an image file holds, from its header, and its colour space."""
    from imageform.io import exif_camera, image_color_space, image_frames, image_info
    from imageform.workflows._characterize_inputs import _RAW_SUFFIXES

    if Path(image).suffix.lower() in _RAW_SUFFIXES:
        from imageform.workflows.raw import raw_info

        one_image_frame(image, opts.frame)  # a raw file holds one image
        return raw_info(image)
    if _is_dicom(image):
        if opts.frame is not None:  # in range, or refused as read_image refuses it
            image_info(image, frame=opts.frame)
        return _dicom_info(image, opts.frame)
    frames = image_frames(image)
    if frames.total > 1 and opts.frame is None:
        return _frames_info(image, frames)
    head = image_info(image, frame=opts.frame)
    declared = image_color_space(image)
    orientation = _exif_orientation(image, head.format)
    turned = orientation in (5, 6, 7, 8)  # stored on its side
    stored = (head.height, head.width) if turned else (head.width, head.height)
    summary = {
        "image": image,
        "format": head.format,
        "width": head.width,
        "height": head.height,
        "stored_width": stored[0],
        "stored_height": stored[1],
        "channels": head.channels,
        "dtype": head.dtype,
        "megapixels": round(head.width * head.height / 1e6, 3),
        "color_space": declared.name,
        "color_space_source": declared.source,
        "description": declared.description or None,
        "exif_orientation": orientation,
        "frames": frames.total,
        "frame": opts.frame,
    }
    space = declared.name or "not declared (read as sRGB)"
    if declared.name is None and declared.source == "icc":
        space = f"an ICC profile imageform does not recognise ({declared.description})"
    elif declared.name is None and declared.source in ("png-gama", "png-chrm", "png-cicp"):
        space = f"PNG chunks no space of imageform matches ({declared.description}); read as sRGB"
    elif declared.source in ("png-gama", "png-chrm", "png-cicp"):
        space = f"{declared.name} ({declared.description})"
    how = {
        "none": "",
        "tiff-description": " (recorded by imageform in the TIFF's description)",
    }.get(declared.source, f" ({declared.source})")
    which = f" (frame {opts.frame} of {frames.total})" if frames.total > 1 else ""
    numbers = tiff_number_type(image) if head.format == "tiff" else None
    summary["stored_dtype"] = numbers or head.dtype
    text = [
        f"{image}{which}: {head.format}, {head.width} x {head.height} px, {head.channels} "
        f"channel(s), {head.dtype}{stored_as(numbers)}",
        f"colour space: {space}{how}",
    ]
    if orientation not in (None, 1):
        how_stored = f"stored {stored[0]} x {stored[1]} px; " if turned else ""
        text.append(f"EXIF orientation {orientation}: {how_stored}read_image turns it upright")
    if head.format == "tiff":
        slide = _tiff_slide(image)
        summary.update(slide)
        text += _slide_lines(slide)
    cam = exif_camera(image)
    summary["exif_camera"] = _exif_summary(cam)
    if cam.found:
        text.append(f"camera (EXIF): {cam.describe()}")
    if cam.focal_length_px is not None:
        text.append(
            f"focal length ~ {cam.focal_length_px:.0f} px (from the EXIF's "
            f"{cam.focal_length_px_source}; an estimate, no calibration)"
        )
    return Result(summary, tuple(text))


def _frames_info(image: Path, frames: Any) -> Result:
    """``imageform info`` of a file of several images: what they are, and how to read one.

    The images are listed by their axes (a TIFF stack's pages, z-planes, time points,
    channels; a GIF's frames), with the size of each (the first's: a stack's images are alike).
    """
    from imageform.io import image_color_space, image_info

    head = image_info(image, frame=0)
    declared = image_color_space(image)
    what = " x ".join(f"{n} {w}" for w, n in frames.axes)
    summary = {
        "image": image,
        "format": head.format,
        "width": head.width,
        "height": head.height,
        "channels": head.channels,
        "dtype": head.dtype,
        "megapixels": round(head.width * head.height / 1e6, 3),
        "color_space": declared.name,
        "color_space_source": declared.source,
        "description": declared.description or None,
        "frames": frames.total,
        "frame_axes": dict(frames.axes),
    }
    numbers = tiff_number_type(image) if head.format == "tiff" else None
    summary["stored_dtype"] = numbers or head.dtype
    last = frames.total - 1
    # a multi-page TIFF's pages may differ (a fax page and a colour photograph): each's size
    picked = range(frames.total) if frames.total <= 64 else (0, last)
    heads = [head] + [image_info(image, frame=k) for k in picked if k]
    summary["sizes_differ"] = len({(h.width, h.height, h.channels, h.dtype) for h in heads}) > 1
    if summary["sizes_differ"]:
        shown = "; ".join(
            f"frame {k}: {h.width} x {h.height} px, {h.channels} channel(s), {h.dtype}"
            for k, h in zip(picked, heads, strict=False)
        )
        each = f"of different sizes or types ({shown})"
    else:
        each = (
            f"each {head.width} x {head.height} px, {head.channels} channel(s), "
            f"{head.dtype}{stored_as(numbers)}"
        )
    text = [
        f"{image}: {head.format}, {frames.total} images ({what}), {each}",
        f"frames 0 to {last}, in the file's order; read one: imageform COMMAND --frame N, "
        "read_image(path, frame=N)",
    ]
    if len(frames.axes) > 1:  # frame N = 2 x (time point) + (z-plane), each from 0
        sizes = [n for _, n in frames.axes]
        steps = [math.prod(sizes[i + 1 :]) for i in range(len(sizes))]
        terms = [
            (f"{s} x " if s > 1 else "") + f"({w.removesuffix('s')})"
            for (w, _), s in zip(frames.axes, steps, strict=True)
        ]
        text.append(f"frame N = {' + '.join(terms)}, each counted from 0")
    text.append(f"colour space: {declared.name or 'not declared (read as sRGB)'}")
    return Result(summary, tuple(text))


#: tifffile's flags of a slide scanner's TIFF, and the format's name (OpenSlide's vendor names).
_SLIDE_VENDORS = (("is_svs", "aperio"), ("is_ndpi", "hamamatsu"), ("is_philips", "philips"),
                  ("is_bif", "ventana"), ("is_scn", "leica"), ("is_qpi", "qptiff"),
                  ("is_ome", "ome"))  # fmt: skip


def _tiff_slide(image: Path) -> dict[str, Any]:
    """Return a TIFF's pyramid levels ((width, height), level 0 first), pixel size, scanner.

    ``vendor`` is the scanner format tifffile recognises (OpenSlide's names), ``generic-tiff``
    for another pyramid, None for a flat TIFF.
    """
    import tifffile

    from imageform.io import pixel_size_um

    levels: list[list[int]] = []
    vendor = None
    try:
        with tifffile.TiffFile(image) as tif:
            series = tif.series[0]
            for level in series.levels:
                axes = series.axes
                shape = dict(zip(axes, level.shape, strict=False))
                levels.append([int(shape.get("X", 0)), int(shape.get("Y", 0))])
            vendor = next((name for flag, name in _SLIDE_VENDORS if getattr(tif, flag)), None)
    except Exception:  # the header was read: a damaged level table says nothing more
        levels = []
    if vendor is None and len(levels) > 1:
        vendor = "generic-tiff"
    um = pixel_size_um(image)
    return {
        "levels": levels or None,
        "pixel_size_um": None if um is None else [round(float(v), 6) for v in um],
        "vendor": vendor,
    }


def _slide_lines(slide: dict[str, Any]) -> list[str]:
    """``imageform info``'s lines on a slide: its format, levels and pixel size."""
    out = []
    levels = slide.get("levels") or []
    if slide.get("vendor") or len(levels) > 1:
        sizes = ", ".join(f"{w} x {h}" for w, h in levels)
        out.append(f"slide: {slide.get('vendor') or 'tiff'}, {len(levels)} level(s): {sizes}")
    um = slide.get("pixel_size_um")
    if um is not None:
        out.append(f"pixel size: {um[0]:g} x {um[1]:g} µm (level 0)")
    return out


def _exif_summary(cam: Any) -> dict[str, Any] | None:
    """Return an :class:`~imageform.io.ExifCamera` for JSON (None: no EXIF)."""
    if not cam.found:
        return None
    import dataclasses

    return {k: v for k, v in dataclasses.asdict(cam).items() if k != "found"}


def _is_dicom(image: Path) -> bool:
    """Whether ``image`` shows DICOM's ``DICM`` at byte 128 (any suffix).

    A ``.dcm`` file without it goes through :func:`image_info`, which reads what it holds.
    """
    from imageform.io.image_io import is_dicom_file

    return is_dicom_file(image)


def _dicom_info(image: Path, frame: int | None = None) -> Result:
    """``imageform info`` of a DICOM file: the image, its modality values, window, spacing.

    ``frame``: the one ``--frame`` named (checked in range by the caller); the header
    describes every frame alike.
    """
    from imageform.io import dicom, dicom_info, image_color_space

    d = dicom_info(image)
    tiles = dicom.slide_tiles(Path(image), dicom.open_dicom(Path(image), pixels=False))
    w, h = (d.width, d.height) if tiles is None else (tiles.width, tiles.height)
    declared = image_color_space(image)
    summary: dict[str, Any] = {
        "image": image,
        "format": "dicom",
        "width": w,
        "height": h,
        "channels": d.channels,
        "dtype": d.dtype,
        "megapixels": round(w * h / 1e6, 3),
        "color_space": declared.name,
        "color_space_source": declared.source,
        "description": declared.description or None,
        "frames": d.frames,
        "frame": frame,
        "dicom": d._asdict(),
    }
    frames = f", {d.frames} frames (read one: --frame N)" if d.frames > 1 else ""
    if frame is not None and d.frames > 1:
        frames = f", frame {frame} of {d.frames}"
    if tiles is not None:
        summary["tiles"] = {"count": d.frames, "organization": tiles.organization}
        frames = (
            f" (a {tiles.organization} slide of {d.frames} tiles of {d.width} x {d.height} px, "
            "read as one image)"
        )
    signed = "signed" if d.signed else "unsigned"
    text = [
        f"{image}: dicom, {w} x {h} px, {d.channels} channel(s), {d.dtype}{frames}",
        f"modality {d.modality or 'not given'}, {d.photometric}, {d.bits_stored} of "
        f"{d.bits_allocated} bits stored ({signed}), {d.transfer_syntax}",
    ]
    if d.channels == 1:
        if d.modality_lut:
            how = "through its Modality LUT Sequence"
        else:
            unit = f" ({d.rescale_type})" if d.rescale_type else ""
            how = f"rescale slope {d.rescale_slope:g}, intercept {d.rescale_intercept:g}{unit}"
        flip = "; MONOCHROME1 read inverted (0 is black)" if d.photometric == "MONOCHROME1" else ""
        text.append(f"values: {how}{flip}")
        if d.window_center:
            pairs = ", ".join(
                f"{c:g}/{w:g}" for c, w in zip(d.window_center, d.window_width, strict=True)
            )
            text.append(
                f"window center/width: {pairs} ({d.window_function}); imageform convert "
                "--window auto applies the first"
            )
        else:
            text.append("window: none in the file (--window auto uses the image's range)")
    slide = _dicom_slide(image, d)
    summary.update(slide)
    text += _slide_lines(slide)
    for name, sp in (("pixel spacing", d.pixel_spacing_mm),
                     ("imager pixel spacing", d.imager_pixel_spacing_mm)):  # fmt: skip
        if sp is not None:
            text.append(f"{name}: {sp[0]:g} x {sp[1]:g} mm (between rows x between columns)")
    if d.channels == 3:
        space = declared.name or (
            f"an ICC profile imageform does not recognise ({declared.description})"
            if declared.source == "icc"
            else "not declared (read as sRGB)"
        )
        text.append(f"colour space: {space}")
    return Result(summary, tuple(text))


def _dicom_slide(image: Path, d: Any) -> dict[str, Any]:
    """Return a DICOM slide image's total pixel matrix (its frames are tiles), pixel size.

    Empty for another modality, or a slide image that states no total pixel matrix.
    """
    from imageform.io import pixel_size_um

    if d.modality != "SM":
        return {}
    from imageform.io import dicom

    try:
        levels = [[w, h] for _, w, h in dicom.slide_levels(Path(image))]
    except Exception:  # dicom_info read it already; an odd attribute says nothing more
        levels = []
    um = pixel_size_um(image)
    out: dict[str, Any] = {
        "vendor": "dicom",
        "pixel_size_um": None if um is None else [round(float(v), 6) for v in um],
    }
    if levels:
        out["levels"] = levels
        out["tile"] = [d.width, d.height]
    return out


def _exif_orientation(path: Path, fmt: str) -> int | None:
    """Read the EXIF orientation tag of a JPEG, PNG, TIFF or WebP (None when absent or unreadable).

    A TIFF's through tifffile, as ``read_image`` reads it (Pillow prints onto stderr about
    TIFFs it cannot decode).
    """
    if fmt == "tiff":
        import tifffile

        try:
            with tifffile.TiffFile(path) as tif:
                tag = tif.pages.first.tags.get(274)
                value = tag.value if tag is not None else None
        except Exception:  # the file's reader has said why, or will
            return None
        return int(value) if value else None
    if fmt not in ("jpeg", "png", "webp"):
        return None
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(path) as im:
            value = im.getexif().get(0x0112)
    except (OSError, UnidentifiedImageError, ValueError, SyntaxError):
        return None
    return int(value) if value else None


WORKFLOWS = (
    Workflow(
        "info",
        "What an image file holds: size, channels, sample type, its colour space, orientation.",
        "imageform.workflows.color:info",
        InfoOptions,
        (
            Input(
                "image",
                "Image (PNG, JPEG, TIFF, .npy, WebP, BMP, GIF, PGM/PPM, PFM, HDR, TGA, QOI, ICO, "
                "HEIF, DICOM) or raw file (DNG, CR2 ...).",
            ),
        ),
        None,
        group="colour",
    ),
    Workflow(
        "convert",
        "Convert an image between colour spaces (sRGB, Lab, HSV, Y'CbCr, XYZ ...).",
        "imageform.workflows.color:convert",
        ConvertOptions,
        (_IMG,),
        Output("Output image (.png/.jpg for RGB-like spaces; .tif/.npy for any)."),
        batch=True,
        group="colour",
    ),
    Workflow(
        "white-balance",
        "White-balance an RGB image in linear light and print the gains.",
        "imageform.workflows.color:white_balance",
        WhiteBalanceOptions,
        (_IMG,),
        Output("Output image (PNG/JPEG integer, TIFF float32, .npy)."),
        batch=True,
        group="colour",
    ),
    Workflow(
        "delta-e",
        "Colour difference (ΔE) between two RGB images: mean, max, percentiles, heat map.",
        "imageform.workflows.color:delta_e",
        DeltaEOptions,
        (
            Input("reference", "Reference image (RGB, in the space it declares or --from)."),
            Input("test", "Test image, same size."),
        ),
        None,
        group="colour",
    ),
    Workflow(
        "cvd",
        "Simulate colour-vision deficiency (protan, deutan, tritan) on an RGB image.",
        "imageform.workflows.color:cvd",
        CvdOptions,
        (_IMG,),
        Output("Output image."),
        batch=True,
        group="colour",
    ),
    Workflow(
        "gamut",
        "Gamut areas and coverage of RGB spaces (xy and u'v'); -o draws the diagram.",
        "imageform.workflows.color:gamut",
        GamutOptions,
        (),
        Output("Chromaticity diagram to write (PNG, SVG or PDF).", required=False),
        suffixes=(".png", ".svg", ".pdf"),
        group="colour",
    ),
    Workflow(
        "palette-check",
        "Check that a palette stays distinguishable for colour-vision-deficient observers.",
        "imageform.workflows.color:palette_check",
        PaletteCheckOptions,
        (Input("colors", 'Comma-separated hex colours, e.g. "#E69F00,#56B4E9".', kind="text"),),
        None,
        group="colour",
        description="Exit code 3 when any condition is under the threshold.",
    ),
)
