"""The README's bullet on learning gestures from effects (notebook 12), written from its tables.

Every slot is filled by :func:`values` from the run's tables; only the papers' numbers are typed.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd

from glu.errors import DataError

TEMPLATE = """\
* **Beyond the self: learning people's gestures from what their actions did** (`12_learning_from_effects`: \
the robot labels unlabelled episodes with its network and learns its HMMs online; {learn_seeds:.0f} seeds, \
budgets of {learn_budgets}; beside each labelling scheme, random labels as accurate as the network's, \
clusters named by the network, semi-supervised EM and {learn_supervised} true labels per action; "matches": \
equivalent to the true labels within ±{learn_margin:g} accuracy, two one-sided tests on two-level bootstrap \
intervals, Benjamini–Hochberg over {learn_tests:.0f} tests; every cell in the notebook). The network's \
labels are right for {label_mixed:.2f} of the episodes on every object without words, \
{label_mixed_words:.2f} with words; the true labels reach {learn_true_easy:.3f} after {learn_last:,.0f} \
episodes in the easy world, {learn_true_hard:.3f} in the hard one (people varied, sensor noise, turned \
views, effects that follow the gesture).
  * Effects without words (TCDS's "beyond the self"), after {learn_last:,.0f} episodes: {learn_effects}.
  * Effects and words (supervision by the spoken verb), after {learn_last:,.0f} episodes: {learn_words}.
  * {learn_random}.
  * The real person ({real_segments:.0f} standing segments from {real_recordings:.0f} recordings, learned \
leave-one-segment-out from a generator fitted to their other repetitions, {real_draws:.0f} draws): \
{real_fitted}; always answering tap {real_tap}. {real_generator}. One person and {real_recordings_words} \
recordings cannot support a general claim."""
"""The bullet, with ``{name:format}`` slots filled by :func:`values` (each claim at the largest budget; the
notebook has every budget)."""

REQUIRED: tuple[str, ...] = (
    "learning_claims",
    "learning_budgets",
    "learning_labels",
    "learning_real_person_summary",
)
"""The tables of notebook 12 the bullet is written from."""


Tables = Mapping[str, tuple[pd.DataFrame, dict[str, Any]]]


def _at_last(claims: pd.DataFrame, claim: str) -> pd.DataFrame:
    g = claims[claims["claim"] == claim]
    return g[g["budget"] == g["budget"].max()]


def _where(cell: str) -> str:
    """The ambiguities of a ``…_where`` cell (``ambiguity: scheme, …; …``), in words."""
    return ", ".join(part.split(":")[0].strip().replace("_", " ") for part in cell.split(";") if part.strip())


def _claim(claims: pd.DataFrame, claim: str) -> str:
    """Per world, at the largest budget: in how many ambiguities a scheme matches the true labels (which)."""
    out = []
    for r in _at_last(claims, claim).itertuples():
        where = f" ({_where(r.matched_where)})" if r.matched else ""
        out.append(f"{r.world} world {r.matched} of {r.conditions}{where}")
    return "a scheme matches the true labels in " + "; ".join(out) + " ambiguities"


def _random(claims: pd.DataFrame) -> str:
    """At the largest budget, per claim and world: where random labels as accurate as the network's match the
    true labels too, and where a scheme beats them."""
    parts = []
    for claim, words in (("effects", "without words"), ("words", "with words")):
        for r in _at_last(claims, claim).itertuples():
            beats = f" ({_where(r.beats_random_where)})" if r.beats_random else ""
            parts.append(
                f"{r.world} world {words}: they match in {r.random_matched} of {r.conditions}, "
                f"a scheme beats them in {r.beats_random}{beats}"
            )
    return "Random labels as accurate as the network's: " + "; ".join(parts)


def _one(df: pd.DataFrame, error: str, **match: Any) -> pd.Series:
    """The one row of ``df`` whose columns equal ``match``; :class:`DataError` ``error`` otherwise."""
    rows = df[np.logical_and.reduce([df[k].astype(object) == v for k, v in match.items()])]
    if len(rows) != 1:
        raise DataError(error)
    return rows.iloc[0]


def _person(summary: pd.DataFrame, study: str, features: str) -> dict[str, str]:
    s = summary[(summary["study"] == study) & (summary["features"] == features)]
    out = {}
    for lr in dict.fromkeys(s["learner"]):
        error = f"learning_real_person_summary: no single row for {study}, {features}, {lr}"
        r = _one(s, error, learner=lr, words=False)
        out[lr] = f"{r['accuracy']:.2f} [{r['ci_low']:.2f}, {r['ci_high']:.2f}]"
    return out


def _number_word(n: int) -> str:
    """A small count in words (as a sentence reads it), digits beyond ten."""
    words = ("no", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine", "ten")
    return words[n] if 0 <= n < len(words) else f"{n:,}"


def values(tables: Tables) -> dict[str, Any]:
    """The slots of the learning-from-effects bullet (notebook 12): the claims per world and budget
    (:func:`glu.studies.learning.tables.claims_table`), the labels, and the real person."""
    claims, meta = tables["learning_claims"]
    params = meta["parameters"]
    budgets = tables["learning_budgets"][0]
    labels = tables["learning_labels"][0]
    real = tables["learning_real_person_summary"][0]

    def label(amb: str, words: bool) -> float:
        error = f"learning_labels: no single row for the easy world, {amb}, words={words}"
        return float(_one(labels, error, world="easy", ambiguity=amb, words=words)["label_accuracy"])

    last = int(budgets["budget"].max())

    def true_acc(world: str) -> float:
        error = f"learning_budgets: no true-label row for the {world} world at {last} episodes"
        return float(_one(budgets, error, world=world, learner="true", budget=last)["accuracy"])

    fitted = _person(real, "fitted", "centred")
    names = {"true": "true labels", "hard": "hard labels", "soft": "soft labels", "random": "random labels"}
    names["clustering"] = "clusters named by the network"
    gen_features = [f for f in dict.fromkeys(real[real["study"] == "generator"]["features"])]
    gen = []
    for f in gen_features:
        g = _person(real, "generator", f)
        gen.append(
            f"{f} features: "
            + ", ".join(f"{names.get(k, k)} {v}" for k, v in g.items() if k in ("true", "soft"))
        )
    return {
        "learn_seeds": len(params["seeds"]),
        "learn_budgets": ", ".join(f"{b:,}" for b in sorted(budgets["budget"].unique())) + " episodes",
        "learn_margin": float(params["margin"]),
        "learn_tests": int(budgets["p_equivalent"].notna().sum()),
        "label_mixed": label("mixed", False),
        "label_mixed_words": label("mixed", True),
        "learn_true_easy": true_acc("easy"),
        "learn_true_hard": true_acc("hard"),
        "learn_last": last,
        "learn_effects": _claim(claims, "effects"),
        "learn_words": _claim(claims, "words"),
        "learn_random": _random(claims),
        "real_segments": int(real["segments"].iloc[0]),
        "real_recordings": int(real["recordings"].iloc[0]),
        "real_recordings_words": _number_word(int(real["recordings"].iloc[0])),
        "learn_supervised": " or ".join(str(k) for k in params["supervised"]),
        "real_draws": int(real["draws"].iloc[0]),
        "real_fitted": ", ".join(
            f"{names.get(k, k)} {v}"
            for k, v in fitted.items()
            if k in ("true", "soft", "random", "clustering")
        ),
        "real_tap": fitted["always_tap"],
        "real_generator": "Learned from glu's standard generator instead (`glu learn-gestures --online`), "
        + "; ".join(gen),
    }
