"""The synthetic generator: schema, determinism, physics, range checks, and that its structure is
learnable."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from glu.bn import learn_bn
from glu.data import WORLD, load_experiments, read_experiments, synthesize_experiments
from glu.data.synthetic import write_synthetic_folder
from glu.errors import DataError
from glu.schema import AFFORDANCE_VALUES, WORDS


def test_schema_and_determinism():
    a = synthesize_experiments(500, seed=7)
    b = synthesize_experiments(500, seed=7)
    c = synthesize_experiments(500, seed=8)
    assert list(a.columns) == [*AFFORDANCE_VALUES, *WORDS]
    pd.testing.assert_frame_equal(a, b)
    assert not a.equals(c)
    for node, values in AFFORDANCE_VALUES.items():
        assert list(a[node].cat.categories) == list(values)


@pytest.mark.parametrize("n", [99, 1_000_001, 0, -5])
def test_size_out_of_range(n):
    with pytest.raises(DataError, match="100 to 1,000,000"):
        synthesize_experiments(n)


@pytest.mark.parametrize("noise", [-0.1, 0.6, float("nan")])
def test_asr_noise_out_of_range(noise):
    with pytest.raises(DataError, match=r"asr_noise=.* is out of range; allowed: 0 to 0.5"):
        synthesize_experiments(200, asr_noise=noise)


def test_a_file_is_not_a_synthetic_folder(tmp_path):
    out = tmp_path / "data"
    out.write_text("notes")
    with pytest.raises(DataError, match="exists and is not a folder"):
        write_synthetic_folder(out, 200, 1)
    assert out.read_text() == "notes"


def test_physics_of_the_generator():
    df = synthesize_experiments(20_000, seed=1)

    def p_fast(**cond):
        sel = np.ones(len(df), bool)
        for k, v in cond.items():
            sel &= (df[k] == v).to_numpy()
        return (df.loc[sel, "ObjVel"] == "fast").mean(), (df.loc[sel, "ObjVel"] == "slow").mean()

    fast_small_sphere, _ = p_fast(Action="tap", Shape="sphere", Size="small")
    fast_big_box, slow_big_box = p_fast(Action="tap", Shape="box", Size="big")
    _, slow_touch = p_fast(Action="touch")
    assert fast_small_sphere > 0.75 and fast_big_box < 0.05 and slow_big_box > 0.75
    assert slow_touch > 0.9
    # a grasp lifts (medium) or fails (slow), never sends the object flying
    grasp = df[df["Action"] == "grasp"]
    assert (grasp["ObjVel"] == "fast").mean() == 0
    # descriptions: every sentence names exactly one verb of the right action, and "and" xor "but"
    verbs = {
        "grasp": ["grasps", "grasping", "grasped", "picks", "picking", "picked"],
        "tap": ["taps", "tapping", "tapped", "pushes", "pushing", "pushed"],
        "touch": ["touches", "touching", "touched", "pokes", "poking", "poked"],
    }
    present = df[list(WORDS)] == "present"
    for action, vs in verbs.items():
        rows = (df["Action"] == action).to_numpy()
        assert (present.loc[rows, vs].sum(axis=1) == 1).all()
        others = [v for a, vv in verbs.items() if a != action for v in vv]
        assert not present.loc[rows, others].any().any()
    assert (present["and"] ^ present["but"]).all()


def test_learning_recovers_the_generating_structure():
    df = synthesize_experiments(20_000, seed=0)
    bn = learn_bn(df)
    for node, parents in WORLD.parents.items():
        assert set(bn.parents[node]) == set(parents), node
    for word, parents in WORLD.word_parents.items():
        assert set(bn.parents[word]) == set(parents), word


def test_learned_cpts_approach_the_generator():
    df = synthesize_experiments(200_000, seed=2)
    bn = learn_bn(df)
    for node in ("ObjVel", "HandVel", "Contact", "ObjHandVel"):
        parents = list(WORLD.parents[node])
        # compare the rows of parent configurations the data actually visits often
        seen = df.groupby(parents, observed=False).size().to_numpy().reshape(WORLD.cpts[node].shape[:-1])
        diff = np.abs(bn.cpts[node] - WORLD.cpts[node])[seen >= 2000]
        assert diff.size > 0 and diff.max() < 0.02, node


def test_synth_folder_reads_back_as_synthetic_source(tmp_path):
    write_synthetic_folder(tmp_path / "syn", n=150, seed=4)
    df = load_experiments(tmp_path / "syn", "lab")
    assert df.attrs["data_source"] == "synthetic data (seed 4, 150 experiments), words=lab"  # no machine path
    from glu.data import resolve_data

    assert str(tmp_path / "syn") in resolve_data(tmp_path / "syn").location()  # messages name the folder
    direct = synthesize_experiments(150, seed=4)
    pd.testing.assert_frame_equal(df.reset_index(drop=True), direct, check_like=False)
    asr = read_experiments(tmp_path / "syn" / "affordance-words" / "sent-all_mllr3_aff_bag.txt")
    assert len(asr) == 150 and not asr.equals(df)


def test_synth_folders_are_complete_or_absent(tmp_path):
    import pytest

    from glu.data.source import SYNTHETIC_MARKER
    from glu.data.synthetic import write_synthetic_folder
    from glu.errors import DataError

    out = tmp_path / "syn"

    def interrupt(name):
        if name.startswith("affordance-words/networkDefinition"):
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        write_synthetic_folder(out, 200, 1, progress=interrupt)
    assert list(tmp_path.iterdir()) == []  # nothing, not even the staging folder
    write_synthetic_folder(out, 200, 1)
    assert (out / SYNTHETIC_MARKER).is_file()
    write_synthetic_folder(out, 300, 2)  # an earlier synthetic folder is replaced whole
    assert '"seed": 2' in (out / SYNTHETIC_MARKER).read_text()
    other = tmp_path / "real"
    (other / "affordance-words").mkdir(parents=True)
    (other / "affordance-words" / "sent-1-5_lab_aff_bag.txt").write_text("x")
    with pytest.raises(DataError, match="refusing to overwrite"):
        write_synthetic_folder(other, 200, 1)
    assert (other / "affordance-words" / "sent-1-5_lab_aff_bag.txt").read_text() == "x"
