"""``glu gestures segment``, ``glu hmm train`` and ``glu recognize``: gestures from hand logs to p_HMM(A | G)
(what a LOG argument and a frame range are: ``LOG_TEXT``, ``FRAMES_TEXT``)."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import Any

from glu.cli.commands import add_command, add_group
from glu.cli.common import (
    add_data_option,
    add_hmm_size_args,
    add_json_option,
    add_out_option,
    hmm_config,
    json_text,
    nonneg_float,
    output_image,
    positive_float,
    positive_int,
    progress,
    say_to,
    seed,
)
from glu.cli.terminal import one_line
from glu.data.source import HAND_LOG
from glu.errors import DataError
from glu.gestures.features import HORIZONTAL_FALLBACK, VERTICAL_FALLBACK
from glu.gestures.invariants import ALL, INVARIANCE_MEANING, INVARIANCES, RAW, Invariants
from glu.gestures.synthetic import GESTURES
from glu.hmm import RECIPES, TrainingConfig
from glu.schema import ACTIONS

LOG_TEXT = (
    "A LOG is a YARP hand log (data.log), a recording folder holding one, or the name of a recording of the "
    "data folder (tap1_hand: DATA/gestures/tap1_hand/data.log)."
)
"""What the help of the commands taking a hand log says about it."""
FRAMES_TEXT = "Frames A:B are 1-based and inclusive, in the numbering of the log, as in the papers."

SYNTHETIC_NOISE = 0.01
"""Default sensor noise (m) of ``glu hmm train --synthetic``."""


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``gestures`` and ``hmm`` command groups and ``recognize``."""
    _register_gestures(sub)
    _register_hmm(sub)
    _register_recognize(sub)


def _register_gestures(sub: argparse._SubParsersAction) -> None:
    """Add ``gestures segment``."""
    gsub = add_group(
        sub,
        "gestures",
        "Inspect hand-trajectory logs: repair their tracking problems and find the gesture "
        "repetitions in them. " + LOG_TEXT,
    )
    s = add_command(
        gsub,
        "segment",
        "Repair a hand log (interpolate short gaps, split at long ones, replace spikes), "
        "then find the repetitions of the gesture from the distance of the hand to its rest pose. --json "
        'prints {"log", "recording", "tracking", "events", "segments", "left_out"}; the rest goes to stderr.',
        _segment,
        help="find the gesture repetitions in a hand log and print them",
    )
    s.add_argument("log", help="hand log: a data.log, a recording folder, or a recording name")
    add_data_option(s, "used to find a recording by name")
    s.add_argument(
        "--plot", type=output_image, metavar="PNG", help="also draw the segmentation into this image"
    )
    s.add_argument("--label", help="action performed (default: from the recording's name, if known)")
    add_json_option(s, "the segments and tracking events")


def _register_hmm(sub: argparse._SubParsersAction) -> None:
    """Add ``hmm train``."""
    hsub = add_group(
        sub,
        "hmm",
        "Train one left-to-right GMM-HMM per action, on the real recordings, synthetic gestures "
        "or your own labelled recordings, and save them as a recogniser file that glu recognize and glu "
        "anticipate take (--models FILE).",
    )
    t = add_command(
        hsub,
        "train",
        "Train on the automatically segmented standing recordings (--data), on synthetic "
        "gestures (--synthetic N, N per action), or on your own labelled recordings (--recordings: a folder "
        "with one subfolder per action, or a CSV manifest file,label[,frames]). --features chooses "
        "invariant features; the recogniser file records them and glu recognize applies them.",
        _train,
        help="train one left-to-right GMM-HMM per action and save the recogniser (JSON)",
        epilog="invariances: "
        + "; ".join(f"{k} = {v}" for k, v in INVARIANCE_MEANING.items())
        + " (formulas: glu.gestures.invariants)",
    )
    _add_training_data(t)
    _add_training_settings(t)


def _add_training_data(t: argparse.ArgumentParser) -> None:
    """``hmm train``'s data (``--data``, ``--synthetic``, ``--recordings``) and output."""
    src = t.add_mutually_exclusive_group()
    add_data_option(src)
    src.add_argument(
        "--synthetic", type=positive_int, metavar="N", help="train on N synthetic gestures per action"
    )
    src.add_argument(
        "--recordings",
        type=Path,
        metavar="PATH",
        help="your labelled recordings, one gesture each: a folder with one subfolder per action (its name "
        "is the label) holding .csv/.tsv/.npy tables, .log files or recording folders; or a CSV manifest "
        "with the columns file,label[,frames A:B]",
    )
    add_out_option(t, "RECOGNISER", "file to write (JSON)")


def _add_training_settings(t: argparse.ArgumentParser) -> None:
    """``hmm train``'s actions, model sizes, EM settings, recipe and features."""
    t.add_argument(
        "--actions",
        type=_actions,
        default=None,
        help=f"comma-separated (default: {','.join(ACTIONS)}; with --recordings: every label found)",
    )
    add_hmm_size_args(t)
    d = TrainingConfig()
    t.add_argument(
        "--tol", type=positive_float, default=d.tol, help=f"EM tolerance per frame (default {d.tol:g})"
    )
    t.add_argument(
        "--covar-reg",
        type=positive_float,
        default=d.covar_reg,
        metavar="R",
        help=f"strength of the covariance prior (default {d.covar_reg:g}; larger: broader Gaussians)",
    )
    t.add_argument(
        "--noise",
        type=nonneg_float,
        default=SYNTHETIC_NOISE,
        help=f"synthetic sensor noise, m (default {SYNTHETIC_NOISE:g})",
    )
    t.add_argument("--seed", type=seed, default=0, help="random seed (default 0)")
    t.add_argument(
        "--recipe",
        choices=RECIPES,
        default=RECIPES[0],
        help="glu = time slices + GaussianMixture, then EM (default); mixsplit = the originals': "
        "flat start, Baum-Welch, split the heaviest component, Baum-Welch, … up to M",
    )
    t.add_argument(
        "--features",
        type=_features,
        default=Invariants(),
        metavar="LIST",
        help=f"{RAW} (default), {ALL}, or comma-separated invariances among {','.join(INVARIANCES)}",
    )
    _add_body_size(t, "--recordings: the body size of t,x,y,z tables")
    t.add_argument(
        "--include-test",
        action="store_true",
        help="real data: also train on the originals' hand-cut segments of the two seated taps (the "
        "effect-anticipation test gestures; default: the standing recordings only)",
    )


def _add_body_size(p: argparse.ArgumentParser, which: str) -> None:
    """``--body-size H V``: what a t,x,y,z table (no skeleton) is divided by; ``which`` starts its help."""
    p.add_argument(
        "--body-size",
        nargs=2,
        type=positive_float,
        metavar=("H", "V"),
        help=f"{which}, horizontal (shoulder) and vertical (neck-torso), m (default: the originals' "
        f"{HORIZONTAL_FALLBACK:g} {VERTICAL_FALLBACK:g})",
    )


def _register_recognize(sub: argparse._SubParsersAction) -> None:
    r = add_command(
        sub,
        "recognize",
        "Score a hand log (or frames A:B of it) under each action's HMM and print the "
        "log-likelihoods and the posterior with equal priors; --stream prints them after every frame. "
        + LOG_TEXT
        + " "
        + FRAMES_TEXT,
        _recognize,
    )
    r.add_argument(
        "log",
        help="a YARP data.log, a recording folder or name, or a .csv/.tsv/.npy trajectory "
        "(t,x,y,z of the hand in the torso frame in m, or skeleton joints)",
    )
    r.add_argument("--frames", type=_frames, metavar="A:B", help="frames A to B (1-based, inclusive)")
    r.add_argument(
        "--models",
        default="original",
        metavar="original|RECOGNISER",
        help="'original' (the 2013 models of the data folder; touch = their push model) or a recogniser "
        "file from glu hmm train (default: original)",
    )
    add_data_option(r)
    r.add_argument(
        "--stream", action="store_true", help="one line per frame: log L(G_1^t | A), p_HMM(A | G_1^t)"
    )
    add_json_option(r, '{"loglik": {…}, "posterior": {…}, "typicality": {…}} (with --stream: one a frame)')
    r.add_argument("--repair", action="store_true", help="repair the log first (default: frames as logged)")
    _add_body_size(r, "for a t,x,y,z table: the body size")


# ------------------------------------------------------------------ argument types


def _frames(s: str) -> tuple[int, int]:
    parts = s.split(":")
    try:
        if len(parts) != 2:
            raise ValueError
        a, b = int(parts[0]), int(parts[1])
    except ValueError:
        raise argparse.ArgumentTypeError(f"{s!r} is not A:B with integers A ≤ B, e.g. 216:351") from None
    if not 1 <= a <= b:
        raise argparse.ArgumentTypeError(f"{s!r}: need 1 ≤ A ≤ B (frames are 1-based, inclusive)")
    return a, b


def _features(s: str) -> Invariants:
    from glu.errors import GluError

    if not s.strip():
        raise argparse.ArgumentTypeError(
            f"expected {RAW}, {ALL} or a comma-separated list, not an empty string"
        )
    try:
        return Invariants.parse(s)
    except GluError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


def _actions(s: str) -> tuple[str, ...]:
    acts = tuple(a.strip() for a in s.split(",") if a.strip())
    if not acts or len(set(acts)) != len(acts) or not all(a.isidentifier() for a in acts):
        raise argparse.ArgumentTypeError(f"{s!r}: give distinct action names, comma-separated")
    return acts


# ------------------------------------------------------------------ helpers


def _resolve_log(log: str, data: str | None) -> tuple[Path, Any]:
    """The log file for a LOG argument, and the data source if one was needed to find it."""
    p = Path(log)
    if p.is_dir():
        p = p / HAND_LOG
    if p.exists():
        return p, None
    if "/" not in log and os.sep not in log and not p.suffix:  # a recording's name, looked up in the data
        from glu.data.source import resolve_data

        source = resolve_data(data)
        return source.hand_log(log), source
    raise DataError(
        f"{log}: file not found (a YARP hand log, a recording folder, a .csv/.tsv/.npy trajectory, or the "
        "name of a recording in the data)"
    )


# ------------------------------------------------------------------ handlers


def _segment(args: argparse.Namespace) -> int:
    from glu.gestures.corpus import RECORDING_ACTION, original_segments
    from glu.gestures.recordings import segment_recording

    if args.label is not None and args.label not in ACTIONS:
        raise DataError(
            f"--label {args.label!r}: not an action of the recordings; allowed: {', '.join(ACTIONS)}"
        )
    say = say_to(args.json)
    path, source = _resolve_log(args.log, args.data)
    if source is not None:
        say(f"data: {source.describe()}")
    name = path.parent.name if path.name == HAND_LOG else path.stem
    seg = segment_recording(path, label=args.label if args.label is not None else RECORDING_ACTION.get(name))
    if args.json:
        print(json_text({"log": str(path), **seg.as_dict()}))
    else:
        _print_segmentation(path, seg)
    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        from glu.plots import save_figure
        from glu.studies.replication.gesture_figures import plot_segmentation

        fig, ax = plt.subplots(figsize=(12, 4), layout="constrained")
        plot_segmentation(
            ax,
            seg,
            f"{seg.recording}: {len(seg.segments)} segments",
            reference=original_segments(seg.recording),
        )
        fmt = Path(args.plot).suffix.lstrip(".").lower() or "png"
        (written,) = save_figure(fig, args.plot, formats=(fmt,))
        plt.close(fig)
        say(f"plot: {written}")
    return 0


def _print_segmentation(path: Path, seg: Any) -> None:
    from glu.gestures.trajectories import summarize_events

    print(f"log: {path} ({seg.recording})")
    print(f"tracking: {summarize_events(seg.events)}")
    for e in seg.events:
        if e.kind in ("gap", "jump", "short-piece"):
            print(f"  {e.describe()}")
    print(f"segments: {len(seg.segments)}")
    for i, s in enumerate(seg.segments, 1):
        print(
            f"  {i}. frames {s.start}:{s.end} ({s.n_frames} frames, peak activity {s.peak:.2f})"
            + (f"  {s.label}" if s.label else "")
        )
    if seg.rejected:
        print(f"left out: {len(seg.rejected)}")
        for s, why in seg.rejected:
            print(f"  frames {s.start}:{s.end}: {why}")


def _train(args: argparse.Namespace) -> int:
    from glu.gestures.recognizer import train_recognizer

    actions = args.actions or ACTIONS
    if args.body_size and args.recordings is None:
        raise DataError("--body-size goes with --recordings (the body size of your t,x,y,z tables)")
    if args.recordings is not None:
        from glu.gestures.corpus import labelled_recordings

        seqs = labelled_recordings(args.recordings, tuple(args.body_size) if args.body_size else None)
        print(f"data: {seqs.description} ({len(seqs)} recordings)")
        found = tuple(dict.fromkeys(s.action for s in seqs))
        unknown = [a for a in args.actions or () if a not in found]
        if unknown:
            raise DataError(
                f"--actions {', '.join(unknown)}: no such label; the labels are {', '.join(found)}"
            )
        actions = args.actions or found
        meta: dict[str, Any] = {"data": seqs.description}
    elif args.synthetic:
        from glu.gestures.corpus import synthetic_corpus

        unknown = [a for a in actions if a not in GESTURES]
        if unknown:
            raise DataError(f"--actions: no synthetic {', '.join(unknown)}; allowed: {', '.join(GESTURES)}")
        print(
            f"data: {args.synthetic} synthetic gestures per action (seed {args.seed}, noise {args.noise} m)"
        )
        seqs = synthetic_corpus(args.synthetic, args.seed, actions=actions, noise=args.noise)
        meta = {"data": f"synthetic, {args.synthetic} per action, noise {args.noise} m"}
    else:
        from glu.data.source import resolve_data
        from glu.gestures.corpus import real_segments

        source = resolve_data(args.data)
        print(f"data: {source.describe()}")
        if not source.has_gestures:
            raise DataError(
                f"the data source has no gesture recordings ({source.describe()}); "
                "give --data DIR with gestures/, or --synthetic N"
            )
        seqs = real_segments(source, include_original=args.include_test)
        meta = {"data": source.describe()}
    by_action = {a: [s.xyz for s in seqs if s.action == a] for a in actions}
    empty = [a for a, v in by_action.items() if not v]
    if empty:
        raise DataError(f"no training segments for {', '.join(empty)}")
    for a, v in by_action.items():
        print(f"  {a}: {len(v)} sequences, {sum(len(x) for x in v)} frames")
    config = hmm_config(args, "tol", "covar_reg", "recipe")
    with progress(len(by_action), "train", "model") as bar:  # ticks while EM runs, as each model converges
        rec = train_recognizer(
            by_action,
            config,
            seed=args.seed,
            warn=False,
            meta=meta,
            features=args.features,
            progress=bar.update if bar is not None else None,
        )
    print(f"  features: {rec.features.name} ({rec.features.describe()})")
    for r in rec.reports.values():
        print(("  " if r.converged else "  warning: ") + r.describe())
    rec.save(args.out)
    print(f"wrote {args.out}")
    return 0


def _load_models(spec: str, data: str | None, say: Any) -> Any:
    from glu.gestures.recognizer import Recognizer

    if spec == "original":
        from glu.data.source import ORIGINAL_HMMS, resolve_data
        from glu.gestures.corpus import original_recognizer

        source = resolve_data(data)
        say(f"data: {source.describe()}")
        mat = source.file(ORIGINAL_HMMS[3])
        say(f"models: {mat} (original 2013 HMMs; touch = their push model)")
        return original_recognizer(source)
    rec = Recognizer.load(spec)
    say(f"models: {spec} ({', '.join(rec.actions)}; features {rec.features.name})")
    return rec


def _recognize(args: argparse.Namespace) -> int:
    import numpy as np

    from glu.gestures.recordings import load_features

    say = say_to(args.json)
    path, source = _resolve_log(args.log, args.data)  # a missing file is said before the models are read
    rec = _load_models(args.models, args.data, say)
    if source is not None and args.models != "original":
        say(f"data: {source.describe()}")
    pieces = load_features(path, policy=None, body=tuple(args.body_size) if args.body_size else None).pieces
    traj = pieces[0]
    if args.repair:
        from glu.gestures.trajectories import repair

        rp = repair(traj)
        traj = next(
            (p for p in rp.pieces if args.frames is None or p.frame[0] <= args.frames[0] <= p.frame[-1]),
            rp.pieces[0],
        )
    if args.frames:
        traj = traj.frames(*args.frames)
    a0, a1 = int(traj.frame[0]), int(traj.frame[-1])
    say(f"log: {path}, frames {a0}:{a1} ({len(traj)} frames)")
    X = traj.xyz
    acts = rec.actions
    if args.stream:
        stream = rec.stream()
        if not args.json:
            print(
                "frame "
                + " ".join(f"{'logL_' + a:>12s}" for a in acts)
                + " "
                + " ".join(f"{'p_' + a:>9s}" for a in acts)
                + "  best"
            )
        for f, x in zip(traj.frame, X, strict=True):
            step = stream.push(x)
            if args.json:
                print(json_text(_as_json(acts, step.loglik, step.p_hmm, frame=int(f))))
            else:
                print(
                    f"{int(f):5d} "
                    + " ".join(f"{v:12.3f}" for v in step.loglik)
                    + " "
                    + " ".join(f"{v:9.4f}" for v in step.p_hmm)
                    + f"  {acts[int(np.argmax(step.loglik))]}"
                )
        return 0
    ll = rec.loglik(X)
    p = rec.p_hmm(X)
    verdict = rec.typicality(X)
    if args.json:
        print(json_text({**_as_json(acts, ll, p), "typicality": verdict.to_json()}))
        if verdict.atypical:
            print(verdict.message(), file=sys.stderr)
        return 0
    print(f"{'action':8s} {'log L(G|A)':>12s} {'p_HMM(A|G)':>11s}")
    for a, v, q in zip(acts, ll, p, strict=True):
        print(f"{one_line(a):8s} {v:12.3f} {q:11.4f}")
    print(f"recognised: {one_line(acts[int(np.argmax(ll))])}")
    print(verdict.message(), file=sys.stderr if verdict.atypical else sys.stdout)
    return 0


def _as_json(actions: tuple[str, ...], ll: Any, p: Any, **extra: Any) -> dict[str, Any]:
    return {
        **extra,
        "loglik": {a: float(v) for a, v in zip(actions, ll, strict=True)},
        "posterior": {a: float(v) for a, v in zip(actions, p, strict=True)},
    }
