"""Videos with known poses for the tracking tests and benchmark (issue 27).

A board (ChArUco as OpenCV draws it, or a checkerboard) pasted on a real photograph (a
Kodak image when the reference data is there, else scikit-image's coffee), the whole plane
seen by a pinhole camera from a smooth path of poses: each frame is the plane's texture
warped by the homography :math:`H = K [r_1\\ r_2\\ t] A` (A maps texture pixels to board
millimetres), with a little sensor noise. The truth is the pose of every frame.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
KODAK = ROOT.parent / "shared" / "data" / "kodak" / "kodim08.png"


def background() -> np.ndarray:
    """A real photograph, uint8 RGB."""
    if KODAK.is_file():
        from imageform.io import read_image

        return np.asarray(read_image(KODAK))
    from skimage import data

    return np.asarray(data.coffee())


def board_texture(
    kind: str = "charuco", squares: tuple[int, int] = (7, 5), px: int = 40, margin: int = 240
) -> tuple[np.ndarray, float]:
    """The plane's texture (uint8 RGB) and the board's top-left in texture pixels.

    A ChArUco board of ``squares`` (5x5_100 markers, 30 mm squares, 22 mm markers) drawn by
    OpenCV, or a checkerboard of ``squares`` squares, pasted on the photograph.
    """
    import cv2

    cols, rows = squares
    if kind == "charuco":
        d = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_5X5_100)
        board = cv2.aruco.CharucoBoard((cols, rows), 30.0, 22.0, d)
        img = board.generateImage((cols * px, rows * px))
    else:
        r, c = np.mgrid[0:rows, 0:cols]
        img = np.kron(((r + c) % 2 == 0) * 255, np.ones((px, px))).astype(np.uint8)
    bg = background()
    h, w = rows * px + 2 * margin, cols * px + 2 * margin
    tex = cv2.resize(bg, (w, h), interpolation=cv2.INTER_AREA)
    quiet = 12  # a white border around the board, as printed
    tex[
        margin - quiet : margin + rows * px + quiet, margin - quiet : margin + cols * px + quiet
    ] = 255
    tex[margin : margin + rows * px, margin : margin + cols * px] = img[..., None]
    return tex, float(margin)


def poses(n: int, distance: float = 420.0) -> list[tuple[np.ndarray, np.ndarray]]:
    """A smooth path: the camera circles and tilts around the board's centre (R, t in mm)."""
    from imageform.geometry import look_at

    out = []
    centre = np.array([105.0, 75.0, 0.0])
    for i in range(n):
        a = 2 * np.pi * i / max(n, 1)
        eye = centre + np.array([90 * np.cos(a), 60 * np.sin(a), -distance])
        pose = look_at(eye, centre + np.array([10 * np.sin(a), 0, 0]), up=(0.0, -1.0, 0.0))
        out.append((np.asarray(pose.R, np.float64), np.asarray(pose.t, np.float64)))
    return out


def render(
    tex: np.ndarray,
    origin_px: float,
    K: np.ndarray,
    pose: tuple[np.ndarray, np.ndarray],
    size: tuple[int, int],
    *,
    px_per_square: int = 40,
    noise: float = 2.0,
    rng: np.random.Generator | None = None,
) -> np.ndarray:
    """One frame: the texture warped by the pose's homography, with Gaussian noise."""
    import cv2

    R, t = pose
    s = 30.0 / px_per_square  # mm per texture pixel
    # texture pixel centre j is at (j + 0.5 - origin) s on the board (pixel edges on its edges)
    off = (0.5 - origin_px) * s
    A = np.array([[s, 0, off], [0, s, off], [0, 0, 1.0]])
    H = K @ np.column_stack([R[:, 0], R[:, 1], t]) @ A
    # pixel centres at integers on both sides: OpenCV's warp maps centres to centres
    frame = cv2.warpPerspective(tex, H, size, flags=cv2.INTER_LINEAR, borderValue=(40, 40, 40))
    if noise:
        rng = rng or np.random.default_rng(0)
        frame = np.clip(frame + rng.normal(0, noise, frame.shape), 0, 255).astype(np.uint8)
    return frame


def write_video(
    path: Path, K: np.ndarray, n: int, size: tuple[int, int], kind: str = "charuco", fps: float = 30
) -> list[tuple[np.ndarray, np.ndarray]]:
    """Render ``n`` frames to ``path`` (a video file, or a folder of PNGs); return the poses."""
    from imageform.io import VideoWriter, write_image

    tex, origin = board_texture(kind)
    truth = poses(n)
    rng = np.random.default_rng(1)
    frames = (render(tex, origin, K, p, size, rng=rng) for p in truth)
    if path.suffix:
        with VideoWriter(path, fps=fps, quality=12) as video:
            for f in frames:
                video.write(f)
    else:
        path.mkdir(parents=True, exist_ok=True)
        for i, f in enumerate(frames):
            write_image(path / f"frame{i:04d}.png", f)
    return truth


def marker_frame(
    K: np.ndarray,
    pose: tuple[np.ndarray, np.ndarray],
    size: tuple[int, int],
    *,
    marker_id: int = 7,
    dictionary: str = "4x4_50",
    side: float = 40.0,
    noise: float = 2.0,
    blur: float = 0.0,
    rng: np.random.Generator | None = None,
) -> np.ndarray:
    """One grey frame of an ArUco marker (imageform's image of it) seen from ``pose``.

    The marker's frame is OpenCV's (centre origin, x right, y up, z out of the print: as
    :func:`imageform.geometry.marker_points`), a white margin of a third of its side around
    it on a grey background; drawn at 4x4 supersampling and averaged down (edges as a lens
    and sensor blur them, not aliased), then a Gaussian blur of ``blur`` pixels and sensor
    noise.
    """
    import cv2

    from imageform.geometry import aruco_marker_image

    R, t = pose
    px = 240
    q = px // 3
    tex = np.full((px + 2 * q, px + 2 * q), 255, np.uint8)
    tex[q : q + px, q : q + px] = aruco_marker_image(marker_id, dictionary, size_px=px)
    s = side / px
    # texture pixel (j, i) centre at x = (j + 0.5 - q) s - side/2, y = side/2 - (i + 0.5 - q) s
    A = np.array([[s, 0, (0.5 - q) * s - side / 2], [0, -s, side / 2 - (0.5 - q) * s], [0, 0, 1]])
    S = 4
    K4 = np.diag([S, S, 1.0]) @ K
    K4[0, 2], K4[1, 2] = S * K[0, 2] + (S - 1) / 2, S * K[1, 2] + (S - 1) / 2
    H = K4 @ np.column_stack([R[:, 0], R[:, 1], t]) @ A
    big = cv2.warpPerspective(
        tex, H, (size[0] * S, size[1] * S), flags=cv2.INTER_LINEAR, borderValue=90
    )
    f = cv2.resize(big, size, interpolation=cv2.INTER_AREA).astype(np.float64)
    if blur:
        f = cv2.GaussianBlur(f, (0, 0), blur)
    if noise:
        rng = rng or np.random.default_rng(0)
        f = f + rng.normal(0, noise, f.shape)
    return np.clip(np.round(f), 0, 255).astype(np.uint8)


def marker_poses(n: int, distance: float = 300.0) -> list[tuple[np.ndarray, np.ndarray]]:
    """A smooth path around a marker at the origin (its z towards the camera): R, t in mm."""
    from imageform.geometry import look_at

    out = []
    for i in range(n):
        a = 2 * np.pi * i / max(n, 1)
        eye = np.array([90 * np.cos(a), 60 * np.sin(a), distance])
        pose = look_at(eye, np.array([8 * np.sin(a), 0.0, 0.0]), up=(0.0, 1.0, 0.0))
        out.append((np.asarray(pose.R, np.float64), np.asarray(pose.t, np.float64)))
    return out


def map_frame(
    K: np.ndarray,
    pose: tuple[np.ndarray, np.ndarray],
    size: tuple[int, int],
    marker_map: object,
    *,
    drawn: dict[int, int] | None = None,
    margin: float = 0.25,
    backing: bool = True,
    noise: float = 2.0,
    blur: float = 0.0,
    rng: np.random.Generator | None = None,
) -> np.ndarray:
    """One grey frame of a :class:`~imageform.geometry.MarkerMap`'s markers seen from ``pose``.

    Each marker is imageform's image of it with a white margin of ``margin`` of its side,
    placed by its corners in the map (``pose``: map to camera), drawn far to near and
    only from its printed side (a cube's hidden faces are not drawn); a planar map is first
    given a white backing over its extent (``backing``). ``drawn`` maps a marker's index in
    the map to the id drawn there instead (a wrongly decoded marker). As
    :func:`marker_frame`: 4x4 supersampling, Gaussian blur of ``blur`` px, noise.
    """
    import cv2

    from imageform.geometry import aruco_marker_image

    R, t = pose
    m = marker_map
    S = 4
    K4 = np.diag([S, S, 1.0]) @ K
    K4[0, 2], K4[1, 2] = S * K[0, 2] + (S - 1) / 2, S * K[1, 2] + (S - 1) / 2
    shape = (size[1] * S, size[0] * S)
    big = np.full(shape, 90.0)
    corners = np.asarray(m.corners)  # type: ignore[attr-defined]
    if backing and np.ptp(corners[..., 2]) == 0:
        lo = corners[..., :2].reshape(-1, 2).min(0) - margin * float(m.sides.max())  # type: ignore[attr-defined]
        hi = corners[..., :2].reshape(-1, 2).max(0) + margin * float(m.sides.max())  # type: ignore[attr-defined]
        A = np.array([[hi[0] - lo[0], 0, lo[0]], [0, hi[1] - lo[1], lo[1]], [0, 0, 1]])
        H = K4 @ np.column_stack([R[:, 0], R[:, 1], R[:, 2] * corners[0, 0, 2] + t]) @ A
        unit = np.float32([[0, 0], [1, 0], [1, 1], [0, 1]])
        quad = cv2.perspectiveTransform(unit[None], H)[0]
        cv2.fillConvexPoly(big, np.round(quad * 16).astype(np.int32), 255.0, shift=4)
    Rm, tm = m.marker_poses  # type: ignore[attr-defined]
    depth = [(R @ tm[i] + t)[2] for i in range(len(m))]  # type: ignore[arg-type]
    px = 120
    q = round(margin * px)
    for i in np.argsort(depth)[::-1]:
        Rc, tc = R @ Rm[i], R @ tm[i] + t
        if Rc[:, 2] @ tc >= 0:  # its printed side (z out of it) faces away from the camera
            continue
        side = float(m.sides[i])  # type: ignore[attr-defined]
        marker_id = int((drawn or {}).get(int(i), int(m.ids[i])))  # type: ignore[attr-defined]
        tex = np.full((px + 2 * q, px + 2 * q), 255, np.uint8)
        tex[q : q + px, q : q + px] = aruco_marker_image(marker_id, m.dictionary, size_px=px)  # type: ignore[attr-defined]
        s = side / px
        A = np.array(
            [[s, 0, (0.5 - q) * s - side / 2], [0, -s, side / 2 - (0.5 - q) * s], [0, 0, 1]]
        )
        H = K4 @ np.column_stack([Rc[:, 0], Rc[:, 1], tc]) @ A
        warped = cv2.warpPerspective(
            tex.astype(np.float32), H, shape[::-1], flags=cv2.INTER_LINEAR, borderValue=-1
        )
        cover = cv2.warpPerspective(
            np.ones(tex.shape, np.float32), H, shape[::-1], flags=cv2.INTER_LINEAR
        )
        big = big * (1 - cover) + np.where(warped >= 0, warped, 0) * cover
    f = cv2.resize(big, size, interpolation=cv2.INTER_AREA)
    if blur:
        f = cv2.GaussianBlur(f, (0, 0), blur)
    if noise:
        rng = rng or np.random.default_rng(0)
        f = f + rng.normal(0, noise, f.shape)
    return np.clip(np.round(f), 0, 255).astype(np.uint8)
