"""SensorModel: the capture chain's statistics, saturation, FPN, inputs, and bad input."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.sensor import (
    QUANTIZATION_NOISE_DN,
    SensorModel,
    ccd_preset,
    cmos_preset,
    photons_per_pixel,
    temporal_noise_dn,
)

QUIET = {"read_noise": 0.0, "dark_current": 0.0, "dsnu": 0.0, "prnu": 0.0, "column_fpn": 0.0}


def test_system_gain_derivation() -> None:
    s = SensorModel(conversion_gain=50e-6, analog_gain=2.0, adc_range=0.5, bit_depth=10)
    assert s.system_gain == pytest.approx(50e-6 * 2.0 * 1023 / 0.5)


def test_photons_per_pixel_value() -> None:
    # μ_p = E A t λ / (h c) (EMVA 1288 4.0 eq. 2): 1 µW/cm² = 1e-2 W/m², 5 µm pixels, 1 ms, 500 nm
    want = 1e-2 * 25e-12 * 1e-3 * 500e-9 / (6.62607015e-34 * 299792458.0)
    assert float(
        photons_per_pixel(1e-2, 500, pixel_area=25e-12, exposure_time=1e-3)
    ) == pytest.approx(want)


def test_mean_and_temporal_noise_follow_emva_model() -> None:
    s = SensorModel(dark_current=0.0, dsnu=0.0, prnu=0.0, read_noise=3.0, black_level=100.0)
    mu_e = 2000.0
    frames = [s.capture(np.full((64, 64, 1), mu_e), exposure_time=1e-3, rng=i) for i in (1, 2)]
    a, b = (f.astype(float) for f in frames)
    assert a.mean() == pytest.approx(s.system_gain * mu_e + 100, rel=2e-3)
    sigma = np.sqrt(0.5 * np.var(a - b))
    want = temporal_noise_dn(mu_e, system_gain=s.system_gain, dark_noise_e=3.0)
    assert sigma == pytest.approx(want, rel=0.03)


def test_poisson_shot_noise_only() -> None:
    s = SensorModel(**QUIET, black_level=0.0, conversion_gain=1 / 4095, adc_range=1.0)  # K = 1 DN/e
    y = s.capture(np.full((128, 128, 1), 400.0), exposure_time=0.0, rng=3).astype(float)
    assert s.system_gain == pytest.approx(1.0)
    assert y.mean() == pytest.approx(400, rel=5e-3)
    assert y.var() == pytest.approx(400 + QUANTIZATION_NOISE_DN**2, rel=0.05)


def test_saturation_at_full_well_and_adc() -> None:
    s = SensorModel(**QUIET, full_well=5000, black_level=0.0)
    y = s.capture(np.full((4, 4, 1), 1e6), exposure_time=1e-3, rng=0)
    assert np.all(y == np.floor(s.system_gain * 5000 + 0.5))  # the ADC rounds half up
    hot = dataclasses.replace(s, full_well=1e6)
    assert np.all(hot.capture(np.full((4, 4, 1), 1e6), exposure_time=1e-3, rng=0) == s.max_dn)


def test_fixed_pattern_is_fixed_and_temporal_noise_is_not() -> None:
    s = cmos_preset(read_noise=0.0, dark_current=0.0)
    a = s.capture(np.full((32, 32, 1), 0.0), exposure_time=1e-3, rng=1)
    b = s.capture(np.full((32, 32, 1), 0.0), exposure_time=1e-3, rng=2)
    np.testing.assert_array_equal(a, b)  # only FPN left: identical frames
    fp = s.fixed_pattern(32, 32)
    assert np.std(fp.column) == pytest.approx(s.column_fpn, rel=0.35)
    # column offsets are shared down a column: column means vary more than DSNU/sqrt(H) alone
    col_means = fp.offset[..., 0].mean(axis=0)
    np.testing.assert_allclose(col_means - fp.column, 0, atol=4 * s.dsnu / np.sqrt(32))
    assert np.all(ccd_preset().fixed_pattern(8, 8).column == 0)  # a CCD has no column ADCs


def test_prnu_scales_with_signal() -> None:
    s = SensorModel(read_noise=0, dark_current=0, dsnu=0, prnu=0.02, black_level=0, fpn_seed=5)
    mu = np.full((64, 64, 1), 3000.0)
    avg = np.mean([s.capture(mu, exposure_time=0, rng=i).astype(float) for i in range(16)], axis=0)
    spatial = avg.std() / avg.mean()
    assert spatial == pytest.approx(0.02, rel=0.15)


def test_dark_current_accumulates_with_exposure() -> None:
    s = SensorModel(read_noise=0.0, dsnu=0.0, prnu=0.0, dark_current=1000.0, black_level=10.0)
    y = s.capture(np.zeros((64, 64, 1)), exposure_time=2.0, rng=0).astype(float)
    assert (y.mean() - 10) / s.system_gain == pytest.approx(2000, rel=0.01)


def test_spectral_and_monochromatic_inputs_agree() -> None:
    s = cmos_preset(color=True, **QUIET)
    wl = np.asarray(s.qe_wavelengths)
    e_mono = s.mean_electrons(
        np.full((2, 2), 1e-3), exposure_time=1e-3, quantity="irradiance", wavelength_nm=550.0
    )
    qe = s.quantum_efficiency(550.0)
    mp = photons_per_pixel(1e-3, 550, pixel_area=s.pixel_area, exposure_time=1e-3)
    np.testing.assert_allclose(e_mono[0, 0], s.fill_factor * mp * qe)
    # a flat spectrum of 1e-5 W/m²/nm: electrons = FF Σ QE(λ) E λ Δλ A t / (h c)
    spec = np.full((2, 2, wl.size), 1e-5)
    e_spec = s.mean_electrons(spec, exposure_time=1e-3, quantity="irradiance")
    w = np.full(wl.size, 10.0)
    w[[0, -1]] = 5.0
    ph = 1e-5 * w * s.pixel_area * 1e-3 * wl * 1e-9 / (6.62607015e-34 * 299792458.0)
    want = s.fill_factor * np.asarray(s.qe_curves) @ ph
    np.testing.assert_allclose(e_spec[0, 0], want, rtol=1e-12)
    assert s.capture(spec, exposure_time=1e-3, quantity="irradiance", rng=0).shape == (2, 2, 3)
    assert e_spec[0, 0, 1] > e_spec[0, 0, 2]  # green channel collects most of a flat spectrum


def test_normalize() -> None:
    s = SensorModel(black_level=64.0, bit_depth=12)
    np.testing.assert_allclose(s.normalize([64, 4095, 0]), [0.0, 1.0, -64 / 4031])


@pytest.mark.parametrize(
    ("call", "exc", "match"),
    [
        (
            lambda s: s.capture(np.ones((2, 2, 1)), exposure_time=-1.0, rng=0),
            InvalidInputError,
            r"exposure_time \(s\) >= 0",
        ),
        (
            lambda s: s.capture(-np.ones((2, 2, 1)), exposure_time=1.0, rng=0),
            InvalidInputError,
            "non-negative",
        ),
        (
            lambda s: s.capture(np.full((2, 2, 1), np.nan), exposure_time=1.0, rng=0),
            InvalidInputError,
            "NaN",
        ),
        (
            lambda s: s.capture(np.ones((2, 2, 3)), exposure_time=1.0, rng=0),
            InvalidInputError,
            r"\(\.\.\., H, W, 1\)",
        ),
        (
            lambda s: s.capture(np.ones((2, 2, 1)), exposure_time=1.0, rng=0, quantity="lux"),
            UnknownOptionError,
            "valid: 'electrons', 'irradiance', 'photons'",
        ),
        (
            lambda s: s.capture(
                np.ones((2, 2)), exposure_time=1.0, rng=0, quantity="photons", wavelength_nm=-5
            ),
            InvalidInputError,
            "wavelength_nm",
        ),
    ],
)
def test_capture_bad_input(call, exc, match) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(exc, match=match):
        call(SensorModel())


@pytest.mark.parametrize(
    ("changes", "match"),
    [
        ({"fill_factor": 1.5}, "fill_factor"),
        ({"bit_depth": 20}, "bit_depth"),
        ({"full_well": -1.0}, "full_well"),
        ({"architecture": "foveon"}, "valid: 'ccd', 'cmos'"),
        ({"shutter": "leaf"}, "valid: 'global', 'rolling'"),
        ({"qe_curves": ((1.5,),)}, r"\[0, 1\]"),
        ({"black_level": 5000.0}, "black_level"),
    ],
)
def test_model_validation(changes: dict, match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        SensorModel(**changes)
