"""``imageform simulate`` end to end, nothing faked: the real scene loader, renderer, camera
pipeline and report writer on the built-in scene at 320 x 180 (tests/report/conftest.py's
``real_run``). The browser half of the check is in test_browser.py."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from imageform.io import read_image

STAGES = [
    "rendered",
    "optics",
    "raw",
    "demosaiced",
    "shading_corrected",
    "white_balanced",
    "color_corrected",
    "output",
]


def test_every_stage_is_written(real_run: dict[str, Any]) -> None:
    out: Path = real_run["out"]
    stages = json.loads((out / "metrics.json").read_text())["stages"]
    assert [s["name"] for s in stages] == STAGES
    assert real_run["stages"] == [str(out / s["file"]) for s in stages]
    for stage in stages:
        img = read_image(out / stage["file"])
        assert img.shape[:2] == (180, 320), stage["name"]
        assert img.std() > 0, f"stage {stage['name']} is flat"
    (raw_file,) = real_run["raw_files"]
    raw = read_image(raw_file)
    assert raw.dtype == np.uint16 and raw.shape[:2] == (180, 320)
    assert 0 < raw.max() < 2**16 - 1  # exposed, not saturated everywhere


def test_metrics_json_matches_the_summary(real_run: dict[str, Any]) -> None:
    metrics = json.loads((real_run["out"] / "metrics.json").read_text())
    summary = real_run["summary"]
    cc = metrics["colorchecker"]
    assert summary == {
        "simulation_time_s": metrics["simulation_time_s"],
        "delta_e00_mean": cc["delta_e00_mean"],
        "delta_e00_max": cc["delta_e00_max"],
        "vanishing_point_error_px": metrics["vanishing"]["vanishing_point_error_px"],
        "system_gain_dn_per_e": metrics["photon_transfer"]["fit"]["system_gain_dn_per_e"],
    }
    assert metrics["image_size_px"] == {"width": 320, "height": 180}
    assert metrics["scene_name"] == "default"
    per_patch = [p["delta_e00"] for p in cc["patches"]]
    assert len(per_patch) == 24 and all(math.isfinite(x) for x in per_patch)
    assert np.isclose(np.mean(per_patch), cc["delta_e00_mean"], rtol=1e-12)
    # At a quarter of the size the closed-loop figures stay in the same range as at 1280 x 720
    # (mean ΔE00 2.3, vanishing point 1.5 px): the pipeline works, not just runs.
    assert summary["delta_e00_mean"] < 4.0
    assert summary["vanishing_point_error_px"] < 8.0
    assert summary["system_gain_dn_per_e"] > 0
    snr = [p["snr_luminance_db"] for p in cc["patches"]]
    assert len(snr) == 24 and all(10.0 < x < 60.0 for x in snr)
    # one total time: the run's wall time, which contains every step
    assert metrics["simulation_time_s"] >= sum(metrics["step_times_s"].values())
    assert [s["name"] for s in metrics["stages"]] == list(metrics["step_times_s"])[:8]
    # the light is CIE illuminant A: 2856 K, computed from its spectrum
    assert metrics["illuminant_cct_K"] == pytest.approx(2856.0, abs=1.0)
    assert metrics["config"]["illuminant"]["temperature_K"] is None


def test_report_embeds_every_stage(real_run: dict[str, Any]) -> None:
    html = (real_run["out"] / "report.html").read_text()
    assert html.count('<img class="photo" src="data:image/jpeg;base64,') >= len(STAGES)
    # each picture links to its lossless PNG in stages/, relative to the swapped-in folder
    links = re.findall(r'<a href="(stages/[^"]+)"><img', html)
    assert len(links) == len(STAGES)
    for h in links:
        assert (real_run["out"] / h).is_file(), h
    assert "<script src=" not in html and '<link rel="stylesheet" href=' not in html
