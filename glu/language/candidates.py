"""Which sentences a description is chosen from: the whole grammar, the originals' samples, or a file.

The originals did not search their grammar: they drew 10,000 sentences at random from it (HTK's HSGen),
kept the 9,941 distinct ones, and ranked those (METHOD.md §5.1). That list is part of the published data
(:meth:`glu.data.DataSource.sentence_samples`). :func:`candidate_sentences` turns a ``--candidates``
choice into what :func:`glu.language.describe` takes: ``None`` for the exact search over the grammar, or
a list of sentences to rank.

A sentence file has one sentence per line, words separated by spaces; blank lines are skipped.

>>> import tempfile, pathlib
>>> f = pathlib.Path(tempfile.mkdtemp()) / "s.txt"
>>> _ = f.write_text("the robot taps the ball \\n\\nhe pokes the box\\n")
>>> read_sentences(f)
[('the', 'robot', 'taps', 'the', 'ball'), ('he', 'pokes', 'the', 'box')]
"""

from __future__ import annotations

import os
from pathlib import Path

from glu.data.source import DataSource
from glu.errors import DataError
from glu.files import read_text
from glu.language.sentences import Sentence

CANDIDATES: tuple[str, ...] = ("grammar", "samples")
"""The named candidate sets: ``grammar`` (every sentence, exact N-best) and ``samples`` (the originals' 9,941
sampled sentences, from the data folder); anything else is a sentence file."""
DEFAULT_CANDIDATES = "grammar"


def read_sentences(path: str | os.PathLike) -> list[Sentence]:
    """The sentences of a text file, one per line (blank lines skipped), each a tuple of words.

    Raises :class:`DataError` naming the file if it cannot be read or holds no sentence.
    """
    path = Path(path)
    text = read_text(path, "sentence file (one sentence per line)")
    sentences = [tuple(line.split()) for line in text.splitlines() if line.strip()]
    if not sentences:
        raise DataError(f"{path}: no sentence in the file (expected one sentence per line)")
    return sentences


def candidate_sentences(choice: str, source: DataSource | None = None) -> list[Sentence] | None:
    """The candidates named by ``choice``: None for ``grammar``, else a list of sentences.

    Parameters
    ----------
    choice : ``"grammar"`` (search the whole grammar), ``"samples"`` (the originals' sampled sentences of
        ``source``) or the path of a sentence file
    source : the data source holding the samples (needed for ``"samples"`` only)
    """
    if choice == "grammar":
        return None
    if choice == "samples":
        path = source.sentence_samples() if source is not None else None
        if path is None:
            where = source.describe() if source is not None else "no data source given"
            raise DataError(
                f"--candidates samples: the originals' sampled sentences are not in the data ({where}); "
                "they come with the real data (`glu data fetch`); use --candidates grammar or a file"
            )
        return read_sentences(path)
    return read_sentences(choice)
