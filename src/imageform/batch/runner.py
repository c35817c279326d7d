"""Run one command over many files on a ``dask.distributed`` cluster.

- **Plan**: the files matching a glob (``**`` recursive) map to ``OUT_DIR`` keeping their folder
  structure relative to the glob's fixed prefix; an output may take another suffix.
- **Resumable**: an output that exists is finished (outputs appear only by an atomic rename),
  so a re-run skips it; ``force=True`` redoes everything.
- **Atomic**: each job writes ``.NAME.<random>.tmpSUFFIX`` in the output's folder, fsyncs it
  and ``os.replace``-s it onto the final name; a worker killed mid-write leaves only a
  temporary file, never taken as finished and removed at the start and end of a run.
- **Inputs never modified**: a plan in which an output is an input, or would match the input
  glob (a re-run would read outputs back as inputs), is refused.
- **Failures** are collected with their reason (``ExceptionType: message``); the other jobs
  still run. A job on a worker that dies is re-run elsewhere by the scheduler.
"""

from __future__ import annotations

import contextlib
import glob
import os
import re
import time
import uuid
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from imageform.batch.commands import get_command
from imageform.errors import InvalidInputError

__all__ = [
    "BatchReport",
    "Job",
    "JobResult",
    "plan_jobs",
    "print_summary",
    "run_batch",
    "run_job",
]

_WILDCARDS = re.compile(r"[*?\[]")


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
        """A JSON-ready summary (what ``imageform batch --json`` prints)."""
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


# ---------------------------------------------------------------- planning


def _glob_base(pattern: str) -> Path:
    """The fixed folder prefix of ``pattern`` (the part before the first wildcard)."""
    parts = Path(pattern).parts
    fixed: list[str] = []
    for part in parts[:-1]:
        if _WILDCARDS.search(part):
            break
        fixed.append(part)
    return Path(*fixed) if fixed else Path(".")


def _glob_regex(pattern: str) -> re.Pattern[str]:
    """A regex for absolute paths that ``glob.glob(pattern, recursive=True)`` would match."""
    pat = os.path.abspath(pattern)
    out, i = "", 0
    while i < len(pat):
        if pat.startswith("**/", i):
            out, i = out + "(?:.*/)?", i + 3
        elif pat.startswith("**", i):
            out, i = out + ".*", i + 2
        elif pat[i] == "*":
            out, i = out + "[^/]*", i + 1
        elif pat[i] == "?":
            out, i = out + "[^/]", i + 1
        elif pat[i] == "[" and "]" in pat[i + 1 :]:
            j = pat.index("]", i + 1)
            body = pat[i + 1 : j]
            out, i = out + "[" + ("^" + body[1:] if body.startswith("!") else body) + "]", j + 1
        else:
            out, i = out + re.escape(pat[i]), i + 1
    return re.compile(out + r"\Z")


def temp_pattern(output: Path) -> str:
    """The glob of the temporary files that jobs writing ``output`` use."""
    return f".{glob.escape(output.name)}.*.tmp{glob.escape(output.suffix)}"


def _temp_path(output: Path) -> Path:
    return output.with_name(f".{output.name}.{uuid.uuid4().hex[:12]}.tmp{output.suffix}")


def _remove_stale_temps(jobs: list[Job]) -> int:
    n = 0
    for job in jobs:
        if job.output.parent.is_dir():
            for stale in job.output.parent.glob(temp_pattern(job.output)):
                stale.unlink(missing_ok=True)
                n += 1
    return n


def plan_jobs(pattern: str, out_dir: str | Path, *, out_suffix: str | None = None) -> list[Job]:
    """The jobs for the files matching ``pattern``, outputs under ``out_dir``.

    Parameters
    ----------
    pattern : str
        A glob; ``**`` matches any number of folders. Hidden files are not matched.
    out_dir : path
        Outputs go to ``out_dir / (input relative to the glob's fixed prefix)``.
    out_suffix : str, optional
        Replace each output's suffix (``".tif"``); by default the input's.

    Returns
    -------
    list of Job
        Sorted by input path.

    Raises
    ------
    InvalidInputError
        No file matches; an output would be an input or match ``pattern`` (``out_dir``
        inside the input tree where the glob reaches); two inputs would write one output.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> root = pathlib.Path(tempfile.mkdtemp())
    >>> (root / "in" / "a").mkdir(parents=True)
    >>> _ = (root / "in" / "a" / "x.png").write_bytes(b"")
    >>> [str(j.output.relative_to(root)) for j in plan_jobs(f"{root}/in/**/*.png", root / "out")]
    ['out/a/x.png']
    """
    if out_suffix is not None and not out_suffix.startswith("."):
        out_suffix = "." + out_suffix
    base = Path(os.path.abspath(_glob_base(pattern)))
    out_root = Path(os.path.abspath(out_dir))
    inputs = sorted(
        Path(os.path.abspath(p)) for p in glob.glob(pattern, recursive=True) if os.path.isfile(p)
    )
    if not inputs:
        raise InvalidInputError(f"no files match {pattern!r}")
    matcher = _glob_regex(pattern)
    input_set = set(inputs)
    jobs = []
    for p in inputs:
        out = out_root / p.relative_to(base)
        if out_suffix is not None:
            out = out.with_suffix(out_suffix)
        if out in input_set or matcher.match(str(out)):
            raise InvalidInputError(
                f"output {out} would overwrite an input or match the input glob {pattern!r}; "
                f"choose an OUT_DIR outside the inputs (got {out_dir})"
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


# ---------------------------------------------------------------- one job (on a worker)


def _fsync(path: Path, *, directory: bool = False) -> None:
    fd = os.open(path, os.O_RDONLY | (os.O_DIRECTORY if directory else 0))
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def run_job(
    command: str,
    in_path: str,
    out_path: str,
    options: Mapping[str, Any],
    hold_s: float = 0.0,
) -> dict[str, Any]:
    """Run ``command`` on one file and publish ``out_path`` atomically (runs on a worker).

    The command writes a temporary file in the output's folder; it is fsync-ed and renamed
    onto ``out_path`` (``os.replace``, atomic on POSIX), then the folder is fsync-ed. An
    exception removes the temporary file and comes back as ``{"ok": False, "error": ...}``.
    ``hold_s`` waits between writing and renaming (a test hook: it widens the window in
    which a killed worker leaves a partial file behind).
    """
    out = Path(out_path)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = _temp_path(out)
    t0 = time.perf_counter()
    try:
        metrics = get_command(command).run(Path(in_path), tmp, options)
        if hold_s > 0:
            time.sleep(hold_s)
        _fsync(tmp)
        os.replace(tmp, out)
        _fsync(out.parent, directory=True)
    except Exception as exc:
        tmp.unlink(missing_ok=True)
        msg = str(exc).splitlines()[0] if str(exc) else ""
        return {"ok": False, "error": f"{type(exc).__name__}: {msg}".rstrip(": ")}
    return {"ok": True, "metrics": metrics, "seconds": time.perf_counter() - t0}


# ---------------------------------------------------------------- the run (on the client)


@contextlib.contextmanager
def _client(scheduler: str | None, n_workers: int) -> Iterator[Any]:
    import logging

    from distributed import Client, LocalCluster

    if scheduler:
        try:
            client = Client(scheduler)  # timeout: distributed.comm.timeouts.connect
        except (OSError, TimeoutError) as exc:
            raise InvalidInputError(f"cannot reach the scheduler {scheduler}: {exc}") from exc
        with client:
            yield client
        return
    cluster = LocalCluster(
        n_workers=n_workers,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        # ":0", not None: with None the scheduler's HTTP server still binds :8787, and two
        # clusters (two runs, pytest-xdist) collide on it
        dashboard_address=":0",
        silence_logs=logging.ERROR,
    )
    with cluster, Client(cluster) as client:
        yield client


def run_batch(
    command: str,
    pattern: str,
    out_dir: str | Path,
    options: Mapping[str, Any] | None = None,
    *,
    scheduler: str | None = None,
    n_workers: int | None = None,
    force: bool = False,
    out_suffix: str | None = None,
    progress: bool = False,
    on_result: Callable[[JobResult], None] | None = None,
    hold_s: float = 0.0,
) -> BatchReport:
    """Run a batch command over the files matching ``pattern`` on a dask cluster.

    Parameters
    ----------
    command : str
        A name in :data:`imageform.batch.COMMANDS` (convert, white-balance, demosaic,
        stain-normalize, harmonize).
    pattern, out_dir, out_suffix :
        See :func:`plan_jobs`.
    options : mapping, optional
        The command's options (``{"to": "linear_srgb"}``); unknown names are refused.
    scheduler : str, optional
        Address of a running scheduler (``tcp://host:port``); the workers must see the same
        paths. By default a ``LocalCluster`` of ``n_workers`` processes, one thread each, on
        127.0.0.1, started for the run and shut down after it.
    n_workers : int, optional
        Worker processes of the local cluster (default: CPU count, at most one per job).
    force : bool
        Redo outputs that exist (otherwise they are skipped: the run resumes).
    progress : bool
        Show a progress bar (rich, on stderr).
    on_result : callable, optional
        Called on the client with each :class:`JobResult` as it completes.
    hold_s : float
        Test hook, see :func:`run_job`.

    Returns
    -------
    BatchReport
        One :class:`JobResult` per file; ``report.ok`` is False when a job failed.

    Examples
    --------
    A re-run where every output exists skips them all (and starts no cluster):

    >>> import tempfile, pathlib, numpy as np
    >>> from imageform.io import write_image
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> for sub in ("in", "out"):
    ...     (d / sub).mkdir()
    ...     _ = write_image(d / sub / "x.png", np.zeros((2, 2, 3), np.uint8))
    >>> report = run_batch("convert", f"{d}/in/*.png", d / "out", {"to": "linear_srgb"})
    >>> report.count("skipped"), report.ok
    (1, True)
    """
    cmd = get_command(command)
    key = cmd.name.replace("-", "_")
    opts = dict(options or {})
    jobs = plan_jobs(pattern, out_dir, out_suffix=out_suffix)
    for suffix in sorted({j.output.suffix for j in jobs}):
        cmd.validate(opts, suffix)
    _remove_stale_temps(jobs)
    results: dict[Job, JobResult] = {}
    todo = []
    for job in jobs:
        if job.output.exists() and not force:
            results[job] = JobResult(job.input, job.output, "skipped")
        else:
            todo.append(job)
    if todo:
        workers = n_workers or min(os.cpu_count() or 1, len(todo))
        try:
            with _client(scheduler, workers) as client:
                _run_on(client, key, todo, opts, hold_s, results, progress, on_result)
        finally:
            _remove_stale_temps(todo)  # left by workers killed mid-write
    return BatchReport(cmd.name, tuple(results[j] for j in jobs))


def _run_on(
    client: Any,
    key: str,
    todo: list[Job],
    opts: dict[str, Any],
    hold_s: float,
    results: dict[Job, JobResult],
    progress: bool,
    on_result: Callable[[JobResult], None] | None,
) -> None:
    from distributed import as_completed
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeRemainingColumn

    run_id = uuid.uuid4().hex[:8]
    by_key = {}
    futures = []
    for i, job in enumerate(todo):
        fut = client.submit(
            run_job,
            key,
            str(job.input),
            str(job.output),
            opts,
            hold_s,
            key=f"imageform-batch-{key}-{run_id}-{i}",
            pure=False,
        )
        by_key[fut.key] = job
        futures.append(fut)
    bar = Progress(
        "[progress.description]{task.description}",
        BarColumn(),
        MofNCompleteColumn(),
        TimeRemainingColumn(),
        console=Console(stderr=True),
        disable=not progress,
    )
    with bar:
        task = bar.add_task(f"batch {key.replace('_', '-')}", total=len(futures))
        for fut in as_completed(futures):
            job = by_key[fut.key]
            try:
                out = fut.result()
            except Exception as exc:  # the task itself died (e.g. KilledWorker)
                out = {"ok": False, "error": f"{type(exc).__name__}: {exc}"}
            if out["ok"]:
                res = JobResult(job.input, job.output, "done", None, out["metrics"], out["seconds"])
            else:
                res = JobResult(job.input, job.output, "failed", out["error"])
            results[job] = res
            bar.advance(task)
            if on_result is not None:
                on_result(res)


def print_summary(report: BatchReport, console: Any = None) -> None:
    """Print the counts and the failures (input and reason): a rich table on a terminal,
    one ``failed: INPUT: REASON`` line each otherwise.

    >>> r = JobResult(Path("a.png"), Path("out/a.png"), "failed", "OSError: truncated")
    >>> print_summary(BatchReport("convert", (r,)))
    batch convert: 0 done, 0 skipped (already finished), 1 failed
    failed: a.png: OSError: truncated
    """
    from rich.console import Console
    from rich.table import Table

    console = console or Console()
    console.print(
        f"batch {report.command}: {report.count('done')} done, "
        f"{report.count('skipped')} skipped (already finished), {report.count('failed')} failed"
    )
    if report.failed and not console.is_terminal:  # logs and pipes: one line per failure
        for r in report.failed:
            console.print(f"failed: {r.input}: {r.error}", soft_wrap=True)
    elif report.failed:
        table = Table(title="failures", show_lines=False)
        table.add_column("input", overflow="fold")
        table.add_column("reason", overflow="fold")
        for r in report.failed:
            table.add_row(str(r.input), r.error or "")
        console.print(table)
