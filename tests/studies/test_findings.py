"""Sentences, verdicts and winners written from the corpus tables: constructed tables with known answers."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from glu.stats import benjamini_hochberg
from glu.studies.corpus_evaluation import conditions as cd
from glu.studies.corpus_evaluation import findings as fd

CELLS = [
    {"action_prior": a, "inference_network": n, "learn_experiments": k, "p_hmm": p}
    for a in ("uniform", "network")
    for n, k in (("generating", 0), ("learned", 100))
    for p in ("likelihood", "per-frame")
]
CONDITIONS = [  # (effects, features, viewpoint, noise)
    ("action", "raw", "front", np.nan),
    ("action", "raw", "side-on", np.nan),
    ("action", "centred+rotated", "front", np.nan),
    ("action", "centred+rotated", "side-on", np.nan),
    ("gesture", "raw", "front", np.nan),
    ("action", "raw", "all", 0.0),
    ("action", "raw", "all", 0.05),
]


def diff_rows():
    """jeffrey − network on effect log-loss: on the front view better in the uniform cells (p = 0.002), no
    difference elsewhere (p = 0.5); side-on with raw features worse everywhere (p = 0.002)."""
    rows = []
    for effects, features, view, noise in CONDITIONS:
        for cell in CELLS:
            good = cell["action_prior"] == "uniform" and view != "side-on"
            bad = view == "side-on" and features == "raw"
            for fraction in (0.2, 1.0):
                d, lo, hi, p = (-0.05, -0.07, -0.03, 0.002) if good else (0.2, 0.1, 0.3, 0.002) if bad else (
                    -0.01, -0.03, 0.01, 0.5)  # fmt: skip
                verdict = "better" if good else "worse" if bad else "no difference"
                base = {**cell, "effects": effects, "features": features, "noise": noise, "viewpoint": view}
                rows.append(
                    {**base, "fraction": fraction, "target": "effect", "metric": "log_loss",
                     "strategy": "jeffrey", "baseline": "network", "difference": d, "ci_low": lo,
                     "ci_high": hi, "p_value": p, "verdict": verdict}
                )  # fmt: skip
                # stored the other way round: network − gesture on action accuracy
                rows.append(
                    {**base, "fraction": fraction, "target": "action", "metric": "accuracy",
                     "strategy": "network", "baseline": "gesture", "difference": 0.2, "ci_low": 0.1,
                     "ci_high": 0.3, "p_value": 0.002, "verdict": "better"}
                )  # fmt: skip
    return pd.DataFrame(rows)


FINDINGS = (
    fd.Finding("Jeffrey beats the network", "effect", "log_loss", "jeffrey", "network"),
    fd.Finding("the gesture beats the network", "action", "accuracy", "gesture", "network"),
)


def test_pair_flips_a_difference_stored_the_other_way_round():
    d = diff_rows().assign(p_adjusted=0.01, verdict_adjusted="better")
    d = fd.pair(d, "action", "accuracy", "gesture", "network")
    assert (d.difference == -0.2).all() and (d.ci_low == -0.3).all() and (d.ci_high == -0.1).all()
    assert (d.verdict == "worse").all() and (d.verdict_adjusted == "worse").all()
    assert (d.strategy == "gesture").all()


def test_finding_verdicts_are_adjusted_as_one_family():
    v = fd.finding_verdicts(diff_rows(), FINDINGS)
    assert len(v) == 2 * len(CELLS) * len(CONDITIONS) and set(v.fraction) == {1.0}
    np.testing.assert_allclose(v.p_adjusted, benjamini_hochberg(v.p_value.to_numpy()))
    strong = v[v.p_value == 0.002]
    assert (strong.p_adjusted <= 0.05).all()  # many at the floor: BH keeps them
    assert set(v[v.p_value == 0.5].verdict_adjusted) == {"no difference"}
    effect = strong[strong.finding == "Jeffrey beats the network"]
    assert set(effect[effect.difference < 0].verdict_adjusted) == {"better"}
    assert set(effect[effect.difference > 0].verdict_adjusted) == {"worse"}
    early = fd.finding_verdicts(
        diff_rows(), (fd.Finding("early", "effect", "log_loss", "jeffrey", "network", early=True),)
    )
    assert set(early.fraction) == {0.2}


def test_a_weak_family_loses_its_verdicts():
    """An interval that excludes 0 with p = 0.04 is a verdict alone; 20 such among 56 differences whose other
    p-values are 0.5 are none once adjusted (BH: 0.04 > 0.05 k / 56 for every k ≤ 20)."""
    d = diff_rows()
    d["p_value"] = np.where(d.verdict == "better", 0.04, 0.5)
    v = fd.finding_verdicts(d, FINDINGS[:1])
    assert (v.p_value == 0.04).sum() == 20
    assert (v.verdict != "no difference").any() and (v.verdict_adjusted == "no difference").all()


def test_sentences_lead_with_the_front_view_and_say_where_it_changes():
    v = fd.finding_verdicts(diff_rows(), FINDINGS)
    counts = fd.verdict_counts(v)
    front = counts[(counts.viewpoint == "front") & (counts.features == "raw") & (counts.effects == "action")]
    row = front[front.finding == "Jeffrey beats the network"].iloc[0]
    assert (row.cells, row.better, row.no_difference, row.worse) == (8, 4, 4, 0)
    reference = {**fd.REFERENCE_CELL, **CELLS[1]}  # uniform, generating, per-frame
    text = fd.finding_sentences(v, reference)[0]
    assert text.startswith(
        "Jeffrey beats the network: on the front view (noise levels pooled), in the reference cell (uniform "
        "actions, generating network, p_HMM per-frame; 100% of the gesture seen) it holds (difference -0.050 "
        "[-0.070, -0.030], adjusted p "
    )
    assert "over the front view's 8 cells it holds in 4, with no difference in 4 and the reverse in 0" in text
    assert "uniform actions 4/4, actions from the network's prior 0/4" in text
    assert "side-on: raw 0/8 (reversed in 8), centred+rotated 0/8" in text
    assert "front view with effects that depend on the gesture: raw 4/8" in text
    assert "raw features, all viewpoints, by sensor noise: 0 cm 4/8, 5 cm 4/8" in text
    brief = fd.finding_sentences(v, reference, brief=True)[0]
    assert "(100% of the gesture seen)" in brief and "where it holds:" not in brief
    gesture = fd.finding_sentences(v, reference)[1]
    assert "it is reversed (difference -0.200 [-0.300, -0.100]" in gesture


def metric_rows():
    rows = []
    for cell in CELLS:
        for view in ("front", "side-on", "all"):
            for features in ("raw", "centred+rotated"):
                for effects in ("action", "gesture"):
                    base = {
                        **cell,
                        "effects": effects,
                        "features": features,
                        "noise": np.nan,
                        "viewpoint": view,
                    }
                    side = view == "side-on" and features == "raw"
                    for strategy, est in (
                        ("network", 0.90),
                        ("hard", 1.20),
                        ("virtual", 0.95),
                        ("jeffrey", 1.5 if side else 0.88 + 0.01 * (effects == "gesture")),
                        ("true_action", 0.5),
                    ):
                        for metric, scale in (("log_loss", 1.0), ("ece", 0.1)):
                            rows.append(
                                {**base, "target": "effect", "strategy": strategy, "fraction": 1.0,
                                 "metric": metric, "estimate": est * scale, "ci_low": est * scale - 0.01,
                                 "ci_high": est * scale + 0.01}
                            )  # fmt: skip
                    for strategy, acc in (("gesture", 0.3 if side else 0.6), ("network", 0.55)):
                        for metric, value in (
                            ("accuracy", acc),
                            ("log_loss", 3.0),
                            ("ece", 0.3 if cell["p_hmm"] == "likelihood" else 0.1),
                        ):
                            rows.append(
                                {**base, "target": "action", "strategy": strategy, "fraction": 1.0,
                                 "metric": metric, "estimate": value, "ci_low": value, "ci_high": value}
                            )  # fmt: skip
    return pd.DataFrame(rows)


def test_winners_name_the_best_and_the_adjusted_ties():
    table = metric_rows()
    diffs = pd.DataFrame(
        [
            {**c, "effects": "action", "features": "raw", "noise": np.nan, "viewpoint": "front",
             "fraction": 1.0, "target": "effect", "metric": "log_loss", "strategy": "jeffrey", "baseline": b,
             "difference": 0.0, "ci_low": lo, "ci_high": hi, "verdict": "better",
             "verdict_adjusted": adjusted}
            for c in CELLS
            for b, lo, hi, adjusted in (
                ("network", -0.05, -0.01, "no difference"),  # a verdict alone, none once adjusted
                ("hard", -0.4, -0.2, "better"),
                ("virtual", -0.1, -0.01, "better"),
            )
        ]
    )  # fmt: skip
    w = fd.winners(table, diffs)
    row = w[
        (w.target == "effect") & (w.metric == "log_loss") & (w.effects == "action") & (w.features == "raw")
    ]
    row = row.iloc[0]
    assert row.best == "jeffrey" and row.tied == "jeffrey, network" and row.beats == "hard, virtual"
    assert row.estimate == pytest.approx(0.88) and row.viewpoint == "front"  # the oracle never wins
    side = fd.winners(table, diffs, viewpoint="side-on")
    assert set(side.viewpoint) == {"side-on"}
    elsewhere = fd.winners(table, diffs, viewpoint="turned")  # not in the sweep: its first viewpoint
    pd.testing.assert_frame_equal(elsewhere, fd.winners(table, diffs))


def calibration_rows():
    return pd.DataFrame(
        {
            "recognizer_seed": [0, 1, 0, 1, 0, 1, 0, 1],
            "features": ["raw"] * 4 + ["centred+rotated"] * 4,
            "reading": ["calibrated", "calibrated", "calibrated-matched", "calibrated-matched"] * 2,
            "fraction": [1.0] * 8,
            "beta": [0.05, 1.0, 0.002, 0.003, 0.1, 0.2, 0.01, 0.02],
            "at_bound": [False, True, False, False, False, False, False, False],
            "n_gestures": [9] * 8,
            "accuracy": [0.9, 0.9, 0.5, 0.6, 0.8, 0.8, 0.7, 0.8],
        }
    )


def test_sentences_of_a_sweep_that_lacks_a_part():
    """A sweep without calibration, without the matched reading, of one world, without the reference cell,
    without a viewpoint's rows for the gesture or the network, without seeds: each sentence says so or
    leaves that part out."""
    table = metric_rows()
    cal = calibration_rows()
    unmatched = cal[cal.reading == "calibrated"]
    assert cd.best_invariant(None) is None and cd.best_invariant(cal.iloc[:0]) is None
    assert cd.best_invariant(unmatched) is None
    assert cd.validation_sentence(unmatched) == (
        "No held-out gestures drawn like the test conditions: no feature set is chosen."
    )
    one_world = table[table.effects == "action"]
    assert cd.gesture_world_sentence(one_world) == "The sweep has one world only: nothing to compare."
    no_side_net = table[~((table.viewpoint == "side-on") & (table.strategy == "network"))]
    views = cd.viewpoint_sentences(no_side_net, ["raw", "centred+rotated"])
    assert len(views) == 1 and views[0].startswith("Seen front:")
    no_side_gesture = table[~((table.viewpoint == "side-on") & (table.target == "action"))]
    text = fd.p_hmm_sentences(no_side_gesture, cal)
    assert text[0].startswith("On the corpus's held-out synthetic gestures seen front")
    assert not any("seen side-on" in t for t in text)
    network_only = table[table.action_prior == "network"]
    first = network_only.iloc[0]
    assert fd.contrast_cells(network_only)[0] == {k: first[k] for k in fd.DESIGN}
    assert fd.seed_sentence(pd.DataFrame()) == "No seed-level estimates in this cell."


def test_selection_verdicts_and_labels_in_edge_cases():
    frame = pd.DataFrame({"noise": [0.05, 0.05 + 1e-12, 0.1, np.nan], "k": range(4)})
    assert fd.select(frame, {"noise": 0.05}).k.tolist() == [0, 1]  # a float matches within rounding
    assert fd.select(frame, {"noise": np.nan}).k.tolist() == [3]
    none = fd.finding_verdicts(diff_rows(), (fd.Finding("words", "words", "log_loss", "jeffrey", "network"),))
    assert none.empty and {"finding", "viewpoint", "fraction", "p_adjusted"} <= set(none.columns)
    assert (
        fd.p_text(float("nan")) == "n/a" and fd.p_text(0.0004) == "< 0.001" and fd.p_text(0.0123) == "0.012"
    )
    row = {**fd.REFERENCE_CELL, "effects": "gesture"}
    assert fd.cell_label(row) == (
        "uniform actions, generating network, p_HMM per-frame, raw features, "
        "effects that depend on the gesture"
    )


def test_network_alone_p_hmm_and_condition_sentences():
    table = metric_rows()
    cells = fd.contrast_cells(table)
    assert cells[0] == fd.REFERENCE_CELL and cells[1]["action_prior"] == "network"
    assert (cells[1]["inference_network"], cells[1]["learn_experiments"]) == ("learned", 100)
    lines = fd.network_alone_sentences(table)
    assert lines[0].startswith(
        "The effect with 100% of the gesture seen, front view, noise levels pooled (uniform actions"
    )
    assert (
        "log-loss 0.900 [0.890, 0.910] for the network alone, hard 1.200, virtual 0.950, jeffrey 0.880"
        in (lines[0])
    )
    assert "the true action 0.500" in lines[0] and "ECE (bias-corrected) 0.090" in lines[0]
    cal = calibration_rows()
    seg = pd.DataFrame(
        {"reading": ["likelihood", "per-frame"], "segments": [11, 11], "accuracy": [0.73, 0.73],
         "confidence": [1.0, 0.9], "ece": [0.27, 0.14], "log_loss": [3.7, 0.9], "certain": [11, 3]}
    )  # fmt: skip
    text = fd.p_hmm_sentences(table, cal, seg)
    assert text[0].startswith("On the corpus's held-out synthetic gestures seen front")
    assert "read from the likelihoods 0.600 of the time, ECE 0.300; read per frame 0.600" in text[0]
    assert (
        "calibrated on clean front-view gestures β = 0.05 to 1 (at a bound of [0, 1] in 1 of 2 seeds)"
        in (text[2])
    )
    assert "1 of 8 fits sit at a bound" in text[2]
    assert "at least 0.99 for 11 of them while naming 0.73 correctly" in text[3]
    assert cd.best_invariant(cal) == "centred+rotated"
    assert "raw 0.55 (0.50–0.60 over seeds), centred+rotated 0.75 (0.70–0.80 over seeds)" in (
        cd.validation_sentence(cal)
    )
    views = cd.viewpoint_sentences(table, ["raw", "centred+rotated"])
    assert views[1] == (
        "Seen side-on: the gesture alone names the action raw 0.30 [0.30, 0.30], centred+rotated 0.60 [0.60, "
        "0.60] (the network alone 0.55); Jeffrey's rule's effect log-loss raw 1.500, centred+rotated 0.880 "
        "(the network alone 0.900)."
    )
    world = cd.gesture_world_sentence(table)
    assert "effects drawn from the action alone: network 0.900 [0.890, 0.910], jeffrey 0.880" in world
    assert "effects that depend on the gesture: network 0.900 [0.890, 0.910], jeffrey 0.890" in world


def test_seed_spread():
    seeds = pd.DataFrame(
        [
            {**fd.REFERENCE_CELL, "recognizer_seed": k, "target": "action", "strategy": s, "fraction": 1.0,
             "metric": "accuracy", "estimate": e}
            for k, (g, n) in enumerate(((0.637, 0.5), (0.576, 0.52)))
            for s, e in (("gesture", g), ("network", n))
        ]
    )  # fmt: skip
    spread = fd.seed_spread(seeds)
    assert spread.set_index("strategy").loc["gesture", "min"] == 0.576 and spread.seeds.max() == 2
    assert fd.seed_sentence(spread) == (
        "Over 2 recogniser seeds (reference cell, full gesture, viewpoints and noise pooled), accuracy "
        "ranges gesture 0.576–0.637; network 0.500–0.520."
    )


def test_viewpoints_keep_the_worlds_order_and_results_keep_the_contrasted_cells():
    table = metric_rows()
    assert fd.viewpoints(table) == ["front", "side-on"] and fd.front_view(table) == "front"
    assert fd.viewpoints(pd.DataFrame({"viewpoint": ["side-on", "all", "left", "turned", "front"]})) == [
        "front", "turned", "side-on", "left"
    ]  # fmt: skip
    kept = fd.in_contrast_cells(table, table)
    pairs = set(zip(kept.action_prior, kept.inference_network, kept.learn_experiments, strict=True))
    assert pairs == {("uniform", "generating", 0), ("network", "learned", 100)} and kept.noise.isna().all()
    assert set(kept.p_hmm) == set(table.p_hmm) and set(kept.features) == set(table.features)
    v = fd.adjusted_verdicts(np.array([0.1, -0.1, 0.1, 0.0]), np.array([0.01, 0.01, 0.2, 0.01]), [True] * 4)
    assert list(v) == ["better", "worse", "no difference", "no difference"]


def test_figures_leave_out_what_the_sweep_lacks():
    """A pair of strategies the sweep has no difference for draws no row; a condition a finding was not
    measured in leaves its cell blank."""
    import matplotlib.pyplot as plt

    from glu.studies.corpus_evaluation.figures import findings_figure, plot_differences

    diffs = diff_rows().assign(p_adjusted=0.01, verdict_adjusted="better")
    pairs = [("words", "log_loss", "jeffrey", "network"), ("effect", "log_loss", "jeffrey", "network")]
    fig, ax = plt.subplots()
    try:
        plot_differences(ax, diffs, pairs, viewpoint="front", where={**fd.REFERENCE_CELL, **CELLS[1]})
        assert list(ax.get_yticks()) == [1]  # the words' row (0) is left out
        assert [t.get_text() for t in ax.get_yticklabels()] == [
            "effect log-loss (nats) (lower is better): Jeffrey's rule − network alone"
        ]
        assert [tuple(line.get_xdata()) for line in ax.lines[:1]] == [(-0.07, -0.03)]
    finally:
        plt.close(fig)
    counts = fd.verdict_counts(fd.finding_verdicts(diff_rows(), FINDINGS))
    counts = counts[~((counts.finding == FINDINGS[1].label) & (counts.viewpoint == "side-on"))]
    columns = [("action", "front", "raw"), ("action", "side-on", "raw")]
    fig = findings_figure(counts, columns)
    try:
        cells = {
            (round(p.get_x() + p.get_width() / 2), round(p.get_y() + p.get_height() / 2))
            for p in fig.axes[0].patches
        }
        assert cells == {(0, 0), (0, 1), (1, 0)}  # (column, finding): the second finding has no side-on cell
    finally:
        plt.close(fig)


def test_the_result_tables_are_the_contrasted_cells_each_stamped_as_its_source():
    """What notebook 11 writes to results/: seven tables in order, each with the stamp of the saved table it
    was computed from (the metrics also the episodes), the metrics and differences in the contrasted cells
    only, the reliability of effects from the action alone, the reference cell's seeds; neither the
    caller's frames nor the saved tables change."""
    from glu.studies.corpus_evaluation.tables import SweepTables

    def stamped(df, name):
        df.attrs = {"experiment": name, "data_source": "synthetic", "parameters": {"seed": 0}}
        return df

    table = metric_rows()
    diffs = diff_rows().assign(p_adjusted=0.01, verdict_adjusted="better")
    saved = SweepTables(
        stamped(table, "corpus_evaluation_results"),
        stamped(diffs, "corpus_evaluation_differences"),
        stamped(table.assign(n=10), "corpus_evaluation_reliability"),
        stamped(table.assign(recognizer_seed=0), "corpus_evaluation_seeds"),
        stamped(calibration_rows(), "corpus_evaluation_calibration"),
        {"episodes": 64},
    )
    before = [dict(t.attrs) for t in saved[:5]]
    verdicts = fd.finding_verdicts(fd.bare(diffs), FINDINGS)
    counts = fd.verdict_counts(verdicts)
    written = fd.result_tables(saved, verdicts, counts)
    assert [name for _, name, _ in written] == [
        "corpus_metrics", "corpus_differences", "corpus_findings", "corpus_finding_counts",
        "corpus_reliability", "corpus_seeds", "corpus_calibration",
    ]  # fmt: skip
    sources = [saved.metrics, saved.differences, saved.differences, saved.differences, saved.reliability]
    sources += [saved.seeds, saved.calibration]
    for (frame, name, extra), source in zip(written, sources, strict=True):
        assert frame.attrs == source.attrs, name
        assert extra == ({"episodes": 64} if name == "corpus_metrics" else {})
    frames = {name: frame for frame, name, _ in written}
    metrics = frames["corpus_metrics"]
    assert "all" not in set(metrics.viewpoint) and metrics.noise.isna().all() and len(metrics)
    cells = set(zip(metrics.action_prior, metrics.inference_network, metrics.learn_experiments, strict=True))
    assert cells == {("uniform", "generating", 0), ("network", "learned", 100)}
    pd.testing.assert_frame_equal(frames["corpus_differences"], fd.in_contrast_cells(diffs, table))
    pd.testing.assert_frame_equal(frames["corpus_findings"], verdicts)
    assert set(frames["corpus_reliability"].effects) == {"action"}
    pd.testing.assert_frame_equal(frames["corpus_seeds"], fd.select(fd.bare(saved.seeds), fd.REFERENCE_CELL))
    assert verdicts.attrs == {} and counts.attrs == {}
    assert [dict(t.attrs) for t in saved[:5]] == before


def test_the_winners_figure_has_a_panel_per_target_and_metric_shown():
    """Notebook 11's winners: a panel per (target, metric) shown, two to a row (none left empty), each
    naming every cell's best strategy and titled by its target and metric; as tall as the cells need."""
    import matplotlib.pyplot as plt

    from glu.studies.corpus_evaluation.figures import winners_figure

    table = metric_rows()
    diffs = pd.DataFrame(
        [
            {**c, "effects": "action", "features": "raw", "noise": np.nan, "viewpoint": "front",
             "fraction": 1.0, "target": t, "metric": m, "strategy": s, "baseline": b, "difference": 0.1,
             "ci_low": 0.05, "ci_high": 0.2, "verdict": "better", "verdict_adjusted": "better"}
            for c in CELLS
            for t, m, s, b in (("effect", "log_loss", "jeffrey", "hard"),
                               ("action", "accuracy", "gesture", "network"))
        ]
    )  # fmt: skip
    win = fd.winners(table, diffs)
    front = win[(win.effects == "action") & (win.features == "raw")]
    shown = [("action", "accuracy"), ("effect", "log_loss"), ("effect", "ece")]
    fig = winners_figure(front, shown)
    try:
        assert len(fig.axes) == 3 and tuple(fig.get_size_inches()) == pytest.approx((10, 0.9 * 4 + 2.5))
        for ax, (target, metric) in zip(fig.axes, shown, strict=True):
            assert ax.get_title().startswith(f"{target}: ")
            rows = front[(front.target == target) & (front.metric == metric)]
            bold = [t.get_text() for t in ax.texts if t.get_fontweight() == "bold"]
            assert sorted(bold) == sorted(rows.best) and len(ax.patches) == len(rows) == len(CELLS)
        assert {t.get_text() for t in fig.axes[1].texts if t.get_fontweight() == "bold"} == {"jeffrey"}
    finally:
        plt.close(fig)
