"""Running a notebook headless: the kernel's environment (BLAS/OpenMP threads) as the caller sets it."""

from __future__ import annotations

import json

import pytest

from glu.machine import THREAD_ENV
from glu.run.execution import RunHandle, run_notebook

NOTEBOOK = """# %% tags=["parameters"]
x: int = 0

# %%
import json, os
import numpy  # loads its BLAS
from threadpoolctl import threadpool_info
print(json.dumps({"env": {k: os.environ.get(k) for k in %s},
                  "blas": sorted({p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"})}))
"""


def _run(tmp_path, threads):
    pytest.importorskip("papermill")
    src = tmp_path / "probe.py"
    src.write_text(NOTEBOOK % json.dumps(list(THREAD_ENV)))
    out = tmp_path / f"probe-{threads}.ipynb"
    run_notebook(src, out, {"x": 1}, handle=RunHandle(threads=threads))
    cell = json.loads(out.read_text())["cells"][-1]
    return json.loads("".join(cell["outputs"][0]["text"]))


def test_a_kernel_gets_its_share_of_the_threads_unless_the_caller_chose(tmp_path, monkeypatch):
    for name in THREAD_ENV:
        monkeypatch.delenv(name, raising=False)
    capped = _run(tmp_path, 1)
    assert all(v == "1" for v in capped["env"].values())
    assert capped["blas"] == [1]  # numpy's BLAS really runs one thread
    monkeypatch.setenv("OMP_NUM_THREADS", "3")  # the user's own setting wins
    chosen = _run(tmp_path, 1)
    assert chosen["env"]["OMP_NUM_THREADS"] == "3" and chosen["env"]["OPENBLAS_NUM_THREADS"] == "1"
    monkeypatch.delenv("OMP_NUM_THREADS")
    free = _run(tmp_path, None)  # not capped: the libraries decide
    assert all(v is None for v in free["env"].values())


CWD_NOTEBOOK = """# %% tags=["parameters"]
x: int = 0

# %%
import os
print(os.getcwd())
"""


def test_notebooks_run_side_by_side_each_in_its_own_folder_and_leave_this_process_where_it_was(tmp_path):
    """papermill's own ``cwd`` would os.chdir this process around each run; two runs in threads (as
    ``glu reproduce -j 2``) then undo each other's change and can leave the process, or start a kernel, in
    the wrong folder. The kernel gets its folder when it starts, and this process never moves."""
    from concurrent.futures import ThreadPoolExecutor

    pytest.importorskip("papermill")
    here = __import__("os").getcwd()
    folders = [tmp_path / f"nb{i}" for i in range(4)]

    def run(folder):
        folder.mkdir()
        src = folder / "probe.py"
        src.write_text(CWD_NOTEBOOK)
        out = tmp_path / f"{folder.name}.ipynb"
        run_notebook(src, out, {"x": 1})  # cwd: the notebook's folder
        return "".join(json.loads(out.read_text())["cells"][-1]["outputs"][0]["text"]).strip()

    with ThreadPoolExecutor(2) as pool:
        seen = list(pool.map(run, folders))
    assert seen == [str(f) for f in folders]
    assert __import__("os").getcwd() == here


def test_a_relative_figure_check_folder_is_the_callers_not_the_kernels(tmp_path, monkeypatch):
    """GLU_FIGURE_CHECK=1 once left its reports in notebooks/1/: the kernel took the folder in its own
    working folder. The runner hands kernels the folder as the caller named it, made absolute."""
    from glu.plots.overlap import CHECK_ENV

    pytest.importorskip("papermill")
    (tmp_path / "caller").mkdir()
    (tmp_path / "nb").mkdir()
    monkeypatch.chdir(tmp_path / "caller")
    monkeypatch.setenv(CHECK_ENV, "check")
    src = tmp_path / "nb" / "probe.py"
    src.write_text(CWD_NOTEBOOK.replace("print(os.getcwd())", f"print(os.environ[{CHECK_ENV!r}])"))
    run_notebook(src, tmp_path / "probe.ipynb", {"x": 1})  # the kernel runs in nb/
    seen = "".join(json.loads((tmp_path / "probe.ipynb").read_text())["cells"][-1]["outputs"][0]["text"])
    assert seen.strip() == str(tmp_path / "caller" / "check")


@pytest.mark.slow  # a fresh interpreter importing papermill twice (5 s)
def test_papermill_loads_without_jsonschemas_slow_optional_iri_checker_and_notebooks_still_validate():
    """rfc3987_syntax (installed with JupyterLab) builds a grammar at import (1.6 s); jsonschema only uses
    it for the ``iri`` format, which nbformat never checks. In a fresh process load_papermill leaves it out;
    in a process that already imported jsonschema it changes nothing."""
    import subprocess
    import sys

    pytest.importorskip("rfc3987_syntax", reason="rfc3987-syntax is not installed: nothing to leave out")
    probe = (
        "import json, sys\n"
        "{before}\n"
        "from glu.run.execution import load_papermill\n"
        "load_papermill()\n"
        "import jsonschema, nbformat, rfc3987_syntax\n"
        "nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell('1')])\n"
        "nbformat.validate(nb)\n"
        "print(json.dumps('iri' in jsonschema.FormatChecker.checkers))\n"
    )

    def iri_checker(before: str) -> bool:
        r = subprocess.run(
            [sys.executable, "-c", probe.format(before=before)], capture_output=True, text=True
        )
        assert r.returncode == 0, r.stderr[-2000:]
        return json.loads(r.stdout.strip().splitlines()[-1])

    assert iri_checker("") is False
    assert iri_checker("import jsonschema") is True


THREE_CELLS = """# %% tags=["parameters"]
x: int = 0

# %%
a = 1

# %%
b = 2
"""


@pytest.mark.parametrize(
    "moment", ["before its kernel", "while its kernel starts", "between cells", "last cell"]
)
@pytest.mark.slow
def test_a_stop_at_any_moment_ends_the_run_as_stopped(tmp_path, monkeypatch, moment):
    """A stop that comes before the kernel starts, while it starts, between two cells (no further cell
    runs), or during the last cell (papermill then ends quietly): NotebookStopped, never a finished run."""
    pytest.importorskip("papermill")
    from glu.run import execution
    from glu.run.execution import NotebookStopped

    src = tmp_path / "three.py"
    src.write_text(THREE_CELLS)
    started = []

    def on_cell(index, n_cells):
        started.append(index)
        if (moment == "between cells" and len(started) == 2) or (
            moment == "last cell" and index == n_cells - 1
        ):
            handle.stopped = True  # as stop() sets it, its kill of the kernel not yet come

    handle = RunHandle(on_cell=on_cell)
    if moment == "before its kernel":
        handle.stopped = True
    elif moment == "while its kernel starts":
        kernel_env = execution._kernel_env

        def stopped_meanwhile(*args):
            handle.stopped = True
            return kernel_env(*args)

        monkeypatch.setattr(execution, "_kernel_env", stopped_meanwhile)
    with pytest.raises(NotebookStopped, match="^three: stopped$"):
        run_notebook(src, tmp_path / "three.ipynb", {"x": 1}, handle=handle)
    assert len(started) == {"before its kernel": 0, "while its kernel starts": 0, "between cells": 2}.get(
        moment, 4
    )


def test_stop_after_the_kernel_is_gone_and_the_engine_registered_when_no_entry_point_did(monkeypatch):
    import subprocess
    import sys
    from types import SimpleNamespace

    from papermill.engines import papermill_engines

    from glu.run.execution import _register_engine

    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    log = SimpleNamespace(disabled=False)
    handle = RunHandle()
    handle._client = SimpleNamespace(log=log, km=SimpleNamespace(provisioner=SimpleNamespace(process=gone)))
    handle.stop()  # the kernel already ended: nothing to kill, no error
    assert handle.stopped and log.disabled
    monkeypatch.delitem(papermill_engines._engines, "glu")  # glu run from a checkout that is not installed
    assert _register_engine() == "glu" and papermill_engines._engines["glu"].__name__ == "GluEngine"
