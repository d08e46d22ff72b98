"""The correspondence problem on the real data: the seated taps of effect anticipation.

The published recordings hold one person's standing repetitions (grasp1, tap1, touch1, push1) and two
taps made seated, towards a small sphere and a big box (docs/method.md §5.3; :func:`seated_taps`). The
seated hand moves in another part of the torso frame (:func:`posture_offsets`), so HMMs trained on raw
standing features judge the seated taps by their tails. Training settings are named by short labels
(:func:`parse_setting`, :func:`setting_label`); the choice among them, made without the seated taps in
view, is :mod:`glu.studies.correspondence.nested`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import pandas as pd

from glu.data.source import DataSource
from glu.errors import DataError
from glu.gestures.corpus import LabelledSequence, original_test_segments, synthetic_corpus
from glu.gestures.synthetic import View
from glu.studies.anticipation.experiment import CASES
from glu.tidy import tidy

SETTING_KEYS = {"Q": "n_states", "M": "n_mix", "reg": "covar_reg", "iter": "n_iter", "tol": "tol"}
"""Short names of training settings in labels such as ``"Q6 M3 reg0.03"`` (as the originals'
``HMM_M3_Q6``)."""
DEFAULT_SETTING = "glu defaults"
"""The label of no override: glu's recipe with :class:`~glu.hmm.training.TrainingConfig` as it is."""


def parse_setting(label: str) -> dict[str, Any]:
    """``"Q6 M3 reg0.03"`` → ``{"n_states": 6, "n_mix": 3, "covar_reg": 0.03}``; a recipe name
    (``"mixsplit"``) → ``{"recipe": "mixsplit"}``; ``"glu defaults"`` → ``{}``."""
    import re

    from glu.hmm import RECIPES

    out: dict[str, Any] = {}
    for part in [] if label.strip() == DEFAULT_SETTING else label.split():
        if part in RECIPES:
            out["recipe"] = part
            continue
        m = re.fullmatch(r"(Q|M|reg|iter|tol)([0-9.eE+-]+)", part)
        try:
            if m is None:
                raise ValueError
            key, value = m.groups()
            out[SETTING_KEYS[key]] = int(value) if key in ("Q", "M", "iter") else float(value)
        except ValueError:
            raise DataError(
                f"{label!r}: expected words KEYvalue with KEY among {', '.join(SETTING_KEYS)}, or a recipe "
                f"({', '.join(RECIPES)}), e.g. 'Q6 M3 reg0.03'"
            ) from None
    return out


def setting_label(setting: Mapping[str, Any]) -> str:
    """``{"n_states": 6, "n_mix": 3, "covar_reg": 0.03}`` → ``"Q6 M3 reg0.03"`` (the inverse
    of :func:`parse_setting`)."""
    short = {v: k for k, v in SETTING_KEYS.items()}
    if not setting:
        return DEFAULT_SETTING
    return " ".join(str(v) if k == "recipe" else f"{short.get(k, k)}{v:g}" for k, v in setting.items())


def posture_offsets(source: DataSource, n_per_action: int = 4) -> pd.DataFrame:
    """Where each gesture happens in the torso frame: the mean hand features of every segment.

    Real data: the standing training segments (automatic segmentation) and the originals' segments of the
    two seated taps, as logged. Synthetic data: standing and seated synthetic gestures (fixed
    normalisation). Columns: recording, start, end, action, posture, x, y, z (feature units).
    """
    from glu.data.recordings import ORIGINAL_SEGMENTS, TRAINING_RECORDINGS
    from glu.gestures.corpus import original_test_segments, real_segments

    if source.has_gestures:
        seqs = real_segments(source, include_original=False) + [
            s for s in original_test_segments(source) if s.recording not in TRAINING_RECORDINGS
        ]
        posture = {r: "seated" for r in ORIGINAL_SEGMENTS if r not in TRAINING_RECORDINGS}
        where = source.describe()
    else:
        seqs, posture = [], {}
        for p in ("standing", "seated"):
            c = synthetic_corpus(n_per_action, 0, view=View(posture=p, normalise_body=False))
            seqs += [s._replace(recording=f"synthetic {p} {i}") for i, s in enumerate(c)]
            posture.update({f"synthetic {p} {i}": p for i in range(len(c))})
        where = "synthetic data: standing and seated gestures (seed 0)"
    rows = [
        {
            "recording": s.recording,
            "start": s.start,
            "end": s.end,
            "action": s.action,
            "posture": posture.get(s.recording, "standing"),
            **dict(zip("xyz", s.xyz.mean(axis=0), strict=True)),
        }
        for s in seqs
    ]
    return tidy(pd.DataFrame(rows), "posture_offsets", where)


def seated_taps(source: DataSource) -> list[LabelledSequence]:
    """The two seated taps of effect anticipation (the recordings of
    :data:`glu.studies.anticipation.experiment.CASES`) among the data's test segments: what the nested
    cross-validation never trains on."""
    cases = {c.recording for c in CASES.values()}
    return [s for s in original_test_segments(source) if s.recording in cases]
