"""Two ways to train the gesture HMMs, measured on the same segments: glu's recipe and the originals'
mixsplit.

:func:`recipe_comparison` trains both recipes (:data:`glu.hmm.RECIPES`) over a grid of seeds
and EM tolerances and reports, per setting, the leave-one-segment-out accuracy on the training segments
and how the held-out test gestures (the two seated taps of effect anticipation) are recognised when the
models are trained on every training segment. The spread over the grid says how fragile a single quoted
accuracy is: with a dozen segments, one segment moves it by several points. mixsplit is deterministic
(flat start), so it runs once per tolerance.

:func:`leave_one_segment_out` gives the predictions of
:func:`glu.studies.replication.gestures.leave_one_out` (``by="segment"``) at a third of the cost: each
action's model depends only on that action's segments, so a fold retrains only the held-out segment's action
and reuses the others' models trained on everything (tested equal).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

from glu.gestures.corpus import LabelledSequence
from glu.gestures.invariants import Invariants
from glu.gestures.recognizer import Recognizer
from glu.hmm import RECIPES, TrainingConfig, train
from glu.studies.replication.gestures import Features, accuracy
from glu.tidy import corpus_source, tidy, training_parameters

RUN_KEYS = ("seed", "features")
"""The keys of a run (:func:`leave_one_segment_out_many`) that are not :class:`~glu.hmm.TrainingConfig`
fields."""

COLUMNS = [
    "recipe",
    "seed",
    "tol",
    "loso_accuracy",
    "loso_correct",
    "loso_testable",
    "test_predicted",
    "test_correct",
    "train_loglik_per_frame",
]


def leave_one_segment_out(
    sequences: Sequence[LabelledSequence],
    seed: int = 0,
    config: TrainingConfig | None = None,
    features: Features = None,
) -> tuple[pd.DataFrame, Recognizer]:
    """Hold out each segment in turn, train on the rest, recognise it; and the models trained on everything.

    Every model (one per action on all segments, one per testable fold) is trained in one batch
    (:func:`leave_one_segment_out_many`), each as :func:`~glu.gestures.recognizer.train_recognizer` would
    train it alone (tested equal).

    Returns
    -------
    (DataFrame with one row per segment: recording, start, end, action, predicted (missing when its
    action has no other segment), testable, correct; the :class:`~glu.gestures.recognizer.Recognizer`
    trained on all segments)
    """
    run = {**(config or TrainingConfig()).as_dict(), "seed": seed, "features": features}
    return leave_one_segment_out_many(sequences, [run])[0]


def leave_one_segment_out_many(
    sequences: Sequence[LabelledSequence], runs: Sequence[Mapping[str, Any]]
) -> list[tuple[pd.DataFrame, Recognizer]]:
    """:func:`leave_one_segment_out` for several runs, each a dict of its ``seed``, its ``features`` and
    :class:`~glu.hmm.TrainingConfig` fields (those left out keep glu's defaults).

    Runs with the same training settings (all but the seed and the features) share one batch of
    :func:`glu.hmm.train`, so every model of a grid of seeds and feature sets runs EM together. Returns
    what :func:`leave_one_segment_out` returns for each run, in order.
    """
    actions = tuple(dict.fromkeys(s.action for s in sequences))
    seen_by: dict[str, list[np.ndarray]] = {}  # the features the models see, per feature set
    plans, groups = [], {}
    for run in runs:
        settings = {k: v for k, v in run.items() if k not in RUN_KEYS}
        features = Invariants.parse(run.get("features"))
        if features.name not in seen_by:
            seen_by[features.name] = [
                s.xyz if features.is_raw else features.transform(s.xyz) for s in sequences
            ]
        seen = seen_by[features.name]
        jobs = [(a, [x for x, s in zip(seen, sequences, strict=True) if s.action == a]) for a in actions]
        folds = []  # held-out segments whose action has other segments: (index, the rest of its action)
        for i, held in enumerate(sequences):
            rest = [
                x
                for j, (x, s) in enumerate(zip(seen, sequences, strict=True))
                if j != i and s.action == held.action
            ]
            if rest:
                folds.append(i)
                jobs.append((held.action, rest))
        key = repr(sorted(settings.items()))
        group = groups.setdefault(key, (settings, []))[1]
        plans.append((features, folds, len(group), len(jobs)))
        group += [(a, seqs, int(run.get("seed", 0))) for a, seqs in jobs]
    trained_by = {}
    for key, (settings, jobs) in groups.items():
        batch = {(i, a): seqs for i, (a, seqs, _) in enumerate(jobs)}
        seeds = {(i, a): sd for i, (a, _, sd) in enumerate(jobs)}
        trained = train(batch, TrainingConfig(**settings), seed=seeds, warn=False)
        trained_by[key] = list(trained.values())
    out = []
    for run, (features, folds, lo, n) in zip(runs, plans, strict=True):
        settings = {k: v for k, v in run.items() if k not in RUN_KEYS}
        trained = trained_by[repr(sorted(settings.items()))][lo : lo + n]
        out.append(_loso_outcome(sequences, actions, features, folds, trained))
    return out


def _loso_outcome(
    sequences: Sequence[LabelledSequence],
    actions: tuple[str, ...],
    features: Invariants,
    folds: list[int],
    trained: Sequence[tuple[Any, Any]],
) -> tuple[pd.DataFrame, Recognizer]:
    """The table and the full recogniser of one run, from its models (one per action, then one per fold)."""
    full = dict(zip(actions, trained[: len(actions)], strict=True))
    fold_model = dict(zip(folds, (m for m, _ in trained[len(actions) :]), strict=True))
    rows = []
    for i, held in enumerate(sequences):
        row = {"recording": held.recording, "start": held.start, "end": held.end, "action": held.action}
        if i in fold_model:
            models = {a: (fold_model[i] if a == held.action else full[a][0]) for a in actions}
            predicted = Recognizer(models, features=features).classify(held.xyz)
        else:
            predicted = None
        rows.append(
            {**row, "predicted": predicted, "testable": i in fold_model, "correct": predicted == held.action}
        )
    everything = Recognizer(
        {a: m for a, (m, _) in full.items()},
        {a: r for a, (_, r) in full.items()},
        features=features,
    )  # the models were trained on these (invariant) features: the recogniser computes them too
    return pd.DataFrame(rows), everything


def recipe_comparison(
    sequences: Sequence[LabelledSequence],
    test: Sequence[LabelledSequence] = (),
    recipes: Sequence[str] = RECIPES,
    seeds: Sequence[int] = (0,),
    tols: Sequence[float] = (1e-4,),
    config: TrainingConfig | None = None,
    features: Features = None,
) -> pd.DataFrame:
    """Leave-one-segment-out accuracy and test recognition for each recipe, seed and EM tolerance.

    Parameters
    ----------
    sequences : the labelled training segments (LOSO runs over them)
    test : gestures recognised by models trained on all of ``sequences`` (e.g. the seated taps)
    recipes : names of :data:`~glu.hmm.RECIPES`
    seeds : seeds of glu's recipe (mixsplit ignores them and runs once per tolerance, seed reported as -1)
    tols : EM tolerances, log-likelihood per training frame
    config : the other training settings (``n_states``, ``n_mix``, ``n_iter``, …; default glu's)
    features : the invariant features the recognisers use (default raw)

    Returns
    -------
    DataFrame, one row per setting: recipe, seed, tol, loso_accuracy, loso_correct, loso_testable,
    test_predicted (the actions recognised for ``test``, comma-separated), test_correct (how many are
    right), train_loglik_per_frame (mean over actions, of the models trained on all segments).
    """
    base = {**(config or TrainingConfig()).as_dict(), "features": features}
    grid = [
        {**base, "tol": float(tol), "recipe": recipe, "seed": int(seed)}
        for recipe in recipes
        for tol in tols
        for seed in (seeds if recipe != "mixsplit" else (-1,))
    ]
    rows = comparison_rows(sequences, test, grid)
    return tidy(
        pd.DataFrame(rows, columns=COLUMNS),
        "hmm_recipe_comparison",
        corpus_source(sequences),
        recipes=list(recipes),
        seeds=list(seeds),
        tols=list(tols),
        n_test=len(test),
        **{k: v for k, v in training_parameters(config, features).items() if k not in ("tol", "recipe")},
    )


def comparison_rows(
    sequences: Sequence[LabelledSequence], test: Sequence[LabelledSequence], grid: Sequence[Mapping[str, Any]]
) -> list[dict[str, Any]]:
    """The rows of :func:`recipe_comparison` for a grid of runs, every run's models trained in one batch.

    Each entry of ``grid`` holds ``recipe``, ``seed`` (-1 for mixsplit, which has none; it trains with 0),
    ``tol``, ``features`` and other :class:`~glu.hmm.TrainingConfig` fields (``n_states``, …).
    """
    results = leave_one_segment_out_many(sequences, [{**g, "seed": max(int(g["seed"]), 0)} for g in grid])
    rows = []
    for g, (loo, rec) in zip(grid, results, strict=True):
        ok = loo[loo["testable"]]
        predicted = [rec.classify(t.xyz) for t in test]
        reports = rec.reports.values()
        rows.append(
            {
                "recipe": g["recipe"],
                "seed": int(g["seed"]),
                "tol": float(g["tol"]),
                "loso_accuracy": accuracy(ok),
                "loso_correct": int(ok["correct"].sum()),
                "loso_testable": len(ok),
                "test_predicted": ",".join(predicted),
                "test_correct": int(sum(p == t.action for p, t in zip(predicted, test, strict=True))),
                "train_loglik_per_frame": float(np.mean([r.final_loglik / r.n_frames for r in reports])),
            }
        )
    return rows


def recipe_spread(comparison: pd.DataFrame) -> pd.DataFrame:
    """Per recipe, the range of the leave-one-segment-out accuracy over the grid of :func:`recipe_comparison`.

    Returns
    -------
    DataFrame, one row per recipe: recipe, settings (how many), loso_min, loso_max, loso_at_default (at
    the first seed and tolerance of the grid), test_correct_min, test_correct_max, n_test.
    """
    rows = []
    n_test = int(comparison.attrs.get("parameters", {}).get("n_test", 0))
    for recipe, g in comparison.groupby("recipe", sort=False):
        rows.append(
            {
                "recipe": recipe,
                "settings": len(g),
                "loso_min": float(g["loso_accuracy"].min()),
                "loso_max": float(g["loso_accuracy"].max()),
                "loso_at_default": float(g["loso_accuracy"].iloc[0]),
                "test_correct_min": int(g["test_correct"].min()),
                "test_correct_max": int(g["test_correct"].max()),
                "n_test": n_test,
            }
        )
    return tidy(
        pd.DataFrame(rows),
        "hmm_recipe_spread",
        comparison.attrs.get("data_source", ""),
        **comparison.attrs.get("parameters", {}),
    )
