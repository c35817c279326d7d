"""Boundary sweep of ``imageform.optics`` and ``imageform.sensor`` (issue 16).

Every public callable of the two packages (each name in their ``__all__`` that can be
called, and the public methods of :class:`~imageform.sensor.SensorModel`) is first called
with a valid baseline; then each parameter in turn gets each malformed value (empty, wrong
shape, NaN, inf, None, complex, object, string, bool, huge, negative, zero, tiny, integers
beyond int64, NumPy scalars, a 0-d torch tensor ...). Each call runs in-process under a
time guard with ``IMAGEFORM_MAX_MEMORY`` set low (:data:`MEMORY_LIMIT`), and its outcome
is classified:

- ``clean``: an ``ImageformError`` or ``TypeError`` in one line of at most 200 characters
  that names the parameter;
- ``ok``: a result whose numbers are all finite;
- ``raw``: any other exception (IndexError, ZeroDivisionError, numba's TypingError, ...);
- ``message``: the right exception type but a message over several lines or too long;
- ``unnamed``: the right exception type but the message does not name the parameter;
- ``nan``: a result holding NaN or inf;
- ``warning``: a warning was issued (RuntimeWarning, ComplexWarning ...);
- ``refused``: a NumPy scalar equal to a valid value was refused (NumPy integers are ints);
- ``timeout``: the call ran longer than the guard.

Run ``PYTHONPATH=src python -m tests.boundary_sweep_optsens`` (``-v`` lists every bad
call); ``tests/test_boundary_optsens.py`` runs it in the suite and requires zero bad calls.
"""

from __future__ import annotations

import dataclasses
import math
import os
import signal
import sys
import time
import warnings
import zlib
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from imageform import optics, sensor
from imageform.errors import ImageformError

#: The memory limit the sweep runs under (``IMAGEFORM_MAX_MEMORY``): a refused size then
#: costs nothing, and a missing bound shows as a MemoryError or a timeout.
MEMORY_LIMIT = "512M"

GOOD = ("clean", "ok")
BAD = ("raw", "message", "unnamed", "nan", "warning", "refused", "timeout")

torch: Any
try:  # a 0-d tensor is one of the malformed values when PyTorch is there
    import torch
except ImportError:  # pragma: no cover - torch is installed in the dev environment
    torch = None


class _Timeout(BaseException):
    pass


def _alarm(signum: int, frame: Any) -> None:
    raise _Timeout


@dataclass
class Case:
    """One callable: ``fn(**kwargs)`` is a valid call; every key is swept."""

    name: str
    fn: Callable[..., Any]
    kwargs: dict[str, Any]
    #: words that also count as naming a parameter (its unit, a field path ...)
    aliases: dict[str, tuple[str, ...]] = field(default_factory=dict)
    skip: tuple[str, ...] = ()
    #: ``"param=label"`` calls documented to give NaN (a NaN fill value marks pixels)
    nan_ok: tuple[str, ...] = ()


def _img(h: int = 8, w: int = 8, c: int | None = 3) -> np.ndarray:
    rng = np.random.default_rng(0)
    return rng.random((h, w) if c is None else (h, w, c))


def _render(t: float) -> np.ndarray:
    return np.full((4, 5), 0.5 + t)


def cases() -> list[Case]:
    """The callables and their valid baselines."""
    fl = (0.0504, 0.05, 0.0496)
    s = sensor.cmos_preset()
    mono = sensor.SensorModel()
    ptc = sensor.simulate_photon_transfer(
        sensor.cmos_preset(prnu=0.0),
        irradiance=0.05,
        wavelength_nm=550,
        exposure_times=np.linspace(0, 4e-3, 6),
        rng=1,
        shape=(8, 8),
    )
    sm_fields = {f.name: getattr(mono, f.name) for f in dataclasses.fields(sensor.SensorModel)}
    out = [
        # ---- optics ----------------------------------------------------------------------
        Case(
            "aperture_diameter", optics.aperture_diameter, {"focal_length": 0.05, "f_number": 2.0}
        ),
        Case("f_number", optics.f_number, {"focal_length": 0.05, "aperture_diameter": 0.02}),
        Case(
            "magnification",
            optics.magnification,
            {"focal_length": 0.05, "d_o": 2.0, "allow_virtual": False},
        ),
        Case(
            "thin_lens",
            optics.thin_lens,
            {"focal_length": 0.05, "d_o": 2.0, "allow_virtual": False},
        ),
        Case("thin_lens(d_i)", optics.thin_lens, {"focal_length": 0.05, "d_i": 0.06}),
        Case(
            "hyperfocal_distance",
            optics.hyperfocal_distance,
            {"focal_length": 0.05, "f_number": 8.0, "coc": 3e-5},
        ),
        Case(
            "depth_of_field",
            optics.depth_of_field,
            {"focal_length": 0.05, "f_number": 2.8, "focus": 2.0, "coc": 3e-5},
        ),
        Case(
            "circle_of_confusion",
            optics.circle_of_confusion,
            {"depth": np.array([1.0, 4.0]), "focal_length": 0.05, "f_number": 2.0, "focus": 2.0},
        ),
        Case("disc_kernel", optics.disc_kernel, {"radius": 3.0}),
        Case(
            "blur_by_radius",
            optics.blur_by_radius,
            {"image": _img(), "radius_px": 1.5, "step": 0.5, "max_layers": 4},
        ),
        Case(
            "defocus_radius_px",
            optics.defocus_radius_px,
            {
                "depth": 4.0,
                "focal_length": 0.05,
                "f_number": 2.0,
                "focus": 2.0,
                "pixel_pitch": 5e-4,
            },
        ),
        Case(
            "defocus_blur",
            optics.defocus_blur,
            {
                "image": _img(),
                "depth": 4.0,
                "focal_length": 0.05,
                "f_number": 2.0,
                "focus": 2.0,
                "pixel_pitch": 5e-4,
                "step": 0.5,
            },
        ),
        Case(
            "spherical_blur_radius",
            optics.spherical_blur_radius,
            {"focal_length": 0.05, "f_number": 2.0, "sa_coefficient": 0.5},
        ),
        Case(
            "spherical_aberration",
            optics.spherical_aberration,
            {
                "image": _img(),
                "focal_length": 0.05,
                "f_number": 2.0,
                "pixel_pitch": 1e-3,
                "sa_coefficient": 0.5,
                "field_coefficient": 0.5,
                "center": (3.0, 4.0),
            },
        ),
        Case(
            "lateral_chromatic_aberration",
            optics.lateral_chromatic_aberration,
            {
                "image": _img(),
                "magnification": (1.01, 1.0, 0.99),
                "center": (3.0, 4.0),
                "fill": 0.0,
            },
            nan_ok=("fill=nan",),
        ),
        Case(
            "chromatic_focal_lengths",
            optics.chromatic_focal_lengths,
            {"focal_length": 0.05, "abbe_number": 64.17},
        ),
        Case(
            "axial_chromatic_blur_diameters",
            optics.axial_chromatic_blur_diameters,
            {
                "depth": np.array([1.0, 3.0]),
                "focal_lengths": fl,
                "f_number": 2.0,
                "focus": 2.0,
                "reference": 1,
            },
        ),
        Case(
            "axial_chromatic_aberration",
            optics.axial_chromatic_aberration,
            {
                "image": _img(),
                "depth": 3.0,
                "focal_lengths": fl,
                "f_number": 2.0,
                "focus": 2.0,
                "pixel_pitch": 1e-4,
                "reference": 1,
            },
        ),
        Case(
            "field_angle",
            optics.field_angle,
            {"shape": (4, 6), "focal_length_px": 5.0, "center": (2.0, 1.5)},
        ),
        Case(
            "cos4_falloff",
            optics.cos4_falloff,
            {"shape": (4, 6), "focal_length_px": 5.0, "center": (2.0, 1.5)},
        ),
        Case(
            "pupil_overlap_fraction",
            optics.pupil_overlap_fraction,
            {"pupil_radius": 1.0, "stop_radius": 1.0, "offset": np.array([0.0, 0.5, 1.0, 3.0])},
        ),
        Case(
            "mechanical_vignetting",
            optics.mechanical_vignetting,
            {
                "shape": (4, 6),
                "focal_length_px": 5.0,
                "pupil_radius": 1.0,
                "barrel_radius": 1.2,
                "barrel_distance": 2.0,
                "center": (2.0, 1.5),
            },
        ),
        Case(
            "apply_vignetting",
            optics.apply_vignetting,
            {"image": _img(), "falloff": np.full((8, 8), 0.5)},
        ),
        # ---- sensor ----------------------------------------------------------------------
        Case("cfa_pattern", sensor.cfa_pattern, {"pattern": "RGGB"}),
        Case("cfa_masks", sensor.cfa_masks, {"shape": (4, 6), "pattern": "RGGB"}),
        Case("mosaic", sensor.mosaic, {"rgb": _img(), "pattern": "RGGB"}),
        Case(
            "demosaic",
            sensor.demosaic,
            {
                "raw": _img(c=None),
                "pattern": "RGGB",
                "method": "bilinear",
                "clip": False,
                "allow_odd": False,
            },
        ),
        Case("demosaic(menon)", sensor.demosaic, {"raw": _img(c=None), "method": "menon"}),
        Case(
            "photons_per_pixel",
            sensor.photons_per_pixel,
            {
                "irradiance": np.array([1e-3, 2e-3]),
                "wavelength_nm": 550.0,
                "pixel_area": 25e-12,
                "exposure_time": 1e-3,
            },
        ),
        Case(
            "emva_snr",
            sensor.emva_snr,
            {"photons": 1000.0, "quantum_efficiency": 0.5, "dark_noise_e": 5.0, "system_gain": 1.0},
        ),
        Case(
            "temporal_noise_dn",
            sensor.temporal_noise_dn,
            {"mean_electrons": 100.0, "system_gain": 0.5, "dark_noise_e": 2.0},
        ),
        Case(
            "fixed_pattern",
            sensor.fixed_pattern,
            {"shape": (4, 5, 1), "prnu": 0.01, "dsnu": 1.0, "column_fpn": 0.5, "rng": 3},
        ),
        Case("ccd_preset", sensor.ccd_preset, {"color": True, "read_noise": 3.0}),
        Case("cmos_preset", sensor.cmos_preset, {"color": False, "bit_depth": 10}),
        Case("comparison_table", sensor.comparison_table, {"rows": 1000}),
        Case(
            "rolling_shutter_skew",
            sensor.rolling_shutter_skew,
            {"velocity": 1000.0, "line_time": 2e-5},
        ),
        Case(
            "row_start_times",
            sensor.row_start_times,
            {"rows": 3, "mode": "rolling", "line_time": 1e-3},
        ),
        Case(
            "rolling_shutter_points",
            sensor.rolling_shutter_points,
            {
                "points_uv": np.array([[10.0, 100.0]]),
                "velocity_uv": np.array([1000.0, 0.0]),
                "line_time": 1e-5,
                "t0": 0.0,
            },
        ),
        Case(
            "shutter_capture",
            sensor.shutter_capture,
            {
                "render": _render,
                "exposure_time": 1e-3,
                "mode": "rolling",
                "line_time": 1e-4,
                "samples": 2,
            },
        ),
        Case(
            "simulate_photon_transfer",
            sensor.simulate_photon_transfer,
            {
                "sensor": s,
                "irradiance": 0.05,
                "wavelength_nm": 550.0,
                "exposure_times": np.array([1e-3, 2e-3]),
                "rng": 0,
                "shape": (8, 8),
                "channel": 0,
            },
        ),
        Case("fit_photon_transfer", sensor.fit_photon_transfer, {"data": ptc, "fit_fraction": 0.7}),
        Case("SensorModel", sensor.SensorModel, sm_fields),
        Case("SensorModel.quantum_efficiency", s.quantum_efficiency, {"wavelength_nm": 550.0}),
        Case("SensorModel.fixed_pattern", s.fixed_pattern, {"height": 4, "width": 5}),
        Case(
            "SensorModel.mean_electrons",
            s.mean_electrons,
            {
                "signal": np.full((4, 5), 0.05),
                "exposure_time": 1e-3,
                "quantity": "irradiance",
                "wavelength_nm": 550.0,
            },
        ),
        Case(
            "SensorModel.capture",
            s.capture,
            {
                "signal": np.full((4, 5), 0.05),
                "exposure_time": 1e-3,
                "rng": 0,
                "quantity": "irradiance",
                "wavelength_nm": 550.0,
            },
        ),
        Case("SensorModel.normalize", s.normalize, {"dn": np.array([64, 4095])}),
        Case("SensorModel.frame_readout_time", s.frame_readout_time, {"rows": 1080}),
        Case("SensorModel.dynamic_range_db", s.dynamic_range_db, {}),
    ]
    return out


def _values(base: Any) -> Iterator[tuple[str, Any, bool]]:
    """(label, malformed value, must succeed) for a parameter whose valid value is ``base``."""
    yield "None", None, False
    yield "nan", math.nan, False
    yield "inf", math.inf, False
    yield "-inf", -math.inf, False
    yield "huge", 1e300, False
    yield "huge308", 1e308, False
    yield "int>int64", 2**70, False
    yield "negative", -1, False
    yield "zero", 0, False
    yield "tiny", 1e-300, False
    yield "bool", True, False
    yield "complex", 1 + 2j, False
    yield "string", "abc", False
    yield "object", object(), False
    yield "object_array", np.array([object(), object()], dtype=object), False
    yield "empty", np.empty(0), False
    yield "empty2d", np.empty((0, 0)), False
    yield "short_tuple", (5,), False
    yield "long_tuple", (4, 5, 6, 7), False
    yield "wrong_shape", np.zeros((2, 3, 4, 5)), False
    yield "list_str", ["a", "b"], False
    if torch is not None:
        yield "torch0d", torch.tensor(2.0), False
        yield "torch0d_int", torch.tensor(2), False
    if isinstance(base, bool):
        yield "np.bool_", np.bool_(base), True
        return
    if isinstance(base, int):
        yield "np.int64", np.int64(base), True
        yield "np.int32", np.int32(base), True
        yield "float_of_int", float(base), False
    elif isinstance(base, float):
        yield "np.float64", np.float64(base), True
        yield "np.float32", np.float32(base), False  # a rounded value may leave the range
    elif isinstance(base, tuple) and base and all(isinstance(v, int) for v in base):
        yield "np_int_tuple", tuple(np.int64(v) for v in base), True
        yield "nan_in_tuple", (math.nan, *base[1:]), False
        yield "huge_in_tuple", (10**12, *base[1:]), False
    elif isinstance(base, tuple) and base and all(isinstance(v, float) for v in base):
        yield "nan_in_tuple", (math.nan, *base[1:]), False
        yield "complex_in_tuple", (1j, *base[1:]), False
    elif isinstance(base, np.ndarray) and base.size:
        yield "complex_like", base.astype(np.complex128), False
        yield "object_like", base.astype(object), False
        yield "string_like", base.astype(str), False
        bad = base.astype(np.float64).copy()
        bad.flat[0] = math.nan
        yield "nan_in_array", bad, False
        bad = base.astype(np.float64).copy()
        bad.flat[-1] = math.inf
        yield "inf_in_array", bad, False
        yield "transposed", np.ascontiguousarray(base.T)[..., None], False
        if torch is not None:
            yield "torch_like", torch.from_numpy(base.copy()), False


def _finite(x: Any, depth: int = 0) -> bool:
    if depth > 4 or x is None or isinstance(x, str | bytes | bool):
        return True
    if isinstance(x, int | float | np.number):
        return bool(np.isfinite(x)) if not isinstance(x, int) else True
    if isinstance(x, np.ndarray):
        if x.dtype.kind in "fc":
            return bool(np.all(np.isfinite(x)))
        return x.dtype.kind in "biu"
    if torch is not None and isinstance(x, torch.Tensor):
        return bool(torch.all(torch.isfinite(x)))
    if dataclasses.is_dataclass(x) and not isinstance(x, type):
        return all(_finite(getattr(x, f.name), depth + 1) for f in dataclasses.fields(x))
    if isinstance(x, dict):
        return all(_finite(v, depth + 1) for v in x.values())
    if isinstance(x, list | tuple):
        return all(_finite(v, depth + 1) for v in x)
    return True


# Results documented to hold inf/NaN on purpose.
_INF_OK = {
    "depth_of_field",  # far = inf beyond the hyperfocal distance
    "SensorModel.dynamic_range_db",
    "fit_photon_transfer",  # read_noise NaN below the quantisation noise (documented)
}


def _named(msg: str, param: str, aliases: tuple[str, ...]) -> bool:
    low = msg.lower()
    return any(w.lower() in low for w in (param, *aliases))


@dataclass
class Outcome:
    case: str
    param: str
    label: str
    kind: str
    detail: str


def classify(
    case: Case, param: str, label: str, value: Any, must_succeed: bool, timeout: float
) -> Outcome:
    kwargs = dict(case.kwargs)
    kwargs[param] = value
    old = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, timeout)
    result: Any = None
    exc: BaseException | None = None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            result = case.fn(**kwargs)
        except _Timeout:
            exc = _Timeout()
        except Exception as e:
            exc = e
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, old)
    warned = [w for w in caught if not issubclass(w.category, DeprecationWarning)]

    def out(kind: str, detail: str) -> Outcome:
        return Outcome(case.name, param, label, kind, detail)

    if isinstance(exc, _Timeout):
        return out("timeout", f"> {timeout} s")
    if exc is not None:
        msg = str(exc)
        text = f"{type(exc).__name__}: {msg}"[:300]
        if not isinstance(exc, ImageformError | TypeError):
            return out("raw", text)
        if "\n" in msg or len(msg) > 200:
            return out("message", text)
        if must_succeed:
            return out("refused", text)
        if not _named(msg, param, case.aliases.get(param, ())):
            return out("unnamed", text)
        if warned:
            return out("warning", f"{warned[0].category.__name__}: {warned[0].message}")
        return out("clean", text)
    if warned:
        return out("warning", f"{warned[0].category.__name__}: {warned[0].message}")
    nan_ok = case.name in _INF_OK or f"{param}={label}" in case.nan_ok
    if not nan_ok and not _finite(result):
        return out("nan", f"result {type(result).__name__} holds NaN/inf")
    return out("ok", "")


def _picked(fraction: float, *key: str) -> bool:
    """A fixed, seedless choice of about ``fraction`` of the calls (CRC-32 of the call)."""
    return fraction >= 1.0 or zlib.crc32("|".join(key).encode()) / 2**32 < fraction


def sweep(timeout: float = 5.0, only: str | None = None, fraction: float = 1.0) -> list[Outcome]:
    """Run every case and every malformed value (or a fixed ``fraction`` of them: every
    callable and parameter keeps its baseline); the baselines must succeed."""
    outcomes: list[Outcome] = []
    for case in cases():
        if only and only not in case.name:
            continue
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error")
                warnings.simplefilter("ignore", DeprecationWarning)
                r = case.fn(**case.kwargs)
        except Exception as e:
            raise AssertionError(f"baseline of {case.name} fails: {e!r}") from e
        if case.name not in _INF_OK and not _finite(r):
            raise AssertionError(f"baseline of {case.name} is not finite")
        for param, base_value in case.kwargs.items():
            if param in case.skip:
                continue
            for label, value, must in _values(base_value):
                if _picked(fraction, case.name, param, label):
                    outcomes.append(classify(case, param, label, value, must, timeout))
    return outcomes


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    os.environ.setdefault("IMAGEFORM_MAX_MEMORY", MEMORY_LIMIT)
    verbose = "-v" in argv
    only = next((a for a in argv if not a.startswith("-")), None)
    t0 = time.perf_counter()
    res = sweep(only=only)
    dt = time.perf_counter() - t0
    counts = Counter(o.kind for o in res)
    n_bad = sum(counts[k] for k in BAD)
    print(f"{len(res)} calls over {len({o.case for o in res})} callables in {dt:.1f} s")
    for k in (*GOOD, *BAD):
        print(f"  {k:8s} {counts[k]}")
    if verbose:
        for o in res:
            if o.kind in BAD:
                print(f"[{o.kind}] {o.case}({o.param}={o.label}): {o.detail}")
    else:
        by = Counter((o.kind, o.case, o.param) for o in res if o.kind in BAD)
        for (k, c, p), n in sorted(by.items()):
            print(f"[{k}] {c}({p}) x{n}")
    return 1 if n_bad else 0


if __name__ == "__main__":
    sys.exit(main())
