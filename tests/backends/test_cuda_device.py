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
from tests.backends.test_cuda_kernels import APPROX_CASES, approx_errors  # noqa: E402
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


def test_float32_kernels_against_float64() -> None:
    """The float32 kernels (the GPU's fast approximations, issue 29) against NumPy's float64.

    NumPy's float64 result of the same float32 input, within ``F32_VS_F64``: the bound the
    CPU twin meets with each approximation emulated at twice its documented error
    (``test_cuda_kernels.test_twin_float32_against_float64``); 65 536 pixels each.
    """
    from imageform import color as c
    from imageform._cuda import _launch
    from tests.backends.test_cuda_kernels import F32_DELTA_E, F32_ROUTES, F32_VS_F64, f32_sample

    if not _launch.use_cuda():
        pytest.skip(f"imageform's CUDA kernels: {_launch.status()}")
    atol, rtol = F32_VS_F64
    rgb, lab1, lab2 = f32_sample(1 << 16)
    for src, dst in F32_ROUTES:
        x = np.asarray(c.convert(rgb, "srgb", src)).astype(np.float32)
        out = c.convert(_cuda(x, "float32"), src, dst)
        assert str(out.dtype) == "torch.float32"
        ref = np.asarray(c.convert(x.astype(np.float64), src, dst))
        np.testing.assert_allclose(_host(out), ref, atol=atol, rtol=rtol, err_msg=f"{src}->{dst}")
    a, b = lab1.astype(np.float32), lab2.astype(np.float32)
    for name, _, fn in F32_DELTA_E:
        out = fn(_cuda(a, "float32"), _cuda(b, "float32"))
        ref = np.asarray(fn(a.astype(np.float64), b.astype(np.float64)))
        np.testing.assert_allclose(_host(out), ref, atol=atol, rtol=rtol, err_msg=name)


@pytest.mark.parametrize("name", [cs[0] for cs in APPROX_CASES])
def test_fast_approximations_within_their_bounds_on_the_device(name: str) -> None:
    """Each float32 helper of ``imageform._cuda.scalar`` on the GPU within its documented bound.

    The primitives (``lg2.approx``, ``ex2.approx``, ``div.approx``, ``rsqrt.approx``,
    ``__expf``, ``sin.approx``, ``cos.approx``) against the CUDA Programming Guide's bounds,
    the Newton-refined roots against their few ulp (``test_cuda_kernels.APPROX_CASES``):
    the emulation of the CPU twin assumes these bounds.
    """
    from imageform._cuda import _launch
    from imageform._cuda.scalar import functions

    if not _launch.use_cuda():
        pytest.skip(f"imageform's CUDA kernels: {_launch.status()}")
    cuda = _launch.cuda()
    fn = functions("float32", "cuda")[name]
    args = tuple(
        np.asarray(a, np.float32) for a in next(cs[1] for cs in APPROX_CASES if cs[0] == name)
    )
    n = args[0].size
    xs = [f"x{k}" for k in range(len(args))]
    call = ", ".join(f"{x}[i]" for x in xs)
    # `cuda` a global of the kernel, as in the library's generated kernels
    src = (
        f"def kernel({', '.join(xs)}, out):\n"
        "    i = cuda.grid(1)\n"
        "    if i < out.size:\n"
        f"        out[i] = fn({call})\n"
    )
    ns: dict[str, Any] = {"cuda": cuda, "fn": fn}
    exec(compile(src, f"<device check {name}>", "exec"), ns)
    kernel = cuda.jit(ns["kernel"])
    out = cuda.device_array(n, np.float32)
    kernel[(n + 255) // 256, 256](*[cuda.to_device(a) for a in args], out)
    ratio = approx_errors(name, out.copy_to_host(), args)
    assert ratio.max() <= 1.0, (name, float(ratio.max()), float(args[0][ratio.argmax()]))
