"""Line-segment detection and vanishing points in images: synthetic renders with known K,
real photographs (Kodak), the numba kernels against their interpreted Python twins."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from imageform._kernels import lsd
from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.geometry import (
    camera_rotation,
    detect_line_segments,
    detect_vanishing_points,
    horizon_line,
    vanishing_point,
)
from tests.geometry.scene_render import render_manhattan

K = np.array([[700.0, 0.0, 383.5], [0.0, 700.0, 255.5], [0.0, 0.0, 1.0]])


def _row_at(line: np.ndarray, u: float) -> float:
    return float(-(line[0] * u + line[2]) / line[1])


def test_step_edge_segment_position() -> None:
    img = np.zeros((64, 80))
    img[:, 40:] = 1.0
    seg = detect_line_segments(img)
    assert len(seg) == 1
    (u0, v0), (u1, v1) = seg.endpoints[0]
    assert u0 == pytest.approx(39.5, abs=0.05) and u1 == pytest.approx(39.5, abs=0.05)
    assert abs(v1 - v0) > 55
    assert seg.log10_nfa[0] < -50


def test_noise_gives_no_segments() -> None:
    """The a-contrario test: on white noise, (almost) no detections (ε = 1 per image)."""
    rng = np.random.default_rng(0)
    seg = detect_line_segments(rng.uniform(size=(128, 128)), sigma=0.0)
    assert len(seg) <= 1


def test_inclined_line_angle() -> None:
    from PIL import Image, ImageDraw

    s = 4
    canvas = Image.new("L", (200 * s, 150 * s), 0)
    ImageDraw.Draw(canvas).line([(20 * s, 30 * s), (180 * s, 120 * s)], fill=255, width=3 * s)
    img = np.asarray(canvas.resize((200, 150), Image.BOX), dtype=float) / 255
    seg = detect_line_segments(img)
    assert len(seg) >= 2  # the two sides of a bright bar
    d = seg.endpoints[0, 1] - seg.endpoints[0, 0]
    angle = math.degrees(math.atan2(d[1], d[0])) % 180
    assert angle == pytest.approx(math.degrees(math.atan2(90, 160)), abs=0.5)


def test_kernels_match_interpreted_twins() -> None:
    rng = np.random.default_rng(1)
    img = render_manhattan(
        K * [[0.25], [0.25], [1]],
        camera_rotation(0.2, 0.4),
        np.zeros(3),
        size=(96, 64),
        n_per_axis=6,
        seed=2,
    )
    from imageform.geometry.line_segments import _gradient

    ang, mag = _gradient(img)
    ang[mag <= 0.02] = np.nan
    order = np.argsort(-mag, axis=None, kind="stable")
    order = order[~np.isnan(ang.ravel()[order])]
    tau = math.radians(22.5)
    lab_c, n_c = lsd.grow_regions(ang, order, tau, 5)
    lab_p, n_p = lsd.grow_regions.py_func(ang, order, tau, 5)
    assert n_c == n_p and n_c > 0
    np.testing.assert_array_equal(lab_c, lab_p)
    rc = lsd.region_rectangles(lab_c, n_c, mag)
    rp = lsd.region_rectangles.py_func(lab_c, n_c, mag)
    np.testing.assert_allclose(rc, rp, rtol=1e-12, atol=1e-9)
    np.testing.assert_array_equal(
        lsd.rect_alignment_counts(rc, ang, tau), lsd.rect_alignment_counts.py_func(rc, ang, tau)
    )
    del rng


@pytest.mark.parametrize(
    "pitch, yaw, roll", [(0.25, 0.5, 0.03), (-0.2, 0.7, -0.05), (0.35, -0.45, 0.0)]
)
def test_render_known_camera_recovers_K_and_horizon(pitch: float, yaw: float, roll: float) -> None:
    R = camera_rotation(pitch, yaw, roll)
    img = render_manhattan(K, R, np.zeros(3), seed=3)
    res = detect_vanishing_points(img)
    assert res.K is not None and res.perspective == 3
    assert res.K[0, 0] == pytest.approx(700.0, rel=0.03)
    np.testing.assert_allclose(res.K[:2, 2], K[:2, 2], atol=12.0)
    truth = horizon_line(K, R)
    for u in (0.0, 383.5, 767.0):
        assert _row_at(res.horizon, u) == pytest.approx(_row_at(truth, u), abs=4.0)
    # each detected vanishing point is one of the three true ones (within 1 % of distance)
    true_vps = [vanishing_point(K, d, R) for d in np.eye(3)]
    for v in res.vanishing_points:
        err = min(
            np.linalg.norm(v[:2] - tv[:2]) / np.linalg.norm(tv[:2] - K[:2, 2]) for tv in true_vps
        )
        assert err < 0.02
    assert res.vertical is not None
    vert_true = int(
        np.argmin(
            [np.linalg.norm(res.vanishing_points[res.vertical][:2] - tv[:2]) for tv in true_vps]
        )
    )
    assert vert_true == 1  # the world's y axis is vertical


def test_two_point_perspective_level_camera() -> None:
    R = camera_rotation(0.0, 0.6, 0.0)  # level: verticals stay parallel in the image
    img = render_manhattan(K, R, np.zeros(3), seed=4)
    res = detect_vanishing_points(img)
    assert res.perspective == 2
    assert res.vertical is not None
    assert res.vanishing_points[res.vertical][2] == 0.0 or np.hypot(
        *(res.vanishing_points[res.vertical][:2] - K[:2, 2])
    ) > 20 * math.hypot(768, 512)


def test_kodak_buildings(shared_data: Path) -> None:
    """Real photographs: kodim24 (a house seen from a corner) gives a plausible triplet."""
    from PIL import Image

    img = np.asarray(Image.open(shared_data / "kodak" / "kodim24.png"))
    res = detect_vanishing_points(img)
    assert len(res.segments) > 100
    assert res.K is not None and res.horizon is not None
    assert 0.5 * 768 < res.K[0, 0] < 5 * 768
    # the horizon is nearly level for a hand-held photo of a house
    assert abs(math.degrees(math.atan2(-res.horizon[0], res.horizon[1]))) < 5
    assert res.vertical is not None


def test_bad_inputs() -> None:
    with pytest.raises(InvalidInputError, match="either an image or segments"):
        detect_vanishing_points()
    with pytest.raises(DegenerateConfigurationError, match="at least two"):
        detect_vanishing_points(np.zeros((50, 50)))
    with pytest.raises(InvalidInputError, match="grey"):
        detect_line_segments(np.zeros((4, 5, 6)))
    with pytest.raises(InvalidInputError, match="angle_tolerance"):
        detect_line_segments(np.zeros((10, 10)), angle_tolerance=2.0)
    with pytest.raises(InvalidInputError, match="0-255"):
        detect_line_segments(np.full((10, 10), 200.0))
