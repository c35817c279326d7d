"""``imageform vanishing``: vanishing points, K and the horizon of a photograph.

Where no vanishing point gives the horizon, it is the visible one when the photograph shows
open water or flat land (:func:`~imageform.geometry.detect_horizon`; ``horizon_source`` says
which). ``imageform horizon`` gives that one alone.

Without a camera file, K is estimated from the orthogonal triplet of vanishing points
(principal point at the image centre by default, ``--principal-point``). With ``--camera``
the file's camera is the truth: the image is undistorted with its model first (lines are
straight only without distortion), the vertical direction and the horizon come from its K,
and the K estimated from the vanishing points is reported with its error against the file's
(``--principal-point camera``: with the file's principal point, the focal length alone).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Literal, get_args

from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.workflows._images import ImageIn, read, write
from imageform.workflows._spec import Input, Output, Result, Run, Workflow, option

__all__ = ["WORKFLOWS", "HorizonOptions", "VanishingOptions"]


#: ``--principal-point`` ("centre" and "orthocentre": the spellings before issue 30).
_PrincipalPoint = Literal["center", "estimate", "orthocenter", "camera", "centre", "orthocentre"]


@dataclass(frozen=True, kw_only=True)
class VanishingOptions(ImageIn):
    """Options of ``imageform vanishing``."""

    camera: Path | None = option(
        None,
        help="Camera file of the photograph: its K gives the vertical and the horizon (the "
        "K from the vanishing points is reported against it); its distortion is removed "
        "first; with a pose, each vanishing point is matched to a world axis.",
        metavar="FILE",
        input=True,
    )
    distortion: bool = option(
        False,
        help="Estimate the lens distortion from the photograph's own straight lines (plumb "
        "lines, division model) and remove it before finding lines (without --camera).",
    )
    seed: int = option(
        0, help="RANSAC seed, an integer (rng= in Python): results are reproducible.", minimum=0
    )
    max_size: int | None = option(
        None,
        help="Find the line segments on a copy at most N px on its long side (the answers are "
        "in the photograph's pixels); default: the photograph as it is.",
        metavar="N",
        minimum=16,
    )
    principal_point: _PrincipalPoint = option(
        "center",
        # "centre" and "orthocentre": the spellings before issue 30, still accepted
        choices=get_args(_PrincipalPoint),
        help="Where the estimated K's principal point is: the image centre; 'estimate': the "
        "orthocentre of three finite, well-supported, consistent vanishing points where it "
        "lies within 20 % of the image's size of the centre and is tightly fixed (the centre "
        "otherwise, with a note why); 'orthocenter': that of any three finite points "
        "(unguarded); or the camera file's (needs --camera; the focal length is then "
        "estimated alone).",
    )


@dataclass(frozen=True, kw_only=True)
class HorizonOptions(ImageIn):
    """Options of ``imageform horizon``."""

    max_roll_deg: float = option(
        30.0,
        help="The largest angle of the horizon to the image rows looked for (degrees, up to "
        "80; an aircraft's camera rolls beyond the default).",
        minimum=0.0,
        maximum=80.0,
    )


def _read_photo(image: Path, opts: ImageIn) -> Any:
    """Read ``image`` as the detectors take it: grey or RGB (alpha dropped), 16 bits as [0, 1]."""
    import numpy as np

    img = read(image, opts)
    arr = img[..., 0] if img.shape[-1] == 1 else img[..., :3]
    if arr.dtype == np.uint16:
        arr = arr.astype(np.float64) / 65535.0
    return arr


def _directions(K: Any, vps: Any) -> Any:
    import numpy as np

    d = np.linalg.solve(K, np.asarray(vps, dtype=np.float64).T).T
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def _with_known_K(res: Any, K: Any) -> tuple[Any, dict[str, Any]]:
    """Return the result with the vertical and the horizon from a known K, and the angles.

    The angles are those between the vanishing directions (90 degrees for a Manhattan scene).
    """
    import numpy as np

    from imageform.geometry import horizon_line

    vps = res.vanishing_points
    extra: dict[str, Any] = {"vp_angles_deg": []}
    if len(vps) < 2:
        return replace(res, K=K, vertical=None, horizon=None, horizon_spread=None), extra
    dirs = _directions(K, vps)
    vertical = int(np.argmax(np.abs(dirs[:, 1])))
    up = dirs[vertical] * (-1.0 if dirs[vertical, 1] > 0 else 1.0)  # image up is -y
    horizon = np.asarray(horizon_line(K, None, up))
    pairs = [(i, j) for i in range(len(dirs)) for j in range(i + 1, len(dirs))]
    extra["vp_angles_deg"] = [
        {
            "pair": [i, j],
            "angle": float(np.degrees(np.arccos(min(1.0, abs(float(dirs[i] @ dirs[j])))))),
        }
        for i, j in pairs
    ]
    # the spread measured the detector's own horizon, not this one
    return replace(res, K=K, vertical=vertical, horizon=horizon, horizon_spread=None), extra


def _world_axes(res: Any, K: Any, R: Any) -> list[dict[str, Any]]:
    """Return, for each vanishing point, the world axis whose direction it is closest to.

    The vanishing point of world axis i is ``K R e_i``.
    """
    import numpy as np

    if not len(res.vanishing_points):
        return []
    dirs = _directions(K, res.vanishing_points)
    axes = np.asarray(R, dtype=np.float64).T  # rows: world x, y, z in the camera frame
    cos = np.abs(dirs @ axes.T)
    out = []
    for k, row in enumerate(cos):
        i = int(np.argmax(row))
        out.append(
            {
                "vanishing_point": k,
                "axis": "xyz"[i],
                "angle_deg": float(np.degrees(np.arccos(min(1.0, float(row[i]))))),
            }
        )
    return out


def _remove_distortion(run: Run, arr: Any, image: Path) -> tuple[Any, dict[str, Any]]:
    """Return the photograph undistorted with the distortion of its straight lines, and it."""
    import numpy as np

    from imageform.geometry import estimate_distortion_from_lines
    from imageform.geometry.undistort import undistort_image

    est = estimate_distortion_from_lines(arr)
    info = {
        "k1": est.k1,
        "k1_std": est.k1_std,
        "k1_interval": list(est.k1_interval),
        "found": est.found,
        "scale_px": float(est.K[0, 0]),
        "lines": len(est.lines),
        "max_displacement_px": est.max_displacement_px,
    }
    if not est.found:
        run.note(
            f"note: no distortion found in the straight lines of {image} (k1 = {est.k1:.4f}): "
            "the photograph is used as it is"
        )
        return arr, info
    out = np.asarray(undistort_image(arr, est.K, est.distortion))
    run.note(
        f"note: {image} was undistorted with the distortion of its {len(est.lines)} straight "
        f"lines (division k1 = {est.k1:.4f} on coordinates over {est.K[0, 0]:.1f} px, corner "
        f"{est.max_displacement_px:.1f} px) before finding lines"
    )
    return out, info


def _spread_line(spread: float, h: int) -> str:
    """Return the text line on how far resampling the segments moves the horizon."""
    import math

    if not math.isfinite(spread):
        return (
            "  the horizon is loosely fixed: fewer than half of the resamples of the points' "
            "segments give one"
        )
    return (
        f"  the horizon moves by ±{spread * h:.1f} px ({100 * spread:.2f} % of the height) "
        "when the points' segments are resampled"
    )


def vanishing(run: Run, opts: VanishingOptions, *, out: Path | None, image: Path) -> Result:
    """``imageform vanishing``: line segments, vanishing points, K and the horizon."""
    import numpy as np

    from imageform._kernels import ahead
    from imageform.geometry import detect_vanishing_points

    if opts.distortion and opts.camera is not None:
        raise InvalidInputError(
            "--distortion estimates what --camera's file gives: use one of them"
        )
    arr = _read_photo(image, opts)
    h, w = int(arr.shape[0]), int(arr.shape[1])
    cf = None
    if opts.camera is not None:
        from imageform.io import read_camera

        cf = read_camera(opts.camera)
        size = cf.camera.image_size
        if size is not None and tuple(size) != (w, h):
            raise InvalidInputError(
                f"camera file {opts.camera} is for {size[0]} x {size[1]} px images, {image} "
                f"is {w} x {h} px"
            )
        if cf.camera.distortion is not None:
            from imageform.geometry.undistort import undistort_image

            arr = np.asarray(undistort_image(arr, np.asarray(cf.camera.K), cf.camera.distortion))
            run.note(
                f"note: {image} was undistorted with the {cf.distortion_model} model of "
                f"{opts.camera} before finding lines"
            )
    plumb: dict[str, Any] | None = None
    if opts.distortion:
        arr, plumb = _remove_distortion(run, arr, image)
    if opts.principal_point == "camera":
        if cf is None:
            raise InvalidInputError("--principal-point camera needs --camera FILE")
        pp: Any = np.asarray(cf.camera.K, dtype=np.float64)[:2, 2]
    else:
        pp = {"centre": "center", "orthocentre": "orthocenter"}.get(
            opts.principal_point, opts.principal_point
        )
    ahead.start("vanishing")  # a first run: its kernels compiled on two cores
    res = detect_vanishing_points(arr, rng=opts.seed, principal_point=pp, max_size=opts.max_size)
    if len(res.segments) < 2:
        # the library answers "none found" (an empty set); the command fails, as before
        raise DegenerateConfigurationError(
            f"found {len(res.segments)} line segment(s); vanishing points need at least two"
        )
    K_est = res.K
    summary: dict[str, Any] = {
        "image": image,
        "camera": opts.camera,
        "segments": len(res.segments),
        "distortion": plumb,
    }
    extra: dict[str, Any] = {}
    if cf is not None:
        K_file = np.asarray(cf.camera.K, dtype=np.float64)
        res, extra = _with_known_K(res, K_file)
        extra["K_source"] = "camera file"
        extra["K_estimated"] = K_est
        if K_est is not None:
            extra["focal_error_px"] = float(K_est[0, 0] - (K_file[0, 0] + K_file[1, 1]) / 2)
            extra["principal_point_error_px"] = float(np.hypot(*(K_est[:2, 2] - K_file[:2, 2])))
        if cf.has_pose:
            extra["world_axes"] = _world_axes(res, K_file, cf.camera.R)
    else:
        extra["K_source"] = "vanishing points" if K_est is not None else None
        from imageform.io import exif_camera

        exif = exif_camera(image)
        if exif.focal_length_px is not None:
            extra["exif_focal_length_px"] = exif.focal_length_px
            extra["exif_focal_length_source"] = exif.focal_length_px_source
    visible = False
    if res.horizon is None:
        # no vanishing point gives the horizon: the visible one of open water or flat land
        from imageform.geometry import detect_horizon

        seen = detect_horizon(arr)
        if seen.found:
            res, visible = replace(res, horizon=seen.line), True
    extra["horizon_source"] = (
        "visible (detect_horizon)"
        if visible
        else ("vanishing points" if res.horizon is not None else None)
    )
    summary.update(
        {
            "vanishing_points": res.vanishing_points,
            "support_px": res.scores,
            "vertical_index": res.vertical,
            "perspective": res.perspective,
            "K": res.K,
            "K_reason": res.K_reason,
            "K_note": res.K_note,
            "focal_spread": res.focal_spread,
            "horizon": res.horizon,
            "horizon_spread": res.horizon_spread,
            **extra,
            "overlay": out,
        }
    )
    if out is not None:
        from imageform.report.overlays import draw_vanishing_overlay

        write(run, out, np.asarray(draw_vanishing_overlay(arr, res)), opts)
    text = [f"{len(res.segments)} line segments; {len(res.vanishing_points)} vanishing points"]
    for j, v in enumerate(res.vanishing_points):
        tag = " (vertical)" if j == res.vertical else ""
        where = (
            f"({v[0]:.1f}, {v[1]:.1f})"
            if v[2] != 0
            else f"at infinity, direction ({v[0]:.3f}, {v[1]:.3f})"
        )
        text.append(f"  v{j}: {where}, support {res.scores[j]:.0f} px{tag}")
    text.append(f"perspective: {res.perspective}-point")
    if res.K is not None:
        k = res.K
        src = f" (from {opts.camera})" if cf is not None else " (from the vanishing points)"
        text.append(f"K: f = {k[0, 0]:.1f} px, principal point ({k[0, 2]:.1f}, {k[1, 2]:.1f}){src}")
        if cf is None and res.focal_spread is not None:
            text.append(
                f"  f moves by ±{100 * res.focal_spread:.1f} % when the points' segments are "
                "resampled (it rests on the scene's directions being orthogonal)"
            )
        if cf is None and res.K_note is not None:
            text.append(f"  note: {res.K_note}")
    elif res.K_reason is not None:
        text.append(f"K: {res.K_reason}")
    if "exif_focal_length_px" in extra:
        f_exif = extra["exif_focal_length_px"]
        line = f"EXIF: f ~ {f_exif:.0f} px (from its {extra['exif_focal_length_source']})"
        if res.K is not None:
            off = 100 * (res.K[0, 0] / f_exif - 1)
            line += f"; the vanishing points' f is {off:+.1f} % from it"
        text.append(line)
    if cf is not None and K_est is None and res.K_reason is not None:
        # the file gives K; say why the vanishing points gave none to report against it
        text.append(f"K from the vanishing points: {res.K_reason}")
    if "focal_error_px" in extra:
        text.append(
            f"K from the vanishing points: f = {K_est[0, 0]:.1f} px ("  # type: ignore[index]
            f"{extra['focal_error_px']:+.1f} px), principal point off by "
            f"{extra['principal_point_error_px']:.1f} px"
        )
    for a in extra.get("vp_angles_deg", []):
        i, j = a["pair"]
        text.append(f"  angle v{i}-v{j}: {a['angle']:.2f} deg")
    for a in extra.get("world_axes", []):
        text.append(
            f"  v{a['vanishing_point']}: world {a['axis']} axis, {a['angle_deg']:.2f} deg off"
        )
    if res.horizon is not None:
        a, b, c = res.horizon
        if abs(b) > 1e-12:
            text.append(
                f"horizon: v = {-c / b:.1f} at u = 0, {-(a * (w - 1) + c) / b:.1f} at u = {w - 1}"
            )
        else:
            text.append(f"horizon: vertical line u = {-c / a:.1f}")
        if visible:
            text.append("  the visible horizon (detect_horizon): no vanishing point gives one")
        elif res.horizon_spread is not None:
            text.append(_spread_line(res.horizon_spread, h))
    if out is not None:
        text.append(f"overlay -> {out}")
    return Result(summary, tuple(text))


def horizon(run: Run, opts: HorizonOptions, *, out: Path | None, image: Path) -> Result:
    """``imageform horizon``: the visible horizon of a sea, lake or plain."""
    import math

    import numpy as np

    from imageform.geometry import detect_horizon

    if not opts.max_roll_deg > 0:
        raise InvalidInputError(f"--max-roll-deg must be above 0, got {opts.max_roll_deg:g}")
    arr = _read_photo(image, opts)
    w = int(arr.shape[1])
    res = detect_horizon(arr, max_roll=math.radians(opts.max_roll_deg))
    if not res.found:  # as imageform chart: the one object looked for is not there
        raise DegenerateConfigurationError(f"no horizon found in the image: {res.reason}")
    summary: dict[str, Any] = {
        "image": image,
        "found": res.found,
        "horizon": res.line,
        "roll_deg": math.degrees(res.roll) if res.found else None,
        "rows": res.rows if res.found else None,
        "confidence": res.confidence,
        "reason": res.reason or None,
        "overlay": out,
    }
    text = [
        f"horizon: v = {res.rows[0]:.1f} at u = 0, {res.rows[1]:.1f} at u = {w - 1}; "
        f"roll {math.degrees(res.roll):+.2f} deg (right end higher: +)",
        f"  an edge along {100 * res.confidence:.0f} % of it across the frame",
    ]
    if out is not None:
        from imageform.report.overlays import draw_vanishing_truth_overlay

        # no vanishing point to draw (one at infinity is not drawn): the horizon alone
        canvas = draw_vanishing_truth_overlay(arr, [1.0, 0.0, 0.0], detected_horizon=res.line)
        write(run, out, np.asarray(canvas), opts)
        text.append(f"overlay -> {out}")
    return Result(summary, tuple(text))


WORKFLOWS = (
    Workflow(
        "vanishing",
        "Vanishing points, K and the horizon of a photograph; -o draws them on it.",
        "imageform.workflows.vanishing:vanishing",
        VanishingOptions,
        (Input("image", "A photograph (PNG, JPEG, TIFF, .npy, WebP, BMP, GIF, PGM/PPM)."),),
        Output(
            "Overlay image to write (segments by vanishing point, the horizon).", required=False
        ),
        suffixes=(".png", ".jpg", ".jpeg", ".tif", ".tiff"),
        group="geometry",
        description="Without --camera, K is estimated from three orthogonal vanishing points "
        "(square pixels, no skew). With --camera, the file's K and distortion are used and "
        "the estimated K is reported against them.",
    ),
    Workflow(
        "horizon",
        "The visible horizon of a sea, lake or plain photograph; -o draws it on it.",
        "imageform.workflows.vanishing:horizon",
        HorizonOptions,
        (Input("image", "A photograph (PNG, JPEG, TIFF, .npy, WebP, BMP, GIF, PGM/PPM)."),),
        Output("Overlay image to write (the horizon found).", required=False),
        suffixes=(".png", ".jpg", ".jpeg", ".tif", ".tiff"),
        group="geometry",
        description="The long straight edge between sky and open water or flat land "
        "(detect_horizon); 'not found' for streets, rooms, close-ups and mountains, where "
        "'imageform vanishing' gives the horizon from vanishing points instead.",
    ),
)
