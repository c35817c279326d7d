"""Dask graph audit: tasks, graph build and compute time of every public function on Dask.

Every case of the backend matrix (``tests/backends/test_backends_matrix.py``) that runs on
Dask, plus demosaicing, the white-balance methods and the stain/tissue recipes, is called on a
realistic input: images 1024 x 1024 x 3 float64 in 256 x 256 chunks (16 chunks), point
sets and hue vectors of 2^20 rows in 4 chunks, small matrices as they are. For each the
script counts the tasks of the graph (the returned Dask arrays' graphs plus the graphs
computed inside the call, e.g. a white balance's reductions), times the call (graph build),
the ``compute`` of the result (threaded scheduler) and the same call on NumPy (eager); medians
of ``--repeat`` runs. A case is flagged (``!``) when it holds more than ``--per-layer`` tasks
per input chunk per graph layer, or when its compute takes over 3 x the eager time (and over
0.1 s: dask's fixed cost on a tiny call is not flagged).

Run: ``OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_dask_graphs.py``.
``--json FILE`` writes the figures; ``--before FILE`` (such a file from a run of the code before
a change, e.g. ``--src /tmp/base/src``) adds its task counts and compute times as "before"
columns. ``--only NAME ...`` runs the named cases.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
IMG_SIDE = 1024
IMG_CHUNK = 256
N_POINTS = 1 << 20
PT_CHUNK = 1 << 18


def _setup_path(src: str | None) -> None:
    sys.path.insert(0, str(ROOT))
    sys.path.insert(0, src or str(ROOT / "src"))


def _scale(a: Any) -> tuple[Any, Any]:
    """An argument grown to a realistic size, and its Dask chunks (None: one chunk)."""
    if not isinstance(a, np.ndarray) or a.dtype.kind not in "fiu":
        return a, None
    if a.ndim == 3 and a.shape[0] >= 4:  # an image (H, W, C)
        reps = (-(-IMG_SIDE // a.shape[0]), -(-IMG_SIDE // a.shape[1]), 1)
        big = np.tile(a, reps)[:IMG_SIDE, :IMG_SIDE]
        return np.ascontiguousarray(big), (IMG_CHUNK, IMG_CHUNK, a.shape[2])
    if a.ndim == 2 and a.shape[0] >= 5:  # points (N, k)
        big = np.tile(a, (-(-N_POINTS // a.shape[0]), 1))[:N_POINTS]
        return np.ascontiguousarray(big), (PT_CHUNK, a.shape[1])
    if a.ndim == 1 and a.shape[0] >= 5:  # a vector of values (hues)
        return np.tile(a, -(-N_POINTS // a.shape[0]))[:N_POINTS], (PT_CHUNK,)
    return a, None


class Case:
    """``fn(*args)``; ``lazy`` arguments become Dask arrays with their chunks."""

    def __init__(self, name: str, fn: Callable[..., Any], args: tuple[Any, ...]) -> None:
        self.name = name
        self.fn = fn
        scaled = [_scale(a) for a in args]
        self.eager_args = tuple(a for a, _ in scaled)
        self.chunks = tuple(ch for _, ch in scaled)

    def dask_args(self) -> tuple[Any, ...]:
        import dask.array as da

        return tuple(
            a if not isinstance(a, np.ndarray) else da.from_array(a, chunks=ch or a.shape)
            for a, ch in zip(self.eager_args, self.chunks, strict=True)
        )

    def n_chunks(self) -> int:
        import math

        n = 1
        for a, ch in zip(self.eager_args, self.chunks, strict=True):
            if ch is not None:
                n = max(n, math.prod(-(-s // c) for s, c in zip(a.shape, ch, strict=True)))
        return n


def _matrix_cases() -> list[Case]:
    from tests.backends.test_backends_matrix import CASES

    out = []
    skip = {
        "palette_check",  # a report over all colour pairs: 6 colours, not an image
        "remap_bilinear",  # sized below (its map must match the image)
        "undistort_image",
        "undistort_image[kannala_brandt]",
        "undistortion_map",
        "chroma_upsample",
    }
    for cs in CASES:
        if "dask" in cs.skip or cs.name in skip:
            continue
        pick = cs.pick
        fn = cs.fn if pick is None else (lambda *a, f=cs.fn, p=pick: p(f(*a)))
        out.append(Case(cs.name, fn, cs.args))
    return out


def _extra_cases() -> list[Case]:
    from imageform import color as c
    from imageform import geometry as g
    from imageform.sensor import demosaic

    rng = np.random.default_rng(7)
    img = rng.uniform(0.05, 0.95, (8, 8, 3))
    ycc = c.srgb_to_ycbcr(img)
    n = IMG_SIDE
    k = np.array([[800.0, 0.0, n / 2 - 0.5], [0.0, 800.0, n / 2 - 0.5], [0.0, 0.0, 1.0]])
    bc = g.BrownConrady(k1=-0.2, k2=0.05, p1=1e-3, p2=-2e-3, k3=0.01)
    kb = g.KannalaBrandt(k1=0.05, k2=-0.01)
    cases = [
        Case("chroma_subsample[4:2:0]", lambda x: c.chroma_subsample(x)[1], (ycc,)),
        Case("chroma_subsample[4:2:2]", lambda x: c.chroma_subsample(x, "4:2:2")[1], (ycc,)),
        Case(
            "chroma_subsample[center]",
            lambda x: c.chroma_subsample(x, siting="center")[1],
            (ycc,),
        ),
        Case(
            "chroma_upsample",
            lambda x: c.chroma_upsample(x[..., 0], c.chroma_subsample(x)[1]),
            (ycc,),
        ),
        Case(
            "chroma_upsample[nearest]",
            lambda x: c.chroma_upsample(x[..., 0], c.chroma_subsample(x)[1], method="nearest"),
            (ycc,),
        ),
        Case(
            "subsample_round_trip[center]",
            lambda x: c.subsample_round_trip(x, siting="center"),
            (img,),
        ),
        Case(
            "remap_bilinear",
            lambda x: g.remap_bilinear(x, g.undistortion_map((n, n), k, bc)),
            (img,),
        ),
        Case("undistort_image", lambda x: g.undistort_image(x, k, bc), (img,)),
        Case("undistort_image[kannala_brandt]", lambda x: g.undistort_image(x, k, kb), (img,)),
    ]
    for method, kw in [
        ("gray_world", {}),
        ("white_patch", {}),
        ("white_patch[97]", {"percentile": 97.0}),
        ("max_rgb", {}),
        ("gray_edge", {}),
        ("gray_edge[sigma=2]", {"sigma": 2.0}),
        ("grayness_index", {}),
        ("pca", {}),
    ]:
        m = method.split("[")[0]
        cases.append(
            Case(
                f"white_balance[{method}]",
                lambda x, m=m, kw=kw: c.white_balance(x, m, **kw),
                (img,),
            )
        )
    raw = rng.uniform(0.0, 1.0, (8, 8, 1))
    for method in ("bilinear", "malvar", "hamilton_adams", "menon"):
        cases.append(
            Case(
                f"demosaic[{method}]",
                lambda x, m=method: demosaic(x[..., 0], "RGGB", m),
                (raw,),
            )
        )
    return cases


def _analysis_cases() -> list[Case]:
    from imageform import analysis as an

    slide, _, _ = an.synthetic_stain_image((64, 64), rng=0)
    slide = slide.astype(np.float64)
    endo, _ = an.synthetic_endoscopy_image((64, 64), rng=0)
    ref = an.macenko_stains(slide)
    return [
        Case("optical_density", an.optical_density, (slide,)),
        Case("macenko_stains", lambda x: an.macenko_stains(x).stain_matrix, (slide,)),
        Case("macenko_normalize", lambda x: an.macenko_normalize(x, ref), (slide,)),
        Case(
            "stain_concentrations",
            lambda x: an.stain_concentrations(x, ref.stain_matrix),
            (slide,),
        ),
        Case("reinhard_stats", lambda x: np.asarray(an.reinhard_stats(x).mean), (slide,)),
        Case(
            "reinhard_normalize",
            lambda x: an.reinhard_normalize(x, an.reinhard_stats(slide)),
            (slide,),
        ),
        Case("tissue_mask", lambda x: an.tissue_mask(x), (slide,)),
        Case(
            "segment_hsv", lambda x: an.segment_hsv(x, (340, 40), (0.1, 1), (0.3, 1)).mask, (endo,)
        ),
    ]


def _tasks_and_result(case: Case, computed: list[int]) -> tuple[Any, int, int]:
    """Call on Dask: the result, its tasks (lazy graph + graphs computed) and graph layers."""
    import dask
    from dask.callbacks import Callback

    class _Count(Callback):  # type: ignore[misc]
        def _start(self, dsk: Any) -> None:
            computed.append(len(dsk))

    with _Count():
        out = case.fn(*case.dask_args())
    lazy = [o for o in _flatten(out) if dask.is_dask_collection(o)]
    tasks = sum(computed)
    layers = 0
    if lazy:
        graph: dict[Any, Any] = {}
        for o in lazy:
            graph.update(dict(o.__dask_graph__()))
        tasks += len(graph)
        hlg = lazy[0].__dask_graph__()
        layers = len(getattr(hlg, "layers", {1: 1}))
    return out, tasks, layers


def _flatten(out: Any) -> list[Any]:
    if isinstance(out, (tuple, list)):
        return [y for o in out for y in _flatten(o)]
    return [out]


def _compute(out: Any) -> Any:
    import dask

    items = _flatten(out)
    lazy = [o for o in items if dask.is_dask_collection(o)]
    done = iter(dask.compute(*lazy)) if lazy else iter(())
    return [next(done) if dask.is_dask_collection(o) else o for o in items]


def _median(fn: Callable[[], Any], repeat: int) -> tuple[float, Any]:
    times, res = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        res = fn()
        times.append(time.perf_counter() - t0)
        if times[-1] > 5.0:
            break
    return statistics.median(times), res


def measure(case: Case, repeat: int) -> dict[str, Any]:
    eager_s, ref = _median(lambda: case.fn(*case.eager_args), repeat)
    computed: list[int] = []
    out, tasks, layers = _tasks_and_result(case, computed)
    build_s, out = _median(lambda: case.fn(*case.dask_args()), repeat)
    compute_s, got = _median(lambda: _compute(out), repeat)
    err = 0.0
    for g_, r in zip(got, _flatten(ref), strict=True):
        g_, r = np.asarray(g_, dtype=float), np.asarray(r, dtype=float)
        if g_.shape != r.shape:
            raise AssertionError(f"{case.name}: shape {g_.shape} != {r.shape}")
        d = np.abs(g_ - r)
        scale = np.maximum(np.abs(r), 1.0)
        both_nan = np.isnan(g_) & np.isnan(r)
        err = max(err, float(np.nanmax(np.where(both_nan, 0.0, d / scale), initial=0.0)))
    return {
        "name": case.name,
        "chunks": case.n_chunks(),
        "tasks": tasks,
        "layers": layers,
        "build_s": build_s,
        "compute_s": compute_s,
        "eager_s": eager_s,
        "max_rel_err": err,
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--per-layer", type=float, default=4.0)
    ap.add_argument("--json", help="write the figures here")
    ap.add_argument("--before", help="figures of a run before a change (--json of that run)")
    ap.add_argument("--src", help="the src folder to import imageform from")
    ap.add_argument("--only", nargs="*", help="the cases to run (names)")
    args = ap.parse_args(argv)
    _setup_path(args.src)
    import dask

    from benchmarks._common import header, markdown_table

    dask.config.set(scheduler="threads")
    cases = _matrix_cases() + _extra_cases() + _analysis_cases()
    if args.only:
        cases = [cs for cs in cases if cs.name in args.only]
    before = {}
    if args.before:
        before = {r["name"]: r for r in json.loads(Path(args.before).read_text())}
    rows, results = [], []
    for cs in cases:
        try:
            r = measure(cs, args.repeat)
        except Exception as e:  # a failing case is reported, not fatal
            print(f"{cs.name}: {type(e).__name__}: {e}", file=sys.stderr)
            continue
        results.append(r)
        ratio = r["compute_s"] / max(r["eager_s"], 1e-6)
        per = r["tasks"] / (r["chunks"] * max(r["layers"], 1))
        slow = ratio > 3.0 and r["compute_s"] > 0.1  # not dask's fixed cost on a tiny call
        flag = "!" if per > args.per_layer or slow else ""
        b = before.get(cs.name)
        rows.append(
            [
                f"{flag}{cs.name}",
                r["chunks"],
                b["tasks"] if b else "",
                r["tasks"],
                r["layers"],
                f"{per:.1f}",
                f"{b['build_s']:.3f}" if b else "",
                f"{r['build_s']:.3f}",
                f"{b['compute_s']:.3f}" if b else "",
                f"{r['compute_s']:.3f}",
                f"{r['eager_s']:.3f}",
                f"{ratio:.2f}",
                f"{r['max_rel_err']:.0e}",
            ]
        )
        print(f"{cs.name}: {r}", file=sys.stderr, flush=True)
    print(header("Dask graphs of the public array functions"))
    print(
        f"dask {dask.__version__}; images {IMG_SIDE} x {IMG_SIDE} x 3 float64 in "
        f"{IMG_CHUNK} x {IMG_CHUNK} chunks, points/hues {N_POINTS} rows in {PT_CHUNK}-row "
        f"chunks; medians of {args.repeat} runs; threaded scheduler.\n"
    )
    cols = [
        "function",
        "chunks",
        "tasks before",
        "tasks",
        "layers",
        "tasks/chunk/layer",
        "build s before",
        "build s",
        "compute s before",
        "compute s",
        "eager s",
        "compute/eager",
        "max rel diff vs eager",
    ]
    print(markdown_table(cols, rows))
    print(
        f"`!`: over {args.per_layer:g} tasks per chunk per layer, or compute over 3 x eager "
        "(and over 0.1 s). "
        "Tasks: the returned arrays' graphs (unoptimised) plus the graphs computed inside the "
        "call."
    )
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    raise SystemExit(main())
