"""Issue 16: every workflow's options are checked when they are made (API, command line and
``imageform batch`` alike), in one line naming the option; the registry and ``execute`` name
what they refuse."""

from __future__ import annotations

import dataclasses
import math
import types
import typing
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from imageform.errors import ImageformError, InvalidInputError, UnknownOptionError
from imageform.workflows import WORKFLOWS, execute, get_workflow, normalize_choice
from imageform.workflows._spec import Options, choice_names, option_label

_REQUIRED = {  # valid values of the options without a default
    "lens": {"focal": "50mm", "f_number": 2.8, "focus": "2m"},
    "undistort": {"camera": "camera.toml"},
    "stain-normalize": {"target": "target.png"},
    "harmonize": {"correction": "c.json"},
    "cvd": {"deficiency": "protan"},
    "calibrate": {"board": "9x6"},
    "stereo-calibrate": {"board": "9x6"},
    "depth": {"camera": "stereo.toml"},
    "track": {"camera": "camera.toml", "board": "9x6", "square": "30mm"},
    "reconstruct": {"camera": "camera.toml"},
}


def _base(wf_name: str) -> dict[str, Any]:
    return dict(_REQUIRED.get(wf_name, {}))


def _bad_values(tp: Any) -> list[Any]:
    """Malformed values for a field of type ``tp``."""
    origin_args = typing.get_args(tp)
    optional = type(None) in origin_args
    core = [a for a in origin_args if a is not type(None)] if optional else [tp]
    kind = core[0] if len(core) == 1 else None
    bad: list[Any] = [object()]
    if not optional and kind is not None:
        bad.append(None)
    if kind is bool:
        bad += ["yes", 0]
    elif kind is int:
        bad += [2.5, "3", True, 10**30, math.nan]
    elif kind is float:
        bad += [math.nan, math.inf, "3", 1 + 1j]
    elif kind is str or typing.get_origin(kind) is typing.Literal:
        bad += [3, ["a", "b"]]
    elif kind is Path:
        bad += [0, ""]
    return bad


def _cases() -> list[tuple[str, str, Any]]:
    out = []
    for name, wf in WORKFLOWS.items():
        hints = typing.get_type_hints(wf.options)
        for f in dataclasses.fields(wf.options):
            for i, v in enumerate(_bad_values(hints[f.name])):
                out.append(pytest.param(name, f.name, v, id=f"{name}-{f.name}-{i}"))
    return out


@pytest.mark.parametrize(("wf_name", "field", "value"), _cases())
def test_each_option_refused_in_one_line_naming_it(wf_name: str, field: str, value: Any) -> None:
    wf = get_workflow(wf_name)
    kw = _base(wf_name)
    kw[field] = value
    with pytest.raises((ImageformError, TypeError)) as info:
        wf.make_options(**kw)
    msg = str(info.value)
    f = {x.name: x for x in dataclasses.fields(wf.options)}[field]
    assert "\n" not in msg and len(msg) <= 200, msg
    assert field.replace("_", "-") in msg or field in msg or option_label(f) in msg, msg


def test_numpy_scalars_and_0d_arrays_are_numbers() -> None:
    wb = get_workflow("white-balance").make_options(
        p=np.float32(3.0), sigma=np.int64(2), max_pixels=np.int64(1000), clip=np.True_
    )
    assert (wb.p, wb.sigma, wb.max_pixels, wb.clip) == (3.0, 2.0, 1000, True)
    assert type(wb.p) is float and type(wb.max_pixels) is int and type(wb.clip) is bool
    seg = get_workflow("segment").make_options(min_area=np.array(10))
    assert seg.min_area == 10 and type(seg.min_area) is int


def test_paths_become_paths_and_numbers_stay_lengths() -> None:
    opts = get_workflow("harmonize").make_options(correction="c.json")
    assert opts.correction == Path("c.json")
    lens = get_workflow("lens").make_options(focal=50, f_number=2, focus=2.0)
    assert lens.lengths() == pytest.approx((0.05, 2.0, 3e-5))


def test_option_label_names_flag_and_field() -> None:
    conv = {f.name: f for f in dataclasses.fields(get_workflow("convert").options)}
    assert option_label(conv["src"]) == "--from (src)"
    assert option_label(conv["code_bits"]) == "--code-bits"
    with pytest.raises(UnknownOptionError, match=r"--from \(src\)"):
        get_workflow("convert").make_options(src="nope")


@pytest.mark.parametrize("name", [None, 0, True, ["convert"], object(), "", "x" * 100_000])
def test_get_workflow_refuses_by_name(name: Any) -> None:
    with pytest.raises(UnknownOptionError) as info:
        get_workflow(name)
    msg = str(info.value)
    assert "name" in msg and "\n" not in msg and len(msg) <= 200, msg


def test_execute_names_workflow_out_and_inputs(tmp_path: Path) -> None:
    for bad in (None, 0, object()):
        with pytest.raises(InvalidInputError, match="workflow"):
            execute(bad)  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match=r"out \(-o/--out\)"):
        execute("white-balance", image=tmp_path / "a.png", out=0)  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="image"):
        execute("white-balance", image=None, out=tmp_path / "o.png")
    with pytest.raises(InvalidInputError, match="force"):
        execute("white-balance", image=tmp_path / "a.png", out=tmp_path / "o.png", force="no")


def test_choices_checked() -> None:
    assert normalize_choice("Gray-World", ("gray_world", "max_rgb"), "--method") == "gray_world"
    for bad in (None, 0, True, object(), "abc", "nomodule:X"):
        with pytest.raises(InvalidInputError, match="choices"):
            choice_names(bad)  # type: ignore[arg-type]
    with pytest.raises(UnknownOptionError, match="--method") as info:
        normalize_choice("x" * 10_000, ("a", "b"), "--method")
    assert len(str(info.value)) <= 200
    with pytest.raises(UnknownOptionError, match="--method"):
        normalize_choice(None, ("a", "b"), "--method")


def test_board_text_refused_in_one_line() -> None:
    from imageform.workflows.calibration import parse_board

    assert parse_board(" 9 x 6 ") == (9, 6)
    for bad in (None, 0, "", "9x", "9" * 10_000 + "x6", "1x6", ["9x6"]):
        with pytest.raises(InvalidInputError, match="--board") as info:
            parse_board(bad)  # type: ignore[arg-type]
        assert len(str(info.value)) <= 200


def test_options_base_has_no_unchecked_field_type() -> None:
    """Every field type the workflows declare is one the check knows (a new type would pass
    unchecked)."""
    known = {bool, int, float, str, Path}
    for wf in WORKFLOWS.values():
        assert issubclass(wf.options, Options)
        for name, tp in typing.get_type_hints(wf.options).items():
            args = [a for a in typing.get_args(tp) if a is not type(None)] or [tp]
            if typing.get_origin(tp) is typing.Literal:  # a choice's names: checked as text
                args = [str]
            args = [str if typing.get_origin(a) is typing.Literal else a for a in args]
            if typing.get_origin(tp) is tuple:
                args = [a for a in typing.get_args(tp) if a is not Ellipsis]
            assert set(args) <= known, (wf.name, name, tp)


@pytest.mark.parametrize("text", ["nan:5", "1e400:2", "x" * 1000, "1:2:3"])
def test_hsv_ranges_are_finite_pairs(text: str) -> None:
    with pytest.raises(InvalidInputError, match="--h") as info:
        get_workflow("segment").make_options(h=text)
    assert len(str(info.value)) <= 200


def test_choice_fields_are_typed_with_their_names() -> None:
    # issue 30: an option that takes one of a fixed set of names says so in its type
    # (Literal), and its choices are those names (choices=get_args(the Literal)); only the
    # options whose names live in a library registry ("module:NAME", imported on use so
    # that --help imports no NumPy) stay str
    for name, wf in WORKFLOWS.items():
        hints = typing.get_type_hints(wf.options)
        for f in dataclasses.fields(wf.options):
            choices = f.metadata.get("choices")
            tp = hints[f.name]
            core = [a for a in typing.get_args(tp) if a is not type(None)]
            if typing.get_origin(tp) in (typing.Union, types.UnionType) and len(core) == 1:
                tp = core[0]
            where = f"{name} {f.name}"
            if choices is None:
                assert typing.get_origin(tp) is not typing.Literal, where
            elif isinstance(choices, str):
                assert tp is str, where
            else:
                assert typing.get_origin(tp) is typing.Literal, where
                assert tuple(choices) == typing.get_args(tp), where
                assert f.default is None or f.default in choices, where
