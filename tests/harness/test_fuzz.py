"""Property-based fuzzing of every ``glu`` subcommand (issue 11): generated bad arguments and corrupted files.

Every run must end in one of two ways: exit 2 with one error line on stderr (what, where, what is allowed), or
exit 0 with valid output (strict JSON under ``--json``, no ``nan``/``inf`` in text). Never a traceback, never
the last-resort "internal error", never a RuntimeWarning, and nothing left in the output folder after a
failure. The subcommands come from the parser itself: a new subcommand without an entry in :data:`COMMANDS`
fails :func:`test_every_subcommand_is_fuzzed`.

CI runs the ``ci`` profile (deterministic, a few examples a test, well under a minute); ``-m slow`` runs
:func:`test_long_profile` with many more. The counts of inputs tried per category are written to
``build/fuzz-counts.json`` and printed at the end of the module (``pytest -s``).
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import re
import socket
import stat
import warnings
from pathlib import Path

import numpy as np
import pytest
from cli_run import train_recogniser
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from glu.cli import build_parser, main
from glu.schema import GLU_SCHEMA_FILE

PROFILE = settings(
    max_examples=30, deadline=None, derandomize=True, database=None, suppress_health_check=list(HealthCheck)
)
LONG = settings(
    max_examples=150, deadline=None, derandomize=True, database=None, suppress_health_check=list(HealthCheck)
)

COUNTS: collections.Counter[str] = collections.Counter()
MISBEHAVED: list[str] = []

NUMBERS = [
    "-1",
    "0",
    "-0",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e400",
    "",
    " ",
    "abc",
    "1.5",
    "1e-400",
    "99999999999999999999",
    "0x10",
    "1_000",
    "2**32",
    "-1e9",
    "3",
]
WORDS = ["", " ", "zzz", "TAP", "grasp,", ",", "..", "\x00", "é", "a b", "--json", "-"]
EVIDENCE = [
    "Action",
    "Action=",
    "=tap",
    "Action=zzz",
    "Nope=tap",
    "Action=tap=1",
    "Action=tap",
    "Shape=box",
    "Action==tap",
    "",
    "Action=tap Action=grasp",
]
SOFT = [
    "Action=grasp:2",
    "Action=grasp:nan",
    "Action=grasp:-1,tap:2",
    "Action:",
    "Action=grasp:1e-400,tap:1e-400",
    "Action=grasp:0,tap:0,touch:0",
    "Action=grasp:0.2,tap:0.6,touch:0.2",
    "Action=grasp:inf",
    "ObjVel=slow:1",
    "Action=grasp:0.5,grasp:0.5",
    "Action=[1,2]",
]
FRAMES = ["5:2", "a:b", "-1:3", "0:0", "1:1", "1:100000", "10:20", ":", "3", "1:2:3"]


def _kind(action: argparse.Action) -> str:
    name = getattr(action.type, "__name__", str(action.type))
    if action.choices:
        return "choice"
    if action.nargs == 0:
        return "flag"
    if name in (
        "integer",
        "positive_int",
        "seed",
        "positive_float",
        "nonneg_float",
        "int",
        "float",
        "_sample_count",
    ):
        return "number"
    if name in ("output_file", "output_folder", "Path") or action.dest in (
        "out",
        "plot",
        "notebooks",
    ):
        return "path"
    if action.dest in ("evidence",):
        return "evidence"
    if action.dest in ("soft",):
        return "soft"
    if action.dest in ("frames",):
        return "frames"
    return "text"


def _leaves(parser: argparse.ArgumentParser, prefix: tuple[str, ...] = ()):
    subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if not subs:
        yield prefix, parser
        return
    for name, sp in subs[0].choices.items():
        yield from _leaves(sp, (*prefix, name))


LEAVES = {" ".join(path): sp for path, sp in _leaves(build_parser())}

# Each subcommand: the arguments it always gets (so a run reaches validation fast), and whether a fully valid
# random combination may run (light commands) or every run must carry one value that is certainly wrong
# (heavy ones: a valid reproduce or sweep would take minutes).
COMMANDS: dict[str, tuple[list[str], bool]] = {
    "data fetch": (
        ["-o", "{tmp}/out/data", "--mirror", "http://127.0.0.1:9/data", "--timeout", "2"],
        False,
    ),
    "data synth": (["-o", "{tmp}/out/synth", "--n", "200"], True),
    "data info": (["--data", "{data}"], True),
    "bn learn": (["--data", "{data}", "-o", "{tmp}/out/m.json"], True),
    "bn edges": (["{model}"], True),
    "bn nodes": (["{model}"], True),
    "bn import": (["{model}", "-o", "{tmp}/out/m2.json"], True),
    "bn export": (["{model}", "--format", "bif", "--zero-rows", "seen", "-o", "{tmp}/out/m.bif"], True),
    "query": (["--model", "{model}", "--target", "ObjVel"], True),
    "gestures segment": (["{log}"], True),
    "hmm train": (
        ["--synthetic", "2", "--states", "2", "--mix", "1", "--iter", "2", "-o", "{tmp}/out/r.json"],
        False,
    ),
    "recognize": (["{log}", "--models", "{recogniser}"], True),
    "reproduce": (["-o", "{tmp}/out/repro", "--quick"], False),
    "run": (["07_glu2017_figures", "-o", "{tmp}/out/run"], False),
    "describe": (["--model", "{model}"], True),
    "anticipate": (["--case", "sphere", "--models", "{recogniser}", "--data", "{data}"], False),
    "readme": (["--summary", "{tmp}/none.json", "--readme", "{tmp}/README.md"], True),
    "evaluate": (["-o", "{tmp}/out/eval", "--episodes", "12"], False),
    "correspondence": (["-o", "{tmp}/out/corr"], False),
    "corpus": (["-o", "{tmp}/out/c.parquet", "--episodes", "12"], False),
    "learn-gestures": (
        [
            "--episodes",
            "12",
            "--labels",
            "soft",
            "--states",
            "2",
            "--mix",
            "1",
            "--iter",
            "2",
            "--data",
            "{data}",
        ]
        + ["-o", "{tmp}/out/l.json"],
        False,
    ),
    "learning-curves": (
        ["--episodes", "12", "--seeds", "0", "--scheduler", "synchronous"]
        + ["--data", "{data}", "-o", "{tmp}/out/lc"],
        False,
    ),
}
CERTAINLY_BAD = {  # one value each heavy command refuses before any work
    "data fetch": ["--timeout", "-1"],
    "hmm train": ["--seed", "-1"],
    "reproduce": ["--jobs", "0"],
    "run": ["--parameter", "rulez", "jeffrey"],
    "anticipate": ["--step", "0"],
    "evaluate": ["--episodes", "0"],
    "correspondence": ["--workers", "0"],
    "corpus": ["--episodes", "0"],
    "learn-gestures": ["--episodes", "0"],
    "learning-curves": ["--episodes", "0"],
}


def test_every_subcommand_is_fuzzed():
    assert set(LEAVES) == set(COMMANDS), f"fuzz these too (COMMANDS): {sorted(set(LEAVES) - set(COMMANDS))}"
    assert {c for c, (_, light) in COMMANDS.items() if not light} == set(CERTAINLY_BAD)


@pytest.fixture(scope="module")
def files(tmp_path_factory, synthetic_folder):
    """Valid inputs the fuzzer starts from: a model, a hand log, a recogniser (all synthetic)."""
    base = tmp_path_factory.mktemp("fuzz-inputs")
    model, recogniser = base / "model.json", base / "r.json"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["bn", "learn", "--data", str(synthetic_folder), "-o", str(model)]) == 0
        train_recogniser(recogniser, states=3, n_iter=5)
    log = base / "tap.log"
    log.write_bytes((synthetic_folder / "gestures" / "tap1_hand" / "data.log").read_bytes())
    loop = base / "loop"
    loop.symlink_to(loop)
    return {
        "model": model,
        "recogniser": recogniser,
        "log": log,
        "data": synthetic_folder,
        "special": special_file(base),
        "loop": loop,
    }


def null_device(folder: Path) -> Path | None:
    """A character device like /dev/null (major 1, minor 3) made in ``folder``; None unless root."""
    if os.geteuid() != 0:
        return None
    dev = folder / "null"
    os.mknod(dev, 0o666 | stat.S_IFCHR, os.makedev(1, 3))
    return dev


def special_file(folder: Path) -> Path:
    """A file that is not a regular file, made in ``folder`` (never a system path): a null device when
    root, else a Unix socket (opening it fails: a clear error, never a hang as a FIFO without a reader)."""
    dev = null_device(folder)
    if dev is not None:
        return dev
    path = folder / "sock"
    s = socket.socket(socket.AF_UNIX)
    s.bind(str(path))
    s.close()
    return path


def _check(category: str, argv: list[str], tmp: Path, capsys) -> None:
    """Run ``glu argv`` in-process and record (and fail on) any misbehaviour."""
    COUNTS[category] += 1
    out_dir = tmp / "out"
    before = sorted(p for p in out_dir.rglob("*")) if out_dir.exists() else []
    capsys.readouterr()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            status = main(argv)
        except SystemExit as e:
            status = e.code
        except BaseException as e:  # noqa: BLE001 - anything escaping main() is a misbehaviour
            status = f"escaped {type(e).__name__}: {e}"
    out, err = capsys.readouterr()
    problems = []
    if status not in (0, 2):
        problems.append(f"exit {status}")
    if "Traceback" in err or "internal error" in err:
        problems.append("traceback or internal error")
    runtime = [w for w in caught if issubclass(w.category, RuntimeWarning)]
    if runtime:
        problems.append(f"RuntimeWarning: {runtime[0].message}")
    if status == 2:
        errors = [line for line in err.splitlines() if ": error:" in line or line.startswith("glu: error")]
        if len(errors) != 1 or err.strip().splitlines()[-1] != errors[0].strip():
            problems.append(f"not one error line at the end: {err[-300:]!r}")
        after = sorted(p for p in out_dir.rglob("*")) if out_dir.exists() else []
        if after != before:
            problems.append(
                f"left {[str(p.relative_to(tmp)) for p in after if p not in before][:3]} after failing"
            )
    if status == 0:
        if "--json" in argv and out.strip():
            try:
                for line in out.strip().splitlines() if "--batch" in argv or "--stream" in argv else [out]:
                    json.loads(line, parse_constant=lambda c: (_ for _ in ()).throw(ValueError(c)))
            except ValueError as e:
                problems.append(f"--json output is not strict JSON ({e})")
        given = {a.lower() for a in argv}  # a label the user typed ("--label nan") is echoed, not computed
        found = [m.group(0) for m in re.finditer(r"(?<![\w-])-?(nan|inf)(?![\w])", out, re.IGNORECASE)]
        if [f for f in found if f.lower() not in given]:
            problems.append("nan or inf in the output")
    if problems:
        MISBEHAVED.append(f"glu {' '.join(argv)}: {'; '.join(problems)}")
        pytest.fail(f"glu {' '.join(argv)!r} misbehaved: {'; '.join(problems)}\nstderr: {err[-800:]}")


def _value(kind: str):
    return {
        "number": st.sampled_from(NUMBERS),
        "path": st.sampled_from(
            ["", "/nonexistent/x/y", "{tmp}", "{tmp}/out/", "{model}", "{special}", "{loop}"]
        ),
        "choice": st.sampled_from(WORDS),
        "evidence": st.sampled_from(EVIDENCE),
        "soft": st.sampled_from(SOFT),
        "frames": st.sampled_from(FRAMES),
        "text": st.sampled_from(WORDS + NUMBERS[:4]),
    }[kind]


@st.composite
def _arguments(draw, command: str) -> list[str]:
    parser = LEAVES[command]
    options = [a for a in parser._actions if a.option_strings and not isinstance(a, argparse._HelpAction)]
    if not options:  # only positional arguments (bn edges): stray words and unknown flags
        return draw(st.lists(st.sampled_from(["--nope", "extra", "-", "--json", ""]), min_size=1, max_size=2))
    chosen = draw(st.lists(st.sampled_from(options), min_size=1, max_size=3, unique_by=lambda a: a.dest))
    argv = []
    for a in chosen:
        flag = a.option_strings[-1]
        kind = _kind(a)
        if kind == "flag":
            argv.append(flag)
        else:
            argv += [flag, draw(_value(kind))]
    return argv


def _fill(args: list[str], tmp: Path, files: dict) -> list[str]:
    return [a.format(tmp=tmp, **files) for a in args]


def _fuzz_command(command: str, tmp_path_factory, files, capsys, profile) -> None:
    base, light = COMMANDS[command]

    @profile
    @given(extra=_arguments(command))
    def run(extra):
        tmp = tmp_path_factory.mktemp("fuzz")
        argv = [*command.split(), *_fill(base, tmp, files), *_fill(extra, tmp, files)]
        if not light:
            argv += CERTAINLY_BAD[command]
        _check(f"arguments: {command}", argv, tmp, capsys)

    run()


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_bad_arguments(command, tmp_path_factory, files, capsys):
    _fuzz_command(command, tmp_path_factory, files, capsys, PROFILE)


# ---------------------------------------------------------------- corrupted files
def _mutate(data: bytes, how: str, at: int, junk: bytes) -> bytes:
    i = at % (len(data) + 1)
    return {
        "truncate": data[:i],
        "insert": data[:i] + junk + data[i:],
        "replace": data[:i] + junk + data[i + len(junk) :],
        "nan": data[:i] + b" nan " + data[i:],
        "huge": data[:i] + b" 1e308 " + data[i:],
        "empty": b"",
    }[how]


MUTATION = st.tuples(
    st.sampled_from(["truncate", "insert", "replace", "nan", "huge", "empty"]),
    st.integers(0, 10**6),
    st.binary(min_size=1, max_size=12),
)


def _hand_log(m, tmp_path_factory, files, capsys):
    tmp = tmp_path_factory.mktemp("fuzz")
    log = tmp / "bad.log"
    log.write_bytes(_mutate(files["log"].read_bytes(), *m))
    _check(
        "files: hand log → recognize",
        ["recognize", str(log), "--models", str(files["recogniser"]), "--json"],
        tmp,
        capsys,
    )
    _check("files: hand log → gestures segment", ["gestures", "segment", str(log)], tmp, capsys)


def _json_mutations(obj, draw_path: list[int], replacement):
    """Replace the node reached by ``draw_path`` (indices into dict items / list elements) with
    ``replacement``."""
    if not draw_path or not isinstance(obj, dict | list) or not obj:
        return replacement
    keys = list(obj) if isinstance(obj, dict) else list(range(len(obj)))
    k = keys[draw_path[0] % len(keys)]
    out = dict(obj) if isinstance(obj, dict) else list(obj)
    out[k] = _json_mutations(obj[k], draw_path[1:], replacement)
    return out


JSON_VALUES = st.sampled_from(
    [
        None,
        0,
        -1,
        1e300,
        "x",
        "",
        [],
        {},
        [[[]]],
        {"a": {"b": {}}},
        True,
        [0.5, 0.5],
        [1.0, 1.0],
        [float("1e-320")],
        "slow",
    ]
)


def _model_json(path, value, tmp_path_factory, files, capsys):
    tmp = tmp_path_factory.mktemp("fuzz")
    model = tmp / "model.json"
    model.write_text(json.dumps(_json_mutations(json.loads(files["model"].read_text()), path, value)))
    _check(
        "files: model JSON → query",
        ["query", "--model", str(model), "--target", "ObjVel", "--evidence", "Action=tap", "--json"],
        tmp,
        capsys,
    )
    _check(
        "files: model JSON → bn export",
        [
            "bn",
            "export",
            str(model),
            "--format",
            "xmlbif",
            "--zero-rows",
            "seen",
            "-o",
            str(tmp / "out" / "m.xmlbif"),
        ],
        tmp,
        capsys,
    )


MAT_FIELDS = st.dictionaries(
    st.sampled_from(["dag", "names", "cpt", "node_sizes", "x", "netobj_lab"]),
    st.sampled_from([0, 1, "a", [1, 2], [[0, 1], [1, 0]], [[1, 1], [1, 0]]]),
    max_size=4,
)


def _mat_file(m, fields, tmp_path_factory, files, capsys):
    import scipy.io

    tmp = tmp_path_factory.mktemp("fuzz")
    mat = tmp / "bad.mat"
    scipy.io.savemat(
        mat, {k: np.array(v, dtype=object) if isinstance(v, list) else v for k, v in fields.items()}
    )
    if m[0] != "empty" or not fields:
        mat.write_bytes(_mutate(mat.read_bytes(), *m))
    _check(
        "files: .mat → bn import", ["bn", "import", str(mat), "-o", str(tmp / "out" / "m.json")], tmp, capsys
    )


BATCH_LINES = st.lists(
    st.one_of(
        st.sampled_from(
            [
                '{"target": ["ObjVel"], "evidence": {"Action": "tap"}}',
                '{"target": "ObjVel"}',
                "[]",
                "1",
                '{"target": ["ObjVel"], "soft": {"Action": {"grasp": "x"}}}',
                '{"target": [["ObjVel"]]}',
                '{"target": ["Nope"]}',
                '{"evidence": {"Action": ["tap"]}, "target": ["ObjVel"]}',
                "",
                '{"target": ["ObjVel"], "soft": {"Action": [0.2, 0.8]}}',
                "{",
                "null",
                '{"target": ["ObjVel"], "evidence": {"Action": "tap", "Shape": "box", "Size": "big"}, '
                '"soft": {"Action": {"grasp": 1e-322, "tap": 1e-322, "touch": 0}}}',
            ]
        ),
        st.text(max_size=20),
    ),
    min_size=1,
    max_size=6,
)


def _query_batch(lines, tmp_path_factory, files, capsys):
    tmp = tmp_path_factory.mktemp("fuzz")
    batch = tmp / "q.jsonl"
    batch.write_text("\n".join(lines) + "\n")
    _check(
        "files: query batch", ["query", "--model", str(files["model"]), "--batch", str(batch)], tmp, capsys
    )


FILE_CASES = {
    "hand logs": (_hand_log, {"m": MUTATION}),
    "model JSON": (
        _model_json,
        {"path": st.lists(st.integers(0, 60), min_size=1, max_size=5), "value": JSON_VALUES},
    ),
    ".mat files": (_mat_file, {"m": MUTATION, "fields": MAT_FIELDS}),
    "query batches": (_query_batch, {"lines": BATCH_LINES}),
}


def _fuzz_files(case: str, tmp_path_factory, files, capsys, profile) -> None:
    check, strategies = FILE_CASES[case]

    @profile
    @given(**strategies)
    def run(**drawn):
        check(**drawn, tmp_path_factory=tmp_path_factory, files=files, capsys=capsys)

    run()


@pytest.mark.parametrize("case", FILE_CASES)
def test_corrupted_files(case, tmp_path_factory, files, capsys):
    _fuzz_files(case, tmp_path_factory, files, capsys, PROFILE)


@pytest.mark.slow
@pytest.mark.parametrize("command", sorted(c for c, (_, light) in COMMANDS.items() if light))
def test_long_profile(command, tmp_path_factory, files, capsys):
    _fuzz_command(command, tmp_path_factory, files, capsys, LONG)


@pytest.mark.slow
@pytest.mark.parametrize("case", FILE_CASES)
def test_long_profile_files(case, tmp_path_factory, files, capsys):
    _fuzz_files(case, tmp_path_factory, files, capsys, LONG)


@pytest.fixture(scope="module", autouse=True)
def _report():
    yield
    if COUNTS:
        root = Path(__file__).resolve().parents[2] / "build"
        root.mkdir(exist_ok=True)
        summary = {
            "inputs": dict(sorted(COUNTS.items())),
            "total": sum(COUNTS.values()),
            "misbehaved": MISBEHAVED,
        }
        (root / "fuzz-counts.json").write_text(json.dumps(summary, indent=1))
        print(f"\nfuzz: {summary['total']} inputs, {len(MISBEHAVED)} misbehaved")
        for k, v in summary["inputs"].items():
            print(f"  {v:5d}  {k}")


# ----------------------------------------------------------- devices, FIFOs, symlink loops, inputs as outputs
def _run(argv: list[str], capsys) -> tuple[int, str, str]:
    capsys.readouterr()
    try:
        status = main([str(a) for a in argv])
    except SystemExit as e:  # a usage error, from argparse
        status = e.code
    out, err = capsys.readouterr()
    COUNTS["devices and inputs"] += 1
    return status, out, err


def _one_error_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and ": error: " in lines[0] and "Traceback" not in err, err
    return lines[0]


def test_an_output_device_is_written_through_never_replaced(tmp_path, files, capsys):
    dev = null_device(tmp_path)
    if dev is None:
        pytest.skip("making a character device needs root")
    for argv in (
        ["bn", "learn", "--data", files["data"], "-o", dev],
        ["bn", "export", files["model"], "--format", "bif", "--zero-rows", "seen", "-o", dev],
    ):
        status, out, err = _run(argv, capsys)
        assert status == 0 and f"wrote {dev}" in out, err
        assert stat.S_ISCHR(os.lstat(dev).st_mode)  # still the device, not a file renamed over it
        assert list(tmp_path.iterdir()) == [dev]  # no temporary file left beside it


def test_an_output_fifo_is_written_through(tmp_path, files, capsys):
    import threading

    fifo = tmp_path / "pipe.bif"
    os.mkfifo(fifo)
    got: list[bytes] = []
    reader = threading.Thread(target=lambda: got.append(fifo.read_bytes()))
    reader.start()
    status, _, err = _run(["bn", "export", files["model"], "--zero-rows", "seen", "-o", fifo], capsys)
    reader.join(timeout=60)
    assert status == 0, err
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    assert got and got[0].startswith(b"network") and b"variable ObjVel" in got[0]


def test_dash_writes_the_file_to_stdout_and_messages_to_stderr(files, capsys):
    status, out, err = _run(
        ["bn", "export", files["model"], "--format", "bif", "--zero-rows", "seen", "-o", "-"], capsys
    )
    assert status == 0
    assert out.startswith("network") and "wrote -" not in out and "wrote -" in err


def test_a_folder_output_cannot_be_a_device_or_stdout(tmp_path, files, capsys):
    for target in ("-", files["special"]):
        status, _, err = _run(["data", "synth", "-o", target], capsys)
        assert status == 2 and "give a folder" in _one_error_line(err)


def test_symlink_loops_and_overlong_paths_are_one_line(tmp_path, files, capsys):
    long = tmp_path / ("x" * 300) / "m.json"
    for argv in (
        ["bn", "edges", files["loop"]],
        ["bn", "learn", "--data", files["loop"], "-o", tmp_path / "m.json"],
        ["bn", "learn", "--data", files["data"], "-o", files["loop"]],
        ["bn", "learn", "--data", files["data"], "-o", long],
        ["bn", "edges", long],
    ):
        status, _, err = _run(argv, capsys)
        assert status == 2, err
        _one_error_line(err)


@pytest.mark.parametrize("which", ["experiments", "schema", "link", "data-file"])
def test_an_output_that_is_an_input_is_refused_before_any_work(tmp_path, files, capsys, which):
    import shutil

    data = tmp_path / "data"
    shutil.copytree(files["data"], data)
    schema = tmp_path / "schema.json"
    schema.write_bytes(GLU_SCHEMA_FILE.read_bytes())
    table = tmp_path / "experiments.csv"
    table.write_text("a\n")
    (tmp_path / "link").symlink_to(table)
    target = {
        "experiments": table,
        "schema": schema,
        "link": tmp_path / "link",
        "data-file": data / "affordance-words" / "networkDefinition.txt",
    }[which]
    before = target.read_bytes()
    own = ["--schema", schema, "--experiments", table]
    argv = ["bn", "learn", *(["--data", data] if which == "data-file" else own), "-o", target]
    status, _, err = _run(argv, capsys)
    assert status == 2 and "input" in _one_error_line(err)
    assert target.read_bytes() == before


def test_corpus_refuses_its_config_as_output(tmp_path, capsys):
    config = tmp_path / "sweep.toml"
    config.write_text("episodes = 12\n")
    status, _, err = _run(["corpus", "--config", config, "-o", config], capsys)
    assert status == 2 and "--config" in _one_error_line(err)
    assert config.read_text() == "episodes = 12\n"
