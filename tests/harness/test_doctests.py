"""The examples in glu's docstrings run, and print what they say (none is skipped)."""

from __future__ import annotations

import doctest
import importlib
import pkgutil
from pathlib import Path

import pytest

import glu


def _modules() -> list[str]:
    return sorted(m.name for m in pkgutil.walk_packages(glu.__path__, "glu.") if m.name != "glu.__main__")


def _with_examples() -> list[str]:
    finder = doctest.DocTestFinder()
    out = []
    for name in _modules():
        module = importlib.import_module(name)
        if any(t.examples for t in finder.find(module, name)):
            out.append(name)
    return out


MODULES = _with_examples()


def test_the_key_entry_points_have_examples():
    for name in (
        "glu.fusion",
        "glu.evidence",
        "glu.bn.inference",
        "glu.hmm.inference",
        "glu.hmm.model",
        "glu.language.descriptions",
        "glu.data.hand_logs",
    ):
        assert name in MODULES, f"{name} has no runnable example"


def test_no_example_is_skipped():
    for name in _modules():
        source = importlib.import_module(name).__loader__.get_source(name) or ""
        assert "doctest: +SKIP" not in source, f"{name} skips an example"


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples_run(name):
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE | doctest.ELLIPSIS)
    assert result.attempted > 0
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples in {name} failed (see above)"


API_PAGE = Path(__file__).resolve().parents[2] / "docs" / "api.md"


def test_the_python_api_page_examples_run():
    """The Python API page (docs/api.md) is a doctest: every example runs and prints what it shows."""
    text = API_PAGE.read_text(encoding="utf-8")
    test = doctest.DocTestParser().get_doctest(text, {}, "docs/api.md", str(API_PAGE), 0)
    assert len(test.examples) >= 15
    runner = doctest.DocTestRunner(optionflags=doctest.NORMALIZE_WHITESPACE | doctest.ELLIPSIS)
    runner.run(test)
    assert runner.failures == 0, f"{runner.failures} examples of docs/api.md failed (see above)"
