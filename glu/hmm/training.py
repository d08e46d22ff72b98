"""Training gesture HMMs: :func:`train`, the one entry point, for one model or many.

``train(sequences, config)`` fits one left-to-right GMM-HMM to a list of sequences (arrays of shape
(T_i, D)) and returns a :class:`Trained` pair (the model, its :class:`~glu.hmm.config.TrainingReport`).
``train({key: sequences, …}, config)`` fits one model per key with their EM batched, and returns a dict of
the same keys. The recipe is the config's (:class:`~glu.hmm.config.TrainingConfig`):

* ``"glu"`` (:mod:`glu.hmm.glu_recipe`): time slices, a mixture per slice, MAP EM;
* ``"mixsplit"`` (:mod:`glu.hmm.mixsplit`): the originals' flat start and mixture splitting.

Every model is trained by the one batched EM (:func:`glu.hmm._engine.em_batch.fit_many`, weighted; one model
is a batch of one), each equal to the readable EM of :mod:`glu.hmm.em` to rounding (tested).

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

from collections.abc import Callable, Hashable, Mapping, Sequence
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
    weights: Sequence[float] | Mapping[Hashable, Sequence[float]] | None = None,
    start: GestureHMM | Mapping[Hashable, GestureHMM] | None = None,
    progress: Callable[[int], None] | None = None,
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
    weights : one weight ≥ 0 per training sequence (with a mapping: a mapping of the same keys to such
        lists): weighted EM, each sequence counted ``weight`` times (glu's recipe only). None (the
        default): every weight 1
    start : with ``weights``, the model(s) EM goes on from (a mapping: for some keys) instead of a fresh
        initial model
    progress : called with the number of models that have just finished training (for a progress bar)

    Returns
    -------
    :class:`Trained` for one model; ``{key: Trained}`` for a mapping, in its order. Every model is trained
    by the one batched EM (:func:`glu.hmm._engine.em_batch.fit_many`), each equal to what it would be
    alone, to rounding.
    """
    config = config or TrainingConfig()
    if start is not None and weights is None:
        raise ModelError("start= continues weighted training; give weights= too")
    if weights is not None and config.recipe != "glu":
        raise ModelError("weighted training uses glu's recipe (recipe='glu')")
    one = not isinstance(sequences, Mapping)
    if one:
        if (
            isinstance(weights, Mapping)
            or isinstance(start, Mapping)
            or not isinstance(seed, int | np.integer)
        ):
            raise ModelError("one model takes one list of weights, one seed and one start")
        jobs: dict[Hashable, Sequence[Any]] = {name: sequences}
        seed, names = {name: int(seed)}, [name]
        weights = None if weights is None else {name: weights}
        start = None if start is None else {name: start}
    else:
        jobs = dict(sequences)
        names = [model_name(k) for k in jobs]
        if weights is not None and (not isinstance(weights, Mapping) or set(weights) != set(jobs)):
            raise ModelError("with a mapping of training sets, give a mapping of weights with the same keys")
    keys = list(jobs)
    seeds = _seeds(keys, seed)
    data = [jobs[k] for k in keys]
    if config.recipe == "mixsplit":
        results = [(m, r) for m, r, _ in mixsplit.train_batch(data, config, names, warn, progress)]
    else:
        ws = None if weights is None else [weights[k] for k in keys]
        firsts = None if start is None else [start.get(k) for k in keys]
        results = glu_recipe.train_batch(data, config, seeds, names, warn, ws, firsts, progress)
    trained = {k: Trained(m, r) for k, (m, r) in zip(keys, results, strict=True)}
    return trained[name] if one else trained


def _seeds(keys: list[Hashable], seed: int | Mapping[Hashable, int]) -> list[int]:
    """One seed per key: the same for all, or each key's from a mapping."""
    if not isinstance(seed, Mapping):
        return [int(seed)] * len(keys)
    missing = [k for k in keys if k not in seed]
    if missing:
        raise ModelError(f"no seed for {', '.join(map(str, missing))}")
    return [int(seed[k]) for k in keys]
