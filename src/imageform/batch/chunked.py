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

from imageform._validate import check_option
from imageform.errors import ImageformError, InvalidInputError
from imageform.workflows.color import DISPLAYABLE_SPACES

__all__ = ["CHUNKED_COMMANDS", "ChunkedResult", "open_lazy", "process_chunked"]

#: Commands :func:`process_chunked` runs.
CHUNKED_COMMANDS = ("convert", "white_balance", "stain_normalize")
#: Most pixels of the regular subsample on which a slide's own stain statistics are measured
#: (every s-th row and column; a whole-slide tool estimates on a thumbnail the same way).
STAIN_SAMPLE_PIXELS = 4_000_000
#: White-balance methods whose illuminant is a streaming reduction (or needs none).
_WB_METHODS = ("gray_world", "shades_of_gray", "manual")
_OUT_DTYPES = ("uint8", "uint16", "float32")


@dataclass(frozen=True)
class ChunkedResult:
    """What :func:`process_chunked` did.

    ``clipped`` counts the values outside [0, 1] clipped to fit an integer output (0 for
    float32); ``gains`` are the white-balance gains (None for convert).
    """

    output: Path
    shape: tuple[int, ...]
    dtype: str
    chunk: int
    clipped: int
    gains: tuple[float, ...] | None
    seconds: float


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


def _tiff_lazy(p: Path, chunk: int, da: Any, zarr: Any) -> Any:
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
    # the store holds the TIFF open: close it when the array goes, not at interpreter exit
    # (an unclosed file is a ResourceWarning wherever the garbage collector happens to run)
    weakref.finalize(arr, store.close)
    return arr


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
            z: Any = _tiff_lazy(p, chunk, da, zarr)
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


def _stain_stats(x: Any, opts: dict[str, Any]) -> tuple[Any, Any, int]:
    """Return the target's statistics (a JSON file or a reference image) and the slide's own.

    The slide's are taken on a regular subsample of at most :data:`STAIN_SAMPLE_PIXELS` (every
    ``step``-th row and column), read block by block.
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
    h, w = int(x.shape[0]), int(x.shape[1])
    step = max(1, int(np.ceil(np.sqrt(h * w / STAIN_SAMPLE_PIXELS))))
    sample = np.asarray(x[::step, ::step].compute())
    return stats_t, measure(sample), step


def _quantize(block: np.ndarray, dtype: str) -> np.ndarray:
    if dtype == "float32":
        return block
    top = 255.0 if dtype == "uint8" else 65535.0
    return np.round(np.clip(block, 0.0, 1.0) * top).astype(dtype)


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
    tile: int = 256,
    force: bool = False,
    num_workers: int | None = None,
) -> ChunkedResult:
    r"""Apply ``convert``, ``white_balance`` or ``stain_normalize`` to an image larger than memory.

    The image is processed chunk-wise.

    .. math:: \text{out}[b] = f(\text{in}[b];\ \theta),\qquad
        \theta = \text{gains } \bar e / e_c,\ e_c = \big(\operatorname{mean}_{\text{all}}
        \rho_c^p\big)^{1/p}

    Pointwise, so each block ``b`` gives the same numbers as the whole image in memory; the
    white-balance illuminant ``e`` is a reduction over every block (a first pass). Stain
    normalisation measures the slide's own statistics (Macenko's stain vectors and
    concentration range, or Reinhard's CIELAB mean and standard deviation) on a regular
    subsample of at most :data:`STAIN_SAMPLE_PIXELS` (the whole image when smaller), then
    maps every block to the target's with those fixed statistics.

    Parameters
    ----------
    src : path
        A tiled TIFF (read through ``tifffile.imread(aszarr=True)``) or a ``.zarr`` array,
        shape (H, W, 3), encoded RGB (uint8/uint16 full range, or floats in [0, 1]).
    dst : path
        ``.tif``/``.tiff`` (tiled, ``tile`` pixels, BigTIFF when needed) or ``.zarr``; written
        under a temporary name in the same folder and renamed when complete.
    command : {"convert", "white_balance", "stain_normalize"}
        ``convert`` takes options ``from`` (default ``srgb``), ``to``, ``white``;
        ``white_balance`` takes ``method`` (gray_world, shades_of_gray, manual), ``p``,
        ``normalize``, ``illuminant``/``cct`` (manual); ``stain_normalize`` takes ``target``
        (a reference image or its statistics as JSON) and ``method`` (macenko, reinhard).
    options : dict, optional
        The command's options named above (default: the command's defaults).
    chunk : int
        Block size in pixels (a multiple of ``tile`` and, for speed, of the input's tiles).
    dtype : {"uint8", "uint16", "float32"}, optional
        Output samples; by default the input's integer type (float32 for float input or for
        a destination space that is not displayable RGB). Integer output clips values
        outside [0, 1]; how many is reported in ``clipped``.
    force : bool
        Replace an existing ``dst``.
    tile : int, keyword-only
        Tile side in pixels of a TIFF destination (``chunk`` must be a multiple of it).
    num_workers : int, optional
        Threads of dask's threaded scheduler (default: CPU count).

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
    """
    from imageform._optional import require
    from imageform._validate import as_bool, as_int, as_path

    t0 = time.perf_counter()
    src_p, dst_p = as_path(src, "src"), as_path(dst, "dst")
    cmd = check_option(command, CHUNKED_COMMANDS, "chunked command")
    opts = _options(cmd, options)
    out_kind = _kind(dst_p)
    chunk = _chunk_size(chunk)
    tile = as_int(tile, "tile", minimum=16, maximum=chunk)
    if chunk % tile or tile % 16:
        raise InvalidInputError(
            f"expected chunk a multiple of tile, and tile a multiple of 16, got chunk {chunk}, "
            f"tile {tile}"
        )
    force = as_bool(force, "force")
    if num_workers is not None:
        num_workers = as_int(num_workers, "num_workers", minimum=1, maximum=1024)
    if dst_p.resolve() == src_p.resolve():
        raise InvalidInputError(f"output {dst_p} is the input; choose another path")
    if dst_p.exists() and not force:
        raise InvalidInputError(f"output {dst_p} exists; pass --force to overwrite it")
    if not dst_p.parent.is_dir():
        raise InvalidInputError(f"output folder {dst_p.parent} does not exist")
    dask = require("dask", what="imageform chunked")
    _remove_stale(dst_p)  # left by a run killed mid-write (SIGKILL cannot be caught)
    x = open_lazy(src_p, chunk)
    in_int = x.dtype in (np.uint8, np.uint16)
    gains: np.ndarray | None = None
    with dask.config.set(scheduler="threads", num_workers=num_workers or os.cpu_count()):
        if cmd == "convert":
            s, d = opts["from"], opts["to"]
            params = {k: opts[k] for k in ("white",) if opts.get(k) is not None}
            op: tuple[Any, ...] = (_convert_block, s, d, params)
            displayable = d in DISPLAYABLE_SPACES
        elif cmd == "stain_normalize":
            stats_t, stats_s, _step = _stain_stats(x, opts)
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
        tmp = _temp(dst_p)
        try:
            clipped = _write(tmp, out_kind, x, op, out_dtype, chunk, tile)
            if dst_p.exists():
                shutil.rmtree(dst_p) if dst_p.is_dir() else dst_p.unlink()
            os.replace(tmp, dst_p)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True) if tmp.is_dir() else tmp.unlink(missing_ok=True)
            raise
    return ChunkedResult(
        dst_p,
        tuple(int(v) for v in x.shape),
        out_dtype,
        chunk,
        clipped if out_dtype != "float32" else 0,
        None if gains is None else tuple(float(g) for g in gains),
        time.perf_counter() - t0,
    )


def _finish(block: np.ndarray, op: tuple[Any, ...], dtype: str) -> tuple[np.ndarray, int]:
    """Process one block: the operation in float32, then the output samples and out-of-range count.

    Both are computed in the task so that no float block outlives it.
    """
    f = op[0](block, *op[1:])
    n = int(np.count_nonzero((f < 0) | (f > 1))) if dtype != "float32" else 0
    return _quantize(f, dtype), n


def _rows(x: Any, op: tuple[Any, ...], dtype: str) -> Any:
    """Yield (row0, output blocks of one block row, out-of-range count), row by row.

    The blocks of a row run in parallel on dask's threaded scheduler.
    """
    import dask

    blocks = x.to_delayed()
    r0 = 0
    for i, h in enumerate(x.chunks[0]):
        parts = dask.compute(*[dask.delayed(_finish)(b, op, dtype) for b in blocks[i, :, 0]])
        yield r0, [q for q, _ in parts], sum(n for _, n in parts)
        r0 += h


def _write(
    tmp: Path, kind: str, x: Any, op: tuple[Any, ...], dtype: str, chunk: int, tile: int
) -> int:
    shape = tuple(int(v) for v in x.shape)
    counts: list[int] = []
    if kind == "zarr":
        import zarr

        z = zarr.create_array(
            store=str(tmp), shape=shape, chunks=(chunk, chunk, shape[-1]), dtype=dtype
        )
        for r0, row, bad in _rows(x, op, dtype):
            c0 = 0
            for q in row:
                z[r0 : r0 + q.shape[0], c0 : c0 + q.shape[1]] = q
                c0 += q.shape[1]
            counts.append(bad)
        return sum(counts)
    import tifffile

    def tiles() -> Any:  # row-major tiles, as TIFF stores them
        for _, row, bad in _rows(x, op, dtype):
            counts.append(bad)
            for tr in range(0, row[0].shape[0], tile):
                for q in row:
                    for tc in range(0, q.shape[1], tile):
                        yield q[tr : tr + tile, tc : tc + tile]

    nbytes = int(np.prod(shape)) * np.dtype(dtype).itemsize
    tifffile.imwrite(
        tmp,
        tiles(),
        shape=shape,
        dtype=dtype,
        tile=(tile, tile),
        photometric="rgb",
        bigtiff=nbytes > 2**32 - 2**26,
    )
    return sum(counts)
