"""The replication notebooks' interpretation in sentences, written from their tables (notebooks 07–09).

Each function reads the tidy frames a notebook has just computed and returns sentences, so that a changed
result cannot leave a sentence that contradicts it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd


def _dist(g: pd.DataFrame, value: str = "ObjVel") -> str:
    return ", ".join(f"{r[value]} {r.p:.3f}" for _, r in g.iterrows())


def effect_sentence(effect: pd.DataFrame) -> str:
    """GLU 2017 Fig. 4 in words: p(ObjVel) after a tap on each object, and its most likely value."""
    parts = []
    for case, g in effect.groupby("case", sort=False):
        top = g.loc[g.p.idxmax()]
        parts.append(f"on a {case}, p(ObjVel) is {_dist(g)} (most likely {top.ObjVel})")
    return "After a tap: " + "; ".join(parts) + "."


def word_change_sentences(changes: Mapping[str, pd.DataFrame], n: int = 4) -> list[str]:
    """GLU 2017 Fig. 5 in words: the words the tap raises and lowers most, and how far the two evidence
    variants (the paper's text, the original code's) differ."""
    first = next(iter(changes.values()))
    shown = first[first["shown"]].sort_values("delta")
    up = shown[shown.delta > 0].iloc[::-1][:n]
    down = shown[shown.delta < 0][:n]
    out = [
        "Adding the tap raises "
        + ", ".join(f'"{r.word}" ({r.delta:+.3f})' for r in up.itertuples())
        + " most, and lowers "
        + ", ".join(f'"{r.word}" ({r.delta:+.3f})' for r in down.itertuples())
        + " most."
    ]
    if len(changes) > 1:
        frames = [c.set_index("word")["delta"] for c in changes.values()]
        gap = max(float((f - frames[0].reindex(f.index)).abs().max()) for f in frames[1:])
        names = " and ".join(changes)
        verdict = "equal to rounding" if gap < 1e-12 else "different"
        out.append(f"The {names} variants of the evidence give Δp(w) {verdict} (max |difference| {gap:.1e}).")
    return out


def verbal_sentences(
    reproduced: pd.DataFrame, and_but: pd.DataFrame, versus: pd.DataFrame, trials: pd.DataFrame
) -> list[str]:
    """Notebook 09's results in words: the published lists reproduced, "and" against "but", what the exact
    search over the grammar finds against the samples, and how often random samples hold the best."""
    scored = reproduced["same_score"].dropna().astype(bool)
    out = [
        f"{int(reproduced['same_sentence'].sum())} of {len(reproduced)} published sentences and "
        f"{int(scored.sum())} of {len(scored)} printed scores are reproduced."
    ]
    parts = []
    for objvel, g in and_but.groupby("ObjVel", sort=False):
        p = g.set_index("word")["p"]
        likelier = "but" if p.get("but", 0) > p.get("and", 0) else "and"
        parts.append(
            f"with ObjVel={objvel} p(and) {p.get('and', np.nan):.3f}, p(but) "
            f"{p.get('but', np.nan):.3f} ({likelier} likelier)"
        )
    out.append("After a grasp: " + "; ".join(parts) + ".")
    for score, g in versus.groupby("score_name", sort=False):
        inside = g[g["exact_in_samples"]]["figure"].tolist()
        outside = g[~g["exact_in_samples"]]
        text = f"Under the {score} score, the grammar's best sentence is among the samples for "
        text += ", ".join(inside) or "no evidence set"
        if len(outside):
            text += (
                "; elsewhere the samples' best ranks "
                + ", ".join(f"{int(r.samples_rank)} ({r.figure})" for r in outside.itertuples())
                + " in the grammar"
            )
        out.append(text + ".")
    other = versus.groupby("figure", sort=False)["rank_under_other"].max()
    differ = other[other > 1]
    out.append(
        f"The two scores pick different best sentences for {len(differ)} of {len(other)} evidence sets"
        + (
            " (" + ", ".join(f"{f}: rank {int(r)} under the other" for f, r in differ.items()) + ")"
            if len(differ)
            else ""
        )
        + "."
    )
    out.append(
        f"Random samples of {int(trials['n_samples'].max()):,} sentences held the grammar's best in "
        f"{int(trials['found_best'].sum())} of {len(trials)} trials (exact chance "
        f"{100 * trials['p_draw_best'].mean():.1f} %)."
    )
    return out


def leader_text(actions: Sequence[str], p_hmm: np.ndarray, update_t: Sequence[int]) -> str:
    """``"grasp from t = 5, touch from t = 10, tap from t = 70"``: the HMMs' leading action at the updates,
    where it changes (``p_hmm`` shape (T, A), ``update_t`` 1-based frames)."""
    out: list[tuple[int, str]] = []
    for t in update_t:
        a = actions[int(np.argmax(p_hmm[int(t) - 1]))]
        if not out or out[-1][1] != a:
            out.append((int(t), a))
    return ", ".join(f"{a} from t = {t}" for t, a in out)


def anticipation_sentence(case: str, hmms: str, run: Any) -> str:
    """One effect-anticipation run (:class:`~glu.studies.anticipation.experiment.AnticipationRun`) in a
    sentence: the HMMs' leading model where it changes (:func:`leader_text`), the predicted ObjVel where it
    changes, the final description."""
    changes = "; ".join(f"{v} from t = {t} (frame {f}, p {p:.2f})" for t, f, v, p in run.prediction_changes())
    leads = leader_text(run.actions, run.p_hmm, run.update_t)
    return f"{case}, {hmms} HMMs: leading model {leads}; predicted ObjVel {changes}; “{run.description}”"


def published_sentence(case: str, versus: pd.DataFrame) -> str:
    """How much of the published Fig. 5 a case reproduces
    (:func:`~glu.studies.anticipation.experiment.published_comparison`): values within the figure's
    resolution, and whether the caption is the paper's."""
    same = "is" if versus.attrs["parameters"]["same_caption"] else "is not"
    return (
        f"{case}: {int(versus.within.sum())} of {len(versus)} published values within the figure's "
        f"resolution; the caption {same} the paper's"
    )


def sampling_line(trials: pd.DataFrame) -> str:
    """How often random samples drew the grammar's best, over every trial of
    :func:`~glu.studies.replication.verbal.sampling_trials`, and the median rank of a sample's best."""
    found, n = trials["found_best"], int(trials["n_samples"].iloc[0])
    return (
        f"over {len(trials)} trials of {n:,} random sentences, the best of the "
        f"grammar was drawn {int(found.sum())} times ({100 * found.mean():.1f} %); "
        f"the median rank of a sample's best in the grammar is {np.median(trials['sample_rank']):.0f}"
    )
