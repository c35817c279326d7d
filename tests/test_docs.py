"""The docs' examples run, and the results they show are compared (issue 20).

Every page of docs/*.md is run top to bottom in ONE namespace: its ```python blocks are
executed (setup code: nothing they print is shown), its ```pycon blocks are doctests
(``>>>``/``...`` prompts, the expected output below) checked with the stdlib doctest
machinery, ``NORMALIZE_WHITESPACE | ELLIPSIS`` and a float-tolerant checker: a number
written with n decimals matches any value within 10**-n of it, so ``0.7354`` matches
0.73540000001 and ``[0.475 0.   ]`` matches what another BLAS prints. A value that comes from
another library (LibRaw's float32 white balance, say) may differ in its last digits between
that library's versions: its example states the tolerance in a comment on the ``>>>`` line,
``# ± 0.001 (LibRaw's float32 gains)``, and its floats then match within that (issue 25: a
LibRaw gain printed to 4 decimals, 4.0826, read 4.0823 with another rawpy, failing README's
test command on a fresh install).

Examples run in a temporary folder whose ``../shared`` links to the reference data, so the
docs' ``../shared/data/...`` paths work as from the repository root and files an example
writes land in the temporary folder, never in the repository.

``test_no_result_comments_in_python_blocks`` keeps the old style (a result written as a
comment after an expression, ``print(x)  # 0.735`` or ``# array([...])``, never checked)
from coming back: a shown result belongs in a ```pycon block.
"""

from __future__ import annotations

import ast
import doctest
import io
import re
import tokenize
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[1] / "docs"
PAGES = sorted(DOCS.glob("*.md"))
_BLOCK = re.compile(r"^[ \t]*```(python|pycon)[ \t]*\n(.*?)^[ \t]*```", re.DOTALL | re.MULTILINE)
_FLAGS = doctest.NORMALIZE_WHITESPACE | doctest.ELLIPSIS

# a float as printed by Python or NumPy: 0.5, -2., 1e-06, 2.5e+03, nan/inf are left exact
_FLOAT = re.compile(r"(?<![\w.])[-+]?(?:\d+\.\d*|\.\d+|\d+(?=[eE]))(?:[eE][-+]?\d+)?(?![\w.])")


# a tolerance stated on an example's own line: "# ± 0.001", "# +- 1e-3"
_STATED = re.compile(r"#.*?(?:±|\+-)\s*(\d+(?:\.\d*)?(?:[eE][-+]?\d+)?)")


def _stated_tolerance(source: str) -> float:
    """The tolerance an example states in a comment on its line (0 when it states none)."""
    m = _STATED.search(source)
    return float(m.group(1)) if m else 0.0


def _tolerance(text: str) -> float:
    """One unit in the last decimal written (``0.735`` -> 1e-3, ``2.5e-03`` -> 1e-4)."""
    mantissa, _, exponent = text.lower().partition("e")
    decimals = len(mantissa.partition(".")[2])
    return 10.0 ** (-decimals + (int(exponent) if exponent else 0))


class _FloatChecker(doctest.OutputChecker):
    """doctest's checker, with the floats of ``want`` compared to the precision written.

    As pytest's ``NUMBER`` option: when ``want`` and ``got`` hold the same count of floats,
    each float of ``got`` within one unit of the last written decimal of its ``want``
    counterpart is replaced by the ``want`` text, then the strings are compared as usual.
    """

    #: the tolerance the current example states (``_Runner`` sets it before each example)
    stated = 0.0

    def check_output(self, want: str, got: str, optionflags: int) -> bool:
        if super().check_output(want, got, optionflags):
            return True
        wants, gots = list(_FLOAT.finditer(want)), list(_FLOAT.finditer(got))
        if not wants or len(wants) != len(gots):
            return False
        parts, last = [], 0
        for w, g in zip(wants, gots, strict=True):
            parts.append(got[last : g.start()])
            tol = max(_tolerance(w.group()), self.stated)
            close = abs(float(w.group()) - float(g.group())) <= tol * (1 + 1e-9)
            parts.append(w.group() if close else g.group())
            last = g.end()
        parts.append(got[last:])
        # NumPy pads columns to the widest number: "[ 1.  -0.5]" is "[1. -0.5]" with other data
        return super().check_output(_squeeze(want), _squeeze("".join(parts)), optionflags)


class _Runner(doctest.DocTestRunner):
    """doctest's runner, telling the checker the tolerance each example states."""

    def report_start(self, out: object, test: doctest.DocTest, example: doctest.Example) -> None:
        self._checker.stated = _stated_tolerance(example.source)  # type: ignore[attr-defined]
        super().report_start(out, test, example)  # type: ignore[arg-type]


def _squeeze(text: str) -> str:
    """Drop the blanks NumPy's column alignment puts after ``[``/``(`` and before ``]``/``)``."""
    return re.sub(r"[ \t]+([\])])", r"\1", re.sub(r"([\[(])[ \t]+", r"\1", text))


def _blocks(text: str) -> list[tuple[str, str, int]]:
    """(kind, code, line of the block's first code line) in page order."""
    return [
        (m.group(1), m.group(2), text.count("\n", 0, m.start(2)) + 1) for m in _BLOCK.finditer(text)
    ]


@pytest.mark.parametrize("page", PAGES, ids=[p.name for p in PAGES])
def test_doc_examples_run(page: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    text = page.read_text()
    blocks = _blocks(text)
    shared = DOCS.parent.parent / "shared"
    if "../shared/data" in text and not (shared / "data").is_dir():
        pytest.skip("reference data not found")
    work = tmp_path / "repo"
    work.mkdir()
    if shared.is_dir():
        (tmp_path / "shared").symlink_to(shared.resolve(), target_is_directory=True)
    monkeypatch.chdir(work)
    namespace: dict[str, object] = {"__name__": f"docs_{page.stem}"}
    parser = doctest.DocTestParser()
    runner = _Runner(checker=_FloatChecker(), optionflags=_FLAGS)
    for i, (kind, code, line) in enumerate(blocks):
        if "torch" in code:
            pytest.importorskip("torch")
        if "rawpy" in code:
            pytest.importorskip("rawpy")
        where = f"{page.name}:{line} (block {i})"
        if kind == "python":
            try:
                exec(compile(code, where, "exec"), namespace)
            except Exception as exc:  # pragma: no cover - the message is the point
                pytest.fail(f"{where} failed: {type(exc).__name__}: {exc}")
            continue
        test = doctest.DocTest(
            parser.get_examples(code, where), namespace, where, str(page), line - 1, code
        )
        test.globs = namespace  # DocTest copies its globals: share the page's namespace
        report: list[str] = []
        result = runner.run(test, out=report.append, clear_globs=False)
        if result.failed:
            pytest.fail(f"{where}: {result.failed} shown result(s) differ\n" + "".join(report))


# --- the old style must not come back ------------------------------------------------------

# a comment that reads as a value: a list, a tuple, an array, a number, a bool, a string, None
_RESULT_COMMENT = re.compile(
    r"#\s*(?:\[|\(|array\(|tensor\(|[-+]?\.?\d|True\b|False\b|None\b|nan\b|'|\")"
)


def _result_comments(code: str) -> list[tuple[int, str]]:
    """(line, comment) of comments that look like the value of the expression before them."""
    try:
        tree = ast.parse(code)
    except SyntaxError:  # pragma: no cover - test_doc_examples_run reports it
        return []
    lines = code.splitlines()
    comments = {
        tok.start[0]: tok.string
        for tok in tokenize.generate_tokens(io.StringIO(code).readline)
        if tok.type == tokenize.COMMENT
    }
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Expr) or isinstance(node.value, ast.Constant):
            continue
        end = node.end_lineno or node.lineno
        # a trailing comment on the expression's last line, or the comment line just after it
        candidates = [end]
        if end < len(lines) and lines[end].lstrip().startswith("#"):
            candidates.append(end + 1)
        for n in candidates:
            comment = comments.get(n)
            if comment and _RESULT_COMMENT.match(comment):
                found.append((n, comment))
    return found


@pytest.mark.parametrize("page", PAGES, ids=[p.name for p in PAGES])
def test_no_result_comments_in_python_blocks(page: Path) -> None:
    bad = [
        f"{page.name}:{line + n - 1}: {comment}"
        for kind, code, line in _blocks(page.read_text())
        if kind == "python"
        for n, comment in _result_comments(code)
    ]
    assert not bad, (
        "a result shown as a comment is never checked: move it to a ```pycon block "
        "(>>> prompts, the output below):\n" + "\n".join(bad)
    )


def test_float_checker() -> None:
    check = _FloatChecker().check_output
    assert check("0.7354\n", "0.73540000001\n", _FLAGS)
    assert check("[0.475 0.   ]\n", "[ 4.75000000e-01 -1.2e-17]\n", _FLAGS)
    assert check("1.53 just noticeable\n", "1.5301 just noticeable\n", _FLAGS)
    assert not check("0.735\n", "0.737\n", _FLAGS)
    assert not check("1.53 just noticeable\n", "1.53 noticeable\n", _FLAGS)
    assert not check("2856\n", "2857\n", _FLAGS)  # integers are exact
    assert check("(4, 100, 2) 1e-06\n", "(4, 100, 2) 1.0000001e-06\n", _FLAGS)


def test_stated_tolerance() -> None:
    # the gain that failed README's test command with another rawpy (issue 25)
    checker = _FloatChecker()
    want, got = "array([0.8105, 1.    , 4.0826])\n", "array([0.8105, 1.    , 4.0823])\n"
    assert not checker.check_output(want, got, _FLAGS)
    checker.stated = _stated_tolerance("raw.white_balance.round(4)  # ± 0.001 (LibRaw)\n")
    assert checker.stated == 0.001
    assert checker.check_output(want, got, _FLAGS)
    assert not checker.check_output(want, "array([0.8105, 1.    , 4.0840])\n", _FLAGS)
    assert _stated_tolerance("x  # +- 1e-3\n") == 1e-3
    assert _stated_tolerance("x.round(4)  # as-shot gains\n") == 0.0


def test_examples_from_other_libraries_state_a_tolerance() -> None:
    # values LibRaw computes are shown with a stated tolerance, never to its last digit
    text = (DOCS / "raw.md").read_text()
    for line in text.splitlines():
        libraw = re.search(r"white_balance|camera_to_srgb|gains", line)
        if line.startswith(">>> ") and libraw and ".round(" in line:
            assert _stated_tolerance(line), line


def test_result_comment_detector() -> None:
    assert _result_comments("x = 1\nprint(x)  # 1\n") == [(2, "# 1")]
    assert _result_comments("f(x)\n# array([1., 2.])\n") == [(2, "# array([1., 2.])")]
    assert _result_comments("for i in y:\n    print(i)\n# [1, 2]\n") == [(3, "# [1, 2]")]
    assert _result_comments("x = f()  # (54, 3), mm\nprint(x)  # the world origin\n") == []
    assert _result_comments("f()\n# the next step, in words\ng()\n") == []
