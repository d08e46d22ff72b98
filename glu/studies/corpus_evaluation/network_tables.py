"""The network's answers the corpus evaluation needs, for every combination of observed values, queried once.

An episode's evidence (the object, the effect) takes one of a few dozen combinations of values; the
evaluation looks each episode's answer up in these tables instead of querying the network per episode.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from itertools import product
from typing import NamedTuple

import numpy as np

from glu.bn.inference import Engine
from glu.errors import ImpossibleEvidenceError

EFFECT = "ObjVel"


class NetworkTables(NamedTuple):
    """The network's answers for every combination of observed values (queried once, used per episode).

    Attributes
    ----------
    nodes : the observed nodes, in order; an episode's combination is ``ravel_multi_index`` of its codes
    p_action : array, shape (C, K) — ``p_BN(A | X_obs)``
    p_given_action : array, shape (C, K, V) — ``p_BN(X | X_obs, A = a)`` of the target(s) (NaN rows for
        combinations of probability 0)
    """

    nodes: tuple[str, ...]
    p_action: np.ndarray
    p_given_action: np.ndarray

    def combo(self, codes: Mapping[str, np.ndarray], shape: Sequence[int]) -> np.ndarray:
        """The combination index of each episode, shape (n,)."""
        if not self.nodes:
            return np.zeros(len(next(iter(codes.values()))), dtype=np.intp)
        return np.ravel_multi_index(tuple(codes[n] for n in self.nodes), tuple(shape))


def network_tables(engine: Engine, nodes: Sequence[str], target: str) -> NetworkTables:
    """:class:`NetworkTables` for observed ``nodes``; ``target`` is a node (e.g. ObjVel) or ``"words"``."""
    schema = engine.bn.schema
    values = [schema.values_of(n) for n in nodes]
    actions = schema.values_of("Action")
    n_out = len(engine.binary_leaves) if target == "words" else schema.cardinality(target)
    combos = list(product(*values))
    p_a = np.full((len(combos), len(actions)), np.nan)
    p_x = np.full((len(combos), len(actions), n_out), np.nan)
    for c, vals in enumerate(combos):
        ev = dict(zip(nodes, vals, strict=True))
        try:
            p_a[c] = engine.query(["Action"], ev)["Action"]
        except ImpossibleEvidenceError:
            continue
        for k, a in enumerate(actions):
            full = {**ev, "Action": a}
            try:
                p_x[c, k] = (
                    engine.word_probability_array(full)
                    if target == "words"
                    else engine.query([target], full)[target]
                )
            except ImpossibleEvidenceError:
                p_x[c, k] = 0.0  # this action is impossible here: p_a is 0 for it, so the row is never used
    return NetworkTables(tuple(nodes), p_a, p_x)
