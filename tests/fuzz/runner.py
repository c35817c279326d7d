"""The fuzz runner: public callables, malformed values, worker processes, outcomes.

Every callable of every public ``__all__`` (and the public methods of the classes there) has
one entry in :data:`tests.fuzz.table.VALID`: a valid call, or a :class:`Skip` with a reason.
From a valid call, each parameter it passes and each optional parameter it leaves to its
default (None, a number, a string, a tuple, any default) is replaced in turn by a malformed
value of each :data:`KINDS` that fits the valid value's type (for a ``None`` default, whose
type is unknown: every kind but ``none``), and the call is made in a worker process with a
time and a memory limit.

A call passes when it

- returns a result whose floating values are finite (when the valid call's were), or
- raises :class:`imageform.errors.ImageformError` or :class:`TypeError` with a one-line
  message of at most :data:`MAX_MESSAGE` characters that names the parameter.

Anything else is a *finding*: ``(callable, parameter, kind)`` with an outcome such as
``raw:IndexError``, ``nonfinite``, ``unnamed``, ``multiline``, ``long``, ``timeout``,
``crash`` or ``np_scalar_refused`` (a NumPy scalar of the valid value's type refused).
"""

from __future__ import annotations

import contextlib
import dataclasses
import importlib
import inspect
import math
import multiprocessing as mp
import os
import pkgutil
import random
import resource
import shutil
import tempfile
import time
import traceback
import warnings
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from tests.fuzz.values import resolve

MAX_MESSAGE = 200
#: The kinds of malformed values, each derived from a valid value of a compatible type.
KINDS = (
    "empty",
    "wrong_shape",
    "nan",
    "inf",
    "none",
    "complex",
    "object",
    "string",
    "bool",
    "huge",
    "negative",
    "zero",
    "np_scalar",
    "torch0d",
)
#: The memory one worker may add to what it holds after start (bytes, RLIMIT_AS).
WORKER_MEMORY = 3 * 2**30
#: Seconds a new worker may take to import imageform (not counted in a call's timeout).
STARTUP_TIMEOUT = 300.0
#: imageform's own allocation limit in the workers (IMAGEFORM_MAX_MEMORY).
IMAGEFORM_MEMORY = "512M"


# --------------------------------------------------------------------------- the table types


@dataclass(frozen=True)
class C:
    """A valid call ``f(*args, **kwargs)``; for a method, ``self_`` builds the instance
    (a :class:`V` or another :class:`C` of the class)."""

    args: tuple[Any, ...] = ()
    kwargs: dict[str, Any] = field(default_factory=dict)
    self_: Any = None
    #: parameters not to mutate (paths, callbacks ...), with a reason in the table
    fixed: tuple[str, ...] = ()


def call(*args: Any, **kwargs: Any) -> C:
    """``call(V("rgb"), "srgb", dst="lab")``: a valid call with these arguments."""
    return C(tuple(args), dict(kwargs))


def method(self_: Any, *args: Any, **kwargs: Any) -> C:
    """A valid call of a method on the instance ``self_``."""
    return C(tuple(args), dict(kwargs), self_=self_)


@dataclass(frozen=True)
class Skip:
    """No valid call in the table: why (a command-line entry point, a private helper
    re-exported for tests, an abstract base ...)."""

    reason: str


# --------------------------------------------------------------------------- public callables


def _public_modules() -> list[Any]:
    import imageform

    names = ["imageform"]
    for info in pkgutil.walk_packages(imageform.__path__, "imageform."):
        if not any(part.startswith("_") for part in info.name.split(".")):
            names.append(info.name)
    mods = [importlib.import_module(n) for n in sorted(names)]
    return [m for m in mods if hasattr(m, "__all__")]


def _is_target(obj: Any) -> bool:
    if inspect.ismodule(obj) or not callable(obj):
        return False
    if inspect.isclass(obj) and issubclass(obj, BaseException | Warning):
        return False
    return not (isinstance(obj, type) and obj.__module__ == "typing")


def _methods(cls: type) -> Iterator[tuple[str, Any]]:
    """Public methods (and class/static methods) defined by imageform on ``cls``."""
    for klass in cls.__mro__:
        if not klass.__module__.startswith("imageform"):
            continue
        for name, raw in vars(klass).items():
            if name.startswith("_") or isinstance(raw, property):
                continue
            if isinstance(raw, staticmethod | classmethod) or inspect.isfunction(raw):
                yield name, getattr(cls, name)


def public_callables() -> dict[str, Any]:
    """``{name: object}``: every callable of every public ``__all__`` once (under its
    shortest public name) and ``Class.method`` for the classes' public methods."""
    found: dict[int, list[str]] = {}
    objs: dict[int, Any] = {}
    for mod in _public_modules():
        for name in mod.__all__:
            obj = getattr(mod, name, None)
            if _is_target(obj):
                found.setdefault(id(obj), []).append(f"{mod.__name__}.{name}")
                objs[id(obj)] = obj
    out: dict[str, Any] = {}
    for key, names in found.items():
        best = min(names, key=lambda n: (n.count("."), n))
        out[best] = objs[key]
        obj = objs[key]
        if inspect.isclass(obj):
            seen: set[str] = set()
            for mname, m in _methods(obj):
                if mname not in seen:
                    seen.add(mname)
                    out[f"{best}.{mname}"] = m
    return dict(sorted(out.items()))


# --------------------------------------------------------------------------- mutations


def _torch0d(x: float) -> Any:
    import torch

    return torch.tensor(x)


def _array_mutations(a: np.ndarray) -> dict[str, Callable[[], Any]]:
    a = np.asarray(a)
    out: dict[str, Callable[[], Any]] = {
        "none": lambda: None,
        "string": lambda: "abc",
        "bool": lambda: True,
        "object": lambda: (
            np.array(a.tolist() if a.size else [], dtype=object).reshape(a.shape)
            if a.size
            else np.empty(a.shape, dtype=object)
        ),
        "torch0d": lambda: _torch0d(1.0),
    }
    if a.ndim >= 1:
        out["empty"] = lambda: np.empty((0, *a.shape[1:]), dtype=a.dtype)
        out["wrong_shape"] = lambda: np.concatenate([a, a[..., :1]], axis=-1)
    else:
        out["wrong_shape"] = lambda: np.stack([a, a])
    if a.dtype.kind in "fiu" and a.size:

        def _with(v: float) -> Callable[[], Any]:
            def make() -> Any:
                b = a.astype(np.float64 if a.dtype.kind != "f" else a.dtype, copy=True)
                b.flat[b.size // 2] = v
                return b

            return make

        out["nan"] = _with(math.nan)
        out["inf"] = _with(math.inf)
        out["complex"] = lambda: a.astype(np.complex128) + 1e-3j
        out["huge"] = lambda: a.astype(np.float64) * 1e300 + 1e300
        out["negative"] = lambda: -np.abs(a.astype(np.float64)) - 1.0
        out["zero"] = lambda: np.zeros_like(a)
    return out


def _scalar_mutations(x: float | int) -> dict[str, Callable[[], Any]]:
    is_int = isinstance(x, int | np.integer)
    out: dict[str, Callable[[], Any]] = {
        "none": lambda: None,
        "string": lambda: str(x),
        "bool": lambda: True,
        "object": lambda: object(),
        "complex": lambda: complex(x, 1.0),
        "empty": list,
        "wrong_shape": lambda: [x, x],
        "nan": lambda: math.nan,
        "inf": lambda: math.inf,
        "huge": (lambda: 10**30) if is_int else (lambda: 1e308),
        "negative": (lambda: -abs(int(x)) - 1) if is_int else (lambda: -abs(float(x)) - 1.0),
        "zero": (lambda: 0) if is_int else (lambda: 0.0),
        "np_scalar": (lambda: np.int64(x)) if is_int else (lambda: np.float64(x)),
        "torch0d": lambda: _torch0d(x),
    }
    return out


def _tuple_mutations(t: tuple[Any, ...]) -> dict[str, Callable[[], Any]]:
    first = t[0]

    def _set(v: Any) -> Callable[[], Any]:
        return lambda: (v, *t[1:])

    return {
        "none": lambda: None,
        "string": lambda: "abc",
        "bool": lambda: True,
        "object": lambda: object(),
        "empty": lambda: (),
        "wrong_shape": lambda: (*t, first),
        "nan": _set(math.nan),
        "inf": _set(math.inf),
        "complex": _set(1 + 1j),
        "huge": _set(10**30 if isinstance(first, int) else 1e308),
        "negative": _set(-abs(first) - 1),
        "zero": _set(0 if isinstance(first, int) else 0.0),
        "np_scalar": lambda: tuple(np.int64(v) if isinstance(v, int) else np.float64(v) for v in t),
    }


def _str_mutations(s: str) -> dict[str, Callable[[], Any]]:
    return {
        "none": lambda: None,
        "empty": lambda: "",
        "object": lambda: object(),
        "bool": lambda: True,
        "zero": lambda: 0,
        "huge": lambda: "x" * 100_000,
        "wrong_shape": lambda: [s, s],
        "np_scalar": lambda: np.str_(s),
    }


def _none_mutations() -> dict[str, Callable[[], Any]]:
    """Malformed values for a parameter whose default is None (its type is unknown): one of
    each kind but ``none`` (None is the valid value)."""
    return {
        "empty": list,
        "wrong_shape": lambda: [[1.0, 2.0, 3.0, 4.0, 5.0]],
        "nan": lambda: math.nan,
        "inf": lambda: math.inf,
        "complex": lambda: 1.0 + 1.0j,
        "object": lambda: object(),
        "string": lambda: "abc",
        "bool": lambda: True,
        "huge": lambda: "x" * 100_000,
        "negative": lambda: -1,
        "zero": lambda: 0,
    }


def _other_mutations(o: Any) -> dict[str, Callable[[], Any]]:
    return {
        "none": lambda: None,
        "string": lambda: "abc",
        "object": lambda: object(),
        "zero": lambda: 0,
        "bool": lambda: True,
    }


def mutations(value: Any) -> dict[str, Callable[[], Any]]:
    """Malformed values derived from a valid ``value``, by kind."""
    if value is None:
        return _none_mutations()
    if isinstance(value, bool | np.bool_):
        return {
            "none": lambda: None,
            "string": lambda: "yes",
            "zero": lambda: 0,
            "object": lambda: object(),
            "np_scalar": lambda: np.bool_(value),
        }
    if isinstance(value, int | float | np.integer | np.floating):
        return _scalar_mutations(value.item() if isinstance(value, np.generic) else value)
    if isinstance(value, np.ndarray):
        return _array_mutations(value)
    if (
        isinstance(value, tuple)
        and value
        and all(isinstance(v, int | float) and not isinstance(v, bool) for v in value)
    ):
        return _tuple_mutations(value)
    if isinstance(value, list) and value and all(isinstance(v, int | float) for v in value):
        return _array_mutations(np.asarray(value))
    if isinstance(value, str):
        return _str_mutations(value)
    if isinstance(value, Path):
        return {"none": lambda: None, "zero": lambda: 0, "empty": lambda: Path("")}
    return _other_mutations(value)


# --------------------------------------------------------------------------- one call


@dataclass(frozen=True)
class Task:
    name: str
    param: str  # "" for the valid call itself
    kind: str  # "valid" for the valid call itself


@dataclass(frozen=True)
class Outcome:
    name: str
    param: str
    kind: str
    result: str  # "ok", "clean" or a finding
    detail: str = ""

    @property
    def is_finding(self) -> bool:
        return self.result not in ("ok", "clean")


def _bound(func: Any, entry: C) -> inspect.BoundArguments:
    sig = inspect.signature(func)
    return sig.bind(*entry.args, **entry.kwargs)


def _simple_default(v: Any) -> bool:
    return v is not None and (
        isinstance(v, bool | int | float | str)
        or (isinstance(v, tuple) and v and all(isinstance(x, int | float) for x in v))
    )


def parameters(func: Any, entry: C, *, defaults: str = "all") -> dict[str, Any]:
    """``{parameter: valid value}``: the parameters the valid call passes and the optional
    ones it leaves to their default.

    ``defaults``: ``"all"`` every default; ``"simple"`` only a simple one (a number, string,
    bool or tuple of numbers: the parameters fuzzed before issue 25); ``"other"`` only the
    parameters with another default (None, a tuple of names, a dataclass factory ...), and
    no parameter the call passes.
    """
    try:
        sig = inspect.signature(func)
        bound = sig.bind(*entry.args, **entry.kwargs)
    except (TypeError, ValueError):
        return {}
    out: dict[str, Any] = {}
    for name, p in sig.parameters.items():
        if p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD) or name in entry.fixed:
            continue
        if name in bound.arguments:
            if defaults != "other":
                out[name] = bound.arguments[name]
        elif p.default is p.empty:
            continue
        elif _simple_default(p.default):
            if defaults != "other":
                out[name] = p.default
        elif defaults != "simple":
            out[name] = p.default
    return out


def _walk_finite(x: Any, depth: int = 0) -> bool:
    """True when every float in ``x`` (arrays, numbers, and containers 3 levels deep) is
    finite; objects imageform does not return as data are ignored, and so is a result with
    ``found`` False (docs/conventions.md, "Not found": its fields are NaN by contract)."""
    if depth > 3:
        return True
    if hasattr(x, "detach") and hasattr(x, "cpu"):  # a torch tensor (torch in, torch out)
        x = x.detach().cpu().numpy()
    if isinstance(x, bool | np.bool_):
        return True
    if isinstance(x, float | np.floating):
        return math.isfinite(float(x))
    if isinstance(x, complex | np.complexfloating):
        return False
    if isinstance(x, np.ndarray):
        if x.dtype.kind == "f":
            return bool(np.all(np.isfinite(x))) if x.size else True
        return x.dtype.kind != "c"
    if isinstance(x, dict):
        return all(_walk_finite(v, depth + 1) for v in x.values())
    if isinstance(x, list | tuple):
        return all(_walk_finite(v, depth + 1) for v in list(x)[:64])
    if dataclasses.is_dataclass(x) and not isinstance(x, type):
        if getattr(x, "found", None) is False:  # not found: NaN fields are documented
            return True
        return all(_walk_finite(getattr(x, f.name), depth + 1) for f in dataclasses.fields(x))
    return True


def _names_param(msg: str, param: str) -> bool:
    """True when ``msg`` names ``param`` as a word (``R`` in "expected R as ...", not the r
    of "error"; ``-`` or a space may stand for ``_``), case-insensitively."""
    import re

    low = msg.lower()
    p = param.lower()
    for variant in {p, p.replace("_", "-"), p.replace("_", " ")}:
        if re.search(rf"(?<![a-z0-9_]){re.escape(variant)}(?![a-z0-9_])", low):
            return True
    return False


def _classify_exception(exc: BaseException, param: str) -> tuple[str, str]:
    from imageform.errors import ImageformError

    msg = str(exc)
    detail = f"{type(exc).__name__}: {msg[:300]}"
    if not isinstance(exc, ImageformError | TypeError):
        return f"raw:{type(exc).__name__}", detail
    if "\n" in msg.strip():
        return "multiline", detail
    if len(msg) > MAX_MESSAGE:
        return "long", detail
    if param and not _names_param(msg, param):
        return "unnamed", detail
    return "clean", ""


class _State:
    """Per-worker cache: the resolved callables and their valid calls' results."""

    def __init__(self) -> None:
        from tests.fuzz.table import VALID

        self.valid = VALID
        self.funcs = public_callables()
        self.baseline: dict[str, tuple[bool, int | None] | None] = {}


def _build_call(state: _State, name: str) -> tuple[Any, C]:
    entry = state.valid[name]
    assert isinstance(entry, C)
    func = state.funcs[name]
    if entry.self_ is not None:
        inst = entry.self_
        if isinstance(inst, C):
            owner = state.funcs[name.rsplit(".", 1)[0]]
            inst = owner(*resolve(inst.args), **resolve(inst.kwargs))
        else:
            inst = resolve(inst)
        func = getattr(inst, name.rsplit(".", 1)[1])
    return func, entry


def _invoke(func: Any, args: tuple[Any, ...], kwargs: dict[str, Any]) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        warnings.simplefilter("error", np.exceptions.ComplexWarning)
        return func(*args, **kwargs)


def _shape(x: Any) -> int | None:
    """The number of dimensions of an array result of any array library."""
    nd = getattr(x, "ndim", None)
    return nd if isinstance(nd, int) and hasattr(x, "shape") else None


def run_task(state: _State, task: Task) -> Outcome:
    """Make one call and classify what happened."""
    name = task.name
    try:
        func, entry = _build_call(state, name)
    except Exception as exc:  # the instance could not be built: a table error
        return Outcome(name, task.param, task.kind, "table_error", repr(exc)[:300])
    if name not in state.baseline:
        try:
            res = _invoke(func, resolve(entry.args), resolve(entry.kwargs))
            state.baseline[name] = (_walk_finite(res), _shape(res))
        except BaseException as exc:
            state.baseline[name] = None
            if task.kind == "valid":
                return Outcome(name, "", "valid", "valid_fails", repr(exc)[:300])
        func, entry = _build_call(state, name)
    base = state.baseline[name]
    if task.kind == "valid":
        return Outcome(name, "", "valid", "ok" if base else "valid_fails")
    if base is None:
        return Outcome(name, task.param, task.kind, "valid_fails")
    try:
        bound = _bound(func, entry)
    except TypeError as exc:
        return Outcome(name, task.param, task.kind, "table_error", str(exc))
    values = parameters(func, entry)
    make = mutations(values[task.param]).get(task.kind)
    if make is None:
        return Outcome(name, task.param, task.kind, "ok", "kind does not apply")
    arguments = resolve(dict(bound.arguments))
    sig = bound.signature
    args: list[Any] = []
    kwargs: dict[str, Any] = {}
    skipped = False  # a parameter left to its default: later ones go by keyword
    for pname, p in sig.parameters.items():
        if pname == task.param:
            value = make()
        elif pname in arguments:
            value = arguments[pname]
        else:
            skipped = skipped or p.kind is p.POSITIONAL_OR_KEYWORD
            continue
        if p.kind is p.VAR_POSITIONAL:
            args.extend(value)
        elif p.kind is p.VAR_KEYWORD:
            kwargs.update(value)
        elif (
            p.kind is p.KEYWORD_ONLY
            or (kwargs and p.kind is p.POSITIONAL_OR_KEYWORD)
            or (skipped and p.kind is p.POSITIONAL_OR_KEYWORD)
            or (pname == task.param and pname not in bound.arguments)
        ):
            kwargs[pname] = value
        else:
            args.append(value)
    try:
        res = _invoke(func, tuple(args), kwargs)
    except RecursionError as exc:
        return Outcome(name, task.param, task.kind, "raw:RecursionError", repr(exc)[:200])
    except Exception as exc:
        result, detail = _classify_exception(exc, task.param)
        if result == "clean" and task.kind == "np_scalar":
            return Outcome(name, task.param, task.kind, "np_scalar_refused", str(exc)[:300])
        return Outcome(name, task.param, task.kind, result, detail)
    if base[0] and not _walk_finite(res):
        from tests.fuzz.table import DOCUMENTED_NONFINITE

        why = DOCUMENTED_NONFINITE.get((name, task.param, task.kind))
        if why is not None:
            return Outcome(name, task.param, task.kind, "ok", f"documented: {why}")
        return Outcome(name, task.param, task.kind, "nonfinite")
    # a 0-d value in place of a scalar keeps the result's shape; in place of an array an
    # elementwise function rightly returns a 0-d result
    original = resolve(values[task.param])
    was_scalar = (
        getattr(original, "ndim", None) == 0
        if hasattr(original, "ndim")
        else isinstance(original, int | float | complex | np.number)
    )
    if (
        task.kind in ("np_scalar", "torch0d")
        and was_scalar
        and base[1] is not None
        and _shape(res) != base[1]
    ):
        return Outcome(name, task.param, task.kind, "wrong_result_shape")
    return Outcome(name, task.param, task.kind, "ok")


def tasks_for(name: str, func: Any, entry: C, *, defaults: str = "all") -> list[Task]:
    """The valid call and its malformed variants (``defaults``: see :func:`parameters`)."""
    out = [Task(name, "", "valid")]
    if entry.self_ is not None:
        try:
            params = parameters(func, entry, defaults=defaults)
        except Exception:
            params = {}
    else:
        params = parameters(func, entry, defaults=defaults)
    for pname, value in params.items():
        try:
            muts = mutations(resolve(value))
        except Exception:
            continue
        out.extend(Task(name, pname, kind) for kind in _kinds() if kind in muts)
    return out


def _kinds() -> tuple[str, ...]:
    """:data:`KINDS`, without ``torch0d`` where PyTorch is not installed."""
    import importlib.util

    if importlib.util.find_spec("torch") is None:
        return tuple(k for k in KINDS if k != "torch0d")
    return KINDS


def all_tasks(*, defaults: str = "all") -> list[Task]:
    """Every task of every callable with a valid call (``defaults``: see :func:`parameters`)."""
    from tests.fuzz.table import VALID

    funcs = public_callables()
    out: list[Task] = []
    for name, func in funcs.items():
        entry = VALID.get(name)
        if isinstance(entry, C):
            out.extend(tasks_for(name, func, entry, defaults=defaults))
    return out


def select(tasks: list[Task], budget: int | None, seed: int) -> list[Task]:
    """All tasks, or ``budget`` of them: every valid call, then a fixed-seed sample of the
    mutations (each callable's share as even as the budget allows)."""
    if budget is None or budget >= len(tasks):
        return tasks
    valid = [t for t in tasks if t.kind == "valid"]
    rest = [t for t in tasks if t.kind != "valid"]
    rng = random.Random(seed)
    rng.shuffle(rest)
    by_name: dict[str, list[Task]] = {}
    for t in rest:
        by_name.setdefault(t.name, []).append(t)
    picked: list[Task] = []
    n = max(0, budget - len(valid))
    rounds = [iter(v) for v in by_name.values()]
    while len(picked) < n and rounds:
        nxt = []
        for it in rounds:
            t = next(it, None)
            if t is not None:
                picked.append(t)
                nxt.append(it)
                if len(picked) >= n:
                    break
        rounds = nxt
    return valid + sorted(picked, key=lambda t: (t.name, t.param, t.kind))


# --------------------------------------------------------------------------- worker pool


def _limit_memory() -> None:
    try:
        with open("/proc/self/status") as fh:
            vm = next(int(line.split()[1]) * 1024 for line in fh if line.startswith("VmSize"))
    except (OSError, StopIteration):
        vm = 0
    limit = vm + WORKER_MEMORY
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))


def _worker(conn: Any, root: str) -> None:
    # a fuzzed path argument ("abc") is relative: it lands in a folder of the worker's own
    # inside the run's folder ``root``, removed when the worker ends (and ``root`` with
    # whatever a killed worker left, when the run ends: :func:`run`), not in the repository
    scratch = tempfile.mkdtemp(prefix="worker-", dir=root)
    os.chdir(scratch)
    # the values' temporary files and folders (values._tmpdir) go there too
    os.environ["IMAGEFORM_FUZZ_TMP"] = scratch
    try:
        _serve(conn)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def _serve(conn: Any) -> None:
    os.environ["IMAGEFORM_MAX_MEMORY"] = IMAGEFORM_MEMORY
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")
    state = _State()
    with contextlib.suppress(ImportError):  # the torch0d values; imported before the limit
        import torch  # noqa: F401
    _limit_memory()
    conn.send("ready")  # the call timeout starts after the imports
    while True:
        try:
            task = conn.recv()
        except EOFError:
            return
        if task is None:
            return
        try:
            out = run_task(state, task)
        except BaseException as exc:  # the harness itself; keep going
            out = Outcome(
                task.name,
                task.param,
                task.kind,
                "harness_error",
                "".join(traceback.format_exception_only(exc))[:300],
            )
        try:
            conn.send(out)
        except Exception:
            conn.send(Outcome(task.name, task.param, task.kind, "harness_error", "unpicklable"))


def run(
    tasks: Iterable[Task],
    *,
    workers: int = 1,
    timeout: float = 20.0,
    progress: Callable[[int, int], None] | None = None,
    tmp: str | os.PathLike[str] | None = None,
) -> list[Outcome]:
    """Run ``tasks`` in ``workers`` forked processes (tasks of one callable go to one
    worker, in order), each call under ``timeout`` seconds; a worker that times out or dies
    is replaced.

    The workers' files (their working folders, the values' temporary files) go in one
    ``imageform-fuzz-*`` folder under ``tmp`` (default: the system's temporary folder),
    removed when the run ends, also what a killed worker could not remove itself.
    """
    root = tempfile.mkdtemp(prefix="imageform-fuzz-", dir=tmp)
    try:
        return _run(tasks, workers, timeout, progress, root)
    finally:
        shutil.rmtree(root, ignore_errors=True)


def _run(
    tasks: Iterable[Task],
    workers: int,
    timeout: float,
    progress: Callable[[int, int], None] | None,
    root: str,
) -> list[Outcome]:
    ctx = mp.get_context("spawn")  # fork after OpenMP/torch threads started is unsafe
    groups: dict[str, list[Task]] = {}
    for t in tasks:
        groups.setdefault(t.name, []).append(t)
    queue = list(groups.values())
    total = sum(len(g) for g in queue)
    outcomes: list[Outcome] = []

    def start() -> tuple[Any, Any]:
        parent, child = ctx.Pipe()
        p = ctx.Process(target=_worker, args=(child, root), daemon=True)
        p.start()
        child.close()
        try:
            ready = parent.poll(STARTUP_TIMEOUT) and parent.recv() == "ready"
        except (EOFError, OSError):
            ready = False
        if not ready:
            p.kill()
            raise RuntimeError(
                f"fuzz worker did not start within {STARTUP_TIMEOUT:g} s (exit {p.exitcode})"
            )
        return p, parent

    slots: list[dict[str, Any]] = []
    for _ in range(max(1, workers)):
        p, conn = start()
        slots.append({"p": p, "conn": conn, "group": None, "task": None, "t0": 0.0})
    try:
        while queue or any(s["group"] or s["task"] for s in slots):
            for s in slots:
                if s["task"] is None:
                    if not s["group"]:
                        s["group"] = queue.pop(0) if queue else None
                    if s["group"]:
                        s["task"] = s["group"].pop(0)
                        s["conn"].send(s["task"])
                        s["t0"] = time.monotonic()
            busy = [s for s in slots if s["task"] is not None]
            if not busy:
                break
            ready = mp.connection.wait([s["conn"] for s in busy], timeout=0.2)
            for s in busy:
                t = s["task"]
                dead = False
                if s["conn"] in ready:
                    try:
                        outcomes.append(s["conn"].recv())
                    except (EOFError, OSError):
                        dead = True
                        s["p"].join(1)
                        code = s["p"].exitcode
                        outcomes.append(Outcome(t.name, t.param, t.kind, "crash", f"exit {code}"))
                    else:
                        s["task"] = None
                elif time.monotonic() - s["t0"] > timeout:
                    dead = True
                    outcomes.append(Outcome(t.name, t.param, t.kind, "timeout", f"> {timeout:g} s"))
                if dead:
                    s["p"].kill()
                    s["p"].join(5)
                    s["conn"].close()
                    s["p"], s["conn"] = start()
                    s["task"] = None
                if s["task"] is None and progress is not None:
                    progress(len(outcomes), total)
    finally:
        for s in slots:
            with contextlib.suppress(Exception):
                s["conn"].send(None)
            s["p"].join(2)
            if s["p"].is_alive():
                s["p"].kill()
    return outcomes


# --------------------------------------------------------------------------- results


#: Outcomes that say the table or the harness is wrong, never listed in KNOWN.
HARNESS_OUTCOMES = ("valid_fails", "table_error", "harness_error")


def findings(outcomes: Iterable[Outcome]) -> dict[tuple[str, str, str], Outcome]:
    """``{(callable, parameter, kind): outcome}`` of the calls that broke the contract."""
    return {(o.name, o.param, o.kind): o for o in outcomes if o.is_finding}


def new_findings(
    outcomes: Iterable[Outcome], known: dict[tuple[str, str, str], str]
) -> dict[tuple[str, str, str], Outcome]:
    """The findings not in ``known`` (harness and table errors always count)."""
    return {
        k: o
        for k, o in findings(outcomes).items()
        if k not in known or o.result in HARNESS_OUTCOMES
    }


def format_findings(found: dict[tuple[str, str, str], Outcome], limit: int = 40) -> str:
    lines = [
        f"{name} {param or '-'} {kind}: {o.result} {o.detail[:120]}"
        for (name, param, kind), o in sorted(found.items())
    ]
    more = f"\n... and {len(lines) - limit} more" if len(lines) > limit else ""
    return "\n".join(lines[:limit]) + more


def package_of(name: str) -> str:
    parts = name.split(".")
    return parts[1] if len(parts) > 2 else "imageform"
