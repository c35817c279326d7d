"""Regression tests of issue 16 ("hardened boundaries") for imageform.spectral."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.spectral import (
    Spectrum,
    blackbody_spectrum,
    integration_weights,
    load_table,
    planck,
    planckian_cct,
    spectrum_to_xyz,
)


@pytest.fixture(autouse=True)
def _no_warnings():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        yield


def _one_line(exc: pytest.ExceptionInfo[BaseException], *names: str) -> None:
    msg = str(exc.value)
    assert "\n" not in msg and len(msg) <= 200, msg
    for n in names:
        assert n in msg, (n, msg)


S = Spectrum(np.linspace(400, 700, 7), np.linspace(0.2, 0.8, 7))


def test_spectrum_refuses_complex_object_string_and_bool() -> None:
    w = np.linspace(400, 700, 7)
    with pytest.raises(InvalidInputError, match="complex"):
        Spectrum(w, np.ones(7) + 1j)
    with pytest.raises(InvalidInputError, match="wavelengths"):
        Spectrum(w.astype(object), np.ones(7))
    with pytest.raises(InvalidInputError, match="values"):
        Spectrum(w, np.array(["1"] * 7))
    with pytest.raises(TypeError, match="bool"):
        Spectrum(w, np.ones(7) > 0)
    with pytest.raises(InvalidInputError, match="complex"):
        S.interpolate(np.array([450.0]) + 0j)
    with pytest.raises(TypeError, match="name"):
        Spectrum(w, np.ones(7), name=5)  # type: ignore[arg-type]


def test_resample_with_infinite_or_huge_bounds_is_a_clear_error() -> None:
    with pytest.raises(InvalidInputError) as exc:
        S.resample(-np.inf, 700, 10)
    _one_line(exc, "start")
    with pytest.raises(InvalidInputError) as exc:
        S.resample(400, 1e300, 10)
    _one_line(exc, "GiB")
    with pytest.raises(InvalidInputError) as exc:
        S.resample(400, 700, 1e-300)
    _one_line(exc, "step")
    assert S.resample(np.int64(400), np.float32(700), np.int32(50)).shape == (7,)


def test_method_arguments_are_checked() -> None:
    with pytest.raises(TypeError, match="other"):
        S.allclose(None)  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="atol"):
        S.allclose(S, atol=np.nan)
    with pytest.raises(InvalidInputError, match="at within"):
        S.normalize(900.0)
    with pytest.raises(InvalidInputError, match="start"):
        S.trim(np.array([400.0, 500.0]), 700)  # type: ignore[arg-type]
    assert S.trim(-np.inf, np.inf).shape == S.shape


def test_blackbody_messages_name_normalize_at_not_wavelengths() -> None:
    with pytest.raises(InvalidInputError) as exc:
        blackbody_spectrum(5000, normalize_at=-1.0)
    _one_line(exc, "normalize_at")
    with pytest.raises(InvalidInputError) as exc:
        blackbody_spectrum(5000, normalize_at=None)  # type: ignore[arg-type]
    _one_line(exc, "normalize_at")


def test_planck_is_finite_in_its_domain_and_refuses_outside() -> None:
    assert np.isfinite(planck([1e-3, 1e12], 1e12)).all()
    assert np.isfinite(planck([1e-3, 1e12], 1e-300)).all()
    with pytest.raises(InvalidInputError, match="temperature"):
        planck(500.0, 1e300)
    with pytest.raises(InvalidInputError, match="wavelength_nm"):
        planck(np.array([500.0]) + 0j, 5000.0)
    # the domain does not change valid results
    assert round(float(planck(500.0, 5000.0) / planck(560.0, 5000.0)), 4) == 0.9487


def test_planckian_cct_refuses_strings_and_complex() -> None:
    for bad in ("abc", np.array([0.95, 1.0, 1.09]) + 0j, [True, True, True]):
        with pytest.raises((InvalidInputError, TypeError)) as exc:
            planckian_cct(bad)
        _one_line(exc, "xyz")


def test_integration_arguments_of_the_wrong_type() -> None:
    from imageform.spectral import cmfs

    with pytest.raises(InvalidInputError, match="functions"):
        integration_weights(None, illuminant=None)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="illuminant"):
        integration_weights(cmfs(2), illuminant=1.5)  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="absolute"):
        spectrum_to_xyz(S, illuminant=None, absolute=np.array([True, False]))  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="observer"):
        spectrum_to_xyz(S, observer=np.array([2, 10]))  # type: ignore[arg-type]


def test_unknown_table_is_one_short_line_naming_key() -> None:
    with pytest.raises(UnknownOptionError) as exc:
        load_table("nope")
    _one_line(exc, "key", "more")


def test_allocations_are_bounded_before_they_are_made(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("IMAGEFORM_MAX_MEMORY", "64M")
    wide = Spectrum([0.0, 1e12], np.ones((2, 3)))
    with pytest.raises(InvalidInputError, match="integration grid") as exc:
        integration_weights(wide, illuminant=None)
    _one_line(exc, "functions")
    dense = Spectrum(np.linspace(400, 700, 5000), np.ones(5000))
    with pytest.raises(InvalidInputError, match="Sprague") as exc:
        dense.interpolate(np.linspace(400, 700, 5000), method="sprague")
    _one_line(exc, "wavelengths")
    with pytest.raises(InvalidInputError, match="GiB"):
        S.resample(400, 700, 1e-6)


def test_arithmetic_never_makes_inf_or_nan() -> None:
    with pytest.raises(InvalidInputError, match="overflow"):
        S * 1e308 * 10
    with pytest.raises(InvalidInputError, match="finite"):
        S * np.nan
    with pytest.raises(InvalidInputError, match="division by zero"):
        S / 0.0
