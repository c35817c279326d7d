"""Three finite vanishing points against their orthocentre: the consistency rule that refuses
(or narrows to a pair) a triplet that is not mutually orthogonal, and the opt-in principal
point estimate ``principal_point="estimate"``."""

from __future__ import annotations

import numpy as np
import pytest

from imageform.errors import InvalidInputError
from imageform.geometry import (
    camera_rotation,
    detect_line_segments,
    detect_vanishing_points,
    intrinsics_from_vanishing_points,
    vanishing_point,
)
from imageform.geometry.vp_detection import _orthocenter
from tests.geometry.scene_render import render_manhattan
from tests.geometry.test_line_segments_vp import K, _segments, _toward


def test_orthocenter_of_a_hand_computed_triangle() -> None:
    """The triangle (0, 0), (4, 0), (1, 3): the altitude from (1, 3) is x = 1, the one from
    (0, 0) (perpendicular to (4, 0) - (1, 3) = (3, -3)) is y = x, so the orthocentre is
    (1, 1); the altitude from (4, 0), perpendicular to (1, 3), passes through it too:
    ((1, 1) - (4, 0)) . (1, 3) = -3 + 3 = 0. Homogeneous scale does not matter; collinear
    points have none. An obtuse triangle has its orthocentre outside: (0, 0), (4, 0),
    (5, 1) gives (5, -5)."""
    o = _orthocenter(np.array([0.0, 0, 1]), np.array([8.0, 0, 2]), np.array([-1.0, -3, -1]))
    assert o is not None
    np.testing.assert_allclose(o, [1.0, 1.0], atol=1e-12)
    obtuse = _orthocenter(np.array([0.0, 0, 1]), np.array([4.0, 0, 1]), np.array([5.0, 1, 1]))
    assert obtuse is not None
    np.testing.assert_allclose(obtuse, [5.0, -5.0], atol=1e-12)
    line = [np.array([0.0, 0, 1]), np.array([1.0, 1, 1]), np.array([3.0, 3, 1])]
    assert _orthocenter(*line) is None
    # the principal point of intrinsics_from_vanishing_points for three orthogonal points
    Kt = np.array([[800.0, 0, 640], [0, 800, 360], [0, 0, 1]])
    vps = [vanishing_point(Kt, d, camera_rotation(0.4, 0.7)) for d in np.eye(3)]
    o3 = _orthocenter(*vps)
    assert o3 is not None
    np.testing.assert_allclose(o3, intrinsics_from_vanishing_points(*vps)[:2, 2], atol=1e-6)
    np.testing.assert_allclose(o3, [640.0, 360.0], atol=1e-6)


def _non_orthogonal(n_third: int) -> tuple[object, np.ndarray]:
    """A nearly level camera (pitch 0.06 rad: the vertical point 11 400 px above the principal
    point), its vertical point A (60 segments) and one horizontal point B (50), and a third
    point 40 px below the other horizontal direction's (``n_third`` segments): a direction
    1.4 degrees off the horizontal plane. With the principal point at the centre a focal
    length makes all three pairs orthogonal within 3.5 degrees (708 px before this rule),
    but their orthocentre, the principal point that would make them orthogonal, is 280 px
    to the right of the centre (36 % of the width)."""
    R = camera_rotation(0.06, 0.5, 0.0)
    A, B, C = (vanishing_point(K, d, R) for d in np.eye(3)[[1, 0, 2]])
    A, B, C = A / A[2], B / B[2], C / C[2] + np.array([0.0, 40.0, 0.0])
    o = _orthocenter(A, B, C)
    assert o is not None and o[0] - K[0, 2] == pytest.approx(280.0, abs=1.0)
    rng = np.random.default_rng(7)
    seg = _segments(_toward([A], 60, rng) + _toward([B], 50, rng) + _toward([C], n_third, rng))
    return seg, np.array([A, B, C])


def test_inconsistent_triplet_falls_back_to_the_best_supported_pair() -> None:
    """The third point weakly supported (20 segments against B's 50): f from A and B alone,
    f^2 = -(A - p).(B - p) = 700^2 exactly, said in ``K_note``; the third point stays in the
    set."""
    seg, true = _non_orthogonal(20)
    res = detect_vanishing_points(segments=seg, image_size=(768, 512))
    assert res.K is not None and res.K_reason is None
    assert res.K[0, 0] == pytest.approx(700.0, rel=0.002)
    np.testing.assert_allclose(res.K[:2, 2], K[:2, 2])
    assert res.K_note is not None and "two best-supported points" in res.K_note
    assert "orthocentre" in res.K_note and "\n" not in res.K_note
    assert len(res.vanishing_points) == 3
    for v in res.vanishing_points:
        assert min(np.hypot(*(v[:2] / v[2] - t[:2])) for t in true) < 3.0


def test_inconsistent_triplet_without_a_clearly_better_pair_is_refused() -> None:
    """The third point nearly as well supported as B (45 segments against 50): no pair
    stands out, and K is refused with a one-line reason naming the orthocentre."""
    seg, _ = _non_orthogonal(45)
    for pp in ("center", "estimate"):
        res = detect_vanishing_points(segments=seg, image_size=(768, 512), principal_point=pp)
        assert res.K is None and res.K_note is None and res.focal_spread is None
        assert res.K_reason is not None and "\n" not in res.K_reason
        assert res.K_reason.startswith("not determined: the three finite vanishing points are")
        assert "orthocentre" in res.K_reason
        assert res.horizon is not None  # the horizon does not need K


def test_estimate_finds_an_off_centre_principal_point_on_a_render() -> None:
    """A render whose principal point is (359.5, 279.5), 34 px from the centre, f = 700 px:
    ``principal_point="estimate"`` takes the orthocentre of the three finite, well-supported
    points (within 2 px of the truth) and f within 0.5 %; the default, at the centre, is
    2.8 % off."""
    Ko = np.array([[700.0, 0, 359.5], [0, 700.0, 279.5], [0, 0, 1]])
    img = render_manhattan(Ko, camera_rotation(0.25, 0.5, 0.03), np.zeros(3), seed=3)
    seg = detect_line_segments(img)
    est = detect_vanishing_points(segments=seg, image_size=(768, 512), principal_point="estimate")
    centre = detect_vanishing_points(segments=seg, image_size=(768, 512))
    assert est.K is not None and centre.K is not None and est.K_note is None
    np.testing.assert_allclose(est.K[:2, 2], Ko[:2, 2], atol=2.0)
    assert est.K[0, 0] == pytest.approx(700.0, rel=0.005)
    assert abs(centre.K[0, 0] / 700.0 - 1) > 0.02
    np.testing.assert_allclose(centre.K[:2, 2], [383.5, 255.5])


def test_estimate_keeps_the_centre_with_fewer_than_three_finite_points() -> None:
    """A level camera (two finite points, verticals parallel): nothing fixes the principal
    point, so K keeps the centre and ``K_note`` says why; the same K as the default."""
    R = camera_rotation(0.0, 0.6, 0.0)
    img = render_manhattan(K, R, np.zeros(3), seed=4)
    seg = detect_line_segments(img)
    est = detect_vanishing_points(segments=seg, image_size=(768, 512), principal_point="estimate")
    centre = detect_vanishing_points(segments=seg, image_size=(768, 512))
    assert est.K is not None and centre.K is not None
    np.testing.assert_allclose(est.K, centre.K)
    assert est.K_note is not None and "image centre" in est.K_note
    assert centre.K_note is None


def test_consistent_triplet_keeps_its_joint_fit() -> None:
    """Three orthogonal points (a render whose principal point is the centre): the rule
    leaves the support-weighted fit as it was, with no note."""
    img = render_manhattan(K, camera_rotation(0.25, 0.5, 0.03), np.zeros(3), seed=3)
    res = detect_vanishing_points(img)
    assert res.K is not None and res.K_note is None and res.K_reason is None
    assert res.K[0, 0] == pytest.approx(700.0, rel=0.03)


def test_estimate_bad_spelling() -> None:
    with pytest.raises(InvalidInputError, match="estimate"):
        detect_vanishing_points(np.zeros((20, 20)), principal_point="estimated")


def test_an_offset_that_resampling_explains_is_not_an_inconsistency(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The triplet of ``_non_orthogonal`` (the third point 40 px off, 45 segments) with the
    vertical point's 60 segments turned by 2 degrees (standard deviation) each: their
    orthocentre is 222 px right of the centre (29 % of the width), but resampling the
    segments moves it by more than a third of that, so the points are not refused and the
    three-point fit stands (f within 1 % of 700 px). With the box alone (no significance
    test) the same segments give no K."""
    import imageform.geometry.vp_detection as vp

    R = camera_rotation(0.06, 0.5, 0.0)
    A, B, C = (vanishing_point(K, d, R) for d in np.eye(3)[[1, 0, 2]])
    A, B, C = A / A[2], B / B[2], C / C[2] + np.array([0.0, 40.0, 0.0])
    rng = np.random.default_rng(5)
    turned = []
    for s in _toward([A], 60, rng):
        m, d = s.mean(axis=0), s[1] - s.mean(axis=0)
        t = np.radians(rng.normal(0.0, 2.0))
        e = np.array([np.cos(t) * d[0] - np.sin(t) * d[1], np.sin(t) * d[0] + np.cos(t) * d[1]])
        turned.append(np.stack([m - e, m + e]))
    seg = _segments(turned + _toward([B], 50, rng) + _toward([C], 45, rng))
    res = detect_vanishing_points(segments=seg, image_size=(768, 512))
    assert res.K is not None and res.K_note is None and res.K_reason is None
    assert res.K[0, 0] == pytest.approx(700.0, rel=0.01)
    assert len(res.vanishing_points) == 3
    o = _orthocenter(*res.vanishing_points)
    assert o is not None and o[0] - K[0, 2] > 0.2 * 768
    monkeypatch.setattr(vp, "_PP_SIGNIFICANT", 0.0)
    box_only = detect_vanishing_points(segments=seg, image_size=(768, 512))
    assert box_only.K is None and box_only.K_reason is not None
    assert "orthocentre" in box_only.K_reason
