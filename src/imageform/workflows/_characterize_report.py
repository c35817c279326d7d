"""The outputs of ``imageform characterize``: camera.toml, report.html and metrics.json.

report.html has the simulate report's style (:mod:`imageform.report.html_parts`), figures
embedded as data: URIs.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from imageform._jsonio import write_json
from imageform.report import html_parts as hp

__all__ = ["METRICS_FORMAT", "write_outputs"]

#: The ``format`` of characterize's metrics.json.
METRICS_FORMAT = "imageform-characterization"


def _pm(v: float | None, s: float | None, fmt: str = ".4g") -> str:
    if v is None or not math.isfinite(v):
        return "—"
    if s is None or not math.isfinite(s) or s == 0:
        return f"{v:{fmt}}"
    return f"{v:{fmt}} ± {s:.2g}"


def _plt() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


# ---------------------------------------------------------------- sections


def _geometry(res: Any) -> str:
    g = res.geometry
    if g is None:
        return hp.section(
            "geometry", "Geometry", hp.note(f"Not measured: {res.missing['geometry']}.")
        )
    c = g.calibration
    K, d, std = c.K, c.distortion, c.std
    rows = [
        ["fx", "px", _pm(K[0, 0], std.get("fx"), ".3f")],
        ["fy", "px", _pm(K[1, 1], std.get("fy"), ".3f")],
        ["cx", "px", _pm(K[0, 2], std.get("cx"), ".3f")],
        ["cy", "px", _pm(K[1, 2], std.get("cy"), ".3f")],
        ["k1", "", _pm(d.k1, std.get("k1"), ".5f")],
        ["k2", "", _pm(d.k2, std.get("k2"), ".5f")],
        ["p1", "", _pm(d.p1, std.get("p1"), ".2e")],
        ["p2", "", _pm(d.p2, std.get("p2"), ".2e")],
        ["k3", "", "0 (held)"],
        ["RMS reprojection error", "px", f"{c.rms:.4f}"],
    ]
    plt = _plt()
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4.2))
    for name, r in zip(g.views, c.residuals, strict=True):
        ax1.scatter(r[:, 0], r[:, 1], s=5, label=name)
    ax1.set_xlabel("u error (px)")
    ax1.set_ylabel("v error (px)")
    ax1.set_aspect("equal", adjustable="datalim")
    ax1.set_title(f"reprojection errors (RMS {c.rms:.4f} px)")
    ax2.bar(np.arange(len(g.views)), c.per_view_rms)
    ax2.set_xticks(np.arange(len(g.views)), list(g.views), rotation=60, ha="right", fontsize=7)
    ax2.set_ylabel("RMS per view (px)")
    fig.tight_layout()
    body = [
        f"<p>Zhang's closed form, then Levenberg-Marquardt on every reprojection error, "
        f"from {len(g.views)} views of the {hp.e(g.board)} board (k3 held at 0). "
        "± one standard deviation of the fit.</p>",
        hp.table(["parameter", "unit", "value"], rows, left=(0,)),
        hp.figure(
            hp.figure_png(fig),
            "reprojection errors",
            "Each detected corner's error (observed minus reprojected) and the RMS per view.",
            "reprojection",
        ),
    ]
    if g.missed:
        body.append(hp.note(f"No board found in: {', '.join(g.missed)}."))
    return hp.section("geometry", "Geometry", "".join(body))


def _sharpness(res: Any) -> str:
    s = res.sharpness
    if s is None:
        return hp.section(
            "sharpness", "Sharpness (MTF)", hp.note(f"Not measured: {res.missing['sharpness']}.")
        )
    rows = [
        [c, _pm(m50, sd, ".4f"), f"{m10:.4f}" if math.isfinite(m10) else "—"]
        for c, m50, sd, m10 in zip(s.channels, s.mtf50, s.mtf50_std, s.mtf10, strict=True)
    ]
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    f = np.asarray(s.frequency)
    colours = {"R": "tab:red", "G": "tab:green", "B": "tab:blue", "raw": "k", "Y": "k"}
    for k, c in enumerate(s.channels):
        ax.plot(f, np.asarray(s.sfr)[:, k], color=colours.get(c, "k"), label=f"measured {c}")
    angle = float(np.median(s.angles_deg))
    t = math.radians(angle)
    box = np.abs(np.sinc(f * math.cos(t)) * np.sinc(f * math.sin(t)))
    model = np.exp(-2 * np.pi**2 * s.gaussian_sigma_px**2 * f**2) * box
    ax.plot(f, model, "k--", lw=1, label=f"Gaussian σ = {s.gaussian_sigma_px:.3f} px × pixel")
    ax.axhline(0.5, color="0.7", lw=0.8)
    ax.axvline(0.5, color="0.7", lw=0.8, ls=":")
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1.05)
    ax.set_xlabel("frequency (cycles/pixel)")
    ax.set_ylabel("SFR (MTF)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    what = (
        "the raw mosaic, its photosites balanced on the neutral edge (one channel)"
        if s.raw
        else "the photograph, decoded to linear light, per channel"
    )
    body = [
        f"<p>ISO 12233 slanted-edge e-SFR of {hp.e(s.image)}: {s.edges} edges found "
        f"(angles {', '.join(f'{a:.1f}' for a in s.angles_deg)} deg), measured on {what}. "
        "MTF50 is the median over the edges, ± its standard error. The optics' blur is "
        "fitted as a Gaussian PSF whose MTF times the pixel aperture's matches the curve up "
        f"to Nyquist: σ = {_pm(s.gaussian_sigma_px, s.gaussian_sigma_std, '.4f')} px.</p>",
        hp.table(["channel", "MTF50 (cy/px)", "MTF10 (cy/px)"], rows, left=(0,)),
        hp.figure(
            hp.figure_png(fig),
            "MTF",
            "The measured SFR (median over the edges) and the fitted model; grey: 0.5 and Nyquist.",
            "mtf",
        ),
    ]
    return hp.section("sharpness", "Sharpness (MTF)", "".join(body))


def _noise(res: Any) -> str:
    n = res.noise
    if n is None:
        return hp.section(
            "noise", "Noise (EMVA 1288)", hp.note(f"Not measured: {res.missing['noise']}.")
        )
    m = n.emva
    rows = [
        ["system gain K", "DN/e⁻", _pm(m.system_gain, n.system_gain_std)],
        [
            "temporal dark (read) noise σd",
            "e⁻",
            _pm(m.dark_noise, n.read_noise_std)
            + (" (upper limit)" if m.dark_noise_upper_limit else ""),
        ],
        ["dark current", "e⁻/s", _pm(m.dark_current, None)],
        ["DSNU", "e⁻", _pm(m.dsnu, None)],
        ["PRNU", "%", _pm(m.prnu, None)],
        [
            "saturation capacity" + ("" if m.saturated else " (lower bound)"),
            "e⁻",
            _pm(m.saturation_capacity, None),
        ],
        ["quantum efficiency", "", _pm(m.quantum_efficiency, None)],
        ["SNR max", "dB", _pm(m.snr_max_db, None, ".1f")],
        ["dynamic range", "dB", _pm(m.dynamic_range_db, None, ".1f")],
        ["black level", "DN", _pm(n.black_level_dn, None, ".2f")],
    ]
    plt = _plt()
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    x = m.mean_dn - m.dark_mean_dn
    y = m.var_dn - m.dark_var_dn
    fit = np.arange(len(x)) < m.fit_points
    ax1.plot(x[fit], y[fit], "o", color="tab:blue", label="fitted")
    ax1.plot(x[~fit], y[~fit], "o", mfc="none", color="tab:blue", label="not fitted")
    xx = np.linspace(0, float(np.nanmax(x)), 50)
    ax1.plot(xx, m.system_gain * xx, "k--", lw=1, label=f"K = {m.system_gain:.4g} DN/e⁻")
    ax1.set_xlabel("mean signal μy − μy.dark (DN)")
    ax1.set_ylabel("temporal variance σ²y − σ²y.dark (DN²)")
    ax1.set_title("photon transfer")
    ax1.legend(fontsize=8)
    e = np.asarray(m.signal_electrons)
    ok = e > 0
    ax2.loglog(e[ok], np.asarray(m.snr_measured)[ok], "o", label="measured")
    ax2.loglog(e[ok], np.asarray(m.snr_model)[ok], "k--", lw=1, label="EMVA model")
    ax2.loglog(e[ok], np.sqrt(e[ok]), ":", color="0.5", label="ideal √μe")
    ax2.set_xlabel("signal μe (e⁻)")
    ax2.set_ylabel("SNR")
    ax2.set_title("signal-to-noise ratio")
    ax2.legend(fontsize=8)
    fig.tight_layout()
    body = [
        f"<p>EMVA 1288 (Release 4.0) from {n.exposures} exposures of flat and dark pairs, "
        f"{n.shape[1]} × {n.shape[0]} pixels of the plane {hp.e(n.plane)}. ± the standard "
        "error of the gain fit (and of the dark variance).</p>",
        hp.table(["quantity", "unit", "value"], rows, left=(0,)),
        hp.figure(
            hp.figure_png(fig),
            "photon transfer and SNR",
            "Left: variance against mean, the gain fitted from 0 to 70 % of saturation. "
            "Right: the SNR curve against the EMVA model with the measured parameters.",
            "ptc",
        ),
    ]
    if not m.saturated:
        body.append(
            hp.note(
                "The temporal variance peaks at the last exposure: the series may not reach "
                "saturation (saturation, SNR max and dynamic range are lower bounds)."
            )
        )
    return hp.section("noise", "Noise (EMVA 1288)", "".join(body))


def _chart_figure(c: Any) -> bytes | None:
    if c.photo is None or c.detection is None:
        return None
    plt = _plt()
    img = np.clip(np.asarray(c.photo), 0, 1)
    # the chart and a margin of a fifth of its size around it
    corners = np.asarray(c.detection.corners, dtype=float)
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    pad = 0.2 * (hi - lo)
    u0, v0 = (int(max(0, x)) for x in np.floor(lo - pad))
    u1 = int(min(img.shape[1], np.ceil(hi[0] + pad[0])))
    v1 = int(min(img.shape[0], np.ceil(hi[1] + pad[1])))
    img = img[v0:v1, u0:u1]
    h, w = img.shape[:2]
    fig, ax = plt.subplots(figsize=(8, 8 * h / max(w, 1)))
    ax.imshow(img, extent=(u0 - 0.5, u1 - 0.5, v1 - 0.5, v0 - 0.5))
    for k, (u, v) in enumerate(np.asarray(c.detection.centers)):
        de = float(np.asarray(c.delta_e00)[k])
        if math.isfinite(de):
            ax.text(
                u,
                v,
                f"{de:.1f}",
                ha="center",
                va="center",
                fontsize=7,
                color="w",
                bbox={"boxstyle": "round,pad=0.15", "fc": "k", "alpha": 0.6, "lw": 0},
            )
    q = np.vstack([c.detection.corners, c.detection.corners[:1]])
    ax.plot(q[:, 0], q[:, 1], "y-", lw=1)
    ax.set_axis_off()
    fig.tight_layout()
    import io

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    plt.close(fig)
    from PIL import Image

    return hp.page_jpeg(Image.open(io.BytesIO(buf.getvalue())), max_width=900)


def _colour(res: Any) -> str:
    c = res.color
    if c is None:
        return hp.section("colour", "Colour", hp.note(f"Not measured: {res.missing['color']}."))
    de = np.asarray(c.delta_e00, dtype=float)
    body = []
    src = []
    if c.raw:
        src.append(f"the raw photograph {hp.e(c.raw)}")
    if c.developed:
        src.append(f"the developed photograph {hp.e(c.developed)}")
    to = {
        "camera_output": "the camera's own developed photograph (its processing, modelled)",
        "srgb": "the chart's reference linear sRGB (D65)",
    }[c.ccm_to]
    body.append(
        f"<p>ColorChecker found in {' and '.join(src)}. White balance gains (green 1) from "
        f"the neutral patches; linear output = (camera RGB × gains) @ CCM, fitted by least "
        f"squares to {to}. The light on the chart: {hp.e(c.illuminant)}.</p>"
    )
    wb = ", ".join(f"{g:.4f}" for g in c.white_balance)
    ccm = "<br>".join(" ".join(f"{v:+.4f}" for v in row) for row in np.asarray(c.ccm))
    body.append(
        hp.table(
            ["quantity", "value"],
            [
                ["white balance (R, G, B)", wb],
                ["CCM (rows: camera R, G, B)", hp.Markup(ccm)],
                [
                    "ΔE00 of the camera against the chart (mean / max)",
                    f"{np.nanmean(de):.2f} / {np.nanmax(de):.2f}",
                ],
                ["ΔE00 of the fitted model (mean)", f"{np.nanmean(c.fit_delta_e00):.2f}"],
            ],
            left=(0,),
        )
    )
    jpg = _chart_figure(c)
    if jpg is not None:
        body.append(
            hp.figure(
                jpg,
                "ColorChecker with ΔE00 per patch",
                "The chart as photographed (developed, or the raw balanced for display), each "
                "patch labelled with its CIEDE2000 against the reference (exposure matched on "
                "the greys).",
                "chart",
                photo=False,
                mime="image/jpeg",
            )
        )
    from imageform.spectral import COLORCHECKER_PATCHES

    ref = np.asarray(c.reference_rgb)
    rows = []
    for k, name in enumerate(COLORCHECKER_PATCHES):
        sw = "#" + "".join(f"{round(float(x) * 255):02x}" for x in _enc(ref[k]))
        rows.append(
            [
                k + 1,
                hp.Markup(f'<span class="swatch" style="background:{sw}"></span> {hp.e(name)}'),
                f"{de[k]:.2f}" if math.isfinite(de[k]) else "—",
                f"{float(np.asarray(c.fit_delta_e00)[k]):.2f}"
                if math.isfinite(float(np.asarray(c.fit_delta_e00)[k]))
                else "—",
            ]
        )
    body.append(hp.table(["#", "patch", "ΔE00 camera", "ΔE00 model fit"], rows, left=(1,)))
    if c.sensitivities is not None:
        body.append(_sensitivity_figure(c))
    else:
        body.append(
            hp.note("No raw photograph of the chart: the spectral sensitivities are not estimated.")
        )
    return hp.section("colour", "Colour", "".join(body))


def _enc(rgb: Any) -> Any:
    from imageform.color import linear_to_srgb

    return np.asarray(linear_to_srgb(np.clip(np.asarray(rgb, dtype=float), 0, 1)))


def _sensitivity_figure(c: Any) -> str:
    from imageform.spectral import camera_sensitivities

    plt = _plt()
    sp = c.sensitivities
    wl = np.asarray(sp.wavelengths)
    v = np.asarray(sp.values)
    fig, ax = plt.subplots(figsize=(7.5, 4))
    ref = camera_sensitivities()
    rv = np.asarray(ref.values) / np.asarray(ref.values).max()
    for k, col in enumerate(("tab:red", "tab:green", "tab:blue")):
        ax.plot(wl, v[:, k], color=col, label=f"estimated {'RGB'[k]}")
        ax.plot(np.asarray(ref.wavelengths), rv[:, k], color=col, ls=":", lw=1)
    ax.set_xlabel("wavelength (nm)")
    ax.set_ylabel("relative sensitivity")
    ax.set_xlim(wl.min(), wl.max())
    ax.legend(fontsize=8)
    fig.tight_layout()
    rms = ", ".join(f"{x:.3f}" for x in c.sensitivity_rms)
    return hp.figure(
        hp.figure_png(fig),
        "spectral sensitivities",
        "Estimated from the raw chart responses and the light (Finlayson, Hordley & Hubel "
        "1998: non-negative, smooth), largest value 1; dotted: the shipped Nikon D5100 "
        f"table (NPL) for comparison. Misfit per channel (relative RMS): {hp.e(rms)}.",
        "sensitivities",
    )


def _camera_section(text: str) -> str:
    return hp.section(
        "camera-file", "Camera file", f"<p>camera.toml, as written:</p><pre>{hp.e(text)}</pre>"
    )


# ---------------------------------------------------------------- writing


def _write_camera(res: Any, path: Path) -> Path | None:
    """Write camera.toml with the geometry and every measured table.

    Returns its path, or None (nothing written) when no photograph gives the image size (flats
    and darks only).
    """
    from imageform.io import write_camera

    if res.image_size is None:
        return None
    write_camera(path, res.camera_file(), **res.tables)
    return path


def write_outputs(res: Any, folder: Path) -> dict[str, Path | None]:
    """Write camera.toml, report.html and metrics.json of ``res`` into ``folder``."""
    camera = _write_camera(res, folder / "camera.toml")
    notes = list(res.notes)
    if camera is None:
        notes.append(
            "no photograph gives the image size: no camera.toml was written (the measured "
            "values are in metrics.json)"
        )
    if res.geometry is None and camera is not None:
        notes.append(
            "no checkerboard: camera.toml has nominal intrinsics (f = the longer image side, "
            "principal point at the centre), not measured ones"
        )
    summary = res.summary()
    metrics = {
        "format": METRICS_FORMAT,
        "version": 1,
        "folder": str(res.folder),
        "image_size_px": list(res.image_size) if res.image_size else None,
        "summary": summary,
        "camera_tables": res.tables,
        "curves": _curves(res),
        "notes": notes,
    }
    mpath = folder / "metrics.json"
    write_json(mpath, metrics)
    sections = [_overview(res, summary)]
    truth = _truth(res, summary)
    if truth:
        sections.append(truth)
    sections += [_geometry(res), _sharpness(res), _noise(res), _colour(res)]
    if camera is not None:
        sections.append(_camera_section(camera.read_text(encoding="utf-8")))
    if notes:
        sections.append(hp.section("notes", "Notes", "".join(hp.note(n) for n in notes)))
    nav = [
        ("overview", "Overview"),
        ("geometry", "Geometry"),
        ("sharpness", "Sharpness"),
        ("noise", "Noise"),
        ("colour", "Colour"),
        ("camera-file", "Camera file"),
    ]
    sub = (
        f'<p class="meta">Lab set {hp.e(res.folder)} · measured '
        f"{hp.e(', '.join(res.measured) or 'nothing')}</p>"
    )
    html = hp.page("imageform camera characterisation", sub, nav, "".join(sections))
    rpath = folder / "report.html"
    rpath.write_text(html, encoding="utf-8")
    return {"camera": camera, "report": rpath, "metrics": mpath}


def _overview(res: Any, summary: dict[str, Any]) -> str:
    rows = []
    for part, title in (
        ("geometry", "geometry (checkerboard)"),
        ("sharpness", "sharpness (slanted edge)"),
        ("noise", "noise (flats and darks)"),
        ("color", "colour (ColorChecker)"),
    ):
        if getattr(res, part) is not None:
            rows.append([title, "measured", _headline(part, summary[part])])
        else:
            rows.append([title, "not measured", res.missing.get(part, "")])
    return hp.section(
        "overview",
        "Overview",
        hp.table(["part", "status", "headline"], rows, left=(0, 1, 2)),
    )


def _truth(res: Any, summary: dict[str, Any]) -> str:
    """Measured against lab.toml's ``[truth]`` (a simulated lab set knows its camera).

    Every numeric true value gets a row (lists element by element: ``white_balance[0]``,
    ``ccm[1][2]``) with what was measured: the geometry, the camera file's ``[sensor]`` and
    ``[optics]``, and the chart's white balance and matrix (also when the twin's processing
    is automatic and they are not in the camera file).
    """
    truth = res.manifest.get("truth")
    if not isinstance(truth, dict) or not truth:
        return ""
    g = summary.get("geometry", {})
    measured: dict[str, Any] = {
        **{k: g.get(k) for k in ("fx", "fy", "cx", "cy", "k1", "k2")},
        **res.tables.get("sensor", {}),
        **res.tables.get("optics", {}),
    }
    for key, same in (("dsnu_e_of_the_frames", "dsnu_e"), ("prnu_of_the_frames", "prnu")):
        measured[key] = measured.get(same)
    if res.noise is not None:  # EMVA's QE at the flats' wavelength (fill factor included)
        measured["quantum_efficiency_green_550nm"] = float(res.noise.emva.quantum_efficiency)
    if res.color is not None:
        measured["white_balance"] = [float(x) for x in res.color.white_balance]
        measured["ccm"] = np.asarray(res.color.ccm, dtype=float).T.tolist()

    def flat(name: str, value: Any) -> list[tuple[str, Any]]:
        if isinstance(value, list | tuple):
            return [p for i, v in enumerate(value) for p in flat(f"{name}[{i}]", v)]
        return [(name, value)]

    rows = []
    for key, true in truth.items():
        got_all = dict(flat(key, measured.get(key)))
        for name, t in flat(key, true):
            got = got_all.get(name, measured.get(key))
            if isinstance(t, bool) or not isinstance(t, int | float) or got is None:
                continue
            if isinstance(got, bool) or not isinstance(got, int | float):
                continue
            if not math.isfinite(float(got)):
                continue
            err = f"{(float(got) / float(t) - 1) * 100:+.2f} %" if t else f"{float(got):+.3g}"
            rows.append([name, f"{float(t):.6g}", f"{float(got):.6g}", err])
    if not rows:
        return ""
    return hp.section(
        "truth",
        "Against the truth",
        "<p>lab.toml gives the true values of the camera that made these photographs (a "
        "simulated lab set): each one beside what was measured.</p>"
        + hp.table(["quantity", "true", "measured", "error"], rows, left=(0,)),
    )


def _headline(part: str, s: dict[str, Any]) -> str:
    if part == "geometry":
        return f"fx {s['fx']:.2f}, fy {s['fy']:.2f}, k1 {s['k1']:.4f}, RMS {s['rms_px']:.3f} px"
    if part == "sharpness":
        m = ", ".join(f"{c} {v:.3f}" for c, v in s["mtf50_cy_per_px"].items())
        return f"MTF50 {m} cy/px; σ {s['gaussian_sigma_px']:.3f} px"
    if part == "noise":
        return (
            f"K {s['system_gain_dn_per_e']:.4g} DN/e⁻, read noise {s['read_noise_e']:.3g} e⁻, "
            f"full well {s['saturation_capacity_e']:.4g} e⁻"
        )
    mean = s["delta_e00_mean"]
    return f"ΔE00 mean {mean:.2f}" if mean is not None else "ΔE00 n/a"


def _curves(res: Any) -> dict[str, Any]:
    out: dict[str, Any] = {}
    if res.sharpness is not None:
        s = res.sharpness
        out["sfr"] = {
            "frequency_cy_per_px": np.asarray(s.frequency),
            "channels": list(s.channels),
            "sfr": np.asarray(s.sfr),
        }
    if res.noise is not None:
        m = res.noise.emva
        out["photon_transfer"] = {
            "exposure_times_s": m.exposure_times,
            "mean_dn": m.mean_dn,
            "var_dn2": m.var_dn,
            "dark_mean_dn": m.dark_mean_dn,
            "dark_var_dn2": m.dark_var_dn,
            "signal_electrons": m.signal_electrons,
            "snr_measured": m.snr_measured,
            "snr_model": m.snr_model,
        }
    if res.geometry is not None:
        c = res.geometry.calibration
        out["reprojection"] = {
            "views": list(res.geometry.views),
            "per_view_rms_px": c.per_view_rms,
        }
    return out
