"""imageform reconstruct on a real colonoscopy video (tests/data/endo: C3VD v3, CC BY 4.0).

Ten frames of an Olympus colonoscope in a colon phantom: an octagonal aperture in black
corners, smooth low-contrast tissue, specular highlights. With the defaults the sequence
cannot start (a few tens of SIFT keypoints a frame, most of them on the aperture's edge,
which stands still); the endoscopy options make it reconstruct
(benchmarks/check_endo_real.py measures the whole clip)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from imageform.cli import main

pytest.importorskip("cv2")
pytest.importorskip("matplotlib")

ENDO = Path(__file__).resolve().parents[1] / "data" / "endo"
#: the ten frames 0, 4, ..., 36 (the folder also has 40, 48 and 56, for every 8th frame)
FIRST_TEN = [ENDO / f"c3vdv3_f{i:03d}.jpg" for i in range(0, 40, 4)]


@pytest.fixture(scope="module")
def frames(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("endo") / "frames"
    folder.mkdir()
    for p in FIRST_TEN:
        shutil.copy(p, folder / p.name)
    return folder


def test_defaults_cannot_start_and_say_what_to_try(
    frames: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cam = ["--camera", str(ENDO / "camera.toml")]
    assert main(["reconstruct", str(frames), *cam, "-o", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert "no texture: at most 33 keypoints a frame" in err
    assert "--auto-mask" in err and "--contrast-threshold 0.01" in err and "--highlights" in err
    assert not (tmp_path / "out").exists()


def test_endoscopy_options_reconstruct_the_real_frames(
    frames: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    args = ["reconstruct", str(frames), "--camera", str(ENDO / "camera.toml"), "-o", str(out)]
    endo = ["--auto-mask", "--highlights", "--contrast-threshold", "0.01"]
    assert main([*args, *endo]) == 0, capsys.readouterr().err
    m = json.loads((out / "metrics.json").read_text())
    assert m["frames"] == 10 and m["registered"] >= 9
    assert m["points"] >= 100 and m["reprojection_px_median"] < 1.0
    assert 0.84 < m["masks"]["field_of_view_share"] < 0.9
    assert 0.001 < m["masks"]["highlight_share_mean"] < 0.02
    assert m["options"]["auto_mask"] is True and m["options"]["contrast_threshold"] == 0.01


def test_equalize_reaches_the_keypoints(
    frames: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # CLAHE before SIFT: more points than test_endoscopy_options_reconstruct_the_real_frames'
    # run without it (benchmarks/results/sfm-pycolmap16-2026-12-01a.md on the whole clip)
    counts = {}
    for eq in ([], ["--equalize"]):
        out = tmp_path / f"out{len(eq)}"
        args = ["reconstruct", str(frames), "--camera", str(ENDO / "camera.toml"), "-o", str(out)]
        endo = ["--auto-mask", "--contrast-threshold", "0.01", *eq]
        assert main([*args, *endo]) == 0, capsys.readouterr().err
        m = json.loads((out / "metrics.json").read_text())
        assert m["registered"] >= 9
        assert m["options"]["equalize"] is bool(eq)
        counts[bool(eq)] = m["points"]
    assert counts[True] > 1.3 * counts[False], counts


def test_mask_and_auto_mask_exclude_each_other(
    frames: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cam = ["--camera", str(ENDO / "camera.toml")]
    mask = ["--mask", str(frames / "c3vdv3_f000.jpg"), "--auto-mask"]
    assert main(["reconstruct", str(frames), *cam, *mask, "-o", str(tmp_path / "o")]) == 2
    assert "--mask FILE or --auto-mask, got both" in capsys.readouterr().err
    for bad in ("0", "1", "-0.5"):
        args = ["reconstruct", str(frames), *cam, "--contrast-threshold", bad]
        assert main([*args, "-o", str(tmp_path / "o")]) == 2
        assert "--contrast-threshold" in capsys.readouterr().err


def test_skip_blurred_leaves_out_the_frames_with_motion_blur(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import cv2
    import numpy as np

    # frames 3 and 7 of the ten smeared by a horizontal motion of 9 px (a line kernel)
    folder = tmp_path / "frames"
    folder.mkdir()
    k = np.zeros((9, 9), np.float32)
    k[4] = 1.0 / 9.0
    for i, p in enumerate(FIRST_TEN):
        im = cv2.imread(str(p))
        assert im is not None
        cv2.imwrite(str(folder / f"{p.stem}.png"), cv2.filter2D(im, -1, k) if i in (3, 7) else im)
    out = tmp_path / "out"
    args = ["reconstruct", str(folder), "--camera", str(ENDO / "camera.toml"), "-o", str(out)]
    endo = ["--auto-mask", "--contrast-threshold", "0.01", "--skip-blurred"]
    assert main([*args, *endo]) == 0, capsys.readouterr().err
    m = json.loads((out / "metrics.json").read_text())
    assert m["skipped_blurred"] == ["c3vdv3_f012.png", "c3vdv3_f028.png"]
    assert m["frames"] == 8 and m["registered"] == 8
    assert "left out 2 blurred frames" in capsys.readouterr().err
