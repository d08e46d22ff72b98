"""The papers' network and fusion experiments as functions returning tidy DataFrames (docs/method.md §7).

Each function takes the network(s) it needs and returns one row per number behind a figure, stamped by
:func:`~glu.tidy.tidy`. When the original model is given (``reference=``, the BN imported
from ``BN_lab.mat``), the frame also holds the original's value and the difference, so every reproduced
figure can be checked against the authors'. Their figures are drawn by :mod:`glu.plots`; the
effect-anticipation experiment, which needs the gesture HMMs, is in
:mod:`glu.studies.anticipation.experiment`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

from glu.bn.inference import Engine, make_engine
from glu.bn.model import BayesNet
from glu.evidence import format_evidence
from glu.fusion import SOFT_STRATEGIES, Strategy, check_strategy, fuse, hmm_rows
from glu.gestures.corpus import LabelledSequence
from glu.gestures.recognizer import Recognizer
from glu.hmm import p_hmm_from_loglik
from glu.tidy import model_source, tidy

EFFECT_CASES: dict[str, dict[str, str]] = {
    "small sphere": {"Action": "tap", "Shape": "sphere", "Size": "small"},
    "big box": {"Action": "tap", "Shape": "box", "Size": "big"},
}
"""GLU 2017 Fig. 4: ObjVel predicted for a tap on a small sphere and on a big box."""

WORD_EVIDENCE: dict[str, dict[str, str]] = {
    "text": {"Size": "big", "Shape": "sphere", "ObjVel": "fast"},
    "code": {"Color": "yellow", "Size": "big", "Shape": "sphere", "ObjVel": "fast"},
}
"""GLU 2017 Fig. 5: the evidence of the paper's text, and of the original code (which adds Color=yellow)."""

TCDS_ACTION_ROWS: tuple[tuple[float, float, float], ...] = (
    (1 / 3, 1 / 3, 1 / 3),
    (0.3, 0.4, 0.3),
    (0.25, 0.5, 0.25),
    (0.2, 0.6, 0.2),
    (0.15, 0.7, 0.15),
    (0.1, 0.8, 0.1),
    (0.05, 0.9, 0.05),
    (0.0, 1.0, 0.0),
)
"""TCDS: p_hmm rows [grasp, tap, touch] from uniform to certain tap."""
TCDS_ACTION_EVIDENCE: dict[str, str] = {"Size": "small", "Shape": "sphere", "ObjVel": "slow"}

TCDS_EFFECT_ROWS: tuple[tuple[float, float, float] | None, ...] = (
    None,
    (0.0, 0.0, 1.0),
    (0.0, 0.25, 0.75),
    (0.0, 0.5, 0.5),
    (0.0, 0.75, 0.25),
    (0.0, 1.0, 0.0),
)
"""TCDS: no action evidence, then p_hmm rows [grasp, tap, touch] from certain touch to certain tap."""


def _label(q: Sequence[float] | None) -> str:
    return "no action evidence" if q is None else "[" + " ".join(f"{x:.2g}" for x in q) + "]"


ORIGINAL_REFERENCE = "original model (BN_lab.mat)"
"""What a table's ``difference`` column is taken against when a reference model is given (the summary's
label)."""


def _stamped(
    df: pd.DataFrame, name: str, bn: BayesNet, reference: BayesNet | None, **params: Any
) -> pd.DataFrame:
    """``df`` stamped by :func:`~glu.tidy.tidy` as the table ``name`` of ``bn``, with its parameters and the
    reference model's label (None without one)."""
    return tidy(
        df, name, model_source(bn), **params, reference=ORIGINAL_REFERENCE if reference is not None else None
    )


def _against_reference(
    rows_of: Callable[[Engine], list[dict[str, Any]]], bn: BayesNet, reference: BayesNet | None
) -> pd.DataFrame:
    """The rows ``rows_of`` gives on ``bn``'s engine; with a ``reference`` model, the same rows' ``p`` on
    its engine beside them (``p_original``) and the ``difference``."""
    df = pd.DataFrame(rows_of(make_engine(bn)))
    if reference is not None:
        df["p_original"] = [r["p"] for r in rows_of(make_engine(reference))]
        df["difference"] = df["p"] - df["p_original"]
    return df


def effect_prediction(bn: BayesNet, reference: BayesNet | None = None) -> pd.DataFrame:
    """GLU 2017 effect prediction: p(ObjVel | Action=tap, Shape, Size) for the small sphere and the big box.

    Returns columns ``case, ObjVel, p`` (+ ``p_original, difference`` with a reference model).
    """
    values = bn.schema.values_of("ObjVel")

    def rows_of(eng: Engine) -> list[dict[str, Any]]:
        return [
            {"case": case, "evidence": format_evidence(ev), "ObjVel": v, "p": p}
            for case, ev in EFFECT_CASES.items()
            for v, p in zip(values, eng.query(["ObjVel"], ev)["ObjVel"], strict=True)
        ]

    df = _against_reference(rows_of, bn, reference)
    return _stamped(df, "glu2017_effect_prediction", bn, reference, cases=EFFECT_CASES)


def word_probability_change(
    bn: BayesNet,
    evidence: str | Mapping[str, str] = "text",
    reference: BayesNet | None = None,
    threshold: float = 0.02,
) -> pd.DataFrame:
    """GLU 2017 word prediction: Δp(w) = p(w | F, E, Action=tap) − p(w | F, E) for every word.

    ``evidence`` is ``"text"`` (the paper's F, E), ``"code"`` (the original code's, with Color=yellow) or a
    mapping. Returns columns ``word, p_without, p_with, delta, shown`` (``|delta| > threshold``), sorted by
    word order (+ ``delta_original, difference`` with a reference model).
    """
    ev = dict(WORD_EVIDENCE[evidence] if isinstance(evidence, str) else evidence)
    eng = make_engine(bn)
    without = eng.word_probability_array(ev)
    with_tap = eng.word_probability_array({**ev, "Action": "tap"})
    df = pd.DataFrame({"word": list(eng.binary_leaves), "p_without": without, "p_with": with_tap})
    df["delta"] = df["p_with"] - df["p_without"]
    df["shown"] = df["delta"].abs() > threshold
    df.insert(0, "evidence", format_evidence(ev))
    if reference:
        r = make_engine(reference)
        df["delta_original"] = r.word_probability_array({**ev, "Action": "tap"}) - r.word_probability_array(
            ev
        )
        df["difference"] = df["delta"] - df["delta_original"]
    return _stamped(df, "glu2017_word_change", bn, reference, evidence=ev, threshold=threshold)


def word_probability_changes(
    bn: BayesNet, reference: BayesNet | None = None, threshold: float = 0.02
) -> dict[str, pd.DataFrame]:
    """:func:`word_probability_change` under each evidence of :data:`WORD_EVIDENCE` (the paper's text's,
    the original code's): its name → the frame."""
    return {name: word_probability_change(bn, name, reference, threshold) for name in WORD_EVIDENCE}


def action_vs_soft_evidence(
    bn: BayesNet,
    rows: Sequence[Sequence[float]] = TCDS_ACTION_ROWS,
    evidence: Mapping[str, str] = TCDS_ACTION_EVIDENCE,
    strategy: Strategy = "product",
    reference: BayesNet | None = None,
) -> pd.DataFrame:
    """TCDS action recognition: p_comb(Action | Size=small, Shape=sphere, ObjVel=slow) for each p_hmm row.

    Returns columns ``case, p_hmm_tap, Action, p`` (+ ``p_original, difference``).
    """
    actions = bn.schema.values_of("Action")

    def rows_of(eng: Engine) -> list[dict[str, Any]]:
        return [
            {"case": _label(q), "p_hmm_tap": q[actions.index("tap")], "Action": a, "p": p}
            for q in rows
            for a, p in zip(actions, fuse(eng, ["Action"], evidence, q, strategy)["Action"], strict=True)
        ]

    df = _against_reference(rows_of, bn, reference)
    df.insert(0, "evidence", format_evidence(evidence))
    df.insert(1, "strategy", strategy)
    return _stamped(df, "tcds_action_vs_soft_evidence", bn, reference, evidence=evidence, strategy=strategy)


def tap_threshold(
    bn: BayesNet,
    evidence: Mapping[str, str] = TCDS_ACTION_EVIDENCE,
    strategy: Strategy = "product",
    tol: float = 1e-12,
) -> float:
    """The p_hmm(tap) above which tap wins p_comb(Action | evidence), the rest split equally; by bisection.

    The papers report tap wins only when p_hmm(tap) > 0.81 for {Size=small, Shape=sphere, ObjVel=slow}.
    The search runs over p_hmm(tap) in [0, 1] (below 1/3 the HMMs favour the other actions), where tap's
    margin grows monotonically; returns ``nan`` if tap never wins (p_BN(tap | evidence) = 0).
    """
    eng = make_engine(bn)
    actions = bn.schema.values_of("Action")
    i_tap = actions.index("tap")

    def margin(t: float) -> float:
        q = [(1 - t) / 2] * 3
        q[i_tap] = t
        post = fuse(eng, ["Action"], evidence, q, strategy)["Action"]
        return float(post[i_tap] - np.delete(post, i_tap).max())

    lo, hi = 0.0, 1.0 - 1e-15
    if margin(hi) <= 0:
        return float("nan")
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        if margin(mid) > 0:
            hi = mid
        else:
            lo = mid
    return 0.5 * (lo + hi)


def effect_vs_soft_evidence(
    bn: BayesNet,
    shapes: Sequence[str] = ("sphere", "box"),
    rows: Sequence[Sequence[float] | None] = TCDS_EFFECT_ROWS,
    rules: Sequence[Strategy] = ("virtual", "jeffrey"),
    reference: BayesNet | None = None,
) -> pd.DataFrame:
    """TCDS effect prediction: p_comb(ObjVel | Shape) for no action evidence and each p_hmm row.

    ``rules``: soft-fusion strategies to compare (``virtual`` is the originals'). Returns columns
    ``Shape, rule, case, ObjVel, p`` (+ ``p_original, difference``).
    """
    values = bn.schema.values_of("ObjVel")

    def rows_of(eng: Engine) -> list[dict[str, Any]]:
        return [
            {"Shape": shape, "rule": rule, "case": _label(q), "ObjVel": v, "p": p}
            for shape in shapes
            for rule in rules
            for q in rows
            for v, p in zip(values, fuse(eng, ["ObjVel"], {"Shape": shape}, q, rule)["ObjVel"], strict=True)
        ]

    df = _against_reference(rows_of, bn, reference)
    return _stamped(df, "tcds_effect_vs_soft_evidence", bn, reference, shapes=shapes, rules=rules)


def soft_evidence_sweep(
    bn: BayesNet,
    evidence: Mapping[str, str],
    target: str = "ObjVel",
    n_points: int = 101,
    rules: Sequence[Strategy] = ("virtual", "jeffrey"),
) -> pd.DataFrame:
    """p_comb(target | evidence, p_hmm) as p_hmm(tap) goes from 0 to 1 (the rest split equally), per rule.

    One batch query per rule (:func:`glu.fusion.fuse` over a (n_points, 3) array of posteriors). Returns
    columns ``evidence, rule, p_hmm_tap, <target>, p``.
    """
    eng = make_engine(bn)
    t = np.linspace(0.0, 1.0, n_points)
    q = hmm_rows(t)
    values = bn.schema.values_of(target)
    frames = []
    for rule in rules:
        check_strategy(rule, SOFT_STRATEGIES)
        post = fuse(eng, [target], evidence, q, rule)[target]
        for i, v in enumerate(values):
            frames.append(pd.DataFrame({"rule": rule, "p_hmm_tap": t, target: v, "p": post[:, i]}))
    df = pd.concat(frames, ignore_index=True)
    df.insert(0, "evidence", format_evidence(evidence))
    return tidy(
        df,
        f"soft_evidence_sweep_{target}",
        model_source(bn),
        evidence=evidence,
        n_points=n_points,
        rules=rules,
    )


SWEEP_SHAPES: tuple[str, ...] = ("sphere", "box")
"""The shapes notebook 05 sweeps p_HMM(tap) for (TCDS's effect-prediction objects)."""


def soft_evidence_sweeps(
    bn: BayesNet, shapes: Sequence[str] = SWEEP_SHAPES, n_points: int = 101
) -> dict[str, pd.DataFrame]:
    """:func:`soft_evidence_sweep` of p_comb(ObjVel | Shape) under virtual evidence and Jeffrey's rule for
    each of ``shapes``: shape → its sweep, in the order given."""
    return {shape: soft_evidence_sweep(bn, {"Shape": shape}, n_points=n_points) for shape in shapes}


def tap_thresholds(bn: BayesNet, nodes: Sequence[str] = ("Shape", "Size", "ObjVel")) -> pd.DataFrame:
    """The tap threshold of :func:`tap_threshold` for every combination of values of ``nodes``.

    Returns columns ``<nodes…>, p_bn_tap, threshold`` (``threshold`` nan where tap can never win).
    """
    import itertools

    eng = make_engine(bn)
    rows = []
    for combo in itertools.product(*[bn.schema.values_of(n) for n in nodes]):
        ev = dict(zip(nodes, combo, strict=True))
        try:
            p_bn = eng.query(["Action"], ev)["Action"][bn.schema.values_of("Action").index("tap")]
        except ValueError:  # impossible evidence under the model
            continue
        rows.append({**ev, "p_bn_tap": p_bn, "threshold": tap_threshold(bn, ev)})
    return tidy(pd.DataFrame(rows), "tap_thresholds", model_source(bn), nodes=nodes)


def structure_comparison(bn: BayesNet, original: BayesNet | None = None) -> pd.DataFrame:
    """The learned structure against a reference: the original's (``original``) or the synthetic generator's.

    One row per edge in either: ``parent, child, in_reference, in_ours, difference`` (1 where they differ).
    The reference's name is in ``attrs["parameters"]["reference"]``.
    """
    if original is not None:
        reference = {n: set(original.parents[n]) for n in bn.nodes}
        name = "BN_lab.mat"
    else:
        from glu.data.synthetic import WORLD

        reference = {n: set(WORLD.parents.get(n, WORLD.word_parents.get(n, bn.parents[n]))) for n in bn.nodes}
        name = "synthetic generator"
    edges = pd.DataFrame(
        [(p, c, p in reference[c]) for p, c in bn.edges()]
        + [(p, c, True) for c in bn.nodes for p in reference[c] if p not in bn.parents[c]],
        columns=["parent", "child", "in_reference"],
    )
    edges["in_ours"] = [p in bn.parents[c] for p, c in zip(edges["parent"], edges["child"], strict=True)]
    edges["difference"] = (edges["in_ours"] != edges["in_reference"]).astype(int)
    return tidy(edges, "bn_structure", model_source(bn), reference=name)


def network_summary(bn: BayesNet, table: pd.DataFrame, original: BayesNet | None = None) -> pd.DataFrame:
    """The learned network in numbers, beside the original's when given (one row per quantity).

    Quantities: ``edges``; ``log_likelihood`` of ``table`` (natural log, all nodes); ``zero_rows`` (CPT rows
    left all zeros); ``lost_prior_mass`` (the prior probability of the affordance configurations those
    rows make impossible, 1 − Σ p). With ``original``: ``differing_edges`` and ``max_cpt_difference`` too.

    Returns
    -------
    DataFrame with columns quantity, ours, and with ``original``: reference (its value), difference.
    """
    from glu.bn.model import encode

    codes = encode(table, bn.schema)
    quantities: dict[str, Callable[[BayesNet], float]] = {
        "edges": lambda m: len(m.edges()),
        "log_likelihood": lambda m: m.log_likelihood(codes),
        "zero_rows": lambda m: sum(m.zero_rows().values()),
        "lost_prior_mass": lambda m: 1 - make_engine(m).probability_of_evidence(),
    }
    rows = [(q, f(bn), f(original) if original else np.nan) for q, f in quantities.items()]
    if original is not None:
        rows += [
            ("differing_edges", len(set(bn.edges()) ^ set(original.edges())), 0),
            ("max_cpt_difference", max(float(abs(bn.cpts[n] - original.cpts[n]).max()) for n in bn.nodes), 0),
        ]
    df = pd.DataFrame(rows, columns=["quantity", "ours", "reference"])
    if original is None:
        return tidy(df[["quantity", "ours"]], "bn_learning_summary", model_source(bn), reference=None)
    df["difference"] = df["ours"] - df["reference"]
    return tidy(df, "bn_learning_summary", model_source(bn), reference="BN_lab.mat")


def unseen_rows_comparison(zero: BayesNet, uniform: BayesNet) -> pd.DataFrame:
    """How much the original's all-zero word rows move the published bars: the same queries on both models.

    Returns columns ``experiment, case, value, p_zero, p_uniform, uniform_minus_zero``.
    """
    rows = []
    for name, val_col, table in (
        ("effect prediction", "ObjVel", effect_prediction),
        ("effect vs soft evidence", "ObjVel", lambda bn: effect_vs_soft_evidence(bn, rules=("virtual",))),
        ("action vs soft evidence", "Action", action_vs_soft_evidence),
    ):
        a, b = table(zero), table(uniform)
        case = a["case"] if "Shape" not in a else a["Shape"] + ", " + a["case"]
        rows.append(
            pd.DataFrame(
                {"experiment": name, "case": case, "value": a[val_col], "p_zero": a["p"], "p_uniform": b["p"]}
            )
        )
    wz, wu = word_probability_change(zero), word_probability_change(uniform)
    words = {"experiment": "word change Δp(w)", "case": wz["evidence"], "value": wz["word"]}
    rows.append(pd.DataFrame({**words, "p_zero": wz["delta"], "p_uniform": wu["delta"]}))
    df = pd.concat(rows, ignore_index=True)
    df["uniform_minus_zero"] = df["p_uniform"] - df["p_zero"]
    return tidy(df, "unseen_rows_comparison", model_source(zero))


def fusion_on_gestures(
    bn: BayesNet,
    recognizer: Recognizer,
    sequences: Sequence[LabelledSequence],
    evidence: Mapping[str, str],
    strategies: Sequence[Strategy] = ("hard", "virtual", "jeffrey"),
    target: str = "ObjVel",
) -> pd.DataFrame:
    """Recognise each gesture with the HMMs and predict ``target`` from it with each fusion strategy.

    ``sequences``: labelled sequences (``action, xyz, recording, start, end``, as
    :class:`glu.gestures.corpus.LabelledSequence`); ``evidence``: the object the gestures are applied to.
    Returns columns ``recording, start, end, true_action, hmm_top, p_hmm_<a>…, strategy, <target>, p``.
    """
    eng = make_engine(bn)
    actions = bn.schema.values_of("Action")
    order = [list(recognizer.actions).index(a) for a in actions]
    rows = []
    for s in sequences:
        q = p_hmm_from_loglik(recognizer.loglik(s.xyz)[order])
        base = {
            "recording": s.recording,
            "start": s.start,
            "end": s.end,
            "true_action": s.action,
            "hmm_top": actions[int(np.argmax(q))],
            **{f"p_hmm_{a}": float(v) for a, v in zip(actions, q, strict=True)},
        }
        for strategy in strategies:
            post = fuse(eng, [target], evidence, q, strategy)[target]
            for v, p in zip(bn.schema.values_of(target), post, strict=True):
                rows.append({**base, "strategy": strategy, target: v, "p": float(p)})
    df = pd.DataFrame(rows)
    df.insert(0, "evidence", format_evidence(evidence))
    return tidy(
        df, "fusion_on_gestures", model_source(bn), evidence=evidence, strategies=strategies, target=target
    )
