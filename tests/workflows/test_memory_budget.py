"""The memory budget (``IMAGEFORM_MAX_MEMORY``, default 4 GiB) and single-image commands that stay
well inside it: pointwise commands compute a band of rows at a time (issue 25: ``cvd`` on a
10000^2 PNG peaked at 7.3 GiB)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import imageform.workflows._images as images
from imageform.cli import main
from imageform.color import convert, simulate_cvd, white_balance
from imageform.io import read_image, write_image

SRC = Path(__file__).resolve().parents[2] / "src"


def _ramp(h: int, w: int) -> np.ndarray:
    rng = np.random.default_rng(7)
    yy, xx = np.mgrid[0:h, 0:w]
    base = np.stack([xx / w, yy / h, 0.5 + 0.45 * np.sin(xx / 23.0 + yy / 31.0)], axis=-1)
    return np.clip(base * 250 + rng.normal(0, 6, base.shape), 0, 255).astype(np.uint8)


def _quantised(a: np.ndarray) -> np.ndarray:
    return np.round(np.clip(np.asarray(a), 0.0, 1.0) * 255).astype(np.uint8)


@pytest.mark.parametrize("suffix", [".png", ".tif", ".npy"])
def test_bands_give_the_whole_image_result(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, suffix: str
) -> None:
    """Bands of 3 rows (a 64 x 48 image): the files hold what the whole-image call gives."""
    img = _ramp(48, 64)
    write_image(tmp_path / "in.png", img)
    monkeypatch.setattr(images, "BAND_BYTES", 3 * 64 * 3 * 8)
    cases = {
        "convert": (["--to", "display-p3"], convert(img, "srgb", "display_p3")),
        "cvd": (["--type", "deutan"], simulate_cvd(img, "deutan", 1.0, "machado2009")),
        "white-balance": ([], white_balance(img, "gray_world").image),
    }
    for cmd, (args, ref) in cases.items():
        out = tmp_path / f"{cmd}{suffix}"
        assert main([cmd, str(tmp_path / "in.png"), "-o", str(out), *args]) == 0
        got = np.load(out) if suffix == ".npy" else read_image(out)
        if suffix == ".png":
            np.testing.assert_array_equal(got, _quantised(ref), err_msg=cmd)
        elif suffix == ".tif":
            np.testing.assert_array_equal(got, np.asarray(ref, np.float32), err_msg=cmd)
        else:
            np.testing.assert_array_equal(got, np.asarray(ref), err_msg=cmd)


def test_out_of_range_error_over_bands(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--out-of-range error``: refused in one line with the count over every band, no file."""
    img = _ramp(48, 64)
    write_image(tmp_path / "in.png", img)
    monkeypatch.setattr(images, "BAND_BYTES", 3 * 64 * 3 * 8)
    ref = np.asarray(simulate_cvd(img, "protan", 1.0, "machado2009"))
    codes = np.round(ref * 255)  # outside: the values whose 8-bit code the clip moves
    n = int(np.count_nonzero((codes < 0) | (codes > 255)))
    assert n > 0
    out = tmp_path / "cvd.png"
    args = ["cvd", str(tmp_path / "in.png"), "-o", str(out), "--type", "protan"]
    assert main([*args, "--out-of-range", "error"]) == 1
    err = capsys.readouterr().err
    assert f"{n} values outside [0, 1]" in err and err.count("\n") == 1
    assert not out.exists()


def _peak_rss_mb(args: list[str], env: dict[str, str]) -> float:
    """Peak resident memory (MB) of ``python -m imageform ARGS`` alone (a fresh parent)."""
    code = (
        "import resource, subprocess, sys\n"
        "r = subprocess.run([sys.executable, '-m', 'imageform', *sys.argv[1:]])\n"
        "assert r.returncode == 0, r.returncode\n"
        "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code, *args], env=env, capture_output=True, text=True, timeout=600
    )
    assert done.returncode == 0, done.stderr
    return float(done.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize(
    ("cmd", "args"),
    [("cvd", ["--type", "deutan"]), ("convert", ["--to", "display-p3"]), ("white-balance", [])],
)
def test_pointwise_commands_need_little_more_than_the_image(
    tmp_path: Path, cmd: str, args: list[str]
) -> None:
    """A 2000 x 2000 RGB PNG (12 MB of samples): the command's peak memory above the same
    command on a 16 x 16 image stays under 150 MB (it was about 300 MB: float64 copies of the
    whole image), with a budget of 256 MiB."""
    env = {**os.environ, "PYTHONPATH": str(SRC), "IMAGEFORM_MAX_MEMORY": "256MiB"}
    write_image(tmp_path / "big.png", _ramp(2000, 2000))
    write_image(tmp_path / "tiny.png", _ramp(16, 16))
    tiny = _peak_rss_mb(
        [cmd, str(tmp_path / "tiny.png"), "-o", str(tmp_path / "t.png"), *args], env
    )
    big = _peak_rss_mb([cmd, str(tmp_path / "big.png"), "-o", str(tmp_path / "b.png"), *args], env)
    assert big - tiny < 150, (cmd, big, tiny)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("cmd", "args"),
    [("cvd", ["--type", "deutan"]), ("convert", ["--to", "display-p3"]), ("white-balance", [])],
)
def test_100_mpx_under_4_gib(tmp_path: Path, cmd: str, args: list[str]) -> None:
    """Issue 25's goal: a 10000 x 10000 RGB PNG through a single-image command under 4 GiB."""
    n = 10000
    yy = np.linspace(0, 255, n, dtype=np.float32)
    img = np.empty((n, n, 3), np.uint8)
    img[..., 0] = yy[None, :].astype(np.uint8)
    img[..., 1] = yy[:, None].astype(np.uint8)
    img[..., 2] = 128
    write_image(tmp_path / "big.png", img)
    del img
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    env.pop("IMAGEFORM_MAX_MEMORY", None)
    peak = _peak_rss_mb([cmd, str(tmp_path / "big.png"), "-o", str(tmp_path / "o.png"), *args], env)
    assert peak < 4 * 1024, peak
