"""glu installed anywhere: where it reads and writes outside a checkout; the wheel in a fresh venv (slow);
dependency lower bounds that resolve together (slow)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from glu import paths
from glu.paths import is_checkout, locate

ROOT = Path(__file__).resolve().parents[2]


def test_a_checkout_keeps_everything_in_the_checkout():
    here = locate(ROOT / "glu")
    assert here.checkout == ROOT and is_checkout(ROOT)
    assert here.notebooks == ROOT / "notebooks" and here.real_data == ROOT / "data" / "real"
    assert here.scratch == ROOT / "build" / "scratch" and here.real_data_label == "data/real/"
    assert here.compiled == ROOT / "build" / "compiled"


def test_an_installed_package_writes_nothing_inside_itself(tmp_path):
    site = tmp_path / "lib" / "python3.11" / "site-packages"
    (site / "glu").mkdir(parents=True)
    (site / "notebooks").mkdir()  # another distribution's top-level folder must not fool it
    loc = locate(site / "glu", user_data=tmp_path / "share" / "glu", user_cache=tmp_path / "cache" / "glu")
    assert loc.checkout is None
    assert loc.notebooks == site / "glu" / "notebooks"  # read-only: the shipped notebooks
    for written in (loc.data, loc.real_data, loc.scratch, loc.compiled):
        assert site not in written.parents
    assert loc.real_data_label.startswith(str(tmp_path / "share" / "glu" / "real"))


def test_an_installed_package_uses_platformdirs(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg-data"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg-cache"))
    if sys.platform != "linux":
        pytest.skip("XDG folders are the Linux convention")
    loc = locate(tmp_path / "site-packages" / "glu")
    assert loc.real_data == tmp_path / "xdg-data" / "glu" / "real"
    assert loc.scratch == tmp_path / "xdg-cache" / "glu" / "scratch"


def test_the_reference_tests_find_the_real_data_where_ci_or_glu_data_fetch_put_it(tmp_path, monkeypatch):
    def data_folder(where: Path) -> Path:
        (where / "affordance-words").mkdir(parents=True)
        return where

    checkout = tmp_path / "project" / "glu"
    monkeypatch.setattr(paths, "PROJECT_ROOT", checkout)
    monkeypatch.setattr(paths, "REAL_DATA_DIR", checkout / "data" / "real")
    monkeypatch.delenv(paths.SHARED_DATA_ENV_VAR, raising=False)
    assert paths.shared_data_dir() is None
    fetched = data_folder(checkout / "data" / "real")  # what `glu data fetch` writes
    assert paths.shared_data_dir() == fetched
    shared = data_folder(tmp_path / "project" / "shared" / "data")  # CI's copy next to the checkout
    assert paths.shared_data_dir() == shared
    chosen = data_folder(tmp_path / "elsewhere")
    monkeypatch.setenv(paths.SHARED_DATA_ENV_VAR, str(chosen))
    assert paths.shared_data_dir() == chosen
    monkeypatch.setenv(paths.SHARED_DATA_ENV_VAR, str(tmp_path / "missing"))  # a wrong setting falls through
    assert paths.shared_data_dir() == shared
    monkeypatch.setenv(paths.SHARED_DATA_ENV_VAR, "none")  # the suite as a fresh clone sees it (.ci/run)
    assert paths.shared_data_dir() is None


def test_the_notebooks_ship_in_the_package():
    """In the checkout glu runs the notebooks of ``notebooks/``; a wheel carries a copy in ``glu/notebooks/``
    (setup.py's build step; the slow wheel test runs them from an installed glu)."""
    assert paths.NOTEBOOKS_DIR == ROOT / "notebooks"
    setup = (ROOT / "setup.py").read_text()
    assert 'Path(self.build_lib, "glu", "notebooks")' in setup and 'Path("notebooks").glob("*.py")' in setup


def test_the_base_install_has_no_jupyter_and_no_rerun():
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    base = {re.split(r"[<>=\[ ;]", d)[0].lower() for d in meta["dependencies"]}
    assert not base & {"jupyterlab", "papermill", "ipykernel", "nbconvert", "rerun-sdk", "jupytext", "pgmpy"}
    extras = meta["optional-dependencies"]
    assert {"notebooks", "lab", "dask", "test"} <= set(extras)
    assert any(d.startswith("rerun-sdk") for d in extras["notebooks"])
    assert "license" in meta and isinstance(meta["license"], str)


IMPORT_TO_DISTRIBUTION = {
    "yaml": "pyyaml",
    "distributed": "dask",
    "requests": "pooch",
    "sklearn": "scikit-learn",
}
"""Import names that differ from the distribution that provides them (requests comes with pooch)."""


def _third_party_imports(files) -> dict[str, set[str]]:
    """Distribution → the files that import it (top-level or inside functions), for ``files``."""
    import ast

    found: dict[str, set[str]] = {}
    for f in files:
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.Import):
                names = [a.name.split(".")[0] for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module.split(".")[0]]
            else:
                continue
            for n in names:
                if n not in sys.stdlib_module_names and n != "glu":
                    found.setdefault(IMPORT_TO_DISTRIBUTION.get(n, n).lower(), set()).add(f.name)
    return found


def test_corpus_and_evaluate_need_only_the_base_and_dask_installs():
    """Everything `glu corpus` and `glu evaluate` import is declared in the base install or in [dask]."""
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]

    def names(deps):
        return {re.split(r"[<>=\[ ;]", d)[0].lower() for d in deps}

    allowed = names(meta["dependencies"]) | names(meta["optional-dependencies"]["dask"])
    pkg = ROOT / "glu"
    layers = ("bn", "data", "experiments", "gestures", "language", "sweep")
    files = [f for layer in layers for f in (pkg / layer).rglob("*.py")]
    files += [pkg / m for m in ("fusion.py", "schema.py", "evidence.py", "files.py", "paths.py")]
    files += [pkg / "cli" / "eval_cmds.py", pkg / "cli" / "common.py"]
    used = _third_party_imports(files)
    used.pop("pgmpy", None)  # tests/bn_reference.py: the tests' reference (pgmpy is a test dependency)
    missing = {d: sorted(fs) for d, fs in used.items() if d not in allowed}
    assert not missing, f"imported but not declared in the base or [dask] install: {missing}"


def test_reproduce_without_the_notebook_extra_says_what_to_install(monkeypatch, capsys):
    import importlib.util

    from glu.cli import main

    real = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util, "find_spec", lambda name, *a: None if name == "papermill" else real(name, *a)
    )
    assert main(["reproduce", "--quick", "--only", "03"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "pip install 'glu[notebooks]'" in err


def _run(cmd, **kw):
    return subprocess.run(cmd, capture_output=True, text=True, check=False, **kw)


def _install_wheel(tmp_path: Path, extra: str) -> tuple[Path, Path]:
    """Build the wheel and install it with ``extra`` in a new venv under ``tmp_path``: (python, glu)."""
    dist = tmp_path / "dist"
    r = _run([sys.executable, "-m", "build", "--wheel", "--outdir", str(dist), str(ROOT)])
    assert r.returncode == 0, r.stderr[-2000:]
    (wheel,) = dist.glob("glu-*.whl")
    venv = tmp_path / "venv"
    assert _run([sys.executable, "-m", "venv", str(venv)]).returncode == 0
    py, glu = venv / "bin" / "python", venv / "bin" / "glu"
    r = _run([str(py), "-m", "pip", "install", "--quiet", f"{wheel}[{extra}]"])
    assert r.returncode == 0, r.stderr[-2000:]
    return py, glu


def _fresh_env(tmp_path: Path, **extra: str) -> dict[str, str]:
    """The environment with its own XDG data and cache folders under ``tmp_path`` and no data folder set."""
    env = {
        **os.environ,
        "XDG_DATA_HOME": str(tmp_path / "xdg-data"),
        "XDG_CACHE_HOME": str(tmp_path / "xdg-cache"),
        **extra,
    }
    env.pop(paths.DATA_ENV_VAR, None)
    return env


@pytest.mark.slow
def test_the_wheel_in_a_fresh_venv_runs_from_an_empty_folder(tmp_path):
    """Build the wheel, install it with its notebooks extra in a new venv, run glu from an empty folder."""
    py, glu = _install_wheel(tmp_path, "notebooks")
    site = Path(
        _run(
            [str(py), "-c", "import glu, pathlib; print(pathlib.Path(glu.__file__).parent.parent)"]
        ).stdout.strip()
    )

    def snapshot():
        return sorted(
            (str(p), p.stat().st_size, p.stat().st_mtime_ns) for p in site.rglob("*") if p.is_file()
        )

    before = snapshot()
    empty = tmp_path / "empty"
    empty.mkdir()
    env = _fresh_env(tmp_path, RERUN_ANALYTICS="0", MPLBACKEND="Agg", PYTHONDONTWRITEBYTECODE="1")
    for cmd in (
        ["data", "info"],
        ["query", "--target", "ObjVel", "--evidence", "Action=tap"],
        ["describe", "--evidence", "Action=grasp", "ObjVel=slow", "--nbest", "2"],
    ):
        r = _run([str(glu), *cmd], cwd=empty, env=env)
        assert r.returncode == 0, (cmd, r.stderr)
    r = _run([str(glu), "reproduce", "--quick"], cwd=empty, env=env)
    assert r.returncode == 2 and "give an output folder (-o DIR)" in r.stderr
    r = _run([str(glu), "reproduce", "--quick", "-o", "out"], cwd=empty, env=env)
    assert r.returncode == 0, r.stderr[-3000:]
    assert (empty / "out" / "results" / "summary.json").is_file() and (
        empty / "out" / "site" / "index.html"
    ).is_file()
    assert sorted(p.name for p in empty.iterdir()) == ["out"]
    assert snapshot() == before, "something was written into site-packages"


@pytest.mark.slow
def test_corpus_and_evaluate_run_in_the_base_and_dask_installs(tmp_path):
    """The wheel with [dask] only (no notebooks, no test tools) in a fresh venv: `glu corpus` and a small
    `glu evaluate` run to the end (they once ended in "internal error … pyarrow")."""
    _, glu = _install_wheel(tmp_path, "dask")
    env = _fresh_env(tmp_path)
    work = tmp_path / "work"
    work.mkdir()
    r = _run(
        [str(glu), "corpus", "--data", "synthetic", "--episodes", "60", "-o", "c.parquet"], cwd=work, env=env
    )
    assert r.returncode == 0, r.stderr[-3000:]
    assert (work / "c.parquet").stat().st_size > 0
    cmd = ["evaluate", "--data", "synthetic", "--episodes", "120", "--scheduler", "synchronous", "-o", "ev"]
    r = _run([str(glu), *cmd], cwd=work, env=env)
    assert r.returncode == 0, r.stderr[-3000:]
    assert (work / "ev" / "results.parquet").is_file()


@pytest.mark.slow
def test_the_lower_bounds_resolve_together(tmp_path):
    """Every dependency pinned to its lower bound (all extras but test) resolves with pip's resolver."""
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    reqs = list(meta["dependencies"])
    for extra in ("notebooks", "lab", "dask"):
        reqs += [d for d in meta["optional-dependencies"][extra] if not d.startswith("glu")]
    pinned = []
    for d in reqs:
        m = re.match(r"^([A-Za-z0-9_.\-]+(?:\[[^\]]+\])?)\s*>=\s*([^,;\s]+)", d)
        assert m, f"{d}: every dependency needs a lower bound"
        pinned.append(f"{m.group(1)}=={m.group(2)}")
    r = _run(
        [
            sys.executable,
            "-m",
            "pip",
            "install",
            "--dry-run",
            "--ignore-installed",
            "--quiet",
            "--report",
            str(tmp_path / "report.json"),
            *pinned,
        ]
    )
    assert r.returncode == 0, "the lower bounds do not resolve together:\n" + r.stderr[-3000:]


def test_progress_bars_are_quiet_without_a_terminal_or_under_json(monkeypatch):
    from glu.cli.common import progress_bar

    assert progress_bar(3, "x", "file") is None  # pytest's stderr is not a terminal
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True, raising=False)
    assert progress_bar(3, "x", "file", quiet=True) is None
    bar = progress_bar(3, "x", "file")
    assert bar is not None
    bar.close()
