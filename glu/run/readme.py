"""The README's results section, written from ``results/summary.json`` — never typed by hand.

``glu readme`` renders :data:`TEMPLATE` with the numbers of a full run on the real data (``make reproduce
DATA=…``; :func:`values` reads each from the summary's tables) and writes it between :data:`BEGIN` and
:data:`END` in ``README.md``; ``glu readme --check`` says whether the README is up to date. The only
numbers in the template itself are the papers' own, quoted as such. A test checks that the README's
section is this template with a number in every slot and nowhere else (:func:`section_pattern`).
"""

from __future__ import annotations

import json
import os
import re
import string
import textwrap
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from glu import paths
from glu.errors import DataError
from glu.run import generated
from glu.run import readme_studies as studies
from glu.run.readme_learning import LEARNING_REQUIRED, LEARNING_TEMPLATE, learning_values

_ROOT = paths.PROJECT_ROOT
README: Path | None = _ROOT / "README.md" if _ROOT is not None else None
"""The checkout's README (None when glu is installed: then give the files explicitly)."""
SUMMARY: Path | None = _ROOT / "results" / "summary.json" if _ROOT is not None else None
BEGIN = (
    "<!-- BEGIN results: written by `glu readme` from results/summary.json; edit glu/run/readme.py, not "
    "here -->"
)
END = "<!-- END results -->"

TEMPLATE = """\
Every number below comes from `make reproduce` on the real data (the tables of its {notebooks} notebooks): \
`glu readme` writes this section from `results/summary.json`.

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
  * On the {loso_n:.0f} real segments of the three standing recordings (one person), leave-one-segment-out \
on raw features gives {raw_loso_span} over {raw_loso_runs:.0f} covariance priors and seeds; with one segment \
worth {segment_points:.0f} points, single accuracies are fragile.
* **The correspondence problem, on the real data** (`10_correspondence`). The seated hand works elsewhere in \
the torso frame: mean height y of the two seated taps {seated_y_lo:.2f} and {seated_y_hi:.2f}, at most \
{standing_y_max:.2f} for every standing repetition; depth z {seated_z_lo:.2f} and {seated_z_hi:.2f}, at \
least {standing_z_min:.2f} standing.
{nested_text}
  * Effect anticipation with glu's centred HMMs (`08_tcds_figures`) ends as the originals' does: the sphere \
will move (p(ObjVel = slow) {glu_sphere_slow:.3f}), the box will not ({glu_box_slow:.3f}).
* **Invariant features and the body frame, on synthetic people** (`10_correspondence`; HMMs trained on \
standard people facing the camera, tested on other people, {study_seeds:.0f} seeds, {ci_percent:.0f} % \
two-level intervals over the seeds and the test gestures).
{study_text}
* **Effect anticipation (TCDS Fig. 5).** With the original HMMs, on the originals' schedule (an update every \
{step:.0f} frames, the last at the last multiple of {step:.0f}), {anticipation_within:.0f} of \
{anticipation_n:.0f} values of the published curves and bars are reproduced within the figure's resolution \
(max |difference| {anticipation_max:.1e}), and both captions are the paper's: "{sphere_caption}", \
"{box_caption}".
* **Verbal descriptions.** Ranking the originals' {n_samples:,.0f} sampled sentences with their score (1 + Σ \
log p)/L, glu prints TCDS Table II, Fig. 7 and Fig. 8 (whose sentences are the best among those that name a \
colour, as the originals' code ranked them): {same_sentences:.0f} of {n_sentences:.0f} sentences and \
{same_scores:.0f} of {n_scores:.0f} scores to the printed digit. The grammar has {n_grammar:,.0f} sentences; \
glu finds the exact N-best under either score without scoring them one by one. Random samples of \
{trial_samples:,.0f} sentences, as the originals drew them, held the grammar's best in {trials_found:.0f} of \
{trials:.0f} trials (the exact chance is {p_draw_percent:.1f} %).
* **Every fusion strategy on a simulated corpus** (`11_corpus_evaluation`: {corpus_episodes:,.0f} episodes \
over {corpus_seeds:.0f} recogniser seeds, each with its own recogniser, learned networks and episodes; \
{ci_percent:.0f} % two-level intervals, and a paired difference whose interval contains 0 counts as none). \
The effects and words are drawn from a network and the gestures from the generator the HMMs are trained on, \
so the design crosses the ways the robot's models can be wrong: actions drawn uniformly or from the \
network's prior, the robot's network the generating one or learned from {corpus_learned} simulated \
experiments, and p_HMM read from the likelihoods, per frame, or calibrated on held-out training gestures \
(`docs/corpus-evaluation.md`).
  * The earlier findings, each followed through the {corpus_cells:.0f} cells of the design (the reference \
cell: {reference_cell}; notebook 11 gives the cells where each holds):
{findings_text}
{network_text}
{p_hmm_text}
  * {seed_text}"""
"""The results section, with ``{name:format}`` slots filled by :func:`values`."""
TEMPLATE += "\n" + LEARNING_TEMPLATE

REQUIRED = (
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
    "tcds_anticipation_sphere_published",
    "tcds_anticipation_box_published",
    "tcds_anticipation_sphere_original_predictions",
    "verbal_published_descriptions",
    "verbal_sampling_vs_exact",
    "corpus_metrics",
    "corpus_findings",
    "corpus_seeds",
    "corpus_calibration",
    "p_hmm_real_calibration",
    "posture_offsets",
    "tcds_anticipation_sphere_glu_predictions",
    "tcds_anticipation_box_glu_predictions",
    "correspondence_summary",
    "correspondence_invariance_effects",
    "correspondence_nested_cv",
    "correspondence_candidates",
    "seated_typicality",
) + LEARNING_REQUIRED
"""The result tables the section is written from."""


def load_summary(path: str | os.PathLike = SUMMARY) -> dict[str, Any]:
    """The summary of ``glu reproduce``; :class:`DataError` if it is missing or not a full run on the real
    data."""
    path = Path(path)
    try:
        summary = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise DataError(f"{path}: no summary; run `make reproduce DATA=<the real data>` first") from None
    except (OSError, ValueError) as e:  # ValueError: not UTF-8, not JSON
        raise DataError(f"{path}: not a readable summary ({e})") from None
    if not isinstance(summary, dict):
        raise DataError(f"{path}: not a summary of `glu reproduce` (expected a JSON object)")
    if summary.get("quick") or not str(summary.get("data_source", "")).startswith("real data"):
        raise DataError(
            f"{path}: the README quotes a full run on the real data, not this one "
            f"({summary.get('data_source')}, quick={summary.get('quick')})"
        )
    missing = [t for t in REQUIRED if t not in summary.get("tables", {})]
    if missing:
        raise DataError(f"{path}: the summary lacks {', '.join(missing)}; run every notebook")
    return summary


_table = studies.table


def values(summary: Mapping[str, Any]) -> dict[str, Any]:
    """Every slot of :data:`TEMPLATE`, read from the summary's tables (see :data:`REQUIRED`)."""
    v: dict[str, Any] = {"notebooks": len(summary["notebooks"])}
    bn = _table(summary, "bn_learning_summary")[0].set_index("quantity")
    v.update(
        edges=bn.loc["edges", "ours"],
        differing_edges=bn.loc["differing_edges", "ours"],
        max_cpt_difference=bn.loc["max_cpt_difference", "ours"],
        log_likelihood=bn.loc["log_likelihood", "ours"],
        log_likelihood_difference=abs(bn.loc["log_likelihood", "difference"]),
        zero_rows=bn.loc["zero_rows", "ours"],
        lost_mass_percent=100 * bn.loc["lost_prior_mass", "ours"],
    )
    fig4 = _table(summary, "glu2017_effect_prediction")[0].set_index(["case", "ObjVel"])["p"]
    v.update({f"fig4_sphere_{x}": fig4["small sphere", x] for x in ("slow", "medium", "fast")})
    v["fig4_box_slow"] = fig4["big box", "slow"]
    fig5 = _table(summary, "glu2017_word_change_text")[0]
    v["fig5_difference"] = fig5["difference"].abs().max()
    v["fig5_rolls"] = float(fig5.set_index("word").loc["rolls", "delta"])
    v["tcds_soft_difference"] = max(
        _table(summary, t)[0]["difference"].abs().max()
        for t in ("tcds_action_vs_soft_evidence", "tcds_effect_vs_soft_evidence")
    )
    v["unseen_max"] = _table(summary, "unseen_rows_comparison")[0]["uniform_minus_zero"].abs().max()
    v["tap_threshold"] = _table(summary, "fusion_product_sweep")[1]["tap_threshold"]
    v["n_thresholds"] = len(_table(summary, "fusion_product_thresholds")[0])
    gaps = []
    for shape in ("sphere", "box"):
        sweep = _table(summary, f"fusion_soft_sweep_{shape}")[0]
        wide = sweep.pivot_table(index=["p_hmm_tap", "ObjVel"], columns="rule", values="p")
        gaps.append((wide["virtual"] - wide["jeffrey"]).abs().max())
    v["soft_rules_max"] = max(gaps)
    scores = _table(summary, "hmm_original_scores")[0]
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
    cv_meta = _table(summary, "hmm_synthetic_cv")[1]
    v["cv_folds"], v["cv_accuracy"] = cv_meta["folds"], cv_meta["accuracy"]
    noise, noise_meta = _table(summary, "hmm_accuracy_vs_noise")
    worst = noise.loc[noise["noise_m"].idxmax()]
    v.update(
        noise_accuracy=worst["accuracy"],
        noise_cm=100 * worst["noise_m"],
        noise_folds=noise_meta["parameters"]["k"],
    )
    v.update(studies.loso_values(summary))
    within, n, worst_diff = 0, 0, 0.0
    for case in ("sphere", "box"):
        df, meta = _table(summary, f"tcds_anticipation_{case}_published")
        within, n = within + int(df["within"].sum()), n + len(df)
        worst_diff = max(worst_diff, float(df["difference"].abs().max()))
        same = meta["parameters"]["same_caption"]
        v[f"{case}_caption"] = meta["parameters"]["caption"] if same else "(not the paper's caption)"
    v.update(anticipation_within=within, anticipation_n=n, anticipation_max=worst_diff)
    v["step"] = _table(summary, "tcds_anticipation_sphere_original_predictions")[1]["parameters"]["step"]
    desc, desc_meta = _table(summary, "verbal_published_descriptions")
    scored = desc["same_score"].dropna()
    v.update(
        same_sentences=int(desc["same_sentence"].sum()),
        n_sentences=len(desc),
        same_scores=int(scored.sum()),
        n_scores=len(scored),
        n_grammar=desc_meta["n_grammar_sentences"],
        n_samples=desc_meta["n_candidates"],
    )
    trials = _table(summary, "verbal_sampling_vs_exact")[0]
    v.update(
        trials=len(trials),
        trials_found=int(trials["found_best"].sum()),
        trial_samples=trials["n_samples"].max(),
        p_draw_percent=100 * float(trials["p_draw_best"].mean()),
    )
    v.update(studies.corpus_values(summary))
    v.update(studies.correspondence_values(summary))
    v.update(learning_values(summary))
    return v


WIDTH = 110
"""README lines are wrapped at this width."""


def _wrap(text: str) -> str:
    """Each paragraph or bullet of ``text`` wrapped at :data:`WIDTH`, bullets indented as markdown wants."""
    out = []
    for line in text.splitlines():
        bullet = re.match(r"( *)(\* )?", line)
        indent = bullet.group(1) + ("  " if bullet.group(2) else "")
        out.append(
            textwrap.fill(
                line, WIDTH, subsequent_indent=indent, break_on_hyphens=False, break_long_words=False
            )
        )
    return "\n".join(out)


def render(summary: Mapping[str, Any]) -> str:
    """The results section (without the markers) for a summary, wrapped at :data:`WIDTH`."""
    return _wrap(TEMPLATE.format(**values(summary)))


NUMBER = r"[-+−]?\d[\d,]*(?:\.\d+)?(?:e[-+]?\d+)?"


def _squeeze(text: str) -> str:
    return re.sub(r"\s+", " ", text).strip()


def section_pattern() -> re.Pattern[str]:
    """A regular expression matching :data:`TEMPLATE` with any number (or, for text slots, any text) in each
    slot.

    It matches the section with its whitespace squeezed to single spaces (:func:`matches_template`).
    """
    out = []
    for literal, field, spec, _ in string.Formatter().parse(_squeeze(TEMPLATE)):
        out.append(re.escape(literal))
        if field is not None:
            out.append(f"(?:{NUMBER})" if spec else ".*?")
    return re.compile("".join(out))


def matches_template(section: str) -> bool:
    """True when ``section`` is :data:`TEMPLATE` with a number in every numeric slot, whatever the line
    breaks."""
    return section_pattern().fullmatch(_squeeze(section)) is not None


def readme_section(text: str) -> str:
    """The text between :data:`BEGIN` and :data:`END` in a README (stripped); DataError without exactly
    one."""
    return generated.section(text, BEGIN, END)


def update_readme(summary: Mapping[str, Any], path: str | os.PathLike = README) -> bool:
    """Write the rendered section into the README (atomically); True if it changed."""
    return generated.replace_section(path, BEGIN, END, render(summary))
