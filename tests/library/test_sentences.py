"""Sentences of a grammar: hand-counted tiny grammars, enumeration against direct expansion, HSGen
sampling."""

from __future__ import annotations

import collections

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from language_reference import expand, grammar_text, recursive_samples

from glu.errors import GrammarError
from glu.language.grammar import load_grammar, parse_grammar
from glu.language.sampling import sample_probability, sample_sentences
from glu.language.sentences import (
    compile_network,
    count_by_length,
    count_sentences,
    enumerate_sentences,
    restrict,
    same_language,
)


def _sents(*texts: str) -> list[tuple[str, ...]]:
    return [tuple(t.split()) for t in texts]


# ---------------------------------------------------------------- counting by hand
@pytest.mark.parametrize(
    "text, counts",
    [
        ("( a [b] (c | d e) )", {2: 1, 3: 2, 4: 1}),  # a c | a d e | a b c | a b d e
        ("$x = a | b | c; ( $x $x )", {2: 9}),
        ("( [a] [a] )", {0: 1, 1: 1, 2: 1}),  # 4 derivations, 3 sentences: '', a, a a
        ("( a | a )", {1: 1}),
        ("( (a | a b) (c | b c) )", {2: 1, 3: 1, 4: 1}),  # a c, a b c (twice), a b b c
        ("( the [big] [green] ball | the ball )", {2: 1, 3: 2, 4: 1}),
    ],
)
def test_counts_of_tiny_grammars(text, counts):
    g = parse_grammar(text)
    assert count_by_length(g) == counts
    assert count_sentences(g) == sum(counts.values())


def test_infinite_grammars_need_a_length_limit():
    g = parse_grammar("( a {b} )")
    with pytest.raises(GrammarError, match="infinitely many"):
        count_sentences(g)
    assert count_by_length(g, max_length=4) == {1: 1, 2: 1, 3: 1, 4: 1}
    assert list(enumerate_sentences(g, max_length=3)) == _sents("a", "a b", "a b b")
    plus = parse_grammar("( a <b c> )")
    assert count_by_length(plus, max_length=6) == {3: 1, 5: 1}
    assert not compile_network(plus).is_finite and compile_network(g).max_length is None


def test_empty_language():
    g = parse_grammar("$x = a; ( <$x> )")
    net = restrict(compile_network(g), exclude=["a"])
    assert count_sentences(net) == 0 and list(enumerate_sentences(net)) == []


# ---------------------------------------------------------------- enumeration vs expansion
def test_enumeration_is_sorted_complete_and_without_repeats():
    g = parse_grammar("$o = the [big | small] (ball | box); ( $o [and $o] )")
    got = list(enumerate_sentences(g))
    assert got == sorted(got)
    assert len(got) == len(set(got)) == count_sentences(g)
    ref_tree = (
        "seq",
        [
            ("w", "the"),
            ("opt", ("alt", [("w", "big"), ("w", "small")])),
            ("alt", [("w", "ball"), ("w", "box")]),
        ],
    )
    ref = expand(("seq", [("ref", "o"), ("opt", ("seq", [("w", "and"), ("ref", "o")]))]), {"o": ref_tree})
    assert set(got) == ref


WORDS_ST = st.sampled_from(["a", "b", "c"])


def _trees(allow_rep: bool):
    leaves = WORDS_ST.map(lambda w: ("w", w))

    def extend(children):
        options = [
            st.lists(children, min_size=2, max_size=3).map(lambda xs: ("seq", xs)),
            st.lists(children, min_size=2, max_size=3).map(lambda xs: ("alt", xs)),
            children.map(lambda x: ("opt", x)),
        ]
        if allow_rep:
            options += [children.map(lambda x: ("star", x)), children.map(lambda x: ("plus", x))]
        return st.one_of(options)

    return st.recursive(leaves, extend, max_leaves=8)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(tree=_trees(allow_rep=True), sub=_trees(allow_rep=False), max_length=st.integers(0, 5))
def test_network_has_exactly_the_expanded_sentences(tree, sub, max_length):
    # the sentence uses a variable twice, as $object does in the default grammar
    sentence = ("seq", [tree, ("ref", "v"), ("opt", ("ref", "v"))])
    g = parse_grammar(grammar_text(sentence, {"v": sub}))
    ref = expand(sentence, {"v": sub}, max_length=max_length)
    got = list(enumerate_sentences(g, max_length=max_length))
    assert set(got) == ref and len(got) == len(ref)
    by_len = collections.Counter(len(s) for s in ref)
    assert count_by_length(g, max_length=max_length) == dict(by_len)
    net = compile_network(g)
    assert all(net.accepts(s) for s in ref)


# ---------------------------------------------------------------- restriction, equivalence, acceptance
def test_restrict_counts_by_hand():
    net = compile_network(load_grammar())
    # no colour in an object: 3 sizes × 5 nouns = 15 of its 60 forms
    no_colour = 3 * 36 * 15 * 2 * 15 * 12
    assert count_sentences(restrict(net, must_contain=["green", "yellow", "blue"])) == 9_331_200 - no_colour
    assert count_sentences(restrict(net, exclude=["but"])) == 9_331_200 // 2
    assert count_sentences(restrict(net, must_contain=["yellow"], exclude=["green", "blue"])) == (
        3 * 36 * 2 * 12 * (30 * 30 - 15 * 15)  # objects without green/blue: 30 forms, of which 15 lack yellow
    )


def test_same_language():
    def net(t):
        return compile_network(parse_grammar(t))

    assert same_language(net("( a [b] )"), net("( a | a b )"))
    assert same_language(net("( {a} )"), net("( [<a>] )"))
    assert not same_language(net("( a [b] )"), net("( a b )"))
    assert not same_language(net("( a {a} )"), net("( a [a] )"))


def test_accepts():
    net = compile_network(load_grammar())
    assert net.accepts("the robot is tapping the big blue ball but the ball is still")
    assert not net.accepts("the robot is tapping the big blue ball but the ball")
    assert not net.accepts("the robot is tapping the blue big ball but the ball is still")
    assert not net.accepts("the robot taps the purple ball and the ball rolls")


# ---------------------------------------------------------------- random sentences (HSGen)
def test_sampling_is_seeded_and_grammatical():
    g = load_grammar()
    a, b, c = (
        sample_sentences(g, 500, seed=7),
        sample_sentences(g, 500, seed=7),
        sample_sentences(g, 500, seed=8),
    )
    assert a == b and a != c
    net = compile_network(g)
    assert all(net.accepts(s) for s in a)


def test_sampling_makes_a_uniform_choice_at_each_alternative_and_a_fair_coin_for_options():
    g = parse_grammar("( (a | b c | d) [e] )")
    n = 30_000
    counts = collections.Counter(sample_sentences(g, n, seed=0))
    first = collections.Counter(s[0] for s in counts.elements())
    for w in "abd":
        assert abs(first[w] / n - 1 / 3) < 0.015
    with_e = sum(c for s, c in counts.items() if s[-1] == "e")
    assert abs(with_e / n - 0.5) < 0.015
    # HSGen follows the grammar, not the language: "the robot" is one of 3 agents, "has" 1/2 of 1/3 verb forms
    samples = sample_sentences(load_grammar(), n, seed=1)
    assert abs(sum(s[0] == "the" for s in samples) / n - 1 / 3) < 0.015
    assert abs(sum("has" in s for s in samples) / n - 1 / 6) < 0.015


def test_sampling_repetitions_are_geometric():
    counts = collections.Counter(len(s) for s in sample_sentences(parse_grammar("( {a} )"), 20_000, seed=3))
    for k in range(4):
        assert abs(counts[k] / 20_000 - 0.5 ** (k + 1)) < 0.015


@pytest.mark.parametrize("seed", [0, 1, 7, 2**31 - 1])
def test_sampling_draws_exactly_what_the_recursive_walk_draws(seed):
    g = load_grammar()
    assert sample_sentences(g, 2000, seed) == recursive_samples(g, 2000, seed)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(tree=_trees(allow_rep=True), sub=_trees(allow_rep=False), seed=st.integers(0, 2**32 - 1))
def test_sampling_any_grammar_draws_what_the_recursive_walk_draws(tree, sub, seed):
    g = parse_grammar(grammar_text(("seq", [tree, ("ref", "v"), ("opt", ("ref", "v"))]), {"v": sub}))
    assert sample_sentences(g, 50, seed) == recursive_samples(g, 50, seed)


def test_sampling_bad_n():
    with pytest.raises(GrammarError):
        sample_sentences(load_grammar(), -1)


# ---------------------------------------------------------------- the sampler's probability of a sentence
def test_sample_probability_by_hand():
    g = parse_grammar("( [a] [a] )")
    assert [sample_probability(g, s) for s in ("", "a", "a a", "a a a", "b")] == [0.25, 0.5, 0.25, 0.0, 0.0]
    # a repetition whose round may be empty: never an 'a' = Σ_k (1/2)^(k+1) (1/2)^k = 2/3
    assert sample_probability(parse_grammar("( {[a]} )"), "") == pytest.approx(2 / 3)
    assert sample_probability(parse_grammar("( <a> )"), "a a") == pytest.approx(0.25)
    # the default grammar: agent 1/3 · pick 1/6 · "is …ing" 1/3 · (no size 1/2 · no colour 1/2 · square 1/5)²
    # · conjunction 1/2 · "is inert" 1/3 · 1/4
    best = "the robot is picking the square but the square is inert"
    by_hand = (1 / 3) * (1 / 6) * (1 / 3) * (1 / 20) ** 2 * (1 / 2) * (1 / 12)
    assert sample_probability(load_grammar(), best) == pytest.approx(by_hand, rel=1e-12)
    assert by_hand == 1 / 518_400


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(tree=_trees(allow_rep=False))
def test_sample_probabilities_of_a_finite_grammar_sum_to_one(tree):
    g = parse_grammar(grammar_text(tree))
    total = sum(sample_probability(g, s) for s in enumerate_sentences(g))
    assert total == pytest.approx(1.0, abs=1e-12)


def test_sample_probability_matches_sampling_frequencies():
    g = parse_grammar("$x = a | a b; ( $x [b] {c} )")
    n = 40_000
    counts = collections.Counter(sample_sentences(g, n, seed=11))
    for s in [("a",), ("a", "b"), ("a", "b", "b"), ("a", "c"), ("a", "b", "c", "c")]:
        p = sample_probability(g, s)
        assert abs(counts[s] / n - p) < 4 * (p * (1 - p) / n) ** 0.5 + 1e-3, s


def test_sampling_a_grammar_nested_deeper_than_python_recurses_is_a_grammar_error():
    text = "".join(f"$v{i} = $v{i + 1};\n" for i in range(3000)) + "$v3000 = a | b;\n( $v0 )\n"
    with pytest.raises(GrammarError, match="nests too deeply"):
        sample_sentences(parse_grammar(text), 3, seed=0)


def test_sample_probability_of_rounds_that_end_at_the_same_word():
    """``{a | a a}``: a round is one 'a' or two (1/2 each), another round with 1/2. "a a" is two short rounds
    (1/4 · 1/4 · 1/2) or one long one (1/4 · 1/2): 5/32; "a a a" is three short rounds or a short and a long
    one in either order: 1/128 + 2/32 = 9/128. A variable used twice is read once."""
    g = parse_grammar("( { a | a a } )")
    assert sample_probability(g, "a a") == 5 / 32 and sample_probability(g, "a a a") == 9 / 128
    twice = parse_grammar("$x = a; ( $x | $x b )")
    assert [sample_probability(twice, s) for s in ("a", "a b", "b")] == [0.5, 0.5, 0.0]


def test_a_sentence_longer_than_python_recurses_is_a_grammar_error():
    with pytest.raises(GrammarError, match="the sentence is too long or the grammar nests too deeply"):
        sample_probability(parse_grammar("( { a } )"), " ".join(["a"] * 20_000))


def test_a_random_sentence_that_grows_without_bound_is_a_grammar_error():
    """One round of the repetition is 11,000 words: a sample that takes it (probability 1/2 each) goes past
    the limit of 10,000 words."""
    text = "$a0 = x x x x x x x x x x;\n" + "".join(
        f"$a{k} = {' '.join([f'$a{k - 1}'] * 10)};\n" for k in (1, 2)
    )
    g = parse_grammar(text + "$a3 = " + " ".join(["$a2"] * 11) + ";\n( { $a3 } )")
    with pytest.raises(GrammarError, match="a random sentence grew beyond 10000 words"):
        sample_sentences(g, 20, seed=0)


@pytest.mark.parametrize("max_length", [-1, 2.5])
def test_a_maximum_length_is_a_whole_number(max_length):
    with pytest.raises(
        GrammarError, match=f"the maximum length must be a whole number ≥ 0, not {max_length}"
    ):
        count_sentences(parse_grammar("( a {b} )"), max_length=max_length)


def test_grammars_too_large_or_too_deep_to_compile(monkeypatch):
    chain = "".join(f"$v{i} = $v{i - 1};\n" if i else "$v0 = a;\n" for i in range(1500)) + "( $v1499 )"
    with pytest.raises(GrammarError, match="the grammar nests variables too deeply to expand"):
        compile_network(parse_grammar(chain))
    # each chain alone is within reach, but the second runs through the first: compiled, they nest 1,200 deep
    x = "".join(f"$x{i} = $x{i - 1};\n" if i else "$x0 = a;\n" for i in range(600))
    y = "".join(f"$y{i} = $y{i - 1};\n" if i else "$y0 = $x599;\n" for i in range(600))
    with pytest.raises(GrammarError, match="the grammar nests too deeply to compile"):
        compile_network(parse_grammar(x + y + "( $x599 | $y599 )"))
    doubling = "$a0 = x x;\n" + "".join(f"$a{k} = $a{k - 1} $a{k - 1};\n" for k in range(1, 20)) + "( $a19 )"
    with pytest.raises(
        GrammarError, match="expands to 1048576 words once variables are substituted; glu handles"
    ):
        compile_network(parse_grammar(doubling))
    # the k-th word from the end is an 'a': a deterministic network needs 2^k states (here k = 11, limit 1000)
    monkeypatch.setattr("glu.language.sentences.MAX_DFA_STATES", 1000)
    explodes = "( { a | b } a " + " ".join(["(a | b)"] * 10) + " )"
    with pytest.raises(GrammarError, match="the grammar's word network needs more than 1000 states"):
        compile_network(parse_grammar(explodes))


def test_counting_needs_a_grammar_or_its_network():
    with pytest.raises(TypeError, match="expected a Grammar or a WordNetwork, not str"):
        count_sentences("( a b )")
