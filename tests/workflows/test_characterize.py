"""``imageform characterize FOLDER -o OUT`` (issue 18): the loop closes.

A lab set photographed by a known camera X (tests/workflows/characterize_lab.py: the
simulator's renderer, a Gaussian lens, its CMOS sensor and X's processing) is characterised
through the command line; the camera file and metrics give X back: fx, fy, cx, cy within
0.2 %, k1 within 2 %, MTF50 within 3 % of X's own (the Gaussian times the pixel box), gain
and read noise within 3 %, and the ColorChecker rendered through the twin (its estimated
sensitivities, white balance and matrix) within a mean CIEDE2000 of 1 of X's rendering.
Then the report in headless Chromium, and refusals: an empty folder, an unreadable image,
flats without darks, each one line, nothing written.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import tomllib
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from imageform.cli import main
from imageform.errors import ImageformError, InvalidInputError
from imageform.workflows import execute
from tests.report.test_browser import browser_page  # noqa: F401 (the shared browser fixture)
from tests.workflows.characterize_lab import CX, CY, FX, FY, K1, SIZE, make_lab_set

pytest.importorskip("matplotlib")
pytest.importorskip("rawpy")


@pytest.fixture(scope="module")
def lab(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The lab set of camera X, characterised once through the command line (--json)."""
    root = tmp_path_factory.mktemp("lab")
    truth = make_lab_set(root / "set")
    out = root / "twin"
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        rc = main(["characterize", str(root / "set"), "-o", str(out), "--json"])
    assert rc == 0
    return {"root": root, "truth": truth, "out": out, "printed": json.loads(buf.getvalue())}


def test_geometry_comes_back(lab: dict[str, Any]) -> None:
    """fx, fy, cx, cy within 0.2 % and k1 within 2 % (measured: -0.05, -0.03, +0.02, +0.09 %,
    k1 -0.6 %), in the camera file and in the printed summary alike."""
    cam = tomllib.loads((lab["out"] / "camera.toml").read_text())
    intr = cam["intrinsics"]
    for key, true in (("fx", FX), ("fy", FY), ("cx", CX), ("cy", CY)):
        assert intr[key] == pytest.approx(true, rel=0.002), key
    assert cam["distortion"]["k1"] == pytest.approx(K1, rel=0.02)
    assert (cam["image"]["width"], cam["image"]["height"]) == SIZE
    g = lab["printed"]["geometry"]
    assert g["fx"] == pytest.approx(intr["fx"]) and g["views_used"] == 10
    assert g["rms_px"] < 0.3


def test_mtf_comes_back(lab: dict[str, Any]) -> None:
    """MTF50 of the raw edge within 3 % of X's own (Gaussian sigma 0.9 px times the 4-point
    pixel box along the edge normal; measured -0.3 %), and the fitted sigma within 3 %."""
    truth = lab["truth"]
    s = lab["printed"]["sharpness"]
    assert s["raw"] and s["edges"] == 4
    angle = float(np.median(s["angles_deg"]))
    assert s["mtf50_cy_per_px"]["raw"] == pytest.approx(truth.mtf50(angle), rel=0.03)
    assert s["gaussian_sigma_px"] == pytest.approx(truth.sigma_px, rel=0.03)
    cam = tomllib.loads((lab["out"] / "camera.toml").read_text())
    metrics = json.loads((lab["out"] / "metrics.json").read_text())
    optics = cam.get("optics", metrics["camera_tables"]["optics"])
    assert optics["model"] == "gaussian"
    assert optics["gaussian_sigma_px"] == pytest.approx(s["gaussian_sigma_px"])


def test_noise_comes_back(lab: dict[str, Any]) -> None:
    """EMVA 1288 gain and read noise within 3 % of the sensor's (measured -0.8 %, +0.8 %),
    and the quantum efficiency from lab.toml's photon rate within 5 %."""
    truth = lab["truth"]
    n = lab["printed"]["noise"]
    assert n["system_gain_dn_per_e"] == pytest.approx(truth.gain, rel=0.03)
    assert n["read_noise_e"] == pytest.approx(truth.read_noise, rel=0.03)
    qe = float(truth.sensor.quantum_efficiency(550.0)[1]) * truth.sensor.fill_factor
    assert n["quantum_efficiency"] == pytest.approx(qe, rel=0.05)
    peak = max(max(c) for c in truth.sensor.qe_curves)
    eff = peak * truth.sensor.fill_factor  # EMVA QE: the effective one (fill factor in)
    assert metrics_sensor(lab)["quantum_efficiency"] == pytest.approx(eff, rel=0.05)
    assert n["system_gain_std"] < 0.01 * truth.gain
    metrics = json.loads((lab["out"] / "metrics.json").read_text())
    sensor = metrics["camera_tables"]["sensor"]
    assert sensor["system_gain_dn_per_e"] == pytest.approx(n["system_gain_dn_per_e"])
    assert sensor["black_level_dn"] == pytest.approx(truth.sensor.black_level, abs=1.0)


def metrics_sensor(lab: dict[str, Any]) -> dict[str, Any]:
    return json.loads((lab["out"] / "metrics.json").read_text())["camera_tables"]["sensor"]


def _twin_sensor(sensor: Any, table: dict[str, Any]) -> Any:
    """X's sensor with the estimated sensitivities (scaled to X's green peak QE)."""
    s = table["sensitivity"]
    curves = np.array([s["r"], s["g"], s["b"]])
    peak = max(max(c) for c in sensor.qe_curves)
    return replace(
        sensor,
        qe_wavelengths=tuple(s["wavelengths_nm"]),
        qe_curves=tuple(tuple(float(x) for x in c * peak) for c in curves),
    )


def test_twin_renders_the_chart_as_the_camera_does(lab: dict[str, Any]) -> None:
    """The ColorChecker simulated through X and through its twin (the estimated
    sensitivities, the measured white balance and colour matrix): mean CIEDE2000 between
    the two renderings < 1 (measured 0.31). Without the measured colour model (the twin's
    sensitivities, identity processing) the renderings differ far more."""
    from imageform.color import delta_e_ciede2000, linear_srgb_to_xyz, xyz_to_lab
    from tests.workflows.characterize_lab import render_chart

    truth = lab["truth"]
    metrics = json.loads((lab["out"] / "metrics.json").read_text())
    color = metrics["camera_tables"]["color"]
    assert color["ccm_to"] == "linear_srgb"
    twin = _twin_sensor(truth.sensor, color)
    orig, *_ = render_chart(truth.sensor, truth.wb, truth.ccm)
    mine, *_ = render_chart(twin, np.array(color["white_balance"]), np.array(color["ccm"]).T)

    def lab_(x: np.ndarray) -> np.ndarray:
        return np.asarray(xyz_to_lab(linear_srgb_to_xyz(x), white="D65"))

    de = np.asarray(delta_e_ciede2000(lab_(orig), lab_(mine)))
    assert float(de.mean()) < 1.0, de
    bare, *_ = render_chart(twin, np.ones(3), np.eye(3))
    assert float(np.mean(delta_e_ciede2000(lab_(orig), lab_(bare)))) > 5.0
    # the estimate against X's own curves: the same peaks within 20 nm
    s = color["sensitivity"]
    wl = np.array(s["wavelengths_nm"])
    est_peaks = [wl[int(np.argmax(s[c]))] for c in "rgb"]
    xw = np.array(truth.sensor.qe_wavelengths)
    true_peaks = [xw[int(np.argmax(c))] for c in truth.sensor.qe_curves]
    assert np.allclose(est_peaks, true_peaks, atol=20.0), (est_peaks, true_peaks)


def test_outputs_and_report(lab: dict[str, Any]) -> None:
    out = lab["out"]
    assert sorted(p.name for p in out.iterdir()) == ["camera.toml", "metrics.json", "report.html"]
    html = (out / "report.html").read_text()
    for anchor in ("geometry", "sharpness", "noise", "colour", "camera-file"):
        assert f'id="{anchor}"' in html
    assert html.count("<img") == 5  # reprojection, MTF, PTC + SNR, chart, sensitivities
    assert "http://" not in html and "https://" not in html
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["format"] == "imageform-characterization"
    assert set(metrics["summary"]["measured"]) == {"geometry", "sharpness", "noise", "color"}
    assert metrics["summary"]["missing"] == {}


def test_python_api_and_rerun_needs_force(lab: dict[str, Any]) -> None:
    from imageform.workflows import CameraCharacterization, characterize_camera

    res = characterize_camera(lab["root"] / "set")
    assert isinstance(res, CameraCharacterization)
    assert res.measured == ("geometry", "sharpness", "noise", "color")
    assert res.tables["optics"]["model"] == "gaussian"
    assert res.summary()["geometry"]["fx"] == lab["printed"]["geometry"]["fx"]
    with pytest.raises(InvalidInputError, match="exists"):
        execute("characterize", folder=str(lab["root"] / "set"), out=lab["out"])


def test_partial_lab_set_reports_what_is_missing(lab: dict[str, Any], tmp_path: Path) -> None:
    """Only the edge and the flats/darks: those are measured, the rest is reported as not
    measured (in the summary and the report), and the camera file still written."""
    import shutil

    src = lab["root"] / "set"
    part = tmp_path / "part"
    part.mkdir()
    for name in ("edge", "flats", "darks"):
        shutil.copytree(src / name, part / name)
    out = tmp_path / "out"
    r = execute("characterize", folder=str(part), out=out)
    assert r.summary["measured"] == ["sharpness", "noise"]
    assert set(r.summary["missing"]) == {"geometry", "color"}
    html = (out / "report.html").read_text()
    assert "Not measured: no checkerboard/ (or charuco/) folder" in html
    assert "nominal intrinsics" in html
    cam = tomllib.loads((out / "camera.toml").read_text())
    assert (cam["image"]["width"], cam["image"]["height"]) == SIZE
    assert set(cam) >= {"sensor", "optics"} and "color" not in cam
    # --force replaces a previous characterisation; flats and darks alone: no camera file
    shutil.rmtree(part / "edge")
    r = execute("characterize", folder=str(part), out=out, force=True)
    assert r.summary["measured"] == ["noise"] and r.summary["camera"] is None
    assert sorted(p.name for p in out.iterdir()) == ["metrics.json", "report.html"]


def _one_line_refusal(folder: Path, out: Path, match: str) -> None:
    with pytest.raises(ImageformError, match=match) as info:
        execute("characterize", folder=str(folder), out=out)
    msg = str(info.value)
    assert "\n" not in msg and len(msg) <= 220, msg
    assert not out.exists()


def test_refusals(tmp_path: Path, lab: dict[str, Any]) -> None:
    import shutil

    out = tmp_path / "out"
    empty = tmp_path / "empty"
    empty.mkdir()
    _one_line_refusal(empty, out, "holds none of checkerboard/")
    _one_line_refusal(tmp_path / "nope", out, "expected FOLDER a folder")
    flats_only = tmp_path / "flats_only"
    shutil.copytree(lab["root"] / "set" / "flats", flats_only / "flats")
    _one_line_refusal(flats_only, out, "nothing to measure.*no darks/")
    bad = tmp_path / "bad"
    (bad / "edge").mkdir(parents=True)
    (bad / "edge" / "edge.png").write_bytes(b"not a png")
    _one_line_refusal(bad, out, "edge.png")
    manifest = tmp_path / "manifest"
    shutil.copytree(lab["root"] / "set" / "edge", manifest / "edge")
    (manifest / "lab.toml").write_text("[camera]\nbogus = 1\n")
    _one_line_refusal(manifest, out, "unknown key.*bogus")
    noboard = tmp_path / "noboard"
    shutil.copytree(lab["root"] / "set" / "checkerboard", noboard / "checkerboard")
    _one_line_refusal(noboard, out, "board = ")
    inside = lab["root"] / "set"
    with pytest.raises(InvalidInputError, match="inside FOLDER"):
        execute("characterize", folder=str(inside), out=inside / "twin")


# ---------------------------------------------------------------- the report in a browser


def test_report_in_headless_chromium(lab: dict[str, Any], request: pytest.FixtureRequest) -> None:
    """Every image loads, no console error, nothing asked beyond the file and data: URIs,
    and the screenshot is not blank (as the simulate report's check)."""
    from tests.report.test_browser import _not_blank, _open

    page = request.getfixturevalue("browser_page")  # the simulate report's fixture
    seen = _open(page, lab["out"] / "report.html")
    images = page.evaluate(
        "Array.from(document.images).map(i => [i.alt, i.complete, i.naturalWidth])"
    )
    assert len(images) >= 5
    broken = [alt for alt, complete, width in images if not (complete and width > 0)]
    assert broken == [], f"images that did not load: {broken}"
    assert seen["console_errors"] == [] and seen["page_errors"] == []
    others = [u for u in seen["requests"] if not u.startswith(("file:", "data:"))]
    assert others == [], f"the report asked for {others}"
    _not_blank(page.screenshot(full_page=True))
    assert page.title() == "imageform camera characterisation"
    assert math.isfinite(lab["printed"]["color"]["delta_e00_mean"])


# ---------------------------------------------------------------- through render_lab_set


def _camera_x() -> Any:
    """Camera X as a camera file: geometry, an EMVA sensor, a Gaussian lens, the Nikon
    D5100 sensitivities and a fixed processing (white balance and matrix)."""
    from imageform.geometry import BrownConrady, Camera
    from imageform.io import CameraFile

    cam = Camera(
        [[FX, 0.0, CX], [0.0, FY, CY], [0.0, 0.0, 1.0]],
        image_size=SIZE,
        distortion=BrownConrady(k1=K1, k2=0.03),
    )
    return CameraFile(
        cam,
        sensor={
            "system_gain_dn_per_e": 0.4,
            "read_noise_e": 4.0,
            "bit_depth": 12,
            "black_level_dn": 64.0,
            "full_well_e": 9000.0,
        },
        optics={"model": "gaussian", "gaussian_sigma_px": 0.8},
        color={
            "white_balance": [1.9, 1.0, 1.6],
            "ccm": [[1.7, -0.5, -0.2], [-0.3, 1.6, -0.3], [0.0, -0.6, 1.6]],
            "ccm_to": "linear_srgb",
            "spectral_sensitivity": "nikon_d5100",
        },
    )


def _chart_scene(size: tuple[int, int], eye: list[float]) -> Any:
    from imageform.simulate import load_scene

    return load_scene(
        {
            "name": "chart",
            "render": {"width": size[0], "height": size[1], "supersampling": 2},
            "illuminant": {"type": "cie", "name": "D65", "illuminance_lux": 1000.0},
            "camera": {"fx_px": 500.0, "eye_m": eye, "target_m": [0.0, 0.0, 0.0]},
            "lens": {"defocus": False, "vignetting": "none", "f_number": 4.0},
            "objects": [{"type": "colorchecker", "center_m": [0.0, 0.0, 0.0], "width_m": 0.12}],
        }
    )


@pytest.mark.slow
def test_closed_loop_through_render_lab_set(tmp_path: Path) -> None:
    """characterise(render_lab_set(X)) gives X back, and simulating through the twin's
    camera file renders the ColorChecker as X does. render_lab_set photographs the chart as
    camera RGB and, from the same exposure, as the camera develops it, so that X's processing
    can be measured. Measured: fx -0.03 %,
    fy -0.01 %, cx -0.04 %, cy +0.07 %, k1 -0.14 %; MTF50 of the raw edge -1.2 % (0.2207
    against 0.2234; Malvar's demosaicing gave +1.5 %, +1.5 %, +0.7 % in R, G, B before issue
    26); gain +1.0 %, read noise -0.5 %; twin vs X mean CIEDE2000 0.76 (max 1.17) (75-90 s on
    2 shared cores)."""

    from imageform.analysis import mtf_crossing
    from imageform.color import delta_e_ciede2000
    from imageform.io import read_camera, write_camera
    from imageform.simulate import apply_camera_file, render_lab_set, simulate
    from tests.workflows.characterize_lab import _sub_box

    x = _camera_x()
    write_camera(tmp_path / "x.toml", x)
    lab = render_lab_set(read_camera(tmp_path / "x.toml"), tmp_path / "lab", views=12)
    text = lab.manifest.read_text()
    assert 'developed = "colorchecker/developed.png"' in text  # the camera's own output
    assert (lab.folder / "colorchecker" / "developed.png").is_file()
    twin_dir = tmp_path / "twin"
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert main(["characterize", str(lab.folder), "-o", str(twin_dir), "--json"]) == 0
    twin = read_camera(twin_dir / "camera.toml")
    assert 'id="truth"' in (twin_dir / "report.html").read_text()  # lab.toml's [truth] shown
    K = twin.camera.K
    for got, true in ((K[0, 0], FX), (K[1, 1], FY), (K[0, 2], CX), (K[1, 2], CY)):
        assert got == pytest.approx(true, rel=0.002)
    assert twin.camera.distortion.k1 == pytest.approx(K1, rel=0.02)
    assert twin.sensor.system_gain_dn_per_e == pytest.approx(0.4, rel=0.03)
    assert twin.sensor.read_noise_e == pytest.approx(4.0, rel=0.03)
    # the estimated sensitivities against X's (the shipped Nikon D5100 table): the same peaks
    from imageform.spectral import camera_sensitivities

    assert twin.color is not None and twin.color.sensitivity is not None
    wl, est = twin.color.sensitivity.to_array()
    nikon = camera_sensitivities("nikon_d5100")
    true_peaks = np.asarray(nikon.wavelengths)[np.argmax(np.asarray(nikon.values), axis=0)]
    assert np.allclose(wl[np.argmax(est, axis=0)], true_peaks, atol=20.0)
    # X's MTF along the edge normal: the Gaussian times the renderer's 2-point pixel box,
    # measured on the raw mosaic (no demosaicing; lab.toml's [truth] has it)
    summary = json.loads(buf.getvalue())
    angle = float(np.median(summary["sharpness"]["angles_deg"]))
    f = np.linspace(0.0, 1.0, 4001)
    t = math.radians(angle)
    own = np.exp(-2 * np.pi**2 * 0.8**2 * f**2) * _sub_box(f * math.cos(t), 2)
    own = own * _sub_box(f * math.sin(t), 2)
    true = tomllib.loads(lab.manifest.read_text())["truth"]["mtf50_cy_per_px"]
    assert true == pytest.approx(mtf_crossing(f, own, 0.5), rel=0.005)
    got = summary["sharpness"]["mtf50_cy_per_px"]["raw"]
    assert got == pytest.approx(true, rel=0.03)
    # the ColorChecker through X and through the twin
    scene = _chart_scene(SIZE, [0.0, -0.2, 0.0])
    a = simulate(apply_camera_file(scene, x), rng=1).patches
    b = simulate(apply_camera_file(scene, twin), rng=1).patches
    assert a is not None and b is not None
    de = np.asarray(delta_e_ciede2000(a.lab_measured, b.lab_measured))
    assert float(np.mean(de)) < 1.0, de


def test_raw_frames_and_grey_mosaics(lab: dict[str, Any], tmp_path: Path) -> None:
    """The other raw forms: flats and darks as DNG files (the first green photosite of each
    2x2 tile measured), and the edge as a grey 16-bit PNG mosaic described by lab.toml's
    [camera] cfa and levels; the same numbers come back."""
    from imageform.io import read_image, read_raw, write_dng, write_image

    src = lab["root"] / "set"
    folder = tmp_path / "raw"
    for kind in ("flats", "darks"):
        (folder / kind).mkdir(parents=True)
        for p in sorted((src / kind).glob("*.png")):
            frame = read_image(p)[..., 0]
            write_dng(folder / kind / (p.stem + ".dng"), frame, color_matrix=np.eye(3))
    (folder / "edge").mkdir()
    edge = read_raw(src / "edge" / "edge.dng")
    write_image(folder / "edge" / "edge.png", edge.mosaic[..., None])
    (folder / "lab.toml").write_text(
        '[camera]\ncfa = "RGGB"\nblack_level_dn = 64.0\nwhite_level_dn = 4095.0\n'
    )
    r = execute("characterize", folder=str(folder), out=tmp_path / "out")
    n = r.summary["noise"]
    assert n["plane"].startswith("G at (0, 1)") and n["frame_shape"] == [64, 64]
    assert n["system_gain_dn_per_e"] == pytest.approx(lab["truth"].gain, rel=0.05)
    assert n["read_noise_e"] == pytest.approx(lab["truth"].read_noise, rel=0.05)
    s = r.summary["sharpness"]
    assert s["raw"] and s["mtf50_cy_per_px"]["raw"] == pytest.approx(
        lab["printed"]["sharpness"]["mtf50_cy_per_px"]["raw"], rel=1e-6
    )


def test_charuco_views(tmp_path: Path) -> None:
    """A charuco/ folder and lab.toml's board = "charuco:9x7" (marker, dictionary): the
    ChArUco corners calibrate the camera (tests/geometry's twelve views, some cut by the
    border, as PNG files: fx, fy, cx, cy within 0.3 %, k1 within 5 %)."""
    pytest.importorskip("cv2")
    from imageform.geometry import CharucoBoard
    from imageform.io import write_image
    from tests.geometry.test_charuco import _render_view

    board = CharucoBoard((9, 7), 20.0, 15.0, "6x6_250")
    px = 64
    art = board.image(px, margin_px=px)
    K = np.array([[700.0, 0, 322.0], [0, 705.0, 238.0], [0, 0, 1]])
    dist = np.array([-0.12, 0.05, 0.0, 0.0, 0.0])
    rng = np.random.default_rng(5)
    (tmp_path / "lab" / "charuco").mkdir(parents=True)
    for k in range(12):
        rvec = np.array([rng.uniform(-0.6, 0.6), rng.uniform(-0.6, 0.6), rng.uniform(-0.3, 0.3)])
        shift = (110.0 if k % 2 else -110.0) if k % 3 == 2 else 0.0  # cut by the border
        tvec = np.array([-90.0 + shift + rng.uniform(-40, 40), -70.0 + rng.uniform(-30, 30), 330.0])
        img = _render_view(board, art, px, K, dist, rvec, tvec, (640, 480))
        write_image(tmp_path / "lab" / "charuco" / f"view-{k}.png", img)
    (tmp_path / "lab" / "lab.toml").write_text(
        '[checkerboard]\nboard = "charuco:9x7"\nsquare = "20mm"\nmarker = "15mm"\n'
        'dictionary = "6x6_250"\n'
    )
    r = execute("characterize", folder=str(tmp_path / "lab"), out=tmp_path / "out")
    g = r.summary["geometry"]
    assert g["views_used"] == 12 and g["board"] == "charuco:9x7"
    for key, want in (("fx", 700.0), ("fy", 705.0), ("cx", 322.0), ("cy", 238.0)):
        assert g[key] == pytest.approx(want, rel=3e-3), key
    assert g["k1"] == pytest.approx(-0.12, rel=0.05)


def test_linear_raw_chart_is_camera_rgb(lab: dict[str, Any], tmp_path: Path) -> None:
    """A ColorChecker as a linear (demosaiced) raw, as phones and LibRaw's X-Trans path give
    it, is camera RGB for characterize (it crashed on the black level's shape): its patch
    means are the mosaic's, within the demosaicing's few per cent."""
    import tifffile

    from imageform.sensor import demosaic
    from imageform.workflows._characterize_inputs import _read_photo
    from imageform.workflows._characterize_measure import _chart_patches

    dng = next((lab["root"] / "set" / "colorchecker").glob("*.dng"))
    with tifffile.TiffFile(dng) as tf:
        tags = [(t.code, t.dtype, t.count, t.value, True) for t in tf.pages[0].tags]
        mosaic = tf.pages[0].asarray()
    keep = [t for t in tags if t[0] >= 50706 and t[0] not in (50710, 50711)]
    rgb = np.asarray(demosaic(mosaic / 65535.0, "RGGB", method="bilinear")) * 65535.0
    linear = tmp_path / "chart.dng"
    tifffile.imwrite(linear, np.round(rgb).astype(np.uint16), photometric=34892, extratags=keep)
    im = _read_photo(linear, {}, "srgb", None, None)
    assert im.camera is not None and im.mosaic is None and im.encoded is None
    _, ours, _ = _chart_patches(im, 1024)
    _, ref, _ = _chart_patches(_read_photo(dng, {}, "srgb", None, None), 1024)
    np.testing.assert_allclose(ours, ref, rtol=0.05, atol=0.002)
