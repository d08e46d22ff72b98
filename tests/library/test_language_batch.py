"""The batched best description equals the exact N-best's first sentence; agreement reads the sentence
right."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from glu.errors import VocabularyError
from glu.language.batch import WORD_MEANING, agreement, best_sentences
from glu.language.descriptions import default_network, nbest
from glu.language.grammar import parse_grammar
from glu.schema import AFFORDANCE_VALUES, WORDS


@pytest.fixture(scope="module")
def words():
    return default_network().words


def test_equals_nbest_on_random_probabilities(words):
    probs = np.random.default_rng(0).uniform(0.001, 0.999, size=(150, len(words)))
    best = best_sentences(probs, words)
    for i in range(len(probs)):
        ref = nbest(None, pd.Series(probs[i], index=words), n=1)
        assert best.sentence(i) == ref.sentence[0]
        assert best.score[i] == pytest.approx(ref.score[0], abs=1e-12)
        assert best.length[i] == ref.length[0]


def test_equals_nbest_with_the_networks_word_probabilities(zero_bn):
    from glu.bn import make_engine

    engine = make_engine(zero_bn)
    cases = [
        {"Action": "grasp", "ObjVel": "slow"},
        {"Shape": "sphere", "ObjVel": "fast"},
        {"Color": "yellow", "Size": "big"},
    ]
    probs = np.stack([engine.word_probability_array(e) for e in cases])
    best = best_sentences(probs, engine.binary_leaves)
    for i in range(len(cases)):
        ref = nbest(None, pd.Series(probs[i], index=engine.binary_leaves), n=1)
        assert best.score[i] == pytest.approx(ref.score[0], abs=1e-12)
        assert sorted(best.sentence(i).split()) == sorted(
            ref.sentence[0].split()
        )  # ties: any order of the same words


def test_columns_in_any_order_and_a_small_grammar():
    g = parse_grammar("$a = x | y; $b = z | w; ( $a $b [$b] )")
    cols = ["w", "z", "y", "x"]
    probs = np.array([[0.9, 0.1, 0.2, 0.3], [0.01, 0.5, 0.9, 0.1]])
    best = best_sentences(probs, cols, g)
    assert [best.sentence(0), best.sentence(1)] == ["x w w", "y z"]  # (.3·.9·.9)^(1/3) > (.3·.9)^(1/2)
    with pytest.raises(VocabularyError, match="no probability"):
        best_sentences(probs[:, :3], cols[:3], g)
    with pytest.raises(VocabularyError, match=r"\[0, 1\]"):
        best_sentences(probs * 2, cols, g)


def test_a_zero_probability_word_is_avoided(words):
    probs = np.full((1, len(words)), 0.5)
    probs[0, list(words).index("robot")] = 0.0
    assert "robot" not in best_sentences(probs, words).sentence(0)


def _best_of(sentence, words):
    """A BestSentences holding one given sentence."""
    from glu.language.batch import BestSentences

    idx = np.array([[list(words).index(w) for w in sentence.split()]])
    return BestSentences(tuple(words), idx, np.array([idx.shape[1]]), np.zeros(1))


@pytest.mark.parametrize(
    ("sentence", "truth", "expected"),
    [
        (
            "the robot taps the big yellow ball and the ball rolls",
            {"Action": "tap", "Shape": "sphere", "Size": "big", "Color": "yellow", "ObjVel": "fast"},
            {"verb": True, "object": True, "effect": True, "all": True},
        ),
        (
            "he is pushing the box but the box is still",
            {"Action": "tap", "Shape": "box", "Size": "small", "Color": "blue", "ObjVel": "medium"},
            {"verb": True, "object": True, "effect": False, "all": False},
        ),
        (
            "baltazar grasped the small green cube and the cube rises",
            {"Action": "touch", "Shape": "box", "Size": "big", "Color": "green2", "ObjVel": "medium"},
            {"verb": False, "object": False, "effect": True, "all": False},
        ),
        (
            "the robot pokes the green sphere and the sphere is inert",
            {"Action": "touch", "Shape": "sphere", "Size": "medium", "Color": "green1", "ObjVel": "slow"},
            {"verb": True, "object": True, "effect": True, "all": True},
        ),
    ],
)
def test_agreement(words, sentence, truth, expected):
    codes = {k: np.array([AFFORDANCE_VALUES[k].index(v)]) for k, v in truth.items()}
    got = agreement(_best_of(sentence, words), codes, AFFORDANCE_VALUES)
    assert {k: bool(v[0]) for k, v in got.items()} == expected


def test_every_meaningful_word_is_a_vocabulary_word():
    assert set(WORD_MEANING) <= set(WORDS)
    for node, values in WORD_MEANING.values():
        assert set(values) <= set(AFFORDANCE_VALUES[node])


def test_word_probabilities_of_the_wrong_shape():
    with pytest.raises(
        VocabularyError, match=r"word probabilities must have shape \(n_rows, 3\), got \(4,\)"
    ):
        best_sentences(np.full(4, 0.5), ["a", "b", "c"], parse_grammar("( a b )"))
