"""Cross-checks against kornia, the GPU peer (PyTorch tensors in, PyTorch tensors out).

Where the definitions match the numbers agree to rounding; where they don't, the test says
why and bounds the difference:

- ``kornia.color.rgb_to_lab`` uses OpenCV's six-digit sRGB→XYZ matrix, the white
  (0.95047, 1, 1.08883) and the rounded CIE constants 0.008856 / 7.787 of the f(t) knee;
  imageform derives the matrix from the primaries and uses the exact (6/29)³ and 841/108.
- ``kornia.geometry.camera.project_points`` divides by z whatever its sign: points behind the
  camera come back mirrored into the image. imageform returns NaN with ``valid = False``.
- ``kornia.color.raw_to_rgb`` is bilinear demosaicing like imageform's ``"bilinear"``, with
  the same border handling: the same numbers everywhere, once the pattern names are mapped.
"""

from __future__ import annotations

import numpy as np
import pytest

from imageform.color import convert, delta_e
from imageform.geometry import project_points
from imageform.sensor import demosaic

torch = pytest.importorskip("torch")
kornia = pytest.importorskip("kornia")


def _rand(shape: tuple[int, ...], dtype: object, seed: int) -> object:
    g = torch.Generator().manual_seed(seed)
    return torch.rand(shape, generator=g, dtype=dtype)


@pytest.mark.parametrize("dtype", ["float32", "float64"])
def test_srgb_to_lab_matches_kornia_within_its_rounded_constants(dtype: str) -> None:
    dt = getattr(torch, dtype)
    rgb = _rand((64, 48, 3), dt, 1)
    ours = convert(rgb, "srgb", "lab")
    theirs = kornia.color.rgb_to_lab(rgb.permute(2, 0, 1))
    theirs = theirs.permute(1, 2, 0)
    assert isinstance(ours, torch.Tensor) and ours.dtype == dt
    diff = (ours - theirs).abs().amax()
    # OpenCV's rounded matrix (entries to 1e-6, row sums off the white by ~1e-5) moves Lab by
    # up to ~0.02; far below a just-noticeable difference.
    assert float(diff) < 0.03
    de = delta_e(ours.double().numpy(), theirs.double().numpy(), method="ciede2000")
    assert float(np.max(de)) < 0.02
    # same definition, same numbers: kornia's matrix through imageform's Lab with its white
    m = np.array(
        [
            [0.412453, 0.357580, 0.180423],
            [0.212671, 0.715160, 0.072169],
            [0.019334, 0.119193, 0.950227],
        ]
    )
    lin = convert(rgb.double().numpy(), "srgb", "linear_srgb")
    white_k = (0.95047, 1.0, 1.08883)
    lab_k = convert(lin @ m.T, "xyz", "lab", white=white_k)
    # above the knee f(t) = t^(1/3) in both: the same numbers; below it kornia's slope 7.787
    # (CIE's exact 841/108 = 7.78704) moves a* by up to 500 x 3.7e-5 x 0.0089 = 1.65e-4
    above = (lin @ m.T / np.array(white_k) > 0.0089).all(axis=-1)
    assert 0.5 < above.mean() < 1.0
    tol = 2e-4 if dtype == "float32" else 1e-9
    theirs64 = theirs.double().numpy()
    np.testing.assert_allclose(lab_k[above], theirs64[above], atol=tol)
    np.testing.assert_allclose(lab_k[~above], theirs64[~above], atol=max(tol, 1.7e-4))


@pytest.mark.parametrize("dtype", ["float32", "float64"])
def test_projection_matches_kornia_in_front_and_refuses_points_behind(dtype: str) -> None:
    dt = getattr(torch, dtype)
    X = _rand((5000, 3), dt, 2) * 4 - 2
    X[:, 2] += 3.0  # z in [1, 5]: in front
    K = torch.tensor([[800.0, 0.0, 640.0], [0.0, 790.0, 360.0], [0.0, 0.0, 1.0]], dtype=dt)
    uv, valid = project_points(X, K)
    theirs = kornia.geometry.camera.project_points(X, K)
    assert bool(valid.all())
    tol = 1e-3 if dtype == "float32" else 1e-9  # px; coordinates up to ~2000 px
    torch.testing.assert_close(uv, theirs, atol=tol, rtol=0)

    behind = torch.tensor([[0.5, -0.2, -2.0]], dtype=dt)
    uv_b, valid_b = project_points(behind, K)
    mirrored = kornia.geometry.camera.project_points(behind, K)
    assert not bool(valid_b[0]) and bool(torch.isnan(uv_b).all())
    assert bool(torch.isfinite(mirrored).all())  # kornia projects it as if it were in front


# imageform's pattern (the top-left 2x2 read row by row) -> kornia's CFA name (kornia names
# the 2x2 block starting at pixel (1, 1)); every other pairing differs by ~0.9.
_KORNIA_CFA = {"RGGB": "BG", "BGGR": "RG", "GRBG": "GB", "GBRG": "GR"}


@pytest.mark.parametrize("pattern", sorted(_KORNIA_CFA))
def test_bilinear_demosaic_matches_kornia(pattern: str) -> None:
    raw = _rand((40, 56), torch.float64, 3)
    ours = demosaic(raw, pattern, "bilinear")
    theirs = kornia.color.raw_to_rgb(
        raw[None, None], getattr(kornia.color.CFA, _KORNIA_CFA[pattern])
    )
    theirs = theirs[0].permute(1, 2, 0)
    assert isinstance(ours, torch.Tensor) and ours.shape == (40, 56, 3)
    torch.testing.assert_close(ours, theirs, atol=1e-12, rtol=0)  # borders included


def test_lab_gradients_match_kornia_within_their_constants() -> None:
    rgb = _rand((8, 8, 3), torch.float64, 4).requires_grad_(True)
    convert(rgb, "srgb", "lab").sum().backward()
    ours = rgb.grad.clone()
    rgb.grad = None
    kornia.color.rgb_to_lab(rgb.permute(2, 0, 1)).sum().backward()
    torch.testing.assert_close(ours, rgb.grad, atol=0.05, rtol=1e-3)
