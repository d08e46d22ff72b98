"""How a notebook shows a result frame (glu.tidy.html_table): rounded for reading, whole on the page.

The expected cells are written out by hand from the rules of :func:`glu.tidy.decimals`, not produced by
the code under test.
"""

from __future__ import annotations

import re

import numpy as np
import pandas as pd

from glu.tidy import MISSING, decimals, html_table


def _rows(html: str) -> list[list[str]]:
    """The table's rows, each a list of its cells' text (header and body)."""
    rows = re.findall(r"<tr[^>]*>(.*?)</tr>", html, flags=re.S)
    return [
        [re.sub(r"<[^>]+>", "", c).strip() for c in re.findall(r"<t[hd][^>]*>(.*?)</t[hd]>", r, re.S)]
        for r in rows
    ]


def test_floats_are_rounded_by_their_size_and_missing_values_are_a_dash():
    df = pd.DataFrame(
        {
            "p": [0.0483, 1.0],  # up to 1: three decimals
            "nats": [-35.018895, 2.979782],  # below 100: two
            "frames": [94.0, 146.0],  # whole: none
            "big": [1234.56, np.nan],  # above 100: one; NaN: a dash
            "tiny": [2.04e-05, 1.8e-06],  # all below 0.01: three significant digits
        }
    )
    rows = _rows(html_table(df))
    assert rows[0] == ["p", "nats", "frames", "big", "tiny"]  # no 0 … n-1 index
    assert rows[1:] == [
        ["0.048", "-35.02", "94", "1234.6", "2.04e-05"],
        ["1.000", "2.98", "146", MISSING, "1.8e-06"],
    ]
    assert decimals(np.array([np.nan])) == 0


def test_an_estimate_and_its_interval_columns_become_one_cell_with_the_interval_under_it():
    df = pd.DataFrame(
        {
            "noise_m": [0.0, 0.05],
            "accuracy": [0.983, 0.883],
            "ci_low": [0.911, 0.778],
            "ci_high": [0.997, 0.942],
            "accuracy_tap": [1.0, 0.95],
            "ci_low_tap": [0.84, 0.76],
            "ci_high_tap": [1.0, 0.99],
        }
    )
    html = html_table(df)
    assert "ci_low" not in html and "ci_high" not in html
    assert '0.983<br><span class="glu-interval">[0.911, 0.997]</span>' in html
    assert '1.000<br><span class="glu-interval">[0.840, 1.000]</span>' in html  # up to 1: three decimals
    cells = pd.DataFrame({"s": ["0.76 [0.67, 0.84]", "plain text"]})
    assert '0.76<br><span class="glu-interval">[0.67, 0.84]</span>' in html_table(cells)


def test_text_is_escaped_and_may_wrap_and_a_named_index_is_kept():
    df = pd.DataFrame(
        {"recording": ["norobotview_tap_notable_seated_2", "<b>&"], "p_tap": [1.0, 0.5]},
        index=pd.Index(["a", "b"], name="seed"),
    )
    html = html_table(df)
    assert "norobotview_<wbr>tap_<wbr>notable_<wbr>seated_<wbr>2" in html and "&lt;b&gt;&amp;" in html
    assert "<b>" not in html and "p_<wbr>tap" in html
    rows = _rows(html)
    assert rows[1][0] == "seed" and [r[0] for r in rows[2:]] == ["a", "b"]  # the named index is shown


def test_a_pivot_with_two_header_rows_is_shown_whole():
    df = pd.DataFrame({"posture": ["seated", "standing"], "x": [-0.39, 0.28], "y": [-0.33, -0.96]})
    pivot = df.set_index("posture").agg(["min", "max"]).T  # not MultiIndex: plain
    multi = df.groupby("posture")[["x", "y"]].agg(["min", "max"])
    for frame in (pivot, multi):
        html = html_table(frame)
        assert html.count("<table") == 1 and "-0.390" in html


def test_missing_values_of_every_column_type_are_a_dash():
    """Text, categoricals and pandas' nullable types (whose missing value pd.NA was written "<NA>", an
    unknown HTML tag that the page showed as an empty cell)."""
    df = pd.DataFrame(
        {
            "text": ["a", None],
            "category": pd.Categorical(["b", None]),
            "string": pd.array(["c", None], dtype="string"),
            "count": pd.array([3, None], dtype="Int64"),
            "flag": pd.array([True, None], dtype="boolean"),
            "share": pd.array([0.25, None], dtype="Float64"),
        }
    )
    html = html_table(df)
    assert "NA" not in html
    assert _rows(html)[1:] == [["a", "b", "c", "3", "True", "0.250"], [MISSING] * 6]


def test_a_missing_estimate_keeps_its_interval_and_columns_not_all_floats_stay_apart():
    df = pd.DataFrame({"accuracy": [np.nan, 0.5], "ci_low": [0.1, 0.2], "ci_high": [0.9, 0.8]})
    assert _rows(html_table(df))[1:] == [[f"{MISSING}[0.100, 0.900]"], ["0.500[0.200, 0.800]"]]
    counts = pd.DataFrame({"n": [3, 4], "ci_low": [1.5, 2.5], "ci_high": [4.5, 5.5]})  # n: integers
    rows = _rows(html_table(counts))  # below 100: two decimals
    assert rows == [["n", "ci_low", "ci_high"], ["3", "1.50", "4.50"], ["4", "2.50", "5.50"]]


def test_parameters_are_stamped_as_json_ready_data():
    from glu.gestures.invariants import Invariants
    from glu.tidy import tidy

    df = tidy(
        pd.DataFrame({"x": [1]}),
        "exp",
        "synthetic",
        features=Invariants(("rotated", "centred")),
        seeds=(np.int64(1), 2),
        rule={"p": np.float64(0.5)},
    )
    assert df.attrs == {
        "experiment": "exp",
        "data_source": "synthetic",
        "parameters": {"features": "centred+rotated", "seeds": [1, 2], "rule": {"p": 0.5}},
    }
    assert (
        type(df.attrs["parameters"]["seeds"][0]) is int and type(df.attrs["parameters"]["rule"]["p"]) is float
    )
