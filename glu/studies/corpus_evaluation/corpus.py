"""A simulated corpus of human–robot episodes: who does what to which object, what happens, how it looks.

An **episode** is one person acting on one object in front of the robot:

1. the person's action is drawn uniformly or from the network's prior p(Action) (the condition's
   ``action_prior``, :data:`ACTION_PRIORS`), the object (Color, Shape, Size) from a :class:`Scenario`;
2. the effects (ObjVel, ObjHandVel, HandVel, Contact) and the words a person would use to describe it are
   drawn from the Affordance–Words network given them (:func:`glu.bn.sampling.sample`) — the network
   learned from the robot's own experiments (the real data, or glu's synthetic generator without it);
3. the person's hand trajectory comes from the gesture generator (:mod:`glu.gestures.synthetic`): its
   own speed, amplitude and body size, the sensor noise and the viewpoint of a :class:`Condition` (and
   its skeleton tracker), tracking gaps and spikes, repaired as the recogniser's training data are; in the
   torso's frame, and (``body=True``) in the shoulder line's frame as well;
4. in the condition's ``effects`` world ``gesture`` (:data:`~glu.studies.episodes.GESTURE_WORLDS`), the
   effects of the taps are drawn again from the gesture's speed: a fast tap sends the object further, the
   slowest taps fail (:func:`glu.studies.episodes.effects_given_gesture`);
5. the robot sees growing prefixes of it (the observed fractions of
   :mod:`glu.studies.corpus_evaluation.evaluation`).

**What this world assumes.** The effects and words come from a Bayesian network of the same family as
the robot's (by default the very network the robot uses, unless the evaluation learns its own from
independent simulated experiments), and the gestures from the generator the recognisers are trained on.
By default (``effects="action"``) the gesture is drawn independently of the object and the effects given
the action, as the fusion rules assume; ``effects="gesture"`` breaks that. Measured here is how fusion
rules behave when the robot's models are right, or learned from limited experience of the same world; not
how they fare on people, objects and effects outside that family.

Episodes are generated in chunks (:func:`simulate_chunk`), so a corpus of any size never sits in memory,
and :func:`write_corpus` streams one to Parquet, one row group per chunk.

**Seeds.** Episode ``i`` of replication ``r`` of a corpus with seed ``s`` has the same object, action,
effects, words and person under every noise level and viewpoint (its gesture uses the generator seeded by
``(s, r, i)``; those conditions change only the noise and the viewpoint), so they are compared on the same
episodes. Its world draws are seeded by ``(s, r, chunk)``: a corpus depends on its chunk size, never on
which machine ran which chunk. Each replication (one recogniser seed of the evaluation) has its own
episodes; the action prior changes the actions drawn, and with them the rest of the episode.

Example
-------
>>> from glu.bn import learn_bn, make_engine
>>> from glu.data import load_experiments
>>> engine = make_engine(learn_bn(load_experiments("synthetic")))
>>> chunk = simulate_chunk(engine, Condition(0.02, "front", "network"), seed=0, chunk=0, n=4, chunk_size=4)
>>> list(chunk.episodes.columns[:6])
['episode', 'Action', 'Color', 'Shape', 'Size', 'ObjVel']
>>> len(chunk.features), chunk.features[0].shape[1]
(4, 3)
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import pandas as pd
from numpy.random import SeedSequence

from glu.bn.inference import Engine
from glu.bn.sampling import categorical, sample
from glu.errors import DataError
from glu.files import atomic_path
from glu.gestures.synthetic import View
from glu.gestures.synthetic_batch import gesture_features
from glu.schema import ROOT_NODES
from glu.studies.episodes import (
    EFFECTS_KEY,
    GESTURE_KEY,
    GESTURE_WORLDS,
    VIEWPOINTS,
    WORLD_KEY,
    Condition,
    GestureSettings,
    Scenario,
    effects_given_gesture,
    gesture_speed,
)


class Chunk(NamedTuple):
    """A chunk of simulated episodes.

    Attributes
    ----------
    episodes : one row per episode: episode (its index in the corpus), the 8 affordance nodes (value
        names), words (the words drawn, space-separated, in vocabulary order), n_frames, duration_s,
        body_size, speed (the gesture's speed quantile, :func:`~glu.studies.episodes.gesture_speed`), noise,
        viewpoint, action_prior, effects, replication
    codes : node → int array, shape (n,), value indices of every node (affordance nodes and words)
    features : n arrays of shape (T_i, 3), the repaired gesture features the robot sees (torso frame)
    body_features : the same in the shoulder line's frame (None unless asked for)
    """

    episodes: pd.DataFrame
    codes: dict[str, np.ndarray]
    features: list[np.ndarray]
    body_features: list[np.ndarray] | None = None


def chunk_ranges(n_episodes: int, chunk_size: int) -> list[tuple[int, int]]:
    """``(chunk index, number of episodes)`` of each chunk of a corpus of ``n_episodes``."""
    if chunk_size < 1:
        raise DataError(f"chunk_size={chunk_size}: must be at least 1")
    return [
        (k, min(chunk_size, n_episodes - k * chunk_size)) for k in range(math.ceil(n_episodes / chunk_size))
    ]


def simulate_chunk(
    engine: Engine,
    condition: Condition,
    seed: int,
    chunk: int,
    n: int,
    chunk_size: int,
    scenario: Scenario = Scenario(),
    gestures: GestureSettings = GestureSettings(),
    views: Mapping[str, View] = VIEWPOINTS,
    replication: int = 0,
    body: bool = False,
) -> Chunk:
    """Episodes ``chunk · chunk_size`` … ``+ n − 1`` of replication ``replication`` of the corpus with
    ``seed``.

    Parameters
    ----------
    engine : the Affordance–Words network the effects and words are drawn from
    condition : the action prior, sensor noise and viewpoint
    seed, chunk, n, chunk_size : the corpus's seed, the chunk's index, its number of episodes
        (``n ≤ chunk_size``; only the last chunk is shorter) and the corpus's chunk size
    scenario : the distribution of objects (and of actions for the action prior ``scenario``)
    gestures : the generator's tracking problems
    views : viewpoint names → :class:`~glu.gestures.synthetic.View`
    replication : which replication (recogniser seed) the episodes belong to; each has its own
    body : also give the features in the shoulder line's frame (:attr:`Chunk.body_features`)
    """
    if condition.viewpoint not in views:
        raise DataError(f"unknown viewpoint {condition.viewpoint!r}; allowed: {', '.join(views)}")
    if not 0 < n <= chunk_size:
        raise DataError(f"a chunk holds 1 to chunk_size={chunk_size} episodes, not {n}")
    view = views[condition.viewpoint]
    first = chunk * chunk_size
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(WORLD_KEY, replication, chunk)))
    roots = {}
    for node in ROOT_NODES:
        p = scenario.probabilities(node)
        if node == "Action" and condition.action_prior == "uniform":
            p = np.full(len(p), 1.0 / len(p))
        elif node == "Action" and condition.action_prior == "network":
            p = np.asarray(engine.query(["Action"], {})["Action"], dtype=float)
        roots[node] = categorical(np.broadcast_to(p, (chunk_size, len(p))), rng)[:n]
    codes = sample(engine, roots, rng)
    schema = engine.bn.schema
    actions = schema.values_of("Action")

    def rngs() -> list[np.random.Generator]:
        keys = [SeedSequence(seed, spawn_key=(GESTURE_KEY, replication, first + i)) for i in range(n)]
        return [np.random.default_rng(k) for k in keys]

    speed = gesture_speed(rngs()).quantile
    world = GESTURE_WORLDS[condition.effects]
    if world.active:
        again = np.random.default_rng(SeedSequence(seed, spawn_key=(EFFECTS_KEY, replication, chunk)))
        codes = effects_given_gesture(engine, codes, speed, world, again)
    frames = (False, True) if body else (False,)
    sensor = {"noise": float(condition.noise), "spike_rate": gestures.spike_rate}
    sensor["dropout_rate"] = gestures.dropout_rate
    names = [actions[a] for a in codes["Action"][:n]]
    seen = [gesture_features(names, rngs(), **sensor, view=replace(view, body_frame=b)) for b in frames]
    batch = seen[0]
    features, duration, size = batch.features, batch.duration, batch.size
    n_frames = np.array([len(x) for x in features], dtype=int)
    table: dict[str, Any] = {"episode": np.arange(first, first + n)}
    for node in schema.affordance_nodes:
        table[node] = pd.Categorical.from_codes(codes[node], categories=list(schema.values_of(node)))
    words = list(schema.word_nodes)
    present = np.stack([codes[w] for w in words], axis=1) == 1 if words else np.zeros((n, 0), bool)
    table["words"] = [" ".join(w for w, on in zip(words, row, strict=True) if on) for row in present]
    table.update(n_frames=n_frames, duration_s=duration, body_size=size, speed=speed)
    table.update(noise=np.full(n, float(condition.noise)), viewpoint=[condition.viewpoint] * n)
    table.update(action_prior=[condition.action_prior] * n, effects=[condition.effects] * n)
    table.update(replication=np.full(n, replication))
    return Chunk(pd.DataFrame(table), codes, features, seen[1].features if body else None)


def iter_corpus(
    engine: Engine,
    conditions: Sequence[Condition],
    n_per_condition: int,
    seed: int,
    chunk_size: int,
    replications: int = 1,
    **settings: Any,
) -> Iterator[tuple[Condition, Chunk]]:
    """Every chunk of a corpus, condition by condition, replication by replication (``settings``:
    scenario, gestures, views)."""
    for condition in conditions:
        for r in range(replications):
            for k, n in chunk_ranges(n_per_condition, chunk_size):
                yield (
                    condition,
                    simulate_chunk(engine, condition, seed, k, n, chunk_size, **settings, replication=r),
                )


def write_corpus(
    path: str | os.PathLike,
    engine: Engine,
    conditions: Sequence[Condition],
    n_per_condition: int,
    seed: int = 0,
    chunk_size: int = 2000,
    data_source: str = "",
    replications: int = 1,
    **settings: Any,
) -> Path:
    """Stream a simulated corpus into one Parquet file, one row group per chunk (written atomically).

    Columns: those of :attr:`Chunk.episodes`, plus ``xyz`` — the gesture features, a list of
    ``3 · n_frames`` float32 numbers (frame after frame, x y z). The file's metadata records the seed,
    the chunk size, the conditions, the replications and ``data_source``. At most one chunk is in memory at
    a time.
    """
    import pyarrow as pa
    import pyarrow.parquet as pq

    meta = {
        "glu.corpus": json.dumps(
            {
                "seed": seed,
                "chunk_size": chunk_size,
                "n_per_condition": n_per_condition,
                "replications": replications,
                "conditions": [[c.noise, c.viewpoint, c.action_prior, c.effects] for c in conditions],
                "data_source": data_source,
            }
        )
    }
    writer = None
    with atomic_path(path, suffix=".parquet") as tmp:
        try:
            for _, chunk in iter_corpus(
                engine, conditions, n_per_condition, seed, chunk_size, replications, **settings
            ):
                table = pa.Table.from_pandas(chunk.episodes, preserve_index=False)
                xyz = pa.array(
                    [x.astype(np.float32).ravel() for x in chunk.features], type=pa.list_(pa.float32())
                )
                table = table.append_column("xyz", xyz)
                if writer is None:
                    schema = table.schema.with_metadata({**(table.schema.metadata or {}), **meta})
                    writer = pq.ParquetWriter(tmp, schema)
                writer.write_table(table.cast(writer.schema))
        finally:
            if writer is not None:
                writer.close()
        if writer is None:
            raise DataError("an empty corpus: give at least one condition and one episode")
    return Path(path)
