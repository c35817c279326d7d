"""The CUDA colour kernels under numba's CUDA simulator (run by test_cuda_kernels.py).

Not collected by the main run (the name has no ``test_`` prefix): numba reads
``NUMBA_ENABLE_CUDASIM`` once, when it is first imported, and the main run imports numba's
CPU target long before; :mod:`tests.backends.test_cuda_kernels` runs this file in a fresh
``python -m pytest`` with the variable set. The public functions get stand-ins for device
arrays (:class:`FakeDeviceArray`: a ``__cuda_array_interface__`` over host memory, which is
what a CUDA array looks like to the dispatch), so the whole path runs: detection, the
dispatch in imageform.color, the generated kernel, the launch; the results are compared
with the NumPy path's and each call must launch exactly one kernel.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np
import pytest

if os.environ.get("NUMBA_ENABLE_CUDASIM") != "1":  # pragma: no cover - the guard
    pytest.skip("needs NUMBA_ENABLE_CUDASIM=1 before numba is imported", allow_module_level=True)

from imageform import color as c
from imageform._cuda import _launch
from imageform.color.white_balance import apply_white_balance_gains


class FakeDeviceArray:
    """A host array seen through ``__cuda_array_interface__`` only (what CuPy exports)."""

    def __init__(self, a: np.ndarray) -> None:
        self.a = np.ascontiguousarray(a)
        self.shape = self.a.shape
        self.dtype = self.a.dtype

    @property
    def __cuda_array_interface__(self) -> dict[str, Any]:
        d = self.a.__array_interface__
        return {
            "shape": d["shape"],
            "typestr": d["typestr"],
            "data": d["data"],
            "strides": None,
            "version": 3,
            "stream": 1,
        }


def host(x: Any) -> np.ndarray:
    return np.asarray(x.copy_to_host())


def one_launch(fn: Any, *args: Any, **kwargs: Any) -> Any:
    before = _launch.launch_count()
    out = fn(*args, **kwargs)
    assert _launch.launch_count() - before == 1, "expected one kernel launch per call"
    return out


_rng = np.random.default_rng(29)
RGB = _rng.uniform(0.02, 0.98, size=(3, 5, 3))
RGB[0, 0] = [0.5, 0.5, 0.5]  # grey: zero chroma, undefined hue
RGB[0, 1] = [0.0, 0.0, 0.0]  # black
RGB[0, 2] = [1.0, 1.0, 1.0]
SPACES3 = [k for k, (n, _) in c.SPACES.items() if n == 3]
TOL = {"float64": (1e-9, 1e-10), "float32": (2e-3, 2e-4)}  # atol, rtol


def _close(got: np.ndarray, ref: np.ndarray, dtype: str, scale: float = 1.0) -> None:
    atol, rtol = TOL[dtype]
    assert got.dtype == ref.dtype
    np.testing.assert_allclose(got, ref, atol=atol * scale, rtol=rtol, equal_nan=True)


@pytest.mark.parametrize("dtype", ["float64", "float32"])
@pytest.mark.parametrize("space", SPACES3)
def test_convert_from_and_to_srgb(space: str, dtype: str) -> None:
    x = c.convert(RGB, "srgb", space).astype(dtype)
    if space == "srgb":
        return
    got = host(one_launch(c.convert, FakeDeviceArray(x), space, "srgb"))
    _close(got, np.asarray(c.convert(x, space, "srgb")), dtype)
    rgb = RGB.astype(dtype)
    got = host(one_launch(c.convert, FakeDeviceArray(rgb), "srgb", space))
    ref = np.asarray(c.convert(rgb, "srgb", space))
    if space == "lch":  # a grey's hue is atan2 of rounding noise: undefined, not compared
        grey = ref[..., 1] < 1e-3
        got[..., 2][grey] = ref[..., 2][grey] = 0.0
    # hue in degrees and code values (ycbcr) are on a larger scale than [0, 1]
    _close(got, ref, dtype, scale=360.0)


@pytest.mark.parametrize(
    ("src", "dst", "params"),
    [
        ("prophoto", "luv", {"white": "D50"}),
        ("rec2020", "lch", {}),
        ("adobe_rgb", "xyy", {}),
        ("display_p3", "rec709", {}),
        ("lab", "luv", {"white": "D65", "observer": 10}),
        ("srgb", "ycbcr", {"standard": "bt709", "signal_range": "limited", "bit_depth": 10}),
        ("ycbcr", "lab", {"standard": "bt2020"}),
    ],
)
def test_convert_longer_routes(src: str, dst: str, params: dict[str, Any]) -> None:
    x = c.convert(RGB, "srgb", src)
    got = host(one_launch(c.convert, FakeDeviceArray(x), src, dst, **params))
    ref = c.convert(x, src, dst, **params)
    if dst == "lch":
        # the hue of a grey is undefined: white's a*, b* are 0 on one path and 1e-14 on the
        # other (the order of the sums), and atan2 turns that into 0 or 180 degrees; the hue
        # is compared where the chroma is above rounding, L* and C* everywhere
        grey = ref[..., 1] < 1e-9
        assert np.all(got[..., 1][grey] < 1e-9)
        got[..., 2][grey] = ref[..., 2][grey]
    np.testing.assert_allclose(got, ref, atol=1e-9, rtol=1e-10)


def test_nan_propagates_without_a_check() -> None:
    x = RGB.copy()
    x[1, 1, 0] = np.nan
    got = host(one_launch(c.convert, FakeDeviceArray(x), "srgb", "lab"))
    assert np.isnan(got[1, 1]).any()
    assert np.isfinite(np.delete(got.reshape(-1, 3), 6, axis=0)).all()


LAB1 = c.convert(RGB, "srgb", "lab").reshape(-1, 3)
LAB2 = c.convert(_rng.uniform(0.02, 0.98, size=(15, 3)), "srgb", "lab")
LAB2[0] = LAB1[0] * [1, -1, -1]  # opposite hues


@pytest.mark.parametrize("dtype", ["float64", "float32"])
@pytest.mark.parametrize(
    ("fn", "kw"),
    [
        (c.delta_e_cie76, {}),
        (c.delta_e_cie94, {}),
        (c.delta_e_cie94, {"application": "textiles", "kC": 1.5}),
        (c.delta_e_cmc, {}),
        (c.delta_e_cmc, {"l": 1.0}),
        (c.delta_e_ciede2000, {}),
        (c.delta_e_ciede2000, {"kL": 2.0, "kH": 0.5}),
    ],
)
def test_delta_e(fn: Any, kw: dict[str, Any], dtype: str) -> None:
    a, b = LAB1.astype(dtype), LAB2.astype(dtype)
    got = host(one_launch(fn, FakeDeviceArray(a), FakeDeviceArray(b), **kw))
    assert got.shape == (15,)
    _close(got, np.asarray(fn(a, b, **kw)), dtype, scale=100.0)


def test_delta_e_by_name() -> None:
    for method in ("cie76", "cie94", "cmc", "ciede2000"):
        got = host(one_launch(c.delta_e, FakeDeviceArray(LAB1), FakeDeviceArray(LAB2), method))
        np.testing.assert_allclose(got, c.delta_e(LAB1, LAB2, method), atol=1e-9, rtol=1e-10)


@pytest.mark.parametrize("method", ["bradford", "cat02", "von_kries"])
def test_chromatic_adaptation(method: str) -> None:
    xyz = c.convert(RGB, "srgb", "xyz")
    got = host(one_launch(c.chromatic_adaptation, FakeDeviceArray(xyz), "D65", "D50", method))
    ref = c.chromatic_adaptation(xyz, "D65", "D50", method)
    np.testing.assert_allclose(got, ref, atol=1e-12, rtol=1e-12)


@pytest.mark.parametrize("transfer", ["srgb", "rec709", "prophoto", "gamma"])
def test_apply_white_balance_gains(transfer: str) -> None:
    gains = [1.3, 1.0, 0.7]
    got = host(
        one_launch(apply_white_balance_gains, FakeDeviceArray(RGB), gains, transfer=transfer)
    )
    ref = apply_white_balance_gains(RGB, gains, transfer=transfer)
    np.testing.assert_allclose(got, ref, atol=1e-12, rtol=1e-12)


TRANSFER = [
    (c.srgb_to_linear, {}),
    (c.linear_to_srgb, {}),
    (c.gamma_to_linear, {"gamma": 2.4}),
    (c.linear_to_gamma, {}),
    (c.adobe_rgb_to_linear, {}),
    (c.linear_to_adobe_rgb, {}),
    (c.rec709_to_linear, {}),
    (c.linear_to_rec709, {}),
    (c.rec2020_to_linear, {}),
    (c.linear_to_rec2020, {}),
    (c.prophoto_to_linear, {}),
    (c.linear_to_prophoto, {}),
    (c.decode, {"transfer": "rec2020"}),
    (c.encode, {"transfer": "adobe_rgb"}),
]


@pytest.mark.parametrize("dtype", ["float64", "float32"])
@pytest.mark.parametrize(("fn", "kw"), TRANSFER, ids=lambda v: getattr(v, "__name__", str(v)))
def test_transfer_functions(fn: Any, kw: dict[str, Any], dtype: str) -> None:
    x = RGB.reshape(5, 9).astype(dtype)  # any shape whose size is a multiple of 3
    got = host(one_launch(fn, FakeDeviceArray(x), **kw))
    assert got.shape == x.shape
    _close(got, np.asarray(fn(x, **kw)), dtype)


def test_numpy_input_launches_nothing() -> None:
    before = _launch.launch_count()
    c.convert(RGB, "srgb", "lab")
    c.delta_e_ciede2000(LAB1, LAB2)
    c.srgb_to_linear(RGB)
    assert _launch.launch_count() == before


def test_detection() -> None:
    assert _launch.use_cuda()
    assert _launch.is_cuda_array(FakeDeviceArray(RGB))
    assert not _launch.is_cuda_array(RGB)
    assert not _launch.is_cuda_array(1.0)
    out = _launch.empty_like(FakeDeviceArray(RGB), shape=(2, 3), dtype="float32")
    assert tuple(out.shape) == (2, 3) and out.dtype == np.float32


def test_a_kernel_that_cannot_compile_switches_the_kernels_off(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from numba.core.errors import TypingError

    def broken(*args: Any) -> None:
        raise TypingError("no NVVM here")

    monkeypatch.setattr(_launch, "launch_1d", broken)
    monkeypatch.setattr(_launch, "_COMPILED", set())
    monkeypatch.setattr(_launch, "_DISABLED", [""])
    # the Array-API path then meets the stand-in, which it cannot read
    warns = pytest.warns(RuntimeWarning, match="CUDA kernels are off")
    with warns, pytest.raises((TypeError, ValueError)):
        c.convert(FakeDeviceArray(RGB), "srgb", "lab")
    assert not _launch.use_cuda()
    assert _launch.status().startswith("off (TypingError")


CODES8 = np.round(RGB * 255).astype(np.uint8)


@pytest.mark.parametrize(
    ("image", "dst"),
    [
        (CODES8, "lab"),
        (CODES8, "hsv"),
        ((RGB * 65535).astype(np.uint16), "lab"),
        (CODES8, "linear_srgb"),
    ],
)
def test_code_values(image: np.ndarray, dst: str) -> None:
    """uint8/uint16 encoded RGB: read as code / 255 (65535) in the kernel, float32 out."""
    got = host(one_launch(c.convert, FakeDeviceArray(image), "srgb", dst))
    ref = np.asarray(c.convert(image, "srgb", dst))
    assert got.dtype == ref.dtype == np.float32
    _close(got, ref, "float32", scale=100.0)
    # (not lch: the hue of a grey pixel is undefined and float32 rounding picks one)
    got = host(one_launch(c.convert, FakeDeviceArray(image), "prophoto", "luv"))
    _close(got, np.asarray(c.convert(image, "prophoto", "luv")), "float32", scale=100.0)


def test_code_values_transfer_and_gains() -> None:
    got = host(one_launch(c.srgb_to_linear, FakeDeviceArray(CODES8)))
    _close(got, np.asarray(c.srgb_to_linear(CODES8)), "float32")
    got = host(one_launch(apply_white_balance_gains, FakeDeviceArray(CODES8), [1.2, 1.0, 0.9]))
    _close(got, np.asarray(apply_white_balance_gains(CODES8, [1.2, 1.0, 0.9])), "float32")
