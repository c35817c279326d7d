"""The steps of :func:`imageform.simulate.render_lab_set`: one function per thing a lab photographs.

The checkerboard views, the ColorChecker, the slanted edge and the EMVA 1288 stacks are each
rendered and written by one function here; :func:`truth` gathers the simulated camera's values
and :func:`write_manifest` writes ``lab.toml``. Every rendering goes through
:func:`imageform.simulate.apply_camera_file`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from imageform.errors import InvalidInputError
from imageform.io import CameraFile, write_image

#: The ``format`` of a lab set's manifest ``lab.toml``.
LAB_FORMAT = "imageform-lab"
#: Files that mark a folder as a lab set (only such a folder is replaced with ``force``).
MARKER = "lab.toml"

# Eight board poses (camera centre, world up, point looked at) for a board 0.2 m wide seen
# from 0.3 m (those of tests/simulate/scenes.py), scaled to the camera's field of view.
_VIEWS = (
    ((0.0, -0.30, 0.0), (0.0, 0.0, 1.0), (0.0, 0.0, 0.0)),
    ((0.12, -0.28, 0.05), (0.0, 0.0, 1.0), (0.07, 0.0, 0.05)),
    ((-0.12, -0.28, -0.05), (0.1, 0.0, 1.0), (-0.07, 0.0, -0.05)),
    ((0.05, -0.27, 0.14), (0.0, 0.0, 1.0), (-0.07, 0.0, 0.05)),
    ((-0.08, -0.28, -0.12), (-0.15, 0.0, 1.0), (0.03, 0.0, -0.02)),
    ((0.15, -0.25, -0.08), (0.0, 0.0, 1.0), (-0.05, 0.0, 0.06)),
    ((-0.15, -0.26, 0.10), (0.2, 0.0, 1.0), (0.06, 0.0, -0.06)),
    ((0.08, -0.33, 0.08), (-0.3, 0.0, 1.0), (0.0, 0.0, 0.0)),
    ((0.10, -0.31, -0.10), (0.1, 0.0, 1.0), (0.02, 0.0, 0.02)),
    ((-0.10, -0.32, 0.06), (-0.1, 0.0, 1.0), (-0.02, 0.0, 0.0)),
    ((0.0, -0.26, -0.14), (0.0, 0.0, 1.0), (0.0, 0.0, -0.03)),
    ((0.0, -0.29, 0.12), (0.05, 0.0, 1.0), (0.0, 0.0, 0.03)),
)
#: Most checkerboard views (each a whole rendering).
MAX_VIEWS = len(_VIEWS)


@dataclass(frozen=True)
class LabOptions:
    """The checked options of one lab set (see :func:`imageform.simulate.render_lab_set`)."""

    seed: int
    views: int
    cols: int
    rows: int
    supersampling: int
    exposures: int
    frames: int
    shape: tuple[int, int]
    angle_deg: float


@dataclass(frozen=True)
class ChartShot:
    """The ColorChecker exposure.

    Its raw file, what the camera's processing applied, where the chart and its patches are
    (pixels).
    """

    path: Path
    automatic: bool
    gains: list[float]
    matrix: np.ndarray
    centers_px: np.ndarray
    corners_px: np.ndarray


def _base_scene(size: tuple[int, int], supersampling: int, objects: list[dict[str, Any]]) -> Any:
    from imageform.simulate.scene import load_scene

    return load_scene(
        {
            "name": "lab",
            "render": {
                "width": size[0],
                "height": size[1],
                "supersampling": supersampling,
                "background_reflectance": 0.3,
            },
            "illuminant": {"type": "cie", "name": "D65", "illuminance_lux": 1000.0},
            "camera": {"fx_px": 500.0, "eye_m": [0.0, -0.3, 0.0], "target_m": [0.0, 0.0, 0.0]},
            "lens": {"defocus": False, "vignetting": "none", "f_number": 4.0},
            "processing": {
                "demosaic": "malvar",
                "white_balance": "none",
                "color_correction": "none",
                "lens_shading_correction": False,
            },
            "objects": objects,
        }
    )


def _linear16(image: np.ndarray) -> np.ndarray:
    return np.asarray(np.round(np.clip(image, 0.0, 1.0) * 65535.0), dtype=np.uint16)


def _stage(result: Any, name: str) -> np.ndarray:
    for s in result.stages:
        if s.name == name:
            return np.asarray(s.image, dtype=np.float64)
    raise InvalidInputError(f"the simulation has no stage {name!r}")  # pragma: no cover


def _lens_sigma(cf: CameraFile) -> float | None:
    """Return the Gaussian sigma (px) of the lens: 0 without ``[optics]``, None if not Gaussian."""
    if cf.optics is None:
        return 0.0
    if cf.optics.model == "gaussian" and cf.optics.gaussian_sigma_px is not None:
        return float(cf.optics.gaussian_sigma_px)
    return None


def _raw_mtf50(sigma: float, angle_deg: float, supersampling: int) -> float:
    r"""Return the true MTF50 (cy/px) of the raw mosaic across a slanted edge.

    The Gaussian lens times the renderer's pixel aperture, ``S`` rays per pixel along each
    axis averaged (the discrete box :math:`\sin(\pi x) / (S \sin(\pi x / S))`), taken along
    the edge normal at ``angle_deg``: the system MTF an e-SFR of the raw mosaic measures.
    """
    from imageform.analysis import mtf_crossing

    f = np.linspace(0.0, 1.0, 20001)
    t = math.radians(angle_deg)

    def box(x: np.ndarray) -> np.ndarray:
        out = np.ones_like(x)
        nz = np.abs(x) > 1e-12
        out[nz] = np.sin(np.pi * x[nz]) / (supersampling * np.sin(np.pi * x[nz] / supersampling))
        return np.abs(out)

    mtf = np.exp(-2.0 * np.pi**2 * sigma**2 * f**2) * box(f * math.cos(t)) * box(f * math.sin(t))
    return float(mtf_crossing(f, mtf, 0.5))


#: The simulator's automatic processing (the built-in scene's): what a camera file without a
#: fixed white balance or matrix develops with.
_AUTOMATIC = {"white_balance": "gray_world", "color_correction": "colorchecker"}


def toml_value(value: Any) -> str:
    """Return the TOML text of ``value``.

    A string, an integer, a finite float (exact repr) or a list of them.
    """
    import json

    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | np.integer):
        return str(int(value))
    if isinstance(value, list | tuple | np.ndarray):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    return repr(float(value))


def render_checkerboards(
    out: Path, cf: CameraFile, opt: LabOptions, square: float = 0.02
) -> list[Path]:
    """Render the board (``cols + 1 x rows + 1`` squares, about half the width) at each view."""
    from imageform.simulate.measured import apply_camera_file
    from imageform.simulate.pipeline import simulate

    assert cf.camera.image_size is not None
    w, h = cf.camera.image_size
    fx = float(np.asarray(cf.camera.K, dtype=np.float64)[0, 0])
    board_w = (opt.cols + 1) * square
    scale = (fx * board_w / (0.62 * w)) / 0.3  # distance for 0.3 m in the test views
    board_obj = {
        "type": "checkerboard",
        "center_m": [0.0, 0.0, 0.0],
        "normal": [0.0, -1.0, 0.0],
        "squares": [opt.cols + 1, opt.rows + 1],
        "square_size_m": square,
    }
    base = _base_scene((w, h), opt.supersampling, [board_obj])
    view_list = [
        {
            "eye_m": [scale * c for c in eye],
            "target_m": [scale * c for c in target],
            "up": list(up),
        }
        for eye, up, target in _VIEWS[: opt.views]
    ]
    scene = apply_camera_file(base.with_changes(views=view_list), cf)
    (out / "checkerboard").mkdir()
    boards = []
    for i in range(opt.views):
        res = simulate(scene.view(i), rng=opt.seed + i)
        p = out / "checkerboard" / f"view-{i + 1:02d}.png"
        write_image(p, _linear16(_stage(res, "output")))
        boards.append(p)
    return boards


def render_colorchecker(out: Path, cf: CameraFile, opt: LabOptions) -> ChartShot:
    """Render a frontal-ish ColorChecker, about 70 % of the width: its raw DNG and developed PNG.

    Without a fixed white balance or matrix in the camera file, the simulator's automatic
    processing (grey world, a matrix fitted on the chart) develops it.
    """
    from imageform.simulate.dng import write_simulated_dng
    from imageform.simulate.measured import apply_camera_file
    from imageform.simulate.pipeline import simulate

    assert cf.camera.image_size is not None
    w, h = cf.camera.image_size
    fx = float(np.asarray(cf.camera.K, dtype=np.float64)[0, 0])
    chart_w = 0.12
    dist = fx * chart_w / (0.7 * w)
    chart = {"type": "colorchecker", "center_m": [0.0, 0.0, 0.0], "width_m": chart_w}
    automatic = cf.color is None or (cf.color.white_balance is None and cf.color.ccm is None)
    cc_base = _base_scene((w, h), opt.supersampling, [chart]).with_changes(
        camera={"eye_m": [0.01 * dist, -dist, 0.01 * dist], "target_m": [0.0, 0.0, 0.0]}
    )
    if automatic:  # the camera balances what it sees (the simulator's automatic processing)
        cc_base = cc_base.with_changes(processing=_AUTOMATIC)
    cc_scene = apply_camera_file(cc_base, cf)
    res = simulate(cc_scene, rng=opt.seed + 100)
    (out / "colorchecker").mkdir()
    cc_path = write_simulated_dng(res, cc_scene, out / "colorchecker" / "chart.dng")
    write_image(out / "colorchecker" / "developed.png", _linear16(_stage(res, "output")))
    centers = res.colorchecker.centers_uv if res.colorchecker is not None else np.zeros((24, 2))
    quad = res.quads[0].corners if res.quads else np.zeros((4, 3))
    return ChartShot(
        path=cc_path,
        automatic=automatic,
        gains=[float(g) for g in res.metrics["white_balance_gains"]],
        matrix=np.asarray(res.metrics["color_correction_matrix"], dtype=np.float64),
        centers_px=np.asarray(centers, dtype=np.float64),
        corners_px=np.asarray(cc_scene.camera.project(quad).uv, dtype=np.float64),
    )


def render_edge(out: Path, cf: CameraFile, opt: LabOptions) -> tuple[Path, Any]:
    """Render a dark square on a light plane turned ``angle_deg``: the raw DNG and the scene."""
    from imageform.simulate.dng import write_simulated_dng
    from imageform.simulate.measured import apply_camera_file
    from imageform.simulate.pipeline import simulate

    assert cf.camera.image_size is not None
    w, h = cf.camera.image_size
    fx = float(np.asarray(cf.camera.K, dtype=np.float64)[0, 0])
    a = math.radians(opt.angle_deg)
    side = 0.1
    e_dist = fx * side / (0.45 * h)
    edge_objs = [
        {
            "type": "plane",
            "name": "ground",
            "center_m": [0.0, 0.01 * e_dist, 0.0],
            "normal": [0.0, -1.0, 0.0],
            "size_m": [8 * side, 8 * side],
            "reflectance": 0.8,
        },
        {
            "type": "plane",
            "name": "dark square",
            "center_m": [0.0, 0.0, 0.0],
            "normal": [0.0, -1.0, 0.0],
            "up": [math.sin(a), 0.0, math.cos(a)],
            "size_m": [side, side],
            "reflectance": 0.1,
        },
    ]
    edge_scene = apply_camera_file(
        _base_scene((w, h), opt.supersampling, edge_objs).with_changes(
            camera={"eye_m": [0.0, -e_dist, 0.0], "target_m": [0.0, 0.0, 0.0]}
        ),
        cf,
    )
    res = simulate(edge_scene, rng=opt.seed + 200)
    (out / "edge").mkdir()
    return write_simulated_dng(res, edge_scene, out / "edge" / "edge.dng"), edge_scene


def write_emva(out: Path, sensor: Any, opt: LabOptions) -> tuple[Path, np.ndarray, float]:
    """Write the EMVA 1288 stacks (green channel at 550 nm, dark to 105 % of the clip).

    Return ``emva.toml``, the exposure times and the green quantum efficiency (with the fill
    factor).
    """
    from imageform.sensor import simulate_emva_frames
    from imageform.sensor.model import photons_per_pixel

    n_exp, n_frames = opt.exposures, opt.frames
    eta = float(sensor.quantum_efficiency(550.0)[1]) * sensor.fill_factor
    per_s = float(photons_per_pixel(1.0, 550.0, pixel_area=sensor.pixel_area, exposure_time=1.0))
    clip = min(sensor.full_well, (sensor.max_dn - sensor.black_level) / sensor.system_gain)
    t_cap = 0.02
    irradiance = clip / (t_cap * per_s * eta)
    times = np.concatenate(
        [
            np.linspace(0.0, 0.75 * t_cap, n_exp - n_exp // 3, endpoint=False),
            np.linspace(0.75, 1.05, n_exp // 3) * t_cap,
        ]
    )
    frames = simulate_emva_frames(
        sensor,
        irradiance=irradiance,
        wavelength_nm=550.0,
        exposure_times=times,
        rng=opt.seed + 300,
        frames=n_frames,
        shape=opt.shape,
        channel=1,
    )
    (out / "flats").mkdir()
    (out / "darks").mkdir()
    lines = [
        "# EMVA 1288 frame stacks (imageform emva reads this folder): raw DN of the green",
        "# channel, uniform 550 nm light; photons = mean photons per pixel of the exposure.",
    ]
    for i, t in enumerate(frames.exposure_times):
        names: dict[str, list[str]] = {"flats": [], "darks": []}
        for n in range(n_frames):
            for kind, stack in (("flats", frames.flats), ("darks", frames.darks)):
                name = f"{kind}/e{i:02d}-{n}.png"
                write_image(out / name, stack[i, n])
                names[kind].append(name)
        lines += [
            "",
            "[[exposure]]",
            f"time = {toml_value(float(t))}",
            f"photons = {toml_value(float(frames.photons[i]))}",
            f"flats = {toml_value(names['flats'])}",
            f"darks = {toml_value(names['darks'])}",
        ]
    emva_path = out / "emva.toml"
    emva_path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return emva_path, times, eta


def truth(
    cf: CameraFile, edge_scene: Any, chart: ChartShot, opt: LabOptions, eta: float
) -> dict[str, Any]:
    """Return the simulated camera's values, in the camera file's units (``[truth]``)."""
    sensor = edge_scene.sensor
    K = np.asarray(cf.camera.K, dtype=np.float64)
    fp = sensor.fixed_pattern(*opt.shape)
    out: dict[str, Any] = {
        "fx": float(K[0, 0]),
        "fy": float(K[1, 1]),
        "cx": float(K[0, 2]),
        "cy": float(K[1, 2]),
        "system_gain_dn_per_e": float(sensor.system_gain),
        "read_noise_e": float(sensor.read_noise),
        "dark_current_e_per_s": float(sensor.dark_current),
        "dsnu_e": float(sensor.dsnu),
        "prnu": float(sensor.prnu),
        "dsnu_e_of_the_frames": float(fp.offset[..., 1].std(ddof=1)),
        "prnu_of_the_frames": float(fp.gain[..., 1].std(ddof=1)),
        "full_well_e": float(sensor.full_well),
        "bit_depth": int(sensor.bit_depth),
        "black_level_dn": float(sensor.black_level),
        "quantum_efficiency_green_550nm": eta,
        "quantum_efficiency": float(
            min(np.max(np.asarray(sensor.qe_curves)) * sensor.fill_factor, 1.0)
        ),
        "pixel_pitch_um": float(sensor.pixel_pitch * 1e6),
        "cfa": str(edge_scene.config.sensor.cfa),
        "f_number": float(edge_scene.config.lens.f_number),
    }
    sigma = _lens_sigma(cf)
    if sigma is not None:  # the raw mosaic's MTF: the Gaussian lens times the pixel
        out["gaussian_sigma_px"] = sigma
        out["mtf50_cy_per_px"] = _raw_mtf50(sigma, opt.angle_deg, opt.supersampling)
    elif cf.optics is not None and cf.optics.mtf50_rgb() is not None:
        out["mtf50_cy_per_px"] = [float(m) for m in cf.optics.mtf50_rgb() or ()]
    out["white_balance"] = chart.gains  # what the camera's processing applied to the chart
    out["ccm"] = [[float(x) for x in row] for row in chart.matrix.T]  # linear sRGB = ccm @ rgb
    if cf.camera.distortion is not None:
        for name in ("k1", "k2"):
            if hasattr(cf.camera.distortion, name):
                out[name] = float(getattr(cf.camera.distortion, name))
    return out


def write_manifest(
    out: Path,
    opt: LabOptions,
    values: dict[str, Any],
    boards: list[Path],
    chart: ChartShot,
    edge_path: Path,
    n_exposures: int,
    square: float = 0.02,
) -> Path:
    """Write ``lab.toml``: what is where, how it was encoded, and the ``[truth]``."""
    manifest = [
        "# imageform lab set (render_lab_set, docs/simulate.md): what a lab photographs to",
        "# characterise a camera, rendered through camera.toml (the truth).",
        f"format = {toml_value(LAB_FORMAT)}",
        "version = 1",
        'camera_file = "camera.toml"  # the truth',
        f"seed = {opt.seed}",
        "",
        "[camera]  # what the lab knows of the camera (its data sheet and settings)",
        f"cfa = {toml_value(values['cfa'])}",
        f"pixel_pitch_um = {toml_value(values['pixel_pitch_um'])}",
        f"f_number = {toml_value(values['f_number'])}",
        "",
        "[checkerboard]",
        'folder = "checkerboard"',
        f"images = {toml_value([p.relative_to(out).as_posix() for p in boards])}",
        f"inner_corners = [{opt.cols}, {opt.rows}]",
        f"square_mm = {toml_value(square * 1e3)}",
        'encoding = "srgb"  # the developed output (imageform calibrate reads it)',
        "",
        "[colorchecker]",
        f"image = {toml_value(chart.path.relative_to(out).as_posix())}  # the raw mosaic",
        'illuminant = "D65"',
        'developed = "colorchecker/developed.png"  # the same exposure, the camera\'s output',
        f"processing = {toml_value('automatic' if chart.automatic else 'fixed')}"
        "  # automatic: the camera white-balances and corrects each scene itself",
        f"corners_px = {toml_value([list(map(float, c)) for c in chart.corners_px])}",
        f"patch_centers_px = {toml_value([list(map(float, c)) for c in chart.centers_px])}",
        "",
        "[edge]",
        f"image = {toml_value(edge_path.relative_to(out).as_posix())}",
        f"angle_deg = {toml_value(opt.angle_deg)}  # the raw mosaic: sharpness without demosaicing",
        "",
        "[emva]",
        'manifest = "emva.toml"',
        'flats = "flats"',
        'darks = "darks"',
        "wavelength_nm = 550.0",
        'channel = "green"',
        f"exposures = {n_exposures}",
        f"frames = {opt.frames}",
        f"frame_shape = [{opt.shape[0]}, {opt.shape[1]}]",
        "",
        "[truth]  # the simulated camera's values (units as in the camera file)",
        *(f"{k} = {toml_value(v)}" for k, v in values.items()),
    ]
    man_path = out / MARKER
    man_path.write_text("\n".join(manifest) + "\n", encoding="utf-8")
    return man_path
