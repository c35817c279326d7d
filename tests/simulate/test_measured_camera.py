"""A camera file's [sensor], [optics] and [color] in the simulator (issue 18, "The loop
closes"): apply_camera_file, the MTF50 -> Gaussian conversion, the noise and colours."""

from __future__ import annotations

import math

import numpy as np
import pytest

from imageform.analysis.sfr import render_slanted_edge, slanted_edge_sfr
from imageform.geometry import Camera
from imageform.io import CameraColor, CameraFile, CameraOptics
from imageform.simulate import (
    apply_camera_file,
    gaussian_sigma_for_mtf50,
    load_scene,
    simulate,
)
from imageform.simulate.measured_sensor import MeasuredCamera
from imageform.simulate.stages import measured_color_matrix, measured_optics_blur

W, H = 96, 64
CAM = Camera([[120.0, 0, (W - 1) / 2], [0, 120.0, (H - 1) / 2], [0, 0, 1]], image_size=(W, H))


def _flat_scene(noise: bool = True):  # type: ignore[no-untyped-def]
    """A uniform grey plane filling the frame, no vignetting or blur, D65."""
    return load_scene(
        {
            "name": "flat",
            "render": {"width": W, "height": H, "supersampling": 1},
            "illuminant": {"type": "cie", "name": "D65", "illuminance_lux": 1000.0},
            "camera": {"fx_px": 120.0, "eye_m": [0.0, -0.3, 0.0], "target_m": [0.0, 0.0, 0.0]},
            "lens": {"defocus": False, "vignetting": "none", "f_number": 4.0},
            "sensor": {"noise": noise, "exposure_time_s": "auto", "auto_exposure_level": 0.4},
            "processing": {
                "white_balance": "none",
                "color_correction": "none",
                "lens_shading_correction": False,
                "demosaic": "bilinear",
            },
            "objects": [
                {
                    "type": "plane",
                    "center_m": [0.0, 0.0, 0.0],
                    "normal": [0.0, -1.0, 0.0],
                    "size_m": [2.0, 2.0],
                    "reflectance": 0.5,
                }
            ],
        }
    )


def _raw(res):  # type: ignore[no-untyped-def]
    return next(s.image for s in res.stages if s.name == "raw").astype(np.float64)


def test_mtf50_sigma_formula() -> None:
    # MTF(f) = exp(-2 pi^2 sigma^2 f^2) = 1/2  <=>  sigma = sqrt(ln 2 / (2 pi^2)) / f50
    assert gaussian_sigma_for_mtf50(0.25) == pytest.approx(
        math.sqrt(math.log(2) / (2 * math.pi**2)) / 0.25, rel=1e-12
    )
    s = gaussian_sigma_for_mtf50(0.25, supersampling=4)
    box = abs(math.sin(math.pi * 0.25) / (4 * math.sin(math.pi * 0.25 / 4)))
    assert math.exp(-2 * math.pi**2 * s**2 * 0.25**2) * box == pytest.approx(0.5, rel=1e-12)
    assert gaussian_sigma_for_mtf50(0.7, supersampling=4) == 0.0  # the pixel alone is blurrier


@pytest.mark.parametrize("mtf50", [0.15, 0.25, 0.35])
def test_mtf50_model_gives_the_file_mtf50_on_an_edge(mtf50: float) -> None:
    # an edge integrated over 4 x 4 samples per pixel (the renderer's pixels) blurred by the
    # mtf50 model: the slanted-edge MTF50 is the file's within 3 %
    step = render_slanted_edge((160, 128), angle_deg=5.0, sigma=0.0, supersampling=4)
    rgb = np.repeat(np.asarray(step, float)[..., None], 3, axis=2)
    optics = CameraOptics(model="mtf50", mtf50_cy_per_px=mtf50)
    out = measured_optics_blur(rgb, optics, pixel_pitch=2e-6, supersampling=4)
    r = slanted_edge_sfr(out[..., 1])
    assert r.mtf50[0] == pytest.approx(mtf50, rel=0.03)


def test_gaussian_zernike_and_diffraction_blur() -> None:
    step = render_slanted_edge((128, 128), angle_deg=5.0, sigma=0.0, supersampling=4)
    rgb = np.repeat(np.asarray(step, float)[..., None], 3, axis=2)
    sharp = slanted_edge_sfr(rgb[..., 1]).mtf50[0]
    g = measured_optics_blur(
        rgb,
        CameraOptics(model="gaussian", gaussian_sigma_px=1.0),
        pixel_pitch=2e-6,
        supersampling=4,
    )
    assert slanted_edge_sfr(g[..., 1]).mtf50[0] < 0.8 * sharp
    diff = measured_optics_blur(
        rgb, CameraOptics(model="diffraction", f_number=8.0), pixel_pitch=2e-6, supersampling=4
    )
    zern = measured_optics_blur(
        rgb,
        CameraOptics(model="zernike", f_number=8.0, zernike=(0, 0, 0, 0.0), wavelength_nm=550),
        pixel_pitch=2e-6,
        supersampling=4,
    )
    defocused = measured_optics_blur(
        rgb,
        CameraOptics(model="zernike", f_number=8.0, zernike=(0, 0, 0, 0.3), wavelength_nm=550),
        pixel_pitch=2e-6,
        supersampling=4,
    )
    m_diff, m_zern = (
        slanted_edge_sfr(diff[..., 1]).mtf50[0],
        slanted_edge_sfr(zern[..., 1]).mtf50[0],
    )
    # an unaberrated Zernike pupil is the diffraction PSF (point-sampled: within 5 %)
    assert m_zern == pytest.approx(m_diff, rel=0.05)
    # 0.3 waves of defocus blurs it further; light is kept
    assert slanted_edge_sfr(defocused[..., 1]).mtf50[0] < 0.8 * m_zern
    assert defocused.sum() == pytest.approx(rgb.sum(), rel=0.01)


def test_no_tables_renders_as_with_camera() -> None:
    scene = _flat_scene()
    a = simulate(apply_camera_file(scene, CameraFile(CAM)), rng=3)
    # what `imageform simulate --camera` did before the tables: the file's K at the scene's pose
    here = scene.camera
    b = simulate(scene.with_camera(Camera(CAM.K, here.R, here.t, CAM.image_size)), rng=3)
    np.testing.assert_array_equal(_raw(a), _raw(b))
    assert apply_camera_file(scene, CameraFile(CAM)).measured is None


@pytest.mark.parametrize(("gain", "read"), [(0.5, 4.0), (1.2, 12.0)])
def test_sensor_table_sets_the_noise(gain: float, read: float) -> None:
    # no PRNU, DSNU or dark current: the temporal variance of a flat green region is
    # K^2 (mu_e + sigma_r^2) + 1/12 (EMVA 1288 eq. 7; quantisation 1/12 DN^2)
    sensor = {
        "system_gain_dn_per_e": gain,
        "read_noise_e": read,
        "prnu": 0.0,
        "dsnu_e": 0.0,
        "dark_current_e_per_s": 0.0,
        "bit_depth": 14,
        "black_level_dn": 100.0,
        "full_well_e": 8000.0,
        "cfa": "GRBG",
    }
    scene = apply_camera_file(_flat_scene(), CameraFile(CAM, sensor=sensor))
    assert scene.sensor.system_gain == pytest.approx(gain, rel=1e-12)
    assert scene.sensor.read_noise == read and scene.config.sensor.cfa == "GRBG"
    raw = _raw(simulate(scene, rng=1))
    green = raw[0::2, 0::2]  # GRBG: green at (0, 0)
    mu_e = (green.mean() - 100.0) / gain
    assert mu_e == pytest.approx(0.4 * 8000.0, rel=0.05)  # auto exposure at 40 % of full well
    predicted = gain**2 * (mu_e + read**2) + 1 / 12
    assert green.var(ddof=1) == pytest.approx(predicted, rel=0.08)


def test_sensor_qe_and_sensitivities() -> None:
    cf = CameraFile(
        CAM,
        sensor={"quantum_efficiency": 0.8, "pixel_pitch_um": 2.5},
        color={"spectral_sensitivity": "nikon_d5100"},
    )
    s = apply_camera_file(_flat_scene(), cf).sensor
    assert float(np.max(s.qe_curves)) == pytest.approx(0.8)
    # the file's QE is the effective one (EMVA 1288): no fill factor on top of it
    assert s.fill_factor == 1.0
    assert float(np.max(s.quantum_efficiency(550.0))) * s.fill_factor <= 0.8 + 1e-12
    assert s.pixel_pitch == pytest.approx(2.5e-6)
    from imageform.spectral import camera_sensitivities

    nikon = camera_sensitivities("nikon_d5100")
    np.testing.assert_allclose(
        np.asarray(s.qe_curves).T, nikon.values / nikon.values.max() * 0.8, rtol=1e-12
    )
    est = CameraColor(
        sensitivity={
            "wavelengths_nm": [450, 550, 650],
            "r": [0, 0.1, 1],
            "g": [0.1, 1, 0.1],
            "b": [1, 0.1, 0],
        }
    )
    s2 = apply_camera_file(_flat_scene(), CameraFile(CAM, color=est)).sensor
    assert s2.quantum_efficiency(650.0)[0] == pytest.approx(float(np.max(s2.qe_curves)))


def test_color_table_sets_white_balance_and_matrix() -> None:
    ccm = [[1.5, -0.3, -0.2], [-0.2, 1.4, -0.2], [0.0, -0.4, 1.4]]
    scene = _flat_scene(noise=False)
    plain = simulate(scene.with_camera(CAM), rng=0)
    cf = CameraFile(CAM, color={"white_balance": [2.0, 1.0, 1.5], "ccm": ccm})
    res = simulate(apply_camera_file(scene, cf), rng=0)
    assert res.metrics["white_balance_gains"] == [2.0, 1.0, 1.5]
    np.testing.assert_allclose(res.metrics["color_correction_matrix"], np.array(ccm).T)
    a = plain.stages[-1].image[20:40, 30:60].mean(axis=(0, 1))
    b = res.stages[-1].image[20:40, 30:60].mean(axis=(0, 1))
    assert np.max(np.abs(a - b)) > 0.05  # the colours changed
    # demosaiced camera RGB x gains, then ccm @ rgb
    dem = next(s.image for s in res.stages if s.name == "demosaiced")[30, 40].astype(float)
    cc = next(s.image for s in res.stages if s.name == "color_corrected")[30, 40]
    np.testing.assert_allclose(cc, np.array(ccm) @ (dem * [2.0, 1.0, 1.5]), rtol=1e-5)


def test_ccm_to_xyz() -> None:
    # a ccm to XYZ that is sRGB's own RGB -> XYZ matrix (IEC 61966-2-1) is the identity to
    # linear sRGB
    m = [[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]]
    M = measured_color_matrix(CameraColor(ccm=m, ccm_to="xyz"))
    assert M is not None
    np.testing.assert_allclose(M, np.eye(3), atol=2e-3)
    assert measured_color_matrix(CameraColor(white_balance=(1.0, 1.0, 1.0))) is None


def test_optics_table_replaces_the_lens_blur_and_survives_views() -> None:
    cf = CameraFile(CAM, optics={"model": "gaussian", "gaussian_sigma_px": 1.5})
    base = _flat_scene().with_changes(views=[{"eye_m": [0.01, -0.3, 0.0]}])
    scene = apply_camera_file(base.with_changes(lens={"defocus": True}), cf)
    assert scene.config.lens.defocus is False and scene.config.lens.diffraction is False
    assert isinstance(scene.measured, MeasuredCamera) and scene.measured.optics == cf.optics
    assert scene.view(0).measured is scene.measured
    assert scene.resized(48).measured is scene.measured


def test_refusals() -> None:
    with pytest.raises(TypeError, match=r"camera_file as an imageform\.io\.CameraFile"):
        apply_camera_file(_flat_scene(), CAM)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="scene as a Scene"):
        apply_camera_file("scene.toml", CameraFile(CAM))  # type: ignore[arg-type]
    bare = Camera([[120.0, 0, 10], [0, 120.0, 10], [0, 0, 1]])
    with pytest.raises(Exception, match=r"no image size"):
        apply_camera_file(_flat_scene(), CameraFile(bare))
    with pytest.raises(Exception, match=r"sensor.bit_depth: the simulator's ADC has at most 16"):
        apply_camera_file(_flat_scene(), CameraFile(CAM, sensor={"bit_depth": 20}))
    with pytest.raises(TypeError, match="measured as a MeasuredCamera"):
        _flat_scene().with_measured({"sensor": None})


def test_zernike_zones_field_dependent_blur() -> None:
    """[optics] zernike_zones: a uniform grid blurs as the one-pupil model; a grid whose
    right column has coma blurs the right side more than the left, and the zone weights
    sum to 1 at every pixel."""
    from imageform.simulate.stages import _zone_weights, measured_optics_blur

    for n, z in ((64, 1), (64, 3), (101, 4)):
        w = _zone_weights(n, z)
        np.testing.assert_allclose(w.sum(axis=0), 1.0, atol=1e-12)
        assert (w >= 0).all()
    rng = np.random.default_rng(1)
    img = rng.random((48, 64, 3))
    base = [0.0, 0.0, 0.0, 0.1]
    one = CameraOptics(model="zernike", f_number=4.0, wavelength_nm=550.0, zernike=base)
    grid = CameraOptics(
        model="zernike", f_number=4.0, wavelength_nm=550.0, zernike_zones=[[base, base]] * 2
    )
    a = measured_optics_blur(img, one, pixel_pitch=2e-6, supersampling=1)
    b = measured_optics_blur(img, grid, pixel_pitch=2e-6, supersampling=1)
    np.testing.assert_allclose(a, b, atol=1e-12)
    coma = [0.0, 0.0, 0.0, 0.1, 0.0, 0.0, 0.0, 0.8]  # Noll 8: coma, 0.8 waves
    field = CameraOptics(
        model="zernike", f_number=4.0, wavelength_nm=550.0, zernike_zones=[[base, coma]] * 2
    )
    c = measured_optics_blur(img, field, pixel_pitch=2e-6, supersampling=1)
    left = np.abs(c[:, :16] - a[:, :16]).max()
    right = np.abs(c[:, -16:] - a[:, -16:]).max()
    assert left < 1e-9 < 0.01 < right  # the left quarter is all zone 0's: unchanged


def test_zernike_zones_checked() -> None:
    from imageform.errors import ImageformError

    z = {"model": "zernike", "f_number": 4.0, "wavelength_nm": 550.0}
    with pytest.raises(ImageformError, match="zernike_zones"):
        CameraOptics(**z, zernike_zones=[[[0.0], [0.1]], [[0.0]]])  # ragged rows
    with pytest.raises(ImageformError, match="zernike_zones"):
        CameraOptics(**z, zernike_zones=[[]])
    with pytest.raises(ImageformError, match="zernike"):
        CameraOptics(**z)  # neither zernike nor zernike_zones
