"""``imageform batch COMMAND`` and ``imageform chunked COMMAND``.

Thin adapters generated from the workflow registry.

Each subcommand takes the workflow's own options (the same flags, names and defaults as the
single command) plus what scaling out needs: ``batch`` a glob of inputs, an output folder
``-o/--out``, ``--scheduler``, ``--workers``, ``--suffix``; ``chunked`` one input, ``-o/--out``,
``--chunk``, ``--tile``, ``--dtype``.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import click

from imageform._files import refuse_special, refuse_special_inside
from imageform.cli._build import (
    CommandExit,
    _choices_text,
    _naming_files,
    option_params,
    take_old_flags,
)
from imageform.errors import ImageformError
from imageform.workflows import Workflow, normalize_choice
from imageform.workflows.color import CHUNKED_CHOICES, CHUNKED_HELP, CHUNKED_OPTIONS

__all__ = ["batch_group", "chunked_group"]

_CHUNKED = ("convert", "white-balance", "stain-normalize")


def _batch_workflows() -> dict[str, Workflow]:
    from imageform.workflows.registry import WORKFLOWS

    return {n: w for n, w in WORKFLOWS.items() if w.batch}


def _extra_outputs(wf: Workflow) -> set[str]:
    return {f.name for f in wf.options.fields() if f.metadata.get("output")}


def _options(wf: Workflow, kw: dict[str, Any]) -> Any:
    try:
        return wf.make_options(**take_old_flags(wf, kw))
    except ImageformError as exc:
        raise click.UsageError(str(exc)) from None


def _refuse_absent_device(opts: Any) -> None:
    """``--device cuda`` where no GPU is usable: one line, exit 1, before any job starts."""
    if getattr(opts, "device", None) != "cuda":
        return
    from imageform._cuda.geometry import require_cuda

    try:
        require_cuda("--device cuda")
    except ImageformError as exc:
        click.echo(f"imageform: error: {exc}", err=True)
        raise CommandExit(1) from None


def _quiet_dask() -> None:
    """Silence dask's own warnings in this process.

    Such as ``Couldn't gather 1 keys, rescheduling`` after a worker is killed: jobs report
    their errors, the run its summary.
    """
    import contextlib
    import logging

    with contextlib.suppress(ImportError):  # without it, run_batch says what to install
        import distributed  # noqa: F401  (its loggers are configured on import)
    for name in list(logging.root.manager.loggerDict):
        if name == "distributed" or name.startswith("distributed."):
            logging.getLogger(name).setLevel(logging.ERROR)


def _batch_command(wf: Workflow) -> click.Command:
    params: list[click.Parameter] = [
        click.Argument(["glob_pattern"], metavar="'GLOB'", required=True),
        click.Option(
            ["-o", "--out", "out"],
            type=click.Path(path_type=Path, file_okay=False),
            required=True,
            help="Output folder (keeps the inputs' folders relative to the glob's fixed part).",
        ),
        # an extra output (--save-target, --overlay) is one file per run, not per input
        *[p for p in option_params(wf) if p.name not in _extra_outputs(wf)],
        click.Option(
            ["--scheduler"], default=None, help="Address of a running dask scheduler (tcp://...)."
        ),
        click.Option(
            ["--workers"],
            type=click.IntRange(1, 4096),
            default=None,
            help="Worker processes of a local cluster (default: one per CPU, at most one per "
            "file).",
        ),
        click.Option(
            ["--suffix"],
            default=None,
            help="Output suffix (.png, .tif, .npy); default the input's, or .png where the "
            "command does not write the input's kind.",
        ),
        click.Option(["--force"], is_flag=True, help="Redo outputs that are up to date."),
        click.Option(["--json", "json_out"], is_flag=True, help="Print the summary as JSON."),
    ]

    def callback(**kw: Any) -> None:
        from imageform._jsonio import dumps
        from imageform.batch import BatchInterrupted, print_summary, run_batch

        pattern, out = kw.pop("glob_pattern"), kw.pop("out")
        scheduler, workers, suffix = kw.pop("scheduler"), kw.pop("workers"), kw.pop("suffix")
        force, as_json = bool(kw.pop("force")), bool(kw.pop("json_out"))
        opts = _options(wf, kw)
        _refuse_absent_device(opts)
        if Path(out).is_dir():  # no job replaces a FIFO or a device (the runner renames over)
            refuse_special_inside(out)
        _quiet_dask()
        try:
            report = run_batch(
                wf.name,
                pattern,
                out,
                opts,
                scheduler=scheduler,
                n_workers=workers,
                force=force,
                out_suffix=suffix,
                progress=not as_json,
            )
        except BatchInterrupted as exc:
            click.echo(f"imageform: {exc}", err=True)
            raise CommandExit(130) from None
        if as_json:
            click.echo(dumps(report.to_dict()))
        else:
            from rich.console import Console

            print_summary(report, Console(highlight=False))
        if not report.ok:
            raise CommandExit(1)

    return click.Command(
        wf.name,
        params=params,
        callback=callback,
        help=f"{wf.summary}\n\nOver every file matching GLOB (quote it; a folder: its files), on "
        "a dask cluster. An input of a kind the command does not write (a raw file, a WebP) "
        "gets a .png output unless --suffix says otherwise.",
        short_help=wf.summary,
        no_args_is_help=True,
    )


def _narrowed(wf: Workflow, param: click.Parameter, choices: tuple[str, ...]) -> click.Parameter:
    """Return an option of the single command that ``chunked`` takes with fewer choices.

    ``--help`` lists only ``choices``; another name is a usage error naming those, also one
    that the single command takes (``--method pca``: not streamed, rather than unknown).
    """
    from imageform.workflows import choice_names

    (field,) = [f for f in wf.options.fields() if f.name == param.name]
    every = choice_names(field.metadata["choices"])
    flag = max(param.opts, key=len)

    def check(ctx: click.Context, p: click.Parameter, value: str | None) -> str | None:
        if value is None:
            return None
        try:
            return normalize_choice(value, choices, flag)
        except ImageformError as exc:
            if value.strip().lower().replace("-", "_") not in every:
                raise click.UsageError(str(exc)) from None
        listed = ", ".join(c.replace("_", "-") for c in choices)
        raise click.UsageError(
            f"{flag} {value} needs the whole image in memory (imageform {wf.name} takes it); "
            f"chunked processing streams {listed}"
        )

    assert isinstance(param, click.Option)
    param.metavar = _choices_text(choices).strip()
    param.callback = check
    return param


def _reworded(param: click.Parameter, words: Mapping[str, str]) -> click.Parameter:
    """Return ``param`` with the help ``chunked`` gives it, where its narrower choices differ."""
    if isinstance(param, click.Option) and param.name in words:
        param.help = words[param.name]
    return param


def _chunked_command(wf: Workflow) -> click.Command:
    narrow: Mapping[str, tuple[str, ...]] = CHUNKED_CHOICES.get(wf.name.replace("-", "_"), {})
    words: Mapping[str, str] = CHUNKED_HELP.get(wf.name.replace("-", "_"), {})
    params: list[click.Parameter] = [
        click.Argument(["image"], type=click.Path(path_type=Path), metavar="IMAGE"),
        click.Option(
            ["-o", "--out", "out"],
            type=click.Path(path_type=Path),
            required=True,
            help="Output: a tiled .tif or a .zarr array.",
        ),
        # only what chunked honours (--alpha, --max-pixels ... were listed and ignored)
        *[
            _reworded(_narrowed(wf, p, narrow[p.name]) if p.name in narrow else p, words)
            for p in option_params(wf)
            if p.name in CHUNKED_OPTIONS[wf.name.replace("-", "_")]
        ],
        click.Option(
            ["--chunk"],
            type=click.IntRange(1, 16384),
            default=1024,
            show_default=True,
            help="Block size in pixels (a multiple of --tile).",
        ),
        click.Option(
            ["--tile"],
            type=click.IntRange(16),
            default=None,
            help="Tile size of a TIFF output, a multiple of 16 dividing --chunk (default: the "
            "input's tiles, else 256).",
        ),
        click.Option(
            ["--pyramid"],
            type=click.Choice(["auto", "none", "build"]),
            default="auto",
            show_default=True,
            help="TIFF output levels: auto writes a pyramidal input's levels back (each the "
            "box mean of the processed level above), none level 0 only, build also halves a "
            "flat input.",
        ),
        click.Option(
            ["--compression"],
            type=click.Choice(["none", "zlib", "lzw", "zstd", "jpeg"]),
            default=None,
            help="TIFF output compression (default: the input's when writable; JPEG for "
            "uint8 only).",
        ),
        click.Option(
            ["--dtype"],
            type=click.Choice(["uint8", "uint16", "float32"]),
            default=None,
            help="Output samples (default: the input's integer type; float32 for float input "
            "or a space outside [0, 1]); integer output clips, with a note.",
        ),
        click.Option(["--force"], is_flag=True, help="Overwrite an existing output."),
        click.Option(["--json", "json_out"], is_flag=True, help="Print the result as JSON."),
    ]
    if wf.name.replace("-", "_") == "stain_normalize":
        params.insert(
            -2,
            click.Option(
                ["--stats-from", "stats_from"],
                type=click.Choice(["auto", "level", "subsample"]),
                default="auto",
                show_default=True,
                help="Where the slide's own stain statistics are measured: a reduced pyramid "
                "level of at most 4 Mpx (level; auto when the input is a pyramid) or every "
                "s-th pixel of level 0 (subsample).",
            ),
        )

    def callback(**kw: Any) -> None:
        from imageform._jsonio import dumps
        from imageform.batch import process_chunked

        image, out = kw.pop("image"), kw.pop("out")
        chunk, tile, dtype = kw.pop("chunk"), kw.pop("tile"), kw.pop("dtype")
        force, as_json = bool(kw.pop("force")), bool(kw.pop("json_out"))
        extra = {k: kw.pop(k) for k in ("pyramid", "compression", "stats_from") if k in kw}
        opts = _options(wf, kw)
        # a FIFO, a device or a folder named like the output is never replaced
        refuse_special(out, folder=Path(out).suffix.lower() == ".zarr")
        with _naming_files({"image": image}):
            r = process_chunked(
                image,
                out,
                wf.name,
                opts,
                chunk=chunk,
                tile=tile,
                dtype=dtype,
                force=force,
                **extra,
            )
        info = {
            "input": image,
            "output": r.output,
            "shape": list(r.shape),
            "dtype": r.dtype,
            "chunk": r.chunk,
            "values_clipped": r.clipped,
            "gains": r.gains,
            "levels": [list(v) for v in r.levels],
            "compression": r.compression,
            "stats_from": r.stats_from,
            "seconds": round(r.seconds, 3),
        }
        if as_json:
            click.echo(dumps(info))
        else:
            h, w = r.shape[:2]
            pyr = f", {len(r.levels)} levels" if len(r.levels) > 1 else ""
            click.echo(f"wrote {r.output} ({w} x {h} {r.dtype}{pyr}, {r.seconds:.1f} s)")
        if r.clipped:
            click.echo(
                f"imageform: note: {r.clipped} values outside [0, 1] were clipped to fit "
                f"{r.dtype}; --dtype float32 keeps them",
                err=True,
            )

    return click.Command(
        wf.name,
        params=params,
        callback=callback,
        help=f"{wf.summary}\n\nOne image larger than memory (a TIFF or a .zarr array), block "
        "by block, with bounded memory.",
        short_help=wf.summary,
        no_args_is_help=True,
    )


class _Lazy(click.Group):
    """A group whose subcommands are built from the registry on first use."""

    def __init__(self, name: str, make: Any, names: Any, **kw: Any) -> None:
        super().__init__(name, **kw)
        self._make, self._names = make, names

    def list_commands(self, ctx: click.Context) -> list[str]:
        return list(self._names())

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        from imageform.workflows.registry import WORKFLOWS

        key = cmd_name.replace("_", "-")
        if key not in self._names():
            return None
        return self._make(WORKFLOWS[key])

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        """List the subcommands from the registry's summaries, without building them.

        A command's options may name choices in a module that loads NumPy; ``--help`` stays
        light (tests/test_lazy_import.py).
        """
        from imageform.workflows.registry import WORKFLOWS

        rows = [(name, WORKFLOWS[name].summary) for name in self.list_commands(ctx)]
        if rows:
            with formatter.section("Commands"):
                formatter.write_dl(rows)


def batch_group() -> click.Group:
    """``imageform batch``: one subcommand per workflow that runs file by file."""
    return _Lazy(
        "batch",
        _batch_command,
        lambda: tuple(_batch_workflows()),
        help="Run a command over many files on a dask cluster: imageform batch COMMAND "
        "'GLOB' -o OUT_DIR [options of COMMAND]. Resumable (a manifest, "
        ".imageform-batch.json, records the command, options and input behind each output: "
        "a re-run with other options recomputes), atomic outputs, failures listed with their "
        "reason (exit 1); Ctrl-C says what is done and exits 130.",
        short_help="Run a command over many files on a dask cluster (resumable).",
        no_args_is_help=True,
    )


def chunked_group() -> click.Group:
    """Return the ``imageform chunked`` group: process one image larger than memory.

    Its commands convert, white-balance or stain-normalise the image block by block.
    """
    return _Lazy(
        "chunked",
        _chunked_command,
        lambda: _CHUNKED,
        help="Process one image larger than memory block by block (bounded memory): "
        "imageform chunked COMMAND IMAGE -o OUT [options of COMMAND].",
        short_help="Process one image larger than memory block by block (bounded memory).",
        no_args_is_help=True,
    )
