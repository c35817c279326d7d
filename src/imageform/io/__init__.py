"""imageform.io: image reading and writing (8/16-bit PNG, float TIFF, .npy)."""

from imageform.io.image_io import IMAGE_FORMATS, image_format, read_image, write_image
from imageform.io.png import read_png, write_png

__all__ = ["IMAGE_FORMATS", "image_format", "read_image", "read_png", "write_image", "write_png"]
