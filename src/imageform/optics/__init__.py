"""imageform.optics — thin lens, depth of field, defocus, vignetting, aberrations, PSFs.

Thin lens, depth of field, defocus, vignetting, aberrations and diffraction PSFs (SI units).

The focal length is always the keyword-only ``focal_length``: in metres, except where a
function works on pixels (the vignetting maps take it in pixels, as ``fx`` of K).
"""

from __future__ import annotations

from imageform.optics.aberrations import (
    ChromaticFocalLengths,
    axial_chromatic_aberration,
    axial_chromatic_blur_diameters,
    chromatic_focal_lengths,
    lateral_chromatic_aberration,
    spherical_aberration,
    spherical_blur_radius,
)
from imageform.optics.defocus import blur_by_radius, defocus_blur, defocus_radius_px, disc_kernel
from imageform.optics.depth_of_field import (
    DepthOfField,
    circle_of_confusion,
    depth_of_field,
    hyperfocal_distance,
)
from imageform.optics.psf import (
    TransferFunction,
    diffraction_limited_mtf,
    diffraction_psf,
    field_psfs,
    mtf,
    noll_to_nm,
    otf,
    pixel_mtf,
    polychromatic_psf,
    psf_from_pupil,
    pupil_function,
    zernike,
    zernike_defocus,
    zernike_radial,
    zernike_wavefront,
)
from imageform.optics.thin_lens import (
    ThinLensSolution,
    aperture_diameter,
    f_number,
    magnification,
    thin_lens,
)
from imageform.optics.vignetting import (
    apply_vignetting,
    cos4_falloff,
    field_angle,
    mechanical_vignetting,
    pupil_overlap_fraction,
)

__all__ = [
    "ChromaticFocalLengths",
    "DepthOfField",
    "ThinLensSolution",
    "TransferFunction",
    "aperture_diameter",
    "apply_vignetting",
    "axial_chromatic_aberration",
    "axial_chromatic_blur_diameters",
    "blur_by_radius",
    "chromatic_focal_lengths",
    "circle_of_confusion",
    "cos4_falloff",
    "defocus_blur",
    "defocus_radius_px",
    "depth_of_field",
    "diffraction_limited_mtf",
    "diffraction_psf",
    "disc_kernel",
    "f_number",
    "field_angle",
    "field_psfs",
    "hyperfocal_distance",
    "lateral_chromatic_aberration",
    "magnification",
    "mechanical_vignetting",
    "mtf",
    "noll_to_nm",
    "otf",
    "pixel_mtf",
    "polychromatic_psf",
    "psf_from_pupil",
    "pupil_function",
    "pupil_overlap_fraction",
    "spherical_aberration",
    "spherical_blur_radius",
    "thin_lens",
    "zernike",
    "zernike_defocus",
    "zernike_radial",
    "zernike_wavefront",
]
