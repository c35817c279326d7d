"""``imageform delta-e`` and ``imageform white-balance``: colour measurement on image files."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import typer

__all__ = ["register", "white_balance_file"]

_PERCENTILES = (50.0, 90.0, 95.0, 99.0)


def _read_rgb(path: Path) -> Any:
    """An RGB image file as an array (uint8/uint16 as stored, float TIFF as floats)."""
    import numpy as np

    from imageform.errors import InvalidInputError

    if not path.exists():
        raise InvalidInputError(f"input {path} does not exist")
    if path.suffix.lower() in (".tif", ".tiff"):
        import tifffile

        arr = np.asarray(tifffile.imread(path))
    else:
        try:
            from PIL import Image
        except ImportError as exc:  # pragma: no cover - pillow ships with the test extra
            raise InvalidInputError("reading PNG/JPEG needs pillow: pip install pillow") from exc
        with Image.open(path) as im:
            keep = im.mode in ("RGB", "I;16", "I;16B", "RGBA", "L")
            arr = np.asarray(im if keep else im.convert("RGB"))
    if arr.ndim == 2:
        raise InvalidInputError(f"{path} is a single-channel image; expected RGB")
    if arr.shape[-1] == 4:
        raise InvalidInputError(f"{path} has an alpha channel; save it as RGB")
    return arr


def _write_rgb(path: Path, rgb: Any, *, sixteen: bool) -> int:
    """Write encoded RGB in [0, 1]; returns how many values were clipped for integer output."""
    import numpy as np

    arr = np.asarray(rgb, dtype=np.float64)
    if path.suffix.lower() in (".tif", ".tiff"):
        import tifffile

        tifffile.imwrite(path, arr.astype(np.float32), photometric="rgb")
        return 0
    from PIL import Image

    clipped = int(np.count_nonzero((arr < 0.0) | (arr > 1.0)))
    arr = np.clip(arr, 0.0, 1.0)
    if sixteen and path.suffix.lower() == ".png":
        from imageform.io.png import write_png  # Pillow cannot write 16-bit RGB PNG

        write_png(path, np.round(arr * 65535).astype(np.uint16))
    else:
        Image.fromarray(np.round(arr * 255).astype(np.uint8)).save(path)
    return clipped


def delta_e_cmd(
    image_a: Path = typer.Argument(..., help="Reference image (sRGB)."),
    image_b: Path = typer.Argument(..., help="Test image (sRGB), same size."),
    method: str = typer.Option("ciede2000", help="ciede2000, cie76, cie94 or cmc."),
    heatmap: Path | None = typer.Option(
        None, "--heatmap", help="Write a heat-map PNG of ΔE (colour scale 0 to 10)."
    ),
    force: bool = typer.Option(False, "--force", help="Overwrite an existing heat-map."),
    json_out: bool = typer.Option(False, "--json", help="Print machine-readable results."),
) -> None:
    """ΔE between two sRGB images of the same size: mean, max, percentiles, heat-map."""
    import numpy as np

    from imageform.cli._common import check_output_path, print_json
    from imageform.color.convert import convert
    from imageform.color.delta_e import delta_e, describe_delta_e
    from imageform.errors import InvalidInputError

    if heatmap is not None:
        check_output_path(heatmap, inputs=(image_a, image_b), force=force)
    a, b = _read_rgb(image_a), _read_rgb(image_b)
    if a.shape != b.shape:
        raise InvalidInputError(f"images differ in size: {a.shape} and {b.shape}")
    de = np.asarray(delta_e(convert(a, "srgb", "lab"), convert(b, "srgb", "lab"), method))
    mean, worst = float(de.mean()), float(de.max())
    pct = {f"p{q:g}": float(np.percentile(de, q)) for q in _PERCENTILES}
    above1, above10 = float(np.mean(de > 1.0)), float(np.mean(de > 10.0))
    if heatmap is not None:
        from matplotlib import colormaps

        rgb = colormaps["magma"](np.clip(de / 10.0, 0.0, 1.0))[..., :3]
        _write_rgb(heatmap, rgb, sixteen=False)
    if json_out:
        print_json(
            {
                "method": method,
                "pixels": int(de.size),
                "mean": mean,
                "max": worst,
                "percentiles": pct,
                "reading": describe_delta_e(mean),
                "fraction_above_1": above1,
                "fraction_above_10": above10,
                "heatmap": None if heatmap is None else str(heatmap),
            }
        )
        return
    typer.echo(f"ΔE ({method}) over {de.size} pixels")
    typer.echo(f"  mean {mean:.4f}   max {worst:.4f}   ({describe_delta_e(mean)})")
    for k, v in pct.items():
        typer.echo(f"  {k:>4} {v:.4f}")
    typer.echo(
        f"  above 1 (perceptible): {100 * above1:.2f} %   above 10 (obvious): {100 * above10:.2f} %"
    )
    if heatmap is not None:
        typer.echo(f"  heat-map (0 to 10): {heatmap}")


def white_balance_cmd(
    image_in: Path = typer.Argument(..., help="Input image (sRGB)."),
    image_out: Path = typer.Argument(..., help="Output image (PNG/JPEG 8-bit, TIFF float)."),
    method: str = typer.Option(
        "gray-world",
        help="gray-world, white-patch, max-rgb, shades-of-gray, gray-edge or manual.",
    ),
    percentile: float | None = typer.Option(None, help="white-patch: percentile (0-100)."),
    p: float = typer.Option(6.0, help="shades-of-gray / gray-edge: Minkowski p >= 1."),
    sigma: float = typer.Option(1.0, help="gray-edge: Gaussian scale in pixels."),
    illuminant: str | None = typer.Option(None, help="manual: illuminant name, e.g. A, D50."),
    cct: float | None = typer.Option(None, help="manual: colour temperature in kelvin."),
    normalize: str = typer.Option("mean", help="mean (keep the grey level) or green."),
    clip: bool = typer.Option(False, "--clip", help="Clip balanced values to [0, 1]."),
    force: bool = typer.Option(False, "--force", help="Overwrite an existing output."),
    json_out: bool = typer.Option(False, "--json", help="Print machine-readable results."),
) -> None:
    """White-balance an sRGB image in linear light; print the gains."""
    from imageform.cli._common import check_output_path, print_json

    check_output_path(image_out, inputs=(image_in,), force=force)
    info = white_balance_file(
        image_in,
        image_out,
        method,
        normalize=normalize,
        percentile=percentile,
        p=p,
        sigma=sigma,
        illuminant=illuminant,
        cct=cct,
        clip=clip,
    )
    g, clipped = info["gains"], info["values_clipped_for_integer_output"]
    if json_out:
        print_json(
            {
                "method": method,
                "gains": g,
                "output": str(image_out),
                "values_clipped_for_integer_output": clipped,
            }
        )
        return
    typer.echo(f"gains (R, G, B) in linear light: {g[0]:.4f} {g[1]:.4f} {g[2]:.4f}")
    if clipped:
        typer.echo(
            f"note: {clipped} values above 1 were clipped to fit the integer output "
            "(write a .tif to keep them)"
        )
    typer.echo(f"wrote {image_out}")


def white_balance_file(
    image_in: Path, image_out: Path, method: str = "gray-world", **params: Any
) -> dict[str, Any]:
    """White-balance the sRGB image file ``image_in`` and write ``image_out``.

    The file-level step of ``imageform white-balance`` (also run by ``imageform batch
    white-balance``): ``params`` are :func:`imageform.color.white_balance`'s keywords;
    16-bit input gives 16-bit PNG output, integer output clips values above 1 and counts them,
    TIFF output is float32. The caller checks the output path. Returns the ``--json`` summary.
    """
    import numpy as np

    from imageform.color.white_balance import white_balance

    img = _read_rgb(image_in)
    out, gains = white_balance(img, method, **params)
    clipped = _write_rgb(image_out, out, sixteen=img.dtype == np.uint16)
    return {
        "method": method,
        "gains": [float(v) for v in np.asarray(gains)],
        "output": str(image_out),
        "values_clipped_for_integer_output": clipped,
    }


def register(app: typer.Typer) -> None:
    app.command("delta-e")(delta_e_cmd)
    app.command("white-balance")(white_balance_cmd)
