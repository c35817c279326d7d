"""Reading a lab set for ``imageform characterize``: lab.toml, folders, photographs, frames.

Used by :mod:`imageform.workflows.characterize`.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from imageform._files import RAW_SUFFIXES as _RAW_SUFFIXES
from imageform.errors import InvalidInputError

#: The optional description of the lab set inside the folder.
LAB_MANIFEST = "lab.toml"
_IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".npy")
_MANIFEST_KEYS: dict[str, tuple[str, ...]] = {
    "camera": (
        "name",
        "cfa",
        "black_level_dn",
        "white_level_dn",
        "bit_depth",
        "pixel_pitch_um",
        "f_number",
    ),
    "checkerboard": (
        "board",
        "inner_corners",
        "square",
        "square_mm",
        "marker",
        "dictionary",
        "folder",
        "images",
        "encoding",
    ),
    "colorchecker": (
        "illuminant",
        "transfer",
        "encoding",
        "image",
        "developed",
        "processing",
        "corners_px",
        "patch_centers_px",
    ),
    "edge": (
        "transfer",
        "encoding",
        "min_angle",
        "max_angle",
        "image",
        "angle_deg",
        "white_balance",
    ),
    "flats": ("photons_per_s", "fit_fraction", "wavelength_nm"),
    "emva": (
        "manifest",
        "flats",
        "darks",
        "wavelength_nm",
        "channel",
        "exposures",
        "frames",
        "frame_shape",
        "fit_fraction",
    ),
    "truth": (),  # any key: the true values of a simulated camera (shown in the report)
}
#: Renamed keys of lab.toml (issue 30: one spelling, American ``center``), (table, old) -> new:
#: an old key is still read, with one warning naming its new one.
_RENAMED_MANIFEST_KEYS = {("colorchecker", "patch_centres_px"): "patch_centers_px"}
#: Top-level keys of lab.toml (render_lab_set writes them).
_MANIFEST_TOP = ("format", "version", "camera", "camera_file", "seed")
_FRAME_NAME = re.compile(r"^(?:(?:flat|dark)s?_)?([0-9][0-9.eE+-]*)_([0-9]+)$")
_NEUTRALS = (18, 19, 20, 21, 22)  # white 9.5 ... neutral 3.5 (black 2 left out: noisy)


# ---------------------------------------------------------------- the lab set


def _manifest(folder: Path) -> dict[str, Any]:
    import tomllib

    path = folder / LAB_MANIFEST
    if not path.is_file():
        return {}
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise InvalidInputError(f"{path}: cannot read the lab description ({msg})"[:200]) from None
    fmt = doc.get("format", "imageform-lab")
    if fmt != "imageform-lab":
        raise InvalidInputError(f'{path}: expected format = "imageform-lab", got {fmt!r}'[:200])
    for section, body in doc.items():
        if section in _MANIFEST_TOP and not isinstance(body, dict):
            continue
        if section not in _MANIFEST_KEYS:
            raise InvalidInputError(
                f"{path}: unknown table [{section}]; valid: {', '.join(_MANIFEST_KEYS)}"
            )
        if not isinstance(body, dict):
            raise InvalidInputError(f"{path}: expected [{section}] as a table")
        if section == "truth":
            continue
        _rename_keys(path, section, body)
        unknown = sorted(set(body) - set(_MANIFEST_KEYS[section]))
        if unknown:
            raise InvalidInputError(
                f"{path}: unknown key(s) {', '.join(unknown)} in [{section}]; valid: "
                f"{', '.join(_MANIFEST_KEYS[section])}"[:200]
            )
    return doc


def _rename_keys(path: Path, section: str, body: dict[str, Any]) -> None:
    """Rename the old keys of ``[section]`` (:data:`_RENAMED_MANIFEST_KEYS`) in place, warning."""
    import warnings

    from imageform._deprecate import REMOVED_IN
    from imageform.errors import ImageformWarning

    for (table, old), new in _RENAMED_MANIFEST_KEYS.items():
        if table != section or old not in body:
            continue
        if new in body:
            raise InvalidInputError(
                f"{path}: give [{section}] {new} or its deprecated spelling {old}, not both"
            )
        warnings.warn(
            f"{path}: [{section}] {old} is deprecated and will be removed in imageform "
            f"{REMOVED_IN}; write {new}",
            ImageformWarning,
            stacklevel=4,
        )
        body[new] = body.pop(old)


def _get(doc: Mapping[str, Any], section: str, key: str, kind: type, default: Any) -> Any:
    """``doc[section][key]`` (or its alias: ``encoding`` for ``transfer``), or default.

    The value is checked to be ``kind`` (int accepted for float).
    """
    body = doc.get(section, {})
    if not isinstance(body, dict):  # lab.toml's top-level camera = "camera.toml"
        body = {}
    alias = {"transfer": "encoding"}.get(key)
    value = body.get(key, body.get(alias, default) if alias else default)
    if value is None or value is default:
        return value
    ok = (
        isinstance(value, int | float) and not isinstance(value, bool)
        if kind is float
        else isinstance(value, kind) and not (kind is int and isinstance(value, bool))
    )
    if not ok:
        raise InvalidInputError(
            f"{LAB_MANIFEST}: expected [{section}] {key} as "
            f"{'a number' if kind in (int, float) else 'text'}, got {value!r}"[:200]
        )
    return float(value) if kind is float else value


def _files(folder: Path, *, raw: bool = True) -> list[Path]:
    suffixes = _IMAGE_SUFFIXES + (_RAW_SUFFIXES if raw else ())
    return sorted(
        p
        for p in folder.iterdir()
        if p.is_file() and not p.name.startswith(".") and p.suffix.lower() in suffixes
    )


def _images(folder: Path) -> list[Path]:
    """Return the images (raw ones included) of a part's folder; refuse an empty one."""
    files = _files(folder)
    if not files:
        raise InvalidInputError(f"{folder} holds no image")
    return files


def _transfer(doc: Mapping[str, Any], table: str) -> str:
    """Return lab.toml's ``[table] transfer`` (``srgb`` by default, or ``linear``)."""
    transfer = str(_get(doc, table, "transfer", str, "srgb"))
    if transfer not in ("srgb", "linear"):
        raise InvalidInputError(f"{LAB_MANIFEST}: expected [{table}] transfer srgb or linear")
    return transfer


def _subfolder(root: Path, names: tuple[str, ...]) -> Path | None:
    for n in names:
        if (root / n).is_dir():
            return root / n
    return None


# ---------------------------------------------------------------- image reading


@dataclass(frozen=True)
class _Image:
    """One photograph: its linear RGB, raw mosaic and encoded pixels, and its name.

    ``rgb`` linear floats (H, W, 3) or None, ``mosaic`` (raw DN floats, black subtracted,
    scaled to 1 at white) with its ``cfa``, ``encoded`` (H, W, 3) floats in [0, 1] as stored
    (developed images), and its name.
    """

    name: str
    encoded: Any = None
    linear: Any = None
    mosaic: Any = None
    cfa: str | None = None
    camera: Any = None  # linear camera RGB (H, W, 3): demosaiced raw, not white-balanced
    grey: bool = False  # a one-channel photograph (its three channels are one)


def _camera_cfa(doc: Mapping[str, Any]) -> str | None:
    cfa = _get(doc, "camera", "cfa", str, None)
    if cfa is None:
        return None
    from imageform.sensor.cfa import cfa_pattern

    try:
        return str(cfa_pattern(cfa))
    except Exception as exc:
        raise InvalidInputError(f"{LAB_MANIFEST}: [camera] cfa: {exc}"[:200]) from None


def _read_photo(
    path: Path, doc: Mapping[str, Any], transfer: str, max_pixels: int | None, black: float | None
) -> _Image:
    """Read a photograph: a raw file, a grey raw mosaic or a developed image.

    A grey raw mosaic is read with [camera] cfa, a developed image decoded with ``transfer``.
    """
    import numpy as np

    from imageform.io import read_image

    if path.suffix.lower() in _RAW_SUFFIXES:
        from imageform.io import read_raw

        r = read_raw(path, max_pixels=max_pixels)
        mosaic = np.asarray(r.mosaic, dtype=np.float64)
        if r.cfa_pattern is None:  # a monochrome or linear (demosaiced) raw: no mosaic
            from imageform.color import linear_to_srgb

            blk = np.asarray(r.black_level, dtype=np.float64)
            lin = (mosaic - (blk if mosaic.ndim == 3 else blk[0])) / (r.white_level - blk)
            if mosaic.ndim == 3:  # camera RGB, demosaiced (by the camera or by LibRaw)
                return _Image(path.name, linear=lin, camera=lin)
            lin = np.repeat(lin[..., None], 3, axis=-1)  # monochrome: one channel three times
            enc = np.asarray(linear_to_srgb(np.clip(lin, 0.0, 1.0)))
            return _Image(path.name, encoded=enc, linear=lin, grey=True)
        blk = np.asarray(r.black_level, dtype=np.float64).reshape(2, 2)  # the 2x2 tile's
        h, w = mosaic.shape
        blk_full = np.tile(blk, (h // 2 + 1, w // 2 + 1))[:h, :w]
        span = float(r.white_level) - float(np.mean(blk))
        return _Image(path.name, mosaic=(mosaic - blk_full) / span, cfa=r.cfa_pattern)
    img = read_image(path, alpha="drop", max_pixels=max_pixels)
    cfa = _camera_cfa(doc)
    if img.shape[-1] == 1 and cfa is not None:
        bits = _get(doc, "camera", "bit_depth", int, None)
        scale = {np.dtype(np.uint8): 255.0, np.dtype(np.uint16): 65535.0}.get(img.dtype, 1.0)
        white = _get(doc, "camera", "white_level_dn", float, None)
        if white is None:
            white = float(2**bits - 1) if bits is not None else scale
        b = _get(doc, "camera", "black_level_dn", float, None)
        b = b if b is not None else (black if black is not None else 0.0)
        m = (img[..., 0].astype(np.float64) - b) / (white - b)
        return _Image(path.name, mosaic=m, cfa=cfa)
    arr = img[..., :3] if img.shape[-1] >= 3 else np.repeat(img[..., :1], 3, axis=-1)
    if arr.dtype.kind == "f":
        enc = np.asarray(arr, dtype=np.float64)
        linear_input = True
    else:
        scale = 65535.0 if arr.dtype == np.uint16 else 255.0
        enc = arr.astype(np.float64) / scale
        linear_input = False
    if transfer == "linear" or linear_input:
        lin = enc
        from imageform.color import linear_to_srgb

        enc = np.asarray(linear_to_srgb(np.clip(lin, 0.0, 1.0)))
    else:
        from imageform.color import srgb_to_linear

        lin = np.asarray(srgb_to_linear(enc))
    return _Image(path.name, encoded=enc, linear=lin, grey=img.shape[-1] == 1)


def _demosaiced(mosaic: Any, cfa: str) -> Any:
    import numpy as np

    from imageform.sensor import demosaic

    h, w = (mosaic.shape[0] // 2) * 2, (mosaic.shape[1] // 2) * 2
    return np.asarray(demosaic(np.clip(mosaic[:h, :w], 0.0, 1.0), cfa, method="bilinear"))


def _grey(im: _Image) -> Any:
    import numpy as np

    if im.mosaic is not None:
        assert im.cfa is not None
        rgb = _demosaiced(im.mosaic, im.cfa)
        return rgb.mean(axis=-1)
    if im.encoded is None and im.camera is not None:  # a linear raw: its camera RGB
        return np.asarray(im.camera).mean(axis=-1)
    assert im.encoded is not None
    return np.asarray(im.encoded).mean(axis=-1)


def _frames(folder: Path, kind: str) -> dict[float, list[Path]]:
    out: dict[float, list[tuple[int, Path]]] = {}
    for p in _files(folder):
        m = _FRAME_NAME.match(p.stem)
        if m is None:
            continue
        try:
            t = float(m.group(1))
        except ValueError:
            continue
        out.setdefault(t, []).append((int(m.group(2)), p))
    if not out:
        raise InvalidInputError(
            f"{folder}: no {kind} frames named {kind}_<time>_<n>.<ext> or <time>_<n>.<ext> "
            "(time in seconds)"
        )
    return {t: [p for _, p in sorted(v)] for t, v in out.items()}


def _frame(path: Path, doc: Mapping[str, Any], max_pixels: int | None) -> tuple[Any, str | None]:
    """Read a frame's digital numbers (2-D floats) and its CFA (None: grey)."""
    import numpy as np

    from imageform.io import read_image

    if path.suffix.lower() in _RAW_SUFFIXES:
        from imageform.io import read_raw

        r = read_raw(path, max_pixels=max_pixels)
        if r.mosaic.ndim == 3:
            raise InvalidInputError(
                f"{path.name}: a linear (demosaiced) raw holds no photosite values; EMVA 1288 "
                "needs the sensor's own frames"
            )
        return np.asarray(r.mosaic, dtype=np.float64), r.cfa_pattern
    img = read_image(path, alpha="drop", max_pixels=max_pixels)
    if img.shape[-1] != 1:
        raise InvalidInputError(
            f"{path.name}: expected a grey frame of raw digital numbers, got {img.shape[-1]} "
            "channels"
        )
    if _get(doc, "emva", "channel", str, None) is not None:
        return np.asarray(img[..., 0], dtype=np.float64), None  # one channel's plane already
    return np.asarray(img[..., 0], dtype=np.float64), _camera_cfa(doc)


def _plane(frame: Any, cfa: str | None) -> tuple[Any, str]:
    if cfa is None:
        return frame, "all"
    k = cfa.index("G")
    dy, dx = divmod(k, 2)
    return frame[dy::2, dx::2], f"G at ({dy}, {dx}) of {cfa}"


def _entries(
    root: Path, flats_dir: Path, darks_dir: Path, doc: Mapping[str, Any]
) -> list[tuple[float, float | None, list[Path], list[Path]]]:
    """Each exposure: (time, photons or None, flat files, dark files).

    From an EMVA manifest (``emva.toml`` in FOLDER, or ``[emva] manifest``) or else the file
    names.
    """
    from imageform.workflows.emva import MANIFEST
    from imageform.workflows.emva import _manifest as emva_manifest

    name = _get(doc, "emva", "manifest", str, MANIFEST)
    if (root / name).is_file():
        if name != MANIFEST:
            raise InvalidInputError(
                f"{LAB_MANIFEST}: [emva] manifest must be {MANIFEST} in FOLDER, got {name!r}"
            )
        return sorted(emva_manifest(root), key=lambda e: e[0])
    flats = _frames(flats_dir, "flat")
    darks = _frames(darks_dir, "dark")
    lonely = [t for t in sorted(flats) if t not in darks]
    if lonely:
        raise InvalidInputError(
            f"{darks_dir}: no dark frames for the flats' exposure time {lonely[0]:g} s (each "
            "time needs both)"
        )
    return [(t, None, flats[t], darks[t]) for t in sorted(flats)]


def _processing(doc: Mapping[str, Any]) -> str:
    """Return lab.toml's ``[colorchecker] processing``: ``fixed`` (default) or ``automatic``.

    ``automatic``: the camera white-balances and colour-corrects each scene itself (auto
    white balance), so the twin's ``[color]`` gets no fixed ``white_balance`` or ``ccm``
    (the simulated scene's own processing balances it); the measured ones are reported.
    """
    value = str(_get(doc, "colorchecker", "processing", str, "fixed"))
    if value not in ("fixed", "automatic"):
        raise InvalidInputError(
            f"{LAB_MANIFEST}: expected [colorchecker] processing fixed or automatic, got {value!r}"[
                :200
            ]
        )
    return value
