"""Sentence scores and the exact N-best: against brute force over every sentence, on tiny and full
grammars."""

from __future__ import annotations

import heapq
import itertools
import json
import math
import time

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from language_reference import brute_force_nbest, exact_key, exact_logs, expand, grammar_text, plain_score

from glu.cli import main
from glu.errors import EvidenceError, GluError, VocabularyError
from glu.language import (
    all_scores,
    compile_network,
    default_network,
    enumerate_sentences,
    load_grammar,
    nbest,
    parse_grammar,
    rank_sentences,
    sample_nbest,
    score_sentence,
    score_sentences,
    word_probabilities,
)
from glu.schema import WORDS


def _random_probs(seed: int, words=WORDS) -> dict[str, float]:
    rng = np.random.default_rng(seed)
    return dict(zip(words, rng.uniform(0.01, 1.0, len(words)).tolist(), strict=True))


# ---------------------------------------------------------------- scores
def test_score_is_the_mean_log_probability_counting_repeated_words():
    p = {"the": 0.9, "robot": 0.5, "taps": 0.2, "ball": 0.4}
    by_hand = (2 * math.log(0.9) + math.log(0.5) + math.log(0.2) + math.log(0.4)) / 5
    assert score_sentence("the robot taps the ball", p) == pytest.approx(by_hand, abs=1e-15)
    assert score_sentence(["the", "ball"], p) == pytest.approx((math.log(0.9) + math.log(0.4)) / 2, abs=1e-15)
    assert score_sentence("the taps", {"the": 1.0, "taps": 0.0}) == -math.inf
    got = score_sentences(["the ball", "robot"], pd.Series(p))
    assert got.shape == (2,) and got[1] == pytest.approx(math.log(0.5))


def test_the_original_score_starts_the_sum_at_one():
    p = {"the": 0.9, "robot": 0.5, "taps": 0.2, "ball": 0.4}
    sentence = "the robot taps the ball"
    by_hand = (1 + 2 * math.log(0.9) + math.log(0.5) + math.log(0.2) + math.log(0.4)) / 5
    assert score_sentence(sentence, p, score="original") == pytest.approx(by_hand, abs=1e-15)
    assert score_sentence(sentence, p, "original") - score_sentence(sentence, p) == pytest.approx(1 / 5)
    assert score_sentence("the taps", {"the": 1.0, "taps": 0.0}, "original") == -math.inf
    # the +1/L favours short sentences: here it reverses the order of a short and a long sentence
    q = {"x": 0.3, "y": 0.6}
    assert score_sentence("x y y y", q) > score_sentence("x", q)
    assert score_sentence("x y y y", q, "original") < score_sentence("x", q, "original")
    with pytest.raises(EvidenceError, match="paper, original"):
        score_sentence(sentence, p, score="mean")


def test_scores_are_exact_so_reordered_words_tie():
    p = _random_probs(0)
    a = score_sentence("the robot taps the big ball and the ball rolls", p)
    b = score_sentence("the robot taps the ball and the big ball rolls", p)
    assert a == b  # exactly, though a plain float sum depends on the order


def test_bad_word_probabilities():
    with pytest.raises(VocabularyError, match="zzz"):
        score_sentence("the zzz", {"the": 0.5})
    with pytest.raises(VocabularyError, match="empty"):
        score_sentence("", {"the": 0.5})
    with pytest.raises(EvidenceError, match="outside"):
        score_sentence("the", {"the": 1.5})
    with pytest.raises(EvidenceError, match="outside"):
        score_sentence("the", {"the": float("nan")})
    with pytest.raises(EvidenceError, match="not a number"):
        score_sentence("the", {"the": "high"})
    with pytest.raises(VocabularyError, match="twice"):
        score_sentence("the", pd.Series([0.5, 0.6], index=["the", "the"]))
    assert score_sentence("the", {"the": 1 + 1e-12}) == 0.0  # rounding noise is clipped


def test_grammar_words_missing_from_the_model_are_an_error():
    probs = _random_probs(1)
    del probs["square"]
    with pytest.raises(VocabularyError, match="square"):
        nbest(None, probs)
    with pytest.raises(VocabularyError, match="purple"):
        nbest(None, _random_probs(1), must_contain=["purple"])
    with pytest.raises(GluError):
        nbest(None, _random_probs(1), n=0)


def test_word_probabilities_of_another_type_and_empty_candidates():
    with pytest.raises(TypeError, match="a mapping word → p or a pandas Series, not list"):
        score_sentence("the", [0.5])
    for empty in ("", "  ", ()):
        with pytest.raises(VocabularyError, match="an empty sentence has no score"):
            rank_sentences([empty, "the"], {"the": 0.5})


def test_sentence_files_and_sets(tmp_path):
    from glu.errors import DataError
    from glu.language import SentenceSet, read_sentences

    blank = tmp_path / "blank.txt"
    blank.write_text("\n  \n\t\n")
    with pytest.raises(DataError, match=f"{blank}: no sentence in the file"):
        read_sentences(blank)
    assert (
        repr(SentenceSet(["the robot taps", "the ball", "the ball"])) == "SentenceSet(2 sentences, 4 words)"
    )


def test_sampling_walks_a_grammar_and_all_scores_has_a_limit():
    from glu.errors import GrammarError

    probs = _random_probs(2)
    with pytest.raises(TypeError, match="pass a Grammar, not a WordNetwork"):
        sample_nbest(default_network(), probs, n_samples=5)
    ten = "(" + " | ".join(WORDS[:10]) + ")"
    huge = compile_network(parse_grammar("( " + " ".join([ten] * 8) + " )"))  # 10⁸ sentences
    with pytest.raises(
        GrammarError, match="the grammar has 100000000 sentences; all_scores handles up to 50000000"
    ):
        all_scores(huge, probs)


# ---------------------------------------------------------------- exact N-best == brute force
def test_ties_are_broken_by_the_words():
    g = parse_grammar("( (a | b) (a | b) )")
    got = nbest(g, {"a": 0.5, "b": 0.5}, n=4)
    assert list(got["sentence"]) == ["a a", "a b", "b a", "b b"]
    assert list(got["rank"]) == [1, 2, 3, 4] and np.all(got["score"] == math.log(0.5))
    assert list(nbest(g, {"a": 0.5, "b": 0.5}, n=2)["sentence"]) == ["a a", "a b"]


def test_longer_sentences_can_win_the_mean():
    g = parse_grammar("( x [y y y] )")
    got = nbest(g, {"x": 0.1, "y": 0.9}, n=2)
    assert list(got["sentence"]) == ["x y y y", "x"]
    assert list(got["length"]) == [4, 1]


def test_zero_probability_sentences_come_last_fewest_impossible_words_first():
    g = parse_grammar("( (a | z) (b | z) )")
    got = nbest(g, {"a": 0.5, "b": 0.25, "z": 0.0}, n=4)
    assert list(got["sentence"]) == ["a b", "a z", "z b", "z z"]
    assert np.isinf(got["score"].iloc[1:]).all()


PROB_VALUES = [0.0, 0.05, 0.25, 0.5, 0.5, 0.8, 1.0]
START = {"paper": 0, "original": 1}
"""Where each score's sum starts (docs/method.md §6.2), written here independently of glu."""


def _tree_strategy():
    leaves = st.sampled_from("abcd").map(lambda w: ("w", w))

    def extend(children):
        return st.one_of(
            st.lists(children, min_size=2, max_size=3).map(lambda xs: ("seq", xs)),
            st.lists(children, min_size=2, max_size=4).map(lambda xs: ("alt", xs)),
            children.map(lambda x: ("opt", x)),
            children.map(lambda x: ("star", x)),
        )

    return st.recursive(leaves, extend, max_leaves=9)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    tree=_tree_strategy(),
    sub=_tree_strategy(),
    probs=st.fixed_dictionaries({w: st.sampled_from(PROB_VALUES) for w in "abcd"}),
    n=st.integers(1, 8),
    max_length=st.integers(1, 6),
    score=st.sampled_from(["paper", "original"]),
)
def test_nbest_equals_brute_force_on_small_grammars(tree, sub, probs, n, max_length, score):
    sentence = ("seq", [tree, ("opt", ("ref", "v")), ("ref", "v")])
    defs = {"v": sub}
    g = parse_grammar(grammar_text(sentence, defs))
    expected = brute_force_nbest(expand(sentence, defs, max_length), probs, n, START[score])
    got = nbest(g, probs, n, max_length=max_length, score=score)
    assert [tuple(s.split()) for s in got["sentence"]] == [s for s, _ in expected]
    np.testing.assert_allclose(got["score"].to_numpy(), [sc for _, sc in expected], rtol=1e-12, atol=1e-12)


@settings(max_examples=60, deadline=None)
@given(probs=st.fixed_dictionaries({w: st.sampled_from(PROB_VALUES) for w in "abc"}), n=st.integers(1, 6))
def test_nbest_with_must_contain_equals_brute_force(probs, n):
    sentence = (
        "seq",
        [("alt", [("w", "a"), ("w", "b")]), ("opt", ("w", "c")), ("alt", [("w", "a"), ("w", "c")])],
    )
    g = parse_grammar(grammar_text(sentence))
    every = [s for s in expand(sentence) if "c" in s]
    got = nbest(g, probs, n, must_contain=["c"])
    assert [tuple(s.split()) for s in got["sentence"]] == [s for s, _ in brute_force_nbest(every, probs, n)]


def test_nbest_on_a_grammar_small_enough_to_score_every_sentence():
    # the default grammar without sizes and colours: 3·36·5·2·5·12 = 32,400 sentences, scored one by one
    g = parse_grammar(
        load_grammar().format().replace("$thing = the [$size] [$colour] $noun;", "$thing = the $noun;")
    )
    sentences = list(enumerate_sentences(g))
    assert len(sentences) == 3 * 36 * 5 * 2 * 5 * 12
    for seed in range(3):
        probs = _random_probs(seed)
        probs.update({"the": 1.0, "is": 0.5, "taps": 0.0})  # exact zeros, ones and ties
        got = nbest(g, probs, 10)
        expected = brute_force_nbest(sentences, probs, 10)
        assert [tuple(s.split()) for s in got["sentence"]] == [s for s, _ in expected]
        np.testing.assert_allclose(got["score"], [sc for _, sc in expected], rtol=1e-12)


def test_nbest_on_the_full_grammar_matches_vectorised_scores_of_all_sentences():
    net = default_network()
    for seed in (0, 1):
        probs = _random_probs(seed)
        scores = all_scores(net, probs)
        assert scores.shape == (9_331_200,)
        top = np.sort(scores)[::-1][:10]
        got = nbest(net, probs, 10)
        np.testing.assert_allclose(got["score"], top, rtol=1e-12)
        for s, sc in zip(got["sentence"], got["score"], strict=True):  # and the sentences carry those scores
            assert plain_score(tuple(s.split()), probs) == pytest.approx(sc, rel=1e-12)


def test_nbest_under_the_original_score_on_the_full_grammar():
    net = default_network()
    probs = _random_probs(2)
    scores = all_scores(net, probs, score="original")
    np.testing.assert_allclose(scores, all_scores(net, probs) + 1 / _lengths(net), rtol=0, atol=1e-12)
    got = nbest(net, probs, 10, score="original")
    np.testing.assert_allclose(got["score"], np.sort(scores)[::-1][:10], rtol=1e-12)
    for s, sc in zip(got["sentence"], got["score"], strict=True):
        assert plain_score(tuple(s.split()), probs, start=1) == pytest.approx(sc, rel=1e-12)
    paper = nbest(net, probs, 10)
    assert set(got["length"]).isdisjoint(set()) and got["length"].mean() <= paper["length"].mean()


def _lengths(net) -> np.ndarray:
    """The length of every sentence of the network, in the order of :func:`all_scores` (by a ones vector)."""
    ones = {w: math.exp(-1.0) for w in net.words}  # log p = -1 for every word: the paper score is -1 exactly
    return 1 / (all_scores(net, ones, score="original") + 1)


def test_rank_sentences_under_both_scores_with_a_word_filter():
    probs = {"a": 0.5, "b": 0.25, "c": 0.9}
    sents = ["a", "b c c", "c c c c b", "a c"]
    paper = rank_sentences(sents, probs)
    original = rank_sentences(sents, probs, score="original")
    for frame, start in ((paper, 0), (original, 1)):
        expected = brute_force_nbest([tuple(s.split()) for s in sents], probs, 4, start)
        assert [tuple(s.split()) for s in frame["sentence"]] == [s for s, _ in expected]
        np.testing.assert_allclose(frame["score"], [sc for _, sc in expected], rtol=1e-12)
    assert list(paper["sentence"]) != list(original["sentence"])
    only_b = rank_sentences(sents, probs, score="original", must_contain=["b"])
    assert set(only_b["sentence"]) == {"b c c", "c c c c b"}


_WORDS = ("a", "b", "c", "d", "e")
# probabilities with exact ties (equal values, and 0.5·0.5 = 0.25), zeros and ones, and arbitrary ones whose
# sums of logs differ from each other by a few units in the last place
_PROB = st.one_of(st.sampled_from([0.0, 1.0, 0.5, 0.25, 0.1, 0.3]), st.floats(1e-300, 1.0))


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    sents=st.lists(
        st.lists(st.sampled_from(_WORDS), min_size=1, max_size=7).map(tuple), min_size=1, max_size=40
    ),
    probs=st.fixed_dictionaries({w: _PROB for w in _WORDS}),
    n=st.integers(1, 45),
    start=st.sampled_from([0, 1]),
    must=st.none() | st.sets(st.sampled_from(_WORDS), min_size=1, max_size=2),
)
def test_ranking_equals_the_exact_key_over_every_sentence(sents, probs, n, start, must):
    """The float shortlist of rank_sentences never changes the exact ranking (brute force: Fraction keys)."""
    from glu.language import SentenceSet

    score = {0: "paper", 1: "original"}[start]
    pool = sorted({s for s in sents if must is None or set(s) & must})
    expected = brute_force_nbest(pool, probs, n, start)
    for given_as in (sents, [" ".join(s) for s in sents], SentenceSet(sents)):
        got = rank_sentences(given_as, probs, n, score, must_contain=must)
        assert [tuple(x.split()) for x in got["sentence"]] == [x for x, _ in expected]
        np.testing.assert_allclose(got["score"], [sc for _, sc in expected], rtol=1e-12)
    every = rank_sentences(sents, probs, None, score, must_contain=must)
    assert [tuple(x.split()) for x in every["sentence"]] == [
        x for x, _ in brute_force_nbest(pool, probs, len(pool), start)
    ]


def test_near_ties_that_floating_point_orders_the_wrong_way_are_ranked_exactly():
    """Two means that differ in the last bits: summed in floating point they tie or come out reversed
    (depending on the order of the sum), and only the exact key ranks them."""
    import math
    from fractions import Fraction

    probs = {"x1": 0.5, "x2": 0.25, "x3": 0.125, "x4": 0.0625, "o": 1.0}
    worse, better = ("x2", "x3", "x4", "o"), ("x1", "x2", "x3", "x3")
    exact = [sum(Fraction(math.log(probs[w])) for w in s) / len(s) for s in (worse, better)]
    floats = [sum(math.log(probs[w]) for w in s) / len(s) for s in (worse, better)]
    assert exact[0] < exact[1] and abs(floats[0] - floats[1]) <= 4 * np.finfo(float).eps * abs(floats[1])
    for start in (0, 1):
        got = rank_sentences([worse, better], probs, 1, {0: "paper", 1: "original"}[start])
        assert (
            tuple(got["sentence"].iloc[0].split())
            == better
            == brute_force_nbest([worse, better], probs, 1, start)[0][0]
        )


def test_exact_nbest_is_fast():
    net = default_network()
    probs = _random_probs(3)
    nbest(net, probs, 10)
    t0 = time.perf_counter()
    nbest(net, probs, 10)
    assert time.perf_counter() - t0 < 0.5


@pytest.mark.slow
def test_nbest_equals_brute_force_over_the_full_grammar():
    """All 9,331,200 sentences, streamed slot by slot from the reference expander and scored one by one (~1
    min)."""
    g = load_grammar()
    tree = {name: _as_tree(e) for name, e in g.definitions.items()}
    slots = [sorted(expand(("ref", item.name), tree)) for item in g.sentence.items]
    assert math.prod(len(s) for s in slots) == 9_331_200
    for seed in (5, 6):
        probs = _random_probs(seed)
        logs = exact_logs(probs)
        best = heapq.nsmallest(
            10, (sum(p, ()) for p in itertools.product(*slots)), key=lambda s: exact_key(s, logs)
        )
        got = nbest(g, probs, 10)
        assert [tuple(s.split()) for s in got["sentence"]] == best


def _as_tree(e):
    """A parsed expression as a reference tree (the default grammar has words, refs, seq, alt, opt)."""
    from glu.language.grammar import Alt, Opt, Ref, Seq, Word

    if isinstance(e, Word):
        return ("w", e.text)
    if isinstance(e, Ref):
        return ("ref", e.name)
    if isinstance(e, Seq):
        return ("seq", [_as_tree(x) for x in e.items])
    if isinstance(e, Alt):
        return ("alt", [_as_tree(x) for x in e.options])
    if isinstance(e, Opt):
        return ("opt", _as_tree(e.expr))
    raise TypeError(e)


# ---------------------------------------------------------------- sampling
def test_sample_nbest_ranks_the_distinct_sampled_sentences():
    g = load_grammar()
    probs = _random_probs(4)
    got = sample_nbest(g, probs, n=5, n_samples=300, seed=2)
    again = sample_nbest(g, probs, n=5, n_samples=300, seed=2)
    pd.testing.assert_frame_equal(got, again)
    exact = nbest(g, probs, 1)
    assert (got["score"] <= exact["score"].iloc[0]).all()
    ranked = rank_sentences(["b a", "a b", "a b"], {"a": 0.5, "b": 0.5})
    assert list(ranked["sentence"]) == ["a b", "b a"]


def test_compiled_network_and_grammar_give_the_same_nbest():
    probs = _random_probs(6)
    g = load_grammar()
    pd.testing.assert_frame_equal(nbest(g, probs, 5), nbest(compile_network(g), probs, 5))


# ---------------------------------------------------------------- the BN: word probabilities given evidence
@pytest.fixture(scope="module")
def engine(zero_bn):
    from glu.bn import make_engine

    return make_engine(zero_bn)


def test_and_but_follow_the_objects_velocity(engine):
    from glu.language import describe

    slow = describe(engine, {"Action": "grasp", "ObjVel": "slow"}, n=10)
    medium = describe(engine, {"Action": "grasp", "ObjVel": "medium"}, n=10)
    assert all("but" in s.split() for s in slow["sentence"])
    assert all("and" in s.split() for s in medium["sentence"])


def test_describe_ranks_a_list_of_candidate_sentences(engine):
    from glu.language import describe, word_probabilities

    ev = {"Action": "grasp", "ObjVel": "slow"}
    sents = ["the robot grasps the ball but the ball is inert", "the robot taps the box", "the ball rolls"]
    got = describe(engine, ev, candidates=sents, n=3)
    probs = word_probabilities(engine, ev).to_dict()
    expected = brute_force_nbest([tuple(s.split()) for s in sents], probs, 3, 0)
    assert [tuple(s.split()) for s in got["sentence"]] == [s for s, _ in expected]
    np.testing.assert_allclose(got["score"], [sc for _, sc in expected], rtol=1e-12)


def test_word_probabilities_match_the_word_marginals(engine):
    from glu.language import word_probabilities

    ev = {"Action": "grasp", "ObjVel": "slow"}
    probs = word_probabilities(engine, ev)
    q = engine.query(["and", "but"], ev)
    assert probs["and"] == pytest.approx(q["and"][1]) and probs["but"] == pytest.approx(q["but"][1])


def test_soft_evidence_certain_of_an_action_equals_hard_evidence(engine):
    from glu.language import describe

    hard = describe(engine, {"Action": "tap", "Shape": "sphere"}, n=5)
    soft = describe(engine, {"Shape": "sphere"}, soft={"Action": {"grasp": 0, "tap": 1, "touch": 0}}, n=5)
    assert list(hard["sentence"]) == list(soft["sentence"])
    np.testing.assert_allclose(hard["score"], soft["score"], rtol=1e-9)
    fused = describe(engine, {"Shape": "sphere"}, soft={"Action": [0.2, 0.6, 0.2]}, n=5)
    assert len(fused) == 5


def test_tcds_experiments(engine):
    from glu.studies.replication import verbal as ex

    yellow = ex.yellow_sphere_nbest(engine)
    assert list(yellow.columns) == ["rank", "sentence", "score", "length"] and len(yellow) == 10
    assert yellow["score"].is_monotonic_decreasing
    ab = ex.and_but_probabilities(engine)
    p = ab.set_index(["ObjVel", "word"])["p"]
    assert p["slow", "but"] > p["slow", "and"] and p["medium", "and"] > p["medium", "but"]
    nb = ex.and_but_nbest(engine, n=3)
    assert list(nb["conjunction"]) == ["and"] * 3 + ["but"] * 3
    fig8 = ex.fig8_descriptions(engine)
    assert len(fig8) == 4
    for row in fig8.itertuples():
        assert set(row.colour_sentence.split()) & {"green", "yellow", "blue"}
        assert row.colour_score <= row.score
    for score in ("paper", "original"):
        cmp = ex.sampling_vs_exact(engine, ex.EVIDENCE_AND_BUT["slow"], [0, 1], n_samples=2000, score=score)
        assert (cmp["gap"] >= 0).all() and (cmp["sample_rank"] >= 1).all()
        assert (cmp["found_best"] == (cmp["gap"] == 0)).all()
        assert ((cmp["p_draw_best"] > 0) & (cmp["p_draw_best"] < 1)).all()


def test_published_descriptions_and_exact_vs_samples(engine):
    from glu.data.published import num2str, published
    from glu.language import sample_sentences
    from glu.studies.replication import verbal as ex

    samples = sample_sentences(load_grammar(), 3000, seed=0)
    rep = ex.published_descriptions(engine, samples, score="original")
    pub = published()["sentences"]
    assert len(rep) == 3 * 10 + 4 and list(rep["figure"].unique()) == [
        *ex.PUBLISHED_LISTS,
        *(f"fig8{x}" for x in "abcd"),
    ]
    assert list(rep["paper_sentence"][:10]) == [r["sentence"] for r in pub["table_ii"]["rows"]]
    assert (rep["printed"] == [num2str(x) for x in rep["score"]]).all()
    drawn = {" ".join(x) for x in samples}
    assert set(rep["sentence"]) <= drawn  # ranked among the candidates only
    for key, ev in ex.PUBLISHED_LISTS.items():  # each list is the ranking of the samples under that evidence
        ours = rep[rep["figure"] == key]
        expected = rank_sentences(samples, word_probabilities(engine, ev), 10, score="original")
        assert list(ours["sentence"]) == list(expected["sentence"])
    fig8 = rep[rep["figure"].str.startswith("fig8")]
    assert (
        all(set(x.split()) & set(ex.COLOUR_WORDS) for x in fig8["sentence"])
        and fig8["same_score"].isna().all()
    )
    vs = ex.exact_vs_samples(engine, samples)
    assert len(vs) == 6 and set(vs["score_name"]) == {"paper", "original"}
    assert (vs["exact_score"] >= vs["samples_score"]).all() and (vs["samples_rank"] >= 1).all()
    assert ((vs["samples_rank"] == 1) == (vs["exact_score"] == vs["samples_score"])).all()
    assert (vs["exact_in_samples"] == [s in drawn for s in vs["exact_best"]]).all()


def test_the_published_evidence_is_the_codes():
    from glu.data.published import published
    from glu.studies.replication import verbal as ex

    pub = published()["sentences"]
    for key, ev in ex.PUBLISHED_LISTS.items():
        assert pub[key]["evidence"] == ev
    assert [r["evidence"] for r in pub["fig8"]["rows"]] == list(ex.EVIDENCE_FIG8)


def test_num2str_prints_whole_numbers_without_a_point_as_matlab():
    """MATLAB's num2str of an integer-valued double prints its digits alone: num2str(3) is '3', num2str(-2)
    '-2', num2str(1e6) '1000000'."""
    from glu.data.published import num2str

    assert [num2str(x) for x in (3.0, -2.0, 0.0, 1e6)] == ["3", "-2", "0", "1000000"]


def test_an_unknown_paper_names_the_published_ones():
    from glu.data.published import published
    from glu.errors import DataError

    with pytest.raises(DataError, match="no published numbers named 'tcds2099'; there are: tcds2020"):
        published("tcds2099")


# ---------------------------------------------------------------- the command line
def test_cli_done_when(source, capsys):
    for objvel, word in [("slow", "but"), ("medium", "and")]:
        assert (
            main(
                [
                    "describe",
                    "--data",
                    str(source.root),
                    "--evidence",
                    "Action=grasp",
                    f"ObjVel={objvel}",
                    "--nbest",
                    "10",
                ]
            )
            == 0
        )
        out = capsys.readouterr().out
        lines = [ln for ln in out.splitlines() if not ln.startswith("#")]
        assert lines[0].split() == ["rank", "score", "sentence"]
        assert len(lines) == 11 and word in lines[1].split()
        assert f"learned from {source.kind} data" in out


def test_cli_json_and_sampling(capsys):
    assert (
        main(["describe", "--data", "synthetic", "--evidence", "Action=tap", "--nbest", "3", "--json"]) == 0
    )
    captured = capsys.readouterr()
    out = json.loads(captured.out)
    assert [set(r) for r in out] == [{"sentence", "score"}] * 3
    assert [r["score"] for r in out] == sorted((r["score"] for r in out), reverse=True)
    assert "synthetic" in captured.err and "9,331,200 sentences" in captured.err  # provenance on stderr
    assert (
        main(["describe", "--data", "synthetic", "--sample", "500", "--seed", "1", "--nbest", "3", "--json"])
        == 0
    )
    captured = capsys.readouterr()
    sampled = json.loads(captured.out)
    assert len(sampled) == 3 and "500 random sentences (HSGen-like, seed 1" in captured.err
    exact_best = float(captured.err.split("exact best over the grammar")[1].split(":")[1].split()[0])
    assert sampled[0]["score"] <= exact_best + 1e-5


def test_cli_scores_and_candidate_files(tmp_path, capsys):
    from glu.bn import learn_bn, make_engine
    from glu.data import load_experiments
    from glu.language import word_probabilities

    sentences = [
        "the robot taps the ball and the ball rolls",
        "he pokes the box but the box is still",
        "the robot is grasping the cube and the cube is rising",
    ]
    f = tmp_path / "candidates.txt"
    f.write_text("\n".join(sentences) + "\n\n")
    ev = ["--evidence", "Action=touch", "Shape=box"]
    for score, start in (("paper", 0), ("original", 1)):
        argv = ["describe", "--data", "synthetic", *ev, "--candidates", str(f), "--score", score, "--json"]
        assert main(argv) == 0
        got = json.loads(capsys.readouterr().out)
        probs = word_probabilities(
            make_engine(learn_bn(load_experiments("synthetic"))), {"Action": "touch", "Shape": "box"}
        ).to_dict()
        expected = brute_force_nbest([tuple(s.split()) for s in sentences], probs, 10, start)
        assert [r["sentence"] for r in got] == [" ".join(s) for s, _ in expected]
        got_scores = [-math.inf if r["score"] is None else r["score"] for r in got]  # JSON has no -inf
        np.testing.assert_allclose(got_scores, [sc for _, sc in expected], rtol=1e-12)
    assert (
        main(["describe", "--data", "synthetic", *ev, "--candidates", str(f), "--must-contain", "box"]) == 0
    )
    text = capsys.readouterr().out
    assert "of 3 candidate sentences" in text and "he pokes the box but the box is still" in text
    assert "the robot taps the ball" not in text and "exact best over the grammar" in text


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--seed", "3"], "--sample"),
        (["--evidence", "Action"], "malformed"),
        (["--evidence", "Action=jump"], "jump"),
        (["--grammar", "/nonexistent.grm"], "no such grammar file"),
        (["--must-contain", "purple"], "purple"),
        (["--candidates", "samples"], "sampled sentences are not in the data"),
        (["--candidates", "/nonexistent.txt"], "no such sentence file"),
        (["--candidates", "/nonexistent.txt", "--sample", "10"], "--candidates grammar only"),
        (["--candidates", "/nonexistent.txt", "--max-length", "10"], "--candidates grammar only"),
    ],
)
def test_cli_bad_input_is_one_line(argv, message, capsys):
    assert main(["describe", "--data", "synthetic", *argv]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_cli_unknown_score_is_a_usage_error(capsys):
    with pytest.raises(SystemExit) as e:
        main(["describe", "--data", "synthetic", "--score", "mean"])
    err = capsys.readouterr().err
    assert e.value.code == 2 and "invalid choice: 'mean'" in err and len(err.strip().splitlines()) == 1


def test_cli_bad_grammars(tmp_path, capsys):
    bad = tmp_path / "bad.grm"
    bad.write_text("$a = the robot;\n( $a $b )\n")
    assert main(["describe", "--data", "synthetic", "--grammar", str(bad)]) == 2
    assert f"{bad}:2:6: $b is not defined" in capsys.readouterr().err
    unknown = tmp_path / "unknown.grm"
    unknown.write_text("( the robot zzz )\n")  # a word that is no network node scores p = 1, and is named
    assert main(["describe", "--data", "synthetic", "--grammar", str(unknown)]) == 0
    assert (
        "# words that are not network nodes score as p = 1 (function words): zzz" in capsys.readouterr().out
    )
    foreign = tmp_path / "foreign.grm"
    foreign.write_text("( zzz yyy )\n")
    assert main(["describe", "--data", "synthetic", "--grammar", str(foreign)]) == 2
    assert "the grammar and the network share no word" in capsys.readouterr().err
    loop = tmp_path / "loop.grm"
    loop.write_text("( the robot {taps} )\n")
    assert main(["describe", "--data", "synthetic", "--grammar", str(loop)]) == 2
    assert "--max-length" in capsys.readouterr().err
    assert main(["describe", "--data", "synthetic", "--grammar", str(loop), "--max-length", "4"]) == 0
    assert "the robot taps taps" in capsys.readouterr().out


# ---------------------------------------------------------------- plots
def test_plots_draw_what_they_are_given():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from glu.studies.replication.verbal_figures import plot_and_but, plot_nbest, plot_sampling

    df = nbest(parse_grammar("( (a | b) [c] )"), {"a": 0.5, "b": 0.2, "c": 0.9}, n=4)
    fig, axes = plt.subplots(1, 3)
    plot_nbest(axes[0], df, title="t", highlight="c")
    ranked = [f"{k}. {s}" for k, s in enumerate(df["sentence"], 1)]
    assert [t.get_text() for t in axes[0].get_yticklabels()] == ranked  # rank 1 first
    (dots,) = axes[0].collections  # a dot per sentence at its score (a dot plot, not bars)
    np.testing.assert_allclose(dots.get_offsets()[:, 0], df["score"])
    assert not axes[0].patches
    probs = pd.DataFrame(
        {
            "ObjVel": ["medium", "medium", "slow", "slow"],
            "word": ["and", "but"] * 2,
            "p": [0.8, 0.2, 0.1, 0.9],
        }
    )
    plot_and_but(axes[1], probs)
    heights = sorted(round(p.get_height(), 6) for p in axes[1].patches)
    assert heights == [0.1, 0.2, 0.8, 0.9]
    plot_sampling(axes[2], np.array([-1.0, -2.0, -np.inf]), np.array([-2.0]), -1.0)
    assert "scoring −∞ (a word of probability 0): 1 of the grammar's sentences (33 %)" in axes[2].get_title()
    plt.close(fig)
