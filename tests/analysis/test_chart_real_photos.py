"""ColorCheckers in real photographs of real charts (tests/data/chart-real, MIT-licensed).

Four photographs from public repositories (tests/data/chart-real/README.md): a chart held by
hand in a cluttered room, a ColorChecker Passport upside down, and two phone photographs of a
printed chart on a desk and on a cluttered floor (turned 137 and -55 degrees, the second
blurred). ``expected.json`` holds each chart's corners, checked by eye on overlays and
against OpenCV's ``mcc`` (patch centres within 0.16 pitch where it finds the chart). Then the
glare and the shadow of tests/analysis/test_chart_light.py put on these photographs (not on
the blurred one: there the chart is found, but a corner lies up to 0.7 pitch off, unsolved).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from imageform.analysis import ChartWarning, detect_colorchecker
from tests.analysis.test_chart_light import _glare, _shadow

DATA = Path(__file__).resolve().parents[1] / "data" / "chart-real"
EXPECTED = json.loads((DATA / "expected.json").read_text(encoding="utf-8"))


def _read(name: str) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(DATA / name).convert("RGB"), dtype=np.float64) / 255.0


def _pitch(corners: np.ndarray) -> float:
    return float(np.linalg.norm(corners[1] - corners[0]) / 6)


def _check(det_corners: np.ndarray, name: str) -> None:
    want = np.asarray(EXPECTED[name]["corners"])
    assert np.linalg.norm(det_corners - want, axis=1).max() < _pitch(want) / 4, name


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_found_where_it_is(name: str) -> None:
    det = detect_colorchecker(_read(name))
    assert det.found, det.reason
    _check(det.corners, name)
    turn = (det.rotation - EXPECTED[name]["rotation"] + 180.0) % 360.0 - 180.0
    assert abs(turn) < 3.0


SHARP = sorted(n for n in EXPECTED if n != "jarrel-20140613_203518.jpg")


@pytest.mark.parametrize("name", SHARP)
def test_glare_on_a_real_chart(name: str) -> None:
    det0 = detect_colorchecker(_read(name))
    det = detect_colorchecker(_glare(_read(name), det0.centers))
    assert det.found, det.reason
    _check(det.corners, name)


@pytest.mark.parametrize("name", SHARP)
def test_shadow_on_a_real_chart(name: str) -> None:
    det0 = detect_colorchecker(_read(name))
    with pytest.warns(ChartWarning, match="uneven"):
        det = detect_colorchecker(_shadow(_read(name), det0.centers))
    assert det.found, det.reason
    _check(det.corners, name)
