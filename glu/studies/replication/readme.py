"""The README's bullets on the replication (notebooks 01–07 and 09), written from their tables.

Every slot of :data:`TEMPLATE` is filled by :func:`values` from the tables of a full run on the real data;
the only numbers typed here are the papers' own, quoted as such (the runner's :mod:`glu.run.readme` puts the
studies' parts together).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import pandas as pd

Tables = Mapping[str, tuple[pd.DataFrame, dict[str, Any]]]

TEMPLATE = """\
* **The Affordance–Words network.** Learned exactly as the original: the same {edges:.0f} edges \
({differing_edges:.0f} differ), every CPT equal (max |difference| {max_cpt_difference:g}), and the same \
log-likelihood of the training data ({log_likelihood:.4f}, difference {log_likelihood_difference:g}).
  * GLU 2017 Fig. 4: a tap on a small sphere gives p(ObjVel) = (slow {fig4_sphere_slow:.3f}, medium \
{fig4_sphere_medium:.3f}, fast {fig4_sphere_fast:.3f}); on a big box, slow {fig4_box_slow:.4f}.
  * GLU 2017 Fig. 5: Δp(w) for every word equals the original model's (max |difference| \
{fig5_difference:g}). "rolls" rises by {fig5_rolls:+.3f}, tap/push words rise, touch/poke words fall.
  * TCDS: action and effect under soft evidence equal the original model's values (max |difference| \
{tcds_soft_difference:g}).
* **The original's quirk.** For a word, a parent configuration never seen in training gets an all-zero CPT \
row ({zero_rows:.0f} rows). Every query then excludes three affordance configurations \
({lost_mass_percent:.2f} % of the prior mass). glu keeps this by default, because the published bars depend \
on it; `--unseen-words uniform` fixes it. The fix moves Δp(w) by up to {unseen_max:.3f} \
(`unseen_rows_comparison`).
* **The tap threshold.** Bisection finds that tap wins p_comb(Action | small sphere, still) only above \
p_HMM(tap) = {tap_threshold:.4f}; the paper read "0.81" off a grid. `06_fusion_product` gives the threshold \
for all {n_thresholds:.0f} (Shape, Size, ObjVel) combinations.
* **Soft fusion, both ways.** The originals enter p_HMM as virtual (likelihood) evidence. Their references \
define soft evidence by Jeffrey's rule. glu has both, and they differ by up to {soft_rules_max:.2f} in \
between certain cases (`fusion_soft_sweep`).
* **Gesture HMMs.** The original 2013 models recognise {original_tap:.0f} of the {original_n:.0f} original \
test segments as tap; {original_other}.
  * Trained by glu on synthetic gestures: {cv_folds:.0f}-fold accuracy {cv_accuracy:.2f}, and \
{noise_accuracy:.2f} with {noise_cm:.0f} cm sensor noise ({noise_folds:.0f}-fold).
* **Verbal descriptions.** Ranking the originals' {n_samples:,.0f} sampled sentences with their score (1 + Σ \
log p)/L, glu prints TCDS Table II, Fig. 7 and Fig. 8 (whose sentences are the best among those that name a \
colour, as the originals' code ranked them): {same_sentences:.0f} of {n_sentences:.0f} sentences and \
{same_scores:.0f} of {n_scores:.0f} scores to the printed digit. The grammar has {n_grammar:,.0f} sentences; \
glu finds the exact N-best under either score without scoring them one by one. Random samples of \
{trial_samples:,.0f} sentences, as the originals drew them, held the grammar's best in {trials_found:.0f} of \
{trials:.0f} trials (the exact chance is {p_draw_percent:.1f} %)."""
"""The replication's bullets, with ``{name:format}`` slots filled by :func:`values`."""

REQUIRED: tuple[str, ...] = (
    "bn_learning_summary",
    "glu2017_effect_prediction",
    "glu2017_word_change_text",
    "tcds_action_vs_soft_evidence",
    "tcds_effect_vs_soft_evidence",
    "unseen_rows_comparison",
    "fusion_product_sweep",
    "fusion_product_thresholds",
    "fusion_soft_sweep_sphere",
    "fusion_soft_sweep_box",
    "hmm_original_scores",
    "hmm_synthetic_cv",
    "hmm_accuracy_vs_noise",
    "verbal_published_descriptions",
    "verbal_sampling_vs_exact",
)
"""The result tables the bullets are written from."""


def values(tables: Tables) -> dict[str, Any]:
    """Every slot of :data:`TEMPLATE`, from the run's tables (name → (rows, meta))."""
    v = _network(tables)
    v.update(_fusion(tables))
    v.update(_gestures(tables))
    v.update(_verbal(tables))
    return v


def _network(tables: Tables) -> dict[str, Any]:
    bn = tables["bn_learning_summary"][0].set_index("quantity")
    v: dict[str, Any] = dict(
        edges=bn.loc["edges", "ours"],
        differing_edges=bn.loc["differing_edges", "ours"],
        max_cpt_difference=bn.loc["max_cpt_difference", "ours"],
        log_likelihood=bn.loc["log_likelihood", "ours"],
        log_likelihood_difference=abs(bn.loc["log_likelihood", "difference"]),
        zero_rows=bn.loc["zero_rows", "ours"],
        lost_mass_percent=100 * bn.loc["lost_prior_mass", "ours"],
    )
    fig4 = tables["glu2017_effect_prediction"][0].set_index(["case", "ObjVel"])["p"]
    v.update({f"fig4_sphere_{x}": fig4["small sphere", x] for x in ("slow", "medium", "fast")})
    v["fig4_box_slow"] = fig4["big box", "slow"]
    fig5 = tables["glu2017_word_change_text"][0]
    v["fig5_difference"] = fig5["difference"].abs().max()
    v["fig5_rolls"] = float(fig5.set_index("word").loc["rolls", "delta"])
    v["tcds_soft_difference"] = max(
        tables[t][0]["difference"].abs().max()
        for t in ("tcds_action_vs_soft_evidence", "tcds_effect_vs_soft_evidence")
    )
    v["unseen_max"] = tables["unseen_rows_comparison"][0]["uniform_minus_zero"].abs().max()
    return v


def _fusion(tables: Tables) -> dict[str, Any]:
    v: dict[str, Any] = {"tap_threshold": tables["fusion_product_sweep"][1]["tap_threshold"]}
    v["n_thresholds"] = len(tables["fusion_product_thresholds"][0])
    gaps = []
    for shape in ("sphere", "box"):
        sweep = tables[f"fusion_soft_sweep_{shape}"][0]
        wide = sweep.pivot_table(index=["p_hmm_tap", "ObjVel"], columns="rule", values="p")
        gaps.append((wide["virtual"] - wide["jeffrey"]).abs().max())
    v["soft_rules_max"] = max(gaps)
    return v


def _gestures(tables: Tables) -> dict[str, Any]:
    v: dict[str, Any] = {}
    scores = tables["hmm_original_scores"][0]
    v["original_tap"], v["original_n"] = int((scores["winner"] == "tap").sum()), len(scores)
    others = scores[scores["winner"] != "tap"]
    v["original_other"] = (
        "; ".join(
            f"{r.recording} {r.start}–{r.end} goes to {r.winner}"
            + (" (their push model)" if r.winner == "touch" else "")
            for r in others.itertuples()
        )
        or "all of them"
    )
    cv_meta = tables["hmm_synthetic_cv"][1]
    v["cv_folds"], v["cv_accuracy"] = cv_meta["folds"], cv_meta["accuracy"]
    noise, noise_meta = tables["hmm_accuracy_vs_noise"]
    worst = noise.loc[noise["noise_m"].idxmax()]
    v.update(
        noise_accuracy=worst["accuracy"],
        noise_cm=100 * worst["noise_m"],
        noise_folds=noise_meta["parameters"]["k"],
    )
    return v


def _verbal(tables: Tables) -> dict[str, Any]:
    desc, desc_meta = tables["verbal_published_descriptions"]
    scored = desc["same_score"].dropna()
    trials = tables["verbal_sampling_vs_exact"][0]
    return dict(
        same_sentences=int(desc["same_sentence"].sum()),
        n_sentences=len(desc),
        same_scores=int(scored.sum()),
        n_scores=len(scored),
        n_grammar=desc_meta["n_grammar_sentences"],
        n_samples=desc_meta["n_candidates"],
        trials=len(trials),
        trials_found=int(trials["found_best"].sum()),
        trial_samples=trials["n_samples"].max(),
        p_draw_percent=100 * float(trials["p_draw_best"].mean()),
    )
