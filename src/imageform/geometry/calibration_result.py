"""The result of :func:`~imageform.geometry.calibrate_camera` and its TOML form."""

from __future__ import annotations

import tomllib
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imageform._files import atomic_write, check_writable
from imageform._validate import describe
from imageform.errors import InvalidInputError
from imageform.geometry.calibration_refine import RefineOutput, global_names, rodrigues
from imageform.geometry.camera import Camera
from imageform.geometry.distortion import BrownConrady, KannalaBrandt

__all__ = ["CalibrationResult"]

F64 = NDArray[np.float64]
_DIST = ("k1", "k2", "p1", "p2", "k3")


@dataclass(frozen=True)
class CalibrationResult:
    """Intrinsics, distortion, poses and error statistics of a calibration.

    Attributes
    ----------
    K : ndarray (3, 3)
        Intrinsic matrix ``[[fx, skew, cx], [0, fy, cy], [0, 0, 1]]`` in pixels.
    distortion : BrownConrady or KannalaBrandt
        The fitted lens model: :class:`BrownConrady` ``(k1, k2, p1, p2, k3)`` (the rational
        terms 0) for ``model="brown_conrady"``, with ``k4, k5, k6`` for ``"rational"``;
        :class:`KannalaBrandt` ``(k1, k2, k3, k4)`` for ``"kannala_brandt"``.
    image_size : (int, int)
        ``(width, height)``.
    rvecs, tvecs : ndarray (V, 3)
        World(target)-to-camera pose of each view (Rodrigues vector, translation).
    rms : float
        ``sqrt(Σ‖u - û‖² / N)`` over all N points (OpenCV's ``calibrateCamera`` return value).
    per_view_rms : ndarray (V,)
        The same per view.
    residuals : tuple of ndarray (N_k, 2)
        Observed minus reprojected pixels of each view; ``np.hypot`` gives per-point errors.
    std : dict str -> float
        Standard deviation of each global parameter (``fx, fy, cx, cy, skew`` and the
        model's coefficients; 0 when fixed).
    std_poses : ndarray (V, 6)
        Standard deviations of ``(rvec, t)`` per view.
    fixed : tuple of str
        Names of the parameters held fixed.
    warnings : tuple of str
        The ill-conditioning warnings that were issued.
    n_evaluations : int
        Residual evaluations of the refinement.
    model : str
        The calibration model: ``"brown_conrady"``, ``"rational"`` or ``"kannala_brandt"``.
    """

    K: F64
    distortion: BrownConrady | KannalaBrandt
    image_size: tuple[int, int]
    rvecs: F64 = field(repr=False)
    tvecs: F64 = field(repr=False)
    rms: float = 0.0
    per_view_rms: F64 = field(default_factory=lambda: np.zeros(0), repr=False)
    residuals: tuple[F64, ...] = field(default=(), repr=False)
    std: dict[str, float] = field(default_factory=dict, repr=False)
    std_poses: F64 = field(default_factory=lambda: np.zeros((0, 6)), repr=False)
    fixed: tuple[str, ...] = ()
    warnings: tuple[str, ...] = field(default=(), repr=False)
    n_evaluations: int = field(default=0, repr=False)
    model: str = "brown_conrady"

    @classmethod
    def from_fit(
        cls,
        out: RefineOutput,
        view: NDArray[np.intp],
        size: tuple[int, int],
        free: NDArray[np.bool_],
        notes: tuple[str, ...],
        model: str = "brown_conrady",
    ) -> CalibrationResult:
        """Assemble the result from the refinement output (internal)."""
        g = out.globals_
        names = global_names(model)
        coeffs = (float(v) for v in g[5:])
        distortion: BrownConrady | KannalaBrandt = (
            KannalaBrandt(*coeffs) if model == "kannala_brandt" else BrownConrady(*coeffs)
        )
        K = np.array([[g[0], g[4], g[2]], [0.0, g[1], g[3]], [0.0, 0.0, 1.0]])
        V = out.rvecs.shape[0]
        res = tuple(out.residuals[view == k] for k in range(V))
        sq = np.sum(out.residuals**2, axis=1)
        return cls(
            K=K,
            distortion=distortion,
            image_size=size,
            rvecs=out.rvecs,
            tvecs=out.tvecs,
            rms=float(np.sqrt(sq.mean())),
            per_view_rms=np.array([np.sqrt(np.mean(sq[view == k])) for k in range(V)]),
            residuals=res,
            std={n: float(s) for n, s in zip(names, out.std_globals, strict=True)},
            std_poses=out.std_poses,
            fixed=tuple(n for n, f in zip(names, free, strict=True) if not f),
            warnings=notes,
            n_evaluations=out.n_iter,
            model=model,
        )

    @property
    def rotations(self) -> F64:
        """``R_k`` (V, 3, 3) of the views."""
        return rodrigues(self.rvecs)

    @property
    def per_point_errors(self) -> tuple[F64, ...]:
        """``‖u - û‖`` (N_k,) of each view, in pixels."""
        return tuple(np.hypot(r[:, 0], r[:, 1]) for r in self.residuals)

    @property
    def camera(self) -> Camera:
        """The calibrated camera: K, the distortion and the image size, no pose.

        The camera file of a calibration (K, distortion, standard deviations, RMS) is
        ``imageform.io.CameraFile.from_calibration(result)``, written by
        ``imageform.io.write_camera``.
        """
        size = self.image_size if min(self.image_size) > 0 else None
        return Camera(self.K, image_size=size, distortion=self.distortion)

    def to_toml(self, path: str | Path | None = None) -> str:
        """Write the camera as TOML in the format before the versioned camera file (deprecated).

        .. deprecated::
            Use ``imageform.io.write_camera(path, CameraFile.from_calibration(result))``:
            the one camera file (docs/camera-file.md), which every command reads. Files
            written here are still read by ``imageform.io.read_camera``.
        """
        warnings.warn(
            "CalibrationResult.to_toml is deprecated: use imageform.io.write_camera(path, "
            "imageform.io.CameraFile.from_calibration(result))",
            DeprecationWarning,
            stacklevel=2,
        )
        if self.model != "brown_conrady":
            raise InvalidInputError(
                f"the deprecated to_toml writes Brown-Conrady k1 ... k3 only, not model "
                f"{self.model!r}: use imageform.io.write_camera(path, "
                "imageform.io.CameraFile.from_calibration(result))"
            )
        K = self.K
        vals: dict[str, float] = {
            "fx": K[0, 0],
            "fy": K[1, 1],
            "cx": K[0, 2],
            "cy": K[1, 2],
            "skew": K[0, 1],
        }
        lines = ["[camera]"]
        lines += [f"{k} = {float(v)!r}" for k, v in vals.items()]
        if min(self.image_size) > 0:  # (0, 0): unknown, e.g. read from a file without it
            lines += [f"width = {self.image_size[0]}", f"height = {self.image_size[1]}"]
        lines += [f"{k} = {float(getattr(self.distortion, k))!r}" for k in _DIST]
        lines += ["", "[calibration]", f"rms = {self.rms!r}", f"views = {len(self.rvecs)}"]
        text = "\n".join(lines) + "\n"
        if path is not None:
            final = check_writable(path, "path")
            atomic_write(final, lambda tmp: tmp.write_text(text, encoding="utf-8"))
        return text

    @classmethod
    def from_toml(cls, source: str | Path) -> CalibrationResult:
        """Read the camera written by :meth:`to_toml` (a path, or the TOML text itself; deprecated).

        .. deprecated::
            Use ``imageform.io.read_camera(path)``, which reads this format, the versioned
            camera file and every distortion model, with full validation.

        Keys at the top level or in a ``[camera]`` table; ``skew``, ``k1 ... k3`` default to 0.
        Poses and residuals are not stored: ``rvecs``/``tvecs`` come back empty, ``rms`` from
        the ``[calibration]`` table (NaN if absent), ``image_size`` (0, 0) if absent.
        """
        warnings.warn(
            "CalibrationResult.from_toml is deprecated: use imageform.io.read_camera(path)",
            DeprecationWarning,
            stacklevel=2,
        )
        if not isinstance(source, str | Path):
            raise TypeError(f"expected source as a path or TOML text (str), got {describe(source)}")
        if isinstance(source, Path) or "=" not in str(source):
            p = Path(source)
            if not p.is_file():
                raise InvalidInputError(f"camera file {p} does not exist")
            text = p.read_text()
        else:
            text = str(source)
        try:
            data: dict[str, Any] = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise InvalidInputError(f"not valid TOML: {exc}") from exc
        cam = data.get("camera", data)
        missing = [k for k in ("fx", "fy", "cx", "cy") if k not in cam]
        if missing:
            raise InvalidInputError(f"missing camera key(s) {missing}")
        K = np.array(
            [
                [float(cam["fx"]), float(cam.get("skew", 0.0)), float(cam["cx"])],
                [0.0, float(cam["fy"]), float(cam["cy"])],
                [0.0, 0.0, 1.0],
            ]
        )
        dist = BrownConrady(**{k: float(cam.get(k, 0.0)) for k in _DIST})
        size = (int(cam.get("width", 0)), int(cam.get("height", 0)))
        rms = float(data.get("calibration", {}).get("rms", np.nan))
        empty = np.zeros((0, 3))
        return cls(K=K, distortion=dist, image_size=size, rvecs=empty, tvecs=empty, rms=rms)
