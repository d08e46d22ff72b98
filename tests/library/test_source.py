"""Data sources (glu.data.source): how a folder is recognised and described, and what it lacks."""

from __future__ import annotations

import shutil

import pytest

from glu import paths
from glu.data import load_experiments, resolve_data
from glu.data.layout import NETWORK_DEFINITION, SYNTHETIC_MARKER, WORD_FILES
from glu.data.source import DataSource, check_words, load_schema
from glu.errors import DataError
from glu.schema import default_schema


@pytest.fixture
def own(synthetic_folder, tmp_path):
    """A folder of one's own data: the synthetic folder's experiment tables, without its marker file."""
    root = tmp_path / "own"
    shutil.copytree(synthetic_folder / "affordance-words", root / "affordance-words")
    return root


def test_synthetic_data_in_memory_has_no_files():
    source = resolve_data("synthetic")
    with pytest.raises(
        DataError, match="affordance-words/sent-1-5_lab_aff_bag.txt: synthetic data generated"
    ):
        source.experiments_file()
    with pytest.raises(DataError, match="no such recording in synthetic data .*it has no gesture recordings"):
        source.hand_log("tap1_hand")


def test_a_folder_without_gestures_or_a_table(own):
    with pytest.warns(UserWarning):
        source = resolve_data(own)
    assert source.recordings() == ()
    with pytest.raises(DataError, match="tap1_hand: no such recording .*it has no gesture recordings"):
        source.hand_log("tap1_hand")
    (own / WORD_FILES["asr"]).unlink()
    with pytest.raises(DataError, match=f"{own / WORD_FILES['asr']}: no such file in the data folder {own}"):
        source.experiments_file("asr")


def test_only_the_original_hmm_files_exist():
    with pytest.raises(DataError, match=r"n_mix=2: the originals have HMMs with M in \[1, 3\]"):
        resolve_data("synthetic").original_hmms(2)


def test_an_unknown_words_option():
    with pytest.raises(DataError, match="unknown words option 'mllr'; allowed: lab, asr"):
        check_words("mllr")


def test_a_folder_with_no_published_file_says_what_it_lacks_or_that_it_differs(tmp_path, own):
    """None of the manifest's files: it lacks the published table; only files that differ (the synthetic
    tables, without the network definition, which is the published one): not the published data."""
    (tmp_path / "mine" / "gestures").mkdir(parents=True)
    lacking = resolve_data(tmp_path / "mine").describe()
    assert lacking == "data folder 'mine' (not the published data: it lacks the published experiment table)"
    (own / NETWORK_DEFINITION).unlink()
    tables = f"{WORD_FILES['lab']}, {WORD_FILES['asr']}"
    with pytest.warns(UserWarning, match=f"own: not the published data: {tables} differ from the published"):
        source = resolve_data(own)
    assert (
        source.describe()
        == f"data folder 'own' (not the published data: {tables} differ from the published files)"
    )


def test_a_malformed_synthetic_marker(own):
    (own / SYNTHETIC_MARKER).write_text('{"seed": 1}')
    with pytest.raises(DataError, match=f"{own / SYNTHETIC_MARKER}: malformed marker file"):
        resolve_data(own)


def test_the_schema_of_a_folder_without_a_network_definition_is_the_default(own):
    (own / NETWORK_DEFINITION).unlink()
    with pytest.warns(UserWarning):
        source = resolve_data(own)
    assert load_schema(source) == default_schema()
    assert len(load_experiments(source)) > 0


def test_a_network_definition_with_other_nodes_is_refused(own):
    path = own / NETWORK_DEFINITION
    lines = path.read_text().splitlines()
    path.write_text("\n".join([lines[1], lines[0], *lines[2:]]) + "\n")  # two nodes swapped
    with pytest.warns(UserWarning):
        source = resolve_data(own)
    with pytest.raises(DataError, match="nodes differ from the model's 8 affordance nodes"):
        load_schema(source)


def test_fetched_data_is_used_when_nothing_is_given(synthetic_folder, monkeypatch):
    monkeypatch.delenv(paths.DATA_ENV_VAR, raising=False)
    monkeypatch.setattr(paths, "REAL_DATA_DIR", synthetic_folder)
    source = resolve_data()
    assert source.origin == "data/real" and source.root == synthetic_folder.resolve()
    assert isinstance(source, DataSource) and source.kind == "synthetic"


def test_a_source_without_the_original_hmms_has_no_original_recogniser():
    from glu.gestures.corpus import original_recognizer

    with pytest.raises(DataError, match=r"^the data source has no original HMMs with M = 3 \("):
        original_recognizer(resolve_data("synthetic"))
