"""Notebooks run by hand (plain papermill, `glu run`): checked at once, written to a scratch folder, never
published."""

from __future__ import annotations

import hashlib
import json
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import jupytext
import papermill as pm
import pytest

from glu import paths
from glu.run.reproduce import list_notebooks

PUBLISHED = [paths.PROJECT_ROOT / kind for kind in paths.PUBLISHED_KINDS]


def _snapshot() -> dict[str, str]:
    """Every file in the project's published folders, with its content hash."""
    out = {}
    for folder in PUBLISHED:
        for f in sorted(folder.rglob("*")) if folder.exists() else []:
            if f.is_file():
                out[str(f)] = hashlib.sha256(f.read_bytes()).hexdigest()
    return out


def _glu(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "glu", *args], capture_output=True, text=True, timeout=300)


@pytest.fixture
def scratch():
    """The scratch folder of 07_glu2017_figures; the run folders this test made in it removed afterwards."""
    folder = paths.scratch_dir("07_glu2017_figures")
    before = set(folder.iterdir()) if folder.is_dir() else set()
    yield folder
    for run in set(folder.iterdir()) - before if folder.is_dir() else ():
        shutil.rmtree(run, ignore_errors=True)


def _documented_papermill() -> list[str]:
    """The papermill commands of docs/notebooks.md, as a reader copies them."""
    text = (paths.PROJECT_ROOT / "docs" / "notebooks.md").read_text()
    block = re.search(r"```bash\n(\.venv/bin/jupytext[^`]*)```", text).group(1)
    return [line for line in block.splitlines() if line.strip()]


def test_plain_papermill_as_documented_writes_to_a_new_scratch_folder_and_warns_of_nothing(scratch, tmp_path):
    """The documented commands, run as a reader runs them (the notebook and its parameter changed to a quick
    one): no warning, nothing published, and two runs never share a scratch folder."""
    before = _snapshot()
    executed = tmp_path / "out.ipynb"
    lines = [
        line.replace("build/08_out.ipynb", str(executed))
        .replace("build/08_tcds_figures.ipynb", str(tmp_path / "in.ipynb"))
        .replace("08_tcds_figures", "07_glu2017_figures")
        .replace("-p rule jeffrey", "-p threshold 0.05")
        .replace(".venv/bin/", str(Path(sys.executable).parent) + "/")
        for line in _documented_papermill()
    ]
    assert len(lines) == 2 and str(executed) in lines[1]
    for line in lines:
        r = subprocess.run(
            line, shell=True, cwd=paths.PROJECT_ROOT, capture_output=True, text=True, timeout=300
        )
        assert r.returncode == 0, r.stderr
        assert not re.search(r"warn|\d+%\|", r.stderr, re.IGNORECASE), r.stderr  # no warning, no bar
    assert _snapshot() == before, "a by-hand run changed the project's published outputs"
    first = json.loads(executed.read_text())["cells"]
    header = next(
        "".join(o["data"]["text/markdown"])
        for c in first
        for o in c.get("outputs", [])
        if "text/markdown" in o.get("data", {})
    )
    assert header.startswith("**07_glu2017_figures** · synthetic data")
    assert "parameters: threshold=0.05" in header
    folder = re.search(r"build/scratch/07_glu2017_figures/([0-9-]+)/", header).group(1)
    run = scratch / folder
    assert (run / "figures" / "glu2017_effect_prediction.png").is_file()
    svg = (run / "figures" / "glu2017_effect_prediction.svg").read_text()
    assert "07_glu2017_figures with threshold=0.05" in svg  # the figure names the run's parameters
    from glu.paths import new_scratch_dir

    again = new_scratch_dir("07_glu2017_figures")  # a second run in the same second: a folder of its own
    assert again != run and again.parent == scratch and not any(again.iterdir())


def test_plain_papermill_refuses_an_unknown_parameter_in_the_first_cell(tmp_path):
    nb = jupytext.read(paths.notebook_file("02_hmm_training"))
    t0 = time.perf_counter()
    with pytest.raises(pm.PapermillExecutionError) as e:
        pm.execute_notebook(
            nb,
            str(tmp_path / "o.ipynb"),
            parameters={"n_statez": 4, "data": "synthetic"},
            kernel_name="python3",
            cwd=str(paths.NOTEBOOKS_DIR),
            progress_bar=False,
        )
    assert e.value.ename == "ParameterError"
    assert "unknown parameter 'n_statez' (did you mean 'n_states'?)" in e.value.evalue
    assert time.perf_counter() - t0 < 60  # refused before any training (a bound, not a benchmark)
    executed = json.loads((tmp_path / "o.ipynb").read_text())
    code = [c for c in executed["cells"] if c["cell_type"] == "code"]
    failed = [i for i, c in enumerate(code) if any(o.get("output_type") == "error" for o in c["outputs"])]
    assert failed == [2]  # parameters, injected parameters, then the first cell: start() refuses


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["08_tcds_figures", "-p", "rulez", "jeffrey"], "unknown parameter 'rulez' (did you mean 'rule'?)"),
        (["08_tcds_figures", "-p", "final_update", "no"], "final_update must be True or False"),
        (["07_glu2017_figures", "-p", "threshold", "abc"], "not a number"),
        (["08_tcds_figures", "-p", "rule", "jefrey"], "rule must be one of virtual, jeffrey"),
        (["08_tcds_figures", "-p", "step", "1", "-p", "step", "2"], "-p step given more than once"),
        (["08_tcds_figures", "-p", "data", "x"], "give 'data' with --data"),
        (["99_nothing"], "no notebook matches '99_nothing'"),
        (["08_tcds_figures", "--data", "/nonexistent/folder"], "no such data folder"),
    ],
)
def test_glu_run_refuses_bad_parameters_at_once_in_one_line(args, message, capsys):
    from glu.cli import main

    status = main(["run", *args])
    err = capsys.readouterr().err
    assert status == 2, err
    assert err.count("\n") == 1 and message in err and "Traceback" not in err


def test_the_command_exits_2_at_once():
    res = _glu("run", "08_tcds_figures", "-p", "rulez", "jeffrey")
    assert res.returncode == 2 and res.stderr.startswith("glu run: error: 08_tcds_figures: unknown parameter")


def test_glu_run_lists_the_parameters_with_their_choices():
    res = _glu("run", "08", "--list")
    assert res.returncode == 0
    lines = {line.split(":")[0]: line for line in res.stdout.splitlines()}
    assert "{virtual, jeffrey}" in lines["rule"] and "[1, 100000]" in lines["step"]


def test_glu_run_runs_one_notebook_into_its_out_folder(tmp_path):
    before = _snapshot()
    res = _glu("run", "07", "-p", "threshold", "0.05", "--data", "synthetic", "-o", str(tmp_path))
    assert res.returncode == 0, res.stderr
    assert _snapshot() == before
    executed = json.loads((tmp_path / "notebooks" / "07_glu2017_figures.ipynb").read_text())
    n_code = sum(c["cell_type"] == "code" for c in executed["cells"])
    shown = [int(n) for n in re.findall(rf"^07_glu2017_figures: cell (\d+)/{n_code} at ", res.stderr, re.M)]
    assert shown == list(range(1, n_code + 1))  # not a pipe's silence: every code cell as it starts
    svg = (tmp_path / "figures" / "glu2017_word_change.svg").read_text()
    assert "07_glu2017_figures with threshold=0.05" in svg
    doc = json.loads((tmp_path / "results" / "glu2017_word_change_text.json").read_text())
    assert doc["meta"]["notebook_parameters"] == {"threshold": 0.05}


def test_the_notebook_list_is_not_empty():
    assert len(list_notebooks()) >= 9


def test_runs_in_the_same_second_get_folders_of_their_own_until_none_is_left(tmp_path, monkeypatch):
    monkeypatch.setattr(paths, "SCRATCH_DIR", tmp_path)
    monkeypatch.setattr(time, "strftime", lambda fmt: "20260101-120000")
    first, second = paths.new_scratch_dir("nb"), paths.new_scratch_dir("nb")
    assert (first.name, second.name) == ("20260101-120000", "20260101-120000-2")
    real = Path.mkdir

    def taken(path: Path, *args, **kwargs) -> None:  # every run folder's name already made
        if not kwargs.get("exist_ok"):
            raise FileExistsError(path)
        real(path, *args, **kwargs)

    monkeypatch.setattr(Path, "mkdir", taken)
    with pytest.raises(paths.OutputError, match=r"nb: no new scratch folder could be made \(10,000 runs"):
        paths.new_scratch_dir("nb")
