"""``glu learn-gestures`` and ``glu learning-curves``: the robot learns people's gestures from what their
actions did.

``glu learn-gestures`` simulates episodes — a person's gesture on an object, the effect, the words — labels
each with the Affordance–Words network learned from the robot's own experiments, trains gesture HMMs from
those labels and writes a recogniser that ``glu recognize`` and ``glu anticipate`` take (``--models FILE``).
``glu learning-curves`` runs the study of notebook 12 — every labelling scheme and baseline, every ambiguity,
with and without words, one Dask task per training seed — and writes its tables.
"""

from __future__ import annotations

import argparse
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from glu.cli.commands import help_of
from glu.cli.common import (
    add_cluster_args,
    add_data_option,
    add_deprecated_alias,
    add_hmm_size_args,
    nonneg_float,
    output_file,
    output_folder,
    positive_float,
    positive_int,
    seed,
)

EPISODE_BYTES = 120_000
"""Memory an episode of ``learn-gestures`` holds at the peak of the simulation (about 110 kB measured:
``tests/harness/test_fuzz_hostile.py``), for the check of ``--episodes`` before anything is allocated."""


def _ambiguities() -> tuple[str, ...]:
    from glu.studies.learning.self_supervised import AMBIGUITIES

    return tuple(AMBIGUITIES)


def _seeds(text: str) -> tuple[int, ...]:
    parts = [p.strip() for p in text.split(",") if p.strip()]
    try:
        if ".." in text and len(parts) == 1:
            a, b = (int(x) for x in parts[0].split(".."))
            values = tuple(range(a, b + 1))
        else:
            values = tuple(int(p) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: seeds as 0,1,2 or 0..9") from None
    if not values or len(set(values)) != len(values) or min(values) < 0:
        raise argparse.ArgumentTypeError(f"{text!r}: distinct seeds ≥ 0, e.g. 0,1,2 or 0..9")
    return values


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``learn-gestures`` and ``learning-curves`` commands."""
    from glu.studies.learning.self_supervised import AMBIGUITIES, LEARNERS

    ambiguity_help = "; ".join(f"{k}: {a.description}" for k, a in AMBIGUITIES.items()).replace("%", "%%")
    p = sub.add_parser(
        "learn-gestures",
        help=help_of("learn-gestures"),
        description="Simulate episodes (a person's gesture on an object, the effect, the words), label each "
        "with the Affordance–Words network learned from the robot's own experiments, train gesture HMMs from "
        "those labels and write a recogniser that glu recognize and glu anticipate take (--models FILE).",
    )
    p.add_argument("--episodes", type=positive_int, required=True, metavar="N", help="episodes watched")
    p.add_argument(
        "--labels",
        choices=LEARNERS,
        required=True,
        help="hard: the network's arg-max; soft: its posterior as weights (weighted EM); confident: the "
        "arg-max above --threshold only; iterative: the product rule of the HMMs and the network, relabelled "
        "until the labels stop changing; true: the true actions (the upper bound); unsupervised: clusters "
        "named after the fact (the lower bound)",
    )
    p.add_argument("--with-words", action="store_true", help="the robot also hears the words someone said")
    add_deprecated_alias(p, "--words", "--with-words")
    p.add_argument("--seed", type=seed, default=0, help="seed of the episodes and of EM (default 0)")
    p.add_argument(
        "--ambiguity",
        choices=tuple(AMBIGUITIES),
        default="mixed",
        help=f"how well the effects tell the actions apart (default mixed): {ambiguity_help}",
    )
    p.add_argument("--online", action="store_true", help="learn one episode at a time (default: all at once)")
    p.add_argument(
        "--threshold",
        type=positive_float,
        default=0.9,
        help="--labels confident: p_BN threshold (default 0.9)",
    )
    add_hmm_size_args(p)
    p.add_argument(
        "--noise",
        type=nonneg_float,
        default=0.02,
        help="sensor noise of the simulated gestures, m (default 0.02)",
    )
    add_data_option(p, "the network is learned from its experiments")
    p.add_argument(
        "-o", "--out", type=output_file, required=True, metavar="RECOGNISER", help="file to write (JSON)"
    )
    p.set_defaults(func=_learn)

    c = sub.add_parser(
        "learning-curves",
        help=help_of("learning-curves"),
        description="Run the study of notebook 12: every labelling scheme and baseline, every ambiguity, "
        "with and without words, one Dask task per training seed, and write its tables "
        "(learning_curves.csv, learning_match.csv, learning_labels.csv, learning_study.json) to -o DIR.",
    )
    c.add_argument(
        "--episodes", type=positive_int, default=10_000, metavar="N", help="per seed (default 10000)"
    )
    c.add_argument("--seeds", type=_seeds, default=tuple(range(10)), help="training seeds (default 0..9)")
    c.add_argument(
        "--ambiguities",
        type=lambda s: tuple(x.strip() for x in s.split(",") if x.strip()),
        default=tuple(AMBIGUITIES),
        metavar="LIST",
        help=f"the worlds to study, comma-separated (default all): {ambiguity_help}",
    )
    c.add_argument("--test-per-action", type=positive_int, default=30, metavar="N", help="held-out gestures")
    add_cluster_args(c, "seed")
    add_deprecated_alias(c, "--synchronous", "--scheduler", const="synchronous")
    add_data_option(c, "the network is learned from its experiments")
    c.add_argument(
        "-o", "--out", type=output_folder, required=True, metavar="DIR", help="folder for the tables"
    )
    c.set_defaults(func=_curves)


def _engine(data: str | None):
    from glu.bn.inference import make_engine
    from glu.bn.learning import learn_bn
    from glu.data.source import load_experiments, resolve_data

    source = resolve_data(data)
    return make_engine(learn_bn(load_experiments(source))), source.describe()


HEARTBEAT_S = 10.0
"""How often ``glu learn-gestures`` says it is still learning (seconds)."""


@contextmanager
def heartbeat(what: str, every: float, enabled: bool | None = None) -> Iterator[None]:
    """While the block runs, a line on stderr every ``every`` seconds: ``what``, still running, the seconds
    so far; when it ends without an error, the time it took. ``enabled``: None = when stderr is a terminal
    (a person waiting; an error stays one line)."""
    if not (sys.stderr.isatty() if enabled is None else enabled):
        yield
        return
    stop = threading.Event()
    t0 = time.perf_counter()

    def beat() -> None:
        while not stop.wait(every):
            print(f"  {what}: {time.perf_counter() - t0:.0f} s so far", file=sys.stderr, flush=True)

    thread = threading.Thread(target=beat, daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()
    print(f"  {what}: done in {time.perf_counter() - t0:.1f} s", file=sys.stderr, flush=True)


def _learn(args: argparse.Namespace) -> int:
    from glu.errors import DataError
    from glu.hmm import TrainingConfig
    from glu.machine import check_memory
    from glu.studies.learning.learned_recognizers import learn_gestures

    check_memory(args.episodes * EPISODE_BYTES, f"--episodes {args.episodes:,}")
    engine, label = _engine(args.data)
    actions = engine.bn.schema.values_of("Action")
    if args.episodes < len(actions):
        raise DataError(
            f"--episodes {args.episodes}: at least one episode per action ({len(actions)}: "
            f"{', '.join(actions)}) to learn a model of each"
        )
    print(f"network: learned from {label}")
    config = TrainingConfig(n_states=args.states, n_mix=args.mix, n_iter=args.iter)
    if args.threshold > 1:
        raise DataError(f"--threshold {args.threshold}: a probability in (0, 1]")
    how = "one episode at a time" if args.online else "EM on all of them, relabelled until the labels settle"
    print(
        f"learning: {args.episodes} episodes simulated, labelled by the network ({args.labels}), then the "
        f"HMMs trained ({how})",
        flush=True,
    )
    with heartbeat("learning", HEARTBEAT_S):
        rec, info = learn_gestures(
            engine,
            args.episodes,
            args.labels,
            seed=args.seed,
            words=args.with_words,
            ambiguity=args.ambiguity,
            online=args.online,
            config=config,
            threshold=args.threshold,
            data_source=label,
        )
    print(f"episodes: {info['data']}")
    print(
        f"labels: arg-max of p_BN right for {info['label_accuracy']:.3f} of the episodes; "
        f"rounds {info['rounds']}"
    )
    rec.save(args.out)
    print(f"wrote {args.out} ({', '.join(rec.actions)}; Q={args.states}, M={args.mix})")
    return 0


def _curves(args: argparse.Namespace) -> int:
    import json

    from glu.errors import DataError
    from glu.files import atomic_write_json, atomic_write_text
    from glu.machine import SYNCHRONOUS, check_reachable
    from glu.studies.learning import study as lc

    bad = [a for a in args.ambiguities if a not in _ambiguities()]
    if bad:
        raise DataError(f"--ambiguities: unknown {bad[0]!r}; allowed: {', '.join(_ambiguities())}")
    if args.scheduler not in (None, SYNCHRONOUS):  # before any work: a scheduler that does not answer
        check_reachable(args.scheduler)
    engine, label = _engine(args.data)
    settings = lc.StudySettings(
        episodes=args.episodes,
        seeds=args.seeds,
        ambiguities=args.ambiguities,
        test_per_action=args.test_per_action,
    )
    here = args.scheduler == SYNCHRONOUS
    scheduler = None if here else args.scheduler
    workers = 0 if here else (args.workers or _cores())
    print(
        f"network: {label}; {len(args.seeds)} seeds × {args.episodes} episodes, "
        f"{len(settings.learners())} learners"
    )
    results = lc.learning_study(
        engine,
        settings,
        workers=0 if scheduler else workers,
        scheduler=scheduler,
        progress=lambda s: print(f"  seed {s} done", flush=True),
    )
    out = Path(args.out)
    curves = lc.curves_table(results, settings, label)
    match = lc.match_table(curves)
    labels = lc.labels_table(results, settings, label)
    for name, df in (("learning_curves", curves), ("learning_match", match), ("learning_labels", labels)):
        atomic_write_text(out / f"{name}.csv", df.to_csv(index=False))
    atomic_write_json(
        out / "learning_study.json",
        {
            "settings": json.loads(json.dumps(settings.as_dict(), default=str)),
            "data_source": label,
            "update_seconds": lc.update_times(results),
        },
    )
    print(f"wrote {out}/learning_curves.csv, learning_match.csv, learning_labels.csv, learning_study.json")
    return 0


def _cores() -> int:
    from glu.machine import available_cores

    return available_cores()
