"""The CUDA kernels (imageform._cuda) under numba's CUDA simulator, against the NumPy path.

Run by ``tests/backends/test_cuda_kernels.py`` in a subprocess with ``NUMBA_ENABLE_CUDASIM=1``
(the flag must be set before ``numba.cuda`` is imported). PyTorch CPU tensors stand for device
arrays: :func:`imageform._cuda.geometry.is_cuda_array` is told they are, and the simulator
runs the kernels on their memory (``Tensor.numpy()`` shares it). Every public function that
dispatches to a kernel is called on tensors and compared with the same call on NumPy arrays
(the numba or NumPy path), and the kernels it launched are counted: one per call.

Prints one line per check, ``ok NAME launches=N``; exits non-zero on the first failure.
Importing it (pytest's ``--doctest-modules`` collection does) runs nothing.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable
from typing import Any

import numpy as np
import torch

from imageform._cuda import _launch
from imageform.geometry import (
    BrownConrady,
    project_points,
    project_points_distorted,
    remap_bilinear,
    undistort_image,
)
from imageform.sensor import demosaic


def stand_in_tensors() -> None:
    """Let CPU tensors stand for device arrays (the simulator runs on their NumPy views)."""
    from numba.cuda.simulator.cudadrv.devicearray import FakeCUDAArray

    is_cuda_array, as_device_array = _launch.is_cuda_array, _launch.as_device_array

    def stand_in_is(x: object) -> bool:
        return isinstance(x, torch.Tensor) or is_cuda_array(x)

    def stand_in_as(x: Any) -> Any:
        return FakeCUDAArray(x.numpy()) if isinstance(x, torch.Tensor) else as_device_array(x)

    _launch.is_cuda_array = stand_in_is
    _launch.as_device_array = stand_in_as


RNG = np.random.default_rng(29)
BC = BrownConrady(k1=-0.21, k2=0.05, p1=0.002, p2=-0.001, k3=-0.01, k4=0.02, k5=0.001, k6=0.0)


def _np(x: Any) -> Any:
    if isinstance(x, tuple):
        return tuple(_np(v) for v in x)
    return x.numpy() if isinstance(x, torch.Tensor) else np.asarray(x)


def check(name: str, fn: Callable[..., Any], args: tuple[Any, ...], tol: float, **kw: Any) -> None:
    """``fn`` on tensors (one kernel) against ``fn`` on NumPy arrays."""
    ref = _np(fn(*args, **kw))
    before = _launch.launch_count()
    out = fn(*[torch.from_numpy(np.ascontiguousarray(a)) for a in args], **kw)
    n = _launch.launch_count() - before
    assert n == 1, f"{name}: {n} kernel launches (expected 1)"
    outs = _np(out)
    refs = ref if isinstance(ref, tuple) else (ref,)
    outs = outs if isinstance(outs, tuple) else (outs,)
    for o, r in zip(outs, refs, strict=True):
        assert o.shape == r.shape, f"{name}: shape {o.shape} != {r.shape}"
        assert o.dtype == r.dtype, f"{name}: dtype {o.dtype} != {r.dtype}"
        if r.dtype == np.bool_:
            assert np.array_equal(o, r), f"{name}: masks differ"
        else:
            # scaled by the value where it exceeds 1: a point just in front of the camera
            # projects to 1e5 px, where float32's own rounding is 1e-2 px (an absolute
            # tolerance failed on some draws, 0.004 and 0.14 px at such coordinates)
            r64 = r.astype(np.float64)
            diff = np.abs(o.astype(np.float64) - r64) / np.maximum(1.0, np.abs(r64))
            err = np.nanmax(diff, initial=0.0)
            assert np.array_equal(np.isnan(o), np.isnan(r)), f"{name}: NaN where NumPy has none"
            assert err <= tol, f"{name}: max |diff| {err:.3g} > {tol:g}"
    print(f"ok {name} launches={n}", flush=True)


def points(n: int, dtype: str, finite: bool) -> np.ndarray:
    X = RNG.uniform(-1.5, 1.5, (n, 3))
    X[:, 2] = RNG.uniform(-1.0, 4.0, n)  # some behind the camera
    X[0] = (0.0, 0.0, 0.0)
    if not finite:  # project_points takes them (invalid); project_points_distorted refuses
        X[1] = (np.nan, 0.0, 2.0)
        X[2] = (0.0, np.inf, 2.0)
    return X.astype(dtype)


def main() -> None:
    K = np.array([[500.0, 0.3, 320.0], [0.0, 480.0, 240.0], [0.0, 0.0, 1.0]])
    ang = 0.3
    R = np.array(
        [[np.cos(ang), 0.0, np.sin(ang)], [0.0, 1.0, 0.0], [-np.sin(ang), 0.0, np.cos(ang)]]
    )
    t = np.array([0.1, -0.2, 0.5])
    for dt, tol in (("float64", 1e-9), ("float32", 2e-3)):
        xy = RNG.uniform(-0.7, 0.7, (3, 5, 2)).astype(dt)
        check(f"distort[{dt}]", BC.distort, (xy,), tol * 1e-3)
        xy_d = np.concatenate([np.asarray(BC.distort(xy)).reshape(-1, 2), [[3.0, 3.0]]])
        xy_d = xy_d.astype(dt)
        check(f"undistort[{dt}]", BC.undistort, (xy_d,), tol * 1e-3)
        args = (points(40, dt, True), K.astype(dt), R.astype(dt), t.astype(dt))
        args_bad = (points(40, dt, False), *args[1:])

        def proj_bc(p: Any, k: Any, r: Any, tt: Any) -> Any:
            return tuple(project_points_distorted(p, k, r, tt, BC))

        def proj_pin(p: Any, k: Any, r: Any, tt: Any) -> Any:
            return tuple(project_points(p, k, r, tt))

        def proj_none(p: Any, k: Any, r: Any, tt: Any) -> Any:
            return tuple(project_points_distorted(p, k, r, tt, None))

        check(f"project_points_distorted[{dt}]", proj_bc, args, tol)
        check(f"project_points_distorted[none,{dt}]", proj_none, args, tol)
        check(f"project_points[{dt}]", proj_pin, args_bad, tol)
        img = RNG.uniform(0.0, 1.0, (2, 9, 11, 3)).astype(dt)
        img[0, 4, 5, 1] = np.nan  # propagates to the pixels that read it
        m = np.stack(np.meshgrid(np.arange(12.0), np.arange(8.0)), axis=-1)
        m = m * 0.93 - 0.4 + RNG.uniform(-0.2, 0.2, m.shape)
        m[0, 0] = np.nan
        m[1, 1] = (10.0, 8.0)  # the last column and row, exactly
        check(f"remap_bilinear[{dt}]", remap_bilinear, (img, m), tol * 1e-2, fill=0.25)
        check(f"remap_bilinear[gray,{dt}]", remap_bilinear, (img[0, ..., 0], m), tol * 1e-2)
        m32 = m.astype(np.float32)  # read as it is (no conversion kernel)
        check(f"remap_bilinear[map32,{dt}]", remap_bilinear, (img, m32), tol * 1e-2)
        Ks = np.array([[9.0, 0.0, 5.2], [0.0, 8.5, 4.1], [0.0, 0.0, 1.0]])

        def undist(im: Any, Ks: np.ndarray = Ks) -> Any:
            return undistort_image(im, Ks, BC, out_shape=(7, 12), fill=-1.0)

        check(f"undistort_image[{dt}]", undist, (img[1],), tol * 1e-2)
        for method in ("bilinear", "malvar"):
            demosaic_checks(method, dt, tol * 1e-3)
    strided_checks()
    develop_checks()
    fallback_check()  # last: it switches the kernels off for the process


def demosaic_checks(method: str, dt: str, tol: float) -> None:
    """The quad kernels (:mod:`imageform._cuda.demosaic_quads`) against the NumPy path.

    All four CFA patterns on a batch, odd sizes (a cut quad in the last row and column),
    clipping, and a mosaic large enough for blocks whose windows lie inside it (the inner
    loads; the simulator's blocks are 8 x 4 quads) with edge blocks on all four sides. The
    mosaics drawn before the GRBG batch and the 19 x 37 one came from the shared generator;
    those two come from one of their own, so that the later checks' inputs stay as they were.
    """
    own = np.random.default_rng(list(map(ord, method + dt)))
    for pattern in ("RGGB", "GRBG", "GBRG", "BGGR"):
        rng = own if pattern == "GRBG" else RNG
        raw = rng.uniform(-0.05, 1.05, (2, 6, 8, 1)).astype(dt)
        check(
            f"demosaic[{method},{pattern},{dt}]",
            demosaic,
            (raw,),
            tol,
            pattern=pattern,
            method=method,
        )
    for rng, pattern, shape, clip in (
        (RNG, "GRBG", (9, 11), True),
        (own, "BGGR", (19, 37), False),
    ):
        raw = rng.uniform(-0.05, 1.05, shape).astype(dt)  # as many draws as uniform(0, 1)
        check(
            f"demosaic[{method},{pattern},odd{shape},clip={clip},{dt}]",
            demosaic,
            (raw,),
            tol,
            pattern=pattern,
            method=method,
            allow_odd=True,
            clip=clip,
        )
    if dt == "float32":  # integer and half mosaics reach the float32 kernel converted
        for src in ("uint8", "uint16", "float16"):
            top = np.iinfo(src).max if src.startswith("uint") else 1.0
            raw = (own.uniform(0.0, 1.0, (6, 10)) * top).astype(src)
            check(f"demosaic[{method},GBRG,{src}]", demosaic, (raw,), tol, pattern="GBRG",
                  method=method)  # fmt: skip


def fallback_check() -> None:
    """A kernel that numba cannot compile turns the kernels off; the call still answers."""
    import warnings

    from numba.core.errors import TypingError

    from imageform._cuda import geometry

    class Broken:
        def __getitem__(self, config: Any) -> Any:
            def launch(*args: Any) -> None:
                raise TypingError("cannot type this kernel (on purpose)")

            return launch

    geometry._kernels().distort = Broken()
    _launch._COMPILED.clear()
    xy = RNG.uniform(-0.6, 0.6, (7, 2))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        got = BC.distort(torch.from_numpy(xy))
    assert isinstance(got, torch.Tensor)
    assert np.abs(got.numpy() - np.asarray(BC.distort(xy))).max() <= 1e-12
    assert _launch.status().startswith("off (TypingError"), _launch.status()
    assert any("kernels are off" in str(w.message) for w in caught)
    before = _launch.launch_count()
    demosaic(torch.from_numpy(RNG.uniform(0, 1, (6, 8))), "RGGB")  # the Array-API path now
    assert _launch.launch_count() == before
    print("ok fallback when a kernel cannot compile launches=1", flush=True)


def strided_checks() -> None:
    """Views with strides (a step, a transpose) reach the kernels as they are, or copied."""
    xy = RNG.uniform(-0.6, 0.6, (9, 2))
    t = torch.from_numpy(xy)[::2]  # a strided view
    before = _launch.launch_count()
    got = BC.distort(t).numpy()
    assert _launch.launch_count() - before == 1
    assert np.abs(got - np.asarray(BC.distort(xy[::2]))).max() <= 1e-12
    raw = RNG.uniform(0.0, 1.0, (10, 8))
    t = torch.from_numpy(raw).T  # (8, 10), column-major
    got = demosaic(t, "RGGB", "malvar").numpy()
    assert np.abs(got - np.asarray(demosaic(raw.T, "RGGB", "malvar"))).max() <= 1e-12
    img = RNG.uniform(0.0, 1.0, (6, 7, 3))
    m = RNG.uniform(-0.5, 6.5, (4, 5, 2))
    t = torch.from_numpy(img)[:, ::2]  # (6, 4, 3), strided columns
    got = remap_bilinear(t, torch.from_numpy(m)).numpy()
    ref = np.asarray(remap_bilinear(np.ascontiguousarray(img[:, ::2]), m))
    assert np.abs(got - ref).max() <= 1e-12
    print("ok strided views launches=1", flush=True)


def develop_checks() -> None:
    """``develop(device="cuda")`` (one kernel) against the CPU pass, every output mode."""
    from imageform.io import RawImage, develop

    cm = np.array([[1.20, -0.30, -0.10], [-0.40, 1.30, 0.10], [-0.05, 0.20, 0.60]])
    for pattern, shape in (("RGGB", (8, 10)), ("GBRG", (9, 7))):
        raw = RawImage(
            mosaic=RNG.integers(40, 4200, size=shape).astype(np.uint16),
            black_level=np.array([[60.0, 64.0], [66.0, 70.0]]),
            white_level=4095.0,
            cfa_pattern=pattern,
            white_balance=np.array([1.9, 1.0, 1.6]),
            xyz_to_camera=cm,
            camera_to_srgb=np.eye(3),
            calibration_illuminant="D65",
            orientation=6,
        )
        for method in ("bilinear", "malvar"):
            for linear in (False, True):
                cpu = develop(raw, demosaic=method, linear=linear)
                for what in ("camera_rgb", "image", "to_integer"):
                    gpu = develop(raw, demosaic=method, linear=linear, device="cuda")
                    before = _launch.launch_count()
                    got = gpu.to_integer(16) if what == "to_integer" else getattr(gpu, what)
                    n = _launch.launch_count() - before
                    ref = cpu.to_integer(16) if what == "to_integer" else getattr(cpu, what)
                    assert n == 1, f"develop {what}: {n} launches"
                    assert got.dtype == ref.dtype and got.shape == ref.shape
                    err = np.abs(got.astype(np.float64) - ref.astype(np.float64)).max()
                    # float32 in the same order; a code may differ at a rounding tie
                    limit = 1.0 if what == "to_integer" else 2e-6
                    name = f"develop[{pattern},{method},{'linear' if linear else 'srgb'},{what}]"
                    assert err <= limit, f"{name}: max |diff| {err:.3g}"
                    print(f"ok {name} launches={n}", flush=True)


if __name__ == "__main__":
    if os.environ.get("NUMBA_ENABLE_CUDASIM") != "1":
        raise SystemExit("run with NUMBA_ENABLE_CUDASIM=1 (numba's CUDA simulator)")
    stand_in_tensors()
    main()
    sys.exit(0)
