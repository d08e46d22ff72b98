"""`glu data fetch` against a local HTTP server serving a data folder (with broken files) and its manifest.

The mirror serves a copy of the synthetic data folder, described by a manifest written here with
checksums computed by hashlib; the real manifest's checksums are checked against the real files in
tests/studies/test_reference.py.
"""

from __future__ import annotations

import hashlib
import json
import re
import shutil
import threading
from functools import partial
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import pytest

from glu.cli import main
from glu.data.fetch import fetch_all, manifest, partial_folder, sha256_of
from glu.errors import FetchError

TRUNCATED = "gestures/tap1_hand/data.log"


class _Handler(SimpleHTTPRequestHandler):
    def log_message(self, *args) -> None:  # keep test output clean
        pass

    def do_GET(self) -> None:
        if self.path.endswith(TRUNCATED) and getattr(self.server, "truncate", False):
            body = (Path(self.directory) / TRUNCATED).read_bytes()
            self.send_response(200)
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body[: len(body) // 2])  # the connection drops mid-file
            self.close_connection = True
            return
        super().do_GET()


@pytest.fixture
def server(synthetic_folder, tmp_path):
    root = tmp_path / "mirror"
    shutil.copytree(synthetic_folder, root)
    httpd = ThreadingHTTPServer(("127.0.0.1", 0), partial(_Handler, directory=str(root)))
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    yield root, f"http://127.0.0.1:{httpd.server_address[1]}", httpd
    httpd.shutdown()
    httpd.server_close()


@pytest.fixture
def mirror_manifest(synthetic_folder, tmp_path):
    """A manifest of every file of the synthetic folder, in the format of glu's own."""
    files = []
    for f in sorted(p for p in synthetic_folder.rglob("*") if p.is_file()):
        local = f.relative_to(synthetic_folder).as_posix()
        digest = hashlib.sha256(f.read_bytes()).hexdigest()
        files.append({"local": local, "source": "S", "path": f"data/{local}", "sha256": digest})
    spec = {
        "url_template": "https://example.org/{repo}/{commit}/{path}",
        "repositories": {"S": {"repo": "lab/data", "commit": "0" * 40}},
        "files": files,
    }
    path = tmp_path / "manifest.json"
    path.write_text(json.dumps(spec))
    return path, len(files)


def test_fetch_is_complete_or_absent(server, mirror_manifest, synthetic_folder, tmp_path):
    root, url, httpd = server
    path, n = mirror_manifest
    corrupted = "affordance-words/networkDefinition.txt"
    missing = "gestures/push1_hand/data.log"
    (root / corrupted).write_bytes((root / corrupted).read_bytes().replace(b"tap", b"t4p"))
    (root / missing).unlink()
    httpd.truncate = True
    dest = tmp_path / "real"
    results = {r.local: r for r in fetch_all(dest, mirror=url, manifest_path=path)}
    failed = {k for k, r in results.items() if r.status == "failed"}
    assert failed == {corrupted, missing, TRUNCATED}
    assert "sha256 mismatch" in results[corrupted].detail
    assert "404" in results[missing].detail
    assert not dest.exists()  # nothing is published until every file is verified
    partial = partial_folder(dest)
    kept = {p.relative_to(partial).as_posix() for p in partial.rglob("*") if p.is_file()}
    assert kept == {i.local for i in manifest(url, path)} - failed  # verified files only, no temporaries
    for local in kept:
        assert (partial / local).read_bytes() == (synthetic_folder / local).read_bytes()

    # the server is mended: a second run downloads only what is missing, then publishes the whole folder
    httpd.truncate = False
    shutil.copy(synthetic_folder / corrupted, root / corrupted)
    shutil.copy(synthetic_folder / missing, root / missing)
    results = {r.local: r.status for r in fetch_all(dest, mirror=url, manifest_path=path)}
    assert {k for k, s in results.items() if s == "downloaded"} == failed
    assert all(s in ("downloaded", "present") for s in results.values())
    assert not partial.exists()
    for item in manifest(url, path):
        assert sha256_of(dest / item.local) == item.sha256
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []


def test_fetch_into_an_existing_data_folder_keeps_its_other_files(server, mirror_manifest, tmp_path):
    _, url, _ = server
    path, _ = mirror_manifest
    dest = tmp_path / "real"
    (dest / "sentence-samples").mkdir(parents=True)
    (dest / "sentence-samples" / "mine.txt").write_text("kept\n")
    assert all(r.status == "downloaded" for r in fetch_all(dest, mirror=url, manifest_path=path))
    assert (dest / "sentence-samples" / "mine.txt").read_text() == "kept\n"
    assert all(r.status == "present" for r in fetch_all(dest, mirror=url, manifest_path=path))


def test_fetch_refuses_a_folder_of_something_else(server, mirror_manifest, tmp_path):
    _, url, _ = server
    path, _ = mirror_manifest
    (tmp_path / "home").mkdir()
    (tmp_path / "home" / "thesis.tex").write_text("x")
    with pytest.raises(FetchError, match="other content"):
        fetch_all(tmp_path / "home", mirror=url, manifest_path=path)
    assert [p.name for p in (tmp_path / "home").iterdir()] == ["thesis.tex"]


def test_fetch_command_reports_failures_with_status_2(server, mirror_manifest, tmp_path, capsys):
    root, url, _ = server
    path, n = mirror_manifest
    (root / "affordance-words" / "networkDefinition.txt").unlink()
    status = main(["data", "fetch", "-o", str(tmp_path / "d"), "--mirror", url, "--manifest", str(path)])
    err = capsys.readouterr().err
    assert status == 2
    last = err.strip().splitlines()[-1]
    assert last.startswith(f"glu data fetch: error: 1 of {n} files could not be fetched")
    assert f"[{n}/{n}]" in err
    assert f"nothing was written to {tmp_path / 'd'}" in last
    assert not (tmp_path / "d").exists()
    assert main(["data", "fetch", "-o", str(tmp_path / "d2"), "--mirror", "http://127.0.0.1:9"]) == 2


def test_the_manifest_names_the_pinned_commits():
    items = manifest()
    assert {i.url.split("/")[5] for i in items} == {
        "421f4554aba944fe4fdbfc51feb01b0967bf930e",
        "fd608ac0f732bc1016df55af0489e5f25c43036c",
    }
    assert all(len(i.sha256) == 64 for i in items)


def test_an_ftp_mirror_is_refused_before_any_request(tmp_path):
    """The downloads speak HTTP only: an ftp:// mirror made every file fail with requests' "No connection
    adapters were found"; it is refused up front now, and nothing is written."""
    with pytest.raises(FetchError, match=r"--mirror 'ftp://127.0.0.1/data': expected an http:// or https://"):
        fetch_all(tmp_path / "d", mirror="ftp://127.0.0.1/data")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ({"files": [{"local": "a.txt"}]}, "malformed manifest (KeyError: 'sha256')"),
        ({"files": [1]}, "malformed manifest (TypeError"),
        ([], "malformed manifest (TypeError"),
    ],
)
def test_a_malformed_manifest_is_one_fetch_error(tmp_path, spec, message):
    path = tmp_path / "manifest.json"
    path.write_text(json.dumps(spec))
    with pytest.raises(FetchError, match=re.escape(f"{path}: {message}")):
        fetch_all(tmp_path / "d", mirror="http://127.0.0.1:9", manifest_path=path)


def test_a_url_the_downloader_cannot_fetch_fails_that_file_only(mirror_manifest, tmp_path):
    """A manifest may give any URL template: a file:// URL fails its file with the reason, nothing is
    published."""
    path, n = mirror_manifest
    spec = json.loads(path.read_text())
    path.write_text(json.dumps({**spec, "url_template": "file:///nowhere/{path}"}))
    results = fetch_all(tmp_path / "d", manifest_path=path, timeout=5)
    assert len(results) == n and {r.status for r in results} == {"failed"}
    assert (
        results[0].detail.startswith("file:///nowhere/data/")
        and "No connection adapters" in results[0].detail
    )
    assert not (tmp_path / "d").exists()


def test_a_destination_that_is_a_file_is_refused(mirror_manifest, tmp_path):
    path, _ = mirror_manifest
    (tmp_path / "d").write_text("x")
    with pytest.raises(FetchError, match="d: exists and is not a folder; give a data folder"):
        fetch_all(tmp_path / "d", mirror="http://127.0.0.1:9", manifest_path=path)
    assert (tmp_path / "d").read_text() == "x"


def test_files_are_copied_where_they_cannot_be_linked(server, mirror_manifest, tmp_path, monkeypatch):
    """A data folder on a file system without hard links (or another device than its partial folder): the
    verified files present are copied into the new folder instead."""
    import os

    _, url, _ = server
    path, _ = mirror_manifest
    dest = tmp_path / "real"
    assert all(r.status == "downloaded" for r in fetch_all(dest, mirror=url, manifest_path=path))
    before = {p: p.read_bytes() for p in dest.rglob("*") if p.is_file()}

    def no_link(src, dst):
        raise OSError(18, "Invalid cross-device link")

    monkeypatch.setattr(os, "link", no_link)
    assert all(r.status == "present" for r in fetch_all(dest, mirror=url, manifest_path=path))
    assert {p: p.read_bytes() for p in dest.rglob("*") if p.is_file()} == before


def test_a_failed_fetch_keeps_the_folders_it_made_if_others_wrote_there(mirror_manifest, tmp_path):
    """Nothing verified: the folders the fetch made above its destination are removed again, up to one that
    something else wrote into meanwhile (kept with its file)."""
    path, _ = mirror_manifest
    top = tmp_path / "a"
    dest = top / "b" / "real"

    def meanwhile(i, n, result):
        (top / "notes.txt").write_text("mine")

    results = fetch_all(dest, mirror="http://127.0.0.1:9", manifest_path=path, timeout=5, progress=meanwhile)
    assert {r.status for r in results} == {"failed"}
    assert not (top / "b").exists() and [p.name for p in top.iterdir()] == ["notes.txt"]


def test_fetch_command_on_a_terminal_writes_failures_above_its_bar(
    server, mirror_manifest, tmp_path, capsys, monkeypatch
):
    """On a terminal the files go by in a progress bar; a failed file still gets its own line, and a fetch
    that verifies every file says so on stdout."""
    import re
    import sys

    root, url, _ = server
    path, n = mirror_manifest
    gone = root / "affordance-words" / "networkDefinition.txt"
    content = gone.read_bytes()
    gone.unlink()
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True, raising=False)
    dest = tmp_path / "d"
    argv = ["data", "fetch", "-o", str(dest), "--mirror", url, "--manifest", str(path)]
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert out == "" and re.search(rf"\[\d+/{n}\] failed     affordance-words/networkDefinition.txt: ", err)
    assert "downloaded " not in err  # the other files are counted by the bar, not listed
    gone.write_bytes(content)
    assert main(argv) == 0
    out, err = capsys.readouterr()
    assert out == f"{n}/{n} files verified in {dest}\n" and "failed" not in err
    assert (dest / "affordance-words" / "networkDefinition.txt").read_bytes() == content
