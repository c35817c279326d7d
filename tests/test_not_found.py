"""One rule for "not found" (docs/conventions.md, "Not found"; issue 30).

A flat grey image holds no object of any kind. Every detector answers it by its rule: a
detector of one object returns its record with ``found`` False (and a reason where it has
one); a detector of any number of objects returns an empty collection; neither raises. What
needs the object (measuring a chart that was not found, sampling a chart from an image)
raises. The list below must name every public ``detect_*`` / ``find_*`` function (a test
checks it), so a new detector is held to the rule too.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

import imageform.analysis as analysis
import imageform.geometry as geometry
from imageform.analysis import ChartNotFoundError
from imageform.errors import InvalidInputError

GREY = np.full((240, 320, 3), 0.5)
GREY8 = np.full((240, 320, 3), 128, np.uint8)
K = np.array([[500.0, 0.0, 159.5], [0.0, 500.0, 119.5], [0.0, 0.0, 1.0]])
BOARD = geometry.CharucoBoard((5, 7), 0.04, 0.03, "4x4_50")

# estimators of the caller's points, not detectors in an image: they return the best model and
# its inlier mask (few inliers on random points); too few or degenerate points raise
# DegenerateConfigurationError (the caller's data), see docs/conventions.md
ESTIMATORS = {"find_homography", "find_fundamental_matrix", "find_essential_matrix"}


def _found_false(res: Any) -> None:
    assert res.found is False
    reason = getattr(res, "reason", "no reason field")
    assert isinstance(reason, str) and reason and "\n" not in reason


def _empty(res: Any) -> None:
    assert len(res) == 0


# name -> (call on a flat image, check of the answer)
ONE: dict[str, Callable[[], Any]] = {
    "geometry.detect_horizon": lambda: geometry.detect_horizon(GREY),
    "geometry.find_checkerboard": lambda: geometry.find_checkerboard(GREY, (9, 6)),
    "analysis.detect_colorchecker": lambda: analysis.detect_colorchecker(GREY),
    "analysis.estimate_background": lambda: analysis.estimate_background(GREY),
    "geometry.BoardTracker.update (checkerboard)": lambda: geometry.BoardTracker((9, 6), K).update(
        GREY
    ),
    "geometry.BoardTracker.update (charuco)": lambda: geometry.BoardTracker(BOARD, K).update(GREY8),
}
MANY: dict[str, Callable[[], Any]] = {
    "geometry.detect_aruco_markers": lambda: geometry.detect_aruco_markers(GREY, "4x4_50"),
    "geometry.detect_charuco": lambda: geometry.detect_charuco(GREY, BOARD),
    "geometry.detect_line_segments": lambda: geometry.detect_line_segments(GREY),
    "geometry.detect_features": lambda: geometry.detect_features(GREY[..., 0]),
    "geometry.lsd_segments": lambda: geometry.lsd_segments(GREY[..., 0])[0],
    "geometry.detect_vanishing_points": lambda: (
        geometry.detect_vanishing_points(GREY).vanishing_points
    ),
    "analysis.find_slanted_edges": lambda: analysis.find_slanted_edges(GREY),
    # one result per view, each found=False: the boards found are none
    "geometry.find_checkerboards": lambda: [
        r for r in geometry.find_checkerboards([GREY, GREY], (9, 6)) if r.found
    ],
}


@pytest.mark.parametrize("name", sorted(ONE))
def test_one_object_detector_returns_found_false(name: str) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no warning either: not found is a plain answer
        res = ONE[name]()
    _found_false(res)


@pytest.mark.parametrize("name", sorted(MANY))
def test_any_number_detector_returns_an_empty_collection(name: str) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        # find_checkerboards names each view without a board in one warning (its contract)
        warnings.simplefilter("ignore", geometry.CheckerboardNotFoundWarning)
        res = MANY[name]()
    _empty(res)


def test_the_tables_name_every_detector() -> None:
    public = {
        f"{mod.__name__.rsplit('.', 1)[1]}.{n}"
        for mod in (geometry, analysis)
        for n in mod.__all__
        if n.startswith(("detect_", "find_")) and n not in ESTIMATORS
    }
    listed = {k.split(" ")[0] for k in (*ONE, *MANY)}
    assert public <= listed, sorted(public - listed)


def test_vanishing_points_without_lines_is_an_empty_set() -> None:
    res = geometry.detect_vanishing_points(GREY)
    assert res.vanishing_points.shape == (0, 3) and res.scores.shape == (0,)
    assert res.K is None and res.vertical is None and res.horizon is None
    assert res.perspective == 0 and len(res.segments) == 0 and len(res.labels) == 0


@pytest.mark.parametrize(
    "call",
    [
        lambda: analysis.measure_chart_patches(GREY, analysis.detect_colorchecker(GREY)),
        lambda: analysis.sample_chart(GREY),
        lambda: analysis.sample_chart(GREY, "detect"),
    ],
    ids=["measure_chart_patches", "sample_chart auto", "sample_chart detect"],
)
def test_what_needs_the_chart_raises(call: Callable[[], Any]) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", analysis.ChartWarning)
        with pytest.raises(ChartNotFoundError, match="no ColorChecker found") as info:
            call()
    msg = str(info.value)
    assert "\n" not in msg and len(msg) <= 240


def test_what_needs_the_board_raises() -> None:
    res = geometry.find_checkerboard(GREY, (9, 6))
    with pytest.raises(InvalidInputError, match="no checkerboard was found"):
        res.grid()


def test_simulator_vanishing_check_on_a_flat_render() -> None:
    # the simulator's check of its rails (simulate.truth.detect_vanishing) finds nothing on a
    # flat render: the truth comes back unfilled and the errors None, as before (it used to
    # catch the detector's DegenerateConfigurationError)
    from imageform.simulate.truth import VanishingTruth, detect_vanishing

    truth = VanishingTruth(np.array([160.0, 60.0, 1.0]), np.array([0.0, 1.0, -60.0]))
    filled, errors = detect_vanishing(GREY, truth, rng=0)
    assert filled is truth
    assert errors == {"vanishing_point_error_px": None, "horizon_angle_error_deg": None}
