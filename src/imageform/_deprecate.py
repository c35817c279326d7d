"""Deprecation shims: a renamed public name keeps working for one release, with a warning.

The 1.0 API pass renamed parameters, functions, methods and constants (CHANGELOG.md lists
every one, old -> new). Each old spelling keeps working until imageform :data:`REMOVED_IN`
through one of these shims, which emit a :class:`DeprecationWarning` naming the
replacement:

- :func:`parameters` wraps a function whose parameters were renamed or made keyword-only;
  the wrapped function reports its *new* signature (``inspect.signature`` follows
  ``__wrapped__``);
- :func:`renamed` makes the old name of a function or method, :func:`renamed_property` the
  old name of a property or dataclass field;
- :func:`module_getattr` builds a module ``__getattr__`` for renamed module constants.

Every object a shim creates carries ``__deprecated__`` (the attribute of PEP 702), so the
API snapshot (``tests/api_snapshot.txt``) marks it. Internal module: imageform's packages
share it, users do not call it.
"""

from __future__ import annotations

import functools
import inspect
import warnings
from collections.abc import Callable, Mapping, Sequence
from typing import Any, TypeVar, cast

__all__ = [
    "REMOVED_IN",
    "Lazy",
    "module_getattr",
    "parameters",
    "renamed",
    "renamed_fields",
    "renamed_property",
    "warn",
]

#: The release that removes the old names deprecated by the 1.0 API pass.
REMOVED_IN = "0.3.0"

F = TypeVar("F", bound=Callable[..., Any])
T = TypeVar("T", bound=type)

_POSITIONAL = (inspect.Parameter.POSITIONAL_ONLY, inspect.Parameter.POSITIONAL_OR_KEYWORD)


def warn(what: str, instead: str, *, stacklevel: int = 3) -> None:
    """Warn that ``what`` is deprecated; ``instead`` says what to write now.

    ``stacklevel=3`` points at the caller of the shim that calls this function.
    """
    warnings.warn(
        f"{what} is deprecated and will be removed in imageform {REMOVED_IN}; {instead}",
        DeprecationWarning,
        stacklevel=stacklevel,
    )


def _public_name(fn: Callable[..., Any]) -> str:
    module = getattr(fn, "__module__", "") or ""
    parts = module.split(".")
    # imageform.optics.thin_lens.thin_lens -> imageform.optics.thin_lens (the package path)
    if len(parts) > 2 and parts[0] == "imageform":
        module = ".".join(parts[:2])
    return f"{module}.{fn.__qualname__}"


def parameters(
    *,
    renamed: Mapping[str, str] | None = None,
    positional: Sequence[str] = (),
    name: str | None = None,
) -> Callable[[F], F]:
    """Accept the old parameter names and the old positional calls, with a warning (a decorator).

    Parameters
    ----------
    renamed : mapping old name -> new name
        A call with ``old=value`` is passed on as ``new=value``.
    positional : sequence of str
        Keyword-only parameters (new names) that used to be positional, in their old order
        after the parameters that are still positional. A call with extra positional
        arguments passes them on by these names.
    name : str, optional
        The public name the warnings give (default: the function's own).

    Examples
    --------
    >>> @parameters(renamed={"centre": "center"}, positional=("center",))
    ... def f(x, *, center=0.0):
    ...     return x - center
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     f(3.0, 1.0), f(3.0, centre=2.0), f(3.0, center=0.5)
    (2.0, 1.0, 2.5)
    >>> [str(x.message).split(" is ")[0] for x in w]
    ['passing center to imageform._deprecate.f() by position', 'imageform._deprecate.f(centre=...)']
    """
    renames = dict(renamed or {})
    moved = tuple(positional)

    def deco(fn: F) -> F:
        params = inspect.signature(fn).parameters
        for new in (*renames.values(), *moved):
            if new not in params:
                raise TypeError(f"{fn.__qualname__} has no parameter {new!r} to shim")
        for kw in moved:
            if params[kw].kind is not inspect.Parameter.KEYWORD_ONLY:
                raise TypeError(f"{fn.__qualname__}: {kw!r} is not keyword-only")
        n_positional = sum(p.kind in _POSITIONAL for p in params.values())
        shown = name or _public_name(fn)

        @functools.wraps(fn)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            if renames:
                for old, new in renames.items():
                    if old in kwargs:
                        if new in kwargs:
                            raise TypeError(f"{shown}() got both {old}= (deprecated) and {new}=")
                        warn(f"{shown}({old}=...)", f"use {new}= instead")
                        kwargs[new] = kwargs.pop(old)
            if len(args) > n_positional and moved:
                extra = args[n_positional:]
                if len(extra) > len(moved):
                    raise TypeError(
                        f"{shown}() takes at most {n_positional + len(moved)} positional "
                        f"arguments ({len(args)} given)"
                    )
                names = moved[: len(extra)]
                for key, value in zip(names, extra, strict=True):
                    if key in kwargs:
                        raise TypeError(f"{shown}() got multiple values for argument {key!r}")
                    kwargs[key] = value
                args = args[:n_positional]
                warn(
                    f"passing {', '.join(names)} to {shown}() by position",
                    f"pass {'it' if len(names) == 1 else 'them'} by keyword "
                    f"({', '.join(k + '=' for k in names)})",
                )
            return fn(*args, **kwargs)

        return cast(F, wrapper)

    return deco


def renamed(new: F, old_name: str, *, instead: str | None = None) -> F:
    """Make the old name of a function or method: it calls ``new`` after a warning.

    ``old_name`` is the dotted public name (``"imageform.sensor.SensorModel.normalise"``);
    ``instead`` overrides the advice (default: use the new function's public name).
    """
    advice = instead or f"use {_public_name(new)} instead"

    @functools.wraps(new)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        warn(old_name, advice)
        return new(*args, **kwargs)

    short = old_name.rsplit(".", 1)[-1]
    owner = new.__qualname__.rpartition(".")[0]  # the class of a method, "" for a function
    wrapper.__name__ = short
    wrapper.__qualname__ = f"{owner}.{short}" if owner else short
    wrapper.__doc__ = f"Deprecated alias: {advice}."
    wrapper.__deprecated__ = advice  # type: ignore[attr-defined]
    return cast(F, wrapper)


def renamed_property(new: str, old_name: str) -> property:
    """Make a read-only property under the old name of the attribute ``new``, with a warning."""
    advice = f"use .{new} instead"

    def getter(self: Any) -> Any:
        warn(old_name, advice)
        return getattr(self, new)

    getter.__deprecated__ = advice  # type: ignore[attr-defined]
    prop = property(getter, doc=f"Deprecated alias of :attr:`{new}`: {advice}.")
    return prop


def renamed_fields(renames: Mapping[str, str]) -> Callable[[T], T]:
    """Keep the old names of a dataclass's (or NamedTuple's) fields (a class decorator).

    Put it above ``@dataclass``.

    Each old name becomes a read-only property of the new field (:func:`renamed_property`)
    and a keyword the constructor still takes (:func:`parameters`), both with a warning.
    The class's ``__renamed_fields__`` maps the old names to the new ones (with its bases').

    Examples
    --------
    >>> from dataclasses import dataclass
    >>> @renamed_fields({"centres": "centers"})
    ... @dataclass(frozen=True)
    ... class Chart:
    ...     centers: tuple[float, float]
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     Chart(centres=(1.0, 2.0)).centres
    (1.0, 2.0)
    >>> len(w)
    2
    """

    def deco(cls: T) -> T:
        owner = _public_name(cast(Callable[..., Any], cls))
        for old, new in renames.items():
            setattr(cls, old, renamed_property(new, f"{owner}.{old}"))
        # old -> new, read by whoever accepts the old names elsewhere (the command line's
        # hidden flags of an options dataclass, imageform batch's option mappings)
        merged = {**getattr(cls, "__renamed_fields__", {}), **renames}
        cls.__renamed_fields__ = merged  # type: ignore[attr-defined]
        # a NamedTuple's constructor is __new__, a dataclass's __init__
        ctor = "__new__" if issubclass(cls, tuple) else "__init__"
        shim = parameters(renamed=renames, name=owner)
        setattr(cls, ctor, shim(getattr(cls, ctor)))
        return cls

    return deco


class Lazy:
    """A constant of :func:`module_getattr` read on access: ``Lazy("pkg.module", "NAME")``."""

    def __init__(self, module: str, name: str) -> None:
        self.module, self.name = module, name

    def load(self) -> Any:
        """Import the module and return the constant."""
        import importlib

        return getattr(importlib.import_module(self.module), self.name)


def module_getattr(module: str, renames: Mapping[str, tuple[str, Any]]) -> Callable[[str], Any]:
    """Make a module ``__getattr__`` serving renamed constants: ``{old: (new name, value)}``.

    A new name with a dot is a full dotted name (the constant moved to another module); a
    :class:`Lazy` value is loaded on access (a constant of a module that this one cannot
    import at load time without a cycle).
    """

    def __getattr__(name: str) -> Any:
        if name in renames:
            new, value = renames[name]
            warn(f"{module}.{name}", f"use {new if '.' in new else f'{module}.{new}'} instead")
            return value.load() if isinstance(value, Lazy) else value
        raise AttributeError(f"module {module!r} has no attribute {name!r}")

    __getattr__.__deprecated_names__ = {old: new for old, (new, _) in renames.items()}  # type: ignore[attr-defined]
    return __getattr__
