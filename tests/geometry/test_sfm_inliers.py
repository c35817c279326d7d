"""reconstruct_sequence's inlier tests, each observation judged in the image through the lens.

The estimators run in undistorted pixels with one threshold for a pair or a frame (the
threshold times the median stretch of its keypoints). A fisheye's rim, stretched ten to
thirty times past that median, lost its matches and points there, and a track one rim
view of which pulled the unweighted point off its other views lost every view. Each match
is now judged by its Sampson distance in image pixels (``_sampson_image``), each pose's
correspondence by its reprojection error in the image, and each track triangulated on
the errors in the image, a failing view set aside rather than the track
(``benchmarks/results/sfm-inliers-2026-11-30k.md``).
"""

from __future__ import annotations

import numpy as np
import pytest

import imageform.geometry.sfm as sfm
from imageform.geometry import KannalaBrandt, reconstruct_sequence
from imageform.geometry._minimal import sampson_sq
from imageform.geometry.rotations import rvec_to_matrix
from imageform.geometry.sfm import _image_jacobian, _sampson_image, _triangulate_tracks
from tests import sfm_scenes

pytest.importorskip("cv2")

K = np.array([[110.0, 0, 159.5], [0, 110.0, 119.5], [0, 0, 1]])
LENS = KannalaBrandt(0.0, 0.0, 0.0, 0.0)


def _skew(t: np.ndarray) -> np.ndarray:
    return np.array([[0, -t[2], t[1]], [t[2], 0, -t[0]], [-t[1], t[0], 0]])


def _pair(n: int, rng: np.random.Generator) -> tuple[np.ndarray, ...]:
    """Points in front of two cameras (the second turned 5 degrees, moved sideways)."""
    R = np.asarray(rvec_to_matrix([0.0, np.radians(5.0), 0.0]))
    t = np.array([-1.0, 0.1, 0.05])
    d = rng.normal(size=(n, 3))
    d[:, 2] = np.abs(d[:, 2]) + 0.05  # rays up to 85 degrees off the axis
    X = d / np.linalg.norm(d, axis=1, keepdims=True) * rng.uniform(4, 8, (n, 1))
    return R, t, X


def _image(K_: np.ndarray, Xc: np.ndarray) -> np.ndarray:
    xn = Xc[:, :2] / Xc[:, 2:3]
    return np.asarray(LENS.distort(xn)) * K_[0, 0] + K_[:2, 2]


def _ideal(uv: np.ndarray) -> np.ndarray:
    return np.asarray(sfm._undistorted(uv, K, LENS))


def test_sampson_image_is_the_usual_one_without_a_lens() -> None:
    rng = np.random.default_rng(0)
    R, t, X = _pair(40, rng)
    p1 = (X @ K.T)[:, :2] / X[:, 2:3] + rng.normal(0, 0.7, (40, 2))
    X2 = X @ R.T + t
    p2 = (X2 @ K.T)[:, :2] / X2[:, 2:3]
    E = _skew(t) @ R
    Ki = np.linalg.inv(K)
    eye = np.broadcast_to(np.eye(2), (40, 2, 2))
    plain = np.sqrt(sampson_sq(Ki.T @ E @ Ki, p1, p2))
    np.testing.assert_allclose(_sampson_image(E, K, p1, p2, eye, eye), plain, rtol=1e-9)
    # an image that shrinks every step 4 times: the distance in its pixels is 4 times less
    np.testing.assert_allclose(
        _sampson_image(E, K, p1, p2, 0.25 * eye, 0.25 * eye), 0.25 * plain, rtol=1e-9
    )


def test_sampson_image_reads_a_fisheye_rim_as_its_pixels() -> None:
    """Half a pixel of noise in the fisheye's image: about half a pixel at every angle.

    In undistorted pixels the same noise reads tens of pixels at the rim (what the one
    threshold of a pair refused), in the image it stays within 1.5 px (first order)."""
    rng = np.random.default_rng(1)
    R, t, X = _pair(400, rng)
    u1 = _image(K, X) + rng.normal(0, 0.5, (400, 2))
    u2 = _image(K, X @ R.T + t) + rng.normal(0, 0.5, (400, 2))
    p1, p2 = _ideal(u1), _ideal(u2)
    ok = np.all(np.isfinite(p1), 1) & np.all(np.isfinite(p2), 1)
    p1, p2 = p1[ok], p2[ok]
    A1, A2 = _image_jacobian(K, LENS, p1), _image_jacobian(K, LENS, p2)
    E = _skew(t) @ R
    d = _sampson_image(E, K, p1, p2, A1, A2)
    Ki = np.linalg.inv(K)
    plain = np.sqrt(sampson_sq(Ki.T @ E @ Ki, p1, p2))
    off = np.degrees(np.arctan(np.linalg.norm((p1 - K[:2, 2]) / K[0, 0], axis=1)))
    rim = off > 70
    assert rim.sum() > 20
    assert np.percentile(d, 99) < 1.5
    assert np.median(plain[rim]) > 5 * np.median(d[rim])


def test_a_rim_view_does_not_pull_the_point_off_the_others() -> None:
    """Three views of a point; the third at a fisheye's rim, 1 image px = 20 undistorted px,
    its keypoint 0.5 image px (10 undistorted px) off. Weighed in the image the point
    reprojects within 0.6 px in every view; unweighted, the rim view pulls it."""
    Rs = np.stack([np.asarray(rvec_to_matrix([0.0, a, 0.0])) for a in (0.0, 0.05, 0.1)])
    ts = np.array([[0.0, 0, 0], [-0.5, 0, 0], [-1.0, 0, 0]])
    X = np.array([[0.3, -0.2, 5.0]])
    Xc = np.einsum("mij,j->mi", Rs, X[0]) + ts
    uv = (Xc @ K.T)[:, :2] / Xc[:, 2:3]
    uv[2] += [10.0, 0.0]  # 0.5 image px at the rim
    A = np.stack([np.eye(2), np.eye(2), 0.05 * np.eye(2)])
    fr, col = np.arange(3), np.zeros(3, np.int64)

    def image_errors(P: np.ndarray) -> np.ndarray:
        Pc = np.einsum("mij,j->mi", Rs, P[0]) + ts
        d = (Pc @ K.T)[:, :2] / Pc[:, 2:3] - uv
        return np.linalg.norm(np.einsum("mij,mj->mi", A, d), axis=1)

    weighed = image_errors(_triangulate_tracks(K, Rs, ts, fr, col, uv, 1, A))
    plain = image_errors(_triangulate_tracks(K, Rs, ts, fr, col, uv, 1))
    assert weighed.max() < 0.6
    assert plain.max() > 2.0


def _rim_walk(per_view: bool) -> tuple[int, int]:
    """The fisheye walk of test_sfm_fisheye, 6 frames: observations kept, those past 60 deg."""
    truth = sfm_scenes.poses(16)[:6]
    rng = np.random.default_rng(5)
    frames = [sfm_scenes.render(K, p, (320, 240), rng=rng, distortion=LENS) for p in truth]
    sfm._PER_VIEW_INLIERS = per_view
    sfm._TRACE = {}
    try:
        rec = reconstruct_sequence(frames, K, LENS, max_features=1500)
        T = sfm._TRACE
    finally:
        sfm._TRACE, sfm._PER_VIEW_INLIERS = None, True
    assert rec.registered.all(), rec.notes
    keep = T["o_ok"] & T["registered"][T["o_frame"]] & T["has_point"][T["o_track"]]
    pairs = zip(T["o_frame"][keep], T["o_kp"][keep], strict=True)
    xy = np.concatenate([T["xy"][f][[q]] for f, q in pairs])
    off = np.degrees(np.arctan(np.linalg.norm((_ideal(xy) - K[:2, 2]) / K[0, 0], axis=1)))
    return int(keep.sum()), int(np.sum(off > 60))


def test_a_fisheye_keeps_its_rim() -> None:
    """Six frames through the 166 degree fisheye, its camera given: the views kept past 60
    degrees off the axis go from 553 to 622 (all views 1812 -> 1906). 3 CPU seconds."""
    before_all, before_rim = _rim_walk(False)
    after_all, after_rim = _rim_walk(True)
    assert after_rim > 1.05 * before_rim, (before_rim, after_rim)
    assert after_all >= before_all, (before_all, after_all)


def test_no_lens_no_change() -> None:
    """Without a lens the per-view tests change nothing: the pinhole's estimators as before
    (1 CPU second)."""
    Kp = np.array([[300.0, 0, 199.5], [0, 300.0, 149.5], [0, 0, 1]])
    frames, _ = sfm_scenes.sequence(Kp, 4, (400, 300))
    sfm._PER_VIEW_INLIERS = False
    try:
        ref = reconstruct_sequence(frames, Kp, max_features=800)
    finally:
        sfm._PER_VIEW_INLIERS = True
    rec = reconstruct_sequence(frames, Kp, max_features=800)
    np.testing.assert_array_equal(rec.points, ref.points)
    np.testing.assert_array_equal(rec.R, ref.R)
