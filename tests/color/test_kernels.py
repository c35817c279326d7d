"""Numba kernels against their plain array twins (IMAGEFORM_DISABLE_NUMBA path).

Stated tolerances: float32 sRGB -> Lab within 2e-3 in L*a*b* units of the float64 twin
(ΔE00 well below 1e-3 is checked separately with colour-science when available);
Lab -> sRGB within 2e-5; HSV and Y'CbCr within float32 rounding (1e-5 relative / 1e-4 deg);
float64 input runs exact formulas: 1e-9.
"""

from __future__ import annotations

import numpy as np
import pytest

from imageform.color import convert
from imageform.errors import InvalidInputError

RNG = np.random.default_rng(30)
IMG = RNG.uniform(0, 1, (96, 160, 3))
# include exact edge values and the decode breakpoint neighbourhood
IMG[0, :8] = [
    [0, 0, 0],
    [1, 1, 1],
    [0.04045, 0.0404, 0.0405],
    [1, 0, 0],
    [0, 1, 0],
    [0, 0, 1],
    [0.001, 0.002, 0.003],
    [0.5, 0.5, 0.5],
]


def twin(
    x: np.ndarray, src: str, dst: str, monkeypatch: pytest.MonkeyPatch, **p: object
) -> np.ndarray:
    with monkeypatch.context() as m:
        m.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
        return np.asarray(convert(x, src, dst, **p))


def test_srgb_to_lab_float32(monkeypatch: pytest.MonkeyPatch) -> None:
    x = IMG.astype(np.float32)
    fast = convert(x, "srgb", "lab")
    assert fast.dtype == np.float32
    ref = twin(IMG, "srgb", "lab", monkeypatch)
    np.testing.assert_allclose(fast, ref, atol=2e-3)


def test_srgb_to_lab_delta_e00(monkeypatch: pytest.MonkeyPatch) -> None:
    # The accuracy bar: within 1e-3 ΔE00 of a float64 reference (colour-science's
    # CIEDE2000 as the oracle).
    colour = pytest.importorskip("colour")
    fast = convert(IMG.astype(np.float32), "srgb", "lab").astype(np.float64)
    ref = twin(IMG, "srgb", "lab", monkeypatch)
    assert colour.delta_E(fast, ref, method="CIE 2000").max() < 1e-3


def test_srgb_to_lab_uint8(monkeypatch: pytest.MonkeyPatch) -> None:
    x8 = (IMG * 255).round().astype(np.uint8)
    np.testing.assert_allclose(
        convert(x8, "srgb", "lab"), twin(x8 / 255.0, "srgb", "lab", monkeypatch), atol=2e-3
    )


def test_float64_exact(monkeypatch: pytest.MonkeyPatch) -> None:
    for a, b in (("srgb", "lab"), ("srgb", "hsv"), ("srgb", "ycbcr")):
        np.testing.assert_allclose(convert(IMG, a, b), twin(IMG, a, b, monkeypatch), atol=1e-9)
    lab = twin(IMG, "srgb", "lab", monkeypatch)
    np.testing.assert_allclose(convert(lab, "lab", "srgb"), IMG, atol=1e-9)


def test_lab_to_srgb_float32_including_out_of_gamut(monkeypatch: pytest.MonkeyPatch) -> None:
    lab = np.stack(
        [
            RNG.uniform(0, 100, (96, 160)),
            RNG.uniform(-100, 100, (96, 160)),
            RNG.uniform(-100, 100, (96, 160)),
        ],
        axis=-1,
    )
    fast = convert(lab.astype(np.float32), "lab", "srgb")
    ref = twin(lab, "lab", "srgb", monkeypatch)
    np.testing.assert_allclose(fast, ref, rtol=2e-5, atol=2e-5)


def test_out_of_range_srgb_takes_exact_path(monkeypatch: pytest.MonkeyPatch) -> None:
    x = IMG.copy()
    x[5, 5] = [-0.1, 1.2, 0.5]
    fast = convert(x.astype(np.float32), "srgb", "lab")
    np.testing.assert_allclose(fast, twin(x, "srgb", "lab", monkeypatch), atol=2e-3)


@pytest.mark.parametrize("dtype", [np.float32, np.uint8])
def test_hsv_and_ycbcr(dtype: type, monkeypatch: pytest.MonkeyPatch) -> None:
    x = (IMG * 255).round().astype(np.uint8) if dtype is np.uint8 else IMG.astype(np.float32)
    xf = x / 255.0 if dtype is np.uint8 else x.astype(np.float64)
    hsv = convert(x, "srgb", "hsv")
    ref = twin(xf, "srgb", "hsv", monkeypatch)
    dh = np.abs(hsv[..., 0] - ref[..., 0])
    assert np.minimum(dh, 360 - dh).max() < 2e-3
    np.testing.assert_allclose(hsv[..., 1:], ref[..., 1:], atol=2e-6)
    for p in ({}, {"standard": "bt709", "signal_range": "limited", "bits": 10}):
        ycc = convert(x, "srgb", "ycbcr", **p)
        np.testing.assert_allclose(
            ycc, twin(xf, "srgb", "ycbcr", monkeypatch, **p), rtol=1e-5, atol=1e-5
        )
        back = convert(ycc.astype(np.float32), "ycbcr", "srgb", **p)
        np.testing.assert_allclose(back, xf, atol=1e-4)


def test_kernel_boundary_checks() -> None:
    x = IMG.astype(np.float32)
    bad = x.copy()
    bad[3, 3, 1] = np.nan
    with pytest.raises(InvalidInputError, match="NaN"):
        convert(bad, "srgb", "lab")
    with pytest.raises(InvalidInputError, match="NaN"):
        convert(bad, "srgb", "hsv")
    with pytest.raises(InvalidInputError, match="0-255"):
        convert((x * 255).round(), "srgb", "hsv")
    with pytest.raises(InvalidInputError, match="0-255"):
        convert((x * 255).round(), "srgb", "ycbcr")
