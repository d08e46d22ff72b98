"""A second fuzz suite (issue #11), complementing tests/harness/test_fuzz.py with other generators and
stricter checks.

tests/harness/test_fuzz.py draws bad values per argument type and a fixed set of corrupted files. This module
adds: cases that *must* fail (an expensive command given only invalid settings may not run: ``--only 0`` once
ran every notebook), inputs and outputs in one work folder whose every file is compared before and after a
failed run (folders made above ``-o`` count), recursive mutations of model and recogniser JSON (keys deleted,
values replaced by arbitrary JSON, non-finite numbers, deep nesting, truncation), random byte flips in the
originals' ``.mat`` (without the real data, in the synthetic network saved in the same BNT layout), and
evidence batches from a file and from stdin with one answer per line.

Each generated input runs ``glu.cli.main(argv)`` in-process and must behave as the project promises:

* exit 2 with one error line (``glu CMD: error: …``, the last line on stderr; informational ``#`` lines such
  as the data source may come before it), or exit 0 with valid output: strict JSON with ``--json`` (no NaN,
  no Infinity), and text without ``nan``/``inf``;
* never a traceback, never an exception out of ``main``, never exit 1 (glu's "internal error": a bug);
* no numpy ``RuntimeWarning``;
* after a failure, every file and folder of the example's work folder is as it was (nothing half-written,
  no folder created, no input changed).

The subcommands are listed from the parser: a new one without a fuzz case fails
:func:`test_every_subcommand_has_a_case_here`, naming it. The default profile (CI) is small and derandomised;
the ``slow`` variants run many more examples (``pytest -m slow tests/harness/test_fuzz_mutations.py``).
Per-category counts are printed at the end of the session (``category: N inputs, M misbehaved``).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import os
import re
import tempfile
import warnings
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from unittest import mock

import numpy as np
import pytest
from cli_run import train_recogniser
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from glu.cli import build_parser, main

PROFILES = {
    "ci": settings(
        max_examples=20,
        deadline=None,
        derandomize=True,
        database=None,
        suppress_health_check=list(HealthCheck),
    ),
    "long": settings(
        max_examples=400,
        deadline=None,
        derandomize=False,
        database=None,
        suppress_health_check=list(HealthCheck),
    ),
}
PROFILE_PARAMS = ["ci", pytest.param("long", marks=pytest.mark.slow)]

TRIED: Counter = Counter()
MISBEHAVED: Counter = Counter()


@pytest.fixture(scope="module", autouse=True)
def _report_counts(pytestconfig):
    """Print ``category: N inputs, M misbehaved`` per category when the module is done."""
    yield
    reporter = pytestconfig.pluginmanager.get_plugin("terminalreporter")
    lines = [f"fuzz {c}: {n} inputs, {MISBEHAVED[c]} misbehaved" for c, n in sorted(TRIED.items())]
    summary = os.environ.get("GLU_FUZZ_SUMMARY")
    if summary:  # for the note: the counts of one run, as JSON
        Path(summary).write_text(json.dumps({c: [n, MISBEHAVED[c]] for c, n in TRIED.items()}, indent=1))
    if reporter is not None:
        reporter.write_line("")
        for line in lines:
            reporter.write_line(line)


# ------------------------------------------------------------------ running glu and judging what it did


@dataclass
class Outcome:
    argv: list[str]
    status: int | None
    out: str
    err: str
    warnings: list[str] = field(default_factory=list)
    escaped: BaseException | None = None


def run_glu(argv: list[str], stdin: str = "") -> Outcome:
    """``glu.cli.main(argv)`` with stdout, stderr, stdin and warnings captured."""
    out, err = io.StringIO(), io.StringIO()
    status, escaped = None, None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with (
            contextlib.redirect_stdout(out),
            contextlib.redirect_stderr(err),
            mock.patch("sys.stdin", io.StringIO(stdin)),
        ):
            try:
                status = main(argv)
            except SystemExit as e:  # argparse: usage errors (2), --help (0)
                status = e.code if isinstance(e.code, int) else 0 if e.code is None else 2
            except BaseException as e:  # noqa: BLE001 - anything escaping main is what we look for
                escaped = e
    noisy = [f"{w.category.__name__}: {w.message}" for w in caught if issubclass(w.category, RuntimeWarning)]
    return Outcome(argv, status, out.getvalue(), err.getvalue(), noisy, escaped)


def _strict(text: str) -> object:
    def refuse(name: str) -> object:
        raise ValueError(f"{name} is not JSON")

    return json.loads(text, parse_constant=refuse)


def _strict_json(text: str) -> str | None:
    """Why ``text`` is not strict JSON (one document, or one document per line), or None."""
    try:
        _strict(text)
        return None
    except ValueError:
        pass
    for i, line in enumerate(text.splitlines(), start=1):
        if not line.strip():
            continue
        try:
            _strict(line)
        except ValueError as e:
            return f"stdout line {i} is not strict JSON ({e}): {line[:120]!r}"
    return None if text.strip() else "no JSON on stdout"


ERROR_LINE = re.compile(r"^glu( [\w-]+)*: error: \S")
NON_FINITE_TEXT = re.compile(r"(?<![\w.])[-+]?(nan|inf|infinity)(?!\w)", re.IGNORECASE)


def problems(o: Outcome, json_mode: bool, before: dict, after: dict) -> list[str]:
    """What ``o`` did wrong, as sentences (empty: it behaved)."""
    found = []
    if o.escaped is not None:
        found.append(f"exception escaped main: {type(o.escaped).__name__}: {o.escaped}")
    if "Traceback" in o.err or "Traceback" in o.out:
        found.append("a traceback")
    if o.warnings:
        found.append(f"warnings reached the user: {o.warnings[:3]}")
    if o.status == 2:
        lines = [ln for ln in o.err.splitlines() if ln.strip()]
        errors = [ln for ln in lines if ": error:" in ln]
        if not lines or not ERROR_LINE.match(lines[-1]) or len(errors) != 1:
            found.append(f"exit 2 without exactly one error line as the last line: {o.err[-400:]!r}")
        if before != after:
            changed = sorted(set(before) ^ set(after)) or [k for k in before if before[k] != after.get(k)]
            found.append(f"a failed run changed its work folder: {changed[:5]}")
    elif o.status == 0:
        if json_mode:
            why = _strict_json(o.out)
            if why:
                found.append(why)
        else:
            m = NON_FINITE_TEXT.search(o.out)
            if m:
                found.append(
                    f"text output prints {m.group(0)!r}: …{o.out[max(0, m.start() - 60) : m.end() + 20]!r}"
                )
    elif o.escaped is None:
        found.append(f"exit status {o.status} (1 is glu's internal error: a bug): {o.err[-300:]!r}")
    return found


def snapshot(root: Path) -> dict[str, tuple]:
    """Every path under ``root`` with its kind, size and content hash (files)."""
    out = {}
    for p in sorted(root.rglob("*")):
        rel = str(p.relative_to(root))
        if p.is_dir():
            out[rel] = ("dir",)
        elif p.is_file():
            out[rel] = ("file", p.stat().st_size, hash(p.read_bytes()))
    return out


def judge(category: str, argv: list[str], work: Path, stdin: str = "", must_fail: bool = False) -> Outcome:
    """Run ``argv`` in ``work`` and assert the contract; counts the input under ``category``."""
    before = snapshot(work)
    o = run_glu(argv, stdin)
    after = snapshot(work)
    found = problems(o, "--json" in argv or "--batch" in argv, before, after)
    if must_fail and o.status == 0:
        found.append("accepted an input the case generated as invalid")
    TRIED[category] += 1
    if found:
        MISBEHAVED[category] += 1
    assert not found, f"glu {' '.join(argv)}\n  " + "\n  ".join(found) + f"\n  stderr: {o.err[-500:]!r}"
    return o


# ------------------------------------------------------------------ the subcommands


def leaf_commands() -> list[str]:
    """Every runnable subcommand of the parser, e.g. ``"data synth"``."""
    found = []

    def walk(p: argparse.ArgumentParser, prefix: list[str]) -> None:
        subs = [a for a in p._actions if isinstance(a, argparse._SubParsersAction)]
        if not subs:
            found.append(" ".join(prefix))
            return
        for name, sp in subs[0].choices.items():
            walk(sp, [*prefix, name])

    walk(build_parser(), [])
    return found


# Bad values by kind: each is invalid for every option of that kind.
BAD = {
    "pos_int": ["0", "-1", "-0", "nan", "inf", "1.5", "1e3", "abc", "", " ", "0x10", "--1"],
    "seed": ["-1", "4294967296", "99999999999999999999999", "nan", "1.0", "", "x"],
    "pos_float": ["0", "-1", "nan", "NaN", "inf", "-inf", "1e309", "abc", ""],
    "nonneg_float": ["-1", "-1e-300", "nan", "inf", "-inf", "1e309", "abc", ""],
    "name": ["", " ", "nope", "Nope", "a,b", "ação", "grasp tap"],
    "url": ["", "nope", "http:/x", "http://", "file:///etc", "http://[::1", "ftp//x", "http://a b"],
}


class Work:
    """An example's work folder: inputs in ``in/``, outputs in ``out/``."""

    def __init__(self, root: Path, assets: dict[str, Path]):
        self.root, self.assets = root, assets
        self.readonly = False  # whether a read-only folder was handed out
        (root / "in").mkdir()
        (root / "out").mkdir()

    def path(self, kind: str, suffix: str = ".json") -> str:
        """A path of a kind that is wrong as an input or as an output."""
        base = self.root / "in"
        if kind == "missing":
            return str(base / "no" / f"such{suffix}")
        if kind == "dir":
            (base / "adir").mkdir(exist_ok=True)
            return str(base / "adir")
        if kind == "empty":
            (base / f"empty{suffix}").write_bytes(b"")
            return str(base / f"empty{suffix}")
        if kind == "garbage":
            (base / f"garbage{suffix}").write_bytes(b"\x00\xff{[<garbage\n\x89PNG")
            return str(base / f"garbage{suffix}")
        if kind == "file_as_dir":  # a path below a file
            (base / "afile").write_text("x")
            return str(base / "afile" / f"x{suffix}")
        if kind == "readonly":
            ro = base / "ro"
            ro.mkdir(exist_ok=True)
            ro.chmod(0o555)
            self.readonly = True
            return str(ro / f"x{suffix}")
        raise ValueError(kind)

    def write(self, name: str, data: bytes | str) -> str:
        p = self.root / "in" / name
        p.write_bytes(data.encode("utf-8", "surrogateescape") if isinstance(data, str) else data)
        return str(p)


PATH_KINDS = ["missing", "dir", "empty", "garbage", "file_as_dir"]


@pytest.fixture(scope="module")
def assets(tmp_path_factory, synthetic_folder) -> dict[str, Path]:
    """A valid model, recogniser and hand log to start from (made once, never changed)."""
    root = tmp_path_factory.mktemp("fuzz-assets")
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        assert main(["bn", "learn", "--data", str(synthetic_folder), "-o", str(root / "model.json")]) == 0
        train_recogniser(root / "recogniser.json")
    log = next((synthetic_folder / "gestures").glob("*/data.log"))
    (root / "hand.log").write_text("".join(log.read_text().splitlines(keepends=True)[:60]))
    (root / "candidates.txt").write_text("the robot taps the ball\nthe robot is tapping the sphere\n")
    return {
        "model": root / "model.json",
        "recogniser": root / "recogniser.json",
        "log": root / "hand.log",
        "data": synthetic_folder,
        "candidates": root / "candidates.txt",
    }


@contextlib.contextmanager
def work_folder(assets: dict[str, Path]):
    with tempfile.TemporaryDirectory(prefix="glu-fuzz-") as d:
        try:
            yield Work(Path(d), assets)
        finally:
            for p in Path(d).rglob("*"):  # a read-only folder must not stop the clean-up
                if p.is_dir():
                    p.chmod(0o755)


# ------------------------------------------------------------------ category "arguments"
#
# A case is (base argv, mutation sites, must_fail). A mutation site is (option, kind) where kind is a key of
# BAD, "path:<suffix>" (a wrong input/output path), or a list of literal bad values. The test appends one or
# two mutations to the base; a later option overrides an earlier one in argparse.

A = "{assets}"  # placeholders filled per example
OUT = "{out}"


def _cases() -> dict[str, tuple[list[str], list[tuple[str, object]], bool]]:
    return {
        "data fetch": (
            ["data", "fetch", "-o", f"{OUT}/d", "--mirror", "http://127.0.0.1:9/", "--timeout", "0.5"],
            [
                ("--timeout", "pos_float"),
                ("--mirror", "url"),
                ("-o", "path:"),
                ("--manifest", "path:.json"),
            ],
            True,
        ),
        "data synth": (
            ["data", "synth", "-o", f"{OUT}/s"],
            [
                ("--n", ["0", "-5", "9", "1e9", "100000000000", "nan", ""]),
                ("--seed", "seed"),
                ("-o", "outdir"),
            ],
            True,
        ),
        "data info": (
            ["data", "info", "--data", "{data}"],
            [("--data", "path:"), ("--words", "name")],
            False,
        ),
        "bn learn": (
            ["bn", "learn", "--data", "{data}", "-o", f"{OUT}/m.json"],
            [
                ("--words", "name"),
                ("--unseen-words", "name"),
                ("--data", "path:"),
                ("-o", "outfile"),
                ("--schema", "path:.yaml"),
                ("--experiments", "path:.csv"),
            ],
            True,
        ),
        "bn edges": (
            ["bn", "edges", "{model}"],
            [("", "path:.json"), ("", "path:.mat"), ("", "path:.bif")],
            False,
        ),
        "bn nodes": (
            ["bn", "nodes", "{model}"],
            [("", "path:.json"), ("", "path:.mat"), ("", "path:.bif")],
            False,
        ),
        "bn import": (
            ["bn", "import", "{model}", "-o", f"{OUT}/x.json"],
            [
                ("", "path:.bif"),
                ("", "path:.mat"),
                ("", "path:.uai"),
                ("--format", "name"),
                ("-o", "outfile"),
            ],
            False,
        ),
        "bn export": (
            ["bn", "export", "{model}", "-o", f"{OUT}/x.bif"],
            [("--format", "name"), ("--zero-rows", "name"), ("-o", "outfile"), ("", "path:.json")],
            False,
        ),
        "query": (
            ["query", "--model", "{model}", "--target", "ObjVel", "--json"],
            [
                ("--target", "name"),
                (
                    "--evidence",
                    [
                        "",
                        "Action",
                        "Action=",
                        "=grasp",
                        "Action=nope",
                        "Nope=grasp",
                        "Action=grasp=tap",
                        "Action=grasp,tap",
                    ],
                ),
                (
                    "--soft",
                    [
                        "Action=grasp:nan,tap:1,touch:0",
                        "Action=grasp:inf,tap:1,touch:1",
                        "Action=grasp:-1,tap:1,touch:1",
                        "Action=grasp:0,tap:0,touch:0",
                        "Action=grasp:1e-320,tap:0,touch:0",
                        "Action=grasp:1e-322,tap:0,touch:0",
                        "Action=grasp:1e308,tap:1e308,touch:1e308",
                        "Action=",
                        "Action=grasp",
                        "Action=grasp:x",
                        "ObjVel=slow:1",
                        "Action=grasp:0.5,grasp:0.5",
                    ],
                ),
                ("--soft-rule", "name"),
                ("--model", "path:.json"),
                ("--data", "path:"),
                ("--batch", "path:.jsonl"),
            ],
            False,
        ),
        "gestures segment": (
            ["gestures", "segment", "{log}"],
            [("--label", "name"), ("--plot", "outfile"), ("", "path:.log")],
            False,
        ),
        "hmm train": (
            [
                "hmm",
                "train",
                "--synthetic",
                "2",
                "--states",
                "2",
                "--mix",
                "1",
                "--iter",
                "2",
                "-o",
                f"{OUT}/r.json",
            ],
            [
                ("--states", "pos_int"),
                ("--mix", "pos_int"),
                ("--iter", "pos_int"),
                ("--tol", "pos_float"),
                ("--covar-reg", "pos_float"),
                ("--noise", "nonneg_float"),
                ("--seed", "seed"),
                ("--recipe", "name"),
                ("--features", "name"),
                ("--actions", "name"),
                ("--synthetic", "pos_int"),
                ("-o", "outfile"),
            ],
            True,
        ),
        "recognize": (
            ["recognize", "{log}", "--models", "{recogniser}"],
            [
                ("--models", "path:.json"),
                ("--frames", ["-1", "nan", "x", "5:1"]),
                ("--body-size", ["0", "-1", "nan", "inf", "1e309"]),
                ("", "path:.log"),
                ("--json", None),
                ("--stream", None),
                ("--repair", None),
            ],
            False,
        ),
        "reproduce": (
            ["reproduce", "--out", f"{OUT}/rep"],
            [
                ("--only", ["", "nope", "99", "0", "-1"]),
                ("--jobs", "pos_int"),
                ("--seed", "seed"),
                ("--data", "path:"),
                ("--notebooks", "path:"),
            ],
            True,
        ),
        "run": (
            ["run", "01", "--out", f"{OUT}/run"],
            [
                (
                    "-p",
                    [
                        ("seed", "-1"),
                        ("seed", "nan"),
                        ("seed", ""),
                        ("nokey", "1"),
                        ("quick", "maybe"),
                        ("data", "/no/such/folder"),
                    ],
                ),
                ("--data", "path:"),
            ],
            True,
        ),
        "describe": (
            ["describe", "--model", "{model}", "--nbest", "3"],
            [
                ("--nbest", "pos_int"),
                ("--sample", ["0", "-1", "200001", "1e9", "nan"]),
                ("--max-length", ["0", "3", "7", "-1", "nan"]),
                ("--must-contain", "name"),
                ("--grammar", "path:.txt"),
                ("--candidates", "path:.txt"),
                ("--score", "name"),
                ("--evidence", ["Action=nope", "Action="]),
                ("--seed", "seed"),
                ("--candidates", ["{candidates}"]),
                ("--json", None),
            ],
            False,
        ),
        "anticipate": (
            ["anticipate", "--case", "sphere", "--models", "{recogniser}", "--data", "{data}"],
            [
                ("--case", "name"),
                ("--step", "pos_int"),
                ("--soft-rule", "name"),
                ("--models", "path:.json"),
                ("--score", "name"),
                ("--candidates", "path:.txt"),
                ("--json", None),
            ],
            False,
        ),
        "readme": (
            ["readme", "--summary", "{model}", "--readme", f"{OUT}/README.md"],
            [("--summary", "path:.json"), ("--readme", "path:.md")],
            True,
        ),
        "evaluate": (
            ["evaluate", "-o", f"{OUT}/ev", "--episodes", "20"],
            [
                ("--episodes", "pos_int"),
                ("--seed", "seed"),
                ("--config", "badpath:.toml"),
                ("--scheduler", ["", "nope", "tcp://", "tcp://256.0.0.1:x"]),
                ("--workers", "pos_int"),
                ("--max-chunks", "pos_int"),
                ("--data", "path:"),
                ("-o", "outdir"),
            ],
            True,
        ),
        "correspondence": (
            ["correspondence", "-o", f"{OUT}/corr"],
            [("--workers", "pos_int"), ("-o", "outdir")],
            True,
        ),
        "corpus": (
            ["corpus", "-o", f"{OUT}/c.parquet", "--episodes", "20"],
            [
                ("--episodes", "pos_int"),
                ("--seed", "seed"),
                ("--config", "badpath:.toml"),
                ("--data", "path:"),
                ("-o", "outfile"),
            ],
            True,
        ),
        "learn-gestures": (
            ["learn-gestures", "--episodes", "12", "--labels", "soft", "--states", "2", "--mix", "1"]
            + ["--iter", "2", "--data", "{data}", "-o", f"{OUT}/l.json"],
            [
                ("--episodes", "pos_int"),
                ("--labels", "name"),
                ("--seed", "seed"),
                ("--ambiguity", "name"),
                ("--threshold", "pos_float"),
                ("--states", "pos_int"),
                ("--mix", "pos_int"),
                ("--iter", "pos_int"),
                ("--noise", "nonneg_float"),
                ("--data", "path:"),
                ("-o", "outfile"),
            ],
            True,
        ),
        "learning-curves": (
            ["learning-curves", "--episodes", "12", "--seeds", "0", "--scheduler", "synchronous"]
            + ["--data", "{data}", "-o", f"{OUT}/lc"],
            [
                ("--episodes", "pos_int"),
                ("--seeds", ["", "x", "1,1", "-1", "0..", "a..b"]),
                ("--ambiguities", ["", " ", "nope", "mixed,nope"]),
                ("--test-per-action", "pos_int"),
                ("--workers", "pos_int"),
                ("--scheduler", ["", "nope", "tcp://", "tcp://256.0.0.1:x"]),
                ("--data", "path:"),
                ("-o", "outdir"),
            ],
            True,
        ),
    }


CASES = _cases()


def test_every_subcommand_has_a_case_here():
    missing = sorted(set(leaf_commands()) - set(CASES))
    assert not missing, f"subcommands without a case in tests/harness/test_fuzz_mutations.py: {missing}"
    assert not sorted(set(CASES) - set(leaf_commands())), "fuzz cases for subcommands that no longer exist"


def _fill(arg: str, w: Work) -> str:
    a = w.assets
    return arg.format(
        out=w.root / "out",
        model=a["model"],
        recogniser=a["recogniser"],
        log=a["log"],
        data=a["data"],
        candidates=a["candidates"],
    )


def _bad_value(kind: object, w: Work, draw) -> list[str]:
    """The argument(s) of one mutation."""
    if kind is None:
        return []
    if isinstance(kind, list):
        v = draw(st.sampled_from(kind))
        return [_fill(x, w) for x in v] if isinstance(v, tuple) else [_fill(v, w)]
    if kind == "outfile":
        return [w.path(draw(st.sampled_from(["dir", "file_as_dir", "readonly"])))]
    if kind == "outdir":
        return [w.path(draw(st.sampled_from(["file_as_dir", "empty", "readonly"])))]
    if isinstance(kind, str) and kind.startswith("badpath:"):  # an empty file may be valid input here
        kinds = [k for k in PATH_KINDS if k != "empty"]
        return [w.path(draw(st.sampled_from(kinds)), kind.removeprefix("badpath:"))]
    if isinstance(kind, str) and kind.startswith("path:"):
        return [w.path(draw(st.sampled_from(PATH_KINDS)), kind.removeprefix("path:"))]
    return [draw(st.sampled_from(BAD[kind]))]


@pytest.mark.parametrize("command", sorted(CASES))
@pytest.mark.parametrize("profile", PROFILE_PARAMS)
def test_bad_arguments(command, profile, assets):
    base, sites, must_fail = CASES[command]
    flags = [s for s in sites if s[1] is not None]
    switches = [s for s in sites if s[1] is None]

    @PROFILES[profile]
    @given(data=st.data())
    def example(data):
        with work_folder(assets) as w:
            argv = [_fill(a, w) for a in base]
            picked = data.draw(st.lists(st.integers(0, len(flags) - 1), min_size=1, max_size=2, unique=True))
            for option, kind in (flags[i] for i in picked):
                values = _bad_value(kind, w, data.draw)
                if option == "":  # the positional argument
                    argv[len(command.split())] = values[0]
                else:
                    argv += [option, *values]
            if switches:
                argv += data.draw(st.lists(st.sampled_from([s[0] for s in switches]), unique=True))
            if w.readonly and os.geteuid() == 0:
                return  # root writes into read-only folders: that case cannot fail as root
            judge(f"arguments ({command})", argv, w.root, must_fail=must_fail)

    example()


# ------------------------------------------------------------------ category "hand logs"

_field = st.one_of(
    st.floats(-1e4, 1e4).map(repr),
    st.sampled_from(
        ["nan", "NaN", "inf", "-inf", "1e157", "-1e157", "1e309", "", "x", "1,5", "0x1", "1e-400"]
    ),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
)


@st.composite
def corrupted_log(draw, text: str) -> str:
    lines = text.splitlines(keepends=True)
    for _ in range(draw(st.integers(1, 3))):
        if not lines:
            break
        i = draw(st.integers(0, len(lines) - 1))
        what = draw(
            st.sampled_from(["field", "garbage", "truncate", "duplicate", "delete", "binary", "crlf"])
        )
        if what == "field" and lines[i].split():
            fields = lines[i].split()
            j = draw(st.integers(0, len(fields) - 1))
            fields[j] = draw(_field)
            lines[i] = " ".join(fields) + "\n"
        elif what == "garbage":
            lines[i] = draw(st.text(max_size=40)) + "\n"
        elif what == "truncate":
            lines = lines[: i + 1]
            lines[i] = lines[i][: draw(st.integers(0, len(lines[i])))]
            if not lines[i]:
                del lines[i]
        elif what == "duplicate":
            lines.insert(i, lines[i])
        elif what == "delete" and len(lines) > 1:
            del lines[i]
        elif what == "binary":
            lines[i] = "\x00\xff" + lines[i]
        elif what == "crlf":
            lines[i] = lines[i].rstrip("\n") + "\r\n"
    return "".join(lines)


HAND_LOG_COMMANDS = {
    "recognize text": ["recognize", "{log}", "--models", "{recogniser}"],
    "recognize --json": ["recognize", "{log}", "--models", "{recogniser}", "--json"],
    "recognize --stream --json": ["recognize", "{log}", "--models", "{recogniser}", "--stream", "--json"],
    "recognize --stream": ["recognize", "{log}", "--models", "{recogniser}", "--stream"],
    "gestures segment": ["gestures", "segment", "{log}"],
}


@pytest.mark.parametrize("command", sorted(HAND_LOG_COMMANDS))
@pytest.mark.parametrize("profile", PROFILE_PARAMS)
def test_corrupted_hand_logs(command, profile, assets):
    text = assets["log"].read_text()

    @PROFILES[profile]
    @given(log=corrupted_log(text))
    def example(log):
        with work_folder(assets) as w:
            path = w.write("data.log", log)
            argv = [path if a == "{log}" else _fill(a, w) for a in HAND_LOG_COMMANDS[command]]
            judge("hand logs", argv, w.root)

    example()


# ----------------------------------------------------------------- categories "model JSON", "recogniser JSON"

_json_leaf = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(10**20), 10**20),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=8),
    st.sampled_from(["grasp", "ObjVel", "", "NaN"]),
)
_json_value = st.recursive(
    _json_leaf,
    lambda c: st.lists(c, max_size=4) | st.dictionaries(st.text(max_size=6), c, max_size=4),
    max_leaves=12,
)


def _paths(obj, prefix=()):
    yield prefix
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _paths(v, (*prefix, k))
    elif isinstance(obj, list):
        for i, v in enumerate(obj[:6]):
            yield from _paths(v, (*prefix, i))


@st.composite
def mutated_json(draw, doc: dict) -> str:
    doc = json.loads(json.dumps(doc))
    for _ in range(draw(st.integers(1, 3))):
        paths = [p for p in _paths(doc) if p]
        p = draw(st.sampled_from(paths))
        parent = doc
        for k in p[:-1]:
            parent = parent[k]
        what = draw(st.sampled_from(["replace", "delete", "duplicate", "number", "nest"]))
        if what == "replace":
            parent[p[-1]] = draw(_json_value)
        elif what == "delete":
            del parent[p[-1]]
        elif what == "duplicate" and isinstance(parent, list) and parent:
            parent.append(parent[0])
        elif what == "number":
            parent[p[-1]] = draw(st.sampled_from([math.nan, math.inf, -1.0, 0.0, 1e308, 2.0, -0.0]))
        else:
            parent[p[-1]] = [[[[[[[[[[parent[p[-1]]]]]]]]]]]]
    text = json.dumps(doc, indent=1)
    if draw(st.booleans()) and draw(st.booleans()):
        text = text[: draw(st.integers(0, len(text)))]  # truncated
    return text


MODEL_COMMANDS = {
    "query --json": ["query", "--model", "{m}", "--target", "ObjVel", "--json", "--evidence", "Action=tap"],
    "query": ["query", "--model", "{m}", "--target", "Action", "--soft", "Shape=circle:0.5,box:0.5"],
    "bn edges": ["bn", "edges", "{m}"],
    "bn nodes --json": ["bn", "nodes", "{m}", "--json"],
    "bn export": ["bn", "export", "{m}", "-o", "{out}/x.bif", "--zero-rows", "seen"],
    "describe --json": ["describe", "--model", "{m}", "--nbest", "2", "--json"],
}
RECOGNISER_COMMANDS = {
    "recognize --json": ["recognize", "{log}", "--models", "{m}", "--json"],
    "recognize --stream": ["recognize", "{log}", "--models", "{m}", "--stream"],
}


def _files_case(category: str, asset: str, suffix: str, commands: dict) -> Callable:
    @pytest.mark.parametrize("command", sorted(commands))
    @pytest.mark.parametrize("profile", PROFILE_PARAMS)
    def test(command, profile, assets):
        doc = json.loads(assets[asset].read_text())

        @PROFILES[profile]
        @given(text=mutated_json(doc))
        def example(text):
            with work_folder(assets) as w:
                m = w.write(f"mutated{suffix}", text)
                argv = [m if a == "{m}" else _fill(a, w) for a in commands[command]]
                judge(category, argv, w.root)

        example()

    return test


test_mutated_model_json = _files_case("model JSON", "model", ".json", MODEL_COMMANDS)
test_mutated_recogniser_json = _files_case("recogniser JSON", "recogniser", ".json", RECOGNISER_COMMANDS)


# --------------------------------------------------------------- category ".mat files" (the originals' model)


@pytest.fixture(scope="module")
def original_mats(tmp_path_factory, assets) -> dict[str, bytes]:
    """The synthetic network in the originals' BNT layout, uncompressed (``-v6``) and compressed (``-v7``,
    as the originals' ``BN_lab.mat``): SciPy's reader crashed on some corruptions of the uncompressed form
    only, so both are fuzzed whether or not the real data is here."""
    from test_model_io import write_bnt_mat

    from glu.bn import BayesNet

    folder = tmp_path_factory.mktemp("bnt")
    out = {}
    for form, compress in (("uncompressed", False), ("compressed", True)):
        path = folder / f"BN_{form}.mat"
        write_bnt_mat(BayesNet.load(assets["model"]), path, do_compression=compress)
        out[form] = path.read_bytes()
    return out


@pytest.mark.parametrize("form", ["uncompressed", "compressed"])
@pytest.mark.parametrize("command", ["bn import", "query"])
@pytest.mark.parametrize("profile", PROFILE_PARAMS)
def test_corrupted_mat_files(command, profile, form, assets, original_mats):
    original = original_mats[form]

    @PROFILES[profile]
    @given(
        cut=st.integers(0, len(original)),
        flips=st.lists(st.integers(0, len(original) - 1), max_size=8),
        byte=st.integers(0, 255),
    )
    def example(cut, flips, byte):
        data = bytearray(original)
        for i in flips:
            data[i] = byte
        with work_folder(assets) as w:
            m = w.write("BN.mat", bytes(data[: cut if not flips else len(data)]))
            argv = (
                ["bn", "import", m, "-o", str(w.root / "out" / "x.json")]
                if command == "bn import"
                else ["query", "--model", m, "--target", "Action", "--json"]
            )
            judge(".mat files", argv, w.root)

    example()


# ------------------------------------------------------------------ category "evidence batches"

_query_line = st.one_of(
    _json_value.map(lambda v: json.dumps(v)),
    st.fixed_dictionaries(
        {},
        optional={
            "target": st.one_of(st.sampled_from(["ObjVel", "Action", "Nope", ""]), _json_value),
            "evidence": st.one_of(
                st.dictionaries(
                    st.sampled_from(["Action", "Shape", "Nope"]),
                    st.one_of(st.sampled_from(["tap", "circle", "x"]), _json_value),
                    max_size=2,
                ),
                _json_value,
            ),
            "soft": st.one_of(
                st.dictionaries(
                    st.sampled_from(["Action", "Shape", "ObjVel"]),
                    st.one_of(
                        st.dictionaries(
                            st.sampled_from(["grasp", "tap", "touch", "x"]),
                            st.one_of(st.floats(allow_nan=True), _json_value),
                            max_size=4,
                        ),
                        _json_value,
                    ),
                    max_size=2,
                ),
                _json_value,
            ),
            "soft_rule": st.one_of(st.sampled_from(["virtual", "jeffrey", "nope"]), _json_value),
        },
    ).map(json.dumps),
    st.text(max_size=30),
)


@pytest.mark.parametrize("via", ["file", "stdin"])
@pytest.mark.parametrize("profile", PROFILE_PARAMS)
def test_evidence_batches(via, profile, assets):
    @PROFILES[profile]
    @given(
        lines=st.lists(
            _query_line.map(lambda s: s.replace("\n", " ").replace("\r", " ")), min_size=1, max_size=6
        )
    )
    def example(lines):
        text = "\n".join(lines) + "\n"
        with work_folder(assets) as w:
            batch = w.write("batch.jsonl", text) if via == "file" else "-"
            o = judge(
                "evidence batches",
                ["query", "--model", str(assets["model"]), "--batch", batch],
                w.root,
                stdin=text,
            )
            if o.status == 0:  # one answer per line, in order, strict JSON (judge checked), nothing lost
                assert len(o.out.splitlines()) == len(text.splitlines()), (lines, o.out)

    example()


# ------------------------------------------------------- issue 26: huge declared sizes, silently wrong inputs
# Each case writes its files into the work folder and must fail with one line naming what is wrong; judge()
# also checks that nothing in the folder changed. The expected word comes from the case, not from glu.


def _uai(cards: str, table: str) -> str:
    return f"BAYES\n1\n{cards}\n1\n1 0\n\n{table}\n"


def _write_chain_bif(n: int) -> str:
    lines = [f"variable X{i} {{\n  type discrete [ 2 ] {{ a, b }};\n}}" for i in range(n)]
    lines.append("probability ( X0 ) {\n  table 0.5, 0.5;\n}")
    lines += [
        f"probability ( X{i} | X{i - 1} ) {{\n  (a) 0.3, 0.7;\n  (b) 0.9, 0.1;\n}}" for i in range(1, n)
    ]
    return "\n".join(lines) + "\n"


def _wide_bif(parents: int) -> str:
    """A child of ``parents`` binary parents: a table of 2**parents rows, declared in a few lines."""
    names = [f"P{i}" for i in range(parents)]
    out = [f"variable {n} {{\n  type discrete [ 2 ] {{ a, b }};\n}}" for n in [*names, "C"]]
    out += [f"probability ( {n} ) {{\n  table 0.5, 0.5;\n}}" for n in names]
    out.append(f"probability ( C | {', '.join(names)} ) {{\n  default 0.5, 0.5;\n}}")
    return "\n".join(out) + "\n"


SIZE_CASES = {
    "uai-1e9-values": ("net.uai", _uai("1000000000", "1000000000 0.5"), "1,000,000,000"),
    "uai-1e18-variables": ("net.uai", "BAYES\n1000000000000000000\n2\n", "1,000,000,000,000,000,000"),
    "uai-table-size": ("net.uai", _uai("2", "99999999999 0.5 0.5"), "99,999,999,999"),
    "bif-1e9-values": (
        "net.bif",
        "variable X {\n  type discrete [ 1000000000 ] { a };\n}\n",
        "1,000,000,000",
    ),
    "bif-2**40-table": ("net.bif", _wide_bif(40), "2,199,023,255,552"),  # 2**40 rows × 2 values
    "bif-unclosed-comment": ("net.bif", "/* " + _write_chain_bif(3), "never closed"),
}


@pytest.mark.parametrize("case", sorted(SIZE_CASES))
def test_declared_sizes_are_checked_before_allocating(case, assets):
    name, text, expected = SIZE_CASES[case]
    with work_folder(assets) as w:
        (w.root / name).write_text(text)
        o = judge(
            "huge declared sizes",
            ["bn", "import", str(w.root / name), "-o", str(w.root / "m.json")],
            w.root,
            must_fail=True,
        )
        assert expected in o.err, o.err


def test_a_linear_bif_reader_imports_a_long_chain(assets):
    """Correctness of the one-pass reader on a long file (its speed is in benchmarks/bench_bif_import.py)."""
    with work_folder(assets) as w:
        (w.root / "chain.bif").write_text(_write_chain_bif(2000))
        o = judge(
            "huge declared sizes",
            ["bn", "import", str(w.root / "chain.bif"), "-o", str(w.root / "m.json")],
            w.root,
        )
        assert o.status == 0 and "2000 nodes, 1999 edges" in o.out


SCHEMA = (
    "format: glu-schema\nversion: 1\nname: t\nnodes:\n"
    "  - {name: Tool, values: [stick, hook], role: action, set_by_experimenter: true}\n"
    "  - {name: Shape, values: [ball, cube], role: object, set_by_experimenter: true}\n"
    "  - {name: Moves, values: ['no', 'yes'], role: effect}\n"
    "words: [the, ball, cube, moves]\n"
)
TABLE = "Tool,Shape,Moves,description\n" + "".join(
    f"{t},{s},{m},the {s} moves\n" for t in ("stick", "hook") for s in ("ball", "cube") for m in ("no", "yes")
)


def _silently_wrong(w: Work, case: str) -> tuple[list[str], str]:
    r = w.root
    (r / "schema.yaml").write_text(SCHEMA)
    (r / "table.csv").write_text(TABLE)
    own = ["--schema", str(r / "schema.yaml"), "--experiments", str(r / "table.csv")]
    out = ["-o", str(r / "m.json")]
    if case == "alias-onto-a-value":
        (r / "schema.yaml").write_text(SCHEMA.replace("nodes:", "aliases: {Shape: {cube: ball}}\nnodes:"))
        return ["bn", "learn", *own, *out], "alias 'cube'"
    if case == "column-twice":
        (r / "table.csv").write_text(TABLE.replace("description\n", "description,Tool\n", 1))
        return ["bn", "learn", *own, *out], "appears twice"
    if case == "complex-npy":
        np.save(r / "g.npy", np.ones((5, 4), dtype=complex))
        return ["recognize", str(r / "g.npy"), "--models", str(w.assets["recogniser"])], "complex"
    if case == "empty-feature-list":
        return ["hmm", "train", "--synthetic", "2", "--features", " , ", *out], "no invariance"
    if case == "anticipate-unused-options":
        return ["anticipate", "--case", "sphere", *own], "not used"
    if case == "unknown-label":
        return ["gestures", "segment", str(w.assets["log"]), "--label", "poke"], "'poke'"
    if case == "tiny-body-size":
        np.savetxt(
            r / "g.csv",
            np.c_[np.arange(5) * 0.03, np.full((5, 3), 0.2)],
            delimiter=",",
            header="t,x,y,z",
            comments="",
        )
        return [
            "recognize",
            str(r / "g.csv"),
            "--models",
            str(w.assets["recogniser"]),
            "--body-size",
            "1e-300",
            "1e-300",
        ], "body size"
    if case == "huge-hmm-means":
        doc = json.loads(w.assets["recogniser"].read_text())
        text = re.sub(
            r'("means": )(\[[^a-z]*?\]\]\])',
            lambda m: m.group(1) + re.sub(r"-?\d[\d.e+-]*", "1e300", m.group(2)),
            json.dumps(doc),
        )
        (r / "r.json").write_text(text)
        return ["recognize", str(w.assets["log"]), "--models", str(r / "r.json")], "means"
    if case == "synthetic-overflow":
        return ["hmm", "train", "--synthetic", "99999999999999999999", *out], "at most"
    if case == "nested-model":
        (r / "deep.json").write_text("[" * 100_000 + "]" * 100_000)
        return ["bn", "edges", str(r / "deep.json")], "nested too deeply"
    raise AssertionError(case)


SILENT_CASES = [
    "alias-onto-a-value",
    "column-twice",
    "complex-npy",
    "empty-feature-list",
    "anticipate-unused-options",
    "unknown-label",
    "tiny-body-size",
    "huge-hmm-means",
    "synthetic-overflow",
    "nested-model",
]


@pytest.mark.parametrize("case", SILENT_CASES)
def test_once_silently_wrong_or_a_traceback_now_one_line(case, assets):
    with work_folder(assets) as w:
        argv, expected = _silently_wrong(w, case)
        o = judge("silently wrong", argv, w.root, must_fail=True)
        assert expected in o.err.strip().splitlines()[-1], o.err


def test_a_batch_line_with_an_unknown_soft_rule_is_an_error_line(assets):
    with work_folder(assets) as w:
        line = json.dumps({"target": ["Action"], "soft_rule": "bogus"})
        o = judge(
            "silently wrong",
            ["query", "--model", str(assets["model"]), "--batch", "-"],
            w.root,
            stdin=line + "\n",
        )
        assert json.loads(o.out) == {"error": "line 1: unknown soft_rule 'bogus'; allowed: virtual, jeffrey"}


def test_printed_posteriors_are_probabilities(assets):
    """Hard evidence on the target itself: the posterior is exactly 1, never 1.0000000000000002."""
    with work_folder(assets) as w:
        for target, value in (("Action", "tap"), ("Shape", "box"), ("ObjVel", "slow")):
            argv = ["query", "--model", str(assets["model"]), "--target", target, "ObjVel", "--evidence"]
            o = judge("silently wrong", [*argv, f"{target}={value}", "--json"], w.root)
            for dist in json.loads(o.out).values():
                assert all(0.0 <= p <= 1.0 for p in dist.values()), dist


def test_a_truncated_sweep_chunk_is_glus_own_message(tmp_path):
    from glu.errors import DataError
    from glu.studies.corpus_evaluation.tables import read_chunk

    chunk = tmp_path / "c.npz"
    np.savez(chunk, meta=np.array("{}"), estimate=np.zeros(3))
    chunk.write_bytes(chunk.read_bytes()[:40])
    with pytest.raises(DataError, match="unreadable chunk"):
        read_chunk(chunk, "x")
