"""Every record of a run names the glu that made it: its version, its commit, "modified" when the code
differs from that commit (glu.run.provenance). Checked on throw-away git repositories made here."""

from __future__ import annotations

import subprocess

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import pytest  # noqa: E402

import glu  # noqa: E402
from glu.plots.overlap import figure_problems  # noqa: E402
from glu.plots.style import save_figure, stamp  # noqa: E402
from glu.run import provenance  # noqa: E402
from glu.run.provenance import ENV, Provenance, made_by, read_provenance  # noqa: E402


def _git(root, *args):
    return subprocess.run(["git", "-C", str(root), *args], capture_output=True, text=True, check=True).stdout


@pytest.fixture
def checkout(tmp_path):
    root = tmp_path / "glu"
    (root / "glu").mkdir(parents=True)
    (root / "figures").mkdir()
    (root / "glu" / "fusion.py").write_text("x = 1\n")
    (root / "figures" / "a.png").write_bytes(b"png")
    _git(root, "init", "-q")
    _git(root, "-c", "user.name=t", "-c", "user.email=t@t", "add", ".")
    _git(root, "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "first")
    return root


def test_a_clean_checkout_names_its_commit(checkout):
    head = _git(checkout, "rev-parse", "HEAD").strip()
    p = read_provenance(checkout)
    assert p == Provenance(glu.__version__, head, modified=False)
    assert p.label() == f"glu {glu.__version__}, commit {head[:12]}"
    assert p.as_dict() == {"version": glu.__version__, "commit": head, "modified": False}


def test_a_change_to_the_code_is_modified_and_a_changed_output_is_not(checkout):
    (checkout / "figures" / "a.png").write_bytes(b"another figure")  # what a run rewrites
    (checkout / "results").mkdir()
    (checkout / "results" / "summary.json").write_text("{}")
    assert not read_provenance(checkout).modified
    (checkout / "glu" / "fusion.py").write_text("x = 2\n")
    assert read_provenance(checkout).modified
    assert read_provenance(checkout).label().endswith(" (modified)")
    _git(checkout, "checkout", "-q", "--", "glu/fusion.py")
    (checkout / "glu" / "new.py").write_text("")  # an untracked file is a change too
    assert read_provenance(checkout).modified


def test_outside_a_checkout_the_version_alone(tmp_path):
    assert read_provenance(tmp_path) == Provenance(glu.__version__)
    assert read_provenance(None).label() == f"glu {glu.__version__}"


def test_without_git_the_version_alone_and_an_unknown_status_is_modified(checkout, monkeypatch, tmp_path):
    monkeypatch.setenv("PATH", str(tmp_path))  # no git on the PATH
    assert read_provenance(checkout) == Provenance(glu.__version__)
    monkeypatch.undo()
    head = _git(checkout, "rev-parse", "HEAD").strip()
    real_run = subprocess.run

    def status_hangs(argv, **kwargs):
        if "status" in argv:
            raise subprocess.TimeoutExpired(argv, kwargs.get("timeout"))
        return real_run(argv, **kwargs)

    monkeypatch.setattr(provenance.subprocess, "run", status_hangs)
    assert read_provenance(checkout) == Provenance(glu.__version__, head, modified=True)


def test_the_run_passes_its_line_to_the_kernels(monkeypatch):
    monkeypatch.setenv(ENV, "glu 9.9.9, commit 0123456789ab")
    assert made_by() == "glu 9.9.9, commit 0123456789ab"
    monkeypatch.delenv(ENV)
    assert made_by() == provenance._this_checkout().label()


def test_a_figure_names_its_glu_under_its_footer_and_is_the_same_for_the_same_commit(tmp_path):
    files = []
    for k in range(2):
        fig, ax = plt.subplots(figsize=(4, 3))
        ax.plot([0, 1], [0, 1])
        stamp(fig, "synthetic data (seed 0)", "glu 0.1.0, commit 0123456789ab")
        assert figure_problems(fig) == []  # the line does not cover the footer
        files.append(save_figure(fig, tmp_path / f"f{k}"))
        plt.close(fig)
    svg = files[0][1].read_text()
    assert "<!-- synthetic data (seed 0) -->" in svg and "<!-- glu 0.1.0, commit 0123456789ab -->" in svg
    assert files[0][0].read_bytes() == files[1][0].read_bytes()


def test_the_version_the_citation_and_the_changelog_agree():
    import re
    import tomllib
    from pathlib import Path

    import yaml

    root = Path(__file__).resolve().parents[2]
    version = tomllib.loads((root / "pyproject.toml").read_text())["project"]["version"]
    cff = yaml.safe_load((root / "CITATION.cff").read_text())
    assert version == glu.__version__ == cff["version"] == cff["preferred-citation"]["version"]
    latest = re.search(
        r"(?m)^## \[(\d+\.\d+\.\d+)\] - (\d{4}-\d\d-\d\d)$", (root / "CHANGELOG.md").read_text()
    )
    assert latest and latest.groups() == (version, str(cff["date-released"]))
    bibtex = (root / "README.md").read_text().split("## How to cite", 1)[1].split("```bibtex", 1)[1]
    fields = dict(re.findall(r"(?m)^\s*(\w+)\s*=\s*\{(.*)\},?$", bibtex.split("```", 1)[0]))
    assert fields["version"] == version and fields["year"] == str(cff["preferred-citation"]["year"])
    assert fields["url"] == cff["repository-code"] == cff["preferred-citation"]["url"]
    assert fields["year"] == str(cff["date-released"])[:4]
