"""Effect anticipation (TCDS 2020): predicting what a tap will do to the object while the hand moves.

On a tap towards a small sphere and one towards a big box, the gesture HMMs score every prefix of the
hand trajectory, ``(1/t) log L(G_1^t | A)`` per model, and every few frames their posterior
``p_HMM(A | G_1^t)`` enters the Affordance–Words network as soft evidence on Action, giving
``p_comb(ObjVel | Shape, Size, G_1^t)`` — the robot anticipates the object's motion before the hand
touches it. :func:`effect_anticipation` runs it (:func:`anticipation_runs`: every case with every bank of
HMMs, and :func:`anticipation_tables`, what notebook 08 writes of them); :func:`case_trajectory` gets the
hand trajectory (the originals' hand-cut segments of the real recordings, or a synthetic tap);
:func:`glu.studies.anticipation.recordings.write_anticipation` turns a run into a Rerun recording.

**The originals' schedule** (docs/method.md §7.4): updates at t = 5, 10, …, the last multiple of 5 within the
segment (t is 1-based within the segment: 90 of T = 94 for the sphere, 145 of T = 146 for the box), and
the scene's description is the best sentence given the evidence of the last update. glu follows it by
default; ``final_update=True`` adds one more update at t = T, marked ``extra``.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from glu.bn.inference import Engine
from glu.data.published import published
from glu.data.source import DataSource
from glu.errors import DataError, ModelError
from glu.fusion import fuse
from glu.gestures.recognizer import Recognizer
from glu.gestures.recordings import load_features
from glu.gestures.synthetic import synthesize_gesture
from glu.gestures.trajectories import RepairPolicy, Trajectory
from glu.hmm import p_hmm_from_loglik
from glu.language.candidates import SentenceSet
from glu.language.descriptions import DEFAULT_SCORE
from glu.language.descriptions import describe as best_sentences
from glu.tidy import tidy

ORIGINAL_STEP = 5
"""The originals fused every 5 frames (``interval = 5`` in their scripts)."""


@dataclass(frozen=True)
class AnticipationCase:
    """One TCDS anticipation experiment: which recording, which frames, which object."""

    name: str
    recording: str
    first: int
    last: int
    evidence: Mapping[str, str]
    description: str


CASES: dict[str, AnticipationCase] = {
    "sphere": AnticipationCase(
        "sphere",
        "tap_notable_seated_1",
        121,
        214,
        {"Shape": "sphere", "Size": "small"},
        "a person taps a small sphere",
    ),
    "box": AnticipationCase(
        "box",
        "norobotview_tap_notable_seated_2",
        230,
        375,
        {"Shape": "box", "Size": "big"},
        "a person taps a big box",
    ),
}
"""The two TCDS cases (docs/method.md §4.3): 1-based inclusive frames of the hand logs."""


@dataclass
class AnticipationRun:
    """The result of one anticipation run.

    Attributes
    ----------
    case, models : names of the case and of the HMM bank used
    evidence : the BN evidence (the object)
    actions : the BN's Action values; columns of ``loglik`` and ``p_hmm`` follow this order
    frames, seconds : frame numbers of the log and seconds from the first frame, shape (T,)
    xyz : the hand features fed to the HMMs, shape (T, 3)
    loglik : ``log L(G_1^t | A)``, shape (T, n_actions)
    p_hmm : ``p_HMM(A | G_1^t)``, shape (T, n_actions)
    update_frames : frames at which the fusion was computed, shape (K,)
    fused : node → ``p_comb(node | evidence, G_1^t)`` at the update frames, shape (K, n_values)
    values : node → its value names
    descriptions : the best verbal description at each update frame (if computed)
    data_source : which data the run used
    parameters : the run's settings (step, rule, targets, score, candidates)
    update_extra : per update, True for the extra update at t = T (not on the originals' schedule), shape (K,)
    """

    case: str
    models: str
    evidence: dict[str, str]
    actions: tuple[str, ...]
    frames: np.ndarray
    seconds: np.ndarray
    xyz: np.ndarray
    loglik: np.ndarray
    p_hmm: np.ndarray
    update_frames: np.ndarray
    fused: dict[str, np.ndarray]
    values: dict[str, tuple[str, ...]]
    data_source: str = ""
    descriptions: list[str] = field(default_factory=list)
    parameters: dict[str, object] = field(default_factory=dict)
    update_extra: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))

    @property
    def update_t(self) -> np.ndarray:
        """t of each update, 1-based within the segment (5, 10, … on the originals' schedule), shape (K,)."""
        return np.searchsorted(self.frames, self.update_frames) + 1

    @property
    def description(self) -> str | None:
        """The scene's description: the best sentence at the last update (None if not computed)."""
        return self.descriptions[-1] if self.descriptions else None

    def as_dict(self) -> dict[str, object]:
        """The run as plain data (what ``glu anticipate --json`` prints).

        ``{"case", "frames": [first, last], "loglik_per_frame": {action: [...]}`` (index i is t = i + 1),
        ``"updates": [{"t", "frame", "p_hmm": {action: p}, <node>: {value: p}, ["extra": true]}, …],
        "description"}``.
        """
        actions = list(self.actions)
        lpf = self.loglik_per_frame
        updates = []
        extra = self.update_extra if len(self.update_extra) else np.zeros(len(self.update_frames), bool)
        for k, (t, f) in enumerate(zip(self.update_t, self.update_frames, strict=True)):
            u: dict[str, object] = {
                "t": int(t),
                "frame": int(f),
                "p_hmm": dict(zip(actions, map(float, self.p_hmm[t - 1]), strict=True)),
            }
            for node, probs in self.fused.items():
                u[node] = dict(zip(self.values[node], map(float, probs[k]), strict=True))
            if extra[k]:
                u["extra"] = True
            updates.append(u)
        return {
            "case": self.case,
            "frames": [int(self.frames[0]), int(self.frames[-1])],
            "loglik_per_frame": {a: [float(x) for x in lpf[:, i]] for i, a in enumerate(actions)},
            "updates": updates,
            "description": self.description,
        }

    @property
    def loglik_per_frame(self) -> np.ndarray:
        """``(1/t) log L(G_1^t | A)``, shape (T, n_actions)."""
        return self.loglik / np.arange(1, len(self.loglik) + 1)[:, None]

    def curves(self) -> pd.DataFrame:
        """Tidy per-frame series: columns
        ``case, models, frame, t, seconds, action, loglik_per_frame, p_hmm``.

        ``seconds``: the frame's time since the segment's first frame.
        """
        T, A = self.loglik.shape
        df = pd.DataFrame(
            {
                "case": self.case,
                "models": self.models,
                "frame": np.repeat(self.frames, A),
                "t": np.repeat(np.arange(1, T + 1), A),
                "seconds": np.repeat(self.seconds, A),
                "action": np.tile(self.actions, T),
                "loglik_per_frame": self.loglik_per_frame.ravel(),
                "p_hmm": self.p_hmm.ravel(),
            }
        )
        return tidy(
            df, f"tcds_anticipation_{self.case}_{self.models}_curves", self.data_source, **self.parameters
        )

    def predictions(self) -> pd.DataFrame:
        """Tidy fused posteriors: columns ``case, models, frame, t, extra, node, value, p``."""
        extra = self.update_extra if len(self.update_extra) else np.zeros(len(self.update_frames), bool)
        rows = [
            (self.case, self.models, int(f), int(t), bool(extra[k]), node, v, p)
            for node, probs in self.fused.items()
            for k, (f, t) in enumerate(zip(self.update_frames, self.update_t, strict=True))
            for v, p in zip(self.values[node], probs[k], strict=True)
        ]
        return tidy(
            pd.DataFrame(rows, columns=["case", "models", "frame", "t", "extra", "node", "value", "p"]),
            f"tcds_anticipation_{self.case}_{self.models}_predictions",
            self.data_source,
            **self.parameters,
        )

    def prediction_changes(self, node: str = "ObjVel") -> list[tuple[int, int, str, float]]:
        """Where the most probable value of ``node`` changes: (t, frame, value, its p_comb), first update
        included."""
        out: list[tuple[int, int, str, float]] = []
        for k, (t, f) in enumerate(zip(self.update_t, self.update_frames, strict=True)):
            j = int(np.argmax(self.fused[node][k]))
            if not out or out[-1][2] != self.values[node][j]:
                out.append((int(t), int(f), self.values[node][j], float(self.fused[node][k][j])))
        return out

    def scene(self) -> str:
        """A markdown description of the run: the scene, the models, and the final beliefs."""
        final = {
            node: dict(zip(self.values[node], probs[-1], strict=True)) for node, probs in self.fused.items()
        }
        lines = [
            f"# Effect anticipation: {CASES[self.case].description if self.case in CASES else self.case}",
            f"*Evidence*: {', '.join(f'{k}={v}' for k, v in self.evidence.items())}; gesture HMMs: "
            f"{self.models}.",
            f"*Frames* {int(self.frames[0])}–{int(self.frames[-1])} ({len(self.frames)} frames).",
            "",
            f"At the last update (frame {int(self.update_frames[-1])}, t = {int(self.update_t[-1])}):",
        ]
        for node, dist in final.items():
            best = max(dist, key=dist.get)
            lines.append(
                f"* p_comb({node}): " + ", ".join(f"{v} {p:.2f}" for v, p in dist.items()) + f" → **{best}**"
            )
        if self.descriptions:
            lines.append(f"* best description: “{self.description}”")
        return "\n".join(lines)


def _bn_order(recognizer: Recognizer, actions: Sequence[str]) -> np.ndarray:
    missing = [a for a in actions if a not in recognizer.actions]
    if missing:
        raise ModelError(
            f"the HMM bank has no model for {', '.join(missing)}; it has {', '.join(recognizer.actions)}"
        )
    return np.array([recognizer.actions.index(a) for a in actions])


def update_indices(n_frames: int, step: int = ORIGINAL_STEP, final_update: bool = False) -> np.ndarray:
    """0-based indices of the fusion updates in a segment of ``n_frames``: t = step, 2·step, … ≤ T, and T if
    asked; int array, shape (n_updates,), ascending frame indices.

    >>> (update_indices(94) + 1).tolist()[-3:], (update_indices(94, final_update=True) + 1).tolist()[-2:]
    ([80, 85, 90], [90, 94])
    """
    if int(step) != step or step < 1:
        raise DataError(f"step={step!r}: the update step must be a whole number of frames ≥ 1")
    idx = np.arange(step - 1, n_frames, step)
    if final_update and (len(idx) == 0 or idx[-1] != n_frames - 1):
        idx = np.r_[idx, n_frames - 1]
    if len(idx) == 0:
        raise DataError(
            f"the segment has {n_frames} frames, fewer than the update step {step}: no update on the "
            "schedule (use a smaller step, or final_update to fuse at the last frame)"
        )
    return idx


def effect_anticipation(
    recognizer: Recognizer,
    engine: Engine,
    trajectory: Trajectory,
    evidence: Mapping[str, str],
    *,
    case: str = "",
    models: str = "",
    step: int = ORIGINAL_STEP,
    final_update: bool = False,
    rule: str = "virtual",
    targets: Sequence[str] = ("ObjVel", "Action"),
    describe: bool | str = False,
    score: str = DEFAULT_SCORE,
    candidates: Iterable[Iterable[str]] | None = None,
) -> AnticipationRun:
    """Score every prefix of ``trajectory`` with the HMMs and fuse their posterior on the originals' schedule.

    Parameters
    ----------
    recognizer : the HMM bank (its models must include the BN's actions; extra models are ignored)
    engine : inference engine of the Affordance–Words network
    trajectory : the hand features, in the units the HMMs expect
    evidence : observed object features, e.g. {"Shape": "sphere", "Size": "small"}
    step : fuse at t = step, 2·step, … (t 1-based within the segment; the originals': 5)
    final_update : also fuse at t = T when T is not a multiple of ``step`` (marked ``extra``)
    rule : how the HMM posterior enters the BN: ``"virtual"`` (the originals') or ``"jeffrey"``
    targets : nodes whose fused posterior is recorded
    describe : the best verbal description at every update (True) or at the last one only (``"last"``)
    score : the sentence score (``"paper"`` or ``"original"``, :data:`glu.language.SCORES`)
    candidates : the sentences to choose from (the originals': their 9,941 samples), None for the whole
        grammar
    """
    actions = engine.bn.schema.values_of("Action")
    order = _bn_order(recognizer, actions)
    X = np.asarray(trajectory.xyz, dtype=float)
    loglik = recognizer.loglik_curve(X)[:, order]
    p_hmm = p_hmm_from_loglik(loglik)
    idx = update_indices(len(X), step, final_update)
    extra = np.zeros(len(idx), dtype=bool)
    extra[-1] = final_update and bool(len(X) % step)
    fused = fuse(engine, list(targets), evidence, p_hmm[idx], rule)
    cands = None if candidates is None else SentenceSet.of(candidates)
    run = AnticipationRun(
        case=case,
        models=models,
        evidence=dict(evidence),
        actions=tuple(actions),
        frames=np.asarray(trajectory.frame),
        seconds=np.asarray(trajectory.t) - float(trajectory.t[0]),
        xyz=X,
        loglik=loglik,
        p_hmm=p_hmm,
        update_frames=np.asarray(trajectory.frame)[idx],
        fused=fused,
        values={t: engine.bn.schema.values_of(t) for t in targets},
        data_source=str(engine.bn.meta.get("data_source", "")),
        parameters={
            "step": step,
            "final_update": final_update,
            "rule": rule,
            "targets": list(targets),
            "score": score,
            "candidates": "grammar" if cands is None else f"{len(cands)} sentences",
        },
        update_extra=extra,
    )
    if describe:
        for i in idx if describe is True else idx[-1:]:
            run.descriptions.append(_best_description(engine, evidence, p_hmm[i], rule, score, cands))
    return run


def _best_description(engine, evidence, p_hmm: np.ndarray, rule: str, score: str, cands) -> str:
    """The best verbal description given the object and p_HMM as soft evidence on Action."""
    best = best_sentences(
        engine, evidence, soft={"Action": p_hmm}, soft_rule=rule, n=1, score=score, candidates=cands
    )
    return str(best["sentence"].iloc[0])


def published_comparison(run: AnticipationRun) -> pd.DataFrame:
    """A run of a TCDS case beside the published Fig. 5 (:mod:`glu.data.published`): curves and final bars.

    Returns
    -------
    DataFrame with columns quantity (``loglik_per_frame`` or ``ObjVel``), key (action or value), t, ours,
    paper, difference (ours − paper), resolution (of the value read from the figure), within
    (``|difference| ≤ resolution``); one row per vertex of the published curves and per bar. The bars
    are compared at the run's last update (the paper's: the last multiple of 5). ``attrs["parameters"]``
    holds the paper's caption and whether the run's description equals it.
    """
    pub = published()["anticipation"][run.case]
    rows = []
    curves = pub["loglik_per_frame"]
    lpf = run.loglik_per_frame
    for a, action in enumerate(run.actions):
        for t, v in zip(curves[action]["t"], curves[action]["value"], strict=True):
            rows.append(("loglik_per_frame", action, int(t), float(lpf[t - 1, a]), v, curves["resolution"]))
    bars = pub["ObjVel"]
    last = int(run.update_t[-1])
    for value, v in bars["values"].items():
        ours = float(run.fused["ObjVel"][-1][run.values["ObjVel"].index(value)])
        rows.append(("ObjVel", value, last, ours, v, bars["resolution"]))
    df = pd.DataFrame(rows, columns=["quantity", "key", "t", "ours", "paper", "resolution"])
    df.insert(5, "difference", df["ours"] - df["paper"])
    df["within"] = df["difference"].abs() <= df["resolution"]
    return tidy(
        df,
        f"tcds_anticipation_{run.case}_published",
        run.data_source,
        reference=published()["read_from"],
        caption=pub["caption"],
        same_caption=run.description == pub["caption"],
    )


def case_trajectory(
    source: DataSource, case: str, seed: int = 0, policy: RepairPolicy | None = None
) -> Trajectory:
    """The hand features of an anticipation case: the originals' segment of the real log, or a synthetic tap.

    Real logs are converted to model units (÷ 1000); by default they are used as logged, like the
    originals did (``policy``: a :class:`~glu.gestures.trajectories.RepairPolicy` to repair tracking gaps and
    outliers first). Synthetic data gives a seeded synthetic tap with the same role.
    """
    c = CASES[case]
    if source.has_hand_log(c.recording):
        pieces = load_features(source.hand_log(c.recording), policy).pieces
        whole = pieces[0] if len(pieces) == 1 else _concat(pieces)
        return whole.frames(c.first, c.last)
    rng = np.random.default_rng(np.random.SeedSequence([seed, 11, list(CASES).index(case)]))
    g = synthesize_gesture("tap", rng, spike_rate=0.0, dropout_rate=0.0)
    traj = g.trajectory()
    return Trajectory(traj.xyz, traj.t, traj.frame, traj.observed, f"synthetic tap ({case})")


def _concat(pieces: Sequence[Trajectory]) -> Trajectory:
    return Trajectory(
        np.concatenate([p.xyz for p in pieces]),
        np.concatenate([p.t for p in pieces]),
        np.concatenate([p.frame for p in pieces]),
        np.concatenate([p.observed for p in pieces]),
        pieces[0].source,
    )


def anticipation_runs(
    banks: Mapping[str, Recognizer], engine: Engine, source: DataSource, seed: int = 0, **options: Any
) -> dict[tuple[str, str], AnticipationRun]:
    """:func:`effect_anticipation` of every case of :data:`CASES` with every bank of HMMs of ``banks`` (name →
    recogniser), bank by bank: the runs by (case, bank). ``options`` go to :func:`effect_anticipation`
    (``step``, ``final_update``, ``rule``, ``describe``, ``score``, ``candidates``); ``seed`` picks the
    synthetic taps of data without the real ones."""
    runs = {}
    for name, recognizer in banks.items():
        for case, c in CASES.items():
            trajectory = case_trajectory(source, case, seed=seed)
            runs[case, name] = effect_anticipation(
                recognizer, engine, trajectory, c.evidence, case=case, models=name, **options
            )
    return runs


def published_comparisons(
    runs: Mapping[tuple[str, str], AnticipationRun], bank: str = "original"
) -> dict[str, pd.DataFrame]:
    """:func:`published_comparison` of each case the HMMs ``bank`` ran (the originals' are those of the
    paper), by case; none without them."""
    return {case: published_comparison(runs[case, bank]) for case in CASES if (case, bank) in runs}


PUBLISHED_REFERENCE = "TCDS 2020 Fig. 5 (published EPS)"
"""What :func:`published_comparison` compares with, as a result table names it."""


def anticipation_tables(
    runs: Mapping[tuple[str, str], AnticipationRun], published: Mapping[str, pd.DataFrame]
) -> list[tuple[pd.DataFrame, str, dict[str, Any]]]:
    """What notebook 08 writes to ``results/`` of its runs (by (case, bank), :func:`anticipation_runs`), as
    ``(frame, name, extra)`` for :meth:`glu.run.outputs.Outputs.table`: each run's curves, and its
    predictions with its final description and where the prediction changes; then each case's comparison
    with the paper (``published``, by case: :func:`published_comparisons`)."""
    out: list[tuple[pd.DataFrame, str, dict[str, Any]]] = []
    for (case, name), run in runs.items():
        out.append((run.curves(), f"tcds_anticipation_{case}_{name}_curves", {}))
        extra = {"final_description": run.description, "prediction_changes": run.prediction_changes()}
        out.append((run.predictions(), f"tcds_anticipation_{case}_{name}_predictions", extra))
    for case, versus in published.items():
        out.append((versus, f"tcds_anticipation_{case}_published", {"reference": PUBLISHED_REFERENCE}))
    return out
