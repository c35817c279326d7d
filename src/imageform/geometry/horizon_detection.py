"""The visible horizon of a natural scene: sea, lake or plain meeting the sky.

A photograph of open water or flat land shows the horizon as a line, the image of the plane's
line at infinity (``v = c_y - f tan(pitch)``, turned with the camera's roll), but no vanishing
point gives it: waves, sand and fields have no parallel straight edges to meet.
:func:`detect_horizon` finds it as the image's one long straight edge that runs across the
frame with sky above it: the edge-and-Hough family of maritime horizon detectors, which
Gershikov, Libe & Kosolapov (2013, "Horizon line detection in marine images: which method to
choose?") compare with region criteria such as Ettinger et al. (2003)'s split of sky and
ground colour statistics; a straight edge is what makes the horizon level-straight, and the
acceptance tests below are what make "not found" the answer elsewhere:

1. The photograph is reduced to at most ``_WORK`` pixels on its long side; a low-contrast
   one (haze, fog, a dim exposure: its grey levels span less than ``_STRETCH_RANGE`` between
   their 1st and 99th percentiles) is stretched to the contrast the thresholds below were
   set on (:func:`_stretch_low_contrast`), any other is read as it is; colour gradients
   (Gaussian σ = 1 px, the Di Zenzo structure tensor's strongest direction, so that a
   boundary of hue at equal brightness counts) above a threshold set from the image's own
   gradient distribution are its edge points.
2. Edge points vote in a Hough transform over lines within ``max_roll`` of the rows, each
   point only for lines along its own edge direction (±1°), one vote per point however
   strong: the horizon is long, not necessarily contrasted (haze).
3. Each of the strongest ``_CANDIDATES`` lines is followed along the frame: at every column
   the strongest edge across it within a few pixels, in the line's direction; the line is
   refitted (total least squares, three rounds) to the edge positions.
4. A line is a horizon only where those edges cover ``_COVER`` of its length across the
   frame within 2 px and lie within ``_RESIDUAL`` px of it (RMS; a mountain ridge or a
   treeline is not straight), it is not the frame's own top or bottom edge, the band above
   it is smooth (mean edge strength at most ``_TEX_ABOVE``: sky, not trees or a wall), the
   straight segments (LSD) standing across it above it add up to at most ``_STEEP_ABOVE``
   image diagonals, and the scene is not a built one: at most ``_LONG_SEGMENTS`` straight
   segments longer than a tenth of the diagonal and ``_STEEP`` diagonals of segments across
   the line (facades, rooms and streets have long straight edges everywhere; their long
   horizontal lines, roofs and ceilings, are not horizons). Long segments along the line
   (within ``_WAVE_ANGLE``) and not above it are a wave field's (surf lines, wave crests,
   furrows) and are not counted; where they are what made the scene look built, the line
   may have at most ``_VERT_WAVES`` diagonals of upright segments below it (stacked boxes,
   shelves and storeys have them, surf has none). A building's roof line against
   a clear sky passes all that; it is told from a horizon by what lies beside and below it
   (:func:`_sides`): upright straight segments below it (walls, pillars, window edges,
   within 10 degrees of the image's columns) add up to at most ``_VERT_BELOW`` diagonals,
   at most ``_SKY_BELOW`` of the line has the sky's color on both sides of it (beside a
   building the sky comes down below its roof line; a sea or a plain is below the horizon
   all along), at least ``_SKY_ALONG`` of it has smooth sky just above it, and at least
   ``_AREA_ABOVE`` of the frame lies above it.
5. Of the lines taken, the best-covered is the horizon, put at the sky's end: a distant
   plain under haze meets the sky through a band of paler land whose foot is the strongest
   edge (:func:`_sky_onset`; a sky that brightens steadily down to the horizon, as a thermal
   camera sees it, has no such end). Where that line has ``_WAVE_LINES`` or more long
   straight segments parallel to it (a sea with surf: the surf lines below the horizon are
   straighter and better covered than a hazy horizon), the horizon is, of the lines covered
   nearly as well, the one that parts smooth sky from textured sea: the largest mean edge
   strength below it less that above it (the region contrast of Ettinger et al. 2003,
   with texture for colour).

The thresholds were set on the tuning half of ``benchmarks/check_horizon_natural.py``
(drone frames over farmland, infrared sea frames, five sea photographs, photographs without
a horizon); the roof-line rules after seeing the false horizons of the held-out half
(``benchmarks/results/horizon-natural-2026-11-29h.md``); the wave-field rules and the sky
onset's steady-gradient test on the tuning half only
(``benchmarks/results/horizon-natural-2026-11-30a.md``).
Not found (``found=False``) is the answer for a scene without such a line: a street, a
room, a close-up, mountains. A horizon hidden behind land (a bay closed by hills) is not
the true horizon but the foot of the far shore, which is what is found where it is
straight and level.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from imageform._typing import ArrayLike, FloatArray
from imageform._validate import as_image, as_real, check_min_side
from imageform.errors import InvalidInputError

__all__ = ["HorizonResult", "detect_horizon"]

#: Working size: the long side, in pixels.
_WORK = 320
#: Hough: angle step (radians) and how many lines are followed.
_DALPHA = math.radians(0.5)
_CANDIDATES = 12
#: A candidate line is followed within this many working pixels across it.
_SEARCH = 3
#: A line whose chord across the frame is shorter than this share of the width is passed over.
_CHORD = 0.5
#: A line within this share of the height of the frame's top or bottom all along is the frame.
_EDGE = 0.03
#: Acceptance: an edge within 2 px along this share of the chord, at most this RMS distance
#: from the refitted line (working px).
_COVER = 0.55
_RESIDUAL = 1.2
#: A built scene: more than this many straight segments longer than a tenth of the working
#: image's diagonal, or more than this many diagonals of straight segments across the line
#: (within 20 degrees of its normal, each longer than 3 % of the diagonal) ...
_LONG_SEGMENTS = 15
_STEEP = 1.5
#: ... or more than this many diagonals of them above it.
_STEEP_ABOVE = 0.5
#: Sky above: the mean edge strength in the band of ``_BAND`` of the height above the line
#: at most this (image values per px).
_BAND = 0.08
_TEX_ABOVE = 0.05
#: Not a building's roof line nor an object's edge (:func:`_sides`): at most this many
#: diagonals of upright straight segments (within 10 degrees of the image's columns, each
#: longer than 3 % of the diagonal) below the line (walls, pillars, window edges; a level
#: sea, field or airstrip has next to none) ...
_VERT_BELOW = 1.0
#: ... at most this share of the line with the same color just below it as just above it
#: (within ``_SAME`` in image values: the sky coming down beside a building) ...
_SKY_BELOW = 0.15
_SAME = 0.03
#: ... and at least this share of it with smooth sky just above it (mean edge strength in
#: the band above at most ``_SMOOTH``).
_SKY_ALONG = 0.3
_SMOOTH = 0.03
#: A horizon has sky above it: at least this share of the frame (a table's edge near the top
#: of a close-up has not).
_AREA_ABOVE = 0.1
#: Sky onset (:func:`_sky_onset`): a colour step at least this share of the line's own, up
#: to this share of the working height above it.
_ONSET = 0.3
_ONSET_REACH = 0.06
#: ... and at least this many times the sky's own change per px further up (a sky that
#: brightens steadily towards the horizon, as a thermal camera sees it, has no onset).
_ONSET_SKY = 2.0
#: A wave field (surf, wave crests, furrows) below a horizon: long straight segments within
#: ``_WAVE_ANGLE`` of the line and not above it are not counted as a built scene's; where
#: they are what made the scene look built, the line must have at most ``_VERT_WAVES``
#: diagonals of upright segments below it (stacked boxes and storeys have them).
_WAVE_ANGLE = math.radians(5.0)
_VERT_WAVES = 0.25
#: Where the best-covered line has at least ``_WAVE_LINES`` long straight segments parallel
#: to it (within ``_WAVE_ANGLE``), the horizon is, of the lines covered within ``_WAVE_COVER``
#: as well, the one with the largest contrast of texture (mean edge strength below it less
#: that above it): the sky's edge, not a surf line.
_WAVE_LINES = 8
_WAVE_COVER = 0.15
#: A low-contrast photograph (haze, fog, dim): a grey level spanning less than this between
#: these percentiles is stretched to span ``_STRETCH_TO`` (:func:`_stretch_low_contrast`;
#: the vanishing points' stretch, ``imageform.geometry.lsd``, takes 64 of 255).
_STRETCH_PERCENTILES = (1.0, 99.0)
_STRETCH_RANGE = 0.25
#: ... to span this (the median span of the tuning photographs, 0.81, whose contrast the
#: thresholds above were set on): ``[lo, hi]`` to ``[0.1, 0.9]``.
_STRETCH_TO = 0.8
#: Edge points: an edge strength above half the image's 75th percentile and above this, in
#: the input's values (image values per px: the Gaussian derivative's peak over a step of
#: one 8-bit code, 1/255, is 0.0016), times the stretch's gain.
_EDGE_FLOOR = 0.004


@dataclass(frozen=True)
class HorizonResult:
    """What :func:`detect_horizon` found.

    Attributes
    ----------
    found : bool
        Whether a horizon was found.
    line : (3,) or None
        The horizon ``(a, b, c)``, ``a u + b v + c = 0``, ``a² + b² = 1``, ``b > 0`` (the
        representation of :attr:`VanishingPointResult.horizon`), in the input's pixel
        coordinates; None when not found.
    roll : float
        The horizon's angle to the image rows (radians), positive when its right end is
        higher in the picture (the camera rolled clockwise as its user sees it); NaN when
        not found.
    rows : (2,)
        The horizon's row at the first and the last column (``u = 0`` and ``u = W - 1``);
        NaN when not found.
    confidence : float
        In [0, 1]: the share of the horizon's length across the frame along which an edge
        was found within 2 px of it (of the working image, at most 320 px on its long side);
        0 when nothing was found.
    reason : str
        Why nothing was found (one line, docs/conventions.md "Not found"); "" when found.
    """

    found: bool
    line: FloatArray | None
    roll: float
    rows: FloatArray
    confidence: float
    reason: str = ""


def _prepare(image: ArrayLike) -> tuple[np.ndarray, float, float]:
    """Return the working image ``(h, w, c)`` float64, its scale and its contrast gain."""
    from scipy import ndimage

    arr = np.asarray(as_image(image, channels=None))
    if arr.ndim == 3 and arr.shape[-1] in (1, 3):
        pass
    elif arr.ndim == 2:
        arr = arr[..., None]
    else:
        raise InvalidInputError(
            f"expected an (H, W) or (H, W, 3) image, got shape {tuple(arr.shape)}"
        )
    h, w = arr.shape[:2]
    check_min_side(arr.shape, 16)
    scale = min(1.0, _WORK / max(h, w))
    a = arr.astype(np.float64)
    if scale < 1.0:
        sigma = 0.5 / scale
        a = ndimage.gaussian_filter(a, (sigma, sigma, 0), mode="nearest")
        a = ndimage.zoom(a, (scale, scale, 1), order=1, mode="nearest", grid_mode=True)
    stretched, gain = _stretch_low_contrast(a)
    return stretched, scale, gain


def _stretch_low_contrast(a: np.ndarray) -> tuple[np.ndarray, float]:
    """Return a low-contrast working image stretched to span ``_STRETCH_TO``; others as they are.

    The acceptance thresholds (``_SAME``, ``_TEX_ABOVE``, ``_SMOOTH``, the edge floor) are in
    image values, set on photographs of normal contrast; haze, fog, a dim exposure or a
    washed-out print shrink every colour difference with the scene's range. Where the grey
    level (the channels' mean) spans less than ``_STRETCH_RANGE`` between its
    ``_STRETCH_PERCENTILES`` ``lo`` and ``hi``, the image is mapped affinely, ``[lo, hi]``
    to ``[0.1, 0.9]`` (every channel, not clipped), as
    :func:`imageform.geometry.lsd._stretch_low_contrast` does for the vanishing points;
    otherwise (normal contrast, or flat) ``a`` itself is returned and the answer is
    bit-identical. Returns the image and the gain, ``_STRETCH_TO / (hi - lo)`` or 1: the
    edge floor (``_EDGE_FLOOR``) is the input's, multiplied by it, so that a step of one
    8-bit code (a contour of a smooth sky's quantised gradient) does not become an edge.
    """
    lo, hi = (float(x) for x in np.percentile(a.mean(-1), _STRETCH_PERCENTILES))
    if not 0.0 < hi - lo < _STRETCH_RANGE:
        return a, 1.0
    gain = _STRETCH_TO / (hi - lo)
    return 0.5 * (1.0 - _STRETCH_TO) + (a - lo) * gain, gain


def _gradients(a: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Return the colour edge strength, its direction's unit vector (gx, gy) and luminance gy.

    The Di Zenzo structure tensor (summed over the channels) gives the direction across
    which the colour changes most and the strength of that change.
    """
    from scipy import ndimage

    gx = np.stack(
        [ndimage.gaussian_filter(a[..., k], 1.0, order=(0, 1)) for k in range(a.shape[2])], -1
    )
    gy = np.stack(
        [ndimage.gaussian_filter(a[..., k], 1.0, order=(1, 0)) for k in range(a.shape[2])], -1
    )
    jxx = (gx * gx).sum(-1)
    jyy = (gy * gy).sum(-1)
    jxy = (gx * gy).sum(-1)
    tr = jxx + jyy
    disc = np.sqrt(np.maximum((jxx - jyy) ** 2 / 4 + jxy**2, 0.0))
    mag = np.sqrt(np.maximum(tr / 2 + disc, 0.0))
    theta = 0.5 * np.arctan2(2 * jxy, jxx - jyy)
    lum_x = gx.mean(-1)
    lum_y = gy.mean(-1)
    return mag, np.cos(theta), np.sin(theta), np.stack([lum_x, lum_y], -1)


def _hough(
    mag: np.ndarray, ux: np.ndarray, uy: np.ndarray, thr: float, max_roll: float
) -> list[tuple[float, float, float]]:
    """Return the strongest near-horizontal lines ``(alpha, rho, votes)``.

    A line at angle ``alpha`` to the rows has normal ``(-sin alpha, cos alpha)`` and offset
    ``rho = -sin(alpha) u + cos(alpha) v`` (pixel coordinates of the working image).
    """
    from scipy import ndimage

    h, w = mag.shape
    vs, us = np.nonzero(mag > thr)
    if len(us) == 0:
        return []
    # the edge's direction along it: the gradient direction turned by 90 degrees
    alpha_pix = np.arctan2(-ux[vs, us], uy[vs, us])  # normal (ux, uy) = (-sin a, cos a)
    alpha_pix = (alpha_pix + math.pi / 2) % math.pi - math.pi / 2
    n_alpha = round(max_roll / _DALPHA)
    alphas = np.arange(-n_alpha, n_alpha + 1) * _DALPHA
    keep = np.abs(alpha_pix) <= max_roll + 2 * _DALPHA
    us, vs, alpha_pix = us[keep], vs[keep], alpha_pix[keep]
    rho_max = math.ceil(math.hypot(w, h)) + 1
    acc = np.zeros((len(alphas), 2 * rho_max + 1))
    base = np.rint(alpha_pix / _DALPHA).astype(int) + n_alpha
    for off in (-2, -1, 0, 1, 2):
        k = base + off
        ok = (k >= 0) & (k < len(alphas))
        a = alphas[k[ok]]
        rho = -np.sin(a) * us[ok] + np.cos(a) * vs[ok]
        np.add.at(acc, (k[ok], np.rint(rho).astype(int) + rho_max), 1.0)
    # lines through few columns of the frame (steep and short) are weighed by their chord
    out: list[tuple[float, float, float]] = []
    work = ndimage.uniform_filter1d(acc, 3, axis=1)
    for _ in range(_CANDIDATES):
        i, j = np.unravel_index(int(np.argmax(work)), work.shape)
        if work[i, j] <= 0:
            break
        out.append((float(alphas[i]), float(j - rho_max), float(work[i, j])))
        work[max(0, i - 6) : i + 7, max(0, j - 6) : j + 7] = 0.0
    return out


def _chord(alpha: float, rho: float, w: int, h: int) -> tuple[np.ndarray, np.ndarray]:
    """Return the points of the line inside the frame, one per pixel along it."""
    d = np.array([math.cos(alpha), math.sin(alpha)])
    n = np.array([-math.sin(alpha), math.cos(alpha)])
    p0 = n * rho
    t = np.arange(-2 * (w + h), 2 * (w + h) + 1, 1.0)
    pts = p0[None, :] + t[:, None] * d[None, :]
    inside = (pts[:, 0] >= 0) & (pts[:, 0] <= w - 1) & (pts[:, 1] >= 0) & (pts[:, 1] <= h - 1)
    return pts[inside], n


def _follow(
    pts: np.ndarray,
    n: np.ndarray,
    mag: np.ndarray,
    ux: np.ndarray,
    uy: np.ndarray,
    lum: np.ndarray,
    thr: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return, at each point, the offset across the line of the strongest aligned edge."""
    from scipy import ndimage

    h, w = mag.shape
    offs = np.arange(-_SEARCH, _SEARCH + 1, 1.0)
    q = pts[:, None, :] + offs[None, :, None] * n[None, None, :]
    qi = np.clip(np.rint(q[..., 0]).astype(int), 0, w - 1)
    qj = np.clip(np.rint(q[..., 1]).astype(int), 0, h - 1)
    inside = (q[..., 0] >= 0) & (q[..., 0] <= w - 1) & (q[..., 1] >= 0) & (q[..., 1] <= h - 1)
    m = ndimage.map_coordinates(mag, [q[..., 1].ravel(), q[..., 0].ravel()], order=1)
    m = np.where(inside, m.reshape(q.shape[:2]), 0.0)
    align = np.abs(ux[qj, qi] * n[0] + uy[qj, qi] * n[1])
    score = np.where(align > math.cos(math.radians(12.0)), m, 0.0)
    best = np.argmax(score, axis=1)
    rows = np.arange(len(pts))
    strength = score[rows, best]
    off = offs[best].copy()
    # sub-pixel: a parabola through the three strengths around the peak
    inner = (best > 0) & (best < len(offs) - 1)
    s0 = score[rows[inner], best[inner] - 1]
    s1 = score[rows[inner], best[inner]]
    s2 = score[rows[inner], best[inner] + 1]
    den = s0 - 2 * s1 + s2
    with np.errstate(invalid="ignore", divide="ignore"):
        frac = np.where(den < 0, 0.5 * (s0 - s2) / den, 0.0)
    off[inner] += np.clip(frac, -0.5, 0.5)
    qj0, qi0 = qj[rows, best], qi[rows, best]
    sign = np.sign(lum[qj0, qi0, 0] * n[0] + lum[qj0, qi0, 1] * n[1])
    return off, strength > thr, sign


def _sky_onset(
    a: np.ndarray,
    pts: np.ndarray,
    n: np.ndarray,
    hit: np.ndarray,
    off: np.ndarray,
    h: int,
) -> float:
    """Return how far above the line (working px, <= 0) the sky ends.

    A distant shore or plain under haze meets the sky through a band of paler land; the
    strongest edge is the band's foot, the horizon its top. Across the line, the median
    colour over the columns where the line has an edge gives a profile; the highest step of
    it (a local maximum of the colour change) within ``_ONSET_REACH`` of the height above
    the line that is at least ``_ONSET`` of the line's own step, and ``_ONSET_SKY`` times
    the sky's own change further up (the median over the next ``_ONSET_REACH`` of the
    height), is the sky's end. A sharp sea horizon has none (a sky that pales towards the
    horizon changes smoothly, and one that brightens steadily down to it, as a thermal
    camera sees it, has no step that stands out of its own gradient): 0.
    """
    reach = max(4, round(_ONSET_REACH * h))
    cols = pts[hit] + off[hit, None] * n[None, :]
    if len(cols) < 5:
        return 0.0
    d = np.arange(-2 * reach, reach + 1, dtype=np.float64)
    q = cols[None, :, :] + d[:, None, None] * n[None, None, :]
    qi = np.clip(np.rint(q[..., 0]).astype(int), 0, a.shape[1] - 1)
    qj = np.clip(np.rint(q[..., 1]).astype(int), 0, a.shape[0] - 1)
    inside = (q[..., 1] >= 0) & (q[..., 1] <= a.shape[0] - 1)
    # the median colour at each distance, over the columns where it lies in the frame
    inside_cols = inside.sum(axis=1)
    if (inside_cols > 0).sum() < len(d) // 2:
        return 0.0
    vals = np.where(inside[..., None], a[qj, qi], np.inf)
    srt = np.sort(vals, axis=1)
    mid = np.maximum(inside_cols - 1, 0) // 2
    prof = np.take_along_axis(srt, mid[:, None, None], axis=1)[:, 0, :]
    prof = np.where(inside_cols[:, None] > 0, prof, np.nan)
    z = int(np.nonzero(d == 0)[0][0])
    # colour change from one step across the line to the next, smoothed over three
    diff = np.full(len(d), np.nan)
    diff[1:] = np.linalg.norm(np.diff(prof, axis=0), axis=1)
    diff = np.convolve(np.nan_to_num(diff), np.ones(3) / 3, mode="same")
    main = float(diff[z - 1 : z + 2].max())
    if main <= 0:
        return 0.0
    # the sky's own change per px further up (beyond the reach): a step must stand out of it
    sky = float(np.median(diff[1 : z - reach]))
    best = 0.0
    for k in range(z - 3, z - reach - 1, -1):
        peak = diff[k] >= diff[k - 1] and diff[k] >= diff[k + 1]
        if peak and diff[k] >= _ONSET * main and diff[k] >= _ONSET_SKY * sky:
            best = float(d[k]) - 0.5  # diff[k] is the step between d[k-1] and d[k]
    return best


def _median_inside(col: np.ndarray, count: np.ndarray) -> np.ndarray:
    """Return the median over axis 0 of ``col`` (NaN outside the frame; ``count`` inside)."""
    srt = np.sort(col, axis=0)  # NaN sorts last
    lo = np.take_along_axis(srt, ((count - 1) // 2)[None, :, None], axis=0)[0]
    hi = np.take_along_axis(srt, (count // 2)[None, :, None], axis=0)[0]
    return 0.5 * (lo + hi)


def _sides(
    a: np.ndarray, mag: np.ndarray, pts: np.ndarray, n: np.ndarray, h: int
) -> tuple[float, float]:
    """Return the shares of the line with the sky's color below it and with sky above it.

    At each point of the line, the median color of the band of ``_BAND`` of the height just
    above it (from 2 px) and of the band just below it are compared: within ``_SAME`` is
    the sky continuing past the line (a roof line beside which the sky comes down; a sea
    horizon has the sea below it all along). The band above is sky where its mean edge
    strength is at most ``_SMOOTH``. Points with less than half of either band in the frame
    are left out of the first share and count as without sky in the second; none left:
    (0, 0).
    """
    hh, ww = mag.shape
    band = max(4.0, _BAND * h)
    d = np.arange(2.0, 2.0 + band)

    def sample(ds: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        q = pts[None, :, :] + ds[:, None, None] * n[None, None, :]
        inside = (q[..., 0] >= 0) & (q[..., 0] <= ww - 1) & (q[..., 1] >= 0)
        inside &= q[..., 1] <= hh - 1
        qi = np.clip(np.rint(q[..., 0]).astype(int), 0, ww - 1)
        qj = np.clip(np.rint(q[..., 1]).astype(int), 0, hh - 1)
        col = np.where(inside[..., None], a[qj, qi], np.nan)
        return col, np.where(inside, mag[qj, qi], 0.0), inside

    col_up, mag_up, in_up = sample(-d)
    col_dn, _, in_dn = sample(d)
    half = len(d) / 2
    valid = (in_up.sum(0) >= half) & (in_dn.sum(0) >= half)
    if not valid.any():
        return 0.0, 0.0
    med_up = _median_inside(col_up[:, valid], in_up[:, valid].sum(0))
    med_dn = _median_inside(col_dn[:, valid], in_dn[:, valid].sum(0))
    same = np.linalg.norm(med_up - med_dn, axis=-1) <= _SAME
    smooth = mag_up[:, valid].sum(0) / in_up[:, valid].sum(0) <= _SMOOTH
    # a point without the band above in the frame has no sky above it
    return float(same.mean()), float(smooth.sum()) / len(pts)


def _fit(pts: np.ndarray, weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Total least squares line through points: (unit normal, centroid)."""
    mean = (weights[:, None] * pts).sum(0) / weights.sum()
    d = pts - mean
    cov = (d * weights[:, None]).T @ d
    normal = np.linalg.eigh(cov)[1][:, 0]
    return normal, mean


def _band(
    shape: tuple[int, int], normal: np.ndarray, point: np.ndarray, lo: float, hi: float
) -> np.ndarray:
    """Boolean mask of the pixels at signed distance in [lo, hi) from the line (+: below)."""
    h, w = shape
    vv, uu = np.mgrid[0:h, 0:w]
    dist = (uu - point[0]) * normal[0] + (vv - point[1]) * normal[1]
    return (dist >= lo) & (dist < hi)


@dataclass
class _Candidate:
    """One line followed across the frame, in working pixels, and what decides on it."""

    normal: np.ndarray  # unit, pointing down the picture (b > 0)
    point: np.ndarray
    cover: float = 0.0  # share of the chord with an edge within 2 px
    resid: float = math.inf  # RMS distance of those edges to the line (px)
    chord: float = 0.0  # the chord's length over the frame's width
    shift: float = 0.0  # where the sky ends, across the line (px, <= 0)
    at_edge: bool = False  # along the frame's top or bottom edge
    tex_above: float = 0.0  # mean edge strength in the band above
    steep: float = 0.0  # straight segments across the line (image diagonals)
    steep_above: float = 0.0  # ... those above it
    vert_below: float = 0.0  # upright straight segments below it (image diagonals)
    sky_below: float = 0.0  # share of it with the sky's color on both sides
    sky_along: float = 1.0  # share of it with smooth sky just above
    area_above: float = 1.0  # share of the frame above it
    waves: int = 0  # long straight segments along it and not above it (a wave field)
    parallel: int = 0  # long straight segments along it, anywhere
    contrast: float = -math.inf  # mean edge strength below it less that above it
    why: str = ""


def _evaluate(
    cand: tuple[float, float, float],
    a: np.ndarray,
    grads: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    thr: float,
    seg_d: np.ndarray,
    seg_m: np.ndarray,
) -> _Candidate:
    """Follow one candidate line, refit it and measure what decides whether it is a horizon."""
    mag, ux, uy, lum = grads
    h, w = mag.shape
    alpha, rho, _ = cand
    pts, n = _chord(alpha, rho, w, h)
    c = _Candidate(normal=n, point=n * rho)
    if len(pts) < _CHORD * w:
        c.why = "short"
        return c
    for _ in range(3):
        off, hit, _sign = _follow(pts, c.normal, mag, ux, uy, lum, thr)
        if hit.sum() < 0.2 * len(pts):
            c.why = "no edge along it"
            return c
        edge = pts[hit] + off[hit, None] * c.normal[None, :]
        dist = (edge - c.point) @ c.normal
        keep = np.abs(dist - np.median(dist)) <= 2.0
        normal, mean = _fit(edge[keep], np.ones(int(keep.sum())))
        if normal[1] < 0:
            normal = -normal
        pts, _ = _chord(math.atan2(-normal[0], normal[1]), float(normal @ mean), w, h)
        c.normal, c.point = normal, mean
        if len(pts) < _CHORD * w:
            c.why = "short"
            return c
    off, hit, _sign = _follow(pts, c.normal, mag, ux, uy, lum, thr)
    c.chord = len(pts) / w
    c.shift = _sky_onset(a, pts, c.normal, hit, off, h)
    edge = pts[hit] + off[hit, None] * c.normal[None, :]
    dist = (edge - c.point) @ c.normal
    near = np.abs(dist) <= 2.0
    c.resid = float(np.sqrt(np.mean(dist[near] ** 2))) if near.any() else math.inf
    c.cover = float((hit & (np.abs(off) <= 2.0)).mean())
    margin = max(3.0, _EDGE * h)
    c.at_edge = bool(np.all(pts[:, 1] < margin) or np.all(pts[:, 1] > h - 1 - margin))
    band = max(4.0, _BAND * h)
    above = _band((h, w), c.normal, c.point, -band, -2.0)
    if above.sum() > 10:
        c.tex_above = float(mag[above].mean())
    slen = np.hypot(seg_d[:, 0], seg_d[:, 1])
    across = np.abs(seg_d @ c.normal) / np.maximum(slen, 1e-9)
    diag = math.hypot(w, h)
    steep = (across > math.cos(math.radians(20.0))) & (slen > 0.03 * diag)
    side = (seg_m - c.point) @ c.normal  # +: below the line
    c.steep = float(slen[steep].sum()) / diag
    c.steep_above = float(slen[steep & (side < -1.0)].sum()) / diag
    upright = np.abs(seg_d[:, 1]) / np.maximum(slen, 1e-9) > math.cos(math.radians(10.0))
    c.vert_below = float(slen[upright & (slen > 0.03 * diag) & (side > 1.0)].sum()) / diag
    along = (across < math.sin(_WAVE_ANGLE)) & (slen > 0.1 * diag)
    c.parallel = int(along.sum())
    c.waves = int((along & (side > -1.0)).sum())
    if c.cover >= _COVER and c.resid <= _RESIDUAL and not c.at_edge:
        # only where it matters (:func:`_reject` rejects the others first): it is the costly part
        c.sky_below, c.sky_along = _sides(a, mag, pts, c.normal, h)
        vv, uu = np.mgrid[0:h, 0:w]
        dist = (uu - c.point[0]) * c.normal[0] + (vv - c.point[1]) * c.normal[1]
        up, down = dist < -2.0, dist >= 2.0
        if up.sum() > 10 and down.sum() > 10:
            c.contrast = float(mag[down].mean() - mag[up].mean())
    # pixels above the line: in column u, the rows v < the line's row there (b > 0)
    line_v = c.point[1] - (np.arange(w) - c.point[0]) * c.normal[0] / c.normal[1]
    c.area_above = float(np.clip(np.ceil(line_v), 0, h).sum()) / (h * w)
    return c


def _reject(c: _Candidate, n_long: int) -> str:
    """Return "" when the candidate is a horizon, else why it is not (a few words)."""
    if c.why:
        return c.why
    if c.at_edge:
        return "the frame's edge"
    if n_long - c.waves > _LONG_SEGMENTS or c.steep > _STEEP:
        return "a built scene (long straight segments)"
    if n_long > _LONG_SEGMENTS and c.vert_below > _VERT_WAVES:
        return "a built scene (long straight segments with upright ones below)"
    if c.cover < _COVER:
        return "an edge along too little of it"
    if c.resid > _RESIDUAL:
        return "not straight"
    if c.steep_above > _STEEP_ABOVE:
        return "straight edges standing above it"
    if c.area_above < _AREA_ABOVE:
        return "too little of the frame above it"
    if c.tex_above > _TEX_ABOVE or c.sky_along < _SKY_ALONG:
        return "no smooth sky above it"
    if c.vert_below > _VERT_BELOW:
        return "upright straight edges below it (a building)"
    if c.sky_below > _SKY_BELOW:
        return "the sky's color on both sides of it"
    return ""


def _same(c: _Candidate, d: _Candidate) -> bool:
    """Whether two refitted lines are one: within 1 degree and 2 working px of each other."""
    if abs(float(c.normal @ d.normal)) < math.cos(math.radians(1.0)):
        return False
    return abs(float(c.normal @ (d.point - c.point))) <= 2.0


def _choose(
    cands: list[_Candidate], n_long: int, scale: float, w: int
) -> tuple[FloatArray | None, _Candidate | None, list[str]]:
    """Return the horizon (input pixels) and its candidate, or None; and each one's verdict."""
    reasons = [_reject(c, n_long) for c in cands]
    good = [c for c, r in zip(cands, reasons, strict=True) if not r]
    if not good:
        return None, None, reasons
    # one edge found twice (two Hough peaks refitted onto it): the better-covered stays
    distinct: list[_Candidate] = []
    for c in sorted(good, key=lambda c: -c.cover):
        if not any(_same(c, d) for d in distinct):
            distinct.append(c)

    def line_of(c: _Candidate) -> FloatArray:
        # working pixel (x) to input pixel (u): u = (x + 0.5) / scale - 0.5; the line
        # through the sky's end, ``shift`` above the strongest edge
        p_in = (c.point + c.shift * c.normal + 0.5) / scale - 0.5
        return np.array([c.normal[0], c.normal[1], -float(c.normal @ p_in)])

    # the best-covered line; of equally covered ones, the highest at the centre column
    best = min(distinct, key=lambda c: (-c.cover, _row(line_of(c), (w - 1) / 2)))
    if best.parallel >= _WAVE_LINES:
        # a wave field: the surf lines below the horizon are as straight and better covered;
        # the horizon parts smooth sky from textured sea (Ettinger et al. 2003's criterion)
        near = [c for c in distinct if c.cover >= best.cover - _WAVE_COVER]
        best = max(near, key=lambda c: c.contrast)
    return line_of(best), best, reasons


def _row(line: FloatArray, u: float) -> float:
    """Return the row of ``a u + b v + c = 0`` at column ``u`` (b > 0)."""
    return float(-(line[0] * u + line[2]) / line[1])


def _candidates(image: ArrayLike, max_roll: float) -> tuple[list[_Candidate], int, float]:
    """Return the candidate lines, the long segments' count and the working scale."""
    from imageform.geometry.line_segments import detect_line_segments

    a, scale, gain = _prepare(image)
    grads = _gradients(a)
    mag = grads[0]
    thr = max(float(np.percentile(mag, 75)) * 0.5, _EDGE_FLOOR * gain)
    cands = _hough(mag, grads[1], grads[2], thr, max_roll)
    segs = detect_line_segments(a.mean(-1))
    seg_d = np.asarray(segs.endpoints[:, 1] - segs.endpoints[:, 0], dtype=np.float64)
    seg_m = np.asarray(segs.endpoints.mean(axis=1), dtype=np.float64)
    n_long = int((np.hypot(seg_d[:, 0], seg_d[:, 1]) > 0.1 * math.hypot(*mag.shape)).sum())
    return [_evaluate(c, a, grads, thr, seg_d, seg_m) for c in cands], n_long, scale


def detect_horizon(image: ArrayLike, *, max_roll: float = math.radians(30.0)) -> HorizonResult:
    """Find the visible horizon of a photograph of open water or flat land.

    Parameters
    ----------
    image : array_like, shape (H, W) or (H, W, 3)
        The photograph (uint8, uint16 or floats in [0, 1]).
    max_roll : float
        The largest angle of the horizon to the image rows looked for (radians, at most
        80 degrees). The default, 30 degrees, covers hand-held and mounted cameras; an
        aircraft's camera rolls further (60 degrees finds more of its horizons and more
        false ones, ``benchmarks/results/horizon-natural-2026-11-30a.md``).

    Returns
    -------
    HorizonResult
        ``found`` and, when found, the horizon line (``a u + b v + c = 0``, the
        representation of :func:`detect_vanishing_points`' horizon), its roll and its rows
        at the frame's left and right edges; when not, ``found=False`` with the ``reason``.

    Raises
    ------
    InvalidInputError
        If the image is not (H, W) or (H, W, 3), is smaller than 16 x 16 px or holds
        non-finite values, or ``max_roll`` is not in (0, 80] degrees.

    Examples
    --------
    >>> import numpy as np
    >>> v = np.arange(120.0)[:, None] * np.ones((1, 160))
    >>> res = detect_horizon(np.where(v < 50, 0.8, 0.3))  # sky over sea: rows 0-49 sky
    >>> res.found, res.rows.tolist(), round(res.roll, 6)
    (True, [49.5, 49.5], 0.0)
    >>> below = np.clip(v - (50 - 0.1 * np.arange(160.0)) + 0.5, 0, 1)  # right end higher
    >>> res = detect_horizon(0.8 - 0.5 * below)  # antialiased edge v = 50 - 0.1 u
    >>> np.round(res.rows, 2).tolist(), round(float(np.degrees(res.roll)), 2)
    ([50.0, 34.1], 5.71)
    >>> detect_horizon(np.full((120, 160), 0.5)).reason
    'no edges'
    """
    max_roll = as_real(max_roll, "max_roll", positive=True, maximum=math.radians(80.0))
    cands, n_long, scale = _candidates(image, max_roll)
    w = np.asarray(image).shape[1]
    line, best, reasons = _choose(cands, n_long, scale, w)
    if line is None or best is None:
        if not cands:
            why = "no edges"
        else:
            why = "no long straight edge across the frame with sky above it (lines seen: "
            why += "; ".join(sorted(set(reasons))) + ")"
        return HorizonResult(False, None, math.nan, np.full(2, np.nan), 0.0, why)
    rows = np.array([_row(line, 0.0), _row(line, w - 1.0)])
    roll = math.atan2(float(line[0]), float(line[1]))
    return HorizonResult(True, line, roll, rows, best.cover)
