"""Sentences scored by the BN's word probabilities, and the exact N-best descriptions of a grammar.

**Two scores** (:data:`SCORES`). The papers' score of a sentence ``s = w_1 … w_L`` given evidence ``e``
(docs/method.md §6.2) is the mean log probability of its words,

    paper:     score(s) = (1/L) Σ_k log p(w_k = present | e),

every occurrence counting (``the`` twice in "the … the …" counts twice). The originals' code started each
sentence's sum at 1 instead of 0, so every score printed in TCDS Table II, Fig. 7 and Fig. 8 is

    original:  score(s) = (1 + Σ_k log p(w_k = present | e)) / L

(docs/method.md §6.2). The ``+1/L`` favours short sentences and changes rankings. ``paper`` is glu's default;
``original`` reproduces the printed numbers. A word of probability 0 gives ``-inf`` under both.

**Candidates.** The originals ranked the 9,941 distinct sentences of 10,000 random draws from the grammar
(:func:`rank_sentences` ranks any such list, :mod:`glu.language.candidates` reads it); :func:`nbest`
searches the whole grammar.

**Exact N-best.** :func:`nbest` finds the N best of the *whole* grammar with a k-best dynamic programme
over the deterministic word network (:mod:`glu.language.sentences`): for every state and every number ``l``
of remaining words it keeps the ``n`` best suffixes of exactly ``l`` words (the mean divides by the length,
so lengths are kept apart until the end), which costs ``O(max length × arcs × n)`` instead of one score per
sentence. The network is deterministic, so the N best are N *different* sentences. Both scores work: within
one length the ``+1/L`` of the original score is a constant, so only the final comparison across lengths
changes.

**Exact ties.** Sums of log probabilities are computed exactly: every ``log p`` is a binary fraction, so
``log p × 2^K`` is an integer for a common ``K``, and sums of those integers have no rounding error.
Sentences are ranked by

1. the number of words of probability 0 (fewest first; all such sentences score ``-inf``),
2. the exact score computed from the other words (highest first),
3. the words themselves, in lexicographic order,

so equal scores (e.g. two orders of the same words) are ordered the same way every time, and the
reported score is the exact mean rounded once to a float.

Example
-------
On glu's synthetic data:

>>> from glu.bn import learn_bn, make_engine
>>> from glu.data import load_experiments
>>> eng = make_engine(learn_bn(load_experiments("synthetic")))
>>> best = describe(eng, {"Action": "grasp", "ObjVel": "slow"}, n=2)
>>> for row in best.itertuples():
...     print(f"{row.score:.4f}  {row.sentence}")
-0.4946  the robot is grasping the ball but the ball is still
-0.5003  the robot is grasping the ball but the ball is inert
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from functools import lru_cache
from typing import Any

import numpy as np
import pandas as pd

from glu.errors import EvidenceError, GrammarError, VocabularyError
from glu.language.candidates import SentenceSet
from glu.language.grammar import Grammar, load_grammar
from glu.language.sampling import sample_sentences
from glu.language.sentences import (
    Sentence,
    WordNetwork,
    as_network,
    as_sentence,
    count_sentences,
    restrict,
)
from glu.language.words import word_probabilities

WordProbs = Mapping[str, float] | pd.Series
"""P(word = present | evidence) by word: a mapping or a Series indexed by word."""
PROB_TOL = 1e-9
"""Probabilities within this of [0, 1] are clipped into it; further out they are an error."""
MAX_ALL_SCORES = 50_000_000
"""Most sentences :func:`all_scores` scores."""
NBEST_COLUMNS = ["rank", "sentence", "score", "length"]
SCORES: dict[str, int] = {"paper": 0, "original": 1}
"""Sentence scores by name → the constant ``c`` in ``(c + Σ_k log p(w_k)) / L``: ``paper`` is the papers'
formula, ``original`` what the originals' code computed and printed (docs/method.md §6.2)."""
DEFAULT_SCORE = "paper"
"""The score used unless another is asked for: the papers' formula."""


def score_offset(score: str) -> int:
    """The constant ``c`` of a score named in :data:`SCORES`; :class:`EvidenceError` for another name."""
    try:
        return SCORES[score]
    except (KeyError, TypeError):
        raise EvidenceError(f"unknown sentence score {score!r}; allowed: {', '.join(SCORES)}") from None


@lru_cache(maxsize=1)
def default_network() -> WordNetwork:
    """The word network of glu's default grammar (compiled once)."""
    from glu.language.sentences import compile_network

    return compile_network(load_grammar())


def word_network(grammar: Grammar | WordNetwork | None = None) -> WordNetwork:
    """The word network of ``grammar`` (a :class:`Grammar` or one already compiled); None: the default."""
    return default_network() if grammar is None else as_network(grammar)


# --------------------------------------------------------------------------------------- log probabilities
@dataclass(frozen=True)
class LogProbs:
    """Log word probabilities as exact integers: ``log p(w) = num[w] / scale`` exactly, or ``-inf``
    (``zero[w]``).

    Attributes
    ----------
    words : the words, in the order of the other fields
    logp : ``log p(w)`` as floats, shape (n_words,)
    num : the integer numerators (0 where ``p = 0``), length n_words
    zero : whether ``p(w) = 0``, length n_words
    scale : the common denominator, a power of two
    """

    words: tuple[str, ...]
    logp: np.ndarray
    num: tuple[int, ...]
    zero: tuple[bool, ...]
    scale: int

    @classmethod
    def from_probs(cls, words: Sequence[str], word_probs: WordProbs) -> LogProbs:
        """The log probabilities of ``words`` looked up in ``word_probs``; VocabularyError for a missing
        word."""
        probs = _as_mapping(word_probs)
        missing = [w for w in words if w not in probs]
        if missing:
            shown = ", ".join(missing[:10]) + (f", … ({len(missing)} words)" if len(missing) > 10 else "")
            raise VocabularyError(
                f"no probability for the word(s) {shown}: the grammar uses words the model does not "
                f"have (the model's words: {', '.join(list(probs)[:8])}, … {len(probs)} in all); words "
                "that are not network nodes score as probability 1 with word_probabilities(engine, …, "
                "vocabulary=grammar)"
            )
        logs = []
        for w in words:
            p = probs[w]
            try:
                p = float(p)
            except (TypeError, ValueError):
                raise EvidenceError(f"the probability of {w!r} is not a number: {p!r}") from None
            if not (-PROB_TOL <= p <= 1 + PROB_TOL):  # also catches nan
                raise EvidenceError(f"the probability of {w!r} is {p!r}, outside [0, 1]")
            p = min(max(p, 0.0), 1.0)
            logs.append(math.log(p) if p > 0 else -math.inf)
        ratios = [x.as_integer_ratio() if math.isfinite(x) else (0, 1) for x in logs]
        scale = max((d for _, d in ratios), default=1)
        num = tuple(n * (scale // d) for n, d in ratios)
        zero = tuple(not math.isfinite(x) for x in logs)
        return cls(tuple(words), np.array(logs, dtype=float), num, zero, scale)


def _as_mapping(word_probs: WordProbs) -> Mapping[str, Any]:
    if isinstance(word_probs, pd.Series):
        if word_probs.index.has_duplicates:
            dup = word_probs.index[word_probs.index.duplicated()][0]
            raise VocabularyError(f"the word probabilities give {dup!r} twice")
        return word_probs.to_dict()
    if isinstance(word_probs, Mapping):
        return word_probs
    raise TypeError(
        f"word probabilities must be a mapping word → p or a pandas Series, not {type(word_probs).__name__}"
    )


# ------------------------------------------------------------------------------------------------ scores
def _exact(lp: LogProbs, index: Sequence[int]) -> tuple[int, int]:
    """(number of zero-probability words, exact numerator of the sum of the others)."""
    return sum(lp.zero[i] for i in index), sum(lp.num[i] for i in index)


def _score(lp: LogProbs, n_zero: int, total: int, length: int, offset: int = 0) -> float:
    """The score, rounded once from its exact value ``(offset + total / scale) / length``."""
    return -math.inf if n_zero else float(Fraction(total + offset * lp.scale, lp.scale * length))


def _rank_key(
    n_zero: int, total: int, length: int, words: Sentence, offset: int = 0, scale: int = 1
) -> tuple:
    return (n_zero, Fraction(-(total + offset * scale), length), words)


def score_sentence(sentence: str | Iterable[str], word_probs: WordProbs, score: str = DEFAULT_SCORE) -> float:
    """The score of one sentence (a string or a sequence of words); -inf if a word has p = 0.

    ``score="paper"``: ``(1/L) Σ_k log p(w_k)`` over its L words; ``"original"``:
    ``(1 + Σ_k log p(w_k)) / L``.

    >>> round(score_sentence("the ball", {"the": 0.5, "ball": 0.25}), 6)
    -1.039721
    >>> round(score_sentence("the ball", {"the": 0.5, "ball": 0.25}, score="original"), 6)
    -0.539721
    """
    return float(score_sentences([sentence], word_probs, score)[0])


def score_sentences(
    sentences: Iterable[str | Iterable[str]], word_probs: WordProbs, score: str = DEFAULT_SCORE
) -> np.ndarray:
    """The score of each sentence (see :func:`score_sentence`), shape (n_sentences,)."""
    offset = score_offset(score)
    sents = [as_sentence(s) for s in sentences]
    if any(len(s) == 0 for s in sents):
        raise VocabularyError("an empty sentence has no score (the score is a mean over its words)")
    vocab = sorted({w for s in sents for w in s})
    lp = LogProbs.from_probs(vocab, word_probs)
    pos = {w: i for i, w in enumerate(vocab)}
    out = np.empty(len(sents))
    for k, s in enumerate(sents):
        n_zero, total = _exact(lp, [pos[w] for w in s])
        out[k] = _score(lp, n_zero, total, len(s), offset)
    return out


def _frame(rows: list[tuple[Sentence, float]]) -> pd.DataFrame:
    return pd.DataFrame(
        {
            "rank": np.arange(1, len(rows) + 1),
            "sentence": [" ".join(s) for s, _ in rows],
            "score": np.array([sc for _, sc in rows], dtype=float),
            "length": np.array([len(s) for s, _ in rows], dtype=int),
        },
        columns=NBEST_COLUMNS,
    )


def rank_sentences(
    sentences: SentenceSet | Iterable[str | Iterable[str]],
    word_probs: WordProbs,
    n: int | None = None,
    score: str = DEFAULT_SCORE,
    must_contain: Iterable[str] | None = None,
) -> pd.DataFrame:
    """The distinct ``sentences`` ranked by score (ties as in :func:`nbest`), the best ``n`` (all if None).

    This is how the originals described a situation: they ranked a fixed list of sentences (9,941 drawn at
    random from the grammar; :func:`glu.language.candidates.candidate_sentences`) with ``score="original"``.

    Parameters
    ----------
    sentences : the candidates, a :class:`~glu.language.candidates.SentenceSet` (prepared once for many
        calls) or any iterable of strings or sequences of words (duplicates count once)
    word_probs : P(word = present | evidence) for every word they use
    n : how many to return (all if None)
    score : a name of :data:`SCORES`
    must_contain : keep only the sentences with at least one of these words (e.g. the colour words)

    Returns
    -------
    DataFrame with columns rank (1 = best), sentence, score, length; one row per distinct sentence.

    Notes
    -----
    The ranking is exact (the key of the module docstring). Every sentence is scored in floating point
    with one matrix product; only the sentences whose float score could reach the ``n`` best — within 64
    times a bound of the rounding error — get the exact key, and the ``n`` best of those are the ``n``
    best of all.
    """
    offset = score_offset(score)
    cands = SentenceSet.of(sentences)
    keep = np.ones(len(cands), dtype=bool)
    if must_contain is not None:
        wanted = set(must_contain)
        cols = [k for k, w in enumerate(cands.vocabulary) if w in wanted]
        keep = cands.counts[:, cols].sum(axis=1) > 0
    rows = np.flatnonzero(keep)
    if (cands.lengths[rows] == 0).any():
        raise VocabularyError("an empty sentence has no score (the score is a mean over its words)")
    used = np.flatnonzero(cands.counts[rows].sum(axis=0) > 0)
    lp = LogProbs.from_probs([cands.vocabulary[k] for k in used], word_probs)
    counts = cands.counts[np.ix_(rows, used)]
    shortlist = rows
    if n is not None and n < len(rows):
        finite = np.where(lp.zero, 0.0, lp.logp)
        n_zero = counts @ np.asarray(lp.zero, dtype=float)
        length = cands.lengths[rows]
        mean = (offset + counts @ finite) / length
        # a bound on |float − exact| of every mean (a product summed over the vocabulary, then one division),
        # with room to spare; the same bound for all, so that the n sentences ahead of `last` in float order
        # are exactly better than any sentence more than 2·err below it
        err = (
            64
            * np.finfo(float).eps
            * (counts.shape[1] + 2)
            * float(np.max((abs(offset) + counts @ np.abs(finite)) / length))
        )
        order = np.lexsort((-mean, n_zero))
        last = order[n - 1]  # the n-th best float key
        reach = (n_zero < n_zero[last]) | ((n_zero == n_zero[last]) & (mean + err >= mean[last] - err))
        shortlist = rows[reach]
    pos = {w: i for i, w in enumerate(lp.words)}
    keyed = []
    for r in shortlist:
        s = cands.sentences[r]
        n_zero_s, total = _exact(lp, [pos[w] for w in s])
        keyed.append(
            (
                _rank_key(n_zero_s, total, len(s), s, offset, lp.scale),
                _score(lp, n_zero_s, total, len(s), offset),
            )
        )
    best = heapq.nsmallest(n, keyed) if n is not None else sorted(keyed)
    return _frame([(k[2], sc) for k, sc in best])


# ------------------------------------------------------------------------------------------------ N-best
def nbest(
    grammar: Grammar | WordNetwork | None,
    word_probs: WordProbs,
    n: int = 10,
    max_length: int | None = None,
    must_contain: Iterable[str] | None = None,
    exclude: Iterable[str] | None = None,
    score: str = DEFAULT_SCORE,
) -> pd.DataFrame:
    """The exact ``n`` best sentences of the grammar under a sentence score (:data:`SCORES`).

    Parameters
    ----------
    grammar : a Grammar, its compiled WordNetwork (faster when reused), or None for glu's default grammar
    word_probs : P(word = present | evidence) for every word of the grammar (e.g. :func:`word_probabilities`)
    n : how many sentences (fewer if the grammar has fewer)
    max_length : only sentences of at most this many words (required when the grammar is infinite)
    must_contain : only sentences with at least one of these words (e.g. the colour words)
    exclude : only sentences with none of these words
    score : a name of :data:`SCORES`

    Returns
    -------
    DataFrame with columns rank (1 = best), sentence (words separated by spaces), score (float; -inf with
    a zero-probability word), length (words); at most ``n`` rows, best first.
    """
    offset = score_offset(score)
    if int(n) != n or n < 1:
        raise EvidenceError(f"the number of sentences must be a whole number ≥ 1, not {n!r}")
    n = int(n)
    net = word_network(grammar)
    if must_contain is not None or exclude is not None:
        must = None if must_contain is None else list(must_contain)
        unknown = sorted(set(must or ()) - set(net.words))
        if unknown:
            raise VocabularyError(
                f"the grammar has no word(s) {', '.join(unknown)}; its words: {', '.join(net.words)}"
            )
        net = restrict(net, must, exclude)
    limit = net.check_length_limit(max_length)
    lp = LogProbs.from_probs(net.words, word_probs)
    zero, num, words = lp.zero, lp.num, net.words
    # cells[s]: the n best suffixes of exactly l words from state s, as (n_zero, -sum, words), best first
    cells: list[list[tuple[int, int, Sentence]]] = [[(0, 0, ())] if f else [] for f in net.final]
    candidates: list[tuple[tuple, float]] = []
    for length in range(1, limit + 1):
        new_cells = []
        for arcs in net.arcs:
            merged = [
                (z + zero[w], neg - num[w], (words[w], *ws)) for w, t in arcs for z, neg, ws in cells[t]
            ]
            new_cells.append(heapq.nsmallest(n, merged) if len(merged) > n else sorted(merged))
        cells = new_cells
        for z, neg, ws in cells[net.start]:  # within one length the +offset/L is a constant
            candidates.append(
                (_rank_key(z, -neg, length, ws, offset, lp.scale), _score(lp, z, -neg, length, offset))
            )
        if not any(cells):
            break
    best = heapq.nsmallest(n, candidates)
    return _frame([(k[2], sc) for k, sc in best])


def sample_nbest(
    grammar: Grammar | None,
    word_probs: WordProbs,
    n: int = 10,
    n_samples: int = 10_000,
    seed: int | None = 0,
    score: str = DEFAULT_SCORE,
) -> pd.DataFrame:
    """The originals' method: the ``n`` best distinct sentences among ``n_samples`` random ones (HSGen-like,
    seeded).

    Returns
    -------
    DataFrame with columns rank, sentence, score, length (as :func:`nbest`).
    """
    g = load_grammar() if grammar is None else grammar
    if not isinstance(g, Grammar):
        raise TypeError("random sampling walks the grammar itself: pass a Grammar, not a WordNetwork")
    return rank_sentences(sample_sentences(g, n_samples, seed), word_probs, n, score)


def all_scores(
    grammar: Grammar | WordNetwork | None, word_probs: WordProbs, score: str = DEFAULT_SCORE
) -> np.ndarray:
    """The score of every sentence of a finite grammar, vectorised, in no particular order; shape
    (n_sentences,).

    Sums are ordinary floating-point sums (not the exact ones of :func:`nbest`); use it for distributions
    and ranks, up to :data:`MAX_ALL_SCORES` sentences.
    """
    offset = score_offset(score)
    net = word_network(grammar)
    total = count_sentences(net)
    if total > MAX_ALL_SCORES:
        raise GrammarError(
            f"the grammar has {total} sentences; all_scores handles up to {MAX_ALL_SCORES}", net.source
        )
    lp = LogProbs.from_probs(net.words, word_probs)
    order = net.topological_order
    assert order is not None  # count_sentences raised for an infinite grammar
    # per state, length → sums of log p over every suffix of that many words; a state's arrays are freed
    # when its last predecessor is done, and the start state writes the means straight into the output
    n_preds = [0] * net.n_states
    for arcs in net.arcs:
        for _, t in arcs:
            n_preds[t] += 1
    suffix: dict[int, dict[int, np.ndarray]] = {}
    out = np.empty(total - (1 if net.final[net.start] else 0))
    for s in reversed(order):
        if s == net.start:
            k = 0
            for w, t in net.arcs[s]:
                for length, sums in suffix[t].items():
                    chunk = out[k : k + len(sums)]
                    np.add(sums, lp.logp[w] + offset, out=chunk)
                    chunk /= length + 1
                    k += len(sums)
            break
        parts: dict[int, list[np.ndarray]] = {0: [np.zeros(1)]} if net.final[s] else {}
        for w, t in net.arcs[s]:
            for length, sums in suffix[t].items():
                parts.setdefault(length + 1, []).append(sums + lp.logp[w])
            n_preds[t] -= 1
            if n_preds[t] == 0:
                del suffix[t]
        suffix[s] = {length: np.concatenate(p) for length, p in parts.items()}
    return out


def describe(
    engine: Any,
    evidence: Mapping[str, str | int] | None = None,
    soft: Mapping[str, Any] | None = None,
    soft_rule: str = "virtual",
    n: int = 10,
    grammar: Grammar | WordNetwork | None = None,
    must_contain: Iterable[str] | None = None,
    score: str = DEFAULT_SCORE,
    candidates: Iterable[str | Iterable[str]] | None = None,
) -> pd.DataFrame:
    """The ``n`` best descriptions given evidence, from :func:`word_probabilities`.

    With ``candidates=None`` the exact :func:`nbest` over the whole grammar; with a list of sentences
    (e.g. the originals' 9,941 samples) :func:`rank_sentences` over that list. ``score`` names one of
    :data:`SCORES`. Words of the grammar (or of the candidates) that are not network nodes score as
    probability 1 (:mod:`glu.language.words`); they are listed in the result's ``attrs["not_in_network"]``.

    Returns
    -------
    DataFrame with columns rank, sentence, score, length (see :func:`nbest`).
    """
    if isinstance(candidates, SentenceSet):
        vocabulary: Any = candidates.vocabulary
    elif candidates is not None:
        candidates = [as_sentence(c) for c in candidates]
        vocabulary = [w for c in candidates for w in c]
    else:
        vocabulary = word_network(grammar)
    probs = word_probabilities(engine, evidence, soft, soft_rule, vocabulary=vocabulary)
    if candidates is not None:
        out = rank_sentences(candidates, probs, n, score, must_contain)
    else:
        out = nbest(grammar, probs, n, must_contain=must_contain, score=score)
    out.attrs["not_in_network"] = probs.attrs["not_in_network"]
    return out
