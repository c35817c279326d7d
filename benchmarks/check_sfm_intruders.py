"""Frames that do not belong: does ``reconstruct_sequence`` register them (its fallbacks)?

Sequences with intruders put in: the synthetic walk through a room of photographs
(tests/sfm_scenes.py, 8 frames of 400 x 300) with a Kodak photograph between frames 3 and 4
(Kodak 3, unrelated; Kodak 8, 1 and 21, tiled on the near, far and right walls: a
repeated texture), and with a burned-in text overlay on every frame and two Kodak
photographs (3, 20) carrying it after the walk (their only matches to the walk on the
overlay); the 8 real colonoscopy frames of
tests/data/endo (C3VD v3, CC BY 4.0; every 8th of the clip's first 57) with Kodak 3 between
frames 3 and 4 and frame 6 mirrored after them, and with frame 7 shifted by (3, -2) px
after them (a copy a few pixels off: a view of the scene, to be registered); with
``--video`` (C3VD v3's preview, as benchmarks/check_endo_real.py), the clip every 8th (37
frames) with Kodak 3 after the 12th, frame 20 mirrored after the 24th and Kodak 20 at the
end. With ``--all-kodak``, each of the 24 Kodak photographs in turn between frames 3 and 4 of
the walk, after the walk with the overlay, and between frames 3 and 4 of the 8 colonoscopy
frames (one row each, summed over the 24). The Kodak photographs:
``/work/shared/data/kodak`` (``--kodak``). Each sequence is reconstructed once (the seed is
fixed; the endoscopic ones with the field-of-view mask of the true frames and SIFT's
contrast threshold 0.01, as check_endo_real.py's rows).

Columns: true frames registered, intruders registered (a false registration each; the
shifted copy counts as a true frame), the frames the fallbacks registered (notes: "registered
by"), and over the true frames, for the room, the largest rotation error against the truth
(degrees, relative to the first frame) and the camera path's error after a similarity
(percent of the path); then each intruder's note (why it was not registered). Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_sfm_intruders.py \\
        [--video /tmp/endo/c3vdv3_prev.mp4] [--all-kodak]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks._common import header, markdown_table

ROOT = Path(__file__).resolve().parents[1]
ENDO = ROOT / "tests" / "data" / "endo"


def main() -> None:
    import cv2

    from imageform.geometry import field_of_view_mask, reconstruct_sequence
    from imageform.io import read_camera, read_image
    from tests import sfm_scenes

    ap = argparse.ArgumentParser()
    ap.add_argument("--kodak", type=Path, default=ROOT.parent / "shared" / "data" / "kodak")
    ap.add_argument("--video", type=Path, default=None)
    ap.add_argument("--all-kodak", action="store_true")
    args = ap.parse_args()

    def kodak(i: int, size: tuple[int, int]) -> np.ndarray:
        im = np.asarray(read_image(args.kodak / f"kodim{i:02d}.png"))[..., :3]
        return np.asarray(cv2.resize(im, size, interpolation=cv2.INTER_AREA))

    rows: list[list[object]] = []
    why: list[str] = []

    def run(name: str, seq: list[np.ndarray], bad: list[int], truth: Any = None, **kw: Any) -> None:
        t0 = time.perf_counter()
        rec = reconstruct_sequence(seq, **kw)
        s = time.perf_counter() - t0
        true = [i for i in range(len(seq)) if i not in bad]
        by = [n.split(":")[0].removeprefix("frame ") for n in rec.notes if "registered by" in n]
        rot = path = "-"
        if truth is not None and rec.registered[true].all():
            f0 = true[0]
            errs = []
            for i, (R, _) in zip(true, truth, strict=True):
                d = (rec.R[i] @ rec.R[f0].T) @ (R @ truth[0][0].T).T
                errs.append(np.degrees(np.arccos(np.clip((np.trace(d) - 1) / 2, -1, 1))))
            rot = f"{max(errs):.2f}"
            C_est = np.array([-rec.R[i].T @ rec.t[i] for i in true])
            C_true = np.array([-R.T @ t for R, t in truth])
            path = f"{100 * sfm_scenes.align_rms(C_est, C_true):.2f}"
        rows.append(
            [
                name,
                len(seq),
                f"{int(rec.registered[true].sum())}/{len(true)}",
                f"{int(rec.registered[bad].sum())}/{len(bad)}" if bad else "-",
                ", ".join(by) or "none",
                rot,
                path,
                f"{s:.1f}",
            ]
        )
        why.extend(
            f"{name}: {n}" for n in rec.notes if any(n.startswith(f"frame {b}:") for b in bad)
        )
        print(f"{name}: done", file=sys.stderr, flush=True)

    K = np.array([[300.0, 0, 199.5], [0, 300.0, 149.5], [0, 0, 1]])
    f, truth = sfm_scenes.sequence(K, 8, (400, 300))
    for i, what in (
        (3, "unrelated"),
        (8, "tiled on the near wall"),
        (1, "tiled on the far wall"),
        (21, "tiled on the right wall"),
    ):
        seq = [*f[:4], kodak(i, (400, 300)), *f[4:]]
        run(f"room + Kodak {i} ({what}) at 4", seq, [4], truth, K=K, max_features=2000)
    seq = [sfm_scenes.burn_in(x) for x in [*f, kodak(3, (400, 300)), kodak(20, (400, 300))]]
    run("room, overlay on all + Kodak 3, 20 at 8, 9", seq, [8, 9], truth, K=K, max_features=2000)

    cam = read_camera(ENDO / "camera.toml").camera
    endo = [np.asarray(read_image(ENDO / f"c3vdv3_f{i:03d}.jpg")) for i in range(0, 57, 8)]
    h, w = endo[0].shape[:2]
    mask = field_of_view_mask(endo)
    ek = {"K": cam.K, "distortion": cam.distortion, "masks": mask, "contrast_threshold": 0.01}
    mirrored = np.ascontiguousarray(endo[6][:, ::-1])
    run("C3VD 8 frames", endo, [], **ek)
    seq = [*endo[:4], kodak(3, (w, h)), *endo[4:], mirrored]
    run("C3VD 8 frames + Kodak 3 at 4, frame 6 mirrored at 9", seq, [4, 9], **ek)
    copy = np.asarray(
        cv2.warpAffine(endo[7], np.array([[1, 0, 3], [0, 1, -2]], np.float32), (w, h))
    )
    run("C3VD 8 frames + frame 7 shifted 3, -2 px at 8", [*endo, copy], [], **ek)

    if args.all_kodak:
        settings: list[tuple[str, Any]] = [
            ("room + each Kodak at 4", lambda p: ([*f[:4], p, *f[4:]], 4, K, None)),
            (
                "room, overlay on all + each Kodak at 8",
                lambda p: ([sfm_scenes.burn_in(x) for x in [*f, p]], 8, K, None),
            ),
            ("C3VD 8 frames + each Kodak at 4", lambda p: ([*endo[:4], p, *endo[4:]], 4, None, 1)),
        ]
        for name, make in settings:
            true_n = true_reg = bad_reg = 0
            by_n = 0
            for i in range(1, 25):
                size = (400, 300) if "room" in name else (w, h)
                seq, bad, k_, endo_ = make(kodak(i, size))
                kw = ek if endo_ else {"K": k_, "max_features": 2000}
                rec = reconstruct_sequence(seq, **kw)
                true = [j for j in range(len(seq)) if j != bad]
                true_n += len(true)
                true_reg += int(rec.registered[true].sum())
                bad_reg += int(rec.registered[bad])
                by_n += sum("registered by" in n for n in rec.notes)
            rows.append(
                [
                    name,
                    "24 runs",
                    f"{true_reg}/{true_n}",
                    f"{bad_reg}/24",
                    f"{by_n} frames",
                    "-",
                    "-",
                    "-",
                ]
            )
            print(f"{name}: done", file=sys.stderr, flush=True)

    if args.video is not None:
        from benchmarks.check_endo_real import read_clip

        clip = read_clip(args.video, 445)[::8]
        mask = field_of_view_mask(clip)
        ek["masks"] = mask
        run("C3VD clip every 8th", clip, [], **ek)
        mir = np.ascontiguousarray(clip[20][:, ::-1])
        seq = [*clip[:12], kodak(3, (w, h)), *clip[12:24], mir, *clip[24:], kodak(20, (w, h))]
        run(
            "C3VD clip every 8th + Kodak 3 at 12, frame 20 mirrored at 25, Kodak 20 at 39",
            seq,
            [12, 25, 39],
            **ek,
        )

    print(header("Structure from motion: frames that do not belong"))
    print(
        markdown_table(
            [
                "sequence",
                "frames",
                "true frames registered",
                "intruders registered",
                "registered by the fallbacks",
                "worst rotation deg",
                "path error %",
                "s",
            ],
            rows,
        )
    )
    print("Why each intruder is left out (the notes):\n")
    print("\n".join(f"- {w}" for w in why))


if __name__ == "__main__":
    main()
