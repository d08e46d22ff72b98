"""The settings of a corpus sweep: defaults, a TOML file, validation with one-line errors.

A sweep file (``glu evaluate --config FILE.toml``) may set any of these; everything left out keeps the
default shown (``docs/corpus-evaluation.md`` explains the design)::

    episodes = 120000         # in all, shared equally by (action prior, noise, viewpoint) and the seeds
    seed = 0
    chunk_size = 2000         # episodes per recogniser seed in one task (and per resumable piece)
    recognizer_seeds = 10     # K replications: each its own recogniser, learned networks and episodes

    [grid]                    # the factors; every episode is scored at every fraction by every strategy
    effects = ["action", "gesture"]              # effects drawn from the action alone, or the gesture too
    action_prior = ["uniform", "network"]        # how often each action is performed (also "scenario")
    inference_network = ["generating", "learned"]  # the robot's network: the world's, or learned
    learn_experiments = [100, 1270, 10000]       # rows of the experiment tables the learned ones see
    p_hmm = ["likelihood", "per-frame", "calibrated", "calibrated-matched"]  # how p_HMM is read
    features = ["raw", "centred+rotated", "body"]  # the recognisers' feature sets (one recogniser each)
    noise = [0.0, 0.02, 0.05, 0.1]
    viewpoints = ["front", "turned", "side-on", "seated"]
    fractions = [0.2, 0.4, 0.6, 0.8, 1.0]
    strategies = ["gesture", "network", "hard", "virtual", "jeffrey", "product", "true_action"]

    [views.left]              # more viewpoints (or new definitions of the named ones)
    yaw_deg = -40.0           # also: mirror = true, posture = "seated", size = 1.1, tracker = "occluding"

    [scenario.Shape]          # weights of a root node's values (Color, Shape, Size; Action with the
    sphere = 2.0              # action prior "scenario"); default uniform

    [gestures]
    spike_rate = 0.005
    dropout_rate = 0.2

    [recognizer]              # gesture HMMs trained on synthetic gestures (front view), or a file
    n_per_action = 20
    n_states = 6
    n_mix = 3
    n_iter = 200
    noise = 0.01
    calibration_per_action = 20   # held-out gestures each calibrated reading is fitted on
    # file = "recognizer.json"    (then recognizer_seeds = 1)

    [network]                 # the Affordance–Words network that draws the episodes: learned from this data
    # data = "/path/to/data"    (default: $GLU_DATA_DIR, data/real, else synthetic)
    words = "lab"
    unseen_words = "zero"

    [evaluation]
    action_evidence = ["Color", "Shape", "Size", "ObjVel"]
    effect_evidence = ["Color", "Shape", "Size"]
    words_evidence = ["Color", "Shape", "Size", "ObjVel"]
    bins = 10
    bootstrap = 1000

Relative paths in a file are relative to the file. Every error names the file, the key and what is
allowed (:class:`glu.errors.DataError`, which the command line prints as one line, exit status 2).
"""

from __future__ import annotations

import math
import os
import tomllib
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, fields, replace
from pathlib import Path
from typing import Any

from glu.bn.learning import UNSEEN_MODES
from glu.data.source import WORD_FILES
from glu.errors import DataError, ModelError
from glu.files import read_text
from glu.gestures.feature_sets import FEATURE_SET_NAMES
from glu.gestures.views import POSTURES, TRACKERS, View
from glu.hmm import TrainingConfig
from glu.studies.corpus_evaluation.evaluation import (
    INFERENCE_NETWORKS,
    P_HMM_READINGS,
    EvaluationSettings,
    Reading,
)
from glu.studies.corpus_evaluation.findings import DESIGN
from glu.studies.episodes import (
    ACTION_PRIORS,
    GESTURE_WORLDS,
    VIEWPOINTS,
    Condition,
    GestureSettings,
    Scenario,
)

MAX_EPISODES = 100_000_000
MAX_SEEDS = 1000
TOP_LEVEL: tuple[str, ...] = ("episodes", "seed", "chunk_size", "recognizer_seeds")
"""The settings of a sweep file's top level (the others are its tables)."""
IN_GRID: tuple[str, ...] = ("fractions", "strategies")
"""The fields of :class:`EvaluationSettings` a sweep file gives in its ``[grid]`` table."""


@dataclass(frozen=True)
class RecognizerSettings:
    """The gesture HMMs: trained on ``n_per_action`` synthetic gestures per action (front view, sensor
    noise ``noise``) with :class:`~glu.hmm.TrainingConfig`'s recipe, one recogniser per feature set, or read
    from ``file``; the calibrated reading of p_HMM is fitted on ``calibration_per_action`` more gestures of
    the same kind, the ``calibrated-matched`` one on as many drawn like the test conditions (the sweep's
    viewpoints and noise levels in equal shares).

    A sweep file gives ``training``'s fields flat in its ``[recognizer]`` table (``n_states = 6``, …).
    """

    n_per_action: int = 20
    training: TrainingConfig = TrainingConfig()
    noise: float = 0.01
    calibration_per_action: int = 20
    file: str | None = None

    def as_dict(self) -> dict[str, Any]:
        """Plain data, ``training`` flat: Q, M and the iterations always, its other fields where they differ
        from glu's defaults (so that sweeps saved before they could be set keep their fingerprints)."""
        d = {k: v for k, v in asdict(self).items() if k != "training"}
        default = TrainingConfig().as_dict()
        for k, v in self.training.as_dict().items():
            if k in ("n_states", "n_mix", "n_iter") or v != default[k]:
                d[k] = v
        return d


@dataclass(frozen=True)
class NetworkSettings:
    """Where the Affordance–Words network is learned from (:func:`glu.data.resolve_data`) and how."""

    data: str | None = None
    words: str = "lab"
    unseen_words: str = UNSEEN_MODES[0]


@dataclass(frozen=True)
class SweepConfig:
    """Everything that defines a sweep's results (see the module docstring for the file format)."""

    episodes: int = 120_000
    seed: int = 0
    chunk_size: int = 2000
    recognizer_seeds: int = 10
    effects: tuple[str, ...] = tuple(GESTURE_WORLDS)
    action_prior: tuple[str, ...] = ("uniform", "network")
    inference_network: tuple[str, ...] = ("generating", "learned")
    learn_experiments: tuple[int, ...] = (100, 1270, 10000)
    p_hmm: tuple[str, ...] = tuple(P_HMM_READINGS)
    features: tuple[str, ...] = ("raw", "centred+rotated", "body")
    noise: tuple[float, ...] = (0.0, 0.02, 0.05, 0.1)
    viewpoints: tuple[str, ...] = ("front", "turned", "side-on", "seated")
    views: Mapping[str, View] = field(default_factory=lambda: dict(VIEWPOINTS))
    scenario: Scenario = Scenario()
    gestures: GestureSettings = GestureSettings()
    recognizer: RecognizerSettings = RecognizerSettings()
    network: NetworkSettings = NetworkSettings()
    evaluation: EvaluationSettings = EvaluationSettings()

    def __post_init__(self) -> None:
        _whole("episodes", self.episodes, 1, MAX_EPISODES)
        _whole("seed", self.seed, 0, 2**63 - 1)
        _whole("chunk_size", self.chunk_size, 1, 1_000_000)
        if not self.noise or any(not _number(x) or x < 0 for x in self.noise):
            raise DataError(f"grid.noise {list(self.noise)}: give one or more noise levels ≥ 0 (metres)")
        _whole("recognizer_seeds", self.recognizer_seeds, 1, MAX_SEEDS)
        factors = {
            "effects": (self.effects, GESTURE_WORLDS),
            "action_prior": (self.action_prior, ACTION_PRIORS),
            "inference_network": (self.inference_network, INFERENCE_NETWORKS),
            "p_hmm": (self.p_hmm, P_HMM_READINGS),
            "features": (self.features, FEATURE_SET_NAMES),
        }
        for name, (given, allowed) in factors.items():
            bad = [v for v in given if v not in allowed]
            if bad or not given:
                raise DataError(
                    f"grid.{name}: unknown value {bad[0] if bad else '(none)'!r}; "
                    f"allowed: {', '.join(allowed)}"
                )
        for name in ("noise", "viewpoints", *factors, "learn_experiments"):
            v = getattr(self, name)
            if len(set(v)) != len(v):
                raise DataError(f"grid.{name}: each value may appear once")
        if "learned" in self.inference_network:
            if not self.learn_experiments:
                raise DataError("grid.learn_experiments: give the rows of at least one experiment table")
            for n in self.learn_experiments:
                _whole("grid.learn_experiments", n, 10, 10_000_000)
        if "scenario" in self.action_prior and "Action" not in self.scenario.weights:
            raise DataError("grid.action_prior 'scenario' needs [scenario.Action] weights")
        if "Action" in self.scenario.weights and "scenario" not in self.action_prior:
            raise DataError('[scenario.Action] applies only with grid.action_prior = ["scenario", …]')
        if not self.viewpoints:
            raise DataError("grid.viewpoints: give at least one viewpoint")
        unknown = [v for v in self.viewpoints if v not in self.views]
        if unknown:
            raise DataError(
                f"grid.viewpoints: unknown viewpoint {unknown[0]!r}; allowed: {', '.join(self.views)} "
                "(define more in [views.NAME])"
            )
        r = self.recognizer
        for name, lo in (("n_per_action", 2), ("calibration_per_action", 1)):
            _whole(f"recognizer.{name}", getattr(r, name), lo, 100_000)
        for name in ("n_states", "n_mix", "n_iter"):
            _whole(f"recognizer.{name}", getattr(r.training, name), 1, 100_000)
        if not _number(r.noise) or r.noise < 0:
            raise DataError(f"recognizer.noise={r.noise!r}: the training noise must be a number ≥ 0 (metres)")
        if r.file is not None and self.recognizer_seeds != 1:
            raise DataError("recognizer.file: one recogniser from a file needs recognizer_seeds = 1")
        if r.file is not None and len(self.features) != 1:
            raise DataError("recognizer.file: one recogniser from a file has one feature set (grid.features)")
        if self.network.words not in WORD_FILES:
            raise DataError(f"network.words={self.network.words!r}; allowed: {', '.join(WORD_FILES)}")
        if self.network.unseen_words not in UNSEEN_MODES:
            raise DataError(
                f"network.unseen_words={self.network.unseen_words!r}; allowed: {', '.join(UNSEEN_MODES)}"
            )

    @property
    def conditions(self) -> list[Condition]:
        """The simulated conditions, effects-major, then action prior: (noise, viewpoint, action prior,
        effects) for every combination."""
        return [
            Condition(float(n), v, a, e)
            for e in self.effects
            for a in self.action_prior
            for n in self.noise
            for v in self.viewpoints
        ]

    @property
    def readings(self) -> list[Reading]:
        """How every episode is read: each inference network (one per table size if learned) × p_HMM ×
        feature set."""
        nets = [
            (name, n)
            for name in self.inference_network
            for n in (self.learn_experiments if name == "learned" else (0,))
        ]
        return [Reading(name, n, p, f) for name, n in nets for p in self.p_hmm for f in self.features]

    @property
    def per_condition(self) -> int:
        """Episodes per condition and recogniser seed: ``episodes`` shared equally, rounded up (every
        reading reads the same episodes)."""
        return math.ceil(self.episodes / (len(self.conditions) * self.recognizer_seeds))

    @property
    def n_episodes(self) -> int:
        """Episodes simulated: :attr:`per_condition` for each condition and recogniser seed."""
        return self.per_condition * len(self.conditions) * self.recognizer_seeds

    def with_overrides(self, **changes: Any) -> SweepConfig:
        """A copy with top-level fields changed (``None`` values are ignored)."""
        return replace(self, **{k: v for k, v in changes.items() if v is not None})

    def as_dict(self) -> dict[str, Any]:
        """The settings as plain data (JSON-ready), for result files and fingerprints."""
        d = {
            **{k: getattr(self, k) for k in TOP_LEVEL},
            "grid": {
                **{k: list(getattr(self, k)) for k in (*DESIGN, "noise", "viewpoints")},
                "fractions": list(self.evaluation.fractions),
                "strategies": list(self.evaluation.strategies),
            },
            "views": {k: asdict(v) for k, v in self.views.items() if k in self.viewpoints},
            "scenario": self.scenario.as_dict(),
            "gestures": asdict(self.gestures),
            "recognizer": self.recognizer.as_dict(),
            "network": asdict(self.network),
            "evaluation": {k: v for k, v in asdict(self.evaluation).items() if k not in IN_GRID},
        }
        return _plain(d)


def _plain(v: Any) -> Any:
    if isinstance(v, Mapping):
        return {str(k): _plain(x) for k, x in v.items()}
    if isinstance(v, list | tuple):
        return [_plain(x) for x in v]
    return v


def _number(x: Any) -> bool:
    return isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x)


def _whole(name: str, v: Any, lo: int, hi: int) -> None:
    if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
        raise DataError(f"{name}={v!r}: a whole number from {lo:,} to {hi:,}")


# ---------------------------------------------------------------------------------------------- files
SECTIONS: dict[str, tuple[str, ...]] = {
    "": (*TOP_LEVEL, "grid", "views", "scenario", "gestures", "recognizer", "network", "evaluation"),
    "grid": (*DESIGN, "noise", "viewpoints", *IN_GRID),
    "gestures": tuple(f.name for f in fields(GestureSettings)),
    "recognizer": tuple(f.name for f in fields(RecognizerSettings) if f.name != "training")
    + tuple(f.name for f in fields(TrainingConfig)),
    "network": tuple(f.name for f in fields(NetworkSettings)),
    "evaluation": tuple(f.name for f in fields(EvaluationSettings) if f.name not in IN_GRID),
    "views.*": ("yaw_deg", "mirror", "posture", "size", "tracker"),
}
"""The keys each table of a sweep file may have."""


def load_config(path: str | os.PathLike) -> SweepConfig:
    """Read and validate a sweep file (TOML); :class:`DataError` naming the file and the problem."""
    path = Path(path)
    text = read_text(path, "sweep file")
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise DataError(f"{path}: {e}") from None
    try:
        return config_from_dict(doc, base=path.parent)
    except DataError as e:
        raise DataError(f"{path}: {e}") from None


def config_from_dict(doc: Mapping[str, Any], base: Path | None = None) -> SweepConfig:
    """A :class:`SweepConfig` from the tables of a sweep file (relative paths resolved against ``base``)."""
    _keys("", doc)
    top = {k: doc[k] for k in TOP_LEVEL if k in doc}
    grid = _table(doc, "grid")
    views = dict(VIEWPOINTS)
    for name, spec in _table(doc, "views").items():
        if not isinstance(spec, Mapping):
            raise DataError(f"views.{name} must be a table, e.g. [views.{name}] yaw_deg = 30.0")
        _keys("views.*", spec, f"views.{name}")
        posture = spec.get("posture", "standing")
        if posture not in POSTURES:
            raise DataError(f"views.{name}.posture={posture!r}; allowed: {', '.join(POSTURES)}")
        for k in ("yaw_deg", "size"):
            if k in spec and not _number(spec[k]):
                raise DataError(f"views.{name}.{k}={spec[k]!r}: must be a number")
        if "mirror" in spec and not isinstance(spec["mirror"], bool):
            raise DataError(f"views.{name}.mirror={spec['mirror']!r}: must be true or false")
        tracker = spec.get("tracker", "ideal")
        if tracker not in TRACKERS:
            raise DataError(f"views.{name}.tracker={tracker!r}; allowed: {', '.join(TRACKERS)}")
        views[name] = View(
            spec.get("yaw_deg"), spec.get("mirror", False), posture, spec.get("size"), tracker=tracker
        )
    scenario = Scenario.from_mapping(_table(doc, "scenario"))
    gestures = GestureSettings(**_table(doc, "gestures"))
    rec = _table(doc, "recognizer")
    if rec.get("file") is not None:
        if not isinstance(rec["file"], str):
            raise DataError("recognizer.file must be a path (a string)")
        rec["file"] = str(_resolve(rec["file"], base))
    net = _table(doc, "network")
    if net.get("data") is not None:
        if not isinstance(net["data"], str):
            raise DataError("network.data must be a folder (a string) or 'synthetic'")
        net["data"] = net["data"] if net["data"] == "synthetic" else str(_resolve(net["data"], base))
    ev = _table(doc, "evaluation")
    for k in IN_GRID:
        if k in grid:
            ev[k] = grid[k]
    for k, v in list(ev.items()):
        if isinstance(v, list):
            ev[k] = tuple(v)
    if isinstance(ev.get("fractions"), tuple):
        ev["fractions"] = tuple(float(f) if _number(f) else f for f in ev["fractions"])
    extra = {k: _list(f"grid.{k}", grid[k]) for k in ("noise", "viewpoints", *DESIGN) if k in grid}
    return SweepConfig(
        **top,
        **extra,
        views=views,
        scenario=scenario,
        gestures=gestures,
        recognizer=_recognizer(rec),
        network=NetworkSettings(**net),
        evaluation=EvaluationSettings(**ev),
    )


NOTEBOOK_NAMES: dict[str, str] = {"feature_sets": "features", "noise_levels": "noise"}
"""Notebook 11's parameters whose names differ from the sweep file's (notebook name → grid key)."""


def config_from_parameters(params: Mapping[str, Any], data: str | os.PathLike | None) -> SweepConfig:
    """The sweep of notebook 11's parameters (its cell's names; others in ``params`` are ignored), with
    the network learned from ``data`` (None: synthetic): one call instead of a sweep file."""
    grid_keys = set(SECTIONS["grid"])
    doc: dict[str, Any] = {k: params[k] for k in TOP_LEVEL if k in params}
    doc["grid"] = {
        NOTEBOOK_NAMES.get(k, k): v for k, v in params.items() if NOTEBOOK_NAMES.get(k, k) in grid_keys
    }
    doc["recognizer"] = {k: v for k, v in params.items() if k in SECTIONS["recognizer"] and k != "file"}
    doc["evaluation"] = {k: v for k, v in params.items() if k in SECTIONS["evaluation"]}
    doc["network"] = {"data": "synthetic" if data is None else str(data)}
    return config_from_dict(doc)


def _recognizer(rec: dict[str, Any]) -> RecognizerSettings:
    """The ``[recognizer]`` table: its training fields gathered into one :class:`TrainingConfig`."""
    names = {f.name for f in fields(TrainingConfig)}
    train = {k: rec.pop(k) for k in list(rec) if k in names}
    for k in ("n_states", "n_mix", "n_iter"):
        if k in train:
            _whole(f"recognizer.{k}", train[k], 1, 100_000)
    try:
        training = TrainingConfig(**train)
    except (ModelError, TypeError) as e:
        raise DataError(f"recognizer: {e}") from None
    return RecognizerSettings(training=training, **rec)


def _resolve(p: str, base: Path | None) -> Path:
    q = Path(p).expanduser()
    return q if q.is_absolute() or base is None else (base / q)


def _list(name: str, v: Any) -> tuple:
    if not isinstance(v, list):
        raise DataError(f"{name} must be a list, e.g. {name.split('.')[-1]} = [ … ]")
    return tuple(v)


def _table(doc: Mapping[str, Any], name: str) -> dict[str, Any]:
    t = doc.get(name, {})
    if not isinstance(t, Mapping):
        raise DataError(f"{name} must be a table ([{name}])")
    if name in SECTIONS:
        _keys(name, t)
    return dict(t)


def _keys(section: str, table: Mapping[str, Any], where: str | None = None) -> None:
    allowed = SECTIONS[section]
    for k in table:
        if k not in allowed:
            place = where or (f"[{section}]" if section else "the top level")
            raise DataError(f"unknown key {k!r} in {place}; allowed: {', '.join(allowed)}")
