"""`glu data fetch` against a local HTTP server serving a copy of the shared data (with broken files)."""

from __future__ import annotations

import shutil
import threading
from functools import partial
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import pytest

from glu.cli import main
from glu.data.fetch import fetch_all, manifest, sha256_of

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
def server(shared_data, tmp_path):
    root = tmp_path / "mirror"
    shutil.copytree(shared_data, root)
    httpd = ThreadingHTTPServer(("127.0.0.1", 0), partial(_Handler, directory=str(root)))
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    yield root, f"http://127.0.0.1:{httpd.server_address[1]}", httpd
    httpd.shutdown()
    httpd.server_close()


def test_manifest_checksums_match_the_shared_copy(shared_data):
    items = manifest()
    assert len(items) == 14
    for item in items:
        assert item.url.startswith("https://raw.githubusercontent.com/")
        assert sha256_of(shared_data / item.local) == item.sha256, item.local


def test_fetch_verifies_and_leaves_nothing_partial(server, tmp_path):
    root, url, httpd = server
    corrupted = "affordance-words/grammar.grm"
    missing = "reference-models/HMM_M1_Q6_mixsplit.mat"
    (root / corrupted).write_bytes((root / corrupted).read_bytes().replace(b"robot", b"r0bot"))
    (root / missing).unlink()
    httpd.truncate = True
    dest = tmp_path / "real"
    results = {r.local: r for r in fetch_all(dest, mirror=url)}
    failed = {k for k, r in results.items() if r.status == "failed"}
    assert failed == {corrupted, missing, TRUNCATED}
    assert "sha256 mismatch" in results[corrupted].detail
    assert "404" in results[missing].detail
    for local in failed:
        assert not (dest / local).exists()
    leftovers = [
        p for p in dest.rglob("*") if p.is_file() and (p.name.startswith(".") or p.suffix == ".part")
    ]
    assert leftovers == []
    for item in manifest(url):
        if item.local not in failed:
            assert sha256_of(dest / item.local) == item.sha256

    # the server is mended: a second run downloads only what is missing
    httpd.truncate = False
    shutil.copy(shared_data_file(root, corrupted), root / corrupted)
    shutil.copy(shared_data_file(root, missing), root / missing)
    results = {r.local: r.status for r in fetch_all(dest, mirror=url)}
    assert {k for k, s in results.items() if s == "downloaded"} == failed
    assert all(s in ("downloaded", "present") for s in results.values())


def shared_data_file(_root: Path, local: str) -> Path:
    from glu.paths import shared_data_dir

    return shared_data_dir() / local


def test_fetch_command_reports_failures_with_status_2(server, tmp_path, capsys):
    root, url, _ = server
    (root / "affordance-words" / "affdata.txt").unlink()
    status = main(["data", "fetch", "--dest", str(tmp_path / "d"), "--mirror", url])
    err = capsys.readouterr().err
    assert status == 2
    last = err.strip().splitlines()[-1]
    assert last.startswith("glu data fetch: error: 1 of 14 files could not be fetched")
    assert "[14/14]" in err
    assert not (tmp_path / "d" / "affordance-words" / "affdata.txt").exists()
    assert main(["data", "fetch", "--dest", str(tmp_path / "d2"), "--mirror", "http://127.0.0.1:9"]) == 2
