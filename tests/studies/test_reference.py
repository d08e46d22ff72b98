"""Reference tests: glu against the originals' models, their files and the published numbers.

These need the real data (``$GLU_SHARED_DATA`` or ``../shared/data``; CI has it) and skip with the reason
without it. Everything that can be checked on any data — glu against pgmpy, hmmlearn, brute force and
closed forms — is in the other test files and runs on synthetic data too. Each test here covers one
published artefact (its parts are subtests, reported one by one), so that a clone without the real data
skips only these few; ``test_reference_tcds.py`` and ``test_correspondence_reference.py`` do the same.
"""

from __future__ import annotations

import json
import os
import warnings

import numpy as np
import pytest
import scipy.io as sio
from cli_run import run
from test_hmm import mat_params, ref_forward

from glu import paths
from glu.bn import learn_bn, make_engine
from glu.bn.model import encode
from glu.data.fetch import manifest, sha256_of
from glu.data.recordings import ORIGINAL_SEGMENTS, TRAINING_RECORDINGS
from glu.errors import ImpossibleEvidenceError
from glu.gestures.corpus import segment_recording_of
from glu.gestures.recognizer import load_original_models
from glu.gestures.recordings import read_hand_log
from glu.gestures.trajectories import repair
from glu.language import compile_network, count_by_length, load_grammar, parse_grammar, same_language
from glu.language.sampling import sample_sentences
from glu.run.provenance import ENV as PROVENANCE_ENV
from glu.run.reproduce import reproduce
from glu.run.summary import RENDERING_RECORD
from glu.schema import ROOT_NODES, default_schema
from glu.studies.replication import fusion as experiments
from glu.studies.replication import gestures
from glu.studies.replication.fusion import network_summary

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    from bn_reference import to_pgmpy_with_zero_rows
    from pgmpy.inference import VariableElimination

LOG_LINES = {  # lines in each real log (wc -l), an independent count
    "grasp1_hand": 958,
    "norobotview_tap_notable_seated_2": 597,
    "push1_hand": 687,
    "tap1_hand": 752,
    "tap_notable_seated_1": 384,
    "touch1_hand": 819,
}
HMM_ORDER = {"grasp": 3, "tap": 1, "touch": 4, "garbage": 0}  # hmm{k} of the .mat files (docs/method.md §4.4)


def _files_schema_and_grammar(shared_data, real_source):
    items = manifest()
    assert len(items) == 15  # 14 files + the originals' sampled sentences
    for item in items:
        assert item.url.startswith("https://raw.githubusercontent.com/")
        assert sha256_of(shared_data / item.local) == item.sha256, item.local
    # the tables and the network definition
    from glu.data import load_experiments, read_network_definition

    schema = read_network_definition(real_source.network_definition())
    assert dict(schema.values) == dict(default_schema().values) and schema.n_affordance == 8
    for words in ("lab", "asr"):
        assert load_experiments(real_source, words).shape == (1270, 57)
    # glu's own grammar file generates exactly the originals' language
    original = load_grammar(shared_data / "affordance-words" / "grammar.grm")
    ours = load_grammar()
    assert set(original.vocabulary) == set(ours.vocabulary)
    net_o, net_g = compile_network(original), compile_network(ours)
    assert count_by_length(net_o) == count_by_length(net_g)
    assert same_language(net_o, net_g)
    assert all(net_g.accepts(s) for s in sample_sentences(original, 2000, seed=1))
    assert all(net_o.accepts(s) for s in sample_sentences(ours, 2000, seed=2))
    text = (shared_data / "affordance-words" / "grammar.grm").read_text()
    changed = parse_grammar(text.replace("$conjunction = and | but;", "$conjunction = and;"))
    assert not same_language(compile_network(changed), net_g)  # the comparison can fail


def _learning_reproduces_the_original_network(lab_table, learned_bn, original_bn):
    assert len(original_bn.edges()) == 66
    assert learned_bn.edges() == original_bn.edges()
    for node in ROOT_NODES:
        assert learned_bn.parents[node] == ()
    worst = max(float(np.abs(learned_bn.cpts[n] - original_bn.cpts[n]).max()) for n in original_bn.nodes)
    assert worst == 0.0
    # the quirk (docs/method.md §3.4): all-zero rows for but/and/falls/falling at three (ObjVel, HandVel,
    # Contact)
    zero = {w: 3 for w in ("but", "and", "falls", "falling")}
    assert original_bn.zero_rows() == zero and learned_bn.zero_rows() == zero
    rows = np.argwhere(learned_bn.cpts["but"].sum(axis=-1) == 0)
    vals = [
        tuple(
            default_schema().values_of(n)[i] for n, i in zip(("ObjVel", "HandVel", "Contact"), r, strict=True)
        )
        for r in rows
    ]
    assert sorted(vals) == sorted(
        [("medium", "slow", "long"), ("fast", "slow", "long"), ("fast", "fast", "short")]
    )
    eng = make_engine(learned_bn)
    with pytest.raises(ImpossibleEvidenceError, match="ObjVel=fast, HandVel=fast, Contact=short"):
        eng.query(["Action"], {"ObjVel": "fast", "HandVel": "fast", "Contact": "short"})
    assert 1 - eng.probability_of_evidence() == pytest.approx(
        0.0165, abs=5e-5
    )  # 1.65 % of the prior mass disappears
    # log-likelihood of the training data: −19692.2025 for all 57 nodes; the struct's L leaves out the roots
    codes = encode(lab_table, learned_bn.schema)
    assert learned_bn.log_likelihood(codes) == pytest.approx(-19692.2025, abs=1e-4)
    non_roots = tuple(n for n in learned_bn.nodes if n not in ROOT_NODES)
    assert original_bn.log_likelihood(codes, non_roots) == pytest.approx(-14723.6182, abs=1e-4)
    uniform = learn_bn(lab_table, unseen_words="uniform")
    assert uniform.edges() == learned_bn.edges() and uniform.zero_rows() == {}


def _the_original_network_file_and_the_command_line(shared_data, real_source, original_bn, tmp_path, capsys):
    mat = real_source.original_bn()
    raw = sio.loadmat(mat, squeeze_me=True, struct_as_record=False)["netobj_lab"]
    names = [str(n) for n in raw.nodeNames]
    j = names.index("ObjVel")
    # CPT[i_Action, i_Shape, i_Size, v] in the .mat; the same cell through glu's model
    np.testing.assert_array_equal(original_bn.cpts["ObjVel"][1, 0, 0], raw.bnet.CPD[j].CPT[1, 0, 0])
    assert original_bn.schema.values_of("Shape") == ("sphere", "box")
    expected = sorted(f"{names[i]} -> {names[k]}" for i, k in zip(*np.nonzero(raw.dag), strict=True))
    model = tmp_path / "lab.json"
    assert run(capsys, "bn", "learn", "--data", str(shared_data), "-o", str(model))[0] == 0
    assert run(capsys, "bn", "edges", str(model))[1].splitlines() == expected
    assert run(capsys, "bn", "edges", str(mat))[1].splitlines() == expected
    # the README's done-when: the sphere and the box, from the data and from the original file, identical
    for evidence in (["Shape=sphere", "Size=small"], ["Shape=box", "Size=big"]):
        argv = ["query", "--target", "ObjVel", "--evidence", "Action=tap", *evidence, "--json"]
        learned = json.loads(run(capsys, *argv, "--data", str(shared_data))[1])["ObjVel"]
        original = json.loads(run(capsys, *argv, "--model", str(mat))[1])["ObjVel"]
        assert learned == original
    assert learned["slow"] == pytest.approx(0.9988375885888248, abs=1e-15)


def _network_summary_of_the_original(learned_bn, original_bn, lab_table):
    df = network_summary(learned_bn, lab_table, original_bn).set_index("quantity")
    assert df.loc["edges", "ours"] == 66 and df.loc["log_likelihood", "ours"] == pytest.approx(
        -19692.2025, abs=1e-4
    )
    assert df.loc["lost_prior_mass", "ours"] == pytest.approx(0.0165, abs=5e-5)  # docs/method.md §3.4: 1.65 %
    assert (df["difference"].abs() == 0).all()


def test_published_network_numbers_equal_the_original_model(learned_bn, original_bn):
    # GLU 2017 Fig. 4, against the original and pgmpy (with an explicit "seen" indicator for the zero rows)
    df = experiments.effect_prediction(learned_bn, original_bn)
    assert df["difference"].abs().max() == 0.0 and "real data" in df.attrs["data_source"]
    model, seen = to_pgmpy_with_zero_rows(original_bn)
    ve = VariableElimination(model)
    for case, ev in experiments.EFFECT_CASES.items():
        ours = df[df.case == case]["p"].to_numpy()
        np.testing.assert_allclose(
            ours, ve.query(["ObjVel"], {**ev, **seen}, show_progress=False).values, atol=1e-9
        )
    sphere, box = (df[df.case == c]["p"].to_numpy() for c in ("small sphere", "big box"))
    assert sphere.argmax() == 2 and box.argmax() == 0  # the sphere rolls fast, the box barely moves
    np.testing.assert_allclose(
        sphere, [0.04778970757590299, 0.42857582710740644, 0.5236344653166904], atol=1e-15
    )
    # GLU 2017 Fig. 5: the paper's statements, and the original code's extra Color=yellow changes nothing
    text = experiments.word_probability_change(learned_bn, "text", original_bn)
    code = experiments.word_probability_change(learned_bn, "code", original_bn)
    assert text["difference"].abs().max() == 0.0
    np.testing.assert_allclose(text["delta"], code["delta"], atol=1e-12)
    d = text.set_index("word")["delta"]
    assert {"taps", "tapped", "pushes", "pushed", "rolls"} <= set(text.loc[text.shown, "word"])
    assert all(d[w] > 0 for w in ("taps", "tapping", "pushes", "rolls"))
    assert all(d[w] < 0 for w in ("touches", "touching", "pokes", "poking"))
    # TCDS: action and effect under soft evidence; the threshold the paper reads as 0.81
    a = experiments.action_vs_soft_evidence(learned_bn, reference=original_bn)
    e = experiments.effect_vs_soft_evidence(learned_bn, reference=original_bn)
    assert a["difference"].abs().max() == 0.0 and e["difference"].abs().max() == 0.0
    assert 0.8043 < experiments.tap_threshold(learned_bn) < 0.8044


def _notebooks_reproduce_the_original_network_figures(summary):
    comparison = {c["table"]: c["max_abs_difference"] for c in summary["comparison_with_reference"]}
    for table in (
        "glu2017_effect_prediction",
        "glu2017_word_change_text",
        "glu2017_word_change_code",
        "bn_structure",
    ):
        assert comparison[table] == 0.0, table
    assert summary["data_source"].startswith("real data")


def test_real_recordings_load_and_segment_as_the_originals_cut_them(shared_data, real_source):
    for name, n_lines in LOG_LINES.items():
        ref = np.loadtxt(real_source.hand_log(name))  # an independent parser
        tr = read_hand_log(real_source.hand_log(name))
        assert len(tr) == n_lines == len(ref)
        np.testing.assert_array_equal(tr.t, ref[:, 1])
        np.testing.assert_array_equal(tr.xyz, ref[:, 2:])
    # push1_hand has a 1.54 s tracking gap, where the trajectory is split; tap1_hand has none
    push = read_hand_log(real_source.hand_log("push1_hand"))
    t = np.loadtxt(real_source.hand_log("push1_hand"))[:, 1]
    after = int(np.argmax(np.diff(t))) + 2
    rp = repair(push.with_xyz(push.xyz / 1000))
    gaps = {e.frame: e for e in rp.events if e.kind == "gap"}
    assert gaps[after].size == pytest.approx(np.diff(t).max()) and gaps[after].size > 1.5
    assert gaps[after].action == "split" and any(p.frame[0] == after for p in rp.pieces)
    tap = read_hand_log(real_source.hand_log("tap1_hand"))
    assert not [e for e in repair(tap.with_xyz(tap.xyz / 1000)).events if e.kind == "gap"]
    # automatic segmentation: one segment per repetition; tap1's around the originals' hand-cut ranges
    counts = {name: len(segment_recording_of(real_source, name).segments) for name in TRAINING_RECORDINGS}
    assert counts == {"grasp1_hand": 4, "tap1_hand": 3, "touch1_hand": 4, "push1_hand": 2}
    found = [(s.start, s.end) for s in segment_recording_of(real_source, "tap1_hand").segments]
    for f, (a, b) in zip(found, ORIGINAL_SEGMENTS["tap1_hand"], strict=True):
        inter = max(0, min(f[1], b + 10) - max(f[0], a - 10) + 1)
        assert inter / (max(f[1], b + 10) - min(f[0], a - 10) + 1) > 0.8, (f, (a, b))


def test_original_hmms_on_the_original_segments(real_source, capsys):
    from hmmlearn.hmm import GMMHMM

    for m in (3, 1):
        path = real_source.original_hmms(m)
        rec = load_original_models(path, include_garbage=True)
        mat = sio.loadmat(path)
        assert rec.actions == ("grasp", "tap", "touch", "garbage")
        for name, ranges in ORIGINAL_SEGMENTS.items():
            log = np.loadtxt(real_source.hand_log(name))
            for a, b in ranges:
                X = log[a - 1 : b, 2:] / 1000
                ours = rec.loglik(X)
                for i, action in enumerate(rec.actions):
                    params = mat_params(mat, HMM_ORDER[action])
                    assert ours[i] == pytest.approx(ref_forward(X, *params)[-1], abs=1e-6)
                    h = GMMHMM(
                        n_components=len(params[0]),
                        n_mix=params[2].shape[1],
                        covariance_type="full",
                        init_params="",
                    )
                    h.n_features = 3
                    h.startprob_, h.transmat_, h.weights_, h.means_, h.covars_ = params
                    assert ours[i] == pytest.approx(h.score(X), abs=1e-6)
    # the winners (README and notebook 02): four of the five are tap, tap1_hand 401–511 goes to "touch"
    df = gestures.original_scores(real_source)
    assert df.winner.tolist() == ["tap", "touch", "tap", "tap", "tap"]
    # the command line prints the same numbers, and a stream whose last line is the whole segment's
    status, out, err = run(
        capsys, "recognize", "tap1_hand", "--data", str(real_source.root), "--frames", "216:351", "--json"
    )
    assert status == 0 and "real data" in err
    d = json.loads(out)
    np.testing.assert_allclose(
        list(d["loglik"].values()), df.iloc[0][["loglik_grasp", "loglik_tap", "loglik_touch"]].to_numpy(float)
    )
    assert max(d["posterior"], key=d["posterior"].get) == "tap"


def _named_by_its_public_origin(shared_data, tmp_path):
    """The label on every result names the repositories and commits, never the folder it was read from."""
    from glu.data import resolve_data

    link = tmp_path / "elsewhere"
    link.symlink_to(shared_data)
    expected = "real data: giampierosalvi/AffordancesAndSpeech@421f455, gsaponaro/tcds-gestures@fd608ac"
    assert resolve_data(shared_data).describe() == resolve_data(link).describe() == expected
    copy = tmp_path / "copy"
    import shutil

    shutil.copytree(shared_data, copy)
    table = copy / "affordance-words" / "sent-1-5_lab_aff_bag.txt"
    table.write_text(table.read_text().replace("tap", "tap ", 1))
    with pytest.warns(UserWarning, match="the published data modified"):
        described = resolve_data(copy).describe()
    assert described == (
        "data folder 'copy' (the published data modified: affordance-words/sent-1-5_lab_aff_bag.txt differs "
        "from the published file)"
    )


FAST_NOTEBOOKS = ["01", "03", "04", "05", "06", "07"]
"""Notebooks whose figures the default suite re-renders from the real data (the others: -m slow)."""


def _render_from_elsewhere(shared_data, tmp_path, only):
    """Run notebooks on the real data reached through another path (a symlink): (summary, output folder)."""
    link = tmp_path / "the-data-seen-from-elsewhere"
    link.symlink_to(shared_data)
    out = tmp_path / "out"
    # the committed figures' footer names the glu that drew them: this run draws the same line
    record = json.loads((paths.PROJECT_ROOT / "figures" / RENDERING_RECORD).read_text())
    before = os.environ.get(PROVENANCE_ENV)
    os.environ[PROVENANCE_ENV] = record.get("made_by", "")
    try:
        return reproduce(data=link, out=out, jobs=2, only=only, log=lambda _: None, site=False), out
    finally:
        if before is None:
            os.environ.pop(PROVENANCE_ENV, None)
        else:
            os.environ[PROVENANCE_ENV] = before


def _figures_equal_the_committed_ones(summary, out):
    """Every PNG the run wrote is byte-identical to the committed one (when rendered by the same versions)."""
    import json

    from glu.paths import PROJECT_ROOT
    from glu.run.summary import RENDERING_RECORD, rendering_versions

    committed = PROJECT_ROOT / "figures"
    record = json.loads((committed / RENDERING_RECORD).read_text())
    if record["quick"] or not record["data_source"].startswith("real data"):
        pytest.fail(f"the committed figures are not the full real-data run: {record}")
    here = rendering_versions()
    if {k: record[k] for k in here} != here:
        pytest.skip(f"the committed figures were rendered with {record}, this machine has {here}")
    pngs = [f for f in summary["figures"] if f.endswith(".png")]
    assert pngs
    for name in pngs:
        assert (out / "figures" / name).read_bytes() == (committed / name).read_bytes(), name
    return pngs


# ------------------------------------------------------------------ one test per published artefact
def test_the_real_data_files(shared_data, real_source, tmp_path, subtests):
    """The published files: their checksums, the schema, the originals' grammar, and how results name them."""
    with subtests.test("checksums, schema and the originals' grammar"):
        _files_schema_and_grammar(shared_data, real_source)
    with subtests.test("results name the public origin, however the folder is reached"):
        _named_by_its_public_origin(shared_data, tmp_path)


def test_the_original_network(
    shared_data, real_source, lab_table, learned_bn, original_bn, tmp_path, capsys, subtests
):
    """The originals' Affordance–Words network: learned again from the data, and read from their file."""
    with subtests.test("learning reproduces it: 66 edges, CPT difference 0, the zero rows"):
        _learning_reproduces_the_original_network(lab_table, learned_bn, original_bn)
    with subtests.test("the summary table of notebook 03 (edges, likelihood, lost prior mass) against it"):
        _network_summary_of_the_original(learned_bn, original_bn, lab_table)
    with subtests.test("its .mat file, and the command line on both"):
        _the_original_network_file_and_the_command_line(
            shared_data, real_source, original_bn, tmp_path, capsys
        )


def test_notebooks_and_figures_from_the_real_data(shared_data, tmp_path, subtests):
    """Notebooks on the real data, reached through another path: their comparisons with the original network
    are exact, and their figures equal the committed ones."""
    summary, out = _render_from_elsewhere(shared_data, tmp_path, FAST_NOTEBOOKS)
    with subtests.test("notebooks 03 and 07 reproduce the original network's figures"):
        _notebooks_reproduce_the_original_network_figures(summary)
    with subtests.test("the figures equal the committed ones"):
        _figures_equal_the_committed_ones(summary, out)


@pytest.mark.slow
def test_every_figure_from_the_real_data_equals_the_committed_one(shared_data, tmp_path):
    summary, out = _render_from_elsewhere(shared_data, tmp_path, None)
    pngs = _figures_equal_the_committed_ones(summary, out)
    from glu.paths import PROJECT_ROOT

    assert set(pngs) == {p.name for p in (PROJECT_ROOT / "figures").glob("*.png")}
