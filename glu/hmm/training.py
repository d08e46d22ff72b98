"""Training gesture HMMs: :func:`train`, the one entry point, for one model or many.

``train(sequences, config)`` fits one left-to-right GMM-HMM to a list of sequences (arrays of shape
(T_i, D)) and returns a :class:`Trained` pair (the model, its :class:`~glu.hmm.config.TrainingReport`).
``train({key: sequences, …}, config)`` fits one model per key with their EM batched, and returns a dict of
the same keys. The recipe is the config's (:class:`~glu.hmm.config.TrainingConfig`):

* ``"glu"`` (:mod:`glu.hmm.glu_recipe`): time slices, a mixture per slice, MAP EM;
* ``"mixsplit"`` (:mod:`glu.hmm.mixsplit`): the originals' flat start and mixture splitting.

One model is trained by the readable EM of :mod:`glu.hmm.em`; many by the batched EM of
:mod:`glu.hmm._engine.em_batch`, each model equal to its one-model result to rounding (tested).

Example
-------
>>> import numpy as np
>>> from glu.hmm import TrainingConfig, train
>>> rng = np.random.default_rng(0)
>>> seqs = [np.cumsum(rng.normal(size=(40, 3)), axis=0) for _ in range(4)]
>>> model, report = train(seqs, TrainingConfig(n_states=3, n_mix=2), name="tap")
>>> model.n_states, model.n_mix, report.n_sequences
(3, 2, 4)
>>> bank = train({"tap": seqs, "grasp": [s[::-1] for s in seqs]}, TrainingConfig(n_states=3, n_mix=1))
>>> sorted(bank), bank["grasp"].model.name
(['grasp', 'tap'], 'grasp')
"""

from __future__ import annotations

from collections.abc import Hashable, Mapping, Sequence
from typing import Any, NamedTuple

import numpy as np

from glu.errors import ModelError
from glu.hmm import glu_recipe, mixsplit
from glu.hmm.config import TrainingConfig, TrainingReport
from glu.hmm.model import GestureHMM


class Trained(NamedTuple):
    """A trained model and how its training went."""

    model: GestureHMM
    report: TrainingReport


def model_name(key: Hashable) -> str:
    """The name of the model trained under ``key`` in :func:`train`: the key itself if it is a string, else
    the last element of a tuple key (``(0, "tap")`` → ``"tap"``), else ``str(key)``."""
    if isinstance(key, str):
        return key
    if isinstance(key, tuple) and key:
        return str(key[-1])
    return str(key)


def train(
    sequences: Sequence[Any] | Mapping[Hashable, Sequence[Any]],
    config: TrainingConfig | None = None,
    *,
    seed: int | Mapping[Hashable, int] = 0,
    name: str = "",
    warn: bool = True,
    engine: str = "glu",
    weights: Sequence[float] | Mapping[Hashable, Sequence[float]] | None = None,
    start: GestureHMM | Mapping[Hashable, GestureHMM] | None = None,
) -> Trained | dict[Hashable, Trained]:
    """Train one gesture HMM, or many at once.

    Parameters
    ----------
    sequences : one model's training sequences, each an array of shape (T_i, D); or a mapping from a key
        to such a list, one model per key (a string key names its model; a tuple key such as
        ``(set, action)`` is named by its last element: :func:`model_name`)
    config : the settings (:class:`~glu.hmm.config.TrainingConfig`; default: glu's)
    seed : seeds glu's recipe's initial mixtures (the mixsplit recipe is deterministic); with a mapping,
        one seed for every model or a mapping of the same keys
    name : the model's name, for one model (the keys name them otherwise)
    warn : emit an :class:`~glu.hmm.config.HMMConvergenceWarning` when EM does not converge
    engine : glu's recipe, one model: ``"glu"`` (:func:`glu.hmm.em.fit`) or ``"hmmlearn"`` (its
        ``GMMHMM``); many models always use glu's batched EM
    weights : one weight ≥ 0 per training sequence (with a mapping: a mapping of the same keys to such
        lists): weighted EM, each sequence counted ``weight`` times
        (:func:`glu.hmm.glu_recipe.train_weighted`; glu's recipe only, one model at a time). None (the
        default): the unweighted training above
    start : with ``weights``, the model(s) EM goes on from (a mapping: for some keys) instead of a fresh
        initial model

    Returns
    -------
    :class:`Trained` for one model; ``{key: Trained}`` for a mapping, in its order.
    """
    config = config or TrainingConfig()
    if weights is not None:
        return _train_weighted(sequences, weights, config, seed, name, warn, engine, start)
    if start is not None:
        raise ModelError("start= continues weighted training; give weights= too")
    if not isinstance(sequences, Mapping):
        if not isinstance(seed, int | np.integer):
            raise ModelError(f"one model takes one seed, got {seed!r}")
        if config.recipe == "mixsplit":
            model, report, _ = mixsplit.train_one(sequences, config, name, warn)
            return Trained(model, report)
        return Trained(*glu_recipe.train_one(sequences, config, int(seed), name, warn, engine))
    keys = list(sequences)
    if isinstance(seed, Mapping):
        missing = [k for k in keys if k not in seed]
        if missing:
            raise ModelError(f"no seed for {', '.join(map(str, missing))}")
        seeds = [int(seed[k]) for k in keys]
    else:
        seeds = [int(seed)] * len(keys)
    if engine != "glu":
        raise ModelError(f"many models are trained by glu's batched EM; engine={engine!r} trains one model")
    names = [model_name(k) for k in keys]
    data = [sequences[k] for k in keys]
    if config.recipe == "mixsplit":
        results = [(m, r) for m, r, _ in mixsplit.train_batch(data, config, names, warn)]
    else:
        results = glu_recipe.train_batch(data, config, seeds, names, warn)
    return {k: Trained(m, r) for k, (m, r) in zip(keys, results, strict=True)}


def _train_weighted(
    sequences: Sequence[Any] | Mapping[Hashable, Sequence[Any]],
    weights: Sequence[float] | Mapping[Hashable, Sequence[float]],
    config: TrainingConfig,
    seed: int | Mapping[Hashable, int],
    name: str,
    warn: bool,
    engine: str,
    start: GestureHMM | Mapping[Hashable, GestureHMM] | None,
) -> Trained | dict[Hashable, Trained]:
    """:func:`train` with sequence weights: glu's recipe, weighted EM, one model after another."""
    if config.recipe != "glu" or engine != "glu":
        raise ModelError("weighted training uses glu's recipe and EM (recipe='glu', engine='glu')")
    if not isinstance(sequences, Mapping):
        if (
            isinstance(weights, Mapping)
            or isinstance(start, Mapping)
            or not isinstance(seed, int | np.integer)
        ):
            raise ModelError("one model takes one list of weights, one seed and one start")
        return Trained(*glu_recipe.train_weighted(sequences, weights, config, int(seed), name, warn, start))
    if not isinstance(weights, Mapping) or set(weights) != set(sequences):
        raise ModelError("with a mapping of training sets, give a mapping of weights with the same keys")
    out = {}
    for k, seqs in sequences.items():
        sd = int(seed[k]) if isinstance(seed, Mapping) else int(seed)
        first = start.get(k) if isinstance(start, Mapping) else None
        out[k] = Trained(*glu_recipe.train_weighted(seqs, weights[k], config, sd, model_name(k), warn, first))
    return out
