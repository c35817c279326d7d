"""What an imaging lab photographs to characterise a camera, rendered through a camera file.

:func:`render_lab_set` writes checkerboard views, a ColorChecker, a slanted edge and EMVA 1288
flat and dark stacks, with a manifest ``lab.toml`` and the true camera file. The input of
``imageform characterize`` (docs/simulate.md, "A lab's photographs of a camera"), and the
closed loop's test bed: characterising these photographs should give the camera file back.
Each step (one thing the lab photographs) is a function of :mod:`imageform.simulate._lab_steps`.
"""

from __future__ import annotations

import dataclasses
import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from imageform import _deprecate
from imageform._random import RNGLike, as_rng
from imageform._validate import as_int, as_real, check_rng, describe
from imageform.errors import InvalidInputError
from imageform.io import CameraFile, Provenance, read_camera, write_camera
from imageform.simulate import _lab_steps as steps
from imageform.simulate._lab_steps import LAB_FORMAT, MAX_VIEWS

__all__ = ["LAB_FORMAT", "LabSet", "render_lab_set"]


@dataclass(frozen=True)
class LabSet:
    """What :func:`render_lab_set` wrote.

    The ``folder``, its ``manifest`` (``lab.toml``), the true ``camera`` file, the
    ``checkerboard`` images, the ``colorchecker`` and ``edge`` images, the EMVA
    ``emva_manifest`` (``emva.toml``, flats/ and darks/) and the ``seconds`` it took.
    """

    folder: Path
    manifest: Path
    camera: Path
    checkerboard: tuple[Path, ...]
    colorchecker: Path
    edge: Path
    emva_manifest: Path
    seconds: float


@_deprecate.parameters(renamed={"seed": "rng"})
def render_lab_set(
    camera: CameraFile | str | Path,
    folder: str | Path,
    *,
    rng: RNGLike = 0,
    views: int = 8,
    board: tuple[int, int] = (9, 6),
    supersampling: int = 2,
    emva_exposures: int = 24,
    emva_frames: int = 2,
    emva_shape: tuple[int, int] = (64, 64),
    edge_angle_deg: float = 5.0,
    force: bool = False,
) -> LabSet:
    """Render what a lab photographs of ``camera`` into ``folder``.

    Layout (images 16-bit PNG, raw mosaics DNG)::

        lab.toml            the manifest: what is where, how it was encoded, the truth
        camera.toml         the camera file rendered through (the truth)
        checkerboard/       view-01.png ... : the board (``board`` inner corners, square
                            ``square_mm`` in lab.toml) at ``views`` poses, the camera's
                            developed output (sRGB-encoded)
        colorchecker/       chart.dng: a frontal ColorChecker under D65, the raw mosaic
                            (:func:`imageform.simulate.write_simulated_dng`);
                            developed.png: the same exposure as the camera develops it
                            (its white balance, colour matrix and sRGB encoding; with no
                            fixed ``white_balance`` or ``ccm`` in ``[color]``, the
                            simulator's automatic processing: grey world and a matrix fitted
                            on the chart), from which ``imageform characterize`` measures
                            the camera's processing (``processing`` in lab.toml says which)
        edge/               edge.dng: a dark square (reflectance 0.1) on a light ground (0.8)
                            turned ``edge_angle_deg``, the raw mosaic (its sharpness is
                            measured without demosaicing)
        emva.toml           the EMVA 1288 manifest ``imageform emva FOLDER`` reads
        flats/, darks/      e00-0.png ... : raw frames (DN) of the green channel at 550 nm
                            (:func:`imageform.sensor.simulate_emva_frames`), one stack of
                            ``emva_frames`` per exposure, ``emva_exposures`` exposures from
                            dark to 105 % of saturation

    Every rendering goes through :func:`imageform.simulate.apply_camera_file` (the file's
    intrinsics and distortion, its ``[sensor]``, ``[optics]`` and ``[color]``; the file's
    pose is not used: the lab poses the camera); the lab's scenes have no defocus and no
    vignetting, a D65 light and sensor noise on (view ``i`` seeded ``seed + i``, ``seed`` the
    int ``rng`` or one drawn from it).

    Parameters
    ----------
    camera : CameraFile, str or Path
        The camera (a camera file path is read with :func:`imageform.io.read_camera`); it
        needs an image size.
    folder : str or Path
        Where to write; must not exist (or be empty) unless ``force`` (then only a previous
        lab set is replaced).
    rng : int, numpy.random.Generator, SeedSequence or None
        The sensor noise: an int seed (default 0: the same lab set every time), or a
        Generator (or None: fresh entropy) from which one seed is drawn; lab.toml records
        the seed. ``seed=`` is the deprecated spelling.
    views : int
        Checkerboard views, 8 to 12.
    board : (cols, rows)
        Inner corners of the checkerboard (the board has one more square each way).
    supersampling : int
        Rays per pixel along each axis (the renderer's S).
    emva_exposures, emva_frames, emva_shape
        The EMVA stacks: exposures (>= 8), frames per stack (>= 2) and frame size.
    edge_angle_deg : float
        Rotation of the slanted-edge square (2 to 10 degrees).
    force : bool
        Replace an existing lab set.

    Returns
    -------
    LabSet

    Examples
    --------
    >>> import tempfile
    >>> from imageform.geometry import Camera
    >>> cam = Camera([[300.0, 0, 159.5], [0, 300.0, 119.5], [0, 0, 1]], image_size=(320, 240))
    >>> lab = render_lab_set(CameraFile(cam), Path(tempfile.mkdtemp()) / "lab",
    ...                      views=8, emva_exposures=8)  # doctest: +SKIP
    """
    import time

    t0 = time.perf_counter()
    cf = read_camera(camera) if isinstance(camera, str | Path) else camera
    if not isinstance(cf, CameraFile):
        raise TypeError(
            f"expected camera as a CameraFile or a camera file path, got {describe(camera)}"
        )
    if cf.camera.image_size is None:
        raise InvalidInputError("camera: the camera file has no image size ([image]) to render")
    check_rng(rng)
    if isinstance(rng, int | np.integer):
        seed = as_int(rng, "rng", minimum=0)
    else:  # one seed drawn, so that the views are seeded seed + i as for an int
        seed = int(as_rng(rng).integers(0, 2**31))
    n_views = as_int(views, "views", minimum=8, maximum=MAX_VIEWS)
    if not (isinstance(board, tuple | list) and len(board) == 2):
        raise InvalidInputError(
            f"expected board as (cols, rows) inner corners, got {describe(board)}"
        )
    cols, rows = (as_int(b, "board", minimum=3, maximum=30) for b in board)
    ss = as_int(supersampling, "supersampling", minimum=1, maximum=8)
    n_exp = as_int(emva_exposures, "emva_exposures", minimum=8, maximum=200)
    n_frames = as_int(emva_frames, "emva_frames", minimum=2, maximum=64)
    if not (isinstance(emva_shape, tuple | list) and len(emva_shape) == 2):
        raise InvalidInputError(
            f"expected emva_shape as (height, width), got {describe(emva_shape)}"
        )
    shape = (
        as_int(emva_shape[0], "emva_shape", minimum=8, maximum=4096),
        as_int(emva_shape[1], "emva_shape", minimum=8, maximum=4096),
    )
    angle = as_real(edge_angle_deg, "edge_angle_deg", minimum=2.0, maximum=10.0)
    opt = steps.LabOptions(seed, n_views, cols, rows, ss, n_exp, n_frames, shape, float(angle))
    out = _new_folder(Path(folder), force)
    posed = dataclasses.replace(cf, has_pose=False)
    boards = steps.render_checkerboards(out, posed, opt)
    chart = steps.render_colorchecker(out, posed, opt)
    edge_path, edge_scene = steps.render_edge(out, posed, opt)
    emva_path, times, eta = steps.write_emva(out, edge_scene.sensor, opt)
    cam_path = write_camera(
        out / "camera.toml",
        posed,
        provenance=Provenance(
            command="imageform.simulate.render_lab_set",
            based_on=None if cf.path is None else str(cf.path),
        ),
    )
    values = steps.truth(cf, edge_scene, chart, opt, eta)
    man_path = steps.write_manifest(out, opt, values, boards, chart, edge_path, len(times))
    return LabSet(
        folder=out,
        manifest=man_path,
        camera=cam_path,
        checkerboard=tuple(boards),
        colorchecker=chart.path,
        edge=edge_path,
        emva_manifest=emva_path,
        seconds=time.perf_counter() - t0,
    )


def _new_folder(out: Path, force: bool) -> Path:
    """Create ``out``; an existing lab set is replaced only with ``force``."""
    if out.is_dir() and not any(out.iterdir()):
        out.rmdir()  # an empty folder (a command's temporary output) is filled as a new one
    if out.exists():
        if not force:
            raise InvalidInputError(f"folder {out} exists; choose a new one or pass force=True")
        if not (out / steps.MARKER).is_file():
            raise InvalidInputError(
                f"folder {out} exists and is not a lab set (no {steps.MARKER}); choose a new folder"
            )
        shutil.rmtree(out)
    out.mkdir(parents=True)
    return out
