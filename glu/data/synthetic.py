"""Synthetic robot experiments with the schema of the real data and a known generating structure.

The generator is a small world of simple physics plus a sentence model:

* the experimenter picks Action, Color, Shape and Size uniformly;
* a tap rolls a sphere fast (a small one most often) and barely moves a box; a touch leaves objects
  still; a grasp lifts the object (ObjVel medium) or fails (slow), failing more often on big objects;
* ObjHandVel, HandVel and Contact follow from the action (and the object's motion or shape);
* each experiment gets one spoken description drawn from the 49-word vocabulary: an agent (``the robot``,
  ``he``, ``baltazar``), a verb synonym of the action in one of several tenses (``taps``, ``is tapping``,
  ``has just tapped``), the object (``the [big|small] [green|yellow|blue] ball|sphere|box|square|cube``),
  ``and`` or ``but`` (``but`` when the outcome is a failure), and an effect phrase (``is still``,
  ``rolls``, ``is sliding``, ``rises``, ``falls``, …).

Everything is vectorised with NumPy and seeded: :func:`synthesize_experiments` makes 1,000,000 rows in a
couple of seconds. :data:`WORLD` exposes the generating DAG, so tests can check that structure learning
recovers it.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from glu.errors import DataError
from glu.files import atomic_write_json, staged_folder
from glu.schema import ACTION_VERBS, AFFORDANCE_VALUES, WORD_VALUES, WORDS, default_schema

MIN_ROWS, MAX_ROWS = 100, 1_000_000
ASR_NOISE = 0.1
"""Synthetic speech-recogniser noise: the probability that a word of the ``asr`` table is flipped."""


@dataclass(frozen=True)
class SyntheticWorld:
    """The generating model of the synthetic data.

    Attributes
    ----------
    parents : affordance node → its parents in the generator (the DAG structure learning should find)
    cpts : affordance node → array, shape ``(*parent cardinalities, cardinality)``, P(node | parents)
    word_parents : word → the affordance nodes its presence depends on, for the words whose dependence
        is clean enough to be identified from data (the others are left out)
    """

    parents: dict[str, tuple[str, ...]]
    cpts: dict[str, np.ndarray]
    word_parents: dict[str, tuple[str, ...]]


def _world() -> SyntheticWorld:
    A = {"grasp": 0, "tap": 1, "touch": 2}
    cpts: dict[str, np.ndarray] = {
        "Action": np.full(3, 1 / 3),
        "Color": np.full(4, 1 / 4),
        "Shape": np.full(2, 1 / 2),
        "Size": np.full(3, 1 / 3),
    }
    # ObjVel | Action, Shape, Size   (slow, medium, fast)
    ov = np.zeros((3, 2, 3, 3))
    grasp_lift = {0: 0.85, 1: 0.65, 2: 0.3}  # small, medium, big: big objects slip out
    for size in range(3):
        for shape in range(2):
            lift = grasp_lift[size] - (0.1 if shape == 0 else 0.0)  # spheres are harder to hold
            ov[A["grasp"], shape, size] = [1 - lift, lift, 0.0]
    ov[A["tap"], 0] = [[0.02, 0.13, 0.85], [0.05, 0.3, 0.65], [0.1, 0.45, 0.45]]  # sphere rolls away
    ov[A["tap"], 1] = [[0.3, 0.6, 0.1], [0.55, 0.4, 0.05], [0.85, 0.15, 0.0]]  # box barely moves
    ov[A["touch"], :, :] = [0.95, 0.05, 0.0]
    cpts["ObjVel"] = ov
    # ObjHandVel | Action, ObjVel   (slow, medium, fast)
    ohv = np.zeros((3, 3, 3))
    ohv[A["grasp"]] = [[0.3, 0.6, 0.1], [0.85, 0.15, 0.0], [0.7, 0.3, 0.0]]  # lifted: moves with the hand
    ohv[A["tap"]] = [[0.1, 0.3, 0.6], [0.2, 0.6, 0.2], [0.15, 0.35, 0.5]]
    ohv[A["touch"]] = [[0.9, 0.1, 0.0], [0.6, 0.4, 0.0], [0.5, 0.5, 0.0]]
    cpts["ObjHandVel"] = ohv
    # HandVel | Action   (slow, fast)
    cpts["HandVel"] = np.array([[0.85, 0.15], [0.15, 0.85], [0.75, 0.25]])
    # Contact | Action, Shape   (short, long)
    cpts["Contact"] = np.array(
        [[[0.1, 0.9], [0.05, 0.95]], [[0.9, 0.1], [0.7, 0.3]], [[0.5, 0.5], [0.35, 0.65]]]
    )
    parents = {
        "Action": (),
        "Color": (),
        "Shape": (),
        "Size": (),
        "ObjVel": ("Action", "Shape", "Size"),
        "ObjHandVel": ("Action", "ObjVel"),
        "HandVel": ("Action",),
        "Contact": ("Action", "Shape"),
    }
    word_parents: dict[str, tuple[str, ...]] = {w: () for w in ("robot", "he", "baltazar", "has", "just")}
    word_parents.update(dict.fromkeys((w for verbs in ACTION_VERBS.values() for w in verbs), ("Action",)))
    word_parents.update(dict.fromkeys(("big", "small"), ("Size",)))
    word_parents.update(dict.fromkeys(("green", "yellow", "blue"), ("Color",)))
    word_parents.update(dict.fromkeys(("ball", "sphere", "box", "square", "cube"), ("Shape",)))
    word_parents.update(dict.fromkeys(("still", "inert"), ("ObjVel",)))
    return SyntheticWorld(parents=parents, cpts=cpts, word_parents=word_parents)


WORLD: SyntheticWorld = _world()
"""The generator's ground truth."""


def _sample(rng: np.random.Generator, probs: np.ndarray) -> np.ndarray:
    """One categorical draw per row of ``probs`` (shape (n, k)) → int array, shape (n,)."""
    u = rng.random(probs.shape[0])[:, None]
    idx = (np.cumsum(probs, axis=1) < u).sum(axis=1)
    return np.minimum(idx, probs.shape[1] - 1)


def _choice(rng: np.random.Generator, n: int, p: list[float]) -> np.ndarray:
    return _sample(rng, np.broadcast_to(np.asarray(p, dtype=float), (n, len(p))))


def synthesize_experiments(n: int = 1270, seed: int = 0, asr_noise: float = 0.0) -> pd.DataFrame:
    """Generate ``n`` synthetic experiments (one verbal description each) with the real data's schema.

    Parameters
    ----------
    n : number of rows, 100 to 1,000,000
    seed : seed of the random generator; the same (n, seed, asr_noise) give the same table
    asr_noise : probability that each word's presence is flipped as by a speech recogniser
        (deletions at this rate, insertions at a tenth of it); 0 gives clean transcriptions

    Returns
    -------
    DataFrame, shape (n, 57), categorical columns as :func:`glu.data.tables.read_experiments` returns.
    """
    if not isinstance(n, int | np.integer) or not MIN_ROWS <= n <= MAX_ROWS:
        raise DataError(
            f"synthetic data size n={n!r} is out of range; allowed: {MIN_ROWS} to {MAX_ROWS:,} rows"
        )
    if not 0.0 <= asr_noise <= 0.5:
        raise DataError(f"asr_noise={asr_noise!r} is out of range; allowed: 0 to 0.5")
    rng = np.random.default_rng(seed)
    n = int(n)
    codes = _draw_world(rng, n)
    words = {w: np.zeros(n, dtype=bool) for w in WORDS}
    action, color, shape, size, objvel = (codes[k] for k in ("Action", "Color", "Shape", "Size", "ObjVel"))
    _say_agent_and_verb(rng, n, action, words)
    _say_object(rng, n, color, shape, size, words)
    failed = ((action == 0) & (objvel == 0)) | ((action == 1) & (objvel == 0))  # not the usual outcome
    words["but"] |= failed
    words["and"] |= ~failed
    _say_effect(rng, n, action, shape, size, objvel, words)
    if asr_noise > 0:
        for w in WORDS:
            present = words[w]
            flip = rng.random(n) < np.where(present, asr_noise, asr_noise / 10)
            words[w] = present ^ flip

    schema = default_schema()
    data: dict[str, pd.Categorical] = {}
    for node in AFFORDANCE_VALUES:
        data[node] = pd.Categorical.from_codes(codes[node], categories=list(schema.values_of(node)))
    for w in WORDS:
        data[w] = pd.Categorical.from_codes(words[w].astype(np.int8), categories=list(WORD_VALUES))
    df = pd.DataFrame(data)
    df.attrs["data_source"] = f"synthetic data (seed {seed}, {n} experiments" + (
        f", asr_noise {asr_noise})" if asr_noise else ")"
    )
    return df


def _draw_world(rng: np.random.Generator, n: int) -> dict[str, np.ndarray]:
    """The affordance nodes of ``n`` experiments, drawn from :data:`WORLD` in its node order (value codes)."""
    codes: dict[str, np.ndarray] = {}
    for node, parents in WORLD.parents.items():
        cpt = WORLD.cpts[node]
        if parents:
            rows = cpt[tuple(codes[p] for p in parents)]
        else:
            rows = np.broadcast_to(cpt, (n, cpt.shape[-1]))
        codes[node] = _sample(rng, rows)
    return codes


def _say_agent_and_verb(rng: np.random.Generator, n: int, action: np.ndarray, words: dict) -> None:
    """ "the robot | he | baltazar", then a synonym of the action in one of four forms."""
    agent = _choice(rng, n, [0.5, 0.25, 0.25])
    words["robot"] |= agent == 0
    words["the"] |= True  # "the robot" or "the <object>": every description has it
    words["he"] |= agent == 1
    words["baltazar"] |= agent == 2
    synonym = _choice(rng, n, [0.6, 0.4])
    form = _choice(rng, n, [0.3, 0.3, 0.2, 0.2])  # taps | is tapping | has just tapped | tapped
    for a, verbs in enumerate(ACTION_VERBS.values()):  # two synonyms: (3rd person, -ing, past participle)
        for s in range(2):
            third, ing, past = verbs[3 * s : 3 * s + 3]
            sel = (action == a) & (synonym == s)
            words[third] |= sel & (form == 0)
            words[ing] |= sel & (form == 1)
            words[past] |= sel & (form >= 2)
    words["is"] |= form == 1
    words["has"] |= form == 2
    words["just"] |= (form == 2) & (rng.random(n) < 0.5)


def _say_object(rng, n: int, color: np.ndarray, shape: np.ndarray, size: np.ndarray, words: dict) -> None:
    """ "the [size] [colour] shape"."""
    says_size = rng.random(n) < 0.6
    words["small"] |= says_size & (size == 0)
    words["big"] |= says_size & (size == 2)
    says_color = rng.random(n) < 0.5
    words["green"] |= says_color & (color <= 1)
    words["yellow"] |= says_color & (color == 2)
    words["blue"] |= says_color & (color == 3)
    noun = _choice(rng, n, [0.5, 0.3, 0.2])
    words["ball"] |= (shape == 0) & (noun != 0)
    words["sphere"] |= (shape == 0) & (noun == 0)
    words["box"] |= (shape == 1) & (noun == 0)
    words["square"] |= (shape == 1) & (noun == 1)
    words["cube"] |= (shape == 1) & (noun == 2)


def _say_effect(rng, n: int, action, shape, size, objvel, words: dict) -> None:
    """What the object did: still or inert, rises or falls after a grasp, rolls, slides or moves."""
    progressive = rng.random(n) < 0.5
    still = objvel == 0
    which = rng.random(n) < 0.5
    words["still"] |= still & which
    words["inert"] |= still & ~which
    words["is"] |= still
    lifted = (action == 0) & (objvel == 1)
    falls = lifted & (rng.random(n) < np.where(size == 2, 0.4, 0.1))
    rises = lifted & ~falls
    moving = (objvel >= 1) & ~lifted
    rolls = moving & (shape == 0) & (objvel == 2)
    slides = moving & (shape == 1) & (objvel == 2)
    moves = moving & ~rolls & ~slides
    for mask, third, ing in (
        (rises, "rises", "rising"),
        (falls, "falls", "falling"),
        (rolls, "rolls", "rolling"),
        (slides, "slides", "sliding"),
        (moves, "moves", "moving"),
    ):
        words[third] |= mask & ~progressive
        words[ing] |= mask & progressive
        words["is"] |= mask & progressive


def write_synthetic_folder(
    out: str | os.PathLike,
    n: int,
    seed: int,
    recordings: Mapping[str, tuple[np.ndarray, np.ndarray]] | None = None,
    progress: Callable[[str], None] | None = None,
    force: bool = False,
) -> Path:
    """Write a synthetic data folder with the layout of the real one, completely or not at all.

    The folder is built beside ``out`` and moved into place when complete (:func:`glu.files.staged_folder`),
    so an interrupted run leaves ``out`` as it was. Raises :class:`DataError` if ``out`` is a file, holds
    the published real data (never replaced), or is a folder with other content (replaced only with
    ``force``).

    Parameters
    ----------
    out : the folder; if it exists it must be empty or an earlier synthetic folder (it is then replaced)
    n, seed : experiments per table, and the generator's seed
    recordings : hand logs to write; none by default (the data layer does not make gestures)
        recording name → (timestamps, shape (n,), seconds; logged coordinates, shape (n, 3), 1000 × body
        units), e.g. :func:`glu.gestures.corpus.hand_log_arrays` of each of
        :func:`glu.gestures.corpus.synthetic_recordings`
    progress : called with the name of each file written (for a progress bar)
    force : replace a folder that holds something else (never the published real data)
    """
    from glu.data.fetch import published_origin
    from glu.data.hand_logs import write_hand_log
    from glu.data.layout import GESTURES, NETWORK_DEFINITION, SYNTHETIC_MARKER, WORD_FILES
    from glu.data.tables import write_experiments, write_network_definition

    out = Path(out)
    if out.exists() and not out.is_dir():
        raise DataError(f"{out}: exists and is not a folder; give a folder for the synthetic data")
    if out.is_dir() and published_origin(out) is not None:
        raise DataError(
            f"{out}: holds the published real data (its checksums say so); glu never overwrites it"
        )
    if out.is_dir() and any(out.iterdir()) and not (out / SYNTHETIC_MARKER).is_file() and not force:
        raise DataError(
            f"{out}: a folder that is not glu synthetic data (no {SYNTHETIC_MARKER}); refusing to overwrite "
            "it: give a new or empty folder (or --force to replace it)"
        )
    tick = progress or (lambda name: None)
    schema = default_schema()
    with staged_folder(out) as tmp:
        for words, rel in WORD_FILES.items():
            df = synthesize_experiments(n, seed, asr_noise=ASR_NOISE if words == "asr" else 0.0)
            write_experiments(df, tmp / rel, schema)
            tick(rel)
        write_network_definition(schema, tmp / NETWORK_DEFINITION)
        tick(NETWORK_DEFINITION)
        for name, (t, xyz) in (recordings or {}).items():
            write_hand_log(tmp / GESTURES / name, t, xyz)
            tick(f"{GESTURES}/{name}")
        atomic_write_json(tmp / SYNTHETIC_MARKER, {"seed": seed, "n": n, "generator": "glu"}, indent=None)
    return out
