"""Verbal descriptions (docs/method.md §6): the grammar, its sentences, and sentences scored by the BN's word
probabilities.

* :mod:`glu.language.grammar` — HTK HParse grammars: :func:`parse_grammar`, :func:`load_grammar`.
* :mod:`glu.language.sentences` — the deterministic word network, counting, enumeration.
* :mod:`glu.language.sampling` — random sentences as the originals drew them (HTK's HSGen).
* :mod:`glu.language.descriptions` — the two scores (:data:`SCORES`), the exact N-best (:func:`nbest`),
  ranking a list of sentences, :func:`describe`.
* :mod:`glu.language.candidates` — the sentences to choose from: the grammar, the originals' samples, a file.

The TCDS experiments built on them are in :mod:`glu.studies.replication.verbal`, their figures in
:mod:`glu.plots`.
"""

from glu.language.candidates import CANDIDATES, SentenceSet, candidate_sentences, read_sentences
from glu.language.descriptions import (
    DEFAULT_SCORE,
    SCORES,
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
from glu.language.sampling import sample_probability, sample_sentences
from glu.language.sentences import (
    WordNetwork,
    compile_network,
    count_by_length,
    count_sentences,
    enumerate_sentences,
    restrict,
    same_language,
)

__all__ = [
    "CANDIDATES",
    "DEFAULT_GRAMMAR_PATH",
    "DEFAULT_SCORE",
    "SCORES",
    "SentenceSet",
    "Grammar",
    "WordNetwork",
    "all_scores",
    "candidate_sentences",
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
    "read_sentences",
    "restrict",
    "same_language",
    "sample_nbest",
    "sample_probability",
    "sample_sentences",
    "score_sentence",
    "score_sentences",
    "word_probabilities",
]
