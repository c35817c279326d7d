r"""One image larger than memory: a pointwise colour operation, chunk by chunk.

The input (a tiled TIFF through tifffile's Zarr store, or a Zarr array) is opened as a dask
array of ``chunk x chunk`` blocks; the operation runs block by block; the output (a tiled
TIFF or a Zarr array) is written one band of block rows at a time. Global statistics (the
grey-world and shades-of-grey illuminant of white balance) are real dask reductions over the
whole image, a first pass before the pointwise pass. Peak memory is bounded by one output
band plus a few blocks per thread, independent of the image's height:

.. math:: M \approx c\,W\,C\,b_{out} + T\,k\,c^2 C\,4

(``c`` the chunk size, ``W`` the width, ``C`` channels, ``b_out`` bytes per output sample,
``T`` threads, ``k`` ~ 6 float32 temporaries per block). benchmarks/bench_chunked.py
measures it.

A pyramidal TIFF (a whole-slide image as scanners and tifffile write it: full resolution
first, reduced levels as SubIFDs or further pages of the series) gives a pyramidal output:
level 0 processed block by block, then each reduced level the box mean (``f x f``, ``f``
the input's factor between levels, usually 2 or 4) of the *processed* level above, computed
in the same block tasks and spooled to a raw scratch file beside the output, so no level is
ever held whole: the bound above gains one band of the level being read back (at most
``c W C b_out / f``) and the reduced band of each block row (a quarter of that). Tiles,
compression (JPEG at quality :data:`JPEG_QUALITY` for JPEG inputs), resolution and
description follow the input's. benchmarks/bench_wsi.py measures a 40000 x 40000 slide.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np

from imageform._files import atomic_write, remove_stale_parts
from imageform._validate import check_option
from imageform.batch._blocks import (
    _WB_METHODS,
    _balance_block,
    _convert_block,
    _stain_block,
    _stain_stats,
    _wb_gains,
)
from imageform.batch._lazy import (
    _chunk_size,
    _dicom_meta,
    _factor,
    _kind,
    _open_lazy,
    _tiff_meta,
    open_lazy,
)
from imageform.batch._write import (
    JPEG_QUALITY,  # noqa: F401 - documented here (process_chunked's compression)
    _check_tile,
    _out_compression,
    _pyramid_levels,
    _TiffSpec,
    _write_tiff,
    _write_zarr,
)
from imageform.errors import (
    ImageformError,
    InvalidInputError,
    UnknownOptionError,
    UnreadableFileError,
)
from imageform.workflows.color import CHUNKED_OPTIONS, DISPLAYABLE_SPACES, declared_encoding

__all__ = ["CHUNKED_COMMANDS", "ChunkedResult", "open_lazy", "process_chunked"]

#: Commands :func:`process_chunked` runs.
CHUNKED_COMMANDS = ("convert", "white_balance", "stain_normalize")
#: Most pixels of the regular subsample on which a slide's own stain statistics are measured
#: (every s-th row and column; a whole-slide tool estimates on a thumbnail the same way).
STAIN_SAMPLE_PIXELS = 4_000_000
_OUT_DTYPES = ("uint8", "uint16", "float32")
#: ``pyramid`` choices: the input's levels when it has them, none, or built by halving.
PYRAMID_MODES = ("auto", "none", "build")
#: Where stain statistics come from: ``auto`` (a reduced level when the input is a pyramid,
#: else a subsample of level 0), ``level`` or ``subsample``.
STATS_SOURCES = ("auto", "level", "subsample")


@dataclass(frozen=True)
class ChunkedResult:
    """What :func:`process_chunked` did.

    ``clipped`` counts the values outside [0, 1] clipped to fit an integer output (0 for
    float32); ``gains`` are the white-balance gains (None for convert); ``levels`` the
    (height, width) of each level written (one for a flat output); ``compression`` the
    TIFF output's (None for Zarr); ``stats_from`` where stain statistics were measured.
    """

    output: Path
    shape: tuple[int, ...]
    dtype: str
    chunk: int
    clipped: int
    gains: tuple[float, ...] | None
    seconds: float
    levels: tuple[tuple[int, int], ...] = ()
    compression: str | None = None
    stats_from: str | None = None


#: Options of each command that chunked processing honours (the others must keep their
#: default).
_HONOURED = CHUNKED_OPTIONS


def _declared(path: Path) -> str:
    """Name the RGB space an image file declares (``image_color_space``), or srgb."""
    from imageform.io import IMAGE_FORMATS, image_color_space

    if path.suffix.lower() not in IMAGE_FORMATS or not path.is_file():
        return "srgb"  # a Zarr store declares nothing imageform reads
    return image_color_space(path).name or "srgb"


def _out_space(
    cmd: str, opts: dict[str, Any], src: Path, meta: Any
) -> tuple[bytes | None, str | None]:
    """Return the output TIFF's colour space: (an ICC profile to embed, a space to record).

    ``convert`` writes its ``to`` space as :func:`imageform.io.write_image` would (a shipped
    profile; sRGB none; a space without a profile, Lab, XYZ, HSV, linear ..., named in the
    description); white balance and stain normalisation keep the input's space (its profile's
    bytes, or the space its description recorded), so that ``--from auto`` reads it back.
    """
    from imageform.io import image_color_space
    from imageform.io.icc import RGB_PROFILED, embedded_profile

    if cmd == "convert":
        to = str(opts["to"])
        return (embedded_profile(to), None) if to in RGB_PROFILED else (None, to)
    icc = meta.icc if meta is not None else None
    if icc is not None or src.suffix.lower() not in (".tif", ".tiff"):
        return icc, None
    declared = image_color_space(src)
    return None, declared.name if declared.source == "tiff-description" else None


def _options(cmd: str, options: Any) -> dict[str, Any]:
    """Return the options of ``cmd``, as the names the block functions use.

    The single command's defaults apply (its options dataclass, or a mapping by field name or flag).
    """
    import dataclasses

    from imageform.batch._plan import batch_options

    given = options
    if isinstance(options, dict) and cmd == "white_balance" and "method" in options:
        # the methods chunked processing can stream, checked before the dataclass's own list
        _wb_method(options["method"])
    opts = batch_options(cmd, given)
    out: dict[str, Any] = {}
    honoured = _HONOURED[cmd]
    for f in dataclasses.fields(opts):
        value = getattr(opts, f.name)
        if f.name in honoured:
            out[honoured[f.name]] = value
        elif f.name in ("alpha", "max_pixels", "bit_depth", "out_of_range", "clip"):
            continue  # reading and writing are chunked's own (--dtype)
        elif value != f.default:
            from imageform.workflows import flag_of

            raise InvalidInputError(
                f"imageform chunked {cmd.replace('_', '-')} does not take {flag_of(f)}; it "
                f"takes {', '.join('--' + v for v in honoured.values())}"
            )
    if cmd == "white_balance":
        out["method"] = _wb_method(out["method"])
    return out


def _wb_method(value: object) -> str:
    """Return a white-balance method chunked processing streams, normalised; else raise.

    One line: for another method of :func:`~imageform.color.white_balance` (``pca``), the
    methods chunked processing streams, not that the name is unknown.
    """
    from imageform.color import WHITE_BALANCE_ALIASES, WHITE_BALANCE_METHODS

    what = "white-balance method for chunked processing"
    try:
        return check_option(value, _WB_METHODS, what)
    except UnknownOptionError:
        key = value.strip().lower().replace("-", "_") if isinstance(value, str) else None
        if key not in {*WHITE_BALANCE_METHODS, *WHITE_BALANCE_ALIASES, "chart"}:
            raise
    streamed = ", ".join(repr(m) for m in _WB_METHODS)
    raise UnknownOptionError(
        f"chunked processing streams the white-balance methods {streamed} only, got {value!r} "
        "(the others need the whole image)"
    )


def _full_range(block: np.ndarray, bits: int) -> np.ndarray:
    """Scale a block of ``bits``-bit integer samples to its container's full range."""
    top = (1 << bits) - 1
    scale = np.float64(np.iinfo(block.dtype).max) / top
    return np.round(np.minimum(block, top) * scale).astype(block.dtype)


def process_chunked(
    src: str | Path,
    dst: str | Path,
    command: str,
    options: dict[str, Any] | None = None,
    *,
    chunk: int = 1024,
    dtype: Literal["uint8", "uint16", "float32"] | None = None,
    tile: int | None = None,
    force: bool = False,
    num_workers: int | None = None,
    pyramid: str = "auto",
    compression: Literal["none", "zlib", "lzw", "zstd", "jpeg"] | None = None,
    stats_from: str = "auto",
) -> ChunkedResult:
    r"""Apply ``convert``, ``white_balance`` or ``stain_normalize`` chunk-wise.

    The image may be larger than memory; a pyramidal TIFF (a whole-slide image) gives a
    pyramidal TIFF.

    .. math:: \text{out}[b] = f(\text{in}[b];\ \theta),\qquad
        \theta = \text{gains } \bar e / e_c,\ e_c = \big(\operatorname{mean}_{\text{all}}
        \rho_c^p\big)^{1/p}

    Pointwise, so each block ``b`` gives the same numbers as the whole image in memory; the
    white-balance illuminant ``e`` is a reduction over every block (a first pass). Stain
    normalisation measures the slide's own statistics (Macenko's stain vectors and
    concentration range, or Reinhard's CIELAB mean and standard deviation) on a reduced
    pyramid level or a regular subsample of at most :data:`STAIN_SAMPLE_PIXELS` (the whole
    image when smaller), then maps every block to the target's with those fixed statistics.

    A reduced level ``k`` of the output is the box mean of the processed level ``k - 1``
    over ``f x f`` pixels (``f`` the factor between the input's levels; a partial box at
    the right and bottom edges averages the pixels it has), rounded half up for integers:

    .. math:: L_k[i, j] = \frac{1}{|B_{ij}|} \sum_{(u, v) \in B_{ij}} L_{k-1}[u, v]

    (the area ("box") reduction of OpenSlide's and libvips' pyramids).

    Parameters
    ----------
    src : path
        A TIFF (tiled, strips, or a pyramid: its first series, level 0 processed) or a
        ``.zarr`` array, shape (H, W, 3), encoded RGB (uint8/uint16 full range, or floats in
        [0, 1]).
    dst : path
        ``.tif``/``.tiff`` (tiled, BigTIFF when needed) or ``.zarr``; written under a
        temporary name in the same folder and renamed when complete.
    command : {"convert", "white_balance", "stain_normalize"}
        ``convert`` takes options ``from`` (default ``srgb``), ``to``, ``white``;
        ``white_balance`` takes ``method`` (gray_world, shades_of_gray, manual), ``p``,
        ``normalize``, ``illuminant``/``cct`` (manual); ``stain_normalize`` takes ``target``
        (a reference image or its statistics as JSON), ``method`` (macenko, reinhard) and
        ``scale_by`` (macenko: ``max``, the 99th-percentile concentrations, or ``mean``,
        the same at any pixel size: for statistics measured on a reduced level).
    options : dict, optional
        The command's options named above (default: the command's defaults).
    chunk : int
        Block size in pixels (a multiple of ``tile``, of the input's tiles for speed, and of
        each pyramid factor).
    dtype : {"uint8", "uint16", "float32"}, optional
        Output samples; by default the input's integer type (float32 for float input or for
        a destination space that is not displayable RGB). Integer output clips values
        outside [0, 1]; how many is reported in ``clipped``.
    tile : int, optional
        Tile side of a TIFF output (default: the input's square tiles, else 256; ``chunk``
        must be a multiple of it).
    force : bool
        Replace an existing ``dst``.
    num_workers : int, optional
        Threads of dask's threaded scheduler and of tile compression (default: CPU count).
    pyramid : {"auto", "none", "build"}
        ``auto``: the input's pyramid levels written back (a flat input gives a flat output);
        ``none``: level 0 only; ``build``: the input's levels, or for a flat input halvings
        until the short side fits in a tile. A Zarr output holds level 0 only.
    compression : {"none", "zlib", "lzw", "zstd", "jpeg"}, optional
        Of a TIFF output; default: the input TIFF's when tifffile writes it (JPEG, at
        quality :data:`JPEG_QUALITY`, for uint8 output only, else zlib), none otherwise.
    stats_from : {"auto", "level", "subsample"}
        Where ``stain_normalize`` measures the slide's statistics: ``level``, the largest
        reduced pyramid level of at most :data:`STAIN_SAMPLE_PIXELS` (a pyramid only);
        ``subsample``, every s-th row and column of level 0 (a decoding pass over level 0);
        ``auto``, a level when the input is a pyramid, else the subsample.

    Returns
    -------
    ChunkedResult

    Examples
    --------
    >>> import tempfile, pathlib, tifffile
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> img = np.full((300, 400, 3), 128, dtype=np.uint8)
    >>> tifffile.imwrite(d / "in.tif", img, tile=(256, 256), photometric="rgb")
    >>> r = process_chunked(d / "in.tif", d / "out.zarr", "convert", {"to": "linear_srgb"},
    ...                     chunk=256, dtype="float32")
    >>> import zarr; round(float(zarr.open(str(r.output), mode="r")[0, 0, 0]), 6)
    0.215861
    >>> r = process_chunked(d / "in.tif", d / "pyr.tif", "convert", {"to": "display_p3"},
    ...                     chunk=256, pyramid="build", tile=64)
    >>> r.levels
    ((300, 400), (150, 200), (75, 100), (38, 50))
    """
    from imageform._optional import require
    from imageform._validate import as_bool, as_int, as_path

    t0 = time.perf_counter()
    src_p, dst_p = as_path(src, "src"), as_path(dst, "dst")
    cmd = check_option(command, CHUNKED_COMMANDS, "chunked command")
    opts = _options(cmd, options)
    out_kind = _kind(dst_p, output=True)
    chunk = _chunk_size(chunk)
    pyramid = check_option(pyramid, PYRAMID_MODES, "pyramid")
    stats_from = check_option(stats_from, STATS_SOURCES, "stats_from")
    if tile is not None:
        tile = as_int(tile, "tile", minimum=16, maximum=chunk)
        _check_tile(chunk, tile)
    force = as_bool(force, "force")
    if num_workers is not None:
        num_workers = as_int(num_workers, "num_workers", minimum=1, maximum=1024)
    if dst_p.resolve() == src_p.resolve():
        raise InvalidInputError(f"output {dst_p} is the input; choose another path")
    if dst_p.exists() and not force:
        raise InvalidInputError(f"output {dst_p} exists; pass --force to overwrite it")
    if not dst_p.parent.is_dir():
        raise InvalidInputError(f"output folder {dst_p.parent} does not exist")
    if out_kind == "zarr" and pyramid == "build":
        raise InvalidInputError(f"--pyramid build needs a .tif output, got {dst_p}")
    dask = require("dask", what="imageform chunked")
    remove_stale_parts(dst_p)  # left by a run killed mid-write (SIGKILL cannot be caught)
    opened: list[Any] = []  # the TIFF stores this run opens: closed when it ends
    try:
        x = _open_lazy(src_p, chunk, opened)
        meta = None
        if _kind(src_p) in ("tiff", "dicom"):
            try:
                meta = _tiff_meta(src_p) if _kind(src_p) == "tiff" else _dicom_meta(src_p)
            except ImageformError:
                raise
            except Exception as exc:  # pragma: no cover - open_lazy read it already
                raise UnreadableFileError(src_p, str(exc)[:120]) from exc
        if tile is None:
            tile = meta.tile if meta is not None and meta.tile and chunk % meta.tile == 0 else 256
            tile = min(tile, chunk)
        _check_tile(chunk, tile)
        shape0 = (int(x.shape[0]), int(x.shape[1]))
        levels = _pyramid_levels(pyramid, meta, shape0, tile) if out_kind == "tiff" else (shape0,)
        for k in range(1, len(levels)):
            f = _factor(levels[k - 1], levels[k])
            if chunk % f:
                raise InvalidInputError(
                    f"expected chunk a multiple of the pyramid factor {f} (level {k}), got {chunk}"
                )
        in_int = x.dtype in (np.uint8, np.uint16)
        if in_int and meta is not None and meta.bits and meta.bits < 8 * x.dtype.itemsize:
            # 10, 12, 14-bit samples in uint16 are colours with 2**bits - 1 as white: scaled to
            # the container's range, as imageform convert reads them
            x = x.map_blocks(_full_range, meta.bits, dtype=x.dtype)
        gains: np.ndarray | None = None
        where: str | None = None
        workers = num_workers or os.cpu_count() or 1
        with dask.config.set(scheduler="threads", num_workers=workers):
            if cmd == "convert":
                s, d = opts["from"], opts["to"]
                if s == "auto":  # the space the file declares (ICC profile), else sRGB
                    s = _declared(src_p)
                params = {k: opts[k] for k in ("white",) if opts.get(k) is not None}
                op: tuple[Any, ...] = (_convert_block, s, d, params)
                displayable = d in DISPLAYABLE_SPACES
            elif cmd == "stain_normalize":
                stats_t, stats_s, where = _stain_stats(
                    x, opts, src_p, meta, stats_from, STAIN_SAMPLE_PIXELS
                )
                op = (_stain_block, opts["method"], stats_t, stats_s, opts["scale-by"])
                displayable = True
            else:
                transfer, space = declared_encoding(_declared(src_p))  # linear: as linear
                gains = _wb_gains(x, opts, transfer, space)
                op = (_balance_block, gains, transfer)
                displayable = True
            out_dtype = dtype or (str(x.dtype) if in_int and displayable else "float32")
            check_option(out_dtype, _OUT_DTYPES, "output dtype")
            if out_dtype != "float32" and not displayable:
                raise InvalidInputError(f"{opts.get('to')} values are not in [0, 1]: use float32")
            comp = _out_compression(compression, meta, out_dtype) if out_kind == "tiff" else None
            written: list[int] = []

            def write(tmp: Path) -> None:
                if out_kind == "zarr":
                    written.append(_write_zarr(tmp, x, op, out_dtype, chunk))
                else:
                    icc, recorded = _out_space(cmd, opts, src_p, meta)
                    spec = _TiffSpec(levels, tile, str(comp), workers, meta, icc, recorded)
                    written.append(_write_tiff(tmp, x, op, out_dtype, chunk, spec))

            # all or nothing (imageform._files): a FIFO or a device at dst is never replaced, a
            # Zarr folder is swapped in whole, an error or Ctrl-C removes the temporary
            atomic_write(dst_p, write, folder=out_kind == "zarr")
            clipped = written[0]
        return ChunkedResult(
            dst_p,
            tuple(int(v) for v in x.shape),
            out_dtype,
            chunk,
            clipped if out_dtype != "float32" else 0,
            None if gains is None else tuple(float(g) for g in gains),
            time.perf_counter() - t0,
            levels,
            comp,
            where,
        )
    finally:
        for store in opened:
            store.close()
