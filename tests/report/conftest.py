"""A small synthetic SimulationResult that exercises every field, with known answers.

- The output image holds 24 flat ColorChecker patches; the ground truth equals the measured
  CIELAB except patch 0, whose truth is 2 L* units lighter at L̄ = 50: then
  ΔE00 = ΔL'/S_L = 2.0 exactly (S_L = 1 at L̄ = 50; Sharma, Wu & Dalal 2005, eq. 10-16).
- The white-balanced linear stage has, in every patch window, a ±δ checker pattern on the
  level μ: SNR = 20 log10(μ/δ) dB exactly.
- The vanishing point is detected 3 px right and 4 px below the truth: error 5 px.
- The photon-transfer data are ideal: σ² = K μ with K = 0.5 DN/e⁻ below saturation.
- The world is y-down (``world_up = (0, -1, 0)``, not the simulator's z-up): the camera looks
  along +z from above the ground y = 0.5; the report's top view must follow ``world_up``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from imageform.geometry import Camera
from imageform.sensor.emva import PhotonTransferData
from imageform.simulate.result import (
    ColorCheckerTruth,
    SceneQuad,
    SimulationResult,
    Stage,
    VanishingTruth,
)

W, H = 192, 128
PATCH_CENTRES = np.array(
    [[30.0 + 26.0 * (i % 6), 30.0 + 22.0 * (i // 6)] for i in range(24)]
)  # 6 x 4 grid, pixels
RADIUS = 4.0
SNR_MU, SNR_DELTA = 0.4, 0.01  # 20 log10(40) = 32.041 dB
GAIN = 0.5  # DN/e-
TRUE_VP = np.array([120.0, 40.0, 1.0])
DETECTED_VP = np.array([123.0, 44.0, 1.0])
HORIZON = np.array([0.0, 1.0, -40.0])  # v = 40
WORLD_UP = (0.0, -1.0, 0.0)  # this synthetic world is y-down (the camera frame's convention)


def patch_linear_rgb() -> np.ndarray:
    """24 distinct linear sRGB colours in (0, 1); patch 0 neutral at L* = 49."""
    from imageform.color.cielab import lab_to_xyz
    from imageform.color.rgb_spaces import xyz_to_linear_srgb

    rng = np.random.default_rng(7)
    rgb = rng.uniform(0.05, 0.85, size=(24, 3))
    rgb[0] = np.asarray(xyz_to_linear_srgb(lab_to_xyz([49.0, 0.0, 0.0], white="D65")))
    return rgb


def _paint(shape: tuple[int, int], colours: np.ndarray, background: float) -> np.ndarray:
    img = np.full((*shape, 3), background)
    for (u, v), c in zip(PATCH_CENTRES, colours, strict=True):
        img[int(v) - 8 : int(v) + 9, int(u) - 10 : int(u) + 11] = c
    return img


def _ptc() -> PhotonTransferData:
    t = np.linspace(0.0, 10e-3, 12)
    photons = t * 2.0e6
    electrons = 0.6 * photons
    cap = 7000.0  # full well
    sat = np.minimum(electrons, cap)
    var = GAIN**2 * sat + 4.0
    var[electrons > cap] = 4.0 + GAIN**2 * cap * np.linspace(0.5, 0.1, int((electrons > cap).sum()))
    return PhotonTransferData(
        exposure_times=t,
        photons=photons,
        mean_dn=10.0 + GAIN * sat,
        var_dn=var,
        dark_mean_dn=np.full(12, 10.0),
        dark_var_dn=np.full(12, 4.0),
    )


def make_result(*, full: bool = True, width: int = W, height: int = H) -> SimulationResult:
    """The synthetic result; ``full=False`` leaves out the ColorChecker, rails, photon
    transfer, quads and patch chromaticities."""
    from imageform.color.cielab import xyz_to_lab
    from imageform.color.rgb_spaces import linear_srgb_to_xyz
    from imageform.color.transfer import linear_to_srgb

    sy, sx = height / H, width / W
    rgb = patch_linear_rgb()
    lin = _paint((H, W), rgb, 0.18)
    if (height, width) != (H, W):
        rows = (np.arange(height) / sy).astype(int)
        cols = (np.arange(width) / sx).astype(int)
        lin = lin[rows][:, cols]
    radiance = lin * 3.5  # arbitrary radiometric scale
    raw = np.round(np.clip(lin.mean(axis=-1), 0, 1) * 4095).astype(np.uint16)
    wb = lin.copy()
    checker = np.where((np.add.outer(np.arange(height), np.arange(width)) % 2) == 0, 1.0, -1.0)
    for u, v in PATCH_CENTRES:
        r0, c0 = round(v * sy) - 4, round(u * sx) - 4
        wb[r0 : r0 + 9, c0 : c0 + 9] = SNR_MU + SNR_DELTA * checker[r0 : r0 + 9, c0 : c0 + 9, None]
    out = np.asarray(linear_to_srgb(np.clip(lin, 0, 1)))
    stages = (
        Stage(
            "radiance", "Scene radiance", "L = E(λ) ρ(λ), integrated", radiance, "linear", None, 0.5
        ),
        Stage(
            "raw", "Raw image", "Noise, mosaic and ADC: DN = round(K e)", raw, "raw", 4095.0, 0.25
        ),
        Stage("demosaiced", "Demosaiced", "Bilinear demosaicing", lin, "linear", None, 0.125),
        Stage("white_balanced", "White balanced", "von Kries gains", wb, "linear", None, 0.0625),
        Stage("output", "Output (sRGB)", "CCM, then the sRGB encoding", out, "srgb", None, 0.0625),
    )
    K = np.array([[200.0 * sx, 0, (width - 1) / 2], [0, 200.0 * sy, (height - 1) / 2], [0, 0, 1]])
    camera = Camera.look_at(K, [0.5, -1.0, -1.0], [0.5, 0.0, 3.0], image_size=(width, height))
    if not full:
        return SimulationResult(
            stages=stages, camera=camera, image_size=(width, height), world_up=WORLD_UP
        )
    lab_meas = np.asarray(xyz_to_lab(linear_srgb_to_xyz(rgb), white="D65"))
    truth = lab_meas.copy()
    truth[0, 0] = 51.0  # measured 49: ΔE00 = 2.0 at L̄ = 50
    quads = (
        SceneQuad(
            "colorchecker", np.array([[0.0, -0.5, 3], [1, -0.5, 3], [1, 0.2, 3], [0, 0.2, 3]])
        ),
        SceneQuad("ground", np.array([[-2.0, 0.5, 0.5], [2, 0.5, 0.5], [2, 0.5, 8], [-2, 0.5, 8]])),
    )
    xy = np.column_stack([np.linspace(0.25, 0.45, 24), np.linspace(0.30, 0.40, 24)])
    return SimulationResult(
        stages=stages,
        camera=camera,
        image_size=(width, height),
        quads=quads,
        colorchecker=ColorCheckerTruth(
            names=tuple(f"patch {i + 1}" for i in range(24)),
            lab_d65=truth,
            centers_uv=PATCH_CENTRES * [sx, sy],
            sample_radius_px=RADIUS,
        ),
        patch_xy={
            "before_white_balance": xy + [0.08, 0.02],
            "after_white_balance": xy,
            "after_color_correction": xy - [0.01, 0.0],
        },
        vanishing=VanishingTruth(
            TRUE_VP * [sx, sy, 1],
            HORIZON * [1, 1, sy],
            DETECTED_VP * [sx, sy, 1],
            (HORIZON + [0, 0, -4]) * [1, 1, sy],
        ),
        photon_transfer=_ptc(),
        metrics={
            "simulation_time_s": 1.0,
            "vp_error_px": 5.0,
            "per_patch": list(range(24)),
            "nan": float("nan"),
        },
        scene_name="synthetic",
        config={"scene": {"name": "synthetic"}, "camera": {"fx": 200.0}},
        world_up=WORLD_UP,
    )


@pytest.fixture(scope="session")
def sim_result() -> SimulationResult:
    """The full synthetic result (192 x 128)."""
    return make_result()


@pytest.fixture(scope="session")
def bare_result() -> SimulationResult:
    """Stages and camera only: no ColorChecker, rails, quads or photon transfer."""
    return make_result(full=False)


@pytest.fixture(scope="session")
def full_report(sim_result: SimulationResult, tmp_path_factory: pytest.TempPathFactory) -> Any:
    """The report of the full synthetic result, written once (a ReportPaths)."""
    pytest.importorskip("matplotlib")
    from imageform.report import write_report

    return write_report(sim_result, tmp_path_factory.mktemp("full") / "report")


@pytest.fixture(scope="session")
def result_factory() -> Callable[..., SimulationResult]:
    return make_result


SMALL_SCENE_EDITS = {  # the built-in scene at a quarter of the size, same field of view
    "width = 1280": "width = 320",
    "height = 720": "height = 180",
    "pixel_pitch_um = 1.75": "pixel_pitch_um = 7.0",
    "supersampling = 2": "supersampling = 1",
}


@pytest.fixture(scope="session")
def real_run(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """``imageform simulate --scene small.toml --json`` for real (no fakes): the built-in
    scene's TOML edited to 320 x 180 with the same field of view. Returns the printed JSON
    with ``"out"`` (the output folder) added."""
    pytest.importorskip("matplotlib")
    import contextlib
    import io
    import json
    from importlib.resources import files

    from imageform.cli import main

    text = files("imageform.simulate").joinpath("scenes/default.toml").read_text()
    for old, new in SMALL_SCENE_EDITS.items():
        assert old in text, old
        text = text.replace(old, new)
    root = tmp_path_factory.mktemp("e2e")
    scene = root / "small.toml"
    scene.write_text(text)
    out = root / "run"
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        rc = main(["simulate", "--scene", str(scene), "-o", str(out), "--json"])
    assert rc == 0
    data: dict[str, Any] = json.loads(buf.getvalue())
    data["out"] = out
    return data
