"""The run summary: which tables count as comparisons with a reference (written by glu.reproduce.write_summary)."""

from __future__ import annotations

import json

import pandas as pd

from glu.reproduce import NotebookResult, write_summary


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
