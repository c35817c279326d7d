"""The views of a calibration as :func:`~imageform.geometry.calibrate_camera` checks them.

One ``(N, 3)`` object-point and one ``(N, 2)`` image-point array per view (shared by the
closed-form initialisation, the refinement and stereo calibration).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from imageform._backend import to_numpy
from imageform._validate import as_points_bounded, describe, points_pass_bounded
from imageform.errors import DegenerateConfigurationError, InvalidInputError

__all__ = ["MAX_VIEWS"]

F64 = NDArray[np.float64]

#: The most views one calibration takes (each adds six unknowns to the solve).
MAX_VIEWS = 10_000


def _all_clean(objs: list[Any], imgs: list[Any]) -> bool:
    """Whether every view is already what the checks below make of it, from one pass.

    Every array passes :func:`~imageform._validate.as_points_bounded` as it is
    (:func:`~imageform._validate.points_pass_bounded`: float64 NumPy, finite, within
    :data:`~imageform._validate.MAX_MAGNITUDE`), and the views are (N, 3) and (N, 2) with the
    same ``N >= 4``: then each view's own checks would pass and return the arrays as they
    are. Anything else goes through the checks view by view, which name the view.
    """
    shapes_ok = all(
        type(o) is np.ndarray
        and type(i) is np.ndarray
        and o.ndim == 2
        and i.ndim == 2
        and o.shape[0] == i.shape[0] >= 4
        for o, i in zip(objs, imgs, strict=True)
    )
    return shapes_ok and points_pass_bounded(objs, 3) and points_pass_bounded(imgs, 2)


def _views(
    object_points: Any, image_points: Any, image_name: str = "image_points"
) -> tuple[list[F64], list[F64]]:
    for value, name, dim in (
        (object_points, "object_points", 3),
        (image_points, image_name, 2),
    ):
        if (
            isinstance(value, str | bytes)
            or not hasattr(value, "__len__")
            or not hasattr(value, "__getitem__")
            or getattr(value, "ndim", 1) == 0
        ):
            raise InvalidInputError(
                f"expected {name} as a sequence of (N, {dim}) arrays, one per view, got "
                + describe(value)
            )
    if len(object_points) > MAX_VIEWS:
        raise InvalidInputError(
            f"expected object_points for at most {MAX_VIEWS} views, got {len(object_points)}"
        )
    objs = [object_points[k] for k in range(len(object_points))]
    imgs = [image_points[k] for k in range(len(image_points))]
    if len(objs) != len(imgs):
        raise InvalidInputError(
            f"expected one object-point array per view of image points (object_points and "
            f"{image_name} of the same length), got {len(objs)} and {len(imgs)}"
        )
    if not objs:
        raise InvalidInputError("expected object_points of at least one view, got none")
    if _all_clean(objs, imgs):
        return objs, imgs
    out_o, out_i = [], []
    for k, (o, i) in enumerate(zip(objs, imgs, strict=True)):
        for v, nm in ((o, f"object_points[{k}]"), (i, f"{image_name}[{k}]")):
            if str(getattr(v, "dtype", "")) in ("bool", "torch.bool"):  # a mask, not points
                raise InvalidInputError(f"expected {nm} as coordinates, got a boolean array")
        oa = np.asarray(to_numpy(as_points_bounded(o, f"object_points[{k}]", 3)), dtype=np.float64)
        ia = np.asarray(to_numpy(as_points_bounded(i, f"{image_name}[{k}]", 2)), dtype=np.float64)
        if oa.ndim != 2 or ia.ndim != 2 or oa.shape[0] != ia.shape[0]:
            raise InvalidInputError(
                f"view {k}: expected object_points (N, 3) and {image_name} (N, 2) with the same "
                f"N, got {oa.shape} and {ia.shape}"
            )
        if oa.shape[0] < 4:
            raise DegenerateConfigurationError(
                f"view {k}: expected at least 4 points in object_points, got {oa.shape[0]}"
            )
        out_o.append(oa)
        out_i.append(ia)
    return out_o, out_i
