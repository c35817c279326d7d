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
import glob
import json
import os
import re
import shutil
import threading
import time
import uuid
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from imageform._files import glob_base, glob_paths, glob_regex, publish
from imageform.errors import ImageformError, InvalidInputError, UnknownOptionError
from imageform.workflows import Options, Workflow, flag_of, get_workflow

__all__ = [
    "MANIFEST",
    "BatchInterrupted",
    "BatchReport",
    "Job",
    "JobResult",
    "NoWorkersError",
    "batch_options",
    "batch_workflow",
    "plan_jobs",
    "print_summary",
    "run_batch",
    "run_job",
]

_WILDCARDS = re.compile(r"[*?\[]")
#: The manifest of a batch output folder: what produced each output.
MANIFEST = ".imageform-batch.json"
_MANIFEST_VERSION = 1


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
    values: dict[str, Any] = {}
    for k, v in dict(options or {}).items():
        name = by_flag.get(_key(k)) if isinstance(k, str) else None
        if name is None:
            valid = ", ".join(sorted(flag_of(f) for f in wf.options.fields()))
            if len(valid) > 90:
                valid = valid[:90].rsplit(", ", 1)[0] + f", ... (imageform {wf.name} --help)"
            raise UnknownOptionError(
                f"unknown option {describe(k)} of batch {wf.name}; valid: {valid}"
            )
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


# ---------------------------------------------------------------- planning


def temp_pattern(output: Path) -> str:
    """Return the glob of the temporary files that jobs writing ``output`` use."""
    return f".{glob.escape(output.name)}.*.tmp{glob.escape(output.suffix)}"


def _temp_path(output: Path, run_id: str | None = None) -> Path:
    token = uuid.uuid4().hex[:12]
    if run_id:
        token = f"{run_id}-{token}"
    return output.with_name(f".{output.name}.{token}.tmp{output.suffix}")


_RUN_ID = re.compile("[0-9a-f]{12}")
_LOCK = re.compile(r"\.imageform-batch\.([0-9a-f]{12})\.lock\Z")


@contextlib.contextmanager
def _run_lock(out_root: Path) -> Iterator[str]:
    """Return a run's id, holding a lock file ``.imageform-batch.<id>.lock`` in ``out_root``.

    The lock is held (``flock``) for as long as the run goes on: another run into the same folder
    then knows that the temporary files named with this id are being written, not left by a dead
    run. Without ``fcntl`` (Windows) the id alone, every temporary file counting as stale.
    """
    run_id = uuid.uuid4().hex[:12]
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        yield run_id
        return
    out_root.mkdir(parents=True, exist_ok=True)
    final = out_root / f".imageform-batch.{run_id}.lock"
    part = out_root / f".imageform-batch.{run_id}.lock-part"
    fd = os.open(part, os.O_CREAT | os.O_WRONLY, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        os.replace(part, final)  # visible only once held
        yield run_id
    finally:
        final.unlink(missing_ok=True)
        part.unlink(missing_ok=True)
        os.close(fd)


def _live_runs(out_root: Path, own: str | None) -> set[str]:
    """Return the ids of the other runs going on into ``out_root`` (their lock is held).

    The lock files of runs that died are removed.
    """
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        return set()
    live: set[str] = set()
    try:
        names = os.listdir(out_root)
    except OSError:
        return live
    for name in names:
        m = _LOCK.match(name)
        if m is None or m.group(1) == own:
            continue
        path = out_root / name
        try:
            fd = os.open(path, os.O_RDONLY)
        except OSError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            live.add(m.group(1))  # held: that run goes on
        else:
            path.unlink(missing_ok=True)  # its run died
        finally:
            os.close(fd)
    return live


def _temps_of(output: Path) -> Iterator[tuple[Path, str | None]]:
    """Yield each temporary file of ``output`` in its folder, with the run id in its name.

    That is ``.NAME.<run>-<token>.tmpSUFFIX`` (``.NAME.<token>.tmpSUFFIX`` without a run id, None),
    and the names older versions nested inside it (``..NAME.<run>-<token>.tmpSUFFIX.<pid>-...``,
    one leading dot per level) when a worker was killed while the workflow wrote.
    """
    match = re.compile(
        rf"\.+{re.escape(output.name)}\.(?:([0-9a-f]{{12}})-)?[0-9a-f]{{12}}\.tmp"
        rf"(?:{re.escape(output.suffix)})?(?:\..*)?"
    ).fullmatch
    try:
        names = os.listdir(output.parent)
    except OSError:
        return
    for name in names:
        m = match(name)
        if m is not None:
            yield output.parent / name, m.group(1)


def _remove_stale_temps(
    jobs: list[Job], out_root: Path | None = None, own: str | None = None
) -> int:
    """Remove the temporary files of ``jobs``' outputs that no live run is writing; return how many.

    A file is stale when no run going on into ``out_root`` is writing it (those of run ``own``, this
    one, included: what it left is from killed workers).
    """
    live = _live_runs(out_root, own) if out_root is not None else set()
    n = 0
    for job in jobs:
        for stale, run_id in _temps_of(job.output):
            if run_id in live:
                continue
            with contextlib.suppress(OSError):
                if stale.is_dir() and not stale.is_symlink():
                    shutil.rmtree(stale, ignore_errors=True)
                else:
                    stale.unlink(missing_ok=True)
                n += 1
    return n


def plan_jobs(pattern: str, out_dir: str | Path, *, out_suffix: str | None = None) -> list[Job]:
    """Return the jobs for the files matching ``pattern``, outputs under ``out_dir``.

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
    base = Path(os.path.abspath(glob_base(pattern)))
    inputs = sorted(Path(os.path.abspath(p)) for p in glob_paths(pattern) if os.path.isfile(p))
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


# ---------------------------------------------------------------- the manifest


def _read_manifest(out_root: Path) -> dict[str, Any]:
    path = out_root / MANIFEST
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    if not isinstance(data, dict) or data.get("version") != _MANIFEST_VERSION:
        return {}
    outputs = data.get("outputs")
    return outputs if isinstance(outputs, dict) else {}


def _write_manifest(out_root: Path, outputs: dict[str, Any]) -> None:
    from imageform._jsonio import write_json

    out_root.mkdir(parents=True, exist_ok=True)
    write_json(out_root / MANIFEST, {"version": _MANIFEST_VERSION, "outputs": outputs}, indent=1)


def _entry(job: Job, producer: dict[str, Any]) -> dict[str, Any] | None:
    try:
        return {**producer, "input": str(job.input), "input_stamp": _stamp(job.input)}
    except OSError:
        return None


# ---------------------------------------------------------------- one job (on a worker)


def _fsync(path: Path, *, directory: bool = False) -> None:
    fd = os.open(path, os.O_RDONLY | (os.O_DIRECTORY if directory else 0))
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _metrics(summary: Mapping[str, Any]) -> dict[str, Any]:
    from imageform._jsonio import json_ready

    small = {k: v for k, v in summary.items() if k not in ("input", "output")}
    out: dict[str, Any] = json_ready(small)
    return out


def run_job(
    command: str,
    in_path: str,
    out_path: str,
    options: Options | Mapping[str, Any] | None = None,
    hold_s: float = 0.0,
    run_id: str | None = None,
) -> dict[str, Any]:
    """Run ``command`` on one file and publish ``out_path`` atomically (runs on a worker).

    The workflow writes a temporary file in the output's folder; it is fsync-ed and renamed
    onto ``out_path`` (``os.replace``, atomic on POSIX), then the folder is fsync-ed. An
    exception removes the temporary file and comes back as ``{"ok": False, "error": ...}``.
    ``hold_s`` waits between writing and renaming (a test hook: it widens the window in
    which a killed worker leaves a partial file behind). ``run_id`` names the run in the
    temporary file's name, so that another run into the same folder leaves it alone while
    this run holds its lock.
    """
    from imageform._validate import as_path, as_real, describe
    from imageform.workflows import run_file

    out = as_path(out_path, "out_path")
    in_file = as_path(in_path, "in_path")
    hold_s = as_real(hold_s, "hold_s", minimum=0.0, maximum=3600.0)
    if run_id is not None and not (isinstance(run_id, str) and _RUN_ID.fullmatch(run_id)):
        raise InvalidInputError(f"expected run_id as 12 hex digits, got {describe(run_id)}")
    tmp = _temp_path(out, run_id)
    t0 = time.perf_counter()
    try:
        opts = batch_options(command, options)
        out.parent.mkdir(parents=True, exist_ok=True)
        result = run_file(batch_workflow(command).name, in_file, tmp, opts)
        if hold_s > 0:
            time.sleep(hold_s)
        _fsync(tmp)
        publish(tmp, out)  # never onto a FIFO or a device (imageform._files)
        _fsync(out.parent, directory=True)
    except Exception as exc:
        tmp.unlink(missing_ok=True)
        msg = str(exc).splitlines()[0] if str(exc) else ""
        return {"ok": False, "error": f"{type(exc).__name__}: {msg}".rstrip(": ")}
    return {"ok": True, "metrics": _metrics(result.summary), "seconds": time.perf_counter() - t0}


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
        See :func:`plan_jobs`.
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
    jobs = plan_jobs(pattern, out_dir, out_suffix=out_suffix)
    for suffix in sorted({j.output.suffix.lower() for j in jobs}):
        if suffix not in wf.suffixes:
            raise InvalidInputError(
                f"batch {wf.name} writes {', '.join(wf.suffixes)} files, got output suffix "
                f"{suffix!r}"
            )
        opts.check_output(Path("output" + suffix))
    for p in opts.paths("input"):
        if not p.is_file():
            raise InvalidInputError(f"{p} does not exist (an input file named by an option)")
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
    return BatchReport(wf.name, tuple(results[j] for j in jobs))


class _Manifest:
    """The manifest being updated as jobs finish (saved at most once a second)."""

    def __init__(self, root: Path, outputs: dict[str, Any], producer: dict[str, Any]) -> None:
        self.root, self.outputs, self.producer = root, outputs, producer
        self.saved_at = 0.0
        self.dirty = False

    def done(self, job: Job) -> None:
        entry = _entry(job, self.producer)
        if entry is not None:
            self.outputs[job.output.relative_to(self.root).as_posix()] = entry
            self.dirty = True
        if time.monotonic() - self.saved_at > 1.0:
            self.save()

    def save(self) -> None:
        if self.dirty:
            _write_manifest(self.root, self.outputs)
            self.dirty = False
        self.saved_at = time.monotonic()


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


def print_summary(report: BatchReport, console: Any = None) -> None:
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
