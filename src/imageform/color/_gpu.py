"""Dispatch of the colour pointwise set to the fused CUDA kernels of :mod:`imageform._cuda`.

The public functions call here first; for a CUDA array (PyTorch CUDA tensor, CuPy array,
anything with ``__cuda_array_interface__``) of float32/float64 channels-last ``(..., 3)``,
when numba's CUDA target is usable, one kernel computes the whole call and its result is
returned; otherwise these functions return ``None`` and the caller runs its Array-API
path. This module belongs to the colour package: it turns the colour parameters (the
conversion route, whites, RGB spaces, Y'CbCr standards, transfer functions, adaptation
matrices, gains) into the plain numbers the kernels take, so the kernels never import the
domain packages (the same split as :mod:`imageform.color._fast` for the CPU kernels). The
steps themselves are made where the parameters live (``transfer._kernel_step``,
``convert._kernel_steps``): this module imports no other colour module (its checks are
:mod:`imageform._validate`'s), so that they can all call it.

Value checks: on device arrays the boundary checks read no values (``_backend.reads_values``
is False; NaN and inf come out as NaN/inf). With ``IMAGEFORM_DEVICE_CHECKS=1`` the public
function's own checks run first (they wait for the device), then the kernel.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

# imports no GPU library and not numba (numba's CUDA target is imported on first launch)
from imageform._cuda import _launch

__all__ = ["Step", "adapt", "convert", "delta_e", "gains", "transfer", "wants"]

#: A kernel step: its name in :data:`imageform._cuda.scalar.NAMES` and its numbers
#: (``("identity", ())``: nothing to do).
Step = tuple[str, tuple[float, ...]]

#: :mod:`imageform._cuda.color`, imported on the first CUDA array (:func:`_kernels`)
_CC: Any = None


def _kernels() -> Any:
    """Return :mod:`imageform._cuda.color` (imported once, when a CUDA array first comes)."""
    global _CC
    if _CC is None:
        from imageform._cuda import color

        _CC = color
    return _CC


def wants(*arrays: object, integers: bool = False) -> bool:
    """Whether every array is a CUDA array the kernels take (cheap for NumPy input).

    A CUDA array (:func:`imageform._cuda._launch.is_cuda_array`) of float32/float64 (and,
    with ``integers``, uint8/uint16 code values: encoded RGB images), shape ``(..., 3)``,
    not recording gradients (autograd keeps the Array-API path), and the kernels usable.
    """
    for a in arrays:
        if not _launch.is_cuda_array(a):
            return False
    if not _launch.use_cuda():
        return False
    cc = _CC or _kernels()
    for a in arrays:
        shape = a.shape if _launch._is_torch(a) else tuple(getattr(a, "shape", ()))  # type: ignore[attr-defined]
        if not shape or shape[-1] != 3 or getattr(a, "requires_grad", False):
            return False
        name = _launch.dtype_name(a)
        if name not in _FLOATS and not (integers and name in cc.INT_SCALE):
            return False
    return True


_FLOATS = frozenset({"float32", "float64"})


def _guard(fn: Callable[..., Any], *args: Any) -> Any:
    """``fn(*args)``, or None when the kernels turned out unusable here (then switched off)."""
    try:
        return fn(*args)
    except (_CC or _kernels()).KernelUnavailable:
        return None


def _checks_on(x: object) -> bool:
    """Whether the public function's own value checks run first (IMAGEFORM_DEVICE_CHECKS=1).

    Only for PyTorch and CuPy arrays (the array path's checks take them); other CUDA arrays
    are checked for shape and dtype only. The switch is read once
    (:func:`imageform._cuda._launch.device_checks`).
    """
    if not _launch.device_checks():
        return False
    from imageform._backend import reads_values

    return (_launch._is_torch(x) or _launch._is_cupy(x)) and reads_values(x)


def convert(
    image: Any, steps: Callable[[], list[Step]], check: Callable[[], Any], integers: bool
) -> Any:
    """Run a conversion on a CUDA array in one kernel, or return None.

    ``steps()`` gives the route's kernel steps (``[]``: the route has none); ``check()``
    runs the array path's boundary checks (only with ``IMAGEFORM_DEVICE_CHECKS=1``);
    ``integers``: the source space takes uint8/uint16 code values.
    """
    if not wants(image, integers=integers):
        return None
    chain = steps()
    if not chain:
        return None
    if _checks_on(image):
        check()
    return _guard((_CC or _kernels()).run_chain, image, chain)


def _elementwise(values: Any) -> bool:
    """Tell whether a CUDA array's elements can be read three at a time (size % 3 == 0)."""
    if not (_launch.is_cuda_array(values) and _launch.use_cuda()):
        return False
    if _launch._is_torch(values) and values.requires_grad:
        return False
    cc = _CC or _kernels()
    shape = tuple(int(s) for s in getattr(values, "shape", ()))
    size = int(np.prod(shape)) if shape else 1
    name = _launch.dtype_name(values)
    known = name in _FLOATS or name in cc.INT_SCALE
    return known and size > 0 and size % 3 == 0


def transfer(values: Any, step: Step, what: str = "values") -> Any:
    """Run a transfer function on a CUDA array in one kernel (elementwise), or return None.

    Arrays of any shape whose size is a multiple of 3 run (the kernel reads them as triples;
    the curve is applied to each element alone); others return None.
    """
    if step[0] == "identity" or not _elementwise(values):
        return None
    if _checks_on(values):
        from imageform._validate import as_image_strict

        as_image_strict(values, what, channels=None, range_check=not what.startswith("linear"))
    return _guard((_CC or _kernels()).run_elementwise, values, [step])


def adapt(xyz: Any, mat: np.ndarray) -> Any:
    """Run ``xyz @ mat.T`` (chromatic adaptation) on a CUDA array in one kernel, or None."""
    if not wants(xyz):
        return None
    if _checks_on(xyz):
        from imageform._validate import as_points_strict

        as_points_strict(xyz, "xyz", 3)
    return _guard(
        (_CC or _kernels()).run_chain,
        xyz,
        [("matrix", tuple(np.asarray(mat, float).ravel().tolist()))],
    )


def gains(image: Any, g: object, decode: Step, encode: Step) -> Any:
    """Decode, multiply by 3 host gains, encode (``apply_white_balance_gains``), or None.

    Only gains given on the host (NumPy, lists) as 3 positive finite numbers run here: gains
    on the device would have to be read back to check them.
    """
    if not wants(image, integers=True) or len(tuple(image.shape)) < 3:
        return None
    if not isinstance(g, np.ndarray | list | tuple):
        return None
    ga = np.asarray(g, dtype=float)
    if ga.shape != (3,) or not (np.isfinite(ga).all() and (ga > 0).all()):
        return None  # the array path explains the error
    if _checks_on(image):
        from imageform._validate import as_image_strict

        as_image_strict(image, "image", channels=3)
    steps = [s for s in (decode, ("gains", tuple(ga.tolist())), encode) if s[0] != "identity"]
    return _guard((_CC or _kernels()).run_chain, image, steps)


def delta_e(lab1: Any, lab2: Any, name: str, params: Sequence[float]) -> Any:
    """Run a ΔE of two same-shape CUDA arrays of one dtype in one kernel, or return None.

    ``name``: ``de76``, ``de94`` (kL, kC, kH, K1, K2), ``decmc`` (l, c) or ``de00`` (kL, kC,
    kH). Broadcasting shapes and mixed dtypes run the Array-API path.
    """
    if not wants(lab1, lab2):
        return None
    if type(lab1) is not type(lab2) or lab1.dtype != lab2.dtype:
        return None
    if tuple(lab1.shape) != tuple(lab2.shape):
        return None
    if _checks_on(lab1):
        from imageform._validate import as_points_strict, check_magnitude

        for x, what in ((lab1, "lab1"), (lab2, "lab2")):
            check_magnitude(as_points_strict(x, what, 3), what, x.__array_namespace__())
    ps = tuple(params)
    if name == "de00":
        ps += (_tiny(_launch.dtype_name(lab1)),)
    return _guard((_CC or _kernels()).run_delta_e, lab1, lab2, name, ps)


#: dtype name -> the square root of its smallest normal number (CIEDE2000's guard)
_TINY: dict[str, float] = {}


def _tiny(dtype: str) -> float:
    got = _TINY.get(dtype)
    if got is None:
        got = _TINY[dtype] = float(np.finfo(dtype).smallest_normal) ** 0.5
    return got
