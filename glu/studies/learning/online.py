"""Learning gestures online, as a robot would live it: one episode at a time, from no gesture model at all.

Each **learner** (a labelling scheme of :mod:`glu.studies.learning.self_supervised`, in one ambiguity, with or
without words) keeps, per action, the sufficient statistics of what it has seen
(:class:`glu.hmm.SufficientStats`) and its current HMM. After each episode it

1. labels the episode: from its network alone (``hard``, ``soft``, ``confident``), from random labels given
   to it (``random``), from the product rule of its current HMMs and its network once it has a model of every
   action (``iterative``, p_HMM read per frame; ``em``, the likelihood itself; before that the network
   alone), from the true action (``true``; ``supervised``: the first K episodes of each action only), or
   from its HMMs alone (``unsupervised`` and ``clustering``: the clusters are named after the fact by the
   best matching with the true actions seen so far, or with the network's posteriors);
2. runs the E-step of the episode under each of its models, and for each action with a label weight ``w > 0``
   makes a stepwise-EM step (:class:`glu.hmm.online.OnlineModels`: the running weighted mean of the
   statistics ``s ← (1 − η) s + η s_episode`` with ``η = w / W^α``, ``W`` the action's label weight so far,
   then the M-step of ``W · s``). With ``α = 1`` (the default) this is the plain accumulation
   ``Σ w s_episode``; ``α < 1`` forgets the early episodes faster;
3. an action without a model buffers its labelled episodes until their weight reaches ``init_weight``, then
   trains its first model on them (weighted EM, a few iterations). The clustering learners first cluster
   their first ``cluster_episodes`` episodes (k-means on the resampled trajectories).

Many learners watch the same episodes (the gestures are the same in every ambiguity): :func:`run_online` runs
them in lockstep, the E-step of every learner's every model on each episode in one call
(:meth:`glu.hmm.online.OnlineModels.estep`), and measures them all on the same held-out gestures at the
checkpoints. The model arithmetic (statistics, steps, M-steps, first models) is :mod:`glu.hmm.online`'s;
this module is the study: the learners, their labels and buffers, the clustering, the checkpoints.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np

from glu.errors import DataError
from glu.gestures.recognizer import Recognizer
from glu.hmm import (
    GestureHMM,
    GMMHMMParams,
    OnlineModels,
    SufficientStats,
    TrainingConfig,
    first_model,
    kmeans_labels,
)
from glu.studies.episodes import check_probability
from glu.studies.learning.self_supervised import (
    ONLINE_LEARNERS,
    POSTERIOR_READINGS,
    STUDY_TRAINING,
    best_matching,
    first_labels,
    label_weights,
    one_hot,
    p_hmm_reading,
    resampled,
)


@dataclass(frozen=True)
class OnlineSettings:
    """How the online learners learn.

    Attributes
    ----------
    config : the HMMs (states, Gaussians, covariance prior; ``n_iter`` and ``tol`` are unused online)
    init_weight : an action's first model is trained once its buffered label weight reaches this
    init_iter : EM iterations of that first training
    step : ``α`` of the stepwise-EM step ``η = w / W^α``, in (0.5, 1]; 1 accumulates
    threshold : the ``confident`` scheme's
    posterior : how ``iterative`` and ``unsupervised`` read ``p_HMM`` (:data:`POSTERIOR_READINGS`)
    cluster_episodes : the unsupervised learner clusters this many first episodes
    """

    config: TrainingConfig = STUDY_TRAINING
    init_weight: float = 3.0
    init_iter: int = 10
    step: float = 1.0
    threshold: float = 0.9
    posterior: str = "per-frame"
    cluster_episodes: int = 15

    def __post_init__(self) -> None:
        if not (isinstance(self.init_weight, int | float) and self.init_weight > 0):
            raise DataError(f"init_weight={self.init_weight!r}: a number > 0")
        if not (isinstance(self.init_iter, int) and self.init_iter >= 1):
            raise DataError(f"init_iter={self.init_iter!r}: a whole number ≥ 1")
        if not (isinstance(self.step, int | float) and 0.5 < self.step <= 1):
            raise DataError(f"step={self.step!r}: the stepwise-EM exponent must be in (0.5, 1]")
        check_probability(self.threshold, "threshold")
        if self.posterior not in POSTERIOR_READINGS:
            raise DataError(f"posterior={self.posterior!r}; allowed: {', '.join(POSTERIOR_READINGS)}")
        if not (isinstance(self.cluster_episodes, int) and self.cluster_episodes >= 3):
            raise DataError(f"cluster_episodes={self.cluster_episodes!r}: a whole number ≥ 3")


class Learner(NamedTuple):
    """One learner: its labelling scheme (:data:`~glu.studies.learning.self_supervised.ONLINE_LEARNERS`) and
    the labels' source, a key of the ``p_bn`` mapping given to :func:`run_online` (None for ``true`` and
    ``unsupervised``; for ``supervised``, how many labelled episodes per action)."""

    scheme: str
    source: Any = None


class OnlineRun(NamedTuple):
    """What :func:`run_online` returns.

    Attributes
    ----------
    learners : the learners, in the order of every ``L`` axis
    actions : the action names, in the order of every ``A`` axis
    checkpoints : episodes seen at each measurement, shape (C,)
    correct : bool array, shape (C, L, J) — each held-out gesture recognised right
    weights : array, shape (N, L, A) — the label weight each episode got from each learner
    episode_actions : int array, shape (N,); test_actions : int array, shape (J,)
    means : array, shape (C, L, A, Q, D) — each model's state means (the first Gaussian), NaN without a model
    params : the final models, stacked: each array with leading axes (L, A); ``exists`` (L, A) says which are
        real
    matching : int array, shape (C, L, A) — the unsupervised learners' cluster → action at each checkpoint
        (the identity for the others)
    update_seconds : CPU seconds (this thread) of each episode's update of every learner, shape (N,): the
        measurements taken at the checkpoints are not included
    """

    learners: list[Learner]
    actions: tuple[str, ...]
    checkpoints: np.ndarray
    correct: np.ndarray
    weights: np.ndarray
    episode_actions: np.ndarray
    test_actions: np.ndarray
    means: np.ndarray
    params: GMMHMMParams
    exists: np.ndarray
    matching: np.ndarray
    update_seconds: np.ndarray

    def accuracy(self) -> np.ndarray:
        """Held-out accuracy of every learner at every checkpoint, shape (C, L)."""
        return self.correct.mean(axis=2)

    def recognizer(self, learner: int, meta: Mapping[str, Any] | None = None) -> Recognizer:
        """The final models of one learner as a recogniser (actions without a model left out; the
        unsupervised learner's clusters named by their final matching)."""
        perm = self.matching[-1, learner]
        models = {}
        for a in range(len(self.actions)):
            if self.exists[learner, a]:
                name = self.actions[perm[a]]
                p = GMMHMMParams(*(x[learner, a] for x in self.params))
                models[name] = GestureHMM(*p, name=name)
        ordered = {a: models[a] for a in self.actions if a in models}
        return Recognizer(ordered, meta={"scheme": self.learners[learner].scheme, **(meta or {})})


@dataclass
class _State:
    """The learners' models over (learner, action) and the episodes each action without a model has
    buffered."""

    models: OnlineModels
    buffers: list[list[list[tuple[int, float]]]] = field(default_factory=list)


class _Labels:
    """How each learner labels each episode: the static labels, computed once, and the rules of those that
    read their own HMMs (:func:`run_online`); every learner's labels of one episode in a few array
    operations."""

    def __init__(self, learners, episode_actions, p_bn, A: int, settings: OnlineSettings) -> None:
        L = len(learners)
        true = np.asarray(episode_actions)
        self.learners, self.settings = list(learners), settings
        static: dict[int, np.ndarray] = {}
        for k, lr in enumerate(learners):
            if lr.scheme in ("hard", "soft", "confident"):
                static[k] = label_weights(lr.scheme, p_bn[lr.source], settings.threshold)
            elif lr.scheme == "random":  # one-hot labels drawn by the caller
                static[k] = label_weights("hard", p_bn[lr.source])
            elif lr.scheme == "true":
                static[k] = one_hot(true, A)
            elif lr.scheme == "supervised":
                static[k] = first_labels(true, int(lr.source), A)
        self.static_rows = np.array(list(static), dtype=int)
        self.static = np.stack(list(static.values()), axis=1) if static else np.zeros((len(true), 0, A))
        self.dynamic = np.array([lr.scheme in DYNAMIC for lr in learners], dtype=bool).reshape(L)
        self.clusters = [k for k, lr in enumerate(learners) if lr.scheme in CLUSTERS]
        # the learners that read their HMMs, by reading; those of them that multiply by the network
        self.readings = {
            r: np.array(
                [k for k, lr in enumerate(learners) if lr.scheme in DYNAMIC and _reading(lr, settings) == r]
            )
            for r in dict.fromkeys(_reading(lr, settings) for lr in learners if lr.scheme in DYNAMIC)
        }
        self.product = np.array([lr.scheme in ("iterative", "em") for lr in learners], dtype=bool).reshape(L)
        prod = np.flatnonzero(self.product)
        self.network = np.stack([p_bn[learners[k].source] for k in prod], axis=1) if len(prod) else None
        self.network_row = np.full(L, -1)
        self.network_row[prod] = np.arange(len(prod))
        # the first model of an action is trained once its buffer weighs this much and holds this many
        self.init_weight = np.array(
            [min(settings.init_weight, lr.source) if lr.scheme == "supervised" else settings.init_weight
             for lr in learners]
        )  # fmt: skip
        self.init_count = np.array([min(2, lr.source) if lr.scheme == "supervised" else 2 for lr in learners])

    def static_weights(self, i: int, L: int, A: int) -> np.ndarray:
        """Episode ``i``'s label weights from the learners whose labels need no HMM, shape (L, A) (rows of 0
        for the others)."""
        W = np.zeros((L, A))
        W[self.static_rows] = self.static[i]
        return W

    def dynamic_weights(self, W: np.ndarray, i: int, loglik: np.ndarray, n_frames: int, exists) -> None:
        """The labels of the learners that read their HMMs, into ``W`` (L, A): the product rule with the
        network (``iterative``: p_HMM read as ``settings.posterior``; ``em``: the likelihood itself), or
        p_HMM alone (the clusters); the network alone while some action has no model."""
        ready = exists.all(axis=1)
        waiting = np.flatnonzero(self.product & ~ready)
        if len(waiting):
            W[waiting] = self.network[i, self.network_row[waiting]]
        for reading, rows in self.readings.items():
            rows = rows[ready[rows]]
            if not len(rows):
                continue
            p_hmm = p_hmm_reading(loglik[rows], np.full(len(rows), n_frames), reading)
            both = self.product[rows]
            if both.any():
                net = self.network[i, self.network_row[rows[both]]]
                W[rows[both]] = label_weights("iterative", net, p_hmm=p_hmm[both])
            W[rows[~both]] = p_hmm[~both]


def _reading(learner: Learner, settings: OnlineSettings) -> str:
    """How a learner that reads its HMMs reads p_HMM: ``em`` the likelihood itself, the others per
    ``settings.posterior``."""
    return "likelihood" if learner.scheme == "em" else settings.posterior


DYNAMIC: tuple[str, ...] = ("iterative", "em", "unsupervised", "clustering")
"""The learners whose labels read their own HMMs."""


def _check_learners(learners: Sequence[Learner], p_bn: Mapping[Any, np.ndarray]) -> None:
    for lr in learners:
        if lr.scheme not in ONLINE_LEARNERS:
            raise DataError(f"unknown learner {lr.scheme!r}; allowed: {', '.join(ONLINE_LEARNERS)}")
        if lr.scheme == "supervised":
            if isinstance(lr.source, bool) or not isinstance(lr.source, int | np.integer) or lr.source < 1:
                raise DataError(f"learner 'supervised': labels per action {lr.source!r}, a whole number ≥ 1")
        elif lr.scheme not in ("true", "unsupervised") and lr.source not in p_bn:
            raise DataError(f"learner {lr.scheme!r}: no network posteriors for {lr.source!r}")


def run_online(
    features: Sequence[np.ndarray],
    episode_actions: np.ndarray,
    learners: Sequence[Learner],
    p_bn: Mapping[Any, np.ndarray],
    test_features: Sequence[np.ndarray],
    test_actions: np.ndarray,
    checkpoints: Sequence[int],
    actions: Sequence[str],
    settings: OnlineSettings = OnlineSettings(),
    seed: int = 0,
    progress: Callable[[str], None] | None = None,
) -> OnlineRun:
    """Run every learner over the episodes in order, measuring all of them at the checkpoints.

    Parameters
    ----------
    features : the episodes' gestures, arrays of shape (T_i, D), in the order they are seen (N of them)
    episode_actions : their true actions, int array of shape (N,) (only ``true``, ``supervised`` and the
        after-the-fact naming of the ``unsupervised`` clusters read them)
    learners : the learners (:class:`Learner`)
    p_bn : label source → ``p_BN(A | what the robot perceived)`` of each episode, shape (N, A) (for
        ``random``: the random labels, one-hot)
    test_features, test_actions : the held-out gestures (J of them) and their true actions
    checkpoints : after how many episodes to measure (each in 1 … N)
    actions : the action names (the columns of ``p_bn``)
    settings : how the learners learn (:class:`OnlineSettings`)
    seed : seeds the first models' initial mixtures and the clustering
    progress : called with ``"episode"`` after each episode
    """
    N, A, L = len(features), len(actions), len(learners)
    _check_learners(learners, p_bn)
    checkpoints = _checkpoints(checkpoints, N)
    config, D = settings.config, features[0].shape[1]
    row, owners = _model_rows(learners)  # learner k learns the models of row row[k]
    R = len(owners)
    state = _State(
        OnlineModels.empty((R, A), config, D, settings.step), [[[] for _ in range(A)] for _ in range(R)]
    )
    labels = _Labels([learners[k] for k in owners], episode_actions, p_bn, A, settings)
    clusters = [k for k, lr in enumerate(learners) if lr.scheme in CLUSTERS]  # learners
    naming = _naming(learners, clusters, episode_actions, p_bn, A)
    cluster_counts = np.zeros((L, A, A))
    C = len(checkpoints)
    correct = np.zeros((C, L, len(test_features)), dtype=bool)
    means = np.full((C, L, A, config.n_states, D), np.nan)
    matching = np.tile(np.arange(A), (C, L, 1))
    all_weights = np.zeros((N, L, A))
    seconds = np.zeros(N)
    first_models: dict = {}  # first models by (action, buffer), shared by learners with the same buffer
    c = 0
    for i, X in enumerate(features):
        t0 = time.thread_time()
        W = labels.static_weights(i, R, A)
        pairs, unit, loglik = _estep(state, X, W, labels.dynamic)
        labels.dynamic_weights(W, i, loglik, len(X), state.models.exists)
        all_weights[i] = W[row]
        if unit is not None:
            _update(state, pairs, unit, W, settings)
        for k in clusters:
            cluster_counts[k] += np.outer(W[row[k]], naming[k][i])
        _initialise(state, W, features, i, labels, seed, first_models)
        if clusters and i + 1 == settings.cluster_episodes:
            _cluster(state, labels.clusters, features[: i + 1], settings, seed, cluster_counts, naming)
        seconds[i] = time.thread_time() - t0
        if progress is not None:
            progress("episode")
        while c < C and checkpoints[c] == i + 1:
            for k in clusters:
                matching[c, k] = best_matching(cluster_counts[k])
            correct[c], means[c] = _measure(state, row, matching[c], test_features, test_actions)
            c += 1
    params = GMMHMMParams(*(p[row] for p in state.models.params))
    return OnlineRun(
        list(learners), tuple(actions), checkpoints, correct, all_weights, np.asarray(episode_actions),
        np.asarray(test_actions), means, params, state.models.exists[row].copy(), matching, seconds,
    )  # fmt: skip


def _checkpoints(checkpoints: Sequence[int], N: int) -> np.ndarray:
    """The checkpoints sorted, each once; :class:`DataError` unless they lie in 1 … N."""
    out = np.array(sorted(set(int(c) for c in checkpoints)))
    if len(out) == 0 or out[0] < 1 or out[-1] > N:
        raise DataError(f"checkpoints must lie in 1 … {N} (the episodes), got {out.tolist()}")
    return out


def _estep(state, X: np.ndarray, W: np.ndarray, dynamic: np.ndarray):
    """The E-step of every model that learns from episode ``X`` (weight ``W`` > 0) or whose likelihood labels
    it (``dynamic`` rows): the (row, action) pairs, their sufficient statistics (None without pairs) and the
    log-likelihoods, -inf elsewhere, shape (R, A)."""
    pairs = np.nonzero(state.models.exists & ((W > 0) | dynamic[:, None]))
    loglik = np.full(W.shape, -np.inf)
    unit = None
    if len(pairs[0]):
        unit, ll = state.models.estep(X, pairs)
        loglik[pairs] = ll
    return pairs, unit, loglik


CLUSTERS: tuple[str, ...] = ("unsupervised", "clustering")
"""The learners that cluster the gestures without labels and name the clusters after the fact: they learn the
same models (named differently), which :func:`run_online` keeps once."""


def _model_rows(learners: Sequence[Learner]) -> tuple[np.ndarray, list[int]]:
    """Which row of models each learner learns, and the learner that owns each row: one row per learner, but
    one row for all the clustering learners (their models do not depend on how the clusters are named)."""
    row, owners, shared = np.zeros(len(learners), dtype=int), [], None
    for k, lr in enumerate(learners):
        if lr.scheme in CLUSTERS and shared is not None:
            row[k] = shared
            continue
        row[k] = len(owners)
        owners.append(k)
        if lr.scheme in CLUSTERS:
            shared = row[k]
    return row, owners


def _naming(learners, clusters, episode_actions, p_bn, A: int) -> dict[int, np.ndarray]:
    """What names each clustering learner's clusters after the fact: the true actions (``unsupervised``) or
    the network's posteriors (``clustering``), shape (N, A)."""
    return {
        k: one_hot(np.asarray(episode_actions), A)
        if learners[k].scheme == "unsupervised"
        else p_bn[learners[k].source]
        for k in clusters
    }


def _update(
    state: _State, pairs: tuple, unit: SufficientStats, W: np.ndarray, settings: OnlineSettings
) -> None:
    """The stepwise-EM step and the M-step of every model with a positive label weight."""
    w = W[pairs]
    keep = w > 0
    if keep.any():
        idx = tuple(p[keep] for p in pairs)
        state.models.update(idx, unit.take(np.flatnonzero(keep)), w[keep], settings.config.covar_reg)


def _first_model(
    seqs: list[np.ndarray],
    w: np.ndarray,
    settings: OnlineSettings,
    seed: int,
    state: _State,
    k: int,
    a: int,
    cache: dict | None = None,
    key: tuple | None = None,
) -> None:
    """Train action ``a``'s first model for learner ``k`` on buffered episodes, and keep their statistics.

    Learners with the same buffer (the same episodes with the same weights) get the same first model:
    ``cache`` keeps it under ``key``."""
    if cache is not None and key in cache:
        p, stats = cache[key]
    else:
        p, stats = first_model(seqs, w, settings.config.replace(n_iter=settings.init_iter), seed)
        if cache is not None:
            cache[key] = p, stats
    state.models.start((k, a), p, stats)


def _initialise(
    state: _State,
    W: np.ndarray,
    features: Sequence[np.ndarray],
    i: int,
    labels: _Labels,
    seed: int,
    cache: dict,
) -> None:
    """Buffer the episode for every action without a model; train those whose buffer weighs enough (the
    clustering learners' weights are 0 until :func:`_cluster` gave them every model)."""
    need = (~state.models.exists) & (W > 0)
    for k, a in zip(*np.nonzero(need), strict=True):
        buf = state.buffers[k][a]
        buf.append((i, float(W[k, a])))
        if sum(x for _, x in buf) >= labels.init_weight[k] and len(buf) >= labels.init_count[k]:
            seqs = [features[j] for j, _ in buf]
            key = (int(a), tuple(buf))
            w = np.array([x for _, x in buf])
            _first_model(seqs, w, labels.settings, seed, state, k, a, cache, key)
            buf.clear()


def _cluster(
    state: _State,
    rows: Sequence[int],
    seen: Sequence[np.ndarray],
    settings: OnlineSettings,
    seed: int,
    cluster_counts: np.ndarray,
    naming: Mapping[int, np.ndarray],
) -> None:
    """The clustering learners' first models (``rows``): k-means of the episodes seen so far, one model per
    cluster; each clustering learner's counts of its clusters against what names them (``naming``)."""
    A = state.models.exists.shape[1]
    labels = kmeans_labels(resampled(seen), A, seed)
    for k in rows:
        for a in range(A):
            members = np.flatnonzero(labels == a)
            _first_model([seen[j] for j in members], np.ones(len(members)), settings, seed, state, k, a)
    for k, names in naming.items():
        cluster_counts[k] = one_hot(labels, A).T @ names[: len(seen)]


def _measure(
    state: _State,
    row: np.ndarray,
    matching: np.ndarray,
    test_features: Sequence[np.ndarray],
    test_actions: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Which held-out gestures every learner recognises right (L, J), and its models' state means (L, A, Q,
    D): the models of row ``row[k]`` (R rows), their clusters named by ``matching[k]`` (L, A)."""
    R, A = state.models.exists.shape
    Q, D = state.models.params.means.shape[2], state.models.params.means.shape[-1]
    pairs = np.nonzero(state.models.exists)
    means = np.full((R, A, Q, D), np.nan)
    ll = np.full((len(test_features), R, A), -np.inf)
    if len(pairs[0]):
        means[pairs] = state.models.params.means[pairs][:, :, 0]
    if len(pairs[0]) and len(test_features):
        ll[:, pairs[0], pairs[1]] = state.models.loglik(test_features, pairs)
    cluster = ll.argmax(axis=2)[:, row]  # (J, L)
    predicted = matching[np.arange(len(row))[None, :], cluster]  # (J, L): each cluster's action
    none = ~np.isfinite(ll.max(axis=2))[:, row]
    ok = (predicted == np.asarray(test_actions)[:, None]) & ~none
    return ok.T, means[row]


def learn_online(
    features: Sequence[np.ndarray],
    episode_actions: np.ndarray,
    scheme: str,
    p_bn: np.ndarray | None,
    actions: Sequence[str],
    settings: OnlineSettings = OnlineSettings(),
    seed: int = 0,
    test_features: Sequence[np.ndarray] = (),
    test_actions: np.ndarray | None = None,
    checkpoints: Sequence[int] | None = None,
    progress: Callable[[str], None] | None = None,
    per_action: int | None = None,
) -> OnlineRun:
    """One learner over the episodes (:func:`run_online` with one :class:`Learner`); measured on the held-out
    gestures, if given, at the checkpoints (default: after the last episode only). ``per_action``: for
    ``supervised``, how many labelled episodes per action (its labels come from no network).

    ``features``: N arrays of shape (T_i, D); ``episode_actions``: int array, shape (N,); ``p_bn``: the
    network's labels, shape (N, A) (not read for ``true``, ``unsupervised``, ``supervised``);
    ``test_features``: J arrays of shape (T_j, D); ``test_actions``: int array, shape (J,). The arrays as
    :func:`run_online` takes them.
    """
    source = {"true": None, "unsupervised": None, "supervised": per_action}.get(scheme, "network")
    sources = {"network": np.asarray(p_bn)} if source == "network" else {}
    return run_online(
        features,
        episode_actions,
        [Learner(scheme, source)],
        sources,
        test_features,
        np.zeros(0, int) if test_actions is None else test_actions,
        checkpoints or [len(features)],
        actions,
        settings,
        seed,
        progress,
    )
