"""What the corpus evaluation finds, cell by cell of its design, written from its tables.

The design (:mod:`glu.studies.corpus_evaluation.config`) crosses how often each action is performed
(``action_prior``), which network the robot infers with (``inference_network``, ``learn_experiments``) and how
it reads p_HMM (``p_hmm``). :func:`winners` names the best strategy of each cell and those tied with it
(paired difference whose interval contains 0: no difference); :func:`finding_verdicts` follows each claim of
:data:`FINDINGS` (a paired difference between two strategies) through every cell, and
:func:`finding_sentences` writes each as a sentence — what it is in the reference cell, and in how many cells,
at which levels of each factor, it holds — so that no sentence about these results is typed by hand.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from glu.stats import HIGHER_IS_BETTER, verdict

DESIGN: tuple[str, ...] = ("action_prior", "inference_network", "learn_experiments", "p_hmm")
"""The factors of the design every table keeps apart (never pooled)."""
REFERENCES: tuple[str, ...] = ("true_action",)
"""Strategies that are references (a ceiling), never a cell's winner."""
REFERENCE_CELL: dict[str, Any] = {
    "action_prior": "uniform",
    "inference_network": "generating",
    "learn_experiments": 0,
    "p_hmm": "per-frame",
}
"""The cell of the earlier results: actions drawn uniformly, the robot's network the one that drew the
episodes, p_HMM read per frame."""


@dataclass(frozen=True)
class Finding:
    """A claim about two strategies: ``strategy`` is better than ``baseline`` on ``target``'s ``metric``.

    Attributes
    ----------
    label : the claim in words (no numbers: those come from the tables)
    target, metric, strategy, baseline : the paired difference it rests on
    early : at the smallest observed fraction of the gesture (else the largest)
    viewpoint : a viewpoint of the sweep, or ``"all"`` (pooled)
    """

    label: str
    target: str
    metric: str
    strategy: str
    baseline: str
    early: bool = False
    viewpoint: str = "all"


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
        "seen from a turned viewpoint, the gesture names the action better than the network alone",
        "action",
        "accuracy",
        "gesture",
        "network",
        viewpoint="turned",
    ),
)
"""The claims followed through the design (each with its interval in every cell)."""


def _pooled(frame: pd.DataFrame, viewpoint: str = "all") -> pd.DataFrame:
    return frame[(frame.viewpoint == viewpoint) & frame.noise.isna()]


def _bare(df: pd.DataFrame) -> pd.DataFrame:
    """``df`` without its ``attrs`` (a view of the same data): pandas deep-copies a stamped table's attrs
    on every row or group it hands out, the bulk of the time of a loop over rows."""
    out = df.copy(deep=False)
    out.attrs = {}
    return out


def winners(table: pd.DataFrame, diffs: pd.DataFrame, fraction: float | None = None) -> pd.DataFrame:
    """Which strategy wins each cell of the design (pooled over noise levels and viewpoints).

    For each (action prior, inference network, learn_experiments, p_HMM, target, metric) at ``fraction``
    (default the largest): ``best``, the strategy with the best estimate (the reference ``true_action``
    left out); ``tied``, every strategy whose paired difference with it has an interval containing 0 (no
    difference), best included; ``beats``, those it is better than with confidence; and the best
    estimate with its interval.
    """
    table, diffs = _bare(table), _bare(diffs)
    full = table["fraction"].max() if fraction is None else fraction
    sel = _pooled(table)
    sel = sel[np.isclose(sel.fraction, full) & ~sel.strategy.isin(REFERENCES)]
    d = _pooled(diffs)
    d = d[np.isclose(d.fraction, full)]
    keys = [*DESIGN, "target", "metric"]
    d_groups = dict(iter(d.groupby(keys, sort=False, dropna=False)))
    rows = []
    for key, g in sel.groupby(keys, sort=False, dropna=False):
        up = HIGHER_IS_BETTER.get(key[-1], True)
        top = g.sort_values("estimate", ascending=not up, kind="stable").iloc[0]
        tied, beats = [top.strategy], []
        for p in d_groups.get(key, d.iloc[:0]).itertuples():
            if top.strategy not in (p.strategy, p.baseline):
                continue
            other = p.baseline if p.strategy == top.strategy else p.strategy
            if other not in REFERENCES:
                (tied if p.verdict == "no difference" else beats).append(other)
        rows.append(
            {
                **dict(zip(keys, key, strict=True)),
                "fraction": full,
                "best": top.strategy,
                "tied": ", ".join(sorted(tied)),
                "beats": ", ".join(sorted(beats)),
                "estimate": float(top.estimate),
                "ci_low": float(top.ci_low),
                "ci_high": float(top.ci_high),
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
    return ba


def finding_verdicts(diffs: pd.DataFrame, findings: Sequence[Finding] = FINDINGS) -> pd.DataFrame:
    """Every finding in every cell of the design: its paired difference, interval and verdict.

    Columns: finding (its label), the columns of ``DESIGN``, viewpoint, fraction, difference, ci_low,
    ci_high, verdict (``better``: the strategy is better than the baseline; ``worse``; ``no difference``).
    Findings whose viewpoint or strategies the sweep lacks are left out.
    """
    fractions = sorted(diffs["fraction"].dropna().unique())
    parts = []
    for f in findings:
        sel = pair(diffs, f.target, f.metric, f.strategy, f.baseline)
        sel = _pooled(sel, f.viewpoint)
        if sel.empty or not fractions:
            continue
        at = fractions[0] if f.early else fractions[-1]
        sel = sel[np.isclose(sel.fraction, at)]
        parts.append(
            sel[[*DESIGN, "viewpoint", "fraction", "difference", "ci_low", "ci_high", "verdict"]].assign(
                finding=f.label
            )
        )
    cols = ["finding", *DESIGN, "viewpoint", "fraction", "difference", "ci_low", "ci_high", "verdict"]
    return pd.concat(parts, ignore_index=True)[cols] if parts else pd.DataFrame(columns=cols)


ACTION_WORDS = {
    "uniform": "uniform actions",
    "network": "actions from the network's prior",
    "scenario": "scenario actions",
}


def cell_label(row: Mapping[str, Any]) -> str:
    """``"actions from the network's prior, learned (100) network, p_HMM calibrated"``: a cell in words."""
    net = row["inference_network"]
    if net == "learned":
        net = f"learned ({int(row['learn_experiments'])})"
    prior = ACTION_WORDS.get(row["action_prior"], f"{row['action_prior']} actions")
    return f"{prior}, {net} network, p_HMM {row['p_hmm']}"


def factor_levels(verdicts: pd.DataFrame) -> dict[str, list[str]]:
    """Each factor's levels as the sentences name them (learned networks by their table size)."""
    net = [
        "generating" if n == "generating" else f"learned ({int(k)})"
        for n, k in dict.fromkeys(zip(verdicts.inference_network, verdicts.learn_experiments, strict=True))
    ]
    return {
        "actions": [ACTION_WORDS.get(a, a) for a in dict.fromkeys(verdicts.action_prior)],
        "network": net,
        "p_HMM": list(dict.fromkeys(verdicts.p_hmm)),
    }


def _level(row: Any, factor: str) -> str:
    if factor == "actions":
        return ACTION_WORDS.get(row.action_prior, row.action_prior)
    if factor == "p_HMM":
        return row.p_hmm
    return (
        "generating" if row.inference_network == "generating" else f"learned ({int(row.learn_experiments)})"
    )


def finding_sentences(
    verdicts: pd.DataFrame, reference: Mapping[str, Any] = REFERENCE_CELL, brief: bool = False
) -> list[str]:
    """One sentence per finding of :func:`finding_verdicts`: its verdict and difference in the reference
    cell, then in how many cells it holds (the strategy better), and how often at each factor level.

    ``brief``: without naming the reference cell (the caller names it once) and without the counts per
    factor level (the README's form; the notebook gives them).
    """
    out = []
    for label, g in verdicts.groupby("finding", sort=False):
        ref = g
        for k, v in reference.items():
            ref = ref[ref[k] == v]
        r = ref.iloc[0] if len(ref) else None
        head = label[0].upper() + label[1:]
        if r is not None:
            where = f"{r.fraction:.0%} of the gesture seen" + (
                "" if r.viewpoint == "all" else f", viewpoint {r.viewpoint}"
            )
            said = {"better": "holds", "worse": "is reversed", "no difference": "is not supported"}[r.verdict]
            cell = where if brief else f"{cell_label(r)}; {where}"
            head += (
                f": in the reference cell ({cell}) it {said} "
                f"(difference {r.difference:+.3f} [{r.ci_low:+.3f}, {r.ci_high:+.3f}])"
            )
        n = len(g)
        counts = g.verdict.value_counts()
        body = (
            f"across the design it holds in {counts.get('better', 0)} of {n} cells, with no difference in "
            f"{counts.get('no difference', 0)} and the reverse in {counts.get('worse', 0)}"
        )
        levels = []
        for factor, values in factor_levels(g).items():
            if brief or len(values) < 2:
                continue
            per = []
            for v in values:
                h = g[[_level(row, factor) == v for row in g.itertuples()]]
                per.append(f"{v} {int((h.verdict == 'better').sum())}/{len(h)}")
            levels.append(", ".join(per) if factor == "actions" else f"{factor}: {', '.join(per)}")
        out.append(f"{head}; {body}" + (f" (where it holds: {'; '.join(levels)})." if levels else "."))
    return out


def seed_spread(seeds: pd.DataFrame, cell: Mapping[str, Any] = REFERENCE_CELL) -> pd.DataFrame:
    """Per strategy of the action target, the accuracy of each recogniser seed at the full gesture in one
    cell: the spread the seed level of the intervals carries. Columns: strategy, min, max, seeds."""
    sel = seeds[(seeds.target == "action") & (seeds.metric == "accuracy")]
    for k, v in cell.items():
        sel = sel[sel[k] == v]
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
    return (
        f"{summary['episodes']:,} episodes over {p['recognizer_seeds']} recogniser seeds; action prior "
        f"{' / '.join(g['action_prior'])} × inference network {' / '.join(nets)} × p_HMM "
        f"{' / '.join(g['p_hmm'])}; noise {', '.join(f'{x:g}' for x in g['noise'])} m × viewpoints "
        f"{', '.join(g['viewpoints'])}; {p['evaluation']['bootstrap']} two-level bootstrap replicates."
    )


def winners_table(win: pd.DataFrame, shown: Sequence[tuple[str, str]]) -> pd.DataFrame:
    """:func:`winners` as a table: one row per (target, metric, action prior, network), one column per p_HMM
    reading, cells ``"jeffrey 0.912 [0.90, 0.93] = virtual"``."""
    rows = win[[(t, m) in set(shown) for t, m in zip(win.target, win.metric, strict=True)]].copy()
    rows["network"] = [
        n if n == "generating" else f"learned ({int(k)})"
        for n, k in zip(rows.inference_network, rows.learn_experiments, strict=True)
    ]
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
    the network learned from the fewest experiments, p_HMM read as in the reference cell."""
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


def _cell_rows(
    table: pd.DataFrame, cell: Mapping[str, Any], target: str, metric: str, fraction: float
) -> pd.DataFrame:
    sel = _pooled(table)
    for k, v in cell.items():
        sel = sel[sel[k] == v]
    return sel[(sel.target == target) & (sel.metric == metric) & np.isclose(sel.fraction, fraction)]


def network_alone_sentences(table: pd.DataFrame) -> list[str]:
    """For the contrasted cells, early and at the full gesture: the effect's log-loss and ECE of the network
    alone beside every fusion rule and the true action (an oracle)."""
    out = []
    fractions = sorted(table.fraction.dropna().unique())
    for cell in contrast_cells(table):
        for f in (fractions[0], fractions[-1]):
            parts = []
            for metric in ("log_loss", "ece"):
                g = _cell_rows(table, cell, "effect", metric, f).set_index("strategy")
                if "network" not in g.index:
                    continue
                net = g.loc["network"]
                rules = [s for s in g.index if s not in ("network", *REFERENCES)]
                name = "log-loss" if metric == "log_loss" else "ECE"
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
                    f"The effect with {f:.0%} of the gesture seen ({cell_label(cell)}): "
                    + "; ".join(parts)
                    + "."
                )
    return out


def p_hmm_table(table: pd.DataFrame, cell: Mapping[str, Any] | None = None) -> pd.DataFrame:
    """p_HMM alone (strategy ``gesture``) at the full gesture under each reading: accuracy, log-loss, ECE
    with intervals, in one cell of actions and network (default the reference cell's)."""
    cell = {k: v for k, v in (cell or REFERENCE_CELL).items() if k != "p_hmm"}
    sel = _pooled(table)
    for k, v in cell.items():
        sel = sel[sel[k] == v]
    sel = sel[
        (sel.target == "action") & (sel.strategy == "gesture") & np.isclose(sel.fraction, sel.fraction.max())
    ]
    return sel.pivot_table(index="p_hmm", columns="metric", values="estimate", sort=False)[
        ["accuracy", "log_loss", "ece"]
    ]


def p_hmm_sentences(
    table: pd.DataFrame, calibration: pd.DataFrame, segments: pd.DataFrame | None = None
) -> list[str]:
    """What the tables say of p_HMM as a probability: its ECE under each reading on held-out synthetic
    gestures, the fitted inverse temperatures, and (with the real data) the held-out real segments."""
    t = p_hmm_table(table)
    out = [
        "On the corpus's held-out synthetic gestures (reference cell, full gesture), p_HMM alone names "
        + "; ".join(
            f"{r} {t.loc[r, 'accuracy']:.3f} of the actions with an ECE of {t.loc[r, 'ece']:.3f}"
            for r in t.index
        )
        + "."
    ]
    if len(calibration):
        full = calibration[np.isclose(calibration.fraction, calibration.fraction.max())]
        out.append(
            "The calibrated reading's inverse temperature at the full gesture, fitted per seed on "
            f"held-out training gestures: β = {full.beta.min():.3g} to {full.beta.max():.3g} (the "
            "likelihood reading is β = 1)."
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
        f"Over {k} recogniser seeds (reference cell, full gesture), accuracy ranges "
        + "; ".join(f"{r.strategy} {r['min']:.3f}–{r['max']:.3f}" for _, r in spread.iterrows())
        + "."
    )
