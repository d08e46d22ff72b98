"""Text on its way to a terminal: no character read from a file can move the cursor, clear the screen,
reverse the text's direction or start a line that glu did not write.

:func:`safe_streams` (entered by :func:`glu.cli.main` for every command) wraps standard output and standard
error so that every control character (C0 and C1, DEL; carriage return too on standard output), every
bidirectional override or isolate and the Unicode line and paragraph separators are written as visible
escapes (``\\x1b``, ``\\u202e``); a line feed and a tab pass, since glu's own output is made of lines. A
newline inside a value read from a file (a model's data source, a value's name) is a different matter: the
command shows such a value with :func:`one_line`, which writes it as ``\\n``, so that it cannot forge a line
of the answer.
"""

from __future__ import annotations

import contextlib
import re
import sys
from collections.abc import Iterator
from typing import Any, TextIO

_BIDI = "\u061c\u200e\u200f\u202a\u202b\u202c\u202d\u202e\u2066\u2067\u2068\u2069\u2028\u2029"
_UNSAFE = re.compile(f"[\x00-\x08\x0b-\x1f\x7f-\x9f{_BIDI}]")  # \r (0x0d) included: no line overwritten
_UNSAFE_ERR = re.compile(f"[\x00-\x08\x0b\x0c\x0e-\x1f\x7f-\x9f{_BIDI}]")  # \r kept: progress bars redraw


def _escape_char(m: re.Match[str]) -> str:
    c = m.group(0)
    return f"\\x{ord(c):02x}" if ord(c) < 0x100 else f"\\u{ord(c):04x}"


def escape(text: str) -> str:
    """``text`` with every control, bidirectional and separator character written as an escape, but the line
    feed and the tab.

    >>> escape("tap\\x1bc \\u202eevil")
    'tap\\\\x1bc \\\\u202eevil'
    """
    return _UNSAFE.sub(_escape_char, text)


def one_line(text: Any) -> str:
    """``text`` (a value read from a file) on one line: a line feed, a carriage return and a tab are written
    as ``\\n``, ``\\r``, ``\\t``, and everything :func:`escape` escapes is escaped.

    >>> one_line("robot data\\nAction  tap  1.000000")
    'robot data\\\\nAction  tap  1.000000'
    """
    text = str(text).replace("\n", "\\n").replace("\r", "\\r").replace("\t", "\\t")
    return escape(text)


class SafeStream:
    """A text stream that escapes what no terminal should receive from glu (see the module docstring)."""

    def __init__(self, stream: TextIO, unsafe: re.Pattern[str]):
        self._stream = stream
        self._unsafe = unsafe

    def write(self, text: str) -> int:
        self._stream.write(self._unsafe.sub(_escape_char, text))
        return len(text)

    def writelines(self, lines: Any) -> None:
        for line in lines:
            self.write(line)

    def __getattr__(self, name: str) -> Any:  # flush, fileno, isatty, buffer, encoding, …
        return getattr(self._stream, name)


@contextlib.contextmanager
def safe_streams() -> Iterator[None]:
    """Within the block, ``sys.stdout`` and ``sys.stderr`` escape what no terminal should receive."""
    out, err = sys.stdout, sys.stderr
    sys.stdout, sys.stderr = SafeStream(out, _UNSAFE), SafeStream(err, _UNSAFE_ERR)
    try:
        yield
    finally:
        sys.stdout, sys.stderr = out, err
