"""The ``imageform`` command.

Generated from the workflow registry (:mod:`imageform.workflows`): inputs are positional, the
main output is ``-o/--out``, ``--force`` overwrites, ``--json`` prints the result. Exit codes:
0 success, 1 failure with a one-line reason on stderr, 2 bad usage, 3 a check that failed,
130 interrupted. No traceback reaches the user unless ``--traceback`` is given (or
``IMAGEFORM_TRACEBACK=1``).
"""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import sys
import threading
from collections.abc import Sequence
from types import FrameType

import click

from imageform.cli._build import EXIT_CODES, CommandExit
from imageform.cli._root import root

__all__ = ["EXIT_CODES", "main", "root"]


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__


def _one_line(text: str) -> str:
    return " ".join(line.strip() for line in text.strip().splitlines() if line.strip())


def _usage_line(exc: click.UsageError) -> str:
    """Return the one line a usage error prints on stderr.

    ``imageform white-balance: error: No such option '--bogus'. (see 'imageform white-balance
    --help')``: the command as typed, the reason, and where its options are listed; click's own
    four lines (usage, hint, blank, ``Error:``) said the same in four.
    """
    ctx = exc.ctx
    where = ctx.command_path if ctx is not None else "imageform"
    hint = ""
    if ctx is not None and ctx.command.get_help_option(ctx) is not None:
        names = ctx.command.get_help_option_names(ctx)
        hint = f" (see '{where} {max(names, key=len)}')"
    message = exc.format_message()
    if isinstance(exc, click.NoSuchOption) and ctx is not None:
        message = _no_such_option(exc, ctx)
    return f"{where}: error: {_one_line(message)}{hint}"


def _no_such_option(exc: click.NoSuchOption, ctx: click.Context) -> str:
    """Return the reason of an unknown option, suggesting only options ``--help`` lists.

    "No such option '--bi'. (Did you mean '--bit-depth'?)". click suggests from every
    option the parser knows, hidden deprecated spellings included (``--bit`` drew '--bits',
    '--to', '--white' and not '--bit-depth'): here the visible options that start with what
    was typed come first, then difflib's close matches (ratio 0.7 or more).
    """
    import difflib

    typed = exc.option_name
    visible = [
        name
        for param in ctx.command.get_params(ctx)
        if isinstance(param, click.Option) and not param.hidden
        for name in (*param.opts, *param.secondary_opts)
        if name.startswith("-")
    ]
    prefix = [name for name in visible if typed.startswith("--") and name.startswith(typed)]
    close = difflib.get_close_matches(typed, visible, n=3, cutoff=0.7)
    picks = list(dict.fromkeys([*prefix, *close]))[:3]
    text = f"No such option '{typed}'."
    if len(picks) == 1:
        return f"{text} (Did you mean '{picks[0]}'?)"
    if picks:
        return f"{text} (Did you mean one of: {', '.join(repr(p) for p in picks)}?)"
    return text


def _os_error(exc: OSError) -> str:
    name = exc.filename if exc.filename is not None else None
    if name is not None and len(str(name)) > 100:  # a name too long to read (or to use)
        from imageform._validate import describe

        name = describe(str(name), 100)
    reason = exc.strerror or _first_line(exc)
    return f"{name}: {reason}" if name else reason


#: Set when a Ctrl-C or SIGTERM reached the running command (cleared as each command starts).
_interrupted = threading.Event()


def _on_signal(signum: int, frame: FrameType | None) -> None:
    """Raise KeyboardInterrupt (SIGINT, SIGTERM), as Python's own handler does, and remember it."""
    _interrupted.set()
    raise KeyboardInterrupt


_INTERRUPTED = "imageform: interrupted; nothing new was written"


def _interrupt_in_finalizer(unraisable: sys.UnraisableHookArgs) -> None:
    """Raise a Ctrl-C that landed in a finalizer again, in the main thread, instead of printing it.

    Python prints an exception raised inside ``__del__`` ("Exception ignored in ...") and goes
    on: a Ctrl-C that lands in one of llvmlite's finalizers while numba compiles (a first run)
    printed ten lines and was lost. Every other unraisable exception is printed as before.
    """
    if isinstance(unraisable.exc_value, KeyboardInterrupt):
        import _thread

        _interrupted.set()

        # from another thread, a moment later: called here, it would raise in this hook
        timer = threading.Timer(0.05, _thread.interrupt_main)
        timer.daemon = True
        timer.start()
        return
    if _half_built_by_an_interrupt(unraisable):
        return
    sys.__unraisablehook__(unraisable)


def _half_built_by_an_interrupt(unraisable: sys.UnraisableHookArgs) -> bool:
    """Return True for an AttributeError in the finalizer of one of llvmlite's objects.

    A Ctrl-C that lands in such an object's constructor while numba compiles leaves it
    without its handle; its ``__del__`` then fails ("'PipelineTuningOptions' object has no
    attribute '_as_parameter_'") when it is collected, after the command has said it was
    interrupted: nine lines of traceback for nothing wrong.
    """
    where = getattr(unraisable.object, "__module__", None) or type(unraisable.object).__module__
    return isinstance(unraisable.exc_value, AttributeError) and str(where).startswith("llvmlite")


def _quiet(unraisable: sys.UnraisableHookArgs) -> None:
    """Say nothing of an exception in a finalizer (the command is leaving after an interrupt)."""


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``imageform`` console script; returns the exit code.

    Ctrl-C (SIGINT) and SIGTERM end a command with exit code 130 and one line on stderr, even
    when the signal lands while the command is already finishing (a signal held back during
    the final renames is delivered when they are done).
    """
    if argv is None:  # run as a program: its hooks are ours
        sys.unraisablehook = _interrupt_in_finalizer
    try:
        code = _main(argv)
    except KeyboardInterrupt:
        print(_INTERRUPTED, file=sys.stderr)
        code = 130
    if argv is None and threading.current_thread() is threading.main_thread():
        # run as a program, the process exits next: a signal arriving now (or one held back
        # and delivered late) must not turn the exit code into death by that signal while
        # the interpreter shuts down
        try:
            signal.signal(signal.SIGINT, signal.SIG_IGN)
            signal.signal(signal.SIGTERM, signal.SIG_IGN)
        except KeyboardInterrupt:
            code = 130
        if code == 130:
            # objects half-built when the interrupt landed may fail in their finalizers from
            # here on: nothing to say about them, the command has said it was interrupted
            sys.unraisablehook = _quiet
            # interrupted: leave now, with exit code 130. The interpreter's shutdown would
            # re-raise a KeyboardInterrupt noticed late (in a thread join, say) as death by
            # SIGINT; everything this command wrote is already renamed or removed. A second
            # process compiling ahead (a first run) is ended here: atexit does not run.
            ahead = sys.modules.get("imageform._kernels.ahead")
            if ahead is not None:
                with contextlib.suppress(Exception):
                    ahead.stop()
            for stream in (sys.stdout, sys.stderr):
                with contextlib.suppress(Exception):
                    stream.flush()
            os._exit(130)
    return code


def _main(argv: Sequence[str] | None) -> int:
    from imageform.errors import ImageformError

    args = list(sys.argv[1:] if argv is None else argv)
    traceback = "--traceback" in args or os.environ.get("IMAGEFORM_TRACEBACK", "") not in ("", "0")
    if not traceback:
        # tifffile logs what it makes of a malformed tag ("<tifffile.TiffTag 338 @524910>
        # raised ValueError(...)") through logging's last resort onto stderr, beside the one
        # line a command says; the file is read or refused either way
        logging.getLogger("tifffile").setLevel(logging.CRITICAL)
    in_main = threading.current_thread() is threading.main_thread()
    _interrupted.clear()
    old = signal.signal(signal.SIGTERM, _on_signal) if in_main else None
    old_int = None
    if in_main and signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        old_int = signal.signal(signal.SIGINT, _on_signal)
    try:
        rv = root.main(args=args, prog_name="imageform", standalone_mode=False)
        return rv if isinstance(rv, int) else 0
    except CommandExit as exc:
        return exc.code
    except click.exceptions.Exit as exc:
        return int(exc.exit_code)
    except click.exceptions.NoArgsIsHelpError as exc:  # a command alone: its help, exit 2
        exc.show()
        return 2
    except click.UsageError as exc:
        print(_usage_line(exc), file=sys.stderr)
        return 2
    except click.ClickException as exc:
        print(f"imageform: error: {_one_line(exc.format_message())}", file=sys.stderr)
        return 1
    except (KeyboardInterrupt, click.exceptions.Abort):
        print(_INTERRUPTED, file=sys.stderr)
        return 130
    except BaseException as exc:
        if isinstance(exc, SystemExit):
            return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
        if _interrupted.is_set() and not traceback:
            # a Ctrl-C that landed inside a library (numba compiling, say) can surface as that
            # library's own error ("no compiled object yet"): the command was interrupted
            print(_INTERRUPTED, file=sys.stderr)
            return 130
        if traceback:
            import traceback as tb

            tb.print_exc()
        if isinstance(exc, ImageformError):
            msg = _first_line(exc)
        elif isinstance(exc, OSError):
            msg = _os_error(exc)
        elif isinstance(exc, MemoryError):
            msg = "not enough memory (use smaller inputs, --max-pixels, or imageform chunked)"
        else:
            msg = f"unexpected {type(exc).__name__}: {_first_line(exc)}"
            if not traceback:
                msg += " (run again with --traceback to see where)"
        print(f"imageform: error: {msg}", file=sys.stderr)
        return 1
    finally:
        if old is not None:
            signal.signal(signal.SIGTERM, old)
        if old_int is not None:
            signal.signal(signal.SIGINT, old_int)
