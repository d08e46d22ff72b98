"""The junction tree engine's arithmetic: exact inference in any discrete network, over rows of evidence.

:class:`JunctionBackend` answers the array queries of :class:`~glu.bn.inference.Engine` (made by
:func:`~glu.bn.inference.make_engine`) for any network. Nothing is planned when the engine is made; each
*evidence pattern* (which nodes carry hard evidence, which soft evidence, which are asked for) gets its own
:class:`~glu.bn.propagation.PatternPlan`, made on first use from the tables the query needs (relevance,
:mod:`glu.bn.relevance`) with the observed nodes conditioned out, and kept (:data:`PLAN_CACHE`). A plan
keeps the tables and messages of its last single query, so the next one recomputes only what the changed
evidence reaches (:func:`~glu.bn.propagation.propagate`).

The size of a plan's largest table is known before any table is built; past a limit (``max_table``,
``$GLU_MAX_TABLE``) the query is refused in one line with that size and the elimination width.

>>> from glu.bn import make_engine
>>> from glu.bn.exchange import from_bif
>>> bn = from_bif('''
... variable Rain { type discrete [ 2 ] { no, yes }; }
... variable Sprinkler { type discrete [ 2 ] { off, on }; }
... variable Wet { type discrete [ 2 ] { dry, wet }; }
... probability ( Rain ) { table 0.8, 0.2; }
... probability ( Sprinkler | Rain ) { (no) 0.6, 0.4; (yes) 0.99, 0.01; }
... probability ( Wet | Rain, Sprinkler ) { (no, off) 1.0, 0.0; (no, on) 0.1, 0.9;
...                                         (yes, off) 0.2, 0.8; (yes, on) 0.01, 0.99; }
... ''')
>>> eng = make_engine(bn, method="junction")
>>> eng.posterior("Rain", {"Wet": "wet"}).round(4).to_dict()  # 0.2·(0.99·0.8 + 0.01·0.99) / 0.44838
{'no': 0.6423, 'yes': 0.3577}
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Collection, Mapping, Sequence
from typing import Any

import numpy as np

from glu.bn.network import NetworkArrays, code_of
from glu.bn.plan import JunctionTreePlan, plan_from_scopes
from glu.bn.propagation import PatternPlan, make_plan, propagate

PLAN_CACHE = 64
"""Plans kept per engine (one per evidence pattern), the most recently used …"""
PLAN_CACHE_ENTRIES = 1 << 25
"""… as long as their tables hold at most this many entries together (256 MiB)."""


class JunctionBackend:
    """Exact marginals of any discrete network on junction trees planned per evidence pattern.

    Parameters
    ----------
    net : the network's arrays
    max_table : the largest clique table a plan may have (entries); None: ``$GLU_MAX_TABLE`` or the default
        of :mod:`glu.bn.plan`
    """

    method = "junction"

    def __init__(self, net: NetworkArrays, max_table: int | None = None) -> None:
        self.net = net
        self.max_table = max_table
        self._plans: OrderedDict[tuple, PatternPlan] = OrderedDict()
        self._tree: JunctionTreePlan | None = None

    def __getstate__(self) -> dict[str, Any]:
        return {**self.__dict__, "_plans": OrderedDict()}  # plans are remade on first use

    def plan(
        self, tables: Collection[int], observed: Sequence[int], soft: Sequence[int], targets: Sequence[int]
    ) -> PatternPlan:
        """The plan of a pattern (variable indices; ``tables``: the nodes whose tables it needs), cached."""
        key = (tuple(observed), tuple(soft), tuple(targets), len(tables))
        plan = self._plans.get(key)
        if plan is not None:
            self._plans.move_to_end(key)
            return plan
        plan = make_plan(self.net, sorted(tables), observed, soft, targets, self.max_table)
        self._plans[key] = plan
        while len(self._plans) > 1 and (
            len(self._plans) > PLAN_CACHE or sum(p.size for p in self._plans.values()) > PLAN_CACHE_ENTRIES
        ):
            self._plans.popitem(last=False)
        return plan

    def size(
        self, tables: Collection[int], observed: Sequence[int], soft: Sequence[int], targets: Sequence[int]
    ) -> int:
        """Table entries one row of this pattern costs (to cut a batch into chunks)."""
        return self.plan(tables, observed, soft, targets).size

    def solve(
        self,
        targets: Sequence[int],
        hard: Mapping[int, np.ndarray],
        likelihood: Mapping[int, np.ndarray],
        rows: int,
        tables: Collection[int],
    ) -> tuple[dict[int, np.ndarray], np.ndarray]:
        """:meth:`glu.bn.core.CoreBackend.solve`'s answer (the same arguments and shapes), propagated in the
        pattern's plan (``tables``: the nodes whose tables it needs; keys of ``hard`` and ``likelihood`` come
        sorted)."""
        plan = self.plan(tables, tuple(hard), tuple(likelihood), targets)
        codes = list(hard.values())
        liks = list(likelihood.values())
        signature = None
        if rows == 1:
            signature = (*map(code_of, codes), *(q.tobytes() for q in liks))
        out, possible, _ = propagate(plan, codes, liks, rows, signature)
        return out, possible

    def log_mass(self, hard: Mapping[int, np.ndarray], rows: int) -> np.ndarray:
        """log P(hard evidence, every all-zero row avoided), shape (rows,) (-inf: probability 0)."""
        net = self.net
        tables = net.ancestors(set(hard) | net.inexact)
        if not tables:
            return np.zeros(rows)
        plan = self.plan(tables, tuple(hard), (), ())
        codes = list(hard.values())
        signature = tuple(map(code_of, codes)) if rows == 1 else None
        _, _, log_mass = propagate(plan, codes, [], rows, signature, mass=True)
        assert log_mass is not None
        return np.broadcast_to(log_mass, (rows,))

    def junction_tree(self) -> JunctionTreePlan:
        """The junction tree of the whole network (no evidence), planned on first use."""
        if self._tree is None:
            every = range(len(self.net.cards))
            families = [self.net.family(v) for v in every]
            self._tree = plan_from_scopes(self.net.cards, families, every, self.max_table)
        return self._tree
