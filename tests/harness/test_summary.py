"""The run summary: which tables count as comparisons with a reference (written by
glu.run.summary.write_summary)."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from glu.run.summary import NotebookResult, write_summary


def _table(results, name, rows, **meta):
    path = results / f"{name}.json"
    path.write_text(
        json.dumps({"meta": {"name": name, "data_source": "synthetic data (seed 0)", **meta}, "rows": rows})
    )
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
        ),
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
    from glu.studies.replication import fusion

    alone = fusion.effect_prediction(zero_bn)
    versus = fusion.effect_prediction(zero_bn, reference=zero_bn)
    assert alone.attrs["parameters"]["reference"] is None and "difference" not in alone
    assert versus.attrs["parameters"]["reference"] == fusion.ORIGINAL_REFERENCE
    assert versus["difference"].abs().max() == 0.0  # the same model: no difference


def test_with_several_jobs_the_notebooks_that_took_longest_last_time_start_first(tmp_path):
    from pathlib import Path

    from glu.paths import OutputLayout
    from glu.run.reproduce import run_order
    from glu.run.summary import expected_seconds

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
    # nothing to go by (no summary, no declared times): the story's later notebooks start first
    assert [i for i, _ in run_order(notebooks, 2, {})] == [4, 3, 2, 1]
    assert [p.stem for _, p in run_order(notebooks, 1, expected_seconds(layout))] == [
        p.stem for p in notebooks
    ]
    (layout.results / "summary.json").write_text("{not json")  # unreadable: the project's summary, or none
    assert isinstance(expected_seconds(layout), dict)


_HEADER = """# ---
# jupyter:
#   glu:
#     expected_seconds: {}
#   jupytext:
#     formats: py:percent
# ---

# %% tags=["parameters"]
data: str = None  # data folder
"""


def test_a_first_run_starts_the_notebooks_that_declare_the_longest_times_first(tmp_path, monkeypatch):
    from glu.paths import OutputLayout
    from glu.run.reproduce import run_order
    from glu.run.summary import declared_seconds, expected_seconds

    project = OutputLayout.under(tmp_path / "project")  # the project's own folders, with no summary yet
    monkeypatch.setattr(OutputLayout, "project", classmethod(lambda cls: project))
    nbs = tmp_path / "nbs"
    nbs.mkdir()
    declared = {"01_a": "3", "02_b": "10", "03_c": "3.5", "04_d": "31", "05_e": "25"}
    for name, seconds in declared.items():
        (nbs / f"{name}.py").write_text(_HEADER.format(seconds))
    (nbs / "06_f.py").write_text(_HEADER.format("a while"))  # no usable time: starts first
    notebooks = sorted(nbs.glob("*.py"))
    layout = OutputLayout.at(tmp_path / "new-out")
    first = expected_seconds(layout, notebooks)
    assert first == {"01_a": 3.0, "02_b": 10.0, "03_c": 3.5, "04_d": 31.0, "05_e": 25.0}
    order = [p.stem for _, p in run_order(notebooks, 2, first)]
    assert order == ["06_f", "04_d", "05_e", "02_b", "03_c", "01_a"]

    # the project's last run wins over the declared times, and declared times fill in what it lacks
    write_summary(
        project.results,
        [NotebookResult("01_a", "ok", 40.0), NotebookResult("04_d", "ok", 2.0)],
        "synthetic data",
        False,
        42.0,
    )
    assert expected_seconds(layout, notebooks) == {**first, "01_a": 40.0, "04_d": 2.0}
    assert [p.stem for _, p in run_order(notebooks, 2, expected_seconds(layout, notebooks))][:3] == [
        "06_f",
        "01_a",
        "05_e",
    ]
    # and this output's own last run wins over the project's
    layout.results.mkdir(parents=True)
    write_summary(layout.results, [NotebookResult("02_b", "ok", 99.0)], "synthetic data", False, 99.0)
    assert expected_seconds(layout, notebooks) == {**first, "02_b": 99.0}

    # an installed package has no project folders: the declared times still count
    from glu.errors import OutputError

    def installed(cls):
        raise OutputError("glu is installed, not a source checkout")

    monkeypatch.setattr(OutputLayout, "project", classmethod(installed))
    assert expected_seconds(OutputLayout.at(tmp_path / "other"), notebooks) == first

    odd = (
        "# %% no header\n",
        "# ---\n# jupyter:\n#   kernelspec: {}\n# ---\n",
        "# ---\n# : [\n# ---\n",
        _HEADER.format("true"),
        _HEADER.format("-1"),
        _HEADER.format(".nan"),
    )
    for text in odd:
        (nbs / "odd.py").write_text(text)
        assert declared_seconds(nbs / "odd.py") is None, text
    assert declared_seconds(nbs / "missing.py") is None


def test_every_notebook_declares_its_time_and_a_first_run_starts_the_long_ones_first(tmp_path, monkeypatch):
    from glu.paths import OutputLayout
    from glu.run.reproduce import list_notebooks, run_order
    from glu.run.summary import declared_seconds, expected_seconds

    monkeypatch.setattr(OutputLayout, "project", classmethod(lambda cls: OutputLayout.under(tmp_path / "p")))
    notebooks = list_notebooks()
    declared = {nb.stem: declared_seconds(nb) for nb in notebooks}
    assert all(s is not None and s > 0 for s in declared.values()), declared
    first = expected_seconds(OutputLayout.at(tmp_path / "out"), notebooks)  # a fresh clone, a new --out
    assert first == declared
    order = [p.stem for _, p in run_order(notebooks, 2, first)]
    longest = sorted(declared, key=declared.__getitem__)[-2:]
    assert set(order[:2]) == set(longest)  # the two longest, together, one per core
    assert order.index("02_hmm_training") < len(order) // 2  # never left for last, one core idle
    assert [declared[n] for n in order] == sorted(declared.values(), reverse=True)


def test_a_quick_runs_times_do_not_order_a_full_run(tmp_path, monkeypatch):
    from glu.paths import OutputLayout
    from glu.run.summary import expected_seconds

    project = OutputLayout.under(tmp_path / "project")
    monkeypatch.setattr(OutputLayout, "project", classmethod(lambda cls: project))
    layout = OutputLayout.at(tmp_path / "out")
    layout.results.mkdir(parents=True)
    write_summary(layout.results, [NotebookResult("01_a", "ok", 2.0)], "synthetic data", True, 3.0)
    assert expected_seconds(layout, quick=True) == {"01_a": 2.0}
    assert expected_seconds(layout, quick=False) == {}  # the quick summary is skipped: no times at all


def _long_csv_by_iterrows(summary):
    """The long format as first written: one dict per cell from DataFrame.iterrows."""
    import pandas as pd

    rows = []
    for name, table in summary["tables"].items():
        for i, row in pd.DataFrame(table["rows"]).iterrows():
            for col, val in row.items():
                rows.append({"table": name, "row": i, "column": col, "value": val})
    return pd.DataFrame(rows).to_csv(index=False, lineterminator="\n")


def test_summary_csv_is_the_cell_by_cell_long_format():
    """Random tables of every kind the notebooks write: ints only (kept as ints), ints and floats (all
    floats, as iterrows gives them), strings and booleans mixed in, None and NaN, empty tables."""
    import numpy as np

    from glu.run.summary import summary_csv

    rng = np.random.default_rng(3)
    kinds = [
        lambda r: int(r.integers(-5, 5)),
        lambda r: float(r.normal()),
        lambda r: bool(r.integers(2)),
        lambda r: ["tap", "grasp", "touch"][int(r.integers(3))],
        lambda r: None,
        lambda r: float("nan"),
        lambda r: 1e-300 * float(r.random()),
    ]
    for trial in range(40):
        tables = {}
        for t in range(int(rng.integers(1, 5))):
            cols = [
                kinds[int(k)]
                for k in rng.integers(0, 2 if trial % 3 == 0 else len(kinds), size=int(rng.integers(1, 5)))
            ]
            n = int(rng.integers(0, 6))
            tables[f"t{t}"] = {"rows": [{f"c{j}": f(rng) for j, f in enumerate(cols)} for _ in range(n)]}
        summary = {"tables": tables}
        assert summary_csv(summary) == _long_csv_by_iterrows(summary), tables
    assert summary_csv({"tables": {}}) == _long_csv_by_iterrows({"tables": {}})


GOOD = {
    "notebooks": [{"name": "01_a", "status": "ok", "seconds": 1.0}],
    "tables": {"t": {"meta": {}, "rows": []}},
}


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"notebooks": [{"name": "01_a", "status": 3}]}, "notebooks[0] (01_a): status or parameters of"),
        ({"notebooks": [{"name": "01_a", "parameters": [1]}]}, "notebooks[0] (01_a): status or parameters"),
        ({"figures": "a.png"}, "figures: expected a list, got str"),
        ({"figures_by_notebook": ["a.png"]}, "figures_by_notebook: expected a mapping, got list"),
        ({"recordings_by_notebook": {"r.rrd": "../x"}}, "recordings_by_notebook['r.rrd']: '../x' is not a"),
        ({"wall_time_s": "1 s"}, "wall_time_s is not a number"),
        ({"tables": {"t": [1, 2]}}, "tables['t']: not a table (its meta and rows)"),
        ({"tables": {"t": {"rows": []}}}, "tables['t']: not a table"),
    ],
)  # fmt: skip
def test_a_malformed_summary_is_refused_naming_its_field(change, message):
    from glu.run.summary import SummaryError, check_summary

    check_summary(GOOD)  # no figures, recordings or wall time: nothing to check there
    with pytest.raises(SummaryError) as e:
        check_summary({**GOOD, **change})
    assert str(e.value).startswith(message)


def test_a_partial_run_keeps_the_earlier_notebooks_of_the_same_data_and_mode(tmp_path):
    """collect_summary with the published summary: the notebooks not run keep their entries (tables,
    figures, recordings), those run replace theirs; a summary of other data keeps nothing."""
    from glu.run.summary import collect_summary

    results = tmp_path / "results"
    results.mkdir()
    new = _table(results, "t_b", [{"x": 2}], notebook="02_b")
    old_table = {"meta": {"name": "t_a", "notebook": "01_a"}, "rows": [{"x": 1}]}
    previous = {
        "data_source": "synthetic data",
        "quick": False,
        "notebooks": [{"name": "01_a", "status": "ok"}, {"name": "02_b", "status": "ok", "seconds": 9.0}],
        "tables": {
            "t_a": old_table,
            "t_b_old": {"meta": {"name": "t_b_old", "notebook": "02_b"}, "rows": []},
        },
        "figures_by_notebook": {"a.png": "01_a", "old_b.png": "02_b"},
        "recordings_by_notebook": {"a.rrd": "01_a"},
    }
    runs = [NotebookResult("02_b", "ok", 1.0, files=[new, str(tmp_path / "figures" / "b.png")])]
    summary = collect_summary(results, runs, "synthetic data", False, previous=previous)
    assert summary["ran"] == ["02_b"]
    assert summary["notebooks"] == [
        {"name": "01_a", "status": "ok"},
        {"name": "02_b", "status": "ok", "seconds": 1.0, "parameters": {}},
    ]
    assert list(summary["tables"]) == ["t_a", "t_b"] and summary["tables"]["t_a"] == old_table
    assert summary["figures_by_notebook"] == {"a.png": "01_a", "b.png": "02_b"}
    assert summary["recordings_by_notebook"] == {"a.rrd": "01_a"}
    other = collect_summary(results, runs, "real data", False, previous=previous)
    assert [nb["name"] for nb in other["notebooks"]] == ["02_b"] and list(other["tables"]) == ["t_b"]
