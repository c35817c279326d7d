"""Several ArUco markers on one object: the marker map, its file, and its tracker.

Frames are imageform's marker images placed by the map's corners and warped by known poses
(tests/video_scenes.map_frame: 4x4 supersampled, blurred, with sensor noise); the truth is
each frame's pose. OpenCV's GridBoard is the reference for the grid's layout.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.geometry import (
    BrownConrady,
    MarkerMap,
    MarkerMapTracker,
    MarkerTracker,
    grid_marker_map,
    look_at,
    marker_points,
)
from imageform.io import read_marker_map, write_marker_map
from tests import video_scenes

cv2 = pytest.importorskip("cv2")

K = np.array([[520.0, 0, 319.5], [0, 520.0, 179.5], [0, 0, 1]])
SIZE = (640, 360)
GRID = grid_marker_map((3, 2), 30.0, 10.0, dictionary="4x4_50")


def _angle(Ra: np.ndarray, Rb: np.ndarray) -> float:
    return float(np.degrees(np.arccos(np.clip((np.trace(Ra @ Rb.T) - 1) / 2, -1, 1))))


def _path(n: int, distance: float = 380.0) -> list[tuple[np.ndarray, np.ndarray]]:
    centre = np.array([50.0, 30.0, 0.0])
    out = []
    for i in range(n):
        a = 2 * np.pi * i / n
        eye = centre + np.array([90 * np.cos(a), 60 * np.sin(a), -distance])
        p = look_at(eye, centre, up=(0.0, -1.0, 0.0))
        out.append((np.asarray(p.R, np.float64), np.asarray(p.t, np.float64)))
    return out


def _frames(path: list, marker_map: MarkerMap = GRID, **kw: object) -> list[np.ndarray]:
    rng = np.random.default_rng(3)
    return [
        video_scenes.map_frame(K, p, SIZE, marker_map, blur=0.6, rng=rng, **kw)  # type: ignore[arg-type]
        for p in path
    ]


def test_grid_is_opencvs_gridboard() -> None:
    d = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50)
    board = cv2.aruco.GridBoard((3, 2), 30.0, 10.0, d)
    np.testing.assert_allclose(np.array(board.getObjPoints()), GRID.corners)
    np.testing.assert_array_equal(board.getIds().ravel(), GRID.ids)


def test_marker_poses_carry_marker_points_onto_the_corners() -> None:
    R, t = GRID.marker_poses
    for i in range(len(GRID)):
        got = marker_points(30.0) @ R[i].T + t[i]
        np.testing.assert_allclose(got, GRID.corners[i], atol=1e-12)
        assert np.linalg.det(R[i]) == pytest.approx(1.0)
        assert R[i][2] @ [0, 0, -1] == pytest.approx(1.0)  # the print faces -z of the grid


@pytest.mark.parametrize(
    ("ids", "corners", "dictionary", "message"),
    [
        ([1, 1], [marker_points(1.0)] * 2, "4x4_50", "ids each once"),
        ([50], [marker_points(1.0)], "4x4_50", "ids 0 to 49"),
        ([1], [marker_points(1.0) * [1, 1.1, 1]], "4x4_50", "as a square"),
        ([1, 2], [marker_points(1.0)], "4x4_50", "(2, 4, 3)"),
        ([1], [marker_points(1.0)], "5x9", "dictionary"),
        ([[1]], [marker_points(1.0)], "4x4_50", "1-D array"),
    ],
)
def test_bad_maps(ids: object, corners: object, dictionary: str, message: str) -> None:
    with pytest.raises(InvalidInputError, match=re.escape(message)):
        MarkerMap(np.asarray(ids), np.asarray(corners), dictionary)


def test_track_a_grid_against_the_truth() -> None:
    path = _path(8)
    tracker = MarkerMapTracker(GRID, K)
    for (R, t), f in zip(path, _frames(path), strict=True):
        pose = tracker.update(f)
        assert pose.found and pose.corners == 24
        assert np.linalg.norm(pose.tvec - t) / np.linalg.norm(t) < 0.003
        assert _angle(pose.R, R) < 0.5
        c = pose.object_points @ R.T + t
        uv = c[:, :2] / c[:, 2:] * 520 + K[:2, 2]
        assert np.median(np.linalg.norm(pose.image_points - uv, axis=1)) < 0.4


def test_a_misread_marker_and_an_occluded_one_are_left_out() -> None:
    """Marker 5's place printed with id 0 (id 0 twice); marker 1 covered.

    Both sightings of id 0 reach the consensus: the misprint's corners disagree with markers
    2, 3 and 4 and are left out; the pose is theirs and the true marker 0's.
    """
    path = _path(6)
    tracker = MarkerMapTracker(GRID, K)
    for (R, t), f in zip(path, _frames(path, drawn={5: 0}), strict=True):
        f[132:188, 300:353] = 150  # a finger over marker 1 (the top row's middle)
        pose = tracker.update(f)
        assert pose.found
        used = {tuple(p) for p in pose.object_points[::4]}
        assert used - {tuple(GRID.corners[0, 0])} == {tuple(GRID.corners[i, 0]) for i in (2, 3, 4)}
        c = pose.object_points @ R.T + t  # a marker 0 used is the true one, not the misprint
        uv = c[:, :2] / c[:, 2:] * 520 + K[:2, 2]
        assert np.abs(pose.image_points - uv).max() < 1.5
        assert np.linalg.norm(pose.tvec - t) / np.linalg.norm(t) < 0.005
        assert _angle(pose.R, R) < 2.0  # three markers of 40 px in an L


def test_opencv_board_is_pulled_by_the_misread_marker() -> None:
    """The reference: OpenCV's matchImagePoints takes both instances of id 0."""
    (R, _t), f = _path(1)[0], _frames(_path(1), drawn={5: 0})[0]
    d = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50)
    det = cv2.aruco.ArucoDetector(d, cv2.aruco.DetectorParameters())
    board = cv2.aruco.Board(list(GRID.corners.astype(np.float32)), d, GRID.ids.astype(np.int32))
    corners, ids, _ = det.detectMarkers(f)
    X, uv = board.matchImagePoints(corners, ids)
    _, rv, _tv = cv2.solvePnP(X, uv, K, None)
    ours = MarkerMapTracker(GRID, K).update(f)
    assert _angle(ours.R, R) < 1.0
    assert _angle(cv2.Rodrigues(rv)[0], R) > 3 * _angle(ours.R, R)


def test_one_marker_map_is_marker_tracker() -> None:
    """One marker in a map: IPPE's two solutions and the continuity rule, as MarkerTracker."""
    from imageform.geometry import rvec_to_matrix

    side = 40.0
    one = MarkerMap(np.array([7]), marker_points(side)[None], "4x4_50")
    rng = np.random.default_rng(3)
    frames = []
    for i in range(24):
        tilt = 40 * np.exp(-i / 4) + 8 + 2 * np.sin(i / 3)
        R = np.diag([1.0, -1, -1]) @ np.asarray(
            rvec_to_matrix(np.array([0.6, 0.8, 0.0]) * np.radians(tilt))
        )
        t = np.array([20 * np.sin(i / 5), 10.0, 700.0])
        frames.append(video_scenes.marker_frame(K, (R, t), SIZE, noise=4.0, blur=0.8, rng=rng))
    a, b = MarkerMapTracker(one, K), MarkerTracker(7, side, K, dictionary="4x4_50")
    for f in frames:
        pa, pb = a.update(f), b.update(f)
        assert pa.found and pb.found
        np.testing.assert_allclose(pa.image_points, pb.image_points, atol=0.01)
        assert _angle(pa.R, pb.R) < 0.01
        np.testing.assert_allclose(pa.tvec, pb.tvec, rtol=1e-4)


def test_a_cube_of_markers() -> None:
    from benchmarks.check_track_markers import _cube_path, cube_map

    cube = cube_map()
    path = _cube_path(6)
    tracker = MarkerMapTracker(cube, K)
    for (R, t), f in zip(path, _frames(path, cube), strict=True):
        pose = tracker.update(f)
        assert pose.found and pose.corners >= 8
        assert np.linalg.norm(pose.tvec - t) / np.linalg.norm(t) < 0.01
        assert _angle(pose.R, R) < 1.0


def test_lost_frames_smoothing_and_reset() -> None:
    path = _path(4)
    frames = _frames(path)
    blank = np.full((SIZE[1], SIZE[0]), 90, np.uint8)
    tracker = MarkerMapTracker(GRID, K, smooth=0.5)
    first = tracker.update(frames[0])
    second = tracker.update(frames[1])
    assert first.found and second.found and second.searched == "box"
    raw = MarkerMapTracker(GRID, K).update(frames[1])
    np.testing.assert_allclose(second.tvec, 0.5 * (first.tvec + raw.tvec), atol=1e-3)
    lost = tracker.update(blank)
    assert not lost.found and np.all(np.isnan(lost.tvec)) and lost.searched == "none"
    assert tracker.update(frames[2]).searched == "frame"
    tracker.reset()
    assert tracker.update(frames[3]).searched == "frame"


def test_distortion_is_undone() -> None:
    d = BrownConrady(k1=-0.2, k2=0.05)
    (R, t) = _path(1)[0]
    f = _frames([(R, t)])[0]
    # the frame through a distorting lens: each pixel fetched from where the lens puts it
    h, w = f.shape
    u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    xy = np.stack([(u - K[0, 2]) / K[0, 0], (v - K[1, 2]) / K[1, 1]], -1)
    und, _ = d.undistort(xy.reshape(-1, 2))
    und = np.asarray(und).reshape(h, w, 2)
    mx = (und[..., 0] * K[0, 0] + K[0, 2]).astype(np.float32)
    my = (und[..., 1] * K[1, 1] + K[1, 2]).astype(np.float32)
    seen = cv2.remap(f, mx, my, cv2.INTER_LINEAR, borderValue=90)
    pose = MarkerMapTracker(GRID, K, d).update(seen)
    assert pose.found
    assert np.linalg.norm(pose.tvec - t) / np.linalg.norm(t) < 0.005
    assert _angle(pose.R, R) < 0.5


@pytest.mark.parametrize(
    ("kw", "message"),
    [
        ({"smooth": 0}, "smooth"),
        ({"min_markers": 7}, "min_markers"),
        ({"redetect": 0}, "redetect"),
    ],
)
def test_bad_tracker_arguments(kw: dict, message: str) -> None:
    with pytest.raises(InvalidInputError, match=message):
        MarkerMapTracker(GRID, K, **kw)


def test_trackers_share_the_camera_check() -> None:
    from imageform.geometry import BoardTracker

    bad = np.zeros((3, 3))
    for make in (
        lambda: MarkerMapTracker(GRID, bad),
        lambda: MarkerTracker(1, 1.0, bad),
        lambda: BoardTracker((4, 3), bad),
    ):
        with pytest.raises(InvalidInputError, match=r"K\[2, 2\] != 0"):
            make()
    with pytest.raises(InvalidInputError):
        MarkerMapTracker(GRID, K, "lens")  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="MarkerMap"):
        MarkerMapTracker("map", K)  # type: ignore[arg-type]


# -- the file ----------------------------------------------------------------------------


def test_file_round_trip(tmp_path: Path) -> None:
    m = MarkerMap(np.array([4, 9]), np.stack([marker_points(20.0), marker_points(20.0) + 30]))
    p = write_marker_map(tmp_path / "tool.toml", m)
    got = read_marker_map(p)
    assert got.dictionary == "6x6_250" and got.unit == "mm"
    np.testing.assert_array_equal(got.ids, m.ids)
    np.testing.assert_allclose(got.corners, m.corners)


def test_file_dictionary_default(tmp_path: Path) -> None:
    p = tmp_path / "m.toml"
    rows = ", ".join(str(list(r)) for r in marker_points(10.0).tolist())
    p.write_text(f"[[markers]]\nid = 3\ncorners = [{rows}]\n")
    assert read_marker_map(p, dictionary="4x4_50").dictionary == "4x4_50"
    p.write_text(f'dictionary = "5x5_100"\n[[markers]]\nid = 3\ncorners = [{rows}]\n')
    assert read_marker_map(p, dictionary="4x4_50").dictionary == "5x5_100"


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("markers = [", "not valid TOML"),
        ("unit = 'mm'\n", "markers: expected one"),
        ("[[markers]]\nid = 1\n", "both id and corners"),
        ("[[markers]]\nid = -1\ncorners = []\n", "integer >= 0"),
        ("[[markers]]\nid = 1\ncorners = [[0, 0, 0]]\n", "4 corners"),
        ("[[markers]]\nid = 1\ncorners = [[0,0,0],[1,0,0],[1,1,0],[0,2,0]]\n", "a square"),
        ("version = 9\n[[markers]]\nid = 1\ncorners = []\n", "newer"),
        ("format = 'x'\n", "imageform-marker-map"),
    ],
)
def test_bad_files(tmp_path: Path, text: str, message: str) -> None:
    p = tmp_path / "m.toml"
    p.write_text(text)
    with pytest.raises(InvalidInputError, match=message) as err:
        read_marker_map(p)
    assert str(p) in str(err.value) and "\n" not in str(err.value)


def test_file_unknown_key_and_missing(tmp_path: Path) -> None:
    p = tmp_path / "m.toml"
    p.write_text("colour = 1\n")
    with pytest.raises(UnknownOptionError, match="colour"):
        read_marker_map(p)
    with pytest.raises(InvalidInputError, match="does not exist"):
        read_marker_map(tmp_path / "none.toml")
    (tmp_path / "bin.toml").write_bytes(b"\xff\xfe\x00")
    with pytest.raises(InvalidInputError, match="not UTF-8"):
        read_marker_map(tmp_path / "bin.toml")
    with pytest.raises(InvalidInputError, match="MarkerMap"):
        write_marker_map(tmp_path / "x.toml", "map")  # type: ignore[arg-type]


def test_the_true_marker_of_an_id_read_twice_is_used() -> None:
    """Marker 5's place printed with id 0: both sightings of id 0 reach the consensus (the
    detector's ``all_sightings``), the true one is used in every frame, never the misprint,
    and never both (OpenCV's Board takes both: test_opencv_board_is_pulled_...)."""
    path = _path(6)
    tracker = MarkerMapTracker(GRID, K)
    for (R, t), f in zip(path, _frames(path, drawn={5: 0}), strict=True):
        pose = tracker.update(f)
        assert pose.found and pose.corners == 20  # markers 0-4
        firsts = pose.object_points[::4]
        assert sorted(map(tuple, firsts)) == sorted(tuple(GRID.corners[i, 0]) for i in range(5))
        c = pose.object_points @ R.T + t
        uv = c[:, :2] / c[:, 2:] * 520 + K[:2, 2]
        assert np.abs(pose.image_points - uv).max() < 1.5
        assert np.linalg.norm(pose.tvec - t) / np.linalg.norm(t) < 0.003
        assert _angle(pose.R, R) < 1.0


def test_a_first_frame_seeing_only_a_marker_read_twice_is_ambiguous() -> None:
    """The map's one marker in view with a misprinted copy beside it (the other markers out
    of view): the two sightings are equally supported, so the first frame gives no pose
    ("ambiguous", both sightings' corners). With the map's other markers in view a first
    frame is settled (only the true sighting agrees with them: the first frame of
    test_the_true_marker_of_an_id_read_twice_is_used)."""
    from benchmarks.check_track_duplicates import K as K_BENCH
    from benchmarks.check_track_duplicates import second_print

    truth, frames = second_print(7)  # marker 7 and, from frame 4 on, a 40 mm print of id 7
    lone = MarkerMap([7], [marker_points(30.0)], "4x4_50")
    tracker = MarkerMapTracker(lone, K_BENCH)
    pose = tracker.update(frames[6])
    assert not pose.found and pose.searched == "ambiguous"
    assert pose.image_points.shape == (8, 2)
    pose = tracker.update(frames[3])  # the copy not in view: found
    assert pose.found and pose.searched == "frame"
    assert np.linalg.norm(pose.tvec - truth[3][1]) / np.linalg.norm(truth[3][1]) < 0.02


def test_rival_sightings() -> None:
    """Equally supported hypotheses that take different sightings of one marker."""
    from imageform.geometry.marker_map import _rival_sightings

    which = np.array([0, 1, 0])
    assert _rival_sightings(np.array([[True, True, False], [False, False, True]]), which)
    assert not _rival_sightings(np.array([[True, True, False], [True, False, False]]), which)
    assert not _rival_sightings(np.array([[True, True, True]]), np.array([0, 1, 2]))


def test_one_sighting_of_a_marker_per_hypothesis() -> None:
    """Of two sightings of one marker that agree with a hypothesis, the nearer stays."""
    from imageform.geometry.marker_map import _one_each

    which = np.array([0, 1, 0, 2])
    agree = np.array([[True, True, True, False], [False, True, True, True], [True] * 4])
    err = np.array([[2.0, 1.0, 1.0, 9.0], [0.5, 1.0, 3.0, 1.0], [1.0, 1.0, 1.0, 1.0]])
    got = _one_each(agree, err, which)
    assert got.tolist() == [
        [False, True, True, False],
        [False, True, True, True],
        [True, True, False, True],
    ]
    plain = agree[:, :2]
    assert _one_each(plain, err[:, :2], np.array([0, 1])) is plain  # no id twice: as it is


def test_a_large_frame_goes_to_the_trackers_own_buffers() -> None:
    """A frame over 4 Mpx (the detector's per-thread buffers stop there): its float grey
    image and the corner refinement's float32 one are written into the tracker's buffers,
    the same arrays frame after frame, and the poses are bit for bit those of fresh arrays
    (the tracker's step run without its buffers)."""
    s = 4.5  # 2880 x 1620, 4.7 Mpx
    path = _path(3)
    frames = [
        cv2.resize(f, None, fx=s, fy=s, interpolation=cv2.INTER_LINEAR) for f in _frames(path)
    ]
    k = K.copy()
    k[:2, :2] *= s
    k[:2, 2] = (k[:2, 2] + 0.5) * s - 0.5
    lent = MarkerMapTracker(GRID, k, predict=False)
    fresh = MarkerMapTracker(GRID, k, predict=False)
    where = None
    for (R, _), f in zip(path, frames, strict=True):
        a, b = lent.update(f), fresh._update(f)
        assert a.found and b.found and _angle(a.R, R) < 1.0
        assert np.array_equal(a.R, b.R) and np.array_equal(a.tvec, b.tvec)
        now = {name: buf.ctypes.data for name, buf in lent._work.buffers.items()}
        assert {"grey", "grey32"} <= set(now) and (where is None or now == where)
        where = now
    assert not fresh._work.buffers
    one = MarkerTracker(0, 30.0, k, dictionary="4x4_50", predict=False)
    for f in frames:
        assert one.update(f).found
    assert {"grey", "grey32"} <= set(one._work.buffers)


def test_colour_frames_are_tracked_as_their_grey_uint8(monkeypatch: pytest.MonkeyPatch) -> None:
    """An RGB uint8 frame goes to its grey uint8 once (the detector's luma weights, rounded)
    and is tracked as that grey frame is, bit for bit, by both marker trackers: no float64
    three-plane image is made (it was, 300 MB a 12 Mpx frame)."""
    from imageform.geometry import aruco

    path = _path(3)
    rng = np.random.default_rng(8)
    rgbs = []
    for f in _frames(path):
        tint = rng.integers(-12, 13, size=(1, 1, 3))
        rgbs.append(np.clip(f[..., None].astype(np.int16) + tint, 0, 255).astype(np.uint8))
    greys = [aruco._luma_u8_numpy(c) for c in rgbs]
    real = aruco._gray01_checked

    def grey_only(image: object) -> np.ndarray:
        assert np.ndim(image) == 2, "a colour frame took the float path"
        return real(image)

    monkeypatch.setattr(aruco, "_gray01_checked", grey_only)
    for make in (
        lambda: MarkerMapTracker(GRID, K),
        lambda: MarkerTracker(int(GRID.ids[0]), 30.0, K, dictionary="4x4_50"),
    ):
        a, b = make(), make()
        for c, g in zip(rgbs, greys, strict=True):
            pa, pb = a.update(c), b.update(g)
            assert pa.found and pb.found and pa.searched == pb.searched
            np.testing.assert_array_equal(pa.image_points, pb.image_points)
            np.testing.assert_array_equal(pa.tvec, pb.tvec)
