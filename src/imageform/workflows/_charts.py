"""Chart arguments of the colour commands: the one place that turns a file into patches.

``imageform fit-correction``, ``imageform harmonize --chart`` and
``imageform white-balance --method chart`` take a chart as

- a CSV of patch values (columns ``a_r,a_g,a_b``, optionally the reference's
  ``b_r,b_g,b_b`` and the 0-based ``patch`` index, as ``imageform chart --csv`` writes), or
- an image: a chart cropped to fill the frame, or a photograph with a ColorChecker anywhere
  in it, found as ``--chart-layout`` says (:func:`imageform.analysis.sample_chart`).

:func:`read_chart` reads either; :func:`write_overlay` draws what was sampled (the chart's
outline, the sampled boxes: green used, red left out, a cross on patch 0).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, get_args

from imageform.errors import InvalidInputError
from imageform.workflows._images import read

__all__ = [
    "CHART_LAYOUTS",
    "CHART_LAYOUT_HELP",
    "ChartInput",
    "notes",
    "read_chart",
    "summary",
    "write_overlay",
]

#: Values of ``--chart-layout`` (as :data:`imageform.analysis.CHART_LAYOUTS`).
ChartLayout = Literal["auto", "cropped", "detect"]
CHART_LAYOUTS: tuple[str, ...] = get_args(ChartLayout)
CHART_LAYOUT_HELP = (
    "How the chart is found in an image: auto (a chart cropped to fill the frame when its "
    "grid validates, else a ColorChecker detected anywhere in the photograph), cropped, detect."
)
_A = ("a_r", "a_g", "a_b")
_B = ("b_r", "b_g", "b_b")


@dataclass(frozen=True)
class ChartInput:
    """A chart argument read: its patches, and where they came from."""

    path: Path
    #: ChartPatches of the chart (encoded sRGB means, row by row).
    patches: Any
    #: The reference's values of the same patches (``b_*`` columns of a CSV), or None.
    reference: Any = None
    #: The ChartSample of an image (None for a CSV).
    sample: Any = None
    #: The image (None for a CSV), for the overlay.
    image: Any = None

    @property
    def layout(self) -> str:
        """``"csv"``, ``"cropped"`` or ``"detect"``."""
        return "csv" if self.sample is None else str(self.sample.layout)


def _read_csv(path: Path, n_patches: int) -> tuple[Any, Any]:
    """ChartPatches of the ``a_*`` columns and the ``b_*`` values (or None)."""
    import csv

    import numpy as np

    from imageform.analysis import ChartPatches

    with path.open(newline="") as fh:
        reader = csv.DictReader(fh)
        names = reader.fieldnames or []
        missing = [c for c in _A if c not in names]
        if missing:
            raise InvalidInputError(
                f"expected CSV columns {','.join(_A + _B)} in {path} (b_* optional); missing "
                f"{','.join(missing)}"
            )
        has_b = all(c in names for c in _B)
        cols = _A + _B if has_b else _A
        try:
            rows = [[float(r[c]) for c in cols] for r in reader]
            fh.seek(0)
            idx = [int(r["patch"]) for r in csv.DictReader(fh)] if "patch" in names else None
        except (TypeError, ValueError) as exc:
            raise InvalidInputError(f"non-numeric value in {path}: {exc}") from None
    if not rows:
        raise InvalidInputError(f"{path} holds no patch rows")
    arr = np.asarray(rows, dtype=np.float64).reshape((-1, len(cols)))
    if idx is None:
        n = len(arr)
        full = arr
        present = np.ones(n, dtype=bool)
    else:
        n = max(n_patches, max(idx) + 1)
        if min(idx) < 0 or len(set(idx)) != len(idx):
            raise InvalidInputError(
                f"expected distinct patch indices >= 0 in the patch column of {path}"
            )
        full = np.full((n, len(cols)), np.nan)
        full[idx] = arr
        present = np.zeros(n, dtype=bool)
        present[idx] = True
    means = np.where(present[:, None], full[:, :3], 0.0)  # absent rows: flagged missing
    zeros = np.zeros(n, dtype=bool)
    pat = ChartPatches(means, np.zeros((n, 3)), zeros, ~present)
    ref = np.where(present[:, None], full[:, 3:], 0.0) if has_b else None
    return pat, ref


def read_chart(
    path: Path,
    opts: Any,
    *,
    flag: str,
    layout: str = "auto",
    rows: int = 4,
    cols: int = 6,
    image: Any = None,
    run: Any = None,
) -> ChartInput:
    """Read the chart argument ``flag`` (e.g. ``--chart``).

    A CSV of patch values or an image (``image``: the array already read from ``path``),
    sampled as ``layout`` says. With ``run``, an image's patch means are brought to sRGB from
    the space the options' ``--from`` names or the file declares (``patches_in_srgb``); without,
    they stay in the file's own encoding.
    """
    import warnings

    from imageform.analysis import ChartNotFoundError, ChartWarning, sample_chart

    path = Path(path)
    if path.suffix.lower() == ".csv":
        pat, ref = _read_csv(path, rows * cols)
        return ChartInput(path, pat, ref)
    img = read(path, opts, colours=True) if image is None else image
    if img.ndim != 3 or img.shape[-1] != 3:
        raise InvalidInputError(
            f"{flag} {path}: expected an RGB image with a chart, got shape {img.shape}"
        )
    try:
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", category=ChartWarning)
            sample = sample_chart(img, layout, rows=rows, cols=cols, name=f"{flag} {path}")
    except ChartNotFoundError as exc:
        why = {
            "auto": ", neither filling the frame nor anywhere in the photograph",
            "detect": " anywhere in the photograph",
        }.get(layout, "")
        hint = "" if layout == "cropped" else "pass --chart-layout cropped for a cropped chart, or "
        if (rows, cols) != (4, 6):
            raise InvalidInputError(f"{flag} {path}: {exc}") from None
        raise ChartNotFoundError(
            f"no ColorChecker found in {flag} {path}{why}; {hint}give the patch values as a CSV"
        ) from None
    except InvalidInputError as exc:  # layout cropped: the grid holds no flat patch
        raise InvalidInputError(f"{flag} {path}: {exc}") from None
    patches = sample.patches
    if run is not None:
        from imageform.workflows._images import input_space, patches_in_srgb

        patches = patches_in_srgb(patches, input_space(run, path, opts))
    return ChartInput(path, _filled(patches), None, sample, img)


def _filled(pat: Any) -> Any:
    """Return the patches with the means of empty (missing) patches set to 0, not NaN.

    The fit leaves them out, and the report's colour conversions take finite values only.
    """
    import numpy as np

    from imageform.analysis import ChartPatches

    means = np.where(np.isfinite(pat.means), pat.means, 0.0)
    return ChartPatches(means, pat.std, pat.saturated, pat.missing, pat.used)


def notes(run: Any, chart: ChartInput, flag: str) -> None:
    """One note per flagged patch kind (saturated / missing), and the layout used."""
    import numpy as np

    p = chart.patches
    for what, mask in (("saturated", p.saturated), ("missing", p.missing)):
        idx = np.flatnonzero(mask)
        if idx.size:
            run.note(f"note: {flag} {chart.path}: {what} patch(es) {idx.tolist()} left out")


def write_overlay(run: Any, path: Path, chart: ChartInput, flag: str) -> None:
    """Write the image with the sampled chart drawn.

    Outline (yellow), sampled boxes (green used, red left out), a white cross on patch 0
    (dark skin, top left of the upright chart).
    """
    import numpy as np

    from imageform.io import write_image
    from imageform.workflows.chart import _draw, _scale

    if chart.sample is None:
        raise InvalidInputError(f"an overlay needs {flag} as an image, got the CSV {chart.path}")
    s = chart.sample
    out = np.array(chart.image, dtype=np.float64, copy=True) / _scale(chart.image)
    valid = s.patches.valid
    _draw(out, [s.outline], (1.0, 0.9, 0.0))
    _draw(out, [q for q, ok in zip(s.quads, valid, strict=True) if ok], (0.0, 1.0, 0.2))
    _draw(out, [q for q, ok in zip(s.quads, valid, strict=True) if not ok], (1.0, 0.0, 0.0))
    c = s.centers[0]
    r = 0.25 * float(np.linalg.norm(s.quads[0][1] - s.quads[0][0]))
    _draw(
        out,
        [np.array([c - [r, 0], c + [r, 0]]), np.array([c - [0, r], c + [0, r]])],
        (1.0, 1.0, 1.0),
    )
    write_image(run.file(path), np.round(np.clip(out, 0, 1) * 255).astype(np.uint8))


def summary(chart: ChartInput) -> dict[str, Any]:
    """Return what a command's JSON says about a chart argument."""
    d: dict[str, Any] = {
        "path": chart.path,
        "layout": chart.layout,
        "patches": len(chart.patches.means),
        "patches_valid": int(chart.patches.valid.sum()),
    }
    if chart.sample is not None:
        d["outline"] = chart.sample.outline.tolist()
        if chart.sample.detection is not None:
            d["score"] = chart.sample.detection.score
            d["rotation_degrees"] = chart.sample.detection.rotation
            d["mirrored"] = chart.sample.detection.mirrored
    return d
