"""The fast CUDA launch's packing against numba's own, without a GPU (issue 29).

:mod:`imageform._cuda._fastlaunch` packs a kernel's arguments straight from the tensors
(pointer, item count, item size, shape, byte strides) instead of building numba device
arrays. On a device it launches that way only for a signature whose packing it has checked
against numba's ``_Kernel._prepare_args`` on the first launch. Here the same comparison runs
on the CPU: numba's built-in CUDA target's ``_prepare_args`` on stand-in device arrays (the
attributes numba reads), against :func:`pack` on CPU tensors of the same shape and pointer.
"""

from __future__ import annotations

import ctypes
import types as pytypes
from typing import Any

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from imageform._cuda import _fastlaunch as fl  # noqa: E402


class _StandIn:
    """What numba's ``_prepare_args`` reads of a device array (``__cuda_memory__`` & co)."""

    __cuda_memory__ = True

    def __init__(self, t: Any) -> None:
        a = t.numpy()
        self.size, self.dtype, self.ndim = a.size, a.dtype, a.ndim
        self.shape = a.shape
        self.strides = fl._c_strides(a.shape, a.itemsize) if t.is_contiguous() else a.strides
        self.device_ctypes_pointer = ctypes.c_void_p(t.data_ptr())


def _numba_pack(types_: list[Any], values: list[Any]) -> list[Any]:
    dispatcher = pytest.importorskip("numba.cuda.dispatcher")
    out: list[Any] = []
    fake = pytypes.SimpleNamespace(extensions=[])
    for ty, v in zip(types_, values, strict=True):
        dispatcher._Kernel._prepare_args(fake, ty, v, 0, [], out)
    return out


@pytest.mark.parametrize("dtype", [torch.float32, torch.float64, torch.uint16])
def test_packing_equals_numbas(dtype: Any) -> None:
    from numba.core import types

    img = torch.zeros((5, 7, 3), dtype=dtype)
    out = torch.zeros((5, 7, 3), dtype=torch.float32)
    col = torch.zeros((6, 4), dtype=torch.float64)[:, 1]  # strided: layout "A"
    from numba.np.numpy_support import from_dtype

    nt = types.Array(from_dtype(np.dtype(str(dtype).removeprefix("torch."))), 3, "C")
    argtypes = [
        nt,
        types.Array(types.float32, 3, "C"),
        types.Array(types.float64, 1, "A"),
        types.int64,
        types.float64,
        types.float32,
        types.boolean,
        types.int32,
    ]
    values = [img, out, col, 35, 0.25, np.float32(1.5), True, 7]
    theirs = _numba_pack(argtypes, [_StandIn(img), _StandIn(out), _StandIn(col), *values[3:]])
    mine = fl.pack(fl.kinds_of(argtypes, types), values, "ctypes")
    assert fl.same_arguments(mine, theirs)
    # a wrong pointer, shape or C type is seen
    assert not fl.same_arguments(
        fl.pack(fl.kinds_of(argtypes, types), [out, *values[1:]], "ctypes"), theirs
    )
    bad = list(mine)
    bad[-1] = ctypes.c_int64(7)
    assert not fl.same_arguments(bad, theirs)


def test_core_flavour_passes_array_fields_as_integers() -> None:
    from numba.core import types

    t = torch.zeros((2, 3), dtype=torch.float64)
    kinds = fl.kinds_of([types.Array(types.float64, 2, "C"), types.boolean], types)
    got = fl.pack(kinds, [t, True], "core")
    assert got == [0, 0, 6, 8, t.data_ptr(), 2, 3, 24, 8, True]


def test_signature_keys_and_unsupported_arguments() -> None:
    t32 = torch.zeros((4, 3), dtype=torch.float32)
    t64 = torch.zeros((4, 3), dtype=torch.float64)
    scalars = (int, float, bool, np.generic)
    k = fl.key_of(object(), [t32, 1.0], scalars)
    assert k is not None and k[1:] == (("float32", 2, True), float)
    assert fl.key_of(len, [t32], scalars) != fl.key_of(len, [t64], scalars)
    assert fl.key_of(len, [t32.T], scalars) != fl.key_of(len, [t32], scalars)  # layout A
    assert fl.key_of(len, [np.zeros(3)], scalars) is None  # not a device array: numba's path
    assert fl.launcher(None) is None
    with pytest.raises(TypeError):
        from numba.core import types

        fl.kinds_of([types.complex128], types)


def test_switch(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("IMAGEFORM_CUDA_FAST_LAUNCH", "0")
    assert not fl.enabled()
    monkeypatch.delenv("IMAGEFORM_CUDA_FAST_LAUNCH")
    assert fl.enabled()


def test_descriptions_from_the_key_are_reused() -> None:
    from numba.core import types

    t = torch.zeros((3, 4), dtype=torch.float32)
    scalars = (int, float, bool, np.generic)
    descs: list[Any] = []
    key = fl.key_of(len, [t, 2.0], scalars, descs)
    assert key is not None and descs[1] is None and descs[0] == fl.describe(t)
    kinds = fl.kinds_of([types.Array(types.float32, 2, "C"), types.float64], types)
    assert fl.same_arguments(
        fl.pack(kinds, [t, 2.0], "ctypes", descs), fl.pack(kinds, [t, 2.0], "ctypes")
    )


def test_a_failing_fast_launch_falls_back_for_good() -> None:
    key = ("probe", 1)

    def broken(*_: Any) -> None:
        raise TypeError("a packing this numba does not take")

    fl._READY[key] = broken
    assert fl.launcher(key) is broken
    fl.forget(key)
    assert fl.launcher(key) is None  # numba's path from now on
    fl.forget(None)  # a launch without a key: nothing to forget
    del fl._READY[key]


_DRY = """
import json, sys
from benchmarks import profile_gpu_host as p
from imageform._cuda import _fastlaunch, _launch

with p.dry_device(sys.argv[1]):
    fns = p.calls("meta")
    gpu_rows = [r for r in p.ROWS if not r.startswith("NumPy")]
    before = _launch.launch_count()
    for name in gpu_rows:
        fns[name]()  # the first launch of its signature: numba's path, then the check
    first = dict(p.COUNTS)
    for name in gpu_rows:
        fns[name]()
        fns[name]()
    print(json.dumps({
        "rows": len(gpu_rows),
        "first": first,
        "then": dict(p.COUNTS),
        "launches": _launch.launch_count() - before,
        "checked": [v is not None for v in _fastlaunch._READY.values()],
    }))
"""


@pytest.mark.parametrize("flavour", ["core", "ctypes"])
def test_dry_device_calls_launch_fast(flavour: str) -> None:
    """``profile_gpu_host.py --dry``'s stand-ins: every profiled public call on ``meta``
    tensors reaches the launch primitive through the fast launch, one launch per call, its
    signature checked against numba's own packing after the first launch."""
    import json
    import os
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(root / "src"), str(root)])}
    env.pop("IMAGEFORM_DISABLE_CUDA", None)
    env.pop("NUMBA_ENABLE_CUDASIM", None)
    proc = subprocess.run(
        [sys.executable, "-c", _DRY, flavour],
        capture_output=True,
        text=True,
        env=env,
        cwd=root,
        timeout=300,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    got = json.loads(proc.stdout.strip().splitlines()[-1])
    n = got["rows"]
    assert got["first"] == {"fast": 0, "numba": n}
    assert got["then"] == {"fast": 2 * n, "numba": n}
    assert got["launches"] == 3 * n
    assert got["checked"] == [True] * n
