"""The real person: learning their gestures from effects, and recognising their held-out repetitions.

The real data hold one person's 11 standing repetitions of grasp, tap and touch. The robot cannot watch that
person act on objects again, so the study simulates what it would have seen, from that person:

* :func:`fit_person` fits a **gesture generator to the person's repetitions** of each action — their mean
  path (each repetition resampled to ``points`` time points), their variation around it (a Gaussian with the
  repetitions' own covariance: a new path is the mean plus a standard normal combination of the
  repetitions' deviations), their speed (a log-normal number of frames, from the repetitions' lengths) and
  the frame-to-frame jitter the resampled path leaves out; :func:`draw_person` draws gestures from it.
* :func:`real_person_draw` runs, for one draw (its episodes' actions, objects, effects and words, drawn as
  the simulated study draws them), a **leave-one-segment-out** loop: for each held-out segment, a generator
  fitted to the 10 others gives the gestures of the episodes; every learner (labels from the network with
  and without words, random labels as accurate, clusters named by the network, the true labels) learns
  online from them (:func:`glu.studies.learning.online.run_online`) and recognises the held-out real
  segment. Beside them: a recogniser that always answers tap.
* The same draw also trains the learners on glu's **standard gesture generator** (as ``glu learn-gestures
  --online`` does), on raw and on the study's features, and recognises all 11 segments.

:func:`real_person_study` runs the draws (here or on Dask); :func:`real_person_summary` gives each learner's
accuracy over the segments with a bootstrap interval that resamples the draws and the segments (crossed), its
gap to the true labels and its difference to always answering tap. One person and three recordings cannot
support a general claim: the study says what happens for this person.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
import pandas as pd

from glu.bn.inference import Engine
from glu.errors import DataError
from glu.gestures.corpus import LabelledSequence
from glu.gestures.invariants import Invariants
from glu.stats import adjust, adjusted_verdict, bootstrap_p_value, interval
from glu.studies.learning.online import Learner, OnlineSettings, run_online
from glu.studies.learning.self_supervised import (
    AMBIGUITIES,
    WORLDS,
    draw_actions,
    draw_world,
    matched_random_labels,
    network_posteriors,
    resampled,
    simulate_episodes,
)
from glu.studies.learning.study import run_units, settings_dict
from glu.tidy import tidy

REAL_KEY, REAL_RANDOM_KEY, REAL_BOOT_KEY = 8, 9, 10
"""Spawn keys of the fitted generator's draws, of the random labels and of the bootstrap."""
LEARNERS: tuple[tuple[str, bool], ...] = (
    ("true", False),
    ("hard", False),
    ("soft", False),
    ("iterative", False),
    ("em", False),
    ("random", False),
    ("clustering", False),
    ("hard", True),
    ("soft", True),
    ("random", True),
)
"""The learners of the real-person study, as (learner, words)."""
GENERATOR_LEARNERS: tuple[str, ...] = ("true", "hard", "soft", "random", "clustering")
"""The learners trained on the standard generator (without words)."""


@dataclass(frozen=True)
class RealPersonSettings:
    """The real-person study's size.

    Attributes
    ----------
    draws : the draws (each: the episodes' actions, objects, effects and words, and the generators' gestures)
    episodes : episodes drawn from the person's fitted generator, per held-out segment and draw
    generator_episodes : episodes drawn from glu's standard generator, per draw
    features : the features the HMMs learn and recognise (an :class:`~glu.gestures.invariants.Invariants`
        name); the standard generator's recognisers also on raw features
    ambiguity : the objects people act on (:data:`~glu.studies.learning.self_supervised.AMBIGUITIES`)
    points : time points of the fitted generator's paths
    min_log_sd : the smallest spread of the log number of frames (two repetitions can be nearly as long)
    online : how the learners learn
    bootstrap : replicates of the crossed bootstrap (draws × segments)
    """

    draws: tuple[int, ...] = tuple(range(50))
    episodes: int = 300
    generator_episodes: int = 2000
    features: str = "centred"
    ambiguity: str = "mixed"
    points: int = 24
    min_log_sd: float = 0.05
    online: OnlineSettings = field(default_factory=OnlineSettings)
    bootstrap: int = 2000

    def __post_init__(self) -> None:
        if not self.draws or len(set(self.draws)) != len(self.draws):
            raise DataError(f"draws {list(self.draws)}: give at least one, each once")
        for k in ("episodes", "generator_episodes"):
            v = getattr(self, k)
            if not (isinstance(v, int) and 10 <= v <= 1_000_000):
                raise DataError(f"{k}={v!r}: a whole number from 10 to 1,000,000")
        if self.ambiguity not in AMBIGUITIES:
            raise DataError(f"unknown ambiguity {self.ambiguity!r}; allowed: {', '.join(AMBIGUITIES)}")
        if not (isinstance(self.points, int) and 4 <= self.points <= 200):
            raise DataError(f"points={self.points!r}: a whole number from 4 to 200")
        Invariants.parse(self.features)

    def as_dict(self) -> dict[str, Any]:
        """The settings as plain data (for the saved study's provenance)."""
        return settings_dict(self)


def settings_from_parameters(params: Mapping[str, Any]) -> RealPersonSettings:
    """The real person's settings from notebook 12's parameters: draws 0 … ``real_draws`` − 1 of
    ``real_episodes`` episodes per held-out segment; computed here (``saved`` ``"none"``), also as many
    episodes from glu's standard generator and ``bootstrap`` replicates (a saved run keeps its own)."""
    draws = params.get("real_draws", len(RealPersonSettings.draws))
    if isinstance(draws, bool) or not isinstance(draws, int) or draws < 1:
        raise DataError(f"real_draws={draws!r}: a whole number of draws ≥ 1")
    given: dict[str, Any] = {
        "draws": tuple(range(draws)),
        "episodes": params.get("real_episodes", RealPersonSettings.episodes),
    }
    if params.get("saved") == "none":
        given["generator_episodes"] = given["episodes"]
        given["bootstrap"] = params.get("bootstrap", RealPersonSettings.bootstrap)
    return RealPersonSettings(**given)


class PersonGenerator(NamedTuple):
    """A gesture generator fitted to one person's repetitions (:func:`fit_person`).

    Attributes
    ----------
    actions : the actions it draws
    mean : array, shape (A, P, D) — each action's mean path at P time points
    deviations : per action, array (n_a, P·D) — its repetitions' deviations from the mean over √(n_a − 1)
        (a draw adds ``zᵀ deviations``, z standard normal: the repetitions' own covariance)
    log_frames : array, shape (A, 2) — the mean and standard deviation of the log number of frames
    jitter : array, shape (A, D) — the standard deviation of each frame around the resampled path
    """

    actions: tuple[str, ...]
    mean: np.ndarray
    deviations: list[np.ndarray]
    log_frames: np.ndarray
    jitter: np.ndarray


def _stretch(path: np.ndarray, n: int) -> np.ndarray:
    """A path of P points (P, D) linearly interpolated to ``n`` frames."""
    t = np.linspace(0.0, 1.0, len(path))
    u = np.linspace(0.0, 1.0, n)
    return np.stack([np.interp(u, t, path[:, d]) for d in range(path.shape[1])], axis=1)


def fit_person(
    repetitions: Sequence[tuple[str, np.ndarray]],
    actions: Sequence[str],
    points: int = 24,
    min_log_sd: float = 0.05,
) -> PersonGenerator:
    """Fit a :class:`PersonGenerator` to ``(action, features)`` repetitions, features of shape (T, D)."""
    means, devs, frames, jitter = [], [], [], []
    for a in actions:
        xs = [np.asarray(x, dtype=float) for act, x in repetitions if act == a]
        if not xs:
            raise DataError(f"fit_person: no repetition of {a!r} to fit")
        paths = resampled(xs, points)  # (n, P·D)
        mean = paths.mean(axis=0)
        n = len(xs)
        devs.append((paths - mean) / np.sqrt(n - 1) if n > 1 else np.zeros((1, paths.shape[1])))
        D = xs[0].shape[1]
        means.append(mean.reshape(points, D))
        logs = np.log([len(x) for x in xs])
        frames.append([logs.mean(), max(min_log_sd, logs.std(ddof=1) if n > 1 else 0.0)])
        resid = np.concatenate(
            [x - _stretch(p.reshape(points, D), len(x)) for x, p in zip(xs, paths, strict=True)]
        )
        jitter.append(resid.std(axis=0))
    return PersonGenerator(tuple(actions), np.array(means), devs, np.array(frames), np.array(jitter))


def draw_person(gen: PersonGenerator, actions: np.ndarray, rng: np.random.Generator) -> list[np.ndarray]:
    """One gesture per action index (into ``gen.actions``), arrays of shape (T_i, D)."""
    out = []
    P, D = gen.mean.shape[1:]
    for a in np.asarray(actions, dtype=int):
        dev = gen.deviations[a]
        path = gen.mean[a] + (rng.standard_normal(len(dev)) @ dev).reshape(P, D)
        mu, sd = gen.log_frames[a]
        n = max(12, int(round(np.exp(mu + sd * rng.standard_normal()))))
        out.append(_stretch(path, n) + rng.normal(0.0, gen.jitter[a], size=(n, D)))
    return out


def _sources(engine, actions: np.ndarray, settings: RealPersonSettings, draw: int, words=(False, True)):
    """The network's posteriors and the matched random labels of a draw's episodes, by (kind, words)."""
    drawn, seen = draw_world(engine, actions, AMBIGUITIES[settings.ambiguity], draw, 0)
    k = engine.bn.schema.cardinality("Action")
    sources, label_acc = {}, {}
    for w in words:
        p = network_posteriors(engine, seen, drawn, w)
        acc = float((p.argmax(axis=1) == actions).mean())
        rng = np.random.default_rng(np.random.SeedSequence(draw, spawn_key=(REAL_RANDOM_KEY, int(w))))
        sources["network", w], sources["random", w] = p, matched_random_labels(actions, acc, k, rng)
        label_acc[w] = acc
    return sources, label_acc


def _spec(learner: str, words: bool) -> Learner:
    if learner == "true":
        return Learner("true")
    return Learner(learner, ("random" if learner == "random" else "network", words))


def _predict(run, k: int, seqs: Sequence[np.ndarray]) -> list[str | None]:
    """Learner ``k``'s answer for each sequence; None while it has no model at all."""
    if not run.exists[k].any():
        return [None] * len(seqs)
    rec = run.recognizer(k)
    return [rec.classify(x) for x in seqs]


class RealPersonJob(NamedTuple):
    """What one Dask task needs: the settings and the person's standing repetitions."""

    settings: RealPersonSettings
    standing: list[LabelledSequence]


def real_person_draw(engine: Engine, draw: int, job: RealPersonJob) -> list[dict[str, Any]]:
    """One draw of the study (a Dask task): the leave-one-segment-out loop on the fitted generator, and the
    standard generator's recognisers on every segment; one row per learner and test segment."""
    s, stand = job.settings, job.standing
    actions = engine.bn.schema.values_of("Action")
    spec = Invariants.parse(s.features)
    true = np.array([actions.index(x.action) for x in stand])
    ep_actions = draw_actions(engine, s.episodes, draw)
    sources, label_acc = _sources(engine, ep_actions, s, draw)
    specs = [_spec(lr, w) for lr, w in LEARNERS]
    rows = []

    def row(study, features, learner, words, seg, predicted, labels):
        return (
            dict(draw=draw, study=study, features=features, learner=learner, words=words)
            | dict(
                recording=seg.recording, start=seg.start, end=seg.end, action=seg.action, predicted=predicted
            )
            | dict(correct=predicted == seg.action, label_accuracy=labels)
        )

    for fold, held in enumerate(stand):
        rest = [(x.action, x.xyz) for j, x in enumerate(stand) if j != fold]
        gen = fit_person(rest, actions, s.points, s.min_log_sd)
        rng = np.random.default_rng(np.random.SeedSequence(draw, spawn_key=(REAL_KEY, fold)))
        feats = [spec.transform(x) for x in draw_person(gen, ep_actions, rng)]
        test = [spec.transform(held.xyz)]
        run = run_online(
            feats,
            ep_actions,
            specs,
            sources,
            test,
            true[fold : fold + 1],
            [s.episodes],
            actions,
            s.online,
            draw,
        )
        for k, (lr, w) in enumerate(LEARNERS):
            rows.append(row("fitted", spec.name, lr, w, held, _predict(run, k, test)[0], label_acc[w]))
        rows.append(row("fitted", spec.name, "always_tap", False, held, "tap", np.nan))
    rows += _generator_rows(engine, draw, stand, s, row)
    return rows


def _generator_rows(engine, draw, stand, s: RealPersonSettings, row) -> list[dict[str, Any]]:
    """The standard generator's recognisers on every segment, on raw and on the study's features."""
    actions = engine.bn.schema.values_of("Action")
    ep = simulate_episodes(engine, AMBIGUITIES[s.ambiguity], s.generator_episodes, draw, world=WORLDS["easy"])
    sources, label_acc = _sources(engine, ep.actions, s, draw, words=(False,))
    specs = [_spec(lr, False) for lr in GENERATOR_LEARNERS]
    true = np.array([actions.index(x.action) for x in stand])
    out = []
    for name in dict.fromkeys(("raw", Invariants.parse(s.features).name)):
        spec = Invariants.parse(name)
        feats = [spec.transform(x) for x in ep.features]
        test = [spec.transform(x.xyz) for x in stand]
        run = run_online(
            feats, ep.actions, specs, sources, test, true, [s.generator_episodes], actions, s.online, draw
        )
        for k, lr in enumerate(GENERATOR_LEARNERS):
            for seg, pred in zip(stand, _predict(run, k, test), strict=True):
                out.append(row("generator", spec.name, lr, False, seg, pred, label_acc[False]))
        out += [row("generator", spec.name, "always_tap", False, seg, "tap", np.nan) for seg in stand]
    return out


def real_person_study(
    engine: Engine,
    standing: Sequence[LabelledSequence],
    settings: RealPersonSettings = RealPersonSettings(),
    *,
    workers: int = 0,
    scheduler: str | None = None,
    progress: Callable[[int], None] | None = None,
    data_source: str = "",
) -> pd.DataFrame:
    """Every draw of the study, here (``workers=0``, no scheduler) or as Dask tasks; one row per draw,
    study (``fitted``: leave-one-segment-out on the person's fitted generator; ``generator``: glu's standard
    generator), features, learner, words and test segment: predicted, correct, label_accuracy."""
    actions = engine.bn.schema.values_of("Action")
    stand = [x for x in standing if x.action in actions]
    missing = [a for a in actions if sum(x.action == a for x in stand) < 2]
    if missing:
        raise DataError(
            f"the real-person study needs two repetitions of each action at least: {', '.join(missing)}"
        )
    job = RealPersonJob(settings, stand)
    parts = run_units(real_person_draw, engine, job, settings.draws, workers, scheduler, progress)
    df = pd.DataFrame([r for p in parts for r in p])
    return tidy(df, "learning_real_person", data_source, **settings.as_dict())


def _crossed(values: np.ndarray, replicates: int, rng: np.random.Generator) -> np.ndarray:
    """Crossed bootstrap of a (draws, segments, K) array: each replicate resamples the draws and, apart, the
    segments; the weighted mean ``vᵀ X w / (Σv Σw)`` per column, shape (replicates + 1, K) (row 0: all
    weights 1)."""
    R, S = values.shape[:2]
    v = np.ones((replicates + 1, R))
    w = np.ones((replicates + 1, S))
    if replicates:
        v[1:] = rng.multinomial(R, np.full(R, 1.0 / R), size=replicates)
        w[1:] = rng.multinomial(S, np.full(S, 1.0 / S), size=replicates)
    total = np.einsum("br,rsk,bs->bk", v, values, w)
    return total / (v.sum(axis=1) * w.sum(axis=1))[:, None]


def real_person_summary(rows: pd.DataFrame, replicates: int = 2000) -> pd.DataFrame:
    """Each learner's accuracy over the segments and draws, with a crossed bootstrap interval (draws and
    segments resampled apart), its gap to the true labels of the same study and features, and its difference
    to always answering tap (verdicts adjusted by Benjamini–Hochberg over the table).

    Columns: study, features, learner, words, accuracy, ci_low, ci_high, gap, gap_low, gap_high,
    vs_tap, vs_tap_low, vs_tap_high, q_vs_tap, vs_tap_verdict, label_accuracy, draws, segments,
    recordings."""
    keys = ["study", "features", "learner", "words"]
    rows = rows.assign(
        words=rows["words"].astype(object), segment=rows["recording"] + ":" + rows["start"].astype(str)
    )
    groups = list(rows.groupby(keys, sort=False, dropna=False).groups)
    draws = sorted(rows["draw"].unique())
    segs = list(dict.fromkeys(rows["segment"]))
    cube = np.full((len(draws), len(segs), len(groups)), np.nan)
    index = {g: k for k, g in enumerate(groups)}
    label_accuracy = {}
    for key, g in rows.groupby(keys, sort=False, dropna=False):
        piv = g.pivot_table(index="draw", columns="segment", values="correct", aggfunc="mean")
        cube[:, :, index[key]] = piv.reindex(index=draws, columns=segs).to_numpy(dtype=float)
        label_accuracy[key] = g["label_accuracy"].mean()
    seed = rows.attrs.get("parameters", {}).get("draws", [0])
    rng = np.random.default_rng(np.random.SeedSequence(list(seed), spawn_key=(REAL_BOOT_KEY,)))
    reps = _crossed(np.nan_to_num(cube), replicates, rng)
    lo, hi = interval(reps)
    nan = np.full(len(reps), np.nan)

    def ref(study, features, learner):
        return index.get((study, features, learner, False))

    out = []
    for (study, features, learner, words), k in index.items():
        t, tap = ref(study, features, "true"), ref(study, features, "always_tap")
        gap = reps[:, k] - reps[:, t] if t is not None else nan
        vs = reps[:, k] - reps[:, tap] if tap is not None and tap != k else nan
        out.append(
            dict(study=study, features=features, learner=learner, words=words, accuracy=reps[0, k])
            | dict(ci_low=lo[k], ci_high=hi[k])
            | dict(zip(("gap", "gap_low", "gap_high"), (gap[0], *interval(gap)), strict=True))
            | dict(zip(("vs_tap", "vs_tap_low", "vs_tap_high"), (vs[0], *interval(vs)), strict=True))
            | dict(p_vs_tap=float(bootstrap_p_value(vs)) if np.isfinite(vs[0]) else np.nan)
            | dict(label_accuracy=label_accuracy[study, features, learner, words], draws=len(draws))
            | dict(segments=len(segs))
            | dict(recordings=rows["recording"].nunique())
        )
    df = pd.DataFrame(out)
    df["q_vs_tap"] = adjust(df["p_vs_tap"].to_numpy(), "bh")
    df["vs_tap_verdict"] = [
        "" if np.isnan(qq) else adjusted_verdict(d, qq)
        for d, qq in zip(df["vs_tap"], df["q_vs_tap"], strict=True)
    ]
    return tidy(
        df,
        "learning_real_person_summary",
        rows.attrs.get("data_source", ""),
        **rows.attrs.get("parameters", {}),
    )


def real_person_lines(summary: pd.DataFrame) -> list[str]:
    """One sentence per study and features, from :func:`real_person_summary`: each learner's accuracy with
    its interval, and always answering tap."""
    from glu.studies.learning.tables import LEARNER_NAMES

    out = []
    for (study, features), g in summary.groupby(["study", "features"], sort=False):
        where = (
            "Learned from a generator fitted to the person's other repetitions (leave-one-segment-out)"
            if study == "fitted"
            else "Learned from glu's standard gesture generator"
        )
        parts = [
            f"{LEARNER_NAMES.get(r.learner, r.learner)}{' with words' if r.words is True else ''} "
            f"{r.accuracy:.2f} [{r.ci_low:.2f}, {r.ci_high:.2f}]"
            for r in g.itertuples()
        ]
        n, d = int(g["segments"].iloc[0]), int(g["draws"].iloc[0])
        out.append(f"{where}, {features} features, on {n} segments × {d} draws: " + "; ".join(parts) + ".")
    return out
