"""``imageform characterize``: measure a camera as imaging labs do.

From one folder of photographs of standard targets, write one camera file plus a
characterisation report.

The folder (every part optional; what is missing is reported as not measured, an error only
when nothing can be measured)::

    FOLDER/
      lab.toml         optional: what the lab knows (board, square size, light, CFA, ...)
      checkerboard/    (or charuco/)   views of a checkerboard        -> intrinsics, distortion
      colorchecker/    (or chart/)     a ColorChecker photograph      -> white balance, CCM,
                                       (raw, developed, or both)         sensitivities, ΔE00
      edge/            (or sfr/)       a slanted-edge target           -> MTF per channel,
                                       (dark squares turned 2-10 deg)     MTF50, Gaussian sigma
      flats/, darks/                   frame stacks, files named       -> EMVA 1288: gain, read
                                       <kind>_<time>_<n>.<ext> or         noise, dark current,
                                       <time>_<n>.<ext> (time in s)       DSNU, PRNU, full well

Images are PNG, JPEG, TIFF or ``.npy``; raw files (``.dng``, ``.cr2``, ``.nef``, ...) are
read with :func:`imageform.io.read_raw`. A grey (one-channel) image in checkerboard/, edge/
or colorchecker/ is a raw mosaic when ``lab.toml`` gives ``[camera] cfa``. Frames in flats/
and darks/ are raw digital numbers as stored; with a CFA (a raw file or ``[camera] cfa``)
the first green photosite of each 2x2 tile is measured.

``lab.toml`` (every key optional, unknown keys refused)::

    [camera]
    name = "bench camera"
    cfa = "RGGB"              # the mosaic of grey raw images and frames
    black_level_dn = 64.0     # of grey raw images (default: the darks' mean, else 0)
    white_level_dn = 4095.0   # of grey raw images (default: the largest code of the depth)
    bit_depth = 12
    pixel_pitch_um = 3.45
    f_number = 4.0

    [checkerboard]
    board = "9x6"             # inner corners (or "charuco:7x5" with marker = "15mm")
    square = "20mm"
    marker = "15mm"
    dictionary = "6x6_250"

    [colorchecker]
    illuminant = "D65"        # the light on the chart (CIE name): for the sensitivities
    transfer = "srgb"         # encoding of developed photographs: srgb or linear
    processing = "fixed"      # or "automatic" (auto white balance): no fixed gains or ccm

    [edge]
    transfer = "srgb"         # encoding of developed edge photographs
    min_angle = 2.0
    max_angle = 10.0

    [flats]
    photons_per_s = 1.2e5     # mean photons per pixel per second on the flats (gives QE)
    fit_fraction = 0.7

The camera file (``camera.toml``) gets what was measured: ``[image]``, ``[intrinsics]``,
``[distortion]`` and ``[std]`` from the checkerboard; ``[optics]`` (``model = "gaussian"``,
the fitted ``gaussian_sigma_px`` and ``mtf50_cy_per_px``) from the edge; ``[sensor]`` from
EMVA 1288; ``[color]`` (``ccm``, ``white_balance``, ``illuminant``, the estimated
``[color.sensitivity]``) from the chart. The report (``report.html``, in the simulate
report's style, figures embedded) and ``metrics.json`` hold every value with its
uncertainty. docs/characterize.md walks through it.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from imageform.errors import InvalidInputError
from imageform.workflows._spec import Input, Options, Output, Result, Run, Workflow, option

__all__ = [
    "LAB_MANIFEST",
    "PARTS",
    "WORKFLOWS",
    "CameraCharacterization",
    "CharacterizeOptions",
    "ColorMeasurement",
    "GeometryMeasurement",
    "NoiseMeasurement",
    "SharpnessMeasurement",
    "characterize_camera",
    "relative_qe",
]

#: The optional description of the lab set inside the folder.
LAB_MANIFEST = "lab.toml"
#: Each measurement and the subfolder names it is looked for under (first found wins).
PARTS: Mapping[str, tuple[str, ...]] = {
    "geometry": ("checkerboard", "charuco"),
    "color": ("colorchecker", "chart"),
    "sharpness": ("edge", "sfr"),
    "noise": ("flats", "darks"),
}
_IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".npy")
_RAW_SUFFIXES = (".dng", ".cr2", ".cr3", ".nef", ".arw", ".raf", ".orf", ".rw2", ".pef", ".srw")
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
        "patch_centres_px",
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
#: Top-level keys of lab.toml (render_lab_set writes them).
_MANIFEST_TOP = ("format", "version", "camera", "camera_file", "seed")
_FRAME_NAME = re.compile(r"^(?:(?:flat|dark)s?_)?([0-9][0-9.eE+-]*)_([0-9]+)$")
_NEUTRALS = (18, 19, 20, 21, 22)  # white 9.5 ... neutral 3.5 (black 2 left out: noisy)

Progress = Callable[[str, float], None]


# ---------------------------------------------------------------- results


@dataclass(frozen=True)
class GeometryMeasurement:
    """The checkerboard calibration.

    ``calibration`` (a :class:`~imageform.geometry.CalibrationResult`), the ``views`` used, the
    ``board`` description and the views where no board was found (``missed``).
    """

    calibration: Any
    views: tuple[str, ...]
    board: str
    missed: tuple[str, ...] = ()


@dataclass(frozen=True)
class SharpnessMeasurement:
    """The slanted-edge e-SFR of the image ``image``.

    Per channel MTF50 and MTF10 (cycles/pixel, median over the edges, ``*_std`` their spread),
    the fitted Gaussian PSF ``gaussian_sigma_px`` (the optics' blur, the pixel aperture divided
    out) and the curves (``frequency``, ``sfr`` (n, channels), the median over the edges);
    ``raw`` when it was measured on a raw mosaic (the CFA balanced on the neutral edge: one
    channel ``"raw"``).
    """

    image: str
    channels: tuple[str, ...]
    mtf50: tuple[float, ...]
    mtf50_std: tuple[float, ...]
    mtf10: tuple[float, ...]
    gaussian_sigma_px: float
    gaussian_sigma_std: float
    frequency: Any
    sfr: Any
    angles_deg: tuple[float, ...]
    edges: int
    raw: bool
    cfa: str | None = None
    image_size: tuple[int, int] | None = None

    @property
    def mtf50_main(self) -> float:
        """MTF50 of the green channel (or the only one)."""
        return self.mtf50[self.channels.index("G")] if "G" in self.channels else self.mtf50[0]


@dataclass(frozen=True)
class NoiseMeasurement:
    """EMVA 1288 from the flats and darks.

    ``emva`` (an :class:`~imageform.sensor.EmvaMeasurement`), the standard errors of the gain
    and the read noise, the black level (mean dark at the shortest exposure, DN), the frame
    ``shape``, the ``plane`` measured (``"all"`` or a CFA photosite) and how many exposures.
    """

    emva: Any
    system_gain_std: float
    read_noise_std: float
    black_level_dn: float
    shape: tuple[int, int]
    plane: str
    exposures: int


@dataclass(frozen=True)
class ColorMeasurement:
    """The ColorChecker: patch means, white balance, CCM, colour errors and sensitivities.

    Where it came from (``raw``, ``developed`` file names), the patch means (``camera_rgb``:
    linear raw, black subtracted, scaled to the white level; ``output_rgb``: the developed
    photograph, linear), the ``white_balance`` gains (green 1) and ``ccm`` (3, 3) with linear
    output = (camera RGB x gains) @ ccm, what it maps to (``ccm_to``: ``"camera_output"`` when
    fitted to the camera's own developed photograph, else ``"srgb"``, the chart's D65
    reference), per-patch CIEDE2000 of the camera's rendering against the reference
    (``delta_e00``) and of the fitted model against its target (``fit_delta_e00``), the
    estimated ``sensitivities`` (a :class:`~imageform.spectral.Spectrum`, or None without a raw
    photograph) and their misfit (``sensitivity_rms``), and ``detection`` (the chart found).
    """

    raw: str | None
    developed: str | None
    camera_rgb: Any
    output_rgb: Any
    white_balance: tuple[float, float, float]
    ccm: Any
    ccm_to: str
    illuminant: str
    delta_e00: Any
    fit_delta_e00: Any
    sensitivities: Any
    sensitivity_rms: tuple[float, ...]
    reference_rgb: Any
    detection: Any
    photo: Any = field(default=None, repr=False)
    half_size: bool = False
    cfa: str | None = None


@dataclass(frozen=True)
class CameraCharacterization:
    """What :func:`characterize_camera` measured.

    Attributes
    ----------
    folder : Path
        The lab set.
    image_size : (int, int) or None
        ``(width, height)`` of the checkerboard views (or the other photographs).
    geometry, sharpness, noise, color : measurement or None
        Each part, None when not measured.
    missing : dict
        Why each part that was not measured was not (``{"noise": "no flats/ folder"}``).
    notes : tuple of str
        Warnings met on the way (a view without a board, ...).
    manifest : dict
        The parsed ``lab.toml`` (empty without one).
    tables : dict
        The camera file's measured tables: ``sensor``, ``optics``, ``color`` (plain data).
    """

    folder: Path
    image_size: tuple[int, int] | None
    geometry: GeometryMeasurement | None
    sharpness: SharpnessMeasurement | None
    noise: NoiseMeasurement | None
    color: ColorMeasurement | None
    missing: dict[str, str]
    notes: tuple[str, ...]
    manifest: dict[str, Any]
    tables: dict[str, dict[str, Any]]

    @property
    def raw_cfa(self) -> str | None:
        """The CFA pattern of a raw photograph measured (None: none was raw)."""
        for part in (self.color, self.sharpness):
            cfa = getattr(part, "cfa", None) if part is not None else None
            if cfa:
                return str(cfa)
        return None

    @property
    def measured(self) -> tuple[str, ...]:
        """The parts measured, in the order geometry, sharpness, noise, color."""
        return tuple(
            p for p in ("geometry", "sharpness", "noise", "color") if getattr(self, p) is not None
        )

    def camera_file(self) -> Any:
        """Return the :class:`~imageform.io.CameraFile` of the geometry.

        A camera with the default intrinsics of the image size when no checkerboard was
        measured.
        """
        from imageform.io import CameraFile, Provenance

        cmd = f"imageform characterize {self.folder}"
        if self.geometry is not None:
            cf = CameraFile.from_calibration(
                self.geometry.calibration, images=list(self.geometry.views), command=cmd
            )
            return cf
        from imageform.geometry import Camera

        if self.image_size is None:
            raise InvalidInputError(
                "no image size is known (no checkerboard, edge or chart photograph) for the "
                "camera file"
            )
        w, h = self.image_size
        f = float(max(w, h))
        cam = Camera([[f, 0.0, (w - 1) / 2], [0.0, f, (h - 1) / 2], [0, 0, 1]], image_size=(w, h))
        return CameraFile(cam, provenance=Provenance(command=cmd))

    def summary(self) -> dict[str, Any]:
        """Return the headline numbers (plain data), as ``metrics.json``'s ``summary``."""
        out: dict[str, Any] = {"measured": list(self.measured), "missing": dict(self.missing)}
        g = self.geometry
        if g is not None:
            c = g.calibration
            K, d = c.K, c.distortion
            out["geometry"] = {
                "fx": float(K[0, 0]),
                "fy": float(K[1, 1]),
                "cx": float(K[0, 2]),
                "cy": float(K[1, 2]),
                "k1": float(d.k1),
                "k2": float(d.k2),
                "p1": float(d.p1),
                "p2": float(d.p2),
                "k3": float(d.k3),
                "std": {k: float(v) for k, v in c.std.items()},
                "rms_px": float(c.rms),
                "views_used": len(g.views),
                "views_missed": list(g.missed),
                "board": g.board,
            }
        s = self.sharpness
        if s is not None:
            out["sharpness"] = {
                "image": s.image,
                "raw": s.raw,
                "edges": s.edges,
                "angles_deg": list(s.angles_deg),
                "mtf50_cy_per_px": dict(zip(s.channels, s.mtf50, strict=True)),
                "mtf50_std": dict(zip(s.channels, s.mtf50_std, strict=True)),
                "mtf10_cy_per_px": dict(zip(s.channels, s.mtf10, strict=True)),
                "gaussian_sigma_px": s.gaussian_sigma_px,
                "gaussian_sigma_std": s.gaussian_sigma_std,
            }
        n = self.noise
        if n is not None:
            m = n.emva
            out["noise"] = {
                "system_gain_dn_per_e": m.system_gain,
                "system_gain_std": n.system_gain_std,
                "read_noise_e": m.dark_noise,
                "read_noise_std": n.read_noise_std,
                "read_noise_upper_limit": bool(m.dark_noise_upper_limit),
                "dark_current_e_per_s": m.dark_current,
                "dsnu_e": m.dsnu,
                "prnu_percent": m.prnu,
                "saturation_capacity_e": m.saturation_capacity,
                "saturated": bool(m.saturated),
                "quantum_efficiency": m.quantum_efficiency,
                "snr_max_db": m.snr_max_db,
                "dynamic_range_db": m.dynamic_range_db,
                "black_level_dn": n.black_level_dn,
                "plane": n.plane,
                "exposures": n.exposures,
                "frame_shape": list(n.shape),
            }
        c2 = self.color
        if c2 is not None:
            import numpy as np

            out["color"] = {
                "raw": c2.raw,
                "developed": c2.developed,
                "white_balance": list(c2.white_balance),
                "ccm": np.asarray(c2.ccm).tolist(),
                "ccm_to": c2.ccm_to,
                "illuminant": c2.illuminant,
                "delta_e00_mean": _nanmean(c2.delta_e00),
                "delta_e00_max": _nanmax(c2.delta_e00),
                "delta_e00_per_patch": [float(x) for x in np.asarray(c2.delta_e00)],
                "fit_delta_e00_mean": _nanmean(c2.fit_delta_e00),
                "sensitivities_estimated": c2.sensitivities is not None,
                "sensitivity_relative_rms": list(c2.sensitivity_rms),
            }
        return out


def _nanmean(x: Any) -> float | None:
    import numpy as np

    a = np.asarray(x, dtype=float)
    return float(np.nanmean(a)) if a.size and np.isfinite(a).any() else None


def _nanmax(x: Any) -> float | None:
    import numpy as np

    a = np.asarray(x, dtype=float)
    return float(np.nanmax(a)) if a.size and np.isfinite(a).any() else None


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
        unknown = sorted(set(body) - set(_MANIFEST_KEYS[section]))
        if unknown:
            raise InvalidInputError(
                f"{path}: unknown key(s) {', '.join(unknown)} in [{section}]; valid: "
                f"{', '.join(_MANIFEST_KEYS[section])}"[:200]
            )
    return doc


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


def _superpixel(mosaic: Any, cfa: str) -> Any:
    """Return the 2x2 tiles of a mosaic as half-size camera RGB (the two greens averaged)."""
    import numpy as np

    h, w = (mosaic.shape[0] // 2) * 2, (mosaic.shape[1] // 2) * 2
    m = mosaic[:h, :w]
    out = np.zeros((h // 2, w // 2, 3))
    count = np.zeros(3)
    for k, ch in enumerate(cfa):
        dy, dx = divmod(k, 2)
        c = "RGB".index(ch)
        out[..., c] += m[dy::2, dx::2]
        count[c] += 1
    return out / count


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
    assert im.encoded is not None
    return np.asarray(im.encoded).mean(axis=-1)


# ---------------------------------------------------------------- geometry


def _measure_geometry(
    folder: Path,
    doc: Mapping[str, Any],
    notes: list[str],
    max_pixels: int | None,
    black: float | None,
    progress: Progress | None,
) -> tuple[GeometryMeasurement, tuple[int, int]]:
    from imageform.errors import DegenerateConfigurationError
    from imageform.geometry import calibrate_camera, checkerboard_points, find_checkerboard
    from imageform.workflows.calibration import (
        MIN_VIEWS,
        parse_board,
        parse_charuco,
    )

    files = _images(folder)
    board = _get(doc, "checkerboard", "board", str, None)
    corners_given = doc.get("checkerboard", {}).get("inner_corners")
    if board is None and corners_given is not None:
        if not (
            isinstance(corners_given, list)
            and len(corners_given) == 2
            and all(isinstance(c, int) and not isinstance(c, bool) for c in corners_given)
        ):
            raise InvalidInputError(
                f"{LAB_MANIFEST}: expected [checkerboard] inner_corners as [cols, rows], got "
                f"{corners_given!r}"[:200]
            )
        board = f"{corners_given[0]}x{corners_given[1]}"
    if board is None:
        raise InvalidInputError(
            f'{folder}: the board\'s size is unknown; give [checkerboard] board = "9x6" '
            f"(inner corners) in {LAB_MANIFEST}"
        )
    from imageform._units import parse_length

    square_mm = _get(doc, "checkerboard", "square_mm", float, None)
    square = (
        square_mm
        if square_mm is not None
        else parse_length(
            str(_get(doc, "checkerboard", "square", str, "1")),
            "square",
            default_unit="mm",
            unit="mm",
        )
    )
    charuco = parse_charuco(board)
    shape: tuple[int, int] | None = None
    objs, corners, names, missed = [], [], [], []
    if charuco is not None:
        from imageform.geometry import CharucoBoard, detect_charuco

        marker = _get(doc, "checkerboard", "marker", str, None)
        if marker is None:
            raise InvalidInputError(f"{LAB_MANIFEST}: a ChArUco board needs [checkerboard] marker")
        mk = parse_length(marker, "marker", default_unit="mm", unit="mm")
        dic = str(_get(doc, "checkerboard", "dictionary", str, "6x6_250"))
        cb = CharucoBoard(charuco, square, mk, dic)
    else:
        cols, rows = parse_board(board)
    for i, f in enumerate(files):
        if progress is not None:
            progress("checkerboard", i / len(files))
        grey = _grey(_read_photo(f, doc, "srgb", max_pixels, black))
        if shape is None:
            shape = (int(grey.shape[1]), int(grey.shape[0]))
        elif (grey.shape[1], grey.shape[0]) != shape:
            raise InvalidInputError(
                f"expected the checkerboard views of one size, got {files[0].name} of "
                f"{shape[0]} x {shape[1]} px and {f.name} of {grey.shape[1]} x {grey.shape[0]}"
            )
        if charuco is not None:
            found = detect_charuco(grey, cb)
            if len(found) >= 6:
                objs.append(found.object_points())
                corners.append(found.corners)
                names.append(f.name)
            else:
                missed.append(f.name)
        else:
            det = find_checkerboard(grey, (cols, rows))
            if det.found and det.corners is not None:
                objs.append(checkerboard_points((cols, rows), square))
                corners.append(det.corners)
                names.append(f.name)
            else:
                missed.append(f.name)
    for m in missed:
        notes.append(f"checkerboard: no {board} board found in {m}")
    if len(corners) < MIN_VIEWS:
        raise DegenerateConfigurationError(
            f"found the {board} board in {len(corners)} of {len(files)} views; calibration "
            f"needs at least {MIN_VIEWS}"
        )
    assert shape is not None
    # k3 held at 0: a few views of a board do not determine it (and it trades off with k1)
    cal = calibrate_camera(objs, corners, shape, fix=("k3",))
    return GeometryMeasurement(cal, tuple(names), board, tuple(missed)), shape


# ---------------------------------------------------------------- sharpness


def _pixel_box(f: Any, angle_deg: float) -> Any:
    import numpy as np

    t = math.radians(angle_deg)
    return np.abs(np.sinc(f * math.cos(t)) * np.sinc(f * math.sin(t)))


def _fit_sigma(freq: Any, sfr: Any, angle: float) -> float:
    """Fit the Gaussian PSF sigma (pixels) to a measured SFR, the pixel aperture's MTF included.

    The sigma whose MTF times the pixel aperture's best fits the measured SFR up to Nyquist
    (least squares on the curve where it is above 0.1).
    """
    import numpy as np
    from scipy.optimize import minimize_scalar

    keep = (freq > 0) & (freq <= 0.5) & np.isfinite(sfr)
    f, s = freq[keep], sfr[keep]
    box = _pixel_box(f, angle)
    w = (s > 0.1).astype(float) + 1e-3

    def cost(sigma: float) -> float:
        model = np.exp(-2.0 * np.pi**2 * sigma**2 * f**2) * box
        return float(np.sum(w * (model - s) ** 2))

    r = minimize_scalar(cost, bounds=(0.0, 10.0), method="bounded", options={"xatol": 1e-5})
    return float(r.x)


def _balanced_mosaic(mosaic: Any, cfa: str) -> Any:
    """Return a raw mosaic of a neutral target as one full-resolution grey image.

    Each photosite of the 2x2 tile is mapped affinely onto the greens' levels (dark and light
    parts, from the 5th and 95th percentiles), so that the CFA's pattern vanishes on a grey
    edge.
    """
    import numpy as np

    out = np.array(mosaic, dtype=np.float64)
    ref = [out[dy::2, dx::2] for dy, dx in ((0, 0), (0, 1), (1, 0), (1, 1))]
    greens = [r for r, ch in zip(ref, cfa, strict=True) if ch == "G"]
    g_lo = float(np.mean([np.percentile(g, 5) for g in greens]))
    g_hi = float(np.mean([np.percentile(g, 95) for g in greens]))
    for k in range(4):
        dy, dx = divmod(k, 2)
        site = out[dy::2, dx::2]
        lo, hi = float(np.percentile(site, 5)), float(np.percentile(site, 95))
        if hi - lo > 1e-9:
            out[dy::2, dx::2] = g_lo + (site - lo) * (g_hi - g_lo) / (hi - lo)
    return out


def _common_sfr_grid(results: Sequence[Any], n_ch: int) -> tuple[Any, Any]:
    """Put the edges' SFR curves on one grid: ``(frequency (n,), curves (edges, n, C))``.

    Each edge's grid follows its ROI's length (ROIs of a small image are cut to different
    lengths), so the curves are interpolated (linearly) onto the coarsest grid, up to the
    lowest top frequency of all.
    """
    import numpy as np

    coarse = min(results, key=lambda r: r.frequency.size)
    top = min(float(r.frequency[-1]) for r in results)
    freq = coarse.frequency[coarse.frequency <= top]
    curves = np.stack(
        [
            np.column_stack([np.interp(freq, r.frequency, r.sfr[:, c]) for c in range(n_ch)])
            for r in results
        ]
    )
    return freq, curves


def _measure_sharpness(
    folder: Path, doc: Mapping[str, Any], max_pixels: int | None, black: float | None
) -> SharpnessMeasurement:
    import numpy as np

    from imageform.analysis import find_slanted_edges, slanted_edge_sfr

    files = _images(folder)
    transfer = _transfer(doc, "edge")
    lo = float(_get(doc, "edge", "min_angle", float, 2.0))
    hi = float(_get(doc, "edge", "max_angle", float, 10.0))
    path = files[0]
    im = _read_photo(path, doc, transfer, max_pixels, black)
    if im.mosaic is not None:
        assert im.cfa is not None
        arr = _balanced_mosaic(im.mosaic, im.cfa)
        channels: tuple[str, ...] = ("raw",)
    elif im.grey:
        arr = np.asarray(im.linear)[..., 0]
        channels = ("Y",)
    else:
        arr = np.asarray(im.linear)
        channels = ("R", "G", "B")
    rois = find_slanted_edges(arr, min_angle=lo, max_angle=hi)
    if not rois:
        raise InvalidInputError(
            f"no slanted edge found in {path.name} (dark squares turned {lo:g}-{hi:g} deg on "
            "a light background)"
        )
    results = [slanted_edge_sfr(arr, r.roi) for r in rois]
    n_ch = len(channels)
    freq, curves = _common_sfr_grid(results, n_ch)  # curves: (edges, n, channels)
    mtf50 = np.array([r.mtf50[:n_ch] for r in results])
    mtf10 = np.array([r.mtf10[:n_ch] for r in results])
    angles = tuple(float(abs(r.angle)) for r in results)
    sig = np.array(
        [
            _fit_sigma(r.frequency, r.sfr[:, c], abs(r.angle))  # its own grid
            for r in results
            for c in range(n_ch)
            if channels[c] in ("G", "raw", "Y")
        ]
    )

    def spread(a: Any) -> tuple[float, ...]:
        if a.shape[0] < 2:
            return tuple(float("nan") for _ in range(a.shape[1]))
        return tuple(float(x) for x in np.nanstd(a, axis=0, ddof=1) / math.sqrt(a.shape[0]))

    return SharpnessMeasurement(
        image=path.name,
        channels=channels,
        mtf50=tuple(float(x) for x in np.nanmedian(mtf50, axis=0)),
        mtf50_std=spread(mtf50),
        mtf10=tuple(float(x) for x in np.nanmedian(mtf10, axis=0)),
        gaussian_sigma_px=float(np.median(sig)),
        gaussian_sigma_std=float(np.std(sig, ddof=1) / math.sqrt(sig.size))
        if sig.size > 1
        else float("nan"),
        frequency=freq,
        sfr=np.median(curves, axis=0),
        angles_deg=angles,
        edges=len(results),
        raw=im.mosaic is not None,
        cfa=im.cfa,
        image_size=(int(arr.shape[1]), int(arr.shape[0])),
    )


# ---------------------------------------------------------------- noise


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


def _measure_noise(
    root: Path, flats_dir: Path, darks_dir: Path, doc: Mapping[str, Any], max_pixels: int | None
) -> NoiseMeasurement:
    import numpy as np

    from imageform.sensor import measure_emva

    entries = _entries(root, flats_dir, darks_dir, doc)
    times = [e[0] for e in entries]
    stacks: dict[str, list[Any]] = {"flat": [], "dark": []}
    plane = "all"
    shape: tuple[int, ...] | None = None
    for t, _, fl, dk in entries:
        for kind, paths in (("flat", fl), ("dark", dk)):
            if len(paths) < 2:
                raise InvalidInputError(
                    f"expected at least 2 {kind} frames at {t:g} s, got {len(paths)}"
                )
            planes = []
            for p in paths:
                if not p.is_file():
                    raise InvalidInputError(f"{kind} frame {p} does not exist")
                fr, cfa = _frame(p, doc, max_pixels)
                a, plane = _plane(fr, cfa)
                if shape is None:
                    shape = a.shape
                elif a.shape != shape:
                    raise InvalidInputError(
                        f"expected frames of one size, got {p.name} of {a.shape[1]} x "
                        f"{a.shape[0]} (others {shape[1]} x {shape[0]})"
                    )
                planes.append(a)
            stacks[kind].append(np.stack(planes))
    photons = None
    pps = _get(doc, "flats", "photons_per_s", float, None)
    if all(e[1] is not None for e in entries):
        photons = np.array([float(e[1]) for e in entries])  # type: ignore[arg-type]
    elif pps is not None:
        photons = np.asarray(times) * pps
    ff = float(
        _get(doc, "flats", "fit_fraction", float, None)
        or _get(doc, "emva", "fit_fraction", float, 0.7)
    )
    m = measure_emva(
        stacks["flat"], stacks["dark"], np.asarray(times), photons=photons, fit_fraction=ff
    )
    # standard error of the gain: the slope of var vs mean through the origin (EMVA eq. 9)
    x = (m.mean_dn - m.dark_mean_dn)[: m.fit_points]
    y = (m.var_dn - m.dark_var_dn)[: m.fit_points]
    if x.size > 1 and float(x @ x) > 0:
        resid = y - m.system_gain * x
        k_se = float(np.sqrt(resid @ resid / (x.size - 1) / (x @ x)))
    else:
        k_se = float("nan")
    assert shape is not None
    n_px = float(shape[0] * shape[1])
    # sigma_d = sigma_y.dark / K: relative errors add; the pair variance of N pixels has a
    # relative standard error sqrt(2 / N), so its square root sqrt(1 / (2 N))
    rel = math.hypot(k_se / m.system_gain if m.system_gain else float("nan"), math.sqrt(0.5 / n_px))
    return NoiseMeasurement(
        emva=m,
        system_gain_std=k_se,
        read_noise_std=float(m.dark_noise * rel),
        black_level_dn=float(m.dark_mean_dn[0]),
        shape=(int(shape[0]), int(shape[1])),
        plane=plane,
        exposures=len(times),
    )


# ---------------------------------------------------------------- colour


def _reference_linear_srgb() -> Any:
    """Return the ColorChecker's linear sRGB under D65 (from its reflectances), (24, 3)."""
    import numpy as np

    from imageform.color import xyz_to_linear_srgb
    from imageform.spectral import colorchecker_reflectances, spectrum_to_xyz

    return np.asarray(
        xyz_to_linear_srgb(spectrum_to_xyz(colorchecker_reflectances(), illuminant="D65"))
    )


def _lab(linear_srgb: Any) -> Any:
    import numpy as np

    from imageform.color import linear_srgb_to_xyz, xyz_to_lab

    return np.asarray(xyz_to_lab(linear_srgb_to_xyz(np.asarray(linear_srgb)), white="D65"))


def _delta_e(a: Any, b: Any) -> Any:
    import numpy as np

    from imageform.color import delta_e_ciede2000

    return np.asarray(delta_e_ciede2000(_lab(a), _lab(b)))


def _fit_ccm(src: Any, dst: Any, ok: Any) -> Any:
    """``M`` (3, 3) minimising ``|| src @ M - dst ||`` over the rows ``ok``."""
    import numpy as np

    m, *_ = np.linalg.lstsq(src[ok], dst[ok], rcond=None)
    return m


def _chart_patches(im: _Image, max_size: int) -> tuple[Any, Any, Any]:
    """Find and measure a photograph's ColorChecker.

    Returns (detection, linear patch means (24, 3), the picture detected in (encoded)); a raw
    photograph is measured on its half-size superpixels, black subtracted.
    """
    import warnings

    import numpy as np

    from imageform.analysis import detect_colorchecker, measure_chart_patches
    from imageform.color import linear_to_srgb

    if im.mosaic is not None or im.camera is not None:
        lin = _superpixel(im.mosaic, str(im.cfa)) if im.mosaic is not None else im.camera
        # only to find the chart: grey-world balanced, exposed to a mean of 0.2, encoded
        means = np.maximum(lin.reshape(-1, 3).mean(axis=0), 1e-9)
        shown = np.clip(lin * (0.2 / means), 0.0, 1.0)
        enc = np.asarray(linear_to_srgb(shown))
    else:
        lin, enc = np.asarray(im.linear), np.asarray(im.encoded)
    det = detect_colorchecker(enc, max_size=max_size)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        pat = measure_chart_patches(np.clip(lin, 0.0, None), det, max_std=1.0, saturation=0.999)
    return det, np.asarray(pat.means, dtype=np.float64), enc


def _measure_color(
    folder: Path, doc: Mapping[str, Any], max_pixels: int | None, black: float | None
) -> ColorMeasurement:
    import numpy as np

    from imageform.analysis import estimate_camera_sensitivities

    files = _images(folder)
    transfer = _transfer(doc, "colorchecker")
    light = str(_get(doc, "colorchecker", "illuminant", str, "D65"))
    developed = _get(doc, "colorchecker", "developed", str, None)
    dev_name = Path(developed).name if developed is not None else None
    if developed is not None and not (folder / dev_name).is_file():  # type: ignore[operator]
        raise InvalidInputError(
            f"{LAB_MANIFEST}: [colorchecker] developed = {developed!r}: no such file in {folder}"[
                :200
            ]
        )
    images = []
    for p in files:
        if p.name == dev_name:  # the camera's own developed output (sRGB-encoded)
            images.append(_read_photo(p, doc, "srgb", max_pixels, black))
            continue
        im = _read_photo(p, doc, transfer, max_pixels, black)
        if transfer == "linear" and im.mosaic is None:  # linear RGB of the chart: camera RGB
            im = _Image(im.name, camera=np.asarray(im.linear))
        images.append(im)
    raw = next((i for i in images if i.mosaic is not None or i.camera is not None), None)
    dev = next((i for i in images if i.encoded is not None), None)
    ref = _reference_linear_srgb()
    cam = out = None
    det = photo = None
    if raw is not None:
        det, cam, photo = _chart_patches(raw, 1024)
    if dev is not None:
        det_d, out, photo_d = _chart_patches(dev, 1024)
        det, photo = det_d, photo_d
    assert det is not None
    sens = None
    sens_rms: tuple[float, ...] = ()
    if cam is not None:
        ok = np.all(np.isfinite(cam), axis=1) & np.all(cam < 0.98, axis=1) & np.all(cam > 0, axis=1)
        neutral = [k for k in _NEUTRALS if ok[k]]
        if not neutral:
            raise InvalidInputError(
                f"{raw.name if raw else folder}: no usable neutral patch (all saturated or dark)"
            )
        gains = np.mean(cam[neutral, 1:2] / cam[neutral], axis=0)
        balanced = cam * gains
        if out is not None:
            usable = (
                ok & np.all(np.isfinite(out), axis=1) & np.all((out > 1e-3) & (out < 0.99), axis=1)
            )
            ccm = _fit_ccm(balanced, out, usable)
            ccm_to = "camera_output"
            fit_de = _delta_e(balanced @ ccm, out)
            rendered = out
        else:
            ccm = _fit_ccm(balanced, ref, ok)
            ccm_to = "srgb"
            rendered = balanced @ ccm
            fit_de = _delta_e(rendered, ref)
        try:
            est = estimate_camera_sensitivities(
                np.where(ok[:, None], cam, np.nan)[ok], _patch_subset(ok), light=light
            )
            sens = est.sensitivities
            sens_rms = tuple(float(x) for x in est.relative_rms)
        except Exception as exc:
            raise InvalidInputError(
                f"sensitivities from {raw.name if raw else folder}: {exc}"[:200]
            ) from None
        wb = (float(gains[0]), float(gains[1]), float(gains[2]))
    else:
        assert out is not None
        ok = np.all(np.isfinite(out), axis=1) & np.all((out > 1e-3) & (out < 0.99), axis=1)
        ccm = _fit_ccm(out, ref, ok)
        ccm_to = "srgb"
        wb = (1.0, 1.0, 1.0)
        rendered = out
        fit_de = _delta_e(out @ ccm, ref)
    # the camera's rendering against the chart's reference, exposure matched on the greys
    scale = _exposure_match(rendered, ref)
    de = _delta_e(np.clip(rendered * scale, 0, None), ref)
    return ColorMeasurement(
        raw=raw.name if raw is not None else None,
        developed=dev.name if dev is not None else None,
        camera_rgb=cam,
        output_rgb=out,
        white_balance=wb,
        ccm=np.asarray(ccm),
        ccm_to=ccm_to,
        illuminant=light,
        delta_e00=de,
        fit_delta_e00=fit_de,
        sensitivities=sens,
        sensitivity_rms=sens_rms,
        reference_rgb=ref,
        detection=det,
        photo=photo,
        half_size=raw is not None and raw.mosaic is not None,
        cfa=raw.cfa if raw is not None else None,
    )


def relative_qe(sensitivities: Any) -> tuple[Any, Any]:
    r"""Return the relative quantum efficiencies of estimated spectral sensitivities.

    The efficiencies are for photon counting, largest 1; the sensitivities are in energy units
    (response per unit of spectral power).

    A photosite counts photons, :math:`N(\lambda) = E(\lambda)\,\lambda / (h c)`, so the
    response per unit power is :math:`S(\lambda) \propto \mathrm{QE}(\lambda)\,\lambda`
    and :math:`\mathrm{QE}(\lambda) \propto S(\lambda) / \lambda`.

    Examples
    --------
    >>> import numpy as np
    >>> from imageform.spectral import Spectrum
    >>> wl, qe = relative_qe(Spectrum(np.array([400.0, 800.0]), np.array([[1, 1, 1], [1, 1, 2.0]])))
    >>> qe[:, 2].tolist()
    [1.0, 1.0]
    """
    import numpy as np

    from imageform._validate import describe
    from imageform.spectral import Spectrum

    if not isinstance(sensitivities, Spectrum):
        raise TypeError(f"expected sensitivities as a Spectrum, got {describe(sensitivities)}")
    wl = np.asarray(sensitivities.wavelengths, dtype=np.float64)
    qe = np.asarray(sensitivities.values, dtype=np.float64).reshape(len(wl), -1) / wl[:, None]
    peak = float(qe.max()) if qe.size else 0.0
    if not peak > 0.0:
        raise InvalidInputError("sensitivities: expected a positive value somewhere, got none")
    return wl, qe / peak


def _patch_subset(ok: Any) -> Any:
    """Return the ColorChecker reflectances of the patches ``ok``."""
    import numpy as np

    from imageform.spectral import Spectrum, colorchecker_reflectances

    r = colorchecker_reflectances()
    return Spectrum(r.wavelengths, np.asarray(r.values)[:, np.asarray(ok)])


def _exposure_match(rendered: Any, ref: Any) -> float:
    """Return the factor that brings the neutral patches' luminance onto the reference's."""
    import numpy as np

    y = np.array([0.2126, 0.7152, 0.0722])
    a, b = rendered[list(_NEUTRALS)] @ y, ref[list(_NEUTRALS)] @ y
    good = np.isfinite(a) & (a > 0)
    return float(np.sum(b[good]) / np.sum(a[good])) if good.any() else 1.0


# ---------------------------------------------------------------- the whole


def _tables(res: CameraCharacterization) -> dict[str, dict[str, Any]]:
    import numpy as np

    tables: dict[str, dict[str, Any]] = {}
    doc = res.manifest
    n = res.noise
    if n is not None:
        m = n.emva
        s: dict[str, Any] = {
            "system_gain_dn_per_e": float(m.system_gain),
            "read_noise_e": float(m.dark_noise),
        }
        for key, v in (
            ("dark_current_e_per_s", max(float(m.dark_current), 0.0)),
            ("dsnu_e", float(m.dsnu)),
            ("prnu", float(m.prnu) / 100.0),
            ("full_well_e", float(m.saturation_capacity)),
            ("black_level_dn", float(n.black_level_dn)),
        ):
            if math.isfinite(v):
                s[key] = v
        qe = _peak_qe(res)
        if qe is not None:
            s["quantum_efficiency"] = qe
        bits = _get(doc, "camera", "bit_depth", int, None)
        if bits is None and math.isfinite(m.saturation_dn) and m.saturation_dn > 1:
            bits = math.ceil(math.log2(float(np.max(m.mean_dn)) + 1))
        if bits is not None:
            s["bit_depth"] = int(bits)
        for key in ("pixel_pitch_um",):
            v2 = _get(doc, "camera", key, float, None)
            if v2 is not None:
                s[key] = v2
        cfa = _camera_cfa(doc) or res.raw_cfa
        if cfa is not None:
            s["cfa"] = cfa
        tables["sensor"] = s
    sh = res.sharpness
    if sh is not None:
        o: dict[str, Any] = {"model": "gaussian", "gaussian_sigma_px": sh.gaussian_sigma_px}
        if all(math.isfinite(m) for m in sh.mtf50):  # a camera sharper than the e-SFR's
            # range (MTF above 0.5 to its end: a pixel without lens blur) has no MTF50
            o["mtf50_cy_per_px"] = list(sh.mtf50) if len(sh.mtf50) == 3 else sh.mtf50[0]
        fn = _get(doc, "camera", "f_number", float, None)
        if fn is not None:
            o["f_number"] = fn
        tables["optics"] = o
    c = res.color
    if c is not None:
        col: dict[str, Any] = {}
        if _processing(doc) == "fixed":
            col = {
                # the camera file's convention: linear sRGB = ccm @ (white-balanced camera RGB)
                "ccm": [[float(x) for x in row] for row in np.asarray(c.ccm).T],
                "ccm_to": "linear_srgb",
                "white_balance": list(c.white_balance),
                "illuminant": c.illuminant,
            }
        if c.sensitivities is not None:
            wl, qe = relative_qe(c.sensitivities)
            col["sensitivity"] = {
                "wavelengths_nm": [float(w) for w in wl],
                "r": [float(x) for x in qe[:, 0]],
                "g": [float(x) for x in qe[:, 1]],
                "b": [float(x) for x in qe[:, 2]],
            }
        if col:
            tables["color"] = col
    return tables


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


def _peak_qe(res: CameraCharacterization) -> float | None:
    """Return the peak quantum efficiency, or None without photon counts.

    The EMVA QE at the flats' wavelength (``[emva]`` or ``[flats] wavelength_nm``, default
    550 nm), divided by the estimated green sensitivity there (relative QE, largest 1) when
    the chart gave one.
    """
    import numpy as np

    n = res.noise
    if n is None or not math.isfinite(n.emva.quantum_efficiency):
        return None
    qe = float(n.emva.quantum_efficiency)
    doc = res.manifest
    lam = _get(doc, "emva", "wavelength_nm", float, None) or _get(
        doc, "flats", "wavelength_nm", float, 550.0
    )
    c = res.color
    if c is not None and c.sensitivities is not None:
        wl, rel = relative_qe(c.sensitivities)
        g = float(np.interp(float(lam), wl, rel[:, 1]))
        if g > 0.05:
            qe = qe / g
    return float(min(max(qe, 1e-6), 1.0))


def characterize_camera(
    folder: str | Path,
    *,
    progress: Progress | None = None,
    max_pixels: int | None = None,
) -> CameraCharacterization:
    """Characterise a camera from a folder of lab photographs.

    Geometry, sharpness, noise and colour are measured, each where its subfolder exists (the
    module docstring gives the layout).

    Parameters
    ----------
    folder : str or Path
        The lab set: ``checkerboard/``, ``colorchecker/``, ``edge/``, ``flats/`` +
        ``darks/``, an optional ``lab.toml``.
    progress : callable, optional
        ``progress(stage, fraction_done)``.
    max_pixels : int, optional
        Refuse images with more pixels (default 100 Mpx, or ``IMAGEFORM_MAX_PIXELS``).

    Returns
    -------
    CameraCharacterization
        Each part's measurement (None where not measured, with the reason in ``missing``)
        and the camera file's tables.

    Raises
    ------
    InvalidInputError
        Not a folder; a folder with none of the parts; a malformed ``lab.toml``; a part
        whose images cannot be read or measured (one line naming the file).

    Examples
    --------
    >>> import tempfile
    >>> characterize_camera(tempfile.mkdtemp())  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    imageform.errors.InvalidInputError: ... holds none of checkerboard/, colorchecker/, ...
    """
    from imageform._validate import as_path, describe

    root = as_path(folder, "folder")
    try:
        is_dir = root.is_dir()
    except OSError:  # a name too long for the file system, ...
        is_dir = False
    if not is_dir:
        raise InvalidInputError(
            f"expected FOLDER a folder of lab photographs, got {describe(str(root), 60)}"
        )
    doc = _manifest(root)
    dirs = {part: _subfolder(root, names) for part, names in PARTS.items() if part != "noise"}
    flats, darks = _subfolder(root, ("flats",)), _subfolder(root, ("darks",))
    if not any(dirs.values()) and flats is None and darks is None:
        raise InvalidInputError(
            f"{root} holds none of checkerboard/, colorchecker/, edge/, flats/ + darks/ "
            "(docs/characterize.md)"
        )
    notes: list[str] = []
    missing: dict[str, str] = {}
    step = {"done": 0}

    def report(stage: str) -> None:
        if progress is not None:
            progress(stage, step["done"] / 4)
        step["done"] += 1

    noise = None
    report("noise")
    if flats is not None and darks is not None:
        noise = _measure_noise(root, flats, darks, doc, max_pixels)
    else:
        missing["noise"] = (
            "no darks/ folder"
            if flats is not None
            else ("no flats/ folder" if darks is not None else "no flats/ and darks/ folders")
        )
    black = None
    if noise is not None and noise.plane == "all":
        black = noise.black_level_dn
    geometry = sharp = color = None
    size: tuple[int, int] | None = None
    report("geometry")
    if dirs["geometry"] is not None:
        geometry, size = _measure_geometry(dirs["geometry"], doc, notes, max_pixels, black, None)
    else:
        missing["geometry"] = "no checkerboard/ (or charuco/) folder"
    report("sharpness")
    if dirs["sharpness"] is not None:
        sharp = _measure_sharpness(dirs["sharpness"], doc, max_pixels, black)
        size = size or sharp.image_size
    else:
        missing["sharpness"] = "no edge/ (or sfr/) folder"
    report("color")
    if dirs["color"] is not None:
        color = _measure_color(dirs["color"], doc, max_pixels, black)
        if size is None and color.photo is not None:
            h, w = color.photo.shape[:2]
            half = color.raw is not None and color.developed is None and color.half_size
            size = (int(w) * 2, int(h) * 2) if half else (int(w), int(h))
    else:
        missing["color"] = "no colorchecker/ (or chart/) folder"
    if noise is None and geometry is None and sharp is None and color is None:
        why = "; ".join(f"{k}: {v}" for k, v in missing.items())
        raise InvalidInputError(f"{root}: nothing to measure ({why})"[:200])
    if progress is not None:
        progress("done", 1.0)
    res = CameraCharacterization(
        folder=root,
        image_size=size,
        geometry=geometry,
        sharpness=sharp,
        noise=noise,
        color=color,
        missing=missing,
        notes=tuple(notes),
        manifest=doc,
        tables={},
    )
    return CameraCharacterization(**{**res.__dict__, "tables": _tables(res)})


# ---------------------------------------------------------------- the workflow

#: The files that mark a folder as imageform characterize's output (only such a folder is
#: replaced with --force).
_MARKERS = ("report.html", "metrics.json", "camera.toml")


@dataclass(frozen=True, kw_only=True)
class CharacterizeOptions(Options):
    """Options of ``imageform characterize``."""

    max_pixels: int | None = option(
        None,
        help="Refuse images with more pixels (default 100 Mpx, or IMAGEFORM_MAX_PIXELS).",
        metavar="N",
    )


def _check_folder(out: Path, force: bool) -> None:
    marked = any((out / m).exists() for m in _MARKERS)
    if out.is_dir() and force and not marked and any(out.iterdir()):
        raise InvalidInputError(
            f"output folder {out} exists and is not an imageform characterize output; "
            "choose a new folder (--force replaces only a previous characterisation)"
        )


def characterize(run: Run, opts: CharacterizeOptions, *, out: Path, folder: str) -> Result:
    """``imageform characterize``: measure, then write camera.toml, report.html, metrics.json.

    They go into a temporary folder that replaces ``out`` when all is written.
    """
    import importlib.util

    from imageform.workflows._characterize_report import write_outputs

    if importlib.util.find_spec("matplotlib") is None:
        raise InvalidInputError(
            "imageform characterize draws its report with matplotlib, which is not installed: "
            'pip install "imageform[plot]"'
        )
    src = Path(folder)
    if out.resolve() == src.resolve() or src.resolve() in out.resolve().parents:
        raise InvalidInputError(f"the output folder {out} must not be inside FOLDER {src}")
    _check_folder(out, run.outputs.force)
    res = characterize_camera(src, progress=run.progress, max_pixels=opts.max_pixels)
    tmp = run.folder(out)
    written = write_outputs(res, tmp)
    for n in res.notes:
        run.note(f"note: {n}")
    s = res.summary()
    summary = {
        "folder": src,
        "out": out,
        "camera": out / written["camera"].name if written["camera"] is not None else None,
        "report": out / "report.html",
        "metrics": out / "metrics.json",
        **s,
    }
    text = [f"characterised {src}: measured {', '.join(res.measured) or 'nothing'}"]
    text += [f"  not measured: {k} ({v})" for k, v in res.missing.items()]
    g = s.get("geometry")
    if g:
        text.append(
            f"  geometry   fx {g['fx']:.2f}, fy {g['fy']:.2f}, cx {g['cx']:.2f}, cy {g['cy']:.2f} "
            f"px, k1 {g['k1']:.4f}; RMS {g['rms_px']:.3f} px over {g['views_used']} views"
        )
    sh = res.sharpness
    if sh is not None:
        text.append(
            "  sharpness  MTF50 "
            + ", ".join(f"{c} {v:.3f}" for c, v in zip(sh.channels, sh.mtf50, strict=True))
            + f" cy/px; Gaussian sigma {sh.gaussian_sigma_px:.3f} px ({sh.edges} edges)"
        )
    nz = s.get("noise")
    if nz:
        text.append(
            f"  noise      K {nz['system_gain_dn_per_e']:.4g} DN/e-, read noise "
            f"{nz['read_noise_e']:.3g} e-, dark current {nz['dark_current_e_per_s']:.3g} e-/s, "
            f"full well {nz['saturation_capacity_e']:.4g} e-"
        )
    co = s.get("color")
    if co:
        text.append(
            f"  colour     white balance {', '.join(f'{g:.3f}' for g in co['white_balance'])}; "
            f"ΔE00 mean {co['delta_e00_mean']:.2f} (max {co['delta_e00_max']:.2f}); "
            "sensitivities "
            + ("estimated" if co["sensitivities_estimated"] else "not estimated (no raw)")
        )
    text += [
        f"camera  -> {summary['camera'] or 'not written (no image size: flats and darks only)'}",
        f"report  -> {summary['report']}",
    ]
    return Result(summary, tuple(text))


WORKFLOWS = (
    Workflow(
        "characterize",
        "Characterise a camera from a folder of lab photographs: camera file + report.",
        "imageform.workflows.characterize:characterize",
        CharacterizeOptions,
        (
            Input(
                "folder",
                "Lab set: checkerboard/, colorchecker/, edge/, flats/ + darks/ (each optional) "
                f"and an optional {LAB_MANIFEST}.",
                kind="text",
                metavar="FOLDER",
            ),
        ),
        Output(
            "Output folder: camera.toml, report.html, metrics.json (replaced whole).",
            folder=True,
        ),
        group="simulation",
        description="Checkerboard views give the intrinsics and distortion, a slanted edge "
        "the MTF (MTF50 per channel, a fitted Gaussian PSF), flat and dark stacks the EMVA "
        "1288 noise model, a ColorChecker the white balance, colour matrix and spectral "
        "sensitivities. What is missing is reported as not measured. docs/characterize.md.",
    ),
)
