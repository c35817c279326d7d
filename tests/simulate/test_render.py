"""The renderer: kernel vs twin, the camera obscura, cos^4 vignetting, physical sanity."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from imageform.simulate import load_scene, simulate
from imageform.simulate.render import raycast_quads_numpy, render_scene
from imageform.spectral import Spectrum, colorchecker_reflectances, spectrum_to_camera_rgb


def _plane_scene(**changes: Any) -> dict[str, Any]:
    d: dict = {
        "render": {"width": 64, "height": 48, "supersampling": 1},
        "illuminant": {"type": "cie", "name": "D65", "illuminance_lux": 1000.0},
        "camera": {"fx_px": 40.0, "eye_m": [0.0, -1.0, 0.0], "target_m": [0.0, 0.0, 0.0]},
        "lens": {"defocus": False, "vignetting": "cos4", "f_number": 4.0, "focus_distance_m": 1.0},
        "sensor": {"noise": False, "exposure_time_s": 0.002},
        "processing": {"white_balance": "none", "color_correction": "none", "demosaic": "bilinear"},
        "objects": [
            {
                "type": "plane",
                "center_m": [0.0, 0.0, 0.0],
                "size_m": [20.0, 20.0],
                "reflectance": 0.5,
            }
        ],
    }
    for k, v in changes.items():
        d[k] = {**d.get(k, {}), **v} if isinstance(v, dict) else v
    return d


def test_raycast_kernel_matches_its_numpy_twin() -> None:
    from imageform._kernels.raycast import raycast_quads

    rng = np.random.default_rng(1)
    xy = rng.uniform(-1.5, 1.5, (5000, 2))
    xy[::97] = np.nan
    q = 5
    origin = rng.uniform(-1, 1, (q, 3)) + [0, 0, 3]
    e1, e2 = rng.normal(size=(q, 3)), rng.normal(size=(q, 3))
    n = np.cross(e1, e2)
    ga = np.cross(e2, n) / np.einsum("ij,ij->i", e1, np.cross(e2, n))[:, None]
    gb = np.cross(n, e1) / np.einsum("ij,ij->i", e2, np.cross(n, e1))[:, None]
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    k = raycast_quads(xy, origin, n, ga, gb)
    t = raycast_quads_numpy(xy, origin, n, ga, gb)
    np.testing.assert_array_equal(k[0], t[0])
    hit = k[0] >= 0
    assert 0.05 < hit.mean() < 0.95
    for a, b in zip(k[1:], t[1:], strict=True):
        np.testing.assert_allclose(a[hit], b[hit], rtol=0, atol=1e-12)
    assert np.all(np.isinf(k[3][~hit]))


def test_camera_obscura_inverts_the_image() -> None:
    d = _plane_scene(
        render={"supersampling": 2},
        objects=[{"type": "colorchecker", "center_m": [0.0, 0.0, 0.0], "width_m": 1.5}],
    )
    virtual = render_scene(load_scene(d)).rate
    d["camera"]["image_plane"] = "real"
    real = render_scene(load_scene(d)).rate
    # principal point at the image centre: the real image is the virtual one turned 180°
    np.testing.assert_allclose(real, virtual[::-1, ::-1], rtol=1e-9, atol=1e-9)
    assert not np.allclose(real, virtual)


def test_vignetting_follows_cos4() -> None:
    scene = load_scene(_plane_scene())
    out = render_scene(scene)
    K = np.asarray(scene.camera.K)
    v, u = np.mgrid[0:48, 0:64].astype(float)
    r2 = ((u - K[0, 2]) / K[0, 0]) ** 2 + ((v - K[1, 2]) / K[1, 1]) ** 2
    cos4 = 1.0 / (1.0 + r2) ** 2  # cos(theta) = 1 / sqrt(1 + r^2) for the ray (x, y, 1)
    # a fronto-parallel uniform Lambertian plane: irradiance falls exactly as cos^4
    centre = out.rate / cos4[..., None]
    np.testing.assert_allclose(centre, np.broadcast_to(centre[24, 32], centre.shape), rtol=1e-12)
    np.testing.assert_allclose(out.falloff, cos4, rtol=1e-12)
    ratio = out.rate[0, 0, 1] / out.rate[24, 32, 1]
    assert ratio == pytest.approx(cos4[0, 0] / cos4[24, 32], rel=1e-12)
    assert cos4[0, 0] < 0.3  # the corners are much darker (field angle ~ 44°)
    flat = render_scene(load_scene(_plane_scene(lens={"vignetting": "none"}))).rate
    np.testing.assert_allclose(flat, np.broadcast_to(flat[24, 32], flat.shape), rtol=1e-12)


@pytest.mark.parametrize("noise", [False, True])
def test_doubling_exposure_doubles_the_raw_signal(noise: bool) -> None:
    means = []
    for t in (0.01, 0.02):
        d = _plane_scene(sensor={"noise": noise, "exposure_time_s": t}, lens={"vignetting": "none"})
        scene = load_scene(d)
        raw = simulate(scene, rng=3).stage("raw").image.astype(float)
        s = scene.sensor
        means.append(raw.mean() - s.black_level - s.system_gain * s.dark_current * t)
    assert means[1] < 0.9 * scene.sensor.max_dn  # below saturation
    assert means[1] / means[0] == pytest.approx(2.0, rel=0.01 if noise else 0.002)


def test_rendered_patches_match_spectral_integration() -> None:
    d = _plane_scene(
        objects=[{"type": "colorchecker", "center_m": [0.0, 0.0, 0.0], "width_m": 1.5}],
        lens={"vignetting": "none"},
        illuminant={"type": "cie", "name": "A"},
    )
    scene = load_scene(d)
    from imageform.simulate.truth import colorchecker_truth, patch_means

    truth = colorchecker_truth(scene.objects[0], scene.camera)
    rgb = patch_means(render_scene(scene).rate, truth)
    # the sensor counts photons: its energy sensitivity is QE(lambda) * lambda
    s = scene.sensor
    wl = np.asarray(s.qe_wavelengths)
    sens = Spectrum(wl, (np.asarray(s.qe_curves) * wl).T)
    ref = spectrum_to_camera_rgb(colorchecker_reflectances(), illuminant="A", camera=sens)
    ratio = (rgb / rgb[:, 1:2]) / (ref / ref[:, 1:2])
    np.testing.assert_allclose(ratio, 1.0, rtol=0.01)
    scale = rgb[:, 1] / ref[:, 1]
    np.testing.assert_allclose(scale, scale.mean(), rtol=0.01)


def test_distortion_bends_straight_lines_barrel() -> None:
    base = _plane_scene(
        objects=[
            {
                "type": "checkerboard",
                "center_m": [0.0, 0.0, 0.0],
                "squares": [8, 6],
                "square_size_m": 0.25,
            }
        ],
        lens={"vignetting": "none"},
        render={"supersampling": 2},
    )
    plain = render_scene(load_scene(base))
    base["camera"]["distortion"] = {"k1": -0.3}
    bent = render_scene(load_scene(base))
    # barrel distortion pulls the image towards the centre: the board looks smaller
    board = plain.rate[..., 1] > 0.5 * plain.rate[..., 1].max()
    board_b = bent.rate[..., 1] > 0.5 * bent.rate[..., 1].max()
    assert board_b.sum() < board.sum()


def test_defocus_blurs_only_out_of_focus_depths() -> None:
    board = [
        {
            "type": "checkerboard",
            "center_m": [0.0, 0.0, 0.0],
            "squares": [8, 6],
            "square_size_m": 0.2,
        }
    ]
    sharp = _plane_scene(
        objects=board,
        lens={"vignetting": "none", "defocus": True, "focus_distance_m": 1.0, "f_number": 2.0},
        camera={"focal_length_mm": 50.0, "fx_px": 40.0},
    )
    res = simulate(load_scene(sharp))
    # in focus (board at 1 m): the circle of confusion is 0, the image is unchanged
    np.testing.assert_array_equal(res.stage("optics").image, res.stage("rendered").image)
    sharp["lens"]["focus_distance_m"] = 0.3
    res = simulate(load_scene(sharp))
    a, b = res.stage("rendered").image, res.stage("optics").image
    # out of focus: the edges soften, the light is kept
    assert np.abs(np.diff(b[..., 1], axis=1)).max() < 0.8 * np.abs(np.diff(a[..., 1], axis=1)).max()
    assert b[10:-10, 10:-10].mean() == pytest.approx(a[10:-10, 10:-10].mean(), rel=0.02)


def test_lateral_chromatic_aberration_magnifies_red() -> None:
    board = [{"type": "plane", "center_m": [0.0, 0.0, 0.0], "size_m": [1.0, 1.0]}]
    d = _plane_scene(
        objects=board,
        lens={"vignetting": "none", "defocus": False, "lateral_ca": [1.05, 1.0, 0.95]},
        render={"background_reflectance": 0.0},
    )
    img = simulate(load_scene(d)).stage("optics").image
    width = (img > 0.5 * img.max(axis=(0, 1))).sum(axis=1)[24]  # the plane's width per channel
    assert width[0] > width[1] > width[2]


def test_render_twin_path_matches_kernel_path(monkeypatch: pytest.MonkeyPatch) -> None:
    from imageform.simulate import default_scene

    scene = default_scene().resized(48)
    fast = render_scene(scene)
    monkeypatch.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
    plain = render_scene(scene)
    np.testing.assert_array_equal(fast.object_index, plain.object_index)
    np.testing.assert_allclose(fast.rate, plain.rate, rtol=1e-9, atol=1e-9 * fast.rate.max())
    np.testing.assert_allclose(fast.depth, plain.depth, rtol=1e-9)
