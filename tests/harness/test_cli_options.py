"""One spelling per option, one help text per command, no markup in ``--help`` (issue 25).

Every test walks the real parser (:func:`glu.cli.build_parser`), so a new command or option is held to the
same rules without being listed here; the few exceptions are listed below, each with its reason.
"""

from __future__ import annotations

import argparse
import json
import re
from pathlib import Path

import pytest

from glu.cli import build_parser, main
from glu.cli.common import DATA_HELP, DeprecatedAlias, output_file, output_folder, output_image


def _commands(parser: argparse.ArgumentParser, path: tuple[str, ...] = ()):
    """(path, parser, help shown in the parent's list, is a leaf) for every command and command group."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            listed = {a.dest: a.help for a in action._choices_actions}
            for name, sub in action.choices.items():
                subs = [a for a in sub._actions if isinstance(a, argparse._SubParsersAction)]
                yield (*path, name), sub, listed.get(name), not subs
                yield from _commands(sub, (*path, name))


PARSER = build_parser()
COMMANDS = {" ".join(path): (sub, listed, leaf) for path, sub, listed, leaf in _commands(PARSER)}
LEAVES = {name: sub for name, (sub, _, leaf) in COMMANDS.items() if leaf}


def _visible(parser: argparse.ArgumentParser) -> list[argparse.Action]:
    """The options ``--help`` shows (not -h, not the hidden deprecated spellings)."""
    return [
        a
        for a in parser._actions
        if a.option_strings and a.help != argparse.SUPPRESS and not isinstance(a, argparse._HelpAction)
    ]


def _long(action: argparse.Action) -> str:
    return next(s for s in action.option_strings if s.startswith("--"))


# ------------------------------------------------------------------ one spelling per option

OUTPUT_TYPES = (output_file, output_folder, output_image)

OUTPUT_EXCEPTIONS = {
    ("gestures segment", "--plot"): "an extra image beside the segments printed on stdout, not the command's "
    "output; -o would suggest the printed result goes to the file",
    ("evaluate", "--save"): "a second, small copy of the tables notebook 11 reads, beside the sweep's own "
    "folder -o",
}
"""Options that write a file but are not the command's output (so not -o/--out)."""

NO_JSON = {
    "data fetch": "writes the data folder; prints one line saying how many files were verified",
    "data synth": "writes a data folder; prints one line saying what it wrote",
    "bn learn": "writes a model file (the result); prints one line saying what it wrote",
    "bn import": "writes a model file (the result); prints one line saying what it wrote",
    "bn export": "writes an exchange file (the result); prints one line saying what it wrote",
    "hmm train": "writes a recogniser file whose 'training' records every report it prints",
    "learn-gestures": "writes a recogniser file whose meta holds the label accuracy and rounds it prints",
    "reproduce": "its results are files; results/summary.json is their machine-readable summary",
    "readme": "writes README.md; --check answers with the exit status",
    "evaluate": "writes its tables to -o DIR; DIR/summary.json holds the overall results it prints",
    "corpus": "writes the episodes to a Parquet file; prints one line saying what it wrote",
    "learning-curves": "writes its tables to -o DIR; prints which files it wrote",
    "correspondence": "writes its tables to -o DIR with their key; prints one line saying what it wrote",
}
"""Commands without --json: their result is a file, and what they print is a receipt."""

SAME_NAME_DIFFERENT_KIND = {
    "--out": "a file for the commands that write one file, a folder for those that write several",
}
"""Options whose type may differ between commands, with the same meaning."""

OTHER_SPELLINGS = {
    "--out": ("--dest", "--output", "--output-dir", "--outdir", "--out-dir", "--to"),
    "--data": ("--data-dir", "--datadir", "--data-folder", "--dataset", "--source"),
    "--json": ("--as-json", "--json-output", "--format-json"),
    "--soft-rule": ("--rule", "--fusion-rule"),
    "--scheduler": ("--synchronous", "--cluster", "--address"),
    "--seed": ("--random-seed", "--rng-seed", "--random-state"),
    "--quiet": ("--silent", "--no-progress"),
    "--workers": ("--n-workers", "--nworkers"),
}
"""Spellings that would be a second name for an option glu already has (as a visible option)."""


def _kind(action: argparse.Action) -> tuple:
    return (
        type(action).__name__,
        getattr(action.type, "__name__", action.type),
        tuple(action.choices) if action.choices else None,
        action.nargs,
    )


def test_the_parser_has_every_command():
    assert {"data fetch", "gestures segment", "run", "reproduce", "query", "learning-curves"} <= set(LEAVES)


def test_every_output_option_is_o_out():
    for name, sub in LEAVES.items():
        outputs = [
            a
            for a in _visible(sub)
            if a.type in OUTPUT_TYPES
            or a.dest == "out"
            or set(a.option_strings) & set(OTHER_SPELLINGS["--out"])
        ]
        for a in outputs:
            if (name, _long(a)) in OUTPUT_EXCEPTIONS:
                continue
            assert a.option_strings == ["-o", "--out"], (
                f"glu {name} {'/'.join(a.option_strings)}: use -o/--out"
            )
        assert sum("-o" in a.option_strings for a in _visible(sub)) <= 1, name
    for name, option in OUTPUT_EXCEPTIONS:
        assert option in {s for a in _visible(LEAVES[name]) for s in a.option_strings}, (
            f"stale: {name} {option}"
        )


def test_one_spelling_for_one_meaning():
    kinds: dict[str, dict[tuple, list[str]]] = {}
    by_choices: dict[tuple, set[str]] = {}
    by_dest: dict[str, set[str]] = {}
    for name, sub in LEAVES.items():
        for a in _visible(sub):
            long = _long(a)
            kinds.setdefault(long, {}).setdefault(_kind(a), []).append(name)
            if a.choices and len(a.choices) > 1:
                by_choices.setdefault(tuple(a.choices), set()).add(long)
            by_dest.setdefault(a.dest, set()).add(long)
            for canonical, others in OTHER_SPELLINGS.items():
                assert long not in others, f"glu {name} {long}: glu spells this {canonical}"
            if long == "--data":
                assert a.help.startswith(DATA_HELP), f"glu {name} --data: use add_data_option"
    two_kinds = {k: v for k, v in kinds.items() if len(v) > 1 and k not in SAME_NAME_DIFFERENT_KIND}
    assert not two_kinds, f"one name, two kinds of value: {two_kinds}"
    assert not {c: n for c, n in by_choices.items() if len(n) > 1}, "the same choices under two names"
    assert not {d: n for d, n in by_dest.items() if len(n) > 1}, "one destination under two names"


def test_every_hidden_option_is_a_deprecated_spelling_that_still_works(capsys, tmp_path):
    hidden = {
        (name, a.option_strings[0]): a
        for name, sub in LEAVES.items()
        for a in sub._actions
        if a.option_strings and a.help == argparse.SUPPRESS
    }
    assert all(isinstance(a, DeprecatedAlias) for a in hidden.values()), hidden
    assert set(hidden) == {
        ("data fetch", "--dest"),
        ("anticipate", "--rule"),
        ("learn-gestures", "--words"),
        ("learning-curves", "--synchronous"),
    }
    learn = [
        "learn-gestures",
        "--episodes",
        "3",
        "--labels",
        "soft",
        "--words",
        "-o",
        str(tmp_path / "r.json"),
    ]
    cases = [
        (["data", "fetch", "--dest", str(tmp_path)], "out", tmp_path, "--dest is deprecated; use -o/--out"),
        (["anticipate", "--case", "box", "--rule", "jeffrey"], "soft_rule", "jeffrey", "use --soft-rule"),
        (learn, "with_words", True, "use --with-words"),
        (
            ["learning-curves", "--synchronous", "-o", str(tmp_path)],
            "scheduler",
            "synchronous",
            "synchronous",
        ),
    ]
    for argv, dest, value, message in cases:
        capsys.readouterr()
        args = PARSER.parse_args(argv)
        err = capsys.readouterr().err
        assert getattr(args, dest) == (Path(value) if isinstance(value, Path) else value)
        assert err.count("\n") == 1 and message in err, err


def test_every_command_that_prints_results_has_json():
    for name, sub in LEAVES.items():
        has = any("--json" in a.option_strings for a in _visible(sub))
        if name in NO_JSON:
            assert not has, f"glu {name} has --json now: take it off NO_JSON"
        else:
            assert has, (
                f"glu {name} prints results: give it --json (add_json_option), or say why not in NO_JSON"
            )
    assert set(NO_JSON) <= set(LEAVES), set(NO_JSON) - set(LEAVES)


# ------------------------------------------------------------------ help texts


def test_every_command_has_its_own_help_and_description():
    for kind, index in (("help", 1), ("description", 0)):
        seen: dict[str, str] = {}
        for name, entry in COMMANDS.items():
            text = entry[index] if kind == "help" else entry[0].description
            assert text and text.strip(), f"glu {name} has no {kind}"
            assert text not in seen, f"glu {name} and glu {seen[text]} share their {kind}"
            seen[text] = name
    epilogs = [sub.epilog for sub, _, _ in COMMANDS.values() if sub.epilog]
    assert len(epilogs) == len(set(epilogs))


MARKUP = re.compile(
    r"`|:(func|mod|class|meth|attr|data|obj|ref|doc):|\*\*|\]\(|^\s*[-*] \S|^#+ ", re.MULTILINE
)
"""reST and Markdown in help text: backticks, roles, bold, links, bullets, headings."""


@pytest.mark.parametrize("command", ["", *COMMANDS])
def test_help_renders_without_markup(command, capsys):
    with pytest.raises(SystemExit) as done:
        main([*command.split(), "--help"])
    out, err = capsys.readouterr()
    assert done.value.code == 0 and not err
    assert out.startswith("usage: glu")
    found = [m.group(0) for m in MARKUP.finditer(out)]
    assert not found, f"glu {command} --help shows markup {found}:\n{out}"


# ------------------------------------------------------------------ the new --json outputs


def _run(capsys, *argv) -> tuple[int, str, str]:
    capsys.readouterr()
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


def test_data_info_json_says_what_the_text_says(capsys, synthetic_folder):
    import collections
    import csv

    from glu.data.source import WORD_FILES

    status, out, _ = _run(capsys, "data", "info", "--data", synthetic_folder, "--json")
    assert status == 0
    info = json.loads(out)
    with open(synthetic_folder / WORD_FILES["lab"], newline="") as f:  # the table, read without glu
        header, *rows = list(csv.reader(f, delimiter="\t"))
    assert info["experiments"] == len(rows)
    assert list(info["values"]) == header[:8]
    for i, (node, counts) in enumerate(info["values"].items()):  # glu may rename values (circle: sphere)
        assert sorted(counts.values()) == sorted(collections.Counter(r[i] for r in rows).values()), node
    present = {w: sum(r[j] != "-" for r in rows) for j, w in enumerate(header) if j >= 8}  # "-": absent
    top = sorted(present.values(), reverse=True)[: len(info["most_frequent_words"])]
    assert sorted(info["most_frequent_words"].values(), reverse=True) == top
    status, text, _ = _run(capsys, "data", "info", "--data", synthetic_folder)
    for node, counts in info["values"].items():
        line = next(line for line in text.splitlines() if line.split() and line.split()[0] == node)
        assert line.split()[1:] == [f"{v}={c}" for v, c in counts.items()]
    assert f"experiments: {info['experiments']} " in text


def test_gestures_segment_json_lists_the_segments_the_text_prints(capsys, synthetic_folder):
    log = synthetic_folder / "gestures" / "tap1_hand" / "data.log"
    status, out, _ = _run(capsys, "gestures", "segment", log, "--json")
    assert status == 0
    seg = json.loads(out)
    status, text, _ = _run(capsys, "gestures", "segment", log)
    printed = re.findall(r"^\s+\d+\. frames (\d+):(\d+) \((\d+) frames", text, re.MULTILINE)
    assert printed and [(s["start"], s["end"], s["frames"]) for s in seg["segments"]] == [
        tuple(int(x) for x in p) for p in printed
    ]
    for s in seg["segments"]:
        assert s["frames"] == s["end"] - s["start"] + 1 and s["label"] == "tap"
    assert f"tracking: {seg['tracking']}" in text


def test_bn_edges_json_are_the_printed_edges(capsys, tmp_path, synthetic_folder):
    model = tmp_path / "m.json"
    assert _run(capsys, "bn", "learn", "--data", synthetic_folder, "-o", model)[0] == 0
    status, out, _ = _run(capsys, "bn", "edges", model, "--json")
    assert status == 0
    edges = json.loads(out)
    _, text, _ = _run(capsys, "bn", "edges", model)
    assert [" -> ".join(e) for e in edges] == text.splitlines()
    nodes = json.loads(model.read_text())["nodes"]  # the model file's own parent lists, read without glu
    assert sorted(map(tuple, edges)) == sorted((p, n["name"]) for n in nodes for p in n["parents"])


# ------------------------------------------------------------------ the documentation's commands

ROOT = Path(__file__).resolve().parents[2]
DOCUMENTS = [ROOT / "README.md", ROOT / "data" / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def _documented_commands(text: str):
    """(line number, command) for every ``glu …`` line of a code block (fenced, indented, or ``$ glu``)."""
    lines = text.splitlines()
    fenced = False
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.strip().startswith("```"):
            fenced = not fenced
        elif fenced or line.startswith("    "):
            command = line.strip().removeprefix("$ ")
            start = i + 1
            while command.endswith("\\"):
                i += 1
                command = command[:-1] + " " + lines[i].strip()
            if command.startswith("glu ") and not re.match(r"^glu [\w -]+: ", command):  # not an error shown
                yield start, command
        i += 1


def test_every_documented_command_parses_with_no_deprecated_spelling(capsys):
    """The commands of README.md and docs/ are what the parser accepts today (``[optional]`` parts given,
    the first of ``a|b`` alternatives taken), and none of them uses a deprecated spelling."""
    import shlex

    checked = 0
    for doc in DOCUMENTS:
        for number, command in _documented_commands(doc.read_text(encoding="utf-8")):
            words = re.split(r"\s+#\s", command)[0].replace("[", " ").replace("]", " ")
            argv = [w.split("|")[0] if "|" in w and "://" not in w else w for w in shlex.split(words)[1:]]
            capsys.readouterr()
            try:
                build_parser().parse_args(argv)
            except SystemExit:
                pass
            err = capsys.readouterr().err
            assert not err, f"{doc.relative_to(ROOT)}:{number}: {command}\n{err}"
            checked += 1
    assert checked >= 40


@pytest.mark.parametrize(
    ("argv", "data", "shown"),
    [
        (["evaluate", "--data", "/home/me/real", "-o", "out"], "/home/me/real", "--data DATA -o out"),
        (["evaluate", "--data=/home/me/real", "-o", "out"], "/home/me/real", "--data=DATA -o out"),
        (["evaluate", "--dat", "rel/real"], "rel/real", "--dat DATA"),  # argparse's abbreviation
        (["evaluate", "--da=rel/real"], "rel/real", "--da=DATA"),
        (
            ["evaluate", "--data", "synthetic", "--save", "/home/me/sweeps/x"],
            "synthetic",
            "--data synthetic --save '…/x'",
        ),
        (["evaluate", "--out=/tmp/run/", "--label", ""], None, "'--out=…/run' --label ''"),
        (["correspondence", "-o", "sweeps/10"], None, "-o sweeps/10"),
    ],
)
def test_the_recorded_command_names_no_path_of_this_machine(argv, data, shown, monkeypatch):
    """The command saved tables record (``glu evaluate --save``, ``glu correspondence``): the data folder is
    DATA however it was typed, other absolute paths by their name, and it parses again as the same words."""
    import shlex

    from glu.cli.common import command_line

    monkeypatch.setattr("sys.argv", ["glu", *argv])
    line = command_line(data)
    assert line == f"glu {argv[0]} {shown}"
    assert "/home/me" not in line and "/tmp/" not in line
    assert len(shlex.split(line)) == len(argv) + 1  # no argument dropped, an empty one quoted
