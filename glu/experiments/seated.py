"""The correspondence problem on the real data: the seated taps of effect anticipation.

The published recordings hold one person's standing repetitions (grasp1, tap1, touch1, push1) and two
taps made seated, towards a small sphere and a big box (docs/method.md §5.3). The seated hand moves in
another part of the torso frame (:func:`posture_offsets`), so HMMs trained on raw standing features judge
the seated taps by their tails. :func:`feature_settings` measures, per feature set
(:mod:`glu.gestures.invariants`), training setting and seed, the leave-one-segment-out accuracy on the
standing segments and how the seated taps are recognised (:func:`glu.experiments.recipes.recipe_comparison`);
:func:`feature_settings_summary` condenses it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import pandas as pd

from glu.data.source import DataSource
from glu.errors import DataError
from glu.experiments.common import corpus_source, tidy, training_parameters
from glu.gestures.corpus import synthetic_corpus
from glu.gestures.invariants import Invariants
from glu.gestures.synthetic import View
from glu.hmm import TrainingConfig

SETTING_KEYS = {"Q": "n_states", "M": "n_mix", "reg": "covar_reg", "iter": "n_iter", "tol": "tol"}
"""Short names of training settings in labels such as ``"Q6 M3 reg0.03"`` (as the originals' ``HMM_M3_Q6``)."""
DEFAULT_SETTING = "glu defaults"
"""The label of no override: glu's recipe with :class:`~glu.hmm.training.TrainingConfig` as it is."""


def parse_setting(label: str) -> dict[str, Any]:
    """``"Q6 M3 reg0.03"`` → ``{"n_states": 6, "n_mix": 3, "covar_reg": 0.03}``; a recipe name (``"mixsplit"``)
    → ``{"recipe": "mixsplit"}``; ``"glu defaults"`` → ``{}``."""
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
    """``{"n_states": 6, "n_mix": 3, "covar_reg": 0.03}`` → ``"Q6 M3 reg0.03"`` (the inverse of :func:`parse_setting`)."""
    short = {v: k for k, v in SETTING_KEYS.items()}
    if not setting:
        return DEFAULT_SETTING
    return " ".join(str(v) if k == "recipe" else f"{short.get(k, k)}{v:g}" for k, v in setting.items())


def feature_settings(
    sequences: Sequence[Any],
    test: Sequence[Any] = (),
    feature_sets: Sequence[str] = ("raw", "centred"),
    settings: Sequence[Mapping[str, Any]] = ({},),
    seeds: Sequence[int] = (0,),
    config: TrainingConfig | None = None,
) -> pd.DataFrame:
    """Leave-one-segment-out accuracy and the recognition of ``test``, per feature set, training setting and seed.

    For each feature set and setting (:func:`parse_setting`; the recipe, Q, M, covariance prior, EM
    tolerance), :func:`glu.experiments.recipes.recipe_comparison` trains on ``sequences`` (for the real data:
    the standing segments) and recognises ``test`` (the two seated taps) with models trained on all of
    them. Settings without random initialisation (mixsplit, or single Gaussians) run with the first seed
    only. Columns: features, setting, and those of ``recipe_comparison`` (recipe, seed, tol, loso_accuracy,
    loso_correct, loso_testable, test_predicted, test_correct, train_loglik_per_frame). ``config`` holds the
    settings the grid's ``settings`` leave as they are (default glu's).
    """
    from glu.experiments.recipes import COLUMNS, comparison_rows

    config = config or TrainingConfig()
    grid, labels = [], []
    for features in feature_sets:
        for setting in settings:
            s = dict(setting)
            recipe, tol = s.pop("recipe", config.recipe), s.pop("tol", config.tol)
            single = recipe == "mixsplit" or s.get("n_mix", config.n_mix) == 1
            for seed in seeds[:1] if single else seeds:  # as recipe_comparison: mixsplit has no seed (-1)
                grid.append(
                    {
                        **config.as_dict(),
                        **s,
                        "features": features,
                        "recipe": recipe,
                        "tol": float(tol),
                        "seed": -1 if recipe == "mixsplit" else int(seed),
                    }
                )
                labels.append((Invariants.parse(features).name, setting_label(setting)))
    rows = comparison_rows(sequences, test, grid)  # every model of the grid trained in one batch per setting
    frame = pd.DataFrame(rows, columns=COLUMNS)
    frame.insert(0, "setting", [lab[1] for lab in labels])
    frame.insert(0, "features", [lab[0] for lab in labels])
    return tidy(
        frame,
        "hmm_feature_settings",
        corpus_source(sequences),
        feature_sets=list(feature_sets),
        settings=[setting_label(s) for s in settings],
        seeds=list(seeds),
        n_test=len(test),
        **training_parameters(config),
    )


def feature_settings_summary(grid: pd.DataFrame) -> pd.DataFrame:
    """Per feature set, over every setting and seed of :func:`feature_settings`: leave-one-segment-out accuracy
    (runs, mean, sd, min, max), how many runs recognised every test gesture, and the settings where all did."""
    n_test = int(grid.attrs.get("parameters", {}).get("n_test", 0))
    rows = []
    for features, g in grid.groupby("features", sort=False):
        a = g["loso_accuracy"]
        every = g[g["test_correct"] == n_test]
        always = [
            s for s, h in g.groupby("setting", sort=False) if n_test and (h["test_correct"] == n_test).all()
        ]
        rows.append(
            {
                "features": features,
                "runs": len(g),
                "loso_mean": a.mean(),
                "loso_sd": a.std(ddof=1),
                "loso_min": a.min(),
                "loso_max": a.max(),
                "n_test": n_test,
                "runs_all_test_correct": len(every),
                "settings_always_all_test_correct": ", ".join(always),
            }
        )
    return tidy(
        pd.DataFrame(rows),
        "hmm_feature_settings_summary",
        grid.attrs.get("data_source", ""),
        **grid.attrs.get("parameters", {}),
    )


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
