"""Line-segment detection and vanishing points in images: synthetic renders with known K,
real photographs (Kodak), the numba kernels against their interpreted Python twins."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from imageform._kernels import lsd
from imageform.errors import InvalidInputError
from imageform.geometry import (
    VanishingPointResult,
    camera_rotation,
    detect_line_segments,
    detect_vanishing_points,
    horizon_line,
    vanishing_point,
)
from tests.geometry.scene_render import render_manhattan, render_seaside

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


def test_max_size_maps_the_segments_back_to_the_image_pixels() -> None:
    """``max_size``: the segments are found on a copy whose long side is ``max_size`` px and
    mapped back with the pixel centres aligned: a step edge between columns 79 and 80 of a
    160 x 128 image is found at u = 79.5 on a copy a quarter the size (within 0.5 px; the
    copy's edge is 4 original pixels wide), and along the full height."""
    img = np.zeros((128, 160))
    img[:, 80:] = 1.0
    seg = detect_vanishing_points(img, max_size=40).segments
    assert len(seg) == 1
    (u0, v0), (u1, v1) = seg.endpoints[0]
    assert u0 == pytest.approx(79.5, abs=0.5) and u1 == pytest.approx(79.5, abs=0.5)
    assert abs(v1 - v0) > 100
    # an image no larger than max_size is used as it is
    same = detect_vanishing_points(img, max_size=160).segments
    np.testing.assert_array_equal(same.endpoints, detect_line_segments(img).endpoints)
    with pytest.raises(InvalidInputError, match="max_size"):
        detect_vanishing_points(img, max_size=8)
    with pytest.raises(InvalidInputError, match="max_size"):
        detect_vanishing_points(segments=seg, image_size=(160, 128), max_size=2.5)


def test_max_size_keeps_K_and_the_horizon_of_a_large_render() -> None:
    """A 1536 x 1024 render (f = 1100 px): with ``max_size=768`` the segments come from a
    copy half the size, and K and the horizon, in the image's pixels, agree with the truth
    (f within 2 %, the horizon within 2 px at both edges) as they do without it."""
    Kb = np.array([[1100.0, 0.0, 767.5], [0.0, 1100.0, 511.5], [0.0, 0.0, 1.0]])
    R = camera_rotation(0.25, 0.5, 0.03)
    img = render_manhattan(Kb, R, np.zeros(3), size=(1536, 1024), seed=3, supersample=2)
    true_h = horizon_line(Kb, R)
    for res in (detect_vanishing_points(img), detect_vanishing_points(img, max_size=768)):
        assert res.K is not None and res.horizon is not None
        assert res.K[0, 0] == pytest.approx(1100.0, rel=0.02)
        for u in (0.0, 1535.0):
            assert _row_at(res.horizon, u) == pytest.approx(_row_at(true_h, u), abs=2.0)
        ends = res.segments.endpoints
        assert ends[..., 0].max() > 1400 and ends[..., 1].max() > 900


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
    # an image without lines is an answer (no vanishing point), not an error
    none = detect_vanishing_points(np.zeros((50, 50)))
    assert none.vanishing_points.shape == (0, 3) and none.scores.shape == (0,)
    assert none.K is None and none.horizon is None and none.vertical is None
    assert none.perspective == 0 and len(none.labels) == len(none.segments) == 0
    with pytest.raises(InvalidInputError, match="grey"):
        detect_line_segments(np.zeros((4, 5, 6)))
    with pytest.raises(InvalidInputError, match="angle_tolerance"):
        detect_line_segments(np.zeros((10, 10)), angle_tolerance=2.0)
    with pytest.raises(InvalidInputError, match="0-255"):
        detect_line_segments(np.full((10, 10), 200.0))


def test_principal_point_options_and_refusals() -> None:
    R = camera_rotation(0.25, 0.5, 0.03)
    img = render_manhattan(K, R, np.zeros(3), seed=3)
    seg = detect_line_segments(img)
    size = (img.shape[1], img.shape[0])
    given = detect_vanishing_points(segments=seg, image_size=size, principal_point=(383.5, 255.5))
    centre = detect_vanishing_points(segments=seg, image_size=size)
    ortho = detect_vanishing_points(segments=seg, image_size=size, principal_point="orthocenter")
    assert given.K is not None and centre.K is not None and ortho.K is not None
    np.testing.assert_allclose(given.K, centre.K)  # the render's principal point is the centre
    assert ortho.K[0, 0] == pytest.approx(700.0, rel=0.03)
    assert abs(ortho.K[0, 2] - 383.5) > 0  # the orthocentre moves it
    with pytest.raises(InvalidInputError, match="principal_point"):
        detect_vanishing_points(segments=seg, image_size=size, principal_point="middle")
    with pytest.raises(InvalidInputError, match="principal_point"):
        detect_vanishing_points(segments=seg, image_size=size, principal_point=(1.0, np.nan))
    with pytest.raises(InvalidInputError, match="principal_point"):
        detect_vanishing_points(segments=seg, image_size=size, principal_point=(1, 2, 3))
    with pytest.raises(InvalidInputError, match="orthogonality_tolerance"):
        detect_vanishing_points(segments=seg, image_size=size, orthogonality_tolerance=0.0)


def test_non_orthogonal_third_point_is_not_a_manhattan_set() -> None:
    """Three finite points whose directions cannot all be orthogonal for any focal length
    with the principal point at the centre: no triplet K (the orthocentre would give one)."""
    from imageform.geometry.vp_detection import _manhattan_K

    pp = np.array([383.5, 255.5])
    Kt = np.array([[700.0, 0, pp[0]], [0, 700.0, pp[1]], [0, 0, 1]])
    R = camera_rotation(0.25, 0.5, 0.03)
    vps = [vanishing_point(Kt, d, R) for d in np.eye(3)]
    vps = [v / v[2] for v in vps]
    diag = math.hypot(768, 512)
    K3 = _manhattan_K(vps, [1.0, 1.0, 1.0], pp, diag, 20 * diag, math.radians(3.5))
    assert K3 is not None and K3[0, 0] == pytest.approx(700.0, rel=1e-6)
    bad = vps[:2] + [np.array([vps[2][0] + 300.0, vps[2][1], 1.0])]
    assert _manhattan_K(bad, [1.0, 1.0, 1.0], pp, diag, 20 * diag, math.radians(3.5)) is None
    # a pair: f from f^2 = -(v1 - p).(v2 - p) exactly
    K2 = _manhattan_K(vps[:2], [1.0, 1.0], pp, diag, 20 * diag, math.radians(3.5))
    a, b = vps[0][:2] - pp, vps[1][:2] - pp
    assert K2 is not None and K2[0, 0] == pytest.approx(math.sqrt(-a @ b), rel=1e-6)


def test_two_horizontal_points_give_the_horizon() -> None:
    """A level camera looking at a floor grid: both points horizontal; the vertical is their
    cross product and the horizon is level through them (vertical index None)."""
    R = camera_rotation(0.3, 0.5, 0.0)
    seg_pts = []
    for d in (np.array([1.0, 0, 0]), np.array([0, 0, 1.0])):
        v = vanishing_point(K, d, R)
        v = v[:2] / v[2]
        for t in np.linspace(-300, 300, 12):
            p0 = np.array([383.5 + t, 400.0 + 0.1 * t])
            p1 = p0 + 0.3 * (v - p0)
            seg_pts.append([p0, p1])
    from imageform.geometry import LineSegments

    n = len(seg_pts)
    seg = LineSegments(np.array(seg_pts), np.ones(n), np.full(n, -10.0))
    res = detect_vanishing_points(segments=seg, image_size=(768, 512))
    assert res.K is not None and len(res.vanishing_points) == 2
    assert res.vertical is None
    truth = horizon_line(K, R)
    for u in (0.0, 383.5, 767.0):
        assert _row_at(res.horizon, u) == pytest.approx(_row_at(truth, u), abs=1.0)


def test_focal_length_on_real_checkerboard_photographs(shared_data: Path) -> None:
    """Real photographs with a known camera (OpenCV's left*.jpg, f = 536.07 px after
    undistortion): focal length within 8 % with the principal point at the centre and
    within 3 % with the calibrated one, on four views (all 13: benchmarks/check_vp_real.py,
    median 6.5 % and 3.6 %)."""
    from PIL import Image

    from imageform.geometry import undistort_image
    from imageform.geometry.distortion import BrownConrady

    Kc = np.array([[536.07345314, 0, 342.37046827], [0, 536.01636274, 235.53687064], [0, 0, 1]])
    D = np.array([-0.26509039, -0.0467422, 0.00183302, -0.00031469, 0.25231221])
    for name in ("left01.jpg", "left03.jpg", "left04.jpg", "left14.jpg"):
        img = np.asarray(Image.open(shared_data / "opencv-left" / name).convert("L"))
        und = undistort_image(img, Kc, BrownConrady.from_opencv(D), keep_dtype=True)
        seg = detect_line_segments(und)
        size = (und.shape[1], und.shape[0])
        centre = detect_vanishing_points(segments=seg, image_size=size)
        calib = detect_vanishing_points(segments=seg, image_size=size, principal_point=Kc[:2, 2])
        assert centre.K is not None and calib.K is not None
        assert abs(centre.K[0, 0] / 536.07 - 1) < 0.08, (name, centre.K[0, 0])
        assert abs(calib.K[0, 0] / 536.07 - 1) < 0.03, (name, calib.K[0, 0])


@pytest.mark.xfail(
    strict=True,
    reason="the candidates depend on RANSAC's seed: on left01 seeds 1-6 give the board's two "
    "families, seeds 0 and 7 the board's horizontal family, the monitor's lines and the room's "
    "vertical (benchmarks/results/vp-seed-2026-11-29i.md)",
)
def test_checkerboard_view_does_not_depend_on_the_seed(shared_data: Path) -> None:
    """OpenCV's left01.jpg, undistorted with its published calibration: the same vanishing
    points (directions within 1 degree at the calibrated f) and the same K (within 1 %) for
    every seed 0-7 as for seed 0. The board's two families (about 3700 and 3400 px of
    segments) compete there with the monitor's lines (about 2000 px) and the room's vertical
    (about 500 px)."""
    from PIL import Image

    from imageform.geometry import undistort_image
    from imageform.geometry.distortion import BrownConrady

    Kc = np.array([[536.07345314, 0, 342.37046827], [0, 536.01636274, 235.53687064], [0, 0, 1]])
    D = np.array([-0.26509039, -0.0467422, 0.00183302, -0.00031469, 0.25231221])
    img = np.asarray(Image.open(shared_data / "opencv-left" / "left01.jpg").convert("L"))
    und = undistort_image(img, Kc, BrownConrady.from_opencv(D), keep_dtype=True)
    seg = detect_line_segments(und)
    size = (und.shape[1], und.shape[0])

    def directions(res: VanishingPointResult) -> np.ndarray:
        d = np.linalg.solve(Kc, res.vanishing_points.T).T
        return d / np.linalg.norm(d, axis=1, keepdims=True)

    first = detect_vanishing_points(segments=seg, image_size=size, rng=0)
    assert first.K is not None and len(first.vanishing_points) >= 2
    for seed in range(1, 8):
        res = detect_vanishing_points(segments=seg, image_size=size, rng=seed)
        assert len(res.vanishing_points) == len(first.vanishing_points), seed
        cos = np.abs(directions(res) @ directions(first).T).max(axis=1)
        assert np.all(cos > np.cos(np.radians(1.0))), (seed, cos)
        assert res.K is not None and res.K[0, 0] == pytest.approx(first.K[0, 0], rel=0.01)


def test_horizon_through_the_horizontal_points_when_the_principal_point_is_off() -> None:
    """The horizon does not move with K's assumed principal point: a camera whose principal
    point is (-12, +12) px from the centre (York Urban's is about that) gives the horizon
    within 1.5 px; from K alone (the centre assumed) it would be about 12 px off."""
    Ko = np.array([[700.0, 0.0, 371.5], [0.0, 700.0, 267.5], [0.0, 0.0, 1.0]])
    R = camera_rotation(0.25, 0.5, 0.03)
    img = render_manhattan(Ko, R, np.zeros(3), seed=3)
    res = detect_vanishing_points(img)
    assert res.horizon is not None and res.K is not None
    truth = horizon_line(Ko, R)
    for u in (0.0, 383.5, 767.0):
        assert _row_at(res.horizon, u) == pytest.approx(_row_at(truth, u), abs=1.5)
    from_k = horizon_line(res.K, None, np.linalg.solve(res.K, res.vanishing_points[res.vertical]))
    assert abs(_row_at(from_k, 383.5) - _row_at(truth, 383.5)) > 5  # what anchoring fixed


def test_level_camera_before_a_wall_gives_the_horizon_without_K() -> None:
    """Verticals (parallel in the image: their point at infinity) and one horizontal
    direction: no focal length can be had, the horizon can (perpendicular to the verticals,
    through the horizontal point)."""
    R = camera_rotation(0.0, 0.5, 0.0)
    segs = []
    rng = np.random.default_rng(0)
    for d in (np.array([1.0, 0, 0]), np.array([0, 1.0, 0])):
        for _ in range(25):
            p0 = R.T @ np.array([rng.uniform(-4, 4), rng.uniform(-3, 3), rng.uniform(6, 14)])
            X = np.stack([p0, p0 + 2.0 * d])
            q = (K @ (R @ X.T)).T
            segs.append(q[:, :2] / q[:, 2:])
    from imageform.geometry import LineSegments

    n = len(segs)
    seg = LineSegments(np.array(segs), np.ones(n), np.full(n, -10.0))
    res = detect_vanishing_points(segments=seg, image_size=(768, 512))
    assert res.K is None and res.horizon is not None
    truth = horizon_line(K, R)
    for u in (0.0, 383.5, 767.0):
        assert _row_at(res.horizon, u) == pytest.approx(_row_at(truth, u), abs=1.0)


@pytest.mark.parametrize(
    ("pitch", "roll", "seed"), [(-3.0, 2.0, 0), (-1.0, -1.5, 1), (-5.0, 0.5, 2)]
)
def test_sea_horizon_of_a_level_camera(pitch: float, roll: float, seed: int) -> None:
    """Issue 26: open sea under a sky, no verticals: one horizontal direction (the horizon,
    the wave crests), its point at infinity, so no vanishing point gives the horizon (none
    was returned). The horizon is in the picture: found within 0.5 px of the truth at both
    edges, not on a wave crest below it."""
    img, truth = render_seaside(pitch_deg=pitch, roll_deg=roll, seed=seed)
    res = detect_vanishing_points(img)
    assert res.horizon is not None and res.K is None and res.vertical is None
    for u in (0.0, 767.0):
        assert _row_at(res.horizon, u) == pytest.approx(_row_at(truth, u), abs=0.5)


@pytest.mark.parametrize(("i", "band"), [(16, (620, 760)), (21, (700, 760))])
def test_sea_horizon_in_real_photographs(shared_data: Path, i: int, band: tuple[int, int]) -> None:
    """Issue 26: Kodak photographs with a sea horizon and no Manhattan triplet (kodim16: an
    island on open water; kodim21: a lighthouse, the sea horizon on the right) returned no
    horizon. Now it passes within 1.5 px of where the sky meets the sea in a band of
    columns showing open sea (the largest step of the band's mean column profile)."""
    from imageform.io import read_image

    path = shared_data / "kodak" / f"kodim{i:02d}.png"
    if not path.is_file():
        pytest.skip("../shared/data/kodak is not available")
    img = np.asarray(read_image(path))
    res = detect_vanishing_points(img)
    assert res.horizon is not None
    grey = img @ np.array([0.299, 0.587, 0.114])
    profile = grey[:, band[0] : band[1]].mean(axis=1)
    guess = _row_at(res.horizon, float(np.mean(band)))
    lo = int(guess) - 15
    step = lo + int(np.argmax(np.abs(np.diff(profile[lo : lo + 30])))) + 0.5
    assert guess == pytest.approx(step, abs=1.5)


def test_no_sea_horizon_on_a_facade(shared_data: Path) -> None:
    """kodim01, a facade seen square on: verticals and horizontals both parallel in the
    image, long horizontal runs of window sills; none of them is a horizon (no point gives
    one, and the image is no open water: its verticals add up to half its horizontals)."""
    from imageform.io import read_image

    path = shared_data / "kodak" / "kodim01.png"
    if not path.is_file():
        pytest.skip("../shared/data/kodak is not available")
    assert detect_vanishing_points(np.asarray(read_image(path))).horizon is None


def _toward(points: list[np.ndarray], n: int, rng: np.random.Generator) -> list[np.ndarray]:
    """``n`` segments for each homogeneous point of ``points`` (``w = 0``: parallel ones),
    their midpoints spread over the 768 x 512 frame, 40 to 120 px long."""
    segs = []
    for v in points:
        for _ in range(n):
            m = rng.uniform([20.0, 20.0], [748.0, 492.0])
            d = v[:2] - m * v[2]
            d = d / np.linalg.norm(d) * rng.uniform(20.0, 60.0)
            segs.append(np.stack([m - d, m + d]))
    return segs


def _segments(segs: list[np.ndarray]) -> object:
    from imageform.geometry import LineSegments

    n = len(segs)
    return LineSegments(np.array(segs), np.ones(n), np.full(n, -10.0))


def test_one_point_perspective_is_not_outvoted_by_weak_points_that_give_a_focal_length() -> None:
    """A level camera looking straight down a hall (a real atrium photograph did this): the
    verticals and the transverse horizontals are parallel in the image (points at infinity),
    the hall's direction vanishes at the principal point; no focal length can be had. Two
    weak clusters of segments on the horizon's row, with the vertical, would make a triplet
    that does give one (f^2 = 500 * 1000). The strong one-point-perspective set is the
    answer: K None, the horizon through the central point, level."""
    p = K[:2, 2]
    true = [np.array([0.0, 1.0, 0.0]), np.array([1.0, 0.0, 0.0]), np.array([*p, 1.0])]
    weak = [np.array([p[0] - 500.0, p[1], 1.0]), np.array([p[0] + 1000.0, p[1], 1.0])]
    rng = np.random.default_rng(5)
    seg = _segments(_toward(true, 40, rng) + _toward(weak, 6, rng))
    res = detect_vanishing_points(segments=seg, image_size=(768, 512))
    assert len(res.vanishing_points) == 3 and res.K is None
    found = sorted(
        ("inf" if v[2] == 0 or np.hypot(*(v[:2] - p)) > 1e4 else "finite")
        for v in res.vanishing_points
    )
    assert found == ["finite", "inf", "inf"]
    assert res.horizon is not None
    for u in (0.0, 767.0):
        assert _row_at(res.horizon, u) == pytest.approx(p[1], abs=1.0)


def test_a_pair_no_focal_length_makes_orthogonal_is_passed_over() -> None:
    """Three-point perspective, the third direction weakly seen (no orthogonal triplet): the
    best-supported pair was returned whether or not its directions can be orthogonal. A
    strong point B with an acute angle at the principal point to the vertical point A,
    ``(A - p).(B - p) > 0``, is no scene direction orthogonal to A for any focal length; the
    orthogonal pair A, C (f = 700 px) is the answer, with its K."""
    R = camera_rotation(0.3, 0.6, 0.0)
    A, C = (vanishing_point(K, d, R) for d in (np.array([0, 1.0, 0]), np.array([1.0, 0, 0])))
    A, C = A / A[2], C / C[2]
    B = np.array([K[0, 2] + 0.8 * (A[0] - K[0, 2]) + 900.0, A[1] + 300.0, 1.0])
    assert (A[:2] - K[:2, 2]) @ (B[:2] - K[:2, 2]) > 0
    rng = np.random.default_rng(6)
    seg = _segments(_toward([A], 60, rng) + _toward([B], 45, rng) + _toward([C], 30, rng))
    res = detect_vanishing_points(segments=seg, image_size=(768, 512))
    assert res.K is not None
    assert res.K[0, 0] == pytest.approx(700.0, rel=0.01)
    assert len(res.vanishing_points) == 2
    for v in res.vanishing_points:
        assert min(np.hypot(*(v[:2] / v[2] - t[:2])) for t in (A, C)) < 5.0


def test_rolled_one_point_perspective_keeps_its_vertical_and_horizon() -> None:
    """A camera rolled 10 degrees down a hall whose point is just above the image centre
    (as in a real atrium photograph, rolled): the direction from the centre to that point
    is nearer the columns than the rolled verticals are, and it was taken for the vertical
    point (no horizon). The vertical point is the one whose segments are most nearly
    vertical; the horizon passes through the hall's point at the roll's tilt."""
    p = K[:2, 2]
    a = math.radians(10.0)
    up = np.array([math.sin(a), math.cos(a), 0.0])
    across = np.array([math.cos(a), -math.sin(a), 0.0])
    hall = np.array([p[0] + 3.0, p[1] - 60.0, 1.0])
    rng = np.random.default_rng(7)
    seg = _segments(_toward([up, across, hall], 40, rng))
    res = detect_vanishing_points(segments=seg, image_size=(768, 512))
    assert res.K is None and res.vertical is not None and res.horizon is not None
    v = res.vanishing_points[res.vertical]
    assert abs(v[:2] @ up[:2]) / np.hypot(*v[:2]) > math.cos(math.radians(1.0))
    tilt = math.degrees(math.atan2(-res.horizon[0], res.horizon[1]))
    assert tilt == pytest.approx(-10.0, abs=0.5)
    assert _row_at(res.horizon, hall[0]) == pytest.approx(hall[1], abs=1.0)


def test_no_focal_length_from_two_horizontal_points_orthogonal_by_chance() -> None:
    """Clutter with no vertical direction (a real photograph of sand ripples): the two
    best-supported points are not orthogonal for any focal length; a weaker point happens to
    be orthogonal to the best one (f about 2.3 image diagonals). Two near-horizontal
    directions reached past the second-best point give no K (it gave f +37 % and a horizon
    tilted 21 degrees): the pair searched for past a non-orthogonal second point has to
    hold the vertical direction. The two best points are returned, without K, and neither
    is called vertical (their segments run nearer the rows than the columns)."""
    p = K[:2, 2]
    A = np.array([p[0] + 1000.0, p[1] - 320.0, 1.0])
    B = np.array([p[0] + 280.0, p[1] - 70.0, 1.0])  # (A - p).(B - p) > 0
    C = np.array([p[0] - 4980.0, p[1] + 1970.0, 1.0])  # (A - p).(C - p) < 0
    assert (A[:2] - p) @ (B[:2] - p) > 0 > (A[:2] - p) @ (C[:2] - p)
    rng = np.random.default_rng(8)
    seg = _segments(_toward([A], 60, rng) + _toward([B], 35, rng) + _toward([C], 25, rng))
    res = detect_vanishing_points(segments=seg, image_size=(768, 512))
    assert res.K is None and len(res.vanishing_points) == 2
    for v in res.vanishing_points:
        assert min(np.hypot(*(v[:2] / v[2] - t[:2])) for t in (A, B)) < 10.0
    assert res.vertical is None and res.horizon is None


def test_a_set_without_focal_length_is_made_of_the_best_supported_points() -> None:
    """A facade seen square on (verticals and horizontals parallel in the image, the two
    strongest points) with clutter: a weak point near the image centre, weaker than the
    clutter's, passes the loose orthogonality check a set without K gets (f is unknown)
    and made a triplet whose 'horizon' ran through it (a real photograph of a statue). A
    set without K is admitted only as the best-supported points: here the facade's pair,
    which gives no horizon."""
    p = K[:2, 2]
    up, across = np.array([0.0, 1.0, 0.0]), np.array([1.0, 0.0, 0.0])
    clutter = [np.array([p[0] + dx, p[1] + dy, 1.0]) for dx, dy in ((900, 700), (-1500, -900))]
    weak = np.array([p[0] - 100.0, p[1] + 50.0, 1.0])
    rng = np.random.default_rng(9)
    segs = _toward([up, across], 40, rng) + _toward(clutter, 14, rng) + _toward([weak], 9, rng)
    res = detect_vanishing_points(segments=_segments(segs), image_size=(768, 512))
    assert res.K is None and len(res.vanishing_points) == 2
    assert all(v[2] == 0 or np.hypot(*(v[:2] / v[2] - p)) > 1e4 for v in res.vanishing_points)
    assert res.horizon is None


@pytest.mark.parametrize("roll", [0.0, 0.15])
def test_one_point_perspective_render_gives_its_three_points_and_horizon(roll: float) -> None:
    """A render of a camera looking along one of the scene's axes (one-point perspective:
    the other two axes vanish at infinity, no focal length to be had): the three points
    and the horizon through the central one; only two points and no horizon before."""
    R = camera_rotation(0.0, 0.0, roll)
    res = detect_vanishing_points(render_manhattan(K, R, np.zeros(3), seed=3))
    assert len(res.vanishing_points) == 3 and res.K is None and res.perspective == 1
    assert res.horizon is not None
    truth = horizon_line(K, R)
    for u in (0.0, 383.5, 767.0):
        assert _row_at(res.horizon, u) == pytest.approx(_row_at(truth, u), abs=1.5)


def test_no_focal_length_from_weak_points_on_a_beach(shared_data: Path) -> None:
    """kodim12, a couple on a beach (the shore, the sea, no buildings): a triplet of the
    second to fourth best points (none of them the dominant, near-level direction) gave
    f = 6587 px and a horizon 220 px above the frame. A set has to hold the best-supported
    point: no K, no horizon from vanishing points."""
    from imageform.io import read_image

    path = shared_data / "kodak" / "kodim12.png"
    if not path.is_file():
        pytest.skip("../shared/data/kodak is not available")
    res = detect_vanishing_points(np.asarray(read_image(path)))
    assert res.K is None
    assert res.horizon is None or -(res.horizon[2] / res.horizon[1]) > 0


def _texture(n: int, rng: np.random.Generator) -> list[np.ndarray]:
    """``n`` short segments (10 to 30 px) at random places and angles in the 768 x 512 frame:
    the edges of rocks, grass or sand, which no scene direction lines up."""
    segs = []
    for _ in range(n):
        m = rng.uniform([20.0, 20.0], [748.0, 492.0])
        a = rng.uniform(0.0, math.pi)
        d = np.array([math.cos(a), math.sin(a)]) * rng.uniform(5.0, 15.0)
        segs.append(np.stack([m - d, m + d]))
    return segs


@pytest.mark.parametrize("seed", range(6))
def test_no_focal_length_from_chance_convergences_in_texture(seed: int) -> None:
    """Texture only (200 short segments at random places and angles, as rocks, grass or sand
    give): RANSAC still finds points that a few segments meet by chance, and any two of them
    on either side of the principal point are orthogonal for some focal length: K came out
    with f = 266, 664, 140, 270, 324 and 618 px for seeds 0-5 (a real photograph of rocks:
    f -75 %). The points that would fix f are too weakly supported: no K, and the reason
    says so."""
    segs = _texture(200, np.random.default_rng(seed))
    res = detect_vanishing_points(segments=_segments(segs), image_size=(768, 512))
    assert len(res.vanishing_points) == 2 and res.K is None
    assert res.K_reason is not None and "weakly supported" in res.K_reason


def test_focal_spread_of_a_manhattan_render() -> None:
    """A render with known K (f = 700 px): resampling the points' segments moves f by well
    under 1 %, and K is kept (within 1 %)."""
    R = camera_rotation(0.2, 0.6, 0.05)
    res = detect_vanishing_points(render_manhattan(K, R, np.zeros(3), seed=3))
    assert res.K is not None and res.K_reason is None
    assert res.K[0, 0] == pytest.approx(700.0, rel=0.01)
    assert res.focal_spread is not None and 0.0 < res.focal_spread < 0.01


@pytest.mark.parametrize(("i", "before"), [(15, 457.0), (23, 428.0), (5, 2088.0), (19, 691.0)])
def test_no_focal_length_on_kodak_photographs_without_a_manhattan_triplet(
    shared_data: Path, i: int, before: float
) -> None:
    """Kodak photographs with no orthogonal scene directions to speak of got a focal length
    (in px: kodim15, a painted face, 457, its horizon across the frame from row 513 to row
    1; kodim23, two parrots, 428; kodim05, motocross riders, 2088; kodim19, a lighthouse
    behind a picket fence, 691). Now none: the points are too weakly supported (15, 23) or
    resampling their segments moves f by more than 2.5 % (5: 9.5 %, 19: 2.7 %)."""
    from imageform.io import read_image

    path = shared_data / "kodak" / f"kodim{i:02d}.png"
    if not path.is_file():
        pytest.skip("../shared/data/kodak is not available")
    res = detect_vanishing_points(np.asarray(read_image(path)))
    assert res.K is None, before
    assert res.K_reason is not None and res.K_reason.startswith("not determined: ")


@pytest.mark.parametrize("i", [3, 7, 8, 24])
def test_kodak_photographs_with_man_made_directions_keep_their_focal_length(
    shared_data: Path, i: int
) -> None:
    """kodim03 (hats on a wall), kodim07 (shutters), kodim08 (houses), kodim24 (a mural on a
    wall) keep the K they had: their points are well supported and resampling moves f by
    2 % or less."""
    from imageform.io import read_image

    path = shared_data / "kodak" / f"kodim{i:02d}.png"
    if not path.is_file():
        pytest.skip("../shared/data/kodak is not available")
    res = detect_vanishing_points(np.asarray(read_image(path)))
    assert res.K is not None and res.focal_spread is not None and res.focal_spread <= 0.021


def test_horizon_without_K_from_a_finite_vertical_point() -> None:
    """A pitched camera (the vertical point finite) seeing verticals and one horizontal
    direction, K left open (the orthocentre needs three finite points): the horizon's
    normal is ``v - p`` whatever the focal length (square pixels, zero skew), and the
    horizontal point fixes its offset. It comes back within 1 px of the truth across the
    frame; None before ("a finite vertical point: the horizon needs the focal length")."""
    R = camera_rotation(0.3, 0.5, 0.05)
    up, across = (vanishing_point(K, d, R) for d in (np.array([0, 1.0, 0]), np.array([1.0, 0, 0])))
    rng = np.random.default_rng(10)
    seg = _segments(_toward([up / up[2], across / across[2]], 40, rng))
    res = detect_vanishing_points(
        segments=seg, image_size=(768, 512), principal_point="orthocenter"
    )
    assert res.K is None and res.vertical is not None and res.horizon is not None
    truth = horizon_line(K, R)
    for u in (0.0, 383.5, 767.0):
        assert _row_at(res.horizon, u) == pytest.approx(_row_at(truth, u), abs=1.0)


def test_horizon_without_K_joins_a_finite_and_a_far_horizontal_point() -> None:
    """A pitched camera looking along a railway (yaw and roll 0): the across direction
    vanishes at infinity, the rails' point, inside the frame, is met by 8 segments (too few
    to fix a focal length: K None), and the posts' vertical point, 2263 px above the
    principal point and met by 15 segments (the across direction's by 40), is moved 40 px
    sideways (1 degree seen from the principal point, as a lens's distortion bends
    off-centre posts). The horizon is the join of the two horizontal points, level within
    0.05 px across the frame; through the rails' point with the normal ``v - p`` it tilted
    by the vertical point's 1 degree (13 px across the frame, the path taken before the far
    point was joined)."""
    R = camera_rotation(0.3, 0.0, 0.0)
    up, across, ahead = (vanishing_point(K, d, R) for d in np.eye(3)[[1, 0, 2]])
    assert abs(across[2]) < 1e-12 and abs(ahead[1] / ahead[2] - K[1, 2]) > 100
    bent = up / up[2] + np.array([40.0, 0.0, 0.0])
    rng = np.random.default_rng(3)
    seg = _segments(
        _toward([bent], 15, rng) + _toward([across], 40, rng) + _toward([ahead / ahead[2]], 8, rng)
    )
    res = detect_vanishing_points(segments=seg, image_size=(768, 512), rng=0)
    assert res.K is None and res.K_reason is not None and "weakly" in res.K_reason
    assert res.vertical is not None and res.horizon is not None
    truth = horizon_line(K, R)
    for u in (0.0, 383.5, 767.0):
        assert _row_at(res.horizon, u) == pytest.approx(_row_at(truth, u), abs=0.05)


def test_level_horizon_joins_the_far_point_only_when_it_agrees_and_outweighs_the_vertical() -> None:
    """A far horizontal point whose join with the finite one is 10 degrees off the normal
    ``v - p`` does not belong with it: the horizon keeps ``v - p``'s normal through the
    finite point (as :func:`_anchor_horizon` does with K); one within 5 degrees is joined
    when its segments outweigh the vertical point's, not when the vertical's outweigh it."""
    from imageform.geometry.vp_detection import _level_horizon

    pp = np.array([383.5, 255.5])
    vertical = np.array([383.5, 2519.0, 1.0])
    finite = np.array([383.5, 30.0, 1.0])
    tilted = np.array([math.cos(math.radians(10.0)), math.sin(math.radians(10.0)), 0.0])
    strong_far = np.array([400.0, 300.0, 5000.0])
    line = _level_horizon(np.array([vertical, finite, tilted]), 0, pp, 18460.0, strong_far)
    assert line is not None
    assert np.allclose(line, [0.0, 1.0, -30.0])
    slight = np.array([math.cos(math.radians(2.0)), math.sin(math.radians(2.0)), 0.0])
    line = _level_horizon(np.array([vertical, finite, slight]), 0, pp, 18460.0, strong_far)
    assert line is not None
    assert line[:2] @ slight[:2] == pytest.approx(0.0, abs=1e-12)  # along the far point
    assert line @ finite == pytest.approx(0.0, abs=1e-9)
    strong_vertical = np.array([5000.0, 300.0, 400.0])
    line = _level_horizon(np.array([vertical, finite, slight]), 0, pp, 18460.0, strong_vertical)
    assert line is not None
    assert np.allclose(line, [0.0, 1.0, -30.0])
