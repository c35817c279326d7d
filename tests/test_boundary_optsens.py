"""Hardened boundaries of imageform.optics and imageform.sensor (issue 16).

The sweep (:mod:`tests.boundary_sweep_optsens`) calls every public callable of the two
packages with malformed values per parameter and requires each call to end in a clean
one-line error naming the parameter or in a finite result; the tests below pin each case
the issue lists.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from imageform.errors import ImageformError, InvalidInputError
from imageform.optics import (
    apply_vignetting,
    axial_chromatic_blur_diameters,
    blur_by_radius,
    cos4_falloff,
    disc_kernel,
    field_angle,
    lateral_chromatic_aberration,
    mechanical_vignetting,
    pupil_overlap_fraction,
    spherical_aberration,
    thin_lens,
)
from imageform.sensor import (
    SensorModel,
    cfa_masks,
    comparison_table,
    demosaic,
    emva_snr,
    fit_photon_transfer,
    fixed_pattern,
    photons_per_pixel,
    rolling_shutter_points,
    row_start_times,
    shutter_capture,
    simulate_photon_transfer,
)
from imageform.sensor.presets import cmos_preset
from tests import boundary_sweep_optsens as sweep_mod


def _one_line(exc: pytest.ExceptionInfo[BaseException], *names: str) -> str:
    msg = str(exc.value)
    assert "\n" not in msg and len(msg) <= 200, msg
    for n in names:
        assert n in msg, msg
    return msg


def _run_sweep(fraction: float, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("IMAGEFORM_MAX_MEMORY", sweep_mod.MEMORY_LIMIT)
    res = sweep_mod.sweep(fraction=fraction)
    bad = [o for o in res if o.kind in sweep_mod.BAD]
    listing = "\n".join(f"[{o.kind}] {o.case}({o.param}={o.label}): {o.detail}" for o in bad)
    assert not bad, f"{len(bad)} of {len(res)} calls misbehave:\n{listing[:4000]}"
    assert {o.case for o in res} == {c.name for c in sweep_mod.cases() if c.kwargs}


def test_boundary_sweep(monkeypatch: pytest.MonkeyPatch) -> None:
    """All of the sweep (about 4,500 calls, a few seconds once imports are warm): 0 bad
    calls. ``python -m tests.boundary_sweep_optsens -v`` lists them when this fails."""
    _run_sweep(1.0, monkeypatch)


# ---- complex, object and string input is refused, never cut to its real part -------------
COMPLEX_CALLS = {
    "SensorModel": lambda v: SensorModel(pixel_pitch=v),
    "SensorModel.qe_curves": lambda v: SensorModel(qe_curves=((v,),)),
    "photons_per_pixel": lambda v: photons_per_pixel(
        np.array([v]), 550.0, pixel_area=1e-11, exposure_time=1e-3
    ),
    "rolling_shutter_points": lambda v: rolling_shutter_points(
        np.array([[v, 1.0]]), [1.0, 0.0], line_time=1e-5
    ),
    "rolling_shutter_points.velocity": lambda v: rolling_shutter_points(
        [[1.0, 1.0]], np.array([v, 0.0]), line_time=1e-5
    ),
    "cos4_falloff.center": lambda v: cos4_falloff((4, 4), focal_length_px=2.0, center=(v, 1.0)),
    "pupil_overlap_fraction": lambda v: pupil_overlap_fraction(1.0, 1.0, np.array([v])),
    "apply_vignetting": lambda v: apply_vignetting(np.ones((2, 2)), np.full((2, 2), v)),
    "lateral_chromatic_aberration": lambda v: lateral_chromatic_aberration(
        np.ones((4, 4, 2)), (v, 1.0)
    ),
    "axial_chromatic_blur_diameters": lambda v: axial_chromatic_blur_diameters(
        np.array([v]), focal_lengths=(0.05, 0.05), f_number=2, focus=2
    ),
    "mechanical_vignetting": lambda v: mechanical_vignetting(
        (3, 3), focal_length_px=1.0, pupil_radius=v, barrel_radius=1, barrel_distance=1
    ),
}


@pytest.mark.parametrize("name", sorted(COMPLEX_CALLS))
@pytest.mark.parametrize("value", [1 + 1j, np.complex128(1 + 0j), "1.0", object()])
def test_complex_object_string_refused(name: str, value: object) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no ComplexWarning on the way
        with pytest.raises(InvalidInputError) as exc:
            COMPLEX_CALLS[name](value)
    _one_line(exc)


def test_object_arrays_refused() -> None:
    obj = np.array([1.0, object()], dtype=object)
    with pytest.raises(InvalidInputError, match="offset"):
        pupil_overlap_fraction(1.0, 1.0, obj)
    with pytest.raises(InvalidInputError, match="irradiance"):
        photons_per_pixel(obj, 550.0, pixel_area=1e-11, exposure_time=1e-3)


# ---- None never becomes NaN -------------------------------------------------------------
def test_none_is_refused() -> None:
    with pytest.raises(InvalidInputError, match="offset"):
        pupil_overlap_fraction(1.0, 1.0, None)
    with pytest.raises(InvalidInputError, match="irradiance"):
        photons_per_pixel(None, 550.0, pixel_area=1e-11, exposure_time=1e-3)
    with pytest.raises(InvalidInputError, match="points_uv"):
        rolling_shutter_points(None, [1.0, 0.0], line_time=1e-5)
    with pytest.raises(InvalidInputError, match="velocity_uv"):
        rolling_shutter_points([[1.0, 2.0]], None, line_time=1e-5)
    with pytest.raises(InvalidInputError, match="dn"):
        SensorModel().normalize(None)
    with pytest.warns(DeprecationWarning), pytest.raises(InvalidInputError, match="dn"):
        SensorModel().normalise(None)


# ---- empty input is an error ------------------------------------------------------------
@pytest.mark.parametrize("shape", [(0, 0), (0, 8), (8,), (8, 8, 8), (8.0, 8)])
def test_simulate_photon_transfer_shape(shape: tuple) -> None:
    with pytest.raises(InvalidInputError) as exc:
        simulate_photon_transfer(
            cmos_preset(),
            irradiance=0.05,
            wavelength_nm=550,
            exposure_times=[1e-3],
            rng=0,
            shape=shape,
        )
    _one_line(exc, "shape")


def test_empty_images_refused() -> None:
    with pytest.raises(InvalidInputError, match="non-empty"):
        blur_by_radius(np.zeros((0, 0)), 1.0)
    with pytest.raises(InvalidInputError, match="signal"):
        SensorModel().capture(np.zeros((0, 0, 1)), exposure_time=1e-3, rng=0)


# ---- tuple arguments of the wrong length: a clear error, not IndexError ----------------
@pytest.mark.parametrize(
    "call",
    [
        lambda: cos4_falloff((5,), focal_length_px=1.0),
        lambda: field_angle((5,), focal_length_px=1.0),
        lambda: field_angle((4, 4), focal_length_px=1.0, center=(1.0,)),
        lambda: mechanical_vignetting(
            (5,), focal_length_px=1.0, pupil_radius=1, barrel_radius=1, barrel_distance=1
        ),
        lambda: spherical_aberration(
            np.ones((4, 4)),
            focal_length=0.05,
            f_number=2,
            pixel_pitch=1e-4,
            sa_coefficient=0.5,
            center=(),
        ),
        lambda: fixed_pattern((4, 5), prnu=0, dsnu=0, column_fpn=0, rng=0),
        lambda: cfa_masks((4,)),
    ],
)
def test_wrong_length_tuples(call) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(InvalidInputError) as exc:
        call()
    msg = _one_line(exc)
    assert "expected" in msg


# ---- wrong object types: TypeError naming the parameter, not AttributeError ------------
def test_wrong_object_types() -> None:
    with pytest.raises(TypeError) as exc:
        fit_photon_transfer(None)  # type: ignore[arg-type]
    _one_line(exc, "data", "PhotonTransferData")
    with pytest.raises(TypeError) as exc:
        simulate_photon_transfer(
            None,  # type: ignore[arg-type]
            irradiance=0.05,
            wavelength_nm=550,
            exposure_times=[1e-3],
            rng=0,
        )
    _one_line(exc, "sensor", "SensorModel")
    with pytest.raises(TypeError) as exc:
        shutter_capture(None, exposure_time=1e-3, mode="global", line_time=0.0)  # type: ignore[arg-type]
    _one_line(exc, "render")


def test_fit_photon_transfer_checks_its_arrays() -> None:
    d = simulate_photon_transfer(
        cmos_preset(prnu=0.0),
        irradiance=0.05,
        wavelength_nm=550,
        exposure_times=np.linspace(0, 4e-3, 6),
        rng=1,
        shape=(8, 8),
    )
    import dataclasses

    bad = dataclasses.replace(d, var_dn=d.var_dn[:3])
    with pytest.raises(InvalidInputError, match="one length"):
        fit_photon_transfer(bad)
    nan = dataclasses.replace(d, mean_dn=np.full(6, np.nan))
    with pytest.raises(InvalidInputError, match=r"data\.mean_dn"):
        fit_photon_transfer(nan)


# ---- int() of inf or 1e308: InvalidInputError, not OverflowError -----------------------
@pytest.mark.parametrize("value", [math.inf, 1e308, math.nan, 1000.0])
def test_counts_and_seeds_are_integers(value: float) -> None:
    with pytest.raises(InvalidInputError, match="rows"):
        comparison_table(value)  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="rows"):
        SensorModel().frame_readout_time(value)  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="rng"):
        fixed_pattern((2, 2, 1), prnu=0, dsnu=0, column_fpn=0, rng=value)  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="fpn_seed"):
        SensorModel(fpn_seed=value)  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="rows"):
        row_start_times(value, mode="rolling", line_time=1e-3)  # type: ignore[arg-type]


def test_deprecated_seed_spelling_also_checked() -> None:
    with pytest.warns(DeprecationWarning), pytest.raises(InvalidInputError, match="rng"):
        fixed_pattern((2, 2, 1), prnu=0, dsnu=0, column_fpn=0, seed=math.inf)  # type: ignore[call-arg]


# ---- tiny positive values: computed stably or refused, never ZeroDivisionError ----------
def test_tiny_values() -> None:
    with pytest.raises(InvalidInputError) as exc:
        pupil_overlap_fraction(1e-300, 1.0, 0.5)
    _one_line(exc, "pupil_radius")
    # K -> 0: the quantisation noise σ_q / K grows without bound, the SNR goes to 0
    assert emva_snr(1000, quantum_efficiency=0.5, dark_noise_e=5, system_gain=1e-300) == 0.0
    assert emva_snr(1000, quantum_efficiency=0.5, dark_noise_e=5, system_gain=1e-100) > 0.0
    with pytest.raises(InvalidInputError, match="quantum_efficiency"):
        emva_snr(1000, quantum_efficiency=1e308, dark_noise_e=5, system_gain=1.0)


def test_overflow_is_refused_not_nan() -> None:
    with pytest.raises(InvalidInputError) as exc:
        photons_per_pixel(1e308, 550.0, pixel_area=1.0, exposure_time=1e10)
    _one_line(exc, "irradiance", "exposure_time")
    with pytest.raises(InvalidInputError) as exc:
        thin_lens(focal_length=1e-300, d_i=1e308)
    _one_line(exc)


# ---- NumPy integers are integers ---------------------------------------------------------
def test_numpy_integers_accepted() -> None:
    s = SensorModel(bit_depth=np.int64(10), fpn_seed=np.int32(3))
    assert s.bit_depth == 10 and type(s.bit_depth) is int and s.max_dn == 1023
    assert type(s.fpn_seed) is int
    assert cmos_preset(bit_depth=np.int16(12)).max_dn == 4095
    assert s.frame_readout_time(np.int64(10)) == pytest.approx(10 * s.line_time)
    assert s.fixed_pattern(np.int64(2), np.uint8(3)).gain.shape == (2, 3, 1)
    assert len(comparison_table(np.int64(500))) > 0
    assert row_start_times(np.int64(3), mode="rolling", line_time=1.0).tolist() == [0, 1, 2]
    img = shutter_capture(
        lambda t: np.ones((2, 3)),
        exposure_time=1e-3,
        mode="rolling",
        line_time=1e-4,
        samples=np.int64(2),
    )
    assert img.shape == (2, 3)
    assert cfa_masks((np.int64(4), np.int32(6))).shape == (4, 6, 3)
    out = blur_by_radius(np.ones((6, 6)), 1.0, max_layers=np.int64(3))
    np.testing.assert_allclose(out, 1.0)
    b = axial_chromatic_blur_diameters(
        3.0, focal_lengths=(0.0504, 0.05, 0.0496), f_number=2, focus=2, reference=np.int64(1)
    )
    assert b.shape == (3,) and b[1] > 0


# ---- what reaches a numba kernel is an array of the right kind ----------------------------
def test_kernels_get_no_odd_values() -> None:
    torch = pytest.importorskip("torch")
    with pytest.raises(ImageformError) as exc:
        demosaic(torch.tensor(2.0))
    _one_line(exc, "raw")
    with pytest.raises(ImageformError) as exc:
        demosaic(np.array([[2**70, 1], [1, 1]], dtype=object))
    _one_line(exc, "raw")
    with pytest.raises(InvalidInputError, match="clip"):
        demosaic(np.zeros((4, 4)), clip=np.array([1, 0]))  # type: ignore[arg-type]


# ---- sizes are bounded before anything is allocated --------------------------------------
@pytest.mark.parametrize(
    "call",
    [
        lambda: disc_kernel(1e10),
        lambda: blur_by_radius(np.ones((4, 4)), 1e9),
        lambda: field_angle((10**6, 10**6), focal_length_px=1.0),
        lambda: cos4_falloff((10**12, 4), focal_length_px=1.0),
        lambda: cfa_masks((10**6, 10**6)),
        lambda: fixed_pattern((10**5, 10**5, 3), prnu=0, dsnu=0, column_fpn=0, rng=0),
        lambda: row_start_times(10**12, mode="rolling", line_time=1e-5),
        lambda: simulate_photon_transfer(
            cmos_preset(),
            irradiance=0.05,
            wavelength_nm=550,
            exposure_times=[1e-3],
            rng=0,
            shape=(10**5, 10**5),
        ),
        lambda: SensorModel().fixed_pattern(10**6, 10**6),
        # inputs that exist but whose results would not fit (a 1 MiB limit below)
        lambda: demosaic(np.zeros((512, 512), np.float32)),
        lambda: SensorModel().capture(np.ones((512, 512, 1)), exposure_time=1e-3, rng=0),
    ],
)
def test_sizes_bounded(call, monkeypatch: pytest.MonkeyPatch) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.setenv("IMAGEFORM_MAX_MEMORY", "1M")
    with pytest.raises(InvalidInputError) as exc:
        call()
    assert "GiB" in _one_line(exc)


def test_disc_kernel_bound_is_the_memory_estimate(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("IMAGEFORM_MAX_MEMORY", "16G")
    with pytest.raises(InvalidInputError, match=r"radius: a blur radius of 1e\+10 px"):
        disc_kernel(1e10)
    assert disc_kernel(40.0).shape == (81, 81)  # 1.9 MB of booleans and floats: allowed


def test_counts_bounded() -> None:
    with pytest.raises(InvalidInputError, match="samples"):
        shutter_capture(
            lambda t: np.ones((2, 2)), exposure_time=1, mode="rolling", line_time=0, samples=10**9
        )
    with pytest.raises(InvalidInputError, match="max_layers"):
        blur_by_radius(np.ones((4, 4)), 1.0, max_layers=10**9)


# ---- a misshaped array is refused before its values are read -----------------------------
def test_shape_before_values() -> None:
    nan = np.full((3, 3), np.nan)
    with pytest.raises(InvalidInputError, match=r"falloff \(3, 3\)"):
        apply_vignetting(np.ones((2, 2)), nan)
    with pytest.raises(InvalidInputError, match="expected radius_px scalar"):
        blur_by_radius(np.ones((2, 2)), nan)
    with pytest.raises(InvalidInputError, match=r"points_uv of shape \(\.\.\., 2\)"):
        rolling_shutter_points(nan, [0.0, 0.0], line_time=1e-5)
    with pytest.raises(InvalidInputError, match="signal"):
        SensorModel().mean_electrons(np.full((2, 2, 3), np.nan), exposure_time=1.0)


# ---- messages -----------------------------------------------------------------------------
def test_messages_one_line() -> None:
    with pytest.raises(InvalidInputError) as exc:
        thin_lens(focal_length=1e300, d_o=2.0)
    _one_line(exc, "focal_length", "virtual")
    with pytest.raises(InvalidInputError) as exc:
        demosaic(np.zeros((2, 3, 4, 5)))
    _one_line(exc, "raw")
    with pytest.raises(InvalidInputError) as exc:
        SensorModel(bit_depth=np.zeros((3, 3)))  # type: ignore[arg-type]
    _one_line(exc, "bit_depth")


def test_sensor_model_domain() -> None:
    """A sensor whose black level is its white has no range (normalize divided by 0)."""
    with pytest.raises(InvalidInputError, match="black_level"):
        SensorModel(bit_depth=6, black_level=63.0)
    with pytest.raises(InvalidInputError, match="name"):
        SensorModel(name=math.nan)  # type: ignore[arg-type]
    # a large PRNU draws some pixel gains below zero: those collect nothing (no crash)
    s = SensorModel(prnu=0.9, read_noise=0, dark_current=0, dsnu=0, black_level=0)
    dn = s.capture(np.full((16, 16, 1), 100.0), exposure_time=1e-3, rng=0)
    assert dn.shape == (16, 16, 1) and dn.min() == 0
