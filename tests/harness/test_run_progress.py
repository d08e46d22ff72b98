"""``glu run`` shows each code cell as it starts (cell n/N, its first line, the time so far); ``--quiet``
nothing."""

from __future__ import annotations

import io
import json
import re

import pytest

from glu.run.progress import CellProgress

CELLS = [
    {"cell_type": "markdown", "source": "# A title"},
    {"cell_type": "code", "source": "\n\nx = 1  # first\ny = 2"},
    {"cell_type": "markdown", "source": "Some words"},
    {"cell_type": "code", "source": "import math\nprint(math.pi)"},
    {"cell_type": "code", "source": "z = '" + "a" * 100 + "'"},
]


def _feed(progress: CellProgress) -> None:
    """Start the cells as papermill's client does: every cell, markdown included, in order."""
    progress.handle.n_code_cells = sum(c["cell_type"] == "code" for c in CELLS)
    for i, cell in enumerate(CELLS):
        progress.handle._cell_started(i, len(CELLS), cell)


def test_plain_lines_name_each_code_cell_once_with_its_first_line():
    stream = io.StringIO()
    with CellProgress("nb", live=False, stream=stream) as progress:
        _feed(progress)
    lines = stream.getvalue().splitlines()
    assert len(lines) == 4  # three code cells and the closing line; markdown cells are not cells that run
    pattern = re.compile(r"^nb: cell (\d)/3 at \d+\.\d s: (.*)$")
    found = [pattern.match(line).groups() for line in lines[:3]]
    assert found == [("1", "x = 1  # first"), ("2", "import math"), ("3", "z = '" + "a" * 54 + "…")]
    assert re.fullmatch(r"nb: 3 cells in \d+\.\d s", lines[3])


def test_a_plain_log_hears_from_a_long_cell_every_heartbeat():
    from glu.run.progress import HEARTBEAT

    stream = io.StringIO()
    with CellProgress("nb", live=False, stream=stream) as progress:
        _feed(progress)
        started = progress.last_line  # when cell 3 started
        progress.beat(started + HEARTBEAT / 2)  # not yet
        progress.beat(started + HEARTBEAT)
        progress.beat(started + HEARTBEAT * 1.5)  # not again yet
        progress.beat(started + HEARTBEAT * 2)
    beats = [line for line in stream.getvalue().splitlines() if "still running" in line]
    assert len(beats) == 2 and all(line.startswith("nb: cell 3/3 still running at ") for line in beats)
    elapsed = [float(re.search(r"at (\d+\.\d) s", line).group(1)) for line in beats]
    assert elapsed[1] - elapsed[0] == pytest.approx(HEARTBEAT, abs=0.11)


def test_on_a_terminal_one_bar_counts_the_cells_done():
    stream = io.StringIO()
    with CellProgress("nb", live=True, stream=stream) as progress:
        _feed(progress)
        assert progress.bar.total == 3 and progress.bar.n == 2  # the third is running
        drawn = len(stream.getvalue())
        progress.beat(progress.last_line + 1e6)  # the bar's clock is redrawn; no line says it still runs
        assert len(stream.getvalue()) > drawn
    text = stream.getvalue()
    assert "still running" not in text and "2/3 cells done" in text
    assert "cell 3: z = 'aaa" in text and "starting its kernel" in text
    assert text.rstrip().splitlines()[-1].strip().startswith("nb: 3 cells in")


def test_a_failed_run_gets_no_closing_line():
    stream = io.StringIO()
    with pytest.raises(RuntimeError), CellProgress("nb", live=False, stream=stream) as progress:
        _feed(progress)
        raise RuntimeError("a cell failed")
    assert "cells in" not in stream.getvalue()


TINY = """# %% tags=["parameters"]
data: str = None  # data folder
out_dir: str = None  # outputs
seed: int = 0  # seed

# %% [markdown]
# Two cells.

# %%
total = sum(range(10))

# %%
print(total)
"""


def test_glu_run_shows_progress_on_stderr_and_nothing_with_quiet(tmp_path, capsys):
    pytest.importorskip("papermill")
    from glu.cli import main

    folder = tmp_path / "nbs"
    folder.mkdir()
    (folder / "01_tiny.py").write_text(TINY)
    argv = ["run", "01", "--notebooks", str(folder), "--data", "synthetic"]
    assert main([*argv, "-o", str(tmp_path / "a")]) == 0
    out, err = capsys.readouterr()
    executed = json.loads((tmp_path / "a" / "notebooks" / "01_tiny.ipynb").read_text())
    code = [c for c in executed["cells"] if c["cell_type"] == "code"]  # papermill adds the injected one
    first = [next(line for line in "".join(c["source"]).splitlines() if line.strip()) for c in code]
    shown = re.findall(r"^01_tiny: cell (\d+)/(\d+) at \d+\.\d s: (.*)$", err, re.MULTILINE)
    assert shown == [(str(i), str(len(code)), line) for i, line in enumerate(first, 1)]
    assert f"01_tiny: {len(code)} cells in" in err and "executed notebook:" in out

    assert main([*argv, "-o", str(tmp_path / "b"), "--quiet", "--json"]) == 0
    out, err = capsys.readouterr()
    assert err == ""
    assert json.loads(out) == {
        "notebook": "01_tiny",
        "executed": str(tmp_path / "b" / "notebooks" / "01_tiny.ipynb"),
        "outputs": str(tmp_path / "b"),
    }


@pytest.mark.slow
def test_glu_run_without_out_writes_to_a_scratch_folder_and_a_failing_cell_is_status_1(
    tmp_path, capsys, monkeypatch
):
    pytest.importorskip("papermill")
    from glu import paths
    from glu.cli import main

    monkeypatch.setattr(paths, "SCRATCH_DIR", tmp_path / "scratch")
    folder = tmp_path / "nbs"
    folder.mkdir()
    (folder / "01_tiny.py").write_text(TINY)
    (folder / "02_fails.py").write_text(TINY + '\n# %%\nraise RuntimeError("deliberate failure")\n')
    argv = ["run", "--notebooks", str(folder), "--data", "synthetic", "--quiet"]
    assert main([*argv, "01"]) == 0
    (run,) = (tmp_path / "scratch" / "01_tiny").iterdir()
    assert (run / "notebooks" / "01_tiny.ipynb").is_file() and f"{run}" in capsys.readouterr().out
    assert main([*argv, "02", "-o", str(tmp_path / "out")]) == 1
    executed = tmp_path / "out" / "notebooks" / "02_fails.ipynb"
    assert capsys.readouterr().err == (
        "glu run: error: notebook 02_fails failed in cell 5: RuntimeError: deliberate failure; "
        f"executed copy at {executed}\n"
    )
    cells = json.loads(executed.read_text())["cells"]
    assert ["RuntimeError"] == [o["ename"] for c in cells for o in c.get("outputs", []) if "ename" in o]
