"""The CUDA colour kernels without a GPU (issue 29): the simulator run and the CPU twin.

Two checks that need no device:

- :func:`test_simulator_cases` runs ``cuda_sim_cases.py`` in a fresh interpreter with
  ``NUMBA_ENABLE_CUDASIM=1`` (numba reads it once, at its first import, so it cannot be
  switched on inside this run): the public functions dispatch stand-in device arrays to the
  generated kernels, which must give the NumPy path's numbers with one launch per call.
- the CPU twin: the same generated kernel bodies and scalar functions compiled by numba's
  CPU target for the input's dtype, so the float32 arithmetic a GPU would run (the
  simulator runs Python floats) is checked against the NumPy path here.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from imageform import color as c
from imageform._cuda import _launch
from imageform._cuda.color import chain_source, run_chain_twin, run_delta_e_twin
from imageform.color import _gpu
from imageform.color.convert import _kernel_steps, path
from imageform.color.rgb_spaces import RGB_SPACES

ROOT = Path(__file__).resolve().parents[2]
CASES = Path(__file__).with_name("cuda_sim_cases.py")


def _measuring_coverage() -> bool:
    try:
        import coverage
    except ImportError:  # pragma: no cover - coverage is a test dependency
        return False
    return coverage.Coverage.current() is not None


def test_simulator_cases() -> None:
    env = dict(os.environ)
    env["NUMBA_ENABLE_CUDASIM"] = "1"
    env.pop("IMAGEFORM_DISABLE_CUDA", None)
    env["PYTHONPATH"] = os.pathsep.join(
        [str(ROOT / "src"), str(ROOT), *filter(None, [env.get("PYTHONPATH", "")])]
    )
    cmd = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:xdist"]
    if _measuring_coverage():  # the kernels' lines count towards CI's coverage too
        cmd[1:3] = ["-m", "coverage", "run", "--parallel-mode", "-m", "pytest"]
    cmd += ["-o", "addopts=", str(CASES)]
    proc = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True, timeout=600)
    tail = (proc.stdout + proc.stderr)[-4000:]
    assert proc.returncode == 0, tail
    assert " passed" in proc.stdout and "skipped" not in proc.stdout.splitlines()[-1], tail


_rng = np.random.default_rng(291)
RGB = _rng.uniform(0.02, 0.98, size=(40, 3))
RGB[0] = [0.5, 0.5, 0.5]
RGB[1] = [0.0, 0.0, 0.0]

# routes that use every step of imageform._cuda.scalar.NAMES between them
ROUTES = [
    ("srgb", "lab", {}),
    ("lab", "srgb", {}),
    ("prophoto", "luv", {"white": "D50"}),
    ("luv", "rec2020", {}),
    ("adobe_rgb", "lch", {}),
    ("lch", "rec709", {}),
    ("srgb", "xyy", {}),
    ("xyy", "srgb", {}),
    ("srgb", "hsv", {}),
    ("hsv", "srgb", {}),
    ("srgb", "hsl", {}),
    ("hsl", "bgr", {}),
    ("srgb", "hsi", {}),
    ("hsi", "cmy", {}),
    ("srgb", "ycbcr", {"signal_range": "limited"}),
    ("ycbcr", "srgb", {"signal_range": "limited"}),
]
# float32 in float32 arithmetic: the twin is as far from the float64 result as NumPy's own
# float32 path (measured: 3e-5 for L*, 8e-5 for hue in degrees, 2e-5 for 8-bit codes)
TOL: dict[str, tuple[float, float]] = {"float64": (1e-9, 1e-10), "float32": (2e-4, 1e-5)}


def _with_white(route: list, params: dict[str, object]) -> dict[str, object]:
    """The parameters convert() hands its edges (its default white: the route's RGB space's)."""
    p = dict(params)
    if any("white" in e.params for e in route) and p.get("white") is None:
        rgb = [k for k in RGB_SPACES for e in route if f"linear_{k}" in (e.src, e.dst)]
        p["white"] = rgb[0] if rgb else "D65"
    return p


@pytest.mark.parametrize("dtype", ["float64", "float32"])
@pytest.mark.parametrize(("src", "dst", "params"), ROUTES)
def test_twin_convert(src: str, dst: str, params: dict[str, object], dtype: str) -> None:
    x = np.asarray(c.convert(RGB, "srgb", src)).astype(dtype)
    route = path(src, dst)
    steps = _kernel_steps(route, _with_white(route, params))
    assert steps, f"no kernel steps for {src} -> {dst}"
    got = run_chain_twin(x, steps)
    ref = np.asarray(c.convert(x, src, dst, **params))
    atol, rtol = TOL[dtype]
    assert got.dtype == np.dtype(dtype)
    if dst == "lch" and dtype == "float32":
        # a grey's hue is atan2 of float32 rounding noise (undefined, as on the device tests):
        # the kernels' cube root (scalar._cbrt, ~1 ulp) and NumPy's round a grey's a*, b* to
        # different noise; its chroma is still compared
        grey = ref[..., 1] < 1e-3
        got[grey, 2] = ref[grey, 2]
    np.testing.assert_allclose(got, ref, atol=atol, rtol=rtol)


LAB1 = np.asarray(c.convert(RGB, "srgb", "lab"))
LAB2 = np.asarray(c.convert(_rng.uniform(0.02, 0.98, size=(40, 3)), "srgb", "lab"))
LAB2[0] = LAB1[2] * [1, -1, -1]
LAB1[0] = LAB1[2]


@pytest.mark.parametrize("dtype", ["float64", "float32"])
@pytest.mark.parametrize(
    ("name", "params", "fn"),
    [
        ("de76", (), c.delta_e_cie76),
        ("de94", (1.0, 1.0, 1.0, 0.045, 0.015), c.delta_e_cie94),
        ("decmc", (2.0, 1.0), c.delta_e_cmc),
        ("de00", (1.0, 1.0, 1.0), c.delta_e_ciede2000),
    ],
)
def test_twin_delta_e(name: str, params: tuple[float, ...], fn: object, dtype: str) -> None:
    a, b = LAB1.astype(dtype), LAB2.astype(dtype)
    ps = list(params)
    if name == "de00":
        ps.append(float(np.finfo(np.dtype(dtype)).smallest_normal) ** 0.5)
    got = run_delta_e_twin(a, b, name, ps)
    ref = np.asarray(fn(a, b))  # type: ignore[operator]
    atol, rtol = TOL[dtype]
    np.testing.assert_allclose(got, ref, atol=atol, rtol=rtol)


def test_chain_source_is_one_pass() -> None:
    src = chain_source(["dec_srgb", "matrix", "xyz_lab"])
    assert src.count("x[i,") == 3 and src.count("out[i,") == 3
    assert "cuda.grid(1)" in src
    assert "for i in range(n)" in chain_source(["swap"], "cpu")


def test_steps_cover_three_channel_routes() -> None:
    three = [k for k, (n, _) in c.SPACES.items() if n == 3]
    for s in three:
        for d in three:
            if s != d:
                p = {"white": "D65"}
                assert _kernel_steps(path(s, d), p), (s, d)
    assert _kernel_steps(path("srgb", "gray"), {"method": "rec601"}) == []


def test_host_arrays_are_not_cuda_arrays() -> None:
    assert not _launch.is_cuda_array(RGB)
    assert not _launch.is_cuda_array([1.0, 2.0, 3.0])
    assert not _gpu.wants(RGB)
    torch = pytest.importorskip("torch")
    assert not _launch.is_cuda_array(torch.zeros(3))
    assert not _launch.is_cuda_array(torch.empty(3, device="meta"))


def test_disable_switch(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("IMAGEFORM_DISABLE_CUDA", "1")
    monkeypatch.setattr(_launch, "_USE", [None])  # read again (once), put back after
    assert not _launch.use_cuda()


def test_first_compile_failure_inside_numba_turns_the_kernels_off(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """numba-cuda 0.30.4 on NumPy 2.5 (seen on a lent H200): the lowering module's import fails
    with a plain AttributeError in numba's code at the first compile; that turns the kernels
    off with one warning (the Array-API path runs), while other errors still propagate."""
    ns: dict[str, object] = {"__name__": "numba.cuda.np.arrayobj"}
    exec(
        "def fail(*a):\n    raise AttributeError(\"module 'numpy' has no attribute 'row_stack'\")",
        ns,
    )
    monkeypatch.setattr(_launch, "launch_1d", ns["fail"])
    monkeypatch.setattr(_launch, "_DISABLED", [""])
    with pytest.warns(RuntimeWarning, match="row_stack"):
        assert _launch.guarded(("probe", "float32"), None, 4) is False
    assert "row_stack" in _launch.status()

    def ours(*a: object) -> None:
        raise AttributeError("an error of imageform's own")

    monkeypatch.setattr(_launch, "launch_1d", ours)
    monkeypatch.setattr(_launch, "_DISABLED", [""])
    with pytest.raises(AttributeError, match="imageform's own"):
        _launch.guarded(("probe", "float64"), None, 4)
    assert _launch._DISABLED == [""]


@pytest.mark.parametrize("dtype", ["uint8", "uint16"])
def test_twin_code_values(dtype: str) -> None:
    """uint8/uint16 code values: read as code / 255 (65535) in float32, as ``as_image`` does."""
    top = 255 if dtype == "uint8" else 65535
    x = np.round(RGB * top).astype(dtype)
    route = path("srgb", "lab")
    got = run_chain_twin(x, _kernel_steps(route, _with_white(route, {})))
    ref = np.asarray(c.convert(x, "srgb", "lab"))
    assert got.dtype == ref.dtype == np.float32
    atol, rtol = TOL["float32"]
    np.testing.assert_allclose(got, ref, atol=atol, rtol=rtol)


# --- the pointwise commands: --device cuda ---------------------------------------------------


@pytest.fixture(scope="module")
def tiny_pngs(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    from imageform.io import write_image

    rng = np.random.default_rng(29)
    folder = tmp_path_factory.mktemp("png")
    paths = (folder / "a.png", folder / "b.png")
    for p in paths:
        write_image(p, rng.integers(0, 256, size=(5, 7, 3)).astype(np.uint8))
    return paths


def _cli(argv: list[str], **env: str) -> subprocess.CompletedProcess[str]:
    from tests.backends.test_cuda_geometry_kernels import _run

    return _run(["-m", "imageform", *argv], **env)


def test_pointwise_device_cuda_refused_in_one_line(
    tiny_pngs: tuple[Path, Path], tmp_path: Path
) -> None:
    a, b = (str(p) for p in tiny_pngs)
    out = tmp_path / "out.npy"
    # no GPU here (and IMAGEFORM_DISABLE_CUDA stands for one that is absent where there is)
    for argv in (
        ["convert", a, "-o", str(out), "--to", "lab"],
        ["white-balance", a, "-o", str(out)],
        ["delta-e", a, b],
        ["batch", "convert", str(tiny_pngs[0].parent / "*.png"), "-o", str(tmp_path / "b")],
    ):
        proc = _cli([*argv, "--device", "cuda"], IMAGEFORM_DISABLE_CUDA="1")
        assert proc.returncode == 1, proc.stdout + proc.stderr
        err = [ln for ln in proc.stderr.strip().splitlines() if ln.strip()]
        assert len(err) == 1 and "--device cuda" in err[0], proc.stderr
        assert not out.exists() and not (tmp_path / "b").exists()


def check_pointwise_cli(
    tiny_pngs: tuple[Path, Path], tmp_path: Path, gpu_env: dict[str, str]
) -> None:
    """A tiny image through ``--device cuda`` gives ``--device cpu``'s numbers.

    ``gpu_env`` is the environment of the CUDA runs: numba's simulator here, ``{}`` on a
    real GPU (``test_cuda_cli_device.py``).
    """
    import json

    a, b = (str(p) for p in tiny_pngs)
    runs = {
        "lab": ["convert", a, "--to", "lab"],
        "gray": ["convert", a, "--to", "gray"],  # no kernel: the CPU, with a note
        "wb": ["white-balance", a, "--method", "shades-of-gray"],
    }
    for name, argv in runs.items():
        got = {}
        for dev, env in (("cpu", {}), ("cuda", gpu_env)):
            out = tmp_path / f"{name}-{dev}.npy"
            proc = _cli([*argv, "-o", str(out), "--device", dev, "--json"], **env)
            assert proc.returncode == 0, proc.stdout + proc.stderr
            assert json.loads(proc.stdout)["device"] == dev
            got[dev] = np.load(out)
            if dev == "cuda":  # a note where no kernel ran (the gray route has none)
                assert ("has no GPU kernel" in proc.stderr) == (name == "gray"), proc.stderr
                assert "kernels are off" not in proc.stderr, proc.stderr
        assert got["cuda"].dtype == got["cpu"].dtype and got["cuda"].shape == got["cpu"].shape
        atol = 1e-3 if name == "lab" else 1e-5  # float32: L* up to 100, the others up to 1
        np.testing.assert_allclose(got["cuda"], got["cpu"], atol=atol, rtol=0, err_msg=name)
    de = {}
    for dev, env in (("cpu", {}), ("cuda", gpu_env)):
        proc = _cli(["delta-e", a, b, "--device", dev, "--json"], **env)
        assert proc.returncode == 0, proc.stdout + proc.stderr
        assert "no GPU kernel" not in proc.stderr, proc.stderr
        assert "kernels are off" not in proc.stderr, proc.stderr
        de[dev] = json.loads(proc.stdout)
    assert de["cuda"]["pixels"] == 35
    for key in ("mean", "max"):
        assert abs(de["cuda"][key] - de["cpu"][key]) <= 1e-3, (key, de)


def test_pointwise_device_cuda_under_simulator(
    tiny_pngs: tuple[Path, Path], tmp_path: Path
) -> None:
    check_pointwise_cli(tiny_pngs, tmp_path, {"NUMBA_ENABLE_CUDASIM": "1"})


# --- float32's fast approximations (issue 29) ------------------------------------------------
#
# The float32 kernels use the GPU's approximate instructions (imageform._cuda.scalar: the
# table above _EXACT); the CPU twin and the simulator emulate each at twice its documented
# bound. These checks run here on the emulation and, with the same data and bounds, on a GPU
# (test_cuda_device.py): each primitive within its bound (the documented one on a GPU, twice
# it here), the Newton-refined roots within a few ulp, and the float32 kernels against
# NumPy's float64 result of the same float32 input within F32_VS_F64.

#: float32 kernel against NumPy float64 (the float32 input upcast): atol, rtol. Measured with
#: the emulated worst case on 100 000 pixels: L* 1.9e-5, a* 7.1e-5, b* 3.7e-5 (NumPy's own
#: float32 path: 4.5e-5, 1.6e-4, 8.3e-5); CIEDE2000 at most 31 % of this bound.
F32_VS_F64 = (2e-4, 1e-5)
F32_ROUTES = [("srgb", "lab"), ("lab", "srgb"), ("srgb", "linear_srgb"), ("prophoto", "luv")]
F32_DELTA_E: list[tuple[str, tuple[float, ...], Any]] = [
    ("de76", (), c.delta_e_cie76),
    ("de94", (1.0, 1.0, 1.0, 0.045, 0.015), c.delta_e_cie94),
    ("decmc", (2.0, 1.0), c.delta_e_cmc),
    ("de00", (1.0, 1.0, 1.0), c.delta_e_ciede2000),
]


def f32_sample(n: int = 4096) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """sRGB pixels (uniform, 8-bit codes, primaries, the curve's joins) and two Lab images."""
    rng = np.random.default_rng(2029)
    rgb = rng.uniform(0.0, 1.0, (n, 3))
    rgb[: n // 4] = rng.integers(0, 256, (n // 4, 3)) / 255.0
    rgb[:8] = [
        [0.0, 0.0, 0.0],
        [1.0, 1.0, 1.0],
        [0.5, 0.5, 0.5],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.04045, 0.0031308, 0.9],
        [0.0404, 0.0405, 0.05],
    ]
    lab1 = np.asarray(c.convert(rgb, "srgb", "lab"))
    near = np.clip(rgb + rng.normal(0.0, 0.03, rgb.shape), 0.0, 1.0)
    lab2 = np.asarray(c.convert(near, "srgb", "lab"))
    lab2[n // 2 :] = np.asarray(c.convert(rng.uniform(0.0, 1.0, (n - n // 2, 3)), "srgb", "lab"))
    return rgb, lab1, lab2


def _ulp_bound(k: float) -> Any:
    return lambda x, ref: k * np.spacing(np.abs(ref).astype(np.float32)).astype(np.float64)


def _lg2_bound(x: np.ndarray, ref: np.ndarray) -> np.ndarray:
    ulp = 2.0 * np.spacing(np.abs(ref).astype(np.float32)).astype(np.float64)
    return np.where((x >= 0.5) & (x <= 2.0), 2.0**-22, ulp)


def _exp_bound(x: np.ndarray, ref: np.ndarray) -> np.ndarray:
    ulp = np.spacing(np.abs(ref).astype(np.float32)).astype(np.float64)
    return (2.0 + np.floor(np.abs(1.173 * x))) * ulp


_G = np.geomspace
_TH = np.linspace(-np.pi, np.pi, 4001)[1:-1]  # the unit circle (atan2's +-180 cut left out)


def _deg_bound(x: np.ndarray, ref: np.ndarray) -> float:
    return 6e-5


#: (helper, arguments (float32 grids), float64 reference, documented bound of |error|)
APPROX_CASES: list[tuple[str, tuple[np.ndarray, ...], Any, Any]] = [
    ("_lg2", (_G(1e-6, 1e6, 4001),), np.log2, _lg2_bound),
    ("_ex2", (np.linspace(-20.0, 20.0, 4001),), np.exp2, _ulp_bound(2.0)),
    ("_div", (np.linspace(-50.0, 50.0, 4001), _G(1e-3, 1e5, 4001)), np.divide, _ulp_bound(2.0)),
    ("_rsqrt", (_G(1e-8, 1e8, 4001),), lambda x: 1.0 / np.sqrt(x), _ulp_bound(2.0)),
    ("_exp", (np.linspace(-30.0, 0.0, 4001),), np.exp, _exp_bound),
    ("_sin", (np.linspace(-np.pi, np.pi, 4001),), np.sin, lambda x, r: 2.0**-21.41),
    ("_cos", (np.linspace(-np.pi, np.pi, 4001),), np.cos, lambda x, r: 2.0**-21.19),
    # the Newton-refined roots: measured 0.91, 2.06, 1.06 ulp with the emulated worst case
    ("_cbrt", (_G(216.0 / 24389.0, 4.0, 4001),), np.cbrt, _ulp_bound(1.5)),
    ("_pow24", (_G(0.0904, 4.0, 4001),), lambda u: u**2.4, _ulp_bound(3.0)),
    ("_pow512", (_G(0.0031308, 4.0, 4001),), lambda x: x ** (1.0 / 2.4), _ulp_bound(2.0)),
    # CIEDE2000's mean hue in degrees (a polynomial, no emulation): 6e-5 degrees (4 ulp of
    # 180 in float32; atan2f's result times 180/pi rounds to 1-2 of them too)
    ("_atan2d", (np.sin(_TH), np.cos(_TH)), lambda y, x: np.degrees(np.arctan2(y, x)), _deg_bound),
]
#: the primitives (not the refined roots): the emulation carries twice their bound
EMULATED = ("_lg2", "_ex2", "_div", "_rsqrt", "_exp", "_sin", "_cos")


def approx_errors(name: str, got: np.ndarray, args: tuple[np.ndarray, ...]) -> np.ndarray:
    """|error| / documented bound of helper ``name``'s float32 results ``got`` on ``args``."""
    case = next(cs for cs in APPROX_CASES if cs[0] == name)
    xs = [np.asarray(a, np.float32).astype(np.float64) for a in args]
    ref = case[2](*xs)
    return np.abs(np.asarray(got, np.float64) - ref) / case[3](xs[0], ref)


def _twin_helper(name: str) -> Any:
    import numba

    from imageform._cuda.scalar import functions

    fn = functions("float32", "cpu")[name]
    if name in ("_div", "_atan2d"):

        @numba.njit
        def two(x: np.ndarray, y: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover
            for i in range(x.size):
                out[i] = fn(x[i], y[i])

        return two

    @numba.njit
    def one(x: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover - compiled
        for i in range(x.size):
            out[i] = fn(x[i])

    return one


@pytest.mark.parametrize("name", [cs[0] for cs in APPROX_CASES])
def test_emulated_approximations_within_their_bounds(name: str) -> None:
    """The emulation carries at least each bound somewhere (it is not the exact function) and
    at most twice the bound's largest relative size (n ulp: n 2^-23 of the result, up to 2n
    ulp); the refined roots stay within their few ulp under it."""
    args = next(cs[1] for cs in APPROX_CASES if cs[0] == name)
    xs = [np.asarray(a, np.float32) for a in args]
    out = np.empty_like(xs[0])
    _twin_helper(name)(*xs, out)
    ratio = approx_errors(name, out, tuple(xs))
    if name in EMULATED:
        assert 1.0 <= ratio.max() <= 5.0, ratio.max()  # 4, and the rounding to float32
    else:
        assert ratio.max() <= 1.0, ratio.max()


@pytest.mark.parametrize(("src", "dst"), F32_ROUTES)
def test_twin_float32_against_float64(src: str, dst: str) -> None:
    rgb = f32_sample()[0]
    x = np.asarray(c.convert(rgb, "srgb", src)).astype(np.float32)
    route = path(src, dst)
    got = run_chain_twin(x, _kernel_steps(route, _with_white(route, {})))
    ref = np.asarray(c.convert(x.astype(np.float64), src, dst))
    np.testing.assert_allclose(got, ref, atol=F32_VS_F64[0], rtol=F32_VS_F64[1])


@pytest.mark.parametrize(("name", "params", "fn"), F32_DELTA_E, ids=[d[0] for d in F32_DELTA_E])
def test_twin_delta_e_float32_against_float64(
    name: str, params: tuple[float, ...], fn: Any
) -> None:
    _, lab1, lab2 = f32_sample()
    a, b = lab1.astype(np.float32), lab2.astype(np.float32)
    ps = list(params)
    if name == "de00":
        ps.append(float(np.finfo(np.float32).smallest_normal) ** 0.5)
    got = run_delta_e_twin(a, b, name, ps)
    ref = np.asarray(fn(a.astype(np.float64), b.astype(np.float64)))
    np.testing.assert_allclose(got, ref, atol=F32_VS_F64[0], rtol=F32_VS_F64[1])


_COLOUR_PTX = r"""
import sys, types
sys.path.insert(0, ".")
try:
    import numba.cuda.dispatcher as d
    from numba import cuda
    d.get_current_device = lambda: types.SimpleNamespace(compute_capability=(9, 0))
    dev = cuda.jit(device=True)(lambda x: x + 1.0)
    def probe(a):
        a[0] = dev(a[0])
    from numba import types as T
    cuda.compile_ptx(probe, (T.float64[::1],), cc=(9, 0))
except Exception as exc:  # no NVVM, or device functions that want a driver
    print("SKIP", type(exc).__name__)
    sys.exit(0)
from numba import types as T
from imageform._cuda import color as cc
from imageform._cuda.scalar import DELTA_E
from imageform.color.convert import _kernel_steps, path
from tests.backends.test_cuda_kernels import F32_ROUTES, _with_white
def kinds(ptx):
    code = [ln for ln in ptx.splitlines() if ".param" not in ln]  # de76's unused float64
    # rcp.approx.ftz.f64: the seed of libdevice's IEEE float64 division and pow, not ours
    approx = ptx.replace("rcp.approx.ftz.f64", "")
    return ("approx" if ".approx" in approx else "exact",
            "f64" if any(".f64" in ln for ln in code) else "no-f64")
for dt, nb in (("float32", T.float32), ("float64", T.float64)):
    for src, dst in F32_ROUTES:
        route = path(src, dst)
        names, vals = cc._chain_params(_kernel_steps(route, _with_white(route, {})), dt)
        sig = (T.Array(nb, 2, "C"), T.Array(nb, 2, "C"), T.int64) + (nb,) * len(vals)
        ptx = cuda.compile_ptx(cc._kernel(names, dt).py_func, sig, cc=(9, 0))[0]
        print("ok", dt, f"{src}->{dst}", *kinds(ptx))
    for name, k in DELTA_E.items():
        arr = T.Array(nb, 2, "C")
        sig = (arr, arr, T.Array(nb, 1, "C"), T.int64) + ((nb,) * k if k else (T.float64,))
        ptx = cuda.compile_ptx(cc._de_kernel(name, dt).py_func, sig, cc=(9, 0))[0]
        print("ok", dt, name, *kinds(ptx))
"""


def test_colour_ptx_approximates_float32_only() -> None:
    """PTX for sm_90 (NVVM, no GPU): float32 kernels use the fast approximations and no
    float64 instruction; float64 kernels no approximation at all (issue 29)."""
    from tests.backends.test_cuda_geometry_kernels import _run

    proc = _run(["-c", _COLOUR_PTX])
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, out[-4000:]
    if proc.stdout.startswith("SKIP"):
        pytest.skip(f"NVVM not available: {proc.stdout.strip()}")
    lines = [ln.split() for ln in proc.stdout.splitlines() if ln.startswith("ok ")]
    assert len(lines) == 2 * (len(F32_ROUTES) + 4), out
    for _, dt, name, approx, f64 in lines:
        if dt == "float64":
            assert approx == "exact", name
        else:
            assert f64 == "no-f64", name
            assert approx == ("exact" if name == "de76" else "approx"), name
