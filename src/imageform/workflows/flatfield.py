"""``imageform flatfield``: estimate a flat field from images, or apply a measured one.

The maths lives in :mod:`imageform.analysis.flatfield`; this module reads the images (files,
folders or globs), writes ``flatfield.tif`` (or ``.npy``), ``darkfield.tif`` with
``--darkfield``, ``flatfield.json`` (what was estimated from what), ``mask.png`` with
``--mask auto`` (the field of view found) and, with ``--apply`` or ``--flat``, every image
corrected under ``corrected/``, all into the output folder, all or nothing.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, get_args

from imageform.errors import InvalidInputError
from imageform.workflows._images import ImageIn, mask_of
from imageform.workflows._spec import (
    Input,
    Output,
    Result,
    Run,
    Workflow,
    option,
    refuse_foreign_folder,
)

__all__ = ["WORKFLOWS", "FlatfieldOptions"]

#: ``format`` of flatfield.json.
FLATFIELD_FORMAT = "imageform-flatfield"

#: The file that marks a folder as imageform flatfield's output (only such a folder is
#: replaced with --force: never a folder of the user's files).
_MARKER = "flatfield.json"

Method = Literal["basic", "radial"]
FileFormat = Literal["tif", "npy"]
Center = Literal["image", "mask", "fit"]


@dataclass(frozen=True, kw_only=True)
class FlatfieldOptions(ImageIn):
    """Options of ``imageform flatfield``."""

    method: Method = option(
        "basic",
        help="basic: BaSiC (Peng et al. 2017) from 2 or more images of varied content (tiles, "
        "frames); radial: a robust radial polynomial fitted to the images' mean (one frame "
        "will do: a photograph; an endoscope's frame with --mask auto).",
        choices=get_args(Method),
    )
    darkfield: bool = option(
        False, help="Also estimate the dark field (dim fluorescence); basic only."
    )
    apply: bool = option(
        False, help="Also write every image corrected, under corrected/ in the output folder."
    )
    flat: Path | None = option(
        None,
        help="A measured flat field (an image of a uniform target, or a flatfield.tif): apply "
        "it to the images instead of estimating one.",
        metavar="FILE",
        input=True,
    )
    dark: Path | None = option(
        None,
        help="A measured dark field (a dark frame) subtracted first; with --flat.",
        metavar="FILE",
        input=True,
    )
    sort_intensity: bool = option(
        False,
        help="Sort every pixel's values over the images before the fit (the reference MATLAB "
        "BaSiC's rule); basic only.",
    )
    smoothness: float | None = option(
        None,
        help="BaSiC's flat-field regularisation (larger: smoother); default the paper's rule.",
        minimum=0.0,
    )
    working_size: int = option(
        128, help="Side of the square BaSiC fits at, in pixels.", minimum=8, maximum=4096
    )
    mask: str | None = option(
        None,
        help="The pixels that count (radial and --flat): auto (an endoscope's field of view, "
        "found in the images: its aperture without the black surround and burned-in text) "
        "or a mask image of the images' size (non-zero: count). The flat field is fitted "
        "there and defined over the whole frame; the corrected images keep the pixels "
        "outside as they were.",
        metavar="auto|FILE",
    )
    center: Center = option(
        "image",
        help="The radial fit's center: image (its center), mask (the center of --mask's "
        "bounding box: an endoscope's aperture) or fit (searched over the middle 40 % of "
        "the frame: an off-axis lamp; on an endoscope's frame the scene misleads it).",
        choices=get_args(Center),
    )
    format: FileFormat = option(
        "tif",
        help="File format of the fields and the corrected images: tif (float32 TIFF) or npy.",
        choices=get_args(FileFormat),
    )

    def check(self) -> None:
        """Refuse --dark without --flat, radial-only options with basic, --mask with basic."""
        super().check()
        if self.dark is not None and self.flat is None:
            raise InvalidInputError(
                "--dark is subtracted with a measured --flat; to estimate the dark field "
                "from the images, give --darkfield"
            )
        if self.flat is not None and self.darkfield:
            raise InvalidInputError(
                "--darkfield estimates a dark field, --flat applies a measured flat field; "
                "give a dark frame with --dark"
            )
        if self.method == "radial" and (self.darkfield or self.sort_intensity):
            raise InvalidInputError(
                "--darkfield and --sort-intensity are options of --method basic"
            )
        if self.mask is not None:
            key = str(self.mask).strip()
            object.__setattr__(self, "mask", "auto" if key.lower() == "auto" else key)
            if self.method != "radial" and self.flat is None:
                raise InvalidInputError(
                    "--mask is an option of --method radial and of --flat (BaSiC takes no mask)"
                )


def _image_files(sources: Any) -> list[Path]:
    """Return the image files of the inputs: files as given, folders' images in natural order."""
    from imageform.io import image_files

    if isinstance(sources, str | Path):
        sources = [sources]
    files: list[Path] = []
    for s in sources:
        p = Path(s)
        if p.is_dir():
            files += image_files(p)
        elif p.is_file():
            files.append(p)
        else:
            raise InvalidInputError(f"input {p} does not exist")
    if not files:
        raise InvalidInputError("expected images: files, folders or glob patterns")
    stems = [f.stem for f in files]
    twice = sorted({s for s in stems if stems.count(s) > 1})
    if twice:
        raise InvalidInputError(
            f"two inputs share the name {twice[0]!r}: their corrected images would collide; "
            "rename one"
        )
    return files


def _read(path: Path, opts: FlatfieldOptions, *, own: bool = True) -> Any:
    """Read an image as stored (uint8/uint16/floats), grey as (H, W).

    ``own``: one of the input images (its ``--frame``); else a file that goes with them (a
    mask, a flat or dark field), which holds one image.
    """
    from imageform.workflows._images import OPTS_FRAME, read

    img = read(path, opts, frame=OPTS_FRAME if own else None)
    return img[..., 0] if img.ndim == 3 and img.shape[2] == 1 else img


def _as_field(path: Path, opts: FlatfieldOptions, scale_integers: bool) -> Any:
    """Read a measured flat or dark field as floats (integer dark frames: fractions of range)."""
    import numpy as np

    a = _read(path, opts, own=False)
    if scale_integers and a.dtype in (np.uint8, np.uint16):
        return a.astype(np.float64) / np.iinfo(a.dtype).max
    return a.astype(np.float64)


def _read_mask(path: Path, opts: FlatfieldOptions, shape: tuple[int, ...]) -> Any:
    """Read ``--mask FILE`` as booleans (non-zero: the pixel counts) of the images' size."""
    if not path.is_file():
        raise InvalidInputError(f"--mask {path} does not exist (give auto or a mask image)")
    return mask_of(
        _read(path, opts, own=False),
        path,
        shape[0],
        shape[1],
        "the images",
        "no pixel would count",
    )


def _check_out(out: Path, files: list[Path], force: bool) -> None:
    """Refuse an output folder that holds an input, or (with --force) one we did not write."""
    res = out.resolve()
    for f in files:
        if res == f.resolve().parent or res in f.resolve().parents:
            raise InvalidInputError(f"output folder {out} holds the input {f}; choose a new folder")
    refuse_foreign_folder(out, force, (_MARKER,), "flatfield", "a previous flatfield output")


def _write_array(path: Path, a: Any) -> None:
    """Write a float array as float32 TIFF or .npy (by suffix)."""
    import numpy as np

    from imageform.io import write_image

    arr = np.asarray(a)
    if path.suffix == ".npy":
        np.save(path, arr.astype(np.float32))
    else:
        write_image(path, arr.astype(np.float32))


def flatfield(run: Run, opts: FlatfieldOptions, *, out: Path, images: Any) -> Result:
    """Estimate the flat field of ``images`` (or apply ``--flat``); write into ``out``."""
    import numpy as np

    from imageform._jsonio import write_json
    from imageform.analysis import correct_flatfield, estimate_flatfield, estimate_vignetting
    from imageform.geometry import field_of_view_mask

    if opts.center != "image" and (opts.method != "radial" or opts.flat is not None):
        raise InvalidInputError("--center is an option of --method radial")
    if opts.center == "mask" and opts.mask is None:
        raise InvalidInputError("--center mask takes the center of --mask: give --mask")
    files = _image_files(images)
    _check_out(out, files, run.outputs.force)
    if run.progress is not None:
        run.progress("reading the images", 0.0)
    stack = [_read(f, opts) for f in files]
    shapes = {tuple(a.shape) for a in stack}
    if len(shapes) > 1:
        first = tuple(stack[0].shape)
        other = next(i for i, a in enumerate(stack) if tuple(a.shape) != first)
        raise InvalidInputError(
            f"expected images of one size, got {files[0].name} {first} and "
            f"{files[other].name} {tuple(stack[other].shape)}"
        )
    ext = "." + opts.format
    mask = None
    if opts.mask == "auto":
        mask = field_of_view_mask(stack)
    elif opts.mask is not None:
        mask = _read_mask(Path(opts.mask), opts, tuple(stack[0].shape))
    summary: dict[str, Any] = {"images": len(files), "shape": list(stack[0].shape), "out": out}
    text: list[str] = []
    if opts.flat is not None:
        flat = _as_field(opts.flat, opts, scale_integers=False)
        dark = None if opts.dark is None else _as_field(opts.dark, opts, scale_integers=True)
        method = "measured"
        converged, iterations, baseline = True, 0, None
        dark_out = dark
    else:
        if run.progress is not None:
            run.progress("estimating the flat field", 0.1)
        if opts.method == "radial":
            mean = np.mean([np.asarray(a, dtype=np.float64) for a in stack], axis=0)
            if stack[0].dtype in (np.uint8, np.uint16):
                mean = mean / np.iinfo(stack[0].dtype).max
            est = estimate_vignetting(
                mean,
                mask=mask,
                center="mask" if opts.center == "mask" else None,
                fit_center=opts.center == "fit",
            )
        else:
            if len(stack) < 2:
                raise InvalidInputError(
                    f"--method basic needs 2 or more images of varied content, got "
                    f"{len(stack)}; for one frame give --method radial"
                )
            est = estimate_flatfield(
                stack,
                darkfield=opts.darkfield,
                smoothness=opts.smoothness,
                sort_intensity=opts.sort_intensity,
                working_size=opts.working_size,
            )
        flat, method = est.flatfield, est.method
        dark = est.darkfield if opts.darkfield else None
        dark_out = dark
        converged, iterations = est.converged, est.iterations
        baseline = np.asarray(est.baseline)
        if not converged:
            run.note(
                f"note: the {method} fit stopped at its iteration limit ({iterations} "
                "iterations) before its tolerance; the flat field may be rough"
            )
    folder = run.folder(out)
    written: list[str] = []
    if opts.flat is None:
        _write_array(folder / ("flatfield" + ext), flat)
        written.append("flatfield" + ext)
        if dark_out is not None:
            _write_array(folder / ("darkfield" + ext), dark_out)
            written.append("darkfield" + ext)
    if opts.mask == "auto" and mask is not None:
        from imageform.io import write_image

        write_image(folder / "mask.png", np.where(mask, 255, 0).astype(np.uint8))
    corrected: list[str] = []
    if opts.apply or opts.flat is not None:
        sub = folder / "corrected"
        sub.mkdir()
        for i, (f, img) in enumerate(zip(files, stack, strict=True)):
            if run.progress is not None:
                run.progress("correcting", 0.5 + 0.5 * i / len(files))
            try:
                fixed = correct_flatfield(img, flat, dark, mask=mask)
            except InvalidInputError as exc:
                where = "--flat " + str(opts.flat) if opts.flat is not None else "the flat field"
                raise InvalidInputError(f"{f.name} with {where}: {exc}") from None
            _write_array(sub / (f.stem + ext), fixed)
            corrected.append(f"corrected/{f.stem}{ext}")
    fl = np.asarray(flat, dtype=np.float64)
    fl = fl / fl.mean(axis=(0, 1)) if mask is None else fl[mask] / fl[mask].mean(axis=0)
    record: dict[str, Any] = {
        "format": FLATFIELD_FORMAT,
        "version": 1,
        "method": method,
        "inputs": [str(f) for f in files],
        "flatfield_file": written[0] if written else None,
        "darkfield_file": written[1] if len(written) > 1 else None,
        "flatfield_min": float(fl.min()),
        "flatfield_max": float(fl.max()),
        "darkfield_mean": None if dark_out is None else float(np.mean(dark_out)),
        "converged": bool(converged),
        "iterations": int(iterations),
        "baseline": None if baseline is None else baseline.tolist(),
        "corrected": corrected,
        "mask": None if opts.mask is None else str(opts.mask),
        "mask_file": "mask.png" if opts.mask == "auto" else None,
        "mask_share": None if mask is None else round(float(np.mean(mask)), 4),
        "center": opts.center if method == "radial" else None,
    }
    write_json(folder / _MARKER, record)
    summary.update({k: v for k, v in record.items() if k not in ("format", "version")})
    if opts.flat is None:
        text.append(
            f"{method} flat field from {len(files)} image(s) "
            f"({stack[0].shape[1]}x{stack[0].shape[0]}): min {fl.min():.3f}, max "
            f"{fl.max():.3f} of its mean"
            + ("" if mask is None else f" in the mask ({np.mean(mask):.0%} of the frame)")
            + ("" if method == "radial" else f", {iterations} iterations")
            + ("" if converged else " (not converged)")
        )
    else:
        text.append(
            f"measured flat field {opts.flat}: min {fl.min():.3f}, max {fl.max():.3f} of its mean"
            + ("" if mask is None else f" in the mask ({np.mean(mask):.0%} of the frame)")
        )
    names = (
        [*written, _MARKER]
        + (["mask.png"] if opts.mask == "auto" else [])
        + ([f"corrected/ ({len(corrected)} images)"] if corrected else [])
    )
    text.append(", ".join(names) + f" -> {out}")
    return Result(summary, tuple(text))


#: What the output folder holds (its --help, and the refusal of a file name for it).
_HOLDS = (
    "flatfield.tif, darkfield.tif (--darkfield), flatfield.json, mask.png (--mask auto), "
    "corrected/ (--apply, --flat)"
)

WORKFLOWS = (
    Workflow(
        "flatfield",
        "Shading (flat-field, vignetting) correction: estimate the flat field or apply one.",
        "imageform.workflows.flatfield:flatfield",
        FlatfieldOptions,
        (
            Input(
                "images",
                "Image files, folders of images or quoted glob patterns ('tiles/*.tif').",
                many=True,
                metavar="FOLDER_OR_FILES...",
                kind="text",
            ),
        ),
        Output(f"Output folder: {_HOLDS}; replaced whole.", folder=True, holds=_HOLDS),
        group="analysis",
        description="Estimated (BaSiC from tiles or frames of varied content; --method radial "
        "from one frame, --mask auto for an endoscope's) or measured (--flat, --dark) flat "
        "field; corrected = (I - D) / (F / mean F). Integer images are read as fractions of "
        "full range (uint16: counts / 65535), so the fields and the corrected images "
        "(float32 TIFF or .npy) are in those units. "
        "docs/optics.md#shading-correction.",
    ),
)
