r"""The renderer: per-pixel ray casting with supersampling, through the lens model.

For each of the ``S x S`` sub-pixel positions of every pixel the ray is found by undoing
the camera model: :math:`(x, y) = \mathrm{undistort}(K^{-1}(u, v, 1))` (for the camera
obscura, the image plane is behind the pinhole and :math:`x = (c_x - u)/f_x`,
:math:`y = (c_y - v)/f_y`: the image is inverted). The ray :math:`s\,(x, y, 1)` is
intersected with every planar object (nearest hit wins), the hit's texture coordinates
give its material, the material's precomputed electron rate (:mod:`.materials`) is looked
up and multiplied by the natural vignetting :math:`\cos^4\theta = (1 + x^2 + y^2)^{-2}`;
the samples of a pixel are averaged (a box filter over the pixel's area).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from imageform._backend import use_numba
from imageform._validate import as_int, check_memory, check_type, real_array
from imageform.errors import InvalidInputError
from imageform.geometry.camera import Camera
from imageform.simulate.config import (
    CheckerboardConfig,
    ColorCheckerConfig,
    GroundConfig,
    ImageConfig,
    ObjectConfig,
    PlaneConfig,
)
from imageform.simulate.materials import electron_rates, reflectance_spectrum, texture_basis
from imageform.simulate.scene import Scene, SceneObject
from imageform.simulate.schema import MAX_SUPERSAMPLING
from imageform.simulate.textures import load_texture
from imageform.spectral import COLORCHECKER_PATCHES

__all__ = ["RenderOutput", "load_texture", "pixel_rays", "raycast_quads_numpy", "render_scene"]


@dataclass(frozen=True)
class RenderOutput:
    """What the renderer produced: photo-electron rate, depth, falloff and object index.

    ``rate`` ``(H, W, 3)`` mean photo-electrons per second (vignetted), ``depth`` ``(H, W)``
    camera-frame depth (m; ``inf`` where nothing was hit), ``falloff`` ``(H, W)`` the cos⁴
    vignetting at pixel centres (1 when disabled) and ``object_index`` ``(H, W)`` the object at each
    pixel centre (-1: background).
    """

    rate: np.ndarray
    depth: np.ndarray
    falloff: np.ndarray
    object_index: np.ndarray


def raycast_quads_numpy(
    xy: np.ndarray, origin: np.ndarray, normal: np.ndarray, dual_a: np.ndarray, dual_b: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Plain NumPy twin of :func:`imageform._kernels.raycast.raycast_quads` (same outputs)."""
    n = xy.shape[0]
    best = np.full(n, np.inf)
    idx = np.full(n, -1, dtype=np.int32)
    a_out = np.zeros(n)
    b_out = np.zeros(n)
    finite = np.isfinite(xy).all(axis=1)
    d = np.concatenate([np.where(finite[:, None], xy, 0.0), np.ones((n, 1))], axis=1)
    for q in range(origin.shape[0]):
        den = d @ normal[q]
        num = float(normal[q] @ origin[q])
        with np.errstate(divide="ignore", invalid="ignore"):
            s = np.where(den != 0, num / np.where(den != 0, den, 1.0), -1.0)
        rel = s[:, None] * d - origin[q]
        a = rel @ dual_a[q]
        b = rel @ dual_b[q]
        hit = finite & (s > 0) & (s < best) & (a >= 0) & (a < 1) & (b >= 0) & (b < 1)
        best = np.where(hit, s, best)
        idx = np.where(hit, q, idx).astype(np.int32)
        a_out = np.where(hit, a, a_out)
        b_out = np.where(hit, b, b_out)
    return idx, a_out, b_out, best


def _raycast(xy: np.ndarray, *quads: np.ndarray) -> tuple[np.ndarray, ...]:
    if use_numba(xy):
        from imageform._kernels.raycast import raycast_quads

        return raycast_quads(xy, *quads)
    return raycast_quads_numpy(xy, *quads)


def _quads_camera(objects: tuple[SceneObject, ...], camera: Camera) -> tuple[np.ndarray, ...]:
    """Origin, normal and dual edge vectors of each object in the camera frame."""
    R = np.asarray(camera.R, dtype=np.float64)
    t = np.asarray(camera.t, dtype=np.float64)
    origin, normal, ga, gb = [], [], [], []
    for o in objects:
        e1 = R @ o.edge_right
        e2 = R @ o.edge_down
        n = np.cross(e1, e2)
        # dual basis: (X - O) . g_a = a, (X - O) . g_b = b for X = O + a e1 + b e2
        g1 = np.cross(e2, n) / float(e1 @ np.cross(e2, n))
        g2 = np.cross(n, e1) / float(e2 @ np.cross(n, e1))
        origin.append(R @ o.origin + t)
        normal.append(n / np.linalg.norm(n))
        ga.append(g1)
        gb.append(g2)
    if not objects:
        z = np.zeros((0, 3))
        return z, z, z, z
    return np.array(origin), np.array(normal), np.array(ga), np.array(gb)


def pixel_rays(camera: Camera, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Ideal normalised ray coordinates ``(N, 2)`` ``(x, y)`` of pixels ``(u, v)``.

    NaN where the distortion model cannot be inverted (outside its valid radius).

    Examples
    --------
    >>> cam = Camera([[100.0, 0, 50], [0, 100.0, 40], [0, 0, 1]], image_plane="real")
    >>> pixel_rays(cam, np.array([60.0]), np.array([40.0])).tolist()
    [[-0.1, -0.0]]
    """
    check_type(camera, Camera, "camera")
    u = real_array(u, "u", ndim=1)
    v = real_array(v, "v", ndim=1)
    if u.shape != v.shape:
        raise InvalidInputError(f"expected u and v of one shape, got {u.shape} and {v.shape}")
    return _pixel_rays(camera, u, v)


def _pixel_rays(camera: Camera, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """:func:`pixel_rays` without the checks (the renderer's own finite pixel grid)."""
    K = np.asarray(camera.K, dtype=np.float64)
    fx, s, cx, fy, cy = K[0, 0], K[0, 1], K[0, 2], K[1, 1], K[1, 2]
    y = (v - cy) / fy
    x = (u - cx - s * y) / fx
    xy = np.stack([x, y], axis=-1)
    if camera.image_plane == "real":
        return -xy
    if camera.distortion is not None:
        ideal, ok = camera.distortion.undistort(xy)
        return np.where(np.asarray(ok)[:, None], np.asarray(ideal), np.nan)
    return xy


class _Shader:
    """Material look-up for each object: texture coordinates -> electrons per second."""

    def __init__(self, scene: Scene, f_number: float) -> None:
        cfg = scene.config
        self.objects = [o.config for o in scene.objects]
        self.keys: list[float | str] = []
        il, lux = scene.illuminant, cfg.illuminant.illuminance_lux
        self.plan: list[Any] = []
        bg = self._mat(cfg.render.background_reflectance)
        for o in self.objects:
            if isinstance(o, CheckerboardConfig):
                self.plan.append((self._mat(o.dark_reflectance), self._mat(o.light_reflectance)))
            elif isinstance(o, ColorCheckerConfig):
                mats = [self._mat(n) for n in COLORCHECKER_PATCHES]
                self.plan.append((mats, self._mat(o.frame_reflectance)))
            elif isinstance(o, GroundConfig):
                self.plan.append(
                    (
                        self._mat(o.reflectance),
                        self._mat(o.rail_reflectance),
                        self._mat(o.sleeper_reflectance),
                    )
                )
            elif isinstance(o, PlaneConfig):
                self.plan.append(self._mat(o.reflectance))
            else:
                assert isinstance(o, ImageConfig)
                self.plan.append(load_texture(o.path, scene.base_dir))
        spectra = [reflectance_spectrum(k) for k in self.keys]
        wl = spectra[0][0]
        refl = np.stack([s[1] for s in spectra], axis=1)
        self.table = electron_rates(refl, wl, il, lux, scene.sensor, f_number)  # (M, 3)
        bwl, B = texture_basis()
        self.texture_matrix = electron_rates(B, bwl, il, lux, scene.sensor, f_number)  # (3, 3)
        self.background = self.table[bg]

    def _mat(self, key: float | str) -> int:
        if key not in self.keys:
            self.keys.append(key)
        return self.keys.index(key)

    def shade(self, idx: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        out = np.empty((idx.size, 3))
        out[:] = self.background
        for q, (o, data) in enumerate(zip(self.objects, self.plan, strict=True)):
            sel = np.flatnonzero(idx == q)
            if sel.size == 0:
                continue
            aq, bq = a[sel], b[sel]
            if isinstance(o, ImageConfig):
                tex = data
                th, tw = tex.shape[:2]
                r = np.minimum((bq * th).astype(np.int64), th - 1)
                c = np.minimum((aq * tw).astype(np.int64), tw - 1)
                out[sel] = tex[r, c] @ self.texture_matrix
                continue
            out[sel] = self.table[_materials(o, data, aq, bq)]
        return out


def _materials(o: ObjectConfig, data: Any, a: np.ndarray, b: np.ndarray) -> Any:
    """Material index of each texture coordinate ``(a, b)`` in [0, 1)² of an object."""
    if isinstance(o, PlaneConfig):
        return np.full(a.shape, data)
    if isinstance(o, CheckerboardConfig):
        dark, light = data
        c, r = o.squares
        m = o.margin_squares
        X = a * (c + 2 * m) - m
        Y = b * (r + 2 * m) - m
        inside = (X >= 0) & (c > X) & (Y >= 0) & (r > Y)
        parity = (np.floor(X) + np.floor(Y)).astype(np.int64) % 2
        return np.where(inside & (parity == 0), dark, light)
    if isinstance(o, ColorCheckerConfig):
        mats, frame = data
        g = o.gap_fraction / 2
        X, Y = a * 6.0, b * 4.0
        i, j = np.floor(X), np.floor(Y)
        fx, fy = X - i, Y - j
        inside = (fx >= g) & (fx < 1 - g) & (fy >= g) & (fy < 1 - g)
        k = (j * 6 + i).astype(np.int64).clip(0, 23)
        return np.where(inside, np.asarray(mats)[k], frame)
    assert isinstance(o, GroundConfig)  # with rails and sleepers
    ground, rail, sleeper = data
    w, length = o.size_m
    x = (a - 0.5) * w
    along = b * length
    out = np.full(a.shape, ground)
    if o.sleeper_spacing_m > 0 and o.sleeper_width_m > 0:
        on = (np.mod(along, o.sleeper_spacing_m) < o.sleeper_width_m) & (
            np.abs(x) < o.sleeper_length_m / 2
        )
        out = np.where(on, sleeper, out)
    count = int(o.rail_count)
    for kr in range(count):
        xk = (kr - (count - 1) / 2) * o.rail_gauge_m
        out = np.where(np.abs(x - xk) < o.rail_width_m / 2, rail, out)
    return out


def render_scene(
    scene: Scene,
    *,
    progress: Callable[[float], object] | None = None,
    rows_per_chunk: int = 180,
) -> RenderOutput:
    """Ray-cast the scene: mean photo-electrons per second per pixel and channel.

    See the module docstring for the model. ``progress(fraction)`` is called after each
    band of rows.

    Examples
    --------
    >>> from imageform.simulate import default_scene
    >>> out = render_scene(default_scene().with_changes(render={"width": 64, "height": 36}))
    >>> out.rate.shape, bool(out.rate.min() >= 0)
    ((36, 64, 3), True)
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"expected scene as a Scene (load_scene), got {type(scene).__name__}")
    if progress is not None and not callable(progress):
        raise TypeError(f"expected progress as a callable or None, got {type(progress).__name__}")
    rows_per_chunk = as_int(rows_per_chunk, "rows_per_chunk", minimum=1)
    cfg = scene.config
    w, h = scene.image_size
    S = int(cfg.render.supersampling)
    if not 1 <= S <= MAX_SUPERSAMPLING:
        raise InvalidInputError(
            f"expected scene render.supersampling in [1, {MAX_SUPERSAMPLING}], got {S}"
        )
    # rate, depth, falloff, index maps + one band of rays (about 16 float64 per ray)
    check_memory(
        8.0 * h * w * 6 + 8.0 * min(rows_per_chunk, h) * w * 16, "scene", f"a {w}x{h} render"
    )
    vignette = cfg.lens.vignetting == "cos4"
    shader = _Shader(scene, float(cfg.lens.f_number))
    quads = _quads_camera(scene.objects, scene.camera)
    offsets = (np.arange(S) + 0.5) / S - 0.5
    rate = np.zeros((h, w, 3))
    inv_depth = np.zeros((h, w))
    falloff = np.ones((h, w))
    obj = np.full((h, w), -1, dtype=np.int32)
    for r0 in range(0, h, rows_per_chunk):
        r1 = min(h, r0 + rows_per_chunk)
        vv, uu = np.mgrid[r0:r1, 0:w].astype(np.float64)
        uu, vv = uu.ravel(), vv.ravel()
        acc = np.zeros((uu.size, 3))
        acc_inv = np.zeros(uu.size)
        for oy in offsets:
            for ox in offsets:
                xy = _pixel_rays(scene.camera, uu + ox, vv + oy)
                idx, a, b, depth = _raycast(xy, *quads)
                val = shader.shade(idx, a, b)
                if vignette:
                    r2 = np.where(np.isfinite(xy[:, 0]), xy[:, 0] ** 2 + xy[:, 1] ** 2, np.inf)
                    val *= (1.0 / (1.0 + r2) ** 2)[:, None]
                acc += val
                acc_inv += np.where(np.isfinite(depth), 1.0 / depth, 0.0)
        rate[r0:r1] = (acc / S**2).reshape(r1 - r0, w, 3)
        inv_depth[r0:r1] = (acc_inv / S**2).reshape(r1 - r0, w)
        xy0 = _pixel_rays(scene.camera, uu, vv)
        idx0 = _raycast(xy0, *quads)[0]
        obj[r0:r1] = idx0.reshape(r1 - r0, w)
        if vignette:
            r2 = xy0[:, 0] ** 2 + xy0[:, 1] ** 2
            f = np.where(np.isfinite(r2), 1.0 / (1.0 + r2) ** 2, np.nan)
            falloff[r0:r1] = f.reshape(r1 - r0, w)
        if progress is not None:
            progress(r1 / h)
    if not np.all(np.isfinite(falloff)):
        raise InvalidInputError(
            "the distortion model cannot be inverted at some pixels (outside its valid "
            "radius): reduce camera.distortion or widen the focal length"
        )
    with np.errstate(divide="ignore"):
        depth_map = np.where(inv_depth > 0, 1.0 / inv_depth, np.inf)
    return RenderOutput(rate=rate, depth=depth_map, falloff=falloff, object_index=obj)
