"""Running a workflow: outputs checked first and written all or nothing.

Warnings are turned into one-line notes.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from imageform._files import Outputs, not_a_regular_file
from imageform.errors import InvalidInputError
from imageform.workflows._spec import (
    IMAGE_SUFFIXES,
    Options,
    Result,
    Run,
    Workflow,
    flag_of,
    resolve,
)

__all__ = ["execute", "run_file"]


def _as_paths(value: Any, name: str, *, required: bool = False) -> list[Path]:
    from imageform._validate import as_path

    if value is None and not required:
        return []
    if isinstance(value, (list, tuple)):
        return [as_path(v, f"{name}[{i}]") for i, v in enumerate(value)]
    return [as_path(value, name)]


def _expand_folders(paths: list[Path]) -> tuple[list[Path], set[Path]]:
    """``paths`` with each folder replaced by its images and each glob pattern by its matches.

    Returns the files and those of them a folder or a pattern stood for (not named one by
    one). A name that exists is taken literally (a file called ``scan[1].png``); a pattern
    that matches nothing is an error naming it.
    """
    from imageform._files import glob_paths
    from imageform.io import image_files

    out: list[Path] = []
    gathered: set[Path] = set()
    for p in paths:
        if p.is_dir():
            found = image_files(p)
        elif not p.exists() and any(c in str(p) for c in "*?["):
            found = [Path(h) for h in sorted(glob_paths(str(p)))]
            if not found:
                raise InvalidInputError(f"no files match {str(p)!r}")
        else:
            out.append(p)
            continue
        out += found
        gathered.update(found)
    return out, gathered


def _note_of(w: warnings.WarningMessage) -> str:
    text = str(w.message).strip().splitlines()
    return "warning: " + (text[0] if text else w.category.__name__)


def _check_data_suffix(wf: Workflow, out: Path) -> None:
    """Refuse a main output of a data file (camera file, table, JSON) under another kind's name.

    ``calibrate -o cam.json`` or ``emva -o e.png`` would write TOML or JSON there, ``gamut -o
    g.txt`` failed in matplotlib; ``undistort -o u.json`` was refused by the image writer only
    after the whole computation. Before anything is read; a folder output is left to
    :func:`_check_folder_name`.
    """
    from imageform._validate import describe

    if wf.output is not None and wf.output.folder:
        return
    if out.suffix.lower() in wf.suffixes:
        return
    if set(wf.suffixes) - set(IMAGE_SUFFIXES):
        kinds = " or ".join(wf.suffixes)
        raise InvalidInputError(
            f"{wf.name} writes a {kinds} file: give -o a {kinds} name, not {describe(out.name, 60)}"
        )
    kinds = ", ".join(wf.suffixes[:-1]) + f" or {wf.suffixes[-1]}"
    if out.suffix.lower() not in IMAGE_SUFFIXES:  # a format imageform reads, never writes?
        from imageform.errors import ImageformError
        from imageform.io import image_format

        try:
            fmt = image_format(out)
        except ImageformError:
            fmt = None
        if fmt is not None:
            name = {"heif": "HEIF", "webp": "WebP"}.get(fmt, fmt.upper())
            raise InvalidInputError(
                f"{wf.name} writes an image: imageform reads {name} but does not write it; "
                f"give -o a {kinds} name, not {describe(out.name, 60)}"
            )
    raise InvalidInputError(
        f"{wf.name} writes an image: give -o a {kinds} name, not {describe(out.name, 60)}"
    )


#: Names of files, never of the folder a folder output (simulate, reconstruct...) writes.
_FILE_SUFFIXES = frozenset(
    (*IMAGE_SUFFIXES, ".ply", ".csv", ".json", ".html", ".toml", ".dng", ".mp4", ".txt")
)


def _check_folder_name(wf: Workflow, out: Path) -> None:
    """Refuse ``reconstruct -o room.ply``: the command writes a folder, which would be named so."""
    if wf.output is None or not wf.output.folder or out.is_dir():
        return
    if out.suffix.lower() in _FILE_SUFFIXES:
        holds = f" ({wf.output.holds})" if wf.output.holds else ""
        raise InvalidInputError(
            f"{wf.name} writes a folder{holds}: give -o a folder name, not the file name "
            f"{out.name!r}"
        )


def execute(
    workflow: Workflow | str,
    *,
    options: Options | None = None,
    out: str | Path | None = None,
    force: bool = False,
    progress: Callable[[str, float], None] | None = None,
    **inputs: str | Path | Sequence[str | Path],
) -> Result:
    """Run ``workflow`` on files: check its outputs, compute, write them all or nothing.

    Parameters
    ----------
    workflow : Workflow or str
        The workflow or its command name (``"white-balance"``).
    options : Options, optional
        Its options (default: all defaults).
    out : path, optional
        The main output (``-o/--out``).
    force : bool
        Overwrite existing outputs.
    progress : callable, optional
        ``progress(stage, fraction_done)``.
    **inputs
        The positional inputs by name (a path, or a list of paths for ``many`` inputs).

    Returns
    -------
    Result
        The summary, the text for a person and the notes (warnings included).

    Raises
    ------
    InvalidInputError
        An output that is an input, exists without ``force``, is not a regular file, or whose
        folder is missing; a missing input; anything the workflow refuses.
    OSError
        Writing an output failed: an ``imageform._files.OutputWriteError`` naming the output
        (never a temporary name) when the error is about an output or the disk.
    """
    from imageform._validate import as_bool, as_path, describe
    from imageform.workflows.registry import get_workflow

    if not isinstance(workflow, str | Workflow):
        raise InvalidInputError(
            f"expected workflow as a Workflow or a command name, got {describe(workflow)}"
        )
    wf = get_workflow(workflow) if isinstance(workflow, str) else workflow
    if out is not None:
        out = as_path(out, "out (-o/--out)")
        _check_data_suffix(wf, Path(out))
        _check_folder_name(wf, Path(out))
    force = as_bool(force, "force")
    if progress is not None and not callable(progress):
        raise InvalidInputError(f"expected progress as a callable, got {describe(progress)}")
    opts = options if options is not None else wf.make_options()
    if not isinstance(opts, wf.options):
        raise InvalidInputError(
            f"expected options as {wf.options.__name__} for {wf.name}, got {type(opts).__name__}"
        )
    names = {i.name for i in wf.inputs}
    if set(inputs) != names:
        raise InvalidInputError(
            f"{wf.name} takes the input(s) {', '.join(sorted(names)) or 'none'}, "
            f"got {', '.join(sorted(inputs)) or 'none'}"
        )
    gathered: set[Path] = set()
    for i in wf.inputs:  # a folder stands for its images where the input says so
        if i.kind == "file" and i.folders and inputs.get(i.name) is not None:
            inputs[i.name], found = _expand_folders(_as_paths(inputs[i.name], i.name))
            gathered |= found
    files = [i.name for i in wf.inputs if i.kind == "file"]
    named = [("input", p) for n in files for p in _as_paths(inputs[n], n, required=True)]
    for f in opts.fields():
        if f.metadata.get("input"):
            named += [(flag_of(f), p) for p in _as_paths(getattr(opts, f.name), flag_of(f))]
    for what, p in named:  # before any work starts (a FIFO is never opened: it would block)
        kind = not_a_regular_file(p)
        if kind is not None:
            expected = "; expected a file" if kind == "is a folder" else ""
            raise InvalidInputError(f"{what} {p} {kind}{expected}")
        if not p.exists():
            raise InvalidInputError(f"{what} file {p} does not exist")
    in_paths = [p for _, p in named]
    if wf.output is not None and out is None:
        if wf.output.default is None and wf.output.required:
            raise InvalidInputError(f"{wf.name} needs an output: -o/--out")
        out = wf.output.default
    _refuse_shared_outputs(out, opts)
    outputs = Outputs(inputs=in_paths, force=force)
    try:
        with outputs:
            run = Run(outputs, progress=progress, gathered=frozenset(gathered))
            if out is not None:  # checked before any work starts
                (run.folder if wf.output is not None and wf.output.folder else run.file)(out)
            folders = {
                Path(v)
                for f in opts.fields()
                if f.metadata.get("folder") and (v := getattr(opts, f.name)) is not None
            }
            for extra in opts.paths("output"):  # a folder option (simulate --lab) is one
                (run.folder if extra in folders else run.file)(extra)
            if out is not None and not (wf.output is not None and wf.output.folder):
                opts.check_output(Path(out))  # what these options cannot write, before any work
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("ignore", DeprecationWarning)
                warnings.simplefilter("ignore", PendingDeprecationWarning)
                warnings.simplefilter("always", UserWarning)
                warnings.simplefilter("always", RuntimeWarning)
                # numba's low-occupancy note on a small image's grid (a UserWarning) is no
                # news for a pointwise kernel whose size is the caller's image
                warnings.filterwarnings("ignore", message=r"Grid size \d+ will likely")
                function = resolve(wf.function)
                result: Result = function(
                    run, opts, out=None if out is None else Path(out), **inputs
                )
    except OSError as exc:  # a full disk, no permission: name the user's output
        explained = outputs.explain(exc)
        if explained is None:
            raise
        raise explained from exc
    notes = tuple(run.notes) + tuple(dict.fromkeys(_note_of(w) for w in caught))
    return replace(result, notes=result.notes + notes)


def _refuse_shared_outputs(out: str | Path | None, opts: Options) -> None:
    """Refuse two outputs that name one path (``-o u.png --camera-out u.png``), before any work.

    Each output is written under a temporary name and renamed at the end: two of them on one
    path would leave only the last one written, silently.
    """
    import os

    claimed = [("-o/--out", Path(out))] if out is not None else []
    for f in opts.fields():
        if f.metadata.get("output"):
            claimed += [(flag_of(f), p) for p in _as_paths(getattr(opts, f.name), flag_of(f))]
    seen: dict[str, str] = {}
    for flag, p in claimed:
        key = os.path.normcase(os.path.abspath(p))
        if key in seen:
            raise InvalidInputError(
                f"{seen[key]} and {flag} both name {p}: give each output its own path"
            )
        seen[key] = flag


def run_file(name: str, input_path: Path, output_path: Path, options: Options) -> Result:
    """One file through a workflow marked ``batch`` (what ``imageform batch`` runs per job).

    The output is overwritten (the batch runner decides what to redo) and written
    atomically.
    """
    from imageform.workflows.registry import get_workflow

    wf = get_workflow(name)
    if not wf.batch:
        raise InvalidInputError(f"{name} does not run file by file in imageform batch")
    inputs: dict[str, Any] = {wf.inputs[0].name: input_path}
    return execute(wf, options=options, out=output_path, force=True, **inputs)
