"""One ``glu reproduce`` at a time on an output folder: a lock file holding the running process's id.

:func:`run_lock` creates ``ROOT/.glu-reproduce.lock`` (``ROOT``: the project, or ``--out``) and holds an
exclusive ``flock`` on it for the whole run, with the process id written inside. A second run on the same
folder finds the lock held and refuses in one line naming the first run's process id. The kernel
releases a ``flock`` when its process dies however it dies, so a lock file left by a killed run (a stale
lock, its process gone) is simply taken over; the file is removed when the run ends.
"""

from __future__ import annotations

import fcntl
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from glu.errors import GluError

LOCK_FILE = ".glu-reproduce.lock"
"""The lock file's name in the output root."""


class RunLockedError(GluError):
    """Another ``glu reproduce`` is running on the same output folder."""


def _holder(fd: int) -> str:
    text = os.pread(fd, 64, 0).decode("ascii", "replace").strip()
    return f"process {text}" if text.isdigit() else "a process that is starting"


@contextmanager
def run_lock(root: str | os.PathLike) -> Iterator[Path]:
    """Hold the reproduce lock of ``root`` for the block; :class:`RunLockedError` if another run holds it."""
    root = Path(root)
    made = [p for p in (root, *root.parents) if not p.exists()]  # removed again if the run leaves them empty
    root.mkdir(parents=True, exist_ok=True)
    try:
        with _locked(root) as lock:
            yield lock
    finally:
        for folder in made:
            try:
                folder.rmdir()
            except OSError:
                break


@contextmanager
def _locked(root: Path) -> Iterator[Path]:
    lock = root / LOCK_FILE
    while True:
        fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = _holder(fd)
            os.close(fd)
            raise RunLockedError(
                f"another glu reproduce ({holder}) is running on {root}; wait for it to finish or stop it "
                f"(its lock: {lock.name} in that folder)"
            ) from None
        try:  # the file may have been removed by the run that just ended: lock the one at the path
            same = os.path.samestat(os.fstat(fd), os.stat(lock))
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        yield lock
    finally:
        lock.unlink(missing_ok=True)
        os.close(fd)
