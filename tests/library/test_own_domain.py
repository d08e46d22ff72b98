"""A made-up domain whose action node is not called Action, with a grammar full of function words.

A person waves at, points at or pushes a cup or a ball, and says what happened; the schema calls the action
node ``Motion`` (``role: action``) and its words are only the content words — the grammar adds "the",
"person", "it", "and", "but", which are no nodes of the network. The chain learn → fuse → describe runs in
the Python API and on the command line (and with gesture HMMs trained from the command line on the lab's own
recordings). The generator below is the reference: pushing makes things fall, a ball more than a cup; waving
and pointing leave them still.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from glu.bn import BayesNet, learn_bn, make_engine
from glu.cli import main
from glu.data.tables import read_experiment_table
from glu.errors import DataError
from glu.fusion import fuse
from glu.language import describe, load_grammar, score_sentence
from glu.language.words import word_probabilities
from glu.schema import Schema, action_node, read_schema_file

SCHEMA = """\
format: glu-schema
version: 1
name: gestures at things (made up for the tests)
nodes:
  - {name: Motion, values: [wave, point, push], role: action, set_by_experimenter: true}
  - {name: Thing, values: [cup, ball], role: object, set_by_experimenter: true}
  - {name: Outcome, values: [still, falls], role: effect}
words: [waves, points, pushes, cup, ball, falls, stays, still]
"""

GRAMMAR = """\
$verb = waves at | points at | pushes;
$thing = cup | ball;
$outcome = and it falls | but it stays still;
( the person $verb the $thing $outcome )
"""
FUNCTION_WORDS = ["the", "person", "at", "and", "it", "but"]
MOTIONS, THINGS = ("wave", "point", "push"), ("cup", "ball")


def experiments(n: int = 500, seed: int = 0) -> str:
    rng = np.random.default_rng(seed)
    lines = ["Motion,Thing,Outcome,description"]
    verb = {"wave": "waves at", "point": "points at", "push": "pushes"}
    for _ in range(n):
        m, t = MOTIONS[rng.integers(3)], THINGS[rng.integers(2)]
        falls = m == "push" and rng.random() < (0.9 if t == "ball" else 0.6)
        said = f"the person {verb[m]} the {t} " + ("and it falls" if falls else "but it stays still")
        lines.append(f"{m},{t},{'falls' if falls else 'still'},{said}")
    return "\n".join(lines) + "\n"


@pytest.fixture(scope="module")
def domain(tmp_path_factory):
    d = tmp_path_factory.mktemp("own-domain")
    (d / "schema.yaml").write_text(SCHEMA)
    (d / "grammar.grm").write_text(GRAMMAR)
    (d / "experiments.csv").write_text(experiments())
    return d


def test_fusion_uses_the_schemas_action_node(domain, tmp_path):
    schema = read_schema_file(domain / "schema.yaml")
    bn = learn_bn(read_experiment_table(domain / "experiments.csv", schema), schema)
    assert action_node(bn.schema) == "Motion"
    path = tmp_path / "model.json"
    bn.save(path)
    back = BayesNet.load(path)  # the role survives the model file
    assert action_node(back.schema) == "Motion" and back.schema.root_nodes == ("Motion", "Thing")
    eng = make_engine(back)
    q = np.array([0.1, 0.1, 0.8])  # the gesture HMMs think: push
    fused = fuse(eng, ["Outcome"], {"Thing": "ball"}, q, "virtual")["Outcome"]
    # virtual evidence by hand: Σ_m p(Outcome, m | ball) q(m), normalised
    p_m = eng.query(["Motion"], {"Thing": "ball"})["Motion"]
    by_hand = sum(
        eng.query(["Outcome"], {"Thing": "ball", "Motion": m})["Outcome"] * p_m[i] * q[i]
        for i, m in enumerate(MOTIONS)
    )
    np.testing.assert_allclose(fused, by_hand / by_hand.sum(), atol=1e-12)
    assert fused[1] > 0.6  # a push at a ball: it falls
    product = eng.query(["Motion"], {"Outcome": "falls"})["Motion"] * q  # the product rule by hand
    np.testing.assert_allclose(
        fuse(eng, ["Motion"], {"Outcome": "falls"}, q, "product")["Motion"], product / product.sum()
    )
    with pytest.raises(ValueError, match=r"Motion is observed directly \(Motion=push\)"):
        fuse(eng, ["Outcome"], {"Motion": "push"}, q, "virtual")


def test_a_network_without_an_action_node_says_so():
    schema = Schema(values={"A": ("a", "b"), "B": ("c", "d")}, n_affordance=2)
    bn = BayesNet(
        schema=schema,
        parents={"A": (), "B": ("A",)},
        cpts={"A": np.array([0.5, 0.5]), "B": np.array([[0.9, 0.1], [0.2, 0.8]])},
    )
    with pytest.raises(DataError, match="the network has no action node: give one node `role: action`"):
        fuse(make_engine(bn), ["B"], {}, [0.5, 0.5])
    np.testing.assert_allclose(fuse(make_engine(bn), ["B"], {}, [0.0, 1.0], action="A")["B"], [0.2, 0.8])


def test_describe_with_function_words_that_are_no_nodes(domain):
    schema = read_schema_file(domain / "schema.yaml")
    eng = make_engine(learn_bn(read_experiment_table(domain / "experiments.csv", schema), schema))
    grammar = load_grammar(domain / "grammar.grm")
    best = describe(eng, {"Motion": "push", "Thing": "ball"}, n=2, grammar=grammar)
    assert best["sentence"].iloc[0] == "the person pushes the ball and it falls"
    assert sorted(best.attrs["not_in_network"]) == sorted(FUNCTION_WORDS)
    # the score: function words contribute log 1 = 0 and count in the length
    probs = word_probabilities(eng, {"Motion": "push", "Thing": "ball"}, vocabulary=grammar)
    assert (probs[FUNCTION_WORDS] == 1.0).all()
    content = ["pushes", "ball", "falls"]
    by_hand = sum(np.log(probs[w]) for w in content) / 8  # eight words, five of them function words
    assert best["score"].iloc[0] == pytest.approx(by_hand, abs=1e-12)
    assert score_sentence(best["sentence"].iloc[0], probs) == pytest.approx(by_hand, abs=1e-12)


def test_the_command_line_runs_learn_query_fuse_describe(domain, tmp_path, capsys):
    own = ["--schema", str(domain / "schema.yaml"), "--experiments", str(domain / "experiments.csv")]
    model = tmp_path / "model.json"
    assert main(["bn", "learn", *own, "-o", str(model)]) == 0
    capsys.readouterr()
    assert main(["bn", "nodes", str(model), "--json"]) == 0
    nodes = {r["name"]: r for r in json.loads(capsys.readouterr().out)}
    assert nodes["Motion"]["kind"] == "action" and nodes["falls"]["kind"] == "word"
    assert nodes["Motion"]["values"] == list(MOTIONS)
    soft = ["--soft", "Motion=wave:0.05,point:0.05,push:0.9"]
    assert main(["query", "--model", str(model), "--target", "Outcome", "words", *soft, "--json"]) == 0
    answer = json.loads(capsys.readouterr().out)
    assert set(answer["words"]) == {"waves", "points", "pushes", "cup", "ball", "falls", "stays", "still"}
    assert answer["words"]["pushes"] > 0.8 and answer["Outcome"]["falls"] > 0.5
    grammar = ["--grammar", str(domain / "grammar.grm")]
    assert (
        main(["describe", "--model", str(model), *grammar, "--evidence", "Thing=cup", *soft, "--nbest", "1"])
        == 0
    )
    out = capsys.readouterr().out
    assert "the person pushes the cup" in out
    assert (
        "# words that are not network nodes score as p = 1 (function words): and, at, but, it, person, the"
        in out
    )


def _write_recordings(root, corpus, label_of):
    """The corpus as one folder per label of t,x,y,z tables in metres (the lab's own recordings)."""
    from glu.gestures.features import HORIZONTAL_FALLBACK, VERTICAL_FALLBACK

    metres = np.array([HORIZONTAL_FALLBACK, VERTICAL_FALLBACK, HORIZONTAL_FALLBACK])
    paths = []
    for i, s in enumerate(corpus):
        folder = root / label_of[s.action]
        folder.mkdir(parents=True, exist_ok=True)
        table = np.column_stack([np.arange(len(s.xyz)) / 30.0, s.xyz * metres])
        path = folder / f"rep{i:02d}.csv"
        np.savetxt(path, table, delimiter=",", header="t,x,y,z", comments="")
        paths.append(path)
    return paths


def test_the_whole_chain_with_the_labs_own_recordings(domain, tmp_path, capsys):
    """learn → train on own recordings → recognise → fuse → describe, every step a glu command."""
    from glu.gestures.corpus import synthetic_corpus

    label_of = {"grasp": "wave", "touch": "point", "push": "push"}  # the lab's movements, drawn synthetic
    _write_recordings(tmp_path / "recordings", synthetic_corpus(6, 1, actions=tuple(label_of)), label_of)
    held = [s for s in synthetic_corpus(3, 90, actions=tuple(label_of)) if s.action == "push"]
    (probe,) = _write_recordings(tmp_path / "probe", held[:1], label_of)

    own = ["--schema", str(domain / "schema.yaml"), "--experiments", str(domain / "experiments.csv")]
    model, rec = tmp_path / "model.json", tmp_path / "recogniser.json"
    assert main(["bn", "learn", *own, "-o", str(model)]) == 0
    hmm = ["--states", "4", "--mix", "1", "--iter", "30", "--features", "centred"]
    assert main(["hmm", "train", "--recordings", str(tmp_path / "recordings"), "-o", str(rec), *hmm]) == 0
    assert "push: 6 sequences" in capsys.readouterr().out
    assert main(["recognize", str(probe), "--models", str(rec), "--json"]) == 0
    posterior = json.loads(capsys.readouterr().out)["posterior"]
    assert set(posterior) == set(MOTIONS) and max(posterior, key=posterior.get) == "push"
    soft = ["--soft", "Motion=" + ",".join(f"{m}:{posterior[m]!r}" for m in MOTIONS)]
    query = ["query", "--model", str(model), "--target", "Outcome", *soft, "--evidence", "Thing=ball"]
    assert main([*query, "--json"]) == 0
    fused = json.loads(capsys.readouterr().out)["Outcome"]
    # the reference: the same virtual evidence by hand in the Python API
    eng = make_engine(BayesNet.load(model))
    by_hand = fuse(eng, ["Outcome"], {"Thing": "ball"}, [posterior[m] for m in MOTIONS], "virtual")["Outcome"]
    assert [fused["still"], fused["falls"]] == pytest.approx(by_hand.tolist(), abs=1e-9)
    assert fused["falls"] > 0.5  # a push at a ball: it falls
    grammar = ["--grammar", str(domain / "grammar.grm")]
    describe_ball = ["describe", "--model", str(model), *grammar, "--evidence", "Thing=ball", *soft]
    assert main([*describe_ball, "--nbest", "1"]) == 0
    assert "the person pushes the ball and it falls" in capsys.readouterr().out
