"""Verbal descriptions (METHOD.md §5): the grammar, its sentences, and sentences scored by the BN's word probabilities.

* :mod:`glu.language.grammar` — HTK HParse grammars: :func:`parse_grammar`, :func:`load_grammar`.
* :mod:`glu.language.sentences` — the deterministic word network, counting, enumeration, HSGen-like sampling.
* :mod:`glu.language.descriptions` — scores, the exact N-best (:func:`nbest`), :func:`describe`.
* :mod:`glu.language.experiments` — the TCDS experiments as DataFrames; :mod:`glu.language.plots` — figures.
"""

from glu.language.descriptions import (
    all_scores,
    default_network,
    describe,
    nbest,
    rank_sentences,
    sample_nbest,
    score_sentence,
    score_sentences,
    word_probabilities,
)
from glu.language.grammar import DEFAULT_GRAMMAR_PATH, Grammar, load_grammar, parse_grammar
from glu.language.sentences import (
    WordNetwork,
    compile_network,
    count_by_length,
    count_sentences,
    enumerate_sentences,
    restrict,
    same_language,
    sample_probability,
    sample_sentences,
)

__all__ = [
    "DEFAULT_GRAMMAR_PATH",
    "Grammar",
    "WordNetwork",
    "all_scores",
    "compile_network",
    "count_by_length",
    "count_sentences",
    "default_network",
    "describe",
    "enumerate_sentences",
    "load_grammar",
    "nbest",
    "parse_grammar",
    "rank_sentences",
    "restrict",
    "same_language",
    "sample_nbest",
    "sample_probability",
    "sample_sentences",
    "score_sentence",
    "score_sentences",
    "word_probabilities",
]
