"""The HParse grammar parser: the default grammar, hand-written trees, clear errors with line and column."""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from language_reference import expand, grammar_text

from glu.errors import GluError, GrammarError
from glu.language.grammar import (
    DEFAULT_GRAMMAR_PATH,
    Alt,
    Opt,
    Ref,
    Rep,
    Seq,
    Word,
    load_grammar,
    parse_grammar,
)
from glu.language.sentences import compile_network, count_by_length, count_sentences
from glu.schema import WORDS


# ---------------------------------------------------------------- the default grammar
def test_default_grammar_uses_exactly_the_models_vocabulary():
    g = load_grammar()
    assert set(g.vocabulary) == set(WORDS)
    assert len(g.vocabulary) == 49
    assert not g.has_repetition


def test_default_grammar_has_the_hand_counted_number_of_sentences():
    # agent 3 × verb 6·(1+4+1) × object (1·3·4·5) × conjunction 2 × object 60 × effect 12
    assert count_sentences(load_grammar()) == 3 * 36 * 60 * 2 * 60 * 12 == 9_331_200


def test_default_grammar_shortest_and_longest_counts_by_hand():
    counts = count_by_length(load_grammar())
    # 8 words: {he, baltazar} × 12 one-word verb forms × "the NOUN" 5 × 2 × 5 × 5 one-word effects
    assert counts[8] == 2 * 12 * 5 * 2 * 5 * 5
    # 16 words: "the robot" × "has just VERBed" 6 × "the SIZE COLOUR NOUN" 30 × 2 × 30 × 7 two-word effects
    assert counts[16] == 6 * 30 * 2 * 30 * 7
    assert min(counts) == 8 and max(counts) == 16


def test_default_grammar_is_our_own_text():
    text = DEFAULT_GRAMMAR_PATH.read_text()
    assert "$subject" in text and "$agent" not in text


# ---------------------------------------------------------------- trees
def test_parse_builds_the_expected_tree():
    g = parse_grammar("$a = x | y z;\n( [$a] w {v} <u> )")
    assert g.definitions == {"a": Alt((Word("x"), Seq((Word("y"), Word("z")))))}
    assert g.sentence == Seq((Opt(Ref("a")), Word("w"), Rep(Word("v")), Rep(Word("u"), at_least_one=True)))
    assert g.vocabulary == ("u", "v", "w", "x", "y", "z")
    assert g.has_repetition


def test_comments_escapes_and_external_names():
    g = parse_grammar("/* a\n comment */ $a = x\\(y /* inline */ | z%Z;\n( $a w%% )  /* trailing */")
    assert g.definitions["a"] == Alt((Word("x(y"), Word("z")))
    assert g.sentence == Seq((Ref("a"), Word("w")))


def test_forward_references_are_accepted():
    g = parse_grammar("$a = $b b; $b = x; ($a)")
    assert expand(("ref", "a"), {"a": ("seq", [("ref", "b"), ("w", "b")]), "b": ("w", "x")}) == {("x", "b")}
    assert count_sentences(g) == 1


def test_format_round_trips():
    g = load_grammar()
    again = parse_grammar(g.format())
    assert again.definitions == g.definitions and again.sentence == g.sentence


def test_positions_are_recorded():
    g = parse_grammar("$a = x;\n\n  ( $a\n    y )")
    assert g.sentence.items[0].pos == (3, 5)
    assert g.sentence.items[1].pos == (4, 5)


# ---------------------------------------------------------------- errors
BAD = [
    # text, line, column, part of the message
    ("", 1, 1, "no sentence"),
    ("$a = x;", 1, 8, "no sentence"),
    ("x y", 1, 1, "found the word 'x'"),
    ("(x", 1, 3, "expected ')' closing the sentence"),
    ("(x | )", 1, 6, "found ')'"),
    ("(| x)", 1, 2, "found '|'"),
    ("( [x )", 1, 6, "expected ']' closing the '['"),
    ("( {x ]", 1, 6, "expected '}' closing the '{'"),
    ("(a) b", 1, 5, "nothing may follow the sentence"),
    ("$a x;\n(a)", 1, 4, "expected '='"),
    ("$a = x\n(a)", 2, 4, "expected ';' at the end of the definition of $a (line 1), found the end"),
    (
        "$a = x\n$b = y;\n(a)",
        2,
        1,
        "expected ';' at the end of the definition of $a (line 1), before the definition of $b",
    ),
    ("$a = x;\n( $b )", 2, 3, "$b is not defined"),
    ("$color = x;\n( $colour )", 2, 3, "did you mean $color"),
    ("$a = x;\n$a = y;\n($a)", 2, 1, "defined twice"),
    ("$a = x $a;\n($a)", 1, 8, "recursive definition $a → $a"),
    ("$a = $b;\n$b = [x $c];\n$c = $a;\n($a)", 3, 6, "$a → $b → $c → $a"),
    ("(x /* never closed", 1, 4, "never closed"),
    ("(x / y)", 1, 4, "unexpected '/'"),
    ("(x * y)", 1, 4, "unexpected '*'"),
    ("( $ x )", 1, 3, "'$' must be followed by a variable name"),
    ("( <<x>> )", 1, 3, "not supported"),
    ("( %x )", 1, 3, "cannot start with '%'"),
    ("(x \\", 1, 4, "backslash"),
    ("\t(x\n\n   ;", 3, 4, "expected ')'"),
]


@pytest.mark.parametrize("text, line, column, part", BAD)
def test_malformed_grammars_say_where(text, line, column, part):
    with pytest.raises(GrammarError) as info:
        parse_grammar(text, "g.grm")
    e = info.value
    assert (e.line, e.column) == (line, column), str(e)
    assert part in str(e)
    assert str(e).startswith(f"g.grm:{line}:{column}: ")
    assert isinstance(e, GluError) and isinstance(e, ValueError)


def test_deep_nesting_is_an_error_not_a_crash():
    with pytest.raises(GrammarError, match="nested more than"):
        parse_grammar("(" * 500 + "x" + ")" * 500)


def test_long_chains_of_variables_compile():
    defs = "\n".join(f"$v{k} = $v{k - 1} | w{k};" for k in range(1, 60))
    g = parse_grammar("$v0 = w0;\n" + defs + "\n($v59)")
    assert count_sentences(g) == 60


def test_grammar_files(tmp_path):
    with pytest.raises(GrammarError, match="no such grammar file"):
        load_grammar(tmp_path / "missing.grm")
    with pytest.raises(GrammarError, match="folder"):
        load_grammar(tmp_path)
    bad = tmp_path / "latin1.grm"
    bad.write_bytes("(caf\xe9)".encode("latin-1"))
    with pytest.raises(GrammarError, match="UTF-8"):
        load_grammar(bad)
    with pytest.raises(GrammarError, match=r"cannot read the grammar file \(File name too long\)"):
        load_grammar(tmp_path / ("g" * 300 + ".grm"))
    with pytest.raises(GrammarError, match="<string>: a grammar is text, not bytes"):
        parse_grammar(b"( a )")
    good = tmp_path / "ok.grm"
    good.write_text(grammar_text(("seq", [("w", "a"), ("opt", ("w", "b"))])))
    assert count_sentences(load_grammar(good)) == 2


# ---------------------------------------------------------------- fuzzing: only GrammarError, with a place
TOKENS = [
    "$a",
    "$b",
    "$",
    "=",
    ";",
    "(",
    ")",
    "[",
    "]",
    "{",
    "}",
    "<",
    ">",
    "|",
    "x",
    "y",
    "\\",
    "/*",
    "*/",
    "/",
    "*",
    "%",
    " ",
    "\n",
    "<<",
    "$a = x;",
    "(x)",
    "é",
    "\t",
]


def _check_error(text: str) -> None:
    try:
        g = parse_grammar(text)
    except GrammarError as e:
        assert e.line is not None and e.column is not None
        assert 1 <= e.line <= text.count("\n") + 1
        assert 1 <= e.column <= len(text.split("\n")[e.line - 1]) + 1
        return
    compile_network(g)  # a grammar that parses also compiles (or raises GrammarError)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.sampled_from(TOKENS), max_size=25).map("".join))
def test_fuzzed_token_soup_raises_only_grammar_errors(text):
    _check_error(text)


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=40))
def test_fuzzed_text_raises_only_grammar_errors(text):
    _check_error(text)


def _trees():
    leaves = st.sampled_from(["a", "b", "c(", "d%"]).map(
        lambda w: ("w", w.replace("(", "\\(").replace("%", "\\%"))
    )

    def extend(children):
        lists = st.lists(children, min_size=2, max_size=3)
        return st.one_of(
            lists.map(lambda xs: ("seq", xs)),
            lists.map(lambda xs: ("alt", xs)),
            children.map(lambda x: ("opt", x)),
            children.map(lambda x: ("star", x)),
            children.map(lambda x: ("plus", x)),
        )

    return st.recursive(leaves, extend, max_leaves=10)


@settings(max_examples=100, deadline=None)
@given(tree=_trees(), sub=_trees())
def test_format_round_trips_random_grammars(tree, sub):
    g = parse_grammar(grammar_text(("seq", [tree, ("ref", "v")]), {"v": sub}))
    again = parse_grammar(g.format())
    assert again.definitions == g.definitions and again.sentence == g.sentence
