"""Experiment tables and the network definition: loading the real files, and clear errors for bad ones."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from glu.data import read_experiments, read_network_definition, synthesize_experiments, write_experiments
from glu.errors import DataError
from glu.schema import AFFORDANCE_VALUES, WORDS, default_schema

HEADER = "\t".join([*AFFORDANCE_VALUES, *WORDS])


def _row(**overrides: str) -> str:
    cells = {
        "Action": "tap",
        "Color": "blue",
        "Shape": "circle",
        "Size": "big",
        "ObjVel": "fast",
        "ObjHandVel": "fast",
        "HandVel": "fast",
        "Contact": "short",
    }
    cells.update({w: "-" for w in WORDS})
    cells.update(overrides)
    return "\t".join(cells[k] for k in [*AFFORDANCE_VALUES, *WORDS])


def _write(tmp_path: Path, text: str | bytes, name: str = "table.txt") -> Path:
    p = tmp_path / name
    p.write_bytes(text if isinstance(text, bytes) else text.encode())
    return p


# ---------------------------------------------------------------- the files of a data folder
@pytest.mark.parametrize("words", ["lab", "asr"])
def test_tables_load_with_ordered_categories(source, words):
    path = source.experiments_file(words)
    df = read_experiments(path)
    assert df.shape == (1270, 57)
    assert list(df.columns) == [*AFFORDANCE_VALUES, *WORDS]
    for node, values in AFFORDANCE_VALUES.items():
        assert list(df[node].cat.categories) == list(values)
    assert set(df["Shape"]) == {"sphere", "box"}
    # independent check of a few cells against the raw text
    lines = path.read_text().splitlines()
    header = lines[0].split("\t")
    for i in (0, 500, 1269):
        raw = lines[i + 1].split("\t")
        for j in (0, 2, 4, 19, 44):
            expected = raw[j]
            if header[j] == "Shape":
                expected = {"circle": "sphere"}.get(expected, expected)
            elif header[j] in WORDS:
                expected = "absent" if expected == "-" else "present"
            assert df.iloc[i][header[j]] == expected


def test_network_definition_matches_schema(source):
    schema = read_network_definition(source.network_definition())
    ref = default_schema()
    assert schema.nodes == ref.nodes
    assert dict(schema.values) == dict(ref.values)
    assert schema.n_affordance == 8


# ---------------------------------------------------------------- errors
def test_unknown_value_names_file_line_column_and_allowed(tmp_path):
    p = _write(tmp_path, "\n".join([HEADER, _row(), _row(Size="huge")]) + "\n")
    with pytest.raises(DataError) as e:
        read_experiments(p)
    msg = str(e.value)
    assert f"{p}:3:" in msg and "column 4 (Size)" in msg and "'huge'" in msg
    assert "small, medium, big" in msg


def test_word_column_holding_another_word(tmp_path):
    p = _write(tmp_path, "\n".join([HEADER, _row(taps="tapped")]) + "\n")
    with pytest.raises(
        DataError,
        match=r":2: column \d+ \(taps\): value 'tapped' is not allowed; allowed: '-' or the word 'taps'",
    ):
        read_experiments(p)


def test_wrong_number_of_columns(tmp_path):
    p = _write(tmp_path, "\n".join([HEADER, _row(), _row() + "\textra"]) + "\n")
    with pytest.raises(DataError, match=r":3: 58 columns, expected 57"):
        read_experiments(p)
    p = _write(tmp_path, "\n".join([HEADER, _row().rsplit("\t", 3)[0]]) + "\n")
    with pytest.raises(DataError, match=r":2: 54 columns, expected 57"):
        read_experiments(p)


def test_missing_and_duplicated_header_names(tmp_path):
    cols = HEADER.split("\t")
    dup = "\t".join(cols[:-1] + ["taps"])
    p = _write(tmp_path, dup + "\n" + _row() + "\n")
    with pytest.raises(DataError, match=r":1: header name 'taps' appears twice \(columns 19 and 57\)"):
        read_experiments(p)
    missing = "\t".join(cols[:-1])
    p = _write(tmp_path, missing + "\n" + "\t".join(_row().split("\t")[:-1]) + "\n")
    with pytest.raises(DataError, match=r":1: header lacks 1 node\(s\): falling"):
        read_experiments(p)
    p = _write(tmp_path, HEADER.replace("Contact", "Contakt") + "\n" + _row() + "\n")
    with pytest.raises(DataError, match=r"column 8: unknown header name 'Contakt'"):
        read_experiments(p)


def test_empty_file_header_only_and_blank_line(tmp_path):
    with pytest.raises(DataError, match="empty file"):
        read_experiments(_write(tmp_path, ""))
    with pytest.raises(DataError, match="no experiments after the header"):
        read_experiments(_write(tmp_path, HEADER + "\n"))
    with pytest.raises(DataError, match=r":3: empty line inside the table"):
        read_experiments(_write(tmp_path, "\n".join([HEADER, _row(), "", _row()]) + "\n"))


@pytest.mark.parametrize("char", ["\x0b", "\x0c", "\x1c", "\x1e", "\x85", "\u2028", "\u2029"])
def test_a_character_other_than_a_newline_is_a_bad_cell_on_its_own_line(tmp_path, char):
    """Characters str.splitlines takes for line breaks are cells' characters here: one in a word cell of
    line 10 is that cell's error, on line 10 (it was "2 columns, expected 57 …; 2 such lines in all")."""
    rows = [_row() for _ in range(12)]
    rows[8] = rows[8].replace("\t-", "\t-" + char, 1)  # line 10: the header, then rows 1 … 9
    p = _write(tmp_path, "\r\n".join([HEADER, *rows]) + "\r\n")
    with pytest.raises(DataError, match=r":10: column \d+ \(\w+\): value '-.+' is not allowed") as e:
        read_experiments(p)
    assert "columns" not in str(e.value)
    good = _write(tmp_path, "\r".join([HEADER, *[_row() for _ in range(3)]]) + "\r", "mac.txt")
    assert len(read_experiments(good)) == 3  # lines ended by \r alone are still lines


def test_binary_and_wrong_encoding(tmp_path):
    with pytest.raises(DataError, match=r":2: not UTF-8 text \(byte 0xe9\)"):
        read_experiments(_write(tmp_path, (HEADER + "\n").encode() + "caf\xe9".encode("latin-1")))
    with pytest.raises(DataError, match="binary data"):
        read_experiments(_write(tmp_path, b"\x00\x01\x02\x03"))
    with pytest.raises(DataError, match="no such file"):
        read_experiments(tmp_path / "missing.txt")


def test_circle_alias_and_sphere_both_read_as_sphere(tmp_path):
    p = _write(tmp_path, "\n".join([HEADER, _row(Shape="circle"), _row(Shape="sphere")]) + "\n")
    assert list(read_experiments(p)["Shape"]) == ["sphere", "sphere"]


def test_write_then_read_round_trip(tmp_path):
    df = synthesize_experiments(300, seed=3)
    p = write_experiments(df, tmp_path / "t.txt")
    text = p.read_text().splitlines()
    assert text[0] == HEADER
    assert "circle" in text[1] + text[2] + text[3] + text[4] or "box" in text[1]
    back = read_experiments(p)
    pd.testing.assert_frame_equal(back, df, check_like=False)


# ---------------------------------------------------------------- property-based: never a traceback
GOOD = "\n".join([HEADER, _row(), _row(Action="grasp", Shape="box"), _row(Action="touch", the="the")]) + "\n"


@st.composite
def corrupted(draw):
    data = bytearray(GOOD.encode())
    kind = draw(st.sampled_from(["truncate", "junk", "replace", "encoding", "delete_tab", "insert"]))
    pos = draw(st.integers(0, len(data) - 1))
    if kind == "truncate":
        data = data[:pos]
    elif kind == "junk":
        data[pos:pos] = draw(st.binary(min_size=1, max_size=20))
    elif kind == "replace":
        data[pos] = draw(st.integers(0, 255))
    elif kind == "encoding":
        data = GOOD.encode("utf-16") if draw(st.booleans()) else GOOD.replace("tap", "táp").encode("latin-1")
    elif kind == "delete_tab":
        tabs = [i for i, b in enumerate(data) if b == 9]
        del data[tabs[pos % len(tabs)]]
    else:
        data[pos:pos] = draw(st.text(min_size=1, max_size=10)).encode()
    return bytes(data)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(blob=corrupted())
def test_corrupted_files_give_data_error_or_a_complete_valid_table(tmp_path, blob):
    p = _write(tmp_path, blob, "fuzz.txt")
    try:
        df = read_experiments(p)
    except DataError as e:
        msg = str(e)
        assert str(p) in msg and "\n" not in msg
        assert re.search(rf"{re.escape(str(p))}(:\d+)?:", msg)
        return
    # accepted: then every row is complete and every value valid
    assert df.shape[1] == 57 and len(df) >= 1
    assert not df.isna().any().any()
    for node in df.columns:
        assert np.all(np.asarray(df[node].cat.codes) >= 0)


def test_a_byte_order_mark_before_the_header_is_ignored(tmp_path):
    p = _write(tmp_path, "\ufeff" + "\n".join([HEADER, _row(Action="grasp")]) + "\n")
    assert list(read_experiments(p)["Action"]) == ["grasp"]


def test_writing_a_value_outside_the_schema_is_refused(tmp_path):
    df = synthesize_experiments(200, seed=1)
    df["Size"] = df["Size"].astype(str).replace({"big": "huge"})
    with pytest.raises(DataError, match=r"column Size: values outside \('small', 'medium', 'big'\)"):
        write_experiments(df, tmp_path / "t.txt")
    assert not (tmp_path / "t.txt").exists()


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("Action\tgrasp\n", ":1: expected a node name and at least two values"),
        ("Action\tgrasp\ttap\nAction\tgrasp\ttap\n", ":2: node 'Action' defined twice"),
        ("Action\tgrasp\tgrasp\n", ":1: node 'Action' lists a value twice"),
        (
            "Action\tgrasp\ttap\nball\t-\tball\nSize\tsmall\tbig\n",
            ":3: affordance node 'Size' after word nodes",
        ),
        ("\n\n", ": empty network definition"),
    ],
)
def test_malformed_network_definitions_name_the_line(tmp_path, text, message):
    p = _write(tmp_path, text, "networkDefinition.txt")
    with pytest.raises(DataError, match=re.escape(f"{p}{message}")):
        read_network_definition(p)


# ---------------------------------------------------------------- your own experiments
def _own(tmp_path: Path, name: str, rows: list[list[str]]) -> Path:
    sep = "\t" if name.endswith(".tsv") else ","
    return _write(tmp_path, "".join(sep.join(r) + "\n" for r in rows), name)


AFFORDANCES = ["tap", "blue", "sphere", "big", "fast", "fast", "fast", "short"]


def test_own_table_with_a_column_per_word(tmp_path):
    """Each word column may say present/absent, 1/0, yes/no, true/false, or the word itself/-."""
    from glu.data.tables import read_experiment_table

    spellings = [("present", "absent"), ("1", "0"), (" Yes", "no"), ("TRUE", "false"), ("{w}", "-")]
    rows = [[*AFFORDANCE_VALUES, *WORDS]]
    for k, (yes, no) in enumerate(spellings):
        rows.append([*AFFORDANCES, *((yes if j % 5 == k else no).format(w=w) for j, w in enumerate(WORDS))])
    df = read_experiment_table(_own(tmp_path, "own.tsv", rows), default_schema())
    assert (
        list(df.columns) == [*AFFORDANCE_VALUES, *WORDS]
        and "own.tsv (5 experiments" in df.attrs["data_source"]
    )
    for k in range(len(spellings)):
        said = [w for j, w in enumerate(WORDS) if j % 5 == k]
        assert [w for w in WORDS if df[w].iloc[k] == "present"] == said
    rows[3][8 + 2] = "maybe"
    with pytest.raises(
        DataError, match=f"own.tsv:4: column {WORDS[2]}: 'maybe'; allowed: present/absent, 1/0"
    ):
        read_experiment_table(_own(tmp_path, "own.tsv", rows), default_schema())


@pytest.mark.parametrize(
    ("name", "rows", "message"),
    [
        ("own.txt", [["Action"]], "own.txt: an experiments table is .csv or .tsv"),
        ("own.csv", [], "own.csv: not a table with a header line (No columns to parse from file)"),
        ("own.csv", [list(AFFORDANCE_VALUES)], "own.csv: no experiments after the header line"),
        (
            "own.csv",
            [[*AFFORDANCE_VALUES, WORDS[0]], [*AFFORDANCES, "1"]],
            "own.csv:1: give a column per word (lacking: ",
        ),
    ],
)
def test_own_tables_that_cannot_be_read(tmp_path, name, rows, message):
    from glu.data.tables import read_experiment_table

    with pytest.raises(DataError, match=re.escape(message)):
        read_experiment_table(_own(tmp_path, name, rows), default_schema())
