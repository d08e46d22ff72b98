"""The corpus simulator: seeded chunks, the same episodes in every condition, scenarios, Parquet streaming."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest

from glu.bn import learn_bn, make_engine
from glu.data import load_experiments
from glu.errors import DataError
from glu.studies.corpus_evaluation.corpus import chunk_ranges, simulate_chunk, write_corpus
from glu.studies.episodes import Condition, Scenario


@pytest.fixture(scope="module")
def engine():
    return make_engine(learn_bn(load_experiments("synthetic")))


WORLD = ["Action", "Color", "Shape", "Size", "ObjVel", "ObjHandVel", "HandVel", "Contact", "words"]


def test_chunks_are_seeded_and_reproducible(engine):
    a = simulate_chunk(engine, Condition(0.02, "front"), seed=3, chunk=1, n=6, chunk_size=6)
    b = simulate_chunk(engine, Condition(0.02, "front"), seed=3, chunk=1, n=6, chunk_size=6)
    pd.testing.assert_frame_equal(a.episodes, b.episodes)
    assert all(np.array_equal(x, y) for x, y in zip(a.features, b.features, strict=True))
    assert a.episodes.episode.tolist() == list(range(6, 12))
    c = simulate_chunk(engine, Condition(0.02, "front"), seed=4, chunk=1, n=6, chunk_size=6)
    assert not np.array_equal(a.episodes.duration_s, c.episodes.duration_s)


def test_conditions_see_the_same_episodes(engine):
    """Noise and viewpoint change only how the gesture is seen: world, words and person are shared."""
    base = simulate_chunk(engine, Condition(0.0, "front"), seed=0, chunk=0, n=8, chunk_size=8)
    for cond in (Condition(0.05, "front"), Condition(0.0, "seated")):
        other = simulate_chunk(engine, cond, seed=0, chunk=0, n=8, chunk_size=8)
        pd.testing.assert_frame_equal(base.episodes[WORLD], other.episodes[WORLD])
        np.testing.assert_array_equal(base.episodes.body_size, other.episodes.body_size)  # the same person
        np.testing.assert_allclose(
            base.episodes.duration_s, other.episodes.duration_s, atol=0.02
        )  # timestamp jitter
        assert any(not np.array_equal(x, y) for x, y in zip(base.features, other.features, strict=True))


def test_the_gesture_shows_the_episodes_action(engine):
    ch = simulate_chunk(engine, Condition(0.0, "front"), seed=1, chunk=0, n=9, chunk_size=9)
    assert (ch.episodes.n_frames == [len(x) for x in ch.features]).all()
    assert all(x.shape[1] == 3 and np.isfinite(x).all() for x in ch.features)
    schema = engine.bn.schema
    for node in ("Action", "ObjVel"):
        assert (ch.episodes[node].cat.codes.to_numpy() == ch.codes[node]).all()
        assert list(ch.episodes[node].cat.categories) == list(schema.values_of(node))


def test_scenario_weights(engine):
    sc = Scenario.from_mapping({"Action": {"tap": 1.0}, "Shape": {"sphere": 3.0, "box": 1.0}})
    ch = simulate_chunk(engine, Condition(0.0, "front", "scenario"), 0, 0, 400, 400, scenario=sc)
    assert (ch.episodes.Action == "tap").all()
    uniform = simulate_chunk(engine, Condition(0.0, "front"), 0, 0, 400, 400, scenario=sc)
    assert (uniform.episodes.Action == "tap").mean() < 0.5  # the uniform prior ignores the Action weights
    assert abs((ch.episodes.Shape == "sphere").mean() - 0.75) < 0.07
    assert sc.as_dict()["Action"] == {"grasp": 0.0, "tap": 1.0, "touch": 0.0}


def test_action_priors(engine):
    """Actions drawn uniformly, or as often as the network's prior p(Action) says."""
    prior = engine.query(["Action"], {})["Action"]
    n = 2000
    for name, expected in (("uniform", np.full(3, 1 / 3)), ("network", prior)):
        ch = simulate_chunk(engine, Condition(0.0, "front", name), 0, 0, n, n)
        freq = np.bincount(ch.codes["Action"], minlength=3) / n
        assert np.abs(freq - expected).max() < 3 * np.sqrt(0.25 / n) + 1e-3, name
        assert (ch.episodes.action_prior == name).all()
    with pytest.raises(DataError, match="unknown action prior 'learned'"):
        Condition(0.0, "front", "learned")


def test_replications_have_their_own_episodes(engine):
    a = simulate_chunk(engine, Condition(0.0, "front"), 0, 0, 8, 8, replication=0)
    b = simulate_chunk(engine, Condition(0.0, "front"), 0, 0, 8, 8, replication=1)
    assert not np.array_equal(a.episodes.duration_s, b.episodes.duration_s)
    assert (b.episodes.replication == 1).all()


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ({"ObjVel": {"slow": 1}}, "not a root node"),
        ({"Action": {"kick": 1}}, "no value 'kick'"),
        ({"Action": {"tap": "x"}}, "must be a number"),
        ({"Action": {"tap": 0}}, "positive sum"),
        ({"Shape": [1, 2]}, "map values to weights"),
    ],
)
def test_scenario_errors(spec, message):
    with pytest.raises(DataError, match=message):
        Scenario.from_mapping(spec)


def test_bad_chunks_and_conditions(engine):
    with pytest.raises(DataError, match="unknown viewpoint 'upside'"):
        simulate_chunk(engine, Condition(0.0, "upside"), 0, 0, 2, 2)
    with pytest.raises(DataError, match="1 to chunk_size"):
        simulate_chunk(engine, Condition(0.0, "front"), 0, 0, 3, 2)
    with pytest.raises(DataError, match="noise"):
        Condition(-1.0, "front")
    with pytest.raises(DataError, match="unknown effects 'magic'; allowed: action, gesture"):
        Condition(0.0, "front", effects="magic")
    with pytest.raises(DataError, match="scenario: 'ObjVel' is not a root node; allowed: Action, "):
        Scenario({"ObjVel": (1.0, 1.0, 1.0)})
    assert chunk_ranges(7, 3) == [(0, 3), (1, 3), (2, 1)]
    with pytest.raises(DataError, match="chunk_size=0: must be at least 1"):
        chunk_ranges(7, 0)


def test_write_corpus_streams_chunks_to_parquet(engine, tmp_path):
    conds = [Condition(0.0, "front"), Condition(0.05, "turned")]
    path = write_corpus(
        tmp_path / "c.parquet", engine, conds, n_per_condition=5, seed=2, chunk_size=2, data_source="test"
    )
    f = pq.ParquetFile(path)
    assert f.metadata.num_row_groups == 6 and f.metadata.num_rows == 10  # 3 chunks per condition
    assert b"glu.corpus" in f.schema_arrow.metadata
    df = f.read().to_pandas()
    ch = simulate_chunk(engine, conds[1], 2, 1, 2, 2)
    rows = df[(df.viewpoint == "turned") & df.episode.isin([2, 3])]
    for (_, r), x in zip(rows.iterrows(), ch.features, strict=True):
        np.testing.assert_array_equal(np.asarray(r.xyz).reshape(-1, 3), x.astype(np.float32))
        assert r.n_frames == len(x)
    assert [p.name for p in tmp_path.iterdir()] == ["c.parquet"]  # no temporary file left
    with pytest.raises(DataError, match="empty corpus"):
        write_corpus(tmp_path / "e.parquet", engine, [], 5)
    assert not (tmp_path / "e.parquet").exists()
