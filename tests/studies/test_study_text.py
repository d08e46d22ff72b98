"""Sentences of notebooks 07–10 written from their tables: constructed tables with known numbers."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from glu.errors import DataError
from glu.studies.correspondence.experiment import OCCLUDED
from glu.studies.correspondence.text import nested_sentences, study_sentences
from glu.studies.replication.text import (
    anticipation_sentence,
    effect_sentence,
    leader_text,
    published_sentence,
    sampling_line,
    verbal_sentences,
    word_change_sentences,
)


def summary_rows():
    rows = []
    for features, front, turned, mirror in (
        ("raw", 0.8, 0.35, 0.33),
        ("centred+rotated", 0.7, 0.74, 0.5),
        ("centred+mirrored", 0.8, 0.36, 0.81),
        ("body", 0.82, 0.81, 0.34),
    ):
        for level, yaw, acc, factor in (
            ("0°", 0.0, front, "viewpoint"),
            ("90°", 90.0, turned, "viewpoint"),
            ("180°", 180.0, turned + 0.02, "viewpoint"),
            ("mirrored", 0.0, mirror, "mirror"),
        ):
            rows.append(
                {
                    "train": "human",
                    "features": features,
                    "factor": factor,
                    "level": level,
                    "yaw_deg": yaw,
                    "accuracy": acc,
                    "ci_low": acc - 0.05,
                    "ci_high": acc + 0.05,
                }
            )
    rows += [
        {
            "train": "robot",
            "features": "raw",
            "factor": "viewpoint",
            "level": "0°",
            "yaw_deg": 0.0,
            "accuracy": 0.4,
            "ci_low": 0.3,
            "ci_high": 0.5,
        },
        {
            "train": "robot",
            "features": "raw",
            "factor": "performer",
            "level": "the robot itself",
            "yaw_deg": 0.0,
            "accuracy": 0.97,
            "ci_low": 0.97,
            "ci_high": 0.97,
        },
    ]
    return pd.DataFrame(rows)


def test_study_sentences():
    effects = pd.DataFrame(
        [
            {"train": "human", "invariance": "rotated", "features": "centred+rotated", "baseline": "centred",
             "level": "0°", "verdict": "worse", "verdict_adjusted": "worse"},
            {"train": "human", "invariance": "centred", "features": "body+centred", "baseline": "body",
             "level": "6 cm", "verdict": "worse", "verdict_adjusted": "worse"},
            {"train": "human", "invariance": "mirrored", "features": "centred+mirrored",
             "baseline": "centred", "level": "90°", "verdict": "worse", "verdict_adjusted": "no difference"},
            {"train": "human", "invariance": "centred", "features": "centred", "baseline": "raw",
             "level": "seated", "verdict": "better", "verdict_adjusted": "better"},
        ]
    )  # fmt: skip
    rows = summary_rows()
    occluded = rows[(rows.factor == "viewpoint") & (rows.yaw_deg > 0) & (rows.train == "human")].copy()
    occluded["factor"] = OCCLUDED
    occluded["accuracy"] = occluded["ci_low"] = occluded["ci_high"] = 0.33
    text = study_sentences(pd.concat([rows, occluded], ignore_index=True), effects)
    assert (
        "facing the camera: raw 0.80 [0.75, 0.85], `centred+rotated` 0.70 [0.65, 0.75], `body` 0.82"
        in text[0]
    )
    assert (
        "Turned by 90–180° and seen by an ideal tracker (both shoulders wherever the person faces): raw "
        "0.35–0.37, `centred+rotated` 0.74–0.76, `body` 0.81–0.83." in text[0]
    )
    assert text[1].startswith("Seen through a tracker that loses the far shoulder beyond 60° and swaps left")
    assert "`body` 90° 0.33 [0.33, 0.33], 180° 0.33 [0.33, 0.33]" in text[1]
    assert (
        text[2] == "A mirror image: raw 0.33 [0.28, 0.38], `centred+mirrored` 0.81 [0.76, 0.86], `body` 0.34 "
        "[0.29, 0.39]."
    )
    assert text[3] == (
        "Where adding an invariance costs accuracy (its paired difference adjusted with the other 3 by "
        "Benjamini–Hochberg): `rotated` added to `centred`: 0°; `centred` added to `body`: 6 cm."
    )
    assert text[4] == "Where it buys accuracy, adjusted alike: `centred` added to `raw`: seated."
    assert "hand-written generator of an iCub-like arm" in text[5] and "not measured on a robot" in text[5]
    assert (
        "better than 0.40 [0.30, 0.50] (raw, viewpoint: 0°), while the robot recognises its own at 0.97."
        in (text[5])
    )
    assert (
        text[-1] == "9 of 26 intervals have zero width (every test gesture of every seed recognised alike)."
    )


def test_nested_sentences():
    summary = pd.DataFrame(
        {
            "seed": [0, 1],
            "correct": [11, 10],
            "testable": [11, 11],
            "accuracy": [1.0, 10 / 11],
            "ci_low": [0.7151, 0.5872],
            "ci_high": [1.0, 0.9977],
            "always_tap": [3 / 11, 3 / 11],
            "tuned_accuracy": [1.0, 1.0],
            "tuned_candidate": ["centred, reg0.03"] * 2,
            "recordings": [3, 3],
        }
    )
    seated = pd.DataFrame(
        {
            "seed": [0, 1],
            "recording": ["tap_seated"] * 2,
            "predicted": ["tap", "tap"],
            "p_tap": [1.0, 1.0],
            "below": [38.0, 38.3],
            "training_low": [2.98, 2.98],
            "training_high": [3.37, 3.37],
            "tap_first": [1, 1],
            "tap_from": [27, 28],
            "onset": [10, 10],
            "n_frames": [94, 94],
            "always_tap": [True] * 2,
        }
    )
    cands = pd.DataFrame({"features": ["raw", "raw", "centred"], "loso_accuracy": [0.64, 0.82, 1.0]})
    text = nested_sentences(summary, seated, cands)
    assert "seed 0: 11 of 11 (1.00, exact 95 % interval [0.72, 1.00]); seed 1: 10 of 11 (0.91" in text[0]
    assert "best candidate scores 1.00 (centred, reg0.03)" in text[0] and '"tap" scores 0.27' in text[0]
    assert text[1].startswith("The segments come from 3 recordings, one per action: the action is confounded")
    assert "treats the segments as independent" in text[1]
    assert (
        text[2]
        == "Plain leave-one-segment-out over candidates and seeds: raw features 0.64–0.82, centred 1.00."
    )
    assert "lies 38.00–38.30 nats below every training sequence (theirs: 2.98 to 3.37" in text[3]
    assert "tap first leads at frame 1, the hand starts to move at frame 10 of 94" in text[3]
    assert "from frame 27–28." in text[3]
    assert "also gets 1 of 1 seated taps right" in text[4]


def test_replication_sentences():
    effect = pd.DataFrame(
        {
            "case": ["small sphere"] * 3 + ["big box"] * 3,
            "ObjVel": ["slow", "medium", "fast"] * 2,
            "p": [0.048, 0.429, 0.524, 0.999, 0.001, 0.0],
        }
    )
    assert effect_sentence(effect) == (
        "After a tap: on a small sphere, p(ObjVel) is slow 0.048, medium 0.429, fast 0.524 (most "
        "likely fast); on a big box, p(ObjVel) is slow 0.999, medium 0.001, fast 0.000 (most likely "
        "slow)."
    )
    change = pd.DataFrame(
        {"word": ["rolls", "pokes", "the"], "delta": [0.064, -0.055, 0.0], "shown": [True, True, False]}
    )
    other = change.assign(delta=change.delta + np.array([0.0, 2e-16, 0.0]))
    text = word_change_sentences({"text": change, "code": other})
    assert text[0] == 'Adding the tap raises "rolls" (+0.064) most, and lowers "pokes" (-0.055) most.'
    assert (
        text[1]
        == "The text and code variants of the evidence give Δp(w) equal to rounding (max |difference| "
        "2.0e-16)."
    )
    reproduced = pd.DataFrame({"same_sentence": [True] * 3 + [False], "same_score": [True, True, None, None]})
    and_but = pd.DataFrame(
        {
            "ObjVel": ["medium", "medium", "slow", "slow"],
            "word": ["and", "but"] * 2,
            "p": [0.8, 0.2, 0.1, 0.9],
        }
    )
    versus = pd.DataFrame(
        {
            "figure": ["fig7a", "fig7b", "fig7a", "fig7b"],
            "score_name": ["paper", "paper", "original", "original"],
            "exact_in_samples": [True, False, False, False],
            "samples_rank": [1, 22, 2, 22],
            "rank_under_other": [9, 1, 1, 1],
        }
    )
    trials = pd.DataFrame(
        {"n_samples": [10000] * 2, "found_best": [True, False], "p_draw_best": [0.019, 0.019]}
    )
    text = verbal_sentences(reproduced, and_but, versus, trials)
    assert text[0] == "3 of 4 published sentences and 2 of 2 printed scores are reproduced."
    assert "with ObjVel=slow p(and) 0.100, p(but) 0.900 (but likelier)" in text[1]
    assert text[2] == (
        "Under the paper score, the grammar's best sentence is among the samples for fig7a; elsewhere the "
        "samples' best ranks 22 (fig7b) in the grammar."
    )
    assert text[3].startswith(
        "Under the original score, the grammar's best sentence is among the samples for no"
    )
    assert (
        text[4]
        == "The two scores pick different best sentences for 1 of 2 evidence sets (fig7a: rank 9 under "
        "the other)."
    )
    assert (
        text[5]
        == "Random samples of 10,000 sentences held the grammar's best in 1 of 2 trials (exact chance 1.9 %)."
    )


def test_leader_text():
    p = np.array([[0.6, 0.3, 0.1]] * 5 + [[0.1, 0.2, 0.7]] * 5 + [[0.2, 0.7, 0.1]] * 5)
    assert (
        leader_text(("grasp", "tap", "touch"), p, [5, 10, 15])
        == "grasp from t = 5, touch from t = 10, tap from t = 15"
    )


def test_an_anticipation_run_and_its_published_comparison_in_a_sentence():
    from types import SimpleNamespace

    p = np.array([[0.6, 0.3, 0.1]] * 5 + [[0.1, 0.7, 0.2]] * 5)
    run = SimpleNamespace(
        actions=("grasp", "tap", "touch"),
        p_hmm=p,
        update_t=[5, 10],
        prediction_changes=lambda: [(5, 125, "slow", 0.61), (10, 130, "fast", 0.55)],
        description="the robot is tapping the ball and the ball is rolling",
    )
    assert anticipation_sentence("sphere", "glu", run) == (
        "sphere, glu HMMs: leading model grasp from t = 5, tap from t = 10; predicted ObjVel slow from t = 5 "
        "(frame 125, p 0.61); fast from t = 10 (frame 130, p 0.55); "
        "“the robot is tapping the ball and the ball is rolling”"
    )
    versus = pd.DataFrame({"within": [True, True, False]})
    versus.attrs["parameters"] = {"same_caption": False}
    assert published_sentence("box", versus) == (
        "box: 2 of 3 published values within the figure's resolution; the caption is not the paper's"
    )
    versus.attrs["parameters"] = {"same_caption": True}
    assert published_sentence("box", versus).endswith("the caption is the paper's")


def test_how_often_random_samples_drew_the_best_in_a_line():
    trials = pd.DataFrame(
        {"n_samples": [10_000] * 4, "found_best": [True, False, False, False], "sample_rank": [1, 3, 8, 20]}
    )
    assert sampling_line(trials) == (
        "over 4 trials of 10,000 random sentences, the best of the grammar was drawn 1 times (25.0 %); "
        "the median rank of a sample's best in the grammar is 6"
    )


def test_readme_values_from_a_summary_that_lacks_them_are_one_error():
    """A summary whose notebook 10 ran without raw features, or whose intervals do not say their
    replicates, or whose real-person summary has two rows for one learner: the README cannot be filled."""
    from glu.studies.correspondence import readme as creadme
    from glu.studies.learning import readme as lreadme

    cands = pd.DataFrame({"features": ["centred"], "loso_accuracy": [0.9]})
    with pytest.raises(DataError, match="correspondence_candidates has no raw-feature rows"):
        creadme._loso({"correspondence_candidates": (cands, {}), "correspondence_nested_cv": (None, {})})
    with pytest.raises(DataError, match="does not say how many replicates it drew"):
        creadme._replicates({"parameters": {"interval": "95 % percentile bootstrap"}})
    assert (
        creadme._replicates({"parameters": {"interval": "95 % two-level bootstrap (2000 replicates)"}})
        == 2000
    )
    rows = {"study": "fitted", "features": "centred", "learner": "true", "words": False, "accuracy": 0.5}
    twice = pd.DataFrame([rows, rows]).assign(ci_low=0.4, ci_high=0.6)
    with pytest.raises(
        DataError, match="learning_real_person_summary: no single row for fitted, centred, true"
    ):
        lreadme._person(twice, "fitted", "centred")
