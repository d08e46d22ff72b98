"""The word probabilities sentences are scored with: the network's word nodes, and the grammar's other words.

The network gives ``P(word = present | evidence)`` for each of its word nodes. A grammar may also use
words that are not nodes — function words such as "the", "it", "and", which a lab has no reason to learn
as nodes of its network. Such a word **scores as probability 1** (``log p = 0``):

* it carries no evidence about the scene, so it should not move the sentence's log probability; a factor
  of 1 in ``Π p(w)`` is exactly that — the score of a sentence is ``(1/L) log Π_{w in the network} p(w)``;
* it is what GLU's own network gives a word that is in every description: "the" is one of GLU's 49 word
  nodes and has ``p(the | e) = 1`` on its data, so a lab that leaves such words out of its network gets
  the scores it would have had by learning them from descriptions that always contain them;
* it keeps the mean over all ``L`` words of the sentence and the exact N-best search unchanged.

The consequence to keep in mind: the mean divides by every word, so between two sentences whose network
words score the same, the one with more function words scores closer to 0. The grammar decides where
function words go, so this compares the grammar's sentence templates, not words.

:func:`word_probabilities` adds the grammar's other words (``vocabulary``) with probability 1 and lists
them in ``attrs["not_in_network"]``; ``glu describe`` prints them, so a misspelt word is seen, not scored.
A grammar that shares no word with the network is refused.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np
import pandas as pd

from glu.errors import VocabularyError
from glu.language.grammar import Grammar
from glu.language.sentences import WordNetwork, as_network

NOT_IN_NETWORK_PROBABILITY = 1.0
"""The probability a word that is not a network node scores with (see the module docstring)."""


def word_probabilities(
    engine: Any,
    evidence: Mapping[str, str | int] | None = None,
    soft: Mapping[str, Any] | None = None,
    soft_rule: str = "virtual",
    vocabulary: Grammar | WordNetwork | Iterable[str] | None = None,
) -> pd.Series:
    """P(word = present | evidence) from an :class:`~glu.bn.Engine`: a Series indexed by word.

    Parameters
    ----------
    engine : the network's inference engine (its word nodes: ``engine.binary_leaves``)
    evidence, soft, soft_rule : as :meth:`~glu.bn.Engine.query`; a gesture posterior ``p_hmm``
        enters as ``soft={action node: p_hmm}`` (fusion, docs/method.md §2.2)
    vocabulary : the grammar (or its words) the sentences come from: its words that are not network
        nodes are added with probability :data:`NOT_IN_NETWORK_PROBABILITY` and listed in
        ``attrs["not_in_network"]``

    Returns
    -------
    Series, shape (n_words,): the network's words in node order, then the vocabulary's other words.

    Raises
    ------
    VocabularyError
        a vocabulary that shares no word with the network (nothing to score)
    """
    probs = engine.word_probability_array(evidence, soft or None, soft_rule)
    out = pd.Series(
        np.asarray(probs, dtype=float), index=list(engine.binary_leaves), name="p(word | evidence)"
    )
    if vocabulary is None:
        return out
    # the distinct words of the grammar, its network, or the iterable of words, in first-seen order
    words = list(
        as_network(vocabulary).words
        if isinstance(vocabulary, Grammar | WordNetwork)
        else dict.fromkeys(vocabulary)
    )
    known = set(out.index)
    extra = [w for w in words if w not in known]
    if words and len(extra) == len(words):
        shown = ", ".join(extra[:8]) + (" …" if len(extra) > 8 else "")
        raise VocabularyError(
            f"the grammar and the network share no word (the grammar's: {shown}; the network's: "
            f"{', '.join(list(out.index)[:8])}{' …' if len(out) > 8 else ''}): nothing to score"
        )
    if extra:
        out = pd.concat([out, pd.Series(NOT_IN_NETWORK_PROBABILITY, index=extra)]).rename(
            "p(word | evidence)"
        )
    out.attrs["not_in_network"] = extra
    return out
