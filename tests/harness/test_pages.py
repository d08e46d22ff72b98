"""The generated parts of the README and of docs/ are what the code writes, never typed by hand.

* the README's story table — from the notebooks' manifests (:mod:`glu.run.generated`);
* the command table of ``docs/cli.md`` — from the parser of ``glu``
  (:func:`glu.cli.readme_cmds.command_table`);
* the tables of ``docs/speed.md`` — from ``benchmarks/results/*.json`` (:mod:`glu.run.speed`), which every
  benchmark writes in one schema.

``glu readme`` rewrites them all; the results section has its own tests (``tests/harness/test_readme.py``).
"""

from __future__ import annotations

import argparse
import json
import re
from pathlib import Path

import pytest

from glu.cli import build_parser
from glu.cli.readme_cmds import COMMANDS_BEGIN, COMMANDS_END, command_table
from glu.errors import DataError
from glu.run import generated, speed
from glu.run.manifest import Manifest

ROOT = Path(__file__).resolve().parents[2]


def _read(path: str) -> str:
    return (ROOT / path).read_text(encoding="utf-8")


def test_the_readme_story_table_is_written_from_the_manifests():
    table = generated.section(_read("README.md"), generated.STORY_BEGIN, generated.STORY_END)
    assert table == generated.story_table(generated.manifests()), "README.md: run `glu readme`"


def test_the_story_table_has_a_row_per_notebook_with_its_about_and_figures():
    notebooks = sorted(p.stem for p in (ROOT / "notebooks").glob("[0-9][0-9]_*.py"))
    table = generated.section(_read("README.md"), generated.STORY_BEGIN, generated.STORY_END)
    rows = table.splitlines()[2:]
    assert [re.match(r"\| `([^`]+)` \|", r).group(1) for r in rows] == notebooks
    # one row written independently of the writer, from a manifest made up here
    m = Manifest("07_x", "a | b, and more", figures=("f1", "f2"))
    assert generated.story_table([m]).splitlines()[2] == "| `07_x` | a \\| b, and more | `f1`, `f2` |"


def test_the_command_table_lists_every_command_of_the_parser():
    page = _read("docs/cli.md")
    assert generated.section(page, COMMANDS_BEGIN, COMMANDS_END, "docs/cli.md") == command_table(), (
        "docs/cli.md: run `glu readme`"
    )
    commands = set()

    def walk(parser: argparse.ArgumentParser, path: tuple[str, ...]) -> None:
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, sub in action.choices.items():
                    commands.add(" ".join((*path, name)))
                    walk(sub, (*path, name))

    walk(build_parser(), ())
    listed = set(re.findall(r"(?m)^\| `glu ([^`]+)` \|", page))
    assert listed == commands and len(commands) > 20


def test_the_speed_page_is_written_from_the_benchmarks_results():
    page = _read("docs/speed.md")
    assert generated.section(page, speed.BEGIN, speed.END, "docs/speed.md") == speed.render(
        speed.load_results()
    ), "docs/speed.md: run `glu readme`"


def test_every_benchmark_reports_in_the_one_schema():
    benchmarks = sorted((ROOT / "benchmarks").glob("bench_*.py"))
    assert len(benchmarks) >= 9
    silent = [b.name for b in benchmarks if not re.search(r"(?m)^\s+report\(", b.read_text(encoding="utf-8"))]
    assert not silent, f"benchmarks that do not write their results with timing.report: {silent}"
    results = speed.load_results()  # every file checked against the schema
    names = {d["benchmark"] for d in results}
    assert names <= {b.stem.removeprefix("bench_") for b in benchmarks}
    assert all(d["rows"] for d in results)


def test_the_speed_tables_show_each_row_of_a_result_file(tmp_path):
    doc = {
        "schema": 1,
        "benchmark": "demo",
        "what": "a made-up benchmark",
        "command": "python benchmarks/bench_demo.py",
        "machine": "2 cores",
        "date": "2026-01-01",
        "notes": ["a note"],
        "rows": [
            {
                "name": "one query",
                "what": "",
                "glu_s": 2.5e-5,
                "reference": "pgmpy",
                "reference_s": 5e-4,
                "ratio": 20.0,
                "target": "≤ 50 µs",
                "met": True,
            },
            {
                "name": "a cold start",
                "what": "in a fresh process",
                "glu_s": 1.5,
                "reference": None,
                "reference_s": None,
                "ratio": None,
                "target": "≤ 1 s",
                "met": False,
            },
        ],
    }
    (tmp_path / "demo.json").write_text(json.dumps(doc))
    text = speed.render(speed.load_results(tmp_path))
    assert text.startswith(
        "## demo\n\nA made-up benchmark: `python benchmarks/bench_demo.py`, 2026-01-01; 2 cores."
    )
    assert "| one query | 25.0 µs | pgmpy: 500.0 µs | 20.0× | ≤ 50 µs: met |" in text
    assert "| a cold start — *in a fresh process* | 1.50 s | — | — | ≤ 1 s: **missed** |" in text
    assert text.endswith("* a note")
    del doc["rows"][0]["met"]
    (tmp_path / "demo.json").write_text(json.dumps(doc))
    with pytest.raises(DataError, match="demo.json: row 0 lacks met"):
        speed.load_results(tmp_path)
    (tmp_path / "demo.json").write_text(json.dumps({"rows": []}))
    with pytest.raises(DataError, match="not in the benchmarks' schema"):
        speed.load_results(tmp_path)


def test_a_generated_section_is_replaced_between_its_markers_only(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("# t\n\n<!-- B -->\nold\n<!-- E -->\n\ntail\n")
    assert generated.replace_section(page, "<!-- B -->", "<!-- E -->", "new\n")
    assert page.read_text() == "# t\n\n<!-- B -->\nnew\n<!-- E -->\n\ntail\n"
    assert not generated.replace_section(page, "<!-- B -->", "<!-- E -->", "new")
    page.write_text("<!-- E -->\n<!-- B -->\n")
    with pytest.raises(DataError, match="expected one generated section"):
        generated.section(page.read_text(), "<!-- B -->", "<!-- E -->")


def test_the_readme_stays_a_front_page():
    lines = _read("README.md").splitlines()
    assert len(lines) <= 250, f"README.md has {len(lines)} lines; move detail into docs/"
    assert lines[2:6] == [
        "```bash",
        "make reproduce   # fresh machine: create .venv, install glu, run every notebook → results/, "
        "recordings/, build/",
        "make test        # fresh machine: create .venv, install glu and its test tools, lint (ruff), "
        "run the test suite",
        "```",
    ]


def test_a_folder_without_notebooks_or_readable_results_is_refused(tmp_path):
    with pytest.raises(DataError, match="no notebooks NN_name.py in"):
        generated.manifests(tmp_path)
    with pytest.raises(DataError, match="installed, not a source checkout"):
        speed.load_results(None)
    (tmp_path / "demo.json").write_text("{not json")
    with pytest.raises(DataError, match="demo.json: not readable benchmark results"):
        speed.load_results(tmp_path)


def test_the_other_pages_are_checked_then_rewritten(tmp_path, monkeypatch, capsys):
    from glu.cli import readme_cmds
    from glu.run import readme

    page = tmp_path / "guide" / "page.txt"
    page.parent.mkdir()
    page.write_text("<!-- B -->\nold\n<!-- E -->\n")
    monkeypatch.setattr(readme, "README", tmp_path / "README.md")
    monkeypatch.setattr(readme_cmds, "_pages", lambda: [(page, "<!-- B -->", "<!-- E -->", lambda: "new")])
    args = argparse.Namespace(readme=tmp_path / "README.md", check=True)
    assert readme_cmds._other_pages(args) is True
    assert "guide/page.txt: a generated section is out of date" in capsys.readouterr().err
    assert page.read_text() == "<!-- B -->\nold\n<!-- E -->\n"
    args.check = False
    assert readme_cmds._other_pages(args) is False
    assert capsys.readouterr().out == "guide/page.txt: generated section updated\n"
    assert page.read_text() == "<!-- B -->\nnew\n<!-- E -->\n"
    args.check = True
    assert readme_cmds._other_pages(args) is False


def test_readme_without_a_checkout_asks_for_its_files(tmp_path, monkeypatch, capsys):
    from glu.cli import main
    from glu.run import readme

    monkeypatch.setattr(readme, "SUMMARY", None)
    assert main(["readme", "--readme", str(tmp_path / "README.md")]) == 2
    assert capsys.readouterr().err == (
        "glu readme: error: glu is installed, not a source checkout: "
        "give --readme README.md and --summary FILE\n"
    )
