"""Raw files as cameras and converters write them: imageform's development against LibRaw's.

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_raw_variants.py \\
        [--src before=/path/to/old/src] [--src after=src]

Every variant is a DNG written from a Kodak photograph (``tests/io/test_raw_variants.py``'s
made-up camera: a mosaic of ``kodim23``'s top-left 384 x 256 pixels through its colour
matrix, as-shot neutral (0.55, 1, 0.42)), then varied as real files are: two colour matrices
under different illuminants, a camera calibration and analog balance, no as-shot white
balance, a monochrome sensor, an X-Trans CFA, floating-point samples, JPEG XL compression
(DNG 1.7), an ActiveArea, a LinearizationTable, black level deltas. Each ``--src`` tree
develops every file (``develop(path)``, defaults: camera white balance, bilinear, sRGB) in its
own process; the table gives, per tree, the mean CIEDE2000 to LibRaw's rendering at matched
settings (``rawpy.postprocess(use_camera_wb=True, no_auto_bright=True, output_bps=16,
gamma=(2.4, 12.92), demosaic_algorithm=LINEAR, adjust_maximum_thr=0)``, two border pixels
left out), or, where LibRaw decodes nothing (floats it leaves at zero, JPEG XL it refuses),
to the same tree's development of the file's integer, uncompressed twin; or why it failed.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def _write_variants(folder: Path) -> dict[str, tuple[str, str | None, dict[str, object]]]:
    """Write the variants; return name -> (file, integer twin or None: LibRaw is the reference,
    options: ``develop``'s and, under ``"libraw"``, LibRaw's beyond the matched settings)."""
    import tifffile

    from imageform.io import write_dng
    from imageform.sensor import mosaic as make_mosaic
    from tests.io import test_raw_variants as tv

    cam = tv._camera_rgb()
    dn = np.round(64 + make_mosaic(cam, "RGGB") * (4095 - 64)).astype(np.uint16)
    path = write_dng(
        folder / "base.dng",
        dn,
        black_level=64,
        white_level=4095,
        color_matrix=tv.CM,
        as_shot_neutral=tv.NEUTRAL,
    )
    with tifffile.TiffFile(path) as tf:
        tags = [(t.code, t.dtype, t.count, t.value, True) for t in tf.pages[0].tags]
    tags = [t for t in tags if t[0] >= 33421]
    lin = np.round(64 + cam * (4095 - 64)).astype(np.uint16)
    base = (path, tags, lin)
    rat = tv._rational
    cfa_tags = {33421, 33422, 50710, 50711}
    out: dict[str, tuple[str, str | None, dict[str, object]]] = {
        "Bayer RGGB, one matrix (D65)": (str(path), None, {})
    }

    def add(name: str, p: Path, twin: Path | None = None, **options: object) -> None:
        out[name] = (str(p), None if twin is None else str(twin), options)

    add("two matrices, StdA + D65", tv._two_matrices(base, "v_a_d65", (17, 21)))
    add("two matrices, StdA + D50", tv._two_matrices(base, "v_a_d50", (17, 23)))
    add(
        "one matrix labelled StdA",
        tv._variant(base, "v_a", drop={50778}, extra=[(50778, 3, 1, 17, True)]),
    )
    cc = np.array([[1.05, 0.03, -0.02], [0.01, 0.98, 0.02], [-0.03, 0.04, 1.10]])
    add(
        "CameraCalibration + AnalogBalance",
        tv._variant(
            base,
            "v_cal",
            extra=[(50723, 10, 9, rat(cc), True), (50727, 5, 3, rat([1.2, 1.0, 0.8]), True)],
        ),
    )
    add("no as-shot white balance", tv._variant(base, "v_nowb", drop={50728}))
    add("monochrome (LinearRaw, 1 sample)", tv._monochrome(base, "v_mono", lin[..., 1].copy()))
    add(
        "linear raw (LinearRaw, 3 samples)",
        tv._variant(base, "v_lin", data=lin, photometric=34892, drop=cfa_tags),
    )
    xt = np.array(
        [
            [1, 1, 0, 1, 1, 2],
            [1, 1, 2, 1, 1, 0],
            [2, 0, 1, 0, 2, 1],
            [1, 1, 2, 1, 1, 0],
            [1, 1, 0, 1, 1, 2],
            [0, 2, 1, 2, 0, 1],
        ]
    )
    h, w = cam.shape[:2]
    which = np.tile(xt, (h // 6 + 1, w // 6 + 1))[:h, :w]
    xdn = np.round(64 + np.take_along_axis(cam, which[..., None], 2)[..., 0] * 4031)
    add(
        "X-Trans 6x6 CFA",
        tv._variant(
            base,
            "v_xtrans",
            data=xdn.astype(np.uint16),
            drop={33421, 33422},
            extra=[(33421, 3, 2, (6, 6), True), (33422, 1, 36, tuple(xt.ravel().tolist()), True)],
        ),
    )
    floats = ((dn.astype(np.float64) - 64) / 4031).astype(np.float32)
    add(
        "32-bit floats, WhiteLevel 1.0",
        tv._variant(
            base,
            "v_float",
            data=floats,
            drop={50713, 50714, 50717},
            extra=[(50717, 11, 1, 1.0, True), (50714, 11, 1, 0.0, True)],
        ),
        path,
    )
    jxl = folder / "v_jxl.dng"
    tifffile.imwrite(
        jxl,
        dn,
        photometric=32803,
        extratags=tags,
        tile=(128, 128),
        compression=52546,
        compressionargs={"lossless": True},
    )
    add("JPEG XL compression (DNG 1.7)", jxl, path)
    add(
        "ActiveArea (3, 5, 251, 381)",
        tv._variant(base, "v_area", extra=[(50829, 4, 4, (3, 5, 251, 381), True)]),
    )
    table = np.round((np.arange(1024) / 1023.0) ** 2 * 4095).astype(np.uint16)
    add(
        "LinearizationTable",
        tv._variant(
            base,
            "v_table",
            data=np.searchsorted(table, dn).clip(0, 1023).astype(np.uint16),
            extra=[(50712, 3, 1024, tuple(table.tolist()), True)],
        ),
    )
    add("orientation 6 (portrait)", tv._variant(base, "v_orient", extra=[(274, 3, 1, 6, True)]))
    dark = tv._variant(base, "v_dark", data=np.round(64 + (dn - 64.0) * 0.35).astype(np.uint16))
    add(
        "a third of the light, LibRaw's default look (auto-bright, BT.709 curve)",
        dark,
        auto_bright=True,
        transfer="rec709",
        libraw={"no_auto_bright": False, "gamma": (2.222, 4.5)},
    )
    return out


def _measure(listing: Path) -> None:
    """Develop every file with the imageform on sys.path; print one JSON object."""
    import warnings

    from imageform.color import decode, delta_e, linear_srgb_to_xyz, xyz_to_lab
    from imageform.io import develop
    from tests.io.test_raw_variants import _libraw as libraw

    warnings.simplefilter("ignore")

    def lab(a: np.ndarray) -> np.ndarray:
        a = np.asarray(a, np.float64)
        if a.ndim == 2:
            a = np.repeat(a[..., None], 3, axis=-1)
        return np.asarray(xyz_to_lab(linear_srgb_to_xyz(decode(a, "srgb"))))

    result: dict[str, str] = {}
    for name, (path, twin, options) in json.loads(listing.read_text()).items():
        theirs = options.pop("libraw", {})
        if "gamma" in theirs:
            theirs["gamma"] = tuple(theirs["gamma"])
        try:
            ours = develop(path, **options).image
            if twin is None:
                ref = libraw(Path(path), **theirs)  # the tests' matched settings
                ref = ref[..., 0] if ref.shape[-1] == 1 else ref
                against = "LibRaw"
            else:
                ref, against = develop(twin).image, "integer twin"
            if ours.shape != ref.shape:
                result[name] = f"size {ours.shape[:2]} vs {against}'s {ref.shape[:2]}"
                continue
            de = float(np.mean(delta_e(lab(ours), lab(ref))[2:-2, 2:-2]))
            result[name] = f"{de:.3f} (vs {against})"
        except Exception as exc:  # the row says why
            why = str(exc).splitlines()[0].replace(str(Path(path).parent) + os.sep, "")
            result[name] = f"{type(exc).__name__}: {why[:80]}"
    print(json.dumps(result))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--src", action="append", default=[], help="LABEL=PATH of a src tree")
    parser.add_argument("--measure", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.measure is not None:
        _measure(args.measure)
        return
    from benchmarks._common import header, markdown_table

    trees = [s.split("=", 1) for s in args.src] or [["imageform", str(ROOT / "src")]]
    with tempfile.TemporaryDirectory() as tmp:
        files = _write_variants(Path(tmp))
        listing = Path(tmp) / "variants.json"
        listing.write_text(json.dumps(files))
        columns: list[dict[str, str]] = []
        for _, src in trees:
            env = dict(
                os.environ, PYTHONPATH=os.pathsep.join([str(Path(src).resolve()), str(ROOT)])
            )
            done = subprocess.run(
                [sys.executable, __file__, "--measure", str(listing)],
                env=env,
                capture_output=True,
                text=True,
                check=True,
                cwd=tmp,
            )
            columns.append(json.loads(done.stdout.strip().splitlines()[-1]))
    print(header("Raw files as cameras and converters write them: mean CIEDE2000 to LibRaw"))
    rows = [[name] + [c.get(name, "-") for c in columns] for name in files]
    print(markdown_table(["DNG variant"] + [label for label, _ in trees], rows))


if __name__ == "__main__":
    main()
