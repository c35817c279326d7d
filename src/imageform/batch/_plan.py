"""Batch planning: the commands, their options, the jobs and their results (internal).

:mod:`imageform.batch.runner` re-exports the public names.
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from imageform import _deprecate
from imageform._files import glob_base, glob_paths, glob_regex
from imageform.errors import ImageformError, InvalidInputError, UnknownOptionError
from imageform.workflows import Options, Workflow, flag_of, get_workflow

__all__ = [
    "BatchInterrupted",
    "BatchReport",
    "Job",
    "JobResult",
    "NoWorkersError",
    "batch_options",
    "batch_workflow",
    "plan_jobs",
]

_WILDCARDS = re.compile(r"[*?\[]")


class BatchInterrupted(KeyboardInterrupt):
    """Ctrl-C during a batch run; running the same command again resumes.

    ``done`` outputs are finished (and recorded in the manifest), ``remaining`` are not.
    """

    def __init__(self, done: int, remaining: int) -> None:
        super().__init__(done, remaining)
        self.done = done
        self.remaining = remaining

    def __str__(self) -> str:
        """Say how many outputs are done and remaining, and how to resume."""
        return (
            f"interrupted: {self.done} done, {self.remaining} remaining; run the same command "
            "again to resume"
        )


class NoWorkersError(ImageformError):
    """Every worker of the cluster is gone and none came back."""


@dataclass(frozen=True)
class Job:
    """One input file and the output it makes."""

    input: Path
    output: Path


@dataclass(frozen=True)
class JobResult:
    """What became of a job: ``status`` is ``"done"``, ``"skipped"`` or ``"failed"``."""

    input: Path
    output: Path
    status: str
    error: str | None = None
    metrics: dict[str, Any] = field(default_factory=dict)
    seconds: float = 0.0

    def __post_init__(self) -> None:
        """Check the paths, ``status``, ``error``, ``metrics`` and ``seconds``."""
        from imageform._validate import as_path, as_real, check_option, describe

        object.__setattr__(self, "input", as_path(self.input, "input"))
        object.__setattr__(self, "output", as_path(self.output, "output"))
        status = check_option(self.status, ("done", "skipped", "failed"), "status")
        object.__setattr__(self, "status", status)
        if self.error is not None and not isinstance(self.error, str):
            raise InvalidInputError(f"expected error as text or None, got {describe(self.error)}")
        if not isinstance(self.metrics, Mapping):
            raise InvalidInputError(f"expected metrics as a mapping, got {describe(self.metrics)}")
        object.__setattr__(self, "seconds", as_real(self.seconds, "seconds", nonnegative=True))


@dataclass(frozen=True)
class BatchReport:
    """The results of a batch run, one per planned file, in input order."""

    command: str
    results: tuple[JobResult, ...]

    def count(self, status: str) -> int:
        """How many jobs ended with ``status`` (done, skipped, failed)."""
        return sum(r.status == status for r in self.results)

    @property
    def failed(self) -> tuple[JobResult, ...]:
        """The failed jobs."""
        return tuple(r for r in self.results if r.status == "failed")

    @property
    def ok(self) -> bool:
        """True when no job failed."""
        return not self.failed

    def to_dict(self) -> dict[str, Any]:
        """Return a JSON-ready summary (what ``imageform batch --json`` prints)."""
        return {
            "command": self.command,
            "done": self.count("done"),
            "skipped": self.count("skipped"),
            "failed": self.count("failed"),
            "jobs": [
                {
                    "input": str(r.input),
                    "output": str(r.output),
                    "status": r.status,
                    "error": r.error,
                    "metrics": r.metrics,
                    "seconds": round(r.seconds, 4),
                }
                for r in self.results
            ],
        }


# ---------------------------------------------------------------- the commands and options


def batch_workflow(command: str | Workflow) -> Workflow:
    """Return the workflow ``command`` if it runs file by file in ``imageform batch``.

    Examples
    --------
    >>> batch_workflow("white_balance").name
    'white-balance'
    """
    from imageform._validate import describe
    from imageform.workflows import WORKFLOWS

    if not isinstance(command, str | Workflow):
        raise UnknownOptionError(
            f"expected command as a workflow (command) name, got {describe(command)}"
        )
    wf = command if isinstance(command, Workflow) else get_workflow(command)
    if not wf.batch:
        valid = ", ".join(n for n, w in WORKFLOWS.items() if w.batch)
        raise UnknownOptionError(f"{wf.name} does not run in imageform batch; valid: {valid}")
    return wf


def _key(name: str) -> str:
    return name.strip().lstrip("-").lower().replace("-", "_")


def batch_options(command: str | Workflow, options: Options | Mapping[str, Any] | None) -> Options:
    """Return the options of ``command`` from its dataclass, or from a mapping.

    The mapping's keys are field names or flags (``{"to": "lab"}``, ``{"--to": "lab"}`` and
    ``{"dst": "lab"}`` alike).

    Examples
    --------
    >>> batch_options("convert", {"to": "lab"}).dst
    'lab'
    """
    from imageform._validate import describe

    wf = batch_workflow(command)
    if isinstance(options, Options):
        if not isinstance(options, wf.options):
            raise InvalidInputError(
                f"expected {wf.options.__name__} for batch {wf.name}, got {type(options).__name__}"
            )
        _no_extra_outputs(wf, options)
        return options
    if options is not None and not isinstance(options, Mapping):
        raise InvalidInputError(
            f"expected options as {wf.options.__name__} or a mapping of option names to "
            f"values, got {describe(options)}"
        )
    by_flag = {_key(flag_of(f)): f.name for f in wf.options.fields()}
    by_flag.update({f.name: f.name for f in wf.options.fields()})
    renamed: dict[str, str] = getattr(wf.options, "__renamed_fields__", {})
    values: dict[str, Any] = {}
    for k, v in dict(options or {}).items():
        if isinstance(k, str) and _key(k) in renamed and _key(k) not in by_flag:
            new = renamed[_key(k)]  # an old name (issue 30), kept one release
            flag = next(flag_of(f) for f in wf.options.fields() if f.name == new)
            if any(by_flag.get(_key(o)) == new for o in options or {} if isinstance(o, str)):
                raise InvalidInputError(
                    f"batch {wf.name}: give {flag} ({new}) or the deprecated {k!r}, not both"
                )
            _deprecate.warn(f"batch {wf.name} option {k!r}", f"use {flag} ({new})")
            k = new
        name = by_flag.get(_key(k)) if isinstance(k, str) else None
        if name is None:
            valid = ", ".join(sorted(flag_of(f) for f in wf.options.fields()))
            head = f"unknown option {describe(k)} of batch {wf.name}; valid: "
            more = f", ... (imageform {wf.name} --help)"
            if len(head) + len(valid) > 200:  # one line of at most 200 characters
                valid = valid[: 200 - len(head) - len(more)].rsplit(", ", 1)[0] + more
            raise UnknownOptionError(head + valid)
        values[name] = v
    opts = wf.make_options(**values)
    _no_extra_outputs(wf, opts)
    return opts


def _no_extra_outputs(wf: Workflow, opts: Options) -> None:
    """Refuse an extra output (``--save-target``): one file per run, every job would write it."""
    for f in wf.options.fields():
        if f.metadata.get("output") and getattr(opts, f.name) is not None:
            raise InvalidInputError(
                f"batch {wf.name} does not take {flag_of(f)} (one file, written once: run "
                f"imageform {wf.name} on one input for it)"
            )


def _stamp(path: Path) -> list[Any]:
    st = path.stat()
    return [st.st_size, st.st_mtime_ns]


def _producer(wf: Workflow, opts: Options) -> dict[str, Any]:
    """Return what produces every output of a run, but the input file.

    That is the command and options (with the size and time of the files options name, such as
    ``--target``).
    """
    from imageform._jsonio import json_ready

    files = {str(p): _stamp(p) for p in opts.paths("input") if p.is_file()}
    return {"command": wf.name, "options": json_ready(opts), "option_files": files}


def _suffix_list(value: object, name: str) -> list[str]:
    """Return ``value``, a list or tuple of file suffixes (``'.png'``), lower-cased, or refuse."""
    from imageform._validate import describe

    kinds: list[str] = []
    if isinstance(value, (list, tuple)) and all(isinstance(v, str) for v in value):
        kinds = [str(v).lower() for v in value]
    if not kinds or not all(k.startswith(".") and len(k) > 1 for k in kinds):
        raise InvalidInputError(
            f"expected {name} as file suffixes such as ('.png', '.tif'), got {describe(value)}"
        )
    return kinds


def plan_jobs(
    pattern: str,
    out_dir: str | Path,
    *,
    out_suffix: str | None = None,
    writes: Sequence[str] | None = None,
    reads: Sequence[str] | None = None,
) -> list[Job]:
    """Return the jobs for the files matching ``pattern``, outputs under ``out_dir``.

    Parameters
    ----------
    pattern : str
        A glob; ``**`` matches any number of folders. Hidden files are not matched. An
        existing folder stands for its files (``folder/*``), those of the ``reads`` suffixes
        where given (a folder's notes or other kinds of file are not the command's inputs).
    out_dir : path
        Outputs go to ``out_dir / (input relative to the glob's fixed prefix)``.
    out_suffix : str, optional
        Replace each output's suffix (``".tif"``); by default the input's.
    writes : sequence of str, optional
        The suffixes the command writes (``".png"``, ...): without ``out_suffix``, an input
        of another suffix (a raw file, a WebP) gets the first of them.
    reads : sequence of str, optional
        The suffixes the command reads, any case (``imageform.io.IMAGE_FORMATS``' or
        ``imageform.io.RAW_SUFFIXES``): a folder's other files are left out.

    Returns
    -------
    list of Job
        Sorted by input path.

    Raises
    ------
    InvalidInputError
        No file matches; an output would be an input or match ``pattern`` (``out_dir``
        inside the input tree where the glob reaches, also through a symbolic link); two
        inputs would write one output.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> root = pathlib.Path(tempfile.mkdtemp())
    >>> (root / "in" / "a").mkdir(parents=True)
    >>> _ = (root / "in" / "a" / "x.png").write_bytes(b"")
    >>> [str(j.output.relative_to(root)) for j in plan_jobs(f"{root}/in/**/*.png", root / "out")]
    ['out/a/x.png']
    """
    from imageform._validate import as_path, describe

    if not isinstance(pattern, str) or not pattern.strip() or "\0" in pattern:
        raise InvalidInputError(f"expected pattern as a glob (text), got {describe(pattern)}")
    out_root = Path(os.path.abspath(as_path(out_dir, "out_dir")))
    if out_suffix is not None:
        if not isinstance(out_suffix, str) or not out_suffix.strip(". ") or "/" in out_suffix:
            raise InvalidInputError(
                f"expected out_suffix as a file suffix such as '.tif', got {describe(out_suffix)}"
            )
        if not out_suffix.startswith("."):
            out_suffix = "." + out_suffix
    folder = os.path.isdir(pattern) and not any(c in pattern for c in "*?[")
    if folder:
        pattern = os.path.join(pattern, "*")  # a folder: its files
    keep = None if reads is None else set(_suffix_list(reads, "reads"))
    kinds = None if writes is None else _suffix_list(writes, "writes")
    base = Path(os.path.abspath(glob_base(pattern)))
    inputs = sorted(Path(os.path.abspath(p)) for p in glob_paths(pattern) if os.path.isfile(p))
    if folder and keep is not None:
        inputs = [p for p in inputs if p.suffix.lower() in keep]
        if not inputs:
            shown = ", ".join(sorted(keep)[:12]) + (", ..." if len(keep) > 12 else "")
            raise InvalidInputError(f"no file of the kinds read ({shown}) in {pattern[:-2]!r}")
    if not inputs:
        raise InvalidInputError(f"no files match {pattern!r}")
    matcher = glob_regex(pattern)
    real_base = os.path.realpath(base)
    rest = os.path.relpath(os.path.abspath(pattern), base)
    real_matcher = glob_regex(os.path.join(real_base, rest))
    real_inputs = {os.path.realpath(p) for p in inputs}
    real_out_root = Path(os.path.realpath(out_root))
    jobs = []
    for p in inputs:
        rel = p.relative_to(base)
        out = out_root / rel
        real_out = real_out_root / rel
        if out_suffix is not None:
            out, real_out = out.with_suffix(out_suffix), real_out.with_suffix(out_suffix)
        elif kinds is not None and p.suffix.lower() not in kinds:
            out, real_out = out.with_suffix(kinds[0]), real_out.with_suffix(kinds[0])
        if (
            str(out) in {str(i) for i in inputs}
            or matcher.match(str(out))
            or str(real_out) in real_inputs
            or real_matcher.match(str(real_out))
        ):
            raise InvalidInputError(
                f"output {out} would overwrite an input or match the input glob {pattern!r}; "
                f"choose an output folder outside the inputs (got {out_dir})"
            )
        jobs.append(Job(p, out))
    seen: dict[Path, Path] = {}
    for job in jobs:
        if job.output in seen:
            raise InvalidInputError(
                f"inputs {seen[job.output]} and {job.input} would both write {job.output}; "
                "narrow the glob or keep the inputs' suffixes"
            )
        seen[job.output] = job.input
    return jobs
