"""The commands ``imageform batch`` runs: name -> a picklable per-file function.

Each entry's ``run(in_path, out_path, options)`` reads one file, applies the library, writes
``out_path`` and returns a dict of small metrics (the runner writes ``out_path`` under a
temporary name and renames it). The functions are module-level, so they pickle by reference
and run on any ``dask.distributed`` worker that can import imageform. ``check(options,
out_suffix)`` validates the options once, on the client, before any job starts.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from imageform._validate import check_option
from imageform.errors import InvalidInputError

__all__ = ["COMMANDS", "BatchCommand", "get_command"]

Options = Mapping[str, Any]


@dataclass(frozen=True)
class BatchCommand:
    """One command of ``imageform batch``.

    Attributes
    ----------
    name : str
        The command's name on the command line (``convert``, ``white-balance``, ...).
    run : callable
        ``run(in_path, out_path, options) -> dict`` of small metrics; picklable.
    options : tuple of str
        The option names ``run`` understands (others are refused by :meth:`validate`).
    suffixes : tuple of str
        Output file suffixes the command can write.
    check : callable or None
        ``check(options, out_suffix)`` raising on invalid options, before any job runs.
    """

    name: str
    run: Callable[[Path, Path, Options], dict[str, Any]]
    options: tuple[str, ...]
    suffixes: tuple[str, ...]
    check: Callable[[Options, str], None] | None = None

    def validate(self, options: Options, out_suffix: str) -> None:
        """Refuse unknown option names and an unsupported output suffix; run ``check``."""
        for key in options:
            check_option(key, self.options, f"option of batch {self.name}")
        if out_suffix.lower() not in self.suffixes:
            raise InvalidInputError(
                f"batch {self.name} writes {', '.join(self.suffixes)} files, got output "
                f"suffix {out_suffix!r}"
            )
        if self.check is not None:
            self.check(options, out_suffix)


# ---------------------------------------------------------------- convert


def _convert_params(options: Options) -> dict[str, object]:
    params: dict[str, object] = {"alpha": options.get("alpha", "reject")}
    if options.get("white"):
        params["white"] = options["white"]
    return params


def _check_convert(options: Options, out_suffix: str) -> None:
    from imageform.cli.color_cmds import check_png_space
    from imageform.color.convert import _space

    if "to" not in options:
        raise InvalidInputError("batch convert needs --to (the colour space of the outputs)")
    _space(options.get("from", "srgb"), "--from")
    check_png_space(_space(options["to"], "--to"), Path("out" + out_suffix))


def run_convert(in_path: Path, out_path: Path, options: Options) -> dict[str, Any]:
    """``imageform convert`` on one file (:func:`imageform.color.convert`)."""
    from imageform.cli.color_cmds import convert_file
    from imageform.color.convert import _space

    src, dst = _space(options.get("from", "srgb"), "--from"), _space(options["to"], "--to")
    info = convert_file(
        in_path,
        out_path,
        src,
        dst,
        _convert_params(options),
        bits=int(options.get("bits", 0)),
        clip=bool(options.get("clip", False)),
    )
    return {"shape": info["shape"], "min": info["min"], "max": info["max"]}


# ---------------------------------------------------------------- white balance


def _wb_params(options: Options) -> dict[str, Any]:
    keys = ("normalize", "percentile", "p", "sigma", "illuminant", "cct", "clip")
    return {k: options[k] for k in keys if k in options}


def _check_white_balance(options: Options, out_suffix: str) -> None:
    from imageform.color.white_balance import _method

    _method(options.get("method", "gray_world"), options.get("percentile"))


def run_white_balance(in_path: Path, out_path: Path, options: Options) -> dict[str, Any]:
    """``imageform white-balance`` on one file (:func:`imageform.color.white_balance`)."""
    from imageform.cli.color_analysis_cmds import white_balance_file

    info = white_balance_file(
        in_path, out_path, options.get("method", "gray_world"), **_wb_params(options)
    )
    return {"gains": info["gains"], "clipped": info["values_clipped_for_integer_output"]}


# ---------------------------------------------------------------- demosaic


def _check_demosaic(options: Options, out_suffix: str) -> None:
    from imageform.sensor import DEMOSAIC_METHODS, cfa_pattern

    cfa_pattern(options.get("pattern", "RGGB"))
    check_option(options.get("method", "menon"), DEMOSAIC_METHODS, "demosaicing method")


def run_demosaic(in_path: Path, out_path: Path, options: Options) -> dict[str, Any]:
    """``imageform demosaic`` on one file (:func:`imageform.sensor.demosaic`)."""
    from imageform.cli.sensor_cmds import demosaic_file
    from imageform.sensor import cfa_pattern

    info = demosaic_file(
        in_path,
        out_path,
        cfa_pattern(options.get("pattern", "RGGB")),
        options.get("method", "menon"),
        bits=int(options.get("bits", 0)),
        clip=bool(options.get("clip", False)),
    )
    return {"shape": info["shape"], "clipped": info["clipped_values"]}


# ---------------------------------------------------------------- analysis recipes
# imageform.analysis (stain normalisation, colour correction) is imported inside the jobs so
# that `imageform batch convert` does not pay for scipy.ndimage at start-up.

_STAIN_METHODS = ("reinhard", "macenko")


def _read_float_rgb(path: Path) -> tuple[Any, Any]:
    import numpy as np

    from imageform._validate import as_image
    from imageform.io import read_image

    raw = read_image(path)
    if raw.ndim != 3 or raw.shape[-1] != 3:
        raise InvalidInputError(f"{path}: expected an RGB image (H, W, 3), got {raw.shape}")
    return np.asarray(as_image(raw)), raw.dtype


def _write_like(path: Path, image: Any, dtype: Any, clip: bool) -> int:
    """Write ``image`` to ``path`` (PNG: the input's bit depth; TIFF: float32); returns how
    many values lie outside [0, 1] (clipped for PNG with ``clip``, an error without)."""
    import numpy as np

    from imageform.io import image_format, write_image

    arr = np.asarray(image)
    n_out = int(np.count_nonzero((arr < 0) | (arr > 1)))
    if image_format(path) == "png":
        write_image(path, arr, bits=16 if dtype == np.uint16 else 8, clip=clip)
    else:
        write_image(path, arr.astype(np.float32, copy=False))
    return n_out


def _check_stain(options: Options, out_suffix: str) -> None:
    check_option(options.get("method", "reinhard"), _STAIN_METHODS, "stain normalisation")
    if not options.get("target"):
        raise InvalidInputError(
            "batch stain-normalize needs --target (a target image, or stats .json)"
        )
    if not Path(options["target"]).exists():
        raise InvalidInputError(f"target {options['target']} does not exist")


def _stain_target(method: str, target: Path) -> Any:
    from imageform import analysis

    if target.suffix.lower() == ".json":
        kind = analysis.ReinhardStats if method == "reinhard" else analysis.MacenkoStains
        return kind.from_json(target)
    return _read_float_rgb(target)[0]


def run_stain_normalize(in_path: Path, out_path: Path, options: Options) -> dict[str, Any]:
    """Stain normalisation of one file (``imageform.analysis.reinhard_normalize`` or
    ``macenko_normalize``) towards ``target`` (an image, or statistics saved as JSON)."""
    from imageform import analysis

    method = check_option(options.get("method", "reinhard"), _STAIN_METHODS, "stain method")
    img, dtype = _read_float_rgb(in_path)
    target = _stain_target(method, Path(options["target"]))
    fn = analysis.reinhard_normalize if method == "reinhard" else analysis.macenko_normalize
    out = fn(img, target)
    return {"out_of_range": _write_like(out_path, out, dtype, bool(options.get("clip", False)))}


def _check_harmonize(options: Options, out_suffix: str) -> None:
    if not options.get("correction"):
        raise InvalidInputError("batch harmonize needs --correction (a corr.json)")
    if not Path(options["correction"]).exists():
        raise InvalidInputError(f"correction {options['correction']} does not exist")


def run_harmonize(in_path: Path, out_path: Path, options: Options) -> dict[str, Any]:
    """Apply a colour correction between devices (``imageform.analysis.ColorCorrection``,
    loaded from ``correction``, a JSON file) to one file."""
    from imageform import analysis

    img, dtype = _read_float_rgb(in_path)
    corr = analysis.ColorCorrection.from_json(Path(options["correction"]))
    out = corr.apply(img)
    return {"out_of_range": _write_like(out_path, out, dtype, bool(options.get("clip", False)))}


_IMAGES = (".png", ".tif", ".tiff")

#: The commands of ``imageform batch``, by name (``_`` for the command line's ``-``).
COMMANDS: dict[str, BatchCommand] = {
    c.name.replace("-", "_"): c
    for c in (
        BatchCommand(
            "convert",
            run_convert,
            ("from", "to", "white", "alpha", "bits", "clip"),
            (*_IMAGES, ".npy"),
            _check_convert,
        ),
        BatchCommand(
            "white-balance",
            run_white_balance,
            ("method", "normalize", "percentile", "p", "sigma", "illuminant", "cct", "clip"),
            _IMAGES,
            _check_white_balance,
        ),
        BatchCommand(
            "demosaic",
            run_demosaic,
            ("pattern", "method", "bits", "clip"),
            (".png", ".npy"),
            _check_demosaic,
        ),
        BatchCommand(
            "stain-normalize",
            run_stain_normalize,
            ("method", "target", "clip"),
            _IMAGES,
            _check_stain,
        ),
        BatchCommand("harmonize", run_harmonize, ("correction", "clip"), _IMAGES, _check_harmonize),
    )
}


def get_command(name: str) -> BatchCommand:
    """The :class:`BatchCommand` called ``name`` (unknown names list the valid ones).

    >>> get_command("convert").options[:2]
    ('from', 'to')
    """
    return COMMANDS[check_option(name, tuple(COMMANDS), "batch command")]
