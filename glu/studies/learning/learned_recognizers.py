"""Recognisers learned from effects, all episodes at once, and what the robot then anticipates with them.

* :func:`learn_recognizer` — one HMM per action trained on unlabelled gestures labelled by a scheme of
  :mod:`glu.studies.learning.self_supervised` (weighted EM, :func:`glu.hmm.train` with ``weights``);
  ``iterative`` (and the ``unsupervised`` baseline) relabel and retrain until the arg-max labels of every
  gesture stop changing;
* :func:`learn_gestures` — watch simulated episodes and learn a recogniser from them, batch or online
  (:mod:`glu.studies.learning.online`): what ``glu learn-gestures`` writes;
* :func:`recorded_life` — one scheme's online learning beside the true labels', measured as it goes: notebook
  12's recording;
* :func:`anticipation_after_learning` — what the robot anticipates and says with learned HMMs (the TCDS
  Fig. 5 cases).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from typing import Any, NamedTuple

import numpy as np
import pandas as pd

from glu.bn.inference import Engine
from glu.data.source import DataSource
from glu.errors import DataError, ModelError
from glu.gestures.invariants import Invariants
from glu.gestures.recognizer import Recognizer
from glu.gestures.typicality import META_KEY, ranges_to_meta, training_range
from glu.hmm import GestureHMM, TrainingConfig, kmeans_labels, train
from glu.schema import ACTIONS
from glu.studies.anticipation.experiment import AnticipationRun
from glu.studies.learning.online import Learner, OnlineRun, OnlineSettings, run_online
from glu.studies.learning.self_supervised import (
    AMBIGUITIES,
    EFFECTS,
    LEARNERS,
    STUDY_TRAINING,
    TEST_OFFSET,
    best_matching,
    label_weights,
    network_posteriors,
    one_hot,
    p_hmm_reading,
    resampled,
    simulate_episodes,
)
from glu.tidy import tidy


class Learned(NamedTuple):
    """What :func:`learn_recognizer` returns.

    Attributes
    ----------
    recognizer : the learned gesture HMMs (actions without any label weight have no model)
    weights : array, shape (n, A) — the final label weights of the training episodes
    rounds : relabelling rounds run (1 for the schemes that do not relabel)
    """

    recognizer: Recognizer
    weights: np.ndarray
    rounds: int


def _fit_all(
    features: Sequence[np.ndarray],
    W: np.ndarray,
    actions: Sequence[str],
    config: TrainingConfig,
    seed: int,
    start: Mapping[str, GestureHMM] | None = None,
    progress: Callable[[str], None] | None = None,
) -> dict[str, GestureHMM]:
    """One model per action with enough label weight: weighted training (from ``start`` when given);
    ``progress(action)`` after each."""
    lengths = np.array([len(x) for x in features])
    models = {}
    for a, name in enumerate(actions):
        w = W[:, a]
        if w @ lengths < config.n_states * config.n_mix or not np.any(w > 0):
            continue
        first = start.get(name) if start is not None else None
        models[name] = train(
            list(features), config, weights=w, seed=seed, name=name, warn=False, start=first
        ).model
        if progress is not None:
            progress(name)
    if not models:
        raise ModelError("no action has enough label weight to train its model")
    return models


def learn_recognizer(
    features: Sequence[np.ndarray],
    scheme: str,
    p_bn: np.ndarray | None = None,
    *,
    true: np.ndarray | None = None,
    actions: Sequence[str] = ACTIONS,
    config: TrainingConfig = STUDY_TRAINING,
    seed: int = 0,
    threshold: float = 0.9,
    posterior: str = "per-frame",
    max_rounds: int = 10,
    invariants: Invariants | str | None = None,
    meta: Mapping[str, Any] | None = None,
    progress: Callable[[str], None] | None = None,
) -> Learned:
    """Train one HMM per action on unlabelled gestures, labelled by ``scheme`` (batch: all at once).

    Parameters
    ----------
    features : the training gestures' hand features, arrays of shape (T_i, 3)
    scheme : one of :data:`LEARNERS`
    p_bn : ``p_BN(A | …)`` of each gesture, shape (n, A) (every scheme but the baselines)
    true : the true action of each gesture, int array of shape (n,) (``true``; ``unsupervised`` uses it only
        to name its clusters after training, by the best matching)
    actions, config, seed : the models' names (the columns of ``p_bn``), training settings and seed
    threshold, posterior : as :class:`~glu.studies.learning.online.OnlineSettings` has them
    max_rounds : most relabelling rounds (``iterative``, ``unsupervised``: until the labels stop changing)
    invariants : the features the models are trained on (computed by the recogniser, as for any);
    progress : called with the action's name after each model is trained (every relabelling round)
    """
    if scheme not in LEARNERS:
        raise DataError(f"unknown labelling scheme {scheme!r}; allowed: {', '.join(LEARNERS)}")
    if scheme == "unsupervised" and true is None:
        raise DataError("the unsupervised baseline needs the true actions to name its clusters afterwards")
    spec = Invariants.parse(invariants)
    seen = [x if spec.is_raw else spec.transform(x) for x in features]
    n, k = len(seen), len(actions)
    lengths = np.array([len(x) for x in seen])
    if scheme == "unsupervised":
        W = one_hot(kmeans_labels(resampled(seen), k, seed), k)
    elif scheme == "true":
        W = label_weights("true", np.zeros((n, k)), true=true)
    else:
        if p_bn is None or np.shape(p_bn) != (n, k):
            raise DataError(f"scheme {scheme!r} needs p_bn of shape ({n}, {k})")
        W = label_weights(scheme, p_bn, threshold)
    models = _fit_all(seen, W, actions, config, seed, progress=progress)
    rounds = 1
    if scheme in ("iterative", "unsupervised"):
        labels = W.argmax(axis=1)
        for rounds in range(2, max_rounds + 1):  # noqa: B007 - the last value is reported
            ll = _loglik(models, actions, seen)
            p_hmm = p_hmm_reading(ll, lengths, posterior)
            W = label_weights("iterative", p_bn, p_hmm=p_hmm) if scheme == "iterative" else p_hmm
            models = _fit_all(seen, W, actions, config, seed, start=models, progress=progress)
            new = W.argmax(axis=1)
            if np.array_equal(new, labels):
                break
            labels = new
    if scheme == "unsupervised":
        perm = best_matching(W.T @ one_hot(np.asarray(true), k))
        models = {
            actions[perm[c]]: replace(models[actions[c]], name=actions[perm[c]])
            for c in range(k)
            if actions[c] in models
        }
        W = W[:, np.argsort(perm)]
    info = {
        "scheme": scheme,
        "rounds": rounds,
        "training_gestures": n,
        **dict(config.as_dict()),
        **(meta or {}),
    }
    order = {a: models[a] for a in actions if a in models}
    return Learned(with_ranges(Recognizer(order, meta=info, features=spec), seen, W, actions), W, rounds)


def with_ranges(
    recognizer: Recognizer, seen: Sequence[np.ndarray], W: np.ndarray, actions: Sequence[str]
) -> Recognizer:
    """``recognizer`` with the typicality ranges of its models (:mod:`glu.gestures.typicality`) measured on
    the training gestures (in the recogniser's features) labelled with each action (arg-max of ``W``, shape
    (n, A)); an action without such a gesture keeps no range (the recogniser samples one when asked)."""
    labels = W.argmax(axis=1)
    ranges = {}
    for a in recognizer.actions:
        mine = [x for x, lab in zip(seen, labels, strict=True) if lab == list(actions).index(a)]
        if mine:
            ranges[a] = training_range(recognizer.models[a], mine)
    if set(ranges) == set(recognizer.actions):
        recognizer.meta[META_KEY] = ranges_to_meta(ranges)
    return recognizer


def _loglik(
    models: Mapping[str, GestureHMM], actions: Sequence[str], seqs: Sequence[np.ndarray]
) -> np.ndarray:
    """``log L(G | a)`` of every sequence under every action's model, shape (n, A); ``-inf`` without a
    model."""
    have = [a for a in actions if a in models]
    ll = Recognizer({a: models[a] for a in have}).loglik_many(seqs)
    out = np.full((len(seqs), len(actions)), -np.inf)
    out[:, [list(actions).index(a) for a in have]] = ll
    return out


def learn_gestures(
    engine: Engine,
    episodes: int,
    labels: str,
    *,
    seed: int = 0,
    words: bool = False,
    ambiguity: str = "mixed",
    online: bool = False,
    config: TrainingConfig | None = None,
    settings: OnlineSettings | None = None,
    effects: Sequence[str] = EFFECTS,
    noise: float | None = None,
    threshold: float = 0.9,
    data_source: str = "",
    progress: Callable[[str], None] | None = None,
) -> tuple[Recognizer, dict[str, Any]]:
    """Watch ``episodes`` simulated episodes and learn gesture HMMs from them, labelled by ``labels``.

    The episodes are those of :func:`~glu.studies.learning.self_supervised.simulate_episodes` (seed ``seed``,
    the given ambiguity, the ``easy`` world, whose features ``glu recognize`` computes too; ``noise``, if
    given, replaces its sensor noise of 2 cm); their labels come
    from the network (``engine``) by the scheme ``labels`` (or a baseline: ``true``, ``unsupervised``).
    Batch (:func:`learn_recognizer`, EM on all episodes, ``iterative`` relabelling until the labels stop
    changing) or ``online`` (:func:`~glu.studies.learning.online.learn_online`, one episode at a time).
    ``progress`` is called after each episode learned online, after each model trained in batch. Returns
    the recogniser (its ``meta`` says how it was learned) and a summary: the labels' accuracy, the rounds.
    """
    from glu.studies.learning.online import learn_online
    from glu.studies.learning.self_supervised import simulate_episodes

    if ambiguity not in AMBIGUITIES:
        raise DataError(f"unknown ambiguity {ambiguity!r}; allowed: {', '.join(AMBIGUITIES)}")
    actions = engine.bn.schema.values_of("Action")
    amb = AMBIGUITIES[ambiguity]
    ep = simulate_episodes(engine, amb, episodes, seed, effects=effects, noise=noise)
    p_bn = network_posteriors(engine, ep.perceived, ep.world, words)
    how = "online" if online else "batch"
    info: dict[str, Any] = {
        "data": f"{episodes} simulated episodes (seed {seed}, {ambiguity}: {amb.description}); labels "
        f"{labels}{' with words' if words else ''}, {how}; network: {data_source or 'unknown data'}",
        "data_source": data_source,
        "labels": labels,
        "learning": how,
        "episodes": episodes,
        "ambiguity": ambiguity,
        "words": words,
        "effects": list(effects),
        "label_accuracy": float((p_bn.argmax(axis=1) == ep.actions).mean()),
        "threshold": threshold,
    }
    features = ep.features
    if online:
        s = settings or OnlineSettings(config=config or OnlineSettings().config, threshold=threshold)
        run = learn_online(features, ep.actions, labels, p_bn, actions, s, seed, progress=progress)
        by_action = run.weights[:, 0][:, np.argsort(run.matching[-1, 0])]  # clusters named as actions
        rec = with_ranges(run.recognizer(0, meta=info), features, by_action, actions)
        info["rounds"] = 1
    else:
        learned = learn_recognizer(
            features,
            labels,
            p_bn,
            true=ep.actions,
            actions=actions,
            config=config or TrainingConfig(),
            seed=seed,
            threshold=threshold,
            meta=info,
            progress=progress,
        )
        rec, info["rounds"] = learned.recognizer, learned.rounds
    rec.meta.update(seed=seed, rounds=info["rounds"])
    missing = [a for a in actions if a not in rec.actions]
    if missing:
        raise DataError(
            f"no episode was labelled {', '.join(missing)} ({labels} labels, {ambiguity}); "
            "watch more episodes, use words, or another labelling scheme"
        )
    return rec, info


def anticipation_after_learning(
    recognizers: Mapping[str, Recognizer],
    engine: Engine,
    source: DataSource,
    *,
    seed: int = 0,
    candidates: Any = None,
) -> tuple[pd.DataFrame, dict[tuple[str, str], AnticipationRun]]:
    """What the robot anticipates and says with learned HMMs: the TCDS Fig. 5 cases
    (:data:`glu.studies.anticipation.experiment.CASES`) run with each recogniser (name → recogniser).

    Returns a table with one row per recogniser and case — hmms, case, p_hmm_tap and ObjVel_<value> at the
    last update, description (the best sentence among ``candidates``, the whole grammar for None) — and
    the runs by (hmms, case).
    """
    from glu.studies.anticipation.experiment import CASES, case_trajectory, effect_anticipation

    rows, runs = [], {}
    for name, recognizer in recognizers.items():
        for case, c in CASES.items():
            run = effect_anticipation(
                recognizer,
                engine,
                case_trajectory(source, case, seed=seed),
                c.evidence,
                case=case,
                models=name,
                describe="last",
                candidates=candidates,
            )
            runs[name, case] = run
            last = run.fused["ObjVel"][-1]
            rows.append(
                {"hmms": name, "case": case, "p_hmm_tap": float(run.p_hmm[-1, run.actions.index("tap")])}
                | {f"ObjVel_{v}": float(p) for v, p in zip(run.values["ObjVel"], last, strict=True)}
                | {"description": run.description}
            )
    return tidy(pd.DataFrame(rows), "learning_anticipation", source.describe(), seed=seed), runs


class RecordedLife(NamedTuple):
    """One labelling scheme's life beside the true labels' (:func:`recorded_life`).

    Attributes
    ----------
    run : the online run of both learners (the scheme first)
    features : the episodes' gestures, in the order seen
    scheme : the labelling scheme; ambiguity : the objects' description; held_out : held-out gestures
    """

    run: OnlineRun
    features: list[np.ndarray]
    scheme: str
    ambiguity: str
    held_out: int

    def recognizers(self) -> dict[str, Recognizer]:
        """What each learned at the end: ``"<scheme> labels"`` and ``"true labels"`` → its recogniser."""
        return {f"{self.scheme} labels": self.run.recognizer(0), "true labels": self.run.recognizer(1)}

    def scene(self) -> str:
        """The recording's description of the scene (Markdown)."""
        return (
            f"# Learning gestures from effects\n{self.scheme} labels, {self.ambiguity}; "
            f"{len(self.features)} episodes."
        )

    def summary(self) -> str:
        """Both learners' held-out accuracy at the end, in one line."""
        last = self.run.accuracy()[-1]
        return (
            f"after {len(self.features)} episodes: {self.scheme} labels {last[0]:.3f}, true labels "
            f"{last[1]:.3f} on {self.held_out} held-out gestures"
        )


def recorded_life(
    engine: Engine,
    scheme: str,
    episodes: int,
    test_per_action: int,
    seed: int = 0,
    settings: OnlineSettings | None = None,
    ambiguity: str = "mixed",
) -> RecordedLife:
    """Notebook 12's recorded learner: ``scheme`` labelling by the network's posteriors without words, and
    the true labels, learning online (:func:`~glu.studies.learning.online.run_online`) from the same
    ``episodes`` episodes of seed ``seed`` (easy world, ``ambiguity``'s objects), measured every 10 episodes
    on ``3 · test_per_action`` held-out gestures, balanced over the actions."""
    amb = AMBIGUITIES[ambiguity]
    seen = simulate_episodes(engine, amb, episodes, seed)
    test = simulate_episodes(engine, amb, 3 * test_per_action, seed, offset=TEST_OFFSET, balanced=True)
    p_bn = network_posteriors(engine, seen.perceived, seen.world)
    every = list(range(10, episodes + 1, 10)) or [episodes]
    run = run_online(
        seen.features,
        seen.actions,
        [Learner(scheme, "network"), Learner("true")],
        {"network": p_bn},
        test.features,
        test.actions,
        every,
        engine.bn.schema.values_of("Action"),
        settings or OnlineSettings(),
        seed,
    )
    return RecordedLife(run, seen.features, scheme, amb.description, len(test.features))
