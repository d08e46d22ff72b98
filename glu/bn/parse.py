"""Evidence as the engines take it: value names, aliases or indices checked and turned into value codes.

:class:`Values` knows every node's values (and the schema's aliases, such as ``circle`` for ``sphere``) and
turns what a caller gives — one value, a column of values for a batch, a soft distribution — into value
indices and checked arrays, with one clear error line for anything wrong (:mod:`glu.errors`).

>>> from glu.bn import learn_bn
>>> from glu.data import load_experiments
>>> vals = Values(learn_bn(load_experiments("synthetic")))
>>> vals.value("Shape", "circle"), vals.codes("Action", ["tap", None, 0], 3).tolist()
(0, [1, -1, 0])
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from glu.bn.model import BayesNet
from glu.bn.soft import SUM_TOL, check_distribution
from glu.errors import EvidenceError, ImpossibleEvidenceError, UnknownNodeError
from glu.schema import unknown_node_message

SoftEvidence = Mapping[str, Mapping[str, float] | Sequence[float] | np.ndarray]
"""Soft evidence of one query: node → {value: probability} or a vector over its values."""


class Values:
    """Value look-up for every node of ``bn`` (aliases included) and the checks of evidence."""

    def __init__(self, bn: BayesNet) -> None:
        self.bn = bn
        self.nodes = bn.nodes
        self.cards: dict[str, int] = {n: c.shape[-1] for n, c in bn.cpts.items()}
        self._index: dict[str, dict[str, int]] = {}

    def index(self, node: str) -> dict[str, int] | None:
        """``node``'s value names and aliases → value index (made on first use); None for an unknown node."""
        d = self._index.get(node)
        if d is None and node in self.cards:
            vals = self.bn.schema.values_of(node)
            d = {v: i for i, v in enumerate(vals)}
            for alias, v in self.bn.schema.aliases.get(node, {}).items():
                if v in d:  # an alias of a value this model does not have does not apply
                    d[alias] = d[v]
            self._index[node] = d
        return d

    def check_node(self, node: str) -> None:
        """:class:`UnknownNodeError` (naming the closest nodes) unless ``node`` is a node of the network."""
        if node not in self.cards:
            raise UnknownNodeError(unknown_node_message(node, self.nodes))

    def value(self, node: str, value: str | int) -> int:
        """The index of ``value`` (a name, an alias or an index) among ``node``'s values."""
        card = self.cards.get(node)
        if card is None:
            raise UnknownNodeError(unknown_node_message(node, self.nodes))
        if type(value) is int and 0 <= value < card:  # the common case first
            return value
        idx = self.index(node)
        assert idx is not None
        if type(value) is str and value in idx:
            return idx[value]
        if isinstance(value, int | np.integer) and not isinstance(value, bool):
            if 0 <= value < self.cards[node]:
                return int(value)
        else:
            i = idx.get(value)  # type: ignore[call-overload]
            if i is not None:
                return i
        return self.bn.schema.value_index(node, str(value))  # raises UnknownValueError

    def codes(self, node: str, values: Sequence, n: int) -> np.ndarray:
        """A batch column as value indices, shape (n,): -1 where not observed (None, NaN, a negative
        index)."""
        self.check_node(node)
        if isinstance(values, np.ndarray) and values.dtype.kind in "iu" and values.ndim == 1:
            out = values.astype(np.intp, copy=False)
            if out.min(initial=0) < 0:
                out = np.where(out < 0, -1, out)
            bad = out >= self.cards[node]
            if bad.any():
                self.value(node, int(out[bad][0]))  # raises UnknownValueError, naming the value
            return out
        out = np.empty(n, dtype=np.intp)
        for i, v in enumerate(values):
            if (
                v is None
                or (isinstance(v, float) and np.isnan(v))
                or (isinstance(v, int | np.integer) and v < 0)
            ):
                out[i] = -1
            else:
                out[i] = self.value(node, v)
        return out

    def soft_vector(self, node: str, dist: Mapping[str, float] | Sequence[float] | np.ndarray) -> np.ndarray:
        """Validate soft evidence on ``node`` and return it as a vector over the node's values, shape (k,)."""
        self.check_node(node)
        values = self.bn.schema.values_of(node)
        if isinstance(dist, Mapping):
            q = np.zeros(len(values))
            for k, p in dist.items():
                if isinstance(p, bool) or not isinstance(p, int | float | np.integer | np.floating):
                    raise EvidenceError(
                        f"soft evidence on {node}: the probability of {k!r} must be a number, got {p!r}"
                    )
                q[self.value(node, k)] = p
        else:
            try:
                q = np.asarray(dist, dtype=float)
            except (TypeError, ValueError):
                raise EvidenceError(
                    f"soft evidence on {node} must be a list of {len(values)} numbers ({', '.join(values)}) "
                    f"or {{value: probability}}, got {dist!r}"
                ) from None
            if q.ndim != 1:
                raise EvidenceError(
                    f"soft evidence on {node} must be a flat list of {len(values)} numbers "
                    f"({', '.join(values)})"
                )
            if q.shape != (len(values),):
                raise EvidenceError(
                    f"soft evidence on {node} has {q.size} entries; expected {len(values)} "
                    f"({', '.join(values)})"
                )
        return check_distribution(node, values, q)

    def batch_soft(self, node: str, arr: np.ndarray, n: int, evidence: Mapping[str, Sequence]) -> np.ndarray:
        """Batch soft evidence on ``node`` checked (shape (n, n_values), every row a distribution, the node
        not also in the hard ``evidence``) and normalised to sum 1 per row."""
        self.check_node(node)
        if node in evidence:
            raise EvidenceError(f"{node} is given twice: as hard evidence and as soft evidence")
        arr = np.asarray(arr, dtype=float)
        if arr.ndim != 2 or arr.shape[0] != n:
            raise EvidenceError(f"batch soft evidence on {node} must have shape (n={n}, n_values)")
        for row in arr[: min(n, 1)]:
            self.soft_vector(node, row)
        sums = arr.sum(axis=1)
        if (arr < 0).any() or not np.all(np.abs(sums - 1) <= SUM_TOL):
            bad = int(np.flatnonzero((np.abs(sums - 1) > SUM_TOL) | (arr < 0).any(axis=1))[0])
            self.soft_vector(node, arr[bad])
        return arr / sums[:, None]

    # ------------------------------------------------------------------ the impossible-evidence error
    def impossible(
        self, evidence: Mapping | None, soft: Mapping | None, hard_possible: bool = False
    ) -> ImpossibleEvidenceError:
        """The error for evidence of probability 0 (one line: the evidence and why it may be so)."""
        hint = ""
        zr = self.bn.zero_rows()
        if hard_possible:
            hint = (
                " (the hard evidence alone is possible: the soft evidence gives probability 0 to every "
                "value it allows)"
            )
        elif zr:
            hint = (
                f" (the model has all-zero CPT rows for {', '.join(zr)}, which exclude some affordance "
                "configurations; learn with unseen_words='uniform' to keep them)"
            )
        parts = [f"{k}={v}" for k, v in (evidence or {}).items()] + [f"soft({k})" for k in (soft or {})]
        described = ", ".join(parts) if parts else "no evidence"
        return ImpossibleEvidenceError(
            f"impossible evidence: {described} has probability 0 under the model{hint}"
        )

    def impossible_row(
        self,
        i: int,
        codes: Mapping[str, np.ndarray],
        soft: Sequence[str],
        n_bad: int,
        hard_possible: bool = False,
    ) -> ImpossibleEvidenceError:
        """The error for row ``i`` of a batch (``codes``: node → value codes, shape (n,), -1 = not observed;
        ``soft``: the names of the soft nodes), the first of ``n_bad`` impossible rows."""
        ev = {node: self.bn.schema.values_of(node)[c[i]] for node, c in codes.items() if c[i] >= 0}
        return ImpossibleEvidenceError(
            f"row {i}: {self.impossible(ev, dict.fromkeys(soft), hard_possible)}"
            + (f" ({n_bad} impossible rows in all)" if n_bad > 1 else "")
        )


def batch_length(evidence: Mapping[str, Sequence], soft: Mapping[str, np.ndarray]) -> int:
    """The number of rows of a batch: every column's length, the same (else :class:`EvidenceError`).

    ``evidence``: node → n values; ``soft``: node → array, shape (n, n_values). Returns n.
    """
    lengths = {len(v) for v in evidence.values()} | {len(v) for v in soft.values()}
    if len(lengths) > 1:
        raise EvidenceError(f"batch evidence columns have different lengths: {sorted(lengths)}")
    if not lengths:
        raise EvidenceError("a batch query needs at least one evidence or soft-evidence column")
    return lengths.pop()
