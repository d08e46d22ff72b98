"""Saved tables of heavy grids (glu.saved): keys, lookup in the committed folder and the cache, provenance."""

from __future__ import annotations

import dataclasses

import pytest

from glu import saved
from glu.machine import map_tasks


@pytest.fixture
def roots(tmp_path, monkeypatch):
    """A checkout whose sweeps/ and build/sweeps/ are temporary folders."""
    here = dataclasses.replace(saved.HERE, saved=tmp_path / "sweeps", sweeps=tmp_path / "build" / "sweeps")
    monkeypatch.setattr(saved, "HERE", here)
    return here


def test_keys_match_whatever_the_order_and_tuples():
    a = {"settings": {"x": (1, 2), "y": 0.5}, "format": ["f", 1]}
    b = {"format": ("f", 1), "settings": {"y": 0.5, "x": [1, 2]}}
    assert saved.canonical(a) == saved.canonical(b) and saved.digest(a) == saved.digest(b)
    assert saved.digest(a) != saved.digest({**a, "data_source": "real"})
    assert saved.cache_key(a)["code"] == saved.code_digest() and len(saved.code_digest()) == 16


def test_find_the_committed_folder_then_the_cache(roots):
    key = {"settings": {"n": 3}, "data_source": "synthetic"}
    assert saved.find("nb", key) is None
    committed = roots.saved / "nb" / "synthetic"
    committed.mkdir(parents=True)
    saved.write_key(committed, {**key, "data_source": "real"}, "make sweeps")
    assert saved.find("nb", key) is None  # another data source
    saved.write_key(committed, key, "make sweeps")
    assert saved.find("nb", key) == committed
    other = {"settings": {"n": 4}, "data_source": "synthetic"}
    cache = saved.cache_folder("nb", other)
    assert cache.parent == roots.sweeps / "nb" and saved.find("nb", other) is None
    cache.mkdir(parents=True)
    saved.write_key(cache, other, "glu run nb")  # without the code's digest: another version of glu's
    assert saved.find("nb", other) is None
    saved.write_key(cache, saved.cache_key(other), "glu run nb")
    assert saved.find("nb", other) == cache


def test_provenance_says_where_when_and_how(roots, monkeypatch):
    folder = roots.saved / "nb" / "x"
    folder.mkdir(parents=True)
    monkeypatch.setattr(
        saved, "made_with", lambda: {"glu": "9.9", "commit": "abcdef0123456789", "dirty": True}
    )
    saved.write_key(folder, {"k": 1}, "glu evaluate --save sweeps/nb/x")
    text = saved.provenance_text(folder)
    assert "computed" in text and "glu 9.9, commit abcdef0123 with uncommitted changes" in text
    assert text.endswith("regenerate them with: glu evaluate --save sweeps/nb/x")
    assert saved.read_key(roots.saved) is None  # no key file: not a saved folder


def test_made_with_names_this_checkout():
    info = saved.made_with()
    assert info["glu"] and (info["commit"] is None or len(info["commit"]) == 40)


def test_made_with_without_git_names_no_commit(tmp_path, monkeypatch):
    """A checkout on a machine without git (or where it hangs): the version only, nothing raised."""
    monkeypatch.setattr(saved, "PROJECT_ROOT", tmp_path)
    monkeypatch.setenv("PATH", str(tmp_path))  # no git to run
    assert saved.made_with() == {"glu": saved.__version__, "commit": None, "dirty": None}


def _square(x: int, add: int) -> int:
    return x * x + add


def test_map_tasks_in_this_process_keeps_the_order():
    assert map_tasks(_square, [3, 1, 2], 1) == [10, 2, 5]


@pytest.mark.slow
def test_map_tasks_on_a_local_cluster_gives_the_same():
    assert map_tasks(_square, [3, 1, 2], 1, workers=2) == [10, 2, 5]
