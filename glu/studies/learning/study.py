"""The study of learning from effects: learning curves of every labelling scheme and baseline, with intervals.

For each training seed (:func:`run_seed`): one stream of episodes (actions and gestures shared by every
ambiguity), the world of each ambiguity (:data:`~glu.studies.learning.self_supervised.AMBIGUITIES`), the
network's posteriors with and without words, and every learner — each labelling scheme in each ambiguity
with and without words, and the baselines (true labels, unsupervised clusters) — run online over the same
episodes (:func:`glu.studies.learning.online.run_online`), measured at the checkpoints on the same
held-out gestures. The network alone (no gestures) is measured on the held-out episodes of each ambiguity.

:func:`learning_study` runs the seeds (in this process, or as Dask tasks on a LocalCluster or an existing
scheduler, as ``glu evaluate`` does) and returns the tidy tables:

* :func:`curves_table` — accuracy against episodes seen, with two-level intervals (seeds × held-out episodes,
  :mod:`glu.stats`), and the paired gap to the true-label HMMs;
* :func:`match_table` — how many episodes each learner needs to match the true-label HMMs within the
  interval (the gap's interval reaches 0 at that checkpoint and at every later one), or none;
* :func:`labels_table` — how good the network's labels are in each ambiguity.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any, NamedTuple

import numpy as np
import pandas as pd

from glu.bn.inference import Engine
from glu.errors import DataError
from glu.machine import close_cluster, ctrl_c_held, kill_local_workers, quiet_dask_logs
from glu.stats import interval, replicate_means, two_level_weights
from glu.studies.learning.online import Learner, OnlineSettings, run_online
from glu.studies.learning.self_supervised import (
    AMBIGUITIES,
    BASELINES,
    EFFECTS,
    SCHEMES,
    TEST_OFFSET,
    draw_actions,
    draw_gestures,
    draw_world,
    network_posteriors,
)
from glu.tidy import tidy

CHECKPOINTS: tuple[int, ...] = (10, 20, 50, 100, 200, 500, 1000, 2000, 5000, 10000)
"""Where the curves are measured (those up to the number of episodes, and that number itself)."""
BOOT_KEY = 5
"""Spawn key of the bootstrap's random numbers."""


@dataclass(frozen=True)
class StudySettings:
    """The study's size and conditions (the defaults are the notebook's).

    Attributes
    ----------
    episodes : episodes each learner sees (per seed)
    seeds : training seeds (each: its own episodes, held-out gestures and EM starts)
    ambiguities : names of :data:`~glu.studies.learning.self_supervised.AMBIGUITIES`
    words : with words, without, or both
    schemes : labelling schemes; baselines : HMM baselines (the network alone is always measured)
    test_per_action : held-out gestures per action and seed
    noise : sensor noise of the gestures (m)
    effects : the effect nodes the robot perceives
    online : how the learners learn (:class:`~glu.studies.learning.online.OnlineSettings`)
    bootstrap : two-level bootstrap replicates
    """

    episodes: int = 300
    seeds: tuple[int, ...] = (0, 1, 2)
    ambiguities: tuple[str, ...] = tuple(AMBIGUITIES)
    words: tuple[bool, ...] = (False, True)
    schemes: tuple[str, ...] = SCHEMES
    baselines: tuple[str, ...] = BASELINES
    test_per_action: int = 15
    noise: float = 0.02
    effects: tuple[str, ...] = EFFECTS
    online: OnlineSettings = field(default_factory=OnlineSettings)
    bootstrap: int = 1000

    def __post_init__(self) -> None:
        if not (isinstance(self.episodes, int) and 10 <= self.episodes <= 1_000_000):
            raise DataError(f"episodes={self.episodes!r}: a whole number from 10 to 1,000,000")
        if not self.seeds or len(set(self.seeds)) != len(self.seeds):
            raise DataError(f"seeds {list(self.seeds)}: give at least one, each once")
        bad = [a for a in self.ambiguities if a not in AMBIGUITIES]
        if bad or not self.ambiguities:
            raise DataError(f"unknown ambiguity {bad[:1] or '(none)'}; allowed: {', '.join(AMBIGUITIES)}")
        bad = [s for s in self.schemes if s not in SCHEMES] + [
            b for b in self.baselines if b not in BASELINES
        ]
        if bad:
            raise DataError(f"unknown learner {bad[0]!r}; allowed: {', '.join(SCHEMES + BASELINES)}")
        if not self.words or any(not isinstance(w, bool) for w in self.words):
            raise DataError(f"words={list(self.words)!r}: True, False or both")
        if not (isinstance(self.test_per_action, int) and self.test_per_action >= 1):
            raise DataError(f"test_per_action={self.test_per_action!r}: a whole number ≥ 1")
        if not (isinstance(self.bootstrap, int) and 0 <= self.bootstrap <= 100_000):
            raise DataError(f"bootstrap={self.bootstrap!r}: a whole number of replicates")

    @property
    def checkpoints(self) -> tuple[int, ...]:
        """:data:`CHECKPOINTS` up to ``episodes``, and ``episodes``."""
        return tuple(sorted({c for c in CHECKPOINTS if c <= self.episodes} | {self.episodes}))

    def learners(self) -> list[tuple[str, str, bool | None]]:
        """Every learner as (learner, ambiguity, words); baselines have ambiguity ``""`` and words None."""
        out: list[tuple[str, str, bool | None]] = [(b, "", None) for b in self.baselines]
        out += [(s, a, w) for a in self.ambiguities for w in self.words for s in self.schemes]
        return out

    def as_dict(self) -> dict[str, Any]:
        """The settings as plain data (the tables' parameters)."""
        d = asdict(self)
        d["online"] = {**d["online"], "config": self.online.config.as_dict()}
        return d


class SeedResult(NamedTuple):
    """One seed's measurements.

    Attributes
    ----------
    seed : the seed
    learners : (learner, ambiguity, words) of each learner, the order of ``correct``'s L axis
    checkpoints : episodes seen at each measurement, shape (C,)
    correct : bool array, shape (C, L, J) — held-out gestures recognised right
    groups : (ambiguity, words) of each row of ``network_correct`` and ``labels``
    network_correct : bool array, shape (G, J) — the network alone on the held-out episodes
    labels : per group: the training labels' arg-max accuracy, the fraction above the ``confident``
        threshold, the accuracy of those, the mean ``p_BN`` of the true action; shape (G, 4)
    update_seconds : the lockstep update of every learner after each episode, shape (episodes,)
    """

    seed: int
    learners: list[tuple[str, str, bool | None]]
    checkpoints: np.ndarray
    correct: np.ndarray
    groups: list[tuple[str, bool]]
    network_correct: np.ndarray
    labels: np.ndarray
    update_seconds: np.ndarray


def run_seed(engine: Engine, seed: int, settings: StudySettings = StudySettings()) -> SeedResult:
    """Simulate one seed's episodes and held-out gestures and run every learner on them (a Dask task)."""
    s = settings
    actions = engine.bn.schema.values_of("Action")
    n_test = s.test_per_action * len(actions)
    train_actions = draw_actions(engine, s.episodes, seed)
    features = draw_gestures(engine, train_actions, seed, 0, s.noise)
    test_actions = draw_actions(engine, n_test, seed, TEST_OFFSET, balanced=True)
    test_features = draw_gestures(engine, test_actions, seed, TEST_OFFSET, s.noise)
    p_bn, groups, network, labels = {}, [], [], []
    for name in s.ambiguities:
        amb = AMBIGUITIES[name]
        world, seen = draw_world(engine, train_actions, amb, seed, 0, s.effects)
        test_world, test_seen = draw_world(engine, test_actions, amb, seed, TEST_OFFSET, s.effects)
        for words in s.words:
            p = network_posteriors(engine, seen, world, words)
            p_bn[name, words] = p
            groups.append((name, words))
            top = p.max(axis=1)
            right = p.argmax(axis=1) == train_actions
            sure = top >= s.online.threshold
            labels.append(
                [
                    right.mean(),
                    sure.mean(),
                    right[sure].mean() if sure.any() else np.nan,
                    p[np.arange(len(p)), train_actions].mean(),
                ]
            )
            pt = network_posteriors(engine, test_seen, test_world, words)
            network.append(pt.argmax(axis=1) == test_actions)
    learners = s.learners()
    specs = [Learner(lr, None if lr in BASELINES else (a, w)) for lr, a, w in learners]
    run = run_online(
        features,
        train_actions,
        specs,
        p_bn,
        test_features,
        test_actions,
        s.checkpoints,
        actions,
        s.online,
        seed,
    )
    return SeedResult(
        seed,
        learners,
        run.checkpoints,
        run.correct,
        groups,
        np.array(network),
        np.array(labels),
        run.update_seconds,
    )


def learning_study(
    engine: Engine,
    settings: StudySettings = StudySettings(),
    *,
    workers: int = 0,
    scheduler: str | None = None,
    progress: Callable[[int], None] | None = None,
) -> list[SeedResult]:
    """Run every seed of the study: in this process (``workers=0``, no scheduler), on a Dask LocalCluster of
    ``workers`` single-threaded processes, or on an existing Dask scheduler (``tcp://host:port``); one task
    per seed. ``progress`` is called with each finished seed. Results are in the order of the seeds."""
    if scheduler is None and not workers:
        out = []
        for sd in settings.seeds:
            out.append(run_seed(engine, sd, settings))
            if progress is not None:
                progress(sd)
        return out
    with quiet_dask_logs():
        return _on_dask(engine, settings, workers, scheduler, progress)


def _on_dask(engine, settings, workers, scheduler, progress) -> list[SeedResult]:
    from dask.distributed import Client, LocalCluster, as_completed

    cluster = None
    try:
        with ctrl_c_held():  # Ctrl-C reaches this process only; the workers are stopped from here
            if scheduler is None:
                cluster = LocalCluster(
                    n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
                )
            client = Client(cluster if cluster is not None else scheduler)
    except BaseException as e:
        close_cluster(cluster, e)
        raise
    try:
        futures = {client.submit(run_seed, engine, sd, settings, pure=False): sd for sd in settings.seeds}
        results = {}
        for fut in as_completed(futures):
            results[futures[fut]] = fut.result()
            if progress is not None:
                progress(futures[fut])
        return [results[sd] for sd in settings.seeds]
    except KeyboardInterrupt:  # Ctrl-C, SIGTERM: the workers are killed, not asked to finish
        kill_local_workers(cluster)
        raise
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def _stack(results: Sequence[SeedResult]) -> tuple[np.ndarray, np.ndarray]:
    """Per-(seed, held-out episode) correctness: learners (S, J, C, L) and the network (S, J, G)."""
    correct = np.stack([np.moveaxis(r.correct, 2, 0) for r in results])  # (S, J, C, L)
    network = np.stack([r.network_correct.T for r in results])  # (S, J, G)
    return correct.astype(float), network.astype(float)


def curves_table(
    results: Sequence[SeedResult], settings: StudySettings = StudySettings(), data_source: str = ""
) -> pd.DataFrame:
    """Accuracy against episodes seen, per learner, ambiguity and words, with two-level intervals.

    Columns: learner (a scheme, ``true``, ``unsupervised``, or ``network``), ambiguity and words (empty and
    None for the HMM baselines, the same in every condition), episodes, accuracy, ci_low, ci_high, gap
    (accuracy − the true-label HMMs' on the same seeds and episodes), gap_low, gap_high, seeds,
    test_gestures. The network's rows repeat its (episode-free) accuracy at every checkpoint.
    """
    first = results[0]
    correct, network = _stack(results)
    S, J, C, L = correct.shape
    rng = np.random.default_rng(np.random.SeedSequence(list(settings.seeds), spawn_key=(BOOT_KEY,)))
    W = two_level_weights(S, J, settings.bootstrap, rng)
    reps = replicate_means(correct, W)  # (B + 1, C, L)
    lo, hi = interval(reps)
    names = [lr for lr, _, _ in first.learners]
    if "true" in names:
        t = names.index("true")
        gap_reps = reps - reps[:, :, t : t + 1]
        gap_lo, gap_hi = interval(gap_reps)
        gap = gap_reps[0]
    else:
        gap = gap_lo = gap_hi = np.full((C, L), np.nan)
    rows = []
    for c, n in enumerate(first.checkpoints):
        for k, (lr, amb, words) in enumerate(first.learners):
            rows.append(
                dict(
                    learner=lr,
                    ambiguity=amb,
                    words=words,
                    episodes=int(n),
                    accuracy=reps[0, c, k],
                    ci_low=lo[c, k],
                    ci_high=hi[c, k],
                    gap=gap[c, k],
                    gap_low=gap_lo[c, k],
                    gap_high=gap_hi[c, k],
                )
            )
    net = replicate_means(network, W)  # (B + 1, G)
    net_lo, net_hi = interval(net)
    net_gap = net - reps[:, -1:, names.index("true")] if "true" in names else None
    for g, (amb, words) in enumerate(first.groups):
        glo, ghi = interval(net_gap[:, g]) if net_gap is not None else (np.nan, np.nan)
        for n in first.checkpoints:
            rows.append(
                dict(
                    learner="network",
                    ambiguity=amb,
                    words=words,
                    episodes=int(n),
                    accuracy=net[0, g],
                    ci_low=net_lo[g],
                    ci_high=net_hi[g],
                    gap=net_gap[0, g] if net_gap is not None else np.nan,
                    gap_low=glo,
                    gap_high=ghi,
                )
            )
    df = pd.DataFrame(rows)
    df["seeds"], df["test_gestures"] = S, J
    return tidy(df, "learning_curves", data_source, **settings.as_dict())


def match_table(curves: pd.DataFrame) -> pd.DataFrame:
    """For every learner, ambiguity and words: the episodes after which the learned HMMs match the
    true-label HMMs within the interval (the gap's interval reaches 0 there and at every later checkpoint;
    NaN if not by the last), and the accuracies and gap at the last checkpoint."""
    rows = []
    hmm = curves[~curves["learner"].isin(["true", "network"])]
    for (lr, amb, words), g in hmm.groupby(["learner", "ambiguity", "words"], sort=False, dropna=False):
        g = g.sort_values("episodes")
        ok = (g["gap_high"] >= 0).to_numpy()
        tail = np.flatnonzero(~ok)
        at = g["episodes"].iloc[tail[-1] + 1] if len(tail) and tail[-1] + 1 < len(g) else None
        if not len(tail):
            at = g["episodes"].iloc[0]
        last = g.iloc[-1]
        rows.append(
            dict(
                learner=lr,
                ambiguity=amb,
                words=words,
                episodes_to_match=np.nan if at is None else float(at),
                last_episodes=int(last["episodes"]),
                accuracy=last["accuracy"],
                true_accuracy=last["accuracy"] - last["gap"],
                gap=last["gap"],
                gap_low=last["gap_low"],
                gap_high=last["gap_high"],
            )
        )
    return tidy(
        pd.DataFrame(rows),
        "learning_match",
        curves.attrs.get("data_source", ""),
        **curves.attrs.get("parameters", {}),
    )


def match_lines(match: pd.DataFrame) -> list[str]:
    """One line per condition (ambiguity × words) saying, from :func:`match_table`, which schemes match the
    true-label HMMs and after how many episodes, and the best scheme's accuracy at the last checkpoint; then
    a line counting the conditions where some scheme matches."""
    lines, hit = [], 0
    schemes = match[match["learner"].isin(SCHEMES)]
    for (amb, words), g in schemes.groupby(["ambiguity", "words"], sort=False):
        reached = g[g["episodes_to_match"].notna()]
        hit += len(reached) > 0
        said = (
            ", ".join(f"{r.learner} after {r.episodes_to_match:,.0f}" for r in reached.itertuples()) or "none"
        )
        best = g.loc[g["accuracy"].idxmax()]
        lines.append(
            f"{amb}, {'with' if words else 'without'} words: matched by {said}; at "
            f"{int(best['last_episodes']):,} episodes, best {best['learner']} {best['accuracy']:.3f} "
            f"against {best['true_accuracy']:.3f} with true labels"
        )
    n = schemes.groupby(["ambiguity", "words"]).ngroups
    lines.append(f"some labelling scheme matches the true-label HMMs in {hit} of {n} conditions")
    return lines


def labels_table(
    results: Sequence[SeedResult], settings: StudySettings = StudySettings(), data_source: str = ""
) -> pd.DataFrame:
    """How good the network's labels of the training episodes are, per ambiguity and words (mean over
    seeds): label_accuracy (its arg-max), confident_fraction and confident_accuracy (above the ``confident``
    threshold), mean_p_true (its probability of the true action)."""
    first = results[0]
    stacked = np.stack([r.labels for r in results])
    with warnings.catch_warnings():  # a group without confident labels in any seed stays NaN
        warnings.simplefilter("ignore", RuntimeWarning)
        labels = np.nanmean(stacked, axis=0)
    rows = [
        dict(
            ambiguity=amb,
            words=words,
            description=AMBIGUITIES[amb].description,
            label_accuracy=v[0],
            confident_fraction=v[1],
            confident_accuracy=v[2],
            mean_p_true=v[3],
        )
        for (amb, words), v in zip(first.groups, labels, strict=True)
    ]
    return tidy(pd.DataFrame(rows), "learning_labels", data_source, **settings.as_dict())


def update_times(results: Sequence[SeedResult]) -> dict[str, float]:
    """Seconds of the lockstep update of every learner after one episode: median, 95th percentile and
    maximum over all seeds' episodes but each seed's first (which loads the compiled kernels)."""
    t = np.concatenate([r.update_seconds[1:] for r in results])
    return {"median": float(np.median(t)), "p95": float(np.percentile(t, 95)), "max": float(t.max())}
