"""Hostile inputs of the surface issue 34 audited: schedulers that never answer, answer garbage or hang up;
names in a run's files that would be paths; declared sizes too large to allocate; data folders that are
truncated or corrupted. Each gives one line, exit status 2, and leaves nothing half-written."""

from __future__ import annotations

import json
import socket
import subprocess
import sys
import threading
from collections.abc import Iterator

import pytest
from cli_run import run
from tiny_notebook import TINY_NOTEBOOK

from glu.errors import DataError
from glu.machine import check_reachable


# ------------------------------------------------------------------ Dask schedulers that misbehave
@pytest.fixture(params=["silent", "garbage", "hangs up"])
def hostile_scheduler(request) -> Iterator[tuple[str, str]]:
    """A server on 127.0.0.1 that accepts connections and then never answers, answers garbage, or closes."""
    kind = request.param
    server = socket.socket()
    server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    server.bind(("127.0.0.1", 0))
    server.listen(16)
    server.settimeout(0.2)
    held: list[socket.socket] = []
    stop = threading.Event()

    def serve() -> None:
        while not stop.is_set():
            try:
                conn, _ = server.accept()
            except OSError:
                continue
            if kind == "garbage":
                try:
                    conn.sendall(b"\xff" * 64 + b"HTTP/1.1 200 OK\r\n\r\n" + bytes(range(256)) * 4)
                except OSError:
                    pass
            if kind == "hangs up":
                conn.close()
            else:
                held.append(conn)

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    try:
        yield kind, f"tcp://127.0.0.1:{server.getsockname()[1]}"
    finally:
        stop.set()
        thread.join(5)
        for c in held:
            c.close()
        server.close()


_SAID = {
    "silent": "accepted the connection but did not answer within 2 s",
    "garbage": "is not a Dask scheduler that answers",
    "hangs up": "accepted the connection and closed it",
}


def test_a_scheduler_that_misbehaves_is_refused_in_one_line_within_its_deadline(hostile_scheduler):
    kind, address = hostile_scheduler
    with pytest.raises(DataError) as e:
        check_reachable(address, timeout=2)
    assert _SAID[kind] in str(e.value) and address in str(e.value) and "\n" not in str(e.value)


@pytest.mark.parametrize("command", ["evaluate", "learning-curves"])
def test_evaluate_and_learning_curves_refuse_a_garbage_scheduler_and_write_nothing(capsys, tmp_path, command):
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(4)

    def serve() -> None:
        conn, _ = server.accept()  # the reachability check's connection
        conn.close()
        conn, _ = server.accept()  # Dask's: a reply that is not Dask's protocol
        conn.sendall(b"\x7f" * 4096)
        conn.close()

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    out = tmp_path / "out"
    argv = [command, "--scheduler", f"tcp://127.0.0.1:{server.getsockname()[1]}", "-o", str(out)]
    status, _, err = run(capsys, *argv)
    server.close()
    assert status == 2 and err.count("\n") == 1, err
    assert "internal error" not in err and "tcp://127.0.0.1" in err
    assert not out.exists()


# ------------------------------------------------------------------ a run's names and files, read back


@pytest.fixture(scope="module")
def published(tmp_path_factory):
    """A run published (without its site) in a folder of its own."""
    from glu.run.reproduce import reproduce

    root = tmp_path_factory.mktemp("published")
    (root / "nbs").mkdir()
    (root / "nbs" / "01_a.py").write_text(TINY_NOTEBOOK)
    reproduce(data="synthetic", out=root / "out", notebooks_dir=root / "nbs", site=False, log=lambda _: None)
    return root / "out"


def _summary(out):
    return json.loads((out / "results" / "summary.json").read_text())


def _tree(folder):
    return {
        str(p): p.read_bytes()
        for p in sorted(folder.rglob("*"))
        if p.is_file() and "site-source" not in p.parts
    }


@pytest.mark.parametrize(
    ("change", "said"),
    [
        (lambda s: [s], "not an object"),
        (lambda s: {**s, "notebooks": "01_a"}, "no list of notebooks"),
        (lambda s: {**s, "notebooks": [{"name": "../../victim", "status": "ok"}]}, "'../../victim'"),
        (lambda s: {**s, "notebooks": [{"name": "/etc/victim"}]}, "'/etc/victim'"),
        (lambda s: {**s, "figures_by_notebook": {"../../x.png": "01_a"}}, "'../../x.png'"),
        (lambda s: {**s, "recordings": [7]}, "recordings: 7"),
        (lambda s: {**s, "notebooks": [{"name": "01_a", "seconds": "a lot"}]}, "seconds is not a number"),
        (lambda s: {**s, "versions": ["numpy"]}, "versions: expected dict"),
        (lambda s: {**s, "comparison_with_reference": [{"table": 1}]}, "is not a comparison"),
        (lambda s: {**s, "tables": {"t": ["x"]}}, "tables['t']: not a table (its meta and rows)"),
    ],
)
def test_make_docs_refuses_a_malformed_summary_in_one_line_and_writes_nowhere(
    published, tmp_path, monkeypatch, capsys, change, said
):
    from glu.run import site as site_module

    current = (published / ".glu-runs" / "current").resolve()
    good = (current / "results" / "summary.json").read_bytes()
    monkeypatch.chdir(tmp_path)
    outside = _tree(published.parent) | _tree(tmp_path)
    try:
        (current / "results" / "summary.json").write_text(json.dumps(change(json.loads(good))))
        status = site_module.main(["--out", str(published)])
    finally:
        (current / "results" / "summary.json").write_bytes(good)
    err = capsys.readouterr().err
    assert status == 2 and err.count("\n") == 1 and said in err, err
    assert _tree(published.parent) | _tree(tmp_path) == outside  # nothing written, inside or out
    assert (published / ".glu-runs" / "current").resolve() == current


@pytest.mark.parametrize("content", [b"", b'{"cells": [', b"\x89PNG\r\n", b'{"cells": 3, "nbformat": 4}'])
def test_make_docs_refuses_a_truncated_or_empty_executed_notebook_in_one_line(published, capsys, content):
    from glu.run import site as site_module

    executed = (published / ".glu-runs" / "current").resolve() / "notebooks" / "01_a.ipynb"
    good = executed.read_bytes()
    try:
        executed.write_bytes(content)
        status = site_module.main(["--out", str(published)])
    finally:
        executed.write_bytes(good)
    err = capsys.readouterr().err
    assert (
        status == 2 and err.count("\n") == 1 and "01_a.ipynb" in err and "not a readable notebook" in err
    ), err


# ------------------------------------------------------------------ declared sizes, before allocation
def _limited(argv: list[str], address_space: int) -> subprocess.CompletedProcess:
    """``glu ARGV`` in a process whose address space is limited (``ulimit -v``)."""
    import resource

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (address_space, address_space))

    return subprocess.run(
        [sys.executable, "-m", "glu", *argv], capture_output=True, text=True, timeout=300, preexec_fn=limit
    )


@pytest.mark.parametrize("episodes", ["1000000000000", "99999999999999999999999"])
def test_learn_gestures_refuses_episodes_beyond_memory_before_any_work(capsys, tmp_path, episodes):
    out = tmp_path / "r.json"
    status, _, err = run(capsys, "learn-gestures", "--labels", "hard", "--episodes", episodes, "-o", str(out))
    assert status == 2 and err.count("\n") == 1 and "needs about" in err and "of memory" in err, err
    assert not out.exists()


def test_learn_gestures_needs_an_episode_per_action(capsys, tmp_path):
    status, _, err = run(
        capsys,
        "learn-gestures",
        "--labels",
        "unsupervised",
        "--episodes",
        "1",
        "-o",
        str(tmp_path / "r.json"),
    )
    assert status == 2 and "at least one episode per action (3" in err and err.count("\n") == 1, err


def test_an_episodes_memory_is_within_what_the_check_assumes():
    """The bound ``learn-gestures`` checks ``--episodes`` against (EPISODE_BYTES) is above the measured
    peak of simulating episodes (tracemalloc, 200 episodes)."""
    import tracemalloc

    from glu.cli.learn_cmds import EPISODE_BYTES, _engine
    from glu.studies.learning.self_supervised import AMBIGUITIES, simulate_episodes

    engine, _ = _engine("synthetic")
    tracemalloc.start()
    try:
        simulate_episodes(engine, AMBIGUITIES["mixed"], 200, 0)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak / 200 < EPISODE_BYTES


def test_max_table_beyond_the_memory_limit_is_one_line():
    r = _limited(["query", "--max-table", "100000000000", "--target", "Action"], 3 * 2**30)
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "--max-table 100,000,000,000" in r.stderr, (
        r.stderr
    )


def test_a_model_file_too_large_to_read_under_the_limit_is_refused_before_reading(tmp_path):
    big = tmp_path / "big.bif"
    with open(big, "wb") as f:  # 200 MB, sparse: never read
        f.truncate(200 * 2**20)
    r = _limited(["query", "--model", str(big), "--target", "A"], 2 * 2**30)
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "big.bif (200.00 MiB" in r.stderr, r.stderr


def test_an_unforeseen_memory_error_is_one_line(capsys, monkeypatch):
    from glu.cli import bn_cmds

    def exhausted(args):
        raise MemoryError

    monkeypatch.setattr(bn_cmds, "_edges", exhausted)
    status, _, err = run(capsys, "bn", "edges", "model.json")
    assert status == 2 and err.startswith("glu bn edges: error: out of memory") and err.count("\n") == 1


# ------------------------------------------------------------------ data folders, verified
def _copy_of_the_data(shared_data, dest):
    import shutil

    shutil.copytree(shared_data / "affordance-words", dest / "affordance-words")
    return dest / "affordance-words" / "sent-1-5_lab_aff_bag.txt"


@pytest.mark.parametrize(
    ("damage", "said"),
    [
        (lambda b: b[: len(b) // 7], "columns, expected 57"),  # cut in the middle of a line
        (lambda b: b[:5000] + bytes(range(128, 256)) + b[5256:], "not UTF-8 text"),  # binary garbage
        (lambda b: b"", ""),  # empty
    ],
)
def test_a_truncated_or_corrupted_data_file_is_refused_in_one_line(
    capsys, tmp_path, shared_data, damage, said
):
    table = _copy_of_the_data(shared_data, tmp_path / "data")
    table.write_bytes(damage(table.read_bytes()))
    out = tmp_path / "r.json"
    argv = ["learn-gestures", "--labels", "hard", "--episodes", "30", "--data", str(tmp_path / "data")]
    status, _, err = run(capsys, *argv, "-o", str(out))
    assert status == 2 and said in err and "sent-1-5_lab_aff_bag.txt" in err, err
    assert err.count("glu learn-gestures: error:") == 1 and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1, err  # the refusal alone: no "published data modified" first
    assert not out.exists()


def test_the_published_data_modified_is_said_as_such_and_never_named_as_published(
    capsys, tmp_path, shared_data
):
    table = _copy_of_the_data(shared_data, tmp_path / "data")
    lines = table.read_text().splitlines(keepends=True)
    table.write_text("".join(lines[:200]))  # cut at a line: it still reads, as 199 experiments
    out = tmp_path / "r.json"
    argv = ["learn-gestures", "--labels", "hard", "--episodes", "30", "--data", str(tmp_path / "data")]
    status, stdout, err = run(capsys, *argv, "-o", str(out))
    assert status == 0, err
    warning = [line for line in err.splitlines() if "warning" in line]
    assert (
        len(warning) == 1
        and "the published data modified: affordance-words/sent-1-5_lab_aff_bag.txt" in warning[0]
    )
    assert "real data:" not in stdout and "the published data modified" in stdout
    meta = json.loads(out.read_text())["meta"]
    assert "the published data modified" in json.dumps(meta) and "real data:" not in json.dumps(meta)
