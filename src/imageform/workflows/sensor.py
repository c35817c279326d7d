"""Sensor workflows: ``mosaic`` (Bayer sampling) and ``demosaic`` (its reconstruction).

Mosaics are grey images (PNG 8/16-bit, TIFF, ``.npy``); an 8-bit or 16-bit input gives an
output of the same depth. ``imageform mosaic`` keeps the image's size, odd or even;
``imageform demosaic`` refuses an odd-sized mosaic unless ``--allow-odd`` (a raw frame is
made of whole 2x2 cells, so an odd size usually means a crop), in which case the cell is cut
at the bottom/right edge as :func:`imageform.sensor.mosaic` cut it.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Literal, get_args

from imageform.errors import InvalidInputError
from imageform.workflows._images import ImageIn, ImageOut, image_out_renames, read, write
from imageform.workflows._spec import Input, Output, Result, Run, Workflow, option

__all__ = ["WORKFLOWS", "DemosaicOptions", "MosaicOptions"]

#: The Bayer patterns (imageform.sensor.CFA_PATTERNS, in the normalised spelling).
_Pattern = Literal["rggb", "bggr", "grbg", "gbrg"]
_PATTERNS = get_args(_Pattern)
#: imageform.sensor.DEMOSAIC_METHODS (kept literal: ``--help`` imports no numerical code).
# imageform.sensor.DEMOSAIC_METHODS (the one list), spelled out so that --help imports no
# NumPy; tests/test_registries.py checks that they are the same.
_DemosaicMethod = Literal["bilinear", "malvar", "hamilton_adams", "menon", "menon_soft"]
_DEMOSAIC_METHODS = get_args(_DemosaicMethod)


@image_out_renames
@dataclass(frozen=True, kw_only=True)
class MosaicOptions(ImageIn, ImageOut):
    """Options of ``imageform mosaic``."""

    pattern: _Pattern = option(
        "rggb", help="Bayer pattern of the colour filter array.", choices=_PATTERNS
    )


def mosaic(run: Run, opts: MosaicOptions, *, out: Path, image: Path) -> Result:
    """``imageform mosaic``: one colour per pixel, through a Bayer colour filter array."""
    from imageform.sensor import mosaic as sample

    img = read(image, opts)
    if img.shape[-1] != 3:
        raise InvalidInputError(f"{image}: expected an RGB image, got {img.shape[-1]} channel(s)")
    pattern = opts.pattern.upper()
    raw = sample(img, pattern)
    n_out = write(run, out, raw, opts, like=img)
    h, w = raw.shape[:2]
    summary = {
        "input": image,
        "output": out,
        "pattern": pattern,
        "shape": [h, w],
        "odd_size": bool(h % 2 or w % 2),
        "values_clipped": n_out,
    }
    text = [f"wrote {out} ({pattern} mosaic, {w} x {h} px)"]
    if h % 2 or w % 2:
        text.append("odd size: demosaic it with imageform demosaic --allow-odd")
    return Result(summary, tuple(text))


@image_out_renames
@dataclass(frozen=True, kw_only=True)
class DemosaicOptions(ImageIn, ImageOut):
    """Options of ``imageform demosaic``."""

    pattern: _Pattern = option("rggb", help="Bayer pattern of the mosaic.", choices=_PATTERNS)
    method: _DemosaicMethod = option("menon", help="Demosaicing method.", choices=_DEMOSAIC_METHODS)
    allow_odd: bool = option(
        False,
        help="Accept an odd height or width (the 2x2 cell is cut at the bottom/right edge, "
        "as imageform mosaic cuts it).",
    )


def demosaic(run: Run, opts: DemosaicOptions, *, out: Path, mosaic: Path) -> Result:
    """``imageform demosaic``: an RGB image from a Bayer mosaic."""
    import time

    from imageform.sensor import demosaic as reconstruct

    raw = read(mosaic, opts)
    if raw.shape[-1] != 1:
        raise InvalidInputError(
            f"{mosaic}: expected a single-channel raw mosaic (a grey image), got "
            f"{raw.shape[-1]} channels; a colour image is not a mosaic (make one with "
            "imageform mosaic)"
        )
    h, w = raw.shape[:2]
    if (h % 2 or w % 2) and not opts.allow_odd:
        raise InvalidInputError(
            f"{mosaic} is {w} x {h} px, not whole 2x2 Bayer cells; pass --allow-odd to cut the "
            "cell at the bottom/right edge"
        )
    pattern = opts.pattern.upper()
    t0 = time.perf_counter()
    rgb = reconstruct(raw, pattern, opts.method, allow_odd=opts.allow_odd)
    seconds = time.perf_counter() - t0
    n_out = write(run, out, rgb, opts, like=raw)
    summary = {
        "input": mosaic,
        "output": out,
        "pattern": pattern,
        "method": opts.method,
        "shape": list(rgb.shape),
        "values_clipped": n_out,
        "seconds": round(seconds, 4),
    }
    return Result(summary, (f"wrote {out} ({opts.method}, {w} x {h} px)",))


WORKFLOWS = (
    Workflow(
        "mosaic",
        "Sample an RGB image through a Bayer colour filter array (one colour per pixel).",
        "imageform.workflows.sensor:mosaic",
        MosaicOptions,
        (Input("image", "RGB image (PNG 8/16-bit, TIFF, JPEG or .npy)."),),
        Output("Output mosaic: a grey image (the input's bit depth) or .npy/.tif (float)."),
        batch=True,
        group="sensor",
    ),
    Workflow(
        "demosaic",
        "Reconstruct an RGB image from a Bayer mosaic (demosaicing).",
        "imageform.workflows.sensor:demosaic",
        DemosaicOptions,
        (Input("mosaic", "Bayer mosaic: a grey image (PNG 8/16-bit, TIFF) or .npy (H, W)."),),
        Output("Output RGB image (PNG keeps the mosaic's bit depth; .tif/.npy float)."),
        batch=True,
        group="sensor",
    ),
)
