"""The local dask cluster of ``imageform batch``, in a process of its own session.

``python -m imageform.batch._local N [SCRATCH]`` starts a ``LocalCluster`` with ``N`` worker
processes (one thread each, on 127.0.0.1), prints its scheduler's address on one line, then
keeps it going until its standard input closes (the run ended, or the process that started it
died), and closes it. Its workers' scratch folder is SCRATCH, a temporary folder :func:`start`
makes and :meth:`LocalProcessCluster.close` removes (dask's default, ``dask-scratch-space`` in
the temporary folder, was left behind by every run).

Why a process of its own, started in a new session (:func:`start`):

- a terminal's Ctrl-C signals the whole foreground process group: the workers, in another
  session, never see it (no worker tracebacks, no semaphores leaked by half-started workers);
  the run alone stops, in order, and closes the cluster;
- the run can always end the cluster and every worker at once (``killpg`` of that session),
  also when a storm of killed workers left the nannies in a state in which closing hangs;
- a nanny that gave up (its worker killed as it started) is replaced: the cluster is scaled
  back to ``N`` workers every few seconds while it has fewer.

Its standard error goes nowhere (:data:`subprocess.DEVNULL`): what the workers print about
being killed is not the run's output; jobs report their own errors.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import selectors
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from typing import IO, Any

from imageform.errors import ImageformError

__all__ = ["LocalProcessCluster", "main", "start"]


class LocalProcessCluster:
    """A cluster process started by :func:`start`: its scheduler ``address``, and ``close``."""

    def __init__(self, proc: subprocess.Popen[str], address: str, scratch: str = "") -> None:
        self.proc, self.address, self.scratch = proc, address, scratch

    def close(self, timeout: float = 30.0) -> None:
        """Close the cluster (its standard input), then kill its whole session after ``timeout``."""
        with contextlib.suppress(OSError):
            if self.proc.stdin is not None:
                self.proc.stdin.close()
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.proc.wait(timeout=timeout)
        with contextlib.suppress(OSError):  # workers the cluster could not close (a storm)
            if hasattr(os, "killpg"):
                os.killpg(self.proc.pid, signal.SIGKILL)
            else:  # pragma: no cover - not POSIX
                self.proc.kill()
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.proc.wait(timeout=10)
        if self.scratch:
            shutil.rmtree(self.scratch, ignore_errors=True)


def start(
    n_workers: int, timeout: float = 120.0, stop: Callable[[], bool] | None = None
) -> LocalProcessCluster:
    """Start the cluster process (a new session) and return it once its scheduler listens.

    Raises :class:`~imageform.errors.ImageformError` when it does not start in ``timeout`` s,
    and ``KeyboardInterrupt`` (the process ended) as soon as ``stop()`` is true (Ctrl-C).
    """
    env = dict(os.environ)
    scratch = tempfile.mkdtemp(prefix="imageform-batch-")
    env["DASK_TEMPORARY_DIRECTORY"] = scratch  # the scheduler's and nannies' lock files too
    src = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    env["PYTHONPATH"] = os.pathsep.join(p for p in (src, env.get("PYTHONPATH")) if p)
    proc = subprocess.Popen(
        [sys.executable, "-m", "imageform.batch._local", str(int(n_workers)), scratch],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
        env=env,
        start_new_session=True,
    )
    try:
        address = _read_line(proc, timeout, stop)
    except KeyboardInterrupt:
        LocalProcessCluster(proc, "", scratch).close(timeout=0)  # nothing to keep: end it now
        raise
    if not address.startswith("tcp://"):
        LocalProcessCluster(proc, "", scratch).close(timeout=5)
        raise ImageformError(
            f"the local dask cluster did not start in {timeout:g} s"
            + (f" (exit {proc.returncode})" if proc.poll() is not None else "")
        )
    return LocalProcessCluster(proc, address, scratch)


def _read_line(proc: subprocess.Popen[str], timeout: float, stop: Callable[[], bool] | None) -> str:
    assert proc.stdout is not None
    sel = selectors.DefaultSelector()
    sel.register(proc.stdout, selectors.EVENT_READ)
    deadline = time.monotonic() + timeout
    try:
        while not sel.select(0.1):
            if stop is not None and stop():
                raise KeyboardInterrupt
            if time.monotonic() > deadline or proc.poll() is not None:
                return ""
        return proc.stdout.readline().strip()
    finally:
        sel.close()


#: A nanny with no worker registered this long (its worker killed as it started, the restart
#: failed or hangs) is dropped, its worker process killed, and another nanny started.
_GRACE_S = 20.0


async def _mend(cluster: Any, n_workers: int, since: dict[str, float]) -> None:
    """Replace the nannies that have had no worker for :data:`_GRACE_S` (in the cluster's loop)."""
    now = time.monotonic()
    registered = {ws.name for ws in cluster.scheduler.workers.values()}
    for name, nanny in list(cluster.workers.items()):
        if name in registered:
            since.pop(name, None)
            continue
        if now - since.setdefault(name, now) < _GRACE_S:
            continue
        del cluster.workers[name]
        cluster.worker_spec.pop(name, None)
        since.pop(name, None)
        pid = getattr(nanny, "pid", None)
        if pid:
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)
        task = asyncio.ensure_future(nanny.close(timeout=5, reason="imageform-batch-replaced"))
        task.add_done_callback(lambda t: t.cancelled() or t.exception())
    for name in list(since):
        if name not in cluster.workers:
            since.pop(name)
    if len(cluster.worker_spec) < n_workers or len(cluster.workers) < n_workers:
        cluster.scale(n_workers)


def _serve(n_workers: int, stdin: IO[str], out: IO[str], scratch: str | None = None) -> None:
    import distributed

    cluster = distributed.LocalCluster(
        n_workers=0,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        # ":0", not None: with None the scheduler's HTTP server still binds :8787, and two
        # clusters (two runs, pytest-xdist) collide on it
        dashboard_address=":0",
        silence_logs=logging.CRITICAL,
        preload=["imageform.batch._worker_setup"],
        death_timeout=60,  # a nanny whose worker never connects gives up, never waits forever
        local_directory=scratch,  # None: dask's own (dask-scratch-space, never removed)
    )
    try:
        cluster.scale(n_workers)
        out.write(cluster.scheduler_address + "\n")
        out.flush()
        sel = selectors.DefaultSelector()
        sel.register(stdin, selectors.EVENT_READ)
        since: dict[str, float] = {}
        while not sel.select(2.0):  # readable: closed (EOF), the run is over
            with contextlib.suppress(Exception):
                cluster.sync(_mend, cluster, n_workers, since, callback_timeout=30)
    finally:
        with contextlib.suppress(Exception):
            cluster.close(timeout=20)


def main(argv: list[str] | None = None) -> int:
    """Run the cluster until standard input closes (``python -m imageform.batch._local N``)."""
    args = sys.argv[1:] if argv is None else argv
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # only the run ends it
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
    with contextlib.suppress(SystemExit):
        _serve(int(args[0]), sys.stdin, sys.stdout, args[1] if len(args) > 1 else None)
    return 0


if __name__ == "__main__":
    sys.exit(main())
