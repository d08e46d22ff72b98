"""The README's results section is written by code from results/summary.json, never by hand."""

from __future__ import annotations

import json

import numpy as np
import pytest

from glu.cli import main
from glu.errors import DataError
from glu.paths import PROJECT_ROOT
from glu.run import readme


def t(rows, **meta) -> dict:
    return {"meta": {"name": "x", **meta}, "rows": rows}


def sweep(gap: float) -> dict:
    rows = []
    for p in (0.0, 0.5, 1.0):
        for v, base in (("slow", 0.5), ("fast", 0.2)):
            rows.append({"p_hmm_tap": p, "ObjVel": v, "rule": "virtual", "p": base})
            rows.append(
                {"p_hmm_tap": p, "ObjVel": v, "rule": "jeffrey", "p": base + (gap if p == 0.5 else 0)}
            )
    return t(rows)


def corpus_rows() -> list[dict]:
    """Rows of corpus_metrics: (posterior, target, strategy, metric, fraction, viewpoint) → (estimate, low, high)."""
    cells = {
        ("likelihood", "action", "gesture", "log_loss", 1.0, "all"): (5.478, 5.324, 5.692),
        ("likelihood", "action", "gesture", "accuracy", 1.0, "all"): (0.5991, 0.58, 0.61),
        ("likelihood", "action", "product", "accuracy", 1.0, "all"): (0.6003, 0.58, 0.61),
        ("per_frame", "action", "product", "accuracy", 1.0, "all"): (0.6344, 0.6171, 0.6472),
        ("per_frame", "action", "gesture", "accuracy", 1.0, "all"): (0.5991, 0.58, 0.61),
        ("per_frame", "action", "product", "accuracy", 0.2, "all"): (0.5104, 0.5, 0.52),
        ("per_frame", "action", "gesture", "accuracy", 0.2, "all"): (0.3871, 0.37, 0.4),
        ("per_frame", "effect", "jeffrey", "ece", 1.0, "all"): (0.0834, 0.0712, 0.1003),
        ("per_frame", "effect", "hard", "ece", 1.0, "all"): (0.1718, 0.15, 0.19),
        ("per_frame", "effect", "jeffrey", "log_loss", 1.0, "all"): (0.9021, 0.87, 0.93),
        ("per_frame", "effect", "hard", "log_loss", 1.0, "all"): (1.2357, 1.2, 1.3),
        ("per_frame", "action", "gesture", "accuracy", 1.0, "turned"): (0.3582, 0.33, 0.38),
        ("per_frame", "action", "network", "accuracy", 1.0, "turned"): (0.5731, 0.55, 0.6),
    }
    rows = [
        dict(
            zip(("posterior", "target", "strategy", "metric", "fraction", "viewpoint"), k, strict=True),
            noise=None,
            estimate=e,
            ci_low=lo,
            ci_high=hi,
        )
        for k, (e, lo, hi) in cells.items()
    ]
    rows.append({**rows[0], "noise": 0.1, "estimate": 9.9})  # a row of one noise level: never quoted
    return rows


def correspondence_tables() -> dict:
    """The tables of the correspondence bullets, with known numbers."""
    off = [{"posture": "standing", "y": y, "z": z} for y, z in ((-0.67, -1.19), (-1.29, -1.32))]
    off += [{"posture": "seated", "y": y, "z": z} for y, z in ((-0.33, -1.82), (-0.23, -1.85))]
    grid = [
        {
            "features": "raw",
            "runs": 9,
            "loso_mean": 0.6,
            "loso_sd": 0.14,
            "loso_min": 0.45,
            "loso_max": 0.73,
            "runs_all_test_correct": 0,
            "settings_always_all_test_correct": "",
        },
        {
            "features": "centred",
            "runs": 9,
            "loso_mean": 0.86,
            "loso_sd": 0.15,
            "loso_min": 0.64,
            "loso_max": 1.0,
            "runs_all_test_correct": 6,
            "settings_always_all_test_correct": "M1, reg0.03",
        },
    ]

    def predictions(slow: float) -> dict:
        return t(
            [
                {"frame": f, "node": "ObjVel", "value": v, "p": p}
                for f in (5, 90)
                for v, p in (("slow", slow if f == 90 else 0.5), ("fast", 0.1))
            ]
        )

    study = []
    for train, feats in (
        (
            "human",
            ("raw", "centred", "centred+rotated", "centred+mirrored", "centred+scaled+rotated+mirrored"),
        ),
        ("robot", ("raw", "centred")),
    ):
        for k, f in enumerate(feats):
            rows = [
                ("viewpoint", "0°", 0.0),
                ("viewpoint", "90°", 90.0),
                ("viewpoint", "180°", 180.0),
                ("mirror", "mirrored", 0.0),
                ("posture", "seated", 0.0),
                ("sensor noise", "3 cm", 0.0),
                ("sensor noise", "6 cm", 0.0),
                ("combined", "seated, mirrored, 90°, body size 1.2", 90.0),
            ]
            if train == "robot":
                rows.append(("performer", "the robot itself", 0.0))
            for factor, level, yaw in rows:
                a = 0.9 - 0.01 * k if level == "0°" else 0.3 + 0.1 * k + (0.05 if yaw == 180 else 0)
                if train == "robot":
                    a = 0.97 + 0.01 * k if factor == "performer" else 0.4 + 0.05 * k
                study.append(
                    {
                        "train": train,
                        "features": f,
                        "factor": factor,
                        "level": level,
                        "yaw_deg": yaw,
                        "accuracy": a,
                    }
                )
    return {
        **learning_tables(),
        "posture_offsets": t(off),
        "hmm_feature_settings_summary": t(grid),
        "tcds_anticipation_sphere_glu_predictions": predictions(0.048),
        "tcds_anticipation_box_glu_predictions": predictions(0.999),
        "correspondence_summary": t(study, parameters={"seeds": [0, 1, 2, 3, 4]}),
    }


def learning_tables() -> dict:
    """The tables of the learning-from-effects bullet (notebook 12), with known numbers."""
    match = []
    for amb, words, hits, accs in (
        ("spheres", False, (10, 50, np.nan), (0.99, 0.98, 0.5)),
        ("still", False, (np.nan, np.nan, np.nan), (0.45, 0.52, 0.0)),
        ("still", True, (200, 100, np.nan), (0.97, 0.98, 0.9)),
    ):
        for lr, n, a in zip(("hard", "soft", "confident"), hits, accs, strict=True):
            match.append(
                {
                    "learner": lr,
                    "ambiguity": amb,
                    "words": words,
                    "episodes_to_match": n,
                    "accuracy": a,
                    "true_accuracy": 0.993,
                    "gap_low": a - 0.993 - 0.1,
                    "gap_high": a - 0.993 + 0.05,
                }
            )
    match.append({**match[0], "learner": "unsupervised", "episodes_to_match": np.nan, "accuracy": 0.7})
    labels = [
        {"ambiguity": "mixed", "words": False, "label_accuracy": 0.578},
        {"ambiguity": "mixed", "words": True, "label_accuracy": 0.938},
    ]
    real = [
        {"learner": lr, "test": test, "accuracy": acc, "draws": 3, "label_accuracy": 0.61}
        for lr, acc in (("soft", 0.64), ("true", 0.73))
        for test in ("loso", "seated")
    ]
    return {
        "learning_match": t(match, parameters={"seeds": [0, 1, 2], "episodes": 10000}),
        "learning_labels": t(labels),
        "learning_real_gestures_summary": t(real, parameters={"features": "centred"}),
    }


@pytest.fixture
def summary() -> dict:
    """A summary with known numbers in every table the README reads (the numbers are inputs, not glu's output)."""
    bn = [
        ("edges", 66, 66, 0),
        ("differing_edges", 0, 0, 0),
        ("max_cpt_difference", 0, 0, 0),
        ("log_likelihood", -19692.20254, -19692.20254, 0.0),
        ("zero_rows", 12, 12, 0),
        ("lost_prior_mass", 0.016521, 0.016521, 0),
    ]
    tables = {
        "bn_learning_summary": t(
            [dict(zip(("quantity", "ours", "reference", "difference"), r, strict=True)) for r in bn]
        ),
        "glu2017_effect_prediction": t(
            [
                {"case": "small sphere", "ObjVel": v, "p": p}
                for v, p in (("slow", 0.0478), ("medium", 0.4286), ("fast", 0.5236))
            ]
            + [{"case": "big box", "ObjVel": "slow", "p": 0.99884}]
        ),
        "glu2017_word_change_text": t(
            [
                {"word": "rolls", "delta": 0.0641, "difference": 0.0},
                {"word": "the", "delta": 0.0, "difference": -2e-17},
            ]
        ),
        "tcds_action_vs_soft_evidence": t([{"difference": 0.0}]),
        "tcds_effect_vs_soft_evidence": t([{"difference": 1e-16}]),
        "unseen_rows_comparison": t([{"uniform_minus_zero": -0.1894}, {"uniform_minus_zero": 0.01}]),
        "fusion_product_sweep": t([], tap_threshold=0.80431),
        "fusion_product_thresholds": t([{}] * 18),
        "fusion_soft_sweep_sphere": sweep(0.21),
        "fusion_soft_sweep_box": sweep(0.05),
        "hmm_original_scores": t(
            [
                {"recording": "tap1_hand", "start": a, "end": b, "winner": w}
                for a, b, w in ((216, 351, "tap"), (401, 511, "touch"), (557, 664, "tap"))
            ]
        ),
        "hmm_synthetic_cv": t([], accuracy=0.9333, folds=5),
        "hmm_accuracy_vs_noise": t(
            [{"noise_m": 0.0, "accuracy": 0.93}, {"noise_m": 0.1, "accuracy": 0.7333}], parameters={"k": 3}
        ),
        "hmm_feature_settings": t(
            [
                {
                    "features": "raw",
                    "setting": "glu defaults",
                    "recipe": "glu",
                    "loso_accuracy": acc,
                    "loso_testable": 11,
                    "test_predicted": "grasp,touch",
                    "test_correct": 0,
                }
                for acc in (0.4545, 0.5455, 0.4545)
            ]
            + [
                {
                    "features": "raw",
                    "setting": "mixsplit",
                    "recipe": "mixsplit",
                    "loso_accuracy": 0.8182,
                    "loso_testable": 11,
                    "test_predicted": "grasp,grasp",
                    "test_correct": 1,
                },
                {
                    "features": "centred",
                    "setting": "mixsplit",
                    "recipe": "mixsplit",
                    "loso_accuracy": 1.0,
                    "loso_testable": 11,
                    "test_predicted": "tap,tap",
                    "test_correct": 2,
                },
            ]
        ),
        "tcds_anticipation_sphere_published": t(
            [{"within": True, "difference": 1.3e-5}] * 3,
            parameters={"caption": "the robot pushed the ball and the ball moves", "same_caption": True},
        ),
        "tcds_anticipation_box_published": t(
            [{"within": True, "difference": -2e-6}] * 2,
            parameters={"caption": "the box is inert", "same_caption": False},
        ),
        "verbal_published_descriptions": t(
            [{"same_sentence": True, "same_score": True}] * 30
            + [{"same_sentence": True, "same_score": None}] * 4,
            n_grammar_sentences=9331200,
            n_candidates=9941,
        ),
        "verbal_sampling_vs_exact": t(
            [{"found_best": f, "p_draw_best": 0.0191, "n_samples": 10000} for f in [True] + [False] * 59]
        ),
        "tcds_anticipation_sphere_original_predictions": t([], parameters={"step": 5}),
        "corpus_metrics": t(
            corpus_rows(),
            episodes=20004,
            parameters={
                "grid": {
                    "noise": [0.0, 0.1],
                    "viewpoints": ["front", "turned", "seated"],
                    "fractions": [0.2, 1.0],
                },
                "views": {"turned": {"yaw_deg": 40.0}},
            },
        ),
        "corpus_differences": t(
            [
                {
                    "noise": None,
                    "viewpoint": "all",
                    "posterior": "per_frame",
                    "target": "action",
                    "fraction": 1.0,
                    "metric": "accuracy",
                    "strategy": "product",
                    "baseline": "gesture",
                    "difference": 0.0353,
                    "ci_low": 0.029,
                    "ci_high": 0.042,
                },
            ]
        ),
        **correspondence_tables(),
    }
    return {
        "quick": False,
        "data_source": "real data: somewhere",
        "wall_time_s": 386.3,
        "notebooks": [{}] * 9,
        "tables": tables,
    }


def test_the_section_reads_every_number_from_the_summary(summary):
    text = readme.render(summary)
    for expected in (
        "the same 66 edges (0 differ)",
        "(-19692.2025, difference 0)",
        "slow 0.048, medium 0.429",
        "slow 0.9988",
        "rises by +0.064",
        "(12 rows)",
        "(1.65 % of the",
        "up to 0.189",
        "p_HMM(tap) = 0.8043",
        "all 18 (Shape",
        "up to 0.21 in",
        "recognise 2 of the 3",
        "tap1_hand 401–511 goes to touch (their push model)",
        "5-fold accuracy 0.93",
        "0.73 with 10 cm",
        "on the 11 real segments",
        "glu's 0.45–0.55 over 3 seeds",
        "mixsplit (flat start, mixture splitting)",
        "splitting) 0.82; with",
        "worth 9 points",
        "(at most 0 and 1 of 2)",
        "5 of 5 values",
        "(max |difference| 1.3e-05)",
        '"the robot pushed the ball and the ball moves"',
        "(not the paper's caption)",
        "9,941 sampled",
        "every 5 frames",
        "multiple of 5)",
        "samples of 10,000",
        "34 of 34 sentences and 30 of 30 scores",
        "9,331,200 sentences",
        "in 1 of 60 trials",
        "is 1.9 %",
        "of its 9 notebooks",
        "20,004 episodes",
        "under 2 noise levels × 3 viewpoints",
        "95 % bootstrap",
        "is 5.48 [5.32, 5.69] nats",
        "accuracy of 0.599",
        "(product rule 0.600)",
        "in 0.634 [0.617, 0.647] of",
        "(paired difference +0.035 [+0.029, +0.042])",
        "with 20 % of the gesture seen, 0.510 against 0.387",
        "ECE of 0.083 [0.071, 0.100] against 0.172",
        "log-loss of 0.902 against 1.236",
        "turned by 40°",
        "name 0.358 of the actions",
        "network alone (0.573)",
        "seated taps -0.33 and -0.23, at most -0.67",
        "depth z -1.85 and -1.82, at least -1.32",
        "both are tap in 0 of 9 runs",
        "both are tap in 6 of 9 runs, in every run with M1, reg0.03",
        "from 0.60 ± 0.14 (0.45–0.73) raw to 0.86 ± 0.15 (0.64–1.00) centred",
        "(p(ObjVel = slow) 0.048), the box will not (0.999)",
        "5 seeds",
        "Turned by 90–180°",
        "fall to 0.30–0.35 (front view 0.90), `rotated` keeps 0.50–0.55",
        "mirror image 0.30 raw, 0.60",
        "seated 0.30 raw, 0.40 `centred`",
        "at once 0.30 raw, 0.70 with all four",
        "with 3 cm of sensor noise accuracy falls from 0.30 (raw) to 0.40",
        "better than 0.45",
        "its own at 0.97–0.98",
        "3 seeds × 10,000 episodes",
        "right for 0.58 of the episodes on every object, with words for 0.94",
        "true labels (0.993) within the interval in 2 of 3 conditions (ambiguity × words): spheres without words "
        "(hard after 10); still with words (soft after 100).",
        "It does not in still without words (best soft 0.520 [gap -0.573 to -0.423]).",
        "leave-one-segment-out accuracy (centred features) is 0.64 with soft labels and 0.73 with the true ones (mean "
        "of 3 draws; the network's labels right for 0.61)",
    ):
        assert expected in " ".join(text.split()), expected
    assert readme.matches_template(text)
    assert all(len(line) <= readme.WIDTH for line in text.splitlines() if " " in line.strip())


def test_a_number_typed_by_hand_does_not_match_the_template(summary):
    text = readme.render(summary)
    assert not readme.matches_template(text.replace("Learned exactly", "Learned in 20 ms exactly"))
    assert not readme.matches_template(text.replace("the same 66 edges", "the same sixty-six edges"))


def test_the_readme_section_is_the_template_filled_with_numbers():
    section = readme.readme_section((PROJECT_ROOT / "README.md").read_text(encoding="utf-8"))
    assert readme.matches_template(section), (
        "README.md: the results section was edited by hand; run `glu readme`"
    )


def test_update_and_check(summary, tmp_path, capsys):
    page = tmp_path / "README.md"
    page.write_text(f"# title\n\n{readme.BEGIN}\nold text\n{readme.END}\n\n## next\n")
    path = tmp_path / "summary.json"
    path.write_text(json.dumps(summary))
    argv = ["readme", "--summary", str(path), "--readme", str(page)]
    assert main([*argv, "--check"]) == 1
    assert main(argv) == 0 and "updated" in capsys.readouterr().out
    text = page.read_text()
    assert text.startswith("# title\n\n") and text.endswith(f"{readme.END}\n\n## next\n")
    assert readme.readme_section(text) == readme.render(summary)
    assert main([*argv, "--check"]) == 0 and main(argv) == 0
    assert "already up to date" in capsys.readouterr().out


def test_only_a_full_run_on_the_real_data_is_quoted(summary, tmp_path, capsys):
    path = tmp_path / "summary.json"
    page = tmp_path / "README.md"
    page.write_text(f"{readme.BEGIN}\nx\n{readme.END}\n")
    for change in ({"quick": True}, {"data_source": "synthetic data (seed 0)"}):
        path.write_text(json.dumps({**summary, **change}))
        with pytest.raises(DataError, match="full run on the real data"):
            readme.load_summary(path)
        assert main(["readme", "--summary", str(path), "--readme", str(page), "--if-complete"]) == 0
        assert "left as it is" in capsys.readouterr().out and page.read_text().count("x\n") == 1
    del summary["tables"]["hmm_feature_settings"]
    path.write_text(json.dumps(summary))
    with pytest.raises(DataError, match="lacks hmm_feature_settings"):
        readme.load_summary(path)
    assert main(["readme", "--summary", str(tmp_path / "none.json"), "--readme", str(page)]) == 2
    assert "no summary" in capsys.readouterr().err
