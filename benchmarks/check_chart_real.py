"""ColorChecker detection on real photographs of real charts, and on harder copies of them.

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_chart_real.py FOLDER \
        [--no-variants | --no-peer-variants] [--peer-cache FILE.json] [--overlays DIR]

``--overlays DIR`` writes each photograph with imageform's detection drawn on it (patch
centres numbered 1-24, patch 1 in red) for checking by eye. ``--no-variants`` leaves out the
harder copies, ``--no-peer-variants`` runs only imageform on
them (its "mcc found" column is then "-"); ``--peer-cache`` keeps the peers' answers
(OpenCV's mcc, colour-checker-detection) in a JSON file and reuses them on the next run (they
do not change between a before and an after run of imageform, and they are the slow part).

``FOLDER`` holds photographs (JPEG/PNG) of X-Rite ColorChecker Classic charts, or of other
scenes (a photograph without a Classic is counted as found or not). The photographs of the
2026-11-29 table come from public repositories, not this one (their licences differ):
jarrelscy/ColorCheckerDetector (7, MIT; printed charts and one on a screen, phone photos of
cluttered desks and floors), karnehen/ColorChecker (3, seeds beside a Classic), luimoli/
ColorcheckerCalibration (4, a machine-vision camera under CWF, D65, TL84 light),
pedrodiamel/colorchecker-detection (1, MIT), QiuJueqin/color-checker-extraction (2, MIT:
a ColorChecker Passport and a Digital SG, which is not a Classic) and 2vin/color-correction
(1, MIT, a portrait without a chart).

The photographs of chart-fresh-2026-12-01e come from alexandresoaresilva/auto_color_calibration,
ian-ellis/colorchecker and agfianf/color-correction (tuning), riskiest/color_calibration,
ij-plugins/ijp-javacv, Robert82310/ColorChecker-DoInfer-OnnxRuntime-, fahadnazmi/imgcolour and
jeffliulab/Color_Calibration (held out); the table there names paths and commits.

Per photograph: found or not (", mirrored" after the score: found with its columns reversed,
as a webcam's mirrored preview shows it) and the time of :func:`detect_colorchecker`, and
where OpenCV's ``mcc`` detector (``cv2.mcc``, MCC24) finds the chart too, the median and
largest difference of the patch means (8-bit units); whether colour-checker-detection's
segmentation detector (``detect_colour_checkers_segmentation``) finds one; the mean
CIEDE2000 of the measured patches (those not flagged missing or saturated; in brackets the
least share of a usable patch's pixels that :func:`measure_chart_patches` averaged, leaving
out marks) to the ColorChecker's published sRGB as they are and after
:func:`fit_color_correction` (3 x 3 in linear light, fitted on them: how well a correction
from this chart can do, and never worse than none).

Then the photographs that both detectors find are made harder, with the geometry known (the
chart's centres of the original photograph carried through the change): turned 90, 180 and
270 degrees; shrunk to a patch pitch of 12 and 8 pixels, and to 24 and 12 pixels at the
photograph's own size (pasted into the middle of a blurred copy of itself); JPEG quality 15;
low light (linear light x 0.06, shot noise, JPEG 85); glare (a white blob, 90 % at its
centre, sigma 0.8 pitch, over patches 7, 8, 13, 14); a shadow's edge (encoded values x 0.35
on one side of the line through patches 2 and 21); a strong perspective (the top edge of the
frame squeezed to 40 %); cropped through the last column of patches. A variant counts as
found when the median centre error is under a quarter pitch.
"""

from __future__ import annotations

import hashlib
import io
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from benchmarks._common import header, markdown_table
from imageform.analysis import (
    ChartDetection,
    ChartWarning,
    detect_colorchecker,
    fit_color_correction,
    measure_chart_patches,
)
from imageform.analysis.synthetic import COLORCHECKER_SRGB8


def _read(path: Path) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(path).convert("RGB"))


def _jpeg(a: np.ndarray, quality: int) -> np.ndarray:
    from PIL import Image

    b = io.BytesIO()
    Image.fromarray(a).save(b, "JPEG", quality=quality)
    return np.asarray(Image.open(b))


def _pitch(c: np.ndarray) -> float:
    return float(np.median(np.linalg.norm(np.diff(c.reshape(4, 6, 2), axis=1), axis=2)))


def _mcc(im: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """OpenCV's mcc: the patch means (24, 3) in [0, 1] and the patch centres, or None."""
    import cv2

    det = cv2.mcc.CCheckerDetector.create()
    det.setColorChartType(cv2.mcc.MCC24)
    det.setUseDnnModel(False)
    if not det.process(cv2.cvtColor(im, cv2.COLOR_RGB2BGR), 1):
        return None
    ch = det.getBestColorChecker()
    means = np.asarray(ch.getChartsRGB(False)).reshape(-1, 3) / 255.0
    centres = np.asarray(ch.getColorCharts()).reshape(-1, 4, 2).mean(axis=1)
    return means, centres


def _ccd(im: np.ndarray) -> bool:
    """Whether colour-checker-detection's segmentation detector finds a chart."""
    try:
        import colour_checker_detection as ccd
    except ImportError:
        return False
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        found = ccd.detect_colour_checkers_segmentation(im.astype(np.float32) / 255.0)
    return len(found) > 0


class _Peers:
    """The peers' answers, kept in a JSON file between runs (keyed by the image's bytes)."""

    def __init__(self, path: str | None) -> None:
        self.path = Path(path) if path else None
        self.data: dict[str, object] = {}
        if self.path is not None and self.path.exists():
            self.data = json.loads(self.path.read_text())

    def _key(self, what: str, im: np.ndarray) -> str:
        return what + ":" + hashlib.sha1(np.ascontiguousarray(im).tobytes()).hexdigest()

    def mcc(self, im: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        key = self._key("mcc", im)
        if key not in self.data:
            res = _mcc(im)
            self.data[key] = None if res is None else [res[0].tolist(), res[1].tolist()]
            self._save()
        got = self.data[key]
        if got is None:
            return None
        assert isinstance(got, list)
        return np.asarray(got[0]), np.asarray(got[1])

    def ccd(self, im: np.ndarray) -> bool:
        key = self._key("ccd", im)
        if key not in self.data:
            self.data[key] = _ccd(im)
            self._save()
        return bool(self.data[key])

    def _save(self) -> None:
        if self.path is not None:
            self.path.write_text(json.dumps(self.data))


def _delta_e00(im: np.ndarray, det: object) -> tuple[str, str, str]:
    """The patches flagged missing or saturated, and the mean CIEDE2000 of the usable
    patches to the published sRGB: as measured, and corrected."""
    from imageform.color.convert import convert
    from imageform.color.delta_e import delta_e

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ChartWarning)
        try:
            p = measure_chart_patches(im, det)  # type: ignore[arg-type]
        except ValueError:
            return "all 24", "-", "-"
        flagged = " ".join(str(i) for i in np.flatnonzero(~p.valid)) or "none"
        used = getattr(p, "used", None)  # the share of each patch's pixels averaged
        if used is not None:
            flagged += f" ({np.min(used[p.valid]):.2f})"
        ref = np.asarray(COLORCHECKER_SRGB8, dtype=np.float64) / 255.0
        use = p.valid & (p.means < 1.0).all(axis=1)
        lab_ref = np.asarray(convert(ref[use], "srgb", "lab"))
        raw = float(np.mean(delta_e(lab_ref, np.asarray(convert(p.means[use], "srgb", "lab")))))
        try:
            corr = fit_color_correction(p, ref)
        except ValueError:
            return flagged, f"{raw:.1f}", "-"
        fixed = corr.apply(p.means[use][:, None, :])[:, 0, :]
        after = float(np.mean(delta_e(lab_ref, np.asarray(convert(fixed, "srgb", "lab")))))
    return flagged, f"{raw:.1f}", f"{after:.1f}"


def _variants(
    im: np.ndarray, c0: np.ndarray, seed: int
) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Harder copies of a photograph and the chart's patch centres in each."""
    import cv2

    rng = np.random.default_rng(seed)
    h, w = im.shape[:2]
    out = {
        "rot90": (np.ascontiguousarray(np.rot90(im, 1)), np.c_[c0[:, 1], w - 1 - c0[:, 0]]),
        "rot180": (np.ascontiguousarray(im[::-1, ::-1]), np.c_[w - 1 - c0[:, 0], h - 1 - c0[:, 1]]),
        "rot270": (np.ascontiguousarray(np.rot90(im, -1)), np.c_[h - 1 - c0[:, 1], c0[:, 0]]),
    }
    pitch = _pitch(c0)
    for target in (12, 8):
        s = target / pitch
        if s < 1:
            size = (max(16, round(w * s)), max(16, round(h * s)))
            sm = cv2.resize(im, size, interpolation=cv2.INTER_AREA)
            sx, sy = sm.shape[1] / w, sm.shape[0] / h
            out[f"pitch {target} px"] = (
                sm,
                np.c_[(c0[:, 0] + 0.5) * sx - 0.5, (c0[:, 1] + 0.5) * sy - 0.5],
            )
    # the same at the photograph's own size: the shrunk photograph pasted into the middle of
    # a blurred copy of itself (sigma 2 pitches: no patches left in it)
    for target in (24, 12):
        s = target / pitch
        if s < 0.5:
            sm = cv2.resize(im, (round(w * s), round(h * s)), interpolation=cv2.INTER_AREA)
            canvas = cv2.GaussianBlur(im, (0, 0), 2 * pitch)
            y0, x0 = (h - sm.shape[0]) // 2, (w - sm.shape[1]) // 2
            canvas[y0 : y0 + sm.shape[0], x0 : x0 + sm.shape[1]] = sm
            sx, sy = sm.shape[1] / w, sm.shape[0] / h
            small = np.c_[(c0[:, 0] + 0.5) * sx - 0.5 + x0, (c0[:, 1] + 0.5) * sy - 0.5 + y0]
            out[f"pitch {target} px, full frame"] = (canvas, small)
    out["JPEG q15"] = (_jpeg(im, 15), c0)
    lin = (im / 255.0) ** 2.2 * 0.06
    noisy = lin + rng.normal(0.0, 1.0, lin.shape) * np.sqrt(lin * 0.002 + 1e-5)
    low = (np.clip(noisy, 0, 1) ** (1 / 2.2) * 255).round().astype(np.uint8)
    out["low light"] = (_jpeg(low, 85), c0)
    vv, uu = np.mgrid[:h, :w]
    cu, cv = c0[[7, 8, 13, 14]].mean(axis=0)
    g = np.exp(-((uu - cu) ** 2 + (vv - cv) ** 2) / (2 * (0.8 * pitch) ** 2))[..., None]
    out["glare"] = ((im + (255 - im) * 0.9 * g).round().astype(np.uint8), c0)
    (au, av), (bu, bv) = c0[2], c0[21]
    side = (bu - au) * (vv - av) - (bv - av) * (uu - au) > 0
    out["shadow"] = ((im * np.where(side, 0.35, 1.0)[..., None]).round().astype(np.uint8), c0)
    src = np.array([[0, 0], [w, 0], [w, h], [0, h]], dtype=np.float32)
    dst = np.array([[w * 0.3, h * 0.1], [w * 0.7, h * 0.1], [w, h], [0, h]], dtype=np.float32)
    hm = cv2.getPerspectiveTransform(src, dst)
    q = np.c_[c0 + 0.5, np.ones(24)] @ hm.T
    warped = cv2.warpPerspective(im, hm, (w, h), flags=cv2.INTER_AREA)
    out["perspective"] = (warped, q[:, :2] / q[:, 2:] - 0.5)
    cols = c0.reshape(4, 6, 2)
    rowdir = cols[:, 5].mean(axis=0) - cols[:, 0].mean(axis=0)
    ax = 0 if abs(rowdir[0]) > abs(rowdir[1]) else 1
    cut = round(float(cols[:, 5, ax].mean()))
    keep_low = rowdir[ax] > 0
    sl = slice(0, cut) if keep_low else slice(cut, None)
    crop = im[:, sl] if ax == 0 else im[sl]
    shift = np.zeros(2)
    shift[ax] = 0 if keep_low else cut
    out["cropped"] = (np.ascontiguousarray(crop), c0 - shift)
    return out


def _overlay(im: np.ndarray, det: ChartDetection, path: Path) -> None:
    """Write the photograph with the detection drawn: patch centres numbered 1-24 (patch 1,
    the brown, in red), the lattice's outline through patches 1, 6, 24, 19 (for checking by
    eye: orientation, centres on the patches)."""
    from PIL import Image, ImageDraw

    out = Image.fromarray(im)
    draw = ImageDraw.Draw(out)
    if det.found:
        c = det.centers
        r = max(2.0, 0.12 * _pitch(c))
        draw.line([tuple(c[k]) for k in (0, 5, 23, 18, 0)], fill=(255, 0, 255), width=1)
        for k, (u, v) in enumerate(c):
            colour = (255, 0, 0) if k == 0 else (0, 255, 0)
            draw.ellipse((u - r, v - r, u + r, v + r), outline=colour, width=2)
            draw.text((u + r, v - r), str(k + 1), fill=(255, 255, 255))
    out.save(path)


def _found_at(im: np.ndarray, truth: np.ndarray) -> tuple[bool, float]:
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ChartWarning)
        det = detect_colorchecker(im)
    dt = time.perf_counter() - t0
    if not det.found:
        return False, dt
    err = np.linalg.norm(det.centers - truth, axis=1) / _pitch(truth)
    return bool(np.median(err) < 0.25), dt


def main(
    folder: str,
    variants: bool = True,
    peer_cache: str | None = None,
    peer_variants: bool = True,
    overlays: str | None = None,
) -> str:
    paths = sorted(
        p for p in Path(folder).iterdir() if p.suffix.lower() in {".jpg", ".jpeg", ".png"}
    )
    peers = _Peers(peer_cache)
    rows, both = [], []
    for path in paths:
        im = _read(path)
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ChartWarning)
            det = detect_colorchecker(im)
            dt = time.perf_counter() - t0
            try:
                ours = measure_chart_patches(im, det).means if det.found else None
            except ValueError:  # every patch flagged: no means to compare
                ours = None
        if overlays is not None:
            Path(overlays).mkdir(parents=True, exist_ok=True)
            _overlay(im, det, Path(overlays) / (path.stem + ".png"))
        peer = peers.mcc(im)
        de = _delta_e00(im, det) if det.found else ("-", "-", "-")
        diff = "-"
        if ours is not None and peer is not None:
            d = np.abs(ours - peer[0]).max(axis=1) * 255
            diff = f"{np.median(d):.1f} / {d.max():.1f}"
            both.append((path.name, im, det.centers))
        rows.append(
            (
                path.name,
                f"{im.shape[1]}x{im.shape[0]}",
                "yes" if det.found else "no",
                (f"{det.score:.2f}" + (", mirrored" if getattr(det, "mirrored", False) else ""))
                if det.found
                else det.reason,
                f"{dt:.2f}",
                "yes" if peer is not None else "no",
                diff,
                "yes" if peers.ccd(im) else "no",
                *de,
            )
        )
    text = markdown_table(
        (
            "photograph",
            "size",
            "imageform found",
            "score / reason",
            "s",
            "mcc found",
            "patch means vs mcc, median / max (8-bit)",
            "colour-checker-detection found",
            "patches flagged (missing, saturated) (least share of pixels used)",
            "ΔE00 to published, as measured",
            "ΔE00 after fit",
        ),
        rows,
    )
    if not variants:
        return text
    tally: dict[str, list[int]] = {}
    worst: dict[str, float] = {}
    for i, (_, im, c0) in enumerate(both):
        for name, (vim, truth) in _variants(im, c0, i).items():
            ok, dt = _found_at(vim, truth)
            peer = peers.mcc(vim) if peer_variants else None
            pok = peer is not None and len(peer[1]) == 24
            if pok:
                assert peer is not None
                perr = np.linalg.norm(peer[1] - truth, axis=1) / _pitch(truth)
                pok = bool(np.median(perr) < 0.25)
            t = tally.setdefault(name, [0, 0, 0])
            t[0] += ok
            t[1] += pok
            t[2] += 1
            worst[name] = max(worst.get(name, 0.0), dt)
    vrows = [
        (n, f"{a} / {c}", f"{b} / {c}" if peer_variants else "-", f"{worst[n]:.2f}")
        for n, (a, b, c) in tally.items()
    ]
    text += "\nHarder copies of the photographs both detectors find:\n\n" + markdown_table(
        ("variant", "imageform found", "mcc found", "imageform slowest s"), vrows
    )
    return text


if __name__ == "__main__":
    args = sys.argv[1:]
    cache = None
    if "--peer-cache" in args:
        i = args.index("--peer-cache")
        cache = args[i + 1]
        del args[i : i + 2]
    overlay_dir = None
    if "--overlays" in args:
        i = args.index("--overlays")
        overlay_dir = args[i + 1]
        del args[i : i + 2]
    with_variants = "--no-variants" not in args
    with_peers = "--no-peer-variants" not in args
    args = [a for a in args if a not in ("--no-variants", "--no-peer-variants")]
    if len(args) != 1:
        raise SystemExit(
            "usage: check_chart_real.py FOLDER_OF_PHOTOGRAPHS [--no-variants | "
            "--no-peer-variants] [--peer-cache FILE.json] [--overlays DIR]"
        )
    print(header("ColorChecker detection on real photographs"))
    print(main(args[0], with_variants, cache, with_peers, overlay_dir))
