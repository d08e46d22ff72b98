"""The ``glu`` command line: thin wrappers over the package, one module per group of commands.

Bad input (a missing file, an unknown node or value, impossible evidence, …) prints one line on stderr —
what was wrong, where, what is allowed — and exits with status 2, never with a traceback; a notebook that
fails in ``glu reproduce`` or ``glu run`` prints its name, cell and error and exits with status 1.
"""

from __future__ import annotations

import argparse
import importlib
import os
import signal
import sys
import threading
import traceback
import warnings
from collections.abc import Sequence

from glu import __version__
from glu.cli.commands import COMMANDS
from glu.cli.guard import guarded_run
from glu.cli.terminal import safe_streams
from glu.errors import GluError, Terminated

COMMAND_MODULES: tuple[str, ...] = tuple(dict.fromkeys(c.module for c in COMMANDS.values()))
"""Each module defines ``register(subparsers)``; handlers import heavy libraries lazily."""

EXIT_BAD_INPUT = 2


class OneLineParser(argparse.ArgumentParser):
    """An ArgumentParser whose usage errors are one line (plus where to find help), exit status 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message} (see `{self.prog} --help`)\n")


def build_parser(argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The argument parser of ``glu``: every command's in full (``argv`` None), or, for the arguments
    ``argv`` of one run, only the module of the command they name (:mod:`glu.cli.commands`); the other
    commands are listed by name and help line only, so that ``glu --help`` imports no command at all."""
    parser = OneLineParser(
        prog="glu",
        description="Gestures, language and affordances: reproduce Saponaro et al. (GLU 2017, TCDS 2020).",
    )
    parser.add_argument("--version", action="version", version=f"glu {__version__}")
    parser.add_argument("--debug", action="store_true", help="show the traceback of an unexpected error")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=OneLineParser)
    sub.required = True
    if argv is None:
        modules = list(COMMAND_MODULES)
    else:
        named = next((a for a in argv if not a.startswith("-")), None)
        modules = [COMMANDS[named].module] if named in COMMANDS else []
    for name in modules:
        importlib.import_module(name).register(sub)
    for command, (_, line) in COMMANDS.items():
        if command not in sub.choices:
            sub.add_parser(command, help=line)
    return parser


DEBUG_ENV = "GLU_DEBUG"
"""Set to 1 to see the traceback of an unexpected error (as ``--debug`` does)."""


def _terminate(signum: int, frame: object) -> None:
    raise Terminated()


def _interrupt_inside(e: BaseException) -> KeyboardInterrupt | None:
    """The Ctrl-C or SIGTERM an exception wraps: numba's dispatcher turns a signal raised while compiled
    code runs into ``SystemError: CPUDispatcher(…) returned a result with an exception set``."""
    seen = set()
    while e is not None and id(e) not in seen:
        if isinstance(e, KeyboardInterrupt):
            return e
        seen.add(id(e))
        e = e.__cause__ or e.__context__
    return None


def _error_text(e: OSError | MemoryError | RecursionError) -> str:
    """The line of an error of the system rather than of glu: a file the system refuses; a size no check
    foresaw; JSON or YAML nested deeper than Python reads (a model, a schema, a query line)."""
    if isinstance(e, MemoryError):
        from glu.machine import available_memory, human_bytes

        free = available_memory()
        return (
            "out of memory: the input needs more than this process may use"
            + (f" ({human_bytes(free)} free now)" if free is not None else "")
            + "; give a smaller input, or run where more memory is available"
        )
    if isinstance(e, RecursionError):
        return "an input file is nested too deeply to read; is it the right file?"
    where = f"{e.filename!r}: " if getattr(e, "filename", None) else ""
    return f"{where}{e.strerror or e}"


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``glu`` console script; returns the exit status.

    Bad input: one line, status 2. Ctrl-C: status 130; SIGTERM: 143 (both stop the work at once and
    leave nothing half-written). Anything else is a bug: one line asking for a report, status 1, and the
    traceback with ``--debug`` or ``GLU_DEBUG=1``.
    """
    previous = None
    try:  # first: a SIGTERM while the parser is built (imports) ends as any other, 143 and one line
        previous = signal.signal(signal.SIGTERM, _terminate)
    except ValueError:  # not the main thread (a test calling main() from a thread): keep the default
        pass
    try:
        with safe_streams():  # nothing read from a file reaches the terminal as a control code
            return _main(argv)
    except KeyboardInterrupt as e:  # before the command started: building the parser, reading arguments
        return _stopped("glu", e)
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


def _is_glu_process() -> bool:
    """Whether this process is the ``glu`` command (the console script, or ``python -m glu``)."""
    parts = os.path.normpath(sys.argv[0] if sys.argv else "").split(os.sep)
    return parts[-1] == "glu" or parts[-2:] == ["glu", "__main__.py"]


def _stopped(name: str, e: KeyboardInterrupt) -> int:
    """The one line of a stop, and its status; what the interrupted libraries leave to be collected
    (an event loop of a killed kernel's client, …) is then dropped silently at exit, not reported."""
    if _is_glu_process():  # the process ends now (not a test calling main())
        sys.unraisablehook = lambda unraisable: None
    if isinstance(e, Terminated):
        print(f"{name}: terminated", file=sys.stderr)
        return 143
    print(f"{name}: interrupted", file=sys.stderr)
    return 130


class _DataWarnings:
    """How a command says that its data folder is the published data modified
    (:class:`glu.data.source.DataWarning`): one line on stderr, once per folder, held for
    :attr:`HOLD` seconds. A command that then refuses its input (a file of that folder that does not parse)
    says only its error, one line; one that goes on, or ends, says the warning too. Other warnings are
    shown as Python shows them."""

    HOLD = 3.0

    def __init__(self, name: str) -> None:
        self.name = name
        self.seen: set[str] = set()
        self.held: list[str] = []
        self.lock = threading.Lock()
        self.timer: threading.Timer | None = None
        self.shown = warnings.showwarning

    def show(self, message, category, filename, lineno, file=None, line=None):  # type: ignore[no-untyped-def]
        if category.__name__ != "DataWarning":
            self.shown(message, category, filename, lineno, file, line)
            return
        with self.lock:
            if str(message) in self.seen:
                return
            self.seen.add(str(message))
            self.held.append(f"{self.name}: warning: {message}; results say so")
            if self.timer is None:
                self.timer = threading.Timer(self.HOLD, self.flush)
                self.timer.daemon = True
                self.timer.start()

    def flush(self) -> None:
        """Say the held warnings now."""
        with self.lock:
            lines, self.held = self.held, []
        for text in lines:
            print(text, file=sys.stderr, flush=True)

    def drop(self) -> None:
        """Forget the held warnings: the command refuses its input, and its error says why."""
        with self.lock:
            self.held = []
            if self.timer is not None:
                self.timer.cancel()


def _main(argv: Sequence[str] | None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser(argv)
    nul = next((a for a in argv if "\x00" in a), None)
    if nul is not None:  # no file name or value can hold one; the OS would refuse it deep inside
        print(f"glu: error: argument {nul!r} contains a NUL byte", file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        args = parser.parse_args(argv)
    except OSError as e:  # a path the system refuses to look at (too long, a symlink loop)
        print(f"glu: error: {_error_text(e)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    sub = getattr(args, f"{args.command}_command", None)
    name = f"glu {args.command}" + (f" {sub}" if sub else "")
    debug = getattr(args, "debug", False) or os.environ.get(DEBUG_ENV, "") not in ("", "0")
    notes = _DataWarnings(name)
    try:
        with warnings.catch_warnings(), guarded_run(args):
            warnings.showwarning = notes.show
            status = args.func(args)
    except GluError as e:
        notes.drop()
        print(f"{name}: error: {e}", file=sys.stderr)
        return getattr(e, "exit_status", EXIT_BAD_INPUT)  # 2: bad input; 1: a run that failed (a notebook)
    except KeyboardInterrupt as e:  # Ctrl-C, or SIGTERM (Terminated)
        return _stopped(name, e)
    except BrokenPipeError:
        return 0
    except (OSError, MemoryError, RecursionError) as e:
        print(f"{name}: error: {_error_text(e)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except Exception as e:  # a bug: one line, the traceback on request
        stop = _interrupt_inside(e)
        if stop is not None:  # an interrupt that compiled code (numba) wrapped in a SystemError
            return _stopped(name, stop)
        if debug:
            traceback.print_exc()
        print(
            f"{name}: internal error: {type(e).__name__}: {e} — this is a bug in glu; please report it "
            f"with the command you ran (set {DEBUG_ENV}=1 or pass --debug for the traceback)",
            file=sys.stderr,
        )
        return 1
    finally:
        notes.flush()  # held warnings of a command that went on (dropped if it refused its input)
    return int(status or 0)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
