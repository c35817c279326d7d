"""Run one workflow over many files on a ``dask.distributed`` cluster.

- **One registry**: the commands are the workflows of :mod:`imageform.workflows` marked
  ``batch`` (one image in, one image out); their options are the same dataclasses, with the
  same defaults, as the single command's.
- **Plan**: the files matching a glob (``**`` recursive) map to ``OUT_DIR`` keeping their folder
  structure relative to the glob's fixed prefix; an output may take another suffix.
- **Resumable, keyed on what produced an output**: a manifest in the output folder
  (:data:`MANIFEST`) records for each output the command, its options and the input's size
  and modification time (and those of option files such as ``--target``). A re-run skips an
  output only when all of these are the same: a re-run with another ``--method`` recomputes.
  ``force=True`` redoes everything.
- **Atomic**: each job writes ``.NAME.<run>-<random>.tmpSUFFIX`` in the output's folder,
  fsyncs it and ``os.replace``-s it onto the final name; a worker killed mid-write leaves only
  a temporary file, never taken as finished and removed at the start and end of a run. A run
  holds a lock file ``.imageform-batch.<run>.lock`` in the output folder while it goes on, so
  that two runs into one folder keep each other's temporary files.
- **Globs end**: ``**`` enters each real folder once, also through symbolic links that loop.
- **Inputs never modified**: a plan in which an output is an input, or would match the input
  glob (a re-run would read outputs back as inputs), is refused, also when the output folder
  reaches the input tree through a symbolic link (real paths are compared).
- **Failures** are collected with their reason (``ExceptionType: message``); the other jobs
  still run. A job on a worker that dies is re-run elsewhere by the scheduler; when no worker
  is left for ``worker_timeout_s`` the run stops with a message (never hangs).
  The local cluster (no ``scheduler``) runs in a process of its own session
  (:mod:`imageform.batch._local`): nannies whose workers are killed as they start are replaced,
  and the run always ends it, with every worker.
- **Ctrl-C** (the first; a terminal's reaches the run alone, not the local workers) cancels the
  jobs, closes the cluster, keeps the manifest of the finished ones and raises
  :class:`BatchInterrupted` (done, remaining): the same command resumes.
"""

from __future__ import annotations

import contextlib
import os
import threading
import time
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

# the parts, in private modules; their public names are this module's
from imageform.batch import _plan
from imageform.batch._job import run_job
from imageform.batch._manifest import MANIFEST, _entry, _Manifest, _read_manifest
from imageform.batch._plan import (
    BatchInterrupted,
    BatchReport,
    Job,
    JobResult,
    NoWorkersError,
    _producer,
    batch_options,
    batch_workflow,
    plan_jobs,
)
from imageform.batch._temps import _live_runs, _remove_stale_temps, _run_lock
from imageform.errors import InvalidInputError
from imageform.workflows import Options

if TYPE_CHECKING:
    from rich.console import Console

# the plan's public names (the commands, the jobs, their results) are this module's too
__all__ = ["MANIFEST", "print_summary", "run_batch", "run_job"]
__all__ += _plan.__all__


# ---------------------------------------------------------------- the run (on the client)


def _wait_some(
    pending: set[Any], timeout: float, interrupted: threading.Event | None = None
) -> tuple[set[Any], set[Any]]:
    """Return ``(finished, still pending)`` once a future is done or ``timeout`` s have passed.

    Also as soon as ``interrupted`` is set.

    ``distributed.wait`` is not used: it looks up the default client, which the run's client is not.
    """
    deadline = time.monotonic() + timeout
    while True:
        finished = {f for f in pending if f.done()}
        if finished or time.monotonic() >= deadline or (interrupted and interrupted.is_set()):
            return finished, pending - finished
        time.sleep(0.02)


@contextlib.contextmanager
def _interrupt_flag() -> Iterator[threading.Event]:
    """Turn the first Ctrl-C (SIGINT) into a flag the run checks between jobs.

    The run then stops in order: it cancels its jobs and closes the cluster before
    :class:`BatchInterrupted` is raised. A second Ctrl-C interrupts at once. Outside the main
    thread (no signal handler can be set there) the flag is never set, and Ctrl-C raises
    ``KeyboardInterrupt`` where it lands.
    """
    import signal

    flag = threading.Event()
    if threading.current_thread() is not threading.main_thread():
        yield flag
        return

    def handler(signum: int, frame: Any) -> None:
        if flag.is_set():
            raise KeyboardInterrupt
        flag.set()

    old = signal.signal(signal.SIGINT, handler)
    try:
        yield flag
    finally:
        signal.signal(signal.SIGINT, old)


def _probe_scheduler(address: str) -> None:
    """Refuse, within dask's connect timeout, an address where no dask scheduler answers.

    ``distributed.Client`` waits for the scheduler's handshake without a time limit: at a
    server that never answers (a web server, the dashboard's port 8787 given for the
    scheduler's 8786) it hung for good, and bytes of another protocol read as a frame length
    asked for exabytes ("not enough memory") and left a traceback at exit. The probe is the
    same connection and handshake, bounded, in a thread of its own (a caller's running event
    loop, as in a notebook, is left alone).
    """
    import asyncio
    import concurrent.futures

    import dask
    from dask.utils import parse_timedelta
    from distributed.comm import connect

    limit = float(parse_timedelta(dask.config.get("distributed.comm.timeouts.connect"), "s"))

    async def handshake() -> None:
        comm = await connect(address, timeout=limit)
        await comm.close()

    def probe() -> None:
        asyncio.run(asyncio.wait_for(handshake(), limit + 1.0))

    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        try:
            pool.submit(probe).result()
        except TimeoutError:
            raise InvalidInputError(
                f"cannot reach the scheduler {address}: no dask scheduler answered within "
                f"{limit:g} s (a scheduler listens on tcp://host:8786 by default; 8787 is its "
                "dashboard)"
            ) from None
        except OSError as exc:
            raise InvalidInputError(f"cannot reach the scheduler {address}: {exc}") from None
        except Exception as exc:  # another protocol's bytes: not a dask scheduler
            raise InvalidInputError(
                f"cannot reach the scheduler {address}: what answers there is not a dask "
                f"scheduler ({type(exc).__name__})"
            ) from None


@contextlib.contextmanager
def _client(
    scheduler: str | None, n_workers: int, interrupted: threading.Event | None = None
) -> Iterator[Any]:
    """Yield the run's client, never dask's default scheduler.

    The run submits to it explicitly: default clients closed out of order (two runs in one process,
    in threads) leave dask's global ``scheduler`` setting naming a closed client, which breaks every
    later ``dask.compute`` in the process. Without ``scheduler``, a local cluster of ``n_workers``
    runs in a process of its own session (:mod:`imageform.batch._local`: a terminal's Ctrl-C does
    not reach its workers, killed workers are started again, and it always ends with the run).
    """
    from imageform._optional import require

    distributed = require("distributed", what="imageform batch")
    local = None
    if not scheduler:
        from imageform.batch import _local

        local = _local.start(n_workers, stop=None if interrupted is None else interrupted.is_set)
        scheduler = local.address
    try:
        try:
            # timeout: distributed.comm.timeouts.connect
            client = distributed.Client(scheduler, set_as_default=False)
        except (OSError, TimeoutError) as exc:
            raise InvalidInputError(f"cannot reach the scheduler {scheduler}: {exc}") from None
        with client:
            yield client
    finally:
        if local is not None:
            local.close()


def run_batch(
    command: str,
    pattern: str,
    out_dir: str | Path,
    options: Options | Mapping[str, Any] | None = None,
    *,
    scheduler: str | None = None,
    n_workers: int | None = None,
    force: bool = False,
    out_suffix: str | None = None,
    progress: bool = False,
    on_result: Callable[[JobResult], None] | None = None,
    hold_s: float = 0.0,
    worker_timeout_s: float = 60.0,
) -> BatchReport:
    """Run a workflow over the files matching ``pattern`` on a dask cluster.

    Parameters
    ----------
    command : str
        A workflow that runs file by file (``convert``, ``white-balance``, ``demosaic``,
        ``stain-normalize``, ``harmonize`` ...: :func:`batch_workflow`).
    pattern, out_dir, out_suffix :
        See :func:`plan_jobs` (``pattern`` may be a folder: its files). Without
        ``out_suffix``, an input whose suffix the command does not write (a raw file for
        ``develop``, a WebP) gets the command's first output suffix (``.png``).
    options : Options or mapping, optional
        The command's options (its dataclass, or ``{"to": "linear_srgb"}``: see
        :func:`batch_options`); the defaults are the single command's.
    scheduler : str, optional
        Address of a running scheduler (``tcp://host:port``); the workers must see the same
        paths. By default a ``LocalCluster`` of ``n_workers`` processes, one thread each, on
        127.0.0.1, started for the run and shut down after it.
    n_workers : int, optional
        Worker processes of the local cluster (default: CPU count, at most one per job).
    force : bool
        Redo every output (otherwise an output made by the same command, options and input
        is skipped: the run resumes).
    progress : bool
        Show a progress bar (rich, on stderr, when it is a terminal).
    on_result : callable, optional
        Called on the client with each :class:`JobResult` as it completes.
    hold_s : float
        Test hook, see :func:`run_job`.
    worker_timeout_s : float
        Stop with :class:`NoWorkersError` when the cluster has had no worker this long.

    Returns
    -------
    BatchReport
        One :class:`JobResult` per file; ``report.ok`` is False when a job failed.

    Raises
    ------
    BatchInterrupted
        Ctrl-C: the finished outputs are kept and recorded; the same call resumes.
    NoWorkersError
        No worker for ``worker_timeout_s`` seconds.
    """
    from imageform._validate import as_bool, as_int, as_real, describe

    if n_workers is not None:
        n_workers = as_int(n_workers, "n_workers", minimum=1, maximum=4096)
    worker_timeout_s = as_real(worker_timeout_s, "worker_timeout_s", positive=True)
    hold_s = as_real(hold_s, "hold_s", minimum=0.0, maximum=3600.0)
    force, progress = as_bool(force, "force"), as_bool(progress, "progress")
    if scheduler is not None and not (isinstance(scheduler, str) and scheduler.strip()):
        raise InvalidInputError(
            f"expected scheduler as an address (tcp://host:port), got {describe(scheduler)}"
        )
    if on_result is not None and not callable(on_result):
        raise InvalidInputError(f"expected on_result as a callable, got {describe(on_result)}")
    wf = batch_workflow(command)
    opts = batch_options(wf, options)
    from imageform.io import IMAGE_FORMATS

    # a folder stands for its files of the kinds the command's input reads
    reads = wf.inputs[0].suffixes or tuple(IMAGE_FORMATS)
    jobs = plan_jobs(pattern, out_dir, out_suffix=out_suffix, writes=wf.suffixes, reads=reads)
    for suffix in sorted({j.output.suffix.lower() for j in jobs}):
        if suffix not in wf.suffixes:
            raise InvalidInputError(
                f"batch {wf.name} writes {', '.join(wf.suffixes)} files, got output suffix "
                f"{suffix!r}"
            )
        opts.check_output(Path("output" + suffix))
    from imageform.workflows import flag_of

    for f in opts.fields():
        value = getattr(opts, f.name)
        if not f.metadata.get("input") or value is None:
            continue
        for p in map(Path, value if isinstance(value, (tuple, list)) else [value]):
            if not p.is_file():
                what = "is not a file" if p.exists() else "does not exist"
                raise InvalidInputError(f"{flag_of(f)} file {p} {what}")
    out_root = Path(os.path.abspath(out_dir))
    producer = _producer(wf, opts)
    manifest = _read_manifest(out_root)
    results: dict[Job, JobResult] = {}
    todo = []
    for job in jobs:
        rel = job.output.relative_to(out_root).as_posix()
        if not force and job.output.exists() and manifest.get(rel) == _entry(job, producer):
            results[job] = JobResult(job.input, job.output, "skipped")
        else:
            manifest.pop(rel, None)
            todo.append(job)
    if not todo:
        _remove_stale_temps(jobs, out_root)  # left by runs that died
    else:
        if scheduler is not None:
            _probe_scheduler(scheduler)  # before the output folder is made
        made = _new_folders(out_root, todo)  # what the run creates, to remove when left empty
        try:
            with _run_lock(out_root) as run_id:
                _remove_stale_temps(jobs, out_root, run_id)  # of runs that died, not running ones
                workers = n_workers or min(os.cpu_count() or 1, len(todo))
                state = _Manifest(out_root, manifest, producer)
                try:
                    with (
                        _interrupt_flag() as interrupted,
                        _client(scheduler, workers, interrupted) as client,
                    ):
                        _run_on(
                            client,
                            interrupted,
                            wf.name,
                            todo,
                            opts,
                            hold_s,
                            results,
                            progress,
                            on_result,
                            state,
                            worker_timeout_s,
                            run_id,
                        )
                except KeyboardInterrupt:
                    state.save()
                    done = sum(r.status != "failed" for r in results.values())
                    raise BatchInterrupted(done, len(jobs) - done) from None
                finally:
                    state.save()
                    _remove_stale_temps(todo, out_root, run_id)  # left by workers killed mid-write
        finally:
            _remove_empty(made, out_root)  # a failed job leaves no empty folder behind
    return BatchReport(wf.name, tuple(results[j] for j in jobs))


def _new_folders(out_root: Path, jobs: list[Job]) -> list[Path]:
    """Return the folders a run into ``out_root`` may create for ``jobs``, deepest first.

    Those that do not exist yet: ``out_root`` and the folders above it up to the first that
    exists, and each job's output folder up to ``out_root``.
    """
    new: set[Path] = set()
    for start, stop in [(out_root, None), *((j.output.parent, out_root) for j in jobs)]:
        folder = start
        while folder != stop and not folder.exists() and folder.parent != folder:
            new.add(folder)
            folder = folder.parent
    return sorted(new, key=lambda p: len(p.parts), reverse=True)


def _remove_empty(folders: list[Path], out_root: Path) -> None:
    """Remove those of ``folders`` (deepest first) that the run left empty.

    A job that failed leaves no new empty folder; a folder that existed before the run, or
    holds anything (an output, the manifest, another run's lock or temporary file), is kept.
    While another run goes on into ``out_root`` (its lock is held), nothing is removed: it
    may be about to write into a folder that is still empty.
    """
    if out_root.is_dir() and _live_runs(out_root, None):
        return
    for folder in folders:
        with contextlib.suppress(OSError):  # not empty, gone, or not ours to remove
            if folder.is_dir() and not folder.is_symlink():
                folder.rmdir()


def _run_on(
    client: Any,
    interrupted: threading.Event,
    name: str,
    todo: list[Job],
    opts: Options,
    hold_s: float,
    results: dict[Job, JobResult],
    progress: bool,
    on_result: Callable[[JobResult], None] | None,
    state: _Manifest,
    worker_timeout_s: float,
    run_id: str,
) -> None:
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeRemainingColumn

    by_key = {}
    futures = []
    for i, job in enumerate(todo):
        fut = client.submit(
            run_job,
            name,
            str(job.input),
            str(job.output),
            opts,
            hold_s,
            run_id,
            key=f"imageform-batch-{name}-{run_id}-{i}",
            pure=False,
        )
        by_key[fut.key] = job
        futures.append(fut)
    console = Console(stderr=True)
    bar = Progress(
        "[progress.description]{task.description}",
        BarColumn(),
        MofNCompleteColumn(),
        TimeRemainingColumn(),
        console=console,
        disable=not progress or not console.is_terminal,  # logs and pipes: no bar
    )
    pending = set(futures)
    no_worker_since: float | None = None
    try:
        with bar:
            task = bar.add_task(f"batch {name}", total=len(futures))
            while pending:
                finished, pending = _wait_some(pending, 1.0, interrupted)
                if not finished:
                    if interrupted.is_set():
                        raise KeyboardInterrupt
                    if client.scheduler_info().get("workers"):
                        no_worker_since = None
                    elif no_worker_since is None:
                        no_worker_since = time.monotonic()
                    elif time.monotonic() - no_worker_since > worker_timeout_s:
                        done = sum(r.status != "failed" for r in results.values())
                        raise NoWorkersError(
                            f"every dask worker is gone and none came back in "
                            f"{worker_timeout_s:g} s ({done} jobs done, {len(pending)} "
                            "remaining); start workers and run the same command to resume"
                        )
                    continue
                for fut in finished:
                    job = by_key[fut.key]
                    try:
                        # a bounded wait: the worker that holds a finished job's (small) result
                        # may be killed before it is fetched; the job then runs again
                        out = fut.result(timeout=10)
                    except TimeoutError:
                        pending.add(fut)
                        continue
                    except Exception as exc:  # the task itself died (e.g. KilledWorker)
                        out = {"ok": False, "error": f"{type(exc).__name__}: {exc}"}
                    if out["ok"]:
                        res = JobResult(
                            job.input, job.output, "done", None, out["metrics"], out["seconds"]
                        )
                        state.done(job)
                    else:
                        res = JobResult(job.input, job.output, "failed", out["error"])
                    results[job] = res
                    bar.advance(task)
                    if on_result is not None:
                        on_result(res)
                if interrupted.is_set() and pending:
                    raise KeyboardInterrupt
    finally:
        if pending:
            with contextlib.suppress(Exception):
                client.cancel(list(pending), force=True)


def print_summary(report: BatchReport, console: Console | None = None) -> None:
    """Print the counts and the failures (input and reason).

    A rich table on a terminal, one ``failed: INPUT: REASON`` line each otherwise.

    Examples
    --------
    >>> r = JobResult(Path("a.png"), Path("out/a.png"), "failed", "OSError: truncated")
    >>> print_summary(BatchReport("convert", (r,)))
    batch convert: 0 done, 0 skipped (already finished), 1 failed
    failed: a.png: OSError: truncated
    """
    from rich.console import Console
    from rich.table import Table

    if not isinstance(report, BatchReport):
        from imageform._validate import describe

        raise InvalidInputError(f"expected report as a BatchReport, got {describe(report)}")
    if console is not None and not (
        callable(getattr(console, "print", None)) and hasattr(console, "is_terminal")
    ):
        from imageform._validate import describe

        raise TypeError(f"expected console as a rich Console (or None), got {describe(console)}")
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
