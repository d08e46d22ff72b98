"""What every command checks before any work: that no output path is one of its inputs; and ``-o -``.

:func:`guarded_run` wraps each command's handler (:func:`glu.cli.main`). Before the handler runs it
resolves the command's outputs (``-o/--out``, ``--plot``) and its inputs (every other argument naming an
existing file or folder — data folder, experiments table, schema, config, model, recordings — and the
default data folder when ``--data`` is left out) and refuses, in one line naming both, an output that is an
input, or an existing file inside an input folder. An output of ``-``
(:data:`glu.files.STDOUT`) sends the file to standard output and the command's own messages to stderr.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
from collections.abc import Iterator
from pathlib import Path

from glu.errors import GluError
from glu.files import is_special, is_stdout, set_stdout

OUTPUT_ARGS = ("out", "plot")
"""The namespace attributes that name outputs."""

NOT_PATHS = frozenset({"func", "command", "debug", "words", "format"})


class InputOverwriteError(GluError):
    """An output path is one of the command's inputs."""


def _paths(value: object) -> list[str]:
    if isinstance(value, str | os.PathLike):
        text = os.fspath(value)
        return [text] if text and not is_stdout(text) else []
    if isinstance(value, list | tuple):
        return [p for v in value for p in _paths(v)]
    return []


def _real(text: str) -> Path | None:
    try:
        if not os.path.lexists(text):
            return None
        return Path(os.path.realpath(text))
    except (OSError, ValueError):
        return None


def _default_data(args: argparse.Namespace) -> list[str]:
    """The data folder a command with ``--data`` left out reads (``$GLU_DATA_DIR`` or the fetched data)."""
    if not hasattr(args, "data") or getattr(args, "data", None) or getattr(args, "model", None):
        return []
    from glu.data.source import resolve_data

    try:
        root = resolve_data(None).root
    except GluError:
        return []
    return [str(root)] if root is not None else []


def _inputs(args: argparse.Namespace) -> dict[Path, str]:
    found: dict[Path, str] = {}
    for key, value in vars(args).items():
        if key in OUTPUT_ARGS or key in NOT_PATHS or key.endswith("_command"):
            continue
        for text in _paths(value):
            real = _real(text)
            if real is not None:
                found.setdefault(real, f"--{key.replace('_', '-')} {text}")
    for text in _default_data(args):
        real = _real(text)
        if real is not None:
            found.setdefault(real, f"the data folder {text}")
    return found


def check_outputs_not_inputs(args: argparse.Namespace) -> None:
    """Raise :class:`InputOverwriteError` when an output of the command resolves to one of its inputs."""
    outputs = [(k, t) for k in OUTPUT_ARGS for t in _paths(getattr(args, k, None))]
    if not outputs:
        return
    inputs = _inputs(args)
    for key, text in outputs:
        if is_special(text):  # written through, never replaced: /dev/null as output and input is harmless
            continue
        out = _real(text) or Path(os.path.realpath(text))
        flag = "-o" if key == "out" else f"--{key}"
        for real, named in inputs.items():
            if out == real:
                raise InputOverwriteError(
                    f"{flag} {text} is also an input ({named}); it would be overwritten; "
                    "write to another path"
                )
            if out.is_file() and real.is_dir() and real in out.parents:
                raise InputOverwriteError(
                    f"{flag} {text} is a file inside an input folder ({named}); write to another path"
                )


@contextlib.contextmanager
def guarded_run(args: argparse.Namespace) -> Iterator[None]:
    """Check the outputs against the inputs, then run the block; with ``-o -`` the file goes to standard
    output and everything the command prints to stderr."""
    check_outputs_not_inputs(args)
    out = getattr(args, "out", None)
    if out is None or not is_stdout(out):
        yield
        return
    set_stdout(sys.stdout.buffer)
    try:
        with contextlib.redirect_stdout(sys.stderr):
            yield
    finally:
        set_stdout(None)
