"""Boundary sweep of ``imageform.spectral`` and ``imageform.color`` (issue 16).

Every public callable of the two packages (every name in their ``__all__`` that can be called,
the constructors of the input types ``Spectrum`` and ``RGBSpace`` and ``Spectrum``'s public
methods) is called from one valid baseline call with one parameter replaced at a time by a
malformed value: empty, wrong shape, NaN, inf, None, complex, object, string, bool, huge
(1e300), negative, zero, NumPy scalars and a 0-d torch tensor. Each call runs in this process
under a timeout and its outcome is classified:

- ``error``: an ImageformError or TypeError in one line of at most 220 characters (good);
- ``result``: a finite result (good, unless the value should have been refused, below);
- ``raw``: any other exception (IndexError, OverflowError, LinAlgError ...);
- ``nan``: the result holds NaN or inf;
- ``warning``: the call issued a non-imageform warning (ComplexWarning, RuntimeWarning ...);
- ``long``: an imageform error whose message is multi-line or longer than 220 characters;
- ``misnamed``: the message names another parameter of the function, not the one replaced;
- ``accepted``: complex, object, string or bool input (or NaN/inf in a parameter) was
  accepted;
- ``refused-np``: a NumPy scalar was refused where the Python number is taken;
- ``timeout``: the call ran past the timeout.

Run ``PYTHONPATH=src python -m tests.color._sweep`` (``-v`` lists every bad outcome).
``tests/color/test_boundary_sweep.py`` runs the same sweep and asserts no bad outcome.
"""

from __future__ import annotations

import contextlib
import inspect
import math
import signal
import sys
import time
import warnings
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, fields, is_dataclass
from typing import Any

import numpy as np

import imageform.color as C
import imageform.spectral as S
from imageform.errors import ImageformError, ImageformWarning

BAD = (
    "raw",
    "nan",
    "warning",
    "long",
    "misnamed",
    "accepted",
    "refused-np",
    "timeout",
)
MAX_LEN = 220

try:  # pragma: no cover - torch is installed in the dev environment
    import torch
except ImportError:  # pragma: no cover
    torch = None


@dataclass
class Outcome:
    target: str
    param: str
    kind: str
    outcome: str
    detail: str = ""


@dataclass
class Target:
    name: str
    func: Callable[..., Any]
    kwargs: dict[str, Any]
    params: tuple[str, ...] = ()  # parameters to mutate; default: every key of kwargs
    skip: dict[str, tuple[str, ...]] = field(default_factory=dict)  # param -> kinds allowed


# ---------------------------------------------------------------------------------------------
# baselines


def _spec(n: int = 41, k: int = 0, lo: float = 380.0, hi: float = 780.0) -> S.Spectrum:
    w = np.linspace(lo, hi, n)
    base = 0.2 + 0.6 * np.exp(-(((w - 550.0) / 80.0) ** 2))
    v = base if k == 0 else np.stack([base * (0.5 + 0.1 * i) for i in range(k)], axis=1)
    return S.Spectrum(w, v, name="test")


def _primaries() -> S.Spectrum:
    w = np.linspace(380.0, 780.0, 41)
    v = np.stack([np.exp(-(((w - c) / 20.0) ** 2)) for c in (610.0, 545.0, 450.0)], axis=1)
    return S.Spectrum(w, v, name="primaries")


RGB = np.array([[0.2, 0.5, 0.8], [0.9, 0.1, 0.3], [0.5, 0.5, 0.5], [0.0, 0.7, 1.0]])
IMG = np.random.default_rng(0).uniform(0.05, 0.95, (4, 6, 3))
XYZ = np.array([[0.2, 0.3, 0.4], [0.5, 0.4, 0.3], [0.95, 1.0, 1.09]])
LAB = np.array([[50.0, 10.0, -20.0], [70.0, -30.0, 5.0]])
LAB2 = np.array([[52.0, 12.0, -18.0], [68.0, -28.0, 9.0]])
XY = np.array([[0.3127, 0.3290], [0.4476, 0.4074]])
HUE = np.array([10.0, 200.0, 355.0])


def targets() -> list[Target]:
    sp = _spec()
    sp3 = _spec(k=3)
    ts: list[Target] = []

    def add(label: str, func: Any, /, **kwargs: Any) -> None:
        ts.append(Target(label, func, kwargs))

    # ---- spectral
    add("Spectrum", S.Spectrum, wavelengths=np.linspace(400, 700, 7), values=np.ones(7))
    add("Spectrum.peak_wavelength", sp.peak_wavelength)
    add("Spectrum.interpolate", sp.interpolate, wavelengths=np.array([450.0, 500.0]))
    add("Spectrum.resample", sp.resample, start=400.0, stop=700.0, step=10.0)
    add("Spectrum.trim", sp.trim, start=400.0, stop=700.0)
    add("Spectrum.normalize", sp.normalize, at=560.0)
    add("Spectrum.allclose", sp.allclose, other=sp)
    add(
        "Spectrum.from_columns",
        S.Spectrum.from_columns,
        wavelengths=np.linspace(400, 700, 7),
        columns=[np.ones(7), np.full(7, 0.5)],
    )
    add("blackbody_spectrum", S.blackbody_spectrum, temperature=5000.0)
    add("camera_sensitivities", S.camera_sensitivities)
    add("cmfs", S.cmfs)
    add("colorchecker_published_xyy", S.colorchecker_published_xyy)
    add("colorchecker_reflectances", S.colorchecker_reflectances)
    add("cone_fundamentals", S.cone_fundamentals)
    add("daylight_spectrum", S.daylight_spectrum, cct=6504.0)
    add("daylight_spectrum_from_xy", S.daylight_spectrum_from_xy, xy=np.array([0.3127, 0.329]))
    add("illuminant", S.illuminant, name="D65")
    add("illuminant_table", S.illuminant_table, name="A")
    add("integration_weights", S.integration_weights, functions=S.cmfs(2), illuminant=None)
    add("led_spectrum", S.led_spectrum)
    add("load_table", S.load_table, key="cmf_2")
    add("luminance", S.luminance, spectrum=sp)
    add("luminous_efficiency", S.luminous_efficiency)
    add("observer_functions", S.observer_functions)
    add("planck", S.planck, wavelength_nm=np.array([400.0, 550.0, 700.0]), temperature=5000.0)
    add("planckian_cct", S.planckian_cct, xyz=np.array([0.9505, 1.0, 1.089]))
    add("read_table", S.read_table, key="cmf_2")
    add("resolve_illuminant", S.resolve_illuminant, illuminant="D65")
    add("spectrum_to_camera_rgb", S.spectrum_to_camera_rgb, spectrum=sp)
    add("spectrum_to_lms", S.spectrum_to_lms, spectrum=sp)
    add("spectrum_to_xyz", S.spectrum_to_xyz, spectrum=sp)
    add("table_source", S.table_source, key="cmf_2")

    # ---- color
    add(
        "RGBSpace",
        C.RGBSpace,
        name="mine",
        primaries_xy=((0.64, 0.33), (0.3, 0.6), (0.15, 0.06)),
        white_xy=(0.3127, 0.329),
        transfer="srgb",
        source="test",
    )
    add("RGBSpace.matrix_to_xyz", C.rgb_space("srgb").matrix_to_xyz)
    for n in (
        "adobe_rgb_to_linear",
        "linear_to_adobe_rgb",
        "linear_to_prophoto",
        "linear_to_rec709",
        "linear_to_rec2020",
        "linear_to_srgb",
        "prophoto_to_linear",
        "rec709_to_linear",
        "rec2020_to_linear",
        "srgb_to_linear",
    ):
        add(n, getattr(C, n), values=RGB)
    add("gamma_to_linear", C.gamma_to_linear, values=RGB)
    add("linear_to_gamma", C.linear_to_gamma, values=RGB)
    add("decode", C.decode, values=RGB)
    add("encode", C.encode, values=RGB)
    for n in ("bgr_to_srgb", "srgb_to_bgr", "srgb_to_cmy", "srgb_to_cmyk", "srgb_to_gray"):
        add(n, getattr(C, n), image=RGB)
    for n in ("srgb_to_hsi", "srgb_to_hsl", "srgb_to_hsv", "linear_srgb_to_luminance"):
        add(n, getattr(C, n), image=RGB)
    add("srgb_to_ycbcr", C.srgb_to_ycbcr, image=RGB)
    add("rgb_to_ycbcr", C.rgb_to_ycbcr, image=RGB)
    add("ycbcr_to_srgb", C.ycbcr_to_srgb, ycbcr=np.array([[0.5, 0.5, 0.5], [0.3, 0.4, 0.6]]))
    add("ycbcr_to_rgb", C.ycbcr_to_rgb, ycbcr=np.array([[0.5, 0.5, 0.5], [0.3, 0.4, 0.6]]))
    add("hsv_to_srgb", C.hsv_to_srgb, hsv=np.array([[10.0, 0.5, 0.5], [200.0, 1.0, 0.2]]))
    add("hsl_to_srgb", C.hsl_to_srgb, hsl=np.array([[10.0, 0.5, 0.5], [200.0, 1.0, 0.2]]))
    add("hsi_to_srgb", C.hsi_to_srgb, hsi=np.array([[10.0, 0.5, 0.5], [200.0, 0.3, 0.2]]))
    add("cmy_to_cmyk", C.cmy_to_cmyk, cmy=RGB)
    add("cmy_to_srgb", C.cmy_to_srgb, cmy=RGB)
    add("cmyk_to_cmy", C.cmyk_to_cmy, cmyk=np.array([[0.1, 0.2, 0.3, 0.4]]))
    add("cmyk_to_srgb", C.cmyk_to_srgb, cmyk=np.array([[0.1, 0.2, 0.3, 0.4]]))
    add("gray_to_srgb", C.gray_to_srgb, gray=np.array([[0.1], [0.5], [0.9]]))
    add("are_metamers", C.are_metamers, s1=sp, s2=sp * 1.01)
    add("brettel_planes", C.brettel_planes, deficiency="protan")
    add("cct_to_xy", C.cct_to_xy, cct=np.array([3000.0, 6500.0]))
    add("check_in_locus", C.check_in_locus, points=XY)
    add("in_locus", C.in_locus, points=XY)
    add("chroma_subsample", C.chroma_subsample, ycbcr=IMG)
    add("chroma_upsample", C.chroma_upsample, luma=IMG[..., 0], chroma=IMG[:2, :3, 1:])
    add("chromatic_adaptation", C.chromatic_adaptation, xyz=XYZ, src_white="D65", dst_white="D50")
    add(
        "chromatic_adaptation_matrix",
        C.chromatic_adaptation_matrix,
        src_white=np.array([0.9505, 1.0, 1.089]),
        dst_white="D50",
    )
    add("convert", C.convert, image=RGB, src="srgb", dst="lab")
    add("srgb8_to_lab", C.srgb8_to_lab, image=np.array([[10, 128, 200], [0, 0, 0]], np.uint8))
    add("cvd_matrix", C.cvd_matrix, deficiency="deutan")
    add("machado_matrix", C.machado_matrix, deficiency="deutan")
    for n in ("delta_e", "delta_e_cie76", "delta_e_cie94", "delta_e_ciede2000", "delta_e_cmc"):
        add(n, getattr(C, n), lab1=LAB, lab2=LAB2)
    add("describe_delta_e", C.describe_delta_e, value=2.5)
    add("downsample", C.downsample, image=IMG, factor=2)
    add("estimate_illuminant", C.estimate_illuminant, image=IMG)
    add("white_balance", C.white_balance, image=IMG)
    add("from_opencv", C.from_opencv, values=np.array([[10.0, 128.0, 200.0]]), convention="hsv8")
    add("to_opencv", C.to_opencv, values=np.array([[10.0, 0.5, 0.8]]), convention="hsv8")
    add("gamut_area", C.gamut_area)
    add("gamut_coverage", C.gamut_coverage)
    add("gamut_figures", C.gamut_figures, spaces=("srgb",))
    add("gamut_map", C.gamut_map, xyz=XYZ)
    add("gamut_triangle", C.gamut_triangle)
    add("in_gamut", C.in_gamut, values=XYZ)
    add("hue_difference", C.hue_difference, h1=HUE, h2=HUE[::-1].copy())
    add("hue_distance", C.hue_distance, h1=HUE, h2=HUE[::-1].copy())
    add("hue_in_range", C.hue_in_range, hue=HUE, start=350.0, stop=20.0)
    add("hue_undefined_mask", C.hue_undefined_mask, values=RGB)
    add("lab_to_lch", C.lab_to_lch, lab=LAB)
    add("lch_to_lab", C.lch_to_lab, lch=np.array([[50.0, 20.0, 30.0]]))
    add("lab_to_xyz", C.lab_to_xyz, lab=LAB)
    add("luv_to_xyz", C.luv_to_xyz, luv=LAB)
    add("xyz_to_lab", C.xyz_to_lab, xyz=XYZ)
    add("xyz_to_luv", C.xyz_to_luv, xyz=XYZ)
    add("xyz_to_xyy", C.xyz_to_xyy, xyz=XYZ)
    add("xyy_to_xyz", C.xyy_to_xyz, xyy=np.array([[0.3, 0.3, 0.5]]))
    add("linear_light_error", C.linear_light_error, image=IMG)
    add("mean_linear_light", C.mean_linear_light, image=IMG)
    add("linear_rgb_to_xyz", C.linear_rgb_to_xyz, rgb=RGB)
    add("linear_srgb_to_xyz", C.linear_srgb_to_xyz, rgb=RGB)
    add("xyz_to_linear_rgb", C.xyz_to_linear_rgb, xyz=XYZ)
    add("xyz_to_linear_srgb", C.xyz_to_linear_srgb, xyz=XYZ)
    add("match_with_primaries", C.match_with_primaries, target=sp, primaries=_primaries())
    add("metamer", C.metamer, spectrum=sp)
    add("metamerism_index", C.metamerism_index, s1=sp, s2=sp * 1.01)
    add("palette", C.palette, name="okabe_ito")
    add("palette_check", C.palette_check, colors=RGB[:3])
    add("parse_colors", C.parse_colors, colors=["#ff0000", "#00ff00"])
    add("path", C.path, src="srgb", dst="lab")
    add("polygon_area", C.polygon_area, vertices=np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]))
    add("resolve_white", C.resolve_white, white="D65")
    add("rgb_space", C.rgb_space, space="srgb")
    add("rgb_to_xyz_matrix", C.rgb_to_xyz_matrix)
    add("xyz_to_rgb_matrix", C.xyz_to_rgb_matrix)
    add("simulate_cvd", C.simulate_cvd, image=RGB, deficiency="protan")
    add("space_name", C.space_name, name="srgb")
    add("spectral_locus", C.spectral_locus)
    add("subsample_round_trip", C.subsample_round_trip, image=IMG)
    add("subsampling_delta_e", C.subsampling_delta_e, image=IMG)
    add("tristimulus", C.tristimulus, spectrum=sp)
    add("uv1960_to_xy", C.uv1960_to_xy, uv=np.array([[0.2, 0.3]]))
    add("uv_prime_to_xy", C.uv_prime_to_xy, uv=np.array([[0.2, 0.45]]))
    add("viridis", C.viridis, n=8)
    add("visible_area", C.visible_area)
    add("whitepoint_xy", C.whitepoint_xy, name="D65")
    add("whitepoint_xyz", C.whitepoint_xyz, name="D65")
    add("xy_to_cct", C.xy_to_cct, xy=XY)
    add("xy_to_uv1960", C.xy_to_uv1960, xy=XY)
    add("xy_to_uv_prime", C.xy_to_uv_prime, xy=XY)
    add("xy_to_xyz", C.xy_to_xyz, xy=XY)
    add("xy_to_xyz_white", C.xy_to_xyz_white, xy=(0.3127, 0.329))
    add("xyz_to_uv_prime", C.xyz_to_uv_prime, xyz=XYZ)
    add("xyz_to_xy", C.xyz_to_xy, xyz=XYZ)
    del sp3
    # the defaulted parameters are swept too (at their default value as the baseline)
    for t in ts:
        _fill_defaults(t)
    return ts


def _fill_defaults(t: Target) -> None:
    try:
        sig = inspect.signature(t.func)
    except (TypeError, ValueError):  # pragma: no cover
        return
    for p in sig.parameters.values():
        if p.kind in (p.VAR_KEYWORD, p.VAR_POSITIONAL) or p.name in t.kwargs:
            continue
        if p.default is not p.empty:
            t.kwargs[p.name] = p.default
    if not t.params:
        t.params = tuple(t.kwargs)


def public_callables() -> set[str]:
    """Every callable public name of both packages (what :func:`targets` must cover)."""
    names = set()
    for mod in (S, C):
        for n in mod.__all__:
            obj = getattr(mod, n)
            if callable(obj) and not _is_result_type(obj):
                names.add(n)
    return names


def _is_result_type(obj: Any) -> bool:
    """NamedTuples and dataclasses that only carry results (never taken as input)."""
    return inspect.isclass(obj) and obj.__name__ not in ("Spectrum", "RGBSpace")


# ---------------------------------------------------------------------------------------------
# malformed values


def _variants(value: Any) -> Iterator[tuple[str, Any]]:
    """(kind, value) pairs of malformed (and a few valid-but-unusual) values for ``value``."""
    if isinstance(value, S.Spectrum):
        yield "none", None
        yield "string", "nonsense"
        yield "array", np.ones(3)
        yield "far-range", _spec(lo=100.0, hi=200.0)
        yield "short", S.Spectrum([500.0], [1.0])
        return
    if isinstance(value, C.RGBSpace):
        yield "none", None
        return
    if isinstance(value, bool):
        yield "none", None
        yield "int", 1
        yield "string", "yes"
        yield "np-scalar", np.bool_(value)
        yield "array", np.array([True, False])
        return
    if isinstance(value, str):
        yield "none", None
        yield "int", 5
        yield "unknown", "no-such-thing"
        yield "empty-str", ""
        yield "bytes", value.encode()
        yield "np-scalar", np.str_(value)
        yield "list", [value]
        return
    if (isinstance(value, int | float) and not isinstance(value, bool)) or value is None:
        is_int = isinstance(value, int)
        v = 2 if value is None else value
        yield "nan", math.nan
        yield "inf", math.inf
        yield "-inf", -math.inf
        yield "none", None
        yield "complex", complex(v, 1.0)
        yield "string", "1"
        yield "bool", True
        yield "huge", 1e300
        yield "1e308", 1e308
        yield "negative", -abs(v) - 1
        yield "zero", 0
        yield "tiny", 1e-300
        yield "array", np.array([v, v])
        yield "object", object()
        if is_int:
            yield "np-scalar", np.int64(v)
            yield "np-int32", np.int32(v)
            yield "float-int", 2.5
            yield "big-int", 2**70
            yield "large-count", 10**12
        elif value is not None:
            yield "np-scalar", np.float64(v)
            yield "np-float32", np.float32(v)
        if torch is not None and value is not None:
            yield "torch-0d", torch.tensor(v)
        return
    if isinstance(value, list | tuple) and value and all(isinstance(v, str) for v in value):
        yield "none", None
        yield "empty", type(value)()
        yield "int", 5
        yield "unknown", type(value)(["no-such-thing"])
        yield "string", "srgb"
        return
    arr = np.asarray(value) if not isinstance(value, list) else None
    if arr is None or arr.dtype.kind not in "fiu" or arr.size == 0:
        yield "none", None
        yield "int", 5
        return
    a = arr.astype(np.float64)
    yield "empty", np.zeros((0,) + a.shape[1:])
    yield "empty-1d", np.zeros((0,))
    if a.ndim >= 3:
        yield "empty-image", np.zeros((0, 0) + a.shape[2:])
    yield "scalar", 0.5
    if a.ndim >= 1:
        wrong = np.concatenate([a, a[..., :1]], axis=-1)
        yield "wrong-shape", wrong
    yield "nan", _poke(a, math.nan)
    yield "inf", _poke(a, math.inf)
    yield "none", None
    yield "complex", a.astype(np.complex128)
    yield "object", a.astype(object)
    yield "string-array", a.astype(str)
    yield "string", "abc"
    yield "bool-array", a > a.mean()
    yield "huge", a * 1e300 + 1e300
    yield "negative", -a - 1.0
    yield "zero", np.zeros_like(a)
    yield "list", a.tolist()
    yield "float32", a.astype(np.float32)
    yield "huge-float32", (a * 1e30 + 1e30).astype(np.float32)
    if torch is not None:
        yield "torch", torch.from_numpy(a.copy())
    if a.ndim >= 1 and isinstance(value, tuple):
        yield "np-array", a


def _poke(a: np.ndarray, v: float) -> np.ndarray:
    b = a.copy()
    b.flat[0] = v
    return b


# kinds whose value must be refused when it reaches a numeric parameter
_REFUSE = {"complex", "object", "string-array", "string", "bool", "bool-array", "bytes"}
_NONFINITE = {"nan", "inf", "-inf"}


# ---------------------------------------------------------------------------------------------
# running


class _Timeout(BaseException):
    pass


@contextlib.contextmanager
def _time_limit(seconds: float) -> Iterator[None]:
    if not hasattr(signal, "setitimer"):  # pragma: no cover - Windows
        yield
        return

    def handler(signum: int, frame: Any) -> None:
        raise _Timeout

    old = signal.signal(signal.SIGALRM, handler)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def _finite(obj: Any, depth: int = 0) -> bool:
    if depth > 4 or obj is None or isinstance(obj, str | bool | bytes):
        return True
    if isinstance(obj, S.Spectrum):
        return bool(np.all(np.isfinite(obj.values)))
    if isinstance(obj, float | int | complex):
        return bool(np.isfinite(obj))
    if isinstance(obj, np.ndarray | np.generic):
        if obj.dtype.kind in "fc":
            return bool(np.all(np.isfinite(obj)))
        return True
    if torch is not None and isinstance(obj, torch.Tensor):
        return bool(torch.all(torch.isfinite(obj)))
    if isinstance(obj, dict):
        return all(_finite(v, depth + 1) for v in obj.values())
    if isinstance(obj, tuple | list):
        return all(_finite(v, depth + 1) for v in obj)
    if is_dataclass(obj):
        return all(_finite(getattr(obj, f.name), depth + 1) for f in fields(obj))
    return True


# results that are NaN by definition (documented), as (target, kind) pairs: none so far
_NAN_DOCUMENTED: set[tuple[str, str]] = set()

# a NaN/inf value that a parameter accepts on purpose: (target, param, kind)
_NONFINITE_OK = {
    # inf is a valid upper bound / tolerance
    ("are_metamers", "tol", "inf"),
    ("are_metamers", "spectral_tol", "inf"),
    ("in_gamut", "tol", "inf"),
    # an unbounded end of the trimmed range
    ("Spectrum.trim", "start", "-inf"),
    ("Spectrum.trim", "stop", "inf"),
}


def _names_param(msg: str, param: str, others: set[str]) -> str:
    """ "ok" if the message names ``param`` (or names no other parameter), else "misnamed"."""
    low = msg.lower()
    if param.lower() in low:
        return "ok"
    wrong = [o for o in others if o != param and len(o) > 2 and _word_in(o, low)]
    return "misnamed" if wrong else "ok"


def _word_in(word: str, text: str) -> bool:
    import re

    return re.search(rf"(?<![a-z_]){re.escape(word.lower())}(?![a-z_])", text) is not None


def run_one(t: Target, param: str, kind: str, value: Any, timeout: float = 10.0) -> Outcome:
    kwargs = dict(t.kwargs)
    kwargs[param] = value
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            with _time_limit(timeout):
                result = t.func(**kwargs)
        except _Timeout:
            return Outcome(t.name, param, kind, "timeout")
        except (ImageformError, TypeError) as exc:
            msg = str(exc)
            signature_error = "argument" in msg and ("unexpected" in msg or "missing" in msg)
            if not isinstance(exc, ImageformError) and signature_error:
                return Outcome(t.name, param, kind, "raw", f"{type(exc).__name__}: {msg}")
            if "\n" in msg or len(msg) > MAX_LEN or not msg:
                return Outcome(t.name, param, kind, "long", msg[:300])
            if kind.startswith("np-") and not isinstance(value, np.ndarray):
                return Outcome(t.name, param, kind, "refused-np", msg)
            if _names_param(msg, param, set(t.kwargs)) == "misnamed":
                return Outcome(t.name, param, kind, "misnamed", msg)
            return Outcome(t.name, param, kind, "error", msg)
        except Exception as exc:
            return Outcome(t.name, param, kind, "raw", f"{type(exc).__name__}: {exc}"[:300])
    bad = [
        w
        for w in caught
        if not issubclass(w.category, ImageformWarning | DeprecationWarning)
        or (issubclass(w.category, DeprecationWarning) and "imageform" not in str(w.filename))
    ]
    bad = [w for w in bad if not issubclass(w.category, ImageformWarning)]
    if bad:
        w = bad[0]
        return Outcome(t.name, param, kind, "warning", f"{w.category.__name__}: {w.message}"[:300])
    if not _finite(result) and (t.name, kind) not in _NAN_DOCUMENTED:
        return Outcome(t.name, param, kind, "nan")
    if kind in _REFUSE and not isinstance(t.kwargs[param], str | bool):
        return Outcome(t.name, param, kind, "accepted", f"{type(value).__name__} accepted")
    if kind in _REFUSE and kind not in ("string", "bytes") and isinstance(t.kwargs[param], str):
        return Outcome(t.name, param, kind, "accepted", f"{type(value).__name__} accepted")
    numeric = isinstance(t.kwargs[param], float | int) or t.kwargs[param] is None
    if kind in _NONFINITE and (t.name, param, kind) not in _NONFINITE_OK and numeric:
        return Outcome(t.name, param, kind, "accepted", f"{kind} accepted")
    return Outcome(t.name, param, kind, "result")


def sweep(only: set[str] | None = None, timeout: float = 10.0) -> list[Outcome]:
    out: list[Outcome] = []
    for t in targets():
        if only is not None and t.name not in only:
            continue
        base = run_one_baseline(t)
        if base is not None:
            out.append(base)
            continue
        for param in t.params:
            for kind, value in _variants(t.kwargs[param]):
                if kind in t.skip.get(param, ()):
                    continue
                out.append(run_one(t, param, kind, value, timeout))
    return out


def run_one_baseline(t: Target) -> Outcome | None:
    """None if the baseline call succeeds cleanly, else its (bad) outcome."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            res = t.func(**t.kwargs)
        except Exception as exc:
            return Outcome(t.name, "-", "baseline", "raw", f"{type(exc).__name__}: {exc}")
    if not _finite(res):
        return Outcome(t.name, "-", "baseline", "nan")
    return None


def main(argv: list[str]) -> int:
    verbose = "-v" in argv
    only = {a for a in argv if not a.startswith("-")} or None
    t0 = time.perf_counter()
    res = sweep(only)
    dt = time.perf_counter() - t0
    counts = Counter(o.outcome for o in res)
    covered = {t.name for t in targets()}
    missing = sorted(public_callables() - covered)
    print(f"{len(res)} calls over {len({o.target for o in res})} callables in {dt:.1f} s")
    for k in ("error", "result", *BAD):
        print(f"  {k:11s} {counts.get(k, 0)}")
    nbad = sum(counts.get(k, 0) for k in BAD)
    print(f"  BAD total   {nbad}")
    if missing:
        print("not covered:", ", ".join(missing))
    if verbose:
        for o in res:
            if o.outcome in BAD:
                print(f"{o.outcome:10s} {o.target}({o.param}={o.kind}): {o.detail[:200]}")
    return 1 if nbad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
