"""Effect anticipation (TCDS 2020): predicting what a tap will do to the object while the hand moves.

On a tap towards a small sphere and one towards a big box, the gesture HMMs score every prefix of the
hand trajectory, ``(1/t) log L(G_1^t | A)`` per model, and every few frames their posterior
``p_HMM(A | G_1^t)`` enters the Affordance–Words network as soft evidence on Action, giving
``p_comb(ObjVel | Shape, Size, G_1^t)`` — the robot anticipates the object's motion before the hand
touches it. :func:`effect_anticipation` runs it; :func:`case_trajectory` gets the hand trajectory (the
originals' hand-cut segments of the real recordings, or a synthetic tap);
:func:`glu.recording.write_anticipation` turns a run into a Rerun recording.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from glu.bn.inference import InferenceEngine
from glu.data.source import DataSource
from glu.errors import ModelError
from glu.experiments.common import tidy
from glu.fusion import fuse
from glu.gestures.features import load_features
from glu.gestures.forward import p_hmm_from_loglik
from glu.gestures.recognizer import Recognizer
from glu.gestures.synthetic import synthesize_gesture
from glu.gestures.trajectories import RepairPolicy, Trajectory
from glu.language.descriptions import describe as best_sentences


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
        "sphere", "tap_notable_seated_1", 121, 214, {"Shape": "sphere", "Size": "small"},
        "a person taps a small sphere",
    ),
    "box": AnticipationCase(
        "box", "norobotview_tap_notable_seated_2", 230, 375, {"Shape": "box", "Size": "big"},
        "a person taps a big box",
    ),
}  # fmt: skip
"""The two TCDS cases (METHOD.md §4–5): 1-based inclusive frames of the hand logs."""


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
    parameters : the run's settings (step, rule, targets)
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

    @property
    def loglik_per_frame(self) -> np.ndarray:
        """``(1/t) log L(G_1^t | A)``, shape (T, n_actions)."""
        return self.loglik / np.arange(1, len(self.loglik) + 1)[:, None]

    def curves(self) -> pd.DataFrame:
        """Tidy per-frame series: columns ``case, models, frame, t, action, loglik_per_frame, p_hmm``."""
        T, A = self.loglik.shape
        df = pd.DataFrame({
            "case": self.case, "models": self.models,
            "frame": np.repeat(self.frames, A), "t": np.repeat(np.arange(1, T + 1), A),
            "action": np.tile(self.actions, T),
            "loglik_per_frame": self.loglik_per_frame.ravel(), "p_hmm": self.p_hmm.ravel(),
        })  # fmt: skip
        return tidy(
            df, f"tcds_anticipation_{self.case}_{self.models}_curves", self.data_source, **self.parameters
        )

    def predictions(self) -> pd.DataFrame:
        """Tidy fused posteriors: columns ``case, models, frame, node, value, p``."""
        rows = []
        for node, probs in self.fused.items():
            for k, f in enumerate(self.update_frames):
                for v, p in zip(self.values[node], probs[k], strict=True):
                    rows.append(
                        {
                            "case": self.case,
                            "models": self.models,
                            "frame": int(f),
                            "node": node,
                            "value": v,
                            "p": p,
                        }
                    )
        return tidy(pd.DataFrame(rows), f"tcds_anticipation_{self.case}_{self.models}_predictions",
                    self.data_source, **self.parameters)  # fmt: skip

    def scene(self) -> str:
        """A markdown description of the run: the scene, the models, and the final beliefs."""
        final = {
            node: dict(zip(self.values[node], probs[-1], strict=True)) for node, probs in self.fused.items()
        }
        lines = [
            f"# Effect anticipation: {CASES[self.case].description if self.case in CASES else self.case}",
            f"*Evidence*: {', '.join(f'{k}={v}' for k, v in self.evidence.items())}; gesture HMMs: {self.models}.",
            f"*Frames* {int(self.frames[0])}–{int(self.frames[-1])} ({len(self.frames)} frames).",
            "",
            "At the last frame:",
        ]
        for node, dist in final.items():
            best = max(dist, key=dist.get)
            lines.append(
                f"* p_comb({node}): " + ", ".join(f"{v} {p:.2f}" for v, p in dist.items()) + f" → **{best}**"
            )
        if self.descriptions:
            lines.append(f"* best description: “{self.descriptions[-1]}”")
        lines.append(f"\n<small>{self.data_source}</small>")
        return "\n".join(lines)


def _bn_order(recognizer: Recognizer, actions: Sequence[str]) -> np.ndarray:
    missing = [a for a in actions if a not in recognizer.actions]
    if missing:
        raise ModelError(
            f"the HMM bank has no model for {', '.join(missing)}; it has {', '.join(recognizer.actions)}"
        )
    return np.array([recognizer.actions.index(a) for a in actions])


def effect_anticipation(
    recognizer: Recognizer,
    engine: InferenceEngine,
    trajectory: Trajectory,
    evidence: Mapping[str, str],
    *,
    case: str = "",
    models: str = "",
    step: int = 5,
    rule: str = "virtual",
    targets: Sequence[str] = ("ObjVel", "Action"),
    describe: bool = False,
) -> AnticipationRun:
    """Score every prefix of ``trajectory`` with the HMMs and fuse their posterior every ``step`` frames.

    Parameters
    ----------
    recognizer : the HMM bank (its models must include the BN's actions; extra models are ignored)
    engine : inference engine of the Affordance–Words network
    trajectory : the hand features, in the units the HMMs expect
    evidence : observed object features, e.g. {"Shape": "sphere", "Size": "small"}
    step : fuse every ``step`` frames (and at the last frame)
    rule : how the HMM posterior enters the BN: ``"virtual"`` (the originals') or ``"jeffrey"``
    targets : nodes whose fused posterior is recorded
    describe : also compute the best verbal description at each update (needs :mod:`glu.language`)
    """
    actions = engine.bn.schema.values_of("Action")
    order = _bn_order(recognizer, actions)
    X = np.asarray(trajectory.xyz, dtype=float)
    loglik = recognizer.loglik_curve(X)[:, order]
    p_hmm = p_hmm_from_loglik(loglik)
    T = len(X)
    idx = np.unique(np.r_[np.arange(step - 1, T, step), T - 1])
    fused = fuse(engine, list(targets), evidence, p_hmm[idx], rule)
    run = AnticipationRun(
        case=case, models=models, evidence=dict(evidence), actions=tuple(actions),
        frames=np.asarray(trajectory.frame), seconds=np.asarray(trajectory.t) - float(trajectory.t[0]),
        xyz=X, loglik=loglik, p_hmm=p_hmm, update_frames=np.asarray(trajectory.frame)[idx], fused=fused,
        values={t: engine.bn.schema.values_of(t) for t in targets},
        data_source=str(engine.bn.meta.get("data_source", "")),
        parameters={"step": step, "rule": rule, "targets": list(targets)},
    )  # fmt: skip
    if describe:
        for i in idx:
            best = best_sentences(engine, evidence, soft={"Action": p_hmm[i]}, soft_rule=rule, n=1)
            run.descriptions.append(str(best["sentence"].iloc[0]))
    return run


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
        np.concatenate([p.xyz for p in pieces]), np.concatenate([p.t for p in pieces]),
        np.concatenate([p.frame for p in pieces]), np.concatenate([p.observed for p in pieces]), pieces[0].source,
    )  # fmt: skip
