"""``imageform sfr``: the ISO 12233 slanted-edge SFR (MTF) of a photograph.

With ``--roi x,y,w,h`` one edge region is measured; without it the slanted edges of a chart
of dark squares are found (:func:`imageform.analysis.find_slanted_edges`) and every one is
measured (:func:`imageform.analysis.slanted_edge_sfr`). 8- and 16-bit images are decoded
from sRGB to linear values first unless ``--transfer linear`` (raw or linear files); a
16-bit grey image that declares no colour space (a detector's) is taken as linear. A raw
file (``.dng``, ``.nef``, ...; what ``imageform simulate --lab`` writes for its edge) is
measured on its mosaic, black level removed and the four photosites of the CFA balanced onto
the greens' levels (:func:`imageform.sensor.equalize_cfa`, as ``imageform characterize``
does): one channel, ``raw``, at the sensor's full sampling, without demosaicing. A DICOM
image (an X-ray detector's, a CT slice) is measured on its values after the Modality LUT,
taken as linear; its Imager Pixel Spacing (the detector's pitch, what IEC 62220-1-1's MTF is
given in), else its Pixel Spacing, turns cycles per pixel into line pairs per millimetre, as
``--pixel-pitch`` does for any image.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, get_args

from imageform.errors import InvalidInputError
from imageform.workflows._images import ImageIn, one_image_frame, read
from imageform.workflows._spec import Input, Output, Result, Run, Workflow, _describe, option

__all__ = ["WORKFLOWS", "SfrOptions"]


#: ``sfr --transfer``: the encoding of integer images.
_Transfer = Literal["auto", "srgb", "linear"]


@dataclass(frozen=True, kw_only=True)
class SfrOptions(ImageIn):
    """Options of ``imageform sfr``."""

    roi: str | None = option(
        None,
        help="Region x,y,w,h in pixels (column, row of its top-left pixel, width, height) "
        "holding one slanted edge; default: find the edges of a chart of dark squares.",
        metavar="X,Y,W,H",
    )
    transfer: _Transfer = option(
        "auto",
        help="Encoding of integer images: srgb (decoded to linear first) or linear; auto: "
        "srgb for photographs, linear for DICOM and raw files and for 16-bit grey images "
        "that declare no colour space (a detector's). Float images are taken as linear.",
        choices=get_args(_Transfer),
    )
    pixel_pitch: str | None = option(
        None,
        help="Pixel pitch (3.76um, 0.139mm; a bare number is in um): MTF50 and MTF10 also in "
        "line pairs per mm. Default: a DICOM's Imager Pixel Spacing (else Pixel Spacing).",
        metavar="LENGTH",
    )
    min_angle: float = option(
        2.0, help="Smallest edge angle (deg) kept by the edge finder.", minimum=0, maximum=40
    )
    max_angle: float = option(
        10.0, help="Largest edge angle (deg) kept by the edge finder.", minimum=0, maximum=40
    )

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

    def pitch_mm(self) -> float | None:
        """Return ``--pixel-pitch`` in millimetres, or None."""
        if self.pixel_pitch is None:
            return None
        from imageform._units import parse_length

        mm = parse_length(self.pixel_pitch, "--pixel-pitch", default_unit="um", unit="mm")
        if not 1e-4 * (1 - 1e-9) <= mm <= 10.0 * (1 + 1e-9):
            raise InvalidInputError(
                f"expected --pixel-pitch from 0.1um to 10mm (a camera's 1-10um, an X-ray "
                f"detector's 50-200um), got {self.pixel_pitch}"
            )
        return mm

    def check(self) -> None:
        """Check the options, the ``--roi`` and the ``--pixel-pitch``."""
        super().check()
        if self.min_angle > self.max_angle:
            raise InvalidInputError(
                f"expected --min-angle <= --max-angle, got {self.min_angle:g} > {self.max_angle:g}"
            )
        self.region()
        self.pitch_mm()


@dataclass(frozen=True)
class _Pitch:
    """The pixel pitch frequencies are scaled by: (between rows, between columns) in mm."""

    rows_mm: float
    cols_mm: float
    source: str

    def along(self, orientation: str) -> float:
        """Return the pitch across an edge: between columns for a vertical edge."""
        return self.cols_mm if orientation == "vertical" else self.rows_mm


def _dicom_pitch(image: Path) -> _Pitch | None:
    """Return a DICOM image's Imager Pixel Spacing, else its Pixel Spacing, else None."""
    from imageform.io import dicom_info

    d = dicom_info(image)
    for name, sp in (("imager pixel spacing", d.imager_pixel_spacing_mm),
                     ("pixel spacing", d.pixel_spacing_mm)):  # fmt: skip
        if sp is not None and sp[0] > 0 and sp[1] > 0:
            return _Pitch(float(sp[0]), float(sp[1]), f"the DICOM's {name}")
    return None


def _linear(img: Any, transfer: str) -> Any:
    import numpy as np

    from imageform.color import srgb_to_linear

    arr = img[..., 0] if img.shape[-1] == 1 else img[..., :3]
    if arr.dtype.kind == "f":
        return np.asarray(arr, dtype=np.float64)
    scale = 65535.0 if arr.dtype == np.uint16 else 255.0
    vals = arr.astype(np.float64) / scale
    return np.asarray(srgb_to_linear(vals)) if transfer == "srgb" else vals


def _detector_data(image: Path, fmt: str, img: Any) -> bool:
    """Whether ``--transfer auto`` takes ``img`` as a detector's linear values.

    A single-channel TIFF of 16 bits or more that declares no colour space (no ICC profile,
    no space in its description): what X-ray, neutron and microscope cameras write. sfrmat3
    takes its input as linear unless given an OECF; a developed photograph is colour or
    8-bit, or carries its space. Decoding such a file from sRGB changed MTF50 by 13 % on a
    neutron radiograph (0.0865 against 0.0991 cy/px). PNGs stay photographs (imageform's
    own 16-bit PNGs declare nothing).
    """
    import numpy as np

    from imageform.io import image_color_space

    grey = img.ndim == 2 or img.shape[-1] == 1
    if not grey or img.dtype.kind not in "ui" or np.dtype(img.dtype).itemsize < 2:
        return False
    if fmt != "tiff":
        return False
    return image_color_space(image).source == "none"


def _edge_image(
    run: Run, image: Path, opts: SfrOptions
) -> tuple[Any, tuple[str, ...] | None, str, _Pitch | None]:
    """Return the linear image, its channels, the transfer applied and the pixel pitch.

    The channel names are None where the SFR's own apply; the pitch None where unknown.

    A raw file: its mosaic less the black level, over the white level's span, with the CFA's
    photosites balanced (one channel, ``raw``); a monochrome raw its one channel (``raw``), a
    linear raw its three; ``--transfer`` does not apply to them. A DICOM image: its values
    after the Modality LUT, linear unless ``--transfer srgb``, its spacing the pitch.
    """
    from imageform.io import image_info
    from imageform.workflows._characterize_inputs import _RAW_SUFFIXES, _read_photo

    given = opts.pitch_mm()
    pitch = None if given is None else _Pitch(given, given, "--pixel-pitch")
    if image.suffix.lower() not in _RAW_SUFFIXES:
        img = read(image, opts)  # reads (and refuses) first: a missing file, a bad DICOM
        fmt = image_info(image, frame=opts.frame).format
        dicom = fmt == "dicom"
        if dicom and pitch is None:
            pitch = _dicom_pitch(image)
        transfer = opts.transfer
        if transfer == "auto":
            transfer = "linear" if dicom else "srgb"
            if not dicom and _detector_data(image, fmt, img):
                transfer = "linear"
                run.note(
                    f"note: {image.name} is a 16-bit grey TIFF that declares no colour space: "
                    "its values are taken as linear (a detector's); --transfer srgb if it is "
                    "a developed photograph"
                )
        return _linear(img, transfer), None, transfer, pitch
    from imageform.sensor import equalize_cfa

    one_image_frame(image, opts.frame)  # a raw file holds one image: --frame 0 or none
    # the raw branch of characterize's reader: black level removed, scaled to 1 at white
    im = _read_photo(image, {}, "linear", opts.max_pixels, None)
    if im.mosaic is None:  # a monochrome or linear raw: its linear values as they are
        import numpy as np

        lin = np.asarray(im.linear)
        return (lin[..., 0], ("raw",), "linear", pitch) if im.grey else (lin, None, "linear", pitch)
    assert im.cfa is not None
    return equalize_cfa(im.mosaic, im.cfa), ("raw",), "linear", pitch


def sfr(run: Run, opts: SfrOptions, *, out: Path | None, image: Path) -> Result:
    """``imageform sfr``: MTF50/MTF10 per edge and channel; ``-o`` writes the SFR curves."""
    from rich.table import Table

    from imageform.analysis import find_slanted_edges, slanted_edge_sfr
    from imageform.workflows._tables import write_table

    image = Path(image)
    arr, names, transfer, pitch = _edge_image(run, image, opts)
    roi = opts.region()
    if roi is not None:
        h, w = arr.shape[:2]
        x, y, rw, rh = roi
        if x < 0 or y < 0 or x + rw > w or y + rh > h:
            raise InvalidInputError(
                f"expected --roi x,y,w,h inside the {w}x{h} image {image.name}, got {opts.roi}"
            )
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
    cols = ["edge", "x,y,w,h", "angle", "channel", "MTF50", "MTF10"]
    if pitch is not None:
        cols += ["MTF50 lp/mm", "MTF10 lp/mm"]
    for col in cols:
        t.add_column(col, justify="right")
    for k, (reg, side) in enumerate(regions):
        res = slanted_edge_sfr(arr, reg)
        channels = names or res.channels
        # one cycle per pixel is one line pair over the pitch across the edge
        per_mm = None if pitch is None else pitch.along(res.orientation)
        chans: dict[str, dict[str, float]] = {}
        for i, c in enumerate(channels):
            m50, m10 = float(res.mtf50[i]), float(res.mtf10[i])
            chans[c] = {"mtf50": m50, "mtf10": m10}
            cells = [str(k), ",".join(str(v) for v in reg), f"{res.angle:.2f}", c]
            cells += [f"{m50:.4f}", f"{m10:.4f}"]
            if per_mm is not None:
                chans[c] |= {"mtf50_lp_per_mm": m50 / per_mm, "mtf10_lp_per_mm": m10 / per_mm}
                cells += [f"{m50 / per_mm:.3f}", f"{m10 / per_mm:.3f}"]
            t.add_row(*cells)
            for f, v in zip(res.frequency, res.sfr[:, i], strict=True):
                rows.append([k, c, f, v] + ([f / per_mm] if per_mm is not None else []))
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
    if out is not None:
        head_cols: tuple[str, ...] = ("edge", "channel", "frequency_cy_per_px", "sfr")
        if pitch is not None:
            head_cols += ("frequency_lp_per_mm",)
        write_table(run.file(out), head_cols, rows)
    summary: dict[str, Any] = {"image": str(image), "transfer": transfer, "edges": edges}
    head = f"{len(edges)} edge(s) measured" + (f" -> {out}" if out is not None else "")
    if pitch is not None:
        summary["pixel_pitch_mm"] = {
            "rows": pitch.rows_mm,
            "columns": pitch.cols_mm,
            "source": pitch.source,
        }
        size = (
            f"{pitch.rows_mm * 1000:g} um"
            if pitch.rows_mm == pitch.cols_mm
            else f"{pitch.rows_mm * 1000:g} um between rows, {pitch.cols_mm * 1000:g} um "
            "between columns"
        )
        head += f"; pixel pitch {size} ({pitch.source})"
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
                "A photograph of a slanted edge or an SFR chart (PNG, TIFF, .npy, a DICOM "
                "image, or a raw file such as .dng: measured on its mosaic).",
            ),
        ),
        Output(
            "CSV to write: edge, channel, frequency (cycles/pixel), SFR (and the frequency in "
            "lp/mm where the pixel pitch is known).",
            required=False,
        ),
        suffixes=(".csv",),
        group="optics",
        description="Without --roi the edges of a chart of dark squares turned a few degrees "
        "are found and each is measured (an image that is one edge crop is measured whole). "
        "Frequencies are in cycles/pixel along the edge normal (Nyquist 0.5). Integer "
        "images are decoded from sRGB to linear first unless --transfer linear (16-bit grey "
        "images that declare no colour space are taken as linear). A raw file "
        "is measured on its mosaic (black level removed, the CFA's photosites balanced on a "
        "neutral edge): one channel, raw. A DICOM image is measured on its values (after the "
        "Modality LUT) as linear, and its Imager Pixel Spacing (else Pixel Spacing) gives "
        "MTF50 and MTF10 in line pairs per mm, as --pixel-pitch does for any image.",
    ),
)
