"""Writing files so that a reader never sees half of one: every write goes through a temporary file.

A file is written next to its destination under a hidden temporary name and renamed into place only when
complete (``os.replace`` is atomic on one file system), so an interrupted or failed write leaves the old
file, or nothing, never a truncated one. The new file gets the permissions a plain ``open(path, "w")``
would give (``0o666`` minus the process's umask), not the ``0o600`` of a temporary file.

Only a regular file (or a new one) is ever renamed over. An output path that exists and is something else
— a character or block device such as ``/dev/null``, a FIFO, a socket — is opened and written through once
the content is complete, as any Unix tool does (so ``-o /dev/null`` discards the output and leaves the
device a device). The path ``-`` (:data:`STDOUT`) writes the content to standard output.

A set of files that readers take as one whole (tables and the key or provenance file that vouches for
them) is rewritten under :func:`marked_set`: its marker first removed, every file written atomically, the
marker last; a whole folder glu owns alone can instead be rebuilt beside it and swapped in
(:func:`staged_folder`).

This module is the one implementation of atomic writes in glu; models, tables, figures and data folders
all use it. Its readers of input files (:func:`read_text`, :func:`read_bytes`, :func:`read_json`) turn the
system's errors into one line naming the file and what it should be.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import stat
import sys
import tempfile
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, BinaryIO

from glu.errors import DataError

STDOUT = "-"
"""The output path that means standard output (``-o -``)."""

_stdout: BinaryIO | None = None


def set_stdout(stream: BinaryIO | None) -> None:
    """Where the path ``-`` is written (default: ``sys.stdout.buffer``); the command line gives the real
    standard output here while it sends its own messages to stderr."""
    global _stdout
    _stdout = stream


def is_stdout(path: str | os.PathLike) -> bool:
    """Whether ``path`` is ``-``, standard output."""
    return os.fspath(path) == STDOUT


def is_special(path: str | os.PathLike) -> bool:
    """Whether ``path`` exists and is neither a regular file nor a folder (a device, a FIFO, a socket),
    following symbolic links: such a path is written through, never replaced."""
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        return False
    return not (stat.S_ISREG(mode) or stat.S_ISDIR(mode))


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

    When ``path`` is a device, FIFO or socket (:func:`is_special`) or ``-`` (:data:`STDOUT`), the
    temporary file is in the system's temporary folder and its content is written through to ``path`` (to
    standard output) at the end; nothing is renamed over it.
    """
    through = is_stdout(path) or is_special(path)
    path = Path(path)
    if not through:
        path.parent.mkdir(parents=True, exist_ok=True)
    fd, name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=suffix, dir=None if through else path.parent)
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        if through:
            _write_through(tmp, path)
        else:
            os.chmod(tmp, 0o666 & ~_umask())
            os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def _write_through(complete: Path, path: Path) -> None:
    """Copy the file ``complete`` into the existing non-regular ``path`` (or standard output)."""
    with open(complete, "rb") as src:
        if is_stdout(path):
            dest = _stdout or sys.stdout.buffer
            shutil.copyfileobj(src, dest)
            dest.flush()
            return
        with open(path, "wb") as dest:  # a device or FIFO: opened for writing, never truncated or replaced
            shutil.copyfileobj(src, dest)


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
def marked_set(folder: str | os.PathLike, *markers: str) -> Iterator[Path]:
    """Rewrite the set of files in ``folder`` that readers take as one whole because its ``markers`` (file
    names: a key, a provenance file) vouch for it; yields ``folder``. ::

        with marked_set(out, "saved.json"):
            with atomic_path(out / "table.parquet") as tmp:
                df.to_parquet(tmp)
            atomic_write_json(out / "saved.json", key)  # the marker, last

    On entry the markers are removed, before any other file is touched; the block writes every file of the
    set atomically (:func:`atomic_path`, :func:`atomic_write_bytes`, …) and the markers last, in order. A
    reader that refuses a folder without its marker therefore sees the old whole set, a set it refuses,
    or the new whole set — never new files beside old ones under the old marker. On an exception or an
    interrupt the markers are removed again (the set is refused until a write of it completes); the files
    already written stay, as does every other file of the folder: the folder may be one the user named, with
    files of their own, so it is never removed or replaced whole (that is :func:`staged_folder`, for a
    folder glu owns alone). A block that ends without writing every marker is a mistake of glu's:
    RuntimeError.
    """
    folder = Path(folder)
    paths = [folder / m for m in markers]
    for path in paths:
        path.unlink(missing_ok=True)
    try:
        yield folder
    except BaseException:
        for path in paths:
            path.unlink(missing_ok=True)
        raise
    missing = [p.name for p in paths if not p.is_file()]
    if missing:
        raise RuntimeError(f"{folder}: the set was written without its marker {', '.join(missing)}")


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


_PLAIN_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.+-]{0,199}")


def plain_name(name: object) -> bool:
    """Whether ``name`` (read from a file) can safely become a file name: letters, digits and ``_ . + -``,
    not starting with a dot or a dash, no ``..``, at most 200 characters; never a path or a terminal code.

    >>> [plain_name(n) for n in ("08_tcds_figures", "a.png", "../../victim", "a/b", ".hidden", "x\\n")]
    [True, True, False, False, False, False]
    """
    return isinstance(name, str) and bool(_PLAIN_NAME.fullmatch(name)) and ".." not in name


def read_text(
    path: str | os.PathLike, what: str = "file", encoding: str = "utf-8", error: type = DataError
) -> str:
    """The text of an input file; ``error`` (default :class:`~glu.errors.DataError`) names the file and
    ``what`` it should be when it is missing, a folder, unreadable or not text."""
    try:
        return Path(path).read_text(encoding=encoding)
    except OSError as e:
        raise error(_unreadable(path, what, e)) from None
    except UnicodeDecodeError as e:
        raise error(f"{path}: cannot read the {what} as text ({e})") from None


def read_bytes(path: str | os.PathLike, what: str = "file", error: type = DataError) -> bytes:
    """The bytes of an input file; ``error`` (default :class:`~glu.errors.DataError`) names the file and
    ``what`` it should be when it is missing, a folder or unreadable."""
    try:
        return Path(path).read_bytes()
    except OSError as e:
        raise error(_unreadable(path, what, e)) from None


def read_json(path: str | os.PathLike, what: str = "JSON file", error: type = DataError) -> Any:
    """The JSON document of an input file; ``error`` (default :class:`~glu.errors.DataError`) names the
    file and ``what`` it should be when it is missing, a folder, unreadable or not JSON."""
    raw = read_bytes(path, what, error)
    try:
        return json.loads(raw)
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise error(f"{path}: not a JSON {what} ({e})") from None


def _unreadable(path: str | os.PathLike, what: str, e: OSError) -> str:
    """What an input file's read error says: the file, and ``what`` it should be."""
    if isinstance(e, FileNotFoundError):
        return f"{path}: no such {what}"
    if isinstance(e, IsADirectoryError):
        return f"{path}: is a folder, not a {what}"
    return f"{path}: cannot read the {what} ({e.strerror})"
