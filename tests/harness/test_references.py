"""Nothing in the repository refers to a file that is not in it.

Every mention of a ``*.md`` file — in the package, the tests, the notebooks, the benchmarks, the pages,
``pyproject.toml`` and the ``Makefile`` — names a file of the repository; every link with an anchor
(a page's name, ``#`` and a heading's anchor) and every section cited as ``docs/method.md §N.M`` names a
heading of that page; every module the package map (docs/api.md) names exists; and every source file cited by
path (``tests/library/test_hmm.py``) is there.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
FOLDERS = ("glu", "tests", "notebooks", "benchmarks", "docs")
TOP = ("README.md", "pyproject.toml", "Makefile", "setup.py", "CITATION.cff")
SUFFIXES = {".py", ".md", ".toml", ".ipynb", ".cfg", ".txt", ".yaml", ".yml", ".json"}

REFERENCE = re.compile(r"(?<![\w.-])([\w./-]*[\w-]\.md)(#[\w-]+)?\b")
"""A file name ending in .md, optionally with an anchor."""
LINK = re.compile(r"\]\(([^)\s]+?\.md)(#[^)\s]+)?\)")
"""A Markdown link to a page, with its anchor if it has one."""
SECTION = re.compile(r"docs/method\.md`{0,2} §(\d+(?:\.\d+)?)")
"""A section of the method page cited by number: ``docs/method.md §4.2``."""


def files() -> list[Path]:
    """The repository's text files that may refer to pages (not build products, not the virtualenv)."""
    out = [ROOT / f for f in TOP if (ROOT / f).is_file()]
    for folder in FOLDERS:
        out += [
            f
            for f in sorted((ROOT / folder).rglob("*"))
            if f.is_file() and f.suffix in SUFFIXES and "__pycache__" not in f.parts
        ]
    return out


def references(path: Path) -> list[tuple[int, str, str]]:
    """(line, file, anchor) of every reference to a ``*.md`` file in a file (anchor "" if none).

    A file name joined onto a folder in code (``tmp_path / "R.md"``, ``f"{out}/README.md"``) is a file the
    code writes, not a reference, and is skipped; so is, in Python, a string literal that is nothing but a
    file name (``pages["index.md"] = …``: a page the documentation site writes).
    """
    out = []
    python = path.suffix == ".py"
    for n, line in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines(), 1):
        for m in REFERENCE.finditer(line):
            before, after = line[: m.start()], line[m.end() :]
            if re.search(r"(/\s*[\"']|\})$", before) or m.group(1).startswith("/"):
                continue
            if (
                python
                and not m.group(2)
                and before[-1:] in "\"'"
                and before[-1:]
                and after[:1] == before[-1:]
            ):
                continue
            out.append((n, m.group(1), (m.group(2) or "")[1:]))
    return out


def resolve(path: Path, name: str) -> Path | None:
    """The file a reference in ``path`` names: relative to the referring file, else to the repository."""
    for base in (path.parent, ROOT):
        target = (base / name).resolve()
        if target.is_file() and ROOT in target.parents:
            return target
    return None


def slug(heading: str) -> str:
    """The anchor MyST (``myst_heading_anchors``, mdit-py-plugins' ``slugify``) and GitHub give a heading."""
    text = heading.strip().lower().replace(" ", "-")
    return re.sub(r"[^\w\u4e00-\u9fff\- ]", "", text)


def anchors(page: Path) -> set[str]:
    """The anchors of a page's headings (outside code blocks)."""
    text = re.sub(r"(?ms)^```.*?^```", "", page.read_text(encoding="utf-8"))
    return {slug(m.group(1)) for m in re.finditer(r"(?m)^#{1,6} +(.+?)\s*$", text)}


def test_the_checker_finds_references_and_skips_files_written_by_code(tmp_path):
    f = tmp_path / "x.py"
    f.write_text(
        '"""See docs/method.md §4.2 and [data](../../docs/data.md#the-published-data)."""\n'
        'page = tmp_path / "R.md"\nother = f"{out}/README.md"\npages = {"index.md": text}\n'
    )
    assert references(f) == [(1, "docs/method.md", ""), (1, "../../docs/data.md", "the-published-data")]
    assert slug("3.4 The all-zero word rows") == "34-the-all-zero-word-rows"
    assert slug("Beyond the self: learning people's gestures") == "beyond-the-self-learning-peoples-gestures"
    try:
        from mdit_py_plugins.anchors.index import slugify
    except ImportError:
        return
    for heading in ("3.4 The all-zero word rows", "2. Fusion", "Every fusion strategy: 95 % (p_HMM) — ok"):
        assert slug(heading) == slugify(heading)


def test_every_referenced_page_is_in_the_repository():
    missing = [
        f"{path.relative_to(ROOT)}:{n}: {name}"
        for path in files()
        for n, name, _ in references(path)
        if resolve(path, name) is None
    ]
    assert not missing, "references to files not in the repository:\n" + "\n".join(missing)


def test_every_anchor_names_a_heading_of_its_page():
    broken = []
    for path in files():
        if path.suffix != ".md":
            continue
        for m in LINK.finditer(path.read_text(encoding="utf-8")):
            name, anchor = m.group(1), (m.group(2) or "")[1:]
            target = resolve(path, name)
            if target is not None and anchor and anchor not in anchors(target):
                broken.append(f"{path.relative_to(ROOT)}: {name}#{anchor}")
    assert not broken, "links to headings that do not exist:\n" + "\n".join(broken)


def test_every_cited_section_of_the_method_exists():
    text = (ROOT / "docs" / "method.md").read_text(encoding="utf-8")
    numbers = set(re.findall(r"(?m)^#{2,3} (\d+(?:\.\d+)?)\.? ", text))
    cited = [
        (path, number)
        for path in files()
        for number in SECTION.findall(path.read_text(encoding="utf-8", errors="replace"))
    ]
    assert len(cited) >= 30  # the package cites the method throughout
    missing = [f"{p.relative_to(ROOT)}: §{n}" for p, n in cited if n not in numbers]
    assert not missing, "sections of docs/method.md that do not exist:\n" + "\n".join(missing)


def test_the_method_sections_are_numbered_in_order():
    text = (ROOT / "docs" / "method.md").read_text(encoding="utf-8")
    found = re.findall(r"(?m)^(#{2,3}) (\d+)(?:\.(\d+))?\.? ", text)
    expected_top, expected_sub = 1, 1
    for level, top, sub in found:
        if level == "##":
            assert (int(top), sub) == (expected_top, ""), f"## {top}: expected {expected_top}"
            expected_top, expected_sub = expected_top + 1, 1
        else:
            assert (int(top), int(sub)) == (expected_top - 1, expected_sub), f"### {top}.{sub}"
            expected_sub += 1


def package_map() -> list[tuple[list[str], list[str]]]:
    """The rows of the package map (docs/api.md, "Package layout"): (packages, modules)."""
    text = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    table = text.split("## Package layout", 1)[1].split("\n## ", 1)[0]
    rows = []
    for line in table.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 3 and cells[0].startswith("`glu"):
            rows.append((re.findall(r"`([\w.]+)`", cells[0]), re.findall(r"`(\w+)`", cells[1])))
    return rows


def test_the_package_map_names_modules_that_exist():
    rows = package_map()
    assert len(rows) >= 10
    missing = []
    for packages, modules in rows:
        folders = [ROOT.joinpath(*p.split(".")) for p in packages]
        assert all(f.is_dir() for f in folders), packages
        for m in modules:
            if not any((f / f"{m}.py").is_file() or (f / m / "__init__.py").is_file() for f in folders):
                missing.append(f"{'/'.join(packages)}: {m}")
    assert not missing, "the README's package map names modules that do not exist: " + ", ".join(missing)


@pytest.mark.parametrize("page", sorted((ROOT / "docs").glob("*.md")), ids=lambda p: p.name)
def test_each_page_has_one_title_and_no_skipped_heading_level(page):
    text = re.sub(r"(?ms)^```.*?^```", "", page.read_text(encoding="utf-8"))
    levels = [len(m.group(1)) for m in re.finditer(r"(?m)^(#{1,6}) ", text)]
    assert levels[0] == 1 and levels.count(1) == 1, f"{page.name}: one top-level heading, first"
    skipped = [(a, b) for a, b in zip(levels, levels[1:], strict=False) if b > a + 1]
    assert not skipped, f"{page.name}: heading levels skipped {skipped}"


TARGET = re.compile(r"\]\(([^)\s#]+)(?:#[^)\s]*)?\)")
"""The target of a Markdown link or image."""


def test_every_relative_link_and_image_of_the_pages_exists():
    missing = []
    for page in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        text = re.sub(r"(?ms)^```.*?^```", "", page.read_text(encoding="utf-8"))
        for target in TARGET.findall(text):
            if re.match(r"[a-z]+:", target):  # https:, mailto:
                continue
            if not (page.parent / target).resolve().exists():
                missing.append(f"{page.relative_to(ROOT)}: {target}")
    assert not missing, "links to files that do not exist:\n" + "\n".join(missing)


def test_no_page_shows_a_machine_path():
    shown = []
    for page in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        for n, line in enumerate(page.read_text(encoding="utf-8").splitlines(), 1):
            if re.search(r"\.\./shared|/work/|/home/|/tmp/|/Users/", line):
                shown.append(f"{page.relative_to(ROOT)}:{n}: {line.strip()}")
    assert not shown, "pages showing paths of one machine:\n" + "\n".join(shown)


SOURCE = re.compile(r"(?<![\w./-])((?:tests|benchmarks|glu|notebooks)/[\w./-]*[\w-]\.py)\b")
"""A path of a source file of the repository: ``tests/library/test_hmm.py``, ``glu/bn/soft.py``."""
MADE_UP = {"benchmarks/bench_demo.py", "notebooks/01.py"}
"""Paths tests write into their own data (a made-up benchmark result, an executed notebook's metadata)."""


def test_every_cited_source_file_is_in_the_repository():
    """A test or module cited as the evidence of a claim (``tests/library/test_gmm_init.py compares …``) is
    there: one moved to another folder leaves no stale path. Placeholders (``notebooks/NN_topic.py``) and
    the paths of :data:`MADE_UP` are not citations."""
    missing = [
        f"{path.relative_to(ROOT)}:{n}: {m.group(1)}"
        for path in files()
        for n, line in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines(), 1)
        for m in SOURCE.finditer(line)
        if m.group(1) not in MADE_UP
        and not re.search(r"[A-Z]{2}", m.group(1))
        and not (ROOT / m.group(1)).is_file()
    ]
    assert not missing, "paths of files not in the repository:\n" + "\n".join(missing)
