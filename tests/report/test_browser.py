"""report.html in a real browser: headless Chromium (Debian's package, installed by .ci/run)
driven by Playwright for Python (``executable_path``: no browser download).

Checks: every ``<img>`` loaded (``complete`` and ``naturalWidth > 0``), the console shows no
error, the page asks for nothing beyond the file itself and its data: URIs, and a screenshot
is not blank. Skips without Chromium or Playwright locally; fails under CI (``CI`` set) so
that the check cannot be skipped silently there.
"""

from __future__ import annotations

import io
import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from imageform.report import ReportPaths, write_report
from imageform.simulate.result import SimulationResult

CHROMIUM = Path(os.environ.get("IMAGEFORM_CHROMIUM", "/usr/bin/chromium"))


def _require(what: str) -> None:
    if os.environ.get("CI"):
        pytest.fail(f"{what} is missing under CI; .ci/run installs it")
    pytest.skip(f"{what} not installed")


@pytest.fixture(scope="module")
def browser_page():  # type: ignore[no-untyped-def]
    if not CHROMIUM.is_file():
        _require(f"Chromium ({CHROMIUM})")
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        _require("Playwright for Python (the test extra)")
    with sync_playwright() as p:
        browser = p.chromium.launch(
            executable_path=str(CHROMIUM),
            args=["--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage"],
        )
        try:
            yield browser.new_page(viewport={"width": 1280, "height": 900})
        finally:
            browser.close()


def _open(page, path: Path) -> dict[str, list[str]]:  # type: ignore[no-untyped-def]
    seen: dict[str, list[str]] = {"console_errors": [], "page_errors": [], "requests": []}
    page.on(
        "console", lambda m: seen["console_errors"].append(m.text) if m.type == "error" else None
    )
    page.on("pageerror", lambda exc: seen["page_errors"].append(str(exc)))
    page.on("request", lambda r: seen["requests"].append(r.url))
    page.goto(path.resolve().as_uri(), wait_until="load")
    return seen


def _not_blank(png: bytes) -> np.ndarray:
    from PIL import Image

    px = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=np.float64)
    assert px.std() > 20.0, f"screenshot looks blank (std {px.std():.1f})"
    assert px.mean() < 250.0 and not np.all(px == 255), "screenshot is all white"
    return px


@pytest.mark.parametrize("which", ["full", "bare"])
def test_report_in_headless_chromium(
    browser_page,  # type: ignore[no-untyped-def]
    which: str,
    full_report: ReportPaths,
    bare_result: SimulationResult,
    tmp_path: Path,
) -> None:
    paths = full_report if which == "full" else write_report(bare_result, tmp_path / "report")
    page = browser_page
    seen = _open(page, paths.html)
    images = page.evaluate(
        "Array.from(document.images).map(i => [i.alt, i.complete, i.naturalWidth])"
    )
    assert len(images) == (11 if which == "full" else 6)
    broken = [alt for alt, complete, width in images if not (complete and width > 0)]
    assert broken == [], f"images that did not load: {broken}"
    assert seen["console_errors"] == [] and seen["page_errors"] == []
    others = [u for u in seen["requests"] if not u.startswith(("file:", "data:"))]
    assert others == [], f"the report asked for {others}"
    _not_blank(page.screenshot())
    if which == "full":
        # a figure further down renders too (scrolled into view)
        _not_blank(page.locator("#chromaticity img").screenshot())
        assert page.title() == "imageform simulation: synthetic"


def test_real_simulation_report_in_headless_chromium(
    browser_page,  # type: ignore[no-untyped-def]
    real_run: dict[str, Any],
) -> None:
    """The report of a real ``imageform simulate`` run (not the synthetic result)."""
    page = browser_page
    seen = _open(page, real_run["out"] / "report.html")
    images = page.evaluate(
        "Array.from(document.images).map(i => [i.alt, i.complete, i.naturalWidth])"
    )
    assert len(images) >= 12  # 8 stages, chromaticity, ΔE, SNR, top view, VP, PTC
    broken = [alt for alt, complete, width in images if not (complete and width > 0)]
    assert broken == [], f"images that did not load: {broken}"
    assert seen["console_errors"] == [] and seen["page_errors"] == []
    others = [u for u in seen["requests"] if not u.startswith(("file:", "data:"))]
    assert others == [], f"the report asked for {others}"
    _not_blank(page.screenshot(full_page=True))


def _load_seconds(page, path: Path, repeat: int = 3) -> float:  # type: ignore[no-untyped-def]
    """Median wall time of opening ``path`` until its load event (HTML parsed, every image
    decoded)."""
    import statistics
    import time

    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        page.goto(path.resolve().as_uri(), wait_until="load")
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def test_report_loads_in_under_a_second(
    browser_page,  # type: ignore[no-untyped-def]
    real_run: dict[str, Any],
    result_factory,  # type: ignore[no-untyped-def]
    tmp_path: Path,
) -> None:
    """issue 19: the page loads in headless Chromium in under 1 s: the real run's report,
    and the report of a noisy full-size (1280 x 720) result, whose stage pictures are
    JPEGs of the default scene's size (the 16 MB PNG page took 2.5 s)."""
    import dataclasses

    from tests.report.test_report_html import _noisy

    r = result_factory(width=1280, height=720)
    rng = np.random.default_rng(0)
    big = write_report(
        dataclasses.replace(r, stages=tuple(_noisy(s, rng) for s in r.stages)), tmp_path / "big"
    )
    assert big.html.stat().st_size <= 3_000_000
    for path in (real_run["out"] / "report.html", big.html):
        seconds = _load_seconds(browser_page, path)
        assert seconds < 1.0, f"{path} took {seconds:.2f} s to load"
