"""Checking a scene against :data:`~imageform.simulate.schema.SCENE_SCHEMA`.

Errors name the key and, for a file or TOML string, the line it is on (``tomllib`` gives no
line numbers for values, so :func:`find_line` finds the key's line in the text).
"""

from __future__ import annotations

import difflib
import math
import re
from typing import Any

from imageform._validate import as_bool, as_int, as_real, as_reals, describe
from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.simulate.budget import (
    BYTES_PER_PIXEL,
    available_memory_bytes,
    estimate_memory_bytes,
    format_bytes,
)
from imageform.simulate.schema import (
    _POSE,
    _SUFFIX_SCALE,
    DEFAULT_LIGHT_TEMPERATURE_K,
    DISTORTION_COEFFICIENTS,
    MAX_VIEWS,
    OBJECT_TYPES,
    SCENE_SCHEMA,
    UNITS,
    Field,
)

__all__ = ["find_line", "validate_scene_dict"]


# ---- locating keys in the TOML text ---------------------------------------------------------
_HEADER = re.compile(r"^\s*(\[\[?)\s*([^\]]+?)\s*\]\]?\s*(#.*)?$")
_KEY = re.compile(r"^\s*([A-Za-z0-9_\-\.\"' ]+?)\s*=")


def _split_key(k: str) -> tuple[str, ...]:
    return tuple(p.strip().strip("\"'") for p in k.split("."))


def find_line(text: str | None, path: tuple[Any, ...]) -> int | None:
    r"""Return the 1-based line of the key (or table) at ``path`` in TOML ``text``.

    ``path`` is e.g. ``("objects", 1, "squares")``; None if not found. Array-of-tables entries count
    from 0.

    Examples
    --------
    >>> find_line("a = 1\n[camera]\nf = 2\n", ("camera", "f"))
    3
    """
    if text is not None and not isinstance(text, str):
        raise TypeError(f"expected text as a TOML string or None, got {type(text).__name__}")
    if not isinstance(path, tuple | list):
        raise TypeError(f"expected path as a tuple of keys, got {type(path).__name__}")
    if not text:
        return None
    section: tuple[Any, ...] = ()
    counts: dict[tuple[str, ...], int] = {}
    for no, line in enumerate(text.splitlines(), 1):
        m = _HEADER.match(line)
        if m and "=" not in line.split("]")[0]:
            names = _split_key(m.group(2))
            if m.group(1) == "[[":
                counts[names] = counts.get(names, -1) + 1
                section = (*names, counts[names])
            else:
                section = names
            if section == tuple(path):
                return no
            continue
        k = _KEY.match(line)
        if k:
            full = (*section, *_split_key(k.group(1)))
            if full == tuple(path) or full[: len(path)] == tuple(path):
                return no
    return None


# ---- value checks ------------------------------------------------------------------------
#: The largest length a scene may hold (m): a scene is a room, not an astronomical
#: distance; beyond this the ray-quad intersections lose every significant digit.
MAX_LENGTH_M = 1e6

#: The most characters of a scene value (or key) an error message repeats.
_ECHO = 60


def _show_text(text: str) -> str:
    """``text`` cut to :data:`_ECHO` characters (a scene file's content is never dumped)."""
    return text if len(text) <= _ECHO else text[: _ECHO - 3] + "..."


def _show(v: object) -> str:
    """Return a scene value for an error message: its repr, cut to :data:`_ECHO` characters."""
    return _show_text(repr(v))


def _names(keys: Any, width: int = 76) -> str:
    """Return the valid keys, as many as fit ``width`` characters, then how many more (one line)."""
    keys = list(keys)
    shown: list[str] = []
    for k in keys:
        if len(", ".join([*shown, k])) > width:
            return f"{', '.join(shown)}, ... ({len(keys) - len(shown)} more; docs/simulate.md)"
        shown.append(k)
    return ", ".join(shown)


def one_line(text: str, limit: int = 200) -> str:
    """Return ``text``'s first line cut to ``limit`` characters.

    An error message never dumps a scene value or a file's content.
    """
    first = text.strip().splitlines()[0] if text.strip() else ""
    return first if len(first) <= limit else first[: limit - 3] + "..."


class _Ctx:
    def __init__(self, text: str | None, origin: str) -> None:
        self.text = text
        self.origin = origin

    def where(self, path: tuple[Any, ...]) -> str:
        dotted = ".".join(f"[{p}]" if isinstance(p, int) else str(p) for p in path)
        dotted = _show_text(dotted.replace(".[", "["))
        line = find_line(self.text, path)
        if line:
            return f"{dotted} ({self.origin}, line {line})"
        if self.text:  # a key the file leaves out: its default; point at its section
            section = find_line(self.text, path[:1]) if len(path) > 1 else None
            at = f", [{path[0]}] at line {section}" if section else ""
            return f"{dotted} ({self.origin}{at}, default)"
        return f"{dotted} ({self.origin})"

    def fail(self, path: tuple[Any, ...], msg: str, unknown: bool = False) -> None:
        cls = UnknownOptionError if unknown else InvalidInputError
        raise cls(one_line(f"scene key {self.where(path)}: {msg}"))


def _quantity(v: str, f: Field, key: str, path: tuple[Any, ...], ctx: _Ctx) -> float:
    m = re.fullmatch(r"\s*([-+0-9.eE]+)\s*([A-Za-zµ]+)\s*", v)
    if m is None or f.dimension is None:
        ctx.fail(path, f"expected a number, got {_show(v)}")
        raise AssertionError  # unreachable (for type checkers)
    num, unit = float(m.group(1)), m.group(2)
    table = UNITS[f.dimension]
    if unit not in table:
        kinds = [d for d, t in UNITS.items() if unit in t]
        got = f" (a {kinds[0]})" if kinds else ""
        ctx.fail(
            path, f"expected a {f.dimension} in one of {sorted(table)}, got unit {_show(unit)}{got}"
        )
    suffix = next((s for s in _SUFFIX_SCALE if key.endswith(s)), "")
    return num * table[unit] * _SUFFIX_SCALE.get(suffix, 1.0)


def _number(v: Any, f: Field, key: str, path: tuple[Any, ...], ctx: _Ctx) -> float:
    if isinstance(v, bool):
        ctx.fail(path, f"expected a number, got {_show(v)}")
    x = _quantity(v, f, key, path, ctx) if isinstance(v, str) else v
    if not isinstance(x, int | float) or not math.isfinite(x):
        ctx.fail(path, f"expected a finite number, got {_show(v)}")
    if f.dimension == "length" and abs(x) > MAX_LENGTH_M:
        ctx.fail(path, f"expected a length within ±{MAX_LENGTH_M:g} m, got {x:g} m")
    return float(x)


def _bounds(x: float, f: Field, path: tuple[Any, ...], ctx: _Ctx) -> None:
    if f.positive and x <= 0:
        ctx.fail(path, f"expected a value > 0, got {x:g}")
    if f.minimum is not None and x < f.minimum:
        ctx.fail(path, f"expected a value >= {f.minimum:g}, got {x:g}")
    if f.maximum is not None and x > f.maximum:
        ctx.fail(path, f"expected a value <= {f.maximum:g}, got {x:g}")


def _check_value(v: Any, f: Field, key: str, path: tuple[Any, ...], ctx: _Ctx) -> Any:
    from imageform.spectral import COLORCHECKER_PATCHES

    kind = f.kind
    if kind == "str":
        if not isinstance(v, str):
            ctx.fail(path, f"expected a string, got {_show(v)}")
        if f.choices:
            key_ = v.strip().lower().replace("-", "_")
            valid = {c.lower(): c for c in f.choices}
            if key_ not in valid and v not in f.choices:
                ctx.fail(path, f"unknown value {_show(v)}; valid: {', '.join(f.choices)}", True)
            return valid.get(key_, v)
        return v
    if kind == "bool":
        if not isinstance(v, bool):
            ctx.fail(path, f"expected true or false, got {_show(v)}")
        return v
    if kind == "int":
        if isinstance(v, bool) or not isinstance(v, int):
            ctx.fail(path, f"expected an integer, got {_show(v)}")
        _bounds(float(v), f, path, ctx)
        return int(v)
    if kind == "float_or_auto" and isinstance(v, str) and v.strip().lower() == "auto":
        return "auto"
    if kind in ("float", "float_or_auto"):
        x = _number(v, f, key, path, ctx)
        _bounds(x, f, path, ctx)
        return x
    if kind == "reflectance":
        if isinstance(v, str):
            if v not in COLORCHECKER_PATCHES:
                near = difflib.get_close_matches(v, COLORCHECKER_PATCHES, 3)
                ctx.fail(path, f"unknown ColorChecker patch {_show(v)}; close: {near}", True)
            return v
        x = _number(v, f, key, path, ctx)
        if not 0.0 <= x <= 1.0:
            ctx.fail(path, f"expected a reflectance in [0, 1], got {x:g}")
        return x
    n = {"vec2": 2, "vec3": 3, "ivec2": 2, "mat3": 3}[kind]
    if not isinstance(v, list) or len(v) != n:
        ctx.fail(
            path,
            f"expected a list of {n} {'rows' if kind == 'mat3' else 'numbers'}, got {_show(v)}",
        )
    if kind == "mat3":
        rows = []
        for r in v:
            if not isinstance(r, list) or len(r) != 3:
                ctx.fail(path, f"expected 3 rows of 3 numbers, got {_show(v)}")
            rows.append(tuple(_number(x, f, key, path, ctx) for x in r))
        return tuple(rows)
    if kind == "ivec2":
        if not all(isinstance(x, int) and not isinstance(x, bool) and x >= 2 for x in v):
            ctx.fail(path, f"expected two integers >= 2, got {_show(v)}")
        return tuple(int(x) for x in v)
    out = tuple(_number(x, f, key, path, ctx) for x in v)
    for x in out:
        _bounds(x, f, path, ctx)
    return out


def _table(data: Any, schema: dict[str, Any], path: tuple[Any, ...], ctx: _Ctx) -> dict[str, Any]:
    if not isinstance(data, dict):
        ctx.fail(path, f"expected a table, got {data!r:.60}")
    out: dict[str, Any] = {}
    for key, value in data.items():
        if key not in schema:
            near = difflib.get_close_matches(key, list(schema), 1)
            hint = f"; did you mean {near[0]!r}?" if near else ""
            unit_hint = ""
            stem = re.sub(r"_(m|mm|um|cm|s|ms|us|deg|rad)$", "", key)
            same = [k for k in schema if re.sub(r"_(m|mm|um|s|deg|K|lux|px|e)$", "", k) == stem]
            if same and key not in same:
                unit_hint = f" (wrong unit? this key is {same[0]!r})"
                if near and near[0] == same[0]:
                    hint = ""  # said once: the message stays within one 200-character line
            ctx.fail((*path, key), f"unknown key{unit_hint}{hint}; valid: {_names(schema)}", True)
        f = schema[key]
        if isinstance(f, dict):
            out[key] = _table(value, f, (*path, key), ctx)
        else:
            out[key] = _check_value(value, f, key, (*path, key), ctx)
    for key, f in schema.items():
        if key in out:
            continue
        if isinstance(f, dict):
            out[key] = _table({}, f, (*path, key), ctx)
        else:
            out[key] = f.default
    return out


#: Renamed keys of ``[[objects]]`` (issue 30: one spelling, American ``center``): old -> new.
#: A scene with an old key still loads, with one warning per old key naming its new one.
_RENAMED_OBJECT_KEYS = {"centre_m": "center_m"}


def _new_keys(
    obj: dict[str, Any],
    path: tuple[Any, ...],
    ctx: _Ctx,
    seen: dict[str, list[tuple[Any, ...]]],
) -> dict[str, Any]:
    """Return ``obj`` with its old keys (:data:`_RENAMED_OBJECT_KEYS`) renamed (noted in seen)."""
    if not any(old in obj for old in _RENAMED_OBJECT_KEYS):
        return obj
    out = dict(obj)
    for old, new in _RENAMED_OBJECT_KEYS.items():
        if old not in out:
            continue
        if new in out:
            ctx.fail((*path, old), f"give {new} or its deprecated spelling {old}, not both")
        seen.setdefault(old, []).append((*path, old))
        out = {new if k == old else k: v for k, v in out.items()}
    return out


def _warn_old_keys(seen: dict[str, list[tuple[Any, ...]]], ctx: _Ctx) -> None:
    """One warning per old key a scene uses (:func:`_new_keys`), at its first place."""
    import warnings

    from imageform._deprecate import REMOVED_IN
    from imageform.errors import ImageformWarning

    for old, paths in seen.items():
        many = f" ({len(paths)} objects use {old})" if len(paths) > 1 else ""
        warnings.warn(
            f"scene key {ctx.where(paths[0])} is deprecated and will be removed in "
            f"imageform {REMOVED_IN}; write {_RENAMED_OBJECT_KEYS[old]}{many}",
            ImageformWarning,
            stacklevel=5,  # the caller of load_scene
        )


def validate_scene_dict(
    data: dict[str, Any], text: str | None = None, origin: str = "scene"
) -> dict[str, Any]:
    """Check a parsed scene against :data:`SCENE_SCHEMA`; return it with every default filled.

    Raises
    ------
    UnknownOptionError
        An unknown key or choice (with the valid ones and the line in ``text``).
    InvalidInputError
        A value of the wrong type, range or unit.

    Examples
    --------
    >>> cfg = validate_scene_dict({"render": {"width": 320, "height": 180}})
    >>> cfg["render"]["supersampling"], cfg["lens"]["f_number"]
    (2, 8.0)
    """
    ctx = _Ctx(text, origin)
    if not isinstance(data, dict):
        raise InvalidInputError(f"expected data as a scene table (dict), got {type(data).__name__}")
    sections = {k: v for k, v in SCENE_SCHEMA.items() if k not in ("", "objects", "views")}
    top = {**SCENE_SCHEMA[""], **sections, "views": None, "objects": None}
    out: dict[str, Any] = {}
    for key in data:
        if key not in top:
            near = difflib.get_close_matches(key, list(top), 1)
            hint = f"; did you mean {near[0]!r}?" if near else ""
            ctx.fail((key,), f"unknown key{hint}; valid: {_names(top)}", True)
    for key, f in SCENE_SCHEMA[""].items():
        out[key] = _check_value(data[key], f, key, (key,), ctx) if key in data else f.default
    for sec, schema in sections.items():
        out[sec] = _table(data.get(sec, {}), schema, (sec,), ctx)
    objs = data.get("objects", [])
    if not isinstance(objs, list):
        ctx.fail(("objects",), "expected an array of tables ([[objects]])")
    out["objects"] = []
    old_keys: dict[str, list[tuple[Any, ...]]] = {}
    for i, obj in enumerate(objs):
        if not isinstance(obj, dict) or "type" not in obj:
            ctx.fail(("objects", i), f"expected a table with a 'type' ({', '.join(OBJECT_TYPES)})")
        obj = _new_keys(obj, ("objects", i), ctx, old_keys)
        t = _check_value(obj["type"], _POSE["type"], "type", ("objects", i, "type"), ctx)
        checked = _table(obj, SCENE_SCHEMA["objects"][t], ("objects", i), ctx)
        if checked["center_m"] is None:
            ctx.fail(("objects", i), "missing key 'center_m' (the object's position, m)")
        if t == "image" and checked["path"] is None:
            ctx.fail(("objects", i), "missing key 'path' (the image file)")
        if not checked["name"]:
            checked["name"] = f"{t}{i}"
        out["objects"].append(checked)
    _warn_old_keys(old_keys, ctx)
    views = data.get("views", [])
    if not isinstance(views, list):
        ctx.fail(("views",), "expected an array of tables ([[views]])")
    out["views"] = []
    for i, view in enumerate(views):
        if not isinstance(view, dict):
            ctx.fail(("views", i), "expected a table with eye_m (and target_m, up)")
        checked = _table(view, SCENE_SCHEMA["views"], ("views", i), ctx)
        if checked["eye_m"] is None:
            ctx.fail(("views", i), "missing key 'eye_m' (the view's camera centre, m)")
        out["views"].append(checked)
    if len(out["views"]) > MAX_VIEWS:
        ctx.fail(("views",), f"expected at most {MAX_VIEWS} views, got {len(out['views'])}")
    _check_illuminant(out["illuminant"], ctx)
    cam = out["camera"]
    if (cam["R"] is None) != (cam["t_m"] is None):
        ctx.fail(("camera", "R" if cam["R"] is not None else "t_m"), "give both R and t_m")
    _check_distortion(cam["distortion"], ctx)
    _check_memory(out["render"], ctx)
    return out


def _check_illuminant(ill: dict[str, Any], ctx: _Ctx) -> None:
    """Check that ``file`` has a path and ``temperature_K`` is for blackbody and daylight only.

    A CIE illuminant's or a file's temperature is not a setting: the report computes the light's CCT
    from its spectrum.
    """
    if ill["type"] == "cie" and len(ill["name"]) > 40:  # no CIE name is that long
        ctx.fail(("illuminant", "name"), f"unknown CIE illuminant {_show(ill['name'])}")
    if ill["type"] == "file" and ill["file"] is None:
        ctx.fail(("illuminant", "type"), "type 'file' needs the key 'file' (a CSV path)")
    if ill["type"] in ("blackbody", "daylight"):
        if ill["temperature_K"] is None:
            ill["temperature_K"] = DEFAULT_LIGHT_TEMPERATURE_K
    elif ill["temperature_K"] is not None:
        ctx.fail(
            ("illuminant", "temperature_K"),
            f"applies to type 'blackbody' or 'daylight', not {ill['type']!r} "
            f"(a {ill['type']} light's spectrum is given; remove the key)",
        )


def _check_distortion(dist: dict[str, Any], ctx: _Ctx) -> None:
    """Check that a coefficient the chosen model does not have is absent or 0."""
    model = dist["model"]
    has = DISTORTION_COEFFICIENTS[model]
    for key, value in dist.items():
        if key != "model" and key not in has and value != 0:
            ctx.fail(
                ("camera", "distortion", key),
                f"the {model} model has no {key}; its coefficients: {', '.join(has)}",
            )


def _check_memory(render: dict[str, Any], ctx: _Ctx) -> None:
    """Refuse an image that cannot fit in the memory available (before anything is made)."""
    w, h = int(render["width"]), int(render["height"])
    need = estimate_memory_bytes(w, h)
    have = available_memory_bytes()
    if have is not None and need > have:
        ctx.fail(
            ("render", "width"),
            f"a {w}x{h} image needs about {format_bytes(need)} of memory ({BYTES_PER_PIXEL} "
            f"bytes/pixel), more than the {format_bytes(have)} this machine has; reduce width "
            "and height",
        )


# ---- the fields of the typed dataclasses, checked against the schema --------------------------


def check_field(value: Any, spec: Any, name: str) -> Any:
    """Check a dataclass field's value against its schema entry ``spec``.

    ``spec`` is a :class:`imageform.simulate.schema.Field`: kind, choices and bounds, in the units
    the typed config holds (already converted). ``None`` is accepted only for an optional key
    (default ``None``).
    """
    if value is None:
        if spec.default is None:
            return None
        raise TypeError(f"expected {name} as a {spec.kind} value, got None")
    kind = spec.kind
    if kind == "str":
        if not isinstance(value, str):
            raise TypeError(f"expected {name} as a string, got {describe(value)}")
        if spec.choices:
            key = value.strip().lower().replace("-", "_")
            valid = {c.lower(): c for c in spec.choices}
            if key in valid:
                return valid[key]
            if value in spec.choices:
                return value
            raise UnknownOptionError(
                f"unknown {name} {describe(value, 30)}; valid: {', '.join(spec.choices)}"[:200]
            )
        return value
    if kind == "bool":
        return as_bool(value, name)
    if kind == "int":
        lo = spec.minimum if spec.minimum is not None else (1 if spec.positive else None)
        hi = spec.maximum
        return as_int(
            value,
            name,
            minimum=None if lo is None else math.ceil(lo),
            maximum=None if hi is None else math.floor(hi),
        )
    if kind == "float_or_auto" and isinstance(value, str):
        if value.strip().lower() == "auto":
            return "auto"
        raise InvalidInputError(f"expected {name} as a number or 'auto', got {describe(value)}")
    if kind in ("float", "float_or_auto"):
        return _bounded(as_real(value, name), spec, name)
    if kind == "reflectance":
        if isinstance(value, str):
            from imageform.spectral import COLORCHECKER_PATCHES

            if value not in COLORCHECKER_PATCHES:
                raise UnknownOptionError(
                    f"unknown ColorChecker patch {describe(value, 30)} for {name}"
                )
            return value
        return as_real(value, name, minimum=0.0, maximum=1.0)
    if kind == "mat3":
        if isinstance(value, str | bytes) or not hasattr(value, "__iter__"):
            raise InvalidInputError(
                f"expected {name} as 3 rows of 3 numbers, got {describe(value)}"
            )
        rows = list(value)
        if len(rows) != 3:
            raise InvalidInputError(
                f"expected {name} as 3 rows of 3 numbers, got {describe(value)}"
            )
        return tuple(as_reals(r, f"{name}[{i}]", 3) for i, r in enumerate(rows))
    n = {"vec2": 2, "vec3": 3, "ivec2": 2}.get(kind)
    if n is None:  # pragma: no cover - a schema kind this module does not know
        return value
    if kind == "ivec2":
        if isinstance(value, str | bytes) or not hasattr(value, "__iter__"):
            raise InvalidInputError(f"expected {name} as 2 integers, got {describe(value)}")
        items = list(value)
        if len(items) != 2:
            raise InvalidInputError(f"expected {name} as 2 integers, got {describe(value)}")
        return tuple(as_int(v, f"{name}[{i}]", minimum=2) for i, v in enumerate(items))
    out = as_reals(value, name, n)
    return tuple(_bounded(x, spec, f"{name}[{i}]") for i, x in enumerate(out))


def _bounded(x: float, spec: Any, name: str) -> float:
    if spec.positive and x <= 0:
        raise InvalidInputError(f"expected {name} > 0, got {x:g}")
    if spec.minimum is not None and x < spec.minimum:
        raise InvalidInputError(f"expected {name} >= {spec.minimum:g}, got {x:g}")
    if spec.maximum is not None and x > spec.maximum:
        raise InvalidInputError(f"expected {name} <= {spec.maximum:g}, got {x:g}")
    if spec.dimension == "length" and abs(x) > MAX_LENGTH_M:
        raise InvalidInputError(f"expected {name} within ±{MAX_LENGTH_M:g}, got {x:g}")
    return x


def check_section(obj: Any, schema: dict[str, Any], section: str) -> None:
    """Check (and normalise, on a frozen dataclass) each field of ``obj`` that ``schema`` describes.

    ``schema`` is a section of :data:`~imageform.simulate.schema.SCENE_SCHEMA`; the error names
    ``section.field``.
    """
    import dataclasses

    for f in dataclasses.fields(obj):
        spec = schema.get(f.name)
        if isinstance(spec, Field):
            name = f"{section}.{f.name}" if section else f.name
            object.__setattr__(obj, f.name, check_field(getattr(obj, f.name), spec, name))
