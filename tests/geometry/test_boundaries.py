"""Hardened boundaries of imageform.geometry (issue 16).

The sweep (:mod:`tests.geometry.boundary_sweep`) calls every public callable with malformed
values one parameter at a time; here a seeded sample of it runs in every test run and the
whole of it under ``-m slow``. The named regressions below are the cases the issue lists.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from imageform.errors import ImageformError, InvalidInputError
from imageform.geometry import (
    Camera,
    CheckerboardResult,
    Intrinsics,
    LineSegments,
    calibrate_camera,
    checkerboard_points,
    detect_line_segments,
    detect_vanishing_points,
    find_checkerboard,
    project_points,
    refine_corners,
    remap_bilinear,
    rvec_to_matrix,
    solve_pnp,
    to_homogeneous,
    undistort_image,
    undistortion_map,
    unproject,
    weak_perspective_project,
)
from tests.geometry.boundary_sweep import FAIL_CLASSES, baseline_failures, run_sweep

K = np.array([[800.0, 0.0, 320.0], [0.0, 800.0, 240.0], [0.0, 0.0, 1.0]])
REPO = Path(__file__).resolve().parents[2]


def _one_line(exc: pytest.ExceptionInfo[BaseException], *names: str) -> None:
    msg = str(exc.value)
    assert "\n" not in msg and len(msg) <= 200, msg
    for name in names:
        assert name in msg, (name, msg)


def _failures(outcomes: list) -> list[str]:
    return [
        f"{o.kind} {o.case}({o.param}={o.value}): {o.detail}"
        for o in outcomes
        if o.kind in FAIL_CLASSES
    ]


# --- the sweep ------------------------------------------------------------------------------


def test_sweep_baselines_are_valid() -> None:
    """Every callable's unmodified arguments give a finite result (the sweep varies one
    parameter at a time around them)."""
    assert baseline_failures() == []


def test_sweep_sample_is_clean() -> None:
    """A seeded sample of 12 malformed calls per public callable: every one a finite result
    or a one-line ImageformError/TypeError naming its parameter."""
    outcomes = run_sweep(full=True, sample=12, seed=16, guard=20.0)
    assert len({o.case for o in outcomes}) >= 80
    assert _failures(outcomes) == []


@pytest.mark.slow
def test_sweep_full_is_clean() -> None:
    outcomes = run_sweep(full=True, guard=30.0)
    assert len(outcomes) > 8000
    assert _failures(outcomes) == []


# --- silent wrong results -------------------------------------------------------------------


@pytest.mark.parametrize(
    "depth", [np.full(3, 5.0) + 1j, np.array([5.0, 5.0, 5.0], dtype=object), np.array(["5"] * 3)]
)
def test_unproject_depth_complex_object_string_refused(depth: np.ndarray) -> None:
    uv = np.array([[1.0, 2.0], [3.0, 4.0], [5.0, 6.0]])
    with pytest.raises(InvalidInputError) as exc:
        unproject(uv, depth, K)
    _one_line(exc, "depth")
    with pytest.raises(InvalidInputError) as exc:
        Camera(K).unproject(uv, depth)
    _one_line(exc, "depth")


def test_unproject_depth_of_the_wrong_length_refused() -> None:
    with pytest.raises(InvalidInputError) as exc:
        unproject(np.zeros((4, 2)), np.ones(3), K)
    _one_line(exc, "depth", "(4,)", "(3,)")


def test_calibrate_camera_K_init_refused_cleanly() -> None:
    board = checkerboard_points((5, 4), 0.1)
    views = [
        project_points(board, K, rvec_to_matrix(np.array(r)), np.array([-0.2, -0.15, 1.0])).uv
        for r in ((0.2, -0.1, 0.0), (-0.25, 0.2, 0.1), (0.1, 0.3, -0.1), (-0.3, -0.2, 0.05))
    ]
    good = calibrate_camera([board] * 4, views, (640, 480), K_init=K)
    assert np.all(np.isfinite(good.K))
    bad = {
        "complex": K + 1j,
        "object": K.astype(object),
        "singular": np.zeros((3, 3)),
        "nan": np.where(np.eye(3, dtype=bool), np.nan, K),
        "misshaped": K[:2],
        "scalar": 800.0,
        "negative focal": np.diag([-800.0, 800.0, 1.0]),
    }
    for label, K_init in bad.items():
        with pytest.raises(InvalidInputError) as exc:
            calibrate_camera([board] * 4, views, (640, 480), K_init=K_init)
        _one_line(exc, "K_init")
        assert label


def test_to_homogeneous_w_none_or_nan_refused() -> None:
    for w in (None, math.nan, math.inf, "1", 1 + 0j, [1.0, 2.0]):
        with pytest.raises(InvalidInputError) as exc:
            to_homogeneous([[1.0, 2.0]], w=w)  # type: ignore[arg-type]
        _one_line(exc, "w")
    assert to_homogeneous([[1.0, 2.0]], w=np.float32(0.0)).tolist() == [[1.0, 2.0, 0.0]]


def test_to_homogeneous_shape_message_is_short() -> None:
    with pytest.raises(InvalidInputError) as exc:
        to_homogeneous(5.0)
    _one_line(exc, "points", "n >= 1")


def test_line_segments_validated() -> None:
    e = np.array([[[0.0, 0.0], [10.0, 0.0]], [[0.0, 0.0], [0.0, 10.0]]])
    seg = LineSegments(e.tolist(), [1, 1], [-2.0, -np.inf])  # lists, ints and -inf accepted
    assert seg.endpoints.dtype == np.float64 and len(seg) == 2
    cases = [
        (np.array([["a", "b"], ["c", "d"]]), np.ones(2), np.zeros(2), "endpoints"),
        (e[:, :, :1], np.ones(2), np.zeros(2), "endpoints"),
        (e, np.ones(3), np.zeros(2), "widths"),
        (e, np.ones(2), np.zeros(1), "log10_nfa"),
        (e, np.array([1.0, np.nan]), np.zeros(2), "widths"),
        (np.where(e == 10.0, np.nan, e), np.ones(2), np.zeros(2), "endpoints"),
    ]
    for endpoints, widths, nfa, name in cases:
        with pytest.raises(InvalidInputError) as exc:
            LineSegments(endpoints, widths, nfa)
        _one_line(exc, name)


@pytest.mark.parametrize(
    "bad",
    [np.zeros((3, 3)), np.diag([800.0, 0.0, 1.0]), np.where(np.eye(3) > 0, np.nan, 0.0)],
)
def test_bad_K_refused_where_project_points_refuses_it(bad: np.ndarray) -> None:
    pts = np.array([[0.0, 0.0, 5.0], [1.0, 0.0, 6.0]])
    with pytest.raises(InvalidInputError):
        project_points(pts, bad)
    with pytest.raises(InvalidInputError) as exc:
        weak_perspective_project(pts, bad)
    _one_line(exc, "K")
    with pytest.raises(InvalidInputError):
        Camera(bad)
    with pytest.raises(InvalidInputError):
        Intrinsics.from_matrix(bad)


def test_negative_focal_refused_by_camera_and_intrinsics() -> None:
    neg = np.diag([-800.0, 800.0, 1.0])
    with pytest.raises(InvalidInputError, match="fx > 0"):
        Camera(neg)
    with pytest.raises(InvalidInputError, match="fx > 0"):
        Intrinsics.from_matrix(neg)
    with pytest.raises(InvalidInputError, match="fx > 0"):
        Intrinsics(-800.0, 800.0, 320.0, 240.0)


def test_intrinsics_from_sensor_refuses_bad_sizes() -> None:
    for sensor in ((6.4, 4.8, 1.0), (6.4,), (0, 0), "6.4x4.8", np.float64(6.4)):
        with pytest.raises(InvalidInputError) as exc:
            Intrinsics.from_sensor(
                focal_length_mm=8.0, sensor_size_mm=sensor, image_size=(640, 480)
            )
        _one_line(exc, "sensor_size_mm")
    for size in ((0, 0), (640,), (640, 480, 3), (640.0, 480)):
        with pytest.raises(InvalidInputError) as exc:
            Intrinsics.from_sensor(focal_length_mm=8.0, sensor_size_mm=(6.4, 4.8), image_size=size)
        _one_line(exc, "image_size")
    ok = Intrinsics.from_sensor(
        focal_length_mm=8.0, sensor_size_mm=(6.4, 4.8), image_size=(np.int64(640), 480)
    )
    assert ok.fx == pytest.approx(800.0)


def test_rvec_to_matrix_huge_refused_not_nan() -> None:
    with pytest.raises(InvalidInputError) as exc:
        rvec_to_matrix([1e300, 0.0, 0.0])
    _one_line(exc, "rvec")
    R = rvec_to_matrix([1e50, 0.0, 0.0])  # large but computable: a rotation
    assert np.all(np.isfinite(R)) and np.allclose(R @ R.T, np.eye(3), atol=1e-9)


# --- raw exceptions -------------------------------------------------------------------------


def test_tuple_arguments_of_the_wrong_length() -> None:
    for shape in ((40,), (40, 50, 3), (), 40, (40.0, 50)):
        with pytest.raises(InvalidInputError) as exc:
            undistortion_map(shape, K, None)  # type: ignore[arg-type]
        _one_line(exc, "shape")
    with pytest.raises(InvalidInputError) as exc:
        undistort_image(np.zeros((8, 8)), K, None, out_shape=(8,))
    _one_line(exc, "out_shape")


def test_detect_vanishing_points_wrong_segments_type() -> None:
    for segments in (np.zeros((4, 4)), "segments", [(0, 0, 1, 1)] * 3, 5):
        with pytest.raises((TypeError, ImageformError)) as exc:
            detect_vanishing_points(segments=segments, image_size=(64, 48))
        _one_line(exc, "segments")


def test_counts_beyond_int_and_inf_refused() -> None:
    X = np.random.default_rng(0).uniform(-1, 1, (8, 3))
    uv = project_points(X, K, None, np.array([0.0, 0.0, 5.0])).uv
    for bad in (math.inf, 1e308, 2**70, 2.5, "20", True):
        with pytest.raises(InvalidInputError) as exc:
            solve_pnp(X, uv, K, max_iter=bad, refine=True)  # type: ignore[arg-type]
        _one_line(exc, "max_iter")
    img = np.random.default_rng(1).uniform(0, 1, (32, 32))
    for bad in (math.inf, 1e308, -1.0):
        with pytest.raises(InvalidInputError) as exc:
            detect_line_segments(img, sigma=bad)
        _one_line(exc, "sigma")
    with pytest.raises(InvalidInputError) as exc:
        Intrinsics(800.0, 800.0, 320.0, 240.0, image_size=(640, 480)).scaled(1e308)
    _one_line(exc, "factor")


def test_numpy_integers_are_integers() -> None:
    X = np.random.default_rng(0).uniform(-1, 1, (8, 3))
    uv = project_points(X, K, None, np.array([0.0, 0.0, 5.0])).uv
    assert solve_pnp(X, uv, K, max_iter=np.int64(5)).valid
    v, u = np.mgrid[0:140, 0:160]
    i, j = (u - 20) // 20, (v - 20) // 20
    dark = (i >= 0) & (i < 6) & (j >= 0) & (j < 5) & ((i + j) % 2 == 0)
    board = np.where(dark, 0.1, 0.9)
    res = find_checkerboard(board, (np.int32(5), np.int64(4)), max_iter=np.int64(10))
    assert res.found
    refined = refine_corners(board, res.corners, half_window=np.int64(3), max_iter=np.int16(5))
    assert refined.corners.shape == res.corners.shape


def test_dask_map_with_numpy_image_refused() -> None:
    da = pytest.importorskip("dask.array")
    img = np.zeros((8, 8))
    m = np.stack(np.meshgrid(np.arange(8.0), np.arange(8.0)), axis=-1)
    with pytest.raises(InvalidInputError) as exc:
        remap_bilinear(img, da.from_array(m, chunks=4))
    _one_line(exc, "map_uv", "image")
    lazy = remap_bilinear(da.from_array(img, chunks=4), m)  # the lazy path: a NumPy map
    assert np.array_equal(lazy.compute(), remap_bilinear(img, m))
    # a lazy K with an eager image: the nine numbers are computed, the result is eager
    eager = undistort_image(img, K, None, new_K=da.from_array(K))
    assert isinstance(eager, np.ndarray)
    assert np.array_equal(eager, undistort_image(img, K, None, new_K=K))


def test_zero_d_tensor_and_huge_int_reach_no_kernel() -> None:
    torch = pytest.importorskip("torch")
    X = np.random.default_rng(0).uniform(-1, 1, (8, 3))
    uv = project_points(X, K, None, np.array([0.0, 0.0, 5.0])).uv
    assert solve_pnp(X, uv, K, max_iter=torch.tensor(5)).valid
    for bad in (torch.tensor(1.5), 2**64):
        with pytest.raises(InvalidInputError):
            solve_pnp(X, uv, K, max_iter=bad)
    board = np.zeros((32, 32))
    with pytest.raises(InvalidInputError):
        refine_corners(board, [[10.0, 10.0]], half_window=2**64)
    with pytest.raises(InvalidInputError):
        refine_corners(board, [[10.0, 10.0]], max_iter=torch.tensor(2.0))


# --- bounds ---------------------------------------------------------------------------------


def test_sizes_checked_against_memory(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("IMAGEFORM_MAX_MEMORY", "64M")
    with pytest.raises(InvalidInputError) as exc:
        undistortion_map((100_000, 100_000), K, None)
    _one_line(exc, "shape", "GiB")
    with pytest.raises(InvalidInputError) as exc:
        undistort_image(np.zeros((8, 8)), K, None, out_shape=(100_000, 100_000))
    _one_line(exc, "out_shape", "GiB")
    with pytest.raises(InvalidInputError) as exc:
        checkerboard_points((100_000, 100_000))
    _one_line(exc, "pattern_size", "GiB")


def test_misshaped_array_refused_before_its_values_are_scanned() -> None:
    """A NaN in an array of the wrong shape: the message is about the shape."""
    bad = np.full((5, 4), np.nan)
    with pytest.raises(InvalidInputError, match=r"shape \(\.\.\., 3\)"):
        project_points(bad, K)
    with pytest.raises(InvalidInputError, match=r"shape \(\.\.\., 3, 3\)"):
        project_points(np.zeros((2, 3)), np.full((3, 4), np.nan))


def test_checkerboard_result_validated() -> None:
    with pytest.raises(InvalidInputError) as exc:
        CheckerboardResult(True, np.zeros((5, 2)), pattern_size=(3, 2))
    _one_line(exc, "corners", "(6, 2)")
    with pytest.raises(InvalidInputError) as exc:
        CheckerboardResult(True, np.full((6, 2), np.nan), pattern_size=(3, 2))
    _one_line(exc, "corners")
    with pytest.raises(InvalidInputError):
        CheckerboardResult("yes", None)  # type: ignore[arg-type]


# --- the numba refinement -------------------------------------------------------------------


def _kernels() -> tuple:
    pytest.importorskip("numba")
    from imageform._kernels.checkerboard import refine_corners_numba, refine_corners_numpy

    return refine_corners_numba, refine_corners_numpy


def test_refinement_kernel_far_and_nan_corners() -> None:
    """Corners beyond int64 range, at inf or NaN: no read outside the image, the start
    kept with status 2 or 4, the kernel and its twin agreeing."""
    numba_k, numpy_k = _kernels()
    v, u = np.mgrid[0:40, 0:40]
    img = (((u // 8) + (v // 8)) % 2).astype(np.float64)
    corners = np.array(
        [[16.2, 15.7], [1e300, 5.0], [-1e300, 5.0], [5.0, 1e19], [np.nan, 5.0], [np.inf, 2.0]]
    )
    for kernel in (numba_k, numpy_k):
        out, status = kernel(img, corners, 3, 3, 30, 1e-3)
        assert np.allclose(out[0], [15.5, 15.5], atol=0.05), out[0]
        assert np.array_equal(out[1:], corners[1:], equal_nan=True)
        assert np.all(status[1:] >= 2)
    a = numba_k(img, corners, 3, 3, 30, 1e-3)
    b = numpy_k(img, corners, 3, 3, 30, 1e-3)
    assert np.array_equal(a[0], b[0], equal_nan=True) or np.allclose(
        a[0], b[0], atol=1e-9, equal_nan=True
    )
    assert np.array_equal(a[1], b[1])


def test_refinement_kernel_stops_on_nan_iteration() -> None:
    """A window whose gradients overflow gives a NaN step: the start is kept (status 2)."""
    numba_k, numpy_k = _kernels()
    v, u = np.mgrid[0:40, 0:40]
    img = (((u // 8) + (v // 8)) % 2).astype(np.float64) * 1e200  # squares overflow to inf
    corners = np.array([[16.2, 15.7]])
    for kernel in (numba_k, numpy_k):
        with np.errstate(all="ignore"):
            out, status = kernel(img, corners, 3, 3, 30, 1e-3)
        assert np.array_equal(out, corners) and status.tolist() == [2]


def _run_bounds_checked(tmp_path: Path, files: list[str], select: str) -> None:
    """``pytest files -k select`` in a fresh interpreter with NUMBA_BOUNDSCHECK=1 (an
    out-of-bounds read raises IndexError there) and an empty numba cache, so that the
    kernels are compiled with the checks."""
    pytest.importorskip("numba")
    env = {
        **os.environ,
        "NUMBA_BOUNDSCHECK": "1",
        "NUMBA_CACHE_DIR": str(tmp_path),
        "PYTHONPATH": os.pathsep.join(
            p for p in (str(REPO / "src"), str(REPO), os.environ.get("PYTHONPATH", "")) if p
        ),
    }
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-x", "-n", "0", "-p", "no:cacheprovider"]
        + files
        + ["-k", select],
        cwd=REPO,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-2000:]
    assert " passed" in done.stdout, done.stdout[-3000:]


BOUNDSCHECKED = pytest.mark.skipif(
    os.environ.get("NUMBA_BOUNDSCHECK") == "1", reason="already bounds-checked"
)


@BOUNDSCHECKED
def test_kernel_tests_pass_with_numba_boundscheck(tmp_path: Path) -> None:
    """The checkerboard refinement kernel's tests under NUMBA_BOUNDSCHECK=1 (issue 16)."""
    _run_bounds_checked(
        tmp_path,
        ["tests/geometry/test_checkerboard_kernels.py", "tests/geometry/test_boundaries.py"],
        "refine_twin or refinement_kernel",
    )


@pytest.mark.slow
@BOUNDSCHECKED
def test_symmetric_kernel_tests_pass_with_numba_boundscheck(tmp_path: Path) -> None:
    """The point-symmetry kernels' twin tests under NUMBA_BOUNDSCHECK=1: the plain and masked
    refinement and ChArUco's (the mask made inside it, every window size in one call; about
    20 s of compilation with the checks): CI runs it with ``-m slow``."""
    _run_bounds_checked(
        tmp_path,
        [
            "tests/geometry/test_checkerboard_symmetric.py",
            "tests/geometry/test_charuco_symmetric.py",
        ],
        "agree or twin",
    )


@pytest.mark.slow
@BOUNDSCHECKED
def test_remap_kernel_tests_pass_with_numba_boundscheck(tmp_path: Path) -> None:
    """The remap and fused-undistort kernels' tests under NUMBA_BOUNDSCHECK=1 (issue 16):
    every dtype and channel count, NaN and edge map entries, non-contiguous and batched
    inputs. Slow (about 40 s of compilation with the checks): CI runs it with ``-m slow``."""
    _run_bounds_checked(
        tmp_path,
        ["tests/geometry/test_remap_fast.py"],
        "remap_kernel_matches_twin or undistort_equals or non_contiguous or keep_dtype or "
        "within_1e6 or one_pixel",
    )
