"""The demosaicing kernels' tests once more with NUMBA_BOUNDSCHECK=1 (issue 16).

A numba kernel that reads outside its array returns garbage (or crashes) without a word;
with bounds checking it raises IndexError. The kernels' tests (each kernel against its
NumPy twin, and demosaic() on odd and tiny sizes, where the mirror padding is tightest)
run in a subprocess where every ``njit`` compiles with ``boundscheck=True``. To keep the
run short the kernels compile there without ``parallel`` and ``cache`` (``prange`` is then
``range``: the same indices, read in order) into a fresh process; the subprocess first
proves that an out-of-bounds read does raise.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("numba")

ROOT = Path(__file__).resolve().parents[2]

SCRIPT = """
import sys
import numba
_njit = numba.njit
def njit(*args, **kwargs):
    kwargs.update(parallel=False, cache=False, boundscheck=True)
    return _njit(*args, **kwargs)
numba.njit = njit
import numpy as np
@numba.njit
def _oob(a):
    return a[5]
try:
    _oob(np.zeros(2))
except IndexError:
    pass
else:
    sys.exit("NUMBA_BOUNDSCHECK is not in effect")
import pytest
sys.exit(pytest.main(["-q", "-x", "-n", "0", "-p", "no:cacheprovider", *sys.argv[1:]]))
"""


def test_demosaic_kernels_in_bounds() -> None:
    env = dict(os.environ, NUMBA_BOUNDSCHECK="1", IMAGEFORM_DISABLE_NUMBA="0")
    env["PYTHONPATH"] = os.pathsep.join(
        [str(ROOT / "src"), str(ROOT), env.get("PYTHONPATH", "")]
    ).rstrip(os.pathsep)
    proc = subprocess.run(
        [
            sys.executable,
            "-c",
            SCRIPT,
            "tests/sensor/test_demosaic.py",
            "-k",
            "kernel_matches_twin_float64 or odd_and_tiny",
        ],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert proc.returncode == 0, (proc.stdout + proc.stderr)[-3000:]
    assert " passed" in proc.stdout
