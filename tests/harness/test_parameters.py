"""Notebook parameters: read from each notebook's parameters cell (as papermill reads it) and checked."""

from __future__ import annotations

import ast

import jupytext
import papermill as pm
import pytest

from glu.errors import ParameterError
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
    nb.write_text("# %%\nx: int = 1\n")
    with pytest.raises(ParameterError, match="expected one cell tagged parameters, found 0"):
        read_spec(nb)
