"""The correspondence results in sentences, written from their tables (notebook 10 and the README).

Every number and every comparison below is read from a table: :func:`study_sentences` from the synthetic
study's summary and invariance effects (:mod:`glu.studies.correspondence.experiment`),
:func:`nested_sentences` from the real data's nested cross-validation and seated taps
(:mod:`glu.studies.correspondence.nested`). A feature set the study did not run is left out of the sentence
that would name it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import pandas as pd

from glu.gestures.views import OCCLUSION_DEG, SWAP_DEG
from glu.studies.correspondence.experiment import OCCLUDED

ALL_FOUR = "centred+scaled+rotated+mirrored"


def _span(values: Sequence[float]) -> str:
    """``"0.71–0.77"``, or ``"0.73"`` when both ends print alike."""
    lo, hi = f"{min(values):.2f}", f"{max(values):.2f}"
    return lo if lo == hi else f"{lo}–{hi}"


def _frames(values: Sequence[float]) -> str:
    """``"27–28"`` (frame numbers), or ``"1"`` when every value is the same."""
    lo, hi = int(min(values)), int(max(values))
    return str(lo) if lo == hi else f"{lo}–{hi}"


def _cell(h: pd.DataFrame, features: str, factor: str, level: str | None = None) -> pd.Series | None:
    rows = h[(h["features"] == features) & (h["factor"] == factor)]
    if level is not None:
        rows = rows[rows["level"] == level]
    return rows.iloc[0] if len(rows) else None


def _name(features: str) -> str:
    """A feature set as the sentences name it: raw, ``all four``, else in backticks."""
    return "all four" if features == ALL_FOUR else (features if features == "raw" else f"`{features}`")


def _interval(r: Any) -> str:
    return f"{r.accuracy:.2f} [{r.ci_low:.2f}, {r.ci_high:.2f}]"


def _named(h: pd.DataFrame, factor: str, features: Sequence[str], level: str | None = None) -> str:
    """``"raw 0.33 [0.28, 0.39], `body` 0.34 [...]"`` for the feature sets the study ran."""
    rows = [(f, _cell(h, f, factor, level)) for f in features]
    return ", ".join(f"{_name(f)} {_interval(r)}" for f, r in rows if r is not None)


TURN_FEATURES = ("raw", "centred+rotated", "body", "body+centred")
"""The feature sets the sentences on turned people name."""


def _per_turn_features(turned: pd.DataFrame, text: Callable[[pd.DataFrame], str], sep: str) -> str:
    """``text`` of the rows of each of :data:`TURN_FEATURES` in ``turned``, named, joined by ``sep``."""
    groups = [(f, turned[turned["features"] == f]) for f in TURN_FEATURES]
    return sep.join(f"{_name(f)} {text(t)}" for f, t in groups if len(t))


def _occluded(h: pd.DataFrame) -> str:
    """The occluding tracker's turned views, per feature set of the turn sentence: accuracy at each yaw."""
    return _per_turn_features(
        h[h["factor"] == OCCLUDED],
        lambda t: ", ".join(f"{r.level} {_interval(r)}" for r in t.itertuples()),
        "; ",
    )


def _changes(effects: pd.DataFrame, verdict: str) -> str:
    """``"`centred` added to `body`: 6 cm; `rotated` added to `centred`: 0.8"`` for one adjusted verdict."""
    sel = effects[effects["verdict_adjusted"] == verdict]
    parts = []
    for (features, baseline), g in sel.groupby(["features", "baseline"], sort=False):
        added = features if baseline == "raw" else g["invariance"].iloc[0]
        factor = g["factor"] if "factor" in g else pd.Series([""] * len(g), index=g.index)
        pairs = zip(factor, g["level"], strict=True)
        levels = [f"{lv} (occluding tracker)" if f == OCCLUDED else lv for f, lv in pairs]
        parts.append(f"`{added}` added to `{baseline}`: {', '.join(dict.fromkeys(levels))}")
    return "; ".join(parts)


def _condition_sentences(h: pd.DataFrame) -> list[str]:
    """The mirror image, the seated posture, everything at once and each sensor noise level."""
    out = []
    for factor, level, feats, what in (
        ("mirror", "mirrored", ("raw", "centred+mirrored", "body"), "A mirror image"),
        ("posture", "seated", ("raw", "centred", "body+centred"), "Seated"),
        ("combined", None, ("raw", ALL_FOUR, "body+centred"), "Seated, mirrored, turned and bigger at once"),
    ):
        text = _named(h, factor, feats, level)
        if text:
            out.append(f"{what}: {text}.")
    noise = h[h["factor"] == "sensor noise"]
    for level in dict.fromkeys(noise["level"]):
        out.append(
            f"With {level} of sensor noise: "
            + _named(h, "sensor noise", ("raw", "centred", "centred+rotated", "body", "body+centred"), level)
            + "."
        )
    return out


def _robot_sentences(summary: pd.DataFrame) -> list[str]:
    """Recognisers trained on the robot's own movements: the best on people beside the robot's own."""
    r = summary[summary["train"] == "robot"]
    own, people = r[r["factor"] == "performer"], r[r["factor"] != "performer"]
    if not (len(own) and len(people)):
        return []
    best = people.loc[people["accuracy"].idxmax()]
    return [
        "Trained on the robot's own movements — drawn by a hand-written generator of an iCub-like arm "
        "(waypoints, timings and proportions chosen for this study, not measured on a robot) — no "
        f"feature set recognises people better than {best.accuracy:.2f} "
        f"[{best.ci_low:.2f}, {best.ci_high:.2f}] ({best.features}, {best.factor}: {best.level}), "
        f"while the robot recognises its own at {_span(own['accuracy'])}."
    ]


def study_sentences(summary: pd.DataFrame, effects: pd.DataFrame, brief: bool = False) -> list[str]:
    """What the synthetic study shows, one sentence per finding (accuracy with its two-level interval; the
    invariances' paired changes by their adjusted verdicts).

    ``brief`` (the README's) keeps the views, the occluding tracker, the invariances' adjusted verdicts and
    the robot's own movements, and leaves the mirror, seated, combined and noisy conditions to the notebook.
    """
    h = summary[summary["train"] == "human"]
    out = []
    front = _cell(h, "raw", "viewpoint", "0°")
    turned = h[(h["factor"] == "viewpoint") & (h["yaw_deg"] > 0)]
    if front is not None and len(turned):
        per = _per_turn_features(turned, lambda t: _span(t["accuracy"]), ", ")
        out.append(
            "Trained on one human view and tested on other people (their own arm lengths and movement "
            "styles), facing the camera: "
            f"{_named(h, 'viewpoint', ('raw', 'centred+rotated', 'body'), '0°')}. Turned by "
            f"{turned['yaw_deg'].min():.0f}–{turned['yaw_deg'].max():.0f}° and seen by an ideal tracker "
            f"(both shoulders wherever the person faces): {per}."
        )
    occluded = _occluded(h)
    if occluded:
        out.append(
            f"Seen through a tracker that loses the far shoulder beyond {OCCLUSION_DEG:.0f}° and swaps left "
            f"and right beyond {SWAP_DEG:.0f}° (as a depth camera's does): {occluded}. The body frame needs "
            "the shoulder line, and from behind the tracker follows the resting hand."
        )
    if not brief:
        out += _condition_sentences(h)
    human = effects[effects["train"] == "human"]
    if len(human):
        n = len(human)
        costs, helps = _changes(human, "worse"), _changes(human, "better")
        out.append(
            "Where adding an invariance costs accuracy (its paired difference adjusted with the other "
            f"{n - 1} by Benjamini–Hochberg): " + (costs or "nowhere") + "."
        )
        out.append("Where it buys accuracy, adjusted alike: " + (helps or "nowhere") + ".")
    out += _robot_sentences(summary)
    if brief:
        return out
    zero = int((summary["ci_high"] - summary["ci_low"] == 0).sum())
    out.append(
        f"{zero} of {len(summary)} intervals have zero width (every test gesture of every seed "
        "recognised alike)."
    )
    return out


def nested_sentences(
    summary: pd.DataFrame, seated: pd.DataFrame, candidates: pd.DataFrame, brief: bool = False
) -> list[str]:
    """What the real data show under nested cross-validation, and how the seated taps are recognised.

    ``brief`` (the README's) leaves out the plain leave-one-segment-out spans and each seated tap's frames.
    """
    out = []
    per = "; ".join(
        f"seed {r.seed}: {r.correct} of {r.testable} ({r.accuracy:.2f}, exact 95 % interval "
        f"[{r.ci_low:.2f}, {r.ci_high:.2f}])"
        for r in summary.itertuples()
    )
    tuned = summary["tuned_accuracy"]
    out.append(
        f"Nested leave-one-segment-out on the {int(summary['testable'].iloc[0])} standing segments, the "
        f"feature set and covariance prior chosen inside each fold on standing data only: {per}. Tuned and "
        f"reported on the same segments instead, the best candidate scores {_span(tuned)} "
        f"({', '.join(dict.fromkeys(summary['tuned_candidate']))}); a recogniser that always answers "
        f'"tap" scores {summary["always_tap"].iloc[0]:.2f}.'
    )
    if "recordings" in summary:
        out.append(
            f"The segments come from {int(summary['recordings'].iloc[0])} recordings, one per action: the "
            "action is confounded with the recording session (whatever else differs between the recordings "
            "differs between the actions too), so a recogniser may tell the sessions apart rather than the "
            "actions, and the exact interval, which treats the segments as independent, is too narrow by an "
            "amount these data cannot measure."
        )
    raw = candidates[candidates["features"] == "raw"]
    cen = candidates[candidates["features"] != "raw"]
    if len(raw) and len(cen) and not brief:
        out.append(
            "Plain leave-one-segment-out over candidates and seeds: raw features "
            f"{_span(raw['loso_accuracy'])}, {', '.join(dict.fromkeys(cen['features']))} "
            f"{_span(cen['loso_accuracy'])}."
        )
    for rec, g in () if brief else seated.groupby("recording", sort=False):
        taps = int((g["predicted"] == "tap").sum())
        out.append(
            f"Seated tap {rec}: recognised as tap by {taps} of {len(g)} seeds' models (p(tap) "
            f"{_span(g['p_tap'])}), yet its per-frame log-likelihood lies {_span(g['below'])} nats "
            f"below every training sequence (theirs: {_span(g['training_low'])} to "
            f"{_span(g['training_high'])} nats per frame); tap first leads at frame "
            f"{_frames(g['tap_first'])}, the hand starts to move at frame {int(g['onset'].iloc[0])} of "
            f"{int(g['n_frames'].iloc[0])}, and tap leads for good from frame {_frames(g['tap_from'])}."
        )
    if len(seated):
        right = int(seated.groupby("recording")["always_tap"].first().sum())
        out.append(
            f'The data hold no seated grasp or touch: always answering "tap" also gets {right} of '
            f"{seated['recording'].nunique()} seated taps right, so they cannot tell a recogniser from that "
            "baseline."
        )
    return out
