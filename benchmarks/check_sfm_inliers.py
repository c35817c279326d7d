"""Per-observation inlier tests through the lens: ``imageform reconstruct`` before and after.

Before this change (``sfm._PER_VIEW_INLIERS = False``, main at ``--before``) the
estimators of ``reconstruct_sequence`` ran in undistorted pixels with one threshold for a
pair or a frame (``threshold_px`` times the median stretch of its keypoints): a
fisheye's rim, whose undistortion stretches the keypoints' noise ten to thirty times past
that median, lost its matches in the essential matrix's inliers and its points in PnP,
and a track one rim view of which pulled the (unweighted) triangulated point off its other
views lost all its views. After: a match that RANSAC refused is judged again by its own
Sampson distance in image pixels (each point's covariance :math:`A^{-1}A^{-T}` through the
lens's local map :math:`A`: Hartley & Zisserman 2004, sec. 4.2.6), a PnP or pair-pose
correspondence by its reprojection error in image pixels (3 px), each track triangulated
on the errors in the image (maximum likelihood) and, when a view fails the checks, without
its worst view (COLMAP's track triangulation keeps the consistent views: Schönberger &
Frahm 2016). The
bundle adjustment's filters already measured in the image (2 and 4 px). Without a lens
(``distortion=None``) nothing changes.

Tables:

1. **Rings** (in-process, each sequence with its camera, ``reconstruct_sequence`` with
   ``_PER_VIEW_INLIERS`` off and on): the share of each ring's keypoints (by the angle
   from the optical axis through the camera) that end as kept observations, the median
   reprojection error in image pixels there; frames, points, median error and, for the
   simulator's room (a 146 degree equidistant fisheye, ``tests/sfm_scenes.py``, 12 frames
   of 640 x 480, f 250 px), the camera centres against the truth (RMS after the best
   similarity, % of the path).
2. **The command** (``python -m imageform reconstruct``, ``--before SRC``: main's ``src``
   on ``PYTHONPATH``, after: this checkout), without ``--camera`` and with it where the
   sequence has one: frames, points, median reprojection error, f, and the poses after
   against before (median relative rotation / translation-direction angles over
   consecutive frames, degrees; centres' RMS after the best similarity, % of the path:
   ``check_sfm_fresh.agreement``); wall seconds and the command's CPU seconds.

Tuning sequences (the earlier sessions'; ``check_sfm_k1.py``'s docstring names their
repositories, commits and licences; ``check_sfm_choice.py``'s the York renders, the
2026-11-30j held-out half, tuning data since): ``c3vd`` (with the working camera of
``tests/data/endo``), ``colon-a``, ``colon-b`` (with pycolmap's ``RADIAL_FISHEYE``
self-calibration as their camera, ``camera.toml``), ``york-chair``, ``york-box``,
``york-skull``, ``york-teddy`` (with the equidistant camera of the repository's map), the
simulator's room, and the pinhole sequences ``temple``, ``dino``, ``viking``, ``gun``,
``dt990`` (no lens given: the command refines ``SIMPLE_RADIAL``). Nothing was tuned: the
thresholds are the ones the code had (``threshold_px`` 1, PnP's 3 px, the triangulation's
4 px), now read in image pixels.

Held out (chosen and frozen by the SHA-256 below before any run, run once with the final
code): PerssonRickard/Sequential-Structure-from-Motion at ``ea35b8c`` (no licence stated:
measured here, never committed), the three Nikon D60 photographs of ``Demo/`` (1936 x
1296 JPEGs with EXIF), halved to 968 x 648 (Pillow's bilinear filter, the EXIF kept); a
repository no earlier check used; pinhole (no fisheye sequence with a
calibration was found in a repository nobody here used): it checks that a lens refined
near the pinhole loses nothing.

Run::

    git archive BASE src | tar -x -C BEFORE
    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_sfm_inliers.py \\
        --data DATA --before BEFORE/src --rings
    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_sfm_inliers.py \\
        --data DATA --before BEFORE/src [--only c3vd colon-a ...]
    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_sfm_inliers.py \\
        --data DATA --before BEFORE/src --held-out --mirrors /work/.mirror

``DATA`` holds the sequences as ``check_sfm_choice.py`` prepares them (``c3vd`` is
prepared from ``tests/data/endo``, the York renders from the mirror).
"""

from __future__ import annotations

import argparse
import itertools
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks._common import header, markdown_table  # noqa: E402
from benchmarks.check_sfm_choice import HELD as YORK  # noqa: E402
from benchmarks.check_sfm_choice import prepare_held  # noqa: E402
from benchmarks.check_sfm_fresh import agreement  # noqa: E402
from benchmarks.check_sfm_k1 import prepare_c3vd, read_frames, run_cli  # noqa: E402

FISHEYE = ["c3vd", "colon-a", "colon-b", *YORK]
PINHOLE = ["temple", "dino", "viking", "gun", "dt990"]
RINGS = [0, 20, 40, 55, 70, 90]

HELD_REPO = "PerssonRickard/Sequential-Structure-from-Motion"
HELD_COMMIT = "ea35b8c01297513d9ee61baa1b2d8fddeda470ce"
#: Frozen before any run: path in the repository -> SHA-256.
HELD_SHA256 = {
    "Demo/DSC_0351.JPG": "48c7aa60596476946adaae0a6860a2b47e7de45bae2c5fef664601a7c63fd403",
    "Demo/DSC_0369.JPG": "17e2cef43209580dacc7614547b4da33ee4b00e8dbce8daf6495b8c3c3dd6da9",
    "Demo/DSC_0391.JPG": "2302eaf53582e29341a68da0788d6f8571396a724cf71ea50f7f3b57e9429aea",
}


def folder_of(name: str, data: Path, mirrors: Path) -> Path:
    if name == "c3vd":
        return prepare_c3vd(data)
    if name in YORK:
        return prepare_held(name, mirrors, data)
    return data / name


def camera_of(folder: Path) -> Path | None:
    for f in ("given.toml", "camera.toml"):
        if (folder / f).exists():
            return folder / f
    return None


def prepare_held_out(data: Path, mirrors: Path) -> Path:
    """The frozen photographs, SHA-256 checked, halved with their EXIF (968 x 648)."""
    import hashlib
    import io
    import subprocess

    from PIL import Image

    git = mirrors / HELD_REPO.replace("/", "+") / "repo"
    folder = data / "persson"
    (folder / "frames").mkdir(parents=True, exist_ok=True)
    for path, sha in HELD_SHA256.items():
        blob = subprocess.run(
            ["git", f"--git-dir={git}", "show", f"{HELD_COMMIT}:{path}"],
            capture_output=True,
            check=True,
        ).stdout
        if hashlib.sha256(blob).hexdigest() != sha:
            raise SystemExit(f"{path}: not the frozen file (SHA-256 differs)")
        with Image.open(io.BytesIO(blob)) as im:
            exif = im.getexif()
            small = im.resize((im.width // 2, im.height // 2), Image.Resampling.BILINEAR)
        small.save(folder / "frames" / Path(path).name, "JPEG", quality=95, exif=exif.tobytes())
    return folder


# --- table 1: the rings, in-process -------------------------------------------------------


def _room() -> tuple[list[np.ndarray], np.ndarray, Any, list[Any]]:
    from imageform.geometry import KannalaBrandt
    from tests import sfm_scenes

    w, h, f = 640, 480, 250.0
    K = np.array([[f, 0, (w - 1) / 2], [0, f, (h - 1) / 2], [0, 0, 1]])
    truth = sfm_scenes.poses(12)
    rng = np.random.default_rng(5)
    frames = [
        sfm_scenes.render(K, p, (w, h), noise=1.5, rng=rng, distortion=KannalaBrandt())
        for p in truth
    ]
    return frames, K, KannalaBrandt(), truth


def rings_of(name: str, data: Path, mirrors: Path, per_view: bool) -> dict[str, Any]:
    """One in-process reconstruction with the sequence's camera, and its rings."""
    import imageform.geometry.sfm as sfm
    from imageform.geometry import field_of_view_mask, reconstruct_sequence
    from imageform.io import read_camera

    truth = None
    if name == "room":
        frames, K, dist, truth = _room()
        mask, ct = None, 0.04
    else:
        folder = folder_of(name, data, mirrors)
        frames = read_frames(folder)
        cam_file = camera_of(folder)
        assert cam_file is not None
        cam = read_camera(cam_file).camera
        K, dist = np.asarray(cam.K, np.float64), cam.distortion
        mask, ct = field_of_view_mask(frames), 0.01
    sfm._PER_VIEW_INLIERS = per_view
    sfm._TRACE = {}
    t0 = time.process_time()
    try:
        rec = reconstruct_sequence(frames, K, dist, masks=mask, contrast_threshold=ct)
    finally:
        T, sfm._TRACE = sfm._TRACE, None
        sfm._PER_VIEW_INLIERS = True
    cpu = time.process_time() - t0
    xy = T["xy"]
    theta = []
    for p in xy:
        u = sfm._undistorted(p, K, dist)
        xn = (u - K[:2, 2]) / np.diag(K)[:2]
        theta.append(np.degrees(np.arctan(np.linalg.norm(xn, axis=1))))
    hp = T["has_point"]
    pid = np.cumsum(hp) - 1
    keep = T["o_ok"] & T["registered"][T["o_frame"]] & hp[T["o_track"]]
    kept = [np.zeros(len(p), bool) for p in xy]
    err = [np.full(len(p), np.nan) for p in xy]
    for f in np.flatnonzero(rec.registered).tolist():
        s = np.flatnonzero(keep & (T["o_frame"] == f))
        kp = T["o_kp"][s]
        kept[f][kp] = True
        Xc = rec.points[pid[T["o_track"][s]]] @ rec.R[f].T + rec.t[f]
        xn = Xc[:, :2] / Xc[:, 2:3]
        d = np.asarray(rec.distortion.distort(xn)) if rec.distortion is not None else xn
        assert rec.K is not None
        proj = d * np.diag(rec.K)[:2] + rec.K[:2, 2]
        err[f][kp] = np.linalg.norm(proj - xy[f][kp], axis=1)
    th, ke, er = (np.concatenate(a) for a in (theta, kept, err))
    # the trace is the last model's: another start (a smaller model) leaves no rings
    same = bool(np.array_equal(T["registered"], rec.registered))
    out: dict[str, Any] = {
        "reg": int(rec.registered.sum()),
        "n": len(frames),
        "points": int(rec.points.shape[0]),
        "median": float(np.median(rec.residuals_px)),
        "cpu": cpu,
        "R": rec.R,
        "t": rec.t,
        "rings": [],
    }
    if truth is not None:
        from tests import sfm_scenes

        C_true = np.array([-R.T @ t for R, t in truth])
        C = np.array([-R.T @ t for R, t in zip(rec.R, rec.t, strict=True)])
        out["truth"] = 100.0 * sfm_scenes.align_rms(C, C_true)  # % of the path
    for a, b in itertools.pairwise(RINGS):
        s = (th >= a) & (th < b)
        if s.any() and same:
            med = float(np.nanmedian(er[s & ke])) if (s & ke).any() else float("nan")
            out["rings"].append((f"{a}-{b}", int(s.sum()), float(ke[s].mean()), med))
    return out


def rings_table(names: list[str], data: Path, mirrors: Path) -> str:
    cols = ["sequence", "run", "frames", "points", "reprojection px (median)"]
    cols += [f"kept {a}-{b} deg" for a, b in itertools.pairwise(RINGS)]
    cols += ["centres vs truth % of path", "poses after vs before", "CPU s"]
    rows = []
    for name in names:
        print(f"  rings: {name}", file=sys.stderr)
        runs = [
            (lab, rings_of(name, data, mirrors, pv))
            for lab, pv in (("before", False), ("after", True))
        ]
        for lab, r in runs:
            by = {k: (m, share, med) for k, m, share, med in r["rings"]}
            cells = []
            for a, b in itertools.pairwise(RINGS):
                key = f"{a}-{b}"
                if key in by:
                    m, share, med = by[key]
                    cells.append(f"{100 * share:.1f} % of {m} ({med:.2f} px)")
                else:
                    cells.append("-")
            vs = "-"
            if lab == "after":
                rot, tra, rms = agreement(r["R"], r["t"], runs[0][1]["R"], runs[0][1]["t"])
                vs = f"{rot:.2f} / {tra:.2f} / {rms:.2f}"
            rows.append(
                [name, lab, f"{r['reg']}/{r['n']}", r["points"], f"{r['median']:.3f}", *cells,
                 f"{r['truth']:.4f}" if "truth" in r else "-", vs, f"{r['cpu']:.1f}"]
            )  # fmt: skip
    return markdown_table(cols, rows)


# --- table 2: the command ----------------------------------------------------------------


def cli_rows(name: str, folder: Path, before: Path, endo: bool, camera: Path | None) -> list[Any]:
    n = len(read_frames(folder))
    how = "--camera" if camera is not None else "no camera"
    b = run_cli(folder, endo, before, camera)
    a = run_cli(folder, endo, ROOT / "src", camera)
    rows = []
    for lab, r in (("before", b), ("after", a)):
        ok = r.get("reg", 0) > 0 and "R" in r
        vs = "-"
        if lab == "after" and ok and b.get("reg", 0) > 0 and "R" in b:
            rot, tra, rms = agreement(r["R"], r["t"], b["R"], b["t"])
            vs = f"{rot:.2f} / {tra:.2f} / {rms:.2f}"
        f = r.get("f") if ok else None
        vt = "-"
        if ok and (folder / "truth.npz").exists():
            tr = np.load(folder / "truth.npz")
            rot, tra, rms = agreement(r["R"], r["t"], tr["R"], tr["t"])
            vt = f"{rot:.2f} / {tra:.2f} / {rms:.2f}"
        rows.append(
            [
                name,
                how,
                lab,
                f"{r.get('reg', 0)}/{n}",
                r.get("points", "-"),
                f"{r['reproj']:.3f}" if ok and r.get("reproj") is not None else "-",
                f"{f:.1f}" if f is not None else "-",
                vs,
                vt,
                f"{r['time']:.1f} ({r['cpu']:.1f})" if "time" in r else "-",
            ]
        )
        if not ok and "note" in r:
            rows[-1][7] = r["note"][:100].replace("|", "/")
    return rows


CLI_COLS = ["sequence", "camera", "run", "frames", "points", "reprojection px (median)"]
CLI_COLS += ["f px", "poses after vs before: rotation / translation deg / centres % of path"]
CLI_COLS += ["poses vs truth (same)", "s (CPU s)"]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", type=Path, required=True)
    ap.add_argument("--before", type=Path, required=True, help="src folder of the code before")
    ap.add_argument("--only", nargs="+", default=None)
    ap.add_argument("--rings", action="store_true", help="table 1 (in-process) only")
    ap.add_argument("--held-out", action="store_true", help="the frozen held-out photographs")
    ap.add_argument("--mirrors", type=Path, default=Path("/work/.mirror"))
    args = ap.parse_args()
    print(header("Per-observation inlier tests through the lens"))
    load = " / ".join(Path("/proc/loadavg").read_text().split()[:3])
    print(f"load average: {load} (a shared machine)\n")
    if args.rings:
        pool = [*FISHEYE, "room"]
        names = [k for k in pool if not args.only or k in args.only]
        print(rings_table(names, args.data, args.mirrors))
        return
    rows: list[Any] = []
    if args.held_out:
        print(f"Held out: {HELD_REPO} at {HELD_COMMIT[:7]}, SHA-256 checked:\n")
        print("\n".join(f"- `{p}` `{h}`" for p, h in HELD_SHA256.items()) + "\n")
        folder = prepare_held_out(args.data, args.mirrors)
        rows += cli_rows("persson", folder, args.before, False, None)
    else:
        pool = FISHEYE + PINHOLE
        for name in [k for k in pool if not args.only or k in args.only]:
            print(f"  command: {name}", file=sys.stderr)
            folder = folder_of(name, args.data, args.mirrors)
            endo = name in FISHEYE
            rows += cli_rows(name, folder, args.before, endo, None)
            cam = camera_of(folder)
            if cam is not None and endo:
                rows += cli_rows(name, folder, args.before, endo, cam)
    print(markdown_table(CLI_COLS, rows))


if __name__ == "__main__":
    main()
