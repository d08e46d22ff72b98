"""Speed of the fast paths added for issue 9, each against the straightforward way it replaced.

Run on demand (not a test)::

    python benchmarks/bench_fast_paths.py [--data DIR] [--repeats N]

Medians over repeats, on one BLAS thread; every pair is checked to give the same result first.

1. **HMM initial mixtures**: the 6 per-state Gaussian mixtures of 30 HMMs (synthetic gestures, 12 per
   action), by scikit-learn's ``GaussianMixture`` against :func:`glu.hmm.initialisation.fit_gaussian_mixture`
   (its own k-means with scikit-learn's labels, and EM compiled: equal to rounding, 1e-10 of each array's
   scale), for one and for three components;
2. **ranking candidate sentences**: 141 evidence sets × the candidates (the originals' 9,941 samples with
   the real data, else 10,000 sentences drawn from the grammar), every sentence keyed exactly as before
   against :func:`glu.language.rank_sentences` on a prepared :class:`~glu.language.SentenceSet`;
3. **random sentences**: 21 × 10,000 from the default grammar, the recursive walk of the grammar tree
   against the compiled walk of :func:`glu.language.sample_sentences` (the same sentences).
"""

from __future__ import annotations

import argparse
import heapq
import sys
import warnings
from pathlib import Path

import numpy as np
from timing import median_time, report, row

ROWS: list[dict] = []
NOTES: list[str] = []


def _row(name: str, reference: str, before: float, after: float) -> None:
    ROWS.append(row(name, after, reference, before))


def bench_mixtures(repeats: int) -> None:
    from sklearn.mixture import GaussianMixture

    from glu.gestures.corpus import synthetic_corpus
    from glu.hmm.initialisation import fit_gaussian_mixture

    corpus = synthetic_corpus(12, seed=3)
    slices = []  # the frames of each state's time slices, as init_left_to_right cuts them (6 states)
    for action in dict.fromkeys(s.action for s in corpus):
        seqs = [s.xyz for s in corpus if s.action == action]
        for q in range(6):
            slices.append(
                np.concatenate([X[np.minimum(np.arange(len(X)) * 6 // len(X), 5) == q] for X in seqs])
            )
    slices = slices * 10  # 30 models' worth

    def sklearn(M):
        out = []
        for i, X in enumerate(slices):
            gm = GaussianMixture(M, covariance_type="full", reg_covar=0.03, random_state=i, n_init=1)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                gm.fit(X)
            out.append((gm.weights_, gm.means_, gm.covariances_))
        return out

    def ours(M):
        return [fit_gaussian_mixture(X, M, 0.03, i) for i, X in enumerate(slices)]

    fits = f"{len(slices)} fits, {int(np.mean([len(X) for X in slices]))} frames each"
    for M in (1, 3):
        same = all(
            np.allclose(a, b, rtol=0, atol=1e-10 * np.abs(a).max())
            for x, y in zip(sklearn(M), ours(M), strict=True)
            for a, b in zip(x, y, strict=True)
        )
        assert same, "the fast mixtures differ from scikit-learn's"
        _row(
            f"HMM initial mixtures ({fits}), M = {M}: fit_gaussian_mixture",
            "scikit-learn GaussianMixture.fit",
            median_time(lambda m=M: sklearn(m), repeats),
            median_time(lambda m=M: ours(m), repeats),
        )


def _rank_every_sentence(sentences, probs, n, score):
    """rank_sentences as it was: split, de-duplicate and key every sentence exactly, on every call."""
    from glu.language.descriptions import LogProbs, _exact, _frame, _rank_key, _score, score_offset

    offset = score_offset(score)
    sents = sorted({tuple(s.split()) if isinstance(s, str) else tuple(s) for s in sentences})
    vocab = sorted({w for s in sents for w in s})
    lp = LogProbs.from_probs(vocab, probs)
    pos = {w: i for i, w in enumerate(vocab)}
    keyed = []
    for s in sents:
        n_zero, total = _exact(lp, [pos[w] for w in s])
        keyed.append(
            (_rank_key(n_zero, total, len(s), s, offset, lp.scale), _score(lp, n_zero, total, len(s), offset))
        )
    return _frame([(k[2], sc) for k, sc in heapq.nsmallest(n, keyed)])


def bench_ranking(data: str | None, repeats: int) -> None:
    from glu.data import resolve_data
    from glu.language import SentenceSet, candidate_sentences, load_grammar, rank_sentences, sample_sentences

    source = resolve_data(data)
    prepared = candidate_sentences("samples", source) if source.is_real else None
    if prepared is None:
        prepared = SentenceSet(sample_sentences(load_grammar(), 10_000, seed=0))
    plain = list(prepared)
    rng = np.random.default_rng(0)
    evidence = [
        dict(zip(prepared.vocabulary, rng.uniform(0.01, 1, len(prepared.vocabulary)).tolist(), strict=True))
        for _ in range(141)
    ]
    for probs in evidence[:10]:
        assert rank_sentences(prepared, probs, 10, "original").equals(
            _rank_every_sentence(plain, probs, 10, "original")
        )
    NOTES.append(f"ranking: {source.describe()}")
    _row(
        f"ranking {len(prepared):,} sentences for 141 evidence sets: float shortlist + exact keys",
        "every sentence keyed exactly",
        median_time(lambda: [_rank_every_sentence(plain, p, 10, "original") for p in evidence], repeats),
        median_time(lambda: [rank_sentences(prepared, p, 10, "original") for p in evidence], repeats),
    )


def bench_sampling(repeats: int) -> None:
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
    from language_reference import recursive_samples  # the sampler as first written

    from glu.language import load_grammar, sample_sentences

    g = load_grammar()
    assert sample_sentences(g, 10_000, 5) == recursive_samples(g, 10_000, 5)
    _row(
        "21 × 10,000 random sentences of the default grammar: compiled walk",
        "the recursive walk",
        median_time(lambda: [recursive_samples(g, 10_000, s) for s in range(21)], repeats),
        median_time(lambda: [sample_sentences(g, 10_000, s) for s in range(21)], repeats),
    )


def main(argv: list[str] | None = None) -> int:
    """Run the three benchmarks and print before/after times."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", help="data folder (default: as glu finds it)")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    import sklearn.cluster  # noqa: F401 - loaded before the limit, which binds only the libraries already loaded
    import sklearn.mixture  # noqa: F401
    from threadpoolctl import threadpool_limits

    with threadpool_limits(1):
        bench_mixtures(args.repeats)
        bench_ranking(args.data, args.repeats)
        bench_sampling(args.repeats)
    report(
        "fast_paths",
        "the fast paths against the straightforward way each replaced (one BLAS thread; same results "
        "checked first)",
        ROWS,
        NOTES,
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
