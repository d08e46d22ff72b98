"""`glu reproduce` stops at once on Ctrl-C or SIGTERM: kernels killed, staging removed, nothing published."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from glu.run.reproduce import OWNER_FILE, clean_stale_staging

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
    assert not (out / ".glu-staging").exists() or not any((out / ".glu-staging").iterdir())


def test_a_staging_folder_left_by_a_killed_run_is_removed(tmp_path):
    root = tmp_path / ".glu-staging"
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    stale, live, unowned = root / "aaa", root / "bbb", root / "ccc"
    for d in (stale, live, unowned):
        (d / "x").mkdir(parents=True)
    (stale / OWNER_FILE).write_text(str(dead.pid))
    (live / OWNER_FILE).write_text(str(os.getpid()))
    removed = clean_stale_staging(root)
    assert sorted(removed) == sorted([stale, unowned])
    assert live.exists() and not stale.exists() and not unowned.exists()
    assert clean_stale_staging(Path(tmp_path / "none")) == []


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
