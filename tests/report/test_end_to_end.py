"""``imageform simulate`` end to end, nothing faked: the real scene loader, renderer, camera
pipeline and report writer on the built-in scene at 320 x 180 (tests/report/conftest.py's
``real_run``). The browser half of the check is in test_browser.py."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

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
    assert metrics["summary"] == summary
    assert metrics["image_size"] == {"width": 320, "height": 180}
    assert metrics["scene_name"] == "default"
    per_patch = metrics["metrics"]["delta_e00_per_patch"]
    assert len(per_patch) == 24 and all(math.isfinite(x) for x in per_patch)
    # the report measures the patches itself, from the written stage: same figures
    assert np.isclose(np.mean(per_patch), summary["mean_delta_e00"], rtol=1e-6)
    # At a quarter of the size the closed-loop figures stay in the same range as at 1280 x 720
    # (mean ΔE00 2.3, vanishing point 1.5 px): the pipeline works, not just runs.
    assert summary["mean_delta_e00"] < 4.0
    assert summary["vanishing_point_error_px"] < 8.0
    assert summary["system_gain_dn_per_e"] > 0
    assert len(metrics["metrics"]["snr_db_per_patch"]) == 24


def test_report_embeds_every_stage(real_run: dict[str, Any]) -> None:
    html = (real_run["out"] / "report.html").read_text()
    assert html.count('<img class="photo" src="data:image/png;base64,') >= len(STAGES)
    assert "<script src=" not in html and '<link rel="stylesheet" href=' not in html
