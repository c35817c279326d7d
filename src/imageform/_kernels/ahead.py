"""A command's first run compiles its kernels on two cores: a second process compiles ahead.

numba compiles in one thread per process (a process-wide compiler lock), so a command's first
run on a new machine compiles its kernels one after the other while the other cores idle:
17 s of ``imageform reconstruct``'s 18 s, 5 s of ``imageform simulate``'s 10 s. Kernels are
cached on disk (:mod:`imageform._kernels.jit`), and numba looks in that cache before it
compiles any kernel, also a kernel called from the one it is compiling. So a second process
that compiles some of the command's kernels into the cache while the command compiles the
others, or renders, shares the work: when the command reaches those kernels, it loads them.

:data:`PLANS` says, for each command that gains from it, which kernels the second process
compiles (``child``), and which the command compiles first itself (``here``), each with the
signature the command uses (``benchmarks/compile_plan.py`` records a command's compilations on
an empty cache and proposes the split; figures in ``benchmarks/results/compile-ahead-*.md``).
The command calls :func:`start` once its arguments are checked. Every imageform kernel calls
:func:`ready` before it compiles a signature (``jit.njit`` wraps numba's ``compile``, which
runs at a call from Python and while a kernel that calls it is typed): when the second
process has that kernel in its plan, the command waits until it is compiled and then loads it
from the cache, so that nothing is compiled twice.

:func:`start` does nothing when the cache already holds every kernel of the plan (every run
after the first), when numba is disabled or checks bounds (no cache then), when the cache
cannot be written, on a single core, or when ``IMAGEFORM_COMPILE_AHEAD=0``. The second
process is ``python -m imageform._kernels.ahead ENTRIES`` (the plan's entries the cache lacks,
as JSON): it prints each kernel's name once it has compiled it, exits quietly on Ctrl-C, and
is ended when the command exits. Whatever goes wrong in it (a kernel
that no longer has the planned signature, a crash), the command compiles what it needs itself,
as without it: the results never depend on it.

A ``here`` entry must not call a ``child`` entry: it would wait for the second process.
"""

from __future__ import annotations

import atexit
import contextlib
import importlib
import json
import os
import subprocess
import sys
import threading
from pathlib import Path
from typing import Any, NamedTuple

from imageform._jsonio import dumps

__all__ = ["PLANS", "Entry", "Plan", "enabled", "pending", "ready", "start", "stop"]

#: how long :func:`ready` waits for the second process at most (s); then the command compiles
_WAIT_S = 300.0


class Entry(NamedTuple):
    """One kernel to compile, with its callees (each cached on its own).

    Its module in ``imageform._kernels``, its name, the argument types in numba's signature
    syntax (``"(float64[:, ::1], int64)"``).
    """

    module: str
    kernel: str
    signature: str


class Plan(NamedTuple):
    """The second process's kernels (in order) and those the command compiles first."""

    child: tuple[Entry, ...]
    here: tuple[Entry, ...] = ()


_A2 = "float64[:, ::1]"
_A1 = "float64[::1]"
_A3 = "float64[:, :, ::1]"
_I1 = "int64[::1]"

#: the checkerboard detector's kernels (calibrate, stereo-calibrate, characterize): the
#: candidates' three here, the refinement and the lattice's three in the second process
_BOARD_HERE = (
    Entry(
        "checkerboard",
        "_saddle_maxima",
        "(uint8[:, ::1], float32[:, ::1], boolean, float32[::1], int64, int64, float64, float32)",
    ),
    Entry("checkerboard", "ring_test_numba", f"(float32[:, ::1], {_A2}, {_A2}, float64)"),
    Entry("checkerboard", "neighbors_numba", f"({_A2}, {_A3}, float64, int64, float64)"),
)
_BOARD_CHILD = (
    Entry(
        "checkerboard",
        "_refine_corners",
        f"(float32[:, ::1], {_A2}, boolean, {_A2}, int64, int64, int64, float64)",
    ),
    Entry(
        "checkerboard",
        "lattice_rectangle_numba",
        f"(int64, {_A3}, int64[:, :, ::1], {_A2}, int64, float64)",
    ),
    Entry("checkerboard", "lattice_problem_numba", f"({_A3}, float64)"),
    Entry(
        "checkerboard_symmetric",
        "_refine_symmetric",
        f"(int64, int64, float32[:, ::1], {_A2}, boolean, {_A2}, int64, {_A2}, {_A2}, {_A3}, "
        f"boolean, int64, float64, {_A2}, {_I1}, boolean)",
    ),
    Entry(
        "checkerboard_local",
        "_refine_local",
        f"(int64, int64, float32[:, ::1], {_A2}, boolean, {_A2}, {_A2}, {_A2}, int64, {_A2}, "
        f"float64, int64, float64, {_A2}, {_I1})",
    ),
)

#: calibration's refinement: the normal equations' blocks (calibrate, stereo-calibrate)
_CALIB_BLOCKS = Entry(
    "calibration",
    "calib_blocks",
    f"(int64, {_A1}, {_A2}, {_A2}, {_A2}, {_A2}, {_I1}, boolean, {_A2}, {_A2}, {_A3}, {_A3}, "
    f"{_A1}, {_A2})",
)

#: the ArUco detector's kernels (track with a ChArUco board or one marker; frames as grey
#: uint8 since 2026-12-01): the threshold's components and the codes' reading in the second
#: process, the quads here
_MARKER_CHILD = (
    Entry(
        "aruco", "dark_components_u8", "(uint8[:, ::1], int32[:, ::1], int64, int64, int64, int64)"
    ),
    Entry("aruco", "decode_cells", f"({_A2}, uint8[:, :, ::1], int64, int64, float64, float64)"),
)
_MARKER_HERE = (
    Entry("aruco", "box_integral_u8", "(uint8[:, ::1], int64, int32[:, ::1])"),
    Entry(
        "aruco", "component_quads", f"(int64[:, ::1], {_I1}, {_I1}, {_I1}, int64[:, ::1], float64)"
    ),
    Entry("aruco", "cell_means", f"({_A2}, {_A3}, int64)"),
)
#: PnP's refinement of every frame's pose (track; reconstruct's plan has it too)
_PNP_REFINE = Entry(
    "pnp",
    "_refine_tasks",
    f"(int64, int64, {_A3}, {_A2}, {_A3}, {_A3}, {_A2}, {_A2}, int64, float64, {_A1})",
)

#: The plans, from ``benchmarks/compile_plan.py`` (its figures: benchmarks/results).
PLANS: dict[str, Plan] = {
    "calibrate": Plan(child=(*_BOARD_CHILD, _CALIB_BLOCKS), here=_BOARD_HERE),
    "stereo-calibrate": Plan(child=(*_BOARD_CHILD, _CALIB_BLOCKS), here=_BOARD_HERE),
    "characterize": Plan(
        child=(
            Entry("chart", "flat_gradient_numba", "(float32[:, :, ::1], float32[::1])"),
            Entry("chart", "lmeds_best_numba", f"({_A2}, {_A2}, {_A2}, int64[:, ::1], {_A2})"),
        )
        + _BOARD_CHILD
        + (_CALIB_BLOCKS,),
        here=_BOARD_HERE
        + (
            Entry("chart", "region_moments_numba", "(int32[:, ::1], int64)"),
            Entry("chart", "block_mean_numba", f"({_A3}, int64, float64)"),
        ),
    ),
    # track (16.7 s of CPU compiling cold, 2026-11-30): the marker detector, the corners'
    # refinement and PnP, split in two halves; the plan is the board's kind's
    "track-charuco": Plan(
        child=_MARKER_CHILD + (_BOARD_CHILD[0],),
        here=_MARKER_HERE
        + (
            Entry("aruco", "sample_quadrants", f"({_A2}, {_A3}, {_A2}, {_A3}, {_A2})"),
            _PNP_REFINE,
        ),
    ),
    "track-aruco": Plan(child=(*_MARKER_CHILD, _PNP_REFINE), here=(*_MARKER_HERE, _BOARD_CHILD[0])),
    # the full line-segment detector (lsd_full.lsd, 5.9 s) split at its callees
    "vanishing": Plan(
        child=(
            Entry("lsd_full", "gaussian_sampler", f"({_A2}, float64, float64)"),
            Entry(
                "lsd_full",
                "region_grow",
                f"(int32, int32, {_A2}, int32[::1], int32[::1], uint8[:, ::1], float64)",
            ),
            Entry(
                "lsd_full",
                "_refine",
                f"(int32[::1], int32[::1], int64, {_A2}, float64, float64, float64, {_A1},"
                f" uint8[:, ::1], {_A2}, float64)",
            ),
        ),
        here=(
            Entry("lsd_full", "ll_angle", f"({_A2}, float64, int64)"),
            Entry(
                "lsd_full",
                "_region2rect",
                f"(int32[::1], int32[::1], int64, {_A2}, float64, float64, float64, {_A1})",
            ),
            Entry("lsd_full", "_rect_improve", f"({_A1}, {_A2}, float64, float64)"),
        ),
    ),
    # semi-global matching: the 8-path aggregation fused with the selection (the largest kernel)
    # compiles in the second process while the command reads, rectifies and takes the census
    "depth": Plan(
        child=(
            Entry(
                "sgm",
                "match",
                "(uint8[:, :, ::1], float32[:, ::1], int64, int64, boolean, int64, float64,"
                " float64, uint16[:, :, ::1], boolean, int32[:, :, ::1])",
            ),
            Entry("sgm", "speckles", "(float32[:, ::1], int64, float64)"),
        ),
        here=(
            Entry("sgm", "census", "(float32[:, ::1], int64, float32, float32)"),
            Entry(
                "sgm",
                "window_costs",
                "(uint64[:, ::1], uint64[:, ::1], int64, int64, int64, int64, int64,"
                " uint8[:, :, ::1])",
            ),
        ),
    ),
    # rendering and optics (3 s of NumPy) overlap the undistortion, demosaicing and the full
    # line-segment detector's sampling and gradients in the second process; the detector's
    # core and the small rendering kernels compile here (2026-11-30: the plan of 11-29 named
    # lsd's kernels, which simulate no longer calls: 16.6 s of CPU compiling cold)
    "simulate": Plan(
        child=(
            Entry(
                "remap",
                "_undistort_tasks",
                "(int64, int64, float64[:, :, :, ::1], float64[::1], boolean, float64, float64,"
                " float64[:, :, :, ::1], float64[::1], int32[::1], float64, int64)",
            ),
            Entry(
                "demosaic_menon",
                "_menon_tasks",
                f"(int64, int64, {_A2}, int64, int64, int64, int64, boolean, boolean, int64,"
                f" {_A3})",
            ),
            Entry("lsd_full", "gaussian_sampler", f"({_A2}, float64, float64)"),
            Entry("lsd_full", "ll_angle", f"({_A2}, float64, int64)"),
        ),
        here=(
            Entry(
                "lsd_full",
                "_detect",
                f"({_A2}, {_A2}, int32[::1], int32[::1], float64, float64, float64, float64,"
                " float64, boolean)",
            ),
            Entry(
                "distortion",
                "_bc_undistort",
                f"(int64, int64, {_A2}, {_A1}, int64, float64, {_A2}, boolean[::1])",
            ),
            Entry(
                "raycast",
                "_raycast_kernel",
                f"(int64, int64, {_A2}, {_A2}, {_A2}, {_A2}, {_A2}, int32[::1], {_A1}, {_A1},"
                f" {_A1})",
            ),
            Entry(
                "remap",
                "_remap_grey_tasks",
                f"(int64, int64, {_A2}, {_A1}, int64, int64, int64, int64, float64, float64,"
                f" {_A2}, {_A1}, float64, int64)",
            ),
        ),
    ),
    # the essential matrix's estimator (13.4 s of 17.1) split at its callees: the 5-point
    # solver here, the LM refinement there; the estimator itself then compiles in 3 s, while
    # the second process goes on with what the command needs after it (the pose, PnP)
    "reconstruct": Plan(
        child=(
            Entry("ransac", "_sample", f"(uint64[::1], int64, int64, {_I1})"),
            Entry("ransac", "_select", f"(int64, {_A2}, {_A2}, {_A2}, float64, {_I1})"),
            Entry(
                "ransac",
                "_support_count_n",
                f"(int64, {_A2}, {_A2}, {_A2}, float64, int64, float64, int64)",
            ),
            Entry("ransac", "_project_e", f"({_A2})"),
            Entry(
                "ransac_e",
                "_score_sprt",
                f"({_A2}, {_A2}, {_A2}, float64, float64, float64, int64, float64, float64,"
                " float64)",
            ),
            Entry(
                "ransac_e",
                "_lm_e",
                f"({_A2}, {_A2}, {_A2}, {_A2}, {_A2}, {_I1}, {_A1}, int64, int64)",
            ),
            Entry(
                "relative_pose",
                "pose_from_essential",
                f"({_A2}, {_A2}, {_A2}, boolean[::1], float64, {_A2}, {_A1}, {_A2}, boolean[::1])",
            ),
            Entry(
                "pnp",
                "_refine_tasks",
                f"(int64, int64, {_A3}, {_A2}, {_A3}, {_A3}, {_A2}, {_A2}, int64, float64, {_A1})",
            ),
            # bundle adjustment's sums (1.2 s of CPU cold), reached after the pairs are verified
            Entry(
                "bundle",
                "normal_equations",
                f"({_A2}, {_A3}, {_A2}, {_A2}, {_I1}, {_I1}, {_I1}, {_I1}, {_A2}, {_A1}, {_A3},"
                f" {_A3}, {_A3}, {_A2}, {_A2}, {_A3})",
            ),
            Entry("bundle", "reduce_cameras", f"({_A3}, {_A3}, {_I1}, {_I1}, {_I1}, int64, {_A2})"),
        ),
        here=(
            Entry("ransac_e", "_e5", f"({_A2}, {_A2}, {_I1}, {_A3})"),
            Entry("ransac", "_to_f", f"({_A2}, {_A2}, {_A2}, {_A2})"),
            Entry("ransac", "_support", f"({_A2}, {_A2}, {_A2}, float64, float64, {_I1})"),
            Entry(
                "ransac",
                "_cheirality",
                f"({_A2}, {_A2}, {_A2}, {_I1}, int64, float64, {_A2}, {_A3})",
            ),
        ),
    ),
}


def _signature(text: str) -> tuple[Any, ...]:
    from numba.core import sigutils

    args, _ = sigutils.normalize_signature("none" + text)  # "(x)" alone is not a tuple
    return tuple(args)


def compile_entry(entry: Entry) -> None:
    """Compile ``entry``'s kernel (and its callees) for its signature, into the cache.

    A kernel of ``jit.njit(signature, lazy=True)`` compiles as at its first call: numba's
    cache key holds the signature as it was given (its text), not only the types.
    """
    module = importlib.import_module(f"imageform._kernels.{entry.module}")
    kernel = getattr(module, entry.kernel)
    if hasattr(kernel, "dispatcher"):  # jit.Deferred
        kernel.compile()
    else:
        kernel.compile(_signature(entry.signature))


def enabled() -> bool:
    """Whether a second process may compile ahead here (see the module's documentation)."""
    if os.environ.get("IMAGEFORM_COMPILE_AHEAD", "") in ("0", "false", "no", "off"):
        return False
    try:
        cores = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):  # not Linux
        cores = os.cpu_count() or 1
    if cores < 2:
        return False
    from imageform._backend import numba_enabled

    if not numba_enabled():
        return False
    import numba

    config = numba.config
    return not (getattr(config, "BOUNDSCHECK", None) or getattr(config, "DISABLE_JIT", 0))


def _cached(entry: Entry, folder: Path) -> bool:
    return any(folder.glob(f"{entry.module}.{entry.kernel}-*.nbi"))


def pending(command: str) -> tuple[Entry, ...]:
    """Return the entries of ``command``'s plan that the cache does not hold yet.

    Empty when imageform's cache folder cannot be written: nothing is compiled ahead then.
    """
    plan = PLANS.get(command)
    if plan is None:
        return ()
    from imageform._kernels.jit import cache_location

    folder, why = cache_location()
    if why == "in-tree":
        return ()
    return tuple(e for e in plan.child + plan.here if not _cached(e, folder))


class _Child:
    """The second process, and a thread that reads which kernels it has compiled."""

    def __init__(self, entries: tuple[Entry, ...]) -> None:
        self.waiting = {f"{e.module}.{e.kernel}" for e in entries}
        self.done: set[str] = set()
        self.ended = threading.Event()
        self.changed = threading.Condition()
        env = {**os.environ, "IMAGEFORM_COMPILE_AHEAD": "0"}  # its own commands: none
        self.proc = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "imageform._kernels.ahead",
                dumps([list(e) for e in entries], indent=None),
            ],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            env=env,
            text=True,
        )
        self.reader = threading.Thread(target=self._read, name="imageform-ahead", daemon=True)
        self.reader.start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        with contextlib.suppress(OSError, ValueError):  # the pipe closed under it
            for line in self.proc.stdout:
                with self.changed:
                    self.done.add(line.strip())
                    self.changed.notify_all()
        with self.changed:
            self.ended.set()
            self.changed.notify_all()

    def wait(self, name: str | None) -> None:
        wanted = self.waiting if name is None else {name}
        with self.changed:
            self.changed.wait_for(
                lambda: wanted <= self.done or self.ended.is_set(), timeout=_WAIT_S
            )

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=5)
            except subprocess.TimeoutExpired:  # pragma: no cover - a stuck child
                self.proc.kill()
                self.proc.wait()
        self.reader.join(timeout=5)  # it reads to the end of the pipe, then ends
        if self.proc.stdout is not None and not self.reader.is_alive():
            self.proc.stdout.close()


_CHILD: _Child | None = None
_LOCK = threading.Lock()


def start(command: str) -> bool:
    """Start compiling ``command``'s planned kernels ahead; return whether a process started.

    Then compiles the plan's ``here`` entries in this process. Nothing happens when the cache
    holds them all already, or when :func:`enabled` says no.
    """
    global _CHILD
    if command not in PLANS or not enabled():
        return False
    todo = pending(command)
    if not todo:
        return False
    plan = PLANS[command]
    child = tuple(e for e in plan.child if e in todo)
    started = False
    with _LOCK:
        if _CHILD is None and child:
            try:
                _CHILD = _Child(child)
            except OSError:  # no interpreter to start (a frozen application): compile here
                _CHILD = None
            else:
                atexit.register(stop)
                from imageform._kernels import jit

                jit._WAIT = ready
                started = True
    for entry in plan.here:
        if entry in todo:
            # a stale plan: the command compiles the kernel on use
            with contextlib.suppress(Exception):
                compile_entry(entry)
    return started


def ready(name: str | None = None) -> None:
    """Wait until the second process has compiled kernel ``name`` (``"module.kernel"``).

    Returns at once when no second process runs or it does not compile that kernel; ``None``
    waits for all its kernels. Every imageform kernel calls it before it compiles (``jit``).
    """
    child = _CHILD
    if child is None or (name is not None and name not in child.waiting):
        return
    child.wait(name)


def stop() -> None:
    """End the second process, if one runs (at exit; on Ctrl-C, by the command line)."""
    global _CHILD
    with _LOCK:
        child, _CHILD = _CHILD, None
    if child is not None:
        from imageform._kernels import jit

        jit._WAIT = None
        child.stop()


def _main(argv: list[str]) -> int:
    """Run the second process: compile the entries (JSON); print each one's name when done."""
    try:
        entries = [Entry(*map(str, e)) for e in json.loads(argv[0])] if len(argv) == 1 else None
    except (ValueError, TypeError):
        entries = None
    if entries is None:
        print(
            'usage: python -m imageform._kernels.ahead \'[["module", "kernel", "(types)"], ...]\'',
            file=sys.stderr,
        )
        return 2
    try:
        for entry in entries:
            with contextlib.suppress(Exception):  # the command compiles it itself
                compile_entry(entry)
            print(f"{entry.module}.{entry.kernel}", flush=True)
    except KeyboardInterrupt:  # Ctrl-C reaches the whole process group: leave quietly
        return 130
    except BrokenPipeError:  # the command has ended
        return 0
    return 0


if __name__ == "__main__":
    sys.exit(_main(sys.argv[1:]))
