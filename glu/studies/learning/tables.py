"""The tables of learning from effects, from the seeds' results (:mod:`glu.studies.learning.study`).

Every interval is a two-level bootstrap interval (the seeds resampled, then the held-out gestures within each
seed: :func:`glu.stats.two_level_weights`), every difference between learners is resampled paired (the same
weights for both), and every verdict is adjusted for the number of verdicts in its table
(Benjamini–Hochberg, :func:`glu.stats.adjust`).

* :func:`curves_table` — accuracy against episodes seen, with the gap to the true-label HMMs;
* :func:`budgets_table` — the main table: at each fixed budget, each learner's accuracy and its gap to the
  true-label HMMs with an interval and an equivalence verdict (TOST against the declared margin), and each
  scheme's difference to random labels as accurate as the network's;
* :func:`claims_table` — per claim (effects without words; words), world and budget: in which ambiguities
  learning from effects matches the true labels, and beats the random labels;
* :func:`labels_table` — how good the network's labels are;
* :func:`claim_lines` — the sentences the notebook and the README print, written from the claims.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
import pandas as pd

from glu.stats import (
    ALPHA,
    LEVEL,
    adjust,
    adjusted_verdict,
    bootstrap_p_value,
    equivalence_verdict,
    interval,
    replicate_means,
    tost_p_value,
    two_level_weights,
)
from glu.studies.learning.self_supervised import AMBIGUITIES, SCHEMES
from glu.studies.learning.study import BOOT_KEY, SeedResult, StudySettings
from glu.tidy import tidy

CLAIMS: dict[str, tuple[bool, str]] = {
    "effects": (
        False,
        "Effects without words (the robot is never told the action: TCDS's 'beyond the self')",
    ),
    "words": (True, "Effects and words (supervision by the spoken verb)"),
}
"""The two claims, reported apart: whether the robot hears words, and what that makes the study."""
LEARNER_NAMES: dict[str, str] = {
    "hard": "hard labels",
    "soft": "soft labels",
    "confident": "confident labels",
    "iterative": "iterative labels",
    "random": "random labels as accurate as the network's",
    "clustering": "clusters named by the network",
    "em": "semi-supervised EM",
    "true": "true labels",
    "unsupervised": "clusters named by the true actions",
    "supervised_1": "1 true label per action",
    "supervised_5": "5 true labels per action",
    "network": "the network alone",
    "always_tap": "always answering tap",
}
"""How tables and sentences name each learner."""


class Replicates(NamedTuple):
    """Bootstrap replicates of every learner's accuracy (row 0: the estimate).

    Attributes
    ----------
    learners, checkpoints, groups : as :class:`~glu.studies.learning.study.SeedResult` has them
    hmm : array, shape (B + 1, C, L)
    network : array, shape (B + 1, G) — the network alone (no episodes)
    seeds, tests : how many seeds and held-out gestures per seed
    """

    learners: list[tuple[str, str, str, bool | None]]
    checkpoints: np.ndarray
    hmm: np.ndarray
    groups: list[tuple[str, str, bool]]
    network: np.ndarray
    seeds: int
    tests: int

    def gaps(self) -> np.ndarray:
        """Replicates of each learner's accuracy minus its world's true-label HMMs', shape (B + 1, C, L)."""
        return self.hmm - self.hmm[:, :, [self.true_of(lr[0]) for lr in self.learners]]

    def network_gaps(self) -> np.ndarray:
        """The network alone minus the true-label HMMs of its world, shape (B + 1, C, G)."""
        idx = [self.true_of(world) for world, _, _ in self.groups]
        return self.network[:, None, :] - self.hmm[:, :, idx]

    def true_of(self, world: str) -> int:
        """The column of ``world``'s true-label learner."""
        return next(k for k, lr in enumerate(self.learners) if lr[0] == world and lr[1] == "true")


def replicates(results: Sequence[SeedResult], settings: StudySettings) -> Replicates:
    """The two-level bootstrap replicates of every learner at every checkpoint (seeds, then held-out gestures
    within each seed; the same weights for every learner, so that differences are paired)."""
    first = results[0]
    correct = np.stack([np.moveaxis(r.correct, 2, 0) for r in results]).astype(float)  # (S, J, C, L)
    network = np.stack([r.network_correct.T for r in results]).astype(float)  # (S, J, G)
    S, J = correct.shape[:2]
    rng = np.random.default_rng(np.random.SeedSequence(list(settings.seeds), spawn_key=(BOOT_KEY,)))
    W = two_level_weights(S, J, settings.bootstrap, rng)
    return Replicates(
        [tuple(lr) for lr in first.learners],
        np.asarray(first.checkpoints),
        replicate_means(correct, W),
        [tuple(g) for g in first.groups],
        replicate_means(network, W),
        S,
        J,
    )


def _stamp(
    df: pd.DataFrame, name: str, settings: StudySettings, source: str, rep: Replicates
) -> pd.DataFrame:
    df["seeds"], df["test_gestures"] = rep.seeds, rep.tests
    return tidy(df, name, source, **settings.as_dict())


def curves_table(rep: Replicates, settings: StudySettings, data_source: str = "") -> pd.DataFrame:
    """Accuracy against episodes seen, per world, learner, ambiguity and words, with two-level intervals.

    Columns: world, learner (:data:`LEARNER_NAMES`), ambiguity and words (empty and None for the baselines
    measured once per world), episodes, accuracy, ci_low, ci_high, gap (accuracy − the true-label HMMs' of
    the same world, seeds and held-out gestures), gap_low, gap_high, seeds, test_gestures. The network's rows
    repeat its (episode-free) accuracy at every checkpoint.
    """
    names, acc, gap = _everyone(rep)
    lo, hi = interval(acc)
    glo, ghi = interval(gap)
    rows = [
        dict(world=world, learner=lr, ambiguity=amb, words=words, episodes=int(n))
        | dict(accuracy=acc[0, c, k], ci_low=lo[c, k], ci_high=hi[c, k])
        | dict(gap=gap[0, c, k], gap_low=glo[c, k], gap_high=ghi[c, k])
        for c, n in enumerate(rep.checkpoints)
        for k, (world, lr, amb, words) in enumerate(names)
    ]
    return _stamp(pd.DataFrame(rows), "learning_curves", settings, data_source, rep)


def _everyone(rep: Replicates) -> tuple[list[tuple[str, str, str, bool | None]], np.ndarray, np.ndarray]:
    """Every learner, then the network alone of every group (learner ``network``), as (world, learner,
    ambiguity, words), with their accuracy and gap replicates, shape (B + 1, C, L + G)."""
    names = list(rep.learners) + [(world, "network", amb, words) for world, amb, words in rep.groups]
    network = np.repeat(rep.network[:, None, :], len(rep.checkpoints), axis=1)
    gaps = np.concatenate([rep.gaps(), rep.network_gaps()], axis=2)
    return names, np.concatenate([rep.hmm, network], axis=2), gaps


def _columns(rep: Replicates, budgets: Sequence[int]) -> tuple[list[dict], np.ndarray, np.ndarray]:
    """The main table's rows (without verdicts), their accuracy replicates and their gap replicates, (B + 1,
    rows): at each budget, world by world, its learners and then its network rows."""
    names, acc, gap = _everyone(rep)
    idx = {int(n): c for c, n in enumerate(rep.checkpoints)}
    worlds = dict.fromkeys(lr[0] for lr in rep.learners)
    cells = [(int(n), k) for n in budgets for w in worlds for k, name in enumerate(names) if name[0] == w]
    rows = [
        dict(world=names[k][0], budget=n, learner=names[k][1], ambiguity=names[k][2], words=names[k][3])
        for n, k in cells
    ]
    acc = np.stack([acc[:, idx[n], k] for n, k in cells], axis=1)
    return rows, acc, np.stack([gap[:, idx[n], k] for n, k in cells], axis=1)


def budgets_table(rep: Replicates, settings: StudySettings, data_source: str = "") -> pd.DataFrame:
    """The main table: at each budget, each learner's accuracy and its gap to the true-label HMMs, with
    intervals, an equivalence verdict and the difference to random labels as accurate as the network's.

    Columns: world, budget (episodes seen), learner, ambiguity, words; accuracy, ci_low, ci_high (95 %);
    gap, gap_low, gap_high (95 %), gap_low90, gap_high90 (the 90 % interval the equivalence test reads);
    p_equivalent (TOST against ± ``settings.margin``), q_equivalent (Benjamini–Hochberg over the table),
    equivalent; p_difference (the gap ≠ 0), q_difference; verdict: ``equivalent`` (q_equivalent ≤ α),
    else ``worse`` or ``better`` (q_difference ≤ α), else ``inconclusive``; vs_random, vs_random_low,
    vs_random_high, q_vs_random, vs_random_verdict (better, worse, no difference) for every learner of a
    condition but the random labels themselves. The true labels' own row has no gap verdict.
    """
    rows, acc, gap = _columns(rep, settings.main_budgets)
    df = pd.DataFrame(rows)
    lo, hi = interval(acc)
    glo, ghi = interval(gap)
    q90 = np.percentile(gap[1:], [5, 95], axis=0)
    df["accuracy"], df["ci_low"], df["ci_high"] = acc[0], lo, hi
    df["gap"], df["gap_low"], df["gap_high"], df["gap_low90"], df["gap_high90"] = gap[0], glo, ghi, *q90
    own = (df["learner"] == "true").to_numpy()
    p_eq = np.where(own, np.nan, tost_p_value(gap, settings.margin))
    p_diff = np.where(own, np.nan, bootstrap_p_value(gap))
    df["p_equivalent"], df["q_equivalent"] = p_eq, adjust(p_eq, "bh")
    df["equivalent"] = [equivalence_verdict(q) for q in df["q_equivalent"]]
    df["p_difference"], df["q_difference"] = p_diff, adjust(p_diff, "bh")
    df["verdict"] = [
        "" if o else "equivalent" if e else _difference(d, q)
        for o, e, d, q in zip(own, df["equivalent"], df["gap"], df["q_difference"], strict=True)
    ]
    _against_random(df, acc)
    df["margin"] = settings.margin
    return _stamp(df, "learning_budgets", settings, data_source, rep)


def _difference(estimate: float, q: float) -> str:
    v = adjusted_verdict(estimate, q)
    return "inconclusive" if v == "no difference" else v


def _against_random(df: pd.DataFrame, acc: np.ndarray) -> None:
    """Each learner of a condition against the random labels of the same world, condition and budget."""
    key = ["world", "budget", "ambiguity", "words"]
    rand = {tuple(r[k] for k in key): i for i, r in df[df["learner"] == "random"].iterrows()}
    diff = np.full((acc.shape[0], len(df)), np.nan)
    for i, r in df.iterrows():
        j = rand.get(tuple(r[k] for k in key))
        if j is not None and r["learner"] not in ("random", "network"):
            diff[:, i] = acc[:, i] - acc[:, j]
    lo, hi = interval(diff)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        p = bootstrap_p_value(diff)
    q = adjust(p, "bh")
    df["vs_random"], df["vs_random_low"], df["vs_random_high"] = diff[0], lo, hi
    df["q_vs_random"] = q
    df["vs_random_verdict"] = [
        "" if np.isnan(x) else adjusted_verdict(d, x) for d, x in zip(diff[0], q, strict=True)
    ]


def claims_table(budgets: pd.DataFrame, schemes: Sequence[str] = SCHEMES) -> pd.DataFrame:
    """Per claim (:data:`CLAIMS`), world and budget: the ambiguities (conditions) where a labelling scheme
    matches the true labels (equivalent), where random labels as accurate as the network's match them too,
    where a scheme beats those random labels, and where every scheme is worse than the true labels.

    Columns: claim, world, budget, conditions, matched, matched_where (``ambiguity: scheme, …``),
    random_matched, random_where, beats_random, beats_random_where, all_worse, all_worse_where, best_where
    (each ambiguity's best scheme, its accuracy and gap).
    """
    rows = []
    for claim, (words, _) in CLAIMS.items():
        part = budgets[budgets["words"].astype(object).eq(words) & budgets["ambiguity"].ne("")]
        for (world, budget), g in part.groupby(["world", "budget"], sort=False):
            matched, rnd, beats, worse, best = [], [], [], [], []
            for amb, a in g.groupby("ambiguity", sort=False):
                s = a[a["learner"].isin(schemes)]
                eq = s[s["verdict"] == "equivalent"]["learner"].tolist()
                if eq:
                    matched.append(f"{amb}: {', '.join(eq)}")
                if (a[a["learner"] == "random"]["verdict"] == "equivalent").any():
                    rnd.append(amb)
                up = s[s["vs_random_verdict"] == "better"]["learner"].tolist()
                if up:
                    beats.append(f"{amb}: {', '.join(up)}")
                if len(s) and (s["verdict"] == "worse").all():
                    worse.append(amb)
                top = s.loc[s["accuracy"].idxmax()]
                best.append(f"{amb}: {top['learner']} {top['accuracy']:.3f} (gap {top['gap']:+.3f})")
            rows.append(
                dict(claim=claim, world=world, budget=int(budget), conditions=g["ambiguity"].nunique())
                | dict(matched=len(matched), matched_where="; ".join(matched))
                | dict(random_matched=len(rnd), random_where=", ".join(rnd))
                | dict(beats_random=len(beats), beats_random_where="; ".join(beats))
                | dict(all_worse=len(worse), all_worse_where=", ".join(worse), best_where="; ".join(best))
            )
    return tidy(
        pd.DataFrame(rows),
        "learning_claims",
        budgets.attrs.get("data_source", ""),
        **budgets.attrs.get("parameters", {}),
    )


def labels_table(
    results: Sequence[SeedResult], settings: StudySettings, data_source: str = ""
) -> pd.DataFrame:
    """How good the labels of the training episodes are, per world, ambiguity and words (mean over seeds):
    label_accuracy (the network's arg-max), confident_fraction and confident_accuracy (above the ``confident``
    threshold), mean_p_true (its probability of the true action), random_accuracy (the random labels')."""
    first = results[0]
    stacked = np.stack([r.labels for r in results])
    with warnings.catch_warnings():  # a group without confident labels in any seed stays NaN
        warnings.simplefilter("ignore", RuntimeWarning)
        labels = np.nanmean(stacked, axis=0)
    rows = [
        dict(world=world, ambiguity=amb, words=words, description=AMBIGUITIES[amb].description)
        | dict(label_accuracy=v[0], confident_fraction=v[1], confident_accuracy=v[2], mean_p_true=v[3])
        | dict(random_accuracy=v[4])
        for (world, amb, words), v in zip(first.groups, labels, strict=True)
    ]
    return tidy(pd.DataFrame(rows), "learning_labels", data_source, **settings.as_dict())


def intervals_line(settings: StudySettings) -> str:
    """How the tables' intervals are made, in one sentence: the two-level bootstrap's level and replicates
    over the seeds and each seed's held-out gestures (``test_per_action`` of each of the three actions),
    and the interval the equivalence tests read."""
    return (
        f"Intervals: {LEVEL:.0%} two-level bootstrap ({settings.bootstrap:,} replicates over "
        f"{len(settings.seeds)} seeds and {3 * settings.test_per_action} held-out gestures each); "
        f"equivalence reads the {1 - 2 * ALPHA:.0%} interval."
    )


def claim_lines(claims: pd.DataFrame, margin: float) -> list[str]:
    """One sentence per claim and world, from :func:`claims_table`: at each budget, in how many ambiguities a
    labelling scheme matches the true labels (equivalent within ± ``margin``, adjusted), in how many random
    labels as accurate as the network's match them too, and in how many a scheme beats those random labels."""
    out = []
    for (claim, world), g in claims.groupby(["claim", "world"], sort=False):
        g = g.sort_values("budget")
        n = int(g["conditions"].iloc[0])
        parts = []
        for r in g.itertuples():
            where = f" ({r.matched_where})" if r.matched else ""
            parts.append(
                f"after {r.budget:,} episodes, a scheme matches them in {r.matched} of {n}{where}, "
                f"random labels as accurate in {r.random_matched}, and a scheme beats those random labels "
                f"in {r.beats_random}"
            )
        out.append(
            f"{CLAIMS[claim][1]}, {world} world (matching = equivalent to the true labels "
            f"within ±{margin:g}, TOST, Benjamini–Hochberg over the table): " + "; ".join(parts) + "."
        )
    return out


def main_table(budgets: pd.DataFrame, words: bool) -> pd.DataFrame:
    """The main table of one claim, for reading: a row per world, ambiguity (``baselines`` for the learners
    measured once per world) and learner; a column per budget, each cell the accuracy, the gap to the true
    labels with its 95 % interval and the verdict (and, where the difference is significant, how the learner
    fares against random labels as accurate as the network's)."""
    b = budgets[budgets["words"].astype(object).eq(words) | budgets["ambiguity"].eq("")]

    def cell(r) -> str:
        if r.learner == "true":
            return f"{r.accuracy:.3f}"
        text = f"{r.accuracy:.3f}  {r.gap:+.3f} [{r.gap_low:+.3f}, {r.gap_high:+.3f}] {r.verdict}"
        if r.vs_random_verdict == "better":
            text += "; beats random labels"
        elif r.vs_random_verdict == "worse":
            text += "; below random labels"
        return text

    rows = [
        dict(
            world=r.world,
            ambiguity=r.ambiguity or "baselines",
            learner=LEARNER_NAMES.get(r.learner, r.learner),
        )
        | dict(budget=f"{r.budget:,} episodes", cell=cell(r))
        for r in b.itertuples()
    ]
    df = pd.DataFrame(rows)
    order = list(dict.fromkeys(df["budget"]))
    out = df.pivot_table(
        index=["world", "ambiguity", "learner"], columns="budget", values="cell", aggfunc="first", sort=False
    )
    return out[order]
