"""Notebook parameters: read from each notebook's parameters cell (as papermill reads it) and checked."""

from __future__ import annotations

import ast

import jupytext
import papermill as pm
import pytest

from glu.errors import OutputError, ParameterError
from glu.run.parameters import (
    CHOICES,
    RANGES,
    Parameter,
    check,
    choices,
    non_defaults,
    parse_value,
    read_spec,
)
from glu.run.reproduce import list_notebooks

NOTEBOOKS = list_notebooks()


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_the_declaration_is_what_papermill_reads(path):
    spec = read_spec(path)
    ref = pm.inspect_notebook(jupytext.read(path))  # papermill's own reading of the parameters cell
    assert list(spec) == list(ref)
    for name, p in spec.items():
        assert ast.literal_eval(ref[name]["default"]) == p.default, name  # papermill keeps the literal text
        assert p.type == ref[name]["inferred_type_name"], name
        assert p.help == ref[name]["help"], name
        if p.choices:
            defaults = p.default if isinstance(p.default, list) else [p.default]
            assert set(defaults) <= set(p.choices), f"{path.stem}: default of {name} is not among its choices"
        if p.range and p.type in ("int", "float"):
            assert p.range[0] <= p.default <= p.range[1], f"{path.stem}: default of {name} out of range"


def test_choices_come_from_the_package():
    from glu.bn.learning import UNSEEN_MODES
    from glu.bn.soft import SOFT_RULES
    from glu.gestures.calibration import READINGS
    from glu.gestures.invariants import FEATURE_NAMES
    from glu.studies.correspondence.experiment import STUDY_FEATURE_NAMES

    assert CHOICES["rule"] is SOFT_RULES and CHOICES["unseen_words"] is UNSEEN_MODES
    assert CHOICES["features"] is FEATURE_NAMES and choices()["feature_sets"] is STUDY_FEATURE_NAMES
    from glu.studies.corpus_evaluation.evaluation import INFERENCE_NETWORKS
    from glu.studies.episodes import ACTION_PRIORS

    assert choices()["action_prior"] == tuple(ACTION_PRIORS)
    assert choices()["inference_network"] == tuple(INFERENCE_NETWORKS)
    assert set(FEATURE_NAMES) < set(STUDY_FEATURE_NAMES) and {"body", "body+centred"} < set(
        STUDY_FEATURE_NAMES
    )
    assert CHOICES["p_hmm"] == tuple(READINGS)


def test_each_element_of_a_list_of_choices_is_checked():
    spec = {"feature_sets": Parameter("feature_sets", "list[str]", ["raw"], "feature sets")}
    assert check(spec, {"feature_sets": ["centred+rotated", "all"]}, "10_x")["feature_sets"][1] == "all"
    with pytest.raises(ParameterError, match="every element of feature_sets must be one of raw, centred"):
        check(spec, {"feature_sets": ["raw", "rotated+centred"]}, "10_x")  # names are canonical
    with pytest.raises(
        ParameterError, match=r"every element of feature_sets must be a string, got \['raw', 3\]"
    ):
        check(spec, {"feature_sets": ["raw", 3]}, "10_x")
    assert parse_value(spec["feature_sets"], "raw, 'centred'") == ["raw", "centred"]
    assert parse_value(spec["feature_sets"], "[]") == []


SPEC = {
    "rule": Parameter("rule", "str", "virtual", "soft rule"),
    "quick": Parameter("quick", "bool", False, "quick"),
    "step": Parameter("step", "int", 5, "every step frames"),
    "threshold": Parameter("threshold", "float", 0.02, "threshold"),
    "noise_levels": Parameter("noise_levels", "list[float]", [0.0, 0.1], "noise"),
    "data": Parameter("data", "str", None, "data folder"),
}


@pytest.mark.parametrize(
    ("values", "message"),
    [
        ({"rulez": "jeffrey"}, "unknown parameter 'rulez' (did you mean 'rule'?)"),
        ({"quick": "no"}, "quick must be True or False, got 'no'"),
        ({"quick": 1}, "quick must be True or False"),
        ({"threshold": "abc"}, "threshold must be a finite number, got 'abc'"),
        ({"threshold": float("nan")}, "threshold must be a finite number"),
        ({"threshold": 2.0}, "threshold must be in [0, 1], got 2.0"),
        ({"step": 2.5}, "step must be an integer"),
        ({"step": True}, "step must be an integer"),
        ({"step": 0}, "step must be in [1, 100000]"),
        ({"rule": "jefrey"}, "rule must be one of virtual, jeffrey; got 'jefrey'"),
        ({"rule": None}, "rule must be a str"),
        ({"rule": 5}, "rule must be a string, got 5"),
        ({"noise_levels": 0.1}, "noise_levels must be a list"),
        ({"noise_levels": [0.1, "x"]}, "noise_levels must be finite numbers"),
        ({"noise_levels": [0.1, 5.0]}, "noise_levels must be in [0, 1]"),
    ],
)
def test_bad_values_are_refused_in_one_line(values, message):
    with pytest.raises(ParameterError) as e:
        check(SPEC, values, "08_x")
    text = str(e.value)
    assert message in text and text.startswith("08_x: ") and "\n" not in text


def test_good_values_pass_and_defaults_fill_in():
    got = check(SPEC, {"rule": "jeffrey", "step": 2, "threshold": 1, "data": None}, "nb")
    assert got == {
        "rule": "jeffrey",
        "quick": False,
        "step": 2,
        "threshold": 1,
        "noise_levels": [0.0, 0.1],
        "data": None,
    }
    assert non_defaults(SPEC, got) == {"rule": "jeffrey", "step": 2, "threshold": 1}


@pytest.mark.parametrize(
    ("name", "text", "value"),
    [
        ("quick", "True", True),
        ("quick", "false", False),
        ("step", "7", 7),
        ("threshold", "0.5", 0.5),
        ("noise_levels", "[0, 0.05]", [0.0, 0.05]),
        ("noise_levels", "0.1,0.2", [0.1, 0.2]),
        ("rule", "jeffrey", "jeffrey"),
        ("data", "None", None),
    ],
)
def test_command_line_values_are_parsed_by_their_declared_type(name, text, value):
    assert parse_value(SPEC[name], text) == value


@pytest.mark.parametrize(
    ("name", "text"),
    [("quick", "no"), ("step", "five"), ("threshold", "abc"), ("rule", "jefrey"), ("noise_levels", "[0, x]")],
)
def test_command_line_values_that_do_not_parse_are_refused(name, text):
    with pytest.raises(ParameterError, match=f"{name}"):
        parse_value(SPEC[name], text)


def test_every_range_and_choice_names_a_declared_parameter():
    declared = {n for path in NOTEBOOKS for n in read_spec(path)}
    assert set(choices()) <= declared and set(RANGES) <= declared


def test_a_malformed_parameters_cell_is_refused(tmp_path):
    nb = tmp_path / "01_bad.py"
    nb.write_text('# %% tags=["parameters"]\nx = 1  # untyped\n')
    with pytest.raises(ParameterError, match="expected `name: type = value"):
        read_spec(nb)
    nb.write_text('# %% tags=["parameters"]\nx: dict = {}  # a dict\n')
    with pytest.raises(ParameterError, match="type 'dict' is not one of"):
        read_spec(nb)
    nb.write_text('# %% tags=["parameters"]\nx: int = len("ab")  # computed\n')
    with pytest.raises(
        ParameterError, match="01_bad.py, parameters cell line 1: the default of x is not a literal"
    ):
        read_spec(nb)
    nb.write_text("# %%\nx: int = 1\n")
    with pytest.raises(ParameterError, match="expected one cell tagged parameters, found 0"):
        read_spec(nb)


def test_a_notebook_run_as_a_plain_script_checks_its_parameters_and_says_its_line(tmp_path, capsys):
    """``start`` outside a kernel (a notebook's .py run by python): no injected names, the line printed."""
    from glu.data import resolve_data
    from glu.run.notebook import start

    out = start("03_bn_learning", {"data": "synthetic", "out_dir": str(tmp_path / "out")})
    source = resolve_data("synthetic")
    assert capsys.readouterr().out == (
        f"03_bn_learning · {source.describe()} ({source.reason()}) · default parameters\n"
    )
    assert out.layout.root == tmp_path / "out"
    with pytest.raises(ParameterError, match="03_bn_learning: unknown parameter 'sede'"):
        start("03_bn_learning", {"In": ["", "# Parameters\nsede = 1\n"], "data": "synthetic"})


def test_the_names_papermill_injected_are_read_from_the_kernels_history():
    from glu.run.notebook import injected_names

    assert injected_names({}) == [] and injected_names({"In": "not a list"}) == []
    assert injected_names({"In": ["", "x = 1", "# Parameters here"]}) == []  # by hand: no injected cell
    history = ["", "# Parameters\nseed = 3\nrule = 'jeffrey'\n", "x = 1", "# Parameters\nseed = 4\n"]
    assert injected_names({"In": history}) == ["seed"]  # the last one
    assert injected_names({"In": ["", "# Parameters\nseed = (\n"]}) == []  # a cell that did not run


def test_outside_a_kernel_a_figure_is_saved_not_shown_and_a_table_needs_a_name(tmp_path, capsys, monkeypatch):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import pandas as pd

    from glu.run import outputs
    from glu.run.notebook import start

    out = start("03_bn_learning", {"data": "synthetic", "out_dir": str(tmp_path / "out")})
    capsys.readouterr()
    fig, ax = plt.subplots()
    ax.plot([0, 1])
    out.figure(fig, "line")
    assert capsys.readouterr() == ("", "")
    assert (tmp_path / "out" / "figures" / "line.png").read_bytes()[:4] == b"\x89PNG"
    with pytest.raises(OutputError, match="a table needs a name"):
        out.table(pd.DataFrame({"x": [1]}))
    assert not (tmp_path / "out" / "results").exists() or not any((tmp_path / "out" / "results").iterdir())
    monkeypatch.setattr(outputs, "PACKAGES", ("numpy", "glu-no-such-package"))
    versions = outputs.package_versions()
    assert (
        versions["glu-no-such-package"] == "not installed"
        and versions["numpy"] == __import__("numpy").__version__
    )
