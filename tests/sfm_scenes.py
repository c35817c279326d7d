"""A room whose walls are real photographs, walked through by a camera (issue 28's bar).

The room is a box 4 m wide (x), 6 m deep (y) and 2.5 m high (z up); its four walls, floor
and ceiling carry photographs (scikit-image's, and Kodak's when the reference data is
there), each tiled so that a wall has texture everywhere. A pinhole camera walks down the
room looking ahead and a little to the side; each frame is ray-cast exactly (every pixel's
ray hits the nearest plane, sampled bilinearly), with a little noise. The truth is every
frame's pose.

The issue's bar adds what a real video has: a little defocus blur (Gaussian), sensor noise
and JPEG compression (:func:`sequence`'s ``blur``, ``noise`` and ``jpeg``).
"""

from __future__ import annotations

from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
KODAK = ROOT.parent / "shared" / "data" / "kodak"

W, D, H = 4.0, 6.0, 2.5


@cache
def _photos() -> list[np.ndarray]:
    from skimage import data

    photos = [data.astronaut(), data.coffee(), data.chelsea(), data.rocket()]
    if KODAK.is_dir():
        from imageform.io import read_image

        photos = [
            np.asarray(read_image(KODAK / f"kodim{i:02d}.png")) for i in (1, 8, 13, 21, 23, 5)
        ]
    return [np.asarray(p[..., :3], np.uint8) for p in photos]


#: planes: (point, normal, u axis, v axis, size u, size v)
_PLANES = [
    ((0, D, 0), (0, -1, 0), (1, 0, 0), (0, 0, 1), W, H),  # far wall
    ((0, 0, 0), (0, 1, 0), (1, 0, 0), (0, 0, 1), W, H),  # near wall
    ((0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1), D, H),  # left wall (x = 0)
    ((W, 0, 0), (-1, 0, 0), (0, 1, 0), (0, 0, 1), D, H),  # right wall
    ((0, 0, 0), (0, 0, 1), (1, 0, 0), (0, 1, 0), W, D),  # floor
    ((0, 0, H), (0, 0, -1), (1, 0, 0), (0, 1, 0), W, D),  # ceiling
]


def poses(n: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """A walk down the room: 3 m forward, swaying, looking ahead and to the side."""
    from imageform.geometry import look_at

    out = []
    for i in range(n):
        s = i / max(n - 1, 1)
        eye = np.array(
            [2.0 + 0.4 * np.sin(2 * np.pi * s), 1.0 + 3.0 * s, 1.4 + 0.1 * np.cos(3 * s)]
        )
        target = eye + np.array([0.8 * np.sin(1.5 * np.pi * s), 2.0, -0.2])
        pose = look_at(eye, target, up=(0.0, 0.0, 1.0))
        out.append((np.asarray(pose.R, np.float64), np.asarray(pose.t, np.float64)))
    return out


def render(
    K: np.ndarray,
    pose: tuple[np.ndarray, np.ndarray],
    size: tuple[int, int],
    *,
    noise: float = 1.5,
    rng: np.random.Generator | None = None,
    distortion: Any = None,
    photos: list[np.ndarray] | None = None,
) -> np.ndarray:
    """One frame of the room, uint8 RGB (through ``distortion``'s lens when given).

    ``photos``: the walls' pictures (default: the Kodak photographs, else scikit-image's).
    """
    import cv2

    photos = _photos() if photos is None else photos
    R, t = pose
    w, h = size
    C = -R.T @ t
    u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    xn = np.stack([u, v, np.ones_like(u)], -1) @ np.linalg.inv(K).T
    if distortion is not None:  # the ideal point of each pixel (NaN: no ray, left black)
        und, ok = distortion.undistort(xn[..., :2].reshape(-1, 2))
        und = np.where(np.asarray(ok)[:, None], np.asarray(und), np.nan)
        xn = np.concatenate([und.reshape(h, w, 2), np.ones((h, w, 1))], axis=2)
    rays = xn @ R  # world directions
    best = np.full((h, w), np.inf)
    out = np.zeros((h, w, 3), np.float64)
    for k, (p0, nrm, ax_u, ax_v, su, sv) in enumerate(_PLANES):
        p0, nrm, ax_u, ax_v = (np.asarray(x, np.float64) for x in (p0, nrm, ax_u, ax_v))
        denom = rays @ nrm
        with np.errstate(divide="ignore", invalid="ignore"):
            dist = ((p0 - C) @ nrm) / denom
        hit = C + dist[..., None] * rays
        a, b = (hit - p0) @ ax_u, (hit - p0) @ ax_v
        ok = (dist > 0) & (dist < best) & (a >= 0) & (a <= su) & (b >= 0) & (b <= sv)
        if not ok.any():
            continue
        photo = photos[k % len(photos)].astype(np.float32)
        ph, pw = photo.shape[:2]
        scale = pw / 1.6  # one photo per 1.6 m, tiled (mirrored) across the plane
        x = np.mod(a * scale, 2 * pw)
        y = np.mod((sv - b) * scale, 2 * ph)
        # pixels with no ray (NaN) sample the corner: OpenCV's reflection loops on NaN
        x = np.where(ok, np.where(x >= pw, 2 * pw - 1 - x, x), 0).astype(np.float32)
        y = np.where(ok, np.where(y >= ph, 2 * ph - 1 - y, y), 0).astype(np.float32)
        sample = cv2.remap(
            photo, x, y, interpolation=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT
        )
        out[ok] = sample[ok]
        best[ok] = dist[ok]
    if noise:
        rng = rng or np.random.default_rng(0)
        out = out + rng.normal(0, noise, out.shape)
    return np.clip(np.round(out), 0, 255).astype(np.uint8)


def degrade(
    image: np.ndarray,
    *,
    blur: float = 0.0,
    noise: float = 0.0,
    jpeg: int | None = None,
    rng: np.random.Generator | None = None,
) -> np.ndarray:
    """A frame as a camera delivers it: Gaussian blur (``blur`` pixels), noise, then JPEG."""
    import cv2

    out: np.ndarray = image.astype(np.float32)
    if blur > 0:
        out = cv2.GaussianBlur(out, (0, 0), blur, borderType=cv2.BORDER_REFLECT)
    if noise > 0:
        out = out + (rng or np.random.default_rng(0)).normal(0, noise, out.shape)
    out = np.clip(np.round(out), 0, 255).astype(np.uint8)
    if jpeg is not None:
        ok, buf = cv2.imencode(".jpg", out[..., ::-1], [cv2.IMWRITE_JPEG_QUALITY, int(jpeg)])
        assert ok
        decoded = cv2.imdecode(buf, cv2.IMREAD_COLOR)
        assert decoded is not None
        out = np.ascontiguousarray(decoded[..., ::-1])
    return out


#: a burned-in overlay (timestamp, camera and patient lines), the same in every frame
OVERLAY = [f"LINE {j} CAM 01 2026/11/29 11:45:{j:02d} ID 48{j}1-A7" for j in range(6)]


def burn_in(image: np.ndarray) -> np.ndarray:
    """``image`` with :data:`OVERLAY` written on it (white on a black outline, top left)."""
    import cv2

    out = np.ascontiguousarray(image.copy())
    for j, text in enumerate(OVERLAY):
        for color, thick in (((0, 0, 0), 4), ((255, 255, 255), 1)):
            org = (10, 20 + 22 * j)
            cv2.putText(out, text, org, cv2.FONT_HERSHEY_SIMPLEX, 0.5, color, thick, cv2.LINE_AA)
    return out


def sequence(
    K: np.ndarray,
    n: int,
    size: tuple[int, int],
    *,
    noise: float = 1.5,
    blur: float = 0.0,
    jpeg: int | None = None,
    photos: list[np.ndarray] | None = None,
) -> tuple[list[np.ndarray], list]:
    """``n`` frames of the walk and their true poses (``photos``: as :func:`render`).

    Without ``blur`` or ``jpeg`` the noise is added by :func:`render` (the frames of the
    first tests); with them each frame is rendered clean, blurred, given its noise and
    JPEG-compressed at quality ``jpeg``.
    """
    truth = poses(n)
    rng = np.random.default_rng(5)
    if not blur and jpeg is None:
        return [render(K, p, size, noise=noise, rng=rng, photos=photos) for p in truth], truth
    frames = [render(K, p, size, noise=0.0, photos=photos) for p in truth]
    return [degrade(f, blur=blur, noise=noise, jpeg=jpeg, rng=rng) for f in frames], truth


def blobs(seed: int, size: tuple[int, int] = (640, 480)) -> np.ndarray:
    """Colour blobs at two scales, uint8 RGB: a texture unlike any photograph's."""
    import cv2

    r = np.random.default_rng(seed)
    coarse = cv2.resize(r.random((24, 32, 3), np.float32), size, interpolation=cv2.INTER_CUBIC)
    fine = cv2.resize(r.random((96, 128, 3), np.float32), size, interpolation=cv2.INTER_CUBIC)
    return np.clip(255 * (0.6 * coarse + 0.4 * fine), 0, 255).astype(np.uint8)


def align_rms(est_centres: np.ndarray, true_centres: np.ndarray) -> float:
    """RMS distance after the best similarity (Umeyama 1991), as a share of the path length."""
    mu_e, mu_t = est_centres.mean(0), true_centres.mean(0)
    e, t = est_centres - mu_e, true_centres - mu_t
    U, S, Vt = np.linalg.svd(t.T @ e / len(e))
    d = np.sign(np.linalg.det(U @ Vt))
    Dm = np.diag([1.0, 1.0, d])
    R = U @ Dm @ Vt
    s = np.trace(np.diag(S) @ Dm) / (e**2).sum(1).mean()
    fitted = s * e @ R.T + mu_t
    path = np.sum(np.linalg.norm(np.diff(true_centres, axis=0), axis=1))
    return float(np.sqrt(np.mean(np.sum((fitted - true_centres) ** 2, 1))) / path)


def rotation_errors_deg(est_R: Any, truth: list[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    """Each frame's rotation error (degrees) in the first true frame's camera frame.

    ``est_R`` ``(n, 3, 3)`` as :func:`~imageform.geometry.reconstruct_sequence` gives them
    (the world is its first registered frame's camera); ``truth`` as :func:`poses`.
    """
    R0 = truth[0][0]
    d = np.asarray(est_R) @ np.transpose(np.stack([R @ R0.T for R, _ in truth]), (0, 2, 1))
    cos = (np.trace(d, axis1=1, axis2=2) - 1.0) / 2.0
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


#: OpenCV's chessboard views (``../shared/data/opencv-left``; left10 is not in the set).
CHESSBOARD_VIEWS = [f"left{i:02d}.jpg" for i in (1, 2, 3, 4, 5, 6, 7, 8, 9, 11, 12, 13, 14)]


def chessboard_views(folder: Path, dilate: int = 25) -> dict[str, Any]:
    """A real multi-view set with known cameras: OpenCV's 13 views of a 9 x 6 chessboard.

    The truth is imageform's own calibration of the views (``calibrate_camera`` on the
    corners ``find_checkerboard`` finds with OpenCV's refinement, ``cornerSubPix`` with its
    tutorial's window, as OpenCV's published figures): ``K``, the lens
    distortion and each view's board pose, the board's frame being the world (unit: one
    square). The camera stood still and the board moved, so only the board moves with
    that world: each view's mask is the convex hull of its corners dilated by ``dilate``
    pixels (the outer squares and the board's white rim; the person holding it and the
    room behind are left out).

    Returns a dict with ``images`` (grey uint8), ``masks`` (uint8, 255 on the board),
    ``K``, ``distortion``, ``R``, ``t`` (the views' world-to-camera poses), ``centres``
    (the camera centres in the board's frame), ``rms`` (the calibration's, pixels) and
    ``names``.
    """
    import cv2

    from imageform.geometry import calibrate_camera, checkerboard_points, rvec_to_matrix
    from imageform.geometry.checkerboard import find_checkerboard
    from imageform.io import read_image

    images = [np.asarray(read_image(folder / v))[..., 0] for v in CHESSBOARD_VIEWS]
    corners = []
    for name, im in zip(CHESSBOARD_VIEWS, images, strict=True):
        found = find_checkerboard(im, (9, 6), half_window=11, method="gradient").corners
        assert found is not None, f"no board found in {name}"
        corners.append(np.asarray(found, np.float64).reshape(-1, 2))
    h, w = images[0].shape
    obj = checkerboard_points((9, 6), 1.0)
    cal = calibrate_camera([obj] * len(images), corners, (w, h))
    R = np.stack([np.asarray(rvec_to_matrix(r), np.float64) for r in cal.rvecs])
    t = np.asarray(cal.tvecs, np.float64)
    disk = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * dilate + 1, 2 * dilate + 1))
    masks = []
    for c in corners:
        m = np.zeros((h, w), np.uint8)
        cv2.fillConvexPoly(m, cv2.convexHull(c.astype(np.float32)).astype(np.int32), 255)
        masks.append(cv2.dilate(m, disk) if dilate > 0 else m)
    return {
        "images": images,
        "masks": masks,
        "K": np.asarray(cal.K, np.float64),
        "distortion": cal.distortion,
        "R": R,
        "t": t,
        "centres": -np.einsum("nji,nj->ni", R, t),
        "rms": float(cal.rms),
        "names": list(CHESSBOARD_VIEWS),
    }
