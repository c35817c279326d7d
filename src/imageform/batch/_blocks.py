"""The per-block operations of chunked processing and their global statistics.

Each block function maps one encoded RGB block to float32 with fixed parameters; the
parameters that depend on the whole image (the white-balance illuminant, a slide's stain
statistics) are measured first, by a dask reduction or on a reduced level or a subsample.
Used by :mod:`imageform.batch.chunked`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Literal

import numpy as np

from imageform._validate import check_option
from imageform.batch._lazy import _TiffMeta
from imageform.errors import InvalidInputError, UnreadableFileError
from imageform.workflows.color import CHUNKED_CHOICES

#: The white-balance methods (of :data:`imageform.color.WHITE_BALANCE_METHODS`, the one
#: list, which the test of the registries checks) whose illuminant is a streaming reduction
#: (or needs none); ``imageform chunked white-balance --method`` lists these alone.
_WB_METHODS = CHUNKED_CHOICES["white_balance"]["method"]


def _convert_block(block: np.ndarray, src: str, dst: str, params: dict[str, Any]) -> np.ndarray:
    from imageform.color import convert
    from imageform.workflows.color import as_values  # a linear file's codes as floats

    return np.asarray(convert(as_values(block, src), src, dst, **params), dtype=np.float32)


def _balance_block(block: np.ndarray, gains: np.ndarray, transfer: str = "srgb") -> np.ndarray:
    from imageform._validate import as_image
    from imageform.color.transfer import decode, encode

    lin = decode(as_image(block, "image", channels=3), transfer)
    return np.asarray(encode(lin * gains, transfer), dtype=np.float32)


def _linear_block(block: np.ndarray, p: float, transfer: str = "srgb") -> np.ndarray:
    from imageform._validate import as_image
    from imageform.color.transfer import decode

    lin = np.asarray(decode(as_image(block, "image", channels=3), transfer), dtype=np.float64)
    return lin if p == 1.0 else lin**p


def _wb_gains(
    x: Any, options: dict[str, Any], transfer: str = "srgb", space: str = "srgb"
) -> np.ndarray:
    """White-balance gains in linear light; the illuminant is a reduction over all blocks.

    ``transfer`` decodes the blocks (the file's declared encoding), ``space`` is the RGB
    space of ``manual``'s white.
    """
    from imageform.color.white_balance import white_balance

    method = check_option(
        options.get("method", "gray_world"),
        _WB_METHODS,
        "white-balance method for chunked processing",
    )
    normalize = check_option(options.get("normalize", "mean"), ("mean", "green"), "normalize")
    if method == "manual":  # the gains do not depend on the image
        probe = np.full((1, 1, 3), 0.5, dtype=np.float32)
        kw = {k: options[k] for k in ("illuminant", "cct") if options.get(k) is not None}
        return np.asarray(
            white_balance(probe, "manual", normalize=normalize, space=space, **kw).gains
        )
    p = float(options.get("p", 6.0)) if method == "shades_of_gray" else 1.0
    if p < 1.0:
        raise InvalidInputError(f"expected Minkowski p >= 1, got {p!r}")
    powered = x.map_blocks(_linear_block, p, transfer, dtype=np.float64)
    e = np.asarray(powered.mean(axis=(0, 1)).compute()) ** (1.0 / p)
    if not np.all(e > 0):
        raise InvalidInputError(f"illuminant estimate {e.tolist()} has an empty channel")
    ref = e.mean() if normalize == "mean" else e[1]
    return (ref / e).astype(np.float32)


def _stain_block(
    block: np.ndarray,
    method: str,
    target: Any,
    source: Any,
    scale_by: Literal["max", "mean"] = "max",
) -> np.ndarray:
    """Normalise one block with the slide's and the target's statistics.

    ``scale_by``: Macenko's concentration reference, ``max`` or ``mean``.
    """
    from imageform import analysis

    if method == "macenko":
        out = analysis.macenko_normalize(block, target, source=source, reference=scale_by)
    else:
        out = analysis.reinhard_normalize(block, target, source_stats=source)
    return np.asarray(out, dtype=np.float32)


def _stain_stats(
    x: Any,
    opts: dict[str, Any],
    src: Path,
    meta: _TiffMeta | None,
    stats_from: str,
    budget: int,
) -> tuple[Any, Any, str]:
    """Return the target's statistics and the slide's own, with where they were measured.

    The target's come from a JSON file or a reference image; the slide's are measured on a
    reduced pyramid level (``level``; ``auto`` when the input has one: the largest level of
    at most ``budget`` pixels, read whole, as whole-slide tools estimate on a thumbnail) or a
    regular subsample of level 0 of at most that many pixels (every ``step``-th row and
    column, read block by block: every tile of level 0 is decoded once). ``budget`` is
    :data:`imageform.batch.chunked.STAIN_SAMPLE_PIXELS`, read when the run starts. Macenko's
    tissue mask is told the sample's pixel size when the TIFF states level 0's (OME, Aperio).
    """
    from imageform import analysis
    from imageform.io import read_image

    method = opts["method"]
    kind = analysis.MacenkoStains if method == "macenko" else analysis.ReinhardStats
    measure = analysis.macenko_stains if method == "macenko" else analysis.reinhard_stats
    target = Path(opts["target"])
    if not target.is_file():
        raise InvalidInputError(f"--target {target} does not exist")
    stats_t = kind.from_json(target) if target.suffix.lower() == ".json" else None
    if stats_t is None:
        ref = read_image(target)
        stats_t = measure(ref[..., :3] if ref.ndim == 3 else ref)
    levels = meta.levels if meta is not None else ()
    microns = meta.microns if meta is not None else None

    def own(img: Any, reduced: float) -> Any:
        """Measure the slide's statistics on ``img``, ``reduced`` times coarser than level 0."""
        if method != "macenko" or microns is None:
            return measure(img)
        mpp = float(np.sqrt(microns[0] * microns[1])) * reduced
        est = analysis.estimate_background(img)  # once, for the mask and the stains
        mask = analysis.tissue_mask(img, glass=False, he="auto", i0=est, pixel_size_um=mpp)
        return analysis.macenko_stains(img, mask=mask, i0=est)

    if stats_from == "level" and len(levels) < 2:
        raise InvalidInputError(
            f"--stats-from level needs a pyramidal TIFF input; {src} has one level"
        )
    if stats_from != "subsample" and len(levels) > 1:
        import tifffile

        small = [k for k in range(1, len(levels)) if np.prod(levels[k]) <= budget]
        k = small[0] if small else len(levels) - 1
        h, w = levels[k]
        step = max(1, int(np.ceil(np.sqrt(h * w / budget))))
        try:
            from imageform.io.image_io import is_dicom_file

            if is_dicom_file(src):  # a DICOM slide's level is a file of its series
                from imageform.io import dicom

                found = [f for f, fw, fh in dicom.slide_levels(src) if (fh, fw) == (h, w)]
                level = read_image(found[0], max_pixels=h * w)[..., :3]
            else:
                with tifffile.TiffFile(src) as tf:
                    level = tf.series[0].levels[k].asarray()
        except (MemoryError, InvalidInputError):
            raise
        except Exception as exc:  # a damaged tile: the codec's own error, in one line
            text = str(exc).strip().splitlines()
            why = f"{type(exc).__name__}: {text[0][:100]}" if text else type(exc).__name__
            raise UnreadableFileError(src, f"pyramid level {k} cannot be decoded ({why})") from None
        where = f"pyramid level {k} ({w} x {h})" + (f", every {step}th pixel" if step > 1 else "")
        return stats_t, own(level[::step, ::step], levels[0][1] / w * step), where
    h, w = int(x.shape[0]), int(x.shape[1])
    step = max(1, int(np.ceil(np.sqrt(h * w / budget))))
    sample = np.asarray(x[::step, ::step].compute())
    where = "level 0" + (f", every {step}th row and column" if step > 1 else ", every pixel")
    return stats_t, own(sample, float(step)), where
