"""One loopback dask cluster for the batch tests (two worker processes, one thread each).

Session-scoped: under pytest-xdist each test process starts its own. Teardown checks that
the worker processes are gone (no leaked processes).
"""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Iterator
from typing import Any

import pytest


@pytest.fixture(scope="session")
def cluster() -> Iterator[Any]:
    """``LocalCluster(n_workers=2, threads_per_worker=1, processes=True)`` on 127.0.0.1."""
    distributed = pytest.importorskip("distributed")
    psutil = pytest.importorskip("psutil")
    c = distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address=":0",  # None still binds :8787 (clashes under xdist)
        silence_logs=logging.ERROR,
    )
    try:
        yield c
    finally:
        with distributed.Client(c) as client:
            pids = list(client.run(os.getpid).values())
        c.close()
        deadline = time.monotonic() + 15
        while any(psutil.pid_exists(p) for p in pids) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not any(psutil.pid_exists(p) for p in pids), "leaked dask worker processes"


@pytest.fixture
def client(cluster: Any) -> Iterator[Any]:
    """A client of the shared cluster, waiting until both workers are up."""
    import distributed

    with distributed.Client(cluster) as c:
        c.wait_for_workers(2, timeout=60)
        yield c
