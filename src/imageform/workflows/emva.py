"""``imageform emva``: EMVA 1288 characterisation of a camera from a folder of raw frames.

The folder holds, for each exposure time, at least two flat-field frames and at least two
dark frames (grey images: 16-bit TIFF or PNG, or ``.npy``; raw digital numbers, read as
stored). It is described in one of two ways:

1. a manifest ``emva.toml`` in the folder (file names relative to it; ``photons``, the mean
   photons per pixel of the flat exposure, is optional and gives the quantum efficiency)::

       [[exposure]]
       time = 0.001                       # seconds
       photons = 1520.0                   # optional
       flats = ["flat_a.tif", "flat_b.tif"]
       darks = ["dark_a.tif", "dark_b.tif"]

2. no manifest: files named ``flat_<time>_<n>.<ext>`` and ``dark_<time>_<n>.<ext>``, the
   exposure ``<time>`` in seconds as a decimal number (``flat_0.001_0.tif``,
   ``dark_2e-3_1.npy``); every time needs both kinds.

The result (``-o result.json``) is written with imageform's JSON writer (NaN as ``null``).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from imageform.errors import InvalidInputError
from imageform.workflows._images import read
from imageform.workflows._spec import Input, Options, Output, Result, Run, Workflow, option

__all__ = ["WORKFLOWS", "EmvaOptions"]

#: The manifest's file name inside the folder.
MANIFEST = "emva.toml"
#: Frame file suffixes (grey images as stored).
_FRAME_SUFFIXES = (".tif", ".tiff", ".png", ".npy")
_NAME = re.compile(r"^(flat|dark)_([0-9.eE+-]+)_([0-9]+)$")
#: One exposure: time (s), photons per pixel (or None), flat files, dark files.
_Entry = tuple[float, float | None, list[Path], list[Path]]


@dataclass(frozen=True, kw_only=True)
class EmvaOptions(Options):
    """Options of ``imageform emva``."""

    max_pixels: int | None = option(
        None,
        help="Refuse frames with more pixels (default 100 Mpx, or IMAGEFORM_MAX_PIXELS).",
        metavar="N",
    )
    fit_fraction: float = option(
        0.7, help="Upper end of the gain fit, as a fraction of the saturation signal (EMVA: 0.7)."
    )
    spatial_index: int | None = option(
        None,
        help="Which exposure (0-based, in increasing time) gives DSNU and PRNU; default: the "
        "one nearest 50 % of saturation.",
        metavar="I",
    )
    channel: int = option(0, help="Channel of colour frames to measure (grey frames: 0).")

    def check(self) -> None:
        """Check ``--fit-fraction`` in (0, 1], ``--spatial-index`` and ``--channel`` >= 0."""
        super().check()
        from imageform._validate import as_int, as_real

        ff = as_real(self.fit_fraction, "--fit-fraction", positive=True, maximum=1.0)
        object.__setattr__(self, "fit_fraction", ff)
        if self.spatial_index is not None:
            si = as_int(self.spatial_index, "--spatial-index", minimum=0)
            object.__setattr__(self, "spatial_index", si)
        object.__setattr__(self, "channel", as_int(self.channel, "--channel", minimum=0))


def _manifest(folder: Path) -> list[_Entry]:
    import tomllib

    path = folder / MANIFEST
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise InvalidInputError(f"{path}: cannot read the manifest ({msg})") from None
    entries = doc.get("exposure")
    if not isinstance(entries, list) or not entries:
        raise InvalidInputError(f"{path}: expected [[exposure]] tables, got none")
    out: list[_Entry] = []
    for i, e in enumerate(entries):
        where = f"{path}, exposure {i + 1}"
        if not isinstance(e, dict):
            raise InvalidInputError(f"{where}: expected a table")
        unknown = sorted(set(e) - {"time", "photons", "flats", "darks"})
        if unknown:
            raise InvalidInputError(
                f"{where}: unknown key(s) {', '.join(unknown)}; valid: time, photons, flats, darks"
            )
        t = e.get("time")
        if isinstance(t, bool) or not isinstance(t, int | float):
            raise InvalidInputError(f"{where}: expected time in seconds, got {t!r}"[:200])
        ph = e.get("photons")
        if ph is not None and (isinstance(ph, bool) or not isinstance(ph, int | float)):
            raise InvalidInputError(f"{where}: expected photons as a number, got {ph!r}"[:200])
        stacks = []
        for kind in ("flats", "darks"):
            names = e.get(kind)
            if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
                raise InvalidInputError(f"{where}: expected {kind} as a list of file names")
            stacks.append([folder / n for n in names])
        out.append((float(t), None if ph is None else float(ph), stacks[0], stacks[1]))
    return out


def _by_name(folder: Path) -> list[_Entry]:
    groups: dict[float, dict[str, list[tuple[int, Path]]]] = {}
    for p in sorted(folder.iterdir()):
        if p.suffix.lower() not in _FRAME_SUFFIXES:
            continue
        m = _NAME.match(p.stem)
        if m is None:
            continue
        try:
            t = float(m.group(2))
        except ValueError:
            raise InvalidInputError(
                f"{p.name}: expected flat_<time>_<n> or dark_<time>_<n> with the time in seconds"
            ) from None
        groups.setdefault(t, {"flat": [], "dark": []})[m.group(1)].append((int(m.group(3)), p))
    if not groups:
        raise InvalidInputError(
            f"{folder} has no {MANIFEST} and no frames named flat_<time>_<n> / "
            f"dark_<time>_<n> ({', '.join(_FRAME_SUFFIXES)})"
        )
    out: list[_Entry] = []
    for t in sorted(groups):
        g = groups[t]
        out.append((t, None, [p for _, p in sorted(g["flat"])], [p for _, p in sorted(g["dark"])]))
    return out


def _read_stack(paths: list[Path], opts: EmvaOptions, what: str) -> Any:
    import numpy as np

    if len(paths) < 2:
        raise InvalidInputError(f"expected at least 2 {what} frames, got {len(paths)}")
    frames = []
    for p in paths:
        if not p.is_file():
            raise InvalidInputError(f"{what} frame {p} does not exist")
        img = read(p, opts, alpha="drop")
        if not 0 <= opts.channel < img.shape[-1]:
            raise InvalidInputError(
                f"expected --channel in [0, {img.shape[-1] - 1}] for {p.name}, got {opts.channel}"
            )
        frames.append(img[..., opts.channel])
    if len({f.shape for f in frames}) > 1:
        raise InvalidInputError(f"expected {what} frames of one size, got several")
    return np.stack(frames)


def emva(run: Run, opts: EmvaOptions, *, out: Path, folder: str) -> Result:
    """``imageform emva``: EMVA 1288 parameters of a camera from flat and dark frame stacks."""
    import numpy as np

    from imageform._jsonio import write_json
    from imageform.sensor import measure_emva

    root = Path(folder)
    if not root.is_dir():
        raise InvalidInputError(f"expected FOLDER a folder of frames, got {folder!r}"[:200])
    layout = "manifest" if (root / MANIFEST).is_file() else "file names"
    entries = _manifest(root) if layout == "manifest" else _by_name(root)
    entries.sort(key=lambda e: e[0])
    given = [e[1] is not None for e in entries]
    if any(given) and not all(given):
        raise InvalidInputError(
            f"{root / MANIFEST}: photons given for some exposures only; give it for all or none"
        )
    flats, darks = [], []
    for i, (t, _, fl, dk) in enumerate(entries):
        if run.progress is not None:
            run.progress("reading frames", i / len(entries))
        flats.append(_read_stack(fl, opts, f"flat (time {t:g} s)"))
        darks.append(_read_stack(dk, opts, f"dark (time {t:g} s)"))
    times = np.array([e[0] for e in entries])
    photons = np.array([e[1] for e in entries], dtype=float) if all(given) else None
    m = measure_emva(
        flats,
        darks,
        times,
        photons=photons,
        fit_fraction=opts.fit_fraction,
        spatial_index=opts.spatial_index,
    )
    doc = {
        "format": "imageform-emva",
        "version": 1,
        "standard": "EMVA 1288 Release 4.0 Linear",
        "folder": root,
        "layout": layout,
        "exposures": len(entries),
        "frame_shape": list(flats[0].shape[1:]),
        "results": m,
    }
    write_json(run.file(out), doc)
    scalars = {
        k: getattr(m, k)
        for k in (
            "system_gain",
            "dark_noise",
            "quantum_efficiency",
            "saturation_capacity",
            "dynamic_range_db",
            "snr_max_db",
            "dsnu",
            "prnu",
            "dark_current",
        )
    }
    summary = {"folder": root, "output": out, "exposures": len(entries), **scalars}
    eta = "n/a (no photon counts)" if photons is None else f"{m.quantum_efficiency:.3f}"
    limit = " (upper limit: below quantisation)" if m.dark_noise_upper_limit else ""
    text = [
        f"EMVA 1288 from {len(entries)} exposures ({layout}) in {root}",
        f"  system gain K         {m.system_gain:.4g} DN/e- ({m.fit_points} points, 0-"
        f"{opts.fit_fraction:.0%} of saturation)",
        f"  temporal dark noise   {m.dark_noise:.3g} e-{limit}",
        f"  quantum efficiency    {eta}",
        f"  saturation capacity   {m.saturation_capacity:.4g} e- ({m.saturation_dn:.1f} DN)",
        f"  SNR max               {m.snr_max_db:.1f} dB",
        f"  dynamic range         {m.dynamic_range_db:.1f} dB ({m.dynamic_range_bits:.1f} bits)",
        f"  DSNU                  {m.dsnu:.3g} e-",
        f"  PRNU                  {m.prnu:.3g} %",
        f"  dark current          {m.dark_current:.3g} e-/s",
        f"wrote {out}",
    ]
    if not m.saturated:
        run.note(
            "note: the temporal variance peaks at the last exposure: the series may not reach "
            "saturation (saturation, SNR max and dynamic range are then lower bounds)"
        )
    return Result(summary, tuple(text))


WORKFLOWS = (
    Workflow(
        "emva",
        "EMVA 1288 characterisation (gain, noise, QE, DSNU, PRNU, ...) from a folder of frames.",
        "imageform.workflows.emva:emva",
        EmvaOptions,
        (
            Input(
                "folder",
                f"Folder of flat and dark frames: a {MANIFEST} manifest, or files named "
                "flat_<time>_<n>.tif / dark_<time>_<n>.tif (time in seconds).",
                kind="text",
                metavar="FOLDER",
            ),
        ),
        Output("Result to write (.json)."),
        suffixes=(".json",),
        group="sensor",
        description="At least two flat and two dark frames per exposure time; the gain is "
        "fitted from 0 to 70 % of saturation (the peak of the photon-transfer curve); DSNU "
        "and PRNU come from the stacks nearest 50 % of saturation (EMVA 1288 Release 4.0).",
    ),
)
