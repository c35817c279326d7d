"""Highlight roll-off of a brightened development, and Git LFS pointers given as raw files
(docs/raw.md; benchmarks/results/raw-sweep-2026-11-30k.md)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imageform.errors import UnreadableFileError
from imageform.io import develop, read_raw, write_dng
from imageform.io.raw import _highlight_shoulder

pytest.importorskip("rawpy")

#: XYZ (D65) to camera RGB of a made-up camera (rows: R, G, B).
CM = np.array([[1.20, -0.30, -0.10], [-0.40, 1.30, 0.10], [-0.05, 0.20, 0.60]])


def test_shoulder_is_the_identity_below_the_knee_and_white_at_the_sensor_white() -> None:
    """f(y) = y up to 0.8, continuous with slope 1 there, increasing, f(g) = 1, below 1
    before; a gain of 1 or less is a plain clip."""
    g = 2.0**2.65
    y = np.linspace(0.0, g, 20001)
    f = _highlight_shoulder(y, g)
    below = y <= 0.8
    np.testing.assert_array_equal(f[below], y[below])
    assert np.all(np.diff(f) > 0)
    assert f[-1] == pytest.approx(1.0) and np.all(f[:-1] < 1.0)
    h = 1e-7
    slope = (_highlight_shoulder(np.array([0.8 + h]), g)[0] - 0.8) / h
    assert slope == pytest.approx(1.0, abs=1e-5)
    np.testing.assert_array_equal(_highlight_shoulder(np.array([0.5, 1.5]), 1.0), [0.5, 1.0])


@pytest.fixture
def bright_dng(tmp_path: Path) -> Path:
    """A ramp from black to the sensor's white with BaselineExposure +2 stops."""
    ramp = np.linspace(64, 4095, 64 * 96).reshape(64, 96).astype(np.uint16)
    return write_dng(
        tmp_path / "b.dng",
        ramp,
        black_level=64,
        white_level=4095,
        color_matrix=CM,
        baseline_exposure_ev=2.0,
    )


def test_rolloff_keeps_the_shadows_and_clips_nothing_the_sensor_did_not(bright_dng: Path) -> None:
    """The same image as the clipped development where its linear values are under the knee;
    above, distinct values stay distinct (the clipped one makes most of them white); the
    float image and ``linear_rgb`` agree (the fused 16-bit pass: the command-line test)."""
    raw = read_raw(bright_dng)
    clip = develop(raw, baseline_exposure=True, linear=True)
    roll = develop(raw, baseline_exposure=True, linear=True, highlight_rolloff=True)
    assert roll.highlight_rolloff and roll.brightness == pytest.approx(4.0)
    a, b = clip.image, roll.image
    low = a < 0.79
    np.testing.assert_allclose(b[low], a[low], atol=2e-5)
    assert np.mean(a >= 1.0) > 0.5 and np.mean(b >= 1.0) < 0.01
    np.testing.assert_allclose(roll.linear_rgb, b, atol=2e-5)
    # no brightening above 1: the option changes nothing
    dark = develop(raw, highlight_rolloff=True)
    assert not dark.highlight_rolloff
    np.testing.assert_array_equal(dark.image, develop(raw).image)
    assert any("roll-off changes nothing" in n for n in dark.notes)  # said, not silent
    assert not any("roll-off" in n for n in roll.notes)


def test_cli_highlight_rolloff(bright_dng: Path, tmp_path: Path) -> None:
    from imageform.cli import main
    from imageform.io import read_image

    out = tmp_path / "r.png"
    args = ["develop", str(bright_dng), "-o", str(out), "--baseline-exposure"]
    assert main([*args, "--highlight-rolloff"]) == 0
    rolled = np.asarray(read_image(out))
    assert main([*args, "--force"]) == 0
    clipped = np.asarray(read_image(out))
    white = np.iinfo(clipped.dtype).max
    assert np.mean(clipped == white) > np.mean(rolled == white) + 0.3


def test_git_lfs_pointer_is_refused_naming_it(tmp_path: Path) -> None:
    """A raw file a clone without ``git lfs`` left as its pointer: said so, with the size."""
    p = tmp_path / "d610.nef"
    p.write_text(
        "version https://git-lfs.github.com/spec/v1\n"
        "oid sha256:5bda50f502dabc37f1e91616197ea6e3dcb158a471f2fbfd38d1c69ce07b055e\n"
        "size 19561780\n"
    )
    with pytest.raises(UnreadableFileError, match=r"Git LFS pointer.*19561780-byte"):
        read_raw(p)


def test_info_names_the_baseline_exposure(
    bright_dng: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from imageform.cli import main

    assert main(["info", str(bright_dng)]) == 0
    assert "BaselineExposure +2.00 EV" in capsys.readouterr().out
