"""Execute one jupytext notebook headless with papermill: progress by cell, and a stop that works at once.

:func:`run_notebook` runs a notebook (``notebooks/NN_name.py``) in its own kernel through papermill, with
the parameters injected after its parameters cell, and writes the executed ``.ipynb``. It uses papermill's
nbclient engine, extended (``GluEngine``, built on first use) in two ways:

* every cell start is reported to ``handle.on_cell(index, n_cells)``, for live progress;
* :meth:`RunHandle.stop` kills the kernel from another thread; nbclient notices the dead kernel within
  about a second and the run ends with :class:`NotebookStopped`, so Ctrl-C never waits for a notebook.

Once the last cell has run, the kernel is killed rather than asked to exit (nbclient's
``shutdown_kernel="immediate"``): every output is already complete by then (files are written atomically
by the cells, Rerun recordings are disconnected, a Dask cluster is closed by the code that opened it), and
a graceful exit cost 0.4–0.5 s a notebook of interpreter teardown and polling.

Kernels run with ``GLU_HEADLESS=1`` in their environment (:data:`glu.machine.HEADLESS_ENV`): interactive
extras (widgets, the Rerun viewer) then show their static form only. A relative ``GLU_FIGURE_CHECK``
(:data:`glu.plots.overlap.CHECK_ENV`) is made absolute from this process's folder, since each kernel runs
in a folder of its own. ``run_notebook(..., threads=N)`` also caps the kernel's BLAS and OpenMP threads
(:data:`THREAD_ENV`) at N, unless the caller's environment sets them: ``glu reproduce`` gives each of its
parallel kernels its share of the cores, since two kernels whose BLAS each spin up a thread per core slow
each other down (the whole collection took 65.9 s on 2 cores with two-thread BLAS in each of 2 kernels,
59.2 s with one; the same outputs).
"""

from __future__ import annotations

import os
import signal
import sys
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from glu.errors import GluError
from glu.files import atomic_write_text
from glu.machine import HEADLESS_ENV, thread_env
from glu.plots.overlap import CHECK_ENV


class NotebookStopped(GluError):
    """A notebook run was stopped (Ctrl-C, SIGTERM) before it finished."""


@dataclass
class RunHandle:
    """What a caller holds on a running notebook: its progress, and a way to stop it.

    Attributes
    ----------
    on_cell : called with (index, number of cells) when a cell starts (from the run's thread)
    threads : the kernel's BLAS/OpenMP threads (:func:`thread_env`); None leaves them to the libraries
    cwd : the kernel's working directory (None: this process's)
    cell, n_cells : the cell running now (0-based) and how many there are
    code_cell, n_code_cells : the same counted over code cells only (1-based: 0 before the first)
    first_line : the first non-blank line of the code cell running now
    """

    on_cell: Callable[[int, int], None] | None = None
    threads: int | None = None
    cwd: str | None = None
    cell: int = -1
    n_cells: int = 0
    code_cell: int = 0
    n_code_cells: int = 0
    first_line: str = ""
    stopped: bool = False
    _client: Any = field(default=None, repr=False)
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    def _cell_started(self, index: int, n_cells: int, cell: Any = None) -> None:
        self.cell, self.n_cells = index, n_cells
        if cell is not None and cell.get("cell_type") == "code":
            self.code_cell += 1
            lines = (line.strip() for line in str(cell.get("source", "")).splitlines())
            self.first_line = next((line for line in lines if line), "")
        if self.on_cell is not None:
            self.on_cell(index, n_cells)

    def stop(self) -> None:
        """Kill the notebook's kernel (if it has one yet); the run then ends with :class:`NotebookStopped`."""
        with self._lock:
            self.stopped = True
            log = getattr(self._client, "log", None)
            if log is not None:  # its "Kernel died while waiting for execute reply" is the stop itself
                log.disabled = True
            provisioner = getattr(getattr(self._client, "km", None), "provisioner", None)
            pid = getattr(getattr(provisioner, "process", None), "pid", None)
        if pid is not None:
            try:
                os.kill(pid, signal.SIGKILL)
            except (ProcessLookupError, PermissionError):
                pass


def _kernel_env(threads: int | None, extra: dict[str, str]) -> dict[str, str]:
    """A kernel's environment: this process's, its thread caps, ``extra``, headless, and the figure check's
    folder made absolute from this process's folder (a kernel works in a folder of its own)."""
    env = {**os.environ, **thread_env(threads), **extra, HEADLESS_ENV: "1"}
    if env.get(CHECK_ENV):
        env[CHECK_ENV] = os.path.abspath(env[CHECK_ENV])
    return env


def _engine_class() -> type:
    """papermill's nbclient engine, reporting cell starts and registering its client with the handle."""
    from jupyter_core.utils import run_sync
    from papermill.clientwrap import PapermillNotebookClient
    from papermill.engines import NBClientEngine, logger
    from papermill.utils import merge_kwargs, remove_args

    class Client(PapermillNotebookClient):  # type: ignore[misc]
        """papermill's client, whose kernel the handle can kill and whose cell starts it hears of."""

        def __init__(self, nb_man, handle: RunHandle, **kw):  # type: ignore[no-untyped-def]
            super().__init__(nb_man, **kw)
            self.handle = handle
            n_cells = len(nb_man.nb.cells)
            handle.n_code_cells = sum(c.get("cell_type") == "code" for c in nb_man.nb.cells)
            started = nb_man.cell_start

            def cell_start(cell, cell_index=None, **k):  # type: ignore[no-untyped-def]
                if handle.stopped:  # a stop that came between two cells: no further cell runs
                    handle.stop()
                    raise NotebookStopped("stopped")
                handle._cell_started(cell_index, n_cells, cell)
                return started(cell, cell_index, **k)

            nb_man.cell_start = cell_start

        async def async_start_new_kernel(self, **kwargs):  # type: ignore[no-untyped-def]
            with self.handle._lock:
                if self.handle.stopped:
                    raise NotebookStopped("stopped before its kernel started")
                self.handle._client = self
            env = _kernel_env(self.handle.threads, kwargs.pop("env", {}))
            if self.handle.cwd is not None:
                kwargs.setdefault("cwd", self.handle.cwd)
            started = await super().async_start_new_kernel(env=env, **kwargs)
            if self.handle.stopped:  # stopped while the kernel was being launched, before its pid was known
                self.handle.stop()
                raise NotebookStopped("stopped while its kernel started")
            return started

        start_new_kernel = run_sync(async_start_new_kernel)  # the sync name is bound to the base method

    class GluEngine(NBClientEngine):
        @classmethod
        def execute_managed_notebook(  # type: ignore[no-untyped-def]
            cls,
            nb_man,
            kernel_name,
            log_output=False,
            stdout_file=None,
            stderr_file=None,
            start_timeout=60,
            execution_timeout=None,
            **kwargs,
        ):
            # as papermill's NBClientEngine, with our client; from papermill's own command line
            # (`papermill --engine glu`) there is no handle, and the kernel's own warnings stay out
            handle = kwargs.pop("glu_handle", None) or RunHandle()
            kwargs.setdefault("extra_arguments", ["--log-level=ERROR"])
            kwargs = remove_args(["input_path"], **kwargs)
            safe_kwargs = remove_args(["timeout", "startup_timeout"], **kwargs)
            final_kwargs = merge_kwargs(
                safe_kwargs,
                timeout=execution_timeout if execution_timeout else kwargs.get("timeout"),
                startup_timeout=start_timeout,
                kernel_name=kernel_name,
                log=logger,
                log_output=log_output,
                stdout_file=stdout_file,
                stderr_file=stderr_file,
            )
            return Client(nb_man, handle, **final_kwargs).execute()

    return GluEngine


def __getattr__(name: str) -> Any:
    """``GluEngine``: papermill's engine entry point ``glu`` (``papermill --engine glu``), built on first use
    so that importing this module does not import papermill."""
    if name == "GluEngine":
        return _engine_class()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def load_papermill() -> Any:
    """Import papermill (with nbformat and jsonschema) and return it, without jsonschema's optional IRI
    checker.

    jsonschema imports ``rfc3987_syntax`` when it is installed (JupyterLab's jupyter-events brings it in),
    which builds a grammar at import and took 1.6 s of the 2.1 s before ``glu reproduce`` could start its
    first kernel. It only checks the ``iri`` format, which nbformat and papermill never ask for. So when
    neither is imported yet, jsonschema is imported with ``rfc3987_syntax`` hidden (jsonschema then skips
    that checker, as it does when the package is absent); the package itself stays importable afterwards.
    """
    if "jsonschema" not in sys.modules and "rfc3987_syntax" not in sys.modules:
        sys.modules["rfc3987_syntax"] = None  # type: ignore[assignment]  # import fails: checker skipped
        try:
            import jsonschema  # noqa: F401
        finally:
            del sys.modules["rfc3987_syntax"]
    import papermill

    return papermill


_ENGINE_LOCK = threading.Lock()


def _register_engine() -> str:
    from papermill.engines import papermill_engines

    with _ENGINE_LOCK:
        if "glu" not in papermill_engines._engines:
            papermill_engines.register("glu", _engine_class())
    return "glu"


def run_notebook(
    src: Path,
    out_ipynb: Path,
    parameters: dict[str, Any],
    cwd: Path | None = None,
    handle: RunHandle | None = None,
) -> Any:
    """Execute the jupytext notebook ``src`` with ``parameters``; write the executed copy to ``out_ipynb``.

    Raises papermill's ``PapermillExecutionError`` when a cell fails (the executed copy, with the error,
    is still written) and :class:`NotebookStopped` when ``handle.stop()`` was called.
    """
    pm = load_papermill()
    import jupytext

    handle = handle or RunHandle()
    handle.cwd = str(cwd or src.parent)  # the kernel's, set when it starts: papermill's own ``cwd`` would
    # os.chdir this whole process, which two notebooks running in threads would undo for each other
    out_ipynb.parent.mkdir(parents=True, exist_ok=True)
    nb = jupytext.read(src)
    try:
        executed = pm.execute_notebook(
            nb,
            str(out_ipynb),
            parameters=parameters,
            kernel_name="python3",
            language="python",
            progress_bar=False,
            engine_name=_register_engine(),
            glu_handle=handle,
            # kernel chatter stays out of the run's log; errors reach the notebook
            extra_arguments=["--log-level=CRITICAL"],
            log_output=False,
            shutdown_kernel="immediate",
        )
    except Exception:
        if handle.stopped:
            raise NotebookStopped(f"{src.stem}: stopped") from None
        raise
    if handle.stopped:  # its kernel was killed and papermill ended quietly: the notebook did not finish
        raise NotebookStopped(f"{src.stem}: stopped")
    return executed


def shown_path(path: str | os.PathLike, root: Path | None = None) -> str:
    """How an executed notebook shows a folder of this machine: relative to the project (``"."`` for the
    project itself, ``"data/real"``), else only its last part (``"…/data"``); never a machine path.

    >>> (shown_path("/home/me/glu/data/real", root=Path("/home/me/glu")),
    ...  shown_path("/srv/x/data", root=Path("/home/me/glu")))
    ('data/real', '…/data')
    """
    from glu import paths

    root = paths.PROJECT_ROOT if root is None else root
    p = Path(path)
    if root is not None:
        try:
            return p.resolve().relative_to(Path(root).resolve()).as_posix() or "."
        except ValueError:
            pass
    return f"…/{p.name}"


def present_executed(
    ipynb: Path, shown: dict[str, tuple[Any, str]], input_path: str, output_path: str
) -> None:
    """Rewrite the executed notebook ``ipynb`` so that it shows no path of this machine.

    In the parameters cell papermill injected, each ``name`` of ``shown`` is assigned its value as a reader
    should see it, with a comment (``shown[name] = (value, comment)``): the data folder relative to the
    project (or named by its origin), the published output folder rather than the run's staging folder.
    papermill's record of the run (``metadata.papermill``) gets the same values, and the notebook's source
    and executed copy as ``input_path`` and ``output_path``.
    """
    import json
    import re

    import nbformat

    nb = nbformat.read(ipynb, as_version=4)
    for cell in nb.cells:
        if "injected-parameters" not in cell.metadata.get("tags", []):
            continue
        lines = cell.source.split("\n")
        for name, (value, comment) in shown.items():
            line = f"{name} = {json.dumps(value, ensure_ascii=False)}" + (f"  # {comment}" if comment else "")
            lines = [line if re.match(rf"{re.escape(name)}\s*=", old) else old for old in lines]
        cell.source = "\n".join(lines)
    record = nb.metadata.get("papermill")
    if record is not None:
        params = record.get("parameters") or {}
        params.update({name: value for name, (value, _) in shown.items() if name in params})
        record["input_path"], record["output_path"] = input_path, output_path
    atomic_write_text(ipynb, nbformat.writes(nb) + "\n")
