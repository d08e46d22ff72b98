"""Hostile inputs of the surface issue 34 audited: schedulers that never answer, answer garbage or hang up;
names in a run's files that would be paths; declared sizes too large to allocate; data folders that are
truncated or corrupted. Each gives one line, exit status 2, and leaves nothing half-written."""

from __future__ import annotations

import socket
import threading
from collections.abc import Iterator

import pytest
from cli_run import run

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
