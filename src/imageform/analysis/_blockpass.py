"""Statistics of a Dask (..., 3) array in few passes, each block computed once per pass.

A stain fit on Dask needs sums (a covariance), then exact percentiles of values derived
from each pixel (angles, concentrations). Written as Dask expressions, every reduction and
every pass of an exact quantile is a ``dask.compute`` of the whole graph, and each one
recomputes the optical densities and the tissue mask (a ``map_overlap`` of the artefact
rules) from the image. Here a *pass* is one task per block that runs a NumPy function on
the block's pixels and returns several small results at once (sums, minima, maxima,
histograms, the values of one histogram bin), merged in a tree of ``split_every`` blocks.
The first pass can keep the mask of each block, packed 8 pixels a byte, so the mask is
computed once per fit (:data:`KEEP_MASK_PIXELS` bounds what is kept).

:func:`block_quantiles` gives NumPy's ``percentile`` (linear interpolation) exactly: a
histogram of each value family over a bound of its range finds the bin holding each order
statistic; the bin is histogrammed again when it holds more than :data:`GATHER_MAX`
values (bounded memory), and its values are gathered and sorted.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from imageform.errors import InvalidInputError

__all__ = ["BlockPasses", "Family", "block_quantiles"]

#: Masks kept by the first pass when the image has at most this many pixels (2**31 pixels:
#: 256 MiB packed); larger images recompute their mask in each pass.
KEEP_MASK_PIXELS = 1 << 31
#: Histogram bins per pass of an exact quantile.
BINS = 1 << 14
#: A bin holding more values than this is histogrammed again rather than gathered.
GATHER_MAX = 1 << 20
#: Blocks merged per task of the tree reduction.
SPLIT_EVERY = 8

#: Results of a pass: a dict whose keys start with how blocks combine: "sum:", "min:",
#: "max:" (arrays), "cat:" (arrays concatenated along axis 0).
Result = dict[str, Any]


def _merge(parts: list[Result]) -> Result:
    out: Result = {}
    for key in parts[0]:
        vals = [p[key] for p in parts]
        kind = key.split(":", 1)[0]
        if kind == "sum":
            out[key] = np.sum(vals, axis=0)
        elif kind == "min":
            out[key] = np.min(vals, axis=0)
        elif kind == "max":
            out[key] = np.max(vals, axis=0)
        else:
            out[key] = np.concatenate(vals, axis=0)
    return out


def _flat_index(shape: tuple[int, ...], starts: tuple[int, ...], sizes: tuple[int, ...]) -> Any:
    """Flat (row-major) positions in ``shape`` of a block at ``starts`` of ``sizes``."""
    idx = np.zeros(sizes, dtype=np.int64)
    stride = 1
    for ax in range(len(shape) - 1, -1, -1):
        view = [1] * len(shape)
        view[ax] = sizes[ax]
        idx += ((starts[ax] + np.arange(sizes[ax], dtype=np.int64)) * stride).reshape(view)
        stride *= shape[ax]
    return idx.reshape(-1)


def _run_block(
    fn: Callable[..., Result],
    od: np.ndarray,
    use: Any,
    packed: Any,
    where: tuple[tuple[int, ...], tuple[int, ...], tuple[int, ...]] | None,
    keep: bool,
) -> Result:
    flat = np.asarray(od).reshape((-1, 3)).astype(np.float64)
    if packed is not None:
        u = np.unpackbits(packed, count=flat.shape[0]).astype(bool)
    elif use is not None:
        u = np.asarray(use).reshape(-1)
    else:
        u = None
    index = None if where is None else _flat_index(*where)
    out = fn(flat, u, index)
    if keep and u is not None:
        out["mask"] = np.packbits(u)
    return out


@dataclass
class BlockPasses:
    """Passes over the blocks of ``od`` (Dask, shape (..., 3)) and a boolean mask ``use``.

    ``use``: Dask booleans of shape ``od.shape[:-1]`` (rechunked to ``od``'s blocks) or None.
    """

    od: Any
    use: Any = None
    passes: int = 0
    _packed: list[Any] | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        od = self.od
        if od.numblocks[-1] != 1:
            od = od.rechunk({od.ndim - 1: 3})
        self.od = od
        if self.use is not None:
            self.use = self.use.rechunk(od.chunks[:-1])
        self._od_blocks = list(od.to_delayed().reshape(-1))
        self._use_blocks = None if self.use is None else list(self.use.to_delayed().reshape(-1))
        grid = np.indices(od.numblocks[:-1]).reshape(od.ndim - 1, -1).T
        starts = [np.concatenate([[0], np.cumsum(c)[:-1]]) for c in od.chunks[:-1]]
        self._where = [
            (
                tuple(int(v) for v in od.shape[:-1]),
                tuple(int(starts[a][g[a]]) for a in range(od.ndim - 1)),
                tuple(int(od.chunks[a][g[a]]) for a in range(od.ndim - 1)),
            )
            for g in grid
        ]

    @property
    def rows(self) -> int:
        """The pixels (rows of 3 values) in all."""
        return int(np.prod(self.od.shape[:-1]))

    def run(
        self, fn: Callable[..., Result], *, index: bool = False, keep_mask: bool = False
    ) -> Result:
        """Run one pass of ``fn(flat, use, index)`` on every block and merge the results.

        ``flat``: the block's OD rows as float64; ``use``: its mask or None; ``index``: its
        flat positions when ``index`` is True, else None. ``keep_mask``: keep each block's
        mask (packed) for the next passes, when the image has at most
        :data:`KEEP_MASK_PIXELS` pixels.
        """
        import dask
        from dask import delayed

        keep = keep_mask and self.use is not None and self._packed is None
        keep = keep and int(np.prod(self.od.shape[:-1])) <= KEEP_MASK_PIXELS
        parts = []
        for i, blk in enumerate(self._od_blocks):
            use = None if self._use_blocks is None or self._packed else self._use_blocks[i]
            packed = self._packed[i] if self._packed else None
            where = self._where[i] if index else None
            parts.append(delayed(_run_block)(fn, blk, use, packed, where, keep))
        masks = [delayed(_pop_mask)(p) for p in parts] if keep else []
        level = [delayed(_without_mask)(p) for p in parts] if keep else parts
        while len(level) > 1:
            level = [
                delayed(_merge)(level[k : k + SPLIT_EVERY])
                for k in range(0, len(level), SPLIT_EVERY)
            ]
        out, *kept = dask.compute(level[0], *masks)
        self.passes += 1
        if keep:
            self._packed = list(kept)
        return dict(out)


def _pop_mask(r: Result) -> Any:
    return r["mask"]


def _without_mask(r: Result) -> Result:
    return {k: v for k, v in r.items() if k != "mask"}


@dataclass
class Family:
    """Values derived per pixel and the percentiles wanted of them.

    ``values(flat, use) -> 1-D array`` (the pixels selected), ``n`` of them in all, within
    ``[lo, hi]``; their percentiles ``qs`` (in %).
    """

    name: str
    values: Callable[[np.ndarray, Any], np.ndarray]
    n: int
    lo: float
    hi: float
    qs: tuple[float, ...]


def _bin(v: np.ndarray, lo: float, scale: float) -> np.ndarray:
    """Return the bins of ``v``: one expression (monotone in ``v``) for histograms and gathers."""
    return np.clip(np.floor((v - lo) * scale), 0, BINS - 1).astype(np.int64)


def _select(v: np.ndarray, path: tuple[tuple[float, float, int], ...]) -> np.ndarray:
    for lo, scale, b in path:
        v = v[_bin(v, lo, scale) == b]
    return v


@dataclass
class _Rank:
    fam: int
    rank: int  # among the values left in the bin of ``path``
    path: tuple[tuple[float, float, int], ...] = ()
    lo: float = 0.0
    hi: float = 0.0
    gather: bool = False
    value: float | None = None


def _pass_fn(families: list[Family], requests: list[tuple[str, int, Any, float, float]]) -> Any:
    def fn(flat: np.ndarray, use: Any, index: Any) -> Result:
        vals = [f.values(flat, use) for f in families]
        out: Result = {}
        for j, (kind, fam, path, lo, scale) in enumerate(requests):
            v = _select(vals[fam], path)
            if kind == "hist":
                out[f"sum:{j}"] = np.bincount(_bin(v, lo, scale), minlength=BINS)
                if path:  # a bin histogrammed again: its values may all be one
                    out[f"min:{j}"] = v.min() if v.size else np.inf
                    out[f"max:{j}"] = v.max() if v.size else -np.inf
            else:
                out[f"cat:{j}"] = v
        return out

    return fn


def block_quantiles(passes: BlockPasses, families: list[Family]) -> list[list[float]]:
    """Each family's percentiles ``qs``, exactly NumPy's (linear interpolation).

    Families histogrammed or gathered in the same pass share it (one task per block).
    """
    ranks: list[_Rank] = []
    plans: list[list[tuple[int, int, float]]] = []  # per family, per q: two ranks, fraction
    for fi, f in enumerate(families):
        if f.n <= 0:
            raise InvalidInputError("cannot take a percentile of no values")
        plan = []
        for q in f.qs:
            pos = q / 100.0 * (f.n - 1)
            k = int(np.floor(pos))
            pair = []
            for rk in (k, min(k + 1, f.n - 1)):
                st = _Rank(fi, rk, (), f.lo, f.hi)
                if not f.hi > f.lo:
                    st.value = f.lo
                pair.append(len(ranks))
                ranks.append(st)
            plan.append((pair[0], pair[1], pos - k))
        plans.append(plan)
    for _ in range(64):
        todo = [r for r in ranks if r.value is None]
        if not todo:
            break
        keys: dict[tuple[Any, ...], int] = {}
        requests: list[tuple[str, int, Any, float, float]] = []
        for r in todo:
            kind = "gather" if r.gather else "hist"
            scale = BINS / (r.hi - r.lo) if kind == "hist" else 0.0
            key = (kind, r.fam, r.path)
            if key not in keys:
                keys[key] = len(requests)
                requests.append((kind, r.fam, r.path, r.lo, scale))
        got = passes.run(_pass_fn(families, requests))
        for r in todo:
            kind = "gather" if r.gather else "hist"
            j = keys[(kind, r.fam, r.path)]
            if kind == "gather":
                vals = np.sort(got[f"cat:{j}"])
                r.value = float(vals[r.rank])
                continue
            lo, scale = requests[j][3], requests[j][4]
            if r.path and got[f"min:{j}"] == got[f"max:{j}"]:  # one value: no finer bins
                r.value = float(got[f"min:{j}"])
                continue
            cum = np.cumsum(got[f"sum:{j}"])
            b = int(np.searchsorted(cum, int(r.rank), side="right"))
            below = int(cum[b - 1]) if b > 0 else 0
            count = int(cum[b]) - below
            r.rank -= below
            r.path = (*r.path, (lo, scale, b))
            # the bin's values: gathered, or histogrammed again over the bin's width
            new_lo, new_hi = lo + b / scale, lo + (b + 1) / scale
            finer = new_hi > new_lo and np.isfinite(BINS / (new_hi - new_lo))
            if count <= GATHER_MAX or not finer or len(r.path) >= 4:
                r.gather = True
            else:
                r.lo, r.hi = new_lo, new_hi
    out = []
    for plan in plans:
        row = []
        for i0, i1, frac in plan:
            va, vb = ranks[i0].value, ranks[i1].value
            assert va is not None and vb is not None
            row.append(float(va) + frac * (float(vb) - float(va)))
        out.append(row)
    return out
