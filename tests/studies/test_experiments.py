"""The papers' network experiments: the TCDS threshold against a grid, and every table's provenance."""

from __future__ import annotations

import numpy as np
import pytest

from glu.bn import make_engine
from glu.fusion import fuse
from glu.studies.replication import fusion as experiments


@pytest.mark.parametrize(
    "evidence", [{"Size": "small", "Shape": "sphere", "ObjVel": "slow"}, {"Shape": "box"}]
)
def test_tap_threshold_by_bisection_agrees_with_a_fine_grid(zero_bn, evidence):
    t = experiments.tap_threshold(zero_bn, evidence)
    eng = make_engine(zero_bn)
    ev = evidence

    def tap_wins(x):
        post = fuse(eng, ["Action"], ev, [(1 - x) / 2, x, (1 - x) / 2], "product")["Action"]
        return post[1] > max(post[0], post[2])

    grid = np.linspace(0, 1, 3001)  # the first crossing on the grid; t itself is pinned to 1e-9 below
    wins = [tap_wins(x) for x in grid]
    if np.isnan(t):
        assert not any(wins)
        return
    first = grid[np.argmax(wins)]
    assert abs(first - t) <= (grid[1] - grid[0])
    assert not tap_wins(t - 1e-9) and tap_wins(t + 1e-9)


def test_tables_are_stamped_with_their_provenance(zero_bn, uniform_bn):
    for df in (
        experiments.effect_prediction(zero_bn),
        experiments.tap_thresholds(zero_bn),
        experiments.unseen_rows_comparison(zero_bn, uniform_bn),
    ):
        assert df.attrs["experiment"] and df.attrs["data_source"] == zero_bn.meta["data_source"]
        assert isinstance(df.attrs["parameters"], dict)
    sweep = experiments.soft_evidence_sweep(zero_bn, {"Shape": "sphere"}, n_points=5, rules=("jeffrey",))
    assert sweep.attrs["parameters"] == {"evidence": {"Shape": "sphere"}, "n_points": 5, "rules": ["jeffrey"]}


def _without(bn, value, actions):
    """``bn`` with P(ObjVel=value | Action=a, …) = 0 for the ``actions`` (their rows renormalised)."""
    from dataclasses import replace

    cpt = bn.cpts["ObjVel"].copy()
    v = bn.schema.values_of("ObjVel").index(value)
    for a in actions:
        i = bn.schema.values_of("Action").index(a)
        cpt[i, ..., v] = 0.0
        cpt[i] /= cpt[i].sum(axis=-1, keepdims=True)
    return replace(bn, cpts={**bn.cpts, "ObjVel": cpt})


def test_evidence_tap_cannot_have_or_nothing_can(zero_bn):
    """Objects that taps never leave still: tap never wins on a still object, whatever the HMMs say (nan);
    objects that no action leaves still: no row of the thresholds' table for them."""
    no_slow_tap = _without(zero_bn, "slow", ["tap"])
    eng = make_engine(no_slow_tap)
    assert eng.query(["Action"], {"ObjVel": "slow"})["Action"][1] == 0
    assert np.isnan(experiments.tap_threshold(no_slow_tap, {"ObjVel": "slow"}))
    table = experiments.tap_thresholds(_without(zero_bn, "slow", ["grasp", "tap", "touch"]))
    assert "slow" not in set(table.ObjVel) and len(table) == 2 * 3 * 2  # Shape × Size × {medium, fast}


def test_the_word_changes_under_both_evidences_and_the_sweeps_of_both_shapes(zero_bn):
    """Notebook 07's two Δp(w) tables, by the evidence's name; notebook 05's sweeps, by shape: each what the
    single call gives."""
    changes = experiments.word_probability_changes(zero_bn, threshold=0.05)
    assert list(changes) == ["text", "code"]
    for name, frame in changes.items():
        assert frame.equals(experiments.word_probability_change(zero_bn, name, threshold=0.05))
        assert frame.attrs["parameters"]["threshold"] == 0.05
    sweeps = experiments.soft_evidence_sweeps(zero_bn, ("box", "sphere"), n_points=5)
    assert list(sweeps) == ["box", "sphere"]
    for shape, sweep in sweeps.items():
        assert sweep.equals(experiments.soft_evidence_sweep(zero_bn, {"Shape": shape}, n_points=5))
        assert set(sweep["rule"]) == {"virtual", "jeffrey"}


def test_one_sampling_trial_drawn_again_and_the_trials_per_set(zero_bn):
    """sampling_example: the first trial of a set drawn again from its seed, scored as the trial scored it,
    beside every sentence of the grammar; trials_per_set counts each set's trials."""
    from glu.language import (
        all_scores,
        default_network,
        load_grammar,
        sample_sentences,
        score_sentences,
        word_probabilities,
    )
    from glu.studies.replication import verbal

    engine, grammar, net = make_engine(zero_bn), load_grammar(), default_network()
    sets = {k: verbal.PUBLISHED_LISTS[k] for k in ("fig7a", "fig7b")}
    trials = verbal.sampling_trials(engine, [3, 4], sets, n_samples=400, n=3, grammar=grammar)
    example = verbal.sampling_example(engine, trials, net, grammar, "fig7b")
    probs = word_probabilities(engine, sets["fig7b"])
    assert example.evidence == sets["fig7b"] and example.n_samples == 400 and example.score == "original"
    drawn = sample_sentences(grammar, 400, 3)
    np.testing.assert_array_equal(example.sample_scores, score_sentences(drawn, probs, "original"))
    np.testing.assert_array_equal(example.grammar_scores, all_scores(net, probs, "original"))
    first = trials[trials["figure"] == "fig7b"].iloc[0]
    assert (
        example.exact_score == first["exact_score"] == pytest.approx(example.grammar_scores.max(), rel=1e-12)
    )
    assert example.sample_scores.max() == pytest.approx(first["sample_score"])
    per_set = verbal.trials_per_set(trials)
    assert list(per_set.index) == ["fig7a", "fig7b"] and list(per_set["trials"]) == [2, 2]
    for key, row in per_set.iterrows():
        mine = trials[trials["figure"] == key]
        assert row["found_best"] == mine["found_best"].sum()
        assert row["median_rank"] == mine["sample_rank"].median()
