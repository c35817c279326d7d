"""simulate(): the stages, every result field, progress, seeds, example scenes."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from imageform.errors import InvalidInputError
from imageform.simulate import (
    STAGE_KINDS,
    SimulationResult,
    default_scene,
    load_scene,
    simulate,
)

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = sorted((ROOT / "examples" / "scenes").glob("*.toml"))


@pytest.fixture(scope="module")
def small() -> SimulationResult:
    calls: list[tuple[str, float]] = []
    scene = default_scene().resized(320, 180)
    res = simulate(scene, progress=lambda name, f: calls.append((name, f)), seed=1)
    object.__setattr__(res, "_calls", calls)
    return res


def test_stages_in_order(small: SimulationResult) -> None:
    names = [s.name for s in small.stages]
    assert names == [
        "rendered",
        "optics",
        "raw",
        "demosaiced",
        "shading_corrected",
        "white_balanced",
        "color_corrected",
        "output",
    ]
    assert all(s.kind in STAGE_KINDS for s in small.stages)
    out = small.stages[-1]
    assert out.kind == "srgb" and out.image.shape == (180, 320, 3)
    assert out.image.min() >= 0.0 and out.image.max() <= 1.0
    raw = small.stage("raw")
    assert raw.image.shape == (180, 320) and raw.image.dtype == np.uint16
    assert raw.white_level == 4095.0 and raw.image.max() <= raw.white_level
    assert all(s.seconds >= 0 and s.description for s in small.stages)


def test_every_field_is_filled(small: SimulationResult) -> None:
    assert small.image_size == (320, 180) and small.scene_name == "default"
    assert {q.name for q in small.quads} == {"ground with rails", "ColorChecker", "checkerboard"}
    assert all(q.corners.shape == (4, 3) for q in small.quads)
    cc = small.colorchecker
    assert cc is not None and cc.lab_d65.shape == (24, 3) and cc.centres_uv.shape == (24, 2)
    assert cc.sample_radius_px > 1
    # ColorChecker "white 9.5" under D65: L* = 96.5 (BabelColor average, ±0.5)
    assert cc.lab_d65[18, 0] == pytest.approx(96.5, abs=0.6)
    assert set(small.patch_xy) == {
        "before_white_balance",
        "after_white_balance",
        "after_color_correction",
    }
    assert all(v.shape == (24, 2) for v in small.patch_xy.values())
    vp = small.vanishing
    assert vp is not None and vp.vanishing_point.shape == (3,) and vp.horizon.shape == (3,)
    assert small.photon_transfer is not None and small.photon_transfer.mean_dn.size >= 10
    m = small.metrics
    for key in (
        "delta_e00_per_patch",
        "delta_e00_mean",
        "delta_e00_max",
        "snr_db_per_patch",
        "vanishing_point_error_px",
        "horizon_angle_error_deg",
        "exposure_time_s",
        "white_balance_gains",
        "color_correction_matrix",
        "stage_seconds",
        "total_seconds",
    ):
        assert key in m, key
    assert len(m["delta_e00_per_patch"]) == 24 and len(m["snr_db_per_patch"]) == 24
    json.dumps(m)
    json.dumps(small.config)
    assert small.config["illuminant"]["name"] == "A"


def test_progress_reports_monotone_to_one(small: SimulationResult) -> None:
    calls = small._calls  # type: ignore[attr-defined]
    fractions = [f for _, f in calls]
    assert len(calls) > 5 and all(isinstance(n, str) for n, _ in calls)
    assert fractions == sorted(fractions) and fractions[-1] == 1.0


def test_seed_makes_runs_reproducible() -> None:
    scene = default_scene().resized(64, 36)
    a = simulate(scene, seed=5).stage("raw").image
    b = simulate(scene, seed=5).stage("raw").image
    c = simulate(scene, seed=6).stage("raw").image
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)


def test_colorchecker_options_need_a_chart() -> None:
    scene = load_scene({"objects": [{"type": "plane", "centre_m": [0, 0, 0]}]})
    with pytest.raises(InvalidInputError, match="needs a colorchecker object"):
        simulate(scene)
    with pytest.raises(InvalidInputError, match="expected a Scene"):
        simulate({"render": {}})  # type: ignore[arg-type]


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_examples_render(path: Path) -> None:
    if "kodak" in path.read_text() and not (ROOT.parent / "shared" / "data").is_dir():
        pytest.skip("reference data not found")
    scene = load_scene(path).resized(96, 64)
    res = simulate(scene)
    assert res.stages[-1].image.shape == (64, 96, 3)
    assert np.isfinite(res.stages[-1].image).all()
