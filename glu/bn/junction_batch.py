"""Batches of evidence sets for the junction tree engine: grouped by pattern, deduplicated, in chunks.

:class:`JunctionBatch` is the part of :class:`~glu.bn.junction.JunctionTreeEngine` that answers
:meth:`~glu.bn.inference.InferenceEngine.query_batch`: it parses the columns, answers rows with the same
hard evidence once, sends each evidence pattern shared by at least ``condition_rows`` rows to a plan
conditioned on it (:mod:`glu.bn.conditioned`) and the other rows together to the network's junction tree,
in chunks of rows whose tables fit in :data:`BATCH_ENTRIES` entries. Tested against single queries,
pgmpy and pyAgrum.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Literal

import numpy as np

from glu.bn.batch import _batch_length
from glu.bn.soft import SoftRule, check_soft_rule

if TYPE_CHECKING:  # pragma: no cover
    from glu.bn.propagation import QueryPlan

BATCH_ENTRIES = 1 << 22
"""A batch is answered in chunks of rows whose tables hold at most this many entries together (32 MiB)."""


class JunctionBatch:
    """Batch queries of the junction tree engine (mixed into :class:`~glu.bn.junction.JunctionTreeEngine`)."""

    cards: tuple[int, ...]
    index: dict[str, int]
    condition_rows: int
    deduplicate: bool = True
    """Answer rows with the same hard evidence once (benchmarks turn it off to time every row)."""

    def plan(self, evidence: frozenset[int], targets: frozenset[int]) -> QueryPlan:  # pragma: no cover
        raise NotImplementedError

    def conditioned(self, observed, soft, targets):  # type: ignore[no-untyped-def]  # pragma: no cover
        raise NotImplementedError

    def _solve(self, targets, hard, soft, rule, rows):  # type: ignore[no-untyped-def]  # pragma: no cover
        raise NotImplementedError

    def _groups(
        self, hard: Mapping[int, np.ndarray], has_soft: bool, n: int
    ) -> list[tuple[np.ndarray, tuple[int, ...]]]:
        """(rows, observed variables): the rows of each pattern with at least :attr:`condition_rows` rows,
        then all other rows together (with every variable observed in any of them)."""
        if not hard or n < self.condition_rows:
            return [(np.arange(n), tuple(hard))]
        vs = tuple(hard)
        observed = np.stack([hard[v] >= 0 for v in vs], axis=1)
        patterns, inverse = np.unique(observed, axis=0, return_inverse=True)
        inverse = inverse.ravel()
        groups, rest = [], []
        for k, pattern in enumerate(patterns):
            rows = np.flatnonzero(inverse == k)
            if len(rows) >= self.condition_rows and pattern.any():
                groups.append((rows, tuple(v for v, on in zip(vs, pattern, strict=True) if on)))
            else:
                rest.append(rows)
        if rest:
            groups.append((np.sort(np.concatenate(rest)), vs))
        return groups

    def _solve_chunked(
        self,
        targets: frozenset[int],
        hard: Mapping[int, np.ndarray],
        soft: Mapping[int, np.ndarray],
        rule: str,
        rows: int,
    ) -> tuple[dict[int, np.ndarray], np.ndarray, np.ndarray]:
        """:meth:`_solve` on chunks of rows (at most :data:`BATCH_ENTRIES` table entries at a time); rows with
        the same hard evidence and no soft evidence are answered once."""
        if self.deduplicate and hard and not soft and rows > 1:
            codes = np.stack([hard[v] for v in hard], axis=1)
            uniq, inverse = np.unique(codes, axis=0, return_inverse=True)
            if len(uniq) < rows:
                res, ok, hp = self._solve_chunked(
                    targets, {v: uniq[:, i] for i, v in enumerate(hard)}, {}, rule, len(uniq)
                )
                inverse = inverse.ravel()
                return {v: m[inverse] for v, m in res.items()}, ok[inverse], hp[inverse]
        plan = None
        if rows >= self.condition_rows and hard and all(bool((c >= 0).all()) for c in hard.values()):
            cp = self.conditioned(frozenset(hard), frozenset(soft), targets)  # what _solve will use
            plan = cp.plan if cp is not None else None
        if plan is None:
            plan = self.plan(frozenset(hard) | frozenset(soft), targets)
        step = max(1, BATCH_ENTRIES // max(plan.size, 1))
        if plan is not self.plan(frozenset(hard) | frozenset(soft), targets):  # conditioned: keep it so
            step = max(step, self.condition_rows)
        if rows <= step:
            return self._solve(targets, hard, soft, rule, rows)
        out: dict[int, np.ndarray] = {v: np.empty((rows, self.cards[v])) for v in targets}
        ok, hp = np.empty(rows, dtype=bool), np.empty(rows, dtype=bool)
        for a in range(0, rows, step):
            b = min(rows, a + step)
            res, ok[a:b], hp[a:b] = self._solve(
                targets,
                {v: c[a:b] for v, c in hard.items()},
                {v: q[a:b] for v, q in soft.items()},
                rule,
                b - a,
            )
            for v in targets:
                out[v][a:b] = res[v]
        return out, ok, hp

    def query_batch(
        self,
        targets: Sequence[str] | str,
        evidence: Mapping[str, Sequence] | None = None,
        soft: Mapping[str, np.ndarray] | None = None,
        soft_rule: SoftRule = "virtual",
        errors: Literal["raise", "nan"] = "raise",
    ) -> dict[str, np.ndarray]:
        """See :meth:`InferenceEngine.query_batch <glu.bn.inference.InferenceEngine.query_batch>`.

        Rows with the same hard evidence (and no soft evidence) are answered once. Rows that share a
        pattern of observed nodes, at least :attr:`condition_rows` of them, are answered on the network
        conditioned on that pattern (:mod:`glu.bn.conditioned`); the other rows together on the network's
        junction tree (a row without a value for an observed node gets a likelihood of ones there). Rows go
        in chunks whose tables hold at most :data:`BATCH_ENTRIES` entries.
        """
        targets = self._targets(targets)
        evidence = dict(evidence or {})
        soft = dict(soft or {})
        n = _batch_length(evidence, soft)
        check_soft_rule(soft_rule)
        hard = {self.index[node]: self._codes(node, vals, n) for node, vals in evidence.items()}
        checked = {node: self._batch_soft(node, arr, n, evidence) for node, arr in soft.items()}
        qs = {self.index[node]: q for node, q in checked.items()}
        want = frozenset(self.index[t] for t in targets)
        out = {t: np.full((n, self.cards[self.index[t]]), np.nan) for t in targets}
        possible = np.ones(n, dtype=bool)
        hard_possible = np.zeros(n, dtype=bool)
        for rows, group in self._groups(hard, bool(qs), n):
            res, ok, hp = self._solve_chunked(
                want,
                {v: hard[v][rows] for v in group},
                {v: q[rows] for v, q in qs.items()},
                soft_rule,
                len(rows),
            )
            for t in targets:
                out[t][rows] = res[self.index[t]]
            possible[rows], hard_possible[rows] = ok, hp
        if errors == "raise" and not possible.all():
            k = int(np.flatnonzero(~possible)[0])
            codes = {node: hard[self.index[node]] for node in evidence}
            raise self._impossible_row(k, codes, list(soft), int((~possible).sum()), bool(hard_possible[k]))
        return out
