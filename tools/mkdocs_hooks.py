"""MkDocs hooks for the documentation site (mkdocs.yml): the command-line reference is
generated from the command definitions (the workflow registry through click), so it cannot
drift from ``imageform --help``."""

from __future__ import annotations

from typing import Any

MARKER = "<!-- cli-reference -->"


def _command_help(name: str, command: Any, ctx_parent: Any) -> str:
    import click

    ctx = click.Context(command, info_name=name, parent=ctx_parent)
    text = command.get_help(ctx)
    return f"## `imageform {name}`\n\n```text\n{text}\n```\n"


def cli_reference() -> str:
    """Markdown: ``imageform --help``, then every command's ``--help``, in the root's order."""
    import click

    from imageform.cli import root

    ctx = click.Context(root, info_name="imageform")
    parts = ["```text\n" + root.get_help(ctx) + "\n```\n"]
    for name in root.list_commands(ctx):
        command = root.get_command(ctx, name)
        if command is not None and not getattr(command, "hidden", False):
            parts.append(_command_help(name, command, ctx))
    return "\n".join(parts)


def on_page_markdown(markdown: str, page: Any, **kwargs: Any) -> str:
    if MARKER in markdown:
        markdown = markdown.replace(MARKER, cli_reference())
    if BENCH_MARKER in markdown:
        from pathlib import Path

        markdown = markdown.replace(BENCH_MARKER, benchmark_results(Path(__file__).parents[1]))
    return markdown


# ------------------------------------------------------------------ benchmark tables

BENCH_MARKER = "<!-- benchmark-results -->"

#: Each committed results file's stem prefix (before the date) and the script that printed it.
#: tests/test_docs_site.py checks that every file in benchmarks/results/ is listed here.
BENCH_SCRIPTS: dict[str, str] = {
    "8bit": "benchmarks/bench_8bit.py",
    "calibration": "benchmarks/bench_calibration.py",
    "calibration-endoscope": "benchmarks/check_calibration_endoscope.py",
    "exif-focal": "benchmarks/check_exif_focal.py",
    "calibration-fisheye": "benchmarks/check_calibration_fisheye.py",
    "sim-dng": "benchmarks/check_sim_dng.py",
    "chart-detect": "benchmarks/bench_chart_detect.py",
    "chart-fresh": "benchmarks/check_chart_real.py",
    "chart-input": "benchmarks/check_chart_input.py",
    "chart-marks": "benchmarks/check_chart_marks.py",
    "chart-photos": "benchmarks/check_chart_photos.py",
    "chart-real": "benchmarks/check_chart_real.py",
    "chart-shape": "benchmarks/check_chart_shape.py",
    "chart-speed": "benchmarks/check_chart_speed.py",
    "chart-third": "benchmarks/check_chart_real.py",
    "board-fresh": "benchmarks/check_board_fresh.py",
    "calib-fresh": "benchmarks/check_calib_fresh.py",
    "board-third": "benchmarks/check_board_third.py",
    "charuco": "benchmarks/bench_charuco.py",
    "charuco-real": "benchmarks/check_charuco_real.py",
    "charuco-symmetric": "benchmarks/check_charuco_symmetric.py",
    "checkerboard": "benchmarks/bench_checkerboard.py",
    "checkerboard-large": "benchmarks/check_checkerboard_large.py",
    "checkerboard-real": "benchmarks/check_checkerboard_real.py",
    "checkerboard-refine": "benchmarks/bench_checkerboard_refine.py",
    "checkerboard-pyramid": "benchmarks/check_checkerboard_pyramid.py",
    "checkerboard-auto": "benchmarks/check_checkerboard_auto.py",
    "chunked": "benchmarks/bench_chunked.py",
    "chunked-strips": "benchmarks/bench_chunked.py",
    "color": "benchmarks/bench_color.py",
    "compile-ahead": "benchmarks/bench_compile_ahead.py",
    "compile-literals": "benchmarks/compile_literals.py",
    "compile-simulate": "benchmarks/bench_first_run.py",
    "corner-refinement": "benchmarks/check_corner_refinement.py",
    "dask-graphs": "benchmarks/check_dask_graphs.py",
    "dask-stains": "benchmarks/bench_dask_stains.py",
    "delta-e": "benchmarks/bench_delta_e.py",
    "demosaic": "benchmarks/bench_demosaic.py",
    "dicom": "benchmarks/check_dicom.py",
    "distortion": "benchmarks/bench_distortion.py",
    "emva": "benchmarks/bench_emva.py",
    "first-run": "benchmarks/bench_first_run.py",
    "flatfield": "benchmarks/check_flatfield.py",
    "fuzz": "tests/fuzz/__main__.py",
    "geometry": "benchmarks/bench_geometry.py",
    "gpu-cpu": "benchmarks/bench_gpu.py",
    "gpu-h200": "benchmarks/bench_gpu.py",
    "gpu-host-dry": "benchmarks/profile_gpu_host.py",
    "gpu-host-h200": "benchmarks/profile_gpu_host.py",
    "sass-colour": "benchmarks/sass_colour.py",
    "sass-demosaic": "benchmarks/sass_demosaic.py",
    "illuminant-fresh": "benchmarks/check_illuminant_fresh.py",
    "illuminant-real": "benchmarks/check_illuminant_real.py",
    "gpr": "benchmarks/check_gpr.py",
    "horizon-natural": "benchmarks/check_horizon_natural.py",
    "horizon-stress": "benchmarks/check_horizon_stress.py",
    "still-mask": "benchmarks/check_still_mask.py",
    "local-homography": "benchmarks/check_local_homography.py",
    "lsd": "benchmarks/bench_lsd.py",
    "locus": "benchmarks/bench_locus.py",
    "locus-device": "benchmarks/bench_locus_device.py",
    "odd-files": "benchmarks/check_odd_files.py",
    "partial-board": "benchmarks/check_partial_board.py",
    "plumb-line": "benchmarks/check_plumb_line.py",
    "psf": "benchmarks/bench_psf.py",
    "phone-dng": "benchmarks/check_phone_dng.py",
    "raw": "benchmarks/bench_raw.py",
    "raw-small": "benchmarks/bench_raw_small.py",
    "raw-fresh": "benchmarks/check_raw_fresh_e.py",  # before 2026-12-01: check_raw_fresh.py
    "raw-sweep": "benchmarks/check_raw_sweep.py",
    "raw-variants": "benchmarks/check_raw_variants.py",
    "read-threads": "benchmarks/bench_read_threads.py",
    "reconstruct": "benchmarks/bench_reconstruct.py",
    "endo-real": "benchmarks/check_endo_real.py",
    "interlace": "benchmarks/check_interlace.py",
    "sfm-fresh": "benchmarks/check_sfm_fresh.py",
    "sfm-autok": "benchmarks/check_sfm_fresh.py",
    "sfm-k1": "benchmarks/check_sfm_k1.py",
    "sfm-fisheye": "benchmarks/check_sfm_fisheye.py",
    "sfm-choice": "benchmarks/check_sfm_choice.py",
    "sfm-model-choice": "benchmarks/check_sfm_model_choice.py",
    "sfm-inliers": "benchmarks/check_sfm_inliers.py",
    "sfm-intruders": "benchmarks/check_sfm_intruders.py",
    "sfm-dense": "benchmarks/check_sfm_dense.py",
    "sfm-pycolmap16": "benchmarks/check_sfm_pycolmap16.py",
    "pair-pose": "benchmarks/check_pair_pose.py",
    "reconstruct-real": "benchmarks/bench_reconstruct_real.py",
    "reconstruct-fisheye": "benchmarks/bench_reconstruct_fisheye.py",
    "track-duplicates": "benchmarks/check_track_duplicates.py",
    "track-breaks": "benchmarks/check_track_breaks.py",
    "track-flips": "benchmarks/check_track_flips.py",
    "track-fresh": "benchmarks/check_track_fresh.py",
    "track-heldout": "benchmarks/check_track_heldout.py",
    "track-large": "benchmarks/check_track_large.py",
    "track-marker": "benchmarks/check_track_marker.py",
    "track-markers": "benchmarks/check_track_markers.py",
    "track-speed": "benchmarks/check_track_speed.py",
    "track-symmetric": "benchmarks/check_track_symmetric.py",
    "track-upscaled": "benchmarks/check_track_upscaled.py",
    "remap": "benchmarks/bench_remap.py",
    "report": "benchmarks/bench_report.py",
    "sfr": "benchmarks/bench_sfr.py",
    "sfr-real": "benchmarks/check_sfr_real.py",
    "sfr-fresh": "benchmarks/check_sfr_fresh.py",
    "stain": "benchmarks/bench_stain.py",
    "stain-glass": "benchmarks/check_stain_glass.py",
    "stain-artefacts": "benchmarks/check_stain_artefacts.py",
    "stain-real": "benchmarks/check_stain_real.py",
    "stain-fresh": "benchmarks/check_stain_fresh.py",
    "stain-ihc": "benchmarks/check_stain_fresh.py",
    "stain-ihcmask": "benchmarks/check_stain_ihc_fresh.py",
    "stain-scale": "benchmarks/check_stain_scale.py",
    "stain-wash": "benchmarks/check_stain_wash.py",
    "stain-dye": "benchmarks/check_stain_dye.py",
    "stain-fold": "benchmarks/check_stain_fold.py",
    "stain-ink": "benchmarks/check_stain_artefacts.py",
    "stereo-depth": "benchmarks/check_stereo_depth.py",
    "stereo-fresh": "benchmarks/check_stereo_fresh.py",
    "stereo-vertical": "benchmarks/check_stereo_vertical.py",
    "stereo-noise": "benchmarks/check_stereo_noise.py",
    "stereo-webcam": "benchmarks/check_stereo_webcam.py",
    "stereo-slant": "benchmarks/check_stereo_slant.py",
    "stereo-recess": "benchmarks/check_stereo_recess.py",
    "stereo-fill": "benchmarks/bench_stereo_fill.py",
    "stereo-speed": "benchmarks/bench_stereo_speed.py",
    "speed-audit": "benchmarks/speed_audit.py",
    "stereo-planes": "benchmarks/check_stereo_planes.py",
    "stereo-sgmp": "benchmarks/check_stereo_sgmp.py",
    "track": "benchmarks/bench_track.py",
    "twin-loop": "benchmarks/check_twin_loop.py",
    "twoview": "benchmarks/bench_twoview.py",
    "twoview-cap": "benchmarks/check_twoview_cap.py",
    "twoview-e": "benchmarks/bench_twoview.py",
    "twoview-f": "benchmarks/bench_twoview.py",
    "twoview-h": "benchmarks/bench_twoview.py",
    "twoview-real": "benchmarks/check_twoview_real.py",
    "twoview-seeds": "benchmarks/check_twoview_real.py",
    "vision": "benchmarks/bench_vision.py",
    "vp-fresh": "benchmarks/check_vp_fresh.py",
    "vp-lsd": "benchmarks/check_vp_lsd.py",
    "vp-manhattan": "benchmarks/check_vp_manhattan.py",
    "vp-real": "benchmarks/check_vp_real.py",
    "vp-seed": "benchmarks/check_vp_seed.py",
    "vp-stress": "benchmarks/check_vp_stress.py",
    "wsi": "benchmarks/bench_wsi.py",
    "wsi-real": "benchmarks/check_wsi_real.py",
}

#: ``NAME-YYYY-MM-DD.md``, or with a letter after the date for a later table of the same day
#: (``remap-2026-11-25b.md`` is newer than ``remap-2026-11-25.md``).
_DATED = r"^(?P<name>.+)-(?P<date>\d{4}-\d{2}-\d{2}[a-z]?)$"


def result_files(root: Any) -> dict[str, list[Any]]:
    """``{prefix: [results file, ...]}``, newest first, from ``root/benchmarks/results``."""
    import re
    from pathlib import Path

    found: dict[str, list[tuple[str, Path]]] = {}
    for path in sorted(Path(root, "benchmarks", "results").glob("*.md")):
        m = re.match(_DATED, path.stem)
        if m is None:
            raise ValueError(f"{path.name}: results files are named NAME-YYYY-MM-DD[a-z].md")
        found.setdefault(m["name"], []).append((m["date"], path))
    return {k: [p for _, p in sorted(v, reverse=True)] for k, v in sorted(found.items())}


def _demote(text: str) -> str:
    """The results file's Markdown with its headings two levels down and its title dropped."""
    lines = text.splitlines()
    if lines and lines[0].startswith("# "):
        lines = lines[1:]
    out, fence = [], False
    for line in lines:
        if line.lstrip().startswith("```"):
            fence = not fence
        if not fence and line.startswith("#"):
            line = "#" + line
        out.append(line)
    return "\n".join(out).strip()


def _script_command(script: str) -> str:
    if script.startswith("tests/"):
        return "PYTHONPATH=src:. python -m tests.fuzz --workers 2 --timeout 20 --report fuzz.md"
    return f"OPENBLAS_NUM_THREADS=1 python {script}   # its defaults printed this table"


def benchmark_results(root: Any) -> str:
    """Markdown: for every benchmark, its script and purpose and its newest committed table."""
    import ast
    from pathlib import Path

    parts = []
    for prefix, files in result_files(root).items():
        script = BENCH_SCRIPTS.get(prefix)
        if script is None:
            raise ValueError(f"benchmarks/results/{files[0].name}: add its script to BENCH_SCRIPTS")
        source = Path(root, script).read_text(encoding="utf-8")
        doc = ast.get_docstring(ast.parse(source)) or ""
        purpose = " ".join(doc.split("\n\n")[0].split())
        text = files[0].read_text(encoding="utf-8")
        title = text.splitlines()[0].lstrip("# ").strip() if text.startswith("# ") else prefix
        older = ", ".join(f"`{p.name}`" for p in files[1:])
        parts.append(
            f"## {title}\n\n{purpose}\n\nScript: `{script}`; table: "
            f"`benchmarks/results/{files[0].name}`"
            + (f" (earlier: {older})" if older else "")
            + ".\n\n"
            + ("" if "python" in text else f"```bash\n{_script_command(script)}\n```\n\n")
            + _demote(text)
            + "\n"
        )
    return "\n".join(parts)
