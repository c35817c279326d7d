"""Options and helpers every image-reading or image-writing workflow shares.

The out-of-range policy lives here, once: integer outputs (PNG, JPEG, and TIFF with
``--bit-depth``) cannot hold values outside [0, 1]; by default they are clipped and a note says
how many (``--out-of-range error`` refuses instead); float outputs (TIFF, ``.npy``) keep every
value as computed.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, get_args

from imageform import _deprecate
from imageform.errors import InvalidInputError
from imageform.workflows._spec import Options, Run, option

__all__ = [
    "FRAME_HELP",
    "OPTS_FRAME",
    "ImageIn",
    "ImageOut",
    "OnDevice",
    "RgbFrom",
    "frame_option",
    "gpu_bands",
    "image_out_renames",
    "in_srgb",
    "input_space",
    "mask_of",
    "not_read",
    "on_gpu",
    "patches_in_srgb",
    "read",
    "refuse_absent_device",
    "refuse_unscaled_floats",
    "write",
    "write_mapped",
]

#: The choices of the options shared by the workflows (``choices=get_args(...)``).
Alpha = Literal["reject", "drop", "keep"]
OutOfRange = Literal["clip", "error"]
Device = Literal["cpu", "cuda"]


#: What ``--frame`` picks, for every command that reads image files.
FRAME_HELP = (
    "The image to read of a file holding several: a TIFF stack's (pages, z-planes, time "
    "points, channels), a multi-frame DICOM's, an animated GIF's or WebP's; 0 the first "
    "(imageform info lists them)."
)


def frame_option(help: str = FRAME_HELP) -> Any:
    """Return the ``--frame N`` option: one image of a file that holds several, 0 the first.

    Declared once here, for :class:`ImageIn` (every command that reads image files) and
    ``imageform info`` (whose help adds that it lists them without it): one metavar, one
    minimum (``--frame -1`` is a usage error), one default (None: a file of one image).
    """
    return option(None, help=help, metavar="N", minimum=0)


@dataclass(frozen=True, kw_only=True)
class ImageIn(Options):
    """How input images are read."""

    alpha: Alpha = option(
        "reject",
        help="Transparent pixels in an input: reject, drop (ignore the alpha channel) or keep.",
        choices=get_args(Alpha),
    )
    max_pixels: int | None = option(
        None,
        help="Refuse input images with more pixels (default 100 Mpx, or IMAGEFORM_MAX_PIXELS).",
        metavar="N",
    )
    frame: int | None = frame_option()


@dataclass(frozen=True, kw_only=True)
class ImageOut(Options):
    """How output images are written."""

    bit_depth: int | None = option(
        None,
        help="Bits per sample of PNG output (8 or 16; JPEG: 8) or of an integer TIFF; "
        "default: 16 for 16-bit input, else 8 (TIFF: float32).",
        metavar="8|16",
    )
    out_of_range: OutOfRange = option(
        "clip",
        help="Values outside [0, 1] in integer output: clip (with a note) or error.",
        choices=get_args(OutOfRange),
    )
    clip: bool = option(False, help="Same as --out-of-range clip.", hidden=True)

    def check(self) -> None:
        super().check()
        if self.bit_depth is not None and self.bit_depth not in (8, 16):
            raise InvalidInputError(f"expected --bit-depth 8 or 16, got {self.bit_depth}")
        if self.clip:
            object.__setattr__(self, "out_of_range", "clip")

    def check_output(self, path: Path) -> None:
        """Refuse ``--bit-depth 16`` into a JPEG before any work (JPEG holds 8 bits)."""
        super().check_output(path)
        if self.bit_depth == 16 and path.suffix.lower() in (".jpg", ".jpeg"):
            raise InvalidInputError(
                "JPEG holds 8 bits per sample: --bit-depth 16 needs a .png or .tif output"
            )


#: The old names of :class:`ImageOut`'s fields (issue 30: one spelling per concept), kept one
#: release: put it above ``@dataclass`` of every options class with ImageOut. The constructor
#: takes ``bits=`` and ``.bits`` reads ``bit_depth`` (a DeprecationWarning); the command line
#: takes the hidden ``--bits`` and ``imageform batch``'s option mappings ``bits`` (a note).
image_out_renames = _deprecate.renamed_fields({"bits": "bit_depth"})


@dataclass(frozen=True, kw_only=True)
class OnDevice(Options):
    """Where a pointwise command computes: the CPU, or the GPU's fused kernels."""

    device: Device = option(
        "cpu",
        help="Where the pixels are computed: cuda runs imageform's fused GPU kernels (numba's "
        "CUDA target; refused in one line when no GPU is usable).",
        choices=get_args(Device),
    )


def refuse_absent_device(opts: Any) -> None:
    """``--device cuda`` where no GPU is usable: one-line InvalidInputError (read nothing first)."""
    if getattr(opts, "device", "cpu") == "cuda":
        from imageform._cuda.geometry import require_cuda

        require_cuda("--device cuda")


def on_gpu(run: Run, what: str, fn: Any, *arrays: Any, first: bool = True) -> Any:
    """``fn(*arrays)`` on the GPU: the arrays copied there, ``fn``'s kernels, the result back.

    Returns the NumPy result, or None where ``fn`` launched no kernel on them (a call the
    kernels do not take, such as a conversion through ``gray``): a note says so and the
    caller runs its CPU path. ``first``: the first call of a run, whose failure (the
    Array-API path meeting a device array) is that answer; later calls' errors propagate.
    Raises a one-line InvalidInputError where numba's CUDA target could not compile the
    kernel (the kernels are then off for the process).
    """
    import numpy as np

    from imageform._cuda import _launch

    c = _launch.cuda()
    dev = [c.to_device(np.ascontiguousarray(a)) for a in arrays]
    before = _launch.launch_count()
    out: Any = None
    if first:
        try:
            out = fn(*dev)
        except Exception:  # the Array-API path cannot read a device array: no kernel took it
            out = None
    else:
        out = fn(*dev)
    if out is not None and _launch.launch_count() > before and _launch.is_cuda_array(out):
        return np.asarray(out.copy_to_host())
    if not _launch.use_cuda():
        raise InvalidInputError(
            "--device cuda: numba's CUDA target cannot compile the kernels here "
            f"({_launch.status()}); use the CPU"
        )
    run.note(f"note: --device cuda: {what} has no GPU kernel; it ran on the CPU")
    return None


def gpu_bands(run: Run, what: str, fn: Any) -> Any:
    """Return a band function for :func:`write_mapped`: ``fn`` on the GPU (:func:`on_gpu`).

    Where the first band launches no kernel, every band runs ``fn`` on the CPU (one note).
    """
    state: list[bool] = []  # [True]: the kernels take it; [False]: the CPU computes

    def band(b: Any) -> Any:
        if state == [False]:
            return fn(b)
        got = on_gpu(run, what, fn, b, first=not state)
        if got is None:
            state[:] = [False]
            return fn(b)
        state[:] = [True]
        return got

    return band


#: ``read(..., frame=OPTS_FRAME)``: the options' ``--frame`` (an :class:`ImageIn`'s).
OPTS_FRAME: Any = object()


def read(
    path: Path,
    opts: Any,
    *,
    alpha: str | None = None,
    colours: bool = False,
    frame: Any = OPTS_FRAME,
) -> Any:
    """Read ``path`` with the options' alpha rule and pixel limit (an :class:`ImageIn`).

    ``colours``: the pixels are read as colours, so integer TIFF samples of fewer bits than
    their container (10, 12, 14 bits in uint16; TIFF 6.0's MaxSampleValue, ``2**bits - 1``,
    is white) are scaled to the container's full range, as a PNG stores them. ``read_image``
    keeps them as stored (a sensor's numbers, DN, which the measuring commands read as
    such); read as colours unscaled, a 10-bit photograph came out 64 times too dark.
    ``frame``: the image of a file that holds several (``read_image``'s ``frame``); by
    default the options' ``--frame``, which every command's input images take alike. A file
    that goes with the input (a mask, a flat field, a stain target) is read with
    ``frame=None``: it holds one image.
    """
    from imageform.io import read_image

    if frame is OPTS_FRAME:
        frame = getattr(opts, "frame", None)

    img = read_image(
        path,
        alpha=str(alpha or getattr(opts, "alpha", "reject")),
        max_pixels=getattr(opts, "max_pixels", None),
        frame=frame,
    )
    return full_range(path, img) if colours else img


def one_image_frame(path: Path, frame: int | None) -> None:
    """Refuse ``--frame N`` (N > 0) for a file read as one image (a camera raw), in one line.

    ``--frame 0`` is that image, as for a file of one image in ``read_image``; the words are
    ``read_image``'s for a frame out of range.
    """
    if frame is not None and frame != 0:
        raise InvalidInputError(f"frame {frame} is out of range: {path} holds one image (frame 0)")


def tiff_sample_bits(path: Path) -> int | None:
    """Bits per sample of a TIFF's first page with integer samples, None for other files."""
    with open(path, "rb") as fh:
        if fh.read(4) not in (b"II*\0", b"MM\0*", b"II+\0", b"MM\0+"):
            return None
    import tifffile

    try:
        with tifffile.TiffFile(path) as tif:
            page = tif.pages.first
            if int(page.sampleformat) != 1 or int(page.photometric) == 3:  # uint; palette
                return None
            return int(page.bitspersample)
    except Exception:  # read_image has read it: nothing more to say here
        return None


def tiff_number_type(path: Path) -> str | None:
    """``"int16"`` (int8, int32, uint32) for a TIFF of samples read as numbers, else None.

    ``read_image`` reads signed integers and uint32 as floats holding the stored numbers
    (float32; float64 for int32 and uint32), as a DICOM's signed samples: a CT's, a
    detector's or a microscope's values, not colours.
    """
    with open(path, "rb") as fh:
        if fh.read(4) not in (b"II*\0", b"MM\0*", b"II+\0", b"MM\0+"):
            return None
    import tifffile

    try:
        with tifffile.TiffFile(path) as tif:
            dtype = tif.series[0].dtype if tif.series else None
    except Exception:  # read_image says what is wrong with it
        return None
    if dtype is None:
        return None
    if (dtype.kind == "i" and dtype.itemsize <= 4) or (dtype.kind == "u" and dtype.itemsize == 4):
        return str(dtype)
    return None


def stored_as(number_type: str | None) -> str:
    """``imageform info``'s words on a TIFF read as numbers: `` (stored int16, signed: ...)``."""
    if number_type is None:
        return ""
    signed = ", signed" if number_type.startswith("int") else ""
    return f" (stored {number_type}{signed}: read as the numbers)"


def full_range(path: Path, image: Any) -> Any:
    """Scale ``image``'s integer samples of fewer bits than their container to its range.

    ``round(code * (2**container - 1) / (2**bits - 1))``, for a TIFF at ``path`` whose
    BitsPerSample says fewer bits than the sample type holds; anything else as it is.
    """
    import numpy as np

    a = image
    if not isinstance(a, np.ndarray) or a.dtype not in (np.uint8, np.uint16):
        return a
    full = 8 * a.dtype.itemsize
    bits = tiff_sample_bits(path)
    if bits is None or not 1 < bits < full:
        return a
    top = (1 << bits) - 1
    scale = np.float64(np.iinfo(a.dtype).max) / top
    return np.round(np.minimum(a, top) * scale).astype(a.dtype)


def not_read(given: int, n_read: int) -> str:
    """``" read (2 others cannot be)"`` after a count of files read, when some were skipped."""
    k = given - n_read
    return f" read ({k} other{'s' if k > 1 else ''} cannot be)" if k > 0 else ""


#: The largest float sample an image of encoded values may hold. Such values are in [0, 1]
#: (1 is white); processing or a wide gamut carry some a little above 1, but twice white is
#: no display value: a float image beyond it holds unscaled numbers (a microscope's or a
#: sensor's 0-4000 counts, say), which read as colours clip to white or overflow.
ENCODED_FLOAT_MAX = 2.0


def mask_of(image: Any, path: Path, height: int, width: int, of: str, counts: str) -> Any:
    """Return a ``--mask`` image as booleans (non-zero: the pixel counts), checked.

    A colour mask counts where any channel is non-zero. One-line errors name ``path`` and
    what the mask must match (``of``: "the images", "the frames") or allow (``counts``).
    """
    import numpy as np

    m = np.asarray(image)
    if m.ndim == 3:
        m = m.max(axis=2)
    if m.shape != (height, width):
        raise InvalidInputError(
            f"--mask {path} is {m.shape[1]} x {m.shape[0]} px, {of} {width} x {height} px"
        )
    if not np.any(m > 0):
        raise InvalidInputError(f"--mask {path} is zero everywhere: {counts}")
    return m > 0


def refuse_unscaled_floats(path: Path, image: Any) -> None:
    """Refuse, in one line, a float image whose values are not encoded colours in [0, 1].

    Commands that read pixels as colours (segment, white-balance, cvd, delta-e, stain
    normalisation) would otherwise clip such an image to white, or fail inside a conversion
    with a message about "linear values"; the line says what the file holds and what to do.
    """
    import numpy as np

    a = np.asarray(image)
    if a.dtype.kind != "f" or a.size == 0:
        return
    ok = np.isfinite(a)  # NaN and inf are the commands' own to refuse
    hi = float(np.max(a, where=ok, initial=-np.inf))
    if hi > ENCODED_FLOAT_MAX:
        lo = float(np.min(a, where=ok, initial=np.inf))
        raise InvalidInputError(
            f"{path} holds floats from {lo:.4g} to {hi:.4g}; a float image is read as colours "
            f"in [0, 1] (1 is white): scale it to [0, 1] first (e.g. divide it by {hi:.4g}, or "
            "by its sensor's full scale)"
        )


def write(
    run: Run,
    path: Path,
    image: Any,
    opts: Any,
    *,
    like: Any = None,
    color_space: str | None = None,
) -> int:
    """Write ``image`` (floats in [0, 1] or integers) to the output ``path``; return the clip count.

    The options' bit depth and out-of-range policy (an :class:`ImageOut`) apply; the count is how
    many values lay outside [0, 1] in an integer output (each clipped, noted once).

    ``like`` is the input array whose depth the output keeps (uint16 in, 16-bit PNG out).
    ``color_space``: the RGB space whose ICC profile the file carries (``write_image``).
    TIFF output is float32 unless ``--bit-depth`` asks for integers; ``.npy`` keeps the dtype.
    """
    import numpy as np

    from imageform.io import image_format, write_image

    fmt = image_format(path)
    bits = getattr(opts, "bit_depth", None)
    policy = getattr(opts, "out_of_range", "clip")
    a = np.asarray(image)
    if fmt in ("png", "jpeg", "netpbm") and bits is None:
        bits = 16 if like is not None and np.asarray(like).dtype == np.uint16 else 8
        if fmt == "jpeg":
            bits = 8
    if fmt == "tiff" and bits is None and a.dtype.kind == "f":
        a = a.astype(np.float32, copy=False)
    written = write_image(
        run.file(path), a, bit_depth=bits, out_of_range=policy, color_space=color_space
    )
    if written.out_of_range:
        run.note(
            f"note: {written.out_of_range} values outside [0, 1] were clipped to fit the "
            f"{written.bit_depth}-bit {path.name}; write .tif or .npy to keep them "
            "(--out-of-range error refuses instead)"
        )
    return written.out_of_range


#: Bytes of float64 values one band of rows holds in :func:`write_mapped` (its temporaries are a
#: few times that): the band's height follows the image's width and channels.
BAND_BYTES = 8 * 2**20


def band_rows(shape: tuple[int, ...], band_bytes: int = BAND_BYTES) -> int:
    """Rows of an image of ``shape`` (H, W[, C]) in one band of ``band_bytes`` float64 values."""
    per_row = 8 * int(shape[1]) * (int(shape[2]) if len(shape) > 2 else 1)
    return max(1, band_bytes // max(per_row, 1))


def write_mapped(
    run: Run,
    path: Path,
    image: Any,
    fn: Any,
    opts: Any,
    *,
    like: Any = None,
    color_space: str | None = None,
) -> tuple[int, Any, Any, Any, tuple[int, ...]]:
    """Write ``fn(image)`` to ``path``, computed a band of rows at a time.

    ``fn`` works pixel by pixel: a colour conversion, a CVD simulation, white-balance gains. The
    same file as ``write(run, path, fn(image), opts, like=like)``, but the whole result never
    exists as floats: each band is computed and stored straight as the output's samples (8 or
    16-bit integers for PNG/JPEG and ``--bit-depth``, float32 for a float TIFF), so that a 100 Mpx
    image goes through in a fraction of the memory budget (``IMAGEFORM_MAX_MEMORY``).

    Returns the clip count (values outside [0, 1] in an integer output), the computed dtype, the
    per-channel minimum and maximum of the computed values, and the result's shape.
    ``color_space``: the RGB space whose ICC profile the file carries (``write_image``).
    """
    import numpy as np

    from imageform.io import image_format, write_image
    from imageform.io.image_io import float_codes

    fmt = image_format(path)
    bits = getattr(opts, "bit_depth", None)
    policy = getattr(opts, "out_of_range", "clip")
    a = np.asarray(image)
    if fmt in ("png", "jpeg", "netpbm") and bits is None:
        bits = 16 if like is not None and np.asarray(like).dtype == np.uint16 else 8
        if fmt == "jpeg":
            bits = 8
    integer = fmt != "npy" and bits is not None
    depth = int(bits or 8)
    h = a.shape[0]
    rows = band_rows(a.shape)
    dest: Any = None
    dtype: Any = None
    lo: Any = None
    hi: Any = None
    n_out = 0
    for r0 in range(0, h, rows):
        band = np.asarray(fn(a[r0 : r0 + rows]))
        if dest is None:
            dtype = band.dtype
            if integer:
                store: Any = np.uint8 if depth == 8 else np.uint16
            elif fmt == "tiff" and band.dtype.kind == "f":
                store = np.float32
            else:
                store = band.dtype
            dest = np.empty((h, *band.shape[1:]), dtype=store)
        flat = band.reshape(-1, band.shape[-1] if band.ndim == 3 else 1)
        b_lo, b_hi = flat.min(axis=0), flat.max(axis=0)
        lo = b_lo if lo is None else np.minimum(lo, b_lo)
        hi = b_hi if hi is None else np.maximum(hi, b_hi)
        if integer and band.dtype.kind == "f":  # as write_image quantises (NaN/inf refused)
            if not np.all(np.isfinite(band)):
                raise InvalidInputError(f"the image to write to {path} contains NaN or inf")
            codes, outside = float_codes(band, depth)
            n_out += outside
            dest[r0 : r0 + rows] = codes
        elif integer:  # integer samples: rescaled by write_image's rule
            top, src_top = 2**depth - 1, np.iinfo(band.dtype).max
            dest[r0 : r0 + rows] = (
                band
                if src_top == top
                else np.round(band.astype(np.float64) * (top / src_top)).astype(dest.dtype)
            )
        else:
            dest[r0 : r0 + rows] = band
    if n_out and policy == "error":
        raise InvalidInputError(
            f"{n_out} values outside [0, 1] (min {float(np.min(lo)):.4g}, max "
            f"{float(np.max(hi)):.4g}) cannot be stored in the {bits}-bit {path.name}; keep "
            "them in a float .tif or .npy, or clip them (--out-of-range clip)"
        )
    shape = tuple(dest.shape)
    if dest.ndim == 3 and dest.shape[-1] == 1 and fmt != "npy":
        dest = dest[..., 0]
    write_image(run.file(path), dest, bit_depth=bits, out_of_range=policy, color_space=color_space)
    if n_out:
        run.note(
            f"note: {n_out} values outside [0, 1] were clipped to fit the "
            f"{bits}-bit {path.name}; write .tif or .npy to keep them "
            "(--out-of-range error refuses instead)"
        )
    return n_out, dtype, lo, hi, shape


def rgb_space_or_auto(value: Any, why: str, *, linear: bool = False) -> str:
    """``--from``: ``auto`` (the space the file declares) or an RGB space's name.

    ``linear``: the ``linear_`` twins are taken too. Anything else is one line saying
    ``why`` an RGB space is needed.
    """
    from imageform.color import RGB_SPACES, space_name

    if str(value).strip().lower() == "auto":
        return "auto"
    name = space_name(value, "--from (src)")
    if name not in RGB_SPACES and not (linear and name.removeprefix("linear_") in RGB_SPACES):
        twins = ", or a linear_ one" if linear else ""
        raise InvalidInputError(
            f"--from {name}: {why}; give an RGB space ({', '.join(RGB_SPACES)}{twins}) or auto"
        )
    return name


def declared_space(run: Run, image: Path, declared: Any, *, grey: bool) -> str:
    """``--from auto``: the space ``image`` declares, else srgb (gray for a grey image)."""
    if grey:
        return "gray"
    if declared.name is not None:
        if declared.name != "srgb":
            how = {
                "icc": "its ICC profile",
                "nclx": "its HEIF colour box (nclx)",
                "png-srgb": "its sRGB chunk",
                "png-gama": f"its PNG gAMA/cHRM chunks ({declared.description})",
                "png-chrm": f"its PNG cHRM chunk ({declared.description})",
                "png-cicp": f"its PNG cICP chunk ({declared.description})",
                "tiff-description": "its TIFF description (written by imageform)",
                "radiance": "its Radiance HDR header (linear RGB)",
            }.get(declared.source, "its EXIF tags")
            run.note(f"note: {image} declares {declared.name} in {how}; read as {declared.name}"
                     " (--from overrides)")  # fmt: skip
        return str(declared.name)
    if declared.source == "icc":
        run.note(
            f"note: {image} carries an ICC profile imageform does not recognise "
            f"({declared.description or 'no description'}); read as srgb (--from overrides)"
        )
    elif declared.source in ("png-gama", "png-chrm", "png-cicp"):
        run.note(
            f"note: {image} declares {declared.description} in its PNG chunks, which no space "
            "imageform knows matches; read as srgb (--from overrides)"
        )
    return "srgb"


@dataclass(frozen=True, kw_only=True)
class RgbFrom(Options):
    """``--from``: the RGB space the input images are encoded in (``auto``: each file's own).

    The commands that take it work on sRGB values (thresholds, stain statistics, chart
    references are sRGB's): an image that declares another space is brought to sRGB first
    (:func:`input_space`, :func:`in_srgb`).
    """

    src: str = option(
        "auto",
        flag="--from",
        help=(
            "RGB space of the input images; auto: the one each file declares (ICC profile, PNG "
            "sRGB chunk, EXIF, HEIF), else srgb. Other spaces are brought to sRGB first."
        ),
        metavar="SPACE",
    )

    def check(self) -> None:
        """Check ``--from`` (auto or an RGB space)."""
        super().check()
        why = "this command reads encoded RGB images"
        object.__setattr__(self, "src", rgb_space_or_auto(self.src, why))


def input_space(run: Run, path: Path, opts: Any) -> str:
    """Return the RGB space of the image file ``path``: ``--from``, or (auto) its declared one."""
    src = str(getattr(opts, "src", "srgb"))
    if src != "auto":
        return src
    from imageform.io import image_color_space

    return declared_space(run, path, image_color_space(path), grey=False)


def as_values(image: Any, space: str) -> Any:
    """``image`` as values of ``space``: integer samples of a linear space as floats.

    A file that declares a linear space (a PNG's gAMA 1.0, an scRGB profile) stores its
    light as full-range integers, ``code / (2**bits - 1)``; :func:`imageform.color.convert`
    takes a linear space's values as floats only. Anything else, a device array included
    (whose conversion then runs on the CPU, :func:`gpu_bands`), is returned as it is.
    """
    import numpy as np

    if not isinstance(image, np.ndarray) or image.dtype.kind != "u":
        return image
    if not str(space).startswith("linear_"):
        return image
    return np.asarray(image, dtype=np.float32) / np.float32(np.iinfo(image.dtype).max)


def in_srgb(run: Run, path: Path, image: Any, space: str, *, clip: bool) -> Any:
    """``image`` (encoded in ``space``) as encoded sRGB; unchanged when ``space`` is srgb.

    Floats from :func:`imageform.color.convert`; ``clip``: colours outside sRGB's gamut are
    clipped to [0, 1] (for methods defined on [0, 1] only), with a note saying how many pixels.
    """
    if space == "srgb":
        return image
    import numpy as np

    from imageform.color import convert

    out = np.asarray(convert(as_values(image, space), space, "srgb"))
    if clip:
        outside = int(np.count_nonzero(((out < 0.0) | (out > 1.0)).any(axis=-1)))
        if outside:
            run.note(f"note: {outside} pixels of {path} lie outside sRGB's gamut; clipped to it")
        out = np.clip(out, 0.0, 1.0)
    return out


def patches_in_srgb(patches: Any, space: str) -> Any:
    """ChartPatches measured in ``space`` with their means as sRGB (floats: none clipped)."""
    if space == "srgb":
        return patches
    import numpy as np

    from imageform.analysis import ChartPatches
    from imageform.color import convert

    ok = np.isfinite(patches.means)
    means = np.asarray(convert(np.where(ok, patches.means, 0.0), space, "srgb"))
    return ChartPatches(np.where(ok, means, np.nan), patches.std, patches.saturated,
                        patches.missing, patches.used)  # fmt: skip
