"""`glu reproduce` stops at once on Ctrl-C or SIGTERM: kernels killed, staging removed, nothing published."""

from __future__ import annotations

import fcntl
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from glu.paths import OUTPUT_KINDS, OutputLayout
from glu.run import publish
from glu.run.publish import OWNER, STEPS, Store

_SLOW = """# ---
# jupyter:
#   glu:
#     about: a test notebook
# ---

# %% tags=["parameters"]
data: str = None  # data folder
seed: int = 0  # seed
out_dir: str = None  # outputs

# %%
import os, time
from pathlib import Path
Path(out_dir, "figures").mkdir(parents=True, exist_ok=True)
Path(out_dir, "figures", "partial.png").write_bytes(b"not finished")
Path(MARK).write_text(str(os.getpid()))
time.sleep(120)
"""


def _as_from_a_terminal() -> None:
    """In the child before it starts glu: SIGINT handled as a terminal's command gets it. A suite started in
    the background (``make test &``) runs with SIGINT and SIGQUIT ignored, which its children inherit; glu
    would then rightly ignore the test's Ctrl-C."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


def _stop(proc: subprocess.Popen, sig: int, status: int) -> str:
    """Send ``sig`` to a running ``glu reproduce``; check it ends with ``status`` within 10 s (the goal is
    2 s; the bound leaves CI slack) and return its stderr."""
    t0 = time.monotonic()
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    stopped_in = time.monotonic() - t0
    assert proc.returncode == status, err
    assert stopped_in < 10, f"took {stopped_in:.1f} s to stop"
    return err


@pytest.mark.parametrize(("sig", "status"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_stops_the_run_at_once_and_publishes_nothing(tmp_path, sig, status):
    nbs, out = tmp_path / "nbs", tmp_path / "out"
    nbs.mkdir()
    marks = [tmp_path / f"kernel{k}.pid" for k in (1, 2)]
    for k, mark in enumerate(marks, start=1):
        (nbs / f"0{k}_slow.py").write_text(_SLOW.replace("MARK", repr(str(mark))))
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "glu",
            "reproduce",
            "--notebooks",
            str(nbs),
            "--data",
            "synthetic",
            "--out",
            str(out),
            "-j",
            "2",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=_as_from_a_terminal,
    )
    deadline = time.monotonic() + 120
    while not all(m.exists() for m in marks):
        assert proc.poll() is None, proc.stderr.read()
        assert time.monotonic() < deadline, "the notebooks did not start"
        time.sleep(0.2)
    kernels = [int(m.read_text()) for m in marks]
    err = _stop(proc, sig, status)
    assert err.strip().splitlines()[-1] in ("glu reproduce: interrupted", "glu reproduce: terminated")
    assert "Traceback" not in err
    time.sleep(0.5)
    assert not any(_alive(pid) for pid in kernels), "a kernel survived"
    assert not (out / "figures").exists() and not (out / "results").exists()  # nothing published
    assert _runs(out) == []  # the staging run removed on the way out


def _runs(out: Path) -> list[str]:
    """The run folders in the store of ``out``."""
    store = out / ".glu-runs"
    return (
        sorted(d.name for d in store.iterdir() if d.is_dir() and d.name.startswith("r"))
        if store.is_dir()
        else []
    )


def test_a_staging_run_left_by_a_killed_process_is_removed_by_the_next_start(tmp_path):
    store = Store(OutputLayout.under(tmp_path))
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    stale, live, unowned = store.begin(), store.begin(), store.begin()
    (stale / OWNER).write_text(str(dead.pid))  # a run killed while it staged
    (unowned / OWNER).unlink()  # an earlier publication whose removal was stopped
    mine = store.begin()  # a start removes what stopped runs left, and only that
    assert not stale.exists() and not unowned.exists() and live.exists() and mine.exists()
    assert Store(OutputLayout.under(tmp_path / "none")).clean() == []


# ----------------------------------------------- a stop between any two steps of the publication
_RUN = """# ---
# jupyter:
#   glu:
#     about: a test notebook whose files name the run (its seed)
#     figures:
#     - NAME
#     tables:
#     - tNAME
# ---

# %% tags=["parameters"]
data: str = None  # data folder
seed: int = 0  # seed
out_dir: str = None  # outputs

# %%
import json
from pathlib import Path
for sub, file in (("figures", "NAME.png"), ("figures", "NAME.svg"), ("results", "tNAME.csv")):
    Path(out_dir, sub).mkdir(parents=True, exist_ok=True)
    Path(out_dir, sub, file).write_text(f"run {seed}")
doc = {"meta": {"name": "tNAME", "notebook": NOTEBOOK}, "rows": [{"run": seed}]}
Path(out_dir, "results", "tNAME.json").write_text(json.dumps(doc))
"""


def _notebooks(folder: Path) -> Path:
    folder.mkdir()
    for nb, name in (("01_a", "a"), ("02_b", "b")):
        (folder / f"{nb}.py").write_text(_RUN.replace("NAME", name).replace("NOTEBOOK", repr(nb)))
    return folder


def _fake_kernel(src, out_ipynb, parameters, cwd=None, handle=None):
    """Execute a test notebook's code cells in this process (the publication, not the kernels, is tested)."""
    import jupytext
    import nbformat

    nb = jupytext.read(src)
    scope = dict(parameters)
    for cell in nb.cells[1:]:
        if cell.cell_type == "code":
            exec(cell.source, scope)
    out_ipynb.parent.mkdir(parents=True, exist_ok=True)
    nbformat.write(nb, out_ipynb)


def _fake_site(layout, summary, log, notebooks_dir, work, published):
    """A site that names its run: the seed of its figures."""
    layout.site.mkdir()
    (layout.site / "index.html").write_text((layout.figures / "a.png").read_text())


def _published(out: Path) -> dict[str, bytes]:
    """Every file a reader sees through the places of ``out``, with its bytes."""
    return {
        f"{kind}/{f.relative_to(out / kind).as_posix()}": f.read_bytes()
        for kind in OUTPUT_KINDS
        for f in sorted((out / kind).rglob("*"))
        if f.is_file()
    }


def _seeds(files: dict[str, bytes]) -> set[int]:
    """The runs (seeds) the published files come from."""
    import json

    seeds = set()
    for name, data in files.items():
        if name == "results/summary.json":
            seeds |= {t["rows"][0]["run"] for t in json.loads(data)["tables"].values()}
        elif name.endswith((".png", ".svg", ".csv", ".html")) and data.startswith(b"run "):
            seeds.add(int(data.split()[1]))
        elif name == "results/summary.csv":
            seeds |= {int(line.rsplit(",", 1)[1]) for line in data.decode().splitlines()[1:]}
    return seeds


def _reproduce_in_process(out: Path, nbs: Path, seed: int) -> None:
    from glu.run.reproduce import reproduce

    reproduce(data="synthetic", out=out, notebooks_dir=nbs, seed=seed, jobs=1, log=lambda _: None)


@pytest.mark.parametrize("step", STEPS)
def test_a_stop_between_any_two_steps_of_the_publication_leaves_one_whole_run(tmp_path, monkeypatch, step):
    """The published set — figures, tables, executed notebooks, summary, site — is wholly the previous run
    until the pointer is swapped, wholly the new one after; no staging is left once the next run starts."""
    import glu.run.reproduce as reproduce_module
    import glu.run.site as site_module

    monkeypatch.setattr(reproduce_module, "run_notebook", _fake_kernel)
    monkeypatch.setattr(site_module, "build_site", _fake_site)
    nbs, out = _notebooks(tmp_path / "nbs"), tmp_path / "out"
    _reproduce_in_process(out, nbs, seed=1)
    old = _published(out)
    assert _seeds(old) == {1} and "site/index.html" in old and "results/summary.json" in old

    def stop(name: str) -> None:
        if name == step:
            raise KeyboardInterrupt

    monkeypatch.setattr(publish, "STEP_HOOK", stop)
    with pytest.raises(KeyboardInterrupt):
        _reproduce_in_process(out, nbs, seed=2)
    now = _published(out)
    assert now.keys() == old.keys()  # the same files: no mixture of a partial publication
    if STEPS.index(step) < STEPS.index("pointer"):
        assert now == old  # the previous run, byte for byte
        assert len(_runs(out)) == 1  # and the staged run removed on the way out
    else:
        assert _seeds(now) == {2}  # wholly the new run
    monkeypatch.setattr(publish, "STEP_HOOK", None)
    Store(OutputLayout.under(out)).clean()  # what the next start does first
    assert len(_runs(out)) == 1 and _published(out) == now


_STOP_AT = """
import os, signal, sys
from glu.run import publish
def hook(name):
    if name == sys.argv[1]:
        os.kill(os.getpid(), getattr(signal, sys.argv[2]))
publish.STEP_HOOK = hook
from glu.cli import main
sys.exit(main(sys.argv[3:]))
"""


@pytest.mark.parametrize(
    ("step", "sig"),
    [("pointer", "SIGINT"), pytest.param("recorded", "SIGKILL", marks=pytest.mark.slow)]
    + [pytest.param(s, "SIGKILL", marks=pytest.mark.slow) for s in STEPS if s != "recorded"],
)
def test_a_signal_between_two_steps_of_a_real_run_leaves_one_whole_run(tmp_path, step, sig):
    """The same with real kernels and a real signal: Ctrl-C (the run ends, status 130) or SIGKILL (nothing
    runs on the way out; the next start cleans up)."""
    nbs, out = _notebooks(tmp_path / "nbs"), tmp_path / "out"
    argv = [
        "reproduce",
        "--notebooks",
        str(nbs),
        "--data",
        "synthetic",
        "-o",
        str(out),
        "-j",
        "1",
        "--no-site",
    ]
    first = subprocess.run(
        [sys.executable, "-c", _STOP_AT, "none", sig, *argv, "--seed", "1"],
        capture_output=True,
        text=True,
        timeout=300,
        preexec_fn=_as_from_a_terminal,
    )
    assert first.returncode == 0, first.stderr
    old = _published(out)
    second = subprocess.run(
        [sys.executable, "-c", _STOP_AT, step, sig, *argv, "--seed", "2"],
        capture_output=True,
        text=True,
        timeout=300,
        preexec_fn=_as_from_a_terminal,
    )
    assert second.returncode == (130 if sig == "SIGINT" else -9), second.stderr
    now = _published(out)
    assert now.keys() == old.keys()
    assert now == old if STEPS.index(step) < STEPS.index("pointer") else _seeds(now) == {2}
    Store(OutputLayout.under(out)).clean()
    assert len(_runs(out)) == 1 and _published(out) == now


# -------------------------------------------------------- signals at random moments, kernel start-up included
def _processes_with(token: str) -> list[int]:
    """The processes whose environment holds ``token`` (the run and every kernel it started)."""
    found = []
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                if token.encode() in (d / "environ").read_bytes():
                    found.append(int(d.name))
            except OSError:
                pass
    return found


@pytest.mark.slow
@pytest.mark.parametrize("moment", [0.3, 1.0, 2.0, 3.0, 4.5])
@pytest.mark.parametrize(("sig", "status"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_at_any_moment_stops_the_run_and_its_kernels(tmp_path, sig, status, moment):
    """Seconds after the start — parsing, kernel start-up (3–5 s), or running — the run stops promptly."""
    import uuid

    nbs, out = tmp_path / "nbs", tmp_path / "out"
    nbs.mkdir()
    for k in (1, 2):
        (nbs / f"0{k}_slow.py").write_text(_SLOW.replace("MARK", repr(str(tmp_path / f"kernel{k}.pid"))))
    token = f"glu-test-{uuid.uuid4().hex}"
    cmd = [sys.executable, "-m", "glu", "reproduce", "--notebooks", str(nbs), "--data", "synthetic"]
    proc = subprocess.Popen(
        [*cmd, "--out", str(out), "-j", "2"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "GLU_TEST_TOKEN": token},
        preexec_fn=_as_from_a_terminal,
    )
    time.sleep(moment)
    err = _stop(proc, sig, status)
    assert "Traceback" not in err and "CancelledError" not in err
    deadline = time.monotonic() + 5
    while _processes_with(token) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not _processes_with(token), "a kernel survived the run"
    assert not (out / "figures").exists() and not (out / "results").exists()  # nothing published


_FAILS = """# ---
# jupyter:
#   glu:
#     about: a test notebook that fails
# ---

# %% tags=["parameters"]
data: str = None  # data folder
seed: int = 0  # seed
out_dir: str = None  # outputs

# %%
raise ValueError("the notebook's own error")
"""


@pytest.mark.slow
def test_a_failing_notebook_ends_with_its_name_cell_and_error_not_cancelled(tmp_path):
    """The notebooks still queued when one fails are cancelled; the run ends with the failure itself."""
    nbs, out = tmp_path / "nbs", tmp_path / "out"
    nbs.mkdir()
    (nbs / "01_fails.py").write_text(_FAILS)
    for k in (2, 3, 4):
        (nbs / f"0{k}_slow.py").write_text(_SLOW.replace("MARK", repr(str(tmp_path / f"kernel{k}.pid"))))
    cmd = [sys.executable, "-m", "glu", "reproduce", "--notebooks", str(nbs), "--data", "synthetic"]
    proc = subprocess.run([*cmd, "--out", str(out), "-j", "1"], capture_output=True, text=True, timeout=300)
    last = proc.stderr.strip().splitlines()[-1]
    assert proc.returncode == 1, proc.stderr  # a failed run, not bad input
    assert "01_fails" in last and "cell" in last and "the notebook's own error" in last, last
    assert "CancelledError" not in proc.stderr and "internal error" not in proc.stderr


# ---------------------------------------------------------------- one run at a time
def test_a_second_reproduce_on_the_same_folder_is_refused_naming_the_first(tmp_path, capsys):
    from glu.cli import main
    from glu.run.lock import LOCK_FILE, run_lock

    out = tmp_path / "out"
    with run_lock(out):
        assert (out / LOCK_FILE).read_text().strip() == str(os.getpid())
        status = main(["reproduce", "--data", "synthetic", "--quick", "--out", str(out)])
        err = capsys.readouterr().err.strip().splitlines()
    assert status == 2 and len(err) == 1
    assert f"process {os.getpid()}" in err[0] and "another glu reproduce" in err[0]
    assert not (out / LOCK_FILE).exists()  # released at the end of the first run


def test_a_stale_lock_of_a_dead_process_is_taken_over(tmp_path):
    from glu.run.lock import LOCK_FILE, run_lock

    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    (tmp_path / LOCK_FILE).write_text(f"{dead.pid}\n")
    with run_lock(tmp_path) as lock:
        assert lock.read_text().strip() == str(os.getpid())


@pytest.mark.parametrize("ending", ["removed", "replaced"])
def test_a_lock_file_the_ending_run_removes_meanwhile_is_not_the_one_held(tmp_path, monkeypatch, ending):
    """Between opening the lock file and locking it, the run that held it ends and removes it (and another
    run may already have made a new one): the lock is taken on the file at the path, not on the old one."""
    from glu.run import lock as lock_module

    path, real_flock, opened = tmp_path / lock_module.LOCK_FILE, fcntl.flock, []

    def flock(fd, op):
        opened.append(os.fstat(fd).st_ino)
        if len(opened) == 1:  # the first open file: removed before it is locked
            path.unlink()
            if ending == "replaced":
                path.write_text("")
        real_flock(fd, op)

    monkeypatch.setattr(lock_module.fcntl, "flock", flock)
    with lock_module.run_lock(tmp_path) as lock:
        assert len(opened) == 2 and os.stat(lock).st_ino == opened[1]
        assert lock.read_text() == f"{os.getpid()}\n"
    assert not path.exists()


def test_two_runs_at_once_one_of_them_refused(tmp_path):
    """Two processes take the lock at the same moment: exactly one holds it."""
    script = (
        "import sys, time\n"
        "from glu.run.lock import run_lock, RunLockedError\n"
        "try:\n"
        "    with run_lock(sys.argv[1]):\n"
        "        print('held', flush=True); time.sleep(3)\n"
        "except RunLockedError as e:\n"
        "    print('refused', e)\n"
    )
    procs = [
        subprocess.Popen([sys.executable, "-c", script, str(tmp_path)], stdout=subprocess.PIPE, text=True)
        for _ in range(3)
    ]
    outs = [p.communicate(timeout=60)[0] for p in procs]
    assert sorted(o.split()[0] for o in outs) == ["held", "refused", "refused"], outs


@pytest.mark.parametrize(
    ("stop", "status", "word"), [(KeyboardInterrupt, 130, "interrupted"), (None, 143, "terminated")]
)
def test_an_interrupt_wrapped_by_compiled_code_is_still_an_interrupt(monkeypatch, capsys, stop, status, word):
    """numba's dispatcher turns a signal raised while compiled code runs into a SystemError (hmm train)."""
    from glu.cli import bn_cmds, main
    from glu.errors import Terminated

    def handler(args):
        try:
            raise (stop or Terminated)()
        except KeyboardInterrupt:
            raise SystemError("CPUDispatcher(<function f>) returned a result with an exception set")  # noqa: B904

    monkeypatch.setattr(bn_cmds, "_edges", handler)
    assert main(["bn", "edges", "model.json"]) == status
    assert capsys.readouterr().err == f"glu bn edges: {word}\n"


def test_a_full_disk_during_the_site_build_publishes_nothing_and_leaves_no_staging(tmp_path, monkeypatch):
    """The site is built inside the staged run: a disk that fills up there leaves the previous run published
    and nothing of the new one behind (no site.new beside the old site)."""
    import errno

    import glu.run.reproduce as reproduce_module
    import glu.run.site as site_module

    monkeypatch.setattr(reproduce_module, "run_notebook", _fake_kernel)
    monkeypatch.setattr(site_module, "build_site", _fake_site)
    nbs, out = _notebooks(tmp_path / "nbs"), tmp_path / "out"
    _reproduce_in_process(out, nbs, seed=1)
    old = _published(out)

    def full(layout, *args, **kwargs):
        layout.site.mkdir()
        (layout.site / "index.html").write_text("half")
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(site_module, "build_site", full)
    with pytest.raises(OSError, match="No space left"):
        _reproduce_in_process(out, nbs, seed=2)
    assert _published(out) == old and len(_runs(out)) == 1
    assert sorted(p.name for p in out.iterdir()) == sorted([".glu-runs", *OUTPUT_KINDS])


def test_an_unexpected_error_is_one_line_asking_for_a_report_and_its_traceback_on_request(
    monkeypatch, capsys
):
    from glu.cli import bn_cmds, main

    def handler(args):
        raise RuntimeError("boom")

    monkeypatch.setattr(bn_cmds, "_edges", handler)
    line = (
        "glu bn edges: internal error: RuntimeError: boom — this is a bug in glu; please report it with the "
        "command you ran (set GLU_DEBUG=1 or pass --debug for the traceback)\n"
    )
    assert main(["bn", "edges", "model.json"]) == 1
    assert capsys.readouterr().err == line
    for argv, env in ((["--debug", "bn", "edges", "model.json"], "0"), (["bn", "edges", "model.json"], "1")):
        monkeypatch.setenv("GLU_DEBUG", env)
        assert main(argv) == 1
        err = capsys.readouterr().err
        assert err.startswith("Traceback (most recent call last):\n") and err.endswith(
            "RuntimeError: boom\n" + line
        )


def test_a_closed_pipe_ends_quietly_and_warnings_are_said_once(monkeypatch, capsys):
    """`glu … | head`: the reader went away, status 0 and nothing said; a warning about the data folder is
    one line however often it is raised, any other warning as Python shows it."""
    import warnings

    from glu.cli import bn_cmds, main
    from glu.data.source import DataWarning

    def closed(args):
        raise BrokenPipeError(32, "Broken pipe")

    def warns(args):
        for _ in range(3):
            warnings.warn(DataWarning("data/real is modified"), stacklevel=1)
        warnings.warn("a user warning", UserWarning, stacklevel=1)
        return 0

    monkeypatch.setattr(bn_cmds, "_edges", closed)
    assert main(["bn", "edges", "model.json"]) == 0
    assert capsys.readouterr() == ("", "")
    monkeypatch.setattr(bn_cmds, "_edges", warns)
    with pytest.warns(UserWarning, match="a user warning"):  # passed on to Python's (here pytest's) handler
        assert main(["bn", "edges", "model.json"]) == 0
    assert capsys.readouterr().err == "glu bn edges: warning: data/real is modified; results say so\n"


def test_an_interrupt_while_the_parser_is_built_and_main_outside_the_main_thread(monkeypatch, capsys):
    import signal
    import threading

    import glu.cli as cli
    from glu.cli import bn_cmds, main

    def interrupted(argv):
        raise KeyboardInterrupt

    with monkeypatch.context() as m:
        m.setattr(cli, "build_parser", interrupted)
        assert main(["bn", "edges", "model.json"]) == 130
    assert capsys.readouterr().err == "glu: interrupted\n"
    monkeypatch.setattr(bn_cmds, "_edges", lambda args: 0)
    before, status = signal.getsignal(signal.SIGTERM), []
    thread = threading.Thread(target=lambda: status.append(main(["bn", "edges", "model.json"])))
    thread.start()
    thread.join(60)
    assert status == [0] and signal.getsignal(signal.SIGTERM) is before


def test_a_site_that_cannot_be_built_is_said_after_the_run_is_published_without_it(tmp_path, monkeypatch):
    import glu.run.reproduce as reproduce_module
    import glu.run.site as site_module
    from glu.run.reproduce import reproduce
    from glu.run.site import SiteError

    def broken(layout, *args, **kwargs):
        raise SiteError("the documentation site was not built: 1 Sphinx warning(s)")

    monkeypatch.setattr(reproduce_module, "run_notebook", _fake_kernel)
    monkeypatch.setattr(site_module, "build_site", broken)
    nbs, out, said = _notebooks(tmp_path / "nbs"), tmp_path / "out", []
    with pytest.raises(SiteError) as e:
        reproduce(data="synthetic", out=out, notebooks_dir=nbs, seed=3, log=said.append)
    assert str(e.value) == (
        "the documentation site was not built: 1 Sphinx warning(s)\n"
        "the run was published without its site (`make docs` builds it again)"
    )
    files = _published(out)
    assert (
        _seeds(files) == {3}
        and "results/summary.json" in files
        and not any(f.startswith("site/") for f in files)
    )
    assert said[-1].startswith("glu reproduce: done in ")


@pytest.mark.slow
def test_on_a_terminal_a_bar_counts_the_notebooks_and_shows_the_running_ones(tmp_path, monkeypatch):
    import io

    import glu.run.reproduce as reproduce_module
    import glu.run.site as site_module
    from glu.run.reproduce import reproduce

    def slow_kernel(src, out_ipynb, parameters, cwd=None, handle=None):
        handle._cell_started(1, 3, {"cell_type": "code", "source": "x = 1"})
        time.sleep(0.6)  # long enough for the bar's ticks (every 0.25 s)
        _fake_kernel(src, out_ipynb, parameters)

    monkeypatch.setattr(reproduce_module, "run_notebook", slow_kernel)
    monkeypatch.setattr(site_module, "build_site", _fake_site)
    terminal = io.StringIO()
    monkeypatch.setattr(sys, "stderr", terminal)
    nbs, said = _notebooks(tmp_path / "nbs"), []
    reproduce(
        data="synthetic", out=tmp_path / "out", notebooks_dir=nbs, jobs=2, log=said.append, progress=True
    )
    text = terminal.getvalue()
    assert "[1/2] " in text and "[2/2] " in text and ": ok in " in text  # written above the bar
    assert re.search(r"0/2 \[.*(01_a|02_b) cell 2/3 \d+s", text)  # the running notebooks, their cell
    assert not any(line.startswith("[") for line in said)  # not also in the plain log
