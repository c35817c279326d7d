"""Planning, atomic single jobs and option checks of imageform.batch (no cluster needed).

The commands are the registry's workflows that run file by file (``batch_workflow``); their
options the workflow's dataclass (``batch_options``), the old ``COMMANDS`` table is gone."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imageform.batch import batch_options, batch_workflow, plan_jobs, run_batch, run_job
from imageform.batch._temps import _remove_stale_temps, temp_pattern
from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.io import read_image, write_image


def _tree(root: Path) -> list[Path]:
    rng = np.random.default_rng(1)
    paths = [root / "in" / "x.png", root / "in" / "a" / "y.png", root / "in" / "a" / "b" / "z.png"]
    for p in paths:
        p.parent.mkdir(parents=True, exist_ok=True)
        write_image(p, rng.integers(0, 256, (6, 8, 3), dtype=np.uint8))
    return paths


def test_plan_keeps_relative_folders(tmp_path: Path) -> None:
    _tree(tmp_path)
    jobs = plan_jobs(f"{tmp_path}/in/**/*.png", tmp_path / "out")
    rel = sorted(str(j.output.relative_to(tmp_path / "out")) for j in jobs)
    assert rel == ["a/b/z.png", "a/y.png", "x.png"]
    jobs = plan_jobs(f"{tmp_path}/in/a/*.png", tmp_path / "out", out_suffix="tif")
    assert [j.output.relative_to(tmp_path / "out").as_posix() for j in jobs] == ["y.tif"]


def test_plan_takes_a_folder_and_a_kind_the_command_writes(tmp_path: Path) -> None:
    """A folder stands for its files (not its sub-folders' nor hidden ones); with ``writes``,
    an input of a suffix the command does not write (a raw file, a WebP) gets the first of
    them, the others keep theirs; ``out_suffix`` still wins."""
    _tree(tmp_path)
    (tmp_path / "in" / "r.dng").write_bytes(b"")
    (tmp_path / "in" / ".hidden.png").write_bytes(b"")
    jobs = plan_jobs(str(tmp_path / "in"), tmp_path / "out", writes=(".png", ".tif"))
    names = sorted(j.output.relative_to(tmp_path / "out").as_posix() for j in jobs)
    assert names == ["r.png", "x.png"]
    jobs = plan_jobs(f"{tmp_path}/in", tmp_path / "out", out_suffix=".tif", writes=(".png",))
    assert sorted(j.output.name for j in jobs) == ["r.tif", "x.tif"]
    assert [j.output.name for j in plan_jobs(f"{tmp_path}/in/r.dng", tmp_path / "o")] == ["r.dng"]
    with pytest.raises(InvalidInputError, match="expected writes as file suffixes"):
        plan_jobs(str(tmp_path / "in"), tmp_path / "out", writes=("png",))
    # reads: a folder's other files are not inputs (a glob's are: it named them)
    (tmp_path / "in" / "notes.txt").write_text("x")
    jobs = plan_jobs(str(tmp_path / "in"), tmp_path / "out", reads=(".PNG", ".dng"))
    assert sorted(j.input.name for j in jobs) == ["r.dng", "x.png"]
    jobs = plan_jobs(str(tmp_path / "in"), tmp_path / "out", reads=(".dng",), writes=(".png",))
    assert [j.output.name for j in jobs] == ["r.png"]
    assert len(plan_jobs(f"{tmp_path}/in/*", tmp_path / "out", reads=(".png",))) == 3
    with pytest.raises(InvalidInputError, match=r"no file of the kinds read \(\.cr2\) in"):
        plan_jobs(str(tmp_path / "in"), tmp_path / "out", reads=(".cr2",))
    with pytest.raises(InvalidInputError, match="expected reads as file suffixes"):
        plan_jobs(str(tmp_path / "in"), tmp_path / "out", reads=".png")
    (tmp_path / "in" / "x.dng").write_bytes(b"")  # x.png and x.dng would both write x.png
    with pytest.raises(InvalidInputError, match="would both write"):
        plan_jobs(str(tmp_path / "in"), tmp_path / "out", writes=(".png",))


def test_plan_refuses_outputs_over_inputs(tmp_path: Path) -> None:
    _tree(tmp_path)
    with pytest.raises(InvalidInputError, match="overwrite an input or match the input glob"):
        plan_jobs(f"{tmp_path}/in/**/*.png", tmp_path / "in")
    with pytest.raises(InvalidInputError, match="match the input glob"):
        plan_jobs(f"{tmp_path}/in/**/*.png", tmp_path / "in" / "out")
    # a non-recursive glob does not reach in/out/: allowed
    assert len(plan_jobs(f"{tmp_path}/in/*.png", tmp_path / "in" / "out")) == 1
    write_image(tmp_path / "in" / "x.tif", np.zeros((2, 2, 3), np.uint8))
    with pytest.raises(InvalidInputError, match="would both write"):
        plan_jobs(f"{tmp_path}/in/x.*", tmp_path / "out", out_suffix=".npy")
    with pytest.raises(InvalidInputError, match="no files match"):
        plan_jobs(f"{tmp_path}/nothing/*.png", tmp_path / "out")


def test_temp_files_are_hidden_from_the_glob(tmp_path: Path) -> None:
    (tmp_path / "in").mkdir()
    write_image(tmp_path / "in" / "x.png", np.zeros((2, 2, 3), np.uint8))
    stale = tmp_path / "in" / ".x.png.0123456789ab.tmp.png"
    stale.write_bytes(b"partial")
    assert stale.match(temp_pattern(tmp_path / "in" / "x.png"))
    assert [j.input.name for j in plan_jobs(f"{tmp_path}/in/**/*.png", tmp_path / "o")] == ["x.png"]


def test_stale_temps_of_killed_workers_removed(tmp_path: Path) -> None:
    """A worker killed mid-write leaves the job's temporary file, or, killed while the
    workflow's own atomic writer was still writing, that writer's part file beside it (the
    leftover CI once found); both go, the outputs and unrelated hidden files stay."""
    (tmp_path / "in").mkdir()
    write_image(tmp_path / "in" / "x.png", np.zeros((2, 2, 3), np.uint8))
    (job,) = plan_jobs(f"{tmp_path}/in/*.png", tmp_path / "out")
    folder = job.output.parent
    folder.mkdir()
    job.output.write_bytes(b"done")
    leftovers = [
        ".x.png.0123456789ab.tmp.png",
        "..x.png.94c6d2ac0bb8.tmp.png.2512-7b4302b7.part.png",
    ]
    for name in [*leftovers, ".y.png.0123456789ab.tmp.png", ".keep"]:
        (folder / name).write_bytes(b"partial")
    assert _remove_stale_temps([job]) == 2
    assert sorted(p.name for p in folder.iterdir()) == [
        ".keep",
        ".y.png.0123456789ab.tmp.png",
        "x.png",
    ]


def test_run_job_atomic_and_failure(tmp_path: Path) -> None:
    (src,) = _tree(tmp_path)[:1]
    out = tmp_path / "out" / "deep" / "x.png"
    res = run_job("convert", str(src), str(out), {"to": "linear_srgb"})
    assert res["ok"] and out.is_file() and res["metrics"]["shape"] == [6, 8, 3]
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"\x89PNG garbage")
    res = run_job("convert", str(bad), str(tmp_path / "out" / "bad.png"), {"to": "srgb"})
    assert not res["ok"] and res["error"].startswith("UnreadableFileError:")
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["deep"]  # no temp left
    assert sorted(p.name for p in (tmp_path / "out" / "deep").iterdir()) == ["x.png"]
    assert read_image(src).dtype == np.uint8  # input untouched and readable


def test_command_options_checked(tmp_path: Path) -> None:
    from imageform.workflows import WORKFLOWS

    batchable = {n for n, w in WORKFLOWS.items() if w.batch}
    assert {"convert", "white-balance", "demosaic", "stain-normalize", "harmonize"} <= batchable
    with pytest.raises(UnknownOptionError, match=r"valid: .*convert"):
        batch_workflow("convrt")
    with pytest.raises(UnknownOptionError, match="does not run in imageform batch"):
        batch_workflow("delta-e")
    with pytest.raises(UnknownOptionError, match="unknown option 'to' of batch demosaic"):
        batch_options("demosaic", {"to": "lab"})
    with pytest.raises(UnknownOptionError, match="valid: bilinear"):
        batch_options("demosaic", {"method": "vng"})
    # flags and field names alike; the single command's defaults
    assert batch_options("convert", {"--to": "lab"}) == batch_options("convert", {"dst": "lab"})
    assert batch_options("stain-normalize", {"target": "t.png"}).method == "macenko"
    assert batch_options("white-balance", {}).method == "gray_world"
    with pytest.raises(InvalidInputError, match="does not take --save-target"):
        batch_options("stain-normalize", {"target": "t.png", "save_target": "s.json"})
    _tree(tmp_path)
    glob_ = f"{tmp_path}/in/*.png"
    with pytest.raises(InvalidInputError, match="do not fit an integer image"):
        run_batch("convert", glob_, tmp_path / "o", {"to": "lab"}, scheduler="tcp://127.0.0.1:1")
    with pytest.raises(InvalidInputError, match=r"writes \.png"):
        run_batch("mosaic", glob_, tmp_path / "o", {}, out_suffix=".json")
    with pytest.raises(InvalidInputError, match=r"^--correction file .*no\.json does not exist$"):
        run_batch("harmonize", glob_, tmp_path / "o", {"correction": str(tmp_path / "no.json")})
    with pytest.raises(InvalidInputError, match=r"^--correction file .* is not a file$"):
        run_batch("harmonize", glob_, tmp_path / "o", {"correction": str(tmp_path)})
    assert not (tmp_path / "o").exists()  # refused before anything ran


def test_plan_refuses_an_output_folder_linked_into_the_inputs(tmp_path: Path) -> None:
    """The self-input guard compares real paths: an output folder that is a symbolic link to
    a folder the glob reaches is refused, as the folder itself would be."""
    _tree(tmp_path)
    (tmp_path / "out_link").symlink_to(tmp_path / "in" / "a", target_is_directory=True)
    with pytest.raises(InvalidInputError, match="match the input glob"):
        plan_jobs(f"{tmp_path}/in/**/*.png", tmp_path / "out_link")
    # a link to a folder outside the inputs is fine
    (tmp_path / "real_out").mkdir()
    (tmp_path / "ok_link").symlink_to(tmp_path / "real_out", target_is_directory=True)
    assert len(plan_jobs(f"{tmp_path}/in/**/*.png", tmp_path / "ok_link")) == 3
    # and an input tree reached through a link is compared by its real path too
    (tmp_path / "in_link").symlink_to(tmp_path / "in", target_is_directory=True)
    with pytest.raises(InvalidInputError, match="match the input glob"):
        plan_jobs(f"{tmp_path}/in_link/**/*.png", tmp_path / "in" / "out")


def test_runner_exports_the_plan_names_from_one_list() -> None:
    # the plan's public names are listed once, in batch._plan (duplicates: the list was
    # written again in batch.runner); runner re-exports them and the package exports both
    import imageform.batch as batch
    from imageform.batch import _plan, runner

    assert set(_plan.__all__) <= set(runner.__all__) <= set(batch.__all__)
    assert len(runner.__all__) == len(set(runner.__all__))
    for name in runner.__all__:
        assert getattr(runner, name) is getattr(batch, name)


def test_batch_develop_takes_a_folder_of_raw_files(tmp_path: Path) -> None:
    """``imageform batch develop FOLDER -o OUT``: the folder's raw files are developed to .png
    (a raw suffix is one develop does not write), which the next command reads; the folder's
    other files (a PNG, notes) are not develop's inputs."""
    from imageform.io import write_dng

    rng = np.random.default_rng(3)
    cm = [[1.2, -0.3, -0.1], [-0.4, 1.3, 0.1], [-0.05, 0.2, 0.6]]
    (tmp_path / "raw").mkdir()
    mosaic = rng.integers(200, 3000, size=(128, 192)).astype(np.uint16)
    write_dng(tmp_path / "raw" / "a.dng", mosaic, black_level=64, white_level=4095, color_matrix=cm)
    (tmp_path / "raw" / "notes.txt").write_text("shot on a Tuesday")
    write_image(tmp_path / "raw" / "preview.png", np.zeros((4, 4, 3), np.uint8))
    report = run_batch("develop", str(tmp_path / "raw"), tmp_path / "out", {}, n_workers=1)
    assert report.ok, report
    (out,) = sorted((tmp_path / "out").glob("*.png"))
    assert out.name == "a.png" and not list((tmp_path / "out").glob("*.dng"))
    img = read_image(out)
    assert img.shape == (128, 192, 3)


def test_a_batch_command_says_which_files_its_input_reads() -> None:
    """``Input.suffixes`` picks a folder's files for ``imageform batch``: develop's input reads
    the raw suffixes; every other batch command's reads the image files (None)."""
    from imageform.io import RAW_SUFFIXES
    from imageform.workflows import WORKFLOWS, get_workflow

    reads = {w.name: w.inputs[0].suffixes for w in map(get_workflow, WORKFLOWS) if w.batch}
    assert reads.pop("develop") == RAW_SUFFIXES
    assert reads and all(v is None for v in reads.values())
