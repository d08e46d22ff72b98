"""The best description for many evidence sets at once, and what its words say about the scene.

:func:`best_sentences` finds, for each row of a matrix of word probabilities, the sentence of the grammar
with the highest score ``(1/L) Σ_k log p(w_k)`` (the score of :mod:`glu.language.descriptions`), with one
dynamic programme over the word network vectorised over the rows: for every number of words ``l`` and
state ``s``, the best suffix of exactly ``l`` words from ``s`` is the best arc plus the best suffix of
``l − 1`` words from where it leads, for all rows at once. It equals :func:`~glu.language.descriptions.nbest`
with ``n = 1`` (tested), except that

* sums are ordinary floating-point sums, so between sentences of exactly equal score (the same words in
  another order) it may pick another one than ``nbest``'s lexicographic tie-break;
* a word of probability 0 counts as ``log p = −10⁶`` instead of ranking the sentence after all others;
  this changes nothing unless every sentence has such a word.

:data:`WORD_MEANING` says which words name which action, object feature and effect, and
:func:`agreement` checks a sentence against the scene it should describe.

Example
-------
>>> import numpy as np
>>> from glu.language.descriptions import default_network
>>> words = default_network().words
>>> rng = np.random.default_rng(0)
>>> best = best_sentences(rng.uniform(0.01, 0.99, size=(2, len(words))), words)
>>> best.index.shape[0], best.length.tolist() == [len(best.sentence(i).split()) for i in range(2)]
(2, True)
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from glu.errors import VocabularyError
from glu.language.descriptions import PROB_TOL, word_network
from glu.language.grammar import Grammar
from glu.language.sentences import WordNetwork
from glu.schema import ACTION_VERBS

LOG_ZERO = -1e6
"""``log p`` used for a word of probability 0."""

WORD_MEANING: dict[str, tuple[str, tuple[str, ...]]] = {
    **{w: ("Action", (action,)) for action, verbs in ACTION_VERBS.items() for w in verbs},
    **{w: ("Shape", ("sphere",)) for w in ("sphere", "ball")},
    **{w: ("Shape", ("box",)) for w in ("box", "square", "cube")},
    "big": ("Size", ("big",)),
    "small": ("Size", ("small",)),
    "green": ("Color", ("green1", "green2")),
    "yellow": ("Color", ("yellow",)),
    "blue": ("Color", ("blue",)),
    **{w: ("ObjVel", ("slow",)) for w in ("still", "inert")},
    **{
        w: ("ObjVel", ("medium", "fast"))
        for w in (
            "moves",
            "moving",
            "rolls",
            "rolling",
            "slides",
            "sliding",
            "rises",
            "rising",
            "falls",
            "falling",
        )
    },
}
"""Word → (node, the values it names): the verbs name the action (tap and push words: tap; touch and poke
words: touch, as in the data), nouns the shape, adjectives the size and colour (green: either green), the
effect phrases whether the object stayed still (ObjVel slow) or moved (medium or fast)."""
ASPECTS: dict[str, tuple[str, ...]] = {
    "verb": ("Action",),
    "object": ("Shape", "Size", "Color"),
    "effect": ("ObjVel",),
}
"""What a description must get right: its verb the action, its object words the object, its effect phrase
the object's motion."""


@dataclass(frozen=True, eq=False)
class BestSentences:
    """The best sentence of each row.

    Attributes
    ----------
    words : the network's vocabulary (``index`` refers to it)
    index : int array, shape (n_rows, max length) — the words of each sentence, −1 after its end
    length : int array, shape (n_rows,)
    score : array, shape (n_rows,) — the mean log probability
    """

    words: tuple[str, ...]
    index: np.ndarray
    length: np.ndarray
    score: np.ndarray

    def sentence(self, i: int) -> str:
        """Row ``i``'s sentence, words separated by spaces."""
        return " ".join(self.words[w] for w in self.index[i, : self.length[i]])


def best_sentences(
    word_probs: np.ndarray, columns: Sequence[str], grammar: Grammar | WordNetwork | None = None
) -> BestSentences:
    """The highest-scoring sentence of the grammar for each row of word probabilities.

    Parameters
    ----------
    word_probs : array, shape (n_rows, n_columns) — ``P(word = present | evidence)``
    columns : the word of each column (every word of the grammar must be among them)
    grammar : a Grammar, its WordNetwork, or None for glu's default grammar (must be finite)
    """
    net = word_network(grammar)
    probs = np.asarray(word_probs, dtype=float)
    if probs.ndim != 2 or probs.shape[1] != len(columns):
        raise VocabularyError(
            f"word probabilities must have shape (n_rows, {len(columns)}), got {probs.shape}"
        )
    pos = {w: i for i, w in enumerate(columns)}
    missing = [w for w in net.words if w not in pos]
    if missing:
        raise VocabularyError(f"no probability for the grammar's word(s) {', '.join(missing[:10])}")
    if (probs < -PROB_TOL).any() or (probs > 1 + PROB_TOL).any() or np.isnan(probs).any():
        raise VocabularyError("word probabilities must be in [0, 1]")
    p = np.clip(probs[:, [pos[w] for w in net.words]], 0.0, 1.0)
    with np.errstate(divide="ignore"):
        logp = np.where(p > 0, np.log(p), LOG_ZERO)  # (n, V) in the network's word order
    logp = np.ascontiguousarray(logp.T)  # (V, n): every gather below copies whole rows
    n, limit = logp.shape[1], net.check_length_limit(None)
    n_arcs = max((len(a) for a in net.arcs), default=0)
    arc_word = np.full((net.n_states, max(n_arcs, 1)), -1)
    arc_next = np.zeros_like(arc_word)
    for s, arcs in enumerate(net.arcs):
        for k, (w, t) in enumerate(arcs):
            arc_word[s, k], arc_next[s, k] = w, t
    feasible = _feasible_lengths(net, limit)  # (limit + 1, n_states): some suffix of exactly l words
    best = np.full((net.n_states, n), -np.inf)
    best[np.array(net.final)] = 0.0  # l = 0
    back = np.zeros((limit + 1, net.n_states, n), dtype=np.int16)
    score = np.full(n, -np.inf)
    length = np.zeros(n, dtype=np.intp)
    for n_words in range(1, limit + 1):
        new = np.full((net.n_states, n), -np.inf)
        for s, arcs in enumerate(net.arcs):
            if not feasible[n_words, s]:
                continue
            k = [j for j, (_, t) in enumerate(arcs) if feasible[n_words - 1, t]]
            cand = logp[arc_word[s, k]] + best[arc_next[s, k]]  # (k, n)
            if len(k) == 1:
                back[n_words, s] = k[0]
                new[s] = cand[0]
            else:
                j = np.argmax(cand, axis=0)
                back[n_words, s] = np.asarray(k)[j]
                new[s] = np.take_along_axis(cand, j[None], axis=0)[0]
        best = new
        if feasible[n_words, net.start]:
            mean = best[net.start] / n_words
            better = mean > score
            score = np.where(better, mean, score)
            length = np.where(better, n_words, length)
    index = np.full((n, limit), -1)
    state = np.full(n, net.start)
    rows = np.arange(n)
    for step in range(limit):
        left = length - step
        on = left > 0
        if not on.any():
            break
        j = back[np.where(on, left, 0), state, rows]
        index[on, step] = arc_word[state[on], j[on]]
        state = np.where(on, arc_next[state, j], state)
    return BestSentences(net.words, index[:, : max(int(length.max(initial=0)), 1)], length, score)


def _feasible_lengths(net: WordNetwork, limit: int) -> np.ndarray:
    """``f[k, s]``: state s has a path of exactly k words to a final state; shape (limit + 1, n_states)."""
    f = np.zeros((limit + 1, net.n_states), dtype=bool)
    f[0] = net.final
    for k in range(1, limit + 1):
        for s, arcs in enumerate(net.arcs):
            f[k, s] = any(f[k - 1, t] for _, t in arcs)
    return f


def agreement(
    best: BestSentences, truth: Mapping[str, np.ndarray], values: Mapping[str, Sequence[str]]
) -> dict[str, np.ndarray]:
    """Does each sentence describe its scene? Per :data:`ASPECTS` and overall.

    Parameters
    ----------
    best : the sentences, n rows
    truth : node → int array, shape (n,), the scene's value indices (Action, Shape, Size, Color, ObjVel)
    values : node → its values, in index order

    Returns
    -------
    dict aspect → bool array, shape (n,): ``verb``, ``object``, ``effect`` (every word of the sentence
    that names a node of the aspect names the true value, and the sentence has at least one such word
    for the verb, the object's shape and the effect), and ``all``.
    """
    n = len(best.index)
    vocab = best.words
    # per word of the vocabulary and node: does the word name the true value? (n_nodes, V, n_values)
    ok_all = {}
    named_any: dict[str, np.ndarray] = {}
    wrong_any: dict[str, np.ndarray] = {}
    present = best.index >= 0
    for node in {node for nodes in ASPECTS.values() for node in nodes}:
        vals = list(values[node])
        table = np.zeros((len(vocab) + 1, len(vals)), dtype=bool)  # last row: padding (−1)
        names = np.zeros(len(vocab) + 1, dtype=bool)
        for i, w in enumerate(vocab):
            meaning = WORD_MEANING.get(w)
            if meaning and meaning[0] == node:
                names[i] = True
                table[i, [vals.index(v) for v in meaning[1]]] = True
        idx = np.where(present, best.index, len(vocab))
        t = np.asarray(truth[node])
        names_w = names[idx]
        right_w = table[idx, t[:, None]]
        named_any[node] = names_w.any(axis=1)
        wrong_any[node] = (names_w & ~right_w).any(axis=1)
    for aspect, nodes in ASPECTS.items():
        must = nodes[0]  # the verb, the shape noun, the effect phrase must be there
        ok = named_any[must].copy()
        for node in nodes:
            ok &= ~wrong_any[node]
        ok_all[aspect] = ok
    ok_all["all"] = np.logical_and.reduce([ok_all[a] for a in ASPECTS]) if n else np.zeros(0, dtype=bool)
    return ok_all
