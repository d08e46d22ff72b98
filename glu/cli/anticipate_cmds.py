"""``glu anticipate``: effect anticipation (TCDS 2020) on one of the two tap recordings, frame by frame."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from glu.cli.commands import add_command
from glu.cli.common import (
    add_data_args,
    add_deprecated_alias,
    add_description_args,
    add_json_option,
    add_soft_rule_option,
    json_text,
    positive_int,
    read_candidates,
    say_to,
)
from glu.errors import DataError

DESCRIPTION = """\
A person taps a small sphere (--case sphere) or a big box (--case box). The gesture HMMs score every
prefix of the hand trajectory, (1/t) log L(G_1^t | A) per action, and on the originals' schedule (t = 5,
10, …, the last multiple of --step within the segment; --final-update adds t = T) their posterior
p_HMM(A | G_1^t) enters the Affordance-Words network as soft evidence on Action, giving
p_comb(ObjVel | Shape, Size, G_1^t). The scene is described by the best sentence at the last update; with
--score original --candidates samples it is the paper's caption. --json prints {"case", "frames",
"loglik_per_frame", "updates", "description"} only; the data source goes to stderr.
"""


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``anticipate``."""
    from glu.studies.anticipation.experiment import CASES, ORIGINAL_STEP

    p = add_command(sub, "anticipate", DESCRIPTION, _anticipate)
    p.add_argument(
        "--case",
        choices=tuple(CASES),
        required=True,
        help="; ".join(
            f"{k}: {c.description}, {c.recording} frames {c.first}-{c.last}" for k, c in CASES.items()
        ),
    )
    p.add_argument(
        "--models",
        default="original",
        metavar="original|RECOGNISER",
        help="'original' (the 2013 HMMs of the data folder; touch = their push model) or a recogniser file "
        "from glu hmm train (default: original)",
    )
    add_data_args(p)
    add_soft_rule_option(p, "p_HMM")
    add_deprecated_alias(p, "--rule", "--soft-rule")
    p.add_argument(
        "--step",
        type=positive_int,
        default=ORIGINAL_STEP,
        help=f"fuse at t = step, 2·step, … (default {ORIGINAL_STEP}, the originals')",
    )
    p.add_argument(
        "--final-update",
        action="store_true",
        help="also fuse at the last frame t = T (not on the originals' schedule; marked extra)",
    )
    add_description_args(p)
    add_json_option(p, "one object (case, frames, loglik_per_frame, updates, description)")


def _load_recognizer(spec: str, source: Any) -> tuple[Any, str]:
    from glu.data.source import ORIGINAL_HMMS
    from glu.gestures.recognizer import Recognizer, load_original_models

    if spec == "original":
        path = source.original_hmms(3)
        if path is None:
            raise DataError(
                f"--models original: the originals' HMMs ({ORIGINAL_HMMS[3]}) are not in the data "
                f"({source.describe()}); give --data with the real data, or a recogniser file"
            )
        return load_original_models(path), "original 2013 HMMs (touch = their push model)"
    return Recognizer.load(spec), f"recogniser {Path(spec).name}"


def _anticipate(args: argparse.Namespace) -> int:
    from glu.bn.inference import make_engine
    from glu.bn.learning import learn_bn
    from glu.data.source import load_experiments, resolve_data
    from glu.studies.anticipation.experiment import CASES, case_trajectory, effect_anticipation

    if args.schema is not None or args.experiments is not None:  # offered by the shared options, not used
        raise DataError(
            "anticipate runs the paper's network on its recorded cases; --schema/--experiments are not used "
            "here (give --data)"
        )
    source = resolve_data(args.data)
    case = CASES[args.case]
    recognizer, models = _load_recognizer(args.models, source)
    candidates = read_candidates(args, source)
    df = load_experiments(source, args.words)
    engine = make_engine(learn_bn(df, unseen_words=args.unseen_words))
    trajectory = case_trajectory(source, args.case)
    run = effect_anticipation(
        recognizer,
        engine,
        trajectory,
        case.evidence,
        case=args.case,
        models=args.models,
        step=args.step,
        final_update=args.final_update,
        rule=args.soft_rule,
        targets=("ObjVel",),
        describe="last",
        score=args.score,
        candidates=candidates,
    )
    say = say_to(args.json)
    say(f"# data: {source.describe()}")
    say(f"# network: learned, words={args.words}, unseen words {args.unseen_words}; HMMs: {models}")
    say(
        f"# case {args.case}: {case.description}; {case.recording}, frames {int(run.frames[0])}-"
        f"{int(run.frames[-1])} (T = {len(run.frames)}); evidence "
        + ", ".join(f"{k}={v}" for k, v in case.evidence.items())
    )
    say(
        f"# soft evidence: {args.soft_rule}; updates every {args.step} frames"
        + (" and at t = T (extra)" if args.final_update else " (the originals' schedule)")
        + f"; description: {args.score} score over {args.candidates}"
    )
    if args.json:
        print(json_text(run.as_dict()))
        return 0
    acts = run.actions
    values = run.values["ObjVel"]
    print(
        f"{'t':>4} {'frame':>5}  "
        + " ".join(f"{'p_' + a:>8}" for a in acts)
        + "  "
        + " ".join(f"{v:>7}" for v in values)
    )
    extra = run.as_dict()["updates"]
    for k, u in enumerate(extra):
        print(
            f"{u['t']:>4} {u['frame']:>5}  "
            + " ".join(f"{u['p_hmm'][a]:8.4f}" for a in acts)
            + "  "
            + " ".join(f"{run.fused['ObjVel'][k][j]:7.4f}" for j in range(len(values)))
            + ("  (extra)" if u.get("extra") else "")
        )
    last = run.loglik_per_frame[-1]
    print(
        f"(1/t) log L at t = {len(run.frames)}: "
        + ", ".join(f"{a} {v:.4f}" for a, v in zip(acts, last, strict=True))
    )
    print(f"description: {run.description}")
    return 0
