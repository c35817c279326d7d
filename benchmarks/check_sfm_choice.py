"""The fisheye chosen by a robust cost on common tracks: ``imageform reconstruct`` before and after.

Without ``--camera``, where COLMAP's ``SIMPLE_RADIAL`` ran off or its barrel term reached
half its bound, ``imageform reconstruct`` also reconstructs with the equidistant fisheye
(``check_sfm_fisheye.py``). Before this change it kept the fisheye when its median
reprojection error was at most 5 % above the other's (the 2 px filter leaves both near 0.54
px on C3VD: a tie); after, when its robust cost on the tracks of both models is at most the
other's (each track triangulated with each model's cameras held, every view's squared
error in the image capped at 2 px, views it cannot explain at the cap, GRIC's penalty
ln(2n) per lens parameter: Torr 1998, Torr & Zisserman 2000; ``sfm._track_cost``). Each
sequence is run by the command before (``--before SRC``: main's ``src`` on ``PYTHONPATH``)
and after (this checkout), without ``--camera``; the fisheye sequences also by pycolmap's
fisheye self-calibration (``RADIAL_FISHEYE``, ``selfcal.json``, and ``SIMPLE_RADIAL_FISHEYE``,
``fisheye-pycolmap.json``: the cached runs of ``check_sfm_fisheye.py``, read from the data
folder). Columns as ``check_sfm_fisheye.py``'s, with the points and the two costs the
command's note printed (the fisheye's / the other's, px^2).

C3VD's reference is imageform's reconstruction with the working camera of
``tests/data/endo`` (``--camera``; a pycolmap self-calibration, not a calibration). How far
that reference itself moves is measured too: the same frames and camera with the RANSAC
seed 1, 2, 3 (``reconstruct_sequence(rng=)``, in-process, the command's masks and contrast)
against seed 0, the ``reference spread`` rows.

Sequences: ``check_sfm_k1.py``'s (its docstring names their repositories, commits and
licences) and its data folder (``--data``), as ``check_sfm_fisheye.py``.

Held out (chosen and frozen by the SHA-256 below before any run, run once with the final
code): fengbolan/York-Fisheye-Image-Rectification-Dataset at ``acd2375`` (Lan et al. 2020,
rendered in Blender; the Pack of Smokies and Chair models CC-0, the Skull CC-BY-NC, the
Teddy CC-BY-NC-SA: measured here, never committed), the fisheye frames of its four
sequences (``york-chair`` 10, ``york-box`` 20, ``york-skull`` 20, ``york-teddy`` 20 frames,
512 x 512 BMPs, made PNG), a 160 degree fisheye. Its calibration is the repository's own
map from the 16 mm perspective frames to the fisheye ones (``fov160to16mm512px.mat``): it
fits the equidistant lens :math:`r_f = f \arctan(r_p / f_p)` with f 183.49 px and
:math:`f_p` 227.82 px (16 / 36 x 512) about (255.5, 255.5), 0.04 px RMS, the f the
160 degrees across the 512 px give (256 / 1.396). f is measured against 183.49 px and the
poses against imageform with that camera (``--camera``, ``KannalaBrandt()``). Run as the
fisheye sequences (``--auto-mask --contrast-threshold 0.01``: the frames are black outside
the image circle). Nothing of it was used to choose the cost or its cap.

Run::

    git archive BASE src | tar -x -C BEFORE
    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_sfm_choice.py \\
        --data DATA --before BEFORE/src [--only c3vd colon-a colon-b]
    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_sfm_choice.py \
        --data DATA --before BEFORE/src --held-out --mirrors /work/.mirror
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks._common import header, markdown_table  # noqa: E402
from benchmarks.check_sfm_fresh import agreement  # noqa: E402
from benchmarks.check_sfm_k1 import prepare_c3vd, read_frames, run_cli  # noqa: E402

FISHEYE = ["c3vd", "colon-a", "colon-b"]
OTHERS = ["temple", "dino", "viking", "gun", "dt990", "sceaux-exif"]

HELD_REPO = "fengbolan/York-Fisheye-Image-Rectification-Dataset"
HELD_COMMIT = "acd2375635c66fd12b1271466a4c6526fdfd97c4"
HELD = {"york-chair": "Chair", "york-box": "Cigarette box", "york-skull": "Skull"}
HELD["york-teddy"] = "Teddy"
#: The equidistant camera the repository's perspective-to-fisheye map fits (f, cx, cy).
HELD_CAMERA = (183.49, 255.5, 255.5)
#: Frozen before any run: path in the repository -> SHA-256.
HELD_SHA256: dict[str, str] = {
    "Chair/fisheye/0001.bmp": "4195d75ec8a45f1a0bc99b17a7468082157b5a3b3e23289082c2509c00b98f32",
    "Chair/fisheye/0002.bmp": "9d660d30e6ab20535de009482262a5dc9901055ce24878a1b1ad0dee9ed3bb24",
    "Chair/fisheye/0003.bmp": "c32bddf3c5a7d50c1351bdfbffbb9049877edd2d69e762990913d3cfbc68fc4f",
    "Chair/fisheye/0004.bmp": "eb7daf42990ee7e6ca9423317b64a8624f657f3e7151a2f887bd558952f7aa70",
    "Chair/fisheye/0005.bmp": "2adc631e01264ef6f986414fcd5823b60ef8186be435c74a959f39f02a9a6a6d",
    "Chair/fisheye/0006.bmp": "743d83b0c57a39a75de49709914f6e3d2c5b6c5d583e3f867314cd45e2330fc4",
    "Chair/fisheye/0007.bmp": "e20cfbd3090927efab8b0db22add820c03366d744a74c17ddc43e9a60040e51e",
    "Chair/fisheye/0008.bmp": "f65b10b2094fd1ea0c02a25d49e2c58ff7ed2117533703fa2d5806678235bf67",
    "Chair/fisheye/0009.bmp": "5bf035e2ac31fa5f3dd20cf4821ae595da06cdd231ef3ca86c1155d18502ba28",
    "Chair/fisheye/0010.bmp": "2ed0bcbb4280ed9383fee6aeb2c63a27a7657d84a428d28f6dc604bb4e0702d7",
    "Cigarette box/fisheye/0001.bmp": "8ab4e3db301db591f6e165997cb1f7ab4a7da8b876aeae7dcf51404651d91a73",  # noqa: E501
    "Cigarette box/fisheye/0002.bmp": "f720d9f8ac442776c67a4eec6d090c5d634aa0b76c1f06319ff0fa4c958d9a3c",  # noqa: E501
    "Cigarette box/fisheye/0003.bmp": "3f3abd62097cbab889492b3cb73c9187cdc32c8792b128bf856d27d4958644eb",  # noqa: E501
    "Cigarette box/fisheye/0004.bmp": "42295ecdc26fafe0216be714c50aa79dbff737b84e7d33acc5af6cd677563cc6",  # noqa: E501
    "Cigarette box/fisheye/0005.bmp": "cf9bb141f9e6084c11d168fa68d62a5887a5ffb14c4f622a489cb05c9591e695",  # noqa: E501
    "Cigarette box/fisheye/0006.bmp": "8e69481b3788db5b24bbbed858ae6fe0551bcd6077e739df494c36762ba6c8b0",  # noqa: E501
    "Cigarette box/fisheye/0007.bmp": "b2a25c24a6c8e7c4d82b35f042438044b5632292a4f54dcaea24003ae8f38fd6",  # noqa: E501
    "Cigarette box/fisheye/0008.bmp": "953e485e1438fcdc447298234090085fb554c65bb63450ba2a70f03a0370144f",  # noqa: E501
    "Cigarette box/fisheye/0009.bmp": "0a923291afe8d904c07b499000369dc2245c95669c5a7540d075ad7d12a2bb44",  # noqa: E501
    "Cigarette box/fisheye/0010.bmp": "28c5a1f0658ae6260f6bac262da107b7c96a72c0a27b550932c003152cc21765",  # noqa: E501
    "Cigarette box/fisheye/0011.bmp": "8fc4f5b6b03e8d3428f6ef56cf75d25981e5d2a84dca71d2a08f0e5b482c7ef4",  # noqa: E501
    "Cigarette box/fisheye/0012.bmp": "190d97db6e0c250795484c1dde9f06c5b258f29ccf608c25bdd4aeeb4f6fda66",  # noqa: E501
    "Cigarette box/fisheye/0013.bmp": "0ddcb306b92fbefd02c60a96f222c8e57d7ca6e862b670f1cffe33ee52cfa3f0",  # noqa: E501
    "Cigarette box/fisheye/0014.bmp": "41ab5378b55afb5349d09062528353f0c22951eb44c28f759ed6d2ad97720379",  # noqa: E501
    "Cigarette box/fisheye/0015.bmp": "227df681faf8eed6ad6834c0390fc833e5d6f0a11e98cc4e8861710c4a4e316f",  # noqa: E501
    "Cigarette box/fisheye/0016.bmp": "67badcf738513bd75fac3f7d0c59a3f1e171bf7c613dec13b6c10f2fce253caf",  # noqa: E501
    "Cigarette box/fisheye/0017.bmp": "3ee70ace06eca85fcb3169ed615f2136191d08e9af53a7fd6c71d7120dae4498",  # noqa: E501
    "Cigarette box/fisheye/0018.bmp": "88e5201dbbb6e6976c9d3b2fa0701d8178831232a85b1d53636c3558866c8ce0",  # noqa: E501
    "Cigarette box/fisheye/0019.bmp": "3e338a08059ba6eef4a7b99439531c3cd73956cc1b3bf12cf3c2f2ff0e5443be",  # noqa: E501
    "Cigarette box/fisheye/0020.bmp": "236d69a612adf43fd76ac62aff6d73147c51c42d3d116ed108a3466b6fe39940",  # noqa: E501
    "fov160to16mm512px.mat": "938e0b484ec57e8a9eddc87b483490c38033a5dcbf33d27cdf00ef61375469f5",
    "Skull/fisheye/0001.bmp": "a75b115ab9a1f0d6b2ace32ae8540de7ef79d45049c31b15de762b9f0f09b883",
    "Skull/fisheye/0002.bmp": "cb1d7b13e8892a4b7f839741fbf45928b954d62c08d1b313194d52017a6a09e6",
    "Skull/fisheye/0003.bmp": "0c8d25a0951c80ea33be380ccffe999dd8dc78b609a5de9aa18ef12637250219",
    "Skull/fisheye/0004.bmp": "2c7600c54c17bc2fc42007dd6a9f99bdf1cc54c47199949a9d9a58bed8ded0d9",
    "Skull/fisheye/0005.bmp": "dc4eb9c0d6678e936a6e57e3d9726817952cb5c161494d3c1b80bc6553e54eae",
    "Skull/fisheye/0006.bmp": "2e15152c7d2f8b1b62d7876e5f5d127c64ba16ada6c79085d4b037479f076698",
    "Skull/fisheye/0007.bmp": "262881de5a2bb8a6172090575c9a436bc3b937d86dc7e0f0dd4013afa7219036",
    "Skull/fisheye/0008.bmp": "300c3db3b776dde1bc17dfb0406c9d8283d3da71f33c358b0d236bcf028cac58",
    "Skull/fisheye/0009.bmp": "94f6df544ac869dc9cd1dc43b019f27a36a511e06ee3a735d5cecf97d565a2d3",
    "Skull/fisheye/0010.bmp": "0f1b89a07aa75a091a6555a33db07569867b7ba6f8558b1aa7e161c441db6451",
    "Skull/fisheye/0011.bmp": "0b2215bf9c5b8cb92af4d28e03cd108ec8e907618db803d83755c44e39bcdb05",
    "Skull/fisheye/0012.bmp": "39b56c814c5627b100c9c4e395bac6d1024865042ee23e52710e6909072208d6",
    "Skull/fisheye/0013.bmp": "481c526ed2d624c0be35f08ddd10f834eba5b15ebd3b9047d6348d856c55b3ac",
    "Skull/fisheye/0014.bmp": "95aa81af947a9c1c7c0c4756da67b86bed5d975a1f4f65e3ee13f01ff0a0f9db",
    "Skull/fisheye/0015.bmp": "b2a5f5c1467c532b5c9d545a52cc8fa105f02aa0a7a1a469b664f221898d7f76",
    "Skull/fisheye/0016.bmp": "d115dd1d4b92d8e6d1914d4a813e946770d3a622743150b8d7af3af4f70208e5",
    "Skull/fisheye/0017.bmp": "ef0f704b90b16e0704ab1364fdcbf8c1ea2a647f1e90613330cddea57c9cb8da",
    "Skull/fisheye/0018.bmp": "3c7cddfab9c0dfd175aacf9026b8576255db2e4002fecf1ab887ceacf2b1f7fd",
    "Skull/fisheye/0019.bmp": "9331d78d0c535c2ae7604bdc0c12746c92161d8b8b583231c4f78e240fcd0f04",
    "Skull/fisheye/0020.bmp": "efe0f5429aab8ebd3315095047ed18cc92889b09737e305edcecf0a520a4bec2",
    "Teddy/fisheye/0001.bmp": "1e75af1337eceae4d90d0ca1d93a33aa73f86b39fd0ace1265cb1119c5fbc2d2",
    "Teddy/fisheye/0002.bmp": "2ed86a2b6d25f2d80c4a75b2dbeb17857a05f93c4e879fac3f52bff7993ee3f5",
    "Teddy/fisheye/0003.bmp": "94cd2951a0cc77daa33576c1c98f814d08223f6bab76aad795236ee002279356",
    "Teddy/fisheye/0004.bmp": "8e977a158d7a3fd842a2ac9afb83f254571ac8b4648aa7019514b6e20298dc56",
    "Teddy/fisheye/0005.bmp": "04b93fb7acfc488ec87b6c18670978ff55bc40ce7a32357d38eda9b2593b9b5f",
    "Teddy/fisheye/0006.bmp": "0c32c37391a4c4e7911cc5fccc1d4d1798a89c90c2338086584eab1320c6c0b6",
    "Teddy/fisheye/0007.bmp": "eb40f8bad0dd3bfd246397f357304d09a67211e6ef5b6618056fb2619b48413b",
    "Teddy/fisheye/0008.bmp": "3f62c79e721d445dc3e94c83e42370eaaad5670877452ccee615f646e5e00604",
    "Teddy/fisheye/0009.bmp": "10d25449a571a3a2b640c0b8345d9f372971b38a78340bc47c643491a73d20e6",
    "Teddy/fisheye/0010.bmp": "98feca4f326010f4cc9b27ee214758e818945836a41ff0428688424bc3653cda",
    "Teddy/fisheye/0011.bmp": "7e3e0ea271d2ded7a0a1e46883ae0e4720ead238f1246225be1367d2503e571f",
    "Teddy/fisheye/0012.bmp": "0b6c177b387e6b5577028ac06c57da8f87073095f525d70d5dcf2aff56d940f7",
    "Teddy/fisheye/0013.bmp": "883af52decd34553c2e82ab21e7c77e14c2668a150d936536447207e70597c35",
    "Teddy/fisheye/0014.bmp": "cd9ea6910f33af3d3d0d18a9a3cb202251154a99484dd08eb6c55b6e9990d860",
    "Teddy/fisheye/0015.bmp": "204f903942ca627b9c0a0634e6df65aff6ad31b577e4015108544dbb76913ef1",
    "Teddy/fisheye/0016.bmp": "bdbd4126140be1633b70123a40bb504d3a5d8b649366b9baeb924866f692711d",
    "Teddy/fisheye/0017.bmp": "1cd10d270750ea8d92036755eb614b8fd14cfd4c2967a6bf32de9eb9b96ab618",
    "Teddy/fisheye/0018.bmp": "0f90b3ef044e826bcad9d51a13044c965be89a4080fe8b4b929efc68ba891064",
    "Teddy/fisheye/0019.bmp": "b3072b20c71de41be970c06d45b8b18417cfd725dcc804b3ab287f60161a286b",
    "Teddy/fisheye/0020.bmp": "5d089753f8bcfa66f3de72ac856ccbe1233d7ccc1cb11868422551eb24afe349",
}

COLUMNS = [
    "sequence",
    "run",
    "model",
    "f found px",
    "f vs reference",
    "k1",
    "registered",
    "points",
    "reprojection px (median)",
    "cost fisheye / other px^2",
    "poses vs reference: rotation / translation deg / centres % of path",
    "s (CPU s)",
]


def _model(r: dict[str, Any]) -> str:
    """The lens the command chose, from its notes."""
    if any("kept (the fisheye)" in n for n in r.get("notes", [])):
        return "equidistant fisheye (KB k1)"
    return "SIMPLE_RADIAL"


def _costs(r: dict[str, Any]) -> str:
    """The two costs of the fisheye tried, from the note (after only)."""
    for n in r.get("notes", []):
        got = re.findall(r"(\d+) px\^2", n)
        if "the fisheye tried" in n and len(got) >= 2:
            return f"{got[0]} / {got[1]}"
    return "-"


def _cached(folder: Path, name: str, w: float) -> dict[str, Any] | None:
    """A cached pycolmap run (``check_sfm_fisheye.py``'s), its camera's f and k."""
    path = folder / name
    if not path.exists():
        return None
    r = json.loads(path.read_text())
    r["R"], r["t"] = np.asarray(r["R"], float), np.asarray(r["t"], float)
    r["f0"] = 0.45 * w
    if "camera" in r:
        r["f"], r["k1"] = r["camera"][0], r["camera"][3]
    return r


def reference_spread(folder: Path, frames: list[np.ndarray]) -> list[list[Any]]:
    """C3VD with its working camera, RANSAC seeds 1-3 against seed 0 (in-process)."""
    from imageform.geometry import field_of_view_mask, reconstruct_sequence
    from imageform.io import read_camera

    cam = read_camera(folder / "given.toml").camera
    mask = field_of_view_mask(frames)
    recs = [
        reconstruct_sequence(
            frames, cam.K, cam.distortion, masks=mask, contrast_threshold=0.01, rng=seed
        )
        for seed in range(4)
    ]
    rows = []
    for seed in (1, 2, 3):
        rot, tra, rms = agreement(recs[seed].R, recs[seed].t, recs[0].R, recs[0].t)
        r = recs[seed]
        rows.append(
            [
                "c3vd",
                f"reference spread: the working camera, seed {seed} against seed 0",
                "the working camera (KB k1-k4)",
                f"{float(cam.K[0, 0]):.1f}",
                "+0.0 %",
                "-",
                f"{int(r.registered.sum())}/{len(frames)}",
                f"{r.points.shape[0]}",
                f"{float(np.median(r.residuals_px)):.2f}",
                "-",
                f"{rot:.2f} / {tra:.2f} / {rms:.2f}",
                "-",
            ]
        )
    return rows


def prepare_held(name: str, mirrors: Path, data: Path) -> Path:
    """The held-out sequence's frames as PNG (checked against the frozen SHA-256) and its
    camera file (the equidistant lens of the repository's map)."""
    import hashlib
    import subprocess

    import cv2

    from imageform.geometry import Camera, KannalaBrandt
    from imageform.io import write_camera

    git = mirrors / HELD_REPO.replace("/", "+") / "repo"
    folder = data / name
    (folder / "frames").mkdir(parents=True, exist_ok=True)
    paths = sorted(p for p in HELD_SHA256 if p.startswith(HELD[name] + "/fisheye/"))
    paths.append("fov160to16mm512px.mat")
    for path in paths:
        blob = subprocess.run(
            ["git", f"--git-dir={git}", "show", f"{HELD_COMMIT}:{path}"],
            capture_output=True,
            check=True,
        ).stdout
        if hashlib.sha256(blob).hexdigest() != HELD_SHA256[path]:
            raise SystemExit(f"{path}: not the frozen file (SHA-256 differs)")
        if path.endswith(".bmp"):
            im = cv2.imdecode(np.frombuffer(blob, np.uint8), cv2.IMREAD_COLOR)
            cv2.imwrite(str(folder / "frames" / Path(path).with_suffix(".png").name), im)
    f, cx, cy = HELD_CAMERA
    K = np.array([[f, 0, cx], [0, f, cy], [0, 0, 1.0]])
    cam = Camera(K, image_size=(512, 512), distortion=KannalaBrandt())
    write_camera(folder / "given.toml", cam)
    return folder


def sequence(
    name: str, data: Path, before: Path, mirrors: Path | None = None
) -> tuple[str, list[list[Any]], list[Any]]:
    endo = name.startswith("colon") or name in ("c3vd", *HELD)
    if name in HELD:
        assert mirrors is not None
        folder = prepare_held(name, mirrors, data)
    else:
        folder = prepare_c3vd(data) if name == "c3vd" else data / name
    frames = read_frames(folder)
    n = len(frames)
    h, w = frames[0].shape[:2]
    print(f"  {name}: {n} frames {w} x {h}", file=sys.stderr)
    runs: list[tuple[str, str, dict[str, Any]]] = []
    b = run_cli(folder, endo, before)
    runs.append(("imageform CLI before (--before)", _model(b), b))
    a = run_cli(folder, endo, ROOT / "src")
    runs.append(("imageform CLI after (this checkout)", _model(a), a))
    ref_label = "the run before"
    if name in FISHEYE:
        for file, model in (
            ("fisheye-pycolmap.json", "SIMPLE_RADIAL_FISHEYE"),
            ("selfcal.json", "RADIAL_FISHEYE"),
        ):
            r = _cached(folder, file, w)
            if r is not None:
                runs.append(("pycolmap, self-calibrated (cached)", model, r))
        if name == "c3vd":
            g = run_cli(folder, endo, ROOT / "src", folder / "given.toml")
            runs.append(("imageform CLI, --camera", "the working camera (KB k1-k4)", g))
            ref_label = "imageform with the working camera (--camera)"
        else:
            ref_label = "pycolmap's RADIAL_FISHEYE self-calibration"
    if name in HELD:
        g = run_cli(folder, endo, ROOT / "src", folder / "given.toml")
        runs.append(("imageform CLI, --camera", "the repository's map: equidistant", g))
        ref_label = "imageform with the camera of the repository's map (--camera)"
    ref = runs[-1][2] if name in (*FISHEYE, *HELD) else runs[0][2]
    f_ref = ref.get("f")
    rows = []
    for label, model, r in runs:
        ok = r.get("reg", 0) > 0 and "R" in r
        if ok and r is not ref:
            rot, tra, rms = agreement(r["R"], r["t"], ref["R"], ref["t"])
            vs = f"{rot:.2f} / {tra:.2f} / {rms:.2f}"
        else:
            vs = "reference" if ok else "-"
        f = r.get("f") if ok else None
        k1 = r.get("k1") if ok else None
        cpu = f" ({r['cpu']:.1f})" if "cpu" in r else ""
        reproj = r.get("reproj")
        rows.append(
            [
                name,
                label,
                model,
                f"{f:.1f}" if f is not None else "-",
                f"{100 * (f / f_ref - 1):+.1f} %" if f is not None and f_ref else "-",
                f"{k1:+.4f}" if k1 is not None else "-",
                f"{r.get('reg', 0)}/{n}",
                f"{r['points']}" if isinstance(r.get("points"), int) else "-",
                f"{reproj:.2f}" if ok and reproj is not None else "-",
                _costs(r),
                vs,
                f"{r['time']:.1f}{cpu}" if "time" in r else "-",
            ]
        )
    if name == "c3vd":
        rows += reference_spread(folder, frames)
    info = f"{name}: {n} frames, {w} x {h} px; f and poses against {ref_label}"
    notes = [(f"{name}, {label}", ln) for label, _, r in runs[:2] for ln in r.get("notes", [])]
    return info, rows, notes


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", type=Path, required=True)
    ap.add_argument("--before", type=Path, required=True, help="src folder of the code before")
    ap.add_argument("--only", nargs="+", default=None)
    ap.add_argument("--held-out", action="store_true", help="the frozen held-out sequences")
    ap.add_argument("--mirrors", type=Path, default=Path("/work/.mirror"))
    args = ap.parse_args()
    import pycolmap

    pool = list(HELD) if args.held_out else FISHEYE + OTHERS
    names = [k for k in pool if not args.only or k in args.only]
    print(header("The fisheye chosen by a robust cost on common tracks"))
    if args.held_out:
        print(f"Held out: {HELD_REPO} at {HELD_COMMIT[:7]}, SHA-256 checked:\n")
        print("\n".join(f"- `{p}` `{h}`" for p, h in HELD_SHA256.items()) + "\n")
    load = " / ".join(Path("/proc/loadavg").read_text().split()[:3])
    print(f"load average: {load} (a shared machine); pycolmap {pycolmap.__version__}\n")
    infos, rows, notes = [], [], []
    for name in names:
        info, r, nt = sequence(name, args.data, args.before, args.mirrors)
        infos.append(f"- {info}")
        rows += r
        notes += nt
    print("\n".join(infos) + "\n")
    print(markdown_table(COLUMNS, rows))
    print("\nEvery note line about the camera `imageform reconstruct` printed:\n")
    keys = ("no camera file", "ran off", "fisheye")
    said = [(run, ln) for run, ln in notes if any(k in ln for k in keys)]
    print("\n".join(f"- {run}: `{line}`" for run, line in said) or "- none")


if __name__ == "__main__":
    main()
