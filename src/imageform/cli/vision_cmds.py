"""``imageform cvd``, ``imageform gamut`` and ``imageform palette-check``: colour vision."""

from __future__ import annotations

from pathlib import Path

import typer

__all__ = ["register"]


def cvd_cmd(
    image: Path = typer.Argument(..., help="Input image (sRGB PNG/JPEG/TIFF)."),
    output: Path = typer.Argument(..., help="Output image (same formats)."),
    deficiency: str = typer.Option(
        ..., "--type", help="protan, deutan or tritan (also protanopia, deuteranomaly ...)."
    ),
    severity: float = typer.Option(1.0, help="0 (normal) to 1 (dichromat)."),
    method: str = typer.Option("machado2009", help="machado2009, brettel1997 or vienot1999."),
    force: bool = typer.Option(False, "--force", help="Overwrite an existing output."),
    json_out: bool = typer.Option(False, "--json", help="Print machine-readable results."),
) -> None:
    """Simulate colour-vision deficiency on an sRGB image (in linear RGB)."""
    import numpy as np

    from imageform.cli._common import check_output_path, print_json
    from imageform.cli.color_analysis_cmds import _read_rgb, _write_rgb
    from imageform.color.cvd import simulate_cvd

    check_output_path(output, inputs=(image,), force=force)
    arr = _read_rgb(image)
    sim = simulate_cvd(arr, deficiency, severity, method)
    out = np.asarray(sim, dtype=np.float64)
    outside = int(np.count_nonzero((out < 0) | (out > 1)))
    clipped = _write_rgb(output, out, sixteen=arr.dtype == np.uint16)
    result = {
        "input": str(image),
        "output": str(output),
        "deficiency": deficiency,
        "severity": severity,
        "method": method,
        "values_outside_0_1": outside,
        "clipped_on_write": clipped,
    }
    if json_out:
        print_json(result)
    else:
        typer.echo(
            f"wrote {output} ({method}, {deficiency}, severity {severity:g}); "
            f"{outside} values outside [0, 1]"
            + (f", {clipped} clipped on write" if clipped else "")
        )


def gamut_cmd(
    spaces: str = typer.Option(
        "srgb,display-p3,rec2020", help="Comma-separated RGB spaces (srgb, adobe-rgb, ...)."
    ),
    plot: Path | None = typer.Option(None, "--plot", help="Write the chromaticity diagram."),
    coords: str = typer.Option("xy", help="Diagram for the plot: xy or uv (u'v')."),
    force: bool = typer.Option(False, "--force", help="Overwrite an existing plot."),
    json_out: bool = typer.Option(False, "--json", help="Print machine-readable results."),
) -> None:
    """Gamut areas and coverage of the visible region (xy and u'v'); optional diagram."""
    from imageform.cli._common import check_output_path, print_json
    from imageform.color.chromaticity import visible_area
    from imageform.color.gamut import gamut_figures

    names = [s.strip() for s in spaces.split(",") if s.strip()]
    if plot is not None:
        check_output_path(plot, force=force)
    figs = gamut_figures(names)
    if json_out:
        print_json(
            {
                "visible_area_xy": visible_area("xy"),
                "visible_area_uv": visible_area("uv"),
                "spaces": [f.as_dict() for f in figs],
            }
        )
    else:
        typer.echo(
            f"visible region (380-780 nm locus): area xy {visible_area('xy'):.4f}, "
            f"u'v' {visible_area('uv'):.4f}"
        )
        typer.echo(f"{'space':<22}{'area xy':>9}{'cover xy':>10}{'area uv':>9}{'cover uv':>10}")
        for f in figs:
            typer.echo(
                f"{f.space:<22}{f.area_xy:>9.4f}{f.coverage_xy:>9.1f}%"
                f"{f.area_uv:>9.4f}{f.coverage_uv:>9.1f}%"
            )
    if plot is not None:
        import matplotlib

        matplotlib.use("Agg")
        from imageform.report.chromaticity_plot import plot_chromaticity_diagram

        plot_chromaticity_diagram(names, coords=coords, path=plot)
        if not json_out:
            typer.echo(f"wrote {plot}")


def palette_check_cmd(
    colors: str = typer.Argument(..., help='Comma-separated hex colours, "#E69F00,#56B4E9".'),
    threshold: float = typer.Option(10.0, help="Smallest acceptable ΔE00."),
    method: str = typer.Option("machado2009", help="CVD model."),
    json_out: bool = typer.Option(False, "--json", help="Print machine-readable results."),
) -> None:
    """Smallest pairwise ΔE00 of a palette, normal and for protan/deutan/tritan observers."""
    from imageform.cli._common import print_json
    from imageform.color.palettes import palette_check

    r = palette_check(colors, threshold=threshold, method=method)
    if json_out:
        print_json(r.as_dict())
        return
    typer.echo(f"{len(r.colors)} colours, threshold ΔE00 {r.threshold:g} ({method})")
    for cond, v in r.min_delta_e.items():
        i, j = r.closest_pair[cond]
        verdict = "pass" if r.passes[cond] else "FAIL"
        typer.echo(f"  {cond:<7} min ΔE00 {v:6.2f}  (colours {i} and {j})  {verdict}")


def register(app: typer.Typer) -> None:
    app.command("cvd")(cvd_cmd)
    app.command("gamut")(gamut_cmd)
    app.command("palette-check")(palette_check_cmd)
