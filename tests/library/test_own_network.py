"""A lab's own network: a made-up tool-use dataset with other nodes and words runs learn → query → fuse →
describe.

The generator below is the reference: a robot pulls or pushes a ball or a cube with a stick, a hook or a
rake; the hook and the rake bring objects closer, the stick pushes them away, balls move farther than
cubes; a person says what happened. The learned network must recover what the generator does.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from glu.bn import learn_bn, make_engine
from glu.cli import main
from glu.data.tables import read_experiment_table
from glu.errors import DataError
from glu.language import describe, load_grammar
from glu.schema import GLU_SCHEMA_FILE, default_schema, read_schema_file, schema_from_dict, schema_to_dict

SCHEMA_YAML = """\
format: glu-schema
version: 1
name: tool use (made up for the tests)
nodes:
  - {name: Tool, values: [stick, hook, rake], role: action, set_by_experimenter: true}
  - {name: ObjShape, values: [ball, cube], role: object, set_by_experimenter: true}
  - {name: Direction, values: [closer, away, still], role: effect}
  - {name: Distance, values: [none, short, far], role: effect}
words: [the, robot, pulls, pushes, ball, cube, with, stick, hook, rake, and, but, it, comes, closer,
        goes, away, stays, put, far]
"""

GRAMMAR = """\
$tool = stick | hook | rake;
$object = ball | cube;
$verb = pulls | pushes;
$effect = and it comes closer | and it goes far away | and it goes away | but it stays put;
( the robot $verb the $object with the $tool $effect )
"""

TOOLS, SHAPES = ("stick", "hook", "rake"), ("ball", "cube")


def tool_use_table(n: int = 600, seed: int = 0) -> list[dict[str, str]]:
    """The made-up experiments: Tool and ObjShape set, Direction and Distance by simple rules, a
    description."""
    rng = np.random.default_rng(seed)
    rows = []
    for _ in range(n):
        tool, shape = TOOLS[rng.integers(3)], SHAPES[rng.integers(2)]
        moves = rng.random() < (0.9 if tool != "stick" else 0.8)
        direction = "still" if not moves else ("closer" if tool != "stick" else "away")
        far = moves and shape == "ball" and rng.random() < 0.7
        distance = "none" if not moves else ("far" if far else "short")
        verb = "pushes" if tool == "stick" else "pulls"
        effect = {
            "closer": "and it comes closer",
            "away": "and it goes far away" if far else "and it goes away",
            "still": "but it stays put",
        }[direction]
        said = f"The robot {verb} the {shape} with the {tool}, {effect}."
        rows.append(
            {
                "Tool": tool,
                "ObjShape": shape,
                "Direction": direction,
                "Distance": distance,
                "description": said,
            }
        )
    return rows


@pytest.fixture(scope="module")
def tool_use(tmp_path_factory):
    d = tmp_path_factory.mktemp("tool-use")
    (d / "schema.yaml").write_text(SCHEMA_YAML)
    (d / "grammar.grm").write_text(GRAMMAR)
    rows = tool_use_table()
    cols = list(rows[0])
    lines = [",".join(cols)] + [
        ",".join(f'"{r[c]}"' if c == "description" else r[c] for c in cols) for r in rows
    ]
    (d / "experiments.csv").write_text("\n".join(lines) + "\n")
    return d


def test_the_glu_schema_is_one_such_file():
    s = read_schema_file(GLU_SCHEMA_FILE)
    assert s == default_schema()
    assert s.root_nodes == ("Action", "Color", "Shape", "Size")
    assert schema_from_dict(schema_to_dict(s)) == s


def test_learn_query_fuse_describe_on_the_tool_use_network(tool_use):
    schema = read_schema_file(tool_use / "schema.yaml")
    df = read_experiment_table(tool_use / "experiments.csv", schema)
    assert df.shape == (600, 4 + 20)
    assert df["pulls"].eq("present").sum() == df["Tool"].isin(["hook", "rake"]).sum()
    bn = learn_bn(df, schema)
    assert bn.parents["Tool"] == () and bn.parents["ObjShape"] == ()  # set by the experimenter
    assert "Tool" in bn.parents["Direction"] and "ObjShape" in bn.parents["Distance"]
    eng = make_engine(bn)
    # query: the generator's physics, recovered
    p = eng.query(["Direction"], {"Tool": "hook"})["Direction"]
    assert bn.schema.values_of("Direction")[int(np.argmax(p))] == "closer" and p[0] > 0.8
    far_ball = eng.query(["Distance"], {"Tool": "rake", "ObjShape": "ball"})["Distance"][2]
    far_cube = eng.query(["Distance"], {"Tool": "rake", "ObjShape": "cube"})["Distance"][2]
    assert far_ball > 0.5 > far_cube
    # fuse: a gesture posterior over the tools as soft evidence moves the effect towards "away"
    p_stick = eng.query(["Direction"], soft={"Tool": {"stick": 0.8, "hook": 0.1, "rake": 0.1}})["Direction"]
    assert p_stick[1] > p[1]
    # describe, with the lab's own grammar
    best = describe(
        eng,
        {"Tool": "stick", "ObjShape": "ball", "Direction": "away"},
        n=3,
        grammar=load_grammar(tool_use / "grammar.grm"),
    )
    assert best["sentence"].iloc[0].startswith("the robot pushes the ball with the stick and it goes")


def test_the_command_line_runs_the_chain(tool_use, tmp_path, capsys):
    own = ["--schema", str(tool_use / "schema.yaml"), "--experiments", str(tool_use / "experiments.csv")]
    model = tmp_path / "tool-use.json"
    assert main(["bn", "learn", *own, "-o", str(model)]) == 0
    capsys.readouterr()
    assert (
        main(["query", "--model", str(model), "--target", "Direction", "--evidence", "Tool=rake", "--json"])
        == 0
    )
    answer = json.loads(capsys.readouterr().out)
    assert max(answer["Direction"], key=answer["Direction"].get) == "closer"
    assert (
        main(
            [
                "query",
                "--model",
                str(model),
                "--target",
                "Direction",
                "--soft",
                "Tool=stick:0.9,hook:0.05,rake:0.05",
                "--json",
            ]
        )
        == 0
    )
    assert max(json.loads(capsys.readouterr().out)["Direction"].items(), key=lambda kv: kv[1])[0] == "away"
    assert (
        main(
            [
                "describe",
                "--model",
                str(model),
                "--grammar",
                str(tool_use / "grammar.grm"),
                "--evidence",
                "Tool=hook",
                "ObjShape=cube",
                "--nbest",
                "2",
                "--json",
            ]
        )
        == 0
    )
    out = json.loads(capsys.readouterr().out)
    assert out[0]["sentence"].startswith("the robot pulls the cube with the hook and it comes closer")
    # GLU's grammar: its words that are not nodes of this network score p = 1, and are named
    assert main(["describe", "--model", str(model), "--evidence", "Tool=hook"]) == 0
    out = capsys.readouterr().out
    assert "# words that are not network nodes score as p = 1 (function words): " in out and "grasping" in out
    assert (
        main(["bn", "export", str(model), "-o", str(tmp_path / "tool-use.bifxml"), "--zero-rows", "seen"])
        == 0
    )


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda s: s.replace("role: effect}", "role: outcome}"), "role 'outcome'"),
        (lambda s: s.replace("[none, short, far]", "[none, none, far]"), "lists a value twice"),
        (lambda s: s.replace("words: [the,", "words: [Tool, the,"), "differ from node names"),
        (lambda s: s.replace("format: glu-schema", "format: other"), "not a glu schema"),
        (lambda s: s + "  :\n", "not YAML"),
    ],
)
def test_malformed_schema_files_are_one_line(tmp_path, edit, message):
    p = tmp_path / "s.yaml"
    p.write_text(edit(SCHEMA_YAML))
    with pytest.raises(DataError, match=message) as e:
        read_schema_file(p)
    assert "\n" not in str(e.value)


def test_malformed_experiment_tables_name_the_line(tool_use, tmp_path):
    schema = read_schema_file(tool_use / "schema.yaml")
    bad = tmp_path / "bad.csv"
    bad.write_text(
        "Tool,ObjShape,Direction,Distance,description\nstick,ball,away,far,x\nspoon,ball,away,far,x\n"
    )
    with pytest.raises(DataError, match=r"bad.csv:3: column Tool: value 'spoon' is not allowed"):
        read_experiment_table(bad, schema)
    bad.write_text("Tool,ObjShape,Direction\nstick,ball,away\n")
    with pytest.raises(DataError, match="no column for the node"):
        read_experiment_table(bad, schema)


def _schema_doc(edit) -> dict:
    import yaml

    d = yaml.safe_load(SCHEMA_YAML)
    edit(d)
    return d


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d.update(version=2), "version 2; this glu reads version 1"),
        (lambda d: d.update(nodes=[]), "'nodes' must be a non-empty list of {name, values, role}"),
        (lambda d: d.update(words=["the", " robot"]), r"'words' must be a list of words \(non-empty"),
        (lambda d: d["nodes"][0].pop("name"), "node 1 needs a 'name'"),
        (lambda d: d["nodes"][0].update(values=["stick"]), "node 'Tool' needs a list of at least two"),
        (lambda d: d["nodes"].append(d["nodes"][0]), "node 'Tool' is defined twice"),
        (lambda d: d["nodes"][0].update(colour="red"), r"node 'Tool': unknown key\(s\) \['colour'\]"),
        (lambda d: d.update(aliases=["stik"]), "'aliases' maps node names to {alias: value}"),
        (lambda d: d.update(aliases={"Tool": {"stik": "spoon"}}), "alias 'stik' of 'Tool' names an unknown"),
    ],
    ids=[
        "version",
        "no-nodes",
        "spaced-word",
        "no-name",
        "one-value",
        "twice",
        "unknown-key",
        "aliases",
        "alias",
    ],
)
def test_malformed_schema_documents_name_the_file_and_the_node(edit, message):
    with pytest.raises(DataError, match="^s.yaml: " + message) as e:
        schema_from_dict(_schema_doc(edit), "s.yaml")
    assert "\n" not in str(e.value)


def test_a_json_schema_file_that_is_not_json_is_one_line(tmp_path):
    p = tmp_path / "s.json"
    p.write_text('{"format": "glu-schema",')
    with pytest.raises(DataError, match=r"s.json: not JSON \(Expecting property name"):
        read_schema_file(p)


def test_schemas_without_roots_or_roles_take_glus_and_name_unknown_nodes():
    """No roots given: GLU's nodes set by the experimenter (Action, Color, Shape, Size) where present; no
    role given: the node called Action is the action; several action roles: the user must choose."""
    from glu.errors import UnknownNodeError
    from glu.schema import Schema, action_node

    s = Schema(values={"Shape": ("a", "b"), "Effect": ("c", "d"), "Action": ("e", "f")}, n_affordance=3)
    assert s.root_nodes == ("Action", "Shape") and action_node(s) == "Action"
    with pytest.raises(UnknownNodeError, match=r"unknown node 'Shap' \(did you mean Shape\?\); nodes are: "):
        s.values_of("Shap")
    two = Schema(values=s.values, n_affordance=3, roles={"Shape": "action", "Action": "action"})
    with pytest.raises(DataError, match=r"several nodes the role action \(Shape, Action\).*action=NODE"):
        action_node(two)
