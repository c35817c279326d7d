r"""What a photograph's EXIF says about the camera that took it, and its focal length in pixels.

A phone's or a camera's JPEG (HEIF, WebP, TIFF, PNG) records the lens's focal length in
millimetres and, mostly, its 35 mm equivalent (Exif 2.3, tags FocalLength and
FocalLengthIn35mmFilm). The focal length in pixels, the f of the intrinsic matrix K, follows
from the 35 mm equivalent :math:`f_{35}` and the image's diagonal :math:`d` in pixels:
:math:`f_{px} = f_{35}\, d / 43.27` (43.27 mm is the diagonal of the 36 x 24 mm frame: the
equivalent focal length gives the same field of view on it, along the diagonal, as cameras
compute it). It holds for a resized image (the diagonal scales with it), not for a cropped
one.

The focal-plane resolution (FocalPlaneXResolution, pixels per unit on the sensor) would give
it from the focal length in millimetres too, but it describes the camera's own image: an
editor that resizes the file keeps it (and often rewrites PixelXDimension to the new width),
so on resized photographs it is off by the resize factor. On the vanishing-point
benchmark's photographs (``benchmarks/check_exif_focal.py``,
``benchmarks/results/exif-focal-2026-11-30a.md``) the 35 mm equivalent is within 0.2 % of
the two focal lengths known from the sensor's width on the data sheet (a Nikon D750 at 35 mm,
778 against 780 px; a Panasonic DMC-FZ7 at 6 mm, 2080 against 2080 px), while the focal-plane
resolution gives 2.7 to 9.2 times the known focal length on the four resized photographs
that carry it: it is not used.

The result is an estimate (a crop, a digital zoom, a lens's focus breathing move it): a prior
and a check for K, not a calibration.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from imageform.errors import InvalidInputError

__all__ = ["FULL_FRAME_DIAGONAL_MM", "ExifCamera", "exif_camera"]

#: The diagonal of the 36 x 24 mm frame the 35 mm equivalent focal length refers to, in mm.
FULL_FRAME_DIAGONAL_MM = math.hypot(36.0, 24.0)

_EXIF_IFD = 0x8769
_MAKE, _MODEL = 0x010F, 0x0110
_EXPOSURE_TIME, _F_NUMBER, _ISO = 0x829A, 0x829D, 0x8827
_FOCAL_LENGTH, _FOCAL_35MM = 0x920A, 0xA405
_LENS_MODEL = 0xA434


@dataclass(frozen=True)
class ExifCamera:
    """A photograph's camera as its EXIF records it (:func:`exif_camera`).

    Attributes
    ----------
    found : bool
        Whether the file holds EXIF with any of the fields below.
    make, model, lens_model : str or None
        The camera's maker and model, the lens's model.
    focal_length_mm : float or None
        The lens's focal length (FocalLength).
    equivalent_focal_length_mm : float or None
        Its 35 mm equivalent (FocalLengthIn35mmFilm).
    f_number : float or None
        The aperture's f-number.
    exposure_time_s : float or None
        The exposure time.
    iso : int or None
        The ISO speed (ISOSpeedRatings / PhotographicSensitivity).
    width_px, height_px : int
        The image's size as read (upright: after its EXIF orientation).
    focal_length_px : float or None
        The focal length in pixels of this image, estimated from the 35 mm equivalent (see
        the module's notes); None without one.
    focal_length_px_source : str or None
        ``"35 mm equivalent"`` (None without an estimate).
    """

    found: bool
    make: str | None
    model: str | None
    lens_model: str | None
    focal_length_mm: float | None
    equivalent_focal_length_mm: float | None
    f_number: float | None
    exposure_time_s: float | None
    iso: int | None
    width_px: int
    height_px: int
    focal_length_px: float | None
    focal_length_px_source: str | None

    def describe(self) -> str:
        """Return one line naming the camera and the exposure, for a report."""
        who = " ".join(s for s in (self.make, self.model) if s) or "camera not named"
        if self.lens_model:
            who += f", {self.lens_model}"
        parts = []
        if self.focal_length_mm is not None:
            eq = self.equivalent_focal_length_mm
            parts.append(f"{self.focal_length_mm:g} mm" + (f" (35 mm equivalent {eq:g} mm)"
                                                          if eq else ""))  # fmt: skip
        elif self.equivalent_focal_length_mm is not None:
            parts.append(f"35 mm equivalent {self.equivalent_focal_length_mm:g} mm")
        if self.f_number is not None:
            parts.append(f"f/{self.f_number:g}")
        if self.exposure_time_s is not None:
            t = self.exposure_time_s
            parts.append(f"1/{1 / t:.0f} s" if 0 < t < 0.5 else f"{t:g} s")
        if self.iso is not None:
            parts.append(f"ISO {self.iso}")
        return who + ("; " + ", ".join(parts) if parts else "")


def _real(value: object) -> float | None:
    """Return an EXIF value (a rational, an int, a 1-tuple) as a positive finite float."""
    if isinstance(value, tuple | list):
        value = value[0] if value else None
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError, ZeroDivisionError):
        return None
    return v if math.isfinite(v) and v > 0 else None


def _text(value: object) -> str | None:
    if isinstance(value, bytes):
        value = value.decode("latin-1", "replace")
    if not isinstance(value, str):
        return None
    s = value.strip("\x00 ").strip()
    return s or None


def exif_camera(path: str | Path) -> ExifCamera:
    r"""Return what a photograph's EXIF says about its camera, and its focal length in pixels.

    Parameters
    ----------
    path : str or Path
        A JPEG, HEIF, WebP, TIFF or PNG file (any image :func:`imageform.io.read_image`
        reads; formats without EXIF give ``found=False``).

    Returns
    -------
    ExifCamera
        ``found=False`` (every field None) for a file without EXIF. ``focal_length_px`` is
        :math:`f_{35}\,\sqrt{w^2 + h^2} / 43.27` from the 35 mm equivalent.

    Raises
    ------
    InvalidInputError
        A missing file or one that is no image.

    Examples
    --------
    A 4000 x 3000 photograph at a 26 mm equivalent: f = 26 x 5000 / 43.27 = 3004.6 px.

    >>> import tempfile, pathlib, numpy as np
    >>> from PIL import Image
    >>> ex = Image.Exif()
    >>> ex.get_ifd(0x8769).update({0xA405: 26, 0x920A: 4.3})
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "phone.jpg"
    >>> Image.fromarray(np.zeros((3000, 4000, 3), np.uint8)).save(p, exif=ex)
    >>> cam = exif_camera(p)
    >>> round(cam.focal_length_px, 1), cam.focal_length_px_source
    (3004.6, '35 mm equivalent')
    """
    from imageform.io.image_io import _existing, _pillow_open, image_info

    p = _existing(path)
    info = image_info(p, frame=0)  # refuses what is no image; a stack: its first image
    w, h = int(info.width), int(info.height)
    none = ExifCamera(False, None, None, None, None, None, None, None, None, w, h, None, None)
    if info.format not in ("jpeg", "tiff", "webp", "png", "heif"):
        return none
    try:
        with _pillow_open(p) as im:
            ex = im.getexif()
            sub = dict(ex.get_ifd(_EXIF_IFD))
            top = dict(ex)
    except InvalidInputError:
        raise
    except Exception:  # Pillow cannot open it (an npy, a DICOM): no EXIF
        return none
    if not sub and not top:
        return none

    def get(tag: int) -> object:
        return sub.get(tag, top.get(tag))

    focal = _real(get(_FOCAL_LENGTH))
    eq = _real(get(_FOCAL_35MM))
    iso_v = _real(get(_ISO))
    f_px: float | None = None
    source: str | None = None
    if eq is not None:
        f_px = eq * math.hypot(w, h) / FULL_FRAME_DIAGONAL_MM
        source = "35 mm equivalent"
    make, model = _text(get(_MAKE)), _text(get(_MODEL))
    found = any(v is not None for v in (make, model, focal, eq, iso_v, _real(get(_F_NUMBER))))
    return ExifCamera(
        found=found,
        make=make,
        model=model,
        lens_model=_text(get(_LENS_MODEL)),
        focal_length_mm=focal,
        equivalent_focal_length_mm=eq,
        f_number=_real(get(_F_NUMBER)),
        exposure_time_s=_real(get(_EXPOSURE_TIME)),
        iso=int(iso_v) if iso_v is not None else None,
        width_px=w,
        height_px=h,
        focal_length_px=f_px,
        focal_length_px_source=source,
    )
