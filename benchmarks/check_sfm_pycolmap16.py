"""The 16 runs against pycolmap on C3VD: where imageform's reconstruction loses, and before/after.

``check_endo_real.py``'s comparison (the C3VD v3 preview clip, ``--video``; its docstring
names the clip's repository, commit and licence: CC BY 4.0, never committed) as the
2026-11-29i track-breaks check ran it: every 8th and every 4th frame, imageform without a
mask and with the aperture mask (``--contrast-threshold 0.01``, the camera of
``tests/data/endo/camera.toml`` held), RANSAC seeds 0 to 3: 2 x 2 x 4 = 16 runs, each
against pycolmap's incremental mapper on the same frames with the same camera held
(``OPENCV_FISHEYE``, sequential matching; the reference: aperture mask, SIFT's peak
threshold a quarter of its default; the other pycolmap row without mask and with its
default threshold). pycolmap runs once a stride (``--reference-cache``, the files
``check_endo_real.py`` writes and reads). There is no ground truth for this clip: the
agreement columns are between two programs (median and worst angle between consecutive
relative rotations, median angle between relative translation directions, degrees).

``--json OUT`` writes this source tree's 16 runs (run it once a tree: ``PYTHONPATH`` names
the tree; ``--every 8`` and ``--every 4`` may run as two processes and write two files);
``--report A.json ... [--before B.json ...]`` prints the per-run table against pycolmap and
the summary of where imageform loses (medians over the 8 runs of a stride), and with
``--before`` the before -> after columns. CPU seconds: imageform's process time; pycolmap's
wall seconds of its one run (one thread). Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_sfm_pycolmap16.py \\
        --video C3VD.mp4 --reference-cache DIR --every 8 --json after8.json
    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_sfm_pycolmap16.py \\
        --video C3VD.mp4 --reference-cache DIR --report after8.json after4.json \\
        [--before before8.json before4.json]
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks import check_endo_real as er
from benchmarks._common import header, markdown_table

ROWS = (("no mask", False), ("aperture mask", True))


def _pycolmap(cache: Path, every: int) -> list[dict[str, Any]]:
    out = []
    for k in range(len(er.PYCOLMAP)):
        path = cache / f"pycolmap-every{every}-{k}.npz"
        if not path.exists():
            raise SystemExit(f"{path}: no pycolmap run (check_endo_real.py --reference-cache)")
        with np.load(path, allow_pickle=False) as z:
            out.append({key: z[key][()] if z[key].ndim == 0 else z[key] for key in z.files})
    return out


def run(video: Path, cache: Path, strides: list[int], seeds: list[int]) -> list[dict[str, Any]]:
    """The imageform runs of ``strides`` x ``ROWS`` x ``seeds``, against pycolmap's reference."""
    from imageform.io import read_camera

    cam = read_camera(er.CAMERA).camera
    frames = er.read_clip(video, 445)
    out = []
    for every in strides:
        sel = frames[::every]
        ref = _pycolmap(cache, every)[-1]
        for label, fov in ROWS:
            for seed in seeds:
                er.SETTINGS["rng"] = seed
                r = er.run_imageform(sel, cam, fov, False, 0.01)
                row: dict[str, Any] = {"every": every, "mask": label, "seed": seed}
                row |= {"n": len(sel), "reg": r["reg"], "note": r.get("note", "")}
                if "points" in r:
                    rot, tra = er.agreement(r["R"], r["t"], ref["R"], ref["t"])
                    row |= {"points": r["points"], "track": r["track"], "reproj": r["reproj"]}
                    row |= {"rot": rot, "tra": tra, "worst": er.worst_rotation(r["R"], ref["R"])}
                    row |= {"cpu": r["cpu"]}
                print(f"  every {every} {label} seed {seed}: {row}", file=sys.stderr)
                out.append(row)
    return out


def _f(v: Any, fmt: str) -> str:
    return "-" if v is None or (isinstance(v, float) and not np.isfinite(v)) else format(v, fmt)


def report(after: list[dict[str, Any]], before: list[dict[str, Any]], cache: Path) -> str:
    key = lambda r: (r["every"], r["mask"], r["seed"])  # noqa: E731
    prior = {key(r): r for r in before}
    cols = ["every", "mask", "seed", "registered", "points", "track length",
            "reprojection px (median)", "vs pycolmap: rotation / translation deg (median)",
            "worst rotation deg", "CPU s"]  # fmt: skip
    fields = [("reg", "d"), ("points", "d"), ("track", ".2f"), ("reproj", ".3f")]
    rows = []
    for r in sorted(after, key=key):
        b = prior.get(key(r))

        def both(name: str, fmt: str, r: dict[str, Any] = r, b: Any = b) -> str:
            now = _f(r.get(name), fmt)
            return now if b is None else f"{_f(b.get(name), fmt)} -> {now}"

        agree = (
            f"{_f(r.get('rot'), '.2f')} / {_f(r.get('tra'), '.2f')}"
            if b is None
            else f"{_f(b.get('rot'), '.2f')} / {_f(b.get('tra'), '.2f')} -> "
            f"{_f(r.get('rot'), '.2f')} / {_f(r.get('tra'), '.2f')}"
        )
        reg = f"{r['reg']}/{r['n']}" if b is None else f"{b['reg']} -> {r['reg']} of {r['n']}"
        rows.append(
            [r["every"], r["mask"], r["seed"], reg]
            + [both(name, fmt) for name, fmt in fields[1:]]
            + [agree, both("worst", ".2f"), both("cpu", ".1f")]
        )
    text = "## The runs\n\n" + markdown_table(cols, rows) + "\n"
    # the summary: medians of a stride's runs, against pycolmap's two rows
    scols = ["every", "run", "runs", "registered (median, fewest)", "points", "track length",
             "reprojection px", "rotation / translation deg vs reference", "worst rotation deg "
             "(median, largest)", "s (CPU for imageform)"]  # fmt: skip
    srows = []
    for every in sorted({r["every"] for r in after}):
        for k, (label, _, _) in enumerate(er.PYCOLMAP):
            p = _pycolmap(cache, every)[k]
            srows.append(
                [
                    every,
                    f"pycolmap {label}",
                    1,
                    f"{int(p['reg'])}",
                    p.get("points", "-"),
                    _f(float(p.get("track", np.nan)), ".2f"),
                    _f(float(p.get("reproj", np.nan)), ".3f"),
                    "reference" if k == len(er.PYCOLMAP) - 1 else str(p.get("note", "-")),
                    "-",
                    f"{float(p['time']):.1f} (wall)",
                ]
            )
        for name, runs in (("imageform before", before), ("imageform", after)):
            runs = [r for r in runs if r["every"] == every]
            if not runs:
                continue
            med = lambda f, runs=runs: statistics.median(  # noqa: E731
                float(r.get(f, np.nan)) for r in runs
            )
            srows.append(
                [
                    every,
                    name,
                    len(runs),
                    f"{med('reg'):.0f}, {min(r['reg'] for r in runs)}",
                    f"{med('points'):.0f}",
                    f"{med('track'):.2f}",
                    f"{med('reproj'):.3f}",
                    f"{med('rot'):.2f} / {med('tra'):.2f}",
                    f"{med('worst'):.2f}, {max(float(r.get('worst', np.nan)) for r in runs):.2f}",
                    f"{med('cpu'):.1f}",
                ]
            )
    text += "\n## Medians over a stride's runs, and pycolmap\n\n" + markdown_table(scols, srows)
    if before:
        worse = better = 0
        for r in after:
            b = prior.get(key(r))
            if b is None or "worst" not in b or "worst" not in r:
                continue
            worse += r["worst"] > b["worst"] + 1e-9
            better += r["worst"] < b["worst"] - 1e-9
        text += f"\nThe worst rotation: better in {better}, worse in {worse} of {len(after)} runs\n"
    return text


def cli_table(data: Path, before: Path, names: list[str]) -> str:
    """The command on the sequences of ``check_sfm_inliers.py``'s data folder, before/after.

    Before: ``before`` (a ``src`` folder) with the sequence's options; after: this checkout
    with the same options, then with ``--equalize`` for the endoscopes (c3vd, colon-a,
    colon-b), with their camera (``--camera``) and without.
    """
    from benchmarks.check_sfm_fresh import agreement
    from benchmarks.check_sfm_inliers import FISHEYE, camera_of, folder_of
    from benchmarks.check_sfm_k1 import read_frames, run_cli

    root = Path(__file__).resolve().parents[1] / "src"
    rows = []
    for name in names:
        folder = folder_of(name, data, Path("/work/.mirror"))
        endo = name in FISHEYE
        n = len(read_frames(folder))
        cams: list[Path | None] = [None]
        if endo and camera_of(folder) is not None:
            cams.append(camera_of(folder))
        for cam in cams:
            print(f"  command: {name} {cam}", file=sys.stderr)
            b = run_cli(folder, endo, before, cam)
            runs = [("before", b), ("after", run_cli(folder, endo, root, cam))]
            if endo:
                runs.append(
                    ("after, --equalize", run_cli(folder, endo, root, cam, ("--equalize",)))
                )
            for label, r in runs:
                ok = r.get("reg", 0) > 0 and "R" in r
                vs = "-"
                if label != "before" and ok and b.get("reg", 0) > 0 and "R" in b:
                    rot, tra, rms = agreement(r["R"], r["t"], b["R"], b["t"])
                    vs = f"{rot:.2f} / {tra:.2f} / {rms:.2f}"
                vt = "-"
                if ok and (folder / "truth.npz").exists():
                    tr = np.load(folder / "truth.npz")
                    rot, tra, rms = agreement(r["R"], r["t"], tr["R"], tr["t"])
                    vt = f"{rot:.2f} / {tra:.2f} / {rms:.2f}"
                note = "" if ok else str(r.get("note", ""))[:90].replace("|", "/")
                rows.append(
                    [
                        name,
                        "--camera" if cam else "no camera",
                        label,
                        f"{r.get('reg', 0)}/{n}",
                        r.get("points", "-"),
                        _f(r.get("reproj") if ok else None, ".3f"),
                        _f(r.get("f") if ok else None, ".1f"),
                        vs,
                        vt,
                        f"{r['time']:.1f} ({r['cpu']:.1f})",
                        note,
                    ]
                )
    cols = ["sequence", "camera", "run", "frames", "points", "reprojection px (median)", "f px",
            "vs before: rotation / translation deg / centres % of path", "vs truth (same)",
            "s (CPU s)", "note"]  # fmt: skip
    return markdown_table(cols, rows)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--video", type=Path, required=True)
    ap.add_argument("--reference-cache", type=Path, required=True)
    ap.add_argument("--every", type=int, nargs="+", default=[8, 4])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3])
    ap.add_argument("--json", type=Path, help="write this tree's runs here")
    ap.add_argument("--equalize", action="store_true", help="imageform with equalize=True")
    ap.add_argument("--report", type=Path, nargs="+", help="print the tables of these runs")
    ap.add_argument("--before", type=Path, nargs="+", default=[], help="the runs before")
    ap.add_argument("--cli", type=Path, help="check_sfm_inliers.py's data folder: the command")
    ap.add_argument("--before-src", type=Path, help="with --cli: the src folder before")
    ap.add_argument("--only", nargs="+", default=["c3vd", "colon-a", "colon-b"])
    args = ap.parse_args()
    if args.cli:
        print(header("The command before and after, --equalize for the endoscopes"))
        load = " / ".join(Path("/proc/loadavg").read_text().split()[:3])
        print(f"load average: {load} (a shared machine)\n")
        print(cli_table(args.cli, args.before_src, args.only))
        return
    if args.equalize:
        er.SETTINGS["equalize"] = True
    if args.json:
        runs = run(args.video, args.reference_cache, args.every, args.seeds)
        args.json.write_text(json.dumps(runs, indent=1))
    if args.report:
        after = [r for p in args.report for r in json.loads(p.read_text())]
        before = [r for p in args.before for r in json.loads(p.read_text())]
        print(header("The 16 runs against pycolmap on C3VD"))
        load = " / ".join(Path("/proc/loadavg").read_text().split()[:3])
        print(f"load average: {load} (a shared machine)\n")
        print(report(after, before, args.reference_cache))


if __name__ == "__main__":
    main()
