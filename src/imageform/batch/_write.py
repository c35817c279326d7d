"""Writing the processed blocks: a Zarr array, or a tiled (pyramidal) TIFF band by band.

Level 0 is written from the blocks of one block row at a time; each reduced level is the box
mean of the level above, spooled to a raw scratch file beside the output and read back band
by band (:class:`_Spool`), so that no level is ever held whole. Used by
:mod:`imageform.batch.chunked`.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from imageform._validate import check_option
from imageform.batch._lazy import _factor, _TiffMeta
from imageform.errors import InvalidInputError

#: The key of a TIFF description's JSON that names a space without an ICC profile, as
#: :func:`imageform.io.write_image` writes it and :func:`imageform.io.image_color_space` reads
#: it back (tests/batch pins the round trip).
COLOR_SPACE_KEY = "imageform_color_space"

#: Compressions of a TIFF output (``None``: the input's, when tifffile can write it).
_COMPRESSIONS = ("none", "zlib", "lzw", "zstd", "jpeg")
#: JPEG quality of a JPEG output (the input's quality is not stored in the file).
JPEG_QUALITY = 90


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
    top = 255.0 if dtype == "uint8" else 65535.0
    f *= top  # in place: the block's own float result, no temporaries
    # outside: the values whose code the clip changes (io.image_io.float_codes' rule: a
    # rounding error outside [0, 1] keeps its own code); top + 0.5 rounds to top + 1 (even)
    n = int(np.count_nonzero(f < -0.5)) + int(np.count_nonzero(f >= top + 0.5))
    np.clip(f, 0.0, top, out=f)
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

    Its levels, tile side, compression, encoding threads, the input's tags to copy, and the
    output's colour space: an ICC profile to embed, or the name of a space without one, which
    level 0's description records (``{"imageform_color_space": "lab"}``, as
    :func:`imageform.io.write_image` writes it), replacing the input's text.
    """

    levels: tuple[tuple[int, int], ...]
    tile: int
    compression: str
    workers: int
    meta: _TiffMeta | None
    icc: bytes | None = None
    recorded: str | None = None


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
    description = meta.description if meta is not None else None
    if spec.recorded is not None:  # a space without a profile: named in level 0's description
        from imageform._jsonio import dumps

        description, ome = dumps({COLOR_SPACE_KEY: spec.recorded}, indent=None), False
        first_kw["metadata"] = None
    if spec.icc is not None:
        first_kw["iccprofile"] = spec.icc
    try:
        with tifffile.TiffWriter(tmp, bigtiff=nbytes > 2**32 - 2**26, ome=ome) as tw:
            h, w = levels[0]
            first = spool(1)
            tw.write(
                level0(first),
                shape=(h, w, channels),
                subifds=len(levels) - 1 or None,
                description=description,
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
