"""Drawing experiments from the Affordance–Words network: the world of a simulated corpus.

:func:`sample` draws values of every node of an :class:`~glu.bn.inference.Engine`'s network, with
some core nodes fixed per row (e.g. the action and the object, chosen by a scenario, as the experimenter
chose them on the robot). It draws from exactly the distribution the engine answers queries with:

1. the free core nodes jointly from ``P(core)`` times the leaves' row masses, sliced at the fixed values and
   normalised — so with the original's all-zero word rows (docs/method.md §3.4) the configurations they
   exclude are never drawn, as they have probability 0 in every query;
2. each leaf (word) from its CPT row given its parents, ``P(w | pa) / m_w(pa)``.

Fixing nodes is an intervention on them (their own distribution is replaced by the caller's), which for
the root nodes Action, Color, Shape and Size is the same as conditioning.

Example
-------
>>> import numpy as np
>>> from glu.bn import learn_bn, make_engine
>>> from glu.data import load_experiments
>>> engine = make_engine(learn_bn(load_experiments("synthetic")))
>>> rng = np.random.default_rng(0)
>>> codes = sample(engine, {"Action": np.full(4000, 1), "Shape": np.zeros(4000, int)}, rng)  # taps on spheres
>>> sorted(codes)[:3], codes["ObjVel"].shape
(['Action', 'Color', 'Contact'], (4000,))
>>> p = np.bincount(codes["ObjVel"], minlength=3) / 4000      # close to p(ObjVel | tap, sphere)
>>> bool(np.abs(p - engine.query("ObjVel", {"Action": "tap", "Shape": "sphere"})["ObjVel"]).max() < 0.03)
True
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from glu.bn.core import CoreBackend
from glu.bn.inference import Engine
from glu.errors import EvidenceError, ImpossibleEvidenceError, ModelError, UnknownNodeError
from glu.schema import unknown_node_message


def categorical(probs: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """One draw per row of ``probs`` (shape (n, k), rows with a positive sum, not necessarily 1): int, shape
    (n,).

    Uses one uniform number per row (inverse CDF), so the draws depend only on ``rng`` and ``probs``.
    """
    cum = np.cumsum(probs, axis=1)
    u = rng.random(len(probs)) * cum[:, -1]
    return np.minimum((cum <= u[:, None]).sum(axis=1), probs.shape[1] - 1)


def sample(
    engine: Engine, fixed: Mapping[str, np.ndarray], rng: np.random.Generator
) -> dict[str, np.ndarray]:
    """Draw every node's value for ``n`` rows given fixed values of some core nodes.

    Parameters
    ----------
    engine : the network's inference engine (its distribution is the one sampled)
    fixed : core node → int array, shape (n,), of value indices (at least one node, to give n)
    rng : the random generator (one uniform per row for the core, then one per row and word)

    Returns
    -------
    dict node → int array, shape (n,), value indices, for every node of the network

    Raises
    ------
    ImpossibleEvidenceError if the fixed values of a row have probability 0 under the model
    """
    if not fixed:
        raise EvidenceError("sample needs at least one fixed node (it gives the number of rows)")
    core = getattr(engine, "backend", None)
    if not isinstance(core, CoreBackend):
        raise ModelError(
            "sampling draws from the core engine's joint table, and this network is answered by the junction "
            "tree (its core is too large): sample a network shaped like GLU's"
        )
    codes = {}
    for node, v in fixed.items():
        if node not in core.axis:
            if node in engine.nodes:
                raise EvidenceError(f"only core (affordance) nodes can be fixed, not the word {node!r}")
            raise UnknownNodeError(unknown_node_message(node, engine.nodes))
        v = np.asarray(v, dtype=np.intp)
        k = core.shape[core.axis[node]]
        if v.ndim != 1 or (v < 0).any() or (v >= k).any():
            raise EvidenceError(f"fixed values of {node} must be a column of value indices 0…{k - 1}")
        codes[node] = v
    lengths = {len(v) for v in codes.values()}
    if len(lengths) != 1:
        raise EvidenceError(f"fixed columns have different lengths: {sorted(lengths)}")
    n = lengths.pop()
    fixed_axes = {core.axis[k]: v for k, v in codes.items()}
    free = [a for a in range(len(core.shape)) if a not in fixed_axes]
    moved = np.moveaxis(core.base, list(fixed_axes), list(range(len(fixed_axes))))
    table = moved[tuple(fixed_axes.values())].reshape(n, -1)  # row by row at the fixed values
    mass = table.sum(axis=1)
    if not (mass > 0).all():
        i = int(np.flatnonzero(~(mass > 0))[0])
        values = ", ".join(f"{k}={engine.bn.schema.values_of(k)[v[i]]}" for k, v in codes.items())
        raise ImpossibleEvidenceError(f"row {i}: {values} has probability 0 under the model")
    drawn = categorical(table, rng) if free else np.zeros(n, dtype=np.intp)
    free_codes = np.unravel_index(drawn, tuple(core.shape[a] for a in free))
    for a, c in zip(free, free_codes, strict=True):
        codes[core.core[a]] = c.astype(np.intp)
    for leaf in core.leaves:
        ratio = core.leaf_ratio[leaf]  # (r, *parent cardinalities)
        parents = tuple(codes[core.core[a]] for a in core.leaf_axes[leaf])
        probs = ratio[(slice(None), *parents)].T if parents else np.broadcast_to(ratio, (n, len(ratio)))
        codes[leaf] = categorical(np.asarray(probs).reshape(n, -1), rng)
    return {node: codes[node] for node in engine.nodes}
