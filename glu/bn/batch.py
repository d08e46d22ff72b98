"""Batch queries of the inference engine: many evidence sets at once, vectorised over the rows.

:class:`BatchQueries` is the part of :class:`~glu.bn.inference.InferenceEngine` that answers a whole table
of evidence (one row per experiment, per frame of a gesture, per point of a sweep) in a few array
operations: rows with the same pattern of observed nodes share one reduced joint table, gathered row by
row. Tested against single queries and pgmpy.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from glu.bn.soft import SoftRule, check_soft_rule
from glu.errors import EvidenceError

if TYPE_CHECKING:  # pragma: no cover
    from glu.bn.model import BayesNet


class BatchQueries:
    """Vectorised batch queries (mixed into :class:`~glu.bn.inference.InferenceEngine`)."""

    bn: BayesNet
    nodes: tuple[str, ...]
    axis: dict[str, int]
    shape: tuple[int, ...]
    base: np.ndarray
    leaf_axes: dict[str, tuple[int, ...]]
    leaf_ratio: dict[str, np.ndarray]
    _value_index: dict[str, dict[str, int]]

    def junction(self) -> Any:  # pragma: no cover - defined by the engine
        raise NotImplementedError

    def query_batch(
        self,
        targets: Sequence[str] | str,
        evidence: Mapping[str, Sequence] | None = None,
        soft: Mapping[str, np.ndarray] | None = None,
        soft_rule: SoftRule = "virtual",
        errors: Literal["raise", "nan"] = "raise",
    ) -> dict[str, np.ndarray]:
        """See :meth:`InferenceEngine.query_batch <glu.bn.inference.InferenceEngine.query_batch>`.

        Rows with the same pattern of observed nodes share one reduced joint table; soft evidence on a leaf,
        and Jeffrey's rule on several nodes, go to the network's junction tree.
        """
        if isinstance(targets, str):
            targets = [targets]
        if (soft and any(s not in self.axis and s in self._value_index for s in soft)) or (
            soft_rule == "jeffrey" and soft and len(soft) > 1
        ):  # soft evidence on a leaf, or Jeffrey's rule on several nodes: the junction tree
            return self.junction().query_batch(targets, evidence, soft, soft_rule, errors)
        evidence = dict(evidence or {})
        soft = dict(soft or {})
        n = _batch_length(evidence, soft)
        targets = self._targets(targets)
        codes = {node: self._codes(node, vals, n) for node, vals in evidence.items()}
        qs = {node: self._batch_soft(node, arr, n, codes) for node, arr in soft.items()}
        check_soft_rule(soft_rule)
        out = {t: np.full((n, self.bn.schema.cardinality(t)), np.nan) for t in targets}
        # rows with the same pattern of observed nodes share one reduced table
        observed = np.stack([c >= 0 for c in codes.values()], axis=1) if codes else np.zeros((n, 0), bool)
        patterns, inverse = np.unique(observed, axis=0, return_inverse=True)
        for k, pattern in enumerate(patterns):
            rows = np.flatnonzero(inverse.ravel() == k)
            obs = {node: codes[node][rows] for node, on in zip(codes, pattern, strict=True) if on}
            res = self._batch_pattern(targets, obs, {s: q[rows] for s, q in qs.items()}, soft_rule, len(rows))
            for t in targets:
                out[t][rows] = res[t]
        if errors == "raise":
            bad = np.flatnonzero(np.isnan(out[targets[0]][:, 0])) if targets else []
            if len(bad):
                raise self._impossible_row(int(bad[0]), codes, list(qs), len(bad))
        return out

    def _batch_pattern(
        self, targets: Sequence[str], obs: dict[str, np.ndarray], qs: dict[str, np.ndarray], rule: str, n: int
    ) -> dict[str, np.ndarray]:
        nd = len(self.shape)
        core_obs = {self.axis[k]: v for k, v in obs.items() if k in self.axis}
        leaf_obs = {k: v for k, v in obs.items() if k not in self.axis}
        keep = set(core_obs) | {self.axis[s] for s in qs}
        for t in targets:
            if t in self.axis:
                keep.add(self.axis[t])
            elif t not in leaf_obs:
                keep.update(self.leaf_axes[t])
        for leaf in leaf_obs:
            keep.update(self.leaf_axes[leaf])
        kept = sorted(keep)
        reduced = (
            self.base.sum(axis=tuple(a for a in range(nd) if a not in keep)) if len(kept) < nd else self.base
        )
        # gather the observed core axes row by row → table over the free kept axes, shape (n, *free)
        free = [a for a in kept if a not in core_obs]
        index = []
        for a in kept:
            if a in core_obs:
                index.append(core_obs[a].reshape((n,) + (1,) * len(free)))
            else:
                j = free.index(a)
                shape = [1] * (len(free) + 1)
                shape[j + 1] = self.shape[a]
                index.append(np.arange(self.shape[a]).reshape(shape))
        p = reduced[tuple(index)] if kept else np.broadcast_to(reduced, (n,)).copy()
        if not kept:
            p = p.reshape(n)
        elif not core_obs:  # rows that observe nothing on the core: the same table in every row
            p = np.broadcast_to(p, (n, *p.shape[1:])).copy()
        pos = {a: 1 + free.index(a) for a in free}

        def expand(table: np.ndarray, axes: Sequence[int]) -> np.ndarray:
            """Row-wise table over ``axes`` (shape (n, *cards)) → broadcastable against p."""
            shape = [n] + [1] * len(free)
            order = np.argsort([pos[a] for a in axes])
            t = table.transpose([0, *(1 + order)])
            for a, s in zip(np.asarray(axes)[order], t.shape[1:], strict=True):
                shape[pos[a]] = s
            return t.reshape(shape)

        for leaf, v in leaf_obs.items():
            axes = self.leaf_axes[leaf]
            ratio = self.leaf_ratio[leaf][v]  # (n, *pa cards)
            fixed = [a for a in axes if a in core_obs]
            if fixed:
                ratio = _gather_rows(ratio, [core_obs.get(a) for a in axes])
                axes = tuple(a for a in axes if a not in core_obs)
            p = p * (expand(ratio, axes) if axes else ratio.reshape((n,) + (1,) * len(free)))
        for s, q in qs.items():
            a = self.axis[s]
            shape = [n] + [1] * len(free)
            shape[pos[a]] = q.shape[1]
            qb = q.reshape(shape)
            if rule == "virtual":
                # as InferenceEngine: each row's likelihood scaled so its largest allowed entry is 1
                others = tuple(i for i in range(1, p.ndim) if i != pos[a])
                allowed = p.sum(axis=others, keepdims=True) > 0
                top = np.where(allowed, qb, 0.0).max(axis=pos[a], keepdims=True)
                qb = np.where(allowed, qb, 0.0) / np.where(top > 0, top, 1.0)
                p = p * qb
            else:
                others = tuple(i for i in range(1, p.ndim) if i != pos[a])
                z = p.sum(axis=others, keepdims=True)
                bad = ((z <= 0) & (qb > 0)).reshape(n, -1).any(axis=1)
                p = p * np.divide(qb, z, out=np.zeros(np.broadcast_shapes(qb.shape, z.shape)), where=z > 0)
                p[bad] = 0.0
        total = p.reshape(n, -1).sum(axis=1)
        ok = total > 0
        res = {}
        for t in targets:
            if t in self.axis and self.axis[t] in core_obs:
                r = np.zeros((n, self.shape[self.axis[t]]))
                r[np.arange(n), core_obs[self.axis[t]]] = 1.0
            elif t in self.axis:
                k = pos[self.axis[t]]
                r = p.sum(axis=tuple(i for i in range(1, p.ndim) if i != k))
                r = r / np.where(ok, total, 1)[:, None]
            elif t in leaf_obs:
                r = np.zeros((n, self.bn.schema.cardinality(t)))
                r[np.arange(n), leaf_obs[t]] = 1.0
            else:
                axes = self.leaf_axes[t]
                ratio = self.leaf_ratio[t]  # (r, *pa)
                fixed = [a for a in axes if a in core_obs]
                cols = []
                for v in range(ratio.shape[0]):
                    rv = np.broadcast_to(ratio[v], (n, *ratio.shape[1:]))
                    ax = axes
                    if fixed:
                        rv = _gather_rows(rv, [core_obs.get(a) for a in axes])
                        ax = tuple(a for a in axes if a not in core_obs)
                    f = expand(rv, ax) if ax else rv.reshape((n,) + (1,) * len(free))
                    cols.append((p * f).reshape(n, -1).sum(axis=1))
                r = np.stack(cols, axis=1) / np.where(ok, total, 1)[:, None]
            r = np.array(r, dtype=float)
            r[~ok] = np.nan
            res[t] = r
        return res


def _gather_rows(table: np.ndarray, fixed: Sequence[np.ndarray | None]) -> np.ndarray:
    """Per row i, index the axes of ``table[i]`` given in ``fixed`` (None = keep the axis): (n, *kept)."""
    n = table.shape[0]
    index: list = [np.arange(n)]
    kept = [k for k, f in enumerate(fixed) if f is None]
    for k, f in enumerate(fixed):
        if f is None:
            shape = [1] * (len(kept) + 1)
            shape[1 + kept.index(k)] = table.shape[1 + k]
            index.append(np.arange(table.shape[1 + k]).reshape(shape))
        else:
            index.append(f.reshape((n,) + (1,) * len(kept)))
    index[0] = index[0].reshape((n,) + (1,) * len(kept))
    return table[tuple(index)]


def _batch_length(evidence: Mapping[str, Sequence], soft: Mapping[str, np.ndarray]) -> int:
    lengths = {len(v) for v in evidence.values()} | {len(v) for v in soft.values()}
    if len(lengths) > 1:
        raise EvidenceError(f"batch evidence columns have different lengths: {sorted(lengths)}")
    if not lengths:
        raise EvidenceError("a batch query needs at least one evidence or soft-evidence column")
    return lengths.pop()
