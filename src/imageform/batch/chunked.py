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

import glob
import os
import shutil
import time
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from imageform._files import publish
from imageform._validate import check_option
from imageform.errors import ImageformError, InvalidInputError
from imageform.workflows.color import DISPLAYABLE_SPACES

__all__ = ["CHUNKED_COMMANDS", "ChunkedResult", "open_lazy", "process_chunked"]

#: Commands :func:`process_chunked` runs.
CHUNKED_COMMANDS = ("convert", "white_balance", "stain_normalize")
#: Most pixels of the regular subsample on which a slide's own stain statistics are measured
#: (every s-th row and column; a whole-slide tool estimates on a thumbnail the same way).
STAIN_SAMPLE_PIXELS = 4_000_000
#: The white-balance methods (of :data:`imageform.color.WHITE_BALANCE_METHODS`, the one
#: list, which the test of the registries checks) whose illuminant is a streaming reduction
#: (or needs none).
_WB_METHODS = ("gray_world", "shades_of_gray", "manual")
_OUT_DTYPES = ("uint8", "uint16", "float32")
#: ``pyramid`` choices: the input's levels when it has them, none, or built by halving.
PYRAMID_MODES = ("auto", "none", "build")
#: Where stain statistics come from: ``auto`` (a reduced level when the input is a pyramid,
#: else a subsample of level 0), ``level`` or ``subsample``.
STATS_SOURCES = ("auto", "level", "subsample")
#: Compressions of a TIFF output (``None``: the input's, when tifffile can write it).
_COMPRESSIONS = ("none", "zlib", "lzw", "zstd", "jpeg")
#: JPEG quality of a JPEG output (the input's quality is not stored in the file).
JPEG_QUALITY = 90


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


def _kind(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix in (".tif", ".tiff"):
        return "tiff"
    if suffix == ".zarr":
        return "zarr"
    raise InvalidInputError(f"expected a tiled .tif/.tiff or a .zarr array, got {path}")


class _ContiguousRows:
    """The pixels of an uncompressed, contiguous (strip or single-strip) TIFF page, read by block.

    Blocks are read with ``pread`` (one read per row of the block): a block costs its own samples,
    never the whole strip (tifffile's Zarr store has one chunk per strip, and an uncompressed TIFF
    is often one strip: the whole image).
    """

    def __init__(self, path: Path, offset: int, shape: tuple[int, ...], dtype: Any) -> None:
        self.path, self.offset = path, offset
        self.shape, self.dtype, self.ndim = shape, np.dtype(dtype), len(shape)

    def __getitem__(self, key: Any) -> np.ndarray:
        if not isinstance(key, tuple):
            key = (key,)
        key = key + (slice(None),) * (self.ndim - len(key))
        if not all(isinstance(k, slice) for k in key[:2]):
            raise TypeError("expected slices of rows and columns")
        r0, r1, rstep = key[0].indices(self.shape[0])
        c0, c1, cstep = key[1].indices(self.shape[1])
        r1, c1 = max(r1, r0), max(c1, c0)
        pixel = int(np.prod(self.shape[2:])) * self.dtype.itemsize
        row_bytes, width = self.shape[1] * pixel, (c1 - c0) * pixel
        out = np.empty((r1 - r0, c1 - c0, *self.shape[2:]), dtype=self.dtype)
        flat = out.reshape(r1 - r0, -1).view(np.uint8)
        with open(self.path, "rb") as fh:  # one read per row: only this block's columns
            for i in range(r1 - r0):
                buf = os.pread(fh.fileno(), width, self.offset + (r0 + i) * row_bytes + c0 * pixel)
                if len(buf) != width:
                    raise InvalidInputError(f"{self.path} is truncated (row {r0 + i} missing)")
                flat[i] = np.frombuffer(buf, dtype=np.uint8)
        return out[(slice(None, None, rstep), slice(None, None, cstep), *key[2:])]


class _DecodedOnce:
    """Blocks of a Zarr array whose chunks (TIFF tiles or strips) are larger than the blocks.

    Zarr decodes a whole chunk for every block read from it: a 16384^2 single-tile TIFF was
    decoded 256 times at ``--chunk 1024``. Here each decoded chunk is kept while the blocks inside
    it are read, and decoded once (a lock per chunk: the blocks of a row run in parallel). The
    cache holds the chunks of one block row and the next row of chunks (LRU), so that memory
    stays bounded by a band of the image, and a chunk is decoded once when blocks go row by row.
    """

    def __init__(self, z: Any, chunk: int) -> None:
        import threading
        from collections import OrderedDict

        self.z, self.shape, self.dtype, self.ndim = z, tuple(z.shape), np.dtype(z.dtype), z.ndim
        self.cell = (int(z.chunks[0]), int(z.chunks[1]))
        across = -(-self.shape[1] // self.cell[1])
        self.capacity = (-(-chunk // self.cell[0]) + 1) * across
        self.decodes = 0
        self._cells: OrderedDict[tuple[int, int], np.ndarray] = OrderedDict()
        self._lock = threading.Lock()
        self._locks: dict[tuple[int, int], Any] = {}

    def _decoded(self, i: int, j: int) -> np.ndarray:
        import threading

        key = (i, j)
        with self._lock:
            if key in self._cells:
                self._cells.move_to_end(key)
                return self._cells[key]
            lock = self._locks.setdefault(key, threading.Lock())
        with lock:
            with self._lock:
                if key in self._cells:
                    return self._cells[key]
            ch, cw = self.cell
            a = np.asarray(self.z[i * ch : (i + 1) * ch, j * cw : (j + 1) * cw])
            with self._lock:
                self.decodes += 1
                self._cells[key] = a
                while len(self._cells) > self.capacity:
                    self._cells.popitem(last=False)
                self._locks.pop(key, None)
            return a

    def __getitem__(self, key: Any) -> np.ndarray:
        if not isinstance(key, tuple):
            key = (key,)
        key = key + (slice(None),) * (self.ndim - len(key))
        if not all(isinstance(k, slice) for k in key[:2]):
            raise TypeError("expected slices of rows and columns")
        r0, r1, rstep = key[0].indices(self.shape[0])
        c0, c1, cstep = key[1].indices(self.shape[1])
        r1, c1 = max(r1, r0), max(c1, c0)
        out = np.empty((r1 - r0, c1 - c0, *self.shape[2:]), dtype=self.dtype)
        ch, cw = self.cell
        for i in range(r0 // ch, -(-r1 // ch)):
            for j in range(c0 // cw, -(-c1 // cw)):
                cell = self._decoded(i, j)
                a0, a1 = max(r0, i * ch), min(r1, (i + 1) * ch)
                b0, b1 = max(c0, j * cw), min(c1, (j + 1) * cw)
                out[a0 - r0 : a1 - r0, b0 - c0 : b1 - c0] = cell[
                    a0 - i * ch : a1 - i * ch, b0 - j * cw : b1 - j * cw
                ]
        return out[(slice(None, None, rstep), slice(None, None, cstep), *key[2:])]


def _tiff_lazy(p: Path, chunk: int, da: Any, zarr: Any, opened: list[Any] | None) -> Any:
    import tifffile

    with tifffile.TiffFile(p) as tf:
        page = tf.pages[0]
        strips = (
            isinstance(page, tifffile.TiffPage)
            and not page.is_tiled
            and page.compression == 1
            and page.planarconfig == 1
            and page.is_contiguous
            and len(tf.series[0].levels) == 1
        )
        if strips:
            src = _ContiguousRows(p, int(page.dataoffsets[0]), tuple(page.shape), page.dtype)
    if strips:
        if len(src.shape) != 3 or src.shape[-1] != 3:
            raise InvalidInputError(f"{p}: expected an RGB image (H, W, 3), got {src.shape}")
        st = p.stat()
        return da.from_array(
            src,
            chunks=(chunk, chunk, 3),
            name=f"imageform-strips-{p}-{st.st_size}-{st.st_mtime_ns}",
            asarray=False,
            fancy=False,
        )
    import weakref

    store = tifffile.imread(p, aszarr=True)
    arr = zarr.open(store, mode="r")
    # the store holds the TIFF open: a caller that knows when it is done closes it (``opened``);
    # else it is closed when the array goes, not at interpreter exit (an unclosed file is a
    # ResourceWarning wherever the garbage collector happens to run)
    if opened is not None:
        opened.append(store)
    weakref.finalize(arr, store.close)
    return arr


@dataclass(frozen=True)
class _TiffMeta:
    """What a TIFF output copies from a TIFF input.

    The level sizes (level 0 first), the tile side (None: strips or non-square tiles),
    compression (tifffile's tag value), resolution (pixels per unit, x and y), its unit and
    level 0's description.
    """

    levels: tuple[tuple[int, int], ...]
    tile: int | None
    compression: int
    resolution: tuple[float, float] | None
    resolutionunit: int | None
    description: str | None
    ome: bool = False
    microns: tuple[float, float] | None = None


def _microns(desc: str) -> tuple[float, float] | None:
    """Return the pixel size in micrometres (x, y) a TIFF description states, or None.

    The description is an OME-XML (``PhysicalSizeX/Y``, in um) or an Aperio SVS one
    (``MPP = ...``).
    """
    import re

    if "Aperio" in desc[:200]:
        m = re.search(r"\bMPP\s*=\s*([0-9.eE+-]+)", desc)
        return (float(m.group(1)),) * 2 if m else None
    xs = re.search(r'PhysicalSizeX="([0-9.eE+-]+)"', desc)
    ys = re.search(r'PhysicalSizeY="([0-9.eE+-]+)"', desc)
    units = re.findall(r'PhysicalSize[XY]Unit="([^"]*)"', desc)
    if not xs or any(u not in ("µm", "um", "\u00b5m") for u in units):
        return None
    return float(xs.group(1)), float(ys.group(1)) if ys else float(xs.group(1))


def _factor(big: tuple[int, int], small: tuple[int, int]) -> int:
    """Return the whole reduction factor from ``big`` to ``small``, or 0 when there is none.

    Each side of ``small`` is the floor or ceil of ``big / f``.
    """
    f = max(1, round(big[0] / max(small[0], 1)))
    ok = all(s in (b // f, -(-b // f)) for b, s in zip(big, small, strict=True))
    return f if f >= 2 and ok else 0


def _tiff_meta(p: Path) -> _TiffMeta:
    """Read the levels and tags of a TIFF's first series, the pyramid checked.

    Every level is RGB like level 0, each a whole factor (2, 4, ...) smaller than the one
    above.
    """
    import tifffile

    with tifffile.TiffFile(p) as tf:
        series = tf.series[0]
        page = series.keyframe
        levels: list[tuple[int, int]] = []
        found: list[Any] = list(series.levels)
        if isinstance(page, tifffile.TiffPage) and page.subifds:
            # every SubIFD, not only those tifffile accepts as levels (it drops the others)
            found = [series, *tifffile.TiffPages(page)]
        for k, level in enumerate(found):
            shape = tuple(int(v) for v in level.shape)
            if len(shape) != 3 or shape[-1] != 3 or level.dtype != series.dtype:
                raise InvalidInputError(
                    f"{p}: pyramid level {k} is {level.dtype} {shape}; expected RGB "
                    f"(H, W, 3) {series.dtype} like level 0"
                )
            if levels and not _factor(levels[-1], shape[:2]):
                raise InvalidInputError(
                    f"{p}: pyramid level {k} is {shape[1]} x {shape[0]}, not level {k - 1} "
                    f"({levels[-1][1]} x {levels[-1][0]}) reduced by a whole factor"
                )
            levels.append((shape[0], shape[1]))
        tile = None
        if page.is_tiled and page.tilewidth == page.tilelength and page.tilewidth % 16 == 0:
            tile = int(page.tilewidth)
        tags = page.tags
        res: tuple[float, float] | None = None
        if "XResolution" in tags and "YResolution" in tags:
            xr, yr = tags["XResolution"].value, tags["YResolution"].value
            res = (xr[0] / xr[1], yr[0] / yr[1]) if xr[1] and yr[1] else None
        unit = int(tags["ResolutionUnit"].value) if "ResolutionUnit" in tags else None
        desc = page.description or None
        microns = _microns(desc) if desc else None
        if desc is not None and (
            page.is_shaped or tf.is_ome or tf.is_svs or desc.lstrip()[:1] in ("{", "<")
        ):
            # tifffile's shape, an OME-XML or an Aperio header describe the input's file
            # layout: the output is written afresh (OME-XML with the pixel size for OME)
            desc = None
        if microns is not None and (res is None or unit in (None, 1) or res == (1.0, 1.0)):
            res, unit = (1e4 / microns[0], 1e4 / microns[1]), 3  # pixels per centimetre
        return _TiffMeta(
            tuple(levels), tile, int(page.compression), res, unit, desc, tf.is_ome, microns
        )


#: tifffile's compression tag values a TIFF output can repeat, by name.
_COMPRESSION_NAMES = {1: "none", 5: "lzw", 7: "jpeg", 8: "zlib", 32946: "zlib", 50000: "zstd"}


def _out_compression(given: str | None, meta: _TiffMeta | None, dtype: str) -> str:
    """Return the TIFF output's compression: ``given``, or the input's.

    The input's when tifffile writes it (JPEG for uint8 only; another JPEG-like codec, JPEG
    2000 say, becomes zlib).
    """
    if given is not None:
        name = check_option(given, _COMPRESSIONS, "compression")
        if name == "jpeg" and dtype != "uint8":
            raise InvalidInputError(f"expected uint8 output for JPEG compression, got {dtype}")
        return name
    if meta is None:
        return "none"
    name = _COMPRESSION_NAMES.get(meta.compression, "zlib")
    return "zlib" if name == "jpeg" and dtype != "uint8" else name


def _pyramid_levels(
    mode: str, meta: _TiffMeta | None, shape: tuple[int, int], tile: int
) -> tuple[tuple[int, int], ...]:
    """Return the levels to write.

    The input's (``auto``, ``build``), level 0 only (``none``, or ``auto`` on a flat input),
    or halvings until the short side fits a tile (``build`` on a flat input).
    """
    if mode == "none":
        return (shape,)
    if meta is not None and len(meta.levels) > 1:
        return meta.levels
    if mode == "auto":
        return (shape,)
    levels = [shape]
    while min(levels[-1]) > tile:
        levels.append((-(-levels[-1][0] // 2), -(-levels[-1][1] // 2)))
    return tuple(levels)


#: The largest block side: a block of 3 float64 channels stays under 2 GiB.
_MAX_CHUNK = 16384


def _chunk_size(chunk: object) -> int:
    """Return the block side in pixels, 1 to 16384, refused by name otherwise."""
    from imageform._validate import as_int

    return as_int(chunk, "chunk", minimum=1, maximum=_MAX_CHUNK)


def open_lazy(path: str | Path, chunk: int = 1024) -> Any:
    """Open a TIFF or a Zarr array as a dask array of ``chunk x chunk`` blocks.

    Nothing is read until the array is computed. A tiled (or compressed strip) TIFF is read
    through tifffile's Zarr store, tile by tile (strip by strip: a compressed strip is
    decoded whole); an uncompressed strip TIFF (one strip or many) row band by row band from
    the file. Blocks have all channels (choose a multiple of the TIFF's tile size).
    """
    return _open_lazy(path, chunk, None)


def _open_lazy(path: str | Path, chunk: int, opened: list[Any] | None) -> Any:
    """:func:`open_lazy`; the TIFF stores it opens are appended to ``opened`` (if given)."""
    from imageform._optional import require
    from imageform._validate import as_path

    p = as_path(path, "path")
    chunk = _chunk_size(chunk)
    da = require("dask.array", what="imageform chunked")
    zarr = require("zarr", what="imageform chunked")
    if not p.exists():
        raise InvalidInputError(f"input {p} does not exist")
    try:
        if _kind(p) == "tiff":
            z: Any = _tiff_lazy(p, chunk, da, zarr, opened)
            if not isinstance(z, (zarr.Array, zarr.Group)):
                return z  # an uncompressed strip TIFF, already a dask array
        else:
            z = zarr.open(str(p), mode="r")
    except (ImageformError, MemoryError):
        raise
    except Exception as exc:  # a damaged file: tifffile's, zarr's or numcodecs' own errors
        text = str(exc).strip().splitlines()
        reason = text[0][:120] if text else type(exc).__name__
        raise InvalidInputError(f"cannot read {p}: {reason}") from exc
    if isinstance(z, zarr.Group):  # a pyramid: level 0 is the full resolution
        z = z["0"]
    if z.ndim != 3 or z.shape[-1] != 3:
        raise InvalidInputError(f"{p}: expected an RGB image (H, W, 3), got shape {z.shape}")
    if z.chunks[0] > chunk or z.chunks[1] > chunk:  # tiles or strips larger than a block
        st = p.stat()
        return da.from_array(
            _DecodedOnce(z, chunk),
            chunks=(chunk, chunk, z.shape[-1]),
            name=f"imageform-decoded-once-{p}-{st.st_size}-{st.st_mtime_ns}-{chunk}",
            asarray=False,
            fancy=False,
        )
    return da.from_zarr(z, chunks=(chunk, chunk, z.shape[-1]))


def _convert_block(block: np.ndarray, src: str, dst: str, params: dict[str, Any]) -> np.ndarray:
    from imageform.color import convert

    return np.asarray(convert(block, src, dst, **params), dtype=np.float32)


def _balance_block(block: np.ndarray, gains: np.ndarray) -> np.ndarray:
    from imageform._validate import as_image
    from imageform.color.transfer import decode, encode

    lin = decode(as_image(block, "image", channels=3), "srgb")
    return np.asarray(encode(lin * gains, "srgb"), dtype=np.float32)


def _linear_block(block: np.ndarray, p: float) -> np.ndarray:
    from imageform._validate import as_image
    from imageform.color.transfer import decode

    lin = np.asarray(decode(as_image(block, "image", channels=3), "srgb"), dtype=np.float64)
    return lin if p == 1.0 else lin**p


def _wb_gains(x: Any, options: dict[str, Any]) -> np.ndarray:
    """White-balance gains in linear light; the illuminant is a reduction over all blocks."""
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
        return np.asarray(white_balance(probe, "manual", normalize=normalize, **kw).gains)
    p = float(options.get("p", 6.0)) if method == "shades_of_gray" else 1.0
    if p < 1.0:
        raise InvalidInputError(f"expected Minkowski p >= 1, got {p!r}")
    powered = x.map_blocks(_linear_block, p, dtype=np.float64)
    e = np.asarray(powered.mean(axis=(0, 1)).compute()) ** (1.0 / p)
    if not np.all(e > 0):
        raise InvalidInputError(f"illuminant estimate {e.tolist()} has an empty channel")
    ref = e.mean() if normalize == "mean" else e[1]
    return (ref / e).astype(np.float32)


def _stain_block(block: np.ndarray, method: str, target: Any, source: Any) -> np.ndarray:
    from imageform import analysis

    if method == "macenko":
        out = analysis.macenko_normalize(block, target, source=source)
    else:
        out = analysis.reinhard_normalize(block, target, source_stats=source)
    return np.asarray(out, dtype=np.float32)


def _stain_stats(
    x: Any, opts: dict[str, Any], src: Path, meta: _TiffMeta | None, stats_from: str
) -> tuple[Any, Any, str]:
    """Return the target's statistics and the slide's own, with where they were measured.

    The target's come from a JSON file or a reference image; the slide's are measured on a
    reduced pyramid level (``level``; ``auto`` when the input has one: the largest level of
    at most :data:`STAIN_SAMPLE_PIXELS`, read whole, as whole-slide tools estimate on a
    thumbnail) or a regular subsample of level 0 of at most that many pixels (every
    ``step``-th row and column, read block by block: every tile of level 0 is decoded once).
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
    if stats_from == "level" and len(levels) < 2:
        raise InvalidInputError(
            f"--stats-from level needs a pyramidal TIFF input; {src} has one level"
        )
    if stats_from != "subsample" and len(levels) > 1:
        import tifffile

        small = [k for k in range(1, len(levels)) if np.prod(levels[k]) <= STAIN_SAMPLE_PIXELS]
        k = small[0] if small else len(levels) - 1
        h, w = levels[k]
        step = max(1, int(np.ceil(np.sqrt(h * w / STAIN_SAMPLE_PIXELS))))
        with tifffile.TiffFile(src) as tf:
            level = tf.series[0].levels[k].asarray()
        where = f"pyramid level {k} ({w} x {h})" + (f", every {step}th pixel" if step > 1 else "")
        return stats_t, measure(level[::step, ::step]), where
    h, w = int(x.shape[0]), int(x.shape[1])
    step = max(1, int(np.ceil(np.sqrt(h * w / STAIN_SAMPLE_PIXELS))))
    sample = np.asarray(x[::step, ::step].compute())
    where = "level 0" + (f", every {step}th row and column" if step > 1 else ", every pixel")
    return stats_t, measure(sample), where


def _temp(path: Path) -> Path:
    return path.with_name(f".{path.name}.{uuid.uuid4().hex[:12]}.tmp{path.suffix}")


def _remove_stale(path: Path) -> None:
    """Remove the temporaries of ``path`` that a killed run left behind."""
    for stale in path.parent.glob(f".{glob.escape(path.name)}.*.tmp{glob.escape(path.suffix)}"):
        shutil.rmtree(stale, ignore_errors=True) if stale.is_dir() else stale.unlink(
            missing_ok=True
        )


#: Options of each command that chunked processing honours (the others must keep their
#: default).
_HONOURED = {
    "stain_normalize": {"target": "target", "method": "method"},
    "convert": {"src": "from", "dst": "to", "white": "white"},
    "white_balance": {
        "method": "method",
        "p": "p",
        "normalize": "normalize",
        "illuminant": "illuminant",
        "cct": "cct",
    },
}


def _options(cmd: str, options: Any) -> dict[str, Any]:
    """Return the options of ``cmd``, as the names the block functions use.

    The single command's defaults apply (its options dataclass, or a mapping by field name or flag).
    """
    import dataclasses

    from imageform.batch.runner import batch_options

    given = options
    if isinstance(options, dict) and cmd == "white_balance" and "method" in options:
        # the methods chunked processing can stream, checked before the dataclass's own list
        method = str(options["method"]).lower().replace("-", "_")
        check_option(method, _WB_METHODS, "white-balance method for chunked processing")
    opts = batch_options(cmd, given)
    out: dict[str, Any] = {}
    honoured = _HONOURED[cmd]
    for f in dataclasses.fields(opts):
        value = getattr(opts, f.name)
        if f.name in honoured:
            out[honoured[f.name]] = value
        elif f.name in ("alpha", "max_pixels", "bits", "out_of_range", "clip"):
            continue  # reading and writing are chunked's own (--dtype)
        elif value != f.default:
            from imageform.workflows import flag_of

            raise InvalidInputError(
                f"imageform chunked {cmd.replace('_', '-')} does not take {flag_of(f)}; it "
                f"takes {', '.join('--' + v for v in honoured.values())}"
            )
    if cmd == "white_balance":
        check_option(out["method"], _WB_METHODS, "white-balance method for chunked processing")
    return out


def process_chunked(
    src: str | Path,
    dst: str | Path,
    command: str,
    options: dict[str, Any] | None = None,
    *,
    chunk: int = 1024,
    dtype: str | None = None,
    tile: int | None = None,
    force: bool = False,
    num_workers: int | None = None,
    pyramid: str = "auto",
    compression: str | None = None,
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
        (a reference image or its statistics as JSON) and ``method`` (macenko, reinhard).
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
    out_kind = _kind(dst_p)
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
    _remove_stale(dst_p)  # left by a run killed mid-write (SIGKILL cannot be caught)
    opened: list[Any] = []  # the TIFF stores this run opens: closed when it ends
    try:
        x = _open_lazy(src_p, chunk, opened)
        meta = None
        if _kind(src_p) == "tiff":
            try:
                meta = _tiff_meta(src_p)
            except ImageformError:
                raise
            except Exception as exc:  # pragma: no cover - open_lazy read it already
                raise InvalidInputError(f"cannot read {src_p}: {str(exc)[:120]}") from exc
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
        gains: np.ndarray | None = None
        where: str | None = None
        workers = num_workers or os.cpu_count() or 1
        with dask.config.set(scheduler="threads", num_workers=workers):
            if cmd == "convert":
                s, d = opts["from"], opts["to"]
                params = {k: opts[k] for k in ("white",) if opts.get(k) is not None}
                op: tuple[Any, ...] = (_convert_block, s, d, params)
                displayable = d in DISPLAYABLE_SPACES
            elif cmd == "stain_normalize":
                stats_t, stats_s, where = _stain_stats(x, opts, src_p, meta, stats_from)
                op = (_stain_block, opts["method"], stats_t, stats_s)
                displayable = True
            else:
                gains = _wb_gains(x, opts)
                op = (_balance_block, gains)
                displayable = True
            out_dtype = dtype or (str(x.dtype) if in_int and displayable else "float32")
            check_option(out_dtype, _OUT_DTYPES, "output dtype")
            if out_dtype != "float32" and not displayable:
                raise InvalidInputError(f"{opts.get('to')} values are not in [0, 1]: use float32")
            comp = _out_compression(compression, meta, out_dtype) if out_kind == "tiff" else None
            tmp = _temp(dst_p)
            try:
                if out_kind == "zarr":
                    clipped = _write_zarr(tmp, x, op, out_dtype, chunk)
                else:
                    spec = _TiffSpec(levels, tile, str(comp), workers, meta)
                    clipped = _write_tiff(tmp, x, op, out_dtype, chunk, spec)
                # the one place an output appears: a FIFO or a device at dst is never replaced,
                # a Zarr folder is swapped in whole (imageform._files.publish)
                publish(tmp, dst_p, folder=out_kind == "zarr")
            except BaseException:
                if tmp.is_dir():
                    shutil.rmtree(tmp, ignore_errors=True)
                else:
                    tmp.unlink(missing_ok=True)
                raise
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


def _check_tile(chunk: int, tile: int) -> None:
    if chunk % tile or tile % 16:
        raise InvalidInputError(
            f"expected chunk a multiple of tile, and tile a multiple of 16, got chunk {chunk}, "
            f"tile {tile}"
        )


def _reduce(a: np.ndarray, f: int) -> np.ndarray:
    """Return the ``f x f`` box mean of ``a`` (H, W, C), ceil(H/f) x ceil(W/f).

    A partial box at the bottom or right edge averages the pixels it has; integers rounded
    half up. Summed as ``f`` row slices, then ``f`` column slices (a reshape-and-sum is ~20
    times slower).
    """
    h, w, c = a.shape
    hh, ww = -(-h // f), -(-w // f)
    partial = (hh * f, ww * f) != (h, w)
    if partial:
        a = np.pad(a, ((0, hh * f - h), (0, ww * f - w), (0, 0)))
    if a.dtype.kind == "f":
        acc: Any = np.float32 if a.dtype.itemsize <= 4 else np.float64
    else:
        acc = np.uint16 if f * f * int(np.iinfo(a.dtype).max) < 2**16 else np.uint32
    rows = a[0::f].astype(acc)  # rows first: contiguous row slices, then column pairs
    for i in range(1, f):
        rows += a[i::f]
    pairs = rows.reshape(hh, ww, f, c)
    s = pairs[:, :, 0].copy()
    for j in range(1, f):
        s += pairs[:, :, j]
    if partial:
        n = np.minimum(f, h - f * np.arange(hh))[:, None] * np.minimum(f, w - f * np.arange(ww))
        n = n[:, :, None].astype(acc)
    else:
        n = acc(f * f)
    if a.dtype.kind == "f":
        return (s / n).astype(a.dtype)
    return ((s + n // 2) // n).astype(a.dtype)


def _finish(
    block: np.ndarray, op: tuple[Any, ...], dtype: str, factor: int = 0
) -> tuple[np.ndarray, int, np.ndarray | None]:
    """Process one block: the operation in float32, then the output samples.

    Return the output samples, the out-of-range count and (``factor``) the block's box mean
    for the next pyramid level, so that no float block outlives its task.
    """
    f = op[0](block, *op[1:])
    if dtype == "float32":
        return f, 0, _reduce(f, factor) if factor else None
    if np.shares_memory(f, block) or not f.flags.writeable:
        f = f.copy()
    n = int(np.count_nonzero(f < 0)) + int(np.count_nonzero(f > 1))
    np.clip(f, 0.0, 1.0, out=f)  # in place: the block's own float result, no temporaries
    f *= 255.0 if dtype == "uint8" else 65535.0
    q = np.rint(f, out=f).astype(dtype)
    return q, n, _reduce(q, factor) if factor else None


def _rows(x: Any, op: tuple[Any, ...], dtype: str, factor: int = 0) -> Any:
    """Yield the processed blocks row by row.

    Each item is (row0, output blocks of one block row, out-of-range count, reduced band or
    None); the blocks of a row run in parallel on dask's threaded scheduler.
    """
    import dask

    blocks = x.to_delayed()
    r0 = 0
    for i, h in enumerate(x.chunks[0]):
        parts = dask.compute(
            *[dask.delayed(_finish)(b, op, dtype, factor) for b in blocks[i, :, 0]]
        )
        small = np.concatenate([p[2] for p in parts], axis=1) if factor else None
        yield r0, [p[0] for p in parts], sum(p[1] for p in parts), small
        r0 += h


def _write_zarr(tmp: Path, x: Any, op: tuple[Any, ...], dtype: str, chunk: int) -> int:
    import zarr

    shape = tuple(int(v) for v in x.shape)
    z = zarr.create_array(
        store=str(tmp), shape=shape, chunks=(chunk, chunk, shape[-1]), dtype=dtype
    )
    counts: list[int] = []
    for r0, row, bad, _ in _rows(x, op, dtype):
        c0 = 0
        for q in row:
            z[r0 : r0 + q.shape[0], c0 : c0 + q.shape[1]] = q
            c0 += q.shape[1]
        counts.append(bad)
    return sum(counts)


@dataclass(frozen=True)
class _TiffSpec:
    """How a TIFF output is written.

    Its levels, tile side, compression, encoding threads and the input's tags to copy.
    """

    levels: tuple[tuple[int, int], ...]
    tile: int
    compression: str
    workers: int
    meta: _TiffMeta | None


class _Spool:
    """A pyramid level spooled to a raw file band by band, then read back band by band.

    The file holds row-major, C-order samples; the level is never held whole.
    """

    def __init__(self, path: Path, shape: tuple[int, int], channels: int, dtype: Any) -> None:
        self.path, self.shape, self.channels = path, shape, channels
        self.dtype = np.dtype(dtype)
        self.rows = 0
        self._fh: Any = open(path, "wb")  # noqa: SIM115 - closed in close()/finish()

    def append(self, band: np.ndarray) -> None:
        band = band[: self.shape[0] - self.rows, : self.shape[1]]  # floor-sized levels
        self._fh.write(np.ascontiguousarray(band).tobytes())
        self.rows += band.shape[0]

    def finish(self) -> None:
        self._fh.close()
        if self.rows != self.shape[0]:  # pragma: no cover - guarded by _factor
            raise InvalidInputError(f"pyramid level has {self.rows} rows, expected {self.shape[0]}")

    def bands(self, rows: int) -> Any:
        h, w = self.shape
        row_bytes = w * self.channels * self.dtype.itemsize
        with open(self.path, "rb") as fh:
            for r0 in range(0, h, rows):
                n = min(rows, h - r0)
                buf = os.pread(fh.fileno(), n * row_bytes, r0 * row_bytes)
                yield np.frombuffer(buf, dtype=self.dtype).reshape(n, w, self.channels)

    def close(self) -> None:
        self._fh.close()
        self.path.unlink(missing_ok=True)


def _band_tiles(band: list[np.ndarray], tile: int) -> Any:
    """Yield the tiles of one band of blocks, row-major as TIFF stores them."""
    for tr in range(0, band[0].shape[0], tile):
        for q in band:
            for tc in range(0, q.shape[1], tile):
                yield q[tr : tr + tile, tc : tc + tile]


def _write_tiff(
    tmp: Path, x: Any, op: tuple[Any, ...], dtype: str, chunk: int, spec: _TiffSpec
) -> int:
    """Write level 0 from the blocks, then each reduced level, into one tiled TIFF.

    Each reduced level comes from the spooled box means of the level above; the file is
    BigTIFF when needed, with reduced levels as SubIFDs of level 0 (as tifffile and OME-TIFF
    write pyramids).
    """
    import tifffile

    levels, tile = spec.levels, spec.tile
    channels = int(x.shape[-1])
    counts: list[int] = []
    nbytes = sum(h * w for h, w in levels) * channels * np.dtype(dtype).itemsize
    kw: dict[str, Any] = {
        "dtype": dtype,
        "tile": (tile, tile),
        "photometric": "rgb",
        "maxworkers": spec.workers,
        # tifffile encodes buffersize // tile-bytes tiles at a time (512 MiB by default:
        # several bands of a wide slide held at once); a few tiles per thread suffice
        "buffersize": 8 * spec.workers * tile * tile * channels * np.dtype(dtype).itemsize,
        "metadata": None,
    }
    if spec.compression != "none":
        kw["compression"] = spec.compression
        if spec.compression == "jpeg":
            kw["compressionargs"] = {"level": JPEG_QUALITY}
    meta = spec.meta
    if meta is not None and meta.resolution is not None:
        kw["resolutionunit"] = meta.resolutionunit
    spools: list[_Spool] = []

    def spool(k: int) -> _Spool | None:
        if k >= len(levels):
            return None
        s = _Spool(tmp.with_name(f"{tmp.name}.level{k}.raw"), levels[k], channels, dtype)
        spools.append(s)
        return s

    def level0(out: _Spool | None) -> Any:
        factor = _factor(levels[0], levels[1]) if out is not None else 0
        for _, row, bad, small in _rows(x, op, dtype, factor):
            counts.append(bad)
            if out is not None and small is not None:
                out.append(small)
            yield from _band_tiles(row, tile)

    def reduced(src: _Spool, out: _Spool | None, k: int) -> Any:
        factor = _factor(levels[k], levels[k + 1]) if out is not None else 0
        src.finish()  # tifffile stops at the last tile: the level above is complete
        for band in src.bands(chunk):
            if out is not None:
                out.append(_reduce(band, factor))
            yield from _band_tiles([band], tile)

    def resolution(k: int) -> dict[str, Any]:
        if meta is None or meta.resolution is None:
            return {}
        sy, sx = levels[0][0] / levels[k][0], levels[0][1] / levels[k][1]
        return {"resolution": (meta.resolution[0] / sx, meta.resolution[1] / sy)}

    ome = meta is not None and meta.ome
    first_kw = dict(kw)
    if ome:  # an OME-TIFF in, an OME-TIFF out, with its pixel size
        assert meta is not None
        first_kw["metadata"] = {"axes": "YXS"}
        if meta.microns is not None:
            first_kw["metadata"].update(
                PhysicalSizeX=meta.microns[0], PhysicalSizeY=meta.microns[1]
            )
    try:
        with tifffile.TiffWriter(tmp, bigtiff=nbytes > 2**32 - 2**26, ome=ome) as tw:
            h, w = levels[0]
            first = spool(1)
            tw.write(
                level0(first),
                shape=(h, w, channels),
                subifds=len(levels) - 1 or None,
                description=meta.description if meta is not None else None,
                **resolution(0),
                **first_kw,
            )
            src = first
            for k in range(1, len(levels)):
                assert src is not None
                nxt = spool(k + 1)
                h, w = levels[k]
                tw.write(
                    reduced(src, nxt, k),
                    shape=(h, w, channels),
                    subfiletype=1,
                    **resolution(k),
                    **kw,
                )
                src.close()
                src = nxt
    finally:
        for s in spools:
            s.close()
    return sum(counts)
