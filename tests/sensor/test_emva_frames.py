"""EMVA 1288 from frame stacks (issue 18): parameters recovered from simulated frames within
3 % of the model, and the same numbers as the reference implementation emva1288 1.0.2."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from benchmarks.bench_emva import (
    SENSORS,
    emva1288_results,
    expected_saturation,
    record,
    truth,
)
from imageform.errors import DegenerateConfigurationError, ImageformError
from imageform.sensor import (
    SensorModel,
    cmos_preset,
    emva_snr,
    measure_emva,
    simulate_emva_frames,
)

SHAPE = (96, 96)


@pytest.fixture(scope="module")
def measured() -> dict[tuple[str, int], tuple]:
    """Frames and their measurement: every sensor of the benchmark, two seeds."""
    out = {}
    for name, s in SENSORS.items():
        for seed in (0, 1):
            f = record(s, seed, shape=SHAPE)
            out[name, seed] = (
                s,
                f,
                measure_emva(f.flats, f.darks, f.exposure_times, photons=f.photons),
            )
    return out


KEYS = [(n, seed) for n in SENSORS for seed in (0, 1)]


@pytest.mark.parametrize("key", KEYS, ids=[f"{n}-{s}" for n, s in KEYS])
def test_parameters_within_3_percent_of_the_model(measured, key) -> None:  # type: ignore[no-untyped-def]
    s, _f, m = measured[key]
    t = truth(s, SHAPE)
    assert m.system_gain == pytest.approx(t["K"], rel=0.03)
    assert m.dark_noise == pytest.approx(t["sigma_d"], rel=0.03)
    assert m.quantum_efficiency == pytest.approx(t["eta"], rel=0.03)
    assert m.dsnu == pytest.approx(t["dsnu"], rel=0.03)  # the chip's drawn pattern
    assert m.prnu == pytest.approx(t["prnu"], rel=0.03)
    # EMVA's saturation point is the peak of the photon-transfer curve, which the pixels'
    # spread (shot noise, PRNU) puts a few % below the clip (full well or ADC)
    assert m.saturation_capacity == pytest.approx(t["sat"], rel=0.03)
    assert 0.9 * t["clip"] < m.saturation_capacity < t["clip"]
    assert m.saturated and not m.dark_noise_upper_limit
    assert m.fit_points >= 15
    # the stacks nearest 50 % of saturation give DSNU and PRNU
    sig = m.mean_dn - m.dark_mean_dn
    assert sig[m.spatial_index] == pytest.approx(0.5 * sig[np.argmax(m.var_dn)], rel=0.1)


def test_saturation_of_a_shot_noise_limited_clip() -> None:
    """Without PRNU and DSNU the photon-transfer curve still peaks below the full well:
    about 3 shot-noise σ (1 % each at 10⁴ e⁻), as the censored-normal model predicts."""
    s = cmos_preset(prnu=0.0, dsnu=0.0, column_fpn=0.0, read_noise=2.0)
    want = expected_saturation(s, (128, 128))
    assert want == pytest.approx(0.972 * s.full_well, rel=0.002)
    f = record(s, 5, frames=2, shape=(128, 128))
    m = measure_emva(f.flats, f.darks, f.exposure_times, photons=f.photons)
    assert m.saturation_capacity == pytest.approx(want, rel=0.03)


def test_dark_current_from_the_dark_mean_slope() -> None:
    s = SensorModel(dark_current=2000.0, read_noise=3.0, dsnu=1.0, prnu=0.0, fpn_seed=2)
    times = np.linspace(0.0, 1.0, 8)
    f = simulate_emva_frames(
        s, irradiance=1e-5, wavelength_nm=550.0, exposure_times=times, rng=4, shape=(48, 48)
    )
    m = measure_emva(f.flats, f.darks, f.exposure_times)
    assert m.dark_current == pytest.approx(2000.0, rel=0.03)
    assert m.dark_current_var == pytest.approx(2000.0, rel=0.1)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_without_photon_counts(seed: int) -> None:
    """No photon counts: QE and μ_p.sat are NaN; the rest is the same, μ_e.sat within 1 %."""
    s = SENSORS["ccd (preset, DSNU 3 e-)"]
    f = record(s, seed, frames=4, shape=(48, 48))
    a = measure_emva(f.flats, f.darks, f.exposure_times, photons=f.photons)
    b = measure_emva(f.flats, f.darks, list(f.exposure_times))
    assert math.isnan(b.quantum_efficiency) and math.isnan(b.saturation_photons)
    for name in ("system_gain", "dark_noise", "dsnu", "prnu", "dark_current"):
        assert getattr(b, name) == getattr(a, name)
    assert b.saturation_capacity == pytest.approx(a.saturation_capacity, rel=0.01)


def test_snr_curve_model_and_measurement_agree() -> None:
    _s, _f, m = _one()
    below = (m.signal_electrons > 100) & (np.arange(m.mean_dn.size) < np.argmax(m.var_dn) - 3)
    np.testing.assert_allclose(m.snr_measured[below], m.snr_model[below], rtol=0.03)
    i = int(np.flatnonzero(below)[-1])
    want = emva_snr(
        float(m.photons[i]),
        quantum_efficiency=m.quantum_efficiency,
        dark_noise_e=m.dark_noise,
        system_gain=m.system_gain,
    )
    assert m.snr_model[i] == pytest.approx(want, rel=1e-12)
    assert m.snr_max == pytest.approx(math.sqrt(m.saturation_capacity))
    assert m.snr_max_db == pytest.approx(20 * math.log10(m.snr_max))
    thr = m.sensitivity_threshold  # the SNR is 1 there (eq. 13 solved exactly)
    assert thr / math.sqrt(m.dark_noise**2 + 1 / 12 / m.system_gain**2 + thr) == pytest.approx(1)
    assert m.dynamic_range == pytest.approx(m.saturation_capacity / thr)
    assert m.dynamic_range_db == pytest.approx(20 * math.log10(m.dynamic_range))
    assert m.dynamic_range_bits == pytest.approx(math.log2(m.dynamic_range))


def _one() -> tuple:
    s = SENSORS["cmos (preset, PRNU 0.5 %)"]
    f = record(s, 3, frames=2, shape=(64, 64))
    return s, f, measure_emva(f.flats, f.darks, f.exposure_times, photons=f.photons)


def test_dark_noise_below_quantisation_is_an_upper_limit() -> None:
    s = SensorModel(read_noise=0.3, dsnu=0.0, prnu=0.0, dark_current=0.0, conversion_gain=20e-6)
    f = record(s, 1, frames=2, shape=(32, 32))
    m = measure_emva(f.flats, f.darks, f.exposure_times, photons=f.photons)
    assert m.dark_noise_upper_limit
    assert m.dark_noise_dn == pytest.approx(math.sqrt(0.24))


def test_unequal_stacks_and_spatial_index() -> None:
    """Stacks may have different frame counts; ``spatial_index`` picks DSNU/PRNU's stacks."""
    _s, f, m = _one()
    flats = [f.flats[i] for i in range(len(f.flats))]
    flats[0] = np.concatenate([flats[0], flats[0][:1]])
    m2 = measure_emva(flats, f.darks, f.exposure_times, photons=f.photons, spatial_index=5)
    assert m2.spatial_index == 5 and m2.system_gain == m.system_gain
    assert m2.prnu != m.prnu


def test_exposures_in_any_order() -> None:
    _s, f, m = _one()
    order = np.random.default_rng(0).permutation(len(f.exposure_times))
    m2 = measure_emva(
        f.flats[order], f.darks[order], f.exposure_times[order], photons=f.photons[order]
    )
    for name in ("system_gain", "dark_noise", "quantum_efficiency", "saturation_capacity", "prnu"):
        assert getattr(m2, name) == pytest.approx(getattr(m, name), rel=1e-9), name
    assert order[m2.spatial_index] == m.spatial_index
    np.testing.assert_array_equal(m2.var_dn, m.var_dn[order])


def test_float_frames_give_the_same_result() -> None:
    _s, f, m = _one()
    m2 = measure_emva(f.flats.astype(np.float32), f.darks.astype(np.float64), f.exposure_times)
    assert m2.system_gain == pytest.approx(m.system_gain, rel=1e-12)
    assert m2.dsnu == pytest.approx(m.dsnu, rel=1e-9)


def _frames(n: int = 4, L: int = 2) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    s = cmos_preset(full_well=2000.0)
    f = simulate_emva_frames(
        s,
        irradiance=0.02,
        wavelength_nm=550.0,
        exposure_times=np.linspace(0, 0.03, n),
        rng=0,
        frames=L,
        shape=(8, 8),
    )
    return f.flats, f.darks, f.exposure_times


@pytest.mark.parametrize(
    ("change", "words"),
    [
        (lambda fl, dk, t: (fl[:, :1], dk, t, {}), "at least 2 frames in flats[0]"),
        (lambda fl, dk, t: (fl, dk[:, :, :4], t, {}), "of one size"),
        (lambda fl, dk, t: (fl[0], dk, t, {}), "flats as stacks of shape (n, L, H, W)"),
        (lambda fl, dk, t: (fl, dk[:3], t, {}), "one flat and one dark stack per exposure"),
        (lambda fl, dk, t: (fl, dk, t[:3], {}), "one flat and one dark stack per exposure"),
        (lambda fl, dk, t: (fl, dk, -t, {}), "exposure_times"),
        (lambda fl, dk, t: (fl, dk, t, {"photons": [1.0, 2.0]}), "photons with one value"),
        (lambda fl, dk, t: (fl, dk, t, {"photons": -t}), "photons"),
        (lambda fl, dk, t: (fl, dk, t, {"fit_fraction": 1.5}), "fit_fraction"),
        (lambda fl, dk, t: (fl, dk, t, {"spatial_index": 9}), "spatial_index in [0, 3]"),
        (lambda fl, dk, t: (fl, dk, t, {"spatial_index": 1.5}), "spatial_index"),
        (lambda fl, dk, t: ("frames", dk, t, {}), "flats as a sequence"),
        (lambda fl, dk, t: ([np.full((2, 8, 8), np.nan)] * 4, dk, t, {}), "flats[0]"),
        (lambda fl, dk, t: ([fl[0].astype(bool)] * 4, dk, t, {}), "flats[0]"),
        (lambda fl, dk, t: (list(fl[:, :, :1, :1]), list(dk[:, :, :1, :1]), t, {}), "2 pixels"),
    ],
)
def test_invalid_input_is_refused_in_one_line(change, words) -> None:  # type: ignore[no-untyped-def]
    fl, dk, t, kw = change(*_frames())
    with pytest.raises(ImageformError) as exc:
        measure_emva(fl, dk, t, **kw)
    msg = str(exc.value)
    assert words in msg and "\n" not in msg and len(msg) < 240


def test_degenerate_series_are_refused() -> None:
    fl, dk, t = _frames()
    with pytest.raises(DegenerateConfigurationError, match="two different exposure_times"):
        measure_emva(fl, dk, np.zeros(4))
    with pytest.raises(DegenerateConfigurationError, match="between zero and"):
        measure_emva(fl, dk, t, fit_fraction=0.01)


def test_simulator_checks_its_inputs() -> None:
    s = cmos_preset()
    kw: dict[str, Any] = {
        "irradiance": 0.02,
        "wavelength_nm": 550.0,
        "exposure_times": [0.0, 0.01],
        "rng": 0,
    }
    with pytest.raises(TypeError, match="SensorModel"):
        simulate_emva_frames("cmos", **kw)  # type: ignore[arg-type]
    with pytest.raises(ImageformError, match="frames"):
        simulate_emva_frames(s, frames=1, **kw)
    with pytest.raises(ImageformError, match="channel"):
        simulate_emva_frames(s, channel=1, **kw)
    with pytest.raises(ImageformError, match="exposure_times"):
        simulate_emva_frames(s, **{**kw, "exposure_times": []})
    f = simulate_emva_frames(s, frames=3, shape=(4, 5), **kw)
    assert f.flats.shape == f.darks.shape == (2, 3, 4, 5)
    # the fixed pattern is the chip's: the same in every frame, as capture draws it
    again = simulate_emva_frames(s, frames=3, shape=(4, 5), **kw)
    np.testing.assert_array_equal(f.flats, again.flats)


# -- the reference implementation --------------------------------------------------------


@pytest.mark.parametrize("name", list(SENSORS))
def test_same_numbers_as_emva1288(measured, name: str) -> None:  # type: ignore[no-untyped-def]
    """emva1288 1.0.2 (the standard's reference code) on the same frames. Tolerances: K,
    σ_d, η, DSNU, PRNU, μ_e.sat, SNR_max and the dark current 1e-6 relative (the same
    formulas; emva1288 fits with scipy's leastsq); the dynamic range 0.5 dB (its threshold
    is the approximation σ_y.dark/K + ½ of the root used here). Its saturation index is
    given where its backward scan stops on the read-noise floor past a full-well clip."""
    pytest.importorskip("emva1288")
    _s, f, m = measured[name, 0]
    i_sat = int(np.argmax(m.var_dn))
    ref = emva1288_results(f, m.spatial_index, index_u_ysat=i_sat)
    assert ref["index_sat"] == i_sat
    ours = {
        "K": m.system_gain,
        "sigma_d": m.dark_noise,
        "eta": m.quantum_efficiency,
        "dsnu": m.dsnu,
        "prnu": m.prnu,
        "sat": m.saturation_capacity,
        "snr_max_db": m.snr_max_db,
        "dark_current": m.dark_current,
    }
    for k, v in ours.items():
        assert v == pytest.approx(ref[k], rel=1e-6), k
    assert m.dynamic_range_db == pytest.approx(ref["dr_db"], abs=0.5)
    # the measured SNR curve is emva1288's too: (μ_y - μ_y.dark) / σ_y
    ok = m.var_dn > 0  # all clipped: no temporal noise left, the SNR is NaN
    np.testing.assert_allclose(
        m.snr_measured[ok], (m.mean_dn - m.dark_mean_dn)[ok] / np.sqrt(m.var_dn[ok])
    )
    assert np.isnan(m.snr_measured[~ok]).all()


def test_emva1288_finds_the_same_saturation_when_the_adc_clips() -> None:
    pytest.importorskip("emva1288")
    f = record(SENSORS["cmos x2 gain (ADC-limited)"], 0, shape=(48, 48))
    m = measure_emva(f.flats, f.darks, f.exposure_times, photons=f.photons)
    ref = emva1288_results(f, m.spatial_index)
    assert ref["index_sat"] == int(np.argmax(m.var_dn))
    assert m.saturation_capacity == pytest.approx(ref["sat"], rel=1e-6)
