"""The recogniser: a bank of gesture HMMs, one per action, its posteriors, its streaming form, its file.

:class:`Recognizer` gives ``log L(G | A)`` and ``p_HMM(A | G) = L(G|A) / Σ_h L(G|h)`` (equal priors, in the
log domain) for whole sequences or every prefix; :meth:`Recognizer.stream` gives a :class:`GestureStream`
that consumes one frame at a time at O(1) cost per frame. :func:`train_recognizer` trains one model per
action (:mod:`glu.hmm.training`).

A recogniser knows which features its models were trained on (:class:`~glu.gestures.invariants.Invariants`:
raw, or invariant to translation, scale, rotation about the vertical, mirroring) and computes them itself
from the hand features it is given, for whole sequences and frame by frame alike, so every caller (``glu
recognize``, effect anticipation, the notebooks) feeds it the same hand features and gets the same answer.

Recogniser files (:meth:`Recognizer.save`) are JSON, not pickle::

    {"format": "glu-gesture-recognizer", "version": 3,
     "features": "<what the models expect>",
     "invariants": {"names": ["centred", …], "lock_radius": ρ, "min_scale": s},
     "actions": ["grasp", "tap", "touch"],
     "models": {"grasp": {"n_states": Q, "n_mix": M, "n_features": D,
                          "startprob": [Q], "transmat": [Q][Q], "weights": [Q][M],
                          "means": [Q][M][D], "covars": [Q][M][D][D]}, …},
     "training": {"grasp": {<TrainingReport fields>}, …},
     "config": {<TrainingConfig fields>},
     "meta": {<free-form: data source, seed, …>}}

Floats are written with ``repr`` precision, so a saved recogniser scores exactly as the one in memory.
``config`` is the :class:`~glu.hmm.TrainingConfig` the models were trained with (absent for models glu did
not train, such as the originals'). Version 2 files kept those settings in ``meta`` (``recipe``,
``n_states``, ``n_mix``, ``n_iter``, ``tol``, ``covar_reg``): they are read into :attr:`Recognizer.config`
too. Version 1 files (before invariant features) are read as raw-feature recognisers.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from glu.errors import DataError, ModelError
from glu.files import atomic_write_json, read_json
from glu.gestures.features import FEATURES_DESCRIPTION
from glu.gestures.invariants import Invariants
from glu.gestures.typicality import (
    FRAMES_KEY,
    META_KEY,
    FeatureRanges,
    LoglikRange,
    Typicality,
    check,
    ranges_from_meta,
    ranges_to_meta,
    sampled_range,
    sampled_sequences,
    training_range,
)
from glu.hmm import (
    Bank,
    BankStream,
    GestureHMM,
    TrainingConfig,
    TrainingReport,
    as_sequence,
    forward_curve,
    load_original_hmms,
    log_emissions,
    loglik_many,
    p_hmm_from_loglik,
    stack_models,
    train,
)
from glu.schema import ACTIONS

FORMAT = "glu-gesture-recognizer"
FORMAT_VERSION = 3
READABLE_VERSIONS = (1, 2, 3)
LEGACY_CONFIG_KEYS = ("recipe", "n_states", "n_mix", "n_iter", "tol", "covar_reg")
"""The training settings version-2 files kept in ``meta``."""


class StreamStep(NamedTuple):
    """One step of a :class:`GestureStream`.

    Attributes
    ----------
    t : frames consumed so far (1-based index of the frame just pushed)
    loglik : array, shape (n_actions,) — ``log L(G_1^t | A)``
    p_hmm : array, shape (n_actions,) — ``p_HMM(A | G_1^t)`` (equal priors)
    """

    t: int
    loglik: np.ndarray
    p_hmm: np.ndarray


class GestureStream:
    """Incremental forward recursion over every model of a recogniser: one frame in, one posterior out.

    Each :meth:`push` costs O(Σ_a Q_a² + Σ_a Q_a M_a D²), independent of how many frames came before;
    it computes the recogniser's invariant features of the frame
    (:class:`~glu.gestures.invariants.InvariantStream`) and advances the models stacked (padded to the
    largest Q and M) by one compiled step (:class:`glu.hmm.BankStream`: the emissions and
    :func:`~glu.hmm.inference.forward_step`'s recursion as the batch scoring runs them), so the results
    equal rescoring the prefix ``G_1^t``.
    """

    def __init__(self, recognizer: Recognizer) -> None:
        self.actions: tuple[str, ...] = recognizer.actions
        self._D = recognizer.n_features
        self.features: Invariants = recognizer.features
        self._invariant = None if self.features.is_raw else self.features.stream()
        self._bank = BankStream(recognizer.bank)
        self.reset()

    def reset(self) -> None:
        """Forget every frame: the next :meth:`push` starts a new gesture."""
        self._bank.reset()
        self.t = 0
        if self._invariant is not None:
            self._invariant.reset()

    def push(self, x: np.ndarray) -> StreamStep:
        """Consume one frame of hand features, shape (D,); return ``log L(G_1^t | A)`` and
        ``p_HMM(A | G_1^t)``."""
        x = np.asarray(x, dtype=float)
        if x.shape != (self._D,) or not np.isfinite(x).all():
            raise DataError(f"a frame must be {self._D} finite numbers, got {x!r}")
        if self._invariant is not None:
            x = self._invariant.push(x)
        ll = self._bank.push(np.ascontiguousarray(x)).copy()
        self.t += 1
        return StreamStep(self.t, ll, p_hmm_from_loglik(ll))

    def extend(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Push every frame of X, shape (T, D); return loglik and p_hmm per frame, each shape (T,
        n_actions)."""
        X = as_sequence(X, self._D)
        ll = np.empty((len(X), len(self.actions)))
        for t, x in enumerate(X):
            ll[t] = self.push(x).loglik
        return ll, p_hmm_from_loglik(ll)


class Recognizer:
    """A bank of gesture HMMs, one per action: log-likelihoods, posteriors ``p_HMM(A | G)``, streaming.

    Every method takes the hand features (:mod:`glu.gestures.features`, shape (T, 3)) and computes the
    recogniser's own :attr:`features` from them before scoring.

    Parameters
    ----------
    models : action → :class:`GestureHMM` (the order is the order of every output vector)
    reports : action → :class:`TrainingReport`, if trained by glu
    meta : free-form information saved with the recogniser (data source, seed, …)
    features : the invariant features the models were trained on
        (:class:`~glu.gestures.invariants.Invariants`, or its name such as ``"centred"``); default raw
    config : the :class:`~glu.hmm.TrainingConfig` the models were trained with (None: not trained by glu)
    """

    def __init__(
        self,
        models: Mapping[str, GestureHMM],
        reports: Mapping[str, TrainingReport] | None = None,
        meta: Mapping[str, Any] | None = None,
        features: Invariants | str | None = None,
        config: TrainingConfig | None = None,
    ) -> None:
        if not models:
            raise ModelError("a recogniser needs at least one model")
        dims = {m.n_features for m in models.values()}
        if len(dims) != 1:
            raise ModelError(f"all models must have the same number of features, got {sorted(dims)}")
        self.models: dict[str, GestureHMM] = dict(models)
        self.actions: tuple[str, ...] = tuple(models)
        self.reports: dict[str, TrainingReport] = dict(reports or {})
        self.meta: dict[str, Any] = dict(meta or {})
        self.n_features: int = dims.pop()
        self.features: Invariants = Invariants.parse(features)
        self.config: TrainingConfig | None = config
        if not self.features.is_raw and self.n_features != 3:
            raise ModelError(f"invariant features need 3-D models, these have {self.n_features} features")
        self._bank: Bank | None = None

    @property
    def bank(self) -> Bank:
        """The models stacked for scoring them together (:func:`glu.hmm.scoring.stack_models`, built
        once)."""
        if self._bank is None:
            self._bank = stack_models([self.models[a] for a in self.actions])
        return self._bank

    def __repr__(self) -> str:
        shapes = ", ".join(f"{a}: Q={m.n_states} M={m.n_mix}" for a, m in self.models.items())
        return f"Recognizer({shapes}; features {self.features.name})"

    def transform(self, X: np.ndarray) -> np.ndarray:
        """The features the models see: the recogniser's invariant features of hand features X, shape (T,
        D)."""
        X = as_sequence(X, self.n_features)
        return X if self.features.is_raw else self.features.transform(X)

    def loglik(self, X: np.ndarray) -> np.ndarray:
        """``log L(G | A)`` for each action, shape (n_actions,), of a sequence of shape (T, D)."""
        return self.loglik_curve(X)[-1]

    def loglik_many(self, sequences: Sequence[np.ndarray]) -> np.ndarray:
        """:meth:`loglik` of many sequences (each of shape (T_i, D)), shape (S, n_actions), in one batch
        (:func:`glu.hmm.scoring.loglik_many` on the recogniser's features): the same numbers as
        :meth:`loglik` of each sequence (tested)."""
        return loglik_many(self.bank, [self.transform(X) for X in sequences])

    def p_hmm(self, X: np.ndarray) -> np.ndarray:
        """``p_HMM(A | G)`` with equal priors, shape (n_actions,), of a sequence of shape (T, D)."""
        return p_hmm_from_loglik(self.loglik(X))

    def posterior(self, X: np.ndarray) -> Any:
        """:meth:`p_hmm` as a pandas Series indexed by action (length n_actions), named ``p_HMM(A | G)``, of a
        sequence of shape (T, D)."""
        import pandas as pd

        return pd.Series(self.p_hmm(X), index=pd.Index(self.actions, name="action"), name="p_HMM(A | G)")

    def loglik_curve(self, X: np.ndarray) -> np.ndarray:
        """``log L(G_1^t | A)`` for every prefix, shape (T, n_actions): one forward pass over the stacked
        bank."""
        bank = self.bank
        log_b = log_emissions(self.transform(X), bank.means, bank.chol_inv, bank.log_norm)
        return forward_curve(log_b, bank.startprob, bank.transmat)

    def p_hmm_curve(self, X: np.ndarray) -> np.ndarray:
        """``p_HMM(A | G_1^t)`` for every prefix, shape (T, n_actions)."""
        return p_hmm_from_loglik(self.loglik_curve(X))

    def classify(self, X: np.ndarray) -> str:
        """The action with the highest likelihood, of a sequence of shape (T, D)."""
        return self.actions[int(np.argmax(self.loglik(X)))]

    def stream(self) -> GestureStream:
        """A fresh :class:`GestureStream` over this bank."""
        return GestureStream(self)

    def reference_ranges(self) -> dict[str, LoglikRange]:
        """Per action, the per-frame log-likelihoods of the reference sequences
        (:mod:`glu.gestures.typicality`).

        A recogniser trained by glu keeps its training range; one without (the originals' models) gets the
        range of sequences sampled from each model, computed once (seeded) and kept in :attr:`meta`.
        """
        ranges = ranges_from_meta(self.meta)
        if ranges is None or set(ranges) != set(self.actions):
            ranges = {a: sampled_range(self.models[a]) for a in self.actions}
            self.meta[META_KEY] = ranges_to_meta(ranges)
        return ranges

    def feature_ranges(self) -> FeatureRanges:
        """Where the reference gestures start and how far they move
        (:class:`~glu.gestures.typicality.FeatureRanges`).

        A recogniser trained by glu keeps those of its training gestures; one without (the originals'
        models) gets those of sequences sampled from its models, computed once (seeded) and kept in
        :attr:`meta`. Only models over raw hand features can be sampled into hand features; an invariant
        recogniser without saved ranges has none (and its gestures are not checked this way).
        """
        ranges = FeatureRanges.from_meta(self.meta)
        if ranges is None and self.features.is_raw:
            ranges = FeatureRanges.of(
                [X for a in self.actions for X in sampled_sequences(self.models[a])], "sampled"
            )
            self.meta[FRAMES_KEY] = ranges.to_meta()
        return ranges

    def typicality(self, X: np.ndarray) -> Typicality:
        """Whether a sequence, shape (T, D), looks like the models' reference data
        (see :func:`typicality.check`)."""
        X = as_sequence(X, self.n_features)
        return check(self.loglik(X), len(X), self.actions, self.reference_ranges(), X, self.feature_ranges())

    # ------------------------------------------------------------------ files

    def to_dict(self) -> dict[str, Any]:
        """The recogniser file's content (see the module docstring)."""
        return {
            "format": FORMAT,
            "version": FORMAT_VERSION,
            "features": FEATURES_DESCRIPTION
            + ("" if self.features.is_raw else f"; invariant features: {self.features.name}"),
            "invariants": self.features.to_dict(),
            "actions": list(self.actions),
            "models": {a: self.models[a].to_dict() for a in self.actions},
            "training": {a: asdict(r) for a, r in self.reports.items()},
            **({} if self.config is None else {"config": self.config.as_dict()}),
            "meta": self.meta,
        }

    @classmethod
    def from_dict(cls, d: Any, source: str = "<dict>") -> Recognizer:
        """A recogniser from :meth:`to_dict` output; :class:`ModelError` naming ``source`` if malformed."""
        if not isinstance(d, dict) or d.get("format") != FORMAT:
            raise ModelError(f'{source}: not a glu gesture recogniser (expected "format": "{FORMAT}")')
        if d.get("version") not in READABLE_VERSIONS:
            raise ModelError(
                f"{source}: format version {d.get('version')!r}; this glu reads "
                + ", ".join(map(str, READABLE_VERSIONS))
            )
        actions, models = d.get("actions"), d.get("models")
        if (
            not isinstance(actions, list)
            or not all(isinstance(a, str) for a in actions)
            or len(set(actions)) != len(actions)
            or not isinstance(models, dict)
            or set(actions) != set(models)
        ):
            raise ModelError(f"{source}: 'actions' must list exactly the keys of 'models', each once")
        training, meta = d.get("training") or {}, d.get("meta") or {}
        if not isinstance(training, dict) or not isinstance(meta, dict):
            raise ModelError(f"{source}: 'training' and 'meta' must be JSON objects")
        try:
            hmms = {a: GestureHMM.from_dict(models[a], name=a) for a in actions}
        except ModelError as e:
            raise ModelError(f"{source}: {e}") from None
        reports = {}
        for a, r in training.items():
            try:
                reports[a] = TrainingReport(**{**r, "history": tuple(r["history"])})
            except (TypeError, KeyError, ValueError):
                raise ModelError(f"{source}: malformed training report for {a!r}") from None
        features = Invariants.from_dict(d.get("invariants"), source)
        try:
            ranges_from_meta(meta)  # the typicality ranges: checked now, not when a gesture is scored
            FeatureRanges.from_meta(meta)
            config = _config_from(d, meta)
        except ModelError as e:
            raise ModelError(f"{source}: {e}") from None
        return cls(hmms, reports, meta, features, config)

    def save(self, path: str | os.PathLike) -> Path:
        """Write the recogniser as JSON (atomically); returns the path."""
        return atomic_write_json(path, self.to_dict(), allow_nan=True)

    @classmethod
    def load(cls, path: str | os.PathLike) -> Recognizer:
        """Read a recogniser written by :meth:`save`; :class:`ModelError` if the file is not one."""
        return cls.from_dict(read_json(path, "recogniser file", ModelError), str(path))


def _config_from(d: Mapping[str, Any], meta: Mapping[str, Any]) -> TrainingConfig | None:
    """The training settings of a recogniser file: its ``config`` (version 3), else those a version-2 file
    kept in ``meta`` (:data:`LEGACY_CONFIG_KEYS`), else None."""
    settings = d.get("config")
    if settings is None and all(k in meta for k in ("n_states", "n_mix")):
        settings = {k: meta[k] for k in LEGACY_CONFIG_KEYS if k in meta}
    if settings is None:
        return None
    known = set(TrainingConfig.__dataclass_fields__)
    if not isinstance(settings, dict) or not set(settings) <= known:
        raise ModelError(f"'config' must be a JSON object with some of {', '.join(sorted(known))}")
    try:
        return TrainingConfig(**settings)
    except (ModelError, TypeError) as e:
        raise ModelError(f"'config': {e}") from None


def train_recognizer(
    sequences: Mapping[str, Sequence[np.ndarray]] | Sequence[Mapping[str, Sequence[np.ndarray]]],
    config: TrainingConfig | None = None,
    *,
    seed: int | Sequence[int] = 0,
    features: Invariants | str | None | Sequence[Invariants | str | None] = None,
    meta: Mapping[str, Any] | None = None,
    warn: bool = True,
    progress: Callable[[int], None] | None = None,
) -> Recognizer | list[Recognizer]:
    """Train one left-to-right GMM-HMM per action (:func:`glu.hmm.train`), as a recogniser; or many
    recognisers.

    The recogniser keeps the settings (:attr:`Recognizer.config`); its meta records the seed, the features
    and the per-frame log-likelihood range of each action's training sequences
    (:mod:`glu.gestures.typicality`).

    Parameters
    ----------
    sequences : action → list of hand-feature sequences of shape (T_i, D); or a list of such mappings, one
        recogniser each, every model of every recogniser trained in one batch (each recogniser equal to
        what it would be alone, to rounding)
    config : the training settings (:class:`~glu.hmm.TrainingConfig`, its recipe included; default glu's)
    seed : seeds the initial mixtures; with a list of training sets, one for all or one per set
    features : the invariant features the models are trained on (:class:`~glu.gestures.invariants.Invariants`
        or a name such as ``"centred,rotated"``; default raw); the recogniser applies the same to whatever
        it scores. With a list of sets, one for all or one per set
    meta : free-form information kept with each recogniser (data source, …)
    warn : warn when EM does not converge
    progress : called with the number of models that have just finished training, while they train (for a
        progress bar over every model of every recogniser)
    """
    config = config or TrainingConfig()
    many = not isinstance(sequences, Mapping)
    sets = list(sequences) if many else [sequences]
    n = len(sets)
    seeds = [seed] * n if isinstance(seed, int | np.integer) else list(seed)
    specs = [
        Invariants.parse(f) for f in (features if isinstance(features, list | tuple) else [features] * n)
    ]
    if len(seeds) != n or len(specs) != n:
        raise ModelError(
            f"{n} training sets need as many seeds and feature sets, got {len(seeds)} and {len(specs)}"
        )
    # what the models see (the typicality ranges are measured on these too)
    seen = [
        {a: seqs if f.is_raw else [f.transform(X) for X in seqs] for a, seqs in s.items()}
        for s, f in zip(sets, specs, strict=True)
    ]
    jobs = {(i, a): seqs for i, sn in enumerate(seen) for a, seqs in sn.items()}
    trained = train(jobs, config, seed={(i, a): seeds[i] for i, a in jobs}, warn=warn, progress=progress)
    out = []
    for i, (sn, spec) in enumerate(zip(seen, specs, strict=True)):
        models = {a: trained[i, a].model for a in sn}
        reports = {a: trained[i, a].report for a in sn}
        ranges = {a: training_range(models[a], sn[a]) for a in models}
        hand = FeatureRanges.of([X for a in sn for X in sets[i][a]], "training")
        info = {
            META_KEY: ranges_to_meta(ranges),
            FRAMES_KEY: hand.to_meta(),
            "seed": seeds[i],
            "features": spec.name,
        }
        out.append(Recognizer(models, reports, {**info, **(meta or {})}, spec, config))
    return out if many else out[0]


def load_original_models(
    path: str | os.PathLike,
    actions: Sequence[str] = ACTIONS,
    include_garbage: bool = False,
) -> Recognizer:
    """The originals' 2013 HMMs as a recogniser (:func:`glu.hmm.original.load_original_hmms`): grasp (hmm3),
    tap (hmm1), touch (hmm4, the push model); with ``include_garbage`` also hmm0 as ``"garbage"``. Their
    inputs are the logged features / 1000."""
    models = load_original_hmms(path, actions, include_garbage)
    meta = {"source": str(path), "note": "original 2013 models; touch is the push model (hmm4)"}
    return Recognizer(models, meta=meta)
