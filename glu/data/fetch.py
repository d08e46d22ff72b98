"""Download the real data from its public origin at pinned commits, verifying each file's sha256 (pooch).

The manifest (``glu/resources/sources.json``) lists each file: where it goes in the data folder, which
repository and commit it comes from, and its sha256. Downloading and checking is pooch's job
(:func:`pooch.retrieve`: a temporary file, renamed into place only when its hash is the known one).

The data folder is **complete or absent**. Files are gathered in a hidden folder beside the destination,
``.<name>.partial/`` (files the destination already holds with the right checksum are linked in, the others
downloaded); only when every file of the manifest is there and verified does that folder become the
destination, by renaming (a destination that already exists is swapped out the same way, its other files
kept). A failed or interrupted fetch therefore changes nothing in the destination; the files it verified
stay in the partial folder, which no command reads as data, and the next run downloads only the rest.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from glu import paths
from glu.errors import FetchError
from glu.files import replace_folder

MANIFEST = paths.RESOURCES_DIR / "sources.json"
"""The pinned sources of the real data (origin, commit, checksum of every file).

:meta hide-value:
"""
PARTIAL_SUFFIX = ".partial"
DATA_SUBFOLDERS = ("affordance-words", "gestures", "reference-models", "sentence-samples")
"""The folders of a glu data folder: a destination that has files but none of these is not one."""


@dataclass(frozen=True)
class RemoteFile:
    """One file of the manifest: its place in the data folder, its URL and its sha256."""

    local: str
    url: str
    sha256: str


@dataclass(frozen=True)
class FetchResult:
    """Outcome of one file: ``status`` is ``downloaded``, ``present`` (already verified) or ``failed``."""

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
        out = []
        for f in spec["files"]:
            if mirror:
                url = mirror.rstrip("/") + "/" + f["local"]
            else:
                repo = spec["repositories"][f["source"]]
                url = spec["url_template"].format(repo=repo["repo"], commit=repo["commit"], path=f["path"])
            out.append(RemoteFile(local=f["local"], url=url, sha256=f["sha256"]))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise FetchError(f"{path}: not a readable manifest ({e})") from None
    except (KeyError, TypeError, AttributeError) as e:
        raise FetchError(f"{path}: malformed manifest ({type(e).__name__}: {e})") from None
    if mirror:
        _check_mirror(mirror)
    return out


def _check_mirror(mirror: str) -> None:
    """FetchError unless ``mirror`` is an http(s) URL with a host (checked before any request)."""
    from urllib.parse import urlsplit

    expected = "expected an http:// or https:// URL with a host, e.g. http://127.0.0.1:8000/data"
    try:
        parts = urlsplit(mirror)
        parts.port  # noqa: B018 - raises ValueError for a port that is not a number
    except ValueError as e:
        raise FetchError(f"--mirror {mirror!r}: not a URL ({e}); {expected}") from None
    if parts.scheme not in ("http", "https") or not parts.hostname or any(c.isspace() for c in mirror):
        raise FetchError(f"--mirror {mirror!r}: {expected}")


def published_origin(root: str | os.PathLike, manifest_path: str | os.PathLike = MANIFEST) -> str | None:
    """The upstream origin of a data folder, ``"owner/name@commit, …"``, if it holds the published data.

    A folder holds the published data when it has the paper's experiment table and every file of the
    manifest that it has carries the published sha256 (files it lacks are not fetched yet, files the
    manifest does not list are ignored). Otherwise None: the folder is someone's own or modified data.
    The commits are abbreviated to 7 characters, as git does.
    """
    same, differ = published_check(root, manifest_path)
    if differ or not any(f.endswith("_lab_aff_bag.txt") for f in same):
        return None
    spec = json.loads(Path(manifest_path).read_text(encoding="utf-8"))
    used = sorted({f["source"] for f in spec["files"] if f["local"] in same})
    repos = spec["repositories"]
    return ", ".join(f"{repos[k]['repo']}@{repos[k]['commit'][:7]}" for k in used)


def published_check(
    root: str | os.PathLike, manifest_path: str | os.PathLike = MANIFEST
) -> tuple[list[str], list[str]]:
    """The files of the manifest that the data folder ``root`` has, split by their checksum: (those that carry
    the published sha256, those that differ), each as its place in the folder."""
    root = Path(root)
    spec = json.loads(Path(manifest_path).read_text(encoding="utf-8"))
    same, differ = [], []
    for f in spec["files"]:
        path = root / f["local"]
        if path.is_file():
            (same if _cached_sha256(path) == f["sha256"] else differ).append(f["local"])
    return same, differ


_SHA_CACHE: dict[tuple[str, int, int], str] = {}


def _cached_sha256(path: Path) -> str:
    st = path.stat()
    key = (str(path.resolve()), st.st_size, st.st_mtime_ns)
    if key not in _SHA_CACHE:
        _SHA_CACHE[key] = sha256_of(path)
    return _SHA_CACHE[key]


def sha256_of(path: str | os.PathLike) -> str:
    """Hex sha256 of a file (the standard library's :func:`hashlib.file_digest`; no pooch import needed)."""
    with open(path, "rb") as f:
        return hashlib.file_digest(f, "sha256").hexdigest()


def partial_folder(dest: str | os.PathLike) -> Path:
    """The hidden folder where a fetch into ``dest`` gathers its files: ``.<name>.partial`` beside it."""
    dest = Path(dest).absolute()
    return dest.parent / f".{dest.name}{PARTIAL_SUFFIX}"


def _verified(path: Path, sha256: str) -> bool:
    return path.is_file() and sha256_of(path) == sha256


def _link_or_copy(src: Path, dst: Path) -> None:
    dst.parent.mkdir(parents=True, exist_ok=True)
    dst.unlink(missing_ok=True)
    try:
        os.link(src, dst)
    except OSError:
        shutil.copy2(src, dst)


def _download(item: RemoteFile, folder: Path, timeout: float) -> FetchResult:
    """Download one file into ``folder`` with pooch (verified, atomic); never raises for a network error."""
    import pooch
    import requests

    pooch.get_logger().setLevel("WARNING")
    target = folder / item.local
    target.parent.mkdir(parents=True, exist_ok=True)
    try:
        pooch.retrieve(
            item.url,
            known_hash=f"sha256:{item.sha256}",
            fname=target.name,
            path=target.parent,
            downloader=pooch.HTTPDownloader(timeout=timeout, progressbar=False),
        )
    except requests.HTTPError as e:
        status = e.response.status_code if e.response is not None else "?"
        return FetchResult(item.local, "failed", f"{item.url}: HTTP {status}")
    except ValueError as e:  # pooch: the hash does not match
        if "hash" not in str(e).lower():
            return FetchResult(item.local, "failed", f"{item.url}: {e}")
        return FetchResult(
            item.local, "failed", f"{item.url}: sha256 mismatch (expected {item.sha256[:12]}…)"
        )
    except (requests.RequestException, OSError) as e:
        return FetchResult(item.local, "failed", f"{item.url}: {type(e).__name__}: {e}")
    if not _verified(target, item.sha256):  # pragma: no cover - pooch verified it
        target.unlink(missing_ok=True)
        return FetchResult(item.local, "failed", f"{item.url}: sha256 mismatch after download")
    return FetchResult(item.local, "downloaded")


def _check_destination(dest: Path) -> None:
    if dest.exists() and not dest.is_dir():
        raise FetchError(f"{dest}: exists and is not a folder; give a data folder to fetch into")
    if dest.is_dir() and any(dest.iterdir()) and not any((dest / d).is_dir() for d in DATA_SUBFOLDERS):
        raise FetchError(
            f"{dest}: a folder with other content (none of {', '.join(DATA_SUBFOLDERS)}); "
            "fetch into a new or empty folder, or into an earlier glu data folder"
        )


def publish(partial: Path, dest: Path) -> None:
    """Make the complete folder ``partial`` the folder ``dest``; the other files of an existing ``dest`` are
    kept.

    They are linked into ``partial`` first, then :func:`glu.files.replace_folder` swaps the folders, so at
    no moment does ``dest`` hold a mix of old and new files.
    """
    if dest.exists():
        for f in sorted(dest.rglob("*")):
            if f.is_file() and not (partial / f.relative_to(dest)).exists():
                _link_or_copy(f, partial / f.relative_to(dest))
    dest.parent.mkdir(parents=True, exist_ok=True)
    replace_folder(partial, dest)


def fetch_all(
    dest: str | os.PathLike = paths.REAL_DATA_DIR,
    mirror: str | None = None,
    progress: Callable[[int, int, FetchResult], None] | None = None,
    timeout: float = 60.0,
    manifest_path: str | os.PathLike = MANIFEST,
) -> list[FetchResult]:
    """Fetch every file of the manifest into ``dest``, completely or not at all.

    ``progress(i, n, result)`` is called after each file. When every file is verified the gathered folder
    becomes ``dest`` (:func:`publish`); otherwise ``dest`` is left exactly as it was and the verified files
    wait in :func:`partial_folder` for the next run. Raises :class:`FetchError` for a malformed manifest or
    a destination that is a file or a folder of something else.
    """
    dest = Path(dest).absolute()
    if not timeout > 0 or timeout == float("inf"):
        raise FetchError(f"--timeout {timeout}: expected a positive number of seconds")
    items = manifest(mirror, manifest_path)
    _check_destination(dest)
    made, above = [], dest.parent  # the folders above dest this fetch creates (removed again if it fails)
    while not above.exists():
        made.append(above)
        above = above.parent
    partial = partial_folder(dest)
    results = []
    for i, item in enumerate(items, start=1):
        staged = partial / item.local
        if _verified(dest / item.local, item.sha256):
            _link_or_copy(dest / item.local, staged)
            r = FetchResult(item.local, "present")
        elif _verified(staged, item.sha256):
            r = FetchResult(item.local, "present")
        else:
            r = _download(item, partial, timeout)
        results.append(r)
        if progress:
            progress(i, len(items), r)
    if all(r.status != "failed" for r in results):
        publish(partial, dest)
    elif partial.is_dir() and not any(f.is_file() for f in partial.rglob("*")):
        shutil.rmtree(partial, ignore_errors=True)  # nothing verified: leave no empty folders behind
        for folder in made:  # deepest first
            try:
                folder.rmdir()
            except OSError:
                break
    return results
