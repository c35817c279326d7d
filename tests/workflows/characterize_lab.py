"""A lab set photographed by a known camera X, made with imageform.simulate's pieces, for the
closed loop of ``imageform characterize`` (issue 18): checkerboard views, a slanted edge, a
ColorChecker (raw DNG + the camera's developed PNG) and EMVA 1288 flat/dark stacks.

Camera X: 640 x 480, fx 560, fy 555, cx 322, cy 236, Brown-Conrady k1 -0.18, k2 0.03; a
Gaussian lens PSF of sigma 0.9 px; the simulator's CMOS preset (K 0.3276 DN/e-, read noise
6 e-, 12 bits, RGGB, its colour QE curves); its processing: white balance on the chart's
greys, a 3x3 colour matrix fitted to the chart's D65 reference, sRGB output.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

FX, FY, CX, CY = 560.0, 555.0, 322.0, 236.0
K1, K2 = -0.18, 0.03
SIZE = (640, 480)
SIGMA = 0.9  # px, the lens's Gaussian PSF
EDGE_S = 4  # rays per pixel side of the edge render (its pixel box: the S-point mean)
CFA = "RGGB"
#: Checkerboard views: eye, up, target (metres) of a 9x6 board (20 mm squares): six with
#: the board in different parts of the frame (the distortion seen out to the corners), four
#: turned 30-35 deg (the focal length): fx within 0.05 %, k1 within 1 % (measured).
VIEWS = (
    ((0.0, -0.30, 0.0), (0.0, 0.0, 1.0), (0.0, 0.0, 0.0)),
    ((0.12, -0.28, 0.05), (0.0, 0.0, 1.0), (0.07, 0.0, 0.05)),
    ((-0.12, -0.28, -0.05), (0.1, 0.0, 1.0), (-0.07, 0.0, -0.05)),
    ((0.05, -0.27, 0.14), (0.0, 0.0, 1.0), (-0.07, 0.0, 0.05)),
    ((-0.08, -0.28, -0.12), (-0.15, 0.0, 1.0), (0.03, 0.0, -0.02)),
    ((0.15, -0.25, -0.08), (0.0, 0.0, 1.0), (-0.05, 0.0, 0.06)),
    ((0.1721, -0.2457, 0.0), (0.0, 0.0, 1.0), (0.0, 0.0, 0.0)),
    ((-0.1721, -0.2457, 0.0), (0.0, 0.0, 1.0), (0.0, 0.0, 0.0)),
    ((0.0, -0.2598, 0.15), (0.0, 0.0, 1.0), (0.0, 0.0, 0.0)),
    ((0.0, -0.2598, -0.15), (0.0, 0.0, 1.0), (0.0, 0.0, 0.0)),
)


def _camera(eye: Any, target: Any, up: Any = (0.0, 0.0, 1.0), distortion: bool = True) -> dict:
    return {
        "fx_px": FX,
        "fy_px": FY,
        "cx_px": CX,
        "cy_px": CY,
        "eye_m": list(eye),
        "target_m": list(target),
        "up": list(up),
        "distortion": {"k1": K1, "k2": K2} if distortion else {},
    }


def _scene(name: str, camera: dict, objects: list, S: int, light: str = "D65") -> dict:
    return {
        "name": name,
        "render": {
            "width": SIZE[0],
            "height": SIZE[1],
            "supersampling": S,
            "background_reflectance": 0.3,
        },
        "illuminant": {"type": "cie", "name": light, "illuminance_lux": 1000.0},
        "camera": camera,
        "lens": {"defocus": False, "vignetting": "none", "f_number": 4.0},
        "sensor": {"preset": "cmos", "cfa": CFA, "noise": True},
        "processing": {
            "demosaic": "malvar",
            "white_balance": "none",
            "color_correction": "none",
            "lens_shading_correction": False,
        },
        "objects": objects,
    }


def checkerboard_scene(eye: Any, up: Any, target: Any, S: int = 2) -> dict:
    board = {
        "type": "checkerboard",
        "center_m": [0.0, 0.0, 0.0],
        "normal": [0.0, -1.0, 0.0],
        "squares": [10, 7],
        "square_size_m": 0.02,
    }
    return _scene("checkerboard view", _camera(eye, target, up), [board], S)


def edge_scene() -> dict:
    """A dark square (reflectance 0.1) turned 5 deg on a light background (0.8)."""
    a = math.radians(5.0)
    square = {
        "type": "plane",
        "name": "dark square",
        "center_m": [0.0, 0.0, 0.0],
        "normal": [0.0, -1.0, 0.0],
        "up": [math.sin(a), 0.0, math.cos(a)],
        "size_m": [0.08, 0.08],
        "reflectance": 0.1,
    }
    d = _scene("slanted edge", _camera((0.0, -0.3, 0.0), (0.0, 0.0, 0.0)), [square], EDGE_S)
    d["render"]["background_reflectance"] = 0.8
    return d


def chart_scene(S: int = 2) -> dict:
    chart = {"type": "colorchecker", "center_m": [0.0, 0.0, 0.0], "width_m": 0.20}
    return _scene("colorchecker", _camera((0.0, -0.3, 0.0), (0.0, 0.0, 0.0)), [chart], S)


@dataclass(frozen=True)
class Truth:
    """What camera X is."""

    gain: float
    read_noise: float
    sigma_px: float
    wb: np.ndarray
    ccm: np.ndarray
    sensor: Any

    def mtf50(self, angle_deg: float) -> float:
        """The system MTF50 of the edge: the Gaussian's MTF times the S-point pixel box
        along the edge normal."""
        from imageform.analysis import mtf_crossing

        f = np.linspace(0.0, 1.0, 4001)
        t = math.radians(angle_deg)
        mtf = np.exp(-2 * np.pi**2 * self.sigma_px**2 * f**2)
        for x in (f * math.cos(t), f * math.sin(t)):
            mtf = mtf * _sub_box(x, EDGE_S)
        return mtf_crossing(f, mtf, 0.5)


def _sub_box(x: np.ndarray, S: int) -> np.ndarray:
    out = np.ones_like(x)
    nz = np.abs(x) > 1e-12
    out[nz] = np.sin(np.pi * x[nz]) / (S * np.sin(np.pi * x[nz] / S))
    return np.abs(out)


def raw_capture(scene_dict: dict, sigma: float, rng: int, sensor: Any = None) -> tuple[Any, Any]:
    """(scene, raw mosaic uint16) of a scene rendered, blurred by the Gaussian PSF and
    captured by the sensor (``sensor`` replaces the scene's)."""
    from scipy.ndimage import gaussian_filter

    from imageform.simulate import load_scene
    from imageform.simulate.render import render_scene
    from imageform.simulate.stages import capture_raw, exposure_time

    scene = load_scene(scene_dict)
    if sensor is not None:
        scene = replace(scene, sensor=sensor)
    rate = render_scene(scene).rate
    if sigma > 0:
        rate = np.stack(
            [gaussian_filter(rate[..., c], sigma, mode="nearest", truncate=5.0) for c in range(3)],
            axis=-1,
        )
    t = exposure_time(rate, scene.config.sensor, scene.sensor)
    raw = capture_raw(rate * t, scene.sensor, scene.config.sensor, t, np.random.default_rng(rng))
    return scene, raw


def chart_patches(scene: Any, raw: np.ndarray) -> np.ndarray:
    """Linear camera RGB of the 24 patches (black subtracted, white 1) from the raw, at the
    chart's true centres (half-size superpixels)."""
    from imageform.simulate.truth import colorchecker_truth

    s = scene.sensor
    norm = (raw.astype(float) - s.black_level) / (s.max_dn - s.black_level)
    h, w = norm.shape
    sp = np.zeros((h // 2, w // 2, 3))
    cnt = np.zeros(3)
    for k, ch in enumerate(CFA):
        dy, dx = divmod(k, 2)
        c = "RGB".index(ch)
        sp[..., c] += norm[dy::2, dx::2]
        cnt[c] += 1
    sp /= cnt
    chart = next(o for o in scene.objects if o.kind == "colorchecker")
    truth = colorchecker_truth(chart, scene.camera)
    out = np.zeros((24, 3))
    r = max(1, int(truth.sample_radius_px / 2))
    for k, (u, v) in enumerate(truth.centers_uv):
        i, j = round(float(v) / 2 - 0.25), round(float(u) / 2 - 0.25)
        out[k] = sp[i - r : i + r + 1, j - r : j + r + 1].reshape(-1, 3).mean(axis=0)
    return out


def render_chart(
    sensor: Any, wb: np.ndarray, ccm: np.ndarray, rng: int = 5
) -> tuple[np.ndarray, Any, np.ndarray]:
    """The ColorChecker through a camera: linear output RGB of the patches (24, 3),
    clipped to [0, 1] as the encoded output is), the scene and the raw."""
    scene, raw = raw_capture(chart_scene(), SIGMA, rng, sensor)
    cam = chart_patches(scene, raw)
    return np.clip((cam * wb) @ ccm, 0.0, 1.0), scene, raw


def _reference() -> np.ndarray:
    from imageform.color import xyz_to_linear_srgb
    from imageform.spectral import colorchecker_reflectances, spectrum_to_xyz

    return np.asarray(
        xyz_to_linear_srgb(spectrum_to_xyz(colorchecker_reflectances(), illuminant="D65"))
    )


def develop(raw: np.ndarray, sensor: Any, wb: Any, ccm: Any, bits: int = 8) -> np.ndarray:
    """Camera X's processing: black level off, bilinear demosaicing, white balance, colour
    matrix, sRGB encoding, ``bits``-bit integers."""
    from imageform.color import linear_to_srgb
    from imageform.sensor.demosaic import demosaic

    norm = (raw.astype(float) - sensor.black_level) / (sensor.max_dn - sensor.black_level)
    rgb = np.asarray(demosaic(np.clip(norm, 0, 1), CFA, method="bilinear"))
    out = np.asarray(linear_to_srgb(np.clip((rgb * wb) @ ccm, 0.0, 1.0)))
    top = 2**bits - 1
    return np.round(out * top).astype(np.uint8 if bits == 8 else np.uint16)


def make_lab_set(
    root: Path, *, views: int = 10, flats_shape: tuple[int, int] = (128, 128)
) -> Truth:
    """Write the lab set of camera X under ``root``; returns the truth."""
    from imageform.io import write_dng, write_image
    from imageform.sensor import simulate_emva_frames

    root.mkdir(parents=True, exist_ok=True)
    # sharpness: the raw of a slanted edge
    (root / "edge").mkdir()
    scene, raw = raw_capture(edge_scene(), SIGMA, 1)
    sensor = scene.sensor
    xyz_to_cam = np.eye(3)
    write_dng(
        root / "edge" / "edge.dng",
        raw,
        cfa_pattern=CFA,
        black_level=sensor.black_level,
        white_level=float(sensor.max_dn),
        color_matrix=xyz_to_cam,
    )
    # colour: the raw of the chart and the camera's own developed photograph
    (root / "colorchecker").mkdir()
    scene, raw = raw_capture(chart_scene(), SIGMA, 2)
    cam = chart_patches(scene, raw)
    greys = [18, 19, 20, 21, 22]
    wb = np.mean(cam[greys, 1:2] / cam[greys], axis=0)
    ref = _reference()
    ccm, *_ = np.linalg.lstsq(cam * wb, ref * (cam[19, 1] * wb[1] / ref[19, 1]), rcond=None)
    write_dng(
        root / "colorchecker" / "chart.dng",
        raw,
        cfa_pattern=CFA,
        black_level=sensor.black_level,
        white_level=float(sensor.max_dn),
        color_matrix=xyz_to_cam,
        as_shot_neutral=1.0 / wb,
    )
    write_image(root / "colorchecker" / "chart.png", develop(raw, sensor, wb, ccm, bits=16))
    # geometry: views of a checkerboard through the same optics, sensor and processing
    (root / "checkerboard").mkdir()
    for i, (eye, up, target) in enumerate(VIEWS[:views]):
        _, raw = raw_capture(checkerboard_scene(eye, up, target), SIGMA, 10 + i)
        write_image(root / "checkerboard" / f"view-{i:02d}.png", develop(raw, sensor, wb, ccm))
    # noise: EMVA flats and darks of the green channel at 550 nm
    from imageform.sensor.model import photons_per_pixel

    irr = 0.05
    per_s = float(photons_per_pixel(irr, 550.0, pixel_area=sensor.pixel_area, exposure_time=1.0))
    qe = float(sensor.quantum_efficiency(550.0)[1]) * sensor.fill_factor
    t_sat = sensor.full_well / (per_s * qe)
    times = np.round(t_sat * np.geomspace(0.01, 1.3, 14), 7)
    frames = simulate_emva_frames(
        sensor,
        irradiance=irr,
        wavelength_nm=550.0,
        exposure_times=times,
        rng=3,
        shape=flats_shape,
        channel=1,
    )
    for kind, stack in (("flats", frames.flats), ("darks", frames.darks)):
        (root / kind).mkdir()
        for i, t in enumerate(times):
            for n in range(stack.shape[1]):
                write_image(root / kind / f"{kind[:-1]}_{t:.7g}_{n}.png", stack[i, n][..., None])
    (root / "lab.toml").write_text(
        '[camera]\nname = "camera X"\n\n[checkerboard]\nboard = "9x6"\nsquare = "20mm"\n\n'
        f'[colorchecker]\nilluminant = "D65"\n\n[flats]\nphotons_per_s = {per_s!r}\n'
    )
    return Truth(sensor.system_gain, sensor.read_noise, SIGMA, wb, ccm, sensor)
