"""imageform.io: the one place where files are read and written.

Images (PNG 8/16-bit, JPEG, TIFF, ``.npy``) with one rule for shape, alpha, orientation and
memory bounds (:func:`read_image`, :func:`write_image`).
"""

from imageform.io.image_io import (
    DEFAULT_MAX_PIXELS,
    IMAGE_FORMATS,
    ImageInfo,
    WrittenImage,
    image_format,
    image_info,
    max_pixels,
    read_image,
    write_image,
)
from imageform.io.png import read_png, write_png

__all__ = [
    "DEFAULT_MAX_PIXELS",
    "IMAGE_FORMATS",
    "ImageInfo",
    "WrittenImage",
    "image_format",
    "image_info",
    "max_pixels",
    "read_image",
    "read_png",
    "write_image",
    "write_png",
]
