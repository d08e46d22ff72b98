"""Atomic writes (glu.files): complete or absent, and with the permissions the umask gives any other file."""

from __future__ import annotations

import os
import stat

import pytest

from glu.files import atomic_write_text, staged_folder


@pytest.fixture
def umask():
    old = os.umask(0o022)
    os.umask(old)

    def set_mask(mask: int) -> None:
        os.umask(mask)

    yield set_mask
    os.umask(old)


@pytest.mark.parametrize(
    ("mask", "file_mode", "folder_mode"),
    [(0o022, 0o644, 0o755), (0o077, 0o600, 0o700), (0o002, 0o664, 0o775)],
)
def test_written_files_and_folders_respect_the_umask(tmp_path, umask, mask, file_mode, folder_mode):
    umask(mask)
    path = atomic_write_text(tmp_path / "a" / "f.txt", "x")
    assert stat.S_IMODE(path.stat().st_mode) == file_mode  # a temporary file alone would be 0o600
    with staged_folder(tmp_path / "d") as tmp:
        (tmp / "g.txt").write_text("y")
    assert stat.S_IMODE((tmp_path / "d").stat().st_mode) == folder_mode
    assert (tmp_path / "d" / "g.txt").read_text() == "y"


def test_a_failed_write_leaves_nothing(tmp_path):
    with pytest.raises(RuntimeError), staged_folder(tmp_path / "d") as tmp:
        (tmp / "half.txt").write_text("half")
        raise RuntimeError("interrupted")
    assert list(tmp_path.iterdir()) == []


def test_a_marked_set_is_vouched_for_only_once_written_whole(tmp_path):
    """marked_set: the markers are gone from the first write of the set to the last, and again after a
    failure (even one after a marker was written); the folder's other files are never touched; a block
    that forgets a marker is glu's mistake."""
    from glu.files import atomic_write_json, marked_set

    (tmp_path / "notes.txt").write_text("mine\n")
    for name in ("table.csv", "summary.json", "key.json"):
        (tmp_path / name).write_text("old\n")
    with marked_set(tmp_path, "summary.json", "key.json") as folder:
        assert folder == tmp_path
        assert not (tmp_path / "summary.json").exists() and not (tmp_path / "key.json").exists()
        atomic_write_text(tmp_path / "table.csv", "new\n")
        atomic_write_json(tmp_path / "summary.json", {"n": 1})
        atomic_write_json(tmp_path / "key.json", {"k": 1})
    assert (tmp_path / "key.json").read_text() == '{\n "k": 1\n}\n'
    with pytest.raises(KeyboardInterrupt), marked_set(tmp_path, "summary.json", "key.json"):
        atomic_write_text(tmp_path / "summary.json", "written too early\n")
        raise KeyboardInterrupt
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.txt", "table.csv"]
    assert (tmp_path / "notes.txt").read_text() == "mine\n"
    with pytest.raises(RuntimeError, match="without its marker key.json"), marked_set(tmp_path, "key.json"):
        atomic_write_text(tmp_path / "table.csv", "newer\n")
    with marked_set(tmp_path / "new" / "folder", "key.json") as folder:  # a folder not there yet
        atomic_write_text(folder / "key.json", "{}")
    assert (tmp_path / "new" / "folder" / "key.json").is_file()


def test_read_text_names_the_file_and_what_it_should_be(tmp_path):
    from glu.errors import DataError
    from glu.files import read_text

    (tmp_path / "s.yaml").write_bytes(b"\xff\xfe not utf-8 \xff")
    for path, message in (
        (tmp_path / "none.yaml", "none.yaml: no such schema file"),
        (tmp_path, "is a folder, not a schema file"),
        (tmp_path / "s.yaml", "s.yaml: cannot read the schema file as text"),
    ):
        with pytest.raises(DataError, match=message):
            read_text(path, "schema file")
    (tmp_path / "ok.yaml").write_text("name: x\n")
    assert read_text(tmp_path / "ok.yaml", "schema file") == "name: x\n"


def test_read_json_names_the_file_and_what_it_should_be(tmp_path):
    from glu.errors import DataError, ModelError
    from glu.files import read_bytes, read_json

    (tmp_path / "bad.json").write_text("{")
    (tmp_path / "latin.json").write_bytes(b'{"a": "\xe9"}')
    for path, message in (
        (tmp_path / "none.json", "none.json: no such model file"),
        (tmp_path, "is a folder, not a model file"),
        (tmp_path / "bad.json", "bad.json: not a JSON model file"),
        (tmp_path / "latin.json", "latin.json: not a JSON model file"),
    ):
        with pytest.raises(ModelError, match=message):
            read_json(path, "model file", ModelError)
    (tmp_path / "ok.json").write_text('{"a": [1, 2]}')
    assert read_json(tmp_path / "ok.json") == {"a": [1, 2]}
    with pytest.raises(DataError, match="none.bin: no such file"):
        read_bytes(tmp_path / "none.bin")
