"""The module-level guard of the tests that need a real CUDA device (issue 29)."""

from __future__ import annotations

from typing import Any

import pytest


def torch_with_cuda() -> Any:
    """Return ``torch``, or skip the calling test module once: no torch, or no CUDA device."""
    torch = pytest.importorskip("torch")
    if not torch.cuda.is_available():  # one skip for the module, not one per case
        pytest.skip("no CUDA device", allow_module_level=True)
    return torch
