"""The four measurements of ``imageform characterize``: geometry, sharpness, noise, colour.

Each reads its part of a lab set and returns its result record; used by
:mod:`imageform.workflows.characterize`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from imageform.errors import InvalidInputError
from imageform.workflows._characterize_inputs import (
    _NEUTRALS,
    LAB_MANIFEST,
    _entries,
    _frame,
    _get,
    _grey,
    _Image,
    _images,
    _plane,
    _read_photo,
    _transfer,
)
from imageform.workflows._characterize_results import (
    ColorMeasurement,
    GeometryMeasurement,
    NoiseMeasurement,
    Progress,
    SharpnessMeasurement,
)

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

    from imageform.analysis import find_slanted_edges, fit_gaussian_sigma, slanted_edge_sfr
    from imageform.sensor import equalize_cfa

    files = _images(folder)
    transfer = _transfer(doc, "edge")
    lo = float(_get(doc, "edge", "min_angle", float, 2.0))
    hi = float(_get(doc, "edge", "max_angle", float, 10.0))
    path = files[0]
    im = _read_photo(path, doc, transfer, max_pixels, black)
    if im.mosaic is not None:
        assert im.cfa is not None
        arr = equalize_cfa(im.mosaic, im.cfa)
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
            fit_gaussian_sigma(r.frequency, r.sfr[:, c], angle_deg=abs(r.angle))  # its own grid
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
    """``M`` (3, 3) minimising ``|| src @ M - dst ||`` over the rows ``ok`` (linear light).

    The library's 3x3 least-squares fit (:func:`imageform.analysis.fit_color_correction`,
    for row vectors ``dst = src @ matrix.T``), transposed.
    """
    from imageform.analysis import fit_color_correction

    fit = fit_color_correction(
        src[ok], dst[ok], "linear", transfer="linear", saturation=None, never_worse=False
    )
    return fit.matrix.T


def _chart_patches(im: _Image, max_size: int) -> tuple[Any, Any, Any]:
    """Find and measure a photograph's ColorChecker.

    Returns (detection, linear patch means (24, 3), the picture detected in (encoded)); a raw
    photograph is measured on its half-size superpixels, black subtracted.
    """
    import warnings

    import numpy as np

    from imageform.analysis import ChartNotFoundError, detect_colorchecker, measure_chart_patches
    from imageform.color import linear_to_srgb
    from imageform.sensor import superpixel

    if im.mosaic is not None or im.camera is not None:
        lin = superpixel(im.mosaic, str(im.cfa)) if im.mosaic is not None else im.camera
        # only to find the chart: grey-world balanced, exposed to a mean of 0.2, encoded
        means = np.maximum(lin.reshape(-1, 3).mean(axis=0), 1e-9)
        shown = np.clip(lin * (0.2 / means), 0.0, 1.0)
        enc = np.asarray(linear_to_srgb(shown))
    else:
        lin, enc = np.asarray(im.linear), np.asarray(im.encoded)
    det = detect_colorchecker(enc, max_size=max_size)
    if not det.found:
        raise ChartNotFoundError(f"no ColorChecker found in the image: {det.reason}")
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
