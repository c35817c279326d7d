"""``imageform batch`` and ``imageform chunked`` through the command line, in real
processes: Ctrl-C (one line, exit 130, no traceback, the rerun resumes), a kill of
``chunked`` leaves no temporary file, and a missing optional extra is one line."""

from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from imageform.io import write_image

pytest.importorskip("distributed")

SRC = Path(__file__).resolve().parents[2] / "src"


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(SRC), "IMAGEFORM_TRACEBACK": ""}


def _imageform(*args: str) -> list[str]:
    return [sys.executable, "-m", "imageform", *args]


def _wait_for(predicate, timeout: float = 600.0) -> bool:  # type: ignore[no-untyped-def]
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if predicate():
            return True
        time.sleep(0.02)
    return False


def test_ctrl_c_prints_one_line_and_the_rerun_resumes(tmp_path: Path) -> None:
    rng = np.random.default_rng(0)
    (tmp_path / "in").mkdir()
    n = 80
    for i in range(n):
        write_image(
            tmp_path / "in" / f"x{i:02d}.png", rng.integers(1, 256, (300, 300, 3), np.uint8)
        )
    out = tmp_path / "out"
    argv = _imageform(
        "batch",
        "white-balance",
        f"{tmp_path}/in/*.png",
        "-o",
        str(out),
        "--workers",
        "1",
    )
    proc = subprocess.Popen(
        argv,
        env=_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,  # its own process group: SIGINT to it is a terminal's Ctrl-C
    )
    try:
        assert _wait_for(lambda: out.is_dir() and len(list(out.glob("*.png"))) >= 3)
        os.killpg(proc.pid, signal.SIGINT)
        stdout, stderr = proc.communicate(timeout=600)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 130, stderr
    assert "Traceback" not in stderr and stdout == ""
    (line,) = stderr.strip().splitlines()
    m = re.fullmatch(
        r"imageform: interrupted: (\d+) done, (\d+) remaining; run the same command again to "
        r"resume",
        line,
    )
    assert m, line
    done, remaining = int(m[1]), int(m[2])
    assert done >= 1 and done + remaining == n and remaining > 0
    assert not [p for p in out.rglob(".*") if ".tmp" in p.name or ".part" in p.name]
    # the same command again: what was recorded is skipped, the rest is done
    rerun = subprocess.run(
        [*argv, "--json"], env=_env(), capture_output=True, text=True, timeout=300
    )
    assert rerun.returncode == 0, rerun.stderr
    summary = json.loads(rerun.stdout)
    assert summary["skipped"] >= done and summary["skipped"] + summary["done"] == n
    assert summary["failed"] == 0 and len(list(out.glob("*.png"))) == n


def test_chunked_killed_leaves_no_temporary_file(tmp_path: Path) -> None:
    """SIGTERM mid-write: the temporary output is removed on the way out (exit 130); SIGKILL
    cannot be caught: the next run removes what it left."""
    tifffile = pytest.importorskip("tifffile")
    n = 4096
    src = tmp_path / "big.tif"

    def tiles():  # type: ignore[no-untyped-def]
        rng = np.random.default_rng(0)
        for _ in range((n // 256) ** 2):
            yield rng.integers(0, 256, (256, 256, 3), dtype=np.uint8)

    tifffile.imwrite(
        src, tiles(), shape=(n, n, 3), dtype=np.uint8, tile=(256, 256), photometric="rgb"
    )
    out = tmp_path / "out" / "p3.tif"
    out.parent.mkdir()
    argv = _imageform(
        "chunked", "convert", str(src), "-o", str(out), "--to", "display-p3", "--chunk", "256"
    )

    def temps() -> list[Path]:
        return [p for p in out.parent.iterdir() if p.name.startswith(".")]

    for sig in (signal.SIGTERM, signal.SIGKILL):
        proc = subprocess.Popen(
            argv, env=_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
        )
        try:
            assert _wait_for(lambda: bool(temps()) and temps()[0].stat().st_size > 2**20)
            proc.send_signal(sig)
            _, stderr = proc.communicate(timeout=600)
        finally:
            if proc.poll() is None:
                proc.kill()
        assert not out.exists()
        if sig == signal.SIGTERM:
            assert proc.returncode == 130 and "Traceback" not in stderr
            assert stderr.strip() == "imageform: interrupted; nothing new was written"
            assert not temps()
        else:
            assert temps()  # a SIGKILL leaves it ...
    done = subprocess.run(argv, env=_env(), capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert out.is_file() and not temps()  # ... and the next run removes it


_NO_DASK = """
import sys
class Block:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in ("dask", "distributed", "zarr"):
            raise ImportError(f"No module named {name!r}", name=name)
sys.meta_path.insert(0, Block())
from imageform.cli import main
sys.exit(main(sys.argv[1:]))
"""


@pytest.mark.parametrize("command", ["batch", "chunked"])
def test_missing_extra_is_one_line(tmp_path: Path, command: str) -> None:
    write_image(tmp_path / "a.tif", np.zeros((8, 8, 3), np.uint8))
    if command == "batch":
        args = ["batch", "convert", f"{tmp_path}/*.tif", "-o", str(tmp_path / "o")]
    else:
        args = ["chunked", "convert", str(tmp_path / "a.tif"), "-o", str(tmp_path / "o.tif")]
    proc = subprocess.run(
        [sys.executable, "-c", _NO_DASK, *args],
        env=_env(),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 1
    assert proc.stderr.strip().splitlines() == [
        f"imageform: error: imageform {command} needs "
        f"{'distributed' if command == 'batch' else 'dask'}, which is not installed: "
        'pip install "imageform[scale]"'
    ]


def test_bad_input_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Refused before any cluster starts: one line on stderr, a non-zero exit."""
    from imageform.cli import main

    (tmp_path / "in").mkdir()
    write_image(tmp_path / "in" / "a.png", np.zeros((4, 4, 3), np.uint8))
    out = str(tmp_path / "out")
    cases = [
        (["batch", "convert", f"{tmp_path}/none/*.png", "-o", out], 1, "no files match"),
        (
            ["batch", "convert", f"{tmp_path}/in/*.png", "-o", out, "--to", "lab"],
            1,
            "do not fit an integer image",
        ),
        (
            ["batch", "demosaic", f"{tmp_path}/in/*.png", "-o", out, "--method", "vng"],
            2,
            "valid: bilinear",
        ),
        (
            [
                "batch",
                "harmonize",
                f"{tmp_path}/in/*.png",
                "-o",
                out,
                "--correction",
                str(tmp_path / "no.json"),
            ],
            1,
            "does not exist",
        ),
        (["batch", "delta-e", f"{tmp_path}/in/*.png", "-o", out], 2, "No such command"),
        (
            ["batch", "convert", f"{tmp_path}/in/**/*.png", "-o", str(tmp_path / "in" / "o")],
            1,
            "match the input glob",
        ),
        (
            ["chunked", "convert", str(tmp_path / "in" / "a.png"), "-o", str(tmp_path / "o.tif")],
            1,
            "expected a TIFF (.tif, .tiff, or a slide scanner",
        ),
        (
            [
                "chunked",
                "white-balance",
                str(tmp_path / "in" / "a.png"),
                "-o",
                str(tmp_path / "o.tif"),
                "--method",
                "white-patch",
            ],
            2,  # a usage error: --help lists the three methods chunked processing streams
            "chunked processing streams gray-world, shades-of-gray, manual",
        ),
    ]
    for argv, code, text in cases:
        assert main(argv) == code, argv
        err = capsys.readouterr().err
        assert text in err, (argv, err)
        if code == 1:
            assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert not (tmp_path / "out").exists()


def _workers_of(pid: int) -> list[Any]:
    """The dask worker processes below ``pid`` (spawned by multiprocessing)."""
    import psutil

    found = []
    try:
        children = psutil.Process(pid).children(recursive=True)
    except psutil.Error:
        return []
    for c in children:
        with contextlib.suppress(psutil.Error):
            if "spawn_main" in " ".join(c.cmdline()):
                found.append(c)
    return found


def _storm(root: Path, seed: int, storm_s: float, n: int = 16) -> tuple[int, str, str, Path]:
    """Run a batch while its worker processes are SIGKILLed over and over (from the first
    output on, for ``storm_s`` seconds, every 0.02-0.1 s: the nannies' restarts fail too, and
    they give up); return the exit, stdout, stderr and
    the output folder. A run still going 240 s after the storm is a hang (pytest.fail)."""
    import psutil

    rng = np.random.default_rng(seed)
    (root / "in").mkdir(parents=True)
    for i in range(n):
        write_image(root / "in" / f"x{i:02d}.png", rng.integers(1, 256, (200, 200, 3), np.uint8))
    out = root / "out"
    argv = _imageform(
        "batch", "convert", f"{root}/in/*.png", "-o", str(out), "--to", "rec2020",
        "--workers", "2", "--suffix", ".tif", "--json",
    )  # fmt: skip
    proc = subprocess.Popen(
        argv, env=_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        start_new_session=True,
    )  # fmt: skip
    pick = np.random.default_rng(seed + 1000)
    try:
        assert _wait_for(lambda: proc.poll() is not None or any(out.glob("*.tif")), 300)
        t0 = time.monotonic()
        while time.monotonic() - t0 < storm_s and proc.poll() is None:
            workers = _workers_of(proc.pid)
            if workers:
                with contextlib.suppress(psutil.Error):
                    workers[int(pick.integers(len(workers)))].kill()
            time.sleep(float(pick.uniform(0.02, 0.1)))
        try:
            stdout, stderr = proc.communicate(timeout=240)
        except subprocess.TimeoutExpired:
            pytest.fail(f"the run hung after a storm of killed workers (seed {seed})")
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
    return proc.returncode, stdout, stderr, out


def _check_storm(rc: int, stdout: str, stderr: str, out: Path, n: int = 16) -> None:
    assert rc in (0, 1), stderr
    assert stderr == "", stderr  # nothing from the workers, the client or multiprocessing
    summary = json.loads(stdout)
    assert summary["done"] + summary["failed"] == n
    # a job whose worker was killed four times is failed (dask's KilledWorker): rerun it
    for job in summary["jobs"]:
        assert job["status"] == "done" or "KilledWorker" in (job["error"] or ""), job
    assert not [p.name for p in out.iterdir() if p.name.startswith(".") and ".tmp" in p.name]
    assert not [p.name for p in out.iterdir() if p.name.endswith(".lock")]


def test_storm_of_killed_workers_finishes(tmp_path: Path) -> None:
    """Worker processes killed over and over for 10 s: the run ends (never hangs), with every
    output done or failed for the kills, no temporary file and nothing on stderr; the rerun
    finishes the rest."""
    rc, stdout, stderr, out = _storm(tmp_path, 0, storm_s=10.0)
    _check_storm(rc, stdout, stderr, out)
    rerun = subprocess.run(
        [*_imageform("batch", "convert", f"{tmp_path}/in/*.png", "-o", str(out)),
         "--to", "rec2020", "--workers", "2", "--suffix", ".tif", "--json"],
        env=_env(), capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert rerun.returncode == 0, rerun.stderr
    assert len(list(out.glob("*.tif"))) == 16


@pytest.mark.slow
def test_twenty_storms_never_hang(tmp_path: Path) -> None:
    """Issue 25: a storm of killed workers hung 2 runs of 4. Twenty storms of 30 s each."""
    for seed in range(20):
        _check_storm(*_storm(tmp_path / f"r{seed}", seed, storm_s=30.0))


@pytest.mark.parametrize("delay", [0.0, 0.5, 1.5])
def test_ctrl_c_while_the_workers_start_is_one_line(tmp_path: Path, delay: float) -> None:
    """Ctrl-C (SIGINT to the whole process group) ``delay`` s after the first worker process
    exists (they import, start, connect): one line, exit 130, no worker traceback, no
    leaked-semaphore warning, no process left."""
    import psutil

    (tmp_path / "in").mkdir()
    # enough work that the run is still going ``delay`` s after the workers start, even on a
    # fast machine (four 8x8 images were all done within 1.5 s on CI's): 200 copies of a
    # 512x512 image, about 30 ms each there
    first = tmp_path / "in" / "x000.png"
    write_image(first, np.random.default_rng(0).integers(1, 256, (512, 512, 3), np.uint8))
    for i in range(1, 200):
        shutil.copyfile(first, tmp_path / "in" / f"x{i:03d}.png")
    proc = subprocess.Popen(
        _imageform("batch", "convert", f"{tmp_path}/in/*.png", "-o", str(tmp_path / "out"),
                   "--to", "rec2020", "--workers", "2"),
        env=_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        start_new_session=True,
    )  # fmt: skip
    family: set[int] = set()
    try:
        assert _wait_for(lambda: proc.poll() is not None or bool(_workers_of(proc.pid)), 300)
        assert proc.poll() is None, proc.communicate()
        time.sleep(delay)  # not a race: any moment of the start must give the same line
        family = {p.pid for p in psutil.Process(proc.pid).children(recursive=True)}
        os.killpg(proc.pid, signal.SIGINT)
        stdout, stderr = proc.communicate(timeout=600)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 130, stderr
    (line,) = stderr.strip().splitlines()
    assert line.startswith("imageform: interrupted: ") and stdout == ""
    assert _wait_for(lambda: not [p for p in family if psutil.pid_exists(p)], 30), "left running"
