"""The study of learning from effects: every labelling scheme and control, online, over seeds and worlds.

For each training seed (:func:`run_seed`) and each world
(:data:`~glu.studies.learning.self_supervised.WORLDS`): one stream of episodes (actions and gestures shared
by every ambiguity), the objects and effects of each ambiguity
(:data:`~glu.studies.learning.self_supervised.AMBIGUITIES`), the network's posteriors with and without
words, random labels as accurate as the network's, and every learner run online over the same episodes
(:func:`glu.studies.learning.online.run_online`), measured at the checkpoints on the same held-out gestures:
in each ambiguity, with and without words, each labelling scheme
(:data:`~glu.studies.learning.self_supervised.SCHEMES`) and each control
(:data:`~glu.studies.learning.self_supervised.CONTROLS`); once per world, the true labels, clusters named by
the true actions, and 1 and 5 true labels per action. The network alone (no gesture) is measured on the
held-out episodes of each ambiguity.

:func:`learning_study` runs the seeds (in this process, or as Dask tasks on a LocalCluster or an existing
scheduler, as ``glu evaluate`` does); :mod:`glu.studies.learning.tables` turns the results into tables, and
:mod:`glu.studies.learning.saved` saves and reads them (``glu learning-curves``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any, NamedTuple

import numpy as np

from glu.bn.inference import Engine
from glu.errors import DataError
from glu.machine import dask_client
from glu.studies.learning.online import Learner, OnlineSettings, run_online
from glu.studies.learning.self_supervised import (
    AMBIGUITIES,
    BASELINES,
    CONTROLS,
    EFFECTS,
    SCHEMES,
    SUPERVISED,
    TEST_OFFSET,
    WORLDS,
    draw_actions,
    draw_gestures,
    draw_world,
    matched_random_labels,
    network_posteriors,
)

CHECKPOINTS: tuple[int, ...] = (10, 20, 50, 100, 200, 500, 1000, 2000, 5000, 10000)
"""Where the curves are measured (those up to the number of episodes, the budgets, and that number)."""
BUDGETS: tuple[int, ...] = (100, 1000, 10000)
"""The fixed budgets (episodes seen) of the main table."""
MARGIN = 0.02
"""The equivalence margin on accuracy, declared before the data: a learner *matches* the true-label HMMs when
its gap to them lies within ± this (TOST, :func:`glu.stats.tost_p_value`)."""
BOOT_KEY, RANDOM_KEY = 5, 7
"""Spawn keys of the bootstrap's random numbers and of the random labels."""


@dataclass(frozen=True)
class StudySettings:
    """The study's size and conditions (the defaults are the saved study's, ``glu learning-curves``).

    Attributes
    ----------
    episodes : episodes each learner sees (per seed)
    seeds : training seeds (each: its own episodes, held-out gestures, random labels and EM starts)
    worlds : names of :data:`~glu.studies.learning.self_supervised.WORLDS`
    ambiguities : names of :data:`~glu.studies.learning.self_supervised.AMBIGUITIES`
    words : with words, without, or both
    schemes : labelling schemes; controls : the controls run beside them in every condition
    baselines : HMM baselines once per world (the network alone is always measured)
    supervised : the ``supervised`` learners' true labels per action
    test_per_action : held-out gestures per action and seed
    effects : the effect nodes the robot perceives
    online : how the learners learn (:class:`~glu.studies.learning.online.OnlineSettings`)
    budgets : the main table's budgets (those up to ``episodes``)
    margin : the equivalence margin on accuracy (:data:`MARGIN`)
    bootstrap : two-level bootstrap replicates
    """

    episodes: int = 10_000
    seeds: tuple[int, ...] = tuple(range(10))
    worlds: tuple[str, ...] = tuple(WORLDS)
    ambiguities: tuple[str, ...] = tuple(AMBIGUITIES)
    words: tuple[bool, ...] = (False, True)
    schemes: tuple[str, ...] = SCHEMES
    controls: tuple[str, ...] = CONTROLS
    baselines: tuple[str, ...] = BASELINES
    supervised: tuple[int, ...] = SUPERVISED
    test_per_action: int = 30
    effects: tuple[str, ...] = EFFECTS
    online: OnlineSettings = field(default_factory=OnlineSettings)
    budgets: tuple[int, ...] = BUDGETS
    margin: float = MARGIN
    bootstrap: int = 2000

    def __post_init__(self) -> None:
        if not (isinstance(self.episodes, int) and 10 <= self.episodes <= 1_000_000):
            raise DataError(f"episodes={self.episodes!r}: a whole number from 10 to 1,000,000")
        if not isinstance(self.seeds, tuple | list) or not all(_whole(k) for k in self.seeds):
            raise DataError(f"seeds={self.seeds!r}: a list of whole numbers ≥ 0")
        if not self.seeds or len(set(self.seeds)) != len(self.seeds):
            raise DataError(f"seeds {list(self.seeds)}: give at least one, each once")
        for name, allowed in (("world", WORLDS), ("ambiguity", AMBIGUITIES)):
            given = getattr(self, "worlds" if name == "world" else "ambiguities")
            bad = [a for a in given if a not in allowed]
            if bad or not given:
                raise DataError(f"unknown {name} {bad[:1] or '(none)'}; allowed: {', '.join(allowed)}")
        bad = (
            [s for s in self.schemes if s not in SCHEMES]
            + [c for c in self.controls if c not in CONTROLS]
            + [b for b in self.baselines if b not in BASELINES]
        )
        if bad:
            raise DataError(
                f"unknown learner {bad[0]!r}; allowed: {', '.join(SCHEMES + CONTROLS + BASELINES)}"
            )
        if "true" not in self.baselines:
            raise DataError(
                "the study measures every learner against the true labels: keep the 'true' baseline"
            )
        if any(isinstance(k, bool) or not isinstance(k, int) or k < 1 for k in self.supervised):
            raise DataError(f"supervised={list(self.supervised)!r}: labels per action, whole numbers ≥ 1")
        if not self.words or any(not isinstance(w, bool) for w in self.words):
            raise DataError(f"words={list(self.words)!r}: True, False or both")
        if not (isinstance(self.test_per_action, int) and self.test_per_action >= 1):
            raise DataError(f"test_per_action={self.test_per_action!r}: a whole number ≥ 1")
        if not (isinstance(self.bootstrap, int) and 0 <= self.bootstrap <= 100_000):
            raise DataError(f"bootstrap={self.bootstrap!r}: a whole number of replicates")
        if not (isinstance(self.margin, int | float) and 0 < self.margin < 1):
            raise DataError(f"margin={self.margin!r}: the equivalence margin, an accuracy in (0, 1)")
        if not self.budgets or any(
            isinstance(b, bool) or not isinstance(b, int) or b < 1 for b in self.budgets
        ):
            raise DataError(f"budgets={list(self.budgets)!r}: episodes, whole numbers ≥ 1")

    @property
    def checkpoints(self) -> tuple[int, ...]:
        """:data:`CHECKPOINTS` and the budgets up to ``episodes``, and ``episodes``."""
        marks = set(CHECKPOINTS) | set(self.main_budgets)
        return tuple(sorted({c for c in marks if c <= self.episodes} | {self.episodes}))

    @property
    def main_budgets(self) -> tuple[int, ...]:
        """The budgets the episodes reach (the main table's); ``episodes`` itself when they reach none."""
        return tuple(b for b in sorted(self.budgets) if b <= self.episodes) or (self.episodes,)

    def world_learners(self) -> list[tuple[str, str, bool | None]]:
        """The learners of one world as (learner, ambiguity, words): the baselines (ambiguity ``""``, words
        None; ``supervised_K`` for K labels per action), then every scheme and control per condition."""
        out: list[tuple[str, str, bool | None]] = [(b, "", None) for b in self.baselines]
        out += [(f"supervised_{k}", "", None) for k in self.supervised]
        out += [(s, a, w) for a in self.ambiguities for w in self.words for s in self.schemes + self.controls]
        return out

    def learners(self) -> list[tuple[str, str, str, bool | None]]:
        """Every learner as (world, learner, ambiguity, words)."""
        return [(wd, *lr) for wd in self.worlds for lr in self.world_learners()]

    def as_dict(self) -> dict[str, Any]:
        """The settings as plain data (the tables' parameters)."""
        return settings_dict(self)


NOTEBOOK_FIELDS: tuple[str, ...] = (
    "seeds",
    "worlds",
    "ambiguities",
    "test_per_action",
    "budgets",
    "margin",
    "bootstrap",
)
"""The fields of :class:`StudySettings` that notebook 12's parameters of the same names give."""


def _whole(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool) and v >= 0


def settings_from_parameters(params: Mapping[str, Any]) -> StudySettings:
    """The study's settings from notebook 12's parameters (its cell's names, :data:`NOTEBOOK_FIELDS`; a list
    becomes a tuple; other names in ``params`` are ignored): each learner sees as many episodes as the
    largest budget. One call instead of the fields one by one, the values checked as
    :class:`StudySettings` checks them (:class:`~glu.errors.DataError`, one line)."""
    given = {k: tuple(v) if isinstance(v, list) else v for k, v in params.items() if k in NOTEBOOK_FIELDS}
    budgets = given.get("budgets")
    if isinstance(budgets, tuple) and budgets and all(_whole(b) for b in budgets):
        given["episodes"] = max(budgets)
    return StudySettings(**given)


def settings_dict(settings: Any) -> dict[str, Any]:
    """Settings (a dataclass with an :class:`~glu.studies.learning.online.OnlineSettings` ``online``) as
    plain data."""
    d = asdict(settings)
    d["online"] = {**d["online"], "config": settings.online.config.as_dict()}
    return d


class SeedResult(NamedTuple):
    """One seed's measurements.

    Attributes
    ----------
    seed : the seed
    learners : (world, learner, ambiguity, words) of each learner, the order of ``correct``'s L axis
    checkpoints : episodes seen at each measurement, shape (C,)
    correct : bool array, shape (C, L, J) — held-out gestures recognised right (J per world, the same
        actions in every world)
    groups : (world, ambiguity, words) of each row of ``network_correct`` and ``labels``
    network_correct : bool array, shape (G, J) — the network alone on the held-out episodes
    labels : per group: the training labels' arg-max accuracy, the fraction above the ``confident``
        threshold, the accuracy of those, the mean ``p_BN`` of the true action, the random labels'
        accuracy; shape (G, 5)
    update_seconds : the lockstep update of every learner after each episode, shape (episodes,)
    """

    seed: int
    learners: list[tuple[str, str, str, bool | None]]
    checkpoints: np.ndarray
    correct: np.ndarray
    groups: list[tuple[str, str, bool]]
    network_correct: np.ndarray
    labels: np.ndarray
    update_seconds: np.ndarray


def _spec(learner: str, ambiguity: str, words: bool | None) -> Learner:
    if learner.startswith("supervised_"):
        return Learner("supervised", int(learner.split("_")[1]))
    if learner in BASELINES:
        return Learner(learner)
    return Learner(learner, ("random" if learner == "random" else "network", ambiguity, words))


def _label_quality(p: np.ndarray, random: np.ndarray, actions: np.ndarray, threshold: float) -> list[float]:
    top = p.max(axis=1)
    right = p.argmax(axis=1) == actions
    sure = top >= threshold
    return [
        right.mean(),
        sure.mean(),
        right[sure].mean() if sure.any() else np.nan,
        p[np.arange(len(p)), actions].mean(),
        (random.argmax(axis=1) == actions).mean(),
    ]


def run_world(engine: Engine, seed: int, world: str, settings: StudySettings):
    """One seed in one world: every learner run online, the network alone, the labels' quality.

    Returns ``(run, groups, network_correct, labels)`` (see :class:`SeedResult`; ``run`` is the
    :class:`~glu.studies.learning.online.OnlineRun` of :meth:`StudySettings.world_learners`)."""
    s, wd = settings, WORLDS[world]
    actions = engine.bn.schema.values_of("Action")
    n_test = s.test_per_action * len(actions)
    train_actions = draw_actions(engine, s.episodes, seed)
    features = draw_gestures(engine, train_actions, seed, 0, world=wd)
    test_actions = draw_actions(engine, n_test, seed, TEST_OFFSET, balanced=True)
    test_features = draw_gestures(engine, test_actions, seed, TEST_OFFSET, world=wd)
    sources, groups, network, labels = {}, [], [], []
    for name in s.ambiguities:
        amb = AMBIGUITIES[name]
        drawn, seen = draw_world(engine, train_actions, amb, seed, 0, s.effects, wd)
        test_drawn, test_seen = draw_world(engine, test_actions, amb, seed, TEST_OFFSET, s.effects, wd)
        for words in s.words:
            p = network_posteriors(engine, seen, drawn, words)
            key = (list(WORLDS).index(world), list(AMBIGUITIES).index(name), int(words))
            rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(RANDOM_KEY, *key)))
            accuracy = float((p.argmax(axis=1) == train_actions).mean())
            random = matched_random_labels(train_actions, accuracy, len(actions), rng)
            sources["network", name, words], sources["random", name, words] = p, random
            groups.append((world, name, words))
            labels.append(_label_quality(p, random, train_actions, s.online.threshold))
            pt = network_posteriors(engine, test_seen, test_drawn, words)
            network.append(pt.argmax(axis=1) == test_actions)
    specs = [_spec(*lr) for lr in s.world_learners()]
    run = run_online(
        features,
        train_actions,
        specs,
        sources,
        test_features,
        test_actions,
        s.checkpoints,
        actions,
        s.online,
        seed,
    )
    return run, groups, np.array(network), np.array(labels)


def run_seed(engine: Engine, seed: int, settings: StudySettings = StudySettings()) -> SeedResult:
    """Simulate one seed's episodes and held-out gestures in every world and run every learner on them (a Dask
    task)."""
    correct, groups, network, labels, seconds = [], [], [], [], np.zeros(settings.episodes)
    for world in settings.worlds:
        run, g, net, lab = run_world(engine, seed, world, settings)
        correct.append(run.correct)
        groups += g
        network.append(net)
        labels.append(lab)
        seconds += run.update_seconds
    return SeedResult(
        seed,
        settings.learners(),
        np.array(settings.checkpoints),
        np.concatenate(correct, axis=1),
        groups,
        np.concatenate(network),
        np.concatenate(labels),
        seconds,
    )


def learning_study(
    engine: Engine,
    settings: StudySettings = StudySettings(),
    *,
    workers: int = 0,
    scheduler: str | None = None,
    progress: Callable[[int], None] | None = None,
) -> list[SeedResult]:
    """Run every seed of the study, one task each (here or on Dask, as :func:`run_units` runs them); results
    in the order of the seeds."""
    return run_units(run_seed, engine, settings, settings.seeds, workers, scheduler, progress)


def run_units(
    task: Callable, engine: Engine, settings: Any, units: Sequence[Any], workers, scheduler, progress
) -> list[Any]:
    """``[task(engine, unit, settings) for unit in units]``: here (``workers=0``, no scheduler), or as Dask
    tasks on a LocalCluster of ``workers`` single-threaded processes or an existing ``scheduler``
    (``tcp://host:port``); ``progress(unit)`` after each (if given); Ctrl-C kills the local workers."""
    if scheduler is None and not workers:
        out = []
        for u in units:
            out.append(task(engine, u, settings))
            if progress is not None:
                progress(u)
        return out
    from distributed import as_completed

    with dask_client(workers, scheduler, dashboard_address=None) as client:
        futures = {client.submit(task, engine, u, settings, pure=False): i for i, u in enumerate(units)}
        results = {}
        for fut in as_completed(futures):
            results[futures[fut]] = fut.result()
            if progress is not None:
                progress(units[futures[fut]])
        return [results[i] for i in range(len(units))]


def update_times(results: Sequence[SeedResult]) -> dict[str, float]:
    """Seconds of the lockstep update of every learner after one episode: median, 95th percentile and
    maximum over all seeds' episodes but each seed's first (which loads the compiled kernels)."""
    t = np.concatenate([r.update_seconds[1:] for r in results])
    return {"median": float(np.median(t)), "p95": float(np.percentile(t, 95)), "max": float(t.max())}
