"""Numba kernels against their plain array twins (IMAGEFORM_DISABLE_NUMBA path).

Stated tolerances: float32 sRGB -> Lab within 2e-3 in L*a*b* units of the float64 twin
(ΔE00 well below 1e-3 is checked separately with colour-science when available);
Lab -> sRGB within 2e-5; HSV and Y'CbCr within float32 rounding (1e-5 relative / 1e-4 deg);
float64 input runs exact formulas: 1e-9.
"""

from __future__ import annotations

import numpy as np
import pytest

from imageform.color import convert
from imageform.errors import InvalidInputError

RNG = np.random.default_rng(30)
IMG = RNG.uniform(0, 1, (96, 160, 3))
# include exact edge values and the decode breakpoint neighbourhood
IMG[0, :8] = np.array(
    [
        [0, 0, 0],
        [1, 1, 1],
        [0.04045, 0.0404, 0.0405],
        [1, 0, 0],
        [0, 1, 0],
        [0, 0, 1],
        [0.001, 0.002, 0.003],
        [0.5, 0.5, 0.5],
    ]
)


def twin(
    x: np.ndarray, src: str, dst: str, monkeypatch: pytest.MonkeyPatch, **p: object
) -> np.ndarray:
    with monkeypatch.context() as m:
        m.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
        return np.asarray(convert(x, src, dst, **p))


def test_srgb_to_lab_float32(monkeypatch: pytest.MonkeyPatch) -> None:
    x = IMG.astype(np.float32)
    fast = convert(x, "srgb", "lab")
    assert fast.dtype == np.float32
    ref = twin(IMG, "srgb", "lab", monkeypatch)
    np.testing.assert_allclose(fast, ref, atol=2e-3)


def test_srgb_to_lab_delta_e00(monkeypatch: pytest.MonkeyPatch) -> None:
    # The accuracy bar: within 1e-3 ΔE00 of a float64 reference (colour-science's
    # CIEDE2000 as the oracle).
    colour = pytest.importorskip("colour")
    fast = convert(IMG.astype(np.float32), "srgb", "lab").astype(np.float64)
    ref = twin(IMG, "srgb", "lab", monkeypatch)
    assert colour.delta_E(fast, ref, method="CIE 2000").max() < 1e-3


def test_srgb_to_lab_uint8(monkeypatch: pytest.MonkeyPatch) -> None:
    x8 = (IMG * 255).round().astype(np.uint8)
    np.testing.assert_allclose(
        convert(x8, "srgb", "lab"), twin(x8 / 255.0, "srgb", "lab", monkeypatch), atol=2e-3
    )


def test_float64_exact(monkeypatch: pytest.MonkeyPatch) -> None:
    for a, b in (("srgb", "lab"), ("srgb", "hsv"), ("srgb", "ycbcr")):
        np.testing.assert_allclose(convert(IMG, a, b), twin(IMG, a, b, monkeypatch), atol=1e-9)
    lab = twin(IMG, "srgb", "lab", monkeypatch)
    np.testing.assert_allclose(convert(lab, "lab", "srgb"), IMG, atol=1e-9)


def test_lab_to_srgb_float32_including_out_of_gamut(monkeypatch: pytest.MonkeyPatch) -> None:
    lab = np.stack(
        [
            RNG.uniform(0, 100, (96, 160)),
            RNG.uniform(-100, 100, (96, 160)),
            RNG.uniform(-100, 100, (96, 160)),
        ],
        axis=-1,
    )
    fast = convert(lab.astype(np.float32), "lab", "srgb")
    ref = twin(lab, "lab", "srgb", monkeypatch)
    np.testing.assert_allclose(fast, ref, rtol=2e-5, atol=2e-5)


def test_out_of_range_srgb_takes_exact_path(monkeypatch: pytest.MonkeyPatch) -> None:
    x = IMG.copy()
    x[5, 5] = [-0.1, 1.2, 0.5]
    fast = convert(x.astype(np.float32), "srgb", "lab")
    np.testing.assert_allclose(fast, twin(x, "srgb", "lab", monkeypatch), atol=2e-3)


@pytest.mark.parametrize("dtype", [np.float32, np.uint8])
def test_hsv_and_ycbcr(dtype: type, monkeypatch: pytest.MonkeyPatch) -> None:
    x = (IMG * 255).round().astype(np.uint8) if dtype is np.uint8 else IMG.astype(np.float32)
    xf = x / 255.0 if dtype is np.uint8 else x.astype(np.float64)
    hsv = convert(x, "srgb", "hsv")
    ref = twin(xf, "srgb", "hsv", monkeypatch)
    dh = np.abs(hsv[..., 0] - ref[..., 0])
    assert np.minimum(dh, 360 - dh).max() < 2e-3
    np.testing.assert_allclose(hsv[..., 1:], ref[..., 1:], atol=2e-6)
    for p in ({}, {"standard": "bt709", "signal_range": "limited", "bit_depth": 10}):
        ycc = convert(x, "srgb", "ycbcr", **p)
        np.testing.assert_allclose(
            ycc, twin(xf, "srgb", "ycbcr", monkeypatch, **p), rtol=1e-5, atol=1e-5
        )
        back = convert(ycc.astype(np.float32), "ycbcr", "srgb", **p)
        np.testing.assert_allclose(back, xf, atol=1e-4)


def test_kernel_boundary_checks() -> None:
    x = IMG.astype(np.float32)
    bad = x.copy()
    bad[3, 3, 1] = np.nan
    with pytest.raises(InvalidInputError, match="NaN"):
        convert(bad, "srgb", "lab")
    with pytest.raises(InvalidInputError, match="NaN"):
        convert(bad, "srgb", "hsv")
    with pytest.raises(InvalidInputError, match="0-255"):
        convert((x * 255).round(), "srgb", "hsv")
    with pytest.raises(InvalidInputError, match="0-255"):
        convert((x * 255).round(), "srgb", "ycbcr")


# --- the float32 sRGB -> Lab kernel checks its input in its own pass (issue 25) ---------

# 200 000 pixels: four parallel chunks of 65 536, each of 32 sub-blocks of 2048
BIG = np.random.default_rng(25).uniform(0, 1, (400, 500, 3)).astype(np.float32)
_WHERE = (0, 2047, 2048, 65536 + 2049, 199_999)  # first, sub-block and chunk edges, last


@pytest.mark.parametrize("where", _WHERE)
@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("threads", [1, 2])
def test_lab_kernel_refuses_non_finite_anywhere(where: int, value: float, threads: int) -> None:
    # the same one-line error wherever the bad value sits, serial or parallel dispatch
    numba = pytest.importorskip("numba")
    x = BIG.copy()
    x.reshape(-1, 3)[where, 1] = value
    old = numba.get_num_threads()
    numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    try:
        with pytest.raises(InvalidInputError, match=r"^srgb image contains NaN or inf$"):
            convert(x, "srgb", "lab")
    finally:
        numba.set_num_threads(old)


def test_lab_kernel_out_of_range_and_0_255(monkeypatch: pytest.MonkeyPatch) -> None:
    x = BIG.copy()
    flat = x.reshape(-1, 3)
    flat[2048] = [-0.05, 1.0, 0.5]
    flat[199_999] = [0.2, 1.0 + 2**-23, 0.0]  # one ulp above 1 is outside too
    fast = convert(x, "srgb", "lab")
    ref = twin(x.astype(np.float64), "srgb", "lab", monkeypatch)
    np.testing.assert_allclose(fast, ref, atol=2e-3)  # out-of-range pixels: exact path
    with pytest.raises(
        InvalidInputError, match=r"^srgb image looks like 0-255 values stored as floats"
    ):
        convert((BIG * 255).round(), "srgb", "lab")


def test_lab_kernel_reports_its_input_statistics() -> None:
    # the kernel itself reports non-finite and out-of-range input (no second pass)
    from imageform._kernels import color_lab
    from imageform._kernels.color_simple import summarize

    m = np.eye(3)
    stats = color_lab.srgb_to_lab(BIG, m)[1]
    assert stats is not None
    assert summarize(stats) == (False, True)
    for value, expected in ((np.nan, (False, False)), (1.5, (True, True))):
        x = BIG.copy()
        x.reshape(-1, 3)[65536 + 2049, 2] = value
        stats = color_lab.srgb_to_lab(x, m)[1]
        assert stats is not None
        assert summarize(stats) == expected


def test_lab_kernel_validates_in_one_pass(monkeypatch: pytest.MonkeyPatch) -> None:
    # valid float32 input: no separate validation pass over the image (the kernel's own
    # statistics decide), and the result is the same
    import sys

    import imageform._validate

    conv = sys.modules["imageform.color.convert"]  # the module (the package exports the function)
    want = convert(BIG, "srgb", "lab")

    def refuse(*args: object, **kwargs: object) -> None:
        raise AssertionError("a separate validation pass ran")

    monkeypatch.setattr(imageform._validate, "check_finite", refuse)
    monkeypatch.setattr(imageform._validate, "as_image_strict", refuse)
    monkeypatch.setattr(conv, "_validate", refuse)
    np.testing.assert_array_equal(convert(BIG, "srgb", "lab"), want)


def test_lab_kernel_hot_loop_vectorised_at_full_width() -> None:
    # The regression of issue 25: the input statistics, gathered as an int64 count in the
    # conversion loop, held the loop to 4 lanes of 64 bits (2.2x slower than 8 float32
    # lanes on AVX2/AVX-512). Compiled afresh here (numba does not show cached code).
    numba = pytest.importorskip("numba")
    import re

    import llvmlite.binding as ll

    from imageform._kernels import color_lab

    if "+avx2" not in ll.get_host_cpu_features().flatten().split(","):
        pytest.skip("8-lane float32 vectors need AVX2")
    fn = numba.njit(color_lab._srgb_to_lab_f32_serial.py_func, cache=False, **color_lab._JIT)
    x = BIG[:2, :5].reshape(-1)
    fn(x, np.empty_like(x), np.eye(3, dtype=np.float32), np.float32(1), np.zeros((1, 2)), 0)
    ir = "".join(fn.inspect_llvm().values())
    assert "x i64>" not in ir  # no 64-bit lanes
    assert re.search(r"<(8|16) x float>", ir)


def test_colour_kernels_compile_no_parallel_kernel() -> None:
    # issue 25: a parallel=True kernel (numba's parallel lowering and its gufunc) compiles
    # much slower than a serial one; the chunks run on threads through jit.run_tasks, and one
    # compiled kernel serves one thread and many (no serial twin)
    numba = pytest.importorskip("numba")
    from imageform._kernels import color_lab, color_u8

    kernels = [
        (mod.__name__, name, k)
        for mod in (color_lab, color_u8)
        for name, k in vars(mod).items()
        if isinstance(k, numba.core.registry.CPUDispatcher)
    ]
    assert len(kernels) > 20
    assert [name for _, name, k in kernels if k.targetoptions.get("parallel")] == []
    assert [name for _, name, k in kernels if name.endswith("_tasks")] == [
        "_srgb_to_lab_f32_tasks",
        "_srgb_to_lab_f64_tasks",
        "_lab_to_srgb_f32_tasks",
        "_lab_to_srgb_f64_tasks",
        "_lab8_tasks",
        "_labf_tasks",
        "_hsv8_tasks",
    ]


@pytest.mark.parametrize("size", [(7, 9), (400, 500)])  # one chunk; several (65536 px each)
def test_colour_kernels_same_result_on_one_thread_and_two(size: tuple[int, int]) -> None:
    numba = pytest.importorskip("numba")
    rng = np.random.default_rng(12)
    u8 = rng.integers(0, 256, (*size, 3), dtype=np.uint8)
    f32 = u8.astype(np.float32) / np.float32(255)
    lab32 = convert(f32, "srgb", "lab")
    calls = {
        "srgb->lab f32": lambda: convert(f32, "srgb", "lab"),
        "srgb->lab f64": lambda: convert(f32.astype(np.float64), "srgb", "lab"),
        "lab->srgb f32": lambda: convert(lab32, "lab", "srgb"),
        "lab->srgb f64": lambda: convert(lab32.astype(np.float64), "lab", "srgb"),
        "lab8": lambda: convert(u8, "srgb", "lab", dtype="uint8"),
        "lab from uint8": lambda: convert(u8, "srgb", "lab"),
        "hsv8": lambda: convert(u8, "srgb", "hsv", dtype="uint8"),
    }
    threads = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = {k: np.asarray(f()) for k, f in calls.items()}
        numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
        two = {k: np.asarray(f()) for k, f in calls.items()}
    finally:
        numba.set_num_threads(threads)
    for k in calls:
        np.testing.assert_array_equal(one[k], two[k], err_msg=k)
