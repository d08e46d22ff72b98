"""Gestures: from a hand trajectory to the posterior over actions, ``p_HMM(A | G)``.

The signal chain, one module per step:

* :mod:`~glu.gestures.trajectories` — YARP hand logs, tracking gaps and outliers, their repair;
* :mod:`~glu.gestures.features` — a skeleton's hand in the torso frame, normalised by body size;
* :mod:`~glu.gestures.invariants` — features invariant to posture, body size, viewpoint and mirroring, online;
* :mod:`~glu.gestures.segmentation` — automatic segmentation of a recording into repetitions;
* :mod:`~glu.gestures.recordings` — a recording read once: the file's arrays (:mod:`glu.data`) through the
  features, the repair and the segmentation, all pure functions over arrays;
* :mod:`~glu.gestures.synthetic` — seeded synthetic people doing grasp, tap, touch and push, seen from a view;
* :mod:`~glu.gestures.synthetic_batch` — many synthetic gestures' features at once, bit for bit those of
  one at a time (the simulated corpora's fast path);
* :mod:`~glu.gestures.robot` — the robot's own grasp, tap and touch (an iCub-like arm in its body frame);
* :mod:`~glu.gestures.corpus` — labelled sequences of a data source (real segments or synthetic);
* :mod:`~glu.gestures.recognizer` — the recogniser: a bank of :mod:`glu.hmm` models over gesture
  features, its posteriors, its streaming form, its file;
* :mod:`~glu.gestures.typicality` — does a gesture look like anything the models know?

The fast paths are public functions beside what they speed up, bit for bit the same:
:func:`~glu.gestures.trajectories.repaired_many` (many trajectories repaired at once),
:func:`~glu.gestures.synthetic.pchip` and :func:`~glu.gestures.synthetic.pchip_many` (monotone cubic
interpolation, SciPy's values without its set-up cost) and
:func:`~glu.gestures.synthetic_batch.gesture_features`.
"""

from glu.gestures.corpus import LabelledSequence, gesture_sequences, synthetic_corpus
from glu.gestures.invariants import Invariants
from glu.gestures.recognizer import GestureStream, Recognizer, load_original_models, train_recognizer
from glu.gestures.recordings import load_features, read_hand_log, read_recording, segment_recording
from glu.gestures.trajectories import Trajectory, repair

__all__ = [
    "GestureStream",
    "Invariants",
    "LabelledSequence",
    "Recognizer",
    "Trajectory",
    "gesture_sequences",
    "load_features",
    "load_original_models",
    "read_hand_log",
    "read_recording",
    "repair",
    "segment_recording",
    "synthetic_corpus",
    "train_recognizer",
]
