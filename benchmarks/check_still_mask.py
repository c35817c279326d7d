"""What stands still while the camera moves: burned-in overlays found by ``still_mask``.

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python -m benchmarks.check_still_mask

:func:`imageform.geometry.still_mask` on the room's walk (``tests/sfm_scenes.py``, 400 x
300, rendered, noise 1.5) with an overlay drawn on every frame, then the frame encoded as
a video would (JPEG at quality 95, 85, 75, or none):

- the overlays: ``tune``, the six lines of white text on a thin black outline of
  ``sfm_scenes.burn_in`` (the one the defaults were set on); held out, never looked at
  while setting them: ``banner``, a black band along the bottom with grey text in another
  font and a clock whose seconds change every frame; ``logo``, a filled disc with two
  letters in the top right corner; ``none``.
- the scenes: the walk's own photographs (Kodak 1, 8, 13, 21, 23, 5), and two held-out
  sets of Kodak photographs on its walls (2, 4, 7, 9, 11, 15 and 14, 17, 18, 19, 22, 24);
  8 and 12 frames.
- ``found``: the share of the overlay's edge pixels (those it changed in the first frame,
  the clock's digits excluded, where the frame's 3 x 3 range is 0.1 or more: where a
  keypoint can be; a banner's flat inside holds none) inside the mask without its margin;
  ``false``: pixels of the mask (margin 0) farther than 3 px from any pixel the overlay
  changed in any frame.
- keypoints (SIFT, :func:`imageform.geometry.detect_features`, 2000 at most, on the first
  frame): of those on the overlay (within 2 px of a pixel it changed), the share the
  default mask (margin 8) leaves out; and of those 12 px or more from it, the share left
  out (scene lost).

Then :func:`imageform.geometry.field_of_view_mask` (``--auto-mask``) on 10 frames of two
scenes: the share of the overlay's keypoints and of the scene's (as above) it leaves out,
with its default 8 px margin (the scene's share is the frame's border); ``--fov-only``
prints that table alone (to compare two source trees).

Then :func:`imageform.geometry.reconstruct_sequence` on 8 frames of the walk with the
overlay and two Kodak photographs (3 and 20) carrying it too, with the default
``overlays=True`` and with ``overlays=False``: which photographs are registered, and the
seconds (one run each, this machine).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import cv2
import numpy as np

from imageform.geometry import detect_features, reconstruct_sequence, still_mask
from imageform.io import read_image
from tests import sfm_scenes

K = np.array([[300.0, 0, 199.5], [0, 300.0, 149.5], [0, 0, 1]])
SIZE = (400, 300)
SETS = {"walk": None, "kodak-a": (2, 4, 7, 9, 11, 15), "kodak-b": (14, 17, 18, 19, 22, 24)}


def banner(image: np.ndarray, i: int) -> np.ndarray:
    """A black band along the bottom, grey text in another font and a running clock."""
    out = np.ascontiguousarray(image.copy())
    h, w = out.shape[:2]
    out[h - 26 :, :] = 0
    cv2.putText(out, "ENDO-3 PT 0042  EXP 12.4", (6, h - 9), cv2.FONT_HERSHEY_PLAIN, 1.0,
                (200, 200, 200), 1, cv2.LINE_AA)  # fmt: skip
    cv2.putText(out, f"10:31:{i:02d}", (w - 92, h - 9), cv2.FONT_HERSHEY_PLAIN, 1.0,
                (200, 200, 200), 1, cv2.LINE_AA)  # fmt: skip
    return out


def logo(image: np.ndarray, i: int) -> np.ndarray:
    """A filled disc with two letters in the top right corner."""
    out = np.ascontiguousarray(image.copy())
    w = out.shape[1]
    cv2.circle(out, (w - 30, 28), 20, (30, 90, 200), -1, cv2.LINE_AA)
    cv2.putText(out, "HD", (w - 45, 35), cv2.FONT_HERSHEY_DUPLEX, 0.6, (255, 255, 255), 1,
                cv2.LINE_AA)  # fmt: skip
    return out


OVERLAYS = {
    "tune": lambda im, i: sfm_scenes.burn_in(im),
    "banner": banner,
    "logo": logo,
    "none": lambda im, i: im.copy(),
}


def jpeg(image: np.ndarray, q: int | None) -> np.ndarray:
    if q is None:
        return image
    ok, buf = cv2.imencode(".jpg", image[..., ::-1], [cv2.IMWRITE_JPEG_QUALITY, q])
    assert ok
    decoded = cv2.imdecode(buf, cv2.IMREAD_COLOR)
    assert decoded is not None
    return np.ascontiguousarray(decoded[..., ::-1])


def kodak(data: Path, i: int) -> np.ndarray:
    im = np.asarray(read_image(data / "kodak" / f"kodim{i:02d}.png"))[..., :3]
    return np.asarray(cv2.resize(im, SIZE, interpolation=cv2.INTER_AREA))


def masks_table(data: Path) -> list[str]:
    rows = [
        "| scene | overlay | frames | JPEG | found | false px | still px | overlay keypoints out "
        "| scene keypoints out |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for name, ids in SETS.items():
        photos = None if ids is None else [kodak(data, i) for i in ids]
        walk, _ = sfm_scenes.sequence(K, 12, SIZE, photos=photos)
        for ov, draw in OVERLAYS.items():
            drawn = [draw(f, i) for i, f in enumerate(walk)]
            changed = [np.any(d != f, axis=2) for d, f in zip(drawn, walk, strict=True)]
            # the first frame's overlay pixels that every frame shares (not the clock)
            same = np.all([np.all(d == drawn[0], axis=2) for d in drawn], axis=0)
            grey = drawn[0].mean(axis=2).astype(np.float32) / 255
            box = np.ones((3, 3), np.uint8)
            edge = (cv2.dilate(grey, box) - cv2.erode(grey, box)) >= 0.1
            target = changed[0] & same & edge
            anywhere = np.any(changed, axis=0).astype(np.uint8)
            near = cv2.dilate(anywhere, np.ones((7, 7))) > 0
            on = cv2.dilate(anywhere, np.ones((5, 5))) > 0
            off = cv2.dilate(anywhere, np.ones((25, 25))) == 0
            for n in (8, 12):
                for q in (None, 95, 85, 75):
                    frames = [jpeg(d, q) for d in drawn[:n]]
                    m = still_mask(frames, margin=0)
                    full = still_mask(frames)
                    xy = np.round(detect_features(frames[0], max_features=2000).xy).astype(int)
                    kp_on = on[xy[:, 1], xy[:, 0]]
                    kp_off = off[xy[:, 1], xy[:, 0]]
                    gone = full[xy[:, 1], xy[:, 0]]
                    found = "" if not target.any() else f"{m[target].mean():.3f}"
                    false = int(np.sum(m & ~near))
                    k_on = f"{gone[kp_on].mean():.3f} of {int(kp_on.sum())}" if kp_on.any() else ""
                    k_off = f"{gone[kp_off].mean():.3f} of {int(kp_off.sum())}"
                    rows.append(
                        f"| {name} | {ov} | {n} | {q or 'none'} | {found} | {false} "
                        f"| {int(m.sum())} | {k_on} "
                        f"| {k_off} |"
                    )
    return rows


def fov_table(data: Path) -> list[str]:
    """``field_of_view_mask`` (``--auto-mask``) on 10 frames of the walk with an overlay."""
    from imageform.geometry import field_of_view_mask

    rows = [
        "| scene | overlay | JPEG | overlay keypoints out | scene keypoints out |",
        "|---|---|---:|---:|---:|",
    ]
    for name in ("walk", "kodak-b"):
        ids = SETS[name]
        photos = None if ids is None else [kodak(data, i) for i in ids]
        walk, _ = sfm_scenes.sequence(K, 10, SIZE, photos=photos)
        for ov in ("tune", "banner", "logo"):
            drawn = [OVERLAYS[ov](f, i) for i, f in enumerate(walk)]
            changed = [np.any(d != f, axis=2) for d, f in zip(drawn, walk, strict=True)]
            anywhere = np.any(changed, axis=0).astype(np.uint8)
            on = cv2.dilate(anywhere, np.ones((5, 5))) > 0
            off = cv2.dilate(anywhere, np.ones((25, 25))) == 0
            for q in (None, 85, 75):
                frames = [jpeg(d, q) for d in drawn]
                keep = field_of_view_mask(frames)
                xy = np.round(detect_features(frames[0], max_features=2000).xy).astype(int)
                gone = ~keep[xy[:, 1], xy[:, 0]]
                k_on, k_off = on[xy[:, 1], xy[:, 0]], off[xy[:, 1], xy[:, 0]]
                rows.append(
                    f"| {name} | {ov} | {q or 'none'} | {gone[k_on].mean():.3f} of "
                    f"{int(k_on.sum())} | {gone[k_off].mean():.3f} of {int(k_off.sum())} |"
                )
    return rows


def sfm_table(data: Path) -> list[str]:
    rows = [
        "| overlay | JPEG | overlays | photographs registered | true frames registered | s |",
        "|---|---:|---|---:|---:|---:|",
    ]
    walk, _ = sfm_scenes.sequence(K, 8, SIZE)
    photos = [kodak(data, i) for i in (3, 20)]
    for ov in ("tune", "banner"):
        for q in (None, 85):
            seq = [jpeg(OVERLAYS[ov](f, i), q) for i, f in enumerate([*walk, *photos])]
            for on in (True, False):
                t0 = time.perf_counter()
                rec = reconstruct_sequence(seq, K, max_features=2000, overlays=on)
                dt = time.perf_counter() - t0
                rows.append(
                    f"| {ov} | {q or 'none'} | {on} | {int(rec.registered[8:].sum())} of 2 | "
                    f"{int(rec.registered[:8].sum())} of 8 | {dt:.1f} |"
                )
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=Path("../shared/data"))
    ap.add_argument("--fov-only", action="store_true", help="only field_of_view_mask's table")
    ap.add_argument("--masks-only", action="store_true", help="only the mask's table")
    args = ap.parse_args()
    if args.masks_only:
        print("\n".join(masks_table(args.data)))
        return
    if args.fov_only:
        print("\n".join(fov_table(args.data)))
        return
    print(f"# still_mask on overlays, {time.strftime('%Y-%m-%d')}\n")
    cmd = "OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python -m benchmarks.check_still_mask"
    print(f"Command: `{cmd}`\n")
    print("## The mask\n")
    print("\n".join(masks_table(args.data)))
    print("\n## field_of_view_mask (--auto-mask), 10 frames\n")
    print("\n".join(fov_table(args.data)))
    print("\n## Structure from motion with two photographs carrying the overlay\n")
    print("\n".join(sfm_table(args.data)))


if __name__ == "__main__":
    main()
