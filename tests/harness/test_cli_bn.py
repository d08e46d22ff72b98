"""The command line of the BN: learn, edges, import, query (single, JSON, batch) and its error handling."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
import scipy.io as sio
from cli_run import run
from test_model_io import write_bnt_mat

from glu.bn import make_engine

SPHERE = ["--target", "ObjVel", "--evidence", "Action=tap", "Shape=sphere", "Size=small"]


def test_query_json_prints_exactly_the_posterior(source, zero_bn, capsys):
    status, out, err = run(capsys, "query", "--data", str(source.root), *SPHERE, "--json")
    assert status == 0
    answer = json.loads(out)
    assert list(answer) == ["ObjVel"] and list(answer["ObjVel"]) == ["slow", "medium", "fast"]
    ref = make_engine(zero_bn).query(["ObjVel"], {"Action": "tap", "Shape": "sphere", "Size": "small"})
    assert list(answer["ObjVel"].values()) == ref["ObjVel"].tolist()  # JSON floats are exact
    assert f"{source.kind} data" in err  # the source is named, on stderr so stdout stays JSON


def test_query_text_output_names_the_source_and_each_value(source, capsys):
    status, out, _ = run(
        capsys,
        "query",
        "--data",
        str(source.root),
        "--target",
        "ObjVel",
        "Action",
        "--evidence",
        "Shape=box",
        "Size=big",
        "--soft",
        "Action=grasp:0.2,tap:0.6,touch:0.2",
    )
    assert status == 0
    lines = out.splitlines()
    assert lines[0].startswith(f"# learned from {source.kind} data")
    assert lines[1].startswith(
        "# evidence: Shape=box, Size=big, Action~(grasp:0.2, tap:0.6, touch:0.2, virtual)"
    )
    rows = [ln.split() for ln in lines[2:]]
    assert [(r[0], r[1]) for r in rows] == [
        ("ObjVel", "slow"),
        ("ObjVel", "medium"),
        ("ObjVel", "fast"),
        ("Action", "grasp"),
        ("Action", "tap"),
        ("Action", "touch"),
    ]
    assert sum(float(r[2]) for r in rows[:3]) == pytest.approx(1, abs=1e-5)


def test_learn_edges_and_import(source, zero_bn, tmp_path, capsys):
    model = tmp_path / "lab.json"
    assert run(capsys, "bn", "learn", "--data", str(source.root), "-o", str(model))[0] == 0
    status, out, _ = run(capsys, "bn", "edges", str(model))
    assert status == 0
    mat = tmp_path / "BN.mat"  # the learned network as the originals' MATLAB code saves one
    write_bnt_mat(zero_bn, mat)
    raw = sio.loadmat(mat, squeeze_me=True, struct_as_record=False)["netobj_lab"]
    names = [str(n) for n in raw.nodeNames]
    expected = sorted(f"{names[i]} -> {names[j]}" for i, j in zip(*np.nonzero(raw.dag), strict=True))
    assert out.splitlines() == expected and len(expected) == len(zero_bn.edges())
    imported = tmp_path / "orig.json"
    mat = str(mat)
    assert run(capsys, "bn", "import", mat, "-o", str(imported))[0] == 0
    assert run(capsys, "bn", "edges", str(imported))[1].splitlines() == expected
    # a query against the saved model equals the query that learns from the data
    a = json.loads(run(capsys, "query", "--model", str(model), *SPHERE, "--json")[1])
    b = json.loads(run(capsys, "query", "--model", mat, *SPHERE, "--json")[1])
    np.testing.assert_allclose(list(a["ObjVel"].values()), list(b["ObjVel"].values()), atol=1e-6)


def test_unseen_words_option_changes_the_answer(source, zero_bn, uniform_bn, capsys):
    args = ["query", "--data", str(source.root), "--target", "ObjVel", "--json"]
    zero = list(json.loads(run(capsys, *args)[1])["ObjVel"].values())
    uniform = list(json.loads(run(capsys, *args, "--unseen-words", "uniform")[1])["ObjVel"].values())
    assert zero == make_engine(zero_bn).query(["ObjVel"])["ObjVel"].tolist()
    assert uniform == make_engine(uniform_bn).query(["ObjVel"])["ObjVel"].tolist()
    assert max(abs(a - b) for a, b in zip(zero, uniform, strict=True)) > 1e-9


def test_impossible_evidence_is_one_line_and_status_2(source, zero_bn, capsys):
    word = sorted(zero_bn.zero_rows())[0]
    row = np.argwhere(zero_bn.cpts[word].sum(axis=-1) == 0)[0]
    evidence = [
        f"{p}={zero_bn.schema.values_of(p)[i]}" for p, i in zip(zero_bn.parents[word], row, strict=True)
    ]
    status, _, err = run(
        capsys, "query", "--data", str(source.root), "--target", "Action", "--evidence", *evidence
    )
    assert status == 2 and err.count("\n") == 1
    assert "impossible evidence" in err and ", ".join(evidence) in err


def test_batch_answers_line_by_line_with_errors_in_place(tmp_path, capsys, zero_bn):
    zero_word = sorted(zero_bn.zero_rows())[0]  # an evidence set the all-zero rows make impossible
    parents = zero_bn.parents[zero_word]
    row = np.argwhere(zero_bn.cpts[zero_word].sum(axis=-1) == 0)[0]
    impossible = {p: zero_bn.schema.values_of(p)[i] for p, i in zip(parents, row, strict=True)}
    queries = [
        {"target": ["ObjVel"], "evidence": {"Action": "tap", "Shape": "sphere", "Size": "small"}},
        {"target": ["Action"], "evidence": impossible},
        {
            "target": ["ObjVel"],
            "evidence": {"Shape": "sphere"},
            "soft": {"Action": {"tap": 0.5, "touch": 0.5}},
        },
        "not json",
        {"target": ["Colour"]},
        {"target": "rolls", "evidence": {"Action": "tap"}},
    ]
    path = tmp_path / "q.jsonl"
    path.write_text("\n".join(q if isinstance(q, str) else json.dumps(q) for q in queries) + "\n")
    model = zero_bn.save(tmp_path / "model.json")
    status, out, err = run(capsys, "query", "--model", str(model), "--batch", str(path))
    assert status == 0
    answers = [json.loads(line) for line in out.splitlines()]
    assert len(answers) == 6
    eng = make_engine(zero_bn)
    np.testing.assert_allclose(
        list(answers[0]["ObjVel"].values()),
        eng.query(["ObjVel"], queries[0]["evidence"])["ObjVel"],
        atol=1e-12,
    )
    assert answers[1]["error"].startswith("line 2: impossible evidence")
    np.testing.assert_allclose(
        list(answers[2]["ObjVel"].values()),
        eng.query(["ObjVel"], {"Shape": "sphere"}, soft={"Action": [0, 0.5, 0.5]})["ObjVel"],
        atol=1e-12,
    )
    assert answers[3]["error"].startswith("line 4: not JSON")
    assert "unknown node 'Colour'" in answers[4]["error"]
    assert list(answers[5]) == ["rolls"]
    assert "3 of 6 queries answered with an error" in err


@pytest.mark.parametrize(
    ("soft", "message"),
    [
        ({"Action": ["a", "b", "c"]}, "must be a list of 3 numbers"),
        ({"Action": [[1], [0], [0]]}, "flat list"),
        ({"Action": {"tap": "x"}}, "must be a number"),
        ({"Action": {"tap": {"p": 1}}}, "must be a number"),
        ({"Action": {"tap": None, "grasp": 1}}, "must be a number"),
        ({"Action": [0.5, 0.5]}, "has 2 entries"),
        ({"Action": [0.5, 0.7, 0.0]}, "not a distribution"),
    ],
)
def test_a_malformed_soft_line_answers_in_place_and_later_lines_still_run(
    tmp_path, capsys, zero_bn, soft, message
):
    good = {"target": ["ObjVel"], "evidence": {"Shape": "box"}}
    lines = [json.dumps(good), json.dumps({"target": ["ObjVel"], "soft": soft}), json.dumps(good)]
    path = tmp_path / "q.jsonl"
    path.write_text("\n".join(lines) + "\n")
    status, out, err = run(
        capsys, "query", "--model", str(zero_bn.save(tmp_path / "m.json")), "--batch", str(path)
    )
    assert status == 0 and "Traceback" not in err
    answers = [json.loads(line) for line in out.splitlines()]
    assert len(answers) == 3 and answers[0] == answers[2] and "ObjVel" in answers[2]
    assert answers[1]["error"].startswith("line 2: ") and message in answers[1]["error"]


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["query", "--target", "Colour"], "unknown node 'Colour' (did you mean Color?)"),
        (["query", "--target", "ObjVel", "--evidence", "Shape"], "expected NODE=VALUE"),
        (["query", "--target", "ObjVel", "--evidence", "Shape=box", "Shape=sphere"], "Shape is given twice"),
        (
            ["query", "--target", "ObjVel", "--evidence", "Action=tap", "--soft", "Action=tap:1"],
            "Action is given twice",
        ),
        (["query", "--target", "ObjVel", "--soft", "Action=tap:0.7,grasp:0.7"], "not a distribution"),
        (["query", "--target", "ObjVel", "--soft", "Action=tap"], "expected VALUE:PROBABILITY"),
        (
            ["query", "--target", "ObjVel", "--soft", "Action=tap:1", "--soft", "Action=grasp:1"],
            "Action is given twice as soft evidence",
        ),
        (["query", "--target", "ObjVel", "--soft", "Action=tap:0.5,tap:0.5"], "on Action gives 'tap' twice"),
        (["query", "--data", "/nonexistent/folder", "--target", "ObjVel"], "no such data folder"),
        (["query", "--model", "/nonexistent/m.json", "--target", "ObjVel"], "no such model file"),
        (["query"], "no target"),
    ],
)
def test_bad_input_is_one_line_and_status_2(source, capsys, argv, message):
    if "--data" not in argv and "--model" not in argv:
        argv = [argv[0], "--data", str(source.root), *argv[1:]]
    status, out, err = run(capsys, *argv)
    assert status == 2
    assert len(err.strip().splitlines()) == 1 and message in err and "Traceback" not in err


def test_cold_start_does_not_import_pgmpy(source, tmp_path):
    """The query path stays light: no pgmpy (its import alone takes seconds)."""
    code = (
        "import sys; from glu.cli import main; "
        f"rc = main(['query', '--data', {str(source.root)!r}, '--target', 'ObjVel', '--json']); "
        "print('pgmpy' in sys.modules, 'hmmlearn' in sys.modules, 'matplotlib' in sys.modules, rc)"
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert res.stdout.strip().splitlines()[-1] == "False False False 0"


def test_console_script_error_has_no_traceback(tmp_path):
    res = subprocess.run(
        [sys.executable, "-m", "glu", "query", "--data", str(tmp_path), "--target", "ObjVel"],
        capture_output=True,
        text=True,
    )
    assert res.returncode == 2
    assert res.stderr.count("\n") == 1 and "not a glu data folder" in res.stderr


def test_a_batch_file_that_cannot_be_read_is_one_line_and_status_2(tmp_path, capsys, zero_bn):
    model = str(zero_bn.save(tmp_path / "m.json"))
    (tmp_path / "latin1.jsonl").write_bytes(b'{"target": ["Action"], "evidence": {"Shape": "b\xf6x"}}\n')
    for batch, message in (
        (tmp_path / "none.jsonl", f"{tmp_path / 'none.jsonl'}: no such batch file"),
        (tmp_path, f"{tmp_path}: cannot read the batch file ([Errno 21] Is a directory"),
        (
            tmp_path / "latin1.jsonl",
            f"{tmp_path / 'latin1.jsonl'}: cannot read the batch file ('utf-8' codec can't decode",
        ),
    ):
        status, out, err = run(capsys, "query", "--model", model, "--batch", str(batch))
        assert status == 2 and out == "" and err.count("\n") == 1
        assert err.startswith(f"glu query: error: {message}")


def test_the_words_target_of_a_model_without_word_nodes_is_refused(tmp_path, capsys):
    bif = tmp_path / "net.bif"
    bif.write_text(
        "network n {}\nvariable A { type discrete [ 2 ] { a0, a1 }; }\n"
        "probability ( A ) { table 0.5, 0.5; }\n"
    )
    status, out, err = run(capsys, "query", "--model", str(bif), "--target", "words")
    assert status == 2 and out == ""
    assert err == "glu query: error: --target words: this model has no word nodes\n"
