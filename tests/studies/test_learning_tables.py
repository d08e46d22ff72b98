"""The study's tables and saved runs (glu.studies.learning.study, tables, saved).

References: learners built to be equal to, or a fixed amount below, the true labels (so every replicate of
their gap is known), closed forms of the two-level bootstrap, counting, and a saved run read back equal.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from glu.bn import learn_bn, make_engine
from glu.data import load_experiments
from glu.errors import DataError
from glu.hmm import TrainingConfig
from glu.stats import interval, replicate_means, two_level_weights
from glu.studies.learning import online as ol
from glu.studies.learning import saved, tables
from glu.studies.learning import study as lc

SMALL = TrainingConfig(n_states=3, n_mix=1, n_iter=20, tol=1e-3)


@pytest.fixture(scope="module")
def engine():
    return make_engine(learn_bn(load_experiments("synthetic")))


def test_two_level_bootstrap_weights_and_means():
    rng = np.random.default_rng(0)
    W = two_level_weights(4, 10, 200, rng)
    assert W.shape == (201, 4, 10) and np.all(W[0] == 1)
    np.testing.assert_array_equal(W[1:].sum(axis=(1, 2)), 40)  # 4 seeds drawn, 10 units each
    values = rng.random((4, 10, 2))
    reps = replicate_means(values, W)
    np.testing.assert_allclose(reps[0], values.mean(axis=(0, 1)))
    b = 5
    np.testing.assert_allclose(reps[b], np.einsum("sj,sjk->k", W[b], values) / W[b].sum())


def test_two_level_intervals_see_the_spread_between_seeds():
    """Seeds that differ and episodes that agree within a seed: the interval is the seeds' bootstrap."""
    rng = np.random.default_rng(1)
    values = np.repeat(np.array([0.2, 0.4, 0.6, 0.8])[:, None], 50, axis=1)[..., None]
    reps = replicate_means(values, two_level_weights(4, 50, 4000, rng))
    lo, hi = interval(reps)
    # the mean of 4 seeds resampled: its replicates have variance σ²/4 with σ² the seeds' (biased) variance
    assert np.std(reps[1:, 0]) == pytest.approx(np.sqrt(values[:, 0, 0].var() / 4), rel=0.05)
    assert lo[0] < 0.4 and hi[0] > 0.6


SETTINGS = lc.StudySettings(
    episodes=20,
    seeds=tuple(range(10)),
    worlds=("easy",),
    ambiguities=("mixed",),
    words=(False,),
    schemes=("hard", "soft"),
    controls=("random",),
    baselines=("true",),
    supervised=(),
    budgets=(10, 20),
    bootstrap=400,
)


def _results(J: int = 40) -> list[lc.SeedResult]:
    """10 seeds of fake measurements: every learner wrong on 5 of 40 gestures in the even seeds; ``hard``
    like the true labels (so every replicate of its gap is 0); ``soft`` wrong on 10 more gestures of every
    seed (its gap is −0.25, and below −0.02 in every replicate); ``random`` also wrong on half the gestures
    after 10 episodes, like the true labels after 20."""
    learners = SETTINGS.learners()
    names = [lr[1] for lr in learners]
    out = []
    for s in SETTINGS.seeds:
        c = np.ones((2, len(learners), J), bool)
        c[:, :, 30:35] = s % 2 == 1
        c[:, names.index("soft"), :10] = False
        c[0, names.index("random"), ::2] = False
        out.append(
            lc.SeedResult(
                s,
                learners,
                np.array([10, 20]),
                c,
                [("easy", "mixed", False)],
                c[0, names.index("true")][None],
                np.array([[0.5, 0.1, 0.9, 0.4, 0.5]]),
                np.zeros(20),
            )
        )
    return out


def test_the_main_table_verdicts_on_known_gaps():
    rep = tables.replicates(_results(), SETTINGS)
    main = tables.budgets_table(rep, SETTINGS, "synthetic").set_index(["budget", "learner"])
    assert main.loc[(20, "hard"), "gap"] == 0 and main.loc[(20, "hard"), "gap_low90"] == 0
    # every replicate of the gap is 0: the TOST p-value is its floor 1 / (B + 1), equivalent after BH
    assert main.loc[(20, "hard"), "p_equivalent"] == pytest.approx(1 / 401)
    assert main.loc[(20, "hard"), "verdict"] == "equivalent"
    # a gap of −0.25 in every replicate: not equivalent (p = 1), a difference (p floor), worse
    assert main.loc[(20, "soft"), "gap"] == pytest.approx(-0.25)
    assert main.loc[(20, "soft"), "p_equivalent"] == 1.0 and main.loc[(20, "soft"), "verdict"] == "worse"
    assert main.loc[(20, "soft"), "vs_random_verdict"] == "worse"  # random labels are all right at 20
    assert main.loc[(10, "hard"), "vs_random_verdict"] == "better"  # and half wrong at 10
    assert main.loc[(20, "true"), "verdict"] == "" and np.isnan(main.loc[(20, "true"), "p_equivalent"])
    assert main.loc[(20, "network"), "verdict"] == "equivalent"
    claims = tables.claims_table(tables.budgets_table(rep, SETTINGS, "synthetic"), schemes=("hard", "soft"))
    row = claims.set_index(["claim", "budget"]).loc[("effects", 20)]
    assert row["matched"] == 1 and row["matched_where"] == "mixed: hard"
    assert row["random_matched"] == 1 and row["beats_random"] == 0
    row10 = claims.set_index(["claim", "budget"]).loc[("effects", 10)]
    assert row10["random_matched"] == 0 and row10["beats_random"] == 1
    lines = tables.claim_lines(claims, 0.02)
    assert (
        lines[0].startswith("Effects without words")
        and "a scheme matches them in 1 of 1 (mixed: hard)" in lines[0]
    )
    view = tables.main_table(tables.budgets_table(rep, SETTINGS, "synthetic"), words=False)
    assert list(view.columns) == ["10 episodes", "20 episodes"]
    assert view.loc[("easy", "mixed", "hard labels"), "20 episodes"].endswith("equivalent")


def test_curves_table_gaps_are_paired():
    rep = tables.replicates(_results(), SETTINGS)
    curves = tables.curves_table(rep, SETTINGS, "synthetic")
    soft = curves[curves.learner == "soft"].set_index("episodes")
    assert soft.loc[20, "accuracy"] == pytest.approx(1 - 0.5 * 5 / 40 - 10 / 40)
    assert soft.loc[20, "gap"] == pytest.approx(-0.25) and soft.loc[20, "gap_high"] < -0.02
    hard = curves[curves.learner == "hard"].set_index("episodes")
    assert hard.loc[20, "ci_low"] < hard.loc[20, "ci_high"]  # the accuracy varies over the replicates …
    assert hard.loc[20, "gap_low"] == hard.loc[20, "gap_high"] == 0  # … its paired gap does not
    assert set(curves.learner) == {"true", "hard", "soft", "random", "network"}


@pytest.mark.parametrize(
    ("bad", "message"),
    [
        ({"ambiguities": ("foggy",)}, "ambiguity"),
        ({"worlds": ("moon",)}, "world"),
        ({"schemes": ("guess",)}, "learner"),
        ({"baselines": ("unsupervised",)}, "true"),
        ({"margin": 0}, "margin"),
        ({"episodes": 5}, "episodes=5: a whole number from 10 to 1,000,000"),
        ({"seeds": ()}, "seeds \\[\\]: give at least one, each once"),
        ({"seeds": (1, 1)}, "seeds \\[1, 1\\]: give at least one, each once"),
        ({"supervised": (0,)}, "supervised=\\[0\\]: labels per action, whole numbers ≥ 1"),
        ({"supervised": (True,)}, "supervised=\\[True\\]"),
        ({"words": ()}, "words=\\[\\]: True, False or both"),
        ({"words": (1,)}, "words=\\[1\\]: True, False or both"),
        ({"test_per_action": 0}, "test_per_action=0: a whole number ≥ 1"),
        ({"bootstrap": -1}, "bootstrap=-1: a whole number of replicates"),
        ({"budgets": ()}, "budgets=\\[\\]: episodes, whole numbers ≥ 1"),
        ({"budgets": (100, 0)}, "budgets=\\[100, 0\\]"),
    ],
)
def test_study_settings_are_checked(bad, message):
    with pytest.raises(DataError, match=message):
        lc.StudySettings(**bad)


def test_study_settings_defaults():
    s = lc.StudySettings(episodes=300, budgets=(100, 1000))
    assert s.checkpoints == (10, 20, 50, 100, 200, 300) and s.main_budgets == (100,)
    assert lc.StudySettings(episodes=30, budgets=(100,)).main_budgets == (30,)


@pytest.fixture(scope="module")
def small_run(engine):
    settings = lc.StudySettings(
        episodes=20,
        seeds=(0, 1),
        ambiguities=("mixed", "still"),
        test_per_action=3,
        bootstrap=30,
        budgets=(20,),
        online=ol.OnlineSettings(config=SMALL, cluster_episodes=9),
    )
    return settings, lc.learning_study(engine, settings)


def test_the_study_runs_end_to_end(small_run):
    settings, results = small_run
    rep = tables.replicates(results, settings)
    curves = tables.curves_table(rep, settings, "synthetic")
    expected = {
        "true",
        "unsupervised",
        "supervised_1",
        "supervised_5",
        "network",
        "random",
        "clustering",
        "em",
    }
    assert set(curves.learner) == expected | {"hard", "soft", "confident", "iterative"}
    assert set(curves.world) == {"easy", "hard"}
    assert curves.attrs["experiment"] == "learning_curves" and curves["seeds"].iloc[0] == 2
    assert curves["accuracy"].between(0, 1).all()
    labels = tables.labels_table(results, settings)
    easy = labels[labels.world == "easy"]
    still = easy[(easy.ambiguity == "still") & ~easy.words.astype(bool)].iloc[0]
    mixed = easy[(easy.ambiguity == "mixed") & easy.words.astype(bool)].iloc[0]
    assert still.label_accuracy < mixed.label_accuracy
    assert set(lc.update_times(results)) == {"median", "p95", "max"}


def test_a_saved_run_reads_back_and_is_checked(engine, small_run, tmp_path):
    settings, results = small_run
    saved.save_study(tmp_path, results, settings, "synthetic data (seed 0, 1270 experiments)", "glu test")
    stored, back, meta = saved.load_study(tmp_path)
    assert stored == settings and meta["made_by"]["command"] == "glu test"
    for a, b in zip(results, back, strict=True):
        np.testing.assert_array_equal(a.correct, b.correct)
        np.testing.assert_array_equal(a.network_correct, b.network_correct)
        np.testing.assert_allclose(a.labels, b.labels)
        assert a.learners == b.learners and a.groups == b.groups
    fewer = lc.StudySettings(**{**settings.__dict__, "seeds": (1,), "ambiguities": ("still",)})
    source_meta = ("synthetic data (seed 0, 1270 experiments)", meta)
    chosen = saved.select(back, stored, fewer, "synthetic data (seed 0, 1270 experiments)", meta)
    k = results[1].learners.index(("hard", "iterative", "still", True))
    j = chosen[0].learners.index(("hard", "iterative", "still", True))
    np.testing.assert_array_equal(chosen[0].correct[:, j], results[1].correct[:, k])
    with pytest.raises(DataError, match="made from"):
        saved.select(back, stored, fewer, "real data: elsewhere", meta)
    more = lc.StudySettings(**{**settings.__dict__, "seeds": (0, 5)})
    with pytest.raises(DataError, match="lacks seed 5.*glu learning-curves"):
        saved.select(back, stored, more, "synthetic data (seed 0, 1270 experiments)", meta)
    only_still = lc.StudySettings(**{**fewer.__dict__, "seeds": (0, 1)})  # a saved run of 'still' alone
    baselines = lc.StudySettings(**{**settings.__dict__, "schemes": (), "controls": ()})
    with pytest.raises(DataError, match=r"lacks group \('easy', 'mixed', False\).*glu learning-curves"):
        saved.select(
            saved.select(back, stored, only_still, *source_meta), only_still, baselines, *source_meta
        )
    with pytest.raises(DataError, match="no saved run"):
        saved.load_study(tmp_path / "nowhere")
    other = lc.StudySettings(**{**settings.__dict__, "test_per_action": 4})
    with pytest.raises(DataError, match="the saved run has other test_per_action than asked: run `glu"):
        saved.select(back, stored, other, *source_meta)
    study_file = tmp_path / saved.STUDY_FILE
    study_file.write_text(study_file.read_text().replace('"format": 1', '"format": 0'))
    with pytest.raises(DataError, match="saved in format 0, glu reads 1; run it again"):
        saved.load_study(tmp_path)


def test_a_rewrite_of_a_saved_run_cut_short_is_refused_never_mixed(tmp_path):
    """A saved run rewritten with other measurements, the disk full when its study file is written: the
    folder is refused in one line, never read as the new measurements under the old study file; a file of
    the user's in the folder survives, and a complete write is read whole."""
    from cut_short import cut_short, old_or_refused

    old, new = _results(), [r._replace(correct=~r.correct) for r in _results()]
    (tmp_path / "notes.txt").write_text("mine\n")
    saved.save_study(tmp_path, old, SETTINGS, "synthetic", "glu test")
    with cut_short(saved, "atomic_write_json", at=1, error=OSError):
        saved.save_study(tmp_path, new, SETTINGS, "synthetic", "glu test")

    def is_old(loaded) -> bool:
        return all((a.correct == b.correct).all() for a, b in zip(loaded[1], old, strict=True))

    refusal = old_or_refused(lambda: saved.load_study(tmp_path), is_old)
    assert (
        refusal is not None
        and "no saved run of learning from effects (learning_study.json missing)" in refusal
    )
    assert (tmp_path / "notes.txt").read_text() == "mine\n"
    saved.save_study(tmp_path, new, SETTINGS, "synthetic", "glu test")
    assert not is_old(saved.load_study(tmp_path)) and (tmp_path / "notes.txt").read_text() == "mine\n"


def test_a_run_its_check_run_and_its_tables_are_one_set(tmp_path):
    """save_study with the check run and the tables: all written, the study file last; cut short at the
    run's own measurements (after the check run was written), the run is refused, never vouched for by a
    check run of another computation; the other files of the folder stay."""
    from cut_short import cut_short, old_or_refused

    small = saved.check_settings(SETTINGS)
    check = [r for r in _results() if r.seed in small.seeds]
    frames = {"learning_curves": pd.DataFrame({"episodes": [10, 20]})}
    (tmp_path / "notes.txt").write_text("mine\n")
    saved.save_study(tmp_path, _results(), SETTINGS, "synthetic", "old", check=(check, small), tables=frames)
    assert saved.load_study(tmp_path / saved.CHECK_FOLDER)[0] == small
    assert (tmp_path / "learning_curves.csv").read_text() == "episodes\n10\n20\n"
    with cut_short(saved, "atomic_write_bytes", at=2, error=KeyboardInterrupt):  # the check's, then the run's
        saved.save_study(
            tmp_path, _results(), SETTINGS, "synthetic", "new", check=(check, small), tables=frames
        )

    def commands() -> tuple[str, str]:
        return tuple(saved.load_study(f)[2]["made_by"]["command"] for f in (tmp_path, tmp_path / "check"))

    refusal = old_or_refused(commands, lambda c: c == ("old", "old"))
    assert refusal is not None and "learning_study.json missing" in refusal
    assert saved.load_study(tmp_path / saved.CHECK_FOLDER)[2]["made_by"]["command"] == "new"
    assert (tmp_path / "notes.txt").read_text() == "mine\n"


def test_an_installed_glu_has_no_shipped_runs(monkeypatch):
    monkeypatch.setattr("glu.saved.roots", lambda notebook: [])
    with pytest.raises(DataError, match="in a source checkout of glu \\(sweeps/\\); make one with `glu"):
        saved.default_folder(True)


def test_a_saved_run_carries_a_check_run_that_this_code_recomputes(engine, small_run, tmp_path):
    """The check run is the first seed, the first budget, mixed objects without words, every other setting
    the long run's; recomputed here it recognises the same held-out gestures at every checkpoint."""
    settings, _ = small_run
    longer = replace(settings, episodes=30, budgets=(20, 30))
    small = saved.check_settings(longer)
    assert (small.seeds, small.episodes, small.ambiguities, small.words) == ((0,), 20, ("mixed",), (False,))
    assert (small.worlds, small.online, small.test_per_action) == (
        longer.worlds,
        longer.online,
        longer.test_per_action,
    )
    check = lc.learning_study(engine, small)
    saved.save_study(tmp_path / saved.CHECK_FOLDER, check, small, "synthetic", "glu learning-curves (test)")
    out = saved.check_against(engine, tmp_path, [0])
    # 2 worlds × (2 baselines + 2 supervised + 7 learners of mixed without words) × checkpoints 10, 20
    # × 9 held-out gestures
    assert out == {"seeds": [0], "episodes": 20, "learners": 22, "decisions": 2 * 11 * 2 * 9, "differ": 0}
    with pytest.raises(DataError, match=r"holds seeds \[0\], not \[3\]"):
        saved.check_against(engine, tmp_path, [3])
    flipped = [r._replace(correct=~r.correct) for r in check]
    saved.save_study(tmp_path / saved.CHECK_FOLDER, flipped, small, "synthetic", "glu learning-curves (test)")
    with pytest.raises(DataError, match="not what this code computes.*glu learning-curves \\(test\\)"):
        saved.check_against(engine, tmp_path, [0])
    reordered = [r._replace(learners=r.learners[::-1]) for r in check]
    saved.save_study(
        tmp_path / saved.CHECK_FOLDER, reordered, small, "synthetic", "glu learning-curves (test)"
    )
    with pytest.raises(DataError, match="other learners or checkpoints than this code makes; run `glu"):
        saved.check_against(engine, tmp_path, [0])


def test_the_shipped_runs_match_the_notebook_defaults():
    """The runs glu ships cover what notebook 12 asks by default (its parameters cell)."""
    from glu.run.parameters import read_spec
    from glu.run.reproduce import list_notebooks

    nb = next(p for p in list_notebooks() if p.stem == "12_learning_from_effects")
    spec = {k: p.default for k, p in read_spec(nb).items()}
    wanted = lc.settings_from_parameters(spec)  # as the notebook makes them
    for real, source in ((True, None), (False, "synthetic data (seed 0, 1270 experiments)")):
        folder = saved.default_folder(real)
        stored, results, meta = saved.load_study(folder)
        saved.select(results, stored, wanted, source or meta["data_source"], meta)
        assert pd.notna(meta["made_by"]["date"])


@pytest.mark.slow
def test_units_run_on_a_local_dask_cluster_as_here():
    """``workers=1``: the tasks run on a LocalCluster's worker; results in the units' order, progress once
    per unit (``max`` stands for a task: it pickles by name and takes (engine, unit, settings))."""
    units = [3, -1, 5, 0]
    calls = []
    out = lc.run_units(max, 0, 1, units, 1, None, calls.append)
    assert out == [max(0, u, 1) for u in units] == [3, 1, 5, 1]
    assert sorted(calls) == sorted(units)


def test_a_learner_missing_at_an_ambiguity_draws_no_curve():
    """``hard`` exists in the world, but only for another ambiguity: its curve is left out; ``true`` (the
    same for every ambiguity) is drawn."""
    import matplotlib.pyplot as plt

    from glu.studies.learning.figures import plot_learning_curves

    rows = [
        {"world": "easy", "learner": lr, "ambiguity": amb, "words": False, "episodes": e, "accuracy": a}
        for lr, amb in (("true", "mixed"), ("hard", "still"))
        for e, a in ((10, 0.4), (100, 0.8))
    ]
    curves = pd.DataFrame(rows).assign(ci_low=lambda d: d.accuracy - 0.1, ci_high=lambda d: d.accuracy + 0.1)
    fig, ax = plt.subplots()
    try:
        plot_learning_curves(ax, curves, "easy", "mixed", False, learners=("true", "hard"))
        drawn = [line for line in ax.lines if len(line.get_xdata()) == 2 and line.get_ydata()[0] != 1 / 3]
        assert [list(line.get_ydata()) for line in drawn] == [[0.4, 0.8]]
    finally:
        plt.close(fig)


def _by_field(p):
    """The settings as notebook 12 built them field by field from its parameters, before it made them in one
    call (study.settings_from_parameters)."""
    return lc.StudySettings(
        episodes=max(p["budgets"]),
        seeds=tuple(p["seeds"]),
        worlds=tuple(p["worlds"]),
        ambiguities=tuple(p["ambiguities"]),
        test_per_action=p["test_per_action"],
        budgets=tuple(p["budgets"]),
        margin=p["margin"],
        bootstrap=p["bootstrap"],
    )


def test_notebook_12s_parameters_cell_makes_its_settings_in_one_call():
    """The notebook's own parameters (its cell's defaults, and its quick run's), other names of its
    namespace beside them, give the settings it built field by field."""
    from glu.paths import PROJECT_ROOT
    from glu.run.manifest import read_manifest
    from glu.run.parameters import read_spec

    path = PROJECT_ROOT / "notebooks" / "12_learning_from_effects.py"
    spec = {k: p.default for k, p in read_spec(path).items()}
    for params in (spec, {**spec, **read_manifest(path).quick}):
        made = lc.settings_from_parameters({**params, "out": object(), "episodes": 5})
        assert made == _by_field(params) and made.episodes == max(params["budgets"])
    assert lc.settings_from_parameters({}) == lc.StudySettings()


@pytest.mark.parametrize(
    ("bad", "message"),
    [
        ({"seeds": [0, "1"]}, r"seeds=\(0, '1'\): a list of whole numbers ≥ 0"),
        ({"seeds": "0,1"}, r"seeds='0,1': a list of whole numbers ≥ 0"),
        ({"worlds": ["easy", "moon"]}, r"unknown world \['moon'\]; allowed: easy, hard"),
        ({"test_per_action": "30"}, r"test_per_action='30': a whole number ≥ 1"),
        ({"margin": 2}, r"margin=2: the equivalence margin, an accuracy in \(0, 1\)"),
        ({"budgets": []}, r"budgets=\[\]: episodes, whole numbers ≥ 1"),
        ({"budgets": [100, "1000"]}, r"budgets=\[100, '1000'\]: episodes, whole numbers ≥ 1"),
    ],
)
def test_an_unknown_or_ill_typed_parameter_of_notebook_12_is_refused_in_one_line(bad, message):
    with pytest.raises(DataError, match=f"^{message}") as err:
        lc.settings_from_parameters(bad)
    assert "\n" not in str(err.value)


class _Run:
    """What learned_anticipation_figure reads of an anticipation run: its curves and predictions."""

    def __init__(self, case, hmms, shift):
        frames = np.arange(1, 11)
        self._curves = pd.DataFrame(
            [
                {"frame": f, "t": f, "seconds": f / 30, "action": a, "loglik_per_frame": -f - k - shift,
                 "p_hmm": (k + 1) / 6, "case": case, "models": hmms}
                for f in frames
                for k, a in enumerate(("grasp", "tap", "touch"))
            ]
        )  # fmt: skip
        ps = (0.2, 0.3 + shift / 100, 0.5 - shift / 100)
        self._predictions = pd.DataFrame(
            [
                {"frame": t, "t": t, "node": "ObjVel", "value": v, "p": p}
                for t in (5, 10)
                for v, p in zip(("slow", "medium", "fast"), ps, strict=True)
            ]
        )

    def curves(self):
        return self._curves

    def predictions(self):
        return self._predictions


def test_the_learned_anticipation_figure_draws_one_learners_cases():
    """A column per case in the order of the TCDS cases, drawing the named learner's runs only: the top
    panel each action's per-frame log-likelihood, the bottom one p_comb(ObjVel) at each update."""
    import matplotlib.pyplot as plt

    from glu.studies.anticipation.experiment import CASES
    from glu.studies.learning.figures import learned_anticipation_figure

    runs = {
        (h, c): _Run(c, h, shift)
        for h, shift in (("true labels", 7), ("soft labels", 0))
        for c in ("box", "sphere")
    }
    fig = learned_anticipation_figure(runs, "soft labels")
    try:
        top, bottom = fig.axes[:2], fig.axes[2:4]
        assert [ax.get_title() for ax in top] == [
            f"{c.description} — HMMs: soft labels" for c in CASES.values()
        ]
        for t, b, case in zip(top, bottom, CASES, strict=True):
            run = runs["soft labels", case]
            for line, (_, g) in zip(t.lines, run.curves().groupby("action", sort=False), strict=True):
                np.testing.assert_array_equal(line.get_ydata(), g.loglik_per_frame)
            p = run.predictions()
            want = [
                p[(p.value == v) & (p.t == t_)].p.item() for v in ("slow", "medium", "fast") for t_ in (5, 10)
            ]
            assert [r.get_height() for r in b.patches] == pytest.approx(want)
        assert fig.axes[0].get_shared_x_axes().joined(fig.axes[0], fig.axes[2])
    finally:
        plt.close(fig)


def test_the_intervals_line_names_the_bootstrap_of_the_settings():
    s = lc.StudySettings(seeds=(0, 1, 2), test_per_action=4, bootstrap=1500)
    assert tables.intervals_line(s) == (
        "Intervals: 95% two-level bootstrap (1,500 replicates over 3 seeds and 12 held-out gestures each); "
        "equivalence reads the 90% interval."
    )


def test_the_provenance_line_names_what_it_is_about():
    """Budgets and the real person's draws each get their own sentence, computed here or read from disk."""
    assert saved.provenance_line({"folder": None}) == "Every budget was computed here."
    assert (
        saved.provenance_line({"folder": None}, "real-person draws")
        == "Every real-person draw was computed here."
    )
    made = {"command": "glu learning-curves --part person", "date": "2026-11-29 14:00 UTC", "glu": "0.1.0"}
    where = {"folder": "sweeps/12/real", "made_by": made, "check": None}
    assert saved.provenance_line(where, "real-person draws") == (
        "The real-person draws come from sweeps/12/real, made by `glu learning-curves --part person` on "
        "2026-11-29 14:00 UTC (glu 0.1.0)."
    )
    assert saved.provenance_line(where).startswith("The budgets come from sweeps/12/real, made by")
