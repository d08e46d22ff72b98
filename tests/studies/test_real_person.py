"""The real person (glu.studies.learning.real_person): a generator fitted to a person's repetitions, the
leave-one-segment-out loop, the crossed bootstrap.

References: repetitions whose resampled paths the fit recovers exactly (so its draws have the repetitions'
own mean and covariance in closed form), brute-force resampling, counting.
"""

from __future__ import annotations

import numpy as np
import pytest

from glu.bn import learn_bn, make_engine
from glu.data import load_experiments
from glu.errors import DataError
from glu.gestures.corpus import synthetic_corpus
from glu.hmm import TrainingConfig
from glu.studies.learning import online as ol
from glu.studies.learning import real_person as rp
from glu.studies.learning.self_supervised import resampled


def _knotted(rng, n_rep=4, knots=5, frames=41):
    """Repetitions linear between ``knots`` points at frames 0, 10, …, 40: the fit's ``knots``-point paths
    are them exactly."""
    out = []
    base = rng.normal(size=(knots, 3))
    for _ in range(n_rep):
        k = base + 0.3 * rng.normal(size=(knots, 3))
        t = np.linspace(0, 1, knots)
        u = np.linspace(0, 1, frames)
        out.append(np.stack([np.interp(u, t, k[:, d]) for d in range(3)], axis=1))
    return out


def test_the_fitted_generator_draws_with_the_repetitions_mean_and_covariance():
    """A draw is the mean plus a standard normal combination of the deviations over √(n − 1): its
    covariance is the repetitions' sample covariance (closed form), its jitter 0 for exact paths."""
    rng = np.random.default_rng(0)
    reps = _knotted(rng)
    gen = rp.fit_person([("tap", x) for x in reps], ["tap"], points=5, min_log_sd=1e-9)
    np.testing.assert_allclose(gen.jitter, 0, atol=1e-12)
    assert gen.log_frames[0, 0] == pytest.approx(np.log(41)) and gen.log_frames[0, 1] == 1e-9
    draws = rp.draw_person(gen, np.zeros(6000, int), np.random.default_rng(1))
    assert {len(x) for x in draws} == {41}
    paths = resampled(draws, 5)
    ref = resampled(reps, 5)
    np.testing.assert_allclose(paths.mean(axis=0), ref.mean(axis=0), atol=0.03)
    np.testing.assert_allclose(np.cov(paths.T), np.cov(ref.T), atol=0.03)


def test_one_repetition_is_drawn_as_it_is_and_none_is_refused():
    rng = np.random.default_rng(2)
    (x,) = _knotted(rng, n_rep=1)
    gen = rp.fit_person([("grasp", x)], ["grasp"], points=5, min_log_sd=1e-9)
    (y,) = rp.draw_person(gen, np.zeros(1, int), rng)
    np.testing.assert_allclose(y, x, atol=1e-9)
    with pytest.raises(DataError, match="no repetition of 'tap'"):
        rp.fit_person([("grasp", x)], ["grasp", "tap"])


def test_the_crossed_bootstrap_by_brute_force():
    values = np.random.default_rng(3).random((6, 5, 2))
    reps = rp._crossed(values, 20, np.random.default_rng(4))
    np.testing.assert_allclose(reps[0], values.mean(axis=(0, 1)))
    rng = np.random.default_rng(4)  # the same draws: the draws' counts first, then the segments'
    v = rng.multinomial(6, np.full(6, 1 / 6), size=20)
    w = rng.multinomial(5, np.full(5, 1 / 5), size=20)
    for b in (0, 7, 19):
        picked = [values[r, s] for r in range(6) for s in range(5) for _ in range(v[b, r] * w[b, s])]
        np.testing.assert_allclose(reps[b + 1], np.mean(picked, axis=0))


@pytest.fixture(scope="module")
def engine():
    return make_engine(learn_bn(load_experiments("synthetic")))


@pytest.fixture(scope="module")
def small_study(engine):
    corpus = synthetic_corpus(3, seed=4)  # 3 repetitions of each action
    small = ol.OnlineSettings(config=TrainingConfig(n_states=3, n_mix=1, n_iter=10), cluster_episodes=9)
    settings = rp.RealPersonSettings(
        draws=(0,), episodes=15, generator_episodes=15, online=small, bootstrap=50
    )
    return corpus, settings, rp.real_person_study(engine, corpus, settings, data_source="synthetic")


def test_the_study_on_a_small_corpus(engine, small_study):
    corpus, settings, rows = small_study
    actions = engine.bn.schema.values_of("Action")
    n = sum(s.action in actions for s in corpus)
    fitted = rows[rows.study == "fitted"]
    assert len(fitted) == n * (len(rp.LEARNERS) + 1)
    assert set(rows[rows.study == "generator"].features) == {"raw", "centred"}
    tap = rows[rows.learner == "always_tap"]
    assert (tap.correct == (tap.action == "tap")).all()
    summary = rp.real_person_summary(rows, 50)
    s = summary.set_index(["study", "features", "learner", "words"])
    taps = sum(x.action == "tap" for x in corpus) / n
    assert s.loc[("fitted", "centred", "always_tap", False), "accuracy"] == pytest.approx(taps)
    assert s.loc[("fitted", "centred", "true", False), "gap"] == 0
    assert summary["accuracy"].between(0, 1).all() and set(summary["segments"]) == {n}
    lines = rp.real_person_lines(summary)
    assert len(lines) == 3 and "always answering tap" in lines[0]
    with pytest.raises(DataError, match="two repetitions"):
        rp.real_person_study(engine, [c for c in corpus if c.action != "grasp"], settings)


@pytest.mark.parametrize(
    ("bad", "message"),
    [
        ({"draws": ()}, "draws \\[\\]: give at least one, each once"),
        ({"draws": (0, 0)}, "draws \\[0, 0\\]: give at least one, each once"),
        ({"episodes": 9}, "episodes=9: a whole number from 10 to 1,000,000"),
        ({"generator_episodes": 2_000_000}, "generator_episodes=2000000: a whole number from 10"),
        ({"ambiguity": "foggy"}, "unknown ambiguity 'foggy'; allowed: "),
        ({"points": 3}, "points=3: a whole number from 4 to 200"),
    ],
)
def test_real_person_settings_are_checked(bad, message):
    with pytest.raises(DataError, match=message):
        rp.RealPersonSettings(**bad)


def test_a_learner_without_any_model_answers_none():
    from types import SimpleNamespace

    run = SimpleNamespace(exists=np.array([[True, True, True], [False, False, False]]))
    assert rp._predict(run, 1, [np.zeros((5, 3))] * 2) == [None, None]


def test_a_rewrite_of_the_saved_study_cut_short_is_refused_never_mixed(tmp_path):
    """The real-person study's rows rewritten, the disk full when their provenance is written (or the run
    interrupted while their summary is): the folder is refused in one line, never read as the new rows under
    the old provenance; a file of the user's in the folder survives, and a complete write is read whole."""
    import pandas as pd
    from cut_short import cut_short, old_or_refused

    from glu.studies.learning import saved

    settings = rp.RealPersonSettings(draws=(0,))
    old = pd.DataFrame({"draw": [0, 0], "predicted": ["tap", None], "correct": [True, False]})
    new = old.assign(correct=~old["correct"])
    (tmp_path / "notes.txt").write_text("mine\n")
    saved.save_real_person(tmp_path, old, settings, "synthetic", "old")
    with cut_short(saved, "atomic_write_json", at=1, error=OSError):
        saved.save_real_person(tmp_path, new, settings, "synthetic", "new")

    def is_old(loaded) -> bool:
        rows, meta = loaded
        return rows["correct"].tolist() == [True, False] and meta["made_by"]["command"] == "old"

    refusal = old_or_refused(lambda: saved.load_real_person(tmp_path, "synthetic"), is_old)
    assert refusal is not None and "no saved real-person study (learning_real_person.json missing)" in refusal
    assert (tmp_path / "notes.txt").read_text() == "mine\n"
    summary = pd.DataFrame({"learner": ["hard"], "accuracy": [0.5]})
    saved.save_real_person(tmp_path, new, settings, "synthetic", "new", summary)
    assert (tmp_path / saved.PERSON_SUMMARY_FILE).read_text() == "learner,accuracy\nhard,0.5\n"
    with cut_short(saved, "atomic_write_text", at=1):  # the summary, after the rows
        saved.save_real_person(tmp_path, old, settings, "synthetic", "old", summary)
    assert old_or_refused(lambda: saved.load_real_person(tmp_path, "synthetic"), lambda _: False)
    saved.save_real_person(tmp_path, new, settings, "synthetic", "new", summary)
    rows, meta = saved.load_real_person(tmp_path, "synthetic")
    assert rows["correct"].tolist() == [False, True] and meta["made_by"]["command"] == "new"
    assert (tmp_path / "notes.txt").read_text() == "mine\n"


@pytest.mark.slow
def test_the_saved_study_reads_back_and_is_checked(engine, small_study, tmp_path, monkeypatch):
    """Saved rows read back equal (the same bytes when saved again); a folder of other data or other
    settings, or an unreadable one, is one error; ``saved="none"`` runs the study on the standing segments."""
    import gzip

    import pandas as pd

    from glu.studies.learning import saved

    corpus, settings, rows = small_study
    saved.save_real_person(tmp_path, rows, settings, "synthetic", "glu test")
    first = (tmp_path / saved.PERSON_FILE).read_bytes()
    saved.save_real_person(tmp_path, rows, settings, "synthetic", "glu test")
    assert (tmp_path / saved.PERSON_FILE).read_bytes() == first
    assert gzip.decompress(first).decode() == rows.to_csv(index=False)
    back, where = saved.real_person_rows(engine, None, settings, tmp_path, "synthetic")
    pd.testing.assert_frame_equal(back, rows, check_dtype=False)
    assert where == {"folder": str(tmp_path), "made_by": where["made_by"], "check": None}
    assert where["made_by"]["command"] == "glu test"
    with pytest.raises(DataError, match="made from 'synthetic', not 'real'"):
        saved.real_person_rows(engine, None, settings, tmp_path, "real")
    with pytest.raises(DataError, match="other settings than asked"):
        saved.real_person_rows(engine, None, rp.RealPersonSettings(draws=(1,)), tmp_path, "synthetic")
    (tmp_path / saved.PERSON_STUDY_FILE).write_text("{", encoding="utf-8")
    with pytest.raises(DataError, match="not a readable saved real-person study"):
        saved.load_real_person(tmp_path, "synthetic")

    def standing(source, include_test=True):
        assert source == "SOURCE" and include_test is False  # the test recordings stay out
        return corpus

    monkeypatch.setattr("glu.gestures.corpus.gesture_sequences", standing)
    here, where = saved.real_person_rows(engine, "SOURCE", settings, saved.HERE, "synthetic")
    pd.testing.assert_frame_equal(here, rows)
    assert where == {"folder": None, "made_by": None, "check": None}


def test_a_learner_never_right_is_marked_on_the_axis():
    """A bar of height 0 cannot be seen: a mark on the axis in the learner's colour says it is 0."""
    import matplotlib.pyplot as plt
    import pandas as pd

    from glu.studies.learning.figures import plot_real_person

    summary = pd.DataFrame(
        {"study": "fitted", "features": "centred", "learner": ["true", "always_tap"], "words": False,
         "accuracy": [0.8, 0.0], "ci_low": [0.7, 0.0], "ci_high": [0.9, 0.0]}
    )  # fmt: skip
    fig, ax = plt.subplots()
    try:
        plot_real_person(ax, summary, "fitted", "centred")
        marks = [line for line in ax.lines if line.get_marker() == "_"]
        assert [(list(m.get_xdata()), list(m.get_ydata())) for m in marks] == [([1], [0.005])]
        assert [b.get_height() for b in ax.patches] == [0.8, 0.0]
    finally:
        plt.close(fig)


def test_notebook_12s_parameters_make_the_real_persons_settings():
    """Its draws and episodes; computed here (saved "none"), as many episodes from glu's generator and the
    notebook's bootstrap; a saved run keeps its own; a number of draws that is not one is refused."""
    params = {"real_draws": 3, "real_episodes": 40, "bootstrap": 300, "saved": "shipped", "seed": 5}
    assert rp.settings_from_parameters(params) == rp.RealPersonSettings(draws=(0, 1, 2), episodes=40)
    here = rp.settings_from_parameters({**params, "saved": "none"})
    assert here == rp.RealPersonSettings(draws=(0, 1, 2), episodes=40, generator_episodes=40, bootstrap=300)
    assert rp.settings_from_parameters({}) == rp.RealPersonSettings()
    for bad in (0, "5", True):
        with pytest.raises(DataError, match=f"^real_draws={bad!r}: a whole number of draws ≥ 1$"):
            rp.settings_from_parameters({"real_draws": bad})
    with pytest.raises(DataError, match="^real_episodes=9|^episodes=9: a whole number from 10"):
        rp.settings_from_parameters({"real_episodes": 9})
