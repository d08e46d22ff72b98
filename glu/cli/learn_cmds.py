"""``glu learn-gestures`` and ``glu learning-curves``: the robot learns people's gestures from what their
actions did (what each command does: its description below; provenance: :mod:`glu.studies.learning.saved`)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from glu.cli.commands import add_command
from glu.cli.common import (
    add_cluster_args,
    add_data_option,
    add_deprecated_alias,
    add_hmm_size_args,
    add_out_option,
    chosen,
    hmm_config,
    nonneg_float,
    positive_float,
    positive_int,
    progress,
    seed,
)

EPISODE_BYTES = 120_000
"""Memory an episode of ``learn-gestures`` holds at the peak of the simulation (about 110 kB measured:
``tests/harness/test_fuzz_hostile.py``), for the check of ``--episodes`` before anything is allocated."""


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
    from glu.studies.learning.self_supervised import AMBIGUITIES, LEARNERS, WORLDS

    ambiguity_help = "; ".join(f"{k}: {a.description}" for k, a in AMBIGUITIES.items()).replace("%", "%%")
    world_help = "; ".join(f"{k}: {w.description}" for k, w in WORLDS.items()).replace("%", "%%")
    p = add_command(
        sub,
        "learn-gestures",
        "Simulate episodes (a person's gesture on an object, the effect, the words), label each "
        "with the Affordance–Words network learned from the robot's own experiments, train gesture HMMs from "
        "those labels and write a recogniser that glu recognize and glu anticipate take (--models FILE).",
        _learn,
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
    add_out_option(p, "RECOGNISER", "file to write (JSON)")

    _register_curves(sub, ambiguity_help, world_help)


def _register_curves(sub: argparse._SubParsersAction, ambiguity_help: str, world_help: str) -> None:
    from glu.studies.learning.self_supervised import AMBIGUITIES, WORLDS

    c = add_command(
        sub,
        "learning-curves",
        "Run the study of notebook 12 at the budgets the notebook does not run itself: every "
        "labelling scheme and control, every world and ambiguity, with and without words, one Dask task per "
        "training seed (--part curves); and the real person, learned from a generator fitted to their "
        "repetitions and recognised leave-one-segment-out, one task per draw (--part real-person, real data "
        "only). Writes the measurements and their provenance (learning_study.json, learning_results.npz, "
        "learning_real_person.csv.gz) and the tables to -o DIR; give the notebook saved=DIR.",
        _curves,
    )
    c.add_argument(
        "--part",
        choices=("curves", "real-person", "all"),
        default="curves",
        help="the learning curves over seeds, the real person over draws, or both (default curves)",
    )
    c.add_argument(
        "--episodes", type=positive_int, default=10_000, metavar="N", help="per seed (default 10000)"
    )
    c.add_argument("--seeds", type=_seeds, default=tuple(range(10)), help="training seeds (default 0..9)")
    for flag, names, text in (
        ("--worlds", WORLDS, world_help),
        ("--ambiguities", AMBIGUITIES, ambiguity_help),
    ):
        c.add_argument(
            flag,
            type=_names,
            default=tuple(names),
            metavar="LIST",
            help=f"comma-separated (default all): {text}",
        )
    c.add_argument("--test-per-action", type=positive_int, default=30, metavar="N", help="held-out gestures")
    c.add_argument(
        "--margin",
        type=positive_float,
        default=0.02,
        help="equivalence margin on accuracy, declared before the data (default 0.02)",
    )
    c.add_argument(
        "--draws", type=_seeds, default=tuple(range(50)), help="--part real-person: draws (default 0..49)"
    )
    add_cluster_args(c, "seed or draw")
    add_deprecated_alias(c, "--synchronous", "--scheduler", const="synchronous")
    add_data_option(c, "the network is learned from its experiments")
    add_out_option(c, "DIR", "folder for the tables", folder=True)


def _names(text: str) -> tuple[str, ...]:
    return tuple(x.strip() for x in text.split(",") if x.strip())


def _engine(data: str | None):
    from glu.bn.inference import make_engine
    from glu.bn.learning import learn_bn
    from glu.data.source import load_experiments, resolve_data

    source = resolve_data(data)
    return make_engine(learn_bn(load_experiments(source))), source.describe()


def _learn(args: argparse.Namespace) -> int:
    from glu.errors import DataError
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
    if args.threshold > 1:
        raise DataError(f"--threshold {args.threshold}: a probability in (0, 1]")
    print(f"network: learned from {label}", flush=True)
    how = (
        "one episode at a time"
        if args.online
        else "EM on all of them, relabelled until the labels settle"
        if args.labels == "iterative"
        else "EM on all of them"
    )
    print(
        f"learning: {args.episodes} episodes simulated, labelled by the network ({args.labels}), then the "
        f"HMMs trained ({how})",
        flush=True,
    )
    config = hmm_config(args)
    with progress(
        args.episodes if args.online else None, "learn", "episode" if args.online else "model"
    ) as bar:
        rec, info = learn_gestures(
            engine,
            args.episodes,
            args.labels,
            words=args.with_words,
            config=config,
            data_source=label,
            progress=(lambda _: bar.update(1)) if bar is not None else None,
            **chosen(args, "seed", "ambiguity", "online", "noise", "threshold"),
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
    from glu.errors import DataError
    from glu.machine import SYNCHRONOUS, available_cores, check_reachable
    from glu.studies.learning import study as lc
    from glu.studies.learning.self_supervised import AMBIGUITIES, WORLDS

    for flag, given, allowed in (
        ("--worlds", args.worlds, tuple(WORLDS)),
        ("--ambiguities", args.ambiguities, tuple(AMBIGUITIES)),
    ):
        bad = [a for a in given if a not in allowed]
        if bad or not given:
            raise DataError(f"{flag}: unknown {(bad or ['(none)'])[0]!r}; allowed: {', '.join(allowed)}")
    if args.margin >= 1:
        raise DataError(f"--margin {args.margin}: an accuracy in (0, 1)")
    if args.scheduler not in (None, SYNCHRONOUS):  # before any work: a scheduler that does not answer
        check_reachable(args.scheduler)
    settings = lc.StudySettings(
        **chosen(args, "episodes", "seeds", "worlds", "ambiguities", "test_per_action", "margin")
    )
    from glu.data.source import resolve_data

    source = resolve_data(args.data)
    if args.part != "curves" and not (source.is_real and source.has_gestures):
        raise DataError(
            f"--part {args.part}: the real person is in the real data only, not {source.describe()}"
        )
    engine, label = _engine(args.data)
    here = args.scheduler == SYNCHRONOUS
    where = dict(
        scheduler=None if here else args.scheduler,
        workers=0 if here or args.scheduler else (args.workers or available_cores()),
    )
    out = Path(args.out)
    if args.part in ("curves", "all"):
        _run_curves(engine, label, settings, where, out, _command(args, "curves"))
    if args.part in ("real-person", "all"):
        _run_real_person(engine, source, label, args.draws, where, out, _command(args, "real-person"))
    return 0


def _command(args: argparse.Namespace, part: str) -> str:
    """The command that makes this part again (the data folder, a machine path, as DATA)."""
    seeds = ",".join(map(str, args.seeds if part == "curves" else args.draws))
    common = f" --data {'synthetic' if args.data == 'synthetic' else 'DATA'} -o DIR"
    if part == "real-person":
        return f"glu learning-curves --part real-person --draws {seeds}" + common
    return (
        f"glu learning-curves --episodes {args.episodes} --seeds {seeds} --worlds {','.join(args.worlds)} "
        f"--ambiguities {','.join(args.ambiguities)} --test-per-action {args.test_per_action} "
        f"--margin {args.margin:g}" + common
    )


def _done(what: str, n: int) -> Any:
    """The progress of one task in ``n`` (a seed, a draw): a line each, with how many are done."""
    done = []
    return lambda task: done.append(task) or print(f"  {what} {task} done ({len(done)} of {n})", flush=True)


def _run_curves(engine, label: str, settings, where: dict, out: Path, command: str) -> None:
    from glu.studies.learning import saved, tables
    from glu.studies.learning import study as lc

    n = len(settings.seeds)
    print(
        f"network: {label}; {n} seeds × {settings.episodes:,} episodes, {len(settings.learners())} learners "
        f"({', '.join(settings.worlds)} worlds)",
        flush=True,
    )
    results = lc.learning_study(engine, settings, **where, progress=_done("seed", n))
    rep = tables.replicates(results, settings)
    budgets = tables.budgets_table(rep, settings, label)
    frames = {
        "learning_curves": tables.curves_table(rep, settings, label),
        "learning_budgets": budgets,
        "learning_claims": tables.claims_table(budgets),
        "learning_labels": tables.labels_table(results, settings, label),
    }
    small = saved.check_settings(settings)
    print(
        f"the check run (recomputed by notebook 12): seed {small.seeds[0]}, {small.episodes:,} episodes, "
        f"{small.ambiguities[0]} objects without words",
        flush=True,
    )
    check = lc.learning_study(engine, small, **where)
    # computed first, then written as one set: an interrupt leaves the old run, or one that is refused
    times = lc.update_times(results)
    saved.save_study(out, results, settings, label, command, times, check=(check, small), tables=frames)
    print(
        f"wrote {out}/{saved.STUDY_FILE}, {saved.RESULTS_FILE}, {', '.join(f'{k}.csv' for k in frames)}, "
        f"{saved.CHECK_FOLDER}/"
    )


def _run_real_person(engine, source, label: str, draws, where: dict, out: Path, command: str) -> None:
    from glu.gestures.corpus import gesture_sequences
    from glu.studies.learning import real_person as rp
    from glu.studies.learning import saved

    settings = rp.RealPersonSettings(draws=draws)
    standing = gesture_sequences(source, include_test=False)
    print(f"the real person: {len(standing)} standing segments × {len(draws)} draws", flush=True)
    rows = rp.real_person_study(
        engine, standing, settings, **where, progress=_done("draw", len(draws)), data_source=label
    )
    summary = rp.real_person_summary(rows, settings.bootstrap)
    saved.save_real_person(out, rows, settings, label, command, summary)
    print(f"wrote {out}/{saved.PERSON_FILE}, {saved.PERSON_STUDY_FILE}, {saved.PERSON_SUMMARY_FILE}")
