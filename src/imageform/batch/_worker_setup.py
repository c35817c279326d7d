"""Preloaded in the worker processes of the local cluster ``imageform batch`` starts.

Ctrl-C in a terminal signals the whole process group: the client stops the run (one line,
exit 130) and closes the cluster, which ends its workers. The workers themselves ignore
SIGINT, so none of them prints a traceback of its own.
"""

from __future__ import annotations

import contextlib
import signal
from typing import Any


def dask_setup(worker: Any) -> None:
    """Ignore SIGINT in this worker process (called by distributed on preload)."""
    with contextlib.suppress(ValueError):  # not the main thread: nothing to do
        signal.signal(signal.SIGINT, signal.SIG_IGN)
