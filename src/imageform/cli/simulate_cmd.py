"""``imageform simulate``: the built-in scene (or ``--scene FILE``) through the whole chain,
written as a self-contained report.html, metrics.json and every stage's image."""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import typer

__all__ = ["register"]


@contextmanager
def _progress_bar(enabled: bool) -> Iterator[Callable[[str, float], None] | None]:
    """A rich progress bar on stderr driven by ``progress(stage_name, fraction_done)``;
    ``None`` (no bar) when disabled."""
    if not enabled:
        yield None
        return
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    with Progress(
        TextColumn("{task.description:<22}"),
        BarColumn(),
        TextColumn("{task.percentage:>3.0f} %"),
        TimeElapsedColumn(),
        console=Console(stderr=True),
        transient=False,
    ) as bar:
        task = bar.add_task("simulating", total=1.0)

        def progress(stage_name: str, fraction_done: float) -> None:
            done = min(max(float(fraction_done), 0.0), 1.0)  # display only
            bar.update(task, completed=done, description=str(stage_name)[:22])

        yield progress
        bar.update(task, completed=1.0)


def simulate_command(
    scene: Path | None = typer.Option(
        None, "--scene", help="Scene description (TOML); default: the built-in scene."
    ),
    out: Path = typer.Option(
        Path("simulation"), "--out", "-o", help="Output folder for report.html and the rest."
    ),
    force: bool = typer.Option(False, "--force", help="Overwrite an existing report."),
    json_out: bool = typer.Option(False, "--json", help="Print machine-readable results."),
    seed: int = typer.Option(0, "--seed", help="Seed of the sensor noise."),
) -> None:
    """Render a scene through the whole image-formation chain and write an HTML report."""
    import importlib.util
    import time

    from imageform.cli._common import print_json
    from imageform.errors import InvalidInputError
    from imageform.report.html import write_report
    from imageform.simulate import default_scene, load_scene, simulate

    if importlib.util.find_spec("matplotlib") is None:  # the report's figures
        raise InvalidInputError(
            "imageform simulate draws its report with matplotlib, which is not installed: "
            "pip install 'imageform[plot]'"
        )
    for name in ("report.html", "metrics.json"):
        if (out / name).exists() and not force:
            raise InvalidInputError(f"output {out / name} exists; pass --force to overwrite it")
    if out.exists() and not out.is_dir():
        raise InvalidInputError(f"output {out} exists and is not a folder")
    if scene is not None and not scene.is_file():
        raise InvalidInputError(f"scene file {scene} does not exist")
    t0 = time.perf_counter()
    sc = load_scene(scene) if scene is not None else default_scene()
    show_bar = not json_out and sys.stderr.isatty()
    with _progress_bar(show_bar) as progress:
        result = simulate(sc, progress=progress, rng=seed)
        if progress is not None:
            progress("writing the report", 1.0)
        paths = write_report(result, out, force=force)
    wall = time.perf_counter() - t0
    s = paths.summary
    if json_out:
        print_json(
            {
                "scene": str(scene) if scene is not None else None,
                "scene_name": result.scene_name,
                "image_size": list(result.image_size),
                "report": str(paths.html),
                "metrics": str(paths.metrics),
                "stages": [str(p) for p in paths.stages],
                "raw_files": [str(p) for p in paths.raw_files],
                "summary": s,
                "report_seconds": paths.seconds,
                "wall_seconds": wall,
            }
        )
        return

    def num(v: object, fmt: str, unit: str = "") -> str:
        return "n/a" if v is None else f"{v:{fmt}}{unit}"

    w, h = result.image_size
    typer.echo(f"scene {result.scene_name!r}: {w}x{h} px, {len(result.stages)} stages")
    typer.echo(f"report  -> {paths.html}")
    typer.echo(f"metrics -> {paths.metrics}")
    typer.echo(
        f"mean ΔE00 {num(s['delta_e00_mean'], '.2f')} (max {num(s['delta_e00_max'], '.2f')}); "
        f"vanishing-point error {num(s['vanishing_point_error_px'], '.2f', ' px')}; "
        f"simulation {num(s['simulation_time_s'], '.1f', ' s')}, report {paths.seconds:.1f} s, "
        f"total {wall:.1f} s"
    )


def register(app: typer.Typer) -> None:
    app.command("simulate")(simulate_command)
