"""``imageform convert``: colour-space conversion of image files."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

__all__ = ["check_png_space", "convert_file", "register"]

# spaces whose values are encoded (or linear) RGB-like in [0, 1]: PNG can hold them
_DISPLAYABLE = {
    "srgb",
    "linear_srgb",
    "bgr",
    "gray",
    "cmy",
    "rec709",
    "adobe_rgb",
    "display_p3",
    "rec2020",
    "prophoto",
    "linear_rec709",
    "linear_adobe_rgb",
    "linear_display_p3",
    "linear_rec2020",
    "linear_prophoto",
}


def convert_cmd(
    input: Annotated[Path, typer.Argument(help="Input image (.png, .tif/.tiff, .npy).")],
    output: Annotated[Path, typer.Argument(help="Output (.png for RGB spaces; .tif/.npy).")],
    src: str = typer.Option("srgb", "--from", help="Colour space of the input."),
    dst: str = typer.Option(..., "--to", help="Colour space of the output."),
    white: str = typer.Option("", help="Reference white for lab/luv/lch/xyy (e.g. D65)."),
    standard: str = typer.Option("", help="Y'CbCr standard: bt601, bt709, bt2020."),
    ycc_range: str = typer.Option("", "--range", help="Y'CbCr range: full or limited."),
    code_bits: int = typer.Option(0, "--code-bits", help="Y'CbCr code-value bits (8, 10)."),
    method: str = typer.Option("", help="Grey method: rec601 or rec709."),
    alpha: str = typer.Option("reject", help="An alpha channel: reject, or keep it unchanged."),
    bits: int = typer.Option(0, help="PNG output bits (8 or 16); default: the input's."),
    clip: bool = typer.Option(False, "--clip", help="Clip values outside [0, 1] for PNG."),
    force: bool = typer.Option(False, "--force", help="Overwrite an existing output."),
    json_out: bool = typer.Option(False, "--json", help="Print a machine-readable summary."),
) -> None:
    """Convert an image between colour spaces (see `imageform.color.SPACES`)."""
    from imageform.cli._common import check_output_path, print_json
    from imageform.color.convert import _space
    from imageform.io import image_format

    s, d = _space(src, "--from"), _space(dst, "--to")
    image_format(input)
    check_output_path(output, inputs=(input,), force=force)
    check_png_space(d, output)
    params: dict[str, object] = {"alpha": alpha}
    for key, val in (
        ("white", white),
        ("standard", standard),
        ("range", ycc_range),
        ("method", method),
    ):
        if val:
            params[key] = val
    if code_bits:
        params["bits"] = code_bits
    summary = convert_file(input, output, s, d, params, bits=bits, clip=clip)
    if json_out:
        print_json(summary)
    else:
        typer.echo(f"{input} ({s}) -> {output} ({d}): {' -> '.join(summary['path']) or 'copy'}")


def check_png_space(dst: str, output: Path) -> None:
    """Refuse a PNG ``output`` for a space whose values PNG cannot hold (Lab, XYZ, ...)."""
    from imageform.errors import InvalidInputError
    from imageform.io import image_format

    if image_format(output) == "png" and dst not in _DISPLAYABLE:
        raise InvalidInputError(
            f"{dst} is not displayable: write a .tif or .npy for {dst}, PNG only holds RGB-like "
            f"spaces ({', '.join(sorted(_DISPLAYABLE))})"
        )


def convert_file(
    input: Path,
    output: Path,
    src: str,
    dst: str,
    params: dict[str, object],
    *,
    bits: int = 0,
    clip: bool = False,
) -> dict[str, Any]:
    """Convert the image file ``input`` from ``src`` to ``dst`` and write ``output``.

    The file-level step of ``imageform convert`` (also run by ``imageform batch convert``):
    PNG output keeps the input's bit depth unless ``bits`` is given, TIFF output is float32,
    ``.npy`` keeps the result's dtype. Returns the summary that ``--json`` prints. The caller
    checks the output path (never an input, ``--force``) and the spaces' names.
    """
    import numpy as np

    from imageform.color import SPACES, convert, path
    from imageform.errors import InvalidInputError
    from imageform.io import image_format, read_image, write_image

    out_fmt = image_format(output)
    img = read_image(input)
    if img.ndim == 2:
        img = img[:, :, None]
    if src != "gray" and img.ndim == 3 and img.shape[-1] == 1:
        raise InvalidInputError(f"{input} is a grey image; convert it with --from gray")
    result = np.asarray(convert(img, src, dst, **params))
    if out_fmt == "png":
        depth = bits or (16 if img.dtype == np.uint16 else 8)
        write_image(output, result, bits=depth, clip=clip)
    elif out_fmt == "tiff":
        write_image(output, result.astype(np.float32, copy=False))
    else:
        write_image(output, result)
    return {
        "input": str(input),
        "output": str(output),
        "from": src,
        "to": dst,
        "path": [e.function for e in path(src, dst)],
        "shape": list(result.shape),
        "dtype": str(result.dtype),
        "channels": SPACES[dst][1],
        "min": [float(v) for v in result.reshape(-1, result.shape[-1]).min(axis=0)],
        "max": [float(v) for v in result.reshape(-1, result.shape[-1]).max(axis=0)],
    }


def register(app: typer.Typer) -> None:
    app.command("convert")(convert_cmd)
