"""Read and write the experiment tables and the network definition of the original data.

An experiment table (``sent-1-5_lab_aff_bag.txt``, ``sent-all_mllr3_aff_bag.txt``) is tab-separated text:
a header naming the 8 affordance nodes and the 49 words, then one robot experiment with one verbal
description per line. Affordance columns hold a value (``tap``, ``circle``, …); a word column holds ``-``
(absent) or the word itself (present).

In memory it is a :class:`pandas.DataFrame` with one categorical column per node, in schema order, with
the categories in the value order of :mod:`glu.schema` (``sphere`` for the files' ``circle``; ``absent`` /
``present`` for words). Every problem with a file raises :class:`~glu.errors.DataError` naming the file,
the line, the column and what is allowed.
"""

from __future__ import annotations

import csv
import io
import os
import re
from pathlib import Path

import numpy as np
import pandas as pd

from glu.errors import DataError
from glu.files import atomic_write_text, read_bytes
from glu.schema import FILE_ALIASES, WORD_VALUES, Schema, default_schema

ABSENT_MARK = "-"


def _lines(text: str) -> list[str]:
    """The lines of a table, split where pandas splits them (``\\n``, ``\\r\\n`` or ``\\r``): not also at the
    characters :meth:`str.splitlines` takes for line breaks (form feed, U+2028, …), which in a cell would put
    the error on the wrong line."""
    return re.split(r"\r\n|\r|\n", text)


def _read_text(path: Path) -> str:
    """Read a whole file as UTF-8 text, with a clear error for missing files and bad encodings."""
    raw = read_bytes(path)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        line = raw[: e.start].count(b"\n") + 1
        raise DataError(
            f"{path}:{line}: not UTF-8 text (byte 0x{raw[e.start]:02x}); expected tab-separated UTF-8 text"
        ) from None
    if "\x00" in text:
        line = text[: text.index("\x00")].count("\n") + 1
        raise DataError(f"{path}:{line}: binary data (NUL byte); expected tab-separated UTF-8 text")
    if text.startswith("\ufeff"):
        text = text[1:]
    return text


def _file_values(node: str, schema: Schema) -> list[str]:
    """The values of ``node`` as the original files write them: ``-`` and the word itself for a word node,
    an affordance node's first alias (``circle`` for glu's ``sphere``) where it has one."""
    if node in schema.word_nodes:
        return [ABSENT_MARK, node]
    alias_of: dict[str, str] = {}
    for alias, value in schema.aliases.get(node, {}).items():
        alias_of.setdefault(value, alias)
    return [alias_of.get(v, v) for v in schema.values_of(node)]


def read_experiments(path: str | os.PathLike, schema: Schema | None = None) -> pd.DataFrame:
    """Read an experiment table into a DataFrame of categorical columns, validating every cell.

    Parameters
    ----------
    path : the tab-separated table (header line, then one experiment per line)
    schema : nodes and values to expect; default :func:`glu.schema.default_schema`

    Returns
    -------
    DataFrame, shape (n_experiments, n_nodes), columns in schema order, categorical dtype whose categories
    are the node's values in order. ``df.attrs["path"]`` holds the file name.
    """
    path = Path(path)
    schema = schema or default_schema()
    text = _read_text(path)
    lines = _lines(text)
    while lines and not lines[-1].strip():
        lines.pop()
    if not lines:
        raise DataError(f"{path}: empty file; expected a header line and at least one experiment")
    header = [h.strip() for h in lines[0].split("\t")]
    _check_header(path, header, schema)
    if len(lines) == 1:
        raise DataError(f"{path}: no experiments after the header line")
    ncol = len(header)
    counts = np.fromiter((ln.count("\t") for ln in lines[1:]), dtype=np.int64, count=len(lines) - 1)
    bad = np.flatnonzero(counts != ncol - 1)
    if bad.size:
        i = int(bad[0])
        if not lines[i + 1].strip():
            raise DataError(f"{path}:{i + 2}: empty line inside the table; every line is one experiment")
        raise DataError(
            f"{path}:{i + 2}: {counts[i] + 1} columns, expected {ncol} (as in the header)"
            + (f"; {bad.size} such lines in all" if bad.size > 1 else "")
        )
    try:
        raw = pd.read_csv(
            io.StringIO("\n".join(lines[1:])),
            sep="\t",
            header=None,
            names=list(range(ncol)),
            dtype=str,
            na_filter=False,
            quoting=3,  # csv.QUOTE_NONE: quotes are ordinary characters here
            engine="c",
        )
    except (pd.errors.ParserError, ValueError) as e:  # pragma: no cover - counts were checked above
        raise DataError(f"{path}: cannot parse the table ({e})") from None
    columns: dict[str, pd.Categorical] = {}
    for j, name in enumerate(header):
        columns[name] = _parse_column(path, f"column {j + 1} ({name})", name, raw[j], schema)
    df = pd.DataFrame({node: columns[node] for node in schema.nodes})
    df.attrs["path"] = str(path)
    return df


def _check_header(path: Path, header: list[str], schema: Schema) -> None:
    seen: dict[str, int] = {}
    for j, h in enumerate(header, start=1):
        if h in seen:
            raise DataError(f"{path}:1: header name {h!r} appears twice (columns {seen[h]} and {j})")
        seen[h] = j
        if h not in schema.values:
            what = "empty header name" if not h else f"unknown header name {h!r}"
            raise DataError(
                f"{path}:1: column {j}: {what}; allowed: the nodes "
                f"{', '.join(schema.affordance_nodes)} and the {len(schema.word_nodes)} words"
            )
    missing = [n for n in schema.nodes if n not in seen]
    if missing:
        shown = ", ".join(missing[:10]) + (" …" if len(missing) > 10 else "")
        raise DataError(f"{path}:1: header lacks {len(missing)} node(s): {shown}")


def _parse_column(
    path: Path, where: str, name: str, col: pd.Series, schema: Schema, count_bad: bool = True
) -> pd.Categorical:
    """The categorical column of node ``name`` from the file's cells (affordance values stripped, aliases
    accepted); DataError naming the line and ``where`` (the column) at the first cell that is not allowed,
    with how many there are when ``count_bad``."""
    values = schema.values_of(name)
    if name in schema.word_nodes:
        file_cats = _file_values(name, schema)
        allowed = f"'-' or the word {name!r} itself"
    else:
        aliases = schema.aliases.get(name, {})
        col = col.str.strip()
        if aliases:
            col = col.replace(dict(aliases))
        file_cats = list(values)
        allowed = ", ".join(values)
    codes = pd.Index(file_cats).get_indexer(col)
    bad = np.flatnonzero(codes < 0)
    if bad.size:
        i = int(bad[0])
        shown = col.iloc[i]
        raise DataError(
            f"{path}:{i + 2}: {where}: value {shown!r} is not allowed; allowed: {allowed}"
            + (f" ({bad.size} bad cells in this column)" if count_bad and bad.size > 1 else "")
        )
    return pd.Categorical.from_codes(codes, categories=list(values))


def write_experiments(df: pd.DataFrame, path: str | os.PathLike, schema: Schema | None = None) -> Path:
    """Write a table in the original file format (atomically: a temporary file moved into place)."""
    schema = schema or default_schema()
    path = Path(path)
    out = {}
    for node in schema.nodes:
        codes = pd.Index(schema.values_of(node)).get_indexer(df[node].astype(object))
        if (codes < 0).any():
            raise DataError(f"column {node}: values outside {schema.values_of(node)}")
        out[node] = np.array(_file_values(node, schema), dtype=object)[codes]
    text = pd.DataFrame(out).to_csv(sep="\t", index=False, lineterminator="\n")
    atomic_write_text(path, text)
    return path


def read_network_definition(path: str | os.PathLike) -> Schema:
    """Read ``networkDefinition.txt`` (``node<TAB>value<TAB>value…`` per line) into a :class:`Schema`.

    A node whose values are ``-`` and its own name is a word node; the others are affordance nodes and
    must come first. Values are translated to glu names (``circle`` → ``sphere``, ``-``/word →
    ``absent``/``present``).
    """
    path = Path(path)
    text = _read_text(path)
    values: dict[str, tuple[str, ...]] = {}
    n_aff = 0
    for i, line in enumerate(_lines(text), start=1):
        if not line.strip():
            continue
        parts = [p.strip() for p in line.split("\t")]
        name, vals = parts[0], [v for v in parts[1:] if v]
        if not name or len(vals) < 2:
            raise DataError(f"{path}:{i}: expected a node name and at least two values separated by tabs")
        if name in values:
            raise DataError(f"{path}:{i}: node {name!r} defined twice")
        if len(set(vals)) != len(vals):
            raise DataError(f"{path}:{i}: node {name!r} lists a value twice")
        if vals == [ABSENT_MARK, name]:
            values[name] = WORD_VALUES
        else:
            if n_aff != len(values):
                raise DataError(f"{path}:{i}: affordance node {name!r} after word nodes; list them first")
            aliases = FILE_ALIASES.get(name, {})
            values[name] = tuple(aliases.get(v, v) for v in vals)
            n_aff += 1
    if not values:
        raise DataError(f"{path}: empty network definition")
    return Schema(values=values, n_affordance=n_aff, aliases=FILE_ALIASES)


def write_network_definition(schema: Schema, path: str | os.PathLike) -> Path:
    """Write a schema as ``networkDefinition.txt`` (file values: ``circle``, ``-``/word), atomically."""
    lines = ["\t".join([node, *_file_values(node, schema)]) for node in schema.nodes]
    return atomic_write_text(path, "\n".join(lines) + "\n")


# ------------------------------------------------------------------ your own experiments
DESCRIPTION_COLUMN = "description"
"""In an own experiments table: the spoken description, from which the word columns are made."""
_PRESENT = {"present", "1", "yes", "true"}
_ABSENT = {"absent", "0", "no", "false", "-"}


def read_experiment_table(path: str | os.PathLike, schema: Schema) -> pd.DataFrame:
    """Read your own robot experiments for a schema: ``.csv`` (comma) or ``.tsv`` (tab), a header line.

    One row per experiment: a column per affordance node of the schema holding one of its values, and
    either a column per word (``present``/``absent``, ``1``/``0``, or the word itself/``-`` as in the
    original files) or one ``description`` column with what was said (lower-cased, split at spaces and
    punctuation; a word of the vocabulary is present when it occurs, other words are ignored).

    Returns a DataFrame of categorical columns in schema order (as :func:`read_experiments`), with
    ``attrs["data_source"]`` naming the file (without its folder). Raises :class:`DataError` naming the
    file, the line and the column.
    """
    import re

    path = Path(path)
    sep = {".csv": ",", ".tsv": "\t"}.get(path.suffix.lower())
    if sep is None:
        raise DataError(f"{path}: an experiments table is .csv or .tsv")
    text = _read_text(path)
    try:
        raw = pd.read_csv(io.StringIO(text), sep=sep, dtype=str, keep_default_na=False, skipinitialspace=True)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, ValueError) as e:
        raise DataError(f"{path}: not a table with a header line ({e})".replace("\n", " ")) from None
    raw.columns = [str(c).strip() for c in raw.columns]
    header = [c.strip() for c in next(csv.reader(io.StringIO(text), delimiter=sep), [])]
    twice = next((c for i, c in enumerate(header) if c in header[:i]), None)
    if twice is not None:  # pandas would keep both, the second renamed "c.1": one would be ignored
        raise DataError(f"{path}:1: the column {twice!r} appears twice; each node and word has one column")
    if len(raw) == 0:
        raise DataError(f"{path}: no experiments after the header line")
    missing = [n for n in schema.affordance_nodes if n not in raw.columns]
    if missing:
        raise DataError(
            f"{path}:1: no column for the node(s) {', '.join(missing)}; columns: {', '.join(raw.columns)}"
        )
    columns: dict[str, pd.Categorical] = {}
    for n in schema.affordance_nodes:
        columns[n] = _parse_column(path, f"column {n}", n, raw[n], schema, count_bad=False)
    words = schema.word_nodes
    if all(w in raw.columns for w in words):
        for w in words:
            cell = raw[w].str.strip().str.lower()
            present = cell.isin(_PRESENT | {w})
            bad = np.flatnonzero(~present & ~cell.isin(_ABSENT))
            if bad.size:
                raise DataError(
                    f"{path}:{bad[0] + 2}: column {w}: {raw[w].iloc[bad[0]]!r}; allowed: "
                    f"present/absent, 1/0, {w}/-"
                )
            columns[w] = pd.Categorical.from_codes(
                present.to_numpy().astype(np.int8), categories=list(WORD_VALUES)
            )
    elif DESCRIPTION_COLUMN in raw.columns:
        tokens = [set(re.findall(r"[^\W\d_]+(?:'[^\W\d_]+)?", s.lower())) for s in raw[DESCRIPTION_COLUMN]]
        for w in words:
            present = np.fromiter((w in t for t in tokens), dtype=np.int8, count=len(tokens))
            columns[w] = pd.Categorical.from_codes(present, categories=list(WORD_VALUES))
    else:
        lacking = [w for w in words if w not in raw.columns][:5]
        raise DataError(
            f"{path}:1: give a column per word (lacking: {', '.join(lacking)}, …) or a "
            f"'{DESCRIPTION_COLUMN}' column with what was said"
        )
    df = pd.DataFrame(columns)
    df.attrs["data_source"] = f"experiments table {path.name} ({len(df)} experiments" + (
        f", schema {schema.name})" if schema.name else ")"
    )
    return df
