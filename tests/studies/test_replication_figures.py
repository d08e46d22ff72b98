"""The replication's figures on small made-up tables: what is drawn (the artists' data), checked by hand."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest

from glu.plots.style import rule_label


@pytest.fixture
def ax():
    fig, ax = plt.subplots()
    yield ax
    plt.close(fig)


def test_strategies_that_differ_get_their_own_bars_and_a_legend(ax):
    from glu.studies.replication.fusion_figures import plot_fusion_on_gestures

    segs = [("r1", 1, 50), ("r2", 3, 60)]
    rows = [
        {"recording": r, "start": a, "end": b, "strategy": st, "p": p, "ObjVel": "fast"}
        | {"hmm_top": "tap", "evidence": "Shape=sphere"}
        for (r, a, b), ps in zip(segs, [(0.2, 0.7), (0.4, 0.9)], strict=True)
        for st, p in zip(("virtual", "jeffrey"), ps, strict=True)
    ]
    plot_fusion_on_gestures(ax, pd.DataFrame(rows))
    heights = [[b.get_height() for b in c] for c in ax.containers]
    assert heights == [[0.2, 0.4], [0.7, 0.9]]
    assert [t.get_text() for t in ax.get_legend().get_texts()] == [
        rule_label("virtual"),
        rule_label("jeffrey"),
    ]
    assert ax.get_title() == "Shape=sphere"  # no note of strategies giving the same p


def test_a_grammar_whose_sentences_all_score_minus_infinity_draws_nothing(ax):
    from glu.studies.replication.verbal_figures import plot_sampling

    scores = np.full(5, -np.inf)
    assert plot_sampling(ax, scores, scores[:2], -np.inf) is ax
    assert not ax.patches and not ax.lines and ax.get_legend() is None


def test_a_word_change_under_other_evidence_is_drawn_beside(ax):
    """Δp(w) of another evidence that differs: half-width bars beside, hatched, labelled by its evidence."""
    from glu.studies.replication.network_figures import plot_word_change

    df = pd.DataFrame(
        {"word": ["ball", "rolls", "the"], "delta": [0.3, -0.2, 0.0], "shown": [True, True, False]}
    )
    df.attrs["parameters"] = {"evidence": {"Shape": "sphere"}}
    other = pd.DataFrame({"word": ["the", "ball", "rolls"], "delta": [0.0, 0.1, -0.25]})
    other.attrs["parameters"] = {"evidence": {"Shape": "sphere", "Color": "yellow"}}
    plot_word_change(ax, df, other)
    ours, theirs = ax.containers
    assert [b.get_height() for b in ours] == [0.3, -0.2] and [b.get_height() for b in theirs] == [0.1, -0.25]
    assert [b.get_x() + b.get_width() / 2 for b in theirs] == pytest.approx([0.2, 1.2])
    assert [b.get_width() for b in [*ours, *theirs]] == pytest.approx([0.4] * 4)
    assert theirs.get_label() == "Shape=sphere, Color=yellow" and theirs[0].get_hatch() == "//"


def test_edges_only_in_ours_or_only_in_the_reference_are_marked():
    """The network learned from 200 rows against the one learned from all of them: a filled red square for
    each edge only in ours, a hollow one for each only in the reference, counted by set difference."""
    from glu.bn import learn_bn
    from glu.data import load_experiments
    from glu.studies.replication.network_figures import plot_structure

    table = load_experiments("synthetic")
    ours, ref = learn_bn(table.iloc[:200]), learn_bn(table)
    aff = set(ours.schema.affordance_nodes)
    mine = {e for e in ours.edges() if e[0] in aff} - set(ref.edges())
    theirs = {e for e in ref.edges() if e[0] in aff} - set(ours.edges())
    assert mine and theirs
    fig, ax = plt.subplots()
    try:
        plot_structure(ax, ours, ref)
        filled = [c for c in ax.collections if len(c.get_facecolor())]
        hollow = [c for c in ax.collections if not len(c.get_facecolor())]
        assert (len(filled), len(hollow)) == (len(mine), len(theirs))
        assert f", {len(mine)} only in ours, {len(theirs)} only in theirs" in ax.get_title()
    finally:
        plt.close(fig)


def _effect_rows(shapes, rules, cases, values):
    """A made-up p_comb(ObjVel | Shape) table as effect_vs_soft_evidence writes it: every p distinct."""
    rows = [
        {"Shape": s, "rule": r, "case": c, "ObjVel": v}
        for s in shapes
        for r in rules
        for c in cases
        for v in values
    ]
    df = pd.DataFrame(rows)
    df["p"] = np.arange(1, len(df) + 1) / 100
    return df


def test_the_effect_under_each_rule_is_a_row_of_panels_one_per_shape():
    """Notebook 05's figure: a row per rule, a column per shape, each panel's stacked bars the table's p of
    its shape and rule (every value over every case), one legend, beside the last row's last panel."""
    from glu.studies.replication.network_figures import effect_vs_rules_figure

    shapes, rules = ("sphere", "box"), ("virtual", "jeffrey")
    cases, values = ("none", "[0 1 0]"), ("slow", "fast")
    df = _effect_rows(shapes, rules, cases, values)
    fig = effect_vs_rules_figure(df, rules)
    try:
        axes = fig.axes
        assert [ax.get_title() for ax in axes] == [f"{s}, {rule_label(r)}" for r in rules for s in shapes]
        for ax, (r, s) in zip(axes, [(r, s) for r in rules for s in shapes], strict=True):
            g = df[(df.Shape == s) & (df.rule == r)]
            expected = [g[(g.ObjVel == v) & (g.case == c)].p.item() for v in values for c in cases]
            assert [b.get_height() for b in ax.patches] == pytest.approx(expected)
        assert [ax.get_legend() is not None for ax in axes] == [False, False, False, True]
        assert axes[0].get_shared_x_axes().joined(axes[0], axes[3])
    finally:
        plt.close(fig)


def test_the_sweeps_are_panels_side_by_side_with_one_legend():
    """Notebook 05's sweeps: a panel per sweep in the order given, each drawing its own p per rule and value,
    the legend beside the last only."""
    from glu.studies.replication.fusion_figures import soft_sweep_figure

    t = np.linspace(0, 1, 5)
    sweeps = {}
    for k, shape in enumerate(("sphere", "box")):
        frames = [
            pd.DataFrame({"rule": r, "p_hmm_tap": t, "ObjVel": v, "p": (t + j + 3 * k) / 10})
            for r in ("virtual", "jeffrey")
            for j, v in enumerate(("slow", "fast"))
        ]
        sweeps[shape] = pd.concat(frames, ignore_index=True).assign(evidence=f"Shape={shape}")
    fig = soft_sweep_figure(sweeps)
    try:
        assert [ax.get_title() for ax in fig.axes] == ["Shape=sphere", "Shape=box"]
        for ax, sweep in zip(fig.axes, sweeps.values(), strict=True):
            drawn = [line.get_ydata() for line in ax.lines]
            wanted = [g.p.to_numpy() for _, g in sweep.groupby(["rule", "ObjVel"], sort=False)]
            assert len(drawn) == len(wanted) == 4
            for a, b in zip(drawn, wanted, strict=True):
                np.testing.assert_array_equal(a, b)
        assert [ax.get_legend() is not None for ax in fig.axes] == [False, True]
    finally:
        plt.close(fig)


def test_an_nbest_figure_is_titled_by_its_evidence_score_and_candidates():
    from glu.studies.replication.verbal_figures import nbest_figure

    nbest = pd.DataFrame({"sentence": ["the robot taps the ball", "the ball rolls"], "score": [-1.5, -2.25]})
    fig = nbest_figure(nbest, {"Color": "yellow", "Shape": "sphere"}, "original", "the samples")
    try:
        (ax,) = fig.axes
        assert ax.get_title(loc="right") == "Color=yellow, Shape=sphere (original score, the samples)"
        assert [t.get_text() for t in ax.get_yticklabels()] == [
            f"{k}. {s}" for k, s in enumerate(nbest.sentence, 1)
        ]
        assert list(ax.collections[0].get_offsets()[:, 0]) == [-1.5, -2.25]
    finally:
        plt.close(fig)


def test_a_sampling_figure_draws_the_example_it_is_given():
    """The grammar's scores and the sample's as histograms, the grammar's best and the sample's as lines,
    titled by the evidence and the sample's size."""
    from glu.studies.replication.verbal import SamplingExample
    from glu.studies.replication.verbal_figures import sampling_figure

    grammar = np.linspace(-4.0, -1.0, 50)
    sample = np.array([-3.0, -2.5, -2.0, -np.inf])
    example = SamplingExample({"ObjVel": "slow"}, grammar, sample, -1.0, 4, "original")
    fig = sampling_figure(example)
    try:
        (ax,) = fig.axes
        assert ax.get_title().split("\n")[0] == "ObjVel=slow: one sample of 4"
        assert [line.get_xdata()[0] for line in ax.lines] == [-1.0, -2.0]  # the grammar's best, the sample's
        assert "1 of the sample's (25 %)" in ax.get_title()  # the −∞ sentence, not drawn
    finally:
        plt.close(fig)


def test_the_segmentation_figure_is_a_row_per_recording_in_the_order_given():
    """Notebook 01's figure: one full-width row per recording, in the order given, each titled by its own
    recording and count, drawing its own hand features and activity and its own reference segments."""
    from glu.gestures.segmentation import RecordingSegmentation, Segment, segment_repetitions
    from glu.gestures.synthetic import synthesize_recording
    from glu.gestures.trajectories import repair
    from glu.studies.replication.gesture_figures import segmentation_figure

    segmentations = []
    for action, n in (("touch", 1), ("tap", 3)):
        g = synthesize_recording(action, n, seed=0)
        name = f"made-up {action}"
        (piece,) = repair(g.trajectory()).pieces
        seg = RecordingSegmentation(name, [segment_repetitions(piece, action, recording=name)])
        segmentations.append((seg, [Segment(a, b, action, name) for a, b in g.segments]))
    fig = segmentation_figure(segmentations)
    try:
        assert len(fig.axes) == 2 and tuple(fig.get_size_inches()) == pytest.approx((10, 4.6))
        counts = [len(seg.segments) for seg, _ in segmentations]
        assert counts == [1, 3]
        assert [ax.get_title() for ax in fig.axes] == ["made-up touch: 1 segment", "made-up tap: 3 segments"]
        for ax, (seg, reference) in zip(fig.axes, segmentations, strict=True):
            (piece,) = seg.pieces
            x, y, z, activity = ax.lines[:4]
            for line, values in zip((x, y, z), piece.trajectory.xyz.T, strict=True):
                np.testing.assert_array_equal(line.get_ydata(), values)
            np.testing.assert_array_equal(activity.get_ydata(), piece.activity)
            bars = [list(line.get_xdata()) for line in ax.lines if line.get_linewidth() == 3]
            assert bars == [[s.start, s.end] for s in reference]
    finally:
        plt.close(fig)


def test_the_accuracy_figure_puts_the_confusion_matrix_beside_the_noise_curve():
    """Notebook 02's accuracy figure: the confusion matrix's counts, titled by the folds and the accuracy,
    then the accuracy against noise (cm), overall and per action, from the tables given."""
    from glu.studies.replication.gesture_figures import accuracy_figure

    actions = ["grasp", "tap", "touch"]
    confusion = pd.DataFrame([[5, 1, 0], [0, 4, 2], [1, 0, 5]], index=actions, columns=actions)
    noise = pd.DataFrame(
        {
            "noise_m": [0.0, 0.02, 0.05],
            "accuracy": [0.9, 0.8, 0.5],
            "accuracy_grasp": [1.0, 0.7, 0.4],
            "accuracy_tap": [0.8, 0.9, 0.6],
        }
    )
    fig = accuracy_figure(confusion, 14 / 18, 4, noise)
    try:
        left, right = fig.axes
        assert left.get_title() == "4-fold CV, accuracy 0.778"
        np.testing.assert_array_equal(left.images[0].get_array(), confusion.to_numpy())
        assert [t.get_text() for t in left.texts] == [str(n) for n in confusion.to_numpy().flat]
        overall, grasp, tap = right.lines
        np.testing.assert_allclose(overall.get_xdata(), [0, 2, 5])
        for line, column in ((overall, "accuracy"), (grasp, "accuracy_grasp"), (tap, "accuracy_tap")):
            np.testing.assert_array_equal(line.get_ydata(), noise[column])
        assert [t.get_text() for t in right.get_legend().get_texts()][1:] == ["grasp", "tap"]
    finally:
        plt.close(fig)


def test_the_segment_scores_figure_draws_each_segments_per_frame_scores():
    """Notebook 02's scores under the original models: per model, one bar per segment, its log-likelihood
    divided by the segment's frames; the best model of each segment edged in black."""
    from glu.studies.replication.gesture_figures import segment_scores_figure

    scores = pd.DataFrame(
        {
            "recording": ["tap1_hand", "tap_notable_seated_1"],
            "start": [216, 121],
            "end": [351, 214],
            "n_frames": [136, 94],
            "loglik_grasp": [-680.0, -188.0],
            "loglik_tap": [-272.0, -470.0],
        }
    )
    fig = segment_scores_figure(scores)
    try:
        (ax,) = fig.axes
        assert ax.get_title().startswith("per-frame log-likelihood of each segment")
        assert [b.get_height() for b in ax.patches] == pytest.approx([-5.0, -2.0, -2.0, -5.0])
        black = [tuple(b.get_edgecolor()) == (0, 0, 0, 1) for b in ax.patches]
        assert black == [False, True, True, False]
        assert [t.get_text().split("\n")[-1] for t in ax.get_xticklabels()] == [
            "frames 216–351",
            "frames 121–214",
        ]
    finally:
        plt.close(fig)


def test_the_structure_figure_is_the_learned_parents_of_every_child():
    """Notebook 03's structure figure: a cell filled for each edge parent → child of the network given (rows:
    the nodes with parents, columns: the affordance nodes), titled by its edges and the reference's."""
    from glu.bn import learn_bn
    from glu.data import load_experiments
    from glu.studies.replication.network_figures import structure_figure

    table = load_experiments("synthetic")
    ours, ref = learn_bn(table.iloc[:200]), learn_bn(table)
    for reference in (None, ref):
        fig = structure_figure(ours, reference)
        try:
            (ax,) = fig.axes
            children = [t.get_text() for t in ax.get_yticklabels()]
            parents = [t.get_text() for t in ax.get_xticklabels()]
            assert parents == list(ours.schema.affordance_nodes)
            drawn = {
                (p, c)
                for i, c in enumerate(children)
                for j, p in enumerate(parents)
                if ax.images[0].get_array()[i, j]
            }
            assert drawn == {(p, c) for p, c in ours.edges() if p in parents}
            title = f"{len(ours.edges())} edges"
            if reference is not None:
                assert ax.get_title().startswith(f"{title}; the original: {len(ref.edges())}, ")
                assert set(children) >= {c for p, c in ref.edges()}
            else:
                assert ax.get_title() == title and not ax.collections
        finally:
            plt.close(fig)


def test_the_unseen_rows_figure_plots_each_experiments_numbers_zero_against_uniform():
    """Notebook 03's unseen-rows figure: per experiment, in order, its points at (all-zero rows, uniform
    rows); the diagonal; the title counting the numbers moved and naming the one moved most."""
    from glu.studies.replication.network_figures import unseen_rows_figure

    df = pd.DataFrame(
        {
            "experiment": ["effect prediction"] * 2 + ["word change Δp(w)"] * 3,
            "case": ["small sphere", "big box", "F, E", "F, E", "F, E"],
            "value": ["fast", "slow", "rolls", "ball", "the"],
            "p_zero": [0.8, 0.1, 0.3, -0.2, 0.0],
            "p_uniform": [0.8, 0.15, 0.1, -0.2, 0.0005],
        }
    )
    df["uniform_minus_zero"] = df.p_uniform - df.p_zero
    fig = unseen_rows_figure(df)
    try:
        (ax,) = fig.axes
        first, second = ax.collections
        np.testing.assert_array_equal(first.get_offsets(), df[["p_zero", "p_uniform"]].to_numpy()[:2])
        np.testing.assert_array_equal(second.get_offsets(), df[["p_zero", "p_uniform"]].to_numpy()[2:])
        (diagonal,) = ax.lines
        assert list(diagonal.get_xdata()) == list(diagonal.get_ydata()) == [-0.2, 1]
        assert ax.get_title() == (
            "uniform rows move 2 of 5 numbers by more than 0.001;\n"
            "the most: rolls (word change Δp(w), F, E), +0.300 → +0.100"
        )
    finally:
        plt.close(fig)


def _gesture_rows(n_segments, strategies=("hard", "virtual")):
    """A made-up fusion_on_gestures table: each segment's p of fast and slow under each strategy, all
    distinct, the strategies apart by more than SAME_P."""
    rows = [
        {"evidence": "Shape=sphere, Size=small", "recording": f"rec_{i}", "start": 10 * i, "end": 10 * i + 9}
        | {"hmm_top": "tap" if i % 2 else "touch", "strategy": st, "ObjVel": v, "p": p}
        for i in range(n_segments)
        for k, st in enumerate(strategies)
        for v, p in (("fast", (i + 1) / 10 + k / 100), ("slow", 0.05 + k / 100))
    ]
    return pd.DataFrame(rows)


def test_the_fusion_on_gestures_figure_widens_with_the_segments_and_draws_the_value_asked():
    """Notebook 04's figure: 1.3 inches per segment (6 at least); per strategy, a bar per segment whose
    height is that segment's p of the value asked (not another value's), each segment's HMM answer below."""
    from glu.studies.replication.fusion_figures import fusion_on_gestures_figure

    for n, width in ((3, 6.0), (5, 6.5)):
        df = _gesture_rows(n)
        fig = fusion_on_gestures_figure(df, value="fast")
        try:
            (ax,) = fig.axes
            assert fig.get_size_inches()[0] == pytest.approx(width)
            for bars, st in zip(ax.containers, ("hard", "virtual"), strict=True):
                wanted = df[(df.strategy == st) & (df.ObjVel == "fast")].p.to_list()
                assert [b.get_height() for b in bars] == pytest.approx(wanted)
            tops = [t.get_text().split("\n")[-1] for t in ax.get_xticklabels()]
            assert tops == [f"HMM: {'tap' if i % 2 else 'touch'}" for i in range(n)]
            assert ax.get_ylabel() == "$p_{comb}(ObjVel=fast)$"
            assert ax.get_title() == "Shape=sphere, Size=small"
        finally:
            plt.close(fig)


def test_the_tap_threshold_sweep_marks_the_threshold_it_is_given():
    """Notebook 06's sweep: p_comb of each action along p_HMM(tap), then a dotted line at the threshold
    and, at its top, "tap wins above" with the threshold to four decimals."""
    from glu.studies.replication.fusion_figures import tap_threshold_sweep_figure

    t = np.linspace(0, 1, 6)
    actions = ("grasp", "tap", "touch")
    sweep = pd.concat(
        [
            pd.DataFrame({"rule": "product", "p_hmm_tap": t, "Action": a, "p": (t + k) / 3})
            for k, a in enumerate(actions)
        ],
        ignore_index=True,
    ).assign(evidence="Size=small, Shape=sphere, ObjVel=slow")
    fig = tap_threshold_sweep_figure(sweep, 0.81234)
    try:
        (ax,) = fig.axes
        *curves, marker = ax.lines
        assert len(curves) == 3
        for line, a in zip(curves, actions, strict=True):
            np.testing.assert_array_equal(line.get_xdata(), t)
            np.testing.assert_array_equal(line.get_ydata(), sweep[sweep.Action == a].p)
        assert list(marker.get_xdata()) == [0.81234, 0.81234] and marker.get_linestyle() == ":"
        (note,) = [c for c in ax.texts if c.get_text().startswith("tap wins")]
        assert note.get_text() == "tap wins above 0.8123" and note.xy == (0.81234, 0.9)
        assert ax.get_title() == "Size=small, Shape=sphere, ObjVel=slow"
    finally:
        plt.close(fig)


def test_the_tap_thresholds_figure_draws_a_bar_per_object_and_effect():
    """Notebook 06's thresholds: a bar per row of the table, in its order, as long as its threshold (none
    where tap never wins), its value written right of the axes."""
    from glu.studies.replication.fusion_figures import tap_thresholds_figure

    thresholds = pd.DataFrame(
        {
            "Shape": ["sphere", "sphere", "box"],
            "Size": ["small", "big", "small"],
            "ObjVel": ["slow", "fast", "slow"],
            "p_bn_tap": [0.1, 0.8, 0.0],
            "threshold": [0.8123, 0.001, np.nan],
        }
    )
    fig = tap_thresholds_figure(thresholds)
    try:
        (ax,) = fig.axes
        assert [b.get_width() for b in ax.patches] == pytest.approx([0.8123, 0.001, 0.0])
        assert [b.get_y() + b.get_height() / 2 for b in ax.patches] == pytest.approx([0, 1, 2])
        assert [t.get_text() for t in ax.get_yticklabels()] == [
            "sphere, small, slow",
            "sphere, big, fast",
            "box, small, slow",
        ]
        assert [t.get_text() for t in ax.texts][:3] == ["0.812", "any > 0", "never"]
        assert list(ax.lines[0].get_xdata()) == pytest.approx([1 / 3, 1 / 3])
    finally:
        plt.close(fig)


def test_the_effect_prediction_figure_is_a_panel_per_case_in_order():
    """Notebook 07's Fig. 4: a panel per case of the table, in its order, each drawing that case's p (and the
    original model's marks) with the value written on each bar; the legend beside the last panel only."""
    from glu.studies.replication.network_figures import effect_prediction_figure

    cases, values = ["small sphere", "big box", "small box"], ["slow", "medium", "fast"]
    df = pd.DataFrame([{"case": c, "ObjVel": v} for c in cases for v in values])
    df["p"] = np.arange(1, 10) / 10
    df["p_original"] = df["p"] + 0.01
    for n in (2, 3):
        table = df[df.case.isin(cases[:n])]
        fig = effect_prediction_figure(table)
        try:
            assert [ax.get_title() for ax in fig.axes] == [f"tap on a {c}" for c in cases[:n]]
            for ax, c in zip(fig.axes, cases, strict=False):
                rows = table[table.case == c]
                assert [b.get_height() for b in ax.patches] == pytest.approx(rows.p.to_list())
                np.testing.assert_array_equal(ax.lines[0].get_ydata(), rows.p_original)
                assert [t.get_text() for t in ax.texts] == [f"{p:.3f}" for p in rows.p]
            assert [ax.get_legend() is not None for ax in fig.axes] == [False] * (n - 1) + [True]
        finally:
            plt.close(fig)


def test_the_word_change_figure_draws_the_shown_words_and_says_when_the_other_evidence_agrees():
    """Notebook 07's Fig. 5: the Δp(w) of the words shown, in order, full width; the other evidence's Δp(w),
    equal within SAME_DELTA, is not drawn but named in the title."""
    from glu.studies.replication.network_figures import word_change_figure

    df = pd.DataFrame(
        {
            "word": ["ball", "rolls", "the", "cube"],
            "delta": [0.3, -0.2, 0.001, 0.05],
            "shown": [True, True, False, True],
        }
    )
    df.attrs["parameters"] = {"evidence": {"Shape": "sphere"}}
    other = df.assign(delta=df.delta + 1e-12)
    other.attrs["parameters"] = {"evidence": {"Shape": "sphere", "Color": "yellow"}}
    fig = word_change_figure(df, other=other)
    try:
        (ax,) = fig.axes
        assert tuple(fig.get_size_inches()) == pytest.approx((7, 3.6))
        (bars,) = ax.containers
        assert [b.get_height() for b in bars] == [0.3, -0.2, 0.05]
        assert [b.get_width() for b in bars] == pytest.approx([0.8] * 3)
        assert [t.get_text() for t in ax.get_xticklabels()] == ["ball", "rolls", "cube"]
        assert "F, E = Shape=sphere (as the paper's text)" in ax.get_title()
        assert (
            "adding Color=yellow (as the original code) changes no Δp(w) by more than 1e-12" in ax.get_title()
        )
    finally:
        plt.close(fig)


def test_the_action_vs_soft_evidence_figure_groups_each_actions_bars_by_case():
    """Notebook 08's action figure: per action, in order, a bar per p_HMM row of that action's p, the original
    model's marks on them, and the threshold given in the title (none when it is not finite)."""
    from glu.studies.replication.network_figures import action_vs_soft_evidence_figure

    cases, actions = ["no action evidence", "[0.1 0.8 0.1]"], ["grasp", "tap", "touch"]
    df = pd.DataFrame([{"case": c, "Action": a} for c in cases for a in actions])
    df["p"] = np.arange(1, 7) / 21
    df["p_original"] = df["p"] + 0.01
    for threshold, suffix in ((0.81234, ": tap wins for $p_{HMM}(tap) > 0.8123$"), (np.nan, "")):
        fig = action_vs_soft_evidence_figure(df, threshold)
        try:
            (ax,) = fig.axes
            assert ax.get_title() == "action given soft evidence (product rule)" + suffix
            wanted = [df[(df.Action == a) & (df.case == c)].p.item() for a in actions for c in cases]
            assert [b.get_height() for b in ax.patches] == pytest.approx(wanted)
            for line, a in zip(ax.lines, actions, strict=True):
                np.testing.assert_array_equal(line.get_ydata(), df[df.Action == a].p_original)
            assert [t.get_text() for t in ax.get_xticklabels()] == ["none", "[0.1 0.8 0.1]"]
        finally:
            plt.close(fig)


def test_the_effect_vs_soft_evidence_figure_draws_one_rule_a_panel_per_shape():
    """Notebook 08's effect figure: a panel per shape, in order, each stacking only the rows of the rule asked
    (not the other rule's), one legend beside the last panel."""
    from glu.studies.replication.network_figures import effect_vs_soft_evidence_figure

    cases, values = ("none", "[0 1 0]"), ("slow", "fast")
    for shapes in (("sphere", "box"), ("sphere", "box", "cylinder")):
        df = _effect_rows(shapes, ("jeffrey", "virtual"), cases, values)
        fig = effect_vs_soft_evidence_figure(df, "virtual")
        try:
            assert [ax.get_title() for ax in fig.axes] == [f"{s}, {rule_label('virtual')}" for s in shapes]
            for ax, s in zip(fig.axes, shapes, strict=True):
                g = df[(df.Shape == s) & (df.rule == "virtual")]
                expected = [g[(g.ObjVel == v) & (g.case == c)].p.item() for v in values for c in cases]
                assert [b.get_height() for b in ax.patches] == pytest.approx(expected)
            assert [ax.get_legend() is not None for ax in fig.axes] == [False] * (len(shapes) - 1) + [True]
        finally:
            plt.close(fig)
