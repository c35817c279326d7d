"""Hardened boundaries of imageform.geometry found by the fuzz test (issue 16).

Each test pins one class of finding of ``python -m tests.fuzz --only imageform.geometry``:
a raw exception (AttributeError, OverflowError, LinAlgError, numba's TypingError), a
message that does not name the parameter, or one that echoes a 100,000-character value.
Every refusal is one line naming the parameter.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from imageform.errors import DegenerateConfigurationError, ImageformError, InvalidInputError
from imageform.geometry import (
    BrownConrady,
    CalibrationResult,
    checkerboard_points,
    cross_ratio,
    detect_line_segments,
    estimate_homography,
    find_essential_matrix,
    find_fundamental_matrix,
    find_homography,
    horizon_line,
    intersect_lines,
    intrinsics_from_vanishing_points,
    lines_from_segments,
    project_points,
    rectification_map,
    rvec_to_matrix,
    stereo_calibrate,
    stereo_rectify,
)
from imageform.geometry.calibration_zhang import dlt_init, homographies
from imageform.geometry.checkerboard_candidates import find_candidates
from imageform.geometry.lsd import lsd_segments

K = np.array([[800.0, 0.0, 320.0], [0.0, 800.0, 240.0], [0.0, 0.0, 1.0]])
R = rvec_to_matrix([0.0, 0.02, 0.0])
T = np.array([-0.1, 0.0, 0.0])
NOT_ARRAYS = [None, "abc", True, 0, object()]


def _one_line(exc: pytest.ExceptionInfo[BaseException], *names: str) -> None:
    msg = str(exc.value)
    assert "\n" not in msg and len(msg) <= 200, msg
    for name in names:
        assert name in msg, (name, msg)


def _views() -> tuple[list[np.ndarray], list[np.ndarray], list[np.ndarray]]:
    obj = checkerboard_points((5, 4), 0.03)
    left, right = [], []
    for rv, t in (([0.2, 0.1, 0], [-0.05, -0.05, 0.5]), ([-0.1, 0.25, 0.1], [-0.06, -0.04, 0.55])):
        Rk = rvec_to_matrix(rv)
        left.append(np.asarray(project_points(obj, K, Rk, t).uv))
        right.append(np.asarray(project_points(obj, K, R @ Rk, R @ np.asarray(t) + T).uv))
    return [obj, obj], left, right


@pytest.mark.parametrize("bad", NOT_ARRAYS)
def test_stereo_calibrate_names_the_side(bad: object) -> None:
    objs, left, right = _views()
    with pytest.raises(InvalidInputError) as exc:
        stereo_calibrate(objs, bad, right, (640, 480))
    _one_line(exc, "image_points_left")
    with pytest.raises(InvalidInputError) as exc:
        stereo_calibrate(objs, left, bad, (640, 480))
    _one_line(exc, "image_points_right")


@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("max_iter", np.inf),
        ("max_iter", 0),  # None is the model's default budget
        ("max_iter", [1]),
        ("model", "fisheye"),
        ("tol", 1j),
        ("tol", np.nan),
        ("tol", -1.0),
        ("tol", "abc"),
    ],
)
def test_stereo_calibrate_scalars_checked_first(name: str, value: object) -> None:
    objs, left, right = _views()
    with pytest.raises(InvalidInputError) as exc:
        stereo_calibrate(objs, left, right, (640, 480), **{name: value})
    _one_line(exc, name)


@pytest.mark.parametrize("bad", ["abc", np.array([["a"] * 3] * 3), np.full((3, 3), object())])
def test_stereo_rectify_matrices_refused_by_name(bad: object) -> None:
    for name in ("K1", "K2", "R"):
        args = {"K1": K, "K2": K, "R": R}
        with pytest.raises(InvalidInputError) as exc:
            stereo_rectify(
                args["K1"] if name != "K1" else bad,
                None,
                args["K2"] if name != "K2" else bad,
                None,
                (640, 480),
                args["R"] if name != "R" else bad,
                T,
            )
        _one_line(exc, name)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # complex T: refused, never cut to its real part
        with pytest.raises(InvalidInputError) as exc:
            stereo_rectify(K, None, K, None, (640, 480), R, T + 1e-3j)
    _one_line(exc, "T")


@pytest.mark.parametrize("bad", ["abc", True, 0, object()])
def test_distortion_models_refused_by_name(bad: object) -> None:
    with pytest.raises(InvalidInputError) as exc:
        stereo_rectify(K, bad, K, None, (640, 480), R, T)
    _one_line(exc, "distortion1")
    with pytest.raises(InvalidInputError) as exc:
        stereo_rectify(K, BrownConrady(), K, bad, (640, 480), R, T)
    _one_line(exc, "distortion2")
    with pytest.raises(InvalidInputError) as exc:
        rectification_map(K, bad, np.eye(3), K, (8, 6))
    _one_line(exc, "distortion")


def test_rectification_sizes_bounded() -> None:
    # before: numpy's "Maximum allowed dimension exceeded" and a NaN rectification
    with pytest.raises(InvalidInputError) as exc:
        rectification_map(K, None, np.eye(3), K, (10**30, 6))
    _one_line(exc, "image_size")
    with pytest.raises(InvalidInputError) as exc:
        rectification_map(K, None, np.eye(3), K, (100_000, 100_000))
    _one_line(exc, "image_size")
    with pytest.raises(InvalidInputError) as exc:
        stereo_rectify(K, None, K, None, (10**30, 480), R, T)
    _one_line(exc, "image_size")
    for P in ("abc", np.full((3, 4), object())):
        with pytest.raises(InvalidInputError) as exc:
            rectification_map(K, None, np.eye(3), P, (8, 6))
        _one_line(exc, "P")


@pytest.mark.parametrize("bad", NOT_ARRAYS)
def test_calibration_steps_check_their_views(bad: object) -> None:
    objs, left, _ = _views()
    for f in (dlt_init, homographies):
        with pytest.raises(InvalidInputError) as exc:
            f(bad, left)
        _one_line(exc, "object_points")
        with pytest.raises(InvalidInputError) as exc:
            f(objs, bad)
        _one_line(exc, "image_points")


@pytest.mark.parametrize("source", [None, 0, object()])
def test_from_toml_source_type(source: object) -> None:
    with pytest.warns(DeprecationWarning), pytest.raises(TypeError) as exc:
        CalibrationResult.from_toml(source)  # type: ignore[arg-type]
    _one_line(exc, "source")


def test_find_candidates_scalars_and_image() -> None:
    gray = np.zeros((32, 32))
    for bad in NOT_ARRAYS:
        with pytest.raises(InvalidInputError) as exc:
            find_candidates(bad, 1.0)  # type: ignore[arg-type]
        _one_line(exc, "gray")
    torch = pytest.importorskip("torch")
    for name, value in (
        ("sigma", np.inf),
        ("sigma", np.nan),
        ("sigma", 1e308),
        ("sigma", 1j),
        ("sigma", None),
        ("sigma", [1.0]),
        ("relative_threshold", 1j),
        ("relative_threshold", "abc"),
        ("relative_threshold", None),
    ):
        kw = {"sigma": 1.0, name: value}
        with pytest.raises(InvalidInputError) as exc:
            find_candidates(gray, **kw)
        _one_line(exc, name)
    # a 0-d tensor is a number (it reached numba as a pyobject before)
    find_candidates(gray, torch.tensor(1.0), relative_threshold=torch.tensor(0.02))


def test_degenerate_messages_name_the_inputs() -> None:
    with pytest.raises(DegenerateConfigurationError) as exc:
        cross_ratio([0.0, 0.0], [1.0, 1.0], [2.0, 0.0], [3.0, 0.0])
    _one_line(exc, "a, b, c, d")
    with pytest.raises(DegenerateConfigurationError) as exc:
        intersect_lines([0.0, 0.0, 0.0], [1.0, 0.0, -2.0])
    _one_line(exc, "l1", "l2")
    with pytest.raises(DegenerateConfigurationError) as exc:
        estimate_homography(
            np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]), np.zeros((4, 2))
        )
    _one_line(exc, "dst")
    with pytest.raises(DegenerateConfigurationError) as exc:
        intrinsics_from_vanishing_points([0.0, 0.0], [0.0, 0.0], [-1.0, -1.0])
    _one_line(exc, "v1")
    with pytest.raises(DegenerateConfigurationError) as exc:
        lines_from_segments(np.zeros((2, 2, 2)))
    _one_line(exc, "segments")


def test_option_messages_do_not_echo_huge_values() -> None:
    huge = "x" * 100_000
    with pytest.raises(ImageformError) as exc:
        detect_line_segments(np.zeros((16, 16)), method=huge)
    _one_line(exc, "method")
    with pytest.raises(ImageformError) as exc:
        horizon_line(K, np.eye(3), up=huge)
    _one_line(exc, "up")


def test_huge_thresholds_and_points_refused() -> None:
    rng = np.random.default_rng(0)
    p1 = rng.uniform(0, 640, (20, 2))
    p2 = p1 + rng.uniform(-1, 1, (20, 2))
    # before: OverflowError (34, 'Numerical result out of range') from threshold ** 2
    with pytest.raises(InvalidInputError) as exc:
        find_fundamental_matrix(p1, p2, threshold=1e308)
    _one_line(exc, "threshold")
    with pytest.raises(InvalidInputError) as exc:
        find_essential_matrix(p1, p2, K, threshold=1e308)
    _one_line(exc, "threshold")
    # before: LinAlgError "Singular matrix" from the normalisation of 1e300 coordinates
    with pytest.raises(InvalidInputError) as exc:
        find_homography(p1[:4], p1[:4] * 1e300 + 1e300)
    _one_line(exc, "dst")


def test_lsd_parameters_bounded() -> None:
    img = np.zeros((16, 16))
    with pytest.raises(InvalidInputError) as exc:
        lsd_segments(img, n_bins=10**30)
    _one_line(exc, "n_bins")
    with pytest.raises(InvalidInputError) as exc:
        lsd_segments(img, sigma_scale=1e308)
    _one_line(exc, "sigma_scale")
