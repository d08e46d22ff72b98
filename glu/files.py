"""Writing files so that a reader never sees half of one: every write goes through a temporary file.

A file is written next to its destination under a hidden temporary name and renamed into place only when
complete (``os.replace`` is atomic on one file system), so an interrupted or failed write leaves the old
file, or nothing, never a truncated one. The new file gets the permissions a plain ``open(path, "w")``
would give (``0o666`` minus the process's umask), not the ``0o600`` of a temporary file.

This module is the one implementation of atomic writes in glu; models, tables, figures and data folders
all use it.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextmanager
def atomic_path(path: str | os.PathLike, suffix: str = ".tmp") -> Iterator[Path]:
    """A temporary path beside ``path``; renamed to ``path`` when the block ends without an exception.

    For writers that want a file name rather than bytes (``savefig``, a Rerun recording, …)::

        with atomic_path("figures/x.png") as tmp:
            fig.savefig(tmp, format="png")

    The folder is created if needed. On an exception (or ``KeyboardInterrupt``) the temporary file is
    removed and ``path`` is left as it was.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=suffix, dir=path.parent)
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically; returns the path."""
    path = Path(path)
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return path


def atomic_write_text(path: str | os.PathLike, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically; returns the path."""
    return atomic_write_bytes(path, text.encode("utf-8"))


def atomic_write_json(path: str | os.PathLike, obj: Any, indent: int | None = 1, **kwargs: Any) -> Path:
    """Write ``obj`` as JSON (strict: no NaN or Infinity) followed by a newline, atomically."""
    kwargs.setdefault("allow_nan", False)
    return atomic_write_text(path, json.dumps(obj, indent=indent, **kwargs) + "\n")


@contextmanager
def staged_folder(dest: str | os.PathLike) -> Iterator[Path]:
    """A new hidden folder beside ``dest`` to build it in; it becomes ``dest`` when the block succeeds.

    ::

        with staged_folder("data/synthetic") as tmp:
            write everything into tmp

    On success :func:`replace_folder` moves it into place (an existing ``dest`` is swapped out whole); on
    an exception or an interrupt it is removed and ``dest`` is left as it was. Readers therefore see the
    old folder, or the complete new one, never a half-written one.
    """
    dest = Path(dest).absolute()
    dest.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{dest.name}.", suffix=".staging", dir=dest.parent))
    try:
        yield tmp
        os.chmod(tmp, 0o777 & ~_umask())
        replace_folder(tmp, dest)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)


def replace_folder(complete: str | os.PathLike, dest: str | os.PathLike) -> Path:
    """Make the folder ``complete`` be ``dest`` by renaming (same file system); an old ``dest`` is removed.

    A missing ``dest`` is one rename. An existing one is renamed aside first, then removed, so ``dest`` is
    at every moment the old folder, absent, or the new folder.
    """
    complete, dest = Path(complete), Path(dest)
    if dest.exists():
        old = dest.parent / f".{dest.name}.old-{uuid.uuid4().hex[:8]}"
        os.replace(dest, old)
        os.replace(complete, dest)
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(complete, dest)
    return dest


def read_text(
    path: str | os.PathLike, what: str = "file", encoding: str = "utf-8", error: type | None = None
) -> str:
    """The text of an input file; ``error`` (default :class:`~glu.errors.DataError`) names the file and ``what``
    it should be when it is missing, a folder, unreadable or not text."""
    from glu.errors import DataError

    error = error or DataError
    try:
        return Path(path).read_text(encoding=encoding)
    except FileNotFoundError:
        raise error(f"{path}: no such {what}") from None
    except IsADirectoryError:
        raise error(f"{path}: is a folder, not a {what}") from None
    except (OSError, UnicodeDecodeError) as e:
        raise error(f"{path}: cannot read the {what} as text ({e})") from None
