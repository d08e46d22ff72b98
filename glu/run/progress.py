"""Progress of one notebook run (``glu run``) on stderr: code cell n of N, its first line, the time so far.

On a terminal it is one tqdm bar, redrawn every second so that the clock moves during a long cell; in a
log or a pipe it is one plain line per code cell, and one more every :data:`HEARTBEAT` seconds that a cell
keeps running, so nothing there holds bar characters and no minute passes in silence::

    08_tcds_figures: cell 6/7 at 11.6 s: engine = make_engine(bn)
    08_tcds_figures: cell 6/7 still running at 41.6 s
    08_tcds_figures: cell 7/7 at 42.1 s: case, name = next(iter(runs))
    08_tcds_figures: 7 cells in 42.4 s

:class:`CellProgress` hands out the :class:`~glu.run.execution.RunHandle` whose cell starts it reports.
"""

from __future__ import annotations

import sys
import threading
import time
from typing import Any, TextIO

from glu.run.execution import RunHandle

WIDTH = 60
"""How many characters of a cell's first line are shown."""

HEARTBEAT = 30.0
"""Seconds a cell may run before a plain log says it still is (and again after as many more)."""


def _short(line: str, width: int = WIDTH) -> str:
    return line if len(line) <= width else line[: width - 1] + "…"


class CellProgress:
    """Report the cells of one notebook run as they start; use as a context manager around the run.

    Parameters
    ----------
    name : the notebook's name, at the start of every line
    live : a tqdm bar (True) or plain lines (False); None: a bar when ``stream`` is a terminal
    stream : where progress goes (stderr)
    """

    def __init__(self, name: str, live: bool | None = None, stream: TextIO | None = None):
        self.name = name
        self.stream = stream if stream is not None else sys.stderr
        self.live = self.stream.isatty() if live is None else live
        self.handle = RunHandle(on_cell=self._on_cell)
        self.t0 = self.last_line = time.perf_counter()
        self.bar: Any = None
        self.shown = 0
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._ticker: threading.Thread | None = None

    def _say(self, text: str, now: float) -> None:
        print(f"{self.name}: {text}", file=self.stream, flush=True)
        self.last_line = now

    def _on_cell(self, index: int, n_cells: int) -> None:
        h = self.handle
        with self._lock:
            if h.code_cell == self.shown:  # not a code cell (markdown, raw): nothing runs
                return
            self.shown = h.code_cell
            if self.bar is not None:
                self.bar.total = h.n_code_cells
                self.bar.n = h.code_cell - 1  # cells finished
                self.bar.set_postfix_str(f"cell {h.code_cell}: {_short(h.first_line, 40)}", refresh=True)
                return
            now = time.perf_counter()
            self._say(
                f"cell {h.code_cell}/{h.n_code_cells} at {now - self.t0:.1f} s: {_short(h.first_line)}", now
            )

    def beat(self, now: float) -> None:
        """Once a second: redraw the bar (its clock), or say in a plain log that a long cell still runs."""
        with self._lock:
            if self.bar is not None:
                self.bar.refresh()
            elif self.shown and now - self.last_line >= HEARTBEAT:
                self._say(
                    f"cell {self.shown}/{self.handle.n_code_cells} still running at {now - self.t0:.1f} s",
                    now,
                )

    def _tick(self) -> None:
        while not self._stop.wait(1.0):
            self.beat(time.perf_counter())

    def __enter__(self) -> CellProgress:
        self.t0 = self.last_line = time.perf_counter()
        if self.live:
            from tqdm import tqdm

            self.bar = tqdm(
                total=None,
                desc=self.name,
                file=self.stream,
                leave=False,
                dynamic_ncols=True,
                bar_format="{desc}: {bar:20} {n_fmt}/{total_fmt} cells done [{elapsed}]{postfix}",
            )
            self.bar.set_postfix_str("starting its kernel", refresh=True)
        self._ticker = threading.Thread(target=self._tick, name="glu-run-progress", daemon=True)
        self._ticker.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        if self._ticker is not None:
            self._ticker.join()
        if self.bar is not None:
            self.bar.close()
        if exc[0] is None:
            now = time.perf_counter()
            self._say(f"{self.handle.code_cell} cells in {now - self.t0:.1f} s", now)
