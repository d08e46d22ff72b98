"""Download the real data from its public origin at pinned commits, verifying each file's sha256.

The manifest (``glu/resources/sources.json``) lists each file: where it goes in the data folder, which
repository and commit it comes from, and its sha256. Each file is downloaded into a temporary file in the
destination folder, checked, and only then renamed into place, so an interrupted or corrupted download
leaves no file behind. Files already present with the right checksum are kept.
"""

from __future__ import annotations

import hashlib
import http.client
import json
import os
import tempfile
import urllib.error
import urllib.request
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from glu import paths
from glu.errors import FetchError

MANIFEST = paths.RESOURCES_DIR / "sources.json"
CHUNK = 1 << 16


@dataclass(frozen=True)
class RemoteFile:
    """One file of the manifest: its place in the data folder, its URL and its sha256."""

    local: str
    url: str
    sha256: str


@dataclass(frozen=True)
class FetchResult:
    """Outcome of one file: ``status`` is ``downloaded``, ``present`` (already there) or ``failed``."""

    local: str
    status: str
    detail: str = ""


def manifest(mirror: str | None = None, path: str | os.PathLike = MANIFEST) -> list[RemoteFile]:
    """The files to fetch; with ``mirror``, URLs are ``{mirror}/{local path}`` instead of GitHub's.

    ``path`` is the manifest (default: glu's, the real data at the pinned commits): JSON with
    ``url_template``, ``repositories`` (key → repo, commit) and ``files`` (local, source, path, sha256).
    """
    try:
        spec = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise FetchError(f"{path}: not a readable manifest ({e})") from None
    out = []
    for f in spec["files"]:
        if mirror:
            url = mirror.rstrip("/") + "/" + f["local"]
        else:
            repo = spec["repositories"][f["source"]]
            url = spec["url_template"].format(repo=repo["repo"], commit=repo["commit"], path=f["path"])
        out.append(RemoteFile(local=f["local"], url=url, sha256=f["sha256"]))
    return out


def published_origin(root: str | os.PathLike, manifest_path: str | os.PathLike = MANIFEST) -> str | None:
    """The upstream origin of a data folder, ``"owner/name@commit, …"``, if it holds the published data.

    A folder holds the published data when it has the paper's experiment table and every file of the
    manifest that it has carries the published sha256 (files it lacks are not fetched yet, files the
    manifest does not list are ignored). Otherwise None: the folder is someone's own or modified data.
    The commits are abbreviated to 7 characters, as git does.
    """
    root = Path(root)
    spec = json.loads(Path(manifest_path).read_text(encoding="utf-8"))
    present = [f for f in spec["files"] if (root / f["local"]).is_file()]
    if not any(f["local"].endswith("_lab_aff_bag.txt") for f in present):
        return None
    if any(_cached_sha256(root / f["local"]) != f["sha256"] for f in present):
        return None
    used = sorted({f["source"] for f in present})
    repos = spec["repositories"]
    return ", ".join(f"{repos[k]['repo']}@{repos[k]['commit'][:7]}" for k in used)


_SHA_CACHE: dict[tuple[str, int, int], str] = {}


def _cached_sha256(path: Path) -> str:
    st = path.stat()
    key = (str(path.resolve()), st.st_size, st.st_mtime_ns)
    if key not in _SHA_CACHE:
        _SHA_CACHE[key] = sha256_of(path)
    return _SHA_CACHE[key]


def sha256_of(path: Path) -> str:
    """Hex sha256 of a file."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(CHUNK), b""):
            h.update(block)
    return h.hexdigest()


def fetch_file(item: RemoteFile, dest: Path, timeout: float = 60.0) -> FetchResult:
    """Download one file into ``dest`` atomically; return what happened (never a partial file)."""
    target = dest / item.local
    if target.is_file() and sha256_of(target) == item.sha256:
        return FetchResult(item.local, "present")
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp_name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".part", dir=target.parent)
    tmp = Path(tmp_name)
    try:
        h = hashlib.sha256()
        with os.fdopen(fd, "wb") as out, urllib.request.urlopen(item.url, timeout=timeout) as resp:
            for block in iter(lambda: resp.read(CHUNK), b""):
                h.update(block)
                out.write(block)
        digest = h.hexdigest()
        if digest != item.sha256:
            raise FetchError(
                f"{item.url}: sha256 mismatch (got {digest[:12]}…, expected {item.sha256[:12]}…)"
            )
        os.replace(tmp, target)
        return FetchResult(item.local, "downloaded")
    except urllib.error.HTTPError as e:
        return FetchResult(item.local, "failed", f"{item.url}: HTTP {e.code} {e.reason}")
    except (urllib.error.URLError, OSError, TimeoutError, http.client.HTTPException) as e:
        reason = getattr(e, "reason", None) or e
        return FetchResult(item.local, "failed", f"{item.url}: {reason}")
    except FetchError as e:
        return FetchResult(item.local, "failed", str(e))
    finally:
        tmp.unlink(missing_ok=True)


def fetch_all(
    dest: str | os.PathLike = paths.REAL_DATA_DIR,
    mirror: str | None = None,
    progress: Callable[[int, int, FetchResult], None] | None = None,
    timeout: float = 60.0,
    manifest_path: str | os.PathLike = MANIFEST,
) -> list[FetchResult]:
    """Fetch every file of the manifest into ``dest``; ``progress(i, n, result)`` is called after each."""
    dest = Path(dest)
    items = manifest(mirror, manifest_path)
    results = []
    for i, item in enumerate(items, start=1):
        r = fetch_file(item, dest, timeout=timeout)
        results.append(r)
        if progress:
            progress(i, len(items), r)
    return results
