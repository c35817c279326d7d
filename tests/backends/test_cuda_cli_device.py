"""The ``--device cuda`` commands on a real GPU (issue 29): skipped where there is none.

The same checks as the simulator runs of ``test_cuda_kernels.py`` and
``test_cuda_geometry_kernels.py`` (``develop``, ``convert``, ``white-balance``, ``delta-e``
with ``--device cuda`` give ``--device cpu``'s numbers, the kernels never switched off), plus
``batch develop --device cuda`` on a one-worker local cluster, each a fresh ``imageform``
process on the GPU.

Run: ``PYTHONPATH=src python -m pytest -q -n 0 tests/backends/test_cuda_cli_device.py``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.backends._gpu import torch_with_cuda

torch = torch_with_cuda()

from tests.backends.test_cuda_geometry_kernels import (  # noqa: E402
    _run,
    check_develop_cli,
    tiny_dng,
)
from tests.backends.test_cuda_kernels import check_pointwise_cli, tiny_pngs  # noqa: E402

__all__ = ["tiny_dng", "tiny_pngs"]  # the fixtures, imported for this module's tests


def test_develop_device_cuda(tiny_dng: Path, tmp_path: Path) -> None:
    check_develop_cli(tiny_dng, tmp_path, {})


def test_pointwise_device_cuda(tiny_pngs: tuple[Path, Path], tmp_path: Path) -> None:
    check_pointwise_cli(tiny_pngs, tmp_path, {})


def test_batch_develop_device_cuda(tmp_path: Path) -> None:
    pytest.importorskip("distributed")
    from imageform.io import write_dng

    # large enough for LibRaw, which the workers use where rawpy is installed
    src = tmp_path / "in" / "frame.dng"
    src.parent.mkdir()
    rng = np.random.default_rng(29)
    mosaic = rng.integers(100, 4000, size=(64, 96)).astype(np.uint16)
    cm = [[1.2, -0.3, -0.1], [-0.4, 1.3, 0.1], [-0.05, 0.2, 0.6]]
    write_dng(src, mosaic, black_level=64, white_level=4095, color_matrix=cm)
    out, ref = tmp_path / "b", tmp_path / "cpu.npy"
    argv = ["batch", "develop", str(src.parent / "*.dng"), "-o", str(out), "--device", "cuda"]
    proc = _run(["-m", "imageform", *argv, "--workers", "1", "--suffix", ".npy"])
    assert proc.returncode == 0, (proc.stdout + proc.stderr)[-3000:]
    assert "kernels are off" not in proc.stderr, proc.stderr
    got = sorted(out.glob("*.npy"))
    assert [p.stem for p in got] == ["frame"], list(out.iterdir())
    proc = _run(["-m", "imageform", "develop", str(src), "-o", str(ref), "--device", "cpu"])
    assert proc.returncode == 0, proc.stdout + proc.stderr
    np.testing.assert_allclose(np.load(got[0]), np.load(ref), atol=2e-6, rtol=0)
