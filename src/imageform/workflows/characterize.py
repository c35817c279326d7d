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
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from imageform.errors import InvalidInputError
from imageform.workflows._characterize_inputs import (
    LAB_MANIFEST,
    _camera_cfa,
    _get,
    _manifest,
    _processing,
    _subfolder,
)
from imageform.workflows._characterize_measure import (
    _measure_color,
    _measure_geometry,
    _measure_noise,
    _measure_sharpness,
)
from imageform.workflows._characterize_results import (
    CameraCharacterization,
    ColorMeasurement,
    GeometryMeasurement,
    NoiseMeasurement,
    Progress,
    SharpnessMeasurement,
)
from imageform.workflows._spec import (
    Input,
    Options,
    Output,
    Result,
    Run,
    Workflow,
    option,
    refuse_foreign_folder,
)

if TYPE_CHECKING:  # at run time through __getattr__ (no NumPy for --help)
    from imageform.analysis.sensitivity import relative_qe

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


def __getattr__(name: str) -> Any:
    """``relative_qe``: the library's (:func:`imageform.analysis.relative_qe`), imported on use.

    (``imageform --help`` imports the workflows without NumPy.)
    """
    if name == "relative_qe":
        from imageform.analysis.sensitivity import relative_qe

        return relative_qe
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


#: Each measurement and the subfolder names it is looked for under (first found wins).
PARTS: Mapping[str, tuple[str, ...]] = {
    "geometry": ("checkerboard", "charuco"),
    "color": ("colorchecker", "chart"),
    "sharpness": ("edge", "sfr"),
    "noise": ("flats", "darks"),
}


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
            from imageform.analysis import relative_qe

            wl, rel = relative_qe(c.sensitivities)
            col["sensitivity"] = {
                "wavelengths_nm": [float(w) for w in wl],
                "r": [float(x) for x in rel[:, 0]],
                "g": [float(x) for x in rel[:, 1]],
                "b": [float(x) for x in rel[:, 2]],
            }
        if col:
            tables["color"] = col
    return tables


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
        from imageform.analysis import relative_qe

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


def characterize(run: Run, opts: CharacterizeOptions, *, out: Path, folder: str) -> Result:
    """``imageform characterize``: measure, then write camera.toml, report.html, metrics.json.

    They go into a temporary folder that replaces ``out`` when all is written.
    """
    import importlib.util

    from imageform._kernels import ahead
    from imageform.workflows._characterize_report import write_outputs

    if importlib.util.find_spec("matplotlib") is None:
        raise InvalidInputError(
            "imageform characterize draws its report with matplotlib, which is not installed: "
            'pip install "imageform[plot]"'
        )
    src = Path(folder)
    if out.resolve() == src.resolve() or src.resolve() in out.resolve().parents:
        raise InvalidInputError(f"the output folder {out} must not be inside FOLDER {src}")
    refuse_foreign_folder(
        out, run.outputs.force, _MARKERS, "characterize", "a previous characterisation"
    )
    ahead.start("characterize")  # a first run: its kernels compiled on two cores
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


#: What the output folder holds (its --help, and the refusal of a file name for it).
_HOLDS = "camera.toml, report.html, metrics.json"

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
            f"Output folder: {_HOLDS} (replaced whole).",
            folder=True,
            holds=_HOLDS,
        ),
        group="simulation",
        description="Checkerboard views give the intrinsics and distortion, a slanted edge "
        "the MTF (MTF50 per channel, a fitted Gaussian PSF), flat and dark stacks the EMVA "
        "1288 noise model, a ColorChecker the white balance, colour matrix and spectral "
        "sensitivities. What is missing is reported as not measured. docs/characterize.md.",
    ),
)
