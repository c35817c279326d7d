"""``imageform sfr``: the ISO 12233 slanted-edge SFR (MTF) of a photograph.

With ``--roi x,y,w,h`` one edge region is measured; without it the slanted edges of a chart
of dark squares are found (:func:`imageform.analysis.find_slanted_edges`) and every one is
measured (:func:`imageform.analysis.slanted_edge_sfr`). 8- and 16-bit images are decoded
from sRGB to linear values first unless ``--transfer linear`` (raw or linear files). A raw
file (``.dng``, ``.nef``, ...; what ``imageform simulate --lab`` writes for its edge) is
measured on its mosaic, black level removed and the four photosites of the CFA balanced onto
the greens' levels (:func:`imageform.sensor.equalize_cfa`, as ``imageform characterize``
does): one channel, ``raw``, at the sensor's full sampling, without demosaicing.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, get_args

from imageform.errors import InvalidInputError
from imageform.workflows._images import ImageIn, read
from imageform.workflows._spec import Input, Output, Result, Run, Workflow, _describe, option

__all__ = ["WORKFLOWS", "SfrOptions"]


#: ``sfr --transfer``: the encoding of integer images.
_Transfer = Literal["srgb", "linear"]


@dataclass(frozen=True, kw_only=True)
class SfrOptions(ImageIn):
    """Options of ``imageform sfr``."""

    roi: str | None = option(
        None,
        help="Region x,y,w,h (column, row of its top-left pixel, width, height) holding one "
        "slanted edge; default: find the edges of a chart of dark squares.",
        metavar="X,Y,W,H",
    )
    transfer: _Transfer = option(
        "srgb",
        help="Encoding of integer images: srgb (decoded to linear first) or linear. Float "
        "images are taken as linear.",
        choices=get_args(_Transfer),
    )
    min_angle: float = option(2.0, help="Smallest edge angle (deg) kept by the edge finder.")
    max_angle: float = option(10.0, help="Largest edge angle (deg) kept by the edge finder.")

    def region(self) -> tuple[int, int, int, int] | None:
        """Return the ``--roi`` as four integers, or None."""
        if self.roi is None:
            return None
        parts = str(self.roi).replace(" ", "").split(",")
        try:
            vals = tuple(int(p) for p in parts)
        except ValueError:
            vals = ()
        if len(vals) != 4 or vals[2] < 1 or vals[3] < 1 or vals[0] < 0 or vals[1] < 0:
            raise InvalidInputError(
                f"expected --roi as x,y,w,h (4 integers, w and h >= 1), got {_describe(self.roi)}"
            )
        return (vals[0], vals[1], vals[2], vals[3])

    def check(self) -> None:
        """Check the options and the ``--roi``."""
        super().check()
        self.region()


def _linear(img: Any, transfer: str) -> Any:
    import numpy as np

    from imageform.color import srgb_to_linear

    arr = img[..., 0] if img.shape[-1] == 1 else img[..., :3]
    if arr.dtype.kind == "f":
        return np.asarray(arr, dtype=np.float64)
    scale = 65535.0 if arr.dtype == np.uint16 else 255.0
    vals = arr.astype(np.float64) / scale
    return np.asarray(srgb_to_linear(vals)) if transfer == "srgb" else vals


def _edge_image(image: Path, opts: SfrOptions) -> tuple[Any, tuple[str, ...] | None]:
    """Return the linear image to measure and its channel names (None: the SFR's own).

    A raw file: its mosaic less the black level, over the white level's span, with the CFA's
    photosites balanced (one channel, ``raw``); a monochrome raw its one channel (``raw``), a
    linear raw its three; ``--transfer`` does not apply to them.
    """
    from imageform.workflows._characterize_inputs import _RAW_SUFFIXES, _read_photo

    if image.suffix.lower() not in _RAW_SUFFIXES:
        return _linear(read(image, opts), opts.transfer), None
    from imageform.sensor import equalize_cfa

    # the raw branch of characterize's reader: black level removed, scaled to 1 at white
    im = _read_photo(image, {}, "linear", opts.max_pixels, None)
    if im.mosaic is None:  # a monochrome or linear raw: its linear values as they are
        import numpy as np

        lin = np.asarray(im.linear)
        return (lin[..., 0], ("raw",)) if im.grey else (lin, None)
    assert im.cfa is not None
    return equalize_cfa(im.mosaic, im.cfa), ("raw",)


def sfr(run: Run, opts: SfrOptions, *, out: Path | None, image: Path) -> Result:
    """``imageform sfr``: MTF50/MTF10 per edge and channel; ``-o`` writes the SFR curves."""
    from rich.table import Table

    from imageform.analysis import find_slanted_edges, slanted_edge_sfr
    from imageform.workflows._tables import write_table

    image = Path(image)
    arr, names = _edge_image(image, opts)
    roi = opts.region()
    if roi is not None:
        regions = [(roi, "roi")]
    else:
        found = find_slanted_edges(arr, min_angle=opts.min_angle, max_angle=opts.max_angle)
        if not found:
            raise InvalidInputError(
                f"no slanted edge found in {image} (neither dark squares turned "
                f"{opts.min_angle:g}-{opts.max_angle:g} deg on a lighter surround nor one such "
                "edge across the whole image); give one with --roi x,y,w,h"
            )
        regions = [(r.roi, r.side) for r in found]
    edges: list[dict[str, Any]] = []
    rows: list[list[Any]] = []
    t = Table(title=f"Slanted-edge SFR of {image.name} (cycles/pixel)")
    for col in ("edge", "x,y,w,h", "angle", "channel", "MTF50", "MTF10"):
        t.add_column(col, justify="right")
    for k, (reg, side) in enumerate(regions):
        res = slanted_edge_sfr(arr, reg)
        channels = names or res.channels
        chans = {
            c: {"mtf50": float(res.mtf50[i]), "mtf10": float(res.mtf10[i])}
            for i, c in enumerate(channels)
        }
        edges.append(
            {
                "edge": k,
                "roi": list(reg),
                "side": side,
                "angle_deg": res.angle,
                "orientation": res.orientation,
                "channels": chans,
            }
        )
        for i, c in enumerate(channels):
            t.add_row(
                str(k),
                ",".join(str(v) for v in reg),
                f"{res.angle:.2f}",
                c,
                f"{res.mtf50[i]:.4f}",
                f"{res.mtf10[i]:.4f}",
            )
            rows += [[k, c, f, s] for f, s in zip(res.frequency, res.sfr[:, i], strict=True)]
    if out is not None:
        write_table(run.file(out), ("edge", "channel", "frequency_cy_per_px", "sfr"), rows)
    transfer = opts.transfer if names is None else "linear"  # a raw mosaic is linear
    summary = {"image": str(image), "transfer": transfer, "edges": edges}
    head = f"{len(edges)} edge(s) measured" + (f" -> {out}" if out is not None else "")
    return Result(summary, (head, t))


WORKFLOWS = (
    Workflow(
        "sfr",
        "Slanted-edge SFR (ISO 12233 e-SFR): MTF50, MTF10 and the MTF curves of a photograph.",
        "imageform.workflows.sharpness:sfr",
        SfrOptions,
        (
            Input(
                "image",
                "A photograph of a slanted edge or an SFR chart (PNG, TIFF, .npy, or a raw "
                "file such as .dng: measured on its mosaic).",
            ),
        ),
        Output("CSV to write: edge, channel, frequency (cycles/pixel), SFR.", required=False),
        suffixes=(".csv",),
        group="optics",
        description="Without --roi the edges of a chart of dark squares turned a few degrees "
        "are found and each is measured (an image that is one edge crop is measured whole). "
        "Frequencies are in cycles/pixel along the edge normal (Nyquist 0.5). Integer "
        "images are decoded from sRGB to linear first unless --transfer linear. A raw file "
        "is measured on its mosaic (black level removed, the CFA's photosites balanced on a "
        "neutral edge): one channel, raw.",
    ),
)
