"""write_report: one self-contained report.html, metrics.json with every key, stage files,
overwrite refusal."""

from __future__ import annotations

import base64
import dataclasses
import io
import json
import re
from pathlib import Path

import numpy as np
import pytest

from imageform.errors import InvalidInputError
from imageform.io import read_image
from imageform.report import ReportPaths, write_report
from imageform.report.metrics import METRICS_KEYS, SUMMARY_KEYS
from imageform.simulate.result import SimulationResult, Stage

pytest.importorskip("matplotlib")

_IMG = re.compile(r"<img\b[^>]*>")
_PNG_URI = re.compile(r'src="data:image/png;base64,([A-Za-z0-9+/=]+)"')
_JPEG_URI = re.compile(r'src="data:image/jpeg;base64,([A-Za-z0-9+/=]+)"')
_HREF = re.compile(r'href="([^"#][^"]*)"')


@pytest.fixture(scope="module")
def written(full_report: ReportPaths) -> ReportPaths:
    return full_report


def test_files_written(written: ReportPaths, sim_result: SimulationResult) -> None:
    assert written.html.name == "report.html" and written.metrics.name == "metrics.json"
    names = [p.name for p in written.stages]
    assert names == [
        "00-radiance.png",
        "01-raw.png",
        "02-demosaiced.png",
        "03-white_balanced.png",
        "04-output.png",
    ]
    for p in written.stages:
        img = read_image(p)
        assert img.dtype == np.uint8 and img.shape == (128, 192, 3)
    assert [p.name for p in written.raw_files] == ["01-raw-dn.png"]
    dn = read_image(written.raw_files[0])
    assert dn.dtype == np.uint16
    assert np.array_equal(dn[..., 0], sim_result.stage("raw").image)  # lossless


def test_html_is_self_contained(written: ReportPaths) -> None:
    text = written.html.read_text(encoding="utf-8")
    assert not re.search(r"https?://", text)
    assert "<script" not in text and 'src="http' not in text and "url(" not in text
    imgs = _IMG.findall(text)
    pngs, jpegs = _PNG_URI.findall(text), _JPEG_URI.findall(text)
    # one data: URI per image: the plots (chromaticity, ΔE00, SNR, top view, PTC) as PNG,
    # the pictures (5 stages, VP overlay) as JPEG
    assert len(imgs) == len(pngs) + len(jpegs) == 11
    assert len(pngs) == 5 and len(jpegs) == 6
    for b64 in pngs:
        assert base64.b64decode(b64)[:8] == b"\x89PNG\r\n\x1a\n"
    for b64 in jpegs:
        assert base64.b64decode(b64)[:3] == b"\xff\xd8\xff"
    for section in ("stages", "colour", "geometry", "sensor", "numbers"):
        assert f'<section id="{section}">' in text
    assert "just noticeable" in text and "imperceptible" in text
    assert 'class="note"' not in text  # nothing left out


def test_stage_pictures_link_to_lossless_files(written: ReportPaths) -> None:
    """Each stage picture (a JPEG in the page) links to its lossless PNG in stages/ by a
    relative link that resolves inside the report's folder (swapped in whole)."""
    text = written.html.read_text(encoding="utf-8")
    links = [h for h in _HREF.findall(text) if not h.startswith("data:")]
    assert links, "no links"
    for h in links:
        assert h.startswith("stages/") and "//" not in h and ".." not in h, h
        assert (written.html.parent / h).is_file(), h
    for p in written.stages:
        assert text.count(f'href="stages/{p.name}"') == 2  # the picture and the caption
    # the page's picture is the stage file, compressed: same size, close in value
    from PIL import Image

    jpg = Image.open(io.BytesIO(base64.b64decode(_JPEG_URI.findall(text)[-2])))
    ref = read_image(written.stages[-1])
    got = np.asarray(jpg.convert("RGB"), dtype=np.float64)
    assert got.shape == ref.shape
    assert np.abs(got - ref).mean() < 4.0


def test_stage_captions(written: ReportPaths, sim_result: SimulationResult) -> None:
    text = written.html.read_text(encoding="utf-8")
    for s in sim_result.stages:
        assert s.title in text and s.description in text and f"{s.seconds:.3f} s" in text


def test_metrics_json_round_trips_with_every_key(
    written: ReportPaths, sim_result: SimulationResult
) -> None:
    raw = written.metrics.read_text()
    assert "NaN" not in raw and "Infinity" not in raw  # strict JSON
    data = json.loads(raw)
    assert tuple(data) == METRICS_KEYS and data["metrics_version"] == 2
    assert json.loads(json.dumps(data)) == data
    assert tuple(written.summary) == SUMMARY_KEYS
    assert data["scene_name"] == "synthetic"
    assert data["image_size_px"] == {"width": 192, "height": 128}
    # the summary repeats fields of metrics.json, same names, same values
    s = written.summary
    assert s["simulation_time_s"] == data["simulation_time_s"] == 1.0
    assert s["vanishing_point_error_px"] == data["vanishing"]["vanishing_point_error_px"]
    assert s["vanishing_point_error_px"] == pytest.approx(5.0)
    assert s["delta_e00_max"] == data["colorchecker"]["delta_e00_max"]
    assert s["delta_e00_max"] == pytest.approx(2.0, abs=1e-6)
    assert s["delta_e00_mean"] == data["colorchecker"]["delta_e00_mean"]
    assert s["system_gain_dn_per_e"] == data["photon_transfer"]["fit"]["system_gain_dn_per_e"]
    assert s["system_gain_dn_per_e"] == pytest.approx(0.5)
    # the result's metrics: a placed one (simulation_time_s) at the top, the others kept
    assert data["other_metrics"] == {"vp_error_px": 5.0, "per_patch": list(range(24)), "nan": None}
    assert data["step_times_s"] == {st.name: st.seconds for st in sim_result.stages}
    assert len(data["stages"]) == 5 and data["stages"][1]["raw_file"] == "stages/01-raw-dn.png"
    assert data["stages"][1]["white_level_dn"] == 4095.0 and data["stages"][1]["dtype"] == "uint16"
    p0 = data["colorchecker"]["patches"][0]
    assert set(p0) == {
        "name",
        "lab_truth",
        "lab_measured",
        "delta_e00",
        "reading",
        "snr_luminance_db",
        "xy",
    }
    assert p0["delta_e00"] == pytest.approx(2.0, abs=1e-6) and p0["reading"] == "just noticeable"
    assert set(p0["xy"]) == set(sim_result.patch_xy)
    xy = [pt["xy"]["after_white_balance"] for pt in data["colorchecker"]["patches"]]
    assert np.allclose(xy, sim_result.patch_xy["after_white_balance"])
    assert np.allclose(data["top_view"]["camera_center_m"], sim_result.camera.center)
    assert data["photon_transfer"]["fit"]["fit_points"] >= 2
    assert data["config"] == sim_result.config and data["notes"] == []


def _field_paths(value: object, path: str, out: dict[str, list[str]]) -> None:
    """Leaf fields of metrics.json as generic paths (list items ``[]``, maps keyed by
    names ``{}``), grouped by the field's own name."""
    if isinstance(value, list) and value and isinstance(value[0], dict):
        for item in value:
            _field_paths(item, f"{path}[]", out)
        return
    if isinstance(value, dict) and path.split(".")[-1] not in _NAME_MAPS:
        for k, v in value.items():
            _field_paths(v, f"{path}.{k}" if path else k, out)
        return
    name = path.split(".")[-1].removesuffix("[]")
    if path not in out.setdefault(name, []):
        out[name].append(path)


# maps keyed by names (of steps, stages, objects), and the echoed input
_NAME_MAPS = ("step_times_s", "xy", "quads_m", "config", "other_metrics", "image_size_px")


def test_metrics_json_has_one_name_per_quantity(written: ReportPaths) -> None:
    data = json.loads(written.metrics.read_text())
    fields: dict[str, list[str]] = {}
    _field_paths(data, "", fields)
    # "name" labels different things (a patch, a stage); every quantity has one place
    twice = {n: paths for n, paths in fields.items() if len(paths) > 1 and n != "name"}
    assert not twice, twice
    # the old names of quantities that had two (snr_db was two different SNRs)
    for old in ("snr_db", "total_seconds", "mean_delta_e00", "error_px", "patch_xy", "summary"):
        assert old not in fields, old


def test_docs_define_every_metrics_field(written: ReportPaths) -> None:
    data = json.loads(written.metrics.read_text())
    fields: dict[str, list[str]] = {}
    _field_paths(data, "", fields)
    doc = (Path(__file__).resolve().parents[2] / "docs" / "simulate-report.md").read_text()
    table = doc[doc.index("| field |") :]
    missing = sorted(p for paths in fields.values() for p in paths if f"`{p}`" not in table)
    assert not missing, missing


def test_refuses_to_overwrite(written: ReportPaths, sim_result: SimulationResult) -> None:
    before = written.html.stat().st_mtime_ns
    with pytest.raises(InvalidInputError, match=r"exists.*force"):
        write_report(sim_result, written.out_dir)
    assert written.html.stat().st_mtime_ns == before


def test_force_overwrites_and_removes_stale_stage_files(
    bare_result: SimulationResult, tmp_path: Path
) -> None:
    write_report(bare_result, tmp_path)
    keep = tmp_path / "stages" / "notes.txt"
    keep.write_text("mine")
    short = dataclasses.replace(bare_result, stages=bare_result.stages[-1:])
    paths = write_report(short, tmp_path, force=True)
    assert sorted(p.name for p in (tmp_path / "stages").iterdir()) == ["00-output.png", "notes.txt"]
    assert paths.raw_files == ()


def test_bare_result_leaves_sections_out_with_notes(
    bare_result: SimulationResult, tmp_path: Path
) -> None:
    paths = write_report(bare_result, tmp_path / "bare")
    text = paths.html.read_text(encoding="utf-8")
    assert text.count('class="note"') == 4  # chromaticity, ΔE/SNR, vanishing point, sensor
    assert "No ColorChecker" in text and "No rails" in text and "photon-transfer" in text
    # 5 stages (JPEG) + top view (PNG)
    assert len(_IMG.findall(text)) == len(_JPEG_URI.findall(text)) + 1 == 6
    assert len(_PNG_URI.findall(text)) == 1
    data = json.loads(paths.metrics.read_text())
    assert data["colorchecker"] is None and data["vanishing"] is None
    assert data["photon_transfer"] is None and len(data["notes"]) == 4
    assert paths.summary["delta_e00_mean"] is None and data["simulation_time_s"] is None


def test_text_is_escaped(bare_result: SimulationResult, tmp_path: Path) -> None:
    s0 = bare_result.stages[0]
    evil = dataclasses.replace(s0, title="<script>alert(1)</script>", name="a/b c")
    r = dataclasses.replace(
        bare_result, stages=(evil, *bare_result.stages[1:]), scene_name="<b>x</b>"
    )
    paths = write_report(r, tmp_path)
    text = paths.html.read_text(encoding="utf-8")
    assert "<script>" not in text and "&lt;script&gt;" in text and "&lt;b&gt;x" in text
    assert paths.stages[0].name == "00-a-b-c.png"


def test_bad_results(sim_result: SimulationResult, tmp_path: Path) -> None:
    with pytest.raises(InvalidInputError, match="SimulationResult"):
        write_report({"stages": []}, tmp_path)  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="at least one stage"):
        write_report(dataclasses.replace(sim_result, stages=()), tmp_path)
    with pytest.raises(InvalidInputError, match="last stage"):
        write_report(dataclasses.replace(sim_result, stages=sim_result.stages[:2]), tmp_path)
    odd = Stage("x", "x", "x", np.zeros((2, 2)), "log")  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="kind 'log'"):
        write_report(dataclasses.replace(sim_result, stages=(odd, *sim_result.stages)), tmp_path)
    with pytest.raises(InvalidInputError, match=r"image_size \(100, 128\)"):
        write_report(dataclasses.replace(sim_result, image_size=(100, 128)), tmp_path)
    (tmp_path / "file").write_text("")
    with pytest.raises(InvalidInputError, match="not a folder"):
        write_report(sim_result, tmp_path / "file")


def test_float_raw_kept_as_tiff(bare_result: SimulationResult, tmp_path: Path) -> None:
    raw = bare_result.stage("raw")
    half = dataclasses.replace(raw, image=raw.image.astype(np.float64) + 0.5)
    r = dataclasses.replace(bare_result, stages=(half, bare_result.stages[-1]))
    paths = write_report(r, tmp_path)
    assert [p.name for p in paths.raw_files] == ["00-raw-dn.tif"]
    assert np.array_equal(read_image(paths.raw_files[0])[..., 0], half.image.astype(np.float32))


def test_metrics_that_are_not_json_are_an_error(
    bare_result: SimulationResult, tmp_path: Path
) -> None:
    r = dataclasses.replace(bare_result, metrics={"f": object()})
    with pytest.raises(InvalidInputError, match=r"metrics\.f"):
        write_report(r, tmp_path)


def _noisy(stage: Stage, rng: np.random.Generator) -> Stage:
    """The stage with camera-like noise (noise is what makes PNGs big and slow)."""
    a = np.asarray(stage.image, dtype=np.float64)
    if stage.kind == "raw":
        img = np.clip(a + rng.normal(0, 30, a.shape), 0, 4095).astype(np.uint16)
    else:
        img = np.clip(a + rng.normal(0, 0.02, a.shape), 0, None if stage.kind == "linear" else 1)
    return dataclasses.replace(stage, image=img)


@pytest.mark.slow
def test_report_of_a_noisy_1280x720_result(result_factory, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    """The report of a full-size result is a small part of the 60 s budget of the default
    run (measured: a few seconds on the 2-core machine)."""
    r = result_factory(width=1280, height=720)
    rng = np.random.default_rng(0)
    noisy = dataclasses.replace(r, stages=tuple(_noisy(s, rng) for s in r.stages))
    paths = write_report(noisy, tmp_path)
    mb = paths.html.stat().st_size / 1e6
    print(f"report of a noisy 1280x720 result: {paths.seconds:.2f} s, report.html {mb:.1f} MB")
    assert paths.seconds < 30.0
    # the page's pictures are JPEG: the page stays small (16 MB with PNG data: URIs)
    assert mb <= 3.0
    assert read_image(paths.stages[0]).shape == (720, 1280, 3)
    assert read_image(paths.raw_files[0]).dtype == np.uint16
