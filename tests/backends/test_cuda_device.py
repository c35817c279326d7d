"""The device checks on a real GPU (issue 29): skipped where there is none.

On a machine with CUDA (a lent GPU; ``benchmarks/bench_gpu.py`` is the timing half):

- every backend-matrix case on CUDA tensors gives a CUDA tensor of NumPy's dtype and
  numbers (``test_backends_matrix``'s tolerances), and on CuPy arrays a CuPy array (CuPy's
  ``asnumpy`` refuses implicit conversion, so a NumPy call on device data fails the case);
- every call of the pointwise set (``test_meta_device.POINTWISE``), after one warm-up call
  (constants uploaded), runs under ``torch.cuda.set_sync_debug_mode("error")``: no host
  synchronisation, and NumPy's numbers.

Run: ``PYTHONPATH=src python -m pytest -q -n 0 tests/backends/test_cuda_device.py``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from tests.backends._gpu import torch_with_cuda

torch = torch_with_cuda()

from tests.backends.test_backends_matrix import CASES, Case, _result  # noqa: E402
from tests.backends.test_meta_device import NEEDS_VALUES, POINTWISE  # noqa: E402


def _cuda(a: Any, dtype: str = "float64") -> Any:
    return torch.asarray(np.asarray(a, dtype=dtype), device="cuda")


def _host(x: Any) -> Any:
    if isinstance(x, tuple):
        return tuple(_host(v) for v in x)
    return x.detach().cpu().numpy() if isinstance(x, torch.Tensor) else np.asarray(x)


@pytest.mark.parametrize("case", CASES, ids=[cs.name for cs in CASES])
def test_matrix_case_on_cuda(case: Case) -> None:
    ref = np.asarray(_result(case, case.fn(*case.args)))
    out = _result(case, case.fn(*[_cuda(a) for a in case.args]))
    if case.same_kind:
        assert isinstance(out, torch.Tensor) and out.device.type == "cuda", out
        assert str(out.dtype).removeprefix("torch.") == ref.dtype.name
    np.testing.assert_allclose(_host(out), ref, atol=case.atol, rtol=1e-12, equal_nan=True)


@pytest.mark.parametrize("case", CASES, ids=[cs.name for cs in CASES])
def test_matrix_case_on_cupy(case: Case) -> None:
    """The same matrix on CuPy arrays: CuPy out, NumPy's numbers, no implicit NumPy copy."""
    cupy = pytest.importorskip("cupy")
    ref = np.asarray(_result(case, case.fn(*case.args)))
    out = _result(case, case.fn(*[cupy.asarray(np.asarray(a, dtype="float64")) for a in case.args]))
    if case.same_kind:
        assert isinstance(out, cupy.ndarray), type(out)
        assert out.dtype.name == ref.dtype.name
    got = cupy.asnumpy(out) if isinstance(out, cupy.ndarray) else _host(out)
    np.testing.assert_allclose(got, ref, atol=case.atol, rtol=1e-12, equal_nan=True)


#: Calls whose numbers are not comparable across libraries, and why (the no-sync check runs).
NUMBERS_DIFFER = {
    "convert[gray->lch]": "the hue of a grey is atan2 of rounding noise (undefined)",
}


@pytest.mark.parametrize("dtype", ["float32", "float64"])
@pytest.mark.parametrize(("fn", "args"), [p[1:] for p in POINTWISE], ids=[p[0] for p in POINTWISE])
def test_pointwise_set_never_syncs(
    fn: Callable[..., Any], args: tuple[Any, ...], dtype: str
) -> None:
    ref = fn(*[np.asarray(a, dtype=dtype) for a in args])
    xs = [_cuda(a, dtype) for a in args]
    fn(*xs)  # warm-up: constants uploaded once
    torch.cuda.synchronize()
    torch.cuda.set_sync_debug_mode("error")
    try:
        out = fn(*xs)
    finally:
        torch.cuda.set_sync_debug_mode("default")
    name = next(p[0] for p in POINTWISE if p[1] is fn)
    if name not in NUMBERS_DIFFER:
        _compare(out, ref, dtype)


def _compare(out: Any, ref: Any, dtype: str) -> None:
    """Each array of a result (a tuple or named tuple: each field) against NumPy's."""
    outs = tuple(out) if isinstance(out, tuple) else (out,)
    refs = tuple(ref) if isinstance(ref, tuple) else (ref,)
    assert len(outs) == len(refs)
    for o, r in zip(outs, refs, strict=True):
        np.testing.assert_allclose(
            np.asarray(_host(o), dtype=np.float64),
            np.asarray(r, dtype=np.float64),
            atol=2e-3 if dtype == "float32" else 1e-8,
            rtol=1e-4 if dtype == "float32" else 1e-10,
            equal_nan=True,
        )


def test_needs_values_still_work_on_cuda() -> None:
    # the reports read values by contract: they copy to the host explicitly
    names = set(NEEDS_VALUES)
    for case in CASES:
        if case.name in names:
            case.fn(*[_cuda(a) for a in case.args])


def test_colour_kernels_one_launch_on_cuda() -> None:
    """The colour set on CUDA tensors: one numba kernel per call, NumPy's numbers (issue 29)."""
    from imageform import color as c
    from imageform._cuda import _launch
    from imageform.color.white_balance import apply_white_balance_gains

    if not _launch.use_cuda():
        pytest.skip(f"imageform's CUDA kernels: {_launch.status()}")
    rng = np.random.default_rng(29)
    rgb = rng.uniform(0.02, 0.98, (64, 48, 3))
    lab = c.convert(rgb, "srgb", "lab")
    lab2 = c.convert(rng.uniform(0.02, 0.98, (64, 48, 3)), "srgb", "lab")
    xyz = c.convert(rgb, "srgb", "xyz")
    calls: list[tuple[Callable[..., Any], tuple[Any, ...], dict[str, Any]]] = [
        (c.convert, (rgb, "srgb", "lab"), {}),
        (c.convert, (lab, "lab", "srgb"), {}),
        (c.convert, (rgb, "prophoto", "luv"), {}),
        (c.convert, (rgb, "srgb", "hsv"), {}),
        (c.srgb_to_linear, (rgb,), {}),
        (c.chromatic_adaptation, (xyz, "D65", "D50"), {}),
        (apply_white_balance_gains, (rgb, [1.3, 1.0, 0.7]), {}),
        (c.delta_e_cie76, (lab, lab2), {}),
        (c.delta_e_cie94, (lab, lab2), {}),
        (c.delta_e_cmc, (lab, lab2), {}),
        (c.delta_e_ciede2000, (lab, lab2), {}),
    ]
    for dtype, atol in (("float64", 1e-9), ("float32", 2e-4)):
        for fn, args, kw in calls:
            ref = np.asarray(
                fn(
                    *[
                        a.astype(dtype) if isinstance(a, np.ndarray) and a.ndim == 3 else a
                        for a in args
                    ],
                    **kw,
                )
            )
            dev = [
                _cuda(a, dtype) if isinstance(a, np.ndarray) and a.ndim == 3 else a for a in args
            ]
            fn(*dev, **kw)  # compiles
            before = _launch.launch_count()
            torch.cuda.set_sync_debug_mode("error")
            try:
                out = fn(*dev, **kw)
            finally:
                torch.cuda.set_sync_debug_mode("default")
            assert _launch.launch_count() - before == 1, fn.__name__
            assert isinstance(out, torch.Tensor) and out.device.type == "cuda"
            assert str(out.dtype).removeprefix("torch.") == dtype
            np.testing.assert_allclose(
                _host(out), ref, atol=atol, rtol=1e-5 if dtype == "float32" else 1e-10
            )
