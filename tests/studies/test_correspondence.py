"""The correspondence study: tidy results, two-level intervals from the per-gesture outcomes, paired effects
by hand, the body frame, the two-view recording read back in strict mode, and invariance end to end (a
turned, mirrored tap scores the same)."""

from __future__ import annotations

import json
import subprocess
import sys

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pyarrow as pa
import pytest
import rerun as rr
from rerun.chunk import RrdReader

from glu.errors import DataError
from glu.gestures.corpus import synthetic_corpus
from glu.gestures.synthetic import View
from glu.hmm import TrainingConfig
from glu.studies.correspondence import experiment as corr
from glu.studies.correspondence import figures as cplots
from glu.studies.correspondence import seated, two_views
from glu.studies.correspondence.recordings import write_two_views

TINY = {"config": TrainingConfig(n_states=2, n_mix=1, n_iter=3)}


FEATURES = ("raw", "centred", "centred+rotated", "body", "body+centred")


@pytest.fixture(scope="module")
def study():
    conds = [c for c in corr.default_conditions() if c.level in ("0°", "90°", "the robot itself")]
    return corr.correspondence_study(
        feature_sets=FEATURES,
        conditions=conds,
        seeds=(0, 1),
        n_train=2,
        n_test=1,
        **TINY,
    )


def test_the_study_is_tidy_and_stamped(study):
    # seeds × training sources × feature sets × conditions (0°, 90° ideal and occluding, the robot)
    assert len(study) == 2 * 2 * 5 * 4
    occluded = study[study["factor"] == corr.OCCLUDED]
    assert set(occluded["level"]) == {"90°"} and set(occluded["tracker"]) == {"occluding"}
    assert set(study[study["factor"] == "viewpoint"]["tracker"]) == {"ideal"}
    assert set(study["train"]) == {"robot", "human"}
    assert list(dict.fromkeys(study["features"])) == list(FEATURES)
    assert study["accuracy"].between(0, 1).all() and (study["n_test"] == 3).all()
    hits = np.array([[c == "1" for c in o] for o in study["outcomes"]])
    np.testing.assert_allclose(hits.mean(axis=1), study["accuracy"])  # one character per test gesture
    assert study.attrs["parameters"]["variety"] == [0.0, 1.0]  # other people; the robot as it is
    assert study.attrs["experiment"] == "correspondence_study"
    assert study.attrs["data_source"].startswith("synthetic data")
    assert study.attrs["parameters"]["seeds"] == [0, 1] and study.attrs["parameters"]["n_states"] == 2
    robot = study[study["factor"] == "performer"]
    assert (robot["level"] == "the robot itself").all()


def test_summary_pools_the_seeds_with_two_level_intervals(study):
    s = corr.summarise(study, replicates=300)
    assert len(s) == len(study) // 2 and (s["n_seeds"] == 2).all()
    for row in s.itertuples():
        g = study[
            (study["train"] == row.train)
            & (study["features"] == row.features)
            & (study["factor"] == row.factor)
            & (study["level"] == row.level)
        ]
        hits = np.array([c == "1" for o in g["outcomes"] for c in o])
        assert row.accuracy == pytest.approx(hits.mean())
        assert row.ci_low <= row.accuracy + 1e-12 and row.accuracy <= row.ci_high + 1e-12
        assert (row.seed_min, row.seed_max) == (g["accuracy"].min(), g["accuracy"].max())
        if 0 < hits.mean() < 1:
            assert row.ci_high > row.ci_low  # never a zero-width interval where the gestures differ
        else:
            assert row.ci_high == row.ci_low
    table = corr.main_table(s, "human")
    assert list(table.columns) == list(FEATURES)
    assert table.index[0] == "viewpoint: 0°"
    with pytest.raises(DataError, match="no results for training source 'robot'"):
        corr.main_table(s[s["train"] == "human"], "robot")
    with pytest.raises(DataError, match="unknown training source 'alien'; allowed: robot, human"):
        corr.training_corpus("alien", 2, 0)


def test_feature_set_names():
    from glu.gestures.feature_sets import FeatureSet

    assert FeatureSet.parse("body+centred") == (True, corr.Invariants.parse("centred"))
    assert FeatureSet.parse("all").body is False and FeatureSet.parse("body").invariants.is_raw
    for name in ("raw", "body", "body+centred+rotated", "centred+mirrored"):
        assert FeatureSet.parse(name).name == name
    assert set(FEATURES) <= set(corr.STUDY_FEATURE_NAMES)


def test_every_turn_is_seen_by_both_trackers():
    conds = corr.default_conditions(yaws=(0, 45, 180))
    ideal = [c for c in conds if c.factor == "viewpoint"]
    occluding = [c for c in conds if c.factor == corr.OCCLUDED]
    assert [c.level for c in ideal] == ["0°", "45°", "180°"] and [c.level for c in occluding] == [
        "45°",
        "180°",
    ]
    assert all(c.view.tracker == "occluding" for c in occluding)
    assert not [
        c for c in corr.default_conditions(yaws=(0, 90), occluding=False) if c.factor == corr.OCCLUDED
    ]


def outcome_rows(features_outcomes):
    rows = []
    for f, per_seed in features_outcomes.items():
        for seed, o in enumerate(per_seed):
            rows.append(
                {
                    "seed": seed,
                    "train": "human",
                    "features": f,
                    "factor": "viewpoint",
                    "level": "0°",
                    "outcomes": o,
                }
            )
    return pd.DataFrame(rows)


def test_invariance_effects_are_paired_differences():
    # centring costs here: on every seed the raw recogniser is right more often, on the same gestures
    effects = corr.invariance_effects(
        outcome_rows({"raw": ["1111101111", "1101111111"], "centred": ["0101100011", "1000110101"]}), 500
    )
    (e,) = effects.itertuples()
    assert (e.invariance, e.baseline) == ("centred", "raw")
    assert e.delta == pytest.approx((10 / 20) - (18 / 20))
    assert e.ci_high < 0 and e.costs and not e.helps and e.verdict == "worse"
    assert e.p_value < 0.05 and e.p_adjusted == e.p_value and e.verdict_adjusted == "worse"  # a family of one
    same = corr.invariance_effects(outcome_rows({"raw": ["1010", "0110"], "centred": ["1010", "0110"]}), 200)
    assert same.iloc[0].delta == 0 and same.iloc[0].ci_low == 0 == same.iloc[0].ci_high
    assert same.iloc[0].verdict == "no difference"


def test_body_frame_pairs_with_body_frame():
    """Adding centring to the body frame is compared with the body frame, not with raw."""
    effects = corr.invariance_effects(
        outcome_rows({"raw": ["11", "11"], "body": ["10", "10"], "body+centred": ["01", "01"]}), 100
    )
    assert set(zip(effects.features, effects.baseline, strict=True)) == {("body+centred", "body")}


def test_plots_draw_the_study(study):
    s = corr.summarise(study)
    fig, axes = plt.subplots(1, 4, figsize=(16, 3))
    assert cplots.plot_accuracy_vs_viewpoint(axes[0], s, "human") is axes[0]
    assert len(axes[0].lines) == 5 + 1  # one line per feature set, and chance
    markers = {line.get_marker() for line in axes[0].lines[:-1]}
    assert len(markers) == 5  # told apart by more than their colour
    cplots.plot_accuracy_vs_viewpoint(axes[3], s, "human", factor=corr.OCCLUDED)
    assert "occluding" in axes[3].get_title()
    cplots.plot_accuracy_by_condition(axes[1], s, "robot")
    assert len(axes[1].patches) == 5 * 2  # the reference and the robot itself, per feature set
    cplots.plot_invariance_effects(axes[2], corr.invariance_effects(study), "human")
    assert len(axes[2].images) == 1
    plt.close(fig)


def _summary_rows(s, train, features, factor):
    """The summary's accuracies one line of plot_accuracy_vs_viewpoint draws, by turn (the occluding
    tracker's panel starts at the ideal one's front view)."""
    g = s[(s["train"] == train) & (s["features"] == features)]
    front = (g["factor"] == "viewpoint") & (g["yaw_deg"] == 0)
    return g[(g["factor"] == factor) | (front if factor != "viewpoint" else False)].sort_values("yaw_deg")


def test_the_viewpoint_figure_has_a_panel_per_training_source_and_tracker(study):
    """Notebook 10's first figure: the robot, one human view, and one human view through the occluding
    tracker, in that order; each panel a line per feature set holding the summary's accuracies by turn, and
    chance; one legend, on the last panel. A summary without the occluding tracker has two panels."""
    s = corr.summarise(study)
    fig = cplots.viewpoint_figure(s)
    try:
        assert [ax.get_title() for ax in fig.axes] == [
            "trained on the robot",
            "trained on one human view",
            "trained on one human view, occluding tracker",
        ]
        for ax, (train, factor) in zip(fig.axes, cplots.VIEWPOINT_PANELS, strict=True):
            assert [c.get_label() for c in ax.containers] == list(FEATURES)
            for c, features in zip(ax.containers, FEATURES, strict=True):
                rows = _summary_rows(s, train, features, factor)
                np.testing.assert_allclose(np.asarray(c.lines[0].get_ydata(), float), rows["accuracy"])
            assert ax.lines[-1].get_ydata()[0] == pytest.approx(1 / 3)  # chance
        assert [ax.get_legend() is not None for ax in fig.axes] == [False, False, True]
    finally:
        plt.close(fig)
    fig = cplots.viewpoint_figure(s[s["factor"] != corr.OCCLUDED])
    assert [ax.get_title() for ax in fig.axes] == ["trained on the robot", "trained on one human view"]
    plt.close(fig)


def test_the_conditions_figure_draws_every_condition_of_one_source(study):
    """A bar per feature set and condition (here the reference and the robot itself), at the summary's
    accuracy, titled by the training source."""
    s = corr.summarise(study)
    fig = cplots.conditions_figure(s, "human")
    try:
        (ax,) = fig.axes
        assert ax.get_title() == "trained on one human view"
        bars = [list(c) for c in ax.containers if hasattr(c, "patches")]
        h = s[
            (s["train"] == "human")
            & s["level"].isin(["0°", "the robot itself"])
            & (s["factor"] != corr.OCCLUDED)
        ]
        for group, features in zip(bars, FEATURES, strict=True):
            want = h[h["features"] == features].set_index("level").loc[["0°", "the robot itself"], "accuracy"]
            assert [b.get_height() for b in group] == pytest.approx(list(want))
        assert [t.get_text() for t in ax.get_legend().get_texts()] == list(FEATURES)
    finally:
        plt.close(fig)


def test_the_invariance_effects_figure_stacks_a_map_per_training_source(study):
    """One map per training source (robot, then human), each writing that source's paired differences."""
    effects = corr.invariance_effects(study)
    fig = cplots.invariance_effects_figure(effects)
    try:
        assert len(fig.axes) == 2
        for ax, train in zip(fig.axes, corr.TRAIN_SOURCES, strict=True):
            assert f"trained on {train};" in ax.get_title() and len(ax.images) == 1
            want = effects.loc[effects["train"] == train, "delta"].dropna()
            assert sorted(t.get_text() for t in ax.texts) == sorted(f"{v:+.2f}" for v in want)
    finally:
        plt.close(fig)


def test_the_nested_cv_figure_draws_each_seeds_accuracy():
    summary = pd.DataFrame(
        {"seed": [0, 1], "accuracy": [0.7, 0.8], "ci_low": [0.5, 0.6], "ci_high": [0.9, 0.95]}
        | {"tuned_accuracy": [0.9, 0.9], "always_tap": [0.33, 0.33]}
    )
    fig = cplots.nested_cv_figure(summary)
    try:
        (ax,) = fig.axes
        assert ax.get_title() == "real standing segments"
        (bars,) = ax.containers
        assert list(bars.lines[0].get_ydata()) == [0.7, 0.8]
        assert [list(line.get_ydata()) for line in ax.lines[-2:]] == [[0.9, 0.9], [0.33, 0.33]]
        assert [t.get_text() for t in ax.get_xticklabels()] == ["seed 0", "seed 1"]
    finally:
        plt.close(fig)


def test_settings_are_labelled_and_parsed_back():
    for label in ("glu defaults", "Q6 M3 reg0.03", "M1", "mixsplit", "mixsplit Q4"):
        assert seated.setting_label(seated.parse_setting(label)) == label
    assert seated.parse_setting("Q6 reg0.03") == {"n_states": 6, "covar_reg": 0.03}
    with pytest.raises(Exception, match="KEYvalue"):
        seated.parse_setting("Q=6")


def test_leave_one_segment_out_keeps_the_features():
    """The fast leave-one-segment-out of glu.studies.replication.recipes equals the plain one with invariant
    features."""
    from glu.studies.replication.gestures import leave_one_out
    from glu.studies.replication.recipes import leave_one_segment_out

    corpus = synthetic_corpus(3, seed=6)
    train = {"config": TrainingConfig(n_states=2, n_mix=1, n_iter=3), "features": "centred+rotated"}
    fast, everything = leave_one_segment_out(corpus, seed=0, **train)
    plain = leave_one_out(corpus, by="segment", seed=0, **train)
    assert list(fast["predicted"]) == list(plain["predicted"])
    assert everything.features.name == "centred+rotated"


# ---------------------------------------------------------------- one gesture, two viewpoints
@pytest.fixture(scope="module")
def runs():
    raw = corr.train_for("human", "raw", 3, seed=0, **TINY)
    inv = corr.train_for("human", "centred+rotated+mirrored", 3, seed=0, **TINY)
    views = (View(yaw_deg=0.0, size=1.0), View(yaw_deg=120.0, mirror=True, size=1.0))
    return two_views.two_views(raw, inv, "tap", views, seed=2, noise=0.0)


def test_an_invariant_recogniser_does_not_see_the_turn_or_the_mirror(runs):
    front, back = runs
    assert front.label == "yaw 0°" and back.label == "yaw 120°, mirrored"
    np.testing.assert_allclose(back.aligned, front.aligned, atol=1e-9)  # the features, exactly
    np.testing.assert_allclose(back.p_aligned, front.p_aligned, atol=1e-9)  # so the posterior, frame by frame
    assert not np.allclose(back.raw, front.raw, atol=1e-3)
    curves = two_views.two_views_curves(runs)
    assert (
        set(curves["recogniser"]) == {"raw", "aligned"}
        and curves.attrs["experiment"] == "correspondence_two_views"
    )


def test_the_two_views_figure_has_a_panel_per_view(runs):
    """A panel per view, titled by it, drawing the raw and the invariant recogniser's p_HMM(tap) over time
    as the curves hold them; one legend, beside the last."""
    curves = two_views.two_views_curves(runs)
    fig = cplots.two_views_figure(curves, "tap")
    try:
        assert [ax.get_title() for ax in fig.axes] == ["yaw 0°", "yaw 120°, mirrored"]
        for ax, run in zip(fig.axes, runs, strict=True):
            tap = run.actions.index("tap")
            raw, aligned = ax.lines
            np.testing.assert_allclose(raw.get_ydata(), run.p_raw[:, tap])
            np.testing.assert_allclose(aligned.get_ydata(), run.p_aligned[:, tap])
            np.testing.assert_allclose(raw.get_xdata(), run.seconds)
        assert [ax.get_legend() is not None for ax in fig.axes] == [False, True]
    finally:
        plt.close(fig)


def test_notebook_10s_two_views_are_the_recognisers_it_names():
    """one_tap_two_views: a raw and an `all` recogniser trained on the front human view with the notebook's
    recipe, the noise-free tap seen from the front and, mirrored, from 120° round."""
    config = TrainingConfig(n_states=2, n_mix=1, tol=1e-3)
    raw, inv = (corr.train_for("human", f, 3, 4, False, config) for f in ("raw", "all"))
    views = (View(yaw_deg=0.0, normalise_body=False), View(yaw_deg=120.0, mirror=True, normalise_body=False))
    by_hand = two_views.two_views(raw, inv, "tap", views, seed=2, noise=0.0)
    runs = two_views.one_tap_two_views(3, seed=4, gesture=2, n_states=2)
    assert [r.label for r in runs] == ["yaw 0°", "yaw 120°, mirrored"]
    assert cplots.feature_label(runs[0].parameters["features"]) == "all"
    assert runs[0].parameters["noise_m"] == 0.0
    for a, b in zip(runs, by_hand, strict=True):
        np.testing.assert_array_equal(a.p_raw, b.p_raw)
        np.testing.assert_array_equal(a.p_aligned, b.p_aligned)


@pytest.fixture
def strict():
    rr.set_strict_mode(True)
    yield
    rr.set_strict_mode(False)


def _column(path, entity, component):
    stream = RrdReader(str(path)).stream().filter(content=entity, is_static=False, components=component)
    return pa.Table.from_batches([c.to_record_batch().select(["frame", component]) for c in stream]).sort_by(
        "frame"
    )


def test_two_view_recording_reads_back(runs, tmp_path, strict):
    path = write_two_views(runs, tmp_path / "two.rrd", "test-two-views")
    res = subprocess.run(
        [sys.executable, "-m", "rerun", "rrd", "verify", str(path)], capture_output=True, text=True
    )
    assert res.returncode == 0, res.stderr
    for i, run in enumerate(runs, start=1):
        for name, p in (("raw", run.p_raw), ("aligned", run.p_aligned)):
            tap = _column(path, f"/view{i}/p_hmm/{name}/tap", "Scalars:scalars")
            assert tap.column("frame").to_pylist() == list(range(1, len(p) + 1))
            np.testing.assert_allclose([v[0] for v in tap.column("Scalars:scalars").to_pylist()], p[:, 1])
        pos = _column(path, f"/view{i}/features/aligned/position", "Points3D:positions")
        np.testing.assert_allclose(
            pos.column("Points3D:positions").to_pylist()[-1][0], run.aligned[-1], rtol=1e-6
        )
        joints = _column(path, f"/view{i}/camera/joints", "Points3D:positions")
        assert len(joints.column("Points3D:positions").to_pylist()[0]) == 15
    assert len(RrdReader(str(path)).blueprints()) == 1
    again = write_two_views(runs, tmp_path / "again.rrd", "test-two-views-again")
    cmp = subprocess.run(
        [sys.executable, "-m", "rerun", "rrd", "compare", str(path), str(again)], capture_output=True
    )
    assert cmp.returncode == 0


def test_posture_offsets_of_synthetic_standing_and_seated_gestures():
    from glu.data import resolve_data

    off = seated.posture_offsets(resolve_data("synthetic"))  # no hand logs: the generator's two postures
    assert set(off["posture"]) == {"standing", "seated"} and {"x", "y", "z"} <= set(off.columns)
    mean = off.groupby("posture")[["y", "z"]].mean()
    assert mean.loc["seated", "y"] > mean.loc["standing", "y"]  # seated: the hand works higher, further out
    assert mean.loc["seated", "z"] < mean.loc["standing", "z"]


def test_the_seated_taps_are_the_anticipation_cases_test_segments(synthetic_folder):
    from glu.data import resolve_data
    from glu.studies.anticipation.experiment import CASES

    taps = seated.seated_taps(resolve_data(synthetic_folder))
    assert [s.recording for s in taps] == [c.recording for c in CASES.values()]
    assert {s.action for s in taps} == {"tap"}


def test_the_invariances_effects_are_one_adjusted_family():
    """Twelve conditions where centring changes nothing and one where it costs: alone its interval excludes 0
    (p at the floor of 400 replicates, 2/401), adjusted with the twelve others (13 · 2/401 > 0.05) it is no
    difference (Benjamini–Hochberg, tested against statsmodels in tests/library/test_multiplicity.py)."""
    from glu.stats import benjamini_hochberg

    rows = []
    for k in range(13):
        a, b = ("1111111111", "1111111111") if k else ("1111111111", "1001001000")
        for seed in range(2):
            rows += [
                {"seed": seed, "train": "human", "features": "raw", "factor": "noise", "level": f"{k}",
                 "outcomes": a},
                {"seed": seed, "train": "human", "features": "centred", "factor": "noise", "level": f"{k}",
                 "outcomes": b},
            ]  # fmt: skip
    effects = corr.invariance_effects(pd.DataFrame(rows), 400)
    np.testing.assert_allclose(effects.p_adjusted, benjamini_hochberg(effects.p_value.to_numpy()))
    first = effects[effects.level == "0"].iloc[0]
    assert first.verdict == "worse" and first.verdict_adjusted == "no difference" and not first.costs


def test_the_study_grid_is_saved_found_and_read_back(tmp_path, monkeypatch):
    """The study's tables computed per seed (as on Dask) are written with their key, found by it, and read
    back equal; other settings are computed into the cache; notebook 10's defaults are the saved key."""
    import dataclasses

    from glu import saved
    from glu.cli.correspondence_cmds import notebook_settings
    from glu.studies.correspondence import grid

    here = dataclasses.replace(saved.HERE, saved=tmp_path / "sweeps", sweeps=tmp_path / "cache")
    monkeypatch.setattr(saved, "HERE", here)
    settings = grid.StudySettings(
        seeds=(0, 1), n_train=2, n_test=1, feature_sets=("raw", "centred"), yaws=(0, 90), n_states=2,
        n_iter=3, bootstrap=20, levels=("0°", "90°"),
    )  # fmt: skip
    tables = grid.run_study(settings)
    assert set(tables[0]["seed"]) == {0, 1} and set(tables[0]["factor"]) == {"viewpoint", corr.OCCLUDED}
    folder = grid.write_tables(tmp_path / "sweeps" / grid.NOTEBOOK / "study", tables, settings.key(), "test")
    found = grid.study_tables(settings)
    assert found.folder == folder
    for a, b in zip(tables, found[:3], strict=True):
        pd.testing.assert_frame_equal(a.reset_index(drop=True), b, check_dtype=False)
        assert b.attrs["experiment"] == a.attrs["experiment"]
    assert found.summary.attrs["parameters"]["interval"] == tables[1].attrs["parameters"]["interval"]
    other = dataclasses.replace(settings, seeds=(1,))
    computed = grid.study_tables(other)
    assert computed.folder.parent == tmp_path / "cache" / grid.NOTEBOOK and set(computed.results["seed"]) == {
        1
    }
    defaults = notebook_settings()
    assert defaults.bootstrap == 1000 and defaults.levels is None and len(defaults.seeds) == 10
    with pytest.raises(DataError, match="nowhere: not a folder of saved correspondence tables"):
        grid.read_tables(tmp_path / "nowhere")


def _stamped_tables(value: int) -> tuple[pd.DataFrame, ...]:
    """Three small tables stamped as the study's (every cell ``value``), in the place of a computed study."""
    from glu.studies.correspondence import grid
    from glu.tidy import tidy

    return tuple(tidy(pd.DataFrame({"value": [value] * 3}), n, "synthetic", seeds=[0]) for n in grid.TABLES)


def test_a_rewrite_of_saved_tables_cut_short_is_refused_never_mixed(tmp_path):
    """Saved tables rewritten with other numbers, interrupted after the first table: the folder is refused in
    one line and passed by when looking for its key, never read as the new table beside the old ones under
    the old key; a file of the user's in the folder survives, and a complete write is read whole."""
    from cut_short import cut_short, old_or_refused

    from glu import saved
    from glu.studies.correspondence import grid

    root = tmp_path / "sweeps"
    folder = root / "study"
    folder.mkdir(parents=True)
    (folder / "notes.txt").write_text("mine\n")
    key = {"format": list(grid.FORMAT), "settings": {"seeds": [0]}}
    grid.write_tables(folder, _stamped_tables(1), key, "test")
    assert saved.find(grid.NOTEBOOK, key, [root]) == folder
    with cut_short(pd.DataFrame, "to_parquet", at=2):
        grid.write_tables(folder, _stamped_tables(2), key, "test")
    refusal = old_or_refused(
        lambda: grid.read_tables(folder), lambda t: all((df["value"] == 1).all() for df in t[:3])
    )
    assert refusal is not None and "not a folder of saved correspondence tables" in refusal
    assert saved.find(grid.NOTEBOOK, key, [root]) is None and saved.read_key(folder) is None
    assert (folder / "notes.txt").read_text() == "mine\n"
    assert not [p.name for p in folder.iterdir() if p.name.startswith(".")]  # no temporary file left
    grid.write_tables(folder, _stamped_tables(3), key, "test")
    assert all((df["value"] == 3).all() for df in grid.read_tables(folder)[:3])
    assert saved.find(grid.NOTEBOOK, key, [root]) == folder and (folder / "notes.txt").read_text() == "mine\n"


def test_glu_correspondence_writes_the_study_with_its_key_and_command(tmp_path, monkeypatch, capsys):
    """`glu correspondence -o DIR` runs the study of notebook 10's settings (here a small grid in their
    place) and writes its tables with their key and the command that makes them again."""
    from glu import saved
    from glu.cli import correspondence_cmds, main
    from glu.studies.correspondence import grid

    settings = grid.StudySettings(
        seeds=(0, 1), n_train=2, n_test=1, feature_sets=("raw",), yaws=(0,), n_states=2, n_iter=3,
        bootstrap=20, levels=("0°",),
    )  # fmt: skip
    monkeypatch.setattr(correspondence_cmds, "notebook_settings", lambda: settings)
    out = tmp_path / "study"
    monkeypatch.setattr(sys, "argv", ["glu", "correspondence", "-o", str(out)])
    assert main(["correspondence", "-o", str(out)]) == 0
    results = pd.read_parquet(out / f"{grid.TABLES[0]}.parquet")
    assert capsys.readouterr().out == f"{len(results)} rows over 2 seeds → {out}\n"
    assert set(results["seed"]) == {0, 1}
    doc = saved.read_key(out)
    assert doc["command"] == "glu correspondence -o '…/study'" and doc["key"] == json.loads(
        json.dumps(settings.key())
    )


def _by_field(p):
    """The settings as notebook 10 built them field by field from its parameters, before it made them in one
    call (grid.settings_from_parameters)."""
    from glu.studies.correspondence import grid

    return grid.StudySettings(
        seeds=tuple(p["seeds"]),
        n_train=p["n_train"],
        n_test=p["n_test"],
        feature_sets=tuple(p["feature_sets"]),
        yaws=tuple(p["yaws"]),
        variety=p["variety"],
        n_states=p["n_states"],
        n_mix=p["n_mix"],
        n_iter=p["n_iter"],
        bootstrap=p["bootstrap"],
        levels=None if p["levels"] is None else tuple(p["levels"]),
        normalise_body=p["normalise_body"],
    )


def test_notebook_10s_parameters_cell_makes_its_settings_in_one_call():
    """The notebook's own parameters (its cell's defaults, and its quick run's), with the other names of its
    namespace beside them, give the settings it built field by field, and the same key of the saved
    tables; `glu correspondence` makes the same from the same cell."""
    from glu.cli.correspondence_cmds import notebook_settings
    from glu.paths import PROJECT_ROOT
    from glu.run.manifest import read_manifest
    from glu.run.parameters import read_spec
    from glu.studies.correspondence import grid

    path = PROJECT_ROOT / "notebooks" / "10_correspondence.py"
    spec = {k: p.default for k, p in read_spec(path).items()}
    for params in (spec, {**spec, **read_manifest(path).quick}):
        made = grid.settings_from_parameters({**params, "out": object(), "np": np})
        assert made == _by_field(params) and made.key() == _by_field(params).key()
    assert notebook_settings() == _by_field(spec)
    assert grid.settings_from_parameters({}) == grid.StudySettings()


@pytest.mark.parametrize(
    ("bad", "message"),
    [
        (
            {"feature_sets": ["raw", "nope"]},
            r"feature_sets=\('raw', 'nope'\): unknown feature set 'nope'; allowed: raw, ",
        ),
        ({"feature_sets": "raw"}, r"feature_sets='raw': a list of feature sets, at least one, each once"),
        ({"seeds": [0, 0]}, r"seeds=\(0, 0\): a list of whole numbers ≥ 0, at least one, each once"),
        ({"seeds": [0, 1.5]}, r"seeds=\(0, 1.5\): a list of whole numbers ≥ 0"),
        ({"n_train": "8"}, r"n_train='8': a whole number ≥ 1"),
        ({"n_states": True}, r"n_states=True: a whole number ≥ 1"),
        ({"yaws": [0, float("nan")]}, r"yaws=\(0, nan\): a list of turns in degrees \(finite numbers\)"),
        ({"variety": -1.0}, r"variety=-1.0: a number ≥ 0"),
        ({"bootstrap": -5}, r"bootstrap=-5: a whole number of replicates ≥ 0"),
        ({"normalise_body": "no"}, r"normalise_body='no': True or False"),
        (
            {"levels": ["0°", "upside down"]},
            r"levels=\('0°', 'upside down'\): unknown level 'upside down'; allowed: '0°'",
        ),
        ({"levels": []}, r"levels=\(\): None \(every condition\) or a list of the conditions' levels"),
    ],
)
def test_an_unknown_or_ill_typed_parameter_is_refused_in_one_line(bad, message):
    from glu.studies.correspondence import grid

    with pytest.raises(DataError, match=f"^{message}") as err:
        grid.settings_from_parameters(bad)
    assert "\n" not in str(err.value)
