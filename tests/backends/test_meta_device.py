"""Device hygiene without a GPU (issue 29): every call on PyTorch ``meta`` tensors.

A ``meta`` tensor has a shape, a dtype and a device but no values, so a call that reads a
value back to the host (``float``, ``bool``, ``.tolist()``, a boolean index) fails on it,
and :class:`~tests.backends._dispatch.DeviceGuard` refuses any operator that mixes it with
a CPU tensor — exactly what a CUDA run refuses or waits for. Two checks:

- the backend matrix (:data:`tests.backends.test_backends_matrix.CASES`) on ``meta``:
  the result's kind, device, shape and dtype equal NumPy's; no device mixing and no
  operator that synchronises. :data:`NEEDS_VALUES` lists the cases that read values by
  contract (reports whose fields are Python numbers, explicit checks), with the reason;
- the pointwise set (docs/design.md, "Devices") in float32 and float64: every conversion
  of ``convert``, the four ΔE, chromatic adaptation, white balance, the transfer
  functions, projection with distortion, the distortion models and their inverses,
  bilinear and Malvar demosaicing, remap and undistortion.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from imageform import color as c  # noqa: E402
from imageform import geometry as g  # noqa: E402
from imageform.sensor import demosaic  # noqa: E402
from tests.backends._dispatch import DeviceGuard  # noqa: E402
from tests.backends.test_backends_matrix import CASES, Case, _result  # noqa: E402

#: Matrix cases that read values by contract, and why (each also runs on CUDA, reading).
NEEDS_VALUES: dict[str, str] = {
    "linear_light_error": "a report: max_error and mean_error are Python floats",
    "palette_check": "a report on the host: Python floats and NumPy colours (explicit copy)",
    "check_in_locus": "an explicit check: it reads its answer (in_locus gives the mask)",
}


def _meta(a: Any, dtype: Any = None) -> Any:
    arr = np.asarray(a)
    dt = dtype or getattr(torch, arr.dtype.name if arr.dtype.kind == "f" else "float64")
    return torch.empty(arr.shape, dtype=dt, device="meta")


def _check_like(out: Any, ref: Any, dtype: str) -> None:
    if isinstance(out, tuple):
        assert isinstance(ref, tuple) and len(out) == len(ref)
        for o, r in zip(out, ref, strict=True):
            _check_like(o, r, dtype)
        return
    ref = np.asarray(ref)
    assert isinstance(out, torch.Tensor), type(out)
    assert out.device.type == "meta", out.device
    assert tuple(out.shape) == ref.shape, (tuple(out.shape), ref.shape)
    want = ref.dtype.name  # NumPy on the same input dtypes: the dtype policy
    assert str(out.dtype).removeprefix("torch.") == want, (out.dtype, want)


def _run_on_meta(fn: Callable[..., Any], args: tuple[Any, ...], dtype: Any = None) -> Any:
    with DeviceGuard() as guard:
        out = fn(*[_meta(a, dtype) for a in args])
    assert not guard.syncs, f"operators that wait for the device: {guard.syncs}"
    return out


#: Every case on meta ("all"), and, for cases of two or more array arguments, with only the
#: first or only the last on meta (a GPU image with a K typed as a list); the cases that
#: need values by contract (NEEDS_VALUES, checked below) are left out.
_PLACED = [
    pytest.param(cs, placement, id=f"{cs.name}-{placement}")
    for cs in CASES
    if cs.name not in NEEDS_VALUES
    for placement in ("all", "first", "last")
    if placement == "all" or len(cs.args) >= 2
]


@pytest.mark.parametrize(("case", "placement"), _PLACED)
def test_matrix_case_on_meta(case: Case, placement: str) -> None:
    ref = _result(case, case.fn(*case.args))
    if placement in ("first", "last"):
        # one argument on meta, the others NumPy: the computation follows the device array,
        # the parameters move to it
        i = 0 if placement == "first" else len(case.args) - 1
        args = [_meta(a) if j == i else a for j, a in enumerate(case.args)]
        with DeviceGuard() as guard:
            out = _result(case, case.fn(*args))
        assert not guard.syncs, f"operators that wait for the device: {guard.syncs}"
    else:
        out = _result(case, _run_on_meta(case.fn, case.args))
    if case.same_kind:
        _check_like(out, ref, "float64")


def test_needs_values_names_are_cases() -> None:
    assert set(NEEDS_VALUES) <= {cs.name for cs in CASES}


# ---------------------------------------------------------------- the pointwise set
_rng = np.random.default_rng(29)
RGB = _rng.uniform(0.05, 0.95, (4, 6, 3))
LAB = c.convert(RGB, "srgb", "lab")
LAB2 = c.convert(_rng.uniform(0.05, 0.95, (4, 6, 3)), "srgb", "lab")
XYZ = c.convert(RGB, "srgb", "xyz")
PTS = _rng.uniform(-1, 1, (7, 3)) + [0, 0, 4]
XYN = _rng.uniform(-0.4, 0.4, (7, 2))
K = np.array([[500.0, 2.0, 320.0], [0.0, 510.0, 240.0], [0.0, 0.0, 1.0]])
KS = np.array([[8.0, 0.0, 3.5], [0.0, 8.0, 3.5], [0.0, 0.0, 1.0]])
R = g.rvec_to_matrix([0.1, -0.2, 0.3])
T = np.array([0.2, -0.1, 4.0])
RAW = _rng.uniform(0, 1, (8, 10))
IMG = _rng.uniform(0, 1, (8, 8, 3))
MODELS = {
    "brown_conrady": g.BrownConrady(k1=-0.2, k2=0.05, p1=1e-3, p2=-2e-3, k3=0.01),
    "kannala_brandt": g.KannalaBrandt(k1=0.05, k2=-0.01),
    "division": g.DivisionModel(k1=-0.1),
}

# one representative input per space: the conversion from sRGB
_SPACE_INPUT = {s: c.convert(RGB, "srgb", s) for s in c.SPACES}

POINTWISE: list[tuple[str, Callable[..., Any], tuple[Any, ...]]] = [
    *[
        (f"convert[{src}->{dst}]", lambda x, s=src, d=dst: c.convert(x, s, d), (_SPACE_INPUT[src],))
        for src in ("srgb", "lab", "xyz", "linear_srgb", "hsv", "ycbcr", "cmyk", "gray")
        for dst in c.SPACES
        if dst != src
    ],
    *[
        (f"convert[{src}->srgb]", lambda x, s=src: c.convert(x, s, "srgb"), (_SPACE_INPUT[src],))
        for src in c.SPACES
        if src not in ("srgb", "lab", "xyz", "linear_srgb", "hsv", "ycbcr", "cmyk", "gray")
    ],
    *[
        (f"delta_e[{m}]", lambda a, b, m=m: c.delta_e(a, b, m), (LAB, LAB2))
        for m in ("cie76", "cie94", "ciede2000", "cmc")
    ],
    *[
        (
            f"chromatic_adaptation[{m}]",
            lambda x, m=m: c.chromatic_adaptation(x, "D65", "D50", method=m),
            (XYZ,),
        )
        for m in ("bradford", "cat02", "von_kries")
    ],
    ("white_balance[gray_world]", lambda x: c.white_balance(x).image, (RGB,)),
    ("white_balance[manual]", lambda x: c.white_balance(x, "manual", illuminant="A").image, (RGB,)),
    *[
        (f"decode[{t}]", lambda x, t=t: c.decode(x, t), (RGB,))
        for t in ("srgb", "adobe_rgb", "rec709", "rec2020", "prophoto", "gamma", "linear")
    ],
    *[
        (f"encode[{t}]", lambda x, t=t: c.encode(x, t), (RGB,))
        for t in ("srgb", "adobe_rgb", "rec709", "rec2020", "prophoto", "gamma", "linear")
    ],
    ("project_points", lambda p: g.project_points(p, K, R, T).uv, (PTS,)),
    *[
        (
            f"project_points_distorted[{n}]",
            lambda p, m=m: g.project_points_distorted(p, K, R, T, m)[0],
            (PTS,),
        )
        for n, m in MODELS.items()
    ],
    *[(f"distort[{n}]", lambda x, m=m: m.distort(x), (XYN,)) for n, m in MODELS.items()],
    *[(f"undistort[{n}]", lambda x, m=m: m.undistort(x), (XYN,)) for n, m in MODELS.items()],
    *[
        (f"demosaic[{m}-{p}]", lambda r, m=m, p=p: demosaic(r, p, m), (RAW,))
        for m in ("bilinear", "malvar")
        for p in ("RGGB", "GBRG")
    ],
    (
        "remap_bilinear",
        lambda im, mp: g.remap_bilinear(im, mp),
        (IMG, g.undistortion_map((8, 8), KS, MODELS["brown_conrady"])),
    ),
    *[
        (f"undistort_image[{n}]", lambda im, m=m: g.undistort_image(im, KS, m), (IMG,))
        for n, m in MODELS.items()
    ],
    (
        "undistortion_map[meta K]",
        lambda k: g.undistortion_map((5, 7), k, MODELS["brown_conrady"]),
        (KS,),
    ),
]


@pytest.mark.parametrize("dtype", ["float32", "float64"])
@pytest.mark.parametrize(("fn", "args"), [p[1:] for p in POINTWISE], ids=[p[0] for p in POINTWISE])
def test_pointwise_set_on_meta(fn: Callable[..., Any], args: tuple[Any, ...], dtype: str) -> None:
    ref = fn(*[np.asarray(a, dtype=dtype) for a in args])
    out = _run_on_meta(fn, args, getattr(torch, dtype))
    if hasattr(ref, "_fields"):  # a named tuple (Undistorted): its arrays
        ref, out = tuple(ref), tuple(out)
    _check_like(out, ref, dtype)


def test_guard_catches_mixing_and_syncs() -> None:
    from tests.backends._dispatch import DeviceMixingError

    x = torch.empty(4, 3, device="meta")
    with pytest.raises(DeviceMixingError), DeviceGuard():
        _ = x + torch.ones(4, 3)
    with DeviceGuard() as guard:
        _ = x + torch.tensor(1.0)  # a 0-d CPU tensor is a scalar: allowed, as on CUDA
        x[x > 0] = 0.0
    assert guard.syncs == ["aten::index_put_"]
