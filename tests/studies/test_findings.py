"""Sentences and winners written from the corpus tables: constructed tables with known answers."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from glu.studies.corpus_evaluation import findings as fd

CELLS = [
    {"action_prior": a, "inference_network": n, "learn_experiments": k, "p_hmm": p}
    for a in ("uniform", "network")
    for n, k in (("generating", 0), ("learned", 100))
    for p in ("likelihood", "per-frame")
]


def diff_rows():
    """jeffrey − virtual on effect log-loss: better (negative) in the uniform cells, no difference elsewhere;
    network − gesture on action accuracy stored the other way round (gesture after network)."""
    rows = []
    for cell in CELLS:
        good = cell["action_prior"] == "uniform"
        for fraction in (0.2, 1.0):
            base = {**cell, "noise": np.nan, "viewpoint": "all", "fraction": fraction}
            rows.append(
                {
                    **base,
                    "target": "effect",
                    "metric": "log_loss",
                    "strategy": "jeffrey",
                    "baseline": "virtual",
                    "difference": -0.05 if good else -0.01,
                    "ci_low": -0.07 if good else -0.03,
                    "ci_high": -0.03 if good else 0.01,
                    "verdict": "better" if good else "no difference",
                }
            )
            rows.append(
                {
                    **base,
                    "viewpoint": "turned",
                    "target": "action",
                    "metric": "accuracy",
                    "strategy": "network",
                    "baseline": "gesture",
                    "difference": 0.2,
                    "ci_low": 0.1,
                    "ci_high": 0.3,
                    "verdict": "better",
                }
            )
    return pd.DataFrame(rows)


def test_pair_flips_a_difference_stored_the_other_way_round():
    d = fd.pair(diff_rows(), "action", "accuracy", "gesture", "network")
    assert (d.difference == -0.2).all() and (d.ci_low == -0.3).all() and (d.ci_high == -0.1).all()
    assert (d.verdict == "worse").all() and (d.strategy == "gesture").all()


def test_finding_verdicts_and_sentences():
    findings = (
        fd.Finding("Jeffrey beats virtual", "effect", "log_loss", "jeffrey", "virtual"),
        fd.Finding(
            "turned, the gesture beats the network",
            "action",
            "accuracy",
            "gesture",
            "network",
            viewpoint="turned",
        ),
    )
    v = fd.finding_verdicts(diff_rows(), findings)
    assert len(v) == 2 * len(CELLS) and set(v.fraction) == {1.0}
    sentences = fd.finding_sentences(v, {**CELLS[1]})  # reference: uniform, generating, per-frame
    assert sentences[0].startswith(
        "Jeffrey beats virtual: in the reference cell (uniform actions, generating"
    )
    assert "it holds (difference -0.050 [-0.070, -0.030])" in sentences[0]
    assert "holds in 4 of 8 cells, with no difference in 4 and the reverse in 0" in sentences[0]
    assert "uniform actions 4/4, actions from the network's prior 0/4" in sentences[0]
    assert "network: generating 2/4, learned (100) 2/4" in sentences[0]
    assert "it is reversed (difference -0.200 [-0.300, -0.100])" in sentences[1]
    assert "holds in 0 of 8 cells, with no difference in 0 and the reverse in 8" in sentences[1]
    brief = fd.finding_sentences(v, {**CELLS[1]}, brief=True)  # the README's form
    assert brief[0] == (
        "Jeffrey beats virtual: in the reference cell (100% of the gesture seen) it holds (difference "
        "-0.050 [-0.070, -0.030]); across the design it holds in 4 of 8 cells, with no difference in "
        "4 and the reverse in 0."
    )
    early = fd.finding_verdicts(
        diff_rows(), (fd.Finding("early", "effect", "log_loss", "jeffrey", "virtual", early=True),)
    )
    assert set(early.fraction) == {0.2}


def metric_rows():
    rows = []
    for cell in CELLS:
        for strategy, est in (
            ("network", 0.90),
            ("hard", 1.20),
            ("virtual", 0.95),
            ("jeffrey", 0.88),
            ("true_action", 0.5),
        ):
            for metric, scale in (("log_loss", 1.0), ("ece", 0.1)):
                rows.append(
                    {
                        **cell,
                        "noise": np.nan,
                        "viewpoint": "all",
                        "target": "effect",
                        "strategy": strategy,
                        "fraction": 1.0,
                        "metric": metric,
                        "estimate": est * scale,
                        "ci_low": est * scale - 0.01,
                        "ci_high": est * scale + 0.01,
                    }
                )
        for strategy, acc in (("gesture", 0.6), ("network", 0.55)):
            for metric, value in (
                ("accuracy", acc),
                ("log_loss", 3.0),
                ("ece", 0.3 if cell["p_hmm"] == "likelihood" else 0.1),
            ):
                rows.append(
                    {
                        **cell,
                        "noise": np.nan,
                        "viewpoint": "all",
                        "target": "action",
                        "strategy": strategy,
                        "fraction": 1.0,
                        "metric": metric,
                        "estimate": value,
                        "ci_low": value,
                        "ci_high": value,
                    }
                )
    return pd.DataFrame(rows)


def test_winners_name_the_best_and_the_ties():
    table = metric_rows()
    diffs = pd.DataFrame(
        [
            {
                **c,
                "noise": np.nan,
                "viewpoint": "all",
                "fraction": 1.0,
                "target": "effect",
                "metric": "log_loss",
                "strategy": "jeffrey",
                "baseline": b,
                "difference": 0.0,
                "ci_low": lo,
                "ci_high": hi,
                "verdict": "no difference" if lo < 0 < hi else "better",
            }
            for c in CELLS
            for b, lo, hi in (("network", -0.05, 0.02), ("hard", -0.4, -0.2), ("virtual", -0.1, -0.01))
        ]
    )
    w = fd.winners(table, diffs)
    row = w[(w.target == "effect") & (w.metric == "log_loss")].iloc[0]
    assert row.best == "jeffrey" and row.tied == "jeffrey, network" and row.beats == "hard, virtual"
    assert row.estimate == pytest.approx(0.88)  # the oracle (0.5) is never the winner
    ece = w[(w.target == "effect") & (w.metric == "ece")].iloc[0]
    assert ece.best == "jeffrey"


def test_network_alone_and_p_hmm_sentences():
    table = metric_rows()
    cells = fd.contrast_cells(table)
    assert cells[0] == fd.REFERENCE_CELL and cells[1]["action_prior"] == "network"
    assert (cells[1]["inference_network"], cells[1]["learn_experiments"]) == ("learned", 100)
    lines = fd.network_alone_sentences(table)
    assert (
        "log-loss 0.900 [0.890, 0.910] for the network alone, hard 1.200, virtual 0.950, jeffrey 0.880"
        in lines[0]
    )
    assert "the true action 0.500" in lines[0] and "ECE 0.090" in lines[0]
    cal = pd.DataFrame(
        {"recognizer_seed": [0, 1], "fraction": [1.0, 1.0], "beta": [0.05, 0.2], "n_gestures": [9, 9]}
    )
    seg = pd.DataFrame(
        {
            "reading": ["likelihood", "per-frame"],
            "segments": [11, 11],
            "accuracy": [0.73, 0.73],
            "confidence": [1.0, 0.9],
            "ece": [0.27, 0.14],
            "log_loss": [3.7, 0.9],
            "certain": [11, 3],
        }
    )
    text = fd.p_hmm_sentences(table, cal, seg)
    assert "likelihood 0.600 of the actions with an ECE of 0.300; per-frame 0.600" in text[0]
    assert "β = 0.05 to 0.2" in text[1]
    assert "at least 0.99 for 11 of them while naming 0.73 correctly" in text[2]


def test_seed_spread():
    seeds = pd.DataFrame(
        [
            {
                **fd.REFERENCE_CELL,
                "recognizer_seed": k,
                "target": "action",
                "strategy": s,
                "fraction": 1.0,
                "metric": "accuracy",
                "estimate": e,
            }
            for k, (g, n) in enumerate(((0.637, 0.5), (0.576, 0.52)))
            for s, e in (("gesture", g), ("network", n))
        ]
    )
    spread = fd.seed_spread(seeds)
    assert spread.set_index("strategy").loc["gesture", "min"] == 0.576 and spread.seeds.max() == 2
    assert fd.seed_sentence(spread) == (
        "Over 2 recogniser seeds (reference cell, full gesture), accuracy ranges gesture 0.576–0.637; "
        "network 0.500–0.520."
    )
