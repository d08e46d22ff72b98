"""The README's bullet on learning gestures from effects (notebook 12), written from its tables.

Every slot is filled by :func:`values` from the run's tables; only the papers' numbers are typed.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import pandas as pd

from glu.errors import DataError

TEMPLATE = """\
* **Beyond the self: learning people's gestures from what their actions did** (`12_learning_from_effects`: \
the robot labels unlabelled episodes with its network and learns its HMMs online from no gesture model; \
{learn_seeds:.0f} seeds × {learn_episodes:,.0f} episodes; two-level intervals over seeds and held-out \
gestures). Without words the network's labels are right for {label_mixed:.2f} of the episodes on every \
object, with words for {label_mixed_words:.2f}.
  * Learning from effects reaches the accuracy of HMMs trained on the true labels ({learn_true:.3f}) within \
the interval in {learn_matched:.0f} of {learn_conditions:.0f} conditions (ambiguity × words): {learn_reached}.
  * {learn_failed}.
  * On the real standing segments, their labels hidden and each paired with an object and an effect drawn \
from the network, leave-one-segment-out accuracy ({real_features} features) is {real_soft:.2f} with soft \
labels and {real_true:.2f} with the true ones (mean of {real_draws:.0f} draws; the network's labels right \
for {real_labels:.2f})."""
"""The bullet, with ``{name:format}`` slots filled by :func:`values`."""

REQUIRED: tuple[str, ...] = ("learning_match", "learning_labels", "learning_real_gestures_summary")
"""The tables of notebook 12 the bullet is written from."""


Tables = Mapping[str, tuple[pd.DataFrame, dict[str, Any]]]


def values(tables: Tables) -> dict[str, Any]:
    """The slots of the learning-from-effects bullet (notebook 12): when the labelling schemes reach the
    true-label HMMs within the interval (:func:`glu.studies.learning.study.match_table`), and when
    not."""
    match, meta = tables["learning_match"]
    params = meta["parameters"]
    labels = tables["learning_labels"][0]
    real, real_meta = tables["learning_real_gestures_summary"]
    schemes = match[~match["learner"].isin(["unsupervised", "true", "network"])]
    reached, failed = [], []
    for (amb, words), g in schemes.groupby(["ambiguity", "words"], sort=False):
        where = f"{amb.replace('_', ' ')} {'with' if words else 'without'} words"
        hit = g[g["episodes_to_match"].notna()]
        if len(hit):
            first = hit.loc[hit["episodes_to_match"].idxmin()]
            reached.append(f"{where} ({first['learner']} after {first['episodes_to_match']:,.0f})")
        else:
            best = g.loc[g["accuracy"].idxmax()]
            failed.append(
                f"{where} (best {best['learner']} {best['accuracy']:.3f} "
                f"[gap {best['gap_low']:+.3f} to {best['gap_high']:+.3f}])"
            )

    def label(amb: str, words: bool) -> float:
        rows = labels[(labels["ambiguity"] == amb) & (labels["words"].astype(bool) == words)]
        if len(rows) != 1:
            raise DataError(f"learning_labels: no single row for {amb}, words={words}")
        return float(rows["label_accuracy"].iloc[0])

    loso = real[real["test"] == "loso"].set_index("learner")
    return {
        "learn_seeds": len(params["seeds"]),
        "learn_episodes": params["episodes"],
        "label_mixed": label("mixed", False),
        "label_mixed_words": label("mixed", True),
        "learn_true": float(schemes["true_accuracy"].iloc[0]),
        "learn_matched": len(reached),
        "learn_conditions": len(reached) + len(failed),
        "learn_reached": "; ".join(reached) or "none",
        "learn_failed": f"It does not in {'; '.join(failed)}"
        if failed
        else "It reaches it in every condition",
        "real_features": real_meta["parameters"]["features"],
        "real_soft": loso.loc["soft", "accuracy"],
        "real_true": loso.loc["true", "accuracy"],
        "real_draws": loso.loc["soft", "draws"],
        "real_labels": loso.loc["soft", "label_accuracy"],
    }
