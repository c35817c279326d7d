"""Reading one image larger than memory lazily: a TIFF or a Zarr array as a dask array.

A tiled (or compressed strip) TIFF is read through tifffile's Zarr store; an uncompressed strip
TIFF row band by row band with ``pread``; tiles larger than a block are decoded once
(:class:`_DecodedOnce`). :func:`_tiff_meta` reads what a TIFF output copies from the input
(pyramid levels, tile, compression, resolution, an OME-XML or Aperio pixel size).
Used by :mod:`imageform.batch.chunked`.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from imageform.errors import ImageformError, InvalidInputError, UnreadableFileError

if TYPE_CHECKING:
    import dask.array

__all__ = ["open_lazy"]


def _kind(path: Path, output: bool = False) -> str:
    """Return "tiff", "zarr" or "dicom" for ``path``.

    An input may be a slide scanner's TIFF (.svs ...) or a DICOM whole-slide image (its frames
    tiles of one matrix).
    """
    from imageform.io import IMAGE_FORMATS
    from imageform.io.image_io import is_dicom_file

    suffix = path.suffix.lower()
    if not output and is_dicom_file(path):
        return "dicom"
    if suffix in (".tif", ".tiff") or (not output and IMAGE_FORMATS.get(suffix) == "tiff"):
        return "tiff"
    if suffix == ".zarr":
        return "zarr"
    if output:
        raise InvalidInputError(f"expected a tiled .tif/.tiff or a .zarr output, got {path}")
    raise InvalidInputError(
        f"expected a TIFF (.tif, .tiff, or a slide scanner's .svs, .ndpi, .scn, .bif, .qptiff), "
        f"a DICOM slide or a .zarr array, got {path}"
    )


class _ContiguousRows:
    """The pixels of an uncompressed, contiguous (strip or single-strip) TIFF page, read by block.

    Blocks are read with ``pread`` (one read per row of the block): a block costs its own samples,
    never the whole strip (tifffile's Zarr store has one chunk per strip, and an uncompressed TIFF
    is often one strip: the whole image).
    """

    def __init__(
        self, path: Path, offset: int, shape: tuple[int, ...], dtype: Any, byteorder: str = "<"
    ) -> None:
        self.path, self.offset = path, offset
        self.shape, self.dtype, self.ndim = shape, np.dtype(dtype), len(shape)
        # the file's byte order: a big-endian ("MM") TIFF's 16-bit samples read as stored
        # were byte-swapped (a 16-bit RGB came out as other colours, ΔE 160)
        self.stored = self.dtype.newbyteorder(byteorder)

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
        out = np.empty((r1 - r0, c1 - c0, *self.shape[2:]), dtype=self.stored)
        flat = out.reshape(r1 - r0, -1).view(np.uint8)
        with open(self.path, "rb") as fh:  # one read per row: only this block's columns
            for i in range(r1 - r0):
                buf = os.pread(fh.fileno(), width, self.offset + (r0 + i) * row_bytes + c0 * pixel)
                if len(buf) != width:
                    raise InvalidInputError(f"{self.path} is truncated (row {r0 + i} missing)")
                flat[i] = np.frombuffer(buf, dtype=np.uint8)
        out = out.astype(self.dtype, copy=False)  # native byte order
        return out[(slice(None, None, rstep), slice(None, None, cstep), *key[2:])]


def _decoded(z: Any, key: tuple[slice, slice], path: Path) -> np.ndarray:
    """Return ``z[key]`` decoded, or refuse the file in one line when a tile cannot be.

    A damaged tile (OpenSlide's ``unreadable.svs``: a JPEG's bogus marker length) raised the
    codec's own error (imagecodecs' Jpeg8Error) out of the block computation, an
    "unexpected" error; the file is named, with the rows and columns of the tile.
    """
    try:
        return np.asarray(z[key])
    except (ImageformError, MemoryError):
        raise
    except Exception as exc:
        text = str(exc).strip().splitlines()
        why = f"{type(exc).__name__}: {text[0][:100]}" if text else type(exc).__name__
        rows, cols = key
        raise UnreadableFileError(
            path,
            f"rows {rows.start}-{rows.stop}, columns {cols.start}-{cols.stop} cannot be "
            f"decoded ({why})",
        ) from None


class _Guarded:
    """A Zarr array whose blocks are decoded through :func:`_decoded` (one-line refusals)."""

    def __init__(self, z: Any, path: Path) -> None:
        self.z, self.shape, self.dtype, self.ndim = z, tuple(z.shape), np.dtype(z.dtype), z.ndim
        self.path = path

    def __getitem__(self, key: Any) -> np.ndarray:
        if not isinstance(key, tuple):
            key = (key,)
        key = key + (slice(None),) * (self.ndim - len(key))
        r0, r1, _ = key[0].indices(self.shape[0])
        c0, c1, _ = key[1].indices(self.shape[1])
        a = _decoded(self.z, (slice(r0, r1), slice(c0, c1)), self.path)
        return a[(slice(None, None, key[0].step), slice(None, None, key[1].step), *key[2:])]


class _DecodedOnce:
    """Blocks of a Zarr array whose chunks (TIFF tiles or strips) are larger than the blocks.

    Zarr decodes a whole chunk for every block read from it: a 16384^2 single-tile TIFF was
    decoded 256 times at ``--chunk 1024``. Here each decoded chunk is kept while the blocks inside
    it are read, and decoded once (a lock per chunk: the blocks of a row run in parallel). The
    cache holds the chunks of one block row and the next row of chunks (LRU), so that memory
    stays bounded by a band of the image, and a chunk is decoded once when blocks go row by row.
    """

    def __init__(self, z: Any, chunk: int, path: Path = Path("input")) -> None:
        import threading
        from collections import OrderedDict

        self.z, self.shape, self.dtype, self.ndim = z, tuple(z.shape), np.dtype(z.dtype), z.ndim
        self.path = path
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
            a = _decoded(
                self.z, (slice(i * ch, (i + 1) * ch), slice(j * cw, (j + 1) * cw)), self.path
            )
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


#: TIFF photometric interpretations whose samples are not RGB or grey (as ``read_image``).
_NOT_RGB = {5: "CMYK (separated)", 8: "CIELab", 9: "ICCLab", 10: "ITULab", 32844: "LogL",
            32845: "LogLuv"}  # fmt: skip


def _refuse_undecodable(p: Path, page: Any) -> None:
    """Refuse a TIFF that is not RGB or grey, or that tifffile cannot decode, before reading.

    A CMYK, Lab or LogLuv TIFF, YCbCr not JPEG-compressed (tifffile returns its Y, Cb, Cr
    samples, or fails on subsampled ones), a compression without a decoder.

    Such files failed inside the block computation, as an "unexpected" NotImplementedError,
    ValueError or Jpeg8Error (libtiff's LogLuv and old-JPEG test images).
    """
    import tifffile

    photometric, compression = int(page.photometric), int(page.compression)
    what = _NOT_RGB.get(photometric)
    if what is None and photometric == 6 and compression != 7:
        what = "YCbCr (not JPEG-compressed)"
    if what is not None:
        raise UnreadableFileError(
            p,
            f"a {what} TIFF; imageform reads RGB, grey and palette TIFFs (convert it to RGB first)",
        )
    if compression not in tifffile.TIFF.DECOMPRESSORS:
        try:
            name = tifffile.COMPRESSION(compression).name
        except ValueError:
            name = str(compression)
        raise UnreadableFileError(p, f"its compression {name} has no decoder here")


def _tiff_lazy(
    p: Path, chunk: int, da: Any, zarr: Any, opened: list[Any] | None, pyramid: bool = False
) -> Any:
    """Level 0 (or, ``pyramid``, the group of levels) of a TIFF's first series, lazily."""
    import tifffile

    with tifffile.TiffFile(p) as tf:
        page = tf.pages[0]
        _refuse_undecodable(p, page)
        strips = (
            not pyramid
            and isinstance(page, tifffile.TiffPage)
            and not page.is_tiled
            and page.compression == 1
            and page.planarconfig == 1
            and page.is_contiguous
            and page.bitspersample == 8 * np.dtype(page.dtype).itemsize  # not 12-bit packed
            and len(tf.series[0].levels) == 1
        )
        if strips:
            src = _ContiguousRows(
                p, int(page.dataoffsets[0]), tuple(page.shape), page.dtype, tf.byteorder
            )
    if strips:
        return _rgb_blocks(da, src, p, chunk, "strips", 0, wrap=False)
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
    compression (tifffile's tag value), resolution (pixels per unit, x and y), its unit,
    level 0's description and ICC profile (the InterColorProfile tag's bytes), and its bits
    per integer sample (10 in a uint16 container: 1023 is white; None for floats).
    """

    levels: tuple[tuple[int, int], ...]
    tile: int | None
    compression: int
    resolution: tuple[float, float] | None
    resolutionunit: int | None
    description: str | None
    ome: bool = False
    microns: tuple[float, float] | None = None
    icc: bytes | None = None
    bits: int | None = None


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

    from imageform.io import pixel_size_um

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
        microns = pixel_size_um(p)  # OME, Aperio, Philips, Ventana, NDPI ... (as OpenSlide)
        if desc is not None and (
            page.is_shaped or tf.is_ome or tf.is_svs or desc.lstrip()[:1] in ("{", "<")
        ):
            # tifffile's shape, an OME-XML or an Aperio header describe the input's file
            # layout: the output is written afresh (OME-XML with the pixel size for OME)
            desc = None
        if microns is not None and (res is None or unit in (None, 1) or res == (1.0, 1.0)):
            res, unit = (1e4 / microns[0], 1e4 / microns[1]), 3  # pixels per centimetre
        icc = tags["InterColorProfile"].value if "InterColorProfile" in tags else None
        return _TiffMeta(
            tuple(levels),
            tile,
            int(page.compression),
            res,
            unit,
            desc,
            tf.is_ome,
            microns,
            bytes(icc) if isinstance(icc, (bytes, bytearray)) and icc else None,
            int(page.bitspersample) if int(page.sampleformat) == 1 else None,
        )


#: The largest block side: a block of 3 float64 channels stays under 2 GiB.
_MAX_CHUNK = 16384


def _chunk_size(chunk: object) -> int:
    """Return the block side in pixels, 1 to 16384, refused by name otherwise."""
    from imageform._validate import as_int

    return as_int(chunk, "chunk", minimum=1, maximum=_MAX_CHUNK)


def open_lazy(path: str | Path, chunk: int = 1024, *, level: int = 0) -> dask.array.Array:
    r"""Open a TIFF or a Zarr array as a dask array of ``chunk x chunk`` blocks.

    Nothing is read until the array is computed. A tiled (or compressed strip) TIFF is read
    through tifffile's Zarr store, tile by tile (strip by strip: a compressed strip is
    decoded whole); an uncompressed strip TIFF (one strip or many) row band by row band from
    the file. Blocks have all channels (choose a multiple of the TIFF's tile size).

    ``level`` is the pyramid level of a whole-slide TIFF (0 the full resolution, 1 the first
    reduced one; -1 the smallest, as a Python index), a slide scanner's own (.svs, .ndpi
    ...) or OME's; a level other than 0 of a flat image is refused. A tissue mask at a
    reduced level, whose pixels are :math:`s = w_0 / w_k` times larger:

    .. math:: m_k = \operatorname{tissue\_mask}(L_k,\ p_k = s\, p_0)

    Examples
    --------
    >>> import tempfile, pathlib, tifffile
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "slide.tif"
    >>> with tifffile.TiffWriter(p) as tw:
    ...     tw.write(np.zeros((512, 512, 3), np.uint8), tile=(256, 256), subifds=1)
    ...     tw.write(np.zeros((256, 256, 3), np.uint8), tile=(256, 256), subfiletype=1)
    >>> open_lazy(p, level=-1).shape
    (256, 256, 3)
    """
    from imageform._validate import as_int

    return _open_lazy(path, chunk, None, as_int(level, "level", minimum=-64, maximum=64))


def _dicom_lazy(p: Path, chunk: int, da: Any, level: int) -> Any:
    """Open a DICOM whole-slide image's level lazily, its frames decoded as blocks need them.

    Level 0 is the file given; the smaller levels are the files of its series in its folder
    (:func:`imageform.io.dicom.slide_levels`).
    """
    from imageform.io import dicom

    levels = dicom.slide_levels(p) or [(p, 0, 0)]
    count = len(levels)
    if not -count <= level < count:
        raise InvalidInputError(
            f"{p} has {count} pyramid level(s) (0 to {count - 1}, or -1 the smallest), got "
            f"level {level}"
        )
    src = levels[level][0]
    return _rgb_blocks(da, dicom.SlideLevel(src), src, chunk, "dicom", 0, shown=p)


def _dicom_meta(p: Path) -> _TiffMeta:
    """Return what a TIFF output copies from a DICOM slide: levels, tile, pixel size, ICC.

    Levels as :func:`_dicom_lazy` reads them, each a whole factor smaller than the one above
    (else level 0 alone); compression: JPEG where the frames are baseline JPEG, else zlib
    (none for uncompressed frames); the pixel size from Pixel Spacing
    (:func:`imageform.io.pixel_size_um`).
    """
    from imageform.io import dicom, pixel_size_um

    levels = [(h, w) for _, w, h in dicom.slide_levels(p)]
    z = dicom.SlideLevel(p)
    levels = levels or [z.shape[:2]]
    kept = [levels[0]]
    for lv in levels[1:]:
        if _factor(kept[-1], lv):
            kept.append(lv)
    th, tw = z.chunks[:2]
    head = dicom.open_dicom(p, pixels=False)
    uid = str(getattr(getattr(head, "file_meta", None), "TransferSyntaxUID", "") or "")
    native = ("1.2.840.10008.1.2", "1.2.840.10008.1.2.1", "1.2.840.10008.1.2.2")
    compression = 7 if uid == "1.2.840.10008.1.2.4.50" else 1 if uid in native else 8
    microns = pixel_size_um(p)
    res = None if microns is None else (1e4 / microns[0], 1e4 / microns[1])
    icc = dicom.icc_profile_of(head)
    return _TiffMeta(
        tuple(kept),
        tw if tw == th and tw % 16 == 0 else None,
        compression,
        res,
        None if res is None else 3,
        None,
        False,
        microns,
        icc,
        None,
    )


def _open_lazy(path: str | Path, chunk: int, opened: list[Any] | None, level: int = 0) -> Any:
    """:func:`open_lazy`; the TIFF stores it opens are appended to ``opened`` (if given)."""
    from imageform._optional import require
    from imageform._validate import as_path

    p = as_path(path, "path")
    chunk = _chunk_size(chunk)
    da = require("dask.array", what="imageform chunked")
    zarr = require("zarr", what="imageform chunked")
    if not p.exists():
        raise InvalidInputError(f"input {p} does not exist")
    kind = _kind(p)
    try:
        if kind == "dicom":
            return _dicom_lazy(p, chunk, da, level)
        if kind == "tiff":
            z: Any = _tiff_lazy(p, chunk, da, zarr, opened, pyramid=level != 0)
            if not isinstance(z, (zarr.Array, zarr.Group)):
                return z  # an uncompressed strip TIFF, already a dask array
        else:
            z = zarr.open(str(p), mode="r")
    except (ImageformError, MemoryError):
        raise
    except Exception as exc:  # a damaged file: tifffile's, zarr's or numcodecs' own errors
        text = str(exc).strip().splitlines()
        reason = text[0][:120] if text else type(exc).__name__
        raise UnreadableFileError(p, reason) from exc
    keys = (
        sorted((k for k in z.array_keys() if k.isdigit()), key=int)
        if isinstance(z, zarr.Group)
        else []
    )
    count = len(keys) if keys else 1
    if not -count <= level < count:
        raise InvalidInputError(
            f"{p} has {count} pyramid level(s) (0 to {count - 1}, or -1 the smallest), got "
            f"level {level}"
        )
    if isinstance(z, zarr.Group):  # a pyramid: level 0 is the full resolution
        z = z[keys[level]]
    return _rgb_blocks(da, z, p, chunk, "tiles", level)


def _rgb_blocks(
    da: Any,
    src: Any,
    p: Path,
    chunk: int,
    kind: str,
    level: int,
    *,
    wrap: bool = True,
    shown: Path | None = None,
) -> Any:
    """Return ``src`` (an RGB array-like of the file ``p``) as a dask array of ``chunk`` blocks.

    ``wrap``: ``src`` has ``chunks`` (tiles or strips, zarr's or a DICOM level's): wrapped in
    :class:`_DecodedOnce` when a stored chunk is larger than a block (each decoded once for
    the blocks it covers), else in :class:`_Guarded` (a damaged chunk is one error naming the
    file). The graph's name holds the file's path, size, time, the level and the block size,
    so two levels or two block sizes of one file never share keys. ``shown``: the path errors
    name (the file the user gave; a DICOM level may be another file of its series).
    """
    if len(src.shape) != 3 or src.shape[-1] != 3:
        raise InvalidInputError(
            f"{shown or p}: expected an RGB image (H, W, 3), got shape {tuple(src.shape)}"
        )
    if wrap:
        big = max(src.chunks[:2]) > chunk
        src = _DecodedOnce(src, chunk, p) if big else _Guarded(src, p)
        kind += "-decoded-once" if big else ""
    st = p.stat()
    return da.from_array(
        src,
        chunks=(chunk, chunk, 3),
        name=f"imageform-{kind}-{p}-{st.st_size}-{st.st_mtime_ns}-{level}-{chunk}",
        asarray=False,
        fancy=False,
    )
