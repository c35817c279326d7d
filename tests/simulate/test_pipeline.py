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
    res = simulate(scene, progress=lambda name, f: calls.append((name, f)), rng=1)
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
    assert cc is not None and cc.lab_d65.shape == (24, 3) and cc.centers_uv.shape == (24, 2)
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
    assert set(m) == {
        "delta_e00_per_patch",
        "delta_e00_mean",
        "delta_e00_max",
        "snr_luminance_db_per_patch",
        "vanishing_point_error_px",
        "horizon_angle_error_deg",
        "exposure_time_s",
        "illuminant_cct_K",
        "illuminant_duv",
        "white_balance_gains",
        "color_correction_matrix",
        "step_times_s",
        "simulation_time_s",
    }
    assert len(m["delta_e00_per_patch"]) == 24 and len(m["snr_luminance_db_per_patch"]) == 24
    json.dumps(m)
    json.dumps(small.config)
    assert small.config["illuminant"]["name"] == "A"
    assert small.config["illuminant"]["temperature_K"] is None  # not a setting of CIE A


def test_metrics_agree_with_the_measurement(small: SimulationResult) -> None:
    # one measurement: the metrics are the result's PatchMeasurements, number for number
    p, m = small.patches, small.metrics
    assert p is not None and p.snr_stage == "color_corrected"
    assert m["delta_e00_per_patch"] == p.delta_e00.tolist()
    assert m["delta_e00_mean"] == p.delta_e00_mean and m["delta_e00_max"] == p.delta_e00_max
    assert m["snr_luminance_db_per_patch"] == p.snr_luminance_db.tolist()
    # one total time, which holds every step
    assert m["simulation_time_s"] >= sum(m["step_times_s"].values()) > 0
    assert [s.seconds for s in small.stages] == [m["step_times_s"][s.name] for s in small.stages]


def test_snr_is_the_luminance_snr_of_the_colour_corrected_patches(
    small: SimulationResult,
) -> None:
    # recomputed here from the kept stage (float32) with the Rec. 709 weights
    cc = small.colorchecker
    assert cc is not None and small.patches is not None
    img = small.stage("color_corrected").image.astype(np.float64)
    y = img @ np.array([0.2126, 0.7152, 0.0722])
    for k, (u, v) in enumerate(cc.centers_uv):
        r = cc.sample_radius_px
        win = y[
            int(np.ceil(v - r)) : int(np.floor(v + r)) + 1,
            int(np.ceil(u - r)) : int(np.floor(u + r)) + 1,
        ]
        snr = 20 * np.log10(win.mean() / win.std())
        assert small.patches.snr_luminance_db[k] == pytest.approx(snr, abs=1e-4)


def test_illuminant_cct_from_its_spectrum(small: SimulationResult) -> None:
    # CIE A is a 2856 K Planckian radiator by definition (CIE 15:2004 §3.1); cross-checked
    # with colour-science's Robertson (1968) on the same chromaticity
    colour = pytest.importorskip("colour")
    from imageform.spectral import illuminant, spectrum_to_xyz

    assert small.metrics["illuminant_cct_K"] == pytest.approx(2856.0, abs=1.0)
    assert abs(small.metrics["illuminant_duv"]) < 1e-3
    xyz = np.asarray(spectrum_to_xyz(illuminant("A"), illuminant=None))
    xy = xyz[:2] / xyz.sum()
    peer = colour.temperature.uv_to_CCT(colour.xy_to_UCS_uv(xy), method="Robertson 1968")
    assert small.metrics["illuminant_cct_K"] == pytest.approx(float(peer[0]), abs=0.01)
    assert small.metrics["illuminant_duv"] == pytest.approx(float(peer[1]), abs=1e-6)


@pytest.mark.parametrize(
    ("light", "cct"),
    [
        ({"type": "cie", "name": "D65"}, 6504.0),
        ({"type": "blackbody", "temperature_K": 3200.0}, 3200.0),
        ({"type": "daylight", "temperature_K": 5000.0}, 5000.0),
    ],
)
def test_illuminant_cct_of_other_lights(light: dict, cct: float) -> None:
    scene = default_scene().resized(48).with_changes(illuminant=light)
    res = simulate(scene, rng=0)
    # D65 is 6504 K; a blackbody is its own temperature; the D-series sits near (±15 K) the
    # nominal one (CIE 015:2018 §3.1: the nominal CCT of D50 is 5003 K)
    assert res.metrics["illuminant_cct_K"] == pytest.approx(cct, abs=15.0)


def test_progress_reports_monotone_to_one(small: SimulationResult) -> None:
    calls = small._calls  # type: ignore[attr-defined]
    fractions = [f for _, f in calls]
    assert len(calls) > 5 and all(isinstance(n, str) for n, _ in calls)
    assert fractions == sorted(fractions) and fractions[-1] == 1.0


def test_rng_makes_runs_reproducible() -> None:
    scene = default_scene().resized(64, 36)
    a = simulate(scene, rng=5).stage("raw").image
    b = simulate(scene, rng=5).stage("raw").image
    c = simulate(scene, rng=6).stage("raw").image
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    # a Generator is drawn from: two generators seeded alike give the same run
    g1 = simulate(scene, rng=np.random.default_rng(9)).stage("raw").image
    g2 = simulate(scene, rng=np.random.default_rng(9)).stage("raw").image
    np.testing.assert_array_equal(g1, g2)
    gen = np.random.default_rng(9)
    simulate(scene, rng=gen)
    assert not np.array_equal(simulate(scene, rng=gen).stage("raw").image, g1)  # advanced
    # None: fresh entropy each time
    assert not np.array_equal(
        simulate(scene, rng=None).stage("raw").image, simulate(scene).stage("raw").image
    )


def test_seed_is_a_deprecated_alias_of_rng() -> None:
    scene = default_scene().resized(64, 36)
    with pytest.warns(DeprecationWarning, match=r"seed=.*deprecated.*use rng="):
        old = simulate(scene, seed=5)
    new = simulate(scene, rng=5)
    for a, b in zip(old.stages, new.stages, strict=True):
        np.testing.assert_array_equal(a.image, b.image)
    assert old.metrics["vanishing_point_error_px"] == new.metrics["vanishing_point_error_px"]
    with pytest.warns(DeprecationWarning), pytest.raises(InvalidInputError, match="not both"):
        simulate(scene, rng=1, seed=2)
    with pytest.raises(InvalidInputError, match="expected rng to be an int seed"):
        simulate(scene, rng="7")  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="rng >= 0"):
        simulate(scene, rng=-1)


def test_measure_false_renders_the_same_stages_without_measuring() -> None:
    """The frames of a trajectory skip the measurements; the pixels are the same."""
    scene = default_scene().resized(96, 54)
    full = simulate(scene, rng=3)
    quick = simulate(scene, rng=3, measure=False)
    for a, b in zip(full.stages, quick.stages, strict=True):
        assert a.name == b.name
        np.testing.assert_array_equal(a.image, b.image)
    assert full.patches is not None and full.photon_transfer is not None
    assert quick.patches is None and quick.photon_transfer is None and quick.vanishing is None
    assert "delta_e00_mean" not in quick.metrics
    assert "photon_transfer" not in quick.metrics["step_times_s"]
    with pytest.raises(InvalidInputError, match="expected measure as True or False"):
        simulate(scene, measure="no")  # type: ignore[arg-type]


def test_colorchecker_options_need_a_chart() -> None:
    scene = load_scene({"objects": [{"type": "plane", "center_m": [0, 0, 0]}]})
    with pytest.raises(InvalidInputError, match="needs a colorchecker object"):
        simulate(scene)
    with pytest.raises(InvalidInputError, match="expected a Scene"):
        simulate({"render": {}})  # type: ignore[arg-type]


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_examples_render(path: Path) -> None:
    if "kodak" in path.read_text() and not (ROOT.parent / "shared" / "data").is_dir():
        pytest.skip("reference data not found")
    scene = load_scene(path).resized(96, 64)
    res = simulate(scene, rng=0)
    assert res.stages[-1].image.shape == (64, 96, 3)
    assert np.isfinite(res.stages[-1].image).all()
