"""On the real data: the seated taps sit elsewhere in the torso frame, and HMMs trained on the standing
recordings recognise them once the features are start-centred (issue 13). Skipped without the real data.

One test for the claim, its parts as subtests: the issue's command trains centred HMMs at seeds 0–2 and
each must call both seated taps tap; raw HMMs must not; effect anticipation with the centred HMMs."""

from __future__ import annotations

import json

import numpy as np

from glu.cli import main

CASES = {"tap_notable_seated_1": "121:214", "norobotview_tap_notable_seated_2": "230:375"}


def _glu(capsys, *argv):
    status = main(list(argv))
    out, err = capsys.readouterr()
    return status, out, err


def _the_seated_taps_sit_apart_from_every_standing_repetition(real_source):
    from glu.studies.correspondence.seated import posture_offsets

    off = posture_offsets(real_source)
    standing, seated = off[off["posture"] == "standing"], off[off["posture"] == "seated"]
    assert len(seated) == 2 and len(standing) == 13
    assert seated["y"].min() > standing["y"].max() + 0.3  # higher
    assert seated["z"].max() < standing["z"].min() - 0.4  # further in front


def _train_centred(shared_data, folder, seed):
    """The issue's command exactly (glu's defaults)."""
    path = folder / f"centred-seed{seed}.json"
    argv = ["hmm", "train", "--data", str(shared_data), "--features", "centred", "-o", str(path)]
    assert main([*argv, "--seed", str(seed)]) == 0
    return path


def _centred_hmms_trained_standing_call_the_seated_tap_tap(capsys, shared_data, centred_models, recording):
    capsys.readouterr()
    status, out, err = _glu(
        capsys,
        "recognize",
        recording,
        "--frames",
        CASES[recording],
        "--data",
        str(shared_data),
        "--models",
        str(centred_models),
        "--json",
    )
    assert status == 0 and "features centred" in err
    posterior = json.loads(out)["posterior"]
    assert max(posterior, key=posterior.get) == "tap" and posterior["tap"] >= 0.9


def _raw_hmms_trained_standing_do_not(shared_data, tmp_path):
    from glu.gestures.corpus import original_test_segments
    from glu.gestures.recognizer import Recognizer

    path = tmp_path / "raw.json"
    assert main(["hmm", "train", "--data", str(shared_data), "-o", str(path)]) == 0
    rec = Recognizer.load(path)
    from glu.data import resolve_data

    seated = [s for s in original_test_segments(resolve_data(shared_data)) if s.recording in CASES]
    assert [rec.classify(s.xyz) for s in seated] != ["tap", "tap"]


def _effect_anticipation_with_centred_glu_hmms(real_source, learned_bn, centred_models):
    from glu.bn.inference import make_engine
    from glu.gestures.recognizer import Recognizer
    from glu.studies.anticipation.experiment import CASES as ANTICIPATION
    from glu.studies.anticipation.experiment import case_trajectory, effect_anticipation

    rec, engine = Recognizer.load(centred_models), make_engine(learned_bn)
    final = {}
    for case, c in ANTICIPATION.items():
        run = effect_anticipation(rec, engine, case_trajectory(real_source, case), c.evidence)
        final[case] = dict(zip(run.values["ObjVel"], run.fused["ObjVel"][-1], strict=True))
    assert max(final["sphere"], key=final["sphere"].get) != "slow"  # the sphere will move
    assert max(final["box"], key=final["box"].get) == "slow"  # the box will not
    assert np.isclose(sum(final["sphere"].values()), 1.0)


def test_the_seated_taps(shared_data, real_source, learned_bn, tmp_path, capsys, subtests):
    """Issue 13: trained on the standing recordings only, centred HMMs call both seated taps tap; raw ones do
    not."""
    with subtests.test("the seated taps sit apart from every standing repetition"):
        _the_seated_taps_sit_apart_from_every_standing_repetition(real_source)
    for seed in (0, 1, 2):
        models = _train_centred(shared_data, tmp_path, seed)
        for recording in CASES:
            with subtests.test(
                "centred HMMs trained standing call the seated tap tap", seed=seed, recording=recording
            ):
                _centred_hmms_trained_standing_call_the_seated_tap_tap(capsys, shared_data, models, recording)
        with subtests.test("effect anticipation with the centred HMMs", seed=seed):
            _effect_anticipation_with_centred_glu_hmms(real_source, learned_bn, models)
    with subtests.test("raw HMMs trained standing do not call both tap"):
        _raw_hmms_trained_standing_do_not(shared_data, tmp_path)
