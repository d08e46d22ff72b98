"""Where the corpus evaluation's conclusions change: with the viewpoint, the recogniser's features and the
world's effects, written from its tables (notebook 11 and the README).

:func:`lead_sentence` is the result read first (the front view); :func:`viewpoint_sentences` follows the
gesture and Jeffrey's rule through the viewpoints and feature sets; :func:`best_invariant` and
:func:`validation_sentence` name the invariant feature set chosen on held-out gestures (never the test
episodes); :func:`gesture_world_sentence` says what changes when the effects depend on the gesture.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pandas as pd

from glu.studies.corpus_evaluation.findings import (
    ACTION_WORDS,
    EFFECT_WORDS,
    REFERENCE_CELL,
    SAID,
    bare,
    front_view,
    p_text,
    pooled,
    select,
    viewpoints,
)


def best_invariant(calibration: pd.DataFrame) -> str | None:
    """The feature set other than ``raw`` whose recognisers name the action best on the held-out gestures
    drawn like the test conditions (the ``calibrated-matched`` fits' validation accuracy at the full gesture,
    mean over seeds): chosen on gestures no test episode is, never on the test episodes. None without them."""
    if calibration is None or calibration.empty or "accuracy" not in calibration:
        return None
    cal = bare(calibration)
    sel = cal[(cal.reading == "calibrated-matched") & (cal.features != "raw")]
    sel = sel[np.isclose(sel.fraction, sel.fraction.max())]
    if sel.empty:
        return None
    means = sel.groupby("features", sort=False).accuracy.mean()
    return str(means.idxmax())


def validation_sentence(calibration: pd.DataFrame) -> str:
    """How the best invariant feature set was chosen, with each feature set's validation accuracy."""
    cal = bare(calibration)
    sel = cal[(cal.reading == "calibrated-matched")]
    sel = sel[np.isclose(sel.fraction, sel.fraction.max())]
    if sel.empty:
        return "No held-out gestures drawn like the test conditions: no feature set is chosen."
    means = sel.groupby("features", sort=False).accuracy.agg(["mean", "min", "max"])
    best = best_invariant(calibration)
    return (
        "On held-out gestures drawn like the test conditions (every viewpoint and noise level of the sweep; "
        "never a test episode), the recognisers name the action "
        + ", ".join(
            f"{f} {r['mean']:.2f} ({r['min']:.2f}–{r['max']:.2f} over seeds)" for f, r in means.iterrows()
        )
        + f" of the time at the full gesture: the best invariant feature set is {best}."
    )


def _value(sel: pd.DataFrame, target: str, strategy: str, metric: str, features: str) -> pd.Series | None:
    r = sel[(sel.target == target) & (sel.strategy == strategy) & (sel.metric == metric)]
    r = r[r.features == features]
    return r.iloc[0] if len(r) else None


def viewpoint_sentences(table: pd.DataFrame, features: Sequence[str]) -> list[str]:
    """Per viewpoint, in the reference cell (noise pooled, full gesture): the gesture's accuracy with each
    feature set, beside the network alone, and the effect's log-loss of Jeffrey's rule with each beside the
    network alone."""
    t = bare(table)
    full = t.fraction.max()
    cell = {k: v for k, v in REFERENCE_CELL.items() if k != "features"}
    out = []
    for view in viewpoints(t):
        sel = select(pooled(t, view), cell)
        sel = sel[np.isclose(sel.fraction, full)]

        acc = [(f, _value(sel, "action", "gesture", "accuracy", f)) for f in features]
        net = _value(sel, "action", "network", "accuracy", features[0])
        jl = [(f, _value(sel, "effect", "jeffrey", "log_loss", f)) for f in features]
        nl = _value(sel, "effect", "network", "log_loss", features[0])
        if net is None or nl is None:
            continue
        out.append(
            f"Seen {view}: the gesture alone names the action "
            + ", ".join(
                f"{f} {r.estimate:.2f} [{r.ci_low:.2f}, {r.ci_high:.2f}]" for f, r in acc if r is not None
            )
            + f" (the network alone {net.estimate:.2f}); Jeffrey's rule's effect log-loss "
            + ", ".join(f"{f} {r.estimate:.3f}" for f, r in jl if r is not None)
            + f" (the network alone {nl.estimate:.3f})."
        )
    return out


def gesture_world_sentence(table: pd.DataFrame) -> str:
    """What changes when the effects depend on the gesture (front view, reference cell, full gesture): the
    effect's log-loss of the network alone, Jeffrey's rule and the true action in both worlds."""
    t = bare(table)
    full = t.fraction.max()
    view = front_view(t)
    cell = {k: v for k, v in REFERENCE_CELL.items() if k != "effects"}
    sel = select(pooled(t, view), cell)
    sel = sel[np.isclose(sel.fraction, full) & (sel.target == "effect") & (sel.metric == "log_loss")]
    parts = []
    for effects, g in sel.groupby("effects", sort=False):
        g = g.set_index("strategy")
        names = [s for s in ("network", "jeffrey", "virtual", "true_action") if s in g.index]
        parts.append(
            f"{EFFECT_WORDS.get(effects, effects)}: "
            + ", ".join(
                f"{'the true action' if s == 'true_action' else s} {g.loc[s].estimate:.3f} "
                f"[{g.loc[s].ci_low:.3f}, {g.loc[s].ci_high:.3f}]"
                for s in names
            )
        )
    if len(parts) < 2:
        return "The sweep has one world only: nothing to compare."
    return (
        f"The effect's log-loss on the {view} view (reference cell, full gesture), "
        + "; ".join(parts)
        + ". When a fast tap sends the object further and the slowest taps fail, even the true action leaves "
        "the speed of the gesture unused, which no fusion rule of the originals' can read."
    )


LEAD = "Jeffrey's rule anticipates the effect better than the network alone"
"""The finding the README and the notebook lead with (one of :data:`FINDINGS`)."""


def lead_sentence(
    table: pd.DataFrame, verdicts: pd.DataFrame, best: str | None = None, features: Sequence[str] = ()
) -> str:
    """The result read first: on the front view (raw features, effects from the action alone, the generating
    network, p_HMM per frame, noise pooled, full gesture), the gesture's accuracy and Jeffrey's rule against
    the network alone for each action prior, with adjusted verdicts; then, at every other viewpoint, the
    same in the reference cell for raw features, ``best`` (the best invariant feature set) and the other
    ``features``."""
    t, v = bare(table), bare(verdicts)
    v = v[v.finding.str.lower() == LEAD.lower()]
    full = t.fraction.max()
    front = front_view(t)
    cell = {k: x for k, x in REFERENCE_CELL.items() if k != "action_prior"}

    def diff(view: str, feature_set: str, prior: str) -> str | None:
        where = {**cell, "action_prior": prior, "features": feature_set, "viewpoint": view, "noise": math.nan}
        r = select(v, where)
        if r.empty:
            return None
        r = r.iloc[0]
        said = SAID[r.verdict_adjusted].replace("is ", "")
        interval = f"[{r.ci_low:+.3f}, {r.ci_high:+.3f}]"
        return f"{r.difference:+.3f} {interval} ({said}, adjusted p {p_text(r.p_adjusted)})"

    def accuracy(view: str, feature_set: str) -> str:
        sel = select(pooled(t, view), {**REFERENCE_CELL, "features": feature_set})
        sel = sel[(sel.target == "action") & (sel.strategy == "gesture") & (sel.metric == "accuracy")]
        sel = sel[np.isclose(sel.fraction, full)]
        return f"{sel.iloc[0].estimate:.2f}" if len(sel) else "?"

    priors = [p for p in ("uniform", "network", "scenario") if p in set(v.action_prior)]
    lead = [f"{diff(front, 'raw', p)} with {ACTION_WORDS.get(p, p)}" for p in priors if diff(front, "raw", p)]
    text = (
        f"On the {front} view, where the recogniser works (the gesture alone names "
        f"{accuracy(front, 'raw')} of the actions with raw features), Jeffrey's rule anticipates the effect "
        "better than the network alone: the difference of log-loss is " + "; ".join(lead) + "."
    )
    sets = list(dict.fromkeys(["raw", *([best] if best else []), *features]))
    for view in [x for x in viewpoints(t) if x != front]:
        parts = [
            f"{f} (the gesture {accuracy(view, f)}) {d}"
            for f in sets
            if (d := diff(view, f, REFERENCE_CELL["action_prior"])) is not None
        ]
        if parts:
            text += f" Seen {view}, uniform actions: " + "; ".join(parts) + "."
    return text + " (Negative: Jeffrey's rule better; the reference cell otherwise, noise levels pooled.)"
