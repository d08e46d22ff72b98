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

RECOGNIZER_KEY, CALIBRATION_KEY, LEARN_KEY, MATCHED_KEY = 5000, 5001, 5002, 5003
"""Seed keys of each replication's training gestures (and EM), calibration gestures, experiment tables and
calibration gestures drawn like the test conditions."""


def replication_seed(seed: int, key: int, replication: int) -> int:
    """An integer seed for one replication's draws of one kind, apart from every other."""
    return int(np.random.SeedSequence([seed, key, replication]).generate_state(1)[0])


def scorer(recognizer: Any) -> Any:
    """A batch scorer (:class:`glu.hmm.BatchScorer`) of ``recognizer``'s models, one per action."""
    from glu.hmm import BatchScorer

    missing = [a for a in ACTIONS if a not in recognizer.models]
    if missing:
        raise ModelError(
            f"the recogniser has no model for {', '.join(missing)}; it needs {', '.join(ACTIONS)}"
        )
    return BatchScorer([recognizer.models[a] for a in ACTIONS])


def _training_view(features: str) -> Any:
    from glu.gestures.feature_sets import FeatureSet
    from glu.gestures.views import View

    return View(body_frame=FeatureSet.parse(features).body)


def recognizers(config: SweepConfig, out: Path, log: Callable[[str], None]) -> list[dict[str, Any]]:
    """Per recogniser seed, one recogniser per feature set (``grid.features``), all trained on the seed's own
    synthetic gestures (and EM start), the body-frame ones on the same gestures in the shoulder line's frame;
    or the file's. Trained once: a folder's ``recognizers/seed-NNN-FEATURES.json`` are reused."""
    from glu.gestures.corpus import synthetic_corpus
    from glu.gestures.feature_sets import FeatureSet
    from glu.gestures.recognizer import Recognizer, train_recognizer

    r = config.recognizer
    if r.file:
        return [{config.features[0]: Recognizer.load(r.file)}]
    folder = out / "recognizers"
    found: list[dict[str, Any]] = [{} for _ in range(config.recognizer_seeds)]
    todo = []
    for k in range(config.recognizer_seeds):
        for features in config.features:
            saved = folder / f"seed-{k:03d}-{features}.json"
            recipe = {**asdict(r), "seed": config.seed, "recognizer_seed": k, "features": features}
            if saved.is_file():
                try:
                    rec = Recognizer.load(saved)
                    if rec.meta.get("sweep_recipe") == recipe:
                        found[k][features] = rec
                        continue
                except ModelError:
                    pass
            todo.append((k, features, recipe, saved))
    if todo:
        log(
            f"training {len(todo)} gesture recognisers ({len(config.features)} feature sets per seed) on "
            f"{r.n_per_action} synthetic gestures per action each "
            f"(Q={r.training.n_states}, M={r.training.n_mix})"
        )
        sets, seeds, specs, metas = [], [], [], []
        for k, features, recipe, _ in todo:
            s = replication_seed(config.seed, RECOGNIZER_KEY, k)
            corpus = synthetic_corpus(r.n_per_action, s, noise=r.noise, view=_training_view(features))
            by_action: dict[str, list[np.ndarray]] = {}
            for seq in corpus:
                by_action.setdefault(seq.action, []).append(seq.xyz)
            sets.append(by_action)
            seeds.append(s)
            specs.append(FeatureSet.parse(features).invariants)
            metas.append({"sweep_recipe": recipe, "data_source": corpus.description})
        trained = train_recognizer(sets, r.training, seed=seeds, features=specs, warn=False)
        for (k, features, _, saved), rec, meta in zip(todo, trained, metas, strict=True):
            rec.meta.update(meta)
            rec.save(saved)
            found[k][features] = rec
    return found


def matched_gestures(config: SweepConfig, k: int, body: bool) -> tuple[list[np.ndarray], np.ndarray]:
    """The held-out gestures of recogniser seed ``k`` drawn like the test conditions:
    ``calibration_per_action`` per action, each seen from one of the sweep's (viewpoint, noise level) pairs
    in turn, with the episodes' tracking problems, repaired as they are; in the shoulder line's frame with
    ``body``. Returns the features, n arrays of shape (T_i, 3), and the actions' indices in
    :data:`glu.schema.ACTIONS`, shape (n,), for n = ``calibration_per_action`` × the number of actions."""
    from dataclasses import replace

    from glu.gestures.synthetic_batch import gesture_features

    n = config.recognizer.calibration_per_action * len(ACTIONS)
    actions = np.arange(n) % len(ACTIONS)
    pairs = [(v, x) for v in config.viewpoints for x in config.noise]
    xs: list[np.ndarray] = [np.empty((0, 3))] * n
    for j, (view, noise) in enumerate(pairs):
        idx = np.arange(j, n, len(pairs))
        if len(idx) == 0:
            continue
        rngs = [np.random.default_rng([config.seed, MATCHED_KEY, k, int(i)]) for i in idx]
        batch = gesture_features(
            [ACTIONS[a] for a in actions[idx]],
            rngs,
            noise=float(noise),
            spike_rate=config.gestures.spike_rate,
            dropout_rate=config.gestures.dropout_rate,
            view=replace(config.views[view], body_frame=body),
        )
        for i, x in zip(idx, batch.features, strict=True):
            xs[i] = x
    return xs, actions


def calibrations(config: SweepConfig, recognizers: list[dict[str, Any]]) -> tuple[list[dict], pd.DataFrame]:
    """Each recogniser's calibrated readings, β per fraction: ``calibrated`` fitted on its own clean
    front-view held-out gestures, ``calibrated-matched`` on held-out gestures drawn like the test conditions
    (:func:`matched_gestures`), as the sweep's ``p_hmm`` asks.

    Returns, per seed, feature set → reading → :class:`~glu.gestures.calibration.Calibration`; and the table
    of every fit: recognizer_seed, features, reading, fraction, beta, at_bound (β at an end of
    :data:`~glu.gestures.calibration.BETA_BOUNDS`: the fit wanted to go further), n_gestures, accuracy (the
    recogniser's on those gestures at that fraction: for the matched set, a validation accuracy the sweep
    never saw as a test episode).
    """
    from glu.gestures.calibration import BETA_BOUNDS, fit_calibration
    from glu.gestures.corpus import synthetic_corpus
    from glu.gestures.feature_sets import FeatureSet

    kinds = [p for p in ("calibrated", "calibrated-matched") if p in config.p_hmm]
    r = config.recognizer
    fractions = np.asarray(config.evaluation.fractions)
    out, rows = [], []
    for k, recs in enumerate(recognizers):
        per: dict[str, dict[str, Any]] = {}
        for features, rec in recs.items():
            spec = FeatureSet.parse(features)
            per[features] = {}
            for kind in kinds:
                if kind == "calibrated":
                    seed = replication_seed(config.seed, CALIBRATION_KEY, k)
                    held = synthetic_corpus(
                        r.calibration_per_action, seed, noise=r.noise, view=_training_view(features)
                    )
                    xs, labels = [s.xyz for s in held], np.array([ACTIONS.index(s.action) for s in held])
                else:
                    xs, labels = matched_gestures(config, k, spec.body)
                if not spec.invariants.is_raw:
                    xs = [spec.invariants.transform(x) for x in xs]
                lengths = np.array([len(x) for x in xs])
                ends = np.maximum(np.ceil(np.round(fractions[None, :] * lengths[:, None], 9)).astype(int), 1)
                loglik = scorer(rec).loglik_at(xs, ends)
                cal = fit_calibration(loglik, labels, fractions)
                per[features][kind] = cal
                right = np.argmax(loglik, axis=-1) == labels[:, None]
                for j, f in enumerate(fractions):
                    rows.append(
                        {
                            "recognizer_seed": k,
                            "features": features,
                            "reading": kind,
                            "fraction": float(f),
                            "beta": float(cal.beta[j]),
                            "at_bound": bool(cal.beta[j] in BETA_BOUNDS),
                            "n_gestures": cal.n_gestures,
                            "accuracy": float(right[:, j].mean()),
                        }
                    )
        out.append(per)
    cols = [
        "recognizer_seed",
        "features",
        "reading",
        "fraction",
        "beta",
        "at_bound",
        "n_gestures",
        "accuracy",
    ]
    return out, pd.DataFrame(rows, columns=cols)


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
