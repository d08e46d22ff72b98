"""Running a notebook headless: the kernel's environment (BLAS/OpenMP threads) as the caller sets it."""

from __future__ import annotations

import json

import pytest

from glu.execution import THREAD_ENV, RunHandle, run_notebook

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
