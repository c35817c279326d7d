"""What an imaging lab photographs to characterise a camera, rendered through a camera file.

:func:`render_lab_set` writes checkerboard views, a ColorChecker, a slanted edge and EMVA 1288
flat and dark stacks, with a manifest ``lab.toml`` and the true camera file. The input of
``imageform characterize`` (docs/simulate.md, "A lab's photographs of a camera"), and the
closed loop's test bed: characterising these photographs should give the camera file back.
"""

from __future__ import annotations

import dataclasses
import math
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from imageform._validate import as_int, as_real, describe
from imageform.errors import InvalidInputError
from imageform.io import CameraFile, Provenance, read_camera, write_camera, write_image

__all__ = ["LAB_FORMAT", "LabSet", "render_lab_set"]

#: The ``format`` of a lab set's manifest ``lab.toml``.
LAB_FORMAT = "imageform-lab"
#: Files that mark a folder as a lab set (only such a folder is replaced with ``force``).
_MARKER = "lab.toml"

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
class LabSet:
    """What :func:`render_lab_set` wrote.

    The ``folder``, its ``manifest`` (``lab.toml``), the true ``camera`` file, the
    ``checkerboard`` images, the ``colorchecker`` and ``edge`` images, the EMVA
    ``emva_manifest`` (``emva.toml``, flats/ and darks/) and the ``seconds`` it took.
    """

    folder: Path
    manifest: Path
    camera: Path
    checkerboard: tuple[Path, ...]
    colorchecker: Path
    edge: Path
    emva_manifest: Path
    seconds: float


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


def _toml(value: Any) -> str:
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
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return repr(float(value))


def render_lab_set(
    camera: CameraFile | str | Path,
    folder: str | Path,
    *,
    seed: int = 0,
    views: int = 8,
    board: tuple[int, int] = (9, 6),
    supersampling: int = 2,
    emva_exposures: int = 24,
    emva_frames: int = 2,
    emva_shape: tuple[int, int] = (64, 64),
    edge_angle_deg: float = 5.0,
    force: bool = False,
) -> LabSet:
    """Render what a lab photographs of ``camera`` into ``folder``.

    Layout (images 16-bit PNG, raw mosaics DNG)::

        lab.toml            the manifest: what is where, how it was encoded, the truth
        camera.toml         the camera file rendered through (the truth)
        checkerboard/       view-01.png ... : the board (``board`` inner corners, square
                            ``square_mm`` in lab.toml) at ``views`` poses, the camera's
                            developed output (sRGB-encoded)
        colorchecker/       chart.dng: a frontal ColorChecker under D65, the raw mosaic
                            (:func:`imageform.simulate.write_simulated_dng`);
                            developed.png: the same exposure as the camera develops it
                            (its white balance, colour matrix and sRGB encoding; with no
                            fixed ``white_balance`` or ``ccm`` in ``[color]``, the
                            simulator's automatic processing: grey world and a matrix fitted
                            on the chart), from which ``imageform characterize`` measures
                            the camera's processing (``processing`` in lab.toml says which)
        edge/               edge.dng: a dark square (reflectance 0.1) on a light ground (0.8)
                            turned ``edge_angle_deg``, the raw mosaic (its sharpness is
                            measured without demosaicing)
        emva.toml           the EMVA 1288 manifest ``imageform emva FOLDER`` reads
        flats/, darks/      e00-0.png ... : raw frames (DN) of the green channel at 550 nm
                            (:func:`imageform.sensor.simulate_emva_frames`), one stack of
                            ``emva_frames`` per exposure, ``emva_exposures`` exposures from
                            dark to 105 % of saturation

    Every rendering goes through :func:`imageform.simulate.apply_camera_file` (the file's
    intrinsics and distortion, its ``[sensor]``, ``[optics]`` and ``[color]``; the file's
    pose is not used: the lab poses the camera); the lab's scenes have no defocus and no
    vignetting, a D65 light and sensor noise on (view ``i`` seeded ``seed + i``).

    Parameters
    ----------
    camera : CameraFile, str or Path
        The camera (a camera file path is read with :func:`imageform.io.read_camera`); it
        needs an image size.
    folder : str or Path
        Where to write; must not exist (or be empty) unless ``force`` (then only a previous
        lab set is replaced).
    seed : int
        Seed of the sensor noise.
    views : int
        Checkerboard views, 8 to 12.
    board : (cols, rows)
        Inner corners of the checkerboard (the board has one more square each way).
    supersampling : int
        Rays per pixel along each axis (the renderer's S).
    emva_exposures, emva_frames, emva_shape
        The EMVA stacks: exposures (>= 8), frames per stack (>= 2) and frame size.
    edge_angle_deg : float
        Rotation of the slanted-edge square (2 to 10 degrees).
    force : bool
        Replace an existing lab set.

    Returns
    -------
    LabSet

    Examples
    --------
    >>> import tempfile
    >>> from imageform.geometry import Camera
    >>> cam = Camera([[300.0, 0, 159.5], [0, 300.0, 119.5], [0, 0, 1]], image_size=(320, 240))
    >>> lab = render_lab_set(CameraFile(cam), Path(tempfile.mkdtemp()) / "lab",
    ...                      views=8, emva_exposures=8)  # doctest: +SKIP
    """
    import time

    from imageform.sensor import simulate_emva_frames
    from imageform.sensor.model import photons_per_pixel
    from imageform.simulate.dng import write_simulated_dng
    from imageform.simulate.measured import apply_camera_file
    from imageform.simulate.pipeline import simulate

    t0 = time.perf_counter()
    cf = read_camera(camera) if isinstance(camera, str | Path) else camera
    if not isinstance(cf, CameraFile):
        raise TypeError(
            f"expected camera as a CameraFile or a camera file path, got {describe(camera)}"
        )
    if cf.camera.image_size is None:
        raise InvalidInputError("camera: the camera file has no image size ([image]) to render")
    seed = as_int(seed, "seed", minimum=0)
    n_views = as_int(views, "views", minimum=8, maximum=MAX_VIEWS)
    if not (isinstance(board, tuple | list) and len(board) == 2):
        raise InvalidInputError(
            f"expected board as (cols, rows) inner corners, got {describe(board)}"
        )
    cols, rows = (as_int(b, "board", minimum=3, maximum=30) for b in board)
    ss = as_int(supersampling, "supersampling", minimum=1, maximum=8)
    n_exp = as_int(emva_exposures, "emva_exposures", minimum=8, maximum=200)
    n_frames = as_int(emva_frames, "emva_frames", minimum=2, maximum=64)
    if not (isinstance(emva_shape, tuple | list) and len(emva_shape) == 2):
        raise InvalidInputError(
            f"expected emva_shape as (height, width), got {describe(emva_shape)}"
        )
    shape = (
        as_int(emva_shape[0], "emva_shape", minimum=8, maximum=4096),
        as_int(emva_shape[1], "emva_shape", minimum=8, maximum=4096),
    )
    angle = as_real(edge_angle_deg, "edge_angle_deg", minimum=2.0, maximum=10.0)
    out = Path(folder)
    if out.is_dir() and not any(out.iterdir()):
        out.rmdir()  # an empty folder (a command's temporary output) is filled as a new one
    if out.exists():
        if not force:
            raise InvalidInputError(f"folder {out} exists; choose a new one or pass force=True")
        if not (out / _MARKER).is_file():
            raise InvalidInputError(
                f"folder {out} exists and is not a lab set (no {_MARKER}); choose a new folder"
            )
        shutil.rmtree(out)
    out.mkdir(parents=True)
    posed = dataclasses.replace(cf, has_pose=False)
    w, h = cf.camera.image_size
    K = np.asarray(cf.camera.K, dtype=np.float64)
    fx = float(K[0, 0])

    # --- checkerboard views: the board (cols+1 x rows+1 squares) fills about half the width
    square = 0.02
    board_w = (cols + 1) * square
    scale = (fx * board_w / (0.62 * w)) / 0.3  # distance for 0.3 m in the test views
    board_obj = {
        "type": "checkerboard",
        "centre_m": [0.0, 0.0, 0.0],
        "normal": [0.0, -1.0, 0.0],
        "squares": [cols + 1, rows + 1],
        "square_size_m": square,
    }
    base = _base_scene((w, h), ss, [board_obj])
    view_list = [
        {
            "eye_m": [scale * c for c in eye],
            "target_m": [scale * c for c in target],
            "up": list(up),
        }
        for eye, up, target in _VIEWS[:n_views]
    ]
    scene = apply_camera_file(base.with_changes(views=view_list), posed)
    (out / "checkerboard").mkdir()
    boards = []
    for i in range(n_views):
        res = simulate(scene.view(i), rng=seed + i)
        p = out / "checkerboard" / f"view-{i + 1:02d}.png"
        write_image(p, _linear16(_stage(res, "output")))
        boards.append(p)

    # --- ColorChecker, frontal-ish, about 70 % of the width
    chart_w = 0.12
    dist = fx * chart_w / (0.7 * w)
    chart = {"type": "colorchecker", "centre_m": [0.0, 0.0, 0.0], "width_m": chart_w}
    automatic = cf.color is None or (cf.color.white_balance is None and cf.color.ccm is None)
    cc_base = _base_scene((w, h), ss, [chart]).with_changes(
        camera={"eye_m": [0.01 * dist, -dist, 0.01 * dist], "target_m": [0.0, 0.0, 0.0]}
    )
    if automatic:  # the camera balances what it sees (the simulator's automatic processing)
        cc_base = cc_base.with_changes(processing=_AUTOMATIC)
    cc_scene = apply_camera_file(cc_base, posed)
    res = simulate(cc_scene, rng=seed + 100)
    (out / "colorchecker").mkdir()
    cc_path = write_simulated_dng(res, cc_scene, out / "colorchecker" / "chart.dng")
    write_image(out / "colorchecker" / "developed.png", _linear16(_stage(res, "output")))
    cc_gains = [float(g) for g in res.metrics["white_balance_gains"]]
    cc_matrix = np.asarray(res.metrics["color_correction_matrix"], dtype=np.float64)
    centres = res.colorchecker.centres_uv if res.colorchecker is not None else np.zeros((24, 2))
    quad = res.quads[0].corners if res.quads else np.zeros((4, 3))
    chart_quad = np.asarray(cc_scene.camera.project(quad).uv, dtype=np.float64)

    # --- slanted edge: a dark square on a light plane, turned by the angle
    a = math.radians(angle)
    side = 0.1
    e_dist = fx * side / (0.45 * h)
    edge_objs = [
        {
            "type": "plane",
            "name": "ground",
            "centre_m": [0.0, 0.01 * e_dist, 0.0],
            "normal": [0.0, -1.0, 0.0],
            "size_m": [8 * side, 8 * side],
            "reflectance": 0.8,
        },
        {
            "type": "plane",
            "name": "dark square",
            "centre_m": [0.0, 0.0, 0.0],
            "normal": [0.0, -1.0, 0.0],
            "up": [math.sin(a), 0.0, math.cos(a)],
            "size_m": [side, side],
            "reflectance": 0.1,
        },
    ]
    edge_scene = apply_camera_file(
        _base_scene((w, h), ss, edge_objs).with_changes(
            camera={"eye_m": [0.0, -e_dist, 0.0], "target_m": [0.0, 0.0, 0.0]}
        ),
        posed,
    )
    res = simulate(edge_scene, rng=seed + 200)
    (out / "edge").mkdir()
    edge_path = write_simulated_dng(res, edge_scene, out / "edge" / "edge.dng")
    sensor = edge_scene.sensor

    # --- EMVA 1288 stacks, green channel at 550 nm, dark to 105 % of the clip
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
        rng=seed + 300,
        frames=n_frames,
        shape=shape,
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
            f"time = {_toml(float(t))}",
            f"photons = {_toml(float(frames.photons[i]))}",
            f"flats = {_toml(names['flats'])}",
            f"darks = {_toml(names['darks'])}",
        ]
    emva_path = out / "emva.toml"
    emva_path.write_text("\n".join(lines) + "\n", encoding="utf-8")

    cam_path = write_camera(
        out / "camera.toml",
        posed,
        provenance=Provenance(
            command="imageform.simulate.render_lab_set",
            based_on=None if cf.path is None else str(cf.path),
        ),
    )
    fp = sensor.fixed_pattern(*shape)
    truth = {
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
        truth["gaussian_sigma_px"] = sigma
        truth["mtf50_cy_per_px"] = _raw_mtf50(sigma, angle, ss)
    elif cf.optics is not None and cf.optics.mtf50_rgb() is not None:
        truth["mtf50_cy_per_px"] = [float(m) for m in cf.optics.mtf50_rgb() or ()]
    truth["white_balance"] = cc_gains  # what the camera's processing applied to the chart
    truth["ccm"] = [[float(x) for x in row] for row in cc_matrix.T]  # linear sRGB = ccm @ rgb
    if cf.camera.distortion is not None:
        for name in ("k1", "k2"):
            if hasattr(cf.camera.distortion, name):
                truth[name] = float(getattr(cf.camera.distortion, name))
    manifest = [
        "# imageform lab set (render_lab_set, docs/simulate.md): what a lab photographs to",
        "# characterise a camera, rendered through camera.toml (the truth).",
        f"format = {_toml(LAB_FORMAT)}",
        "version = 1",
        'camera_file = "camera.toml"  # the truth',
        f"seed = {seed}",
        "",
        "[camera]  # what the lab knows of the camera (its data sheet and settings)",
        f"cfa = {_toml(truth['cfa'])}",
        f"pixel_pitch_um = {_toml(truth['pixel_pitch_um'])}",
        f"f_number = {_toml(truth['f_number'])}",
        "",
        "[checkerboard]",
        'folder = "checkerboard"',
        f"images = {_toml([p.relative_to(out).as_posix() for p in boards])}",
        f"inner_corners = [{cols}, {rows}]",
        f"square_mm = {_toml(square * 1e3)}",
        'encoding = "srgb"  # the developed output (imageform calibrate reads it)',
        "",
        "[colorchecker]",
        f"image = {_toml(cc_path.relative_to(out).as_posix())}  # the raw mosaic",
        'illuminant = "D65"',
        'developed = "colorchecker/developed.png"  # the same exposure, the camera\'s output',
        f"processing = {_toml('automatic' if automatic else 'fixed')}"
        "  # automatic: the camera white-balances and corrects each scene itself",
        f"corners_px = {_toml([list(map(float, c)) for c in chart_quad])}",
        f"patch_centres_px = {_toml([list(map(float, c)) for c in centres])}",
        "",
        "[edge]",
        f"image = {_toml(edge_path.relative_to(out).as_posix())}",
        f"angle_deg = {_toml(angle)}  # the raw mosaic: sharpness without demosaicing",
        "",
        "[emva]",
        'manifest = "emva.toml"',
        'flats = "flats"',
        'darks = "darks"',
        "wavelength_nm = 550.0",
        'channel = "green"',
        f"exposures = {len(times)}",
        f"frames = {n_frames}",
        f"frame_shape = [{shape[0]}, {shape[1]}]",
        "",
        "[truth]  # the simulated camera's values (units as in the camera file)",
        *(f"{k} = {_toml(v)}" for k, v in truth.items()),
    ]
    man_path = out / _MARKER
    man_path.write_text("\n".join(manifest) + "\n", encoding="utf-8")
    return LabSet(
        folder=out,
        manifest=man_path,
        camera=cam_path,
        checkerboard=tuple(boards),
        colorchecker=cc_path,
        edge=edge_path,
        emva_manifest=emva_path,
        seconds=time.perf_counter() - t0,
    )
