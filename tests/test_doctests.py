"""The examples in glu's docstrings run, and print what they say (none is skipped)."""

from __future__ import annotations

import doctest
import importlib
import pkgutil

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
    for name in ("glu.fusion", "glu.evidence", "glu.bn.inference", "glu.gestures.forward",
                 "glu.gestures.model", "glu.language.descriptions", "glu.data.hand_logs"):  # fmt: skip
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
