"""The simulation report: one self-contained ``report.html``, ``metrics.json`` and stage PNGs.

Every stage is written as a PNG file.

:func:`write_report` turns a :class:`~imageform.simulate.SimulationResult` into::

    out_dir/report.html            figures embedded as base64 data: URIs (plots PNG, stage
                                   pictures JPEG, each linking to its lossless PNG in
                                   stages/), inline CSS, no external URL, no script
    out_dir/metrics.json           the numbers (layout: imageform.report.metrics)
    out_dir/stages/NN-name.png     each stage as displayed (8-bit sRGB)
    out_dir/stages/NN-name-dn.png  raw stages' digital numbers as 16-bit PNG
                                   (a float TIFF ``-dn.tif`` when they are not whole numbers)
"""

from __future__ import annotations

import os
import re
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from imageform._jsonio import write_json
from imageform._validate import check_path, describe
from imageform.errors import InvalidInputError
from imageform.report import html_parts as hp
from imageform.report.metrics import (
    METRICS_VERSION,
    PLACED_METRICS,
    TOP_LEVEL_METRICS,
    to_json_value,
)
from imageform.simulate.result import STAGE_KINDS, SimulationResult, Stage

__all__ = ["ReportPaths", "write_report"]

_OUR_STAGE_FILE = re.compile(r"^\d{2,}-[A-Za-z0-9_.-]+\.(png|tif)$")


@dataclass(frozen=True)
class ReportPaths:
    """What :func:`write_report` wrote.

    ``html`` (report.html), ``metrics`` (metrics.json), ``stages`` (one display PNG per stage, in
    order), ``raw_files`` (the raw stages' digital numbers), ``summary`` (the headline numbers, as
    in metrics.json) and ``seconds`` (how long writing took).
    """

    out_dir: Path
    html: Path
    metrics: Path
    stages: tuple[Path, ...]
    raw_files: tuple[Path, ...] = ()
    summary: dict[str, Any] = field(default_factory=dict)
    seconds: float = 0.0


def _slug(name: str) -> str:
    s = re.sub(r"[^A-Za-z0-9_.-]+", "-", name).strip("-.")
    return s or "stage"


def _check_result(result: Any) -> SimulationResult:
    if not isinstance(result, SimulationResult):
        raise InvalidInputError(
            f"expected result as a SimulationResult, got {type(result).__name__}"
        )
    if not result.stages:
        raise InvalidInputError("expected at least one stage in the SimulationResult, got none")
    for i, s in enumerate(result.stages):
        if s.kind not in STAGE_KINDS:
            raise InvalidInputError(
                f"stage {i} ({describe(s.name)}) has kind {describe(s.kind)}; valid: "
                f"{', '.join(STAGE_KINDS)}"
            )
    if result.stages[-1].kind != "srgb":
        raise InvalidInputError(
            f"expected the last stage to be the encoded 'srgb' output, got kind "
            f"{describe(result.stages[-1].kind)} ({describe(result.stages[-1].name)})"
        )
    w, h = result.image_size
    if tuple(np.shape(result.stages[-1].image)[:2]) != (h, w):
        raise InvalidInputError(
            f"expected the output image to be {h}x{w} (image_size {(w, h)}), got shape "
            f"{np.shape(result.stages[-1].image)}"
        )
    to_json_value(result.metrics, "metrics")  # fail before drawing anything
    to_json_value(result.config, "config")
    return result


def _prepare_out_dir(out_dir: Path, force: bool) -> Path:
    if out_dir.exists() and not out_dir.is_dir():
        raise InvalidInputError(f"output {out_dir} exists and is not a folder")
    existing = [p for p in (out_dir / "report.html", out_dir / "metrics.json") if p.exists()]
    if existing and not force:
        raise InvalidInputError(
            f"a report exists in {out_dir} ({existing[0].name}); pass force=True (--force) "
            "to overwrite it"
        )
    stages = out_dir / "stages"
    stages.mkdir(parents=True, exist_ok=True)
    for p in stages.iterdir():  # stale stage files of an earlier report (only ours)
        if p.is_file() and _OUR_STAGE_FILE.match(p.name):
            p.unlink()
    return stages


def _fast_png(image: np.ndarray) -> bytes:
    """Encode a uint8/uint16 array as lossless PNG bytes, for speed.

    libpng through imagecodecs: zlib level 1, run-length strategy, the Sub filter, as OpenCV's fast
    setting: noisy camera images hardly compress further, and the default settings cost 3-40x the
    time. The report folder is swapped in whole, so no atomic write is needed here.
    """
    import imagecodecs

    return bytes(imagecodecs.png_encode(image, level=1, strategy=3, filter=16))


def _write_stage(
    stage: Stage, index: int, folder: Path
) -> tuple[Path, Path | None, bytes, np.ndarray]:
    """Write the stage's lossless display PNG (and raw digital numbers).

    Return the paths, the page's compressed picture of it (JPEG, see :func:`html_parts.page_jpeg`)
    and the displayed 8-bit image. Safe to run in a thread (the encoders release the GIL).
    """
    from imageform.io.image_io import write_image
    from imageform.report.display import raw_to_uint16, stage_display_image

    shown = stage_display_image(stage.image, stage.kind, white_level=stage.white_level)
    base = f"{index:02d}-{_slug(stage.name)}"
    path = folder / f"{base}.png"
    path.write_bytes(_fast_png(shown))
    raw_path = None
    if stage.kind == "raw":
        dn = raw_to_uint16(stage.image)
        if dn is not None:
            raw_path = folder / f"{base}-dn.png"
            raw_path.write_bytes(_fast_png(dn))
        else:
            raw_path = folder / f"{base}-dn.tif"
            write_image(raw_path, np.asarray(stage.image, dtype=np.float32))
    return path, raw_path, hp.page_jpeg(shown), shown


def _stage_section(result: SimulationResult, jpegs: list[bytes], files: list[Path]) -> str:
    parts = []
    for i, (s, jpg, f) in enumerate(zip(result.stages, jpegs, files, strict=True)):
        shape = "×".join(str(d) for d in np.shape(s.image))
        extra = f", white level {s.white_level:g} DN" if s.white_level is not None else ""
        cap = (
            f"<b>{i}. {hp.e(s.title)}</b> — {hp.e(s.description)}"
            f'<br><span class="meta">{s.seconds:.3f} s · kind {hp.e(s.kind)}{hp.e(extra)} · '
            f"{hp.e(shape)} "
            f"{hp.e(np.asarray(s.image).dtype)} · "
            f'<a href="stages/{hp.e(f.name)}">stages/{hp.e(f.name)}</a> (lossless)</span>'
        )
        parts.append(
            hp.figure(
                jpg,
                s.title,
                cap,
                fig_id=f"stage-{i}",
                photo=True,
                mime="image/jpeg",
                href=f"stages/{f.name}",
            )
        )
    intro = (
        "<p>Every stage of the chain in order. Linear-light stages are shown with their 99th "
        "percentile as white and the sRGB transfer function; raw stages as grey, digital "
        "number over white level; the output as it is. The page shows each as a JPEG; click "
        "one for its lossless PNG in stages/.</p>"
    )
    return hp.section("stages", "Stages of the image formation", intro + "".join(parts))


def _colour_section(result: SimulationResult, m: Any, notes: list[str]) -> str:
    from imageform.report.figures_color import (
        plot_delta_e,
        plot_patch_chromaticity,
        plot_patch_snr,
    )

    body = []
    fig = plot_patch_chromaticity(result, m)
    if fig is None:
        n = "No patch chromaticities in this result: the chromaticity diagram is left out."
        notes.append(n)
        body.append(hp.note(n))
    else:
        body.append(
            hp.figure(
                hp.figure_png(fig),
                "chromaticity diagram",
                "ColorChecker patches on the CIE 1931 xy diagram at each stage "
                f"({hp.e(', '.join(k.replace('_', ' ') for k in result.patch_xy))})"
                + (", and the ground truth" if m is not None else "")
                + "; a thin line joins each patch's positions.",
                "chromaticity",
            )
        )
    if m is None:
        n = "No ColorChecker in this scene: ΔE00 and SNR per patch are left out."
        notes.append(n)
        body.append(hp.note(n))
        return hp.section("colour", "Colour", "".join(body))
    body.append(
        hp.figure(
            hp.figure_png(plot_delta_e(m)),
            "CIEDE2000 per patch",
            f"CIEDE2000 of every patch of the output against the D65 ground truth "
            f"(delta_e00): delta_e00_mean {m.delta_e00_mean:.2f}, "
            f"delta_e00_max {m.delta_e00_max:.2f}.",
            "delta-e",
        )
    )
    rows = []
    for i, name in enumerate(m.names):
        sw = "#" + "".join(f"{round(float(c) * 255):02x}" for c in np.clip(m.truth_srgb[i], 0, 1))
        rows.append(
            [
                i + 1,
                hp.Markup(f'<span class="swatch" style="background:{sw}"></span> {hp.e(name)}'),
                " ".join(f"{v:.1f}" for v in m.lab_truth[i]),
                " ".join(f"{v:.1f}" for v in m.lab_measured[i])
                if np.all(np.isfinite(m.lab_measured[i]))
                else "—",
                f"{m.delta_e00[i]:.2f}" if np.isfinite(m.delta_e00[i]) else "—",
                m.readings[i],
                f"{m.snr_luminance_db[i]:.1f}"
                if np.isfinite(m.snr_luminance_db[i])
                else ("∞" if m.snr_luminance_db[i] > 0 else "—"),
            ]
        )
    body.append(
        hp.table(
            [
                "#",
                "name",
                "lab_truth (L* a* b*)",
                "lab_measured (L* a* b*)",
                "delta_e00",
                "reading",
                "snr_luminance_db",
            ],
            rows,
            left=(1, 5),
        )
    )
    body.append(
        "<p>Readings follow the lecture: below 1 imperceptible, about 2 just noticeable, "
        "above 10 obviously different.</p>"
    )
    body.append(
        hp.figure(
            hp.figure_png(plot_patch_snr(m)),
            "SNR per patch",
            "snr_luminance_db: the signal-to-noise ratio 20 log10(mean(Y) / std(Y)) of the "
            "luminance Y = 0.2126 R + 0.7152 G + 0.0722 B of each patch window on stage "
            f"'{hp.e(m.snr_stage)}' (the report's one SNR).",
            "snr",
        )
    )
    return hp.section("colour", "Colour", "".join(body))


def _geometry_section(
    result: SimulationResult,
    top: dict[str, Any],
    vp: dict[str, Any] | None,
    shown: np.ndarray,
    notes: list[str],
) -> str:
    from imageform.report.figures_geometry import plot_top_view, vanishing_overlay

    c = top["camera_center_m"]
    up = ", ".join(f"{x:g}" for x in top["world_up"])
    body = [
        hp.figure(
            hp.figure_png(plot_top_view(top)),
            "top view",
            f"The scene from above, looking down the world's up axis ({up}), the camera "
            f"looking up the page: {len(top['quads_m'])} objects, the camera centre "
            f"(camera_center_m) at ({c[0]:.3f}, {c[1]:.3f}, {c[2]:.3f}) m and the frustum "
            "rays through the image corners.",
            "top-view",
        )
    ]
    if vp is None:
        n = "No rails in this scene: the vanishing point and horizon are left out."
        notes.append(n)
        body.append(hp.note(n))
    else:
        im = vanishing_overlay(result, shown)
        t = vp["vanishing_point_px"]
        det = vp["detected_vanishing_point_px"]
        where = f"({t[0]:.1f}, {t[1]:.1f}) px" if t[2] == 1 else "at infinity"
        if det is None:
            found = "The detector found no vanishing point."
        elif det[2] != 1:
            found = "The detector put it at infinity."
        else:
            found = (
                f"Detected at ({det[0]:.1f}, {det[1]:.1f}) px, "
                f"{vp['vanishing_point_error_px']:.2f} px from the truth "
                "(vanishing_point_error_px)."
            )
        body.append(
            hp.figure(
                hp.page_jpeg(im),
                "vanishing point and horizon",
                "The output image with the rails' true vanishing point and horizon (green) and "
                f"the detected ones (orange). True vanishing point {hp.e(where)}. {hp.e(found)}",
                "vanishing",
                photo=True,
                mime="image/jpeg",
            )
        )
    return hp.section("geometry", "Geometry", "".join(body))


def _sensor_section(ptc: dict[str, Any] | None, notes: list[str]) -> str:
    from imageform.report.figures_color import plot_photon_transfer

    if ptc is None:
        n = "No photon-transfer measurement in this result: the sensor section is left out."
        notes.append(n)
        return hp.section("sensor", "Sensor", hp.note(n))
    cap = "Temporal variance against mean signal of flat-field pairs (EMVA 1288)."
    if ptc["fit"] is None:
        n = f"The photon-transfer fit failed: {ptc.get('fit_error', '')}"
        notes.append(n)
        cap += " " + hp.e(n)
    fig = plot_photon_transfer(ptc)
    return hp.section(
        "sensor", "Sensor", hp.figure(hp.figure_png(fig), "photon transfer", cap, "ptc")
    )


def write_report(
    result: SimulationResult, out_dir: str | Path, *, force: bool = False
) -> ReportPaths:
    """Write the simulation report of ``result`` into ``out_dir`` (created if needed).

    Writes ``report.html`` (one self-contained file: every figure a base64 ``data:`` URI,
    plots as PNG, stage pictures as JPEG at most 1280 px wide, each linking to its lossless
    PNG in ``stages/`` by a relative link; inline CSS, no external URL, nothing to run),
    ``metrics.json`` (see :mod:`imageform.report.metrics`) and ``stages/NN-name.png`` for
    every stage (displayed with :func:`imageform.report.display.stage_display_image`), plus
    ``NN-name-dn.png``
    (16-bit) with the digital numbers of raw stages.

    Sections: the stages; colour (the patches on the chromaticity diagram at each stage of
    ``patch_xy``, CIEDE2000 per patch with the lecture's reading, SNR per patch); geometry
    (the scene and frustum from above, the true and detected vanishing point and horizon);
    sensor (the photon-transfer curve and its EMVA 1288 fit). A part the result lacks
    (no ColorChecker, no rails, no photon-transfer data) is left out with a note.

    Raises
    ------
    InvalidInputError
        ``report.html`` or ``metrics.json`` exists in ``out_dir`` and ``force`` is False;
        a stage of unknown kind; a last stage that is not ``"srgb"``.
    """
    import matplotlib

    from imageform.report.figures_color import photon_transfer_summary
    from imageform.report.figures_geometry import top_view_data, vanishing_summary
    from imageform.report.patches import measure_patches

    t0 = time.perf_counter()
    res = _check_result(result)
    check_path(out_dir, "out_dir")
    out = Path(out_dir)
    folder = _prepare_out_dir(out, force)
    if matplotlib.get_backend().lower() != "agg":
        matplotlib.use("Agg")
    # The stage files (display, lossless PNG, page JPEG) are written by worker threads
    # while this thread draws the figures: the image work is in numpy and the encoders,
    # which release the GIL. The overlay of the vanishing point needs the output first.
    workers = max(1, min(4, os.cpu_count() or 1))
    with ThreadPoolExecutor(max_workers=workers) as pool:
        jobs = [pool.submit(_write_stage, s, i, folder) for i, s in enumerate(res.stages)]
        m = measure_patches(res)
        top = top_view_data(res)
        vp = vanishing_summary(res)
        ptc = photon_transfer_summary(res)
        notes: list[str] = []
        colour = _colour_section(res, m, notes)
        done = [j.result() for j in jobs]
    files = [d[0] for d in done]
    raws = [d[1] for d in done if d[1] is not None]
    shown = done[-1][3]  # the output, "srgb": displayed as it is
    sections = [
        _stage_section(res, [d[2] for d in done], files),
        colour,
        _geometry_section(res, top, vp, shown, notes),
        _sensor_section(ptc, notes),
    ]
    metrics = _metrics(res, files, raws, m, top, vp, ptc, notes)
    summary = {
        "simulation_time_s": metrics["simulation_time_s"],
        "delta_e00_mean": cc["delta_e00_mean"] if (cc := metrics["colorchecker"]) else None,
        "delta_e00_max": cc["delta_e00_max"] if cc else None,
        "vanishing_point_error_px": (
            metrics["vanishing"]["vanishing_point_error_px"] if metrics["vanishing"] else None
        ),
        "system_gain_dn_per_e": (
            fit["system_gain_dn_per_e"]
            if (pt := metrics["photon_transfer"]) and (fit := pt["fit"])
            else None
        ),
    }
    metrics_path = out / "metrics.json"
    write_json(metrics_path, metrics)
    sections.append(_numbers_section(metrics))
    w, h = res.image_size
    t_sim = summary["simulation_time_s"]
    sub = (
        f"<p>Scene <b>{hp.e(res.scene_name)}</b> · {w}×{h} px · {len(res.stages)} stages"
        + (f" · simulation_time_s {t_sim:.2f}" if t_sim is not None else "")
        + (f" · delta_e00_mean {m.delta_e00_mean:.2f}" if m is not None else "")
        + (
            f" · vanishing_point_error_px {vp['vanishing_point_error_px']:.2f}"
            if vp is not None and vp["vanishing_point_error_px"] is not None
            else ""
        )
        + "</p>"
    )
    nav = [
        ("stages", "Stages"),
        ("colour", "Colour"),
        ("geometry", "Geometry"),
        ("sensor", "Sensor"),
        ("numbers", "Numbers"),
    ]
    html_path = out / "report.html"
    html_path.write_text(
        hp.page(f"imageform simulation: {res.scene_name}", sub, nav, "".join(sections)),
        encoding="utf-8",
    )
    return ReportPaths(
        out_dir=out,
        html=html_path,
        metrics=metrics_path,
        stages=tuple(files),
        raw_files=tuple(raws),
        summary=to_json_value(summary),
        seconds=time.perf_counter() - t0,
    )


def _metrics(
    res: SimulationResult,
    files: list[Path],
    raws: list[Path],
    m: Any,
    top: dict[str, Any],
    vp: dict[str, Any] | None,
    ptc: dict[str, Any] | None,
    notes: list[str],
) -> dict[str, Any]:
    """metrics.json (layout: :mod:`imageform.report.metrics`): each quantity once."""
    raw_iter = iter(raws)
    stages = [
        {
            "index": i,
            "name": s.name,
            "title": s.title,
            "description": s.description,
            "kind": s.kind,
            "white_level_dn": s.white_level,
            "shape": list(np.shape(s.image)),
            "dtype": str(np.asarray(s.image).dtype),
            "file": f"stages/{f.name}",
            "raw_file": f"stages/{next(raw_iter).name}" if s.kind == "raw" else None,
        }
        for i, (s, f) in enumerate(zip(res.stages, files, strict=True))
    ]
    cc = None
    if m is not None:
        cc = {
            "snr_stage": m.snr_stage,
            "delta_e00_mean": m.delta_e00_mean,
            "delta_e00_max": m.delta_e00_max,
            "patches": [
                {
                    "name": n,
                    "lab_truth": m.lab_truth[i],
                    "lab_measured": m.lab_measured[i],
                    "delta_e00": m.delta_e00[i],
                    "reading": m.readings[i],
                    "snr_luminance_db": m.snr_luminance_db[i],
                    "xy": {k: np.asarray(v)[i] for k, v in res.patch_xy.items()},
                }
                for i, n in enumerate(m.names)
            ],
        }
    pipeline = res.metrics
    top_level = {k: pipeline.get(k) for k in TOP_LEVEL_METRICS}
    if top_level["step_times_s"] is None:  # a result without the simulator's timings
        top_level["step_times_s"] = {s.name: s.seconds for s in res.stages}
    w, h = res.image_size
    out = {
        "metrics_version": METRICS_VERSION,
        "scene_name": res.scene_name,
        "image_size_px": {"width": w, "height": h},
        **top_level,
        "colorchecker": cc,
        "vanishing": vp,
        "photon_transfer": ptc,
        "top_view": top,
        "stages": stages,
        "other_metrics": {k: v for k, v in pipeline.items() if k not in PLACED_METRICS},
        "config": res.config,
        "notes": notes,
    }
    return dict(to_json_value(out))


def _numbers_section(metrics: dict[str, Any]) -> str:
    scalars = {
        k: v
        for k, v in metrics.items()
        if k not in ("metrics_version", "scene_name")
        and (v is None or isinstance(v, int | float | str))
    }
    for part in ("colorchecker", "vanishing"):
        if metrics[part]:
            scalars |= {
                f"{part}.{k}": v
                for k, v in metrics[part].items()
                if v is None or isinstance(v, int | float | str)
            }
    if metrics["photon_transfer"] and metrics["photon_transfer"]["fit"]:
        scalars |= {
            f"photon_transfer.fit.{k}": v for k, v in metrics["photon_transfer"]["fit"].items()
        }
    scalars |= {
        f"other_metrics.{k}": v
        for k, v in metrics["other_metrics"].items()
        if v is None or isinstance(v, int | float | str)
    }
    rows = [
        [k, "—" if v is None else (f"{v:.4g}" if isinstance(v, float) else v)]
        for k, v in scalars.items()
    ]
    body = (
        "<p>The numbers of metrics.json, by their field names (units in the names; "
        "docs/simulate-report.md defines each):</p>" + hp.table(["field", "value"], rows, left=(0,))
    )
    body += hp.json_block(metrics, "metrics.json (everything above as numbers)")
    if metrics["config"]:
        body += hp.json_block(metrics["config"], "the scene description")
    return hp.section("numbers", "Numbers", body)
