"""``imageform reconstruct``: camera poses and a coloured point cloud from a video.

The course's structure-from-motion application: with the intrinsics known (a camera file),
or a focal length from the EXIF or guessed and refined, the frames of a video (a file, a
folder or a glob of images) give the camera's motion and the scene's shape up to a similarity.
The maths lives in :func:`imageform.geometry.reconstruct_sequence`; this module reads the
frames, writes ``cameras.csv``, ``points.ply``, ``report.html`` and ``metrics.json`` into the
output folder (all or nothing), and reports the time and the errors.
"""

from __future__ import annotations

import csv
import math
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.workflows._spec import (
    Input,
    Options,
    Output,
    Result,
    Run,
    Workflow,
    option,
    refuse_foreign_folder,
)
from imageform.workflows._video import (
    DEINTERLACE_CHOICES,
    DeinterlaceChoice,
    FieldOrderChoice,
    field_order_option,
)

__all__ = ["CAMERA_COLUMNS", "WORKFLOWS", "ReconstructOptions"]

#: Columns of ``cameras.csv`` (world to camera: X_cam = R(r) X + t; NaN when not registered).
CAMERA_COLUMNS = ("frame", "name", "registered", "rx", "ry", "rz", "tx", "ty", "tz", "rms_px")

#: The files that mark a folder as imageform reconstruct's output (only such a folder is
#: replaced with --force: never a folder of the user's files).
_MARKERS = ("cameras.csv", "points.ply", "metrics.json", "report.html")

#: The ``format`` of metrics.json.
METRICS_FORMAT = "imageform-reconstruction"


@dataclass(frozen=True, kw_only=True)
class ReconstructOptions(Options):
    """Options of ``imageform reconstruct``."""

    camera: Path | None = option(
        None,
        help="Camera file of the frames' camera (K and distortion: imageform calibrate); "
        "without it, the focal length from the frames' EXIF (35 mm equivalent) or "
        "1.2 x max(width, height) (COLMAP's guess), the principal point at the center, no "
        "distortion.",
        metavar="FILE",
        input=True,
    )
    focal: float | None = option(
        None,
        help="Without --camera: the focal length in pixels (the principal point at the "
        "center, no distortion), instead of the EXIF's or the guess.",
        metavar="PX",
    )
    refine_focal: bool = option(
        False,
        help="Refine the focal length given by --camera or --focal in the bundle "
        "adjustments (one for every frame, the principal point held); a focal length from "
        "the EXIF or the guess is always refined.",
    )
    refine_distortion: bool = option(
        False,
        help="Refine one radial distortion term k1 shared by every frame (COLMAP's "
        "SIMPLE_RADIAL: u = c + f (1 + k1 r^2) x) in the bundle adjustments, from the "
        "--camera file's (no distortion, or k1 alone) or 0 with --focal; without a camera "
        "file or --focal it is always refined. Where it runs off or its barrel term is "
        "strong (a fisheye), the equidistant fisheye (Kannala-Brandt, f and one term k1) is "
        "tried and kept when it registers as many frames and the tracks of both models "
        "cost it no more (errors capped at 2 px, GRIC's penalty per parameter). The camera "
        "found is written to camera.toml.",
    )
    max_features: int = option(
        4000, help="SIFT keypoints per frame (the strongest).", minimum=8, maximum=1_000_000
    )
    window: int = option(
        3, help="Match each frame with the next this many frames.", minimum=1, maximum=100
    )
    ratio: float = option(
        0.8,
        help="Lowe's ratio: a match is kept when its nearest descriptor is nearer than this "
        "times the second nearest, in (0, 1].",
        maximum=1.0,
    )
    every: int = option(
        1,
        help="Take every Nth frame (neighbouring frames of a video barely move).",
        metavar="N",
        minimum=1,
    )
    max_frames: int | None = option(
        None, help="Use at most this many frames (after --every).", minimum=2
    )
    mask: Path | None = option(
        None,
        help="Image of the frames' size, nonzero where keypoints may be, one for every frame "
        "(e.g. without an endoscope's dark vignetted corners).",
        metavar="FILE",
        input=True,
    )
    auto_mask: bool = option(
        False,
        help="Find where keypoints may be from the frames: an endoscope's aperture without "
        "its black border and burned-in overlays, and a margin off its edge.",
    )
    keep_overlays: bool = option(
        False,
        help="Keep the keypoints on what stands still while the camera moves (burned-in "
        "text, an icon, an aperture's rim), which are left out by default from 8 frames on.",
    )
    highlights: bool = option(
        False,
        help="Keep keypoints off the specular highlights (bright, nearly white pixels) of "
        "every frame: they move with the light, not with the tissue.",
    )
    skip_blurred: bool = option(
        False,
        help="Leave out the blurred frames: sharpness (the variance of the Laplacian in the "
        "field of view) below half the median of the 3 frames on either side.",
    )
    deinterlace: DeinterlaceChoice = option(
        "auto",
        help="Interlaced video: auto (linear when the first frames comb, else off), off, "
        "linear (the first field kept, the other field's rows interpolated: the frame's "
        "size and camera matrix), fields (the first field at half height, fy and cy halved) "
        "or blend.",
        choices=DEINTERLACE_CHOICES,
    )
    field_order: FieldOrderChoice | None = field_order_option()
    contrast_threshold: float = option(
        0.04,
        help="SIFT's contrast threshold, in (0, 1): 0.01 finds ten times as many keypoints "
        "on smooth, low-contrast tissue (endoscopy).",
        maximum=1.0,
    )
    equalize: bool = option(
        False,
        help="Equalize each frame's grey levels by CLAHE (tiles of about 64 px) before SIFT: an "
        "endoscope's dim parts, far from its light, then keep as many keypoints as the lit "
        "ones (more points; check it against a run without it, with --camera).",
    )

    def check(self) -> None:
        """Check ``--ratio``, ``--contrast-threshold``, and ``--mask`` without ``--auto-mask``."""
        super().check()
        if not 0 < self.ratio <= 1:
            raise InvalidInputError(f"expected --ratio in (0, 1], got {self.ratio:g}")
        if not 0 < self.contrast_threshold < 1:
            raise InvalidInputError(
                f"expected --contrast-threshold in (0, 1), got {self.contrast_threshold:g}"
            )
        if self.mask is not None and self.auto_mask:
            raise InvalidInputError("expected --mask FILE or --auto-mask, got both")
        if self.focal is not None:
            if self.camera is not None:
                raise InvalidInputError("expected --camera FILE or --focal PX, got both")
            if not (math.isfinite(self.focal) and self.focal > 0):
                raise InvalidInputError(f"expected --focal > 0 pixels, got {self.focal:g}")


def _hint(opts: ReconstructOptions) -> str:
    """Say what to try when no pair starts: the options not yet used for an endoscope."""
    tries = []
    if opts.mask is None and not opts.auto_mask:
        tries.append("--auto-mask (an endoscope's black border and overlays)")
    if not opts.highlights:
        tries.append("--highlights (specular highlights)")
    if opts.contrast_threshold > 0.01:
        tries.append("--contrast-threshold 0.01 (smooth, low-contrast tissue)")
    if opts.every == 1:
        tries.append("--every 2 or more (more motion between frames)")
    return "; try " + ", ".join(tries) if tries else ""


def _fmt(x: float) -> str:
    return "nan" if not math.isfinite(x) else f"{x:.9g}"


def _read_frames(
    source: str, opts: ReconstructOptions, size: tuple[int, int] | None
) -> tuple[list[Any], list[str], Any, Path | None]:
    """Read the frames (every ``--every``-th, at most ``--max-frames``), their names, the reader.

    The last: the first frame's file (None for a video's frames).

    An interlaced video read as fields (``--deinterlace``) gives the first field of each frame.
    """
    from imageform.io import open_video

    reader = open_video(
        source, deinterlace=opts.deinterlace, field_order=opts.field_order, auto_method="linear"
    )
    info = reader.info
    if size is not None and tuple(size) != (info.width, info.height):
        reader.close()
        raise InvalidInputError(
            f"camera file {opts.camera} is for {size[0]} x {size[1]} px images, {source} has "
            f"{info.width} x {info.height} px frames"
        )
    images: list[Any] = []
    names: list[str] = []
    first: Path | None = None
    with reader:
        for frame in reader:
            index = frame.index
            if frame.field is not None:  # the first field of each frame: one camera matrix
                if frame.field != reader.field_order:
                    continue
                index //= 2
            if index % opts.every:
                continue
            images.append(frame.image)
            if not images[1:]:
                first = frame.path
            names.append(frame.path.name if frame.path is not None else f"frame_{index:06d}")
            if opts.max_frames is not None and len(images) >= opts.max_frames:
                break
    return images, names, reader, first


def _read_mask(path: Path, info: Any, field: str | None = None) -> Any:
    """Read the ``--mask`` image as booleans (nonzero: keypoints allowed), the frames' size."""
    from imageform.io import read_image
    from imageform.workflows._images import mask_of

    mask = mask_of(
        read_image(path, alpha="drop"),
        path,
        info.height,
        info.width,
        "the frames",
        "no keypoint could be kept",
    )
    if field is None:
        return mask
    return mask[0::2] if field == "top" else mask[1::2]  # the field's rows


def _masks(
    images: list[Any], opts: ReconstructOptions, info: Any, field: str | None = None
) -> tuple[Any, dict[str, Any], Any]:
    """Return the keypoint masks (one, one a frame, or None), their shares, the field of view."""
    import numpy as np

    from imageform.geometry import field_of_view_mask, highlight_mask

    if opts.mask is not None:
        fov = _read_mask(opts.mask, info, field)
    elif opts.auto_mask:
        fov = field_of_view_mask(images)
    else:
        fov = None
    shares: dict[str, Any] = {}
    if fov is not None:
        shares["field_of_view_share"] = round(float(np.mean(fov)), 4)
    if not opts.highlights:
        return fov, shares, fov
    spec = [highlight_mask(im) for im in images]
    shares["highlight_share_mean"] = round(float(np.mean([s.mean() for s in spec])), 4)
    keep = [~s if fov is None else fov & ~s for s in spec]
    return keep, shares, fov


def _guess_camera(
    opts: ReconstructOptions, width: int, height: int, first: Path | None
) -> tuple[Any, dict[str, Any]]:
    """Return K without a camera file, and where its focal length comes from.

    ``--focal``, else the first frame's EXIF focal length (its 35 mm equivalent,
    :func:`imageform.io.exif_camera`), else COLMAP's guess f = 1.2 max(w, h); the
    principal point at the center, no distortion.
    """
    import numpy as np

    if opts.focal is not None:
        f, source = float(opts.focal), "--focal"
    else:
        f, source = 1.2 * max(width, height), "guess"
        if first is not None:
            from imageform.io import exif_camera

            exif = exif_camera(first)
            if (
                exif.focal_length_px is not None
                and (exif.width_px, exif.height_px) == (width, height)
                and math.isfinite(exif.focal_length_px)
                and exif.focal_length_px > 0
            ):
                f, source = float(exif.focal_length_px), "exif"
    K = np.array([[f, 0.0, (width - 1) / 2], [0.0, f, (height - 1) / 2], [0.0, 0.0, 1.0]])
    return K, {"source": source, "focal_px_initial": f}


def _camera_note(intr: dict[str, Any], first: Path | None) -> str:
    """Say where K comes from (no camera file), and what the refinement found."""
    f0 = intr["focal_px_initial"]
    sd, fixed = intr.get("focal_px_sd"), intr.get("focal_fixed")
    spread = (
        ""
        if fixed is None
        else (f" +- {sd:.1f} px" if sd is not None else " +- inf")
        + (", fixed by the frames" if fixed else ", not fixed by the frames")
    )
    refined = (
        f"; refined by bundle adjustment to f = {intr['focal_px']:.1f} px{spread} "
        f"({100 * (intr['focal_px'] / f0 - 1):+.1f} %)"
        if intr["refined"]
        else ""
    )
    if intr.get("distortion_refined"):
        k1 = intr["k1"]
        model = intr.get("model", "SIMPLE_RADIAL")
        what = "the equidistant fisheye, Kannala-Brandt" if model == "KANNALA_BRANDT" else model
        refined += (", " if refined else "; refined by bundle adjustment to ") + (
            f"k1 = {k1:.4f} ({what})"
        )
    if intr["source"] == "camera file":
        return f"the camera file's f = {f0:.1f} px{refined}"
    why = {
        "--focal": "--focal",
        "exif": f"the EXIF 35 mm equivalent focal length of {first.name if first else ''}",
        "guess": "COLMAP's guess 1.2 x max(width, height) (no EXIF focal length)",
    }[intr["source"]]
    return (
        f"no camera file: f = {f0:.1f} px from {why}, the principal point at the center, "
        f"no distortion{refined}"
    )


def _metrics_rms(rec: Any) -> float | None:
    """Return the RMS of the final reprojection errors (px), None without any."""
    import numpy as np

    r = np.asarray(rec.residuals_px, np.float64)
    return float(np.sqrt(np.mean(r**2))) if r.size else None


def _metrics(rec: Any, names: list[str], seconds: dict[str, float]) -> dict[str, Any]:
    import numpy as np

    n, nreg = len(names), int(np.sum(rec.registered))
    r = np.asarray(rec.residuals_px, np.float64)
    tl = np.asarray(rec.track_length)
    return {
        "frames": n,
        "registered": nreg,
        "registered_share": nreg / n,
        "points": int(rec.points.shape[0]),
        "observations": int(r.size),
        "track_length_mean": float(tl.mean()) if tl.size else None,
        "reprojection_px_median": float(np.median(r)) if r.size else None,
        "reprojection_px_rms": float(np.sqrt(np.mean(r**2))) if r.size else None,
        "unregistered": [names[i] for i in np.flatnonzero(~rec.registered).tolist()],
        "notes": list(rec.notes),
        "seconds": {k: round(v, 3) for k, v in seconds.items()},
    }


def reconstruct(run: Run, opts: ReconstructOptions, *, out: Path, frames: str) -> Result:
    """Reconstruct the cameras and points of the frames; write the four files into ``out``."""
    import importlib.util

    import numpy as np

    if importlib.util.find_spec("matplotlib") is None:  # the report's figures
        raise InvalidInputError(
            "imageform reconstruct draws its report with matplotlib, which is not installed: "
            'pip install "imageform[plot]"'
        )
    from imageform._jsonio import write_json
    from imageform._kernels import ahead
    from imageform.geometry import Camera, matrix_to_rvec, reconstruct_sequence
    from imageform.io import Provenance, field_camera_matrix, read_camera, write_camera
    from imageform.workflows._ply import write_points_ply
    from imageform.workflows._reconstruct_report import write_report
    from imageform.workflows._video import deinterlace_note, deinterlace_summary

    refuse_foreign_folder(
        out, run.outputs.force, _MARKERS, "reconstruct", "a previous reconstruction"
    )
    cam = None if opts.camera is None else read_camera(opts.camera).camera
    lens0 = None if cam is None else cam.distortion
    if opts.refine_distortion and lens0 is not None:
        coeffs = tuple(getattr(lens0, "coeffs", ()))
        if type(lens0).__name__ != "BrownConrady" or any(coeffs[1:]):
            raise InvalidInputError(
                f"{opts.camera}: --refine-distortion refines one radial term k1 (COLMAP's "
                f"SIMPLE_RADIAL), the camera file's lens is {type(lens0).__name__} "
                f"{', '.join(f'{c:g}' for c in coeffs)}: give a camera without distortion or "
                "with brown_conrady k1 alone"
            )
    size = (
        None
        if cam is None or cam.image_size is None
        else (int(cam.image_size[0]), int(cam.image_size[1]))
    )
    seconds: dict[str, float] = {}
    t0 = time.perf_counter()
    if run.progress is not None:
        run.progress("reading the frames", 0.0)
    images, names, reader, first = _read_frames(frames, opts, size)
    info = reader.info
    field = reader.field_order if getattr(reader, "deinterlaced", "off") == "fields" else None
    if cam is None:
        K_frame, intrinsics = _guess_camera(opts, info.width, info.height, first)
        distortion = None
    else:
        K_frame, distortion = cam.K, cam.distortion
        intrinsics = {"source": "camera file", "focal_px_initial": float(cam.K[0, 0])}
    K = K_frame if field is None else field_camera_matrix(K_frame, field)
    refine = opts.refine_focal or intrinsics["source"] in ("exif", "guess")
    refine_lens = opts.refine_distortion or intrinsics["source"] in ("exif", "guess")
    if len(images) < 2:
        raise InvalidInputError(
            f"{frames}: {len(images)} frame"
            + (f" (one in {opts.every})" if opts.every > 1 else "")
            + "; reconstruct needs at least 2"
        )
    mask, mask_shares, fov = _masks(images, opts, info, field)
    skipped: list[str] = []
    if opts.skip_blurred:
        from imageform.geometry import blurred_frames

        blur = blurred_frames(images, fov)
        skipped = [nm for nm, b in zip(names, blur.tolist(), strict=True) if b]
        keep_i = np.flatnonzero(~blur).tolist()
        images = [images[i] for i in keep_i]
        names = [names[i] for i in keep_i]
        if isinstance(mask, list):
            mask = [mask[i] for i in keep_i]
        if len(images) < 2:
            raise InvalidInputError(
                f"{frames}: {len(images)} sharp frame (--skip-blurred left out "
                f"{len(skipped)}); reconstruct needs at least 2"
            )
    seconds["read"] = time.perf_counter() - t0
    ahead.start("reconstruct")  # a first run: its kernels compiled on two cores
    if run.progress is not None:
        run.progress("reconstructing", 0.1)
    t1 = time.perf_counter()
    try:
        rec = reconstruct_sequence(
            images,
            K,
            distortion,
            window=opts.window,
            max_features=opts.max_features,
            ratio=opts.ratio,
            masks=mask,
            contrast_threshold=opts.contrast_threshold,
            refine_focal=refine,
            equalize=opts.equalize,
            refine_distortion=refine_lens,
            overlays=not opts.keep_overlays,
        )
    except DegenerateConfigurationError as exc:
        raise DegenerateConfigurationError(f"{frames}: {exc}{_hint(opts)}") from exc
    except InvalidInputError as exc:
        if not str(exc).startswith("no texture"):  # the frames' texture, not an option
            raise
        raise InvalidInputError(f"{frames}: {exc}{_hint(opts)}") from exc
    seconds["reconstruct"] = time.perf_counter() - t1
    # fx: the frame's and its field's (a field halves fy)
    intrinsics["refined"] = refine
    intrinsics["focal_px"] = float(np.asarray(K if rec.K is None else rec.K)[0, 0])
    # held: the focal length a bundle adjustment refining it finds (the given K's check)
    intrinsics["focal_px_fit"] = rec.focal_fit_px
    # refined: how well the frames fix it (its standard deviation; None: not refined, or
    # too few frames), and whether that is within 10 % (the result's one verdict)
    sd = rec.focal_sd_px
    intrinsics["focal_px_sd"] = None if sd is None or not np.isfinite(sd) else float(sd)
    intrinsics["focal_fixed"] = rec.focal_fixed
    # the camera found (the frame's, not its field's: the refinement scales fx and fy alike)
    K_out = np.array(K_frame, np.float64)
    K_out[:2, :2] *= intrinsics["focal_px"] / float(np.asarray(K)[0, 0])
    lens = rec.distortion if refine_lens else distortion
    intrinsics["distortion_refined"] = refine_lens
    intrinsics["k1"] = float(getattr(lens, "k1", 0.0)) if refine_lens else None
    # the lens model refined: COLMAP's SIMPLE_RADIAL, or the equidistant fisheye with one
    # Kannala-Brandt term where SIMPLE_RADIAL ran off and the fisheye fits (reconstruct_sequence)
    intrinsics["model"] = (
        ("KANNALA_BRANDT" if type(lens).__name__ == "KannalaBrandt" else "SIMPLE_RADIAL")
        if refine_lens
        else None
    )
    # the radial term's check: the camera ran off (a fisheye) or the term cost frames, and
    # what was held instead (reconstruct_sequence's note); None when the term stood
    intrinsics["fallback"] = next(
        (n for n in rec.notes if n.startswith(("the camera ran off", "the radial term cost"))),
        None,
    )
    # the equidistant fisheye tried (SIMPLE_RADIAL ran off, or its barrel term was strong):
    # what it found and whether it was kept; None when not tried
    intrinsics["fisheye"] = next((n for n in rec.notes if n.startswith("the fisheye tried")), None)
    del images
    folder = run.folder(out)
    t2 = time.perf_counter()
    with open(folder / "cameras.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(CAMERA_COLUMNS)
        for i, name in enumerate(names):
            ok = bool(rec.registered[i])
            r = np.asarray(matrix_to_rvec(rec.R[i]), np.float64) if ok else np.full(3, np.nan)
            t = rec.t[i] if ok else np.full(3, np.nan)
            w.writerow(
                [str(i), name, str(int(ok)), *(_fmt(float(v)) for v in (*r, *t)),
                 _fmt(float(rec.rms_px[i]))]
            )  # fmt: skip
    write_points_ply(
        folder / "points.ply",
        rec.points,
        rec.colors,
        rec.track_length,
        comment=f"imageform reconstruct {Path(frames).name}: the world is the camera frame of "
        "the first registered frame",
    )
    write_camera(
        folder / "camera.toml",
        Camera(K_out, distortion=lens, image_size=(info.width, info.height)),
        provenance=Provenance(
            command="imageform reconstruct",
            based_on=None if opts.camera is None else str(opts.camera),
            rms_px=_metrics_rms(rec),
            views_used=int(np.sum(rec.registered)),
            points_used=int(rec.points.shape[0]),
            fixed=tuple(
                [*([] if refine else ["focal length"]), "principal point"]
                + ([] if refine_lens else ["distortion"])
            ),
        ),
    )
    seconds["write"] = time.perf_counter() - t2
    metrics = {
        "format": METRICS_FORMAT,
        "version": 1,
        "source": {"frames": frames, "width": info.width, "height": info.height},
        "camera": None if opts.camera is None else str(opts.camera),
        "intrinsics": intrinsics,
        **_metrics(rec, names, seconds),
        "masks": mask_shares,
        "deinterlace": deinterlace_summary(reader),
        "skipped_blurred": skipped,
        "options": {k: (str(v) if isinstance(v, Path) else v) for k, v in asdict(opts).items()},
    }
    if run.progress is not None:
        run.progress("writing the report", 0.95)
    t3 = time.perf_counter()
    write_report(folder / "report.html", rec, names, metrics, title_source=frames)
    seconds["report"] = time.perf_counter() - t3
    metrics["seconds"] = {k: round(v, 3) for k, v in seconds.items()}
    write_json(folder / "metrics.json", metrics)
    if cam is None or refine or refine_lens:
        run.note(f"note: {_camera_note(intrinsics, first)}")
    deint = deinterlace_note(reader, info.fps, "reconstructing from")
    if deint:
        run.note(f"note: {deint}")
    if skipped:
        run.note(f"note: left out {len(skipped)} blurred frames: {', '.join(skipped)}")
    for note in rec.notes:
        run.note(f"note: {note}")
    n, nreg = metrics["frames"], metrics["registered"]
    summary: dict[str, Any] = {
        "frames_source": frames,
        "out": out,
        "cameras": out / "cameras.csv",
        "points_file": out / "points.ply",
        "report": out / "report.html",
        "metrics": out / "metrics.json",
        "camera_file": out / "camera.toml",
        **{k: v for k, v in metrics.items() if k not in ("format", "version", "options")},
    }
    med, rms = metrics["reprojection_px_median"], metrics["reprojection_px_rms"]
    total = sum(seconds.values())
    text = (
        f"{frames}: {n} frames ({info.width}x{info.height}), {nreg} registered "
        f"({100 * nreg / n:.0f} %), {metrics['points']} points, mean track length "
        f"{metrics['track_length_mean'] or 0:.2f}",
        "reprojection error "
        + (f"median {med:.3f} px, RMS {rms:.3f} px" if med is not None else "-")
        + f"; {total:.1f} s ("
        + ", ".join(f"{k} {v:.1f} s" for k, v in seconds.items())
        + ")",
        f"cameras.csv, points.ply, camera.toml, report.html, metrics.json -> {out}",
    )
    return Result(summary, text)


#: What the output folder holds (its --help, and the refusal of a file name for it).
_HOLDS = "cameras.csv, points.ply, camera.toml, report.html, metrics.json"

WORKFLOWS = (
    Workflow(
        "reconstruct",
        "Camera poses and a coloured 3-D point cloud from a video (structure from motion).",
        "imageform.workflows.reconstruct:reconstruct",
        ReconstructOptions,
        (
            Input(
                "frames",
                "A video file (needs imageform[video]), a folder or a glob of images, in order.",
                metavar="FRAMES",
                kind="text",
            ),
        ),
        Output(f"Output folder: {_HOLDS} (replaced whole).", folder=True, holds=_HOLDS),
        group="geometry",
        description="SIFT keypoints matched between neighbouring frames (--window), each pair "
        "verified by its essential matrix (RANSAC), the pair with the most parallax first, "
        "the other frames registered by PnP, the points triangulated, then bundle adjustment "
        "of every pose and point (needs imageform[reconstruct]); without --camera the focal "
        "length from the EXIF or 1.2 x max(width, height), refined; --mask keeps the keypoints to "
        "a region of every frame, --auto-mask finds an endoscope's aperture, --highlights keeps "
        "them off specular highlights. The world is the camera "
        "frame of the first registered frame (frame 0 when registered), the initial pair's "
        "baseline 1. cameras.csv: "
        "frame,name,registered,rx,ry,rz,tx,ty,tz,rms_px (world to camera); points.ply: x,y,z, "
        "colour, track_length. docs/reconstruction.md.",
    ),
)
