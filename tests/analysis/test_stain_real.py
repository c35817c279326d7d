"""Macenko on real slides: glass found at its mode, glass that does not rescale the stains.

Real tiles (``tests/data/stain/README.md``): a crop of torchstain's H&E target tile (no glass)
and a crop of TIAToolbox's colon slide thumbnail (tissue and glass). Generated tiles
(:func:`synthetic_he_tile`) reproduce each property with a known answer: glass at a known
I0 with a scanner's noise, the same tissue with more or less glass around it, tiles of one
flat colour. Peer: torchstain 1.4.1's numpy Macenko (the reference code's port).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imageform.analysis import (
    estimate_background,
    macenko_normalize,
    macenko_stains,
    stain_angle,
    synthetic_he_tile,
    vahadane_stains,
)
from imageform.color import delta_e_ciede2000, srgb8_to_lab
from imageform.errors import DegenerateConfigurationError

DATA = Path(__file__).resolve().parent.parent / "data" / "stain"


def _read(name: str) -> np.ndarray:
    iio = pytest.importorskip("imageio.v3")
    return np.asarray(iio.imread(DATA / name))[..., :3]


def _u8(x: np.ndarray) -> np.ndarray:
    return np.clip(np.round(np.asarray(x, dtype=np.float64) * 255), 0, 255).astype(np.uint8)


def _de(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.mean(delta_e_ciede2000(srgb8_to_lab(_u8(a)), srgb8_to_lab(_u8(b)))))


def _tile(seed: int, *, glass: float, noise: float = 1.5) -> np.ndarray:
    t = synthetic_he_tile((192, 192), background=glass, noise=noise / 255, rng=seed)
    return np.round(t.image * 255).astype(np.uint8)


def _pad_with_glass(img8: np.ndarray, factor: int, seed: int = 0) -> np.ndarray:
    """``img8`` in the corner of a ``factor``-times larger field of glass at 240 (noise 1.5)."""
    h, w, _ = img8.shape
    gen = np.random.default_rng(seed)
    out = np.clip(np.round(240 + gen.normal(0, 1.5, (h * factor, w * factor, 3))), 0, 255)
    out = out.astype(np.uint8)
    out[:h, :w] = img8
    return out


@pytest.mark.parametrize("noise", [3.0, 5.0])
def test_i0_is_the_glass_not_its_noise_tail(noise: float) -> None:
    """Glass at 240 with a scanner's noise (3-5 codes: JPEG, stitching): the 99th percentile
    lies 5-10 codes above it, the glass's mode on it."""
    img8 = _tile(4, glass=0.3, noise=noise)
    p99 = np.percentile(img8.reshape(-1, 3), 99, axis=0)
    assert np.all(p99 >= 240 + 1.5 * noise)
    est = estimate_background(img8)
    assert est.found
    # measured within 0.03 codes (noise 3) and 1.0 (noise 5: the histogram's own noise);
    # the percentile: 5-10 codes above
    np.testing.assert_allclose(est.i0 * 255, 240, atol=1.5)


def test_i0_on_a_real_slide_is_its_glass() -> None:
    """The colon crop's glass: a strip along its left edge at 243 (the 99th percentile of
    the tile, (251, 246, 253), lies on brighter specks and a blue cast of the tissue edge)."""
    img8 = _read("tiatoolbox_colon_crop.png")
    glass = np.median(img8[:, :24].reshape(-1, 3), axis=0)
    np.testing.assert_allclose(glass, 243)
    est = estimate_background(img8)
    assert est.found
    np.testing.assert_allclose(est.i0 * 255, glass, atol=1.0)  # measured within 0.06


@pytest.mark.parametrize("factor", [2, 3])
def test_max_concentrations_do_not_depend_on_the_share_of_glass(factor: int) -> None:
    """The same tissue with 75 % or 89 % glass around it: the reference code's percentile
    over every pixel falls with the glass (to 0.89 and 0.72 of the glass-free value for H;
    measured now: equal)."""
    tile = _tile(5, glass=0.0)
    padded = _pad_with_glass(tile, factor)
    alone = macenko_stains(tile, i0=240 / 255)
    framed = macenko_stains(padded, i0=240 / 255)
    np.testing.assert_allclose(framed.max_concentrations, alone.max_concentrations, rtol=0.01)
    # Vahadane shares the percentile
    np.testing.assert_allclose(
        vahadane_stains(padded, i0=240 / 255).max_concentrations,
        vahadane_stains(tile, i0=240 / 255).max_concentrations,
        rtol=0.02,
    )


@pytest.mark.parametrize("factor", [2, 3])
def test_real_tissue_normalises_alike_with_and_without_glass(factor: int) -> None:
    """torchstain's H&E target crop alone and framed by glass, normalised (defaults) to the
    colon crop: the tissue comes out the same (before: 4.3 and 9.4 CIEDE2000 apart;
    torchstain: 5.0 and 10.7)."""
    tile = _read("torchstain_target_crop.png")
    target = _read("tiatoolbox_colon_crop.png")
    padded = _pad_with_glass(tile, factor)
    h, w, _ = tile.shape
    alone = macenko_normalize(tile, target)
    framed = macenko_normalize(padded, target)[:h, :w]
    assert _de(alone, framed) < 0.5  # measured 0.001


def test_real_tile_without_glass_agrees_with_torchstain() -> None:
    normalizers = pytest.importorskip("torchstain.numpy.normalizers")
    tile = _read("torchstain_target_crop.png")
    peer = normalizers.NumpyMacenkoNormalizer()
    peer.fit(tile, Io=240, alpha=1, beta=0.15)
    he = np.asarray(peer.HERef).T
    est = macenko_stains(tile)
    assert est.i0_source == "default"
    # measured 0.04 / 0.22 deg
    assert max(stain_angle(est.stain_matrix[i], he[i]) for i in range(2)) < 0.5
    # measured 0.6 % (H) and 3.9 % (E): torchstain adds 1 to the codes, which lowers the OD
    # of the darkest pixels, those the 99th percentile is taken at
    np.testing.assert_allclose(est.max_concentrations, np.asarray(peer.maxCRef), rtol=0.05)


@pytest.mark.parametrize(
    "colour",
    [(0, 0, 0), (200, 120, 170), (60, 60, 60)],
    ids=["black", "flat-pink", "grey"],
)
def test_a_tile_of_one_colour_is_refused(colour: tuple[int, int, int]) -> None:
    """Before, macenko_stains returned two identical vectors (and normalisation failed
    later on a singular matrix)."""
    img8 = np.broadcast_to(np.asarray(colour, dtype=np.uint8), (32, 32, 3)).copy()
    with pytest.raises(DegenerateConfigurationError, match=r"Macenko: .* one colour"):
        macenko_stains(img8, mask=None)
    with pytest.raises(DegenerateConfigurationError, match=r"Vahadane: .* one colour"):
        vahadane_stains(img8, mask=None)
    if colour != (200, 120, 170):  # black and dark grey: the tissue mask's dark rule
        with pytest.raises(DegenerateConfigurationError, match=r"tissue mask left out"):
            macenko_stains(img8)


def test_chunked_glass_estimate_and_maxima_match_in_memory() -> None:
    da = pytest.importorskip("dask.array")
    img8 = _tile(6, glass=0.4, noise=3.0)
    lazy = da.from_array(img8, chunks=(64, 96, 3))
    a, b = estimate_background(img8), estimate_background(lazy)
    np.testing.assert_allclose(b.i0, a.i0, atol=1e-12)
    assert b.glass_fraction == pytest.approx(a.glass_fraction)
    np.testing.assert_allclose(
        macenko_stains(lazy).max_concentrations,
        macenko_stains(img8).max_concentrations,
        atol=1e-9,
    )
