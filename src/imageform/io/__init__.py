"""imageform.io: the one place where files are read and written.

Images (PNG 8/16-bit, JPEG, TIFF, ``.npy``, Netpbm, PFM; more formats read: WebP, BMP, GIF,
TGA, QOI, ICO, Radiance HDR, HEIF) with one rule for shape, alpha, orientation and
memory bounds (:func:`read_image`, :func:`write_image`), one image of a stack or an animation
(``frame=``, :func:`image_frames`), and the colour space a file
declares in its ICC profile or tags, PNG's ``gAMA``/``cHRM`` included
(:func:`image_color_space`); raw files (:func:`write_dng`,
:func:`read_raw`, :func:`develop`, docs/raw.md); the one camera file, versioned TOML
(:func:`read_camera`, :func:`write_camera`, docs/camera-file.md); video files, image
sequences and capture devices (:func:`open_video`, :class:`VideoWriter`, PyAV), interlaced
video (:func:`detect_interlacing`, :func:`split_fields`, :func:`field_camera_matrix`); DICOM images
through pydicom (:func:`read_dicom`, :func:`dicom_info`, :func:`dicom_window`, the ``dicom``
extra).
"""

from imageform.io.camera_file import (
    CAMERA_FILE_FORMAT,
    CAMERA_FILE_VERSION,
    CCM_TARGETS,
    DISTORTION_MODELS,
    OPTICS_MODELS,
    CameraColor,
    CameraFile,
    CameraOptics,
    CameraSensitivity,
    CameraSensor,
    Provenance,
    read_camera,
    write_camera,
)
from imageform.io.dicom import DICOM_WINDOW_FUNCTIONS, DicomInfo, dicom_info, dicom_window
from imageform.io.exif import ExifCamera, exif_camera
from imageform.io.icc import (
    RGB_PROFILED,
    DeclaredColorSpace,
    IccProfile,
    icc_profile,
    identify_icc,
    parse_icc,
)
from imageform.io.image_io import (
    DEFAULT_MAX_PIXELS,
    IMAGE_FORMATS,
    ImageFrames,
    ImageInfo,
    WrittenImage,
    image_color_space,
    image_files,
    image_format,
    image_frames,
    image_info,
    max_pixels,
    pixel_size_um,
    read_dicom,
    read_image,
    write_image,
)
from imageform.io.interlace import (
    DEINTERLACE_METHODS,
    FIELD_ORDERS,
    Interlacing,
    deinterlace,
    detect_interlacing,
    field_camera_matrix,
    split_fields,
)
from imageform.io.marker_map_file import (
    MARKER_MAP_FORMAT,
    MARKER_MAP_VERSION,
    read_marker_map,
    write_marker_map,
)
from imageform.io.plan import PLAN_MESH_SUFFIXES, Plan, read_plan
from imageform.io.png import read_png, write_png
from imageform.io.raw import (
    CALIBRATION_ILLUMINANTS,
    RAW_MAX_PIXELS,
    RAW_SUFFIXES,
    Development,
    RawImage,
    develop,
    read_raw,
    write_dng,
)
from imageform.io.stereo_file import (
    STEREO_FILE_FORMAT,
    STEREO_FILE_VERSION,
    StereoCameraFile,
    read_stereo_camera,
    write_stereo_camera,
)
from imageform.io.video import (
    VIDEO_SUFFIXES,
    Frame,
    VideoInfo,
    VideoReader,
    VideoWriter,
    open_video,
)

__all__ = [
    "CALIBRATION_ILLUMINANTS",
    "CAMERA_FILE_FORMAT",
    "CAMERA_FILE_VERSION",
    "CCM_TARGETS",
    "DEFAULT_MAX_PIXELS",
    "DEINTERLACE_METHODS",
    "DICOM_WINDOW_FUNCTIONS",
    "DISTORTION_MODELS",
    "FIELD_ORDERS",
    "IMAGE_FORMATS",
    "MARKER_MAP_FORMAT",
    "MARKER_MAP_VERSION",
    "OPTICS_MODELS",
    "PLAN_MESH_SUFFIXES",
    "RAW_MAX_PIXELS",
    "RAW_SUFFIXES",
    "RGB_PROFILED",
    "STEREO_FILE_FORMAT",
    "STEREO_FILE_VERSION",
    "VIDEO_SUFFIXES",
    "CameraColor",
    "CameraFile",
    "CameraOptics",
    "CameraSensitivity",
    "CameraSensor",
    "DeclaredColorSpace",
    "Development",
    "DicomInfo",
    "ExifCamera",
    "Frame",
    "IccProfile",
    "ImageFrames",
    "ImageInfo",
    "Interlacing",
    "Plan",
    "Provenance",
    "RawImage",
    "StereoCameraFile",
    "VideoInfo",
    "VideoReader",
    "VideoWriter",
    "WrittenImage",
    "deinterlace",
    "detect_interlacing",
    "develop",
    "dicom_info",
    "dicom_window",
    "exif_camera",
    "field_camera_matrix",
    "icc_profile",
    "identify_icc",
    "image_color_space",
    "image_files",
    "image_format",
    "image_frames",
    "image_info",
    "max_pixels",
    "open_video",
    "parse_icc",
    "pixel_size_um",
    "read_camera",
    "read_dicom",
    "read_image",
    "read_marker_map",
    "read_plan",
    "read_png",
    "read_raw",
    "read_stereo_camera",
    "split_fields",
    "write_camera",
    "write_dng",
    "write_image",
    "write_marker_map",
    "write_png",
    "write_stereo_camera",
]
