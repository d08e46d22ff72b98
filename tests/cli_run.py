"""Running the ``glu`` command inside a test: its exit status and what it printed."""

from __future__ import annotations

from pathlib import Path

from glu.cli import main


def run(capsys, *argv: str) -> tuple[int, str, str]:
    """``glu ARGV`` in this process: (exit status, stdout, stderr); argparse's usage errors give their
    status."""
    try:
        status = main(list(argv))
    except SystemExit as e:  # argparse usage errors exit from parse_args
        status = e.code
    out, err = capsys.readouterr()
    return status, out, err


def train_recogniser(out: Path, states: int = 2, n_iter: int = 3) -> Path:
    """A small recogniser for tests that need one: ``glu hmm train`` on 3 synthetic gestures per action."""
    argv = ["hmm", "train", "--synthetic", "3", "--states", str(states), "--mix", "1", "--iter", str(n_iter)]
    assert main([*argv, "-o", str(out)]) == 0
    return out
