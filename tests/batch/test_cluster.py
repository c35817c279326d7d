"""imageform batch on a loopback dask cluster: results equal the in-process command,
resumability keyed on the manifest, a worker killed mid-run, every worker gone, failures,
Ctrl-C, --scheduler and the default local cluster. (Adapted to the registry: jobs run the
workflows, ``run_file`` replaces ``get_command(...).run``, the output folder is -o/--out.)"""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from imageform.batch import MANIFEST, JobResult, NoWorkersError, batch_options, run_batch
from imageform.cli import main
from imageform.io import read_image, write_image

pytest.importorskip("distributed")

N_IMAGES = 12


def _rgb_tree(root: Path, n: int = N_IMAGES, size: tuple[int, int] = (24, 32)) -> Path:
    """``n`` random 8-bit RGB PNGs in nested folders under ``root/in``."""
    rng = np.random.default_rng(7)
    for i in range(n):
        sub = root / "in" / f"site{i % 3}" / ("deep" if i % 2 else "")
        sub.mkdir(parents=True, exist_ok=True)
        write_image(sub / f"img{i:02d}.png", rng.integers(1, 256, (*size, 3), dtype=np.uint8))
    return root / "in"


def _mosaic_tree(root: Path, n: int = N_IMAGES) -> Path:
    rng = np.random.default_rng(8)
    for i in range(n):
        sub = root / "raw" / f"s{i % 2}"
        sub.mkdir(parents=True, exist_ok=True)
        write_image(sub / f"m{i:02d}.png", rng.integers(0, 65536, (16, 20), dtype=np.uint16))
    return root / "raw"


def _check_equal_in_process(report: Any, command: str, options: dict[str, Any], tmp: Path) -> None:
    """Each output decodes and equals the command run in this process on the same input."""
    from imageform.workflows import run_file

    opts = batch_options(command, options)
    assert report.count("done") + report.count("skipped") == len(report.results)
    for i, r in enumerate(report.results):
        ref = tmp / f"ref{i}{r.output.suffix}"
        run_file(command, r.input, ref, opts)
        np.testing.assert_array_equal(read_image(r.output), read_image(ref))


def _leftover_temps(out: Path) -> list[Path]:
    return [p for p in out.rglob(".*") if ".tmp" in p.name]


@pytest.mark.parametrize(
    ("command", "options", "tree"),
    [
        ("convert", {"to": "linear_srgb"}, _rgb_tree),
        ("white-balance", {"method": "gray-world"}, _rgb_tree),
        ("demosaic", {"pattern": "RGGB", "method": "bilinear"}, _mosaic_tree),
    ],
)
def test_outputs_equal_in_process(
    cluster: Any, tmp_path: Path, command: str, options: dict[str, Any], tree: Any
) -> None:
    src = tree(tmp_path)
    out = tmp_path / "out"
    report = run_batch(
        command, f"{src}/**/*.png", out, options, scheduler=cluster.scheduler_address
    )
    assert report.ok and report.count("done") == N_IMAGES
    assert {r.output.relative_to(out) for r in report.results} == {
        r.input.relative_to(src) for r in report.results
    }
    _check_equal_in_process(report, command, options, tmp_path)
    assert not _leftover_temps(out)


def _stain_tree(root: Path, n: int = 6) -> Path:
    """``n`` synthetic H&E tiles (known stains, different seeds) as 8-bit PNGs."""
    from imageform.analysis import synthetic_stain_image

    for i in range(n):
        sub = root / "slides" / f"scanner{i % 2}"
        sub.mkdir(parents=True, exist_ok=True)
        img, _, _ = synthetic_stain_image((40, 48), max_concentration=(0.8 + 0.1 * i, 0.6), rng=i)
        write_image(sub / f"tile{i}.png", img)
    return root / "slides"


def _expected_png(out: Path, result: np.ndarray) -> np.ndarray:
    """What an 8-bit PNG of ``result`` (clipped) decodes to, written the library's way."""
    write_image(out, np.clip(result, 0.0, 1.0))
    return read_image(out)


@pytest.mark.parametrize(
    ("method", "target_kind"),
    [("reinhard", "image"), ("macenko", "image"), ("reinhard", "json"), ("macenko", "json")],
)
def test_stain_normalize_on_the_cluster(
    cluster: Any, tmp_path: Path, method: str, target_kind: str
) -> None:
    """batch stain-normalize gives, file by file, what imageform.analysis's normaliser gives
    (target as an image or as saved statistics), never touching the inputs."""
    from imageform import analysis

    src = _stain_tree(tmp_path)
    target_img, _, _ = analysis.synthetic_stain_image(
        (48, 48), max_concentration=(1.4, 1.0), rng=99
    )
    target_png = tmp_path / "target.png"
    write_image(target_png, target_img)
    target_arr = read_image(target_png) / 255.0
    target: Path = target_png
    if target_kind == "json":
        target = tmp_path / "target.json"
        stats = (
            analysis.reinhard_stats(target_arr)
            if method == "reinhard"
            else analysis.macenko_stains(target_arr)
        )
        stats.to_json(target)
    before = {p: p.read_bytes() for p in src.rglob("*.png")}
    out = tmp_path / "out"
    options = {"method": method, "target": str(target), "clip": True}
    report = run_batch(
        "stain-normalize", f"{src}/**/*.png", out, options, scheduler=cluster.scheduler_address
    )
    assert report.ok and report.count("done") == len(before), [r.error for r in report.failed]
    fn = analysis.reinhard_normalize if method == "reinhard" else analysis.macenko_normalize
    for i, r in enumerate(report.results):
        expected = fn(read_image(r.input) / 255.0, target_arr)
        got = read_image(r.output)
        assert got.dtype == np.uint8 and got.shape == (40, 48, 3)
        diff = np.abs(got.astype(int) - _expected_png(tmp_path / f"e{i}.png", expected))
        assert diff.max() <= 1  # statistics from JSON round to the same 8-bit codes
    assert {p: p.read_bytes() for p in src.rglob("*.png")} == before


def test_harmonize_on_the_cluster(cluster: Any, tmp_path: Path) -> None:
    """batch harmonize applies a correction fitted on two charts (device B -> device A) to
    every file, as ColorCorrection.apply does, and brings device B's images to device A's."""
    from imageform.analysis import fit_color_correction
    from imageform.analysis.synthetic import COLORCHECKER_SRGB8
    from imageform.color import linear_to_srgb, srgb_to_linear

    def device_b(encoded: np.ndarray) -> np.ndarray:  # a 3x3 crosstalk in linear light
        m = np.array([[0.9, 0.08, 0.02], [0.05, 0.85, 0.1], [0.02, 0.1, 0.8]])
        return np.asarray(linear_to_srgb(np.asarray(srgb_to_linear(encoded)) @ m.T))

    chart_a = np.asarray(COLORCHECKER_SRGB8, dtype=np.float64) / 255.0
    corr = fit_color_correction(device_b(chart_a), chart_a, method="linear")
    corr_json = tmp_path / "corr.json"
    corr.to_json(corr_json)
    rng = np.random.default_rng(5)
    src = tmp_path / "site_b"
    src.mkdir()
    truth = {}
    for i in range(6):
        img_a = rng.uniform(0.1, 0.9, (24, 32, 3))
        write_image(src / f"b{i}.png", device_b(img_a), bit_depth=16)
        truth[f"b{i}.png"] = img_a
    out = tmp_path / "out"
    report = run_batch(
        "harmonize",
        f"{src}/*.png",
        out,
        {"correction": str(corr_json), "clip": True},
        scheduler=cluster.scheduler_address,
    )
    assert report.ok and report.count("done") == 6, [r.error for r in report.failed]
    for r in report.results:
        got = read_image(r.output)
        assert got.dtype == np.uint16  # the input's bit depth
        expected = np.clip(corr.apply(read_image(r.input) / 65535.0), 0, 1)
        np.testing.assert_allclose(got / 65535.0, expected, atol=1.0 / 65535)
        # and the correction undoes device B: back to device A's colours
        np.testing.assert_allclose(got / 65535.0, truth[r.input.name], atol=2e-3)


def test_resumable(cluster: Any, tmp_path: Path) -> None:
    src = _rgb_tree(tmp_path)
    out = tmp_path / "out"
    glob_ = f"{src}/**/*.png"
    addr = cluster.scheduler_address
    first = run_batch("convert", glob_, out, {"to": "rec2020"}, scheduler=addr)
    assert first.count("done") == N_IMAGES
    mtimes = {r.output: r.output.stat().st_mtime_ns for r in first.results}
    # second run: everything finished, nothing redone (no cluster needed at all)
    second = run_batch("convert", glob_, out, {"to": "rec2020"}, scheduler="tcp://127.0.0.1:1")
    assert second.count("skipped") == N_IMAGES and second.count("done") == 0
    # a deleted output is redone; a stale temporary file is never taken as finished
    gone, partial = first.results[3].output, first.results[5].output
    gone.unlink()
    partial.unlink()
    stale = partial.with_name(f".{partial.name}.deadbeef0000.tmp{partial.suffix}")
    stale.write_bytes(partial.name.encode())  # a truncated write left by a dead worker
    third = run_batch("convert", glob_, out, {"to": "rec2020"}, scheduler=addr)
    assert {r.output for r in third.results if r.status == "done"} == {gone, partial}
    assert third.count("skipped") == N_IMAGES - 2
    assert not stale.exists() and not _leftover_temps(out)
    _check_equal_in_process(third, "convert", {"to": "rec2020"}, tmp_path)
    for r in third.results:
        if r.status == "skipped":
            assert r.output.stat().st_mtime_ns == mtimes[r.output]
    # --force redoes everything
    assert (
        run_batch("convert", glob_, out, {"to": "rec2020"}, scheduler=addr, force=True).count(
            "done"
        )
        == N_IMAGES
    )


def test_worker_killed_mid_run(cluster: Any, client: Any, tmp_path: Path) -> None:
    """SIGKILL one worker process while jobs are in flight (each job holds its temporary
    file for 0.4 s before the rename); the scheduler re-runs its job elsewhere, the batch
    completes, every output is correct and no partial or temporary file remains."""
    src = _rgb_tree(tmp_path)
    out = tmp_path / "out"
    killed: dict[str, Any] = {}

    def kill_one(res: JobResult) -> None:
        temps = _leftover_temps(out)
        busy = [w for w, keys in client.processing().items() if keys]
        if killed or not busy or not temps:
            return  # wait for a result at which a job is mid-write
        pid = client.run(os.getpid, workers=[busy[0]])[busy[0]]
        os.kill(pid, signal.SIGKILL)
        killed.update(pid=pid, temps=temps)

    report = run_batch(
        "convert",
        f"{src}/**/*.png",
        out,
        {"to": "linear_srgb"},
        scheduler=cluster.scheduler_address,
        on_result=kill_one,
        hold_s=0.4,
    )
    assert killed, "the kill never happened"
    assert killed["temps"], "no job was mid-write when the worker was killed"
    assert report.ok, [r.error for r in report.failed]
    assert report.count("done") == N_IMAGES
    _check_equal_in_process(report, "convert", {"to": "linear_srgb"}, tmp_path)
    assert not _leftover_temps(out)
    client.wait_for_workers(2, timeout=60)  # the nanny restarts the worker
    assert killed["pid"] not in client.run(os.getpid).values()


def test_failures_reported_cli(
    cluster: Any, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    src = _rgb_tree(tmp_path, n=4)
    (src / "site0" / "corrupt.png").write_bytes(b"\x89PNG\r\n\x1a\n truncated")
    out = tmp_path / "out"
    argv = ["batch", "white-balance", f"{src}/**/*.png", "-o", str(out)]
    code = main([*argv, "--scheduler", cluster.scheduler_address])
    text = capsys.readouterr().out
    assert code == 1
    assert "4 done, 0 skipped (already finished), 1 failed" in text
    (line,) = [ln for ln in text.splitlines() if ln.startswith("failed: ")]
    assert "corrupt.png: UnreadableFileError:" in line and "corrupt" in line.split(": ", 2)[2]
    assert len(list(out.rglob("*.png"))) == 4 and not _leftover_temps(out)
    code = main([*argv, "--scheduler", cluster.scheduler_address, "--json"])
    import json

    payload = json.loads(capsys.readouterr().out)
    assert code == 1 and (payload["skipped"], payload["failed"]) == (4, 1)
    (bad,) = [j for j in payload["jobs"] if j["status"] == "failed"]
    assert bad["input"].endswith("corrupt.png") and bad["error"].startswith("UnreadableFileError")


def test_bad_scheduler_address(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import dask

    src = _rgb_tree(tmp_path, n=1)
    with dask.config.set({"distributed.comm.timeouts.connect": "1s"}):
        code = main(
            ["batch", "convert", f"{src}/**/*.png", "-o", str(tmp_path / "o"), "--to", "srgb"]
            + ["--scheduler", "tcp://127.0.0.1:9"]
        )
    assert code == 1 and "cannot reach the scheduler" in capsys.readouterr().err


def test_default_local_cluster_cli(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """No --scheduler: a LocalCluster of worker processes is started and shut down."""
    src = _rgb_tree(tmp_path, n=3)
    code = main(
        ["batch", "convert", f"{src}/**/*.png", "-o", str(tmp_path / "o"), "--to", "lab"]
        + ["--suffix", ".npy", "--workers", "1", "--json"]
    )
    assert code == 0
    import json

    assert json.loads(capsys.readouterr().out)["done"] == 3
    lab = np.load(next((tmp_path / "o").rglob("*.npy")))
    assert lab.shape == (24, 32, 3) and lab[..., 0].min() >= 0 and lab[..., 0].max() <= 100


def test_rerun_with_another_method_recomputes(
    cluster: Any, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Resume is keyed on what produced an output (manifest): the same command skips every
    finished file; another --method recomputes them all, and its outputs are the new
    method's; a touched input is redone alone."""
    import json

    src = _rgb_tree(tmp_path, n=4)
    out = tmp_path / "out"
    base = ["batch", "white-balance", f"{src}/**/*.png", "-o", str(out), "--json"]
    base += ["--scheduler", cluster.scheduler_address]
    assert main([*base, "--method", "gray-world"]) == 0
    assert json.loads(capsys.readouterr().out)["done"] == 4
    manifest = json.loads((out / MANIFEST).read_text())
    assert len(manifest["outputs"]) == 4
    entry = next(iter(manifest["outputs"].values()))
    assert entry["command"] == "white-balance" and entry["options"]["method"] == "gray_world"
    first = {p: read_image(p) for p in out.rglob("*.png")}
    assert main([*base, "--method", "gray_world"]) == 0  # the other spelling: same options
    assert json.loads(capsys.readouterr().out)["skipped"] == 4
    assert main([*base, "--method", "max-rgb"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert (res["done"], res["skipped"]) == (4, 0)
    _check_equal_in_process(
        run_batch(
            "white-balance",
            f"{src}/**/*.png",
            out,
            {"method": "max-rgb"},
            scheduler="tcp://127.0.0.1:1",
        ),
        "white-balance",
        {"method": "max-rgb"},
        tmp_path,
    )
    assert any(not np.array_equal(first[p], read_image(p)) for p in first)
    # an input that changed (size or time) is redone, the others are not
    touched = next(src.rglob("*.png"))
    os.utime(touched, ns=(touched.stat().st_atime_ns, touched.stat().st_mtime_ns + 10**9))
    assert main([*base, "--method", "max-rgb"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert (res["done"], res["skipped"]) == (1, 3)
    (done,) = [j for j in res["jobs"] if j["status"] == "done"]
    assert done["input"] == str(touched)


def test_every_worker_gone_stops_with_a_message(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A scheduler with no worker (all died, none restarted): the run stops after the
    timeout with one line saying what is done, never hangs."""
    import logging

    import distributed

    src = _rgb_tree(tmp_path, n=2)
    with (
        distributed.LocalCluster(
            n_workers=0, processes=False, dashboard_address=":0", silence_logs=logging.ERROR
        ) as empty,
        pytest.raises(
            NoWorkersError, match=r"every dask worker is gone .*\(0 jobs done, 2 remaining\)"
        ),
    ):
        run_batch(
            "convert",
            f"{src}/**/*.png",
            tmp_path / "o",
            {"to": "srgb"},
            scheduler=empty.scheduler_address,
            worker_timeout_s=2,
        )
    assert not list((tmp_path / "o").rglob("*.png")) if (tmp_path / "o").exists() else True


def test_two_runs_into_one_folder_keep_each_others_temporaries(
    cluster: Any, tmp_path: Path
) -> None:
    """Run B starts while run A's jobs hold their temporary files (hold_s): B's cleanup of
    temporaries left by dead runs leaves A's alone, and both runs finish every job."""
    import threading

    (tmp_path / "in").mkdir()
    for i in range(2):
        write_image(tmp_path / "in" / f"x{i}.png", np.full((4, 4, 3), 60 + i, np.uint8))
    out = tmp_path / "out"
    addr = cluster.scheduler_address
    reports: dict[str, Any] = {}

    def run_a() -> None:
        reports["a"] = run_batch(
            "convert", f"{tmp_path}/in/*.png", out, {"to": "rec2020"}, scheduler=addr, hold_s=4.0
        )

    thread = threading.Thread(target=run_a)
    thread.start()
    deadline = time.monotonic() + 600
    while not list(out.glob(".x*.tmp.png")) and time.monotonic() < deadline:
        time.sleep(0.05)
    live = list(out.glob(".x*.tmp.png"))
    assert live, "run A wrote no temporary file"
    reports["b"] = run_batch(
        "convert", f"{tmp_path}/in/*.png", out, {"to": "rec2020"}, scheduler=addr, force=True
    )
    thread.join(120)
    assert reports["a"].ok and reports["a"].count("done") == 2, reports["a"].failed
    assert reports["b"].ok and reports["b"].count("done") == 2, reports["b"].failed
    assert not _leftover_temps(out)
    assert sorted(p.name for p in out.iterdir()) == [MANIFEST, "x0.png", "x1.png"]
