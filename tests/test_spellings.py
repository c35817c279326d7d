"""One spelling per concept in the public signatures (issue 30), so that off-spellings cannot
come back.

The library's spellings: ``rng`` (a seed, a Generator or None; SPEC 7) for random numbers,
``tol`` for a stopping tolerance, ``max_trials`` for a RANSAC budget, ``bit_depth`` for bits
per sample (the flag ``--bit-depth``), and American ``center`` in names, option values and
scene-file keys (prose stays British). Every parameter, dataclass field and method parameter
of every public name is scanned; the allow-list below names each exception with its reason.
Renamed parameters keep a deprecation shim (:mod:`imageform._deprecate`), which hides the old
name from the signature.

One rule, not an exception (docs/design.md, Conventions): the command line's random seed is
``--seed``. A flag can only take an integer, while Python's ``rng=`` takes a seed, a
Generator or None; so the ``seed`` field of a workflow's options dataclass (whose field is its
flag) is an integer passed on as ``rng=``, and the scan skips it (:func:`_by_rule`;
:func:`test_the_command_line_seed_rule` checks what the rule promises).
"""

from __future__ import annotations

import dataclasses
import inspect
import re

import pytest

from tests.regen_api_snapshot import public_modules

#: Off-spelling -> the library's spelling.
OFF_SPELLINGS: dict[str, str] = {
    r"seed": "rng",
    r"eps|epsilon": "tol",
    r"max_hypotheses|n_hypotheses|num_trials|n_trials|max_ransac_iter": "max_trials",
    r"bits|nbits|n_bits|bitdepth": "bit_depth",
    r".*centre.*": "center",
}
_OFF = re.compile(f"^(?:{'|'.join(OFF_SPELLINGS)})$")

#: ``module.qualname: parameter`` -> why it keeps its spelling today.
ALLOWED: dict[str, str] = {
    # already deprecated aliases, kept in the signature by random_source()
    "imageform.simulate.pipeline.simulate: seed": "deprecated alias of rng (random_source)",
    "imageform.simulate.truth.detect_vanishing: seed": "deprecated alias of rng (random_source)",
    # not a random seed: the lattice node a breadth-first walk starts from
    "imageform.geometry.checkerboard_grid.label_lattice: seed": "a seed node, not randomness",
    "imageform.geometry.checkerboard_grid.lattice_rectangle: seed": "a seed node, not randomness",
}


def _names(obj: object) -> list[str]:
    try:
        return list(inspect.signature(obj).parameters)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return []


def _spelled() -> dict[str, set[str]]:
    """``module.qualname -> parameter and field names`` of every public callable."""
    out: dict[str, set[str]] = {}
    for mod in public_modules():
        for name in mod.__all__:
            obj = getattr(mod, name)
            if not callable(obj):
                continue
            qual = (
                f"{getattr(obj, '__module__', mod.__name__)}.{getattr(obj, '__qualname__', name)}"
            )
            out.setdefault(qual, set()).update(_names(obj))
            if dataclasses.is_dataclass(obj):
                out[qual].update(f.name for f in dataclasses.fields(obj))
            if inspect.isclass(obj):
                out[qual].update(getattr(obj, "_fields", ()))  # NamedTuple fields
                for attr, value in vars(obj).items():
                    fn = value.__func__ if isinstance(value, classmethod | staticmethod) else value
                    if not attr.startswith("_") and inspect.isfunction(fn):
                        out.setdefault(f"{qual}.{attr}", set()).update(_names(fn))
    return out


def _by_rule(entry: str) -> bool:
    """The command line's seed: the ``seed`` field of a workflow's options (``--seed``)."""
    qual, _, name = entry.partition(": ")
    return name == "seed" and qual.startswith("imageform.workflows.") and qual.endswith("Options")


def _offenders() -> set[str]:
    found = {f"{q}: {p}" for q, params in _spelled().items() for p in params if _OFF.match(p)}
    return {e for e in found if not _by_rule(e)}


def test_no_off_spelling_in_public_signatures() -> None:
    new = sorted(_offenders() - set(ALLOWED))
    assert not new, (
        "off-spelling(s) in public signatures (use "
        + ", ".join(f"{v} for {k}" for k, v in OFF_SPELLINGS.items())
        + f"): {new}"
    )


def test_allow_list_has_no_stale_entries() -> None:
    """An exception that is gone (renamed, removed) leaves the allow-list too."""
    assert not sorted(set(ALLOWED) - _offenders())


def _seeded_workflows() -> list[str]:
    from imageform.workflows import WORKFLOWS

    return [n for n, w in WORKFLOWS.items() if "seed" in {f.name for f in w.options.fields()}]


@pytest.mark.parametrize("name", _seeded_workflows())
def test_the_command_line_seed_rule(name: str) -> None:
    """``seed`` of an options dataclass: the flag ``--seed``, an integer, help naming ``rng=``."""
    import typing

    from imageform.workflows import WORKFLOWS, flag_of

    wf = WORKFLOWS[name]
    f = next(f for f in wf.options.fields() if f.name == "seed")
    assert flag_of(f) == "--seed"
    assert typing.get_type_hints(wf.options)["seed"] is int
    assert "rng=" in f.metadata["help"], f.metadata["help"]
    assert "rng" not in {f.name for f in wf.options.fields()}  # one spelling on the command line
    assert _by_rule(f"{wf.options.__module__}.{wf.options.__qualname__}: seed")


def test_the_seed_rule_is_used() -> None:
    """The rule covers the workflows that take ``--seed`` (simulate, vanishing), nothing else."""
    assert {"simulate", "vanishing"} <= set(_seeded_workflows())
    assert not _by_rule("imageform.simulate.pipeline.simulate: seed")
    assert not _by_rule("imageform.workflows.simulate.SimulateOptions: bits")


@pytest.mark.parametrize("name", ["seed", "eps", "max_hypotheses", "bits", "centre", "centres_uv"])
def test_the_pattern_catches(name: str) -> None:
    assert _OFF.match(name)


@pytest.mark.parametrize("name", ["rng", "tol", "max_trials", "bit_depth", "center", "centers"])
def test_the_pattern_passes(name: str) -> None:
    assert not _OFF.match(name)
