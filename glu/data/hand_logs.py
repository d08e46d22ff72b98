r"""YARP hand logs: the file format of the gesture recordings, read with line-precise errors, and written.

A hand log (``gestures/<recording>/data.log``) has one frame a line, about 30 frames a second::

    index timestamp x y z
    -1 1495933414.180140 644.291918 -809.62949 -934.764515

``index`` is the YARP envelope counter (an integer, ``-1`` when absent), ``timestamp`` is in seconds, and
``x y z`` are the hand features as logged (docs/method.md §4.2: the right hand minus the torso, x and z
divided by the shoulder distance, y by the neck–torso distance, all × 1000 — that is, 1000 × the units of the
original models). Blank lines are skipped and do not count as frames. Timestamps must increase.

>>> log = parse_hand_log("-1 10.0 1 2 3\n-1 10.033 4 5 6\n")
>>> log.t, log.xyz.shape
(array([10.   , 10.033]), (2, 3))
>>> format_hand_log(log.t, log.xyz).splitlines()[0]
'-1 10.000000 1.000000 2.000000 3.000000'
"""

from __future__ import annotations

import math
import os
import re
from pathlib import Path
from typing import NamedTuple

import numpy as np

from glu.errors import DataError
from glu.files import atomic_write_text

LOG_FIELDS: tuple[str, ...] = ("index", "timestamp", "x", "y", "z")
"""The columns of a YARP hand log."""
FILE_NAME = "data.log"
"""The name of the hand log in a recording's folder."""

_INT = re.compile(rb"[+-]?\d+")
_FLOAT = re.compile(rb"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
_MAX_REPORTED_LINE = 80
MAX_LOGGED_COORDINATE = 10_000.0
"""Largest ``|x|``, ``|y|``, ``|z|`` a hand log may hold: 10 body units (about 3 m from the torso); the
published logs reach 2,300. Beyond it a value is a tracking or writing error, and would overflow the HMMs'
densities."""


class HandLog(NamedTuple):
    """The frames of a hand log.

    Attributes
    ----------
    t : array, shape (n_frames,) — timestamps, seconds, strictly increasing
    xyz : array, shape (n_frames, 3) — the hand features as logged
    source : the file name (for messages)
    """

    t: np.ndarray
    xyz: np.ndarray
    source: str


def read_hand_log(path: str | os.PathLike) -> HandLog:
    """Read a YARP hand log (a ``data.log`` file or a recording folder holding one).

    Returns the frames exactly as logged. Raises :class:`DataError` naming the file and the
    line for a missing file, an undecodable byte, a line without five fields, a field that is not a
    number, or a timestamp that does not increase.
    """
    path = Path(path)
    if path.is_dir():
        path = path / FILE_NAME
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise DataError(f"{path}: no such file (expected a YARP hand log, `index timestamp x y z`)") from None
    except OSError as e:
        raise DataError(f"{path}: cannot read: {e.strerror or e}") from None
    return parse_hand_log(data, source=str(path))


def parse_hand_log(data: bytes | str, source: str = "<string>") -> HandLog:
    """Parse the text of a YARP hand log (see :func:`read_hand_log`); ``source`` names it in errors."""
    if isinstance(data, str):
        data = data.encode("utf-8", errors="surrogatepass")
    rows: list[tuple[float, float, float, float]] = []
    for lineno, raw in enumerate(data.split(b"\n"), start=1):
        line = raw[:-1] if raw.endswith(b"\r") else raw
        rows_line = _parse_line(line, source, lineno)
        if rows_line is not None:
            if rows and not rows_line[0] > rows[-1][0]:
                raise DataError(
                    f"{source}:{lineno}: timestamp {rows_line[0]!r} does not increase "
                    f"(previous frame: {rows[-1][0]!r})"
                )
            rows.append(rows_line)
    if not rows:
        raise DataError(f"{source}: no frames (expected lines `index timestamp x y z`)")
    arr = np.array(rows, dtype=float)
    return HandLog(t=arr[:, 0], xyz=arr[:, 1:], source=source)


def _show(b: bytes) -> str:
    s = repr(b)[2:-1]
    return s if len(s) <= _MAX_REPORTED_LINE else s[:_MAX_REPORTED_LINE] + "…"


def _parse_line(line: bytes, source: str, lineno: int) -> tuple[float, float, float, float] | None:
    try:
        text = line.decode("ascii")
    except UnicodeDecodeError as e:
        raise DataError(
            f"{source}:{lineno}: byte {line[e.start]:#04x} at column {e.start + 1} is not ASCII text "
            f"(a YARP hand log has lines `index timestamp x y z`): {_show(line)}"
        ) from None
    fields = text.split()
    if not fields:
        return None
    if len(fields) != len(LOG_FIELDS):
        raise DataError(
            f"{source}:{lineno}: expected 5 fields `index timestamp x y z`, got {len(fields)}: {_show(line)}"
        )
    if not _INT.fullmatch(fields[0].encode()):
        raise DataError(f"{source}:{lineno}: index {fields[0]!r} is not an integer: {_show(line)}")
    values = []
    columns = [m.start() + 1 for m in re.finditer(r"\S+", text)][1:]
    for name, f, col in zip(LOG_FIELDS[1:], fields[1:], columns, strict=True):
        v = float(f) if _FLOAT.fullmatch(f.encode()) else math.nan
        if not math.isfinite(v):
            raise DataError(f"{source}:{lineno}:{col}: {name} {f!r} is not a finite number: {_show(line)}")
        if name != "timestamp" and abs(v) > MAX_LOGGED_COORDINATE:
            raise DataError(
                f"{source}:{lineno}:{col}: {name} {f!r} is outside ±{MAX_LOGGED_COORDINATE:,.0f}, the "
                "range of a hand relative to the torso in logged units (1000 × body units): "
                f"{_show(line)}"
            )
        values.append(v)
    return values[0], values[1], values[2], values[3]


def format_hand_log(t: np.ndarray, xyz: np.ndarray) -> str:
    """The text of a hand log for timestamps, shape (n,), and logged coordinates, shape (n, 3)."""
    t = np.asarray(t, dtype=float)
    xyz = np.asarray(xyz, dtype=float)
    if xyz.shape != (len(t), 3) or len(t) == 0:
        raise DataError(
            f"a hand log needs n ≥ 1 timestamps and (n, 3) coordinates, got {t.shape} and {xyz.shape}"
        )
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(xyz)) and np.all(np.diff(t) > 0)):
        raise DataError("a hand log needs finite coordinates and finite, strictly increasing timestamps")
    return "".join(f"-1 {ti:.6f} {x:.6f} {y:.6f} {z:.6f}\n" for ti, (x, y, z) in zip(t, xyz, strict=True))


def write_hand_log(path: str | os.PathLike, t: np.ndarray, xyz: np.ndarray) -> Path:
    """Write a hand log (atomically); ``path`` is the file or the recording's folder.

    ``t``, shape (n,), seconds, strictly increasing; ``xyz``, shape (n, 3), the hand features in logged
    units (1000 × body units: the module docstring). Returns the file written.
    """
    path = Path(path)
    if path.suffix != ".log":
        path = path / FILE_NAME
    return atomic_write_text(path, format_hand_log(t, xyz))
