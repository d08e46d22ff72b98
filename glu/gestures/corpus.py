"""Labelled gesture sequences of a data source: the real recordings, or a seeded synthetic corpus.

The real data (``gestures/<recording>/data.log``, docs/method.md §4.1; :mod:`glu.data.recordings`) holds four
training recordings of one person repeating one gesture (cut into repetitions automatically by
:mod:`glu.gestures.segmentation`) and two single taps towards a small sphere and a big box, of which the
originals cut their test segments by hand. Without real recordings, every
function here falls back on synthetic gestures (:mod:`glu.gestures.synthetic`) with the same roles, so
the gesture chain runs on any data source.

Frame ranges are 1-based and inclusive, in the numbering of the log, as in the papers.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import NamedTuple

import numpy as np

from glu.data.hand_logs import FILE_NAME
from glu.data.recordings import ORIGINAL_SEGMENTS, RECORDING_ACTION, TRAINING_RECORDINGS
from glu.data.source import DataSource
from glu.data.trajectory_files import is_trajectory_file
from glu.errors import DataError
from glu.gestures.features import LOG_SCALE
from glu.gestures.recognizer import Recognizer, load_original_models
from glu.gestures.recordings import load_features, segment_recording
from glu.gestures.segmentation import (
    DEFAULT_PARAMS,
    RecordingSegmentation,
    Segment,
    SegmentationParams,
    extract,
    segment_repetitions,
)
from glu.gestures.synthetic import SyntheticGesture, View, synthesize_gestures, synthesize_recording
from glu.gestures.trajectories import DEFAULT_POLICY, RepairPolicy, repair
from glu.gestures.typicality import FRAMES_KEY, FeatureRanges
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


MAX_SYNTHETIC_PER_ACTION = 100_000
"""The most synthetic gestures per action :func:`synthetic_corpus` makes (each is a few hundred frames)."""


def synthetic_corpus(
    n_per_action: int,
    seed: int = 0,
    *,
    actions: tuple[str, ...] = ACTIONS,
    view: View | None = None,
    **sensor: float,
) -> Corpus:
    """``n_per_action`` synthetic gestures per action, as repaired feature sequences
    (:mod:`glu.gestures.synthetic`).

    ``view``: how they are seen (:class:`~glu.gestures.synthetic.View`; default the generator's: a person
    facing the camera), or the robot's own movements (``View(performer="robot")``); ``sensor``: ``noise``,
    ``spike_rate``, ``dropout_rate``, as :func:`~glu.gestures.synthetic.synthesize_gestures` (its defaults).
    ``n_per_action`` is at most :data:`MAX_SYNTHETIC_PER_ACTION` (DataError beyond).
    """
    if n_per_action > MAX_SYNTHETIC_PER_ACTION:
        from glu.errors import DataError

        raise DataError(
            f"{n_per_action:,} synthetic gestures per action: at most {MAX_SYNTHETIC_PER_ACTION:,} are made"
        )
    gestures = synthesize_gestures(n_per_action * len(actions), seed, actions=actions, view=view, **sensor)
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
        cut = ORIGINAL_SEGMENTS.get(name)  # the originals' segments, where the gestures are placed
        out[name] = synthesize_recording(
            action, 4 if cut is None else 0, seed + i, noise=noise, placements=cut
        )
    return out


def hand_log_arrays(gesture: SyntheticGesture) -> tuple[np.ndarray, np.ndarray]:
    """A synthetic recording as a hand log holds it: timestamps (s) and features × 1000, shapes (n,),
    (n, 3)."""
    traj = gesture.trajectory()
    return traj.t, traj.xyz * LOG_SCALE


MANIFEST_COLUMNS: tuple[str, ...] = ("file", "label", "frames")
"""The columns of a manifest of labelled recordings (``frames`` optional: ``A:B``, 1-based, inclusive)."""


def _recording_files(folder: Path) -> list[Path]:
    """The recordings in one action's folder: trajectory tables, YARP logs, and recording folders."""
    found = []
    for p in sorted(folder.iterdir()):
        if p.name.startswith("."):
            continue
        if p.is_dir() and (p / FILE_NAME).is_file():
            found.append(p / FILE_NAME)
        elif p.is_file() and (is_trajectory_file(p) or p.name == FILE_NAME or p.suffix == ".log"):
            found.append(p)
    return found


def _read_manifest(path: Path) -> list[tuple[Path, str, tuple[int, int] | None, int]]:
    """(file, label, frames, line) of every row of a CSV manifest; files relative to the manifest."""
    import csv

    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise DataError(f"{path}: cannot read the manifest ({e})") from None
    rows = list(csv.reader(text.splitlines()))
    if not rows or [c.strip() for c in rows[0]][:2] != ["file", "label"]:
        raise DataError(f"{path}: a manifest starts with the header file,label[,frames]; got {rows[:1]}")
    header = [c.strip() for c in rows[0]]
    if len(header) > 3 or (len(header) == 3 and header[2] != "frames"):
        raise DataError(f"{path}: columns must be {', '.join(MANIFEST_COLUMNS)}; got {', '.join(header)}")
    out = []
    for line, row in enumerate(rows[1:], start=2):
        if not any(c.strip() for c in row):
            continue
        if len(row) != len(header):
            raise DataError(f"{path}, line {line}: expected {len(header)} fields, got {len(row)}")
        file, label = row[0].strip(), row[1].strip()
        if not file or not label:
            raise DataError(f"{path}, line {line}: empty file or label")
        frames = None
        if len(row) == 3 and row[2].strip():
            a, sep, b = row[2].strip().partition(":")
            if not sep or not a.strip().isdigit() or not b.strip().isdigit() or int(a) > int(b):
                raise DataError(f"{path}, line {line}: frames must be A:B with 1 ≤ A ≤ B, got {row[2]!r}")
            frames = (int(a), int(b))
        target = Path(file) if Path(file).is_absolute() else path.parent / file
        if target.is_dir() and (target / FILE_NAME).is_file():
            target = target / FILE_NAME
        out.append((target, label, frames, line))
    if not out:
        raise DataError(f"{path}: the manifest lists no recordings")
    return out


def labelled_recordings(path: str | os.PathLike, body: tuple[float, float] | None = None) -> Corpus:
    """Your own labelled recordings, each one gesture: a folder with one subfolder per action, or a CSV
    manifest.

    Parameters
    ----------
    path : a folder whose subfolders are named by action and hold that action's recordings (YARP logs,
        recording folders with a ``data.log``, or CSV/TSV/NPY trajectory
        tables: :mod:`glu.data.trajectory_files`), or a CSV file with the columns ``file,label[,frames]``
        (files relative to it; ``frames`` ``A:B`` picks frames A to B of the recording, 1-based, inclusive)
    body : the body size for hand tables without a skeleton (shoulder and neck–torso distances, m)

    Returns
    -------
    a :class:`Corpus` of one :class:`LabelledSequence` per recording (the features as
    :func:`~glu.gestures.recordings.load_features` reads them, unrepaired: a frame that is not finite is an
    error naming the file), described by the folder or manifest's name.
    """
    path = Path(path)
    if path.is_dir():
        folders = [p for p in sorted(path.iterdir()) if p.is_dir() and not p.name.startswith(".")]
        items = [(f, d.name, None, 0) for d in folders for f in _recording_files(d)]
        if not items:
            raise DataError(
                f"{path}: no recordings found; expected one subfolder per action holding its recordings "
                "(.csv, .tsv, .npy, .log, or folders with a data.log)"
            )
    elif path.is_file():
        items = _read_manifest(path)
    else:
        raise DataError(f"{path}: no such folder or manifest")
    corpus = Corpus(description=f"labelled recordings: {path.name}")
    for file, label, frames, line in items:
        where = f"{file}" + (f" (manifest line {line})" if line else "")
        if not file.is_file():
            raise DataError(f"{where}: no such recording")
        traj = load_features(file, policy=None, body=body).pieces[0]
        if frames is not None:
            traj = traj.frames(*frames)
        xyz = np.asarray(traj.xyz, dtype=float)
        start, end = frames or (int(traj.frame[0]), int(traj.frame[-1]))
        base = path.parent if path.is_file() else path
        name = os.path.relpath(file, base) if file.is_relative_to(base) else file.name
        corpus.append(LabelledSequence(label, xyz, name, start, end))
    return corpus


def original_recognizer(source: DataSource, n_mix: int = 3) -> Recognizer:
    """The originals' 2013 models of a data source (:func:`~glu.gestures.recognizer.load_original_models`),
    whose typicality check knows where gestures start and how far they move from the published standing
    recordings (:func:`real_segments`) — the originals' own training data is not published, and sequences
    sampled from their models start elsewhere (their person's rest pose) than the published logs."""
    path = source.original_hmms(n_mix)
    if path is None:
        raise DataError(f"the data source has no original HMMs with M = {n_mix} ({source.describe()})")
    rec = load_original_models(path)
    reference = [s.xyz for s in real_segments(source, include_original=False)]
    if reference:
        rec.meta[FRAMES_KEY] = FeatureRanges.of(reference, "published standing").to_meta()
    return rec
