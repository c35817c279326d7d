"""EMVA 1288 photon transfer: gain and read noise recovered within 5 % of the model's values."""

from __future__ import annotations

import numpy as np
import pytest

from imageform.errors import DegenerateConfigurationError
from imageform.sensor import (
    SensorModel,
    ccd_preset,
    cmos_preset,
    emva_snr,
    fit_photon_transfer,
    photons_per_pixel,
    simulate_photon_transfer,
)


def _run(s: SensorModel, seed: int, n: int = 30) -> tuple:
    eta = float(s.quantum_efficiency(550.0)[0]) * s.fill_factor
    per_s = float(photons_per_pixel(1.0, 550, pixel_area=s.pixel_area, exposure_time=1.0)) * eta
    tmax = 0.01
    irradiance = s.full_well / (0.8 * tmax * per_s)  # saturates at 80 % of the sweep
    d = simulate_photon_transfer(
        s,
        irradiance=irradiance,
        wavelength_nm=550.0,
        exposure_times=np.linspace(0, tmax, n),
        rng=seed,
        shape=(64, 64),
    )
    return d, fit_photon_transfer(d), eta


@pytest.mark.parametrize("preset", [cmos_preset, ccd_preset], ids=["cmos", "ccd"])
def test_photon_transfer_recovers_gain_and_read_noise(preset) -> None:  # type: ignore[no-untyped-def]
    s = preset()
    _, r, eta = _run(s, seed=11)
    assert r.system_gain == pytest.approx(s.system_gain, rel=0.05)
    assert r.read_noise == pytest.approx(s.read_noise, rel=0.05)
    assert r.quantum_efficiency == pytest.approx(eta, rel=0.05)
    assert r.saturation_capacity <= s.full_well
    assert r.fit_points >= 5


def test_gain_recovery_across_analog_gain() -> None:
    for g in (1.0, 2.0, 4.0):
        s = cmos_preset(analog_gain=g, full_well=3000.0)
        _, r, _ = _run(s, seed=int(g), n=20)
        assert r.system_gain == pytest.approx(s.system_gain, rel=0.05)


def test_ptc_shape_linear_then_drops_at_saturation() -> None:
    d, r, _ = _run(cmos_preset(), seed=3)
    i = int(np.argmax(d.var_dn))
    assert 0 < i < len(d.var_dn) - 1 and d.var_dn[-1] < 0.5 * d.var_dn[i]
    assert r.saturation_dn == pytest.approx(d.mean_dn[i])


def test_snr_formula_matches_simulation() -> None:
    s = cmos_preset(prnu=0.0)
    d, _, eta = _run(s, seed=5)
    k = 10
    snr_meas = (d.mean_dn[k] - d.dark_mean_dn[k]) / np.sqrt(d.var_dn[k])
    snr_model = emva_snr(
        d.photons[k], quantum_efficiency=eta, dark_noise_e=s.read_noise, system_gain=s.system_gain
    )
    assert snr_meas == pytest.approx(snr_model, rel=0.05)


def test_fit_needs_two_exposures() -> None:
    s = cmos_preset()
    d = simulate_photon_transfer(
        s, irradiance=1.0, wavelength_nm=550.0, exposure_times=[1e-3], rng=0, shape=(8, 8)
    )
    with pytest.raises(DegenerateConfigurationError, match="two different exposure times"):
        fit_photon_transfer(d)


def test_photon_count_overflow_names_wavelength_nm() -> None:
    """Issue 16: a wavelength of 1e308 nm overflowed the photon count, and the refusal named
    only irradiance and exposure_times."""
    import pytest

    from imageform.errors import InvalidInputError
    from imageform.sensor import SensorModel, simulate_photon_transfer

    s = SensorModel(qe_wavelengths=(400.0, 1e308), qe_curves=((0.5, 0.5),))
    with pytest.raises(InvalidInputError, match="wavelength_nm") as exc:
        simulate_photon_transfer(
            s, irradiance=1.0, wavelength_nm=1e308, exposure_times=[4e-3], rng=0, shape=(4, 4)
        )
    assert len(str(exc.value)) <= 200
