"""DICOM files read by imageform against pydicom's own decoding, on every file pydicom ships.

Run::

    PYTHONPATH=src python benchmarks/check_dicom.py

Files: the ``.dcm`` files of ``pydicom/data/test_files`` in the installed pydicom wheel (MIT
licence; CT, MR, RT, secondary captures in every transfer syntax pydicom tests, some broken on
purpose). For each: ``read_image`` (``read_dicom(frame=0)`` for a multi-frame file) against
the reference built from pydicom alone: ``dcmread(...).pixel_array`` (frame 0), through
``apply_modality_lut`` for grey images or ``apply_color_lut`` for palette ones, a bilevel
image as 0/255 and MONOCHROME1 inverted over its stored range (``f(lo) + f(hi) - v``):
imageform's documented rules. A file both refuse is listed with imageform's one line; "equal"
means every value is the same.
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks._common import header, markdown_table
from imageform.io import dicom_info, read_dicom, read_image


def _reference(path: Path) -> np.ndarray:
    """Frame 0 as pydicom decodes it, through its LUTs, in MONOCHROME2's sense."""
    import pydicom
    from pydicom.pixels import apply_color_lut, apply_modality_lut

    ds = pydicom.dcmread(path)
    arr = np.asarray(ds.pixel_array)
    if int(ds.get("NumberOfFrames", 1) or 1) > 1:
        arr = arr[0]
    photometric = str(ds.PhotometricInterpretation)
    if photometric == "PALETTE COLOR":
        return np.asarray(apply_color_lut(arr, ds))
    if int(ds.get("SamplesPerPixel", 1)) != 1:
        return arr
    if int(ds.BitsAllocated) == 1:  # bilevel: 0/255, as imageform reads a bilevel TIFF
        arr = arr * 255
    out = np.asarray(apply_modality_lut(arr, ds), dtype=np.float64)
    if photometric == "MONOCHROME1":
        bits = int(ds.BitsStored)
        signed = int(ds.get("PixelRepresentation", 0)) == 1
        lo, hi = (-(2 ** (bits - 1)), 2 ** (bits - 1) - 1) if signed else (0, 2**bits - 1)
        ends = apply_modality_lut(np.array([lo, hi]), ds).astype(np.float64)
        out = ends.sum() - out
    return out[..., None]


def _text(value: Any, width: int = 90) -> str:
    """One table cell: no pipes, no square brackets (mkdocs reads them as links)."""
    s = str(value).replace("|", "/").replace("[", "(").replace("]", ")").replace("\n", " ")
    return s if len(s) <= width else s[: width - 3] + "..."


def main() -> None:
    import pydicom

    folder = Path(pydicom.__file__).parent / "data" / "test_files"
    rows = []
    counts = {
        "equal": 0,
        "differ": 0,
        "both refuse": 0,
        "imageform refuses": 0,
        "only pydicom refuses": 0,
    }
    for path in sorted(folder.glob("*.dcm")):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                ref: np.ndarray | None = _reference(path)
                ref_err = ""
            except Exception as exc:
                ref, ref_err = None, f"{type(exc).__name__}"
            try:
                info = dicom_info(path)
                got = read_dicom(path, frame=0) if info.frames > 1 else read_image(path)
                err, what = "", f"{info.photometric}, {info.frames} frame(s)"
                syntax = info.transfer_syntax
            except Exception as exc:
                got, err, what, syntax = None, str(exc).split(": ", 1)[-1], "", ""
        if got is not None and ref is not None:
            same = got.shape == ref.shape and np.array_equal(got, ref)
            outcome = "equal" if same else "differ"
            shown = f"{' x '.join(map(str, got.shape))} {got.dtype}"
        elif got is None and ref is None:
            outcome, shown = "both refuse", err
        elif got is None:
            outcome, shown = "imageform refuses", err
        else:
            outcome, shown = "only pydicom refuses", ref_err
        counts[outcome] += 1
        rows.append((path.name, _text(syntax, 40), _text(what, 40), outcome, _text(shown)))
    print(header("DICOM: imageform against pydicom on pydicom's test files"))
    print(f"pydicom {pydicom.__version__}; {len(rows)} files: "
          + ", ".join(f"{k} {v}" for k, v in counts.items()) + ".\n")  # fmt: skip
    print(markdown_table(("file", "transfer syntax", "image", "outcome", "imageform"), rows))


if __name__ == "__main__":
    main()
