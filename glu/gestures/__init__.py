"""Gestures: from a hand trajectory to the posterior over actions, ``p_HMM(A | G)``.

The chain, one module per step:

* :mod:`~glu.gestures.trajectories` — YARP hand logs, tracking gaps and outliers, their repair;
* :mod:`~glu.gestures.repair_many` — the repair of many trajectories at once (the corpus's fast path);
* :mod:`~glu.gestures.features` — a skeleton's hand in the torso frame, normalised by body size;
* :mod:`~glu.gestures.invariants` — features invariant to posture, body size, viewpoint and mirroring, online;
* :mod:`~glu.gestures.segmentation` — automatic segmentation of a recording into repetitions;
* :mod:`~glu.gestures.synthetic` — seeded synthetic skeletons of grasp, tap, touch and push, seen from a view;
* :mod:`~glu.gestures.synthetic_batch` — many synthetic gestures' repaired features at once, bit for bit;
* :mod:`~glu.gestures.robot` — the robot's own grasp, tap and touch (an iCub-like arm in its body frame);
* :mod:`~glu.gestures.corpus` — labelled sequences of a data source (real segments or synthetic);
* :mod:`~glu.gestures.forward` — the forward algorithm as pure functions over arrays;
* :mod:`~glu.gestures.model` — one left-to-right GMM-HMM;
* :mod:`~glu.gestures.training` — training settings, initialisation, EM;
* :mod:`~glu.gestures.recognizer` — the bank of models, streaming, recogniser files;
* :mod:`~glu.gestures.original` — the originals' 2013 models.
"""

from glu.gestures.corpus import LabelledSequence, gesture_sequences, synthetic_corpus
from glu.gestures.features import load_features
from glu.gestures.forward import p_hmm_from_loglik
from glu.gestures.invariants import Invariants
from glu.gestures.model import GestureHMM
from glu.gestures.original import load_original_models
from glu.gestures.recognizer import GestureStream, Recognizer, train_recognizer
from glu.gestures.training import TrainingConfig, train_hmm
from glu.gestures.trajectories import Trajectory, read_hand_log, repair

__all__ = [
    "GestureHMM",
    "GestureStream",
    "Invariants",
    "LabelledSequence",
    "Recognizer",
    "TrainingConfig",
    "Trajectory",
    "gesture_sequences",
    "load_features",
    "load_original_models",
    "p_hmm_from_loglik",
    "read_hand_log",
    "repair",
    "synthetic_corpus",
    "train_hmm",
    "train_recognizer",
]
