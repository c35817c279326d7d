"""A ColorChecker beside many periodic textures (tiles, a grid of lines, a facade).

Found on a real photograph (DarSIA's ``baseline_with_laser_grid.jpg``, a fluid-flow rig
crossed by a laser grid, a ColorChecker Passport small in a corner; benchmarks/results/
chart-fresh-2026-11-30b.md and chart-third-2026-11-30d.md): the grid's cells and the rig's
other regular structures made eight lattices of a hundred cells or more, each ranked above
the chart's 24, and the search stopped after eight lattices without reaching the chart.
A lattice that continues far past a chart's 24 cells is a periodic texture: it is tried
once as a whole and does not use up the attempts left for lattices of a chart's size.
"""

from __future__ import annotations

import numpy as np

from imageform.analysis import detect_colorchecker, synthetic_chart_photo


def _tiles(pitch: int, n: int, grey: float, rng: np.random.Generator) -> np.ndarray:
    """An n x n grid of flat squares (side 0.7 pitch) of one grey on a darker ground."""
    side = n * pitch
    out = np.full((side, side, 3), 0.25 * grey)
    inner = round(0.7 * pitch)
    for i in range(n):
        for j in range(n):
            v0, u0 = i * pitch + (pitch - inner) // 2, j * pitch + (pitch - inner) // 2
            out[v0 : v0 + inner, u0 : u0 + inner] = grey + rng.normal(0.0, 0.003, 3)
    return out


def _scene(seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A chart in the top left corner and nine tiled textures around it (1000 x 1000)."""
    rng = np.random.default_rng([41, seed])
    canvas = np.full((1000, 1000, 3), 0.45) + rng.normal(0.0, 0.01, (1000, 1000, 3))
    photo = synthetic_chart_photo(
        canvas[:330, :330].copy(), width=0.8, tilt=10.0, rotation=5.0, shading=0.0, rng=rng
    )
    img = canvas.copy()
    img[:330, :330] = photo.image
    k = 0
    for r in range(4):
        for c in range(4):
            if r < 2 and c < 2:
                continue  # the chart's corner
            if k == 9:
                break
            pitch = 15 + k  # a lattice of its own each
            tex = _tiles(pitch, 10, rng.uniform(0.5, 0.9), rng)[:240, :240]
            v0, u0 = 250 * r + 5, 250 * c + 5
            img[v0 : v0 + tex.shape[0], u0 : u0 + tex.shape[1]] = tex
            k += 1
    return np.clip(img, 0.0, 1.0), photo.centers


def test_chart_beside_many_periodic_textures() -> None:
    for seed in range(2):
        img, centres = _scene(seed)
        det = detect_colorchecker(img)
        assert det.found, det.reason
        pitch = float(np.median(np.linalg.norm(np.diff(centres.reshape(4, 6, 2), axis=1), axis=2)))
        err = np.linalg.norm(det.centers - centres, axis=1) / pitch
        assert err.max() < 1 / 6


def test_periodic_textures_alone_are_no_chart() -> None:
    img, _ = _scene(0)
    img[:330, :330] = 0.45
    assert not detect_colorchecker(img).found


def test_degenerate_lattice_collects_only_its_own() -> None:
    from imageform.analysis.chart_detect import _on_lattice

    cand = {
        "c": np.array([[10.0, 10.0], [20.0, 10.0], [30.0, 10.0]]),
        "area": np.array([40.0, 40.0, 40.0]),
        "cov": np.tile(np.eye(2) * 3.3, (3, 1, 1)),
    }
    h = np.array([[10.0, 0.0, 10.0], [0.0, 0.0, 10.0], [0.0, 0.0, 1.0]])  # rank 2
    idx = np.array([0, 1, 2])
    keys = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    assert np.array_equal(_on_lattice(cand, h, idx, keys), idx)
