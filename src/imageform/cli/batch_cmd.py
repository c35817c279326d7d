"""``imageform batch`` (many files on a dask cluster) and ``imageform chunked`` (one image
larger than memory, block by block)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

__all__ = ["register"]


def batch_cmd(
    command: Annotated[
        str, typer.Argument(help="convert, white-balance, demosaic, stain-normalize, harmonize.")
    ],
    pattern: Annotated[str, typer.Argument(help="Input glob, quoted ('in/**/*.png').")],
    out_dir: Annotated[Path, typer.Argument(help="Output folder (keeps the input folders).")],
    scheduler: str = typer.Option(
        "", "--scheduler", help="Address of a running dask scheduler (tcp://host:port)."
    ),
    workers: int = typer.Option(0, "--workers", help="Local cluster worker processes."),
    suffix: str = typer.Option("", "--suffix", help="Output suffix (.png, .tif, .npy)."),
    src: str | None = typer.Option(None, "--from", help="convert: space of the inputs."),
    dst: str | None = typer.Option(None, "--to", help="convert: space of the outputs."),
    white: str | None = typer.Option(None, "--white", help="convert: reference white."),
    method: str | None = typer.Option(
        None, "--method", help="white-balance / demosaic / stain-normalize method."
    ),
    pattern_cfa: str | None = typer.Option(None, "--pattern", help="demosaic: RGGB, ..."),
    normalize: str | None = typer.Option(None, "--normalize", help="white-balance: mean/green."),
    percentile: float | None = typer.Option(None, "--percentile", help="white-patch percentile."),
    p: float | None = typer.Option(None, "--p", help="shades-of-gray: Minkowski p."),
    sigma: float | None = typer.Option(None, "--sigma", help="gray-edge: Gaussian scale."),
    illuminant: str | None = typer.Option(None, "--illuminant", help="manual: e.g. A, D50."),
    cct: float | None = typer.Option(None, "--cct", help="manual: temperature in kelvin."),
    target: str | None = typer.Option(None, "--target", help="stain-normalize: image or .json."),
    correction: str | None = typer.Option(None, "--correction", help="harmonize: corr.json."),
    bits: int | None = typer.Option(None, "--bits", help="PNG output bits (8 or 16)."),
    clip: bool | None = typer.Option(None, "--clip", help="Clip values outside [0, 1]."),
    force: bool = typer.Option(False, "--force", help="Redo outputs that exist."),
    json_out: bool = typer.Option(False, "--json", help="Print a machine-readable summary."),
) -> None:
    """Run a command over many files on a dask cluster (resumable; atomic outputs).

    A local cluster of worker processes by default, a running one with --scheduler. Outputs
    that exist are skipped (a re-run resumes); failures are listed with their reason and
    the exit code is 1.
    """
    from rich.console import Console

    from imageform.batch import print_summary, run_batch
    from imageform.cli._common import print_json

    given = {
        "from": src,
        "to": dst,
        "white": white,
        "method": method,
        "pattern": pattern_cfa,
        "normalize": normalize,
        "percentile": percentile,
        "p": p,
        "sigma": sigma,
        "illuminant": illuminant,
        "cct": cct,
        "target": target,
        "correction": correction,
        "bits": bits,
        "clip": clip,
    }
    options = {k: v for k, v in given.items() if v is not None}
    report = run_batch(
        command,
        pattern,
        out_dir,
        options,
        scheduler=scheduler or None,
        n_workers=workers or None,
        force=force,
        out_suffix=suffix or None,
        progress=not json_out,
    )
    if json_out:
        print_json(report.to_dict())
    else:
        print_summary(report, Console(highlight=False))
    if not report.ok:
        raise typer.Exit(1)


def chunked_cmd(
    command: Annotated[str, typer.Argument(help="convert or white-balance.")],
    input: Annotated[Path, typer.Argument(help="Tiled TIFF or .zarr array (H, W, 3).")],
    output: Annotated[Path, typer.Argument(help="Output: tiled .tif or .zarr.")],
    src: str | None = typer.Option(None, "--from", help="convert: space of the input."),
    dst: str | None = typer.Option(None, "--to", help="convert: space of the output."),
    white: str | None = typer.Option(None, "--white", help="convert: reference white."),
    method: str | None = typer.Option(
        None, "--method", help="white-balance: gray-world, shades-of-gray or manual."
    ),
    p: float | None = typer.Option(None, "--p", help="shades-of-gray: Minkowski p."),
    normalize: str | None = typer.Option(None, "--normalize", help="white-balance: mean/green."),
    illuminant: str | None = typer.Option(None, "--illuminant", help="manual: e.g. A, D50."),
    cct: float | None = typer.Option(None, "--cct", help="manual: temperature in kelvin."),
    chunk: int = typer.Option(1024, "--chunk", help="Block size in pixels."),
    tile: int = typer.Option(256, "--tile", help="Output TIFF tile size."),
    dtype: str | None = typer.Option(None, "--dtype", help="uint8, uint16 or float32."),
    force: bool = typer.Option(False, "--force", help="Overwrite an existing output."),
    json_out: bool = typer.Option(False, "--json", help="Print a machine-readable summary."),
) -> None:
    """Process one image larger than memory block by block (bounded memory)."""
    from imageform.batch import process_chunked
    from imageform.cli._common import print_json

    given: dict[str, Any] = {
        "from": src,
        "to": dst,
        "white": white,
        "method": method,
        "p": p,
        "normalize": normalize,
        "illuminant": illuminant,
        "cct": cct,
    }
    r = process_chunked(
        input,
        output,
        command,
        {k: v for k, v in given.items() if v is not None},
        chunk=chunk,
        tile=tile,
        dtype=dtype,
        force=force,
    )
    info = {
        "input": str(input),
        "output": str(r.output),
        "shape": list(r.shape),
        "dtype": r.dtype,
        "chunk": r.chunk,
        "clipped_values": r.clipped,
        "gains": r.gains,
        "seconds": round(r.seconds, 3),
    }
    if json_out:
        print_json(info)
        return
    h, w = r.shape[:2]
    note = f", {r.clipped} values clipped to [0, 1]" if r.clipped else ""
    typer.echo(f"wrote {r.output} ({w}x{h} {r.dtype}, {r.seconds:.1f} s{note})")


def register(app: typer.Typer) -> None:
    app.command("batch")(batch_cmd)
    app.command("chunked")(chunked_cmd)
