"""The numba ArUco pipeline against its NumPy/SciPy twin (the component-by-component
implementation it replaced): the same markers, ids and corners, on photographs with a
ChArUco board at many poses, scales, blurs and noise levels, and on frames without one."""

from __future__ import annotations

import numpy as np
import pytest

from imageform.geometry import CharucoBoard, aruco_dictionary, detect_aruco_markers, detect_charuco
from imageform.geometry.aruco import _rotated_codes, _search_numba, _search_numpy
from tests.geometry.test_charuco import _composite, _kodak


def _both(g: np.ndarray, name: str = "5x5_100") -> tuple[dict, dict]:
    d = aruco_dictionary(name)
    big = max(g.shape)
    wins = sorted({max(3, int(big * f) | 1) for f in (0.015, 0.04, 0.10)}, reverse=True)
    args = (d, _rotated_codes(d.name), 12.0, int(d.max_correction_bits * 0.6), 0.35)
    return _search_numba(g, wins, *args), _search_numpy(g, wins, *args)


def _same(fast: dict, slow: dict) -> None:
    """The same ids, each with the same sightings (every one, in the order of their centres)."""
    assert sorted(fast) == sorted(slow)
    for mid in fast:
        a, b = (sorted(s, key=lambda x: tuple(x[1].mean(axis=0))) for s in (fast[mid], slow[mid]))
        assert len(a) == len(b)
        for x, y in zip(a, b, strict=True):
            np.testing.assert_allclose(x[1], y[1], atol=1e-9)
            assert x[2] == y[2]
            assert x[0] == pytest.approx(y[0], abs=1e-9)


def test_kernels_find_the_twins_markers_in_composites() -> None:
    board = CharucoBoard((7, 5), 30.0, 22.0, "5x5_100")
    rng = np.random.default_rng(5)
    total = 0
    for k in range(8):
        img, _ = _composite(
            rng,
            board,
            _kodak(k * 3 + 2),
            square_px=int(rng.integers(20, 60)),
            blur=float(rng.choice([0.0, 0.7, 1.5])),
            noise=float(rng.choice([0.0, 0.01, 0.03])),
            cut=k % 4 == 3,
        )
        fast, slow = _both(img / 255.0)
        _same(fast, slow)
        total += len(fast)
    assert total >= 8 * 8  # the comparison saw markers


def test_kernels_find_the_twins_markers_in_a_video_frame() -> None:
    from tests import video_scenes as vs

    tex, origin = vs.board_texture()
    K = np.array([[1000.0, 0, 639.5], [0, 1000.0, 359.5], [0, 0, 1]])
    for pose in vs.poses(8)[::3]:
        frame = vs.render(tex, origin, K, pose, (1280, 720))
        g = frame @ np.array([0.299, 0.587, 0.114]) / 255.0
        fast, slow = _both(g)
        _same(fast, slow)
        assert len(fast) == 17


def test_kernels_and_twin_agree_without_a_board() -> None:
    for i in (3, 8):
        fast, slow = _both(_kodak(i), "6x6_250")
        _same(fast, slow)


def test_numba_disabled_gives_the_same_corners(monkeypatch: pytest.MonkeyPatch) -> None:
    board = CharucoBoard((5, 7), 30.0, 24.0, "4x4_50")
    img = board.image(60, margin_px=30)
    fast = detect_charuco(img, board)
    monkeypatch.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
    slow = detect_charuco(img, board)
    np.testing.assert_array_equal(fast.ids, slow.ids)
    np.testing.assert_allclose(fast.corners, slow.corners, atol=1e-9)


def test_dark_components_asks_for_room_when_the_runs_overflow() -> None:
    """More runs than ``cap``: every output empty (the caller retries with the worst case);
    a fine noise image overflows the first guess and still gives the twin's (no) markers."""
    from imageform._kernels.aruco import box_integral, dark_components

    g = np.random.default_rng(3).random((120, 160))
    integral = box_integral(g, 7)
    runs, _, _, stats = dark_components(g, integral, 7, 15, 0.02, 50, 50)
    assert len(runs) == 0 and stats.shape == (0, 5)
    runs, _, _, stats = dark_components(g, integral, 7, 15, 0.02, 120 * 80, 20)  # labels
    assert len(runs) == 0 and stats.shape == (0, 5)
    runs, comp_runs, comp_ptr, stats = dark_components(
        g, integral, 7, 15, 0.02, 120 * 80 + 2, 120 * 80 + 2
    )
    assert stats[1:, 0].sum() == (runs[:, 2] - runs[:, 1] + 1).sum()
    assert comp_ptr[-1] == len(runs) == len(comp_runs)
    noise = np.random.default_rng(4).random((400, 400))  # ~0.25 runs a pixel: overflows
    fast, slow = _both(noise)
    _same(fast, slow)


def _bowed_marker(k1: float, side: int = 720, n: int = 1400) -> np.ndarray:
    """A ``side``-pixel 4x4 marker (id 3) seen through radial distortion ``k1`` and a blur."""
    from scipy import ndimage

    from imageform.geometry import aruco_marker_image

    canvas = np.full((n, n), 230.0)
    o = (n - side) // 2
    canvas[o : o + side, o : o + side] = 20 + aruco_marker_image(3, "4x4_50", size_px=side) * (
        210 / 255
    )
    c = (n - 1) / 2
    v, u = np.mgrid[0:n, 0:n].astype(float)
    f = 1 + k1 * ((u - c) ** 2 + (v - c) ** 2) / (n / 2) ** 2
    out = ndimage.map_coordinates(canvas, [c + (v - c) * f, c + (u - c) * f], order=1, cval=230)
    return ndimage.gaussian_filter(out, 1.5).round() / 255.0


@pytest.mark.parametrize("k1", [0.03, 0.06])
def test_large_marker_with_bowed_sides_is_read_by_both_twins(k1: float) -> None:
    """A marker of several hundred pixels whose sides bow by 3-6 px (a wide lens, a bent
    print; a 12-megapixel photograph of a floor board showed 3-10 px) is read: the corner
    tolerance grows with the marker (3 % of its side), it was 3 px whatever the size."""
    g = _bowed_marker(k1)
    fast, slow = _both(g, "4x4_50")
    _same(fast, slow)
    assert sorted(fast) == [3]


def test_integer_threshold_gives_the_float_thresholds_components() -> None:
    """A uint8 image thresholded in integers (``10 g w² < 10 S - 51 w²``) gives the dark pixels
    of the floating-point test on ``g / 255``: the same runs and components."""
    from imageform._kernels.aruco import (
        box_integral,
        box_integral_u8,
        dark_components,
        dark_components_u8,
    )

    rng = np.random.default_rng(8)
    images = [rng.integers(0, 256, (90, 130)).astype(np.uint8)]
    images.append(np.clip(_kodak(5), 0, 255).round().astype(np.uint8))
    for g8 in images:
        pad = 40
        table = box_integral_u8(g8, pad, np.empty((g8.shape[0] + 81, g8.shape[1] + 81), np.int32))
        np.testing.assert_array_equal(table, np.round(box_integral(g8 / 255.0, pad) * 255))
        for win in (3, 15, 81):
            cap = g8.shape[0] * ((g8.shape[1] + 1) // 2) + 2
            fast = dark_components_u8(g8, table, pad, win, cap, cap)
            slow = dark_components(
                g8 / 255.0, box_integral(g8 / 255.0, pad), pad, win, 0.02, cap, cap
            )
            for a, b in zip(fast, slow, strict=True):
                np.testing.assert_array_equal(a, b)


def test_region_table_equals_the_images() -> None:
    from imageform._kernels.aruco import box_integral, box_integral_roi, dark_components

    g = np.random.default_rng(2).random((70, 90))
    pad = 12
    whole = box_integral(g, pad)
    r0, r1, c0, c1 = 5, 40, 0, 33
    part = box_integral_roi(g, pad, r0, r1, c0, c1, np.empty((r1 - r0 + 25, c1 - c0 + 25)))
    # differences of the tables (window sums) agree to rounding inside the region
    a = whole[r0 : r1 + 2 * pad + 1, c0 : c1 + 2 * pad + 1]
    np.testing.assert_allclose(
        a[25:, 25:] - a[:-25, 25:] - a[25:, :-25] + a[:-25, :-25],
        part[25:, 25:] - part[:-25, 25:] - part[25:, :-25] + part[:-25, :-25],
        rtol=1e-12,
    )
    cap = 70 * 46
    sub = np.ascontiguousarray(g[r0:r1, c0:c1])
    runs_part = dark_components(sub, part, pad, 25, 0.02, cap, cap)[0]
    runs_view = dark_components(sub, np.ascontiguousarray(a), pad, 25, 0.02, cap, cap)[0]
    np.testing.assert_array_equal(runs_part, runs_view)


def test_decode_cells_gives_the_twins_verdicts() -> None:
    from imageform._kernels.aruco import decode_cells
    from imageform.geometry.aruco import _decode

    rng = np.random.default_rng(0)
    for name in ("4x4_50", "5x5_100", "6x6_250", "4x4_1000"):
        d = aruco_dictionary(name)
        cells, rot = d.marker_size + 2, _rotated_codes(name)
        means = rng.random((300, cells * cells))
        for j in range(150):  # codes read with a few flipped cells and noise
            code = np.zeros((cells, cells))
            code[1:-1, 1:-1] = np.rot90(d.codes[rng.integers(d.size)], int(rng.integers(4)))
            code = np.where(rng.random(code.shape) < 0.05, 1 - code, code)
            means[j] = (0.2 + 0.6 * code + rng.normal(0, 0.05, code.shape)).ravel()
        means[5] = 0.5  # no contrast
        for bits, border, contrast in ((1, 0.35, 0.08), (3, 0.5, 0.04), (0, 0.35, 0.08)):
            want = _decode(means, d, cells, rot, bits, border, contrast)
            code_, r, dist, con = decode_cells(means, rot, cells, bits, border, contrast)
            got = [
                None if code_[j] < 0 else (int(code_[j]), int(r[j]), int(dist[j]), float(con[j]))
                for j in range(len(means))
            ]
            assert got == want


def test_reduced_search_finds_the_full_resolution_markers() -> None:
    """A large view (2400 x 1800) searched on the image reduced twice and each candidate
    fitted again at full resolution: the markers and corners of the full-resolution search."""
    import cv2

    from imageform.geometry.aruco import _reduction

    board = CharucoBoard((7, 5), 30.0, 22.0, "5x5_100")
    rng = np.random.default_rng(11)
    bg = cv2.resize(_kodak(7), (2400, 1800), interpolation=cv2.INTER_LINEAR)
    img, _ = _composite(rng, board, bg, square_px=160, blur=1.0, noise=0.01, cut=False)
    g = img / 255.0
    assert _reduction(g.shape, None) == 2  # the default: markers of 0.75 % of 2400 px kept
    assert _reduction(g.shape, 6.0) == 1 and _reduction(g.shape, 11.0) == 1  # asked for 6 px
    assert _reduction(g.shape, 12.0) == 2 and _reduction(g.shape, 48.0) == 2  # at most 0.75 %
    assert _reduction((1200, 1599), None) == 1
    d = aruco_dictionary("5x5_100")
    wins = sorted({max(3, int(2400 * f) | 1) for f in (0.015, 0.04, 0.10)}, reverse=True)
    args = (d, _rotated_codes(d.name), 6.0, int(d.max_correction_bits * 0.6), 0.35)
    full = _search_numba(g, wins, *args)
    reduced = _search_numba(g, wins, *args, reduce=2)
    _same(reduced, full)
    assert len(full) == 17
    # the integer threshold of the uint8 image: the same markers again
    _same(_search_numba(g, wins, *args, g8=img), full)


def test_min_side_px_asks_for_the_full_resolution_search() -> None:
    """Small ChArUco markers (about 20 px) in a 4000 x 3000 view: the default's reduced search
    (markers of 0.75 % of the larger side, as OpenCV's default) may drop some; ``min_side_px=6``
    searches at full resolution and finds every marker, as the search did before."""
    import cv2

    board = CharucoBoard((7, 5), 30.0, 22.0, "5x5_100")
    rng = np.random.default_rng(3)
    bg = cv2.resize(_kodak(3), (4000, 3000), interpolation=cv2.INTER_LINEAR)
    img, _ = _composite(rng, board, bg, square_px=28, blur=0.7, noise=0.01, cut=False)
    full = detect_aruco_markers(img, "5x5_100", min_side_px=6)
    assert len(full) == 17
    default = detect_aruco_markers(img, "5x5_100")
    assert set(default.ids.tolist()) <= set(full.ids.tolist())


def test_block_means_u8_rounds_each_blocks_mean() -> None:
    """The uint8 reduction of a 4K frame's marker search: each block's mean, rounded."""
    from imageform._kernels.aruco import block_means_u8

    g8 = np.random.default_rng(3).integers(0, 256, (37, 50), dtype=np.uint8)
    for f in (2, 3):
        h, w = 37 // f, 50 // f
        ref = np.floor(g8[: h * f, : w * f].reshape(h, f, w, f).mean(axis=(1, 3)) + 0.5)
        out = block_means_u8(g8, f)
        assert out.dtype == np.uint8 and out.shape == (h, w)
        np.testing.assert_array_equal(out, ref.astype(np.uint8))


def test_luma_u8_is_the_detectors_luma_rounded_and_its_numpy_twin() -> None:
    """A 4K RGB frame's grey (BoardTracker): 0.299 R + 0.587 G + 0.114 B rounded, both paths."""
    from imageform._kernels.aruco import luma_u8
    from imageform.geometry.aruco import _luma_u8_numpy

    rng = np.random.default_rng(5)
    rgb = rng.integers(0, 256, (41, 67, 3), dtype=np.uint8)
    rgb[0, :8] = [[0, 0, 0], [255, 255, 255], [255, 0, 0], [0, 255, 0], [0, 0, 255],
                  [1, 1, 1], [254, 255, 254], [128, 127, 129]]  # fmt: skip
    ref = np.floor(rgb.astype(np.float64) @ [0.299, 0.587, 0.114] + 0.5)
    out = luma_u8(rgb)
    assert out.dtype == np.uint8 and out.shape == (41, 67)
    np.testing.assert_array_equal(out, ref.astype(np.uint8))
    np.testing.assert_array_equal(_luma_u8_numpy(rgb), out)
    # the division by 1000 without a division: exact over every sum the weights reach
    s = np.arange(0, 255 * 1000 + 1, dtype=np.int64) + 500
    np.testing.assert_array_equal((s * 67109) >> 26, s // 1000)


def _two_sevens() -> np.ndarray:
    """Marker 7 printed twice (120 and 90 px) and marker 3 once, on white."""
    from imageform.geometry import aruco_marker_image

    canvas = np.full((300, 560), 255, np.uint8)
    canvas[40:160, 30:150] = aruco_marker_image(7, "4x4_50", size_px=120)
    canvas[60:150, 230:320] = aruco_marker_image(7, "4x4_50", size_px=90)
    canvas[40:160, 400:520] = aruco_marker_image(3, "4x4_50", size_px=120)
    canvas[200:260, 30:300] = 140  # a grey bar: no marker
    return canvas


def test_every_sighting_of_an_id_on_request(monkeypatch: pytest.MonkeyPatch) -> None:
    """``all_sightings``: both prints of id 7 (the clearer, then the other), OpenCV's ids;
    the default keeps one sighting an id (the clearer), as before; the twin agrees."""
    cv2 = pytest.importorskip("cv2")
    img = _two_sevens()
    one = detect_aruco_markers(img, "4x4_50")
    every = detect_aruco_markers(img, "4x4_50", all_sightings=True)
    assert one.ids.tolist() == [3, 7]
    assert every.ids.tolist() == [3, 7, 7]
    np.testing.assert_array_equal(one.corners, every.corners[:2])  # the clearer first
    np.testing.assert_allclose(sorted(every.corners[1:, 0, 0]), [29.5, 229.5], atol=0.3)
    assert every.hamming.tolist() == [0, 0, 0]
    det = cv2.aruco.ArucoDetector(
        cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50), cv2.aruco.DetectorParameters()
    )
    corners, ids, _ = det.detectMarkers(img)
    assert sorted(ids.ravel().tolist()) == every.ids.tolist()
    for c, i in zip(corners, ids.ravel(), strict=True):  # the same corners, within a pixel
        near = np.abs(every.corners[every.ids == i] - c.reshape(4, 2)).max(axis=(1, 2)).min()
        assert near < 1.0
    monkeypatch.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
    slow = detect_aruco_markers(img, "4x4_50", all_sightings=True)
    np.testing.assert_array_equal(slow.ids, every.ids)
    np.testing.assert_allclose(slow.corners, every.corners, atol=1e-9)


def test_one_marker_found_twice_is_one_sighting() -> None:
    """Sightings of an id whose centres lie within half a side are one marker (the clearer)."""
    from imageform.geometry.aruco import _sightings

    sq = np.array([[0.0, 0.0], [40.0, 0.0], [40.0, 40.0], [0.0, 40.0]])
    kept = _sightings([(0.5, sq + 3.0, 1), (0.9, sq, 0), (0.7, sq + [100.0, 0.0], 0)])
    assert [s[0] for s in kept] == [0.9, 0.7]


def test_span_hull_is_qhulls() -> None:
    """The rows' spans' hull (status 6's test): twice Qhull's area, in integers."""
    from scipy.spatial import ConvexHull

    from imageform._kernels.aruco import _span_hull

    rng = np.random.default_rng(8)
    for _ in range(300):
        n = int(rng.integers(2, 40))
        first = rng.integers(0, 30, n).astype(np.int64)
        last = first + rng.integers(0, 30, n)
        spans, twice, _ = _span_hull(first, last, np.empty(4 * n + 2, np.int64))
        rows = np.arange(n)
        pts = np.concatenate([np.stack([first, rows], 1), np.stack([last, rows], 1)])
        assert spans == int(np.sum(last - first + 1))
        assert twice == pytest.approx(2 * ConvexHull(pts.astype(float)).volume, abs=1e-9)


def test_a_holed_cross_is_left_before_its_boundary_is_traced() -> None:
    """A dark X with a ring at its centre (holed, its rows' spans about half their hull):
    status 6, in both twins; a marker (spans filling their hull) is read as before."""
    from imageform._kernels.aruco import box_integral, component_quads, dark_components
    from imageform.geometry import aruco_marker_image
    from imageform.geometry.aruco import _spans_thin

    g = np.ones((200, 400))
    for d in range(-2, 3):
        idx = np.arange(20, 180)
        g[idx, np.clip(idx + d, 0, 399)] = 0.0  # one arm
        g[idx, np.clip(200 - idx + d, 0, 399)] = 0.0  # the other
    g[90:111, 90:111] = 0.0
    g[95:106, 95:106] = 1.0  # a ring (a hole) where the arms cross
    g[40:160, 250:370] = aruco_marker_image(7, "4x4_50", size_px=120) / 255.0
    integral = box_integral(g, 30)
    runs, comp_runs, comp_ptr, stats = dark_components(g, integral, 30, 61, 0.02, 200 * 200, 20000)
    cand = np.nonzero(stats[:, 0] > 500)[0]
    _, status = component_quads(runs, comp_runs, comp_ptr, cand, stats, 6.0)
    boxes = stats[cand]
    cross = int(np.argmin(boxes[:, 3]))  # the leftmost: the X
    assert status[cross] == 6 and status[1 - cross] == 0
    r0, r1, c0, c1 = boxes[cross, 1:]
    assert _spans_thin(g[r0 : r1 + 1, c0 : c1 + 1] < 0.5)
    m = detect_aruco_markers((g * 255).astype(np.uint8), "4x4_50")
    assert m.ids.tolist() == [7]


def test_quad_pretest_never_refuses_a_quad_the_boundary_gives() -> None:
    """``_quad_possible`` (the spans' hull vertices, each tried as the first point) is False
    only where ``_quad`` on the traced boundary and the sides' test refuse too: on random
    squares, discs, triangles, Ls and blobs, rasterised at random poses; and it refuses
    most of the shapes that are no quadrilateral."""
    from imageform._kernels.aruco import _quad, _quad_possible, _span_hull

    rng = np.random.default_rng(11)
    refused = kept = 0
    for k in range(120):
        n = 48
        v, u = np.mgrid[0:n, 0:n] - (n - 1) / 2 + rng.uniform(-0.5, 0.5, 2)[:, None, None]
        a = rng.uniform(0, np.pi)
        x, y = np.cos(a) * u + np.sin(a) * v, -np.sin(a) * u + np.cos(a) * v
        r = rng.uniform(6, 20)
        kind = k % 5
        if kind == 0:  # a square, a little sheared
            mask = (np.abs(x + 0.2 * rng.uniform(-1, 1) * y) < r) & (np.abs(y) < r * 0.9)
        elif kind == 1:  # a disc
            mask = x**2 + y**2 < r * r
        elif kind == 2:  # a triangle
            mask = (y > -r) & (y < r - np.abs(2 * x))
        elif kind == 3:  # an L
            mask = ((np.abs(x) < r) & (np.abs(y) < r)) & ~((x > 0) & (y > 0))
        else:  # a blob
            mask = x**2 / r**2 + y**2 / (0.5 * r) ** 2 + 0.3 * np.sin(3 * x / r) < 1
        if mask.sum() < 20:
            continue
        rows = np.flatnonzero(mask.any(axis=1))
        sub = mask[rows[0] : rows[-1] + 1]
        first = np.argmax(sub, axis=1).astype(np.int64)
        last = (n - 1 - np.argmax(sub[:, ::-1], axis=1)).astype(np.int64)
        hull = np.empty(4 * len(sub) + 2, np.int64)
        _, _, top = _span_hull(first, last, hull)
        pad = np.pad(mask, 1)
        inner = pad[:-2, 1:-1] & pad[2:, 1:-1] & pad[1:-1, :-2] & pad[1:-1, 2:]
        vv, uu = np.nonzero(mask & ~inner)
        pts = np.column_stack([uu, vv]).astype(np.float64)
        area = float(mask.sum())
        quad = np.empty((4, 2))
        ok = bool(_quad(pts, area, quad))
        if ok:
            s = np.hypot(*(np.roll(quad, -1, axis=0) - quad).T)
            ok = not (s.min() < 6.0 or s.min() < 0.25 * s.max())
        vx, vy = np.empty(4 * len(sub) + 2), np.empty(4 * len(sub) + 2)
        possible = bool(_quad_possible(hull, top, 0, int(rows[0]), area, 6.0, vx, vy))
        assert possible or not ok, (k, kind)
        refused += not possible
        kept += ok
    assert kept >= 20 and refused >= 35


def _upscaled_sheet(blur: float = 1.2, scale: float = 3.6) -> tuple[np.ndarray, np.ndarray]:
    """Eight 4x4 markers (ids 0-7) on a tilted sheet in a 640 x 360 frame (about 35 px each),
    blurred, and the frame enlarged ``scale`` times (bicubic): (small, enlarged)."""
    import cv2

    from imageform.geometry import aruco_marker_image

    px, q, w, h, S = 100, 20, 640, 360, 4
    cell = px + 2 * q
    sheet = np.full((2 * cell, 4 * cell), 255, np.uint8)
    for k in range(8):
        r, c = divmod(k, 4)
        sheet[r * cell + q : r * cell + q + px, c * cell + q : c * cell + q + px] = (
            aruco_marker_image(k, "4x4_50", size_px=px)
        )
    src = np.float32([[0, 0], [4 * cell, 0], [4 * cell, 2 * cell], [0, 2 * cell]])
    x0, x1, y0, y1 = 0.35 * w, 0.65 * w, 0.35 * h, 0.65 * h
    dst = np.float32([[x0, y0], [x1, y0 - 0.1 * h], [x1, y1 + 0.1 * h], [x0, y1]]) * S
    H = cv2.getPerspectiveTransform(src, dst)
    big = cv2.warpPerspective(sheet.astype(np.float32) * 0.8 + 20, H, (w * S, h * S))
    small = cv2.GaussianBlur(cv2.resize(big, (w, h), interpolation=cv2.INTER_AREA), (0, 0), blur)
    small += np.random.default_rng(0).normal(0, 2, small.shape)
    g = np.clip(small.round(), 0, 255).astype(np.uint8)
    return g, cv2.resize(g, None, fx=scale, fy=scale, interpolation=cv2.INTER_CUBIC)


def test_markers_read_small_are_read_enlarged() -> None:
    """A frame enlarged 3.6 times (a 12 Mpx frame of a webcam's sharpness: corners rounded
    by 3-6 px) gives the markers read at its own size, by both twins: the fitted corners'
    tolerance is 12 % of the side (at least 3 px); at 3 % (3 px at 100 px) 2 of the 8 were
    lost (OpenCV reads all 8)."""
    small, big = _upscaled_sheet()
    assert detect_aruco_markers(small, "4x4_50").ids.tolist() == list(range(8))
    assert detect_aruco_markers(big, "4x4_50").ids.tolist() == list(range(8))
    fast, slow = _both(big.astype(np.float64) / 255.0, "4x4_50")
    _same(fast, slow)
    assert sorted(fast) == list(range(8))


def test_a_colour_image_is_read_on_its_grey_uint8(monkeypatch: pytest.MonkeyPatch) -> None:
    """``detect_aruco_markers`` of an RGB(A) uint8 image: the markers and corners of its grey
    uint8 (luma rounded), by the integer threshold, as OpenCV reads a colour frame; no
    float64 image of three planes is made (it was)."""
    from imageform.geometry import aruco
    from imageform.geometry.aruco import _luma_u8_numpy

    _, big = _upscaled_sheet(scale=1.5)
    rng = np.random.default_rng(2)
    rgb = np.clip(big[..., None].astype(np.int16) + rng.integers(-9, 10, (1, 1, 3)), 0, 255)
    rgb = rgb.astype(np.uint8)
    grey = detect_aruco_markers(_luma_u8_numpy(rgb), "4x4_50")
    assert grey.ids.tolist() == list(range(8))
    real = aruco._gray01_checked

    def grey_only(image: object) -> np.ndarray:
        assert np.ndim(image) == 2, "a colour image took the float path"
        return real(image)

    monkeypatch.setattr(aruco, "_gray01_checked", grey_only)
    for image in (rgb, np.dstack([rgb, np.full(rgb.shape[:2], 255, np.uint8)])):
        got = detect_aruco_markers(image, "4x4_50")
        assert got.ids.tolist() == grey.ids.tolist()
        np.testing.assert_array_equal(got.corners, grey.corners)
