"""The documentation site (mkdocs.yml) builds with warnings as errors, documents every public
name, resolves every internal link, and works in a real browser.

The build needs the ``docs`` extra (MkDocs, mkdocs-material, mkdocstrings); the browser check
needs Debian's Chromium and Playwright (the test extra). Both skip locally when missing and
fail under CI (``CI`` set), where .ci/run installs them.
"""

from __future__ import annotations

import fcntl
import functools
import http.server
import importlib
import importlib.util
import json
import os
import re
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any
from urllib.parse import unquote, urlsplit

import pytest

ROOT = Path(__file__).resolve().parents[1]
CHROMIUM = Path(os.environ.get("IMAGEFORM_CHROMIUM", "/usr/bin/chromium"))
PACKAGES = [
    "spectral",
    "color",
    "geometry",
    "optics",
    "sensor",
    "io",
    "analysis",
    "simulate",
    "report",
    "workflows",
    "batch",
    "errors",
]


def _require(what: str) -> None:
    if os.environ.get("CI"):
        pytest.fail(f"{what} is missing under CI; .ci/run installs it")
    pytest.skip(f"{what} not installed")


def _build(out: Path) -> str:
    """``mkdocs build --strict`` into ``out``: its log (the build's failure fails the test)."""
    env = {
        **os.environ,
        "NO_MKDOCS_2_WARNING": "1",
        "MPLBACKEND": "Agg",
        "PYTHONPATH": str(ROOT / "src"),
    }
    done = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(out)],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    log = done.stdout + done.stderr
    assert done.returncode == 0, f"mkdocs build --strict failed:\n{log[-4000:]}"
    return log


@pytest.fixture(scope="session")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The site, built once per test run (about 34 s of CPU): the pytest-xdist workers that
    run this module's tests (split between them) share one build, in the run's own folder
    (PYTEST_XDIST_TESTRUNUID), the first worker building it while the others wait."""
    try:
        importlib.import_module("mkdocs")
        importlib.import_module("mkdocstrings")
    except ImportError:
        _require('MkDocs (pip install -e ".[docs]")')
    run = os.environ.get("PYTEST_XDIST_TESTRUNUID")
    if run:  # the workers' base folders share a parent, this run's alone
        shared = tmp_path_factory.getbasetemp().parent / f"site-{run}"
        shared.mkdir(exist_ok=True)
    else:
        shared = tmp_path_factory.mktemp("site-build")
    out, built = shared / "site", shared / "built.log"
    # the build also writes the gallery into docs/generated: two test runs of this checkout
    # at once take turns
    lock_dir = ROOT / "docs" / "generated"
    lock_dir.mkdir(parents=True, exist_ok=True)
    with open(shared / ".lock", "w") as mine, open(lock_dir / ".build.lock", "w") as lock:
        fcntl.flock(mine, fcntl.LOCK_EX)
        if not built.is_file():
            fcntl.flock(lock, fcntl.LOCK_EX)
            built.write_text(_build(out))
    warnings = [line for line in built.read_text().splitlines() if "WARNING" in line]
    assert warnings == [], "\n".join(warnings)
    return out


def _page(site: Path, name: str) -> str:
    """The built page of ``docs/<name>.md`` (directory URLs: ``<name>/index.html``)."""
    for path in (site / name / "index.html", site / f"{name}.html"):
        if path.is_file():
            return path.read_text(encoding="utf-8")
    raise AssertionError(f"the site has no page {name}")


def test_every_public_name_is_in_the_api_reference(site: Path) -> None:
    missing = []
    for pkg in PACKAGES:
        module = importlib.import_module(f"imageform.{pkg}")
        html = _page(site, f"reference/{pkg}")
        ids = set(re.findall(r'id="(imageform\.[\w.]+)"', html))
        for name in module.__all__:
            # a function that shares its module's name is documented as module.function
            if not {f"imageform.{pkg}.{name}", f"imageform.{pkg}.{name}.{name}"} & ids:
                missing.append(f"imageform.{pkg}.{name}")
    assert missing == [], f"not in the API reference: {missing}"


def test_the_cli_reference_lists_every_command(site: Path) -> None:
    from imageform.workflows import WORKFLOWS

    html = _page(site, "reference/cli")
    absent = [name for name in WORKFLOWS if f"imageform {name}" not in html]
    assert absent == []
    assert "Exit codes" in html


def _hooks() -> object:
    spec = importlib.util.spec_from_file_location(
        "mkdocs_hooks", ROOT / "tools" / "mkdocs_hooks.py"
    )
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_benchmark_table_is_on_the_benchmarks_page() -> None:
    """Every committed table (benchmarks/results/NAME-DATE.md) names its script, which exists;
    the page shows the newest table of each (no MkDocs needed for this check)."""
    hooks: Any = _hooks()
    files = hooks.result_files(ROOT)
    assert files, "no committed benchmark tables"
    unmapped = sorted(set(files) - set(hooks.BENCH_SCRIPTS))
    assert unmapped == [], (
        f"add these results to BENCH_SCRIPTS in tools/mkdocs_hooks.py: {unmapped}"
    )
    for prefix in files:
        assert (ROOT / hooks.BENCH_SCRIPTS[prefix]).is_file(), hooks.BENCH_SCRIPTS[prefix]
    page = hooks.benchmark_results(ROOT)
    for prefix, paths in files.items():
        assert f"`benchmarks/results/{paths[0].name}`" in page, prefix
    assert "2026-11-25 · x86_64" in page  # a table's own text is on the page


def test_the_benchmarks_page_is_built(site: Path) -> None:
    html = _page(site, "benchmarks")
    assert "benchmark-results" not in html and "bench_remap.py" in html and "<table>" in html


def _pages(site: Path) -> list[Path]:
    return [
        p
        for p in sorted(site.rglob("*.html"))
        if p.name != "404.html" and "assets" not in p.relative_to(site).parts
    ]


def test_every_internal_link_resolves(site: Path) -> None:
    broken = []
    for page in _pages(site):
        html = page.read_text(encoding="utf-8")
        anchors_here = set(re.findall(r'id="([^"]+)"', html))
        for href in re.findall(r'href="([^"]+)"', html):
            parts = urlsplit(href)
            if parts.scheme or href.startswith(("//", "mailto:")):
                continue
            target = (page.parent / unquote(parts.path)).resolve() if parts.path else page
            if target.is_dir():
                target = target / "index.html"
            if not target.exists():
                broken.append(f"{page.relative_to(site)} -> {href}")
                continue
            if parts.fragment and target.suffix == ".html":
                ids = (
                    anchors_here
                    if target == page
                    else set(re.findall(r'id="([^"]+)"', target.read_text(encoding="utf-8")))
                )
                if unquote(parts.fragment) not in ids:
                    broken.append(f"{page.relative_to(site)} -> {href} (no such anchor)")
    assert broken == [], "broken links:\n" + "\n".join(broken[:40])


@pytest.fixture(scope="module")
def served(site: Path) -> Iterator[str]:
    handler = functools.partial(_QuietHandler, directory=str(site))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}"
    finally:
        server.shutdown()
        server.server_close()


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, format: str, *args: object) -> None:
        pass


def test_the_site_in_headless_chromium(site: Path, served: str) -> None:
    """Every page loads without console errors, every image renders, nothing is fetched from
    outside the site, and the search finds "vanishing point".

    Each page's search worker gets an index of one page while the pages load (the theme's
    worker fetches and indexes the whole search_index.json, 2.3 MB, on every page: half of
    this test's time); the search at the end gets the site's own index."""
    if not CHROMIUM.is_file():
        _require(f"Chromium ({CHROMIUM})")
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        _require("Playwright for Python (the test extra)")
    problems: list[str] = []
    with sync_playwright() as p:
        browser = p.chromium.launch(
            executable_path=str(CHROMIUM),
            args=["--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage"],
        )
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 900})
            errors: list[str] = []
            outside: list[str] = []
            page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
            page.on("pageerror", lambda exc: errors.append(str(exc)))
            page.on(
                "request",
                lambda r: None if r.url.startswith((served, "data:")) else outside.append(r.url),
            )
            index = json.loads((site / "search" / "search_index.json").read_text("utf-8"))
            small = json.dumps({**index, "docs": index["docs"][:1]})
            route = f"{served}/search/search_index.json"
            page.route(
                route,
                lambda r: r.fulfill(status=200, content_type="application/json", body=small),
            )
            for path in _pages(site):
                rel = path.relative_to(site).as_posix()
                errors.clear()
                page.goto(f"{served}/{rel}", wait_until="load")
                images = page.evaluate(
                    "Array.from(document.images).map(i => [i.src, i.complete, i.naturalWidth])"
                )
                broken = [src for src, complete, width in images if not (complete and width > 0)]
                if errors or broken:
                    problems.append(f"{rel}: console {errors[:3]}, broken images {broken[:3]}")
            assert outside == [], f"the site fetched from outside itself: {outside[:5]}"
            page.unroute(route)
            page.goto(f"{served}/index.html", wait_until="load")
            page.keyboard.press("/")  # the theme's shortcut to the search box
            page.locator("input[data-md-component='search-query']").fill("vanishing point")
            page.wait_for_selector(".md-search-result__item", timeout=15_000)
            hits = page.locator(".md-search-result__item").count()
            assert hits > 0
        finally:
            browser.close()
    assert problems == [], "\n".join(problems)
