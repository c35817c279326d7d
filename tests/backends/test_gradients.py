"""PyTorch gradients through projection, distortion, colour conversion and ΔE (issue 9).

``torch.autograd.gradcheck`` compares the analytic Jacobian with central finite differences
in float64 (its default eps 1e-6, atol 1e-5, rtol 1e-3). Inputs stay away from the points
where the functions are not differentiable: sRGB's piecewise threshold (0.04045), HSV's
hue at ties of the largest channel and at grey, CIEDE2000's hue branch (|Δh'| = 180°,
C' = 0), points behind the camera.
"""

from __future__ import annotations

import numpy as np
import pytest

from imageform import color as c
from imageform import geometry as g
from imageform.sensor import demosaic

torch = pytest.importorskip("torch")
gradcheck = torch.autograd.gradcheck

K = np.array([[500.0, 2.0, 320.0], [0.0, 510.0, 240.0], [0.0, 0.0, 1.0]])
T = np.array([0.2, -0.1, 4.0])


def _t(a: object) -> object:
    return torch.tensor(np.asarray(a, dtype=np.float64), dtype=torch.float64, requires_grad=True)


def _rgb(seed: int, n: int = 6) -> np.ndarray:
    """Colours with three well separated channels in (0.1, 0.9): no ties, no threshold."""
    rng = np.random.default_rng(seed)
    base = np.sort(rng.uniform(0.1, 0.9, size=(n, 3)), axis=-1)
    base[:, 1] = 0.5 * (base[:, 0] + base[:, 2])  # middle channel away from both
    base[:, 2] = np.maximum(base[:, 2], base[:, 0] + 0.2)
    return np.stack([rng.permutation(row) for row in base])


def test_projection_points_intrinsics_rotation() -> None:
    X = _t([[0.3, -0.2, 2.0], [0.1, 0.4, 3.0]])
    k = _t([500.0, 510.0, 320.0, 240.0, 2.0])  # fx, fy, cx, cy, skew (K keeps its zeros)
    rvec = _t([0.1, -0.2, 0.3])

    def f(pts: object, kk: object, r: object) -> object:
        Km = g.intrinsic_matrix(kk[0], kk[1], kk[2], kk[3], kk[4])  # type: ignore[index]
        return g.project_points(pts, Km, g.rvec_to_matrix(r), torch.tensor(T)).uv

    assert gradcheck(f, (X, k, rvec))


@pytest.mark.parametrize(
    "model",
    [
        g.BrownConrady(k1=-0.2, k2=0.05, p1=1e-3, p2=-2e-3, k3=0.01),
        g.KannalaBrandt(k1=0.05, k2=-0.01, k3=0.002),
    ],
    ids=["brown_conrady", "kannala_brandt"],
)
def test_distortion(model: object) -> None:
    xy = _t([[0.1, -0.2], [0.3, 0.25], [-0.4, 0.05]])
    assert gradcheck(model.distort, (xy,))  # type: ignore[attr-defined]
    X = _t([[0.3, -0.2, 2.0], [0.1, 0.4, 3.0]])

    def f(pts: object) -> object:
        return g.project_points_distorted(pts, K, np.eye(3), T, model)[0]

    assert gradcheck(f, (X,))


def test_srgb_to_lab_and_back() -> None:
    rgb = _t(_rgb(1))
    assert gradcheck(lambda x: c.convert(x, "srgb", "lab"), (rgb,))
    lab = _t(c.convert(_rgb(2), "srgb", "lab"))
    assert gradcheck(lambda x: c.convert(x, "lab", "srgb"), (lab,))


def test_srgb_to_hsv_away_from_singularities() -> None:
    assert gradcheck(c.srgb_to_hsv, (_t(_rgb(3)),))


def test_delta_e_cie76_and_ciede2000() -> None:
    lab1 = c.convert(_rgb(4), "srgb", "lab")
    lab2 = c.convert(_rgb(5), "srgb", "lab")
    h1 = np.degrees(np.arctan2(lab1[:, 2], lab1[:, 1]))
    h2 = np.degrees(np.arctan2(lab2[:, 2], lab2[:, 1]))
    dh = np.abs((h2 - h1 + 180.0) % 360.0 - 180.0)
    assert np.all(np.abs(dh - 180.0) > 5.0) and np.all(np.hypot(lab1[:, 1], lab1[:, 2]) > 1.0)
    a, b = _t(lab1), _t(lab2)
    assert gradcheck(c.delta_e_cie76, (a, b))
    assert gradcheck(c.delta_e_ciede2000, (a, b))


@pytest.mark.parametrize("method", ["bilinear", "malvar"])
def test_demosaic_generic_path(method: str) -> None:
    raw = _t(np.random.default_rng(6).uniform(0, 1, (6, 8)))
    assert gradcheck(lambda r: demosaic(r, "GRBG", method), (raw,))


def test_undistort_image_wrt_image() -> None:
    img = _t(np.random.default_rng(7).uniform(0, 1, (6, 7, 2)))
    Ks = np.array([[8.0, 0.0, 3.0], [0.0, 8.0, 2.5], [0.0, 0.0, 1.0]])
    assert gradcheck(lambda im: g.undistort_image(im, Ks, g.BrownConrady(k1=-0.3)), (img,))
