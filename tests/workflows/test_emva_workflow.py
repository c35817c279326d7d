"""``imageform emva FOLDER -o result.json`` (issue 18): both folder layouts, the JSON result,
and one-line refusals of a malformed folder."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from benchmarks.bench_emva import SENSORS, record, truth
from imageform.cli import main
from imageform.errors import InvalidInputError
from imageform.io import write_image
from imageform.workflows import execute

SENSOR = SENSORS["ccd (preset, DSNU 3 e-)"]
SHAPE = (48, 48)


@pytest.fixture(scope="module")
def frames():  # type: ignore[no-untyped-def]
    return record(SENSOR, 0, frames=4, shape=SHAPE)


def _by_name(folder: Path, f, ext: str = ".tif") -> None:  # type: ignore[no-untyped-def]
    folder.mkdir(exist_ok=True)
    for i, t in enumerate(f.exposure_times):
        for n in range(f.flats.shape[1]):
            for kind, stack in (("flat", f.flats), ("dark", f.darks)):
                p = folder / f"{kind}_{t:.6g}_{n}{ext}"
                if ext == ".npy":
                    np.save(p, stack[i, n])
                else:
                    write_image(p, stack[i, n])


def _manifest(folder: Path, f, photons: bool = True) -> None:  # type: ignore[no-untyped-def]
    folder.mkdir(exist_ok=True)
    lines = []
    for i, t in enumerate(f.exposure_times):
        names: dict[str, list[str]] = {"flats": [], "darks": []}
        for n in range(f.flats.shape[1]):
            for kind, stack in (("flats", f.flats), ("darks", f.darks)):
                name = f"{kind}/e{i:02d}-{n}.png"
                (folder / kind).mkdir(exist_ok=True)
                write_image(folder / name, stack[i, n])
                names[kind].append(name)
        lines += ["[[exposure]]", f"time = {float(t)!r}"]
        if photons:
            lines.append(f"photons = {float(f.photons[i])!r}")
        lines += [f"flats = {json.dumps(names['flats'])}", f"darks = {json.dumps(names['darks'])}"]
    (folder / "emva.toml").write_text("\n".join(lines) + "\n")


def test_file_name_layout_through_the_command_line(
    tmp_path: Path, frames, capsys: pytest.CaptureFixture[str]
) -> None:  # type: ignore[no-untyped-def]
    _by_name(tmp_path / "frames", frames)
    out = tmp_path / "result.json"
    assert main(["emva", str(tmp_path / "frames"), "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "system gain K" in printed and "n/a (no photon counts)" in printed
    doc = json.loads(out.read_text())
    assert doc["format"] == "imageform-emva" and doc["layout"] == "file names"
    assert doc["exposures"] == len(frames.exposure_times) and doc["frame_shape"] == list(SHAPE)
    r = doc["results"]
    t = truth(SENSOR, SHAPE)
    assert r["system_gain"] == pytest.approx(t["K"], rel=0.03)
    assert r["dark_noise"] == pytest.approx(t["sigma_d"], rel=0.03)
    assert r["quantum_efficiency"] is None  # NaN is written as null
    assert len(r["snr_measured"]) == len(frames.exposure_times)


def test_manifest_with_photons_gives_the_quantum_efficiency(
    tmp_path: Path, frames, capsys: pytest.CaptureFixture[str]
) -> None:  # type: ignore[no-untyped-def]
    _manifest(tmp_path / "m", frames)
    out = tmp_path / "r.json"
    assert main(["emva", str(tmp_path / "m"), "-o", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    eta = truth(SENSOR, SHAPE)["eta"]
    assert summary["quantum_efficiency"] == pytest.approx(eta, rel=0.03)
    doc = json.loads(out.read_text())
    assert doc["layout"] == "manifest"
    assert doc["results"]["quantum_efficiency"] == summary["quantum_efficiency"]


def test_npy_frames_and_options(tmp_path: Path, frames) -> None:  # type: ignore[no-untyped-def]
    _by_name(tmp_path / "npy", frames, ext=".npy")
    res = execute(
        "emva",
        options=None,
        out=tmp_path / "r.json",
        folder=str(tmp_path / "npy"),
    )
    doc = json.loads((tmp_path / "r.json").read_text())
    assert res.summary["exposures"] == len(frames.exposure_times)
    assert doc["results"]["spatial_index"] > 0
    from imageform.workflows.registry import get_workflow

    opts = get_workflow("emva").make_options(spatial_index=3, fit_fraction=0.5)
    execute("emva", options=opts, out=tmp_path / "r2.json", folder=str(tmp_path / "npy"))
    doc2 = json.loads((tmp_path / "r2.json").read_text())
    assert doc2["results"]["spatial_index"] == 3
    assert doc2["results"]["fit_points"] < doc["results"]["fit_points"]


def _write(folder: Path, files: dict[str, np.ndarray | str]) -> Path:
    folder.mkdir()
    for name, v in files.items():
        p = folder / name
        p.parent.mkdir(exist_ok=True)
        if isinstance(v, str):
            p.write_text(v)
        else:
            np.save(p, v)
    return folder


FRAME = np.full((4, 4), 100, dtype=np.uint16)


@pytest.mark.parametrize(
    ("files", "words"),
    [
        ({}, "no emva.toml and no frames named"),
        ({"flat_0.1_0.npy": FRAME, "dark_0.1_0.npy": FRAME}, "at least 2 flat"),
        ({"emva.toml": "[[exposure]\n"}, "cannot read the manifest"),
        ({"emva.toml": "x = 1\n"}, "expected [[exposure]] tables"),
        (
            {"emva.toml": '[[exposure]]\ntime = 0.1\nflats = ["a.npy"]\ndarks = []\ngain = 2\n'},
            "unknown key(s) gain",
        ),
        ({"emva.toml": '[[exposure]]\ntime = "fast"\n'}, "expected time in seconds"),
        ({"emva.toml": "[[exposure]]\ntime = 0.1\nflats = 3\n"}, "flats as a list"),
        (
            {
                "emva.toml": '[[exposure]]\ntime = 0.1\nflats = ["a.npy", "b.npy"]\n'
                'darks = ["a.npy", "b.npy"]\nphotons = 5.0\n'
                '[[exposure]]\ntime = 0.2\nflats = ["a.npy", "b.npy"]\n'
                'darks = ["a.npy", "b.npy"]\n',
                "a.npy": FRAME,
                "b.npy": FRAME,
            },
            "photons given for some exposures only",
        ),
        (
            {
                "emva.toml": '[[exposure]]\ntime = 0.1\nflats = ["a.npy", "z.npy"]\ndarks = []\n',
                "a.npy": FRAME,
            },
            "does not exist",
        ),
        (
            {
                "flat_0.1_0.npy": FRAME,
                "flat_0.1_1.npy": FRAME[:2],
                "dark_0.1_0.npy": FRAME,
                "dark_0.1_1.npy": FRAME,
            },
            "frames of one size",
        ),
    ],
)
def test_malformed_folders_are_refused_in_one_line(tmp_path: Path, files, words) -> None:  # type: ignore[no-untyped-def]
    folder = _write(tmp_path / "f", files)
    with pytest.raises(InvalidInputError) as exc:
        execute("emva", out=tmp_path / "r.json", folder=str(folder))
    msg = str(exc.value)
    assert words in msg and "\n" not in msg
    assert not (tmp_path / "r.json").exists()


def test_not_a_folder(tmp_path: Path) -> None:
    with pytest.raises(InvalidInputError, match="expected FOLDER a folder"):
        execute("emva", out=tmp_path / "r.json", folder=str(tmp_path / "missing"))
    assert main(["emva", str(tmp_path / "missing"), "-o", str(tmp_path / "r.json")]) != 0


@pytest.mark.parametrize(
    ("values", "words"),
    [
        ({"fit_fraction": 1.5}, "--fit-fraction"),
        ({"fit_fraction": float("nan")}, "--fit-fraction"),
        ({"spatial_index": -1}, "--spatial-index"),
        ({"channel": 1.5}, "--channel"),
    ],
)
def test_options_are_checked(values: dict, words: str) -> None:  # type: ignore[type-arg]
    from imageform.workflows.registry import get_workflow

    with pytest.raises(InvalidInputError, match=words):
        get_workflow("emva").make_options(**values)
