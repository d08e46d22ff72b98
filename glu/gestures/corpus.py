"""Labelled gesture sequences of a data source: the real recordings, or a seeded synthetic corpus.

The real data (``gestures/<recording>/data.log``, METHOD.md §4; :mod:`glu.data.recordings`) holds four
training recordings of one person repeating one gesture (cut into repetitions automatically by
:mod:`glu.gestures.segmentation`) and two single taps towards a small sphere and a big box, of which the
originals cut their test segments by hand. Without real recordings, every
function here falls back on synthetic gestures (:mod:`glu.gestures.synthetic`) with the same roles, so
the gesture chain runs on any data source.

Frame ranges are 1-based and inclusive, in the numbering of the log, as in the papers.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from glu.data.recordings import ORIGINAL_SEGMENTS, RECORDING_ACTION, TRAINING_RECORDINGS
from glu.data.source import DataSource
from glu.gestures.features import LOG_SCALE, load_features
from glu.gestures.segmentation import (
    DEFAULT_PARAMS,
    RecordingSegmentation,
    Segment,
    SegmentationParams,
    extract,
    segment_recording,
    segment_repetitions,
)
from glu.gestures.synthetic import SyntheticGesture, View, synthesize_gestures, synthesize_recording
from glu.gestures.trajectories import DEFAULT_POLICY, RepairPolicy, repair
from glu.schema import ACTIONS

SYNTHETIC_TEST_SEED_OFFSET = 1000
"""Synthetic test gestures are drawn with ``seed + 1000``, apart from the training corpus of ``seed``."""


class LabelledSequence(NamedTuple):
    """A gesture sequence for training or testing: its action, its features and where it comes from.

    Attributes
    ----------
    action : the action performed
    xyz : array, shape (n_frames, 3) — the features (model units)
    recording : the recording's name
    start, end : its frames in the recording (1-based, inclusive)
    """

    action: str
    xyz: np.ndarray
    recording: str
    start: int
    end: int


class Corpus(list):
    """A list of :class:`LabelledSequence` that says where the sequences come from.

    Attributes
    ----------
    description : one line naming the data (a data source, or the synthetic generator's settings); the
        experiments stamp it on their tables
    """

    def __init__(self, items: Sequence[LabelledSequence] = (), description: str = "") -> None:
        super().__init__(items)
        self.description = description


def original_segments(recording: str) -> list[Segment]:
    """The originals' hand-cut segments of a recording (empty if it has none), labelled with its action."""
    return [
        Segment(a, b, RECORDING_ACTION.get(recording), recording)
        for a, b in ORIGINAL_SEGMENTS.get(recording, ())
    ]


def segment_recording_of(
    source: DataSource,
    recording: str,
    policy: RepairPolicy = DEFAULT_POLICY,
    params: SegmentationParams = DEFAULT_PARAMS,
) -> RecordingSegmentation:
    """Automatic segmentation of one recording of a data folder, labelled with its action if known."""
    return segment_recording(source.hand_log(recording), RECORDING_ACTION.get(recording), policy, params)


def real_segments(
    source: DataSource,
    recordings: Sequence[str] = TRAINING_RECORDINGS,
    include_original: bool = True,
    policy: RepairPolicy = DEFAULT_POLICY,
    params: SegmentationParams = DEFAULT_PARAMS,
) -> list[LabelledSequence]:
    """Labelled segments of the real recordings of ``source``.

    The recordings in ``recordings`` are segmented automatically (repaired by ``policy``); with
    ``include_original`` the hand-cut segments of the single-tap recordings (``ORIGINAL_SEGMENTS``,
    except those of recordings segmented automatically) are added, taken from the repaired trajectory.
    """
    out: list[LabelledSequence] = []
    for rec in recordings:
        seg = segment_recording_of(source, rec, policy, params)
        for piece in seg.pieces:
            for s in piece.segments:
                out.append(LabelledSequence(s.label or "", extract(piece.trajectory, s), rec, s.start, s.end))
    if include_original:
        for rec, ranges in ORIGINAL_SEGMENTS.items():
            if rec in recordings:
                continue
            pieces = load_features(source.hand_log(rec), policy).pieces
            for a, b in ranges:
                piece = next((p for p in pieces if p.frame[0] <= a and b <= p.frame[-1]), None)
                if piece is None:
                    continue
                s = Segment(a, b, RECORDING_ACTION[rec], rec)
                out.append(LabelledSequence(RECORDING_ACTION[rec], extract(piece, s), rec, a, b))
    return out


def original_test_segments(source: DataSource) -> list[LabelledSequence]:
    """The originals' five test segments, as logged (model units, no repair)."""
    out = []
    for name, ranges in ORIGINAL_SEGMENTS.items():
        traj = load_features(source.hand_log(name), policy=None).pieces[0]
        out += [
            LabelledSequence(RECORDING_ACTION[name], traj.frames(a, b).xyz, name, a, b) for a, b in ranges
        ]
    return out


def synthetic_corpus(
    n_per_action: int,
    seed: int = 0,
    *,
    actions: tuple[str, ...] = ACTIONS,
    noise: float = 0.01,
    spike_rate: float = 0.005,
    dropout_rate: float = 0.2,
    view: View | None = None,
) -> Corpus:
    """``n_per_action`` synthetic gestures per action, as repaired feature sequences (:mod:`glu.gestures.synthetic`).

    ``view``: how they are seen (:class:`~glu.gestures.synthetic.View`; default the generator's: a person
    facing the camera), or the robot's own movements (``View(performer="robot")``).
    """
    gestures = synthesize_gestures(
        n_per_action * len(actions),
        seed,
        actions=actions,
        noise=noise,
        spike_rate=spike_rate,
        dropout_rate=dropout_rate,
        view=view,
    )
    seqs = [
        LabelledSequence(g.action, g.features(), f"synthetic-{i}", 1, len(g.t))
        for i, g in enumerate(gestures)
    ]
    seen = "" if view is None else f", {view.describe()}"
    return Corpus(seqs, f"synthetic data: gestures (seed {seed}, {n_per_action} per action{seen})")


def gesture_sequences(
    source: DataSource,
    n_per_action: int = 20,
    seed: int = 0,
    actions: Sequence[str] = ACTIONS,
    include_test: bool = True,
) -> Corpus:
    """Labelled training sequences of a data source: the real segments, or a seeded synthetic corpus.

    With real gesture recordings, the repetitions found by automatic segmentation of the training
    recordings plus, with ``include_test``, the originals' hand-cut segments of the two single-tap
    recordings (leave them out when those recordings are the test data, as in effect anticipation);
    restricted to ``actions``. Otherwise ``n_per_action`` synthetic gestures per action.
    """
    if source.has_gestures:
        seqs = [s for s in real_segments(source, include_original=include_test) if s.action in actions]
        return Corpus(seqs, source.describe())
    return synthetic_corpus(n_per_action, seed, actions=tuple(actions))


def held_out_gestures(source: DataSource, seed: int = 0, n_per_action: int = 2) -> Corpus:
    """Gestures to recognise in the fusion experiments: the originals' five tap segments, as logged, or
    ``n_per_action`` fresh synthetic gestures per action (seeded apart from the training corpus)."""
    if source.has_gestures:
        return Corpus(original_test_segments(source), source.describe())
    corpus = synthetic_corpus(n_per_action, seed + SYNTHETIC_TEST_SEED_OFFSET)
    seqs = [s._replace(recording=f"synthetic {s.action} {i}") for i, s in enumerate(corpus)]
    return Corpus(seqs, corpus.description)


def recording_segmentations(
    source: DataSource, seed: int = 0
) -> list[tuple[RecordingSegmentation, list[Segment]]]:
    """Automatic segmentation of every recording, each with its reference segments.

    Real data: the six logs, with the originals' hand-cut segments as reference. Synthetic data: one
    continuous synthetic recording per action (four repetitions each), with the true repetitions.
    """
    if source.has_gestures:
        return [
            (segment_recording_of(source, n), original_segments(n))
            for n in RECORDING_ACTION
            if source.has_hand_log(n)
        ]
    out = []
    for action in ("grasp", "tap", "touch", "push"):
        g = synthesize_recording(action, 4, seed)
        repaired = repair(g.trajectory())
        name = f"synthetic {action}"
        pieces = [segment_repetitions(tr, action, recording=name) for tr in repaired.pieces if len(tr) >= 2]
        ref = [Segment(a, b, action, name) for a, b in g.segments]
        out.append((RecordingSegmentation(name, pieces, repaired.events), ref))
    return out


def synthetic_recordings(seed: int = 0, noise: float = 0.01) -> dict[str, SyntheticGesture]:
    """Synthetic look-alikes of the six real recordings (:data:`glu.data.recordings.RECORDING_ACTION`).

    Each has the recording's action; the recordings with the originals' segments have their gestures at
    exactly those frames (so ``tap1_hand`` frames 216–351 hold a tap, as in the real log); the other
    training recordings hold four repetitions each. Deterministic in ``seed``.
    """
    out = {}
    for i, (name, action) in enumerate(RECORDING_ACTION.items()):
        if name in ORIGINAL_SEGMENTS:
            out[name] = synthesize_recording(
                action, 0, seed + i, noise=noise, placements=ORIGINAL_SEGMENTS[name]
            )
        else:
            out[name] = synthesize_recording(action, 4, seed + i, noise=noise)
    return out


def hand_log_arrays(gesture: SyntheticGesture) -> tuple[np.ndarray, np.ndarray]:
    """A synthetic recording as a hand log holds it: timestamps (s) and features × 1000, shapes (n,), (n, 3)."""
    traj = gesture.trajectory()
    return traj.t, traj.xyz * LOG_SCALE
