"""Shared fixtures: the reference data folder and the array backends under test."""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
#: ../shared/data relative to the project root; override with IMAGEFORM_DATA.
DATA = Path(os.environ.get("IMAGEFORM_DATA", ROOT.parent / "shared" / "data"))

# A command's first run starts a second process that compiles kernels ahead
# (imageform._kernels.ahead); the test run's workers share one warmed cache and the cores
# already, so the commands they run start none. tests/test_compile_ahead.py turns it on.
os.environ.setdefault("IMAGEFORM_COMPILE_AHEAD", "0")


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """The shared reference images (Kodak, OpenCV chessboards); skips if absent."""
    if not DATA.is_dir():
        pytest.skip(f"reference data not found at {DATA}")
    return DATA


def _backends() -> list[str]:
    names = ["numpy", "array_api_strict"]
    try:
        import torch  # noqa: F401

        names.append("torch")
    except ImportError:
        pass
    try:
        import dask.array  # noqa: F401

        names.append("dask")
    except ImportError:
        pass
    return names


BACKENDS = _backends()

#: Files run only in their own interpreter under numba's CUDA simulator (numba reads
#: NUMBA_ENABLE_CUDASIM once, at import): ``test_cuda_kernels.py`` runs ``cuda_sim_cases.py``
#: with ``python -m pytest`` and the variable set, ``test_cuda_geometry_kernels.py`` runs the
#: script ``cuda_sim_check.py``. Any other run leaves them out of collection (the doctest
#: collection would import them; the cases would show as a skipped module).
collect_ignore = (
    []
    if os.environ.get("NUMBA_ENABLE_CUDASIM") == "1"
    else ["backends/cuda_sim_cases.py", "backends/cuda_sim_check.py"]
)


@pytest.fixture(params=BACKENDS)
def xp_name(request: pytest.FixtureRequest) -> str:
    """Name of an array library under test: numpy, array_api_strict, torch, dask (if
    installed). A test that does not apply to one of them skips it with a reason
    (:func:`tests.helpers.skip_backend`)."""
    return str(request.param)


_NUMPY_PRINT_OPTIONS = np.get_printoptions()


@pytest.fixture(autouse=True)
def _restore_numpy_print_options() -> Iterator[None]:
    """colour-science sets ``np.set_printoptions(legacy="1.13")`` on import (colour/__init__.py),
    which breaks every later doctest's array repr; restore the options after each test."""
    yield
    np.set_printoptions(**_NUMPY_PRINT_OPTIONS)


# CI runs property tests with a fixed example sequence: a red CI must be reproducible, and a
# rare example must not decide whether a submission lands (run locally for random search).
from hypothesis import settings as _hyp_settings  # noqa: E402

_hyp_settings.register_profile("ci", derandomize=True, deadline=None, print_blob=True)
if os.environ.get("CI"):
    _hyp_settings.load_profile("ci")
