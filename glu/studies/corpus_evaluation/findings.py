"""What the corpus evaluation finds, condition by condition and cell by cell of its design, written from its
tables.

The design (:mod:`glu.studies.corpus_evaluation.config`) crosses whether the effects depend on the gesture
(``effects``), how often each action is performed (``action_prior``), which network the robot infers with
(``inference_network``, ``learn_experiments``), how it reads p_HMM (``p_hmm``) and which features its
recogniser sees (``features``); each is measured per viewpoint and noise level and pooled over them.
:func:`finding_verdicts` follows each claim of :data:`FINDINGS` (a paired difference between two strategies)
through every cell, viewpoint and noise level, with its bootstrap p-value adjusted for the whole family of
verdicts (Benjamini–Hochberg); :func:`verdict_counts` counts, per condition, the cells where each holds;
:func:`finding_sentences` writes each claim as a sentence that starts where the recogniser works — the front
view, raw features, effects drawn from the action alone (:data:`FRONT`) — and then says where the conclusion
changes. :func:`winners` names the best strategy of each cell and those tied with it. No sentence about
these results is typed by hand.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from glu.stats import ALPHA, HIGHER_IS_BETTER, adjust, verdict
from glu.studies.episodes import VIEWPOINTS

DESIGN: tuple[str, ...] = (
    "effects",
    "action_prior",
    "inference_network",
    "learn_experiments",
    "p_hmm",
    "features",
)
"""The factors of the design every table keeps apart (never pooled)."""
CELL: tuple[str, ...] = ("action_prior", "inference_network", "learn_experiments", "p_hmm")
"""The factors of the robot's models: a finding is counted over these cells within each condition."""
REFERENCES: tuple[str, ...] = ("true_action",)
"""Strategies that are references (a ceiling), never a cell's winner."""
REFERENCE_CELL: dict[str, Any] = {
    "effects": "action",
    "action_prior": "uniform",
    "inference_network": "generating",
    "learn_experiments": 0,
    "p_hmm": "per-frame",
    "features": "raw",
}
"""The cell of the earlier results: effects drawn from the action alone, actions drawn uniformly, the robot's
network the one that drew the episodes, p_HMM read per frame from a recogniser of raw features."""
FRONT: dict[str, Any] = {"effects": "action", "features": "raw", "viewpoint": "front"}
"""Where the findings are read first: the front view, where the recogniser works, with the originals' raw
features, in the world the fusion rules assume (pooled over the noise levels)."""
ADJUSTMENT = "bh"
"""How each family of verdicts is adjusted for its size (:func:`glu.stats.adjust`): Benjamini–Hochberg,
since the smallest bootstrap p-value, 2 / (B + 1), puts Holm's first threshold out of reach of a family of
more than α (B + 1) / 2 differences (:mod:`glu.stats`). The verdicts of the findings table are one family;
the sweep's differences one per pooling (:func:`glu.studies.corpus_evaluation.tables.adjust_families`)."""


@dataclass(frozen=True)
class Finding:
    """A claim about two strategies: ``strategy`` is better than ``baseline`` on ``target``'s ``metric``.

    Attributes
    ----------
    label : the claim in words (no numbers: those come from the tables)
    target, metric, strategy, baseline : the paired difference it rests on
    early : at the smallest observed fraction of the gesture (else the largest)
    """

    label: str
    target: str
    metric: str
    strategy: str
    baseline: str
    early: bool = False


FINDINGS: tuple[Finding, ...] = (
    Finding(
        "the product rule names the action better than the gesture alone",
        "action",
        "accuracy",
        "product",
        "gesture",
    ),
    Finding(
        "early in the gesture, the product rule names the action better than the gesture alone",
        "action",
        "accuracy",
        "product",
        "gesture",
        early=True,
    ),
    Finding(
        "Jeffrey's rule anticipates the effect with a lower log-loss than virtual evidence (the originals')",
        "effect",
        "log_loss",
        "jeffrey",
        "virtual",
    ),
    Finding(
        "Jeffrey's rule anticipates the effect with a smaller calibration error than a hard decision",
        "effect",
        "ece",
        "jeffrey",
        "hard",
    ),
    Finding(
        "Jeffrey's rule anticipates the effect better than the network alone",
        "effect",
        "log_loss",
        "jeffrey",
        "network",
    ),
    Finding(
        "early in the gesture, Jeffrey's rule anticipates the effect better than the network alone",
        "effect",
        "log_loss",
        "jeffrey",
        "network",
        early=True,
    ),
    Finding(
        "virtual evidence anticipates the effect better than the network alone",
        "effect",
        "log_loss",
        "virtual",
        "network",
    ),
    Finding(
        "the gesture names the action better than the network alone",
        "action",
        "accuracy",
        "gesture",
        "network",
    ),
)
"""The claims followed through the design (each with its interval in every cell and condition)."""


def bare(df: pd.DataFrame) -> pd.DataFrame:
    """``df`` without its ``attrs`` (a view of the same data): pandas deep-copies a stamped table's attrs
    on every row or group it hands out, the bulk of the time of a loop over rows."""
    out = df.copy(deep=False)
    out.attrs = {}
    return out


def select(frame: pd.DataFrame, where: Mapping[str, Any]) -> pd.DataFrame:
    """The rows of ``frame`` matching ``where`` (column → value; a NaN value matches NaN: pooled noise)."""
    keep = np.ones(len(frame), dtype=bool)
    for k, v in where.items():
        col = frame[k]
        if isinstance(v, float) and math.isnan(v):
            keep &= col.isna().to_numpy()
        elif isinstance(v, float):
            keep &= np.isclose(col.to_numpy(dtype=float), v)
        else:
            keep &= (col == v).to_numpy()
    return frame[keep]


def pooled(frame: pd.DataFrame, viewpoint: str = "all") -> pd.DataFrame:
    """The rows of ``frame`` for ``viewpoint`` with the noise levels pooled (noise missing)."""
    return frame[(frame.viewpoint == viewpoint) & frame.noise.isna()]


def winners(
    table: pd.DataFrame, diffs: pd.DataFrame, fraction: float | None = None, viewpoint: str = "front"
) -> pd.DataFrame:
    """Which strategy wins each cell of the design at one viewpoint (pooled over the noise levels).

    For each (design cell, target, metric) at ``fraction`` (default the largest): ``best``, the strategy
    with the best estimate (the reference ``true_action`` left out); ``tied``, every strategy without an
    adjusted difference from it (``verdict_adjusted``: no difference), best included; ``beats``, those it is
    better than; and the best estimate with its interval. Where the sweep lacks ``viewpoint``, its first.
    """
    table, diffs = bare(table), bare(diffs)
    views = viewpoints(table)
    if viewpoint not in views:
        viewpoint = views[0] if views else "all"
    full = table["fraction"].max() if fraction is None else fraction
    sel = pooled(table, viewpoint)
    sel = sel[np.isclose(sel.fraction, full) & ~sel.strategy.isin(REFERENCES)].copy()
    keys = [*DESIGN, "target", "metric"]
    up = higher_is_better(sel.metric)
    sel["_rank"] = np.where(up, -sel.estimate.to_numpy(dtype=float), sel.estimate.to_numpy(dtype=float))
    best = sel.sort_values([*keys, "_rank"], kind="stable").drop_duplicates(keys, keep="first")
    best = best[[*keys, "strategy", "estimate", "ci_low", "ci_high"]].rename(columns={"strategy": "best"})
    d = pooled(diffs, viewpoint)
    d = d[np.isclose(d.fraction, full)][[*keys, "strategy", "baseline", "verdict_adjusted"]]
    m = d.merge(best[[*keys, "best"]], on=keys, how="inner")
    m = m[(m.strategy == m.best) | (m.baseline == m.best)]
    m["other"] = np.where(m.strategy == m.best, m.baseline, m.strategy)
    m = m[~m.other.isin(REFERENCES)]
    tied = m[m.verdict_adjusted == "no difference"].groupby(keys, dropna=False).other.agg(list)
    beats = m[m.verdict_adjusted != "no difference"].groupby(keys, dropna=False).other.agg(list)
    rows = []
    for r in best.itertuples(index=False):
        key = tuple(getattr(r, k) for k in keys)
        rows.append(
            {
                **dict(zip(keys, key, strict=True)),
                "viewpoint": viewpoint,
                "fraction": full,
                "best": r.best,
                "tied": ", ".join(sorted([r.best, *tied.get(key, [])])),
                "beats": ", ".join(sorted(beats.get(key, []))),
                "estimate": float(r.estimate),
                "ci_low": float(r.ci_low),
                "ci_high": float(r.ci_high),
            }
        )
    return pd.DataFrame(rows)


def pair(diffs: pd.DataFrame, target: str, metric: str, strategy: str, baseline: str) -> pd.DataFrame:
    """The rows of ``strategy − baseline`` (flipped when the table stores ``baseline − strategy``)."""
    sel = diffs[(diffs.target == target) & (diffs.metric == metric)]
    ab = sel[(sel.strategy == strategy) & (sel.baseline == baseline)]
    if len(ab):
        return ab.copy()
    ba = sel[(sel.strategy == baseline) & (sel.baseline == strategy)].copy()
    ba["difference"], ba["ci_low"], ba["ci_high"] = -ba["difference"], -ba["ci_high"], -ba["ci_low"]
    ba["strategy"], ba["baseline"] = strategy, baseline
    up = HIGHER_IS_BETTER.get(metric, True)
    ba["verdict"] = [verdict(lo, hi, up) for lo, hi in zip(ba.ci_low, ba.ci_high, strict=True)]
    if "verdict_adjusted" in ba:
        ba["verdict_adjusted"] = adjusted_verdicts(ba.difference.to_numpy(), ba.p_adjusted.to_numpy(), up)
    return ba


VERDICT_COLUMNS = ["difference", "ci_low", "ci_high", "p_value", "verdict", "p_adjusted", "verdict_adjusted"]


def finding_verdicts(diffs: pd.DataFrame, findings: Sequence[Finding] = FINDINGS) -> pd.DataFrame:
    """Every finding in every cell of the design, per viewpoint, per noise level and pooled: its paired
    difference, interval and verdict, unadjusted and adjusted.

    Columns: finding (its label), the columns of ``DESIGN``, viewpoint, noise, fraction, difference, ci_low,
    ci_high, p_value, verdict (``better``: the strategy is better than the baseline; ``worse``; ``no
    difference``), p_adjusted (Benjamini–Hochberg over every row of the table: one family) and
    verdict_adjusted (a verdict only where p_adjusted ≤ α). Findings whose strategies the sweep lacks are
    left out.
    """
    diffs = bare(diffs)
    fractions = sorted(diffs["fraction"].dropna().unique())
    cols = ["finding", *DESIGN, "viewpoint", "noise", "fraction", *VERDICT_COLUMNS]
    parts = []
    for f in findings:
        sel = pair(diffs, f.target, f.metric, f.strategy, f.baseline)
        if sel.empty or not fractions:
            continue
        at = fractions[0] if f.early else fractions[-1]
        sel = sel[np.isclose(sel.fraction, at)]
        parts.append(sel.assign(finding=f.label))
    if not parts:
        return pd.DataFrame(columns=cols)
    out = pd.concat(parts, ignore_index=True)
    out["p_adjusted"] = adjust(out["p_value"].to_numpy(dtype=float), ADJUSTMENT)
    out["verdict_adjusted"] = verdicts_adjusted(out)
    return out[cols]


def higher_is_better(metrics: pd.Series) -> np.ndarray:
    """Per row, whether a higher value of its metric is better (:data:`glu.stats.HIGHER_IS_BETTER`): bool
    array, shape (n_rows,)."""
    return metrics.map(lambda m: HIGHER_IS_BETTER.get(m, True)).to_numpy(dtype=bool)


def verdicts_adjusted(frame: pd.DataFrame) -> np.ndarray:
    """The adjusted verdict of every row of a differences table (its difference, p_adjusted and metric):
    object array of ``"better"``, ``"worse"``, ``"no difference"``, shape (n_rows,)."""
    return adjusted_verdicts(frame["difference"], frame["p_adjusted"], higher_is_better(frame["metric"]))


def adjusted_verdicts(difference: np.ndarray, p_adjusted: np.ndarray, up: np.ndarray) -> np.ndarray:
    """:func:`glu.stats.adjusted_verdict` of many differences at once: ``difference``, ``p_adjusted`` and
    ``up`` (whether higher is better), each shape (n,) → verdicts, object array, shape (n,)."""
    d, p = np.asarray(difference, dtype=float), np.asarray(p_adjusted, dtype=float)
    sure = np.isfinite(d) & np.isfinite(p) & (p <= ALPHA) & (d != 0)
    better = (d > 0) == np.asarray(up, dtype=bool)
    return np.where(sure, np.where(better, "better", "worse"), "no difference").astype(object)


def verdict_counts(verdicts: pd.DataFrame) -> pd.DataFrame:
    """How many cells of the robot's models (:data:`CELL`) each finding holds in, per condition.

    One row per (finding, effects, features, viewpoint, noise): cells, better, no_difference, worse (from
    ``verdict_adjusted``), and better_unadjusted (from the unadjusted ``verdict``).
    """
    keys = ["finding", "effects", "features", "viewpoint", "noise"]
    rows = [
        (*key, *_counts(g), int((g.verdict == "better").sum()))  # cells, better, no_difference, worse
        for key, g in bare(verdicts).groupby(keys, sort=False, dropna=False)
    ]
    return pd.DataFrame(
        rows, columns=[*keys, "cells", "better", "no_difference", "worse", "better_unadjusted"]
    )


ACTION_WORDS = {
    "uniform": "uniform actions",
    "network": "actions from the network's prior",
    "scenario": "scenario actions",
}
EFFECT_WORDS = {
    "action": "effects drawn from the action alone",
    "gesture": "effects that depend on the gesture",
}


def network_name(row: Mapping[str, Any]) -> str:
    """``generating`` or ``learned (100)``."""
    net = row["inference_network"]
    return net if net == "generating" else f"learned ({int(row['learn_experiments'])})"


def cell_label(row: Mapping[str, Any], features: bool = True) -> str:
    """``"actions from the network's prior, learned (100) network, p_HMM calibrated, raw features"``: a cell
    in words (the world named too when its effects depend on the gesture)."""
    prior = ACTION_WORDS.get(row["action_prior"], f"{row['action_prior']} actions")
    out = f"{prior}, {network_name(row)} network, p_HMM {row['p_hmm']}"
    if features and "features" in row:
        out += f", {row['features']} features"
    if row.get("effects", "action") != "action":
        out += f", {EFFECT_WORDS.get(row['effects'], row['effects'])}"
    return out


def network_names(frame: pd.DataFrame) -> list[str]:
    """:func:`network_name` of every row of ``frame``."""
    return [
        network_name({"inference_network": n, "learn_experiments": k})
        for n, k in zip(frame.inference_network, frame.learn_experiments, strict=True)
    ]


def factor_levels(verdicts: pd.DataFrame) -> dict[str, np.ndarray]:
    """Each row's level of each factor of the cells, as the sentences name them (learned networks by their
    table size): factor → array, shape (n_rows,)."""
    return {
        "actions": verdicts.action_prior.map(lambda a: ACTION_WORDS.get(a, a)).to_numpy(),
        "network": np.array(network_names(verdicts), dtype=object),
        "p_HMM": verdicts.p_hmm.to_numpy(),
    }


SAID = {"better": "holds", "worse": "is reversed", "no difference": "is not supported"}


def _counts(g: pd.DataFrame) -> tuple[int, int, int, int]:
    c = g.verdict_adjusted.value_counts()
    return len(g), int(c.get("better", 0)), int(c.get("no difference", 0)), int(c.get("worse", 0))


def _held(name: str, h: pd.DataFrame) -> str:
    """``"raw 3/12 (reversed in 1)"``: in how many of ``h``'s cells a finding holds (and is reversed)."""
    n, better, _, worse = _counts(h)
    return f"{name} {better}/{n}" + (f" (reversed in {worse})" if worse else "")


def _elsewhere(g: pd.DataFrame) -> str:
    """Where a finding's count of cells changes from the front view's: per turned viewpoint and feature set,
    with effects that depend on the gesture, and per noise level (viewpoints pooled), raw features."""
    parts = []
    views = [v for v in viewpoints(g) if v != FRONT["viewpoint"]]
    features = list(dict.fromkeys(g.features))

    def per_features(h: pd.DataFrame) -> str:
        return ", ".join(_held(f, h[h.features == f]) for f in features if (h.features == f).any())

    base = g[(g.effects == FRONT["effects"]) & g.noise.isna()]
    for view in views:
        if per := per_features(base[base.viewpoint == view]):
            parts.append(f"{view}: {per}")
    other = g[(g.effects != FRONT["effects"]) & g.noise.isna() & (g.viewpoint == FRONT["viewpoint"])]
    for effects, h in other.groupby("effects", sort=False):
        parts.append(f"front view with {EFFECT_WORDS.get(effects, effects)}: {per_features(h)}")
    noisy = g[(g.effects == FRONT["effects"]) & g.noise.notna() & (g.viewpoint == "all")]
    noisy = noisy[noisy.features == FRONT["features"]]
    per = [_held(f"{noise * 100:g} cm", h) for noise, h in noisy.groupby("noise", sort=True)]
    if len(per) > 1:
        parts.append("raw features, all viewpoints, by sensor noise: " + ", ".join(per))
    return "; ".join(parts)


def finding_sentences(
    verdicts: pd.DataFrame, reference: Mapping[str, Any] = REFERENCE_CELL, brief: bool = False
) -> list[str]:
    """One sentence per finding of :func:`finding_verdicts`, adjusted verdicts throughout: first on the front
    view (:data:`FRONT`) — its verdict and difference in the reference cell, then in how many of the front
    view's cells it holds — and then where the count changes: per turned viewpoint and feature set, with
    effects that depend on the gesture, and per noise level.

    ``brief``: without naming the reference cell (the caller names it once) and without the counts per
    factor level (the README's form; the notebook gives them).
    """
    v = bare(verdicts)
    out = []
    for label, g in v.groupby("finding", sort=False):
        front = select(g, {**FRONT, "noise": math.nan})
        ref = select(front, {k: x for k, x in reference.items() if k in CELL})
        r = ref.iloc[0] if len(ref) else None
        head = label[0].upper() + label[1:]
        if r is not None:
            where = f"{r.fraction:.0%} of the gesture seen"
            cell = where if brief else f"{cell_label(r, features=False)}; {where}"
            head += (
                f": on the front view (noise levels pooled), in the reference cell ({cell}) it "
                f"{SAID[r.verdict_adjusted]} "
                f"(difference {r.difference:+.3f} [{r.ci_low:+.3f}, {r.ci_high:+.3f}], adjusted "
                f"p {p_text(r.p_adjusted)})"
            )
        n, better, none, worse = _counts(front)
        body = (
            f"over the front view's {n} cells it holds in {better}, with no difference in {none} and the "
            f"reverse in {worse}"
        )
        levels = []
        for factor, level in factor_levels(front).items():
            values = list(dict.fromkeys(level))
            if brief or len(values) < 2:
                continue
            per = []
            for value in values:
                h = front[level == value]
                per.append(f"{value} {int((h.verdict_adjusted == 'better').sum())}/{len(h)}")
            levels.append(", ".join(per) if factor == "actions" else f"{factor}: {', '.join(per)}")
        text = f"{head}; {body}" + (f" (where it holds: {'; '.join(levels)})" if levels else "")
        elsewhere = _elsewhere(g)
        out.append(text + (f". Cells where it holds elsewhere: {elsewhere}." if elsewhere else "."))
    return out


def p_text(p: float) -> str:
    """An adjusted p-value as the sentences write it: ``0.012``, ``< 0.001``, ``≤ α`` context-free."""
    if not np.isfinite(p):
        return "n/a"
    return "< 0.001" if p < 0.001 else f"{p:.3f}"


def seed_spread(seeds: pd.DataFrame, cell: Mapping[str, Any] = REFERENCE_CELL) -> pd.DataFrame:
    """Per strategy of the action target, the accuracy of each recogniser seed at the full gesture in one
    cell: the spread the seed level of the intervals carries. Columns: strategy, min, max, seeds."""
    sel = select(seeds[(seeds.target == "action") & (seeds.metric == "accuracy")], cell)
    sel = sel[np.isclose(sel.fraction, sel.fraction.max())]
    out = sel.groupby("strategy", sort=False).estimate.agg(["min", "max", "count"]).reset_index()
    return out.rename(columns={"count": "seeds"})


def design_text(summary: Mapping[str, Any]) -> str:
    """One sentence naming the design of a sweep from its summary: episodes, seeds, factors, replicates."""
    p = summary["parameters"]
    g = p["grid"]
    nets = [
        n if n == "generating" else f"learned from {', '.join(map(str, g['learn_experiments']))} experiments"
        for n in g["inference_network"]
    ]
    effects = " / ".join(EFFECT_WORDS.get(e, e) for e in g.get("effects", ["action"]))
    return (
        f"{summary['episodes']:,} episodes over {p['recognizer_seeds']} recogniser seeds; {effects} × action "
        f"prior {' / '.join(g['action_prior'])} × inference network {' / '.join(nets)} × p_HMM "
        f"{' / '.join(g['p_hmm'])} × features {' / '.join(g.get('features', ['raw']))}; noise "
        f"{', '.join(f'{x:g}' for x in g['noise'])} m × viewpoints {', '.join(g['viewpoints'])}; "
        f"{p['evaluation']['bootstrap']:,} two-level bootstrap replicates."
    )


def winners_table(win: pd.DataFrame, shown: Sequence[tuple[str, str]]) -> pd.DataFrame:
    """:func:`winners` as a table: one row per (target, metric, action prior, network), one column per p_HMM
    reading, cells ``"jeffrey 0.912 [0.90, 0.93] = virtual"``."""
    rows = win[[(t, m) in set(shown) for t, m in zip(win.target, win.metric, strict=True)]].copy()
    rows["network"] = network_names(rows)
    rows["cell"] = [
        f"{r.best} {r.estimate:.3f} [{r.ci_low:.3f}, {r.ci_high:.3f}]"
        + "".join(f" = {t}" for t in r.tied.split(", ") if t and t != r.best)
        for r in rows.itertuples()
    ]
    return rows.pivot_table(
        index=["target", "metric", "action_prior", "network"],
        columns="p_hmm",
        values="cell",
        aggfunc="first",
        sort=False,
    )


def contrast_cells(table: pd.DataFrame) -> list[dict[str, Any]]:
    """The reference cell and the one furthest from it that the sweep has: the network's action prior and
    the network learned from the fewest experiments, p_HMM read and features as in the reference cell."""
    have = table.drop_duplicates(list(DESIGN))[list(DESIGN)]
    ref = dict(REFERENCE_CELL)
    if not ((have[list(ref)] == pd.Series(ref)).all(axis=1)).any():
        ref = have.iloc[0].to_dict()
    other = dict(ref)
    if "network" in set(have.action_prior):
        other["action_prior"] = "network"
    learned = have[have.inference_network == "learned"]
    if len(learned):
        other["inference_network"], other["learn_experiments"] = (
            "learned",
            int(learned.learn_experiments.min()),
        )
    return [ref, other]


def viewpoints(table: pd.DataFrame) -> list[str]:
    """The viewpoints of a table (not ``all``), in the order of :data:`glu.studies.episodes.VIEWPOINTS`
    (others after, by name)."""
    order = list(VIEWPOINTS)
    views = {v for v in table.viewpoint.unique() if v != "all"}
    return sorted(views, key=lambda v: (order.index(v) if v in order else len(order), v))


def in_contrast_cells(frame: pd.DataFrame, table: pd.DataFrame) -> pd.DataFrame:
    """The rows of ``frame`` in the action priors and networks of :func:`contrast_cells` (every reading of
    p_HMM, feature set and world), pooled over the noise levels: what notebook 11 writes to ``results/``
    beside the findings (the full tables stay in the sweep's folder)."""
    frame = bare(frame)
    keep = np.zeros(len(frame), dtype=bool)
    for cell in contrast_cells(table):
        keep |= (
            (frame.action_prior == cell["action_prior"])
            & (frame.inference_network == cell["inference_network"])
            & (frame.learn_experiments == cell["learn_experiments"])
        ).to_numpy()
    return frame[keep & frame.noise.isna().to_numpy()]


def result_tables(
    stamped: Any, verdicts: pd.DataFrame, counts: pd.DataFrame
) -> list[tuple[pd.DataFrame, str, dict[str, Any]]]:
    """What notebook 11 writes to ``results/``, as ``(frame, name, extra)`` for
    :meth:`glu.run.outputs.Outputs.table`: the findings whole (``verdicts``, :func:`finding_verdicts`, and
    ``counts``, :func:`verdict_counts`); the metrics and differences of the contrasted cells (every reading,
    feature set, world and viewpoint, noise pooled: :func:`in_contrast_cells`), their reliability diagrams
    (effects from the action alone), the reference cell's seeds and the calibrations. The rest stays in the
    sweep's folder.

    ``stamped``: the saved tables (:func:`glu.studies.corpus_evaluation.tables.saved_subset`). Each frame
    returned is a view carrying the stamp of the table it was computed from (the caller's frames stay
    unstamped); the metrics' extra names the sweep's episodes.
    """
    table, diffs, rel, seeds, calibration = (bare(t) for t in stamped[:5])
    found = (
        (in_contrast_cells(table[table.viewpoint != "all"], table), stamped.metrics, "corpus_metrics"),
        (in_contrast_cells(diffs, table), stamped.differences, "corpus_differences"),
        (verdicts, stamped.differences, "corpus_findings"),
        (counts, stamped.differences, "corpus_finding_counts"),
        (in_contrast_cells(rel[rel.effects == "action"], table), stamped.reliability, "corpus_reliability"),
        (select(seeds, REFERENCE_CELL), stamped.seeds, "corpus_seeds"),
        (calibration, stamped.calibration, "corpus_calibration"),
    )
    out = []
    for frame, stamp, name in found:
        frame = bare(frame)
        frame.attrs = dict(stamp.attrs)
        extra = {"episodes": stamped.summary["episodes"]} if name == "corpus_metrics" else {}
        out.append((frame, name, extra))
    return out


def front_view(table: pd.DataFrame) -> str:
    """The viewpoint the findings are read on first (:data:`FRONT`), or the sweep's first."""
    views = viewpoints(table)
    return FRONT["viewpoint"] if FRONT["viewpoint"] in views else (views[0] if views else "all")


def metric_rows(table: pd.DataFrame, target: str, metric: str, fraction: float) -> pd.DataFrame:
    """The rows of ``table`` of one metric of one target at one observed fraction of the gesture."""
    return table[(table.target == target) & (table.metric == metric) & np.isclose(table.fraction, fraction)]


def network_alone_sentences(table: pd.DataFrame) -> list[str]:
    """For the contrasted cells on the front view (noise pooled), early and at the full gesture: the effect's
    log-loss and ECE of the network alone beside every fusion rule and the true action (an oracle)."""
    table = bare(table)
    out = []
    fractions = sorted(table.fraction.dropna().unique())
    view = front_view(table)
    for cell in contrast_cells(table):
        for f in (fractions[0], fractions[-1]):
            parts = []
            for metric in ("log_loss", "ece"):
                g = metric_rows(select(pooled(table, view), cell), "effect", metric, f).set_index("strategy")
                if "network" not in g.index:
                    continue
                net = g.loc["network"]
                rules = [s for s in g.index if s not in ("network", *REFERENCES)]
                name = "log-loss" if metric == "log_loss" else "ECE (bias-corrected)"
                parts.append(
                    f"{name} {net.estimate:.3f} [{net.ci_low:.3f}, {net.ci_high:.3f}] for the network alone, "
                    + ", ".join(f"{s} {g.loc[s].estimate:.3f}" for s in rules)
                    + (
                        f", the true action {g.loc['true_action'].estimate:.3f}"
                        if "true_action" in g.index
                        else ""
                    )
                )
            if parts:
                out.append(
                    f"The effect with {f:.0%} of the gesture seen, {view} view, noise levels pooled "
                    f"({cell_label(cell)}): " + "; ".join(parts) + "."
                )
    return out


def p_hmm_table(
    table: pd.DataFrame, cell: Mapping[str, Any] | None = None, viewpoint: str | None = None
) -> pd.DataFrame:
    """p_HMM alone (strategy ``gesture``) at the full gesture under each reading: accuracy, log-loss, ECE,
    in one cell of effects, actions, network and features (default the reference cell's), at one viewpoint
    (default the front view) pooled over the noise levels."""
    table = bare(table)
    cell = {k: v for k, v in (cell or REFERENCE_CELL).items() if k != "p_hmm"}
    sel = select(pooled(table, viewpoint or front_view(table)), cell)
    sel = sel[
        (sel.target == "action") & (sel.strategy == "gesture") & np.isclose(sel.fraction, sel.fraction.max())
    ]
    wide = sel.pivot_table(index="p_hmm", columns="metric", values="estimate", sort=False)
    return wide.reindex(columns=["accuracy", "log_loss", "ece"])


READING_WORDS = {
    "likelihood": "read from the likelihoods",
    "per-frame": "read per frame",
    "calibrated": "calibrated on clean front-view gestures",
    "calibrated-matched": "calibrated on gestures drawn like the test conditions",
}


def p_hmm_sentences(
    table: pd.DataFrame, calibration: pd.DataFrame, segments: pd.DataFrame | None = None
) -> list[str]:
    """What the tables say of p_HMM as a probability: its accuracy and ECE under each reading on held-out
    synthetic gestures, per viewpoint; the fitted inverse temperatures and how many sit at a bound; (with
    the real data) the held-out real segments."""
    table = bare(table)
    out = []
    for view in viewpoints(table):
        t = p_hmm_table(table, viewpoint=view).dropna(subset=["accuracy", "ece"])
        if t.empty:
            continue
        out.append(
            f"On the corpus's held-out synthetic gestures seen {view} (reference cell, full gesture, noise "
            "pooled), p_HMM alone names the action right "
            + "; ".join(
                f"{READING_WORDS.get(r, r)} {t.loc[r, 'accuracy']:.3f} of the time, ECE {t.loc[r, 'ece']:.3f}"
                for r in t.index
            )
            + "."
        )
    if len(calibration):
        cal = bare(calibration)
        full = cal[np.isclose(cal.fraction, cal.fraction.max())]
        raw = full[full.features == REFERENCE_CELL["features"]] if "features" in full else full
        parts = []
        for reading, g in raw.groupby("reading", sort=False) if "reading" in raw else [("calibrated", raw)]:
            hits = int(g.at_bound.sum()) if "at_bound" in g else 0
            parts.append(
                f"{READING_WORDS.get(reading, reading)} β = {g.beta.min():.3g} to {g.beta.max():.3g} "
                f"(at a bound of [0, 1] in {hits} of {len(g)} seeds)"
            )
        allhits = int(cal.at_bound.sum()) if "at_bound" in cal else 0
        out.append(
            "The calibrated readings' inverse temperature at the full gesture, fitted per seed on held-out "
            f"gestures (raw features): {'; '.join(parts)}; the likelihood reading is β = 1. Over every "
            f"feature set and fraction, {allhits} of {len(cal)} fits sit at a bound."
        )
    if segments is not None and len(segments):
        s = segments.set_index("reading")
        n = int(s["segments"].iloc[0])
        out.append(
            f"On the {n} real standing segments, each left out: read from the likelihoods, p_HMM is at "
            f"least 0.99 for {int(s.loc['likelihood', 'certain'])} of them while naming "
            f"{s.loc['likelihood', 'accuracy']:.2f} correctly (ECE "
            + ", ".join(f"{r} {s.loc[r, 'ece']:.3f}" for r in s.index)
            + "; log-loss "
            + ", ".join(f"{r} {s.loc[r, 'log_loss']:.3f}" for r in s.index)
            + ")."
        )
    return out


def seed_sentence(spread: pd.DataFrame) -> str:
    """One sentence from :func:`seed_spread`: how far apart the recogniser seeds put each strategy."""
    if spread.empty:
        return "No seed-level estimates in this cell."
    k = int(spread.seeds.max())
    return (
        f"Over {k} recogniser seeds (reference cell, full gesture, viewpoints and noise pooled), accuracy "
        "ranges "
        + "; ".join(f"{r.strategy} {r['min']:.3f}–{r['max']:.3f}" for _, r in spread.iterrows())
        + "."
    )
