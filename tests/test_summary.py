"""The run summary: which tables count as comparisons with a reference (written by glu.summary.write_summary)."""

from __future__ import annotations

import json

import pandas as pd

from glu.summary import NotebookResult, write_summary


def _table(results, name, rows, **meta):
    path = results / f"{name}.json"
    path.write_text(json.dumps({"meta": {"name": name, "data_source": "synthetic data (seed 0)", **meta},
                                "rows": rows}))  # fmt: skip
    return str(path)


def test_only_tables_that_declare_a_reference_are_comparisons(tmp_path):
    results = tmp_path / "results"
    results.mkdir()
    files = [
        _table(results, "declared_top", [{"p": 0.5, "difference": 0.25}], reference="TCDS 2020 Fig. 5"),
        _table(
            results,
            "declared_param",
            [{"difference": -0.5}, {"difference": 0.125}],
            parameters={"reference": "original model (BN_lab.mat)"},
        ),  # fmt: skip
        _table(results, "strategy_differences", [{"difference": 5.2}]),  # paired strategies: no reference
        _table(results, "declared_none", [{"difference": 3.0}], parameters={"reference": None}),
    ]
    summary = write_summary(
        results, [NotebookResult("nb", "ok", 1.0, files=files)], "synthetic data", True, 1.0
    )
    got = {
        c["table"]: (c["reference"], c["rows"], c["max_abs_difference"])
        for c in summary["comparison_with_reference"]
    }
    assert got == {
        "declared_top": ("TCDS 2020 Fig. 5", 1, 0.25),
        "declared_param": ("original model (BN_lab.mat)", 2, 0.5),
    }
    assert set(pd.read_csv(results / "summary.csv")["table"]) >= {"strategy_differences", "declared_none"}


def test_the_fusion_experiments_declare_the_original_model_only_when_given_it(zero_bn):
    from glu.experiments import fusion

    alone = fusion.effect_prediction(zero_bn)
    versus = fusion.effect_prediction(zero_bn, reference=zero_bn)
    assert alone.attrs["parameters"]["reference"] is None and "difference" not in alone
    assert versus.attrs["parameters"]["reference"] == fusion.ORIGINAL_REFERENCE
    assert versus["difference"].abs().max() == 0.0  # the same model: no difference


def test_with_several_jobs_the_notebooks_that_took_longest_last_time_start_first(tmp_path):
    from pathlib import Path

    from glu.paths import OutputLayout
    from glu.reproduce import run_order
    from glu.summary import expected_seconds

    layout = OutputLayout.at(tmp_path)
    layout.results.mkdir(parents=True)
    runs = [
        NotebookResult("01_a", "ok", 4.0),
        NotebookResult("02_b", "ok", 30.5),
        NotebookResult("03_c", "ok", 9.25),
    ]
    write_summary(layout.results, runs, "synthetic data", False, 31.0)
    assert expected_seconds(layout) == {"01_a": 4.0, "02_b": 30.5, "03_c": 9.25}
    notebooks = [Path(f"{n}.py") for n in ("01_a", "02_b", "03_c", "04_new")]
    order = run_order(notebooks, 2, expected_seconds(layout))
    assert [(i, p.stem) for i, p in order] == [(4, "04_new"), (2, "02_b"), (3, "03_c"), (1, "01_a")]
    # a fresh clone has no summary: the story's later notebooks (its larger studies) start first
    assert [i for i, _ in run_order(notebooks, 2, {})] == [4, 3, 2, 1]
    assert [p.stem for _, p in run_order(notebooks, 1, expected_seconds(layout))] == [
        p.stem for p in notebooks
    ]
    (layout.results / "summary.json").write_text("{not json")  # unreadable: the project's summary, or none
    assert isinstance(expected_seconds(layout), dict)
