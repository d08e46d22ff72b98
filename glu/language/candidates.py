"""Which sentences a description is chosen from: the whole grammar, the originals' samples, or a file.

The originals did not search their grammar: they drew 10,000 sentences at random from it (HTK's HSGen),
kept the 9,941 distinct ones, and ranked those (docs/method.md §6.3). That list is part of the published data
(:meth:`glu.data.DataSource.sentence_samples`). :func:`candidate_sentences` turns a ``--candidates``
choice into what :func:`glu.language.describe` takes: ``None`` for the exact search over the grammar, or
the sentences to rank, prepared once (:class:`SentenceSet`).

A sentence file has one sentence per line, words separated by spaces; blank lines are skipped.

>>> import tempfile, pathlib
>>> f = pathlib.Path(tempfile.mkdtemp()) / "s.txt"
>>> _ = f.write_text("the robot taps the ball \\n\\nhe pokes the box\\n")
>>> read_sentences(f)
[('the', 'robot', 'taps', 'the', 'ball'), ('he', 'pokes', 'the', 'box')]
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path

import numpy as np

from glu.data.source import DataSource
from glu.errors import DataError
from glu.files import read_text
from glu.language.sentences import Sentence, as_sentence

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


def candidate_sentences(choice: str, source: DataSource | None = None) -> SentenceSet | None:
    """The candidates named by ``choice``: None for ``grammar``, else the sentences as a :class:`SentenceSet`.

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
        return SentenceSet(read_sentences(path))
    return SentenceSet(read_sentences(choice))


class SentenceSet(Sequence):
    """Distinct candidate sentences, sorted, with their word counts: prepared once, ranked many times.

    A sequence of sentences (tuples of words, in sorted order, each once), plus what ranking them needs:
    the vocabulary (sorted), each sentence's word counts as an array of shape (n_sentences, n_words) and
    its length. :func:`glu.language.describe` and :func:`glu.language.rank_sentences` take one (or any
    iterable of sentences, prepared on each call), so a list ranked under many evidence sets — the
    originals' 9,941 samples in effect anticipation — is split, de-duplicated and counted once.

    >>> s = SentenceSet.of(["the ball", "the box", "the ball"])
    >>> len(s), s[0], s.vocabulary, s.counts.tolist()
    (2, ('the', 'ball'), ('ball', 'box', 'the'), [[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]])
    """

    __slots__ = ("sentences", "vocabulary", "counts", "lengths")

    def __init__(self, sentences: Iterable[str | Iterable[str]]) -> None:
        self.sentences: tuple[Sentence, ...] = tuple(sorted({as_sentence(s) for s in sentences}))
        self.vocabulary: tuple[str, ...] = tuple(sorted({w for s in self.sentences for w in s}))
        pos = {w: i for i, w in enumerate(self.vocabulary)}
        rows = np.repeat(np.arange(len(self.sentences)), [len(s) for s in self.sentences])
        cols = np.fromiter((pos[w] for s in self.sentences for w in s), dtype=np.intp, count=len(rows))
        self.counts = np.zeros((len(self.sentences), len(self.vocabulary)))
        np.add.at(self.counts, (rows, cols), 1.0)
        self.lengths = np.array([len(s) for s in self.sentences], dtype=np.intp)

    @classmethod
    def of(cls, sentences: SentenceSet | Iterable[str | Iterable[str]]) -> SentenceSet:
        """``sentences`` itself if it is a SentenceSet, else a new one."""
        return sentences if isinstance(sentences, SentenceSet) else cls(sentences)

    def __len__(self) -> int:
        return len(self.sentences)

    def __getitem__(self, i):  # type: ignore[no-untyped-def]
        return self.sentences[i]

    def __iter__(self) -> Iterator[Sentence]:
        return iter(self.sentences)

    def __repr__(self) -> str:
        return f"SentenceSet({len(self)} sentences, {len(self.vocabulary)} words)"
