"""Where the code runs (glu.machine): memory, the viewer, Ctrl-C, Dask clusters and schedulers, including the
cases of another platform or a missing extra."""

from __future__ import annotations

import asyncio
import logging
import signal
import socket
import subprocess
import sys
import threading

import pytest

from glu import machine
from glu.errors import DataError, MissingDependencyError


def test_meminfo_reads_a_kb_field_and_nothing_else(tmp_path):
    status = tmp_path / "status"
    status.write_text("Name:\tpython\nVmSize:\t  2048 kB\nVmRSS:\tmany kB\n")
    assert machine._meminfo("VmSize", str(status)) == 2048 * 1024
    assert machine._meminfo("VmPeak", str(status)) is None  # no such field
    assert machine._meminfo("VmRSS", str(status)) is None  # not a number
    assert machine._meminfo("VmSize", str(tmp_path / "none")) is None  # no such file (macOS, Windows)


def test_without_proc_or_resource_nothing_is_known_and_nothing_refused(monkeypatch):
    """Windows has neither /proc nor the resource module: the available memory is unknown (it raised
    ModuleNotFoundError from every memory check before) and no input is refused for its size."""
    monkeypatch.setitem(sys.modules, "resource", None)
    monkeypatch.setattr(machine, "_meminfo", lambda *a: None)
    assert machine.available_memory() is None
    machine.check_memory(1e30, "a huge input")


def test_without_rerun_notebook_there_is_no_viewer(monkeypatch):
    monkeypatch.setitem(sys.modules, "rerun.notebook", None)
    assert machine.viewer_class() is None


def test_ctrl_c_held_runs_the_block_where_there_are_no_signal_masks(monkeypatch):
    monkeypatch.delattr(signal, "pthread_sigmask")
    ran = []
    with machine.ctrl_c_held():
        ran.append(1)
    assert ran == [1]


class _Nanny:
    def __init__(self, pid):
        self.pid = pid


class _Cluster:
    """What glu uses of a LocalCluster: its workers' nannies (with their process ids) and close()."""

    def __init__(self, *pids):
        self.workers = {k: _Nanny(pid) for k, pid in enumerate(pids)}
        self.closed = 0

    def close(self):
        self.closed += 1


@pytest.fixture
def worker_process():
    p = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    yield p
    p.kill()
    p.wait()


def test_an_interrupt_kills_the_workers_before_the_cluster_is_closed(worker_process):
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()  # a worker that already exited: its pid is skipped silently
    cluster = _Cluster(None, gone.pid, worker_process.pid)
    machine.close_cluster(None, KeyboardInterrupt())  # no cluster: nothing to do
    machine.close_cluster(cluster, ValueError("bad"))  # any other error: closed, the workers left to it
    assert cluster.closed == 1 and worker_process.poll() is None
    machine.close_cluster(cluster, KeyboardInterrupt())
    assert worker_process.wait(10) == -signal.SIGKILL and cluster.closed == 2


def test_dask_logs_are_silent_in_the_block_and_as_before_after():
    handler = logging.StreamHandler()
    handler.setLevel(logging.INFO)
    logging.getLogger("distributed").addHandler(handler)
    try:
        with machine.quiet_dask_logs():
            assert handler.level > logging.CRITICAL
        assert handler.level == logging.INFO
    finally:
        logging.getLogger("distributed").removeHandler(handler)


def test_without_distributed_dask_says_which_extra_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)
    with pytest.raises(MissingDependencyError, match=r"pip install 'glu\[dask\]'"):
        with machine.dask_client(1):
            pass


def test_a_scheduler_that_refuses_the_client_is_one_data_error(monkeypatch):
    import distributed

    def refuse(address, timeout):
        raise OSError(f"Timed out trying to connect to {address} after 30 s")

    monkeypatch.setattr(distributed, "Client", refuse)
    with pytest.raises(DataError, match="cannot reach the Dask scheduler at tcp://127.0.0.1:9: Timed out"):
        with machine.dask_client(1, scheduler="tcp://127.0.0.1:9"):
            pass


def test_an_interrupt_in_the_block_kills_the_local_workers_and_closes_all(monkeypatch, worker_process):
    import distributed

    cluster = _Cluster(worker_process.pid)
    clients = []

    class Client:
        def __init__(self, of):
            assert of is cluster
            self.closed = False
            clients.append(self)

        def close(self):
            self.closed = True

    monkeypatch.setattr(distributed, "LocalCluster", lambda **options: cluster)
    monkeypatch.setattr(distributed, "Client", Client)
    with pytest.raises(KeyboardInterrupt):
        with machine.dask_client(1):
            raise KeyboardInterrupt
    assert worker_process.wait(10) == -signal.SIGKILL and clients[0].closed and cluster.closed == 1


@pytest.fixture
def listening():
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(0)  # nobody accepts: once the first connection waits, later ones are not answered
    yield f"tcp://127.0.0.1:{server.getsockname()[1]}"
    server.close()


def test_without_dask_an_open_port_is_all_that_is_checked(monkeypatch, listening):
    monkeypatch.setitem(sys.modules, "distributed.comm", None)
    assert machine.check_reachable(listening, timeout=2) is None


@pytest.mark.slow
def test_a_scheduler_whose_connections_time_out_did_not_answer(listening):
    with pytest.raises(
        DataError, match=f"the Dask scheduler at {listening} accepted the connection but did not"
    ):
        machine.check_reachable(listening, timeout=1)


@pytest.fixture
def dask_worker_like():
    """A server that speaks Dask's protocol and answers ``identity`` as a worker (with a long id)."""
    from distributed.comm import listen

    async def answer(comm):
        await comm.read()
        await comm.write({"type": "Worker", "id": "w" * 100})
        await comm.close()

    loop = asyncio.new_event_loop()
    thread = threading.Thread(target=loop.run_forever, daemon=True)
    thread.start()
    listener = listen("tcp://127.0.0.1:0", answer)
    asyncio.run_coroutine_threadsafe(listener.start(), loop).result(10)
    yield listener.contact_address
    listener.stop()
    loop.call_soon_threadsafe(loop.stop)
    thread.join(5)


def test_a_dask_server_that_is_not_a_scheduler_is_refused(dask_worker_like):
    with pytest.raises(DataError) as e:
        machine.check_reachable(dask_worker_like, timeout=5)
    said = str(e.value)
    assert said.startswith(
        f"{dask_worker_like} answered, but not as a Dask scheduler (its identity: {{'type': "
    )
    assert "'Worker'" in said and "w" * 100 not in said and "…)" in said  # the identity shortened
