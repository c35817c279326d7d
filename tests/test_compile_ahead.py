"""A first run compiles on two cores (imageform._kernels.ahead) and deferred kernels (jit).

The plans must name kernels that exist with the signatures the commands use (a stale entry
costs a first run its gain, silently); the second process must fill the cache, end, and never
change a result; and nothing may start when the cache is warm or the feature is off.
"""

from __future__ import annotations

import inspect
import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path
from typing import cast

import numpy as np
import pytest

from imageform._kernels import ahead, jit

SRC = Path(__file__).resolve().parents[1] / "src"
ROOT = SRC.parent


def _python(code: str, cache: Path | None = None, **env: str) -> subprocess.CompletedProcess[str]:
    """``python -c code`` with this checkout's sources, the second process on, a fresh cache."""
    extra = {} if cache is None else {"NUMBA_CACHE_DIR": str(cache)}
    return subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        env={
            **os.environ,
            "PYTHONPATH": str(SRC),
            "IMAGEFORM_COMPILE_AHEAD": "1",
            **extra,
            **env,
        },
        timeout=300,
    )


def _entries() -> list[tuple[str, ahead.Entry]]:
    return [(command, e) for command, plan in ahead.PLANS.items() for e in plan.child + plan.here]


@pytest.mark.parametrize(
    ("command", "entry"), _entries(), ids=lambda v: str(getattr(v, "kernel", v))
)
def test_every_entry_names_a_kernel_with_its_signature(command: str, entry: ahead.Entry) -> None:
    """Each entry: an imageform kernel, its signature parses, one type per parameter."""
    import importlib

    from numba.core.registry import CPUDispatcher

    module = importlib.import_module(f"imageform._kernels.{entry.module}")
    kernel = getattr(module, entry.kernel)
    dispatcher = kernel.dispatcher if isinstance(kernel, jit.Deferred) else kernel
    assert isinstance(dispatcher, CPUDispatcher)
    args = ahead._signature(entry.signature)
    assert len(args) == len(inspect.signature(dispatcher.py_func).parameters)
    if isinstance(kernel, jit.Deferred):
        from numba.core import sigutils

        assert tuple(sigutils.normalize_signature(kernel.signature)[0]) == args


def test_a_here_entry_is_not_a_child_entry() -> None:
    for plan in ahead.PLANS.values():
        assert not {(e.module, e.kernel) for e in plan.here} & {
            (e.module, e.kernel) for e in plan.child
        }


def test_nothing_starts_when_off_or_unplanned(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("IMAGEFORM_COMPILE_AHEAD", "0")
    assert not ahead.enabled()
    assert ahead.start("simulate") is False
    monkeypatch.setenv("IMAGEFORM_COMPILE_AHEAD", "1")
    monkeypatch.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
    assert not ahead.enabled()
    monkeypatch.delenv("IMAGEFORM_DISABLE_NUMBA")
    assert ahead.start("no-such-command") is False
    assert ahead.pending("no-such-command") == ()
    ahead.ready("lsd.grow_regions")  # no second process: returns at once
    ahead.ready()


def test_the_second_process_refuses_bad_arguments() -> None:
    for argv in ([], ["not json"], ['{"a": 1}'], ["[[1]]"]):
        done = subprocess.run(
            [sys.executable, "-m", "imageform._kernels.ahead", *argv],
            capture_output=True,
            text=True,
            env={**os.environ, "PYTHONPATH": str(SRC)},
        )
        assert done.returncode == 2, argv
        assert done.stderr.count("\n") == 1 and "usage:" in done.stderr


def test_the_second_process_leaves_quietly_on_ctrl_c(monkeypatch: pytest.MonkeyPatch) -> None:
    def interrupted(entry: ahead.Entry) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(ahead, "compile_entry", interrupted)
    assert ahead._main([json.dumps([["ransac", "_copy3", "(float64[:, ::1])"]])]) == 130


_RUN = textwrap.dedent(
    """
    import json, sys, time
    from pathlib import Path
    from imageform._kernels import ahead
    from imageform._kernels.jit import cache_location

    E = ahead.Entry
    A2 = "float64[:, ::1]"
    ahead.PLANS["t"] = ahead.Plan(
        child=(
            E("ransac", "_copy3", f"({A2}, {A2})"),
            E("ransac", "no_such_kernel", "(int64)"),  # stale: skipped, the rest still done
            E("ransac", "_fro_unit", f"({A2})"),
            E("ransac_e", "_e_of", f"({A2}, float64[::1], {A2})"),
        ),
        here=(E("ransac", "_finite3", f"({A2})"),),
    )
    from numba.core import event
    compiled = []

    class Seen(event.Listener):
        def on_start(self, e):
            pass

        def on_end(self, e):
            compiled.append(e.data["dispatcher"].py_func.__qualname__)

    event.register("numba:compile", Seen())
    folder = cache_location()[0]
    before = [e.kernel for e in ahead.pending("t")]
    started = ahead.start("t")
    # at once: this process waits for the second one, then loads the kernel from the cache
    ahead.compile_entry(ahead.PLANS["t"].child[2])
    ahead.ready("ransac._copy3")
    child = ahead._CHILD
    ahead.ready()
    done = sorted(child.done)
    ahead.stop()
    names = sorted(p.name.split("-")[0] for p in folder.glob("*.nbi"))
    print(json.dumps({"before": before, "started": started, "done": done, "names": names,
                      "after": [e.kernel for e in ahead.pending("t")],
                      "again": ahead.start("t"), "code": child.proc.returncode,
                      "compiled": compiled}))
    """
)


def _run(cache: Path, **env: str) -> dict[str, object]:
    done = _python(_RUN, cache, **env)
    assert done.returncode == 0, done.stderr[-3000:]
    return dict(json.loads(done.stdout.strip().splitlines()[-1]))


def test_the_second_process_fills_the_cache_then_nothing_starts(tmp_path: Path) -> None:
    """A cold cache: the child compiles its entries (a stale one skipped), this process its
    own; both land in the cache, the child exits 0, and a second start finds nothing to do."""
    out = _run(tmp_path / "cache")
    assert out["started"] is True
    assert set(cast(list[str], out["before"])) == {
        "_copy3",
        "no_such_kernel",
        "_fro_unit",
        "_e_of",
        "_finite3",
    }
    assert out["done"] == [
        "ransac._copy3",
        "ransac._fro_unit",
        "ransac.no_such_kernel",
        "ransac_e._e_of",
    ]
    names = set(cast(list[str], out["names"]))
    assert {"ransac._copy3", "ransac._fro_unit", "ransac_e._e_of", "ransac._finite3"} <= names
    assert out["after"] == ["no_such_kernel"]  # a stale entry never counts as cached ...
    assert out["again"] is True  # ... so the plan tests above keep every entry real
    assert out["code"] in (0, -signal.SIGTERM)  # done, or ended by the command's exit
    compiled = set(cast(list[str], out["compiled"]))
    assert "_finite3" in compiled  # this process's entry
    assert not {"_copy3", "_fro_unit", "_e_of"} & compiled  # waited for, then loaded


def test_a_single_core_starts_nothing(tmp_path: Path) -> None:
    if not hasattr(os, "sched_setaffinity"):
        pytest.skip("needs os.sched_setaffinity (Linux)")
    code = (
        "import os; os.sched_setaffinity(0, {0})\n"
        "from imageform._kernels import ahead\n"
        "print(ahead.enabled(), ahead.start('simulate'), ahead._CHILD)"
    )
    done = _python(code, tmp_path / "cache")
    assert done.stdout.split() == ["False", "False", "None"], done.stderr[-2000:]


def test_ready_returns_when_the_second_process_dies(monkeypatch: pytest.MonkeyPatch) -> None:
    """A child that ends without reporting (a crash) does not hold the command."""
    child = ahead._Child.__new__(ahead._Child)
    child.waiting = {"lsd.grow_regions"}
    child.done = set()
    import threading

    child.ended = threading.Event()
    child.changed = threading.Condition()
    child.proc = subprocess.Popen(
        [sys.executable, "-c", "import sys; sys.exit(3)"], stdout=subprocess.PIPE, text=True
    )
    child.reader = threading.Thread(target=child._read, daemon=True)
    child.reader.start()
    monkeypatch.setattr(ahead, "_CHILD", child)
    ahead.ready("lsd.grow_regions")
    ahead.ready()
    assert child.ended.is_set() and child.done == set()
    child.stop()


def test_a_deferred_kernel_compiles_at_its_first_call_for_its_signature_only() -> None:
    """``njit(signature, lazy=True)``: nothing at import, one signature, numba's conversions."""
    code = textwrap.dedent(
        """
        import numpy as np
        from imageform._kernels import jit
        from imageform._kernels.relative_pose import pose_from_essential as k
        assert isinstance(k, jit.Deferred) and k.signatures == [], k.signatures
        E = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
        rng = np.random.default_rng(0)
        q = rng.normal(size=(20, 2))
        R, t, X = np.empty((3, 3)), np.empty(3), np.empty((20, 3))
        m = k(E, q, q + 0.01, np.ones(20, bool), 50.0, R, t, X, np.empty(20, bool))
        assert len(k.signatures) == 1 and isinstance(m, int)
        try:
            k(E.astype(np.float32), q, q, np.ones(20, bool), 50.0, R, t, X, np.empty(20, bool))
        except TypeError:
            print("ok")
        """
    )
    done = _python(code)
    assert done.returncode == 0 and done.stdout.strip() == "ok", done.stderr[-2000:]


def test_njit_lazy_needs_a_signature() -> None:
    with pytest.raises(TypeError, match="signature"):
        jit.njit(lazy=True)


@pytest.mark.slow
@pytest.mark.parametrize("command", sorted(ahead.PLANS))
def test_the_plans_are_what_the_commands_compile(command: str, tmp_path: Path) -> None:
    """Every entry is compiled by its command, with that signature, on an empty cache
    (``benchmarks/compile_plan.py --check``: a cold run of the command)."""
    done = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "compile_plan.py"), command, "--check"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=900,
    )
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]


@pytest.mark.slow
def test_simulate_writes_the_same_files_with_and_without_the_second_process(
    tmp_path: Path,
) -> None:
    """Two cold first runs of ``imageform simulate``: every stage image and metric equal."""
    outs = []
    for flag in ("1", "0"):
        out = tmp_path / f"sim{flag}"
        env = {
            **os.environ,
            "PYTHONPATH": str(SRC),
            "NUMBA_CACHE_DIR": str(tmp_path / f"cache{flag}"),
            "IMAGEFORM_COMPILE_AHEAD": flag,
            "MPLBACKEND": "Agg",
        }
        done = subprocess.run(
            [sys.executable, "-m", "imageform", "simulate", "-o", str(out)],
            capture_output=True,
            text=True,
            env=env,
            timeout=900,
        )
        assert done.returncode == 0, done.stderr[-2000:]
        outs.append(out)
    for png in sorted((outs[0] / "stages").glob("*.png")):
        assert png.read_bytes() == (outs[1] / "stages" / png.name).read_bytes(), png.name
    m0, m1 = (json.loads((o / "metrics.json").read_text()) for o in outs)
    for m in (m0, m1):
        m.pop("simulation_time_s", None)
        m.pop("step_times_s", None)
    assert m0 == m1
    assert np.isfinite(float(len(m0)))


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    # a zombie (ended, not yet reaped by its parent) counts as gone
    stat = Path(f"/proc/{pid}/stat")
    return not (stat.exists() and stat.read_text().split(")")[-1].split()[0] == "Z")


@pytest.mark.skipif(not hasattr(os, "killpg"), reason="process groups: POSIX")
def test_ctrl_c_on_a_first_run_ends_both_processes_in_one_line(tmp_path: Path) -> None:
    """Ctrl-C (SIGINT to the terminal's process group) while the second process compiles:
    the command's one line and exit 130, no traceback from either process, none left."""
    if not Path(f"/proc/{os.getpid()}/task/{os.getpid()}/children").exists():
        pytest.skip("needs /proc/PID/task/TID/children (Linux) to find the second process")
    text = (ROOT / "examples" / "scenes" / "default.toml").read_text()
    text = text.replace("width = 1280", "width = 320").replace("height = 720", "height = 180")
    (tmp_path / "small.toml").write_text(text)
    env = {
        **os.environ,
        "PYTHONPATH": str(SRC),
        "NUMBA_CACHE_DIR": str(tmp_path / "cache"),
        "IMAGEFORM_COMPILE_AHEAD": "1",
        "MPLBACKEND": "Agg",
    }
    run = subprocess.Popen(
        [sys.executable, "-m", "imageform", "simulate", "--scene", "small.toml", "-o", "out"],
        cwd=tmp_path,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,  # its own process group, as a terminal's foreground job
    )
    children: set[int] = set()
    t0 = time.monotonic()
    while not children and time.monotonic() - t0 < 120 and run.poll() is None:
        kids = Path(f"/proc/{run.pid}/task/{run.pid}/children")
        if kids.exists():
            children = {int(p) for p in kids.read_text().split()}
        time.sleep(0.05)
    assert children, "no second process started"
    time.sleep(0.5)
    os.killpg(run.pid, signal.SIGINT)
    _, err = run.communicate(timeout=120)
    assert run.returncode == 130, err
    assert err.strip().splitlines() == ["imageform: interrupted; nothing new was written"]
    t1 = time.monotonic()
    while any(_alive(p) for p in children) and time.monotonic() - t1 < 10:
        time.sleep(0.05)
    assert not any(_alive(p) for p in children)
    assert not (tmp_path / "out").exists()


def test_a_ctrl_c_inside_a_finalizer_is_raised_again_not_printed(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The command's hook for exceptions raised in ``__del__``: a KeyboardInterrupt there (a
    Ctrl-C landing in llvmlite's finalizers while numba compiles) interrupts the main thread
    again, silently; any other is printed by Python's own hook, as before."""
    from imageform.cli import _interrupt_in_finalizer

    class Interrupted:
        def __del__(self) -> None:
            raise KeyboardInterrupt

    class Broken:
        def __del__(self) -> None:
            raise ValueError("boom")

    monkeypatch.setattr(sys, "unraisablehook", _interrupt_in_finalizer)
    with pytest.raises(KeyboardInterrupt):
        Interrupted()
        for _ in range(100):
            time.sleep(0.01)
    assert capsys.readouterr().err == ""
    Broken()
    assert "ValueError: boom" in capsys.readouterr().err


def test_an_error_after_a_ctrl_c_is_the_interrupt(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A Ctrl-C that lands inside a library can come out as that library's own error (CI:
    numba, interrupted while compiling, then raised "no compiled object yet for <Library
    '_bc_undistort'>"): once the command has been interrupted, any error is reported as the
    interrupt (one line, exit 130); without an interrupt the same error is "unexpected"."""
    import imageform.cli as cli

    def interrupted_then_broken(**_: object) -> int:
        cli._interrupted.set()  # what the SIGINT handler does before raising
        raise RuntimeError("no compiled object yet for <Library '_bc_undistort'>")

    def broken(**_: object) -> int:
        raise RuntimeError("no compiled object yet for <Library '_bc_undistort'>")

    monkeypatch.setattr(cli.root, "main", interrupted_then_broken)
    assert cli.main(["simulate"]) == 130
    assert capsys.readouterr().err.strip() == "imageform: interrupted; nothing new was written"
    monkeypatch.setattr(cli.root, "main", broken)  # a new command: the flag is cleared
    assert cli.main(["simulate"]) == 1
    assert "unexpected RuntimeError: no compiled object yet" in capsys.readouterr().err


def test_a_half_built_llvmlite_object_says_nothing_when_collected(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A Ctrl-C landing in the constructor of one of llvmlite's objects leaves it without its
    handle; its finalizer's AttributeError (seen in CI after "interrupted; nothing new was
    written") is not printed. An AttributeError in any other finalizer still is."""
    from imageform.cli import _interrupt_in_finalizer

    class HalfBuilt:
        def __del__(self) -> None:
            raise AttributeError("'PipelineTuningOptions' object has no attribute '_as_parameter_'")

    HalfBuilt.__del__.__module__ = "llvmlite.binding.ffi"

    class Ours:
        def __del__(self) -> None:
            raise AttributeError("no such thing")

    monkeypatch.setattr(sys, "unraisablehook", _interrupt_in_finalizer)
    HalfBuilt()
    assert capsys.readouterr().err == ""
    Ours()
    assert "AttributeError: no such thing" in capsys.readouterr().err
