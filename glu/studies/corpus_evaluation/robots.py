"""The robot of each recogniser seed of a sweep: its gesture recogniser, the calibration of its p_HMM, and
the networks it learns from its own simulated experiments.

Every draw is seeded apart from the episodes and from the other seeds (:func:`replication_seed`): the
recogniser's training gestures and EM start, its held-out calibration gestures, and its experiment tables.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from glu.errors import ModelError
from glu.schema import ACTIONS
from glu.studies.corpus_evaluation.config import SweepConfig

RECOGNIZER_KEY, CALIBRATION_KEY, LEARN_KEY = 5000, 5001, 5002
"""Seed keys of each replication's training gestures (and EM), calibration gestures and experiment tables."""


def replication_seed(seed: int, key: int, replication: int) -> int:
    """An integer seed for one replication's draws of one kind, apart from every other."""
    return int(np.random.SeedSequence([seed, key, replication]).generate_state(1)[0])


def scorer(recognizer: Any) -> Any:
    from glu.hmm import BatchScorer

    missing = [a for a in ACTIONS if a not in recognizer.models]
    if missing:
        raise ModelError(
            f"the recogniser has no model for {', '.join(missing)}; it needs {', '.join(ACTIONS)}"
        )
    return BatchScorer([recognizer.models[a] for a in ACTIONS])


def recognizers(config: SweepConfig, out: Path, log: Callable[[str], None]) -> list[Any]:
    """One recogniser per seed: trained on its own synthetic gestures (and EM start), or the file's."""
    from glu.gestures.corpus import synthetic_corpus
    from glu.gestures.recognizer import Recognizer, train_recognizer

    r = config.recognizer
    if r.file:
        return [Recognizer.load(r.file)]
    folder = out / "recognizers"
    recognizers: list[Any] = [None] * config.recognizer_seeds
    todo = []
    for k in range(config.recognizer_seeds):
        saved = folder / f"seed-{k:03d}.json"
        recipe = {**asdict(r), "seed": config.seed, "recognizer_seed": k}
        if saved.is_file():
            try:
                rec = Recognizer.load(saved)
                if rec.meta.get("sweep_recipe") == recipe:
                    recognizers[k] = rec
                    continue
            except ModelError:
                pass
        todo.append((k, recipe, saved))
    if todo:
        log(
            f"training {len(todo)} gesture recognisers on {r.n_per_action} synthetic gestures per action "
            f"each (Q={r.n_states}, M={r.n_mix})"
        )
        sets, seeds, metas = [], [], []
        for k, recipe, _ in todo:
            s = replication_seed(config.seed, RECOGNIZER_KEY, k)
            corpus = synthetic_corpus(r.n_per_action, s, noise=r.noise)
            by_action: dict[str, list[np.ndarray]] = {}
            for seq in corpus:
                by_action.setdefault(seq.action, []).append(seq.xyz)
            sets.append(by_action)
            seeds.append(s)
            metas.append({"sweep_recipe": recipe, "data_source": corpus.description})
        trained = train_recognizer(sets, r.training(), seed=seeds, warn=False)
        for (k, _, saved), rec, meta in zip(todo, trained, metas, strict=True):
            rec.meta.update(meta)
            rec.save(saved)
            recognizers[k] = rec
    return recognizers


def calibrations(config: SweepConfig, recognizers: list[Any]) -> list[Any]:
    """Each recogniser's calibrated reading: β per fraction, fitted on its own held-out training gestures."""
    from glu.gestures.calibration import fit_calibration
    from glu.gestures.corpus import synthetic_corpus

    if "calibrated" not in config.p_hmm:
        return [None] * len(recognizers)
    r = config.recognizer
    fractions = np.asarray(config.evaluation.fractions)
    out = []
    for k, rec in enumerate(recognizers):
        held = synthetic_corpus(
            r.calibration_per_action, replication_seed(config.seed, CALIBRATION_KEY, k), noise=r.noise
        )
        xs = [s.xyz for s in held]
        lengths = np.array([len(x) for x in xs])
        ends = np.maximum(np.ceil(np.round(fractions[None, :] * lengths[:, None], 9)).astype(int), 1)
        loglik = scorer(rec).loglik_at(xs, ends)
        labels = np.array([ACTIONS.index(s.action) for s in held])
        out.append(fit_calibration(loglik, labels, fractions))
    return out


def learned_networks(config: SweepConfig, engine: Any) -> list[dict[int, Any]]:
    """Per recogniser seed, the networks glu learns (K2 + BIC) from experiment tables drawn from the world."""
    from glu.bn import learn_bn, make_engine
    from glu.bn.sampling import categorical, sample

    if "learned" not in config.inference_network:
        return [{} for _ in range(config.recognizer_seeds)]
    schema = engine.bn.schema
    prior = np.asarray(engine.query(["Action"], {})["Action"], dtype=float)
    out = []
    for k in range(config.recognizer_seeds):
        nets = {}
        for n in config.learn_experiments:
            rng = np.random.default_rng(np.random.SeedSequence([config.seed, LEARN_KEY, k, n]))
            codes = sample(engine, {"Action": categorical(np.broadcast_to(prior, (n, len(prior))), rng)}, rng)
            table = pd.DataFrame(
                {
                    node: pd.Categorical.from_codes(codes[node], categories=list(schema.values_of(node)))
                    for node in schema.nodes
                }
            )
            table.attrs["data_source"] = f"{n} experiments drawn from the generating network (seed {k})"
            nets[n] = make_engine(learn_bn(table, schema, unseen_words=config.network.unseen_words))
        out.append(nets)
    return out
