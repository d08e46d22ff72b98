"""Where the code runs: the cores it may use, and whether a person watches (a notebook kernel) or not.

:func:`available_cores` and :func:`thread_env` size the work: ``glu reproduce`` gives each notebook
kernel its share of the cores for BLAS and OpenMP, the sweeps one thread per Dask worker.

:func:`dask_client` runs work on Dask (the corpus sweep, :func:`map_tasks`): a LocalCluster of this
machine is started inside :func:`ctrl_c_held` (its workers never receive the terminal's Ctrl-C, so they
print no tracebacks of their own: glu stops them), stopped after :func:`kill_local_workers` on an interrupt
(at once, silently), with :func:`quiet_dask_logs` around the whole (glu reports what went wrong in one line).

Interactive extras (the evidence explorer's widgets, the Rerun viewer in a notebook) appear only in a
live kernel; headless runs (``glu reproduce``, ``glu run``: their kernels have ``GLU_HEADLESS=1``) and
plain Python show the static form. The tests force either with :func:`is_live`'s ``force`` argument.

A sweep's ``--scheduler`` is checked by :func:`check_scheduler` (an address, or :data:`SYNCHRONOUS`: in this
process) and, before any work, :func:`check_reachable`.
"""

from __future__ import annotations

import contextlib
import logging
import os
import re
import signal
from collections.abc import Iterator
from typing import Any

from glu.errors import DataError

HEADLESS_ENV = "GLU_HEADLESS"
"""Environment variable set (to ``1``) in the kernels of headless runs."""


def in_kernel() -> bool:
    """True when running inside an IPython kernel (a notebook), where outputs can be displayed."""
    try:
        from IPython import get_ipython
    except ImportError:  # pragma: no cover - IPython comes with ipykernel
        return False
    shell = get_ipython()
    return shell is not None and getattr(shell, "kernel", None) is not None


def is_live(force: bool | None = None) -> bool:
    """True in a kernel that is not headless (a person may interact); ``force`` overrides the guess."""
    if force is not None:
        return force
    return in_kernel() and os.environ.get(HEADLESS_ENV, "") in ("", "0")


THREAD_ENV: tuple[str, ...] = (
    "OMP_NUM_THREADS",
    "OPENBLAS_NUM_THREADS",
    "MKL_NUM_THREADS",
    "BLIS_NUM_THREADS",
    "VECLIB_MAXIMUM_THREADS",
    "NUMEXPR_NUM_THREADS",
)
"""The variables that size the thread pools of BLAS, OpenMP and numexpr when a process starts."""


def available_cores() -> int:
    """The cores this process may run on (its CPU affinity where the system has one)."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def thread_env(threads: int | None, environ: dict[str, str] | None = None) -> dict[str, str]:
    """The variables of :data:`THREAD_ENV` set to ``threads``, leaving out those ``environ`` already sets.

    >>> thread_env(1, {"OMP_NUM_THREADS": "4"})["OPENBLAS_NUM_THREADS"], "OMP_NUM_THREADS" in thread_env(1,
    ...     {"OMP_NUM_THREADS": "4"})
    ('1', False)
    >>> thread_env(None)
    {}
    """
    environ = os.environ if environ is None else environ
    if threads is None:
        return {}
    return {name: str(int(threads)) for name in THREAD_ENV if name not in environ}


def _meminfo(field: str, path: str = "/proc/meminfo") -> int | None:
    """A ``kB`` field of a ``/proc`` status file, in bytes (None where there is no such file or field)."""
    try:
        with open(path) as f:
            for line in f:
                if line.startswith(field + ":"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def available_memory() -> int | None:
    """Bytes this process may still allocate: the system's available memory, and below the address-space
    limit (``ulimit -v``) what this process does not use yet; None where neither can be read."""
    system = _meminfo("MemAvailable")
    limits = [] if system is None else [system]
    try:
        import resource
    except ImportError:  # Windows: no address-space limit to read
        return system
    soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    if soft != resource.RLIM_INFINITY:
        used = _meminfo("VmSize", "/proc/self/status") or 0
        limits.append(max(soft - used, 0))
    return min(limits) if limits else None


def human_bytes(n: float) -> str:
    """``n`` bytes as people read them.

    >>> human_bytes(8_000_000_000_000), human_bytes(1536), human_bytes(12)
    ('7.28 TiB', '1.50 KiB', '12 B')
    """
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if n < 1024 or unit == "PiB":
            return f"{n:.0f} B" if unit == "B" else f"{n:.3g} {unit}" if n >= 1024 else f"{n:.2f} {unit}"
        n /= 1024
    raise AssertionError  # pragma: no cover


def check_memory(need: float, what: str) -> None:
    """DataError in one line when ``need`` bytes (what ``what`` declares) exceed what this process may still
    allocate (:func:`available_memory`); checked before anything is allocated."""
    free = available_memory()
    if free is not None and need > free:
        raise DataError(
            f"{what} needs about {human_bytes(need)} of memory; this process may use {human_bytes(free)} "
            "(the machine's available memory, or its ulimit)"
        )


VIEWER_ASSETS_ENV = "RERUN_NOTEBOOK_ASSET"
VIEWER_ASSETS = "serve-local"
"""Where the inline Rerun viewer's files come from: ``serve-local``, the installed ``rerun-notebook``'s,
served on localhost by the kernel (so the viewer works offline); ``$RERUN_NOTEBOOK_ASSET`` set by the user
wins."""


def viewer_class() -> Any:
    """Rerun's inline notebook viewer (``rerun.notebook.Viewer``), its files served offline
    (:data:`VIEWER_ASSETS`); None without ``rerun-notebook``."""
    # the viewer's JavaScript and WebAssembly come from the installed rerun-notebook, served on localhost by
    # the kernel, never from the web (rerun-notebook's default is app.rerun.io); read when it is imported
    os.environ.setdefault(VIEWER_ASSETS_ENV, VIEWER_ASSETS)
    try:
        from rerun.notebook import Viewer
    except ImportError:
        return None
    return Viewer


@contextlib.contextmanager
def ctrl_c_held() -> Iterator[None]:
    """Block SIGINT in this thread for the block: the threads and worker processes started in it inherit
    the blocked signal, so a Ctrl-C at the terminal (sent to the whole process group) reaches this process
    only; a Ctrl-C that came during the block is delivered when it ends."""
    try:
        signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    except (AttributeError, ValueError, OSError):  # no POSIX signal masks here
        yield
        return
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


def kill_local_workers(cluster: Any) -> None:
    """SIGKILL the worker processes of a Dask LocalCluster (None: nothing), so that closing it after an
    interrupt is quick and silent: a worker told to stop in the middle of a task prints tracebacks."""
    for nanny in list(getattr(cluster, "workers", {}).values()):
        pid = getattr(nanny, "pid", None)
        if pid:
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)


def close_cluster(cluster: Any, error: BaseException) -> None:
    """Close a LocalCluster (None: nothing) whose start or use ``error`` ended; after an interrupt its workers
    are killed first (:func:`kill_local_workers`), so the close is quick and silent."""
    if cluster is None:
        return
    if isinstance(error, KeyboardInterrupt):
        kill_local_workers(cluster)
    cluster.close()


@contextlib.contextmanager
def quiet_dask_logs() -> Iterator[None]:
    """dask.distributed's log handlers silent for the block, closing the cluster included (the cluster's
    own ``silence_logs`` ends before: a stop then printed the closing connections' tracebacks)."""
    with contextlib.suppress(ImportError):  # its import installs the handlers
        import distributed  # noqa: F401
    handlers = [h for h in logging.getLogger("distributed").handlers if isinstance(h, logging.StreamHandler)]
    levels = [h.level for h in handlers]
    for h in handlers:
        h.setLevel(logging.CRITICAL + 1)
    try:
        yield
    finally:
        for h, level in zip(handlers, levels, strict=True):
            h.setLevel(level)


# ------------------------------------------------------------------ Dask schedulers

SYNCHRONOUS = "synchronous"
"""The ``--scheduler`` that runs a sweep in this process, one task after another (no cluster)."""
ADDRESS = re.compile(r"^(tcp|tls|ws|wss)://[^\s/]+:\d+/?$")


def check_scheduler(address: str | None) -> str | None:
    """``address`` if it is None, ``synchronous`` or a Dask address ``tcp://host:port``; else DataError."""
    if address is None or address == SYNCHRONOUS or ADDRESS.match(address):
        return address
    raise DataError(
        f"--scheduler {address!r}: expected a Dask scheduler address such as tcp://127.0.0.1:8786, "
        f"or '{SYNCHRONOUS}' to run in this process"
    )


def check_reachable(address: str, timeout: float = 10.0) -> None:
    """DataError, in one line naming ``address``, unless a Dask scheduler answers there within ``timeout``
    seconds: something accepts TCP connections at its host and port, completes Dask's handshake, and says it
    is a scheduler (its ``identity``). A server that accepts and never answers, answers with anything else,
    or closes the connection is refused here, before any work (and before any output folder is made)."""
    import socket

    host, _, port = address.split("://", 1)[1].rstrip("/").rpartition(":")
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=timeout):
            pass
    except OSError as e:
        raise DataError(f"cannot reach the Dask scheduler at {address}: {e.strerror or e}") from None
    try:
        import distributed.comm  # noqa: F401
    except ImportError:  # the command that needs it says so (glu[dask]); the port at least answers
        return
    reply = _ask_identity(address, timeout)
    if not isinstance(reply, dict) or reply.get("type") != "Scheduler":
        raise DataError(
            f"{address} answered, but not as a Dask scheduler (its identity: {_short(reply)}); is it the "
            "scheduler's address (tcp://host:8786 by default)?"
        )


def _short(value: Any, limit: int = 80) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 1] + "…"


def _ask_identity(address: str, timeout: float) -> Any:
    """The scheduler's answer to Dask's ``identity`` request, within ``timeout`` seconds; DataError otherwise.

    Asked from a daemon thread with an event loop of its own, so that a caller inside an event loop (a
    notebook) can ask too, and a server that never answers can hold up neither the caller nor the exit."""
    import asyncio
    import threading

    async def identity() -> Any:
        from distributed.comm import connect

        comm = await connect(address, timeout=timeout)
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    outcome: dict[str, Any] = {}

    def ask() -> None:
        try:
            outcome["reply"] = asyncio.run(asyncio.wait_for(identity(), timeout + 2))
        except BaseException as e:  # reported by the caller's thread
            outcome["error"] = e

    silent = DataError(
        f"the Dask scheduler at {address} accepted the connection but did not answer within {timeout:g} s"
    )
    with quiet_dask_logs():
        thread = threading.Thread(target=ask, name="glu-scheduler-probe", daemon=True)
        thread.start()
        thread.join(timeout + 7)
    if thread.is_alive() or isinstance(outcome.get("error"), TimeoutError):
        raise silent
    error = outcome.get("error")
    if error is None:
        return outcome.get("reply")
    cause = error.__cause__ or error  # Dask's "Timed out trying to connect" names the last attempt's error
    why = str(cause).splitlines()[0][:120] if str(cause).strip() else type(cause).__name__
    if isinstance(cause, OSError) and ("closed" in why.lower() or "reset" in why.lower()):
        raise DataError(f"{address} accepted the connection and closed it: not a Dask scheduler that answers")
    if isinstance(cause, TimeoutError) or "Timed out" in why:
        raise silent
    # an answer that is not Dask's (garbage decodes as anything)
    raise DataError(f"{address} is not a Dask scheduler that answers ({why})")


@contextlib.contextmanager
def dask_client(workers: int, scheduler: str | None = None, **options: Any) -> Iterator[Any]:
    """A dask.distributed ``Client`` for the block: of the scheduler at ``scheduler``, or of a LocalCluster
    of ``workers`` single-threaded processes (``options``: more of LocalCluster's) started as
    :func:`ctrl_c_held` says. On leaving, the client and the cluster are closed, the workers killed first
    after an interrupt (at once, silently); dask.distributed's logs stay quiet throughout
    (:func:`quiet_dask_logs`: glu says what went wrong in one line)."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        from glu.errors import MissingDependencyError

        raise MissingDependencyError(
            "running on Dask needs dask.distributed, which the plain `pip install glu` leaves out; "
            "install it with: pip install 'glu[dask]'"
        ) from None
    with quiet_dask_logs():
        cluster = None
        try:
            if scheduler is None:
                with ctrl_c_held():  # the workers and the cluster threads never see Ctrl-C: glu stops them
                    options.setdefault("dashboard_address", ":0")
                    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, **options)
                    client = Client(cluster)
            else:
                try:
                    client = Client(scheduler, timeout="30s")
                except (OSError, TimeoutError) as e:
                    raise DataError(f"cannot reach the Dask scheduler at {scheduler}: {e}") from None
        except BaseException as e:
            close_cluster(cluster, e)
            raise
        try:
            yield client
        except KeyboardInterrupt:  # Ctrl-C, SIGTERM: the workers are killed, not asked to finish (or talk)
            kill_local_workers(cluster)
            raise
        finally:
            client.close()
            if cluster is not None:
                cluster.close()


def map_tasks(fn: Any, items: list[Any], *args: Any, workers: int = 0) -> list[Any]:
    """``[fn(item, *args) for item in items]``: in this process (``workers=0``), or one Dask task per item on
    a LocalCluster of ``workers`` single-threaded processes (:func:`dask_client`). Results keep the order of
    ``items``."""
    if not workers:
        return [fn(item, *args) for item in items]
    with dask_client(workers) as client:
        from distributed import as_completed

        futures = {client.submit(fn, item, *args, pure=False): k for k, item in enumerate(items)}
        done = {futures[f]: f.result() for f in as_completed(futures)}
        return [done[k] for k in range(len(items))]
