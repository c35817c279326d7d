"""``imageform simulate``: a scene through the whole image-formation chain, in one folder.

The output folder (report.html, metrics.json, the stage images and the ground-truth camera file)
replaces the previous one all at once.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from imageform.errors import InvalidInputError
from imageform.workflows._spec import (
    Options,
    Output,
    Result,
    Run,
    Workflow,
    option,
    refuse_foreign_folder,
)

__all__ = ["WORKFLOWS", "SimulateOptions"]

#: The files that mark a folder as imageform simulate's output (only such a folder is
#: replaced with --force: never a folder of the user's files).
_MARKERS = ("report.html", "metrics.json")


@dataclass(frozen=True, kw_only=True)
class SimulateOptions(Options):
    """Options of ``imageform simulate``."""

    scene: Path | None = option(
        None, help="Scene description (TOML); default: the built-in scene.", input=True
    )
    camera: Path | None = option(
        None,
        help="Render through this camera file (from imageform calibrate or characterize, or a "
        "simulation's camera.toml): its intrinsics and distortion, its pose if it has one (else "
        "the scene's), and its [sensor] noise model, [optics] blur and [color] white balance, "
        "CCM and sensitivities when present; the file's values override the scene's.",
        input=True,
    )
    lab: Path | None = option(
        None,
        help="Also render what a lab photographs of the --camera file into this folder: "
        "checkerboard/, colorchecker/, edge/, flats/ and darks/ with emva.toml, lab.toml and "
        "the camera file (imageform.simulate.render_lab_set; docs/simulate.md).",
        output=True,
        folder=True,
        metavar="FOLDER",
    )
    seed: int = option(
        0,
        help="Seed of the sensor noise, an integer (rng= in Python): the same seed, the same "
        "pixels.",
        minimum=0,
    )
    raw: Path | None = option(
        None,
        help="Also write the raw mosaic as a DNG file with the simulated camera's colour "
        "matrix and white balance (opens in LibRaw, darktable, RawTherapee); a path outside the "
        "output folder.",
        output=True,
        metavar="FILE.dng",
    )

    trajectory: Path | None = option(
        None,
        help="Also render the scene along this camera path (CSV: time_s and rx,ry,rz,tx,ty,tz "
        "world to camera in metres, or eye_x..z,target_x..z) into --video, with the true poses "
        "beside it.",
        input=True,
        metavar="PATH.csv",
    )
    video: Path | None = option(
        None,
        help="The video of --trajectory (.mp4, .mkv, .avi); the truth goes to VIDEO.poses.csv "
        "(the checkerboard's pose, as imageform track writes it).",
        output=True,
        metavar="FILE",
    )

    def check(self) -> None:
        """Check ``--seed`` (an integer >= 0) and that ``--raw`` names a .dng file."""
        super().check()
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise InvalidInputError(f"expected --seed as an integer >= 0, got {self.seed!r}")
        if self.lab is not None and self.camera is None:
            raise InvalidInputError("--lab renders a camera file's lab set: give --camera FILE")
        if self.raw is not None and Path(self.raw).suffix.lower() != ".dng":
            raise InvalidInputError(f"expected --raw as a .dng file, got {str(self.raw)[-60:]!r}")
        if (self.trajectory is None) != (self.video is None):
            raise InvalidInputError("--trajectory and --video go together")
        if self.video is not None and Path(self.video).suffix.lower() not in (
            ".mp4", ".mkv", ".avi", ".mov",
        ):  # fmt: skip
            raise InvalidInputError(
                f"expected --video as .mp4, .mkv, .avi or .mov, got {str(self.video)[-60:]!r}"
            )


def _camera_tables(scene: Any, measured: Any) -> tuple[Any, Any]:
    """Return the truth camera file's ``[sensor]`` and ``[color]``: the scene's own camera.

    ``[sensor]`` holds the sensor model's EMVA values (the effective peak QE, fill factor
    included; DSNU with the column offsets), its pixel pitch and CFA; ``[color]`` the shape
    of its QE curves (a shipped table by name), so that ``--camera`` and ``--lab`` render
    this camera, not the simulator's defaults (issue 26). No ``white_balance`` or ``ccm``:
    the scene's processing is automatic (``[processing]``). A camera file's own tables
    (``--camera``) win.
    """
    import numpy as np

    sen = scene.sensor
    curves = np.asarray(sen.qe_curves, dtype=np.float64)
    table: dict[str, Any] = {
        "system_gain_dn_per_e": float(sen.system_gain),
        "read_noise_e": float(sen.read_noise),
        "dark_current_e_per_s": float(sen.dark_current),
        "dsnu_e": float(np.hypot(sen.dsnu, sen.column_fpn if sen.architecture == "cmos" else 0)),
        "prnu": float(sen.prnu),
        "full_well_e": float(sen.full_well),
        "bit_depth": int(sen.bit_depth),
        "black_level_dn": float(sen.black_level),
        "quantum_efficiency": float(min(curves.max() * sen.fill_factor, 1.0)),
        "pixel_pitch_um": float(sen.pixel_pitch * 1e6),
        "cfa": str(scene.config.sensor.cfa),
    }
    if measured is not None and measured.sensor is not None:
        table |= measured.sensor.to_dict()
    if measured is not None and measured.color is not None:
        return table, measured.color
    if scene.config.sensor.spectral_sensitivity != "preset":
        return table, {"spectral_sensitivity": scene.config.sensor.spectral_sensitivity}
    rel = curves / curves.max()
    color = {
        "sensitivity": {
            "wavelengths_nm": [float(w) for w in sen.qe_wavelengths],
            **{c: [float(x) for x in rel[k]] for k, c in enumerate("rgb")},
        }
    }
    return table, color


def simulate(run: Run, opts: SimulateOptions, *, out: Path) -> Result:
    """Render the scene, write the report, the metrics, the stage images and the truth camera file.

    They are written into a temporary folder that replaces ``out`` when everything is written.
    """
    import importlib.util

    if importlib.util.find_spec("matplotlib") is None:  # the report's figures
        raise InvalidInputError(
            "imageform simulate draws its report with matplotlib, which is not installed: "
            'pip install "imageform[plot]"'
        )
    from imageform._kernels import ahead
    from imageform.io import CameraFile, Provenance, read_camera, write_camera
    from imageform.report.html import write_report
    from imageform.simulate import default_scene, load_scene
    from imageform.simulate import simulate as simulate_scene

    refuse_foreign_folder(out, run.outputs.force, _MARKERS, "simulate", "a previous simulation")
    folder = run.folder(out)
    t0 = time.perf_counter()
    scene = load_scene(opts.scene) if opts.scene is not None else default_scene()
    if opts.camera is not None:
        from imageform.simulate import apply_camera_file

        scene = apply_camera_file(scene, read_camera(opts.camera))
    traj = None
    if opts.trajectory is not None:  # read first: a bad path fails before any rendering
        from imageform.simulate import read_trajectory

        traj = read_trajectory(opts.trajectory, up=scene.config.camera.up)
    ahead.start("simulate")  # a first run: its kernels compiled on two cores
    result = simulate_scene(scene, progress=run.progress, rng=opts.seed)
    if run.progress is not None:
        run.progress("writing the report", 1.0)
    paths = write_report(result, folder, force=True)
    views = _render_views(run, scene, folder, opts.seed)
    measured = getattr(scene, "measured", None)  # the camera file's tables, if any
    sensor_table, color_table = _camera_tables(scene, measured)
    camera_file = write_camera(
        folder / "camera.toml",
        CameraFile(
            result.camera,
            has_pose=True,
            sensor=sensor_table,
            optics=None if measured is None else measured.optics,
            color=color_table,
            provenance=Provenance(
                command="imageform simulate",
                based_on=str(opts.scene) if opts.scene is not None else "built-in scene",
            ),
        ),
    )
    raw_dng = None
    if opts.raw is not None:
        from imageform.simulate import write_simulated_dng

        write_simulated_dng(result, scene, run.file(opts.raw))
        raw_dng = opts.raw
    lab_folder = None
    if opts.lab is not None and opts.camera is not None:
        from imageform.simulate import render_lab_set

        lab_out = Path(opts.lab)
        if lab_out.is_dir() and any(lab_out.iterdir()) and not (lab_out / "lab.toml").is_file():
            raise InvalidInputError(
                f"--lab folder {lab_out} exists and is not a lab set (no lab.toml); choose a "
                "new folder"
            )
        if run.progress is not None:
            run.progress("lab set", 1.0)
        render_lab_set(read_camera(opts.camera), run.folder(lab_out), rng=opts.seed)
        lab_folder = opts.lab
    video = _render_trajectory(run, scene, opts, traj) if traj is not None else None
    wall = time.perf_counter() - t0

    def final(p: Path) -> Path:
        return out / Path(p).relative_to(folder)

    s: dict[str, Any] = dict(paths.summary)
    summary = {
        "scene": opts.scene,
        "scene_name": result.scene_name,
        "camera_file_in": opts.camera,
        "image_size": list(result.image_size),
        "report": final(paths.html),
        "metrics": final(paths.metrics),
        "camera": final(camera_file),
        "stages": [final(p) for p in paths.stages],
        "raw_files": [final(p) for p in paths.raw_files],
        "views": [final(p) for p in views],
        "raw_dng": raw_dng,
        "lab": lab_folder,
        "video": video,
        "summary": s,
        "report_time_s": paths.seconds,
        "total_time_s": wall,
    }

    def num(v: object, fmt: str, unit: str = "") -> str:
        return "n/a" if v is None else f"{v:{fmt}}{unit}"

    w, h = result.image_size
    text = (
        f"scene {result.scene_name!r}: {w}x{h} px, {len(result.stages)} stages",
        f"report  -> {summary['report']}",
        f"metrics -> {summary['metrics']}",
        f"camera  -> {summary['camera']}",
        *([f"views   -> {out / 'views'} ({len(views)} images)"] if views else []),
        *([f"raw DNG -> {raw_dng}"] if raw_dng is not None else []),
        *([f"lab set -> {lab_folder}"] if lab_folder is not None else []),
        *(
            [f"video   -> {opts.video} ({video['frames']} frames), truth -> {video['truth']}"]
            if video is not None
            else []
        ),
        f"mean ΔE00 {num(s.get('delta_e00_mean'), '.2f')} "
        f"(max {num(s.get('delta_e00_max'), '.2f')}); "
        f"vanishing-point error {num(s.get('vanishing_point_error_px'), '.2f', ' px')}; "
        f"simulation {num(s.get('simulation_time_s'), '.1f', ' s')}, "
        f"report {paths.seconds:.1f} s, total {wall:.1f} s",
    )
    return Result(summary, text)


def _truth_path(video: Path) -> Path:
    return video.with_name(video.name + ".poses.csv")


def _render_trajectory(run: Run, scene: Any, opts: SimulateOptions, traj: Any) -> dict[str, Any]:
    """Render the scene along ``--trajectory`` into ``--video``; write the truth beside it."""
    import csv

    import numpy as np

    from imageform.geometry import matrix_to_rvec
    from imageform.io import VideoWriter
    from imageform.simulate import board_poses, render_frames

    assert opts.video is not None
    truth_path = _truth_path(Path(opts.video))
    board = board_poses(scene, traj)
    with VideoWriter(run.file(opts.video), fps=traj.fps, quality=12) as writer:
        for frame in render_frames(scene, traj, rng=opts.seed, progress=run.progress):
            writer.write(frame)
    if board is not None:
        what, poses = board
        cols, rows = (int(x) for x in what.split(":")[1].split("x"))
        corners, unit = cols * rows, "mm"
    else:
        poses = list(zip(traj.R, traj.t, strict=True))
        what, corners, unit = "camera (world to camera)", 0, "m"
    with open(run.file(truth_path), "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(("frame", "time_s", "found", "corners", "rx", "ry", "rz", "tx", "ty", "tz",
                    "rms_px"))  # fmt: skip
        for i, (time_s, (R, t)) in enumerate(zip(traj.times, poses, strict=True)):
            r = np.asarray(matrix_to_rvec(R), np.float64)
            w.writerow([i, f"{time_s:.6f}", 1, corners, *(f"{v:.9g}" for v in (*r, *t)), 0])
    return {"frames": len(traj), "fps": traj.fps, "truth": truth_path, "pose_of": what,
            "unit": unit}  # fmt: skip


def _render_views(run: Run, scene: Any, folder: Path, seed: int) -> list[Path]:
    """Render each extra view of the scene (``[[views]]``) through the whole chain.

    Its encoded output is written as ``views/view-NN.png`` (the noise of view i seeded with
    ``seed + 1 + i``).
    """
    from imageform.io import write_image
    from imageform.simulate import simulate as simulate_scene

    n = len(scene.config.views)
    if not n:
        return []
    (folder / "views").mkdir()
    written = []
    for i in range(n):
        if run.progress is not None:
            run.progress(f"view {i + 1} of {n}", (i + 0.5) / n)
        res = simulate_scene(scene.view(i), rng=seed + 1 + i)
        path = folder / "views" / f"view-{i + 1:02d}.png"
        write_image(path, res.stages[-1].image)
        written.append(path)
    return written


#: What the output folder holds (its --help, and the refusal of a file name for it).
_HOLDS = "report.html, metrics.json, stages/, camera.toml, views/"

WORKFLOWS = (
    Workflow(
        "simulate",
        "Render a scene through the whole image-formation chain and write an HTML report.",
        "imageform.workflows.simulate:simulate",
        SimulateOptions,
        (),
        Output(
            f"Output folder: {_HOLDS} (replaced whole).",
            holds=_HOLDS,
            required=False,
            default="simulation",
            folder=True,
        ),
        group="simulation",
        description="The built-in scene (or --scene FILE) through illumination, optics, "
        "sensor and the camera's processing. The folder is written beside the old one and "
        "swapped in at the end, so an interrupted run leaves the previous output untouched.",
    ),
)
