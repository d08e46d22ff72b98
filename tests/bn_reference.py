"""pgmpy (1.x) as the independent reference of glu's networks (tests and benchmarks only: pgmpy is a test
dependency, and importing it takes seconds)."""

from __future__ import annotations

from typing import Any

import numpy as np

from glu.bn.model import BayesNet


def to_pgmpy(bn: BayesNet, check: bool = True) -> Any:
    """The same network as a ``pgmpy.models.DiscreteBayesianNetwork`` with explicit state names.

    pgmpy CPDs are laid out (child value, parent configuration) with the first parent varying slowest,
    which is our ``cpt`` reshaped to (n_configs, n_values) and transposed. All-zero rows (configurations a
    word never saw) are kept as they are; pass ``check=False`` to skip pgmpy's column-sum check, which
    rejects them.
    """
    from pgmpy.factors.discrete import TabularCPD
    from pgmpy.models import DiscreteBayesianNetwork

    model = DiscreteBayesianNetwork()
    model.add_nodes_from(bn.nodes)
    model.add_edges_from(bn.edges())
    cpds = []
    for node in bn.nodes:
        ps = list(bn.parents[node])
        card = bn.schema.cardinality(node)
        table = bn.cpts[node].reshape(-1, card).T
        names = {n: list(bn.schema.values_of(n)) for n in [node, *ps]}
        cpds.append(
            TabularCPD(
                node,
                card,
                np.ascontiguousarray(table),
                evidence=ps or None,
                evidence_card=[bn.schema.cardinality(p) for p in ps] or None,
                state_names=names,
            )
        )
    model.add_cpds(*cpds)
    if check:
        model.check_model()
    return model


SEEN_PREFIX = "seen__"


def to_pgmpy_with_zero_rows(bn: BayesNet) -> tuple[Any, dict[str, str]]:
    """A pgmpy network equivalent to ``bn`` *including* its all-zero CPT rows, plus the evidence to add.

    pgmpy rejects all-zero rows and prunes unobserved leaves, so the original's behaviour (a parent
    configuration never seen by a word gets probability 0 in every query) is expressed explicitly: each
    zero row is made uniform and an observed indicator node ``seen__<node>`` with the same parents is
    added, ``P(seen=yes | pa) = 1`` if the row was seen, else 0. Pass the returned evidence
    (``{"seen__but": "yes", …}``) with every query.
    """
    from pgmpy.factors.discrete import TabularCPD

    cpts = {}
    indicators: dict[str, np.ndarray] = {}
    for node in bn.nodes:
        cpt = bn.cpts[node].copy()
        sums = cpt.sum(axis=-1)
        if (sums == 0).any():
            cpt[sums == 0] = 1.0 / cpt.shape[-1]
            indicators[node] = (sums > 0).astype(float)
        cpts[node] = cpt
    filled = BayesNet(schema=bn.schema, parents=bn.parents, cpts=cpts, meta=bn.meta)
    model = to_pgmpy(filled)
    evidence = {}
    for node, seen in indicators.items():
        name = SEEN_PREFIX + node
        ps = list(bn.parents[node])
        model.add_node(name)
        model.add_edges_from((p, name) for p in ps)
        table = np.stack([1.0 - seen.ravel(), seen.ravel()])
        names = {name: ["no", "yes"], **{p: list(bn.schema.values_of(p)) for p in ps}}
        model.add_cpds(
            TabularCPD(
                name,
                2,
                table,
                evidence=ps or None,
                evidence_card=[bn.schema.cardinality(p) for p in ps] or None,
                state_names=names,
            )
        )
        evidence[name] = "yes"
    model.check_model()
    return model, evidence
