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


@pytest.fixture
def flavour(monkeypatch: pytest.MonkeyPatch) -> Any:
    """Set how :func:`fl.pack_call` packs (numba-cuda's ``"core"`` or the built-in ``"ctypes"``)."""

    def set_(name: str) -> None:
        monkeypatch.setattr(fl, "_FLAVOUR", [name])

    return set_


@pytest.mark.parametrize("dtype", [torch.float32, torch.float64, torch.uint16])
def test_packing_equals_numbas(dtype: Any, flavour: Any) -> None:
    from numba.core import types

    flavour("ctypes")
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
        types.float32,
        types.float64,
        types.boolean,
    ]
    consts = fl.Constants((np.float32(0.5), 2.0, False))
    values = [img, out, col, 35, 0.25, np.float32(1.5), True, np.int32(7), consts]
    expanded = fl.expand(values)
    assert expanded[-3:] == [np.float32(0.5), 2.0, False]
    stand_ins = [_StandIn(img), _StandIn(out), _StandIn(col), *expanded[3:]]
    theirs = _numba_pack(argtypes, stand_ins)
    got = fl.pack_call(len, values)
    assert got is not None
    _, mine, first = got
    assert first is img
    assert fl.same_arguments(mine, theirs)
    # a wrong pointer, shape or C type is seen
    other = fl.pack_call(len, [out, *values[1:]])
    assert other is not None and not fl.same_arguments(other[1], theirs)
    bad = list(mine)
    bad[-4] = ctypes.c_int64(7)
    assert not fl.same_arguments(bad, theirs)


def test_core_flavour_passes_array_fields_as_integers(flavour: Any) -> None:
    flavour("core")
    t = torch.zeros((2, 3), dtype=torch.float64)
    got = fl.pack_call(len, [t, True])
    assert got is not None
    assert got[1] == [0, 0, 6, 8, t.data_ptr(), 2, 3, 24, 8, True]


def test_signature_keys_and_unsupported_arguments(flavour: Any) -> None:
    flavour("core")
    t32 = torch.zeros((4, 3), dtype=torch.float32)
    t64 = torch.zeros((4, 3), dtype=torch.float64)

    def key(kernel: Any, args: list[Any]) -> Any:
        got = fl.pack_call(kernel, args)
        return None if got is None else got[0]

    k = key(len, [t32, 1.0])
    assert k is not None and k[1:] == (("float32", 2, True), float)
    assert key(len, [t32]) != key(len, [t64])
    assert key(len, [t32.T]) != key(len, [t32])  # layout A
    assert key(len, [t32]) != key(abs, [t32])  # another kernel
    c1, c2 = fl.Constants((1.0, 2.0)), fl.Constants((1.0, np.float32(2.0)))
    assert key(len, [t32, c1]) != key(len, [t32, c2])  # the numbers' types
    assert key(len, [t32, c1]) == key(len, [t32, fl.Constants((3.0, 4.0))])
    assert key(len, [np.zeros(3)]) is None  # not a device array: numba's path
    assert key(len, [t32, np.float16(1.0)]) is None  # a number numba packs
    assert fl.launcher(None) is None


def test_constants_are_packed_once(flavour: Any) -> None:
    flavour("core")
    c = fl.Constants((np.float32(0.5), 2.0, 3, True))
    t = torch.zeros(3)
    first = fl.pack_call(len, [t, c])
    again = fl.pack_call(len, [t, c])
    assert first is not None and again is not None
    assert first[1][-4:] == again[1][-4:]
    assert all(a is b for a, b in zip(first[1][-3:], again[1][-3:], strict=True))
    assert [type(v).__name__ for v in first[1][-4:]] == ["c_float", "c_double", "c_long", "bool"]
    assert len(c) == 4 and "0.5" in repr(c)


def test_switch(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("IMAGEFORM_CUDA_FAST_LAUNCH", "0")
    assert not fl.enabled()
    monkeypatch.delenv("IMAGEFORM_CUDA_FAST_LAUNCH")
    assert fl.enabled()


def test_environment_switches_are_read_once(monkeypatch: pytest.MonkeyPatch) -> None:
    from imageform._cuda import _launch

    monkeypatch.setattr(_launch, "_USE", [True])  # as on a machine with a GPU
    monkeypatch.setattr(_launch, "_CHECKS", [None])
    monkeypatch.setattr(_launch, "_FAST", [None])
    monkeypatch.setattr(_launch, "_available", lambda: True)
    monkeypatch.setenv("IMAGEFORM_DISABLE_CUDA", "1")
    monkeypatch.setenv("IMAGEFORM_DEVICE_CHECKS", "1")
    assert _launch.use_cuda()  # read before: not read again in every call
    assert _launch.device_checks()  # read now, on first use
    monkeypatch.delenv("IMAGEFORM_DEVICE_CHECKS")
    assert _launch.device_checks()
    _launch.refresh_switches()
    assert not _launch.use_cuda()
    assert not _launch.device_checks()
    assert _launch.status() == "off (IMAGEFORM_DISABLE_CUDA)"
    monkeypatch.delenv("IMAGEFORM_DISABLE_CUDA")
    _launch.refresh_switches()
    assert _launch.use_cuda()


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
