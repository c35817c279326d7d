"""Real-world image files through chained command lines, checked against other decoders.

Run::

    PYTHONPATH=src:. python benchmarks/check_odd_files_chain.py FOLDER [--sources TSV]

Where :mod:`benchmarks.check_odd_files` runs one command per class, this sweep chains them the
way a user does and checks the values, not only that the command ran: every file of FOLDER
(``--sources``: a tab-separated list of SHA-256, file name, repository, commit and path, which
the table prints and checks) goes through

- ``read``: ``read_image`` against another decoder (that of ``check_odd_files``);
- ``info`` then ``convert --to lab`` (TIFF) and back ``--from lab --to srgb``: the Lab values
  against colour-science's on the reference decoder (sRGB-declared or undeclared 8/16-bit
  files: ΔE76 of at most 0.1 where neither is clipped) and the round trip to within 1/255;
- ``convert --to display_p3`` (16-bit PNG), ``convert --from auto`` (PNG): the upright size;
- ``white-balance`` (PNG), ``stain-normalize --method macenko``, ``sfr``, ``chart``,
  ``develop``: a result or one line;
- ``chunked convert --to lab``: the same Lab as ``convert`` (to 1e-3);
- ``frame 0``: ``convert --frame 0 --to lab`` (TIFF): a file of several images (a TIFF
  stack, an animated GIF) converts its first; a file of one image the same Lab as
  ``convert``'s (to 1e-6);
- ``frame last``: ``cvd --frame N --type deutan`` (PNG) with ``N`` the last image ``info``
  lists (0 for a file of one image): the size of that image;
- ``info cut``: ``info`` of a copy of a PFM or Radiance HDR cut to 60 % of its bytes: one
  line saying it is short (``fine`` on a cut file is **wrong**); skipped for other formats;
- ``batch convert 'FOLDER/*' --to lab``, once for the folder (its own temporary folder must
  stay empty): each file's Lab checked as ``convert``'s, and the same outcome;
- ``bad options``: ``convert --to nonsense`` and ``white-balance --method nonsense``: exit 2,
  one line, nothing written.

``--compare BEFORE.md AFTER.md`` prints one table of the two runs' outcomes (two sweeps'
printed tables, e.g. of the main branch and of a change, on the same files): per file, the
verdicts before and after, and every run whose verdict changed. ``--report INTRO.md
TUNE_BEFORE TUNE_AFTER HELD_BEFORE HELD_AFTER HELD_SOURCES.tsv`` prints a results page: the
introduction, the held-out files frozen by SHA-256 (checked again), each half's verdict
counts before and after, and its ``--compare`` tables.

Each gets one verdict (as in ``check_odd_files``): **fine**, **error** (exit 1 or 2, one
line, no output left behind), **noisy**, **crash**, **wrong** (wrong values or size, an output
left behind on failure, anything left in the worker's own temporary folder (TMPDIR), the
input changed), **hang** (over 120 s).
"""

from __future__ import annotations

import argparse
import glob
import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.check_odd_files import (
    TIMEOUT,
    _cell,
    _check_read,
    _hash,
    _reference,
    _run_cli,
)
from benchmarks.check_odd_files import _verdict as _verdict_runtime

CLASSES = (
    "read",
    "info",
    "convert lab",
    "lab -> srgb",
    "convert p3",
    "convert auto",
    "white-balance",
    "stain-normalize",
    "sfr",
    "chart",
    "develop",
    "batch convert",
    "chunked convert",
    "frame 0",
    "frame last",
    "info cut",
    "bad options",
)


def _upright(path: Path) -> np.ndarray | None:
    from imageform.io import read_image

    try:
        return read_image(path, alpha="drop", max_pixels=10**9)
    except Exception:
        return None


def _lab_reference(path: Path) -> np.ndarray | None:
    """colour-science's Lab (D65) of the reference decode; None where it does not apply."""
    import colour

    try:
        ref = _reference(path)
    except Exception:
        return None
    if ref is None or ref.dtype not in (np.uint8, np.uint16):
        return None
    ref = ref[..., None] if ref.ndim == 2 else ref
    if ref.shape[2] not in (1, 3):
        return None
    rgb = ref.astype(np.float64) / _white(path, ref.dtype)
    rgb = np.repeat(rgb, 3, axis=2) if rgb.shape[2] == 1 else rgb
    xyz = colour.RGB_to_XYZ(rgb, colour.RGB_COLOURSPACES["sRGB"], apply_cctf_decoding=True)
    d65 = colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"]
    return np.asarray(colour.XYZ_to_Lab(xyz, d65))


def _white(path: Path, dtype: np.dtype) -> int:
    """The code of white: ``2**bits - 1`` for a TIFF of fewer bits than its sample type
    (TIFF 6.0's MaxSampleValue default), else the type's maximum."""
    import tifffile

    top = int(np.iinfo(dtype).max)
    if path.read_bytes()[:4] in (b"II*\0", b"MM\0*", b"II+\0", b"MM\0+"):
        with tifffile.TiffFile(path) as tif:
            page = tif.pages.first
            bits = int(page.bitspersample)
            if int(page.photometric) != 3 and 1 < bits < 8 * np.dtype(dtype).itemsize:
                top = (1 << bits) - 1
    return top


def _tmp_leftovers() -> set[str]:
    """What is in the worker's own temporary folder (TMPDIR, one per file)."""
    return set(glob.glob(os.path.join(tempfile.gettempdir(), "*")))


def _verdict(code: int, err: str, seconds: float) -> tuple[str, str]:
    """``check_odd_files``'s verdict, a usage error's line (``imageform X: error: ...``) too."""
    lines = [ln for ln in err.splitlines() if ln.strip()]
    usage = [ln for ln in lines if ln.startswith("imageform ") and ": error: " in ln]
    if code == 2 and len(lines) == 1 and usage and "Traceback" not in err:
        return "error", usage[0].partition(": error: ")[2][:160]
    return _verdict_runtime(code, err, seconds)


def _step(argv: list[str]) -> tuple[str, str, float, str]:
    code, so, se, sec = _run_cli(argv)
    verdict, note = _verdict(code, se, sec)
    failed = [ln for ln in so.splitlines() if ln.startswith("failed: ")]
    if argv[0] == "batch" and code == 1 and not se.strip() and len(failed) == 1:
        # batch lists each failed file with its reason on stdout (exit 1), documented
        return "error", failed[0].partition(": ")[2].rpartition(": ")[2][:160], sec, so
    return verdict, note, sec, so


def sweep_file(path: Path) -> list[dict[str, Any]]:
    """Run every chained command class on ``path``; one record per class."""
    import warnings

    from imageform.io import read_image

    warnings.simplefilter("ignore")
    s = str(path)
    rows: list[dict[str, Any]] = []
    verdict, note = _check_read(path)
    rows.append({"file": path.name, "cls": "read", "verdict": verdict, "note": note, "s": 0.0})
    up = _upright(path)
    hw = None if up is None else up.shape[:2]
    before = _hash(path)
    declared = None
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)

        def add(cls: str, verdict: str, note: str, sec: float, *written: Path) -> None:
            if verdict in ("error", "noisy") and any(p.exists() for p in written):
                left = ", ".join(p.name for p in written if p.exists())
                verdict, note = "wrong", f"left {left} behind: {note}"
            if verdict == "fine" and hw is not None:
                for p in written:
                    if p.is_file() and p.suffix in (".png", ".tif"):
                        got = read_image(p, alpha="drop", max_pixels=10**9).shape[:2]
                        if got != hw:
                            verdict, note = "wrong", f"{p.name} is {got}, the upright input {hw}"
            rows.append({"file": path.name, "cls": cls, "verdict": verdict, "note": note, "s": sec})

        leftovers = _tmp_leftovers()
        v, n, sec, so = _step(["info", s, "--json"])
        if v == "fine":
            try:
                head = json.loads(so)
                declared = head.get("color_space")
                n = f"{head.get('channels')} ch, {head.get('dtype', '')}, declares {declared}"
            except Exception:
                v, n = "wrong", "--json printed no JSON"
        add("info", v, n, sec)
        frames = 1
        if v == "fine":
            frames = int(json.loads(so).get("frames") or 1)

        lab = out / "lab.tif"
        v, n, sec, _ = _step(["convert", s, "--to", "lab", "-o", str(lab)])
        if v == "fine":
            v, n = _check_lab(path, lab, declared)
        add("convert lab", v, n, sec, lab)

        back = out / "back.png"
        if lab.is_file():
            argv = ["convert", str(lab), "--from", "lab", "--to", "srgb", "-o", str(back)]
            argv += ["--bit-depth", "16"]
            v, n, sec, _ = _step(argv)
            if v == "fine" and up is not None and up.dtype in (np.uint8, np.uint16):
                a = read_image(back, alpha="drop").astype(np.float64) / 65535
                b = up.astype(np.float64) / _white(path, up.dtype)
                b = b[..., :3] if b.shape[2] >= 3 else np.repeat(b[..., :1], 3, axis=2)
                if declared in (None, "srgb", "gray") and a.shape == b.shape:
                    d = float(np.abs(a - b).max())
                    if d > 1.5 / 255:
                        v, n = "wrong", f"Lab round trip off by {d * 255:.2f}/255"
                    else:
                        n = f"round trip within {d * 255:.3f}/255"
            add("lab -> srgb", v, n, sec, back)
        else:
            add("lab -> srgb", "skipped", "no Lab", 0.0)

        p3 = out / "p3.png"
        v, n, sec, _ = _step(
            ["convert", s, "--to", "display_p3", "--bit-depth", "16", "-o", str(p3)]
        )
        add("convert p3", v, n, sec, p3)
        auto = out / "auto.png"
        v, n, sec, so = _step(["convert", s, "--from", "auto", "-o", str(auto)])
        add("convert auto", v, n, sec, auto)
        wb = out / "wb.png"
        v, n, sec, _ = _step(["white-balance", s, "-o", str(wb)])
        add("white-balance", v, n, sec, wb)
        sn = out / "sn.png"
        v, n, sec, _ = _step(
            ["stain-normalize", s, "--target", s, "--method", "macenko", "-o", str(sn)]
        )
        add("stain-normalize", v, n, sec, sn)
        v, n, sec, _ = _step(["sfr", s, "--json"])
        add("sfr", v, n, sec)
        ch = out / "chart.json"
        v, n, sec, _ = _step(["chart", s, "-o", str(ch)])
        add("chart", v, n, sec, ch)
        dev = out / "dev.png"
        v, n, sec, _ = _step(["develop", s, "-o", str(dev)])
        add("develop", v, n, sec, dev)

        chunk = out / "chunk.tif"
        v, n, sec, _ = _step(["chunked", "convert", s, "-o", str(chunk), "--to", "lab"])
        if v == "fine" and lab.is_file():
            a, b = _read_tif(chunk), _read_tif(lab)
            if a.shape != b.shape or not np.allclose(a, b, atol=1e-3, equal_nan=True):
                d = "shape" if a.shape != b.shape else f"{np.nanmax(np.abs(a - b)):.3g}"
                v, n = "wrong", f"chunked Lab differs from convert's ({d})"
        elif v == "fine" and not lab.is_file():
            v, n = "wrong", "chunked convert wrote what convert refused"
        add("chunked convert", v, n, sec, chunk)

        first = out / "frame0.tif"
        v, n, sec, _ = _step(["convert", s, "--frame", "0", "--to", "lab", "-o", str(first)])
        if v == "fine" and lab.is_file():
            a, b = _read_tif(first), _read_tif(lab)
            if a.shape != b.shape or not np.allclose(a, b, atol=1e-6, equal_nan=True):
                v, n = "wrong", "--frame 0 of a file of one image differs from convert's"
        add("frame 0", v, n, sec, first)

        last = out / "last.png"
        argv = ["cvd", s, "--frame", str(frames - 1), "--type", "deutan", "-o", str(last)]
        v, n, sec, _ = _step(argv)
        if v == "fine":
            try:
                want = read_image(path, frame=frames - 1, alpha="drop", max_pixels=10**9)
                got = read_image(last, alpha="drop").shape[:2]
                if got != want.shape[:2]:
                    v, n = "wrong", f"{last.name} is {got}, frame {frames - 1} {want.shape[:2]}"
                else:
                    n = f"frame {frames - 1} of {frames}"
            except Exception as exc:
                v, n = "wrong", f"cvd read what read_image refuses: {str(exc)[:100]}"
        hw_all = hw
        hw = None  # the frame's size is checked above (a stack has no upright size)
        add("frame last", v, n, sec, last)
        hw = hw_all

        head16 = path.read_bytes()[:16]
        if head16[:2] in (b"PF", b"Pf") or head16.startswith((b"#?RADIANCE", b"#?RGBE")):
            cut = out / f"cut{path.suffix}"
            data = path.read_bytes()
            cut.write_bytes(data[: int(len(data) * 0.6)])
            v, n, sec, _ = _step(["info", str(cut)])
            if v == "fine":
                v, n = "wrong", "info of a file cut to 60 % passed"
            elif v == "error":
                v, n = "fine", f"refused: {n}"
            add("info cut", v, n, sec)
        else:
            add("info cut", "skipped", "not PFM or HDR", 0.0)

        bad = out / "bad.png"
        v1, n1, sec1, _ = _step(["convert", s, "--to", "nonsense", "-o", str(bad)])
        v2, n2, sec2, _ = _step(["white-balance", s, "--method", "nonsense", "-o", str(bad)])
        v, n = (v1, n1) if v1 != "error" else (v2, n2)
        if v == "fine":
            v, n = "wrong", "a nonsense option accepted"
        add("bad options", v, n, sec1 + sec2, bad)
        new = _tmp_leftovers() - leftovers
        if new:
            rows.append({"file": path.name, "cls": "temporaries", "verdict": "wrong",
                         "note": f"left {', '.join(sorted(new))}", "s": 0.0})  # fmt: skip
    if _hash(path) != before:
        rows.append({"file": path.name, "cls": "input", "verdict": "wrong",
                     "note": "the input file changed", "s": 0.0})  # fmt: skip
    return rows


def _read_tif(p: Path) -> np.ndarray:
    import tifffile

    return np.asarray(tifffile.imread(p), np.float64)


def _check_lab(path: Path, lab: Path, declared: str | None) -> tuple[str, str]:
    got = _read_tif(lab)
    if declared not in (None, "srgb", "gray"):
        return "fine", f"from {declared}"
    ref = _lab_reference(path)
    if ref is None:
        return "fine", "no reference Lab"
    got = got.reshape(ref.shape) if got.size == ref.size else got
    if got.shape != ref.shape:
        return "wrong", f"Lab of shape {got.shape}, reference {ref.shape}"
    d = np.sqrt(((got - ref) ** 2).sum(axis=-1))
    worst = float(np.nanmax(d))
    if worst > 0.1:
        return "wrong", f"Lab differs from colour-science's by ΔE76 up to {worst:.3g}"
    return "fine", f"Lab within ΔE76 {worst:.2g} of colour-science"


def _worker(path: Path) -> None:
    for row in sweep_file(path):
        print("ROW " + json.dumps(row, ensure_ascii=False), flush=True)


def batch_rows(folder: Path, rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """``imageform batch convert 'FOLDER/*' --to lab`` once (as a user runs it over a folder),
    in a process with its own temporary folder: one row per file (its Lab checked as
    ``convert``'s, and the same outcome as ``convert``'s), one for what it left behind."""

    files = sorted(p for p in folder.iterdir() if p.is_file())
    out_rows: list[dict[str, Any]] = []
    said = {(r["file"], r["cls"]): r for r in rows}
    with tempfile.TemporaryDirectory(prefix="walk-batch-") as tmp_s:
        tmp = Path(tmp_s)
        own_tmp, out, staged = tmp / "tmp", tmp / "out", tmp / "in"
        own_tmp.mkdir()
        staged.mkdir()
        # a link per file, its name's dots but the last made "_": batch refuses (rightly) two
        # inputs that would write one output ("a.pbm" and "a.tiff" both "a.tif")
        link = {p.name: staged / (p.stem.replace(".", "_") + "_" + p.suffix[1:] + p.suffix)
                for p in files}  # fmt: skip
        for p in files:
            link[p.name].symlink_to(p)
        env = dict(os.environ, PYTHONWARNINGS="ignore", TMPDIR=str(own_tmp))
        argv = [sys.executable, "-m", "imageform", "batch", "convert"]
        argv += [glob.escape(str(staged)) + "/*", "-o", str(out), "--to", "lab", "--suffix", ".tif"]
        t0 = time.perf_counter()
        done = subprocess.run(argv, capture_output=True, text=True, env=env, check=False)
        sec = time.perf_counter() - t0
        failed = {}
        for line in done.stdout.splitlines():
            if line.startswith("failed: "):
                rest = line.removeprefix("failed: ")
                for p in files:
                    if rest.startswith(f"{link[p.name]}: "):
                        why = rest.removeprefix(f"{link[p.name]}: ").partition(": ")[2]
                        failed[p.name] = why.replace(str(link[p.name]), str(p))[:160]
        refused = [ln for ln in done.stderr.splitlines() if ln.startswith("imageform: error:")]
        for p in files:
            got = out / f"{link[p.name].stem}.tif"
            if refused:
                out_rows.append({"file": p.name, "cls": "batch convert", "verdict": "skipped",
                                 "note": "the run was refused", "s": 0.0})  # fmt: skip
                continue
            conv = said.get((p.name, "convert lab"), {}).get("verdict")
            if p.name in failed:
                v, n = "error", failed[p.name]
                if conv == "fine":
                    v, n = "wrong", f"convert reads it, batch fails: {n}"
            elif got.is_file():
                note = said.get((p.name, "info"), {}).get("note", "")
                declared = note.rpartition("declares ")[2] or None
                declared = None if declared == "None" else declared
                v, n = _check_lab(p, got, declared)
                if conv in ("error", "crash", "noisy", "hang"):  # not "wrong": it ran
                    v, n = "wrong", "batch wrote what convert refused"
            else:
                v, n = "wrong", "no output and no failure listed"
            out_rows.append({"file": p.name, "cls": "batch convert", "verdict": v, "note": n,
                             "s": sec / max(len(files), 1)})  # fmt: skip
        left = sorted(x.name for x in own_tmp.iterdir())
        stray = [ln for ln in done.stderr.splitlines() if ln.strip()]
        v, n = "fine", f"exit {done.returncode}, {len(failed)} failed"
        if left:
            v, n = "wrong", f"left {', '.join(left)} in the temporary folder"
        elif refused:
            v, n = "error", refused[0][:160]
        elif "Traceback" in done.stderr or done.returncode not in (0, 1):
            v, n = "crash", (stray or ["?"])[-1][:160]
        out_rows.append({"file": f"(the folder, {len(files)} files)", "cls": "batch convert",
                         "verdict": v, "note": n, "s": sec})  # fmt: skip
    return out_rows


def run(folder: Path, jobs: int = 2) -> list[dict[str, Any]]:
    files = sorted(p for p in folder.iterdir() if p.is_file())
    rows: list[dict[str, Any]] = []
    env = dict(os.environ, PYTHONWARNINGS="ignore")
    procs: list[tuple[Path, subprocess.Popen[str], float, Path]] = []

    def reap(p: Path, proc: subprocess.Popen[str], t0: float, tmp: Path) -> None:
        limit = TIMEOUT * len(CLASSES)
        try:
            so, se = proc.communicate(timeout=max(1.0, limit - (time.time() - t0)))
        except subprocess.TimeoutExpired:
            proc.kill()
            so, se = proc.communicate()
        got = [json.loads(ln[4:]) for ln in so.splitlines() if ln.startswith("ROW ")]
        if len(got) < len(CLASSES) - 2:
            tail = (se.strip().splitlines() or ["?"])[-1][:140]
            got.append({"file": p.name, "cls": "worker", "verdict": "crash", "note": tail, "s": 0})
        rows.extend(got)
        shutil.rmtree(tmp, ignore_errors=True)
        print(f"done {p.name}", file=sys.stderr, flush=True)

    for p in files:
        while len(procs) >= jobs:
            done = [it for it in procs if it[1].poll() is not None]
            for it in done:
                reap(*it)
                procs.remove(it)
            if not done:
                time.sleep(0.2)
        cmd = [sys.executable, __file__, "--worker", str(p)]
        tmp = Path(tempfile.mkdtemp(prefix="walk-"))  # its own: another's temporaries differ
        env["TMPDIR"] = str(tmp)
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                env=env)  # fmt: skip
        procs.append((p, proc, time.time(), tmp))
    for it in procs:
        reap(*it)
    return rows


def _parse(table: Path) -> dict[tuple[str, str], tuple[str, str]]:
    """``(file, command) -> (verdict, note)`` from a printed table's "Every run" section."""
    rows: dict[tuple[str, str], tuple[str, str]] = {}
    section = ""
    for line in table.read_text(encoding="utf-8").splitlines():
        if line.startswith("## "):
            section = line
        if section.startswith("## Every run") and line.startswith("| ") and "---" not in line:
            cells = [c.strip() for c in line.strip("|").split(" | ")]
            if len(cells) == 5 and cells[0] != "file":
                rows[(cells[0], cells[1])] = (cells[2], cells[4])
    return rows


def compare(before: Path, after: Path) -> None:
    """Print the per-file outcomes of two sweeps' tables and the runs whose verdict changed."""
    from benchmarks._common import markdown_table

    a, b = _parse(before), _parse(after)
    files = sorted({f for f, _ in a} | {f for f, _ in b})
    bad = ("crash", "wrong", "hang", "noisy")

    def summary(rows: dict[tuple[str, str], tuple[str, str]], f: str) -> str:
        counts: dict[str, int] = {}
        for (g, _), (v, _) in rows.items():
            if g == f:
                counts[v] = counts.get(v, 0) + 1
        return ", ".join(f"{k} {n}" for k, n in sorted(counts.items())) or "-"

    def worst(rows: dict[tuple[str, str], tuple[str, str]], f: str) -> str:
        got = sorted({c for (g, c), (v, _) in rows.items() if g == f and v in bad})
        return "; ".join(got) if got else "none"

    print(f"Before: `{before.name}`; after: `{after.name}`.\n")
    print("### Per file\n")
    print(markdown_table(
        ["file", "before", "bad before", "after", "bad after"],
        [[f, summary(a, f), worst(a, f), summary(b, f), worst(b, f)] for f in files],
    ))  # fmt: skip
    changed = [
        [f, c, a.get((f, c), ("-", ""))[0], b.get((f, c), ("-", ""))[0],
         b.get((f, c), ("-", ""))[1] or a.get((f, c), ("-", ""))[1]]
        for f, c in sorted(set(a) | set(b))
        if a.get((f, c), ("-", ""))[0] != b.get((f, c), ("-", ""))[0]
    ]  # fmt: skip
    print("\n### Runs whose verdict changed\n")
    print(markdown_table(["file", "command", "before", "after", "note"],
                         changed or [["none", "", "", "", ""]]))  # fmt: skip


def _verdicts(table: Path) -> str:
    """The "Verdicts: ..." line of a printed sweep."""
    for line in table.read_text(encoding="utf-8").splitlines():
        if line.startswith("Verdicts: "):
            return line.removeprefix("Verdicts: ")
    return "?"


def report(intro: Path, tables: list[Path], held_sources: Path) -> None:
    """Print a results page of a tuning and a held-out half, each run before and after."""
    from benchmarks._common import markdown_table

    print(intro.read_text(encoding="utf-8").rstrip() + "\n")
    rows = []
    for line in held_sources.read_text(encoding="utf-8").splitlines():
        sha, name, repo, commit, path = line.split("\t")
        f = held_sources.parent / "held" / name
        same = f.is_file() and hashlib.sha256(f.read_bytes()).hexdigest() == sha
        rows.append([sha, name, f"{repo} @ {commit[:12]}", path, "yes" if same else "NO"])
    print("Held-out files (frozen before any run; SHA-256 checked again now):\n")
    print(markdown_table(["SHA-256", "file", "repository @ commit", "path", "same"], rows))
    for title, (before, after) in (("Tuning half", tables[:2]), ("Held-out half", tables[2:])):
        print(f"\n## {title}: before -> after\n")
        print(f"Before: {_verdicts(before)}\n")
        print(f"After: {_verdicts(after)}\n")
        compare(before, after)


def main() -> None:
    from benchmarks._common import header, markdown_table

    if sys.argv[1:2] == ["--compare"]:
        compare(Path(sys.argv[2]), Path(sys.argv[3]))
        return
    if sys.argv[1:2] == ["--report"]:
        report(Path(sys.argv[2]), [Path(a) for a in sys.argv[3:7]], Path(sys.argv[7]))
        return

    ap = argparse.ArgumentParser()
    ap.add_argument("folder", type=Path)
    ap.add_argument("--worker", action="store_true")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--sources", type=Path, help="SHA-256, name, repository, commit, path (TSV)")
    ap.add_argument("--title", default="")
    args = ap.parse_args()
    if args.worker:
        _worker(args.folder)
        return
    sources = []
    if args.sources:
        for line in args.sources.read_text().splitlines():
            sha, name, repo, commit, p = line.split("\t")
            f = args.folder / name
            ok = f.is_file() and hashlib.sha256(f.read_bytes()).hexdigest() == sha
            sources.append([name, f"{repo} @ {commit[:12]}", p, sha[:16], "yes" if ok else "NO"])
    rows = run(args.folder, args.jobs)
    rows += batch_rows(args.folder, rows)
    order = {c: i for i, c in enumerate(CLASSES)}
    rows.sort(key=lambda r: (r["file"], order.get(r["cls"], 99)))
    counts: dict[str, int] = {}
    for r in rows:
        counts[r["verdict"]] = counts.get(r["verdict"], 0) + 1
    files = len({r["file"] for r in rows if not r["file"].startswith("(the folder")})
    print(header(f"Chained command lines on real image files{args.title} ({files} files)"))
    src = f" --sources {args.sources}" if args.sources else ""
    print(f"`PYTHONPATH=src:. python benchmarks/check_odd_files_chain.py {args.folder}{src}`\n")
    print("Verdicts: " + ", ".join(f"{k} {v}" for k, v in sorted(counts.items()))
          + f" (of {len(rows)} file x command runs).\n")  # fmt: skip
    bad = [r for r in rows if r["verdict"] in ("crash", "wrong", "hang", "noisy")]
    print("## Crashes, wrong results, hangs and noisy errors\n")
    print(markdown_table(["file", "command", "verdict", "note"],
                         [[r["file"], r["cls"], r["verdict"], _cell(r["note"])] for r in bad]
                         or [["none", "", "", ""]]))  # fmt: skip
    print("\n## Every run\n")
    print(markdown_table(["file", "command", "verdict", "s", "note"],
                         [[r["file"], r["cls"], r["verdict"], f"{r['s']:.1f}", _cell(r["note"])]
                          for r in rows]))  # fmt: skip
    if sources:
        print("\n## Sources (SHA-256 checked before the run)\n")
        print(markdown_table(["file", "repository @ commit", "path", "SHA-256 (16)", "same"],
                             sources))  # fmt: skip


if __name__ == "__main__":
    main()
