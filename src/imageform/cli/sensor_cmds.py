"""``imageform mosaic`` and ``imageform demosaic``: Bayer sampling and reconstruction of files.

Images are 8/16-bit PNG (grey for mosaics, RGB for colour) or ``.npy`` float arrays in
[0, 1]. A PNG output keeps the input's bit depth unless ``--bits`` says otherwise; values
that overshoot [0, 1] (the interpolating filters ring at sharp edges) are clipped for PNG
output and the count is reported; ``.npy`` output keeps them unless ``--clip``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

__all__ = ["demosaic_file", "register"]


def mosaic_cmd(
    input: Annotated[Path, typer.Argument(help="RGB image (PNG, 8/16-bit) or .npy (H, W, 3).")],
    raw: Annotated[Path, typer.Argument(help="Output mosaic: .png (grey) or .npy (float32).")],
    pattern: str = typer.Option("RGGB", "--pattern", help="RGGB, BGGR, GRBG or GBRG."),
    bits: int = typer.Option(0, "--bits", help="PNG bit depth 8/16 (default: the input's)."),
    force: bool = typer.Option(False, "--force", help="Overwrite an existing output."),
    json_out: bool = typer.Option(False, "--json", help="Print machine-readable results."),
) -> None:
    """Sample an RGB image through a Bayer colour filter array (one colour per pixel)."""
    from imageform.cli._common import check_output_path, print_json
    from imageform.cli._imageio_demosaic import read_image, write_image
    from imageform.errors import InvalidInputError
    from imageform.sensor import cfa_pattern, mosaic

    pattern = cfa_pattern(pattern)
    check_output_path(raw, inputs=(input,), force=force)
    img, in_bits = read_image(input)
    if img.ndim != 3 or img.shape[-1] != 3:
        raise InvalidInputError(f"{input}: expected an RGB image (H, W, 3), got shape {img.shape}")
    out = mosaic(img, pattern)
    out_bits = bits or in_bits
    write_image(raw, out, out_bits)
    info = {
        "input": str(input),
        "output": str(raw),
        "pattern": pattern,
        "shape": list(out.shape),
        "bits": out_bits if raw.suffix.lower() != ".npy" else None,
    }
    if json_out:
        print_json(info)
    else:
        typer.echo(f"wrote {raw} ({pattern} mosaic, {out.shape[1]}x{out.shape[0]})")


def demosaic_cmd(
    raw: Annotated[Path, typer.Argument(help="Bayer mosaic: grey PNG (8/16-bit) or .npy (H, W).")],
    out: Annotated[Path, typer.Argument(help="Output RGB image: .png or .npy (float32).")],
    pattern: str = typer.Option("RGGB", "--pattern", help="RGGB, BGGR, GRBG or GBRG."),
    method: str = typer.Option(
        "menon", "--method", help="bilinear, malvar, hamilton_adams, menon or menon_soft."
    ),
    bits: int = typer.Option(0, "--bits", help="PNG bit depth 8/16 (default: the input's)."),
    clip: bool = typer.Option(False, "--clip", help="Clip to [0, 1] (always done for PNG)."),
    force: bool = typer.Option(False, "--force", help="Overwrite an existing output."),
    json_out: bool = typer.Option(False, "--json", help="Print machine-readable results."),
) -> None:
    """Reconstruct an RGB image from a Bayer mosaic (demosaicing)."""
    from imageform._validate import check_option
    from imageform.cli._common import check_output_path, print_json
    from imageform.sensor import DEMOSAIC_METHODS, cfa_pattern

    pattern = cfa_pattern(pattern)
    method = check_option(method, DEMOSAIC_METHODS, "demosaicing method")
    check_output_path(out, inputs=(raw,), force=force)
    info = demosaic_file(raw, out, pattern, method, bits=bits, clip=clip)
    n_clipped = info["out_of_range_values"]
    to_png = out.suffix.lower() != ".npy"
    rgb_shape = info["shape"]
    if json_out:
        print_json(info)
    else:
        note = f", {n_clipped} values clipped to [0, 1]" if (to_png or clip) and n_clipped else ""
        typer.echo(f"wrote {out} ({method}, {rgb_shape[1]}x{rgb_shape[0]}{note})")


def demosaic_file(
    raw: Path, out: Path, pattern: str, method: str, *, bits: int = 0, clip: bool = False
) -> dict[str, Any]:
    """Demosaic the mosaic file ``raw`` (grey PNG 8/16-bit or ``.npy``) and write ``out``.

    The file-level step of ``imageform demosaic`` (also run by ``imageform batch demosaic``):
    PNG output keeps the input's bit depth unless ``bits`` is given and is clipped to [0, 1]
    (the count is reported); ``.npy`` output keeps overshoots unless ``clip``. The caller
    validates ``pattern``/``method`` and checks the output path. Returns the ``--json`` summary.
    """
    import time

    import numpy as np

    from imageform.cli._imageio_demosaic import read_image, write_image
    from imageform.sensor import demosaic

    arr, in_bits = read_image(raw)
    t0 = time.perf_counter()
    rgb = demosaic(arr, pattern, method)
    seconds = time.perf_counter() - t0
    to_png = out.suffix.lower() != ".npy"
    n_clipped = int(np.count_nonzero((rgb < 0) | (rgb > 1)))
    if to_png or clip:
        np.clip(rgb, 0.0, 1.0, out=rgb)
    write_image(out, rgb, bits or in_bits)
    return {
        "input": str(raw),
        "output": str(out),
        "pattern": pattern,
        "method": method,
        "shape": list(rgb.shape),
        "clipped_values": n_clipped if (to_png or clip) else 0,
        "out_of_range_values": n_clipped,
        "seconds": round(seconds, 4),
    }


def register(app: typer.Typer) -> None:
    app.command("mosaic")(mosaic_cmd)
    app.command("demosaic")(demosaic_cmd)
