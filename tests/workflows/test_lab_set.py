"""render_lab_set (issue 18, "The loop closes"): what a lab photographs of a camera file,
measured back by imageform's own commands: ``imageform calibrate`` on checkerboard/,
``imageform emva`` on the folder (emva.toml, flats/, darks/), the e-SFR on edge/."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import numpy as np
import pytest

from imageform.analysis.sfr import find_slanted_edges, slanted_edge_sfr
from imageform.cli import main
from imageform.errors import InvalidInputError
from imageform.geometry import BrownConrady, Camera
from imageform.io import CameraFile, read_camera, read_image
from imageform.simulate import LAB_FORMAT, LabSet, render_lab_set

FX, FY, CX, CY = 560.0, 555.0, 322.0, 236.0
SENSOR = {
    "system_gain_dn_per_e": 0.4,
    "read_noise_e": 2.5,
    "dsnu_e": 2.0,
    "prnu": 0.008,
    "full_well_e": 9000.0,
    "bit_depth": 12,
    "black_level_dn": 64.0,
    "quantum_efficiency": 0.65,
    "pixel_pitch_um": 3.0,
    "cfa": "RGGB",
}
MTF50 = 0.28


@pytest.fixture(scope="module")
def lab(tmp_path_factory: pytest.TempPathFactory) -> LabSet:
    cam = Camera(
        [[FX, 0, CX], [0, FY, CY], [0, 0, 1]],
        image_size=(640, 480),
        distortion=BrownConrady(k1=-0.18, k2=0.03),
    )
    cf = CameraFile(
        cam,
        sensor=SENSOR,
        optics={"model": "mtf50", "mtf50_cy_per_px": MTF50},
        color={"white_balance": [2.0, 1.0, 1.6]},
    )
    return render_lab_set(cf, tmp_path_factory.mktemp("lab") / "lab", rng=0)


def test_layout_and_manifest(lab: LabSet) -> None:
    root = lab.folder
    for sub in ("checkerboard", "colorchecker", "edge", "flats", "darks"):
        assert (root / sub).is_dir(), sub
    assert len(lab.checkerboard) == 8
    assert lab.colorchecker == root / "colorchecker" / "chart.dng"  # raw mosaics (issue 26)
    assert lab.edge == root / "edge" / "edge.dng"
    doc = tomllib.loads(lab.manifest.read_text())
    assert doc["format"] == LAB_FORMAT and doc["version"] == 1
    assert doc["checkerboard"]["inner_corners"] == [9, 6]
    assert [root / p for p in doc["checkerboard"]["images"]] == list(lab.checkerboard)
    assert doc["emva"]["manifest"] == "emva.toml" and doc["emva"]["exposures"] == 24
    truth = doc["truth"]
    assert truth["fx"] == FX and truth["read_noise_e"] == 2.5
    assert truth["system_gain_dn_per_e"] == pytest.approx(0.4, rel=1e-12)
    assert len(doc["colorchecker"]["patch_centers_px"]) == 24
    cf = read_camera(lab.camera)
    assert cf.sensor is not None and cf.sensor.read_noise_e == 2.5
    assert cf.optics is not None and cf.optics.mtf50_cy_per_px == MTF50
    img = read_image(lab.checkerboard[0])
    assert img.dtype == np.uint16 and img.shape == (480, 640, 3)
    flat = read_image(root / "flats" / "e10-0.png")
    assert flat.dtype == np.uint16 and flat.shape[:2] == (64, 64) and flat.size == 64 * 64


def test_emva_gives_back_gain_and_read_noise(lab: LabSet, tmp_path: Path) -> None:
    out = tmp_path / "emva.json"
    assert main(["emva", str(lab.folder), "-o", str(out)]) == 0
    r = json.loads(out.read_text())["results"]
    # measured +1.05 % and -0.8 % (seed 0)
    assert r["system_gain"] == pytest.approx(0.4, rel=0.03)
    assert r["dark_noise"] == pytest.approx(2.5, rel=0.03)
    truth = tomllib.loads(lab.manifest.read_text())["truth"]
    assert r["quantum_efficiency"] == pytest.approx(
        truth["quantum_efficiency_green_550nm"], rel=0.03
    )


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_calibrate_gives_back_the_intrinsics(lab: LabSet, tmp_path: Path) -> None:
    out = tmp_path / "cam.toml"
    pattern = str(lab.folder / "checkerboard" / "*.png")
    assert main(["calibrate", pattern, "--board", "9x6", "--square", "20mm", "-o", str(out)]) == 0
    est = read_camera(out).camera
    K = np.asarray(est.K)
    # measured -0.07 %, -0.04 %, -0.04 %, -0.05 % (seed 0)
    for value, true in ((K[0, 0], FX), (K[1, 1], FY), (K[0, 2], CX), (K[1, 2], CY)):
        assert abs(value / true - 1) < 0.002, (value, true)
    assert est.distortion is not None
    assert est.distortion.k1 == pytest.approx(-0.18, rel=0.02)  # measured -0.35 %


def test_edge_mtf50_is_the_files(lab: LabSet) -> None:
    pytest.importorskip("rawpy")
    from imageform.io import read_raw
    from imageform.sensor import equalize_cfa

    raw = read_raw(lab.edge)
    blk = float(np.mean(raw.black_level))
    img = equalize_cfa((raw.mosaic - blk) / (raw.white_level - blk), str(raw.cfa_pattern))
    rois = find_slanted_edges(img)
    assert len(rois) == 4
    truth = tomllib.loads(lab.manifest.read_text())["truth"]
    assert truth["mtf50_cy_per_px"] == [MTF50] * 3
    for roi in rois:
        r = slanted_edge_sfr(img, roi.roi)
        assert abs(abs(r.angle) - 5.0) < 0.3
        # the raw mosaic, no demosaicing (Malvar's added up to +5 %)
        assert r.mtf50[0] == pytest.approx(MTF50, rel=0.03)


def test_refusals(lab: LabSet, tmp_path: Path) -> None:
    with pytest.raises(InvalidInputError, match="exists"):
        render_lab_set(lab.camera, lab.folder)
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "photo.png").write_bytes(b"")
    with pytest.raises(InvalidInputError, match="not a lab set"):
        render_lab_set(lab.camera, tmp_path / "mine", force=True)
    with pytest.raises(InvalidInputError, match="views"):
        render_lab_set(lab.camera, tmp_path / "x", views=3)
    bare = CameraFile(Camera([[100.0, 0, 10], [0, 100.0, 10], [0, 0, 1]]))
    with pytest.raises(InvalidInputError, match="no image size"):
        render_lab_set(bare, tmp_path / "y")
