"""imageform.io: the one place where files are read and written.

Images (PNG 8/16-bit, JPEG, TIFF, ``.npy``) with one rule for shape, alpha, orientation and
memory bounds (:func:`read_image`, :func:`write_image`); the one camera file, versioned TOML
(:func:`read_camera`, :func:`write_camera`, docs/camera-file.md).
"""

from imageform.io.camera_file import (
    CAMERA_FILE_FORMAT,
    CAMERA_FILE_VERSION,
    DISTORTION_MODELS,
    CameraFile,
    Provenance,
    read_camera,
    write_camera,
)
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
    "CAMERA_FILE_FORMAT",
    "CAMERA_FILE_VERSION",
    "DEFAULT_MAX_PIXELS",
    "DISTORTION_MODELS",
    "IMAGE_FORMATS",
    "CameraFile",
    "ImageInfo",
    "Provenance",
    "WrittenImage",
    "image_format",
    "image_info",
    "max_pixels",
    "read_camera",
    "read_image",
    "read_png",
    "write_camera",
    "write_image",
    "write_png",
]
