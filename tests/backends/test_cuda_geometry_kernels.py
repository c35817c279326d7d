"""The geometry, demosaicing and raw-development CUDA kernels without a GPU (issue 29).

- :func:`test_simulator_check`: ``cuda_sim_check.py`` in a fresh interpreter with
  ``NUMBA_ENABLE_CUDASIM=1`` (numba reads it once, at its first import): every public function
  that dispatches to :mod:`imageform._cuda.geometry` or :mod:`imageform._cuda.demosaic`, and
  ``develop(device="cuda")``, gives the NumPy path's numbers with one kernel launch per call.
- :func:`test_kernels_compile_for_hopper`: every kernel, float32 and float64, compiled to PTX
  for ``sm_90`` by numba's CUDA target and NVVM (no device needed; skipped where NVVM is not
  installed): what the simulator cannot check (typing and lowering on the real target), with
  the float32 demosaicing and development kernels free of float64 instructions and the image
  kernels free of 64-bit integer divisions. The demosaicing kernels are compiled for the
  block ``launch_rows`` launches (:func:`test_quad_kernels_know_the_launch_block`).
- NumPy calls never import numba's CUDA target; ``imageform develop --device cuda`` and
  ``imageform batch develop --device cuda`` refuse in one line, non-zero, where no GPU is
  usable, and develop a raw file through the kernel under the simulator.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
CHECK = Path(__file__).with_name("cuda_sim_check.py")


def _env(**extra: str) -> dict[str, str]:
    env = dict(os.environ)
    env.pop("IMAGEFORM_DISABLE_CUDA", None)
    env.pop("NUMBA_ENABLE_CUDASIM", None)
    env["PYTHONPATH"] = os.pathsep.join(
        [str(ROOT / "src"), str(ROOT), *filter(None, [env.get("PYTHONPATH", "")])]
    )
    env.update(extra)
    return env


def _run(args: list[str], **extra: str) -> subprocess.CompletedProcess[str]:
    # under --cov, modules and scripts run by the simulator count towards CI's coverage too:
    # a parallel-mode data file in the root, combined by pytest-cov at the end
    if (args[0] == "-m" or args[0].endswith(".py")) and _measuring_coverage():
        args = ["-m", "coverage", "run", "--parallel-mode", *args]
    return subprocess.run(
        [sys.executable, *args],
        cwd=ROOT,
        env=_env(**extra),
        capture_output=True,
        text=True,
        timeout=600,
    )


def _measuring_coverage() -> bool:
    try:
        import coverage
    except ImportError:  # pragma: no cover - coverage is a test dependency
        return False
    return coverage.Coverage.current() is not None


def test_simulator_check() -> None:
    proc = _run([str(CHECK)], NUMBA_ENABLE_CUDASIM="1")
    tail = (proc.stdout + proc.stderr)[-4000:]
    assert proc.returncode == 0, tail
    lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("ok ")]
    assert all(ln.endswith("launches=1") for ln in lines), tail
    names = " ".join(lines)
    for op in (
        "distort[",
        "undistort[",
        "project_points_distorted[",
        "project_points[",
        "remap_bilinear[",
        "undistort_image[",
        "demosaic[bilinear",
        "demosaic[malvar",
        "develop[",
        "fallback",
    ):
        assert op in names, f"{op} not checked: {tail}"
    assert len(lines) >= 50, tail


_PTX = r"""
import re, sys, types
try:
    import numba.cuda.dispatcher as d
    from numba import cuda, types as T
    # the device functions are compiled for the current device's compute capability:
    # name one (no driver needed to make PTX)
    d.get_current_device = lambda: types.SimpleNamespace(compute_capability=(9, 0))
    cuda.compile_ptx(lambda a: None, (T.float64[::1],), cc=(9, 0))
except Exception as exc:  # no NVVM (libnvvm) on this machine
    print("SKIP", type(exc).__name__, str(exc).splitlines()[0] if str(exc) else "")
    sys.exit(0)
from imageform._cuda import demosaic as dm, demosaic_quads as dq, geometry as g
try:  # a numba CUDA target that wants a driver to compile device functions: cannot check here
    dev = cuda.jit(device=True)(lambda x: x + 1.0)

    def probe(a):
        a[0] = dev(a[0])

    cuda.compile_ptx(probe, (T.float64[::1],), cc=(9, 0))
except Exception as exc:
    if type(exc).__name__ != "CudaSupportError":
        raise
    print("SKIP", type(exc).__name__, "(device functions need a driver here)")
    sys.exit(0)
A = lambda dt, nd, layout="C": T.Array(dt, nd, layout)
f64, f32, b1, i64 = T.float64, T.float32, T.boolean, T.int64
kg, kd, kq = g._kernels(), dm._kernels(), dq.kernels()
def show(name, ptx):
    f = "f64-ops" if ".f64" in ptx else "no-f64"
    div = "div64" if re.search(r"\b(div|rem)\.[su]64", ptx) else "no-div64"
    print("ok", name, f, div)
for dt in (f64, f32):
    sigs = {
        "project": (A(dt, 2, "A"), A(dt, 2, "A"), A(dt, 2, "A"), A(dt, 1, "A"), *[f64] * 8, b1,
                    A(dt, 2), A(b1, 1)),
        "distort": (A(dt, 2, "A"), *[f64] * 8, A(dt, 2)),
        "undistort": (A(dt, 2, "A"), *[f64] * 8, i64, f64, A(dt, 2), A(b1, 1)),
        "remap": (A(dt, 4, "A"), A(f64, 3, "A"), f64, A(dt, 4)),
        "undistort_image": (A(dt, 4, "A"), A(f64, 2), A(f64, 2), *[f64] * 8, f64, A(dt, 4)),
    }
    for name, sig in sigs.items():
        show(f"{name}[{dt}]", cuda.compile_ptx(kg.py[name], sig, cc=(9, 0))[0])
    for method in ("bilinear", "malvar"):
        name = f"{method}{32 if dt == f32 else 64}"
        for layout in ("C", "A"):  # a contiguous mosaic, a strided view
            sig = (A(dt, 3, layout), i64, i64, b1, A(dt, 3))
            show(f"{name}[{layout}]", cuda.compile_ptx(kq.py[name], sig, cc=(9, 0))[0])
sig = (A(T.uint16, 2), A(f32, 2), i64, i64, i64, A(f32, 2), A(f32, 1), b1, i64, A(f32, 3),
       A(T.uint16, 3))
show("develop", cuda.compile_ptx(kd.py["develop"], sig, cc=(9, 0))[0])
"""


def test_kernels_compile_for_hopper() -> None:
    proc = _run(["-c", _PTX])
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, out[-4000:]
    if proc.stdout.startswith("SKIP"):
        pytest.skip(f"NVVM not available: {proc.stdout.strip()}")
    lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("ok ")]
    assert len(lines) == 19, out
    # float32 data is demosaiced and developed in float32, as on the CPU
    for name in ("bilinear32[C]", "bilinear32[A]", "malvar32[C]", "malvar32[A]", "develop"):
        assert f"ok {name} no-f64 no-div64" in lines, out
    # the image kernels find their pixel from a 2-D grid: no 64-bit division (slow on a GPU)
    for ln in lines:
        if any(k in ln for k in ("remap", "undistort_image", "bilinear", "malvar", "develop")):
            assert ln.endswith("no-div64"), ln


def test_quad_kernels_know_the_launch_block(monkeypatch: pytest.MonkeyPatch) -> None:
    """The demosaicing kernels are compiled for the block ``launch_rows`` launches.

    Their staging tile's size and offsets are compile-time constants
    (:func:`imageform._cuda.demosaic_quads.block_shape`); another block would store wrong
    values, so a change of ``launch_rows``'s blocks must change that function too.
    """
    from imageform._cuda import _launch, demosaic_quads

    seen = []
    monkeypatch.setattr(_launch, "_launch", lambda k, grid, block, args: seen.append(block))
    for rows, cols in ((2, 2), (540, 960), (1080, 1920), (3, 10**6), (10**6, 3)):
        _launch.launch_rows(None, rows, cols)
    # the launcher passes (x, y, z) blocks (z = 1) since the one-pass launch
    assert {tuple(b[:2]) for b in seen} == {demosaic_quads.block_shape()}
    assert all(len(b) == 2 or b[2] == 1 for b in seen)
    assert demosaic_quads.block_shape()[0] == 32  # a warp along a row: its barrier is a warp's


def test_numpy_calls_never_import_numba_cuda() -> None:
    code = (
        "import sys, numpy as np\n"
        "from imageform.geometry import BrownConrady, project_points, remap_bilinear\n"
        "from imageform.sensor import demosaic\n"
        "BrownConrady(k1=-0.1).undistort(np.zeros((4, 2)))\n"
        "project_points(np.ones((5, 3)), np.eye(3))\n"
        "remap_bilinear(np.zeros((4, 4)), np.zeros((2, 2, 2)))\n"
        "demosaic(np.zeros((4, 4)), 'RGGB', 'malvar')\n"
        "assert 'numba.cuda' not in sys.modules, 'numba.cuda imported'\n"
    )
    proc = _run(["-c", code])
    assert proc.returncode == 0, (proc.stdout + proc.stderr)[-3000:]


@pytest.fixture(scope="module")
def tiny_dng(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from imageform.io import write_dng

    rng = np.random.default_rng(7)
    path = tmp_path_factory.mktemp("raw") / "tiny.dng"
    mosaic = rng.integers(100, 4000, size=(12, 16)).astype(np.uint16)
    cm = [[1.2, -0.3, -0.1], [-0.4, 1.3, 0.1], [-0.05, 0.2, 0.6]]
    write_dng(path, mosaic, black_level=64, white_level=4095, color_matrix=cm)
    return path


def test_develop_device_cuda_refused_in_one_line(tiny_dng: Path, tmp_path: Path) -> None:
    out = tmp_path / "out.png"
    # no GPU here (and IMAGEFORM_DISABLE_CUDA stands for one that is absent where there is)
    for cmd in (
        ["develop", str(tiny_dng), "-o", str(out), "--device", "cuda"],
        ["batch", "develop", str(tiny_dng.parent / "*.dng"), "-o", str(tmp_path / "b")]
        + ["--device", "cuda"],
    ):
        proc = _run(["-m", "imageform", *cmd], IMAGEFORM_DISABLE_CUDA="1")
        assert proc.returncode != 0, proc.stdout + proc.stderr
        err = [ln for ln in proc.stderr.strip().splitlines() if ln.strip()]
        assert len(err) == 1 and "--device cuda" in err[0], proc.stderr
        assert not out.exists()


def check_develop_cli(tiny_dng: Path, tmp_path: Path, gpu_env: dict[str, str]) -> None:
    """``develop --device cuda`` (and ``batch develop``) give ``--device cpu``'s numbers.

    ``gpu_env`` is the environment of the CUDA runs: numba's simulator here, ``{}`` on a
    real GPU (``test_cuda_cli_device.py``).
    """
    out_gpu, out_cpu = tmp_path / "gpu.npy", tmp_path / "cpu.npy"
    for out, dev, extra in ((out_cpu, "cpu", {}), (out_gpu, "cuda", gpu_env)):
        # imageform's own DNG reader (LibRaw refuses so small a frame)
        argv = ["develop", str(tiny_dng), "-o", str(out), "--device", dev, "--json"]
        code = "import sys; sys.modules['rawpy'] = None\nfrom imageform.cli import main\n"
        code += f"sys.exit(main({argv!r}))"
        proc = _run(["-c", code], **extra)
        assert proc.returncode == 0, proc.stdout + proc.stderr
        assert f'"device": "{dev}"' in proc.stdout
        assert "kernels are off" not in proc.stderr, proc.stderr
    gpu, cpu = np.load(out_gpu), np.load(out_cpu)
    assert gpu.shape == cpu.shape == (12, 16, 3)
    np.testing.assert_allclose(gpu, cpu, atol=2e-6, rtol=0)


def test_develop_device_cuda_under_simulator(tiny_dng: Path, tmp_path: Path) -> None:
    check_develop_cli(tiny_dng, tmp_path, {"NUMBA_ENABLE_CUDASIM": "1"})


def test_develop_api_refuses_cuda_without_a_device(monkeypatch: pytest.MonkeyPatch) -> None:
    from imageform._cuda import _launch
    from imageform.errors import InvalidInputError
    from imageform.io import RawImage, develop

    monkeypatch.setenv("IMAGEFORM_DISABLE_CUDA", "1")
    monkeypatch.setattr(_launch, "_USE", [None])  # read again (once), put back after
    raw = RawImage(
        mosaic=np.full((4, 4), 1000, np.uint16),
        black_level=np.zeros((2, 2)),
        white_level=4095.0,
        cfa_pattern="RGGB",
        white_balance=np.ones(3),
        xyz_to_camera=None,
        camera_to_srgb=np.eye(3),
        calibration_illuminant="D65",
    )
    with pytest.raises(InvalidInputError, match="device='cuda': no CUDA device") as info:
        develop(raw, device="cuda")
    assert "\n" not in str(info.value)
    with pytest.raises(InvalidInputError, match="unknown device"):
        develop(raw, device="tpu")
    assert develop(raw, device="cpu").image.shape == (4, 4, 3)
