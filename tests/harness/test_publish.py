"""Publishing a run (glu.run.publish): nothing glu did not write is replaced, a synthetic run in the checkout
leaves git's tree clean, and a run's names never become paths outside its folders."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from cli_run import run
from tiny_notebook import TINY_NOTEBOOK

from glu import paths
from glu.errors import OutputError
from glu.paths import OUTPUT_KINDS, OutputLayout
from glu.run.publish import CURRENT, MARKER, OWNER, PublishError, Store, legacy_files


@pytest.fixture(scope="module")
def notebooks(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("nbs")
    (folder / "01_a.py").write_text(TINY_NOTEBOOK)
    return folder


def _reproduce(capsys, notebooks: Path, out: Path, *extra: str) -> tuple[int, str, str]:
    argv = ["reproduce", "--notebooks", str(notebooks), "--data", "synthetic", "-o", str(out), "-j", "1"]
    return run(capsys, *argv, "--no-site", *extra)


def _tree(folder: Path) -> dict[str, bytes]:
    return {
        str(f.relative_to(folder)): f.read_bytes()
        for f in sorted(folder.rglob("*"))
        if f.is_file() and ".glu-runs" not in f.relative_to(folder).parts
    }


@pytest.mark.parametrize(
    "mine",
    [
        "site/index.html",
        "site/blog/post.html",
        "figures/my_figure.png",
        "results",  # a file where glu would put a folder
        "notebooks/analysis.ipynb",
    ],
)
def test_a_file_of_the_users_in_the_output_folder_is_refused_in_one_line_and_kept(
    capsys, tmp_path, notebooks, mine
):
    out = tmp_path / "out"
    (out / mine).parent.mkdir(parents=True, exist_ok=True)
    (out / mine).write_text("the user's own")
    for other in ("site-source/x", "site.old/x", "site.new/x", ".glu-staging/x/y"):  # never looked at
        (out / other).parent.mkdir(parents=True, exist_ok=True)
        (out / other).write_text("the user's own")
    before = _tree(out)
    status, _, err = _reproduce(capsys, notebooks, out)
    assert status == 2 and len(err.strip().splitlines()) == 1, err
    assert mine.split("/")[0] in err and "--force" in err
    assert _tree(out) == before  # nothing of the user's touched, nothing ran
    status, _, err = _reproduce(capsys, notebooks, out, "--force")
    assert status == 0, err
    assert _tree(out) == {**before, **{k: v for k, v in _tree(out).items() if k not in before}}
    kind = mine.split("/")[0]
    assert not (out / kind).is_symlink()  # left as it was: the run is in the store
    assert (out / ".glu-runs" / CURRENT / "figures" / "a.png").read_text() == "run 0"
    if kind != "figures":
        assert (out / "figures" / "a.png").read_text() == "run 0"


def test_a_store_glu_did_not_make_is_refused(capsys, tmp_path, notebooks):
    out = tmp_path / "out"
    (out / ".glu-runs").mkdir(parents=True)
    (out / ".glu-runs" / "notes.txt").write_text("mine")
    status, _, err = _reproduce(capsys, notebooks, out)
    assert status == 2 and "notes.txt" in err and MARKER in err
    assert (out / ".glu-runs" / "notes.txt").read_text() == "mine"


def test_runs_replace_only_what_glu_published_and_a_stale_staging_goes(capsys, tmp_path, notebooks):
    out = tmp_path / "out"
    assert _reproduce(capsys, notebooks, out)[0] == 0
    assert _reproduce(capsys, notebooks, out, "--seed", "5")[0] == 0
    assert (out / "figures" / "a.png").read_text() == "run 5"
    assert all((out / kind).is_symlink() for kind in OUTPUT_KINDS)
    runs = [d for d in (out / ".glu-runs").iterdir() if d.name.startswith("r")]
    assert len(runs) == 1 and (out / ".glu-runs" / CURRENT).resolve() == runs[0].resolve()


def test_a_partial_run_keeps_the_other_notebooks_outputs_unless_the_published_summary_is_malformed(
    capsys, tmp_path
):
    """--only 02 after a full run: 01's figures and summary entries are kept from the published run (a
    malformed published summary keeps nothing: the run publishes what it ran, as with no summary)."""
    nbs, out = tmp_path / "nbs", tmp_path / "out"
    nbs.mkdir()
    (nbs / "01_a.py").write_text(TINY_NOTEBOOK)
    (nbs / "02_b.py").write_text(
        TINY_NOTEBOOK.replace("    - a\n", "    - b\n").replace('"a.{ext}"', '"b.{ext}"')
    )
    assert _reproduce(capsys, nbs, out)[0] == 0
    assert _reproduce(capsys, nbs, out, "--only", "02", "--seed", "5")[0] == 0
    assert (out / "figures" / "a.png").read_text() == "run 0" and (
        out / "figures" / "b.png"
    ).read_text() == "run 5"
    summary = json.loads((out / "results" / "summary.json").read_text())
    assert [(nb["name"], nb["parameters"]) for nb in summary["notebooks"]] == [
        ("01_a", {}),
        ("02_b", {"seed": 5}),
    ]
    assert summary["figures_by_notebook"] == {
        "a.png": "01_a",
        "a.svg": "01_a",
        "b.png": "02_b",
        "b.svg": "02_b",
    }
    for notebooks in (["01_a", {"name": "02_b"}], [{"title": "01_a"}]):
        published = out / "results" / "summary.json"
        text = json.dumps({**summary, "notebooks": notebooks})
        published.unlink()  # a file of its own, not the one the runs share
        published.write_text(text)
        status, _, err = _reproduce(capsys, nbs, out, "--only", "02")
        assert status == 0, err
        summary = json.loads(published.read_text())
        assert [nb["name"] for nb in summary["notebooks"]] == ["02_b"] and summary["figures"] == [
            "b.png",
            "b.svg",
        ]
        assert not (out / "figures" / "a.png").exists()


def test_glu_run_refuses_to_write_into_a_published_run(capsys, tmp_path, notebooks):
    out = tmp_path / "out"
    assert _reproduce(capsys, notebooks, out)[0] == 0
    before = _tree(out / ".glu-runs")
    status, _, err = run(capsys, "run", "01_a", "--notebooks", str(notebooks), "-o", str(out), "-q")
    assert status == 2 and "glu reproduce published" in err
    assert _tree(out / ".glu-runs") == before


def test_an_earlier_glus_folders_in_the_checkout_are_recognised_and_anything_else_refused(
    tmp_path, monkeypatch
):
    """Before the store, glu wrote real folders at the checkout's places; their files are recognised by
    the earlier summary and the notebooks' manifests, and a file of the user's among them is refused."""
    from glu.run import publish

    root = tmp_path / "checkout"
    monkeypatch.setattr(publish, "PROJECT_ROOT", root)
    layout = OutputLayout(
        root,
        *(root / k for k in ("build/figures", "results", "recordings", "models")),
        root / "build" / "notebooks",
        root / "build" / "site",
        tracked_figures=root / "figures",
    )
    layout.results.mkdir(parents=True)
    summary = {"notebooks": [{"name": "01_a"}], "tables": {"t": {}}, "recordings": ["r.rrd"]}
    (layout.results / "summary.json").write_text(json.dumps(summary))
    for f in (
        "results/t.csv",
        "results/t.json",
        "results/summary.csv",
        "recordings/r.rrd",
        "build/site/index.html",
        "build/notebooks/01_a.ipynb",
    ):
        (root / f).parent.mkdir(parents=True, exist_ok=True)
        (root / f).write_text("an earlier glu's")
    legacy = legacy_files(layout)
    assert Store(layout).survey(legacy) == {
        "figures": "absent",
        "results": "legacy",
        "recordings": "legacy",
        "models": "absent",
        "notebooks": "legacy",
        "site": "legacy",
    }
    store = Store(layout)
    store.survey(legacy)
    run_folder = store.begin()
    (run_folder / "results").mkdir()
    (run_folder / "results" / "summary.json").write_text("{}")
    store.record(run_folder, {})
    store.publish(run_folder)  # the earlier glu's folders moved aside, then removed with the earlier runs
    assert all(layout.folder(kind).is_symlink() for kind in OUTPUT_KINDS)
    assert (layout.results / "summary.json").read_text() == "{}"
    assert [d.name for d in (root / ".glu-runs").iterdir() if d.name.startswith("r")] == [run_folder.name]
    (layout.results.parent / "results2").mkdir()
    layout.results.unlink()
    (layout.results.parent / "results2").rename(layout.results)
    (layout.results / "my_notes.txt").write_text("the user's own")
    with pytest.raises(PublishError, match="my_notes.txt"):
        Store(layout).survey(legacy)


def _copy_of_the_checkout(dest: Path) -> Path:
    """The checkout's files as git sees them now (edits and new files included), in a new repository."""
    root = paths.PROJECT_ROOT
    files = subprocess.run(
        ["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
        cwd=root,
        capture_output=True,
        check=True,
    ).stdout
    for name in files.decode().split("\0"):
        if name and (root / name).is_file():
            (dest / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(root / name, dest / name)
    git = ["git", "-c", "user.name=t", "-c", "user.email=t@t", "-c", "commit.gpgsign=false"]
    subprocess.run(["git", "init", "-q"], cwd=dest, check=True)
    subprocess.run([*git, "add", "-A"], cwd=dest, check=True)
    subprocess.run([*git, "commit", "-q", "-m", "copy"], cwd=dest, check=True)
    return dest


def test_a_synthetic_make_reproduce_leaves_gits_tree_clean(tmp_path):
    """`make reproduce` on synthetic data in a checkout (one notebook, quick, no site, for time): its figures
    go to build/figures/, never to the tracked figures/; git status shows nothing."""
    clone = _copy_of_the_checkout(tmp_path / "clone")
    tracked = {f.name: f.read_bytes() for f in (clone / "figures").iterdir()}
    venv = Path(sys.executable).parent.parent
    stamp = venv / ".glu-installed"
    make = ["make", "reproduce", f"VENV={venv}", "-o", str(stamp), "DATA=synthetic"]
    env = {**os.environ, "PYTHONPATH": str(clone), "GLU_SHARED_DATA": "none"}
    r = subprocess.run(
        [*make, "ARGS=--quick --only 01 --no-site"],
        cwd=clone,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert r.returncode == 0, r.stderr[-3000:]
    assert "build/figures" in r.stderr or (clone / "build" / "figures" / "gesture_segmentation.png").is_file()
    assert (clone / "build" / "figures" / "gesture_segmentation.png").is_file()
    assert (clone / "results" / "summary.json").is_file()  # through the link into the store
    status = subprocess.run(["git", "status", "--porcelain"], cwd=clone, capture_output=True, text=True)
    assert status.stdout == "", status.stdout
    assert {f.name: f.read_bytes() for f in (clone / "figures").iterdir()} == tracked


def test_an_installed_glu_asks_for_an_output_folder(tmp_path, monkeypatch):
    from glu.errors import OutputError

    monkeypatch.setattr(paths, "PROJECT_ROOT", None)
    with pytest.raises(OutputError, match=r"^glu is installed, not a source checkout: give an output"):
        OutputLayout.at(None)
    assert OutputLayout.at(tmp_path).results == tmp_path.resolve() / "results"


def test_a_store_or_a_link_glu_did_not_make_is_refused(tmp_path):
    layout = OutputLayout.under(tmp_path / "out")
    layout.root.mkdir()
    layout.store.write_text("a file where the store goes")
    with pytest.raises(PublishError, match=r"\.glu-runs is not a folder glu made; move it away"):
        Store(layout).survey()
    layout.store.unlink()
    (tmp_path / "elsewhere").mkdir()
    layout.store.symlink_to(tmp_path / "elsewhere")
    with pytest.raises(PublishError, match="is not a folder glu made"):
        Store(layout).survey()
    layout.store.unlink()
    layout.figures.symlink_to(tmp_path / "elsewhere")
    with pytest.raises(PublishError, match=r"figures is a link glu did not make; glu never replaces"):
        Store(layout).survey()
    assert Store(layout, force=True).survey()["figures"] == "kept"


def test_clean_removes_a_pointer_never_swapped_in_and_keeps_a_run_of_a_live_process(tmp_path, monkeypatch):
    from glu.run import publish

    store = Store(OutputLayout.under(tmp_path / "out"))
    run = store.begin()
    (run / OWNER).write_text("1\n")  # a process of another user's: signals to it are refused
    pointer = store.root / f".{CURRENT}-1234"
    pointer.symlink_to(run.name)
    monkeypatch.setattr(publish.os, "kill", lambda pid, sig: (_ for _ in ()).throw(PermissionError(1, "no")))
    assert store.clean() == [] and run.is_dir() and not pointer.is_symlink()
    monkeypatch.undo()
    (run / OWNER).write_text("not a process id\n")
    assert store.clean() == [run] and not run.exists()


def test_files_are_copied_where_hard_links_are_refused_and_a_bad_record_is_none(tmp_path, monkeypatch):
    from glu.run import publish

    (tmp_path / "a.txt").write_text("kept")

    def refused(src, dst):
        raise OSError(18, "Invalid cross-device link")

    monkeypatch.setattr(publish.os, "link", refused)
    publish._link_or_copy(tmp_path / "a.txt", tmp_path / "run" / "x" / "a.txt")
    assert (tmp_path / "run" / "x" / "a.txt").read_text() == "kept"
    assert (tmp_path / "run" / "x" / "a.txt").stat().st_ino != (tmp_path / "a.txt").stat().st_ino
    run = tmp_path / "run"
    assert publish.read_record(run) == {}  # none
    for text in ("{not json", '{"other": 1}', '["files"]', '{"files": ["a"]}'):
        (run / publish.RUN_RECORD).write_text(text)
        assert publish.read_record(run) == {}, text
    (run / publish.RUN_RECORD).write_text('{"files": {"x/a.txt": "01_a", "../b": "01_a", "c": 3}}')
    assert publish.read_record(run) == {"x/a.txt": "01_a"}


def test_an_unknown_output_kind_is_refused(tmp_path):
    layout = OutputLayout.under(tmp_path)
    assert layout.folder("figures") == layout.figures
    with pytest.raises(OutputError, match=r"^unknown output kind 'nope'; allowed: figures, results, "):
        layout.folder("nope")
