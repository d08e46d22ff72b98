"""Bad arguments are refused where they enter, before any work: one line, exit 2 (issue 11)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from cli_run import run

from glu.cli import main


def _glu(capsys, *argv):
    try:
        status = main([str(a) for a in argv])
    except SystemExit as e:  # argparse refuses an argument by exiting
        status = e.code
    out, err = capsys.readouterr()
    return status, out, err


@pytest.mark.parametrize(
    "argv",
    [
        ["hmm", "train", "--synthetic", "3", "--seed", "-1", "-o", "{tmp}/r.json"],
        ["data", "synth", "--seed", "-1", "-o", "{tmp}/d"],
        ["data", "synth", "--seed", str(2**32), "-o", "{tmp}/d"],
        ["evaluate", "--seed", "-1", "-o", "{tmp}/e"],
        ["describe", "--sample", "5", "--seed", "-1", "--evidence", "Action=grasp"],
        ["reproduce", "--seed", "-1", "--out", "{tmp}/o"],
    ],
)
def test_a_seed_is_a_whole_number_in_0_to_2_32(capsys, tmp_path, argv):
    status, out, err = _glu(capsys, *(a.format(tmp=tmp_path) for a in argv))
    assert status == 2 and out == "" and err.count("\n") == 1
    assert "a seed is a whole number in [0, 2**32 - 1]" in err
    assert not any(tmp_path.iterdir())  # nothing was written


@pytest.mark.parametrize(
    ("out", "message"),
    [
        ("", "expected a file name, not an empty string"),
        ("{tmp}", "is a folder; give a file name"),
        ("{tmp}/a_file/r.json", "a_file is a file, not a folder"),
    ],
)
def test_hmm_train_checks_its_output_before_training(capsys, tmp_path, out, message):
    (tmp_path / "a_file").write_text("x")
    status, stdout, err = _glu(capsys, "hmm", "train", "--synthetic", "3", "-o", out.format(tmp=tmp_path))
    assert (
        status == 2 and stdout == "" and err.count("\n") == 1 and message in err
    )  # no "data: …" line: no work done


def test_an_unwritable_output_folder_is_refused_at_once(capsys, tmp_path, monkeypatch):
    real_access = os.access
    monkeypatch.setattr(os, "access", lambda p, mode: False if Path(p) == tmp_path else real_access(p, mode))
    status, out, err = _glu(capsys, "bn", "learn", "--data", "synthetic", "-o", tmp_path / "m.json")
    assert status == 2 and out == "" and f"the folder {tmp_path} is not writable" in err
    assert list(tmp_path.iterdir()) == []


def test_describe_refuses_a_maximum_below_the_shortest_sentence(capsys):
    status, out, err = _glu(capsys, "describe", "--max-length", "3", "--evidence", "Action=grasp")
    assert (
        status == 2 and "the grammar's shortest sentence has 8 words; give at least 8" in err.splitlines()[-1]
    )


def test_describe_bounds_the_number_of_random_sentences(capsys):
    from glu.language.sampling import MAX_SAMPLES

    status, out, err = _glu(capsys, "describe", "--sample", MAX_SAMPLES + 1, "--evidence", "Action=grasp")
    assert status == 2 and out == "" and f"at most {MAX_SAMPLES:,} random sentences" in err


def test_sample_sentences_refuses_too_many():
    from glu.errors import GrammarError
    from glu.language.grammar import load_grammar
    from glu.language.sampling import MAX_SAMPLES, sample_sentences

    with pytest.raises(GrammarError, match="at most"):
        sample_sentences(load_grammar(None), MAX_SAMPLES + 1)


def test_impossible_sentences_print_as_impossible_never_as_inf(capsys):
    status, out, err = _glu(capsys, "describe", "--sample", "5", "--seed", "1", "--evidence", "Action=grasp")
    assert status == 0 and "inf" not in out and "nan" not in out.lower()
    assert "impossible" in out  # these five random sentences each have a word of probability 0 under grasp
    status, out, _ = _glu(
        capsys, "describe", "--sample", "5", "--seed", "1", "--evidence", "Action=grasp", "--json"
    )
    rows = json.loads(out, parse_constant=lambda c: pytest.fail(f"{c} in --json output"))
    assert [r["score"] for r in rows] == [None] * 5


@pytest.mark.parametrize(
    "mirror", ["http://[::1", "ftp:", "http://host:port/x", "file:///tmp", "localhost:8000"]
)
def test_a_malformed_mirror_url_is_refused_before_any_request(capsys, tmp_path, mirror):
    status, out, err = _glu(capsys, "data", "fetch", "-o", tmp_path / "d", "--mirror", mirror)
    assert status == 2 and err.count("\n") == 1 and "expected an http:// or https:// URL" in err
    assert not (tmp_path / "d").exists()


def test_a_stray_marker_does_not_relabel_verified_real_data_and_synth_never_overwrites_it(
    capsys, tmp_path, monkeypatch
):
    from glu.data import fetch
    from glu.data.source import SYNTHETIC_MARKER, resolve_data

    folder = tmp_path / "real"
    assert main(["data", "synth", "--n", "200", "-o", str(folder)]) == 0
    tables = {p: p.read_bytes() for p in folder.rglob("*") if p.is_file() and p.name != SYNTHETIC_MARKER}
    # the checksums say this folder is the published data (as test_fetch checks them on the real files)
    monkeypatch.setattr(fetch, "published_origin", lambda root, *a, **k: "owner/repo@abc1234")
    assert resolve_data(folder).kind == "real"  # the marker file is stray: ignored
    capsys.readouterr()
    for force in ([], ["--force"]):
        status, out, err = _glu(capsys, "data", "synth", "-o", folder, *force)
        assert status == 2 and "holds the published real data" in err and "never overwrites it" in err
    assert {p: p.read_bytes() for p in tables} == tables


def test_synth_replaces_a_foreign_folder_only_with_force(capsys, tmp_path):
    folder = tmp_path / "mine"
    folder.mkdir()
    (folder / "notes.txt").write_text("mine")
    status, out, err = _glu(capsys, "data", "synth", "--n", "200", "-o", folder)
    assert status == 2 and "refusing to overwrite" in err and (folder / "notes.txt").read_text() == "mine"
    status, out, err = _glu(capsys, "data", "synth", "--n", "200", "-o", folder, "--force")
    assert status == 0 and not (folder / "notes.txt").exists() and (folder / "SYNTHETIC.json").is_file()


def test_json_output_is_strict_json_with_impossible_as_null():
    from glu.cli.common import json_text

    text = json_text(
        {"loglik": {"tap": -1.5, "grasp": float("-inf")}, "scores": [float("inf"), 0.25], "n": 3}
    )
    assert json.loads(text, parse_constant=lambda c: pytest.fail(c)) == {
        "loglik": {"tap": -1.5, "grasp": None},
        "scores": [None, 0.25],
        "n": 3,
    }
    with pytest.raises(ValueError):  # a NaN is a bug: never printed as JSON's non-standard NaN
        json_text({"p": float("nan")})


# -------------------------------------------------------- found by tests/harness/test_fuzz_mutations.py


def _one_line(status, err):
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert status == 2 and ": error:" in lines[-1] and sum(": error:" in ln for ln in lines) == 1, err
    assert "Traceback" not in err and "internal error" not in err
    return lines[-1]


def test_a_number_names_one_notebook_never_a_prefix_of_others():
    from glu.run.reproduce import NotebookError, list_notebooks

    every = [p.stem for p in list_notebooks()]
    assert [p.stem for p in list_notebooks(["1"])] == [every[0]] == [p.stem for p in list_notebooks(["01"])]
    assert [p.stem for p in list_notebooks(["10"])] == [s for s in every if s.startswith("10_")]
    for key in ("0", "00", "", "99"):  # "0" used to select 01 … 09
        with pytest.raises(NotebookError, match="no notebook matches"):
            list_notebooks([key])


def test_failed_evaluate_and_fetch_leave_no_folder_behind(capsys, tmp_path):
    line = _one_line(
        *_glu(capsys, "evaluate", "--episodes", "20", "--data", tmp_path / "no", "-o", tmp_path / "ev")[::2]
    )
    assert "no such data folder" in line
    line = _one_line(
        *_glu(
            capsys,
            "data",
            "fetch",
            "-o",
            tmp_path / "a" / "b" / "d",
            "--mirror",
            "http://127.0.0.1:9/",
            "--timeout",
            "0.5",
        )[::2]
    )
    assert "could not be fetched" in line
    assert list(tmp_path.iterdir()) == []


def test_empty_feature_list_and_unreadable_summary_are_refused(capsys, tmp_path):
    assert "empty string" in _one_line(
        *_glu(capsys, "hmm", "train", "--features", "", "-o", tmp_path / "r.json")[::2]
    )
    bad = tmp_path / "summary.json"
    bad.write_bytes(b"\xff\xfe not utf-8")
    assert "not a readable summary" in _one_line(
        *_glu(capsys, "readme", "--summary", bad, "--readme", tmp_path / "R.md")[::2]
    )
    bad.write_text("[1, 2]")
    assert "expected a JSON object" in _one_line(
        *_glu(capsys, "readme", "--summary", bad, "--readme", tmp_path / "R.md")[::2]
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["summary.json"]


def test_huge_soft_evidence_is_refused_without_a_runtime_warning(capsys):
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # an overflow in the sum used to reach stderr
        status, _, err = _glu(
            capsys,
            "query",
            "--data",
            "synthetic",
            "--target",
            "ObjVel",
            "--soft",
            "Action=grasp:1e308,tap:1e308,touch:1e308",
        )
    assert "not a distribution" in _one_line(status, err)


def _tiny_recogniser(capsys, tmp_path):
    """A recogniser file trained in a second (2 synthetic gestures an action, Q = 2, M = 1, 2 iterations)."""
    rec = tmp_path / "r.json"
    argv = ["hmm", "train", "--synthetic", "2", "--states", "2", "--mix", "1", "--iter", "2", "-o", rec]
    assert _glu(capsys, *argv)[0] == 0
    return rec


@pytest.mark.parametrize(
    "change, fragment",
    [
        (lambda d: d.update(actions=[[], "tap", "touch"]), "'actions' must list exactly the keys"),
        (lambda d: d.update(actions=["tap", "tap", "touch"]), "each once"),
        (lambda d: d.update(training=[1]), "must be JSON objects"),
        (lambda d: d.update(meta=[["x"]]), "must be JSON objects"),
        (lambda d: d["meta"].update(per_frame_loglik={"tap": [None, 1.0]}), "two finite numbers"),
        (lambda d: d["meta"].update(per_frame_loglik={"tap": [2.0, 1.0]}), "two finite numbers"),
    ],
)
def test_a_malformed_recogniser_file_is_one_line(capsys, tmp_path, change, fragment):
    rec = _tiny_recogniser(capsys, tmp_path)
    d = json.loads(rec.read_text())
    change(d)
    rec.write_text(json.dumps(d))
    log = tmp_path / "g.log"
    log.write_text("".join(f"-1 1495933414.{i:02d} {600 + i}.0 -790.0 -930.0\n" for i in range(10)))
    assert fragment in _one_line(*_glu(capsys, "recognize", log, "--models", rec, "--json")[::2])


@pytest.mark.parametrize("mode", [[], ["--json"], ["--stream"], ["--stream", "--json"]])
def test_coordinates_at_the_physical_bound_give_finite_posteriors(capsys, tmp_path, mode):
    from glu.data.hand_logs import MAX_LOGGED_COORDINATE as B

    rec = _tiny_recogniser(capsys, tmp_path)
    near = "".join(f"-1 1495933414.{i:02d} {600 + i}.0 -790.0 -930.0\n" for i in range(10))
    far = "".join(f"-1 1495933415.{i:02d} {B} {-B if i % 2 else B} {B}\n" for i in range(10))
    log = tmp_path / "far.log"
    log.write_text(near + far)
    status, out, err = _glu(capsys, "recognize", log, "--models", rec, *mode)
    assert status == 0 and "nan" not in out.lower() and "inf" not in out.lower()
    if "--json" in mode:
        for line in out.splitlines():
            p = list(json.loads(line, parse_constant=lambda c: pytest.fail(c))["posterior"].values())
            assert all(x is not None and 0 <= x <= 1 for x in p) and abs(sum(p) - 1) < 1e-9


def test_a_model_whose_value_is_not_a_string_is_one_line(capsys, tmp_path):
    model = tmp_path / "m.json"
    assert _glu(capsys, "bn", "learn", "--data", "synthetic", "-o", model)[0] == 0
    d = json.loads(model.read_text())
    next(n for n in d["nodes"] if n["name"] == "Shape")["values"][0] = None  # was read as the value "None"
    model.write_text(json.dumps(d))
    line = _one_line(*_glu(capsys, "describe", "--model", model, "--nbest", "2", "--json")[::2])
    assert "must be non-empty strings" in line


def test_a_model_json_with_an_infinite_count_is_one_line(capsys, tmp_path):
    """Found by the long fuzz profile: "n_affordance": Infinity (json reads it) overflowed int()."""
    model = tmp_path / "m.json"
    assert _glu(capsys, "bn", "learn", "--data", "synthetic", "-o", model)[0] == 0
    d = json.loads(model.read_text())
    d["n_affordance"] = float("inf")
    model.write_text(json.dumps(d))
    status, out, err = _glu(capsys, "query", "--model", model, "--target", "ObjVel", "--json")
    assert status == 2 and out == "" and "malformed model (OverflowError" in err.splitlines()[-1]


# ------------------------------------------------------------ text from files never forges a line
@pytest.fixture
def model_json(tmp_path, capsys):
    out = tmp_path / "m.json"
    assert main(["bn", "learn", "--data", "synthetic", "-o", str(out)]) == 0
    capsys.readouterr()
    return out


def _edited(model: Path, dest: Path, change) -> Path:
    doc = json.loads(model.read_text())
    change(doc)
    dest.write_text(json.dumps(doc))
    return dest


def test_a_data_source_with_a_newline_cannot_forge_an_answer_line(capsys, tmp_path, model_json):
    def forge(doc):
        doc["meta"]["data_source"] = "robot data\nAction  tap  1.000000"

    forged = _edited(model_json, tmp_path / "forged.json", forge)
    status, out, _ = run(capsys, "query", "--model", str(forged), "--target", "Action")
    assert status == 0
    lines = out.splitlines()
    assert lines[0] == f"# model {forged} (robot data\\nAction  tap  1.000000)"
    assert [line.split()[1] for line in lines[2:]] == ["grasp", "tap", "touch"]  # the three answers only
    assert not any(line.startswith("Action  tap  1.000000") for line in lines)


@pytest.mark.parametrize("name", ["grasp\x1bc", "tap\u202eevil", "touch\nAction  tap  1.000000", "x\x07\r"])
def test_a_value_name_reaches_the_terminal_escaped(capsys, tmp_path, model_json, name):
    def rename(doc):
        doc["nodes"][0]["values"][0] = name

    model = _edited(model_json, tmp_path / "escape.json", rename)
    for argv in (["query", "--model", str(model), "--target", "Action"], ["bn", "nodes", str(model)]):
        status, out, err = run(capsys, *argv)
        assert status == 0, err
        for bad in ("\x1b", "\u202e", "\x07", "\r"):
            assert bad not in out and bad not in err
        assert len([line for line in out.splitlines() if line.startswith("Action ")]) <= 3


def test_glu_help_imports_no_command():
    """`glu --help` lists every command from glu.cli.commands alone: no command module, no pandas."""
    code = (
        "import sys, contextlib, io\n"
        "from glu.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()) as f:\n"
        "    try:\n"
        "        main(['--help'])\n"
        "    except SystemExit:\n"
        "        pass\n"
        "loaded = sorted(m for m in sys.modules if m.endswith('_cmds') or m.split('.')[0] in "
        "('pandas', 'scipy', 'matplotlib', 'numba'))\n"
        "print(loaded, 'learning-curves' in f.getvalue())\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.stdout.strip() == "[] True", r.stdout + r.stderr


def test_the_full_parser_lists_the_commands_of_the_table_with_their_lines():
    from glu.cli import build_parser
    from glu.cli.commands import COMMANDS

    sub = next(a for a in build_parser()._actions if a.dest == "command")
    assert list(sub.choices) == list(COMMANDS)
    assert {c.dest: c.help for c in sub._choices_actions} == {k: v.help for k, v in COMMANDS.items()}


def test_recognize_says_a_missing_file_is_not_found(capsys):
    status, _, err = run(capsys, "recognize", "missing.csv")
    assert status == 2 and "missing.csv: file not found" in err and len(err.splitlines()) == 1


def test_query_offers_the_renormalise_its_advice_names(capsys, tmp_path):
    bif = tmp_path / "net.bif"
    bif.write_text(
        "network n {}\nvariable A { type discrete [ 2 ] { a0, a1 }; }\n"
        "probability ( A ) { table 0.50003, 0.5; }\n"
    )
    status, _, err = run(capsys, "query", "--model", str(bif), "--target", "A")
    assert status == 2 and "--renormalise" in err
    status, out, err = run(capsys, "query", "--model", str(bif), "--target", "A", "--renormalise")
    assert status == 0, err
    assert "1 CPT row(s) rescaled" in out and "A  a0" in out


def test_the_safe_streams_escape_what_writelines_writes_too(capsys):
    from glu.cli.terminal import safe_streams

    with safe_streams():
        sys.stdout.writelines(["tap\x1bc\n", "\u202eevil\r\n"])
        sys.stderr.writelines(["50 %\r", "\x07done\n"])
    out, err = capsys.readouterr()
    assert out == "tap\\x1bc\n\\u202eevil\\x0d\n" and err == "50 %\r\\x07done\n"


RENORMALISE = "--renormalise applies to BIF, XMLBIF and UAI files"


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["gestures", "segment", "x.log", "--plot", "-"], "an image is not written to standard output"),
        (["query", "--model", "m.json", "--renormalise", "--target", "A"], RENORMALISE),
        (["query", "--model", "m.mat", "--renormalise", "--target", "A"], RENORMALISE),
        (["describe", "--sample", "3", "--max-length", "9"], "--max-length applies to the exact N-best"),
    ],
)
def test_options_that_do_not_go_together_are_refused_before_any_work(capsys, argv, message):
    status, out, err = _glu(capsys, *argv)
    assert status == 2 and out == "" and err.count("\n") == 1 and message in err


def test_describe_says_when_no_sentence_is_left(capsys):
    # "falling" comes after "is" (the ball is falling): in no sentence of the shortest length, 8 words
    argv = ["describe", "--evidence", "Action=grasp", "--must-contain", "falling", "--max-length", "8"]
    status, out, err = _glu(capsys, *argv)
    assert status == 0 and out.splitlines()[-1] == "# no sentence" and "rank" not in out
    status, out, err = _glu(capsys, *argv, "--json")
    assert status == 0 and json.loads(out) == []


def test_the_default_data_folder_is_an_input_too(capsys, tmp_path, monkeypatch, synthetic_folder):
    """With --data left out, $GLU_DATA_DIR is what the command reads: no output may land in it; a
    $GLU_DATA_DIR that is no data folder is the command's own error, not the guard's."""
    table = synthetic_folder / "gestures" / "tap1_hand" / "data.log"
    monkeypatch.setenv("GLU_DATA_DIR", str(synthetic_folder))
    status, out, err = _glu(capsys, "bn", "learn", "-o", table)
    assert (
        status == 2
        and out == ""
        and err
        == (
            f"glu bn learn: error: -o {table} is a file inside an input folder (the data folder "
            f"{synthetic_folder}); write to another path\n"
        )
    )
    monkeypatch.setenv("GLU_DATA_DIR", str(tmp_path / "none"))
    status, out, err = _glu(capsys, "bn", "learn", "-o", tmp_path / "m.json")
    assert status == 2 and out == "" and err.count("\n") == 1 and str(tmp_path / "none") in err
    assert not (tmp_path / "m.json").exists()


def test_an_input_path_the_system_cannot_resolve_is_no_input(tmp_path, monkeypatch):
    from glu.cli.guard import _real

    gone = tmp_path / "gone"
    gone.mkdir()
    monkeypatch.chdir(gone)
    gone.rmdir()  # the working folder is removed: "." is still there, its absolute path no longer
    assert _real(".") is None and _real(str(tmp_path)) == tmp_path.resolve()


def test_a_path_too_long_for_the_system_is_one_line(capsys, tmp_path):
    long = tmp_path / ("a" * 300) / "d"
    status, out, err = _glu(capsys, "data", "synth", "-o", long)
    assert status == 2 and out == "" and err == f"glu: error: {str(long)!r}: File name too long\n"
