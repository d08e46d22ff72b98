"""``glu evaluate`` and ``glu corpus``: measure every fusion strategy on a simulated corpus, on Dask (the
sweep of :mod:`glu.studies.corpus_evaluation.sweep`; what each command does: its description below)."""

from __future__ import annotations

import argparse
from pathlib import Path

from glu.cli.commands import add_command
from glu.cli.common import (
    add_cluster_args,
    add_data_option,
    add_out_option,
    command_line,
    output_folder,
    positive_int,
    seed,
)


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``evaluate`` and ``corpus`` commands."""
    e = add_command(
        sub,
        "evaluate",
        "Measure every fusion strategy (gesture only, network only, hard, virtual, Jeffrey, "
        "product) on simulated episodes: the factorial design effects × action prior × inference network × "
        "p_HMM reading × feature set × noise × viewpoint, over recogniser seeds, every strategy at every "
        "observed fraction of the gesture (docs/corpus-evaluation.md). Runs on a LocalCluster sized to the "
        "machine or on an existing Dask cluster (--scheduler), and writes the merged tables to -o DIR; run "
        "it again on the same folder to finish an interrupted sweep.",
        _evaluate,
    )
    c = add_command(
        sub,
        "corpus",
        "Write the simulated episodes of a sweep's design (the same settings as glu evaluate: "
        "--config, --episodes, --seed, --data) to one Parquet file, one row per episode, without scoring "
        "them.",
        _corpus,
    )
    for p in (e, c):  # the sweep's settings
        p.add_argument(
            "--config",
            type=Path,
            metavar="FILE.toml",
            help="sweep settings (see glu.studies.corpus_evaluation.config)",
        )
        p.add_argument("--episodes", type=positive_int, metavar="N", help="episodes in all (default 120000)")
        p.add_argument("--seed", type=seed, metavar="S", help="the corpus's seed (default 0)")
        add_data_option(p, "the network is learned from its experiments")
    add_cluster_args(e, "chunk")
    e.add_argument(
        "--max-chunks",
        type=positive_int,
        metavar="N",
        help="compute at most N chunks now; run again to continue",
    )
    add_out_option(e, "DIR", "output folder (resumable)", folder=True)
    e.add_argument(
        "--save",
        type=output_folder,
        metavar="DIR",
        help="once finished, also write the tables notebook 11 reads (a small subset) to DIR, with their key "
        "and provenance (glu.saved): how sweeps/11_corpus_evaluation/ is made",
    )
    add_out_option(c, "FILE.parquet", "file to write")


def _config(args: argparse.Namespace):
    from dataclasses import replace

    from glu.studies.corpus_evaluation.config import SweepConfig, load_config

    config = load_config(args.config) if args.config else SweepConfig()
    config = config.with_overrides(episodes=args.episodes, seed=args.seed)
    if args.data:
        config = replace(config, network=replace(config.network, data=args.data))
    return config


def _evaluate(args: argparse.Namespace) -> int:
    from glu.studies.corpus_evaluation.sweep import run_sweep

    result = run_sweep(
        _config(args), args.out, scheduler=args.scheduler, workers=args.workers, max_chunks=args.max_chunks
    )
    print(
        f"{result.computed} chunks computed, {result.reused} reused, in {result.seconds:.1f} s → {args.out}"
    )
    if result.summary:
        print(overall_text(result.summary))
        if args.save:
            from glu.studies.corpus_evaluation.sweep import export_saved

            print(f"saved tables → {export_saved(args.out, args.save, command_line(args.data))}")
    return 0


def overall_text(summary: dict) -> str:
    """The winner of each cell of the design at the full gesture, pooled over noise levels and viewpoints:
    one line per (action prior, network, p_HMM, target, metric), with the strategies tied with it."""
    import pandas as pd

    best = pd.DataFrame(summary["best"])
    view = best.viewpoint.iloc[0] if len(best) and "viewpoint" in best else "all"
    lines = [
        f"{summary['episodes']} episodes; {summary['data_source']}",
        f"the best strategy of each cell, {view} view, noise pooled (ties: no adjusted difference); an ECE "
        "is bias-corrected, with its basic bootstrap interval",
    ]
    for r in best.itertuples():
        net = r.inference_network + (f"-{r.learn_experiments}" if r.learn_experiments else "")
        tied = [s for s in r.tied.split(", ") if s and s != r.best]
        lines.append(
            f"  {r.effects:7s} {r.action_prior:8s} {net:14s} {r.p_hmm:18s} {r.features:16s} {r.target:7s} "
            f"{r.metric:9s} {r.best} {r.estimate:.3f} [{r.ci_low:.3f}, {r.ci_high:.3f}]"
            + (f" (no difference: {', '.join(tied)})" if tied else "")
        )
    return "\n".join(lines)


def _corpus(args: argparse.Namespace) -> int:
    from glu.studies.corpus_evaluation.sweep import prepare_world

    config = _config(args)
    engine, label = prepare_world(config)
    from glu.studies.corpus_evaluation.corpus import write_corpus

    path = write_corpus(
        args.out,
        engine,
        config.conditions,
        config.per_condition,
        config.seed,
        config.chunk_size,
        label,
        replications=config.recognizer_seeds,
        scenario=config.scenario,
        gestures=config.gestures,
        views={v: config.views[v] for v in config.viewpoints},
    )
    print(
        f"{config.n_episodes} episodes ({len(config.conditions)} conditions × {config.recognizer_seeds} "
        f"replications) → {path}"
    )
    return 0
