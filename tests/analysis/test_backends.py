"""Other array libraries and invariants.

The analysis recipes compute in NumPy (scipy.ndimage, small SVDs) or lazily in Dask;
PyTorch and array-api-strict images are converted to NumPy at the boundary and NumPy
comes back (documented in imageform.analysis._arrays).
"""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from imageform.analysis import (
    fit_color_correction,
    macenko_stains,
    optical_density,
    reinhard_normalize,
    reinhard_stats,
    segment_hsv,
    synthetic_endoscopy_image,
    synthetic_stain_image,
)
from imageform.analysis.synthetic import COLORCHECKER_SRGB8

from ..helpers import to_backend


def test_other_backends_give_numpy_results(xp_name: str) -> None:
    img, _ = synthetic_endoscopy_image((64, 64), rng=0)
    ref = segment_hsv(img, (340, 40), (0.1, 1), (0.3, 1))
    got = segment_hsv(to_backend(img, xp_name), (340, 40), (0.1, 1), (0.3, 1))
    # Dask stays lazy (a dask mask, the same pixels once computed); the others give NumPy
    mask = got.mask.compute() if xp_name == "dask" else got.mask
    assert isinstance(mask, np.ndarray)
    np.testing.assert_array_equal(mask, ref.mask)
    slide, _, _ = synthetic_stain_image((48, 48), rng=0)
    s_ref = macenko_stains(slide)
    s_got = macenko_stains(to_backend(slide, xp_name))
    np.testing.assert_allclose(s_got.stain_matrix, s_ref.stain_matrix, atol=1e-12)
    ref_chart = np.asarray(COLORCHECKER_SRGB8) / 255
    corr = fit_color_correction(ref_chart, ref_chart)
    out = corr.apply(to_backend(ref_chart[None], xp_name))
    np.testing.assert_allclose(out[0], ref_chart, atol=1e-9)


pixels = arrays(np.float64, (6, 5, 3), elements=st.floats(1 / 255, 1.0))


@given(pixels)
def test_optical_density_round_trip(img: np.ndarray) -> None:
    np.testing.assert_allclose(np.exp(-optical_density(img)), img, rtol=1e-12)
    np.testing.assert_allclose(10.0 ** -optical_density(img, base="10"), img, rtol=1e-12)
    np.testing.assert_allclose(0.9 * np.exp(-optical_density(img, i0=0.9)), img, rtol=1e-12)


@given(arrays(np.float64, (6, 5, 3), elements=st.floats(0.05, 0.95)))
def test_reinhard_to_own_statistics_is_identity(img: np.ndarray) -> None:
    s = reinhard_stats(img)
    if min(s.std) < 1e-3:
        return  # a flat channel: covered by the DegenerateConfigurationError test
    np.testing.assert_allclose(reinhard_normalize(img, s), img, atol=1e-9)
