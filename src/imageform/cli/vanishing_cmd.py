"""``imageform vanishing IMAGE --out overlay.png``: vanishing points, K and the horizon."""

from __future__ import annotations

from pathlib import Path

import typer

__all__ = ["register"]


def vanishing(
    image: Path = typer.Argument(..., help="A photograph (PNG, JPEG, TIFF)."),
    out: Path | None = typer.Option(None, "--out", "-o", help="Overlay PNG to write."),
    force: bool = typer.Option(False, "--force", help="Overwrite an existing output."),
    json_out: bool = typer.Option(False, "--json", help="Print machine-readable results."),
    seed: int = typer.Option(0, help="RANSAC seed."),
) -> None:
    """Find line segments, vanishing points, K and the horizon; draw them on the image."""
    import numpy as np

    from imageform.cli._common import check_output_path, print_json
    from imageform.errors import InvalidInputError
    from imageform.geometry import detect_vanishing_points

    if out is not None:
        check_output_path(out, inputs=(image,), force=force)
    try:
        from PIL import Image, UnidentifiedImageError

        with Image.open(image) as im:
            arr = np.asarray(im.convert("RGB") if im.mode not in ("L", "RGB") else im)
    except FileNotFoundError as exc:
        raise InvalidInputError(f"{image}: no such file") from exc
    except (UnidentifiedImageError, OSError) as exc:
        raise InvalidInputError(f"{image}: not a readable image ({exc})") from exc
    res = detect_vanishing_points(arr, seed=seed)
    payload = {
        "image": str(image),
        "segments": len(res.segments),
        "vanishing_points": res.vanishing_points,
        "support_px": res.scores,
        "vertical_index": res.vertical,
        "perspective": res.perspective,
        "K": res.K,
        "horizon": res.horizon,
    }
    if out is not None:
        from imageform.report.overlays import draw_vanishing_overlay

        draw_vanishing_overlay(arr, res).save(out)
        payload["overlay"] = str(out)
    if json_out:
        print_json(payload)
        return
    typer.echo(f"{len(res.segments)} line segments; {len(res.vanishing_points)} vanishing points")
    for j, v in enumerate(res.vanishing_points):
        tag = " (vertical)" if j == res.vertical else ""
        where = (
            f"({v[0]:.1f}, {v[1]:.1f})"
            if v[2] != 0
            else f"at infinity, direction ({v[0]:.3f}, {v[1]:.3f})"
        )
        typer.echo(f"  v{j}: {where}, support {res.scores[j]:.0f} px{tag}")
    typer.echo(f"perspective: {res.perspective}-point")
    if res.K is not None:
        k = res.K
        typer.echo(f"K: f = {k[0, 0]:.1f} px, principal point ({k[0, 2]:.1f}, {k[1, 2]:.1f})")
    if res.horizon is not None:
        a, b, c = res.horizon
        w = arr.shape[1]
        typer.echo(
            f"horizon: v = {-(c) / b:.1f} at u = 0, {-(a * (w - 1) + c) / b:.1f} at u = {w - 1}"
        )
    if out is not None:
        typer.echo(f"overlay -> {out}")


def register(app: typer.Typer) -> None:
    app.command("vanishing")(vanishing)
